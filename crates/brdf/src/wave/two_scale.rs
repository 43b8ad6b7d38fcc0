//! The Holzschuch–Pacanowski (2017) two-scale BRDF, as reconstructed in
//! `physics.md` §8.3:
//!
//! ```text
//! f(i,o) = F(θd) G₂(i,o)/(4 cosθi cosθo) · [ A_d D(h) + (1 − A_d) D̃_eff(h) ]
//! A_d    = exp(−(2kσ cosθd)²),   cosθd = i·h,
//! D_eff(h) = ∫_{H²} K_d(h·m) D(m) dω_m,
//! K_d(cosψ) = κ² P_KC(κ sinψ)/σ²  (ψ < 90°),   κ = 2k cosθd,
//! ```
//!
//! with D the exponential NDF ([`super::epd`]), G₂ its height-correlated
//! Smith term, and D̃_eff = D_eff / ∫D_eff cosθ_h dω_h renormalised for every
//! κ (the raw integral is 0.97–1.0, and → 0 as κLc → 0 where the KC lobe of
//! each facet becomes evanescent).
//!
//! **The two readings of §8.3** ([`CoherentPart`]): the coherent fraction A_d
//! is reflected by every microfacet, so it is seen through the macro NDF D
//! ([`CoherentPart::MacroNdf`], the formula above); or, as in the paper's
//! eq. 10, it is a mirror delta of weight F(θi)·A(θi) with the flat
//! macro-surface and only the diffracted part R G (1−A)(P⋆D) is glossy
//! ([`CoherentPart::Delta`]). In that reading the glossy factor is
//! 1 − A(min(cosθi, cosθo)) rather than 1 − A(θd): with A(θd) the delta and
//! the glossy part do not partition the energy (measured albedo 1.10 at
//! θi = 75°, β = 0.1, σ = 0.05 µm, λ = 400 nm), while this choice is
//! reciprocal and keeps A(θi) + glossy ≤ 1.
//!
//! **The table.** D̃_eff depends on h only through θ_h and on the material and
//! wavelength only through w = κ·Lc (K_d = w²ν/(π(1 + w² sin²ψ)^{ν+1}) is a
//! function of w and γ). At construction the convolution is computed by
//! nested Gauss–Legendre quadrature, on panels graded towards the scales of
//! both factors (β for D, 1/w for K_d), for `w` nodes uniform in ln(1 + w)
//! over [0, 2k_max·Lc] (k_max at [`crate::WAVELENGTH_MIN_NM`]) and θ_h nodes
//! uniform in v with tanθ_h = τ·a·sinh(v V) (linear near the pole, logarithmic
//! in the power-law tail) up to tanθ_h = 10³, beyond which D̃_eff is held.
//! Evaluation interpolates ln D̃_eff by Catmull–Rom in v and the values
//! linearly in ln(1 + w). Wavelengths below 360 nm use the last
//! node (w beyond the table, where D̃_eff ≈ D).
//!
//! **Energy.** Even with G₂ from the lobe's own Smith Λ, the albedo can
//! exceed 1 at grazing incidence (1.037 at 88° for β 0.05, Lc 0.5 µm,
//! γ 1.5), because the NDF changes with θd across the lobe. Such materials
//! get the reciprocal cap of [`super::albedo_cap`]: the glossy part is
//! divided by max(1, C(θi), C(θo)) with C = E/(1 − S) tabulated at
//! construction; [`TwoScale::is_energy_capped`] says whether it was needed.
//!
//! **Sampling** draws the half vector from a mixture: D cosθ_h (exact
//! inversion, [`super::epd::ExponentialNdf::sample`]) with probability w_D,
//! and otherwise the tabulated D̃_eff cosθ_h at the fixed κ_s = 2k cosθ_i:
//! a node of the two bracketing w nodes is chosen with the interpolation
//! weights, then a θ_h bin from its CDF, and tan²θ_h uniformly inside the
//! bin. The pdf of that procedure is computed exactly (piecewise constant in
//! tan²θ_h per node), so `pdf` is the density `sample` realises; the
//! eval/pdf mismatch (cosθd varies over the lobe, the bin density is flat)
//! only costs variance. `Delta` adds the discrete mirror lobe with
//! probability min(A(θi), 0.99).

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;

use crate::error::BrdfError;
use crate::frame::reflect_z;
use crate::fresnel::Fresnel;
use crate::math::finite_nonneg;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::wave::albedo_cap::{self, AlbedoCap};
use crate::wave::epd::ExponentialNdf;
use crate::wave::kc::KcPsd;
use crate::wave::quadrature::{GL4_W, GL4_X, gl4, gl4_graded_from_zero, panel_edges};

/// Where the coherent (specular) fraction A of each microfacet goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum CoherentPart {
    /// Each microfacet reflects its coherent part into its own mirror
    /// direction, so the macro-scale lobe of that part is D itself:
    /// f ∝ A_d D + (1 − A_d) D̃_eff. No delta lobe.
    #[default]
    MacroNdf,
    /// The paper's eq. 10: the coherent part is a mirror delta of the mean
    /// plane with weight F(θi)·exp(−(2kσ cosθi)²); the glossy lobe is
    /// F G₂ (1 − A(min(cosθi, cosθo))) D̃_eff/(4 cosθi cosθo).
    Delta,
}

/// Resolution of the per-material D̃_eff table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TableResolution {
    /// Nodes in w = 2k cosθd·Lc (uniform in ln(1 + w)).
    pub w_nodes: usize,
    /// Nodes in θ_h.
    pub theta_nodes: usize,
}

impl Default for TableResolution {
    fn default() -> Self {
        TableResolution {
            w_nodes: 40,
            theta_nodes: 92,
        }
    }
}

