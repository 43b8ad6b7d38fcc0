//! Furnace test: the directional albedo ρ(wi) = ∫ f(wi, wo) cosθo dωo + specular
//! weight, computed two independent ways.
//!
//! * [`albedo_sampled`]: the mean of the sample weights of [`Bxdf::sample`]
//!   (delta weights included, `None` counting 0), with its standard error.
//!   Unbiased only if sampling, pdf and weights agree.
//! * [`albedo_quadrature`]: deterministic adaptive cubature of `eval · cosθo`
//!   over the upper hemisphere, plus `specular(wi).weight`. It never calls
//!   `sample` or `pdf`. The initial panels are graded geometrically towards
//!   the mirror direction's z and azimuth, towards the pole and towards the
//!   horizon, down to widths of 10⁻⁷, so lobes as narrow as α ≈ 10⁻³ are
//!   bracketed before the error-driven refinement starts; the area-preserving
//!   (z, φ) map needs no Jacobian.

use core::f64::consts::PI;

use glam::DVec3;

use super::domain::Domain;
use super::quadrature::{Cubature, Tolerance, graded_edges, grid};
use super::rng::Pcg32;
use crate::model::Bxdf;

/// Albedo estimated from the model's own sampling routine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledAlbedo {
    /// Mean sample weight.
    pub mean: f64,
    /// Standard error of the mean.
    pub std_error: f64,
    /// Number of samples drawn.
    pub samples: usize,
    /// Fraction of samples that were delta samples.
    pub delta_fraction: f64,
    /// Fraction of samples that returned `None`.
    pub lost_fraction: f64,
    /// Largest single weight seen.
    pub max_weight: f64,
    /// Samples whose weight was NaN, infinite or negative (counted as 0).
    pub invalid: usize,
}

/// Albedo by deterministic cubature of `eval`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadratureAlbedo {
    /// Glossy part plus specular weight.
    pub value: f64,
    /// ∫ eval · cosθo dω over the upper hemisphere.
    pub glossy: f64,
    /// `specular(wi).weight`.
    pub specular: f64,
    /// Error estimate of the cubature.
    pub error: f64,
    /// Integrand evaluations.
    pub evals: usize,
    /// Whether the tolerance was met.
    pub converged: bool,
}

/// Mean of `samples` sample weights at `wi`, `lambda_nm`, seeded by `seed`.
pub fn albedo_sampled<B: Bxdf + ?Sized>(
    bxdf: &B,
    wi: DVec3,
    lambda_nm: f64,
    samples: usize,
    seed: u64,
) -> SampledAlbedo {
    let mut rng = Pcg32::new(seed, 3);
    let n = samples.max(1);
    // Welford's running mean and variance: many near-equal weights.
    let (mut mean, mut m2) = (0.0, 0.0);
    let (mut delta, mut lost, mut invalid) = (0usize, 0usize, 0usize);
    let mut max_weight = 0.0f64;
    for i in 0..n {
        let w = match bxdf.sample(wi, lambda_nm, rng.uniform3()) {
            None => {
                lost += 1;
                0.0
            }
            Some(s) => {
                if s.is_delta {
                    delta += 1;
                }
                if s.weight.is_finite() && s.weight >= 0.0 {
                    s.weight
                } else {
                    invalid += 1;
                    0.0
                }
            }
        };
        max_weight = max_weight.max(w);
        let d = w - mean;
        mean += d / (i + 1) as f64;
        m2 += d * (w - mean);
    }
    let var = if n > 1 { m2 / (n - 1) as f64 } else { 0.0 };
    SampledAlbedo {
        mean,
        std_error: libm::sqrt(var / n as f64),
        samples: n,
        delta_fraction: delta as f64 / n as f64,
        lost_fraction: lost as f64 / n as f64,
        max_weight,
        invalid,
    }
}

/// Albedo at `wi`, `lambda_nm` by adaptive cubature of `eval · cosθo` to
/// absolute tolerance `tol` (plus `specular(wi).weight`).
pub fn albedo_quadrature<B: Bxdf + ?Sized>(
    bxdf: &B,
    wi: DVec3,
    lambda_nm: f64,
    tol: f64,
) -> QuadratureAlbedo {
    let domain = Domain::new(wi);
    let z_mirror = wi.z.clamp(0.0, 1.0);
    let zs = graded_edges(0.0, 1.0, &[0.0, z_mirror, 1.0], 4.0, 1e-7);
    let phis = graded_edges(-PI, PI, &[-PI, 0.0, PI], 4.0, 1e-7);
    let integral = Cubature::new().integrate(
        |z, phi| {
            let v = bxdf.eval(wi, domain.direction(z, phi), lambda_nm) * z;
            if v.is_finite() { v } else { f64::INFINITY }
        },
        &grid(&zs, &phis),
        Tolerance {
            abs: tol,
            rel: 0.0,
            max_evals: 40_000_000,
        },
    );
    let specular = bxdf.specular(wi, lambda_nm).weight;
    QuadratureAlbedo {
        value: integral.value + specular,
        glossy: integral.value,
        specular,
        error: integral.error,
        evals: integral.evals,
        converged: integral.converged,
    }
}
