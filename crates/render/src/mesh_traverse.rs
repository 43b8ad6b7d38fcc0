//! Ray queries over the mesh BVH with the triangle test inlined into the
//! loop.
//!
//! The tree is obvhs's compressed 8-wide BVH (CWBVH), copied into nodes laid
//! out for a CPU: obvhs stores a child box's planes as bytes on a per-node
//! grid (80-byte nodes, built for GPU bandwidth) and converts them to floats
//! on every visit; here they are converted once, exactly (a byte is an
//! f32), with the grid's origin and cell size and the child bookkeeping
//! pre-split by what the octant changes, 256 bytes per node. With AVX2 the
//! eight child boxes are tested at once. The order in which nodes and
//! triangles are visited, the box test's arithmetic (the same operations in
//! the same order, multiplies and adds unfused) and the triangle test
//! (obvhs's own) are obvhs's, so a query finds the same triangle at the same
//! f32 distance as `CwBvh::ray_traverse` / `ray_traverse_miss` (the tests
//! check both, and against a loop over all triangles).

use glam::Vec3A;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray as BvhRay;
use obvhs::rt_triangle::RtTriangle;

use crate::mesh_leaves::{Block, TriRay, any, nearest};

/// Depth of the node-group stack: obvhs's CWBVH validation bounds the depth
/// below this; a deeper tree (never built) would overwrite the top entry,
/// as obvhs's own stack does, rather than index out of bounds.
const STACK: usize = 32;

/// obvhs clamps a child box's entry distance to this (its `EPSILON`, not
/// the ray's `tmin`): a box the ray leaves before it is skipped. Kept, so
/// that the same triangles are found.
const BOX_T_MIN: f32 = 1e-4;

/// Bits 24–31 of a hit mask: inner children; bits 0–23: leaf triangles.
const NODE_BITS: u32 = 0xff00_0000;

/// One CWBVH node (child j in lane j of every array).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Node {
    /// Child box planes in grid cells: min x, max x, min y, max y, min z, max z.
    q: [[f32; 8]; 6],
    /// Grid origin and cell size per axis (a plane at q lies at origin + q·cell).
    origin: Vec3A,
    cell: Vec3A,
    /// Per child byte: a leaf's triangle count in unary, or 1 for an inner
    /// child, in bits 0–2; in bits 5–7, 7 for an inner child, whose slot is
    /// XORed with the ray's octant to visit children front to back.
    child_bits: u64,
    /// Per child byte: where the child's bits go in the hit mask: a leaf's
    /// first triangle (0–23), an inner child's slot + 24 before the flip.
    bit_index: u64,
    /// First child node and first triangle (leaf order); which slots hold
    /// inner children.
    child_base: u32,
    prim_base: u32,
    imask: u32,
    /// The node's first [`Block`] of leaf triangles (slots 0–7, then 8–15,
    /// 16–23 in the next ones, as many as its leaves fill).
    block_base: u32,
}

// Four cache lines; the layout's comments and the doc above count on it.
const _: () = assert!(size_of::<Node>() == 256);

/// The mesh BVH in [`Node`]s, with the leaf triangles in [`Block`]s.
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    blocks: Vec<Block>,
}

impl Bvh {
    /// The nodes of an obvhs CWBVH (see `CwBvhNode`'s documentation for its
    /// child metadata byte: an inner child is 0b001 in bits 5–7 and its
    /// slot + 24 in bits 0–4; a leaf has its triangle count in unary in bits
    /// 5–7 and its first triangle's offset in bits 0–4).
    /// `tri(i)` is the triangle in leaf order (`cw.primitive_indices`) `i`,
    /// `None` past the last: the blocks are filled from it, with no copy of
    /// all triangles beside them (500 k triangles take 32 MB as obvhs's).
    pub(crate) fn new(cw: &CwBvh, tri: impl Fn(usize) -> Option<RtTriangle>) -> Bvh {
        let lanes = |b: [u8; 8]| b.map(f32::from);
        let bytes = |meta: [u8; 8], f: &dyn Fn(u8) -> u8| u64::from_le_bytes(meta.map(f));
        let inner = |m: u8| m & 0x18 == 0x18;
        let mut blocks = Vec::new();
        let nodes = cw
            .nodes
            .iter()
            .map(|n| {
                let meta = n.child_meta;
                let cell = n.compute_extent();
                // The node's leaf slots: up to the last leaf's last triangle.
                let slots = meta
                    .iter()
                    .filter(|&&m| m != 0 && !inner(m))
                    .map(|&m| (m & 0x1f) as usize + (m >> 5).count_ones() as usize)
                    .max()
                    .unwrap_or(0);
                let block_base = blocks.len() as u32;
                let first = n.primitive_base_idx as usize;
                for b in (0..slots).step_by(8) {
                    let lanes = (first + b..first + slots.min(b + 8)).map_while(&tri);
                    blocks.push(Block::new(lanes));
                }
                Node {
                    q: [
                        lanes(n.child_min_x),
                        lanes(n.child_max_x),
                        lanes(n.child_min_y),
                        lanes(n.child_max_y),
                        lanes(n.child_min_z),
                        lanes(n.child_max_z),
                    ],
                    origin: n.p.into(),
                    cell,
                    child_bits: bytes(meta, &|m| m >> 5 | if inner(m) { 7 << 5 } else { 0 }),
                    bit_index: bytes(meta, &|m| m & 0x1f),
                    child_base: n.child_base_idx,
                    prim_base: n.primitive_base_idx,
                    imask: n.imask.into(),
                    block_base,
                }
            })
            .collect();
        Bvh { nodes, blocks }
    }

