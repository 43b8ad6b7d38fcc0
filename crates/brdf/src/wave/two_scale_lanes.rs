//! ln, eˣ and the coherent fraction on four lanes at once, for the two-scale
//! cap's integrand: at every quadrature node it needs them at the four
//! wavenumber nodes of the cap's table, and a library call per value (a ln
//! for the w bracket, an exp for Λ at wo, an expm1 or exp for A) was a third
//! of the cap's instructions. With AVX2 and FMA (the x86-64-v3 level and
//! above) the four lanes are one vector register; elsewhere the same
//! polynomials run lane by lane. Accurate to a few ulp on the ranges the
//! integrand uses; not a general replacement for the library functions (no
//! subnormal results, no special cases beyond those documented).

/// Number of lanes.
pub(crate) const LANES: usize = 4;

/// Four values.
pub(crate) type Lanes = [f64; LANES];

/// ln 2 split so that n·[`LN2_HI`] is exact for |n| < 2¹¹ (its low 21
/// mantissa bits are zero), [`LN2_LO`] the rest.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);

/// 1.5·2⁵²: adding it rounds a double of magnitude < 2⁵¹ to an integer held
/// in the low bits of the sum's mantissa.
const SHIFTER: f64 = 6_755_399_441_055_744.0;

/// 2⁵² + 1023: the bits of 2⁵² with a biased exponent e in the low bits of
/// the mantissa are the double 2⁵² + e, exactly.
const EXP_BIAS_OFFSET: f64 = 4_503_599_627_370_496.0 + 1023.0;

/// Lowest and highest argument of [`exp`] (beyond them 0 and +∞).
const EXP_LO: f64 = -708.0;
const EXP_HI: f64 = 709.0;

/// 1/n! for n = 0 … N − 1 (n! exact in a double up to 18!).
const fn inv_factorials<const N: usize>() -> [f64; N] {
    let mut out = [0.0; N];
    let mut f = 1.0;
    let mut n = 0;
    while n < N {
        out[n] = 1.0 / f;
        n += 1;
        f *= n as f64;
    }
    out
}

/// eʳ = Σ rⁿ/n! to r¹³ for |r| ≤ ½ ln 2 (the rest below 5e−18).
const EXP_COEF: [f64; 14] = inv_factorials::<14>();

/// e^y − 1 = y Σ yⁿ/(n + 1)! to y¹⁸ for |y| < 1 (the rest below 2e−17 of
/// it): `EXPM1_COEF[n]` = 1/(n + 1)!.
const EXPM1_COEF: [f64; 18] = {
    let f = inv_factorials::<19>();
    let mut out = [0.0; 18];
    let mut n = 0;
    while n < 18 {
        out[n] = f[n + 1];
        n += 1;
    }
    out
};

/// ln m = 2 atanh s = 2s Σ s²ⁿ/(2n + 1), n = 0 … 11, for |s| ≤ 0.1716
/// (the rest below 2e−19 of ln m): `LN_COEF[n]` = 1/(2n + 1).
const LN_COEF: [f64; 12] = {
    let mut out = [0.0; 12];
    let mut n = 0;
    while n < 12 {
        out[n] = 1.0 / (2 * n + 1) as f64;
        n += 1;
    }
    out
};

/// ln x for every lane, x ≥ 1 and finite (the integrand's 1 + w): the
/// exponent e and mantissa m ∈ [√½, √2) of x, and ln m = 2 atanh s with
/// s = (m − 1)/(m + 1). A few ulp of ln x; other inputs give an
/// unspecified value.
#[inline(always)]
pub(crate) fn ln(x: Lanes) -> Lanes {
    lanes::ln(x)
}

/// eˣ for every lane: x = n ln 2 + r with |r| ≤ ½ ln 2, eʳ by its Taylor
/// series, times 2ⁿ by its bits. A few ulp for x ∈ [−708, 709]; below −708
/// the result is 0 (the true value is below 3.3e−308: an absolute error,
/// which is what A and Λ need), above 709 it is +∞, NaN stays NaN.
#[inline(always)]
pub(crate) fn exp(x: Lanes) -> Lanes {
    lanes::exp(x)
}

/// The coherent fraction A = e^{−g} and 1 − A for every lane (g ≥ 0), each
/// without cancellation: for g < 1, 1 − A = −(e^{−g} − 1) by the Taylor
/// series of e^{−g} − 1, A = 1 − that; for g ≥ 1, A by [`exp`] and 1 − A by
/// subtraction (A ≤ 1/e). As `TwoScale::coherent_fraction`, which takes
/// libm's expm1 or exp per value.
#[inline(always)]
pub(crate) fn coherent(g: Lanes) -> (Lanes, Lanes) {
    lanes::coherent(g)
}

