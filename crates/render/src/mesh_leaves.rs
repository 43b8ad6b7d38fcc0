//! A BVH node's leaf triangles, eight to a block in structure-of-arrays
//! layout, tested eight at a time.
//!
//! A CWBVH node's leaf children hold up to 24 triangles, stored one after
//! the other from the node's first triangle; here they fill one to three
//! [`Block`]s of the node's own, so that the triangles of every leaf the ray
//! reaches are tested in one pass per block (with AVX2; one lane at a time
//! without it). The arithmetic per lane is obvhs's `RtTriangle::intersect`
//! (Möller–Trumbore with e₁ = v₀ − v₁, e₂ = v₂ − v₀, n = e₁ × e₂), the same
//! operations in the same order, unfused, so a lane's distance is the one
//! obvhs's test gives; and the nearest lane is chosen as obvhs's traversal,
//! which tests a node's triangles from its highest slot down and keeps a hit
//! only if strictly nearer, would: among equal distances the highest slot.

use obvhs::ray::Ray as BvhRay;
use obvhs::rt_triangle::RtTriangle;

/// Lanes of a [`Block`]: v₀ x, y, z; e₁ x, y, z; e₂ x, y, z; n x, y, z.
const FIELDS: usize = 12;

/// Eight triangles, one per lane (unused lanes zero: never in a hit mask).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
pub(crate) struct Block {
    lanes: [[f32; 8]; FIELDS],
}

// 384 bytes: 48 per triangle, against obvhs's 64-byte `RtTriangle`.
const _: () = assert!(size_of::<Block>() == 384);

impl Block {
    /// Up to eight triangles in lanes 0, 1, …
    pub(crate) fn new(tris: impl IntoIterator<Item = RtTriangle>) -> Block {
        let mut lanes = [[0.0; 8]; FIELDS];
        for (j, t) in tris.into_iter().take(8).enumerate() {
            for (k, v) in [t.v0, t.e1, t.e2, t.ng].into_iter().enumerate() {
                lanes[3 * k][j] = v.x;
                lanes[3 * k + 1][j] = v.y;
                lanes[3 * k + 2][j] = v.z;
            }
        }
        Block { lanes }
    }
}

/// The ray's part of the triangle test.
pub(crate) struct TriRay {
    o: [f32; 3],
    d: [f32; 3],
    t_min: f32,
}

impl TriRay {
    #[inline(always)]
    pub(crate) fn new(ray: &BvhRay) -> TriRay {
        TriRay {
            o: ray.origin.to_array(),
            d: ray.direction.to_array(),
            t_min: ray.tmin,
        }
    }
}

/// The nearest hit within `(ray.t_min, t_max)` among the triangles of
/// `blocks` whose slot (8·block + lane) has its bit set in `mask`: that
/// slot and the distance; among equal distances the highest slot.
#[inline(always)]
pub(crate) fn nearest(blocks: &[Block], mask: u32, ray: &TriRay, t_max: f32) -> Option<(u32, f32)> {
    let mut best = None;
    let mut t_best = t_max;
    for (b, block) in blocks.iter().enumerate().take(3).rev() {
        let bits = (mask >> (8 * b)) & 0xff;
        if bits == 0 {
            continue;
        }
        let (t, mut hits) = block_hits(block, bits, ray, t_best);
        while hits != 0 {
            let lane = 31 - hits.leading_zeros();
            hits &= !(1 << lane);
            if t[lane as usize] < t_best {
                t_best = t[lane as usize];
                best = Some((8 * b as u32 + lane, t_best));
            }
        }
    }
    best
}

/// Whether any triangle of `blocks` whose slot's bit is set in `mask` is hit
/// within `(ray.t_min, t_max)`.
#[inline(always)]
pub(crate) fn any(blocks: &[Block], mask: u32, ray: &TriRay, t_max: f32) -> bool {
    blocks.iter().take(3).enumerate().any(|(b, block)| {
        let bits = (mask >> (8 * b)) & 0xff;
        bits != 0 && block_hits(block, bits, ray, t_max).1 != 0
    })
}

