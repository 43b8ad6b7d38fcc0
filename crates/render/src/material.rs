//! Materials: a scene's `[materials.NAME]` table is a [`brdf::spec::MaterialDesc`],
//! the flat schema `brdf eval` queries and `lustre fit` material files use too.
//! This module reads the files a description names (through [`Inputs`], so they
//! are part of the film fingerprint), folds in an `include`d fit file, and lets
//! `brdf::spec` validate and build the model: one schema, one validation, one
//! builder for every entry point.

use crate::inputs::{Inputs, MAX_CSV_BYTES, MAX_TOML_BYTES};
use crate::spectrum::parse_csv_rows;
use brdf::Fresnel;
pub use brdf::spec::DynBxdf;
use brdf::spec::{FileLoader, FresnelSpec, MaterialDesc, MaterialSpec, ModelKind};
use std::path::Path;

/// A built material.
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// The model kind.
    pub model: ModelKind,
    /// The model.
    pub bxdf: DynBxdf,
    /// For the models whose only dependence on λ is a Fresnel factor
    /// ([`ModelKind::fresnel_only`]): that factor and the model without it,
    /// so the integrator can integrate a single-scattering contribution
    /// over λ exactly (`spectral_table.rs`). It must describe `bxdf`: whoever
    /// replaces `bxdf` by another model replaces or clears it too.
    pub fresnel_only: Option<FresnelOnly>,
}

/// A material split into its Fresnel factor and a λ-free rest.
pub struct FresnelOnly {
    /// The Fresnel factor F(λ, cosθd).
    pub fresnel: Fresnel,
    /// The same model built with F ≡ 1.
    pub unit: DynBxdf,
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
    /// The file as read, and the table the two-scale keys came from, so that
    /// an invalid value it supplied is reported at its own line.
    path: std::path::PathBuf,
    text: String,
    split: Option<String>,
}

/// 1-based line of `key = …` inside `[table]` of a TOML text (as `lustre fit`
/// writes it: one key per line, tables by header).
fn key_line(text: &str, table: &str, key: &str) -> Option<usize> {
    let header = format!("[{table}]");
    let mut inside = false;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            inside = t == header;
        } else if inside
            && let Some(rest) = t.strip_prefix(key)
            && rest.trim_start().starts_with('=')
        {
            return Some(i + 1);
        }
    }
    None
}

impl Included {
    /// Where an invalid value of `field` that the include supplied is: the
    /// file, line and table.
    fn locate(&self, field: &str) -> String {
        let table = match &self.split {
            Some(name) if matches!(field, "beta" | "sigma_um" | "lc_um" | "gamma") => {
                format!("two_scale.{name}")
            }
            _ => "material".to_string(),
        };
        match key_line(&self.text, &table, field) {
            Some(l) => format!("{}:{l}: [{table}]", self.path.display()),
            None => format!("{}: [{table}]", self.path.display()),
        }
    }
}

/// A `lustre fit` material file. `[material]` is a [`MaterialDesc`]; the
/// parameters of `[two_scale.NAME]` and `[psd]` are read next to the
/// provenance `lustre fit` writes there; the diagnostics tables are accepted
/// whatever they hold. Every table refuses unknown keys, so a misspelt key in
/// a hand-edited file is an error with its line and column.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitFile {
    material: Option<MaterialDesc>,
    #[serde(default)]
    two_scale: std::collections::BTreeMap<String, FitSplit>,
    psd: Option<FitPsd>,
    /// Diagnostics of `lustre fit` (not read).
    #[serde(default, rename = "provenance")]
    _provenance: Option<toml::Table>,
    #[serde(default, rename = "fit")]
    _fit: Option<toml::Table>,
    #[serde(default, rename = "kc_2d")]
    _kc_2d: Option<toml::Table>,
    #[serde(default, rename = "reliability")]
    _reliability: Option<toml::Table>,
    #[serde(default, rename = "form")]
    _form: Option<toml::Table>,
    #[serde(default, rename = "anisotropy")]
    _anisotropy: Option<toml::Table>,
}

