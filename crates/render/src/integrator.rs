//! The spectral path tracer: next-event estimation and BSDF sampling
//! combined by multiple importance sampling (power heuristic by default),
//! exact delta lobes, Russian roulette, and hero wavelengths with spectral
//! MIS (Wilkie et al. 2014).
//!
//! Bookkeeping (one set for both modes; `n` = 1 or 4 wavelengths): the
//! wavelengths are stratified in the wavelength CDF's primary space, so each
//! has marginal density p(λ_j) whichever of them is the hero. With `P_k` the
//! directional pdf of the path so far had wavelength k been the hero and
//! `F_j` the path's measurement product at λ_j, the tracer keeps
//! `T_j = F_j / (p(λ_j) P_hero)` and `Q_k = P_k / P_hero`. A complete path
//! is then weighted with B = Σ_k Q_k (BSDF sampling, summed over which
//! wavelength was the hero) and A = Σ_k L_k p_light (light sampling, where
//! `L_k p_light` is that strategy's density for the last edge relative to the
//! BSDF one): the balance heuristic over heroes (p(λ_j) is common to all of
//! them and cancels) inside, and between the two strategies the power
//! heuristic by default, `T_j Le_j B / (A² + B²)` for a BSDF-sampled hit and
//! the mirror image for a light sample (or the balance heuristic,
//! `T_j Le_j / (A + B)`). The weights sum to one for every path and depend
//! only on the path and the set of wavelengths, so both the estimator and
//! the Russian roulette probability (a function of `T_j / Σ Q_k` only) are
//! symmetric in which wavelength was the hero, which makes hero sampling
//! unbiased.

use crate::film::{
    BadSample, BandLayout, CameraSample, SampleRadiance, sample_xyz, sample_xyz_bands,
};
use crate::geometry::Ray;
use crate::glossy_lambda_table::GlossyTable;
use crate::guide::{Cones, Guided};
use crate::light::{Emission, LightSample, Lights};
use crate::light_resample;
use crate::sampler::{Reserved2d, Sampler};
use crate::scene::desc::MisHeuristic;
use crate::scene::{Scene, Settings};
use crate::shapes::{Hit, Surface};
use crate::spectral_table::SpectralTables;
use crate::wavelength::{MAX_WAVELENGTHS, SampledWavelengths};
use brdf::Bxdf;
use brdf::frame::orthonormal_basis;
use glam::DVec3;

const N: usize = MAX_WAVELENGTHS;

mod glossy_cv;
mod nee_density;
mod split;

/// Shading frame at a hit: tangent `t`, bitangent `b`, normal `n` (facing the viewer).
struct Frame {
    t: DVec3,
    b: DVec3,
    n: DVec3,
}

impl Frame {
    fn new(n: DVec3, tangent: DVec3) -> Frame {
        let t = (tangent - n * n.dot(tangent))
            .try_normalize()
            .unwrap_or_else(|| orthonormal_basis(n).0);
        Frame {
            t,
            b: n.cross(t),
            n,
        }
    }
    /// From a unit normal and a unit tangent orthogonal to it.
    #[inline]
    fn from_orthonormal(n: DVec3, t: DVec3) -> Frame {
        Frame {
            t,
            b: n.cross(t),
            n,
        }
    }
    #[inline]
    fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
    #[inline]
    fn to_world(&self, v: DVec3) -> DVec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

/// Moves a ray origin off its surface along the normal, relative to the
/// coordinates' magnitude: 1e−9 for analytic shapes (intersected in f64),
/// 1e−5 (~170 f32 ulps) for mesh triangles, which the BVH tests in f32.
#[inline]
fn offset(p: DVec3, n: DVec3, mesh: bool) -> DVec3 {
    let scale = 1.0f64.max(p.abs().max_element());
    p + n * (if mesh { 1e-5 } else { 1e-9 } * scale)
}

/// MIS weight of the strategy that produced a sample, divided by that
/// strategy's (relative) density `own`, given the other strategy's `other`:
/// balance 1/(own + other), power own/(own² + other²), written as
/// 1/(own (1 + r²)) with r = other/own so that neither squares overflows.
#[inline]
fn mis_over_pdf(mis: MisHeuristic, own: f64, other: f64) -> f64 {
    // NaN-safe: a NaN density gives no contribution either.
    if own.is_nan() || own <= 0.0 {
        return 0.0;
    }
    let w = match mis {
        MisHeuristic::Balance => 1.0 / (own + other),
        MisHeuristic::Power => {
            let r = other / own;
            1.0 / (own * (1.0 + r * r))
        }
    };
    if w.is_finite() { w } else { 0.0 }
}

/// [`mis_over_pdf`] for a light sample of density `light` (relative to the
/// BSDF strategy's `bsdf`), with the light density counted `c` times
/// ([`Settings::mis_light_weight`](crate::scene::Settings::mis_light_weight)):
/// weight w(c·light, bsdf), divided by `light`.
#[inline]
fn light_weight_over_pdf(mis: MisHeuristic, c: f64, light: f64, bsdf: f64) -> f64 {
    c * mis_over_pdf(mis, c * light, bsdf)
}

/// The BSDF strategy's counterpart of [`light_weight_over_pdf`]: the two
/// weights of a direction sum to one.
#[inline]
fn bsdf_weight_over_pdf(mis: MisHeuristic, c: f64, bsdf: f64, light: f64) -> f64 {
    mis_over_pdf(mis, bsdf, c * light)
}

/// Most times [`light_weight`] counts a light's density.
const MAX_LIGHT_COUNT: f64 = 3.0;

/// How many times a light's density `p_light` counts in the MIS heuristic
/// at a vertex whose glossy lobe has peak density `peak`
/// ([`brdf::Bxdf::lobe_peak_pdf`]), unless the scene fixes it (`fixed`).
///
/// The heuristics weigh the two strategies by density alone, as if their
/// samples were independent. Under the stratified sampler the light
/// strategy gains more when the lobe is as wide as the light or wider: its
/// strata then spread over a smooth integrand on the light, while a BSDF
/// sample hits or misses the light, a discontinuity stratification does far
/// less for. When the lobe is much narrower than the light the roles turn:
/// the BSDF sample lands inside the light, and the light's integrand is a
/// narrow peak. So the light's density counts three times while the lobe's
/// peak density is at most 16/3 ≈ 5.3× the light's, once from 16× on, and
/// in between in proportion. Relative RMSE at 64 spp against the textbook
/// weight (crates/render/README.md, with the earlier cap of 2): 0.43–0.85
/// on GGX α 0.05–0.3 plates under a light 23° wide and a Beckmann α 0.05
/// plate at 70°, 1.00 with α 0.01 and 0.02 under that light, 0.99–1.00
/// under small lights; the cap of 3 against 2 on α 0.05 and 0.1 under that
/// light: 0.90 and 0.88 at 64 spp, 0.79 and 0.71 at 256, 1.07 and 1.05 at
/// 16 (α 0.3 and the other peer scenes within 1 %). Models that do not
/// know their lobe keep the textbook weight, and so does the independent
/// sampler (the scene sets `fixed` to 1 for it): without strata the
/// argument fails, and the same plates measured 1.02–1.07. Lights at
/// infinity keep it too ([`VertexMis::at_infinity`]).
#[inline]
fn light_weight(fixed: Option<f64>, peak: Option<f64>, p_light: f64) -> f64 {
    if let Some(c) = fixed {
        return c;
    }
    let Some(peak) = peak else {
        return 1.0;
    };
    let c = 16.0 * p_light / peak;
    // NaN (an infinite peak and light density) keeps the textbook weight.
    if c > 1.0 { c.min(MAX_LIGHT_COUNT) } else { 1.0 }
}

/// The lobe size [`light_weight`] reads at a vertex: asked of the model
/// only when the scene does not fix the weight.
#[inline]
fn lobe_peak(fixed: Option<f64>, bxdf: &(impl Bxdf + ?Sized), wi: DVec3) -> Option<f64> {
    if fixed.is_none() {
        bxdf.lobe_peak_pdf(wi)
    } else {
        None
    }
}

/// How one vertex weighs light sampling against BSDF sampling: the
/// scene's heuristic and fixed light-density count, and the vertex's lobe
/// size ([`light_weight`]). Both strategies' weights come from here.
#[derive(Clone, Copy)]
struct VertexMis {
    heuristic: MisHeuristic,
    fixed: Option<f64>,
    peak: Option<f64>,
    /// The light sample's candidate count: a sample resampled from m has up
    /// to m times the density its light gives it, and both strategies count
    /// the light's density that many times more. Any count both compute
    /// alike for a direction keeps their weights summing to one, so the
    /// estimate unbiased, whatever the resampled sample's true density.
    ris: f64,
}

impl VertexMis {
    #[inline]
    fn new(settings: &Settings, peak: Option<f64>, ris: u32) -> VertexMis {
        VertexMis {
            heuristic: settings.mis,
            fixed: settings.mis_light_weight,
            peak,
            ris: f64::from(ris),
        }
    }

    /// The weights toward a light at infinity (an environment or sky) or
    /// reached by escaping: the textbook count (or the scene's fixed one).
    /// [`light_weight`]'s argument needs a light whose samples are strata
    /// of a compact emitter; a map's or sky's samples are strata of its
    /// luminance, scattered over the sphere (an HDR map's sun among its sky),
    /// and counting them up to three times raised an HDR-lit scene's
    /// variance 11–23 % (`benches/peer/generality_scenes_2.toml`).
    #[inline]
    fn at_infinity(self, yes: bool) -> VertexMis {
        if yes {
            VertexMis { peak: None, ..self }
        } else {
            self
        }
    }

    /// Weight / density of a light sample of solid-angle density `p_light`
    /// on a path whose BSDF densities sum to `q_sum` over the hero choices
    /// (1 with one wavelength), against the BSDF strategy's density
    /// `p_bsdf` toward it.
    #[inline]
    fn light(&self, p_light: f64, q_sum: f64, p_bsdf: f64) -> f64 {
        let c = light_weight(self.fixed, self.peak, p_light) * self.ris;
        light_weight_over_pdf(self.heuristic, c, q_sum * p_light, p_bsdf)
    }

