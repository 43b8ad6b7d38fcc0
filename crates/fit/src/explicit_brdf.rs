//! The scan's own scalar-diffraction (Kirchhoff / Harvey–Shack) BRDF at arbitrary directions,
//! averaged over tiles of the map for speckle, with a confidence band and the angular window in
//! which it can be trusted.
//!
//! **What is computed.** For incidence `i`, outgoing `o` (unit vectors away from the surface,
//! `n = +z`), wavelength λ and `k = 2π/λ`: `ζ = k(o⊥ + i⊥)`, `q = k(cosθi + cosθo)`, and the
//! periodogram `P̂(ζ; q)` of `U = exp(−i q h)` normalised as in [`crate::field_spectrum`] (whose
//! ensemble mean for Gaussian heights is physics.md's `S(ζ; g)`, `g = q²σ²`). The scattered BRDF
//! for R = 1 is `f = k² P̂` [sr⁻¹]; the coherent (specular-delta) weight is `|⟨U⟩|²` at
//! `q = 2k cosθi`. For a profile the 1-D version `f₁ = k P̂₁(ζx; q)` is the in-plane BRDF
//! integrated over the out-of-plane direction cosine, `∫ f do_y`.
//!
//! **One evaluation per direction pair, no interpolation.** `q` and `ζ` are exact for every
//! `(i, o, λ)`: the field is formed with that pair's `q`, and its spectrum is evaluated at exactly
//! that `ζ` by a separable direct Fourier sum (the band-limited interpolation of the FFT grid of
//! [`crate::field_spectrum`], with no interpolation error). Cost: one `sincos` and a few complex
//! multiply-adds per pixel per direction.
//!
//! **Speckle and confidence band.** One map gives one speckle realisation. The map is cut into
//! overlapping tiles (Welch: Hann taper, 50 % overlap by default); each tile's periodogram is
//! formed with its own windowed mean subtracted (this removes the coherent peak and its leakage
//! exactly) and the tile periodograms are averaged. The standard error is the tile scatter
//! divided by `sqrt(n/κ)`, where `κ` accounts for the overlap (the periodogram correlation of
//! two tiles shifted by `d` is `(Σ w w_d)² / (Σ w²)²` per axis, exact for a spectrum that is flat
//! over the tile resolution). The estimate is the true spectrum smoothed by the tile window's
//! spectral kernel ([`ExplicitBrdf::kernel_nodes`]): compare models smoothed by the same kernel.
//!
//! **Valid window** ([`AngularWindow`]): directions within the Hann main lobe of the specular
//! direction (`|o⊥ − s⊥| < 2λ/L_tile`) are not resolved; the pixel pitch represents
//! `|Δ sinθ| ≤ λ/(2 dx)` (Nyquist) and beyond half of that aliases from above the Nyquist
//! frequency may exceed a few per cent; where the spectrum is within 10× of its value at the
//! Nyquist edge the aliases are not negligible; and the method has no shadowing or masking, so
//! directions where the Smith factor of the measured slopes (Beckmann, α = rms slope) drops
//! below 0.9 are flagged. Multiple scattering is absent as in every model judged.

use crate::field_spectrum::{Window, check};
use crate::{FitError, Topography};
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// How the map is cut into tiles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileOptions {
    /// Tile edge in pixels (default: a quarter of the shorter side, at least 32 or the whole
    /// side when shorter). Larger tiles resolve finer angular detail, smaller ones average
    /// more speckle.
    pub size: Option<usize>,
    /// Fractional overlap of neighbouring tiles, in [0, 0.9].
    pub overlap: f64,
    /// Taper of each tile.
    pub window: Window,
}

impl Default for TileOptions {
    fn default() -> Self {
        TileOptions {
            size: None,
            overlap: 0.5,
            window: Window::Hann,
        }
    }
}

/// A mean with its standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Mean.
    pub value: f64,
    /// Standard error of the mean.
    pub se: f64,
    /// Number of tiles averaged.
    pub n: usize,
}

