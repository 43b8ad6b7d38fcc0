//! Exact integration over λ of the path contributions whose spectrum is one
//! emission spectrum times one conductor Fresnel factor.
//!
//! A camera ray that meets a microfacet or smooth conductor
//! ([`brdf::spec::ModelKind::fresnel_only`]) and then light contributes
//! XYZ = G · ∫ Le(λ) F(λ, cosθd) cmf(λ) dλ with G free of λ. Sampling λ
//! estimates that integral with noise and costs a Fresnel term, an emission
//! value and a colour-matching lookup per wavelength; but the integral
//! depends on the path only through cosθd, so it is computed once per
//! (Fresnel term, emission basis spectrum) pair on a grid in cosθd and
//! interpolated (cubic Lagrange). Each grid is checked against direct
//! quadrature halfway between its nodes and refined until every channel is
//! within [`TOLERANCE`] of that channel's largest magnitude; a term that
//! needs more than [`MAX_INTERVALS`] intervals gets no table and its paths
//! sample wavelengths.
//!
//! The quadrature over λ is Gauss–Legendre (4 points) on the intervals
//! between every knot of the integrand's pieces (the 1 nm colour-matching
//! and sky rows, the n, κ table's rows, an emission table's rows), inside
//! which the integrand is smooth: it integrates the very functions the
//! sampled estimator evaluates, so the table is that estimator's
//! expectation, not an approximation of the physics beside it.
//!
//! Emission is linear in a few basis spectra: a light's own spectrum (one
//! per distinct spectrum), the three colour-matching functions of an
//! RGB-lifted environment map, the four daylight-sky functions.

use crate::glossy_lambda_table::{Corners, GlossyTable, Rows};
use crate::light::{Emission, Environment, LightKind, Lights};
use crate::spectrum::{Cie, LAMBDA_MAX, LAMBDA_MIN, Spectrum};
use brdf::Fresnel;
use brdf::fresnel::conductor_reflectance_ratio;
use brdf::numerics::interp::lagrange4;
use brdf::numerics::quadrature::gl4_nodes;

/// Largest interpolation error accepted, relative to the largest magnitude
/// of the same basis function's channel over cosθd ∈ [0, 1].
pub const TOLERANCE: f64 = 1e-6;

/// Intervals in cosθd of the finest grid tried.
pub const MAX_INTERVALS: usize = 4096;

/// Intervals of the first grid tried.
const FIRST_INTERVALS: usize = 32;

/// One emission basis function, borrowed from the lights while building.
#[derive(Clone, Copy)]
enum Basis<'a> {
    Spectrum(&'a Spectrum),
    /// Colour-matching function k of an RGB-lifted environment map.
    Cmf(usize),
    /// Basis function k of the daylight sky.
    Sky(&'a crate::sky::Sky, usize),
}

impl Basis<'_> {
    fn eval(&self, lambda: f64) -> f64 {
        match *self {
            Basis::Spectrum(s) => s.eval(lambda),
            Basis::Cmf(k) => Cie::get().xyz(lambda)[k],
            Basis::Sky(sky, k) => {
                let mut c = [0.0; 4];
                c[k] = 1.0;
                sky.spectral(&c, lambda)
            }
        }
    }

    /// Wavelengths inside 360–830 nm where the function has a kink.
    fn knots(&self) -> Vec<f64> {
        match self {
            Basis::Spectrum(Spectrum::Table(t)) => t.rows().iter().map(|r| r[0]).collect(),
            _ => Vec::new(),
        }
    }
}

/// Quadrature nodes in λ with each basis function's weighted colour matching.
struct Nodes {
    /// The wavelength of each node (nm).
    lambda: Vec<f64>,
    /// (n, κ) at each node.
    nk: Vec<(f64, f64)>,
    /// Per node, per basis: quadrature weight · basis(λ) · (x̄, ȳ, z̄)(λ).
    w: Vec<[f64; 3]>,
    bases: usize,
}

impl Nodes {
    fn new(fresnel: &Fresnel, bases: &[Basis]) -> Nodes {
        Self::with_cuts(fresnel, bases, &[])
    }

