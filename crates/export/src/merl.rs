//! MERL `.binary` BRDF tables (Matusik, Pfister, Brand & McMillan 2003, "A
//! Data-Driven Reflectance Model"), as the database's published reader
//! (`BRDFRead.cpp`) defines them:
//!
//! * header: three little-endian i32, the cell counts along θh, θd and φd:
//!   90, 90, 180;
//! * then 3 × 90·90·180 f64: the red block, the green block, the blue block,
//!   each indexed `φd + 180·(θd + 90·θh)`;
//! * a reader multiplies red, green and blue by 1/1500, 1.15/1500 and
//!   1.66/1500 to get the BRDF (sr⁻¹).
//!
//! Directions are in Rusinkiewicz's half/difference angles: h = (ωi + ωo)/|·|
//! at (θh, φh), and d = ωi rotated by −φh about the normal and by −θh about
//! the y axis, at (θd, φd). The table is isotropic (no φh) and holds
//! φd ∈ [0, π) only, φd and φd + π being the same configuration of a
//! reciprocal BRDF. A reader takes the cell an angle falls in, no
//! interpolation: θd and φd in 1° cells, θh in cells of √(θh/90° · 90)
//! (index k covers k²/90 to (k+1)²/90 degrees, 0.011° at the normal,
//! 2° at 90°).
//!
//! The exporter stores each cell's value at its centre in index space,
//! where a cell-lookup reader's error is smallest, and the colour of the
//! model's spectral BRDF in linear sRGB (see [`crate::color`]; D65 by
//! default). A cell below the horizon (ωi or ωo under the surface) holds 0;
//! the database marks those with negative numbers, which [`MerlTable`]
//! reads as 0 too.

use brdf::{Bxdf, DVec3};
use core::f64::consts::{FRAC_PI_2, PI};

use crate::check::{self, CheckPoint, Rng, Sides};
use crate::color::{Illuminant, srgb_weights};
use crate::{ExportError, Exported, Report, par_map};

/// Cells along θh.
pub const THETA_H: usize = 90;
/// Cells along θd.
pub const THETA_D: usize = 90;
/// Cells along φd (over [0, π)).
pub const PHI_D: usize = 180;
/// Cells per channel.
pub const CELLS: usize = THETA_H * THETA_D * PHI_D;
/// Most wavelengths a MERL export integrates (every 5 nm over 360–830 nm).
pub const MAX_WAVELENGTHS: usize = 95;
/// The readers' channel scales: value (sr⁻¹) = stored × scale.
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// A MERL export's contents.
#[derive(Clone, Debug, PartialEq)]
pub struct MerlOptions {
    /// Wavelengths (nm) at which the model is evaluated and integrated to
    /// sRGB, strictly increasing within 360–830 nm.
    pub wavelengths_nm: Vec<f64>,
    /// The light under which the spectrum becomes sRGB.
    pub illuminant: Illuminant,
    /// Leave out a coherent (delta) lobe instead of refusing the model.
    pub drop_specular: bool,
    /// Monte Carlo samples per checked incidence (0: no estimate).
    pub check_samples: usize,
    /// Largest incidence the estimate covers (degrees).
    pub check_theta_max_deg: f64,
}

impl Default for MerlOptions {
    fn default() -> MerlOptions {
        MerlOptions {
            wavelengths_nm: (0..=47).map(|k| 360.0 + 10.0 * k as f64).collect(),
            illuminant: Illuminant::D65,
            drop_specular: false,
            check_samples: 4096,
            check_theta_max_deg: 80.0,
        }
    }
}

/// Rotation of `v` by `angle` about the unit `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis * axis.dot(v) * (1.0 - c) + axis.cross(v) * s
}

/// (θh, θd, φd) of a pair of directions (φh dropped: isotropy).
pub fn half_diff(wi: DVec3, wo: DVec3) -> Option<(f64, f64, f64)> {
    let h = (wi + wo).try_normalize()?;
    let theta_h = h.z.clamp(-1.0, 1.0).acos();
    let phi_h = h.y.atan2(h.x);
    let t = rotate(wi, DVec3::Z, -phi_h);
    let d = rotate(t, DVec3::Y, -theta_h);
    Some((theta_h, d.z.clamp(-1.0, 1.0).acos(), d.y.atan2(d.x)))
}