    /// The blocks of `node`'s leaf triangles (up to three; an empty slice
    /// for a node without leaves is never indexed: its hit mask has no
    /// triangle bits).
    #[inline(always)]
    fn blocks(&self, node: &Node) -> &[Block] {
        self.blocks.get(node.block_base as usize..).unwrap_or(&[])
    }
}

/// A group of pending children: the index of the first child node and a
/// mask whose top byte flags the children still to visit (and whose low
/// byte is the parent's `imask`, needed to locate them).
#[derive(Clone, Copy, Default)]
struct Group {
    base: u32,
    bits: u32,
}

/// Per axis, whether the reciprocal direction is negative: then the box's
/// max plane is the near one. obvhs tests `d < 0`, false for −0, while its
/// reciprocal of a component within ε of zero is ±1/ε by the sign bit
/// (`safe_inverse`), −1/ε for −0: the near and far planes then swapped and
/// every box with extent along that axis was missed, so a ray with a −0
/// component missed the whole mesh.
#[inline(always)]
fn negative(ray: &BvhRay) -> [bool; 3] {
    let inv = ray.inv_direction;
    [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0]
}

/// The ray octant as obvhs encodes it: one bit per axis, set for a
/// non-negative direction, XORed into an inner child's slot.
#[inline(always)]
fn octant(ray: &BvhRay) -> u32 {
    let [x, y, z] = negative(ray);
    (if x { 0 } else { 4 }) | (if y { 0 } else { 2 }) | (if z { 0 } else { 1 })
}