/// Parameters of [`TwoScale`].
#[derive(Clone, Debug, PartialEq)]
pub struct TwoScaleParams {
    /// Scale β of the exponential macro NDF.
    pub beta: f64,
    /// rms height of the micro-scale KC spectrum (σ_rel of HP17), µm.
    pub sigma_um: f64,
    /// KC correlation length Lc, µm.
    pub lc_um: f64,
    /// KC exponent γ > 1.
    pub gamma: f64,
    /// Fresnel term, applied at θd (and at θi for the delta).
    pub fresnel: Fresnel,
    /// Reading of §8.3.
    pub coherent: CoherentPart,
    /// Table resolution.
    pub resolution: TableResolution,
}

/// Holzschuch–Pacanowski two-scale model: exponential NDF at the macro scale,
/// KC diffraction at the micro scale.
#[derive(Clone, Debug)]
pub struct TwoScale {
    ndf: ExponentialNdf,
    psd: KcPsd,
    fresnel: Fresnel,
    coherent: CoherentPart,
    table: EffTable,
    /// ln(1 + Λ) of the macro NDF at tanθ = β a sinh(v V_m), v on
    /// [`MACRO_LAMBDA_NODES`] points: the closed form (physics.md §8.2)
    /// costs a Bessel quadrature, too slow for every evaluation.
    macro_log1p_lambda: Vec<f64>,
    /// 1/(β·a) and (nodes − 1)/V_m: the table's lookup scales.
    macro_inv_scale: f64,
    macro_v_scale: f64,
    /// Reciprocal energy cap where the albedo would exceed 1 (`None` when
    /// it never does, the common case).
    cap: Option<AlbedoCap>,
}

/// Points of the macro NDF's Λ table.
const MACRO_LAMBDA_NODES: usize = 128;

/// Ratio of successive panel widths away from a focus. With 4-point
/// Gauss–Legendre per panel in both nested integrals, 3 keeps the
/// convolution within 1e−4 of an adaptive cubature (measured ≤ 6.8e−5,
/// tested at 2e−4), 40× below the table's interpolation error; 8-point
/// rules (1e−6) tripled the build time for no visible gain.
const GRADING: f64 = 3.0;

/// The convolution D_eff(θh) = ∫ K_w(h·m) D(m) dω_m (not normalised), for
/// K_w(cosψ) = w²ν/(π(1 + w² sin²ψ)^{ν+1}) on ψ < 90°.
///
/// Outer integral over θ_m (D's polar angle, where D is smooth: its cusp in
/// slope space sits at the pole of these coordinates), inner over the
/// azimuth φ of m relative to h, on panels graded towards φ = 0 on the scale
/// of K_w along the ring.
struct Convolver {
    ndf: ExponentialNdf,
    nu: f64,
    outer: Vec<f64>,
}

impl Convolver {
    fn new(ndf: ExponentialNdf, nu: f64) -> Self {
        Convolver {
            ndf,
            nu,
            outer: Vec::new(),
        }
    }

    fn d_eff(&mut self, theta_h: f64, w: f64) -> f64 {
        let beta = self.ndf.beta();
        let (sh, ch) = libm::sincos(theta_h);
        // K's angular width (sinψ ~ 1/w), capped at one radian.
        let eps = (1.0 / w).min(1.0);
        // D is below e^{−45} of its peak beyond tanθm = 45β.
        let tm_max = libm::atan(45.0 * beta);
        let mut outer = core::mem::take(&mut self.outer);
        // At θm = 90° − θh the ring starts to reach ψ = 90° (the edge of
        // K's hemisphere): the ring integral has a square-root kink there.
        let kink = core::f64::consts::FRAC_PI_2 - theta_h;
        panel_edges(
            0.0,
            tm_max,
            &[
                (0.0, 0.25 * beta.min(eps)),
                (theta_h, 0.25 * eps),
                (kink, 1e-2),
            ],
            GRADING,
            &mut outer,
        );
        let kernel = Kernel::new(w, self.nu);
        let mut total = 0.0;
        for p in outer.windows(2) {
            total += gl4(p[0], p[1], |tm| {
                let (sm, cm) = crate::math::sincos(tm);
                let d = self.ndf.d_tan_cos(sm / cm, cm);
                if d == 0.0 {
                    return 0.0;
                }
                d * sm * ring(&kernel, eps, theta_h, sh, ch, tm, sm, cm)
            });
        }
        self.outer = outer;
        total
    }
}

/// K_w(cosψ) = w²ν/π (1 + w² sin²ψ)^{−(ν+1)} for one w.
struct Kernel {
    scale: f64,
    w2: f64,
    power: f64,
}

impl Kernel {
    fn new(w: f64, nu: f64) -> Self {
        Kernel {
            scale: w * w * nu / PI,
            w2: w * w,
            power: nu + 1.0,
        }
    }

    /// K as a function of sin²ψ.
    #[inline]
    fn at(&self, sin2_psi: f64) -> f64 {
        // exp(−(ν+1) ln(1 + x)) rather than pow: the exponent's absolute
        // error is ~1e−14 at most (the table is built to 1e−4), at two
        // thirds of pow's cost, which was a third of the build. Forming
        // 1 + x costs at most one rounding (relative 1e−16 in the result).
        self.scale * crate::math::exp(-self.power * crate::math::ln(1.0 + self.w2 * sin2_psi))
    }
}

