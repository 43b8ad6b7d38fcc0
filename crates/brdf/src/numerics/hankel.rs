//! Hankel transforms of the full GHS kernel (physics.md §4.1, §10):
//!
//! S̃(u; g) = (1/2π) ∫₀^∞ [e^{−g(1−M(x))} − e^{−g}] J₀(ux) x dx.
//!
//! Two independent methods:
//! * [`s_tilde_direct`]: composite 16-point Gauss–Legendre on panels that
//!   resolve both the kernel and the Bessel oscillation — the accurate,
//!   slow reference (no allocation); [`s_tilde_direct_bounded`] is the same
//!   method with the cusp term confined to x ≲ 50 and the integration
//!   stopped where a bound on its rest is below a tolerance, fast enough for
//!   the slowly decaying covariance of a measured spectrum;
//! * `FftLog` (crate-internal, feature `alloc`): Hamilton's FFTLog on a logarithmic grid,
//!   all u at once in O(N log N) — the table generator.
//!
//! Both subtract the cusp. With A = 1 − e^{−g} and ε = (A/g)^{1/(2ν)}, the
//! function A·M(x/ε) has the same value at 0 and the same leading
//! non-analytic term −g a x^{2ν} as the kernel, and its transform is known
//! exactly: A ε² p(εu), p the unit PSD in u. What is left is smoother and
//! small in the tail, where the analytic part then carries the value.

use core::f64::consts::PI;

use super::quadrature::gauss_legendre;

/// The normalised covariance M(x) of a surface (x = r/L), with the unit
/// PSD p(u) = L² P(u/L)/σ² that is its Hankel transform.
pub trait Correlation {
    /// M(x), M(0) = 1.
    fn m(&self, x: f64) -> f64;
    /// 1 − M(x), accurate in relative terms at small x.
    fn one_minus_m(&self, x: f64) -> f64;
    /// p(u) with ∫ p d²u = 1.
    fn unit_psd_u(&self, u: f64) -> f64;
    /// Exponent ν of the leading non-analytic term 1 − M ≈ a x^{2ν}
    /// (p ∝ u^{−2ν−2} in the tail).
    fn cusp_nu(&self) -> f64;
    /// Whether a table of S̃ should leave the first diffraction order
    /// g e^{−g} p(u) out, to be added back exactly. Heavy tails need it (the
    /// orders sit at scales m^{1/(2ν)} apart), and so does any p with sharp
    /// features (a measured PSD's machining peak), which the first order
    /// carries unsmoothed.
    fn separate_first_order(&self) -> bool {
        self.cusp_nu() < FIRST_ORDER_APART_BELOW_NU
    }
    /// An upper bound of |M(y)| over all y ≥ x, non-increasing in x: where
    /// the transforms may stop integrating. The default, M itself, holds for
    /// a covariance that falls monotonically to 0 (the K-correlation's
    /// Matérn); a measured spectrum's covariance oscillates and goes
    /// negative, and stopping at its first zero drops the lobes beyond it.
    fn m_envelope(&self, x: f64) -> f64 {
        self.m(x)
    }
    /// The function K the transforms subtract, as A·K(x/ε), to remove the
    /// cusp: K(0) = 1 and 1 − M = w(1 − K) + (terms smoother than the cusp),
    /// w = [`Correlation::cusp_weight`]. Its transform
    /// [`Correlation::cusp_psd_u`] is added back exactly, so the two must be
    /// an exact pair: the default, M itself with p, is for covariances known
    /// in closed form; a measured spectrum's M is a numerical transform of p,
    /// and the difference, multiplied by A ε² p(0) ≫ S̃ at large g, would
    /// swamp the result.
    fn cusp_m(&self, x: f64) -> f64 {
        self.m(x)
    }
    /// The transform of [`Correlation::cusp_m`] in the unit-mass convention of
    /// [`Correlation::unit_psd_u`].
    fn cusp_psd_u(&self, u: f64) -> f64 {
        self.unit_psd_u(u)
    }
    /// [`Correlation::m_envelope`] for [`Correlation::cusp_m`].
    fn cusp_m_envelope(&self, x: f64) -> f64 {
        self.m_envelope(x)
    }
    /// The weight w of [`Correlation::cusp_m`] in 1 − M's leading
    /// non-analytic term.
    fn cusp_weight(&self) -> f64 {
        1.0
    }
    /// A key naming M exactly (equal keys: the same M, cusp, envelopes and
    /// p), so that work that depends on M alone, such as a full-GHS table's
    /// diffraction orders, can be shared between tables of surfaces with
    /// the same correlation but other σ and Lc. `None`, the default, shares
    /// nothing (a measured spectrum).
    fn identity(&self) -> Option<CorrelationKey> {
        None
    }
}

/// What [`Correlation::identity`] returns: a family name and its
/// parameters' bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CorrelationKey {
    /// The family, e.g. `"matern"`.
    pub family: &'static str,
    /// The family's parameters as `f64::to_bits`.
    pub params: [u64; 2],
}

/// An upper bound of |h(y)| over all y ≥ x for the GHS kernel h (or, with
/// `without_first_order`, the kernel less its first order), from
/// [`Correlation::m_envelope`]: |e^{gM} − 1| ≤ e^{g|M|} − 1 and
/// |e^{t} − 1 − t| ≤ e^{|t|} − 1 − |t|, so the bound is the kernel at the
/// envelope, and non-increasing with it.
#[inline]
pub(crate) fn kernel_envelope<C: Correlation + ?Sized>(
    c: &C,
    x: f64,
    g: f64,
    without_first_order: bool,
) -> f64 {
    let m = c.m_envelope(x).clamp(0.0, 1.0);
    if without_first_order {
        kernel_without_first_order(m, 1.0 - m, g)
    } else {
        kernel_from(m, 1.0 - m, g)
    }
}

/// Below this tail exponent ν a KC table leaves the first order out (see
/// [`Correlation::separate_first_order`]).
pub const FIRST_ORDER_APART_BELOW_NU: f64 = 0.25;

/// The GHS kernel h(x) = e^{−g(1−M)} − e^{−g}, formed without cancellation:
/// e^{−g}·expm1(gM) for small g, exp(−g(1−M)) − e^{−g} otherwise.
#[inline]
pub(crate) fn kernel<C: Correlation + ?Sized>(c: &C, x: f64, g: f64) -> f64 {
    if g < 1.0 {
        kernel_small_g(c.m(x), g)
    } else {
        kernel_large_g(c.one_minus_m(x), g)
    }
}

/// [`kernel`] from M(x) and 1 − M(x) already at hand.
#[inline]
pub(crate) fn kernel_from(m: f64, one_minus_m: f64, g: f64) -> f64 {
    KernelAtG::new(g).h(m, one_minus_m)
}

#[inline]
fn kernel_small_g(m: f64, g: f64) -> f64 {
    crate::numerics::math::exp(-g) * libm::expm1(g * m)
}

#[inline]
fn kernel_large_g(one_minus_m: f64, g: f64) -> f64 {
    crate::numerics::math::exp(-g * one_minus_m) - crate::numerics::math::exp(-g)
}

/// [`kernel`] at one g from M(x) and 1 − M(x) already at hand (the table
/// builder evaluates them once per point of a lattice shared by all its
/// rows), with e^{−g} computed once per row instead of once per point (the
/// same value, so the same bits as [`kernel`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct KernelAtG {
    g: f64,
    e_neg_g: f64,
}