impl Estimate {
    /// Relative standard error (∞ for a zero mean).
    pub fn relative_se(&self) -> f64 {
        if self.value > 0.0 {
            self.se / self.value
        } else {
            f64::INFINITY
        }
    }

    fn scaled(self, s: f64) -> Estimate {
        Estimate {
            value: self.value * s,
            se: self.se * s,
            n: self.n,
        }
    }
}

/// `(ζx, ζy, q)` for a direction pair at wavenumber `k`.
pub fn scattering_vector(k: f64, wi: [f64; 3], wo: [f64; 3]) -> (f64, f64, f64) {
    (
        k * (wo[0] + wi[0]),
        k * (wo[1] + wi[1]),
        k * (wi[2] + wo[2]),
    )
}

/// Why a direction is or is not inside the trusted window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Validity {
    /// Trusted.
    Valid,
    /// Closer to the specular direction than the tile resolution.
    NearSpecular,
    /// Beyond half the Nyquist offset of the pixel pitch.
    BeyondNyquist,
    /// The spectrum is within 10× of the aliasing floor.
    Aliased,
    /// Shadowing/masking of the measured slopes exceeds 10 % (absent from the method).
    Shadowed,
    /// Below the horizon.
    BelowHorizon,
}

impl Validity {
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Validity::Valid => "valid",
            Validity::NearSpecular => "near_specular",
            Validity::BeyondNyquist => "beyond_nyquist",
            Validity::Aliased => "aliased",
            Validity::Shadowed => "shadowed",
            Validity::BelowHorizon => "below_horizon",
        }
    }
}

/// The angular window of one (incidence, wavelength), in direction-cosine offsets
/// `Δ = o⊥ − s⊥` from the specular direction `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngularWindow {
    /// Wavelength [m].
    pub lambda: f64,
    /// Smallest trusted `|Δ|`: the Hann main-lobe half-width `2λ/L_tile` (`1λ/L_tile` for
    /// the rectangular window).
    pub resolution: f64,
    /// `λ/(2dx)`, `λ/(2dy)`: the largest `|Δ sinθ|` the pixel pitch represents.
    pub nyquist: (f64, f64),
    /// Largest trusted `|Δx|`, `|Δy|`: half of the Nyquist offsets.
    pub max_offset: (f64, f64),
    /// Field spectrum at the Nyquist edge for the largest `q` of this incidence
    /// (`k(cosθi + 1)`), in spectrum units (m², m for profiles).
    pub alias_floor: f64,
    /// Rms phase step between neighbouring pixels at that `q`, `q · rms slope · dx` [rad];
    /// above ~1 the field is undersampled and most of the window is aliased.
    pub phase_step: f64,
    /// Beckmann α used for the shadowing flag (the rms slope of the map).
    pub shadow_alpha: f64,
    /// Smith factor of the incidence direction, `G1(θi)`.
    pub g1_incidence: f64,
}

/// Smith masking factor `G1 = 1/(1 + Λ)` of a Beckmann surface with roughness `alpha` at
/// polar angle `theta` [rad].
pub fn smith_g1_beckmann(alpha: f64, theta: f64) -> f64 {
    let t = theta.tan().abs();
    if alpha.is_nan() || alpha <= 0.0 || t == 0.0 {
        return 1.0;
    }
    if !t.is_finite() {
        return 0.0;
    }
    let a = 1.0 / (alpha * t);
    let lambda = 0.5 * ((-a * a).exp() / (a * PI.sqrt()) - libm::erfc(a));
    1.0 / (1.0 + lambda.max(0.0))
}

