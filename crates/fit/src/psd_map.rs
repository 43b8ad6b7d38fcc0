//! The map's 2-D PSD on a coarse regular grid (`[psd.map]`, physics.md §15.4): what
//! `model = "measured_psd2d_ssa"` reads for a scan whose 2-D PSD is not constant on
//! ellipses.
//!
//! The Hann-windowed periodogram of [`crate::kc2d::periodogram`] (`∫P d²ζ = σ²`) is
//! averaged over boxes of b_x × b_y frequency bins centred on the nodes (i b_x Δζx,
//! j b_y Δζy), with b chosen so that each half axis has at most [`HALF_NODES`] nodes up to
//! the axis' Nyquist frequency, and at least [`MIN_BOX_BINS`] bins per box (a periodogram
//! bin scatters by ±100 %; a mean of n bins by 1/√n). The box mean is the smoothing (the
//! radial table's ±0.05-decade average plays that part there). Excluded from every box,
//! as from the anisotropic fit's cells: the DC bin and the ζx = 0 column (a scanning
//! instrument's line offsets and glitches, removed by line levelling). Only the half plane
//! ζy ≥ 0 is written (P(−ζ) = P(ζ)); row ζy = 0 is made even by the reader.
//!
//! Beyond the grid (above the Nyquist frequency) the model continues each ray from the edge
//! as s^−α with α the tail exponent of the map's smoothed radial table
//! ([`crate::candidates::smoothed_table`]): an assumption, reported with the share of σ² it
//! holds.

use crate::kc2d::periodogram;
use crate::{FitError, Topography};

/// Most nodes on a half axis (the grid has at most 2·43 cells across). With
/// [`MIN_BOX_BINS`] it gives 3 × 3 boxes on a 256² map: against the explicit BRDF of
/// crossing-lay maps (physics.md §15.4) 4 × 4 boxes smeared a lay one bin wide and 2 × 2
/// or single bins kept the bins' scatter.
pub const HALF_NODES: usize = 43;
/// Fewest periodogram bins in a node's box.
pub const MIN_BOX_BINS: usize = 9;

/// The grid, µm units (rad/µm, µm⁴), as `[psd.map]` holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct PsdMapGrid {
    /// Nodes on each half of the ζx axis.
    pub half_nx: usize,
    /// Node rows above ζy = 0.
    pub half_ny: usize,
    /// Node step along ζx [rad/µm].
    pub dzx_rad_per_um: f64,
    /// Node step along ζy [rad/µm].
    pub dzy_rad_per_um: f64,
    /// P₂ at the nodes [µm⁴], rows ζy = 0, Δζy, …, each from ζx = −half_nx·Δζx up.
    pub p_um4: Vec<f64>,
    /// Periodogram bins per box (b_x, b_y).
    pub box_bins: (usize, usize),
}

/// How the grid is made (`[psd.map].source`).
pub const MAP_SOURCE: &str = "Hann-windowed 2D periodogram of the map, box-averaged onto a \
     grid of at most 86 × 86 cells up to each axis' Nyquist frequency (DC bin and ζx = 0 \
     column left out), half plane ζy ≥ 0";

/// Box size along one axis of n frequency bins per half axis: at most [`HALF_NODES`] nodes.
fn box_len(half: usize) -> usize {
    half.div_ceil(HALF_NODES).max(1)
}

/// The grid of a NaN-free map (≥ 16 × 16).
pub fn psd_map(t: &Topography) -> Result<PsdMapGrid, FitError> {
    let (p, dzx, dzy) = periodogram(t)?;
    Ok(grid_of(&p, t.nx, t.ny, dzx, dzy))
}

