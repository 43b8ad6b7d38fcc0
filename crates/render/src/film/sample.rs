//! From one camera sample's spectral radiance to what the film adds.
//!
//! The integrator hands the film each camera sample as radiance estimates
//! at its sampled wavelengths (wavelength pdf included) plus the XYZ of the
//! contributions it integrated over λ exactly ([`SampleRadiance`]);
//! [`sample_xyz`] matches each wavelength to CIE 1931 XYZ and checks the
//! sample, [`to_fixed`] rounds its XYZ to a multiple of 2⁻⁴⁰ (≈ 9·10⁻¹³), and
//! [`TileSums`] adds samples in i128, leaving 2⁸⁷ of head-room: quantisation
//! is 10⁻⁹ of a unit radiance, far below Monte Carlo noise, and overflow
//! needs ~10²⁶ in one pixel.

use super::bands::{self, BandLayout};
use crate::spectrum::Cie;
use crate::wavelength::{MAX_WAVELENGTHS, SampledWavelengths};
use std::fmt;

/// One unit of the fixed point is 2⁻⁴⁰.
pub(super) const SCALE: f64 = (1u64 << 40) as f64;
/// Largest |X|, |Y| or |Z| of one camera sample the film adds: 10²⁰ · 2⁴⁰ is
/// 1.1·10³², so the i128 sums (up to 1.7·10³⁸) hold a million such samples
/// per pixel. A larger estimate (lights of radiance ~10²⁴ and up) is dropped
/// and counted: saturating the fixed-point conversion instead would give
/// every lit pixel the same value without a word.
pub const MAX_SAMPLE_XYZ: f64 = 1e20;
/// [`MAX_SAMPLE_XYZ`] in the film's fixed point: no pixel sum exceeds the
/// pixel's sample count times this.
pub(super) const MAX_SAMPLE_FIXED: i128 = (MAX_SAMPLE_XYZ * SCALE) as i128;

/// One camera sample: its wavelengths and spectral radiance estimates.
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// The wavelengths carried ([`Settings::wavelengths_per_path`](crate::scene::Settings::wavelengths_per_path))
    /// and their pdfs.
    pub wavelengths: SampledWavelengths,
    /// Radiance estimates at each wavelength, wavelength pdf included; the
    /// first `wavelengths.len()` are used.
    pub radiance: [f64; MAX_WAVELENGTHS],
    /// XYZ (before the film's 1/∫ȳ normalisation) of the contributions
    /// integrated over λ exactly ([`crate::spectral_table`]); a path that
    /// needs no sampled wavelength carries none.
    pub xyz: [f64; 3],
}

/// What the integrator measured for one camera sample.
// Not boxed: the value is returned through the caller's slot, so a small
// variant writes its few bytes only, and a box would allocate per sample.
#[allow(clippy::large_enum_variant)]
pub enum SampleRadiance {
    /// Nothing reached the camera: zero at every wavelength.
    Zero,
    /// Every contribution was integrated over λ exactly: their XYZ (before
    /// the film's 1/∫ȳ normalisation).
    Xyz([f64; 3]),
    /// Sampled wavelengths were needed.
    Spectral(CameraSample),
}