impl AngularWindow {
    /// Classifies `wo` for incidence `wi` given the explicit spectrum value there.
    pub fn classify(&self, wi: [f64; 3], wo: [f64; 3], spectrum: f64) -> Validity {
        if !(wi[2] > 0.0 && wo[2] > 0.0) {
            return Validity::BelowHorizon;
        }
        let (dx, dy) = (wo[0] + wi[0], wo[1] + wi[1]);
        if (dx * dx + dy * dy).sqrt() < self.resolution {
            return Validity::NearSpecular;
        }
        if dx.abs() > self.max_offset.0 || dy.abs() > self.max_offset.1 {
            return Validity::BeyondNyquist;
        }
        if spectrum.is_nan() || spectrum <= 10.0 * self.alias_floor {
            return Validity::Aliased;
        }
        let g = smith_g1_beckmann(self.shadow_alpha, wi[2].clamp(-1.0, 1.0).acos())
            * smith_g1_beckmann(self.shadow_alpha, wo[2].clamp(-1.0, 1.0).acos());
        if g < 0.9 {
            return Validity::Shadowed;
        }
        Validity::Valid
    }
}

/// A levelled map or profile prepared for explicit BRDF evaluation.
#[derive(Debug, Clone)]
pub struct ExplicitBrdf {
    nx: usize,
    ny: usize,
    dx: f64,
    dy: f64,
    heights: Vec<f64>,
    tx: usize,
    ty: usize,
    x0: Vec<usize>,
    y0: Vec<usize>,
    wx: Vec<f64>,
    wy: Vec<f64>,
    /// Σ wx, Σ wy, Σ wx², Σ wy².
    sums: [f64; 4],
    kappa: f64,
    window: Window,
    rms_slope: f64,
}

fn tile_origins(n: usize, size: usize, overlap: f64) -> Vec<usize> {
    if size >= n {
        return vec![0];
    }
    let step = ((size as f64 * (1.0 - overlap)).round() as usize).max(1);
    let count = (n - size) / step + 1;
    let offset = (n - ((count - 1) * step + size)) / 2;
    (0..count).map(|i| offset + i * step).collect()
}

/// Periodogram correlation of two tapers shifted by `d` samples.
fn shift_correlation(w: &[f64], d: usize) -> f64 {
    if d >= w.len() {
        return 0.0;
    }
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let c: f64 = w.iter().zip(&w[d..]).map(|(a, b)| a * b).sum();
    (c / s2).powi(2)
}

impl ExplicitBrdf {
    /// Prepares a levelled, NaN-free map or profile (see [`crate::pipeline::prepare`]).
    pub fn new(t: &Topography, opts: &TileOptions) -> Result<ExplicitBrdf, FitError> {
        check(t)?;
        if !(0.0..=0.9).contains(&opts.overlap) {
            return Err(FitError::data(
                "explicit BRDF",
                format!("tile overlap {} must lie in [0, 0.9]", opts.overlap),
            ));
        }
        let profile = t.ny == 1;
        let short = if profile { t.nx } else { t.nx.min(t.ny) };
        let size = match opts.size {
            Some(s) if s >= 4 => s,
            Some(s) => {
                return Err(FitError::data(
                    "explicit BRDF",
                    format!("tile size {s} must be at least 4 pixels"),
                ));
            }
            None => (short / 4).max(32),
        };
        let tx = size.min(t.nx);
        let ty = if profile { 1 } else { size.min(t.ny) };
        let x0 = tile_origins(t.nx, tx, opts.overlap);
        let y0 = if profile {
            vec![0]
        } else {
            tile_origins(t.ny, ty, opts.overlap)
        };
        let wx = opts.window.weights(tx);
        let wy = if profile {
            vec![1.0]
        } else {
            opts.window.weights(ty)
        };
        let sums = [
            wx.iter().sum(),
            wy.iter().sum(),
            wx.iter().map(|v| v * v).sum(),
            wy.iter().map(|v| v * v).sum(),
        ];
        let mut kappa = 0.0;
        for a in &x0 {
            for b in &x0 {
                let rx = shift_correlation(&wx, a.abs_diff(*b));
                if rx == 0.0 {
                    continue;
                }
                for c in &y0 {
                    for d in &y0 {
                        kappa += rx * shift_correlation(&wy, c.abs_diff(*d));
                    }
                }
            }
        }
        kappa /= (x0.len() * y0.len()) as f64;
        Ok(ExplicitBrdf {
            nx: t.nx,
            ny: t.ny,
            dx: t.dx,
            dy: if profile { t.dx } else { t.dy },
            heights: t.heights.clone(),
            tx,
            ty,
            x0,
            y0,
            wx,
            wy,
            sums,
            kappa,
            window: opts.window,
            rms_slope: crate::stats::compute(t).rms_slope(),
        })
    }