/// `[two_scale.NAME]`: the split's parameters and `lustre fit`'s notes on it.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitSplit {
    beta: f64,
    sigma_um: f64,
    lc_um: f64,
    gamma: f64,
    #[serde(default, rename = "beta_source")]
    _beta_source: Option<toml::Value>,
    #[serde(default, rename = "cutoff_um")]
    _cutoff_um: Option<toml::Value>,
    #[serde(default, rename = "fit_f_range_per_m")]
    _fit_f_range_per_m: Option<toml::Value>,
    #[serde(default, rename = "kc_degenerate")]
    _kc_degenerate: Option<toml::Value>,
    #[serde(default, rename = "problem")]
    _problem: Option<toml::Value>,
}

/// `[psd]`: the measured PSD and `lustre fit`'s notes on it.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitPsd {
    zeta_rad_per_um: Vec<f64>,
    p_um4: Vec<f64>,
    #[serde(default, rename = "source")]
    _source: Option<toml::Value>,
    #[serde(default, rename = "integral_um2")]
    _integral_um2: Option<toml::Value>,
    #[serde(default, rename = "usable")]
    _usable: Option<toml::Value>,
    #[serde(default, rename = "dropped_bins")]
    _dropped_bins: Option<toml::Value>,
}

/// Reads an included fit file: its `[material]` under the scene's keys, the
/// chosen `[two_scale.NAME]` over it for `two_scale`, its `[psd]` for
/// `measured_psd`.
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
    let file: FitFile = toml::from_str(&text).map_err(|e| {
        let pos = e.span().map(|s| crate::error::line_column(&text, s.start));
        match pos {
            Some((l, c)) => format!("{}:{l}:{c}: {}", path.display(), e.message().trim()),
            None => format!("{}: {}", path.display(), e.message().trim()),
        }
    })?;
    let Some(mut base) = file.material else {
        return Err(format!(
            "{}: a material file needs a [material] table (as written by `lustre fit`)",
            path.display()
        ));
    };
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
    let mut split = None;
    if model == Some(ModelKind::TwoScale) {
        let names: Vec<&str> = file.two_scale.keys().map(String::as_str).collect();
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
        let Some(t) = file.two_scale.get(chosen) else {
            return Err(format!(
                "{}: no [two_scale.{chosen}] table; the file has: {listed}",
                path.display()
            ));
        };
        // The split's micro scale replaces the whole-surface KC fit.
        base.beta = Some(t.beta);
        base.sigma_um = Some(t.sigma_um);
        base.lc_um = Some(t.lc_um);
        base.gamma = Some(t.gamma);
        split = Some(chosen.to_string());
    }
    let psd = match file.psd {
        Some(t) if model == Some(ModelKind::MeasuredPsd) => {
            let name = format!("[psd] of {inc}");
            if base.psd_csv.is_none() {
                base.psd_csv = Some(name.clone());
            }
            Some((name, (t.zeta_rad_per_um, t.p_um4)))
        }
        _ => None,
    };
    Ok(Included {
        base,
        psd,
        path,
        text,
        split,
    })
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
    let (base, inline_psd) = match &included {
        Some(inc) => (Some(&inc.base), inc.psd.clone()),
        None => (None, None),
    };
    let mut files = SceneFiles {
        base_dir,
        inputs,
        inline_psd,
    };
    let spec = desc
        .resolve(base, &mut files)
        .map_err(|e| match &included {
            // The value came from the include: say where it is, not only which key.
            Some(inc) if desc.inherits(&inc.base, e.field) => {
                format!("{}: {e}", inc.locate(e.field))
            }
            _ => e.to_string(),
        })?;
    let bxdf = spec.build().map_err(|e| e.to_string())?;
    let fresnel_only = if spec.model.kind().fresnel_only() {
        let unit = MaterialSpec {
            model: spec.model.clone(),
            fresnel: FresnelSpec::One,
        };
        Some(FresnelOnly {
            fresnel: spec.fresnel.build().map_err(|e| e.to_string())?,
            unit: unit.build().map_err(|e| e.to_string())?,
        })
    } else {
        None
    };
    Ok(Material {
        name: name.to_string(),
        model: spec.model.kind(),
        bxdf,
        fresnel_only,
    })
}
