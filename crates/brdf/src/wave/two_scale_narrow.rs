//! A Gauss rule for the two-scale convolution when the macro NDF is narrow
//! against the kernel ([`super::two_scale_table`]).
//!
//! D_eff(θh) = ∫ D(θm) sinθm R(θh, θm) dθm, with R the kernel's integral
//! around the ring of m at polar angle θm. R is even and analytic in θm
//! (a mean of a smooth function over a circle of radius θm about the pole)
//! as long as the kernel is smooth on the circle: K varies on the scale
//! 1/w and is cut at ψ = 90°. When β·w is small, D's mass lies where R is a
//! low-degree polynomial in x = θm², so an n-point Gauss rule for the
//! measure D(θm) sinθm dθm in x integrates it to high order with n ring
//! integrals instead of the nested rule's ~30.

use crate::numerics::quadrature::{gl4_nodes, panel_edges};
use crate::statistics::epd::ExponentialNdf;

/// Nodes of the rule.
const N: usize = 5;

/// Largest β·w at which the rule is used (beyond, the nested rule).
pub(crate) const NARROW_BW_MAX: f64 = 0.07;

/// tanθm, in units of β, beyond which a kink of the ring integral (where
/// rings reach ψ = 90°) is ignored.
const REACH_BETAS: f64 = 20.0;

/// The rule: per node θm, sinθm, cosθm and its weight (D sinθm dθm).
#[derive(Clone, Debug)]
pub(crate) struct NarrowRule {
    nodes: [(f64, f64, f64, f64); N],
    /// θm beyond which D's mass is negligible ([`REACH_BETAS`]).
    reach: f64,
}

impl NarrowRule {
    /// The rule for `ndf`, from the Stieltjes procedure on a fine discrete
    /// measure (stable where moments are not: they grow like (2j + 1)!β^{2j}).
    pub(crate) fn new(ndf: &ExponentialNdf) -> Option<NarrowRule> {
        let beta = ndf.beta();
        // D is below e^{−45} of its peak beyond tanθm = 45β.
        let reach = libm::atan(45.0 * beta);
        let mut edges = alloc::vec::Vec::new();
        panel_edges(0.0, reach, &[(0.0, 0.02 * beta)], 1.25, &mut edges);
        // The measure in x = (θm/β)², scaled so the recurrence stays O(1).
        let measure: alloc::vec::Vec<(f64, f64)> = gl4_nodes(&edges)
            .into_iter()
            .map(|(tm, w)| {
                let (sm, cm) = libm::sincos(tm);
                let x = (tm / beta) * (tm / beta);
                (x, w * ndf.d_tan_cos(sm / cm, cm) * sm)
            })
            .collect();
        let (a, b, h) = recurrence(&measure);
        let xs = jacobi_eigenvalues(&a, &b)?;
        let mut nodes = [(0.0, 0.0, 0.0, 0.0); N];
        for (k, &x) in xs.iter().enumerate() {
            // Christoffel weight 1/Σ p_j(x)²/h_j, monic p_j by the recurrence.
            let (mut p0, mut p1) = (0.0, 1.0);
            let mut sum = 1.0 / h[0];
            for j in 0..N - 1 {
                let p2 = (x - a[j]) * p1 - if j > 0 { b[j] * p0 } else { 0.0 };
                (p0, p1) = (p1, p2);
                sum += p1 * p1 / h[j + 1];
            }
            let tm = beta * libm::sqrt(x.max(0.0));
            let (sm, cm) = libm::sincos(tm);
            nodes[k] = (tm, sm, cm, 1.0 / sum);
        }
        let ok = nodes
            .iter()
            .all(|n| n.0.is_finite() && n.3.is_finite() && n.3 > 0.0 && n.0 < reach);
        // The ring integral has a kink where the ring reaches ψ = 90°;
        // D's mass beyond tanθm = 20β is (1 + 20)e^{−20} = 4.3e−8 of it (with
        // 10β the rule is 1.7e−5 off near the horizon, with 15β 4e−7).
        let reach = libm::atan(REACH_BETAS * beta);
        ok.then_some(NarrowRule { nodes, reach })
    }

    /// The nodes (θm, sinθm, cosθm, weight).
    pub(crate) fn nodes(&self) -> &[(f64, f64, f64, f64); N] {
        &self.nodes
    }

