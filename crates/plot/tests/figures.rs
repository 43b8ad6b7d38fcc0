//! End-to-end checks of the PNG/CSV output: sizes, where series pixels land, error paths.

use plot::{Axis, ImageGrid, LineStyle, Marker, Plot, PlotError, Rgb, RgbImage, Series};
use proptest::prelude::*;
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("plot-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn no_temp_files_left(dir: &PathBuf) {
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

const RED: Rgb = Rgb(220, 20, 60);

fn px(img: &RgbImage, p: (f64, f64)) -> [u8; 3] {
    img.get_pixel(p.0.floor() as u32, p.1.floor() as u32).0
}

#[test]
fn linear_plot_png_has_size_and_series_where_expected() {
    let dir = scratch("linear");
    let path = dir.join("line.png");
    let xs = [0.0, 10.0];
    let ys = [5.0, 5.0];
    let report = Plot::new("flat line")
        .x_axis(Axis::linear("x [m]").range(0.0, 10.0))
        .y_axis(Axis::linear("y [s]").range(0.0, 10.0))
        .series(Series::line("y = 5", &xs, &ys).color(RED).width(3.0))
        .save_png(&path, 640, 480)
        .unwrap();
    let img = image::open(&path).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (640, 480));
    no_temp_files_left(&dir);

    // On the line: exactly the series colour (the legend is top right, the probe is at x=2..5).
    for x in [2.0, 3.5, 5.0] {
        assert_eq!(
            px(&img, report.to_px(x, 5.0).unwrap()),
            [220, 20, 60],
            "x = {x}"
        );
    }
    // Well away from the line: no red.
    for (x, y) in [(5.0, 2.0), (5.0, 7.5), (1.0, 1.0)] {
        let p = px(&img, report.to_px(x, y).unwrap());
        assert_ne!(p, [220, 20, 60], "({x}, {y})");
    }
    // The red row spans nearly the whole frame width.
    let (_, ly) = report.to_px(0.0, 5.0).unwrap();
    let red_in_row = (0..640)
        .filter(|&x| img.get_pixel(x, ly as u32).0 == [220, 20, 60])
        .count() as i64;
    assert!(
        red_in_row > report.frame.x1 - report.frame.x0 - 220,
        "{red_in_row} red pixels"
    );
    // Frame is inside the image and leaves room for labels on the left and bottom.
    assert!(
        report.frame.x0 > 30
            && report.frame.y1 < 450
            && report.frame.x1 < 640
            && report.frame.y0 > 10
    );
}

#[test]
fn log_log_plot_places_power_law_and_skips_bad_points() {
    let xs: Vec<f64> = (0..200)
        .map(|i| 10f64.powf(-3.0 + 5.0 * f64::from(i) / 199.0))
        .collect();
    let mut ys: Vec<f64> = xs.iter().map(|x| x.powi(-2)).collect();
    // Bad points beyond x = 10^1.5 so the probed stretch below is one unbroken run.
    ys[180] = f64::NAN;
    ys[182] = -1.0;
    ys[184] = 0.0;
    ys[186] = f64::INFINITY;
    let (img, report) = Plot::new("")
        .x_axis(Axis::log("β − β₀"))
        .y_axis(Axis::log("BRDF [sr⁻¹]"))
        .legend(plot::Legend::BottomLeft)
        .series(Series::line("x⁻²", &xs, &ys).color(RED).width(3.0))
        .render(800, 600)
        .unwrap();
    assert_eq!(img.dimensions(), (800, 600));
    assert_eq!(
        report.skipped,
        vec![plot::Skipped {
            label: "x⁻²".into(),
            count: 4
        }]
    );
    // Auto range covers the data with a small margin, in decades.
    assert!(report.x.lo < 1e-3 && report.x.lo > 1e-4 && report.x.hi > 1e2 && report.x.hi < 1e3);
    for x in [1e-2, 1e-1, 1.0, 10.0] {
        let p = report.to_px(x, x.powi(-2)).unwrap();
        assert_eq!(px(&img, p), [220, 20, 60], "x = {x}");
    }
    // A straight line on log-log: pixel positions of decades are evenly spaced.
    let a = report.to_px(1e-2, 1e4).unwrap();
    let b = report.to_px(1e-1, 1e2).unwrap();
    let c = report.to_px(1.0, 1.0).unwrap();
    assert!(((b.0 - a.0) - (c.0 - b.0)).abs() < 1e-9 && ((b.1 - a.1) - (c.1 - b.1)).abs() < 1e-9);
    assert!(b.1 < c.1, "larger values are higher up");
}

