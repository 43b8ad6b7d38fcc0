//! The film: per-pixel XYZ sums in fixed point, so that films rendered over
//! disjoint sample ranges add up *exactly* (integer addition is associative)
//! to the film of one render over the union — on any machine, in any order.
//!
//! A sample's XYZ is rounded to a multiple of 2⁻⁴⁰ (≈ 9·10⁻¹³) and summed in
//! i128, leaving 2⁸⁷ of head-room: quantisation is 10⁻⁹ of a unit radiance,
//! far below Monte Carlo noise, and overflow needs ~10²⁶ in one pixel.
//!
//! File format 2 (`.film`, little endian): magic `LUSTREFILM2\n`; u32 width,
//! u32 height; u64 scene fingerprint; u64 seed; f64 exposure; the dropped
//! samples (u64 non-finite, u64 negative, u64 first sample index, u32 x,
//! u32 y of the first; all-ones when none); u32 input count and per input
//! file (u32 name length, the UTF-8 name, u64 length, u64 hash); u32 range
//! count and that many (u64 start, u64 end) sample ranges, sorted and
//! disjoint; width·height·3 i128 sums (X, Y, Z per pixel, row-major from
//! the top); and last a CRC-32 of everything before it.
//!
//! Reading trusts nothing: the checksum is verified first, then every count
//! and length is checked against the bytes that remain before anything is
//! allocated, so a corrupt or crafted film is an error naming the file,
//! never a panic or an attempt to allocate what the header claims.

use crate::color::xyz_to_srgb;
use crate::error::RenderError;
use crate::scene::inputs::{InputFile, describe_differences};
use crate::spectrum::Cie;
use std::fmt;
use std::ops::Range;
use std::path::Path;

const MAGIC: &[u8; 12] = b"LUSTREFILM2\n";
const MAGIC_V1: &[u8; 12] = b"LUSTREFILM1\n";
const SCALE: f64 = (1u64 << 40) as f64;
/// Largest |X|, |Y| or |Z| of one camera sample the film adds: 10²⁰ · 2⁴⁰ is
/// 1.1·10³², so the i128 sums (up to 1.7·10³⁸) hold a million such samples
/// per pixel. A larger estimate (lights of radiance ~10²⁴ and up) is dropped
/// and counted, where it used to saturate the fixed-point conversion and
/// give every lit pixel the same value without a word.
pub const MAX_SAMPLE_XYZ: f64 = 1e20;
/// Largest |exposure| of a film (and of a scene's `[film] exposure`), in
/// stops: the gain 2^exposure must leave the f32 EXR and the PNG conversion
/// finite for any radiance a scene can reasonably produce.
pub const MAX_EXPOSURE_STOPS: f64 = 60.0;
/// Most samples per pixel, and the end of any sample range a film holds
/// (2⁴⁰, far beyond any render: a billion samples of one pixel take hours;
/// shards may still start past 2³²).
pub const MAX_SPP: u64 = 1 << 40;
/// [`MAX_SAMPLE_XYZ`] in the film's fixed point: no pixel sum exceeds the
/// pixel's sample count times this.
const MAX_SAMPLE_FIXED: i128 = (MAX_SAMPLE_XYZ * SCALE) as i128;
/// Largest width or height of a film (and of a scene's `resolution`).
pub const MAX_SIDE: u32 = 1 << 15;
/// Largest pixel count of a film: 2²⁵ pixels (8K UHD, 7680 × 4320, fits)
/// hold 1.5 GiB of sums, and a render of them about 2.4 GiB at its peak
/// ([`crate::memory::PEAK_BYTES_PER_PIXEL`]).
pub const MAX_PIXELS: u64 = 1 << 25;
/// Most input files a film records.
const MAX_INPUTS: usize = 1 << 16;
/// Longest recorded input name, bytes.
const MAX_NAME: usize = 4096;
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
    let bound = MAX_SAMPLE_FIXED.saturating_mul(spp as i128);
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

/// A writer that passes bytes on and keeps their CRC-32.
struct Crc32Writer<'a> {
    inner: &'a mut dyn std::io::Write,
    crc: crc32fast::Hasher,
}

impl Crc32Writer<'_> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.crc.update(bytes);
        self.inner.write_all(bytes)
    }
}

/// Bytes per pixel: three i128 sums.
const PIXEL_BYTES: u128 = 48;
/// Largest film file read: the sums of [`MAX_PIXELS`] pixels and room for the
/// largest input and range records.
pub const MAX_FILM_BYTES: u64 = MAX_PIXELS * PIXEL_BYTES as u64 + (1 << 30);

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

