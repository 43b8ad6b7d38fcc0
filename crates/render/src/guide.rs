//! Aiming a share of the BSDF samples of diffuse and rough-plastic
//! surfaces at glossy objects (`[integrator] caustic_guiding`).
//!
//! Light that a glossy conductor reflects onto a diffuse surface (the sun's
//! glint on a brass object lighting the floor around it) reaches a diffuse
//! vertex only through that vertex's BSDF sample, and only when the sample
//! hits the small part of the object that mirrors the light toward it:
//! next-event estimation cannot see such light. With cosine sampling alone
//! these paths are rare and bright, and they hold most of the noise of a
//! metal object on a floor under a small light. Here a share `c` of the
//! samples is drawn uniformly in the cone each glossy object's bounding
//! sphere subtends, the rest from the BSDF, and every sample is weighted by
//! the mixture's density `(1 − c)·p_bsdf + c·p_cones` (one-sample MIS,
//! balance heuristic), which keeps the estimator unbiased for any c < 1.
//! The mixture is also the BSDF strategy's density in the MIS against light
//! sampling, so both strategies see the same sampler ([`Guided`] is a
//! [`Bxdf`], the integrator uses it in place of the material's).

use crate::light::{cone_one_minus_cos, cone_pdf, sample_cone};
use brdf::spec::ModelKind;
use brdf::{Bxdf, BxdfSample, Specular};
use glam::DVec3;

/// Most cones a vertex samples among: more glossy objects than this are
/// aimed at through one sphere around them all.
pub const MAX_CASTERS: usize = 8;

/// Narrowest lobe that counts as glossy: the peak density of the lobe at
/// normal incidence ([`Bxdf::lobe_peak_pdf`]), 1/sr. GGX α ≈ 0.28 has
/// 1/(4πα²) ≈ 1; a wider lobe spreads what it reflects too thinly to light
/// anything brightly, and a Lambertian surface has 1/π.
pub const CASTER_PEAK_PDF: f64 = 1.0;

/// Largest `caustic_guiding` share: the BSDF keeps at least this much of
/// the samples (its weight f·cos/p then stays within 10× a cosine sample's).
pub const MAX_SHARE: f64 = 0.9;

/// The glossy objects of a scene, and which materials aim at them.
#[derive(Clone, Debug, Default)]
pub struct Casters {
    /// Bounding spheres (centre, radius) of the glossy objects.
    spheres: Vec<(DVec3, f64)>,
    /// Per material index: whether its vertices aim samples at the casters.
    receivers: Vec<bool>,
    /// Share of a receiving vertex's samples aimed at the casters.
    share: f64,
}

/// Whether a material of `model` with peak lobe density `peak` (at normal
/// incidence) aims samples at glossy objects (`Some(false)`: it is one).
pub fn role(model: ModelKind, peak: Option<f64>) -> Option<bool> {
    match model {
        ModelKind::Diffuse | ModelKind::RoughPlastic => Some(true),
        // Unknown lobe sizes (delta and wave-optical lobes) count as glossy.
        _ if peak.is_none_or(|p| p >= CASTER_PEAK_PDF || p.is_nan()) => Some(false),
        _ => None,
    }
}

/// The smallest sphere about the centre of their box that holds all
/// `balls` (centre, radius); `None` for none or a non-finite one.
fn enclosing(balls: impl Iterator<Item = (DVec3, f64)> + Clone) -> Option<(DVec3, f64)> {
    let (lo, hi) = balls.clone().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (c, r)| (lo.min(c - DVec3::splat(r)), hi.max(c + DVec3::splat(r))),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let centre = 0.5 * (lo + hi);
    let radius = balls.fold(0.0f64, |a, (c, r)| a.max((c - centre).length() + r));
    Some((centre, radius))
}

