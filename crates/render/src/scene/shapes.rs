//! The runtime scene's geometry and the two ray queries the integrator asks of it.

use super::{Hit, Surface};
use crate::geometry::{Planar, Ray, Sphere};
use crate::mesh::MeshAccel;

/// Everything a ray can hit: analytic shapes tested one by one (a scene
/// has a handful) and, only when the scene has meshes, one BVH over all
/// their triangles.
pub struct Shapes {
    /// Rectangles and disks (reflectors and emitters).
    pub planars: Vec<(Planar, Surface)>,
    /// Spheres (reflectors and emitters).
    pub spheres: Vec<(Sphere, Surface)>,
    /// Mesh triangles (only when the scene has any).
    pub mesh: Option<MeshAccel>,
}

impl Shapes {
    /// Number of analytic shapes.
    pub fn analytic_count(&self) -> usize {
        self.planars.len() + self.spheres.len()
    }

    /// Nearest hit along `ray` in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for (p, s) in &self.planars {
            if let Some(g) = p.intersect(ray, 0.0, t_max) {
                t_max = g.t;
                best = Some(Hit::analytic(g, *s));
            }
        }
        // The nearest sphere by distance alone; its point, normal and tangent
        // (a normalisation and a division each) only for the one that wins.
        let mut nearest_sphere = None;
        for (i, (sp, _)) in self.spheres.iter().enumerate() {
            if let Some(t) = sp.hit_distance(ray, 0.0, t_max) {
                t_max = t;
                nearest_sphere = Some(i);
            }
        }
        if let Some(i) = nearest_sphere {
            let (sp, s) = &self.spheres[i];
            best = Some(Hit::analytic(sp.geometry_at(ray, t_max), *s));
        }
        if let Some(m) = &self.mesh
            && let Some((g, mat, shading_n)) = m.intersect(ray, 0.0, t_max)
        {
            best = Some(Hit {
                geo: g,
                surface: Surface::Material(mat),
                mesh: true,
                shading_n,
            });
        }
        best
    }

    /// Whether anything lies on `ray` within `(0, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.planars
            .iter()
            .any(|(p, _)| p.intersect(ray, 0.0, t_max).is_some())
            || self
                .spheres
                .iter()
                .any(|(s, _)| s.hit_distance(ray, 0.0, t_max).is_some())
            || self
                .mesh
                .as_ref()
                .is_some_and(|m| m.occluded(ray, 0.0, t_max))
    }
}