/// Every lane's distance and, for the lanes in `bits`, which are hits: a
/// valid Möller–Trumbore intersection at t with t_min ≤ t < t_max.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn block_hits(block: &Block, bits: u32, ray: &TriRay, t_max: f32) -> ([f32; 8], u32) {
    use core::arch::x86_64::*;
    // SAFETY: AVX2 is enabled for this build (the cfg above); each load reads
    // one 32-byte aligned [f32; 8] of the block, the store a local [f32; 8].
    unsafe {
        let f = |k: usize| _mm256_load_ps(block.lanes[k].as_ptr());
        let s = |x: f32| _mm256_set1_ps(x);
        let mul = |a, b| _mm256_mul_ps(a, b);
        let add = |a, b| _mm256_add_ps(a, b);
        let sub = |a, b| _mm256_sub_ps(a, b);
        let [ox, oy, oz] = ray.o.map(s);
        let [dx, dy, dz] = ray.d.map(s);
        // glam's Vec3A dot: (x·x' + y·y') + z·z'.
        let dot = |a: [__m256; 3], b: [__m256; 3]| {
            add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]))
        };
        let c = [sub(f(0), ox), sub(f(1), oy), sub(f(2), oz)];
        // d × c, each component a·b − c·d as glam's cross computes it:
        // the second product subtracted fused where the build has FMA.
        #[cfg(target_feature = "fma")]
        let ab_cd = |a, b, c, d| _mm256_fnmadd_ps(c, d, mul(a, b));
        #[cfg(not(target_feature = "fma"))]
        let ab_cd = |a, b, c, d| sub(mul(a, b), mul(c, d));
        let r = [
            ab_cd(dy, c[2], dz, c[1]),
            ab_cd(dz, c[0], dx, c[2]),
            ab_cd(dx, c[1], dy, c[0]),
        ];
        let e1 = [f(3), f(4), f(5)];
        let e2 = [f(6), f(7), f(8)];
        let ng = [f(9), f(10), f(11)];
        let inv_det = _mm256_div_ps(s(1.0), dot(ng, [dx, dy, dz]));
        let u = mul(dot(r, e2), inv_det);
        let v = mul(dot(r, e1), inv_det);
        let w = sub(sub(s(1.0), u), v);
        let t = mul(dot(ng, c), inv_det);
        // A sign bit in u, v or w (−0 included) misses, as in obvhs.
        let negative = _mm256_movemask_ps(_mm256_or_ps(_mm256_or_ps(u, v), w)) as u32;
        let ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(inv_det, s(0.0)),
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(t, s(ray.t_min)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(t, s(t_max)),
            ),
        );
        let hits = _mm256_movemask_ps(ok) as u32 & !negative & bits;
        let mut out = [0.0f32; 8];
        _mm256_storeu_ps(out.as_mut_ptr(), t);
        (out, hits)
    }
}