/// The vector registers where the build has them.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
use avx as lanes;

/// Elsewhere the lane-by-lane versions, four at a time.
#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
)))]
mod lanes {
    use super::{LANES, Lanes, scalar};

    pub(super) fn ln(x: Lanes) -> Lanes {
        x.map(scalar::ln)
    }

    pub(super) fn exp(x: Lanes) -> Lanes {
        x.map(scalar::exp)
    }

    pub(super) fn coherent(g: Lanes) -> (Lanes, Lanes) {
        let mut a = [0.0; LANES];
        let mut one_minus_a = [0.0; LANES];
        for l in 0..LANES {
            (a[l], one_minus_a[l]) = scalar::coherent(g[l]);
        }
        (a, one_minus_a)
    }
}

/// The lane-by-lane versions: the same polynomials without vector
/// registers (the fallback, and a second implementation for the tests).
#[cfg_attr(
    all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ),
    allow(dead_code)
)]
mod scalar {
    use super::*;

    pub(super) fn ln(x: f64) -> f64 {
        let bits = x.to_bits();
        let mut e = f64::from_bits((bits >> 52) | SHIFTER_EXP_BITS) - EXP_BIAS_OFFSET;
        let mut m = f64::from_bits((bits & MANTISSA) | ONE_BITS);
        if m > core::f64::consts::SQRT_2 {
            m *= 0.5;
            e += 1.0;
        }
        let s = (m - 1.0) / (m + 1.0);
        let s2 = s * s;
        let p = LN_COEF[1..].iter().rev().fold(0.0, |p, &c| p * s2 + c);
        e * LN2_HI + (e * LN2_LO + (2.0 * s + 2.0 * s * (s2 * p)))
    }

    pub(super) fn exp(x: f64) -> f64 {
        if x.is_nan() {
            return x;
        }
        if x < EXP_LO {
            return 0.0;
        }
        if x > EXP_HI {
            return f64::INFINITY;
        }
        let t = x * core::f64::consts::LOG2_E + SHIFTER;
        let n = t - SHIFTER;
        let r = (x - n * LN2_HI) - n * LN2_LO;
        let p = EXP_COEF.iter().rev().fold(0.0, |p, &c| p * r + c);
        let n_bits = t.to_bits().wrapping_sub(SHIFTER.to_bits());
        p * f64::from_bits(n_bits.wrapping_add(1023) << 52)
    }

    pub(super) fn coherent(g: f64) -> (f64, f64) {
        if g < 1.0 {
            let y = -g;
            let em1 = y * EXPM1_COEF.iter().rev().fold(0.0, |p, &c| p * y + c);
            (1.0 + em1, -em1)
        } else {
            let a = exp(-g);
            (a, 1.0 - a)
        }
    }
}

/// 0x433…: the exponent bits of 2⁵² (see [`EXP_BIAS_OFFSET`]).
const SHIFTER_EXP_BITS: u64 = 0x4330_0000_0000_0000;
/// The mantissa bits of a double.
const MANTISSA: u64 = 0x000f_ffff_ffff_ffff;
/// The bits of 1.0.
const ONE_BITS: u64 = 0x3ff0_0000_0000_0000;

/// The AVX2 + FMA versions: the four lanes in one register.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
))]
mod avx {
    use super::*;
    use core::arch::x86_64::*;

    #[inline(always)]
    fn load(x: Lanes) -> __m256d {
        // SAFETY: `Lanes` is four f64; loadu has no alignment requirement.
        unsafe { _mm256_loadu_pd(x.as_ptr()) }
    }

    #[inline(always)]
    fn store(v: __m256d) -> Lanes {
        let mut out = [0.0; LANES];
        // SAFETY: `out` holds four f64; storeu has no alignment requirement.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
        out
    }

    /// Horner's rule Σ c[n] xⁿ.
    #[inline(always)]
    fn poly<const N: usize>(x: __m256d, c: &[f64; N]) -> __m256d {
        // SAFETY: AVX2 and FMA are enabled for this build (the module's cfg).
        unsafe {
            let mut p = _mm256_set1_pd(c[N - 1]);
            for n in (0..N - 1).rev() {
                p = _mm256_fmadd_pd(p, x, _mm256_set1_pd(c[n]));
            }
            p
        }
    }

