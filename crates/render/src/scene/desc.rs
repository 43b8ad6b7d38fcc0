//! The scene file as written: serde types mirroring the TOML schema.
//!
//! Every table denies unknown keys, so a misspelt key is an error that lists
//! the valid ones. Defaults are only used where this file documents them.
//!
//! The types serialise too, leaving out every key at its default, so a
//! scene can be built in code and written as a file ([`super::write`]) that
//! parses back to the same description. Positions ([`Spanned`]) are those of
//! a parsed text; a description built in code has none ([`spanless`]).

use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;
use std::path::PathBuf;
use toml::Spanned;

/// `[T; N]` read from an array of exactly `N` elements. serde's array impl
/// stops after `N` elements and the TOML deserializer does not complain
/// about the rest, so without this `resolution = [320, 240, 7, …]` would
/// pass as `[320, 240]`. The surplus is counted (without storing it) for the
/// message.
struct Exact<T, const N: usize>([T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an array of exactly {N} numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut v = Vec::with_capacity(N);
                while v.len() < N {
                    match seq.next_element()? {
                        Some(x) => v.push(x),
                        None => return Err(de::Error::invalid_length(v.len(), &self)),
                    }
                }
                let mut extra = 0usize;
                while seq.next_element::<IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(de::Error::invalid_length(N + extra, &self));
                }
                match v.try_into() {
                    Ok(a) => Ok(Exact(a)),
                    Err(_) => Err(de::Error::invalid_length(N, &self)),
                }
            }
        }
        d.deserialize_seq(V(PhantomData))
    }
}

/// A value with no position in any text: a description built in code.
pub fn spanless<T>(value: T) -> Spanned<T> {
    Spanned::new(0..0, value)
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

fn exact<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<[T; N], D::Error> {
    Ok(Exact::<T, N>::deserialize(d)?.0)
}

fn exact_spanned<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<Spanned<[T; N]>, D::Error> {
    let s = Spanned::<Exact<T, N>>::deserialize(d)?;
    let span = s.span();
    Ok(Spanned::new(span, s.into_inner().0))
}

/// A whole scene file.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// The camera.
    pub camera: CameraDesc,
    /// Samples, seed and outputs.
    pub film: FilmDesc,
    /// Path-tracing settings (all keys optional).
    #[serde(default, skip_serializing_if = "is_default")]
    pub integrator: IntegratorDesc,
    /// Named materials, `[materials.NAME]`.
    #[serde(default)]
    pub materials: BTreeMap<String, Spanned<MaterialDesc>>,
    /// `[[shapes]]` entries.
    #[serde(default)]
    pub shapes: Vec<Spanned<ShapeDesc>>,
    /// `[[lights]]` entries.
    #[serde(default)]
    pub lights: Vec<Spanned<LightDesc>>,
}

/// `[camera]`: a pinhole perspective camera.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    #[serde(deserialize_with = "exact_spanned")]
    pub look_from: Spanned<[f64; 3]>,
    /// Point the camera looks at.
    #[serde(deserialize_with = "exact_spanned")]
    pub look_at: Spanned<[f64; 3]>,
    /// Up direction (default +y).
    #[serde(
        default = "default_up",
        deserialize_with = "exact_spanned",
        skip_serializing_if = "is_default_up"
    )]
    pub up: Spanned<[f64; 3]>,
    /// Vertical field of view in degrees, in (0, 179).
    pub fov_deg: Spanned<f64>,
    /// Image width and height in pixels.
    #[serde(deserialize_with = "exact_spanned")]
    pub resolution: Spanned<[u32; 2]>,
}

fn zero_stops() -> Spanned<f64> {
    Spanned::new(0..0, 0.0)
}

fn default_up() -> Spanned<[f64; 3]> {
    Spanned::new(0..0, [0.0, 1.0, 0.0])
}

fn is_default_up(up: &Spanned<[f64; 3]>) -> bool {
    *up == default_up()
}

fn is_zero_stops(stops: &Spanned<f64>) -> bool {
    *stops.get_ref() == 0.0
}

