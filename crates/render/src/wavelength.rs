//! Sampling wavelengths in proportion to the eye's sensitivity.
//!
//! The pdf is piecewise constant, proportional to |r̄| + |ḡ| + |b̄| (the
//! linear-sRGB colour-matching functions, which the film's output is made
//! of) on a fine grid over the scene's emission range. With this choice the
//! colour weights r̄/p, ḡ/p, b̄/p stay bounded, so no wavelength can produce
//! a firefly by itself; and since λ is drawn per path, wavelength-dependent
//! models (GHS, whose roughness exponent g ∝ 1/λ²) see the full continuum.
//!
//! The hero set of a path is stratified in the CDF's primary space
//! (u, u + 1/n, …): every member has the same marginal density p, which is
//! what the integrator's spectral MIS relies on. The summed per-path
//! variance of linear R, G, B for a flat spectrum is 1 490 with this choice,
//! against 13 900 with a pdf ∝ x̄ + ȳ + z̄ and the hero set rotated in λ,
//! and 3 530 with Mitsuba 3's sech² pdf stratified the same way; with one
//! wavelength per path it is 10 % lower than with the x̄ + ȳ + z̄ pdf.

use crate::color::XYZ_TO_SRGB;
use crate::distribution::Distribution1D;
use crate::spectrum::Cie;

/// Most wavelengths a path carries (`[integrator] hero_wavelengths`).
pub const MAX_WAVELENGTHS: usize = 16;

/// Wavelengths per path in hero mode when some material's value depends on λ
/// beyond its Fresnel term (the wave-optical models), where each further
/// wavelength costs a model evaluation: four (Wilkie et al. 2014). Measured
/// on `scenes/samples/s138_{ghs_ssa,ghs,two_scale}_45deg` at 64 spp, eight
/// and sixteen wavelengths are 0.71–0.86× and 0.38–0.50× as efficient; with
/// the floor of the GHS delta-lobe choice (`brdf` `GhsCommon::choice`)
/// sixteen are 0.69× on `s138_ghs_ssa_45deg` and 0.47× on
/// `s138_two_scale_45deg` but 2.9× on `s138_ghs_normal`, whose noise is
/// spectral: the split by model is a compromise, and `hero_wavelengths`
/// overrides it.
pub const HERO_COUNT: usize = 4;

/// Wavelengths per path in hero mode when every material is a microfacet or
/// smooth conductor (λ enters only through Fresnel, so a further wavelength
/// costs a Fresnel term, a colour-matching lookup and a draw). Each camera
/// sample's light and pixel draws are paired at random with its wavelength
/// draw, so the product of the geometric variation (±15 % over a small
/// light's cone on a glossy lobe) and the spread of a hero set's spectral
/// estimate is integrated at the Monte Carlo rate; more wavelengths per set
/// shrink that spread. Measured on the peer GGX copper plate (256², 256 spp):
/// relative RMSE 2.15e−3 with 4, 1.19e−3 with 8, 0.79e−3 with 16, for 1.25×
/// and 1.74× the instructions; efficiency 2.5× and 3.9× that of 4 (and
/// 2.2–3.8× on the s138 GGX and Beckmann plates).
pub const HERO_COUNT_CONDUCTORS: usize = 16;

/// Guide-entry flag: the cell's draws may need more than one step.
const WALK: u16 = 1 << 15;

/// A piecewise-constant wavelength distribution over `[lo, hi]` nm.
///
/// The density follows |r̄| + |ḡ| + |b̄| on 0.25 nm bins. Drawing inverts the
/// CDF through a guide table (four cells per bin) and a forward walk over
/// bins laid out as `[cdf at the bin's start, 1/pmf, density]`, so a draw
/// returns λ and its density from one bin record with no division, where
/// the generic [`Distribution1D`] inversion plus a separate density lookup
/// would add 15 % to a direct-lighting camera sample with four hero
/// wavelengths.
///
/// The bins must stay fine where the density is small: a histogram of 2048
/// equal-probability segments, cheaper still, gives 3× the RMSE at 256 spp
/// on the peer GGX plate, because its segments in the tails span tens of nm
/// over which the colour-matching functions change by orders of magnitude.
#[derive(Clone, Debug)]
pub struct WavelengthSampler {
    lo: f64,
    hi: f64,
    bin: f64,
    /// Bin `i`: (CDF at its start, 1 / its probability, density per nm).
    bins: Vec<[f64; 3]>,
    /// `guide[c]`: the first bin whose end exceeds c / guide.len(), with
    /// [`WALK`] set if the next cell starts two or more bins further on.
    guide: Vec<u16>,
}

