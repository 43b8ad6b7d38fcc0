//! The material file: a TOML document the renderer can `include`, holding every model's
//! parameters (lengths in µm, angles in degrees) and the provenance of the fit, in the one
//! schema `brdf::spec::MaterialFile` every reader shares.
//!
//! Length conventions: `lc_um` is the Matérn range Lc of physics.md §2 (rad convention);
//! the reference-table length of the 1D form is `2π·lc_um` and is written as
//! `[fit].l_1d_um`. The `[psd]` table is the isotropic 2D PSD in rad/µm with
//! `∫ P d²ζ = σ²` (µm⁴).
//!
//! The parameters are those of the analysis' candidates ([`crate::candidates`]), so every
//! one is in the renderer's range. What is unreliable — a degenerate K-correlation fit, a
//! clamped α, a PSD table the renderer cannot use, a two-scale split without a measured β,
//! form left in the residual, anisotropy the isotropic models ignore — is listed in
//! `[reliability]`, and the model defaults to one whose inputs are reliable.

use crate::candidates::{Candidate, Family, candidates};
use crate::pipeline::Analysis;
use crate::two_scale::BetaSource;
use crate::{FitError, sha256};
use brdf::Metal;
use brdf::spec::file::{
    Anisotropy, Asymptote, DestretchedPsd, FitDiagnostics, Form, Kc2d, MaterialFile, Named,
    Provenance as ProvenanceTable, PsdMap, PsdTable, Reliability, Split,
};
use brdf::spec::{FresnelSpec, MaterialDesc, ModelKind, ModelSpec};

const UM: f64 = 1e6;

/// Inputs that are not part of the analysis.
#[derive(Debug, Clone)]
pub struct Provenance<'a> {
    /// Scan file name as given.
    pub file: &'a str,
    /// Raw bytes of the scan file (for the checksum).
    pub bytes: &'a [u8],
    /// Stylus profile file and bytes, if merged.
    pub stylus: Option<(&'a str, &'a [u8])>,
    /// Merge cutoff [rad/µm].
    pub merge_cutoff_rad_per_um: f64,
    /// Metal name for `[material].metal`.
    pub metal: &'a str,
    /// Model name for `[material].model`; `"auto"` chooses the model whose inputs are
    /// reliable (GHS with a sound K-correlation fit, else the measured PSD, else GGX).
    pub model: &'a str,
    /// What the reader had to assume or change (resampling, units, …).
    pub notes: &'a [String],
}

/// How far the K-correlation σ may be from the measured Sq before the material file
/// says so: a factor 2 (a quarter or four times the variance).
pub const SIGMA_SQ_RATIO_MAX: f64 = 2.0;

/// The problem when the fitted σ (`sigma`, of the model over all frequencies) and the
/// measured rms height (`sq`), both in metres, differ by more than [`SIGMA_SQ_RATIO_MAX`]. The fit
/// matches the PSD inside its band (`band`, cycles/m); σ ≪ Sq means most of the height
/// variance lies outside it, at wavelengths longer than the band (waviness, form), which
/// the GHS models then render as mirror reflection; σ ≫ Sq means the fitted roll-off lies
/// beyond the scan, and the model has more long-wavelength roughness than was measured.
/// Either way g = (kσ(cosθi + cosθo))², the specular weight e^−g and the lobe width
/// follow σ, not Sq.
pub fn variance_mismatch(
    sigma: f64,
    sq: f64,
    band: (f64, f64),
    suggest_measured_psd: bool,
) -> Option<String> {
    if !(sigma.is_finite() && sq.is_finite() && sigma > 0.0 && sq > 0.0) {
        return None;
    }
    let ratio = sigma / sq;
    let (sigma_um, sq_um) = (sigma * UM, sq * UM);
    if (1.0 / SIGMA_SQ_RATIO_MAX..=SIGMA_SQ_RATIO_MAX).contains(&ratio) {
        return None;
    }
    let (lo, hi) = band;
    let wavelengths = if lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo {
        format!(" (wavelengths {:.3e}–{:.3e} µm)", UM / hi, UM / lo)
    } else {
        String::new()
    };
    // Suggested only where the material file's own table builds (the caller knows).
    let (short, long) = if suggest_measured_psd {
        (
            ", otherwise compare with model = \"measured_psd\", whose table holds the whole \
             measured spectrum",
            ", otherwise compare with model = \"measured_psd\"",
        )
    } else {
        ("", "")
    };
    Some(if ratio < 1.0 {
        format!(
            "the K-correlation σ {sigma_um:.4e} µm holds {:.2} % of the measured height \
             variance (Sq {sq_um:.4e} µm): the rest lies outside the fitted band{wavelengths}, \
             mostly at longer wavelengths, and the GHS models render it as mirror \
             reflection; if it is form, level it away (--level){short}",
            100.0 * ratio * ratio
        )
    } else {
        format!(
            "the K-correlation σ {sigma_um:.4e} µm is {ratio:.2}× the measured Sq \
             {sq_um:.4e} µm: the fitted roll-off lies beyond the scan{wavelengths}, so the \
             model holds long-wavelength roughness that was not measured and renders \
             rougher than the scan; a longer scan (or a stylus profile, --stylus) would \
             measure it{long}"
        )
    })
}

