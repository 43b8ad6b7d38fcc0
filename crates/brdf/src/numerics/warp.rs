//! Warps of the unit square onto other domains, for samplers.

use crate::numerics::math::sincos_2pi;

/// Shirley–Chiu concentric map of the unit square onto the unit disk:
/// area-preserving (uniform in, uniform out) and of low distortion, so the
/// strata of a stratified or low-discrepancy 2D draw stay compact on the
/// disk, where the polar map (r = √u₀, φ = 2πu₁) stretches them into thin
/// wedges near the centre and long arcs near the rim. Returns (x, y) with
/// x² + y² ≤ 1.
///
/// Branch-free: which of |a|, |b| is larger is a coin toss for random
/// draws, so a branch would mispredict half the time.
#[inline]
pub fn concentric_disk(u: [f64; 2]) -> [f64; 2] {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    let a_major = a.abs() > b.abs();
    let (r, minor) = if a_major { (a, b) } else { (b, a) };
    // |minor/r| ≤ 1; r = 0 only at the centre, where either answer is 0.
    let t = if r != 0.0 { minor / r } else { 0.0 };
    // θ = (π/4)·t, i.e. 2π·(t/8) with t/8 ∈ [−1/8, 1/8].
    let (s, c) = sincos_2pi(0.125 * t);
    // |a| > |b|: φ = θ; otherwise φ = π/2 − θ, (cos φ, sin φ) = (sin θ, cos θ).
    if a_major {
        [r * c, r * s]
    } else {
        [r * s, r * c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_is_the_shirley_chiu_map() {
        // Radius max(|a|, |b|) and the polar angle of the square's point
        // mapped linearly per octant, against atan2 (independent of the
        // polynomial), including the centre, edges and corners.
        let n = 400;
        for i in 0..=n {
            for j in 0..=n {
                let u = [i as f64 / n as f64, j as f64 / n as f64];
                let [x, y] = concentric_disk(u);
                let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
                let r = a.abs().max(b.abs());
                assert!((libm::hypot(x, y) - r).abs() < 1e-15, "{u:?}");
                if r == 0.0 {
                    assert_eq!([x, y], [0.0, 0.0]);
                    continue;
                }
                let phi = if a.abs() > b.abs() {
                    core::f64::consts::FRAC_PI_4 * (b / a)
                        + if a < 0.0 { core::f64::consts::PI } else { 0.0 }
                } else {
                    core::f64::consts::FRAC_PI_2 - core::f64::consts::FRAC_PI_4 * (a / b)
                        + if b < 0.0 { core::f64::consts::PI } else { 0.0 }
                };
                let (ws, wc) = libm::sincos(phi);
                assert!(
                    (x - r * wc).abs() < 1e-15 && (y - r * ws).abs() < 1e-15,
                    "{u:?}"
                );
            }
        }
    }

    #[test]
    fn concentric_disk_preserves_area() {
        // Cell midpoints of a fine grid of the square land uniformly on the
        // disk: equal counts in 8 rings of equal area × 16 sectors.
        let n = 1024;
        let mut counts = [[0u32; 16]; 8];
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                let [x, y] = concentric_disk(u);
                let ring = ((x * x + y * y) * 8.0) as usize;
                let phi = libm::atan2(y, x);
                let phi = if phi < 0.0 {
                    phi + core::f64::consts::TAU
                } else {
                    phi
                };
                let sector = (phi / core::f64::consts::TAU * 16.0) as usize;
                counts[ring.min(7)][sector.min(15)] += 1;
            }
        }
        let want = (n * n) as f64 / 128.0;
        for row in counts {
            for c in row {
                // Only midpoints of cells cut by a ring or sector edge can
                // land on the wrong side (≈ 1 % here); a map off uniform by a
                // radial factor of 1.1 moves the inner rings by 10 %.
                assert!((c as f64 - want).abs() < 0.02 * want, "{c} vs {want}");
            }
        }
    }
}
