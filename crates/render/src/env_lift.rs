//! The lift of an environment map's linear-sRGB texels to spectra.

use crate::color::{SRGB_TO_XYZ, mul};
use crate::spectrum::{Cie, LAMBDA_MIN};

/// Lifts linear sRGB to the spectrum `Σ cᵢ·cmfᵢ(λ)` whose XYZ (with the
/// film's normalisation ∫S·cmf/∫ȳ) is exactly that of the RGB value: the
/// coefficients solve the 3×3 Gram system of the CIE functions. The lift is
/// exact in colour and smooth in λ; saturated colours may go negative at some
/// wavelengths, which a linear estimator handles without bias.
#[derive(Clone, Debug)]
pub struct RgbLift {
    m: [[f64; 3]; 3],
}

impl RgbLift {
    /// Builds the lift from the CIE table.
    pub fn new() -> RgbLift {
        let cie = Cie::get();
        let mut g = [[0.0; 3]; 3];
        for i in 0..=470 {
            let l = LAMBDA_MIN + i as f64;
            let w = if i == 0 || i == 470 { 0.5 } else { 1.0 };
            let c = cie.xyz(l);
            for a in 0..3 {
                for b in 0..3 {
                    g[a][b] += w * c[a] * c[b] / cie.y_integral();
                }
            }
        }
        let gi = invert3(g);
        let mut m = [[0.0; 3]; 3];
        for (a, row) in m.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| gi[a][k] * SRGB_TO_XYZ[k][b]).sum();
            }
        }
        RgbLift { m }
    }

    /// CMF coefficients of a linear sRGB value.
    pub fn coefficients(&self, rgb: [f64; 3]) -> [f64; 3] {
        mul(&self.m, rgb)
    }
}

impl Default for RgbLift {
    fn default() -> Self {
        RgbLift::new()
    }
}

fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let c =
        |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    [
        [
            c(1, 1, 2, 2) / det,
            -c(0, 1, 2, 2) / det,
            c(0, 1, 1, 2) / det,
        ],
        [
            -c(1, 0, 2, 2) / det,
            c(0, 0, 2, 2) / det,
            -c(0, 0, 1, 2) / det,
        ],
        [
            c(1, 0, 2, 1) / det,
            -c(0, 0, 2, 1) / det,
            c(0, 0, 1, 1) / det,
        ],
    ]
}