/// The XYZ one camera sample adds to the film (before the film's 1/∫ȳ
/// normalisation), or why it cannot be averaged: a wavelength's radiance
/// estimate is NaN, infinite, or negative while `signed` is false (no
/// emission spectrum of the scene is negative anywhere; see
/// [`Scene::signed_radiance`](crate::Scene)), or the XYZ lies beyond
/// [`MAX_SAMPLE_XYZ`]. Each means a model misbehaved; the render loop counts
/// and reports such samples instead of averaging them (one branch, never
/// taken in a sound render).
#[inline]
pub fn sample_xyz(radiance: SampleRadiance, signed: bool) -> Result<[f64; 3], BadSample> {
    // Read in place: moving the 416-byte sample out of the enum took two
    // memcpy calls per spectral sample.
    let cs = match &radiance {
        SampleRadiance::Zero => return Ok([0.0; 3]),
        &SampleRadiance::Xyz(xyz) => {
            // The checks below with no sampled wavelength, returned from
            // here so that the caller need not keep the whole value alive.
            // See below for why Y decides the sign.
            let finite = xyz.iter().all(|v| in_film_range(*v));
            return match (finite, signed || xyz[1] >= 0.0) {
                (false, _) => Err(BadSample::NonFinite),
                (true, false) => Err(BadSample::Negative),
                (true, true) => Ok(xyz),
            };
        }
        SampleRadiance::Spectral(cs) => cs,
    };
    let n = cs.wavelengths.len();
    let r = &cs.radiance[..n];
    if !r.iter().all(|v| v.is_finite()) || !cs.xyz.iter().all(|v| v.is_finite()) {
        return Err(BadSample::NonFinite);
    }
    // The exactly integrated part is a non-negative spectrum's XYZ, whose Y
    // (unlike X and Z of a narrow band, within the table's tolerance of 0)
    // is clearly positive: a negative Y is a model's negative value.
    let non_negative = r.iter().all(|v| *v >= 0.0) && cs.xyz[1] >= 0.0;
    if !signed && !non_negative {
        return Err(BadSample::Negative);
    }
    let cie = Cie::get();
    let mut xyz = cs.xyz;
    for (j, &lambda) in cs.wavelengths.lambdas().iter().enumerate() {
        let c = cie.xyz(lambda);
        for k in 0..3 {
            xyz[k] += cs.radiance[j] * c[k];
        }
    }
    // Finite radiances can still overflow in the sum, or leave the film's range.
    if xyz.iter().all(|v| in_film_range(*v)) {
        Ok(xyz)
    } else {
        Err(BadSample::NonFinite)
    }
}

/// [`sample_xyz`], and the sample's band values in `bands` (cleared first;
/// one per band of `layout`, see [`super::bands`]). Only renders with bands
/// call it, so a render without pays nothing for them. A sample whose band
/// value leaves the film's range is dropped like one whose XYZ does.
/// Contributions integrated over λ exactly carry no spectrum, so a scene
/// with bands samples every wavelength ([`crate::Scene::set_spectral_bands`]
/// leaves no exact tables): an `Xyz` sample there adds its XYZ and no band.
#[inline]
pub fn sample_xyz_bands(
    radiance: SampleRadiance,
    signed: bool,
    layout: &BandLayout,
    bands: &mut [f64],
) -> Result<[f64; 3], BadSample> {
    bands.fill(0.0);
    let cs = match radiance {
        SampleRadiance::Spectral(cs) => cs,
        other => return sample_xyz(other, signed),
    };
    let xyz = sample_xyz(SampleRadiance::Spectral(cs), signed)?;
    let n = cs.wavelengths.len();
    bands::add_sample(layout, cs.wavelengths.lambdas(), &cs.radiance[..n], bands);
    if bands.iter().all(|v| in_film_range(*v)) {
        Ok(xyz)
    } else {
        Err(BadSample::NonFinite)
    }
}

/// Whether a sample's XYZ component can be added to the film: finite and
/// within [`MAX_SAMPLE_XYZ`] (false for NaN).
#[inline(always)]
fn in_film_range(v: f64) -> bool {
    v.abs() <= MAX_SAMPLE_XYZ
}

/// The sums of a rectangle of pixels over a range of samples, in the film's
/// fixed point: what a render task builds off the film, to be added to it
/// whole ([`Film::add_pass`](super::Film::add_pass)).
#[derive(Clone, Debug)]
pub struct TileSums {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
    sums: Vec<[i128; 3]>,
    /// Band sums, `bands` per pixel after each other (empty without bands).
    band_sums: Vec<i128>,
    bands: usize,
    dropped: Dropped,
}

impl TileSums {
    /// Empty sums of columns `x0..x1` and rows `y0..y1`.
    pub fn new(x0: u32, y0: u32, x1: u32, y1: u32) -> TileSums {
        let pixels = x1.saturating_sub(x0) as usize * y1.saturating_sub(y0) as usize;
        TileSums {
            x0,
            y0,
            x1,
            y1,
            sums: Vec::with_capacity(pixels),
            band_sums: Vec::new(),
            bands: 0,
            dropped: Dropped::default(),
        }
    }

