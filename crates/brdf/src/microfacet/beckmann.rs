//! Beckmann distribution.

use crate::numerics::math::exp;
use core::f64::consts::{FRAC_1_SQRT_2, PI};
use glam::DVec3;

const SQRT_PI: f64 = 1.772_453_850_905_516;

/// D(h) for h.z > 0: exp(−tan²θ (cos²φ/αx² + sin²φ/αy²)) / (π αx αy cos⁴θ).
#[inline]
pub(super) fn d(h: DVec3, ax: f64, ay: f64) -> f64 {
    let z2 = h.z * h.z;
    let x = h.x / ax;
    let y = h.y / ay;
    let e = (x * x + y * y) / z2;
    let num = exp(-e);
    // Near the horizon cos⁴θ underflows before e^{−tan²θ/α²} does not:
    // the limit is 0, not 0/0.
    if num == 0.0 {
        return 0.0;
    }
    num / (PI * ax * ay * z2 * z2)
}

/// Λ from t = α² tan²θ, with a = 1/√t: (e^{−a²}/(a√π) − erfc a)/2.
///
/// For a ≥ 1.25 (x = 1/a = √t ≤ 0.8) it is e^{−a²} x³ H(x), with H a
/// polynomial ([`LAMBDA_POLY`]): one exp instead of libm's erfc, which
/// there takes two exps of its own, and no cancellation, where the
/// difference above loses up to three digits as a grows (its two terms
/// agree to 1/(2a²)). Below a = 1.25 Λ is not small, erfc is a cheap
/// rational function and the difference loses nothing.
#[inline]
pub(super) fn lambda(t: f64) -> f64 {
    if t.is_infinite() {
        return f64::INFINITY;
    }
    if t <= 0.0 {
        return 0.0;
    }
    if t <= LAMBDA_POLY_MAX_X * LAMBDA_POLY_MAX_X {
        let x = libm::sqrt(t);
        // e^{−1/t} underflows to 0 from a ≈ 27.3 on: the right limit.
        return exp(-1.0 / t) * scaled_lambda(x);
    }
    let a = 1.0 / libm::sqrt(t);
    (0.5 * (exp(-a * a) / (a * SQRT_PI) - libm::erfc(a))).max(0.0)
}

/// [`lambda`] at t = q/z² from q = αx²x² + αy²y² > 0 and z = cosθ > 0
/// (tangential components, exact as α → 0; any common scale of the
/// direction cancels), for sums with 1 ([`scaled_lambda_in_sum`]). Where
/// the polynomial applies, a² = z²/q and x = √q/z come from two
/// independent divisions, so the exp does not wait for the square root:
/// Λ ends a sample's dependency chain.
#[inline]
pub(super) fn lambda_qz(q: f64, z: f64) -> f64 {
    let s = libm::sqrt(q);
    // z ≥ 1e−100 (z² stays normal) and, past the caller's negligible-Λ
    // test, q > z²/4.7²: neither quotient overflows or underflows.
    if s <= LAMBDA_POLY_MAX_X * z && z > 0.0 {
        return exp(-(z * z / q)) * scaled_lambda_in_sum(s / z);
    }
    lambda(q / (z * z))
}

/// From a = 1/(α tanθ) = 4.7 on, Λ < 3.26·10⁻¹³ (mpmath) is taken as 0
/// (see [`super::Distribution::lambda_frac`]): Λ enters only sums with 1,
/// so G1 = 1/(1 + Λ) moves by less than 3.3·10⁻¹³ and G2 by less than
/// 6.6·10⁻¹³ relative, and from a = 5.8 on (Λ < 1.8·10⁻¹⁸) by no bit. The
/// cut saves an exp and a polynomial per Λ for a quarter to a third of a
/// plate's directions (α 0.2 seen at 40°–47°).
pub(super) const LAMBDA_NEGLIGIBLE_A: f64 = 4.7;

/// Upper end of the polynomial's range in x = 1/a (a ≥ 1.25).
const LAMBDA_POLY_MAX_X: f64 = 0.8;

/// Λ(a) e^{a²} = (1/(a√π) − erfcx a)/2 for x = 1/a ∈ [0, 0.8], as x³ H(x).
#[inline]
fn scaled_lambda(x: f64) -> f64 {
    x * x * x * estrin(&LAMBDA_POLY, x * (2.0 / LAMBDA_POLY_MAX_X) - 1.0)
}

/// Upper end of [`LAMBDA_POLY_NEAR`]'s range in x = 1/a (a ≥ 3.33).
const LAMBDA_NEAR_MAX_X: f64 = 0.3;

/// [`scaled_lambda`] for a Λ that only enters sums with 1: the conductor's
/// G1 = 1/(1 + Λ) and G2 = 1/(1 + Λi + Λo), the slope CDF's total
/// cotθ (1 + Λ) and mass 1 − erfc(cotθ)/2. For x ≤ 0.3, where
/// Λ < 5·10⁻⁸, the degree-12 [`LAMBDA_POLY_NEAR`] instead of the
/// degree-28 polynomial: Λ to 2.2·10⁻¹⁹ absolute, a five-hundredth of an
/// ulp of those sums (`near_polynomial_is_lambda_beside_one`).
#[inline]
fn scaled_lambda_in_sum(x: f64) -> f64 {
    if x <= LAMBDA_NEAR_MAX_X {
        return x * x * x * estrin(&LAMBDA_POLY_NEAR, x * (2.0 / LAMBDA_NEAR_MAX_X) - 1.0);
    }
    scaled_lambda(x)
}

