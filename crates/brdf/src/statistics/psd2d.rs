//! A measured 2-D PSD on a regular (ζx, ζy) grid (physics.md §15.4): what a
//! scan whose PSD is not constant on ellipses (crossing lays, the streaks of
//! straight edges) needs in place of [`EllipticalPsd`](super::EllipticalPsd).
//!
//! The table holds P₂ at the nodes (i Δζx, j Δζy), |i| ≤ m_x, |j| ≤ m_y, of the
//! grid's frame, given over the half plane j ≥ 0 and completed by P(−ζ) = P(ζ)
//! (the PSD of a real surface is even). The grid's frame is turned by φ from
//! the tangent x towards y (the convention of the `_aniso` models'
//! `angle_deg`).
//!
//! * Inside the grid's rectangle R = [−X, X] × [−Y, Y] (X = m_x Δζx, Y = m_y Δζy)
//!   P₂ is the bilinear interpolant of the nodes: a convex combination of
//!   values ≥ 0, so never negative, and exact on the nodes.
//! * Beyond R (above the measured band) it is continued along each ray from the
//!   origin as a power law from the edge: with s = max(|ζx|/X, |ζy|/Y) > 1,
//!   P₂(ζ) = P₂(ζ/s) · s^{−α}, α > 2 (`tail_exponent`). This is an
//!   assumption: every direction keeps the edge value it was measured with and
//!   falls with one exponent, that of the radial table's tail; its share of σ²
//!   is [`TabulatedPsd2d::tail_fraction`].
//!
//! σ² = ∫P₂ d²ζ is exact: a cell holds Δζx Δζy × the mean of its corners; the
//! tail beyond an edge segment of the edge x = X holds X Δζy (p_a + p_b)/(2(α − 2))
//! (with ζ = s·(X, t): d²ζ = s X ds dt, ∫₁^∞ s^{1−α} ds = 1/(α − 2)), likewise
//! the other edges. Sampling picks a cell or edge segment from their masses,
//! then the point within it exactly (the bilinear law's linear x marginal and
//! linear conditional in y; the edge's linear law in t and s^{1−α} in s), so
//! the density of a sample is P₂(ζ)/σ² exactly.

use alloc::vec::Vec;

use crate::BrdfError;

/// Largest accepted half-size of the grid, nodes per half axis.
pub const HALF_NODES_MAX: usize = 1024;

/// Largest accepted tail exponent (the steepest tail of [`TabulatedPsd`](super::TabulatedPsd)).
pub const TAIL_EXPONENT_MAX: f64 = -super::measured_psd::TAIL_SLOPE_MIN;

/// A 2-D PSD tabulated on a regular grid with a power-law continuation beyond
/// it (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedPsd2d {
    mx: usize,
    my: usize,
    dzx: f64,
    dzy: f64,
    /// Nodes of the full plane, row j + m_y holds i = −m_x..=m_x.
    p: Vec<f64>,
    alpha: f64,
    angle_rad: f64,
    /// cos φ, sin φ of the grid's frame.
    cs: (f64, f64),
    sigma2: f64,
    tail_mass: f64,
    /// Cumulative normalised mass over the cells (row-major), then the edge
    /// segments (x = X, x = −X: 2m_y each; y = Y, y = −Y: 2m_x each).
    cum: Vec<f64>,
}

/// Where a sample's mass lies.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Cell {
        i: usize,
        j: usize,
    },
    /// The edge x = ±X (`sign`), segment between node rows j and j + 1.
    EdgeX {
        sign: f64,
        j: usize,
    },
    /// The edge y = ±Y, segment between node columns i and i + 1.
    EdgeY {
        sign: f64,
        i: usize,
    },
}