/// 2∫₀^{φmax} K_w(ψ(φ)) dφ over the ring of m at polar angle θm, φ the
/// azimuth of m relative to h; 4-point Gauss–Legendre on panels graded
/// towards φ = 0 on the scale of K_w along the ring.
#[allow(clippy::too_many_arguments)]
#[inline]
fn ring(kernel: &Kernel, eps: f64, th: f64, sh: f64, ch: f64, tm: f64, sm: f64, cm: f64) -> f64 {
    let ss = sh * sm;
    // ψ < 90° ⇔ cosθh cosθm + sinθh sinθm cosφ > 0.
    let phi_max = if ss <= 0.0 {
        PI
    } else {
        let c = -ch * cm / ss;
        if c <= -1.0 {
            PI
        } else {
            libm::acos(c.min(1.0))
        }
    };
    // 1 − h·m = 2sin²((θm − θh)/2) + 2 sinθh sinθm sin²(φ/2): a sum of
    // non-negative terms, so sin²ψ = (1 − h·m)(1 + h·m) keeps its relative
    // accuracy where m ≈ h, and only sin²(φ/2) varies along the ring.
    let half_dt = libm::sin(0.5 * (tm - th));
    let a0 = 2.0 * half_dt * half_dt;
    let b = 2.0 * ss;
    let at = |phi: f64| {
        // sin(φ/2) by the exact quarter-turn polynomial, not a general-purpose
        // sincos: φ/2 ∈ [0, π/2].
        let (s, _) = crate::math::sincos_2pi(phi * (0.25 / PI));
        let one_minus_c = a0 + b * s * s;
        kernel.at(one_minus_c * (2.0 - one_minus_c))
    };
    let delta0 = (tm - th).abs();
    let scale = 0.5 * eps.max(delta0) / libm::sqrt(ss.max(1e-300));
    2.0 * gl4_graded_from_zero(phi_max, scale, GRADING, at)
}

/// Catmull–Rom cubic through `row` at position j + f (0 ≤ f ≤ 1).
///
/// ln D_eff is even in v at the pole (t ∝ sinh vV is odd), so the missing
/// left neighbour of node 0 is its mirror image row[1]; past the last node
/// the row is extended linearly.
#[inline]
fn catmull_rom(row: &[f64], j: usize, f: f64) -> f64 {
    let n = row.len();
    let y1 = row[j];
    let y2 = row[j + 1];
    let y0 = if j > 0 { row[j - 1] } else { row[1] };
    let y3 = if j + 2 < n { row[j + 2] } else { 2.0 * y2 - y1 };
    let c1 = 0.5 * (y2 - y0);
    let c2 = y0 - 2.5 * y1 + 2.0 * y2 - 0.5 * y3;
    let c3 = 1.5 * (y1 - y2) + 0.5 * (y3 - y0);
    y1 + f * (c1 + f * (c2 + f * c3))
}

/// Per-material table of the normalised D̃_eff and its sampling CDFs.
#[derive(Clone, Debug)]
struct EffTable {
    /// Spacing of the w nodes in x = ln(1 + w).
    dx: f64,
    nw: usize,
    nv: usize,
    /// Per w node: τ (tanθ scale) and V (v ↦ t extent) of the D̃ grid (the
    /// Λ grid has the same τ and reaches closer to the horizon).
    tau: Vec<f64>,
    v_extent: Vec<f64>,
    /// Per w node, for lookups without divisions: 1/(τ·a), (nv − 1)/V and
    /// (LAMBDA_NODES − 1)/V_Λ.
    inv_tau_a: Vec<f64>,
    v_scale: Vec<f64>,
    lambda_v_scale: Vec<f64>,
    /// ln D̃_eff at (node, v_j), row-major by node.
    log_d: Vec<f64>,
    /// Density in T = tan²θ per bin (piecewise constant), and CDF per node
    /// (nv entries, first 0, last 1).
    dens_t: Vec<f64>,
    cdf: Vec<f64>,
    /// Raw normalisation ∫ D_eff cosθ dω per node (diagnostics).
    norm: Vec<f64>,
    /// ln(1 + Λ) of the normalised D̃_eff at (node, l) for tanθ on the
    /// node's Λ sinh grid (top at [`LAMBDA_TOP_TAN`]) with [`LAMBDA_NODES`]
    /// points.
    log1p_lambda: Vec<f64>,
}

/// tan²θ at point j of a row's sinh grid (scale τ, extent V, nv points).
#[inline]
fn grid_tan2(tau: f64, v_ext: f64, j: usize, nv: usize) -> f64 {
    let tan_t = tau * SINH_A * libm::sinh(j as f64 / (nv - 1) as f64 * v_ext);
    tan_t * tan_t
}

/// One w node of [`EffTable`], as built.
struct EffRow {
    tau: f64,
    v_ext: f64,
    lambda_v_ext: f64,
    log_d: Vec<f64>,
    norm: f64,
    dens_t: Vec<f64>,
    cdf: Vec<f64>,
    log1p_lambda: Vec<f64>,
}

/// Points of the Smith Λ tables in v (θ = atan(τ a sinh(vV))).
const LAMBDA_NODES: usize = 64;

/// ∫₀^{2π} max(0, ω·m) dφ for ω, m at polar angles θ, θm (cosines `c`,
/// `cm`, sines `s`, `sm`), φ the azimuth between them.
#[inline]
fn ring_projection(c: f64, s: f64, cm: f64, sm: f64) -> f64 {
    let a = s * sm;
    let b = c * cm;
    if b >= a {
        2.0 * PI * b
    } else {
        // ω·m > 0 for |φ| < φ0 = acos(−b/a).
        let phi0 = libm::acos((-b / a).clamp(-1.0, 1.0));
        2.0 * (b * phi0 + libm::sqrt((a * a - b * b).max(0.0)))
    }
}

/// Quadrature nodes of ∫ D(m) g(θm) dω_m / 2π-ring for an isotropic,
/// normalised NDF given as ln D on a sinh grid in tanθm (`row`, scale
/// `tau_a` = τ·a, extent `v_ext`): 4-point Gauss–Legendre per bin with the
/// Catmull–Rom interpolant the table evaluates. Returns (weight = D sinθm
/// dθm, cosθm, sinθm) per node; computed once per row, reused for every θ.
fn ring_nodes(row: &[f64], tau_a: f64, v_ext: f64) -> Vec<(f64, f64, f64)> {
    let nv = row.len();
    let mut out = Vec::with_capacity(4 * (nv - 1));
    for j in 0..nv - 1 {
        for (x, w) in GL4_X.iter().zip(GL4_W.iter()) {
            for f in [0.5 - 0.5 * x, 0.5 + 0.5 * x] {
                let v = (j as f64 + f) / (nv - 1) as f64;
                let tm = tau_a * libm::sinh(v * v_ext);
                let cm = 1.0 / libm::sqrt(1.0 + tm * tm);
                let sm = tm * cm;
                // dθm/dv = τ a V cosh(vV) cos²θm; dv/df = 1/(nv − 1); GL on [0, 1].
                let dth = tau_a * v_ext * libm::cosh(v * v_ext) * cm * cm / (nv - 1) as f64;
                let d = libm::exp(catmull_rom(row, j, f));
                out.push((0.5 * w * d * sm * dth, cm, sm));
            }
        }
    }
    out
}

