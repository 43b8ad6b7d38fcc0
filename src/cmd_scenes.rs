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

use crate::models::{self, Surface};

/// Arguments of `lustre scenes`.
#[derive(clap::Args, Debug)]
pub struct ScenesArgs {
    /// Folder to write `samples/` and `psd/` into.
    #[arg(long, default_value = "scenes")]
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
    for (name, text) in crate::cmd_preview::assets() {
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

/// Why the parameters of `model` are what they are, as comment lines.
fn provenance(s: &PaperSample, model: PaperModel) -> String {
    let k = &s.surface;
    let lam = REFERENCE_LAMBDA_NM;
    match model {
        PaperModel::Ggx(rule) | PaperModel::Beckmann(rule) => format!(
            "# alpha = {}: {} (at {lam} nm); sigma = {} um, Lc = {} um, gamma = {}.\n",
            brdf::paper::short(brdf::paper::microfacet_alpha(k, rule, lam)),
            rule.reason(),
            k.sigma_um,
            k.lc_um,
            k.gamma
        ),
        PaperModel::TwoScale(m) => format!(
            "# Two-scale split at {m} wavelengths ({:.1} um): beta from the KC slope variance \
             below 2 pi / cutoff (6 beta^2 = <|grad h|^2>); micro scale = the sample's KC.\n",
            m * lam * 1e-3
        ),
        PaperModel::MeasuredPsd => format!(
            "# No measured PSD of the paper's samples is in the repository: the KC PSD of {}\n\
             # sampled as a table ({}), which exercises the tabulated-PSD path. For a real\n\
             # sample use `include = \"fit.toml\"` from `lustre fit`.\n",
            s.name,
            psd_path(s)
        ),
        _ => String::new(),
    }
}

/// Where the plate scenes put the camera and the light for a view `view_deg` from the
/// plate's normal: `(camera position, light centre, camera up as TOML)`. The light sits at
/// the camera's mirror direction, so the specular peak is in view.
pub fn plate_view(view_deg: f64) -> ([f64; 3], [f64; 3], &'static str) {
    let t = view_deg.to_radians();
    let cam = [0.0, t.cos(), t.sin()];
    // At normal view the light sits 1° further out so camera and light do not coincide.
    let tl = view_deg.max(1.0).to_radians();
    let light = [0.0, 1.2 * tl.cos(), -1.2 * tl.sin()];
    // Looking straight down, the usual +y up is the view direction itself.
    let up = if view_deg < 1.0 {
        "[0.0, 0.0, -1.0]"
    } else {
        "[0.0, 1.0, 0.0]"
    };
    (cam, light, up)
}

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
    let (cam, light, up) = plate_view(theta_deg);
    let v = |p: [f64; 3]| format!("[{:.6}, {:.6}, {:.6}]", p[0], p[1], p[2]);
    Ok(format!(
        "# {} plate, model {tag} ({}), {view} viewing ({theta_deg} deg from the normal).\n\
         # Written by `lustre scenes` from brdf::paper; do not edit by hand.\n\
         \n\
         [camera]\n\
         look_from = {}\n\
         look_at = [0.0, 0.0, 0.0]\n\
         up = {up}\n\
         fov_deg = 14.0\n\
         resolution = [160, 120]\n\
         \n\
         [film]\n\
         spp = 16\n\
         seed = 1\n\
         exr = \"{name}.exr\"\n\
         png = \"{name}.png\"\n\
         \n\
         [integrator]\n\
         max_depth = 3\n\
         wavelengths = \"hero\"\n\
         \n\
         # Paper sample {} ({}); KC parameters of docs/physics.md section 12.\n\
         {}[materials.plate]\n\
         {material}\n\
         # A 20 cm x 20 cm plate in the xz plane, normal +y.\n\
         [[shapes]]\n\
         type = \"rectangle\"\n\
         size = [0.2, 0.2]\n\
         material = \"plate\"\n\
         transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}\n\
         \n\
         # A small light at the mirror direction of the camera (about 1.7 deg across).\n\
         [[lights]]\n\
         type = \"sphere\"\n\
         center = {}\n\
         radius = 0.018\n\
         radiance = 200.0\n\
         spectrum = \"d65\"\n\
         \n\
         [[lights]]\n\
         type = \"environment\"\n\
         radiance = 0.02\n\
         spectrum = \"d65\"\n",
        s.name,
        l.label,
        v(cam),
        s.number,
        s.metal.name(),
        provenance(s, model),
        v(light),
    ))
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
