//! A 2-D discrete Fourier transform of power-of-two sides, for the full GHS
//! of a tabulated 2-D PSD (`wave::ghs_psd2d_table`).
//!
//! X[k, l] = Σ_{m, n} x[m, n] e^{−2πi(km/N_x + ln/N_y)}, rows of length N_x
//! first, then columns. The 1-D transform is an iterative radix-2 FFT. (The
//! FFTLog's 1-D FFT is private to `hankel`; the transforms here are of real,
//! even sequences, for which the sign of the exponent does not matter.)

use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;

/// A 1-D radix-2 FFT plan of length n (a power of two).
#[derive(Clone, Debug)]
pub(crate) struct Fft1 {
    n: usize,
    /// e^{−2πik/n}, k < n/2.
    tw: Vec<(f64, f64)>,
    rev: Vec<usize>,
}

impl Fft1 {
    pub(crate) fn new(n: usize) -> Self {
        assert!(n.is_power_of_two());
        let bits = n.trailing_zeros();
        let rev = (0..n)
            .map(|i| {
                if bits == 0 {
                    0
                } else {
                    i.reverse_bits() >> (usize::BITS - bits)
                }
            })
            .collect();
        let tw = (0..n / 2)
            .map(|k| {
                let (s, c) = libm::sincos(-2.0 * PI * k as f64 / n as f64);
                (c, s)
            })
            .collect();
        Fft1 { n, tw, rev }
    }

    /// In place on the first n entries of `re`, `im`.
    pub(crate) fn run(&self, re: &mut [f64], im: &mut [f64]) {
        let n = self.n;
        let (re, im) = (&mut re[..n], &mut im[..n]);
        for i in 0..n {
            let j = self.rev[i];
            if j > i {
                re.swap(i, j);
                im.swap(i, j);
            }
        }
        let mut len = 2;
        while len <= n {
            let half = len / 2;
            let stride = n / len;
            for start in (0..n).step_by(len) {
                for k in 0..half {
                    let (wr, wi) = self.tw[k * stride];
                    let (a, b) = (start + k, start + k + half);
                    let tr = re[b] * wr - im[b] * wi;
                    let ti = re[b] * wi + im[b] * wr;
                    re[b] = re[a] - tr;
                    im[b] = im[a] - ti;
                    re[a] += tr;
                    im[a] += ti;
                }
            }
            len *= 2;
        }
    }
}

/// Plans for an N_x × N_y transform (row-major, row length N_x).
#[derive(Clone, Debug)]
pub(crate) struct Fft2 {
    x: Fft1,
    y: Fft1,
}

impl Fft2 {
    pub(crate) fn new(nx: usize, ny: usize) -> Self {
        Fft2 {
            x: Fft1::new(nx),
            y: Fft1::new(ny),
        }
    }

    /// In place on `re`, `im` of length N_x N_y.
    pub(crate) fn run(&self, re: &mut [f64], im: &mut [f64]) {
        let (nx, ny) = (self.x.n, self.y.n);
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