/// Λ from a row of ln(1 + Λ) on the uniform v grid of tanθ = scale·sinh(vV),
/// given `t` = tanθ/scale and `v_scale` = (n − 1)/V: Catmull–Rom in v, held
/// at the ends.
#[inline]
fn lambda_from_log1p_row(row: &[f64], t: f64, v_scale: f64) -> f64 {
    let n = row.len();
    let x = crate::math::asinh_nonneg(t) * v_scale;
    let ln1p = if !(x >= 0.0) {
        row[0]
    } else if x >= (n - 1) as f64 {
        row[n - 1]
    } else {
        let j = x as usize;
        catmull_rom(row, j, x - j as f64)
    };
    // e^x − 1 rather than expm1: G₂ = 1/(1 + Λi + Λo) needs Λ to an
    // absolute 1e−16, not a relative one, and exp is 3× cheaper.
    (crate::math::exp(ln1p) - 1.0).max(0.0)
}

/// Smith 1 + Λ(θ) = (1/cosθ) ∫ D(m) max(0, ω·m) dω_m from [`ring_nodes`].
fn one_plus_lambda(nodes: &[(f64, f64, f64)], tan_t: f64) -> f64 {
    let c = 1.0 / libm::sqrt(1.0 + tan_t * tan_t);
    let s = tan_t * c;
    let sum: f64 = nodes
        .iter()
        .map(|&(w, cm, sm)| w * ring_projection(c, s, cm, sm))
        .sum();
    sum / c
}

/// t = a sinh(vV) is linear near the pole; a fixes where logarithmic
/// spacing starts (in units of τ: past the exponential core of D).
const SINH_A: f64 = 1.0;
/// Largest tabulated tanθ_h of D̃_eff (θ_h = 90° − 1e−3 rad). Closer to
/// the horizon D̃_eff is constant to ~1e−4 relative (h·m changes by
/// ≤ 1e−3·sinθm there, and K is flat in h·m near ψ = 90°), so the last
/// value is held; a top at 1e6 spent a third of the nodes on that sliver.
const D_TOP_TAN: f64 = 1e3;
/// Largest tabulated tanθ of the Smith Λ tables (θ = 90° − 1e−6 rad): Λ
/// grows like tanθ towards the horizon, so it is not held early.
const LAMBDA_TOP_TAN: f64 = 1e6;

impl EffTable {
    fn build(ndf: ExponentialNdf, psd: &KcPsd, res: TableResolution) -> EffTable {
        let nw = res.w_nodes.max(2);
        let nv = res.theta_nodes.max(8);
        let k_max = 2000.0 * PI / WAVELENGTH_MIN_NM;
        let w_max = 2.0 * k_max * psd.lc_um();
        let dx = libm::log1p(w_max) / (nw - 1) as f64;
        let beta = ndf.beta();
        let nu = psd.nu();
        // Every row (convolutions, nearly all of the build time; sampling
        // CDF; Smith Λ) on all cores with `std`, each with its own
        // quadrature scratch space.
        let rows: Vec<EffRow> = crate::parallel::map_rows(nw, |i| {
            let mut conv = Convolver::new(ndf, nu);
            let w = libm::expm1(i as f64 * dx);
            let tau = if w > 0.0 {
                libm::hypot(beta, 1.0 / w).min(1.0)
            } else {
                1.0
            };
            let tau = tau.max(beta.min(1.0));
            let v_ext = libm::asinh(D_TOP_TAN / (tau * SINH_A));
            let lambda_v_ext = libm::asinh(LAMBDA_TOP_TAN / (tau * SINH_A));
            let mut log_d: Vec<f64> = (0..nv)
                .map(|j| {
                    let v = j as f64 / (nv - 1) as f64;
                    let theta = libm::atan(tau * SINH_A * libm::sinh(v * v_ext));
                    libm::log(conv.d_eff(theta, w).max(1e-300))
                })
                .collect();
            // Bin masses of D̃ cosθ dω in T = tan²θ from the interpolant.
            let masses: Vec<f64> = (0..nv - 1)
                .map(|j| {
                    gl4(0.0, 1.0, |f| {
                        let v = (j as f64 + f) / (nv - 1) as f64;
                        let sh = libm::sinh(v * v_ext);
                        let tan_t = tau * SINH_A * sh;
                        let c2 = 1.0 / (1.0 + tan_t * tan_t);
                        // dT/dv = 2 tanθ · τ a V cosh(vV); dv/df = 1/(nv−1).
                        let dt_dv = 2.0 * tan_t * tau * SINH_A * v_ext * libm::cosh(v * v_ext);
                        let d = libm::exp(catmull_rom(&log_d, j, f));
                        PI * d * c2 * c2 * dt_dv / (nv - 1) as f64
                    })
                })
                .collect();
            let total: f64 = masses.iter().sum();
            let log_total = libm::log(total);
            for v in &mut log_d {
                *v -= log_total;
            }
            let tan2 = |j: usize| grid_tan2(tau, v_ext, j, nv);
            let mut dens_t = Vec::with_capacity(nv);
            let mut cdf = Vec::with_capacity(nv);
            let mut acc = 0.0;
            cdf.push(0.0);
            for (j, m) in masses.iter().enumerate() {
                dens_t.push(m / total / (tan2(j + 1) - tan2(j)));
                acc += m / total;
                cdf.push(acc);
            }
            dens_t.push(0.0);
            cdf[nv - 1] = 1.0;
            // Smith Λ of the normalised row.
            let tau_a = tau * SINH_A;
            let nodes = ring_nodes(&log_d, tau_a, v_ext);
            let log1p_lambda = (0..LAMBDA_NODES)
                .map(|l| {
                    let v = l as f64 / (LAMBDA_NODES - 1) as f64;
                    let q = one_plus_lambda(&nodes, tau_a * libm::sinh(v * lambda_v_ext));
                    // Λ ≥ 0; quadrature round-off near the pole can dip below.
                    libm::log(q.max(1.0))
                })
                .collect();
            EffRow {
                tau,
                v_ext,
                lambda_v_ext,
                log_d,
                norm: total,
                dens_t,
                cdf,
                log1p_lambda,
            }
        });
        let mut t = EffTable {
            dx,
            nw,
            nv,
            tau: Vec::with_capacity(nw),
            v_extent: Vec::with_capacity(nw),
            inv_tau_a: Vec::with_capacity(nw),
            v_scale: Vec::with_capacity(nw),
            lambda_v_scale: Vec::with_capacity(nw),
            log_d: Vec::with_capacity(nw * nv),
            dens_t: Vec::with_capacity(nw * nv),
            cdf: Vec::with_capacity(nw * nv),
            norm: Vec::with_capacity(nw),
            log1p_lambda: Vec::with_capacity(nw * LAMBDA_NODES),
        };
        for r in rows {
            t.tau.push(r.tau);
            t.v_extent.push(r.v_ext);
            t.inv_tau_a.push(1.0 / (r.tau * SINH_A));
            t.v_scale.push((nv - 1) as f64 / r.v_ext);
            t.lambda_v_scale
                .push((LAMBDA_NODES - 1) as f64 / r.lambda_v_ext);
            t.log_d.extend(r.log_d);
            t.norm.push(r.norm);
            t.dens_t.extend(r.dens_t);
            t.cdf.extend(r.cdf);
            t.log1p_lambda.extend(r.log1p_lambda);
        }
        t
    }

