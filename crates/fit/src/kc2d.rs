//! The anisotropic (stretched) K-correlation fitted to a map's 2-D PSD (physics.md §15):
//!
//! ```text
//! P(ζ) = Lx Ly (γ−1) σ² / (2π [1 + Lx² (ζ·a)² + Ly² (ζ·b)²]^{(γ+1)/2}),
//! a = (cos φ₀, sin φ₀),  b = (−sin φ₀, cos φ₀),
//! ```
//!
//! in the map's own axes (x along a line, y along the lines' index), the convention of
//! `brdf::statistics::AnisotropicKc`, the explicit BRDF of `fit::field_spectrum` and `judge`
//! (plane of incidence along x).
//!
//! **Data.** The Hann-windowed 2-D periodogram (normalised as [`crate::psd::radial`]:
//! `∫P d²ζ = σ²`), pooled in polar cells of the half plane (P(−ζ) = P(ζ) for real heights):
//! [`RINGS`] log-spaced rings between three frequency steps of the coarser axis (below, the
//! window kernel and the levelling dominate) and half the Nyquist frequency of the coarser
//! axis (above, interpolation and the instrument's transfer function), each ring split into
//! as many angular sectors (at most [`MAX_SECTORS`]) as give [`MIN_BINS`] bins per sector,
//! so that the rings near the bottom of the band, which hold few bins, are not noise.
//!
//! **Model and weights.** The cell mean of `P_KC(ζ) + N` over the cell's own bins (not at
//! its centroid: across a narrow lobe the PSD changes within a cell), `N` a white noise
//! floor fitted with the five surface parameters, compared in natural logarithms. A cell
//! mean of n periodogram bins scatters by ≈ 1/√n in ln; a real surface also departs from
//! any 5-parameter model, so each cell is weighted by `1/(1/n + s²)` with a model-error
//! scale `s` = [`MODEL_ERROR`]: well-populated cells count alike instead of the many bins
//! at high ζ outvoting the roll-off.
//!
//! **Minimiser.** Levenberg–Marquardt over `(ln σ, ln Lx, ln Ly, φ₀, ln(γ−1), ln N)` with a
//! central-difference Jacobian, started from the best isotropic fit of a grid over `Lc` and
//! `γ` combined with several axis angles and ratios, the best end kept. Lx ≤ Ly on output
//! (a is the direction across the lay) and φ₀ in (−90°, 90°].

use crate::psd::{RadialPsdTable, hann};
use crate::{FitError, Topography};
use nalgebra::{DMatrix, DVector};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// Log-spaced rings of the fit band.
pub const RINGS: usize = 20;
/// Most angular sectors of a ring.
pub const MAX_SECTORS: usize = 24;
/// Fewest periodogram bins of a sector.
pub const MIN_BINS: usize = 12;
/// Most bins of a cell the model mean is evaluated on.
pub const MODEL_NODES: usize = 16;
/// Model-error scale in ln P added to each cell's sampling variance.
pub const MODEL_ERROR: f64 = 0.1;
/// γ range accepted (the renderer's).
pub const GAMMA_BOUNDS: (f64, f64) = (1.001, 100.0);

/// Stretched K-correlation parameters in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnisoKcParams {
    /// Rms height σ [m].
    pub sigma: f64,
    /// Matérn range along the axis a [m].
    pub lx: f64,
    /// Matérn range along the axis b [m].
    pub ly: f64,
    /// φ₀: angle of a from +x towards +y [rad].
    pub angle_rad: f64,
    /// Exponent γ (> 1).
    pub gamma: f64,
}

impl AnisoKcParams {
    /// The PSD [m⁴] at ζ = (ζx, ζy) [rad/m].
    pub fn psd(&self, zx: f64, zy: f64) -> f64 {
        let (s, c) = self.angle_rad.sin_cos();
        let za = c * zx + s * zy;
        let zb = -s * zx + c * zy;
        let q = 1.0 + (self.lx * za).powi(2) + (self.ly * zb).powi(2);
        self.lx * self.ly * (self.gamma - 1.0) * self.sigma * self.sigma
            / (2.0 * PI * q.powf(0.5 * (self.gamma + 1.0)))
    }

