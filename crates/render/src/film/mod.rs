//! The film: the colour of an image as per-pixel XYZ sums in fixed point, so
//! that films rendered over disjoint sample ranges add up *exactly* (integer
//! addition is associative) to the film of one render over the union — on
//! any machine, in any order.
//!
//! The film owns every step from a camera sample's spectral radiance to
//! colour: the CIE matching of each sampled wavelength and the fixed point
//! of one sample ([`sample`]), the sums of a tile and of a pass
//! ([`TileSums`], [`Film::add_pass`]), and the mean XYZ and linear sRGB of a
//! pixel ([`Film::xyz`], [`Film::rgb`]). Its `.film` file is [`mod@file`]'s.
//!
//! A film knows nothing of scenes: it is made from plain values (resolution,
//! the fingerprint of the inputs, seed, exposure, the input records).

pub mod bands;
pub mod file;
pub mod sample;

use crate::color::xyz_to_srgb;
use crate::inputs::{InputFile, describe_differences};
use crate::spectrum::Cie;
pub use bands::{BandLayout, MAX_BAND_SUMS, MAX_BANDS};
pub use file::MAX_FILM_BYTES;
use sample::SCALE;
pub use sample::{
    BadSample, CameraSample, Dropped, DroppedAt, MAX_SAMPLE_XYZ, SampleRadiance, TileSums,
    sample_xyz, sample_xyz_bands, to_fixed,
};
use std::fmt;
use std::ops::Range;

/// Largest |exposure| of a film (and of a scene's `[film] exposure`), in
/// stops: the gain 2^exposure must leave the f32 EXR and the PNG conversion
/// finite for any radiance a scene can reasonably produce.
pub const MAX_EXPOSURE_STOPS: f64 = 60.0;
/// Most samples per pixel, and the end of any sample range a film holds
/// (2⁴⁰, far beyond any render: a billion samples of one pixel take hours;
/// shards may still start past 2³²).
pub const MAX_SPP: u64 = 1 << 40;
/// Largest width or height of a film (and of a scene's `resolution`).
pub const MAX_SIDE: u32 = 1 << 15;
/// Largest pixel count of a film: 2²⁵ pixels (8K UHD, 7680 × 4320, fits)
/// hold 1.5 GiB of sums, and a render of them about 2.4 GiB at its peak
/// ([`crate::memory::PEAK_BYTES_PER_PIXEL`]).
pub const MAX_PIXELS: u64 = 1 << 25;
fn check_resolution(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "resolution {width}×{height} (expected 1..={MAX_SIDE} each)"
        ));
    }
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(format!("{width}×{height} is more than {MAX_PIXELS} pixels"));
    }
    Ok(())
}

fn check_exposure(stops: f64) -> Result<(), String> {
    let m = MAX_EXPOSURE_STOPS;
    if stops.is_finite() && stops.abs() <= m {
        Ok(())
    } else {
        Err(format!(
            "exposure {stops} is outside ±{m} stops (2^{m} already takes any sane pixel past \
             f32's range); give a value within it"
        ))
    }
}

/// Sample ranges as renders leave them: at least one, each non-empty, sorted,
/// disjoint, and ending by [`MAX_SPP`].
fn check_ranges(ranges: &[Range<u64>]) -> Result<(), String> {
    if ranges.is_empty() {
        return Err("no sample range: a render writes a film only once it holds samples".into());
    }
    for (i, r) in ranges.iter().enumerate() {
        if r.start >= r.end || (i > 0 && ranges[i - 1].end >= r.start) {
            return Err(format!(
                "sample range {}..{} is empty, unsorted or overlaps",
                r.start, r.end
            ));
        }
        if r.end > MAX_SPP {
            return Err(format!(
                "sample range {}..{} ends beyond sample {MAX_SPP}, the most a render takes",
                r.start, r.end
            ));
        }
    }
    Ok(())
}

