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
use brdf::spec::file::WithOwnPsd;
use brdf::spec::{FileLoader, FresnelSpec, MaterialDesc, MaterialFile, MaterialSpec, ModelKind};
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
    /// For the models whose delta lobe's weight depends on the path only
    /// through cosθi and λ ([`delta_by_cos_only`]): their Fresnel factor,
    /// whose n, κ rows the integrator's λ quadrature of that lobe breaks
    /// at (`spectral_table.rs`). Whoever replaces `bxdf` clears it or
    /// replaces it too.
    pub delta_fresnel: Option<Fresnel>,
    /// The model's value, density and sampling do not depend on λ
    /// ([`MaterialSpec::lambda_free`]): a camera path whose vertices are
    /// all such materials (and at most one Fresnel-only conductor) is
    /// integrated over λ exactly (`integrator.rs`, `trace_flat`). Whoever replaces
    /// `bxdf` clears it or sets it for the new model.
    pub lambda_free: bool,
}

/// Whether a model's delta lobe (its [`brdf::Bxdf::specular`]) depends on
/// the incident direction only through cosθi: R(λ, cosθi)·e^{−g(λ, cosθi)}
/// for the wave-optical models, whose coherent attenuation uses the RMS
/// height (isotropic even for the anisotropic surfaces) and whose energy
/// tables are indexed by cosθi. Tested over azimuths in
/// `tests/delta_exact.rs`.
pub fn delta_by_cos_only(kind: ModelKind) -> bool {
    matches!(
        kind,
        ModelKind::GhsSsa
            | ModelKind::Ghs
            | ModelKind::MeasuredPsd
            | ModelKind::TwoScale
            | ModelKind::RayleighRice
            | ModelKind::GhsSsaAniso
            | ModelKind::GhsAniso
            | ModelKind::MeasuredPsdSsaAniso
            | ModelKind::MeasuredPsdAniso
            | ModelKind::MeasuredPsd2dSsa
            | ModelKind::MeasuredPsd2d
    )
}

/// Whether a model's glossy lobe is isotropic: f(λ; wi, wo) depends on the
/// directions only through cosθi, cosθo and |wi_xy + wo_xy| (the
/// scattering vector's in-plane length, the PSD's argument; the Fresnel
/// angle, Q factor and energy tables are functions of these), so a
/// table over those three and λ describes it (`glossy_lambda_table.rs`).
/// Tested over azimuths in `tests/glossy_cv.rs`.
pub fn glossy_isotropic(kind: ModelKind) -> bool {
    matches!(
        kind,
        ModelKind::GhsSsa
            | ModelKind::Ghs
            | ModelKind::MeasuredPsd
            | ModelKind::TwoScale
            | ModelKind::RayleighRice
    )
}

/// A material split into its Fresnel factor and a λ-free rest.
pub struct FresnelOnly {
    /// The Fresnel factor F(λ, cosθd).
    pub fresnel: Fresnel,
    /// The same model built with F ≡ 1.
    pub unit: DynBxdf,
}

/// Reads `nk_csv` / `psd_csv` / `reflectance_csv` relative to the scene file through `inputs`.
struct SceneFiles<'a> {
    base_dir: &'a Path,
    inputs: &'a mut Inputs,
}

impl FileLoader for SceneFiles<'_> {
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
        let full = self.base_dir.join(path);
        let text = self.inputs.read_text(&full, "nk_csv", MAX_CSV_BYTES)?;
        let rows = parse_csv_rows(&text, 3).map_err(|e| format!("{}: {e}", full.display()))?;
        Ok(rows.into_iter().map(|r| [r[0], r[1], r[2]]).collect())
    }

    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
        let full = self.base_dir.join(path);
        let text = self.inputs.read_text(&full, "psd_csv", MAX_CSV_BYTES)?;
        let rows = parse_csv_rows(&text, 2).map_err(|e| format!("{}: {e}", full.display()))?;
        Ok(rows.into_iter().map(|r| (r[0], r[1])).unzip())
    }

    fn reflectance_table(&mut self, path: &str) -> Result<Vec<[f64; 2]>, String> {
        let full = self.base_dir.join(path);
        let text = self
            .inputs
            .read_text(&full, "reflectance_csv", MAX_CSV_BYTES)?;
        let rows = parse_csv_rows(&text, 2).map_err(|e| format!("{}: {e}", full.display()))?;
        Ok(rows.into_iter().map(|r| [r[0], r[1]]).collect())
    }
}

/// What an `include`d `lustre fit` file contributes.
struct Included {
    /// The file.
    file: MaterialFile,
    /// Its `[material]` as the scene's description builds on it (see
    /// [`MaterialFile::base_for`]), paths made relative to the scene file.
    base: MaterialDesc,
    /// The file as read, and the split the two-scale keys came from, so that
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

/// Why a material description did not resolve: the message (with the file and line
/// when an included file supplied the value) and the key it is about.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolveError {
    /// The key as the user writes it (`include`, `cutoff`, `energy`, …).
    pub field: &'static str,
    /// What is wrong and the fix.
    pub message: String,
}

