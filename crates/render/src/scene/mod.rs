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
use crate::guide::Casters;
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
pub const ESTIMATOR: &str = "lustre estimator 16";

/// The share of a scene-with-bands' wavelength density spread uniformly
/// over its emission range ([`Scene::set_spectral_bands`]): with 256 bands a
/// band at either end of 360–830 nm gets ≥ 1/5 of a uniform density's
/// wavelengths, against ~10⁻⁴ of the peak density without; the second
/// moment of a colour estimate grows by at most 1/(1 − ⅕).
pub const BAND_UNIFORM_SHARE: f64 = 0.2;

/// Most BSDF continuations `[integrator] branches` may ask for.
pub const MAX_BRANCHES: u32 = 64;

/// Default `[integrator] caustic_guiding`.
pub const DEFAULT_CAUSTIC_GUIDING: f64 = 0.0;

/// Default `[integrator] glossy_residual`.
pub const DEFAULT_GLOSSY_RESIDUAL: f64 = 1.0;

/// Smallest `[integrator] glossy_residual`: below it the residual's 1/p
/// weight would make rare samples fireflies.
pub const MIN_GLOSSY_RESIDUAL: f64 = 1e-3;

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
    /// `[integrator] delta_pixel_samples` (default 1): where a first
    /// vertex's delta lobe is integrated over λ exactly, the emission it
    /// reflects is averaged over this many positions in the pixel per camera
    /// sample (a camera ray and a mirror ray each), for the sharp edge of a
    /// small light's mirror image (`integrator::delta_over_pixel`).
    pub delta_pixel_samples: usize,
    /// `[integrator] glossy_residual` (default [`DEFAULT_GLOSSY_RESIDUAL`]):
    /// the probability with which a first vertex's light sample evaluates
    /// the glossy control variate's residual f − f̃ (weighted by its
    /// inverse), instead of only the exact part (`integrator::glossy_cv`).
    pub glossy_residual: f64,
    /// `[integrator] emitter_pixel_samples` (default
    /// [`crate::emitter_edges::DEFAULT_SAMPLES`]; 1 turns it off): on the
    /// pixels a directly seen light's outline may cross, the emission seen
    /// directly is averaged over this many positions in the pixel per camera
    /// sample (a camera ray each; `integrator::emission_over_pixel`).
    pub emitter_pixel_samples: usize,
    /// `[integrator] caustic_guiding` (default [`DEFAULT_CAUSTIC_GUIDING`]):
    /// the share of the BSDF samples of diffuse and rough-plastic surfaces
    /// drawn toward glossy objects instead of from the BSDF, weighted by the
    /// mixture's density ([`crate::guide`]). 0 turns it off.
    pub caustic_guiding: f64,
    /// `[integrator] branches`: the BSDF continuations a camera sample
    /// splits into at its first vertex (`integrator::branches`), or `None`
    /// for one (no split).
    pub branches: Option<u32>,
    /// EXR output path.
    pub exr: Option<PathBuf>,
    /// PNG output path.
    pub png: Option<PathBuf>,
    /// Exposure in stops.
    pub exposure: f64,
    /// Spectral bands over 360–830 nm the film holds beside XYZ (0: none);
    /// set through [`Scene::set_spectral_bands`].
    pub spectral_bands: usize,
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
    /// The exact spectral integrals of λ-flat paths and the first bounce,
    /// when some material is Fresnel-only or λ-free and
    /// `spectral_integration = "auto"`.
    pub spectral: Option<SpectralTables>,
    /// The glossy objects diffuse surfaces aim a share of their samples at.
    pub casters: Casters,
    /// The pixels a directly seen emitter's outline may cross, where the
    /// emission seen directly is averaged over the pixel; `None` where no
    /// outline is in view, `emitter_pixel_samples` is 1 or λ is not
    /// integrated exactly.
    pub emitter_edges: Option<crate::emitter_edges::EmitterEdges>,
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
    /// average, and only non-finite samples are dropped. Likewise when a
    /// material has a glossy control variate (`glossy_lambda_table.rs`),
    /// whose estimate may be negative.
    pub signed_radiance: bool,
}

impl Scene {
    /// An empty film for this scene: its resolution, fingerprint, seed,
    /// exposure and input records.
    pub fn film(&self) -> Result<Film, String> {
        Film::new(
            self.camera.width,
            self.camera.height,
            self.fingerprint,
            self.settings.seed,
            self.settings.exposure,
        )?
        .with_inputs(self.inputs.clone())
        .with_bands(self.settings.spectral_bands)
    }

    /// Renders `n` spectral bands (1..=[`MAX_BANDS`](crate::film::MAX_BANDS))
    /// beside XYZ, or none (0). Bands need the spectrum of every
    /// contribution, so a scene with bands integrates nothing over λ
    /// exactly (as `spectral_integration = "sampled"`), and its wavelength
    /// density spreads [`BAND_UNIFORM_SHARE`] of its probability uniformly
    /// so that every band gets wavelengths. Its samples differ from the
    /// scene's without bands; films refuse to combine across band counts.
    pub fn set_spectral_bands(&mut self, n: usize) -> Result<(), String> {
        let pixels = self.camera.width as u64 * self.camera.height as u64;
        if n > crate::film::MAX_BANDS
            || pixels.saturating_mul(n as u64) > crate::film::MAX_BAND_SUMS
        {
            return Err(format!(
                "{n} spectral bands for {}×{} pixels: expected 0..={} bands and at most {} \
                 pixels × bands",
                self.camera.width,
                self.camera.height,
                crate::film::MAX_BANDS,
                crate::film::MAX_BAND_SUMS
            ));
        }
        if n == self.settings.spectral_bands {
            return Ok(());
        }
        if self.settings.spectral_bands == 0 {
            self.spectral = None;
            let (lo, hi) = self.wavelengths.range();
            self.wavelengths = WavelengthSampler::with_uniform_share(lo, hi, BAND_UNIFORM_SHARE);
            self.prepared
                .push_str(&format!("; {n} spectral bands (λ sampled at every bounce)"));
        } else if n == 0 {
            return Err(
                "spectral bands cannot be removed from a scene built with them: load it again"
                    .into(),
            );
        }
        self.settings.spectral_bands = n;
        Ok(())
    }
}
