//! Special functions the wave-optical models need, written for `no_std`:
//! the modified Bessel function K_μ for real order (Temme's method), the
//! reciprocal gamma series near 1, and log Γ of a complex argument.

use core::f64::consts::PI;

/// Euler–Mascheroni constant.
pub(crate) const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// Taylor coefficients of 1/Γ(z) = Σ c_k z^k, k = 1…20 (Abramowitz & Stegun
/// 6.1.34); `RGAMMA[k-1] = c_k`.
const RGAMMA: [f64; 20] = [
    1.0,
    0.577_215_664_901_532_9,
    -0.655_878_071_520_253_8,
    -0.042_002_635_034_095_2,
    0.166_538_611_382_291_5,
    -0.042_197_734_555_544_3,
    -0.009_621_971_527_877_0,
    0.007_218_943_246_663_0,
    -0.001_165_167_591_859_1,
    -0.000_215_241_674_114_9,
    0.000_128_050_282_388_2,
    -0.000_020_134_854_780_7,
    -0.000_001_250_493_482_1,
    0.000_001_133_027_232_0,
    -0.000_000_205_633_841_7,
    0.000_000_006_116_095_0,
    0.000_000_005_002_007_5,
    -0.000_000_001_181_274_6,
    0.000_000_000_104_342_7,
    0.000_000_000_007_782_3,
];

/// Temme's auxiliary functions for |μ| ≤ ½:
/// γ₁ = (1/Γ(1−μ) − 1/Γ(1+μ))/(2μ), γ₂ = (1/Γ(1−μ) + 1/Γ(1+μ))/2,
/// and 1/Γ(1+μ), 1/Γ(1−μ). The series avoids the 0/0 of γ₁ at small μ.
fn temme_gammas(mu: f64) -> (f64, f64, f64, f64) {
    if mu.abs() < 0.2 {
        let m2 = mu * mu;
        // 1/Γ(1+μ) = Σ c_k μ^{k−1}: odd k give the even part, even k the odd part.
        let mut even = 0.0;
        let mut odd = 0.0;
        let mut p = 1.0;
        for j in 0..10 {
            even += RGAMMA[2 * j] * p;
            odd += RGAMMA[2 * j + 1] * p;
            p *= m2;
        }
        let gampl = even + mu * odd;
        let gammi = even - mu * odd;
        (-odd, even, gampl, gammi)
    } else {
        let gampl = 1.0 / libm::tgamma(1.0 + mu);
        let gammi = 1.0 / libm::tgamma(1.0 - mu);
        (
            (gammi - gampl) / (2.0 * mu),
            0.5 * (gammi + gampl),
            gampl,
            gammi,
        )
    }
}

/// K_μ(x) and K_{μ+1}(x) for |μ| ≤ ½ and x > 0, both multiplied by eˣ
/// (so that large x does not underflow).
///
/// Temme's series for x ≤ 2 and Steed's continued fraction (Temme's CF2)
/// for x > 2, as in Numerical Recipes' `bessik`; relative accuracy ~1e−15.
pub(crate) fn bessel_k_pair_scaled(mu: f64, x: f64) -> (f64, f64) {
    const EPS: f64 = 1e-16;
    if x <= 2.0 {
        let (gam1, gam2, gampl, gammi) = temme_gammas(mu);
        let x2 = 0.5 * x;
        let pimu = PI * mu;
        let fact = if pimu.abs() < 1e-12 {
            1.0
        } else {
            pimu / libm::sin(pimu)
        };
        let d = -libm::log(x2);
        let e = mu * d;
        let fact2 = if e.abs() < 1e-12 {
            1.0
        } else {
            libm::sinh(e) / e
        };
        let mut ff = fact * (gam1 * libm::cosh(e) + gam2 * fact2 * d);
        let mut sum = ff;
        let ee = libm::exp(e);
        let mut p = 0.5 * ee / gampl;
        let mut q = 0.5 / (ee * gammi);
        let mut c = 1.0;
        let dd = x2 * x2;
        let mut sum1 = p;
        let mut i = 1.0;
        loop {
            ff = (i * ff + p + q) / (i * i - mu * mu);
            c *= dd / i;
            p /= i - mu;
            q /= i + mu;
            let del = c * ff;
            sum += del;
            let del1 = c * (p - i * ff);
            sum1 += del1;
            if del.abs() < sum.abs() * EPS || i > 500.0 {
                break;
            }
            i += 1.0;
        }
        let s = libm::exp(x);
        (sum * s, sum1 * 2.0 / x * s)
    } else {
        let mut b = 2.0 * (1.0 + x);
        let mut d = 1.0 / b;
        let mut h = d;
        let mut delh = d;
        let mut q1 = 0.0;
        let mut q2 = 1.0;
        let a1 = 0.25 - mu * mu;
        let mut q = a1;
        let mut c = a1;
        let mut a = -a1;
        let mut s = 1.0 + q * delh;
        let mut i = 1.0;
        loop {
            a -= 2.0 * i;
            c = -a * c / (i + 1.0);
            let qnew = (q1 - b * q2) / a;
            q1 = q2;
            q2 = qnew;
            q += c * qnew;
            b += 2.0;
            d = 1.0 / (b + a * d);
            delh *= b * d - 1.0;
            h += delh;
            let dels = q * delh;
            s += dels;
            if (dels / s).abs() < EPS || i > 5000.0 {
                break;
            }
            i += 1.0;
        }
        h *= a1;
        let kmu = libm::sqrt(PI / (2.0 * x)) / s;
        let k1 = kmu * (mu + x + 0.5 - h) / x;
        (kmu, k1)
    }
}

