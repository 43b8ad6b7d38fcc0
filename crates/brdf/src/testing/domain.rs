//! The (z, φ) parametrisation of the sphere shared by both harnesses.
//!
//! z = cosθ ∈ [−1, 1] and φ ∈ [−π, π] measured from the azimuth of the mirror
//! direction of wi, so a specular lobe sits at φ = 0, away from the ±π seam.
//! The map is area-preserving, dω = dz dφ, so a solid-angle pdf is also the
//! density in (z, φ) and no Jacobian enters the integrals.

use core::f64::consts::PI;
use glam::DVec3;

/// Coordinates attached to one incident direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Domain {
    phi_mirror: f64,
}

impl Domain {
    pub(crate) fn new(wi: DVec3) -> Domain {
        let phi_mirror = if wi.x == 0.0 && wi.y == 0.0 {
            0.0
        } else {
            libm::atan2(-wi.y, -wi.x)
        };
        Domain { phi_mirror }
    }

    /// Unit direction at (z, φ).
    #[inline]
    pub(crate) fn direction(&self, z: f64, phi: f64) -> DVec3 {
        let z = z.clamp(-1.0, 1.0);
        let s = libm::sqrt(((1.0 - z) * (1.0 + z)).max(0.0));
        let (sp, cp) = libm::sincos(phi + self.phi_mirror);
        DVec3::new(s * cp, s * sp, z)
    }

    /// (z, φ) of a unit direction, φ wrapped into [−π, π).
    #[inline]
    pub(crate) fn coords(&self, w: DVec3) -> (f64, f64) {
        let mut phi = libm::atan2(w.y, w.x) - self.phi_mirror;
        if phi >= PI {
            phi -= 2.0 * PI;
        }
        if phi < -PI {
            phi += 2.0 * PI;
        }
        (w.z.clamp(-1.0, 1.0), phi.clamp(-PI, PI))
    }
}
