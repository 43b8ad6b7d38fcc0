//! The per-material table of the two-scale model ([`super::two_scale`]).
//! D̃_eff depends on h only through θ_h and on the material and
//! wavelength only through w = κ·Lc (K_d = w²ν/(π(1 + w² sin²ψ)^{ν+1}) is a
//! function of w and γ). At construction the convolution is computed by
//! nested Gauss–Legendre quadrature, on panels graded towards the scales of
//! both factors (β for D, 1/w for K_d), for `w` nodes uniform in ln(1 + w)
//! over [0, 2k_max·Lc] (k_max at [`crate::WAVELENGTH_MIN_NM`]; where β·w is
//! small the outer integral is a 5-point Gauss rule in θm²,
//! [`super::two_scale_narrow`], near the horizon over whole rings less the
//! part beyond ψ = 90°) and θ_h nodes
//! uniform in v with tanθ_h = τ·a·sinh(v V) (linear near the pole, logarithmic
//! in the power-law tail) up to tanθ_h = 10³, beyond which D̃_eff is held.
//! Evaluation interpolates ln D̃_eff by Catmull–Rom in v and the values
//! linearly in ln(1 + w). Wavelengths below 360 nm use the last
//! node (w beyond the table, where D̃_eff ≈ D).

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;

use crate::model::WAVELENGTH_MIN_NM;
use crate::numerics::quadrature::{gl4, gl4_graded_from_zero, panel_edges};
use crate::statistics::epd::ExponentialNdf;
use crate::statistics::kc::KcPsd;
use crate::wave::two_scale_lambda::RingSums;
use crate::wave::two_scale_lanes::{self, LANES, Lanes};
use crate::wave::two_scale_narrow::NarrowRule;

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
pub(crate) struct Convolver {
    ndf: ExponentialNdf,
    nu: f64,
    outer: Vec<f64>,
    /// The Gauss rule of a narrow D, where it applies ([`Convolver::d_eff_fast`]).
    narrow: Option<NarrowRule>,
}

impl Convolver {
    /// The nested rule alone (the reference of the tests).
    pub(crate) fn new(ndf: ExponentialNdf, nu: f64) -> Self {
        Convolver {
            ndf,
            nu,
            outer: Vec::new(),
            narrow: None,
        }
    }

    /// With the narrow-D Gauss rule where it applies.
    fn with_narrow(ndf: ExponentialNdf, nu: f64, narrow: Option<NarrowRule>) -> Self {
        Convolver {
            narrow,
            ..Convolver::new(ndf, nu)
        }
    }

    /// [`Convolver::d_eff`], by the narrow-D Gauss rule where it holds
    /// (N ring integrals instead of the nested rule's ~30).
    pub(crate) fn d_eff_fast(&mut self, theta_h: f64, w: f64) -> f64 {
        let beta = self.ndf.beta();
        let Some(rule) = self.narrow.as_ref().filter(|r| r.holds(beta, w)) else {
            return self.d_eff(theta_h, w);
        };
        let (sh, ch) = libm::sincos(theta_h);
        let eps = (1.0 / w).min(1.0);
        let kernel = Kernel::new(w, self.nu);
        if !rule.reaches_horizon(theta_h) {
            return rule
                .nodes()
                .iter()
                .map(|&(tm, sm, cm, wt)| wt * ring(&kernel, eps, theta_h, sh, ch, tm, sm, cm))
                .sum();
        }
        // Rings of D's support reach ψ = 90°, where R(θm) has a kink. The
        // kernel over whole rings (ψ past 90° too: K depends on sin²ψ, smooth
        // there) is analytic in θm, so the rule integrates it; the part
        // beyond ψ = 90° is taken off by a rule that follows the kink.
        let whole: f64 = rule
            .nodes()
            .iter()
            .map(|&(tm, sm, _, wt)| wt * ring_over(&kernel, eps, theta_h, tm, sh * sm, PI))
            .sum();
        whole - beyond_horizon(&self.ndf, &kernel, theta_h, sh, ch)
    }

    pub(crate) fn d_eff(&mut self, theta_h: f64, w: f64) -> f64 {
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
                let (sm, cm) = crate::numerics::math::sincos(tm);
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
    power: Power,
}

/// How a kernel takes q^{−(ν+1)}.
#[derive(Clone, Copy)]
enum Power {
    /// ν + 1 = n/4 (γ a multiple of ½, as S138's 2, S280's 3 and S091's
    /// 1.5): integer powers and square roots of 1/q, within a few ulp; a
    /// third of the instructions of exp and ln, which were half of the
    /// convolution's.
    Quarters(u32),
    /// exp(−(ν+1) ln q) rather than pow: the exponent's absolute error is
    /// ~1e−14 at most (the table is built to 1e−4), at two thirds of pow's
    /// cost. Forming q = 1 + x costs at most one rounding (relative 1e−16
    /// in the result).
    General(f64),
}

/// Largest n of [`Power::Quarters`] (γ = 15.5).
const QUARTERS_MAX: u32 = 33;

impl Power {
    fn new(p: f64) -> Power {
        let n = libm::round(4.0 * p);
        if (4.0 * p - n).abs() <= 1e-12 * n && n >= 1.0 && n <= QUARTERS_MAX as f64 {
            Power::Quarters(n as u32)
        } else {
            Power::General(p)
        }
    }

