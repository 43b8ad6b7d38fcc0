//! Chi-square goodness-of-fit test of a model's sampling routine against its pdf.
//!
//! A sample of [`Bxdf::sample`] falls into one of three kinds of outcome:
//! a glossy direction, a delta (specular) direction, or no direction at all
//! (`None`: below the horizon, evanescent, zero weight). The test compares
//! the counts of all three with what the model *claims*:
//!
//! * glossy directions are histogrammed in cells of the sphere, and each
//!   cell's expected count is N ∫_cell pdf dω, integrated by adaptive
//!   cubature ([`super::quadrature`]);
//! * delta samples are expected N · [`Specular::probability`](crate::Specular::probability) times;
//! * lost samples are expected N (1 − P_delta − ∫_{S²} pdf dω) times.
//!
//! **Adaptive binning.** Cells are rectangles in (z = cosθ, φ − φ_mirror),
//! an area-preserving map. Their edges are quantiles of an independent pilot
//! run (first the z-marginal, then φ within each z strip), so every cell holds
//! about the same probability however peaked the lobe (α = 10⁻⁴ works), and
//! the cubature inside a cell only has to resolve an O(1) variation. The
//! horizon z = 0 is always an edge, so a pdf that is discontinuous there
//! costs nothing, and pdf mass below the horizon is tested too.
//!
//! Cells with an expected count below `min_expected` are pooled (smallest
//! first) until the pool reaches it; the statistic Σ (O − E)²/E has
//! (categories − 1) degrees of freedom and its p-value is the chi-square
//! tail, computed with [`super::gamma::chi2_survival`].
//!
//! Besides the statistic the harness checks every sample for consistency:
//! finite unit directions, `sample.pdf == pdf(wi, wo)`, glossy weight
//! `== eval · cosθo / pdf`, delta weight `== specular.weight /
//! specular.probability`, delta direction `== mirror(wi)`, and pdf > 0 at
//! every sampled glossy direction. Any violation is a *defect* and fails the
//! test regardless of the p-value.

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use core::f64::consts::PI;
use core::fmt;

use glam::DVec3;

use super::domain::Domain;
use super::gamma::chi2_survival;
use super::quadrature::{Cubature, Rect, Tolerance, rings_around};
use super::rng::Pcg32;
use crate::frame::reflect_z;
use crate::model::{Bxdf, BxdfSample, Specular};

/// Settings of [`chi2_test`].
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Config {
    /// Samples histogrammed in the test run.
    pub samples: usize,
    /// Samples of the independent pilot run that places the cell edges.
    pub pilot_samples: usize,
    /// Number of z strips (before deduplication).
    pub z_cells: usize,
    /// Maximum number of φ cells per strip.
    pub phi_cells: usize,
    /// Cells expecting fewer samples are pooled (5 is the textbook rule).
    pub min_expected: f64,
    /// Seed of the generator; pilot and test runs use different streams.
    pub seed: u64,
    /// Relative tolerance of the per-sample consistency checks.
    pub consistency_tol: f64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Chi2Config {
            samples: 400_000,
            pilot_samples: 100_000,
            z_cells: 20,
            phi_cells: 20,
            min_expected: 5.0,
            seed: 0x5EED,
            consistency_tol: 1e-6,
        }
    }
}

/// One histogram cell: a (z, φ) rectangle with its counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// z = cosθ range.
    pub z: (f64, f64),
    /// φ range, radians from the mirror azimuth.
    pub phi: (f64, f64),
    /// Samples that fell in the cell.
    pub observed: f64,
    /// N ∫_cell pdf dω.
    pub expected: f64,
}