impl TabulatedPsd2d {
    /// From the half plane: `half_psd_um4` holds the rows j = 0..=`half_ny`, each
    /// with the nodes i = −`half_nx`..=`half_nx` (row j = 0 is made even by
    /// averaging P(i, 0) with P(−i, 0)); steps `dzx`, `dzy` in rad/µm; the tail
    /// exponent α ∈ (2, 101]; the grid's frame turned by `angle_rad`.
    pub fn new(
        half_nx: usize,
        half_ny: usize,
        dzx_rad_per_um: f64,
        dzy_rad_per_um: f64,
        half_psd_um4: &[f64],
        tail_exponent: f64,
        angle_rad: f64,
    ) -> Result<Self, BrdfError> {
        let (mx, my) = (half_nx, half_ny);
        if !(1..=HALF_NODES_MAX).contains(&mx) || !(1..=HALF_NODES_MAX).contains(&my) {
            return Err(BrdfError::InvalidTable {
                reason: "the grid needs 1 to 1024 nodes on each half axis (half_nx, half_ny)",
                row: None,
            });
        }
        let (w, h) = (2 * mx + 1, 2 * my + 1);
        if half_psd_um4.len() != w * (my + 1) {
            return Err(BrdfError::InvalidTable {
                reason: "psd2d must hold (2 half_nx + 1)(half_ny + 1) values: the rows \
                         j = 0..=half_ny of the half plane, each i = -half_nx..=half_nx",
                row: None,
            });
        }
        for (name, d) in [
            ("dzx_rad_per_um", dzx_rad_per_um),
            ("dzy_rad_per_um", dzy_rad_per_um),
        ] {
            crate::error::check_range(name, d, 1e-9, 1e9, "a finite positive step, rad/µm")?;
        }
        crate::error::check_range(
            "tail_exponent",
            tail_exponent,
            2.0 + 1e-6,
            TAIL_EXPONENT_MAX,
            "2 < α ≤ 101 (the tail must fall faster than ζ^-2 for a finite σ²)",
        )?;
        super::anisotropic::check_angle(angle_rad)?;
        if let Some(k) = half_psd_um4
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(BrdfError::InvalidTable {
                reason: "psd2d values must be finite and ≥ 0 (µm⁴)",
                row: Some(k),
            });
        }
        if !half_psd_um4.iter().any(|v| *v > 0.0) {
            return Err(BrdfError::InvalidTable {
                reason: "psd2d is zero everywhere (the surface has no roughness)",
                row: None,
            });
        }
        let mut p = alloc::vec![0.0; w * h];
        p[my * w..(my + 1) * w].copy_from_slice(&half_psd_um4[..w]);
        for j in 1..=my {
            for i in 0..w {
                let v = half_psd_um4[j * w + i];
                p[(my + j) * w + i] = v;
                p[(my - j) * w + (w - 1 - i)] = v;
            }
        }
        for i in 0..mx {
            let (a, b) = (my * w + i, my * w + (w - 1 - i));
            let m = 0.5 * (p[a] + p[b]);
            p[a] = m;
            p[b] = m;
        }
        let mut t = TabulatedPsd2d {
            mx,
            my,
            dzx: dzx_rad_per_um,
            dzy: dzy_rad_per_um,
            p,
            alpha: tail_exponent,
            angle_rad,
            cs: (libm::cos(angle_rad), libm::sin(angle_rad)),
            sigma2: 0.0,
            tail_mass: 0.0,
            cum: Vec::new(),
        };
        t.build_cdf();
        if !(t.sigma2.is_finite() && t.sigma2 > 0.0) {
            return Err(BrdfError::InvalidTable {
                reason: "psd2d integrates to no finite positive σ² (values too large?)",
                row: None,
            });
        }
        Ok(t)
    }

    fn node(&self, i: usize, j: usize) -> f64 {
        self.p[j * (2 * self.mx + 1) + i]
    }

    /// The masses of every piece in the order of `cum`, unnormalised.
    fn masses(&self) -> Vec<f64> {
        let (mx, my) = (self.mx, self.my);
        let mut m = Vec::with_capacity(4 * mx * my + 4 * (mx + my));
        let cell = 0.25 * self.dzx * self.dzy;
        for j in 0..2 * my {
            for i in 0..2 * mx {
                let s = self.node(i, j)
                    + self.node(i + 1, j)
                    + self.node(i, j + 1)
                    + self.node(i + 1, j + 1);
                m.push(cell * s);
            }
        }
        let k = 0.5 / (self.alpha - 2.0);
        let (x_edge, y_edge) = (mx as f64 * self.dzx, my as f64 * self.dzy);
        for col in [2 * mx, 0] {
            for j in 0..2 * my {
                let s = self.node(col, j) + self.node(col, j + 1);
                m.push(k * x_edge * self.dzy * s);
            }
        }
        for row in [2 * my, 0] {
            for i in 0..2 * mx {
                let s = self.node(i, row) + self.node(i + 1, row);
                m.push(k * y_edge * self.dzx * s);
            }
        }
        m
    }

    fn build_cdf(&mut self) {
        let m = self.masses();
        let cells = 4 * self.mx * self.my;
        let total: f64 = m.iter().sum();
        self.tail_mass = m[cells..].iter().sum();
        self.sigma2 = total;
        let mut acc = 0.0;
        self.cum = m
            .iter()
            .map(|v| {
                acc += v / total;
                acc
            })
            .collect();
        if let Some(last) = self.cum.last_mut() {
            *last = 1.0;
        }
    }

    fn piece(&self, k: usize) -> Piece {
        let (mx, my) = (self.mx, self.my);
        let cells = 4 * mx * my;
        if k < cells {
            return Piece::Cell {
                i: k % (2 * mx),
                j: k / (2 * mx),
            };
        }
        let k = k - cells;
        if k < 4 * my {
            let sign = if k < 2 * my { 1.0 } else { -1.0 };
            return Piece::EdgeX {
                sign,
                j: k % (2 * my),
            };
        }
        let k = k - 4 * my;
        let sign = if k < 2 * mx { 1.0 } else { -1.0 };
        Piece::EdgeY {
            sign,
            i: k % (2 * mx),
        }
    }

    /// rms height σ, µm.
    pub fn sigma_um(&self) -> f64 {
        libm::sqrt(self.sigma2)
    }

    /// The share of σ² that lies beyond the grid (the assumed continuation).
    pub fn tail_fraction(&self) -> f64 {
        self.tail_mass / self.sigma2
    }

    /// The grid's half widths (X, Y), rad/µm, in its own frame.
    pub fn band_rad_per_um(&self) -> (f64, f64) {
        (self.mx as f64 * self.dzx, self.my as f64 * self.dzy)
    }

    /// The tail exponent α.
    pub fn tail_exponent(&self) -> f64 {
        self.alpha
    }

    /// φ of the grid's frame, radians from the tangent x towards y.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// The smallest grid step, rad/µm (the finest detail the table holds).
    pub fn step_rad_per_um(&self) -> f64 {
        self.dzx.min(self.dzy)
    }

    /// Bilinear value at a point (gx, gy) of grid coordinates in [0, 2m_x] × [0, 2m_y].
    fn bilinear(&self, gx: f64, gy: f64) -> f64 {
        let i = (libm::floor(gx) as usize).min(2 * self.mx - 1);
        let j = (libm::floor(gy) as usize).min(2 * self.my - 1);
        let (tx, ty) = (gx - i as f64, gy - j as f64);
        let lo = (1.0 - tx) * self.node(i, j) + tx * self.node(i + 1, j);
        let hi = (1.0 - tx) * self.node(i, j + 1) + tx * self.node(i + 1, j + 1);
        ((1.0 - ty) * lo + ty * hi).max(0.0)
    }

    /// P₂ at (a, b) in the grid's frame.
    fn psd_frame(&self, a: f64, b: f64) -> f64 {
        let (x_edge, y_edge) = self.band_rad_per_um();
        let s = (libm::fabs(a) / x_edge).max(libm::fabs(b) / y_edge);
        if !s.is_finite() {
            return 0.0;
        }
        let (a, b, scale) = if s > 1.0 {
            (a / s, b / s, libm::pow(s, -self.alpha))
        } else {
            (a, b, 1.0)
        };
        let gx = (a / self.dzx + self.mx as f64).clamp(0.0, 2.0 * self.mx as f64);
        let gy = (b / self.dzy + self.my as f64).clamp(0.0, 2.0 * self.my as f64);
        self.bilinear(gx, gy) * scale
    }

    /// P₂(ζ), µm⁴, at ζ = (ζx, ζy) in the tangent frame (rad/µm); ∫P₂ d²ζ = σ².
    pub fn psd(&self, zx: f64, zy: f64) -> f64 {
        let (c, s) = self.cs;
        self.psd_frame(c * zx + s * zy, c * zy - s * zx)
    }

    /// P₂ at (a, b) in the grid's own frame (turned by [`angle_rad`](Self::angle_rad)
    /// from the tangent frame), µm⁴.
    pub fn psd_in_frame(&self, a: f64, b: f64) -> f64 {
        self.psd_frame(a, b)
    }

    /// The grid steps (Δζx, Δζy), rad/µm, in its own frame.
    pub fn steps_rad_per_um(&self) -> (f64, f64) {
        (self.dzx, self.dzy)
    }

    /// P₂(ζ)/σ², the density of [`sample_zeta`](Self::sample_zeta), 1/(rad/µm)².
    pub fn unit_psd(&self, zx: f64, zy: f64) -> f64 {
        self.psd(zx, zy) / self.sigma2
    }

    /// A frequency ζ (tangent frame, rad/µm) drawn from P₂/σ² with two uniform
    /// numbers in [0, 1).
    pub fn sample_zeta(&self, u1: f64, u2: f64) -> (f64, f64) {
        let u1 = u1.clamp(0.0, 1.0);
        let k = self
            .cum
            .partition_point(|&c| c <= u1)
            .min(self.cum.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cum[k - 1] };
        let v = ((u1 - lo) / (self.cum[k] - lo)).clamp(0.0, 1.0);
        let u2 = u2.clamp(0.0, 1.0);
        let (x_edge, y_edge) = self.band_rad_per_um();
        let (a, b) = match self.piece(k) {
            Piece::Cell { i, j } => {
                let (p00, p10) = (self.node(i, j), self.node(i + 1, j));
                let (p01, p11) = (self.node(i, j + 1), self.node(i + 1, j + 1));
                let tx = sample_linear(p00 + p01, p10 + p11, v);
                let ty =
                    sample_linear((1.0 - tx) * p00 + tx * p10, (1.0 - tx) * p01 + tx * p11, u2);
                (
                    (i as f64 + tx - self.mx as f64) * self.dzx,
                    (j as f64 + ty - self.my as f64) * self.dzy,
                )
            }
            Piece::EdgeX { sign, j } => {
                let col = if sign > 0.0 { 2 * self.mx } else { 0 };
                let t = sample_linear(self.node(col, j), self.node(col, j + 1), v);
                let s = self.tail_scale(u2);
                (
                    s * sign * x_edge,
                    s * (j as f64 + t - self.my as f64) * self.dzy,
                )
            }
            Piece::EdgeY { sign, i } => {
                let row = if sign > 0.0 { 2 * self.my } else { 0 };
                let t = sample_linear(self.node(i, row), self.node(i + 1, row), v);
                let s = self.tail_scale(u2);
                (
                    s * (i as f64 + t - self.mx as f64) * self.dzx,
                    s * sign * y_edge,
                )
            }
        };
        let (c, s) = self.cs;
        (c * a - s * b, s * a + c * b)
    }

    /// s ≥ 1 with density (α − 2) s^{1−α}.
    fn tail_scale(&self, u: f64) -> f64 {
        libm::pow(1.0 - u.min(1.0 - 1e-16), -1.0 / (self.alpha - 2.0))
    }
}

