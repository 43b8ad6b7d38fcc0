//! Residual roulette for the glossy control variate at a first vertex
//! (`first_vertex_cv`): the light sample's estimate is the exact
//! n·∫ Le f̃ cmf dλ plus the sampled residual Σ_j T_j (f − f̃)(λ_j) Le cmf,
//! and the residual is evaluated only with probability p, weighted 1/p.
//!
//! Why: with the continued table the residual is ≈ 0.4 % of f near the
//! mirror direction (`tests/glossy_cv.rs`), yet it costs the model's full
//! evaluation at every wavelength for every light sample (19 % of a
//! full-GHS plate's instructions). Skipped, the light sample needs only
//! the model's densities (for the MIS weights), which the wave-optical
//! models compute without the lobe itself. Measured, it does not pay on
//! the s138 plates (the residual still holds 18 % of full GHS's variance
//! at 256 spp and half of two-scale's), so the default p is 1
//! (`crates/render/README.md`, `glossy_residual`).
//!
//! Unbiased for any p > 0: the residual's term has its expectation over
//! the roulette's draw, and nothing else depends on f (the weights use the
//! densities, and whether a light sample is counted no longer asks whether
//! f is zero at the path's wavelengths). The variance added is
//! (1/p − 1)·E[residual²], small where the table resolves the lobe.

use crate::sampler::Sampler;
use crate::wavelength::MAX_WAVELENGTHS as N;

/// (f, pdf) at each of a path's wavelengths (the integrator's type of the
/// same name; not imported from it, which would make the modules a cycle).
type FPerLambda = [(f64, f64); N];
use brdf::Bxdf;
use glam::DVec3;

/// Whether this light sample evaluates the residual, and the weight its
/// residual term then carries (1/p; 0 where it is skipped).
#[derive(Clone, Copy, Debug)]
pub(super) struct Residual {
    /// 1/p where the residual is evaluated, 0 where it is not.
    pub weight: f64,
}

impl Residual {
    /// The roulette with probability `p` of evaluating: draws its own
    /// number from `sampler` only where p < 1, so p = 1 draws the same
    /// numbers as before it existed.
    #[inline]
    pub fn draw(p: f64, sampler: &mut Sampler) -> Residual {
        if p >= 1.0 {
            return Residual { weight: 1.0 };
        }
        let u = sampler.get_1d();
        Residual {
            weight: if u < p { 1.0 / p } else { 0.0 },
        }
    }

    /// Whether the residual is evaluated.
    #[inline]
    pub fn evaluated(self) -> bool {
        self.weight > 0.0
    }
}

/// The BSDF side of a first vertex's light sample at `wo`: the density at
/// each wavelength (none toward a delta light), and f as well where the
/// residual is evaluated; with Σ Q_k and the density Σ Q_k p_k of the
/// path's wavelengths' sampling, as `nee_bsdf` returns them.
///
/// Never `None`: the exact part n·∫ Le f̃ cmf dλ is the residual's
/// expectation over all λ, not only over those where f is positive, so a
/// light sample is counted whatever f is at the path's wavelengths.
pub(super) fn nee_bsdf(
    bxdf: &dyn Bxdf,
    wi: DVec3,
    wo: DVec3,
    is_delta: bool,
    lambdas: &[f64],
    q: &[f64],
    residual: Residual,
) -> Option<(f64, f64, FPerLambda)> {
    let n = lambdas.len();
    let mut fp = [(0.0, 0.0); N];
    if residual.evaluated() {
        bxdf.eval_pdf_many(wi, wo, lambdas, &mut fp[..n]);
    } else if !is_delta {
        for (v, &l) in fp.iter_mut().zip(lambdas) {
            v.1 = bxdf.pdf(wi, wo, l);
        }
    }
    let (q_sum, p_bsdf) = super::nee_density::sums(&mut fp[..n], is_delta, q);
    Some((q_sum, p_bsdf, fp))
}

#[cfg(test)]
mod tests {
    use super::Residual;
    use crate::sampler::Sampler;
    use crate::scene::MIN_GLOSSY_RESIDUAL;
    use crate::scene::desc::SamplerKind;

    proptest::proptest! {
        /// Over every accepted p, the roulette's weight is 1/p or 0 and its
        /// mean over a pixel's first 2¹² Sobol samples is 1 within the
        /// strata's bound (its draw is each sample's first, a net: the
        /// evaluated count is ⌊pN⌋ or ⌈pN⌉), so the residual's expectation
        /// is kept; and p = 1 draws nothing.
        #[test]
        fn the_roulette_keeps_the_residuals_mean(
            p in MIN_GLOSSY_RESIDUAL..=1.0f64,
            seed in proptest::prelude::any::<u64>(),
            pixel in 0u64..1 << 20,
        ) {
            const N: u64 = 1 << 12;
            let mut sum = 0.0;
            for s in 0..N {
                let mut sampler = Sampler::new(SamplerKind::Sobol, seed, pixel, s);
                let r = Residual::draw(p, &mut sampler);
                proptest::prop_assert!(r.weight == 0.0 || r.weight == 1.0 / p, "{}", r.weight);
                proptest::prop_assert_eq!(r.evaluated(), r.weight > 0.0);
                sum += r.weight;
            }
            let mean = sum / N as f64;
            // ±1 evaluated sample of weight 1/p among N.
            proptest::prop_assert!((mean - 1.0).abs() <= 1.0 / (p * N as f64) + 1e-12, "p {p}: mean {mean}");
            let mut untouched = Sampler::new(SamplerKind::Sobol, seed, pixel, 3);
            let mut fresh = untouched.clone();
            Residual::draw(1.0, &mut untouched);
            proptest::prop_assert_eq!(untouched.get_1d(), fresh.get_1d());
        }
    }
}
