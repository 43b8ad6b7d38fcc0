//! Materials: one `brdf` model per named material, built from its description.
//!
//! Each model is one match arm producing a `Box<dyn Bxdf + Send + Sync>`, so
//! adding a model is adding an arm.

use crate::scene::desc::{FresnelKind, MaterialDesc, ModelKind};
use crate::spectrum::parse_csv_rows;
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

/// Resolves `include` (a `lustre fit` material file) under the scene's own
/// keys: keys set in the scene win. Returns the merged description.
pub fn resolve_include(desc: &MaterialDesc, base_dir: &Path) -> Result<MaterialDesc, String> {
    let Some(inc) = &desc.include else {
        return Ok(desc.clone());
    };
    let path = base_dir.join(inc);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        format!(
            "include = \"{}\": cannot read {}: {e}",
            inc.display(),
            path.display()
        )
    })?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| {
        let pos = e.span().map(|s| crate::error::line_column(&text, s.start));
        match pos {
            Some((l, c)) => format!("{}:{l}:{c}: {}", path.display(), e.message()),
            None => format!("{}: {}", path.display(), e.message()),
        }
    })?;
    let Some(mat) = table.get("material") else {
        return Err(format!(
            "{}: a material file needs a [material] table (as written by `lustre fit`)",
            path.display()
        ));
    };
    let fit: FitMaterial = mat
        .clone()
        .try_into()
        .map_err(|e: toml::de::Error| format!("{}: [material]: {}", path.display(), e.message()))?;
    let mut out = desc.clone();
    out.include = None;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    macro_rules! inherit {
        ($($f:ident),*) => { $( if out.$f.is_none() { out.$f = fit.$f; } )* };
    }
    inherit!(model, metal, alpha, alpha_beckmann, sigma_um, lc_um, gamma);
    if out.nk_csv.is_none() {
        out.nk_csv = fit.nk_csv.map(|p| base_dir.join(p));
    }
    Ok(out)
}

/// The `[material]` table of a fit file. Unlike scene tables it tolerates
/// extra keys, since `lustre fit` records provenance next to the parameters.
#[derive(serde::Deserialize)]
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

/// Builds the Fresnel factor of a (resolved) material description.
fn fresnel(desc: &MaterialDesc, base_dir: &Path) -> Result<Fresnel, String> {
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
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("nk_csv: cannot read {}: {e}", path.display()))?;
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

/// Builds the named material. `base_dir` resolves relative paths.
pub fn build_material(
    name: &str,
    desc: &MaterialDesc,
    base_dir: &Path,
) -> Result<Material, String> {
    let desc = resolve_include(desc, base_dir)?;
    let Some(model) = desc.model else {
        return Err(
            "needs `model`; valid: ggx, beckmann, smooth, ghs_ssa, ghs, two_scale, measured_psd"
                .into(),
        );
    };
    let fresnel = fresnel(&desc, base_dir)?;
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
        ModelKind::GhsSsa | ModelKind::Ghs | ModelKind::TwoScale | ModelKind::MeasuredPsd => {
            let _ = (
                required(desc.sigma_um, "sigma_um", model),
                desc.lc_um,
                desc.gamma,
            );
            return Err(format!(
                "model `{}` is not available yet: the brdf crate does not provide it in this build",
                model.name()
            ));
        }
    };
    Ok(Material {
        name: name.to_string(),
        model,
        bxdf,
    })
}
