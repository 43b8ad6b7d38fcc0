//! Materials: one `brdf` model per named material, built from its description.
//!
//! Each model is one match arm producing a `Box<dyn Bxdf + Send + Sync>`, so
//! adding a model is adding an arm.

use crate::scene::desc::{
    CoherentDesc, EnergyDesc, FresnelAngleDesc, FresnelKind, MaterialDesc, ModelKind,
};
use crate::scene::inputs::{Inputs, MAX_CSV_BYTES, MAX_TOML_BYTES};
use crate::spectrum::parse_csv_rows;
use brdf::wave::two_scale::{
    CoherentPart, TableResolution as TwoScaleResolution, TwoScale, TwoScaleParams,
};
use brdf::wave::{Energy, FresnelAngle, GhsFull, GhsOptions, GhsSsa, KcPsd, TabulatedPsd};
use brdf::{Bxdf, Distribution, Fresnel, Ior, Metal, MicrofacetConductor, SmoothConductor};
use std::path::Path;

/// A model behind dynamic dispatch, shareable across render threads.
pub type DynBxdf = Box<dyn Bxdf + Send + Sync>;

/// A built material.
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// The model kind.
    pub model: ModelKind,
    /// The model.
    pub bxdf: DynBxdf,
}

/// A material description with its include file folded in.
pub struct Resolved {
    /// Scalar keys (scene keys win over the include's).
    pub desc: MaterialDesc,
    /// Measured PSD samples (ζ rad/µm, P µm⁴) from the include's `[psd]` table.
    pub psd: Option<(Vec<f64>, Vec<f64>)>,
}