    /// q^{−(ν+1)} for q ≥ 1.
    #[inline]
    fn of(self, q: f64) -> f64 {
        match self {
            Power::Quarters(n) => {
                let r = 1.0 / q;
                let mut out = 1.0;
                for _ in 0..n / 4 {
                    out *= r;
                }
                match n % 4 {
                    0 => out,
                    2 => out * libm::sqrt(r),
                    rem => {
                        let s = libm::sqrt(r);
                        let quarter = libm::sqrt(s);
                        out * if rem == 1 { quarter } else { s * quarter }
                    }
                }
            }
            Power::General(p) => crate::numerics::math::exp(-p * crate::numerics::math::ln(q)),
        }
    }
}

impl Kernel {
    pub(crate) fn new(w: f64, nu: f64) -> Self {
        Kernel {
            scale: w * w * nu / PI,
            w2: w * w,
            power: Power::new(nu + 1.0),
        }
    }

    /// K as a function of sin²ψ.
    #[inline]
    fn at(&self, sin2_psi: f64) -> f64 {
        self.scale * self.power.of(1.0 + self.w2 * sin2_psi)
    }
}

/// 2∫₀^{φmax} K_w(ψ(φ)) dφ over the ring of m at polar angle θm, φ the
/// azimuth of m relative to h, up to ψ = 90°: [`ring_over`] to φmax.
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
    ring_over(kernel, eps, th, tm, ss, phi_max)
}

/// K_w along the ring of m at polar angle θm as a function of φ (the
/// azimuth of m relative to h).
struct RingKernel<'a> {
    kernel: &'a Kernel,
    a0: f64,
    b: f64,
}

impl<'a> RingKernel<'a> {
    /// For ss = sinθh sinθm.
    #[inline]
    fn new(kernel: &'a Kernel, th: f64, tm: f64, ss: f64) -> Self {
        // 1 − h·m = 2sin²((θm − θh)/2) + 2 sinθh sinθm sin²(φ/2): a sum of
        // non-negative terms, so sin²ψ = (1 − h·m)(1 + h·m) keeps its relative
        // accuracy where m ≈ h, and only sin²(φ/2) varies along the ring.
        let half_dt = libm::sin(0.5 * (tm - th));
        RingKernel {
            kernel,
            a0: 2.0 * half_dt * half_dt,
            b: 2.0 * ss,
        }
    }

    #[inline(always)]
    fn at(&self, phi: f64) -> f64 {
        // sin(φ/2) by the exact quarter-turn polynomial, not a general-purpose
        // sincos: φ/2 ∈ [0, π/2].
        let (s, _) = crate::numerics::math::sincos_2pi(phi * (0.25 / PI));
        let one_minus_c = self.a0 + self.b * s * s;
        self.kernel.at(one_minus_c * (2.0 - one_minus_c))
    }
}

/// 2∫₀^{φmax} K_w dφ along the ring of m at polar angle θm (ss = sinθh
/// sinθm); 4-point Gauss–Legendre on panels graded towards φ = 0 on the
/// scale of K_w along the ring.
#[inline]
fn ring_over(kernel: &Kernel, eps: f64, th: f64, tm: f64, ss: f64, phi_max: f64) -> f64 {
    let ring = RingKernel::new(kernel, th, tm, ss);
    let delta0 = (tm - th).abs();
    let scale = 0.5 * eps.max(delta0) / libm::sqrt(ss.max(1e-300));
    2.0 * gl4_graded_from_zero(phi_max, scale, GRADING, |phi| ring.at(phi))
}

/// First panel edge of [`beyond_horizon`] in x = √(θm − θk), in units of
/// √min(β, θk) (D falls by e over Δx² = β, and the arc's length varies on
/// Δx² ~ θk), and the ratio of successive edges. Against a rule on panels
/// graded from the kink in θm by 1.2 from 1e−6β, with 8 panels of 4
/// points along each arc (β 1e−4, 7.2e−4, 0.02; θk 0.2β–1e−2): within
/// 3.7e−6 in 20–40 nodes (edges 0.5, ratio 1.2: 2e−6 in 52–92 nodes;
/// 1, 2: 8e−5).
const BEYOND_FIRST: f64 = 1.0;
const BEYOND_GRADING: f64 = 1.5;

/// 2-point Gauss–Legendre node on [−1, 1] (weights 1).
const GL2_X: f64 = 0.577_350_269_189_625_8;