/// [`block_hits`] one lane at a time, where the build has no AVX2 (and in
/// the tests, against the AVX2 version).
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
fn block_hits_scalar(block: &Block, bits: u32, ray: &TriRay, t_max: f32) -> ([f32; 8], u32) {
    let mut out = [0.0f32; 8];
    let mut hits = 0;
    for (j, out) in out.iter_mut().enumerate() {
        let f = |k: usize| block.lanes[k][j];
        let [ox, oy, oz] = ray.o;
        let [dx, dy, dz] = ray.d;
        let dot = |a: [f32; 3], b: [f32; 3]| (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
        let c = [f(0) - ox, f(1) - oy, f(2) - oz];
        let r = [
            ab_cd(dy, c[2], dz, c[1]),
            ab_cd(dz, c[0], dx, c[2]),
            ab_cd(dx, c[1], dy, c[0]),
        ];
        let (e1, e2, ng) = ([f(3), f(4), f(5)], [f(6), f(7), f(8)], [f(9), f(10), f(11)]);
        let inv_det = 1.0 / dot(ng, [dx, dy, dz]);
        let u = dot(r, e2) * inv_det;
        let v = dot(r, e1) * inv_det;
        let w = (1.0 - u) - v;
        let t = dot(ng, c) * inv_det;
        *out = t;
        let negative = (u.to_bits() | v.to_bits() | w.to_bits()) >> 31 == 1;
        let ok = inv_det != 0.0 && !negative && t >= ray.t_min && t < t_max;
        hits |= u32::from(ok) << j;
    }
    (out, hits & bits)
}

/// a·b − c·d as glam's `Vec3A::cross` forms a component: with FMA in the
/// build, c·d is subtracted from the rounded a·b in one rounding.
#[cfg(any(test, not(all(target_arch = "x86_64", target_feature = "avx2"))))]
#[inline(always)]
fn ab_cd(a: f32, b: f32, c: f32, d: f32) -> f32 {
    if cfg!(target_feature = "fma") {
        (-c).mul_add(d, a * b)
    } else {
        a * b - c * d
    }
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
use block_hits_scalar as block_hits;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use glam::Vec3A;
    use obvhs::triangle::Triangle;

    fn point(rng: &mut Rng, scale: f32) -> Vec3A {
        let [x, y, z] = rng.uniform3();
        Vec3A::new(x as f32 - 0.5, y as f32 - 0.5, z as f32 - 0.5) * scale
    }

    /// Eight triangles: random, slivers, sharing an edge, degenerate, at
    /// scales 1e−4 to 1e4.
    fn triangles(rng: &mut Rng, scale: f32) -> Vec<RtTriangle> {
        let mut out = Vec::new();
        for k in 0..8 {
            let a = point(rng, scale);
            let (b, c) = (a + point(rng, scale), a + point(rng, scale));
            let tri = match k {
                5 => Triangle {
                    v0: a,
                    v1: b,
                    v2: a + (b - a) * 0.5 + (c - a) * 1e-5,
                },
                6 => Triangle {
                    v0: a,
                    v1: b,
                    v2: a + (b - a) * 0.5,
                },
                7 => Triangle {
                    v0: b,
                    v1: a,
                    v2: c - (b - a),
                },
                _ => Triangle {
                    v0: a,
                    v1: b,
                    v2: c,
                },
            };
            out.push(RtTriangle::from(&tri));
        }
        // Lane 4 shares lane 0's edge a–b.
        let t0 = out[0];
        let (a, b) = (t0.v0, t0.v0 - t0.e1);
        out[4] = RtTriangle::from(&Triangle {
            v0: b,
            v1: a,
            v2: a + point(rng, scale),
        });
        out
    }

    /// Rays at the lanes' triangles: through vertices, edge points and
    /// interiors, and along random directions with ±0 components.
    fn rays(rng: &mut Rng, tris: &[RtTriangle], scale: f32) -> Vec<(usize, BvhRay)> {
        let mut out = Vec::new();
        for (k, t) in tris.iter().enumerate() {
            let (a, b, c) = (t.v0, t.v0 - t.e1, t.v0 + t.e2);
            let targets = [a, b, c, (a + b) * 0.5, (a + b + c) / 3.0, point(rng, scale)];
            for (i, target) in targets.into_iter().enumerate() {
                let o = point(rng, 4.0 * scale);
                let mut d = (target - o).normalize_or(Vec3A::Y);
                if i == 5 && k % 3 == 0 {
                    d.x = if k % 2 == 0 { 0.0 } else { -0.0 };
                }
                let t_max = [f32::INFINITY, 8.0 * scale, 0.3 * scale][(i + k) % 3];
                out.push((k, BvhRay::new(o, d, [0.0, 1e-4 * scale][i % 2], t_max)));
            }
        }
        out
    }

    /// Checks one block against obvhs's test of its triangles; whether any
    /// was hit.
    fn check_block(tris: &[RtTriangle], ray: &BvhRay, bits: u32) -> bool {
        let block = [Block::new(tris.iter().copied())];
        let tr = TriRay::new(ray);
        let (t, h) = block_hits(&block[0], bits, &tr, ray.tmax);
        let (ts, hs) = block_hits_scalar(&block[0], bits, &tr, ray.tmax);
        assert_eq!((t.map(f32::to_bits), h), (ts.map(f32::to_bits), hs));
        let mut want = None;
        let mut r = *ray;
        for j in (0..8).rev().filter(|j| bits >> j & 1 == 1) {
            let tj = tris[j as usize].intersect(ray);
            assert_eq!(h >> j & 1 == 1, tj < ray.tmax, "{j} {tj}");
            if tj < ray.tmax {
                assert_eq!(t[j as usize].to_bits(), tj.to_bits());
            }
            // obvhs's traversal: the test against the shortened ray.
            let tj = tris[j as usize].intersect(&r);
            if tj < r.tmax {
                r.tmax = tj;
                want = Some((j, tj));
            }
        }
        assert_eq!(nearest(&block, bits, &tr, ray.tmax), want);
        assert_eq!(any(&block, bits, &tr, ray.tmax), want.is_some());
        want.is_some()
    }

    /// Every lane's test, vectorised and one lane at a time, is obvhs's
    /// `RtTriangle::intersect` (hit and distance bit for bit), and
    /// `nearest` / `any` choose as a loop over the slots from the highest.
    #[test]
    fn lanes_are_obvhs_triangle_test() {
        let mut rng = Rng::for_sample(7, 0, 0);
        let mut hits = 0;
        for round in 0..400 {
            let scale = [1e-4, 1e-2, 1.0, 1e2, 1e4][round % 5];
            let tris = triangles(&mut rng, scale);
            for (k, base) in rays(&mut rng, &tris, scale) {
                // The aimed-at lane and others at random.
                let bits = (rng.next_u64() & 0xff) as u32 | 1 << k;
                // The ray, and where it hits lane k, the ray ending or
                // starting exactly there (obvhs: t_min ≤ t < t_max).
                let t_k = tris[k].intersect(&base);
                let mut variants = vec![base];
                if t_k.is_finite() {
                    variants.push(BvhRay { tmax: t_k, ..base });
                    variants.push(BvhRay { tmin: t_k, ..base });
                }
                for ray in variants {
                    hits += usize::from(check_block(&tris, &ray, bits));
                }
            }
        }
        assert!(hits > 3500, "{hits} hits");
    }
}
