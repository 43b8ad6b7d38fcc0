//! Triangle meshes from OBJ files, in one obvhs CWBVH.
//!
//! The BVH is traversed in f32 (obvhs's only precision); the hit triangle is
//! then re-intersected in f64 so that hit points and normals keep the
//! accuracy of the analytic shapes. When the OBJ file has vertex normals
//! (`vn`), the hit also carries the shading normal interpolated from them
//! with f64 barycentrics; otherwise triangles are shaded flat.

use crate::geometry::{Ray, SurfacePoint, Transform};
use crate::mesh_traverse::{Bvh, any_hit, closest};
use glam::{DVec3, Vec3A};
use obvhs::ray::Ray as BvhRay;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use std::path::Path;
use std::time::Duration;

/// Largest |coordinate| of a mesh vertex after its transform. Both f32
/// stages overflow with size: obvhs's build squares box extents (inf past
/// √f32::MAX ≈ 1.8e19, on which its CWBVH conversion panics), and
/// its Möller–Trumbore test forms the triangle normal (edge²) dotted with
/// the origin-to-vertex vector, a cube of the scene's size that must stay
/// below f32::MAX ≈ 3.4e38. With coordinates within ±1e12 that product is
/// at most ~(2e12)³·√3 ≈ 1.4e37 for rays starting among the meshes. The ray
/// offset off mesh hits is relative to the coordinates' magnitude, so it
/// sets no bound.
pub const MAX_MESH_COORDINATE: f64 = 1e12;

/// Triangles of one OBJ file after its transform, tagged with a surface id.
pub struct MeshSource {
    /// Triangle vertices in world space.
    pub triangles: Vec<[DVec3; 3]>,
    /// Unit vertex normals in world space, per triangle, where the file has them.
    pub normals: Vec<Option<[DVec3; 3]>>,
    /// Texture coordinates (OBJ `vt`) of each triangle's vertices, when the file has
    /// them; `None`: a triangle's (u, v) are its barycentric coordinates (Mitsuba's
    /// rule for meshes without them).
    pub uvs: Option<Vec<[[f64; 2]; 3]>>,
    /// Surface id given to every triangle of this mesh.
    pub surface: u32,
}