/// The first dropped sample inside the image and present exactly when some
/// were dropped; no more dropped than were taken.
fn check_dropped(d: &Dropped, width: u32, height: u32, spp: u64) -> Result<(), String> {
    if let Some(a) = d.first
        && (a.x >= width || a.y >= height)
    {
        return Err(format!(
            "first dropped sample at pixel ({}, {}) outside {width}×{height}",
            a.x, a.y
        ));
    }
    if d.first.is_some() != (d.total() > 0) {
        return Err("dropped-sample counts and location disagree".into());
    }
    let taken = spp as u128 * width as u128 * height as u128;
    if d.non_finite as u128 + d.negative as u128 > taken {
        return Err(format!(
            "{} dropped samples of the {taken} taken",
            d.non_finite as u128 + d.negative as u128
        ));
    }
    Ok(())
}

/// Sums a render can produce: no component beyond `spp` samples at the
/// film's per-sample limit, and luminance Y never negative (a sample's Y is
/// non-negative, or the sample is dropped, except under a signed sky whose
/// negative part lies where Y's matching function is nearly zero).
fn check_sums(sums: &[[i128; 3]], width: u32, spp: u64) -> Result<(), String> {
    let bound = sample::MAX_SAMPLE_FIXED.saturating_mul(spp as i128);
    let bad = sums
        .iter()
        .position(|s| s[1] < 0 || s.iter().any(|v| v.unsigned_abs() > bound.unsigned_abs()));
    match bad {
        None => Ok(()),
        Some(i) => {
            let (x, y) = (i as u64 % width as u64, i as u64 / width as u64);
            Err(format!(
                "pixel ({x}, {y}) holds sums {:?}, which {spp} samples cannot produce \
                 (Y must be ≥ 0 and every component within {spp} × {MAX_SAMPLE_XYZ:e})",
                sums[i]
            ))
        }
    }
}

/// Band sums a render can produce: as [`check_sums`]'s bound for X and Z
/// (a band's value may be negative under a signed sky).
fn check_band_sums(band_sums: &[i128], bands: usize, width: u32, spp: u64) -> Result<(), String> {
    let bound = sample::MAX_SAMPLE_FIXED.saturating_mul(spp as i128);
    match band_sums
        .iter()
        .position(|v| v.unsigned_abs() > bound.unsigned_abs())
    {
        None => Ok(()),
        Some(k) => {
            let i = (k / bands) as u64;
            let (x, y) = (i % width as u64, i / width as u64);
            Err(format!(
                "pixel ({x}, {y}) band {} holds the sum {}, which {spp} samples cannot produce \
                 (every band within {spp} × {MAX_SAMPLE_XYZ:e})",
                k % bands,
                band_sums[k]
            ))
        }
    }
}

/// The number of band sums of a `width` × `height` film with `bands` bands,
/// or why it cannot hold them.
fn check_bands(width: u32, height: u32, bands: usize) -> Result<u64, String> {
    if bands > MAX_BANDS {
        return Err(format!("{bands} spectral bands (expected 0..={MAX_BANDS})"));
    }
    let n = width as u64 * height as u64 * bands as u64;
    if n > MAX_BAND_SUMS {
        return Err(format!(
            "{width}×{height} pixels × {bands} spectral bands is {n} band sums, more than a film \
             holds ({MAX_BAND_SUMS}, 2 GiB): use fewer bands or render the image in crops"
        ));
    }
    Ok(n)
}

/// Bytes per pixel: three i128 sums.
const PIXEL_BYTES: u128 = 48;

/// Accumulated samples of one image.
///
/// The fields carry invariants (sums of exactly width × height pixels,
/// sorted disjoint sample ranges, a fingerprint that says which scene the
/// sums belong to), so they are private: a film is made empty
/// ([`Film::new`]), filled by the renderer ([`Film::add_pass`]), combined
/// with [`Film::merge`] / [`Film::resume`], read from a `.film`, or
/// assembled from checked [`FilmParts`].
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    p: FilmParts,
}