/// `[film]`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    /// Samples per pixel (≥ 1).
    pub spp: Spanned<u64>,
    /// Random seed (default 0).
    #[serde(default, skip_serializing_if = "is_default")]
    pub seed: u64,
    /// Linear sRGB float EXR output, relative to the working directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exr: Option<PathBuf>,
    /// 8-bit sRGB PNG output, relative to the working directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub png: Option<PathBuf>,
    /// Exposure in stops applied to both outputs (default 0; at most
    /// [`MAX_EXPOSURE_STOPS`](super::MAX_EXPOSURE_STOPS) either way).
    #[serde(default = "zero_stops", skip_serializing_if = "is_zero_stops")]
    pub exposure: Spanned<f64>,
    /// Spectral bands of equal width over 360–830 nm written beside RGB
    /// (1..=[`MAX_BANDS`](crate::film::MAX_BANDS); unset or 0: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectral_bands: Option<Spanned<u32>>,
}

/// How wavelengths are sampled per camera path.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum WavelengthMode {
    /// One wavelength per path.
    Single,
    /// Several stratified wavelengths per path with spectral MIS (Wilkie et
    /// al. 2014): `hero_wavelengths` of them, by default 16 in scenes whose
    /// materials are all conductors and 4 otherwise.
    #[default]
    Hero,
}

/// Where the random numbers of a camera sample come from (see `sampler.rs`).
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points, padded per draw (Burley 2020).
    #[default]
    Sobol,
    /// Independent uniform numbers (white noise).
    Independent,
}

/// How next-event estimation and BSDF sampling are weighted (Veach 1997).
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum MisHeuristic {
    /// w_s = p_s² / Σ p². Near-zero weight for the rare BSDF hits on small
    /// lights, whose balance-heuristic weight would leave visible noise.
    #[default]
    Power,
    /// w_s = p_s / Σ p.
    Balance,
}

/// `[integrator]`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntegratorDesc {
    /// Maximum number of scattering events along a path (default 8; 1 = direct light only).
    #[serde(default = "default_depth", skip_serializing_if = "is_default_depth")]
    pub max_depth: Spanned<u32>,
    /// `hero` (default) or `single`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub wavelengths: WavelengthMode,
    /// Wavelengths per path in `hero` mode, 2–16 (default: 16 when every
    /// material is a microfacet or smooth conductor, 4 otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hero_wavelengths: Option<Spanned<u32>>,
    /// Bounces before Russian roulette may end a path (default 3).
    #[serde(default = "default_rr", skip_serializing_if = "is_default_rr")]
    pub rr_depth: u32,
    /// `sobol` (default) or `independent`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub sampler: SamplerKind,
    /// `power` (default) or `balance`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub mis: MisHeuristic,
    /// How many times the light-sampling density counts in the MIS
    /// heuristic, > 0 (1 is the textbook heuristic); unset, it is chosen per
    /// vertex and light ([`Settings::mis_light_weight`](super::Settings::mis_light_weight)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mis_light_weight: Option<Spanned<f64>>,
    /// `auto` (default), `glossy` or `sampled`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub spectral_integration: SpectralIntegration,
    /// Positions per camera sample at which a first vertex's exactly
    /// integrated delta lobe is evaluated, 1–64 (default 1)
    /// ([`Settings::delta_pixel_samples`](super::Settings::delta_pixel_samples)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delta_pixel_samples: Option<Spanned<u32>>,
    /// Probability, 0.001–1, with which a first vertex's light sample
    /// evaluates the glossy control variate's residual (default
    /// [`DEFAULT_GLOSSY_RESIDUAL`](super::DEFAULT_GLOSSY_RESIDUAL))
    /// ([`Settings::glossy_residual`](super::Settings::glossy_residual)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glossy_residual: Option<Spanned<f64>>,
    /// Positions per camera sample at which the emission seen directly is
    /// evaluated on a light's outline, 1–64 (default 16; 1: off)
    /// ([`Settings::emitter_pixel_samples`](super::Settings::emitter_pixel_samples)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emitter_pixel_samples: Option<Spanned<u32>>,
    /// Share of the BSDF samples of diffuse and rough-plastic surfaces
    /// aimed at glossy objects, 0–0.9 (default 0: off)
    /// ([`Settings::caustic_guiding`](super::Settings::caustic_guiding)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caustic_guiding: Option<Spanned<f64>>,
    /// BSDF continuations per camera sample at its first vertex, 1–64
    /// (default 1: off)
    /// ([`Settings::branches`](super::Settings::branches)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branches: Option<Spanned<u32>>,
}