    /// Empty sums of columns `x0..x1` and rows `y0..y1` with `bands`
    /// spectral bands per pixel (filled by [`TileSums::add_pixel_bands`]).
    pub fn with_bands(x0: u32, y0: u32, x1: u32, y1: u32, bands: usize) -> TileSums {
        let mut t = TileSums::new(x0, y0, x1, y1);
        t.bands = bands;
        t.band_sums = Vec::with_capacity(t.sums.capacity() * bands);
        t
    }

    /// Adds pixel (`x`, `y`), the tile's next in row-major order, from the
    /// samples `samples`: `sample(s, bands)` is what [`sample_xyz_bands`]
    /// makes of sample `s`, its band values written to `bands`.
    pub fn add_pixel_bands(
        &mut self,
        x: u32,
        y: u32,
        samples: std::ops::Range<u64>,
        mut sample: impl FnMut(u64, &mut [f64]) -> Result<[f64; 3], BadSample>,
    ) {
        let mut acc = [0i128; 3];
        let start = self.band_sums.len();
        self.band_sums.resize(start + self.bands, 0);
        let mut values = vec![0.0; self.bands];
        for s in samples {
            match sample(s, &mut values) {
                Ok(xyz) => {
                    let f = to_fixed(xyz);
                    for k in 0..3 {
                        acc[k] = acc[k].saturating_add(f[k]);
                    }
                    for (a, v) in self.band_sums[start..].iter_mut().zip(&values) {
                        *a = a.saturating_add(fixed_one(*v));
                    }
                }
                Err(why) => self.dropped.record(why, x, y, s),
            }
        }
        self.sums.push(acc);
    }

    /// Bands per pixel (0 without bands).
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The pixels' band sums so far, row-major, [`TileSums::bands`] per pixel.
    pub fn band_sums(&self) -> &[i128] {
        &self.band_sums
    }

    /// Adds pixel (`x`, `y`), the tile's next in row-major order, from its
    /// samples: (sample index, what [`sample_xyz`] made of it).
    #[inline]
    pub fn add_pixel(
        &mut self,
        x: u32,
        y: u32,
        samples: impl Iterator<Item = (u64, Result<[f64; 3], BadSample>)>,
    ) {
        debug_assert_eq!(
            (x, y),
            {
                let (w, i) = ((self.x1 - self.x0) as usize, self.sums.len());
                (self.x0 + (i % w) as u32, self.y0 + (i / w) as u32)
            },
            "pixels are added in row-major order"
        );
        let mut acc = [FixedSum::default(); 3];
        for (s, value) in samples {
            match value {
                Ok(xyz) => {
                    for k in 0..3 {
                        acc[k].add(xyz[k]);
                    }
                }
                Err(why) => self.dropped.record(why, x, y, s),
            }
        }
        // Not `acc.map`: it compiled to a drain loop of ≈ 160 instructions.
        self.sums
            .push([acc[0].total(), acc[1].total(), acc[2].total()]);
    }

    /// The pixels' sums so far, row-major.
    pub fn sums(&self) -> &[[i128; 3]] {
        &self.sums
    }

    /// The samples left out so far.
    pub fn dropped(&self) -> &Dropped {
        &self.dropped
    }

    /// Whether the tile is complete and lies inside a `width` × `height` image.
    pub(super) fn fits(&self, width: u32, height: u32) -> bool {
        self.x0 <= self.x1
            && self.y0 <= self.y1
            && self.x1 <= width
            && self.y1 <= height
            && self.sums.len() as u64 == (self.x1 - self.x0) as u64 * (self.y1 - self.y0) as u64
            && self.band_sums.len() == self.sums.len() * self.bands
    }
}

/// Converts one sample's XYZ to fixed point: `(v·2⁴⁰).round() as i128`,
/// 0 for non-finite `v`.
#[inline]
pub fn to_fixed(xyz: [f64; 3]) -> [i128; 3] {
    xyz.map(fixed_one)
}