impl WavelengthSampler {
    /// Builds the distribution over `[lo, hi]` ⊂ [360, 830] nm.
    pub fn new(lo: f64, hi: f64) -> WavelengthSampler {
        WavelengthSampler::with_uniform_share(lo, hi, 0.0)
    }

    /// The distribution with `share` ∈ [0, 1) of its probability spread
    /// uniformly over `[lo, hi]`: a film with spectral bands needs
    /// wavelengths in every band, including the far ends of the range where
    /// the colour-matching functions (and so the density of [`Self::new`])
    /// are ~10⁻⁴ of their peak.
    pub fn with_uniform_share(lo: f64, hi: f64, share: f64) -> WavelengthSampler {
        let cie = Cie::get();
        let n = ((4.0 * (hi - lo)).ceil() as usize).clamp(64, 4096);
        // Bin indices and the WALK flag share a u16.
        const _: () = assert!(4096 < WALK as usize);
        let bin = (hi - lo) / n as f64;
        // Midpoint weight; a small floor keeps the pdf positive where the CMFs vanish.
        let weights: Vec<f64> = (0..n)
            .map(|i| {
                let rgb = crate::color::mul(&XYZ_TO_SRGB, cie.xyz(lo + (i as f64 + 0.5) * bin));
                rgb.iter().map(|c| c.abs()).sum::<f64>() + 1e-4
            })
            .collect();
        let weights = if share > 0.0 {
            let floor = weights.iter().sum::<f64>() / n as f64 * share / (1.0 - share);
            weights.iter().map(|w| w + floor).collect()
        } else {
            weights
        };
        let dist = Distribution1D::new(&weights);
        let cdf = dist.cdf();
        let bins = (0..n)
            .map(|i| {
                let p = dist.pmf(i);
                [cdf[i], 1.0 / p, p / bin]
            })
            .collect();
        let cells = 4 * n;
        // First bin of each cell, and n − 1 closing the last cell.
        let first: Vec<usize> = (0..cells)
            .map(|c| {
                let u = c as f64 / cells as f64;
                cdf[1..].partition_point(|&e| e <= u).min(n - 1)
            })
            .chain([n - 1])
            .collect();
        // The top bit marks a cell whose draws may lie two or more bins past
        // its first one (the next cell starts at least two bins on).
        let guide = first
            .windows(2)
            .map(|w| w[0] as u16 | if w[1] > w[0] + 1 { WALK } else { 0 })
            .collect();
        WavelengthSampler {
            lo,
            hi,
            bin,
            bins,
            guide,
        }
    }

