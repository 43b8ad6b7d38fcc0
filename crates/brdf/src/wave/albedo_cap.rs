//! A reciprocal energy cap for models whose single-scattering albedo can
//! exceed 1 (the two-scale model at grazing incidence: its NDF changes with
//! θd across the lobe, so the microfacet identity ∫ D_vis G₂/G₁ ≤ 1 no
//! longer holds).
//!
//! With E(μ) the albedo of the glossy part and S(μ) the delta weight (both
//! with F = 1) at incidence cosine μ, let C(μ) = E(μ)/(1 − S(μ)). Dividing
//! the glossy BRDF by max(1, C(μi), C(μo)) keeps it reciprocal and bounds
//! the new albedo: S(μi) + ∫ f cosθo / max(1, C(μi), C(μo)) dωo ≤
//! S(μi) + E(μi)/max(1, C(μi)) ≤ 1. Where C ≤ 1 everywhere nothing changes.
//!
//! C is tabulated on incidence angles × wavenumbers and interpolated in
//! cosθ by the larger of the chord and a cubic Hermite curve (which follows
//! a concave peak between nodes), by the cubic through the four wavenumber
//! nodes in k (C is smooth but far from linear in k), the angles refined
//! where the interpolation would fall below C; E comes from a product Gauss–Legendre rule over the
//! half vector (θh, φh), on θh panels graded away from the pole on the scale
//! of the lobe ([`albedo_many_half`]).

use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;

use crate::numerics::quadrature::gl4_nodes;
#[cfg(test)]
use crate::numerics::quadrature::panel_edges;

/// Incidence angles of the table, degrees: denser towards grazing, where
/// the excess lives and C peaks (between 89.7° and 89.9° in the materials
/// measured). C is smooth below 84° but not always monotone (β 2e−3,
/// σ 1 µm, Lc 1 µm, γ 3: 1.009 at 0°, 0.874 at 60° at 830 nm), which the
/// refinement resolves. Over nine materials (β 1e−4–0.1), with the
/// refinement these nodes take 20–30 albedo integrals (the earlier
/// 0, 60, 70, 75, 80, 84, 87, 89, 89.9° with chords 20–42), keep the table
/// ≥ 1.00068·C on a 0.05° grid over 84–89.9° and at 11 angles below, and
/// above max(1, C) by at most 5.1 % (chords: 9.7 %).
const THETA_DEG: [f64; 9] = [0.0, 60.0, 70.0, 80.0, 84.0, 87.0, 89.0, 89.5, 89.9];

/// Relative allowance for the table's quadrature and interpolation error
/// (measured up to 6e−4 between nodes): C is inflated by it, so that the
/// capped albedo stays ≤ 1 between nodes too.
const MARGIN: f64 = 1e-3;

/// Indices into [`THETA_DEG`] screened first (0°, 84°, 89°, 89.9°): the
/// excess is a grazing effect on most surfaces, but very steep ones (σ/Lc
/// ≈ 46) exceed 1 at normal incidence and not at grazing.
const SCREEN: [usize; 4] = [0, 4, 6, 8];

/// How far below 1 the largest screened C·(1 + [`MARGIN`]) may be and still
/// call for the table: the screen takes the maximum over k of the cubic
/// through the wavenumber nodes (C can peak between them), whose own error
/// is this large ([`K_NODES`]).
const SCREEN_SLACK: f64 = 2e-3;

/// Wavenumber nodes, uniform in k between the ends of the visible range,
/// joined by the cubic through all four. C is smooth in k but not linear:
/// it often peaks inside the range (β 4e−4, σ 0.05 µm, Lc 0.036 µm, γ 2 at
/// 84°: 1.4005 at 830 nm, 1.4598 at 502 nm, 1.4184 at 360 nm), where
/// three nodes joined by chords held 0.9869·C (the albedo reached 1.0101).
/// Over 12 materials (β 1e−4–0.3, σ/Lc 0.05–1.4, γ 1.1–4, both readings,
/// 9 angles 0–89.9°, 61 wavenumbers, where C > 0.97) the cubic through
/// four nodes stays within 0.99858…1.0008 of C (chords: 0.9933; five
/// nodes' quartic: 0.99953, at two thirds more wavenumber work).
const K_NODES: usize = 4;

/// Ratio of the distances of a θh panel's far and near ends from a focus
/// of [`graded_edges`]. 2.5 integrates a Gaussian lobe of width 0.05 at
/// 89.9° 1.1e−4 low (`half_vector_rule_matches_the_outgoing_rule`, limit
/// 1e−4); 2.2 within 8.0e−5, where the union of geometric sequences
/// graded by 2.5 that it replaces was 9.7e−5.
const GRADING: f64 = 2.2;

/// Ratio of successive panel widths of the (cosθo, φo) reference rule.
#[cfg(test)]
const REFERENCE_GRADING: f64 = 2.5;