/// Resolves `include` (a `lustre fit` material file) under the scene's own
/// keys: keys set in the scene win. For `two_scale`, the parameters come from
/// the include's `[two_scale.NAME]` table chosen by `cutoff = "NAME"`.
///
/// The file is read through `inputs`, so it is part of the film fingerprint.
/// Its `[material]`, `[two_scale.NAME]` and `[psd]` tables reject unknown
/// keys (listing the valid ones), as scene tables do; `[provenance]`,
/// `[fit]` and `[kc_2d]` hold `lustre fit`'s diagnostics and are not read.
pub fn resolve_include(
    desc: &MaterialDesc,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Resolved, String> {
    let Some(inc) = &desc.include else {
        return Ok(Resolved {
            desc: desc.clone(),
            psd: None,
        });
    };
    let path = base_dir.join(inc);
    let text = inputs
        .read_text(&path, "material file", MAX_TOML_BYTES)
        .map_err(|e| format!("include = \"{}\": {e}", inc.display()))?;
    let located = |e: toml::de::Error, what: &str| {
        let pos = e.span().map(|s| crate::error::line_column(&text, s.start));
        match pos {
            Some((l, c)) => format!("{}:{l}:{c}: {what}{}", path.display(), e.message().trim()),
            None => format!("{}: {what}{}", path.display(), e.message().trim()),
        }
    };
    let file: FitFile = toml::from_str(&text).map_err(|e| located(e, ""))?;
    let Some(fit) = file.material else {
        return Err(format!(
            "{}: a material file needs a [material] table (as written by `lustre fit`)",
            path.display()
        ));
    };
    let mut out = desc.clone();
    out.include = None;
    // The include's own relative paths are relative to the include; the
    // caller joins the result to `base_dir`, so keep it relative to that.
    let inc_dir = inc.parent().unwrap_or(Path::new(""));
    macro_rules! inherit {
        ($src:expr; $($f:ident),*) => { $( if out.$f.is_none() { out.$f = $src.$f; } )* };
    }
    inherit!(fit; model, metal, alpha, alpha_beckmann);
    if out.nk_csv.is_none() {
        out.nk_csv = fit.nk_csv.map(|p| inc_dir.join(p));
    }
    if out.model == Some(ModelKind::TwoScale) {
        let names: Vec<&str> = file.two_scale.keys().map(String::as_str).collect();
        let chosen = match (&desc.cutoff, names.as_slice()) {
            (Some(c), _) => c.as_str(),
            (None, [only]) => only,
            (None, _) => {
                return Err(format!(
                    "{}: choose a two-scale split with `cutoff = \"NAME\"`; the file has: {}",
                    path.display(),
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ));
            }
        };
        let t = file.two_scale.get(chosen).ok_or_else(|| {
            format!(
                "{}: no [two_scale.{chosen}] table; the file has: {}",
                path.display(),
                names.join(", ")
            )
        })?;
        inherit!(t; beta, sigma_um, lc_um, gamma);
    }
    inherit!(fit; sigma_um, lc_um, gamma);
    let psd = file.psd.map(|p| (p.zeta_rad_per_um, p.p_um4));
    Ok(Resolved { desc: out, psd })
}

/// A `lustre fit` material file. The tables the renderer reads reject
/// unknown keys, so that a misspelt parameter is an error rather than a
/// silently kept default; the diagnostics tables `fit` writes next to them
/// are accepted whatever they hold.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitFile {
    material: Option<FitMaterial>,
    #[serde(default)]
    two_scale: std::collections::BTreeMap<String, FitTwoScale>,
    psd: Option<FitPsd>,
    /// Diagnostics of `lustre fit` (not read).
    #[serde(default, rename = "provenance")]
    _provenance: Option<toml::Table>,
    /// Diagnostics of `lustre fit` (not read).
    #[serde(default, rename = "fit")]
    _fit: Option<toml::Table>,
    /// Diagnostics of `lustre fit` (not read).
    #[serde(default, rename = "kc_2d")]
    _kc_2d: Option<toml::Table>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitMaterial {
    model: Option<ModelKind>,
    metal: Option<String>,
    nk_csv: Option<std::path::PathBuf>,
    alpha: Option<f64>,
    alpha_beckmann: Option<f64>,
    sigma_um: Option<f64>,
    lc_um: Option<f64>,
    gamma: Option<f64>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitTwoScale {
    beta: Option<f64>,
    sigma_um: Option<f64>,
    lc_um: Option<f64>,
    gamma: Option<f64>,
    /// Written by `lustre fit` as provenance of the split (not read).
    #[serde(default, rename = "beta_source")]
    _beta_source: Option<toml::Value>,
    #[serde(default, rename = "cutoff_um")]
    _cutoff_um: Option<toml::Value>,
    #[serde(default, rename = "fit_f_range_per_m")]
    _fit_f_range_per_m: Option<toml::Value>,
    #[serde(default, rename = "kc_degenerate")]
    _kc_degenerate: Option<toml::Value>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitPsd {
    zeta_rad_per_um: Vec<f64>,
    p_um4: Vec<f64>,
    /// Written by `lustre fit` as provenance of the table (not read).
    #[serde(default, rename = "source")]
    _source: Option<toml::Value>,
    #[serde(default, rename = "integral_um2")]
    _integral_um2: Option<toml::Value>,
}

/// Reads a two-column `zeta_rad_per_um,p_um4` CSV.
fn read_psd_csv(path: &Path, inputs: &mut Inputs) -> Result<(Vec<f64>, Vec<f64>), String> {
    let text = inputs
        .read_text(path, "psd_csv", MAX_CSV_BYTES)
        .map_err(|e| format!("psd_csv: {e}"))?;
    let rows = parse_csv_rows(&text, 2).map_err(|e| format!("psd_csv {}: {e}", path.display()))?;
    Ok(rows.into_iter().map(|r| (r[0], r[1])).unzip())
}

/// Builds the Fresnel factor of a (resolved) material description.
fn fresnel(desc: &MaterialDesc, base_dir: &Path, inputs: &mut Inputs) -> Result<Fresnel, String> {
    if desc.fresnel == Some(FresnelKind::One) {
        return Ok(Fresnel::One);
    }
    let given = [
        desc.metal.is_some(),
        desc.nk_csv.is_some(),
        desc.nk.is_some(),
    ];
    match given.iter().filter(|&&g| g).count() {
        0 => {
            return Err(
                "needs one of `metal = \"NAME\"`, `nk_csv = \"file.csv\"`, `nk = [n, k]` \
                        (or `fresnel = \"one\"`)"
                    .into(),
            );
        }
        1 => {}
        _ => return Err("give only one of `metal`, `nk_csv`, `nk`".into()),
    }
    let ior = if let Some(name) = &desc.metal {
        let metal = Metal::from_name(name).ok_or_else(|| {
            let names: Vec<&str> = Metal::ALL.iter().map(|m| m.name()).collect();
            format!("unknown metal `{name}`; valid: {}", names.join(", "))
        })?;
        Ior::metal(metal)
    } else if let Some(csv) = &desc.nk_csv {
        let path = base_dir.join(csv);
        let text = inputs
            .read_text(&path, "nk_csv", MAX_CSV_BYTES)
            .map_err(|e| format!("nk_csv: {e}"))?;
        let rows =
            parse_csv_rows(&text, 3).map_err(|e| format!("nk_csv {}: {e}", path.display()))?;
        Ior::table(rows.into_iter().map(|r| [r[0], r[1], r[2]]).collect())
            .map_err(|e| format!("nk_csv {}: {e}", path.display()))?
    } else {
        let [n, k] = desc.nk.unwrap_or_default();
        Ior::constant(n, k).map_err(|e| format!("nk: {e}"))?
    };
    Ok(Fresnel::conductor(ior))
}

fn required(v: Option<f64>, key: &str, model: ModelKind) -> Result<f64, String> {
    v.ok_or_else(|| format!("model `{}` needs `{key}`", model.name()))
}

fn roughness(
    desc: &MaterialDesc,
    model: ModelKind,
    iso: Option<f64>,
) -> Result<(f64, f64), String> {
    match (desc.alpha_x, desc.alpha_y, iso) {
        (Some(x), Some(y), _) => Ok((x, y)),
        (None, None, Some(a)) => Ok((a, a)),
        (Some(_), None, _) | (None, Some(_), _) => Err("give both `alpha_x` and `alpha_y`".into()),
        (None, None, None) => Err(format!(
            "model `{}` needs `alpha` (or `alpha_x` and `alpha_y`)",
            model.name()
        )),
    }
}

/// The KC surface of a GHS-family material.
fn kc(desc: &MaterialDesc, model: ModelKind) -> Result<KcPsd, String> {
    KcPsd::new(
        required(desc.sigma_um, "sigma_um", model)?,
        required(desc.lc_um, "lc_um", model)?,
        required(desc.gamma, "gamma", model)?,
    )
    .map_err(|e| e.to_string())
}

fn ghs_options(desc: &MaterialDesc) -> GhsOptions {
    GhsOptions {
        energy: match desc.energy.unwrap_or(EnergyDesc::Raw) {
            EnergyDesc::Raw => Energy::Raw,
            EnergyDesc::Krywonos => Energy::Krywonos,
            EnergyDesc::SigmaRel => Energy::SigmaRel,
        },
        fresnel_angle: match desc.fresnel_angle.unwrap_or(FresnelAngleDesc::Halfway) {
            FresnelAngleDesc::Halfway => FresnelAngle::Halfway,
            FresnelAngleDesc::Incident => FresnelAngle::Incident,
        },
    }
}

/// Builds the named material. `base_dir` resolves relative paths; every
/// file is read through `inputs`.
pub fn build_material(
    name: &str,
    desc: &MaterialDesc,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Material, String> {
    let Resolved { desc, psd } = resolve_include(desc, base_dir, inputs)?;
    let Some(model) = desc.model else {
        return Err(
            "needs `model`; valid: ggx, beckmann, smooth, ghs_ssa, ghs, two_scale, measured_psd"
                .into(),
        );
    };
    let fresnel = fresnel(&desc, base_dir, inputs)?;
    let err = |e: brdf::BrdfError| e.to_string();
    let bxdf: DynBxdf = match model {
        ModelKind::Ggx => {
            let (ax, ay) = roughness(&desc, model, desc.alpha)?;
            Box::new(
                MicrofacetConductor::new(Distribution::ggx(ax, ay).map_err(err)?, fresnel)
                    .map_err(err)?,
            )
        }
        ModelKind::Beckmann => {
            let (ax, ay) = roughness(&desc, model, desc.alpha_beckmann.or(desc.alpha))?;
            Box::new(
                MicrofacetConductor::new(Distribution::beckmann(ax, ay).map_err(err)?, fresnel)
                    .map_err(err)?,
            )
        }
        ModelKind::Smooth => Box::new(SmoothConductor::new(fresnel).map_err(err)?),
        ModelKind::GhsSsa => Box::new(
            GhsSsa::with_options(kc(&desc, model)?, fresnel, ghs_options(&desc)).map_err(err)?,
        ),
        ModelKind::Ghs => Box::new(
            GhsFull::with_options(kc(&desc, model)?, fresnel, ghs_options(&desc)).map_err(err)?,
        ),
        ModelKind::MeasuredPsd => {
            let (zeta, p) = match (&desc.psd_csv, psd) {
                (Some(csv), _) => read_psd_csv(&base_dir.join(csv), inputs)?,
                (None, Some(t)) => t,
                (None, None) => {
                    return Err("model `measured_psd` needs `psd_csv = \"file.csv\"` (zeta_rad_per_um,p_um4) \
                                or an `include` file with a [psd] table"
                        .into());
                }
            };
            let table = TabulatedPsd::new(&zeta, &p).map_err(|e| format!("measured PSD: {e}"))?;
            Box::new(GhsFull::with_options(table, fresnel, ghs_options(&desc)).map_err(err)?)
        }
        ModelKind::TwoScale => Box::new(
            TwoScale::new(TwoScaleParams {
                beta: required(desc.beta, "beta", model)?,
                sigma_um: required(desc.sigma_um, "sigma_um", model)?,
                lc_um: required(desc.lc_um, "lc_um", model)?,
                gamma: required(desc.gamma, "gamma", model)?,
                fresnel,
                coherent: match desc.coherent.unwrap_or(CoherentDesc::MacroNdf) {
                    CoherentDesc::MacroNdf => CoherentPart::MacroNdf,
                    CoherentDesc::Delta => CoherentPart::Delta,
                },
                resolution: TwoScaleResolution::default(),
            })
            .map_err(err)?,
        ),
    };
    Ok(Material {
        name: name.to_string(),
        model,
        bxdf,
    })
}