/// Bounding sphere of a set of points (about the centre of their box).
pub fn bounding_sphere(points: impl Iterator<Item = DVec3> + Clone) -> Option<(DVec3, f64)> {
    enclosing(points.map(|p| (p, 0.0)))
}

impl Casters {
    /// Casters `spheres` for the materials flagged in `receivers`, with
    /// `share` of their samples (0 turns guiding off).
    pub fn new(spheres: Vec<(DVec3, f64)>, receivers: Vec<bool>, share: f64) -> Casters {
        let spheres: Vec<_> = spheres
            .into_iter()
            .filter(|(c, r)| c.is_finite() && r.is_finite() && *r > 0.0)
            .collect();
        let spheres = if spheres.len() > MAX_CASTERS {
            enclosing(spheres.iter().copied()).into_iter().collect()
        } else {
            spheres
        };
        let active = share > 0.0 && !spheres.is_empty() && receivers.iter().any(|&r| r);
        Casters {
            spheres,
            receivers,
            share: if active { share.min(MAX_SHARE) } else { 0.0 },
        }
    }

    /// Whether any vertex aims at casters.
    pub fn active(&self) -> bool {
        self.share > 0.0
    }

    /// Number of casters (bounding spheres) aimed at.
    pub fn len(&self) -> usize {
        if self.active() { self.spheres.len() } else { 0 }
    }

    /// Whether there is nothing to aim at.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The cones a vertex of material `m` at `p` aims at, in the frame
    /// `to_local` maps world directions into; `None` if it aims at none
    /// (not a receiver, or inside every caster's sphere).
    #[inline]
    pub fn cones(&self, m: u32, p: DVec3, to_local: impl Fn(DVec3) -> DVec3) -> Option<Cones> {
        if self.share <= 0.0 || !self.receivers.get(m as usize).copied().unwrap_or(false) {
            return None;
        }
        let mut c = Cones {
            axis: [DVec3::ZERO; MAX_CASTERS],
            one_minus: [0.0; MAX_CASTERS],
            n: 0,
            share: self.share,
        };
        for (centre, radius) in &self.spheres {
            let d = *centre - p;
            let d2 = d.length_squared();
            // From inside (or on) a sphere its cone is every direction: no aim.
            let Some(one_minus) = cone_one_minus_cos(d2, radius * radius) else {
                continue;
            };
            c.axis[c.n] = to_local(d / d2.sqrt());
            c.one_minus[c.n] = one_minus;
            c.n += 1;
        }
        (c.n > 0).then_some(c)
    }
}

/// Cones toward the casters from one vertex, in its local frame.
#[derive(Clone, Copy, Debug)]
pub struct Cones {
    axis: [DVec3; MAX_CASTERS],
    /// 1 − cosθmax of each cone.
    one_minus: [f64; MAX_CASTERS],
    n: usize,
    share: f64,
}

impl Cones {
    /// A direction uniform in one cone, chosen by `u[0]` with equal odds
    /// (the sphere lights' cone draw, [`sample_cone`]).
    fn sample(&self, u: [f64; 3]) -> DVec3 {
        let k = ((u[0] * self.n as f64) as usize).min(self.n - 1);
        sample_cone(self.axis[k], self.one_minus[k], [u[1], u[2]]).0
    }

    /// Solid-angle density of [`Cones::sample`] toward unit `d`.
    fn pdf(&self, d: DVec3) -> f64 {
        let mut p = 0.0;
        for k in 0..self.n {
            // A sample on a cone's rim may round to just outside it: 1e−12
            // of slack in the cosine keeps its own density.
            if 1.0 - d.dot(self.axis[k]) <= self.one_minus[k] + 1e-12 {
                p += cone_pdf(Some(self.one_minus[k]));
            }
        }
        p / self.n as f64
    }

