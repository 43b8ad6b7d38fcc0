//! `lustre scenes`: writes every bundled scene and asset from the code that
//! defines them —
//! * the paper-sample plates `scenes/samples/<sample>_<model>_<view>.toml` and
//!   the sampled KC PSD tables their `measured_psd` variants read
//!   (`scenes/psd/<sample>_kc.csv`), from `brdf::paper`, the one home of the
//!   samples and of the rules that turn a surface into each model;
//! * the material previews `scenes/preview/<sample>.toml` and their object and
//!   floor `scenes/assets/*.obj` (`render::preview_mesh`).
//!
//! `tests/scenes_generated.rs` checks the committed files are its output.

use std::path::PathBuf;

use anyhow::Context;
use brdf::paper::{AlphaRule, PaperModel, PaperSample, REFERENCE_LAMBDA_NM};
use render::scene::presets::{PlateScene, preview_assets};

use crate::models::{self, Surface};

/// Arguments of `lustre scenes`.
#[derive(clap::Args, Debug)]
pub struct ScenesArgs {
    /// Folder to write `samples/`, `psd/`, `preview/` and `assets/` into (required, so that
    /// a stray run never rewrites a checkout's `scenes/`; `--out scenes` regenerates them).
    #[arg(long)]
    pub out: PathBuf,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The models of the bundled scenes, with their file-name tags.
pub const SCENE_MODELS: [(&str, PaperModel); 7] = [
    ("ggx", PaperModel::Ggx(AlphaRule::Slope)),
    ("ggx_identity", PaperModel::Ggx(AlphaRule::Identity)),
    ("beckmann", PaperModel::Beckmann(AlphaRule::Slope)),
    ("ghs_ssa", PaperModel::GhsSsa),
    ("ghs", PaperModel::Ghs),
    ("two_scale", PaperModel::TwoScale(100.0)),
    ("measured_psd", PaperModel::MeasuredPsd),
];

/// The viewing directions: name and angle from the normal, degrees.
pub const VIEWS: [(&str, f64); 3] = [("normal", 0.0), ("45deg", 45.0), ("grazing", 80.0)];

/// Every file `lustre scenes` writes: path relative to the output folder,
/// and contents.
pub fn files() -> anyhow::Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    for s in &brdf::paper::SAMPLES {
        out.push((psd_path(s), psd_csv(s)));
    }
    for (name, text) in preview_assets() {
        out.push((format!("assets/{name}"), text));
    }
    for (name, text) in crate::cmd_preview::bundled_scenes()? {
        out.push((format!("preview/{name}"), text));
    }
    for s in &brdf::paper::SAMPLES {
        for (tag, model) in SCENE_MODELS {
            for (view, theta) in VIEWS {
                let name = format!("{}_{tag}_{view}", s.name.to_lowercase());
                out.push((
                    format!("samples/{name}.toml"),
                    scene(s, tag, model, view, theta, &name)?,
                ));
            }
        }
    }
    Ok(out)
}

fn psd_path(s: &PaperSample) -> String {
    format!("psd/{}_kc.csv", s.name.to_lowercase())
}

fn psd_csv(s: &PaperSample) -> String {
    let (z, p) = brdf::paper::sampled_kc_psd(&s.surface);
    models::psd_csv_text(&z, &p)
}

/// Why the parameters of `model` are what they are, as comment text.
fn provenance(s: &PaperSample, model: PaperModel) -> String {
    let k = &s.surface;
    let lam = REFERENCE_LAMBDA_NM;
    match model {
        PaperModel::Ggx(rule) | PaperModel::Beckmann(rule) => format!(
            "alpha = {}: {} (at {lam} nm); sigma = {} um, Lc = {} um, gamma = {}.",
            brdf::paper::short(brdf::paper::microfacet_alpha(k, rule, lam)),
            rule.reason(),
            k.sigma_um,
            k.lc_um,
            k.gamma
        ),
        PaperModel::TwoScale(m) => format!(
            "Two-scale split at {m} wavelengths ({:.1} um): beta from the KC slope variance \
             below 2 pi / cutoff (6 beta^2 = <|grad h|^2>); micro scale = the sample's KC.",
            m * lam * 1e-3
        ),
        PaperModel::MeasuredPsd => format!(
            "No measured PSD of the paper's samples is in the repository: the KC PSD of {}\n\
             sampled as a table ({}), which exercises the tabulated-PSD path. For a real\n\
             sample use `include = \"fit.toml\"` from `lustre fit`.",
            s.name,
            psd_path(s)
        ),
        _ => String::new(),
    }
}

/// The plate scene of paper sample `s` under `model`, viewed at `theta_deg`
/// from the normal ([`PlateScene`], the scene of `lustre compare`'s cells).
fn scene(
    s: &PaperSample,
    tag: &str,
    model: PaperModel,
    view: &str,
    theta_deg: f64,
    name: &str,
) -> anyhow::Result<String> {
    let surface = Surface::from_sample(s);
    let l = surface.material(model);
    let psd = format!("../{}", psd_path(s));
    let material = models::material_toml(&l.spec, Some(&psd))?;
    let mut file = PlateScene {
        view_deg: theta_deg,
        width: 160,
        height: 120,
        spp: 16,
        material: toml::from_str(&material).context("the plate's material")?,
        outputs: Some((format!("{name}.exr").into(), format!("{name}.png").into())),
    }
    .file();
    file.comments.header = format!(
        "{} plate, model {tag} ({}), {view} viewing ({theta_deg} deg from the normal).\n\
         Written by `lustre scenes` from brdf::paper; do not edit by hand.",
        s.name, l.label
    );
    let mut about = format!(
        "Paper sample {} ({}); KC parameters of docs/physics.md section 12.",
        s.number,
        s.metal.name()
    );
    let why = provenance(s, model);
    if !why.is_empty() {
        about = format!("{about}\n{why}");
    }
    file.comments.materials.insert("plate".into(), about);
    Ok(file.to_toml()?)
}

/// Runs `lustre scenes`.
pub fn run(args: ScenesArgs) -> anyhow::Result<()> {
    let files = files()?;
    for (rel, text) in &files {
        let path = args.out.join(rel);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        plot::write_atomic(&path, text.as_bytes())?;
    }
    if !args.quiet {
        eprintln!("wrote {} files under {}", files.len(), args.out.display());
    }
    Ok(())
}
