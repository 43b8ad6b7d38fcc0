//! Cropping and band-limited upsampling of height maps, for the explicit BRDF of scans whose
//! pixels are too coarse for the wave field.
//!
//! The field `exp(−i q h)` needs `q · |∇h| · dx ≲ 1` rad per pixel, and the pixel pitch limits
//! the exit angles to `|Δ sinθ| ≤ λ/(2dx)`. A profilometer map whose spectrum has already
//! rolled off at the pixel scale (the instrument's transfer function) is a band-limited
//! function, so trigonometric (FFT zero-padding) interpolation reconstructs it between the
//! pixels without inventing roughness: the interpolated map has the same spectrum up to the
//! old Nyquist frequency and none above it. Each axis is interpolated separately (the 2-D
//! zero padding is separable), after an even mirror extension so the map's edges do not wrap
//! onto each other. The original samples are reproduced exactly (to round-off).

use crate::{FitError, Topography};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// The central `nx × ny` block of a map (the whole axis where the map is smaller).
pub fn crop_center(t: &Topography, nx: usize, ny: usize) -> Topography {
    let (cx, cy) = (nx.min(t.nx).max(1), ny.min(t.ny).max(1));
    let (x0, y0) = ((t.nx - cx) / 2, (t.ny - cy) / 2);
    let mut heights = Vec::with_capacity(cx * cy);
    for y in y0..y0 + cy {
        heights.extend_from_slice(&t.heights[y * t.nx + x0..y * t.nx + x0 + cx]);
    }
    Topography {
        nx: cx,
        ny: cy,
        heights,
        ..t.clone()
    }
}

/// Band-limited upsampling by an integer `factor` along both axes (along x only for a
/// profile): pixel pitch `dx/factor`, `factor·nx × factor·ny` points.
pub fn upsample(t: &Topography, factor: usize) -> Result<Topography, FitError> {
    crate::field_spectrum::check(t)?;
    if factor == 0 || factor > 64 {
        return Err(FitError::data(
            "upsampling",
            format!("factor {factor} must lie in 1..=64"),
        ));
    }
    if factor == 1 {
        return Ok(t.clone());
    }
    let (nx, ny) = (t.nx, t.ny);
    let fy = if ny == 1 { 1 } else { factor };
    let (mx, my) = (nx * factor, ny * fy);
    let mut planner = FftPlanner::<f64>::new();
    let rows: Vec<Vec<f64>> = t
        .heights
        .chunks(nx)
        .map(|r| upsample_line(r, factor, &mut planner))
        .collect();
    let mut heights = vec![0.0; mx * my];
    if ny == 1 {
        heights.copy_from_slice(&rows[0]);
    } else {
        let mut col = vec![0.0; ny];
        for x in 0..mx {
            for (c, r) in col.iter_mut().zip(&rows) {
                *c = r[x];
            }
            for (y, v) in upsample_line(&col, factor, &mut planner)
                .into_iter()
                .enumerate()
            {
                heights[y * mx + x] = v;
            }
        }
    }
    Ok(Topography {
        nx: mx,
        ny: my,
        dx: t.dx / factor as f64,
        dy: if ny == 1 {
            t.dx / factor as f64
        } else {
            t.dy / factor as f64
        },
        heights,
        channel: format!("{} (upsampled ×{factor})", t.channel),
        format: t.format,
    })
}

/// Trigonometric interpolation of the even extension of `line` at `factor`× the rate.
fn upsample_line(line: &[f64], factor: usize, planner: &mut FftPlanner<f64>) -> Vec<f64> {
    let n = line.len();
    let m = 2 * n;
    let mut buf: Vec<Complex<f64>> = line
        .iter()
        .chain(line.iter().rev())
        .map(|v| Complex::new(*v, 0.0))
        .collect();
    planner.plan_fft_forward(m).process(&mut buf);
    let big = m * factor;
    let mut pad = vec![Complex::new(0.0, 0.0); big];
    // Bins 0..n−1 and −(n−1)..−1 carry over; the Nyquist bin n is split between ±n.
    pad[..n].copy_from_slice(&buf[..n]);
    pad[big - (n - 1)..].copy_from_slice(&buf[n + 1..]);
    pad[n] = buf[n] * 0.5;
    pad[big - n] += buf[n] * 0.5;
    planner.plan_fft_inverse(big).process(&mut pad);
    pad[..n * factor].iter().map(|c| c.re / m as f64).collect()
}