    /// True for a profile.
    pub fn is_profile(&self) -> bool {
        self.ny == 1
    }

    /// Tile edge lengths `(tx·dx, ty·dy)` [m] (`ty·dy` = 0 for a profile).
    pub fn tile_size(&self) -> (f64, f64) {
        (
            self.tx as f64 * self.dx,
            if self.is_profile() {
                0.0
            } else {
                self.ty as f64 * self.dy
            },
        )
    }

    /// Tile size in pixels `(tx, ty)`.
    pub fn tile_pixels(&self) -> (usize, usize) {
        (self.tx, self.ty)
    }

    /// Number of tiles averaged.
    pub fn tiles(&self) -> usize {
        self.x0.len() * self.y0.len()
    }

    /// Variance inflation from the tile overlap (1 for disjoint tiles).
    pub fn overlap_factor(&self) -> f64 {
        self.kappa
    }

    /// Rms slope of the map (Sdq; Rdq for a profile).
    pub fn rms_slope(&self) -> f64 {
        self.rms_slope
    }

    /// Pixel pitch `(dx, dy)` [m].
    pub fn pixel(&self) -> (f64, f64) {
        (self.dx, self.dy)
    }

    /// Tile-averaged field spectrum `P̂(ζ; q)` (m² for maps, m for profiles; `zeta_y` is
    /// ignored for profiles).
    pub fn spectrum(&self, zeta: (f64, f64), q: f64) -> Estimate {
        let (tx, ty) = (self.tx, self.ty);
        let ex = phasors(&self.wx, zeta.0 * self.dx);
        let ey = phasors(&self.wy, zeta.1 * self.dy);
        let wxs: Complex<f64> = ex.iter().sum();
        let wys: Complex<f64> = if self.is_profile() {
            Complex::new(1.0, 0.0)
        } else {
            ey.iter().sum()
        };
        let ncol = self.x0.len();
        // Row pass: per row, per tile column, Σ_x w e^{−iζx x} U and Σ_x w U.
        let mut b = vec![Complex::new(0.0, 0.0); ncol * self.ny];
        let mut b0 = vec![Complex::new(0.0, 0.0); ncol * self.ny];
        let mut u = vec![Complex::new(0.0, 0.0); self.nx];
        for y in 0..self.ny {
            let row = &self.heights[y * self.nx..(y + 1) * self.nx];
            for (v, h) in u.iter_mut().zip(row) {
                let (s, c) = (q * h).sin_cos();
                *v = Complex::new(c, -s);
            }
            for (c, &x0) in self.x0.iter().enumerate() {
                let seg = &u[x0..x0 + tx];
                let mut a = Complex::new(0.0, 0.0);
                let mut a0 = Complex::new(0.0, 0.0);
                for ((v, e), w) in seg.iter().zip(&ex).zip(&self.wx) {
                    a += v * e;
                    a0 += v * w;
                }
                b[y * ncol + c] = a;
                b0[y * ncol + c] = a0;
            }
        }
        let norm = if self.is_profile() {
            self.dx / (2.0 * PI * self.sums[2])
        } else {
            self.dx * self.dy / (4.0 * PI * PI * self.sums[2] * self.sums[3])
        };
        let wsum = self.sums[0] * self.sums[1];
        let mut vals = Vec::with_capacity(self.tiles());
        for &y0 in &self.y0 {
            for c in 0..ncol {
                let (mut a, mut a0) = (Complex::new(0.0, 0.0), Complex::new(0.0, 0.0));
                for (j, (e, w)) in ey.iter().zip(&self.wy).enumerate().take(ty) {
                    let r = (y0 + j) * ncol + c;
                    a += b[r] * e;
                    a0 += b0[r] * w;
                }
                let cs = a0 / wsum;
                let f = a - cs * wxs * wys;
                vals.push(f.norm_sqr() * norm);
            }
        }
        let n = vals.len();
        let mean = vals.iter().sum::<f64>() / n as f64;
        let se = if n > 1 {
            let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            (self.kappa * var / n as f64).sqrt()
        } else {
            // One tile: a periodogram is exponentially distributed, sd = mean.
            mean
        };
        Estimate { value: mean, se, n }
    }