/// A film's contents as plain data, for tools that build or inspect films
/// field by field; [`Film::from_parts`] checks them.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmParts {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Scene fingerprint the samples belong to.
    pub fingerprint: u64,
    /// Seed the samples were drawn with.
    pub seed: u64,
    /// Exposure (stops) applied when writing images.
    pub exposure: f64,
    /// The files the scene was built from (names the file that changed when
    /// two films, or a film and a scene, disagree).
    pub inputs: Vec<InputFile>,
    /// Samples left out because their estimate was non-finite or negative.
    pub dropped: Dropped,
    /// Sample-index ranges accumulated: non-empty, sorted, with gaps between.
    pub ranges: Vec<Range<u64>>,
    /// Fixed-point X, Y, Z sums per pixel (see [`to_fixed`]), row-major from the top.
    pub sums: Vec<[i128; 3]>,
    /// Spectral bands per pixel over 360–830 nm (0: none; see [`bands`]).
    pub bands: usize,
    /// Fixed-point band sums, `bands` per pixel, pixels row-major from the
    /// top (empty without bands).
    pub band_sums: Vec<i128>,
}

/// Why a checkpoint cannot be resumed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ResumeError {
    /// It holds samples of another render (resolution, seed or inputs differ).
    Incompatible(String),
    /// It holds samples that are not one prefix of the requested range.
    NotAPrefix {
        /// The ranges the checkpoint holds.
        held: Vec<Range<u64>>,
        /// The range the render asks for.
        target: Range<u64>,
    },
}

impl fmt::Display for ResumeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ResumeError::Incompatible(why) => {
                write!(f, "the checkpoint does not belong to this render: {why}")
            }
            ResumeError::NotAPrefix { held, target } => write!(
                f,
                "holds samples {held:?}, not a prefix of {}..{}",
                target.start, target.end
            ),
        }
    }
}

impl std::error::Error for ResumeError {}

impl Film {
    /// An empty film. The resolution must be within [`MAX_SIDE`] and
    /// [`MAX_PIXELS`], the exposure within [`MAX_EXPOSURE_STOPS`]; memory the
    /// sums cannot get is an error with the number of bytes, not an abort.
    pub fn new(
        width: u32,
        height: u32,
        fingerprint: u64,
        seed: u64,
        exposure: f64,
    ) -> Result<Film, String> {
        check_resolution(width, height)?;
        check_exposure(exposure)?;
        let pixels = width as usize * height as usize;
        let mut sums = Vec::new();
        sums.try_reserve_exact(pixels).map_err(|_| {
            format!(
                "cannot allocate the film's {} MiB of sums for {width}×{height} pixels: lower \
                 the resolution",
                (pixels as u128 * PIXEL_BYTES) >> 20
            )
        })?;
        sums.resize(pixels, [0; 3]);
        Ok(Film {
            p: FilmParts {
                width,
                height,
                fingerprint,
                seed,
                exposure,
                inputs: Vec::new(),
                dropped: Dropped::default(),
                ranges: Vec::new(),
                sums,
                bands: 0,
                band_sums: Vec::new(),
            },
        })
    }

    /// The film with `bands` spectral bands (0: none) of zero sums; the
    /// band count must be within [`MAX_BANDS`] and the sums within
    /// [`MAX_BAND_SUMS`], and memory the sums cannot get is an error.
    pub fn with_bands(mut self, bands: usize) -> Result<Film, String> {
        let n = check_bands(self.p.width, self.p.height, bands)? as usize;
        let mut sums = Vec::new();
        sums.try_reserve_exact(n).map_err(|_| {
            format!(
                "cannot allocate the film's {} MiB of band sums for {}×{} pixels × {bands} \
                 bands: use fewer bands",
                (n as u128 * 16) >> 20,
                self.p.width,
                self.p.height
            )
        })?;
        sums.resize(n, 0);
        self.p.bands = bands;
        self.p.band_sums = sums;
        Ok(self)
    }

    /// The film with `inputs` recorded as the files its scene was built from.
    pub fn with_inputs(mut self, inputs: Vec<InputFile>) -> Film {
        self.p.inputs = inputs;
        self
    }

