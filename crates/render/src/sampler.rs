//! The random numbers of one camera sample.
//!
//! Two samplers share one interface, a sequence of 1D and 2D draws:
//!
//! * `independent`: every number from a counter-seeded [`Rng`]. Unstructured
//!   white noise; what Mitsuba's `independent` sampler does.
//! * `sobol` (default): each draw of a camera sample is its own *padded*
//!   dimension: a 2D draw takes point `i'` of the Sobol (0, 2)-sequence in
//!   dimensions 0 and 1, a 1D draw its dimension 0, where `i'` is the sample
//!   index shuffled by a nested uniform (Owen) scramble and every coordinate
//!   is Owen-scrambled too, all with seeds hashed from (scene seed, pixel,
//!   draw number) — Burley, "Practical Hash-based Owen Scrambling", JCGT 2020.
//!   The first 2^k samples of a pixel are then, in every draw, a
//!   (0, k, 2)-net (stratified in every elementary interval), while different
//!   draws and different pixels stay statistically independent. Every point
//!   is uniformly distributed, so estimates are unbiased for any sample
//!   count and for any union of sample ranges (sharded or resumed renders);
//!   the variance is lowest at powers of two.
//!
//! The Sobol points are 32-bit: sample indices ≥ 2³² would repeat the first
//! 2³² samples of the pixel. Each further block of 2³² indices therefore
//! gets scrambles of its own (the block number is hashed into the pixel's
//! seed; block 0 keeps the seed it always had), so every index is a distinct
//! sample and each block is a scrambled net on its own.
//!
//! Like [`Rng`], the numbers depend only on (seed, pixel, sample index), never
//! on threads or shards.

use crate::rng::Rng;
use crate::scene::desc::SamplerKind;
use brdf::numerics::splitmix::mix;

/// Random numbers for one camera sample.
#[derive(Clone, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    rng: Rng,
    /// Sobol: the sample index within its block of 2³², bit-reversed.
    index_rev: u32,
    /// Sobol: per-pixel (and per block of 2³² samples) hash, mixed with the
    /// draw number into scramble seeds.
    pixel_seed: u64,
    /// Sobol: the next padded dimension.
    next_draw: u32,
}

/// Sobol generator matrix of dimension 1 (primitive polynomial x + 1) as
/// byte-indexed XOR tables over the *bit-reversed* index, with bit-reversed
/// output: `SOBOL1_REV[b][v]` = rev(C · rev(v · 2^(8b))). Working in the
/// reversed domain saves two bit reversals per draw.
static SOBOL1_REV: [[u32; 256]; 4] = sobol1_rev_tables();

const fn reverse(x: u32) -> u32 {
    x.reverse_bits()
}

const fn sobol1_rev_tables() -> [[u32; 256]; 4] {
    // Direction numbers: v_0 = 2^31, v_j = v_{j−1} ⊕ (v_{j−1} >> 1).
    let mut dir = [0u32; 32];
    dir[0] = 1 << 31;
    let mut j = 1;
    while j < 32 {
        dir[j] = dir[j - 1] ^ (dir[j - 1] >> 1);
        j += 1;
    }
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut v = 0;
        while v < 256 {
            // Bit `bit` of byte b of the reversed index is index bit 31 − (8b + bit).
            let mut acc = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if v & (1 << bit) != 0 {
                    acc ^= dir[31 - (8 * b + bit)];
                }
                bit += 1;
            }
            t[b][v] = reverse(acc);
            v += 1;
        }
        b += 1;
    }
    t
}

/// rev(Sobol dimension 1 of rev(`i_rev`)).
#[inline]
fn sobol1_rev(i_rev: u32) -> u32 {
    SOBOL1_REV[0][(i_rev & 0xff) as usize]
        ^ SOBOL1_REV[1][((i_rev >> 8) & 0xff) as usize]
        ^ SOBOL1_REV[2][((i_rev >> 16) & 0xff) as usize]
        ^ SOBOL1_REV[3][(i_rev >> 24) as usize]
}

