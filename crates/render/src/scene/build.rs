//! Building a runtime [`Scene`] from its description, in named stages —
//! camera, settings, materials (on first use), shapes, lights, wavelengths,
//! and the fingerprint of every file read — each returning an error that
//! points at the scene text it is about.

use super::desc::{
    LightDesc, MaterialDesc, ModelKind, SamplerKind, SceneDesc, ShapeDesc, SpectralIntegration,
    TransformDesc, WavelengthMode,
};
use super::tables;
use super::{ESTIMATOR, Scene, Settings};
use crate::analytic_bvh::AnalyticBvh;
use crate::camera::Camera;
use crate::error::SceneError;
use crate::geometry::{Planar, Sphere, Transform};
use crate::guide::{self, Casters};
use crate::inputs::{self, Inputs};
use crate::light::{EnvMap, Environment, LightKind, Lights};
use crate::material::{Material, build_material};
use crate::mesh::{MeshAccel, MeshSource, obj_from_bytes};
use crate::shapes::{Checker, Shapes, Surface};
use crate::sky::{Sky, SkyParams};
use crate::spectral_table::{DeltaLobe, SpectralTables};
use crate::spectrum::{LAMBDA_MAX, LAMBDA_MIN, Spectrum, parse_spectrum_with};
use crate::wavelength::{HERO_COUNT, HERO_COUNT_CONDUCTORS, MAX_WAVELENGTHS, WavelengthSampler};
use glam::DVec3;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Builds a scene from its parsed description (`text` is the file's text,
/// for error positions and the fingerprint).
pub(super) fn build(path: &Path, text: &str, desc: &SceneDesc) -> Result<Scene, SceneError> {
    let start = Instant::now();
    let mut b = Builder::new(path, text, desc);
    let camera = b.camera()?;
    let settings = b.settings()?;
    // Checked before any material is built: building can take milliseconds.
    if desc.lights.is_empty() {
        return Err(SceneError::new(
            path,
            "the scene has no lights: add a [[lights]] entry (point, sphere, rectangle, environment or sky)",
        ));
    }
    let mut shapes = b.shapes()?;
    let (lights, signed_radiance) = b.lights(&mut shapes)?;
    let Some((lo, hi)) = lights.emission_range() else {
        return Err(SceneError::new(
            path,
            "no light emits between 360 and 830 nm",
        ));
    };
    let wavelengths = WavelengthSampler::new(lo, hi);
    // Applied once the scene stands (`Scene::set_spectral_bands`).
    let mut settings = settings;
    let bands = std::mem::take(&mut settings.spectral_bands);
    let n_tris: usize = shapes.meshes.iter().map(|m| m.triangles.len()).sum();
    let casters = casters(&shapes, &b.materials, settings.caustic_guiding);
    let shapes = Shapes {
        analytic_bvh: AnalyticBvh::build(&shapes.planars, &shapes.spheres),
        planars: shapes.planars,
        spheres: shapes.spheres,
        mesh: (!shapes.meshes.is_empty()).then(|| MeshAccel::build(shapes.meshes)),
        checkers: if b.checkers.iter().any(Option::is_some) {
            std::mem::take(&mut b.checkers)
        } else {
            Vec::new()
        },
    };
    let (materials, inputs) = (b.materials, b.inputs.into_files());
    let conductors = materials.iter().all(|m| {
        matches!(
            m.model,
            ModelKind::Ggx | ModelKind::Beckmann | ModelKind::Smooth
        )
    });
    // Visible-normal (or delta) sampling of a conductor, cosine sampling of
    // a Lambertian base and the coat-or-base choice of roughplastic each
    // cover the whole lobe, so a constant environment can be left to them
    // (see `Lights`). For a Lambertian surface BSDF sampling is the exact
    // importance function of an unoccluded constant environment (weight ρ),
    // and next-event estimation then draws only the other lights, each
    // twice as often when one environment was among two lights.
    let covering = materials.iter().all(|m| {
        matches!(
            m.model,
            ModelKind::Ggx
                | ModelKind::Beckmann
                | ModelKind::Smooth
                | ModelKind::Diffuse
                | ModelKind::RoughPlastic
        )
    });
    let mut lights = lights;
    lights.bsdf_only_environment = covering
        && lights.environment.is_some_and(|i| {
            matches!(
                lights.lights[i],
                LightKind::Environment(Environment::Constant(_))
            )
        });
    if settings.hero_wavelengths == 0 {
        settings.hero_wavelengths = if conductors {
            HERO_COUNT_CONDUCTORS
        } else {
            HERO_COUNT
        };
    }
    let fingerprint = inputs::fingerprint(ESTIMATOR, &inputs);
    // No tables when no material could use them: a λ-free material's
    // paths use the emission integrals (`integrator.rs`, `trace_flat`).
    let tables_start = Instant::now();
    /// A delta lobe is integrated only where its emission would otherwise
    /// be traced by `delta_emission` (a model that chooses among lobes).
    fn delta_lobe(m: &Material) -> Option<DeltaLobe<'_>> {
        m.delta_fresnel
            .as_ref()
            .filter(|_| m.bxdf.uses_lobe_choice())
            .map(|fresnel| DeltaLobe {
                fresnel,
                bxdf: &*m.bxdf,
            })
    }
    let glossy_cv = settings.spectral_integration == SpectralIntegration::Glossy;
    let spectral = (settings.spectral_integration != SpectralIntegration::Sampled
        && materials.iter().any(|m| {
            m.fresnel_only.is_some()
                || m.lambda_free
                || delta_lobe(m).is_some()
                || glossy_cv && crate::material::glossy_isotropic(m.model)
        }))
    .then(|| {
        let fresnels: Vec<_> = materials
            .iter()
            .map(|m| m.fresnel_only.as_ref().map(|f| &f.fresnel))
            .collect();
        let deltas: Vec<_> = materials.iter().map(delta_lobe).collect();
        let mut t = SpectralTables::build_with_deltas(&lights, &fresnels, &deltas);
        if glossy_cv && lights.nee_len() > 0 {
            let lobes: Vec<bool> = materials
                .iter()
                .map(|m| crate::material::glossy_isotropic(m.model))
                .collect();
            t.add_glossy(&lights, &lobes);
        }
        t
    });
    let spectral_summary = match &spectral {
        None => String::new(),
        Some(t) => format!(
            ", λ integrated exactly on λ-flat paths and at the first bounce ({} Fresnel grid(s) and {} delta-lobe grid(s) of ≤ {} intervals, {} λ-free, {} refused, {} glossy control-variate table(s) built as used; {:.1} ms)",
            t.stats.grids,
            t.stats.delta_grids,
            t.stats.max_intervals,
            t.stats.flat,
            t.stats.refused + t.stats.delta_refused,
            t.stats.glossy_grids,
            tables_start.elapsed().as_secs_f64() * 1e3
        ),
    };

    // Averaging the emission seen directly needs its exact λ integral.
    let emitter_edges = spectral.as_ref().and_then(|_| {
        crate::emitter_edges::EmitterEdges::build(&camera, &lights, settings.emitter_pixel_samples)
    });
    let models: Vec<String> = materials
        .iter()
        .map(|m| format!("{} ({})", m.name, m.model.name()))
        .collect();
    let prepared = format!(
        "prepared {}: {}×{} px, {} material(s) [{}], {} analytic shape(s), {}, {} light(s){}, λ {lo:.0}–{hi:.0} nm{}, {} per path{}{}{}, in {:.1} ms",
        path.display(),
        camera.width,
        camera.height,
        materials.len(),
        models.join(", "),
        shapes.analytic_count(),
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
        settings.wavelengths_per_path(),
        spectral_summary,
        if casters.is_empty() {
            String::new()
        } else {
            format!(
                ", {:.0} % of diffuse samples aimed at {} glossy object(s)",
                100.0 * settings.caustic_guiding,
                casters.len()
            )
        },
        match &emitter_edges {
            None => String::new(),
            Some(e) => format!(
                ", the emission seen directly averaged over {} points per sample on {} light-outline pixel(s)",
                settings.emitter_pixel_samples,
                e.count()
            ),
        },
        start.elapsed().as_secs_f64() * 1e3
    );

    // A control variate's estimate (the exact integral of the table's
    // interpolant plus the sampled residual) is negative now and then where
    // the interpolant exceeds the lobe; dropping those samples would bias
    // the image upward (by 10–16 % on a narrow lobe under a 1 nm band),
    // kept they average to the lobe's own XYZ.
    let signed_radiance =
        signed_radiance || spectral.as_ref().is_some_and(|t| t.stats.glossy_grids > 0);
    let mut scene = Scene {
        path: path.to_path_buf(),
        camera,
        settings,
        materials,
        shapes,
        lights,
        wavelengths,
        spectral,
        casters,
        emitter_edges,
        fingerprint,
        inputs,
        prepared,
        signed_radiance,
    };
    if bands > 0 {
        scene
            .set_spectral_bands(bands)
            .map_err(|m| SceneError::new(path, format!("[film]: {m}")))?;
    }
    Ok(scene)
}

