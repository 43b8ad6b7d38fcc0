//! The CLI's view of materials: a named surface with its Fresnel term, and
//! the labelled materials the figure commands (`brdf plot`, `compare`,
//! `preview`, `judge`) draw for it. The samples and the rules that turn a
//! KC surface into every model live in `brdf::paper`; materials are
//! `brdf::spec::MaterialSpec`, the type every entry point shares.

use anyhow::{anyhow, bail};
use brdf::Metal;
use brdf::paper::{PaperModel, PaperSample};
use brdf::spec::{FresnelSpec, KcSpec, MaterialDesc, MaterialSpec, ModelSpec};

/// Refuse wavelengths [nm] the models do not cover; `flag` names them in the message.
pub fn check_wavelengths(flag: &str, values: &[f64]) -> anyhow::Result<()> {
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    for &l in values {
        if !(lo..=hi).contains(&l) {
            bail!("{flag} {l}: must lie in {lo}–{hi} nm");
        }
    }
    Ok(())
}

/// Refuse `--theta-i` angles outside `[0, max_deg)` degrees.
pub fn check_incidence(values: &[f64], max_deg: f64) -> anyhow::Result<()> {
    for &t in values {
        if !(0.0..max_deg).contains(&t) {
            bail!("--theta-i {t}: must lie in [0, {max_deg}) degrees");
        }
    }
    Ok(())
}

/// A K-correlation surface to draw models of.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Name for titles and file names.
    pub name: String,
    /// Its statistics.
    pub kc: KcSpec,
    /// Its Fresnel term.
    pub fresnel: FresnelSpec,
}

impl Surface {
    /// A paper sample with its own metal.
    pub fn from_sample(s: &PaperSample) -> Surface {
        Surface {
            name: s.name.to_string(),
            kc: s.surface,
            fresnel: FresnelSpec::Metal(s.metal),
        }
    }

    /// The material of `model` for this surface, with its label.
    pub fn material(&self, model: PaperModel) -> Labelled {
        Labelled {
            label: model.label(&self.kc),
            spec: model.material(&self.kc, self.fresnel.clone()),
        }
    }

    /// `σ 0.28 µm, Lc 5 µm, γ 3, brass` for titles.
    pub fn describe(&self) -> String {
        format!(
            "σ {} µm, Lc {} µm, γ {}, {}",
            self.kc.sigma_um,
            self.kc.lc_um,
            self.kc.gamma,
            fresnel_name(&self.fresnel)
        )
    }
}

/// A material with a legend / row label.
#[derive(Clone, Debug)]
pub struct Labelled {
    /// The label.
    pub label: String,
    /// The material.
    pub spec: MaterialSpec,
}

/// A paper sample by name, or an error listing them.
pub fn sample(name: &str) -> anyhow::Result<&'static PaperSample> {
    brdf::paper::find_sample(name.trim()).ok_or_else(|| {
        anyhow!(
            "unknown sample {name:?}; the paper samples are {}",
            brdf::paper::sample_names()
        )
    })
}

/// Paper models by name (`ggx`, `ggx_identity`, `two_scale_50`, …).
pub fn paper_models(names: &[String]) -> anyhow::Result<Vec<PaperModel>> {
    names
        .iter()
        .map(|n| {
            PaperModel::from_name(n.trim()).ok_or_else(|| {
                anyhow!(
                    "unknown model {n:?}; use {}",
                    brdf::paper::PaperModel::names()
                )
            })
        })
        .collect()
}

/// `none` (R ≡ 1) or a metal name.
pub fn fresnel_from_name(name: &str) -> anyhow::Result<FresnelSpec> {
    if name.eq_ignore_ascii_case("none") || name.eq_ignore_ascii_case("one") {
        return Ok(FresnelSpec::One);
    }
    match Metal::from_name(name) {
        Some(m) => Ok(FresnelSpec::Metal(m)),
        None => {
            let names: Vec<&str> = Metal::ALL.iter().map(|m| m.name()).collect();
            bail!(
                "unknown metal {name:?}; use none or one of {}",
                names.join(", ")
            )
        }
    }
}

