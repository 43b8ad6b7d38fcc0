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
//! | `model` | all | `ggx`, `beckmann`, `smooth`, `ghs_ssa`, `ghs`, `two_scale`, `measured_psd`, `rayleigh_rice`, `ghs_ssa_aniso`, `ghs_aniso`, `measured_psd_ssa_aniso`, `measured_psd_aniso`, `measured_psd2d_ssa`, `measured_psd2d`, `diffuse`, `roughplastic` |
//! | `metal` / `nk` / `nk_csv` | all but diffuse, roughplastic | built-in metal, constant `[n, k]`, or a CSV `wavelength_nm,n,k` |
//! | `fresnel` | all but diffuse, roughplastic | `conductor` (default) or `one` (R ≡ 1; alias `none`) |
//! | `alpha`, or `alpha_x` + `alpha_y` | ggx, beckmann (roughplastic: `alpha` only) | roughness (αx along the axis at `angle_deg`, the surface tangent by default) |
//! | `angle_deg` | ggx, beckmann | the axis of `alpha_x`, degrees from the tangent x towards y (default 0; the convention of the `_aniso` models' `angle_deg`) |
//! | `reflectance` or `reflectance_csv` | diffuse, roughplastic | the (base's) reflectance ρ ∈ [0, 1]: a constant, or a CSV `wavelength_nm,reflectance` |
//! | `int_ior`, `ext_ior`, `nonlinear` | roughplastic | the coat's index (default 1.49) and the medium's (default 1.0); whether internal scattering tints (`ρ/(1 − ρR_i)`) or not (`ρ/(1 − R_i)`, default `false`) |
//! | `alpha_beckmann` | beckmann | used in preference to `alpha` (a fit file serves both models) |
//! | `sigma_um`, `lc_um`, `gamma` | ghs_ssa, ghs, two_scale, rayleigh_rice | K-correlation σ (µm), Lc (µm), γ |
//! | `sigma_um`, `lx_um`, `ly_um`, `angle_deg`, `gamma` | ghs_ssa_aniso, ghs_aniso | anisotropic K-correlation: Lx along the axis at `angle_deg` (from the tangent x towards y; default 0), Ly across it |
//! | `psd_csv`, `lx_um`, `ly_um`, `angle_deg` | measured_psd_ssa_aniso, measured_psd_aniso | a measured radial PSD of the de-stretched frame stretched along the axis at `angle_deg` by the ratio Ly/Lx, areas kept (physics.md §15.2; only the ratio of the two lengths is read) |
//! | `psd_map`, `angle_deg` | measured_psd2d_ssa, measured_psd2d (full GHS) | a measured 2-D PSD on a grid (physics.md §15.4): `"[psd.map]"` of an included `lustre fit` material file (the default there); `angle_deg` turns the grid's frame (default 0: the scan's axes) |
//! | `energy` | ghs_ssa, ghs, measured_psd (the `_aniso` and `measured_psd2d` models: `raw` only) | `raw` (default), `krywonos`, `sigma_rel` |
//! | `fresnel_angle` | ghs_ssa, ghs, measured_psd, `_aniso`, measured_psd2d(_ssa) | `halfway` (default) or `incident` |
//! | `polarization` | ghs_ssa, ghs, measured_psd, rayleigh_rice, `_aniso`, measured_psd2d(_ssa) | `unpolarized` (default), `s`, `p` (incident; both scattered polarisations summed) |
//! | `polarization_factor` | ghs_ssa, ghs, measured_psd, `_aniso`, measured_psd2d(_ssa) | `r` (default: scalar Fresnel R) or `q` (Rayleigh–Rice Q, physics.md §13.2) |
//! | `psd_csv` | measured_psd, rayleigh_rice, measured_psd_(ssa_)aniso | CSV `zeta_rad_per_um,p_um4` (rayleigh_rice: in place of the K-correlation keys, which must then not be set) |
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