    /// [`new`](Self::new), the intervals also broken at `extra` (nm).
    fn with_cuts(fresnel: &Fresnel, bases: &[Basis], extra: &[f64]) -> Nodes {
        let mut cuts: Vec<f64> = (LAMBDA_MIN as i64..=LAMBDA_MAX as i64)
            .map(|l| l as f64)
            .chain(extra.iter().copied())
            .collect();
        if let Fresnel::Conductor(ior) = fresnel
            && let Some(rows) = ior.rows()
        {
            cuts.extend(rows.iter().map(|r| r[0]));
        }
        for b in bases {
            cuts.extend(b.knots());
        }
        cuts.retain(|l| (LAMBDA_MIN..=LAMBDA_MAX).contains(l));
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let cie = Cie::get();
        let nodes = gl4_nodes(&cuts);
        let mut nk = Vec::with_capacity(nodes.len());
        let mut lambda = Vec::with_capacity(nodes.len());
        let mut w = Vec::with_capacity(nodes.len() * bases.len());
        for (l, gw) in nodes {
            lambda.push(l);
            nk.push(match fresnel {
                Fresnel::Conductor(ior) => ior.at(l),
                Fresnel::One => (1.0, 0.0),
            });
            let c = cie.xyz(l);
            for b in bases {
                let v = gw * b.eval(l);
                w.push([v * c[0], v * c[1], v * c[2]]);
            }
        }
        Nodes {
            lambda,
            nk,
            w,
            bases: bases.len(),
        }
    }

    /// ∫ basis · F(cos²θd = `cos2`) · cmf dλ for every basis, into `out`.
    fn integrate(&self, fresnel: bool, cos2: f64, out: &mut [[f64; 3]]) {
        self.integrate_with(
            |i| {
                if fresnel {
                    let (n, k) = self.nk[i];
                    conductor_reflectance_ratio(cos2, 1.0, n, k)
                } else {
                    1.0
                }
            },
            out,
        );
    }

    /// ∫ basis · f · cmf dλ for every basis, into `out`, with `f(i)` the
    /// factor's value at node i.
    fn integrate_with(&self, f: impl Fn(usize) -> f64, out: &mut [[f64; 3]]) {
        out.iter_mut().for_each(|o| *o = [0.0; 3]);
        for i in 0..self.lambda.len() {
            let f = f(i);
            let w = &self.w[i * self.bases..(i + 1) * self.bases];
            for (o, w) in out.iter_mut().zip(w) {
                for c in 0..3 {
                    o[c] += f * w[c];
                }
            }
        }
    }
}

/// Cubic Lagrange weights at `x` ∈ [0, 1] on a grid of `n` ≥ 3 intervals:
/// the first of the four nodes and their weights.
#[inline]
fn cubic(x: f64, n: usize) -> (usize, [f64; 4]) {
    let x = x.clamp(0.0, 1.0) * n as f64;
    // Nodes i − 1 … i + 2 around x, shifted inward at the ends.
    let i = (x as u32 as usize).clamp(1, n - 2);
    (i - 1, lagrange4(x - i as f64))
}

/// The integrals for one Fresnel term.
enum FresnelTable {
    /// F does not depend on λ (F ≡ 1 or a constant index): F(cosθd) times
    /// the direct integrals.
    Flat(Fresnel),
    /// Per node of a grid of `intervals` in cosθd, per basis function.
    Grid {
        intervals: usize,
        rows: Vec<[f64; 3]>,
    },
}

/// What was tabulated, for the scene summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TableStats {
    /// Fresnel terms with a grid.
    pub grids: usize,
    /// Fresnel terms independent of λ (no grid needed).
    pub flat: usize,
    /// Fresnel terms whose grid did not converge (their paths sample λ).
    pub refused: usize,
    /// Largest grid, in intervals.
    pub max_intervals: usize,
    /// Delta lobes with a grid.
    pub delta_grids: usize,
    /// Delta lobes whose grid did not converge (their paths sample λ).
    pub delta_refused: usize,
    /// Glossy control-variate tables ([`SpectralTables::add_glossy`]).
    pub glossy_grids: usize,
}

/// A material's delta lobe whose weight depends on the path only through
/// cosθi, to integrate over λ exactly at a first vertex.
#[derive(Clone, Copy)]
pub struct DeltaLobe<'a> {
    /// The model's Fresnel factor: its n, κ rows break the λ quadrature.
    pub fresnel: &'a Fresnel,
    /// The model: [`brdf::Bxdf::specular`] gives the lobe's weight.
    pub bxdf: &'a dyn brdf::Bxdf,
}