/// H(x) on [0, 0.3] in powers of τ = 2x/0.3 − 1: Chebyshev interpolation
/// of degree 12 in 50-digit arithmetic by
/// `scripts/beckmann_lambda_poly.py near`. Its relative error (5.7·10⁻¹²)
/// is far above [`LAMBDA_POLY`]'s, which is why only sums with 1 use it
/// (see [`scaled_lambda_in_sum`]); H is not analytic at x = 0, so the
/// degree falls slowly with the range.
#[rustfmt::skip]
static LAMBDA_POLY_NEAR: [f64; 13] = [
    0.13653563306416083,
    -0.008561314954780113,
    -0.0034200678860009767,
    0.0007438605258193373,
    5.9709613997901364e-05,
    -5.214926274189423e-05,
    6.0034981523301636e-06,
    2.5009125718764555e-06,
    -1.0525768479235643e-06,
    3.6179020220080146e-08,
    8.7258564150326e-08,
    -1.8988211826521815e-08,
    -2.6726131991979985e-09,
];

/// H(x) = Λ(a) e^{a²} a³, x = 1/a, in powers of τ = 2x/0.8 − 1 ∈ [−1, 1]:
/// Chebyshev interpolation of degree 28 at the Chebyshev points, computed
/// in 50-digit arithmetic (mpmath), converted to powers of τ, by
/// `scripts/beckmann_lambda_poly.py`. Largest
/// relative error, evaluated in f64 with [`estrin`], 1.3·10⁻¹⁵ over the
/// range (`lambda_polynomial_matches_high_precision_values`). H → 1/(4√π)
/// as x → 0; the erfc asymptotic series diverges there, which is why the
/// high coefficients decay slowly.
#[rustfmt::skip]
static LAMBDA_POLY: [f64; 29] = [
    0.11616772935905417,
    -0.037507356478600935,
    -0.0015601406501020915,
    0.007535348069090752,
    -0.003966228494363846,
    0.0007683531645973102,
    0.00045754216209269676,
    -0.0005284971251748197,
    0.0002702884782423687,
    -5.831603303118069e-05,
    -3.4525289828697614e-05,
    4.746163384186838e-05,
    -2.9930523443346776e-05,
    1.0751508735307965e-05,
    4.651193968010865e-07,
    -4.265134939070862e-06,
    4.022675325005617e-06,
    -2.2502178379877568e-06,
    4.0092154061414155e-07,
    3.5324770556564823e-07,
    -3.6683742496535256e-08,
    1.4178677125823401e-08,
    -5.376212085736731e-07,
    4.7420800605569827e-07,
    1.352487715058823e-07,
    -3.014770850994431e-07,
    5.603091740884268e-08,
    5.5161883504094235e-08,
    -2.01398442055637e-08,
];

/// Σ c_i τ^i by Estrin's scheme: the same terms as Horner's rule in a tree
/// of depth ⌈log₂ n⌉ instead of a chain of n, which matters here because a
/// sample's arithmetic is one long dependency chain.
#[inline(always)]
fn estrin<const N: usize>(c: &[f64; N], tau: f64) -> f64 {
    let mut buf = [0.0f64; 32];
    buf[..N].copy_from_slice(c);
    let mut n = N;
    let mut p = tau;
    while n > 1 {
        let half = n.div_ceil(2);
        for j in 0..half {
            let hi = if 2 * j + 1 < n { buf[2 * j + 1] } else { 0.0 };
            buf[j] = buf[2 * j] + hi * p;
        }
        n = half;
        p *= p;
    }
    buf[0]
}

/// Visible-normal sampling: stretch to unit roughness, draw the slope along
/// the view azimuth from its visible marginal by inverting its CDF, draw the
/// orthogonal slope from the (independent) Gaussian marginal, unstretch.
pub(super) fn sample_visible(wi: DVec3, ax: f64, ay: f64, u: [f64; 2]) -> DVec3 {
    super::normalize_or_none(sample_visible_with_lambda(wi, ax, ay, u).0).unwrap_or(DVec3::Z)
}

/// [`sample_visible`] up to a positive factor (h.z = 1: the unstretched
/// normal (−s, 1) of the sampled slopes s), Smith Λ(wi), which the
/// inversion computes on the way (its normalisation is cotθ (1 + Λ) in the
/// stretched frame), and e^{−|s|²} of the stretched slopes, D's exponential:
/// the sampler's caller needs G1(wi) and D(h), would otherwise evaluate both
/// again, and works with an unnormalised h, as for GGX. With h.z = 1,
/// D(h/|h|) = e^{−|s|²} |h|⁴ / (π αx αy).
/// Λ is 0 from a = cotθ ≥ [`LAMBDA_NEGLIGIBLE_A`] on, as in
/// [`super::Distribution::lambda_frac`].
pub(super) fn sample_visible_with_lambda(
    wi: DVec3,
    ax: f64,
    ay: f64,
    u: [f64; 2],
) -> (DVec3, f64, f64) {
    // The stretched view (αx x, αy y, z), left unnormalised: the inversion
    // needs only its azimuth and cotθ, ratios of its components, so one
    // square root and one division give both (normalising first put two
    // more of each on the sample's critical path).
    let (vx, vy, vz) = (ax * wi.x, ay * wi.y, wi.z);
    let r2 = vx * vx + vy * vy;
    let (rx, ry, lambda, s2) = if r2 > 0.0 && r2 >= 1e-14 * (r2 + vz * vz) {
        let r = libm::sqrt(r2);
        let inv_r = 1.0 / r;
        // tanθ = r/vz alongside cotθ = vz/r, not as 1/cotθ: two divisions
        // side by side instead of one after the other on the chain.
        let tan = r / vz;
        let (cos_phi, sin_phi) = (vx * inv_r, vy * inv_r);
        let (sx, sy, lambda) = sample_slopes_unit(vz * inv_r, tan, vz, r2 * inv_r, u);
        // Rotate back to the view azimuth.
        (
            cos_phi * sx - sin_phi * sy,
            sin_phi * sx + cos_phi * sy,
            lambda,
            sx * sx + sy * sy,
        )
    } else {
        // sinθ < 1e−7 (or a NaN or zero view): the normal view, whose visible slope
        // density is the isotropic Gaussian; the azimuth plays no part.
        let r2 = -libm::log1p(-u[0]);
        let r = libm::sqrt(r2);
        let (sp, cp) = libm::sincos(2.0 * PI * u[1]);
        (r * cp, r * sp, 0.0, r2)
    };
    // Unstretch; the normal is (−s, 1).
    (DVec3::new(-rx * ax, -ry * ay, 1.0), lambda, exp(-s2))
}

