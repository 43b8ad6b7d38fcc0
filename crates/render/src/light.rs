//! Lights: point, sphere and rectangle emitters, constant, EXR and daylight-sky environments.

pub use crate::env_lift::RgbLift;
pub use crate::env_map::EnvMap;
use crate::geometry::{Planar, Ray, Sphere};
use crate::shapes::Surface;
use crate::sky::Sky;
use crate::spectrum::{Cie, LAMBDA_MAX, LAMBDA_MIN, Spectrum};
use glam::DVec3;
use std::f64::consts::PI;

/// Spectral radiance (or intensity) of one emission event.
#[derive(Clone, Copy, Debug)]
pub enum Emission<'a> {
    /// A spectrum times a scale, emitted by light number `.2` (whose
    /// spectrum it is: the integrator's spectral tables are indexed by it).
    Spectrum(&'a Spectrum, f64, u32),
    /// `c · (x̄, ȳ, z̄)(λ)`: an RGB texel lifted to a spectrum (see [`RgbLift`]).
    Cmf([f64; 3]),
    /// Daylight: coefficients on the sky's basis (S0, S1, S2, sun); see [`Sky::coefficients`].
    Sky(&'a Sky, [f64; 4]),
    /// Nothing.
    None,
}

impl Emission<'_> {
    /// Value at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f64) -> f64 {
        match *self {
            Emission::Spectrum(s, k, _) => k * s.eval(lambda),
            Emission::Cmf(c) => {
                let m = Cie::get().xyz(lambda);
                c[0] * m[0] + c[1] * m[1] + c[2] * m[2]
            }
            Emission::Sky(sky, c) => sky.spectral(&c, lambda),
            Emission::None => 0.0,
        }
    }

    /// [`eval`](Self::eval) at each of `lambdas` into `out` (as many as the
    /// shorter of the two), bit-identical to it: the kind of emission is
    /// matched once for the whole set rather than per wavelength.
    #[inline]
    pub fn eval_many(&self, lambdas: &[f64], out: &mut [f64]) {
        let pairs = out.iter_mut().zip(lambdas);
        match *self {
            Emission::Spectrum(s, k, _) => {
                s.eval_many(lambdas, out);
                out.iter_mut().take(lambdas.len()).for_each(|o| *o *= k);
            }
            Emission::Cmf(c) => {
                let cie = Cie::get();
                for (o, &l) in pairs {
                    let m = cie.xyz(l);
                    *o = c[0] * m[0] + c[1] * m[1] + c[2] * m[2];
                }
            }
            Emission::Sky(sky, c) => {
                for (o, &l) in pairs {
                    *o = sky.spectral(&c, l);
                }
            }
            Emission::None => {
                for (o, _) in pairs {
                    *o = 0.0;
                }
            }
        }
    }
}

/// An environment: constant radiance, an equirectangular map or a daylight sky.
// A scene holds one environment: the map's inline tables cost nothing, and a
// box would put one more load on every escaping ray's lookup.
#[allow(clippy::large_enum_variant)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Spectrum),
    /// A lat-long map of CMF coefficients, importance-sampled by luminance.
    Map(EnvMap),
    /// The analytic Preetham sky with its sun disk and ground (`sky.rs`).
    Sky(Box<Sky>),
}

/// What a light is.
pub enum LightKind {
    /// Point light with intensity spectrum.
    Point {
        /// Position.
        position: DVec3,
        /// Intensity.
        spectrum: Spectrum,
    },
    /// Spherical emitter.
    Sphere {
        /// Geometry.
        sphere: Sphere,
        /// Radiance.
        spectrum: Spectrum,
    },
    /// Rectangular emitter.
    Rectangle {
        /// Geometry.
        shape: Planar,
        /// Radiance.
        spectrum: Spectrum,
        /// Emits from both sides.
        two_sided: bool,
    },
    /// Environment.
    Environment(Environment),
}

