//! The far field of an explicit height map in the Kirchhoff / Harvey–Shack scalar theory, on
//! the FFT grid: the periodogram of the reflected field `U(x) = exp(−i q h(x))` for one phase
//! scale `q = k (cosθi + cosθo)` (one transform per `q`).
//!
//! **Sign.** The far-field amplitude toward `o` for light arriving from `i` (both unit vectors
//! pointing away from the surface) is `∝ ∫ exp(−i k (o + i)·r) d²x` over the surface
//! `r = (x, h(x))`, i.e. `∫ exp(−i ζ·x) U(x) d²x` with `ζ = k(o⊥ + i⊥)` (physics.md §1). A facet
//! tilted by slope `a` along x therefore sends its light to `ζx = −q a`, the geometric mirror
//! direction of the facet; the sign matters for skewed or blazed surfaces, not for Gaussian ones.
//!
//! **Normalisation** (rad convention of physics.md §1). With window `w`, pixel area `dA` and the
//! windowed mean `c = Σ w U / Σ w`,
//!
//! ```text
//! P̂(ζ) = |Σ_j w_j (U_j − c) e^{−iζ·x_j} dA|² / ((2π)² dA Σ_j w_j²)        [m² for maps]
//! ```
//!
//! For a stationary surface `E[P̂] = (S ⋆ K_w)(ζ)` (+ aliases from beyond the Nyquist frequency),
//! where `S(ζ) = F_rad{⟨U(x+r) U*(x)⟩ − |⟨U⟩|²}` and `K_w` is the window's unit-mass spectral
//! kernel. For Gaussian heights `⟨U(x+r)U*(x)⟩ = exp(−g(1 − M(r)))` and `|⟨U⟩|² = e^{−g}` with
//! `g = q²σ²`, so `S` is exactly physics.md's `S(ζ; g)` and the scattered BRDF is `R k² P̂`;
//! the coherent (specular) part is `R |c|²`. For a periodic map and the rectangular window the
//! grid bins carry no leakage: `E[P̂(ζ_k)]` equals the (aliased) `S(ζ_k)` exactly for `k ≠ 0`.
//!
//! **Parseval.** `Σ_grid P̂ Δζx Δζy = Σ w² |U − c|² / Σ w²`, which is `1 − |c|²` for the
//! rectangular window: scattered + coherent = 1 (R = 1) before the evanescent part is removed.
//!
//! A profile (`ny == 1`) gives the 1-D version, `P̂₁(ζx) = |Σ w (U − c) e^{−iζx x} dx|² /
//! (2π dx Σ w²)` [m], whose expectation for an isotropic surface is the line marginal
//! `∫ S(ζx, ζy) dζy`.

use crate::psd::hann;
use crate::{FitError, Topography};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// Data taper applied before the transform.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// No taper: exact for periodic (synthetic) maps, leaks for measured ones.
    Rect,
    /// Separable periodic Hann taper (as [`crate::psd::hann`]): sidelobes fall as ζ⁻⁶.
    Hann,
}

impl Window {
    /// The taper of length `n`.
    pub fn weights(self, n: usize) -> Vec<f64> {
        match self {
            Window::Rect => vec![1.0; n],
            Window::Hann => hann(n),
        }
    }
}

/// Periodogram of `exp(−i q h)` on the FFT grid of a whole map or profile.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSpectrum {
    /// Grid points along x.
    pub nx: usize,
    /// Grid points along y (1 for a profile).
    pub ny: usize,
    /// Frequency step along x [rad/m] (`2π / (nx dx)`).
    pub dzeta_x: f64,
    /// Frequency step along y [rad/m] (0 for a profile).
    pub dzeta_y: f64,
    /// `P̂` in FFT order, row-major `[iy * nx + ix]`; m² for maps, m for profiles.
    /// The DC bin holds what is left after subtracting the windowed mean (≈ 0).
    pub p: Vec<f64>,
    /// Windowed mean field `c = Σ w U / Σ w` (real, imaginary).
    pub mean: (f64, f64),
    /// Coherent fraction `|c|²` (R = 1).
    pub coherent: f64,
    /// `Σ w² |U − c|² / Σ w²`, which [`FieldSpectrum::total`] reproduces (Parseval).
    pub windowed_variance: f64,
    /// Phase scale `q` [rad/m].
    pub q: f64,
    /// Window used.
    pub window: Window,
    /// `N Σw² / (Σw)²`: 1 for the rectangular window, 2.25 for the 2-D Hann window.
    pub variance_factor: f64,
}

impl FieldSpectrum {
    /// Signed frequency of bin `(ix, iy)` [rad/m].
    pub fn zeta(&self, ix: usize, iy: usize) -> (f64, f64) {
        (
            crate::fft::signed(ix, self.nx) * self.dzeta_x,
            crate::fft::signed(iy, self.ny) * self.dzeta_y,
        )
    }