    /// A film from its parts, checked as a `.film` file is: resolution
    /// within [`MAX_SIDE`] / [`MAX_PIXELS`], one sum per pixel, finite
    /// exposure, ranges non-empty, sorted and disjoint, the first dropped
    /// sample inside the image and present exactly when some were dropped.
    pub fn from_parts(p: FilmParts) -> Result<Film, String> {
        check_resolution(p.width, p.height)?;
        let pixels = p.width as u64 * p.height as u64;
        if p.sums.len() as u64 != pixels {
            return Err(format!(
                "{} pixel sums for {}×{} pixels",
                p.sums.len(),
                p.width,
                p.height
            ));
        }
        check_exposure(p.exposure)?;
        check_ranges(&p.ranges)?;
        let spp: u64 = p.ranges.iter().map(|r| r.end - r.start).sum();
        check_dropped(&p.dropped, p.width, p.height, spp)?;
        check_sums(&p.sums, p.width, spp)?;
        let n_bands = check_bands(p.width, p.height, p.bands)?;
        if p.band_sums.len() as u64 != n_bands {
            return Err(format!(
                "{} band sums for {}×{} pixels × {} bands",
                p.band_sums.len(),
                p.width,
                p.height,
                p.bands
            ));
        }
        check_band_sums(&p.band_sums, p.bands, p.width, spp)?;
        Ok(Film { p })
    }

    /// Adds a complete pass: samples `pass` of every pixel, in `tiles` that
    /// cover the image once. Returns the samples the pass left out (also
    /// added to the film's count). On error (tiles that do not fit the
    /// image, a range that overlaps the film's) the film is unchanged.
    pub fn add_pass(&mut self, pass: Range<u64>, tiles: &[TileSums]) -> Result<Dropped, String> {
        let (w, h) = (self.p.width, self.p.height);
        let bands = self.p.bands;
        if let Some(t) = tiles.iter().find(|t| !t.fits(w, h) || t.bands() != bands) {
            return Err(format!(
                "tile {}..{} × {}..{} with {} bands does not fit the {w}×{h} film with {bands}",
                t.x0,
                t.x1,
                t.y0,
                t.y1,
                t.bands()
            ));
        }
        self.add_range(pass)?;
        let mut dropped = Dropped::default();
        for t in tiles {
            dropped.add(t.dropped());
            let mut k = 0;
            for y in t.y0..t.y1 {
                for x in t.x0..t.x1 {
                    let px = &mut self.p.sums[(y * w + x) as usize];
                    for (p, v) in px.iter_mut().zip(&t.sums()[k]) {
                        *p = p.saturating_add(*v);
                    }
                    if bands > 0 {
                        let at = (y * w + x) as usize * bands;
                        let film = &mut self.p.band_sums[at..at + bands];
                        for (p, v) in film.iter_mut().zip(&t.band_sums()[k * bands..]) {
                            *p = p.saturating_add(*v);
                        }
                    }
                    k += 1;
                }
            }
        }
        self.p.dropped.add(&dropped);
        Ok(dropped)
    }

    /// The film's contents as plain data.
    pub fn into_parts(self) -> FilmParts {
        self.p
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.p.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.p.height
    }

    /// Fingerprint of the scene the samples belong to.
    pub fn fingerprint(&self) -> u64 {
        self.p.fingerprint
    }

    /// Seed the samples were drawn with.
    pub fn seed(&self) -> u64 {
        self.p.seed
    }

    /// Exposure (stops) applied when writing images.
    pub fn exposure(&self) -> f64 {
        self.p.exposure
    }

    /// Sets the exposure used by [`Film::rgb`] (it does not change the
    /// samples, so it is no part of a film's identity); non-finite values
    /// are refused.
    pub fn set_exposure(&mut self, stops: f64) -> Result<(), String> {
        check_exposure(stops)?;
        self.p.exposure = stops;
        Ok(())
    }

