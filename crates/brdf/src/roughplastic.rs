//! A rough dielectric coat over a Lambertian base, Mitsuba's `roughplastic`
//! model (docs/physics.md §17): a GGX interface of relative index
//! η = int_ior / ext_ior reflects
//!
//! f_s = F(wi·h, η) D(h) G2(wi, wo) / (4 cosθi cosθo),
//!
//! and what it transmits reaches a Lambertian base of reflectance ρ(λ), is
//! scattered back and leaves through the interface:
//!
//! f_d = ρ / (1 − R_i) · t(cosθi) t(cosθo) / (π η²)   (`nonlinear = false`, Mitsuba's default)
//! f_d = ρ / (1 − ρ R_i) · t(cosθi) t(cosθo) / (π η²)  (`nonlinear = true`),
//!
//! with t(μ) the interface's transmittance from outside at incidence cosine μ
//! and R_i its reflectance from inside averaged over a diffuse (cosine)
//! distribution: R_i = ∫₀¹ 2μ R_in(μ) dμ. G2 is the height-correlated Smith
//! term every microfacet model here uses (Mitsuba: the separable G1·G1).

// `!(x > 0.0)` is how these guards also refuse NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use core::f64::consts::FRAC_1_PI;

use glam::DVec3;

use crate::diffuse::{Reflectance, sample_cosine_hemisphere};
use crate::error::{BrdfError, check_range};
use crate::fresnel::dielectric_reflectance;
use crate::microfacet::{COS_HORIZON, Distribution};
use crate::numerics::quadrature::gauss_legendre;
use crate::{Bxdf, BxdfSample, Kept};

/// Nodes of the transmittance table t(μ): μ_j = j / (N − 1), j < N (μ_0 taken
/// as 10⁻⁶), linear between them, as Mitsuba's `roughplastic` tabulates it.
pub const TRANSMITTANCE_NODES: usize = 64;

/// Parameters of [`RoughPlastic::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlasticParams {
    /// GGX roughness of the coat, 1e-4 ≤ α ≤ 1.
    pub alpha: f64,
    /// Index of the coat, 1 ≤ int_ior ≤ 4 (polypropylene: 1.49).
    pub int_ior: f64,
    /// Index of the medium above, 1 ≤ ext_ior < int_ior.
    pub ext_ior: f64,
    /// Reflectance ρ(λ) of the diffuse base.
    pub reflectance: Reflectance,
    /// Whether the base's colour enters the internal scattering
    /// (ρ/(1 − ρR_i)) or not (ρ/(1 − R_i), Mitsuba's default).
    pub nonlinear: bool,
}

/// A GGX dielectric coat over a Lambertian base (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlastic {
    dist: Distribution,
    eta: f64,
    reflectance: Reflectance,
    nonlinear: bool,
    transmittance: [f64; TRANSMITTANCE_NODES],
    internal_reflectance: f64,
    specular_weight: f64,
    /// 1 / (π η²), times 1 / (1 − R_i) unless `nonlinear`: the base's
    /// λ-independent factor.
    diffuse_scale: f64,
}

/// n-point Gauss–Legendre on [0, 1] (n = 2H): nodes and weights, made once
/// per integral (Newton's iteration for the nodes cost more than the
/// integrands when it ran inside the loops).
struct Gl01<const H: usize> {
    x: [f64; H],
    w: [f64; H],
}

impl<const H: usize> Gl01<H> {
    fn new() -> Self {
        let (x, w) = gauss_legendre::<H>();
        Gl01 { x, w }
    }

    fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..2 * H).map(move |i| {
            let (xi, wi) = if i < H {
                (-self.x[i], self.w[i])
            } else {
                (self.x[i - H], self.w[i - H])
            };
            (0.5 + 0.5 * xi, 0.5 * wi)
        })
    }
}

