//! An equirectangular (lat-long) environment map: piecewise-constant
//! radiance per texel, sampled texel by texel in proportion to its power and
//! uniformly in solid angle within the texel, so radiance ÷ pdf is constant
//! over each texel.
//!
//! No trigonometric function runs per ray: a direction's row comes from
//! 1 − cos θ and its column from a monotone "pseudo-angle" (one division, no
//! atan2), each located among the texel edges' keys with a guide table; a
//! drawn direction from tables of the edges' sines and cosines, a linear
//! draw in cos θ and a short series for the azimuth's offset within its
//! column.

use crate::color::{SRGB_TO_XYZ, mul};
use crate::distribution::{Distribution2D, walk_count_le};
use crate::env_lift::RgbLift;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

/// One texel: its radiance as CMF coefficients and the solid-angle density
/// with which [`EnvMap::sample`] draws a direction in it (one cache line
/// serves both for a ray that escapes to the map).
#[derive(Clone, Copy, Debug)]
struct Texel {
    coeffs: [f64; 3],
    pdf: f64,
}

/// A monotone key's position among sorted edge keys: `count_le(x)` = the
/// number of edges ≤ x, found from a guide cell and a short walk (exact
/// with respect to the stored keys, whatever the cell's rounding).
#[derive(Clone, Debug)]
struct GuidedEdges {
    keys: Vec<f64>,
    guide: Vec<u32>,
    /// Guide cells per unit key.
    scale: f64,
}

impl GuidedEdges {
    /// From non-decreasing `keys` over [0, `range`], with `cells` guide cells.
    fn new(keys: Vec<f64>, range: f64, cells: usize) -> GuidedEdges {
        let cells = cells.max(1);
        let scale = cells as f64 / range;
        let guide = (0..cells)
            .map(|k| keys.partition_point(|&c| c <= k as f64 / scale) as u32)
            .collect();
        GuidedEdges { keys, guide, scale }
    }

    #[inline]
    fn count_le(&self, x: f64) -> usize {
        // A NaN or negative key saturates to cell 0 and walks from there
        // (through u32: a cast to usize costs a dozen instructions more).
        let cell = ((x * self.scale) as u32 as usize).min(self.guide.len() - 1);
        walk_count_le(&self.keys, self.guide[cell] as usize, x)
    }
}

/// A monotone stand-in for the angle atan2(s, c) ∈ [0, 2π): a value in
/// [0, 4), one unit per quadrant, |s| / (|s| + |c|) within it. Its slope
/// against the angle stays within a factor 2, so a guide table over it
/// finds an edge in a step or two. Scale-free: (s, c) need not be unit.
/// (0, 0) and NaN give 0.
#[inline]
fn pseudo_angle(s: f64, c: f64) -> f64 {
    let d = s.abs() + c.abs();
    if s >= 0.0 && c > 0.0 {
        s / d
    } else if s > 0.0 && c <= 0.0 {
        1.0 - c / d
    } else if s <= 0.0 && c < 0.0 {
        2.0 - s / d
    } else if s < 0.0 {
        3.0 + c / d
    } else {
        0.0
    }
}

/// (sin δ, cos δ) for |δ| ≤ π/8 by their Taylor series to δ¹³ and δ¹⁴
/// (truncation below 10⁻¹⁸), in nested form with constant reciprocals.
#[inline]
fn sin_cos_small(x: f64) -> (f64, f64) {
    let x2 = x * x;
    let s = 1.0 - x2 * (1.0 / 156.0);
    let s = 1.0 - x2 * (1.0 / 110.0) * s;
    let s = 1.0 - x2 * (1.0 / 72.0) * s;
    let s = 1.0 - x2 * (1.0 / 42.0) * s;
    let s = 1.0 - x2 * (1.0 / 20.0) * s;
    let s = 1.0 - x2 * (1.0 / 6.0) * s;
    let c = 1.0 - x2 * (1.0 / 182.0);
    let c = 1.0 - x2 * (1.0 / 132.0) * c;
    let c = 1.0 - x2 * (1.0 / 90.0) * c;
    let c = 1.0 - x2 * (1.0 / 56.0) * c;
    let c = 1.0 - x2 * (1.0 / 30.0) * c;
    let c = 1.0 - x2 * (1.0 / 12.0) * c;
    let c = 1.0 - x2 * (1.0 / 2.0) * c;
    (x * s, c)
}

