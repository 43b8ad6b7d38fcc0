//! Spectra to colour: CIE 1931 2° colour matching functions and linear sRGB.
//!
//! A spectral quantity sampled at the export's wavelengths λk is taken as
//! piecewise linear between them (constant beyond the ends) and integrated
//! against x̄, ȳ, z̄ times an illuminant at the CIE tables' 1 nm steps, over
//! 360–830 nm. The illuminant is normalised so that a reflectance of 1 has
//! Y = 1; under D65, sRGB's white point, it is then sRGB (1, 1, 1) to 1e-4.
//! So a BRDF f(λ) becomes the linear sRGB "colour of f" a renderer working
//! in sRGB under daylight would use.

use std::sync::OnceLock;

/// The light under which spectra become colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Illuminant {
    /// CIE standard illuminant D65 (sRGB's white; the default).
    #[default]
    D65,
    /// Equal energy (illuminant E): a flat reflectance is then slightly pink
    /// in sRGB, (1.205, 0.948, 0.909).
    E,
}

/// XYZ → linear sRGB (IEC 61966-2-1, D65 white).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266_0, 1.876_010_8, 0.041_556_0],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

struct Tables {
    /// 360..=830 nm at 1 nm.
    lambda: Vec<f64>,
    xyz: Vec<[f64; 3]>,
    d65: Vec<f64>,
}

fn parse(text: &str, cols: usize) -> Vec<Vec<f64>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse().unwrap_or(f64::NAN))
                .collect();
            debug_assert_eq!(v.len(), cols);
            v
        })
        .collect()
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let cmf = parse(
            include_str!("../../../data/spectra/cie1931_2deg_xyz.csv"),
            4,
        );
        let d65 = parse(include_str!("../../../data/spectra/illuminant_D65.csv"), 2);
        let lambda: Vec<f64> = cmf.iter().map(|r| r[0]).collect();
        let xyz = cmf.iter().map(|r| [r[1], r[2], r[3]]).collect();
        let d65 = lambda
            .iter()
            .map(|&l| {
                d65.iter()
                    .find(|r| (r[0] - l).abs() < 1e-9)
                    .map_or(f64::NAN, |r| r[1])
            })
            .collect();
        Tables { lambda, xyz, d65 }
    })
}

/// Weight of sample k at wavelength `l` for samples at `lambdas` (strictly
/// increasing): the hat function of linear interpolation, flat outside.
fn hat(lambdas: &[f64], k: usize, l: f64) -> f64 {
    let n = lambdas.len();
    if n == 1 {
        return 1.0;
    }
    if l <= lambdas[0] {
        return if k == 0 { 1.0 } else { 0.0 };
    }
    if l >= lambdas[n - 1] {
        return if k == n - 1 { 1.0 } else { 0.0 };
    }
    let j = lambdas.partition_point(|&x| x <= l) - 1;
    let t = (l - lambdas[j]) / (lambdas[j + 1] - lambdas[j]);
    if k == j {
        1.0 - t
    } else if k == j + 1 {
        t
    } else {
        0.0
    }
}

/// Per sample wavelength, the weights w_k with XYZ = Σ_k w_k s(λk) for a
/// spectrum s sampled at `lambdas_nm`, under `illum` normalised to Y = 1
/// for s ≡ 1.
pub fn xyz_weights(lambdas_nm: &[f64], illum: Illuminant) -> Vec<[f64; 3]> {
    let t = tables();
    let e = |i: usize| match illum {
        Illuminant::D65 => t.d65[i],
        Illuminant::E => 1.0,
    };
    let norm: f64 = (0..t.lambda.len()).map(|i| e(i) * t.xyz[i][1]).sum();
    (0..lambdas_nm.len())
        .map(|k| {
            let mut w = [0.0; 3];
            for (i, &l) in t.lambda.iter().enumerate() {
                let h = hat(lambdas_nm, k, l) * e(i) / norm;
                for (wc, xc) in w.iter_mut().zip(t.xyz[i]) {
                    *wc += h * xc;
                }
            }
            w
        })
        .collect()
}

