//! Poisson weights of the diffraction orders, w_m(g) = e^{−g} g^m/m!, in log
//! space (physics.md §4.2): never e^{−g} or g^m/m! on their own, which
//! underflow (g ≳ 745) and overflow (m ≳ 170) in f64.

/// ln w_m(g) = −g + m ln g − ln Γ(m+1), for g > 0 and m ≥ 0.
///
/// Formed as −½ ln(2πm) − stirlerr(m) − bd0(m, g) (Loader's saddle-point
/// form), which avoids the cancellation of terms ~m ln m that costs the
/// direct form ~1e−11 absolute at g = 1e4.
#[inline]
pub fn log_weight(m: u64, g: f64) -> f64 {
    if m == 0 {
        return -g;
    }
    let x = m as f64;
    -0.5 * crate::numerics::math::ln(2.0 * core::f64::consts::PI * x)
        - stirling_error(x)
        - bd0(x, g)
}

/// ln Γ(n+1) − [(n+½) ln n − n + ½ ln 2π].
fn stirling_error(n: f64) -> f64 {
    if n < 16.0 {
        return libm::lgamma(n + 1.0)
            - ((n + 0.5) * crate::numerics::math::ln(n) - n
                + 0.5 * crate::numerics::math::ln(2.0 * core::f64::consts::PI));
    }
    let n2 = 1.0 / (n * n);
    (1.0 / 12.0 - n2 * (1.0 / 360.0 - n2 * (1.0 / 1260.0 - n2 * (1.0 / 1680.0 - n2 / 1188.0)))) / n
}

/// x ln(x/g) + g − x, without cancellation when x ≈ g.
fn bd0(x: f64, g: f64) -> f64 {
    if libm::fabs(x - g) < 0.1 * (x + g) {
        let v = (x - g) / (x + g);
        let mut s = (x - g) * v;
        let mut ej = 2.0 * x * v;
        let v2 = v * v;
        let mut j = 1.0;
        loop {
            ej *= v2;
            let s1 = s + ej / (2.0 * j + 1.0);
            if s1 == s || j > 200.0 {
                return s1;
            }
            s = s1;
            j += 1.0;
        }
    }
    x * crate::numerics::math::ln(x / g) + g - x
}

/// ln(1 − e^{−g}), the log of the mass of all orders m ≥ 1.
#[inline]
pub(crate) fn log_scattered_mass(g: f64) -> f64 {
    crate::numerics::math::ln(-libm::expm1(-g))
}

/// ln of the weight conditioned on m ≥ 1: w_m/(1 − e^{−g}) = g^m/(m! expm1(g)).
#[inline]
pub(crate) fn log_conditioned_weight(m: u64, g: f64) -> f64 {
    log_weight(m, g) - log_scattered_mass(g)
}

/// Mode of the conditioned distribution: max(1, ⌊g⌋).
#[inline]
pub fn mode(g: f64) -> u64 {
    if g < 1.0 {
        1
    } else {
        libm::floor(g.min(1e15)) as u64
    }
}

/// Orders [m_lo, m_hi] found by the rule of physics.md §4.2: walk out from
/// the mode with w_{m±1} = w_m·(g/(m+1) or m/g) and stop at the first order
/// whose conditioned weight has ln w < ln ε − 3 (that order is included).
pub fn term_range(g: f64, eps: f64) -> (u64, u64) {
    if !(g > 0.0) {
        return (1, 1);
    }
    let stop = crate::numerics::math::ln(eps) - 3.0;
    let m0 = mode(g);
    let lw0 = log_conditioned_weight(m0, g);
    let lg = crate::numerics::math::ln(g);
    let mut lo = m0;
    let mut lw = lw0;
    while lo > 1 {
        if lw < stop {
            break;
        }
        lw += crate::numerics::math::ln(lo as f64) - lg;
        lo -= 1;
    }
    let mut hi = m0;
    lw = lw0;
    loop {
        if lw < stop {
            break;
        }
        lw += lg - crate::numerics::math::ln((hi + 1) as f64);
        hi += 1;
    }
    (lo, hi)
}

