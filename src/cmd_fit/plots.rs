//! PNG plots (and the same data as CSV) of a `lustre fit` analysis: the PSD with its fits on log-log
//! axes, the NDF with its GGX/Beckmann fits, the levelled scan in false colour with a colour
//! bar and a scale bar, its height histogram beside the Gaussian of the same Sq, and its
//! ACF with the correlation length. Files are written next to the material file as
//! `<stem>_psd.png/.csv`, `<stem>_ndf.png/.csv`, `<stem>_heights.png`,
//! `<stem>_histogram.png/.csv` and `<stem>_acf.png/.csv`.

use fit::pipeline::Analysis;
use fit::{Topography, areal, ndf};
use plot::{Axis, Legend, LineStyle, Marker, Plot, PlotError, Rgb8, RgbImage, Series};
use std::path::{Path, PathBuf};

/// The plot file `<stem>_<suffix>` next to `material`.
fn plot_path(material: &Path, suffix: &str) -> PathBuf {
    let stem = material
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "material".into());
    let dir = material
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    dir.join(format!("{stem}_{suffix}"))
}

/// Every file [`write`] may write next to `material` (PSD and NDF, PNG and CSV).
pub fn paths(material: &Path) -> Vec<PathBuf> {
    [
        "psd.png",
        "psd.csv",
        "ndf.png",
        "ndf.csv",
        "heights.png",
        "histogram.png",
        "histogram.csv",
        "acf.png",
        "acf.csv",
    ]
    .iter()
    .map(|s| plot_path(material, s))
    .collect()
}

/// Write the plots; returns the files written.
pub fn write(a: &Analysis, material: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let mut written = Vec::new();

    // PSD in cycles/µm and µm³ so the numbers read naturally.
    let (f, p): (Vec<f64>, Vec<f64>) = a
        .fit_psd
        .f
        .iter()
        .zip(&a.fit_psd.p)
        .filter(|(f, _)| **f > 0.0)
        .map(|(f, p)| (f * 1e-6, p * 1e18))
        .unzip();
    let k = a.kc.params;
    // A fit estimated without PSD points has no range: draw it over the measured band.
    let (flo, fhi) = if a.kc.range.0.is_finite() && a.kc.range.1 > a.kc.range.0 {
        (a.kc.range.0 * 1e-6, a.kc.range.1 * 1e-6)
    } else {
        (
            f.first().copied().unwrap_or(1.0),
            f.last().copied().unwrap_or(1.0),
        )
    };
    let fk: Vec<f64> = (0..200)
        .map(|i| flo * (fhi / flo).powf(i as f64 / 199.0))
        .collect();
    let pk: Vec<f64> = fk.iter().map(|f| k.psd_1d(f * 1e6) * 1e18).collect();
    let mut psd_plot = Plot::new(format!(
        "line PSD and K-correlation fit (σ {:.3} µm, Lc {:.3} µm, γ {:.2})",
        k.sigma * 1e6,
        k.lc * 1e6,
        k.gamma
    ))
    .x_axis(Axis::log("f [cycles/µm]"))
    .y_axis(Axis::log("PSD (1D, one-sided) [µm³]"))
    .series(
        Series::points("measured", &f, &p)
            .marker(Marker::Circle)
            .marker_size(2.0),
    )
    .series(Series::line("KC fit", &fk, &pk).width(2.0));
    for t in &a.two_scale {
        let tk = t.kc.params;
        let lo = (t.kc.range.0 * 1e-6).max(flo);
        let ft: Vec<f64> = (0..100)
            .map(|i| lo * (fhi / lo).powf(i as f64 / 99.0))
            .collect();
        let pt: Vec<f64> = ft.iter().map(|f| tk.psd_1d(f * 1e6) * 1e18).collect();
        psd_plot = psd_plot.series(
            Series::line(
                format!("residual KC, Λ = {:.1} µm", t.cutoff * 1e6),
                &ft,
                &pt,
            )
            .style(LineStyle::Dashed),
        );
    }
    let png = plot_path(material, "psd.png");
    psd_plot.save_png(&png, 900, 650)?;
    let csv = plot_path(material, "psd.csv");
    psd_plot.save_csv(&csv)?;
    written.extend([png, csv]);

    if let Some(h) = &a.ndf.ndf {
        let (th, d): (Vec<f64>, Vec<f64>) = h
            .theta
            .iter()
            .zip(&h.d)
            .filter(|(_, d)| **d > 0.0)
            .map(|(t, d)| (t.to_degrees(), *d))
            .unzip();
        let (ag, ab) = (a.ndf.alpha_ggx.0, a.ndf.alpha_beckmann.0);
        // Keep the axis on the measured data; model curves far below it are clipped.
        let dmin = d.iter().copied().fold(f64::INFINITY, f64::min);
        let dmax = d.iter().copied().fold(0.0, f64::max);
        let gg: Vec<f64> = th.iter().map(|t| ndf::ggx(ag, t.to_radians())).collect();
        let bb: Vec<f64> = th
            .iter()
            .map(|t| ndf::beckmann(ab, t.to_radians()))
            .collect();
        let ndf_plot = Plot::new("NDF of facet normals (projected-area weighted)")
            .x_axis(Axis::linear("θm [deg]"))
            .y_axis(Axis::log("D(θm) [sr⁻¹]").range(dmin / 100.0, dmax * 10.0))
            .series(
                Series::points("measured", &th, &d)
                    .marker(Marker::Circle)
                    .marker_size(2.5),
            )
            .series(Series::line(format!("GGX α = {ag:.4}"), &th, &gg).width(2.0))
            .series(
                Series::line(format!("Beckmann α = {ab:.4}"), &th, &bb)
                    .style(LineStyle::Dashed)
                    .width(2.0),
            );
        let png = plot_path(material, "ndf.png");
        ndf_plot.save_png(&png, 900, 650)?;
        let csv = plot_path(material, "ndf.csv");
        ndf_plot.save_csv(&csv)?;
        written.extend([png, csv]);
    }
    written.extend(scan_figures(&a.scan, material)?);
    Ok(written)
}

