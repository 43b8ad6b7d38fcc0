//! Scenes: parsing the TOML file and building what the renderer needs.

pub mod desc;
pub mod inputs;

use crate::camera::Camera;
use crate::error::SceneError;
use crate::geometry::{HitGeometry, Planar, Ray, Sphere, Transform};
use crate::light::{EnvMap, Environment, LightKind, Lights};
use crate::material::{Material, build_material};
use crate::mesh::{MeshAccel, obj_from_bytes};
use crate::sky::{Sky, SkyParams};
use crate::spectrum::{LAMBDA_MAX, LAMBDA_MIN, parse_spectrum_with};
use crate::wavelength::WavelengthSampler;
use desc::{
    LightDesc, MisHeuristic, SamplerKind, SceneDesc, ShapeDesc, TransformDesc, WavelengthMode,
};
use glam::DVec3;
pub use inputs::{FNV_OFFSET, InputFile, Inputs, fnv1a};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The estimator version, hashed into every fingerprint: films rendered by
/// an earlier estimator (other wavelength or random-number sampling, other
/// inputs hashed) must not merge with new ones.
pub const ESTIMATOR: &str = "lustre estimator 4: sobol sampler with 64-bit sample indices, \
                             stratified hero, power MIS, every input file hashed";

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
    /// Random-number source of camera samples.
    pub sampler: SamplerKind,
    /// Weighting of light and BSDF sampling.
    pub mis: MisHeuristic,
    /// EXR output path.
    pub exr: Option<PathBuf>,
    /// PNG output path.
    pub png: Option<PathBuf>,
    /// Exposure in stops.
    pub exposure: f64,
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
    /// Analytic planar shapes.
    pub planars: Vec<(Planar, Surface)>,
    /// Analytic spheres.
    pub spheres: Vec<(Sphere, Surface)>,
    /// Meshes (only when the scene has any).
    pub mesh: Option<MeshAccel>,
    /// Lights.
    pub lights: Lights,
    /// Wavelength distribution over the emission range.
    pub wavelengths: WavelengthSampler,
    /// Hash of everything that determines the per-sample values (not spp or outputs).
    pub fingerprint: u64,
    /// The files the scene was built from, with their hashes (the scene file
    /// itself first, hashed without the keys that do not change samples).
    pub inputs: Vec<InputFile>,
    /// One line describing what was prepared and how long it took.
    pub prepared: String,
    /// Whether an emitter's spectrum may be negative at some wavelengths
    /// (an RGB-lifted environment map, see [`crate::light::RgbLift`]): then a
    /// negative estimate at one wavelength is part of an unbiased colour
    /// average, and only non-finite samples are dropped.
    pub signed_radiance: bool,
}

/// Parses a scene file's text into its description, with positioned errors.
pub fn parse(path: &Path, text: &str) -> Result<SceneDesc, SceneError> {
    toml::from_str::<SceneDesc>(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(span) => SceneError::at(path, text, span.start, msg),
            None => SceneError::new(path, msg),
        }
    })
}

/// Loads and builds a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = read_scene_text(path)?;
    load_str(path, &text)
}

/// Reads a scene file: at most [`inputs::MAX_SCENE_BYTES`], UTF-8.
fn read_scene_text(path: &Path) -> Result<String, SceneError> {
    use std::io::Read;
    let fail = |e: std::io::Error| SceneError::new(path, format!("cannot read scene file: {e}"));
    let file = std::fs::File::open(path).map_err(fail)?;
    let mut bytes = Vec::new();
    file.take(inputs::MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(fail)?;
    if bytes.len() as u64 > inputs::MAX_SCENE_BYTES {
        return Err(SceneError::new(
            path,
            format!(
                "the scene file is larger than {} MiB; scenes describe geometry by reference \
                 (put meshes in OBJ files)",
                inputs::MAX_SCENE_BYTES >> 20
            ),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        let off = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
        SceneError::at(path, &text, off, "the scene file is not UTF-8 text")
    })
}

fn transform(t: &TransformDesc) -> Result<Transform, String> {
    let all = t
        .translate
        .iter()
        .chain(&t.rotate_deg)
        .chain(std::iter::once(&t.scale));
    if !all.into_iter().all(|v| v.is_finite()) {
        return Err("transform values must be finite".into());
    }
    if t.scale <= 0.0 {
        return Err(format!(
            "transform.scale = {} is invalid: expected > 0",
            t.scale
        ));
    }
    Ok(Transform::new(t.rotate_deg, t.scale, t.translate))
}

fn positive(name: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "{name} = {v} is invalid: expected a finite value > 0"
        ))
    }
}

fn non_negative(name: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "{name} = {v} is invalid: expected a finite value ≥ 0"
        ))
    }
}

