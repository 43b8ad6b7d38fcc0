//! The `.film` file: a film's sums with everything needed to merge or
//! resume it.
//!
//! Format 2 (little endian): magic `LUSTREFILM2\n`; u32 width, u32 height;
//! u64 scene fingerprint; u64 seed; f64 exposure; the dropped samples (u64
//! non-finite, u64 negative, u64 first sample index, u32 x, u32 y of the
//! first; all-ones when none); u32 input count and per input file (u32 name
//! length, the UTF-8 name, u64 length, u64 hash); u32 range count and that
//! many (u64 start, u64 end) sample ranges, sorted and disjoint;
//! width·height·3 i128 sums (X, Y, Z per pixel, row-major from the top); and
//! last a CRC-32 of everything before it.
//!
//! Format 3 is written by films with spectral bands ([`super::bands`]) and
//! differs from format 2 only in its magic `LUSTREFILM3\n`, a u32 band count
//! N (1..=256) after the sample ranges, and N i128 band sums after each
//! pixel's X, Y, Z (pixel by pixel: X, Y, Z, band 0 … band N − 1). A film
//! without bands is written in format 2, byte for byte as before.
//!
//! Reading trusts nothing: the checksum is verified first, then every count
//! and length is checked against the bytes that remain before anything is
//! allocated, so a corrupt or crafted film is an error naming the file,
//! never a panic or an attempt to allocate what the header claims.

use super::sample::{Dropped, DroppedAt};
use super::{Film, FilmParts, MAX_BAND_SUMS, MAX_BANDS, MAX_PIXELS, PIXEL_BYTES, check_resolution};
use crate::error::RenderError;
use crate::inputs::InputFile;
use std::ops::Range;
use std::path::Path;

const MAGIC: &[u8; 12] = b"LUSTREFILM2\n";
const MAGIC_V3: &[u8; 12] = b"LUSTREFILM3\n";
const MAGIC_V1: &[u8; 12] = b"LUSTREFILM1\n";
/// Most input files a film records.
const MAX_INPUTS: usize = 1 << 16;
/// Longest recorded input name, bytes.
const MAX_NAME: usize = 4096;
/// Largest film file read: the sums of [`MAX_PIXELS`] pixels and room for the
/// largest input and range records.
pub const MAX_FILM_BYTES: u64 = MAX_PIXELS * PIXEL_BYTES as u64 + MAX_BAND_SUMS * 16 + (1 << 30);

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

impl Film {
    /// Serialises the film.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out =
            Vec::with_capacity(128 + self.p.sums.len() * 48 + self.p.band_sums.len() * 16);
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
        let bands = self.p.bands;
        out.put(if bands > 0 { MAGIC_V3 } else { MAGIC })?;
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
        if bands > 0 {
            out.put(&(bands as u32).to_le_bytes())?;
        }
        for (i, s) in self.p.sums.iter().enumerate() {
            for v in s {
                out.put(&v.to_le_bytes())?;
            }
            for v in &self.p.band_sums[i * bands..(i + 1) * bands] {
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
        if magic != MAGIC && magic != MAGIC_V3 {
            return Err(NOT_A_FILM.into());
        }
        let v3 = magic == MAGIC_V3;
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
        let bands = if v3 {
            let n = u32::from_le_bytes(r.array()?) as usize;
            if !(1..=MAX_BANDS).contains(&n) {
                return Err(format!(
                    "corrupt film: {n} spectral bands (a film of format 3 holds 1..={MAX_BANDS})"
                ));
            }
            if pixels * n as u64 > MAX_BAND_SUMS {
                return Err(format!(
                    "corrupt film: {width}×{height} pixels × {n} bands is more band sums than \
                     a film holds ({MAX_BAND_SUMS})"
                ));
            }
            n
        } else {
            0
        };
        let want = pixels as u128 * (PIXEL_BYTES + 16 * bands as u128);
        if r.remaining() as u128 != want {
            return Err(format!(
                "corrupt film: {} bytes of sums for {width}×{height} pixels with {bands} spectral \
                 bands (expected {want})",
                r.remaining()
            ));
        }
        let mut sums = Vec::with_capacity(pixels as usize);
        let mut band_sums = Vec::with_capacity(pixels as usize * bands);
        for _ in 0..pixels {
            let mut px = [0i128; 3];
            for v in px.iter_mut() {
                *v = i128::from_le_bytes(r.array()?);
            }
            sums.push(px);
            for _ in 0..bands {
                band_sums.push(i128::from_le_bytes(r.array()?));
            }
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
            bands,
            band_sums,
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
