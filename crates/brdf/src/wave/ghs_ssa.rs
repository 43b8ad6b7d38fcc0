//! GHS smooth-surface approximation (physics.md §3.2 "SSA (paper)"):
//!
//! f(i,o) = R_s A_s δ_ω(o − s)/cosθo + R·(1 − e^{−g(i,o)})·k²·P(ζ)/σ²,
//! A_s = exp(−(2kσ cosθi)²), g(i,o) = [kσ(cosθi + cosθo)]², ζ = k(o⊥ + i⊥).
//!
//! The scattered lobe is sampled exactly from P/σ² (the radial inverse CDF),
//! so its pdf is k² cosθo P(ζ)/σ² and the weight is R(1 − e^{−g}) (× the
//! energy factor). The delta and the lobe are chosen in proportion to
//! R_s A_s and R_s(1 − A_s).

use glam::DVec3;

use super::energy::{Energy, EnergyTable, GhsOptions, hemispherical_integral, in_disk_fraction};
use super::polarization::{Medium, Polarization, PolarizationFactor};
use super::{Geometry, direction_from_u, wavenumber};
use crate::fresnel::Fresnel;
use crate::model::{Bxdf, BxdfSample, Specular, WAVELENGTH_MAX_NM, WAVELENGTH_MIN_NM};
use crate::numerics::math::finite_nonneg;
use crate::statistics::{KcPsd, RadialPsd};
use crate::{BrdfError, frame};

/// Least probability with which a GHS sample draws the delta lobe (see
/// [`GhsCommon::choice`]).
pub const DELTA_PROBABILITY_MIN: f64 = 0.05;

/// Coherent fraction A_s from which the floor [`DELTA_PROBABILITY_MIN`]
/// applies: below it the coherent reflection is invisible even of the sun
/// (~10⁶ × the sky), and drawing it would only waste samples.
const DELTA_FLOOR_FROM: f64 = 1e-12;

/// Which lobe a GHS sample draws (see [`GhsCommon::choose_lobe`]).
pub(crate) enum LobeChoice {
    /// The delta lobe was drawn (`None`: it reflects nothing at this λ).
    Delta(Option<BxdfSample>),
    /// The glossy lobe was drawn; `v` is the choice number rescaled to [0, 1).
    // Read only by the full GHS model, which needs `alloc`.
    #[cfg_attr(not(feature = "alloc"), allow(dead_code))]
    Glossy { v: f64, gs: f64 },
}

/// Reflectance, specular weight and energy factor shared by the GHS models.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GhsCommon {
    pub fresnel: Fresnel,
    pub opts: GhsOptions,
    /// Krywonos: the raw scattered albedo a_s(θi, λ); SigmaRel: the
    /// in-disk fraction σ_rel²/σ².
    pub energy_table: Option<EnergyTable>,
    /// SigmaRel only: the scattered albedo with σ_rel, from which the factor
    /// ≤ 1 that keeps A_s + scattered ≤ 1 is formed.
    pub cap_table: Option<EnergyTable>,
    pub sigma: f64,
    pub length: f64,
}

impl GhsCommon {
    /// σ used in A_s and g for this incidence: σ_rel under [`Energy::SigmaRel`].
    #[inline]
    pub fn sigma_eff(&self, ci: f64, lambda_nm: f64) -> f64 {
        match (self.opts.energy, &self.energy_table) {
            (Energy::SigmaRel, Some(t)) => {
                self.sigma * libm::sqrt(t.at(ci, lambda_nm).clamp(0.0, 1.0))
            }
            _ => self.sigma,
        }
    }

    /// Multiplier of the scattered part: Krywonos K = (1 − A_s)/a_s, the
    /// σ_rel cap min(1, (1 − A_s)/a_s), 1 otherwise.
    ///
    /// The tables hold the albedo a_s, and 1 − A_s is formed here exactly:
    /// near grazing 1 − A_s → 0 as cos²θi while a_s stays finite, so their
    /// ratio changes far faster than either, and interpolating the ratio
    /// would leave the renormalised albedo 2.6 % above 1 at 89°.
    #[inline]
    pub fn scatter_factor(&self, ci: f64, lambda_nm: f64) -> f64 {
        let loss = |sigma: f64| {
            let t = 2.0 * wavenumber(lambda_nm) * sigma * ci;
            -libm::expm1(-t * t)
        };
        match (self.opts.energy, &self.energy_table, &self.cap_table) {
            (Energy::Krywonos, Some(t), _) => {
                let (b, a) = (loss(self.sigma), t.at(ci, lambda_nm));
                if a > 1e-6 * b { b / a } else { 0.0 }
            }
            (Energy::SigmaRel, _, Some(c)) => {
                let (b, a) = (loss(self.sigma_eff(ci, lambda_nm)), c.at(ci, lambda_nm));
                if a > b { b / a } else { 1.0 }
            }
            _ => 1.0,
        }
    }