    /// Weight / density of emission reached by a BSDF sample of relative
    /// density `own`, whose light strategy's density relative to it is
    /// `l_sum · p_light` (`l_sum` the sum of the edge's `L_k`).
    #[inline]
    fn bsdf(&self, p_light: f64, own: f64, l_sum: f64) -> f64 {
        let c = light_weight(self.fixed, self.peak, p_light) * self.ris;
        bsdf_weight_over_pdf(self.heuristic, c, own, l_sum * p_light)
    }
}

/// A glossy BSDF sample whose other-wavelength factors are not yet applied.
#[derive(Clone)]
struct Pending {
    material: u32,
    wi: DVec3,
    wo: DVec3,
    /// The hero's density of `wo` (a mixture's, where the vertex aimed at casters).
    pdf: f64,
    /// (1 − c, c·p_cones(wo)) of a vertex that aimed a share c of its samples
    /// at casters ([`crate::guide`]); (1, 0) where it did not.
    guide: (f64, f64),
    /// What the material's evaluation at `wo` shares between wavelengths.
    kept: brdf::Kept,
}

/// Traces camera sample `sample` of pixel (`x`, `y`).
pub fn camera_sample(scene: &Scene, x: u32, y: u32, sample: u64) -> CameraSample {
    match traced(scene, x, y, sample) {
        SampleRadiance::Spectral(cs) => cs,
        SampleRadiance::Xyz(xyz) => CameraSample {
            wavelengths: SampledWavelengths::none(),
            radiance: [0.0; N],
            xyz,
        },
        SampleRadiance::Zero => {
            // Zero at the wavelengths its draws give.
            let (sampler, _, u_lambda, _) = camera_draws(scene, x, y, sample);
            CameraSample {
                wavelengths: draw_wavelengths(scene, &sampler, u_lambda),
                radiance: [0.0; N],
                xyz: [0.0; 3],
            }
        }
    }
}

/// A camera sample's first draws: its sampler, its camera ray, the
/// reserved 2-D wavelength draw (the set's position and, jointly stratified
/// with it, which member is the hero), and the ray's offset in the pixel.
#[inline(always)]
fn camera_draws(
    scene: &Scene,
    x: u32,
    y: u32,
    sample: u64,
) -> (Sampler, Ray, Reserved2d, [f64; 2]) {
    let pixel = y as u64 * scene.camera.width as u64 + x as u64;
    let mut sampler = Sampler::new(scene.settings.sampler, scene.settings.seed, pixel, sample);
    let [ux, uy] = sampler.get_2d();
    let ray = scene.camera.ray(x as f64 + ux, y as f64 + uy);
    let u_lambda = sampler.reserve_2d();
    (sampler, ray, u_lambda, [ux, uy])
}

/// The camera sample's wavelengths, from its reserved draw `u_lambda`.
#[inline]
fn draw_wavelengths(scene: &Scene, sampler: &Sampler, u_lambda: Reserved2d) -> SampledWavelengths {
    scene.wavelengths.sample_set(
        sampler.reserved_2d(u_lambda),
        scene.settings.wavelengths_per_path(),
    )
}

/// Traces a camera sample: the radiance the film turns into colour.
#[inline(always)]
fn traced(scene: &Scene, x: u32, y: u32, sample: u64) -> SampleRadiance {
    let (mut sampler, ray, u_lambda, u_pix) = camera_draws(scene, x, y, sample);
    let first = scene.shapes.intersect(&ray, f64::INFINITY);
    if let Some(tables) = emitter_edge_tables(scene, x, y) {
        let seen = emission_over_pixel(scene, tables, (x, y), u_pix, &ray, first.as_ref());
        // The camera sample's own emission seen directly is in `seen`.
        if !matches!(
            first,
            Some(Hit {
                surface: Surface::Material(_),
                ..
            })
        ) {
            return with_xyz(SampleRadiance::Zero, seen);
        }
        return with_xyz(
            traced_beyond(scene, (x, y), u_pix, ray, first, &mut sampler, u_lambda),
            seen,
        );
    }
    traced_beyond(scene, (x, y), u_pix, ray, first, &mut sampler, u_lambda)
}

/// [`traced_from`], with a first vertex's delta lobe averaged over the pixel
/// where [`delta_over_pixel_tables`] says so.
#[inline(always)]
fn traced_beyond(
    scene: &Scene,
    xy: (u32, u32),
    u_pix: [f64; 2],
    ray: Ray,
    first: Option<Hit>,
    sampler: &mut Sampler,
    u_lambda: Reserved2d,
) -> SampleRadiance {
    let Some(tables) = delta_over_pixel_tables(scene) else {
        return traced_from(scene, ray, first, sampler, u_lambda, false);
    };
    let delta = delta_over_pixel(scene, tables, xy, u_pix, &ray, first.as_ref());
    let radiance = traced_from(scene, ray, first, sampler, u_lambda, true);
    with_xyz(radiance, delta)
}

/// Point `i` of `k` in the pixel: the 2-D Hammersley set shifted by the
/// camera sample's own offset `u` modulo the pixel (point 0 is `u`), so
/// every point is uniform over the pixel and the set stays stratified.
#[inline]
fn pixel_point(u: [f64; 2], i: usize, k: usize) -> [f64; 2] {
    [
        (u[0] + i as f64 / k as f64).fract(),
        (u[1] + (i as u32).reverse_bits() as f64 * 2f64.powi(-32)).fract(),
    ]
}

/// The scene's spectral tables where pixel (`x`, `y`) is on a directly
/// seen emitter's outline ([`crate::emitter_edges`]) and the emission seen
/// there is integrated over λ exactly.
#[inline]
fn emitter_edge_tables(scene: &Scene, x: u32, y: u32) -> Option<&SpectralTables> {
    let edges = scene.emitter_edges.as_ref()?;
    if !edges.contains(x, y) {
        return None;
    }
    scene.spectral.as_ref()
}

/// The emission seen directly (an emitter or the environment, ∫Le·cmf dλ
/// exactly) averaged over `emitter_pixel_samples` positions of pixel `xy`
/// ([`pixel_point`]; the first is the camera ray `ray`, whose hit is
/// `first`): an unbiased estimate of that term's pixel integral (the
/// film's filter is the pixel box), which the camera sample's own path
/// then leaves out. Each extra position costs a camera ray and nothing
/// else.
fn emission_over_pixel(
    scene: &Scene,
    tables: &SpectralTables,
    (x, y): (u32, u32),
    u: [f64; 2],
    ray: &Ray,
    first: Option<&Hit>,
) -> [f64; 3] {
    let k = scene.settings.emitter_pixel_samples;
    let seen = |r: &Ray, h: Option<&Hit>| match h {
        Some(Hit {
            surface: Surface::Material(_),
            ..
        }) => [0.0; 3],
        _ => tables.direct(&emission_at(&scene.lights, r, h).0),
    };
    average_over_pixel(scene, (x, y), u, k, seen(ray, first), seen)
}

/// The average of `value` (of a camera ray and its hit) over `k` positions
/// of pixel `xy` ([`pixel_point`] with the camera sample's offset `u`),
/// the first of which is the camera sample's own ray, whose value is
/// `first`.
fn average_over_pixel(
    scene: &Scene,
    (x, y): (u32, u32),
    u: [f64; 2],
    k: usize,
    first: [f64; 3],
    value: impl Fn(&Ray, Option<&Hit>) -> [f64; 3],
) -> [f64; 3] {
    let mut sum = first;
    for i in 1..k {
        let [px, py] = pixel_point(u, i, k);
        let r = scene.camera.ray(x as f64 + px, y as f64 + py);
        let e = value(&r, scene.shapes.intersect(&r, f64::INFINITY).as_ref());
        for c in 0..3 {
            sum[c] += e[c];
        }
    }
    sum.map(|v| v / k as f64)
}

/// `radiance` with `xyz` added to its exactly integrated part.
#[inline]
fn with_xyz(radiance: SampleRadiance, xyz: [f64; 3]) -> SampleRadiance {
    match radiance {
        SampleRadiance::Zero if xyz == [0.0; 3] => SampleRadiance::Zero,
        SampleRadiance::Zero => SampleRadiance::Xyz(xyz),
        SampleRadiance::Xyz(v) => SampleRadiance::Xyz(std::array::from_fn(|c| v[c] + xyz[c])),
        SampleRadiance::Spectral(mut cs) => {
            for (a, b) in cs.xyz.iter_mut().zip(xyz) {
                *a += b;
            }
            SampleRadiance::Spectral(cs)
        }
    }
}

/// The scene's spectral tables if the delta lobes of first vertices are
/// averaged over the pixel ([`delta_over_pixel`]): `delta_pixel_samples`
/// above 1 and some material's delta lobe integrated over λ exactly.
#[inline]
fn delta_over_pixel_tables(scene: &Scene) -> Option<&SpectralTables> {
    if scene.settings.delta_pixel_samples <= 1 || scene.settings.max_depth < 1 {
        return None;
    }
    scene.spectral.as_ref().filter(|t| t.has_delta())
}

/// The emission that first vertices' delta lobes reflect along their
/// mirror directions ([`exact_delta`]), averaged over
/// `delta_pixel_samples` positions in pixel `xy`: the 2-D Hammersley set
/// shifted by the camera sample's own offset `u` (so its first point is the
/// camera ray `ray`, whose hit is `first`) modulo the pixel. Every point is
/// uniform over the pixel, so the average is an unbiased estimate of the
/// term's pixel integral (the film's filter is the pixel box), which the
/// camera sample's path then leaves out (`delta_elsewhere`).
///
/// Why: where a small light's mirror image falls on a surface with a
/// coherent lobe, the term is a disk with a sharp edge, drawn by one
/// mirror ray per camera sample; its edge pixels were 91–97 % of the
/// squared error of the s138 full-GHS plate. The extra points cost a camera
/// ray and a mirror ray each, no model evaluation.
fn delta_over_pixel(
    scene: &Scene,
    tables: &SpectralTables,
    (x, y): (u32, u32),
    u: [f64; 2],
    ray: &Ray,
    first: Option<&Hit>,
) -> [f64; 3] {
    let at = |r: &Ray, h: Option<&Hit>| h.map_or([0.0; 3], |h| delta_at(scene, tables, h, r));
    let k = scene.settings.delta_pixel_samples;
    average_over_pixel(scene, (x, y), u, k, at(ray, first), at)
}

/// [`exact_delta`] at a camera ray's hit, zero unless it is a material
/// with a delta table.
#[inline]
fn delta_at(scene: &Scene, tables: &SpectralTables, hit: &Hit, ray: &Ray) -> [f64; 3] {
    match hit.surface {
        Surface::Material(m) => tables
            .delta(m)
            .map_or([0.0; 3], |d| exact_delta(scene, tables, d, hit, ray)),
        _ => [0.0; 3],
    }
}

/// [`traced`] after the camera ray's hit `first`; `delta_elsewhere`: the
/// first vertex's exact delta-lobe emission is counted by
/// [`delta_over_pixel`], not here.
#[inline(always)]
fn traced_from(
    scene: &Scene,
    ray: Ray,
    first: Option<Hit>,
    sampler: &mut Sampler,
    u_lambda: Reserved2d,
    delta_elsewhere: bool,
) -> SampleRadiance {
    // Most of the misses around an object or a plate: returned before the
    // wavelengths are drawn (their draw is reserved, so every later draw is
    // the same).
    if first.is_none() && !scene.lights.has_environment() {
        return SampleRadiance::Zero;
    }
    if let Some(tables) = &scene.spectral {
        return trace_exact(
            scene,
            tables,
            ray,
            first,
            sampler,
            u_lambda,
            delta_elsewhere,
        );
    }
    let wavelengths = draw_wavelengths(scene, sampler, u_lambda);
    let start = Throughput::camera(&wavelengths);
    let radiance = trace(scene, ray, first, &wavelengths, sampler, start, 0);
    SampleRadiance::Spectral(CameraSample {
        wavelengths,
        radiance,
        xyz: [0.0; 3],
    })
}

/// XYZ estimate (before the film's 1/∫ȳ normalisation) of one camera sample
/// at pixel (`x`, `y`); zero where [`sample_pixel_checked`] rejects it.
pub fn sample_pixel(scene: &Scene, x: u32, y: u32, sample: u64) -> [f64; 3] {
    sample_pixel_checked(scene, x, y, sample).unwrap_or([0.0; 3])
}

/// The XYZ the film adds for one camera sample, or why it cannot be
/// averaged ([`sample_xyz`]).
#[inline]
pub fn sample_pixel_checked(
    scene: &Scene,
    x: u32,
    y: u32,
    sample: u64,
) -> Result<[f64; 3], BadSample> {
    sample_xyz(traced(scene, x, y, sample), scene.signed_radiance)
}

/// [`sample_pixel_checked`] with the sample's spectral band values written
/// to `bands` ([`sample_xyz_bands`]).
#[inline]
pub fn sample_pixel_bands(
    scene: &Scene,
    x: u32,
    y: u32,
    sample: u64,
    layout: &BandLayout,
    bands: &mut [f64],
) -> Result<[f64; 3], BadSample> {
    sample_xyz_bands(
        traced(scene, x, y, sample),
        scene.signed_radiance,
        layout,
        bands,
    )
}

/// A path vertex on a reflecting surface, seen from the ray that reached it.
struct Vertex {
    frame: Frame,
    /// Geometric normal on the viewer's side.
    ng: DVec3,
    /// Shaded with an interpolated normal (directions must still leave on
    /// the geometric side).
    smooth: bool,
    /// Direction toward the viewer, local frame.
    wi: DVec3,
    /// Origin of rays leaving the vertex.
    p: DVec3,
}

impl Vertex {
    /// `None` if the viewer is below the shading frame's horizon.
    // Inlined: returned from a call, the 152-byte option would be copied
    // out by a memcpy call at every hit.
    #[inline(always)]
    fn new(hit: &Hit, ray: &Ray) -> Option<Vertex> {
        let ng = if hit.geo.n.dot(ray.d) > 0.0 {
            -hit.geo.n
        } else {
            hit.geo.n
        };
        // Smooth-shaded meshes: the BSDF frame follows the interpolated
        // normal, turned to the viewer's side of the triangle; directions
        // must still leave on the geometric side, or light would leak
        // through the surface.
        let smooth = hit.shading_n.is_some();
        let ns = match hit.shading_n {
            Some(s) if s.dot(ng) < 0.0 => -s,
            Some(s) => s,
            None => ng,
        };
        // On an analytic shape the hit's tangent is a unit vector orthogonal
        // to its normal to round-off (`analytic_hit_tangents_are_orthonormal`),
        // so the Gram–Schmidt step (a square root and a division on every
        // hit's critical path) is skipped. A mesh triangle's normal, a cross
        // product of its edges, loses that on slivers; an interpolated normal
        // never had it.
        let frame = if smooth || hit.mesh {
            Frame::new(ns, hit.geo.tangent)
        } else {
            Frame::from_orthonormal(ns, hit.geo.tangent)
        };
        let wi = frame.to_local(-ray.d);
        (wi.z > 0.0).then(|| Vertex {
            frame,
            ng,
            smooth,
            wi,
            p: offset(hit.geo.p, ng, hit.mesh),
        })
    }

