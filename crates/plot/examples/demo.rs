//! Writes a demonstration log-log plot, a linear plot and an image grid into the folder given
//! as the first argument (default: the current folder).
//!
//! `cargo run -p plot --example demo -- /tmp/plot-demo`

use plot::{Axis, ImageGrid, Legend, LineStyle, Marker, Plot, PlotError, Rgb, RgbImage, Series};
use std::path::PathBuf;

fn main() -> Result<(), PlotError> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| ".".into()));
    // Synthetic scatter-like curves: a Lorentzian-ish core and power-law tails.
    let b: Vec<f64> = (0..400)
        .map(|i| 10f64.powf(-4.0 + 4.3 * f64::from(i) / 399.0))
        .collect();
    let curve = |c: f64, p: f64| {
        b.iter()
            .map(|x| 1e3 / (1.0 + (x / c).powf(p)))
            .collect::<Vec<f64>>()
    };
    Plot::new("In-plane BRDF, θi = 0°, λ = 550 nm")
        .x_axis(Axis::log("β − β₀"))
        .y_axis(Axis::log("BRDF [sr⁻¹]"))
        .series(Series::line("GGX α = 0.05", &b, &curve(0.02, 4.0)))
        .series(Series::line("GHS SSA", &b, &curve(0.01, 2.6)).style(LineStyle::Dashed))
        .series(Series::line("full GHS", &b, &curve(0.015, 3.0)).style(LineStyle::DashDot))
        .series(Series::line("two-scale 100λ", &b, &curve(0.03, 3.4)).style(LineStyle::Dotted))
        .series(
            Series::points("measured", &b, &curve(0.015, 3.1))
                .marker(Marker::Square)
                .marker_every(25),
        )
        .save_png(dir.join("demo_loglog.png"), 800, 600)?;

    let th: Vec<f64> = (0..=89).map(f64::from).collect();
    let alb = |a: f64| {
        th.iter()
            .map(|t| 1.0 - a * (t / 90.0f64).powi(4))
            .collect::<Vec<f64>>()
    };
    let p = Plot::new("Directional albedo")
        .x_axis(Axis::linear("θi [deg]").range(0.0, 90.0))
        .y_axis(Axis::linear("albedo [–]"))
        .legend(Legend::BottomLeft)
        .series(
            Series::line("α = 0.1", &th, &alb(0.05))
                .marker(Marker::Circle)
                .marker_every(10),
        )
        .series(
            Series::line("α = 0.3", &th, &alb(0.2))
                .marker(Marker::Triangle)
                .marker_every(10),
        )
        .series(
            Series::line("α = 0.6", &th, &alb(0.45))
                .marker(Marker::Diamond)
                .marker_every(10)
                .color(Rgb(120, 0, 0)),
        );
    p.save_png(dir.join("demo_linear.png"), 640, 480)?;
    p.save_csv(dir.join("demo_linear.csv"))?;

    let rows = ["GGX", "GHS SSA", "full GHS", "two-scale\n50λ"];
    let cols = ["0°", "45°", "80°"];
    let mut g = ImageGrid::new(rows.len(), cols.len())
        .title("Sample 3, copper")
        .row_labels(rows)
        .col_labels(cols);
    for r in 0..rows.len() {
        for c in 0..cols.len() {
            let img = RgbImage::from_fn(160, 120, |x, y| {
                let v = ((x + y * (r as u32 + 1) + c as u32 * 40) % 255) as u8;
                image_rgb(v, 120, 255 - v)
            });
            g.set(r, c, img)?;
        }
    }
    g.caption(3, 2, "RMSE 0.012")?;
    g.save_png(dir.join("demo_grid.png"))?;
    Ok(())
}

fn image_rgb(r: u8, g: u8, b: u8) -> plot::Rgb8<u8> {
    plot::Rgb8([r, g, b])
}