/// ∫∫_[0,1]² f(u) du by the tensor product of two n-point rules (n = 2H)
/// after the change of variables u = 3s² − 2s³ in each coordinate. The
/// visible-normal map has square-root endpoint singularities in u (at
/// normal incidence the sampled slope grows as 1/√(1 − u)), which cost a
/// plain Gauss–Legendre rule its accuracy (2 % in R_in(1) at α 0.1); the
/// map's vanishing derivative at both ends makes the integrand smooth in s.
fn integrate_unit_square<const H: usize>(mut f: impl FnMut([f64; 2]) -> f64) -> f64 {
    let smooth = |(s, w): (f64, f64)| (s * s * (3.0 - 2.0 * s), w * 6.0 * s * (1.0 - s));
    let rule = Gl01::<H>::new();
    let mut sum = 0.0;
    for (u0, w0) in rule.iter().map(smooth) {
        for (u1, w1) in rule.iter().map(smooth) {
            sum += w0 * w1 * f([u0, u1]);
        }
    }
    sum
}

/// ∫∫_[0,1]² f(u) du for an f with kinks along the zero lines of the two
/// functions `kinks` returns (total reflection setting in, the reflected
/// direction crossing the horizon). For each Gauss–Legendre node in u[0]
/// the zeros in u[1] are located (a coarse scan, then bisection), and each
/// piece between them is integrated by a 32-point rule with the endpoint
/// map of [`integrate_unit_square`]: the kinks lie in a band of u[1] a few
/// thousandths wide at near-normal incidence, which a fixed rule does not
/// resolve (R_in(1) 1.6 % low at α 0.1).
fn integrate_with_kinks(
    mut f: impl FnMut([f64; 2]) -> f64,
    mut kinks: impl FnMut([f64; 2]) -> [f64; 2],
) -> f64 {
    const SCAN: usize = 32;
    const MAX_EDGES: usize = 10;
    let smooth = |s: f64| s * s * (3.0 - 2.0 * s);
    let rule = Gl01::<16>::new();
    let mut sum = 0.0;
    for (u0, w0) in rule.iter() {
        let mut edges = [0.0; MAX_EDGES];
        let mut n = 1;
        let mut prev = kinks([u0, 0.0]);
        let mut prev_u = 0.0;
        for k in 1..=SCAN {
            let u1 = smooth(k as f64 / SCAN as f64);
            let cur = kinks([u0, u1]);
            for j in 0..2 {
                if (prev[j] > 0.0) != (cur[j] > 0.0) && n < MAX_EDGES - 1 {
                    let (mut lo, mut hi) = (prev_u, u1);
                    for _ in 0..50 {
                        let mid = 0.5 * (lo + hi);
                        if (kinks([u0, mid])[j] > 0.0) == (prev[j] > 0.0) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    edges[n] = 0.5 * (lo + hi);
                    n += 1;
                }
            }
            prev = cur;
            prev_u = u1;
        }
        edges[n] = 1.0;
        n += 1;
        edges[..n].sort_unstable_by(f64::total_cmp);
        for e in edges[..n].windows(2) {
            let (a, b) = (e[0], e[1]);
            if b <= a {
                continue;
            }
            for (s, w1) in rule.iter() {
                let u1 = a + (b - a) * smooth(s);
                sum += w0 * w1 * (b - a) * 6.0 * s * (1.0 - s) * f([u0, u1]);
            }
        }
    }
    sum
}

/// The direction of incidence cosine μ in the xz plane.
fn direction(mu: f64) -> DVec3 {
    let mu = mu.clamp(0.0, 1.0);
    DVec3::new(libm::sqrt(1.0 - mu * mu), 0.0, mu)
}

impl RoughPlastic {
    /// Validates the parameters and tabulates t(μ) and R_i (about 64 × 32²
    /// and 48 × 32 × 200 interface samples).
    pub fn new(p: RoughPlasticParams) -> Result<RoughPlastic, BrdfError> {
        let dist = Distribution::ggx(p.alpha, p.alpha)?;
        check_range("int_ior", p.int_ior, 1.0, 4.0, "1 ≤ int_ior ≤ 4")?;
        check_range("ext_ior", p.ext_ior, 1.0, 4.0, "1 ≤ ext_ior ≤ 4")?;
        if p.int_ior <= p.ext_ior {
            return Err(BrdfError::OutOfRange {
                name: "int_ior",
                value: p.int_ior,
                valid: "int_ior > ext_ior (the coat denser than the medium above it)",
            });
        }
        let mut m = RoughPlastic {
            dist,
            eta: p.int_ior / p.ext_ior,
            specular_weight: 1.0 / (1.0 + p.reflectance.mean()),
            reflectance: p.reflectance,
            nonlinear: p.nonlinear,
            transmittance: [0.0; TRANSMITTANCE_NODES],
            internal_reflectance: 0.0,
            diffuse_scale: 0.0,
        };
        for j in 0..TRANSMITTANCE_NODES {
            let mu = (j as f64 / (TRANSMITTANCE_NODES - 1) as f64).max(1e-6);
            m.transmittance[j] = m.transmittance_at(mu);
        }
        // ∫₀¹ 2μ R_in(μ) dμ: R_in steps up to 1 (total reflection) at the
        // critical cosine, smoothed over a width of about α, so the two sides
        // are integrated apart, with nodes drawn towards the step.
        let mu_c = libm::sqrt(1.0 - 1.0 / (m.eta * m.eta));
        let mut ri = 0.0;
        let rule = Gl01::<12>::new();
        for (a, b) in [(0.0, mu_c), (mu_c, 1.0)] {
            for (s, w) in rule.iter() {
                let mu = a + (b - a) * s * s * (3.0 - 2.0 * s);
                let jac = (b - a) * 6.0 * s * (1.0 - s);
                ri += w * jac * 2.0 * mu * m.internal_reflectance_at(mu);
            }
        }
        m.internal_reflectance = ri.clamp(0.0, 1.0 - 1e-12);
        let linear = if m.nonlinear {
            1.0
        } else {
            1.0 / (1.0 - m.internal_reflectance)
        };
        m.diffuse_scale = FRAC_1_PI / (m.eta * m.eta) * linear;
        Ok(m)
    }

    /// The relative index η = int_ior / ext_ior.
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// The coat's GGX distribution.
    pub fn distribution(&self) -> &Distribution {
        &self.dist
    }

    /// R_i = ∫₀¹ 2μ R_in(μ) dμ, the coat's reflectance from inside for
    /// diffuse light.
    pub fn internal_reflectance(&self) -> f64 {
        self.internal_reflectance
    }

    /// Probability weight of the specular lobe before the transmittance
    /// enters, 1 / (1 + mean ρ) (Mitsuba's `specular_sampling_weight`).
    pub fn specular_sampling_weight(&self) -> f64 {
        self.specular_weight
    }

    /// t(μ) from the table (linear between [`TRANSMITTANCE_NODES`] nodes).
    pub fn transmittance(&self, mu: f64) -> f64 {
        let x = mu.clamp(0.0, 1.0) * (TRANSMITTANCE_NODES - 1) as f64;
        // Through u32 (x ∈ [0, 63], or NaN → 0): a shorter instruction
        // sequence than the saturating f64 → usize.
        let i = (x as u32 as usize).min(TRANSMITTANCE_NODES - 2);
        let (a, b) = (self.transmittance[i], self.transmittance[i + 1]);
        a + (b - a) * (x - i as f64)
    }

    /// t(μ) by quadrature: the expected (1 − F) G1 over the normals visible
    /// from a direction of cosine μ, G1 of the refracted direction (light
    /// that refracts into a microfacet and is not masked on its way in).
    pub fn transmittance_at(&self, mu: f64) -> f64 {
        let wi = direction(mu);
        if !(wi.z > 0.0) {
            return 0.0;
        }
        integrate_unit_square::<16>(|u| {
            let m = self.dist.sample_visible(wi, u);
            let c = wi.dot(m);
            let (f, ct) = dielectric_reflectance(c, self.eta);
            if f >= 1.0 || c <= 0.0 {
                return 0.0;
            }
            // The refracted direction, mirrored to point up (G1 is even in it).
            let up = wi / self.eta - (c / self.eta - ct) * m;
            if up.z <= 0.0 {
                return 0.0;
            }
            (1.0 - f) * self.dist.g1(up.normalize())
        })
        .clamp(0.0, 1.0)
    }

    /// R_in(μ): the coat's reflectance from inside at incidence cosine μ,
    /// total reflection included, with the same visible-normal average.
    pub fn internal_reflectance_at(&self, mu: f64) -> f64 {
        let wi = direction(mu);
        if !(wi.z > 0.0) {
            return 0.0;
        }
        // Total reflection for wi·m below the critical cosine.
        let cos_critical = libm::sqrt(1.0 - 1.0 / (self.eta * self.eta));
        integrate_with_kinks(
            |u| {
                let m = self.dist.sample_visible(wi, u);
                let c = wi.dot(m);
                let wo = 2.0 * c * m - wi;
                if wo.z <= 0.0 || c <= 0.0 {
                    return 0.0;
                }
                dielectric_reflectance(c, 1.0 / self.eta).0 * self.dist.g1(wo)
            },
            |u| {
                let m = self.dist.sample_visible(wi, u);
                let c = wi.dot(m);
                [c - cos_critical, 2.0 * c * m.z - wi.z]
            },
        )
        .clamp(0.0, 1.0)
    }

    /// Probability that [`Bxdf::sample`] picks the coat's lobe at `cos_i`.
    pub fn specular_probability(&self, cos_i: f64) -> f64 {
        let t = self.transmittance(cos_i);
        let s = (1.0 - t) * self.specular_weight;
        let d = t * (1.0 - self.specular_weight);
        if s + d > 0.0 { s / (s + d) } else { 1.0 }
    }

    /// (f, pdf) for directions both above the surface.
    #[inline]
    fn eval_pdf_above(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        self.above(wi, wo).at(self, self.reflectance.at(lambda_nm))
    }

    /// `out[j]` = (f, pdf) at `lambdas[j]` from the λ-free part `above`.
    #[inline]
    fn fill(&self, above: &Above, lambdas: &[f64], out: &mut [(f64, f64)]) {
        match &self.reflectance {
            // One value for every wavelength: no lookup per λ.
            Reflectance::Constant(rho) => {
                let v = above.at(self, *rho);
                for o in out.iter_mut().take(lambdas.len()) {
                    *o = v;
                }
            }
            #[cfg(feature = "alloc")]
            Reflectance::Table(t) => {
                for (o, &l) in out.iter_mut().zip(lambdas) {
                    *o = above.at(self, t.at(l));
                }
            }
        }
    }

    /// What (f, pdf) above the surface shares between wavelengths: only the
    /// base's reflectance depends on λ, so hero wavelengths pay for the coat's
    /// D, G2, Fresnel and the transmittance lookups once.
    ///
    /// GGX's D, Λ(wi), Λ(wo) and the Fresnel factor are formed as fractions
    /// over the unnormalised half vector v = wi + wo (as the conductors form
    /// them, `microfacet/conductor.rs`), so that f_s takes one division and
    /// the pdf, lobe choice included, another: the textbook chain (normalise
    /// h, D, G2 from two Λ, G1, Fresnel, the lobe probability) took eleven.
    #[inline]
    fn above(&self, wi: DVec3, wo: DVec3) -> Above {
        let (t_i, t_o) = (self.transmittance(wi.z), self.transmittance(wo.z));
        let t_io = t_i * t_o * self.diffuse_scale;
        let c = self.choice(wi, wo, t_i);
        let Some((v, len2)) = c.coat else {
            return Above {
                f_s: 0.0,
                t_io,
                pdf: base_only_pdf(c.s, c.d, c.diffuse_pdf),
            };
        };
        let (d_num, d_den) = self.dist.ggx_d_fraction(v, len2);
        let (ai, di) = self.dist.ggx_lambda_frac(wi);
        let (ao, do_) = self.dist.ggx_lambda_frac(wo);
        // wi·h = (1 + wi·wo)/|v| = |v|/2.
        let (f_num, f_den) = fresnel_fraction((0.5 * libm::sqrt(len2)).min(1.0), self.eta);
        // F D G2 / (4 cosθi cosθo) with G2 = di do / (di do + ai do + ao di).
        let f_s = f_num * d_num * (di * do_)
            / (f_den * d_den * (di * do_ + ai * do_ + ao * di) * (4.0 * wi.z * wo.z));
        Above {
            f_s: finite_nonneg(f_s),
            t_io,
            pdf: mixed_pdf([c.s, c.d], c.diffuse_pdf, (d_num, d_den), (ai, di), wi.z),
        }
    }

    /// `above(wi, wo).pdf`, bit for bit, without what only f needs (the
    /// transmittance at wo, Λ(wo), Fresnel): a caller that wants the
    /// density alone (a resampled light sample's proxy) pays for it alone.
    #[inline]
    fn pdf_above(&self, wi: DVec3, wo: DVec3) -> f64 {
        let c = self.choice(wi, wo, self.transmittance(wi.z));
        let Some((v, len2)) = c.coat else {
            return base_only_pdf(c.s, c.d, c.diffuse_pdf);
        };
        let dh = self.dist.ggx_d_fraction(v, len2);
        let lambda_i = self.dist.ggx_lambda_frac(wi);
        mixed_pdf([c.s, c.d], c.diffuse_pdf, dh, lambda_i, wi.z)
    }

    /// What `above` and `pdf_above` both start from, given the
    /// transmittance `t_i` at wi.
    #[inline(always)]
    fn choice(&self, wi: DVec3, wo: DVec3, t_i: f64) -> Choice {
        let v = wi + wo;
        let len2 = v.length_squared();
        // The coat's products of Smith terms underflow near the horizon: as
        // for the conductors, it reflects nothing there.
        let coat = (wi.z >= COS_HORIZON && wo.z >= COS_HORIZON && len2 > 0.0 && len2.is_finite())
            .then_some((v, len2));
        Choice {
            s: (1.0 - t_i) * self.specular_weight,
            d: t_i * (1.0 - self.specular_weight),
            diffuse_pdf: wo.z * FRAC_1_PI,
            coat,
        }
    }
}

/// The lobe choice s : d of `specular_probability` at wi, the base's cosine
/// density at wo, and the unnormalised half vector v = wi + wo with |v|²
/// where the coat reflects (`None` this close to the horizon).
struct Choice {
    s: f64,
    d: f64,
    diffuse_pdf: f64,
    coat: Option<(DVec3, f64)>,
}

/// The density where the coat reflects nothing: the base's share `d` of the
/// lobe choice `s : d` times its cosine density.
#[inline(always)]
fn base_only_pdf(s: f64, d: f64, diffuse_pdf: f64) -> f64 {
    let pdf = if s + d > 0.0 {
        d / (s + d) * diffuse_pdf
    } else {
        0.0
    };
    finite_nonneg(pdf)
}

/// The coat's visible-normal density G1(wi) D(h) (wi·h) / cosθi times the
/// reflection Jacobian 1 / (4 wo·h) (wo·h = wi·h), G1 = di/(di + ai), mixed
/// with the base's cosine density by s : d; D and Λ(wi) as the fractions
/// (d_num, d_den) and (ai, di).
#[inline(always)]
fn mixed_pdf(
    [s, d]: [f64; 2],
    diffuse_pdf: f64,
    (d_num, d_den): (f64, f64),
    (ai, di): (f64, f64),
    cos_i: f64,
) -> f64 {
    let spec_den = d_den * (di + ai) * (4.0 * cos_i);
    let pdf = if s + d > 0.0 {
        (s * d_num * di + d * diffuse_pdf * spec_den) / ((s + d) * spec_den)
    } else {
        d_num * di / spec_den
    };
    finite_nonneg(pdf)
}

/// The dielectric Fresnel reflectance from outside at incidence cosine `c`
/// for η > 1 (no total reflection), as a fraction (num, den):
/// ½ (r_s² + r_p²) with r_s = (c − η c_t)/(c + η c_t), r_p = (η c − c_t)/(η c + c_t)
/// over their common denominator, so that its division joins f_s's.
#[inline(always)]
fn fresnel_fraction(c: f64, eta: f64) -> (f64, f64) {
    let sin2_t = (1.0 - c * c) / (eta * eta);
    let ct = libm::sqrt((1.0 - sin2_t).max(0.0));
    let (rs_n, rs_d) = (c - eta * ct, c + eta * ct);
    let (rp_n, rp_d) = (eta * c - ct, eta * c + ct);
    let (rs_d2, rp_d2) = (rs_d * rs_d, rp_d * rp_d);
    (
        0.5 * (rs_n * rs_n * rp_d2 + rp_n * rp_n * rs_d2),
        rs_d2 * rp_d2,
    )
}

/// The wavelength-independent part of [`RoughPlastic`]'s (f, pdf) at one
/// pair of directions above the surface.
struct Above {
    f_s: f64,
    /// t(cosθi) t(cosθo) / (π η²), times 1 / (1 − R_i) unless `nonlinear`.
    t_io: f64,
    pdf: f64,
}

impl Above {
    /// (f, pdf) for the base's reflectance `rho`.
    #[inline]
    fn at(&self, m: &RoughPlastic, rho: f64) -> (f64, f64) {
        let base = if m.nonlinear {
            rho / (1.0 - rho * m.internal_reflectance)
        } else {
            rho
        };
        (finite_nonneg(self.f_s + base * self.t_io), self.pdf)
    }
}

fn finite_nonneg(x: f64) -> f64 {
    if x.is_finite() && x > 0.0 { x } else { 0.0 }
}

impl Bxdf for RoughPlastic {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        self.eval_pdf(wi, wo, lambda_nm).0
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, _lambda_nm: f64) -> f64 {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.pdf_above(wi, wo)
        } else {
            0.0
        }
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.eval_pdf_above(wi, wo, lambda_nm)
        } else {
            (0.0, 0.0)
        }
    }

    fn eval_pdf_many(&self, wi: DVec3, wo: DVec3, lambdas: &[f64], out: &mut [(f64, f64)]) {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.fill(&self.above(wi, wo), lambdas, out);
        } else {
            for o in out.iter_mut().take(lambdas.len()) {
                *o = (0.0, 0.0);
            }
        }
    }

    /// `kept` is the sampled direction's [`Above`]: only the base's
    /// reflectance is looked up per λ.
    fn eval_pdf_many_kept(
        &self,
        wi: DVec3,
        wo: DVec3,
        kept: &Kept,
        lambdas: &[f64],
        out: &mut [(f64, f64)],
    ) {
        match kept.parts() {
            Some([f_s, t_io, pdf]) => self.fill(&Above { f_s, t_io, pdf }, lambdas, out),
            None => self.eval_pdf_many(wi, wo, lambdas, out),
        }
    }

    /// `u[0]` picks the coat (visible-normal sampling from `u[1]`, `u[2]`)
    /// with [`RoughPlastic::specular_probability`], else the base (cosine).
    #[inline]
    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        self.sample_kept(wi, lambda_nm, u).map(|(s, _)| s)
    }

    /// [`Bxdf::sample`], keeping the sampled direction's λ-free [`Above`].
    fn sample_kept(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<(BxdfSample, Kept)> {
        if !(wi.z > 0.0) {
            return None;
        }
        let wo = if u[0] < self.specular_probability(wi.z) {
            let m = self.dist.sample_visible(wi, [u[1], u[2]]);
            2.0 * wi.dot(m) * m - wi
        } else {
            sample_cosine_hemisphere([u[1], u[2]])
        };
        if !(wo.z > 0.0) {
            return None;
        }
        let wo = wo.normalize();
        let above = self.above(wi, wo);
        let (f, pdf) = above.at(self, self.reflectance.at(lambda_nm));
        (f > 0.0 && pdf > 0.0).then(|| {
            let s = BxdfSample {
                wo,
                weight: f * wo.z / pdf,
                pdf,
                is_delta: false,
            };
            (s, Kept::new([above.f_s, above.t_io, above.pdf]))
        })
    }

    /// The coat's peak D(n)/(4 cosθi) (bounds its visible-normal density)
    /// plus the base's 1/π, each times its probability.
    fn lobe_peak_pdf(&self, wi: DVec3) -> Option<f64> {
        (wi.z > 0.0).then(|| {
            let p_s = self.specular_probability(wi.z);
            p_s * self.dist.d_max() / (4.0 * wi.z) + (1.0 - p_s) * FRAC_1_PI
        })
    }
}
