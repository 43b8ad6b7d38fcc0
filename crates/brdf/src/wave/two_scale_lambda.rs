//! The Smith Λ of a tabulated isotropic NDF ([`super::two_scale_table`]'s
//! rows) at many directions from one set of quadrature nodes.
//!
//! 1 + Λ(θ) = (1/cosθ) Σ_k w_k P(θ, θm_k), with P the ring projection
//! ∫₀^{2π} max(0, ω·m) dφ. With T = tanθ, t = tanθm and x = T·t, P is
//! 2π cosθ cosθm for x ≤ 1 (the whole ring faces ω) and otherwise
//! 2π cosθ cosθm + 2 cosθ cosθm·h(x), h(x) = √(x² − 1) − acos(1/x). For
//! x ≥ [`SERIES_FROM`], h(x) = x − π/2 + Σₙ hₙ x^{−(2n−1)} converges fast,
//! and every term is a power of T times a moment of the nodes: with the nodes
//! ascending in t, sums over the nodes beyond any x are suffix sums made once
//! per row. Only nodes with 1 < x < [`SERIES_FROM`] (a factor 6 in tanθm:
//! ~30 of a row's ~180) need the acos.

use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;

/// x = tanθ·tanθm from which h(x) is taken by its series.
const SERIES_FROM: f64 = 6.0;

/// Terms hₙ x^{−(2n−1)} of the series: all are positive and the next would
/// be ≤ h₁₁·6^{−21} = 1.7e−20 (h ≥ 6 − π/2 there).
const TERMS: usize = 10;

/// ∫₀^{2π} max(0, ω·m) dφ for ω, m at polar angles θ, θm (cosines `c`,
/// `cm`, sines `s`, `sm`), φ the azimuth between them.
#[inline]
pub(crate) fn ring_projection(c: f64, s: f64, cm: f64, sm: f64) -> f64 {
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

/// Smith 1 + Λ(θ) = (1/cosθ) ∫ D(m) max(0, ω·m) dω_m from quadrature nodes
/// (weight = D sinθm dθm, cosθm, sinθm), node by node: the reference of
/// [`RingSums`] in the tests.
#[cfg(test)]
pub(crate) fn one_plus_lambda(nodes: &[(f64, f64, f64)], tan_t: f64) -> f64 {
    let c = 1.0 / libm::sqrt(1.0 + tan_t * tan_t);
    let s = tan_t * c;
    let sum: f64 = nodes
        .iter()
        .map(|&(w, cm, sm)| w * ring_projection(c, s, cm, sm))
        .sum();
    sum / c
}

/// Coefficients hₙ of h(x) = x − π/2 + Σₙ hₙ x^{−(2n−1)}: with
/// cₘ = C(2m, m)/4^m, hₙ = c_{n−1}/((2n − 1)·2n) (the difference of the
/// series of √(1 − u²)/u and of asin u, u = 1/x).
fn series_coefficients() -> [f64; TERMS] {
    let mut out = [0.0; TERMS];
    let mut c = 1.0;
    for (i, o) in out.iter_mut().enumerate() {
        let n = (i + 1) as f64;
        *o = c / ((2.0 * n - 1.0) * 2.0 * n);
        // c_n = c_{n−1}·(2n − 1)/(2n).
        c *= (2.0 * n - 1.0) / (2.0 * n);
    }
    out
}

/// One row's nodes with the sums [`RingSums::one_plus_lambda`] needs.
pub(crate) struct RingSums<'a> {
    nodes: &'a [(f64, f64, f64)],
    /// tanθm per node, ascending.
    t: Vec<f64>,
    /// Σ_{j<k} w cosθm (prefix sums, n + 1 entries).
    head: Vec<f64>,
    /// Suffix sums Σ_{j≥k}, n + 1 entries per moment: w cosθm, w sinθm,
    /// then w cosθm t^{−(2n−1)} for n = 1..=TERMS.
    tail: Vec<[f64; TERMS + 2]>,
    h: [f64; TERMS],
}