    /// A light sample's direction in the local frame, if it leaves above
    /// both horizons.
    #[inline]
    fn light_direction(&self, ls: &LightSample) -> Option<DVec3> {
        self.toward(ls.wi, ls.pdf)
    }

    /// [`Vertex::light_direction`] of world direction `wi` of density `pdf`.
    #[inline]
    fn toward(&self, wi: DVec3, pdf: f64) -> Option<DVec3> {
        let wo = self.frame.to_local(wi);
        (wo.z > 0.0 && pdf > 0.0 && (!self.smooth || wi.dot(self.ng) > 0.0)).then_some(wo)
    }

    /// The ray along local direction `wo`, if it leaves on the geometric side.
    #[inline]
    fn ray(&self, wo: DVec3) -> Option<Ray> {
        let d = self.frame.to_world(wo).normalize();
        (!self.smooth || d.dot(self.ng) > 0.0).then_some(Ray { o: self.p, d })
    }
}

/// The emission `ray` meets at `hit` (an emitter, or the environment when
/// it escapes) with the light-sampling density of that point; nothing at a
/// reflecting surface.
#[inline]
fn emission_at<'a>(lights: &'a Lights, ray: &Ray, hit: Option<&Hit>) -> (Emission<'a>, f64) {
    match hit {
        None => lights.environment(ray.d),
        Some(Hit {
            surface: Surface::Emitter(i),
            geo,
            ..
        }) => lights.emitted(*i as usize, ray.o, ray.d, geo.n, geo.t),
        Some(_) => (Emission::None, 0.0),
    }
}

/// A vertex's numbers for light sampling and for BSDF sampling, in that
/// order. Both are drawn before either is used: every vertex that samples a
/// light goes on to sample its BSDF, so nothing is drawn in vain, and the two
/// Sobol draws (each a chain of a dozen dependent multiplications) overlap
/// instead of each waiting at the head of its strategy.
#[inline(always)]
fn vertex_draws(
    sampler: &mut Sampler,
    lights: &Lights,
    bxdf: &(impl Bxdf + ?Sized),
) -> ([f64; 3], [f64; 3]) {
    let u_light = sampler.get_1d_2d_if(lights.nee_len() > 1);
    let u_bsdf = sampler.get_1d_2d_if(bxdf.uses_lobe_choice());
    (u_light, u_bsdf)
}

/// Adds the emission that the delta lobe of a multi-lobe model reflects at
/// vertex `v` (its weight R·A at each of the `n` wavelengths times the
/// radiance along the mirror direction, times `w`, the path's spectral MIS
/// normalisation) through `add(j, value)`; returns whether it traced the
/// mirror ray (some wavelength's delta weight is positive).
///
/// Why not leave it to BSDF sampling: a model such as GHS reflects a
/// fraction A = e^{−g} coherently, and its sampler picks the delta lobe with
/// probability p = max(A, 0.05). Where the mirror direction meets a small,
/// bright light, that lobe is most of the pixel, so the pick is a rare event
/// of weight 1/p: left to it, the s138 full-GHS plates have a relative RMSE
/// of 5.9 at 1 spp and 0.14 at 256 (hero), falling slower than spp^−½. One
/// more ray per such vertex makes the term exact; the sampled delta
/// direction still carries the path on, but counts no emission.
#[inline]
fn delta_emission(
    scene: &Scene,
    bxdf: &(impl Bxdf + ?Sized),
    v: &Vertex,
    lambdas: &[f64; N],
    n: usize,
    mut add: impl FnMut(usize, f64),
    w: f64,
) -> bool {
    let mut spec = [0.0; N];
    for (s, &lambda) in spec.iter_mut().zip(lambdas).take(n) {
        *s = bxdf.specular(v.wi, lambda).weight;
    }
    if !spec[..n].iter().any(|&s| s > 0.0) {
        return false;
    }
    let Some(ray) = v.ray(brdf::frame::reflect_z(v.wi)) else {
        return true;
    };
    let hit = scene.shapes.intersect(&ray, f64::INFINITY);
    let (em, _) = emission_at(&scene.lights, &ray, hit.as_ref());
    if w > 0.0 && !matches!(em, Emission::None) {
        let mut e = [0.0; N];
        em.eval_many(&lambdas[..n], &mut e[..n]);
        for j in 0..n {
            add(j, spec[j] * e[j] * w);
        }
    }
    true
}

/// (f, pdf) at each of a path's wavelengths.
type FPerLambda = [(f64, f64); N];

/// The BSDF side of a light sample at `wo` for [`next_event`]: f and pdf at
/// each wavelength (no pdf toward a delta light, which BSDF sampling cannot
/// reach), Σ Q_k and the pdf Σ Q_k p_k of the path's wavelengths' sampling;
/// `None` where f is zero at every wavelength.
fn nee_bsdf(
    bxdf: &dyn Bxdf,
    wi: DVec3,
    wo: DVec3,
    is_delta: bool,
    lambdas: &[f64],
    q: &[f64],
) -> Option<(f64, f64, FPerLambda)> {
    let n = lambdas.len();
    let mut fp = [(0.0, 0.0); N];
    bxdf.eval_pdf_many(wi, wo, lambdas, &mut fp[..n]);
    if !fp[..n].iter().any(|v| v.0 > 0.0) {
        return None;
    }
    let (q_sum, p_bsdf) = nee_density::sums(&mut fp[..n], is_delta, q);
    Some((q_sum, p_bsdf, fp))
}

/// Added to the RIS proxy (a BSDF density, sr⁻¹) so that it is positive
/// wherever the BSDF may be, as `light_resample`'s unbiasedness needs.
const RIS_FLOOR: f64 = 1e-3;

/// Candidates per resampled light sample, and the factor by which the MIS
/// heuristics count the light's density at such a vertex. hdri_spheres and
/// softbox_object, 64 spp, 4 seeds (relRMSE, CPU s): none 0.1443, 0.89 and
/// 0.1197, 1.15; 4 candidates counted once 0.1261 / –; 4 counted 4× 0.1115,
/// 1.21 / 0.0943, 1.44; 8 counted 8× 0.0881, 1.51 / 0.0821, 1.70; 16
/// counted 16× 0.0824, 2.22 / –; 8 counted 16× 0.0902 / –. Counted once,
/// the resampled sample's weight follows its original density, and at a
/// narrow lobe BSDF sampling keeps most of the weight the resampling won;
/// a sample picked among m has up to m times its density.
const RIS_CANDIDATES: u32 = 8;