/// The tabulated cap C(μ, k) ≥ 1.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AlbedoCap {
    /// cos θ at the nodes, descending (θ ascending).
    mu: Vec<f64>,
    k_lo: f64,
    k_hi: f64,
    /// c[ik · mu.len() + iμ].
    c: Vec<f64>,
    /// dC/dμ at the nodes, laid out as `c` ([`node_slopes`]).
    d: Vec<f64>,
}

impl AlbedoCap {
    /// Builds the table from `ratio(μ, ks, out)`, which writes E/(1 − S)
    /// at incidence cosine μ for each wavenumber of `ks` into `out` (the
    /// wavenumbers of one μ share one quadrature: its directions, and what
    /// depends on them alone, are computed once); `None` when the ratio
    /// stays ≤ 1 (the model needs no cap).
    ///
    /// The excess is mostly a grazing-incidence effect, and on very steep
    /// surfaces one at normal incidence, so the ratio is first screened at
    /// the [`SCREEN`] angles for the two extreme wavenumbers, and the full
    /// table is built only when one of them exceeds 1: most materials pay 8
    /// albedo integrals instead of 20–30.
    pub(crate) fn build(
        k_lo: f64,
        k_hi: f64,
        ratio: impl Fn(f64, &[f64], &mut [f64]) + Sync,
    ) -> Option<AlbedoCap> {
        let mu: Vec<f64> = THETA_DEG
            .iter()
            .map(|t| libm::cos(t.to_radians()))
            .collect();
        let k_node = |ik: usize| k_lo + (k_hi - k_lo) * ik as f64 / (K_NODES - 1) as f64;
        let ks: [f64; K_NODES] = core::array::from_fn(k_node);
        let screen = crate::parallel::map_rows(SCREEN.len(), |j| {
            let mut r = [0.0; K_NODES];
            ratio(mu[SCREEN[j]], &ks, &mut r);
            r
        });
        if !screen
            .iter()
            .any(|r| k_cubic_max(r) * (1.0 + MARGIN) > 1.0 - SCREEN_SLACK)
        {
            return None;
        }
        // Not floored at 1 here: the interpolants pass through the nodes'
        // own values, and the floor is taken after interpolation.
        let stored = |r: f64| {
            if r.is_finite() {
                r * (1.0 + MARGIN)
            } else {
                1.0
            }
        };
        let mut columns: Vec<(f64, [f64; K_NODES])> = crate::parallel::map_rows(mu.len(), |im| {
            let mut r = [0.0; K_NODES];
            match SCREEN.iter().position(|&s| s == im) {
                Some(p) => r = screen[p],
                None => ratio(mu[im], &ks, &mut r),
            }
            (mu[im], r.map(stored))
        });
        refine(&mut columns, |m, out| {
            ratio(m, &ks, out);
            for v in out.iter_mut() {
                *v = stored(*v);
            }
        });
        let mu: Vec<f64> = columns.iter().map(|c| c.0).collect();
        let c: Vec<f64> = (0..K_NODES)
            .flat_map(|ik| columns.iter().map(move |col| col.1[ik]))
            .collect();
        let d = c
            .chunks(mu.len())
            .flat_map(|r| node_slopes(&mu, r))
            .collect();
        Some(AlbedoCap {
            mu,
            k_lo,
            k_hi,
            c,
            d,
        })
    }

    /// The largest C of the table at its angle nodes, over wavenumbers
    /// (the cubic in k can peak between its nodes): at least 1.
    pub(crate) fn peak(&self) -> f64 {
        let n = self.mu.len();
        (0..n)
            .map(|i| k_cubic_max(&core::array::from_fn(|ik| self.c[ik * n + i])))
            .fold(1.0, f64::max)
    }

    /// max(1, C(cos_a, k), C(cos_b, k)), the divisor of a reciprocal BRDF,
    /// with the wavenumber weights found once.
    pub(crate) fn max_at(&self, cos_a: f64, cos_b: f64, k: f64) -> f64 {
        let t = ((k - self.k_lo) / (self.k_hi - self.k_lo)).clamp(0.0, 1.0);
        let w = k_weights(t);
        self.at(cos_a, &w).max(self.at(cos_b, &w)).max(1.0)
    }

    /// C at incidence cosine `cos` (clamped to the table) with the
    /// wavenumber weights `w` of [`k_weights`].
    fn at(&self, cos: f64, w: &[f64; K_NODES]) -> f64 {
        let n = self.mu.len();
        // μ nodes descend; find the interval [μ_{i+1}, μ_i] holding cos.
        let cos = cos.clamp(self.mu[n - 1], 1.0);
        let i = self.mu[1..].iter().position(|&m| cos >= m).unwrap_or(n - 2);
        (0..K_NODES)
            .map(|ik| {
                let (r, d) = (&self.c[ik * n..][..n], &self.d[ik * n..][..n]);
                w[ik]
                    * upper_interpolant(
                        (self.mu[i], self.mu[i + 1]),
                        (r[i], r[i + 1]),
                        (d[i], d[i + 1]),
                        cos,
                    )
            })
            .sum()
    }
}