#[test]
fn styles_and_markers_draw_series_colour_pixels() {
    let xs: Vec<f64> = (0..50).map(f64::from).collect();
    let ys: Vec<f64> = xs.iter().map(|x| x * 0.5).collect();
    let styles = [
        LineStyle::Dashed,
        LineStyle::Dotted,
        LineStyle::DashDot,
        LineStyle::None,
    ];
    let markers = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::Cross,
        Marker::Plus,
    ];
    for (i, m) in markers.iter().enumerate() {
        let (img, report) = Plot::new("markers")
            .series(
                Series::line("s", &xs, &ys)
                    .style(styles[i % styles.len()])
                    .marker(*m)
                    .marker_every(7)
                    .color(RED),
            )
            .render(500, 400)
            .unwrap();
        // Marker centre pixels carry the full series colour.
        let p = report.to_px(14.0, 7.0).unwrap();
        assert_eq!(px(&img, p), [220, 20, 60], "{m:?}");
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let ok = [1.0, 2.0];
    let e = Plot::new("t")
        .series(Series::line("empty", &[], &[]))
        .render(400, 300)
        .unwrap_err();
    assert!(
        matches!(e, PlotError::EmptySeries { ref label } if label == "empty"),
        "{e}"
    );
    let e = Plot::new("t")
        .series(Series::line("m", &ok, &[1.0]))
        .render(400, 300)
        .unwrap_err();
    assert!(
        matches!(e, PlotError::LengthMismatch { xs: 2, ys: 1, .. }),
        "{e}"
    );
    let e = Plot::new("t")
        .y_axis(Axis::log("y"))
        .series(Series::line("neg", &ok, &[-1.0, 0.0]))
        .render(400, 300)
        .unwrap_err();
    assert!(
        matches!(e, PlotError::NoPlottablePoints { points: 2, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("neg"));
    let e = Plot::new("nothing").render(400, 300).unwrap_err();
    assert!(matches!(e, PlotError::NoSeries { .. }), "{e}");
    for (lo, hi) in [(0.0, 1.0), (2.0, 1.0), (f64::NAN, 1.0)] {
        let e = Plot::new("t")
            .x_axis(Axis::log("x").range(lo, hi))
            .series(Series::line("s", &ok, &ok))
            .render(400, 300)
            .unwrap_err();
        assert!(
            matches!(e, PlotError::InvalidRange { axis: "x", .. }),
            "{e}"
        );
    }
    let e = Plot::new("t")
        .series(Series::line("s", &ok, &ok))
        .render(60, 40)
        .unwrap_err();
    assert!(matches!(e, PlotError::TooSmall { .. }), "{e}");
    let e = Plot::new("t")
        .series(Series::line("s", &ok, &ok))
        .render(100_000, 100_000)
        .unwrap_err();
    assert!(matches!(e, PlotError::TooLarge { .. }), "{e}");

    let dir = scratch("errors");
    let missing = dir.join("no-such-dir").join("p.png");
    let e = Plot::new("t")
        .series(Series::line("s", &ok, &ok))
        .save_png(&missing, 400, 300)
        .unwrap_err();
    assert!(matches!(e, PlotError::Io { .. }), "{e}");
    assert!(e.to_string().contains("no-such-dir"), "{e}");
    no_temp_files_left(&dir);
}

#[test]
fn csv_holds_exactly_the_plotted_values() {
    let dir = scratch("csv");
    let xs = [0.1, 0.2, 0.30000000000000004];
    let ys = [1.0 / 3.0, 2e-12, f64::NAN];
    let p = Plot::new("c")
        .x_axis(Axis::linear("θo [deg]"))
        .y_axis(Axis::log("BRDF [sr⁻¹]"))
        .series(Series::line("a", &xs, &ys))
        .series(Series::line("b", &xs[..1], &ys[..1]));
    p.save_csv(dir.join("c.csv")).unwrap();
    no_temp_files_left(&dir);
    let text = std::fs::read_to_string(dir.join("c.csv")).unwrap();
    let mut rows = text.lines();
    assert_eq!(rows.next(), Some("series,θo [deg],BRDF [sr⁻¹]"));
    let parsed: Vec<(String, f64, f64)> = rows
        .map(|r| {
            let f: Vec<&str> = r.split(',').collect();
            (
                f[0].to_string(),
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(parsed.len(), 4);
    for (i, (l, x, y)) in parsed.iter().take(3).enumerate() {
        assert_eq!(l, "a");
        assert_eq!(x.to_bits(), xs[i].to_bits());
        assert!(y.to_bits() == ys[i].to_bits() || (y.is_nan() && ys[i].is_nan()));
    }
    assert_eq!(parsed[3].0, "b");
}

fn solid(w: u32, h: u32, c: [u8; 3]) -> RgbImage {
    RgbImage::from_pixel(w, h, plot::Rgb8(c))
}

#[test]
fn image_grid_places_cells_and_labels() {
    let dir = scratch("grid");
    let mut g = ImageGrid::new(2, 3)
        .title("Fig. 1")
        .row_labels(["GGX", "full GHS"])
        .col_labels(["0°", "45°", "80°"]);
    let colors = [
        [200, 0, 0],
        [0, 200, 0],
        [0, 0, 200],
        [200, 200, 0],
        [0, 200, 200],
        [200, 0, 200],
    ];
    for r in 0..2 {
        for c in 0..3 {
            g.set(r, c, solid(120, 90, colors[r * 3 + c])).unwrap();
        }
    }
    // One smaller cell: centred in its slot, grey-free surroundings stay white.
    g.set(1, 2, solid(60, 40, colors[5])).unwrap();
    g.caption(1, 1, "RMSE 0.01").unwrap();
    let layout = g.save_png(dir.join("grid.png")).unwrap();
    no_temp_files_left(&dir);
    let img = image::open(dir.join("grid.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (layout.width, layout.height));
    assert_eq!(layout.slots.len(), 6);
    for (i, s) in layout.slots.iter().enumerate() {
        assert_eq!((s.x1 - s.x0, s.y1 - s.y0), (120, 90), "slot {i}");
        let centre = img
            .get_pixel(((s.x0 + s.x1) / 2) as u32, ((s.y0 + s.y1) / 2) as u32)
            .0;
        assert_eq!(centre, colors[i], "slot {i}");
    }
    let small = layout.slots[5];
    assert_eq!(
        img.get_pixel(small.x0 as u32 + 2, small.y0 as u32 + 2).0,
        [255, 255, 255]
    );
    // Slots are left-to-right, top-to-bottom, non-overlapping.
    assert!(layout.slots[0].x1 <= layout.slots[1].x0 && layout.slots[0].y1 <= layout.slots[3].y0);
    // Row labels put dark text pixels left of the first column; column labels above row 0.
    let s0 = layout.slots[0];
    let dark = |x0: i64, y0: i64, x1: i64, y1: i64| {
        (y0.max(0)..y1)
            .flat_map(|y| (x0.max(0)..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x as u32, y as u32).0.iter().all(|&v| v < 100))
            .count()
    };
    assert!(dark(0, s0.y0, s0.x0, s0.y1) > 20, "row label missing");
    assert!(dark(s0.x0, 0, s0.x1, s0.y0) > 10, "column label missing");
}

#[test]
fn image_grid_rejects_bad_cells() {
    let mut g = ImageGrid::new(2, 2);
    assert!(matches!(
        g.set(2, 0, solid(4, 4, [0; 3])),
        Err(PlotError::CellOutOfRange { row: 2, .. })
    ));
    assert!(matches!(
        g.set_rgb8(0, 0, 4, 4, vec![0; 47]),
        Err(PlotError::BadPixelBuffer {
            expected: 48,
            got: 47,
            ..
        })
    ));
    assert!(matches!(g.render(), Err(PlotError::EmptyGrid(_))));
    assert!(matches!(
        ImageGrid::new(0, 3).render(),
        Err(PlotError::EmptyGrid(_))
    ));
    let e = g.load(0, 0, "/nonexistent/cell.png").unwrap_err();
    assert!(e.to_string().contains("/nonexistent/cell.png"), "{e}");
    g.set_rgb8(1, 1, 4, 4, vec![9; 48]).unwrap();
    let (img, layout) = g.render().unwrap();
    assert_eq!(img.dimensions(), (layout.width, layout.height));
}

/// Pixels of exactly colour `c` inside `r` (x0, y0, x1, y1), clipped to the image.
fn count(img: &RgbImage, (x0, y0, x1, y1): (i64, i64, i64, i64), c: [u8; 3]) -> usize {
    let (w, h) = (i64::from(img.width()), i64::from(img.height()));
    (y0.max(0)..y1.min(h))
        .flat_map(|y| (x0.max(0)..x1.min(w)).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x as u32, y as u32).0 == c)
        .count()
}

fn dark(img: &RgbImage, r: (i64, i64, i64, i64)) -> usize {
    let (w, h) = (i64::from(img.width()), i64::from(img.height()));
    (r.1.max(0)..r.3.min(h))
        .flat_map(|y| (r.0.max(0)..r.2.min(w)).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x as u32, y as u32).0.iter().all(|&v| v < 100))
        .count()
}

#[test]
fn log_axes_put_grid_ticks_and_labels_at_decades() {
    // Five powers of ten: few enough to label each and draw minor lines at 2…9 × 10ⁿ.
    let xs = [1e-2, 1e2];
    let (img, rep) = Plot::new("")
        .x_axis(Axis::log("x").range(1e-2, 1e2))
        .y_axis(Axis::log("y").range(1e-2, 1e2))
        .legend(plot::Legend::Hidden)
        .series(Series::line("s", &xs, &[1e2, 1e2]).color(RED))
        .render(800, 600)
        .unwrap();
    let f = rep.frame;
    let grid = [222, 222, 222];
    let minor = [240, 240, 240];
    let mid_y = (f.y0 + f.y1) / 2;
    for k in -1..=1 {
        let x = rep.x.to_px(10f64.powi(k)).unwrap().floor() as i64;
        // Grid line through the frame, an outward tick mark and a label under it.
        assert_eq!(
            img.get_pixel(x as u32, mid_y as u32).0,
            grid,
            "decade 1e{k}"
        );
        assert!(
            count(&img, (x, f.y1 + 1, x + 1, f.y1 + 4), [0, 0, 0]) == 3,
            "tick 1e{k}"
        );
        assert!(
            dark(&img, (x - 15, f.y1 + 8, x + 15, f.y1 + 40)) > 10,
            "label 1e{k}"
        );
        // Half-way between decades (≈ 3×10^k) there is a light minor line and no label.
        let xm = rep.x.to_px(3.0 * 10f64.powi(k)).unwrap().floor() as i64;
        assert_eq!(
            img.get_pixel(xm as u32, mid_y as u32).0,
            minor,
            "minor 3e{k}"
        );
        assert_eq!(count(&img, (xm, f.y1 + 1, xm + 1, f.y1 + 4), [0, 0, 0]), 0);
        let y = rep.y.to_px(10f64.powi(k)).unwrap().floor() as i64;
        assert_eq!(img.get_pixel(((f.x0 + f.x1) / 2) as u32, y as u32).0, grid);
        assert!(
            dark(&img, (0, y - 10, f.x0 - 6, y + 10)) > 10,
            "y label 1e{k}"
        );
    }
    // The frame closes on all four sides.
    for (x, y) in [
        (f.x0 - 1, mid_y),
        (f.x1, mid_y),
        ((f.x0 + f.x1) / 2, f.y0 - 1),
    ] {
        assert_eq!(img.get_pixel(x as u32, y as u32).0, [0, 0, 0], "({x}, {y})");
    }
}

#[test]
fn legend_lists_labelled_series_only() {
    let xs = [0.0, 10.0];
    let (a, b, hidden) = (Rgb(250, 0, 250), Rgb(0, 200, 250), Rgb(120, 250, 0));
    let build = |legend| {
        Plot::new("")
            .x_axis(Axis::linear("x").range(0.0, 10.0))
            .y_axis(Axis::linear("y").range(0.0, 10.0))
            .legend(legend)
            .series(Series::line("first", &xs, &[1.0, 1.0]).color(a))
            .series(
                Series::line("second", &xs, &[2.0, 2.0])
                    .color(b)
                    .marker(Marker::Square),
            )
            .series(Series::line("", &xs, &[3.0, 3.0]).color(hidden))
            .render(600, 400)
            .unwrap()
    };
    let (img, rep) = build(plot::Legend::TopLeft);
    let f = rep.frame;
    // Top-left quarter of the frame holds no data: what is there is the legend.
    let corner = (f.x0, f.y0, (f.x0 + f.x1) / 2, (f.y0 + f.y1) / 2);
    assert!(count(&img, corner, [250, 0, 250]) > 20);
    assert!(count(&img, corner, [0, 200, 250]) > 20);
    assert_eq!(
        count(&img, corner, [120, 250, 0]),
        0,
        "unlabelled series in the legend"
    );
    assert!(dark(&img, corner) > 50, "legend text missing");
    let (img, _) = build(plot::Legend::Hidden);
    assert_eq!(count(&img, corner, [250, 0, 250]), 0);
    // Outside: the legend sits right of the frame, which shrinks to make room.
    let (img, out) = build(plot::Legend::Outside);
    assert!(out.frame.x1 < f.x1 - 60);
    let right = (out.frame.x1 + 2, 0, 600, 400);
    assert!(count(&img, right, [250, 0, 250]) > 20 && dark(&img, right) > 50);
}

#[test]
fn long_titles_wrap_instead_of_being_cut() {
    let title = "S280: brass, σ = 0.28 µm, Lc = 9.1 µm, γ = 2.3, with the GGX ≡ KC identity α, \
                 in-plane BRDF at θi = 0° and 80°, λ = 550 nm";
    let xs = [0.0, 1.0];
    let render = |t: &str| {
        Plot::new(t)
            .series(Series::line("s", &xs, &xs))
            .render(500, 400)
            .unwrap()
    };
    let (img, rep) = render(title);
    let (_, short) = render("short");
    assert!(
        rep.frame.y0 > short.frame.y0 + 15,
        "{} vs {}",
        rep.frame.y0,
        short.frame.y0
    );
    // Title ink spans several lines and stays clear of the image edges.
    let band = |x0, x1| dark(&img, (x0, 0, x1, rep.frame.y0 - 12));
    assert!(band(0, 500) > 400);
    assert_eq!(band(0, 4) + band(496, 500), 0, "title cut at an edge");
    let rows: Vec<i64> = (0..rep.frame.y0 - 12)
        .filter(|&y| dark(&img, (0, y, 500, y + 1)) > 0)
        .collect();
    assert!(
        rows.last().unwrap() - rows[0] > 25,
        "one line only: {rows:?}"
    );
}

#[test]
fn too_small_error_names_a_size_that_works() {
    let xs = [1.0, 2.0];
    let p = Plot::new("a title")
        .x_axis(Axis::log("x [m]"))
        .y_axis(Axis::linear("y [s]"))
        .legend(plot::Legend::Outside)
        .series(Series::line("a rather long legend entry", &xs, &xs));
    for (w, h) in [(60, 40), (200, 140), (170, 400)] {
        let Err(e) = p.render(w, h) else {
            panic!("{w}x{h} rendered")
        };
        let PlotError::TooSmall {
            min_width,
            min_height,
            ..
        } = e
        else {
            panic!("{e}")
        };
        assert!(
            e.to_string().contains(&format!("{min_width}x{min_height}")),
            "{e}"
        );
        let (img, _) = p
            .render(min_width.max(w), min_height.max(h))
            .unwrap_or_else(|e| panic!("{w}x{h} → {min_width}x{min_height}: {e}"));
        assert_eq!(img.width(), min_width.max(w));
    }
    // An absurd font size gives an error, not an overflow or a hang.
    let Err(e) = p.clone().font_px(1e12).render(400, 300) else {
        panic!("rendered at 1e12 px")
    };
    assert!(matches!(e, PlotError::TooSmall { .. }), "{e}");
}

#[test]
fn image_grid_wraps_a_long_title() {
    let mut g = ImageGrid::new(1, 2)
        .title("Sample S280 (brass, σ 0.28 µm): every model side by side under a daylight sky");
    g.set(0, 0, solid(100, 80, [0, 0, 200])).unwrap();
    g.set(0, 1, solid(100, 80, [0, 200, 0])).unwrap();
    let (img, layout) = g.render().unwrap();
    let s = layout.slots[0];
    let title_band = |x0, x1| dark(&img, (x0, 0, x1, s.y0));
    assert!(title_band(0, i64::from(layout.width)) > 200);
    let w = i64::from(layout.width);
    assert_eq!(
        title_band(0, 3) + title_band(w - 3, w),
        0,
        "title cut at an edge"
    );
}

/// Distance from `p` to segment a→b.
fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p.0 - a.0 - t * dx).powi(2) + (p.1 - a.1 - t * dy).powi(2)).sqrt()
}

fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        Just(-f64::MAX),
        -1e6..1e6f64,
        (-300.0..300.0f64).prop_map(|e| 10f64.powf(e)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn series_pixels_lie_on_the_data_polyline(
        // Zig-zags with sharp reversals, as in noisy data.
        pts in prop::collection::vec((-20.0..120.0f64, -20.0..120.0f64), 1..25),
        width in 1.0..7.0f64,
    ) {
        let (xs, ys): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
        let (img, rep) = Plot::new("")
            .x_axis(Axis::linear("").range(0.0, 100.0))
            .y_axis(Axis::linear("").range(0.0, 100.0))
            .legend(plot::Legend::Hidden)
            .grid(false)
            .series(Series::line("s", &xs, &ys).color(RED).width(width))
            .render(400, 300)
            .unwrap();
        let px: Vec<(f64, f64)> = pts.iter().map(|p| rep.to_px(p.0, p.1).unwrap()).collect();
        let f = rep.frame;
        // Joins are mitred up to turns of 120° (the mitre then reaches one width from the
        // vertex), sharper turns are cut and rounded.
        let reach = width.round().max(1.0) + 2.5;
        let mut drawn = 0;
        for y in 0..300u32 {
            for x in 0..400u32 {
                if img.get_pixel(x, y).0 != [220, 20, 60] {
                    continue;
                }
                drawn += 1;
                let c = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                let near = if px.len() == 1 {
                    seg_dist(c, px[0], px[0])
                } else {
                    px.windows(2).map(|w| seg_dist(c, w[0], w[1])).fold(f64::INFINITY, f64::min)
                };
                prop_assert!(near <= reach, "pixel ({x}, {y}) is {near:.1} px from the line");
                // Clipped at the frame (a mitre at a vertex on the edge may overhang it).
                let (i, j) = (f64::from(x), f64::from(y));
                let (x0, y0, x1, y1) = (f.x0 as f64, f.y0 as f64, f.x1 as f64, f.y1 as f64);
                prop_assert!(i >= x0 - reach && i < x1 + reach && j >= y0 - reach && j < y1 + reach,
                    "pixel ({x}, {y}) outside the frame {f:?}");
            }
        }
        // A visible piece of line leaves pixels: any data point inside the frame is drawn.
        if pts.iter().any(|p| (1.0..99.0).contains(&p.0) && (1.0..99.0).contains(&p.1)) {
            prop_assert!(drawn > 0);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn rendering_never_panics(
        pts in prop::collection::vec((wild_f64(), wild_f64()), 0..30),
        logx in any::<bool>(),
        logy in any::<bool>(),
        style in 0usize..5,
    ) {
        let (xs, ys): (Vec<f64>, Vec<f64>) = pts.into_iter().unzip();
        let ax = |log: bool, l: &str| if log { Axis::log(l) } else { Axis::linear(l) };
        let st = [LineStyle::Solid, LineStyle::Dashed, LineStyle::Dotted, LineStyle::DashDot, LineStyle::None][style];
        let r = Plot::new("fuzz")
            .x_axis(ax(logx, "x"))
            .y_axis(ax(logy, "y"))
            .series(Series::line("s", &xs, &ys).style(st).marker(Marker::Circle))
            .render(320, 240);
        if let Ok((img, rep)) = r {
            prop_assert_eq!(img.dimensions(), (320, 240));
            prop_assert!(rep.x.lo < rep.x.hi && rep.y.lo < rep.y.hi);
        }
    }
}