/// The glossy objects of `shapes` that diffuse and rough-plastic
/// surfaces aim `share` of their samples at ([`crate::guide`]): one
/// bounding sphere per analytic shape and per mesh file of a glossy
/// material.
fn casters(shapes: &ShapeLists, materials: &[Material], share: f64) -> Casters {
    // Off (the default): no pass over the meshes' triangles.
    if share <= 0.0 {
        return Casters::default();
    }
    let roles: Vec<Option<bool>> = materials
        .iter()
        .map(|m| guide::role(m.model, m.bxdf.lobe_peak_pdf(DVec3::Z)))
        .collect();
    let glossy =
        |s: &Surface| matches!(s, Surface::Material(m) if roles[*m as usize] == Some(false));
    let mut spheres: Vec<(DVec3, f64)> = Vec::new();
    for (p, s) in &shapes.planars {
        if glossy(s) {
            spheres.push((
                p.center,
                p.half.0.hypot(if p.disk { 0.0 } else { p.half.1 }),
            ));
        }
    }
    for (sp, s) in &shapes.spheres {
        if glossy(s) {
            spheres.push((sp.center, sp.radius));
        }
    }
    for m in &shapes.meshes {
        if glossy(&Surface::Material(m.surface)) {
            spheres.extend(guide::bounding_sphere(
                m.triangles.iter().flatten().copied(),
            ));
        }
    }
    let receivers = roles.iter().map(|r| *r == Some(true)).collect();
    Casters::new(spheres, receivers, share)
}