/// The exact spectral integrals of a scene's single-Fresnel contributions.
pub struct SpectralTables {
    /// Per light: its first basis function and how many it has.
    light_basis: Vec<(u32, u32)>,
    /// The environment's basis functions, for [`Emission::Cmf`] and
    /// [`Emission::Sky`], which do not name their light.
    environment_basis: (u32, u32),
    /// ∫ basis · cmf dλ per basis function (F ≡ 1).
    direct: Vec<[f64; 3]>,
    /// Per material: its Fresnel table, if it has one.
    material: Vec<Option<u32>>,
    /// Per material: the table of its delta lobe, if it has one.
    delta: Vec<Option<u32>>,
    tables: Vec<FresnelTable>,
    /// Per material: the control-variate table of its glossy lobe
    /// ([`add_glossy`](Self::add_glossy)), if it has one.
    glossy: Vec<Option<GlossyTable>>,
    /// What was built.
    pub stats: TableStats,
}

impl SpectralTables {
    /// Tables for every distinct Fresnel term among `fresnels` (one entry
    /// per material, `None` for materials that are not Fresnel-only),
    /// against the emission of `lights`.
    pub fn build(lights: &Lights, fresnels: &[Option<&Fresnel>]) -> SpectralTables {
        Self::build_with_deltas(lights, fresnels, &[])
    }

    /// [`build`](Self::build), and a table per delta lobe among `deltas`
    /// (one entry per material, `None` for materials without such a lobe;
    /// may be shorter than `fresnels`): ∫ Le(λ) w(λ, cosθi) cmf(λ) dλ with
    /// w the lobe's weight ([`brdf::Bxdf::specular`]) at wi = (sinθi, 0,
    /// cosθi). A lobe whose weight is zero everywhere gets none.
    pub fn build_with_deltas(
        lights: &Lights,
        fresnels: &[Option<&Fresnel>],
        deltas: &[Option<DeltaLobe>],
    ) -> SpectralTables {
        let (bases, light_basis, environment_basis) = scene_bases(lights);
        let direct = {
            let nodes = Nodes::new(&Fresnel::One, &bases);
            let mut d = vec![[0.0; 3]; bases.len()];
            nodes.integrate(false, 1.0, &mut d);
            d
        };

        // Each distinct Fresnel term with the table it got.
        let mut distinct: Vec<(&Fresnel, Option<u32>)> = Vec::new();
        let mut tables = Vec::new();
        let mut stats = TableStats::default();
        let material = fresnels
            .iter()
            .map(|f| {
                let f = (*f)?;
                if let Some(&(_, id)) = distinct.iter().find(|(g, _)| *g == f) {
                    return id;
                }
                let t = match f {
                    Fresnel::One => Some(FresnelTable::Flat(Fresnel::One)),
                    Fresnel::Conductor(ior) if ior.rows().is_none() => {
                        Some(FresnelTable::Flat(f.clone()))
                    }
                    Fresnel::Conductor(_) => grid(f, &bases),
                };
                match &t {
                    Some(FresnelTable::Flat(_)) => stats.flat += 1,
                    Some(FresnelTable::Grid { intervals, .. }) => {
                        stats.grids += 1;
                        stats.max_intervals = stats.max_intervals.max(*intervals);
                    }
                    None => stats.refused += 1,
                }
                let id = t.map(|t| {
                    tables.push(t);
                    (tables.len() - 1) as u32
                });
                distinct.push((f, id));
                id
            })
            .collect();
        let delta = deltas
            .iter()
            .map(|d| {
                let d = (*d)?;
                let weight = |cos: f64, lambda: f64| {
                    let sin = (1.0 - cos * cos).max(0.0).sqrt();
                    d.bxdf
                        .specular(glam::DVec3::new(sin, 0.0, cos), lambda)
                        .weight
                };
                let Some(t) = delta_grid(d.fresnel, &weight, &bases) else {
                    stats.delta_refused += 1;
                    return None;
                };
                if let FresnelTable::Grid { intervals, rows } = &t {
                    if rows.iter().all(|r| r.iter().all(|&v| v == 0.0)) {
                        return None;
                    }
                    stats.delta_grids += 1;
                    stats.max_intervals = stats.max_intervals.max(*intervals);
                }
                tables.push(t);
                Some((tables.len() - 1) as u32)
            })
            .collect();
        SpectralTables {
            light_basis,
            environment_basis,
            direct,
            material,
            delta,
            tables,
            glossy: Vec::new(),
            stats,
        }
    }

    /// Adds a glossy control-variate table ([`crate::glossy_lambda_table`],
    /// built lazily by its users) for every material whose entry in
    /// `glossy` is true (an isotropic glossy lobe), against the emission of
    /// `lights` (the lights these tables were built for).
    pub fn add_glossy(&mut self, lights: &Lights, glossy: &[bool]) {
        if !glossy.iter().any(|&g| g) {
            return;
        }
        let (bases, _, _) = scene_bases(lights);
        let hats = hat_integrals(&bases);
        self.glossy = glossy
            .iter()
            .map(|&g| {
                g.then(|| {
                    self.stats.glossy_grids += 1;
                    GlossyTable::new(hats.clone(), bases.len())
                })
            })
            .collect();
    }