/// An equirectangular environment map (+y up, u = 0 at −z, increasing
/// toward +x), rotated about +y.
pub struct EnvMap {
    width: usize,
    height: usize,
    texels: Vec<Texel>,
    dist: Distribution2D,
    /// cos θ at the row edges, 1 down to −1 (`height + 1` entries).
    z_edges: Vec<f64>,
    /// (sin φ, cos φ) of the column edges in world azimuth (`width + 1`).
    col_edges: Vec<[f64; 2]>,
    /// The rotation's (sin, cos): map azimuth = world azimuth + rotation.
    rot: [f64; 2],
    /// 1 − cos θ at the row edges (over [0, 2]). Rows crowd together in
    /// cos θ toward the poles (1/sin θ of them per unit), but directions
    /// thin out there as sin θ: over uniform directions a guide of 2·height
    /// cells walks ½ a step on average, without the square root and division
    /// of an angle.
    rows: GuidedEdges,
    /// Pseudo-angles of the column edges in map azimuth (over [0, 4]).
    cols: GuidedEdges,
}

impl EnvMap {
    /// A lat-long EXR from the file's bytes (`path` for messages), scaled by
    /// `scale` and rotated by `rotate_deg` about +y.
    pub fn from_exr_bytes(
        path: &Path,
        bytes: &[u8],
        scale: f64,
        rotate_deg: f64,
    ) -> Result<EnvMap, String> {
        use exr::prelude::*;
        // A header may claim any size: refuse maps beyond 2²⁸ texels
        // (6 GB of coefficients) before allocating them.
        const MAX_TEXELS: usize = 1 << 28;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |res, _| {
                    let n = res.width().saturating_mul(res.height());
                    let n = if n <= MAX_TEXELS { n } else { 0 };
                    (res.width(), res.height(), vec![[0.0f64; 3]; n])
                },
                |px: &mut (usize, usize, Vec<[f64; 3]>),
                 pos,
                 (r, g, b, _a): (f32, f32, f32, f32)| {
                    let i = pos.y() * px.0 + pos.x();
                    if let Some(p) = px.2.get_mut(i) {
                        *p = [r as f64, g as f64, b as f64];
                    }
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .map_err(|e| format!("cannot read environment EXR {}: {e}", path.display()))?;
        {
            let (w, h, px) = &image.layer_data.channel_data.pixels;
            if px.len() != w * h {
                return Err(format!(
                    "environment EXR {} is {w}×{h}: more than {MAX_TEXELS} texels",
                    path.display()
                ));
            }
        }
        let (width, height, rgb) = image.layer_data.channel_data.pixels;
        if width == 0 || height == 0 {
            return Err(format!("environment EXR {} is empty", path.display()));
        }
        // A NaN or negative texel has no radiance to stand for: zeroing it made an
        // all-NaN sky black and negative ones a negative image, without a word.
        if let Some(i) = rgb
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0))
        {
            return Err(format!(
                "environment EXR {}: pixel ({}, {}) from the top left has RGB ({}, {}, {}); \
                 radiance must be finite and ≥ 0: repair the map (e.g. clamp it to 0 and \
                 replace non-finite values in an image editor) or use another one",
                path.display(),
                i % width,
                i / width,
                rgb[i][0],
                rgb[i][1],
                rgb[i][2]
            ));
        }
        Ok(EnvMap::from_rgb(width, height, &rgb, scale, rotate_deg))
    }

    /// From `width × height` linear-sRGB texels, row-major from the top
    /// (`rgb` is padded with black or cut to that size; a zero size counts
    /// as 1).
    pub(crate) fn from_rgb(
        width: usize,
        height: usize,
        rgb: &[[f64; 3]],
        scale: f64,
        rotate_deg: f64,
    ) -> EnvMap {
        let (width, height) = (width.max(1), height.max(1));
        let z_edges: Vec<f64> = (0..=height)
            .map(|k| match k {
                0 => 1.0,
                k if k == height => -1.0,
                k => (PI * k as f64 / height as f64).cos(),
            })
            .collect();
        // Solid angle of a texel in each row: uniform in azimuth and in cos θ.
        let omega: Vec<f64> = z_edges
            .windows(2)
            .map(|z| (z[0] - z[1]).max(0.0) * 2.0 * PI / width as f64)
            .collect();
        let lift = RgbLift::new();
        let mut coeffs = Vec::with_capacity(width * height);
        let mut weights = Vec::with_capacity(width * height);
        for i in 0..width * height {
            let px = rgb.get(i).copied().unwrap_or([0.0; 3]).map(|v| v * scale);
            coeffs.push(lift.coefficients(px));
            // |Y| plus a tenth of the channel sum keeps dim-but-coloured texels sampleable.
            let lum =
                mul(&SRGB_TO_XYZ, px)[1].abs() + 0.1 * (px[0].abs() + px[1].abs() + px[2].abs());
            weights.push(lum * omega[i / width]);
        }
        let dist = Distribution2D::new(&weights, width, height);
        let texels = coeffs
            .into_iter()
            .enumerate()
            .map(|(i, coeffs)| {
                let (row, col) = (i / width, i % width);
                let om = omega[row];
                let pdf = if om > 0.0 {
                    dist.pmf(row, col) / om
                } else {
                    0.0
                };
                Texel { coeffs, pdf }
            })
            .collect();
        let rotation = rotate_deg.to_radians();
        let col_edges = (0..=width)
            .map(|k| {
                let (s, c) = (2.0 * PI * k as f64 / width as f64 - rotation).sin_cos();
                [s, c]
            })
            .collect();
        let row_keys = z_edges.iter().map(|&z| 1.0 - z).collect();
        let col_keys = (0..=width)
            .map(|k| match k {
                0 => 0.0,
                k if k == width => 4.0,
                k => {
                    let (s, c) = (2.0 * PI * k as f64 / width as f64).sin_cos();
                    pseudo_angle(s, c)
                }
            })
            .collect();
        let (rs, rc) = rotation.sin_cos();
        EnvMap {
            width,
            height,
            texels,
            dist,
            z_edges,
            col_edges,
            rot: [rs, rc],
            rows: GuidedEdges::new(monotone(row_keys), 2.0, 2 * height),
            cols: GuidedEdges::new(monotone(col_keys), 4.0, width + 1),
        }
    }

    /// The texel index a world direction falls in.
    #[inline]
    fn texel_index(&self, d: DVec3) -> usize {
        let row = self.rows.count_le(1.0 - d.y);
        // Map azimuth φ + rotation, from (sin, cos) of the world azimuth = (x, −z).
        let [rs, rc] = self.rot;
        let (s, c) = (d.x, -d.z);
        let col = self
            .cols
            .count_le(pseudo_angle(s * rc + c * rs, c * rc - s * rs));
        let row = row.saturating_sub(1).min(self.height - 1);
        let col = col.saturating_sub(1).min(self.width - 1);
        row * self.width + col
    }

    /// The CMF coefficients of the radiance along world direction `d` and
    /// the solid-angle density with which [`sample`](Self::sample) draws it.
    #[inline]
    pub fn eval(&self, d: DVec3) -> ([f64; 3], f64) {
        let t = self.texels[self.texel_index(d)];
        (t.coeffs, t.pdf)
    }

    /// A direction drawn in proportion to texel power, uniformly in solid
    /// angle within its texel: (direction, solid-angle pdf, CMF
    /// coefficients); `None` where the texel has no density.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> Option<(DVec3, f64, [f64; 3])> {
        let ([row, col], [tu, tv]) = self.dist.sample_bins(u);
        let t = self.texels[row * self.width + col];
        if t.pdf <= 0.0 {
            return None;
        }
        let (z0, z1) = (self.z_edges[row], self.z_edges[row + 1]);
        let z = z0 + (z1 - z0) * tv;
        let st = ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();
        let delta = tu * 2.0 * PI / self.width as f64;
        let (sd, cd) = if self.width >= 16 {
            sin_cos_small(delta)
        } else {
            delta.sin_cos()
        };
        let [se, ce] = self.col_edges[col];
        let (sp, cp) = (se * cd + ce * sd, ce * cd - se * sd);
        Some((DVec3::new(st * sp, z, -st * cp), t.pdf, t.coeffs))
    }
}