use crate::statistics::anisotropic::AnisotropicKc;
use crate::statistics::kc::KcPsd;
use crate::statistics::{EllipticalPsd, TabulatedPsd, TabulatedPsd2d};
use crate::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use crate::wave::{
    GhsAnisotropic, GhsFull, GhsOptions, GhsPsd2d, GhsSsa, GhsSsaPsd2d, Polarization, RayleighRice,
};
use crate::{
    BrdfError, Bxdf, Diffuse, Distribution, Fresnel, Ior, Metal, MicrofacetConductor, Reflectance,
    RoughPlastic, RoughPlasticParams, SmoothConductor, microfacet::Rotated,
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
    /// GHS smooth-surface approximation of a measured PSD stretched along two axes.
    MeasuredPsdSsaAniso,
    /// Full GHS of a measured PSD stretched along two axes.
    MeasuredPsdAniso,
    /// GHS smooth-surface approximation of a measured 2-D PSD on a grid.
    MeasuredPsd2dSsa,
    /// Full GHS of a measured 2-D PSD on a grid.
    MeasuredPsd2d,
    /// Lambertian reflector (no Fresnel term).
    Diffuse,
    /// GGX dielectric coat over a Lambertian base (Mitsuba's `roughplastic`).
    #[cfg_attr(feature = "serde", serde(rename = "roughplastic"))]
    RoughPlastic,
}