/// ∫ D(m) K_w(h·m) dω_m over the m of D's support with ψ > 90° (the part
/// of whole rings the convolution does not take): the rings with θm past
/// the kink θk = 90° − θh, each over φ ∈ [φmax, π]. The arc's length grows
/// like √(θm − θk), so the outer integral is taken in x = √(θm − θk),
/// where it is smooth, on panels graded from 0 on D's scale; along the arc
/// ψ ∈ [90°, θh + θm], K is near its minimum and smooth: 2-point
/// Gauss–Legendre.
fn beyond_horizon(ndf: &ExponentialNdf, kernel: &Kernel, th: f64, sh: f64, ch: f64) -> f64 {
    let beta = ndf.beta();
    let kink = core::f64::consts::FRAC_PI_2 - th;
    // D is below e^{−45} of its peak beyond tanθm = 45β.
    let tm_max = libm::atan(45.0 * beta);
    if !(kink < tm_max) {
        return 0.0;
    }
    let x_max = libm::sqrt(tm_max - kink);
    let first = BEYOND_FIRST * libm::sqrt(beta.min(kink));
    gl4_graded_from_zero(x_max, first, BEYOND_GRADING, |x| {
        let tm = kink + x * x;
        let (sm, cm) = crate::numerics::math::sincos(tm);
        let d = ndf.d_tan_cos(sm / cm, cm);
        let ss = sh * sm;
        if d == 0.0 || !(ss > 0.0) {
            return 0.0;
        }
        let phi_max = libm::acos((-ch * cm / ss).clamp(-1.0, 1.0));
        let ring = RingKernel::new(kernel, th, tm, ss);
        let (c, r) = (0.5 * (phi_max + PI), 0.5 * (PI - phi_max));
        let arc = 2.0 * r * (ring.at(c - r * GL2_X) + ring.at(c + r * GL2_X));
        // dθm = 2x dx.
        d * sm * arc * 2.0 * x
    })
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
pub(crate) struct EffTable {
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

/// Quadrature nodes of ∫ D(m) g(θm) dω_m / 2π-ring for an isotropic,
/// normalised NDF given as ln D on a sinh grid in tanθm (`row`, scale
/// `tau_a` = τ·a, extent `v_ext`), by `rule` on each bin with the
/// Catmull–Rom interpolant the table evaluates. Returns (weight = D sinθm
/// dθm, cosθm, sinθm) per node; computed once per row, reused for every θ.
fn ring_nodes(row: &[f64], tau_a: f64, v_ext: f64, rule: &BinRule) -> Vec<(f64, f64, f64)> {
    let nv = row.len();
    let parts = rule.parts.max(1);
    let mut out = Vec::with_capacity(2 * rule.x.len() * parts * (nv - 1));
    for j in 0..nv - 1 {
        for p in 0..parts {
            let (lo, width) = (p as f64 / parts as f64, 1.0 / parts as f64);
            for (x, w) in rule.x.iter().zip(rule.w) {
                for f in [lo + width * (0.5 - 0.5 * x), lo + width * (0.5 + 0.5 * x)] {
                    let v = (j as f64 + f) / (nv - 1) as f64;
                    let (sh, ch) = crate::numerics::math::sinh_cosh(v * v_ext);
                    let tm = tau_a * sh;
                    let cm = 1.0 / libm::sqrt(1.0 + tm * tm);
                    let sm = tm * cm;
                    // dθm/dv = τ a V cosh(vV) cos²θm; dv/df = 1/(nv − 1); GL on [0, 1].
                    let dth = tau_a * v_ext * ch * cm * cm / (nv - 1) as f64;
                    let d = libm::exp(catmull_rom(row, j, f));
                    out.push((0.5 * width * w * d * sm * dth, cm, sm));
                }
            }
        }
    }
    out
}

/// A Gauss–Legendre rule (positive nodes on [−1, 1] and their weights)
/// applied on `parts` equal parts of every bin of [`ring_nodes`].
struct BinRule {
    x: &'static [f64],
    w: &'static [f64],
    parts: usize,
}

/// The Λ rows' rule: 2-point Gauss–Legendre per bin. The Λ integrand is a
/// bin's cubic (in v) times exp and the sinh map, times the ring
/// projection, whose kink (at tanθ tanθm = 1) bounds every rule's order;
/// against 4 points on each quarter bin Λ is within 1.4e−5 of 1 + Λ
/// (4 points per bin: 2.2e−6), at half the ring projections of 4 points,
/// and eval moves by ≤ 2.2e−5 (five materials, both readings).
const LAMBDA_RULE: BinRule = BinRule {
    x: &[0.577_350_269_189_625_8],
    w: &[1.0],
    parts: 1,
};

/// Λ from a row of ln(1 + Λ) on the uniform v grid of tanθ = scale·sinh(vV),
/// given `t` = tanθ/scale and `v_scale` = (n − 1)/V: Catmull–Rom in v, held
/// at the ends.
#[inline]
pub(crate) fn lambda_from_log1p_row(row: &[f64], t: f64, v_scale: f64) -> f64 {
    lambda_from_log1p(log1p_from_row(row, t, v_scale))
}

/// The interpolated ln(1 + Λ) of [`lambda_from_log1p_row`], before e^x − 1.
#[inline]
fn log1p_from_row(row: &[f64], t: f64, v_scale: f64) -> f64 {
    let n = row.len();
    let x = crate::numerics::math::asinh_nonneg(t) * v_scale;
    if !(x >= 0.0) {
        row[0]
    } else if x >= (n - 1) as f64 {
        row[n - 1]
    } else {
        let j = x as usize;
        catmull_rom(row, j, x - j as f64)
    }
}

/// Λ from an interpolated ln(1 + Λ).
#[inline]
fn lambda_from_log1p(ln1p: f64) -> f64 {
    // e^x − 1 rather than expm1: G₂ = 1/(1 + Λi + Λo) needs Λ to an
    // absolute 1e−16, not a relative one, and exp is 3× cheaper.
    (crate::numerics::math::exp(ln1p) - 1.0).max(0.0)
}

/// Smith Λ rows resampled onto one sinh grid in tanθ shared by all rows,
/// for integrands that need Λ at one direction for several rows (the
/// energy cap: the macro NDF's and two w nodes' per wavenumber, at every
/// outgoing direction of its quadrature). One grid position and one set of
/// Catmull–Rom weights per direction serve every row, where each row's own
/// grid costs an asinh and a cubic per row. The shared grid is at least
/// twice as fine as every source row's (in asinh units) and starts at the
/// smallest of their scales: resampling moves 1 + Λ by ≤ 1e−4 relative
/// (measured 4.7e−5, where a source row's own cubic bends most), and the
/// cap C of S138 by ≤ 4e−7, against the cap's 1e−3 margin.
#[derive(Clone, Debug)]
pub(crate) struct SharedLambdaGrid {
    inv_scale: f64,
    v_scale: f64,
    n: usize,
    /// ln(1 + Λ) per row on n + 2 points: the grid's n values with the
    /// mirror image of the second in front (ln(1 + Λ) is even in v at the
    /// pole) and the linear extension of the last two behind, so that the
    /// cubic needs no end cases.
    rows: Vec<f64>,
}

/// A direction's place on a [`SharedLambdaGrid`]: the first of four padded
/// points and their Catmull–Rom weights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GridPosition {
    j: usize,
    w: [f64; 4],
}

impl SharedLambdaGrid {
    /// Resamples `sources` (each a row of ln(1 + Λ) on its own sinh grid
    /// tanθ = s·sinh(vV), given with 1/s and (points − 1)/V as its lookup
    /// takes them, all topped at [`LAMBDA_TOP_TAN`]) onto one grid.
    pub(crate) fn new<'a>(sources: impl Iterator<Item = (&'a [f64], f64, f64)>) -> Self {
        let sources: Vec<_> = sources.collect();
        let mut scale = f64::INFINITY;
        let mut step = f64::INFINITY;
        for &(_, inv_s, v_scale) in &sources {
            scale = scale.min(1.0 / inv_s);
            step = step.min(1.0 / v_scale);
        }
        let v_ext = libm::asinh(LAMBDA_TOP_TAN / scale);
        let n = (libm::ceil(v_ext / (0.5 * step)) as usize + 1).max(8);
        // The grid's tanθ, shared by every row.
        let tans: Vec<f64> = (0..n)
            .map(|l| scale * libm::sinh(l as f64 / (n - 1) as f64 * v_ext))
            .collect();
        // Each row resampled on its own (in parallel with `std`).
        let padded = crate::parallel::map_rows(sources.len(), |r| {
            let (row, inv_s, row_v_scale) = sources[r];
            let mut out = Vec::with_capacity(n + 2);
            out.push(0.0);
            out.extend(
                tans.iter()
                    .map(|&t| log1p_from_row(row, t * inv_s, row_v_scale)),
            );
            out[0] = out[2];
            let (a, b) = (out[n - 1], out[n]);
            out.push(2.0 * b - a);
            out
        });
        let rows = padded.concat();
        SharedLambdaGrid {
            inv_scale: 1.0 / scale,
            v_scale: (n - 1) as f64 / v_ext,
            n,
            rows,
        }
    }

    /// The place of tanθ on the grid (held at the ends, as the source rows are).
    #[inline]
    pub(crate) fn position(&self, tan_t: f64) -> GridPosition {
        let x = crate::numerics::math::asinh_nonneg(tan_t * self.inv_scale) * self.v_scale;
        let (j, f) = if !(x >= 0.0) {
            (0, 0.0)
        } else if x >= (self.n - 1) as f64 {
            (self.n - 2, 1.0)
        } else {
            let j = x as usize;
            (j, x - j as f64)
        };
        let (f2, f3) = (f * f, f * f * f);
        GridPosition {
            j,
            w: [
                -0.5 * f + f2 - 0.5 * f3,
                1.0 - 2.5 * f2 + 1.5 * f3,
                0.5 * f + 2.0 * f2 - 1.5 * f3,
                -0.5 * f2 + 0.5 * f3,
            ],
        }
    }

    /// Λ of row `r` at a position.
    #[inline]
    pub(crate) fn lambda(&self, r: usize, p: &GridPosition) -> f64 {
        lambda_from_log1p(self.log1p_lambda(r, p))
    }

    /// ln(1 + Λ) of row `r` at a position.
    #[inline]
    pub(crate) fn log1p_lambda(&self, r: usize, p: &GridPosition) -> f64 {
        let y = &self.rows[r * (self.n + 2) + p.j..][..4];
        p.w[0] * y[0] + p.w[1] * y[1] + p.w[2] * y[2] + p.w[3] * y[3]
    }
}