/// Resampling only where the lobe's peak density exceeds this (sr⁻¹): a
/// diffuse vertex (1/π) and the widest glossy ones gain too little for m
/// samples and evaluations (with the diffuse floor of hdri_spheres included,
/// 8 candidates took 2.8 CPU s for relRMSE 0.092 against 1.3 s for 0.094;
/// softbox_object's rough-plastic α 0.3 floor, peak 0.5–1 at its views,
/// resampled: relRMSE 0.0819 → 0.0823 for 1.27 → 1.85 CPU s). 2 rather than
/// 5 takes in the rough-plastic α 0.1 sphere of cornell_box_metals (64 spp,
/// 4 seeds: relRMSE 0.0578 → 0.0552 for 1.86 → 1.93 CPU s) and the
/// hdri_spheres plastic (0.0935 → 0.0896, 1.09 → 1.16 s); softbox_object
/// the same (0.0819 / 0.0820).
const RIS_MIN_PEAK: f64 = 2.0;

/// Whether and how a vertex resamples its light sample (`light_resample`).
#[derive(Clone, Copy)]
struct Resampling {
    /// Candidates (1: the plain light sample).
    m: u32,
    /// The uniform number that picks among them.
    u_pick: f64,
}

/// The resampling of a vertex whose lobe has peak density `peak`
/// (`None` where the scene fixes the MIS weight: it then keeps the plain
/// light sample, so both strategies' weights stay the ones it asked for).
/// Draws the pick's number only where it resamples.
///
/// Not where every light is a point or sphere ([`Lights::resamples`]), but
/// wherever else the lobe is narrow, also where it is wider than a
/// rectangle light: requiring the peak to exceed
/// 2× the light's density (a lobe that covers the light, whose candidates
/// differ little in the proxy, was thought to gain nothing) lost on both
/// rectangle-lit scenes, 64 spp, 4 seeds, relRMSE at 2×, ½×, 0×:
/// softbox_object 0.0867, 0.0820, 0.0819 and cornell_box_metals 0.0624,
/// 0.0582, 0.0578, CPU within the noise and +3 %.
#[inline]
fn resampling(sampler: &mut Sampler, lights: &Lights, peak: Option<f64>) -> Resampling {
    let on = peak.is_some_and(|k| k > RIS_MIN_PEAK && lights.resamples());
    if on {
        Resampling {
            m: RIS_CANDIDATES,
            u_pick: sampler.get_1d(),
        }
    } else {
        Resampling { m: 1, u_pick: 0.0 }
    }
}

/// Next-event estimation at vertex `v`: one light sample drawn with
/// `u_light`, weighted against BSDF sampling by `mis`. `bsdf(wo, is_delta)`
/// evaluates the BSDF toward the sampled point: `None` where it is zero at
/// every wavelength, otherwise the sum of the path's `Q_k`, the BSDF
/// strategy's density toward it (0 for a delta light, which BSDF sampling
/// cannot reach) and what `add` needs of the evaluation; `add(light sample,
/// wo, weight / density, evaluation)` counts the contribution of a light
/// that nothing blocks.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn next_event<'s, E>(
    scene: &'s Scene,
    v: &Vertex,
    u_light: [f64; 3],
    mis: VertexMis,
    ris: Resampling,
    proxy: impl Fn(DVec3) -> f64,
    bsdf: impl FnOnce(DVec3, bool) -> Option<(f64, f64, E)>,
    add: impl FnOnce(&LightSample<'s>, DVec3, f64, E),
) {
    let (ls, ratio) = if ris.m > 1 {
        let h = |wi, pdf| v.toward(wi, pdf).map_or(0.0, |wo| proxy(wo) + RIS_FLOOR);
        let Some(x) = light_resample::resample(&scene.lights, v.p, u_light, ris.m, ris.u_pick, h)
        else {
            return;
        };
        x
    } else {
        let Some(ls) = scene.lights.sample(v.p, u_light) else {
            return;
        };
        (ls, 1.0)
    };
    let Some(wo) = v.light_direction(&ls) else {
        return;
    };
    let Some((q_sum, p_bsdf, eval)) = bsdf(wo, ls.is_delta) else {
        return;
    };
    if !unoccluded(scene, v.p, &ls) {
        return;
    }
    let w = ratio
        * mis
            .at_infinity(ls.dist.is_infinite())
            .light(ls.pdf, q_sum, p_bsdf);
    if w > 0.0 {
        add(&ls, wo, w, eval);
    }
}

/// Whether nothing blocks the segment from `p` to a light sample.
#[inline]
fn unoccluded(scene: &Scene, p: DVec3, ls: &LightSample) -> bool {
    let shadow = Ray { o: p, d: ls.wi };
    let t_max = if ls.dist.is_finite() {
        ls.dist * (1.0 - 1e-7)
    } else {
        f64::INFINITY
    };
    !scene.shapes.occluded(&shadow, t_max, ls.shape)
}

/// The per-wavelength state of a path (see the module documentation):
/// `T_j`, `Q_k`, and the BSDF-sampling densities `L_k` of the last edge
/// for the MIS of an emitter it reaches.
#[derive(Clone)]
struct Throughput {
    t: [f64; N],
    q: [f64; N],
    l_mis: [f64; N],
    /// The last vertex's lobe size ([`light_weight`]).
    peak: Option<f64>,
    /// The last vertex's light-sample candidates ([`VertexMis::ris`]).
    ris: u32,
    /// The glossy sample of the last vertex, until its other wavelengths'
    /// BSDF value and pdf are applied ([`Throughput::resolve`]).
    pending: Option<Pending>,
    /// The next vertex's delta-lobe emission is already counted
    /// ([`exact_delta`]).
    delta_counted: bool,
}

impl Throughput {
    /// At the camera.
    fn camera(wavelengths: &SampledWavelengths) -> Throughput {
        let mut t = [0.0; N];
        for (t, p) in t.iter_mut().zip(wavelengths.pdfs()) {
            *t = 1.0 / p;
        }
        Throughput {
            t,
            q: [1.0; N],
            l_mis: [0.0; N],
            peak: None,
            ris: 1,
            pending: None,
            delta_counted: false,
        }
    }

    /// Applies the pending glossy sample's factors at the wavelengths other
    /// than the hero. They are needed only if the path goes on to another
    /// vertex or reaches emission; a path that ends (it escapes into no
    /// environment, or hits a surface at the last depth) skips them, and at
    /// the last bounce of a direct-lighting render that is most paths.
    #[inline]
    fn resolve(&mut self, scene: &Scene, lambdas: &[f64; N], n: usize) {
        if let Some(p) = self.pending.take() {
            let bxdf = &scene.materials[p.material as usize].bxdf;
            let mut fp = [(0.0, 0.0); N];
            bxdf.eval_pdf_many_kept(p.wi, p.wo, &p.kept, &lambdas[1..n], &mut fp[1..n]);
            let pairs = self.t[1..n].iter_mut().zip(&mut self.q[1..n]);
            let (keep, g) = p.guide;
            for ((t, q), &(f, pdf)) in pairs.zip(&fp[1..n]) {
                *t *= f * p.wo.z / p.pdf;
                *q *= (keep * pdf + g) / p.pdf;
            }
        }
    }
}

/// max_j T_j / Σ Q_k at the camera, the scale Russian roulette compares with.
#[inline]
fn roulette_scale(wavelengths: &SampledWavelengths) -> f64 {
    let pdfs = wavelengths.pdfs();
    pdfs.iter().fold(0.0f64, |a, &p| a.max(1.0 / p)) / pdfs.len() as f64
}

/// Russian roulette on the hero-symmetric throughput T_j / Σ Q_k, compared
/// with its value `m0` at the camera: `false` ends the path; a survivor's
/// throughput is divided by its survival probability.
#[inline]
fn survives(th: &mut Throughput, n: usize, m0: f64, sampler: &mut Sampler) -> bool {
    let sum_q: f64 = th.q[..n].iter().sum();
    let m = th.t[..n].iter().fold(0.0f64, |a, v| a.max(v.abs())) / (sum_q * m0);
    let survive = m.min(1.0);
    if survive.is_nan() || survive <= 0.0 || sampler.get_1d() >= survive {
        return false;
    }
    for tj in th.t.iter_mut().take(n) {
        *tj /= survive;
    }
    true
}

/// Any wavelength: the λ-free part of a Fresnel-only model ignores it.
const UNIT_LAMBDA: f64 = 550.0;

/// A Fresnel factor F(λ, cosθd) a λ-exact path carries: its table, the
/// factor itself, and cos²θd = `num`/`den` at its vertex.
#[derive(Clone, Copy)]
struct Conductor<'a> {
    table: u32,
    fresnel: &'a brdf::Fresnel,
    num: f64,
    den: f64,
}

/// `xyz += w · e`.
#[inline]
fn add_scaled(xyz: &mut [f64; 3], e: [f64; 3], w: f64) {
    for c in 0..3 {
        xyz[c] += w * e[c];
    }
}

/// A camera path integrated over λ exactly where its materials allow it:
/// emission seen directly, and a path whose first vertex is λ-free or
/// Fresnel-only ([`trace_flat`], which hands over to sampled
/// wavelengths at the first vertex that needs them). A first vertex of
/// any other material is traced with sampled wavelengths from the start,
/// its delta lobe and glossy control variate integrated exactly where it
/// has their tables.
fn trace_exact(
    scene: &Scene,
    tables: &SpectralTables,
    ray: Ray,
    first: Option<Hit>,
    sampler: &mut Sampler,
    u_lambda: Reserved2d,
    delta_elsewhere: bool,
) -> SampleRadiance {
    let settings = &scene.settings;
    let Some(
        hit @ Hit {
            surface: Surface::Material(m),
            ..
        },
    ) = first
    else {
        // Emission seen directly: the only strategy, weight 1.
        let (em, _) = emission_at(&scene.lights, &ray, first.as_ref());
        return SampleRadiance::Xyz(tables.direct(&em));
    };
    let material = &scene.materials[m as usize];
    // (A λ-free model with a delta lobe among others is handed over at
    // once; it has no delta or glossy table to miss.)
    if material.lambda_free || tables.material(m).is_some() && material.fresnel_only.is_some() {
        return trace_flat(scene, tables, ray, hit, sampler, u_lambda);
    }
    let mut xyz = [0.0; 3];
    let wavelengths = draw_wavelengths(scene, sampler, u_lambda);
    let mut start = Throughput::camera(&wavelengths);
    if let Some(delta) = tables.delta(m).filter(|_| settings.max_depth >= 1) {
        if !delta_elsewhere {
            add_scaled(&mut xyz, exact_delta(scene, tables, delta, &hit, &ray), 1.0);
        }
        start.delta_counted = true;
    }
    if let Some(glossy) = tables.glossy(m).filter(|_| settings.max_depth >= 1) {
        let first = FirstVertex {
            tables,
            glossy,
            m,
            hit: &hit,
            ray: &ray,
        };
        return first_vertex_cv(scene, first, &wavelengths, sampler, start, xyz);
    }
    let radiance = trace(scene, ray, Some(hit), &wavelengths, sampler, start, 0);
    SampleRadiance::Spectral(CameraSample {
        wavelengths,
        radiance,
        xyz,
    })
}

