//! Rough and smooth conductors built on a microfacet distribution.

use super::Distribution;
use crate::error::BrdfError;
use crate::fresnel::Fresnel;
use crate::math::finite_nonneg;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use glam::DVec3;

/// A rough conductor: f = F(i·h) D(h) G2(i, o) / (4 cosθi cosθo).
///
/// Sampling draws visible normals, so the Monte Carlo weight is
/// F · G2/G1(i), bounded by 1 for F ≤ 1.
#[derive(Clone, Debug, PartialEq)]
pub struct MicrofacetConductor {
    dist: Distribution,
    fresnel: Fresnel,
}

impl MicrofacetConductor {
    /// Builds the model; the Fresnel data must cover 360–830 nm.
    pub fn new(dist: Distribution, fresnel: Fresnel) -> Result<MicrofacetConductor, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        Ok(MicrofacetConductor { dist, fresnel })
    }

    /// The normal distribution.
    pub fn distribution(&self) -> &Distribution {
        &self.dist
    }

    /// The Fresnel term.
    pub fn fresnel(&self) -> &Fresnel {
        &self.fresnel
    }
}

/// The λ-independent part of a rough-conductor evaluation.
struct Geometry {
    /// f / F: D G2 / (4 cosθi cosθo).
    f_over_fresnel: f64,
    /// Solid-angle pdf of sampling `wo`.
    pdf: f64,
    /// cosθd = wi·h, the Fresnel angle.
    cos_ih: f64,
}

impl MicrofacetConductor {
    /// D, G2 and the pdf at (wi, wo) with three divisions in all: with
    /// Λ = a/d, G2 = di do / (di do + ai do + ao di) and
    /// G1(i) = di / (di + ai).
    #[inline]
    fn geometry(&self, wi: DVec3, wo: DVec3) -> Option<Geometry> {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return None;
        }
        let (d, cos_ih) = self.dist.d_half(wi, wo)?;
        let (ai, di) = self.dist.lambda_frac(wi);
        let (ao, do_) = self.dist.lambda_frac(wo);
        let g2_den = di * do_ + ai * do_ + ao * di;
        Some(Geometry {
            f_over_fresnel: finite_nonneg(d * (di * do_) / (g2_den * (4.0 * wi.z * wo.z))),
            // Visible-normal density G1(i)(i·h)D(h)/cosθi times the
            // reflection Jacobian 1/(4 o·h), with o·h = i·h cancelling.
            pdf: finite_nonneg(d * di / ((di + ai) * (4.0 * wi.z))),
            cos_ih,
        })
    }
}

impl Bxdf for MicrofacetConductor {
    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.eval_pdf(wi, wo, lambda_nm).0
    }

    #[inline]
    fn pdf(&self, wi: DVec3, wo: DVec3, _lambda_nm: f64) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let Some((d, _)) = self.dist.d_half(wi, wo) else {
            return 0.0;
        };
        let (ai, di) = self.dist.lambda_frac(wi);
        finite_nonneg(d * di / ((di + ai) * (4.0 * wi.z)))
    }

    #[inline]
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let Some(g) = self.geometry(wi, wo) else {
            return (0.0, 0.0);
        };
        let f = self.fresnel.reflectance(g.cos_ih, lambda_nm) * g.f_over_fresnel;
        (finite_nonneg(f), g.pdf)
    }

    #[inline]
    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        let Some(g) = self.geometry(wi, wo) else {
            for o in out.iter_mut().take(lambdas.len()) {
                *o = (0.0, 0.0);
            }
            return;
        };
        // Only Fresnel depends on λ; the same expressions as `eval_pdf`, so
        // the results are bit-identical to it.
        for (o, &l) in out.iter_mut().zip(lambdas) {
            let f = self.fresnel.reflectance(g.cos_ih, l) * g.f_over_fresnel;
            *o = (finite_nonneg(f), g.pdf);
        }
    }

    #[inline]
    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let h = self.dist.sample_visible(wi, [u[1], u[2]]);
        let cos_ih = wi.dot(h);
        if cos_ih <= 0.0 {
            return None;
        }
        let wo = 2.0 * cos_ih * h - wi;
        if wo.z <= 0.0 {
            return None;
        }
        let (ai, di) = self.dist.lambda_frac(wi);
        let (ao, do_) = self.dist.lambda_frac(wo);
        // G2/G1(i) = (di + ai) do / (di do + ai do + ao di).
        let weight = self.fresnel.reflectance(cos_ih, lambda_nm) * ((di + ai) * do_)
            / (di * do_ + ai * do_ + ao * di);
        let pdf = self.dist.d(h) * di / ((di + ai) * (4.0 * wi.z));
        if !(weight > 0.0 && weight.is_finite() && pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BxdfSample {
            wo,
            weight,
            pdf,
            is_delta: false,
        })
    }
}

/// A perfectly smooth conductor: a single delta lobe of weight F(cosθi).
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothConductor {
    fresnel: Fresnel,
}