/// The height image, the histogram and the ACF of the levelled scan.
fn scan_figures(t: &Topography, material: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let mut written = Vec::new();
    let p = areal::height_params(t);
    let sq = fit::stats::compute(t).sq;
    let (zs, zunit) = height_unit(t);
    if !t.is_profile() {
        let png = plot_path(material, "heights.png");
        plot::save_png(&height_image(t, p)?, &png)?;
        written.push(png);
    }
    if let Some(h) = areal::histogram(t, 64) {
        let w = h.edges[1] - h.edges[0];
        let z: Vec<f64> = (0..h.counts.len())
            .map(|i| (h.edges[i] + w / 2.0) * zs)
            .collect();
        let d: Vec<f64> = h.density.iter().map(|d| d / zs).collect();
        let gauss: Vec<f64> = z
            .iter()
            .map(|z| {
                let s = sq * zs;
                (-0.5 * (z / s).powi(2)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt())
            })
            .collect();
        let hist = Plot::new(format!(
            "height histogram (Sa {:.4} {zunit}, Sz {:.4} {zunit}, Ssk {:.3}, Sku {:.3})",
            p.sa * zs,
            p.sz * zs,
            p.ssk,
            p.sku
        ))
        .x_axis(Axis::linear(format!("height about the mean [{zunit}]")))
        .y_axis(Axis::linear(format!("probability density [1/{zunit}]")))
        .series(Series::line("measured", &z, &d).width(2.0))
        .series(
            Series::line(format!("Gaussian, Sq {:.4} {zunit}", sq * zs), &z, &gauss)
                .style(LineStyle::Dashed),
        );
        let png = plot_path(material, "histogram.png");
        hist.save_png(&png, 900, 650)?;
        let csv = plot_path(material, "histogram.csv");
        hist.save_csv(&csv)?;
        written.extend([png, csv]);
    }
    if let Some(acf) = areal::acf(t) {
        let r: Vec<f64> = acf.r.iter().map(|r| r * 1e6).collect();
        let len = acf.length(areal::ACF_THRESHOLD);
        let title = match len {
            Some(l) => format!(
                "areal ACF, radially averaged: correlation length {:.4} µm (ρ = {})",
                l * 1e6,
                areal::ACF_THRESHOLD
            ),
            None => format!(
                "areal ACF, radially averaged: ρ stays above {} to half the scan",
                areal::ACF_THRESHOLD
            ),
        };
        let rmax = r.last().copied().unwrap_or(1.0);
        let mut acf_plot = Plot::new(title)
            .x_axis(Axis::linear("lag r [µm]"))
            .y_axis(Axis::linear("normalised ACF ρ = 1 − A(r)/Sq²"))
            .series(Series::line("ACF", &r, &acf.rho).width(2.0))
            .series(
                Series::line(
                    format!("ρ = {}", areal::ACF_THRESHOLD),
                    &[0.0, rmax],
                    &[areal::ACF_THRESHOLD; 2],
                )
                .style(LineStyle::Dotted),
            );
        if let Some(l) = len {
            acf_plot = acf_plot.series(
                Series::line("correlation length", &[l * 1e6; 2], &[0.0, 1.0])
                    .style(LineStyle::Dashed),
            );
        }
        let png = plot_path(material, "acf.png");
        acf_plot.save_png(&png, 900, 650)?;
        let csv = plot_path(material, "acf.csv");
        acf_plot.save_csv(&csv)?;
        written.extend([png, csv]);
    }
    Ok(written)
}

