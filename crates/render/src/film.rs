//! The film: per-pixel XYZ sums in fixed point, so that films rendered over
//! disjoint sample ranges add up *exactly* (integer addition is associative)
//! to the film of one render over the union — on any machine, in any order.
//!
//! A sample's XYZ is rounded to a multiple of 2⁻⁴⁰ (≈ 9·10⁻¹³) and summed in
//! i128, leaving 2⁸⁷ of head-room: quantisation is 10⁻⁹ of a unit radiance,
//! far below Monte Carlo noise, and overflow needs ~10²⁶ in one pixel.
//!
//! File format (`.film`, little endian): magic `LUSTREFILM1\n`; u32 width,
//! u32 height; u64 scene fingerprint; u64 seed; f64 exposure; u32 range
//! count and that many (u64 start, u64 end) sample ranges; then
//! width·height·3 i128 sums (X, Y, Z per pixel, row-major from the top).

use crate::color::xyz_to_srgb;
use crate::error::RenderError;
use crate::spectrum::Cie;
use std::io::Write;
use std::ops::Range;
use std::path::Path;

const MAGIC: &[u8; 12] = b"LUSTREFILM1\n";
const SCALE: f64 = (1u64 << 40) as f64;

/// Accumulated samples of one image.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
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
    /// Sample-index ranges accumulated, sorted and disjoint.
    pub ranges: Vec<Range<u64>>,
    /// Fixed-point X, Y, Z sums per pixel.
    pub sums: Vec<[i128; 3]>,
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
    /// An empty film.
    pub fn new(width: u32, height: u32, fingerprint: u64, seed: u64, exposure: f64) -> Film {
        Film {
            width,
            height,
            fingerprint,
            seed,
            exposure,
            ranges: Vec::new(),
            sums: vec![[0; 3]; width as usize * height as usize],
        }
    }

    /// Total samples per pixel accumulated.
    pub fn spp(&self) -> u64 {
        self.ranges.iter().map(|r| r.end - r.start).sum()
    }

    /// Records that samples `r` have been added; errors if they overlap.
    pub fn add_range(&mut self, r: Range<u64>) -> Result<(), String> {
        if r.is_empty() {
            return Ok(());
        }
        if let Some(o) = self
            .ranges
            .iter()
            .find(|o| o.start < r.end && r.start < o.end)
        {
            return Err(format!(
                "sample range {}..{} overlaps {}..{} already in the film",
                r.start, r.end, o.start, o.end
            ));
        }
        self.ranges.push(r);
        self.ranges.sort_by_key(|r| r.start);
        let mut merged: Vec<Range<u64>> = Vec::with_capacity(self.ranges.len());
        for r in self.ranges.drain(..) {
            match merged.last_mut() {
                Some(last) if last.end == r.start => last.end = r.end,
                _ => merged.push(r),
            }
        }
        self.ranges = merged;
        Ok(())
    }

    /// Mean XYZ of pixel `i`, normalised so that a unit constant spectrum has Y = 1.
    pub fn xyz(&self, i: usize) -> [f64; 3] {
        let n = self.spp();
        if n == 0 {
            return [0.0; 3];
        }
        let k = 1.0 / (SCALE * n as f64 * Cie::get().y_integral());
        self.sums[i].map(|s| s as f64 * k)
    }

    /// Linear sRGB of every pixel with the exposure applied.
    pub fn rgb(&self) -> Vec<[f32; 3]> {
        let gain = self.exposure.exp2();
        (0..self.sums.len())
            .map(|i| xyz_to_srgb(self.xyz(i)).map(|v| (v * gain) as f32))
            .collect()
    }

    /// Adds another film's samples; both must come from the same scene and seed.
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(format!(
                "resolution {}×{} differs from {}×{}",
                other.width, other.height, self.width, self.height
            ));
        }
        if self.fingerprint != other.fingerprint {
            return Err("rendered from a different scene (fingerprints differ)".into());
        }
        if self.seed != other.seed {
            return Err(format!("seed {} differs from {}", other.seed, self.seed));
        }
        for r in &other.ranges {
            self.add_range(r.clone())?;
        }
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for k in 0..3 {
                a[k] = a[k].saturating_add(b[k]);
            }
        }
        Ok(())
    }

    /// Serialises the film.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + self.sums.len() * 48);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&self.width.to_le_bytes());
        out.extend_from_slice(&self.height.to_le_bytes());
        out.extend_from_slice(&self.fingerprint.to_le_bytes());
        out.extend_from_slice(&self.seed.to_le_bytes());
        out.extend_from_slice(&self.exposure.to_le_bytes());
        out.extend_from_slice(&(self.ranges.len() as u32).to_le_bytes());
        for r in &self.ranges {
            out.extend_from_slice(&r.start.to_le_bytes());
            out.extend_from_slice(&r.end.to_le_bytes());
        }
        for s in &self.sums {
            for v in s {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    /// Parses a film.
    pub fn from_bytes(bytes: &[u8]) -> Result<Film, String> {
        let mut r = Reader { b: bytes, at: 0 };
        if r.take(12)? != MAGIC {
            return Err("not a lustre film (bad magic); films are the `.film` files written by `lustre render`".into());
        }
        let width = u32::from_le_bytes(r.array()?);
        let height = u32::from_le_bytes(r.array()?);
        let fingerprint = u64::from_le_bytes(r.array()?);
        let seed = u64::from_le_bytes(r.array()?);
        let exposure = f64::from_le_bytes(r.array()?);
        let n_ranges = u32::from_le_bytes(r.array()?) as usize;
        let mut film = Film::new(width, height, fingerprint, seed, exposure);
        let pixels = width as usize * height as usize;
        if bytes.len() != 12 + 32 + 4 + 16 * n_ranges + 48 * pixels {
            return Err(format!(
                "truncated or corrupt film: {} bytes for {width}×{height} px",
                bytes.len()
            ));
        }
        for _ in 0..n_ranges {
            let a = u64::from_le_bytes(r.array()?);
            let b = u64::from_le_bytes(r.array()?);
            if a > b {
                return Err(format!("corrupt sample range {a}..{b}"));
            }
            film.add_range(a..b)?;
        }
        for s in film.sums.iter_mut() {
            for v in s.iter_mut() {
                *v = i128::from_le_bytes(r.array()?);
            }
        }
        Ok(film)
    }

    /// Writes the film atomically.
    pub fn save(&self, path: &Path) -> Result<(), RenderError> {
        crate::output::write_atomic(path, |f| f.write_all(&self.to_bytes()))
    }

    /// Reads a film file.
    pub fn load(path: &Path) -> Result<Film, RenderError> {
        let bytes = std::fs::read(path).map_err(|e| RenderError::io(path, e))?;
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
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let s = self
            .b
            .get(self.at..self.at + n)
            .ok_or("truncated film file")?;
        self.at += n;
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
        let mut f = Film::new(3, 2, 42, 7, 0.5);
        f.sums[4] = [1, -2, i128::MAX / 3];
        f.add_range(0..4).unwrap();
        f.add_range(8..10).unwrap();
        f.add_range(4..8).unwrap();
        assert_eq!(f.ranges, vec![0..10]);
        assert!(f.add_range(9..12).is_err());
        let g = Film::from_bytes(&f.to_bytes()).unwrap();
        assert_eq!(f, g);
        assert!(Film::from_bytes(&f.to_bytes()[..50]).is_err());
        assert!(Film::from_bytes(b"nonsense").is_err());
    }

    #[test]
    fn merge_checks_compatibility() {
        let mut a = Film::new(2, 2, 1, 0, 0.0);
        a.add_range(0..5).unwrap();
        let mut b = a.clone();
        b.ranges.clear();
        b.add_range(5..9).unwrap();
        b.sums[0] = [3, 3, 3];
        a.merge(&b).unwrap();
        assert_eq!(a.spp(), 9);
        assert_eq!(a.sums[0], [3, 3, 3]);
        let c = Film::new(2, 2, 2, 0, 0.0);
        assert!(a.merge(&c).unwrap_err().contains("different scene"));
        assert!(a.merge(&b).unwrap_err().contains("overlaps"));
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
