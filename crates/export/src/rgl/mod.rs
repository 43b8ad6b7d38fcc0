//! The RGL measured-BSDF format (Dupuy & Jakob 2018, "An Adaptive
//! Parameterization for Efficient Material Acquisition and Rendering"), read
//! by Mitsuba 3's and pbrt-v4's `measured` plugins.
//!
//! A file is a [tensor file](crate::tensor) with these fields (shapes
//! slowest first; angles in radians):
//!
//! | field | type, shape | meaning |
//! |---|---|---|
//! | `description` | u8 [n] | UTF-8 text |
//! | `jacobian` | u8 [1] | 1: spectra hold S = f cosθo · 4σ(ωi) / D(m) |
//! | `theta_i`, `phi_i` | f32 [nθ], [nφ] | incident directions of the slices (nφ ≤ 2: isotropic) |
//! | `ndf` | f32 [a, b] | D on (u_φ rows, u_θ columns) |
//! | `sigma` | f32 [c, d] | projected area σ(ωi) on (u_φ, u_θ) |
//! | `vndf` | f32 [nφ, nθ, e, f] | density of the visible normals per slice, on (u_φ, u_θ) of m (φ relative to φi when isotropic) |
//! | `luminance` | f32 [nφ, nθ, n, n] | density of the luminance warp on the unit square |
//! | `spectra` + `wavelengths` | f32 [nφ, nθ, nλ, n, n], [nλ] nm | S at the n × n nodes of the unit square |
//! | or `rgb` | f32 [nφ, nθ, 3, n, n] | S as linear sRGB (Mitsuba's RGB variants) |
//!
//! u_θ = √(2θ/π), u_φ = (φ + π)/2π. A reader maps the half vector m of
//! (ωi, ωo) to u_m, inverts the VNDF warp of ωi's slice to a point s of the
//! unit square, and returns f cosθo = S(s) D(u_m) / (4 σ(ωi)), every table
//! interpolated (bi)linearly, the slices linearly in φi, θi and λ.
//!
//! The exporter ([`build`]) computes D and σ from the model ([`crate::ndf`]),
//! the VNDF from D, places the n × n nodes of S where the readers' VNDF warp
//! sends the unit square's grid, and evaluates the model there, so that a
//! reader reproduces the model exactly at every node and by interpolation in
//! between; the luminance warp is S's luminance. It then reads its own file
//! back ([`RglTable`]) and measures the difference ([`crate::check`]).

mod read;
mod write;

pub use read::{RglTable, TableSample};
pub use write::build;

use crate::color::Illuminant;

/// What the file's colour table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Colour {
    /// `spectra` at the option's wavelengths (Mitsuba's spectral variants,
    /// pbrt-v4).
    #[default]
    Spectral,
    /// `rgb`: linear sRGB of the spectrum under the illuminant (Mitsuba's
    /// RGB variants; pbrt-v4 reads spectral files only).
    Rgb,
}

/// The table's resolution and contents.
#[derive(Clone, Debug, PartialEq)]
pub struct RglOptions {
    /// Incident elevations of the slices, degrees, strictly increasing in
    /// [0, 90]. A reader interpolates linearly between them and holds the
    /// last slice beyond it.
    pub theta_i_deg: Vec<f64>,
    /// Incident azimuth nodes over [−π, π] for an anisotropic model (≥ 3);
    /// isotropic models get one slice.
    pub phi_i_nodes: usize,
    /// n of the n × n grid of S and of the luminance warp.
    pub sample_nodes: usize,
    /// VNDF grid per slice: nodes along u_θ and u_φ.
    pub vndf_nodes: [usize; 2],
    /// NDF grid: nodes along u_θ and u_φ (u_φ is 2 for an isotropic model).
    pub ndf_nodes: [usize; 2],
    /// σ grid: nodes along u_θ and u_φ (u_φ is 2 for an isotropic model).
    pub sigma_nodes: [usize; 2],
    /// Wavelengths of S (nm), strictly increasing within the models' range
    /// 360–830 nm; for [`Colour::Rgb`], the spectrum integrated into RGB.
    pub wavelengths_nm: Vec<f64>,
    /// Spectral or RGB.
    pub colour: Colour,
    /// Light for RGB and for the luminance warp.
    pub illuminant: Illuminant,
    /// Leave out the model's coherent (delta) lobe instead of refusing to
    /// export a model that has one (a table holds glossy reflection only).
    pub drop_specular: bool,
    /// Text for the `description` field.
    pub description: String,
    /// Monte Carlo samples per checked incidence and wavelength of the error
    /// estimate (0: no estimate).
    pub check_samples: usize,
    /// Largest incidence (degrees) the error estimate covers.
    pub check_theta_max_deg: f64,
}

impl Default for RglOptions {
    fn default() -> RglOptions {
        RglOptions {
            // 4° steps to 60°, 2° beyond, where Fresnel, shadowing and the
            // wave-optical models' coherent fraction change fastest.
            theta_i_deg: (0..=15)
                .map(|k| 4.0 * k as f64)
                .chain((31..=44).map(|k| 2.0 * k as f64))
                .collect(),
            phi_i_nodes: 17,
            sample_nodes: 64,
            vndf_nodes: [128, 64],
            ndf_nodes: [256, 64],
            sigma_nodes: [128, 64],
            wavelengths_nm: (0..=47).map(|k| 360.0 + 10.0 * k as f64).collect(),
            colour: Colour::Spectral,
            illuminant: Illuminant::D65,
            drop_specular: false,
            description: String::new(),
            check_samples: 4096,
            check_theta_max_deg: 80.0,
        }
    }
}
