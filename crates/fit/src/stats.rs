//! Height and slope statistics with the conventions of the data README: rms about the mean,
//! forward-difference slopes, Sdq over the common `(nx−1)×(ny−1)` region.

use crate::Topography;

/// Summary statistics of a (levelled) map or profile; NaN points are skipped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    /// Rms height about the global mean [m] (Sq; Rq for a profile).
    pub sq: f64,
    /// Rms height of each x-line about its own mean, pooled over lines [m].
    pub rq_lines: f64,
    /// Rms gradient `sqrt(mean(sx² + sy²))` (Sdq); for a profile the rms slope Rdq.
    pub sdq: f64,
    /// Rms forward-difference slope along x (Rdq_x).
    pub rdq_x: f64,
}

impl Stats {
    /// The rms slope used for scattering: Sdq for maps, Rdq for profiles.
    pub fn rms_slope(&self) -> f64 {
        self.sdq
    }
}

/// Compute [`Stats`].
pub fn compute(t: &Topography) -> Stats {
    let h = &t.heights;
    let (nx, ny) = (t.nx, t.ny);
    let (mut s, mut n) = (0.0, 0.0);
    for &v in h.iter().filter(|v| v.is_finite()) {
        s += v;
        n += 1.0;
    }
    let mean = s / n;
    let sq = (h
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| (v - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();

    let (mut acc, mut cnt) = (0.0, 0.0);
    for y in 0..ny {
        let line = t.line(y);
        let (ls, ln) = line
            .iter()
            .filter(|v| v.is_finite())
            .fold((0.0, 0.0), |(a, c), v| (a + v, c + 1.0));
        if ln == 0.0 {
            continue;
        }
        let m = ls / ln;
        acc += line
            .iter()
            .filter(|v| v.is_finite())
            .map(|v| (v - m).powi(2))
            .sum::<f64>();
        cnt += ln;
    }
    let rq_lines = (acc / cnt).sqrt();

    let (mut gx, mut nxs) = (0.0, 0.0);
    for y in 0..ny {
        for x in 0..nx.saturating_sub(1) {
            let d = (h[y * nx + x + 1] - h[y * nx + x]) / t.dx;
            if d.is_finite() {
                gx += d * d;
                nxs += 1.0;
            }
        }
    }
    let rdq_x = (gx / nxs).sqrt();
    let sdq = if ny == 1 {
        rdq_x
    } else {
        let (mut g, mut c) = (0.0, 0.0);
        for y in 0..ny - 1 {
            for x in 0..nx - 1 {
                let i = y * nx + x;
                let sx = (h[i + 1] - h[i]) / t.dx;
                let sy = (h[i + nx] - h[i]) / t.dy;
                let v = sx * sx + sy * sy;
                if v.is_finite() {
                    g += v;
                    c += 1.0;
                }
            }
        }
        (g / c).sqrt()
    };
    Stats {
        sq,
        rq_lines,
        sdq,
        rdq_x,
    }
}