    /// `P̂` at bin `(ix, iy)`.
    pub fn at(&self, ix: usize, iy: usize) -> f64 {
        self.p[iy * self.nx + ix]
    }

    /// Area (length for a profile) of one frequency cell.
    pub fn cell(&self) -> f64 {
        if self.ny == 1 {
            self.dzeta_x
        } else {
            self.dzeta_x * self.dzeta_y
        }
    }

    /// `Σ P̂ · cell` over the whole grid: the scattered power before the evanescent cut.
    pub fn total(&self) -> f64 {
        self.p.iter().sum::<f64>() * self.cell()
    }

    /// Estimated variance `v` of the coherent amplitude `c`, `Var c ≈ S(0)·cell·N Σw²/(Σw)²`
    /// with `S(0)` read from the bins around DC that the mean subtraction leaves untouched
    /// (ring 1 for the rectangular window, ring 2 for Hann). The coherent fraction is biased
    /// upwards by about `v` and has a standard error of about `sqrt(2|c|² v + v²)`.
    pub fn coherent_variance(&self) -> f64 {
        let mut s = 0.0;
        let mut n = 0.0f64;
        let ring: isize = match self.window {
            Window::Rect => 1,
            Window::Hann => 2,
        };
        let ry = if self.ny == 1 { 0 } else { ring };
        for dy in -ry..=ry {
            for dx in -ring..=ring {
                if dx.abs().max(dy.abs()) != ring {
                    continue;
                }
                let ix = dx.rem_euclid(self.nx as isize) as usize;
                let iy = dy.rem_euclid(self.ny as isize) as usize;
                s += self.at(ix, iy);
                n += 1.0;
            }
        }
        let s0 = s / n.max(1.0);
        s0 * self.cell() * self.variance_factor
    }
}

/// Periodogram of `exp(−i q h)` of a levelled, NaN-free map or profile with `window`.
/// `q` is in rad per unit of height (rad/m for SI heights).
pub fn field_spectrum(t: &Topography, q: f64, window: Window) -> Result<FieldSpectrum, FitError> {
    check(t)?;
    if !q.is_finite() {
        return Err(FitError::data(
            "field spectrum",
            format!("phase scale q = {q} is not finite"),
        ));
    }
    let (nx, ny) = (t.nx, t.ny);
    let wx = window.weights(nx);
    let wy = if ny == 1 {
        vec![1.0]
    } else {
        window.weights(ny)
    };
    let (mut sw, mut sw2) = (0.0, 0.0);
    let mut c = Complex::new(0.0, 0.0);
    let mut buf = Vec::with_capacity(nx * ny);
    for (row, wyv) in t.heights.chunks(nx).zip(&wy) {
        for (h, wxv) in row.iter().zip(&wx) {
            let w = wxv * wyv;
            let (s, co) = (q * h).sin_cos();
            let u = Complex::new(co, -s);
            c += u * w;
            sw += w;
            sw2 += w * w;
            buf.push(u);
        }
    }
    if sw.is_nan() || sw <= 0.0 {
        return Err(FitError::data(
            "field spectrum",
            "the window has no weight (map too small)",
        ));
    }
    c /= sw;
    let mut var = 0.0;
    for (row, wyv) in buf.chunks_mut(nx).zip(&wy) {
        for (v, wxv) in row.iter_mut().zip(&wx) {
            *v = (*v - c) * (wxv * wyv);
            var += v.norm_sqr();
        }
    }
    let mut planner = FftPlanner::<f64>::new();
    crate::fft::fft2(&mut buf, nx, ny, &mut planner, false);
    let (dzx, dzy, scale) = if ny == 1 {
        (2.0 * PI / (nx as f64 * t.dx), 0.0, t.dx / (2.0 * PI * sw2))
    } else {
        (
            2.0 * PI / (nx as f64 * t.dx),
            2.0 * PI / (ny as f64 * t.dy),
            t.dx * t.dy / (4.0 * PI * PI * sw2),
        )
    };
    Ok(FieldSpectrum {
        nx,
        ny,
        dzeta_x: dzx,
        dzeta_y: dzy,
        p: buf.iter().map(|v| v.norm_sqr() * scale).collect(),
        mean: (c.re, c.im),
        coherent: c.norm_sqr(),
        windowed_variance: var / sw2,
        q,
        window,
        variance_factor: (nx * ny) as f64 * sw2 / (sw * sw),
    })
}