/// t ∈ [0, 1] with density ∝ (1 − t) a + t b (a, b ≥ 0, a + b > 0), from u ∈ [0, 1]:
/// the root of a t + (b − a) t²/2 = u (a + b)/2 in the form that does not cancel.
fn sample_linear(a: f64, b: f64, u: f64) -> f64 {
    let sum = a + b;
    if !(sum > 0.0) {
        return u;
    }
    let d = libm::sqrt((a * a + (b * b - a * a) * u).max(0.0));
    let den = a + d;
    if !(den > 0.0) {
        // a = 0 and u = 0: the density vanishes at t = 0, where the CDF starts.
        return 0.0;
    }
    (u * sum / den).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    fn grid(mx: usize, my: usize, f: impl Fn(f64, f64) -> f64) -> Vec<f64> {
        let mut v = Vec::new();
        for j in 0..=my {
            for i in 0..=2 * mx {
                v.push(f(i as f64 - mx as f64, j as f64));
            }
        }
        v
    }

    #[test]
    fn linear_sampling_inverts_its_cdf() {
        for (a, b) in [(1.0, 1.0), (0.0, 2.0), (3.0, 0.0), (1.0, 1e-12), (2.0, 7.0)] {
            for k in 0..=20 {
                let u = k as f64 / 20.0;
                let t = sample_linear(a, b, u);
                let cdf = (a * t + 0.5 * (b - a) * t * t) / (0.5 * (a + b));
                assert!((cdf - u).abs() < 1e-12, "{a} {b} {u}: {t} {cdf}");
            }
        }
    }

    #[test]
    fn nodes_symmetry_and_sigma() {
        let v = grid(3, 2, |i, j| 1.0 + i + 2.0 * j + 3.0);
        let t = TabulatedPsd2d::new(3, 2, 0.5, 0.25, &v, 4.0, 0.0).unwrap();
        // Node values of the half plane; row 0 made even.
        assert_eq!(t.psd(1.0, 0.5), 1.0 + 2.0 + 4.0 + 3.0);
        assert_eq!(t.psd(-1.0, -0.5), t.psd(1.0, 0.5));
        assert_eq!(t.psd(1.0, 0.0), 4.0);
        for (x, y) in [(0.3, 0.1), (1.2, -0.4), (7.0, 0.1), (-3.0, 9.0)] {
            assert!((t.psd(x, y) - t.psd(-x, -y)).abs() < 1e-12);
        }
        // A constant table: σ² = 4XY c + the tail 4XY c·2/(α − 2).
        let c = vec![2.0; 7 * 3];
        let t = TabulatedPsd2d::new(3, 2, 0.5, 0.25, &c, 4.0, 0.3).unwrap();
        let area = 4.0 * 1.5 * 0.5;
        let want = area * 2.0 * (1.0 + 2.0 / (4.0 - 2.0));
        assert!((t.sigma_um().powi(2) / want - 1.0).abs() < 1e-12);
        assert!((t.tail_fraction() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn bad_tables_name_the_problem() {
        let ok = vec![1.0; 7 * 3];
        assert!(TabulatedPsd2d::new(0, 2, 0.5, 0.5, &ok, 4.0, 0.0).is_err());
        assert!(TabulatedPsd2d::new(3, 2, 0.5, 0.5, &ok[1..], 4.0, 0.0).is_err());
        assert!(TabulatedPsd2d::new(3, 2, 0.0, 0.5, &ok, 4.0, 0.0).is_err());
        assert!(TabulatedPsd2d::new(3, 2, 0.5, 0.5, &ok, 2.0, 0.0).is_err());
        assert!(TabulatedPsd2d::new(3, 2, 0.5, 0.5, &ok, 4.0, f64::NAN).is_err());
        let mut bad = ok.clone();
        bad[5] = -1.0;
        match TabulatedPsd2d::new(3, 2, 0.5, 0.5, &bad, 4.0, 0.0) {
            Err(BrdfError::InvalidTable { row, .. }) => assert_eq!(row, Some(5)),
            other => panic!("{other:?}"),
        }
        assert!(TabulatedPsd2d::new(3, 2, 0.5, 0.5, &[0.0; 21], 4.0, 0.0).is_err());
        assert!(TabulatedPsd2d::new(3000, 2, 0.5, 0.5, &ok, 4.0, 0.0).is_err());
    }
}