    /// The share of samples aimed at the cones, and their density toward
    /// local `d` times it: a mixture density is `(1 − share)·p_bsdf + this`.
    /// Zero below the horizon, where [`Guided::sample`] returns no sample.
    #[inline]
    pub fn weighted_pdf(&self, d: DVec3) -> (f64, f64) {
        let p = if d.z > 0.0 { self.pdf(d) } else { 0.0 };
        (self.share, self.share * p)
    }
}

/// A material's BSDF sampled as the mixture of its own sampling (share
/// 1 − c) and the cones toward the casters (share c).
pub struct Guided<'a> {
    /// The material's model.
    pub inner: &'a dyn Bxdf,
    /// The cones, in the vertex's local frame.
    pub cones: Cones,
}

impl<'a> Guided<'a> {
    /// `inner` guided by `cones` when a vertex has them, else `inner`
    /// itself; `slot` holds the guided model for as long as it is used.
    #[inline]
    pub fn over(
        slot: &'a mut Option<Guided<'a>>,
        inner: &'a dyn Bxdf,
        cones: Option<Cones>,
    ) -> &'a dyn Bxdf {
        match cones {
            Some(cones) => slot.insert(Guided { inner, cones }),
            None => inner,
        }
    }

    #[inline]
    fn mix(&self, p_bsdf: f64, wo: DVec3) -> f64 {
        let (c, g) = self.cones.weighted_pdf(wo);
        (1.0 - c) * p_bsdf + g
    }
}

