//! Direction dependence of a map's roughness: rms slope and PSD along x and along y, the
//! principal axes of the slope covariance, and the anisotropic microfacet roughness they
//! imply.
//!
//! The slope covariance `C = ⟨s sᵀ⟩` (forward differences on the common
//! `(nx−1)×(ny−1)` region) has principal rms slopes `s₁ ≥ s₂` along the unit vectors at
//! `slope_direction_deg` and 90° from it; grooves (the lay) run perpendicular to the
//! steepest direction. A Beckmann surface with roughness `(α₁, α₂)` has per-axis slope
//! variance `αᵢ²/2`, so `αᵢ = √2·sᵢ`; GGX has no finite slope variance, so its isotropic
//! NDF fit `α` is split in the same proportion: `αᵢ = α·sᵢ/√((s₁² + s₂²)/2)`.
//!
//! At the pixel scale the slope covariance is dominated by what a scanning instrument adds
//! there (line glitches, the first rows of a scan), so the axes and lengths of the
//! anisotropic wave-optical models come from the stretched K-correlation fitted to the 2-D
//! PSD in the band ([`crate::kc2d`], fitted on every map), and so does the flag where that
//! fit is sound: a map is anisotropic when its fitted Ly/Lx exceeds
//! [`ANISOTROPY_THRESHOLD`]. For a stretched surface of finite slope variance the principal
//! slope ratio is Ly/Lx itself, so the threshold means the same on both measures: a lobe
//! 1.5× wider across the lay than along it, well above the fit's own scatter on isotropic
//! maps (Ly/Lx within 7 % of the truth, physics.md §15). Where the fit fails, is flagged
//! (a map too small, a degenerate γ, a floor above the band) or does not describe the
//! periodogram (cell residual above [`FLAG_FIT_RESIDUAL_MAX`]), the slope ratio decides.

use crate::kc2d::{self, AnisoKcFit};
use crate::psd::{self, Psd1d, WelchOptions};
use crate::{FitError, Topography};

/// Largest rms ln cell residual of the 2-D PSD fit for its Ly/Lx to decide the flag: the
/// cells of a stretched K-correlation map scatter by 0.22–0.26 (sampling), those of a
/// terraced film by 1.1, those of pure grooves (a line in the ζ plane) by 6.
pub const FLAG_FIT_RESIDUAL_MAX: f64 = 1.0;

/// Ly/Lx of a sound 2-D PSD fit (else the principal-slope ratio) above which a surface is
/// treated as anisotropic.
pub const ANISOTROPY_THRESHOLD: f64 = 1.5;

/// Direction-resolved roughness of a map.
#[derive(Debug, Clone, PartialEq)]
pub struct Anisotropy {
    /// Rms slope along x (`∂h/∂x`).
    pub rms_slope_x: f64,
    /// Rms slope along y.
    pub rms_slope_y: f64,
    /// `max/min` of the two.
    pub ratio_xy: f64,
    /// Principal rms slopes, larger first.
    pub principal: (f64, f64),
    /// `principal.0 / principal.1`.
    pub ratio: f64,
    /// Direction of the steepest rms slope, degrees from +x towards +y, in (−90, 90].
    pub slope_direction_deg: f64,
    /// Welch PSD of the x-lines.
    pub psd_x: Psd1d,
    /// Welch PSD of the y-columns.
    pub psd_y: Psd1d,
    /// Rms slope along x and y integrated from the two PSDs, `√∫(2πf)²P df`.
    pub psd_slopes: (f64, f64),
    /// True when the sound 2-D PSD fit's Ly/Lx (else `ratio`) exceeds
    /// [`ANISOTROPY_THRESHOLD`].
    pub anisotropic: bool,
    /// What decided `anisotropic`, in words (the measure and its value).
    pub flag_source: String,
    /// The stretched K-correlation fitted to the 2-D PSD ([`crate::kc2d`]) of every map of
    /// at least 16 × 16 points; the error in words when the fit failed.
    pub kc: Option<Result<AnisoKcFit, String>>,
}