/// Slopes of the visible normals of a unit-roughness Beckmann surface, for a
/// view along +x at cotθ = `cot` (= `c`/`s`, with `c`, `s` any positive
/// multiple of cosθ, sinθ; `tan` = 1/cotθ), and Λ at that view. The x-slope
/// density is ∝ (cotθ − x) e^{−x²} on x < cotθ, with CDF
/// C(x) = [cotθ (1 + erf x) + e^{−x²}/√π] / 2; y is Gaussian with variance ½.
fn sample_slopes_unit(cot: f64, tan: f64, c: f64, s: f64, u: [f64; 2]) -> (f64, f64, f64) {
    // Per-axis slope variance ½ at unit roughness: a standard normal / √2.
    let sy = normal_quantile(u[1]) * FRAC_1_SQRT_2;
    // Start from the cotθ → ∞ limit, moved by the tabulated difference
    // between it and the root: within 1e−4 of the root for nine draws in
    // ten, so one Halley step usually finishes (from the limit alone it
    // takes four to five, each an erfc and an exp).
    let st = gaussian_start_and_target(cot, tan, u[0]);
    let start = st.start + start_correction(c, s, u[0]);
    (solve_slope(cot, st.target, start, true), sy, st.lambda)
}

/// From cotθ = 4.7 on the start and target take the Gaussian limit: the
/// target's total cotθ (1 + Λ) drops the Λ that [`LAMBDA_NEGLIGIBLE_A`]
/// drops from G1 (so the sampled density and the stated pdf agree, both
/// within 3.3·10⁻¹³ of the exact ones), and the start's mass
/// 1 − erfc(cotθ)/2 drops erfc(4.7)/2 = 1.5·10⁻¹¹ (a start only has to be
/// near the root). From cotθ = 6 on both are the exact values to the bit.
const GAUSSIAN_LIMIT_COT: f64 = LAMBDA_NEGLIGIBLE_A;

/// What the slope inversion needs at one view, and Λ at it.
struct StartAndTarget {
    /// The exact inverse at `u` of the cotθ → ∞ limit (the Gaussian CDF
    /// rescaled to the mass below cotθ).
    start: f64,
    /// u·C(cotθ), the value of C the root must reach.
    target: f64,
    /// Smith Λ at a = cotθ (0 from [`LAMBDA_NEGLIGIBLE_A`] on).
    lambda: f64,
}

/// The start, target and Λ of one inversion: one erfc, 1 + erf(cotθ),
/// serves all three.
///
/// From cotθ ≥ 1.25 on, C(cotθ) = cotθ (1 + Λ) and
/// erfc(cotθ) = e^{−cot²θ} (x/√π − 2x³H(x)) with x = tanθ (see [`lambda`]):
/// one exp and the polynomial instead of erfc's two exps and another, and
/// Λ = e^{−cot²θ} x³H(x) is [`lambda`]'s own expression. Below 1.25,
/// Λ = (e^{−cot²θ}/(cotθ √π) − (2 − (1 + erf cotθ)))/2: the same difference
/// as [`lambda`]'s, with erfc(cotθ) taken from 1 + erf, whose rounding
/// (2·10⁻¹⁶ absolute) is below 2.5·10⁻¹⁴ of Λ there (Λ ≥ 0.0087).
#[inline]
fn gaussian_start_and_target(cot: f64, tan: f64, u: f64) -> StartAndTarget {
    if cot >= GAUSSIAN_LIMIT_COT {
        // erfc(cotθ) < 3·10⁻¹¹ beside 2 and Λ < 3.3·10⁻¹³ beside 1 (from
        // cotθ = 6 on below half an ulp: the branch below to the last bit);
        // its exp and polynomial are skipped.
        return StartAndTarget {
            start: normal_quantile(u) * FRAC_1_SQRT_2,
            target: u * cot,
            lambda: 0.0,
        };
    }
    if cot >= 1.0 / LAMBDA_POLY_MAX_X {
        return polynomial_start_and_target(cot, tan, u);
    }
    let one_plus_erf = libm::erfc(-cot);
    let e = exp(-cot * cot) / SQRT_PI;
    let total = 0.5 * (cot * one_plus_erf + e);
    StartAndTarget {
        start: normal_quantile(0.5 * u * one_plus_erf) * FRAC_1_SQRT_2,
        target: u * total,
        lambda: (0.5 * (e / cot - (2.0 - one_plus_erf))).max(0.0),
    }
}

