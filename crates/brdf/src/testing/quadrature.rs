//! Globally adaptive 2-D Gauss–Legendre cubature on unions of rectangles.
//!
//! Each panel is integrated by an 8 × 8 Gauss–Legendre rule on the whole
//! panel and on its four quarters; their difference is the (pessimistic)
//! error estimate. The panel with the largest estimate is split next, until
//! the summed estimate meets the tolerance or the evaluation budget runs out.
//! Narrow features must be bracketed by the initial panels (the callers grade
//! them towards the specular peak, or use equal-probability cells), because
//! a spike that falls between all nodes of a panel is invisible to it.

use alloc::collections::BinaryHeap;
use alloc::vec::Vec;
use core::cmp::Ordering;

const ORDER: usize = 8;

/// Nodes and weights of the `ORDER`-point Gauss–Legendre rule on [−1, 1]:
/// the positive half from [`crate::numerics::quadrature::gauss_legendre`],
/// then its mirror images, in decreasing order of the node.
fn gauss_legendre() -> ([f64; ORDER], [f64; ORDER]) {
    let (xh, wh) = crate::numerics::quadrature::gauss_legendre::<{ ORDER / 2 }>();
    let mut x = [0.0; ORDER];
    let mut w = [0.0; ORDER];
    for i in 0..ORDER / 2 {
        x[i] = xh[i];
        w[i] = wh[i];
        x[ORDER - 1 - i] = -xh[i];
        w[ORDER - 1 - i] = wh[i];
    }
    (x, w)
}

/// An axis-aligned rectangle `[x0, x1] × [y0, y1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Lower x bound.
    pub x0: f64,
    /// Upper x bound.
    pub x1: f64,
    /// Lower y bound.
    pub y0: f64,
    /// Upper y bound.
    pub y1: f64,
}

impl Rect {
    fn quarters(&self) -> [Rect; 4] {
        let xm = 0.5 * (self.x0 + self.x1);
        let ym = 0.5 * (self.y0 + self.y1);
        [
            Rect {
                x0: self.x0,
                x1: xm,
                y0: self.y0,
                y1: ym,
            },
            Rect {
                x0: xm,
                x1: self.x1,
                y0: self.y0,
                y1: ym,
            },
            Rect {
                x0: self.x0,
                x1: xm,
                y0: ym,
                y1: self.y1,
            },
            Rect {
                x0: xm,
                x1: self.x1,
                y0: ym,
                y1: self.y1,
            },
        ]
    }
}

/// Result of an adaptive integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integral {
    /// The integral.
    pub value: f64,
    /// Estimated absolute error (sum of panel estimates; usually pessimistic).
    pub error: f64,
    /// Integrand evaluations used.
    pub evals: usize,
    /// Whether the tolerance was met within the evaluation budget.
    pub converged: bool,
}

/// Tolerances and budget of [`Cubature::integrate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Absolute error target.
    pub abs: f64,
    /// Relative error target (relative to the integral).
    pub rel: f64,
    /// Maximum number of integrand evaluations.
    pub max_evals: usize,
}

struct Panel {
    rect: Rect,
    value: f64,
    error: f64,
    quarters: [f64; 4],
}

impl PartialEq for Panel {
    fn eq(&self, other: &Self) -> bool {
        self.error.total_cmp(&other.error) == Ordering::Equal
    }
}
impl Eq for Panel {}
impl PartialOrd for Panel {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Panel {
    fn cmp(&self, other: &Self) -> Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// A reusable 2-D adaptive Gauss–Legendre integrator.
#[derive(Clone, Debug)]
pub struct Cubature {
    nodes: [f64; ORDER],
    weights: [f64; ORDER],
}

impl Default for Cubature {
    fn default() -> Self {
        Cubature::new()
    }
}

impl Cubature {
    /// Builds the 8-point rule.
    pub fn new() -> Cubature {
        let (nodes, weights) = gauss_legendre();
        Cubature { nodes, weights }
    }

    /// Tensor-product rule on one rectangle.
    fn rule<F: FnMut(f64, f64) -> f64>(&self, f: &mut F, r: &Rect) -> f64 {
        let (cx, hx) = (0.5 * (r.x0 + r.x1), 0.5 * (r.x1 - r.x0));
        let (cy, hy) = (0.5 * (r.y0 + r.y1), 0.5 * (r.y1 - r.y0));
        let mut sum = 0.0;
        for (xi, wx) in self.nodes.iter().zip(&self.weights) {
            let x = cx + hx * xi;
            let mut row = 0.0;
            for (yj, wy) in self.nodes.iter().zip(&self.weights) {
                row += wy * f(x, cy + hy * yj);
            }
            sum += wx * row;
        }
        sum * hx * hy
    }

    fn panel<F: FnMut(f64, f64) -> f64>(&self, f: &mut F, rect: Rect, coarse: f64) -> Panel {
        let q = rect.quarters();
        let quarters = [
            self.rule(f, &q[0]),
            self.rule(f, &q[1]),
            self.rule(f, &q[2]),
            self.rule(f, &q[3]),
        ];
        let value = quarters.iter().sum::<f64>();
        let error = libm::fabs(value - coarse);
        // A NaN integrand must not hide as a zero error.
        let error = if error.is_nan() { f64::INFINITY } else { error };
        Panel {
            rect,
            value,
            error,
            quarters,
        }
    }