/// The name of a Fresnel term for titles and CSV columns.
pub fn fresnel_name(f: &FresnelSpec) -> String {
    match f {
        FresnelSpec::One => "none".into(),
        FresnelSpec::Metal(m) => m.name().into(),
        FresnelSpec::Constant { n, k } => format!("n {n} k {k}"),
        FresnelSpec::Table(_) => "nk table".into(),
    }
}

/// The `[materials.NAME]` body of a scene for this material. A measured
/// PSD's table goes to `psd_csv`, written by the caller.
pub fn material_toml(spec: &MaterialSpec, psd_csv: Option<&str>) -> anyhow::Result<String> {
    let mut desc = spec.to_desc();
    if let ModelSpec::MeasuredPsd { .. } = spec.model {
        desc.psd_csv = Some(
            psd_csv
                .ok_or_else(|| anyhow!("a measured-PSD material needs a psd_csv file"))?
                .to_string(),
        );
    }
    desc_toml(&desc)
}

/// A `zeta_rad_per_um,p_um4` CSV of PSD samples.
pub fn psd_csv_text(zeta: &[f64], p: &[f64]) -> String {
    let mut t = String::from("zeta_rad_per_um,p_um4\n");
    for (z, p) in zeta.iter().zip(p) {
        t += &format!("{z:.9e},{p:.9e}\n");
    }
    t
}

/// A material description as TOML keys (model first).
pub fn desc_toml(desc: &MaterialDesc) -> anyhow::Result<String> {
    Ok(toml::to_string(desc)?)
}

/// A `lustre fit` material file as `compare` and `preview` read it.
pub struct FitFile {
    /// The document.
    pub file: brdf::spec::MaterialFile,
    /// The file's absolute path, for the `include` of generated scenes.
    pub abs: std::path::PathBuf,
}

impl FitFile {
    /// The `[materials.*]` body that draws the file as `offer` does.
    pub fn material_toml(&self, offer: &brdf::spec::file::Offer) -> anyhow::Result<String> {
        desc_toml(&MaterialDesc {
            include: Some(self.abs.display().to_string()),
            ..offer.desc()
        })
    }
}

/// Reads a `lustre fit` material file; an error names the file, line and what is wrong.
pub fn read_fit_file(path: &std::path::Path) -> anyhow::Result<FitFile> {
    use anyhow::Context;
    let bytes = safe_io::read_input(path, "material file", render::scene::inputs::MAX_TOML_BYTES)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| anyhow!("{}: the material file is not UTF-8 text", path.display()))?;
    let file: brdf::spec::MaterialFile = toml::from_str(&text).map_err(|e| {
        let at = e.span().map(|s| {
            let line = text[..s.start].matches('\n').count() + 1;
            let shown = text.lines().nth(line - 1).unwrap_or("").trim();
            format!(":{line}: `{shown}`")
        });
        anyhow!(
            "{}{}: {}. Fix: correct it, or write the file again with `lustre fit`",
            path.display(),
            at.unwrap_or_default(),
            e.message().trim()
        )
    })?;
    let abs =
        std::fs::canonicalize(path).with_context(|| format!("resolving {}", path.display()))?;
    Ok(FitFile { file, abs })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn material_toml_round_trips_through_the_schema() {
        for s in brdf::paper::SAMPLES {
            let surf = Surface::from_sample(&s);
            for m in brdf::paper::PaperModel::FIGURE_SET {
                let l = surf.material(m);
                let text = material_toml(&l.spec, None).unwrap();
                let desc: MaterialDesc = toml::from_str(&text).unwrap();
                let back = desc.into_spec(&mut brdf::spec::NoFiles).unwrap();
                assert_eq!(back, l.spec, "{}: {text}", l.label);
            }
        }
    }
}
