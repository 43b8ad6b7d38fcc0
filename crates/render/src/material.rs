//! Materials: a scene's `[materials.NAME]` table is a [`brdf::spec::MaterialDesc`],
//! the flat schema `brdf eval` queries and `lustre fit` material files use too.
//! This module reads the files a description names (through [`Inputs`], so they
//! are part of the film fingerprint), folds in an `include`d fit file, and lets
//! `brdf::spec` validate and build the model: one schema, one validation, one
//! builder for every entry point.

use crate::scene::inputs::{Inputs, MAX_CSV_BYTES, MAX_TOML_BYTES};
use crate::spectrum::parse_csv_rows;
pub use brdf::spec::DynBxdf;
use brdf::spec::{FileLoader, MaterialDesc, ModelKind};
use std::path::Path;

/// A built material.
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// The model kind.
    pub model: ModelKind,
    /// The model.
    pub bxdf: DynBxdf,
}

/// A PSD table `(ζ rad/µm, P µm⁴)` under the name `psd_csv` refers to it by.
type NamedPsd = (String, (Vec<f64>, Vec<f64>));

/// Reads `nk_csv` / `psd_csv` relative to the scene file through `inputs`;
/// the included file's `[psd]` table answers for the name it was given.
struct SceneFiles<'a> {
    base_dir: &'a Path,
    inputs: &'a mut Inputs,
    inline_psd: Option<NamedPsd>,
}

impl FileLoader for SceneFiles<'_> {
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
        let full = self.base_dir.join(path);
        let text = self.inputs.read_text(&full, "nk_csv", MAX_CSV_BYTES)?;
        let rows = parse_csv_rows(&text, 3).map_err(|e| format!("{}: {e}", full.display()))?;
        Ok(rows.into_iter().map(|r| [r[0], r[1], r[2]]).collect())
    }

    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
        if let Some((name, table)) = &self.inline_psd
            && name == path
        {
            return Ok(table.clone());
        }
        let full = self.base_dir.join(path);
        let text = self.inputs.read_text(&full, "psd_csv", MAX_CSV_BYTES)?;
        let rows = parse_csv_rows(&text, 2).map_err(|e| format!("{}: {e}", full.display()))?;
        Ok(rows.into_iter().map(|r| (r[0], r[1])).unzip())
    }
}

/// What an `include`d `lustre fit` file contributes.
struct Included {
    /// Its `[material]` (with the chosen `[two_scale.NAME]` over it for
    /// `two_scale`), paths made relative to the scene file.
    base: MaterialDesc,
    /// Its `[psd]` table under the name `psd_csv` refers to it by.
    psd: Option<NamedPsd>,
}