impl Anisotropy {
    /// The principal slope ratio for a message: "principal slope ratio 7.30", or, for a
    /// map that varies along one direction only (an infinite ratio), what that means.
    pub fn ratio_text(&self) -> String {
        if self.ratio.is_finite() {
            format!("principal slope ratio {:.2}", self.ratio)
        } else {
            "no slope at all along the lay".to_string()
        }
    }

    /// Direction of the lay (the grooves), degrees in (−90, 90].
    pub fn lay_direction_deg(&self) -> f64 {
        let d = self.slope_direction_deg + 90.0;
        if d > 90.0 { d - 180.0 } else { d }
    }

    /// Rms slopes along the axis at `angle_deg` (from +x towards +y) and across it, from
    /// the slope covariance: `s_a² = s₁² cos²Δ + s₂² sin²Δ` with Δ the angle from the
    /// steepest direction (the principal slopes at Δ = 0).
    pub fn slopes_along(&self, angle_deg: f64) -> (f64, f64) {
        let (s1, s2) = self.principal;
        let (sin, cos) = (angle_deg - self.slope_direction_deg)
            .to_radians()
            .sin_cos();
        let (c2, s2sq) = (cos * cos, sin * sin);
        (
            (s1 * s1 * c2 + s2 * s2 * s2sq).sqrt(),
            (s1 * s1 * s2sq + s2 * s2 * c2).sqrt(),
        )
    }

    /// Anisotropic GGX roughness along the axis at `angle_deg` and across it, from the
    /// isotropic fit `alpha` split like the slopes along those axes (their mean square is
    /// the principal slopes', so the split keeps the isotropic fit's mean square).
    pub fn ggx_along(&self, alpha: f64, angle_deg: f64) -> (f64, f64) {
        let (a, b) = self.slopes_along(angle_deg);
        let m = ((a * a + b * b) / 2.0).sqrt();
        if m > 0.0 {
            (alpha * a / m, alpha * b / m)
        } else {
            (alpha, alpha)
        }
    }

    /// Anisotropic Beckmann roughness along the principal axes `(α₁, α₂)`.
    pub fn beckmann(&self) -> (f64, f64) {
        (
            2f64.sqrt() * self.principal.0,
            2f64.sqrt() * self.principal.1,
        )
    }

    /// Anisotropic GGX roughness along the principal axes from the isotropic fit `alpha`,
    /// split like the slopes.
    pub fn ggx(&self, alpha: f64) -> (f64, f64) {
        self.ggx_along(alpha, self.slope_direction_deg)
    }
}

/// Transpose a map (columns become lines).
pub fn transpose(t: &Topography) -> Topography {
    let (nx, ny) = (t.nx, t.ny);
    let mut h = vec![0.0; nx * ny];
    for y in 0..ny {
        for x in 0..nx {
            h[x * ny + y] = t.heights[y * nx + x];
        }
    }
    Topography {
        nx: ny,
        ny: nx,
        dx: t.dy,
        dy: t.dx,
        heights: h,
        channel: t.channel.clone(),
        format: t.format,
    }
}

fn slope_rms(p: &Psd1d) -> f64 {
    let mut acc = 0.0;
    for i in 1..p.f.len() {
        let g = |k: usize| (2.0 * std::f64::consts::PI * p.f[k]).powi(2) * p.p[k];
        acc += 0.5 * (g(i) + g(i - 1)) * (p.f[i] - p.f[i - 1]);
    }
    acc.max(0.0).sqrt()
}