/// The directions of (θh, θd, φd) with φh = 0.
pub fn from_half_diff(theta_h: f64, theta_d: f64, phi_d: f64) -> (DVec3, DVec3) {
    let d = crate::param::direction(theta_d, phi_d);
    let wi = rotate(d, DVec3::Y, theta_h);
    let h = DVec3::new(theta_h.sin(), 0.0, theta_h.cos());
    let wo = 2.0 * wi.dot(h) * h - wi;
    (wi, wo)
}

/// The reader's cell of (θh, θd, φd).
pub fn cell(theta_h: f64, theta_d: f64, phi_d: f64) -> usize {
    let ih = if theta_h <= 0.0 {
        0
    } else {
        let deg = theta_h / FRAC_PI_2 * THETA_H as f64;
        ((deg * THETA_H as f64).sqrt() as usize).min(THETA_H - 1)
    };
    let id = ((theta_d / FRAC_PI_2 * THETA_D as f64).max(0.0) as usize).min(THETA_D - 1);
    let p = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    let ip = ((p / PI * PHI_D as f64).max(0.0) as usize).min(PHI_D - 1);
    ip + PHI_D * (id + THETA_D * ih)
}

/// The angles at the centre of cell (ih, id, ip), in index space.
pub fn cell_centre(ih: usize, id: usize, ip: usize) -> (f64, f64, f64) {
    let h = ih as f64 + 0.5;
    (
        (h * h / THETA_H as f64) / THETA_H as f64 * FRAC_PI_2,
        (id as f64 + 0.5) / THETA_D as f64 * FRAC_PI_2,
        (ip as f64 + 0.5) / PHI_D as f64 * PI,
    )
}

/// A MERL table, evaluated as the database's reader does.
#[derive(Clone, Debug)]
pub struct MerlTable {
    /// Scaled values (sr⁻¹), channel-major.
    values: Vec<f64>,
}

impl MerlTable {
    /// Parses a `.binary` file: the three dimensions must be 90, 90, 180 and
    /// the file exactly as long as they say (checked before reading).
    pub fn parse(bytes: &[u8]) -> Result<MerlTable, ExportError> {
        let bad = |message: String| ExportError::Parse {
            what: "MERL .binary",
            message,
        };
        if bytes.len() < 12 {
            return Err(bad(format!(
                "{} bytes: shorter than the 12-byte header",
                bytes.len()
            )));
        }
        let dims: Vec<i32> = bytes[..12]
            .chunks_exact(4)
            .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if dims != [THETA_H as i32, THETA_D as i32, PHI_D as i32] {
            return Err(bad(format!(
                "dimensions {dims:?}: a MERL table is [90, 90, 180] (θh, θd, φd)"
            )));
        }
        let want = 12 + 3 * CELLS * 8;
        if bytes.len() != want {
            return Err(bad(format!(
                "{} bytes: a [90, 90, 180] table is {want} bytes (truncated or padded?)",
                bytes.len()
            )));
        }
        let mut values = Vec::with_capacity(3 * CELLS);
        for (i, c) in bytes[12..].chunks_exact(8).enumerate() {
            let v = f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]);
            if !v.is_finite() {
                return Err(bad(format!(
                    "value {i} (channel {}, cell {}) is not finite",
                    i / CELLS,
                    i % CELLS
                )));
            }
            values.push(v * SCALE[i / CELLS]);
        }
        Ok(MerlTable { values })
    }

    /// The BRDF (sr⁻¹, linear RGB) at (ωi, ωo): the value of the cell the
    /// pair falls in; negative (unmeasured) cells and directions below the
    /// horizon give 0.
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> [f64; 3] {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let Some((th, td, pd)) = half_diff(wi, wo) else {
            return [0.0; 3];
        };
        let i = cell(th, td, pd);
        [0, 1, 2].map(|c| self.values[c * CELLS + i].max(0.0))
    }
}