/// Outcome of [`chi2_test`].
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Report {
    /// Σ (O − E)² / E over the pooled categories.
    pub statistic: f64,
    /// Degrees of freedom (categories after pooling − 1).
    pub dof: usize,
    /// Probability of a statistic at least this large if sampling and pdf agree.
    pub p_value: f64,
    /// Samples in the test run.
    pub samples: usize,
    /// Glossy samples observed, and expected (N ∫ pdf).
    pub glossy: (usize, f64),
    /// Delta samples observed, and expected (N · P_delta).
    pub delta: (usize, f64),
    /// Samples returning `None`, and expected (N (1 − P_delta − ∫ pdf)).
    pub lost: (usize, f64),
    /// ∫_{S²} pdf dω by cubature.
    pub pdf_integral: f64,
    /// Summed error estimate of that cubature.
    pub quadrature_error: f64,
    /// Glossy histogram cells before pooling.
    pub cells: usize,
    /// Categories merged into the pooled one.
    pub pooled: usize,
    /// Largest relative mismatch between `sample.pdf` and `pdf()`.
    pub max_pdf_mismatch: f64,
    /// Largest relative mismatch between a sample's weight and the value
    /// implied by `eval`, `pdf` and `specular`.
    pub max_weight_mismatch: f64,
    /// The three cells contributing most to the statistic.
    pub worst_cells: Vec<Cell>,
    /// Consistency violations (first few, with the offending values).
    pub defects: Vec<String>,
    /// Total number of consistency violations.
    pub defect_count: usize,
}

impl Chi2Report {
    /// Whether the model passes at `significance`: no defects and
    /// p-value ≥ significance.
    pub fn passes(&self, significance: f64) -> bool {
        self.defect_count == 0 && self.p_value >= significance
    }

    /// `Ok` if [`Chi2Report::passes`], otherwise the full report as the error.
    pub fn check(&self, significance: f64) -> Result<(), String> {
        if self.passes(significance) {
            Ok(())
        } else {
            Err(format!(
                "chi-square test rejected at significance {significance:.3e}: {self}"
            ))
        }
    }
}

impl fmt::Display for Chi2Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chi2 = {:.2}, dof = {}, p = {:.4e}; N = {}: glossy {}/{:.1}, delta {}/{:.1}, lost {}/{:.1} \
             (observed/expected); ∫pdf = {:.8} ± {:.1e}; {} cells, {} pooled; \
             max pdf mismatch {:.1e}, max weight mismatch {:.1e}",
            self.statistic,
            self.dof,
            self.p_value,
            self.samples,
            self.glossy.0,
            self.glossy.1,
            self.delta.0,
            self.delta.1,
            self.lost.0,
            self.lost.1,
            self.pdf_integral,
            self.quadrature_error,
            self.cells,
            self.pooled,
            self.max_pdf_mismatch,
            self.max_weight_mismatch,
        )?;
        for c in &self.worst_cells {
            write!(
                f,
                "; cell z∈[{:.6}, {:.6}] φ∈[{:.4}, {:.4}]: {}/{:.1}",
                c.z.0, c.z.1, c.phi.0, c.phi.1, c.observed, c.expected
            )?;
        }
        if self.defect_count > 0 {
            write!(
                f,
                "; {} DEFECTS: {}",
                self.defect_count,
                self.defects.join(" | ")
            )?;
        }
        Ok(())
    }
}

/// Cell layout: z strips, each with its own φ edges.
struct Bins {
    z_edges: Vec<f64>,
    phi_edges: Vec<Vec<f64>>,
    offsets: Vec<usize>,
}

/// Edges at the quantiles k/cells of `values` (sorted in place), midway
/// between neighbouring order statistics, strictly inside (lo, hi).
fn quantile_edges(values: &mut [f64], cells: usize, lo: f64, hi: f64) -> Vec<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    let mut edges = Vec::with_capacity(cells + 1);
    edges.push(lo);
    for k in 1..cells {
        let j = (k * n) / cells;
        if j == 0 || j >= n {
            continue;
        }
        let e = 0.5 * (values[j - 1] + values[j]);
        if e > *edges.last().unwrap_or(&lo) && e < hi {
            edges.push(e);
        }
    }
    edges.push(hi);
    edges
}