/// The grid of a periodogram `p` (FFT order, row-major nx × ny, m⁴, steps rad/m).
pub fn grid_of(p: &[f64], nx: usize, ny: usize, dzx: f64, dzy: f64) -> PsdMapGrid {
    let (hx, hy) = (nx / 2, ny / 2);
    let (mut bx, mut by) = (box_len(hx), box_len(hy));
    // Widen the smaller box until it holds enough bins (small maps).
    while bx * by < MIN_BOX_BINS && (bx < hx || by < hy) {
        if (bx <= by && bx < hx) || by >= hy {
            bx += 1;
        } else {
            by += 1;
        }
    }
    let (mx, my) = ((hx / bx).max(1), (hy / by).max(1));
    let signed = |k: usize, n: usize| crate::fft::signed(k, n);
    let w = 2 * mx + 1;
    let mut sum = vec![0.0; w * (my + 1)];
    let mut cnt = vec![0.0; w * (my + 1)];
    for iy in 0..ny {
        let ky = signed(iy, ny);
        for ix in 0..nx {
            let kx = signed(ix, nx);
            if kx == 0.0 {
                continue;
            }
            // A bin and its mirror carry the same power: fold into ky ≥ 0.
            let (kx, ky) = if ky < 0.0 { (-kx, -ky) } else { (kx, ky) };
            let i = (kx / bx as f64).round();
            let j = (ky / by as f64).round();
            if i.abs() > mx as f64 || j > my as f64 {
                continue;
            }
            let k = j as usize * w + (i + mx as f64) as usize;
            sum[k] += p[iy * nx + ix];
            cnt[k] += 1.0;
        }
    }
    // m⁴ → µm⁴; an empty box (the origin of a one-bin-wide box) takes its row neighbours'.
    let to_um4 = 1e24;
    let mut out: Vec<f64> = (sum.iter().zip(&cnt))
        .map(|(s, c)| if *c > 0.0 { s / c * to_um4 } else { f64::NAN })
        .collect();
    for k in 0..out.len() {
        if out[k].is_nan() {
            let (l, r) = (k.checked_sub(1).map(|q| out[q]), out.get(k + 1).copied());
            let v = [l, r]
                .into_iter()
                .flatten()
                .filter(|v| v.is_finite())
                .fold((0.0, 0.0), |(s, n), v| (s + v, n + 1.0));
            out[k] = if v.1 > 0.0 { v.0 / v.1 } else { 0.0 };
        }
    }
    PsdMapGrid {
        half_nx: mx,
        half_ny: my,
        dzx_rad_per_um: dzx * bx as f64 * 1e-6,
        dzy_rad_per_um: dzy * by as f64 * 1e-6,
        p_um4: out,
        box_bins: (bx, by),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kc2d::{AnisoKcParams, synth_surface};

    /// A stretched KC map (lay along 30°): the grid holds σ² (less the band's edge and
    /// the ζx = 0 column) with its tail, and the lobe is wide across the lay.
    #[test]
    fn a_stretched_map_gives_its_sigma_and_its_lay() {
        let p = AnisoKcParams {
            sigma: 0.02e-6,
            lx: 0.3e-6,
            ly: 2.0e-6,
            angle_rad: 30f64.to_radians(),
            gamma: 3.0,
        };
        let t = synth_surface(256, 256, 20e-6 / 256.0, p, 3);
        let g = psd_map(&t).unwrap();
        assert_eq!(g.box_bins, (3, 3));
        assert_eq!((g.half_nx, g.half_ny), (42, 42));
        let table = brdf::statistics::TabulatedPsd2d::new(
            g.half_nx,
            g.half_ny,
            g.dzx_rad_per_um,
            g.dzy_rad_per_um,
            &g.p_um4,
            4.0,
            0.0,
        )
        .unwrap();
        let ratio = table.sigma_um() / 0.02;
        assert!((ratio - 1.0).abs() < 0.1, "σ ratio {ratio}");
        // Along a (across the lay) the PSD reaches further than along b.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let z = 6.0;
        let (pa, pb) = (table.psd(z * c, z * s), table.psd(-z * s, z * c));
        assert!(pa > 10.0 * pb, "{pa} vs {pb}");
    }

    #[test]
    fn small_maps_widen_the_box() {
        let p = vec![1.0; 16 * 16];
        let g = grid_of(&p, 16, 16, 1.0, 1.0);
        assert!(g.box_bins.0 * g.box_bins.1 >= MIN_BOX_BINS);
        assert_eq!(g.p_um4.len(), (2 * g.half_nx + 1) * (g.half_ny + 1));
        assert!(g.p_um4.iter().all(|v| v.is_finite() && *v >= 0.0));
    }
}