    /// Smith Λ of the normalised D̃_eff at node i for tanθ.
    #[inline]
    fn lambda_node(&self, i: usize, tan_t: f64) -> f64 {
        let row = &self.log1p_lambda[i * LAMBDA_NODES..(i + 1) * LAMBDA_NODES];
        lambda_from_log1p_row(row, tan_t * self.inv_tau_a[i], self.lambda_v_scale[i])
    }

    /// Smith Λ of the w-interpolated D̃_eff at the bracket `wb`: the table mixes the two
    /// bracketing (normalised) rows linearly, and Λ of a mixture of NDFs
    /// is the same mixture of their Λs (∫D max(0, ω·m) dω is linear in D).
    #[inline]
    fn lambda(&self, wb: (usize, f64), tan_t: f64) -> f64 {
        self.mix_nodes(wb, |i| self.lambda_node(i, tan_t))
    }

    /// (1 − f)·value(i) + f·value(i + 1) for the nodes bracketing w: the
    /// table's linear mixture in w of every per-node quantity (a node with
    /// zero weight is not evaluated).
    #[inline]
    fn mix_nodes(&self, (i, f): (usize, f64), value: impl Fn(usize) -> f64) -> f64 {
        let a = if f < 1.0 { value(i) } else { 0.0 };
        let b = if f > 0.0 { value(i + 1) } else { 0.0 };
        (1.0 - f) * a + f * b
    }

    /// tan²θ at node (i, j).
    #[inline]
    fn tan2_at(&self, i: usize, j: usize) -> f64 {
        grid_tan2(self.tau[i], self.v_extent[i], j, self.nv)
    }

    /// (lower node, weight of the upper node) for w = κ·Lc.
    #[inline]
    fn w_bracket(&self, w: f64) -> (usize, f64) {
        let x = libm::log1p(w.max(0.0)) / self.dx;
        if !(x < (self.nw - 1) as f64) {
            return (self.nw - 2, 1.0);
        }
        let i = x as usize;
        (i, x - i as f64)
    }

    /// Fractional v position (bin, fraction) of tanθ at node i, or None past the top.
    #[inline]
    fn v_position(&self, i: usize, tan_t: f64) -> Option<(usize, f64)> {
        let x = crate::math::asinh_nonneg(tan_t * self.inv_tau_a[i]) * self.v_scale[i];
        if !(x >= 0.0) {
            return Some((0, 0.0));
        }
        if x >= (self.nv - 1) as f64 {
            return None;
        }
        let j = x as usize;
        Some((j, x - j as f64))
    }

    /// D̃_eff at node i (tanθ, clamped to the top node beyond it).
    #[inline]
    fn d_node(&self, i: usize, tan_t: f64) -> f64 {
        let row = &self.log_d[i * self.nv..(i + 1) * self.nv];
        match self.v_position(i, tan_t) {
            Some((j, f)) => crate::math::exp(catmull_rom(row, j, f)),
            None => crate::math::exp(row[self.nv - 1]),
        }
    }

    /// D̃_eff(h) at the w bracket `wb` ([`EffTable::w_bracket`]), tanθh given.
    #[inline]
    fn d_eff(&self, wb: (usize, f64), tan_t: f64) -> f64 {
        self.mix_nodes(wb, |i| self.d_node(i, tan_t))
    }

    /// Solid-angle density of [`EffTable::sample_node`] at node i.
    #[inline]
    fn pdf_node(&self, i: usize, tan_t: f64, cos_t: f64) -> f64 {
        match self.v_position(i, tan_t) {
            // p_ω = p_T · cos³θ/ … : dω = (cos³θ/2) dT dφ.
            Some((j, _)) => self.dens_t[i * self.nv + j] / (PI * cos_t * cos_t * cos_t),
            None => 0.0,
        }
    }

    /// Sampling density of h (solid angle) at the w bracket `wb`, for h
    /// given by tanθh and cosθh > 0.
    #[inline]
    fn pdf(&self, wb: (usize, f64), tan_t: f64, cos_t: f64) -> f64 {
        self.mix_nodes(wb, |i| self.pdf_node(i, tan_t, cos_t))
    }