impl Bins {
    fn from_pilot(points: &[(f64, f64)], cfg: &Chi2Config) -> Bins {
        let mut zs: Vec<f64> = points.iter().map(|p| p.0).collect();
        let mut z_edges = quantile_edges(&mut zs, cfg.z_cells.max(1), -1.0, 1.0);
        if !z_edges.contains(&0.0) {
            z_edges.push(0.0);
            z_edges.sort_by(f64::total_cmp);
        }
        let mut phi_edges = Vec::with_capacity(z_edges.len() - 1);
        let mut offsets = Vec::with_capacity(z_edges.len());
        let mut total = 0;
        for w in z_edges.windows(2) {
            let mut phis: Vec<f64> = points
                .iter()
                .filter(|p| p.0 >= w[0] && p.0 < w[1])
                .map(|p| p.1)
                .collect();
            // About 50 pilot points per cell keep the quantiles meaningful.
            let cells = (phis.len() / 50).clamp(1, cfg.phi_cells.max(1));
            let edges = quantile_edges(&mut phis, cells, -PI, PI);
            offsets.push(total);
            total += edges.len() - 1;
            phi_edges.push(edges);
        }
        offsets.push(total);
        Bins {
            z_edges,
            phi_edges,
            offsets,
        }
    }

    fn cell_count(&self) -> usize {
        *self.offsets.last().unwrap_or(&0)
    }

    fn locate(&self, z: f64, phi: f64) -> usize {
        let strips = self.z_edges.len() - 1;
        let s = self
            .z_edges
            .partition_point(|&e| e <= z)
            .saturating_sub(1)
            .min(strips - 1);
        let pe = &self.phi_edges[s];
        let c = pe
            .partition_point(|&e| e <= phi)
            .saturating_sub(1)
            .min(pe.len() - 2);
        self.offsets[s] + c
    }

    fn rect(&self, index: usize) -> Rect {
        let s = self.offsets.partition_point(|&o| o <= index) - 1;
        let c = index - self.offsets[s];
        Rect {
            x0: self.z_edges[s],
            x1: self.z_edges[s + 1],
            y0: self.phi_edges[s][c],
            y1: self.phi_edges[s][c + 1],
        }
    }
}

/// Symmetric relative difference in [0, 1]; 0 when both are 0.
fn rel_diff(a: f64, b: f64) -> f64 {
    let m = libm::fabs(a).max(libm::fabs(b));
    if m == 0.0 { 0.0 } else { libm::fabs(a - b) / m }
}

struct Defects {
    list: Vec<String>,
    count: usize,
}

impl Defects {
    fn push(&mut self, make: impl FnOnce() -> String) {
        self.count += 1;
        if self.list.len() < 5 {
            self.list.push(make());
        }
    }
}

/// The model under test at one incident direction and wavelength.
struct Setup<'a, B: ?Sized> {
    bxdf: &'a B,
    wi: DVec3,
    lambda_nm: f64,
    domain: Domain,
    mirror: DVec3,
    spec: Specular,
}