/// Shapes as the shape and light stages collect them (meshes not yet in a BVH).
struct ShapeLists {
    planars: Vec<(Planar, Surface)>,
    spheres: Vec<(Sphere, Surface)>,
    meshes: Vec<MeshSource>,
}

/// The state the stages share: where relative files live, every file read
/// so far (for the fingerprint), and the materials built so far.
struct Builder<'a> {
    path: &'a Path,
    text: &'a str,
    desc: &'a SceneDesc,
    base: PathBuf,
    inputs: Inputs,
    materials: Vec<Material>,
    /// Per material index, its checkerboard (the ρ1 squares' material holds it).
    checkers: Vec<Option<Checker>>,
    material_index: HashMap<String, u32>,
}

/// Most `[integrator] delta_pixel_samples`.
const DELTA_PIXEL_SAMPLES_MAX: u32 = 64;

/// Range of `[integrator] mis_light_weight`: the factor multiplies light
/// densities inside the MIS weights, and past these bounds the product leaves
/// the range where both strategies' weights stay representable for the
/// densities lights produce (at 1e306 a light's contribution vanished).
/// Weights beyond 1e3 or below 1e-3 are one strategy alone in all but name.
pub const MIS_LIGHT_WEIGHT_MIN: f64 = 1e-3;
/// See [`MIS_LIGHT_WEIGHT_MIN`].
pub const MIS_LIGHT_WEIGHT_MAX: f64 = 1e3;