    /// The same surface with Lx ≤ Ly (swapping the axes turns them by 90°) and φ₀ in
    /// (−π/2, π/2].
    pub fn normalised(mut self) -> Self {
        if self.lx > self.ly {
            std::mem::swap(&mut self.lx, &mut self.ly);
            self.angle_rad += 0.5 * PI;
        }
        self.angle_rad = wrap_half_turn(self.angle_rad);
        self
    }

    /// `Ly / Lx`.
    pub fn ratio(&self) -> f64 {
        self.ly / self.lx
    }
}

/// An angle of an axis (defined modulo π) in (−π/2, π/2].
pub fn wrap_half_turn(a: f64) -> f64 {
    let r = a.rem_euclid(PI);
    if r > 0.5 * PI { r - PI } else { r }
}

/// Result of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct AnisoKcFit {
    /// Best-fit surface, normalised (Lx ≤ Ly, φ₀ in (−π/2, π/2]).
    pub params: AnisoKcParams,
    /// Fitted white-noise floor [m⁴].
    pub noise_m4: f64,
    /// Weighted rms of the ln residuals over the cells.
    pub rms_log_residual: f64,
    /// Rms of the ln residuals of the best isotropic fit (Lx = Ly) on the same cells.
    pub rms_log_residual_isotropic: f64,
    /// Cells fitted.
    pub cells: usize,
    /// Band [rad/m].
    pub band: (f64, f64),
    /// Why the fit should not be used, if it should not.
    pub problem: Option<String>,
    /// The radial PSD of the map in the frame where the fitted ellipse (Ly/Lx, φ₀ of
    /// `params`) is a circle, areas kept ([`destretched_radial`]): the table of the
    /// stretched measured-PSD model.
    pub destretched: RadialPsdTable,
    /// Weighted rms ln residual of the same cells against the elliptical measured model
    /// (the smoothed de-stretched table stretched back, no noise term added: the table
    /// holds the floor); NaN when the table is unusable.
    pub rms_log_residual_elliptical: f64,
    /// The same for the isotropic measured model (the radially averaged table, ratio 1).
    pub rms_log_residual_radial: f64,
}

/// Hann-windowed 2-D periodogram of a NaN-free map, FFT order, row-major, m⁴
/// (`Σ P Δζx Δζy` ≈ the variance).
pub fn periodogram(t: &Topography) -> Result<(Vec<f64>, f64, f64), FitError> {
    if t.is_profile() || t.nx < 16 || t.ny < 16 {
        return Err(FitError::data(
            "anisotropic K-correlation fit",
            "needs a map of at least 16 × 16 points",
        ));
    }
    if t.heights.iter().any(|h| !h.is_finite()) {
        return Err(FitError::data(
            "anisotropic K-correlation fit",
            "the map has invalid points; fill them first",
        ));
    }
    let (nx, ny) = (t.nx, t.ny);
    let (wx, wy) = (hann(nx), hann(ny));
    let mean = t.heights.iter().sum::<f64>() / (nx * ny) as f64;
    let spread = t
        .heights
        .iter()
        .map(|h| (h - mean).abs())
        .fold(0.0, f64::max);
    let scale = t.heights.iter().map(|h| h.abs()).fold(0.0, f64::max);
    if spread <= 1e-12 * scale || spread == 0.0 {
        return Err(FitError::data(
            "anisotropic K-correlation fit",
            "the map's heights are constant (to rounding): there is no spectrum to fit",
        ));
    }
    let w2 = wx.iter().map(|w| w * w).sum::<f64>() / nx as f64
        * wy.iter().map(|w| w * w).sum::<f64>()
        / ny as f64;
    let mut buf: Vec<Complex<f64>> = (0..nx * ny)
        .map(|i| Complex::new((t.heights[i] - mean) * wx[i % nx] * wy[i / nx], 0.0))
        .collect();
    let mut planner = FftPlanner::<f64>::new();
    crate::fft::fft2(&mut buf, nx, ny, &mut planner, false);
    let norm = t.dx * t.dy / ((nx * ny) as f64 * w2) / (4.0 * PI * PI);
    let dzx = 2.0 * PI / (nx as f64 * t.dx);
    let dzy = 2.0 * PI / (ny as f64 * t.dy);
    Ok((buf.iter().map(|c| c.norm_sqr() * norm).collect(), dzx, dzy))
}

