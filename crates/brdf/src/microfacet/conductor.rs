//! Rough and smooth conductors built on a microfacet distribution.

use super::{COS_HORIZON, Distribution, NdfKind};
use crate::error::BrdfError;
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use glam::DVec3;

/// A rough conductor: f = F(i·h) D(h) G2(i, o) / (4 cosθi cosθo).
///
/// Sampling draws visible normals, so the Monte Carlo weight is
/// F · G2/G1(i), bounded by 1 for F ≤ 1.
///
/// Grazing limit: a direction with cosθ < [`COS_HORIZON`] (1e−100; in
/// particular on or below the horizon) gives f = pdf = 0 and no sample;
/// above it `eval`, `pdf` and `sample` agree to round-off.
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
    /// |wi + wo|² = 4 cos²θd, for the Fresnel term (as the ratio |wi + wo|²/4,
    /// which skips a product and the clamps on the Fresnel chain).
    len2: f64,
}

impl MicrofacetConductor {
    /// D, G2 and the pdf at (wi, wo), instantiated per distribution (no
    /// dispatch inside the arithmetic).
    #[inline]
    fn geometry(&self, wi: DVec3, wo: DVec3) -> Option<Geometry> {
        let d = &self.dist;
        match d.kind() {
            NdfKind::Ggx => Self::geometry_with(
                wi,
                wo,
                |v, q| d.ggx_d_fraction(v, q),
                |w| d.ggx_lambda_frac(w),
            ),
            NdfKind::Beckmann => Self::geometry_with(
                wi,
                wo,
                |v, q| d.beckmann_d_fraction(v, q),
                |w| d.lambda_frac(w),
            ),
        }
    }

