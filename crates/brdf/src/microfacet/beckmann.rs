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
/// the view azimuth from its visible marginal (by rejection from a Gaussian),
/// draw the orthogonal slope from the (independent) Gaussian marginal,
/// unstretch.
pub(super) fn sample_visible(wi: DVec3, ax: f64, ay: f64, u: [f64; 2]) -> DVec3 {
    super::normalize_or_none(sample_visible_with_lambda(wi, ax, ay, u).0).unwrap_or(DVec3::Z)
}

/// [`sample_visible`] up to a positive factor (h.z = 1: the unstretched
/// normal (−s, 1) of the sampled slopes s), Smith Λ(wi) and e^{−|s|²} of the
/// stretched slopes, D's exponential: the sampler's caller needs G1(wi) and
/// D(h), and works with an unnormalised h, as for GGX. With h.z = 1,
/// D(h/|h|) = e^{−|s|²} |h|⁴ / (π αx αy). Λ is the one
/// [`super::Distribution::lambda_frac`] gives at `wi`, to the bit (0 from
/// a = cotθ ≥ [`LAMBDA_NEGLIGIBLE_A`] on), so the sample's pdf and NEE's
/// agree exactly.
pub(super) fn sample_visible_with_lambda(
    wi: DVec3,
    ax: f64,
    ay: f64,
    u: [f64; 2],
) -> (DVec3, f64, f64) {
    // The stretched view (αx x, αy y, z), left unnormalised: the sampler
    // needs only its azimuth and cotθ, ratios of its components.
    let (vx, vy, vz) = (ax * wi.x, ay * wi.y, wi.z);
    let r2 = vx * vx + vy * vy;
    let (rx, ry, lambda, s2) = if r2 > 0.0 && r2 >= 1e-14 * (r2 + vz * vz) {
        let r = libm::sqrt(r2);
        let inv_r = 1.0 / r;
        let (cos_phi, sin_phi) = (vx * inv_r, vy * inv_r);
        let (sx, sy) = sample_slopes_unit(vz * inv_r, u);
        // Rotate back to the view azimuth.
        (
            cos_phi * sx - sin_phi * sy,
            sin_phi * sx + cos_phi * sy,
            lambda_at_view(r2, vz),
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

/// Λ at a view with stretched tangential length² `q` = αx²x² + αy²y² and
/// normal component `z` > 0: the expressions of
/// [`super::Distribution::lambda_frac`], so the same bits.
#[inline]
fn lambda_at_view(q: f64, z: f64) -> f64 {
    const A2: f64 = LAMBDA_NEGLIGIBLE_A * LAMBDA_NEGLIGIBLE_A;
    if q * A2 <= z * z {
        return 0.0;
    }
    lambda_qz(q, z)
}

/// Proposals after which [`sample_slopes_unit`] gives up and keeps the
/// last one: each is accepted with probability ≥ 0.66, so all 64 are
/// rejected with probability < 10⁻³⁰.
const MAX_PROPOSALS: usize = 64;

/// Slopes (x, y) of the visible normals of a unit-roughness Beckmann
/// surface, for a view along +x at cotθ = `cot` > 0. y is Gaussian with
/// variance ½; x has the density p(x) ∝ (cotθ − x) e^{−x²} on x < cotθ.
///
/// x is drawn by rejection, exactly: for any k > 0 and t = k (cotθ − x),
/// log t ≤ t − 1 gives t ≤ e^{t−1} = e^{k cotθ − 1} e^{−kx}, so
/// p(x) ∝ t e^{−x²} ≤ const · e^{−(x + k/2)²}: propose x from the Gaussian
/// N(−k/2, ½) and accept it with probability t e^{1−t} (≤ 1; 0 for t ≤ 0).
/// k = √(cot²θ + 2) − cotθ, the tangent at the proposal's mean, maximises
/// the acceptance: 0.99 at cotθ = 5, 0.97 at 3, 0.86 at 1, 0.67 as
/// cotθ → 0. No erfc, no root finding: a normal quantile (which does not
/// wait for the view) and, mostly, a cubic instead of the exp.
fn sample_slopes_unit(cot: f64, u: [f64; 2]) -> (f64, f64) {
    // Per-axis slope variance ½ at unit roughness: a standard normal / √2.
    let sy = normal_quantile(u[1]) * FRAC_1_SQRT_2;
    (propose_until(cot, u[0], Draws::new(u), accept), sy)
}

/// The x slope of [`sample_slopes_unit`]: Gaussian proposals (the first
/// from `u0`, the rest from `more`) until `accepts(t, v)` takes one, or the
/// last of [`MAX_PROPOSALS`]. The tests pass a wrong acceptance to show the
/// chi-square test sees it.
#[inline(always)]
fn propose_until(cot: f64, u0: f64, mut more: Draws, accepts: impl Fn(f64, f64) -> bool) -> f64 {
    // √(cot² + 2) − cotθ without its cancellation at large cotθ.
    let k = 2.0 / (cot + libm::sqrt(cot * cot + 2.0));
    let mut z = normal_quantile(u0);
    let mut x = 0.0;
    for _ in 0..MAX_PROPOSALS {
        x = z * FRAC_1_SQRT_2 - 0.5 * k;
        if accepts(k * (cot - x), more.next()) {
            break;
        }
        z = normal_quantile(more.next());
    }
    x
}

/// Whether uniform `v` accepts a proposal at t: v < t e^{1−t}, for t > 0.
/// e^s ≥ 1 + s + s²/2 + s³/6 for every s (the remainder e^ξ s⁴/24 is
/// ≥ 0), so below t times that the answer is yes without the exp; the exp
/// decides only in the gap, under 7·10⁻⁵ wide for |1 − t| ≤ 0.2.
#[inline]
fn accept(t: f64, v: f64) -> bool {
    // t ≤ 0 (x ≥ cotθ, a back-facing normal) and NaN: never.
    if t.is_nan() || t <= 0.0 {
        return false;
    }
    let s = 1.0 - t;
    let lower = t * (1.0 + s * (1.0 + s * (0.5 + s * (1.0 / 6.0))));
    v < lower || v < t * exp(s)
}

/// Uniform numbers in [0, 1) for the rejection tests and the proposals
/// after a rejection: a splitmix64 sequence seeded with the bits of the
/// sample's two numbers. The sampler is given two numbers; each test needs
/// one independent of the proposal it tests, and a mixed hash of (u0, u1)
/// is (the first proposal comes from u0 alone, y from u1 alone).
struct Draws(u64);

impl Draws {
    #[inline]
    fn new(u: [f64; 2]) -> Draws {
        Draws(u[0].to_bits() ^ u[1].to_bits().rotate_left(32))
    }

    #[inline]
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
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
        // and the cut at a = 4.7; and to the bit `lambda_frac`'s, which the
        // pdf of NEE's evaluation takes.
        let mut branches = [0usize; 3];
        for (ax, ay) in [
            (0.05, 0.05),
            (0.3, 0.1),
            (1.0, 1.0),
            (0.01, 0.9),
            (1e-4, 1e-4),
        ] {
            let dist = crate::microfacet::Distribution::beckmann(ax, ay).unwrap();
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
                        assert_eq!(got.to_bits(), dist.lambda_frac(wi).0.to_bits());
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

    /// The visible x-slope CDF at unit roughness, C(x)/C(cotθ) with
    /// C(x) = [cotθ (1 + erf x) + e^{−x²}/√π]/2, from libm's erfc and exp.
    fn slope_cdf(cot: f64, x: f64) -> f64 {
        let c = |x: f64| 0.5 * (cot * libm::erfc(-x) + libm::exp(-x * x) / SQRT_PI);
        if x >= cot { 1.0 } else { c(x) / c(cot) }
    }

    /// Pearson's χ² of `draw`'s x slopes at `cot` over 64 cells of equal
    /// probability under [`slope_cdf`] (edges by bisection).
    fn slope_chi2(cot: f64, n: usize, draw: impl Fn(f64, [f64; 2]) -> f64) -> f64 {
        const CELLS: usize = 64;
        let mut edges = [0.0f64; CELLS - 1];
        for (i, e) in edges.iter_mut().enumerate() {
            let p = (i + 1) as f64 / CELLS as f64;
            let (mut lo, mut hi) = (-10.0f64, cot);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if slope_cdf(cot, mid) < p {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            *e = 0.5 * (lo + hi);
        }
        let mut counts = [0usize; CELLS];
        let mut rng = Draws(0x2545_F491_4F6C_DD1D ^ cot.to_bits());
        for _ in 0..n {
            let x = draw(cot, [rng.next(), rng.next()]);
            assert!(x.is_finite() && x < cot, "cot {cot}: {x}");
            counts[edges.partition_point(|&e| e <= x)] += 1;
        }
        let want = n as f64 / CELLS as f64;
        counts
            .iter()
            .map(|&c| (c as f64 - want).powi(2) / want)
            .sum()
    }

    /// χ² with 63 degrees of freedom: mean 63, standard deviation 11.2;
    /// 140 is exceeded with probability ~1e−8.
    const CHI2_63_LIMIT: f64 = 140.0;

    #[test]
    fn rejection_draws_the_visible_slope_density() {
        // From grazing (cotθ → 0, acceptance 0.67) to near the normal, the
        // plate's cotθ ≈ 5 included; a million draws each.
        for cot in [1e-3, 0.1, 0.5, 1.0, 2.5, 5.0, 12.0, 1e4] {
            let chi2 = slope_chi2(cot, 1_000_000, |c, u| sample_slopes_unit(c, u).0);
            extern crate std;
            std::println!("cot {cot}: χ² = {chi2:.1}");
            assert!(chi2 < CHI2_63_LIMIT, "cot {cot}: χ² = {chi2}");
        }
    }

    #[test]
    fn the_slope_chi_square_sees_a_wrong_acceptance() {
        // The test above must fail for a sampler that is wrong by a little:
        // acceptance t e^{1−t} replaced by t^1.1 e^{1.1(1−t)} (the density
        // times (t e^{1−t})^0.1, 1–10 % off in the tails) at cotθ = 1, and
        // by the proposal alone (no rejection) at cotθ = 0.5.
        let tilted = |cot: f64, u: [f64; 2]| {
            propose_until(cot, u[0], Draws::new(u), |t, v| {
                t > 0.0 && v < libm::pow(t * libm::exp(1.0 - t), 1.1)
            })
        };
        let chi2 = slope_chi2(1.0, 1_000_000, tilted);
        assert!(
            chi2 > CHI2_63_LIMIT,
            "tilted acceptance passed: χ² = {chi2}"
        );
        let proposal = |cot: f64, u: [f64; 2]| {
            let k = 2.0 / (cot + libm::sqrt(cot * cot + 2.0));
            (normal_quantile(u[0]) * FRAC_1_SQRT_2 - 0.5 * k).min(cot * (1.0 - 1e-15))
        };
        let chi2 = slope_chi2(0.5, 1_000_000, proposal);
        assert!(chi2 > CHI2_63_LIMIT, "proposal alone passed: χ² = {chi2}");
    }

    #[test]
    fn the_acceptance_test_is_t_exp_one_minus_t() {
        // The cubic shortcut never accepts what the exp would reject: over
        // t from 1e−6 to 40 and v on a grid, `accept` equals v < t e^{1−t}
        // except within an ulp of the boundary.
        let mut shortcut = 0;
        for i in 1..=4000 {
            let t = 1e-6 + 40.0 * (i as f64 / 4000.0).powi(2);
            let f = t * libm::exp(1.0 - t);
            for j in 0..=200 {
                let v = j as f64 / 200.0;
                if (v - f).abs() <= 4.0 * f64::EPSILON {
                    continue;
                }
                assert_eq!(accept(t, v), v < f, "t {t} v {v}");
                let s = 1.0 - t;
                shortcut += usize::from(v < t * (1.0 + s * (1.0 + s * (0.5 + s / 6.0))));
            }
        }
        assert!(shortcut > 10_000, "{shortcut}");
        assert!(!accept(0.0, 0.0) && !accept(-1.0, 0.0) && !accept(f64::NAN, 0.0));
    }
}