    /// Integrates `f(x, y)` over the union of `rects` (assumed disjoint).
    /// Degenerate rectangles are skipped.
    pub fn integrate<F: FnMut(f64, f64) -> f64>(
        &self,
        mut f: F,
        rects: &[Rect],
        tol: Tolerance,
    ) -> Integral {
        let per_rule = ORDER * ORDER;
        let mut heap = BinaryHeap::new();
        let mut evals = 0;
        for r in rects {
            if !(r.x1 > r.x0 && r.y1 > r.y0) {
                continue;
            }
            let coarse = self.rule(&mut f, r);
            heap.push(self.panel(&mut f, *r, coarse));
            evals += 5 * per_rule;
        }
        let totals = |heap: &BinaryHeap<Panel>| {
            heap.iter()
                .fold((0.0, 0.0), |(v, e), p| (v + p.value, e + p.error))
        };
        let (mut value, mut error) = totals(&heap);
        let mut since_resum = 0;
        while error > tol.abs.max(tol.rel * libm::fabs(value)) && evals < tol.max_evals {
            let Some(worst) = heap.pop() else { break };
            let parts = worst.rect.quarters();
            value -= worst.value;
            error -= worst.error;
            for (r, coarse) in parts.iter().zip(worst.quarters) {
                let p = self.panel(&mut f, *r, coarse);
                value += p.value;
                error += p.error;
                heap.push(p);
            }
            evals += 16 * per_rule;
            since_resum += 1;
            // Running sums drift by round-off; re-add from scratch now and then.
            if since_resum == 256 {
                (value, error) = totals(&heap);
                since_resum = 0;
            }
        }
        let (value, error) = totals(&heap);
        let converged = error <= tol.abs.max(tol.rel * libm::fabs(value));
        Integral {
            value,
            error,
            evals,
            converged,
        }
    }
}

/// Panel edges on `[lo, hi]` refined geometrically (ratio `ratio` > 1)
/// towards each focus, down to a smallest width `min_width`: a focus c gets
/// edges at c ± (hi − lo)/ratioᵏ. Sorted, deduplicated, including both ends.
pub fn graded_edges(lo: f64, hi: f64, foci: &[f64], ratio: f64, min_width: f64) -> Vec<f64> {
    let mut edges = Vec::new();
    edges.push(lo);
    edges.push(hi);
    for &c in foci {
        if !(c >= lo && c <= hi) {
            continue;
        }
        edges.push(c);
        let mut d = (hi - lo) / ratio;
        while d >= min_width {
            for e in [c - d, c + d] {
                if e > lo && e < hi {
                    edges.push(e);
                }
            }
            d /= ratio;
        }
    }
    edges.sort_by(f64::total_cmp);
    edges.dedup_by(|a, b| *a - *b < 0.5 * min_width);
    // Dedup keeps the first of a close pair; make sure `hi` is the last edge.
    if let Some(last) = edges.last_mut() {
        *last = hi;
    }
    edges
}

/// Panels covering `cell` that resolve mass concentrated in `core` (a
/// sub-rectangle of it): `core` itself, then rings around it whose width
/// triples each time (each ring split into up to 8 rectangles), until the
/// cell is covered. Used where the integrand is known to live mostly in
/// `core` but may have tails reaching across the cell.
pub fn rings_around(cell: Rect, core: Rect) -> Vec<Rect> {
    let min_w = 1e-12 * (cell.x1 - cell.x0).max(cell.y1 - cell.y0);
    let clamp = |r: Rect| Rect {
        x0: r.x0.max(cell.x0),
        x1: r.x1.min(cell.x1),
        y0: r.y0.max(cell.y0),
        y1: r.y1.min(cell.y1),
    };
    let mut inner = clamp(core);
    if !(inner.x1 >= inner.x0 && inner.y1 >= inner.y0) {
        return alloc::vec![cell];
    }
    let mut out = Vec::new();
    out.push(inner);
    for _ in 0..200 {
        let wx = (inner.x1 - inner.x0).max(min_w);
        let wy = (inner.y1 - inner.y0).max(min_w);
        let outer = clamp(Rect {
            x0: inner.x0 - wx,
            x1: inner.x1 + wx,
            y0: inner.y0 - wy,
            y1: inner.y1 + wy,
        });
        if outer == inner {
            break;
        }
        let xs = [outer.x0, inner.x0, inner.x1, outer.x1];
        let ys = [outer.y0, inner.y0, inner.y1, outer.y1];
        for i in 0..3 {
            for j in 0..3 {
                if i == 1 && j == 1 {
                    continue;
                }
                let r = Rect {
                    x0: xs[i],
                    x1: xs[i + 1],
                    y0: ys[j],
                    y1: ys[j + 1],
                };
                if r.x1 > r.x0 && r.y1 > r.y0 {
                    out.push(r);
                }
            }
        }
        inner = outer;
    }
    out
}

/// All rectangles of the tensor grid `xs × ys`.
pub fn grid(xs: &[f64], ys: &[f64]) -> Vec<Rect> {
    let mut out = Vec::with_capacity(xs.len().saturating_sub(1) * ys.len().saturating_sub(1));
    for x in xs.windows(2) {
        for y in ys.windows(2) {
            out.push(Rect {
                x0: x[0],
                x1: x[1],
                y0: y[0],
                y1: y[1],
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TIGHT: Tolerance = Tolerance {
        abs: 1e-12,
        rel: 1e-12,
        max_evals: 2_000_000,
    };

    #[test]
    fn rule_is_exact_for_polynomials() {
        let (x, w) = gauss_legendre();
        assert!(libm::fabs(w.iter().sum::<f64>() - 2.0) < 1e-14);
        // Degree 15 is integrated exactly by 8 points: ∫ x^14 = 2/15.
        let m: f64 = x.iter().zip(&w).map(|(x, w)| w * libm::pow(*x, 14.0)).sum();
        assert!(libm::fabs(m - 2.0 / 15.0) < 1e-14);
    }

    #[test]
    fn integrates_a_narrow_peak_bracketed_by_graded_edges() {
        // ∫∫ of a unit-mass Gaussian of width 1e-4 centred off-grid.
        let s = 1e-4;
        let (cx, cy) = (0.3137, -0.271);
        let f = |x: f64, y: f64| {
            let r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (s * s);
            libm::exp(-0.5 * r2) / (2.0 * core::f64::consts::PI * s * s)
        };
        let xs = graded_edges(-1.0, 1.0, &[cx], 4.0, 1e-7);
        let ys = graded_edges(-1.0, 1.0, &[cy], 4.0, 1e-7);
        let r = Cubature::new().integrate(f, &grid(&xs, &ys), TIGHT);
        assert!(r.converged, "{r:?}");
        assert!(libm::fabs(r.value - 1.0) < 1e-10, "{r:?}");
        // Without the graded edges the peak is missed entirely: the harness
        // callers must bracket narrow lobes.
        let blind = Cubature::new().integrate(
            f,
            &[Rect {
                x0: -1.0,
                x1: 1.0,
                y0: -1.0,
                y1: 1.0,
            }],
            TIGHT,
        );
        assert!(blind.value < 1e-3);
    }

    #[test]
    fn handles_discontinuity_and_reports_budget_exhaustion() {
        // Indicator of the unit disc: area π, slow (line singularity).
        let f = |x: f64, y: f64| if x * x + y * y < 1.0 { 1.0 } else { 0.0 };
        let r = Cubature::new().integrate(
            f,
            &[Rect {
                x0: -1.0,
                x1: 1.0,
                y0: -1.0,
                y1: 1.0,
            }],
            Tolerance {
                abs: 1e-4,
                rel: 0.0,
                max_evals: 3_000_000,
            },
        );
        assert!(
            r.converged && libm::fabs(r.value - core::f64::consts::PI) < 1e-4,
            "{r:?}"
        );
        let starved = Cubature::new().integrate(
            f,
            &[Rect {
                x0: -1.0,
                x1: 1.0,
                y0: -1.0,
                y1: 1.0,
            }],
            Tolerance {
                abs: 1e-12,
                rel: 0.0,
                max_evals: 10_000,
            },
        );
        assert!(!starved.converged);
    }

    #[test]
    fn rings_tile_the_cell_and_resolve_a_corner_peak() {
        let cell = Rect {
            x0: 0.0,
            x1: 1.0,
            y0: -3.0,
            y1: 3.0,
        };
        let core = Rect {
            x0: 0.9990,
            x1: 0.9995,
            y0: 2.9,
            y1: 2.9004,
        };
        let rings = rings_around(cell, core);
        let area: f64 = rings.iter().map(|r| (r.x1 - r.x0) * (r.y1 - r.y0)).sum();
        assert!(libm::fabs(area - 6.0) < 1e-12);
        // Exponential tails of scale 1e-4 leaving the core.
        let f = |x: f64, y: f64| {
            libm::exp(-(libm::fabs(x - 0.99925) + libm::fabs(y - 2.9002)) / 1e-4) / 4e-8
        };
        let r = Cubature::new().integrate(f, &rings, TIGHT);
        let want =
            (1.0 - 0.5 * libm::exp(-0.00075 / 1e-4)) * (1.0 - 0.5 * libm::exp(-0.0998 / 1e-4));
        assert!(libm::fabs(r.value - want) < 1e-9, "{r:?} vs {want}");
    }

    #[test]
    fn graded_edges_are_sorted_and_bracket_foci() {
        let e = graded_edges(0.0, 1.0, &[0.0, 0.37, 1.0], 2.0, 1e-6);
        assert_eq!(e[0], 0.0);
        assert_eq!(*e.last().unwrap(), 1.0);
        assert!(e.windows(2).all(|w| w[1] > w[0]));
        assert!(e.contains(&0.37));
        assert!(e[1] < 2e-6 && 1.0 - e[e.len() - 2] < 2e-6);
    }
}