fn validate(o: &MerlOptions) -> Result<(), ExportError> {
    let l = &o.wavelengths_nm;
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    // Each wavelength costs 1.46 million evaluations of the model.
    if l.is_empty()
        || l.len() > MAX_WAVELENGTHS
        || l.iter().any(|v| !(lo..=hi).contains(v))
        || l.windows(2).any(|w| w[1] <= w[0])
    {
        return Err(ExportError::Option {
            field: "wavelengths_nm",
            message: format!(
                "1 to {MAX_WAVELENGTHS} strictly increasing wavelengths within {lo}–{hi} nm"
            ),
        });
    }
    if o.check_samples > crate::MAX_CHECK_SAMPLES {
        return Err(ExportError::Option {
            field: "check_samples",
            message: format!("{}: at most {}", o.check_samples, crate::MAX_CHECK_SAMPLES),
        });
    }
    if !(0.0..90.0).contains(&o.check_theta_max_deg) {
        return Err(ExportError::Option {
            field: "check_theta_max_deg",
            message: "must lie in [0, 90) degrees".into(),
        });
    }
    Ok(())
}

/// The MERL table of `model`, with its error estimate.
pub fn build(model: &(dyn Bxdf + Sync), o: &MerlOptions) -> Result<Exported, ExportError> {
    validate(o)?;
    if !crate::is_isotropic(model) {
        return Err(ExportError::Model(
            "the model is anisotropic (its BRDF changes when both directions turn about the \
             normal) and a MERL table is isotropic; export it as an RGL file, which keeps \
             the anisotropy of GGX and Beckmann"
                .into(),
        ));
    }
    let mut dropped = 0.0f64;
    let mut worst = (0.0, 0.0);
    for t in (0..=90)
        .map(|k| k as f64)
        .filter(|&t| t <= o.check_theta_max_deg)
    {
        let wi = crate::param::direction(t.to_radians(), 0.0);
        for &l in &o.wavelengths_nm {
            let w = model.specular(wi, l).weight;
            if w > dropped {
                dropped = w;
                worst = (t, l);
            }
        }
    }
    if dropped > crate::DELTA_TOLERANCE && !o.drop_specular {
        return Err(ExportError::Specular {
            weight: dropped,
            theta_i_deg: worst.0,
            lambda_nm: worst.1,
        });
    }
    let w = srgb_weights(&o.wavelengths_nm, o.illuminant);
    let planes = par_map(THETA_H, |ih| {
        let mut out = vec![[0.0f64; 3]; THETA_D * PHI_D];
        let mut fp = vec![(0.0, 0.0); o.wavelengths_nm.len()];
        for id in 0..THETA_D {
            for ip in 0..PHI_D {
                let (th, td, pd) = cell_centre(ih, id, ip);
                let (wi, wo) = from_half_diff(th, td, pd);
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    continue;
                }
                model.eval_pdf_many(wi, wo, &o.wavelengths_nm, &mut fp);
                out[id * PHI_D + ip] =
                    [0, 1, 2].map(|c| w.iter().zip(&fp).map(|(wk, f)| wk[c] * f.0).sum());
            }
        }
        out
    });
    let mut bytes = Vec::with_capacity(12 + 3 * CELLS * 8);
    for d in [THETA_H, THETA_D, PHI_D] {
        bytes.extend_from_slice(&(d as i32).to_le_bytes());
    }
    for c in 0..3 {
        for plane in &planes {
            for v in plane {
                bytes.extend_from_slice(&(v[c] / SCALE[c]).to_le_bytes());
            }
        }
    }
    let table = MerlTable::parse(&bytes)?;
    let checks = check_table(model, &table, o);
    let report = Report {
        format: "MERL .binary (linear sRGB)",
        resolution: "90 θh (√-spaced) × 90 θd × 180 φd cells, values at cell centres".into(),
        ndf: match o.illuminant {
            Illuminant::D65 => "CIE 1931 2° under D65 → linear sRGB",
            Illuminant::E => "CIE 1931 2° under illuminant E → linear sRGB",
        },
        bytes: bytes.len(),
        dropped_specular: dropped,
        unrepresented_nodes: 0,
        check_theta_max_deg: o.check_theta_max_deg,
        checks,
    };
    Ok(Exported { bytes, report })
}