// Camera paths integrated over λ exactly for as long as they allow it.
//
// A path's measurement at λ is the product of its vertices' factors times
// the emission it reaches. While every vertex is λ-free
// ([`Material::lambda_free`](crate::material::Material::lambda_free):
// grey diffuse or rough plastic, a conductor with `fresnel = "one"`), the
// product is one number T for every λ and each emission the path counts
// is T·∫Le·cmf dλ, exact with [`SpectralTables::direct`]. One Fresnel-only
// conductor vertex anywhere on the path adds the factor F(λ, cosθd) to
// every later contribution, still exact with
// [`SpectralTables::reflected`] at that vertex's cosθd. A vertex that
// would add a second λ-dependent factor (a second conductor, a
// wave-optical model, a tabulated reflectance) ends the exact part: the
// path draws its wavelengths from the camera sample's reserved draw and
// goes on in [`trace`] with the state the sampled estimator would have
// there.
//
// Unbiased against the sampled estimator path by path: no density depends
// on λ on such a path, so every `Q_k` is 1 and the sampled MIS weights,
// summed over the n wavelengths, are the weights used here (one
// wavelength's share, 1/n, of each strategy's density); Russian roulette
// reads T, which is what the sampled estimator's hero-symmetric
// throughput equals on a path without a conductor (with one, the factor
// at [`UNIT_LAMBDA`] stands in for the sampled wavelengths' largest; any
// survival probability above zero keeps the estimate unbiased).
/// How a material enters a λ-exact path.
#[derive(Clone, Copy)]
enum FlatVertex<'a> {
    /// A λ-free model: its factor is the same number at every λ.
    Free(&'a dyn Bxdf),
    /// A Fresnel-only model: its λ-free part, and the table and Fresnel
    /// factor of the part that is not.
    Fresnel(&'a dyn Bxdf, u32, &'a brdf::Fresnel),
}

impl<'a> FlatVertex<'a> {
    /// The model's λ-free part.
    #[inline]
    fn unit(self) -> &'a dyn Bxdf {
        match self {
            FlatVertex::Free(b) | FlatVertex::Fresnel(b, ..) => b,
        }
    }

    /// The Fresnel factor a path carries past this vertex, left at
    /// cos²θd = `num`/`den`: this vertex's own, or the one it held (`held`).
    #[inline]
    fn conductor(self, num: f64, den: f64, held: Option<Conductor<'a>>) -> Option<Conductor<'a>> {
        match self {
            FlatVertex::Fresnel(_, table, fresnel) => Some(Conductor {
                table,
                fresnel,
                num,
                den,
            }),
            FlatVertex::Free(_) => held,
        }
    }
}

/// How material `m` enters a λ-exact path at a vertex seen from `wi`
/// that carries a conductor's factor already (`held`), or `None` where the
/// path must sample λ.
#[inline]
fn flat_vertex<'a>(
    scene: &'a Scene,
    tables: &SpectralTables,
    m: u32,
    held: bool,
    wi: DVec3,
) -> Option<FlatVertex<'a>> {
    let material = &scene.materials[m as usize];
    let bxdf = &*material.bxdf;
    // A delta lobe among others would need `delta_emission`; no λ-free
    // model has one, but one that says it might is left to the sampled
    // tracer rather than trusted.
    if material.lambda_free
        && (!bxdf.uses_lobe_choice() || bxdf.specular(wi, UNIT_LAMBDA).weight == 0.0)
    {
        return Some(FlatVertex::Free(bxdf));
    }
    if held {
        return None;
    }
    let (table, split) = (tables.material(m)?, material.fresnel_only.as_ref()?);
    Some(FlatVertex::Fresnel(&*split.unit, table, &split.fresnel))
}

/// The state of a λ-exact path.
#[derive(Clone)]
struct FlatPath<'a> {
    /// The path's throughput, the same at every λ but for `conductor`.
    tau: f64,
    /// The one λ-dependent factor the path carries, if any.
    conductor: Option<Conductor<'a>>,
    /// The last edge's BSDF density relative to the light strategy's (0
    /// for a delta direction, which light sampling cannot produce).
    l_mis: f64,
    /// The last vertex's lobe size ([`light_weight`]).
    peak: Option<f64>,
    /// The last vertex's light-sample candidates ([`VertexMis::ris`]).
    ris: u32,
    /// What the path has counted.
    xyz: [f64; 3],
}

impl<'a> FlatPath<'a> {
    /// ∫ Le · cmf dλ, times the carried Fresnel factor `c` if any.
    #[inline]
    fn integral(tables: &SpectralTables, em: &Emission, c: Option<Conductor>) -> [f64; 3] {
        match c {
            None => tables.direct(em),
            Some(c) => tables.reflected(c.table, c.num, c.den, em),
        }
    }

    /// Counts the emission the last edge `ray` reaches at `hit` (an
    /// emitter, or the environment), weighted as [`reached_emission`]
    /// weighs it; seen from the camera (`depth` 0), weight 1.
    #[inline]
    fn reached(
        &mut self,
        scene: &Scene,
        tables: &SpectralTables,
        ray: &Ray,
        hit: Option<&Hit>,
        depth: u32,
    ) {
        let (em, pdf_l) = emission_at(&scene.lights, ray, hit);
        if matches!(em, Emission::None) {
            return;
        }
        let w = if depth == 0 {
            1.0
        } else {
            VertexMis::new(&scene.settings, self.peak, self.ris)
                .at_infinity(hit.is_none())
                .bsdf(pdf_l, 1.0, self.l_mis)
        };
        if w > 0.0 {
            let e = Self::integral(tables, &em, self.conductor);
            add_scaled(&mut self.xyz, e, self.tau * w);
        }
    }

    /// Next-event estimation and the BSDF sample at vertex `v` of material
    /// `vertex`: the ray the path goes on along, if it does.
    fn scatter(
        &mut self,
        scene: &Scene,
        tables: &SpectralTables,
        vertex: FlatVertex<'a>,
        v: &Vertex,
        cones: Option<Cones>,
        sampler: &mut Sampler,
    ) -> Option<Ray> {
        let mut guided = None;
        let bx = Guided::over(&mut guided, vertex.unit(), cones);
        let u_bsdf = self.light(scene, tables, vertex, bx, v, sampler);
        self.sample(vertex, bx, v, u_bsdf)
    }

    /// Next-event estimation at vertex `v` of material `vertex` (whose
    /// λ-free part, guided where the vertex has cones, is `bx`); returns
    /// the BSDF sample's numbers, drawn with the light's.
    fn light(
        &mut self,
        scene: &Scene,
        tables: &SpectralTables,
        vertex: FlatVertex<'a>,
        bx: &dyn Bxdf,
        v: &Vertex,
        sampler: &mut Sampler,
    ) -> [f64; 3] {
        let settings = &scene.settings;
        let wi = v.wi;
        self.peak = lobe_peak(settings.mis_light_weight, bx, wi);
        let (u_light, u_bsdf) = vertex_draws(sampler, &scene.lights, bx);
        let ris = resampling(sampler, &scene.lights, self.peak);
        self.ris = ris.m;
        let mis = VertexMis::new(settings, self.peak, ris.m);
        let (tau, held) = (self.tau, self.conductor);
        let xyz = &mut self.xyz;
        next_event(
            scene,
            v,
            u_light,
            mis,
            ris,
            |wo| bx.pdf(wi, wo, UNIT_LAMBDA),
            |wo, is_delta| {
                let (f, pdf) = bx.eval_pdf(wi, wo, UNIT_LAMBDA);
                (f > 0.0).then_some((1.0, if is_delta { 0.0 } else { pdf }, f))
            },
            |ls, wo, w, f| {
                let c = vertex.conductor((wi + wo).length_squared(), 4.0, held);
                let e = Self::integral(tables, &ls.emission, c);
                add_scaled(xyz, e, tau * f * wo.z * w);
            },
        );
        u_bsdf
    }

    /// The BSDF sample at vertex `v` (see [`FlatPath::light`]) drawn with
    /// `u_bsdf`: the ray the path goes on along, if it does.
    #[inline]
    fn sample(
        &mut self,
        vertex: FlatVertex<'a>,
        bx: &dyn Bxdf,
        v: &Vertex,
        u_bsdf: [f64; 3],
    ) -> Option<Ray> {
        let wi = v.wi;
        let s = bx.sample(wi, UNIT_LAMBDA, u_bsdf)?;
        if s.pdf.is_nan() || s.pdf <= 0.0 || s.wo.z <= 0.0 {
            return None;
        }
        // cos²θd as a ratio: the mirror's θi, or |wi + wo|²/4.
        let (num, den) = if s.is_delta {
            (wi.z * wi.z, 1.0)
        } else {
            ((wi + s.wo).length_squared(), 4.0)
        };
        self.conductor = vertex.conductor(num, den, self.conductor);
        self.tau *= s.weight;
        self.l_mis = if s.is_delta { 0.0 } else { 1.0 / s.pdf };
        v.ray(s.wo)
    }

    /// Russian roulette on the path's throughput (see the module
    /// documentation); a survivor's throughput is divided by its survival
    /// probability.
    #[inline]
    fn survives(&mut self, sampler: &mut Sampler) -> bool {
        let f = self.conductor.map_or(1.0, |c| {
            c.fresnel.reflectance_ratio(c.num, c.den, UNIT_LAMBDA)
        });
        let survive = (self.tau.abs() * f).min(1.0);
        if survive.is_nan() || survive <= 0.0 || sampler.get_1d() >= survive {
            return false;
        }
        self.tau /= survive;
        true
    }