/// A polar cell: its bins' frequencies [rad/m], the mean measured PSD and the weight.
struct Cell {
    zeta: Vec<(f64, f64)>,
    ln_p: f64,
    weight: f64,
}

fn cells_of(t: &Topography, p: &[f64], dzx: f64, dzy: f64) -> (Vec<Cell>, (f64, f64)) {
    let (nx, ny) = (t.nx, t.ny);
    let z_lo = 3.0 * dzx.max(dzy);
    let z_hi = 0.5 * PI / t.dx.max(t.dy);
    let step = (z_hi / z_lo).ln() / RINGS as f64;
    let mut rings: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); RINGS];
    for iy in 0..ny {
        let zy = crate::fft::signed(iy, ny) * dzy;
        for ix in 0..nx {
            let zx = crate::fft::signed(ix, nx) * dzx;
            // The half plane θ ∈ [0, π): P(−ζ) = P(ζ). The two axes are left out: a
            // scanning instrument's line offsets and glitches put their power on ζx = 0,
            // and row-wise levelling removes power there.
            if zy <= 0.0 || ix == 0 {
                continue;
            }
            let z = zx.hypot(zy);
            if !(z_lo..=z_hi).contains(&z) {
                continue;
            }
            let r = (((z / z_lo).ln() / step) as usize).min(RINGS - 1);
            rings[r].push((zx, zy, p[iy * nx + ix]));
        }
    }
    let mut cells = Vec::new();
    for ring in rings {
        let sectors = (ring.len() / MIN_BINS).clamp(1, MAX_SECTORS);
        let mut parts: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); sectors];
        for b in ring {
            let th = b.1.atan2(b.0).clamp(0.0, PI - 1e-12);
            parts[((th / PI * sectors as f64) as usize).min(sectors - 1)].push(b);
        }
        for part in parts {
            let n = part.len();
            let mean = part.iter().map(|b| b.2).sum::<f64>() / n.max(1) as f64;
            if n == 0 || !(mean > 0.0 && mean.is_finite()) {
                continue;
            }
            // The model's cell mean from at most MODEL_NODES of the cell's bins, spread
            // through it (bins are pushed in raster order): the fit costs the same on any map.
            let stride = n.div_ceil(MODEL_NODES);
            cells.push(Cell {
                zeta: part.iter().step_by(stride).map(|b| (b.0, b.1)).collect(),
                ln_p: mean.ln(),
                weight: 1.0 / (1.0 / n as f64 + MODEL_ERROR * MODEL_ERROR),
            });
        }
    }
    (cells, (z_lo, z_hi))
}

/// Parameter vector `(ln σ, ln Lx, ln Ly, φ₀, ln(γ−1), ln N)` → surface and noise floor.
fn unpack(x: &[f64]) -> (AnisoKcParams, f64) {
    let gamma = (1.0 + x[4].exp()).clamp(GAMMA_BOUNDS.0, GAMMA_BOUNDS.1);
    (
        AnisoKcParams {
            sigma: x[0].exp(),
            lx: x[1].exp(),
            ly: x[2].exp(),
            angle_rad: x[3],
            gamma,
        },
        x[5].exp(),
    )
}

