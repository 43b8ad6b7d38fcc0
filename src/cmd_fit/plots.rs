//! PNG plots (and the same data as CSV) of a `lustre fit` analysis: the PSD with its fits on log-log
//! axes and the NDF with its GGX/Beckmann fits. Files are written next to the material file
//! as `<stem>_psd.png/.csv` and `<stem>_ndf.png/.csv`.

use fit::ndf;
use fit::pipeline::Analysis;
use plot::{Axis, LineStyle, Marker, Plot, PlotError, Series};
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
    ["psd.png", "psd.csv", "ndf.png", "ndf.csv"]
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
    Ok(written)
}

#[cfg(test)]
mod tests {
    use fit::io::{ReadOptions, read_path};
    use fit::pipeline::{Options, analyse};
    use std::path::PathBuf;

    /// PNG and CSV for the PSD and the NDF, next to the material file.
    #[test]
    fn plots_of_a_map_are_written_next_to_the_material_file() {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/surfaces/di-6.di");
        let scan = read_path(&path, &ReadOptions::default()).unwrap();
        let a = analyse(scan, None, &Options::default()).unwrap();
        let out = std::env::temp_dir().join(format!("fit-plots-{}.toml", std::process::id()));
        let files = super::write(&a, &out).unwrap();
        assert_eq!(files.len(), 4);
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