/// `(v·2⁴⁰).round() as i128` without the libm `round` and the f64→i128
/// `__fixdfti` call for |v·2⁴⁰| < 2⁶³ (|v| < 8.4·10⁶, every sample a sane scene
/// produces): truncate to i64 (one instruction), and the fractional part
/// `w − trunc(w)` is exact in f64 (`trunc(w)` lies on `w`'s ulp grid and, below
/// 2⁶³, converts back without rounding: for |w| ≥ 2⁵² `w` is an integer), so
/// |frac| ≥ ½ → step away from zero reproduces `round`'s ties-away rule
/// exactly. Larger values take the general i128 path.
#[inline]
pub(super) fn fixed_one(v: f64) -> i128 {
    // The step as arithmetic on the comparisons (`fixed_small`), not as
    // branches: the fraction of a Monte Carlo sample is random, and the
    // branches were mispredicted about once per sample.
    match fixed_small(v) {
        Some(t) => i128::from(t),
        None if v.is_finite() => (v * SCALE).round() as i128,
        None => 0,
    }
}

/// A pixel channel's sum of [`fixed_one`] values, kept as an i64 part and an
/// i128 rest: the same integer as a sum of i128 saturating adds whenever
/// that sum does not saturate (past a million samples at
/// [`MAX_SAMPLE_XYZ`]; both are then clamped, this one possibly at another
/// sample). Why: three i128 saturating adds per camera sample; with an
/// i64 add and its overflow test instead, the 16-spp checker scene's render
/// loop takes 39 instructions fewer per camera sample (−1.7 %).
#[derive(Clone, Copy, Debug, Default)]
struct FixedSum {
    /// What did not fit `part`: values beyond i64 and overflowed parts.
    wide: i128,
    part: i64,
}

impl FixedSum {
    /// Adds `fixed_one(v)`.
    #[inline(always)]
    fn add(&mut self, v: f64) {
        if let Some(f) = fixed_small(v) {
            let (p, over) = self.part.overflowing_add(f);
            if !over {
                self.part = p;
                return;
            }
        }
        self.add_wide(v);
    }

    /// [`FixedSum::add`] of a value beyond i64 or one that overflows the
    /// part: out of line, so that the per-sample path stays two
    /// instructions.
    #[cold]
    #[inline(never)]
    fn add_wide(&mut self, v: f64) {
        let all = i128::from(self.part).saturating_add(fixed_one(v));
        self.wide = self.wide.saturating_add(all);
        self.part = 0;
    }

    /// The sum.
    #[inline]
    fn total(self) -> i128 {
        self.wide.saturating_add(i128::from(self.part))
    }
}

/// [`fixed_one`] of `v` where |v·2⁴⁰| < 2⁶³ (its i64 path); `None` elsewhere.
#[inline(always)]
fn fixed_small(v: f64) -> Option<i64> {
    const I64_RANGE: f64 = 9_223_372_036_854_775_808.0; // 2⁶³
    let w = v * SCALE;
    if w.abs() < I64_RANGE {
        let t = w as i64;
        let frac = w - t as f64;
        // See `fixed_one`; at |w| ≥ 2⁵² the fraction is 0, so t ± 1 stays
        // within i64.
        Some(t + i64::from(frac >= 0.5) - i64::from(frac <= -0.5))
    } else {
        None
    }
}

/// Why a camera sample was left out of the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BadSample {
    /// A wavelength's radiance estimate was NaN or infinite, or the
    /// sample's XYZ lies beyond [`MAX_SAMPLE_XYZ`].
    NonFinite,
    /// A wavelength's radiance estimate was negative (a model returned f < 0).
    Negative,
}

/// Where the first dropped sample was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DroppedAt {
    /// Pixel column.
    pub x: u32,
    /// Pixel row, from the top.
    pub y: u32,
    /// Sample index within the pixel.
    pub sample: u64,
}