/// Laine–Karras-style hash in which every bit depends only on itself and
/// the bits below it: applied to bit-reversed values it is a nested uniform
/// (Owen) scramble. Constants from Burley 2020.
#[inline]
fn lk_permute(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// A 32-bit fraction to [0, 1); the 2^−33 offset centres the point in its
/// 2^−32 cell so that 0 is never returned exactly.
#[inline]
fn to_unit(x: u32) -> f64 {
    (x as f64 + 0.5) * (1.0 / 4_294_967_296.0)
}

/// Seeds of padded draw `draw`: the index shuffle (low 32 bits) and the
/// scramble of its first dimension (high 32 bits).
#[inline]
fn draw_seed(pixel_seed: u64, draw: u32) -> u64 {
    mix(pixel_seed ^ (draw as u64).wrapping_mul(0xd1b5_4a32_d192_ed03))
}

/// First dimension of padded draw `draw` (see [`sobol_draw`]); a 1-D draw
/// needs only this, which saves the second dimension's table lookups,
/// hash and bit reversal.
#[inline]
fn sobol_draw_x(index_rev: u32, h: u64) -> (u32, f64) {
    let shuffled_rev = lk_permute(index_rev, h as u32);
    let x = lk_permute(reverse(shuffled_rev), (h >> 32) as u32).reverse_bits();
    (shuffled_rev, to_unit(x))
}

/// Padded draw `draw` of the sample with reversed index `index_rev`.
///
/// In the reversed domain an Owen scramble is a single `lk_permute`:
/// shuffled index i′ = owen(i) has rev(i′) = lk(rev(i)); dimension 0 of i′
/// is rev(i′), whose scramble is rev(lk(i′)); dimension 1 is C·i′, whose
/// scramble is rev(lk(rev(C·i′))).
#[inline]
fn sobol_draw(index_rev: u32, pixel_seed: u64, draw: u32) -> [f64; 2] {
    let h = draw_seed(pixel_seed, draw);
    let (shuffled_rev, x) = sobol_draw_x(index_rev, h);
    let y = lk_permute(sobol1_rev(shuffled_rev), mix(h) as u32).reverse_bits();
    [x, to_unit(y)]
}

/// A 2D draw whose place in the sequence is taken ([`Sampler::reserve_2d`]).
#[derive(Clone, Copy, Debug)]
pub enum Reserved2d {
    /// Already drawn (independent sampler).
    Drawn([f64; 2]),
    /// The padded draw number to compute (Sobol).
    Draw(u32),
}

impl Sampler {
    /// The sampler of sample `sample` of pixel `pixel` under `seed`.
    #[inline]
    pub fn new(kind: SamplerKind, seed: u64, pixel: u64, sample: u64) -> Sampler {
        let mut pixel_seed =
            mix(mix(seed ^ 0x243f_6a88_85a3_08d3) ^ pixel.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let block = sample >> 32;
        if block != 0 {
            pixel_seed = mix(pixel_seed ^ mix(block ^ 0x1319_8a2e_0370_7344));
        }
        Sampler {
            kind,
            // Only the independent sampler reads it: three hashes saved per
            // Sobol camera sample.
            rng: match kind {
                SamplerKind::Independent => Rng::for_sample(seed, pixel, sample),
                SamplerKind::Sobol => Rng::for_sample(0, 0, 0),
            },
            // Truncation on purpose: the index within the block.
            index_rev: (sample as u32).reverse_bits(),
            pixel_seed,
            next_draw: 0,
        }
    }

    #[inline]
    fn next_draw(&mut self) -> u32 {
        let d = self.next_draw;
        self.next_draw = d.wrapping_add(1);
        d
    }

    /// One uniform number in [0, 1) (a padded dimension of its own).
    #[inline]
    pub fn get_1d(&mut self) -> f64 {
        match self.kind {
            SamplerKind::Independent => self.rng.uniform(),
            SamplerKind::Sobol => {
                let d = self.next_draw();
                sobol_draw_x(self.index_rev, draw_seed(self.pixel_seed, d)).1
            }
        }
    }

    /// Two uniform numbers in [0, 1)², stratified together.
    #[inline(always)]
    pub fn get_2d(&mut self) -> [f64; 2] {
        match self.kind {
            SamplerKind::Independent => [self.rng.uniform(), self.rng.uniform()],
            SamplerKind::Sobol => {
                let d = self.next_draw();
                sobol_draw(self.index_rev, self.pixel_seed, d)
            }
        }
    }

    /// Takes the next 2D draw's place in the sequence without computing it
    /// (Sobol), so a draw a sample may not need costs nothing when it is not
    /// needed; [`reserved_2d`](Self::reserved_2d) gives the values
    /// [`get_2d`](Self::get_2d) would have returned. The independent
    /// sampler's stream is sequential, so it draws at once.
    #[inline]
    pub fn reserve_2d(&mut self) -> Reserved2d {
        match self.kind {
            SamplerKind::Independent => Reserved2d::Drawn(self.get_2d()),
            SamplerKind::Sobol => Reserved2d::Draw(self.next_draw()),
        }
    }

    /// The values of a draw reserved with [`reserve_2d`](Self::reserve_2d).
    #[inline]
    pub fn reserved_2d(&self, r: Reserved2d) -> [f64; 2] {
        match r {
            Reserved2d::Drawn(u) => u,
            Reserved2d::Draw(d) => sobol_draw(self.index_rev, self.pixel_seed, d),
        }
    }

    /// A 1D draw followed by a 2D draw, as `[u1d, u2d.0, u2d.1]` (the layout
    /// of light and BSDF sampling: a discrete choice, then a direction).
    #[inline]
    pub fn get_1d_2d(&mut self) -> [f64; 3] {
        let a = self.get_1d();
        let [b, c] = self.get_2d();
        [a, b, c]
    }

    /// The sampler of branch `b` of `k` that a camera sample splits into
    /// from here on (`integrator`'s first-vertex splitting): it goes on with
    /// the same draw numbers, so its values are independent of the draws
    /// taken so far. Sobol: branch b of sample i takes point i·k + b of each
    /// later draw, so the k branches of a sample are a stratified set of
    /// their own (a net when k is a power of two) and the branches of the
    /// first N samples are the first N·k points; indices past 2³² get a
    /// scramble of their own, as [`Sampler::new`]'s blocks do. Independent:
    /// a stream seeded from the sample's next number and `b`.
    pub fn branch(&self, b: u32, k: u32) -> Sampler {
        match self.kind {
            SamplerKind::Independent => {
                let seed = self.rng.clone().next_u64();
                Sampler {
                    rng: Rng::for_sample(seed, 0, u64::from(b)),
                    ..self.clone()
                }
            }
            SamplerKind::Sobol => {
                let j = u64::from(self.index_rev.reverse_bits()) * u64::from(k) + u64::from(b);
                let high = j >> 32;
                let pixel_seed = if high == 0 {
                    self.pixel_seed
                } else {
                    mix(self.pixel_seed ^ mix(high ^ 0xa409_3822_299f_31d0))
                };
                Sampler {
                    // Truncation on purpose: the index within its block.
                    index_rev: (j as u32).reverse_bits(),
                    pixel_seed,
                    ..self.clone()
                }
            }
        }
    }

    /// [`get_1d_2d`](Self::get_1d_2d) for a caller that reads the 1D value
    /// only if `first` (a light choice among one light, the lobe choice of a
    /// single-lobe model): otherwise the Sobol sampler takes its place in
    /// the sequence without computing it and returns 0.5 there, so every
    /// value the caller reads is the one `get_1d_2d` gives. The independent
    /// sampler's stream is sequential, so it draws it anyway.
    #[inline]
    pub fn get_1d_2d_if(&mut self, first: bool) -> [f64; 3] {
        if !first && self.kind == SamplerKind::Sobol {
            self.next_draw();
            let [b, c] = self.get_2d();
            return [0.5, b, c];
        }
        self.get_1d_2d()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Plain Sobol dimension 1 by its definition, bit by bit.
    fn sobol1_reference(mut i: u32) -> u32 {
        let mut v = 1u32 << 31;
        let mut r = 0;
        while i != 0 {
            if i & 1 != 0 {
                r ^= v;
            }
            i >>= 1;
            v ^= v >> 1;
        }
        r
    }

    #[test]
    fn sobol_table_matches_the_definition_and_known_values() {
        // First points of Sobol dimension 1 (Joe–Kuo dimension 2): 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8.
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        let sobol1 = |i: u32| sobol1_rev(i.reverse_bits()).reverse_bits();
        for (i, w) in want.iter().enumerate() {
            assert_eq!(sobol1(i as u32) as f64 / 4_294_967_296.0, *w);
        }
        let mut r = Rng::for_sample(1, 2, 3);
        for _ in 0..10_000 {
            let i = r.next_u64() as u32;
            assert_eq!(sobol1(i), sobol1_reference(i));
        }
    }

    #[test]
    fn a_skipped_1d_draw_changes_no_other_value() {
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            for sample in [0u64, 7, 1 << 35] {
                let mut a = Sampler::new(kind, 3, 11, sample);
                let mut b = Sampler::new(kind, 3, 11, sample);
                for round in 0..4 {
                    let x = a.get_1d_2d();
                    let y = b.get_1d_2d_if(round % 2 == 0);
                    if round % 2 == 0 || kind == SamplerKind::Independent {
                        assert_eq!(x, y);
                    } else {
                        assert_eq!([x[1], x[2]], [y[1], y[2]]);
                        assert_eq!(y[0], 0.5);
                    }
                }
                assert_eq!(a.get_2d(), b.get_2d());
            }
        }
    }

    #[test]
    fn a_reserved_draw_is_the_draw_it_replaced() {
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            for sample in [0u64, 5, 1 << 33] {
                let mut a = Sampler::new(kind, 9, 4, sample);
                let mut b = Sampler::new(kind, 9, 4, sample);
                let first = a.get_2d();
                let r = b.reserve_2d();
                // Later draws do not depend on whether the reserved one was computed.
                assert_eq!(a.get_1d_2d(), b.get_1d_2d());
                assert_eq!(b.reserved_2d(r), first);
            }
        }
    }

    #[test]
    fn owen_scramble_is_a_nested_permutation() {
        // Bits above position b of the output depend only on bits above b of
        // the input: the top k bits of 2^k inputs differing only there
        // form a permutation.
        for seed in [0u32, 1, 0xdead_beef, 77] {
            for k in [1u32, 3, 6, 10] {
                let mut seen = vec![false; 1 << k];
                for top in 0..(1u32 << k) {
                    let x = (top << (32 - k)) | 0x0012_3456 & ((1u32 << (32 - k)) - 1);
                    let y = lk_permute(x.reverse_bits(), seed).reverse_bits() >> (32 - k);
                    assert!(!seen[y as usize], "seed {seed} k {k}: not a permutation");
                    seen[y as usize] = true;
                }
            }
        }
    }

    /// Count of the first 2^k points of a draw in every elementary interval
    /// of shape 2^−a × 2^−(k−a).
    fn check_net(points: &[[f64; 2]], k: u32) {
        for a in 0..=k {
            let (nx, ny) = (1usize << a, 1usize << (k - a));
            let mut cells = vec![0u32; nx * ny];
            for p in points {
                let cx = (p[0] * nx as f64) as usize;
                let cy = (p[1] * ny as f64) as usize;
                cells[cy * nx + cx] += 1;
            }
            assert!(
                cells.iter().all(|&c| c == 1),
                "2^{k} points are not a (0,{k},2)-net for intervals {nx}×{ny}"
            );
        }
    }

    #[test]
    fn branches_are_nets_per_sample_and_together() {
        for pixel in [0u64, 77] {
            let (k, n) = (4u32, 8u64);
            let mut all = Vec::new();
            for s in 0..n {
                let mut sm = Sampler::new(SamplerKind::Sobol, 5, pixel, s);
                let before = sm.get_1d_2d();
                let mut own = Vec::new();
                for b in 0..k {
                    let mut br = sm.branch(b, k);
                    own.push(br.get_2d());
                }
                // The draws before the split are the sample's own.
                assert_eq!(
                    before,
                    Sampler::new(SamplerKind::Sobol, 5, pixel, s).get_1d_2d()
                );
                check_net(&own, 2);
                all.extend(own);
            }
            check_net(&all, 5);
        }
        // Branch indices past 2³² are new points (not those of the index
        // with the same low 32 bits), and the independent sampler's
        // branches differ from each other.
        let far = Sampler::new(SamplerKind::Sobol, 5, 3, (1 << 32) - 1).branch(1, 4);
        let near = Sampler::new(SamplerKind::Sobol, 5, 3, (1 << 30) - 1).branch(1, 4);
        assert_eq!(far.index_rev, near.index_rev);
        assert_ne!(far.clone().get_2d(), near.clone().get_2d());
        let i = Sampler::new(SamplerKind::Independent, 5, 3, 9);
        assert_ne!(i.branch(0, 2).get_2d(), i.branch(1, 2).get_2d());
    }

    proptest::proptest! {
        /// Every branch count the scene accepts (1–64), at any sample index
        /// (past 2³² too) and pixel: a branch's draws are uniform numbers in
        /// [0, 1), one branch of one continues the sample's own draws, and
        /// the branches of a sample differ from each other.
        #[test]
        fn branches_of_any_count_and_sample_draw_in_range(
            k in 1u32..=64,
            b_frac in 0.0f64..1.0,
            sample in proptest::prelude::any::<u64>(),
            pixel in 0u64..1 << 40,
            sobol in proptest::prelude::any::<bool>(),
        ) {
            let kind = if sobol { SamplerKind::Sobol } else { SamplerKind::Independent };
            let mut sm = Sampler::new(kind, 7, pixel, sample);
            sm.get_1d_2d();
            let b = ((b_frac * f64::from(k)) as u32).min(k - 1);
            let draws = |mut s: Sampler| [s.get_1d(), s.get_1d(), s.get_1d()];
            let mine = draws(sm.branch(b, k));
            for u in mine {
                proptest::prop_assert!((0.0..1.0).contains(&u), "{u}");
            }
            if sobol && k == 1 {
                proptest::prop_assert_eq!(mine, draws(sm.clone()));
            }
            if k > 1 {
                let other = draws(sm.branch((b + 1) % k, k));
                proptest::prop_assert_ne!(mine, other);
            }
        }
    }

    #[test]
    fn every_draw_of_the_first_power_of_two_samples_is_a_net() {
        for pixel in [0u64, 5, 123_456] {
            for k in [0u32, 1, 4, 8] {
                let n = 1u64 << k;
                // Draws 0..6, alternating 2D and 1D as the integrator does.
                let mut per_draw: Vec<Vec<[f64; 2]>> = vec![Vec::new(); 3];
                let mut per_1d: Vec<Vec<f64>> = vec![Vec::new(); 3];
                for s in 0..n {
                    let mut sm = Sampler::new(SamplerKind::Sobol, 9, pixel, s);
                    for d in 0..3 {
                        per_1d[d].push(sm.get_1d());
                        per_draw[d].push(sm.get_2d());
                    }
                }
                for d in 0..3 {
                    check_net(&per_draw[d], k);
                    let mut strata = vec![0u32; n as usize];
                    for &u in &per_1d[d] {
                        assert!((0.0..1.0).contains(&u));
                        strata[(u * n as f64) as usize] += 1;
                    }
                    assert!(strata.iter().all(|&c| c == 1), "1D draw {d} at 2^{k}");
                }
                // The next block of 2^k samples is a net on its own too.
                if k > 0 {
                    let pts: Vec<[f64; 2]> = (n..2 * n)
                        .map(|s| Sampler::new(SamplerKind::Sobol, 9, pixel, s).get_2d())
                        .collect();
                    check_net(&pts, k);
                }
            }
        }
    }

    #[test]
    fn indices_past_two_to_the_32_are_new_samples() {
        // Sample 2³² + i draws other numbers than sample i (a 32-bit index
        // would repeat them).
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            for i in [0u64, 1, 77, (1 << 32) - 1] {
                for block in [1u64, 2, 0xffff_ffff] {
                    let mut a = Sampler::new(kind, 4, 9, i);
                    let mut b = Sampler::new(kind, 4, 9, (block << 32) | i);
                    let da: Vec<[f64; 2]> = (0..8).map(|_| a.get_2d()).collect();
                    let db: Vec<[f64; 2]> = (0..8).map(|_| b.get_2d()).collect();
                    assert_ne!(da, db, "{kind:?} sample {i} block {block}");
                }
            }
        }
        // Block 1 is itself stratified: its first 2^k samples form a net.
        for k in [2u32, 6] {
            let pts: Vec<[f64; 2]> = (0..1u64 << k)
                .map(|s| Sampler::new(SamplerKind::Sobol, 9, 3, (1 << 32) + s).get_2d())
                .collect();
            check_net(&pts, k);
        }
        // Block 0 is the padded Sobol sequence with the pixel's scramble
        // alone: sample indices below 2³² get no block term.
        let mut a = Sampler::new(SamplerKind::Sobol, 9, 3, 5);
        assert_eq!(
            a.get_2d(),
            sobol_draw(
                5u32.reverse_bits(),
                mix(mix(9 ^ 0x243f_6a88_85a3_08d3) ^ 3u64.wrapping_mul(0x9e37_79b9_7f4a_7c15)),
                0
            )
        );
    }

    #[test]
    fn draws_are_uniform_and_mutually_uncorrelated_across_pixels() {
        // One sample per pixel over many pixels: each draw is uniform, and
        // pairs of different draws are uncorrelated (the scrambles are
        // independent), for both samplers.
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            let n = 40_000;
            let mut sums = [0.0; 4];
            let mut sq = [0.0; 4];
            let mut cross = [0.0; 3];
            let mut hist = [[0u32; 16]; 4];
            for p in 0..n {
                let mut sm = Sampler::new(kind, 3, p, 1);
                let [a, b] = sm.get_2d();
                let c = sm.get_1d();
                let [d, _] = sm.get_2d();
                let v = [a, b, c, d];
                for j in 0..4 {
                    sums[j] += v[j];
                    sq[j] += v[j] * v[j];
                    hist[j][(v[j] * 16.0) as usize] += 1;
                }
                cross[0] += (a - 0.5) * (c - 0.5);
                cross[1] += (a - 0.5) * (d - 0.5);
                cross[2] += (b - 0.5) * (c - 0.5);
            }
            let nf = n as f64;
            for j in 0..4 {
                assert!((sums[j] / nf - 0.5).abs() < 0.006, "{kind:?} draw {j} mean");
                assert!(
                    (sq[j] / nf - 1.0 / 3.0).abs() < 0.006,
                    "{kind:?} draw {j} E[x²]"
                );
                // χ² with 15 degrees of freedom; 37.7 is the 0.001 quantile.
                let e = nf / 16.0;
                let chi2: f64 = hist[j].iter().map(|&h| (h as f64 - e).powi(2) / e).sum();
                assert!(chi2 < 37.7, "{kind:?} draw {j}: χ² {chi2}");
            }
            for (j, c) in cross.iter().enumerate() {
                // Correlation of two independent uniforms: sd 1/(12 √n) ≈ 4.2e-4.
                assert!((c / nf).abs() < 2.5e-3, "{kind:?} pair {j}: {}", c / nf);
            }
        }
    }
}
