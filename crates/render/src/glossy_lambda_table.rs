//! A control variate for the λ integral of a wave-optical glossy lobe at a
//! first vertex.
//!
//! An isotropic model's glossy lobe f(λ; wi, wo) depends on the geometry
//! only through cosθi, cosθo and ρ = |wi_xy + wo_xy| (the in-plane part of
//! the scattering vector: its Q factor, the PSD's argument ρ/λ, the
//! Fresnel factor's angle and the energy factors are functions of these).
//! [`GlossyTable`] holds f·cosθo (below simply f) at the nodes of a grid
//! over those three and λ; f̃ is its multilinear interpolant. For an emission basis function b, the
//! λ integral of the interpolant at a geometry is
//! Σ_c w_c ∫ b(λ) f̃_c(λ) cmf(λ) dλ, with w_c the geometric corner weights
//! and f̃_c(λ) the node's values linear in λ, so it is exact from the
//! per-node integrals I_c = Σ_k f_c(λ_k) ∫ hat_k(λ) b(λ) cmf(λ) dλ.
//!
//! The integrator's estimate at a first vertex is then
//! ∫ Le f̃ cmf dλ (exact) + the sampled wavelengths' estimate of
//! ∫ Le (f − f̃) cmf dλ: unbiased whatever the table's accuracy, with the
//! sampled part's variance that of the residual f − f̃ instead of f.

use crate::spectrum::{LAMBDA_MAX, LAMBDA_MIN};
use brdf::Bxdf;
use glam::DVec3;

/// Wavelength nodes, uniform over 360–830 nm (the interpolant is linear
/// between them).
pub const LAMBDA_NODES: usize = 48;
/// Nodes of cosθi and of cosθo, uniform over [0, 1].
pub const COS_NODES: usize = 16;
/// Nodes of ρ = |wi_xy + wo_xy| over [0, 2], uniform in √(ρ/2): dense near
/// ρ = 0, the specular direction, where the lobe peaks (its width there is
/// of order λ/Lc).
pub const RHO_NODES: usize = 64;
const RHO_MAX: f64 = 2.0;
/// Directions closer than this to the horizon are evaluated at it: models
/// give no lobe at exactly cosθ = 0.
const COS_FLOOR: f64 = 1e-3;

/// Geometric nodes of the grid.
pub const GEOMETRIC_NODES: usize = COS_NODES * COS_NODES * RHO_NODES;

/// The wavelength (nm) of λ node `k`.
#[inline]
pub fn lambda_node(k: usize) -> f64 {
    LAMBDA_MIN + (LAMBDA_MAX - LAMBDA_MIN) * k as f64 / (LAMBDA_NODES - 1) as f64
}

/// The eight grid corners around a geometry and their multilinear weights.
#[derive(Clone, Copy, Debug)]
pub struct Corners {
    /// Geometric node index of each corner.
    pub node: [u32; 8],
    /// Weight of each corner (they sum to 1).
    pub w: [f64; 8],
}

/// Index of the lower node and the fraction toward the next, for a
/// coordinate `x` in node units on an axis of `n` nodes.
#[inline]
fn cell(x: f64, n: usize) -> (usize, f64) {
    let x = x.clamp(0.0, (n - 1) as f64);
    let i = (x as usize).min(n - 2);
    (i, x - i as f64)
}

#[inline]
fn node_index(i_ci: usize, i_co: usize, i_rho: usize) -> usize {
    (i_ci * COS_NODES + i_co) * RHO_NODES + i_rho
}

/// The corners around local directions `wi`, `wo` (z the normal).
#[inline]
pub fn corners(wi: DVec3, wo: DVec3) -> Corners {
    let rho = ((wi.x + wo.x).powi(2) + (wi.y + wo.y).powi(2)).sqrt();
    let t = (rho / RHO_MAX).min(1.0).sqrt();
    let (a, fa) = cell(wi.z * (COS_NODES - 1) as f64, COS_NODES);
    let (b, fb) = cell(wo.z * (COS_NODES - 1) as f64, COS_NODES);
    let (c, fc) = cell(t * (RHO_NODES - 1) as f64, RHO_NODES);
    let mut out = Corners {
        node: [0; 8],
        w: [0.0; 8],
    };
    for s in 0..8 {
        let (da, db, dc) = (s >> 2 & 1, s >> 1 & 1, s & 1);
        out.node[s] = node_index(a + da, b + db, c + dc) as u32;
        let wa = if da == 1 { fa } else { 1.0 - fa };
        let wb = if db == 1 { fb } else { 1.0 - fb };
        let wc = if dc == 1 { fc } else { 1.0 - fc };
        out.w[s] = wa * wb * wc;
    }
    out
}

