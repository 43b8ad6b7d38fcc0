//! Ray queries over the mesh BVH (obvhs's compressed 8-wide nodes) with the
//! triangle test inlined into the loop.
//!
//! obvhs's `ray_traverse` reaches the triangle test through a closure that
//! the compiler did not always inline, and tests a node's eight child boxes
//! four at a time from bytes converted one by one. Here, where the build has
//! AVX2, the eight boxes are tested at once from one byte-to-float
//! conversion per plane array. The order in which nodes and triangles are
//! visited, the box test's arithmetic (same operations in the same order,
//! multiplies and adds unfused) and the triangle test (obvhs's own) are
//! obvhs's, so a query finds the same triangle at the same f32 distance as
//! `CwBvh::ray_traverse` / `ray_traverse_miss` (checked in the tests against
//! both and against a loop over all triangles).

use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::Ray as BvhRay;
use obvhs::rt_triangle::RtTriangle;

/// Depth of the node-group stack: obvhs's CWBVH validation bounds the depth
/// below this; a deeper tree (never built) would overwrite the top entry,
/// as obvhs's own stack does, rather than index out of bounds.
const STACK: usize = 32;

/// A group of pending children: the index of the first child node and a
/// mask whose top byte flags the children still to visit (and whose low
/// byte is the parent's `imask`, needed to locate them).
#[derive(Clone, Copy, Default)]
struct Group {
    base: u32,
    bits: u32,
}

/// Bits 24–31: child nodes still to visit.
const NODE_BITS: u32 = 0xff00_0000;

/// The ray octant in obvhs's encoding (`ray_get_octant_inv4`, private
/// there): one bit per axis set for a non-negative direction, in all four
/// bytes, XORed into a child's slot to visit children front to back.
#[inline(always)]
fn octant_inv4(ray: &BvhRay) -> u32 {
    let d = ray.direction;
    (if d.x < 0.0 { 0 } else { 0x0404_0404 })
        | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
        | (if d.z < 0.0 { 0 } else { 0x0101_0101 })
}

/// Walks the BVH front to back, calling `prim(ray, index)` for every
/// triangle (leaf-order index) whose leaf box the ray crosses within
/// `ray.tmax`; `prim` may shorten `ray.tmax`, and returning `true` stops
/// the walk. The loop is obvhs's `traverse!` order: a node's triangles
/// before its children, children nearest first by the ray's octant.
#[inline(always)]
fn walk<F: FnMut(&mut BvhRay, u32) -> bool>(bvh: &CwBvh, ray: &mut BvhRay, mut prim: F) {
    if bvh.nodes.is_empty() {
        return;
    }
    let oct = octant_inv4(ray);
    let mut stack = [Group::default(); STACK];
    let mut depth = 0usize;
    // The root is the only child of a virtual group at index 0.
    let mut nodes = Group {
        base: 0,
        bits: 0x8000_0000,
    };
    let mut prims = Group::default();
    loop {
        while prims.bits != 0 {
            let local = 31 - prims.bits.leading_zeros();
            prims.bits &= !(1 << local);
            if prim(ray, prims.base + local) {
                return;
            }
        }
        if nodes.bits & NODE_BITS != 0 {
            let hits = nodes.bits;
            let offset = 31 - hits.leading_zeros();
            nodes.bits &= !(1 << offset);
            if nodes.bits & NODE_BITS != 0 {
                stack[depth] = nodes;
                depth = (depth + 1).min(STACK - 1);
            }
            // The visited child's rank among the parent's inner children.
            let slot = (offset - 24) ^ (oct & 0xff);
            let rank = (hits & !(u32::MAX << slot)).count_ones();
            let Some(node) = bvh.nodes.get((nodes.base + rank) as usize) else {
                return;
            };
            let mask = child_hits(node, ray, oct);
            nodes = Group {
                base: node.child_base_idx,
                bits: (mask & NODE_BITS) | node.imask as u32,
            };
            prims = Group {
                base: node.primitive_base_idx,
                bits: mask & !NODE_BITS,
            };
        } else {
            nodes = Group::default();
        }
        if prims.bits == 0 && nodes.bits & NODE_BITS == 0 {
            if depth == 0 {
                return;
            }
            depth -= 1;
            nodes = stack[depth];
        }
    }
}

