//! When to split a camera path at its first vertex (the split itself is
//! `integrator`'s `flat_split` and `sampled_split`): one camera ray and one
//! light sample there, then k BSDF continuations, each with weight 1/k and
//! its own later vertices, light samples and Russian roulette.
//!
//! Why: in a scene whose noise is light that bounced more than once (a
//! sun's caustic off a glossy object onto the floor, the object reflecting
//! the lit floor), k continuations share one prefix (the camera ray
//! through a mesh, the light sample and its shadow ray).
//!
//! Unbiased: each branch is the unsplit estimator's continuation with the
//! same distribution (its draws are as uniform as the unsplit ones,
//! [`Sampler::branch`](crate::sampler::Sampler::branch)), so the mean of
//! k of them has the same mean. Every branch carries the camera sample's
//! wavelengths: those that hand over to sampled wavelengths draw them from
//! the camera sample's own reserved draw, so all of them add to one film
//! sample.

use crate::film::SampleRadiance;
use crate::scene::Scene;
use brdf::Bxdf;
use glam::DVec3;

/// The branches a camera sample splits into at its first vertex, of model
/// `bxdf` seen from `wi`: the scene's `branches` where it sets them and the
/// model says how wide its lobe is (not a delta lobe, whose branches would
/// all follow one direction, nor a model that does not say); one where the
/// path ends there (direct light only) and, unset, everywhere.
///
/// Off unless asked for: no static rule paid on every scene. Splitting pays
/// where a camera sample's prefix (camera ray, light sample and its shadow
/// ray) is dear against a continuation and most of the variance comes
/// after the first vertex. Measured at 64 spp, 4 seeds against 4096-spp
/// references (relRMSE, CPU s; crates/render/README.md): the preview
/// object on a meshed floor under a sun, 0.0744, 1.22 → 0.0399, 2.97 with
/// 4 branches; but scenes whose continuations are long lose: a Cornell
/// box with metal spheres, 0.0624, 1.80 → 0.0488, 5.52 with 4 (analytic
/// walls) and 0.0627, 1.84 → 0.0527, 5.23 (walls as a mesh), half the
/// efficiency. One k per scene from a pilot's statistics (the branches'
/// within-sample variance against the between-sample variance, and the
/// two parts' costs) was measured and not kept: as good as a fixed 4 on
/// the preview, ×0.80–0.86 on three scenes whose glints a small pilot sees
/// or misses (docs/profiling.md).
#[inline]
pub(super) fn branches(scene: &Scene, bxdf: &dyn Bxdf, wi: DVec3) -> u32 {
    let s = &scene.settings;
    match s.branches {
        Some(k) if s.max_depth > 1 && bxdf.lobe_peak_pdf(wi).is_some_and(f64::is_finite) => k,
        _ => 1,
    }
}

/// `a + b`, two parts of one camera sample's radiance (at the same
/// wavelengths where both are spectral).
pub(super) fn sum(a: SampleRadiance, b: SampleRadiance) -> SampleRadiance {
    let add = |x: &mut [f64; 3], y: [f64; 3]| {
        for (x, y) in x.iter_mut().zip(y) {
            *x += y;
        }
    };
    match (a, b) {
        (SampleRadiance::Zero, x) | (x, SampleRadiance::Zero) => x,
        (SampleRadiance::Xyz(mut u), SampleRadiance::Xyz(v)) => {
            add(&mut u, v);
            SampleRadiance::Xyz(u)
        }
        (SampleRadiance::Xyz(v), SampleRadiance::Spectral(mut c))
        | (SampleRadiance::Spectral(mut c), SampleRadiance::Xyz(v)) => {
            add(&mut c.xyz, v);
            SampleRadiance::Spectral(c)
        }
        (SampleRadiance::Spectral(mut a), SampleRadiance::Spectral(b)) => {
            debug_assert_eq!(a.wavelengths.lambdas(), b.wavelengths.lambdas());
            for (x, y) in a.radiance.iter_mut().zip(b.radiance) {
                *x += y;
            }
            add(&mut a.xyz, b.xyz);
            SampleRadiance::Spectral(a)
        }
    }
}