/// The tables of a fit file the renderer reads. `[material]` is a
/// `MaterialDesc` and refuses unknown keys; from `[two_scale.NAME]` and
/// `[psd]` only the parameters are read (`lustre fit` writes provenance and
/// reliability notes next to them); the diagnostics tables (`[fit]`,
/// `[reliability]`, `[form]`, …) are not read.
fn read_include(
    desc: &MaterialDesc,
    inc: &str,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Included, String> {
    let path = base_dir.join(inc);
    let text = inputs
        .read_text(&path, "material file", MAX_TOML_BYTES)
        .map_err(|e| format!("include = \"{inc}\": {e}"))?;
    let located = |e: toml::de::Error| {
        let pos = e.span().map(|s| crate::error::line_column(&text, s.start));
        match pos {
            Some((l, c)) => format!("{}:{l}:{c}: {}", path.display(), e.message().trim()),
            None => format!("{}: {}", path.display(), e.message().trim()),
        }
    };
    let mut file: toml::Table = toml::from_str(&text).map_err(located)?;
    let Some(material) = file.remove("material") else {
        return Err(format!(
            "{}: a material file needs a [material] table (as written by `lustre fit`)",
            path.display()
        ));
    };
    let mut base: MaterialDesc = material.try_into().map_err(|e: toml::de::Error| {
        format!("{}: [material]: {}", path.display(), e.message().trim())
    })?;
    if base.include.is_some() || base.cutoff.is_some() {
        return Err(format!(
            "{}: [material] cannot itself use `include` or `cutoff`",
            path.display()
        ));
    }
    // The include's own relative paths are relative to the include.
    let inc_dir = Path::new(inc).parent().unwrap_or(Path::new(""));
    for p in [&mut base.nk_csv, &mut base.psd_csv].into_iter().flatten() {
        *p = inc_dir.join(&*p).to_string_lossy().into_owned();
    }

    let model = desc.model.or(base.model);
    if model == Some(ModelKind::TwoScale) {
        let splits = match file.remove("two_scale") {
            None => toml::Table::new(),
            Some(toml::Value::Table(t)) => t,
            Some(_) => {
                return Err(format!(
                    "{}: `two_scale` must be tables [two_scale.NAME]",
                    path.display()
                ));
            }
        };
        let names: Vec<&str> = splits.keys().map(String::as_str).collect();
        let listed = if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        };
        let chosen = match (&desc.cutoff, names.as_slice()) {
            (Some(c), _) => c.as_str(),
            (None, [only]) => only,
            (None, _) => {
                return Err(format!(
                    "{}: choose a two-scale split with `cutoff = \"NAME\"`; the file has: {listed}",
                    path.display()
                ));
            }
        };
        let Some(toml::Value::Table(t)) = splits.get(chosen) else {
            return Err(format!(
                "{}: no [two_scale.{chosen}] table; the file has: {listed}",
                path.display()
            ));
        };
        let number = |key: &str| -> Result<f64, String> {
            match t.get(key) {
                Some(toml::Value::Float(v)) => Ok(*v),
                Some(toml::Value::Integer(v)) => Ok(*v as f64),
                Some(_) => Err(format!(
                    "{}: [two_scale.{chosen}] `{key}` must be a number",
                    path.display()
                )),
                None => Err(format!(
                    "{}: [two_scale.{chosen}] needs `{key}`",
                    path.display()
                )),
            }
        };
        // The split's micro scale replaces the whole-surface KC fit.
        base.beta = Some(number("beta")?);
        base.sigma_um = Some(number("sigma_um")?);
        base.lc_um = Some(number("lc_um")?);
        base.gamma = Some(number("gamma")?);
    }

    let psd = match file.remove("psd") {
        Some(toml::Value::Table(t)) if model == Some(ModelKind::MeasuredPsd) => {
            let column = |key: &str| -> Result<Vec<f64>, String> {
                let bad = || {
                    format!(
                        "{}: [psd] `{key}` must be an array of numbers",
                        path.display()
                    )
                };
                match t.get(key) {
                    Some(toml::Value::Array(a)) => a
                        .iter()
                        .map(|v| match v {
                            toml::Value::Float(x) => Ok(*x),
                            toml::Value::Integer(x) => Ok(*x as f64),
                            _ => Err(bad()),
                        })
                        .collect(),
                    Some(_) => Err(bad()),
                    None => Err(format!("{}: [psd] needs `{key}`", path.display())),
                }
            };
            let name = format!("[psd] of {inc}");
            if base.psd_csv.is_none() {
                base.psd_csv = Some(name.clone());
            }
            Some((name, (column("zeta_rad_per_um")?, column("p_um4")?)))
        }
        _ => None,
    };
    Ok(Included { base, psd })
}

/// Builds the named material. `base_dir` resolves relative paths; every
/// file is read through `inputs`.
pub fn build_material(
    name: &str,
    desc: &MaterialDesc,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Material, String> {
    let included = match &desc.include {
        Some(inc) => Some(read_include(desc, inc, base_dir, inputs)?),
        None => {
            if desc.cutoff.is_some() {
                return Err(
                    "`cutoff` picks a split of an `include`d fit file; this material has no `include`"
                        .into(),
                );
            }
            None
        }
    };
    let (base, inline_psd) = match included {
        Some(Included { base, psd }) => (Some(base), psd),
        None => (None, None),
    };
    let mut files = SceneFiles {
        base_dir,
        inputs,
        inline_psd,
    };
    let spec = desc
        .resolve(base.as_ref(), &mut files)
        .map_err(|e| e.to_string())?;
    let bxdf = spec.build().map_err(|e| e.to_string())?;
    Ok(Material {
        name: name.to_string(),
        model: spec.model.kind(),
        bxdf,
    })
}
