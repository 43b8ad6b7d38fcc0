//! Scenes: the TOML description ([`desc`]), the files it reads
//! ([`inputs`]), building it in stages ([`build`]) and the runtime scene the
//! integrator traces ([`Scene`], whose geometry answers ray queries:
//! [`Shapes`]).

mod build;
pub mod desc;
pub mod inputs;
mod shapes;
mod tables;

use crate::camera::Camera;
use crate::error::SceneError;
use crate::geometry::HitGeometry;
use crate::light::Lights;
use crate::material::Material;
use crate::spectral_table::SpectralTables;
use crate::wavelength::WavelengthSampler;
use desc::{MisHeuristic, SamplerKind, SceneDesc, SpectralIntegration, WavelengthMode};
use glam::DVec3;
pub use inputs::{FNV_OFFSET, InputFile, Inputs, fnv1a};
pub use shapes::Shapes;
use std::path::{Path, PathBuf};

/// The estimator version, hashed into every fingerprint: films rendered by
/// an earlier estimator (other wavelength or random-number sampling, other
/// inputs hashed) must not merge with new ones.
pub const ESTIMATOR: &str = "lustre estimator 10: sobol sampler with 64-bit sample indices, \
                             hero sets from a 2-D draw (base u/n, hero index), 16 per path \
                             for conductor-only scenes, power MIS, every input file hashed, \
                             first bounce off fresnel-only materials integrated over λ exactly, \
                             sphere lights sampled through the concentric disk, \
                             a constant environment left to BSDF sampling in conductor-only \
                             scenes, Beckmann's orthogonal slope by the AS 241 normal quantile, \
                             the light density counted up to twice in MIS where a microfacet \
                             lobe is not much narrower than the light, the emission \
                             along a mixed delta lobe's mirror direction traced at every vertex";

pub use crate::film::{MAX_EXPOSURE_STOPS, MAX_SPP};

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// A reflecting surface with this material index.
    Material(u32),
    /// An emitting shape: index into [`Lights::lights`].
    Emitter(u32),
}

/// A ray hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Geometry at the hit.
    pub geo: HitGeometry,
    /// What was hit.
    pub surface: Surface,
    /// Whether it is a mesh triangle (traversed in f32: needs a larger ray offset).
    pub mesh: bool,
    /// Interpolated vertex normal of a smooth-shaded mesh triangle (same
    /// orientation convention as `geo.n`); `None`: shade with `geo.n`.
    pub shading_n: Option<DVec3>,
}

impl Hit {
    /// A hit on an analytic shape (intersected in f64, shaded with its geometric normal).
    #[inline]
    pub fn analytic(geo: HitGeometry, surface: Surface) -> Hit {
        Hit {
            geo,
            surface,
            mesh: false,
            shading_n: None,
        }
    }
}

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

/// Parses a scene file's text into its description, with positioned errors.
pub fn parse(path: &Path, text: &str) -> Result<SceneDesc, SceneError> {
    toml::from_str::<SceneDesc>(text).map_err(|e| {
        let mut msg = e.message().trim().to_string();
        if let Some(hint) = e.span().and_then(|span| duplicate_hint(text, &msg, span)) {
            msg = hint;
        } else if let Some(hint) = shape_hint(text) {
            msg = format!("{msg} ({hint})");
        }
        match e.span() {
            Some(span) => SceneError::at(path, text, span.start, msg),
            None => SceneError::new(path, msg),
        }
    })
}

/// The tables a scene holds as arrays of tables, with what one entry is.
const ARRAYS_OF_TABLES: [(&str, &str); 2] = [("shapes", "shape"), ("lights", "light")];

/// The fix for an array of tables written as a table twice (`[lights]` …
/// `[lights]`), which toml reports only as "duplicate key", at the second
/// header: the key named, and the brackets to write.
fn duplicate_hint(text: &str, msg: &str, span: std::ops::Range<usize>) -> Option<String> {
    if !msg.starts_with("duplicate key") {
        return None;
    }
    let key = text.get(span.clone())?.trim().trim_matches(['"', '\'']);
    let (key, one) = ARRAYS_OF_TABLES.into_iter().find(|(k, _)| *k == key)?;
    // Only a table header: a duplicated key inside a table (`lights = 1`
    // twice) is another mistake, which the bare message describes.
    let line_start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
    if !text[line_start..span.start].trim_start().starts_with('[') {
        return None;
    }
    Some(format!(
        "duplicate key `{key}` ({key} are an array of tables: write [[{key}]] (two \
         brackets) for each {one})"
    ))
}

/// The fix for a top-level table written with the wrong brackets, which
/// serde reports only as a type mismatch ("invalid type: map, expected a
/// sequence").
fn shape_hint(text: &str) -> Option<String> {
    let table: toml::Table = text.parse().ok()?;
    for (key, one) in ARRAYS_OF_TABLES {
        if matches!(table.get(key), Some(v) if !v.is_array()) {
            return Some(format!(
                "{key} are an array of tables: write [[{key}]] before each {one}"
            ));
        }
    }
    match table.get("materials") {
        Some(toml::Value::Table(m)) if m.values().all(toml::Value::is_table) => None,
        Some(_) => Some(
            "materials are named tables: write [materials.NAME] (single brackets) before each \
             material's keys"
                .to_string(),
        ),
        None => None,
    }
}

/// Loads and builds a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = read_scene_text(path)?;
    load_str(path, &text)
}

/// Reads a scene file: at most [`inputs::MAX_SCENE_BYTES`], UTF-8.
fn read_scene_text(path: &Path) -> Result<String, SceneError> {
    let bytes = safe_io::read_input(path, "scene file", inputs::MAX_SCENE_BYTES).map_err(|e| {
        let hint = match e {
            safe_io::ReadError::TooLarge { .. } => {
                " (scenes describe geometry by reference: put meshes in OBJ files)"
            }
            _ => "",
        };
        SceneError::new(path, format!("{e}{hint}"))
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let off = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
        SceneError::at(path, &text, off, "the scene file is not UTF-8 text")
    })
}

/// Builds a scene from its text (`path` locates relative files and errors).
pub fn load_str(path: &Path, text: &str) -> Result<Scene, SceneError> {
    if text.len() as u64 > inputs::MAX_SCENE_BYTES {
        return Err(SceneError::new(
            path,
            format!(
                "the scene text is larger than {} MiB",
                inputs::MAX_SCENE_BYTES >> 20
            ),
        ));
    }
    let desc = parse(path, text)?;
    build::build(path, text, &desc)
}
