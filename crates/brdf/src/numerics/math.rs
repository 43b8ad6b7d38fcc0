//! Small numerical helpers shared by the models.

/// Clamps a float to a finite, non-negative value (NaN → 0); the last line of
/// defence that keeps every public evaluation finite and ≥ 0.
#[inline]
pub fn finite_nonneg(x: f64) -> f64 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

/// (sin x, cos x): the platform's fast version with `std`, libm's without.
#[inline]
pub fn sincos(x: f64) -> (f64, f64) {
    #[cfg(feature = "std")]
    {
        x.sin_cos()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sincos(x)
    }
}

/// eˣ: the platform's version with `std`, libm's without.
#[inline]
pub fn exp(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.exp()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::exp(x)
    }
}

/// ln x: the platform's version with `std`, libm's without.
#[inline]
pub fn ln(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.ln()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::log(x)
    }
}

// Only the two-scale tables (alloc) use it.
#[cfg(feature = "alloc")]
/// asinh x for x ≥ 0 (NaN stays NaN), as ln(x + √(x² + 1)) with the
/// platform's ln: several times cheaper than libm's asinh. There is no
/// cancellation for x ≥ 0; the absolute error is a few 1e−16 (the relative
/// error grows for x ≪ 1, which is fine for its use: positions on table
/// grids, where only absolute accuracy matters).
#[inline]
pub fn asinh_nonneg(x: f64) -> f64 {
    if x > 1e150 {
        // x² + 1 would overflow; asinh x = ln 2x to double precision.
        return core::f64::consts::LN_2 + ln(x);
    }
    ln(x + libm::sqrt(x * x + 1.0))
}

/// (sin 2πu, cos 2πu) for `u` ∈ [−1/8, 1], without a libm call.
///
/// Samplers draw azimuths as 2πu, where the general-purpose `sincos` (argument
/// reduction for any x) costs several times more than the rest of a sample.
/// Here the reduction is exact: with j = ⌊4u + ½⌋, u − j/4 is computed
/// without rounding (Sterbenz), so x = 2π(u − j/4) ∈ [−π/4, π/4] carries
/// only the rounding of one product, and Taylor polynomials of degree 15/16
/// give sin x and cos x to a few ulps. The
/// quadrant j then rotates the pair. Agrees with libm to < 5e−16 (tested).
#[inline]
pub fn sincos_2pi(u: f64) -> (f64, f64) {
    // Truncation is ⌊·⌋ for u ≥ 0 (and saturates harmlessly outside).
    let q = (4.0 * u + 0.5) as i64;
    let x = core::f64::consts::TAU * (u - 0.25 * q as f64);
    let x2 = x * x;
    let x4 = x2 * x2;
    let x8 = x4 * x4;
    // Taylor polynomials in x² (sin to x¹⁵: truncation < 5e−17; cos to x¹⁶:
    // < 3e−18 on |x| ≤ π/4), evaluated by Estrin's scheme: the same terms
    // as Horner's rule in a tree of depth 4 instead of a chain of 8, which
    // matters because a sample's arithmetic is one long dependency chain.
    let s = {
        let p01 = 1.0 - x2 * (1.0 / 6.0);
        let p23 = 1.0 / 120.0 - x2 * (1.0 / 5040.0);
        let p45 = 1.0 / 362_880.0 - x2 * (1.0 / 39_916_800.0);
        let p67 = 1.0 / 6_227_020_800.0 - x2 * (1.0 / 1_307_674_368_000.0);
        x * ((p01 + x4 * p23) + x8 * (p45 + x4 * p67))
    };
    let c = {
        let p01 = 1.0 - x2 * 0.5;
        let p23 = 1.0 / 24.0 - x2 * (1.0 / 720.0);
        let p45 = 1.0 / 40_320.0 - x2 * (1.0 / 3_628_800.0);
        let p67 = 1.0 / 479_001_600.0 - x2 * (1.0 / 87_178_291_200.0);
        let p8 = 1.0 / 20_922_789_888_000.0;
        (p01 + x4 * p23) + x8 * ((p45 + x4 * p67) + x8 * p8)
    };
    // Rotate by q quarter turns without branches (q is random in samplers,
    // so a `match` mispredicts most of the time): odd q swaps the pair,
    // q = 2, 3 negate sin and q = 1, 2 negate cos, as sign-bit flips.
    let swap = 0u64.wrapping_sub((q & 1) as u64);
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let a = (sb & !swap) | (cb & swap);
    let b = (cb & !swap) | (sb & swap);
    let neg_sin = (((q >> 1) & 1) as u64) << 63;
    let neg_cos = ((((q >> 1) ^ q) & 1) as u64) << 63;
    (f64::from_bits(a ^ neg_sin), f64::from_bits(b ^ neg_cos))
}