    /// Whether the rule holds for w: the kernel is smooth on D's support
    /// (β·w small).
    pub(crate) fn holds(&self, beta: f64, w: f64) -> bool {
        beta * w <= NARROW_BW_MAX
    }

    /// Whether rings of D's support at θh reach ψ = 90°, where the ring
    /// integral has a kink (the caller then integrates the kernel over
    /// whole rings and takes the part beyond ψ = 90° off separately).
    pub(crate) fn reaches_horizon(&self, theta_h: f64) -> bool {
        theta_h + self.reach >= core::f64::consts::FRAC_PI_2
    }
}

/// Monic orthogonal-polynomial recurrence p_{j+1} = (x − a_j) p_j − b_j p_{j−1}
/// of a discrete measure (Stieltjes), with h_j = Σ w p_j².
fn recurrence(measure: &[(f64, f64)]) -> ([f64; N], [f64; N], [f64; N]) {
    let (mut a, mut b, mut h) = ([0.0; N], [0.0; N], [0.0; N]);
    let mut p_prev = alloc::vec![0.0; measure.len()];
    let mut p = alloc::vec![1.0; measure.len()];
    for j in 0..N {
        let (mut hj, mut xj) = (0.0, 0.0);
        for (&(x, w), &pi) in measure.iter().zip(&p) {
            hj += w * pi * pi;
            xj += w * x * pi * pi;
        }
        h[j] = hj;
        a[j] = xj / hj;
        if j > 0 {
            b[j] = hj / h[j - 1];
        }
        for (i, &(x, _)) in measure.iter().enumerate() {
            let next = (x - a[j]) * p[i] - b[j] * p_prev[i];
            p_prev[i] = p[i];
            p[i] = next;
        }
    }
    (a, b, h)
}

/// Eigenvalues of the symmetric tridiagonal Jacobi matrix (diagonal `a`,
/// squared off-diagonal `b[1..]`), ascending, by Sturm-sequence bisection.
fn jacobi_eigenvalues(a: &[f64; N], b: &[f64; N]) -> Option<[f64; N]> {
    // Gershgorin bounds.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..N {
        let r = if i > 0 { libm::sqrt(b[i]) } else { 0.0 }
            + if i + 1 < N { libm::sqrt(b[i + 1]) } else { 0.0 };
        lo = lo.min(a[i] - r);
        hi = hi.max(a[i] + r);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    // Number of eigenvalues below x.
    let below = |x: f64| {
        let (mut count, mut q) = (0, 1.0);
        for i in 0..N {
            let off = if i > 0 { b[i] / q } else { 0.0 };
            q = a[i] - x - off;
            if q == 0.0 {
                q = -1e-300;
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    let mut out = [0.0; N];
    for (k, o) in out.iter_mut().enumerate() {
        let (mut l, mut h) = (lo, hi);
        for _ in 0..200 {
            let m = 0.5 * (l + h);
            if m <= l || m >= h {
                break;
            }
            if below(m) > k {
                h = m;
            } else {
                l = m;
            }
        }
        *o = 0.5 * (l + h);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates D sinθm θm^{2j} for j < 2N (against a finer
    /// graded rule; j = 0: its weights sum to ∫ D sinθm dθm).
    #[test]
    fn rule_integrates_even_powers() {
        for beta in [1e-4, 7.2e-4, 5e-3, 0.02] {
            let ndf = ExponentialNdf::new(beta).unwrap();
            let rule = NarrowRule::new(&ndf).unwrap();
            let reach = libm::atan(45.0 * beta);
            let mut edges = alloc::vec::Vec::new();
            panel_edges(0.0, reach, &[(0.0, 0.01 * beta)], 1.2, &mut edges);
            for j in 0..2 * N {
                let want: f64 = gl4_nodes(&edges)
                    .into_iter()
                    .map(|(tm, w)| {
                        let (sm, cm) = libm::sincos(tm);
                        w * ndf.d_tan_cos(sm / cm, cm) * sm * libm::pow(tm / beta, 2.0 * j as f64)
                    })
                    .sum();
                let got: f64 = rule
                    .nodes()
                    .iter()
                    .map(|n| n.3 * libm::pow(n.0 / beta, 2.0 * j as f64))
                    .sum();
                // The rule's own discrete measure (panel ratio 1.25) is
                // within ~2e−8 of this one.
                assert!(
                    (got - want).abs() <= 1e-7 * want,
                    "β {beta} j {j}: {got:e} vs {want:e}"
                );
            }
        }
    }
}