    /// Scattered BRDF for R = 1 at `(wi, wo)`, wavelength `lambda` [m]: `k² P̂` [sr⁻¹] for maps,
    /// `k P̂₁` (integrated over the out-of-plane direction cosine) for profiles. Zero below the
    /// horizon.
    pub fn scattered(&self, wi: [f64; 3], wo: [f64; 3], lambda: f64) -> Estimate {
        if !(wi[2] > 0.0 && wo[2] > 0.0 && lambda > 0.0) {
            return Estimate {
                value: 0.0,
                se: 0.0,
                n: self.tiles(),
            };
        }
        let k = 2.0 * PI / lambda;
        let (zx, zy, q) = scattering_vector(k, wi, wo);
        let s = self.spectrum((zx, zy), q);
        s.scaled(if self.is_profile() { k } else { k * k })
    }

    /// [`ExplicitBrdf::scattered`] for many outgoing directions, in parallel.
    pub fn scattered_many(&self, wi: [f64; 3], wos: &[[f64; 3]], lambda: f64) -> Vec<Estimate> {
        wos.par_iter()
            .map(|wo| self.scattered(wi, *wo, lambda))
            .collect()
    }

    /// Coherent (specular-delta) weight `|⟨U⟩|²` for R = 1 at incidence `wi`: the squared mean
    /// field over the whole map at `q = 2k cosθi`, less its estimated bias `v = Var⟨U⟩`
    /// (from the tile spectrum next to the specular direction), with standard error
    /// `sqrt(2|⟨U⟩|² v + v²)`.
    pub fn coherent(&self, wi: [f64; 3], lambda: f64) -> Estimate {
        let n = self.nx * self.ny;
        if !(wi[2] > 0.0 && lambda > 0.0) {
            return Estimate {
                value: 0.0,
                se: 0.0,
                n,
            };
        }
        let q = 4.0 * PI / lambda * wi[2];
        let (mut re, mut im) = (0.0, 0.0);
        for h in &self.heights {
            let (s, c) = (q * h).sin_cos();
            re += c;
            im -= s;
        }
        let c2 = (re * re + im * im) / (n * n) as f64;
        let d = self.resolution_step();
        let s0 = if self.is_profile() {
            self.spectrum((2.0 * d.0, 0.0), q).value
        } else {
            0.5 * (self.spectrum((2.0 * d.0, 0.0), q).value
                + self.spectrum((0.0, 2.0 * d.1), q).value)
        };
        let area_cell = if self.is_profile() {
            2.0 * PI / (self.nx as f64 * self.dx)
        } else {
            4.0 * PI * PI / (self.nx as f64 * self.dx * self.ny as f64 * self.dy)
        };
        let v = s0 * area_cell;
        Estimate {
            value: (c2 - v).max(0.0),
            se: (2.0 * c2 * v + v * v).sqrt(),
            n,
        }
    }

    /// Frequency step of one tile `(2π/(tx dx), 2π/(ty dy))` [rad/m].
    pub fn resolution_step(&self) -> (f64, f64) {
        (
            2.0 * PI / (self.tx as f64 * self.dx),
            if self.is_profile() {
                0.0
            } else {
                2.0 * PI / (self.ty as f64 * self.dy)
            },
        )
    }

