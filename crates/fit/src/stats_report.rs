//! The report of `lustre fit stats <scan> --json`: the headline numbers of a
//! [`pipeline::summarise_checked`] analysis as one JSON object, with the warnings the
//! analysis raised. The CLI prints it; the Python package returns it as a dict, so
//! both give the same numbers to the last bit.
//!
//! Lengths are in metres, frequencies in cycles/m (the `units` key says so in the
//! report itself); a non-finite number is `null`.

use serde_json::{Value, json};

use crate::pipeline::{Quality, Summary};
use crate::{Topography, areal};

/// Where the analysed heights came from, as the report names them.
#[derive(Clone, Copy, Debug)]
pub struct Source<'a> {
    /// The file as the user named it (or a caller's name for an in-memory map).
    pub file: &'a str,
    /// Name of the reader that read it ([`crate::io::Format::name`]).
    pub format: &'a str,
    /// Index of the channel read.
    pub channel: usize,
    /// Name of that channel, when the file has one.
    pub channel_name: Option<&'a str>,
    /// What the reader noted (assumed units, resampling, flags used).
    pub notes: &'a [String],
}

/// The report and the warnings it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct StatsReport {
    /// What to distrust, in words (also under `warnings` in [`StatsReport::json`]); the
    /// CLI prints each on stderr after the file name.
    pub warnings: Vec<String>,
    /// The JSON object `lustre fit stats --json` prints.
    pub json: Value,
}

/// The report of the analysis `s` of the scan `source`.
pub fn report(source: &Source<'_>, s: &Summary) -> StatsReport {
    let warnings = warnings(s);
    let t = &s.prepared.scan;
    let form = &s.prepared.form;
    let json = json!({
        "file": source.file,
        "format": source.format,
        "channel": { "index": source.channel, "name": source.channel_name },
        "grid": [t.nx, t.ny],
        "pixel_m": [t.dx, t.dy],
        "filled_points": s.prepared.filled,
        "notes": source.notes.iter().chain(&s.notes).collect::<Vec<_>>(),
        "warnings": warnings,
        "level": {
            "kind": form.level.name(),
            "removed_rms_m": form.removed_rms,
            "terms": form.terms.iter().map(|x| json!({"x_pow": x.i, "y_pow": x.j, "coefficient_si": x.c})).collect::<Vec<_>>(),
            "residual_form_fraction": form.residual_form.map(|r| r.1),
            "residual_shows_form": form.warning().is_some(),
        },
        "quality": {
            "invalid": s.quality.invalid,
            "outliers": s.quality.outliers,
            "outlier_points": s.quality.outlier_count,
            "units": s.quality.units,
        },
        "sq_m": s.stats.sq,
        "rms_slope": s.stats.rms_slope(),
        "iso25178": iso25178(t),
        "rq_lines_m": s.stats.rq_lines,
        "rdq_x": num(s.stats.rdq_x),
        "kc": kc(s),
        "anisotropy": anisotropy(s),
        "psd": { "f_per_m": s.line_psd.f, "p": s.line_psd.p },
        "units": "SI; lc_m is the Matérn range Lc (physics.md), l_1d_m = 2π·Lc is the data-README 1D-form length; psd p in m³ (one-sided, f in cycles/m, along x; psd_y along y)",
    });
    StatsReport { warnings, json }
}

/// A finite number, or `null` (JSON has no NaN or infinity).
fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// What the analysis found that makes a number doubtful.
fn warnings(s: &Summary) -> Vec<String> {
    let (form, kc) = (&s.prepared.form, &s.kc);
    let mut warnings: Vec<String> = Vec::new();
    if let Some(f) = &s.flat {
        warnings.push(format!(
            "{f}; the statistics stand but the K-correlation fit is of rounding noise, and \
             `lustre fit` refuses this scan"
        ));
    }
    if let Some(w) = form.warning() {
        warnings.push(w);
    }
    if let Some(r) = kc.reason {
        warnings.push(format!("K-correlation fit degenerate: {}", r.describe()));
    }
    if let Some(a) = s.anisotropy.as_ref().filter(|a| a.anisotropic) {
        warnings.push(format!(
            "anisotropic surface ({}, lay at {:.1}°): the isotropic \
             K-correlation fit is an approximation",
            a.ratio_text(),
            a.lay_direction_deg()
        ));
    }
    if s.flat.is_none()
        && kc.reason.is_none()
        && let Some(w) =
            crate::material_file::variance_mismatch(kc.params.sigma, s.stats.sq, kc.range, false)
    {
        warnings.push(w);
    }
    warnings.extend(quality_warnings(&s.quality));
    warnings
}

/// Warnings for what the checks of a scan found.
pub fn quality_warnings(q: &Quality) -> Vec<String> {
    [
        ("invalid", &q.invalid),
        ("outliers", &q.outliers),
        ("units", &q.units),
    ]
    .into_iter()
    .filter_map(|(k, v)| v.as_ref().map(|v| format!("{k}: {v}")))
    .collect()
}