impl SmoothConductor {
    /// Builds the model; the Fresnel data must cover 360–830 nm.
    pub fn new(fresnel: Fresnel) -> Result<SmoothConductor, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        Ok(SmoothConductor { fresnel })
    }
}

impl Bxdf for SmoothConductor {
    fn eval(&self, _wi: DVec3, _wo: DVec3, _lambda_nm: f64) -> f64 {
        0.0
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3, _lambda_nm: f64) -> f64 {
        0.0
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, _u: [f64; 3]) -> Option<BxdfSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let weight = self.fresnel.reflectance(wi.z, lambda_nm);
        (weight > 0.0).then_some(BxdfSample {
            wo: crate::frame::reflect_z(wi),
            weight,
            pdf: 1.0,
            is_delta: true,
        })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        if wi.z <= 0.0 {
            return Specular::default();
        }
        Specular {
            weight: self.fresnel.reflectance(wi.z, lambda_nm),
            probability: 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    /// Brute-force ∫ D(h) cosθh dω over the hemisphere in (θ, φ).
    fn ndf_mass(dist: &Distribution) -> f64 {
        let (nt, np) = (4000, 64);
        let mut sum = 0.0;
        for i in 0..nt {
            // Substitution θ = (π/2) v² concentrates nodes near the normal.
            let v = (i as f64 + 0.5) / nt as f64;
            let theta = core::f64::consts::FRAC_PI_2 * v * v;
            let dtheta = core::f64::consts::PI * v / nt as f64;
            for j in 0..np {
                let phi = 2.0 * core::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                let h = spherical(theta, phi);
                sum += dist.d(h) * h.z * libm::sin(theta) * dtheta;
            }
        }
        sum * 2.0 * core::f64::consts::PI / np as f64
    }

    #[test]
    fn ndfs_are_normalised() {
        for a in [(0.05, 0.05), (0.3, 0.1), (1.0, 1.0), (0.5, 0.8)] {
            for d in [
                Distribution::ggx(a.0, a.1).unwrap(),
                Distribution::beckmann(a.0, a.1).unwrap(),
            ] {
                let m = ndf_mass(&d);
                // GGX's heavy tail converges slowly in θ; 2e-4 bounds the quadrature error.
                assert!((m - 1.0).abs() < 2e-4, "{d:?}: {m}");
            }
        }
    }

    #[test]
    fn projected_area_identity() {
        // ∫ G1(w) max(0, w·h) D(h) dω_h = cosθ_w for every w (Smith's definition).
        for d in [
            Distribution::ggx(0.4, 0.2).unwrap(),
            Distribution::beckmann(0.3, 0.6).unwrap(),
        ] {
            for th in [0.0, 0.7, 1.3, 1.5] {
                let w = spherical(th, 0.4);
                let (nt, np) = (3000, 256);
                let mut sum = 0.0;
                for i in 0..nt {
                    let theta = core::f64::consts::FRAC_PI_2 * (i as f64 + 0.5) / nt as f64;
                    for j in 0..np {
                        let phi = 2.0 * core::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                        let h = spherical(theta, phi);
                        sum += d.d(h) * w.dot(h).max(0.0) * libm::sin(theta);
                    }
                }
                sum *= core::f64::consts::FRAC_PI_2 / nt as f64 * 2.0 * core::f64::consts::PI
                    / np as f64;
                let lhs = d.g1(w) * sum;
                assert!(
                    (lhs - w.z).abs() < 2e-3 * w.z.max(0.05),
                    "{d:?} θ={th}: {lhs} vs {}",
                    w.z
                );
            }
        }
    }

    #[test]
    fn sample_weight_matches_eval_over_pdf() {
        let m = MicrofacetConductor::new(
            Distribution::ggx(0.3, 0.15).unwrap(),
            Fresnel::conductor(crate::Ior::metal(crate::Metal::Au)),
        )
        .unwrap();
        let b = MicrofacetConductor::new(Distribution::beckmann(0.2, 0.4).unwrap(), Fresnel::One)
            .unwrap();
        let wi = spherical(1.1, 0.3);
        for model in [&m, &b] {
            let mut hits = 0;
            for i in 0..50 {
                let u = [
                    0.5,
                    (i as f64 + 0.5) / 50.0,
                    ((i * 37 % 50) as f64 + 0.5) / 50.0,
                ];
                // Some reflected directions fall below the horizon at θi = 63°.
                let Some(s) = model.sample(wi, 600.0, u) else {
                    continue;
                };
                hits += 1;
                let f = model.eval(wi, s.wo, 600.0);
                let pdf = model.pdf(wi, s.wo, 600.0);
                assert!((pdf - s.pdf).abs() < 1e-9 * pdf, "{pdf} vs {}", s.pdf);
                assert!((f * s.wo.z / pdf - s.weight).abs() < 1e-9 * s.weight);
            }
            assert!(hits > 40, "only {hits} of 50 samples above the horizon");
        }
    }
}