    /// The sampled interval in nm.
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }

    /// λ and its density for a uniform `u` ∈ [0, 1).
    #[inline(always)]
    fn draw(&self, u: f64) -> (f64, f64) {
        let u = u.clamp(0.0, 1.0f64.next_down());
        let cells = self.guide.len();
        // Through u32 (u·cells < 2¹⁸): shorter than the saturating f64 → usize.
        let g = self.guide[((u * cells as f64) as u32 as usize).min(cells - 1)];
        let mut i = (g & !WALK) as usize;
        let last = self.bins.len() - 1;
        // The end of bin i is the start of bin i + 1. A guide cell holds at
        // most one bin end wherever a bin's probability is at least a
        // quarter of the mean, so one branch-free step finishes the search
        // (as a loop, its exit mispredicted for most draws); the cells in
        // the tails that span more bins are marked, and only they walk on.
        i += usize::from(i < last && self.bins[i + 1][0] <= u);
        if g & WALK != 0 {
            while i < last && self.bins[i + 1][0] <= u {
                i += 1;
            }
        }
        let [start, inv_p, density] = self.bins[i];
        let t = ((u - start) * inv_p).clamp(0.0, 1.0);
        ((self.lo + (i as f64 + t) * self.bin).min(self.hi), density)
    }

    /// Draws λ from a uniform `u` ∈ [0, 1).
    pub fn sample(&self, u: f64) -> f64 {
        self.draw(u).0
    }

    /// Density (per nm) of `lambda`.
    pub fn pdf(&self, lambda: f64) -> f64 {
        if !(self.lo..=self.hi).contains(&lambda) {
            return 0.0;
        }
        let i = (((lambda - self.lo) / self.bin) as usize).min(self.bins.len() - 1);
        self.bins[i][2]
    }

    /// The hero set of one path: `count` wavelengths at b, b + 1/count, …
    /// in the CDF's primary space, with b = `u[0]`/count, listed from
    /// member ⌊`u[1]` · count⌋ on (the hero first).
    ///
    /// Every member has marginal density [`pdf`](Self::pdf) (b is uniform on
    /// [0, 1/count) and the starting member uniform and independent of it),
    /// and which member is the hero does not depend on the set, which the
    /// integrator's spectral MIS relies on. Taking b from `u[0]`/count rather
    /// than `u[0]` mod 1/count keeps the sampler's stratification: N
    /// stratified values of `u[0]` put the N·count wavelengths of a pixel in
    /// N·count distinct strata, where the members of u, u + 1/count, … fell
    /// count to a stratum of width 1/N.
    pub fn stratified(&self, u: [f64; 2], count: usize) -> [f64; MAX_WAVELENGTHS] {
        self.sample_set(u, count).lambda
    }

    /// The wavelengths of one camera sample: [`stratified`](Self::stratified)
    /// with the density of each member, taken from the bin it was drawn in.
    pub fn sample_set(&self, u: [f64; 2], count: usize) -> SampledWavelengths {
        let count = count.clamp(1, MAX_WAVELENGTHS);
        let mut lambda = [0.0; MAX_WAVELENGTHS];
        let mut pdf = [0.0; MAX_WAVELENGTHS];
        let step = 1.0 / count as f64;
        let base = u[0].clamp(0.0, 1.0f64.next_down()) * step;
        let hero = ((u[1] * count as f64) as usize).min(count - 1);
        let mut member = hero;
        for j in 0..count {
            (lambda[j], pdf[j]) = self.draw(base + member as f64 * step);
            member += 1;
            if member == count {
                member = 0;
            }
        }
        SampledWavelengths {
            n: count,
            lambda,
            pdf,
        }
    }
}

/// The wavelengths one camera sample carries (1, or up to
/// [`MAX_WAVELENGTHS`] hero wavelengths) with the density each was drawn with: the two travel
/// together so that no estimate divides by another sample's pdf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    pub(crate) n: usize,
    pub(crate) lambda: [f64; MAX_WAVELENGTHS],
    pub(crate) pdf: [f64; MAX_WAVELENGTHS],
}

impl SampledWavelengths {
    /// Number of wavelengths carried.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether none are carried: a path whose every contribution was
    /// integrated over λ exactly (`spectral_table.rs`) draws none.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The empty set.
    pub fn none() -> SampledWavelengths {
        SampledWavelengths {
            n: 0,
            lambda: [0.0; MAX_WAVELENGTHS],
            pdf: [0.0; MAX_WAVELENGTHS],
        }
    }

    /// The wavelengths in nm.
    pub fn lambdas(&self) -> &[f64] {
        &self.lambda[..self.n]
    }

