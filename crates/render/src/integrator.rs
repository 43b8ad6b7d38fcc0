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

use crate::film::BadSample;
use crate::geometry::Ray;
use crate::light::Emission;
use crate::sampler::{Reserved2d, Sampler};
use crate::scene::desc::MisHeuristic;
use crate::scene::{Hit, Scene, Surface};
use crate::spectrum::Cie;
use crate::wavelength::{MAX_WAVELENGTHS, SampledWavelengths};
use brdf::frame::orthonormal_basis;
use glam::DVec3;

const N: usize = MAX_WAVELENGTHS;

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

/// A glossy BSDF sample whose other-wavelength factors are not yet applied.
struct Pending {
    material: u32,
    wi: DVec3,
    wo: DVec3,
    pdf: f64,
}

/// One camera sample: its wavelengths and spectral radiance estimates.
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// The wavelengths carried ([`Settings::wavelengths_per_path`](crate::scene::Settings::wavelengths_per_path))
    /// and their pdfs.
    pub wavelengths: SampledWavelengths,
    /// Radiance estimates at each wavelength, wavelength pdf included; the
    /// first `wavelengths.len()` are used.
    pub radiance: [f64; N],
}

/// Traces camera sample `sample` of pixel (`x`, `y`).
pub fn camera_sample(scene: &Scene, x: u32, y: u32, sample: u64) -> CameraSample {
    traced(scene, x, y, sample).unwrap_or_else(|| {
        // The ray escaped into no environment: zero at the wavelengths its
        // draws give.
        let (sampler, _, u_lambda) = camera_draws(scene, x, y, sample);
        CameraSample {
            wavelengths: scene.wavelengths.sample_set(
                sampler.reserved_2d(u_lambda),
                scene.settings.wavelengths_per_path(),
            ),
            radiance: [0.0; N],
        }
    })
}

/// A camera sample's first draws: its sampler, its camera ray, and the
/// reserved 2-D wavelength draw (the set's position and, jointly stratified
/// with it, which member is the hero).
#[inline]
fn camera_draws(scene: &Scene, x: u32, y: u32, sample: u64) -> (Sampler, Ray, Reserved2d) {
    let pixel = y as u64 * scene.camera.width as u64 + x as u64;
    let mut sampler = Sampler::new(scene.settings.sampler, scene.settings.seed, pixel, sample);
    let [ux, uy] = sampler.get_2d();
    let ray = scene.camera.ray(x as f64 + ux, y as f64 + uy);
    let u_lambda = sampler.reserve_2d();
    (sampler, ray, u_lambda)
}

/// Traces a camera sample; `None` if its ray escapes into no environment
/// (most of the misses around an object or a plate), which is zero at every
/// wavelength and returns before the wavelengths are drawn: their draw is
/// reserved, so every later draw is the same.
#[inline(always)]
fn traced(scene: &Scene, x: u32, y: u32, sample: u64) -> Option<CameraSample> {
    let (mut sampler, ray, u_lambda) = camera_draws(scene, x, y, sample);
    let first = scene.shapes.intersect(&ray, f64::INFINITY);
    if first.is_none() && !scene.lights.has_environment() {
        return None;
    }
    let wavelengths = scene.wavelengths.sample_set(
        sampler.reserved_2d(u_lambda),
        scene.settings.wavelengths_per_path(),
    );
    let radiance = trace(scene, ray, first, &wavelengths, &mut sampler);
    Some(CameraSample {
        wavelengths,
        radiance,
    })
}

/// XYZ estimate (before the film's 1/∫ȳ normalisation) of one camera sample
/// at pixel (`x`, `y`); zero where [`sample_pixel_checked`] rejects it.
pub fn sample_pixel(scene: &Scene, x: u32, y: u32, sample: u64) -> [f64; 3] {
    sample_pixel_checked(scene, x, y, sample).unwrap_or([0.0; 3])
}