    /// The files the scene was built from.
    pub fn inputs(&self) -> &[InputFile] {
        &self.p.inputs
    }

    /// Samples left out of the sums.
    pub fn dropped(&self) -> &Dropped {
        &self.p.dropped
    }

    /// Sample-index ranges accumulated, sorted and disjoint.
    pub fn ranges(&self) -> &[Range<u64>] {
        &self.p.ranges
    }

    /// Fixed-point X, Y, Z sums per pixel, row-major from the top.
    pub fn sums(&self) -> &[[i128; 3]] {
        &self.p.sums
    }

    /// Spectral bands per pixel (0: none).
    pub fn bands(&self) -> usize {
        self.p.bands
    }

    /// How the bands divide 360–830 nm (`None` without bands).
    pub fn band_layout(&self) -> Option<BandLayout> {
        BandLayout::new(self.p.bands).ok()
    }

    /// Fixed-point band sums, [`Film::bands`] per pixel, row-major from the top.
    pub fn band_sums(&self) -> &[i128] {
        &self.p.band_sums
    }

    /// The mean spectral radiance of every band of every pixel, band by
    /// band within a pixel, pixels row-major (see [`bands`] for the unit):
    /// the band sums / (2⁴⁰ · spp). No exposure is applied: the bands are
    /// for comparing with measurements.
    pub fn band_means(&self) -> Vec<f64> {
        let n = self.spp();
        if n == 0 {
            return vec![0.0; self.p.band_sums.len()];
        }
        let k = 1.0 / (SCALE * n as f64);
        self.p.band_sums.iter().map(|&s| s as f64 * k).collect()
    }

    /// Total samples per pixel accumulated.
    pub fn spp(&self) -> u64 {
        self.p
            .ranges
            .iter()
            .fold(0u64, |a, r| a.saturating_add(r.end - r.start))
    }

    /// Records that samples `r` have been added; errors if they overlap.
    pub fn add_range(&mut self, r: Range<u64>) -> Result<(), String> {
        self.p.ranges = with_range(&self.p.ranges, r)?;
        Ok(())
    }

    /// Mean XYZ of pixel `i`, normalised so that a unit constant spectrum has Y = 1.
    pub fn xyz(&self, i: usize) -> [f64; 3] {
        let n = self.spp();
        if n == 0 {
            return [0.0; 3];
        }
        let k = 1.0 / (SCALE * n as f64 * Cie::get().y_integral());
        self.p.sums[i].map(|s| s as f64 * k)
    }

    /// Linear sRGB of every pixel with the exposure applied.
    pub fn rgb(&self) -> Vec<[f32; 3]> {
        let gain = self.p.exposure.exp2();
        (0..self.p.sums.len())
            .map(|i| xyz_to_srgb(self.xyz(i)).map(|v| (v * gain) as f32))
            .collect()
    }

    /// Whether `other` holds samples of the same render as this film: same
    /// resolution, seed and fingerprint. The error names the input files
    /// that differ when the fingerprints do, as changes from this film's
    /// inputs ("then") to `other`'s ("now").
    pub fn compatible_with(&self, other: &Film) -> Result<(), String> {
        if (self.p.width, self.p.height) != (other.p.width, other.p.height) {
            return Err(format!(
                "resolution {}×{} differs from {}×{}",
                other.p.width, other.p.height, self.p.width, self.p.height
            ));
        }
        // Before the fingerprint: a film with bands samples λ at every
        // bounce, so its samples are another estimator's, and the band
        // count is the clearer reason.
        if self.p.bands != other.p.bands {
            return Err(format!(
                "{} spectral bands differ from {} (`--spectral` / `spectral_bands` must agree)",
                other.p.bands, self.p.bands
            ));
        }
        if self.p.fingerprint != other.p.fingerprint {
            let diff = describe_differences(&other.p.inputs, &self.p.inputs);
            return Err(if diff.is_empty() {
                "rendered from a different scene or by a different lustre version \
                 (fingerprints differ, input files agree)"
                    .into()
            } else {
                format!("rendered from different inputs: {}", diff.join("; "))
            });
        }
        if self.p.seed != other.p.seed {
            return Err(format!(
                "seed {} differs from {}",
                other.p.seed, self.p.seed
            ));
        }
        Ok(())
    }

