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

/// Branches at a first vertex on a mesh, unless the scene sets `branches`.
pub const MESH_BRANCHES: u32 = 4;

/// The branches a camera sample splits into at its first vertex, of model
/// `bxdf` seen from `wi`, on a mesh triangle if `mesh`: the scene's
/// `branches` where it sets them, and none where the path ends there
/// (direct light only).
///
/// By default [`MESH_BRANCHES`] on a mesh whose model says how wide its
/// lobe is (not a delta lobe, whose branches would all follow one
/// direction, nor a model that does not say), none elsewhere. Splitting
/// pays where a camera sample's prefix (camera ray, light sample and its
/// shadow ray) is dear against a continuation and most of the variance
/// comes after the first vertex. Measured at 64 spp, 4 seeds against
/// 4096-spp references (relRMSE, CPU s; crates/render/README.md): the
/// preview object on a meshed floor under a sun, 0.0744, 1.22 → 0.0399,
/// 2.97 with 4 branches everywhere; the copper object on an analytic floor
/// under a softbox, 0.0867, 1.40 → 0.0640, 2.06 with 4 at the object's
/// (mesh) vertices, 0.0555, 3.30 with 4 everywhere. On scenes of analytic
/// shapes the continuations cost as much as or more than the prefix and
/// splitting lost: hdri_spheres 0.0935, 1.25 → 0.0779, 3.26 (4 everywhere)
/// or 0.0888, 1.88 (4 at glossy vertices only); cornell_box_metals 0.0624,
/// 1.80 → 0.0488, 5.52 or 0.0621, 2.20.
#[inline]
pub(super) fn branches(scene: &Scene, bxdf: &dyn Bxdf, wi: DVec3, mesh: bool) -> u32 {
    let s = &scene.settings;
    if s.max_depth <= 1 {
        return 1;
    }
    if let Some(k) = s.branches {
        return k;
    }
    if mesh && bxdf.lobe_peak_pdf(wi).is_some_and(f64::is_finite) {
        MESH_BRANCHES
    } else {
        1
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