/// The document: every table filled from the analysis and its candidates.
pub fn build(a: &Analysis, prov: &Provenance<'_>) -> MaterialFile {
    let fresnel = Metal::from_name(prov.metal).map_or(FresnelSpec::One, FresnelSpec::Metal);
    let cands = candidates(a, &fresnel);
    let find = |f: Family| cands.iter().find(|c| c.family == f);
    let kc = find(Family::GhsSsa).expect("the GHS SSA candidate");
    let psd = find(Family::MeasuredPsd).expect("the measured-PSD candidate");
    let aniso = anisotropy(a, find(Family::Ggx).and_then(alpha_of).unwrap_or(f64::NAN));
    let (two_scale, split_problems) = splits(a, &cands);
    let flagged = a.anisotropy.as_ref().filter(|an| an.anisotropic);
    let mut material = material_desc(prov.metal, &cands, flagged);
    let kc_ok = kc.problems.is_empty();
    let variance = kc_ok
        .then(|| variance_mismatch(a.kc.params.sigma, a.stats.sq, a.kc.range, psd.sound()))
        .flatten();
    let (model, why) = chosen_model(prov.model, kc, psd);
    let aniso_fit = (a.anisotropy.as_ref())
        .filter(|an| an.anisotropic)
        .and_then(|an| an.kc.as_ref())
        .and_then(|r| r.as_ref().ok());
    material.model = Some(model);
    let mut psd_table = psd_table(psd);
    if let Some(t) = psd_table.as_mut() {
        let residual = aniso_fit.map_or(f64::NAN, |f| f.rms_log_residual_elliptical);
        t.destretched = find(Family::MeasuredPsdAniso).and_then(|c| destretched_table(c, residual));
        t.map = find(Family::MeasuredPsd2dSsa).and_then(map_table);
    }
    let mut reliability = reliability(&Flags {
        cands: &cands,
        model,
        why,
        form: a.form.warning(),
        anisotropy: aniso.as_ref().and_then(|t| t.warning.clone()),
        non_elliptical: aniso_fit.and_then(crate::candidates::non_elliptical),
        flagged: a.anisotropy.as_ref().is_some_and(|an| an.anisotropic),
        variance,
        split_problems,
        quality: &a.quality,
    });
    reliability.psd_extrapolation = psd_extrapolation(psd_table.as_ref());
    MaterialFile {
        provenance: provenance(a, prov),
        material,
        fit: diagnostics(a, kc),
        reliability,
        form: form(a),
        anisotropy: aniso,
        kc_2d: a.kc_2d.map(|f| kc_2d(&f)),
        two_scale,
        psd: psd_table,
    }
}

/// The isotropic roughness of a microfacet candidate.
fn alpha_of(c: &Candidate) -> Option<f64> {
    match c.spec.as_ref()?.model {
        ModelSpec::Ggx { alpha_x, .. } | ModelSpec::Beckmann { alpha_x, .. } => Some(alpha_x),
        _ => None,
    }
}