/// Camera samples that were not averaged into the film because their
/// estimate was non-finite or negative. They count as black (the sample is
/// still part of the pixel's sample count), so a render with dropped samples
/// is biased dark there; the count says by how much at most.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Dropped {
    /// Samples with a NaN or infinite estimate.
    pub non_finite: u64,
    /// Samples with a negative estimate.
    pub negative: u64,
    /// The first dropped sample: lowest sample index, then row-major pixel order.
    pub first: Option<DroppedAt>,
}

impl Dropped {
    /// All dropped samples.
    pub fn total(&self) -> u64 {
        self.non_finite.saturating_add(self.negative)
    }

    /// Counts one dropped sample.
    pub fn record(&mut self, why: BadSample, x: u32, y: u32, sample: u64) {
        match why {
            BadSample::NonFinite => self.non_finite = self.non_finite.saturating_add(1),
            BadSample::Negative => self.negative = self.negative.saturating_add(1),
        }
        self.keep_first(DroppedAt { x, y, sample });
    }

    /// Adds another count (another tile, pass or film).
    pub fn add(&mut self, other: &Dropped) {
        self.non_finite = self.non_finite.saturating_add(other.non_finite);
        self.negative = self.negative.saturating_add(other.negative);
        if let Some(at) = other.first {
            self.keep_first(at);
        }
    }

    fn keep_first(&mut self, at: DroppedAt) {
        let key = |a: &DroppedAt| (a.sample, a.y, a.x);
        if self.first.is_none_or(|f| key(&at) < key(&f)) {
            self.first = Some(at);
        }
    }
}

impl fmt::Display for Dropped {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} sample(s) dropped ({} non-finite or beyond the film's range, {} negative)",
            self.total(),
            self.non_finite,
            self.negative
        )?;
        if let Some(a) = self.first {
            write!(f, ", first at pixel ({}, {}) sample {}", a.x, a.y, a.sample)?;
        }
        write!(
            f,
            "; they count as black, so the image is too dark where they fell"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_sums_are_the_i128_saturating_sums() {
        // Sequences of small values, values whose fixed point nearly fills
        // an i64 (two overflow the part), values beyond i64 and non-finite
        // ones, of both signs: the same integer as i128 saturating adds.
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let (mut overflows, mut wide) = (0, 0);
        for _ in 0..2_000 {
            let mut sum = FixedSum::default();
            let mut want = 0i128;
            let mut part = 0i64;
            for _ in 0..(next() % 300) {
                let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
                let mag = match next() % 8 {
                    0..=3 => u * 1e3,
                    4 | 5 => 8.0e6 + u * 0.38e6,
                    6 => 8.4e6 + u * 1e20,
                    _ => [f64::NAN, f64::INFINITY, 0.0, 1e-300][(next() % 4) as usize],
                };
                let v = if next() % 2 == 0 { mag } else { -mag };
                match fixed_small(v).map(|f| part.checked_add(f)) {
                    Some(Some(p)) => part = p,
                    Some(None) => (overflows, part) = (overflows + 1, 0),
                    None => wide += 1,
                }
                sum.add(v);
                want = want.saturating_add(fixed_one(v));
            }
            assert_eq!(sum.total(), want);
        }
        assert!(overflows > 1_000 && wide > 10_000, "{overflows} {wide}");
    }

    #[test]
    fn fast_fixed_point_matches_round_as_i128_bit_for_bit() {
        let reference = |v: f64| {
            if v.is_finite() {
                (v * SCALE).round() as i128
            } else {
                0
            }
        };
        let mut vals = vec![
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN_POSITIVE,
            1e300,
            -1e300,
        ];
        // Ties and their neighbours, at every scale up to and beyond 2⁶³.
        for e in -60..80 {
            for m in [0.5, 1.0, 1.5, 2.5, 0.49999999999999994, 3.0] {
                let w = m * 2f64.powi(e);
                for w in [w, w.next_up(), w.next_down()] {
                    let v = w / SCALE;
                    vals.extend([v, -v]);
                }
            }
        }
        // Random bit patterns of every exponent.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..200_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            vals.push(f64::from_bits(x));
            vals.push(f64::from_bits(x >> 3)); // biased toward small exponents
        }
        for v in vals {
            assert_eq!(fixed_one(v), reference(v), "v = {v:e}");
        }
    }
}