/// Walks the BVH front to back, calling `leaf(ray, node, mask)` for every
/// node with leaves whose box the ray crosses within `ray.tmax`: `mask` has
/// bit i set for the node's triangle slot i (in [`Bvh::blocks`]) to test; `leaf`
/// may shorten `ray.tmax`, and returning `true` stops the walk. The order is
/// obvhs's `traverse!`: a node's triangles before its children, children
/// nearest first by the ray's octant.
#[inline(always)]
fn walk<F: FnMut(&mut BvhRay, &Node, u32) -> bool>(bvh: &Bvh, ray: &mut BvhRay, mut leaf: F) {
    if bvh.nodes.is_empty() {
        return;
    }
    let oct = octant(ray);
    let slab = Slabs::new(ray);
    let mut stack = [Group::default(); STACK];
    let mut depth = 0usize;
    // The root is the only child of a virtual group at index 0.
    let mut nodes = Group {
        base: 0,
        bits: 0x8000_0000,
    };
    loop {
        if nodes.bits & NODE_BITS != 0 {
            let hits = nodes.bits;
            let offset = 31 - hits.leading_zeros();
            nodes.bits &= !(1 << offset);
            if nodes.bits & NODE_BITS != 0 {
                stack[depth] = nodes;
                depth = (depth + 1).min(STACK - 1);
            }
            // The visited child's rank among the parent's inner children.
            let slot = (offset - 24) ^ oct;
            let rank = (hits & !(u32::MAX << slot)).count_ones();
            let Some(node) = bvh.nodes.get((nodes.base + rank) as usize) else {
                return;
            };
            let mask = hit_mask(node, child_hits(node, &slab, ray.tmax), oct);
            nodes = Group {
                base: node.child_base,
                bits: (mask & NODE_BITS) | node.imask,
            };
            let prims = mask & !NODE_BITS;
            if prims != 0 && leaf(ray, node, prims) {
                return;
            }
        }
        if nodes.bits & NODE_BITS == 0 {
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
pub(crate) fn closest(bvh: &Bvh, mut ray: BvhRay) -> Option<(u32, f32)> {
    let tri_ray = TriRay::new(&ray);
    let mut best = None;
    walk(bvh, &mut ray, |r, node, mask| {
        if let Some((slot, t)) = nearest(bvh.blocks(node), mask, &tri_ray, r.tmax) {
            r.tmax = t;
            best = Some((node.prim_base + slot, t));
        }
        false
    });
    best
}

/// Whether any triangle is hit within `(ray.tmin, ray.tmax)`.
#[inline]
pub(crate) fn any_hit(bvh: &Bvh, mut ray: BvhRay) -> bool {
    let tri_ray = TriRay::new(&ray);
    let mut hit = false;
    walk(bvh, &mut ray, |r, node, mask| {
        hit = any(bvh.blocks(node), mask, &tri_ray, r.tmax);
        hit
    });
    hit
}

/// The ray's part of the box test.
struct Slabs {
    origin: Vec3A,
    inv_d: Vec3A,
    /// Per axis, 1 where the direction is negative: the near plane is then
    /// the box's max (index 2·axis + 1 in [`Node::q`]).
    neg: [usize; 3],
}

impl Slabs {
    #[inline(always)]
    fn new(ray: &BvhRay) -> Slabs {
        Slabs {
            origin: ray.origin,
            inv_d: ray.inv_direction,
            neg: negative(ray).map(usize::from),
        }
    }
}

/// The hit mask from the children hit (`hits`, bit j for child j): bits
/// 24–31 the inner children by traversal priority, bits 0–23 the triangles
/// of the leaves hit. A loop over the hit children: its branches are
/// predicted, where a branch-free OR of eight shifted lanes put ~10 cycles
/// of shuffles on the path to the next node's address (2.5 % more CPU time
/// on the preview scene).
#[inline(always)]
fn hit_mask(node: &Node, mut hits: u32, oct: u32) -> u32 {
    let flip = (node.child_bits >> 5) & 0x0707_0707_0707_0707;
    let index = node.bit_index ^ (flip & (u64::from(oct) * 0x0101_0101_0101_0101));
    let mut mask = 0u32;
    while hits != 0 {
        let j = 8 * hits.trailing_zeros();
        hits &= hits - 1;
        mask |= (((node.child_bits >> j) & 7) as u32) << ((index >> j) & 0xff);
    }
    mask
}

/// Which children's boxes the ray crosses within `(BOX_T_MIN, t_max)`: bit
/// j for child j. A plane q cells from the node's origin lies at distance
/// q·(cell/d) + (origin − o)/d, multiplied and added in that order as obvhs
/// does.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn child_hits(node: &Node, slab: &Slabs, t_max: f32) -> u32 {
    use core::arch::x86_64::*;
    let scale = node.cell * slab.inv_d;
    let shift = (node.origin - slab.origin) * slab.inv_d;
    // SAFETY: AVX2 is enabled for this build (the cfg above); the loads read
    // one 32-byte aligned [f32; 8] of `node.q` each.
    unsafe {
        let lanes = |k: usize| _mm256_load_ps(node.q[k].as_ptr());
        let axis = |a: usize, s: f32, o: f32| {
            let near = 2 * a + slab.neg[a];
            let (s, o) = (_mm256_set1_ps(s), _mm256_set1_ps(o));
            (
                _mm256_add_ps(_mm256_mul_ps(lanes(near), s), o),
                _mm256_add_ps(_mm256_mul_ps(lanes(near ^ 1), s), o),
            )
        };
        let (x0, x1) = axis(0, scale.x, shift.x);
        let (y0, y1) = axis(1, scale.y, shift.y);
        let (z0, z1) = axis(2, scale.z, shift.z);
        // obvhs's operand order (it matters only for NaN).
        let t0 = _mm256_max_ps(x0, _mm256_max_ps(y0, z0));
        let t1 = _mm256_min_ps(x1, _mm256_min_ps(y1, z1));
        let t0 = _mm256_max_ps(t0, _mm256_set1_ps(BOX_T_MIN));
        let t1 = _mm256_min_ps(t1, _mm256_set1_ps(t_max));
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(t0, t1)) as u32
    }
}

/// [`child_hits`] one child at a time, where the build has no AVX2 (and in
/// the tests, against the AVX2 version): the same operations, with `maxps`
/// and `minps`'s choice of operand.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
fn child_hits_scalar(node: &Node, slab: &Slabs, t_max: f32) -> u32 {
    let max = |a: f32, b: f32| if a > b { a } else { b };
    let min = |a: f32, b: f32| if a < b { a } else { b };
    let scale = node.cell * slab.inv_d;
    let shift = (node.origin - slab.origin) * slab.inv_d;
    let (s, o) = (scale.to_array(), shift.to_array());
    let mut hits = 0;
    for j in 0..8 {
        let t = |a: usize, far: usize| node.q[(2 * a + slab.neg[a]) ^ far][j] * s[a] + o[a];
        let t0 = max(max(t(0, 0), max(t(1, 0), t(2, 0))), BOX_T_MIN);
        let t1 = min(min(t(0, 1), min(t(1, 1), t(2, 1))), t_max);
        hits |= u32::from(t0 <= t1) << j;
    }
    hits
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
use child_hits_scalar as child_hits;

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
        let (cw, bvh, tris) = accel.bvh_parts();
        let mut rng = Rng::for_sample(seed, 0, 0);
        let mut hits = 0;
        for k in 0..count {
            let (r, t_min, t_max) = ray(&mut rng, &all, k);
            let br = MeshAccel::bvh_ray(&r, t_min, t_max);
            let mut want = obvhs::ray::RayHit::none();
            let found = cw.ray_traverse(br, &mut want, |r, i| tris[i].intersect(r));
            let got = closest(bvh, br);
            let want = found.then_some((want.primitive_id, want.t.to_bits()));
            assert_eq!(got.map(|(i, t)| (i, t.to_bits())), want, "ray {k}: {r:?}");
            let blocked = !cw.ray_traverse_miss(br, |r, i| tris[i].intersect(r));
            assert_eq!(any_hit(bvh, br), blocked, "ray {k}: {r:?}");
            assert_eq!(blocked, got.is_some(), "ray {k}");
            // The BVH skips boxes the ray leaves within obvhs's 1e−4 of its
            // origin; beyond that it finds what testing every triangle does.
            let bf = brute_force(tris, &br);
            if bf >= 2e-4 {
                let bf = bf.is_finite().then_some(bf);
                assert_eq!(got.map(|g| g.1), bf, "ray {k}: {r:?}");
            }
            // Every node's box test, vectorised and one child at a time.
            let slab = Slabs::new(&br);
            for node in &bvh.nodes {
                let t_max = got.map_or(br.tmax, |g| g.1);
                assert_eq!(
                    child_hits(node, &slab, t_max),
                    child_hits_scalar(node, &slab, t_max)
                );
            }
            hits += usize::from(got.is_some());
        }
        hits
    }

    /// Rays with zero direction components of either sign find what
    /// testing every triangle finds (obvhs's traversal misses every box for
    /// a −0 component).
    #[test]
    fn signed_zero_directions_find_the_nearest_triangle() {
        let mut rng = Rng::for_sample(4, 0, 0);
        let accel = MeshAccel::build(preview_meshes());
        let (_, bvh, tris) = accel.bvh_parts();
        let mut hits = 0;
        for k in 0..3000 {
            let mut d = unit(&mut rng).to_array();
            // One or two components zero, with either sign; unit length.
            for (axis, c) in d.iter_mut().enumerate() {
                if (k >> axis) & 1 == 1 && axis != k % 3 {
                    *c = if (k >> (axis + 3)) & 1 == 1 {
                        -0.0
                    } else {
                        0.0
                    };
                }
            }
            let o = DVec3::new(
                rng.uniform() - 0.5,
                1.5 * rng.uniform(),
                rng.uniform() - 0.5,
            );
            // Unit, as the renderer's: a short direction scales the 1/ε that
            // obvhs's reciprocal gives a near-zero component down against
            // the distances, and boxes are then culled wrongly.
            let d = DVec3::from(d).normalize();
            let br = MeshAccel::bvh_ray(&Ray { o, d }, 0.0, f64::INFINITY);
            let bf = brute_force(tris, &br);
            let got = closest(bvh, br);
            assert_eq!(got.map(|g| g.1), bf.is_finite().then_some(bf), "{o} {d:?}");
            assert_eq!(any_hit(bvh, br), bf.is_finite(), "{o} {d:?}");
            hits += usize::from(got.is_some());
        }
        assert!(hits > 600, "{hits} hits");
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