/// √x of four lanes at once (correctly rounded, so each lane equals
/// `libm::sqrt` of it): one packed instruction where the target has AVX, two
/// SSE2 ones on any other x86-64, four scalar roots elsewhere.
#[inline(always)]
pub fn sqrt_lanes(x: [f64; 4]) -> [f64; 4] {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use core::arch::x86_64::{_mm256_loadu_pd, _mm256_sqrt_pd, _mm256_storeu_pd};
        let mut r = [0.0; 4];
        // SAFETY: AVX is enabled for this build (the cfg above); the load and
        // store touch exactly the four f64 of `x` and `r`.
        unsafe { _mm256_storeu_pd(r.as_mut_ptr(), _mm256_sqrt_pd(_mm256_loadu_pd(x.as_ptr()))) };
        r
    }
    #[cfg(all(target_arch = "x86_64", not(target_feature = "avx")))]
    {
        use core::arch::x86_64::{_mm_loadu_pd, _mm_sqrt_pd, _mm_storeu_pd};
        let mut r = [0.0; 4];
        // SAFETY: SSE2 is part of every x86-64; each load and store touches two
        // f64 inside `x` and `r`.
        unsafe {
            _mm_storeu_pd(r.as_mut_ptr(), _mm_sqrt_pd(_mm_loadu_pd(x.as_ptr())));
            _mm_storeu_pd(
                r.as_mut_ptr().add(2),
                _mm_sqrt_pd(_mm_loadu_pd(x.as_ptr().add(2))),
            );
        }
        r
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        x.map(libm::sqrt)
    }
}

/// (sinh x, cosh x) for x ≥ 0 from one platform exponential (libm's sinh
/// and cosh are an expm1 and an exp each, and the table build takes both at
/// every quadrature point of its bin masses and Λ nodes); sinh by its series
/// below 1/4, where (eˣ − e⁻ˣ)/2 would cancel. Within 2 ulp of libm.
/// Only the (alloc) two-scale table calls it.
#[cfg(feature = "alloc")]
#[inline]
pub(crate) fn sinh_cosh(x: f64) -> (f64, f64) {
    let e = exp(x);
    let inv = 1.0 / e;
    let s = if x < 0.25 {
        // x(1 + x²/3!(1 + x²/(4·5)(1 + …))), to x¹³/13! (below 3e−18·x).
        let x2 = x * x;
        let mut t = 1.0;
        for d in [156.0, 110.0, 72.0, 42.0, 20.0, 6.0] {
            t = 1.0 + x2 / d * t;
        }
        x * t
    } else {
        0.5 * (e - inv)
    };
    (s, 0.5 * (e + inv))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`sinh_cosh`] against libm's sinh and cosh over 0–40 (the table's
    /// arguments reach V ≈ 20), through the series' end at 1/4.
    #[test]
    fn sinh_cosh_matches_libm() {
        let mut worst = 0.0f64;
        for e in 0..=4000 {
            let x = if e < 2000 {
                0.25 * e as f64 / 2000.0
            } else {
                0.25 + 40.0 * (e - 2000) as f64 / 2000.0
            };
            let (s, c) = sinh_cosh(x);
            if x > 0.0 {
                worst = worst.max((s / libm::sinh(x) - 1.0).abs());
            }
            worst = worst.max((c / libm::cosh(x) - 1.0).abs());
        }
        assert!(worst < 5e-16, "{worst:e}");
    }

    #[test]
    fn asinh_nonneg_matches_libm() {
        let mut worst: f64 = 0.0;
        let mut x = 1e-12;
        while x < 1e300 {
            let e = (asinh_nonneg(x) - libm::asinh(x)).abs() / libm::asinh(x).max(1.0);
            worst = worst.max(e);
            x *= 1.37;
        }
        assert!(worst < 5e-16, "{worst}");
        assert_eq!(asinh_nonneg(0.0), 0.0);
        assert!(asinh_nonneg(f64::NAN).is_nan());
        assert_eq!(asinh_nonneg(f64::INFINITY), f64::INFINITY);
    }

    #[test]
    fn sincos_2pi_matches_libm() {
        let mut worst: f64 = 0.0;
        let n = 200_000;
        let grid = (0..=n).map(|i| i as f64 / n as f64);
        // Octant and quadrant boundaries and their neighbours.
        let edges = (0..=8).flat_map(|k| {
            let b = k as f64 / 8.0;
            [b, b.next_up(), b.next_down()]
        });
        // Negative arguments down to −1/8 too (the concentric map's range).
        let negative = (0..=n / 8).map(|i| -(i as f64) / n as f64);
        for u in grid
            .chain(negative)
            .chain(edges)
            .chain([-0.125, (-0.125f64).next_up()])
            .filter(|u| (-0.125..=1.0).contains(u))
        {
            let (s, c) = sincos_2pi(u);
            // Against libm on the same reduced argument: the polynomials alone.
            let j = libm::floor(4.0 * u + 0.5);
            let (rs, rc) = libm::sincos(core::f64::consts::TAU * (u - 0.25 * j));
            let (ws, wc) = match (j as i64) & 3 {
                0 => (rs, rc),
                1 => (rc, -rs),
                2 => (-rs, -rc),
                _ => (-rc, rs),
            };
            worst = worst.max((s - ws).abs()).max((c - wc).abs());
            // Against libm on 2πu, whose rounded argument alone moves the
            // result by up to ~4.4e−16 near u = 1.
            let (ls, lc) = libm::sincos(core::f64::consts::TAU * u);
            assert!((s - ls).abs() < 1e-15 && (c - lc).abs() < 1e-15, "u = {u}");
            assert!((s * s + c * c - 1.0).abs() < 1e-15, "u = {u}");
        }
        assert!(worst < 2.5e-16, "worst |Δ| = {worst:e}");
    }
}
