//! `--reference`: the models (and the scan's explicit BRDF) ranked against a measured BRDF.

use std::path::Path;

use crate::{JudgeError, invalid};
use fit::explicit_brdf::{ExplicitBrdf, Validity};

use crate::LOG_FLOOR;
use crate::compare::{Judged, Score, cos_d, dvec, ln10_floor};
use brdf::Fresnel;

/// The comparison against a measured BRDF file.
pub(crate) struct ReferenceResult {
    pub(crate) file: String,
    pub(crate) rows: usize,
    pub(crate) skipped_rows: usize,
    /// (key, label, score); the explicit BRDF of the scan as key "explicit".
    pub(crate) scores: Vec<(String, String, Score)>,
}

pub(crate) fn judge_reference(
    path: &Path,
    judged: &[Judged],
    e: &ExplicitBrdf,
    fresnel: &Fresnel,
) -> Result<ReferenceResult, JudgeError> {
    let rows = read_reference(path)?;
    let usable: Vec<&[f64; 5]> = rows.iter().filter(|r| r[4] > 0.0).collect();
    if usable.is_empty() {
        return Err(invalid!(
            "{}: no row with a positive brdf value to compare in log space",
            path.display()
        ));
    }
    let mut scores: Vec<(String, String, Score)> = judged
        .iter()
        .map(|j| (j.c.key.clone(), j.c.label.clone(), Score::default()))
        .collect();
    let mut ex = Score::default();
    for r in &usable {
        let (ti, to, po, lam, f) = (
            r[0].to_radians(),
            r[1].to_radians(),
            r[2].to_radians(),
            r[3],
            r[4],
        );
        let wi = [ti.sin(), 0.0, ti.cos()];
        let wo = [to.sin() * po.cos(), to.sin() * po.sin(), to.cos()];
        let lf = f.log10();
        for (j, s) in judged.iter().zip(scores.iter_mut()) {
            let v = j.c.bxdf.eval(dvec(wi), dvec(wo), lam);
            s.2.add(ln10_floor(v, f * LOG_FLOOR) - lf);
        }
        let w = e.angular_window(wi, lam * 1e-9);
        let est = e.scattered(wi, wo, lam * 1e-9);
        let k = 2.0 * std::f64::consts::PI / (lam * 1e-9);
        let spec = est.value / if e.is_profile() { k } else { k * k };
        if !e.is_profile() && w.classify(wi, wo, spec) == Validity::Valid {
            let v = est.value * fresnel.reflectance(cos_d(wi, wo), lam);
            ex.add(ln10_floor(v, f * LOG_FLOOR) - lf);
        }
    }
    scores.push((
        "explicit".into(),
        "explicit BRDF of the scan (inside its window)".into(),
        ex,
    ));
    scores.sort_by(|a, b| {
        let (x, y) = (a.2.rms(), b.2.rms());
        x.is_nan().cmp(&y.is_nan()).then(x.total_cmp(&y))
    });
    Ok(ReferenceResult {
        file: path.display().to_string(),
        rows: rows.len(),
        skipped_rows: rows.len() - usable.len(),
        scores,
    })
}

/// Largest reference CSV read (a goniometer's BRDF table is a few MB).
const MAX_REFERENCE_BYTES: u64 = 64 << 20;

/// Rows `[θi, θo, φo, λ, brdf]` of a reference CSV.
pub(crate) fn read_reference(path: &Path) -> Result<Vec<[f64; 5]>, JudgeError> {
    let bytes = safe_io::read_input(path, "reference BRDF", MAX_REFERENCE_BYTES)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| invalid!("{}: the reference is not UTF-8 text", path.display()))?;
    let names = [
        "theta_i_deg",
        "theta_o_deg",
        "phi_o_deg",
        "lambda_nm",
        "brdf",
    ];
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (hline, header) = lines
        .next()
        .ok_or_else(|| invalid!("{}: empty file", path.display()))?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_ascii_lowercase())
        .collect();
    let mut idx = [0usize; 5];
    for (i, n) in names.iter().enumerate() {
        idx[i] = cols.iter().position(|c| c == n).ok_or_else(|| {
            invalid!(
                "{}:{}: header has no column `{n}` (need {}; got {})",
                path.display(),
                hline + 1,
                names.join(", "),
                cols.join(", ")
            )
        })?;
    }
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    let mut rows = Vec::new();
    for (ln, line) in lines {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let mut r = [0.0; 5];
        for (i, &c) in idx.iter().enumerate() {
            let s = f.get(c).copied().unwrap_or("");
            r[i] = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    invalid!(
                        "{}:{}: column `{}` = {s:?} is not a finite number",
                        path.display(),
                        ln + 1,
                        names[i]
                    )
                })?;
        }
        let bad = |what: &str| invalid!("{}:{}: {what}", path.display(), ln + 1);
        if !(0.0..90.0).contains(&r[0]) || !(0.0..90.0).contains(&r[1]) {
            return Err(bad("theta_i_deg and theta_o_deg must lie in [0, 90)"));
        }
        if !(lo..=hi).contains(&r[3]) {
            return Err(bad(&format!("lambda_nm must lie in {lo}–{hi} nm")));
        }
        if r[4] < 0.0 {
            return Err(bad("brdf must not be negative"));
        }
        rows.push(r);
    }
    if rows.is_empty() {
        return Err(invalid!(
            "{}: no data rows after the header",
            path.display()
        ));
    }
    Ok(rows)
}