/// Relative L1 errors per channel at incidences 0, 5, …, up to the checked
/// angle (a MERL table has no sampler: the cosine hemisphere stands in).
fn check_table(model: &(dyn Bxdf + Sync), table: &MerlTable, o: &MerlOptions) -> Vec<CheckPoint> {
    if o.check_samples == 0 {
        return Vec::new();
    }
    let nodes: Vec<f64> = (0..=18).map(|k| 5.0 * k as f64).collect();
    let fine = crate::color::FineRgb::new(o.illuminant);
    let angles = check::check_angles(&nodes, o.check_theta_max_deg);
    let per = par_map(angles.len(), |i| {
        let t = angles[i];
        let wi = crate::param::direction(t.to_radians(), 0.0);
        let truth = |wo: DVec3, out: &mut [f64]| {
            out.copy_from_slice(&fine.rgb(|l| model.eval(wi, wo, l)));
        };
        let approx = |wo: DVec3, out: &mut [f64]| out.copy_from_slice(&table.eval(wi, wo));
        let sides = Sides {
            model,
            sample_lambda_nm: 550.0,
            table_sample: &check::cosine_hemisphere,
            table_pdf: &check::cosine_pdf,
            truth: &truth,
            approx: &approx,
        };
        let r = check::estimate(
            wi,
            &sides,
            3,
            o.check_samples,
            &mut Rng::new(0x3e71 ^ i as u64),
        );
        r.into_iter()
            .enumerate()
            .map(|(c, v)| CheckPoint {
                theta_i_deg: t,
                phi_i_deg: 0.0,
                lambda: c as f64,
                albedo_model: v[0],
                albedo_table: v[1],
                rel_l1: v[2],
                rel_l1_se: v[3],
            })
            .collect::<Vec<_>>()
    });
    per.into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_diff_round_trips_and_cell_centres_map_to_their_cells() {
        for ih in (0..THETA_H).step_by(7) {
            for id in (0..THETA_D).step_by(11) {
                for ip in (0..PHI_D).step_by(13) {
                    let (th, td, pd) = cell_centre(ih, id, ip);
                    let (wi, wo) = from_half_diff(th, td, pd);
                    assert!((wi.length() - 1.0).abs() < 1e-12 && (wo.length() - 1.0).abs() < 1e-12);
                    let (a, b, c) = half_diff(wi, wo).unwrap();
                    assert!(
                        (a - th).abs() < 1e-9 && (b - td).abs() < 1e-9,
                        "{th} {td}: {a} {b}"
                    );
                    assert!((c - pd).abs() < 1e-9, "{pd} vs {c}");
                    assert_eq!(cell(a, b, c), ip + PHI_D * (id + THETA_D * ih));
                }
            }
        }
    }

    #[test]
    fn in_plane_mirror_geometry() {
        // θd is the angle between ωi and h; in the plane of incidence with
        // h at the normal, θd = θi.
        let wi = crate::param::direction(0.5, 0.0);
        let wo = crate::param::direction(0.5, PI);
        let (th, td, _) = half_diff(wi, wo).unwrap();
        assert!(th.abs() < 1e-12 && (td - 0.5).abs() < 1e-12);
    }

    #[test]
    fn malformed_files_are_refused_by_name() {
        assert!(
            MerlTable::parse(&[0; 5])
                .unwrap_err()
                .to_string()
                .contains("shorter")
        );
        let mut b: Vec<u8> = [90i32, 90, 360]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert!(
            MerlTable::parse(&b)
                .unwrap_err()
                .to_string()
                .contains("[90, 90, 180]")
        );
        b = [90i32, 90, 180]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        b.extend_from_slice(&[0; 64]);
        assert!(
            MerlTable::parse(&b)
                .unwrap_err()
                .to_string()
                .contains("truncated")
        );
    }
}