// Only the tests use K_ν of any order (the models need the pair at |μ| ≤ ½).
#[cfg(test)]
/// eˣ K_ν(x) for real ν ≥ 0 and x > 0, by upward recurrence from |μ| ≤ ½.
pub(crate) fn bessel_k_scaled(nu: f64, x: f64) -> f64 {
    let n = libm::floor(nu + 0.5);
    let mu = nu - n;
    let (mut k0, mut k1) = bessel_k_pair_scaled(mu, x);
    let mut m = mu;
    let mut steps = n as i64;
    while steps > 0 {
        let k2 = 2.0 * (m + 1.0) / x * k1 + k0;
        k0 = k1;
        k1 = k2;
        m += 1.0;
        steps -= 1;
    }
    k0
}

/// ln Γ(z) for complex z = (re, im) with re > 0 (principal branch up to a
/// multiple of 2πi in the imaginary part, which callers exponentiate).
/// Shifts to re ≥ 15 and uses the Stirling series (error < 1e−15).
pub fn ln_gamma_complex(re: f64, im: f64) -> (f64, f64) {
    let mut zr = re;
    let zi = im;
    // Σ ln(z + k) for the shift, accumulated as a product's log.
    let mut acc_r = 0.0;
    let mut acc_i = 0.0;
    // Stirling's series below is accurate once |z| ≥ 15 anywhere in the
    // right half-plane, so only small |z| is shifted: FFTLog plans evaluate
    // this at every frequency bin, nearly all with |Im z| ≫ 15, and the
    // shift (a log and an atan2 per step) would be most of a plan's cost.
    while zr < 15.0 && zr * zr + zi * zi < 225.0 {
        acc_r += 0.5 * libm::log(zr * zr + zi * zi);
        acc_i += libm::atan2(zi, zr);
        zr += 1.0;
    }
    // ln z
    let lr = 0.5 * libm::log(zr * zr + zi * zi);
    let li = libm::atan2(zi, zr);
    // (z − ½) ln z − z + ½ ln 2π
    let mut sr = (zr - 0.5) * lr - zi * li - zr + 0.5 * libm::log(2.0 * PI);
    let mut si = (zr - 0.5) * li + zi * lr - zi;
    // 1/z
    let den = zr * zr + zi * zi;
    let (ir, ii) = (zr / den, -zi / den);
    // 1/z² for the series in odd powers of 1/z
    let (i2r, i2i) = (ir * ir - ii * ii, 2.0 * ir * ii);
    const B: [f64; 6] = [
        1.0 / 12.0,
        -1.0 / 360.0,
        1.0 / 1260.0,
        -1.0 / 1680.0,
        1.0 / 1188.0,
        -691.0 / 360_360.0,
    ];
    let (mut pr, mut pi) = (ir, ii);
    for b in B {
        sr += b * pr;
        si += b * pi;
        let t = pr * i2r - pi * i2i;
        pi = pr * i2i + pi * i2r;
        pr = t;
    }
    (sr - acc_r, si - acc_i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reciprocal_gamma_series_matches_tgamma() {
        for &mu in &[-0.19, -0.1, -1e-3, 0.0, 1e-5, 0.05, 0.15, 0.199] {
            let (_, _, gp, gm) = temme_gammas(mu);
            assert!((gp * libm::tgamma(1.0 + mu) - 1.0).abs() < 1e-14, "{mu}");
            assert!((gm * libm::tgamma(1.0 - mu) - 1.0).abs() < 1e-14, "{mu}");
        }
        let (g1, g2, _, _) = temme_gammas(0.0);
        assert!((g1 + EULER_GAMMA).abs() < 1e-15 && (g2 - 1.0).abs() < 1e-15);
    }

    #[test]
    fn bessel_k_closed_forms() {
        // K_{1/2}(x) = sqrt(π/(2x)) e^{−x}; K_{3/2} = K_{1/2}(1 + 1/x);
        // K_{5/2} = K_{1/2}(1 + 3/x + 3/x²).
        for &x in &[1e-6, 0.01, 0.3, 1.0, 1.99, 2.0, 2.01, 5.0, 30.0, 700.0, 1e4] {
            let k12 = libm::sqrt(PI / (2.0 * x));
            let cases = [
                (0.5, k12),
                (1.5, k12 * (1.0 + 1.0 / x)),
                (2.5, k12 * (1.0 + 3.0 / x + 3.0 / (x * x))),
            ];
            for (nu, want) in cases {
                let got = bessel_k_scaled(nu, x);
                assert!(
                    (got / want - 1.0).abs() < 3e-14,
                    "nu={nu} x={x}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn bessel_k_integer_orders_and_wronskian() {
        // Reference values (A&S tables): K0(1) = 0.42102443824070834,
        // K1(1) = 0.6019072301972346, K0(0.1) = 2.4270690247020166, K1(3) = 0.04015643112819418.
        let e1 = libm::exp(1.0);
        assert!((bessel_k_scaled(0.0, 1.0) / e1 / 0.421_024_438_240_708_34 - 1.0).abs() < 1e-14);
        assert!((bessel_k_scaled(1.0, 1.0) / e1 / 0.601_907_230_197_234_6 - 1.0).abs() < 1e-14);
        assert!(
            (bessel_k_scaled(0.0, 0.1) / libm::exp(0.1) / 2.427_069_024_702_017 - 1.0).abs()
                < 1e-14
        );
        assert!(
            (bessel_k_scaled(1.0, 3.0) / libm::exp(3.0) / 0.040_156_431_128_194_18 - 1.0).abs()
                < 1e-14
        );
        // Both sides of the x = 2 branch switch, non-integer order, against
        // 30-digit mpmath values of eˣK_ν(x).
        let cases = [
            (3.7, 1.999_999, 10.950_390_372_891_24),
            (3.7, 2.000_001, 10.950_364_763_774_955),
            (-0.3, 1.999_999, 0.857_403_915_334_477_1),
            (0.7, 2.000_001, 0.931_118_878_718_136_8),
        ];
        for (nu, x, want) in cases {
            let got = if nu < 0.0 {
                bessel_k_pair_scaled(nu, x).0
            } else {
                bessel_k_scaled(nu, x)
            };
            assert!(
                (got / want - 1.0).abs() < 3e-15,
                "nu={nu} x={x}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn complex_ln_gamma() {
        // Real axis against libm, and |Γ(iy)|² = π/(y sinh πy).
        for &x in &[0.1, 0.5, 1.0, 2.5, 7.3, 40.0] {
            let (r, i) = ln_gamma_complex(x, 0.0);
            assert!(
                (r - libm::lgamma(x)).abs() < 1e-13 && i.abs() < 1e-15,
                "{x}"
            );
        }
        for &y in &[0.3, 1.0, 5.0, 50.0] {
            let (r, _) = ln_gamma_complex(1e-300, y);
            let want = 0.5 * libm::log(PI / (y * libm::sinh(PI * y)));
            assert!(
                (r - want).abs() < 1e-12 * want.abs().max(1.0),
                "{y}: {r} {want}"
            );
        }
        // Γ(1+z) = zΓ(z), also just outside |z| = 15 near the imaginary
        // axis, where the series is used without a shift, and across it.
        for (a, b) in [
            (0.3, 2.7),
            (0.25, 15.2),
            (0.5, 14.99),
            (1e-3, 40.0),
            (0.75, -22.0),
        ] {
            let (r0, i0) = ln_gamma_complex(a, b);
            let (r1, i1) = ln_gamma_complex(a + 1.0, b);
            let lr = 0.5 * libm::log(a * a + b * b);
            let li = libm::atan2(b, a);
            assert!((r1 - r0 - lr).abs() < 1e-13 * r0.abs().max(1.0), "{a} {b}");
            let d = libm::remainder(i1 - i0 - li, 2.0 * PI);
            assert!(d.abs() < 1e-13 * i0.abs().max(1.0), "{a} {b}: {d}");
        }
    }
}