fn finite3(name: &str, v: [f64; 3]) -> Result<DVec3, String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from(v))
    } else {
        Err(format!("{name} must be finite"))
    }
}

/// The scene text without the keys that do not change sample values
/// (`[film]` spp, exr, png, exposure), as hashed into the fingerprint.
fn normalised_text(text: &str) -> String {
    let mut table: toml::Table = toml::from_str(text).unwrap_or_default();
    if let Some(toml::Value::Table(film)) = table.get_mut("film") {
        for k in ["spp", "exr", "png", "exposure"] {
            film.remove(k);
        }
    }
    table.to_string()
}

/// Builds a scene from its text (`path` locates relative files and errors).
pub fn load_str(path: &Path, text: &str) -> Result<Scene, SceneError> {
    let start = Instant::now();
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
    let base = path
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let mut inputs = Inputs::new(&base);
    inputs.record(inputs.name_of(path), normalised_text(text).as_bytes());
    let at =
        |span: std::ops::Range<usize>, msg: String| SceneError::at(path, text, span.start, msg);

    // Camera and settings.
    let cam = &desc.camera;
    let [w, h] = *cam.resolution.get_ref();
    if w == 0
        || h == 0
        || w > crate::film::MAX_SIDE
        || h > crate::film::MAX_SIDE
        || w as u64 * h as u64 > crate::film::MAX_PIXELS
    {
        return Err(at(
            cam.resolution.span(),
            format!(
                "resolution = [{w}, {h}] is invalid: expected 1..={} each and at most {} \
                 pixels in all",
                crate::film::MAX_SIDE,
                crate::film::MAX_PIXELS
            ),
        ));
    }
    for v in [&cam.look_from, &cam.look_at, &cam.up] {
        if !v.get_ref().iter().all(|x| x.is_finite()) {
            return Err(at(v.span(), "[camera]: coordinates must be finite".into()));
        }
    }
    let camera = Camera::new(
        DVec3::from(*cam.look_from.get_ref()),
        DVec3::from(*cam.look_at.get_ref()),
        DVec3::from(*cam.up.get_ref()),
        *cam.fov_deg.get_ref(),
        w,
        h,
    )
    .map_err(|m| {
        // Point at the key the message is about (`up` may be defaulted: then the table).
        let span = if m.contains("`look_at`") {
            cam.look_at.span()
        } else if m.contains("`up`") && !cam.up.span().is_empty() {
            cam.up.span()
        } else if m.contains("`up`") {
            cam.look_at.span()
        } else {
            cam.fov_deg.span()
        };
        at(span, format!("[camera]: {m}"))
    })?;
    let film = &desc.film;
    if *film.spp.get_ref() == 0 {
        return Err(at(
            film.spp.span(),
            "spp = 0 is invalid: expected ≥ 1".into(),
        ));
    }
    if !film.exposure.is_finite() {
        return Err(SceneError::new(path, "[film]: exposure must be finite"));
    }
    let max_depth = *desc.integrator.max_depth.get_ref();
    if max_depth == 0 || max_depth > 1000 {
        return Err(at(
            desc.integrator.max_depth.span(),
            format!("max_depth = {max_depth} is invalid: expected 1..=1000"),
        ));
    }
    let settings = Settings {
        spp: *film.spp.get_ref(),
        seed: film.seed,
        max_depth,
        rr_depth: desc.integrator.rr_depth,
        mode: desc.integrator.wavelengths,
        sampler: desc.integrator.sampler,
        mis: desc.integrator.mis,
        exr: film.exr.clone(),
        png: film.png.clone(),
        exposure: film.exposure,
    };

    // Checked before any material is built: building can take milliseconds.
    if desc.lights.is_empty() {
        return Err(SceneError::new(
            path,
            "the scene has no lights: add a [[lights]] entry (point, sphere, rectangle, environment or sky)",
        ));
    }

    // Materials: only those some shape uses are built.
    let mut materials: Vec<Material> = Vec::new();
    let mut material_index: HashMap<String, u32> = HashMap::new();
    let mut use_material = |name: &str,
                            span: std::ops::Range<usize>,
                            inputs: &mut Inputs|
     -> Result<u32, SceneError> {
        if let Some(&i) = material_index.get(name) {
            return Ok(i);
        }
        let Some(m) = desc.materials.get(name) else {
            let names: Vec<&str> = desc.materials.keys().map(String::as_str).collect();
            return Err(at(
                span,
                format!(
                    "unknown material `{name}`; defined: {}",
                    if names.is_empty() {
                        "none (add a [materials.NAME] table)".into()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        };
        let built = build_material(name, m.get_ref(), &base, inputs)
            .map_err(|e| at(m.span(), format!("[materials.{name}]: {e}")))?;
        let i = materials.len() as u32;
        materials.push(built);
        material_index.insert(name.to_string(), i);
        Ok(i)
    };

    let mut planars = Vec::new();
    let mut spheres = Vec::new();
    let mut meshes = Vec::new();
    for (i, s) in desc.shapes.iter().enumerate() {
        let span = s.span();
        let ctx = |m: String| at(span.clone(), format!("shapes[{i}]: {m}"));
        match s.get_ref() {
            ShapeDesc::Rectangle {
                size,
                material,
                transform: t,
            } => {
                positive("size[0]", size[0])
                    .and(positive("size[1]", size[1]))
                    .map_err(ctx)?;
                let xf = transform(t).map_err(ctx)?;
                let m = use_material(material, span.clone(), &mut inputs)?;
                planars.push((Planar::rectangle(*size, &xf), Surface::Material(m)));
            }
            ShapeDesc::Disk {
                radius,
                material,
                transform: t,
            } => {
                positive("radius", *radius).map_err(ctx)?;
                let xf = transform(t).map_err(ctx)?;
                let m = use_material(material, span.clone(), &mut inputs)?;
                planars.push((Planar::disk(*radius, &xf), Surface::Material(m)));
            }
            ShapeDesc::Sphere {
                center,
                radius,
                material,
            } => {
                positive("radius", *radius).map_err(ctx)?;
                let c = finite3("center", *center).map_err(ctx)?;
                let m = use_material(material, span.clone(), &mut inputs)?;
                spheres.push((
                    Sphere {
                        center: c,
                        radius: *radius,
                    },
                    Surface::Material(m),
                ));
            }
            ShapeDesc::Mesh {
                file,
                material,
                transform: t,
            } => {
                let xf = transform(t).map_err(ctx)?;
                let m = use_material(material, span.clone(), &mut inputs)?;
                let full = base.join(file);
                let bytes = inputs
                    .read(&full, "mesh file", inputs::MAX_BINARY_BYTES)
                    .map_err(ctx)?;
                meshes.push(obj_from_bytes(&full, &bytes, &xf, m).map_err(ctx)?);
            }
        }
    }

    // Lights.
    let mut lights = Vec::new();
    let mut environment = None;
    for (i, l) in desc.lights.iter().enumerate() {
        let span = l.span();
        let ctx = |m: String| at(span.clone(), format!("lights[{i}]: {m}"));
        let spectrum = |s: &Option<String>, scale: f64, inputs: &mut Inputs| {
            parse_spectrum_with(s.as_deref().unwrap_or("d65"), &base, &mut |p: &Path| {
                inputs.read_text(p, "spectrum CSV", inputs::MAX_CSV_BYTES)
            })
            .and_then(|sp| sp.with_luminance(scale))
            .map_err(ctx)
        };
        let idx = lights.len() as u32;
        match l.get_ref() {
            LightDesc::Point {
                position,
                intensity,
                spectrum: s,
            } => {
                positive("intensity", *intensity).map_err(ctx)?;
                let position = finite3("position", *position).map_err(ctx)?;
                lights.push(LightKind::Point {
                    position,
                    spectrum: spectrum(s, *intensity, &mut inputs)?,
                });
            }
            LightDesc::Sphere {
                center,
                radius,
                radiance,
                spectrum: s,
            } => {
                positive("radius", *radius)
                    .and(positive("radiance", *radiance))
                    .map_err(ctx)?;
                let sphere = Sphere {
                    center: finite3("center", *center).map_err(ctx)?,
                    radius: *radius,
                };
                spheres.push((sphere, Surface::Emitter(idx)));
                lights.push(LightKind::Sphere {
                    sphere,
                    spectrum: spectrum(s, *radiance, &mut inputs)?,
                });
            }
            LightDesc::Rectangle {
                size,
                radiance,
                transform: t,
                two_sided,
                spectrum: s,
            } => {
                positive("size[0]", size[0])
                    .and(positive("size[1]", size[1]))
                    .map_err(ctx)?;
                positive("radiance", *radiance).map_err(ctx)?;
                let shape = Planar::rectangle(*size, &transform(t).map_err(ctx)?);
                planars.push((shape, Surface::Emitter(idx)));
                lights.push(LightKind::Rectangle {
                    shape,
                    spectrum: spectrum(s, *radiance, &mut inputs)?,
                    two_sided: *two_sided,
                });
            }
            LightDesc::Environment {
                radiance,
                spectrum: s,
                file,
                rotate_deg,
            } => {
                if environment.is_some() {
                    return Err(ctx("only one environment light is allowed".into()));
                }
                non_negative("radiance", *radiance).map_err(ctx)?;
                let env = match file {
                    Some(f) => {
                        if s.is_some() {
                            return Err(ctx("an EXR environment takes its colour from the map; remove `spectrum`".into()));
                        }
                        if !rotate_deg.is_finite() {
                            return Err(ctx("rotate_deg must be finite".into()));
                        }
                        let full = base.join(f);
                        let bytes = inputs
                            .read(&full, "environment map", inputs::MAX_BINARY_BYTES)
                            .map_err(ctx)?;
                        Environment::Map(
                            EnvMap::from_exr_bytes(&full, &bytes, *radiance, *rotate_deg)
                                .map_err(ctx)?,
                        )
                    }
                    None => {
                        Environment::Constant(spectrum(s, (*radiance).max(1e-300), &mut inputs)?)
                    }
                };
                environment = Some(lights.len());
                lights.push(LightKind::Environment(env));
            }
            LightDesc::Sky {
                sun_elevation_deg,
                sun_azimuth_deg,
                turbidity,
                scale,
                sun,
                ground_albedo,
            } => {
                if environment.is_some() {
                    return Err(ctx(
                        "only one environment light is allowed (a sky is one)".into()
                    ));
                }
                let sky = Sky::new(SkyParams {
                    turbidity: *turbidity,
                    sun_elevation_deg: *sun_elevation_deg,
                    sun_azimuth_deg: *sun_azimuth_deg,
                    scale: *scale,
                    sun: *sun,
                    ground_albedo: *ground_albedo,
                })
                .map_err(ctx)?;
                environment = Some(lights.len());
                lights.push(LightKind::Environment(Environment::Sky(Box::new(sky))));
            }
        }
    }
    let signed_radiance = environment
        .is_some_and(|i| matches!(lights[i], LightKind::Environment(Environment::Map(_))));
    let lights = Lights {
        lights,
        environment,
    };
    let Some((lo, hi)) = lights.emission_range() else {
        return Err(SceneError::new(
            path,
            "no light emits between 360 and 830 nm",
        ));
    };
    let wavelengths = WavelengthSampler::new(lo, hi);

    let n_tris: usize = meshes.iter().map(|m| m.triangles.len()).sum();
    let mesh = (!meshes.is_empty()).then(|| MeshAccel::build(meshes));

    let inputs = inputs.into_files();
    let fingerprint = inputs::fingerprint(ESTIMATOR, &inputs);

    let models: Vec<String> = materials
        .iter()
        .map(|m| format!("{} ({})", m.name, m.model.name()))
        .collect();
    let prepared = format!(
        "prepared {}: {}×{} px, {} material(s) [{}], {} analytic shape(s), {}, {} light(s){}, λ {lo:.0}–{hi:.0} nm{} in {:.1} ms",
        path.display(),
        w,
        h,
        materials.len(),
        models.join(", "),
        planars.len() + spheres.len(),
        if n_tris > 0 {
            format!("BVH over {n_tris} triangle(s)")
        } else {
            "no BVH".into()
        },
        lights.len(),
        if lights.environment.is_some() {
            " incl. environment"
        } else {
            ", no environment sampling"
        },
        if lo > LAMBDA_MIN || hi < LAMBDA_MAX {
            " (narrowed to the lights' emission)"
        } else {
            ""
        },
        start.elapsed().as_secs_f64() * 1e3
    );

    Ok(Scene {
        path: path.to_path_buf(),
        camera,
        settings,
        materials,
        planars,
        spheres,
        mesh,
        lights,
        wavelengths,
        fingerprint,
        inputs,
        prepared,
        signed_radiance,
    })
}

impl Scene {
    /// Nearest hit along `ray` in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = t_max;
        for (p, s) in &self.planars {
            if let Some(g) = p.intersect(ray, 0.0, t_max) {
                t_max = g.t;
                best = Some(Hit {
                    geo: g,
                    surface: *s,
                    mesh: false,
                    shading_n: None,
                });
            }
        }
        for (sp, s) in &self.spheres {
            if let Some(g) = sp.intersect(ray, 0.0, t_max) {
                t_max = g.t;
                best = Some(Hit {
                    geo: g,
                    surface: *s,
                    mesh: false,
                    shading_n: None,
                });
            }
        }
        if let Some(m) = &self.mesh
            && let Some((g, mat, shading_n)) = m.intersect(ray, 0.0, t_max)
        {
            best = Some(Hit {
                geo: g,
                surface: Surface::Material(mat),
                mesh: true,
                shading_n,
            });
        }
        best
    }

    /// Whether anything lies on `ray` within `(0, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f64) -> bool {
        self.planars
            .iter()
            .any(|(p, _)| p.intersect(ray, 0.0, t_max).is_some())
            || self
                .spheres
                .iter()
                .any(|(s, _)| s.intersect(ray, 0.0, t_max).is_some())
            || self
                .mesh
                .as_ref()
                .is_some_and(|m| m.occluded(ray, 0.0, t_max))
    }
}