    /// The glossy control-variate table of material `m`, if it has one.
    #[inline]
    pub fn glossy(&self, m: u32) -> Option<&GlossyTable> {
        self.glossy.get(m as usize).and_then(Option::as_ref)
    }

    /// ∫ Le f̃ cmf dλ: the λ integral of `table`'s interpolant of `bxdf`'s
    /// lobe at the geometry of `corners`, under emission `em`.
    #[inline]
    pub fn glossy_exact(
        &self,
        table: &GlossyTable,
        bxdf: &dyn brdf::Bxdf,
        corners: &Corners,
        em: &Emission,
    ) -> [f64; 3] {
        self.glossy_exact_rows(&table.rows(bxdf, corners), em)
    }

    /// [`glossy_exact`](Self::glossy_exact) from the corners' rows, found
    /// once for this and the residual's interpolants.
    #[inline]
    pub fn glossy_exact_rows(&self, rows: &Rows, em: &Emission) -> [f64; 3] {
        let (b, c) = self.basis(em);
        let mut out = [0.0; 3];
        rows.for_corners(|w, rows| c.accumulate(&rows[b..], w, &mut out));
        out
    }

    /// The table of material `m`'s delta lobe, if its emission along the
    /// mirror direction at a first vertex is integrated exactly: read it
    /// with [`reflected`](Self::reflected) at cos²θd = cos²θi.
    #[inline]
    pub fn delta(&self, m: u32) -> Option<u32> {
        self.delta.get(m as usize).copied().flatten()
    }

    /// Whether some material's delta lobe has a table.
    #[inline]
    pub fn has_delta(&self) -> bool {
        self.delta.iter().any(Option::is_some)
    }

    /// The table of material `m`, if its contributions are integrated exactly.
    #[inline]
    pub fn material(&self, m: u32) -> Option<u32> {
        self.material.get(m as usize).copied().flatten()
    }

    /// The basis functions of `em` and their coefficients.
    #[inline]
    fn basis<'e>(&self, em: &'e Emission) -> (usize, Coefficients<'e>) {
        match em {
            Emission::Spectrum(_, k, light) => {
                let (b, _) = self.light_basis[*light as usize];
                (b as usize, Coefficients::One(*k))
            }
            Emission::Cmf(c) => (self.environment_basis.0 as usize, Coefficients::Many(c)),
            Emission::Sky(_, c) => (self.environment_basis.0 as usize, Coefficients::Many(c)),
            Emission::None => (0, Coefficients::None),
        }
    }

    /// ∫ Le cmf dλ: emission seen directly.
    #[inline]
    pub fn direct(&self, em: &Emission) -> [f64; 3] {
        let (b, c) = self.basis(em);
        let mut out = [0.0; 3];
        c.accumulate(&self.direct[b..], 1.0, &mut out);
        out
    }

    /// ∫ Le F cmf dλ through Fresnel table `table` at cos²θd = `num`/`den`.
    #[inline]
    pub fn reflected(&self, table: u32, num: f64, den: f64, em: &Emission) -> [f64; 3] {
        let (b, c) = self.basis(em);
        let mut out = [0.0; 3];
        match &self.tables[table as usize] {
            FresnelTable::Flat(f) => {
                // Any wavelength: the index does not depend on it.
                let r = f.reflectance_ratio(num, den, 550.0);
                c.accumulate(&self.direct[b..], r, &mut out);
            }
            FresnelTable::Grid { intervals, rows } => {
                let nb = self.direct.len();
                // The grid variable x = √cosθd (see `grid`).
                let x = (num / den).max(0.0).sqrt().sqrt();
                let (i, w) = cubic(x, *intervals);
                for (s, &ws) in w.iter().enumerate() {
                    c.accumulate(&rows[(i + s) * nb + b..], ws, &mut out);
                }
            }
        }
        out
    }
}

/// Coefficients of an emission on its basis functions.
enum Coefficients<'e> {
    One(f64),
    Many(&'e [f64]),
    None,
}

impl Coefficients<'_> {
    /// `out += scale · Σ coefficient · rows[j]`.
    #[inline]
    fn accumulate(&self, rows: &[[f64; 3]], scale: f64, out: &mut [f64; 3]) {
        match self {
            Coefficients::One(k) => {
                let s = scale * k;
                for c in 0..3 {
                    out[c] += s * rows[0][c];
                }
            }
            Coefficients::Many(ks) => {
                for (k, r) in ks.iter().zip(rows) {
                    let s = scale * k;
                    for c in 0..3 {
                        out[c] += s * r[c];
                    }
                }
            }
            Coefficients::None => {}
        }
    }
}

