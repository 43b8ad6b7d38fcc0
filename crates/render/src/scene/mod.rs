//! Scenes: the TOML description ([`desc`]), reading and parsing it
//! ([`load`]), writing it ([`mod@write`]), the scenes lustre makes itself
//! ([`presets`]), building it in stages (`build`) and the runtime scene
//! the integrator traces ([`Scene`]).
//!
//! The files a build reads are recorded by [`crate::inputs`], also reachable
//! as `scene::inputs`.

mod build;
pub mod desc;
mod load;
pub mod presets;
mod tables;
pub mod write;

use crate::camera::Camera;
use crate::film::Film;
pub use crate::film::{MAX_EXPOSURE_STOPS, MAX_SPP};
pub use crate::inputs;
use crate::inputs::InputFile;
use crate::light::Lights;
use crate::material::Material;
use crate::shapes::Shapes;
use crate::spectral_table::SpectralTables;
use crate::wavelength::WavelengthSampler;
use desc::{MisHeuristic, SamplerKind, SpectralIntegration, WavelengthMode};
pub use load::{load, load_str, parse};
use std::path::PathBuf;

/// The estimator's version, hashed into every fingerprint. Raise it whenever
/// the same inputs give other sample values (other wavelength or
/// random-number sampling, other weights, other inputs hashed), so that
/// films of an earlier estimator refuse to merge with or resume into new
/// ones.
pub const ESTIMATOR: &str = "lustre estimator 10";

/// Render settings from `[film]` and `[integrator]`.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Samples per pixel.
    pub spp: u64,
    /// Seed.
    pub seed: u64,
    /// Maximum scattering events.
    pub max_depth: u32,
    /// Depth from which Russian roulette applies.
    pub rr_depth: u32,
    /// Wavelength sampling mode.
    pub mode: WavelengthMode,
    /// Wavelengths each path carries in `hero` mode: `[integrator]
    /// hero_wavelengths`, or by default
    /// [`HERO_COUNT_CONDUCTORS`](crate::wavelength::HERO_COUNT_CONDUCTORS)
    /// when every material is a microfacet or smooth conductor and
    /// [`HERO_COUNT`](crate::wavelength::HERO_COUNT) otherwise.
    pub hero_wavelengths: usize,
    /// Random-number source of camera samples.
    pub sampler: SamplerKind,
    /// Weighting of light and BSDF sampling.
    pub mis: MisHeuristic,
    /// How many times the light-sampling density counts in it: `[integrator]
    /// mis_light_weight`; unset, `None` (the per-vertex choice of
    /// `integrator::light_weight`) with the Sobol sampler and 1 with the
    /// independent one.
    pub mis_light_weight: Option<f64>,
    /// Exact or sampled integration over λ.
    pub spectral_integration: SpectralIntegration,
    /// EXR output path.
    pub exr: Option<PathBuf>,
    /// PNG output path.
    pub png: Option<PathBuf>,
    /// Exposure in stops.
    pub exposure: f64,
}

impl Settings {
    /// Wavelengths each path carries: 1 in `single` mode, `hero_wavelengths` in `hero` mode.
    #[inline]
    pub fn wavelengths_per_path(&self) -> usize {
        match self.mode {
            WavelengthMode::Single => 1,
            WavelengthMode::Hero => self.hero_wavelengths,
        }
    }
}

/// A scene ready to render.
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Camera.
    pub camera: Camera,
    /// Settings.
    pub settings: Settings,
    /// Materials in use, in order of first use.
    pub materials: Vec<Material>,
    /// Everything a ray can hit, with the ray queries.
    pub shapes: Shapes,
    /// Lights.
    pub lights: Lights,
    /// Wavelength distribution over the emission range.
    pub wavelengths: WavelengthSampler,
    /// The exact spectral integrals of the first bounce, when some material
    /// is Fresnel-only and `spectral_integration = "auto"`.
    pub spectral: Option<SpectralTables>,
    /// Hash of everything that determines the per-sample values (not spp or outputs).
    pub fingerprint: u64,
    /// The files the scene was built from, with their hashes (the scene file
    /// itself first, hashed without the keys that do not change samples).
    pub inputs: Vec<InputFile>,
    /// One line describing what was prepared and how long it took.
    pub prepared: String,
    /// Whether an emitter's spectrum may be negative at some wavelengths
    /// (an RGB-lifted environment map, see [`crate::light::RgbLift`], or a
    /// daylight sky, whose CIE basis spectrum is negative in the blue for a
    /// low sun): then a
    /// negative estimate at one wavelength is part of an unbiased colour
    /// average, and only non-finite samples are dropped.
    pub signed_radiance: bool,
}

impl Scene {
    /// An empty film for this scene: its resolution, fingerprint, seed,
    /// exposure and input records.
    pub fn film(&self) -> Result<Film, String> {
        Ok(Film::new(
            self.camera.width,
            self.camera.height,
            self.fingerprint,
            self.settings.seed,
            self.settings.exposure,
        )?
        .with_inputs(self.inputs.clone()))
    }
}