    #[inline(always)]
    pub(super) fn ln(x: Lanes) -> Lanes {
        // SAFETY: AVX2 and FMA are enabled for this build (the module's cfg).
        unsafe {
            let bits = _mm256_castpd_si256(load(x));
            let e_bits = _mm256_or_si256(
                _mm256_srli_epi64::<52>(bits),
                _mm256_set1_epi64x(SHIFTER_EXP_BITS as i64),
            );
            let e = _mm256_sub_pd(_mm256_castsi256_pd(e_bits), _mm256_set1_pd(EXP_BIAS_OFFSET));
            let m = _mm256_castsi256_pd(_mm256_or_si256(
                _mm256_and_si256(bits, _mm256_set1_epi64x(MANTISSA as i64)),
                _mm256_set1_epi64x(ONE_BITS as i64),
            ));
            let big = _mm256_cmp_pd::<_CMP_GT_OQ>(m, _mm256_set1_pd(core::f64::consts::SQRT_2));
            let m = _mm256_blendv_pd(m, _mm256_mul_pd(m, _mm256_set1_pd(0.5)), big);
            let e = _mm256_add_pd(e, _mm256_and_pd(big, _mm256_set1_pd(1.0)));
            let one = _mm256_set1_pd(1.0);
            let s = _mm256_div_pd(_mm256_sub_pd(m, one), _mm256_add_pd(m, one));
            let s2 = _mm256_mul_pd(s, s);
            let mut c = [0.0; 11];
            c.copy_from_slice(&LN_COEF[1..]);
            let p = poly(s2, &c);
            let two_s = _mm256_add_pd(s, s);
            let ln_m = _mm256_fmadd_pd(two_s, _mm256_mul_pd(s2, p), two_s);
            let lo = _mm256_fmadd_pd(e, _mm256_set1_pd(LN2_LO), ln_m);
            store(_mm256_fmadd_pd(e, _mm256_set1_pd(LN2_HI), lo))
        }
    }

    #[inline(always)]
    fn exp_v(x: __m256d) -> __m256d {
        // SAFETY: AVX2 and FMA are enabled for this build (the module's cfg).
        unsafe {
            let xc = _mm256_min_pd(
                _mm256_max_pd(x, _mm256_set1_pd(EXP_LO)),
                _mm256_set1_pd(EXP_HI),
            );
            let shifter = _mm256_set1_pd(SHIFTER);
            let t = _mm256_fmadd_pd(xc, _mm256_set1_pd(core::f64::consts::LOG2_E), shifter);
            let n = _mm256_sub_pd(t, shifter);
            let r = _mm256_fnmadd_pd(n, _mm256_set1_pd(LN2_HI), xc);
            let r = _mm256_fnmadd_pd(n, _mm256_set1_pd(LN2_LO), r);
            let p = poly(r, &EXP_COEF);
            let n_bits = _mm256_sub_epi64(
                _mm256_castpd_si256(t),
                _mm256_set1_epi64x(SHIFTER.to_bits() as i64),
            );
            let scale = _mm256_slli_epi64::<52>(_mm256_add_epi64(n_bits, _mm256_set1_epi64x(1023)));
            let v = _mm256_mul_pd(p, _mm256_castsi256_pd(scale));
            // Below EXP_LO: 0; above EXP_HI: +∞; NaN: itself.
            let v = _mm256_blendv_pd(
                v,
                _mm256_setzero_pd(),
                _mm256_cmp_pd::<_CMP_LT_OQ>(x, _mm256_set1_pd(EXP_LO)),
            );
            let v = _mm256_blendv_pd(
                v,
                _mm256_set1_pd(f64::INFINITY),
                _mm256_cmp_pd::<_CMP_GT_OQ>(x, _mm256_set1_pd(EXP_HI)),
            );
            _mm256_blendv_pd(v, x, _mm256_cmp_pd::<_CMP_UNORD_Q>(x, x))
        }
    }

    #[inline(always)]
    pub(super) fn exp(x: Lanes) -> Lanes {
        store(exp_v(load(x)))
    }

    #[inline(always)]
    pub(super) fn coherent(g: Lanes) -> (Lanes, Lanes) {
        // SAFETY: AVX2 and FMA are enabled for this build (the module's cfg).
        unsafe {
            let g = load(g);
            let y = _mm256_sub_pd(_mm256_setzero_pd(), g);
            let one = _mm256_set1_pd(1.0);
            let big = exp_v(y);
            let em1 = _mm256_mul_pd(y, poly(y, &EXPM1_COEF));
            let small = _mm256_cmp_pd::<_CMP_LT_OQ>(g, one);
            let a = _mm256_blendv_pd(big, _mm256_add_pd(one, em1), small);
            let one_minus_a = _mm256_blendv_pd(
                _mm256_sub_pd(one, big),
                _mm256_sub_pd(_mm256_setzero_pd(), em1),
                small,
            );
            (store(a), store(one_minus_a))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative error of `got` against `want` in units of want's ulp.
    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            return 0.0;
        }
        (got - want).abs() / (want.abs() * f64::EPSILON)
    }