impl KernelAtG {
    pub(crate) fn new(g: f64) -> Self {
        KernelAtG {
            g,
            e_neg_g: crate::numerics::math::exp(-g),
        }
    }

    /// h = e^{−g(1−M)} − e^{−g}.
    #[inline]
    pub(crate) fn h(&self, m: f64, one_minus_m: f64) -> f64 {
        if self.g < 1.0 {
            self.e_neg_g * expm1_fast(self.g * m)
        } else {
            crate::numerics::math::exp(-self.g * one_minus_m) - self.e_neg_g
        }
    }

    /// e^{−g}·(e^{gM} − 1 − gM): the kernel without its first diffraction
    /// order e^{−g} g M, whose transform g e^{−g} p(u) is known exactly. The
    /// series below gM = ½ keeps full relative accuracy where the two nearly
    /// cancel.
    #[inline]
    pub(crate) fn h_without_first_order(&self, m: f64, one_minus_m: f64) -> f64 {
        let t = self.g * m;
        if t < 0.5 {
            self.e_neg_g * exp_minus_1_minus_x(t)
        } else {
            self.h(m, one_minus_m) - self.e_neg_g * t
        }
    }
}

/// e^t − 1: by its Taylor polynomial for |t| ≤ 1/16 (the terms left out are
/// below t^{13}/13! < 1e−25 of it, so the sum is exact to round-off), which
/// costs a third of `expm1` and covers most points of the small-g table rows
/// (t = gM ≤ g); `expm1` beyond.
#[inline]
pub(crate) fn expm1_fast(t: f64) -> f64 {
    if libm::fabs(t) > 0.0625 {
        return libm::expm1(t);
    }
    // Σ_{k=1}^{12} t^k/k! by Horner in t with the coefficients 1/k! as
    // constants (a division per term would cost more than expm1).
    const C: [f64; 12] = [
        1.0,
        1.0 / 2.0,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5040.0,
        1.0 / 40320.0,
        1.0 / 362880.0,
        1.0 / 3628800.0,
        1.0 / 39916800.0,
        1.0 / 479001600.0,
    ];
    let mut p = C[11];
    for &c in C[..11].iter().rev() {
        p = c + t * p;
    }
    t * p
}

/// The kernel without its first diffraction order
/// ([`KernelAtG::h_without_first_order`]) at one point.
#[inline]
pub(crate) fn kernel_without_first_order(m: f64, one_minus_m: f64, g: f64) -> f64 {
    KernelAtG::new(g).h_without_first_order(m, one_minus_m)
}

/// e^t − 1 − t for |t| ≤ ½, by its Taylor series (relative error < 1e−16).
#[inline]
fn exp_minus_1_minus_x(t: f64) -> f64 {
    let mut term = 0.5 * t * t;
    let mut sum = term;
    let mut k = 3.0;
    while libm::fabs(term) > 1e-17 * libm::fabs(sum) && k < 40.0 {
        term *= t / k;
        sum += term;
        k += 1.0;
    }
    sum
}

/// Cusp-subtraction parameters (A', ε') for the kernel without its first
/// order: its value at 0 is A' = 1 − e^{−g} − g e^{−g} and its leading
/// non-analytic term −g(1 − e^{−g}) a x^{2ν}, so A' K(x/ε') matches both with
/// ε'^{2ν} = A'/(g(1 − e^{−g})w), for the subtracted K of weight w
/// ([`Correlation::cusp_weight`]).
#[inline]
pub(crate) fn cusp_params_without_first_order(nu: f64, w: f64, g: f64) -> (f64, f64) {
    let b = -libm::expm1(-g);
    let a = if g < 0.5 {
        crate::numerics::math::exp(-g) * exp_minus_1_minus_x(g)
    } else {
        b - g * crate::numerics::math::exp(-g)
    };
    let eps = crate::numerics::math::exp(crate::numerics::math::ln(a / (g * b * w)) / (2.0 * nu));
    (a, eps)
}

/// Cusp-subtraction parameters (A, ε) for this g and a subtracted K of
/// weight w ([`Correlation::cusp_weight`]): ε^{2ν} = A/(g w).
#[inline]
pub(crate) fn cusp_params(nu: f64, w: f64, g: f64) -> (f64, f64) {
    let a = -libm::expm1(-g);
    let eps = crate::numerics::math::exp(crate::numerics::math::ln(a / (g * w)) / (2.0 * nu));
    (a, eps)
}

/// The cusp term A·K(x/ε) of [`cusp_params`] confined to x ≲ 50: (B, δ)
/// with δ = min(ε, 1) and B = A(δ/ε)^{2ν}, so B·K(x/δ) has the same
/// non-analytic term −A a (x/ε)^{2ν} (B δ^{−2ν} = A ε^{−2ν}) and carries the
/// same u^{−2ν−2} tail in closed form. Where the subtracted K has a small
/// weight w (a measured table whose tail holds little of its mass: w = 1.3e−3
/// on corpus/al3d-1.al3d) ε = (A/(g w))^{1/(2ν)} reaches 1e5; A·K(x/ε) then
/// spans 1e7 separations and its transform A ε² p_K(εu), ~1e6 times S̃ below
/// u ~ 1/ε, cancels against the numerical part (1.2e−2 off at the mirror).
/// For w = 1 (closed-form covariances) ε < 1 and nothing changes.
pub(crate) fn confined_cusp(nu: f64, a: f64, eps: f64) -> (f64, f64) {
    if !(eps > 1.0) {
        return (a, eps);
    }
    let delta = 1.0;
    let b = a * crate::numerics::math::exp(2.0 * nu * crate::numerics::math::ln(delta / eps));
    (b, delta)
}