/// The nearest triangle hit within `(ray.tmin, ray.tmax)`: its leaf-order
/// index and f32 distance.
#[inline]
pub(crate) fn closest(bvh: &CwBvh, tris: &[RtTriangle], mut ray: BvhRay) -> Option<(u32, f32)> {
    let mut best = None;
    walk(bvh, &mut ray, |r, i| {
        if let Some(tri) = tris.get(i as usize) {
            let t = tri.intersect(r);
            if t < r.tmax {
                r.tmax = t;
                best = Some((i, t));
            }
        }
        false
    });
    best
}

/// Whether any triangle is hit within `(ray.tmin, ray.tmax)`.
#[inline]
pub(crate) fn any_hit(bvh: &CwBvh, tris: &[RtTriangle], mut ray: BvhRay) -> bool {
    let mut hit = false;
    walk(bvh, &mut ray, |r, i| {
        hit = tris
            .get(i as usize)
            .is_some_and(|t| t.intersect(r) < r.tmax);
        hit
    });
    hit
}

/// The node's hit mask for the ray (obvhs's `CwBvhNode::intersect_ray`
/// layout: bits 24–31 the inner children hit, by traversal priority; bits
/// 0–23 the triangles of the leaves hit).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn child_hits(node: &CwBvhNode, ray: &BvhRay, oct: u32) -> u32 {
    use core::arch::x86_64::*;
    // SAFETY: AVX2 is enabled for this build (the cfg above), and no
    // intrinsic here reads or writes memory.
    unsafe {
        // The child planes are bytes on the node's grid: a plane at q lies at
        // p + q·extent, so its distance is q·(extent/d) + (p − o)/d.
        let scale = node.compute_extent() * ray.inv_direction;
        let shift = (glam::Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
        // Eight bytes to eight f32 lanes (child j in lane j).
        let lanes = |b: [u8; 8]| {
            _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_cvtsi64_si128(i64::from_le_bytes(
                b,
            ))))
        };
        let slab = |lo: [u8; 8], hi: [u8; 8], neg: bool, s: f32, o: f32| {
            let (near, far) = if neg { (hi, lo) } else { (lo, hi) };
            let (s, o) = (_mm256_set1_ps(s), _mm256_set1_ps(o));
            (
                _mm256_add_ps(_mm256_mul_ps(lanes(near), s), o),
                _mm256_add_ps(_mm256_mul_ps(lanes(far), s), o),
            )
        };
        let d = ray.direction;
        let (x0, x1) = slab(
            node.child_min_x,
            node.child_max_x,
            d.x < 0.0,
            scale.x,
            shift.x,
        );
        let (y0, y1) = slab(
            node.child_min_y,
            node.child_max_y,
            d.y < 0.0,
            scale.y,
            shift.y,
        );
        let (z0, z1) = slab(
            node.child_min_z,
            node.child_max_z,
            d.z < 0.0,
            scale.z,
            shift.z,
        );
        // obvhs's operand order (it matters only for NaN) and its entry clamp.
        let t0 = _mm256_max_ps(x0, _mm256_max_ps(y0, z0));
        let t1 = _mm256_min_ps(x1, _mm256_min_ps(y1, z1));
        let t0 = _mm256_max_ps(t0, _mm256_set1_ps(BOX_T_MIN));
        let t1 = _mm256_min_ps(t1, _mm256_set1_ps(ray.tmax));
        let hit = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LE_OS>(t0, t1));
        // Each hit child's bits (1 for an inner node, its triangle count in
        // unary for a leaf) shifted to its bit index. A loop over the hit
        // children: its branches are predicted, where a branch-free OR of
        // eight shifted lanes put ~10 cycles of shuffles on the path to the
        // next node's address (2.5 % more CPU time on the preview scene).
        let (child_bits, bit_index) = node.get_child_and_index_bits(oct);
        let mut h = _mm256_movemask_ps(_mm256_castsi256_ps(hit)) as u32;
        let mut mask = 0u32;
        while h != 0 {
            let j = h.trailing_zeros();
            h &= h - 1;
            mask |= (((child_bits >> (8 * j)) & 0xff) as u32) << ((bit_index >> (8 * j)) & 0xff);
        }
        mask
    }
}