impl<'a> Builder<'a> {
    fn new(path: &'a Path, text: &'a str, desc: &'a SceneDesc) -> Builder<'a> {
        let base = path
            .parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
        let mut inputs = Inputs::new(&base);
        inputs.record(inputs.name_of(path), normalised_text(text).as_bytes());
        Builder {
            path,
            text,
            desc,
            base,
            inputs,
            materials: Vec::new(),
            checkers: Vec::new(),
            material_index: HashMap::new(),
        }
    }

    /// An error at a byte span of the scene text.
    fn at(&self, span: Range<usize>, msg: String) -> SceneError {
        SceneError::at(self.path, self.text, span.start, msg)
    }

    /// An `[integrator]` count of positions per camera sample (`key`):
    /// `default` when unset, else 1..=`max`, or an error at the value
    /// ending with `why`.
    fn pixel_samples(
        &self,
        key: &str,
        value: &Option<toml::Spanned<u32>>,
        max: u32,
        default: usize,
        why: &str,
    ) -> Result<usize, SceneError> {
        match value {
            Some(k) if !(1..=max).contains(k.get_ref()) => Err(self.at(
                k.span(),
                format!(
                    "{key} = {} is invalid: expected 1..={max}{why}",
                    k.get_ref()
                ),
            )),
            Some(k) => Ok(*k.get_ref() as usize),
            None => Ok(default),
        }
    }

    /// An `[integrator]` real number (`key`): `default` when unset, else in
    /// `range` (NaN is not), or an error at the value ending with `why`.
    fn real_in(
        &self,
        key: &str,
        value: &Option<toml::Spanned<f64>>,
        range: std::ops::RangeInclusive<f64>,
        default: f64,
        why: &str,
    ) -> Result<f64, SceneError> {
        match value {
            Some(v) if !range.contains(v.get_ref()) => Err(self.at(
                v.span(),
                format!(
                    "{key} = {} is invalid: expected {} to {}{why}",
                    v.get_ref(),
                    range.start(),
                    range.end()
                ),
            )),
            Some(v) => Ok(*v.get_ref()),
            None => Ok(default),
        }
    }

    /// Stage 1: the camera, with its resolution checked against the film's limits.
    fn camera(&self) -> Result<Camera, SceneError> {
        let cam = &self.desc.camera;
        let [w, h] = *cam.resolution.get_ref();
        if w == 0
            || h == 0
            || w > crate::film::MAX_SIDE
            || h > crate::film::MAX_SIDE
            || w as u64 * h as u64 > crate::film::MAX_PIXELS
        {
            return Err(self.at(
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
                return Err(self.at(v.span(), "[camera]: coordinates must be finite".into()));
            }
        }
        Camera::new(
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
            self.at(span, format!("[camera]: {m}"))
        })
    }

    /// Stage 2: `[film]` and `[integrator]`.
    fn settings(&self) -> Result<Settings, SceneError> {
        let film = &self.desc.film;
        let spp = *film.spp.get_ref();
        if spp == 0 || spp > super::MAX_SPP {
            return Err(self.at(
                film.spp.span(),
                format!("spp = {spp} is invalid: expected 1..={}", super::MAX_SPP),
            ));
        }
        let exposure = *film.exposure.get_ref();
        if !exposure.is_finite() || exposure.abs() > super::MAX_EXPOSURE_STOPS {
            return Err(self.at(
                film.exposure.span(),
                format!(
                    "[film]: exposure = {exposure} is invalid: expected a number of stops in \
                     −{m}..={m} (2^{m} already scales a radiance of 1 to ~1e18; larger gains \
                     overflow the f32 outputs to inf)",
                    m = super::MAX_EXPOSURE_STOPS
                ),
            ));
        }
        let integrator = &self.desc.integrator;
        let max_depth = *integrator.max_depth.get_ref();
        if max_depth == 0 || max_depth > 1000 {
            return Err(self.at(
                integrator.max_depth.span(),
                format!("max_depth = {max_depth} is invalid: expected 1..=1000"),
            ));
        }
        let max = MAX_WAVELENGTHS as u32;
        let hero_wavelengths = match &integrator.hero_wavelengths {
            Some(n) if !(2..=max).contains(n.get_ref()) => {
                return Err(self.at(
                    n.span(),
                    format!(
                        "hero_wavelengths = {} is invalid: expected 2..={max}",
                        n.get_ref()
                    ),
                ));
            }
            Some(n) if integrator.wavelengths == WavelengthMode::Single => {
                return Err(self.at(
                    n.span(),
                    "hero_wavelengths needs wavelengths = \"hero\" (\"single\" carries one)".into(),
                ));
            }
            Some(n) => *n.get_ref() as usize,
            // Chosen once the materials are known (see `build`).
            None => 0,
        };
        let mis_light_weight = match &integrator.mis_light_weight {
            Some(w) if !(MIS_LIGHT_WEIGHT_MIN..=MIS_LIGHT_WEIGHT_MAX).contains(w.get_ref()) => {
                return Err(self.at(
                    w.span(),
                    format!(
                        "mis_light_weight = {} is invalid: expected {MIS_LIGHT_WEIGHT_MIN} to \
                         {MIS_LIGHT_WEIGHT_MAX} (1 is the textbook heuristic; leave it out for \
                         the per-vertex choice)",
                        w.get_ref()
                    ),
                ));
            }
            Some(w) => Some(*w.get_ref()),
            // The per-vertex choice rests on stratification; white noise
            // keeps the textbook weight (see `integrator::light_weight`).
            None if integrator.sampler == SamplerKind::Independent => Some(1.0),
            None => None,
        };
        let delta_pixel_samples = self.pixel_samples(
            "delta_pixel_samples",
            &integrator.delta_pixel_samples,
            DELTA_PIXEL_SAMPLES_MAX,
            1,
            "",
        )?;
        let glossy_residual = self.real_in(
            "glossy_residual",
            &integrator.glossy_residual,
            super::MIN_GLOSSY_RESIDUAL..=1.0,
            super::DEFAULT_GLOSSY_RESIDUAL,
            " (the probability that a light sample evaluates the glossy control variate's \
             residual)",
        )?;
        let emitter_pixel_samples = self.pixel_samples(
            "emitter_pixel_samples",
            &integrator.emitter_pixel_samples,
            crate::emitter_edges::MAX_SAMPLES,
            crate::emitter_edges::DEFAULT_SAMPLES,
            " (positions per camera sample on a light's outline; 1 turns it off)",
        )?;
        let caustic_guiding = self.real_in(
            "caustic_guiding",
            &integrator.caustic_guiding,
            0.0..=crate::guide::MAX_SHARE,
            super::DEFAULT_CAUSTIC_GUIDING,
            " (the share of a diffuse surface's samples aimed at glossy objects; 0 turns it off)",
        )?;
        let branches = match &integrator.branches {
            Some(_) => Some(self.pixel_samples(
                "branches",
                &integrator.branches,
                super::MAX_BRANCHES,
                1,
                " (BSDF continuations at a camera sample's first vertex; 1 turns it off)",
            )? as u32),
            None => None,
        };
        let spectral_bands = match &film.spectral_bands {
            Some(n) if *n.get_ref() as usize > crate::film::MAX_BANDS => {
                return Err(self.at(
                    n.span(),
                    format!(
                        "[film]: spectral_bands = {} is invalid: expected 1..={} (0 or unset: \
                         no bands)",
                        n.get_ref(),
                        crate::film::MAX_BANDS
                    ),
                ));
            }
            Some(n) => *n.get_ref() as usize,
            None => 0,
        };
        Ok(Settings {
            spp: *film.spp.get_ref(),
            spectral_bands,
            seed: film.seed,
            max_depth,
            rr_depth: integrator.rr_depth,
            mode: integrator.wavelengths,
            hero_wavelengths,
            sampler: integrator.sampler,
            mis: integrator.mis,
            mis_light_weight,
            spectral_integration: integrator.spectral_integration,
            delta_pixel_samples,
            glossy_residual,
            emitter_pixel_samples,
            caustic_guiding,
            branches,
            exr: film.exr.clone(),
            png: film.png.clone(),
            exposure,
        })
    }

    /// Stage 3, on demand: the index of material `name`, built the first
    /// time a shape uses it (materials nobody uses are never built).
    fn material(&mut self, name: &str, span: Range<usize>) -> Result<u32, SceneError> {
        if let Some(&i) = self.material_index.get(name) {
            return Ok(i);
        }
        let Some(m) = self.desc.materials.get(name) else {
            let names: Vec<&str> = self.desc.materials.keys().map(String::as_str).collect();
            return Err(self.at(
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
        let fail = |b: &Self, e: String| b.at(m.span(), format!("[materials.{name}]: {e}"));
        self.check_material(m.get_ref())
            .map_err(|e| fail(self, e))?;
        let checker = m
            .get_ref()
            .checker_split()
            .map_err(|e| fail(self, e.to_string()))?;
        let i = self.materials.len() as u32;
        match checker {
            None => {
                let built = build_material(name, m.get_ref(), &self.base, &mut self.inputs)
                    .map_err(|e| fail(self, e))?;
                self.materials.push(built);
                self.checkers.push(None);
            }
            Some(c) => {
                // Index i (what shapes are given) is the ρ1 squares; i + 1 the ρ0 squares.
                for d in [&c.squares[1], &c.squares[0]] {
                    let built = build_material(name, d, &self.base, &mut self.inputs)
                        .map_err(|e| fail(self, e))?;
                    self.materials.push(built);
                }
                self.checkers.push(Some(Checker {
                    tiles: c.tiles,
                    color0: i + 1,
                }));
                self.checkers.push(None);
            }
        }
        self.material_index.insert(name.to_string(), i);
        Ok(i)
    }

    /// The `nk_csv` / `psd_csv` contents of a material table that brdf would
    /// refuse or mis-read without the file's line numbers to explain it. An
    /// `include`d file may answer for `psd_csv`, so then the build alone
    /// judges the table.
    fn check_material(&mut self, m: &MaterialDesc) -> Result<(), String> {
        if m.include.is_some() {
            return Ok(());
        }
        let mut read = |key: &str, path: &str| -> Result<(String, String), String> {
            let full = self.base.join(path);
            // The same role and limit as the material build's own read: the
            // file is then read (and fingerprinted) once, in the same order.
            let text = self.inputs.read_text(&full, key, inputs::MAX_CSV_BYTES)?;
            Ok((full.display().to_string(), text))
        };
        if let Some(path) = &m.nk_csv {
            let (name, text) = read("nk_csv", path)?;
            tables::check_nk_csv(&name, &text).map_err(|e| format!("`nk_csv`: {e}"))?;
        }
        if let (Some(path), Some(ModelKind::MeasuredPsd)) = (&m.psd_csv, m.model) {
            let (name, text) = read("psd_csv", path)?;
            tables::check_psd_csv(&name, &text).map_err(|e| format!("`psd_csv`: {e}"))?;
        }
        Ok(())
    }

    /// Stage 4: `[[shapes]]`, with the materials they use.
    fn shapes(&mut self) -> Result<ShapeLists, SceneError> {
        let desc = self.desc;
        let mut out = ShapeLists {
            planars: Vec::new(),
            spheres: Vec::new(),
            meshes: Vec::new(),
        };
        for (i, s) in desc.shapes.iter().enumerate() {
            let span = s.span();
            let ctx = |m: String| self.at(span.clone(), format!("shapes[{i}]: {m}"));
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
                    let m = self.material(material, span.clone())?;
                    out.planars
                        .push((Planar::rectangle(*size, &xf), Surface::Material(m)));
                }
                ShapeDesc::Disk {
                    radius,
                    material,
                    transform: t,
                } => {
                    positive("radius", *radius).map_err(ctx)?;
                    let xf = transform(t).map_err(ctx)?;
                    let m = self.material(material, span.clone())?;
                    out.planars
                        .push((Planar::disk(*radius, &xf), Surface::Material(m)));
                }
                ShapeDesc::Sphere {
                    center,
                    radius,
                    material,
                } => {
                    positive("radius", *radius).map_err(ctx)?;
                    let c = finite3("center", *center).map_err(ctx)?;
                    let m = self.material(material, span.clone())?;
                    out.spheres.push((
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
                    let m = self.material(material, span.clone())?;
                    let full = self.base.join(file);
                    let bytes = self
                        .inputs
                        .read(&full, "mesh file", inputs::MAX_BINARY_BYTES)
                        .map_err(|m| self.at(span.clone(), format!("shapes[{i}]: {m}")))?;
                    out.meshes.push(
                        obj_from_bytes(&full, &bytes, &xf, m)
                            .map_err(|m| self.at(span.clone(), format!("shapes[{i}]: {m}")))?,
                    );
                }
            }
        }
        Ok(out)
    }

    /// A light's emission spectrum (D65 unless named), scaled to `scale`.
    fn spectrum(&mut self, name: &Option<String>, scale: f64) -> Result<Spectrum, String> {
        let inputs = &mut self.inputs;
        parse_spectrum_with(
            name.as_deref().unwrap_or("d65"),
            &self.base,
            &mut |p: &Path| inputs.read_text(p, "spectrum CSV", inputs::MAX_CSV_BYTES),
        )
        .and_then(|sp| sp.with_luminance(scale))
    }

    /// Stage 5: `[[lights]]`; emitting shapes join `shapes`. Also returns
    /// whether some emitter's spectrum may be negative (see
    /// [`Scene::signed_radiance`]).
    fn lights(&mut self, shapes: &mut ShapeLists) -> Result<(Lights, bool), SceneError> {
        let desc = self.desc;
        let mut lights = Vec::new();
        let mut environment = None;
        for (i, l) in desc.lights.iter().enumerate() {
            let span = l.span();
            let err = |b: &Self, m: String| b.at(span.clone(), format!("lights[{i}]: {m}"));
            let idx = lights.len() as u32;
            match l.get_ref() {
                LightDesc::Point {
                    position,
                    intensity,
                    spectrum: s,
                } => {
                    positive("intensity", *intensity).map_err(|m| err(self, m))?;
                    let position = finite3("position", *position).map_err(|m| err(self, m))?;
                    let spectrum = self.spectrum(s, *intensity).map_err(|m| err(self, m))?;
                    lights.push(LightKind::Point { position, spectrum });
                }
                LightDesc::Sphere {
                    center,
                    radius,
                    radiance,
                    spectrum: s,
                } => {
                    positive("radius", *radius)
                        .and(positive("radiance", *radiance))
                        .map_err(|m| err(self, m))?;
                    let sphere = Sphere {
                        center: finite3("center", *center).map_err(|m| err(self, m))?,
                        radius: *radius,
                    };
                    let spectrum = self.spectrum(s, *radiance).map_err(|m| err(self, m))?;
                    shapes.spheres.push((sphere, Surface::Emitter(idx)));
                    lights.push(LightKind::Sphere { sphere, spectrum });
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
                        .and(positive("radiance", *radiance))
                        .map_err(|m| err(self, m))?;
                    let shape = Planar::rectangle(*size, &transform(t).map_err(|m| err(self, m))?);
                    let spectrum = self.spectrum(s, *radiance).map_err(|m| err(self, m))?;
                    shapes.planars.push((shape, Surface::Emitter(idx)));
                    lights.push(LightKind::Rectangle {
                        shape,
                        spectrum,
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
                        return Err(err(self, "only one environment light is allowed".into()));
                    }
                    non_negative("radiance", *radiance).map_err(|m| err(self, m))?;
                    if !rotate_deg.is_finite() {
                        return Err(err(self, "rotate_deg must be finite".into()));
                    }
                    let env = match file {
                        Some(f) => {
                            if s.is_some() {
                                return Err(err(
                                    self,
                                    "an EXR environment takes its colour from the map; remove `spectrum`".into(),
                                ));
                            }
                            let full = self.base.join(f);
                            let bytes = self
                                .inputs
                                .read(&full, "environment map", inputs::MAX_BINARY_BYTES)
                                .map_err(|m| err(self, m))?;
                            Environment::Map(
                                EnvMap::from_exr_bytes(&full, &bytes, *radiance, *rotate_deg)
                                    .map_err(|m| err(self, m))?,
                            )
                        }
                        None => Environment::Constant(
                            self.spectrum(s, (*radiance).max(1e-300))
                                .map_err(|m| err(self, m))?,
                        ),
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
                        return Err(err(
                            self,
                            "only one environment light is allowed (a sky is one)".into(),
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
                    .map_err(|m| err(self, m))?;
                    environment = Some(lights.len());
                    lights.push(LightKind::Environment(Environment::Sky(Box::new(sky))));
                }
            }
        }
        // Both spectra are reconstructions that may dip below zero: the RGB
        // lift of a map's colours, and the CIE daylight basis S0 + M1 S1 +
        // M2 S2 at the reddish chromaticities of a sun a few degrees above
        // the horizon, whose M1 makes the blue end negative. Dropping those
        // samples would darken such skies (up to 40 % of samples at 0.5°);
        // kept, they average to the sky's own XYZ.
        let signed_radiance = environment.is_some_and(|i| {
            matches!(
                lights[i],
                LightKind::Environment(Environment::Map(_) | Environment::Sky(_))
            )
        });
        Ok((
            Lights {
                lights,
                environment,
                // Set once the materials are known (see `build`).
                bsdf_only_environment: false,
            },
            signed_radiance,
        ))
    }
}

/// The scene text without the keys that do not change sample values
/// (`[film]` spp, exr, png, exposure, spectral_bands), as hashed into the fingerprint.
fn normalised_text(text: &str) -> String {
    let mut table: toml::Table = toml::from_str(text).unwrap_or_default();
    if let Some(toml::Value::Table(film)) = table.get_mut("film") {
        // The band count is checked on its own (films refuse to merge or
        // resume across band counts, naming both), so that `--spectral N`
        // and `spectral_bands = N` give the same fingerprint.
        for k in ["spp", "exr", "png", "exposure", "spectral_bands"] {
            film.remove(k);
        }
    }
    table.to_string()
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
