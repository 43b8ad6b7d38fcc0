//! The complex FFT under the FFTLog Hankel transforms (`hankel`) and the
//! 2-D transforms of a tabulated PSD (`fft2`): in-place, radix 2, twiddles
//! laid out per stage so that each stage's butterflies vectorise.

use alloc::vec::Vec;
use core::f64::consts::PI;

/// In-place iterative radix-2 FFT, X_k = Σ x_n e^{−2πikn/N}.
#[derive(Clone, Debug)]
pub(crate) struct Fft {
    n: usize,
    /// Twiddles e^{−2πik/len} for every stage len = 2, 4, …, n,
    /// concatenated (stage len starts at len/2 − 1): each stage reads a
    /// contiguous run instead of every (n/len)-th entry of one table.
    /// Real and imaginary parts apart, so a stage's loop loads them as
    /// vectors.
    tw_re: Vec<f64>,
    tw_im: Vec<f64>,
    rev: Vec<usize>,
}

impl Fft {
    /// The plan of length `n`, a power of two.
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
        let mut tw_re = Vec::with_capacity(n.saturating_sub(1));
        let mut tw_im = Vec::with_capacity(n.saturating_sub(1));
        let mut len = 2;
        while len <= n {
            // The same angles as one table of n/2 entries read with
            // stride n/len: k·(n/len)/n = k/len exactly.
            for k in 0..len / 2 {
                let (s, c) = libm::sincos(-2.0 * PI * (k * (n / len)) as f64 / n as f64);
                tw_re.push(c);
                tw_im.push(s);
            }
            len *= 2;
        }
        Fft {
            n,
            tw_re,
            tw_im,
            rev,
        }
    }

    /// Its length.
    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// The transform in place on the first n entries of `re`, `im`.
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
        if n >= 4 {
            // The first two stages (twiddles 1 and −i) as one radix-4
            // pass: as general stages their blocks of one and two
            // butterflies cost more in loop overhead than in arithmetic.
            for (r, i) in re.chunks_exact_mut(4).zip(im.chunks_exact_mut(4)) {
                let (a0r, a0i, a1r, a1i) = (r[0] + r[1], i[0] + i[1], r[0] - r[1], i[0] - i[1]);
                let (a2r, a2i, a3r, a3i) = (r[2] + r[3], i[2] + i[3], r[2] - r[3], i[2] - i[3]);
                r[0] = a0r + a2r;
                i[0] = a0i + a2i;
                r[2] = a0r - a2r;
                i[2] = a0i - a2i;
                // (a3r + i a3i)·(−i) = a3i − i a3r
                r[1] = a1r + a3i;
                i[1] = a1i - a3r;
                r[3] = a1r - a3i;
                i[3] = a1i + a3r;
            }
            len = 8;
        }
        while len <= n {
            let half = len / 2;
            let tw_re = &self.tw_re[half - 1..len - 1];
            let tw_im = &self.tw_im[half - 1..len - 1];
            for (block_re, block_im) in re.chunks_exact_mut(len).zip(im.chunks_exact_mut(len)) {
                let (a_re, b_re) = block_re.split_at_mut(half);
                let (a_im, b_im) = block_im.split_at_mut(half);
                butterflies(a_re, a_im, b_re, b_im, tw_re, tw_im);
            }
            len *= 2;
        }
    }
}

/// One run of radix-2 butterflies a, b ← a + w·b, a − w·b. Separate
/// `&mut` arguments of one length let the compiler vectorise the loop
/// (no aliasing or bounds checks left in it).
#[inline]
fn butterflies(
    a_re: &mut [f64],
    a_im: &mut [f64],
    b_re: &mut [f64],
    b_im: &mut [f64],
    w_re: &[f64],
    w_im: &[f64],
) {
    let n = a_re.len();
    let (a_im, b_re, b_im) = (&mut a_im[..n], &mut b_re[..n], &mut b_im[..n]);
    let (w_re, w_im) = (&w_re[..n], &w_im[..n]);
    for k in 0..n {
        let (br, bi) = (b_re[k], b_im[k]);
        let tr = br * w_re[k] - bi * w_im[k];
        let ti = br * w_im[k] + bi * w_re[k];
        b_re[k] = a_re[k] - tr;
        b_im[k] = a_im[k] - ti;
        a_re[k] += tr;
        a_im[k] += ti;
    }
}