pub(crate) fn check(t: &Topography) -> Result<(), FitError> {
    if t.nx < 4 || t.heights.len() != t.nx * t.ny || t.ny == 0 || (t.ny > 1 && t.ny < 4) {
        return Err(FitError::data(
            "explicit BRDF",
            format!(
                "needs a profile of ≥ 4 points or a map of ≥ 4 × 4 points, got {} × {}. \
                 Fix: give it a longer profile or a larger map (re-export the whole scan)",
                t.nx, t.ny
            ),
        ));
    }
    if !(t.dx > 0.0 && t.dx.is_finite() && (t.ny == 1 || (t.dy > 0.0 && t.dy.is_finite()))) {
        return Err(FitError::data(
            "explicit BRDF",
            format!("pixel spacing ({}, {}) must be positive", t.dx, t.dy),
        ));
    }
    if t.heights.iter().any(|h| !h.is_finite()) {
        return Err(FitError::data(
            "explicit BRDF",
            "the map has invalid points; fill and level it first (fit::pipeline::prepare)",
        ));
    }
    Ok(())
}

/// Energy balance of the explicit BRDF at one incidence (R = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Albedo {
    /// Coherent (specular) weight `|c|²` at `q = 2k cosθi`.
    pub coherent: f64,
    /// `∫_{H²} f cosθo dω = ∫_{|o⊥|<1} f d²o⊥` of the scattered part, with each direction's own
    /// `q(o)` (linear interpolation between the band transforms).
    pub scattered: f64,
    /// Scattered power of the specular-`q` transform that falls outside the propagating disk
    /// (evanescent), for the energy account: `coherent + in-disk + outside = 1` at frozen `q`.
    pub evanescent_frozen: f64,
    /// Transforms used for the scattered part.
    pub bands: usize,
}

impl Albedo {
    /// `coherent + scattered`: the patch's directional reflectance in the scalar theory.
    pub fn total(&self) -> f64 {
        self.coherent + self.scattered
    }
}

/// Hemispherical integral of the explicit BRDF at incidence `wi` (unit vector away from the
/// surface), wavelength `lambda` [m], from `bands` transforms at `cosθo` nodes evenly spaced
/// over [0, 1] (`bands == 1`: `q` frozen at the specular value `2k cosθi`). The error of the
/// banding is the change when `bands` doubles; the grid sum itself is exact (Parseval).
pub fn hemispherical_albedo(
    t: &Topography,
    wi: [f64; 3],
    lambda: f64,
    bands: usize,
    window: Window,
) -> Result<Albedo, FitError> {
    if !(wi[2] > 0.0 && wi[2] <= 1.0 + 1e-12 && lambda > 0.0 && bands >= 1) {
        return Err(FitError::data(
            "hemispherical albedo",
            "needs cosθi in (0, 1], λ > 0 and at least one band",
        ));
    }
    let k = 2.0 * PI / lambda;
    let ci = wi[2].min(1.0);
    let spec = field_spectrum(t, 2.0 * k * ci, window)?;
    let nodes: Vec<f64> = if bands == 1 {
        vec![ci]
    } else {
        (0..bands).map(|j| j as f64 / (bands - 1) as f64).collect()
    };
    let spectra: Vec<FieldSpectrum> = if bands == 1 {
        vec![spec.clone()]
    } else {
        nodes
            .iter()
            .map(|c| field_spectrum(t, k * (ci + c), window))
            .collect::<Result<_, _>>()?
    };
    let (mut inside, mut inside_frozen) = (0.0, 0.0);
    for iy in 0..spec.ny {
        for ix in 0..spec.nx {
            let (zx, zy) = spec.zeta(ix, iy);
            let (ox, oy) = (
                zx / k - wi[0],
                if spec.ny == 1 { 0.0 } else { zy / k - wi[1] },
            );
            let r = (ox * ox + oy * oy).sqrt();
            if r >= 1.0 {
                continue;
            }
            inside_frozen += spec.at(ix, iy);
            let co = ((1.0 - r) * (1.0 + r)).sqrt();
            let p = if bands == 1 {
                spectra[0].at(ix, iy)
            } else {
                let x = co * (bands - 1) as f64;
                let j = (x.floor() as usize).min(bands - 2);
                let f = x - j as f64;
                (1.0 - f) * spectra[j].at(ix, iy) + f * spectra[j + 1].at(ix, iy)
            };
            inside += p;
        }
    }
    let cell = spec.cell();
    Ok(Albedo {
        coherent: spec.coherent,
        scattered: inside * cell,
        evanescent_frozen: spec.total() - inside_frozen * cell,
        bands,
    })
}

#[cfg(test)]
mod too_small_tests {
    use super::*;

    /// A map too small for the explicit BRDF is refused with its size and
    /// what to do about it (a 3 × 4 text export).
    #[test]
    fn a_map_too_small_is_refused_with_its_size_and_the_fix() {
        let t = Topography {
            nx: 3,
            ny: 4,
            dx: 1e-6,
            dy: 1e-6,
            heights: vec![0.0; 12],
            channel: "z".into(),
            format: "test",
        };
        let e = check(&t).unwrap_err().to_string();
        assert!(e.contains("got 3 × 4") && e.contains("Fix: "), "{e}");
    }
}