impl<'a> RingSums<'a> {
    /// `nodes` as [`one_plus_lambda`] takes them, ascending in θm (as
    /// `ring_nodes` makes them).
    pub(crate) fn new(nodes: &'a [(f64, f64, f64)]) -> Self {
        let n = nodes.len();
        let t: Vec<f64> = nodes.iter().map(|&(_, cm, sm)| sm / cm).collect();
        let mut head = vec![0.0; n + 1];
        for (k, &(w, cm, _)) in nodes.iter().enumerate() {
            head[k + 1] = head[k] + w * cm;
        }
        let mut tail = vec![[0.0; TERMS + 2]; n + 1];
        for k in (0..n).rev() {
            let (w, cm, sm) = nodes[k];
            let mut row = tail[k + 1];
            row[0] += w * cm;
            row[1] += w * sm;
            // Only summed from nodes with x ≥ SERIES_FROM, so t^{−21} stays
            // finite for any node the sum is read at (t ≥ 6/T ≥ 6e−6).
            let inv_t2 = 1.0 / (t[k] * t[k]);
            let mut p = w * cm / t[k];
            for m in row[2..].iter_mut() {
                *m += p;
                p *= inv_t2;
            }
            tail[k] = row;
        }
        RingSums {
            nodes,
            t,
            head,
            tail,
            h: series_coefficients(),
        }
    }

    /// 1 + Λ at tanθ: [`one_plus_lambda`] with the nodes beyond x = 6 by
    /// the series (within a few 1e−16 of it, relative).
    pub(crate) fn one_plus_lambda(&self, tan_t: f64) -> f64 {
        let n = self.t.len();
        // Nodes with x ≤ 1 (the whole ring faces ω), then those below the series.
        let j0 = self.t.partition_point(|&t| tan_t * t <= 1.0);
        let j1 = j0 + self.t[j0..].partition_point(|&t| tan_t * t < SERIES_FROM);
        let c = 1.0 / libm::sqrt(1.0 + tan_t * tan_t);
        let s = tan_t * c;
        let middle: f64 = self.nodes[j0..j1]
            .iter()
            .map(|&(w, cm, sm)| w * ring_projection(c, s, cm, sm))
            .sum();
        let mut out = 2.0 * PI * self.head[j0] + middle / c;
        if j1 < n {
            let m = &self.tail[j1];
            // Σ w cosθm (2π + 2h(x)) = Σ w cosθm (π + 2x + 2Σ hₙ x^{1−2n}).
            let inv_t = 1.0 / tan_t;
            let inv_t2 = inv_t * inv_t;
            let mut series = 0.0;
            let mut p = inv_t;
            for (hn, mn) in self.h.iter().zip(&m[2..]) {
                series += hn * p * mn;
                p *= inv_t2;
            }
            out += PI * m[0] + 2.0 * tan_t * m[1] + 2.0 * series;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// h(x) by its series against √(x² − 1) − acos(1/x) from x = 6 up.
    #[test]
    fn series_matches_h() {
        let h = series_coefficients();
        for e in 0..=200 {
            let x = 6.0 * libm::pow(1e6, e as f64 / 200.0);
            let exact = libm::sqrt(x * x - 1.0) - libm::acos(1.0 / x);
            let mut s = x - 0.5 * PI;
            for (n, hn) in h.iter().enumerate() {
                s += hn * libm::pow(x, -(2.0 * n as f64 + 1.0));
            }
            // The exact form itself rounds x² − 1 and the difference: ~1 ulp of x.
            assert!((s - exact).abs() <= 1e-15 * x, "x {x}: {s} vs {exact}");
        }
    }

    /// The sums against the node-by-node projections, for a narrow and a
    /// wide lobe, at tanθ from 0 past every node's x = 1 and x = 6.
    #[test]
    fn sums_match_node_by_node() {
        for (tau, spread) in [(7.2e-4, 12.0), (0.3, 8.0)] {
            // Nodes ascending in t over a sinh grid, a Gaussian-ish D.
            let nodes: Vec<(f64, f64, f64)> = (0..180)
                .map(|k| {
                    let t: f64 = tau * libm::sinh(spread * (k as f64 + 0.5) / 180.0);
                    let cm = 1.0 / libm::sqrt(1.0 + t * t);
                    let w = libm::exp(-t / tau) * (1.0 + t) * 1e-2;
                    (w, cm, t * cm)
                })
                .collect();
            let sums = RingSums::new(&nodes);
            for e in 0..=600 {
                let tan_t = if e == 0 {
                    0.0
                } else {
                    1e-3 * libm::pow(1e9, e as f64 / 600.0)
                };
                let want = one_plus_lambda(&nodes, tan_t);
                let got = sums.one_plus_lambda(tan_t);
                assert!(
                    (got - want).abs() <= 1e-13 * want,
                    "τ {tau} tanθ {tan_t}: {got:e} vs {want:e}"
                );
            }
        }
    }
}