/// Runs the chi-square test of `bxdf.sample` against `bxdf.pdf` (and
/// `bxdf.specular`) for one incident direction and wavelength.
pub fn chi2_test<B: Bxdf + ?Sized>(
    bxdf: &B,
    wi: DVec3,
    lambda_nm: f64,
    cfg: &Chi2Config,
) -> Chi2Report {
    let setup = Setup {
        bxdf,
        wi,
        lambda_nm,
        domain: Domain::new(wi),
        mirror: reflect_z(wi),
        spec: bxdf.specular(wi, lambda_nm),
    };
    let n = cfg.samples.max(1);
    let mut defects = Defects {
        list: Vec::new(),
        count: 0,
    };

    let pilot = pilot_run(&setup, cfg);
    let bins = Bins::from_pilot(&pilot, cfg);
    let pilot_cells = PilotCells::new(&bins, &pilot);
    let run = test_run(&setup, &bins, n, cfg, &mut defects);
    let expected = expected_counts(&setup, &bins, &pilot_cells, &run.observed, n, &mut defects);
    let (pdf_integral, quadrature_error) = (expected.pdf_integral, expected.quadrature_error);

    let p_delta = setup.spec.probability;
    if !(p_delta.is_finite() && (0.0..=1.0).contains(&p_delta)) {
        defects.push(|| format!("specular().probability = {p_delta} is not a probability"));
    }
    let lost_p = 1.0 - p_delta - pdf_integral;
    if lost_p < -(1e-6 + quadrature_error) {
        defects.push(|| {
            format!("∫pdf = {pdf_integral} plus P_delta = {p_delta} exceeds 1: the pdf is over-normalised")
        });
    }
    let lost_expected = n as f64 * lost_p.max(0.0);
    let delta_expected = n as f64 * p_delta;

    // Categories: glossy cells, delta, lost.
    let mut categories: Vec<(f64, f64)> = expected
        .cells
        .iter()
        .map(|c| (c.observed, c.expected))
        .collect();
    if p_delta > 0.0 || run.delta > 0 {
        categories.push((run.delta as f64, delta_expected));
    }
    categories.push((run.lost as f64, lost_expected));
    let pooled = pool_and_sum(categories, cfg.min_expected);

    Chi2Report {
        statistic: pooled.statistic,
        dof: pooled.dof,
        p_value: pooled.p_value,
        samples: n,
        glossy: (run.glossy, n as f64 * pdf_integral),
        delta: (run.delta, delta_expected),
        lost: (run.lost, lost_expected),
        pdf_integral,
        quadrature_error,
        cells: expected.cells.len(),
        pooled: pooled.pooled,
        max_pdf_mismatch: run.max_pdf_mismatch,
        max_weight_mismatch: run.max_weight_mismatch,
        worst_cells: worst_cells(&expected.cells),
        defects: defects.list,
        defect_count: defects.count,
    }
}

/// Positions (z, φ) of the glossy samples of the pilot run, which places the cell edges.
fn pilot_run<B: Bxdf + ?Sized>(setup: &Setup<'_, B>, cfg: &Chi2Config) -> Vec<(f64, f64)> {
    let mut rng = Pcg32::new(cfg.seed, 1);
    let mut pilot = Vec::with_capacity(cfg.pilot_samples);
    for _ in 0..cfg.pilot_samples {
        if let Some(s) = setup.bxdf.sample(setup.wi, setup.lambda_nm, rng.uniform3())
            && !s.is_delta
            && s.wo.is_finite()
        {
            pilot.push(setup.domain.coords(s.wo));
        }
    }
    pilot
}

/// Per cell: pilot count and bounding box of its pilot points, around which the cubature
/// grades its panels (edge cells of a narrow lobe hold all their mass in one corner).
struct PilotCells {
    counts: Vec<usize>,
    boxes: Vec<Rect>,
    total: usize,
}

impl PilotCells {
    fn new(bins: &Bins, pilot: &[(f64, f64)]) -> PilotCells {
        let mut counts = alloc::vec![0usize; bins.cell_count()];
        let empty = Rect {
            x0: f64::INFINITY,
            x1: f64::NEG_INFINITY,
            y0: f64::INFINITY,
            y1: f64::NEG_INFINITY,
        };
        let mut boxes = alloc::vec![empty; bins.cell_count()];
        for &(z, phi) in pilot {
            let c = bins.locate(z, phi);
            counts[c] += 1;
            let b = &mut boxes[c];
            *b = Rect {
                x0: b.x0.min(z),
                x1: b.x1.max(z),
                y0: b.y0.min(phi),
                y1: b.y1.max(phi),
            };
        }
        PilotCells {
            counts,
            boxes,
            total: pilot.len(),
        }
    }
}

/// Counts of the test run and the worst per-sample mismatches seen.
struct TestRun {
    observed: Vec<usize>,
    glossy: usize,
    delta: usize,
    lost: usize,
    max_pdf_mismatch: f64,
    max_weight_mismatch: f64,
}