impl std::fmt::Display for ResolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<ResolveError> for String {
    fn from(e: ResolveError) -> String {
        e.message
    }
}

/// Reads an included fit file and the `[material]` the scene's description builds on.
fn read_include(
    desc: &MaterialDesc,
    inc: &str,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Included, ResolveError> {
    let at_include = |message| ResolveError {
        field: "include",
        message,
    };
    let path = base_dir.join(inc);
    let text = inputs
        .read_text(&path, "material file", MAX_TOML_BYTES)
        .map_err(|e| at_include(format!("include = \"{inc}\": {e}")))?;
    let mut file: MaterialFile = toml::from_str(&text).map_err(|e| {
        let pos = e.span().map(|s| crate::error::line_column(&text, s.start));
        at_include(match pos {
            Some((l, c)) => format!("{}:{l}:{c}: {}", path.display(), e.message().trim()),
            None => format!("{}: {}", path.display(), e.message().trim()),
        })
    })?;
    // The include's own relative paths are relative to the include.
    let inc_dir = Path::new(inc).parent().unwrap_or(Path::new(""));
    for p in [
        &mut file.material.nk_csv,
        &mut file.material.psd_csv,
        &mut file.material.reflectance_csv,
    ]
    .into_iter()
    .flatten()
    {
        *p = inc_dir.join(&*p).to_string_lossy().into_owned();
    }
    let (base, split) = file.base_for(desc).map_err(|e| ResolveError {
        field: e.field,
        message: format!("{}: {}", path.display(), e.message),
    })?;
    Ok(Included {
        file,
        base,
        path,
        text,
        split,
    })
}

/// The typed material of a description as a scene's `[materials.NAME]` gives it: its
/// `include`d fit file (with the split `cutoff` names) under it, every file it names read
/// through `inputs` relative to `base_dir`. An invalid value an include supplied is reported
/// at its own file and line. `lustre brdf export` takes a material file this way too.
pub fn resolve_spec(
    desc: &MaterialDesc,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<MaterialSpec, ResolveError> {
    let included = match &desc.include {
        Some(inc) => Some(read_include(desc, inc, base_dir, inputs)?),
        None => {
            if desc.cutoff.is_some() {
                return Err(ResolveError {
                    field: "cutoff",
                    message: "`cutoff` picks a split of an `include`d fit file; this material \
                              has no `include`"
                        .into(),
                });
            }
            None
        }
    };
    let mut scene_files = SceneFiles { base_dir, inputs };
    let (base, mut files) = match &included {
        Some(inc) => (
            Some(&inc.base),
            WithOwnPsd {
                psd: inc.file.psd.as_ref(),
                files: &mut scene_files,
            },
        ),
        None => (
            None,
            WithOwnPsd {
                psd: None,
                files: &mut scene_files,
            },
        ),
    };
    desc.resolve(base, &mut files).map_err(|e| ResolveError {
        field: e.field,
        message: match &included {
            // The value came from the include: say where it is, not only which key.
            Some(inc) if desc.inherits(&inc.base, e.field) => {
                format!("{}: {e}", inc.locate(e.field))
            }
            _ => e.to_string(),
        },
    })
}

/// The material of `desc` over an in-memory material file, as a scene's `include`
/// of that file resolves it ([`MaterialFile::base_for`], the file's own `[psd]`
/// answering `psd_csv = "[psd]"`): for a fit result that was never written to disk
/// (the Python `Material.from_fit`). Paths the description or the file name are
/// relative to `base_dir`.
pub fn resolve_spec_over_file(
    desc: &MaterialDesc,
    file: &MaterialFile,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<MaterialSpec, String> {
    if desc.include.is_some() {
        return Err(
            "`include` names a material file, but one was given already: drop `include`".into(),
        );
    }
    let (base, _) = file.base_for(desc).map_err(|e| e.to_string())?;
    let mut scene_files = SceneFiles { base_dir, inputs };
    let mut files = WithOwnPsd {
        psd: file.psd.as_ref(),
        files: &mut scene_files,
    };
    desc.resolve(Some(&base), &mut files)
        .map_err(|e| e.to_string())
}

/// Builds the named material. `base_dir` resolves relative paths; every
/// file is read through `inputs`.
pub fn build_material(
    name: &str,
    desc: &MaterialDesc,
    base_dir: &Path,
    inputs: &mut Inputs,
) -> Result<Material, String> {
    let spec = resolve_spec(desc, base_dir, inputs)?;
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
    let delta_fresnel = if delta_by_cos_only(spec.model.kind()) {
        Some(spec.fresnel.build().map_err(|e| e.to_string())?)
    } else {
        None
    };
    Ok(Material {
        name: name.to_string(),
        model: spec.model.kind(),
        bxdf,
        fresnel_only,
        delta_fresnel,
        lambda_free: spec.lambda_free(),
    })
}