/// How the integral over λ is estimated.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum SpectralIntegration {
    /// Exactly, through tables, for the contributions whose spectrum is one
    /// emission spectrum times one conductor Fresnel factor (emission seen
    /// directly, and the first bounce off a microfacet or smooth
    /// conductor); by sampled wavelengths for the rest.
    #[default]
    Auto,
    /// As `auto`, and the glossy lobe of an isotropic wave-optical model at
    /// the first vertex by a control variate over λ
    /// ([`crate::glossy_lambda_table`]): less colour noise under a small
    /// light, but a single sample's estimate can be negative (the film keeps
    /// signed samples, so a low-spp image can hold negative pixels).
    Glossy,
    /// By sampled wavelengths everywhere.
    Sampled,
}

fn default_depth() -> Spanned<u32> {
    Spanned::new(0..0, 8)
}

fn is_default_depth(d: &Spanned<u32>) -> bool {
    *d == default_depth()
}

fn default_rr() -> u32 {
    3
}

fn is_default_rr(d: &u32) -> bool {
    *d == default_rr()
}

impl Default for IntegratorDesc {
    fn default() -> Self {
        IntegratorDesc {
            max_depth: default_depth(),
            wavelengths: WavelengthMode::Hero,
            hero_wavelengths: None,
            rr_depth: 3,
            sampler: SamplerKind::Sobol,
            mis: MisHeuristic::Power,
            mis_light_weight: None,
            spectral_integration: SpectralIntegration::Auto,
            delta_pixel_samples: None,
            glossy_residual: None,
            emitter_pixel_samples: None,
            caustic_guiding: None,
            branches: None,
        }
    }
}

/// `[materials.NAME]` is the flat material schema of `brdf::spec`, shared with
/// `brdf eval` queries and `lustre fit` material files: unknown keys are
/// refused there, and keys given in the scene override those of `include`.
pub use brdf::spec::{FresnelKind, MaterialDesc, ModelKind};

/// Optional placement of a shape.
#[derive(Deserialize, Serialize, Debug, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    /// Translation.
    #[serde(
        default,
        deserialize_with = "exact",
        skip_serializing_if = "is_default"
    )]
    pub translate: [f64; 3],
    /// Rotation in degrees about x, then y, then z.
    #[serde(
        default,
        deserialize_with = "exact",
        skip_serializing_if = "is_default"
    )]
    pub rotate_deg: [f64; 3],
    /// Uniform scale (default 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub scale: f64,
}

fn one() -> f64 {
    1.0
}

fn is_one(v: &f64) -> bool {
    *v == 1.0
}

impl Default for TransformDesc {
    fn default() -> Self {
        TransformDesc {
            translate: [0.0; 3],
            rotate_deg: [0.0; 3],
            scale: 1.0,
        }
    }
}

/// `[[shapes]]`, tagged by `type`.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeDesc {
    /// `size = [w, h]` in the local xy plane, normal +z.
    Rectangle {
        /// Width and height.
        #[serde(deserialize_with = "exact")]
        size: [f64; 2],
        /// Material name.
        material: String,
        /// Placement.
        #[serde(default, skip_serializing_if = "is_default")]
        transform: TransformDesc,
    },
    /// A disk in the local xy plane, normal +z.
    Disk {
        /// Radius.
        radius: f64,
        /// Material name.
        material: String,
        /// Placement.
        #[serde(default, skip_serializing_if = "is_default")]
        transform: TransformDesc,
    },
    /// A sphere.
    Sphere {
        /// Centre.
        #[serde(deserialize_with = "exact")]
        center: [f64; 3],
        /// Radius.
        radius: f64,
        /// Material name.
        material: String,
    },
    /// A triangle mesh from an OBJ file (relative to the scene file).
    Mesh {
        /// OBJ file.
        file: PathBuf,
        /// Material name.
        material: String,
        /// Placement.
        #[serde(default, skip_serializing_if = "is_default")]
        transform: TransformDesc,
    },
}

