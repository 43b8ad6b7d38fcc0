//! The spectral side of the render-vs-`brdf` reference tests, computed from
//! the data files themselves (not from the renderer's tables): CIE 1931 ȳ and
//! D65 at 1 nm, D65 normalised to unit luminance by the trapezoid rule, as
//! the renderer documents.

use std::path::PathBuf;

/// Rows of a CSV under `data/spectra/`, header skipped.
pub fn read_csv(name: &str) -> Vec<Vec<f64>> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data/spectra")
        .join(name);
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
        .collect()
}

/// CIE 1931 rows (λ, x̄, ȳ, z̄) and unit-luminance D65.
pub struct Spectra {
    /// CIE 1931 2° rows at 1 nm.
    pub cie: Vec<Vec<f64>>,
    d65: Vec<Vec<f64>>,
    /// ∫ȳ dλ (trapezoid).
    pub y_int: f64,
    d65_lum: f64,
}

impl Spectra {
    /// Reads the tables.
    pub fn load() -> Spectra {
        let cie = read_csv("cie1931_2deg_xyz.csv");
        let d65 = read_csv("illuminant_D65.csv");
        let y_int: f64 = cie.windows(2).map(|w| 0.5 * (w[0][2] + w[1][2])).sum();
        let mut s = Spectra {
            cie,
            d65,
            y_int,
            d65_lum: 1.0,
        };
        s.d65_lum = (0..s.cie.len())
            .map(|i| s.trapezoid_weight(i) * s.d65_raw(s.cie[i][0]) * s.cie[i][2])
            .sum::<f64>()
            / y_int;
        s
    }

    /// Trapezoid weight of CIE row i (ends halved).
    pub fn trapezoid_weight(&self, i: usize) -> f64 {
        if i == 0 || i == self.cie.len() - 1 {
            0.5
        } else {
            1.0
        }
    }

    fn d65_raw(&self, l: f64) -> f64 {
        self.d65.iter().find(|r| r[0] == l).unwrap()[1]
    }

    /// D65 at integer λ, scaled to unit luminance.
    pub fn d65(&self, l: f64) -> f64 {
        self.d65_raw(l) / self.d65_lum
    }
}