impl ModelKind {
    /// Every model, in the order the documentation lists them.
    pub const ALL: [ModelKind; 16] = [
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
        ModelKind::MeasuredPsdSsaAniso,
        ModelKind::MeasuredPsdAniso,
        ModelKind::MeasuredPsd2dSsa,
        ModelKind::MeasuredPsd2d,
        ModelKind::Diffuse,
        ModelKind::RoughPlastic,
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
            ModelKind::MeasuredPsdSsaAniso => "measured_psd_ssa_aniso",
            ModelKind::MeasuredPsdAniso => "measured_psd_aniso",
            ModelKind::MeasuredPsd2dSsa => "measured_psd2d_ssa",
            ModelKind::MeasuredPsd2d => "measured_psd2d",
            ModelKind::Diffuse => "diffuse",
            ModelKind::RoughPlastic => "roughplastic",
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

    /// Whether the model's reflectance is a conductor's Fresnel factor (its
    /// [`MaterialSpec::fresnel`] is read). False for `diffuse` and
    /// `roughplastic`, whose reflectance is their own parameter: their
    /// [`MaterialSpec::fresnel`] must be [`FresnelSpec::One`].
    pub fn conductor(self) -> bool {
        !matches!(self, ModelKind::Diffuse | ModelKind::RoughPlastic)
    }

    /// Whether the model describes an anisotropic surface whose parameters exist only for
    /// a scan `lustre fit` flags anisotropic: a surface stretched along two axes
    /// (`ghs_ssa_aniso`, `ghs_aniso`, `measured_psd_ssa_aniso`, `measured_psd_aniso`) or
    /// a 2-D PSD that is not elliptical (`measured_psd2d_ssa`, `measured_psd2d`, their `[psd.map]`), so a fit
    /// file cannot recommend it for every scan.
    pub fn stretched(self) -> bool {
        matches!(
            self,
            ModelKind::GhsSsaAniso
                | ModelKind::GhsAniso
                | ModelKind::MeasuredPsdSsaAniso
                | ModelKind::MeasuredPsdAniso
                | ModelKind::MeasuredPsd2dSsa
                | ModelKind::MeasuredPsd2d
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

/// A measured radial PSD stretched along two axes (physics.md §15.2), validated as
/// [`TabulatedPsd::new`] and [`EllipticalPsd::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredAnisoSpec {
    /// Radial frequencies ζ of the de-stretched frame, rad/µm, strictly increasing.
    pub zeta_rad_per_um: Vec<f64>,
    /// PSD values P(ζ) of the de-stretched frame, µm⁴.
    pub psd_um4: Vec<f64>,
    /// Length along the axis at `angle_deg`, µm (only Ly/Lx is read).
    pub lx_um: f64,
    /// Length across it, µm.
    pub ly_um: f64,
    /// Axis angle from the tangent x towards y, degrees.
    pub angle_deg: f64,
}

impl MeasuredAnisoSpec {
    /// The stretched PSD, or the error naming the key.
    pub fn psd(&self) -> Result<EllipticalPsd<TabulatedPsd>, SpecError> {
        let table = TabulatedPsd::new(&self.zeta_rad_per_um, &self.psd_um4)
            .map_err(|e| SpecError::new("psd", e.to_string()))?;
        Ok(EllipticalPsd::new(
            table,
            self.lx_um,
            self.ly_um,
            self.angle_deg.to_radians(),
        )?)
    }
}

/// A measured 2-D PSD on a grid (physics.md §15.4), validated as [`TabulatedPsd2d::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct Psd2dSpec {
    /// Nodes on each half of the ζx axis (the grid has 2·half_nx + 1 columns).
    pub half_nx: usize,
    /// Node rows of the half plane ζy ≥ 0 above the ζy = 0 row.
    pub half_ny: usize,
    /// Grid step along ζx, rad/µm.
    pub dzx_rad_per_um: f64,
    /// Grid step along ζy, rad/µm.
    pub dzy_rad_per_um: f64,
    /// P₂ at the nodes of the half plane, µm⁴: rows j = 0..=half_ny, each
    /// i = −half_nx..=half_nx.
    pub psd_um4: Vec<f64>,
    /// Exponent α of the continuation beyond the grid, P ∝ s^−α along each ray.
    pub tail_exponent: f64,
    /// The grid's x axis from the tangent x towards y, degrees.
    pub angle_deg: f64,
}

impl Psd2dSpec {
    /// The table, or the error naming the key.
    pub fn psd(&self) -> Result<TabulatedPsd2d, SpecError> {
        TabulatedPsd2d::new(
            self.half_nx,
            self.half_ny,
            self.dzx_rad_per_um,
            self.dzy_rad_per_um,
            &self.psd_um4,
            self.tail_exponent,
            self.angle_deg.to_radians(),
        )
        .map_err(|e| match e {
            BrdfError::InvalidTable { .. } => SpecError::new("psd_map", e.to_string()),
            other => other.into(),
        })
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

/// A reflectance ρ(λ) ∈ [0, 1] of a diffuse surface or base.
#[derive(Clone, Debug, PartialEq)]
pub enum ReflectanceSpec {
    /// The same at every wavelength.
    Constant(f64),
    /// Rows `[λ nm, ρ]`, λ strictly increasing.
    Table(Vec<[f64; 2]>),
}

impl ReflectanceSpec {
    /// The reflectance, or the error naming what is wrong.
    pub fn build(&self) -> Result<Reflectance, SpecError> {
        match self {
            ReflectanceSpec::Constant(r) => Ok(Reflectance::constant(*r)?),
            ReflectanceSpec::Table(rows) => Reflectance::table(rows.clone())
                .map_err(|e| SpecError::new("reflectance_csv", e.to_string())),
        }
    }
}

/// A model and its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSpec {
    /// GGX with roughness αx along the axis at `angle_deg` from the surface tangent
    /// towards the bitangent, αy across it.
    Ggx {
        /// α along the axis at `angle_deg` (the tangent when it is 0).
        alpha_x: f64,
        /// α across it (the bitangent when `angle_deg` is 0).
        alpha_y: f64,
        /// The axis of `alpha_x`, degrees from the tangent towards the bitangent (finite;
        /// 0: the tangent axes), the convention of [`AnisoSpec::angle_deg`].
        angle_deg: f64,
    },
    /// Beckmann with roughness αx along the axis at `angle_deg`, αy across it.
    Beckmann {
        /// α along the axis at `angle_deg` (the tangent when it is 0).
        alpha_x: f64,
        /// α across it (the bitangent when `angle_deg` is 0).
        alpha_y: f64,
        /// The axis of `alpha_x`, degrees from the tangent towards the bitangent (finite;
        /// 0: the tangent axes), the convention of [`AnisoSpec::angle_deg`].
        angle_deg: f64,
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
    /// GHS smooth-surface approximation, measured PSD stretched along two axes.
    MeasuredPsdSsaAniso {
        /// The surface.
        surface: MeasuredAnisoSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
    /// Full GHS, measured PSD stretched along two axes.
    MeasuredPsdAniso {
        /// The surface.
        surface: MeasuredAnisoSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
    /// GHS smooth-surface approximation, measured 2-D PSD.
    MeasuredPsd2dSsa {
        /// The table.
        surface: Psd2dSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
    /// Full GHS, measured 2-D PSD.
    MeasuredPsd2d {
        /// The table.
        surface: Psd2dSpec,
        /// Options (energy `raw` only).
        options: GhsOptions,
    },
    /// A Lambertian reflector.
    Diffuse {
        /// Its reflectance.
        reflectance: ReflectanceSpec,
    },
    /// A GGX dielectric coat over a Lambertian base.
    RoughPlastic {
        /// The coat's GGX roughness.
        alpha: f64,
        /// The coat's index.
        int_ior: f64,
        /// The index of the medium above.
        ext_ior: f64,
        /// The base's reflectance.
        reflectance: ReflectanceSpec,
        /// ρ/(1 − ρR_i) (true) or ρ/(1 − R_i) (false, Mitsuba's default).
        nonlinear: bool,
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
            ModelSpec::MeasuredPsdSsaAniso { .. } => ModelKind::MeasuredPsdSsaAniso,
            ModelSpec::MeasuredPsdAniso { .. } => ModelKind::MeasuredPsdAniso,
            ModelSpec::MeasuredPsd2dSsa { .. } => ModelKind::MeasuredPsd2dSsa,
            ModelSpec::MeasuredPsd2d { .. } => ModelKind::MeasuredPsd2d,
            ModelSpec::Diffuse { .. } => ModelKind::Diffuse,
            ModelSpec::RoughPlastic { .. } => ModelKind::RoughPlastic,
        }
    }

    /// The distribution of `ggx` and `beckmann`, in its own frame, and the angle of that
    /// frame's x axis from the tangent (radians), each checked (the error names its key);
    /// `None` for the other models.
    pub fn microfacet(&self) -> Result<Option<(Distribution, f64)>, SpecError> {
        let (distribution, angle_deg) = match self {
            ModelSpec::Ggx {
                alpha_x,
                alpha_y,
                angle_deg,
            } => (Distribution::ggx(*alpha_x, *alpha_y)?, *angle_deg),
            ModelSpec::Beckmann {
                alpha_x,
                alpha_y,
                angle_deg,
            } => (Distribution::beckmann(*alpha_x, *alpha_y)?, *angle_deg),
            _ => return Ok(None),
        };
        let angle_rad = angle_deg.to_radians();
        crate::statistics::anisotropic::check_angle(angle_rad)?;
        Ok(Some((distribution, angle_rad)))
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
        if !self.model.kind().conductor() && self.fresnel != FresnelSpec::One {
            return Err(SpecError::new(
                "metal",
                format!(
                    "model `{}` has no conductor Fresnel term (its reflectance is its own \
                     parameter); give it no `metal`, `nk`, `nk_csv` or `fresnel`",
                    self.model.kind().name()
                ),
            ));
        }
        match &self.model {
            ModelSpec::Ggx { .. } | ModelSpec::Beckmann { .. } => {
                self.model.microfacet()?;
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
                raw_only(options)?;
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
            ModelSpec::MeasuredPsdSsaAniso { surface, options }
            | ModelSpec::MeasuredPsdAniso { surface, options } => {
                surface.psd()?;
                raw_only(options)?;
            }
            ModelSpec::MeasuredPsd2dSsa { surface, options }
            | ModelSpec::MeasuredPsd2d { surface, options } => {
                surface.psd()?;
                raw_only(options)?;
            }
            ModelSpec::Diffuse { reflectance } => {
                reflectance.build()?;
            }
            ModelSpec::RoughPlastic {
                alpha,
                int_ior,
                ext_ior,
                reflectance,
                nonlinear,
            } => {
                rough_plastic(*alpha, *int_ior, *ext_ior, reflectance, *nonlinear)?;
            }
        }
        Ok(())
    }
}

/// The anisotropic models' energy option: `raw` only.
fn raw_only(options: &GhsOptions) -> Result<(), SpecError> {
    if options.energy != crate::wave::Energy::Raw {
        return Err(SpecError::new(
            "energy",
            "the anisotropic models take `energy = \"raw\"` only (the krywonos and \
             sigma_rel tables are over θi and λ; an anisotropic lobe also depends on \
             the incidence azimuth)",
        ));
    }
    Ok(())
}

/// The parameters of a `roughplastic` material, checked (its tables are built
/// by [`RoughPlastic::new`]).
fn rough_plastic(
    alpha: f64,
    int_ior: f64,
    ext_ior: f64,
    reflectance: &ReflectanceSpec,
    nonlinear: bool,
) -> Result<RoughPlasticParams, SpecError> {
    Distribution::ggx(alpha, alpha)?;
    crate::error::check_range("int_ior", int_ior, 1.0, 4.0, "1 ≤ int_ior ≤ 4")?;
    crate::error::check_range("ext_ior", ext_ior, 1.0, 4.0, "1 ≤ ext_ior ≤ 4")?;
    if int_ior <= ext_ior {
        return Err(SpecError::new(
            "int_ior",
            format!(
                "int_ior = {int_ior} must exceed ext_ior = {ext_ior} (a coat denser than \
                     the medium above it)"
            ),
        ));
    }
    Ok(RoughPlasticParams {
        alpha,
        int_ior,
        ext_ior,
        reflectance: reflectance.build()?,
        nonlinear,
    })
}

impl MaterialSpec {
    /// Whether the built model's value, density and sampling do not depend
    /// on λ at all: `diffuse` and `roughplastic` with a constant
    /// reflectance (the coat's indices are constants), and the
    /// Fresnel-only models ([`ModelKind::fresnel_only`]) with
    /// [`FresnelSpec::One`]. A renderer can then carry such a vertex's
    /// factor as one number for every wavelength. The wave-optical models
    /// scatter by λ-dependent diffraction, so they are never λ-free.
    pub fn lambda_free(&self) -> bool {
        match &self.model {
            ModelSpec::Diffuse { reflectance } | ModelSpec::RoughPlastic { reflectance, .. } => {
                matches!(reflectance, ReflectanceSpec::Constant(_))
            }
            m => m.kind().fresnel_only() && self.fresnel == FresnelSpec::One,
        }
    }

    /// Builds the model (tables included: tens of ms for the wave models).
    pub fn build(&self) -> Result<DynBxdf, SpecError> {
        self.validate()?;
        let fresnel = self.fresnel.build()?;
        Ok(match &self.model {
            ModelSpec::Ggx { .. } | ModelSpec::Beckmann { .. } => {
                let Some((distribution, angle_rad)) = self.model.microfacet()? else {
                    return Err(SpecError::new(
                        "model",
                        "ggx and beckmann have a distribution",
                    ));
                };
                let conductor = MicrofacetConductor::new(distribution, fresnel)?;
                // The unturned model itself at 0 (bit-identical to a material without the
                // key) and for an isotropic pair, which a turn leaves unchanged.
                if angle_rad == 0.0 || distribution.alpha_x() == distribution.alpha_y() {
                    Box::new(conductor)
                } else {
                    Box::new(Rotated::new(conductor, angle_rad)?)
                }
            }
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
            ModelSpec::MeasuredPsdSsaAniso { surface, options } => {
                Box::new(GhsAnisotropic::ssa(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::MeasuredPsdAniso { surface, options } => {
                Box::new(GhsAnisotropic::full(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::MeasuredPsd2dSsa { surface, options } => {
                Box::new(GhsSsaPsd2d::new(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::MeasuredPsd2d { surface, options } => {
                Box::new(GhsPsd2d::new(surface.psd()?, fresnel, *options)?)
            }
            ModelSpec::Diffuse { reflectance } => Box::new(Diffuse::new(reflectance.build()?)),
            ModelSpec::RoughPlastic {
                alpha,
                int_ior,
                ext_ior,
                reflectance,
                nonlinear,
            } => Box::new(RoughPlastic::new(rough_plastic(
                *alpha,
                *int_ior,
                *ext_ior,
                reflectance,
                *nonlinear,
            )?)?),
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
            ModelSpec::Ggx {
                alpha_x, alpha_y, ..
            }
            | ModelSpec::Beckmann {
                alpha_x, alpha_y, ..
            } => alpha_x.min(*alpha_y),
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
            ModelSpec::MeasuredPsdSsaAniso { surface, .. }
            | ModelSpec::MeasuredPsdAniso { surface, .. } => {
                let ratio = (surface.ly_um / surface.lx_um).max(surface.lx_um / surface.ly_um);
                let z0 = surface.zeta_rad_per_um.first().copied().unwrap_or(1.0);
                z0 / (k * libm::sqrt(ratio))
            }
            ModelSpec::MeasuredPsd2dSsa { surface, .. }
            | ModelSpec::MeasuredPsd2d { surface, .. } => {
                surface.dzx_rad_per_um.min(surface.dzy_rad_per_um) / k
            }
            ModelSpec::Smooth => 1e-3,
            ModelSpec::Diffuse { .. } => 1.0,
            ModelSpec::RoughPlastic { alpha, .. } => *alpha,
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
pub use desc::{
    CheckerSquares, FileLoader, FresnelKind, KeyDoc, MaterialDesc, NoFiles, ROUGHPLASTIC_EXT_IOR,
    ROUGHPLASTIC_INT_IOR, ROUGHPLASTIC_REFLECTANCE,
};
#[cfg(feature = "serde")]
pub mod file;
#[cfg(feature = "serde")]
pub use file::MaterialFile;

#[cfg(feature = "serde")]
mod desc;

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
        let measured_aniso = MeasuredAnisoSpec {
            zeta_rad_per_um: zeta.clone(),
            psd_um4: p.clone(),
            lx_um: 0.5,
            ly_um: 4.0,
            angle_deg: -20.0,
        };
        let specs = [
            ModelSpec::Ggx {
                alpha_x: 0.1,
                alpha_y: 0.2,
                angle_deg: 0.0,
            },
            ModelSpec::Beckmann {
                alpha_x: 0.1,
                alpha_y: 0.1,
                angle_deg: 0.0,
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
            ModelSpec::MeasuredPsdSsaAniso {
                surface: measured_aniso.clone(),
                options: GhsOptions::default(),
            },
            ModelSpec::MeasuredPsdAniso {
                surface: measured_aniso,
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
            ModelKind::MeasuredPsdSsaAniso,
            ModelKind::MeasuredPsdAniso,
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
            fn reflectance_table(&mut self, path: &str) -> Result<Vec<[f64; 2]>, String> {
                match path {
                    "grey.csv" => Ok(alloc::vec![[400.0, 0.3], [700.0, 0.5]]),
                    "bright.csv" => Ok(alloc::vec![[400.0, 0.3], [700.0, 1.5]]),
                    _ => Err(format!("{path}: no such file")),
                }
            }
        }

        #[test]
        fn diffuse_and_roughplastic_parse_refuse_an_index_and_round_trip() {
            let d = desc(r#"{"model": "diffuse", "reflectance": 0.25}"#).unwrap();
            let s = d.into_spec(&mut NoFiles).unwrap();
            assert_eq!(
                s.model,
                ModelSpec::Diffuse {
                    reflectance: ReflectanceSpec::Constant(0.25)
                }
            );
            assert_eq!(s.fresnel, FresnelSpec::One);
            assert_eq!(s.to_desc(), d);
            let d = desc(r#"{"model": "diffuse", "reflectance_csv": "grey.csv"}"#).unwrap();
            let s = d.into_spec(&mut Files).unwrap();
            assert!(matches!(
                s.model,
                ModelSpec::Diffuse {
                    reflectance: ReflectanceSpec::Table(ref r)
                } if r.len() == 2
            ));
            let d = desc(r#"{"model": "roughplastic", "alpha": 0.2}"#).unwrap();
            let s = d.into_spec(&mut NoFiles).unwrap();
            assert_eq!(
                s.model,
                ModelSpec::RoughPlastic {
                    alpha: 0.2,
                    int_ior: 1.49,
                    ext_ior: 1.0,
                    reflectance: ReflectanceSpec::Constant(0.5),
                    nonlinear: false
                }
            );
            assert_eq!(s.to_desc().into_spec(&mut NoFiles).unwrap(), s);
            for model in ["diffuse", "roughplastic"] {
                assert!(!ModelKind::from_name(model).unwrap().fresnel_only());
                for (key, value) in [
                    ("metal", r#""cu""#),
                    ("nk", "[0.2, 3.0]"),
                    ("nk_csv", r#""cu.csv""#),
                    ("fresnel", r#""one""#),
                ] {
                    let json = format!(
                        r#"{{"model": "{model}", "alpha": 0.1, "reflectance": 0.5, "{key}": {value}}}"#
                    );
                    let json = json.replace(
                        r#""alpha": 0.1, "#,
                        if model == "diffuse" {
                            ""
                        } else {
                            r#""alpha": 0.1, "#
                        },
                    );
                    let e = desc(&json).unwrap().into_spec(&mut Files).unwrap_err();
                    assert_eq!(e.field, key, "{json}: {e}");
                    assert!(e.message.contains("no conductor Fresnel"), "{e}");
                }
                // A typed spec with a conductor index is refused too.
                let mut s = desc(&format!(r#"{{"model": "{model}", "alpha": 0.1}}"#).replace(
                    r#", "alpha": 0.1"#,
                    if model == "diffuse" {
                        r#", "reflectance": 1"#
                    } else {
                        r#", "alpha": 0.1"#
                    },
                ))
                .unwrap()
                .into_spec(&mut NoFiles)
                .unwrap();
                s.fresnel = FresnelSpec::Metal(Metal::Cu);
                assert!(
                    s.validate()
                        .unwrap_err()
                        .message
                        .contains("no conductor Fresnel")
                );
            }
            // An included fit file's metal is not this model's concern.
            let base = desc(r#"{"model": "ggx", "metal": "cu", "alpha": 0.2}"#).unwrap();
            let own = desc(r#"{"model": "diffuse", "reflectance": 0.4}"#).unwrap();
            assert_eq!(
                own.resolve(Some(&base), &mut NoFiles).unwrap().fresnel,
                FresnelSpec::One
            );
            for (json, field) in [
                (r#"{"model": "diffuse"}"#, "reflectance"),
                (
                    r#"{"model": "diffuse", "reflectance": 1.01}"#,
                    "reflectance",
                ),
                (
                    r#"{"model": "diffuse", "reflectance": 0.5, "reflectance_csv": "grey.csv"}"#,
                    "reflectance",
                ),
                (
                    r#"{"model": "diffuse", "reflectance_csv": "bright.csv"}"#,
                    "reflectance_csv",
                ),
                (
                    r#"{"model": "diffuse", "reflectance_csv": "missing.csv"}"#,
                    "reflectance_csv",
                ),
                (
                    r#"{"model": "diffuse", "reflectance": 0.5, "alpha": 0.1}"#,
                    "alpha",
                ),
                (r#"{"model": "roughplastic", "reflectance": 0.5}"#, "alpha"),
                (
                    r#"{"model": "roughplastic", "alpha": 0.1, "int_ior": 1.0}"#,
                    "int_ior",
                ),
                (
                    r#"{"model": "roughplastic", "alpha": 0.1, "int_ior": 9}"#,
                    "int_ior",
                ),
                (
                    r#"{"model": "roughplastic", "alpha": 0.1, "ext_ior": 0.5}"#,
                    "ext_ior",
                ),
                (
                    r#"{"model": "roughplastic", "alpha": 0.1, "alpha_x": 0.1, "alpha_y": 0.2}"#,
                    "alpha",
                ),
                (
                    r#"{"model": "roughplastic", "alpha_x": 0.1, "alpha_y": 0.2}"#,
                    "alpha_x",
                ),
                (
                    r#"{"model": "ggx", "metal": "cu", "alpha": 0.1, "reflectance": 0.2}"#,
                    "reflectance",
                ),
            ] {
                let e = desc(json).unwrap().into_spec(&mut Files).unwrap_err();
                assert_eq!(e.field, field, "{json}: {e}");
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
                let (ModelSpec::Ggx {
                    alpha_x, alpha_y, ..
                }
                | ModelSpec::Beckmann {
                    alpha_x, alpha_y, ..
                }) = s.model
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
                    alpha_y: 0.1,
                    angle_deg: 0.0,
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
                    alpha_y: 0.25,
                    angle_deg: 0.0,
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
                angle_deg: 0.0,
            },
            fresnel: FresnelSpec::One,
        };
        assert!(bad.validate().is_err());
    }
}