/// Directions with the given cosines and in-plane sum of length `rho`, for
/// evaluating a node: unit vectors where the cosines allow that ρ, and
/// below that range (ρ < |sinθi − sinθo|) `wo` with the node's cosθo and ρ
/// but not of unit length (its in-plane part antiparallel to wi's); above
/// it (ρ > sinθi + sinθo), ρ clamped.
///
/// Why not clamp ρ below too: the lobe peaks at ρ = 0, which only the
/// nodes with cosθo = cosθi reach. Clamped, every other corner of a cell
/// holds the lobe's value |sinθi − sinθo| away from the peak (0.065 for
/// neighbouring cosine nodes at 45°, wider than a 2 µm-Lc GHS lobe), so
/// the interpolant near the mirror direction mixed peak and tail: its
/// residual was 25 % of f there on the s138 GHS plate. The models' f is a
/// smooth function of (cosθo, ρ) through the non-unit direction (their
/// scattering vector, g and Fresnel angle are polynomials in its
/// components), so the table interpolates that continuation instead.
pub fn node_directions(ci: f64, co: f64, rho: f64) -> (DVec3, DVec3) {
    let ci = ci.clamp(COS_FLOOR, 1.0);
    let co = co.clamp(COS_FLOOR, 1.0);
    let si = (1.0 - ci * ci).max(0.0).sqrt();
    let so = (1.0 - co * co).max(0.0).sqrt();
    let rho = rho.max(0.0);
    if rho < (si - so).abs() {
        // Continuous with the unit direction at ρ = |si − so|, where
        // wo_xy = −so along wi_xy.
        let x = if si >= so { rho - si } else { -rho - si };
        return (DVec3::new(si, 0.0, ci), DVec3::new(x, 0.0, co));
    }
    let rho = rho.min(si + so);
    // wo_xy = ρ(cosφ, sinφ) − wi_xy with |wo_xy| = so.
    let (cos_phi, sin_phi) = if rho * si > 1e-12 {
        let c = ((rho * rho + si * si - so * so) / (2.0 * rho * si)).clamp(-1.0, 1.0);
        (c, (1.0 - c * c).max(0.0).sqrt())
    } else {
        (1.0, 0.0)
    };
    let wi = DVec3::new(si, 0.0, ci);
    let wo = DVec3::new(rho * cos_phi - si, rho * sin_phi, co).normalize();
    (wi, wo)
}

/// The geometry (cosθi, cosθo, ρ) of geometric node `g`.
pub fn node_geometry(g: usize) -> (f64, f64, f64) {
    let i_rho = g % RHO_NODES;
    let i_co = (g / RHO_NODES) % COS_NODES;
    let i_ci = g / (RHO_NODES * COS_NODES);
    let t = i_rho as f64 / (RHO_NODES - 1) as f64;
    (
        i_ci as f64 / (COS_NODES - 1) as f64,
        i_co as f64 / (COS_NODES - 1) as f64,
        RHO_MAX * t * t,
    )
}

/// The nodes of one (cosθi, cosθo) pair: f over ρ and λ, and the λ
/// integrals per ρ node and basis function.
struct Cell {
    /// f at (ρ node r, λ node k): `f[r * LAMBDA_NODES + k]`.
    f: Vec<f32>,
    /// `integrals[r * bases + b]` = ∫ b f̃ cmf dλ at ρ node r.
    integrals: Vec<[f64; 3]>,
}

/// A material's glossy lobe on the grid, with its exact λ integrals. Each
/// (cosθi, cosθo) pair of nodes is evaluated the first time a lookup needs
/// it: a scene's first vertices see a narrow range of cosθi, and the
/// light's directions a narrow range of cosθo, so most of the grid is
/// never built. A cell's values do not depend on which thread builds it.
pub struct GlossyTable {
    cells: Vec<std::sync::OnceLock<Cell>>,
    /// ∫ hat_k b cmf dλ per λ node k and basis function b.
    hats: Vec<[f64; 3]>,
    bases: usize,
}

impl GlossyTable {
    /// An empty table against basis functions whose weighted hat integrals
    /// are `hats` (`hats[k * bases + b]` = ∫ hat_k(λ) b(λ) cmf(λ) dλ,
    /// hat_k the piecewise linear function that is 1 at λ node k and 0 at
    /// the others).
    pub fn new(hats: Vec<[f64; 3]>, bases: usize) -> GlossyTable {
        GlossyTable {
            cells: (0..COS_NODES * COS_NODES)
                .map(|_| std::sync::OnceLock::new())
                .collect(),
            hats,
            bases,
        }
    }

    /// The cell of nodes (`i_ci`, `i_co`) of `bxdf`'s lobe, built if new.
    /// Non-finite values of the model count as 0.
    #[inline]
    fn cell(&self, bxdf: &dyn Bxdf, i_ci: usize, i_co: usize) -> &Cell {
        self.cells[i_ci * COS_NODES + i_co].get_or_init(|| self.build_cell(bxdf, i_ci, i_co))
    }