/// `[material]`: the metal, the K-correlation parameters, the NDF roughness, and on a
/// surface flagged anisotropic (`flagged`) its axes: `angle_deg` is the direction across
/// the lay in the scan's frame (x along a scan line, y along the line index, the
/// renderer's tangent and bitangent; degrees from x towards y), the stretched
/// K-correlation's φ₀ where that fit was made, else the steepest slope direction;
/// `lx_um`/`ly_um` and the GGX `alpha_x`/`alpha_y` lie along it and across it, so every
/// model the file offers renders the scan as it lay.
fn material_desc(
    metal: &str,
    cands: &[Candidate],
    flagged: Option<&crate::anisotropy::Anisotropy>,
) -> MaterialDesc {
    let find = |f: Family| cands.iter().find(|c| c.family == f);
    let surface = find(Family::GhsSsa)
        .and_then(|c| c.spec.as_ref())
        .and_then(|s| s.model.surface());
    let stretched = find(Family::GhsAniso)
        .and_then(|c| c.spec.as_ref())
        .and_then(|s| match &s.model {
            ModelSpec::GhsAniso { surface, .. } => Some(*surface),
            _ => None,
        });
    let alpha = find(Family::Ggx).and_then(alpha_of);
    let angle_deg = stretched
        .map(|s| s.angle_deg)
        .or(flagged.map(|an| an.slope_direction_deg));
    let axes = match (flagged, alpha, angle_deg) {
        (Some(an), Some(alpha), Some(angle)) => {
            let fix = |v: f64| crate::candidates::renderer_alpha(v).0;
            let (x, y) = an.ggx_along(alpha, angle);
            Some([fix(x), fix(y)])
        }
        _ => None,
    };
    MaterialDesc {
        metal: Some(metal.to_string()),
        sigma_um: surface.map(|s| s.sigma_um),
        lc_um: surface.map(|s| s.lc_um),
        gamma: surface.map(|s| s.gamma),
        alpha: find(Family::Ggx).and_then(alpha_of),
        alpha_beckmann: find(Family::Beckmann).and_then(alpha_of),
        alpha_x: axes.map(|a| a[0]),
        alpha_y: axes.map(|a| a[1]),
        lx_um: stretched.map(|s| s.lx_um),
        ly_um: stretched.map(|s| s.ly_um),
        angle_deg,
        ..MaterialDesc::default()
    }
}

/// The model `[material]` recommends and why: `auto` takes the full GHS where the
/// K-correlation fit is sound, else the measured PSD where its table is, else GGX.
fn chosen_model(asked: &str, kc: &Candidate, psd: &Candidate) -> (ModelKind, String) {
    if asked != "auto" {
        let m = ModelKind::from_name(asked).unwrap_or(ModelKind::Ghs);
        return (m, "chosen with --model".into());
    }
    if kc.problems.is_empty() {
        (
            ModelKind::Ghs,
            "auto: the K-correlation fit is sound".into(),
        )
    } else if psd.sound() {
        (
            ModelKind::MeasuredPsd,
            "auto: the K-correlation fit is degenerate, the measured PSD is used".into(),
        )
    } else {
        (
            ModelKind::Ggx,
            "auto: neither the K-correlation fit nor the PSD table is usable".into(),
        )
    }
}

/// `[reliability].psd_extrapolation`: the band the `[psd]` table measures and the tails
/// `model = "measured_psd"` assumes beyond it (`brdf::statistics::TabulatedPsd`: a
/// K-correlation roll-off below the band, matched to the first segment in value and slope,
/// and the last segment's power law above it). The full GHS of a table held flat below the
/// band disagreed with the direct transform of its own covariance by up to 26 %.
pub fn psd_extrapolation(psd: Option<&PsdTable>) -> String {
    let Some(Ok(t)) = psd
        .filter(|p| p.usable)
        .map(|p| brdf::statistics::TabulatedPsd::new(&p.zeta_rad_per_um, &p.p_um4))
    else {
        return "not used: the [psd] table is not usable (see psd)".into();
    };
    let (lo, hi) = t.band_rad_per_um();
    let below = match t.low_rolloff() {
        (zc, beta) if zc.is_finite() => format!(
            "rolls off as (1 + (ζ/{zc:.4})²)^−{beta:.3} (K-correlation shape with the \
             table's fitted tail exponent, matched to its first segment in value and slope)"
        ),
        _ => "is held at its first value (the lowest bins rise, or fall too steeply to \
              roll off)"
            .into(),
    };
    format!(
        "assumed, not measured: the table covers {lo:.4}–{hi:.4} rad/µm; below it the PSD \
         {below}; above it it falls as ζ^{:.3} (its last segment)",
        t.high_slope()
    )
}