#[cfg(feature = "alloc")]
/// Draws an order m ≥ 1 from Poisson(g) conditioned on m ≥ 1, by inversion
/// starting at the mode (chop-down search both ways), from one uniform ξ.
///
/// Exact up to round-off for every g: the weights are formed in log space
/// relative to the mode and normalised by their own sum over the range
/// holding all but 1e−17 of the mass, so nothing overflows and g > 709 needs
/// no special case. Cost O(√g) per draw. For g < 1e−12, m = 1
/// (P(m ≥ 2 | m ≥ 1) < 1e−12).
pub(crate) fn sample_conditioned(g: f64, xi: f64) -> u64 {
    if !(g >= 1e-12) {
        return 1;
    }
    let (lo, hi) = term_range(g, 1e-17);
    let m0 = mode(g);
    // Unnormalised weights relative to the mode: left mass (lo..=m0) and right mass.
    let mut left = 0.0;
    let mut w = 1.0;
    let mut m = m0;
    loop {
        left += w;
        if m == lo {
            break;
        }
        w *= m as f64 / g;
        m -= 1;
    }
    let mut right = 0.0;
    w = 1.0;
    m = m0;
    while m < hi {
        w *= g / (m + 1) as f64;
        right += w;
        m += 1;
    }
    let total = left + right;
    let target = xi.clamp(0.0, 1.0) * total;
    if target < left {
        // Walk down from the mode: the mass of orders ≤ m is `acc`.
        let mut acc = left;
        let mut w = 1.0;
        let mut m = m0;
        loop {
            acc -= w;
            if target >= acc || m == lo {
                return m;
            }
            w *= m as f64 / g;
            m -= 1;
        }
    }
    let mut acc = left;
    let mut w = 1.0;
    let mut m = m0;
    while m < hi {
        w *= g / (m + 1) as f64;
        acc += w;
        m += 1;
        if target < acc {
            return m;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_match_direct() {
        for &g in &[1e-6, 1e-3, 0.5, 3.0, 40.0, 700.0, 710.0, 1e4] {
            let (lo, hi) = term_range(g, 1e-17);
            let s: f64 = (lo..=hi)
                .map(|m| crate::numerics::math::exp(log_conditioned_weight(m, g)))
                .sum();
            assert!((s - 1.0).abs() < 1e-13, "g={g}: {s}");
        }
        // Direct formula where it is safe.
        let g: f64 = 2.5;
        let direct = crate::numerics::math::exp(-g) * g.powi(3)
            / 6.0
            / (1.0 - crate::numerics::math::exp(-g));
        assert!(
            (crate::numerics::math::exp(log_conditioned_weight(3, g)) / direct - 1.0).abs() < 1e-14
        );
    }

    #[test]
    fn term_ranges_match_reference() {
        // data/reference/ghs_reference.json → extras.poisson_range_tol_1e-17
        let want = [
            (0.001, 1, 6),
            (0.1, 1, 11),
            (1.0, 1, 20),
            (10.0, 1, 50),
            (100.0, 25, 200),
            (1000.0, 736, 1288),
        ];
        for (g, lo, hi) in want {
            let (a, b) = term_range(g, 1e-17);
            assert!(
                (a as i64 - lo).abs() <= 1 && (b as i64 - hi).abs() <= 1,
                "g={g}: {a}-{b} vs {lo}-{hi}"
            );
        }
    }

    #[test]
    fn sampler_frequencies_match_weights() {
        // Stratified ξ: the empirical frequencies equal the weights to 1/n.
        for &g in &[1e-13, 1e-3, 0.7, 5.0, 300.0, 2000.0] {
            let n = 200_000;
            let (lo, hi) = term_range(g, 1e-17);
            let mut counts = alloc_counts(hi as usize + 2);
            for i in 0..n {
                let xi = (i as f64 + 0.5) / n as f64;
                let m = sample_conditioned(g, xi);
                assert!(m >= lo && m <= hi, "g={g} m={m}");
                counts[m as usize] += 1;
            }
            for m in lo..=hi {
                let p = if g < 1e-12 {
                    if m == 1 { 1.0 } else { 0.0 }
                } else {
                    crate::numerics::math::exp(log_conditioned_weight(m, g))
                };
                let f = counts[m as usize] as f64 / n as f64;
                assert!((f - p).abs() < 2.0 / n as f64, "g={g} m={m}: {f} vs {p}");
            }
        }
    }

    fn alloc_counts(n: usize) -> [u32; 4096] {
        assert!(n <= 4096);
        [0; 4096]
    }
}