    /// Draws h at node i from two uniforms.
    fn sample_node(&self, i: usize, u1: f64, u2: f64) -> DVec3 {
        let cdf = &self.cdf[i * self.nv..(i + 1) * self.nv];
        // Last j with cdf[j] ≤ u1, among the nv − 1 bins.
        let j = cdf.partition_point(|&c| c <= u1).clamp(1, self.nv - 1) - 1;
        let width = cdf[j + 1] - cdf[j];
        let f = if width > 0.0 {
            ((u1 - cdf[j]) / width).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let (t0, t1) = (self.tan2_at(i, j), self.tan2_at(i, j + 1));
        let tan2 = t0 + f * (t1 - t0);
        let cos_t = 1.0 / libm::sqrt(1.0 + tan2);
        let sin_t = libm::sqrt(tan2) * cos_t;
        let (sp, cp) = libm::sincos(2.0 * PI * u2);
        DVec3::new(sin_t * cp, sin_t * sp, cos_t)
    }

    /// Draws h for w, choosing a bracketing node with `u0`.
    fn sample(&self, w: f64, u0: f64, u1: f64, u2: f64) -> DVec3 {
        let (i, f) = self.w_bracket(w);
        let node = if u0 < f { i + 1 } else { i };
        self.sample_node(node, u1, u2)
    }
}

/// What an evaluation at (wi, wo) shares across wavelengths.
struct Pair {
    zi: f64,
    zo: f64,
    h_z: f64,
    /// wi·h (not clamped).
    cos_d: f64,
    tan_h: f64,
    tan_i: f64,
    tan_o: f64,
    /// Macro NDF D(h) and its Λ at wi and wo (MacroNdf reading; 0 otherwise).
    d_macro: f64,
    macro_lambda_i: f64,
    macro_lambda_o: f64,
}

/// Smallest probability given to each component of the half-vector mixture
/// in the MacroNdf reading.
const MIX_FLOOR: f64 = 0.05;
/// Largest probability of the delta lobe in the Delta reading.
const DELTA_MAX: f64 = 0.99;

impl TwoScale {
    /// The same surface under another Fresnel term. No table depends on the
    /// Fresnel factor (the D̃_eff table and the energy cap use R = 1), so
    /// they are shared instead of rebuilt: the result equals `new` with the
    /// same parameters and `fresnel`, exactly, at the cost of a clone.
    pub fn with_fresnel(&self, fresnel: Fresnel) -> Result<TwoScale, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        let mut m = self.clone();
        m.fresnel = fresnel;
        Ok(m)
    }

    /// Validates the parameters and builds the D̃_eff table.
    ///
    /// β ∈ [1e−4, 10]; σ ∈ [0, 10] µm, Lc ∈ [0.03, 1000] µm, γ ∈ [1.001, 100]
    /// (as [`KcPsd::new`]); Fresnel data must cover 360–830 nm.
    pub fn new(p: TwoScaleParams) -> Result<TwoScale, BrdfError> {
        let ndf = ExponentialNdf::new(p.beta)?;
        let psd = KcPsd::new(p.sigma_um, p.lc_um, p.gamma)?;
        p.fresnel
            .check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        if p.resolution.w_nodes < 2 || p.resolution.theta_nodes < 8 {
            return Err(BrdfError::OutOfRange {
                name: "resolution",
                value: p.resolution.w_nodes.min(p.resolution.theta_nodes) as f64,
                valid: "w_nodes ≥ 2 and theta_nodes ≥ 8",
            });
        }
        let table = EffTable::build(ndf, &psd, p.resolution);
        let beta = ndf.beta();
        let macro_v_extent = libm::asinh(LAMBDA_TOP_TAN / (beta * SINH_A));
        let macro_log1p_lambda = crate::parallel::map_rows(MACRO_LAMBDA_NODES, |l| {
            let v = l as f64 / (MACRO_LAMBDA_NODES - 1) as f64;
            let tan_t = beta * SINH_A * libm::sinh(v * macro_v_extent);
            let lam = if tan_t > 0.0 {
                crate::wave::bessel01::smith_lambda_exp(1.0 / (beta * tan_t))
            } else {
                0.0
            };
            libm::log1p(finite_nonneg(lam))
        });
        let mut m = TwoScale {
            ndf,
            psd,
            fresnel: p.fresnel,
            coherent: p.coherent,
            table,
            macro_log1p_lambda,
            macro_inv_scale: 1.0 / (beta * SINH_A),
            macro_v_scale: (MACRO_LAMBDA_NODES - 1) as f64 / macro_v_extent,
            cap: None,
        };
        m.cap = m.build_cap();
        Ok(m)
    }

    /// The energy cap of [`super::albedo_cap`] for this material and reading:
    /// C(μ, k) = E/(1 − S) from the uncapped glossy part with F = 1.
    fn build_cap(&self) -> Option<AlbedoCap> {
        let k_lo = super::wavenumber(WAVELENGTH_MAX_NM);
        let k_hi = super::wavenumber(WAVELENGTH_MIN_NM);
        // The lobe's angular scale: the macro NDF's, widened by the KC lobe
        // at small w.
        let width = self.ndf.beta().clamp(1e-3, 1.0);
        AlbedoCap::build(k_lo, k_hi, |mu, k| {
            let mu = mu.max(1e-3);
            let wi = DVec3::new(libm::sqrt(1.0 - mu * mu), 0.0, mu);
            let e = albedo_cap::albedo(mu, width, |wo| self.glossy_unit(wi, wo, k));
            let s = match self.coherent {
                CoherentPart::MacroNdf => 0.0,
                CoherentPart::Delta => self.coherent_fraction(k, mu).0,
            };
            e / (1.0 - s).max(1e-12)
        })
    }

    /// The macro NDF.
    pub fn ndf(&self) -> &ExponentialNdf {
        &self.ndf
    }

    /// The micro-scale spectrum.
    pub fn psd(&self) -> &KcPsd {
        &self.psd
    }

    /// The coherent-part reading.
    pub fn coherent(&self) -> CoherentPart {
        self.coherent
    }