/// What `[reliability]` is made from.
struct Flags<'a> {
    cands: &'a [Candidate],
    model: ModelKind,
    why: String,
    form: Option<String>,
    anisotropy: Option<String>,
    /// The 2-D PSD is not constant on ellipses ([`crate::candidates::non_elliptical`]).
    non_elliptical: Option<String>,
    /// The scan is flagged anisotropic.
    flagged: bool,
    variance: Option<String>,
    split_problems: Vec<String>,
    quality: &'a crate::pipeline::Quality,
}

/// `[reliability]`: each part `"ok"` or its problem, the model's reason, and the list of
/// parts flagged.
fn reliability(f: &Flags<'_>) -> Reliability {
    let problems = |families: &[Family]| -> Option<String> {
        let all: Vec<String> = (f.cands.iter())
            .filter(|c| families.contains(&c.family))
            .flat_map(|c| c.problems.iter().cloned())
            .collect();
        (!all.is_empty()).then(|| all.join("; "))
    };
    let kc = problems(&[Family::GhsSsa])
        .map(|p| format!("{p}; [material] holds the bounded best estimate"));
    let alpha = problems(&[Family::Ggx, Family::Beckmann]);
    let psd = problems(&[Family::MeasuredPsd]);
    // Only a scan flagged anisotropic has the table; for the others the candidate's one
    // problem says so, which is not a fault of the scan.
    let flagged = f.flagged;
    let psd_destretched = problems(&[Family::MeasuredPsdAniso])
        .into_iter()
        .chain(f.non_elliptical.clone())
        .reduce(|a, b| format!("{a}; {b}"))
        .filter(|_| flagged);
    let two_scale = (!f.split_problems.is_empty())
        .then(|| format!("see problem in {}", f.split_problems.join(", ")));
    let q = f.quality;
    let parts = [
        ("kc", &kc),
        ("alpha", &alpha),
        ("psd", &psd),
        ("psd_destretched", &psd_destretched),
        ("two_scale", &two_scale),
        ("form", &f.form),
        ("anisotropy", &f.anisotropy),
        ("variance", &f.variance),
        ("invalid", &q.invalid),
        ("outliers", &q.outliers),
        ("units", &q.units),
    ];
    let unreliable = (parts.iter())
        .filter(|(_, p)| p.is_some())
        .map(|(n, _)| n.to_string())
        .collect();
    let uses_kc = matches!(f.model, ModelKind::Ghs | ModelKind::GhsSsa);
    let model = if uses_kc && kc.is_some() {
        format!(
            "{}; WARNING: it uses the unreliable K-correlation parameters",
            f.why
        )
    } else if uses_kc && f.variance.is_some() {
        format!(
            "{}; WARNING: its σ does not match the measured Sq (see [reliability].variance)",
            f.why
        )
    } else if f.model == ModelKind::MeasuredPsd && psd.is_some() {
        format!("{}; WARNING: the renderer rejects the PSD table", f.why)
    } else {
        f.why.clone()
    };
    let ok = |p: &Option<String>| p.clone().unwrap_or_else(|| "ok".into());
    Reliability {
        kc: ok(&kc),
        alpha: ok(&alpha),
        psd: ok(&psd),
        psd_extrapolation: String::new(),
        psd_destretched: if flagged {
            ok(&psd_destretched)
        } else {
            "not written: the scan is not flagged anisotropic".into()
        },
        two_scale: ok(&two_scale),
        form: ok(&f.form),
        anisotropy: ok(&f.anisotropy),
        variance: ok(&f.variance),
        model,
        invalid: ok(&q.invalid),
        outliers: ok(&q.outliers),
        units: ok(&q.units),
        unreliable,
    }
}