    /// Goes on with sampled wavelengths at `hit`, scattering event `depth`
    /// (reached along `ray`): the wavelengths from the camera sample's
    /// reserved draw `u_lambda`, and the state [`trace`] would have there,
    /// T_j = T·F(λ_j)/p(λ_j), every Q_k = 1 and L_k the last edge's
    /// relative density.
    fn hand_over(
        self,
        scene: &Scene,
        ray: Ray,
        hit: Hit,
        sampler: &mut Sampler,
        u_lambda: Reserved2d,
        depth: u32,
    ) -> SampleRadiance {
        let wavelengths = draw_wavelengths(scene, sampler, u_lambda);
        let n = wavelengths.len();
        let mut th = Throughput::camera(&wavelengths);
        let mut f = [1.0; N];
        if let Some(c) = self.conductor {
            c.fresnel
                .reflectance_ratio_many(c.num, c.den, wavelengths.lambdas(), &mut f[..n]);
        }
        let state = th.t.iter_mut().zip(&mut th.l_mis).zip(&f);
        for ((t, l), f) in state.take(n) {
            *t *= self.tau * f;
            *l = self.l_mis;
        }
        th.peak = self.peak;
        th.ris = self.ris;
        let radiance = trace(scene, ray, Some(hit), &wavelengths, sampler, th, depth);
        SampleRadiance::Spectral(CameraSample {
            wavelengths,
            radiance,
            xyz: self.xyz,
        })
    }
}

/// A camera path from its first hit `first` (a material that
/// [`flat_vertex`] takes) along camera ray `ray`, integrated over λ
/// exactly until a vertex needs sampled wavelengths (then handed over to
/// [`trace`] with the reserved draw `u_lambda`).
fn trace_flat(
    scene: &Scene,
    tables: &SpectralTables,
    ray: Ray,
    first: Hit,
    sampler: &mut Sampler,
    u_lambda: Reserved2d,
) -> SampleRadiance {
    let path = FlatPath {
        tau: 1.0,
        conductor: None,
        l_mis: 0.0,
        peak: None,
        ris: 1,
        xyz: [0.0; 3],
    };
    flat_walk(scene, tables, path, ray, Some(first), sampler, u_lambda, 0)
}

/// A λ-exact path `path` from scattering event `depth0` on, whose ray
/// `ray` reached `hit`; at its first vertex it may split into branches
/// ([`split::branches`]).
#[allow(clippy::too_many_arguments)]
fn flat_walk<'a>(
    scene: &'a Scene,
    tables: &SpectralTables,
    mut path: FlatPath<'a>,
    mut ray: Ray,
    mut hit: Option<Hit>,
    sampler: &mut Sampler,
    u_lambda: Reserved2d,
    depth0: u32,
) -> SampleRadiance {
    let settings = &scene.settings;
    for depth in depth0..=settings.max_depth {
        let Some(
            h @ Hit {
                surface: Surface::Material(m),
                ..
            },
        ) = hit
        else {
            path.reached(scene, tables, &ray, hit.as_ref(), depth);
            break;
        };
        if depth == settings.max_depth {
            break;
        }
        let Some(v) = Vertex::new(&h, &ray) else {
            break;
        };
        let Some(vertex) = flat_vertex(scene, tables, m, path.conductor.is_some(), v.wi) else {
            return path.hand_over(scene, ray, h, sampler, u_lambda, depth);
        };
        let cones = scene.casters.cones(m, v.p, |d| v.frame.to_local(d));
        if depth == 0 {
            let k = split::branches(scene, vertex.unit(), v.wi);
            if k > 1 {
                let at = FlatSplit {
                    tables,
                    vertex,
                    v: &v,
                    cones,
                    u_lambda,
                    k,
                };
                return flat_split(scene, path, at, sampler);
            }
        }
        let Some(next) = path.scatter(scene, tables, vertex, &v, cones, sampler) else {
            break;
        };
        if depth + 1 >= settings.rr_depth && !path.survives(sampler) {
            break;
        }
        ray = next;
        hit = scene.shapes.intersect(&ray, f64::INFINITY);
    }
    SampleRadiance::Xyz(path.xyz)
}

/// A first vertex whose glossy lobe has a control-variate table.
struct FirstVertex<'a> {
    tables: &'a SpectralTables,
    glossy: &'a GlossyTable,
    m: u32,
    hit: &'a Hit,
    ray: &'a Ray,
}

/// Σ_j `r[j]` · cmf(λ_j) into `xyz`.
#[inline]
fn add_spectral(xyz: &mut [f64; 3], lambdas: &[f64], r: &[f64]) {
    let cie = crate::spectrum::Cie::get();
    for (&l, &v) in lambdas.iter().zip(r) {
        let c = cie.xyz(l);
        for k in 0..3 {
            xyz[k] += v * c[k];
        }
    }
}

/// The first vertex of a camera path on a material with a glossy
/// control-variate table ([`crate::glossy_lambda_table`]): what [`trace`]
/// does at depth 0, except that both strategies' glossy contributions,
/// Σ_j T_j f(λ_j) Le(λ_j) cmf(λ_j) · cosθo · weight, become
/// n · ∫ Le f̃ cmf dλ + Σ_j T_j (f − f̃)(λ_j) Le(λ_j) cmf(λ_j), times the same
/// cosθo · weight, into the sample's XYZ. The first term is the second's
/// expectation over the wavelengths with f̃ in place of f, so each
/// strategy's estimate keeps its expectation for every direction; both
/// use the same MIS weights as [`trace`], which sum to one for every
/// direction and wavelength set, so the sum over strategies stays unbiased
/// though the weights depend on the wavelengths. The sampled part is the
/// residual f − f̃, small where the table resolves the lobe: most of a
/// wave-optical plate's colour noise under a small light.
///
/// The XYZ holds the whole glossy estimate, not only its exact part, and
/// the radiance at each wavelength stays the non-negative rest. The
/// estimate itself can be negative where f̃ exceeds f; such scenes are
/// [`Scene::signed_radiance`], so the film keeps those samples. A path that
/// goes on continues in [`trace`] from depth 1. The light sample's
/// residual is evaluated with probability `glossy_residual`
/// ([`glossy_cv`]; the BSDF sample's always, its f being the throughput).
// The loops index several per-wavelength arrays at once.
#[allow(clippy::needless_range_loop)]
fn first_vertex_cv(
    scene: &Scene,
    first: FirstVertex,
    wavelengths: &SampledWavelengths,
    sampler: &mut Sampler,
    mut th: Throughput,
    mut xyz: [f64; 3],
) -> SampleRadiance {
    let (lambdas, n) = (&wavelengths.lambda, wavelengths.n);
    let (lights, settings) = (&scene.lights, &scene.settings);
    let bxdf = &scene.materials[first.m as usize].bxdf;
    let g = first.glossy;
    let mut out = [0.0; N];
    let done = |radiance, xyz| {
        SampleRadiance::Spectral(CameraSample {
            wavelengths: *wavelengths,
            radiance,
            xyz,
        })
    };
    let Some(v) = Vertex::new(first.hit, first.ray) else {
        return done(out, xyz);
    };
    let wi = v.wi;
    th.peak = lobe_peak(settings.mis_light_weight, bxdf, wi);
    let (u_light, u_bsdf) = vertex_draws(sampler, lights, bxdf);
    let ris = resampling(sampler, lights, th.peak);
    th.ris = ris.m;
    let mis = VertexMis::new(settings, th.peak, ris.m);
    let residual = glossy_cv::Residual::draw(settings.glossy_residual, sampler);
    // Every Q_k is 1 at the camera.
    let q_sum = n as f64;
    let t = th.t;
    // n ∫ Le f̃ cmf dλ + r Σ_j T_j (f cosθo − f̃)(λ_j) Le(λ_j) cmf(λ_j), times
    // `scale` (the table holds f cosθo); no residual where r is 0.
    let glossy =
        |xyz: &mut [f64; 3], wo: DVec3, f: &[(f64, f64); N], em: &Emission, scale: f64, r: f64| {
            let rows = g.rows(&**bxdf, &crate::glossy_lambda_table::corners(wi, wo));
            let exact = first.tables.glossy_exact_rows(&rows, em);
            for k in 0..3 {
                xyz[k] += scale * q_sum * exact[k];
            }
            if r == 0.0 {
                return;
            }
            let mut e = [0.0; N];
            em.eval_many(&lambdas[..n], &mut e[..n]);
            for j in 0..n {
                e[j] *= r * scale * t[j] * (f[j].0 * wo.z - rows.interpolant(lambdas[j]));
            }
            add_spectral(xyz, &lambdas[..n], &e[..n]);
        };

    next_event(
        scene,
        &v,
        u_light,
        mis,
        ris,
        |wo| bxdf.pdf(wi, wo, lambdas[0]),
        |wo, is_delta| {
            glossy_cv::nee_bsdf(
                &**bxdf,
                wi,
                wo,
                is_delta,
                &lambdas[..n],
                &th.q[..n],
                residual,
            )
        },
        |ls, wo, w, fp| glossy(&mut xyz, wo, &fp, &ls.emission, w, residual.weight),
    );

    // The delta lobe's emission, as in `trace`.
    let delta_traced = std::mem::take(&mut th.delta_counted)
        || bxdf.uses_lobe_choice()
            && delta_emission(
                scene,
                bxdf,
                &v,
                lambdas,
                n,
                |j, e| out[j] += th.t[j] * e,
                bsdf_weight_over_pdf(mis.heuristic, 1.0, q_sum, 0.0),
            );

    // BSDF sampling at the hero wavelength.
    let Some(s) = bxdf.sample(wi, lambdas[0], u_bsdf) else {
        return done(out, xyz);
    };
    if s.pdf.is_nan() || s.pdf <= 0.0 || s.wo.z <= 0.0 {
        return done(out, xyz);
    }
    let Some(ray) = v.ray(s.wo) else {
        return done(out, xyz);
    };
    let next = scene.shapes.intersect(&ray, f64::INFINITY);
    if s.is_delta {
        th.t[0] *= s.weight;
        for j in 1..n {
            let sp = bxdf.specular(wi, lambdas[j]);
            th.t[j] *= sp.weight / s.pdf;
            th.q[j] *= sp.probability / s.pdf;
        }
        th.l_mis = [0.0; N];
        // Its emission is counted above, unless the lobe has none.
        if !delta_traced {
            reached_emission(scene, &ray, next.as_ref(), &mut th, lambdas, n, &mut out);
        }
    } else {
        let (em, pdf_l) = emission_at(lights, &ray, next.as_ref());
        let goes_on = settings.max_depth > 1
            && matches!(
                next,
                Some(Hit {
                    surface: Surface::Material(_),
                    ..
                })
            );
        // The other wavelengths' values only if something uses them: at
        // the last bounce of a direct-lighting render most samples escape.
        if matches!(em, Emission::None) && !goes_on {
            return done(out, xyz);
        }
        let mut fp = [(0.0, 0.0); N];
        bxdf.eval_pdf_many(wi, s.wo, &lambdas[..n], &mut fp[..n]);
        if !matches!(em, Emission::None) {
            let own: f64 = fp[..n].iter().map(|v| v.1).sum::<f64>() / s.pdf;
            let w = mis
                .at_infinity(next.is_none())
                .bsdf(pdf_l, own, q_sum / s.pdf);
            if w > 0.0 {
                glossy(&mut xyz, s.wo, &fp, &em, w / s.pdf, 1.0);
            }
        }
        for j in 0..n {
            th.t[j] *= fp[j].0 * s.wo.z / s.pdf;
            th.q[j] *= fp[j].1 / s.pdf;
            th.l_mis[j] = 1.0 / s.pdf;
        }
    }
    let Some(next) = next.filter(|h| matches!(h.surface, Surface::Material(_))) else {
        return done(out, xyz);
    };
    if settings.max_depth == 1 {
        return done(out, xyz);
    }
    if 1 >= settings.rr_depth && !survives(&mut th, n, roulette_scale(wavelengths), sampler) {
        return done(out, xyz);
    }
    let rest = trace(scene, ray, Some(next), wavelengths, sampler, th, 1);
    for j in 0..n {
        out[j] += rest[j];
    }
    done(out, xyz)
}

