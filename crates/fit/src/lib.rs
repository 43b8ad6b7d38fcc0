//! From a measured surface scan to a renderable material.
//!
//! * [`io`] reads instrument files into a [`Topography`] (heights and lengths in metres,
//!   invalid points as NaN).
//! * [`fill`], [`level`] prepare the map; [`stats`] gives Sq/Sdq; [`psd`] computes Welch
//!   line PSDs and radially averaged 2D PSDs; [`kc`] fits the K-correlation model;
//!   [`ndf`] builds and fits normal distributions; [`two_scale`] splits a surface at a
//!   cutoff period; [`material`] builds the TOML material file the renderer includes.
//! * [`synth`] generates surfaces with a prescribed K-correlation PSD (for tests and benches).
//!
//! Conventions: spatial frequencies `f` are in cycles per metre unless a name says
//! `zeta` (rad per length, the physics.md convention). The 1D K-correlation form uses the
//! reference-table length `L = 2π·Lc`, where `Lc` is the Matérn range of physics.md §2.

pub mod anisotropy;
pub mod areal;
pub mod candidates;
pub mod error;
pub mod explicit_brdf;
mod fft;
pub mod field_spectrum;
pub mod fill;
pub mod io;
pub mod kc;
pub mod kc2d;
pub mod level;
pub mod material_file;
pub mod ndf;
mod ordered_sum;
pub mod pipeline;
pub mod psd;
pub mod psd_map;
pub mod quality;
pub mod resample;
pub mod rng;
pub mod sampled_kc;
pub mod sha256;
pub mod stats;
pub mod stats_report;
pub mod surrogate;
pub mod synth;
pub mod topography;
pub mod two_scale;

pub use error::{FitError, ReadError};
pub use topography::Topography;