    fn build_cell(&self, bxdf: &dyn Bxdf, i_ci: usize, i_co: usize) -> Cell {
        let lambdas: [f64; LAMBDA_NODES] = std::array::from_fn(lambda_node);
        let mut f = vec![0.0f32; RHO_NODES * LAMBDA_NODES];
        let mut fp = [(0.0, 0.0); LAMBDA_NODES];
        // Nodes outside the ρ the cosines allow take the value at the
        // nearest allowed ρ: evaluated once per end.
        let mut last: Option<(DVec3, DVec3)> = None;
        for (i_rho, out) in f.chunks_mut(LAMBDA_NODES).enumerate() {
            let (ci, co, rho) = node_geometry(node_index(i_ci, i_co, i_rho));
            let dirs = node_directions(ci, co, rho);
            if last != Some(dirs) {
                bxdf.eval_pdf_many(dirs.0, dirs.1, &lambdas, &mut fp);
                last = Some(dirs);
            }
            // f·cosθo, the factor the integrand carries: bounded where
            // f alone grows toward the horizon, so the interpolant does not
            // overshoot between the horizon's node and the next.
            let cos_o = dirs.1.z;
            for (o, v) in out.iter_mut().zip(&fp) {
                let g = v.0 * cos_o;
                *o = if g.is_finite() { g as f32 } else { 0.0 };
            }
        }
        let nb = self.bases;
        let mut integrals = vec![[0.0; 3]; RHO_NODES * nb];
        for (out, fr) in integrals.chunks_mut(nb).zip(f.chunks(LAMBDA_NODES)) {
            for (k, &v) in fr.iter().enumerate() {
                let v = v as f64;
                if v == 0.0 {
                    continue;
                }
                for (o, h) in out.iter_mut().zip(&self.hats[k * nb..(k + 1) * nb]) {
                    for c in 0..3 {
                        o[c] += v * h[c];
                    }
                }
            }
        }
        Cell { f, integrals }
    }

    /// Bytes held by the cells built so far.
    pub fn bytes(&self) -> usize {
        let per_cell = RHO_NODES * (LAMBDA_NODES * 4 + self.bases * 24);
        self.cells.iter().filter(|c| c.get().is_some()).count() * per_cell + self.hats.len() * 24
    }

    /// The rows of the corners of `c`, each cell found once (the two ρ
    /// corners of a (cosθi, cosθo) pair share it).
    #[inline]
    pub fn rows<'t>(&'t self, bxdf: &dyn Bxdf, c: &Corners) -> Rows<'t> {
        let mut f: [&[f32]; 8] = [&[]; 8];
        let mut integrals: [&[[f64; 3]]; 8] = [&[]; 8];
        for s in (0..8).step_by(2) {
            let g = c.node[s] as usize;
            let i_rho = g % RHO_NODES;
            let cell = self.cell(
                bxdf,
                g / (RHO_NODES * COS_NODES),
                (g / RHO_NODES) % COS_NODES,
            );
            // Corner s + 1 is the next ρ node of the same cell.
            for (d, r) in [(0, i_rho), (1, i_rho + 1)] {
                f[s + d] = &cell.f[r * LAMBDA_NODES..(r + 1) * LAMBDA_NODES];
                integrals[s + d] = &cell.integrals[r * self.bases..(r + 1) * self.bases];
            }
        }
        Rows {
            w: c.w,
            f,
            integrals,
        }
    }

    /// The interpolant f̃ of `bxdf`'s lobe at the geometry of `c` and
    /// wavelength `lambda` nm.
    #[inline]
    pub fn interpolant(&self, bxdf: &dyn Bxdf, c: &Corners, lambda: f64) -> f64 {
        self.rows(bxdf, c).interpolant(lambda)
    }

    /// f̃ of `bxdf`'s lobe at geometric node `g` and λ node `k`.
    pub fn node_value(&self, bxdf: &dyn Bxdf, g: usize, k: usize) -> f64 {
        let (i_ci, i_co, i_rho) = (
            g / (RHO_NODES * COS_NODES),
            (g / RHO_NODES) % COS_NODES,
            g % RHO_NODES,
        );
        self.cell(bxdf, i_ci, i_co).f[i_rho * LAMBDA_NODES + k] as f64
    }
}

/// The table's rows at the eight corners of one geometry, found once for
/// its exact part and every wavelength's interpolant: the lookups were a
/// tenth of a full-GHS plate's instructions when each of them searched
/// its cells again.
pub struct Rows<'t> {
    w: [f64; 8],
    f: [&'t [f32]; 8],
    integrals: [&'t [[f64; 3]]; 8],
}

impl Rows<'_> {
    /// The per-basis λ integrals of the corners, with their weights, to
    /// `each(weight, integrals)`.
    #[inline]
    pub(crate) fn for_corners(&self, mut each: impl FnMut(f64, &[[f64; 3]])) {
        for s in 0..8 {
            each(self.w[s], self.integrals[s]);
        }
    }

    /// The interpolant f̃ at wavelength `lambda` nm.
    #[inline]
    pub fn interpolant(&self, lambda: f64) -> f64 {
        let x = (lambda - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN) * (LAMBDA_NODES - 1) as f64;
        let (k, t) = cell(x, LAMBDA_NODES);
        let mut v = 0.0;
        for s in 0..8 {
            let row = self.f[s];
            v += self.w[s] * ((1.0 - t) * row[k] as f64 + t * row[k + 1] as f64);
        }
        v
    }
}
