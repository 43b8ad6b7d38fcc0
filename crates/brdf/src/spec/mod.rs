//! One description of a material for every entry point: a typed
//! [`MaterialSpec`] (which model, its parameters, its Fresnel term) with
//! validation and [`MaterialSpec::build`], and — with the `serde` feature —
//! the flat key/value schema [`MaterialDesc`] that scene files, `brdf eval`
//! queries and `lustre fit` material files all use.
//!
//! ```text
//! MaterialDesc (keys as written)  --into_spec-->  MaterialSpec  --build-->  Box<dyn Bxdf>
//!            ^---------------------to_desc-------------'
//! ```
//!
//! Keys of the flat schema (every entry point, every model):
//!
//! | key | models | meaning |
//! |---|---|---|
//! | `model` | all | `ggx`, `beckmann`, `smooth`, `ghs_ssa`, `ghs`, `two_scale`, `measured_psd`, `rayleigh_rice`, `ghs_ssa_aniso`, `ghs_aniso` |
//! | `metal` / `nk` / `nk_csv` | all | built-in metal, constant `[n, k]`, or a CSV `wavelength_nm,n,k` |
//! | `fresnel` | all | `conductor` (default) or `one` (R ≡ 1; alias `none`) |
//! | `alpha`, or `alpha_x` + `alpha_y` | ggx, beckmann | roughness (x along the surface tangent) |
//! | `alpha_beckmann` | beckmann | used in preference to `alpha` (a fit file serves both models) |
//! | `sigma_um`, `lc_um`, `gamma` | ghs_ssa, ghs, two_scale, rayleigh_rice | K-correlation σ (µm), Lc (µm), γ |
//! | `sigma_um`, `lx_um`, `ly_um`, `angle_deg`, `gamma` | ghs_ssa_aniso, ghs_aniso | anisotropic K-correlation: Lx along the axis at `angle_deg` (from the tangent x towards y; default 0), Ly across it |
//! | `energy` | ghs_ssa, ghs, measured_psd (the `_aniso` models: `raw` only) | `raw` (default), `krywonos`, `sigma_rel` |
//! | `fresnel_angle` | ghs_ssa, ghs, measured_psd, `_aniso` | `halfway` (default) or `incident` |
//! | `polarization` | ghs_ssa, ghs, measured_psd, rayleigh_rice, `_aniso` | `unpolarized` (default), `s`, `p` (incident; both scattered polarisations summed) |
//! | `polarization_factor` | ghs_ssa, ghs, measured_psd, `_aniso` | `r` (default: scalar Fresnel R) or `q` (Rayleigh–Rice Q, physics.md §13.2) |
//! | `psd_csv` | measured_psd, rayleigh_rice | CSV `zeta_rad_per_um,p_um4` (rayleigh_rice: in place of the K-correlation keys, which must then not be set) |
//! | `beta`, `coherent` | two_scale | macro NDF width β; `macro_ndf` (default) or `delta` |
//! | `include`, `cutoff` | all | a `lustre fit` material file and its two-scale split (resolved by the caller) |
//!
//! File references (`nk_csv`, `psd_csv`, `include`) are resolved by the
//! caller, which reads the files: this crate does no I/O. A key a model does
//! not use is an error naming the key, so a misspelt or misplaced parameter
//! never falls back to a default silently.
//!
//! ```
//! use brdf::spec::{FresnelSpec, KcSpec, MaterialSpec, ModelSpec};
//! use brdf::wave::GhsOptions;
//! use brdf::Bxdf;
//!
//! // The paper's S280 (brass, σ 0.28 µm, Lc 5 µm, γ 3) under full GHS.
//! let s280 = MaterialSpec {
//!     model: ModelSpec::Ghs {
//!         surface: KcSpec { sigma_um: 0.28, lc_um: 5.0, gamma: 3.0 },
//!         options: GhsOptions::default(),
//!     },
//!     fresnel: FresnelSpec::Metal(brdf::Metal::BrassCu70Zn30),
//! };
//! let model = s280.build()?;
//! let wi = brdf::frame::spherical(0.5, 0.0);
//! let wo = brdf::frame::spherical(0.5, core::f64::consts::PI);
//! assert!(model.eval(wi, wo, 550.0) > 0.0);
//!
//! // A parameter out of range names its key.
//! let bad = MaterialSpec {
//!     model: ModelSpec::Ghs {
//!         surface: KcSpec { sigma_um: 0.28, lc_um: 5.0, gamma: 0.5 },
//!         options: GhsOptions::default(),
//!     },
//!     ..s280
//! };
//! assert_eq!(bad.build().err().unwrap().field, "gamma");
//! # Ok::<(), brdf::spec::SpecError>(())
//! ```

use alloc::boxed::Box;
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use crate::statistics::TabulatedPsd;
use crate::statistics::anisotropic::AnisotropicKc;
use crate::statistics::kc::KcPsd;
use crate::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use crate::wave::{GhsAnisotropic, GhsFull, GhsOptions, GhsSsa, Polarization, RayleighRice};
use crate::{
    BrdfError, Bxdf, Distribution, Fresnel, Ior, Metal, MicrofacetConductor, SmoothConductor,
};

/// A built model, shareable across threads.
pub type DynBxdf = Box<dyn Bxdf + Send + Sync>;

/// Why a description does not make a material: the key to fix and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{field}`: {message}")]
pub struct SpecError {
    /// The key as the user writes it (`sigma_um`, `model`, …).
    pub field: &'static str,
    /// What is wrong and what is valid.
    pub message: String,
}

impl SpecError {
    /// An error on `field`.
    pub fn new(field: &'static str, message: impl Into<String>) -> SpecError {
        SpecError {
            field,
            message: message.into(),
        }
    }
}

impl From<BrdfError> for SpecError {
    fn from(e: BrdfError) -> SpecError {
        let field = match &e {
            BrdfError::OutOfRange { name, .. } => name,
            BrdfError::WavelengthOutOfRange { .. } => "lambda_nm",
            BrdfError::InvalidTable { .. } => "table",
        };
        SpecError::new(field, e.to_string())
    }
}

/// The reflection models.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum ModelKind {
    /// GGX / Trowbridge–Reitz microfacet conductor.
    Ggx,
    /// Beckmann microfacet conductor.
    Beckmann,
    /// Perfect mirror.
    Smooth,
    /// GHS smooth-surface approximation with a K-correlation PSD.
    GhsSsa,
    /// Full GHS with a K-correlation PSD.
    Ghs,
    /// Full GHS with a tabulated (measured) PSD.
    MeasuredPsd,
    /// Holzschuch–Pacanowski two-scale model.
    TwoScale,
    /// Rayleigh–Rice (first-order vector perturbation theory), KC or measured PSD.
    RayleighRice,
    /// GHS smooth-surface approximation of an anisotropic K-correlation surface.
    GhsSsaAniso,
    /// Full GHS of an anisotropic K-correlation surface.
    GhsAniso,
}