/// One light sample seen from a shading point.
pub struct LightSample<'a> {
    /// Unit direction toward the light.
    pub wi: DVec3,
    /// Distance to the emitting point (infinite for environments).
    pub dist: f64,
    /// Solid-angle pdf including light selection; for delta lights, the selection probability.
    pub pdf: f64,
    /// Point light (cannot be hit by BSDF sampling).
    pub is_delta: bool,
    /// Emitted radiance (intensity / d² for point lights).
    pub emission: Emission<'a>,
    /// The emitting shape, for an area light: the sampled point is the
    /// nearest point of that shape along `wi`, so the shape cannot shadow it.
    pub shape: Option<Surface>,
}

/// A light sample's direction, distance and density without its emission:
/// a resampling candidate ([`Lights::direction`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Direction {
    /// Unit direction toward the light.
    pub wi: DVec3,
    /// Distance to the emitting point.
    pub dist: f64,
    /// Solid-angle pdf including light selection (a point light's: its
    /// selection probability).
    pub pdf: f64,
}

/// The scene's lights with uniform light selection.
pub struct Lights {
    /// All lights; emitting shapes refer to them by index.
    pub lights: Vec<LightKind>,
    /// Index of the environment, if any.
    pub environment: Option<usize>,
    /// A constant environment is left to BSDF sampling alone: next-event
    /// estimation chooses among the other lights only, and a BSDF-sampled
    /// ray that escapes to it has MIS weight 1 (its light pdf is 0). Uniform
    /// directions know nothing a constant environment could add, while
    /// visible-normal sampling of a microfacet conductor weighs each
    /// direction by F·G2/G1 ≤ 1, so the light strategy only adds variance
    /// (pbrt-v4 drops it for the same reason when allowed an incomplete
    /// pdf); cosine sampling of a Lambertian surface weighs each direction
    /// by ρ, constant. Sound only where every material's sampling covers
    /// its whole lobe, so the scene sets it only when every material is a
    /// microfacet or smooth conductor, diffuse or roughplastic.
    pub bsdf_only_environment: bool,
}

/// 1 − cosθmax of the cone `sphere` subtends from a point at squared
/// distance `d2` from its centre, written without cancellation; `None` from
/// inside the sphere, where it fills every direction.
#[inline]
pub(crate) fn cone_one_minus_cos(d2: f64, r2: f64) -> Option<f64> {
    if d2 <= r2 {
        return None;
    }
    let cos_max = (1.0 - r2 / d2).max(0.0).sqrt();
    Some((r2 / d2) / (1.0 + cos_max))
}

/// Distance from a point at distance `d` from the centre of a sphere of
/// radius `r` < `d` to the sphere's near side along a direction at angle θ
/// from the centre (`cos_t`, `sin2` = sin²θ, inside the sphere's cone): the
/// near root of t² − 2dt cosθ + d² − r² = 0, as (d − r)(d + r) / (d cosθ +
/// √(r² − d² sin²θ)), which cancels neither for far spheres nor at the
/// cone's edge (where the discriminant, 0 up to round-off, is clamped: the
/// tangent distance). Known from the draw, it needs no ray–sphere test.
#[inline]
fn sphere_near_distance(d: f64, r: f64, cos_t: f64, sin2: f64) -> f64 {
    let disc = (r * r - d * d * sin2).max(0.0);
    (d - r) * (d + r) / (d * cos_t + disc.sqrt())
}

/// A direction uniform in the cone of 1 − cosθmax = `one_minus` about unit
/// `w`, and its 1 − cosθ, through the concentric disk: the disk's r² is
/// uniform, so 1 − cosθ = r²(1 − cosθmax), and sinθ = r √((1 − cosθmax)(2 −
/// r²(1 − cosθmax))) scales the disk point itself (no azimuth, no
/// division). The strata of a low-discrepancy draw stay compact in the
/// cone, where the polar map made thin wedges.
#[inline]
pub(crate) fn sample_cone(w: DVec3, one_minus: f64, uv: [f64; 2]) -> (DVec3, f64) {
    let [x, y] = brdf::numerics::warp::concentric_disk(uv);
    let h = (x * x + y * y) * one_minus;
    let scale = (one_minus * (2.0 - h)).max(0.0).sqrt();
    let (t, b) = frame(w);
    // Unit by construction: scale²(x² + y²) + cos²θ = h(2 − h) + (1 − h)²
    // = 1, so no normalisation (a square root and a division on the
    // sample's critical path); what is left is round-off, checked to 1e−15
    // in `sphere_light_samples_are_uniform_in_its_cone`.
    (scale * x * t + scale * y * b + (1.0 - h) * w, h)
}

