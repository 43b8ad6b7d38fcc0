//! Two renders of one scene compared camera sample by camera sample.

use render::Scene;
use render::integrator::sample_pixel;

/// Per channel over the image: the means of the two scenes' estimates and
/// the mean of their difference with its standard error. Both draw the same
/// random numbers for the same sample (the wavelengths have their own
/// reserved draw), so the difference is paired: its error is that of the
/// part of the estimate that differs (the spectral noise), which makes the
/// comparison far sharper than two independent means would be. The error
/// comes from per-pixel variances, so pixel-to-pixel differences do not
/// inflate it.
pub fn paired(a: &Scene, b: &Scene, spp: u64) -> [(f64, f64, f64, f64); 3] {
    let (w, h) = (a.camera.width, a.camera.height);
    let pixels = (w * h) as f64;
    let mut out = [(0.0, 0.0, 0.0, 0.0); 3];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [[0.0; 3]; 3];
            let mut sq = [0.0; 3];
            for s in 0..spp {
                let va = sample_pixel(a, x, y, s);
                let vb = sample_pixel(b, x, y, s);
                for c in 0..3 {
                    let d = va[c] - vb[c];
                    sum[0][c] += va[c];
                    sum[1][c] += vb[c];
                    sum[2][c] += d;
                    sq[c] += d * d;
                }
            }
            let n = spp as f64;
            for c in 0..3 {
                let mean = sum[2][c] / n;
                let var = (sq[c] / n - mean * mean).max(0.0) * n / (n - 1.0);
                out[c].0 += sum[0][c] / n / pixels;
                out[c].1 += sum[1][c] / n / pixels;
                out[c].2 += mean / pixels;
                out[c].3 += var / n / (pixels * pixels);
            }
        }
    }
    out.map(|(ma, mb, d, v)| (ma, mb, d, v.sqrt()))
}

/// The variance of a pixel's `spp`-sample estimate of the green channel,
/// from `batches` consecutive batches of samples, averaged over the image:
/// what a change that lowers the error must lower.
#[allow(dead_code)] // Not every test crate that includes this module uses it.
pub fn batch_variance(s: &Scene, batches: u64, spp: u64) -> f64 {
    let (w, h) = (s.camera.width, s.camera.height);
    let mut v = 0.0;
    for y in 0..h {
        for x in 0..w {
            let est: Vec<f64> = (0..batches)
                .map(|b| {
                    (0..spp)
                        .map(|i| sample_pixel(s, x, y, b * spp + i)[1])
                        .sum::<f64>()
                        / spp as f64
                })
                .collect();
            let mean = est.iter().sum::<f64>() / batches as f64;
            v += est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (batches - 1) as f64;
        }
    }
    v / (w * h) as f64
}