impl ModelKind {
    /// Every model, in the order the documentation lists them.
    pub const ALL: [ModelKind; 10] = [
        ModelKind::Ggx,
        ModelKind::Beckmann,
        ModelKind::Smooth,
        ModelKind::GhsSsa,
        ModelKind::Ghs,
        ModelKind::TwoScale,
        ModelKind::MeasuredPsd,
        ModelKind::RayleighRice,
        ModelKind::GhsSsaAniso,
        ModelKind::GhsAniso,
    ];

    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Ggx => "ggx",
            ModelKind::Beckmann => "beckmann",
            ModelKind::Smooth => "smooth",
            ModelKind::GhsSsa => "ghs_ssa",
            ModelKind::Ghs => "ghs",
            ModelKind::MeasuredPsd => "measured_psd",
            ModelKind::TwoScale => "two_scale",
            ModelKind::RayleighRice => "rayleigh_rice",
            ModelKind::GhsSsaAniso => "ghs_ssa_aniso",
            ModelKind::GhsAniso => "ghs_aniso",
        }
    }

    /// The model of a file name.
    pub fn from_name(name: &str) -> Option<ModelKind> {
        ModelKind::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether the model depends on the wavelength only through one
    /// conductor Fresnel factor at the reflecting microfacet:
    /// `f(wi, wo, λ) = F(λ, cosθd) · f₁(wi, wo)`, where `f₁` is the same
    /// model built with [`FresnelSpec::One`] and cosθd = wi·h =
    /// |wi + wo| / 2; its sampled directions and pdfs do not depend on λ,
    /// and a sample's weight is F(λ, cosθd) times `f₁`'s (for the delta
    /// lobe of `smooth`, cosθd = cosθi). A renderer can then integrate a
    /// single-scattering contribution over λ exactly instead of sampling it.
    /// False for the wave-optical models, whose lobes change with λ.
    pub fn fresnel_only(self) -> bool {
        matches!(
            self,
            ModelKind::Ggx | ModelKind::Beckmann | ModelKind::Smooth
        )
    }

    /// `ggx, beckmann, …` for error messages.
    pub fn names() -> String {
        let names: Vec<&str> = ModelKind::ALL.iter().map(|m| m.name()).collect();
        names.join(", ")
    }
}

/// K-correlation surface statistics (physics.md §2), validated as
/// [`KcPsd::new`]: σ ∈ [0, 10] µm, Lc ∈ [0.03, 1000] µm, γ ∈ [1.001, 100].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KcSpec {
    /// rms height σ, µm.
    pub sigma_um: f64,
    /// Correlation (Matérn range) length Lc, µm.
    pub lc_um: f64,
    /// Spectral exponent γ.
    pub gamma: f64,
}

impl KcSpec {
    /// The PSD, or the range error naming the parameter.
    pub fn psd(&self) -> Result<KcPsd, BrdfError> {
        KcPsd::new(self.sigma_um, self.lc_um, self.gamma)
    }
}

/// Anisotropic K-correlation statistics (physics.md §15), validated as
/// [`AnisotropicKc::new`]: σ ∈ [0, 10] µm, Lx, Ly ∈ [0.03, 1000] µm,
/// γ ∈ [1.001, 100].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnisoSpec {
    /// rms height σ, µm.
    pub sigma_um: f64,
    /// Correlation length along the axis at `angle_deg`, µm.
    pub lx_um: f64,
    /// Correlation length across it, µm.
    pub ly_um: f64,
    /// Axis angle from the tangent x towards y, degrees.
    pub angle_deg: f64,
    /// Spectral exponent γ.
    pub gamma: f64,
}

impl AnisoSpec {
    /// The PSD, or the range error naming the parameter.
    pub fn psd(&self) -> Result<AnisotropicKc, BrdfError> {
        AnisotropicKc::new(
            self.sigma_um,
            self.lx_um,
            self.ly_um,
            self.angle_deg.to_radians(),
            self.gamma,
        )
    }
}

/// The PSD of a Rayleigh–Rice material: K-correlation or tabulated.
#[derive(Clone, Debug, PartialEq)]
pub enum RrSurface {
    /// K-correlation statistics.
    Kc(KcSpec),
    /// A tabulated (measured) PSD.
    Measured {
        /// Radial frequencies ζ, rad/µm, strictly increasing.
        zeta_rad_per_um: Vec<f64>,
        /// PSD values P(ζ), µm⁴.
        psd_um4: Vec<f64>,
    },
}

/// A model and its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSpec {
    /// GGX with roughness α along x (surface tangent) and y.
    Ggx {
        /// α along the tangent.
        alpha_x: f64,
        /// α along the bitangent.
        alpha_y: f64,
    },
    /// Beckmann with roughness α along x and y.
    Beckmann {
        /// α along the tangent.
        alpha_x: f64,
        /// α along the bitangent.
        alpha_y: f64,
    },
    /// A perfect mirror.
    Smooth,
    /// GHS smooth-surface approximation.
    GhsSsa {
        /// The surface.
        surface: KcSpec,
        /// Energy and Fresnel-angle switches.
        options: GhsOptions,
    },
    /// Full GHS.
    Ghs {
        /// The surface.
        surface: KcSpec,
        /// Energy and Fresnel-angle switches.
        options: GhsOptions,
    },
    /// Full GHS with a tabulated PSD.
    MeasuredPsd {
        /// Radial frequencies ζ, rad/µm, strictly increasing.
        zeta_rad_per_um: Vec<f64>,
        /// PSD values P(ζ), µm⁴.
        psd_um4: Vec<f64>,
        /// Energy and Fresnel-angle switches.
        options: GhsOptions,
    },
    /// Two-scale: exponential macro NDF of width β, KC micro scale.
    TwoScale {
        /// Macro NDF width β.
        beta: f64,
        /// The micro-scale surface.
        surface: KcSpec,
        /// Where the coherent part goes.
        coherent: CoherentPart,
    },
    /// Rayleigh–Rice for a conductor.
    RayleighRice {
        /// The surface PSD.
        surface: RrSurface,
        /// Incident polarisation.
        polarization: Polarization,
    },
    /// GHS smooth-surface approximation, anisotropic K-correlation surface.
    GhsSsaAniso {
        /// The surface.
        surface: AnisoSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
    /// Full GHS, anisotropic K-correlation surface.
    GhsAniso {
        /// The surface.
        surface: AnisoSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
}

impl ModelSpec {
    /// Which model this is.
    pub fn kind(&self) -> ModelKind {
        match self {
            ModelSpec::Ggx { .. } => ModelKind::Ggx,
            ModelSpec::Beckmann { .. } => ModelKind::Beckmann,
            ModelSpec::Smooth => ModelKind::Smooth,
            ModelSpec::GhsSsa { .. } => ModelKind::GhsSsa,
            ModelSpec::Ghs { .. } => ModelKind::Ghs,
            ModelSpec::MeasuredPsd { .. } => ModelKind::MeasuredPsd,
            ModelSpec::TwoScale { .. } => ModelKind::TwoScale,
            ModelSpec::RayleighRice { .. } => ModelKind::RayleighRice,
            ModelSpec::GhsSsaAniso { .. } => ModelKind::GhsSsaAniso,
            ModelSpec::GhsAniso { .. } => ModelKind::GhsAniso,
        }
    }

    /// The KC surface of the wave-optical models.
    pub fn surface(&self) -> Option<KcSpec> {
        match self {
            ModelSpec::GhsSsa { surface, .. }
            | ModelSpec::Ghs { surface, .. }
            | ModelSpec::TwoScale { surface, .. }
            | ModelSpec::RayleighRice {
                surface: RrSurface::Kc(surface),
                ..
            } => Some(*surface),
            _ => None,
        }
    }
}

/// The Fresnel term of a conductor.
#[derive(Clone, Debug, PartialEq)]
pub enum FresnelSpec {
    /// R ≡ 1 (furnace tests).
    One,
    /// A built-in metal's measured n + ik.
    Metal(Metal),
    /// A constant n + ik.
    Constant {
        /// Real part n.
        n: f64,
        /// Extinction κ.
        k: f64,
    },
    /// A table of (λ nm, n, κ) rows.
    Table(Vec<[f64; 3]>),
}

impl FresnelSpec {
    /// The Fresnel factor.
    pub fn build(&self) -> Result<Fresnel, BrdfError> {
        Ok(match self {
            FresnelSpec::One => Fresnel::One,
            FresnelSpec::Metal(m) => Fresnel::conductor(Ior::metal(*m)),
            FresnelSpec::Constant { n, k } => Fresnel::conductor(Ior::constant(*n, *k)?),
            FresnelSpec::Table(rows) => Fresnel::conductor(Ior::table(rows.clone())?),
        })
    }
}

/// A complete material: model and Fresnel term.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    /// The model and its parameters.
    pub model: ModelSpec,
    /// The Fresnel term.
    pub fresnel: FresnelSpec,
}

