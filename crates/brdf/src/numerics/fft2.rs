//! A 2-D discrete Fourier transform of power-of-two sides, for the full GHS
//! of a tabulated 2-D PSD (`wave::ghs_psd2d_table`).
//!
//! X[k, l] = Σ_{m, n} x[m, n] e^{−2πi(km/N_x + ln/N_y)}, rows of length N_x
//! first, then columns, each by the 1-D [`Fft`] the FFTLog transforms use.

use alloc::vec;

use super::fft::Fft;

/// Plans for an N_x × N_y transform (row-major, row length N_x).
#[derive(Clone, Debug)]
pub(crate) struct Fft2 {
    x: Fft,
    y: Fft,
}

impl Fft2 {
    pub(crate) fn new(nx: usize, ny: usize) -> Self {
        Fft2 {
            x: Fft::new(nx),
            y: Fft::new(ny),
        }
    }

    /// In place on `re`, `im` of length N_x N_y.
    pub(crate) fn run(&self, re: &mut [f64], im: &mut [f64]) {
        let (nx, ny) = (self.x.len(), self.y.len());
        for (r, i) in re.chunks_exact_mut(nx).zip(im.chunks_exact_mut(nx)) {
            self.x.run(r, i);
        }
        let (mut cr, mut ci) = (vec![0.0; ny], vec![0.0; ny]);
        for col in 0..nx {
            for row in 0..ny {
                cr[row] = re[row * nx + col];
                ci[row] = im[row * nx + col];
            }
            self.y.run(&mut cr, &mut ci);
            for row in 0..ny {
                re[row * nx + col] = cr[row];
                im[row * nx + col] = ci[row];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use core::f64::consts::PI;

    /// The FFT against the defining sum, on a non-symmetric input.
    #[test]
    fn matches_the_direct_sum() {
        let (nx, ny) = (8, 4);
        let x: Vec<f64> = (0..nx * ny)
            .map(|i| libm::sin(i as f64 * 0.7) + 0.1 * i as f64)
            .collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; nx * ny]);
        Fft2::new(nx, ny).run(&mut re, &mut im);
        for k in 0..nx {
            for l in 0..ny {
                let (mut sr, mut si) = (0.0, 0.0);
                for m in 0..nx {
                    for n in 0..ny {
                        let ph =
                            -2.0 * PI * ((k * m) as f64 / nx as f64 + (l * n) as f64 / ny as f64);
                        sr += x[n * nx + m] * libm::cos(ph);
                        si += x[n * nx + m] * libm::sin(ph);
                    }
                }
                assert!((re[l * nx + k] - sr).abs() < 1e-10, "{k} {l}");
                assert!((im[l * nx + k] - si).abs() < 1e-10, "{k} {l}");
            }
        }
    }
}