    /// Reflectance factor of the scattered part: R at the angle of
    /// `fresnel_angle`, or the Rayleigh–Rice Q times the obliquity ratio
    /// 4 cosθi cosθo/(cosθi + cosθo)² (physics.md §13.2), for the incident
    /// polarisation.
    #[inline]
    pub fn r_scatter(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        let pol = self.opts.polarization;
        match self.opts.polarization_factor {
            PolarizationFactor::R => {
                let c = match self.opts.fresnel_angle {
                    super::FresnelAngle::Halfway => {
                        libm::sqrt((0.5 * (1.0 + wi.dot(wo))).clamp(0.0, 1.0))
                    }
                    super::FresnelAngle::Incident => wi.z,
                };
                self.reflectance(c, lambda_nm)
            }
            PolarizationFactor::Q => {
                let (ci, co) = (wi.z.max(0.0), wo.z.max(0.0));
                let sum = ci + co;
                if !(sum > 0.0) {
                    return 0.0;
                }
                let q = Medium::of(&self.fresnel, lambda_nm).q_factor(wi, wo, pol);
                q * (4.0 * ci * co / (sum * sum))
            }
        }
    }

    /// Fresnel reflectance of the incident polarisation at incidence cosine
    /// `c` (the unpolarised one through [`Fresnel::reflectance`]).
    #[inline]
    pub fn reflectance(&self, c: f64, lambda_nm: f64) -> f64 {
        match self.opts.polarization {
            Polarization::Unpolarized => self.fresnel.reflectance(c, lambda_nm),
            pol => Medium::of(&self.fresnel, lambda_nm).reflectance(c, pol),
        }
    }

    /// (probability of choosing the delta lobe, specular exponent g_s).
    ///
    /// The delta lobe carries R_s A_s with A_s = e^{−g_s}. It is chosen with
    /// probability max(A_s, [`DELTA_PROBABILITY_MIN`]) (A_s itself below
    /// 1e−12), not A_s: when A_s is
    /// tiny (rough surfaces, short λ) the coherent reflection of a bright,
    /// small light is a rare event of weight R_s and probability A_s, whose
    /// relative variance 1/A_s dominated the s138 full-GHS images (one
    /// camera sample at ~1 300× its pixel's mean, with A_s ≈ 2·10⁻⁵). The
    /// floor bounds that variance at the price of a few glossy samples; the
    /// glossy pdf carries 1 − p, so both lobes stay unbiased.
    #[inline]
    pub fn choice(&self, ci: f64, lambda_nm: f64) -> (f64, f64) {
        let (p, _, gs) = self.choice_coherent(ci, lambda_nm);
        (p, gs)
    }

    /// (delta probability [`choice`](Self::choice), A_s = e^{−g_s}, g_s).
    #[inline]
    pub fn choice_coherent(&self, ci: f64, lambda_nm: f64) -> (f64, f64, f64) {
        let t = 2.0 * wavenumber(lambda_nm) * self.sigma_eff(ci, lambda_nm) * ci;
        let gs = t * t;
        let a_s = crate::numerics::math::exp(-gs);
        let p = if a_s >= DELTA_FLOOR_FROM {
            a_s.max(DELTA_PROBABILITY_MIN)
        } else {
            a_s
        };
        (p, a_s, gs)
    }