/// `[two_scale.cutoff_N]` from the two-scale candidates, and the names of those with a
/// problem.
fn splits(a: &Analysis, cands: &[Candidate]) -> (Named<Split>, Vec<String>) {
    let mut problems = Vec::new();
    let mut out = Vec::new();
    for (t, c) in a
        .two_scale
        .iter()
        .zip(cands.iter().filter(|c| c.family == Family::TwoScale))
    {
        let Some(ModelSpec::TwoScale { beta, surface, .. }) = c.spec.as_ref().map(|s| &s.model)
        else {
            continue;
        };
        let name = format!("cutoff_{}", t.multiple.round() as i64);
        let problem = (!c.problems.is_empty()).then(|| c.problems.join("; "));
        if problem.is_some() {
            problems.push(name.clone());
        }
        let split = Split {
            beta: *beta,
            beta_source: match t.beta_source {
                BetaSource::Map => "map",
                BetaSource::Psd => "psd",
                BetaSource::Unresolved => "unresolved",
            }
            .into(),
            sigma_um: surface.sigma_um,
            lc_um: surface.lc_um,
            gamma: surface.gamma,
            cutoff_um: t.cutoff * UM,
            fit_f_range_per_m: finite_range(t.kc.range),
            kc_degenerate: t.kc.degenerate,
            problem,
        };
        out.push((name, split));
    }
    (Named(out), problems)
}

/// `[psd]`: the measured-PSD candidate's table, or the empty, unusable table saying why.
fn psd_table(c: &Candidate) -> Option<PsdTable> {
    let Some(ModelSpec::MeasuredPsd {
        zeta_rad_per_um,
        psd_um4,
        ..
    }) = c.spec.as_ref().map(|s| &s.model)
    else {
        return None;
    };
    let mut integral = 0.0;
    for i in 1..zeta_rad_per_um.len() {
        let f = |j: usize| 2.0 * std::f64::consts::PI * zeta_rad_per_um[j] * psd_um4[j];
        integral += 0.5 * (f(i) + f(i - 1)) * (zeta_rad_per_um[i] - zeta_rad_per_um[i - 1]);
    }
    let info = c.table.as_ref();
    Some(PsdTable {
        source: info.map_or("", |t| t.source).to_string(),
        integral_um2: integral,
        usable: c.sound(),
        tail_exponent: info.map(|t| t.tail_exponent),
        zeta_rad_per_um: zeta_rad_per_um.clone(),
        p_um4: psd_um4.clone(),
        destretched: None,
        map: None,
    })
}

/// `[psd.map]`: the 2-D PSD candidate's grid, with the share of σ² its assumed
/// continuation beyond the grid holds.
fn map_table(c: &Candidate) -> Option<PsdMap> {
    let Some(ModelSpec::MeasuredPsd2dSsa { surface, .. }) = c.spec.as_ref().map(|s| &s.model)
    else {
        return None;
    };
    let tail_fraction = surface.psd().map_or(f64::NAN, |t| t.tail_fraction());
    Some(PsdMap {
        source: c.table.as_ref().map_or("", |t| t.source).to_string(),
        usable: c.sound(),
        tail_fraction,
        tail_exponent: surface.tail_exponent,
        half_nx: surface.half_nx,
        half_ny: surface.half_ny,
        dzx_rad_per_um: surface.dzx_rad_per_um,
        dzy_rad_per_um: surface.dzy_rad_per_um,
        p_um4: surface.psd_um4.clone(),
    })
}

/// `[psd.destretched]`: the stretched measured-PSD candidate's table.
fn destretched_table(c: &Candidate, residual: f64) -> Option<DestretchedPsd> {
    let Some(ModelSpec::MeasuredPsdAniso { surface, .. }) = c.spec.as_ref().map(|s| &s.model)
    else {
        return None;
    };
    Some(DestretchedPsd {
        source: c.table.as_ref().map_or("", |t| t.source).to_string(),
        usable: c.sound(),
        rms_log_residual: residual,
        zeta_rad_per_um: surface.zeta_rad_per_um.clone(),
        p_um4: surface.psd_um4.clone(),
    })
}