    /// Adds another film's samples; both must come from the same scene and
    /// seed and hold disjoint sample ranges (a duplicated shard would count
    /// its samples twice). On error the film is unchanged.
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        self.compatible_with(other)?;
        let mut ranges = self.p.ranges.clone();
        for r in &other.p.ranges {
            ranges = with_range(&ranges, r.clone())?;
        }
        let overflow = (self.p.sums.iter().zip(&other.p.sums))
            .position(|(a, b)| (0..3).any(|k| a[k].checked_add(b[k]).is_none()));
        let band_overflow = (self.p.band_sums.iter().zip(&other.p.band_sums))
            .position(|(a, b)| a.checked_add(*b).is_none())
            .map(|k| k / self.p.bands.max(1));
        if let Some(i) = overflow.or(band_overflow) {
            let w = self.p.width as usize;
            return Err(format!(
                "the sums of pixel ({}, {}) overflow when added",
                i % w,
                i / w
            ));
        }
        for (a, b) in self.p.sums.iter_mut().zip(&other.p.sums) {
            for k in 0..3 {
                a[k] += b[k];
            }
        }
        for (a, b) in self.p.band_sums.iter_mut().zip(&other.p.band_sums) {
            *a += b;
        }
        self.p.ranges = ranges;
        self.p.dropped.add(&other.p.dropped);
        Ok(())
    }

    /// Continues from `checkpoint`, a film of the same render holding one
    /// prefix of `target` (what an interrupted render of `target` leaves):
    /// adopts its samples and returns the sample range still to render
    /// (empty when the checkpoint already covers `target`). On error this
    /// film is unchanged.
    pub fn resume(
        &mut self,
        checkpoint: Film,
        target: Range<u64>,
    ) -> Result<Range<u64>, ResumeError> {
        checkpoint
            .compatible_with(self)
            .map_err(ResumeError::Incompatible)?;
        let done_end = match checkpoint.p.ranges.as_slice() {
            [done] if done.start == target.start => done.end,
            _ => {
                return Err(ResumeError::NotAPrefix {
                    held: checkpoint.p.ranges,
                    target,
                });
            }
        };
        let todo = done_end.min(target.end)..target.end;
        self.p.ranges = checkpoint.p.ranges;
        self.p.sums = checkpoint.p.sums;
        self.p.band_sums = checkpoint.p.band_sums;
        self.p.dropped = checkpoint.p.dropped;
        Ok(todo)
    }
}