impl MaterialSpec {
    /// Checks every parameter against its model's accepted range without
    /// building tables (cheap: what `lustre fit` runs on what it writes).
    pub fn validate(&self) -> Result<(), SpecError> {
        self.fresnel.build()?;
        match &self.model {
            ModelSpec::Ggx { alpha_x, alpha_y } => {
                Distribution::ggx(*alpha_x, *alpha_y)?;
            }
            ModelSpec::Beckmann { alpha_x, alpha_y } => {
                Distribution::beckmann(*alpha_x, *alpha_y)?;
            }
            ModelSpec::Smooth => {}
            ModelSpec::GhsSsa { surface, .. } | ModelSpec::Ghs { surface, .. } => {
                let psd = surface.psd()?;
                if self.model.kind() == ModelKind::Ghs
                    && psd.gamma() < crate::statistics::kc::GAMMA_MIN_FULL
                {
                    return Err(SpecError::new(
                        "gamma",
                        format!(
                            "{} is below {} for the full GHS (its lobe spans more decades than \
                             f64 holds); use ghs_ssa",
                            psd.gamma(),
                            crate::statistics::kc::GAMMA_MIN_FULL
                        ),
                    ));
                }
            }
            ModelSpec::MeasuredPsd {
                zeta_rad_per_um,
                psd_um4,
                ..
            } => {
                TabulatedPsd::new(zeta_rad_per_um, psd_um4)
                    .map_err(|e| SpecError::new("psd", e.to_string()))?;
            }
            ModelSpec::TwoScale { beta, surface, .. } => {
                crate::statistics::epd::ExponentialNdf::new(*beta)?;
                surface.psd()?;
            }
            ModelSpec::RayleighRice { surface, .. } => match surface {
                RrSurface::Kc(kc) => {
                    kc.psd()?;
                }
                RrSurface::Measured {
                    zeta_rad_per_um,
                    psd_um4,
                } => {
                    TabulatedPsd::new(zeta_rad_per_um, psd_um4)
                        .map_err(|e| SpecError::new("psd", e.to_string()))?;
                }
            },
            ModelSpec::GhsSsaAniso { surface, options }
            | ModelSpec::GhsAniso { surface, options } => {
                let psd = surface.psd()?;
                if options.energy != crate::wave::Energy::Raw {
                    return Err(SpecError::new(
                        "energy",
                        "the anisotropic models take `energy = \"raw\"` only (the krywonos and \
                         sigma_rel tables are over θi and λ; an anisotropic lobe also depends on \
                         the incidence azimuth)",
                    ));
                }
                if self.model.kind() == ModelKind::GhsAniso
                    && psd.gamma() < crate::statistics::kc::GAMMA_MIN_FULL
                {
                    return Err(SpecError::new(
                        "gamma",
                        format!(
                            "{} is below {} for the full GHS; use ghs_ssa_aniso",
                            psd.gamma(),
                            crate::statistics::kc::GAMMA_MIN_FULL
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Builds the model (tables included: tens of ms for the wave models).
    pub fn build(&self) -> Result<DynBxdf, SpecError> {
        self.validate()?;
        let fresnel = self.fresnel.build()?;
        Ok(match &self.model {
            ModelSpec::Ggx { alpha_x, alpha_y } => Box::new(MicrofacetConductor::new(
                Distribution::ggx(*alpha_x, *alpha_y)?,
                fresnel,
            )?),
            ModelSpec::Beckmann { alpha_x, alpha_y } => Box::new(MicrofacetConductor::new(
                Distribution::beckmann(*alpha_x, *alpha_y)?,
                fresnel,
            )?),
            ModelSpec::Smooth => Box::new(SmoothConductor::new(fresnel)?),
            ModelSpec::GhsSsa { surface, options } => {
                Box::new(GhsSsa::with_options(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::Ghs { surface, options } => {
                Box::new(GhsFull::with_options(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::MeasuredPsd {
                zeta_rad_per_um,
                psd_um4,
                options,
            } => {
                let table = TabulatedPsd::new(zeta_rad_per_um, psd_um4)
                    .map_err(|e| SpecError::new("psd", e.to_string()))?;
                Box::new(GhsFull::with_options(table, fresnel, *options)?)
            }
            ModelSpec::TwoScale {
                beta,
                surface,
                coherent,
            } => Box::new(TwoScale::new(TwoScaleParams {
                beta: *beta,
                sigma_um: surface.sigma_um,
                lc_um: surface.lc_um,
                gamma: surface.gamma,
                fresnel,
                coherent: *coherent,
                resolution: TableResolution::default(),
            })?),
            ModelSpec::RayleighRice {
                surface,
                polarization,
            } => match surface {
                RrSurface::Kc(kc) => Box::new(RayleighRice::with_polarization(
                    kc.psd()?,
                    fresnel,
                    *polarization,
                )?),
                RrSurface::Measured {
                    zeta_rad_per_um,
                    psd_um4,
                } => {
                    let table = TabulatedPsd::new(zeta_rad_per_um, psd_um4)
                        .map_err(|e| SpecError::new("psd", e.to_string()))?;
                    Box::new(RayleighRice::with_polarization(
                        table,
                        fresnel,
                        *polarization,
                    )?)
                }
            },
            ModelSpec::GhsSsaAniso { surface, options } => {
                Box::new(GhsAnisotropic::ssa(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::GhsAniso { surface, options } => {
                Box::new(GhsAnisotropic::full(surface.psd()?, fresnel, *options)?)
            }
        })
    }
}

/// The directional albedo of a material at one incidence and wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Albedo {
    /// ∫ f cosθo dωo over the hemisphere (the glossy part).
    pub scattered: f64,
    /// The delta lobe's weight.
    pub specular: f64,
}

impl Albedo {
    /// Scattered plus specular.
    pub fn total(&self) -> f64 {
        self.scattered + self.specular
    }
}

impl MaterialSpec {
    /// Width of the lobe in projected-direction (o⊥) units at `lambda_nm`: where the
    /// albedo quadrature puts its nodes (microfacet α, the diffraction width 1/(kLc) of the
    /// wave models, a two-scale model's β when wider).
    pub fn lobe_rho(&self, lambda_nm: f64) -> f64 {
        let k = crate::wave::wavenumber(lambda_nm);
        let wave = |kc: &KcSpec| 1.0 / (k * kc.lc_um);
        let rho = match &self.model {
            ModelSpec::Ggx { alpha_x, alpha_y } | ModelSpec::Beckmann { alpha_x, alpha_y } => {
                alpha_x.min(*alpha_y)
            }
            ModelSpec::TwoScale { beta, surface, .. } => beta.max(wave(surface)),
            ModelSpec::GhsSsa { surface, .. } | ModelSpec::Ghs { surface, .. } => wave(surface),
            ModelSpec::MeasuredPsd {
                zeta_rad_per_um, ..
            } => zeta_rad_per_um.first().copied().unwrap_or(1.0) / k,
            ModelSpec::RayleighRice { surface, .. } => match surface {
                RrSurface::Kc(kc) => wave(kc),
                RrSurface::Measured {
                    zeta_rad_per_um, ..
                } => zeta_rad_per_um.first().copied().unwrap_or(1.0) / k,
            },
            ModelSpec::GhsSsaAniso { surface, .. } | ModelSpec::GhsAniso { surface, .. } => {
                1.0 / (k * surface.lx_um.max(surface.ly_um))
            }
            ModelSpec::Smooth => 1e-3,
        };
        if rho.is_finite() && rho > 0.0 {
            rho.clamp(1e-6, 1.0)
        } else {
            1e-3
        }
    }

    /// The directional albedo of `model` (this material, built) at incidence `wi` (local
    /// frame) and `lambda_nm`, by the adaptive hemispherical quadrature of
    /// [`crate::wave::energy::hemispherical_integral`] about the mirror direction.
    pub fn albedo(&self, model: &dyn Bxdf, wi: crate::DVec3, lambda_nm: f64) -> Albedo {
        let rho = self.lobe_rho(lambda_nm);
        Albedo {
            scattered: crate::wave::energy::hemispherical_integral(wi, rho, |o| {
                model.eval(wi, o, lambda_nm)
            }),
            specular: model.specular(wi, lambda_nm).weight,
        }
    }
}

#[cfg(feature = "serde")]
pub use desc::{FileLoader, FresnelKind, MaterialDesc, NoFiles};
#[cfg(feature = "serde")]
pub mod file;
#[cfg(feature = "serde")]
pub use file::MaterialFile;

#[cfg(feature = "serde")]
mod desc {
    use super::*;
    use crate::wave::{Energy, FresnelAngle, PolarizationFactor};

    /// `fresnel = …`: a conductor (default) or R ≡ 1.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "snake_case")]
    pub enum FresnelKind {
        /// The measured or given n + ik (default).
        Conductor,
        /// R ≡ 1.
        #[serde(alias = "none")]
        One,
    }

    /// The flat key/value form of a material, as scene files, `brdf eval`
    /// queries and `lustre fit` material files write it (keys in the module
    /// documentation). Unknown keys are refused when deserialised.
    #[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct MaterialDesc {
        /// The reflection model.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub model: Option<ModelKind>,
        /// A built-in metal by name (aliases as [`Metal::from_name`]).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub metal: Option<String>,
        /// A CSV `wavelength_nm,n,k` (resolved by the caller).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub nk_csv: Option<String>,
        /// A constant `[n, k]` (exactly two numbers).
        #[serde(
            default,
            deserialize_with = "exact_nk",
            skip_serializing_if = "Option::is_none"
        )]
        pub nk: Option<[f64; 2]>,
        /// `conductor` (default) or `one`.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub fresnel: Option<FresnelKind>,
        /// Isotropic microfacet roughness.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub alpha: Option<f64>,
        /// Roughness along the surface tangent.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub alpha_x: Option<f64>,
        /// Roughness along the bitangent.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub alpha_y: Option<f64>,
        /// Beckmann roughness, used in preference to `alpha` by `beckmann`.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub alpha_beckmann: Option<f64>,
        /// KC rms height σ, µm.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub sigma_um: Option<f64>,
        /// KC correlation length Lc, µm.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub lc_um: Option<f64>,
        /// KC exponent γ.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub gamma: Option<f64>,
        /// GHS energy handling.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub energy: Option<Energy>,
        /// GHS Fresnel angle.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub fresnel_angle: Option<FresnelAngle>,
        /// Incident polarisation (`unpolarized`, `s`, `p`).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub polarization: Option<Polarization>,
        /// GHS reflectance factor of the scattered part (`r` or `q`).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub polarization_factor: Option<PolarizationFactor>,
        /// Anisotropic KC correlation length along the axis, µm.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub lx_um: Option<f64>,
        /// Anisotropic KC correlation length across the axis, µm.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub ly_um: Option<f64>,
        /// Anisotropic KC axis angle from the tangent x towards y, degrees.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub angle_deg: Option<f64>,
        /// A CSV `zeta_rad_per_um,p_um4` (resolved by the caller).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub psd_csv: Option<String>,
        /// Two-scale macro NDF width β.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub beta: Option<f64>,
        /// Two-scale coherent part.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub coherent: Option<CoherentPart>,
        /// A `lustre fit` material file (resolved by the caller).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub include: Option<String>,
        /// Which two-scale split of the included file.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub cutoff: Option<String>,
    }

    /// `nk = [n, k]` from exactly two numbers: serde's array impl stops after
    /// two and formats such as TOML do not complain about the rest, so
    /// `nk = [0.2, 3.5, 9]` would otherwise pass as `[0.2, 3.5]`.
    fn exact_nk<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
        use serde::de::{Error, IgnoredAny, SeqAccess, Visitor};
        struct Nk;
        impl<'de> Visitor<'de> for Nk {
            type Value = [f64; 2];
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("an array of exactly two numbers [n, k]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; 2], A::Error> {
                let n = seq
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(0, &self))?;
                let k = seq
                    .next_element()?
                    .ok_or_else(|| A::Error::invalid_length(1, &self))?;
                let mut len = 2;
                while seq.next_element::<IgnoredAny>()?.is_some() {
                    len += 1;
                }
                if len != 2 {
                    return Err(A::Error::invalid_length(len, &self));
                }
                Ok([n, k])
            }
        }
        d.deserialize_seq(Nk).map(Some)
    }

    /// Reads the files a description refers to (this crate does no I/O).
    pub trait FileLoader {
        /// Rows `(λ nm, n, κ)` of an `nk_csv` file.
        fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String>;
        /// `(ζ rad/µm, P µm⁴)` samples of a `psd_csv` file.
        fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String>;
    }

    /// A loader for descriptions that must not refer to files.
    pub struct NoFiles;

    impl FileLoader for NoFiles {
        fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
            Err(format!(
                "cannot read {path:?} here: give `metal` or `nk` instead"
            ))
        }
        fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
            Err(format!("cannot read {path:?} here"))
        }
    }

    fn need(v: Option<f64>, key: &'static str, model: ModelKind) -> Result<f64, SpecError> {
        v.ok_or_else(|| SpecError::new(key, format!("model `{}` needs `{key}`", model.name())))
    }

    impl MaterialDesc {
        /// Fills every key this description leaves unset from `base` (an
        /// included file): keys set here win.
        ///
        /// Keys that together describe one quantity are inherited as a group,
        /// and only when none of them is set here: the roughness (`alpha`,
        /// `alpha_x`, `alpha_y`, `alpha_beckmann`) and the index (`metal`,
        /// `nk`, `nk_csv`, `fresnel`; an explicit `fresnel = "conductor"` here
        /// still takes the index from `base`). Key by key, a fit file's `alpha_x`
        /// and `alpha_y` (or `alpha_beckmann`) would silently beat an `alpha`
        /// set here, and its `metal` would clash with an `nk` set here.
        pub fn inherit(&mut self, base: &MaterialDesc) {
            macro_rules! inherit {
                ($($f:ident),*) => { $( if self.$f.is_none() { self.$f = base.$f.clone(); } )* };
            }
            if !self.roughness_here() {
                inherit!(alpha, alpha_x, alpha_y, alpha_beckmann);
            }
            if !self.index_here() {
                inherit!(metal, nk_csv, nk, fresnel);
            }
            inherit!(
                model,
                sigma_um,
                lc_um,
                gamma,
                energy,
                fresnel_angle,
                psd_csv,
                beta,
                coherent,
                polarization,
                polarization_factor,
                lx_um,
                ly_um,
                angle_deg
            );
        }

        /// Whether a roughness key is set here ([`inherit`](Self::inherit)
        /// then takes none of the base's).
        fn roughness_here(&self) -> bool {
            self.alpha.is_some()
                || self.alpha_x.is_some()
                || self.alpha_y.is_some()
                || self.alpha_beckmann.is_some()
        }

        /// Whether the index is set here ([`inherit`](Self::inherit) then
        /// takes none of the base's index keys).
        fn index_here(&self) -> bool {
            self.metal.is_some()
                || self.nk.is_some()
                || self.nk_csv.is_some()
                || self.fresnel == Some(FresnelKind::One)
        }

        /// Whether `key` (a key of this table as written in a scene) is set.
        fn is_set(&self, key: &str) -> bool {
            macro_rules! set {
                ($($f:ident),*) => { match key { $( stringify!($f) => self.$f.is_some(), )* _ => false } };
            }
            set!(
                model,
                metal,
                nk_csv,
                nk,
                fresnel,
                alpha,
                alpha_x,
                alpha_y,
                alpha_beckmann,
                sigma_um,
                lc_um,
                gamma,
                energy,
                fresnel_angle,
                psd_csv,
                beta,
                coherent,
                polarization,
                polarization_factor,
                lx_um,
                ly_um,
                angle_deg
            )
        }

        /// Whether [`inherit`](Self::inherit) from `base` takes the value of
        /// `key` from `base`: `base` sets it, and this description neither
        /// sets it nor replaces its group (roughness, index). A caller that
        /// reports an invalid merged value uses it to name the file the value
        /// came from.
        pub fn inherits(&self, base: &MaterialDesc, key: &str) -> bool {
            let replaced = match key {
                "alpha" | "alpha_x" | "alpha_y" | "alpha_beckmann" => self.roughness_here(),
                "metal" | "nk_csv" | "nk" | "fresnel" => self.index_here() || self.is_set(key),
                _ => self.is_set(key),
            };
            base.is_set(key) && !replaced
        }

        /// Keys set together here of which one would silently override the
        /// other (keys inherited from an included file cannot clash with
        /// these: [`MaterialDesc::inherit`] takes each group whole).
        fn check_conflicts(&self) -> Result<(), SpecError> {
            if self.alpha.is_some() && (self.alpha_x.is_some() || self.alpha_y.is_some()) {
                let other = if self.alpha_x.is_some() {
                    "alpha_x"
                } else {
                    "alpha_y"
                };
                return Err(SpecError::new(
                    "alpha",
                    format!(
                        "`alpha` and `{other}` are both set, and `alpha_x`/`alpha_y` would win; \
                         give `alpha` (isotropic) or `alpha_x` and `alpha_y` (anisotropic), not both"
                    ),
                ));
            }
            if self.fresnel == Some(FresnelKind::One) {
                let given = [
                    ("metal", self.metal.is_some()),
                    ("nk", self.nk.is_some()),
                    ("nk_csv", self.nk_csv.is_some()),
                ];
                if let Some((key, _)) = given.iter().find(|(_, set)| *set) {
                    return Err(SpecError::new(
                        "fresnel",
                        format!(
                            "`fresnel = \"one\"` (R ≡ 1) and `{key}` are both set, and `{key}` \
                             would be ignored; remove one of them"
                        ),
                    ));
                }
            }
            Ok(())
        }

        /// The keys that are set, by name.
        fn set_keys(&self) -> Vec<&'static str> {
            let mut k = Vec::new();
            macro_rules! set {
                ($($f:ident),*) => { $( if self.$f.is_some() { k.push(stringify!($f)); } )* };
            }
            set!(
                alpha,
                alpha_x,
                alpha_y,
                alpha_beckmann,
                sigma_um,
                lc_um,
                gamma,
                energy,
                fresnel_angle,
                psd_csv,
                beta,
                coherent,
                polarization,
                polarization_factor,
                lx_um,
                ly_um,
                angle_deg
            );
            k
        }

        /// The typed material of a description with nothing to inherit:
        /// [`MaterialDesc::resolve`] with no base.
        pub fn into_spec(&self, files: &mut dyn FileLoader) -> Result<MaterialSpec, SpecError> {
            self.resolve(None, files)
        }

        /// The typed material of this description over `base` (the
        /// `[material]` of an included `lustre fit` file, already chosen and
        /// read by the caller; keys set here win). `files` reads `nk_csv`
        /// and `psd_csv`.
        ///
        /// Every key set *here* must be one the model uses: a misspelt,
        /// misplaced or leftover key is an error naming it. Keys inherited
        /// from `base` are not checked that way, since a fit file carries α
        /// and the KC statistics for whichever model a scene picks.
        pub fn resolve(
            &self,
            base: Option<&MaterialDesc>,
            files: &mut dyn FileLoader,
        ) -> Result<MaterialSpec, SpecError> {
            self.check_conflicts()?;
            let mut merged = self.clone();
            if let Some(b) = base {
                merged.inherit(b);
            }
            merged.include = None;
            merged.cutoff = None;
            let model = merged.model.ok_or_else(|| {
                SpecError::new(
                    "model",
                    format!("missing `model`; one of {}", ModelKind::names()),
                )
            })?;
            self.check_used(model)?;
            if model == ModelKind::RayleighRice && merged.psd_csv.is_some() {
                // The table is the whole PSD (σ included): K-correlation keys set here
                // would be ignored (included ones are, as for measured_psd).
                let kc = [
                    ("sigma_um", self.sigma_um.is_some()),
                    ("lc_um", self.lc_um.is_some()),
                    ("gamma", self.gamma.is_some()),
                ];
                if let Some((key, _)) = kc.iter().find(|(_, set)| *set) {
                    return Err(SpecError::new(
                        key,
                        format!(
                            "`psd_csv` gives the whole PSD (σ included) and `{key}` would be \
                             ignored; give the table or `sigma_um`, `lc_um`, `gamma`"
                        ),
                    ));
                }
            }
            if self.cutoff.is_some() && model != ModelKind::TwoScale {
                return Err(SpecError::new(
                    "cutoff",
                    "`cutoff` picks the split of a two_scale material's included file",
                ));
            }
            merged.build_spec(model, files)
        }

        /// The keys `model` reads.
        pub fn keys_of(model: ModelKind) -> &'static [&'static str] {
            match model {
                ModelKind::Ggx => &["alpha", "alpha_x", "alpha_y"],
                ModelKind::Beckmann => &["alpha", "alpha_x", "alpha_y", "alpha_beckmann"],
                ModelKind::Smooth => &[],
                ModelKind::GhsSsa | ModelKind::Ghs => &[
                    "sigma_um",
                    "lc_um",
                    "gamma",
                    "energy",
                    "fresnel_angle",
                    "polarization",
                    "polarization_factor",
                ],
                ModelKind::MeasuredPsd => &[
                    "psd_csv",
                    "energy",
                    "fresnel_angle",
                    "polarization",
                    "polarization_factor",
                ],
                ModelKind::TwoScale => &["sigma_um", "lc_um", "gamma", "beta", "coherent"],
                ModelKind::RayleighRice => {
                    &["sigma_um", "lc_um", "gamma", "psd_csv", "polarization"]
                }
                ModelKind::GhsSsaAniso | ModelKind::GhsAniso => &[
                    "sigma_um",
                    "lx_um",
                    "ly_um",
                    "angle_deg",
                    "gamma",
                    "energy",
                    "fresnel_angle",
                    "polarization",
                    "polarization_factor",
                ],
            }
        }

        /// Refuses a key set here that `model` does not read.
        pub fn check_used(&self, model: ModelKind) -> Result<(), SpecError> {
            let used = Self::keys_of(model);
            match self.set_keys().into_iter().find(|k| !used.contains(k)) {
                None => Ok(()),
                Some(extra) => Err(SpecError::new(
                    extra,
                    format!(
                        "model `{}` does not use `{extra}`; its parameters are: {}",
                        model.name(),
                        if used.is_empty() {
                            "none".to_string()
                        } else {
                            used.join(", ")
                        }
                    ),
                )),
            }
        }

        fn build_spec(
            &self,
            model: ModelKind,
            files: &mut dyn FileLoader,
        ) -> Result<MaterialSpec, SpecError> {
            let fresnel = self.fresnel_spec(files)?;
            let kc = |m| -> Result<KcSpec, SpecError> {
                Ok(KcSpec {
                    sigma_um: need(self.sigma_um, "sigma_um", m)?,
                    lc_um: need(self.lc_um, "lc_um", m)?,
                    gamma: need(self.gamma, "gamma", m)?,
                })
            };
            let options = GhsOptions {
                energy: self.energy.unwrap_or_default(),
                fresnel_angle: self.fresnel_angle.unwrap_or_default(),
                polarization: self.polarization.unwrap_or_default(),
                polarization_factor: self.polarization_factor.unwrap_or_default(),
            };
            let aniso = |m| -> Result<AnisoSpec, SpecError> {
                Ok(AnisoSpec {
                    sigma_um: need(self.sigma_um, "sigma_um", m)?,
                    lx_um: need(self.lx_um, "lx_um", m)?,
                    ly_um: need(self.ly_um, "ly_um", m)?,
                    angle_deg: self.angle_deg.unwrap_or(0.0),
                    gamma: need(self.gamma, "gamma", m)?,
                })
            };
            let spec = match model {
                ModelKind::Ggx => {
                    let (alpha_x, alpha_y) = self.roughness(model, self.alpha)?;
                    ModelSpec::Ggx { alpha_x, alpha_y }
                }
                ModelKind::Beckmann => {
                    let (alpha_x, alpha_y) =
                        self.roughness(model, self.alpha_beckmann.or(self.alpha))?;
                    ModelSpec::Beckmann { alpha_x, alpha_y }
                }
                ModelKind::Smooth => ModelSpec::Smooth,
                ModelKind::GhsSsa => ModelSpec::GhsSsa {
                    surface: kc(model)?,
                    options,
                },
                ModelKind::Ghs => ModelSpec::Ghs {
                    surface: kc(model)?,
                    options,
                },
                ModelKind::MeasuredPsd => {
                    let path = self.psd_csv.as_deref().ok_or_else(|| {
                        SpecError::new(
                            "psd_csv",
                            "model `measured_psd` needs `psd_csv = \"file.csv\"` \
                             (zeta_rad_per_um,p_um4) or an included fit file with a [psd] table",
                        )
                    })?;
                    let (zeta_rad_per_um, psd_um4) = files
                        .psd_table(path)
                        .map_err(|e| SpecError::new("psd_csv", e))?;
                    ModelSpec::MeasuredPsd {
                        zeta_rad_per_um,
                        psd_um4,
                        options,
                    }
                }
                ModelKind::TwoScale => ModelSpec::TwoScale {
                    beta: need(self.beta, "beta", model)?,
                    surface: kc(model)?,
                    coherent: self.coherent.unwrap_or_default(),
                },
                ModelKind::RayleighRice => {
                    let surface = match self.psd_csv.as_deref() {
                        Some(path) => {
                            let (zeta_rad_per_um, psd_um4) = files
                                .psd_table(path)
                                .map_err(|e| SpecError::new("psd_csv", e))?;
                            RrSurface::Measured {
                                zeta_rad_per_um,
                                psd_um4,
                            }
                        }
                        None => RrSurface::Kc(kc(model)?),
                    };
                    ModelSpec::RayleighRice {
                        surface,
                        polarization: options.polarization,
                    }
                }
                ModelKind::GhsSsaAniso => ModelSpec::GhsSsaAniso {
                    surface: aniso(model)?,
                    options,
                },
                ModelKind::GhsAniso => ModelSpec::GhsAniso {
                    surface: aniso(model)?,
                    options,
                },
            };
            let spec = MaterialSpec {
                model: spec,
                fresnel,
            };
            spec.validate()?;
            Ok(spec)
        }

        fn roughness(&self, model: ModelKind, iso: Option<f64>) -> Result<(f64, f64), SpecError> {
            match (self.alpha_x, self.alpha_y, iso) {
                (Some(x), Some(y), _) => Ok((x, y)),
                (None, None, Some(a)) => Ok((a, a)),
                (Some(_), None, _) => Err(SpecError::new(
                    "alpha_y",
                    "give both `alpha_x` and `alpha_y`",
                )),
                (None, Some(_), _) => Err(SpecError::new(
                    "alpha_x",
                    "give both `alpha_x` and `alpha_y`",
                )),
                (None, None, None) => Err(SpecError::new(
                    "alpha",
                    format!(
                        "model `{}` needs `alpha` (or `alpha_x` and `alpha_y`)",
                        model.name()
                    ),
                )),
            }
        }

        fn fresnel_spec(&self, files: &mut dyn FileLoader) -> Result<FresnelSpec, SpecError> {
            if self.fresnel == Some(FresnelKind::One) {
                return Ok(FresnelSpec::One);
            }
            let given = [
                self.metal.is_some(),
                self.nk_csv.is_some(),
                self.nk.is_some(),
            ];
            match given.iter().filter(|&&g| g).count() {
                0 => Err(SpecError::new(
                    "metal",
                    "needs one of `metal = \"NAME\"`, `nk_csv = \"file.csv\"`, `nk = [n, k]` \
                     (or `fresnel = \"one\"` for R ≡ 1)",
                )),
                1 => {
                    if let Some(name) = &self.metal {
                        let m = Metal::from_name(name).ok_or_else(|| {
                            let names: Vec<&str> = Metal::ALL.iter().map(|m| m.name()).collect();
                            SpecError::new(
                                "metal",
                                format!("unknown metal `{name}`; valid: {}", names.join(", ")),
                            )
                        })?;
                        Ok(FresnelSpec::Metal(m))
                    } else if let Some(path) = &self.nk_csv {
                        let rows = files
                            .nk_table(path)
                            .map_err(|e| SpecError::new("nk_csv", e))?;
                        Ior::table(rows.clone())
                            .map_err(|e| SpecError::new("nk_csv", e.to_string()))?;
                        Ok(FresnelSpec::Table(rows))
                    } else {
                        let [n, k] = self.nk.unwrap_or_default();
                        Ior::constant(n, k).map_err(|e| SpecError::new("nk", e.to_string()))?;
                        Ok(FresnelSpec::Constant { n, k })
                    }
                }
                _ => Err(SpecError::new(
                    "metal",
                    "give only one of `metal`, `nk_csv`, `nk`",
                )),
            }
        }
    }

    impl MaterialSpec {
        /// The flat form. Tabulated data (a measured PSD, an n,k table) is
        /// not representable as keys: `psd_csv` / `nk_csv` are left unset
        /// and the caller writes the data next to the description.
        pub fn to_desc(&self) -> MaterialDesc {
            let mut d = MaterialDesc {
                model: Some(self.model.kind()),
                ..MaterialDesc::default()
            };
            match &self.fresnel {
                FresnelSpec::One => d.fresnel = Some(FresnelKind::One),
                FresnelSpec::Metal(m) => d.metal = Some(m.name().to_string()),
                FresnelSpec::Constant { n, k } => d.nk = Some([*n, *k]),
                FresnelSpec::Table(_) => {}
            }
            let set_kc = |d: &mut MaterialDesc, s: &KcSpec| {
                d.sigma_um = Some(s.sigma_um);
                d.lc_um = Some(s.lc_um);
                d.gamma = Some(s.gamma);
            };
            let set_opts = |d: &mut MaterialDesc, o: &GhsOptions| {
                d.energy = Some(o.energy);
                d.fresnel_angle = Some(o.fresnel_angle);
                // The scalar theory's defaults are left implicit, as files written
                // before the polarisation options have them.
                let defaults = GhsOptions::default();
                d.polarization =
                    (o.polarization != defaults.polarization).then_some(o.polarization);
                d.polarization_factor = (o.polarization_factor != defaults.polarization_factor)
                    .then_some(o.polarization_factor);
            };
            match &self.model {
                ModelSpec::Ggx { alpha_x, alpha_y } | ModelSpec::Beckmann { alpha_x, alpha_y } => {
                    if alpha_x == alpha_y {
                        d.alpha = Some(*alpha_x);
                    } else {
                        d.alpha_x = Some(*alpha_x);
                        d.alpha_y = Some(*alpha_y);
                    }
                }
                ModelSpec::Smooth => {}
                ModelSpec::GhsSsa { surface, options } | ModelSpec::Ghs { surface, options } => {
                    set_kc(&mut d, surface);
                    set_opts(&mut d, options);
                }
                ModelSpec::MeasuredPsd { options, .. } => set_opts(&mut d, options),
                ModelSpec::TwoScale {
                    beta,
                    surface,
                    coherent,
                } => {
                    d.beta = Some(*beta);
                    set_kc(&mut d, surface);
                    d.coherent = Some(*coherent);
                }
                ModelSpec::RayleighRice {
                    surface,
                    polarization,
                } => {
                    if let RrSurface::Kc(kc) = surface {
                        set_kc(&mut d, kc);
                    }
                    d.polarization = Some(*polarization);
                }
                ModelSpec::GhsSsaAniso { surface, options }
                | ModelSpec::GhsAniso { surface, options } => {
                    d.sigma_um = Some(surface.sigma_um);
                    d.lx_um = Some(surface.lx_um);
                    d.ly_um = Some(surface.ly_um);
                    d.angle_deg = Some(surface.angle_deg);
                    d.gamma = Some(surface.gamma);
                    set_opts(&mut d, options);
                }
            }
            d
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_model_builds_and_validates() {
        let kc = KcSpec {
            sigma_um: 0.1,
            lc_um: 2.0,
            gamma: 2.5,
        };
        let zeta: Vec<f64> = (0..40).map(|i| 0.01 * 1.3f64.powi(i)).collect();
        let p: Vec<f64> = zeta
            .iter()
            .map(|z| 0.01 / libm::pow(1.0 + 4.0 * z * z, 2.0))
            .collect();
        let aniso = AnisoSpec {
            sigma_um: 0.1,
            lx_um: 0.5,
            ly_um: 4.0,
            angle_deg: 30.0,
            gamma: 2.5,
        };
        let specs = [
            ModelSpec::Ggx {
                alpha_x: 0.1,
                alpha_y: 0.2,
            },
            ModelSpec::Beckmann {
                alpha_x: 0.1,
                alpha_y: 0.1,
            },
            ModelSpec::Smooth,
            ModelSpec::GhsSsa {
                surface: kc,
                options: GhsOptions::default(),
            },
            ModelSpec::Ghs {
                surface: kc,
                options: GhsOptions::default(),
            },
            ModelSpec::MeasuredPsd {
                zeta_rad_per_um: zeta.clone(),
                psd_um4: p.clone(),
                options: GhsOptions::default(),
            },
            ModelSpec::TwoScale {
                beta: 0.05,
                surface: kc,
                coherent: CoherentPart::MacroNdf,
            },
            ModelSpec::RayleighRice {
                surface: RrSurface::Kc(kc),
                polarization: Polarization::S,
            },
            ModelSpec::RayleighRice {
                surface: RrSurface::Measured {
                    zeta_rad_per_um: zeta.clone(),
                    psd_um4: p.clone(),
                },
                polarization: Polarization::Unpolarized,
            },
            ModelSpec::GhsSsaAniso {
                surface: aniso,
                options: GhsOptions::default(),
            },
            ModelSpec::GhsAniso {
                surface: aniso,
                options: GhsOptions::default(),
            },
        ];
        for (spec, kind) in specs.into_iter().zip([
            ModelKind::Ggx,
            ModelKind::Beckmann,
            ModelKind::Smooth,
            ModelKind::GhsSsa,
            ModelKind::Ghs,
            ModelKind::MeasuredPsd,
            ModelKind::TwoScale,
            ModelKind::RayleighRice,
            ModelKind::RayleighRice,
            ModelKind::GhsSsaAniso,
            ModelKind::GhsAniso,
        ]) {
            assert_eq!(spec.kind(), kind);
            let m = MaterialSpec {
                model: spec,
                fresnel: FresnelSpec::Metal(Metal::Cu),
            };
            m.validate().unwrap();
            let b = m.build().unwrap();
            let wi = crate::frame::spherical(0.3, 0.0);
            let wo = crate::frame::spherical(0.3, core::f64::consts::PI);
            assert!(b.eval(wi, wo, 550.0).is_finite());
        }
    }

    #[cfg(feature = "serde")]
    mod desc {
        use super::super::*;
        use crate::wave::{Energy, FresnelAngle};
        use alloc::string::ToString;

        fn desc(json: &str) -> Result<MaterialDesc, String> {
            serde_json::from_str(json).map_err(|e| e.to_string())
        }

        struct Files;
        impl FileLoader for Files {
            fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
                assert_eq!(path, "cu.csv");
                Ok(alloc::vec![[300.0, 1.0, 2.0], [900.0, 0.5, 5.0]])
            }
            fn psd_table(&mut self, _: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
                Err("no".to_string())
            }
        }

        #[test]
        fn keys_parse_into_the_typed_spec() {
            let d = desc(
                r#"{"model": "ghs", "metal": "cu", "sigma_um": 0.1, "lc_um": 2,
                    "gamma": 2.5, "energy": "sigma_rel", "fresnel_angle": "incident"}"#,
            )
            .unwrap();
            let s = d.into_spec(&mut NoFiles).unwrap();
            assert_eq!(
                s.model,
                ModelSpec::Ghs {
                    surface: KcSpec {
                        sigma_um: 0.1,
                        lc_um: 2.0,
                        gamma: 2.5
                    },
                    options: GhsOptions {
                        energy: Energy::SigmaRel,
                        fresnel_angle: FresnelAngle::Incident,
                        ..GhsOptions::default()
                    }
                }
            );
            assert_eq!(s.fresnel, FresnelSpec::Metal(Metal::Cu));
            // and back
            assert_eq!(s.to_desc().into_spec(&mut NoFiles).unwrap(), s);
            // `fresnel = "none"` is R ≡ 1; nk_csv goes through the loader.
            let d = desc(r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.3, "fresnel": "none"}"#)
                .unwrap();
            assert_eq!(d.into_spec(&mut NoFiles).unwrap().fresnel, FresnelSpec::One);
            let d = desc(r#"{"model": "smooth", "nk_csv": "cu.csv"}"#).unwrap();
            assert!(matches!(
                d.into_spec(&mut Files).unwrap().fresnel,
                FresnelSpec::Table(_)
            ));
        }

        #[test]
        fn polarisation_and_anisotropy_keys_parse_and_round_trip() {
            use crate::wave::{Polarization, PolarizationFactor};
            let cases = [
                r#"{"model": "rayleigh_rice", "metal": "au", "sigma_um": 0.01, "lc_um": 2,
                    "gamma": 3, "polarization": "s"}"#,
                r#"{"model": "ghs", "metal": "al", "sigma_um": 0.1, "lc_um": 2, "gamma": 2.5,
                    "polarization": "p", "polarization_factor": "q"}"#,
                r#"{"model": "ghs_ssa", "metal": "cu", "sigma_um": 0.1, "lc_um": 2,
                    "gamma": 2.5, "polarization": "unpolarised"}"#,
                r#"{"model": "ghs_aniso", "metal": "cu", "sigma_um": 0.05, "lx_um": 0.5,
                    "ly_um": 5, "angle_deg": 30, "gamma": 2.5, "polarization_factor": "q"}"#,
                r#"{"model": "ghs_ssa_aniso", "fresnel": "one", "sigma_um": 0.05,
                    "lx_um": 0.5, "ly_um": 5, "gamma": 1.5}"#,
            ];
            for json in cases {
                let s = desc(json).unwrap().into_spec(&mut NoFiles).unwrap();
                assert_eq!(s.to_desc().into_spec(&mut NoFiles).unwrap(), s, "{json}");
                let m = s.build().unwrap();
                let wi = crate::frame::spherical(0.4, 0.0);
                let wo = crate::frame::spherical(0.45, 3.0);
                assert!(m.eval(wi, wo, 550.0) > 0.0, "{json}");
            }
            let s = desc(cases[1]).unwrap().into_spec(&mut NoFiles).unwrap();
            let ModelSpec::Ghs { options, .. } = s.model else {
                panic!("{:?}", s.model)
            };
            assert_eq!(options.polarization, Polarization::P);
            assert_eq!(options.polarization_factor, PolarizationFactor::Q);
        }

        #[test]
        fn polarisation_and_anisotropy_errors_name_the_key() {
            for (json, field) in [
                (
                    r#"{"model": "ghs_aniso", "metal": "au", "sigma_um": 0.1, "lx_um": 1,
                        "ly_um": 2, "gamma": 3, "energy": "krywonos"}"#,
                    "energy",
                ),
                (
                    r#"{"model": "ghs_aniso", "metal": "au", "sigma_um": 0.1, "ly_um": 2,
                        "gamma": 3}"#,
                    "lx_um",
                ),
                (
                    r#"{"model": "ghs_aniso", "metal": "au", "sigma_um": 0.1, "lx_um": 1,
                        "ly_um": 2, "gamma": 1.02}"#,
                    "gamma",
                ),
                (
                    r#"{"model": "rayleigh_rice", "metal": "au", "sigma_um": 0.1, "lc_um": 1,
                        "gamma": 3, "polarization_factor": "q"}"#,
                    "polarization_factor",
                ),
                (
                    r#"{"model": "rayleigh_rice", "metal": "au", "psd_csv": "p.csv",
                        "sigma_um": 0.1}"#,
                    "sigma_um",
                ),
                (
                    r#"{"model": "ggx", "metal": "au", "alpha": 0.1, "lx_um": 1}"#,
                    "lx_um",
                ),
            ] {
                let e = desc(json).unwrap().into_spec(&mut NoFiles).unwrap_err();
                assert_eq!(e.field, field, "{json}: {e}");
            }
            let e = desc(r#"{"model": "ghs", "polarization": "circular"}"#).unwrap_err();
            assert!(e.contains("unpolarized") && e.contains("circular"), "{e}");
        }

        #[test]
        fn unknown_unused_and_missing_keys_name_the_key() {
            let e = desc(r#"{"model": "ghs", "enrgy": "krywonos"}"#).unwrap_err();
            assert!(e.contains("enrgy") && e.contains("energy"), "{e}");
            let d = desc(r#"{"model": "ggx", "alpha": 0.1, "metal": "au", "beta": 0.2}"#).unwrap();
            let e = d.into_spec(&mut NoFiles).unwrap_err();
            assert_eq!(e.field, "beta");
            assert!(e.message.contains("alpha"), "{e}");
            let d = desc(
                r#"{"model": "two_scale", "metal": "au", "sigma_um": 0.1, "lc_um": 1, "gamma": 2}"#,
            )
            .unwrap();
            assert_eq!(d.into_spec(&mut NoFiles).unwrap_err().field, "beta");
            let d = desc(r#"{"model": "ggx", "alpha": 0.1}"#).unwrap();
            assert_eq!(d.into_spec(&mut NoFiles).unwrap_err().field, "metal");
            let d = desc(r#"{"model": "ggx", "alpha": 0.1, "metal": "unobtainium"}"#).unwrap();
            let e = d.into_spec(&mut NoFiles).unwrap_err();
            assert!(e.message.contains("stainless_steel"), "{e}");
            let d =
                desc(r#"{"model": "ghs", "metal": "au", "sigma_um": 20, "lc_um": 1, "gamma": 2}"#)
                    .unwrap();
            assert_eq!(d.into_spec(&mut NoFiles).unwrap_err().field, "sigma_um");
            let e = desc(r#"{"model": "phong"}"#).unwrap_err();
            assert!(e.contains("ghs_ssa"), "{e}");
        }

        #[test]
        fn keys_that_would_silently_override_each_other_are_refused() {
            for (json, field) in [
                (
                    r#"{"model": "ggx", "metal": "cu", "alpha": 0.2, "alpha_x": 0.1, "alpha_y": 0.3}"#,
                    "alpha",
                ),
                (
                    r#"{"model": "ggx", "fresnel": "one", "nk": [0.2, 3.0], "alpha": 0.2}"#,
                    "fresnel",
                ),
            ] {
                let e = desc(json).unwrap().into_spec(&mut NoFiles).unwrap_err();
                assert_eq!(e.field, field, "{json}: {e}");
            }
        }

        #[test]
        fn a_group_set_here_replaces_the_included_one_whole() {
            let base = desc(
                r#"{"model": "ggx", "metal": "brass", "alpha_x": 0.3, "alpha_y": 0.1,
                    "alpha_beckmann": 0.25}"#,
            )
            .unwrap();
            // `alpha` here: the file's anisotropic pair (or its Beckmann α)
            // used to win over it without a word.
            for model in ["ggx", "beckmann"] {
                let own = desc(&format!(r#"{{"model": "{model}", "alpha": 0.05}}"#)).unwrap();
                let s = own.resolve(Some(&base), &mut NoFiles).unwrap();
                let (ModelSpec::Ggx { alpha_x, alpha_y }
                | ModelSpec::Beckmann { alpha_x, alpha_y }) = s.model
                else {
                    panic!("{model}: {:?}", s.model);
                };
                assert_eq!((alpha_x, alpha_y), (0.05, 0.05), "{model}");
            }
            // An index here replaces the file's metal instead of clashing with it.
            let own = desc(r#"{"nk": [1.5, 3.0]}"#).unwrap();
            let s = own.resolve(Some(&base), &mut NoFiles).unwrap();
            assert_eq!(s.fresnel, FresnelSpec::Constant { n: 1.5, k: 3.0 });
            let own = desc(r#"{"fresnel": "one"}"#).unwrap();
            let s = own.resolve(Some(&base), &mut NoFiles).unwrap();
            assert_eq!(s.fresnel, FresnelSpec::One);
            // Nothing of a group here: the file's whole group.
            let own = desc(r#"{"fresnel": "conductor"}"#).unwrap();
            let s = own.resolve(Some(&base), &mut NoFiles).unwrap();
            assert_eq!(s.fresnel, FresnelSpec::Metal(Metal::BrassCu70Zn30));
            assert_eq!(
                s.model,
                ModelSpec::Ggx {
                    alpha_x: 0.3,
                    alpha_y: 0.1
                }
            );
        }

        #[test]
        fn included_keys_are_inherited_and_not_checked() {
            // A fit file carries α and the KC for whichever model a scene picks.
            let base = desc(
                r#"{"model": "ghs", "metal": "brass", "alpha": 0.2, "alpha_beckmann": 0.25,
                    "sigma_um": 0.1, "lc_um": 2, "gamma": 2.5}"#,
            )
            .unwrap();
            let own = desc(r#"{"model": "beckmann"}"#).unwrap();
            let s = own.resolve(Some(&base), &mut NoFiles).unwrap();
            assert_eq!(
                s.model,
                ModelSpec::Beckmann {
                    alpha_x: 0.25,
                    alpha_y: 0.25
                }
            );
            // …but a key the scene sets itself must be used.
            let own = desc(r#"{"model": "ggx", "gamma": 3}"#).unwrap();
            assert_eq!(
                own.resolve(Some(&base), &mut NoFiles).unwrap_err().field,
                "gamma"
            );
            let own = desc(r#"{"alpha": 0.05}"#).unwrap();
            assert_eq!(
                own.resolve(Some(&base), &mut NoFiles).unwrap_err().field,
                "alpha"
            );
        }
    }

    #[test]
    fn out_of_range_names_the_field() {
        let bad = MaterialSpec {
            model: ModelSpec::Ghs {
                surface: KcSpec {
                    sigma_um: 0.1,
                    lc_um: 2.0,
                    gamma: 1.02,
                },
                options: GhsOptions::default(),
            },
            fresnel: FresnelSpec::One,
        };
        assert_eq!(bad.validate().unwrap_err().field, "gamma");
        let bad = MaterialSpec {
            model: ModelSpec::Ggx {
                alpha_x: 0.0,
                alpha_y: 0.1,
            },
            fresnel: FresnelSpec::One,
        };
        assert!(bad.validate().is_err());
    }
}