/// The emission basis functions of `lights`, each light's first basis
/// function and count, and the environment's.
#[allow(clippy::type_complexity)]
fn scene_bases(lights: &Lights) -> (Vec<Basis<'_>>, Vec<(u32, u32)>, (u32, u32)) {
    let mut bases: Vec<Basis> = Vec::new();
    let mut light_basis = Vec::with_capacity(lights.lights.len());
    let mut environment_basis = (0, 0);
    for (i, l) in lights.lights.iter().enumerate() {
        let own: Vec<Basis> = match l {
            LightKind::Point { spectrum, .. }
            | LightKind::Sphere { spectrum, .. }
            | LightKind::Rectangle { spectrum, .. }
            | LightKind::Environment(Environment::Constant(spectrum)) => {
                vec![Basis::Spectrum(spectrum)]
            }
            LightKind::Environment(Environment::Map(_)) => (0..3).map(Basis::Cmf).collect(),
            LightKind::Environment(Environment::Sky(sky)) => {
                (0..4).map(|k| Basis::Sky(sky, k)).collect()
            }
        };
        // Lights with the same spectrum share its basis function.
        let first = match own.as_slice() {
            [Basis::Spectrum(s)] => bases
                .iter()
                .position(|b| matches!(b, Basis::Spectrum(t) if t == s)),
            _ => None,
        };
        let first = first.unwrap_or_else(|| {
            bases.extend(own.iter().copied());
            bases.len() - own.len()
        });
        light_basis.push((first as u32, own.len() as u32));
        if lights.environment == Some(i) {
            environment_basis = (first as u32, own.len() as u32);
        }
    }

    (bases, light_basis, environment_basis)
}

/// Per λ node k of [`crate::glossy_lambda_table`] and basis function b:
/// ∫ hat_k(λ) b(λ) cmf(λ) dλ at `[k * bases.len() + b]`, by the same
/// knot-aware quadrature, its intervals also broken at the λ nodes (the
/// hats' kinks).
fn hat_integrals(bases: &[Basis]) -> Vec<[f64; 3]> {
    use crate::glossy_lambda_table::{LAMBDA_NODES, lambda_node};
    let knots: Vec<f64> = (0..LAMBDA_NODES).map(lambda_node).collect();
    let nodes = Nodes::with_cuts(&Fresnel::One, bases, &knots);
    let nb = bases.len();
    let mut hats = vec![[0.0; 3]; LAMBDA_NODES * nb];
    let step = (LAMBDA_MAX - LAMBDA_MIN) / (LAMBDA_NODES - 1) as f64;
    for (i, &l) in nodes.lambda.iter().enumerate() {
        let x = ((l - LAMBDA_MIN) / step).clamp(0.0, (LAMBDA_NODES - 1) as f64);
        let k = (x as usize).min(LAMBDA_NODES - 2);
        let t = x - k as f64;
        for b in 0..nb {
            let w = nodes.w[i * nb + b];
            for c in 0..3 {
                hats[k * nb + b][c] += (1.0 - t) * w[c];
                hats[(k + 1) * nb + b][c] += t * w[c];
            }
        }
    }
    hats
}

/// The grid for a Fresnel term whose index depends on λ, refined until it
/// meets [`TOLERANCE`]; `None` if [`MAX_INTERVALS`] do not.
fn grid(fresnel: &Fresnel, bases: &[Basis]) -> Option<FresnelTable> {
    let nodes = Nodes::new(fresnel, bases);
    // Nodes uniform in x = √cosθd, so cosθd = x²: dense near grazing,
    // where a large |n + iκ| puts a narrow pseudo-Brewster dip at
    // cosθd ≈ 1/|n + iκ|. F is smooth in x (F(cosθd) is, and x² is).
    refine(bases.len(), |x, v| {
        let cos = x * x;
        nodes.integrate(true, cos * cos, v);
    })
}