    /// The trusted angular window at incidence `wi` and wavelength `lambda` [m].
    pub fn angular_window(&self, wi: [f64; 3], lambda: f64) -> AngularWindow {
        let k = 2.0 * PI / lambda;
        let q = k * (wi[2].clamp(0.0, 1.0) + 1.0);
        let (zn_x, zn_y) = (PI / self.dx, PI / self.dy);
        let floor = if self.is_profile() {
            self.spectrum((zn_x, 0.0), q).value
        } else {
            self.spectrum((zn_x, 0.0), q)
                .value
                .max(self.spectrum((0.0, zn_y), q).value)
                .max(self.spectrum((zn_x, zn_y), q).value)
        };
        let lobe = match self.window {
            Window::Hann => 2.0,
            Window::Rect => 1.0,
        };
        let (lx, ly) = self.tile_size();
        let l = if self.is_profile() { lx } else { lx.min(ly) };
        let nyq = (lambda / (2.0 * self.dx), lambda / (2.0 * self.dy));
        AngularWindow {
            lambda,
            resolution: lobe * lambda / l,
            nyquist: nyq,
            max_offset: (0.5 * nyq.0, 0.5 * nyq.1),
            alias_floor: floor,
            phase_step: q * self.rms_slope * self.dx.max(self.dy),
            shadow_alpha: self.rms_slope,
            g1_incidence: smith_g1_beckmann(self.rms_slope, wi[2].clamp(-1.0, 1.0).acos()),
        }
    }

    /// Quadrature of the tile window's unit-mass spectral kernel `K(ξ)` (what the estimate is
    /// smoothed with): `per_axis` equally spaced nodes over `±reach` tile frequency steps per
    /// axis, weights `K·spacing` normalised to 1. Returns `(ξx, ξy, weight)` [rad/m]; for a
    /// profile `ξy = 0`.
    pub fn kernel_nodes(&self, per_axis: usize, reach: f64) -> Vec<(f64, f64, f64)> {
        let per_axis = per_axis.max(1);
        let axis = |w: &[f64], d: f64, step: f64| -> Vec<(f64, f64)> {
            (0..per_axis)
                .map(|j| {
                    let xi = if per_axis == 1 {
                        0.0
                    } else {
                        reach * step * (2.0 * j as f64 / (per_axis - 1) as f64 - 1.0)
                    };
                    let s: Complex<f64> = phasors(w, xi * d).iter().sum();
                    (xi, s.norm_sqr())
                })
                .collect()
        };
        let step = self.resolution_step();
        let ax = axis(&self.wx, self.dx, step.0);
        let ay = if self.is_profile() {
            vec![(0.0, 1.0)]
        } else {
            axis(&self.wy, self.dy, step.1)
        };
        let mut nodes = Vec::with_capacity(ax.len() * ay.len());
        for &(yi, wyv) in &ay {
            for &(xi, wxv) in &ax {
                nodes.push((xi, yi, wxv * wyv));
            }
        }
        let total: f64 = nodes.iter().map(|n| n.2).sum();
        for n in &mut nodes {
            n.2 /= total;
        }
        nodes
    }
}

/// `w_i e^{−i φ i}` for `i = 0..w.len()`, by recurrence re-anchored every 64 steps.
fn phasors(w: &[f64], phi: f64) -> Vec<Complex<f64>> {
    let step = Complex::new(phi.cos(), -phi.sin());
    let mut out = Vec::with_capacity(w.len());
    let mut z = Complex::new(1.0, 0.0);
    for (i, wv) in w.iter().enumerate() {
        if i % 64 == 0 {
            let (s, c) = (phi * i as f64).sin_cos();
            z = Complex::new(c, -s);
        }
        out.push(z * *wv);
        z *= step;
    }
    out
}