/// Weighted residuals `√w (ln M̄ − ln P̄)` of every cell.
fn residuals(cells: &[Cell], x: &[f64]) -> Vec<f64> {
    let (s, noise) = unpack(x);
    cells
        .iter()
        .map(|c| {
            let m =
                c.zeta.iter().map(|&(a, b)| s.psd(a, b)).sum::<f64>() / c.zeta.len() as f64 + noise;
            c.weight.sqrt() * (m.ln() - c.ln_p)
        })
        .collect()
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// The least-squares ln σ for the other parameters fixed and no noise: the weighted mean
/// of the log residuals moves ln σ² one for one.
fn best_sigma(cells: &[Cell], x: &mut [f64]) -> f64 {
    x[0] = 0.0;
    let r = residuals(cells, x);
    let (mut num, mut den) = (0.0, 0.0);
    for (c, ri) in cells.iter().zip(&r) {
        num += c.weight.sqrt() * ri;
        den += c.weight;
    }
    x[0] = -0.5 * num / den;
    cost(&residuals(cells, x))
}

/// Fits the stretched K-correlation to the 2-D PSD of a levelled, NaN-free map.
/// `axis_hint_rad` (e.g. the steepest-slope direction) is one of the start angles.
pub fn fit(t: &Topography, axis_hint_rad: f64) -> Result<AnisoKcFit, FitError> {
    let (p, dzx, dzy) = periodogram(t)?;
    let (cells, band) = cells_of(t, &p, dzx, dzy);
    if cells.len() < 12 {
        return Err(FitError::data(
            "anisotropic K-correlation fit",
            format!("only {} usable PSD cells in the band", cells.len()),
        ));
    }
    let floor = cells.iter().map(|c| c.ln_p).fold(f64::INFINITY, f64::min) - 6.0 * 10f64.ln();
    // Isotropic start: a grid over Lc and γ, σ solved, then refined with Lx = Ly.
    let mut best_iso = (f64::INFINITY, vec![0.0; 6]);
    for i in 0..13 {
        let lc = (0.3 / band.1) * (30.0 * band.1 / band.0).powf(i as f64 / 12.0);
        for gamma in [1.5, 2.5, 4.0, 7.0] {
            let mut x = vec![0.0, lc.ln(), lc.ln(), 0.0, (gamma - 1.0f64).ln(), floor];
            let c = best_sigma(&cells, &mut x);
            if c < best_iso.0 {
                best_iso = (c, x);
            }
        }
    }
    let iso = minimise_isotropic(&cells, best_iso.1);
    let iso_rms = rms(&cells, iso.1);
    let mut best = iso.clone();
    for ratio in [1.5f64, 3.0, 8.0] {
        for k in 0..4 {
            let angle = axis_hint_rad + k as f64 * PI / 4.0;
            let mut x = iso.0.clone();
            let s = ratio.sqrt().ln();
            x[1] -= s;
            x[2] += s;
            x[3] = angle;
            let end = lm(&|y: &[f64]| residuals(&cells, y), x);
            if end.1 < best.1 {
                best = end;
            }
        }
    }
    let (params, noise) = unpack(&best.0);
    let params = params.normalised();
    let problem = problem_of(&params, band, noise, &cells);
    let (ratio, angle) = (params.ratio(), params.angle_rad);
    let destretched = destretched_radial(t, &p, (dzx, dzy), ratio, angle);
    let isotropic = destretched_radial(t, &p, (dzx, dzy), 1.0, 0.0);
    Ok(AnisoKcFit {
        params,
        noise_m4: noise,
        rms_log_residual: rms(&cells, best.1),
        rms_log_residual_isotropic: iso_rms,
        cells: cells.len(),
        band,
        problem,
        rms_log_residual_elliptical: radial_residual(&cells, &destretched, ratio, angle),
        rms_log_residual_radial: radial_residual(&cells, &isotropic, 1.0, 0.0),
        destretched,
    })
}

/// The radial PSD of the de-stretched frame: the periodogram `p` (FFT order, steps `dz`
/// rad/m) averaged over ellipses ρ = |(s_a ζ·a, s_b ζ·b)| = const, s_a = 1/√ratio,
/// s_b = √ratio, a at `angle_rad` (ratio 1: the radially averaged PSD). Under the
/// elliptical model P(ζ) = P_r(ρ) (areas kept: the stretch has unit Jacobian), so each bin
/// mean estimates P_r(ρ), from whatever part of its ellipse lies inside the measured band
/// (0 < |ζ| ≤ the coarser axis' Nyquist frequency): at ρ below the band's bottom ×√ratio or
/// above its top /√ratio only the sector along the long, resp. short, axis is measured.
/// Bins of the coarser frequency step in ρ; fewer than [`MIN_BINS`] samples are dropped.
pub fn destretched_radial(
    t: &Topography,
    p: &[f64],
    dz: (f64, f64),
    ratio: f64,
    angle_rad: f64,
) -> RadialPsdTable {
    let (nx, ny) = (t.nx, t.ny);
    let (sa, sb) = (1.0 / ratio.sqrt(), ratio.sqrt());
    let (s, c) = angle_rad.sin_cos();
    let width = dz.0.max(dz.1);
    let z_max = PI / t.dx.max(t.dy);
    let nbins = (z_max * sb / width).ceil() as usize + 2;
    let (mut sz, mut sp, mut sw) = (vec![0.0; nbins], vec![0.0; nbins], vec![0.0; nbins]);
    for iy in 0..ny {
        let zy = crate::fft::signed(iy, ny) * dz.1;
        for ix in 0..nx {
            let zx = crate::fft::signed(ix, nx) * dz.0;
            let z = zx.hypot(zy);
            if z == 0.0 || z > z_max {
                continue;
            }
            let rho = (sa * (c * zx + s * zy)).hypot(sb * (c * zy - s * zx));
            let b = (rho / width).round() as usize;
            if b == 0 || b >= nbins {
                continue;
            }
            sz[b] += rho;
            sp[b] += p[iy * nx + ix];
            sw[b] += 1.0;
        }
    }
    let mut out = RadialPsdTable {
        zeta: Vec::new(),
        p: Vec::new(),
        count: Vec::new(),
    };
    for b in 0..nbins {
        if sw[b] >= MIN_BINS as f64 {
            out.zeta.push(sz[b] / sw[b]);
            out.p.push(sp[b] / sw[b]);
            out.count.push(sw[b]);
        }
    }
    out
}

/// Weighted rms ln residual of the cells against the radial table `r` (rad/m, m⁴), smoothed
/// as the measured-PSD model's table and stretched by `ratio` along the axis at `angle_rad`;
/// NaN when the table cannot be made.
fn radial_residual(cells: &[Cell], r: &RadialPsdTable, ratio: f64, angle_rad: f64) -> f64 {
    let model = crate::candidates::smoothed_table(r, "")
        .ok()
        .and_then(|(z, p, _)| brdf::statistics::TabulatedPsd::new(&z, &p).ok())
        .and_then(|t| brdf::statistics::EllipticalPsd::new(t, 1.0, ratio, angle_rad).ok());
    let Some(model) = model else {
        return f64::NAN;
    };
    let (mut acc, mut wsum) = (0.0, 0.0);
    for c in cells {
        let m = c
            .zeta
            .iter()
            .map(|&(a, b)| model.psd(a * 1e-6, b * 1e-6) * 1e-24)
            .sum::<f64>()
            / c.zeta.len() as f64;
        acc += c.weight * (m.ln() - c.ln_p).powi(2);
        wsum += c.weight;
    }
    (acc / wsum).sqrt()
}

/// Lx = Ly = Lc: minimise over (ln σ, ln Lc, ln(γ−1), ln N), the angle unused.
fn minimise_isotropic(cells: &[Cell], x: Vec<f64>) -> (Vec<f64>, f64) {
    let expand = |y: &[f64]| vec![y[0], y[1], y[1], 0.0, y[2], y[3]];
    let y0 = vec![x[0], 0.5 * (x[1] + x[2]), x[4], x[5]];
    let (y, c) = lm(&|y: &[f64]| residuals(cells, &expand(y)), y0);
    (expand(&y), c)
}

/// Levenberg–Marquardt with a central-difference Jacobian over the residuals `res`, from
/// `y`; the last parameter is ln N, kept in [−300, 0] (far below and above anything a map
/// holds). Returns the end point and its cost.
fn lm(res: &dyn Fn(&[f64]) -> Vec<f64>, mut y: Vec<f64>) -> (Vec<f64>, f64) {
    let n = y.len();
    let mut r = res(&y);
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let m = r.len();
        let mut jac = DMatrix::<f64>::zeros(m, n);
        for i in 0..n {
            let h = 1e-5;
            let (mut yp, mut ym) = (y.clone(), y.clone());
            yp[i] += h;
            ym[i] -= h;
            let (rp, rm) = (res(&yp), res(&ym));
            for j in 0..m {
                jac[(j, i)] = (rp[j] - rm[j]) / (2.0 * h);
            }
        }
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        while lambda < 1e10 {
            let mut a = jtj.clone();
            for k in 0..n {
                a[(k, k)] += lambda * (jtj[(k, k)] + 1e-9);
            }
            let Some(step) = a.lu().solve(&(-&jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let mut yn: Vec<f64> = y.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            yn[n - 1] = yn[n - 1].clamp(-300.0, 0.0);
            let rn = res(&yn);
            let cn = cost(&rn);
            if cn.is_finite() && cn < c {
                let done = (c - cn) <= 1e-10 * c;
                y = yn;
                r = rn;
                c = cn;
                lambda = (lambda / 10.0).max(1e-12);
                improved = true;
                if done {
                    return (y, c);
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (y, c)
}

fn rms(cells: &[Cell], cost: f64) -> f64 {
    (cost / cells.iter().map(|c| c.weight).sum::<f64>()).sqrt()
}

fn problem_of(p: &AnisoKcParams, band: (f64, f64), noise: f64, cells: &[Cell]) -> Option<String> {
    if !(p.sigma.is_finite() && p.lx.is_finite() && p.ly.is_finite() && p.gamma.is_finite()) {
        return Some("the fit did not converge to finite parameters".into());
    }
    if p.gamma <= GAMMA_BOUNDS.0 * 1.0001 || p.gamma >= GAMMA_BOUNDS.1 * 0.9999 {
        return Some(format!("γ ended on a bound of 1.001…100 ({:.3})", p.gamma));
    }
    if p.ly * band.0 > 1e3 || p.lx * band.1 < 1e-3 {
        return Some(format!(
            "a correlation length ({:.3e} or {:.3e} m) lies 10³ beyond the fitted band \
             {:.3e}…{:.3e} rad/m",
            p.lx, p.ly, band.0, band.1
        ));
    }
    let lo = cells.iter().map(|c| c.ln_p).fold(f64::INFINITY, f64::min);
    if noise.ln() > lo + 2.0f64.ln()
        && noise.ln() > cells.iter().map(|c| c.ln_p).sum::<f64>() / cells.len() as f64
    {
        return Some("the fitted noise floor is above half the band's PSD".into());
    }
    None
}

/// A periodic `nx × ny` map (square pixels `dx` [m]) whose expected 2-D periodogram is the
/// stretched K-correlation `p` (white noise filtered by √PSD; the DC term zero): the
/// synthetic surfaces of the tests, whose parameters are known.
pub fn synth_surface(nx: usize, ny: usize, dx: f64, p: AnisoKcParams, seed: u64) -> Topography {
    synth_surface_with(nx, ny, dx, &|zx, zy| p.psd(zx, zy), seed)
}

/// A periodic `nx × ny` map (square pixels `dx` [m]) whose expected 2-D periodogram is
/// `psd(ζx, ζy)` [m⁴ at rad/m] (white noise filtered by √PSD; the DC term zero).
pub fn synth_surface_with(
    nx: usize,
    ny: usize,
    dx: f64,
    psd: &dyn Fn(f64, f64) -> f64,
    seed: u64,
) -> Topography {
    let mut buf = crate::rng::white_noise(nx * ny, seed);
    let mut planner = FftPlanner::<f64>::new();
    crate::fft::fft2(&mut buf, nx, ny, &mut planner, false);
    let (dzx, dzy) = (2.0 * PI / (nx as f64 * dx), 2.0 * PI / (ny as f64 * dx));
    for ky in 0..ny {
        let zy = crate::fft::signed(ky, ny) * dzy;
        for kx in 0..nx {
            let zx = crate::fft::signed(kx, nx) * dzx;
            // E|FFT(noise)|² = N; the periodogram normalisation dx²/(N 4π²)·|·|² gives P.
            let a = if kx == 0 && ky == 0 {
                0.0
            } else {
                (4.0 * PI * PI * psd(zx, zy) / (dx * dx)).sqrt()
            };
            buf[ky * nx + kx] *= a;
        }
    }
    crate::fft::fft2(&mut buf, nx, ny, &mut planner, true);
    let n = (nx * ny) as f64;
    Topography {
        nx,
        ny,
        dx,
        dy: dx,
        heights: buf.iter().map(|c| c.re / n).collect(),
        channel: "synthetic anisotropic".into(),
        format: "synthetic",
    }
}