/// `[provenance]`.
fn provenance(a: &Analysis, prov: &Provenance<'_>) -> ProvenanceTable {
    let mut notes: Vec<String> = prov.notes.to_vec();
    notes.extend(a.notes.iter().cloned());
    let level_name = a.form.level.name();
    ProvenanceTable {
        file: prov.file.to_string(),
        sha256: sha256::hex(prov.bytes),
        fit_f_range_per_m: finite_range(a.kc.range),
        tool: format!("lustre fit {}", env!("CARGO_PKG_VERSION")),
        format: a.scan.format.to_string(),
        channel: a.scan.channel.clone(),
        grid: [a.scan.nx, a.scan.ny],
        pixel_um: [a.scan.dx * UM, a.scan.dy * UM],
        levelling: match a.form.level {
            crate::level::Level::None => "harmonic fill of invalid points, no levelling".into(),
            crate::level::Level::Line if !a.scan.is_profile() => {
                "harmonic fill of invalid points, least-squares line per scan line".into()
            }
            _ => format!("harmonic fill of invalid points, least-squares {level_name}"),
        },
        filled_points: a.filled,
        notes,
        stylus_file: prov.stylus.map(|s| s.0.to_string()),
        stylus_sha256: prov.stylus.map(|s| sha256::hex(s.1)),
        merge_cutoff_rad_per_um: prov.stylus.map(|_| prov.merge_cutoff_rad_per_um),
    }
}

/// `[fit]`: the KC fit's uncertainties and residual, the statistics, the NDF fits.
fn diagnostics(a: &Analysis, kc: &Candidate) -> FitDiagnostics {
    let lc_um = (kc.spec.as_ref())
        .and_then(|s| s.model.surface())
        .map_or(f64::NAN, |s| s.lc_um);
    FitDiagnostics {
        sigma_um_err: finite(a.kc.stderr.sigma * UM),
        lc_um_err: finite(a.kc.stderr.lc * UM),
        gamma_err: finite(a.kc.stderr.gamma),
        l_1d_um: lc_um * 2.0 * std::f64::consts::PI,
        kc_rms_log_residual: finite(a.kc.rms_log_residual),
        kc_points: a.kc.points,
        kc_degenerate: a.kc.degenerate,
        kc_reason: a.kc.reason.map(|r| r.describe().to_string()),
        kc_asymptote: a.kc.asymptote.map(|p| Asymptote {
            exponent: p.exponent,
            prefactor_si: p.prefactor,
            f_range_per_m: [p.range.0, p.range.1],
        }),
        sq_um: a.stats.sq * UM,
        rms_slope: a.stats.rms_slope(),
        alpha_ggx_rms_log_residual: finite(a.ndf.alpha_ggx.1),
        alpha_beckmann_rms_log_residual: finite(a.ndf.alpha_beckmann.1),
        alpha_beckmann_moment: finite(a.ndf.alpha_beckmann_moment),
    }
}

/// `[form]`.
fn form(a: &Analysis) -> Form {
    Form {
        level: a.form.level.name().into(),
        removed_rms_um: a.form.removed_rms * UM,
        terms: (a.form.terms.iter())
            .map(|t| {
                [
                    t.i as f64,
                    t.j as f64,
                    t.c * UM.powi(1 - t.i as i32 - t.j as i32),
                ]
            })
            .collect(),
        residual_form_fraction: a.form.residual_form.map(|r| r.1),
        warning: a.form.warning(),
    }
}