/// Analyse a levelled, NaN-free map (at least 2 × 2); `psd_x` is its Welch PSD of the
/// x-lines with full-length segments (computed once by the caller).
pub fn analyse(t: &Topography, psd_x: Psd1d) -> Result<Anisotropy, FitError> {
    if t.is_profile() || t.nx < 2 || t.ny < 2 {
        return Err(FitError::data(
            "anisotropy",
            "needs a map of at least 2 × 2 points",
        ));
    }
    let (nx, ny) = (t.nx, t.ny);
    let h = &t.heights;
    let (mut cxx, mut cyy, mut cxy, mut n) = (0.0, 0.0, 0.0, 0.0);
    for y in 0..ny - 1 {
        for x in 0..nx - 1 {
            let i = y * nx + x;
            let sx = (h[i + 1] - h[i]) / t.dx;
            let sy = (h[i + nx] - h[i]) / t.dy;
            if sx.is_finite() && sy.is_finite() {
                cxx += sx * sx;
                cyy += sy * sy;
                cxy += sx * sy;
                n += 1.0;
            }
        }
    }
    if n == 0.0 {
        return Err(FitError::data("anisotropy", "no valid slopes"));
    }
    let (cxx, cyy, cxy) = (cxx / n, cyy / n, cxy / n);
    let mean = 0.5 * (cxx + cyy);
    let r = (0.25 * (cxx - cyy).powi(2) + cxy * cxy).sqrt();
    let (l1, l2) = (mean + r, (mean - r).max(0.0));
    let theta = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
    let mut deg = theta.to_degrees();
    if deg <= -90.0 {
        deg += 180.0;
    }
    let (sx, sy) = (cxx.sqrt(), cyy.sqrt());
    let principal = (l1.sqrt(), l2.sqrt());
    let ratio = if principal.1 > 0.0 {
        principal.0 / principal.1
    } else {
        f64::INFINITY
    };
    let psd_y = psd::welch(&transpose(t), &WelchOptions::default())?;
    let psd_slopes = (slope_rms(&psd_x), slope_rms(&psd_y));
    let kc = (t.nx >= 16 && t.ny >= 16).then(|| kc2d::fit(t, theta).map_err(|e| e.to_string()));
    let (anisotropic, flag_source) = flag(ratio, kc.as_ref());
    Ok(Anisotropy {
        rms_slope_x: sx,
        rms_slope_y: sy,
        ratio_xy: if sx.min(sy) > 0.0 {
            sx.max(sy) / sx.min(sy)
        } else {
            f64::INFINITY
        },
        principal,
        ratio,
        slope_direction_deg: deg,
        psd_x,
        psd_y,
        psd_slopes,
        anisotropic,
        flag_source,
        kc,
    })
}

/// Whether the map is anisotropic, and what decided it: the 2-D PSD fit's Ly/Lx where that
/// fit is sound, else the principal slope ratio.
fn flag(slope_ratio: f64, kc: Option<&Result<AnisoKcFit, String>>) -> (bool, String) {
    match kc {
        Some(Ok(f)) if f.problem.is_none() && f.rms_log_residual <= FLAG_FIT_RESIDUAL_MAX => (
            f.params.ratio() > ANISOTROPY_THRESHOLD,
            format!(
                "Ly/Lx {:.2} of the 2-D PSD fit (threshold {ANISOTROPY_THRESHOLD})",
                f.params.ratio()
            ),
        ),
        other => {
            let why = match other {
                Some(Ok(f)) => f.problem.clone().unwrap_or_else(|| {
                    format!(
                        "its cells scatter by {:.2} in ln about the ellipse (> \
                         {FLAG_FIT_RESIDUAL_MAX}: the PSD is not a stretched K-correlation)",
                        f.rms_log_residual
                    )
                }),
                Some(Err(e)) => e.clone(),
                None => "the map is smaller than 16 × 16".into(),
            };
            let ratio = if slope_ratio.is_finite() {
                format!("{slope_ratio:.2}")
            } else {
                "∞".into()
            };
            (
                slope_ratio > ANISOTROPY_THRESHOLD,
                format!(
                    "principal slope ratio {ratio} (threshold {ANISOTROPY_THRESHOLD}; the 2-D \
                     PSD fit is not used: {why})"
                ),
            )
        }
    }
}