/// The emission a first vertex's delta lobe reflects along the mirror
/// direction, integrated over λ with the lobe's table `delta`
/// ([`SpectralTables::delta`]): the XYZ that `delta_emission` estimates
/// from the path's sampled wavelengths, and with weight 1 too, since no
/// other strategy reaches a delta direction.
///
/// Why: the lobe's weight R·e^{−g} changes with λ by orders of magnitude
/// (e^{−(4πσ cosθ/λ)²}: 8·10⁻⁵ at 400 nm and 0.05 at 700 nm for σ 0.138 µm
/// at 45°), and where the mirror direction meets a small light that
/// spike is the pixel: a few sampled wavelengths estimate it with large
/// colour noise, which was most of a full-GHS plate's error.
fn exact_delta(
    scene: &Scene,
    tables: &SpectralTables,
    delta: u32,
    hit: &Hit,
    ray: &Ray,
) -> [f64; 3] {
    let Some(v) = Vertex::new(hit, ray) else {
        return [0.0; 3];
    };
    let Some(mirror) = v.ray(brdf::frame::reflect_z(v.wi)) else {
        return [0.0; 3];
    };
    let next = scene.shapes.intersect(&mirror, f64::INFINITY);
    let (em, _) = emission_at(&scene.lights, &mirror, next.as_ref());
    if matches!(em, Emission::None) {
        return [0.0; 3];
    }
    let ci = v.wi.z.min(1.0);
    let xyz = tables.reflected(delta, ci * ci, 1.0, &em);
    // Where e^{−g} underflows (σ ≫ λ near normal incidence) the lobe's
    // integrals are ~10⁻⁷⁰ and the cubic interpolation's overshoot, within
    // the table's tolerance, can make them negative. The weight R·e^{−g}
    // is at most 1, reached at grazing, so the grazing value bounds every
    // channel: what is within the tolerance of it from zero is zero, and
    // the integral of a non-negative emission is not negative.
    let top = tables.reflected(delta, 0.0, 1.0, &em);
    std::array::from_fn(|c| {
        let v = xyz[c];
        if v.abs() <= crate::spectral_table::TOLERANCE * top[c].abs() {
            0.0
        } else if scene.signed_radiance {
            v
        } else {
            v.max(0.0)
        }
    })
}

/// Spectral radiance estimates (wavelength pdf included) along `ray` at each
/// λ_j from scattering event `depth0` on, with the path's state `th`
/// (for `depth0` = 0, [`Throughput::camera`]); `first` is `ray`'s hit,
/// already found.
fn trace(
    scene: &Scene,
    mut ray: Ray,
    first: Option<Hit>,
    wavelengths: &SampledWavelengths,
    sampler: &mut Sampler,
    // Updated in place: a local copy was a 496-byte memcpy per path.
    mut th: Throughput,
    depth0: u32,
) -> [f64; N] {
    let (lambdas, n) = (&wavelengths.lambda, wavelengths.n);
    let lights = &scene.lights;
    let settings = &scene.settings;
    let m0 = roulette_scale(wavelengths);
    let mut out = [0.0; N];

    // The last edge is a delta direction whose emission `delta_emission`
    // has already counted.
    let mut emission_counted = false;
    let mut first = Some(first);
    for depth in depth0..=settings.max_depth {
        let hit = match first.take() {
            Some(h) => h,
            None => scene.shapes.intersect(&ray, f64::INFINITY),
        };
        let Some(
            hit @ Hit {
                surface: Surface::Material(m),
                ..
            },
        ) = hit
        else {
            if !emission_counted {
                reached_emission(scene, &ray, hit.as_ref(), &mut th, lambdas, n, &mut out);
            }
            break;
        };
        if depth == settings.max_depth {
            break;
        }
        let Some(v) = Vertex::new(&hit, &ray) else {
            break;
        };
        let wi = v.wi;
        let cones = scene.casters.cones(m, v.p, |d| v.frame.to_local(d));
        let mut guided = None;
        let bxdf = Guided::over(&mut guided, &*scene.materials[m as usize].bxdf, cones);
        th.resolve(scene, lambdas, n);
        th.peak = lobe_peak(settings.mis_light_weight, bxdf, wi);
        let (u_light, u_bsdf) = vertex_draws(sampler, lights, bxdf);
        let ris = resampling(sampler, lights, th.peak);
        th.ris = ris.m;
        let mis = VertexMis::new(settings, th.peak, ris.m);
        let Throughput {
            t,
            q,
            delta_counted,
            ..
        } = &mut th;

        next_event(
            scene,
            &v,
            u_light,
            mis,
            ris,
            |wo| bxdf.pdf(wi, wo, lambdas[0]),
            |wo, is_delta| nee_bsdf(bxdf, wi, wo, is_delta, &lambdas[..n], &q[..n]),
            |ls, wo, w, fp| {
                let mut e = [0.0; N];
                ls.emission.eval_many(&lambdas[..n], &mut e[..n]);
                for j in 0..n {
                    out[j] += t[j] * fp[j].0 * wo.z * e[j] * w;
                }
            },
        );

        // The emission a delta lobe mixed with others reflects, traced
        // deterministically (see `delta_emission`) or already integrated
        // over λ (`exact_delta`); a delta direction the BSDF sample below
        // picks then counts no emission.
        let delta_traced = std::mem::take(delta_counted)
            || bxdf.uses_lobe_choice()
                && delta_emission(
                    scene,
                    bxdf,
                    &v,
                    lambdas,
                    n,
                    |j, e| {
                        out[j] += t[j] * e;
                    },
                    bsdf_weight_over_pdf(mis.heuristic, 1.0, q[..n].iter().sum(), 0.0),
                );

        if depth == 0 {
            let k = split::branches(scene, bxdf, wi);
            if k > 1 {
                let at = SampledSplit {
                    v: &v,
                    m,
                    bxdf,
                    cones,
                    delta_traced,
                    k,
                };
                sampled_split(scene, at, &th, wavelengths, sampler, &mut out);
                break;
            }
        }
        let Some((wo, is_delta)) = bsdf_step(&mut th, bxdf, m, wi, cones, lambdas, n, u_bsdf)
        else {
            break;
        };
        emission_counted = is_delta && delta_traced;
        if depth + 1 >= settings.rr_depth {
            th.resolve(scene, lambdas, n);
            if !survives(&mut th, n, m0, sampler) {
                break;
            }
        }
        let Some(next) = v.ray(wo) else {
            break;
        };
        ray = next;
    }
    out
}

/// BSDF sampling at the hero wavelength at vertex `v` of material `m`
/// (`bxdf`, guided by `cones` where it is), drawn with `u_bsdf`: updates
/// the path's state `th` and returns the direction and whether it is a
/// delta one, or `None` where the path ends.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn bsdf_step(
    th: &mut Throughput,
    bxdf: &dyn Bxdf,
    m: u32,
    wi: DVec3,
    cones: Option<Cones>,
    lambdas: &[f64; N],
    n: usize,
    u_bsdf: [f64; 3],
) -> Option<(DVec3, bool)> {
    let (s, kept) = bxdf.sample_kept(wi, lambdas[0], u_bsdf)?;
    if s.pdf.is_nan() || s.pdf <= 0.0 || s.wo.z <= 0.0 {
        return None;
    }
    let Throughput {
        t,
        q,
        l_mis,
        pending,
        ..
    } = th;
    if s.is_delta {
        t[0] *= s.weight;
        for j in 1..n {
            let sp = bxdf.specular(wi, lambdas[j]);
            t[j] *= sp.weight / s.pdf;
            q[j] *= sp.probability / s.pdf;
        }
        *l_mis = [0.0; N];
    } else {
        t[0] *= s.weight;
        for k in 0..n {
            l_mis[k] = q[k] / s.pdf;
        }
        *pending = Some(Pending {
            material: m,
            wi,
            wo: s.wo,
            pdf: s.pdf,
            guide: cones.map_or((1.0, 0.0), |c| {
                let (share, g) = c.weighted_pdf(s.wo);
                (1.0 - share, g)
            }),
            kept,
        });
    }
    Some((s.wo, s.is_delta))
}

/// Where a λ-exact path splits.
struct FlatSplit<'a, 'v> {
    tables: &'v SpectralTables,
    vertex: FlatVertex<'a>,
    v: &'v Vertex,
    cones: Option<Cones>,
    /// The camera sample's reserved wavelength draw.
    u_lambda: Reserved2d,
    k: u32,
}