/// obvhs's node test where the build has no AVX2.
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline(always)]
fn child_hits(node: &CwBvhNode, ray: &BvhRay, oct: u32) -> u32 {
    node.intersect_ray(ray, oct)
}

/// obvhs clamps a child box's entry distance to this (its `EPSILON`, not
/// the ray's `tmin`): a box the ray leaves before it is skipped. Kept so
/// both node tests agree.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
const BOX_T_MIN: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, Transform};
    use crate::mesh::{MeshAccel, MeshSource, obj_from_bytes};
    use crate::preview_mesh::PreviewObject;
    use crate::rng::Rng;
    use glam::DVec3;
    use std::path::Path;

    /// The preview scene's meshes: the object and the two checker floors.
    fn preview_meshes() -> Vec<MeshSource> {
        let xf = Transform::new([0.0; 3], 1.0, [0.0; 3]);
        let files: [(&str, &[u8]); 2] = [
            (
                "a.obj",
                include_bytes!("../../../scenes/assets/preview_floor_a.obj"),
            ),
            (
                "b.obj",
                include_bytes!("../../../scenes/assets/preview_floor_b.obj"),
            ),
        ];
        let object = PreviewObject::new().obj();
        let mut out = vec![obj_from_bytes(Path::new("o.obj"), object.as_bytes(), &xf, 0).unwrap()];
        for (k, (name, bytes)) in files.into_iter().enumerate() {
            out.push(obj_from_bytes(Path::new(name), bytes, &xf, k as u32 + 1).unwrap());
        }
        out
    }

    /// Random triangles of all sizes and slivers crossing one another, and
    /// a grid of quads whose shared edges rays hit exactly.
    fn soup(rng: &mut Rng) -> Vec<MeshSource> {
        let mut tris = Vec::new();
        let point = |rng: &mut Rng| DVec3::from(rng.uniform3()) * 2.0 - 1.0;
        for k in 0..600 {
            let a = point(rng);
            let size = [1.0, 0.1, 0.01, 1e-3][k % 4];
            let (b, c) = (a + point(rng) * size, a + point(rng) * size);
            if k % 7 == 0 {
                // A sliver: c almost on the line a–b.
                tris.push([a, b, a + (b - a) * 0.5 + (c - a) * 1e-4]);
            } else {
                tris.push([a, b, c]);
            }
        }
        for i in 0..20 {
            for j in 0..20 {
                let v = |di: usize, dj: usize| {
                    DVec3::new(
                        (i + di) as f64 * 0.1 - 1.0,
                        0.25,
                        (j + dj) as f64 * 0.1 - 1.0,
                    )
                };
                tris.push([v(0, 0), v(1, 0), v(1, 1)]);
                tris.push([v(0, 0), v(1, 1), v(0, 1)]);
            }
        }
        tris.retain(|[a, b, c]| (*b - *a).cross(*c - *a).length_squared() > 0.0);
        let normals = vec![None; tris.len()];
        vec![MeshSource {
            triangles: tris,
            normals,
            uvs: None,
            surface: 0,
        }]
    }

    fn unit(rng: &mut Rng) -> DVec3 {
        let [u, v, _] = rng.uniform3();
        let z = 2.0 * u - 1.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f64::consts::TAU * v;
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// A ray of one of the kinds the renderer casts, with its (t_min, t_max):
    /// from anywhere around the meshes; leaving a triangle's surface from the
    /// integrator's offset point (1e−5 relative, either side) in any
    /// direction or grazing it; and shadow-ray segments toward a point.
    fn ray(rng: &mut Rng, tris: &[[DVec3; 3]], k: usize) -> (Ray, f64, f64) {
        let [a, b, c] = tris[(rng.next_u64() % tris.len() as u64) as usize];
        let n = (b - a).cross(c - a).normalize();
        let [u, v, w] = rng.uniform3();
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let p = a + (b - a) * u + (c - a) * v;
        let side = if w < 0.5 { 1.0 } else { -1.0 };
        let on = p + side * n * 1e-5 * 1f64.max(p.abs().max_element());
        let t_max = [f64::INFINITY, 0.5, 2.0][k % 3];
        match k % 4 {
            0 => {
                let o = DVec3::from(rng.uniform3()) * 6.0 - 3.0;
                (Ray { o, d: unit(rng) }, 0.0, t_max)
            }
            1 => (
                Ray {
                    o: on,
                    d: unit(rng),
                },
                0.0,
                t_max,
            ),
            2 => {
                // Grazing: along the surface, tilted off it by 1e−7 to 1e−2.
                let along = (unit(rng) - n * n.dot(unit(rng)))
                    .normalize_or(b - a)
                    .normalize();
                let tilt = side * 10f64.powf(-7.0 + 5.0 * rng.uniform());
                let d = (along + n * tilt).normalize();
                (Ray { o: on, d }, 0.0, t_max)
            }
            _ => {
                // A segment from a point of the surface to a point around
                // the meshes, shortened the way shadow rays are.
                let q = DVec3::from(rng.uniform3()) * 6.0 - 3.0;
                let d = (q - on).normalize();
                let t_min = if rng.uniform() < 0.5 { 0.0 } else { 1e-3 };
                (Ray { o: on, d }, t_min, (q - on).length() * (1.0 - 1e-7))
            }
        }
    }

    /// Nearest hit by testing every triangle (obvhs's triangle test, the one
    /// the traversal uses): its f32 distance.
    fn brute_force(tris: &[RtTriangle], r: &BvhRay) -> f32 {
        tris.iter()
            .map(|t| t.intersect(r))
            .fold(f32::INFINITY, f32::min)
    }

    /// Checks `closest` and `any_hit` on `count` rays against obvhs's own
    /// traversals (same triangle, same f32 distance, same answer) and
    /// against a loop over all triangles; returns how many rays hit.
    fn check(sources: Vec<MeshSource>, seed: u64, count: usize) -> usize {
        let all: Vec<[DVec3; 3]> = sources.iter().flat_map(|s| s.triangles.clone()).collect();
        let accel = MeshAccel::build(sources);
        let (bvh, tris) = accel.bvh_parts();
        let mut rng = Rng::for_sample(seed, 0, 0);
        let mut hits = 0;
        for k in 0..count {
            let (r, t_min, t_max) = ray(&mut rng, &all, k);
            let br = MeshAccel::bvh_ray(&r, t_min, t_max);
            let mut want = obvhs::ray::RayHit::none();
            let found = bvh.ray_traverse(br, &mut want, |r, i| tris[i].intersect(r));
            let got = closest(bvh, tris, br);
            let want = found.then_some((want.primitive_id, want.t.to_bits()));
            assert_eq!(got.map(|(i, t)| (i, t.to_bits())), want, "ray {k}: {r:?}");
            let blocked = !bvh.ray_traverse_miss(br, |r, i| tris[i].intersect(r));
            assert_eq!(any_hit(bvh, tris, br), blocked, "ray {k}: {r:?}");
            assert_eq!(blocked, got.is_some(), "ray {k}");
            // The BVH skips boxes the ray leaves within obvhs's 1e−4 of its
            // origin; beyond that it finds what testing every triangle does.
            let bf = brute_force(tris, &br);
            if bf >= 2e-4 {
                let bf = bf.is_finite().then_some(bf);
                assert_eq!(got.map(|g| g.1), bf, "ray {k}: {r:?}");
            }
            hits += usize::from(got.is_some());
        }
        hits
    }

    #[test]
    fn queries_on_the_preview_scene_match_obvhs_and_brute_force() {
        let hits = check(preview_meshes(), 1, 20_000);
        assert!(hits > 5_000 && hits < 19_000, "{hits} hits");
    }

    #[test]
    fn queries_on_a_triangle_soup_match_obvhs_and_brute_force() {
        let mut rng = Rng::for_sample(2, 0, 0);
        let hits = check(soup(&mut rng), 3, 20_000);
        assert!(hits > 5_000 && hits < 19_000, "{hits} hits");
    }
}