/// XYZ estimate of one camera sample, or why it cannot be averaged: a
/// wavelength's radiance estimate is NaN, infinite, or negative in a scene
/// whose emission spectra are all non-negative (see
/// [`Scene::signed_radiance`](crate::Scene)). Either means a model
/// misbehaved; the render loop counts and reports such samples instead of
/// averaging them (one branch, never taken in a sound render).
#[inline]
pub fn sample_pixel_checked(
    scene: &Scene,
    x: u32,
    y: u32,
    sample: u64,
) -> Result<[f64; 3], BadSample> {
    let Some(cs) = traced(scene, x, y, sample) else {
        return Ok([0.0; 3]);
    };
    let n = cs.wavelengths.len();
    let r = &cs.radiance[..n];
    if !r.iter().all(|v| v.is_finite()) {
        return Err(BadSample::NonFinite);
    }
    if !scene.signed_radiance && !r.iter().all(|v| *v >= 0.0) {
        return Err(BadSample::Negative);
    }
    let cie = Cie::get();
    let mut xyz = [0.0; 3];
    for (j, &lambda) in cs.wavelengths.lambdas().iter().enumerate() {
        let c = cie.xyz(lambda);
        for k in 0..3 {
            xyz[k] += cs.radiance[j] * c[k];
        }
    }
    // Finite radiances can still overflow in the sum.
    if xyz.iter().all(|v| v.is_finite()) {
        Ok(xyz)
    } else {
        Err(BadSample::NonFinite)
    }
}