    /// The same material under the other reading of §8.3, sharing no work
    /// with a rebuild: the D̃_eff table does not depend on the reading.
    pub fn with_coherent_part(&self, coherent: CoherentPart) -> TwoScale {
        let mut m = TwoScale {
            coherent,
            cap: None,
            ..self.clone()
        };
        m.cap = m.build_cap();
        m
    }

    /// Whether this material needed the energy cap (its uncapped albedo
    /// exceeds 1 somewhere).
    pub fn is_energy_capped(&self) -> bool {
        self.cap.is_some()
    }

    /// The largest factor the energy cap divides by (1 when uncapped): the
    /// uncapped albedo's excess E/(1 − S) at its worst angle and wavelength.
    pub fn energy_cap_peak(&self) -> f64 {
        self.cap.as_ref().map_or(1.0, |c| c.peak())
    }

    /// Raw ∫D_eff cosθ dω at the table's w nodes, as (w, value) pairs,
    /// before renormalisation.
    pub fn raw_normalisation(&self) -> Vec<(f64, f64)> {
        (0..self.table.nw)
            .map(|i| (libm::expm1(i as f64 * self.table.dx), self.table.norm[i]))
            .collect()
    }

    /// The renormalised D̃_eff(θh) at κ = 2k cosθd (rad/µm), from the table.
    pub fn d_eff(&self, kappa: f64, theta_h: f64) -> f64 {
        let (s, c) = libm::sincos(theta_h);
        if !(c > 0.0) {
            return 0.0;
        }
        let wb = self.table.w_bracket(kappa * self.psd.lc_um());
        self.table.d_eff(wb, s / c)
    }

    /// The un-normalised convolution ∫ K_d(h·m) D(m) dω_m at κ (rad/µm),
    /// computed directly by quadrature (slow; for tests and diagnostics).
    pub fn d_eff_direct(&self, kappa: f64, theta_h: f64) -> f64 {
        Convolver::new(self.ndf, self.psd.nu()).d_eff(theta_h, kappa * self.psd.lc_um())
    }

    /// Coherent fraction A = exp(−(2kσ cos)²).
    #[inline]
    fn coherent_fraction(&self, k: f64, cos: f64) -> (f64, f64) {
        let x = 2.0 * k * self.psd.sigma_um() * cos;
        let g = x * x;
        // One transcendental: A = 1 + expm1(−g) has no cancellation while
        // A ≥ 1/e, and 1 − A none while A < 1/e.
        if g < 1.0 {
            let e = libm::expm1(-g);
            (1.0 + e, -e)
        } else {
            let a = crate::math::exp(-g);
            (a, 1.0 - a)
        }
    }

    /// Probability of the delta lobe (Delta reading) and of the D component
    /// of the half-vector mixture.
    #[inline]
    fn choice(&self, k: f64, ci: f64) -> (f64, f64) {
        let (a, _) = self.coherent_fraction(k, ci);
        match self.coherent {
            CoherentPart::MacroNdf => (0.0, a.clamp(MIX_FLOOR, 1.0 - MIX_FLOOR)),
            CoherentPart::Delta => (a.min(DELTA_MAX), 0.0),
        }
    }

    /// Smith Λ of the macro NDF at tanθ (table, Catmull–Rom in v).
    #[inline]
    fn macro_lambda(&self, tan_t: f64) -> f64 {
        lambda_from_log1p_row(
            &self.macro_log1p_lambda,
            tan_t * self.macro_inv_scale,
            self.macro_v_scale,
        )
    }

    /// The wavelength-independent part of an evaluation at (wi, wo): shared
    /// by `eval` and `pdf`, and by every hero wavelength of a path. `None`
    /// below either horizon or without a half vector.
    #[inline]
    fn pair(&self, wi: DVec3, wo: DVec3) -> Option<Pair> {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        let (h, cos_d) = crate::frame::half_vector(wi, wo)?;
        let tan_i = libm::hypot(wi.x, wi.y) / wi.z;
        let tan_o = libm::hypot(wo.x, wo.y) / wo.z;
        let (d_macro, macro_lambda_i, macro_lambda_o) = match self.coherent {
            CoherentPart::MacroNdf => (
                self.ndf.d(h),
                self.macro_lambda(tan_i),
                self.macro_lambda(tan_o),
            ),
            CoherentPart::Delta => (0.0, 0.0, 0.0),
        };
        Some(Pair {
            zi: wi.z,
            zo: wo.z,
            h_z: h.z,
            cos_d,
            tan_h: libm::hypot(h.x, h.y) / h.z,
            tan_i,
            tan_o,
            d_macro,
            macro_lambda_i,
            macro_lambda_o,
        })
    }

    /// Smith Λ of the lobe's own microfacet distribution at a direction
    /// (tanθ, and the macro NDF's Λ there): MacroNdf reading, the mixture
    /// A·D + (1 − A)·D̃_eff, whose Λ is A·Λ_D + (1 − A)·Λ_eff; Delta
    /// reading, D̃_eff alone. With Λ of the macro NDF alone (HP17's reading
    /// of G₂) the wider D̃_eff lobe is under-shadowed and the albedo
    /// exceeded 1 by up to 7 % at oblique incidence; with the lobe's own Λ,
    /// single scattering conserves energy.
    #[inline]
    fn lobe_lambda(&self, tan_t: f64, macro_lambda: f64, wb: (usize, f64), a: f64) -> f64 {
        let eff = self.table.lambda(wb, tan_t);
        match self.coherent {
            CoherentPart::MacroNdf => a * macro_lambda + (1.0 - a) * eff,
            CoherentPart::Delta => eff,
        }
    }