/// Draws `n` samples, checks each for consistency and histograms the glossy ones.
fn test_run<B: Bxdf + ?Sized>(
    setup: &Setup<'_, B>,
    bins: &Bins,
    n: usize,
    cfg: &Chi2Config,
    defects: &mut Defects,
) -> TestRun {
    let mut rng = Pcg32::new(cfg.seed, 2);
    let mut run = TestRun {
        observed: alloc::vec![0usize; bins.cell_count()],
        glossy: 0,
        delta: 0,
        lost: 0,
        max_pdf_mismatch: 0.0,
        max_weight_mismatch: 0.0,
    };
    for _ in 0..n {
        let u = rng.uniform3();
        let Some(s) = setup.bxdf.sample(setup.wi, setup.lambda_nm, u) else {
            run.lost += 1;
            continue;
        };
        if !(s.weight.is_finite() && s.weight >= 0.0 && s.pdf.is_finite() && s.pdf > 0.0) {
            defects.push(|| {
                format!(
                    "u = {u:?}: weight {} / pdf {} not finite, positive",
                    s.weight, s.pdf
                )
            });
            continue;
        }
        if !(s.wo.is_finite() && libm::fabs(s.wo.length() - 1.0) < 1e-9) {
            defects.push(|| format!("u = {u:?}: wo = {:?} is not a unit vector", s.wo));
            continue;
        }
        if s.is_delta {
            run.delta += 1;
            check_delta(setup, &s, u, cfg.consistency_tol, &mut run, defects);
            continue;
        }
        run.glossy += 1;
        check_glossy(setup, &s, u, cfg.consistency_tol, &mut run, defects);
        let (z, phi) = setup.domain.coords(s.wo);
        run.observed[bins.locate(z, phi)] += 1;
    }
    run
}

/// A delta sample must be the mirror direction with the weight and probability of
/// `specular()`.
fn check_delta<B: Bxdf + ?Sized>(
    setup: &Setup<'_, B>,
    s: &BxdfSample,
    u: [f64; 3],
    tol: f64,
    run: &mut TestRun,
    defects: &mut Defects,
) {
    let spec = setup.spec;
    let want_w = if spec.probability > 0.0 {
        spec.weight / spec.probability
    } else {
        f64::NAN
    };
    let dw = rel_diff(s.weight, want_w);
    let dp = rel_diff(s.pdf, spec.probability);
    run.max_weight_mismatch = run
        .max_weight_mismatch
        .max(if dw.is_nan() { 1.0 } else { dw });
    run.max_pdf_mismatch = run.max_pdf_mismatch.max(dp);
    if !(dw <= tol && dp <= tol) || (s.wo - setup.mirror).length() > 1e-9 {
        defects.push(|| {
            format!(
                "u = {u:?}: delta sample (wo {:?}, weight {}, pdf {}) disagrees with mirror {:?} / \
                 specular() {:?}",
                s.wo, s.weight, s.pdf, setup.mirror, spec
            )
        });
    }
}

/// A glossy sample must land where `pdf()` is positive, with `pdf()` as its pdf and
/// `eval · cosθo / pdf` as its weight.
fn check_glossy<B: Bxdf + ?Sized>(
    setup: &Setup<'_, B>,
    s: &BxdfSample,
    u: [f64; 3],
    tol: f64,
    run: &mut TestRun,
    defects: &mut Defects,
) {
    let pdf = setup.bxdf.pdf(setup.wi, s.wo, setup.lambda_nm);
    let f = setup.bxdf.eval(setup.wi, s.wo, setup.lambda_nm);
    if !(pdf > 0.0 && pdf.is_finite()) {
        defects.push(|| {
            format!(
                "u = {u:?}: sampled wo = {:?} where pdf() = {pdf} (eval {f})",
                s.wo
            )
        });
        return;
    }
    let dp = rel_diff(s.pdf, pdf);
    let want_w = f * libm::fabs(s.wo.z) / pdf;
    let dw = rel_diff(s.weight, want_w);
    run.max_pdf_mismatch = run.max_pdf_mismatch.max(dp);
    run.max_weight_mismatch = run.max_weight_mismatch.max(dw);
    if dp > tol || dw > tol {
        defects.push(|| {
            format!(
                "u = {u:?}, wo = {:?}: sample (weight {}, pdf {}) vs eval·cos/pdf = {want_w}, pdf() = {pdf}",
                s.wo, s.weight, s.pdf
            )
        });
    }
}