    /// The delta lobe at `wi` (zero below the horizon).
    #[inline]
    pub fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        if !(wi.z > 0.0) {
            return Specular::default();
        }
        let (weight, probability, _) = self.specular_and_choice(wi.z.min(1.0), lambda_nm);
        Specular {
            weight: finite_nonneg(weight),
            probability,
        }
    }

    /// The shared part of a model over a surface of RMS height `sigma` and
    /// correlation length `length` (µm), before its energy tables are built.
    pub fn new(fresnel: Fresnel, opts: GhsOptions, sigma: f64, length: f64) -> GhsCommon {
        GhsCommon {
            fresnel,
            opts,
            energy_table: None,
            cap_table: None,
            sigma,
            length,
        }
    }

    /// Draws the delta lobe with probability [`choice`](Self::choice) from `u0`: its
    /// sample (`None` when R_s A_s = 0), or the glossy lobe's turn with `u0`
    /// rescaled to [0, 1) and g_s.
    #[inline]
    pub fn choose_lobe(&self, wi: DVec3, lambda_nm: f64, u0: f64) -> LobeChoice {
        let (p_delta, a_s, gs) = self.choice_coherent(wi.z.min(1.0), lambda_nm);
        if u0 >= p_delta {
            return LobeChoice::Glossy {
                v: (u0 - p_delta) / (1.0 - p_delta),
                gs,
            };
        }
        let spec = self.reflectance(wi.z.min(1.0), lambda_nm) * a_s;
        LobeChoice::Delta((spec > 0.0).then(|| BxdfSample {
            wo: frame::reflect_z(wi),
            weight: spec / p_delta,
            pdf: p_delta,
            is_delta: true,
        }))
    }

    /// A sample of a first-order lobe (the SSA, Rayleigh–Rice), whose glossy directions
    /// follow the PSD's radial CDF in u = |ζ|L: the delta lobe with its probability, else a
    /// direction drawn from `psd` and its `(f, pdf)` from `eval_pdf`.
    #[inline]
    pub fn sample_first_order(
        &self,
        psd: &impl RadialPsd,
        wi: DVec3,
        lambda_nm: f64,
        u: [f64; 3],
        eval_pdf: impl Fn(DVec3) -> (f64, f64),
    ) -> Option<BxdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        if let LobeChoice::Delta(s) = self.choose_lobe(wi, lambda_nm, u[0]) {
            return s;
        }
        let kl = wavenumber(lambda_nm) * self.length;
        let uu = psd.sample_u(u[1]);
        let wo = direction_from_u(wi, kl, uu, 2.0 * core::f64::consts::PI * u[2])?;
        super::glossy_sample(wo, eval_pdf(wo))
    }

    /// (specular weight R_s A_s, delta probability, g_s).
    pub fn specular_and_choice(&self, ci: f64, lambda_nm: f64) -> (f64, f64, f64) {
        let (p, a_s, gs) = self.choice_coherent(ci, lambda_nm);
        (self.reflectance(ci, lambda_nm) * a_s, p, gs)
    }

    /// Builds the energy tables for `opts.energy`. `raw_albedo(c, θi, λ)`
    /// must return the scattered albedo of the model's raw lobe evaluated
    /// with the settings `c` (whose Fresnel term is R ≡ 1: times
    /// `c.r_scatter`, which is 1 for the scalar factor and the perfect
    /// conductor's Q for the Rayleigh–Rice one), without the scatter factor.
    pub fn build_table(
        &mut self,
        cdf_u: impl Fn(f64) -> f64 + Sync,
        raw_albedo: impl Fn(&GhsCommon, f64, f64) -> f64 + Sync,
    ) {
        let probe = GhsCommon {
            fresnel: Fresnel::One,
            opts: GhsOptions {
                energy: self.opts.energy,
                polarization: self.opts.polarization,
                polarization_factor: self.opts.polarization_factor,
                ..GhsOptions::default()
            },
            energy_table: None,
            cap_table: None,
            ..self.clone()
        };
        match self.opts.energy {
            Energy::Raw => {}
            Energy::SigmaRel => {
                let l = self.length;
                let frac = EnergyTable::build(|th, lam| {
                    in_disk_fraction(libm::sin(th), wavenumber(lam) * l, &cdf_u)
                });
                let probe = GhsCommon {
                    energy_table: Some(frac.clone()),
                    ..probe
                };
                // Cap: where σ_rel still leaves a total above 1 (the grazing
                // gain of physics.md §5), the scattered part is scaled down to
                // 1 − A_s (see `scatter_factor`); elsewhere left untouched.
                let cap = EnergyTable::build_log(|th, lam| raw_albedo(&probe, th, lam));
                self.energy_table = Some(frac);
                self.cap_table = Some(cap);
            }
            Energy::Krywonos => {
                let probe = GhsCommon {
                    opts: GhsOptions {
                        energy: Energy::Raw,
                        ..probe.opts
                    },
                    ..probe
                };
                self.energy_table = Some(EnergyTable::build_log(|th, lam| {
                    raw_albedo(&probe, th, lam)
                }));
            }
        }
    }
}

/// The GHS smooth-surface approximation driven by a radial PSD.
#[derive(Clone, Debug, PartialEq)]
pub struct GhsSsa<P: RadialPsd = KcPsd> {
    psd: P,
    common: GhsCommon,
}

impl<P: RadialPsd> GhsSsa<P> {
    /// Raw energy, Fresnel at the halfway angle.
    pub fn new(psd: P, fresnel: Fresnel) -> Result<Self, BrdfError> {
        Self::with_options(psd, fresnel, GhsOptions::default())
    }