impl Bxdf for Guided<'_> {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.inner.eval(wi, wo, lambda_nm)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.mix(self.inner.pdf(wi, wo, lambda_nm), wo)
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let (f, p) = self.inner.eval_pdf(wi, wo, lambda_nm);
        (f, self.mix(p, wo))
    }

    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        self.inner.eval_pdf_many(wi, wo, lambdas, out);
        let (c, g) = self.cones.weighted_pdf(wo);
        for v in out.iter_mut() {
            v.1 = (1.0 - c) * v.1 + g;
        }
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let c = self.cones.share;
        if u[0] < c {
            let wo = self.cones.sample([u[0] / c, u[1], u[2]]);
            // Below the horizon the integrand is zero: the path ends.
            if wo.z <= 0.0 {
                return None;
            }
            let (f, p) = self.inner.eval_pdf(wi, wo, lambda_nm);
            let pdf = self.mix(p, wo);
            return (pdf > 0.0 && f.is_finite()).then(|| BxdfSample {
                wo,
                weight: f * wo.z / pdf,
                pdf,
                is_delta: false,
            });
        }
        let s = self
            .inner
            .sample(wi, lambda_nm, [(u[0] - c) / (1.0 - c), u[1], u[2]])?;
        if s.is_delta {
            // A discrete choice: only its probability is shared.
            return Some(BxdfSample {
                weight: s.weight / (1.0 - c),
                pdf: s.pdf * (1.0 - c),
                ..s
            });
        }
        let pdf = self.mix(s.pdf, s.wo);
        Some(BxdfSample {
            weight: s.weight * (s.pdf / pdf),
            pdf,
            ..s
        })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        let s = self.inner.specular(wi, lambda_nm);
        Specular {
            probability: s.probability * (1.0 - self.cones.share),
            ..s
        }
    }

    fn uses_lobe_choice(&self) -> bool {
        // `u[0]` chooses between the cones and the BSDF.
        true
    }

    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        self.inner.lobe_peak_pdf(wi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::testing::Pcg32;
    use brdf::{Diffuse, RoughPlastic, RoughPlasticParams};
    use std::f64::consts::PI;

    fn unit(theta_deg: f64, phi_deg: f64) -> DVec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// Casters around a vertex at the origin with normal +z (local = world).
    fn cones(spheres: &[(DVec3, f64)], share: f64) -> Cones {
        Casters::new(spheres.to_vec(), vec![true], share)
            .cones(0, DVec3::ZERO, |d| d)
            .expect("the origin is outside every sphere")
    }

    #[test]
    fn cone_samples_follow_their_density() {
        // Two cones, one reaching below the horizon; a histogram over the
        // sphere in (cosθ, φ) cells against the density integrated per cell.
        let c = cones(
            &[
                (3.0 * unit(30.0, 40.0), 0.8),
                (2.0 * unit(80.0, 200.0), 0.5),
            ],
            0.5,
        );
        let (nz, nphi, n) = (40usize, 40usize, 2_000_000usize);
        let mut rng = Pcg32::new(7, 1);
        let mut hist = vec![0.0f64; nz * nphi];
        let cell = |d: DVec3| {
            let iz = (((d.z + 1.0) * 0.5 * nz as f64) as usize).min(nz - 1);
            let phi = d.y.atan2(d.x).rem_euclid(2.0 * PI);
            let ip = ((phi / (2.0 * PI) * nphi as f64) as usize).min(nphi - 1);
            iz * nphi + ip
        };
        for _ in 0..n {
            let u = rng.uniform3();
            let d = c.sample(u);
            assert!((d.length() - 1.0).abs() < 1e-12, "{d}");
            assert!(c.pdf(d) > 0.0, "a sample outside its own cone: {d}");
            hist[cell(d)] += 1.0;
        }
        // Expected counts by a midpoint rule on a 16×16 grid per cell.
        let (mut chi2, mut dof) = (0.0, 0usize);
        let sub = 16;
        for iz in 0..nz {
            for ip in 0..nphi {
                let mut e = 0.0;
                for a in 0..sub {
                    for b in 0..sub {
                        let z =
                            -1.0 + 2.0 * (iz as f64 + (a as f64 + 0.5) / sub as f64) / nz as f64;
                        let phi =
                            2.0 * PI * (ip as f64 + (b as f64 + 0.5) / sub as f64) / nphi as f64;
                        let s = (1.0 - z * z).max(0.0).sqrt();
                        e += c.pdf(DVec3::new(s * phi.cos(), s * phi.sin(), z));
                    }
                }
                let area = (2.0 / nz as f64) * (2.0 * PI / nphi as f64);
                let expected = e / (sub * sub) as f64 * area * n as f64;
                if expected > 20.0 {
                    let o = hist[iz * nphi + ip];
                    chi2 += (o - expected).powi(2) / expected;
                    dof += 1;
                }
            }
        }
        // Cells cut by a cone's rim hold midpoint-rule error; the bound is
        // loose for that but fails on a wrong density (e.g. the cosine of
        // the rim for 1 − cosθmax: chi² in the hundreds of thousands).
        assert!(dof > 20, "{dof}");
        assert!(chi2 < 3.0 * dof as f64, "chi² {chi2:.0} over {dof} cells");
    }

    /// Monte Carlo estimates of ∫ f·cosθo·g dω for each test function of
    /// `gs` with `bxdf`'s own sampling: (mean, standard error) per function.
    fn estimates(
        bxdf: &dyn Bxdf,
        wi: DVec3,
        gs: &[&dyn Fn(DVec3) -> f64],
        n: usize,
        seed: u64,
    ) -> Vec<(f64, f64)> {
        let mut rng = Pcg32::new(seed, 3);
        let mut sums = vec![(0.0f64, 0.0f64); gs.len()];
        for _ in 0..n {
            let Some(s) = bxdf.sample(wi, 550.0, rng.uniform3()) else {
                continue;
            };
            // Weight and density as the integrator uses them.
            let (f, p) = bxdf.eval_pdf(wi, s.wo, 550.0);
            assert!(
                (p - s.pdf).abs() <= 1e-9 * p,
                "pdf {p} vs sample's {}",
                s.pdf
            );
            assert!((f * s.wo.z / p - s.weight).abs() <= 1e-9 * s.weight.max(1e-300));
            for (k, g) in gs.iter().enumerate() {
                let x = s.weight * g(s.wo);
                sums[k].0 += x;
                sums[k].1 += x * x;
            }
        }
        sums.iter()
            .map(|&(s, s2)| {
                let m = s / n as f64;
                (m, ((s2 / n as f64 - m * m) / n as f64).max(0.0).sqrt())
            })
            .collect()
    }

    #[test]
    fn guided_sampling_is_unbiased_against_the_models_own() {
        // The mixture estimates the same integrals ∫ f·cos·g as the model's
        // own (chi-square-tested) sampling, for test functions g that weigh
        // the whole lobe, the inside of each cone, the part of a cone next
        // to the horizon, and a smooth function; with every sample's pdf
        // and weight equal to what eval_pdf gives for its direction.
        // Dropping the (1 − c) factor, or the cones' 1/n, moves the
        // estimates by 29 and 615 standard errors.
        let (a, b) = (2.5 * unit(60.0, 30.0), 4.0 * unit(85.0, 250.0));
        let spheres = [(a, 0.6), (b, 1.0)];
        let diffuse = Diffuse::new(brdf::Reflectance::Constant(0.7));
        let plastic = RoughPlastic::new(RoughPlasticParams {
            alpha: 0.2,
            int_ior: 1.49,
            ext_ior: 1.0,
            reflectance: brdf::Reflectance::Constant(0.5),
            nonlinear: false,
        })
        .unwrap();
        let in_cone = |c: DVec3, r: f64| {
            let cos_max = (1.0 - r * r / c.length_squared()).sqrt();
            move |d: DVec3| f64::from(u8::from(d.dot(c.normalize()) >= cos_max))
        };
        let (cone_a, cone_b) = (in_cone(a, 0.6), in_cone(b, 1.0));
        let one = |_: DVec3| 1.0;
        let low_b = |d: DVec3| cone_b(d) * f64::from(u8::from(d.z < 0.05));
        let smooth = |d: DVec3| (1.0 + d.x) * (1.0 + 0.5 * d.y * d.y);
        let gs: [&dyn Fn(DVec3) -> f64; 5] = [&one, &cone_a, &cone_b, &low_b, &smooth];
        let cases: [(&dyn Bxdf, f64, f64); 4] = [
            (&diffuse, 0.25, 10.0),
            (&diffuse, 0.9, 70.0),
            (&plastic, 0.25, 30.0),
            (&plastic, 0.5, 75.0),
        ];
        let n = 1_000_000;
        for (i, (inner, share, theta)) in cases.into_iter().enumerate() {
            let wi = unit(theta, 0.0);
            let g = Guided {
                inner,
                cones: cones(&spheres, share),
            };
            let want = estimates(inner, wi, &gs, n, 100 + i as u64);
            let got = estimates(&g, wi, &gs, n, 200 + i as u64);
            for (k, (w, o)) in want.iter().zip(&got).enumerate() {
                let z = (o.0 - w.0) / (w.1 * w.1 + o.1 * o.1).sqrt().max(1e-300);
                assert!(
                    z.abs() < 4.5 && w.0 > 0.0,
                    "case {i}, function {k}: guided {:.6} ± {:.1e}, own {:.6} ± {:.1e} (z {z:.1})",
                    o.0,
                    o.1,
                    w.0,
                    w.1
                );
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        /// Over the whole accepted domain (shares up to the cap, casters
        /// anywhere outside the vertex, incidence to grazing, both
        /// receiving models, any draw): every sample the mixture returns
        /// leaves above the horizon, with the density and weight that
        /// `eval_pdf` gives its direction, finite and positive, and a
        /// direction inside a cone has at least the cones' share of density.
        #[test]
        fn every_guided_sample_is_consistent(
            share in 1e-3f64..=MAX_SHARE,
            centres in proptest::collection::vec(
                ((-1.0f64..1.0), (-1.0f64..1.0), (-1.0f64..1.0), (1.01f64..50.0), (1e-3f64..1.0)),
                1..12,
            ),
            theta in 0.0f64..89.99,
            plastic in proptest::bool::ANY,
            u in proptest::array::uniform3(0.0f64..1.0),
        ) {
            let spheres: Vec<_> = centres
                .iter()
                .filter_map(|&(x, y, z, d, r)| {
                    DVec3::new(x, y, z).try_normalize().map(|c| (c * d, r * d * 0.99))
                })
                .collect();
            proptest::prop_assume!(!spheres.is_empty());
            let diffuse = Diffuse::new(brdf::Reflectance::Constant(0.7));
            let coat = RoughPlastic::new(RoughPlasticParams {
                alpha: 0.15,
                int_ior: 1.49,
                ext_ior: 1.0,
                reflectance: brdf::Reflectance::Constant(0.3),
                nonlinear: false,
            })
            .unwrap();
            let inner: &dyn Bxdf = if plastic { &coat } else { &diffuse };
            // More than MAX_CASTERS spheres are merged into one, which may
            // hold the vertex: then nothing aims.
            let c = Casters::new(spheres, vec![true], share).cones(0, DVec3::ZERO, |d| d);
            proptest::prop_assume!(c.is_some() || centres.len() > MAX_CASTERS);
            let Some(c) = c else {
                return Ok(());
            };
            let g = Guided { inner, cones: c };
            let wi = unit(theta, 17.0);
            if let Some(s) = g.sample(wi, 550.0, u) {
                proptest::prop_assert!(s.wo.z > 0.0 && (s.wo.length() - 1.0).abs() < 1e-12);
                let (f, p) = g.eval_pdf(wi, s.wo, 550.0);
                proptest::prop_assert!(p > 0.0 && p.is_finite() && s.weight.is_finite());
                proptest::prop_assert!((p - s.pdf).abs() <= 1e-12 * p, "{} vs {}", p, s.pdf);
                proptest::prop_assert!((f * s.wo.z / p - s.weight).abs() <= 1e-12 * s.weight.max(1e-300));
                let (c_share, cone) = c.weighted_pdf(s.wo);
                proptest::prop_assert!(p >= cone && c_share == share.min(MAX_SHARE));
            }
        }
    }

    #[test]
    fn roles_and_empty_cases() {
        assert_eq!(role(ModelKind::Diffuse, Some(0.3)), Some(true));
        assert_eq!(role(ModelKind::RoughPlastic, Some(5.0)), Some(true));
        assert_eq!(role(ModelKind::Ggx, Some(3.5)), Some(false));
        assert_eq!(role(ModelKind::Ggx, Some(0.5)), None);
        assert_eq!(role(ModelKind::Smooth, None), Some(false));
        // No share, no receivers or no casters: nothing aims.
        let s = vec![(DVec3::new(0.0, 0.0, 3.0), 1.0)];
        assert!(!Casters::new(s.clone(), vec![true], 0.0).active());
        assert!(!Casters::new(s.clone(), vec![false], 0.5).active());
        assert!(!Casters::new(Vec::new(), vec![true], 0.5).active());
        let c = Casters::new(s, vec![true, false], 0.5);
        assert!(c.cones(1, DVec3::ZERO, |d| d).is_none());
        // Inside the sphere, or a material index out of range: no aim.
        assert!(c.cones(0, DVec3::new(0.0, 0.0, 2.5), |d| d).is_none());
        assert!(c.cones(7, DVec3::ZERO, |d| d).is_none());
        // More casters than MAX_CASTERS: one sphere holds them all.
        let many: Vec<_> = (0..12)
            .map(|i| (DVec3::new(i as f64, 5.0, 0.0), 0.5))
            .collect();
        let c = Casters::new(many.clone(), vec![true], 0.5);
        assert_eq!(c.len(), 1);
        let (centre, r) = c.spheres[0];
        assert!(
            many.iter()
                .all(|(p, q)| (*p - centre).length() + q <= r + 1e-12)
        );
    }
}