    /// The geometry with two divisions in all: D on the unnormalised half
    /// vector v = wi + wo (as a fraction whose division joins the others), cos²θd = |v|²/4, and with Λ = a/d,
    /// G2 = di do / (di do + ai do + ao di) and G1(i) = di / (di + ai).
    #[inline(always)]
    fn geometry_with(
        wi: DVec3,
        wo: DVec3,
        d: impl Fn(DVec3, f64) -> (f64, f64),
        lambda_frac: impl Fn(DVec3) -> (f64, f64),
    ) -> Option<Geometry> {
        if !(wi.z >= COS_HORIZON && wo.z >= COS_HORIZON) {
            return None;
        }
        let v = wi + wo;
        let len2 = v.length_squared();
        if !(len2 > 0.0 && len2.is_finite()) {
            return None;
        }
        let (d_num, d_den) = d(v, len2);
        let (ai, di) = lambda_frac(wi);
        let (ao, do_) = lambda_frac(wo);
        let g2_den = di * do_ + ai * do_ + ao * di;
        Some(Geometry {
            f_over_fresnel: finite_nonneg(
                d_num * (di * do_) / (d_den * g2_den * (4.0 * wi.z * wo.z)),
            ),
            // Visible-normal density G1(i)(i·h)D(h)/cosθi times the
            // reflection Jacobian 1/(4 o·h), with o·h = i·h cancelling.
            pdf: finite_nonneg(d_num * di / (d_den * (di + ai) * (4.0 * wi.z))),
            len2,
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
        // Only G1(i) and D: cheaper than the full geometry.
        if !(wi.z >= COS_HORIZON && wo.z >= COS_HORIZON) {
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
        let f = self.fresnel.reflectance_ratio(g.len2, 4.0, lambda_nm) * g.f_over_fresnel;
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
        let mut r = [0.0; 16];
        for (ls, os) in lambdas.chunks(r.len()).zip(out.chunks_mut(r.len())) {
            let m = ls.len().min(os.len());
            self.fresnel
                .reflectance_ratio_many(g.len2, 4.0, &ls[..m], &mut r[..m]);
            for (o, &r) in os.iter_mut().zip(&r[..m]) {
                *o = (finite_nonneg(r * g.f_over_fresnel), g.pdf);
            }
        }
    }

    fn eval_pdf_rows(
        &self,
        wi: &[DVec3],
        wo: &[DVec3],
        lambda_nm: &[f64],
        f: &mut [f64],
        pdf: &mut [f64],
    ) {
        match self.dist.kind() {
            NdfKind::Ggx => super::rows::ggx_eval_pdf_rows(self, (wi, wo, lambda_nm), (f, pdf)),
            // Beckmann's Λ branches between 0 and erfc: row by row.
            NdfKind::Beckmann => crate::model::eval_pdf_each_row(self, wi, wo, lambda_nm, f, pdf),
        }
    }

    #[inline]
    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let d = &self.dist;
        // One body, instantiated per distribution so that the GGX path has
        // no per-step dispatch: sampling is on every path's critical path, and
        // dispatch nearly doubles its cost (docs/profiling.md).
        match d.kind() {
            NdfKind::Ggx => self.sample_with(
                wi,
                lambda_nm,
                u,
                |wi, u| {
                    (
                        d.ggx_sample_visible_unnormalised(wi, u),
                        d.ggx_lambda_frac(wi),
                        0.0,
                    )
                },
                |w| d.ggx_lambda_frac(w),
                |h, q, _| d.ggx_d_fraction(h, q),
                true,
            ),
            // Beckmann's Λ is homogeneous of degree 0 in the direction, and D
            // comes from the sampled slopes: neither waits for a division.
            NdfKind::Beckmann => self.sample_with(
                wi,
                lambda_nm,
                u,
                |wi, u| {
                    let (h, lambda, e) = d.beckmann_sample_visible_with_lambda(wi, u);
                    (h, (lambda, 1.0), e)
                },
                |w| d.lambda_frac(w),
                |_, q, e| (d.beckmann_d_from_slopes(e, q), 1.0),
                true,
            ),
        }
    }

    /// One glossy lobe: `sample` reads only `u[1]` and `u[2]`.
    fn uses_lobe_choice(&self) -> bool {
        false
    }

    /// D(n)/(4 cosθi) = 1/(4π αx αy cosθi): the density of the mirror
    /// direction divided by G1(wi) ≤ 1, and no density exceeds it (both
    /// distributions peak at the normal; the visible-normal density is
    /// G1 D(h)/(4 cosθi)).
    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        (wi.z >= COS_HORIZON).then(|| self.dist.d_max() / (4.0 * wi.z))
    }
}

impl MicrofacetConductor {
    /// Visible-normal sampling given the distribution's pieces: `visible`
    /// draws h up to a positive factor and returns Smith Λ(wi) as a fraction
    /// with it (Beckmann's inversion computes it anyway) and a value of its
    /// own that `d` receives, `lambda_frac` is Smith Λ as a
    /// fraction, `d` is D(h/|h|) from h, |h|² and that value as a fraction
    /// (its division joins the pdf's), and `homogeneous` says
    /// that `lambda_frac` accepts an unnormalised direction.
    ///
    /// The cost of a sample is the latency of one dependent chain of square
    /// roots and divisions, so the chain is kept free of normalisations:
    /// with p = wi·h, q = |h|² the mirror direction is v/q for
    /// v = 2p h − q wi (|v| = q exactly), and Fresnel takes cos²θd as the
    /// unformed ratio p²/q.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn sample_with(
        &self,
        wi: DVec3,
        lambda_nm: f64,
        u: [f64; 3],
        visible: impl Fn(DVec3, [f64; 2]) -> (DVec3, (f64, f64), f64),
        lambda_frac: impl Fn(DVec3) -> (f64, f64),
        d: impl Fn(DVec3, f64, f64) -> (f64, f64),
        homogeneous: bool,
    ) -> Option<BxdfSample> {
        if wi.z.is_nan() || wi.z < COS_HORIZON {
            return None;
        }
        let (h, (ai, di), aux) = visible(wi, [u[1], u[2]]);
        let p = wi.dot(h);
        let q = h.length_squared();
        if !(p > 0.0 && q > 0.0 && q.is_finite()) {
            return None;
        }
        let v = 2.0 * p * h - q * wi;
        // wo = v/q: the same horizon as `eval` and `pdf`.
        if v.z.is_nan() || v.z < COS_HORIZON * q {
            return None;
        }
        let wo = v * (1.0 / q);
        let (ao, do_) = lambda_frac(if homogeneous { v } else { wo });
        // G2/G1(i) = (di + ai) do / (di do + ai do + ao di).
        let weight = self.fresnel.reflectance_ratio(p * p, q, lambda_nm) * ((di + ai) * do_)
            / (di * do_ + ai * do_ + ao * di);
        let (d_num, d_den) = d(h, q, aux);
        let pdf = d_num * di / (d_den * (di + ai) * (4.0 * wi.z));
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

    /// One delta lobe: `sample` reads no random number.
    fn uses_lobe_choice(&self) -> bool {
        false
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

    /// α pairs of the Beckmann sampler's round-off checks: the accepted
    /// domain's ends, isotropic and both ways anisotropic.
    const BECKMANN_ALPHAS: [(f64, f64); 6] = [
        (1e-4, 1e-4),
        (0.05, 0.05),
        (0.2, 0.2),
        (0.3, 0.1),
        (1.0, 1.0),
        (0.01, 0.9),
    ];

    #[test]
    fn beckmann_sample_pdf_and_weight_are_the_evaluations_to_round_off() {
        // The sample's pdf and weight against `pdf` and `eval` at the
        // returned wo (which re-forms the half vector from wi + wo: for small
        // α its tangential part cancels, the more so towards the horizon,
        // hence 1e−9 and θi ≤ 85°; the sampler's own parts are checked to
        // round-off up to the horizon in `beckmann_sampler_d_and_lambda_...`):
        // α from 1e−4 to 1, anisotropic, u over the unit square to 1e−12 of its edges (beyond,
        // e^{−|s|²} turns subnormal in both forms and loses digits).
        let mut compared = 0;
        let mut worst = 0.0f64;
        for (ax, ay) in BECKMANN_ALPHAS {
            let m = MicrofacetConductor::new(Distribution::beckmann(ax, ay).unwrap(), Fresnel::One)
                .unwrap();
            for i in 0..=60 {
                let theta = 1.48 * i as f64 / 60.0;
                for phi in [0.0, 0.9, 2.5, 4.1] {
                    let wi = spherical(theta, phi);
                    for a in 0..=24 {
                        for b in 0..=8 {
                            let u1 = (a as f64 / 24.0).clamp(1e-12, 1.0 - 1e-12);
                            let u2 = (b as f64 / 8.0).clamp(1e-12, 1.0 - 1e-12);
                            let Some(s) = m.sample(wi, 550.0, [0.5, u1, u2]) else {
                                continue;
                            };
                            let (f, pdf) = m.eval_pdf(wi, s.wo, 550.0);
                            if pdf == 0.0 {
                                // wo within round-off of the horizon cut.
                                continue;
                            }
                            compared += 1;
                            let rp = (s.pdf - pdf).abs() / pdf;
                            let w = f * s.wo.z / pdf;
                            let rw = (s.weight - w).abs() / w;
                            worst = worst.max(rp).max(rw);
                            assert!(
                                rp < 1e-9 && rw < 1e-9,
                                "α ({ax}, {ay}) θ {theta} φ {phi} u ({u1}, {u2}): pdf {} vs {pdf}, weight {} vs {w}",
                                s.pdf,
                                s.weight
                            );
                        }
                    }
                }
            }
        }
        assert!(compared > 50_000 && worst > 0.0, "{compared} {worst:e}");
    }

    #[test]
    fn beckmann_sampler_d_and_lambda_are_the_distributions_to_round_off() {
        // D from the sampled slopes' e^{−|s|²} against D on the sampled h,
        // and Λ on the unnormalised mirror direction v against Λ on v/|v|.
        let mut compared = 0;
        let mut worst = 0.0f64;
        for (ax, ay) in BECKMANN_ALPHAS {
            let d = Distribution::beckmann(ax, ay).unwrap();
            for i in 0..=60 {
                let theta = core::f64::consts::FRAC_PI_2 * (i as f64 / 60.0).min(1.0 - 1e-6);
                for phi in [0.0, 0.9, 2.5, 4.1] {
                    let wi = spherical(theta, phi);
                    for a in 0..=24 {
                        for b in 0..=8 {
                            let u1 = (a as f64 / 24.0).clamp(1e-12, 1.0 - 1e-12);
                            let u2 = (b as f64 / 8.0).clamp(1e-12, 1.0 - 1e-12);
                            let (h, _, e) = d.beckmann_sample_visible_with_lambda(wi, [u1, u2]);
                            let q = h.length_squared();
                            let (got, want) =
                                (d.beckmann_d_from_slopes(e, q), d.d_unnormalised(h, q));
                            // e^{−|s|²} turns the exponent's few ulps into |s|² times that.
                            let s2 = -libm::log(e);
                            let rd = (got - want).abs() / want;
                            assert!(
                                rd < 1e-14 * (1.0 + s2),
                                "α ({ax}, {ay}) θ {theta}: D {got} vs {want}"
                            );
                            let v = 2.0 * wi.dot(h) * h - q * wi;
                            if v.z < COS_HORIZON * q {
                                continue;
                            }
                            let (lv, lw) = (d.lambda_frac(v).0, d.lambda_frac(v * (1.0 / q)).0);
                            let a2 = v.z * v.z / (ax * ax * v.x * v.x + ay * ay * v.y * v.y);
                            let rl = if lw == 0.0 { lv } else { (lv - lw).abs() / lw };
                            assert!(
                                rl < 1e-14 * (1.0 + a2),
                                "α ({ax}, {ay}) θ {theta}: Λ {lv} vs {lw}"
                            );
                            worst = worst.max(rd).max(rl);
                            compared += 1;
                        }
                    }
                }
            }
        }
        assert!(compared > 50_000 && worst > 0.0, "{compared} {worst:e}");
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