/// The grid of a delta lobe whose weight `weight(cosθi, λ)` (R·e^{−g} for
/// the wave-optical models) depends on the path only through cosθi; the
/// λ nodes also break at the rows of `fresnel`'s n, κ table, where R has
/// kinks. Same grid variable x = √cosθi as [`grid`] (cosθd = cosθi at the
/// mirror), so [`SpectralTables::reflected`] reads it.
fn delta_grid(
    fresnel: &Fresnel,
    weight: &dyn Fn(f64, f64) -> f64,
    bases: &[Basis],
) -> Option<FresnelTable> {
    let nodes = Nodes::new(fresnel, bases);
    let mut f = vec![0.0; nodes.lambda.len()];
    refine(bases.len(), |x, v| {
        // Models give no lobe at exactly cosθi = 0 (wi on the horizon);
        // the grid's end node takes the limit, continuous with its
        // neighbours.
        let cos = (x * x).max(1e-12);
        for (f, &l) in f.iter_mut().zip(&nodes.lambda) {
            *f = weight(cos, l);
        }
        nodes.integrate_with(|i| f[i], v);
    })
}

/// A grid of `nb` basis functions' integrals `at(x, out)` over x ∈ [0, 1],
/// from [`FIRST_INTERVALS`] intervals doubled until cubic interpolation
/// meets [`TOLERANCE`] halfway between the nodes; `None` if
/// [`MAX_INTERVALS`] do not.
fn refine(nb: usize, mut at: impl FnMut(f64, &mut [[f64; 3]])) -> Option<FresnelTable> {
    let mut eval = |x: f64| {
        let mut v = vec![[0.0; 3]; nb];
        at(x, &mut v);
        v
    };
    let mut n = FIRST_INTERVALS;
    let mut rows: Vec<[f64; 3]> = (0..=n).flat_map(|i| eval(i as f64 / n as f64)).collect();
    loop {
        // The midpoints: the check, and the next grid's new nodes.
        let mids: Vec<[f64; 3]> = (0..n)
            .flat_map(|i| eval((i as f64 + 0.5) / n as f64))
            .collect();
        // Per basis function and channel: each is weighted by its own
        // coefficients at run time.
        let mut scale = vec![[0.0f64; 3]; nb];
        for (i, r) in rows.iter().chain(&mids).enumerate() {
            for c in 0..3 {
                scale[i % nb][c] = scale[i % nb][c].max(r[c].abs());
            }
        }
        let mut ok = true;
        'check: for i in 0..n {
            let (j, w) = cubic((i as f64 + 0.5) / n as f64, n);
            for b in 0..nb {
                for c in 0..3 {
                    let v: f64 = (0..4).map(|s| w[s] * rows[(j + s) * nb + b][c]).sum();
                    let exact = mids[i * nb + b][c];
                    // NaN fails too.
                    let within = (v - exact).abs() <= TOLERANCE * scale[b][c];
                    if !within {
                        ok = false;
                        break 'check;
                    }
                }
            }
        }
        if ok {
            return Some(FresnelTable::Grid { intervals: n, rows });
        }
        if 2 * n > MAX_INTERVALS {
            return None;
        }
        let mut finer = Vec::with_capacity((2 * n + 1) * nb);
        for i in 0..n {
            finer.extend_from_slice(&rows[i * nb..(i + 1) * nb]);
            finer.extend_from_slice(&mids[i * nb..(i + 1) * nb]);
        }
        finer.extend_from_slice(&rows[n * nb..]);
        rows = finer;
        n *= 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::{Sky, SkyParams};
    use crate::spectrum::d65;
    use brdf::fresnel::conductor_reflectance;
    use brdf::{Ior, Metal};
    use glam::DVec3;

    fn point(spectrum: Spectrum) -> LightKind {
        LightKind::Point {
            position: DVec3::ZERO,
            spectrum,
        }
    }

    /// ∫ b F cmf dλ by the midpoint rule on 0.01 nm steps: a method that
    /// shares nothing with the tables' knot-aware Gauss–Legendre grid.
    fn brute(fresnel: &Fresnel, cos: f64, b: &dyn Fn(f64) -> f64) -> [f64; 3] {
        let h = 0.01;
        let steps = ((LAMBDA_MAX - LAMBDA_MIN) / h).round() as usize;
        let cie = Cie::get();
        let mut out = [0.0; 3];
        for i in 0..steps {
            let l = LAMBDA_MIN + (i as f64 + 0.5) * h;
            let f = match fresnel {
                Fresnel::One => 1.0,
                Fresnel::Conductor(ior) => {
                    let (n, k) = ior.at(l);
                    conductor_reflectance(cos, n, k)
                }
            };
            let v = f * b(l) * h;
            let c = cie.xyz(l);
            for k in 0..3 {
                out[k] += v * c[k];
            }
        }
        out
    }

    fn close(got: [f64; 3], want: [f64; 3], tol: f64, what: &str) {
        let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() <= tol * scale,
                "{what}: channel {c}: {got:?} vs {want:?}"
            );
        }
    }

    /// Every metal, a constant and a user table, against six emission
    /// spectra (constant, blackbodies at 2700 K and at the accepted extremes
    /// 100 K and 10⁶ K, D65's 5 nm table, a narrow table with knots off the
    /// 1 nm grid) at cosθd from grazing to normal.
    #[test]
    fn tables_are_the_integral_by_an_independent_quadrature() {
        let narrow = Spectrum::table(vec![
            [512.3, 0.0],
            [530.7, 2.0],
            [548.25, 0.5],
            [561.9, 0.0],
        ]);
        let spectra = [
            Spectrum::Constant(1.0),
            Spectrum::Blackbody {
                kelvin: 2700.0,
                scale: 1e-12,
            },
            // The ends of the accepted temperatures: a spectrum rising by
            // e^{−144 000/λ} over the visible, and a Rayleigh–Jeans one.
            Spectrum::Blackbody {
                kelvin: 100.0,
                scale: 1.0,
            },
            Spectrum::Blackbody {
                kelvin: 1e6,
                scale: 1e-20,
            },
            d65(),
            narrow,
        ];
        let lights = Lights {
            lights: spectra.iter().cloned().map(point).collect(),
            environment: None,
            bsdf_only_environment: false,
        };
        let mut fresnels: Vec<Fresnel> = Metal::ALL
            .into_iter()
            .map(|m| Fresnel::conductor(Ior::metal(m)))
            .collect();
        fresnels.push(Fresnel::conductor(Ior::constant(0.3, 4.0).unwrap()));
        fresnels.push(Fresnel::One);
        fresnels.push(Fresnel::conductor(
            Ior::table(vec![
                [350.0, 1.9, 0.2],
                [555.5, 0.2, 3.1],
                [840.0, 3.0, 7.0],
            ])
            .unwrap(),
        ));
        let refs: Vec<Option<&Fresnel>> = fresnels.iter().map(Some).collect();
        let t = SpectralTables::build(&lights, &refs);
        assert_eq!(t.stats.refused, 0);
        assert_eq!(t.stats.flat, 2);
        for (m, f) in fresnels.iter().enumerate() {
            let table = t.material(m as u32).unwrap();
            for (li, s) in spectra.iter().enumerate() {
                let em = Emission::Spectrum(s, 1.7, li as u32);
                for cos in [0.0, 1e-3, 0.05, 0.2, 0.37, 0.5, 0.71, 0.9, 0.999, 1.0] {
                    let want = brute(f, cos, &|l| 1.7 * s.eval(l));
                    let got = t.reflected(table, cos * cos * 3.0, 3.0, &em);
                    close(
                        got,
                        want,
                        2e-6,
                        &format!("material {m}, light {li}, cos {cos}"),
                    );
                }
                if m == 0 {
                    let want = brute(&Fresnel::One, 1.0, &|l| 1.7 * s.eval(l));
                    close(t.direct(&em), want, 2e-6, &format!("direct, light {li}"));
                }
            }
        }
    }

    /// An RGB-lifted environment and the daylight sky: emission on several
    /// basis functions at once.
    #[test]
    fn environment_bases_combine_linearly() {
        let fresnel = Fresnel::conductor(Ior::metal(Metal::Au));
        let sky = Sky::new(SkyParams::default()).unwrap();
        let lights = Lights {
            lights: vec![LightKind::Environment(Environment::Sky(Box::new(sky)))],
            environment: Some(0),
            bsdf_only_environment: false,
        };
        let t = SpectralTables::build(&lights, &[None, Some(&fresnel)]);
        assert_eq!(t.material(0), None);
        let table = t.material(1).unwrap();
        let LightKind::Environment(Environment::Sky(sky)) = &lights.lights[0] else {
            unreachable!()
        };
        let c = [0.8, -0.1, 0.05, 0.3];
        let em = Emission::Sky(sky, c);
        for cos in [0.02, 0.4, 0.95] {
            let want = brute(&fresnel, cos, &|l| sky.spectral(&c, l));
            close(t.reflected(table, cos * cos, 1.0, &em), want, 2e-6, "sky");
        }
        // The colour-matching basis of a lifted map (no map needed: the
        // basis is the environment's, whatever its kind, once built).
        let lights = Lights {
            lights: vec![point(Spectrum::Constant(1.0))],
            environment: None,
            bsdf_only_environment: false,
        };
        let mut t = SpectralTables::build(&lights, &[Some(&fresnel)]);
        let cie_basis: Vec<Basis> = (0..3).map(Basis::Cmf).collect();
        let nodes = Nodes::new(&Fresnel::One, &cie_basis);
        let mut d = vec![[0.0; 3]; 3];
        nodes.integrate(false, 1.0, &mut d);
        t.direct = d;
        t.environment_basis = (0, 3);
        let c = [0.2, 0.5, -0.05];
        let want = brute(&Fresnel::One, 1.0, &|l| {
            let m = Cie::get().xyz(l);
            c[0] * m[0] + c[1] * m[1] + c[2] * m[2]
        });
        close(t.direct(&Emission::Cmf(c)), want, 2e-6, "cmf");
    }

    /// Random n, κ tables over the whole accepted range (n from 1e-6 to 1e6,
    /// κ 0 or from 1e-6 to 1e6, log-uniform, rows at random wavelengths): every grid the builder
    /// accepts meets the tolerance between its nodes, not only at the
    /// midpoints it was checked on.
    #[test]
    fn accepted_grids_meet_the_tolerance_everywhere() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut u = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let lights = Lights {
            lights: vec![point(Spectrum::Constant(1.0))],
            environment: None,
            bsdf_only_environment: false,
        };
        let em = Emission::Spectrum(&Spectrum::Constant(1.0), 1.0, 0);
        let (mut accepted, mut refused) = (0, 0);
        for case in 0..60 {
            let last = [900.0, 1.0 + u(), u()];
            let mut rows: Vec<[f64; 3]> = (0..2 + case % 7)
                .map(|i| {
                    let l = if i == 0 {
                        300.0
                    } else {
                        360.0 + 470.0 * u() + i as f64 * 1e-3
                    };
                    let n = 10f64.powf(-6.0 + 12.0 * u());
                    let k = if u() < 0.2 {
                        0.0
                    } else {
                        10f64.powf(-6.0 + 12.0 * u())
                    };
                    [l, n, k]
                })
                .chain([last])
                .collect();
            rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
            rows.dedup_by(|a, b| a[0] == b[0]);
            let fresnel = Fresnel::conductor(Ior::table(rows).unwrap());
            let t = SpectralTables::build(&lights, &[Some(&fresnel)]);
            let Some(table) = t.material(0) else {
                // Refused only where, at some λ, the index nearly matches
                // air (|η² − 1| small: F rises from ≈ 0 to 1 within a grazing
                // band of that width), nearly vanishes (|η| small: F departs
                // from 1 by ≈ 2|η| within 1 − cosθd ≲ |η|² of the normal), or
                // is huge (|η| large: a pseudo-Brewster dip ≈ 1/|η| wide at
                // cosθd ≈ 1/|η|); no grid resolves these to 10⁻⁶, and their
                // paths sample λ instead.
                let Fresnel::Conductor(ior) = &fresnel else {
                    unreachable!()
                };
                let (closest, smallest, largest) = (0..47_000)
                    .map(|i| {
                        let (n, k) = ior.at(360.0 + i as f64 * 0.01);
                        let e2_minus_1 =
                            ((n * n - k * k - 1.0).powi(2) + (2.0 * n * k).powi(2)).sqrt();
                        (e2_minus_1, (n * n + k * k).sqrt())
                    })
                    .fold((f64::INFINITY, f64::INFINITY, 0.0f64), |a, b| {
                        (a.0.min(b.0), a.1.min(b.1), a.2.max(b.1))
                    });
                assert!(
                    closest < 0.1 || smallest < 0.1 || largest > 100.0,
                    "case {case}: refused, |η² − 1| ≥ {closest}, {smallest} ≤ |η| ≤ {largest}"
                );
                refused += 1;
                continue;
            };
            accepted += 1;
            let nodes = Nodes::new(&fresnel, &[Basis::Spectrum(&Spectrum::Constant(1.0))]);
            let exact = |cos: f64| {
                let mut v = vec![[0.0; 3]];
                nodes.integrate(true, cos * cos, &mut v);
                v[0]
            };
            let scale = (0..=200).fold([0.0f64; 3], |mut s, i| {
                let v = exact(i as f64 / 200.0);
                for c in 0..3 {
                    s[c] = s[c].max(v[c].abs());
                }
                s
            });
            for _ in 0..300 {
                let cos = u();
                let got = t.reflected(table, cos * cos, 1.0, &em);
                let want = exact(cos);
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 2.0 * TOLERANCE * scale[c],
                        "case {case}: cos {cos}: {got:?} vs {want:?}"
                    );
                }
            }
        }
        eprintln!("{accepted} accepted, {refused} refused");
        assert!(accepted >= 10, "{accepted} accepted, {refused} refused");
    }
}