/// Heights shown in nm below 2 µm of range, in µm above: (metres → unit, its name).
fn height_unit(t: &Topography) -> (f64, &'static str) {
    let (lo, hi) = t
        .heights
        .iter()
        .filter(|h| h.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(*h), b.max(*h))
        });
    if hi - lo < 2e-6 {
        (1e9, "nm")
    } else {
        (1e6, "µm")
    }
}

/// A perceptually ordered colour map (dark violet → blue → green → yellow), linear between
/// five stops.
fn colour(v: f64) -> Rgb8<u8> {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = v.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let c = |k: usize| (STOPS[i][k] + f * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8;
    Rgb8([c(0), c(1), c(2)])
}

/// 1, 2 or 5 × 10ⁿ: the round length nearest below `x`.
fn round_length(x: f64) -> f64 {
    let e = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * e)
        .find(|&v| v <= x)
        .unwrap_or(e)
}

/// The levelled map in false colour (0.5 % to 99.5 % of the heights across the colour
/// range, so a few spikes do not wash it out) on axes in µm, with a white scale bar and,
/// to its right, the colour bar with its height axis.
fn height_image(t: &Topography, p: areal::HeightParams) -> Result<RgbImage, PlotError> {
    let (lx, ly) = (t.size_x() * 1e6, t.size_y() * 1e6);
    let mut sorted: Vec<f64> = t
        .heights
        .iter()
        .copied()
        .filter(|h| h.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let pick = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
    let (zs, zunit) = height_unit(t);
    let (zlo, zhi) = (pick(0.005), pick(0.995));
    let zhi = if zhi > zlo { zhi } else { zlo + 1e-12 };
    let bar = round_length(lx / 5.0);
    let map_plot = |h: u32| {
        Plot::new(format!(
            "levelled heights (Sa {:.4} {zunit}, Sz {:.4} {zunit}); scale bar {bar} µm",
            p.sa * zs,
            p.sz * zs
        ))
        .x_axis(Axis::linear("x [µm]").range(0.0, lx))
        .y_axis(Axis::linear("y [µm]").range(0.0, ly))
        .grid(false)
        .legend(Legend::Hidden)
        .series(Series::line("", &[0.0, lx], &[0.0, ly]).width(0.1))
        .render(760, h)
    };
    // Size the frame to the scan's aspect ratio.
    let (_, first) = map_plot(640)?;
    let (fw, fh) = (
        first.frame.x1 - first.frame.x0,
        first.frame.y1 - first.frame.y0,
    );
    let want = (fw as f64 * ly / lx).clamp(80.0, 1400.0);
    let h = (640.0 + want - fh as f64).round().max(200.0) as u32;
    let (mut img, r) = map_plot(h)?;
    let f = r.frame;
    let (w, hh) = ((f.x1 - f.x0).max(1) as f64, (f.y1 - f.y0).max(1) as f64);
    for py in f.y0..f.y1 {
        for px in f.x0..f.x1 {
            let x = (px - f.x0) as f64 + 0.5;
            let y = (f.y1 - py) as f64 - 0.5;
            let ix = ((x / w * t.nx as f64) as usize).min(t.nx - 1);
            let iy = ((y / hh * t.ny as f64) as usize).min(t.ny - 1);
            let z = t.heights[iy * t.nx + ix];
            let c = if z.is_finite() {
                colour((z - zlo) / (zhi - zlo))
            } else {
                Rgb8([128, 128, 128])
            };
            img.put_pixel(px as u32, py as u32, c);
        }
    }
    // Scale bar: white with a black outline, bottom left inside the frame.
    let bar_px = (bar / lx * w).round() as i64;
    let (bx, by) = (f.x0 + 12, f.y1 - 18);
    for py in by - 2..by + 6 {
        for px in bx - 2..bx + bar_px + 2 {
            let inner = (by..by + 4).contains(&py) && (bx..bx + bar_px).contains(&px);
            img.put_pixel(
                px as u32,
                py as u32,
                if inner { Rgb8([255; 3]) } else { Rgb8([0; 3]) },
            );
        }
    }
    let (cb, cr) = Plot::new("")
        .x_axis(Axis::linear(" ").range(0.0, 1.0))
        .y_axis(Axis::linear(format!("height [{zunit}]")).range(zlo * zs, zhi * zs))
        .grid(false)
        .legend(Legend::Hidden)
        .series(Series::line("", &[0.0, 1.0], &[zlo * zs, zhi * zs]).width(0.1))
        .render(200, img.height())?;
    let mut cb = cb;
    let g = cr.frame;
    for py in g.y0..g.y1 {
        let v = (g.y1 - py) as f64 / (g.y1 - g.y0).max(1) as f64;
        for px in g.x0..g.x1 {
            cb.put_pixel(px as u32, py as u32, colour(v));
        }
    }
    let mut out = RgbImage::from_pixel(img.width() + cb.width(), img.height(), Rgb8([255; 3]));
    for (x, y, c) in img.enumerate_pixels() {
        out.put_pixel(x, y, *c);
    }
    for (x, y, c) in cb.enumerate_pixels() {
        out.put_pixel(img.width() + x, y, *c);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use fit::io::{ReadOptions, read_path};
    use fit::pipeline::{Options, analyse};
    use std::path::PathBuf;

    /// PNG and CSV for the PSD, the NDF, the histogram and the ACF, and the height image,
    /// next to the material file.
    #[test]
    fn plots_of_a_map_are_written_next_to_the_material_file() {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/di-6.di");
        let scan = read_path(&path, &ReadOptions::default()).unwrap();
        let a = analyse(scan, None, &Options::default()).unwrap();
        let out = std::env::temp_dir().join(format!("fit-plots-{}.toml", std::process::id()));
        let files = super::write(&a, &out).unwrap();
        assert_eq!(files.len(), 9);
        assert_eq!(files, super::paths(&out));
        for f in &files {
            let b = std::fs::read(f).unwrap();
            if f.extension().is_some_and(|e| e == "png") {
                assert!(b.starts_with(b"\x89PNG"), "{}", f.display());
            } else {
                assert!(b.len() > 100, "{}", f.display());
            }
            std::fs::remove_file(f).unwrap();
        }
    }
}
