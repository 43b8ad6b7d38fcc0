//! The material file: a TOML document the renderer can `include`, holding every model's
//! parameters (lengths in µm, angles in degrees) and the provenance of the fit.
//!
//! Length conventions: `lc_um` is the Matérn range Lc of physics.md §2 (rad convention);
//! the reference-table length of the 1D form is `2π·lc_um` and is written as
//! `[fit].l_1d_um`. The `[psd]` table is the isotropic 2D PSD in rad/µm with
//! `∫ P d²ζ = σ²` (µm⁴).
//!
//! Every parameter written is one the renderer accepts: each is checked with the
//! renderer's own constructors (`brdf::statistics::KcPsd::new`, `brdf::Distribution::ggx`,
//! `TabulatedPsd::new`, the exponential NDF's β range) and brought into range if needed.
//! What is unreliable — a degenerate K-correlation fit, a clamped α, a PSD table the
//! renderer cannot use, a two-scale split without a measured β, form left in the
//! residual, anisotropy the isotropic models ignore — is listed in `[reliability]`, and
//! the model defaults to one whose inputs are reliable.

use crate::kc::KcParams;
use crate::pipeline::Analysis;
use crate::two_scale::BetaSource;
use crate::{FitError, sha256};
use serde::Serialize;

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

/// The TOML document.
#[derive(Debug, Serialize)]
pub struct MaterialFile {
    /// Where the numbers come from.
    pub provenance: ProvenanceTable,
    /// The renderer's material keys.
    pub material: MaterialTable,
    /// Fit diagnostics: uncertainties, residuals, statistics.
    pub fit: FitTable,
    /// Which parts are unreliable, and why.
    pub reliability: ReliabilityTable,
    /// What levelling removed.
    pub form: FormTable,
    /// Direction dependence (maps only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropy: Option<AnisotropyTable>,
    /// K-correlation fit of the radial 2D PSD (maps only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_2d: Option<KcTable>,
    /// One table per cutoff, `cutoff_50` etc., in the order given.
    pub two_scale: Ordered<TwoScaleTable>,
    /// Tabulated PSD for the measured-PSD model.
    pub psd: PsdTable,
}