    /// With explicit energy and Fresnel-angle options. [`Energy::Krywonos`]
    /// integrates the raw scattered albedo on a 96 × 16 (θi, λ) grid at
    /// build time (one hemispherical integral per node; rows in parallel
    /// with `std`).
    pub fn with_options(psd: P, fresnel: Fresnel, opts: GhsOptions) -> Result<Self, BrdfError> {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        let common = GhsCommon::new(fresnel, opts, psd.sigma_um(), psd.length_um());
        let mut model = GhsSsa { psd, common };
        let mut common = model.common.clone();
        common.build_table(
            |u| model.psd.cdf_u(u),
            |c, th, lam| {
                let wi = frame::spherical(th, 0.0);
                let kl = wavenumber(lam) * c.length;
                hemispherical_integral(wi, 1.0 / kl, |o| {
                    raw_lobe(&model.psd, c, wi, o, lam) * c.r_scatter(wi, o, lam)
                })
            },
        );
        model.common = common;
        Ok(model)
    }

    /// The same surface under another Fresnel term. No table depends on the
    /// Fresnel factor (the energy tables integrate the lobe with R = 1), so
    /// they are shared instead of rebuilt: the result equals
    /// `with_options(psd, fresnel, opts)` exactly, at the cost of a clone.
    pub fn with_fresnel(&self, fresnel: Fresnel) -> Result<Self, BrdfError>
    where
        P: Clone,
    {
        fresnel.check_covers(WAVELENGTH_MIN_NM, WAVELENGTH_MAX_NM)?;
        let mut m = self.clone();
        m.common.fresnel = fresnel;
        Ok(m)
    }

    /// The surface PSD.
    pub fn psd(&self) -> &P {
        &self.psd
    }

    /// The options in use.
    pub fn options(&self) -> GhsOptions {
        self.common.opts
    }
}

/// R = 1, unrenormalised scattered lobe (1 − e^{−g}) k² L² p(u).
fn raw_lobe<P: RadialPsd>(psd: &P, c: &GhsCommon, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
    let Some(geo) = Geometry::new(wi, wo, lambda_nm, c.length) else {
        return 0.0;
    };
    let s = c.sigma_eff(geo.ci, lambda_nm);
    let t = geo.k * s * (geo.ci + geo.co);
    let kl = geo.k * c.length;
    -libm::expm1(-t * t) * kl * kl * psd.unit_psd_u(libm::sqrt(geo.u2))
}

impl<P: RadialPsd> Bxdf for GhsSsa<P> {
    fn eval(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        let f = raw_lobe(&self.psd, &self.common, wi, wo, lambda_nm);
        if f == 0.0 {
            return 0.0;
        }
        finite_nonneg(
            f * self.common.r_scatter(wi, wo, lambda_nm)
                * self.common.scatter_factor(wi.z, lambda_nm),
        )
    }

    fn pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> f64 {
        let Some(geo) = Geometry::new(wi, wo, lambda_nm, self.common.length) else {
            return 0.0;
        };
        let (p_delta, _) = self.common.choice(geo.ci, lambda_nm);
        let kl = geo.k * self.common.length;
        finite_nonneg((1.0 - p_delta) * kl * kl * geo.co * self.psd.unit_psd_u(libm::sqrt(geo.u2)))
    }

    fn eval_pdf(&self, wi: DVec3, wo: DVec3, lambda_nm: f64) -> (f64, f64) {
        let Some(geo) = Geometry::new(wi, wo, lambda_nm, self.common.length) else {
            return (0.0, 0.0);
        };
        let (p_delta, _) = self.common.choice(geo.ci, lambda_nm);
        let kl = geo.k * self.common.length;
        let lobe = kl * kl * self.psd.unit_psd_u(libm::sqrt(geo.u2));
        let pdf = finite_nonneg((1.0 - p_delta) * geo.co * lobe);
        let s = self.common.sigma_eff(geo.ci, lambda_nm);
        let t = geo.k * s * (geo.ci + geo.co);
        let f = -libm::expm1(-t * t) * lobe;
        if f == 0.0 {
            return (0.0, pdf);
        }
        let f = finite_nonneg(
            f * self.common.r_scatter(wi, wo, lambda_nm)
                * self.common.scatter_factor(geo.ci, lambda_nm),
        );
        (f, pdf)
    }

    fn sample(&self, wi: DVec3, lambda_nm: f64, u: [f64; 3]) -> Option<BxdfSample> {
        self.common
            .sample_first_order(&self.psd, wi, lambda_nm, u, |wo| {
                self.eval_pdf(wi, wo, lambda_nm)
            })
    }

    fn specular(&self, wi: DVec3, lambda_nm: f64) -> Specular {
        self.common.specular(wi, lambda_nm)
    }
}