/// The glossy cells with their expected counts, and ∫_{S²} pdf dω with its error.
struct Expected {
    cells: Vec<Cell>,
    pdf_integral: f64,
    quadrature_error: f64,
}

/// Expected counts by cubature of the pdf over each cell. The absolute tolerance keeps
/// N·error far below the cell's Poisson noise √E.
fn expected_counts<B: Bxdf + ?Sized>(
    setup: &Setup<'_, B>,
    bins: &Bins,
    pilot_cells: &PilotCells,
    observed: &[usize],
    n: usize,
    defects: &mut Defects,
) -> Expected {
    let cubature = Cubature::new();
    let pilot_n = pilot_cells.total.max(1) as f64;
    let mut out = Expected {
        cells: Vec::with_capacity(bins.cell_count()),
        pdf_integral: 0.0,
        quadrature_error: 0.0,
    };
    for (i, (&obs, &pc)) in observed.iter().zip(&pilot_cells.counts).enumerate() {
        let rect = bins.rect(i);
        let panels = if pc > 0 {
            rings_around(rect, pilot_cells.boxes[i])
        } else {
            alloc::vec![rect]
        };
        let p_guess = (pc as f64 / pilot_n).max(1.0 / n as f64);
        let tol = Tolerance {
            abs: 1e-3 * libm::sqrt(p_guess / n as f64),
            rel: 1e-12,
            max_evals: 4_000_000,
        };
        let integral = cubature.integrate(
            |z, phi| {
                let p = setup
                    .bxdf
                    .pdf(setup.wi, setup.domain.direction(z, phi), setup.lambda_nm);
                if p.is_finite() { p } else { f64::INFINITY }
            },
            &panels,
            tol,
        );
        if !integral.value.is_finite() || integral.value < 0.0 {
            defects.push(|| {
                format!(
                    "pdf is not finite and non-negative in cell {rect:?}: ∫ = {}",
                    integral.value
                )
            });
        }
        out.pdf_integral += integral.value;
        out.quadrature_error += integral.error;
        out.cells.push(Cell {
            z: (rect.x0, rect.x1),
            phi: (rect.y0, rect.y1),
            observed: obs as f64,
            expected: n as f64 * integral.value,
        });
    }
    out
}

/// The statistic over the pooled categories.
struct Pooled {
    statistic: f64,
    dof: usize,
    p_value: f64,
    pooled: usize,
}

/// Pools the (observed, expected) categories expecting fewer than `min_expected`, smallest
/// first, until the pool reaches it; then Σ (O − E)²/E and its chi-square tail.
fn pool_and_sum(mut categories: Vec<(f64, f64)>, min_expected: f64) -> Pooled {
    categories.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut pool_o, mut pool_e, mut pooled) = (0.0, 0.0, 0usize);
    let mut kept = Vec::with_capacity(categories.len());
    for (o, e) in categories {
        if e < min_expected || (pooled > 0 && pool_e < min_expected) {
            pool_o += o;
            pool_e += e;
            pooled += 1;
        } else {
            kept.push((o, e));
        }
    }
    if pooled > 0 {
        kept.push((pool_o, pool_e));
    }
    let statistic: f64 = kept
        .iter()
        .map(|&(o, e)| {
            if e > 0.0 {
                (o - e) * (o - e) / e
            } else if o > 0.0 {
                f64::INFINITY
            } else {
                0.0
            }
        })
        .sum();
    let dof = kept.len().saturating_sub(1);
    let p_value = if statistic.is_finite() {
        chi2_survival(statistic, dof)
    } else {
        0.0
    };
    Pooled {
        statistic,
        dof,
        p_value,
        pooled,
    }
}

/// The three cells contributing most to the statistic.
fn worst_cells(cells: &[Cell]) -> Vec<Cell> {
    let mut worst = cells.to_vec();
    let contribution = |c: &Cell| {
        if c.expected > 0.0 {
            (c.observed - c.expected) * (c.observed - c.expected) / c.expected
        } else {
            c.observed
        }
    };
    worst.sort_by(|a, b| contribution(b).total_cmp(&contribution(a)));
    worst.truncate(3);
    worst
}