/// As [`xyz_weights`], for linear sRGB.
pub fn srgb_weights(lambdas_nm: &[f64], illum: Illuminant) -> Vec<[f64; 3]> {
    xyz_weights(lambdas_nm, illum)
        .into_iter()
        .map(|w| {
            let mut o = [0.0; 3];
            for (r, row) in XYZ_TO_SRGB.iter().enumerate() {
                o[r] = row[0] * w[0] + row[1] * w[1] + row[2] * w[2];
            }
            o
        })
        .collect()
}

/// The linear sRGB of a spectrum sampled every 5 nm over 360–830 nm: the
/// reference the RGB exports' error estimates compare with, finer than any
/// export's own wavelengths so that their spectral quadrature is part of the
/// measured error.
pub struct FineRgb {
    lambdas_nm: Vec<f64>,
    weights: Vec<[f64; 3]>,
}

impl FineRgb {
    /// The 5 nm weights under `illum`.
    pub fn new(illum: Illuminant) -> FineRgb {
        let lambdas_nm: Vec<f64> = (0..=94).map(|k| 360.0 + 5.0 * k as f64).collect();
        let weights = srgb_weights(&lambdas_nm, illum);
        FineRgb {
            lambdas_nm,
            weights,
        }
    }

    /// Linear sRGB of the spectrum `f(λ nm)`.
    pub fn rgb(&self, f: impl Fn(f64) -> f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (&l, w) in self.lambdas_nm.iter().zip(&self.weights) {
            let v = f(l);
            for c in 0..3 {
                out[c] += w[c] * v;
            }
        }
        out
    }
}

/// Luminance (Y) weights of `lambdas_nm` under `illum`.
pub fn luminance_weights(lambdas_nm: &[f64], illum: Illuminant) -> Vec<f64> {
    xyz_weights(lambdas_nm, illum)
        .iter()
        .map(|w| w[1])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(step: f64) -> Vec<f64> {
        let n = ((830.0 - 360.0) / step).round() as usize + 1;
        (0..n).map(|k| 360.0 + step * k as f64).collect()
    }

    #[test]
    fn a_flat_reflectance_is_white_under_d65() {
        for step in [1.0, 5.0, 10.0, 47.0] {
            let l = grid(step);
            let rgb: [f64; 3] = srgb_weights(&l, Illuminant::D65)
                .iter()
                .fold([0.0; 3], |a, w| [a[0] + w[0], a[1] + w[1], a[2] + w[2]]);
            for c in rgb {
                assert!((c - 1.0).abs() < 1e-3, "step {step}: {rgb:?}");
            }
        }
        let e: [f64; 3] = srgb_weights(&grid(1.0), Illuminant::E)
            .iter()
            .fold([0.0; 3], |a, w| [a[0] + w[0], a[1] + w[1], a[2] + w[2]]);
        assert!(
            (e[0] - 1.205).abs() < 2e-3 && (e[1] - 0.948).abs() < 2e-3,
            "{e:?}"
        );
    }

    #[test]
    fn copper_colour_matches_the_data_readme() {
        // data/spectra/README.md: Cu under D65 (2°) has XYZ (0.701, 0.681, 0.589).
        let l = grid(1.0);
        let ior = brdf::Ior::metal(brdf::Metal::Cu);
        let w = xyz_weights(&l, Illuminant::D65);
        let mut xyz = [0.0; 3];
        for (k, &lk) in l.iter().enumerate() {
            let (n, kk) = ior.at(lk);
            let r = ((n - 1.0).powi(2) + kk * kk) / ((n + 1.0).powi(2) + kk * kk);
            for c in 0..3 {
                xyz[c] += w[k][c] * r;
            }
        }
        for (a, b) in xyz.iter().zip([0.701, 0.681, 0.589]) {
            assert!((a - b).abs() < 1.5e-3, "{xyz:?}");
        }
    }
}
