//! Phase-randomised Gaussian surrogate of a measured map: the same power spectrum, Gaussian
//! heights. Comparing the explicit BRDF of a map with that of its surrogate isolates what the
//! Gaussian-height assumption of GHS costs, with the spectrum, anisotropy, window and
//! resolution held fixed.
//!
//! A measured map is mirror-extended to `2nx × 2ny` (even, so no edge jump adds spurious
//! power), its Fourier amplitudes are kept and its phases replaced by those of white Gaussian
//! noise (uniform and Hermitian-symmetric, so the result is real), and the first `nx × ny`
//! block is returned; the block is not periodic, so analyse it with a taper. A periodic map
//! ([`gaussian_surrogate_periodic`], e.g. a synthetic one) is randomised as it is and keeps its
//! periodogram exactly. Every Fourier mode then has an independent uniform phase, so the
//! heights are Gaussian by the central limit theorem while the periodogram is unchanged.

use crate::two_scale::{extended, first_block};
use crate::{FitError, Topography};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// Gaussian surrogate of a levelled, NaN-free measured map or profile (mirror-extended).
pub fn gaussian_surrogate(t: &Topography, seed: u64) -> Result<Topography, FitError> {
    surrogate(t, seed, true)
}

/// Gaussian surrogate of a periodic map or profile, with exactly the same periodogram.
pub fn gaussian_surrogate_periodic(t: &Topography, seed: u64) -> Result<Topography, FitError> {
    surrogate(t, seed, false)
}

fn surrogate(t: &Topography, seed: u64, mirror: bool) -> Result<Topography, FitError> {
    crate::field_spectrum::check(t)?;
    let (mut buf, mx, my) = extended(t, mirror);
    let mut noise = crate::rng::white_noise(mx * my, seed);
    let mut planner = FftPlanner::<f64>::new();
    crate::fft::fft2(&mut buf, mx, my, &mut planner, false);
    crate::fft::fft2(&mut noise, mx, my, &mut planner, false);
    for (b, z) in buf.iter_mut().zip(&noise) {
        let m = z.norm();
        *b = if m > 0.0 {
            *z * (b.norm() / m)
        } else {
            Complex::new(b.norm(), 0.0)
        };
    }
    crate::fft::fft2(&mut buf, mx, my, &mut planner, true);
    let mut out = first_block(t, &buf, mx, my);
    out.channel = format!("{} (Gaussian surrogate)", t.channel);
    Ok(out)
}