/// The K-correlation fit.
fn kc(s: &Summary) -> Value {
    let kc = &s.kc;
    json!({
        "sigma_m": kc.params.sigma,
        "lc_m": kc.params.lc,
        "l_1d_m": kc.params.l_cycles(),
        "gamma": kc.params.gamma,
        "degenerate": kc.degenerate,
        "reason": kc.reason.map(|r| r.describe()),
        "stderr": { "sigma_m": num(kc.stderr.sigma), "lc_m": num(kc.stderr.lc), "gamma": num(kc.stderr.gamma) },
        "fit_f_range_per_m": [num(kc.range.0), num(kc.range.1)],
        "asymptote": kc.asymptote.map(|a| json!({
            "exponent": a.exponent,
            "prefactor_si": a.prefactor,
            "f_range_per_m": [a.range.0, a.range.1],
            "form": "P1 = prefactor · f^(−exponent), P1 in m³, f in cycles/m",
        })),
    })
}

/// Direction dependence (maps only).
fn anisotropy(s: &Summary) -> Value {
    json!(s.anisotropy.as_ref().map(|a| json!({
        "rms_slope_x": a.rms_slope_x,
        "rms_slope_y": a.rms_slope_y,
        "ratio_xy": num(a.ratio_xy),
        "principal_rms_slopes": [a.principal.0, a.principal.1],
        "ratio": num(a.ratio),
        "slope_direction_deg": a.slope_direction_deg,
        "lay_direction_deg": a.lay_direction_deg(),
        "anisotropic": a.anisotropic,
        "psd_rms_slopes": [a.psd_slopes.0, a.psd_slopes.1],
        "psd_y": { "f_per_m": a.psd_y.f, "p": a.psd_y.p },
    })))
}

/// The ISO 25178-2 height parameters, the ACF with its correlation length and the height
/// histogram of a prepared scan.
fn iso25178(t: &Topography) -> Value {
    let num = |v: f64| v.is_finite().then_some(v);
    let p = areal::height_params(t);
    let acf = areal::acf(t);
    let hist = areal::histogram(t, 64);
    json!({
        "sa_m": num(p.sa),
        "sz_m": num(p.sz),
        "ssk": num(p.ssk),
        "sku": num(p.sku),
        "acf": acf.as_ref().map(|a| json!({
            "r_m": a.r,
            "rho": a.rho,
            "correlation_length_m": a.length(areal::ACF_THRESHOLD),
            "threshold": areal::ACF_THRESHOLD,
        })),
        "histogram": hist.map(|h| json!({
            "edges_m": h.edges,
            "counts": h.counts,
            "density_per_m": h.density,
        })),
        "conventions": "heights about their mean; Sz = max − min; Ssk, Sku over Sq³, Sq⁴; ACF \
            ρ = 1 − A/Sq², A the non-periodic height-difference ACF over every direction, \
            averaged radially in one-pixel bins to half the scan; correlation length where ρ \
            first falls to the threshold (null: longer than half the scan)",
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kc::KcParams;
    use crate::pipeline::summarise;

    fn source<'a>(notes: &'a [String]) -> Source<'a> {
        Source {
            file: "mem.x3p",
            format: "x3p",
            channel: 2,
            channel_name: Some("Z"),
            notes,
        }
    }

    /// A rough isotropic map: the report carries the file, the fit and the analysis numbers
    /// as they are, and a warning list equal to the one the caller prints.
    #[test]
    fn report_holds_the_analysis_numbers() {
        let p = KcParams {
            sigma: 0.2e-6,
            lc: 2e-6,
            gamma: 3.0,
        };
        let t = crate::synth::kc_surface(128, 128, 0.25e-6, p, 7);
        let s = summarise(t, None).unwrap();
        let notes = vec!["read note".to_string()];
        let r = report(&source(&notes), &s);
        let j = &r.json;
        assert_eq!(j["file"], "mem.x3p");
        assert_eq!(j["channel"]["index"], 2);
        assert_eq!(j["channel"]["name"], "Z");
        assert_eq!(j["grid"], json!([128, 128]));
        assert_eq!(j["notes"][0], "read note");
        assert_eq!(j["sq_m"].as_f64(), Some(s.stats.sq));
        assert_eq!(j["kc"]["sigma_m"].as_f64(), Some(s.kc.params.sigma));
        assert_eq!(j["kc"]["gamma"].as_f64(), Some(s.kc.params.gamma));
        assert_eq!(j["psd"]["p"].as_array().unwrap().len(), s.line_psd.p.len());
        assert_eq!(j["warnings"], json!(r.warnings));
        assert!(j["anisotropy"].is_object());
        assert!(j["iso25178"]["sa_m"].as_f64().unwrap() > 0.0);
    }

    /// Constant heights: the flat-scan warning is raised, and the numbers that cannot be
    /// computed are `null`, never NaN (which is not JSON).
    #[test]
    fn flat_scan_warns_and_keeps_json_valid() {
        let t = Topography {
            nx: 64,
            ny: 64,
            dx: 1e-6,
            dy: 1e-6,
            heights: vec![1e-6; 64 * 64],
            channel: "Z".into(),
            format: "test",
        };
        let s = summarise(t, None).unwrap();
        let r = report(&source(&[]), &s);
        assert!(
            r.warnings
                .iter()
                .any(|w| w.contains("`lustre fit` refuses")),
            "{:?}",
            r.warnings
        );
        let text = serde_json::to_string(&r.json).unwrap();
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
        let back: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back["warnings"], json!(r.warnings));
    }

    #[test]
    fn non_finite_numbers_are_null() {
        assert_eq!(num(f64::NAN), Value::Null);
        assert_eq!(num(f64::INFINITY), Value::Null);
        assert_eq!(num(1.5), json!(1.5));
    }
}