    /// The glossy BRDF without Fresnel and without the cap, at wavenumber k.
    fn glossy(&self, p: &Pair, k: f64) -> f64 {
        let cos_d = p.cos_d.min(1.0);
        let w = 2.0 * k * cos_d * self.psd.lc_um();
        let wb = self.table.w_bracket(w);
        let d_eff = self.table.d_eff(wb, p.tan_h);
        let (a_d, one_minus_a_d) = self.coherent_fraction(k, cos_d);
        let lobe = match self.coherent {
            CoherentPart::MacroNdf => a_d * p.d_macro + one_minus_a_d * d_eff,
            CoherentPart::Delta => {
                // The delta takes A(θi); the glossy part takes what the
                // less-coherent of the two directions leaves, 1 − A(min(cosθi,
                // cosθo)) ≤ 1 − A(θi): reciprocal, and A(θi) + glossy ≤ 1.
                let (_, one_minus_a) = self.coherent_fraction(k, p.zi.min(p.zo));
                one_minus_a * d_eff
            }
        };
        let g2 = 1.0
            / (1.0
                + self.lobe_lambda(p.tan_i, p.macro_lambda_i, wb, a_d)
                + self.lobe_lambda(p.tan_o, p.macro_lambda_o, wb, a_d));
        g2 * lobe / (4.0 * p.zi * p.zo)
    }

    /// [`TwoScale::glossy`] at (wi, wo) as a plain value (0 where undefined).
    fn glossy_unit(&self, wi: DVec3, wo: DVec3, k: f64) -> f64 {
        self.pair(wi, wo)
            .map_or(0.0, |p| finite_nonneg(self.glossy(&p, k)))
    }

    /// The BRDF at one wavelength (k = 2π/λ).
    fn eval_pair(&self, p: &Pair, k: f64, lambda_nm: f64) -> f64 {
        let f = self.glossy(p, k);
        let cap = match &self.cap {
            Some(c) => c.max_at(p.zi, p.zo, k),
            None => 1.0,
        };
        finite_nonneg(self.fresnel.reflectance(p.cos_d.min(1.0), lambda_nm) * f / cap)
    }

    /// The solid-angle density of `sample` at one wavelength.
    fn pdf_pair(&self, p: &Pair, k: f64) -> f64 {
        if !(p.cos_d > 0.0) {
            return 0.0;
        }
        let (p_delta, w_d) = self.choice(k, p.zi);
        let wb = self.table.w_bracket(self.kappa_s(k, p.zi));
        let mut ph = (1.0 - w_d) * self.table.pdf(wb, p.tan_h, p.h_z);
        if w_d > 0.0 {
            // The macro NDF's own pdf, D(h) cosθh.
            ph += w_d * (p.d_macro * p.h_z);
        }
        finite_nonneg((1.0 - p_delta) * ph / (4.0 * p.cos_d))
    }

    fn kappa_s(&self, k: f64, ci: f64) -> f64 {
        2.0 * k * ci * self.psd.lc_um()
    }
}

#[inline]
/// k = 2π/λ in rad/µm, `None` for a wavelength that is not positive and finite.
fn wavenumber(lambda_nm: f64) -> Option<f64> {
    let k = super::wavenumber(lambda_nm);
    (k > 0.0).then_some(k)
}

impl Bxdf for TwoScale {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        match (wavenumber(lambda_nm), self.pair(wi, wo)) {
            (Some(k), Some(p)) => self.eval_pair(&p, k, lambda_nm),
            _ => 0.0,
        }
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        match (wavenumber(lambda_nm), self.pair(wi, wo)) {
            (Some(k), Some(p)) => self.pdf_pair(&p, k),
            _ => 0.0,
        }
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        match (wavenumber(lambda_nm), self.pair(wi, wo)) {
            (Some(k), Some(p)) => (self.eval_pair(&p, k, lambda_nm), self.pdf_pair(&p, k)),
            _ => (0.0, 0.0),
        }
    }

    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        let p = self.pair(wi, wo);
        for (o, &l) in out.iter_mut().zip(lambdas) {
            *o = match (wavenumber(l), &p) {
                (Some(k), Some(p)) => (self.eval_pair(p, k, l), self.pdf_pair(p, k)),
                _ => (0.0, 0.0),
            };
        }
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let k = wavenumber(lambda_nm)?;
        if !(wi.z > 0.0) {
            return None;
        }
        let (p_delta, w_d) = self.choice(k, wi.z);
        let mut u0 = u[0];
        if p_delta > 0.0 {
            if u0 < p_delta {
                let spec = self.specular(wi, lambda_nm);
                if !(spec.weight > 0.0) {
                    return None;
                }
                return Some(BxdfSample {
                    wo: reflect_z(wi),
                    weight: spec.weight / p_delta,
                    pdf: p_delta,
                    is_delta: true,
                });
            }
            u0 = ((u0 - p_delta) / (1.0 - p_delta)).clamp(0.0, 1.0);
        }
        let h = if u0 < w_d {
            self.ndf.sample([u[1], u[2]])
        } else {
            let u0 = if w_d > 0.0 {
                ((u0 - w_d) / (1.0 - w_d)).clamp(0.0, 1.0)
            } else {
                u0
            };
            self.table.sample(self.kappa_s(k, wi.z), u0, u[1], u[2])
        };
        let cos_d = wi.dot(h);
        if !(cos_d > 0.0) {
            return None;
        }
        let wo = (2.0 * cos_d * h - wi).normalize();
        if !(wo.z > 0.0 && wo.is_finite()) {
            return None;
        }
        let (f, pdf) = self.eval_pdf(wi, wo, lambda_nm);
        if !(pdf > 0.0 && f > 0.0) {
            return None;
        }
        Some(BxdfSample {
            wo,
            weight: finite_nonneg(f * wo.z / pdf),
            pdf,
            is_delta: false,
        })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        let Some(k) = wavenumber(lambda_nm) else {
            return Specular::default();
        };
        if self.coherent != CoherentPart::Delta || !(wi.z > 0.0) {
            return Specular::default();
        }
        let ci = wi.z.min(1.0);
        let (a, _) = self.coherent_fraction(k, ci);
        let (p_delta, _) = self.choice(k, ci);
        Specular {
            weight: finite_nonneg(self.fresnel.reflectance(ci, lambda_nm) * a),
            probability: p_delta,
        }
    }
}