/// Spectral radiance estimates (wavelength pdf included) along `ray` at each
/// λ_j; `first` is the camera ray's hit, already found.
fn trace(
    scene: &Scene,
    mut ray: Ray,
    first: Option<Hit>,
    wavelengths: &SampledWavelengths,
    sampler: &mut Sampler,
) -> [f64; N] {
    let (lambdas, pl, n) = (&wavelengths.lambda, &wavelengths.pdf, wavelengths.n);
    let lights = &scene.lights;
    let settings = &scene.settings;
    let mut t = [0.0; N];
    let mut q = [0.0; N];
    let mut l_mis = [0.0; N];
    for k in 0..n {
        t[k] = 1.0 / pl[k];
        q[k] = 1.0;
    }
    // Russian roulette compares max_j T_j / Σ Q_k with its value at the camera.
    let m0 = t[..n].iter().fold(0.0f64, |a, &v| a.max(v)) / n as f64;
    let mis = settings.mis;
    let mut out = [0.0; N];

    // The other wavelengths' BSDF value and pdf for the direction just
    // sampled at the hero wavelength are needed only if the path goes on to
    // another vertex or reaches emission; a path that ends (it escapes into
    // no environment, or hits a surface at the last depth) skips them. At the
    // last bounce of a direct-lighting render that is most paths.
    let mut pending: Option<Pending> = None;
    let resolve = |pending: &mut Option<Pending>, t: &mut [f64; N], q: &mut [f64; N]| {
        if let Some(p) = pending.take() {
            let bxdf = &scene.materials[p.material as usize].bxdf;
            let mut fp = [(0.0, 0.0); N];
            bxdf.eval_pdf_many(p.wi, p.wo, &lambdas[1..n], &mut fp[1..n]);
            for j in 1..n {
                t[j] *= fp[j].0 * p.wo.z / p.pdf;
                q[j] *= fp[j].1 / p.pdf;
            }
        }
    };

    let add_emission = |out: &mut [f64; N],
                        t: &[f64; N],
                        q: &[f64; N],
                        l_mis: &[f64; N],
                        em: Emission,
                        pdf_l: f64| {
        if matches!(em, Emission::None) {
            return;
        }
        let own: f64 = q[..n].iter().sum();
        let other: f64 = l_mis[..n].iter().sum::<f64>() * pdf_l;
        let w = mis_over_pdf(mis, own, other);
        if w > 0.0 {
            let mut e = [0.0; N];
            em.eval_many(&lambdas[..n], &mut e[..n]);
            for j in 0..n {
                out[j] += t[j] * e[j] * w;
            }
        }
    };

    let mut first = Some(first);
    for depth in 0..=settings.max_depth {
        let hit = match first.take() {
            Some(h) => h,
            None => scene.shapes.intersect(&ray, f64::INFINITY),
        };
        let Some(hit) = hit else {
            let (em, pdf_l) = lights.environment(ray.d);
            if !matches!(em, Emission::None) {
                resolve(&mut pending, &mut t, &mut q);
                add_emission(&mut out, &t, &q, &l_mis, em, pdf_l);
            }
            break;
        };
        let m = match hit.surface {
            Surface::Emitter(i) => {
                let (em, pdf_l) = lights.emitted(i as usize, ray.o, ray.d, hit.geo.n, hit.geo.t);
                if !matches!(em, Emission::None) {
                    resolve(&mut pending, &mut t, &mut q);
                    add_emission(&mut out, &t, &q, &l_mis, em, pdf_l);
                }
                break;
            }
            Surface::Material(m) => m,
        };
        if depth == settings.max_depth {
            break;
        }
        let bxdf = &scene.materials[m as usize].bxdf;
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
        let frame = Frame::new(ns, hit.geo.tangent);
        let wi = frame.to_local(-ray.d);
        if wi.z <= 0.0 {
            break;
        }
        let p = offset(hit.geo.p, ng, hit.mesh);
        resolve(&mut pending, &mut t, &mut q);

        // Next-event estimation.
        if let Some(ls) = lights.sample(p, sampler.get_1d_2d()) {
            let wo = frame.to_local(ls.wi);
            if wo.z > 0.0 && ls.pdf > 0.0 && (!smooth || ls.wi.dot(ng) > 0.0) {
                let shadow = Ray { o: p, d: ls.wi };
                let t_max = if ls.dist.is_finite() {
                    ls.dist * (1.0 - 1e-7)
                } else {
                    f64::INFINITY
                };
                // A delta light cannot be reached by BSDF sampling: its MIS
                // denominator has no BSDF term, so the pdf is not needed.
                let mut fp = [(0.0, 0.0); N];
                bxdf.eval_pdf_many(wi, wo, &lambdas[..n], &mut fp[..n]);
                if ls.is_delta {
                    for v in &mut fp[..n] {
                        v.1 = 0.0;
                    }
                }
                if fp[..n].iter().any(|v| v.0 > 0.0) && !scene.shapes.occluded(&shadow, t_max) {
                    let own: f64 = q[..n].iter().sum::<f64>() * ls.pdf;
                    let other: f64 = (0..n).map(|k| q[k] * fp[k].1).sum();
                    let w = mis_over_pdf(mis, own, other);
                    if w > 0.0 {
                        let mut e = [0.0; N];
                        ls.emission.eval_many(&lambdas[..n], &mut e[..n]);
                        for j in 0..n {
                            out[j] += t[j] * fp[j].0 * wo.z * e[j] * w;
                        }
                    }
                }
            }
        }

        // BSDF sampling at the hero wavelength.
        let Some(s) = bxdf.sample(wi, lambdas[0], sampler.get_1d_2d()) else {
            break;
        };
        if s.pdf.is_nan() || s.pdf <= 0.0 || s.wo.z <= 0.0 {
            break;
        }
        if s.is_delta {
            t[0] *= s.weight;
            for j in 1..n {
                let sp = bxdf.specular(wi, lambdas[j]);
                t[j] *= sp.weight / s.pdf;
                q[j] *= sp.probability / s.pdf;
            }
            l_mis = [0.0; N];
        } else {
            t[0] *= s.weight;
            for k in 0..n {
                l_mis[k] = q[k] / s.pdf;
            }
            pending = Some(Pending {
                material: m,
                wi,
                wo: s.wo,
                pdf: s.pdf,
            });
        }

        // Russian roulette on the hero-symmetric throughput T_j / Σ Q_k.
        if depth + 1 >= settings.rr_depth {
            resolve(&mut pending, &mut t, &mut q);
            let sum_q: f64 = q[..n].iter().sum();
            let m = t[..n].iter().fold(0.0f64, |a, v| a.max(v.abs())) / (sum_q * m0);
            let survive = m.min(1.0);
            if survive.is_nan() || survive <= 0.0 || sampler.get_1d() >= survive {
                break;
            }
            for tj in t.iter_mut().take(n) {
                *tj /= survive;
            }
        }
        let d = frame.to_world(s.wo).normalize();
        if smooth && d.dot(ng) <= 0.0 {
            break;
        }
        ray = Ray { o: p, d };
    }
    out
}