    /// Points spread over [lo, hi] (log-spaced beside uniform ones).
    fn points(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..=n).map(move |i| lo + (hi - lo) * (i as f64 / n as f64).powi(3))
    }

    #[test]
    fn ln_matches_libm() {
        let mut worst = 0.0f64;
        let xs: alloc::vec::Vec<f64> = points(1.0, 2.0, 4000)
            .chain(points(1.0, 1e6, 4000))
            .chain([
                1.0,
                1.0 + f64::EPSILON,
                core::f64::consts::SQRT_2,
                2.0,
                1e300,
            ])
            .collect();
        for c in xs.chunks(LANES) {
            let mut x = [1.5; LANES];
            x[..c.len()].copy_from_slice(c);
            let got = ln(x);
            for l in 0..LANES {
                let want = libm::log(x[l]);
                // ln 1 = 0: compare absolutely there.
                for got in [got[l], scalar::ln(x[l])] {
                    let e = if want == 0.0 {
                        got.abs() / f64::EPSILON
                    } else {
                        ulps(got, want)
                    };
                    worst = worst.max(e);
                }
            }
        }
        extern crate std;
        std::eprintln!("ln: {worst} ulp");
        assert!(worst <= 2.0, "ln: {worst} ulp");
    }

    #[test]
    fn exp_matches_libm() {
        let mut worst = 0.0f64;
        let xs: alloc::vec::Vec<f64> = points(-708.0, 709.0, 8000)
            .chain(points(-1.0, 1.0, 4000))
            .chain([0.0, -0.0, 1e-300, -1e-20, 0.5 * core::f64::consts::LN_2])
            .collect();
        for c in xs.chunks(LANES) {
            let mut x = [0.0; LANES];
            x[..c.len()].copy_from_slice(c);
            let got = exp(x);
            for l in 0..LANES {
                let want = libm::exp(x[l]);
                for got in [got[l], scalar::exp(x[l])] {
                    // Below 2^−1022 the result loses bits (subnormal): absolute.
                    let e = if want < f64::MIN_POSITIVE {
                        (got - want).abs() / f64::MIN_POSITIVE
                    } else {
                        ulps(got, want)
                    };
                    worst = worst.max(e);
                }
            }
        }
        extern crate std;
        std::eprintln!("exp: {worst} ulp");
        assert!(worst <= 2.0, "exp: {worst} ulp");
        let edge = exp([-800.0, 800.0, f64::NAN, -708.5]);
        let scalar_edge = [-800.0, 800.0, f64::NAN, -708.5].map(scalar::exp);
        for e in [edge, scalar_edge] {
            assert_eq!(e[0], 0.0);
            assert_eq!(e[1], f64::INFINITY);
            assert!(e[2].is_nan());
            assert_eq!(e[3], 0.0);
        }
    }

    #[test]
    fn coherent_matches_expm1() {
        let mut worst = 0.0f64;
        let gs: alloc::vec::Vec<f64> = points(0.0, 1.0, 4000)
            .chain(points(1.0, 800.0, 4000))
            .chain([0.0, 1e-300, 1e-12, 0.999_999_999, 1.0])
            .collect();
        for c in gs.chunks(LANES) {
            let mut g = [0.0; LANES];
            g[..c.len()].copy_from_slice(c);
            let (a, b) = coherent(g);
            for l in 0..LANES {
                // As `TwoScale::coherent_fraction`: 1 + e^{−g} − 1 has no
                // cancellation while A ≥ 1/e, and 1 − A none below it.
                let (wa, wb) = if g[l] < 1.0 {
                    let e = libm::expm1(-g[l]);
                    (1.0 + e, -e)
                } else {
                    let a = libm::exp(-g[l]);
                    (a, 1.0 - a)
                };
                for (ga, gb) in [(a[l], b[l]), scalar::coherent(g[l])] {
                    let ea = if wa < f64::MIN_POSITIVE {
                        (ga - wa).abs() / f64::MIN_POSITIVE
                    } else {
                        ulps(ga, wa)
                    };
                    let eb = if wb == 0.0 {
                        gb.abs() / f64::EPSILON
                    } else {
                        ulps(gb, wb)
                    };
                    worst = worst.max(ea).max(eb);
                }
            }
        }
        extern crate std;
        std::eprintln!("coherent: {worst} ulp");
        assert!(worst <= 3.0, "coherent: {worst} ulp");
    }
}