/// `[anisotropy]`, with the principal-axis roughness of GGX (scaled from the isotropic
/// `alpha`) and Beckmann in the renderer's range.
fn anisotropy(a: &Analysis, alpha: f64) -> Option<Anisotropy> {
    let an = a.anisotropy.as_ref()?;
    let fix = |v: f64| crate::candidates::renderer_alpha(v).0;
    let (gx, gy) = an.ggx(alpha);
    let (bx, by) = an.beckmann();
    Some(Anisotropy {
        rms_slope_x: an.rms_slope_x,
        rms_slope_y: an.rms_slope_y,
        ratio_xy: finite(an.ratio_xy),
        principal_rms_slopes: [an.principal.0, an.principal.1],
        ratio: finite(an.ratio),
        slope_direction_deg: an.slope_direction_deg,
        lay_direction_deg: an.lay_direction_deg(),
        psd_rms_slopes: [an.psd_slopes.0, an.psd_slopes.1],
        anisotropic: an.anisotropic,
        alpha_ggx: [fix(gx), fix(gy)],
        alpha_beckmann: [fix(bx), fix(by)],
        warning: an.anisotropic.then(|| {
            format!(
                "anisotropic ({}; {}, lay at {:.1}°): the isotropic K-correlation and NDF fits \
                 average over directions and are only an approximation; \
                 [material].alpha_x/alpha_y (GGX's; a beckmann include reads them too) lie along \
                 [material].angle_deg, across the lay, and across that (the steepest slope is \
                 at {:.1}°), the frame ggx and beckmann read; \
                 [anisotropy].alpha_ggx/alpha_beckmann are along the principal slope axes",
                an.flag_source,
                an.ratio_text(),
                an.lay_direction_deg(),
                an.slope_direction_deg
            )
        }),
    })
}

/// `[kc_2d]`.
fn kc_2d(f: &crate::kc::KcFit) -> Kc2d {
    Kc2d {
        sigma_um: f.params.sigma * UM,
        lc_um: f.params.lc * UM,
        gamma: f.params.gamma,
        stderr: match (
            finite(f.stderr.sigma * UM),
            finite(f.stderr.lc * UM),
            finite(f.stderr.gamma),
        ) {
            (Some(s), Some(l), Some(g)) => Some([s, l, g]),
            _ => None,
        },
        fit_zeta_range_rad_per_um: [f.range.0 / UM, f.range.1 / UM],
        rms_log_residual: f.rms_log_residual,
        degenerate: f.degenerate,
    }
}

/// A value for the file, or `None` (the key left out) when it is not known: a NaN or an
/// infinity, which TOML can spell but scripts trip on, and a sentinel such as −1 would
/// read as a number.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A fit's frequency range, or `None` when it has none (a NaN pair: the fit had no points).
fn finite_range(r: (f64, f64)) -> Option<[f64; 2]> {
    (r.0.is_finite() && r.1.is_finite()).then_some([r.0, r.1])
}

/// Every material the file offers (`MaterialFile::offered`), built as a scene `include`
/// of it builds them. A file [`build`] makes passes by construction; an error is a bug
/// there, and `lustre fit` refuses to write the file.
pub fn check(doc: &MaterialFile) -> Result<Vec<(String, brdf::spec::MaterialSpec)>, FitError> {
    let bad = |what: &str, e: String| FitError::data("material file", format!("{what}: {e}"));
    let mut out = Vec::new();
    for offer in doc.offered() {
        let spec = (doc.resolve(&offer.desc(), &mut brdf::spec::NoFiles))
            .map_err(|e| bad(&offer.name, e.to_string()))?;
        spec.build().map_err(|e| bad(&offer.name, e.to_string()))?;
        out.push((offer.name, spec));
    }
    Ok(out)
}

/// Serialise with the header comment.
pub fn to_toml(doc: &MaterialFile) -> Result<String, FitError> {
    let body = toml::to_string(doc).map_err(|e| FitError::data("material file", e.to_string()))?;
    let mut out = String::from(
        "# written by lustre fit\n\
         # Units: lengths in µm, angles in degrees, PSD in rad/µm with ∫P d²ζ = σ² (physics.md §1–2).\n\
         # lc_um is the Matérn range Lc; the 1D-form length of the data README is 2π·lc_um.\n",
    );
    if !doc.reliability.unreliable.is_empty() {
        out.push_str(&format!(
            "# WARNING: unreliable parts: {} (see [reliability]).\n",
            doc.reliability.unreliable.join(", ")
        ));
    }
    out.push_str(&body);
    Ok(out)
}