/// Accumulated samples of one image.
///
/// The fields carry invariants (sums of exactly width × height pixels,
/// sorted disjoint sample ranges, a fingerprint that says which scene the
/// sums belong to), so they are private: a film is made empty
/// ([`Film::new`], [`Film::for_scene`]), filled by the renderer, combined
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
/// exactly. Larger values take the original i128 path.
#[inline]
fn fixed_one(v: f64) -> i128 {
    const I64_RANGE: f64 = 9_223_372_036_854_775_808.0; // 2⁶³
    let w = v * SCALE;
    if w.abs() < I64_RANGE {
        let t = w as i64;
        let frac = w - t as f64;
        let r = if frac >= 0.5 {
            t + 1
        } else if frac <= -0.5 {
            t - 1
        } else {
            t
        };
        r as i128
    } else if v.is_finite() {
        w.round() as i128
    } else {
        0
    }
}

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
            },
        })
    }

    /// An empty film for `scene` (its resolution, fingerprint, inputs,
    /// seed and exposure).
    pub fn for_scene(scene: &crate::Scene) -> Result<Film, String> {
        Ok(Film::new(
            scene.camera.width,
            scene.camera.height,
            scene.fingerprint,
            scene.settings.seed,
            scene.settings.exposure,
        )?
        .with_inputs(scene.inputs.clone()))
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
        Ok(Film { p })
    }

    /// Mutable sums and dropped counts, for the render loop (which keeps
    /// the invariants: it adds to existing pixels and records ranges with
    /// [`Film::add_range`]).
    pub(crate) fn accumulators(&mut self) -> (&mut [[i128; 3]], &mut Dropped) {
        (&mut self.p.sums, &mut self.p.dropped)
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
        if let Some(i) = overflow {
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
        self.p.dropped = checkpoint.p.dropped;
        Ok(todo)
    }

    /// Serialises the film.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(128 + self.p.sums.len() * 48);
        self.write_to(&mut out)
            .expect("writing to memory cannot fail");
        out
    }

    /// Writes the film's bytes (those of [`Film::to_bytes`]) to `w` as they
    /// are made, with the checksum computed on the way.
    pub fn write_to(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut out = Crc32Writer {
            inner: w,
            crc: crc32fast::Hasher::new(),
        };
        out.put(MAGIC)?;
        out.put(&self.p.width.to_le_bytes())?;
        out.put(&self.p.height.to_le_bytes())?;
        out.put(&self.p.fingerprint.to_le_bytes())?;
        out.put(&self.p.seed.to_le_bytes())?;
        out.put(&self.p.exposure.to_le_bytes())?;
        out.put(&self.p.dropped.non_finite.to_le_bytes())?;
        out.put(&self.p.dropped.negative.to_le_bytes())?;
        let first = self.p.dropped.first.unwrap_or(DroppedAt {
            x: u32::MAX,
            y: u32::MAX,
            sample: u64::MAX,
        });
        out.put(&first.sample.to_le_bytes())?;
        out.put(&first.x.to_le_bytes())?;
        out.put(&first.y.to_le_bytes())?;
        let inputs = &self.p.inputs[..self.p.inputs.len().min(MAX_INPUTS)];
        out.put(&(inputs.len() as u32).to_le_bytes())?;
        for f in inputs {
            let mut end = f.name.len().min(MAX_NAME);
            // Keep a valid UTF-8 prefix.
            while !f.name.is_char_boundary(end) {
                end -= 1;
            }
            out.put(&(end as u32).to_le_bytes())?;
            out.put(&f.name.as_bytes()[..end])?;
            out.put(&f.len.to_le_bytes())?;
            out.put(&f.hash.to_le_bytes())?;
        }
        out.put(&(self.p.ranges.len() as u32).to_le_bytes())?;
        for r in &self.p.ranges {
            out.put(&r.start.to_le_bytes())?;
            out.put(&r.end.to_le_bytes())?;
        }
        for s in &self.p.sums {
            for v in s {
                out.put(&v.to_le_bytes())?;
            }
        }
        let crc = out.crc.finalize();
        out.inner.write_all(&crc.to_le_bytes())
    }

    /// Parses a film, checking its checksum and every length before
    /// allocating.
    pub fn from_bytes(bytes: &[u8]) -> Result<Film, String> {
        const NOT_A_FILM: &str =
            "not a lustre film (bad magic); films are the `.film` files written by `lustre render`";
        let Some(magic) = bytes.get(..12) else {
            return Err(format!("{NOT_A_FILM} (only {} bytes)", bytes.len()));
        };
        if magic == MAGIC_V1 {
            return Err(
                "a film of format 1, written by an older lustre (no checksum, no input record): \
                 render it again with this version"
                    .into(),
            );
        }
        if magic != MAGIC {
            return Err(NOT_A_FILM.into());
        }
        let Some(body_len) = bytes.len().checked_sub(4).filter(|&n| n >= 12) else {
            return Err("truncated film: no checksum".into());
        };
        let (body, tail) = bytes.split_at(body_len);
        let stored = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]);
        let actual = crc32fast::hash(body);
        if stored != actual {
            return Err(format!(
                "corrupt film: checksum mismatch (stored {stored:08x}, computed {actual:08x}); \
                 the file was truncated or modified after lustre wrote it"
            ));
        }
        let mut r = Reader { b: body, at: 12 };
        let width = u32::from_le_bytes(r.array()?);
        let height = u32::from_le_bytes(r.array()?);
        check_resolution(width, height).map_err(|m| format!("corrupt film: {m}"))?;
        let pixels = width as u64 * height as u64;
        let fingerprint = u64::from_le_bytes(r.array()?);
        let seed = u64::from_le_bytes(r.array()?);
        let exposure = f64::from_le_bytes(r.array()?);
        let non_finite = u64::from_le_bytes(r.array()?);
        let negative = u64::from_le_bytes(r.array()?);
        let first_sample = u64::from_le_bytes(r.array()?);
        let first_x = u32::from_le_bytes(r.array()?);
        let first_y = u32::from_le_bytes(r.array()?);
        let first = (first_sample != u64::MAX || first_x != u32::MAX || first_y != u32::MAX)
            .then_some(DroppedAt {
                x: first_x,
                y: first_y,
                sample: first_sample,
            });
        let n_inputs = u32::from_le_bytes(r.array()?) as usize;
        // Each input takes at least 20 bytes.
        if n_inputs > MAX_INPUTS || n_inputs.saturating_mul(20) > r.remaining() {
            return Err(format!(
                "corrupt film: {n_inputs} input records do not fit in the file"
            ));
        }
        let mut inputs = Vec::with_capacity(n_inputs);
        for _ in 0..n_inputs {
            let n = u32::from_le_bytes(r.array()?) as usize;
            if n > MAX_NAME {
                return Err(format!("corrupt film: input name of {n} bytes"));
            }
            let name = std::str::from_utf8(r.take(n)?)
                .map_err(|_| "corrupt film: input name is not UTF-8".to_string())?
                .to_string();
            let len = u64::from_le_bytes(r.array()?);
            let hash = u64::from_le_bytes(r.array()?);
            inputs.push(InputFile { name, len, hash });
        }
        let n_ranges = u32::from_le_bytes(r.array()?) as usize;
        if n_ranges.saturating_mul(16) > r.remaining() {
            return Err(format!(
                "corrupt film: {n_ranges} sample ranges do not fit in the file"
            ));
        }
        let mut ranges: Vec<Range<u64>> = Vec::with_capacity(n_ranges);
        for _ in 0..n_ranges {
            let a = u64::from_le_bytes(r.array()?);
            let b = u64::from_le_bytes(r.array()?);
            ranges.push(a..b);
        }
        let want = pixels as u128 * PIXEL_BYTES;
        if r.remaining() as u128 != want {
            return Err(format!(
                "corrupt film: {} bytes of sums for {width}×{height} pixels (expected {want})",
                r.remaining()
            ));
        }
        let mut sums = Vec::with_capacity(pixels as usize);
        for _ in 0..pixels {
            let mut px = [0i128; 3];
            for v in px.iter_mut() {
                *v = i128::from_le_bytes(r.array()?);
            }
            sums.push(px);
        }
        Film::from_parts(FilmParts {
            width,
            height,
            fingerprint,
            seed,
            exposure,
            inputs,
            dropped: Dropped {
                non_finite,
                negative,
                first,
            },
            ranges,
            sums,
        })
        .map_err(|m| format!("corrupt film: {m}"))
    }

    /// Writes the film atomically.
    pub fn save(&self, path: &Path) -> Result<(), RenderError> {
        safe_io::create_parent(path).map_err(|e| RenderError::io(&e.path, e.source))?;
        safe_io::write_atomic_with(path, &mut |w| self.write_to(w))
            .map_err(|e| RenderError::io(path, e.source))
    }

    /// Reads a film file as an input (a shard to merge: no output of this
    /// process may replace it); a corrupt film is an error naming the file.
    pub fn load(path: &Path) -> Result<Film, RenderError> {
        Film::read(path, safe_io::read_input)
    }

    /// Reads the checkpoint a render resumes, which it goes on writing.
    pub fn load_checkpoint(path: &Path) -> Result<Film, RenderError> {
        Film::read(path, safe_io::read_regular)
    }

    fn read(
        path: &Path,
        read: fn(&Path, &str, u64) -> Result<Vec<u8>, safe_io::ReadError>,
    ) -> Result<Film, RenderError> {
        let bytes = read(path, "film", MAX_FILM_BYTES).map_err(|e| RenderError::Film {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Film::from_bytes(&bytes).map_err(|message| RenderError::Film {
            path: path.to_path_buf(),
            message,
        })
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

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn remaining(&self) -> usize {
        self.b.len() - self.at
    }
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).ok_or("truncated film file")?;
        let s = self.b.get(self.at..end).ok_or("truncated film file")?;
        self.at = end;
        Ok(s)
    }
    fn array<const K: usize>(&mut self) -> Result<[u8; K], String> {
        let s = self.take(K)?;
        let mut a = [0u8; K];
        a.copy_from_slice(s);
        Ok(a)
    }
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
        // `lustre merge --exposure 200` wrote infinite pixels.
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