/// `[[lights]]`, tagged by `type`. `spectrum` defaults to `"d65"`; every
/// spectrum is normalised to unit luminance before `intensity`/`radiance`
/// scales it.
#[derive(Deserialize, Serialize, Debug, Clone, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightDesc {
    /// An isotropic point light; `intensity` in luminance units per sr.
    Point {
        /// Position.
        #[serde(deserialize_with = "exact")]
        position: [f64; 3],
        /// Radiant intensity scale.
        intensity: f64,
        /// Spectrum.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spectrum: Option<String>,
    },
    /// A spherical emitter of uniform radiance.
    Sphere {
        /// Centre.
        #[serde(deserialize_with = "exact")]
        center: [f64; 3],
        /// Radius.
        radius: f64,
        /// Radiance scale.
        radiance: f64,
        /// Spectrum.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spectrum: Option<String>,
    },
    /// A rectangular emitter, emitting from its +z side (both with `two_sided`).
    Rectangle {
        /// Width and height.
        #[serde(deserialize_with = "exact")]
        size: [f64; 2],
        /// Radiance scale.
        radiance: f64,
        /// Placement.
        #[serde(default, skip_serializing_if = "is_default")]
        transform: TransformDesc,
        /// Emit from both sides.
        #[serde(default, skip_serializing_if = "is_default")]
        two_sided: bool,
        /// Spectrum.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spectrum: Option<String>,
    },
    /// Light from infinitely far away: constant, or a lat-long EXR map.
    Environment {
        /// Radiance scale.
        radiance: f64,
        /// Spectrum of a constant environment.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        spectrum: Option<String>,
        /// Lat-long (equirectangular) EXR file, relative to the scene file; +y is up.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        file: Option<PathBuf>,
        /// Rotation of the map about +y in degrees.
        #[serde(default, skip_serializing_if = "is_default")]
        rotate_deg: f64,
    },
    /// A daylight sky with its sun and a ground below the horizon (Preetham
    /// 1999, evaluated spectrally; see `sky.rs`). It is the scene's environment.
    Sky {
        /// Sun elevation above the horizon in degrees, (0, 90].
        sun_elevation_deg: f64,
        /// Sun azimuth in degrees: 0 toward −z, 90 toward +x (default 0).
        #[serde(default, skip_serializing_if = "is_default")]
        sun_azimuth_deg: f64,
        /// Atmospheric turbidity, 2–10 (default 2.5).
        #[serde(
            default = "default_turbidity",
            skip_serializing_if = "is_default_turbidity"
        )]
        turbidity: f64,
        /// Scene radiance per physical cd/m² (e.g. 1e-4: a 10 kcd/m² sky gives 1).
        scale: f64,
        /// Whether the sun disk emits (default true).
        #[serde(default = "yes", skip_serializing_if = "is_yes")]
        sun: bool,
        /// Albedo of the Lambertian ground below the horizon (default 0.2).
        #[serde(
            default = "default_ground_albedo",
            skip_serializing_if = "is_default_ground_albedo"
        )]
        ground_albedo: f64,
    },
}

fn default_turbidity() -> f64 {
    2.5
}

fn is_default_turbidity(t: &f64) -> bool {
    *t == default_turbidity()
}

fn default_ground_albedo() -> f64 {
    0.2
}

fn is_default_ground_albedo(a: &f64) -> bool {
    *a == default_ground_albedo()
}

fn yes() -> bool {
    true
}

fn is_yes(b: &bool) -> bool {
    *b
}