/// `ranges` (sorted, disjoint) with `r` added and adjacent ranges joined;
/// an error if `r` overlaps one of them.
fn with_range(ranges: &[Range<u64>], r: Range<u64>) -> Result<Vec<Range<u64>>, String> {
    if r.start > r.end {
        return Err(format!("invalid sample range {}..{}", r.start, r.end));
    }
    if r.is_empty() {
        return Ok(ranges.to_vec());
    }
    if let Some(o) = ranges.iter().find(|o| o.start < r.end && r.start < o.end) {
        return Err(format!(
            "sample range {}..{} overlaps {}..{} already in the film \
             (a duplicated or overlapping shard would count samples twice)",
            r.start, r.end, o.start, o.end
        ));
    }
    let mut all: Vec<Range<u64>> = ranges.to_vec();
    all.push(r);
    all.sort_by_key(|r| r.start);
    let mut merged: Vec<Range<u64>> = Vec::with_capacity(all.len());
    for r in all {
        match merged.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => merged.push(r),
        }
    }
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_range_bookkeeping() {
        let mut f = Film::new(3, 2, 42, 7, 0.5).unwrap();
        f.p.sums[4] = [1, 2, 3];
        f.add_range(0..4).unwrap();
        f.add_range(8..10).unwrap();
        f.add_range(4..8).unwrap();
        assert_eq!(f.p.ranges, vec![0..10]);
        assert!(f.add_range(9..12).is_err());
        let g = Film::from_bytes(&f.to_bytes()).unwrap();
        assert_eq!(f, g);
        assert!(Film::from_bytes(&f.to_bytes()[..50]).is_err());
        assert!(Film::from_bytes(b"nonsense").is_err());
    }

    #[test]
    fn exposure_is_bounded_as_in_a_scene() {
        // Beyond ±60 stops a sane pixel leaves f32's range (an exposure of
        // 200 would write infinite pixels).
        let mut f = Film::new(1, 1, 1, 0, 0.0).unwrap();
        for bad in [61.0, -200.0, f64::INFINITY, f64::NAN] {
            assert!(f.set_exposure(bad).is_err(), "{bad}");
        }
        for good in [60.0, -60.0, 0.0, 2.5] {
            f.set_exposure(good).unwrap();
        }
    }

    #[test]
    fn merge_checks_compatibility() {
        let mut a = Film::new(2, 2, 1, 0, 0.0).unwrap();
        a.add_range(0..5).unwrap();
        let mut b = a.clone();
        b.p.ranges.clear();
        b.add_range(5..9).unwrap();
        b.p.sums[0] = [3, 3, 3];
        a.merge(&b).unwrap();
        assert_eq!(a.spp(), 9);
        assert_eq!(a.p.sums[0], [3, 3, 3]);
        let c = Film::new(2, 2, 2, 0, 0.0).unwrap();
        assert!(a.merge(&c).unwrap_err().contains("different scene"));
        let before = a.clone();
        assert!(a.merge(&b).unwrap_err().contains("overlaps"));
        assert_eq!(a, before, "a refused merge leaves the film unchanged");
        // A shard holding new samples and a duplicate is refused as a whole.
        let mut d = b.clone();
        d.p.ranges = vec![0..2, 20..30];
        assert!(a.merge(&d).is_err());
        assert_eq!(a, before);
    }

    #[test]
    fn differing_inputs_are_named_and_dropped_counts_travel() {
        let file = |name: &str, hash| InputFile {
            name: name.into(),
            len: 10,
            hash,
        };
        let mut a = Film::new(2, 1, 1, 0, 0.0).unwrap();
        a.p.inputs = vec![file("scene.toml", 1), file("fit.toml", 2)];
        a.add_range(0..4).unwrap();
        a.p.dropped.record(BadSample::Negative, 1, 0, 3);
        a.p.dropped.record(BadSample::NonFinite, 0, 0, 2);
        let mut b = Film::new(2, 1, 9, 0, 0.0).unwrap();
        b.p.inputs = vec![file("scene.toml", 1), file("fit.toml", 5)];
        let e = a.merge(&b).unwrap_err();
        assert!(e.contains("`fit.toml` changed"), "{e}");
        assert!(!e.contains("scene.toml"), "{e}");

        let g = Film::from_bytes(&a.to_bytes()).unwrap();
        assert_eq!(g, a);
        assert_eq!(g.p.dropped.total(), 2);
        assert_eq!(
            g.p.dropped.first,
            Some(DroppedAt {
                x: 0,
                y: 0,
                sample: 2
            })
        );
        let mut c = a.clone();
        c.p.ranges.clear();
        c.add_range(4..8).unwrap();
        c.p.dropped = Dropped::default();
        c.p.dropped.record(BadSample::Negative, 1, 0, 1);
        a.merge(&c).unwrap();
        assert_eq!((a.p.dropped.non_finite, a.p.dropped.negative), (1, 2));
        assert_eq!(a.p.dropped.first.unwrap().sample, 1);
        let msg = a.p.dropped.to_string();
        assert!(
            msg.starts_with(
                "3 sample(s) dropped (1 non-finite or beyond the film's range, 2 negative), first at pixel (1, 0) sample 1"
            ),
            "{msg}"
        );
    }
}