/// t = a sinh(vV) is linear near the pole; a fixes where logarithmic
/// spacing starts (in units of τ: past the exponential core of D).
pub(crate) const SINH_A: f64 = 1.0;
/// Largest tabulated tanθ_h of D̃_eff (θ_h = 90° − 1e−3 rad). Closer to
/// the horizon D̃_eff is constant to ~1e−4 relative (h·m changes by
/// ≤ 1e−3·sinθm there, and K is flat in h·m near ψ = 90°), so the last
/// value is held; a top at 1e6 spent a third of the nodes on that sliver.
const D_TOP_TAN: f64 = 1e3;
/// Largest tabulated tanθ of the Smith Λ tables (θ = 90° − 1e−6 rad): Λ
/// grows like tanθ towards the horizon, so it is not held early.
pub(crate) const LAMBDA_TOP_TAN: f64 = 1e6;

impl EffTable {
    /// Raw ∫D_eff cosθ dω at the w nodes, as (w, value) pairs, before
    /// renormalisation.
    pub(crate) fn raw_normalisation(&self) -> Vec<(f64, f64)> {
        (0..self.nw)
            .map(|i| (libm::expm1(i as f64 * self.dx), self.norm[i]))
            .collect()
    }

    pub(crate) fn build(ndf: ExponentialNdf, psd: &KcPsd, res: TableResolution) -> EffTable {
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
        let narrow = NarrowRule::new(&ndf);
        let rows: Vec<EffRow> = crate::parallel::map_rows(nw, |i| {
            let mut conv = Convolver::with_narrow(ndf, nu, narrow.clone());
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
                    let theta =
                        libm::atan(tau * SINH_A * crate::numerics::math::sinh_cosh(v * v_ext).0);
                    libm::log(conv.d_eff_fast(theta, w).max(1e-300))
                })
                .collect();
            // Bin masses of D̃ cosθ dω in T = tan²θ from the interpolant.
            let masses: Vec<f64> = (0..nv - 1)
                .map(|j| {
                    gl4(0.0, 1.0, |f| {
                        let v = (j as f64 + f) / (nv - 1) as f64;
                        let (sh, ch) = crate::numerics::math::sinh_cosh(v * v_ext);
                        let tan_t = tau * SINH_A * sh;
                        let c2 = 1.0 / (1.0 + tan_t * tan_t);
                        // dT/dv = 2 tanθ · τ a V cosh(vV); dv/df = 1/(nv−1).
                        let dt_dv = 2.0 * tan_t * tau * SINH_A * v_ext * ch;
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
            let nodes = ring_nodes(&log_d, tau_a, v_ext, &LAMBDA_RULE);
            let sums = RingSums::new(&nodes);
            let log1p_lambda = (0..LAMBDA_NODES)
                .map(|l| {
                    let v = l as f64 / (LAMBDA_NODES - 1) as f64;
                    let q = sums.one_plus_lambda(
                        tau_a * crate::numerics::math::sinh_cosh(v * lambda_v_ext).0,
                    );
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

    /// Every w node's row of ln(1 + Λ) with its lookup scales 1/(τ·a) and
    /// (points − 1)/V (for [`SharedLambdaGrid::new`]).
    pub(crate) fn lambda_rows(&self) -> impl Iterator<Item = (&[f64], f64, f64)> + Clone {
        (0..self.nw).map(|i| {
            (
                &self.log1p_lambda[i * LAMBDA_NODES..(i + 1) * LAMBDA_NODES],
                self.inv_tau_a[i],
                self.lambda_v_scale[i],
            )
        })
    }

    /// The number of w nodes.
    pub(crate) fn w_nodes(&self) -> usize {
        self.nw
    }

    /// Smith Λ of the normalised D̃_eff at every w node for tanθ (for
    /// [`EffTable::mix_nodes`] at many w brackets and one direction).
    pub(crate) fn lambda_nodes(&self, tan_t: f64) -> Vec<f64> {
        (0..self.nw).map(|i| self.lambda_node(i, tan_t)).collect()
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
    pub(crate) fn lambda(&self, wb: (usize, f64), tan_t: f64) -> f64 {
        self.mix_nodes(wb, |i| self.lambda_node(i, tan_t))
    }

    /// (1 − f)·value(i) + f·value(i + 1) for the nodes bracketing w: the
    /// table's linear mixture in w of every per-node quantity (a node with
    /// zero weight is not evaluated).
    #[inline]
    pub(crate) fn mix_nodes(&self, (i, f): (usize, f64), value: impl Fn(usize) -> f64) -> f64 {
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
    pub(crate) fn w_bracket(&self, w: f64) -> (usize, f64) {
        // ln(1 + w) rather than log1p: only x's absolute error matters (a
        // position on the grid), and rounding 1 + w costs at most 1.1e−16
        // of it; the platform's ln is a third of log1p's instructions.
        self.w_bracket_ln(crate::numerics::math::ln(1.0 + w.max(0.0)))
    }

    /// [`EffTable::w_bracket`] given ln(1 + max(w, 0)).
    #[inline]
    pub(crate) fn w_bracket_ln(&self, ln_1p_w: f64) -> (usize, f64) {
        let x = ln_1p_w / self.dx;
        if !(x < (self.nw - 1) as f64) {
            return (self.nw - 2, 1.0);
        }
        let i = x as usize;
        (i, x - i as f64)
    }

    /// Fractional v position (bin, fraction) of tanθ at node i, or None past the top.
    #[inline]
    fn v_position(&self, i: usize, tan_t: f64) -> Option<(usize, f64)> {
        self.v_bin(crate::numerics::math::asinh_nonneg(tan_t * self.inv_tau_a[i]) * self.v_scale[i])
    }

    /// (bin, fraction) of a scaled v position `x`, or None past the top.
    #[inline]
    fn v_bin(&self, x: f64) -> Option<(usize, f64)> {
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
    pub(crate) fn d_node(&self, i: usize, tan_t: f64) -> f64 {
        crate::numerics::math::exp(self.log_d_at(i, self.v_position(i, tan_t)))
    }

    /// ln D̃_eff at node i and v position `pos` ([`EffTable::v_bin`]).
    #[inline]
    fn log_d_at(&self, i: usize, pos: Option<(usize, f64)>) -> f64 {
        let row = &self.log_d[i * self.nv..(i + 1) * self.nv];
        match pos {
            Some((j, f)) => catmull_rom(row, j, f),
            None => row[self.nv - 1],
        }
    }

    /// [`EffTable::d_node`] at the four nodes i, i + 1, … (those past the last
    /// node repeat it), the asinh's ln and the exponentials on four lanes: for
    /// the cap's integrand, which needs D̃_eff at a run of neighbouring nodes
    /// on every θh ring. Within a few ulp of `d_node`'s position, and so of
    /// its value.
    #[inline]
    pub(crate) fn d_nodes(&self, i: usize, tan_t: f64) -> Lanes {
        let node = |l: usize| (i + l).min(self.nw - 1);
        let mut arg = [1.0; LANES];
        for (l, a) in arg.iter_mut().enumerate() {
            let x = tan_t * self.inv_tau_a[node(l)];
            if !(0.0..=1e150).contains(&x) {
                // Outside the lanes' ln (NaN too): node by node.
                return core::array::from_fn(|l| self.d_node(node(l), tan_t));
            }
            *a = x + libm::sqrt(x * x + 1.0);
        }
        let asinh = two_scale_lanes::ln(arg);
        let log_d = core::array::from_fn(|l| {
            let n = node(l);
            self.log_d_at(n, self.v_bin(asinh[l] * self.v_scale[n]))
        });
        two_scale_lanes::exp(log_d)
    }

    /// D̃_eff(h) at the w bracket `wb` ([`EffTable::w_bracket`]), tanθh given.
    #[inline]
    pub(crate) fn d_eff(&self, wb: (usize, f64), tan_t: f64) -> f64 {
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
    pub(crate) fn pdf(&self, wb: (usize, f64), tan_t: f64, cos_t: f64) -> f64 {
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
    pub(crate) fn sample(&self, w: f64, u0: f64, u1: f64, u2: f64) -> DVec3 {
        let (i, f) = self.w_bracket(w);
        let node = if u0 < f { i + 1 } else { i };
        self.sample_node(node, u1, u2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::quadrature::{GL4_W, GL4_X};
    use crate::wave::two_scale_lambda::one_plus_lambda;

    /// D̃_eff at four nodes on lanes equals `d_node` node by node to a few
    /// ulp, on S138's table for every block start (the last blocks repeat
    /// the last node) and tanθ from 0 to beyond the table's top: measured
    /// 1.9e−15 (the asinh's argument 1e−12 off fails it at 1.5e−12).
    #[test]
    fn d_nodes_match_d_node() {
        let ndf = ExponentialNdf::new(7.2e-4).unwrap();
        let psd = KcPsd::new(0.138, 2.0, 2.0).unwrap();
        let t = EffTable::build(ndf, &psd, TableResolution::default());
        let mut worst = 0.0f64;
        for e in 0..=300 {
            let tan_t = if e == 0 {
                0.0
            } else {
                1e-6 * libm::pow(1e12, e as f64 / 300.0)
            };
            for i in 0..t.nw {
                let got = t.d_nodes(i, tan_t);
                for (l, &g) in got.iter().enumerate() {
                    let want = t.d_node((i + l).min(t.nw - 1), tan_t);
                    worst = worst.max((g - want).abs() / want);
                }
            }
        }
        extern crate std;
        std::eprintln!("worst {worst:e}");
        assert!(worst < 1e-13, "{worst:e}");
    }

    /// The table's Smith Λ of every w node (the lobe's own G₂) against the
    /// same integral by 4-point Gauss–Legendre on each quarter of every bin,
    /// relative to 1 + Λ, over the whole Λ grid.
    #[test]
    fn lambda_rows_match_a_fine_rule() {
        let fine = BinRule {
            x: &GL4_X,
            w: &GL4_W,
            parts: 4,
        };
        let mut all = [0.0f64; 3];
        for (c, (beta, sigma, lc, gamma)) in [
            (7.2e-4, 0.138, 2.0, 2.0),
            (0.05, 0.02, 0.5, 1.5),
            (0.3, 0.2, 1.0, 3.7),
        ]
        .into_iter()
        .enumerate()
        {
            let ndf = ExponentialNdf::new(beta).unwrap();
            let psd = KcPsd::new(sigma, lc, gamma).unwrap();
            let res = TableResolution {
                w_nodes: 10,
                theta_nodes: 92,
            };
            let t = EffTable::build(ndf, &psd, res);
            let mut worst = 0.0f64;
            for i in 0..t.nw {
                let row = &t.log_d[i * t.nv..(i + 1) * t.nv];
                let tau_a = t.tau[i] * SINH_A;
                let nodes = ring_nodes(row, tau_a, t.v_extent[i], &fine);
                let lambda_v_ext = (LAMBDA_NODES - 1) as f64 / t.lambda_v_scale[i];
                for l in 0..LAMBDA_NODES {
                    let v = l as f64 / (LAMBDA_NODES - 1) as f64;
                    let q = one_plus_lambda(&nodes, tau_a * libm::sinh(v * lambda_v_ext)).max(1.0);
                    let got = libm::exp(t.log1p_lambda[i * LAMBDA_NODES + l]);
                    worst = worst.max((got - q).abs() / q);
                }
            }
            all[c] = worst;
        }
        // Measured 1.1, 1.3, 1.3e−5 (2 points per bin; 4 points: 2.2e−6).
        assert!(
            all.iter().all(|&w| w < 3e-5),
            "{:e} {:e} {:e}",
            all[0],
            all[1],
            all[2]
        );
    }

    /// The nested rule on outer panels 5× finer at the foci (10⁻⁵β at the
    /// kink where rings reach ψ = 90°) and graded by 1.3 instead of 3: the
    /// reference of the narrow-D Gauss rule (the same ring integrals; the
    /// nested rule itself integrates D 9.6e−5 low on its pole panels, a
    /// constant factor the table's renormalisation removes).
    fn d_eff_fine(ndf: &ExponentialNdf, nu: f64, theta_h: f64, w: f64) -> f64 {
        let beta = ndf.beta();
        let (sh, ch) = libm::sincos(theta_h);
        let eps = (1.0 / w).min(1.0);
        let tm_max = libm::atan(45.0 * beta);
        let kink = core::f64::consts::FRAC_PI_2 - theta_h;
        let foci = [
            (0.0, 0.05 * beta.min(eps)),
            (theta_h, 0.05 * eps),
            (kink, 1e-5 * beta),
        ];
        let mut outer = Vec::new();
        panel_edges(0.0, tm_max, &foci, 1.3, &mut outer);
        let kernel = Kernel::new(w, nu);
        outer
            .windows(2)
            .map(|p| {
                gl4(p[0], p[1], |tm| {
                    let (sm, cm) = libm::sincos(tm);
                    let d = ndf.d_tan_cos(sm / cm, cm);
                    d * sm * ring(&kernel, eps, theta_h, sh, ch, tm, sm, cm)
                })
            })
            .sum()
    }

    /// The narrow-D Gauss rule against a fine nested rule at every θh node
    /// of the tables' grids, w up to its β·w limit: away from the horizon
    /// and, where rings of D's support reach ψ = 90°, with the part beyond
    /// taken off ([`beyond_horizon`]).
    #[test]
    fn narrow_rule_matches_a_fine_nested_rule() {
        extern crate std;
        use crate::wave::two_scale_narrow::NARROW_BW_MAX;
        let cases = [
            (1e-4, 2.5),
            (7.2e-4, 2.0),
            (2e-3, 3.0),
            (5e-3, 1.5),
            (0.02, 4.0),
        ];
        for (beta, gamma) in cases {
            let ndf = ExponentialNdf::new(beta).unwrap();
            let nu = 0.5 * (gamma - 1.0);
            let rule = NarrowRule::new(&ndf).unwrap();
            let mut fast = Convolver::with_narrow(ndf, nu, Some(rule.clone()));
            let (mut worst, mut used) = ([0.0f64; 2], [0; 2]);
            for e in 0..=8 {
                let w = 0.01 * libm::pow(NARROW_BW_MAX / beta / 0.01, e as f64 / 8.0);
                let tau = libm::hypot(beta, 1.0 / w).min(1.0);
                let v_ext = libm::asinh(D_TOP_TAN / (tau * SINH_A));
                for j in 0..92 {
                    let theta = libm::atan(tau * SINH_A * libm::sinh(j as f64 / 91.0 * v_ext));
                    if !rule.holds(beta, w) {
                        continue;
                    }
                    let at = usize::from(rule.reaches_horizon(theta));
                    used[at] += 1;
                    let a = fast.d_eff_fast(theta, w);
                    let b = d_eff_fine(&ndf, nu, theta, w);
                    worst[at] = worst[at].max((a - b).abs() / b);
                }
            }
            std::eprintln!(
                "β {beta}: {} + {} nodes (horizon), max rel {:.2e}, {:.2e}",
                used[0],
                used[1],
                worst[0],
                worst[1]
            );
            assert!(used[0] > 30 && used[1] > 30, "β {beta}: {used:?}");
            assert!(worst[0] < 1e-5 && worst[1] < 1e-5, "β {beta}: {worst:?}");
        }
    }

    /// Both ways of taking the kernel's power agree with pow to round-off,
    /// for every γ a multiple of ½ or ¼ up to the largest taken by quarters
    /// and for γ between them.
    #[test]
    fn kernel_power_matches_pow() {
        let mut quarters = 0;
        for i in 1..=140 {
            let gamma = 1.0 + 0.125 * i as f64;
            let p = 0.5 * (gamma - 1.0) + 1.0;
            let power = Power::new(p);
            if let Power::Quarters(n) = power {
                assert_eq!(n as f64, 4.0 * p);
                quarters += 1;
            }
            for e in 0..=60 {
                let q = libm::pow(10.0, 0.1 * e as f64);
                let want = libm::pow(q, -p);
                let got = power.of(q);
                assert!(
                    (got - want).abs() <= 4e-14 * want,
                    "γ {gamma} q {q}: {got:e} vs {want:e}"
                );
            }
        }
        // γ from 1.5 in steps of ½ up to 15.5 (ν + 1 = 33/4).
        assert_eq!(quarters, 29);
    }

    /// The shared grid reproduces every source row's own lookup (the
    /// energy cap's Λ at wo) over the whole tanθ range, including both held
    /// ends, for tables whose w nodes' scales τ span from the macro NDF's
    /// β to 1.
    #[test]
    fn shared_lambda_grid_matches_each_row() {
        for (beta, lc, gamma) in [(7.2e-4, 2.0, 2.0), (0.05, 0.5, 1.5), (0.3, 1.0, 3.0)] {
            let ndf = ExponentialNdf::new(beta).unwrap();
            let psd = KcPsd::new(0.1, lc, gamma).unwrap();
            let res = TableResolution {
                w_nodes: 12,
                theta_nodes: 40,
            };
            let t = EffTable::build(ndf, &psd, res);
            let grid = SharedLambdaGrid::new(t.lambda_rows());
            let mut worst = 0.0f64;
            for e in 0..=400 {
                // tanθ from 1e−6 to 1e7, past the top of every row.
                let tan_t = 10f64.powf(-6.0 + 13.0 * e as f64 / 400.0);
                let p = grid.position(tan_t);
                for i in 0..t.w_nodes() {
                    let own = t.lambda_node(i, tan_t);
                    let shared = grid.lambda(i, &p);
                    // G₂ = 1/(1 + Λi + Λo) sees Λ relative to 1 + Λ.
                    worst = worst.max((shared - own).abs() / (1.0 + own));
                }
            }
            // Measured 4.7e−5 (β 7.2e−4, at Λ 0.05–2 where the source rows'
            // own cubic bends most).
            assert!(worst < 1e-4, "β {beta} Lc {lc} γ {gamma}: {worst:e}");
            let p = grid.position(0.0);
            assert_eq!(grid.lambda(0, &p), t.lambda_node(0, 0.0));
        }
    }
}
