//! Filling invalid (NaN) points by harmonic interpolation: the filled values solve Laplace's
//! equation with the valid points as fixed boundary values (mirror/Neumann at the map
//! edges). This is what the reference statistics of the data README use.

use crate::{FitError, Topography};

/// Fill NaN points in place; returns how many were filled.
pub fn harmonic(topo: &mut Topography) -> Result<usize, FitError> {
    let (nx, ny) = (topo.nx, topo.ny);
    let h = &mut topo.heights;
    let holes: Vec<usize> = (0..h.len()).filter(|&i| !h[i].is_finite()).collect();
    if holes.is_empty() {
        return Ok(0);
    }
    if holes.len() == h.len() {
        return Err(FitError::data(
            "filling invalid points",
            "every point of the map is invalid",
        ));
    }
    let valid: Vec<f64> = h.iter().copied().filter(|v| v.is_finite()).collect();
    let mean = valid.iter().sum::<f64>() / valid.len() as f64;
    for &i in &holes {
        h[i] = mean;
    }
    // Successive over-relaxation restricted to the holes.
    let omega = 1.9;
    let scale = valid
        .iter()
        .map(|v| (v - mean).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // Bound the work (≈ 5·10⁸ point updates) so a map that is mostly holes cannot stall
    // the command; small holes converge long before the cap.
    let sweeps = (500_000_000 / holes.len()).clamp(200, 20_000);
    for _sweep in 0..sweeps {
        let mut max_change: f64 = 0.0;
        for &i in &holes {
            let (x, y) = (i % nx, i / nx);
            let mut sum = 0.0;
            let mut cnt = 0.0;
            if x > 0 {
                sum += h[i - 1];
                cnt += 1.0;
            }
            if x + 1 < nx {
                sum += h[i + 1];
                cnt += 1.0;
            }
            if y > 0 {
                sum += h[i - nx];
                cnt += 1.0;
            }
            if y + 1 < ny {
                sum += h[i + nx];
                cnt += 1.0;
            }
            if cnt > 0.0 {
                let new = h[i] + omega * (sum / cnt - h[i]);
                max_change = max_change.max((new - h[i]).abs());
                h[i] = new;
            }
        }
        if max_change <= 1e-12 * scale {
            break;
        }
    }
    Ok(holes.len())
}