/// [`gaussian_start_and_target`] for cotθ ≥ 1.25 (see there); `x` = tanθ.
#[inline]
fn polynomial_start_and_target(cot: f64, x: f64, u: f64) -> StartAndTarget {
    let e = exp(-cot * cot);
    let s = scaled_lambda_in_sum(x);
    let lambda = e * s;
    let erfc = e * (x / SQRT_PI - 2.0 * s);
    StartAndTarget {
        start: normal_quantile(u * (1.0 - 0.5 * erfc)) * FRAC_1_SQRT_2,
        target: u * (cot * (1.0 + lambda)),
        lambda: if cot >= LAMBDA_NEGLIGIBLE_A {
            0.0
        } else {
            lambda
        },
    }
}

/// The root of C(x) = `target` on (−8, cotθ] (C(x) < 1e−30 below −8 for
/// every cotθ) by safeguarded Halley iteration from `start`.
///
/// Halley's error after a step δ is of order δ³ (C″/2C′)², and C″/C′ =
/// −1/(cotθ − x) − 2x: with ℓ = min(cotθ − x, 1/(1 + |x|)) the local scale,
/// a Halley step below 1e−4 ℓ leaves an error below ~1e−12 ℓ, so with
/// `early` it is accepted without the evaluation that would confirm it.
/// Otherwise the iteration stops when a step or the bracket falls below
/// 1e−11 relative (slopes to 1e−11 are far below any visible or statistical
/// effect; asking for more makes the step chase round-off in C(x) − target).
fn solve_slope(cot: f64, target: f64, start: f64, early: bool) -> f64 {
    let mut lo = (-8.0f64).min(cot - 1.0);
    let mut hi = cot;
    let mut x = start;
    if !(x > lo && x < hi) {
        // A start below the bracket (u so small that the root lies below
        // C's 1e−30 floor at −8, where the Gaussian quantile goes on to
        // −26) starts at its end, which is then the answer; others, and NaN,
        // at the midpoint.
        x = if x <= lo { lo } else { 0.5 * (lo + hi) };
    }
    for _ in 0..40 {
        let e = exp(-x * x) / SQRT_PI;
        let f = 0.5 * (cot * libm::erfc(-x) + e) - target;
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        // Halley's step (cubic convergence; C″ = −(1 + 2x(cotθ − x)) e^{−x²}/√π
        // comes free with C′).
        let dens = (cot - x) * e;
        let curv = -(1.0 + 2.0 * x * (cot - x)) * e;
        let denom = 2.0 * dens * dens - f * curv;
        let mut next = if dens > 0.0 && denom > 0.0 {
            x - 2.0 * f * dens / denom
        } else {
            f64::NAN
        };
        // A step of zero (the start already at the root to round-off) is a
        // valid Halley step: the bracket has just closed on x, so it must be
        // accepted, not replaced by the midpoint of a possibly wide bracket.
        let halley = next >= lo && next <= hi;
        if !halley {
            next = 0.5 * (lo + hi);
        }
        let step = (next - x).abs();
        x = next;
        if early && halley && step <= 1e-4 * (cot - x).min(1.0 / (1.0 + x.abs())) {
            break;
        }
        if step <= 1e-11 * (1.0 + x.abs()) || hi - lo <= 1e-12 * (1.0 + x.abs()) {
            break;
        }
    }
    x
}

/// Nodes per axis of [`START`]: t = sinθ/(sinθ + cosθ) (close to linear in
/// θ, without an atan2) and v = √(1 − u) (the root approaches cotθ as
/// √(1 − u), the Gaussian start linearly, so their difference is smooth in v).
const START_N: usize = 65;

/// Root of the slope CDF minus the Gaussian-limit start, at node (t, v) of
/// the grid (row-major in t), as f32: it only has to start the iteration.
/// Written by `write_start_table` (an ignored test) from [`solve_slope`];
/// `start_table_matches_the_solver` checks every entry against it.
static START: [f32; START_N * START_N] = include!("beckmann_start.in");

/// Bilinear interpolation in [`START`].
#[inline]
fn start_correction(c: f64, s: f64, u: f64) -> f64 {
    let last = (START_N - 1) as f64;
    let ft = (s / (s + c)).clamp(0.0, 1.0) * last;
    let fv = libm::sqrt((1.0 - u).clamp(0.0, 1.0)) * last;
    // Through u32 (both lie in [0, 64]): shorter than f64 → usize.
    let (it, iv) = (
        (ft as u32 as usize).min(START_N - 2),
        (fv as u32 as usize).min(START_N - 2),
    );
    let (at, av) = (ft - it as f64, fv - iv as f64);
    let row = |i: usize| {
        let (a, b) = (
            START[i * START_N + iv] as f64,
            START[i * START_N + iv + 1] as f64,
        );
        a + av * (b - a)
    };
    let (r0, r1) = (row(it), row(it + 1));
    let r = r0 + at * (r1 - r0);
    if r.is_finite() { r } else { 0.0 }
}

/// The exact value behind `START[i · START_N + j]`.
#[cfg(test)]
fn start_table_entry(i: usize, j: usize) -> f64 {
    let last = (START_N - 1) as f64;
    let t = (i as f64 / last).clamp(1e-9, 1.0 - 1e-12);
    let h = libm::sqrt(t * t + (1.0 - t) * (1.0 - t));
    let (c, s) = ((1.0 - t) / h, t / h);
    let v = j as f64 / last;
    let u = (1.0 - v * v).clamp(1e-12, 1.0);
    if j == 0 {
        // u = 1: root and start are both cotθ.
        return 0.0;
    }
    let cot = c / s;
    let st = gaussian_start_and_target(cot, s / c, u);
    solve_slope(cot, st.target, st.start, false) - st.start
}