    /// The density (per nm) each wavelength was drawn with.
    pub fn pdfs(&self) -> &[f64] {
        &self.pdf[..self.n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pdf_integrates_to_one_and_sampling_follows_it() {
        for &(lo, hi) in &[(360.0, 830.0), (520.0, 540.0)] {
            let s = WavelengthSampler::new(lo, hi);
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| s.pdf(lo + (i as f64 + 0.5) * (hi - lo) / n as f64))
                .sum::<f64>()
                * (hi - lo)
                / n as f64;
            assert!((integral - 1.0).abs() < 1e-6, "{integral}");
            // E[ȳ(λ)/p(λ)] = ∫ȳ dλ over the range (the ratio is bounded by construction).
            let cie = Cie::get();
            let m = 100_000;
            let mean: f64 = (0..m)
                .map(|i| {
                    let l = s.sample((i as f64 + 0.5) / m as f64);
                    cie.xyz(l)[1] / s.pdf(l)
                })
                .sum::<f64>()
                / m as f64;
            let exact: f64 = (0..200_000)
                .map(|i| cie.xyz(lo + (i as f64 + 0.5) * (hi - lo) / 2e5)[1])
                .sum::<f64>()
                * (hi - lo)
                / 2e5;
            assert!((mean / exact - 1.0).abs() < 1e-4, "{mean} vs {exact}");
        }
    }

    #[test]
    fn stratified_members_each_follow_the_pdf_and_form_the_same_set_for_any_hero() {
        let s = WavelengthSampler::new(360.0, 830.0);
        for count in [HERO_COUNT, HERO_COUNT_CONDUCTORS, 3] {
            // Histogram of every member against the pdf over 47 bins of 10 nm.
            let n = 40_000;
            let mut hist = vec![[0usize; 47]; count];
            for i in 0..n {
                // A stratified first coordinate and a hero index that cycles
                // independently of it, as the Sobol draws give.
                let u = [
                    (i as f64 + 0.37) / n as f64,
                    ((i * 7919) % n) as f64 / n as f64,
                ];
                let set = s.stratified(u, count);
                for (j, l) in set[..count].iter().enumerate() {
                    assert!((360.0..=830.0).contains(l));
                    hist[j][(((l - 360.0) / 10.0) as usize).min(46)] += 1;
                }
            }
            for b in 0..47 {
                let p: f64 = (0..1000)
                    .map(|k| s.pdf(360.0 + 10.0 * b as f64 + (k as f64 + 0.5) / 100.0))
                    .sum::<f64>()
                    / 100.0;
                for h in &hist {
                    let got = h[b] as f64 / n as f64;
                    assert!(
                        (got - p).abs() < 2e-4 + 2e-3 * p,
                        "{count}: bin {b}: {got} vs {p}"
                    );
                }
            }
        }
        // The hero choice rotates the same set.
        let a = s.stratified([0.5, 0.1], HERO_COUNT);
        let b = s.stratified([0.5, 0.3], HERO_COUNT);
        assert_eq!(a[1].to_bits(), b[0].to_bits());
        assert_eq!(a[0].to_bits(), b[3].to_bits());
        // Members sit at b + j/4 in primary space.
        for (j, &l) in a[..HERO_COUNT].iter().enumerate() {
            assert_eq!(l, s.sample(0.125 + j as f64 * 0.25));
        }
        assert_eq!(s.stratified([0.7, 0.9], 1)[0], s.sample(0.7));
        let set = s.sample_set([0.5, 0.1], HERO_COUNT);
        assert_eq!(set.lambdas(), &a[..HERO_COUNT]);
        for (l, p) in set.lambdas().iter().zip(set.pdfs()) {
            assert_eq!(*p, s.pdf(*l));
        }
        assert_eq!(s.sample_set([0.7, 0.2], 1).lambdas(), &[s.sample(0.7)]);
        assert_eq!(s.sample_set([0.7, 0.2], 99).len(), MAX_WAVELENGTHS);
    }

    #[test]
    fn guided_draw_finds_the_bin_a_full_search_finds() {
        // Every bin start, the floats on either side of it, and a dense
        // sweep, over ranges whose tails span many bins per guide cell.
        for &(lo, hi) in &[(360.0, 830.0), (520.0, 540.0), (380.0, 780.5)] {
            let s = WavelengthSampler::new(lo, hi);
            let starts: Vec<f64> = s.bins.iter().map(|b| b[0]).collect();
            let mut us: Vec<f64> = (0..200_000).map(|k| k as f64 / 200_000.0).collect();
            for &b in &starts {
                us.extend([b, b.next_up(), b.next_down().max(0.0)]);
            }
            for u in us {
                let want = starts.partition_point(|&b| b <= u).max(1) - 1;
                let (l, p) = s.draw(u);
                assert_eq!(p, s.bins[want][2], "{lo}–{hi}: u {u}");
                let t = (l - lo) / s.bin - want as f64;
                assert!((-1e-9..=1.0 + 1e-9).contains(&t), "{lo}–{hi}: u {u}: λ {l}");
            }
        }
    }

    #[test]
    fn a_pixels_stratified_draws_fill_distinct_strata() {
        // N stratified first coordinates give N·count wavelengths, one in
        // each of N·count equal-probability strata of the CDF.
        let s = WavelengthSampler::new(360.0, 830.0);
        for count in [HERO_COUNT, HERO_COUNT_CONDUCTORS] {
            let n = 16;
            let mut seen = vec![0usize; n * count];
            for i in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, ((i * 5) % n) as f64 / n as f64];
                let set = s.stratified(u, count);
                for (j, &l) in set[..count].iter().enumerate() {
                    let member = (((u[1] * count as f64) as usize) + j) % count;
                    let v = (u[0] + member as f64) / count as f64;
                    assert_eq!(l, s.sample(v));
                    seen[(v * (n * count) as f64) as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{seen:?}");
        }
    }
}