/// A λ-exact path `path` split at its first vertex `at`.
fn flat_split<'a>(
    scene: &'a Scene,
    mut path: FlatPath<'a>,
    at: FlatSplit<'a, '_>,
    sampler: &mut Sampler,
) -> SampleRadiance {
    let FlatSplit {
        tables,
        vertex,
        v,
        cones,
        u_lambda,
        k,
    } = at;
    let mut guided = None;
    let bx = Guided::over(&mut guided, vertex.unit(), cones);
    // The light sample's draws are the camera sample's; its BSDF draw is
    // left unused (each branch draws its own).
    path.light(scene, tables, vertex, bx, v, sampler);
    // Resolved by the camera sample's own sampler, so that every branch
    // that needs wavelengths has the same ones.
    let u_lambda = Reserved2d::Drawn(sampler.reserved_2d(u_lambda));
    let mut total = SampleRadiance::Xyz(path.xyz);
    let share = FlatPath {
        tau: path.tau / f64::from(k),
        xyz: [0.0; 3],
        ..path
    };
    for b in 0..k {
        let mut sb = sampler.branch(b, k);
        let mut p = share.clone();
        let u_bsdf = sb.get_1d_2d_if(bx.uses_lobe_choice());
        let Some(ray) = p.sample(vertex, bx, v, u_bsdf) else {
            continue;
        };
        if 1 >= scene.settings.rr_depth && !p.survives(&mut sb) {
            continue;
        }
        let hit = scene.shapes.intersect(&ray, f64::INFINITY);
        let r = flat_walk(scene, tables, p, ray, hit, &mut sb, u_lambda, 1);
        total = split::sum(total, r);
    }
    total
}

/// Where a path with sampled wavelengths splits: its first vertex `v` of
/// material `m` (`bxdf`, guided by `cones` where it is), whether its delta
/// lobe's emission is counted already, and the branch count.
struct SampledSplit<'v> {
    v: &'v Vertex,
    m: u32,
    bxdf: &'v dyn Bxdf,
    cones: Option<Cones>,
    delta_traced: bool,
    k: u32,
}

/// The k BSDF continuations of a path with sampled wavelengths, whose
/// state after its first vertex's light sample is `th`, added to `out`.
fn sampled_split(
    scene: &Scene,
    at: SampledSplit,
    th: &Throughput,
    wavelengths: &SampledWavelengths,
    sampler: &Sampler,
    out: &mut [f64; N],
) {
    let (lambdas, n) = (&wavelengths.lambda, wavelengths.n);
    let k = at.k;
    let mut share = th.clone();
    for t in &mut share.t[..n] {
        *t /= f64::from(k);
    }
    let m0 = roulette_scale(wavelengths);
    for b in 0..k {
        let mut sb = sampler.branch(b, k);
        let mut tb = share.clone();
        let u_bsdf = sb.get_1d_2d_if(at.bxdf.uses_lobe_choice());
        let step = bsdf_step(
            &mut tb, at.bxdf, at.m, at.v.wi, at.cones, lambdas, n, u_bsdf,
        );
        let Some((wo, is_delta)) = step else {
            continue;
        };
        if 1 >= scene.settings.rr_depth {
            tb.resolve(scene, lambdas, n);
            if !survives(&mut tb, n, m0, &mut sb) {
                continue;
            }
        }
        let Some(ray) = at.v.ray(wo) else {
            continue;
        };
        match scene.shapes.intersect(&ray, f64::INFINITY) {
            Some(
                h @ Hit {
                    surface: Surface::Material(_),
                    ..
                },
            ) => {
                let r = trace(scene, ray, Some(h), wavelengths, &mut sb, tb, 1);
                for j in 0..n {
                    out[j] += r[j];
                }
            }
            // The emission a delta direction reaches is counted already
            // where its lobe's was traced.
            hit if !(is_delta && at.delta_traced) => {
                reached_emission(scene, &ray, hit.as_ref(), &mut tb, lambdas, n, out);
            }
            _ => {}
        }
    }
}

/// Adds the emission a BSDF-sampled edge of a path reaches along `ray` (at
/// `hit`, an emitter, or the environment as it escapes), weighted against
/// light sampling by the MIS of the vertex it left.
#[inline]
fn reached_emission(
    scene: &Scene,
    ray: &Ray,
    hit: Option<&Hit>,
    th: &mut Throughput,
    lambdas: &[f64; N],
    n: usize,
    out: &mut [f64; N],
) {
    let (em, pdf_l) = emission_at(&scene.lights, ray, hit);
    if matches!(em, Emission::None) {
        return;
    }
    th.resolve(scene, lambdas, n);
    let own: f64 = th.q[..n].iter().sum();
    let l_sum: f64 = th.l_mis[..n].iter().sum();
    let w = VertexMis::new(&scene.settings, th.peak, th.ris)
        .at_infinity(hit.is_none())
        .bsdf(pdf_l, own, l_sum);
    if w > 0.0 {
        let mut e = [0.0; N];
        em.eval_many(&lambdas[..n], &mut e[..n]);
        for j in 0..n {
            out[j] += th.t[j] * e[j] * w;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn narrow_lobes_resample_unless_every_light_is_a_point_or_sphere() {
        use crate::geometry::{Planar, Sphere, Transform};
        use crate::light::LightKind;
        use crate::scene::desc::SamplerKind;
        use crate::spectrum::Spectrum;
        // A 0.5 × 0.5 rectangle 1 above the vertex (density 4 sr⁻¹ at its
        // centre: a lobe just over the threshold peak is wider than it), and
        // a sphere light, alone or beside it (with several lights, the
        // narrowest counts).
        let xf = Transform::new([180.0, 0.0, 0.0], 1.0, [0.0, 0.0, 1.0]);
        let rect = || LightKind::Rectangle {
            shape: Planar::rectangle([0.5, 0.5], &xf),
            spectrum: Spectrum::Constant(1.0),
            two_sided: false,
        };
        let sphere = || LightKind::Sphere {
            sphere: Sphere {
                center: DVec3::new(3.0, 0.0, 2.0),
                radius: 0.1,
            },
            spectrum: Spectrum::Constant(1.0),
        };
        let m = |lights: Vec<LightKind>, peak: Option<f64>| {
            let lights = Lights {
                lights,
                environment: None,
                bsdf_only_environment: false,
            };
            let mut sampler = Sampler::new(SamplerKind::Sobol, 1, 2, 3);
            resampling(&mut sampler, &lights, peak).m
        };
        let rect_only = || vec![rect()];
        assert_eq!(m(rect_only(), Some(RIS_MIN_PEAK * 1.01)), RIS_CANDIDATES);
        assert_eq!(m(rect_only(), Some(0.5)), 1);
        assert_eq!(m(rect_only(), None), 1);
        assert_eq!(m(vec![sphere()], Some(1e6)), 1);
        assert_eq!(m(vec![rect(), sphere()], Some(1e6)), RIS_CANDIDATES);
        assert_eq!(m(vec![], Some(1e6)), 1);
    }

    #[test]
    fn light_and_bsdf_weights_sum_to_one_for_any_light_weight() {
        // The two strategies' weights of one direction, each recovered from
        // weight/density, for both heuristics, fixed and per-vertex light
        // weights, and densities over 24 decades.
        let mut rng = Rng::for_sample(1, 2, 3);
        for _ in 0..100_000 {
            let mut log = || 10f64.powf(24.0 * rng.uniform() - 12.0);
            let (p_light, p_bsdf, peak, fixed) = (log(), log(), log(), log());
            for mis in [MisHeuristic::Power, MisHeuristic::Balance] {
                for fixed in [Some(fixed), Some(1.0), None] {
                    for peak in [Some(peak), None] {
                        let c = light_weight(fixed, peak, p_light);
                        assert!(c > 0.0 && c.is_finite());
                        if fixed.is_none() {
                            assert!((1.0..=MAX_LIGHT_COUNT).contains(&c), "{c}");
                        }
                        let wl = light_weight_over_pdf(mis, c, p_light, p_bsdf) * p_light;
                        let wb = bsdf_weight_over_pdf(mis, c, p_bsdf, p_light) * p_bsdf;
                        assert!(
                            (wl + wb - 1.0).abs() < 1e-12,
                            "{mis:?} c {c}: {wl} + {wb} (p_light {p_light}, p_bsdf {p_bsdf})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_resampling_vertex_weighs_both_strategies_with_one_count() {
        // Both strategies read the candidate count from `VertexMis`: for a
        // light sample of density p_l and a one-wavelength BSDF sample of
        // density p_b toward the same direction the weights sum to one
        // (counted on one side only, they would not), and resampling from
        // 8 candidates hands the light strategy the larger share.
        let mut rng = Rng::for_sample(4, 5, 6);
        for _ in 0..20_000 {
            let mut log = || 10f64.powf(8.0 * rng.uniform() - 4.0);
            let (p_l, p_b, peak) = (log(), log(), log());
            let mut shares = [0.0; 2];
            for (share, m) in shares.iter_mut().zip([1, RIS_CANDIDATES]) {
                for far in [false, true] {
                    let mis = VertexMis {
                        heuristic: MisHeuristic::Power,
                        fixed: None,
                        peak: Some(peak),
                        ris: f64::from(m),
                    }
                    .at_infinity(far);
                    let wl = mis.light(p_l, 1.0, p_b) * p_l;
                    let wb = mis.bsdf(p_l, 1.0, 1.0 / p_b);
                    assert!((wl + wb - 1.0).abs() < 1e-12, "m {m}: {wl} + {wb}");
                    *share = wl;
                }
            }
            assert!(shares[1] >= shares[0], "{shares:?}");
        }
    }

    #[test]
    fn the_per_vertex_light_weight_follows_the_lobe_against_the_light() {
        // Three times while the lobe's peak density is ≤ 16/3 × the light's,
        // once from 16× on, in proportion between; textbook without a lobe
        // size, and for a NaN ratio; a fixed weight wins.
        assert_eq!(light_weight(None, Some(16.0 / 3.0), 1.0), 3.0);
        assert_eq!(light_weight(None, Some(1e-9), 1.0), 3.0);
        assert_eq!(light_weight(None, Some(8.0), 1.0), 2.0);
        assert_eq!(light_weight(None, Some(12.0), 1.0), 16.0 / 12.0);
        assert_eq!(light_weight(None, Some(16.0), 1.0), 1.0);
        assert_eq!(light_weight(None, Some(1e9), 1.0), 1.0);
        assert_eq!(light_weight(None, None, 1.0), 1.0);
        assert_eq!(light_weight(None, Some(f64::INFINITY), f64::INFINITY), 1.0);
        assert_eq!(light_weight(Some(0.3), Some(1.0), 1.0), 0.3);
    }
}