/// The standard normal quantile Φ⁻¹(p) for p in (0, 1), to about 1e−16
/// relative: Wichura's rational approximations (Algorithm AS 241, Applied
/// Statistics 37(3), 1988), with no transcendental call for
/// |p − ½| ≤ 0.425 (85 % of uniform draws) and one log and one square root
/// in the tails. p = 0 and 1 (which [0, 1) samplers can return) are read as
/// the smallest normal double and its complement: finite, ±37.5.
fn normal_quantile(p: f64) -> f64 {
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180625 - q * q;
        return q * estrin(&AS241_A, r) / estrin(&AS241_B, r);
    }
    let tail = if q < 0.0 { p } else { 1.0 - p }.max(f64::MIN_POSITIVE);
    let r = libm::sqrt(-libm::log(tail));
    let x = if r <= 5.0 {
        let r = r - 1.6;
        estrin(&AS241_C, r) / estrin(&AS241_D, r)
    } else {
        let r = r - 5.0;
        estrin(&AS241_E, r) / estrin(&AS241_F, r)
    };
    if q < 0.0 { -x } else { x }
}

// AS 241's coefficients (PPND16), lowest power first.
#[allow(clippy::excessive_precision)]
const AS241_A: [f64; 8] = [
    3.3871328727963666080e0,
    1.3314166789178437745e+2,
    1.9715909503065514427e+3,
    1.3731693765509461125e+4,
    4.5921953931549871457e+4,
    6.7265770927008700853e+4,
    3.3430575583588128105e+4,
    2.5090809287301226727e+3,
];
#[allow(clippy::excessive_precision)]
const AS241_B: [f64; 8] = [
    1.0,
    4.2313330701600911252e+1,
    6.8718700749205790830e+2,
    5.3941960214247511077e+3,
    2.1213794301586595867e+4,
    3.9307895800092710610e+4,
    2.8729085735721942674e+4,
    5.2264952788528545610e+3,
];
#[allow(clippy::excessive_precision)]
const AS241_C: [f64; 8] = [
    1.42343711074968357734e0,
    4.63033784615654529590e0,
    5.76949722146069140550e0,
    3.64784832476320460504e0,
    1.27045825245236838258e0,
    2.41780725177450611770e-1,
    2.27238449892691845833e-2,
    7.74545014278341407640e-4,
];
#[allow(clippy::excessive_precision)]
const AS241_D: [f64; 8] = [
    1.0,
    2.05319162663775882187e0,
    1.67638483018380384940e0,
    6.89767334985100004550e-1,
    1.48103976427480074590e-1,
    1.51986665636164571966e-2,
    5.47593808499534494600e-4,
    1.05075007164441684324e-9,
];
#[allow(clippy::excessive_precision)]
const AS241_E: [f64; 8] = [
    6.65790464350110377720e0,
    5.46378491116411436990e0,
    1.78482653991729133580e0,
    2.96560571828504891230e-1,
    2.65321895265761230930e-2,
    1.24266094738807843860e-3,
    2.71155556874348757815e-5,
    2.01033439929228813265e-7,
];
#[allow(clippy::excessive_precision)]
const AS241_F: [f64; 8] = [
    1.0,
    5.99832206555887937690e-1,
    1.36929880922735805310e-1,
    1.48753612908506148525e-2,
    7.86869131145613259100e-4,
    1.84631831751005468180e-5,
    1.42151175831644588870e-7,
    2.04426310338993978564e-15,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Regenerates `beckmann_start.in`:
    /// `cargo test -p brdf --lib write_start_table -- --ignored`.
    #[test]
    #[ignore]
    fn write_start_table() {
        extern crate std;
        use std::fmt::Write;
        let mut out = std::string::String::from(
            "// Written by `write_start_table` in beckmann.rs; do not edit.\n[\n",
        );
        for i in 0..START_N {
            for j in 0..START_N {
                write!(out, "{:e}_f32,", start_table_entry(i, j) as f32).unwrap();
                out.push(if j % 8 == 7 || j + 1 == START_N {
                    '\n'
                } else {
                    ' '
                });
            }
        }
        out.push_str("]\n");
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/src/microfacet/beckmann_start.in"
        );
        std::fs::write(path, out).unwrap();
    }

    #[test]
    fn start_table_matches_the_solver() {
        for i in 0..START_N {
            for j in 0..START_N {
                let want = start_table_entry(i, j);
                let got = START[i * START_N + j] as f64;
                assert!(
                    (got - want).abs() <= 1e-6 * (1.0 + want.abs()),
                    "({i}, {j}): {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn early_stop_finds_the_root_over_the_domain() {
        // Every incidence from normal to grazing and every u, the tails
        // included: the accepted slope agrees with the fully converged root.
        for a in 0..=160 {
            // (Below sinθ = 1e−7 the normal-view branch draws without inversion.)
            let theta = core::f64::consts::FRAC_PI_2 * (a as f64 / 160.0).clamp(1e-6, 1.0 - 1e-12);
            let (s, c) = libm::sincos(theta);
            for b in 0..=400 {
                let u0 = match b {
                    0 => 1e-300,
                    400 => 1.0 - 1e-16,
                    _ => b as f64 / 400.0,
                };
                for u0 in [u0, u0 * 1e-6, 1.0 - (1.0 - u0) * 1e-6] {
                    let cot = c / s;
                    let (x, _, _) = sample_slopes_unit(cot, s / c, c, s, [u0, 0.5]);
                    // Bisection to adjacent floats: independent of Halley.
                    let cdf = |x: f64| 0.5 * (cot * libm::erfc(-x) + exp(-x * x) / SQRT_PI);
                    // The stated density's total: from the cut on, G1 = 1
                    // and the total is cotθ (Λ < 3.3e−13 dropped).
                    let total = if cot >= LAMBDA_NEGLIGIBLE_A {
                        cot
                    } else {
                        cdf(cot)
                    };
                    let (mut lo, mut hi) = ((-8.0f64).min(cot - 1.0), cot);
                    for _ in 0..2000 {
                        let mid = 0.5 * (lo + hi);
                        if mid <= lo || mid >= hi {
                            break;
                        }
                        if cdf(mid) > u0 * total {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    let exact = 0.5 * (lo + hi);
                    if exact <= -8.0 + 1e-6 {
                        // Below C(−8) < 1e−30 both stop at the bracket's end.
                        assert!(x <= -7.999);
                        continue;
                    }
                    // C is a sum of order `total`, so its round-off limits
                    // any root to ~ε·total/C′ (both solvers share that floor).
                    let dens = (cot - exact) * exp(-exact * exact) / SQRT_PI;
                    let floor = 8.0 * f64::EPSILON * total.max(1.0) / dens;
                    let err = (x - exact).abs() / (1e-10 * (1.0 + exact.abs()) + floor);
                    assert!(err <= 1.0, "θ {theta} u {u0}: {x} vs {exact}");
                }
            }
        }
    }

    #[test]
    fn normal_quantile_inverts_the_normal_cdf() {
        // Φ(x) = erfc(−x/√2)/2, in the lower tail without cancellation; the
        // upper tail by symmetry, Φ⁻¹(1 − p) = −Φ⁻¹(p), checked exactly where
        // 1 − p is representable.
        let phi = |x: f64| 0.5 * libm::erfc(-x * FRAC_1_SQRT_2);
        let mut worst = 0.0f64;
        let mut check = |p: f64| {
            let x = normal_quantile(p);
            assert!(x.is_finite(), "p={p}: {x}");
            // Relative error in x from the residual of Φ: δx = (Φ(x) − p)/φ(x).
            let density = (-0.5 * x * x).exp() / (2.0 * PI).sqrt();
            let rel = ((phi(x) - p) / density).abs() / x.abs().max(1e-300);
            worst = worst.max(rel);
            assert!(rel < 5e-15, "p={p}: x={x}, relative error {rel:e}");
        };
        for i in 1..100_000 {
            check(i as f64 / 100_000.0);
        }
        // Both boundaries of the central region and the tail approximation.
        for p in [0.075, 0.075 + 1e-12, 0.925, 0.925 - 1e-12] {
            check(p);
        }
        for k in 0..=3000 {
            // p from 1e−2 down to 1e−300: all three branches of the tail.
            let p = 10f64.powf(-2.0 - k as f64 * 0.0993333);
            check(p);
        }
        assert!(worst > 0.0, "the check measured nothing");
        // Dyadic p: 1 − p and p − ½ are exact, so the branches see mirrored
        // input and the symmetry holds to the bit.
        for i in 1..=(1 << 19) {
            let p = i as f64 / (1u64 << 20) as f64;
            assert_eq!(normal_quantile(1.0 - p), -normal_quantile(p), "p={p}");
        }
        // The sampler's domain includes 0 (Sobol and the uniform generators
        // return [0, 1)): finite, and on the correct side.
        for (p, sign) in [(0.0, -1.0), (1.0, 1.0), (f64::NAN, 1.0)] {
            let x = normal_quantile(p);
            assert!(x.is_finite() && x * sign > 37.0, "p={p}: {x}");
        }
        assert_eq!(normal_quantile(0.5), 0.0);
    }

    /// Λ(a) from the difference of libm's terms (no polynomial).
    fn lambda_by_erfc(a: f64) -> f64 {
        0.5 * (exp(-a * a) / (a * SQRT_PI) - libm::erfc(a))
    }

    #[test]
    // The reference values are quoted to the digits mpmath gave.
    #[allow(clippy::excessive_precision)]
    fn lambda_polynomial_matches_high_precision_values() {
        // Λ(a) = (e^{−a²}/(a√π) − erfc a)/2 in 40-digit arithmetic (mpmath),
        // from the polynomial's edge to where e^{−a²} nearly underflows.
        let want = [
            (1.25, 0.008_754_288_617_687_272_512_3),
            (1.3, 0.007_043_969_931_108_848_747_9),
            (1.7, 0.001_117_441_133_162_044_571_3),
            (2.2, 8.245_810_838_589_569_773_7e-5),
            (3.0, 5.591_724_962_696_004_711_5e-7),
            (4.0, 2.277_677_197_765_894_916_4e-10),
            (5.0, 1.481_342_933_684_934_031_8e-14),
            (5.8, 1.702_041_420_125_301_240_7e-18),
            (7.0, 2.093_110_968_281_757_212_6e-25),
            (10.0, 5.170_265_957_331_844_021_4e-48),
            (20.0, 3.364_037_179_547_611_794_5e-179),
            (26.0, 2.091_289_097_187_750_035_1e-299),
        ];
        for (a, w) in want {
            let got = lambda(1.0 / (a * a));
            // 4e−15: the polynomial's 1.3e−15, e^{−a²}'s argument rounding
            // (a² ulp-exact only to 2e−16 a², 1.4e−13 at a = 26 — hence
            // relative to the rounded t, which is what the caller holds).
            let t = 1.0 / (a * a);
            let exact_at_t = w * libm::exp(-(1.0 / t) + a * a);
            assert!(
                (got - exact_at_t).abs() <= 4e-15 * exact_at_t,
                "a = {a}: {got:e} vs {exact_at_t:e}"
            );
        }
        // Against the erfc difference where it loses little, densely, and
        // across the switch at 1.25: its terms agree to 1/(2a²), so its own
        // error is ~2a² ulps of erfc (up to ~1e−14 at a = 3).
        let mut worst: f64 = 0.0;
        for i in 0..=20_000 {
            let a = 1.0 + 2.0 * i as f64 / 20_000.0;
            let t = 1.0 / (a * a);
            let (got, reference) = (lambda(t), lambda_by_erfc(1.0 / libm::sqrt(t)));
            worst = worst.max((got - reference).abs() / reference);
        }
        assert!(worst < 5e-14, "worst relative difference {worst:e}");
        // Monotone decreasing in a through the switch and the whole range.
        let mut last = f64::INFINITY;
        for i in 0..=100_000 {
            let a = 0.5 + 30.0 * i as f64 / 100_000.0;
            let l = lambda(1.0 / (a * a));
            assert!(l <= last && l >= 0.0, "a = {a}");
            last = l;
        }
    }

    #[test]
    fn near_polynomial_is_lambda_beside_one() {
        // Λ = e^{−a²} x³ H(x) from the degree-12 polynomial against the
        // degree-28 one (1.3e−15 relative, so its own absolute error here is
        // below 1e−22), densely over x ∈ (0, 0.3] (a ≥ 3.33), and against
        // 40-digit values: within 2.5e−19 absolute, a few hundredths of an ulp
        // of the sums 1 + Λ it enters.
        let mut worst = 0.0f64;
        for i in 1..=30_000 {
            let x = LAMBDA_NEAR_MAX_X * i as f64 / 30_000.0;
            let e = exp(-1.0 / (x * x));
            let (near, full) = (e * scaled_lambda_in_sum(x), e * scaled_lambda(x));
            let err = (near - full).abs();
            worst = worst.max(err);
            assert!(err <= 2.5e-19, "x {x}: {near:e} vs {full:e}");
        }
        // mpmath's Λ(a) at a = 4 and 5 (`lambda_polynomial_matches_...`).
        #[allow(clippy::excessive_precision)]
        for (a, w) in [
            (4.0, 2.277_677_197_765_894_916_4e-10),
            (5.0, 1.481_342_933_684_934_031_8e-14),
        ] {
            let got = exp(-a * a) * scaled_lambda_in_sum(1.0 / a);
            assert!((got - w).abs() <= 2.5e-19 + 1e-14 * w, "a {a}: {got:e}");
        }
        assert!(
            worst > 1e-21,
            "the two polynomials agree to {worst:e}: same one?"
        );
    }

    #[test]
    fn lambda_from_q_and_z_is_lambda_from_t() {
        // a = z/√q from 0.01 to 6 (both sides of the polynomial's end at
        // 1.25), cosθ from 1e−100 to 1: the one-division form against t's.
        let mut worst = 0.0f64;
        for i in 0..=3000 {
            let a =
                libm::exp(libm::log(0.01) + (libm::log(6.0) - libm::log(0.01)) * i as f64 / 3000.0);
            for z in [1e-100, 1e-30, 1e-8, 1e-3, 0.2, 0.7, 1.0] {
                let q = (z / a) * (z / a);
                let (got, want) = (lambda_qz(q, z), lambda(q / (z * z)));
                assert!(got.is_finite() && got >= 0.0, "a {a} z {z}: {got}");
                // e^{−a²} turns the argument's round-off (a few ulps of a²
                // in either form) into a² times that, relative; from
                // a = 3.33 on the near polynomial's 2.2e−19 absolute.
                let rel = (got - want).abs() / want;
                worst = worst.max(rel);
                let tol = 1e-14 + 1e-15 * a * a + 2.5e-19 / want;
                assert!(rel < tol, "a {a} z {z}: {got} against {want}");
            }
        }
        assert!(
            worst > 0.0,
            "the two forms never differ: the test compares a form with itself"
        );
    }

    #[test]
    fn d_on_the_unnormalised_half_vector_is_d() {
        // The fraction on v = wi + wo (any scale) against D(v/|v|), over
        // half vectors from the normal to 1e−9 rad of the horizon, α from
        // 1e−4 to 1 and anisotropic; where D underflows the fraction must
        // give 0 (or 0/0, which the callers read as 0).
        use crate::microfacet::Distribution;
        let mut compared = 0;
        for (ax, ay) in [
            (1e-4, 1e-4),
            (0.05, 0.05),
            (0.3, 0.1),
            (1.0, 1.0),
            (0.01, 0.9),
        ] {
            let dist = Distribution::beckmann(ax, ay).unwrap();
            for i in 0..=500 {
                let theta = core::f64::consts::FRAC_PI_2 * (i as f64 / 500.0) * (1.0 - 1e-9);
                for phi in [0.0, 0.7, 2.2, 4.5] {
                    for scale in [1e-3, 1.0, 1.9] {
                        let (st, ct) = libm::sincos(theta);
                        let h = DVec3::new(st * libm::cos(phi), st * libm::sin(phi), ct);
                        let v = h * scale;
                        let want = d(h, ax, ay);
                        let (num, den) = dist.beckmann_d_fraction(v, v.length_squared());
                        let got = num / den;
                        if want == 0.0 {
                            assert!(num == 0.0, "α ({ax}, {ay}) θ {theta}: {num}/{den}");
                            continue;
                        }
                        compared += 1;
                        // e^{−e} amplifies the exponent's round-off (a few
                        // ulps in either form) by e.
                        let e = (st / ct) * (st / ct) / (ax * ax).min(ay * ay);
                        let rel = (got - want).abs() / want;
                        let tol = 1e-14 + 1e-15 * e;
                        assert!(
                            rel < tol,
                            "α ({ax}, {ay}) θ {theta} φ {phi}: {got} against {want}"
                        );
                    }
                }
            }
        }
        assert!(compared > 10_000, "{compared}");
    }

    #[test]
    fn the_samplers_lambda_is_smiths_lambda() {
        // Λ(wi) returned with the sample against `lambda` from t = α² tan²θ,
        // over views from the normal to 1e−9 of the horizon, anisotropic
        // roughness, both branches (a = cotθ of the stretched view ≷ 1.25)
        // and the cut at a = 4.7.
        let mut branches = [0usize; 3];
        for (ax, ay) in [
            (0.05, 0.05),
            (0.3, 0.1),
            (1.0, 1.0),
            (0.01, 0.9),
            (1e-4, 1e-4),
        ] {
            for i in 0..=400 {
                let theta =
                    core::f64::consts::FRAC_PI_2 * (i as f64 / 400.0).min(1.0 - 1e-9 / 1.57);
                for phi in [0.0, 0.4, 1.3, 2.9, 4.0] {
                    let (st, ct) = libm::sincos(theta);
                    let wi = DVec3::new(st * libm::cos(phi), st * libm::sin(phi), ct);
                    let t = (ax * ax * wi.x * wi.x + ay * ay * wi.y * wi.y) / (wi.z * wi.z);
                    let want = lambda(t);
                    let a = 1.0 / libm::sqrt(t);
                    branches[if a < 1.25 {
                        0
                    } else if a < LAMBDA_NEGLIGIBLE_A {
                        1
                    } else {
                        2
                    }] += 1;
                    for u in [[0.5, 0.5], [1e-9, 0.3], [0.999, 0.01]] {
                        let (h, got, _) = sample_visible_with_lambda(wi, ax, ay, u);
                        assert!(h.is_finite() && h.z > 0.0);
                        // Λ for sums with 1: the near polynomial's 2.2e−19.
                        let tol = if a >= LAMBDA_NEGLIGIBLE_A {
                            3.3e-13
                        } else {
                            3e-14 * want + 2.5e-19
                        };
                        assert!(
                            (got - want).abs() <= tol,
                            "α=({ax},{ay}) θ={theta} φ={phi}: {got:e} vs {want:e}"
                        );
                    }
                }
            }
        }
        assert!(branches.iter().all(|&n| n > 100), "{branches:?}");
    }

    #[test]
    fn the_gaussian_limit_is_the_polynomial_branch_from_the_cut() {
        // From cotθ = 6 on to the bit; between the cut (4.7) and 6 the
        // target within Λ(4.7) < 3.3e−13 and the start within what
        // erfc(4.7)/2 = 1.5e−11 of the mass moves it (Φ⁻¹'s slope
        // 1/φ grows towards u = 1, where both starts leave the bracket).
        let mut near = 0;
        for i in 0..=20000 {
            let cot = GAUSSIAN_LIMIT_COT * (1.0 + i as f64 / 1000.0);
            for j in 0..=64 {
                let u = (j as f64 / 64.0).clamp(1e-300, 1.0 - 1e-16);
                let (a, b) = (
                    gaussian_start_and_target(cot, 1.0 / cot, u),
                    polynomial_start_and_target(cot, 1.0 / cot, u),
                );
                assert_eq!(a.lambda, 0.0);
                if cot >= 6.0 {
                    assert_eq!(a.start.to_bits(), b.start.to_bits(), "{cot} {u}");
                    assert_eq!(a.target.to_bits(), b.target.to_bits(), "{cot} {u}");
                    assert!(b.lambda == 0.0, "{cot}: {}", b.lambda);
                    continue;
                }
                near += 1;
                assert!(
                    (a.target - b.target).abs() <= 3.3e-13 * b.target,
                    "{cot} {u}"
                );
                if u <= 1.0 - 1e-6 {
                    let p = u * (1.0 - 0.5 * libm::erfc(cot));
                    let z = normal_quantile(p);
                    let slope = 1.0 / ((-0.5 * z * z).exp() / (2.0 * PI).sqrt());
                    let tol = 1e-15 * (1.0 + z.abs()) + 2.0 * 1.5e-11 * p * slope;
                    assert!((a.start - b.start).abs() <= tol, "{cot} {u}");
                }
            }
        }
        assert!(near > 10_000, "{near}");
    }

    #[test]
    fn start_and_target_agree_with_their_erfc_forms() {
        // The polynomial branch of `gaussian_start_and_target` against the
        // erfc expressions it replaces, up to the Gaussian limit's cut
        // (beyond, `the_gaussian_limit_is_the_polynomial_branch_from_the_cut`).
        for i in 0..4000 {
            let cot = 1.25 + (GAUSSIAN_LIMIT_COT - 1.25) * i as f64 / 4000.0;
            for u in [1e-12, 0.03, 0.5, 0.97, 1.0 - 1e-12] {
                let StartAndTarget {
                    start: x0, target, ..
                } = gaussian_start_and_target(cot, 1.0 / cot, u);
                let one_plus_erf = libm::erfc(-cot);
                let total = 0.5 * (cot * one_plus_erf + exp(-cot * cot) / SQRT_PI);
                let rel = (target - u * total).abs() / (u * total);
                assert!(rel <= 1e-15, "{cot} {u}: {rel:e}");
                let x_ref = normal_quantile(0.5 * u * one_plus_erf) * FRAC_1_SQRT_2;
                assert!(
                    (x0 - x_ref).abs() <= 1e-12 * (1.0 + x_ref.abs()),
                    "{cot} {u}"
                );
            }
        }
    }
}