/// The largest value over k of the cubic through the values `c` at the
/// wavenumber nodes, on a grid of 64 steps (its curvature is C's, a few per
/// cent of C over the range: the grid misses its peak by < 1e−5).
fn k_cubic_max(c: &[f64; K_NODES]) -> f64 {
    const STEPS: usize = 64;
    (0..=STEPS)
        .map(|s| {
            let w = k_weights(s as f64 / STEPS as f64);
            (0..K_NODES).map(|ik| w[ik] * c[ik]).sum::<f64>()
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Weights of the wavenumber nodes in the cubic through them at t ∈ [0, 1]
/// (the position between the first and the last node): Lagrange's basis on
/// the uniform nodes 0, 1, 2, 3 at x = 3t, its constant denominators (−6, 2,
/// −2, 6) folded in, since every two-scale evaluation with the cap asks for
/// it once per wavelength.
#[inline]
fn k_weights(t: f64) -> [f64; K_NODES] {
    const _: () = assert!(K_NODES == 4, "k_weights is the cubic's basis");
    let x = 3.0 * t;
    let (a, b, c, d) = (x, x - 1.0, x - 2.0, x - 3.0);
    [
        -(b * c * d) * (1.0 / 6.0),
        0.5 * (a * c * d),
        -0.5 * (a * b * d),
        (a * b * c) * (1.0 / 6.0),
    ]
}

#[cfg(test)]
#[test]
fn k_weights_are_the_cubic_through_the_nodes() {
    // The basis reproduces every cubic, so it sums to 1 and interpolates
    // the nodes.
    for s in 0..=30 {
        let t = s as f64 / 30.0;
        let w = k_weights(t);
        let x = 3.0 * t;
        let cubic = |x: f64| 0.7 - 1.3 * x + 0.4 * x * x - 0.05 * x * x * x;
        let got: f64 = (0..K_NODES).map(|j| w[j] * cubic(j as f64)).sum();
        assert!(
            (got - cubic(x)).abs() < 1e-13,
            "t {t}: {got} vs {}",
            cubic(x)
        );
    }
    for j in 0..K_NODES {
        let w = k_weights(j as f64 / 3.0);
        for (m, &v) in w.iter().enumerate() {
            assert!(
                (v - f64::from(u8::from(m == j))).abs() < 1e-15,
                "node {j}: {w:?}"
            );
        }
    }
}

/// dC/dμ at every node of a row (μ descending, at least two nodes): the
/// slope of the parabola through each node and its neighbours, the secant
/// at the ends.
fn node_slopes(mu: &[f64], c: &[f64]) -> Vec<f64> {
    let n = mu.len();
    let secant = |i: usize| (c[i + 1] - c[i]) / (mu[i + 1] - mu[i]);
    (0..n)
        .map(|i| {
            if i == 0 {
                secant(0)
            } else if i == n - 1 {
                secant(n - 2)
            } else {
                let (h0, h1) = (mu[i] - mu[i - 1], mu[i + 1] - mu[i]);
                (h1 * secant(i - 1) + h0 * secant(i)) / (h0 + h1)
            }
        })
        .collect()
}

/// C between two nodes (μ, value, slope) at `x`: the larger of the chord
/// and the cubic Hermite interpolant. The chord lies above C where C is
/// convex; near a concave peak (C peaks between 89.7° and 89.9° in the
/// materials measured) it falls below by the peak's height over the
/// interval, where the cubic follows the peak to O(h⁴).
#[inline]
fn upper_interpolant(
    (m0, m1): (f64, f64),
    (c0, c1): (f64, f64),
    (d0, d1): (f64, f64),
    x: f64,
) -> f64 {
    let h = m1 - m0;
    let t = (x - m0) / h;
    let chord = c0 + t * (c1 - c0);
    let (t2, t3) = (t * t, t * t * t);
    let cubic = (2.0 * t3 - 3.0 * t2 + 1.0) * c0
        + (t3 - 2.0 * t2 + t) * h * d0
        + (3.0 * t2 - 2.0 * t3) * c1
        + (t3 - t2) * h * d1;
    chord.max(cubic)
}

/// Relative amount by which the cap at an interval's midpoint may exceed
/// the table's interpolation there before the interval is split.
const REFINE_TOL: f64 = 2e-4;
/// Largest number of μ nodes refinement may add.
const REFINE_NODES_MAX: usize = 24;
/// Intervals narrower than this in μ are not split.
const REFINE_DMU_MIN: f64 = 2e-5;

/// Splits the intervals of `columns` (μ descending, one stored C per
/// wavenumber node) where the table's interpolant ([`upper_interpolant`])
/// falls below the cap at the midpoint: there the interpolated cap would
/// let the albedo exceed 1. C is not always convex: for β 4e−4, Lc
/// 0.036 µm, γ 2 at 360 nm it peaks at 89.8°, and between the fixed 89°
/// and 89.9° nodes the chord is 0.7 % low (albedo 1.0014 at 89.34°).
fn refine(columns: &mut Vec<(f64, [f64; K_NODES])>, value: impl Fn(f64, &mut [f64]) + Sync) {
    let mut added = 0;
    // Midpoints computed and not (yet) inserted: an insertion moves the
    // slopes of its neighbours, and so the interpolant over the intervals
    // next to it, which are checked again against these at no cost.
    let mut checked: Vec<(f64, [f64; K_NODES])> = Vec::new();
    // Intervals still to check, by the index of their upper-μ end.
    let mut todo: Vec<usize> = (0..columns.len() - 1).collect();
    while !todo.is_empty() && added < REFINE_NODES_MAX {
        let todo_now: Vec<usize> = todo
            .iter()
            .copied()
            .filter(|&i| columns[i].0 - columns[i + 1].0 > REFINE_DMU_MIN)
            .take(REFINE_NODES_MAX - added)
            .collect();
        checked.extend(crate::parallel::map_rows(todo_now.len(), |t| {
            let i = todo_now[t];
            let m = 0.5 * (columns[i].0 + columns[i + 1].0);
            let mut mid = [0.0; K_NODES];
            value(m, &mut mid);
            (m, mid)
        }));
        let mut inserted = Vec::new();
        while added < REFINE_NODES_MAX {
            let Some(p) = checked.iter().position(|(m, v)| {
                let at = interpolate_columns(columns, *m);
                // Below 1 the cap is floored and the interpolant's error is moot.
                (0..K_NODES).any(|ik| v[ik] > 1.0 && v[ik] > at[ik] * (1.0 + REFINE_TOL))
            }) else {
                break;
            };
            let node = checked.swap_remove(p);
            let at = columns.partition_point(|c| c.0 > node.0);
            columns.insert(at, node);
            added += 1;
            inserted.push(node.0);
        }
        // The intervals on both sides of every new node.
        todo = Vec::new();
        for m in inserted {
            let j = columns.partition_point(|c| c.0 > m);
            todo.extend([j - 1, j]);
        }
        todo.sort_unstable();
        todo.dedup();
    }
}

/// The table's interpolant ([`upper_interpolant`]) over `columns` (μ
/// descending) at μ = `x` inside them, per wavenumber node.
fn interpolate_columns(columns: &[(f64, [f64; K_NODES])], x: f64) -> [f64; K_NODES] {
    let mu: Vec<f64> = columns.iter().map(|c| c.0).collect();
    let i = mu[1..].iter().position(|&m| x >= m).unwrap_or(mu.len() - 2);
    core::array::from_fn(|ik| {
        let c: Vec<f64> = columns.iter().map(|col| col.1[ik]).collect();
        let d = node_slopes(&mu, &c);
        upper_interpolant((mu[i], mu[i + 1]), (c[i], c[i + 1]), (d[i], d[i + 1]), x)
    })
}

/// ∫ f(wo) cosθo dωo over the upper hemisphere for wi = (sinθi, 0, μ) and an
/// isotropic lobe around the mirror direction of angular scale `width`
/// (radians): f must be symmetric in wo.y. Taken in (cosθo, φo): the
/// independent reference of [`albedo_many_half`]'s tests.
#[cfg(test)]
pub(crate) fn albedo(mu: f64, width: f64, f: impl Fn(DVec3) -> f64) -> f64 {
    let mut out = [0.0];
    albedo_many(mu, width, &mut out, |_, _| (), |_, wo, v| v[0] = f(wo));
    out[0]
}

/// [`albedo`] by [`albedo_many_half`].
#[cfg(test)]
pub(crate) fn albedo_half(mu: f64, width: f64, f: impl Fn(DVec3) -> f64) -> f64 {
    let mut out = [0.0];
    albedo_many_half(mu, width, &mut out, |_, _| (), |_, _, wo, v| v[0] = f(wo));
    out[0]
}

/// Half the points of the Gauss–Legendre rule over φh ∈ [0, φc] per θh
/// ring of [`albedo_many_half`] (one panel). The integrand is smooth in φh
/// (the lobe is isotropic in h; only cosθd, and through it A and w, and the
/// Smith term at wo vary along a ring) and vanishes with cosθo at φc.
/// Against a rule of 0.25-width core panels, 0.025 rad θh panels beyond and
/// 8 φ panels of 4 points, over nine materials (β 1e−4–0.3, both readings,
/// 62 angles 0–89.9° and 5 wavenumbers, where C ≥ 0.98), C is within
/// −2.5e−4 … +3.6e−4 with 6 points; with two panels of 4 points (the rule
/// before) −2.7e−4 … +3.3e−4, with one panel of 4 points 6e−4 low.
const HALF_PHI_POINTS: usize = 3;

/// Widest θh panel of [`albedo_many_half`], radians. The graded panels alone
/// reach 0.6 rad, where D̃_eff, cosθd and the Smith terms still vary: on
/// S138 (β 7.2e−4) at 89° their C was 9e−4 high; with panels ≤ 0.1 rad it is
/// within 1e−5 of a rule with 0.025 rad panels and 8 φ panels (≤ 8e−5 at
/// 89.9°).
const HALF_THETA_PANEL_MAX: f64 = 0.1;

/// Extent of the lobe's core in θh, in units of its width, where
/// [`albedo_many_half`]'s panels are at most [`CORE_PANEL_WIDTHS`] wide.
const CORE_WIDTHS: f64 = 8.0;

/// Widest θh panel in the lobe's core, in units of its width. Over seven
/// materials (β 1e−4–0.02, both readings, 17 angles 0–89.9°, 3 wavenumbers),
/// 2 widths moves C by ≤ 2.3e−5 from 1 width, and against a rule of
/// 0.25-width core panels, 0.025 rad panels beyond and 8 φ panels C stays
/// within −1.08e−4 … +1.32e−3 as with 1 width. 3 widths integrates a
/// Gaussian lobe 1.6e−4 high at normal incidence
/// (`half_vector_rule_matches_the_outgoing_rule`).
const CORE_PANEL_WIDTHS: f64 = 2.0;

/// ∫ f(wo) cosθo dωo over the upper hemisphere for wi = (sinθi, 0, μ), for
/// several integrands on the same nodes (`out` receives one integral per
/// entry; f must be symmetric in wo.y), taken over the half vector
/// h = (θh, φh): dωo = 4 cosθd dωh, and a lobe isotropic around the pole in
/// h at every incidence (angular scale `width`) needs grading towards its
/// scale in θh only, where in wo it is squeezed by cosθi in φo at grazing
/// incidence.
/// `per_ring(cosθh, sinθh)` is computed once per polar ring of h (what the
/// lobe's value at θh needs); `f(ring, h, wo, values)` writes one value per
/// entry of `out`. h is restricted to wo above the horizon: cosθo ≥ 0 ⇔
/// cos φh ≥ c0(θh) = −μ cot(2θh)/sinθi, which holds on the whole ring below
/// θ* = (90° − θi)/2 and on no part of it beyond 45° + θi/2.
pub(crate) fn albedo_many_half<R>(
    mu: f64,
    width: f64,
    out: &mut [f64],
    per_ring: impl Fn(f64, f64) -> R,
    f: impl Fn(&R, DVec3, DVec3, &mut [f64]),
) {
    let mu = mu.clamp(0.0, 1.0);
    let sin_i = libm::sqrt(1.0 - mu * mu);
    let theta_i = libm::atan2(sin_i, mu);
    let wi = DVec3::new(sin_i, 0.0, mu);
    let theta_full = 0.5 * (0.5 * PI - theta_i);
    let theta_max = (0.25 * PI + 0.5 * theta_i).min(0.5 * PI);
    let first = (0.25 * width).max(1e-7);
    // Within a few widths of the pole the lobe falls off like e^{−θ/β} or
    // e^{−θ²/β²}: panels there are at most a few widths wide.
    let ts = gl4_nodes(&graded_edges(
        0.0,
        theta_max,
        &[(0.0, first), (theta_full, first.min(0.25 * theta_full))],
        |t| {
            if t < CORE_WIDTHS * width {
                (CORE_PANEL_WIDTHS * width).min(HALF_THETA_PANEL_MAX)
            } else {
                HALF_THETA_PANEL_MAX
            }
        },
    ));
    let (gx, gw) = crate::numerics::quadrature::gauss_legendre::<HALF_PHI_POINTS>();
    let n = out.len();
    let mut values = vec![0.0; n];
    let mut ring = vec![0.0; n];
    out.fill(0.0);
    for &(th, wt) in &ts {
        let (sh, ch) = libm::sincos(th);
        // wo is above the horizon on |φh| ≤ φc.
        let phi_c = if th <= theta_full || !(sin_i > 0.0) {
            PI
        } else {
            let c0 = -mu * libm::cos(2.0 * th) / (sin_i * libm::sin(2.0 * th));
            libm::acos(c0.clamp(-1.0, 1.0))
        };
        if !(phi_c > 0.0) {
            continue;
        }
        let shared = per_ring(ch, sh);
        ring.fill(0.0);
        let r = 0.5 * phi_c;
        for j in 0..2 * HALF_PHI_POINTS {
            let x = if j < HALF_PHI_POINTS {
                -gx[j]
            } else {
                gx[j - HALF_PHI_POINTS]
            };
            let wp = r * gw[j % HALF_PHI_POINTS];
            // φh ∈ [0, π]: sincos_2pi's exact reduction, a few ulp.
            let (sp, cp) = crate::numerics::math::sincos_2pi((r + r * x) * (0.5 / PI));
            let h = DVec3::new(sh * cp, sh * sp, ch);
            let cos_d = wi.dot(h);
            let wo = 2.0 * cos_d * h - wi;
            if !(wo.z > 0.0 && cos_d > 0.0) {
                continue;
            }
            f(&shared, h, wo, &mut values);
            // dωo = 4 cosθd dωh; the cosθo of the albedo.
            let jac = wp * 4.0 * cos_d * wo.z;
            for (acc, &v) in ring.iter_mut().zip(&values) {
                if v.is_finite() {
                    *acc += jac * v;
                }
            }
        }
        for (o, &r) in out.iter_mut().zip(&ring) {
            *o += wt * sh * r;
        }
    }
    // φh over [0, π] only: the lobe is symmetric in h.y.
    for o in out.iter_mut() {
        *o *= 2.0;
    }
}

/// [`albedo`] of several integrands on the same nodes: `f(row, wo, values)`
/// writes one value per entry of `out`, and `out` receives their integrals
/// (each summed in the same order as a single one would be). `row` is
/// `per_row(cosθo, sinθo)`, computed once per polar node: what depends on
/// θo alone is shared by all its azimuths.
#[cfg(test)]
pub(crate) fn albedo_many<R>(
    mu: f64,
    width: f64,
    out: &mut [f64],
    per_row: impl Fn(f64, f64) -> R,
    f: impl Fn(&R, DVec3, &mut [f64]),
) {
    let mu = mu.clamp(0.0, 1.0);
    let sin_i = libm::sqrt(1.0 - mu * mu);
    // In (z = cosθo, φo) the solid angle is dz dφ. The lobe's extent in z is
    // ≈ sinθ·width. In φ it is ≈ width/tanθ around the mirror azimuth π: a
    // normal tilted across the plane of incidence by δ moves wo sideways by
    // only 2δ·cosθi, so at grazing incidence the lobe is far narrower in φ
    // than in θ (with width/sinθ, a β = 1.2e−4 lobe at 89° falls between the
    // φ nodes and its albedo comes out 0.7 % high).
    let hz = (0.25 * width * sin_i.max(width)).max(1e-6);
    let hp = (0.25 * width * mu.max(width) / sin_i.max(width)).clamp(1e-9, 0.5);
    let zs = gl4_nodes(&edges(0.0, 1.0, &[(mu, hz)]));
    let ps: Vec<(f64, f64, f64)> = gl4_nodes(&edges(0.0, PI, &[(PI, hp)]))
        .into_iter()
        .map(|(phi, w)| {
            let (s, c) = libm::sincos(phi);
            (c, s, w)
        })
        .collect();
    let n = out.len();
    let mut values = vec![0.0; n];
    let mut row = vec![0.0; n];
    out.fill(0.0);
    for &(zo, wz) in &zs {
        let so = libm::sqrt((1.0 - zo * zo).max(0.0));
        row.fill(0.0);
        let shared = per_row(zo, so);
        for &(c, s, wp) in &ps {
            f(&shared, DVec3::new(so * c, so * s, zo), &mut values);
            for (r, &v) in row.iter_mut().zip(&values) {
                if v.is_finite() {
                    *r += wp * v;
                }
            }
        }
        for (o, &r) in out.iter_mut().zip(&row) {
            *o += wz * zo * r;
        }
    }
    // φ over [0, π] only: the lobe is symmetric in wo.y.
    for o in out.iter_mut() {
        *o *= 2.0;
    }
}

/// Largest number of panels [`graded_edges`] makes before its last panel
/// ends on hi (a guard: S138's integrals take 25–39).
const PANELS_MAX: usize = 4096;

/// Panel edges on [lo, hi], marched upwards: every panel is at most
/// `max(its lower edge)` wide and graded by [`GRADING`] about each focus
/// `(c, s)`: a panel [a, b] has b − c ≤ GRADING·(a − c) above c and
/// c − a ≤ GRADING·(c − b) below it (at least s wide, ending on c), so it
/// spans the same ratio of distances from the focus as the panels of a
/// geometric sequence from c. The union of one geometric sequence per focus
/// (`panel_edges`) meets such bounds too but, far from two nearby foci
/// (the pole and the horizon cut θ* at grazing incidence), puts pairs of
/// edges a few per cent of a panel apart (5 of its 40 panels at 89.7° on
/// S138) and interleaves the two sequences elsewhere: the union graded by
/// 2.5 took 991 θh panels over S138's 25 cap integrals, this rule by 2.2
/// takes 846.
fn graded_edges(lo: f64, hi: f64, foci: &[(f64, f64)], max: impl Fn(f64) -> f64) -> Vec<f64> {
    // Edges closer than this merge (as `panel_edges`' dedup).
    let tiny = 1e-9 * (hi - lo);
    let mut out = Vec::with_capacity(64);
    out.push(lo);
    let mut a = lo;
    while a < hi {
        let mut b = a + max(a);
        for &(c, s) in foci.iter().filter(|f| f.1 > 0.0) {
            if a >= c {
                b = b.min(a + s.max((GRADING - 1.0) * (a - c)));
            } else {
                // Towards c, ending on it.
                let w = s.max((GRADING - 1.0) / GRADING * (c - a));
                b = b.min(if a + w >= c - tiny { c } else { a + w });
            }
        }
        if b >= hi - tiny || out.len() == PANELS_MAX {
            b = hi;
        }
        out.push(b);
        a = b;
    }
    out
}

/// Panel edges on [lo, hi] graded geometrically away from each `(focus, first width)`.
#[cfg(test)]
fn edges(lo: f64, hi: f64, foci: &[(f64, f64)]) -> Vec<f64> {
    let mut out = Vec::new();
    panel_edges(lo, hi, foci, REFERENCE_GRADING, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadrature_integrates_known_lobes() {
        for mu in [1.0, 0.7, 0.26, 0.035, 0.0017] {
            for width in [1e-3, 0.05, 0.3, 1.0] {
                // Lambertian: ∫ cosθ/π dω = 1.
                let e = albedo(mu, width, |_| 1.0 / PI);
                assert!((e - 1.0).abs() < 1e-12, "μ {mu} width {width}: {e}");
                // A Phong-like lobe around the mirror direction, normalised
                // over the whole sphere: its cut-off mass is known from a
                // fine reference rule (the same code at 1/16 the width).
                let mirror = DVec3::new(-libm::sqrt(1.0 - mu * mu), 0.0, mu);
                let n = 1.0 / (width * width);
                let lobe = |wo: DVec3| {
                    let c = wo.dot(mirror).max(0.0);
                    (n + 1.0) / (2.0 * PI) * libm::pow(c, n) / wo.z.max(1e-300)
                };
                let e = albedo(mu, width, lobe);
                let fine = albedo(mu, width / 16.0, lobe);
                assert!(
                    (e - fine).abs() < 2e-3,
                    "μ {mu} width {width}: {e} vs {fine}"
                );
                if mu > 0.5 && width < 0.1 {
                    assert!((e - 1.0).abs() < 1e-3, "μ {mu} width {width}: {e}");
                }
            }
        }
    }

    #[test]
    fn half_vector_rule_matches_the_outgoing_rule() {
        // The half-vector rule the cap uses against the (cosθo, φo) rule
        // above at 1/16 of the lobe width, on lobes isotropic in h (as the
        // two-scale lobe is): a Beckmann NDF without shadowing, whose
        // albedo ∫ D(h) (wi·h) dωh / μ over wo above the horizon is 1 at
        // normal incidence and departs from it at grazing.
        for mu in [1.0, 0.7, 0.26, 0.035, 0.0017] {
            let wi = DVec3::new(libm::sqrt(1.0 - mu * mu), 0.0, mu);
            for width in [1e-3, 0.05, 0.3, 1.0] {
                let e = albedo_half(mu, width, |_| 1.0 / PI);
                assert!((e - 1.0).abs() < 1e-5, "μ {mu} width {width}: {e}");
                let lobe = |wo: DVec3| {
                    let h = (wi + wo).normalize();
                    let t2 = (h.x * h.x + h.y * h.y) / (h.z * h.z);
                    let d = libm::exp(-t2 / (width * width))
                        / (PI * width * width * h.z * h.z * h.z * h.z);
                    d / (4.0 * mu * wo.z)
                };
                let e = albedo_half(mu, width, lobe);
                let fine = albedo(mu, width / 16.0, lobe);
                assert!(
                    (e - fine).abs() < 1e-4 * fine.max(1.0),
                    "μ {mu} width {width}: {e} vs {fine}"
                );
            }
        }
    }

    #[test]
    fn table_interpolates_and_floors_at_one() {
        let ratio = |mu: f64, k: f64| 0.9 + 0.2 * (1.0 - mu) + 0.001 * k;
        let each = |mu: f64, ks: &[f64], out: &mut [f64]| {
            for (o, &k) in out.iter_mut().zip(ks) {
                *o = ratio(mu, k);
            }
        };
        let cap = AlbedoCap::build(7.0, 17.0, each).unwrap();
        for (i, &t) in THETA_DEG.iter().enumerate() {
            let mu = libm::cos(t.to_radians());
            for k in [7.0, 17.0] {
                let want = (ratio(mu, k) * (1.0 + MARGIN)).max(1.0);
                assert!(
                    (cap.max_at(mu, mu, k) - want).abs() < 1e-12,
                    "node {i} k {k}"
                );
            }
        }
        // Linear in μ and k, so exact between nodes too where above 1.
        assert!((cap.max_at(0.05, 0.05, 12.0) - ratio(0.05, 12.0) * (1.0 + MARGIN)).abs() < 1e-12);
        // Clamped outside the table, never below 1.
        assert!(cap.max_at(0.0, 0.0, 30.0) >= 1.0 && cap.max_at(1.0, 1.0, 1.0) == 1.0);
        assert!(AlbedoCap::build(7.0, 17.0, |_, _, o| o.fill(0.995)).is_none());
        assert!(AlbedoCap::build(7.0, 17.0, |_, _, o| o.fill(0.9995)).is_some());
    }

    /// A cap with a narrow concave peak between the fixed nodes (as the
    /// two-scale model's C peaks between 89.7° and 89.9°) and a dip below
    /// 60° (C need not be monotone): refinement and interpolation keep the
    /// table above C·(1 + MARGIN/2) everywhere (the two-scale model's tables
    /// measured ≥ 1.00066·C), and every μ the build evaluated is kept to
    /// REFINE_TOL of its value.
    #[test]
    fn refined_table_stays_above_a_peaked_cap() {
        extern crate std;
        let theta = |mu: f64| libm::acos(mu).to_degrees();
        let ratio = |mu: f64, k: f64| {
            let t = theta(mu);
            let peak = 0.4 * libm::exp(-((t - 89.78) / 0.12).powi(2));
            let dip = 0.02 * libm::cos((t / 30.0) * PI);
            1.0 + peak + dip + 0.004 * (k - 12.0)
        };
        let evaluated = std::sync::Mutex::new(Vec::new());
        let cap = AlbedoCap::build(7.0, 17.0, |mu, ks, out| {
            for (o, &k) in out.iter_mut().zip(ks) {
                *o = ratio(mu, k);
            }
            evaluated.lock().unwrap().push(mu);
        })
        .unwrap();
        let floor = 1.0 + 0.5 * MARGIN;
        let mut worst = f64::INFINITY;
        for e in 0..=20_000 {
            let t = 89.9 * e as f64 / 20_000.0;
            let mu = libm::cos(t.to_radians());
            for k in [7.0, 12.0, 17.0] {
                worst = worst.min(cap.max_at(mu, mu, k) / ratio(mu, k));
            }
        }
        assert!(worst >= floor - 1e-12, "table/C down to {worst}");
        for &mu in evaluated.lock().unwrap().iter() {
            for k in [7.0, 12.0, 17.0] {
                let got = cap.max_at(mu, mu, k) * (1.0 + REFINE_TOL);
                assert!(
                    got >= ratio(mu, k) * (1.0 + MARGIN) - 1e-12,
                    "θ {}",
                    theta(mu)
                );
            }
        }
    }

    /// Every panel of the marched rule is within the grading bounds of every
    /// focus and the width limit, ends on a focus rather than crossing it,
    /// and is as wide as those bounds allow (so there are no slivers: the
    /// union of per-focus sequences fails this at grazing incidence, where
    /// the pole and θ* are 1e−3 rad apart); and it has a fifth fewer
    /// panels than the union graded by 2.5 there (32 against 40).
    #[test]
    fn graded_edges_are_graded_and_without_slivers() {
        for (theta_full, theta_max, width) in [
            (0.0026f64, 1.568f64, 1e-3f64),
            (0.35, 1.22, 0.05),
            (PI / 4.0, PI / 4.0, 1e-3),
            (1e-5, 1.5, 0.3),
        ] {
            let s = 0.25 * width;
            let foci = [(0.0, s), (theta_full, s.min(0.25 * theta_full))];
            let max = |t: f64| if t < 8.0 * width { 2.0 * width } else { 0.1 };
            let e = graded_edges(0.0, theta_max, &foci, max);
            assert_eq!((e[0], *e.last().unwrap()), (0.0, theta_max));
            for p in e.windows(2) {
                let (a, b) = (p[0], p[1]);
                assert!(b > a, "{e:?}");
                let mut bound = a + max(a);
                for &(c, s) in &foci {
                    let w = if a >= c {
                        s.max((GRADING - 1.0) * (a - c))
                    } else {
                        s.max((GRADING - 1.0) / GRADING * (c - a)).min(c - a)
                    };
                    bound = bound.min(a + w);
                    assert!(!(a < c && b > c), "[{a}, {b}] crosses {c}");
                }
                let tol = 1e-9 * theta_max;
                assert!(b <= bound + tol, "[{a}, {b}] wider than {bound}");
                assert!(b >= bound - tol || b == theta_max, "[{a}, {b}]: a sliver");
            }
            if theta_full < 0.01 && width < 0.01 {
                let mut union = Vec::new();
                panel_edges(0.0, theta_max, &foci, REFERENCE_GRADING, &mut union);
                let parts: usize = union
                    .windows(2)
                    .map(|p| libm::ceil((p[1] - p[0]) / max(p[0])).max(1.0) as usize)
                    .sum();
                assert!(6 * (e.len() - 1) <= 5 * parts, "{} vs {parts}", e.len() - 1);
            }
        }
    }
}
