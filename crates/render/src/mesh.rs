//! Triangle meshes from OBJ files, in one obvhs CWBVH.
//!
//! The BVH is traversed in f32 (obvhs's only precision); the hit triangle is
//! then re-intersected in f64 so that hit points and normals keep the
//! accuracy of the analytic shapes. Barycentrics are not needed: metals are
//! shaded with the geometric normal (OBJ vertex normals are ignored).

use crate::geometry::{HitGeometry, Ray, Transform};
use glam::{DVec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as BvhRay, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use std::path::Path;
use std::time::Duration;

/// Triangles of one OBJ file after its transform, tagged with a surface id.
pub struct MeshSource {
    /// Triangle vertices in world space.
    pub triangles: Vec<[DVec3; 3]>,
    /// Surface id given to every triangle of this mesh.
    pub surface: u32,
}

/// Loads every model of an OBJ file as triangles, transformed to world space.
pub fn load_obj(path: &Path, xf: &Transform, surface: u32) -> Result<MeshSource, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &opts).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => format!("cannot open mesh file {}", path.display()),
        other => format!("cannot parse OBJ file {}: {other}", path.display()),
    })?;
    let mut triangles = Vec::new();
    for m in &models {
        let pos = &m.mesh.positions;
        let vertex = |i: u32| -> Option<DVec3> {
            let i = 3 * i as usize;
            let p = pos.get(i..i + 3)?;
            Some(xf.point(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
        };
        for tri in m.mesh.indices.chunks_exact(3) {
            let (Some(a), Some(b), Some(c)) = (vertex(tri[0]), vertex(tri[1]), vertex(tri[2]))
            else {
                return Err(format!(
                    "{}: model `{}` has a vertex index out of range",
                    path.display(),
                    m.name
                ));
            };
            // Degenerate triangles have no normal; dropping them changes nothing visible.
            if (b - a).cross(c - a).length_squared() > 0.0 {
                triangles.push([a, b, c]);
            }
        }
    }
    if triangles.is_empty() {
        return Err(format!(
            "{}: the OBJ file contains no triangles",
            path.display()
        ));
    }
    Ok(MeshSource { triangles, surface })
}

/// All mesh triangles of a scene in one BVH, stored in leaf order.
pub struct MeshAccel {
    bvh: CwBvh,
    rt: Vec<RtTriangle>,
    tris: Vec<[DVec3; 3]>,
    surface: Vec<u32>,
}

fn to_f32(v: DVec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

impl MeshAccel {
    /// Builds the BVH over all sources.
    pub fn build(sources: Vec<MeshSource>) -> MeshAccel {
        let mut tris = Vec::new();
        let mut surface = Vec::new();
        for s in sources {
            surface.extend(std::iter::repeat_n(s.surface, s.triangles.len()));
            tris.extend(s.triangles);
        }
        let f32_tris: Vec<Triangle> = tris
            .iter()
            .map(|t| Triangle {
                v0: to_f32(t[0]),
                v1: to_f32(t[1]),
                v2: to_f32(t[2]),
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &f32_tris,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        // Reorder into leaf order once so traversal indexes directly.
        let order: Vec<usize> = bvh.primitive_indices.iter().map(|&i| i as usize).collect();
        let rt = order
            .iter()
            .map(|&i| RtTriangle::from(&f32_tris[i]))
            .collect();
        let tris_leaf = order.iter().map(|&i| tris[i]).collect();
        let surface_leaf = order.iter().map(|&i| surface[i]).collect();
        MeshAccel {
            bvh,
            rt,
            tris: tris_leaf,
            surface: surface_leaf,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    fn bvh_ray(ray: &Ray, t_min: f64, t_max: f64) -> BvhRay {
        let t_max = if t_max.is_finite() {
            t_max as f32
        } else {
            f32::INFINITY
        };
        BvhRay::new(to_f32(ray.o), to_f32(ray.d), t_min as f32, t_max)
    }

    /// Nearest hit in `(t_min, t_max)` and its surface id.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(HitGeometry, u32)> {
        let mut hit = RayHit::none();
        let r = Self::bvh_ray(ray, t_min, t_max);
        if !self
            .bvh
            .ray_traverse(r, &mut hit, |r, id| self.rt[id].intersect(r))
        {
            return None;
        }
        let id = hit.primitive_id as usize;
        let [a, b, c] = self.tris[id];
        let n = (b - a).cross(c - a).normalize();
        // f64 plane intersection of the triangle the f32 traversal found.
        let denom = ray.d.dot(n);
        let t = if denom.abs() > 1e-300 {
            (a - ray.o).dot(n) / denom
        } else {
            hit.t as f64
        };
        let t = if t.is_finite() && t > t_min {
            t
        } else {
            hit.t as f64
        };
        let tangent = (b - a).normalize();
        Some((
            HitGeometry {
                t,
                p: ray.at(t),
                n,
                tangent,
            },
            self.surface[id],
        ))
    }

    /// Whether anything blocks the segment `(t_min, t_max)` of `ray`.
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        !self
            .bvh
            .ray_traverse_miss(Self::bvh_ray(ray, t_min, t_max), |r, id| {
                self.rt[id].intersect(r)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bvh_finds_the_nearest_triangle_and_occlusion() {
        let quad = |z: f64| {
            vec![
                [
                    DVec3::new(-1.0, -1.0, z),
                    DVec3::new(1.0, -1.0, z),
                    DVec3::new(1.0, 1.0, z),
                ],
                [
                    DVec3::new(-1.0, -1.0, z),
                    DVec3::new(1.0, 1.0, z),
                    DVec3::new(-1.0, 1.0, z),
                ],
            ]
        };
        let accel = MeshAccel::build(vec![
            MeshSource {
                triangles: quad(0.0),
                surface: 7,
            },
            MeshSource {
                triangles: quad(-2.0),
                surface: 9,
            },
        ]);
        assert_eq!(accel.len(), 4);
        let ray = Ray {
            o: DVec3::new(0.3, 0.2, 5.0),
            d: DVec3::NEG_Z,
        };
        let (h, s) = accel.intersect(&ray, 1e-6, f64::INFINITY).unwrap();
        assert_eq!(s, 7);
        assert!((h.t - 5.0).abs() < 1e-9 && (h.n.z.abs() - 1.0).abs() < 1e-12);
        assert!(accel.occluded(&ray, 1e-6, 6.0));
        assert!(!accel.occluded(&ray, 1e-6, 4.9));
        let (h2, s2) = accel.intersect(&ray, 5.5, f64::INFINITY).unwrap();
        assert_eq!(s2, 9);
        assert!((h2.t - 7.0).abs() < 1e-9);
    }
}