/// Solid-angle pdf of a direction drawn uniformly in that cone (uniformly
/// over the sphere of directions from inside).
pub(crate) fn cone_pdf(one_minus_cos: Option<f64>) -> f64 {
    one_minus_cos.map_or(1.0 / (4.0 * PI), |om| 1.0 / (2.0 * PI * om))
}

fn sphere_cone_pdf(sphere: &Sphere, p: DVec3) -> f64 {
    let d2 = (sphere.center - p).length_squared();
    cone_pdf(cone_one_minus_cos(d2, sphere.radius * sphere.radius))
}

fn frame(n: DVec3) -> (DVec3, DVec3) {
    brdf::frame::orthonormal_basis(n)
}

impl Lights {
    /// Number of lights.
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// Whether there are no lights.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// The environment index when [`Lights::bsdf_only_environment`] keeps
    /// it out of next-event estimation.
    fn skipped(&self) -> Option<usize> {
        self.environment.filter(|_| self.bsdf_only_environment)
    }

    /// Number of lights next-event estimation chooses among.
    pub fn nee_len(&self) -> usize {
        self.lights.len() - usize::from(self.skipped().is_some())
    }

    fn select_pdf(&self) -> f64 {
        1.0 / self.nee_len() as f64
    }

    /// Samples a light and a direction toward it from `p`: `u[0]` chooses
    /// the light (and is not read when there is one), `u[1..]` the point.
    #[inline]
    pub fn sample(&self, p: DVec3, u: [f64; 3]) -> Option<LightSample<'_>> {
        let idx = self.choose(u[0])?;
        self.sample_from(idx, p, [u[1], u[2]])
    }

    /// The light next-event estimation's number `u0` chooses: its index.
    #[inline]
    pub(crate) fn choose(&self, u0: f64) -> Option<usize> {
        let n = self.nee_len();
        if n == 0 {
            return None;
        }
        let mut idx = ((u0 * n as f64) as usize).min(n - 1);
        if self.skipped().is_some_and(|e| idx >= e) {
            idx += 1;
        }
        Some(idx)
    }

    /// Whether [`Lights::direction`] draws from light `idx`: every emitter
    /// at a finite distance, not an environment.
    #[inline]
    pub(crate) fn has_direction(&self, idx: usize) -> bool {
        !matches!(self.lights[idx], LightKind::Environment(_))
    }

    /// The direction part of [`Lights::sample_from`] for a light at a finite
    /// distance (`None` for an environment): what a resampling candidate
    /// reads, its emission left to [`Lights::finish`] for the one picked.
    #[inline]
    pub(crate) fn direction(&self, idx: usize, p: DVec3, uv: [f64; 2]) -> Option<Direction> {
        let sel = self.select_pdf();
        match &self.lights[idx] {
            LightKind::Point { position, .. } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let dist = dist2.sqrt();
                Some(Direction {
                    wi: d / dist,
                    dist,
                    pdf: sel,
                })
            }
            LightKind::Sphere { sphere, .. } => {
                let to_c = sphere.center - p;
                let d2 = to_c.length_squared();
                let r2 = sphere.radius * sphere.radius;
                // One 1 − cosθmax for the draw and its pdf, the same
                // expression `sphere_cone_pdf` gives a BSDF-sampled hit.
                let cone = cone_one_minus_cos(d2, r2);
                let (wi, dist) = if let Some(one_minus) = cone {
                    let d = d2.sqrt();
                    let (wi, h) = sample_cone(to_c / d, one_minus, uv);
                    (
                        wi,
                        sphere_near_distance(d, sphere.radius, 1.0 - h, h * (2.0 - h)),
                    )
                } else {
                    let wi = uniform_sphere(uv);
                    let ray = Ray { o: p, d: wi };
                    // Inside the sphere: the far side; round-off can miss it
                    // only at a point on the surface, where 0 is the distance.
                    let dist = sphere.hit_distance(&ray, 0.0, f64::INFINITY).unwrap_or(0.0);
                    (wi, dist)
                };
                Some(Direction {
                    wi,
                    dist,
                    pdf: sel * cone_pdf(cone),
                })
            }
            LightKind::Rectangle {
                shape, two_sided, ..
            } => {
                let q = shape.sample_point(uv);
                let d = q - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                if dist <= 0.0 {
                    return None;
                }
                let wi = d / dist;
                let cos_l = -wi.dot(shape.n);
                if cos_l <= 0.0 && !two_sided {
                    return None;
                }
                Some(Direction {
                    wi,
                    dist,
                    pdf: sel * dist2 / (shape.area() * cos_l.abs()),
                })
            }
            LightKind::Environment(_) => None,
        }
    }

    /// The light sample of direction `d` drawn from light `idx` by
    /// [`Lights::direction`]: its emission and shape added.
    #[inline]
    pub(crate) fn finish(&self, idx: usize, d: Direction) -> LightSample<'_> {
        let (is_delta, emission, shape) = match &self.lights[idx] {
            LightKind::Point { spectrum, .. } => (
                true,
                Emission::Spectrum(spectrum, 1.0 / (d.dist * d.dist), idx as u32),
                None,
            ),
            LightKind::Sphere { spectrum, .. } | LightKind::Rectangle { spectrum, .. } => (
                false,
                Emission::Spectrum(spectrum, 1.0, idx as u32),
                Some(Surface::Emitter(idx as u32)),
            ),
            LightKind::Environment(_) => (false, Emission::None, None),
        };
        LightSample {
            wi: d.wi,
            dist: d.dist,
            pdf: d.pdf,
            is_delta,
            emission,
            shape,
        }
    }

    /// [`Lights::sample`] from light `idx` with the point's numbers `uv`.
    pub(crate) fn sample_from(
        &self,
        idx: usize,
        p: DVec3,
        uv: [f64; 2],
    ) -> Option<LightSample<'_>> {
        let sel = self.select_pdf();
        match &self.lights[idx] {
            LightKind::Point { .. } | LightKind::Sphere { .. } | LightKind::Rectangle { .. } => {
                Some(self.finish(idx, self.direction(idx, p, uv)?))
            }
            LightKind::Environment(env) => {
                let (wi, pdf, emission) = match env {
                    Environment::Constant(s) => (
                        uniform_sphere(uv),
                        1.0 / (4.0 * PI),
                        Emission::Spectrum(s, 1.0, idx as u32),
                    ),
                    Environment::Map(m) => {
                        let (wi, pdf, c) = m.sample(uv)?;
                        (wi, pdf, Emission::Cmf(c))
                    }
                    Environment::Sky(sky) => {
                        let (wi, pdf, c) = sky.sample(uv)?;
                        (wi, pdf, Emission::Sky(sky, c))
                    }
                };
                (pdf > 0.0).then_some(LightSample {
                    wi,
                    dist: f64::INFINITY,
                    pdf: sel * pdf,
                    is_delta: false,
                    emission,
                    shape: None,
                })
            }
        }
    }

    /// Whether a narrow lobe may resample its light sample: some light that
    /// next-event estimation draws from is a rectangle or an environment.
    /// Points and spheres never resample (a point's draws are one
    /// direction), and with them a scene whose lights are all points and
    /// spheres; a property of the scene, not of the vertex.
    ///
    /// A sphere counts as a point: its draws are already uniform in the cone
    /// it subtends, and resampling them measured a loss (GGX α 0.05 gold
    /// under a sphere 23° wide, `ggx_au_30deg_wide_light`, 64 spp: relRMSE
    /// 0.0341 → 0.0299 for 3.3× the CPU, 0.0344 for 1.7× with resampling
    /// only where the lobe's peak is ≤ 4× the light's density, a band that
    /// took `softbox_object` from 0.087 back to 0.096–0.099). A rectangle or
    /// environment among other lights is enough: the light choice is shared
    /// by all candidates, so the candidates of a point or sphere chosen there
    /// cost their draws and nothing else.
    pub fn resamples(&self) -> bool {
        let skipped = self.skipped();
        self.lights.iter().enumerate().any(|(i, light)| {
            Some(i) != skipped
                && matches!(
                    light,
                    LightKind::Rectangle { .. } | LightKind::Environment(_)
                )
        })
    }

    /// Radiance leaving emitter `idx` toward `-dir` at a hit with geometric normal `n`,
    /// and the pdf with which [`Lights::sample`] from `from` would have chosen that point.
    pub fn emitted(
        &self,
        idx: usize,
        from: DVec3,
        dir: DVec3,
        n: DVec3,
        dist: f64,
    ) -> (Emission<'_>, f64) {
        let sel = self.select_pdf();
        match &self.lights[idx] {
            LightKind::Sphere { sphere, spectrum } => (
                Emission::Spectrum(spectrum, 1.0, idx as u32),
                sel * sphere_cone_pdf(sphere, from),
            ),
            LightKind::Rectangle {
                shape,
                spectrum,
                two_sided,
            } => {
                let cos_l = -dir.dot(n);
                if cos_l <= 0.0 && !two_sided {
                    return (Emission::None, 0.0);
                }
                let pdf = sel * dist * dist / (shape.area() * cos_l.abs().max(1e-300));
                (Emission::Spectrum(spectrum, 1.0, idx as u32), pdf)
            }
            LightKind::Point { .. } | LightKind::Environment(_) => (Emission::None, 0.0),
        }
    }

    /// Whether the scene has an environment light (rays that escape see it).
    #[inline]
    pub fn has_environment(&self) -> bool {
        self.environment.is_some()
    }

    /// Environment radiance along `dir` (escaping rays) and its sampling pdf.
    #[inline]
    pub fn environment(&self, dir: DVec3) -> (Emission<'_>, f64) {
        let Some(i) = self.environment else {
            return (Emission::None, 0.0);
        };
        let sel = self.select_pdf();
        match &self.lights[i] {
            // Left to BSDF sampling, next-event estimation never draws it.
            LightKind::Environment(Environment::Constant(s)) => {
                let pdf = if self.bsdf_only_environment {
                    0.0
                } else {
                    sel / (4.0 * PI)
                };
                (Emission::Spectrum(s, 1.0, i as u32), pdf)
            }
            LightKind::Environment(Environment::Map(m)) => {
                let (c, pdf) = m.eval(dir);
                (Emission::Cmf(c), sel * pdf)
            }
            LightKind::Environment(Environment::Sky(sky)) => (
                Emission::Sky(sky, sky.coefficients(dir)),
                sel * sky.pdf(dir),
            ),
            _ => (Emission::None, 0.0),
        }
    }

    /// The union of the lights' emission ranges within 360–830 nm.
    pub fn emission_range(&self) -> Option<(f64, f64)> {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for l in &self.lights {
            let s = match l {
                LightKind::Point { spectrum, .. }
                | LightKind::Sphere { spectrum, .. }
                | LightKind::Rectangle { spectrum, .. }
                | LightKind::Environment(Environment::Constant(spectrum)) => spectrum.support(),
                LightKind::Environment(Environment::Map(_) | Environment::Sky(_)) => {
                    Some((LAMBDA_MIN, LAMBDA_MAX))
                }
            };
            if let Some((a, b)) = s {
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        (lo < hi).then_some((lo, hi))
    }
}

/// Uniform direction on the unit sphere.
pub fn uniform_sphere(u: [f64; 2]) -> DVec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{SRGB_TO_XYZ, mul};

    #[test]
    fn eval_many_is_eval_at_each_wavelength_for_every_kind() {
        let constant = Spectrum::Constant(2.5);
        let black = Spectrum::Blackbody {
            kelvin: 3200.0,
            scale: 1e-9,
        };
        let table = crate::spectrum::d65();
        let sky = Sky::new(crate::sky::SkyParams::default()).unwrap();
        let c = sky.coefficients(DVec3::new(0.3, 0.2, 0.9).normalize());
        let kinds = [
            Emission::Spectrum(&constant, 0.7, 0),
            Emission::Spectrum(&black, 3.0, 1),
            Emission::Spectrum(&table, 1.5, 2),
            Emission::Cmf([0.4, -0.1, 0.9]),
            Emission::Sky(&sky, c),
            Emission::None,
        ];
        // Inside, at the ends of, and outside the rendered range; odd length.
        let lambdas = [359.0, 360.0, 412.3, 555.5, 700.25, 830.0, 831.0];
        for em in kinds {
            let mut out = [-1.0; 8];
            em.eval_many(&lambdas, &mut out);
            for (o, &l) in out.iter().zip(&lambdas) {
                assert_eq!(o.to_bits(), em.eval(l).to_bits(), "{em:?} at {l}");
            }
            assert_eq!(out[7], -1.0);
        }
    }

    #[test]
    fn rgb_lift_reproduces_xyz() {
        let lift = RgbLift::new();
        let cie = Cie::get();
        for rgb in [[1.0, 1.0, 1.0], [0.8, 0.2, 0.1], [0.0, 0.0, 1.0]] {
            let c = lift.coefficients(rgb);
            let e = Emission::Cmf(c);
            let mut xyz = [0.0; 3];
            for i in 0..=470 {
                let l = 360.0 + i as f64;
                let w = if i == 0 || i == 470 { 0.5 } else { 1.0 };
                let m = cie.xyz(l);
                for k in 0..3 {
                    xyz[k] += w * e.eval(l) * m[k] / cie.y_integral();
                }
            }
            let want = mul(&SRGB_TO_XYZ, rgb);
            for k in 0..3 {
                assert!(
                    (xyz[k] - want[k]).abs() < 1e-9,
                    "{rgb:?}: {xyz:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn sphere_cone_pdf_integrates_to_one() {
        // Monte Carlo over the cone: E[1/pdf] = solid angle; compare with 2π(1 − cosθmax).
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, 5.0),
            radius: 1.0,
        };
        let pdf = sphere_cone_pdf(&s, DVec3::ZERO);
        let cos_max = (1.0f64 - 1.0 / 25.0).sqrt();
        assert!((1.0 / pdf - 2.0 * PI * (1.0 - cos_max)).abs() < 1e-12);
        let lights = one_sphere(s.center, s.radius);
        for i in 0..100 {
            let ls = lights
                .sample(
                    DVec3::ZERO,
                    [0.0, i as f64 / 100.0, (i * 31 % 100) as f64 / 100.0],
                )
                .unwrap();
            assert!(ls.wi.z >= cos_max - 1e-9 && (ls.dist - 4.0).abs() < 1.0 + 1e-9);
        }
    }

    /// A scene's lights: one sphere of unit constant radiance.
    fn one_sphere(center: DVec3, radius: f64) -> Lights {
        Lights {
            lights: vec![LightKind::Sphere {
                sphere: Sphere { center, radius },
                spectrum: Spectrum::Constant(1.0),
            }],
            environment: None,
            bsdf_only_environment: false,
        }
    }

    #[test]
    fn sphere_light_sample_distances_reach_the_near_side() {
        // The distance from the draw against the ray–sphere test of the
        // sampled ray, and the point it gives on the sphere, for spheres
        // from 1e−4 to 1e4 radii away and 1e−9 of a radius off the surface,
        // over the whole cone (u on a grid with the disk's edge).
        let mut worst = 0.0f64;
        for (dist, radius) in [
            (1.2, 1.0),
            (5.0, 1.0),
            (1.0, 0.03),
            (1e4, 1.0),
            (1.0 + 1e-9, 1.0),
            (2.0, 1e-4),
        ] {
            let dir = DVec3::new(0.3, -0.5, 0.8).normalize();
            let p = DVec3::new(0.1, 0.2, -0.3);
            let center = p + dir * dist;
            let lights = one_sphere(center, radius);
            let sphere = Sphere { center, radius };
            for i in 0..=64 {
                for j in 0..=64 {
                    let u = [0.5, i as f64 / 64.0, j as f64 / 64.0];
                    let ls = lights.sample(p, u).unwrap();
                    let on = p + ls.dist * ls.wi;
                    // Radial residual: along the ray the distance is
                    // ill-conditioned at the cone's edge (tangent rays), but
                    // the point stays on the sphere.
                    let radial = ((on - center).length() - radius).abs();
                    assert!(
                        radial <= 1e-12 * (dist + radius),
                        "d {dist} r {radius} u {u:?}: {radial:e}"
                    );
                    let ray = Ray { o: p, d: ls.wi };
                    if let Some(t) = sphere.hit_distance(&ray, 0.0, f64::INFINITY) {
                        let rel = (t - ls.dist).abs() / t;
                        // Away from the edge both are well conditioned.
                        if i % 64 != 0 && j % 64 != 0 {
                            assert!(
                                rel <= 1e-9,
                                "d {dist} r {radius} u {u:?}: {} vs {t}",
                                ls.dist
                            );
                            worst = worst.max(rel);
                        }
                    }
                }
            }
        }
        assert!(
            worst > 0.0,
            "the distances never differ: nothing was compared"
        );
    }

    #[test]
    fn sphere_light_samples_are_uniform_in_its_cone() {
        // Chi-square of the sampled directions against the uniform density
        // in the cone (what `sphere_cone_pdf` claims): 10 bins of equal
        // solid angle in 1 − cosθ × 12 azimuth bins, from wide cones to
        // one of half-angle 1e−4, seen off-axis so the frame is general.
        let mut rng = brdf::numerics::splitmix::SplitMix64::new(17);
        for (dist, radius) in [(1.2, 1.0), (5.0, 1.0), (1.0, 0.03), (1e4, 1.0)] {
            let dir = DVec3::new(0.3, -0.5, 0.8).normalize();
            let center = dir * dist;
            let lights = one_sphere(center, radius);
            let r2d2 = (radius / dist) * (radius / dist);
            let one_minus = r2d2 / (1.0 + (1.0 - r2d2).sqrt());
            let (t, b) = frame(dir);
            let (rings, sectors, n) = (10usize, 12usize, 120_000usize);
            let mut counts = vec![0u32; rings * sectors];
            for _ in 0..n {
                let u = [rng.uniform(), rng.uniform(), rng.uniform()];
                let ls = lights.sample(DVec3::ZERO, u).unwrap();
                assert!(
                    (ls.wi.length() - 1.0).abs() < 1e-15,
                    "|wi| = {}",
                    ls.wi.length()
                );
                assert!((ls.pdf * 2.0 * PI * one_minus - 1.0).abs() < 1e-9);
                // 1 − cosθ from the perpendicular part: no cancellation.
                let perp = (ls.wi - ls.wi.dot(dir) * dir).length_squared();
                let h = perp / (1.0 + ls.wi.dot(dir));
                let ring = ((h / one_minus) * rings as f64) as usize;
                assert!(ring <= rings, "outside the cone: {h} > {one_minus}");
                let phi = ls.wi.dot(b).atan2(ls.wi.dot(t)) + PI;
                let sector = (phi / (2.0 * PI) * sectors as f64) as usize;
                counts[ring.min(rings - 1) * sectors + sector.min(sectors - 1)] += 1;
            }
            let want = n as f64 / (rings * sectors) as f64;
            let chi2: f64 = counts
                .iter()
                .map(|&c| (c as f64 - want).powi(2) / want)
                .sum();
            // 119 degrees of freedom: P(χ² > 185) ≈ 1e−4.
            assert!(chi2 < 185.0, "d = {dist}, r = {radius}: χ² = {chi2}");
        }
    }

    #[test]
    fn lights_resample_unless_all_points_and_spheres() {
        // An environment among the lights resamples, points and spheres
        // alone never, a rectangle beside them does, and a BSDF-only
        // environment counts not at all.
        let sphere = || LightKind::Sphere {
            sphere: Sphere {
                center: DVec3::new(0.0, 0.0, 5.0),
                radius: 1.0,
            },
            spectrum: Spectrum::Constant(1.0),
        };
        let point = || LightKind::Point {
            position: DVec3::new(0.0, 3.0, 0.0),
            spectrum: Spectrum::Constant(1.0),
        };
        let env = || LightKind::Environment(Environment::Constant(Spectrum::Constant(1.0)));
        let xf = crate::geometry::Transform::new([180.0, 0.0, 0.0], 1.0, [0.0, 0.0, 2.0]);
        let rect = || LightKind::Rectangle {
            shape: Planar::rectangle([1.0, 0.5], &xf),
            spectrum: Spectrum::Constant(1.0),
            two_sided: false,
        };
        let of = |lights: Vec<LightKind>, environment: Option<usize>, bsdf_only: bool| {
            Lights {
                lights,
                environment,
                bsdf_only_environment: bsdf_only,
            }
            .resamples()
        };
        assert!(!of(vec![sphere(), point()], None, false));
        assert!(of(vec![sphere(), env()], Some(1), false));
        assert!(!of(vec![sphere(), env()], Some(1), true));
        assert!(of(vec![point(), rect()], None, false));
        assert!(of(vec![rect(), env()], Some(1), false));
        assert!(of(vec![rect(), env()], Some(1), true));
        assert!(!of(vec![], None, false));
    }

    #[test]
    fn a_bsdf_only_environment_is_never_chosen_and_has_no_light_pdf() {
        // Sphere, constant environment, point: with the environment left to
        // BSDF sampling, light choice is uniform over the other two.
        let lights = Lights {
            lights: vec![
                LightKind::Sphere {
                    sphere: Sphere {
                        center: DVec3::new(0.0, 0.0, 5.0),
                        radius: 1.0,
                    },
                    spectrum: Spectrum::Constant(1.0),
                },
                LightKind::Environment(Environment::Constant(Spectrum::Constant(1.0))),
                LightKind::Point {
                    position: DVec3::new(0.0, 3.0, 0.0),
                    spectrum: Spectrum::Constant(1.0),
                },
            ],
            environment: Some(1),
            bsdf_only_environment: true,
        };
        assert_eq!(lights.nee_len(), 2);
        let mut seen = [0u32; 2];
        for i in 0..1000 {
            let u0 = (i as f64 + 0.5) / 1000.0;
            let ls = lights.sample(DVec3::ZERO, [u0, 0.3, 0.7]).unwrap();
            assert!(ls.dist.is_finite(), "the environment was chosen");
            if ls.is_delta {
                assert_eq!(ls.pdf, 0.5);
                seen[1] += 1;
            } else {
                let cone = sphere_cone_pdf(
                    &Sphere {
                        center: DVec3::new(0.0, 0.0, 5.0),
                        radius: 1.0,
                    },
                    DVec3::ZERO,
                );
                assert!((ls.pdf - 0.5 * cone).abs() < 1e-12 * cone);
                seen[0] += 1;
            }
        }
        assert_eq!(seen, [500, 500]);
        let (em, pdf) = lights.environment(DVec3::Y);
        assert!(matches!(em, Emission::Spectrum(..)));
        assert_eq!(pdf, 0.0);
        // Without the flag: three lights, the environment sampled uniformly.
        let all = Lights {
            bsdf_only_environment: false,
            ..lights
        };
        assert_eq!(all.nee_len(), 3);
        assert!((all.environment(DVec3::Y).1 - 1.0 / (3.0 * 4.0 * PI)).abs() < 1e-15);
        assert!((0..300).any(|i| {
            all.sample(DVec3::ZERO, [(i as f64 + 0.5) / 300.0, 0.3, 0.7])
                .is_some_and(|l| l.dist.is_infinite())
        }));
    }
}