/// `keys` made non-decreasing (round-off in the edges' sines and cosines
/// could otherwise swap two neighbours' keys).
fn monotone(mut keys: Vec<f64>) -> Vec<f64> {
    for i in 1..keys.len() {
        keys[i] = keys[i].max(keys[i - 1]);
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A map with a bright small "sun", a dim gradient and black texels.
    fn test_rgb(w: usize, h: usize) -> Vec<[f64; 3]> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (x, y) == (w / 3, h / 3) {
                    [400.0, 380.0, 340.0]
                } else if x % 5 == 4 {
                    [0.0; 3]
                } else {
                    [0.1 + 0.05 * y as f64, 0.2, 0.3 + 0.01 * x as f64]
                }
            })
            .collect()
    }

    /// The texel by the closed forms (atan2 and acos), `None` within `eps`
    /// of a texel edge, where round-off may pick either neighbour.
    fn reference_texel(w: usize, h: usize, rot: f64, d: DVec3, eps: f64) -> Option<usize> {
        let u = ((d.x.atan2(-d.z) + rot) / (2.0 * PI)).rem_euclid(1.0) * w as f64;
        let v = d.y.clamp(-1.0, 1.0).acos() / PI * h as f64;
        let near = |t: f64| (t - t.round()).abs() < eps;
        if near(u) || near(v) {
            return None;
        }
        Some((v as usize).min(h - 1) * w + (u as usize).min(w - 1))
    }

    fn uniform_dir(rng: &mut Rng) -> DVec3 {
        crate::light::uniform_sphere([rng.uniform(), rng.uniform()])
    }

    #[test]
    fn texel_of_a_direction_is_the_closed_forms_texel() {
        let mut rng = Rng::for_sample(7, 0, 0);
        for &(w, h, deg) in &[
            (256, 128, 0.0),
            (37, 19, 123.4),
            (4, 2, -30.0),
            (1, 1, 10.0),
        ] {
            let m = EnvMap::from_rgb(w, h, &test_rgb(w, h), 1.0, deg);
            let rot = f64::to_radians(deg);
            let mut checked = 0;
            for _ in 0..100_000 {
                let d = uniform_dir(&mut rng);
                if let Some(want) = reference_texel(w, h, rot, d, 1e-9) {
                    assert_eq!(m.texel_index(d), want, "{w}×{h}, {deg}°: {d:?}");
                    checked += 1;
                }
            }
            assert!(checked > 99_000);
            // The poles, the axes and bad directions land somewhere, without panicking.
            for d in [
                DVec3::Y,
                -DVec3::Y,
                DVec3::X,
                -DVec3::Z,
                DVec3::ZERO,
                DVec3::NAN,
            ] {
                assert!(m.texel_index(d) < w * h);
            }
        }
    }

    #[test]
    fn small_angle_sin_cos_is_libm_to_round_off() {
        for k in 0..=10_000 {
            let x = (k as f64 / 5000.0 - 1.0) * PI / 8.0;
            let (s, c) = sin_cos_small(x);
            let err = (s - x.sin()).abs().max((c - x.cos()).abs());
            assert!(err < 2.3e-16, "{x}: {err:e}");
        }
    }

    /// Draws fall in each quarter of each texel (split at its middle cos θ
    /// and azimuth, four equal solid angles) with probability ¼ of the
    /// texel's share of Σ luminance × solid angle, which the test computes
    /// from the closed forms: a chi-square test of the draw against its
    /// intended density, within texels as well as between them. Each draw's
    /// pdf is the one [`EnvMap::eval`] gives its direction, and texels of no
    /// radiance are never drawn.
    #[test]
    fn draws_follow_power_and_are_uniform_within_texels() {
        let (w, h, deg) = (10, 5, 33.0);
        let rgb = test_rgb(w, h);
        let m = EnvMap::from_rgb(w, h, &rgb, 2.0, deg);
        let rot = f64::to_radians(deg);
        let power: Vec<f64> = rgb
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let lum = mul(&SRGB_TO_XYZ, *p)[1] + 0.1 * (p[0] + p[1] + p[2]);
                let (t0, t1) = (
                    (i / w) as f64 * PI / h as f64,
                    (i / w + 1) as f64 * PI / h as f64,
                );
                lum * (t0.cos() - t1.cos())
            })
            .collect();
        let total: f64 = power.iter().sum();
        let n = 400_000;
        let mut hist = vec![0usize; 4 * w * h];
        let mut rng = Rng::for_sample(3, 0, 0);
        for _ in 0..n {
            let (d, pdf, c) = m.sample([rng.uniform(), rng.uniform()]).unwrap();
            assert!((d.length() - 1.0).abs() < 1e-14);
            let Some(i) = reference_texel(w, h, rot, d, 1e-9) else {
                continue;
            };
            assert!(power[i] > 0.0, "drew black texel {i}");
            let (ec, epdf) = m.eval(d);
            assert_eq!((ec, epdf), (c, pdf));
            let (row, col) = (i / w, i % w);
            let (t0, t1) = (row as f64 * PI / h as f64, (row + 1) as f64 * PI / h as f64);
            let lower = d.y < 0.5 * (t0.cos() + t1.cos());
            let u = ((d.x.atan2(-d.z) + rot) / (2.0 * PI)).rem_euclid(1.0) * w as f64;
            let right = u - col as f64 >= 0.5;
            hist[4 * i + 2 * lower as usize + right as usize] += 1;
        }
        let mut chi2 = 0.0;
        let mut cells = 0;
        for (k, &o) in hist.iter().enumerate() {
            let e = n as f64 * power[k / 4] / total / 4.0;
            if e > 0.0 {
                chi2 += (o as f64 - e).powi(2) / e;
                cells += 1;
            } else {
                assert_eq!(o, 0);
            }
        }
        let dof = (cells - 1) as f64;
        eprintln!("chi² {chi2:.1} over {dof} degrees of freedom");
        assert!(
            chi2 < dof + 5.0 * (2.0 * dof).sqrt(),
            "chi² {chi2} ({dof} dof)"
        );
    }

    /// The density, read at each texel's centre direction, times the
    /// texel's solid angle by its closed form, (cos θ₀ − cos θ₁)·2π/W, is
    /// the texel's share of Σ luminance × solid angle (so the density
    /// integrates to 1 and L/pdf is one constant per texel).
    #[test]
    fn density_times_solid_angle_is_the_texels_power_share() {
        let (w, h, deg) = (64, 32, 71.0);
        let rgb = test_rgb(w, h);
        let m = EnvMap::from_rgb(w, h, &rgb, 1.0, deg);
        let omega = |row: usize| {
            let (t0, t1) = (row as f64 * PI / h as f64, (row + 1) as f64 * PI / h as f64);
            (t0.cos() - t1.cos()) * 2.0 * PI / w as f64
        };
        let power = |i: usize| {
            let p = rgb[i];
            (mul(&SRGB_TO_XYZ, p)[1] + 0.1 * (p[0] + p[1] + p[2])) * omega(i / w)
        };
        let total: f64 = (0..w * h).map(power).sum();
        let mut integral = 0.0;
        for i in 0..w * h {
            let theta = ((i / w) as f64 + 0.5) * PI / h as f64;
            let phi = ((i % w) as f64 + 0.5) * 2.0 * PI / w as f64 - deg.to_radians();
            let d = DVec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            let p = m.eval(d).1 * omega(i / w);
            let want = power(i) / total;
            assert!((p - want).abs() <= 1e-12 * want, "texel {i}: {p} vs {want}");
            integral += p;
        }
        assert!((integral - 1.0).abs() < 1e-12, "∫pdf = {integral}");
    }

    #[test]
    fn degenerate_maps_sample_and_evaluate_without_panicking() {
        let black = EnvMap::from_rgb(3, 2, &[[0.0; 3]; 6], 1.0, 0.0);
        let empty = EnvMap::from_rgb(0, 0, &[], 1.0, 0.0);
        let tall = EnvMap::from_rgb(1, 4000, &[[1.0; 3]; 4000], 1.0, 0.0);
        for m in [&black, &empty, &tall] {
            for u in [[0.0, 0.0], [0.5, 0.5], [1.0f64.next_down(); 2]] {
                if let Some((d, pdf, _)) = m.sample(u) {
                    assert!(pdf > 0.0 && pdf.is_finite() && (d.length() - 1.0).abs() < 1e-12);
                }
            }
            let (_, pdf) = m.eval(DVec3::NAN);
            assert!(pdf.is_finite());
        }
    }
}