/// Named tables serialised as a map in insertion order.
#[derive(Debug)]
pub struct Ordered<T>(pub Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// `[provenance]`.
#[derive(Debug, Serialize)]
pub struct ProvenanceTable {
    /// Scan file.
    pub file: String,
    /// SHA-256 of the scan file.
    pub sha256: String,
    /// Frequency range of the material KC fit [cycles/m] (absent when the fit had no range,
    /// e.g. too few PSD points: never written as `nan`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_f_range_per_m: Option<[f64; 2]>,
    /// Tool and version.
    pub tool: String,
    /// Reader used.
    pub format: String,
    /// Channel read.
    pub channel: String,
    /// Grid size `[nx, ny]`.
    pub grid: [usize; 2],
    /// Pixel spacing `[dx, dy]` [µm].
    pub pixel_um: [f64; 2],
    /// Preparation steps.
    pub levelling: String,
    /// Invalid points filled by harmonic interpolation.
    pub filled_points: usize,
    /// What the reader and the analysis had to assume, change or skip.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Stylus profile merged below the cutoff.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stylus_file: Option<String>,
    /// SHA-256 of the stylus file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stylus_sha256: Option<String>,
    /// AFM/stylus merge cutoff [rad/µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_cutoff_rad_per_um: Option<f64>,
}

/// `[material]`.
#[derive(Debug, Serialize)]
pub struct MaterialTable {
    /// Metal name.
    pub metal: String,
    /// Default model.
    pub model: String,
    /// KC σ [µm].
    pub sigma_um: f64,
    /// KC Matérn range Lc [µm].
    pub lc_um: f64,
    /// KC γ.
    pub gamma: f64,
    /// GGX α.
    pub alpha: f64,
    /// Beckmann α.
    pub alpha_beckmann: f64,
    /// Anisotropic GGX α along the principal axes (anisotropic surfaces only; the
    /// directions are in `[anisotropy]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_x: Option<f64>,
    /// See `alpha_x`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_y: Option<f64>,
}

/// `[reliability]`: one entry per part, `"ok"` or the reason it should not be trusted.
#[derive(Debug, Serialize)]
pub struct ReliabilityTable {
    /// The K-correlation parameters of `[material]`.
    pub kc: String,
    /// The NDF roughness `alpha`/`alpha_beckmann` (and `alpha_x`/`alpha_y`).
    pub alpha: String,
    /// The `[psd]` table for `model = "measured_psd"`.
    pub psd: String,
    /// What `model = "measured_psd"` assumes outside the band the `[psd]` table covers
    /// (the renderer continues it there; see `brdf::statistics::TabulatedPsd`).
    pub psd_extrapolation: String,
    /// The two-scale tables.
    pub two_scale: String,
    /// Form left in the residual after levelling.
    pub form: String,
    /// Anisotropy that the isotropic models ignore.
    pub anisotropy: String,
    /// Whether the K-correlation σ accounts for the measured height variance (Sq²).
    pub variance: String,
    /// Why `[material].model` is what it is.
    pub model: String,
    /// A scan mostly invalid, cropped or filled on request (`--invalid`).
    pub invalid: String,
    /// Heights far outside the distribution (spikes, corrupted values), flagged or masked.
    pub outliers: String,
    /// An Sq or RMS slope implausible for a metal surface: a unit is probably wrong.
    pub units: String,
    /// The parts flagged above, for scripts.
    pub unreliable: Vec<String>,
}

/// `[form]`.
#[derive(Debug, Serialize)]
pub struct FormTable {
    /// `none`, `line`, `plane`, `poly2` or `poly3`.
    pub level: String,
    /// Rms of what was removed [µm].
    pub removed_rms_um: f64,
    /// Fitted terms `[i, j, c]`: `c·Xⁱ·Yʲ` with X, Y in µm from the map centre and c in
    /// µm^(1−i−j).
    pub terms: Vec<[f64; 3]>,
    /// Fraction of the residual variance the next polynomial degree would remove.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_form_fraction: Option<f64>,
    /// Set when the residual still shows form.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// `[anisotropy]`.
#[derive(Debug, Serialize)]
pub struct AnisotropyTable {
    /// Rms slope along x.
    pub rms_slope_x: f64,
    /// Rms slope along y.
    pub rms_slope_y: f64,
    /// Larger over smaller of the two.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio_xy: Option<f64>,
    /// Principal rms slopes `[steepest, across it]`.
    pub principal_rms_slopes: [f64; 2],
    /// Principal ratio (> 1.5: anisotropic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    /// Direction of the steepest slope (`alpha_x`), degrees from +x towards +y.
    pub slope_direction_deg: f64,
    /// Direction of the lay (grooves, `alpha_y`), degrees from +x towards +y.
    pub lay_direction_deg: f64,
    /// Rms slopes along x and y from the x- and y-PSDs.
    pub psd_rms_slopes: [f64; 2],
    /// True when `ratio > 1.5`.
    pub anisotropic: bool,
    /// GGX α along the principal axes.
    pub alpha_ggx: [f64; 2],
    /// Beckmann α along the principal axes.
    pub alpha_beckmann: [f64; 2],
    /// Set for anisotropic surfaces.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// `[fit.kc_asymptote]`.
#[derive(Debug, Serialize)]
pub struct AsymptoteTable {
    /// `P1 ∝ f^(−exponent)` over the top half of the fitted band.
    pub exponent: f64,
    /// Prefactor A of `P1 = A·f^(−exponent)`, SI (P1 in m³, f in cycles/m).
    pub prefactor_si: f64,
    /// Frequencies used [cycles/m].
    pub f_range_per_m: [f64; 2],
}

/// `[fit]`.
#[derive(Debug, Serialize)]
pub struct FitTable {
    /// Standard error of σ [µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma_um_err: Option<f64>,
    /// Standard error of Lc [µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lc_um_err: Option<f64>,
    /// Standard error of γ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_err: Option<f64>,
    /// README 1D-form length `L = 2π·Lc` [µm].
    pub l_1d_um: f64,
    /// Rms natural-log residual of the KC fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_rms_log_residual: Option<f64>,
    /// PSD points in the KC fit.
    pub kc_points: usize,
    /// True if the KC fit is not meaningful.
    pub kc_degenerate: bool,
    /// Why, when degenerate; `[material]` then holds the bounded best estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_reason: Option<String>,
    /// High-frequency power law of the fitted band.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_asymptote: Option<AsymptoteTable>,
    /// Sq (Rq for profiles) [µm].
    pub sq_um: f64,
    /// Rms slope (Sdq; Rdq for profiles).
    pub rms_slope: f64,
    /// Rms log residual of the GGX NDF fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_ggx_rms_log_residual: Option<f64>,
    /// Rms log residual of the Beckmann NDF fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_beckmann_rms_log_residual: Option<f64>,
    /// Beckmann α from the slope second moment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_beckmann_moment: Option<f64>,
}

/// `[kc_2d]`.
#[derive(Debug, Serialize)]
pub struct KcTable {
    /// σ [µm].
    pub sigma_um: f64,
    /// Lc [µm].
    pub lc_um: f64,
    /// γ.
    pub gamma: f64,
    /// Standard errors `[σ µm, Lc µm, γ]` (absent unless all three are known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stderr: Option<[f64; 3]>,
    /// Fitted ζ range [rad/µm].
    pub fit_zeta_range_rad_per_um: [f64; 2],
    /// Rms log residual.
    pub rms_log_residual: f64,
    /// Degenerate flag.
    pub degenerate: bool,
}

/// `[two_scale.cutoff_N]`.
#[derive(Debug, Serialize)]
pub struct TwoScaleTable {
    /// Exponential-NDF β of the large scale.
    pub beta: f64,
    /// `map`, `psd` or `unresolved`.
    pub beta_source: String,
    /// Residual KC σ [µm].
    pub sigma_um: f64,
    /// Residual KC Lc [µm].
    pub lc_um: f64,
    /// Residual KC γ.
    pub gamma: f64,
    /// Cutoff period [µm].
    pub cutoff_um: f64,
    /// Residual KC fit range [cycles/m] (absent when the fit had none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_f_range_per_m: Option<[f64; 2]>,
    /// Degenerate flag of the residual fit.
    pub kc_degenerate: bool,
    /// What is unreliable in this split (absent when it is sound).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub problem: Option<String>,
}

/// `[psd]`.
#[derive(Debug, Serialize)]
pub struct PsdTable {
    /// How the table was made.
    pub source: String,
    /// ∫ P d²ζ over the tabulated range (trapezoid, µm²); compare with `sq_um²`.
    pub integral_um2: f64,
    /// True when the renderer accepts the table (`model = "measured_psd"`).
    pub usable: bool,
    /// Bins dropped so the renderer accepts it (non-positive bins, the noise floor).
    pub dropped_bins: usize,
    /// Radial frequency ζ [rad/µm].
    pub zeta_rad_per_um: Vec<f64>,
    /// Isotropic 2D PSD [µm⁴].
    pub p_um4: Vec<f64>,
}

/// A value for the file, or `None` (the key left out) when it is not known: a NaN or an
/// infinity, which TOML can spell but scripts trip on, and a sentinel such as −1 would
/// read as a number.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// A fit's frequency range, or `None` when it has none (a NaN pair: the fit had no points).
/// TOML can spell `nan`, but a range of `nan` tells a reader nothing and trips scripts.
fn finite_range(r: (f64, f64)) -> Option<[f64; 2]> {
    (r.0.is_finite() && r.1.is_finite()).then_some([r.0, r.1])
}

/// Largest Lc the two-scale model accepts [µm] (its micro scale is a `KcPsd`).
const TWO_SCALE_LC_MAX_UM: f64 = brdf::statistics::kc::LC_MAX_UM;

/// K-correlation parameters in µm the renderer accepts; `Some(problem)` if they had to
/// be brought into range.
pub fn renderer_kc(k: &KcParams) -> ((f64, f64, f64), Option<String>) {
    let (s, l, g) = (k.sigma * UM, k.lc * UM, k.gamma);
    if brdf::statistics::KcPsd::new(s, l, g).is_ok() {
        return ((s, l, g), None);
    }
    let fix = |v: f64, lo: f64, hi: f64| if v.is_finite() { v.clamp(lo, hi) } else { lo };
    let out = (
        fix(s, 0.0, brdf::statistics::kc::SIGMA_MAX_UM),
        fix(
            l,
            brdf::statistics::kc::LC_MIN_UM,
            brdf::statistics::kc::LC_MAX_UM,
        ),
        fix(
            g,
            brdf::statistics::kc::GAMMA_MIN,
            brdf::statistics::kc::GAMMA_MAX,
        ),
    );
    (
        out,
        Some(format!(
            "σ {s:.4e} µm, Lc {l:.4e} µm, γ {g:.4} brought into the renderer's range"
        )),
    )
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

/// A microfacet α the renderer accepts (1e-4 … 1); `Some(problem)` if clamped.
pub fn renderer_alpha(a: f64) -> (f64, Option<String>) {
    if brdf::Distribution::ggx(a, a).is_ok() {
        return (a, None);
    }
    let c = if a.is_finite() {
        a.clamp(brdf::microfacet::ALPHA_MIN, brdf::microfacet::ALPHA_MAX)
    } else {
        brdf::microfacet::ALPHA_MIN
    };
    (
        c,
        Some(format!(
            "α {a:.4e} clamped to {c} (the renderer accepts 1e-4 … 1)"
        )),
    )
}

/// The `[psd]` table as the renderer needs it: finite positive samples at strictly
/// increasing ζ, ending in a segment steeper than ζ^−2.02. A noise floor at the high
/// end is trimmed; returns the table, how many bins were dropped, and the problem if the
/// renderer still rejects it.
pub fn renderer_psd(zeta: &[f64], p: &[f64]) -> (Vec<f64>, Vec<f64>, usize, Option<String>) {
    let mut z = Vec::with_capacity(zeta.len());
    let mut q = Vec::with_capacity(p.len());
    for (&a, &b) in zeta.iter().zip(p) {
        if a.is_finite() && a > 0.0 && b.is_finite() && b > 0.0 && z.last().is_none_or(|l| a > *l) {
            z.push(a);
            q.push(b);
        }
    }
    let slope = |z: &[f64], q: &[f64]| {
        let n = z.len();
        (q[n - 1].ln() - q[n - 2].ln()) / (z[n - 1].ln() - z[n - 2].ln())
    };
    // The tail must be normalisable (steeper than ζ^−2.02: a noise floor is not) and no
    // steeper than the steepest KC tail (an instrument's roll-off is not surface).
    while z.len() > 2 && {
        let s = slope(&z, &q);
        s.partial_cmp(&-2.02) != Some(std::cmp::Ordering::Less)
            || brdf::statistics::measured_psd::tail_too_steep(s)
    } {
        z.pop();
        q.pop();
    }
    let dropped = zeta.len() - z.len();
    let problem = match brdf::statistics::TabulatedPsd::new(&z, &q) {
        Ok(_) => None,
        Err(e) => Some(format!("the renderer rejects the PSD table: {e}")),
    };
    (z, q, dropped, problem)
}

/// `[reliability].psd_extrapolation`: the band the `[psd]` table measures and the tails
/// `model = "measured_psd"` assumes beyond it (`brdf::statistics::TabulatedPsd`: a
/// K-correlation roll-off below the band, matched to the first segment in value and slope,
/// and the last segment's power law above it). The full GHS of a table held flat below the
/// band disagreed with the direct transform of its own covariance by up to 26 %.
pub fn psd_extrapolation(zeta: &[f64], p: &[f64]) -> String {
    let Ok(t) = brdf::statistics::TabulatedPsd::new(zeta, p) else {
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

/// Build the document.
pub fn build(a: &Analysis, prov: &Provenance<'_>) -> MaterialFile {
    let ((sigma_um, lc_um, gamma), kc_range) = renderer_kc(&a.kc.params);
    let kc_state = match (a.kc.reason, &kc_range) {
        (Some(r), _) => format!(
            "degenerate: {}; [material] holds the bounded best estimate",
            r.describe()
        ),
        (None, Some(p)) => p.clone(),
        (None, None) => "ok".into(),
    };
    let (alpha, alpha_problem) = renderer_alpha(a.ndf.alpha_ggx.0);
    let (alpha_beckmann, beckmann_problem) = renderer_alpha(a.ndf.alpha_beckmann.0);
    let zeta: Vec<f64> = a.table.0.zeta.iter().map(|z| z / UM).collect();
    let p: Vec<f64> = a.table.0.p.iter().map(|p| p * UM.powi(4)).collect();
    let (zeta, p, dropped, psd_problem) = renderer_psd(&zeta, &p);
    let mut integral = 0.0;
    for i in 1..zeta.len() {
        let f = |j: usize| 2.0 * std::f64::consts::PI * zeta[j] * p[j];
        integral += 0.5 * (f(i) + f(i - 1)) * (zeta[i] - zeta[i - 1]);
    }
    let mut split_problems = Vec::new();
    let two_scale = Ordered(
        a.two_scale
            .iter()
            .map(|t| {
                let name = format!("cutoff_{}", t.multiple.round() as i64);
                let ((s, l, g), range) = renderer_kc(&t.kc.params);
                let mut problems = Vec::new();
                if let Some(r) = t.kc.reason {
                    problems.push(format!(
                        "residual K-correlation fit degenerate: {}",
                        r.describe()
                    ));
                }
                if let Some(r) = range {
                    problems.push(r);
                }
                let l = if l > TWO_SCALE_LC_MAX_UM {
                    problems.push(format!(
                        "Lc {l:.4e} µm clamped to the two-scale limit {TWO_SCALE_LC_MAX_UM:e} µm"
                    ));
                    TWO_SCALE_LC_MAX_UM
                } else {
                    l
                };
                let beta = if brdf::statistics::epd::ExponentialNdf::new(t.beta).is_ok() {
                    t.beta
                } else {
                    let c = if t.beta.is_finite() {
                        t.beta.clamp(
                            brdf::statistics::epd::BETA_MIN,
                            brdf::statistics::epd::BETA_MAX,
                        )
                    } else {
                        brdf::statistics::epd::BETA_MIN
                    };
                    problems.push(format!(
                        "β {:.4e} {} set to {c}",
                        t.beta,
                        if t.beta_source == BetaSource::Unresolved {
                            "(not measured: the scan does not reach the cutoff period)"
                        } else {
                            "(outside 1e-4 … 10)"
                        }
                    ));
                    c
                };
                let problem = (!problems.is_empty()).then(|| problems.join("; "));
                if problem.is_some() {
                    split_problems.push(name.clone());
                }
                (
                    name,
                    TwoScaleTable {
                        beta,
                        beta_source: match t.beta_source {
                            BetaSource::Map => "map",
                            BetaSource::Psd => "psd",
                            BetaSource::Unresolved => "unresolved",
                        }
                        .into(),
                        sigma_um: s,
                        lc_um: l,
                        gamma: g,
                        cutoff_um: t.cutoff * UM,
                        fit_f_range_per_m: finite_range(t.kc.range),
                        kc_degenerate: t.kc.degenerate,
                        problem,
                    },
                )
            })
            .collect(),
    );
    let form_warning = a.form.warning();
    let aniso = a.anisotropy.as_ref().map(|an| {
        let (gx, gy) = an.ggx(alpha);
        let (gx, gy) = (renderer_alpha(gx).0, renderer_alpha(gy).0);
        let (bx, by) = an.beckmann();
        let (bx, by) = (renderer_alpha(bx).0, renderer_alpha(by).0);
        AnisotropyTable {
            rms_slope_x: an.rms_slope_x,
            rms_slope_y: an.rms_slope_y,
            ratio_xy: finite(an.ratio_xy),
            principal_rms_slopes: [an.principal.0, an.principal.1],
            ratio: finite(an.ratio),
            slope_direction_deg: an.slope_direction_deg,
            lay_direction_deg: an.lay_direction_deg(),
            psd_rms_slopes: [an.psd_slopes.0, an.psd_slopes.1],
            anisotropic: an.anisotropic,
            alpha_ggx: [gx, gy],
            alpha_beckmann: [bx, by],
            warning: an.anisotropic.then(|| {
                format!(
                    "anisotropic ({}, lay at {:.1}°): the isotropic \
                     K-correlation and NDF fits average over directions and are only an \
                     approximation; [material].alpha_x/alpha_y (GGX) and \
                     [anisotropy].alpha_beckmann describe the two axes, with alpha_x across \
                     the lay (at {:.1}°)",
                    an.ratio_text(),
                    an.lay_direction_deg(),
                    an.slope_direction_deg
                )
            }),
        }
    });
    let anisotropic = aniso.as_ref().is_some_and(|t| t.anisotropic);
    let kc_ok = a.kc.reason.is_none() && kc_range.is_none();
    // A degenerate or clamped fit is flagged as such already; the silent case is a sound
    // fit whose σ is not the measured one.
    let variance_warning = kc_ok
        .then(|| {
            variance_mismatch(
                a.kc.params.sigma,
                a.stats.sq,
                a.kc.range,
                psd_problem.is_none(),
            )
        })
        .flatten();
    let (model, model_reason) = match prov.model {
        "auto" if kc_ok => (
            "ghs".to_string(),
            "auto: the K-correlation fit is sound".to_string(),
        ),
        "auto" if psd_problem.is_none() => (
            "measured_psd".to_string(),
            "auto: the K-correlation fit is degenerate, the measured PSD is used".to_string(),
        ),
        "auto" => (
            "ggx".to_string(),
            "auto: neither the K-correlation fit nor the PSD table is usable".to_string(),
        ),
        m => (m.to_string(), "chosen with --model".to_string()),
    };
    let mut unreliable = Vec::new();
    if !kc_ok {
        unreliable.push("kc".to_string());
    }
    let alpha_state = match (&alpha_problem, &beckmann_problem) {
        (None, None) => "ok".to_string(),
        (a, b) => {
            unreliable.push("alpha".into());
            [a.clone(), b.clone()]
                .into_iter()
                .flatten()
                .collect::<Vec<_>>()
                .join("; ")
        }
    };
    if psd_problem.is_some() {
        unreliable.push("psd".into());
    }
    if !split_problems.is_empty() {
        unreliable.push("two_scale".into());
    }
    if form_warning.is_some() {
        unreliable.push("form".into());
    }
    if anisotropic {
        unreliable.push("anisotropy".into());
    }
    if variance_warning.is_some() {
        unreliable.push("variance".into());
    }
    let q = &a.quality;
    for (name, flag) in [
        ("invalid", &q.invalid),
        ("outliers", &q.outliers),
        ("units", &q.units),
    ] {
        if flag.is_some() {
            unreliable.push(name.into());
        }
    }
    let uses_kc = matches!(model.as_str(), "ghs" | "ghs_ssa");
    let model_reason = if uses_kc && !kc_ok {
        format!("{model_reason}; WARNING: it uses the unreliable K-correlation parameters")
    } else if uses_kc && variance_warning.is_some() {
        format!(
            "{model_reason}; WARNING: its σ does not match the measured Sq \
             (see [reliability].variance)"
        )
    } else if model == "measured_psd" && psd_problem.is_some() {
        format!("{model_reason}; WARNING: the renderer rejects the PSD table")
    } else {
        model_reason
    };
    let mut notes: Vec<String> = prov.notes.to_vec();
    notes.extend(a.notes.iter().cloned());
    let level_name = a.form.level.name();
    MaterialFile {
        provenance: ProvenanceTable {
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
        },
        material: MaterialTable {
            metal: prov.metal.to_string(),
            model,
            sigma_um,
            lc_um,
            gamma,
            alpha,
            alpha_beckmann,
            alpha_x: aniso
                .as_ref()
                .filter(|t| t.anisotropic)
                .map(|t| t.alpha_ggx[0]),
            alpha_y: aniso
                .as_ref()
                .filter(|t| t.anisotropic)
                .map(|t| t.alpha_ggx[1]),
        },
        fit: FitTable {
            sigma_um_err: finite(a.kc.stderr.sigma * UM),
            lc_um_err: finite(a.kc.stderr.lc * UM),
            gamma_err: finite(a.kc.stderr.gamma),
            l_1d_um: lc_um * 2.0 * std::f64::consts::PI,
            kc_rms_log_residual: finite(a.kc.rms_log_residual),
            kc_points: a.kc.points,
            kc_degenerate: a.kc.degenerate,
            kc_reason: a.kc.reason.map(|r| r.describe().to_string()),
            kc_asymptote: a.kc.asymptote.map(|p| AsymptoteTable {
                exponent: p.exponent,
                prefactor_si: p.prefactor,
                f_range_per_m: [p.range.0, p.range.1],
            }),
            sq_um: a.stats.sq * UM,
            rms_slope: a.stats.rms_slope(),
            alpha_ggx_rms_log_residual: finite(a.ndf.alpha_ggx.1),
            alpha_beckmann_rms_log_residual: finite(a.ndf.alpha_beckmann.1),
            alpha_beckmann_moment: finite(a.ndf.alpha_beckmann_moment),
        },
        reliability: ReliabilityTable {
            kc: kc_state,
            alpha: alpha_state,
            psd: psd_problem.clone().unwrap_or_else(|| "ok".into()),
            psd_extrapolation: psd_extrapolation(&zeta, &p),
            two_scale: if split_problems.is_empty() {
                "ok".into()
            } else {
                format!("see problem in {}", split_problems.join(", "))
            },
            form: form_warning.clone().unwrap_or_else(|| "ok".into()),
            anisotropy: aniso
                .as_ref()
                .and_then(|t| t.warning.clone())
                .unwrap_or_else(|| "ok".into()),
            variance: variance_warning.unwrap_or_else(|| "ok".into()),
            model: model_reason,
            invalid: q.invalid.clone().unwrap_or_else(|| "ok".into()),
            outliers: q.outliers.clone().unwrap_or_else(|| "ok".into()),
            units: q.units.clone().unwrap_or_else(|| "ok".into()),
            unreliable,
        },
        form: FormTable {
            level: level_name.into(),
            removed_rms_um: a.form.removed_rms * UM,
            terms: a
                .form
                .terms
                .iter()
                .map(|t| {
                    [
                        t.i as f64,
                        t.j as f64,
                        t.c * UM.powi(1 - t.i as i32 - t.j as i32),
                    ]
                })
                .collect(),
            residual_form_fraction: a.form.residual_form.map(|r| r.1),
            warning: form_warning,
        },
        anisotropy: aniso,
        kc_2d: a.kc_2d.map(|f| KcTable {
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
        }),
        two_scale,
        psd: PsdTable {
            source: a.table.1.to_string(),
            integral_um2: integral,
            usable: psd_problem.is_none(),
            dropped_bins: dropped,
            zeta_rad_per_um: zeta,
            p_um4: p,
        },
    }
}

/// Every material the file offers, as the renderer builds it: `[material]`
/// with its own model, and under each model it can name (GGX, Beckmann,
/// GHS-SSA, GHS where γ ≥ 1.05, the measured PSD when its table is usable,
/// two-scale at each split), read back from the
/// written TOML as a `brdf::spec::MaterialDesc` and resolved and built by
/// `brdf::spec`, exactly as a scene `include` of the file would be. A file
/// `lustre fit` writes passes this by construction; an error here is a bug in
/// `build`, and `lustre fit` refuses to write the file.
pub fn renderer_materials(
    doc: &MaterialFile,
) -> Result<Vec<(String, brdf::spec::MaterialSpec)>, FitError> {
    use brdf::spec::{FileLoader, MaterialDesc, ModelKind};
    struct Psd<'a>(&'a PsdTable);
    impl FileLoader for Psd<'_> {
        fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
            Err(format!("a fit file names no n,k table ({path})"))
        }
        fn psd_table(&mut self, _: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
            Ok((self.0.zeta_rad_per_um.clone(), self.0.p_um4.clone()))
        }
    }
    let bad = |what: &str, e: String| FitError::data("material file", format!("{what}: {e}"));
    let text = to_toml(doc)?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| bad("TOML", e.to_string()))?;
    let base: MaterialDesc = table
        .remove("material")
        .ok_or_else(|| bad("[material]", "missing".into()))?
        .try_into()
        .map_err(|e: toml::de::Error| bad("[material]", e.message().to_string()))?;
    let mut out = Vec::new();
    let mut build =
        |name: String, desc: MaterialDesc, over: &MaterialDesc| -> Result<(), FitError> {
            let spec = desc
                .resolve(Some(over), &mut Psd(&doc.psd))
                .map_err(|e| bad(&name, e.to_string()))?;
            spec.build().map_err(|e| bad(&name, e.to_string()))?;
            out.push((name, spec));
            Ok(())
        };
    let with = |m: ModelKind| MaterialDesc {
        model: Some(m),
        ..MaterialDesc::default()
    };
    // The file's own model is what a bare `include` of it renders.
    if let Some(m) = base.model {
        // An include hands the file's [psd] to `measured_psd` (see render's material.rs).
        let own = MaterialDesc {
            psd_csv: (m == ModelKind::MeasuredPsd).then(|| "[psd]".to_string()),
            ..base.clone()
        };
        build(
            format!("[material] ({})", m.name()),
            MaterialDesc::default(),
            &own,
        )?;
    }
    // The full GHS is offered only where its series is representable (γ ≥ 1.05);
    // below that a scene asking for it gets the library's message pointing to ghs_ssa.
    let full_ok = base
        .gamma
        .is_some_and(|g| g >= brdf::statistics::kc::GAMMA_MIN_FULL);
    for m in [
        ModelKind::Ggx,
        ModelKind::Beckmann,
        ModelKind::GhsSsa,
        ModelKind::Ghs,
    ] {
        if m != ModelKind::Ghs || full_ok {
            build(m.name().to_string(), with(m), &base)?;
        }
    }
    if doc.psd.usable {
        let mut b = base.clone();
        b.psd_csv = Some("[psd]".into());
        build("measured_psd".into(), with(ModelKind::MeasuredPsd), &b)?;
    }
    for (name, t) in &doc.two_scale.0 {
        let b = MaterialDesc {
            beta: Some(t.beta),
            sigma_um: Some(t.sigma_um),
            lc_um: Some(t.lc_um),
            gamma: Some(t.gamma),
            ..base.clone()
        };
        build(format!("two_scale {name}"), with(ModelKind::TwoScale), &b)?;
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