/// Width scale of the kernel in x: the root x_s of g(1 − M(x_s)) = 1 − e^{−g}
/// (→ 1 − M = 1/g for large g; M(x_s) ≈ g/2 for small g). Smooth in g, so
/// the lobe width W = sqrt(1 + 1/x_s²) built on it interpolates well.
pub(crate) fn kernel_width<C: Correlation + ?Sized>(c: &C, g: f64) -> f64 {
    if !(g > 0.0) {
        return f64::INFINITY;
    }
    let target = -libm::expm1(-g) / g;
    // 1 − M increases from 0 to 1; bracket in ln x, bisected to half a unit
    // of ln x (which crossing is found is decided there, as by bisection to
    // the end), then refined by false position (Illinois) on a function
    // nearly linear across the bracket: ~8 evaluations where bisection to
    // the same 1e−13 took ~42 more (M costs Bessel functions, and a table
    // asks for a width per row).
    let omm_at = |t: f64| c.one_minus_m(crate::numerics::math::exp(t));
    let (mut lo, mut hi) = (-700.0f64, 8.0f64);
    if omm_at(hi) < target {
        return crate::numerics::math::exp(hi);
    }
    while hi - lo > 0.5 {
        let mid = 0.5 * (lo + hi);
        if omm_at(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // ln(1 − M) where 1 − M is small at the root; where M is (target ≥ ½),
    // −ln M (≈ x for most correlations): both increase with t.
    let ln_target = crate::numerics::math::ln(target);
    let ln_m_target = libm::log1p(-target);
    let phi = |t: f64| {
        if target < 0.5 {
            crate::numerics::math::ln(omm_at(t).max(f64::MIN_POSITIVE)) - ln_target
        } else {
            let m = c.m(crate::numerics::math::exp(t));
            ln_m_target - crate::numerics::math::ln(m.max(f64::MIN_POSITIVE))
        }
    };
    let (mut f_lo, mut f_hi) = (phi(lo), phi(hi));
    // Which end moved last (−1 lo, +1 hi): when one end moves twice, the
    // other's value is halved (Illinois), so both ends converge.
    let mut moved = 0i8;
    for _ in 0..100 {
        if hi - lo < 1e-13 || !(f_lo < 0.0 && f_hi >= 0.0) || f_hi == 0.0 {
            break;
        }
        let t = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let t = if t > lo && t < hi { t } else { 0.5 * (lo + hi) };
        let f = phi(t);
        if f < 0.0 {
            lo = t;
            f_lo = f;
            if moved == -1 {
                f_hi *= 0.5;
            }
            moved = -1;
        } else {
            hi = t;
            f_hi = f;
            if moved == 1 {
                f_lo *= 0.5;
            }
            moved = 1;
        }
    }
    // Bisection ends the search if the two functions disagree on a side at
    // round-off or false position stalls.
    while hi - lo >= 1e-13 {
        let mid = 0.5 * (lo + hi);
        if omm_at(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    crate::numerics::math::exp(0.5 * (lo + hi))
}

/// Lobe width W(g) in u used to scale tables: sqrt(1 + 1/x_s²).
pub fn lobe_width<C: Correlation + ?Sized>(c: &C, g: f64) -> f64 {
    let xs = kernel_width(c, g);
    if xs.is_finite() {
        libm::sqrt(1.0 + 1.0 / (xs * xs))
    } else {
        1.0
    }
}

/// Smallest x in [x0, 1e6] at which the decreasing function `f` drops below
/// `level` (bisection in ln x); 1e6 if it never does.
fn crossing(f: impl Fn(f64) -> f64, x0: f64, level: f64) -> f64 {
    let mut hi = x0.max(1e-300);
    while f(hi) > level {
        hi *= 2.0;
        if hi > 1e6 {
            return 1e6;
        }
    }
    let mut lo = hi * 0.5;
    for _ in 0..60 {
        let mid = libm::sqrt(lo * hi);
        if f(mid) > level {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The panel rule of the direct transforms: 16-point Gauss–Legendre.
type PanelRule = ([f64; 8], [f64; 8]);

/// ∫_lo^hi f(x) J₀(ux) x dx by the panel rule `(gx, gw)` (`gauss_legendre::<8>()`,
/// computed once per transform by the caller: it is a Newton iteration).
fn j0_panel((gx, gw): &PanelRule, f: &impl Fn(f64) -> f64, u: f64, lo: f64, hi: f64) -> f64 {
    let half = 0.5 * (hi - lo);
    let mid = 0.5 * (hi + lo);
    let mut s = 0.0;
    for k in 0..8 {
        for sign in [-1.0, 1.0] {
            let x = mid + sign * half * gx[k];
            s += gw[k] * f(x) * libm::j0(u * x) * x;
        }
    }
    s * half
}

/// S̃(u; g) by the direct, cusp-subtracted Hankel transform: the reference
/// generator (~1e−12 relative where S̃ is above the round-off floor of
/// ~1e−18·A absolute). Costs O(u·x_c) kernel evaluations. Where the
/// correlation asks for it ([`Correlation::separate_first_order`]: heavy
/// tails, measured spectra) the first order g e^{−g} p(u) is added exactly
/// and only the rest transformed (physics.md §4.1): a measured spectrum's M
/// is itself a numerical transform of p, good to ~1e−3 of p at the band's
/// low end, and the first order is most of S̃ at small g.
pub fn s_tilde_direct<C: Correlation + ?Sized>(c: &C, u: f64, g: f64) -> f64 {
    s_tilde_direct_within(c, u, g, f64::INFINITY).unwrap_or(0.0)
}

/// [`s_tilde_direct`], or `None` when it would integrate more than
/// `max_panels` Bessel half-periods (16 kernel evaluations each): a measured
/// covariance whose envelope decays slowly, at a u far out, costs O(u·x_c) and
/// can take minutes; a caller with a time budget (`judge`'s table check) asks
/// this first.
pub fn s_tilde_direct_within<C: Correlation + ?Sized>(
    c: &C,
    u: f64,
    g: f64,
    max_panels: f64,
) -> Option<f64> {
    if !(g > 0.0) || !(u >= 0.0) || !u.is_finite() {
        return Some(0.0);
    }
    let nu = c.cusp_nu();
    let apart = c.separate_first_order();
    let (a, eps) = if apart {
        cusp_params_without_first_order(nu, c.cusp_weight(), g)
    } else {
        cusp_params(nu, c.cusp_weight(), g)
    };
    let first = if apart {
        g * crate::numerics::math::exp(-g) * c.unit_psd_u(u)
    } else {
        0.0
    };
    let analytic = a * eps * eps * c.cusp_psd_u(eps * u) + first;
    let xs = kernel_width(c, g).min(1.0);
    let xw = xs.min(eps);
    let h = |x: f64| {
        if apart {
            kernel_without_first_order(c.m(x), c.one_minus_m(x), g)
        } else {
            kernel(c, x, g)
        }
    };
    let rem = |x: f64| h(x) - a * c.cusp_m(x / eps);
    // Where the kernel and the subtracted M(x/ε) have decayed for good (their
    // envelopes: a measured covariance crosses zero long before it has).
    let xh = crossing(|x| kernel_envelope(c, x, g, apart), xs, 1e-19 * a);
    let xe = eps * crossing(|x| c.cusp_m_envelope(x), 1.0, 1e-19);
    let xc = xh.max(xe);
    let rule: PanelRule = gauss_legendre::<8>();
    let integrate = |lo: f64, hi: f64| j0_panel(&rule, &rem, u, lo, hi);
    // Geometric panels resolve the kernel's own scale (down to 1e−9·x_w);
    // uniform panels of at most half a Bessel period take over from 0.25.
    let panel = if u > 0.0 { (PI / u).min(0.25) } else { 0.25 };
    let n_uniform = libm::ceil((xc - panel).max(0.0) / panel).min(1e8);
    if n_uniform > max_panels {
        return None;
    }
    let mut total = 0.0;
    // geometric panels (ratio 2) from 1e-9·x_w up to one panel length
    let mut lo = 1e-9 * xw;
    while lo < panel {
        let hi = (2.0 * lo).min(panel);
        total += integrate(lo, hi);
        lo = hi;
    }
    for i in 0..n_uniform as usize {
        let l = panel + i as f64 * panel;
        total += integrate(l, l + panel);
    }
    Some(analytic + total / (2.0 * PI))
}

/// How far [`s_tilde_direct_bounded`] integrates: it stops where a bound on
/// the rest of the integral is below `relative`·|S̃ so far| or below
/// `absolute`, and gives up (`None`) past `max_panels` Bessel half-periods
/// (16 kernel evaluations each).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectTolerance {
    /// Bound on the neglected rest relative to the value.
    pub relative: f64,
    /// Bound on the neglected rest in S̃'s own units: a caller that only
    /// needs S̃ where it is above a fraction of its peak passes a small
    /// fraction of the peak, so points far below it cost little.
    pub absolute: f64,
    /// Largest number of uniform panels integrated before giving up.
    pub max_panels: f64,
}

impl DirectTolerance {
    /// Rest below `relative` of the value, no absolute floor, no budget.
    pub fn relative(relative: f64) -> Self {
        DirectTolerance {
            relative,
            absolute: 0.0,
            max_panels: f64::INFINITY,
        }
    }
}

/// A value of [`s_tilde_direct_bounded`] and the bound on what it left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectValue {
    /// S̃(u; g).
    pub value: f64,
    /// Upper bound of |S̃ − value| from the integral's neglected rest (the
    /// quadrature's own error, ~1e−12 relative, is not included).
    pub rest_bound: f64,
}

/// sup_y √y·|J₀(y)| = √(2/π) (approached as y → ∞; y(J₀² + Y₀²) increases to
/// 2/π), with a margin: |J₀(y)| ≤ min(1, [`J0_DECAY`]/√y) for y > 0.
pub const J0_DECAY: f64 = 0.8;

/// Points of the geometric grid on which [`s_tilde_direct_bounded`] bounds
/// the rest of its integral.
const REST_GRID: usize = 1024;

/// S̃(u; g) by the direct Hankel transform of [`s_tilde_direct`], made fast
/// for covariances that decay slowly (a measured spectrum's: its M
/// oscillates out to many correlation lengths), and still independent of
/// the FFTLog table. Two things differ:
///
/// * the subtracted cusp is B·K(x/δ) with δ = min(ε, 1) and B = A(δ/ε)^{2ν}:
///   the same non-analytic term −g w a x^{2ν} (so the same u^{−2ν−2} tail
///   carried in closed form, B δ² p_K(δu)), but confined to x ≲ 50 δ. With
///   the cusp's own weight w small (a table whose tail holds little of its
///   mass, w ~ 1e−3), ε = (A/(g w))^{1/(2ν)} reaches 1e5 and
///   [`s_tilde_direct`] integrates A·K(x/ε) out to 1e7;
/// * it stops where the rest is provably small: with |h| ≤ the kernel's
///   envelope ([`Correlation::m_envelope`]) and |J₀(y)| ≤ min(1, 0.8/√y), the
///   rest beyond x is at most (1/2π)∫_x^{x_c} E(y) min(1, 0.8/√(uy)) y dy,
///   accumulated on a geometric grid from the far end.
///
/// `None` when more than `tol.max_panels` panels would be needed.
pub fn s_tilde_direct_bounded<C: Correlation + ?Sized>(
    c: &C,
    u: f64,
    g: f64,
    tol: DirectTolerance,
) -> Option<DirectValue> {
    if !(g > 0.0) || !(u >= 0.0) || !u.is_finite() {
        return Some(DirectValue {
            value: 0.0,
            rest_bound: 0.0,
        });
    }
    let nu = c.cusp_nu();
    let apart = c.separate_first_order();
    let (a, eps) = if apart {
        cusp_params_without_first_order(nu, c.cusp_weight(), g)
    } else {
        cusp_params(nu, c.cusp_weight(), g)
    };
    let (b, delta) = confined_cusp(nu, a, eps);
    let first = if apart {
        g * crate::numerics::math::exp(-g) * c.unit_psd_u(u)
    } else {
        0.0
    };
    let analytic = b * delta * delta * c.cusp_psd_u(delta * u) + first;
    let xs = kernel_width(c, g).min(1.0);
    let xw = xs.min(delta);
    let xh = crossing(|x| kernel_envelope(c, x, g, apart), xs, 1e-19 * a);
    let xe = delta * crossing(|x| c.cusp_m_envelope(x), 1.0, 1e-19);
    let xc = xh.max(xe);
    let kern = KernelAtG::new(g);
    // 1 − M only where the kernel needs it (e^{−g(1−M)} at g ≥ 1, gM ≥ ½):
    // each of M, 1 − M and K costs a Matérn function of a measured table.
    let h = |x: f64| {
        let m = c.m(x);
        let need_omm = g >= 1.0 && (!apart || g * m >= 0.5);
        let omm = if need_omm { c.one_minus_m(x) } else { 1.0 - m };
        if apart {
            kern.h_without_first_order(m, omm)
        } else {
            kern.h(m, omm)
        }
    };
    let rem = |x: f64| {
        let cusp = if x < xe { b * c.cusp_m(x / delta) } else { 0.0 };
        h(x) - cusp
    };
    let rule: PanelRule = gauss_legendre::<8>();
    let integrate = |lo: f64, hi: f64| j0_panel(&rule, &rem, u, lo, hi);
    let panel = if u > 0.0 { (PI / u).min(0.25) } else { 0.25 };
    let envelope = |x: f64| {
        kernel_envelope(c, x, g, apart)
            + if x < xe {
                b * c.cusp_m_envelope(x / delta)
            } else {
                0.0
            }
    };
    let rest = RestBound::new(&envelope, u, panel, xc);
    let mut total = 0.0;
    let mut lo = 1e-9 * xw;
    while lo < panel {
        let hi = (2.0 * lo).min(panel);
        total += integrate(lo, hi);
        lo = hi;
    }
    let n_uniform = libm::ceil((xc - panel).max(0.0) / panel).min(1e8);
    let mut x = panel;
    let mut i = 0.0;
    loop {
        let value = analytic + total / (2.0 * PI);
        let left = rest.beyond(x);
        if i >= n_uniform || left <= tol.absolute.max(tol.relative * libm::fabs(value)) {
            return Some(DirectValue {
                value,
                rest_bound: if i >= n_uniform { 0.0 } else { left },
            });
        }
        if i >= tol.max_panels {
            return None;
        }
        total += integrate(x, x + panel);
        i += 1.0;
        x = panel + i * panel;
    }
}

/// The bound on the rest of [`s_tilde_direct_bounded`]'s integral beyond x,
/// on a geometric grid x_j from the first uniform panel to the cut-off:
/// (1/2π) Σ_{j ≥ i} E(x_j)·min(1, 0.8/√(u x_j))·(x_{j+1}² − x_j²)/2, with E
/// an envelope of |integrand/(J₀ x)| that does not increase, so each term
/// bounds its cell.
struct RestBound {
    x0: f64,
    ln_ratio: f64,
    n: usize,
    tail: [f64; REST_GRID + 1],
}

impl RestBound {
    fn new(envelope: &dyn Fn(f64) -> f64, u: f64, x0: f64, xc: f64) -> Self {
        let mut r = RestBound {
            x0,
            ln_ratio: 1.0,
            n: 0,
            tail: [0.0; REST_GRID + 1],
        };
        if !(xc > x0) {
            return r;
        }
        let span = crate::numerics::math::ln(xc / x0);
        r.n = (libm::ceil(span / 0.02) as usize).clamp(1, REST_GRID);
        r.ln_ratio = span / r.n as f64;
        let at = |j: usize| x0 * crate::numerics::math::exp(j as f64 * r.ln_ratio);
        let mut acc = 0.0;
        for j in (0..r.n).rev() {
            let (xa, xb) = (at(j), if j + 1 == r.n { xc } else { at(j + 1) });
            let bessel = if u > 0.0 {
                (J0_DECAY / libm::sqrt(u * xa)).min(1.0)
            } else {
                1.0
            };
            acc += envelope(xa) * bessel * 0.5 * (xb - xa) * (xb + xa) / (2.0 * PI);
            r.tail[j] = acc;
        }
        r
    }

    /// Bound on the rest of the integral over [x, x_c].
    fn beyond(&self, x: f64) -> f64 {
        if self.n == 0 || !(x >= self.x0) {
            return self.tail[0];
        }
        let j = libm::floor(crate::numerics::math::ln(x / self.x0) / self.ln_ratio);
        if j >= self.n as f64 {
            return 0.0;
        }
        self.tail[j as usize]
    }
}

#[cfg(feature = "alloc")]
pub(crate) use fftlog::FftLog;

#[cfg(feature = "alloc")]
mod fftlog {
    use super::super::fft::Fft;
    use super::super::special::ln_gamma_complex;
    use alloc::vec;
    use alloc::vec::Vec;
    use core::f64::consts::PI;

    /// Hamilton's FFTLog for F(u) = ∫₀^∞ f(x) J₀(ux) x dx on the grid
    /// x_n = e^{t₀ + nΔ}, u_j = e^{s₀ + jΔ} with s₀ = −(t₀ + (N−1)Δ).
    ///
    /// f(x)·x^{2−q} is expanded in a Fourier series in ln x and each term
    /// x^{q−2+iω} is transformed exactly: ∫ y^{s−1} J₀(y) dy =
    /// 2^{s−1} Γ(s/2)/Γ(1 − s/2), s = q + iω. The bias q = 1 makes both ends
    /// of the input and output decay for every kernel used here; the window
    /// must be wide enough that f·x^{2−q} and F·u^q are negligible at its
    /// edges (the result is periodic in ln u with period NΔ).
    pub struct FftLog {
        n: usize,
        dt: f64,
        q: f64,
        /// Half-length complex FFT: the input and output are real, so each
        /// N-point transform runs as one N/2-point complex FFT plus an O(N)
        /// split (halves the build time of a transform).
        fft: Fft,
        /// e^{−2πim/N}, m = 0…N/2: the split's twiddles (real and
        /// imaginary parts apart, so the split's loops vectorise).
        split_re: Vec<f64>,
        split_im: Vec<f64>,
        /// K(q + iω_m)·e^{−2πim/N}/N for the bins m = 0…N/2 (the rest are
        /// their conjugates: the kernel is Hermitian in m), real and
        /// imaginary parts apart.
        pub(super) kern_re: Vec<f64>,
        pub(super) kern_im: Vec<f64>,
        /// e^{(2−q)iΔ} and e^{−qjΔ}: the bias weights x^{2−q}, u^{−q} up to
        /// a factor per transform, so a transform costs no exponentials.
        pub(super) bias_in: Vec<f64>,
        pub(super) bias_out: Vec<f64>,
    }

    impl FftLog {
        /// Plan for `n` (a power of two) points spaced `dt` in ln x, bias q = 1.
        pub fn new(n: usize, dt: f64) -> Self {
            Self::with_bias(n, dt, 1.0)
        }

        /// Plan with bias `q` ∈ (0, 3/2): f·x^{2−q} and F·u^q must decay at
        /// both ends of the window.
        pub fn with_bias(n: usize, dt: f64, q: f64) -> Self {
            assert!(n >= 4 && n.is_power_of_two());
            let l = n as f64 * dt;
            let mut kernel = vec![(0.0, 0.0); n / 2 + 1];
            for (m, slot) in kernel.iter_mut().enumerate() {
                if m == n / 2 {
                    continue; // Nyquist bin dropped (input decays at both ends)
                }
                let mm = if m < n / 2 {
                    m as f64
                } else {
                    m as f64 - n as f64
                };
                let w = 2.0 * PI * mm / l;
                // ln K = (s−1) ln 2 + lnΓ(s/2) − lnΓ(1 − s/2), s = q + iω
                let (a_r, a_i) = ln_gamma_complex(0.5 * q, 0.5 * w);
                let (b_r, b_i) = ln_gamma_complex(1.0 - 0.5 * q, -0.5 * w);
                let lr = (q - 1.0) * core::f64::consts::LN_2 + a_r - b_r;
                let li = w * core::f64::consts::LN_2 + a_i - b_i;
                // phase e^{−2πi m/N}
                let ph = li - 2.0 * PI * m as f64 / n as f64;
                let mag = crate::numerics::math::exp(lr) / n as f64;
                let (s, c) = libm::sincos(ph);
                *slot = (mag * c, mag * s);
            }
            let (split_re, split_im) = (0..=n / 2)
                .map(|m| {
                    let (s, c) = libm::sincos(-2.0 * PI * m as f64 / n as f64);
                    (c, s)
                })
                .unzip();
            FftLog {
                n,
                dt,
                q,
                fft: Fft::new(n / 2),
                split_re,
                split_im,
                kern_re: kernel.iter().map(|k| k.0).collect(),
                kern_im: kernel.iter().map(|k| k.1).collect(),
                bias_in: (0..n)
                    .map(|i| crate::numerics::math::exp((2.0 - q) * i as f64 * dt))
                    .collect(),
                bias_out: (0..n)
                    .map(|j| crate::numerics::math::exp(-q * j as f64 * dt))
                    .collect(),
            }
        }

        /// Number of grid points.
        pub fn len(&self) -> usize {
            self.n
        }

        /// Grid spacing in ln x and ln u.
        pub fn dt(&self) -> f64 {
            self.dt
        }

        /// Transforms samples `f[n] = f(e^{t0 + nΔ})`; returns F at
        /// u_j = e^{s0 + jΔ}, s0 = −(t0 + (N−1)Δ), in `out` (length N).
        /// `work` is scratch (any contents; reused across calls).
        pub fn transform(&self, t0: f64, f: &[f64], out: &mut Vec<f64>, work: &mut Vec<f64>) {
            self.transform_scaled(t0, f, 1.0, out, work);
        }

        /// [`FftLog::transform`] with the output multiplied by `factor`
        /// (folded into the output weights: no pass of its own).
        pub fn transform_scaled(
            &self,
            t0: f64,
            f: &[f64],
            factor: f64,
            out: &mut Vec<f64>,
            work: &mut Vec<f64>,
        ) {
            let n = self.n;
            let h = n / 2;
            // work = [z_re | z_im | y_re | y_im], the last two h + 1 long;
            // only z past the samples needs clearing.
            work.resize(4 * h + 2, 0.0);
            let (zr, rest) = work.split_at_mut(h);
            let (zi, rest) = rest.split_at_mut(h);
            let (yr, yi) = rest.split_at_mut(h + 1);
            // x_n = f_n·bias, packed as z_k = x_{2k} + i x_{2k+1}.
            let scale_in = crate::numerics::math::exp((2.0 - self.q) * t0);
            // Samples past f's end are zero.
            let given = f.len().min(n);
            zr[given.div_ceil(2)..].fill(0.0);
            zi[given / 2..].fill(0.0);
            for (k, pair) in f[..given].chunks(2).enumerate() {
                zr[k] = pair[0] * scale_in * self.bias_in[2 * k];
                if let Some(&v) = pair.get(1) {
                    zi[k] = v * scale_in * self.bias_in[2 * k + 1];
                }
            }
            self.fft.run(zr, zi);
            self.spectrum_times_kernel(zr, zi, yr, yi);
            self.split_for_real_output(yr, yi, zr, zi);
            self.fft.run(zr, zi);
            let s0 = -(t0 + (n - 1) as f64 * self.dt);
            let scale_out = crate::numerics::math::exp(-self.q * s0) * factor;
            out.clear();
            out.extend(
                zr.iter()
                    .zip(zi.iter())
                    .zip(self.bias_out.chunks_exact(2))
                    .flat_map(|((&a, &b), w)| [a * scale_out * w[0], b * scale_out * w[1]]),
            );
        }

        /// Y_m = X_m·K_m for m = 0…h from the half-length spectrum Z of the
        /// packed samples (E, O: spectra of the even and odd samples):
        /// E_m = (Z_m + Z̄_{h−m})/2, O_m = (Z_m − Z̄_{h−m})/2i,
        /// X_m = E_m + e^{−2πim/N} O_m (indices of Z mod h). Out of place,
        /// with Z_{h−m} read backwards, so that the loop vectorises.
        fn spectrum_times_kernel(&self, zr: &[f64], zi: &[f64], yr: &mut [f64], yi: &mut [f64]) {
            let h = zr.len();
            let y = |m: usize, (ar, ai): (f64, f64), (br, bi): (f64, f64)| {
                Self::y_from(
                    ar,
                    ai,
                    br,
                    bi,
                    self.split_re[m],
                    self.split_im[m],
                    self.kern_re[m],
                    self.kern_im[m],
                )
            };
            // m = 0 and m = h both pair Z_0 with itself.
            let (y0, yh) = (
                y(0, (zr[0], zi[0]), (zr[0], -zi[0])),
                y(h, (zr[0], zi[0]), (zr[0], -zi[0])),
            );
            (yr[0], yi[0], yr[h], yi[h]) = (y0.0, y0.1, yh.0, yh.1);
            let lanes = zr[1..h]
                .iter()
                .zip(&zi[1..h])
                .zip(zr[1..h].iter().rev().zip(zi[1..h].iter().rev()))
                .zip(self.split_re[1..h].iter().zip(&self.split_im[1..h]))
                .zip(self.kern_re[1..h].iter().zip(&self.kern_im[1..h]))
                .zip(yr[1..h].iter_mut().zip(yi[1..h].iter_mut()));
            for (((((&ar, &ai), (&br, &bi)), (&wr, &wi)), (&kr, &ki)), (oyr, oyi)) in lanes {
                let (vr, vi) = Self::y_from(ar, ai, br, -bi, wr, wi, kr, ki);
                *oyr = vr;
                *oyi = vi;
            }
        }

        /// Y_m from a = Z_m and b = Z̄_{h−m}, the split twiddle w and kernel K.
        #[inline(always)]
        #[allow(clippy::too_many_arguments)]
        fn y_from(
            ar: f64,
            ai: f64,
            br: f64,
            bi: f64,
            wr: f64,
            wi: f64,
            kr: f64,
            ki: f64,
        ) -> (f64, f64) {
            let (er, ei) = (0.5 * (ar + br), 0.5 * (ai + bi));
            // (Z_m − Z̄_{h−m})/2i = (d_i − i d_r)/2 for d = Z_m − Z̄_{h−m}.
            let (or_, oi) = (0.5 * (ai - bi), -0.5 * (ar - br));
            let (xr, xi) = (er + wr * or_ - wi * oi, ei + wr * oi + wi * or_);
            (xr * kr - xi * ki, xr * ki + xi * kr)
        }

        /// C_m = (Y_m + Y_{m+h}) + i e^{−2πim/N} (Y_m − Y_{m+h}), m = 0…h−1,
        /// with Y_{m+h} = Ȳ_{h−m} (Y is Hermitian): its h-point transform is
        /// y_{2k} + i y_{2k+1}, the real output.
        fn split_for_real_output(&self, yr: &[f64], yi: &[f64], cr: &mut [f64], ci: &mut [f64]) {
            let h = cr.len();
            let lanes = yr[..h]
                .iter()
                .zip(&yi[..h])
                .zip(yr[1..=h].iter().rev().zip(yi[1..=h].iter().rev()))
                .zip(self.split_re[..h].iter().zip(&self.split_im[..h]))
                .zip(cr.iter_mut().zip(ci.iter_mut()));
            for ((((&ar, &ai), (&br, &bi)), (&wr, &wi)), (ocr, oci)) in lanes {
                let (sr, si) = (ar + br, ai - bi);
                let (dr, di) = (ar - br, ai + bi);
                let (tr, ti) = (wr * dr - wi * di, wr * di + wi * dr);
                *ocr = sr - ti;
                *oci = si + tr;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::statistics::matern::Matern;

    fn closed_form_gamma2(u: f64, g: f64) -> f64 {
        // γ = 2: p_m(u) = m/(2π(m²+u²)^{3/2}); S̃ = Σ w_m p_m.
        let (lo, hi) = super::super::poisson::term_range(g, 1e-18);
        let mut s = 0.0;
        for m in lo..=hi {
            let w = crate::numerics::math::exp(super::super::poisson::log_weight(m, g));
            let mf = m as f64;
            s += w * mf / (2.0 * PI * libm::pow(mf * mf + u * u, 1.5));
        }
        s
    }

    /// The polynomial branch against `expm1` over its whole range and at
    /// the switch, to round-off.
    #[test]
    fn expm1_fast_matches_expm1() {
        let mut worst: f64 = 0.0;
        for i in -2000..=2000 {
            let t = i as f64 * (0.07 / 2000.0);
            let (a, b) = (expm1_fast(t), libm::expm1(t));
            if b != 0.0 {
                worst = worst.max((a / b - 1.0).abs());
            }
        }
        for t in [1e-300, -1e-300, 1e-17, 1e-9, 0.0625, -0.0625, 0.0625000001] {
            worst = worst.max((expm1_fast(t) / libm::expm1(t) - 1.0).abs());
        }
        assert_eq!(expm1_fast(0.0), 0.0);
        assert!(worst < 4e-16, "{worst}");
    }

    /// The width's root against the definition g(1 − M(x_s)) = 1 − e^{−g}
    /// and against plain bisection in ln x, from heavy tails to near-Gaussian
    /// correlations and over the tables' whole g range.
    #[test]
    fn kernel_width_solves_its_equation() {
        let mut worst: f64 = 0.0;
        for &nu in &[0.025, 0.1, 0.5, 1.0, 2.5, 12.0, 49.5] {
            let m = Matern::new(nu);
            for k in 0..=100 {
                let g = 1e-5 * libm::pow(10.0, k as f64 * 0.11);
                let xs = kernel_width(&m, g);
                let target = -libm::expm1(-g) / g;
                let (mut lo, mut hi) = (-700.0f64, 8.0f64);
                while hi - lo > 1e-13 {
                    let mid = 0.5 * (lo + hi);
                    if m.one_minus_m(libm::exp(mid)) < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let by_bisection = libm::exp(0.5 * (lo + hi));
                let e = (xs / by_bisection - 1.0).abs();
                worst = worst.max(e);
                // Where M → 1, 1 − M carries ~1e−16 absolute round-off, so
                // the root is defined only to ~1e−16/(2ν(1 − M)): 1e−12 at
                // g = 1e4 for ν = 1 (measured 1.8e−12), 1e-10 at g = 1e6.
                assert!(e < 1e-9, "ν = {nu}, g = {g}: {xs} vs {by_bisection}");
                let r = m.one_minus_m(xs) / target - 1.0;
                assert!(r.abs() < 1e-9, "ν = {nu}, g = {g}: residual {r:e}");
            }
        }
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn direct_matches_gamma2_closed_form() {
        let m = Matern::new(0.5);
        let mut worst: f64 = 0.0;
        for &g in &[1e-3, 0.1, 1.0, 10.0, 100.0, 1000.0] {
            for &u in &[0.0, 0.3, 3.0, 30.0, 300.0] {
                let a = s_tilde_direct(&m, u, g);
                let b = closed_form_gamma2(u, g);
                worst = worst.max((a / b - 1.0).abs());
                assert!((a / b - 1.0).abs() < 1e-9, "g={g} u={u}: {a} vs {b}");
            }
        }
        assert!(worst < 1e-9, "{worst}");
    }

    /// The half-length real transform against the definition (a naive
    /// N-point DFT, the Hermitian kernel on all N bins, a naive DFT back)
    /// and against the full-length complex FFT of the same sequence.
    #[cfg(feature = "alloc")]
    #[test]
    fn fftlog_real_split_matches_naive_dft() {
        use alloc::vec::Vec;
        for (n, q, dt) in [(64usize, 1.0, 0.4), (128, 0.5, 0.2)] {
            let t0 = -13.0;
            let plan = FftLog::with_bias(n, dt, q);
            let f: Vec<f64> = (0..n)
                .map(|i| {
                    let x = crate::numerics::math::exp(t0 + i as f64 * dt);
                    crate::numerics::math::exp(-x) * (1.0 + 0.3 * libm::sin(7.0 * i as f64))
                })
                .collect();
            let (mut re, mut im) = (Vec::new(), Vec::new());
            plan.transform(t0, &f, &mut re, &mut im);
            let scale_in = crate::numerics::math::exp((2.0 - q) * t0);
            let x: Vec<f64> = (0..n).map(|i| f[i] * scale_in * plan.bias_in[i]).collect();
            let dft = |v: &dyn Fn(usize) -> (f64, f64), k: usize| {
                (0..n).fold((0.0, 0.0), |(ar, ai), i| {
                    let (vr, vi) = v(i);
                    let (s, c) = libm::sincos(-2.0 * PI * ((i * k) % n) as f64 / n as f64);
                    (ar + vr * c - vi * s, ai + vr * s + vi * c)
                })
            };
            let y: Vec<(f64, f64)> = (0..n)
                .map(|m| {
                    let (xr, xi) = dft(&|i| (x[i], 0.0), m);
                    let (kr, ki) = if m <= n / 2 {
                        (plan.kern_re[m], plan.kern_im[m])
                    } else {
                        let (kr, ki) = (plan.kern_re[n - m], plan.kern_im[n - m]);
                        (kr, -ki)
                    };
                    (xr * kr - xi * ki, xr * ki + xi * kr)
                })
                .collect();
            let s0 = -(t0 + (n - 1) as f64 * dt);
            let scale_out = crate::numerics::math::exp(-q * s0);
            let want: Vec<f64> = (0..n)
                .map(|j| dft(&|m| y[m], j).0 * scale_out * plan.bias_out[j])
                .collect();
            let peak = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            // The full-length complex transform, for the error scale.
            let full = crate::numerics::fft::Fft::new(n);
            let (mut fr, mut fi): (Vec<f64>, Vec<f64>) = (x.clone(), alloc::vec![0.0; n]);
            full.run(&mut fr, &mut fi);
            for m in 0..n {
                let (kr, ki) = if m <= n / 2 {
                    (plan.kern_re[m], plan.kern_im[m])
                } else {
                    let (kr, ki) = (plan.kern_re[n - m], plan.kern_im[n - m]);
                    (kr, -ki)
                };
                let (a, b) = (fr[m], fi[m]);
                fr[m] = a * kr - b * ki;
                fi[m] = a * ki + b * kr;
            }
            full.run(&mut fr, &mut fi);
            // Both paths differ from the naive sums by ~1e−11 of the peak
            // (the bias weights span many decades); a wrong split is O(1).
            for j in 0..n {
                let old = fr[j] * scale_out * plan.bias_out[j];
                assert!(
                    (re[j] - want[j]).abs() < 1e-10 * peak && (re[j] - old).abs() < 1e-10 * peak,
                    "n {n} j {j}: split {} naive {} full-length {old}",
                    re[j],
                    want[j]
                );
            }
        }
    }

    #[cfg(feature = "alloc")]
    #[test]
    fn fftlog_known_pairs() {
        use alloc::vec::Vec;
        let n = 4096;
        let dt = 0.02;
        let plan = FftLog::new(n, dt);
        let t0 = -45.0;
        let f: Vec<f64> = (0..n)
            .map(|i| crate::numerics::math::exp(-crate::numerics::math::exp(t0 + i as f64 * dt)))
            .collect();
        let (mut re, mut im) = (Vec::new(), Vec::new());
        plan.transform(t0, &f, &mut re, &mut im);
        let s0 = -(t0 + (n - 1) as f64 * dt);
        let mut worst: f64 = 0.0;
        for (j, v) in re.iter().enumerate() {
            let u = crate::numerics::math::exp(s0 + j as f64 * dt);
            if (1e-4..1e4).contains(&u) {
                let want = libm::pow(1.0 + u * u, -1.5);
                worst = worst.max((v / want - 1.0).abs());
            }
        }
        assert!(worst < 1e-8, "exp: {worst}");
        let f: Vec<f64> = (0..n)
            .map(|i| {
                let x = crate::numerics::math::exp(t0 + i as f64 * dt);
                crate::numerics::math::exp(-0.5 * x * x)
            })
            .collect();
        plan.transform(t0, &f, &mut re, &mut im);
        let mut worst: f64 = 0.0;
        for (j, v) in re.iter().enumerate() {
            let u = crate::numerics::math::exp(s0 + j as f64 * dt);
            if (1e-4..6.0).contains(&u) {
                let want = crate::numerics::math::exp(-0.5 * u * u);
                worst = worst.max((v - want).abs() / want.max(1e-6));
            }
        }
        assert!(worst < 1e-8, "gauss: {worst}");
    }

    /// |J₀(y)| ≤ min(1, J0_DECAY/√y), the bound the rest of the bounded transform rests on:
    /// sampled densely over the first 3000 oscillations (√y|J₀| rises towards √(2/π) =
    /// 0.7979 from below).
    #[test]
    fn j0_stays_under_its_decay_bound() {
        let mut worst = 0.0f64;
        for i in 1..2_000_000 {
            let y = i as f64 * 5e-3;
            worst = worst.max(libm::fabs(libm::j0(y)) * libm::sqrt(y));
        }
        assert!(worst < J0_DECAY, "{worst}");
        assert!(worst > 0.797, "{worst}");
    }

    #[test]
    fn bounded_direct_matches_the_gamma2_closed_form_and_the_full_transform() {
        let tol = DirectTolerance::relative(1e-12);
        let m = Matern::new(0.5);
        for &g in &[1e-3, 0.1, 1.0, 10.0, 100.0, 1000.0] {
            for &u in &[0.0, 0.3, 3.0, 30.0, 300.0] {
                let want = closed_form_gamma2(u, g);
                let v = s_tilde_direct_bounded(&m, u, g, tol).unwrap();
                assert!(
                    (v.value / want - 1.0).abs() < 1e-9,
                    "g={g} u={u}: {v:?} vs {want}"
                );
                assert!(v.rest_bound <= 1e-12 * v.value, "g={g} u={u}: {v:?}");
            }
        }
        // Other tails, heavy (first order apart) to smooth: the same values as the
        // transform that integrates to its cut-off.
        for nu in [0.1, 0.3, 1.5, 4.0] {
            let m = Matern::new(nu);
            for &g in &[1e-3, 0.5, 20.0] {
                let peak = s_tilde_direct(&m, 0.0, g);
                for &u in &[0.0, 1.0, 10.0, 100.0] {
                    let full = s_tilde_direct(&m, u, g);
                    if !(full >= 1e-6 * peak) {
                        continue;
                    }
                    let v = s_tilde_direct_bounded(&m, u, g, tol).unwrap().value;
                    assert!(
                        (v / full - 1.0).abs() < 1e-9,
                        "ν={nu} g={g} u={u}: {v} vs {full}"
                    );
                }
            }
        }
    }

    /// M = w e^{−x} + (1 − w) e^{−x/s}: a covariance whose cusp (that of e^{−x}, weight
    /// w + (1 − w)/s ≈ 0.02) holds little of its mass, as a measured table's tail does, so the
    /// unconfined cusp term would span ε ~ 50 correlation lengths. Its S̃ is closed form:
    /// M^m is a sum of exponentials e^{−a x}, each transforming to a/(2π(a² + u²)^{3/2}).
    struct TwoExponentials {
        w: f64,
        s: f64,
    }

    impl Correlation for TwoExponentials {
        fn m(&self, x: f64) -> f64 {
            self.w * libm::exp(-x) + (1.0 - self.w) * libm::exp(-x / self.s)
        }
        fn one_minus_m(&self, x: f64) -> f64 {
            -self.w * libm::expm1(-x) - (1.0 - self.w) * libm::expm1(-x / self.s)
        }
        fn unit_psd_u(&self, u: f64) -> f64 {
            let p = |a: f64| a / (2.0 * PI * libm::pow(a * a + u * u, 1.5));
            self.w * p(1.0) + (1.0 - self.w) * p(1.0 / self.s)
        }
        fn cusp_nu(&self) -> f64 {
            0.5
        }
        fn cusp_m(&self, x: f64) -> f64 {
            libm::exp(-x)
        }
        fn cusp_psd_u(&self, u: f64) -> f64 {
            1.0 / (2.0 * PI * libm::pow(1.0 + u * u, 1.5))
        }
        fn cusp_weight(&self) -> f64 {
            self.w + (1.0 - self.w) / self.s
        }
    }

    fn two_exponentials_closed_form(c: &TwoExponentials, u: f64, g: f64) -> f64 {
        let (lo, hi) = super::super::poisson::term_range(g, 1e-18);
        let mut s = 0.0;
        for m in lo..=hi {
            let wm = crate::numerics::math::exp(super::super::poisson::log_weight(m, g));
            // Σ_k C(m, k) w^k (1 − w)^{m−k} p(a_k), a_k = k + (m − k)/s
            let mut binom = 1.0;
            let mut pm = 0.0;
            for k in 0..=m {
                if k > 0 {
                    binom *= (m - k + 1) as f64 / k as f64;
                }
                let a = k as f64 + (m - k) as f64 / c.s;
                let weight =
                    binom * libm::pow(c.w, k as f64) * libm::pow(1.0 - c.w, (m - k) as f64);
                pm += weight * a / (2.0 * PI * libm::pow(a * a + u * u, 1.5));
            }
            s += wm * pm;
        }
        s
    }

    #[test]
    fn a_weak_cusp_is_confined_and_still_exact() {
        let c = TwoExponentials { w: 1e-3, s: 50.0 };
        let tol = DirectTolerance::relative(1e-12);
        let mut worst = 0.0f64;
        for &g in &[1e-3, 0.1, 1.0, 10.0] {
            let (_, eps) = cusp_params(0.5, c.cusp_weight(), g);
            assert!(
                g > 5.0 || eps > 10.0,
                "g {g}: ε {eps} (the case is meant to confine)"
            );
            let peak = two_exponentials_closed_form(&c, 0.0, g);
            for &u in &[0.0, 0.01, 0.1, 0.3, 1.0, 3.0, 30.0] {
                let want = two_exponentials_closed_form(&c, u, g);
                // Far below the peak the x-space sum cancels to round-off (3.8e−8 relative
                // at 3e−10 of the peak); the checks judge S̃ above 1e−3 of it.
                if want < 1e-6 * peak {
                    continue;
                }
                let v = s_tilde_direct_bounded(&c, u, g, tol).unwrap().value;
                worst = worst.max((v / want - 1.0).abs());
                assert!((v / want - 1.0).abs() < 1e-9, "g={g} u={u}: {v} vs {want}");
            }
        }
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn the_cusp_is_confined_only_when_it_reaches_past_one() {
        // Closed-form covariances (weight 1) have ε < 1 at every g: unchanged.
        for nu in [0.1, 0.5, 3.0] {
            for g in [1e-4, 1e-2, 1.0, 1e3] {
                for (a, eps) in [
                    cusp_params(nu, 1.0, g),
                    cusp_params_without_first_order(nu, 1.0, g),
                ] {
                    assert!(eps < 1.0, "ν {nu} g {g}: ε {eps}");
                    assert_eq!(confined_cusp(nu, a, eps), (a, eps));
                }
            }
        }
        // A weak cusp: δ = 1 and the same coefficient B δ^{−2ν} = A ε^{−2ν}.
        let (a, eps) = cusp_params(0.25, 1e-3, 1e-2);
        let (b, delta) = confined_cusp(0.25, a, eps);
        assert_eq!(delta, 1.0);
        assert!((b / libm::pow(delta, 0.5) / (a / libm::pow(eps, 0.5)) - 1.0).abs() < 1e-12);
    }

    /// With a budget smaller than the panels it needs, `None`; an absolute tolerance stops it
    /// early with a bound that holds.
    #[test]
    fn bounded_direct_keeps_its_budget_and_its_bound() {
        let m = Matern::new(0.5);
        let (u, g) = (300.0, 0.1);
        let tight = DirectTolerance::relative(1e-13);
        assert!(
            s_tilde_direct_bounded(
                &m,
                u,
                g,
                DirectTolerance {
                    max_panels: 10.0,
                    ..tight
                }
            )
            .is_none()
        );
        let want = closed_form_gamma2(u, g);
        let loose = DirectTolerance {
            relative: 0.0,
            absolute: 1e-3 * want,
            max_panels: f64::INFINITY,
        };
        let v = s_tilde_direct_bounded(&m, u, g, loose).unwrap();
        assert!(v.rest_bound <= 1e-3 * want && v.rest_bound > 0.0, "{v:?}");
        assert!(
            (v.value - want).abs() <= v.rest_bound + 1e-12 * want,
            "{v:?} vs {want}"
        );
    }
}