/// The (u, v) of the vertices of a triangle without texture coordinates: its
/// barycentric coordinates (w₁, w₂) then come out as (u, v).
const BARYCENTRIC_UV: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// Every model of an OBJ file, from the file's bytes (`path` for messages),
/// as triangles transformed to world space. `mtllib`
/// references are not followed: the renderer takes materials from the scene.
pub fn obj_from_bytes(
    path: &Path,
    bytes: &[u8],
    xf: &Transform,
    surface: u32,
) -> Result<MeshSource, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("cannot parse OBJ file {}: {e}", path.display()))?;
    let mut triangles = Vec::new();
    let mut normals = Vec::new();
    let has_uv = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let mut uvs = Vec::new();
    // Triangles with area in the file: if none survive the transform, it is
    // the transform's fault, and the message says so.
    let mut proper_in_file = 0usize;
    let mut seen = std::collections::HashSet::new();
    for m in &models {
        let pos = &m.mesh.positions;
        let nrm = &m.mesh.normals;
        // single_index: normals (when present) share the position indices.
        let normal = |i: u32| -> Option<DVec3> {
            let i = 3 * i as usize;
            let v = nrm.get(i..i + 3)?;
            xf.direction(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
                .try_normalize()
        };
        // single_index: texture coordinates (when present) share them too.
        let tc = &m.mesh.texcoords;
        let uv = |i: u32| -> Option<[f64; 2]> {
            let i = 2 * i as usize;
            let t = tc.get(i..i + 2)?;
            Some([t[0] as f64, t[1] as f64])
        };
        let local = |i: u32| -> Option<DVec3> {
            let i = 3 * i as usize;
            let p = pos.get(i..i + 3)?;
            Some(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        };
        for tri in m.mesh.indices.chunks_exact(3) {
            let (Some(la), Some(lb), Some(lc)) = (local(tri[0]), local(tri[1]), local(tri[2]))
            else {
                return Err(format!(
                    "{}: model `{}` has a vertex index out of range",
                    path.display(),
                    m.name
                ));
            };
            let [a, b, c] = [la, lb, lc].map(|v| xf.point(v));
            for (l, w) in [(la, a), (lb, b), (lc, c)] {
                if !w.is_finite() || w.abs().max_element() > MAX_MESH_COORDINATE {
                    let xyz = |v: DVec3| [v.x, v.y, v.z].map(number).join(", ");
                    return Err(format!(
                        "{}: model `{}` has the vertex ({}), which lies at ({}) after the \
                         shape's transform, outside ±{MAX_MESH_COORDINATE:e}, the range the \
                         mesh BVH (f32) handles; make the coordinates finite and reduce \
                         transform.scale / transform.translate (or rescale the file)",
                        path.display(),
                        m.name,
                        xyz(l),
                        xyz(w)
                    ));
                }
            }
            proper_in_file += usize::from((lb - la).cross(lc - la).length_squared() > 0.0);
            // Degenerate triangles have no normal; dropping them changes nothing visible.
            // Neither does dropping a repeat of a triangle already kept (the
            // first hit is the same surface), and the BVH build's time grows
            // with the square of the repeats of one triangle (20 000 copies
            // take 21 s, against 0.4 s for 10 000 distinct triangles).
            let mut key = [a, b, c].map(|v| [v.x, v.y, v.z].map(f64::to_bits));
            key.sort_unstable();
            if (b - a).cross(c - a).length_squared() > 0.0 && seen.insert(key) {
                triangles.push([a, b, c]);
                normals.push(match (normal(tri[0]), normal(tri[1]), normal(tri[2])) {
                    (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                    _ => None,
                });
                if has_uv {
                    uvs.push(match (uv(tri[0]), uv(tri[1]), uv(tri[2])) {
                        (Some(x), Some(y), Some(z)) => [x, y, z],
                        _ => BARYCENTRIC_UV,
                    });
                }
            }
        }
    }
    if triangles.is_empty() && proper_in_file > 0 {
        return Err(format!(
            "{}: all {proper_in_file} triangle(s) of the OBJ file degenerate to zero area after \
             the shape's transform (f64 cannot resolve them at that scale and offset); use a \
             transform.scale nearer 1 or a smaller transform.translate, or rescale the file",
            path.display()
        ));
    }
    if triangles.is_empty() {
        return Err(format!(
            "{}: the OBJ file contains no triangles of non-zero area (faces `f` with three \
             distinct, non-collinear vertices)",
            path.display()
        ));
    }
    Ok(MeshSource {
        triangles,
        normals,
        uvs: has_uv.then_some(uvs),
        surface,
    })
}

/// What a hit on a triangle needs in f64, computed once per triangle
/// instead of per hit (152 bytes; the vertices alone took 72).
#[derive(Clone, Copy)]
struct Facet {
    /// First vertex, and the edges from it to the second and third.
    a: DVec3,
    ab: DVec3,
    ac: DVec3,
    /// `ab × ac` (twice the area, along the normal) and 1/|ab × ac|².
    area: DVec3,
    inv_area2: f64,
    /// Unit normal and unit tangent (along `ab`).
    n: DVec3,
    tangent: DVec3,
}

impl Facet {
    fn new([a, b, c]: [DVec3; 3]) -> Facet {
        let (ab, ac) = (b - a, c - a);
        let area = ab.cross(ac);
        Facet {
            a,
            ab,
            ac,
            area,
            inv_area2: 1.0 / area.length_squared(),
            n: area.normalize(),
            tangent: ab.normalize(),
        }
    }

    /// Barycentric coordinates of `p` (in the triangle's plane) from sub-triangle areas.
    #[inline]
    fn barycentric(&self, p: DVec3) -> [f64; 3] {
        let ap = p - self.a;
        let w1 = ap.cross(self.ac).dot(self.area) * self.inv_area2;
        let w2 = self.ab.cross(ap).dot(self.area) * self.inv_area2;
        [1.0 - w1 - w2, w1, w2]
    }
}

/// A coordinate for messages: plain where that is short, else in e-notation.
fn number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// All mesh triangles of a scene in one BVH, stored in leaf order.
pub struct MeshAccel {
    bvh: Bvh,
    /// The obvhs tree `bvh` was copied from, for the traversal's tests.
    #[cfg(test)]
    cw: obvhs::cwbvh::CwBvh,
    /// The triangles in leaf order as obvhs tests them, for the tests.
    #[cfg(test)]
    rt: Vec<RtTriangle>,
    facets: Vec<Facet>,
    normals: Vec<Option<[DVec3; 3]>>,
    /// Per triangle, when some source has texture coordinates; else empty.
    uvs: Vec<[[f64; 2]; 3]>,
    surface: Vec<u32>,
    /// Triangles in the sources (the leaves may hold a triangle more than
    /// once: the build splits large triangles' boxes).
    triangles: usize,
}

fn to_f32(v: DVec3) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

/// obvhs's `BvhRay::new` reciprocal (`safe_inverse`: ±1/ε by the sign bit
/// for a component within f32::EPSILON of zero, else 1/d), bit for bit, in
/// one vector division and a select instead of three divisions behind
/// branches.
#[inline(always)]
fn safe_inverse(d: Vec3A) -> Vec3A {
    let tiny = d.abs().cmple(Vec3A::splat(f32::EPSILON));
    let clamped = Vec3A::splat(1.0 / f32::EPSILON).copysign(d);
    Vec3A::select(tiny, clamped, Vec3A::ONE / d)
}

impl MeshAccel {
    /// Builds the BVH over all sources.
    pub fn build(sources: Vec<MeshSource>) -> MeshAccel {
        let mut tris = Vec::new();
        let mut normals = Vec::new();
        let mut surface = Vec::new();
        let mut uvs = Vec::new();
        let any_uv = sources.iter().any(|s| s.uvs.is_some());
        for s in sources {
            let n = s.triangles.len();
            surface.extend(std::iter::repeat_n(s.surface, n));
            tris.extend(s.triangles);
            normals.extend(s.normals);
            if any_uv {
                match s.uvs {
                    Some(t) => uvs.extend(t),
                    None => uvs.extend(std::iter::repeat_n(BARYCENTRIC_UV, n)),
                }
            }
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
            // Pre-split boxes and a wider search: with the rough plastic's
            // shared geometry, 5–6 % less CPU per sample on the preview scene
            // (6.7 k triangles) than `medium_build`, for a slower build (a
            // 500 k-triangle scene loads in 2.0 s instead of 1.7 s).
            obvhs::BvhBuildParams::slow_build(),
            &mut Duration::default(),
        );
        // Reorder into leaf order once so traversal indexes directly.
        let order: Vec<usize> = bvh.primitive_indices.iter().map(|&i| i as usize).collect();
        let rt_of = |k: usize| Some(RtTriangle::from(f32_tris.get(*order.get(k)?)?));
        let leaf_bvh = Bvh::new(&bvh, rt_of);
        #[cfg(test)]
        let rt: Vec<RtTriangle> = (0..order.len()).filter_map(rt_of).collect();
        // Freed before the f64 data are built: they set the peak memory.
        drop(f32_tris);
        #[cfg(not(test))]
        drop(bvh);
        let triangles = tris.len();
        let facets = order.iter().map(|&i| Facet::new(tris[i])).collect();
        let surface_leaf = order.iter().map(|&i| surface[i]).collect();
        let normals_leaf = order.iter().map(|&i| normals[i]).collect();
        let uvs_leaf = if any_uv {
            order.iter().map(|&i| uvs[i]).collect()
        } else {
            Vec::new()
        };
        MeshAccel {
            bvh: leaf_bvh,
            #[cfg(test)]
            cw: bvh,
            #[cfg(test)]
            rt,
            facets,
            normals: normals_leaf,
            uvs: uvs_leaf,
            surface: surface_leaf,
            triangles,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.facets.is_empty()
    }

    pub(crate) fn bvh_ray(ray: &Ray, t_min: f64, t_max: f64) -> BvhRay {
        let t_max = if t_max.is_finite() {
            t_max as f32
        } else {
            f32::INFINITY
        };
        let direction = to_f32(ray.d);
        BvhRay {
            origin: to_f32(ray.o),
            direction,
            inv_direction: safe_inverse(direction),
            tmin: t_min as f32,
            tmax: t_max,
        }
    }

    /// The BVH and its triangles in leaf order, for the traversal's tests.
    #[cfg(test)]
    pub(crate) fn bvh_parts(&self) -> (&obvhs::cwbvh::CwBvh, &Bvh, &[RtTriangle]) {
        (&self.cw, &self.bvh, &self.rt)
    }

    /// Nearest hit in `(t_min, t_max)`, its surface id, for triangles with
    /// vertex normals the interpolated unit shading normal, and the triangle
    /// (for [`MeshAccel::uv`]).
    pub fn intersect(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<(SurfacePoint, u32, Option<DVec3>, usize)> {
        let (id, t_f32) = closest(&self.bvh, Self::bvh_ray(ray, t_min, t_max))?;
        let id = id as usize;
        let f = &self.facets[id];
        let n = f.n;
        // f64 plane intersection of the triangle the f32 traversal found.
        let denom = ray.d.dot(n);
        let t = if denom.abs() > 1e-300 {
            (f.a - ray.o).dot(n) / denom
        } else {
            t_f32 as f64
        };
        let t = if t.is_finite() && t > t_min {
            t
        } else {
            t_f32 as f64
        };
        let tangent = f.tangent;
        let p = ray.at(t);
        let shading = self.normals[id].and_then(|[na, nb, nc]| {
            let [w0, w1, w2] = f.barycentric(p);
            (w0 * na + w1 * nb + w2 * nc).try_normalize()
        });
        Some((
            SurfacePoint { t, p, n, tangent },
            self.surface[id],
            shading,
            id,
        ))
    }

    /// Texture coordinates of point `p` of triangle `id` (an id from
    /// [`MeshAccel::intersect`]): its vertices' `vt` interpolated, or its
    /// barycentric coordinates (w₁, w₂) where the file has no `vt`.
    pub fn uv(&self, id: usize, p: DVec3) -> [f64; 2] {
        let [w0, w1, w2] = self.facets[id].barycentric(p);
        match self.uvs.get(id) {
            Some([ua, ub, uc]) => [
                w0 * ua[0] + w1 * ub[0] + w2 * uc[0],
                w0 * ua[1] + w1 * ub[1] + w2 * uc[1],
            ],
            None => [w1, w2],
        }
    }

    /// Whether anything blocks the segment `(t_min, t_max)` of `ray`.
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        any_hit(&self.bvh, Self::bvh_ray(ray, t_min, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &[u8] =
        b"v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\nf 1 3 2\nf 1 4 3\n";

    /// The ray's reciprocal direction is obvhs's, bit for bit, for zeros,
    /// components at and around f32::EPSILON, subnormals, huge values,
    /// infinities and random directions.
    #[test]
    fn ray_reciprocals_are_obvhs_ones() {
        let eps = f32::EPSILON;
        let special = [
            0.0,
            1e-45,
            1e-40,
            eps * 0.5,
            eps,
            f32::from_bits(eps.to_bits() + 1),
            1e-3,
            1.0,
            3e38,
            f32::INFINITY,
        ];
        let mut rng = crate::rng::Rng::for_sample(9, 0, 0);
        let mut values: Vec<f32> = special.iter().flat_map(|&x| [x, -x]).collect();
        values.extend((0..3000).map(|_| (rng.uniform() * 2.0 - 1.0) as f32));
        for w in values.chunks(3).filter(|w| w.len() == 3) {
            let d = Vec3A::new(w[0], w[1], w[2]);
            // `Ray::new`'s reciprocal (called directly: `Ray::new` asserts a
            // finite direction in debug builds).
            let want = d.to_array().map(obvhs::ray::safe_inverse);
            let got = safe_inverse(d);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.map(f32::to_bits),
                "{d}"
            );
        }
    }

    #[test]
    fn texture_coordinates_are_the_files_or_barycentric() {
        let with_vt = b"v 0 0 0\nv 2 0 0\nv 0 0 -2\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.1 0.6\n\
            f 1/1 2/2 3/3\n";
        let without = b"v 0 1 0\nv 2 1 0\nv 0 1 -2\nf 1 2 3\n";
        let (a, b) = (
            load(with_vt, 1.0, [0.0; 3]).unwrap(),
            load(without, 1.0, [0.0; 3]).unwrap(),
        );
        assert!(a.uvs.is_some() && b.uvs.is_none());
        let accel = MeshAccel::build(vec![a, b]);
        for (y, want) in [(0.0, [0.3, 0.3]), (1.0, [0.25, 0.25])] {
            // The point (0.5, y, −0.5): barycentric (0.5, 0.25, 0.25).
            let ray = Ray {
                o: DVec3::new(0.5, y + 1.0 - 1e-3, -0.5),
                d: DVec3::NEG_Y,
            };
            let (h, _, _, id) = accel.intersect(&ray, 0.0, 1.0).unwrap();
            let uv = accel.uv(id, h.p);
            assert!(
                (uv[0] - want[0]).abs() < 1e-6 && (uv[1] - want[1]).abs() < 1e-6,
                "y {y}: {uv:?}"
            ); // vt are f32
        }
    }

    fn load(bytes: &[u8], scale: f64, translate: [f64; 3]) -> Result<MeshSource, String> {
        let xf = Transform::new([0.0; 3], scale, translate);
        obj_from_bytes(Path::new("q.obj"), bytes, &xf, 0)
    }

    #[test]
    fn repeated_triangles_are_kept_once() {
        // The quad's first triangle three times more, once in another vertex
        // order and once through vertices of its own: the two distinct
        // triangles remain, the first copy of each with its place.
        let obj = b"v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\n\
            v -0.5 0 -0.5\nv 0.5 0 0.5\nv 0.5 0 -0.5\n\
            f 1 3 2\nf 1 4 3\nf 1 3 2\nf 3 2 1\nf 5 6 7\n";
        let m = load(obj, 1.0, [0.0; 3]).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.normals.len(), 2);
        let q = load(QUAD, 1.0, [0.0; 3]).unwrap();
        assert_eq!(m.triangles, q.triangles);
    }

    #[test]
    fn vertices_beyond_the_f32_bvh_range_are_refused() {
        // Scale 1e20 takes obvhs's box extents to inf, on which its CWBVH
        // conversion panics: refused before the build.
        for (bytes, scale) in [
            (QUAD, 1e20),
            (QUAD, 1e15),
            (QUAD, 2.1e12),
            (&b"v 0 0 0\nv 3e38 0 3e38\nv 1 0 0\nf 1 2 3\n"[..], 1.0),
            (&b"v 0 0 0\nv inf 0 0\nv 1 0 1\nf 1 2 3\n"[..], 1.0),
            (&b"v 0 0 0\nv nan 0 0\nv 1 0 1\nf 1 2 3\n"[..], 1.0),
        ] {
            let e = load(bytes, scale, [0.0; 3]).err().expect("refused");
            assert!(
                e.contains("q.obj") && e.contains("1e12") && e.contains("transform.scale"),
                "{e}"
            );
        }
        // The largest accepted extent builds a BVH that still finds the quad.
        // Scaled to 1e15 the f32 triangle test overflowed and missed it.
        let src = load(QUAD, 2e12, [0.0; 3]).unwrap();
        let accel = MeshAccel::build(vec![src]);
        for o in [
            DVec3::new(1e10, 1e12, 2e10),
            DVec3::new(-9.9e11, 1e12, 9.9e11),
        ] {
            let ray = Ray { o, d: DVec3::NEG_Y };
            let (h, _, _, _) = accel.intersect(&ray, 0.0, f64::INFINITY).unwrap();
            assert!((h.t / 1e12 - 1.0).abs() < 1e-9, "{}", h.t);
        }
    }

    #[test]
    fn triangles_collapsed_by_the_transform_are_named_so() {
        for (scale, translate) in [(1e-300, [0.0; 3]), (1e-6, [1e12, 0.0, 0.0])] {
            let e = load(QUAD, scale, translate).err().expect("refused");
            assert!(e.contains("after the shape's transform"), "{e}");
        }
        let e = load(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", 1.0, [0.0; 3])
            .err()
            .expect("refused");
        assert!(e.contains("no triangles of non-zero area"), "{e}");
    }

    /// The hit's f64 values from per-triangle data computed at build time
    /// are, bit for bit, those of the formulas on the vertices: every
    /// triangle its own source, so the surface id names it.
    #[test]
    fn precomputed_triangle_data_gives_the_vertex_formulas_values() {
        let mut rng = crate::rng::Rng::for_sample(5, 0, 0);
        let mut point = || DVec3::from(rng.uniform3()) * 2.0 - 1.0;
        let tris: Vec<([DVec3; 3], [DVec3; 3])> = (0..300)
            .map(|_| {
                let a = point();
                let (b, c) = (a + point() * 0.3, a + point() * 0.3);
                (
                    [a, b, c],
                    [point(), point(), point()].map(|v| v.normalize()),
                )
            })
            .collect();
        let sources = tris.iter().enumerate().map(|(k, &(t, vn))| MeshSource {
            triangles: vec![t],
            normals: vec![Some(vn)],
            uvs: None,
            surface: k as u32,
        });
        let accel = MeshAccel::build(sources.collect());
        let mut hits = 0;
        for _ in 0..5000 {
            let ray = Ray {
                o: point() * 2.0,
                d: point().normalize(),
            };
            let Some((h, s, shading, id)) = accel.intersect(&ray, 0.0, f64::INFINITY) else {
                continue;
            };
            let ([a, b, c], [na, nb, nc]) = tris[s as usize];
            let n = (b - a).cross(c - a).normalize();
            let t = (a - ray.o).dot(n) / ray.d.dot(n);
            assert_eq!(h.t.to_bits(), t.to_bits());
            assert_eq!((h.n, h.tangent), (n, (b - a).normalize()));
            let area = (b - a).cross(c - a);
            let inv = 1.0 / area.length_squared();
            let w1 = (h.p - a).cross(c - a).dot(area) * inv;
            let w2 = (b - a).cross(h.p - a).dot(area) * inv;
            let want = ((1.0 - w1 - w2) * na + w1 * nb + w2 * nc).try_normalize();
            assert_eq!(shading, want);
            assert_eq!(accel.uv(id, h.p), [w1, w2]);
            hits += 1;
        }
        assert!(hits > 500, "{hits} hits");
    }

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
        // The far quad has vertex normals from a linear field, (0.1x, 0.1y, 1):
        // barycentric interpolation must reproduce it exactly at any point.
        let field = |v: DVec3| DVec3::new(0.1 * v.x, 0.1 * v.y, 1.0);
        let far = quad(-2.0);
        let far_normals = far.iter().map(|t| Some(t.map(field))).collect();
        let accel = MeshAccel::build(vec![
            MeshSource {
                triangles: quad(0.0),
                normals: vec![None; 2],
                uvs: None,
                surface: 7,
            },
            MeshSource {
                triangles: far,
                normals: far_normals,
                uvs: None,
                surface: 9,
            },
        ]);
        assert_eq!(accel.len(), 4);
        let ray = Ray {
            o: DVec3::new(0.3, 0.2, 5.0),
            d: DVec3::NEG_Z,
        };
        let (h, s, shading, _) = accel.intersect(&ray, 1e-6, f64::INFINITY).unwrap();
        assert_eq!(s, 7);
        assert_eq!(shading, None);
        assert!((h.t - 5.0).abs() < 1e-9 && (h.n.z.abs() - 1.0).abs() < 1e-12);
        assert!(accel.occluded(&ray, 1e-6, 6.0));
        assert!(!accel.occluded(&ray, 1e-6, 4.9));
        let (h2, s2, shading2, _) = accel.intersect(&ray, 5.5, f64::INFINITY).unwrap();
        assert_eq!(s2, 9);
        assert!((h2.t - 7.0).abs() < 1e-9);
        let want = field(DVec3::new(0.3, 0.2, -2.0)).normalize();
        assert!(
            (shading2.unwrap() - want).length() < 1e-12,
            "{shading2:?} vs {want}"
        );
    }
}
