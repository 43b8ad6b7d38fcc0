//! Gauss–Legendre quadrature: the n-point rule on [−1, 1] ([`gauss_legendre`],
//! the one source of its nodes and weights, also behind the `testing`
//! cubature) and, with `alloc`, 4-point rules on graded panels, shared by the
//! table builders that integrate peaked lobes (the two-scale convolution and
//! the albedo cap).

use core::f64::consts::PI;

#[cfg(feature = "alloc")]
use alloc::vec::Vec;

/// Nodes and weights of n-point Gauss–Legendre on [−1, 1], positive half
/// (n even): `nodes[i]`, `weights[i]` for i < n/2, with the mirror images
/// implied. Newton iteration on P_n, accurate to round-off.
pub fn gauss_legendre<const H: usize>() -> ([f64; H], [f64; H]) {
    let n = 2 * H;
    let mut x = [0.0; H];
    let mut w = [0.0; H];
    for i in 0..H {
        let mut z = libm::cos(PI * (i as f64 + 0.75) / (n as f64 + 0.5));
        let mut dp = 1.0;
        for _ in 0..100 {
            let mut p0 = 1.0;
            let mut p1 = z;
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

#[cfg(feature = "alloc")]
/// 4-point Gauss–Legendre on [−1, 1]: the positive nodes and their weights.
pub(crate) const GL4_X: [f64; 2] = [0.339_981_043_584_856_3, 0.861_136_311_594_052_6];
#[cfg(feature = "alloc")]
pub(crate) const GL4_W: [f64; 2] = [0.652_145_154_862_546_1, 0.347_854_845_137_453_9];

#[cfg(feature = "alloc")]
/// ∫_a^b f by 4-point Gauss–Legendre.
#[inline]
pub(crate) fn gl4(a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
    let mut s = 0.0;
    for j in 0..2 {
        s += GL4_W[j] * (f(c - r * GL4_X[j]) + f(c + r * GL4_X[j]));
    }
    s * r
}

#[cfg(feature = "alloc")]
/// The nodes and weights of [`gl4`] on every panel of `edges`, for integrals
/// whose integrand setup is worth doing once per node.
pub fn gl4_nodes(edges: &[f64]) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(4 * edges.len());
    for e in edges.windows(2) {
        let (c, r) = (0.5 * (e[0] + e[1]), 0.5 * (e[1] - e[0]));
        for j in 0..2 {
            out.push((c - r * GL4_X[j], r * GL4_W[j]));
            out.push((c + r * GL4_X[j], r * GL4_W[j]));
        }
    }
    out
}

#[cfg(feature = "alloc")]
/// ∫₀^hi f by [`gl4`] on the panels [`panel_edges`] makes for one focus at
/// 0 with scale `first` (0, first, first·grading, …, hi), generated in order:
/// no allocation or sort, for inner integrals evaluated millions of times.
#[inline]
pub(crate) fn gl4_graded_from_zero(
    hi: f64,
    first: f64,
    grading: f64,
    mut f: impl FnMut(f64) -> f64,
) -> f64 {
    let mut sum = 0.0;
    // A non-positive or NaN first width means one panel.
    let first = if first > 0.0 { first } else { hi };
    let (mut a, mut d) = (0.0, first.min(hi));
    loop {
        // An edge within 1e−9 of hi merges with it (as panel_edges' dedup).
        let b = if d >= hi * (1.0 - 1e-9) { hi } else { d };
        sum += gl4(a, b, &mut f);
        if b >= hi {
            return sum;
        }
        a = b;
        d *= grading;
    }
}

#[cfg(feature = "alloc")]
/// Sorted panel edges on [lo, hi] into `out`: the ends and, for every
/// (center, scale) in `foci`, the center and the geometric sequences
/// `center ± scale·grading^j`.
pub(crate) fn panel_edges(lo: f64, hi: f64, foci: &[(f64, f64)], grading: f64, out: &mut Vec<f64>) {
    out.clear();
    out.push(lo);
    out.push(hi);
    for &(c, scale) in foci {
        if !(scale > 0.0) {
            continue;
        }
        if c > lo && c < hi {
            out.push(c);
        }
        let mut d = scale;
        while d < hi - lo {
            for x in [c - d, c + d] {
                if x > lo && x < hi {
                    out.push(x);
                }
            }
            d *= grading;
        }
    }
    out.sort_by(|a, b| a.total_cmp(b));
    let span = hi - lo;
    out.dedup_by(|b, a| (*b - *a).abs() <= 1e-9 * span);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre::<8>();
        let mut s = 0.0;
        let mut s_w = 0.0;
        for i in 0..8 {
            s += 2.0 * w[i] * x[i] * x[i] * x[i] * x[i] * x[i] * x[i] * x[i] * x[i] * x[i] * x[i];
            s_w += 2.0 * w[i];
        }
        assert!((s - 2.0 / 11.0).abs() < 1e-15 && (s_w - 2.0).abs() < 1e-14);
    }

    /// The allocation-free graded rule is the same sum as gl4 over
    /// panel_edges with one focus at 0, and integrates a peaked function.
    #[test]
    fn graded_from_zero_matches_panel_edges() {
        let f = |x: f64| 1.0 / (1.0 + 1e4 * x * x);
        for (hi, first) in [(3.0f64, 1e-3f64), (1.0, 0.4), (2.0, 5.0), (1.0, 0.0)] {
            let mut edges = Vec::new();
            panel_edges(0.0, hi, &[(0.0, first.min(hi))], 3.0, &mut edges);
            let want: f64 = edges.windows(2).map(|p| gl4(p[0], p[1], f)).sum();
            let got = gl4_graded_from_zero(hi, first, 3.0, f);
            assert!(
                (got - want).abs() <= 1e-14 * want,
                "hi {hi} first {first}: {got} vs {want}"
            );
        }
        let exact = libm::atan(100.0 * 3.0) / 100.0;
        let got = gl4_graded_from_zero(3.0, 1e-3, 3.0, f);
        assert!((got / exact - 1.0).abs() < 1e-4, "{got} vs {exact}");
    }
}
