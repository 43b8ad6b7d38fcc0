//! `lustre compare`: renders one surface with each model at three viewing
//! angles and assembles a labelled grid (rows = models, columns = views), like
//! the paper's Fig. 1 and 4.
//!
//! Every cell is a scene with the geometry of the bundled sample scenes
//! (`lustre scenes`: a 20 cm plate, the camera at θ from the normal, a small
//! light in the mirror direction, a dim environment), rendered in-process by
//! the `render` crate.
//!
//! Rows per surface:
//! * paper sample (`--sample`): the models of `brdf::paper` — GGX with the
//!   slope-based α (the microfacet prediction the paper rendered) and with
//!   the GGX ≡ KC identity α (matches SSA by construction), GHS SSA, full GHS,
//!   and two-scale at Λ = m·550 nm (β from the KC slope variance below 2π/Λ,
//!   micro scale = the sample's own KC);
//! * material file (`--material`, as written by `lustre fit`): included as is,
//!   with `model` set per row: every model the file offers (GGX, Beckmann, GHS
//!   SSA, full GHS, and where the file carries their data the anisotropic GHS
//!   and the measured-PSD models, the 2-D PSD grid's SSA and full GHS) and one
//!   two-scale row per `[two_scale.*]` table.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use plot::ImageGrid;
use render::scene::presets::PlateScene;
use render::{Film, RenderOptions};

use crate::cmd_brdf_plot::parse_size;
use crate::cmd_preview::to_srgb8;
use brdf::paper::{AlphaRule, PaperModel};

use crate::models::{self, Surface};

/// Arguments of `lustre compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// Paper sample: S808, S280, S138, S091 or S027 (default S280).
    #[arg(long, conflicts_with = "material")]
    pub sample: Option<String>,
    /// Material file written by `lustre fit` instead of a paper sample.
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// Two-scale cutoffs as multiples of 550 nm (paper samples only; a material
    /// file brings its own `[two_scale.*]` tables).
    #[arg(long, value_delimiter = ',', default_value = "50,100,150")]
    pub cutoffs: Vec<f64>,
    /// Viewing angles from the normal in degrees (columns).
    #[arg(long, value_delimiter = ',', default_value = "0,45,80")]
    pub views: Vec<f64>,
    /// Size of each cell in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "128x96")]
    pub size: String,
    /// Samples per pixel of each cell.
    #[arg(long, default_value_t = 8)]
    pub spp: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Exposure in stops (the PNG clips at 1; each cell's EXR holds the unclipped values).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f64,
    /// Output PNG (default out/compare/<sample>.png); the cell table goes beside it as
    /// `.cells.csv`, each cell's linear EXR as `<stem>_r<row>c<col>.exr`.
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// One grid row: its label and the `[materials.plate]` body of its scenes.
struct Row {
    label: String,
    material: String,
}

fn sample_rows(s: &Surface, cutoffs: &[f64]) -> anyhow::Result<Vec<Row>> {
    let mut models = vec![
        PaperModel::Ggx(AlphaRule::Slope),
        PaperModel::Ggx(AlphaRule::Identity),
        PaperModel::GhsSsa,
        PaperModel::Ghs,
    ];
    for &m in cutoffs {
        if !(m.is_finite() && m > 0.0) {
            bail!("--cutoffs {m}: must be positive multiples of the wavelength");
        }
        models.push(PaperModel::TwoScale(m));
    }
    models
        .into_iter()
        .map(|m| {
            let l = s.material(m);
            Ok(Row {
                label: l.label.replacen(", ", "\n", 1).replacen(" (", "\n(", 1),
                material: models::material_toml(&l.spec, None)?,
            })
        })
        .collect()
}

/// The rows of a `lustre fit` file: every model it offers ([`brdf::spec::file::MaterialFile::offered`]:
/// GGX, Beckmann, GHS SSA, full GHS, the anisotropic and measured-PSD models its tables
/// allow) in that order, then each two-scale split ordered by its number
/// (cutoff_50 < cutoff_100).
fn material_rows(path: &Path) -> anyhow::Result<(String, Vec<Row>)> {
    use brdf::spec::ModelKind;
    let fit = models::read_fit_file(path)?;
    let mat = &fit.file.material;
    let order = |name: &str| -> f64 {
        name.trim_start_matches(|c: char| !c.is_ascii_digit())
            .parse()
            .unwrap_or(f64::MAX)
    };
    // The file's own `[material]` model is one of the others again.
    let mut offers: Vec<_> = (fit.file.offered().into_iter())
        .filter(|o| o.model.is_some())
        .collect();
    offers.sort_by(|a, b| {
        let key = |o: &brdf::spec::file::Offer| o.cutoff.as_deref().map_or(-1.0, order);
        key(a).total_cmp(&key(b))
    });
    let mut rows = Vec::new();
    for o in &offers {
        let label = match (o.model, &o.cutoff) {
            (Some(ModelKind::Ggx), _) => {
                format!(
                    "GGX\nα {}",
                    brdf::paper::short(mat.alpha.unwrap_or(f64::NAN))
                )
            }
            (Some(ModelKind::Beckmann), _) => "Beckmann".into(),
            (Some(ModelKind::GhsSsa), _) => "GHS SSA".into(),
            (Some(ModelKind::Ghs), _) => "full GHS".into(),
            (Some(ModelKind::GhsAniso), _) => "full GHS\nanisotropic KC".into(),
            (Some(ModelKind::MeasuredPsd), _) => "full GHS\nmeasured PSD".into(),
            (Some(ModelKind::MeasuredPsdAniso), _) => "full GHS\nPSD on ellipses".into(),
            (Some(ModelKind::MeasuredPsd2dSsa), _) => "GHS SSA\n2-D PSD grid".into(),
            (Some(ModelKind::MeasuredPsd2d), _) => "full GHS\n2-D PSD grid".into(),
            (_, Some(c)) => {
                let beta = fit.file.two_scale.get(c).map_or(f64::NAN, |t| t.beta);
                let what = match order(c) {
                    o if o < f64::MAX => format!("{o}λ"),
                    _ => c.clone(),
                };
                format!("two-scale {what}\nβ {}", brdf::paper::short(beta))
            }
            (Some(m), None) => m.name().to_string(),
            (None, _) => continue,
        };
        rows.push(Row {
            label,
            material: fit.material_toml(o)?,
        });
    }
    let name = path
        .file_stem()
        .map_or_else(|| "material".into(), |s| s.to_string_lossy().into_owned());
    Ok((name, rows))
}

/// The scene of one cell: the plate scene of the bundled sample scenes
/// ([`PlateScene`]) with the row's `[materials.plate]` body.
pub fn scene_text(
    view_deg: f64,
    width: u32,
    height: u32,
    spp: u64,
    material: &str,
) -> anyhow::Result<String> {
    let material = toml::from_str(material).context("the cell's material")?;
    let plate = PlateScene {
        view_deg,
        width,
        height,
        spp,
        material,
        outputs: None,
    };
    Ok(plate.file().to_toml()?)
}

/// The linear EXR of the cell in row `r`, column `c`, beside the grid's PNG.
fn cell_exr(png: &Path, r: usize, c: usize) -> PathBuf {
    let stem = png.file_stem().unwrap_or_default().to_string_lossy();
    png.with_file_name(format!("{stem}_r{r}c{c}.exr"))
}

/// Fraction of the pixels with a channel above 1 (white in the PNG).
fn clipped_fraction(rgb: &[[f32; 3]]) -> f64 {
    let n = rgb.iter().filter(|p| p.iter().any(|v| *v > 1.0)).count();
    n as f64 / rgb.len().max(1) as f64
}

/// Runs `lustre compare`.
pub fn run(args: CompareArgs) -> anyhow::Result<()> {
    let (w, h) = parse_size(&args.size)?;
    crate::flags::check_exposure(args.exposure)?;
    crate::flags::check_spp(args.spp, crate::flags::MAX_FIGURE_SPP)?;
    let threads = crate::flags::thread_count(args.threads, args.quiet)?;
    if args.views.is_empty() || args.views.iter().any(|v| !(0.0..90.0).contains(v)) {
        bail!("--views: give angles in [0, 90) degrees, e.g. 0,45,80");
    }
    let (name, title, rows, base) = match &args.material {
        Some(path) => {
            let (name, rows) = material_rows(path)?;
            let title = format!("{name} (fitted material {})", path.display());
            let base = path
                .parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
            (name, title, rows, base)
        }
        None => {
            let s = Surface::from_sample(models::sample(args.sample.as_deref().unwrap_or("S280"))?);
            let title = format!(
                "{}: {}\n\
                 GGX slope: α = rms slope below 2k at 550 nm\n\
                 GGX KC identity: α = 1/(2kLc) at 550 nm\n\
                 two-scale at Λ = m·550 nm: β from the\n\
                 KC slope variance below 2π/Λ;\n\
                 micro scale = the sample's KC",
                s.name,
                s.describe()
            );
            (
                s.name.to_lowercase(),
                title,
                sample_rows(&s, &args.cutoffs)?,
                PathBuf::from("."),
            )
        }
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/compare/{name}.png")));
    if let Some(material) = &args.material {
        safe_io::register_input(material);
    }
    let mut outputs = vec![
        (out.clone(), "compare PNG"),
        (out.with_extension("cells.csv"), "cell table"),
    ];
    for r in 0..rows.len() {
        outputs.extend((0..args.views.len()).map(|c| (cell_exr(&out, r, c), "cell EXR")));
    }
    crate::outputs::check(&outputs)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let opts = RenderOptions {
        threads,
        ..RenderOptions::default()
    };
    let pool = render::thread_pool(threads)?;
    let mut grid = ImageGrid::new(rows.len(), args.views.len())
        .title(format!(
            "{title}\n{w}×{h} px, {} spp per cell, exposure {:+} stops",
            args.spp, args.exposure
        ))
        .row_labels(rows.iter().map(|r| r.label.clone()))
        .col_labels(args.views.iter().map(|v| match *v {
            0.0 => "normal (0°)".to_string(),
            v if v >= 75.0 => format!("grazing ({v}°)"),
            v => format!("{v}°"),
        }));
    let scene_path = base.join("compare.toml");
    let start = Instant::now();
    let mut most_clipped = (0.0f64, String::new());
    for (r, row) in rows.iter().enumerate() {
        for (c, &view) in args.views.iter().enumerate() {
            let text = scene_text(view, w, h, args.spp, &row.material)?;
            let scene = render::load_str(&scene_path, &text)
                .map_err(|e| anyhow!("{} at {view}°: {e}", row.label.replace('\n', ", ")))?;
            let mut film = Film::new(
                w,
                h,
                scene.fingerprint,
                scene.settings.seed,
                scene.settings.exposure + args.exposure,
            )
            .map_err(anyhow::Error::msg)?;
            render::render_range_in(&pool, &scene, &mut film, 0..args.spp, &opts)?;
            let rgb = film.rgb();
            render::output::write_exr(&cell_exr(&out, r, c), w, h, &rgb)?;
            let clipped = clipped_fraction(&rgb);
            if clipped > most_clipped.0 {
                most_clipped = (
                    clipped,
                    format!("{} at {view}°", row.label.replace('\n', ", ")),
                );
            }
            let px: Vec<u8> = rgb.iter().flat_map(|p| p.map(to_srgb8)).collect();
            grid.set_rgb8(r, c, w, h, px)?;
            if !args.quiet {
                eprintln!(
                    "  {} at {view}°: done ({:.1} s total)",
                    row.label.replace('\n', ", "),
                    start.elapsed().as_secs_f64()
                );
            }
        }
    }
    let layout = grid.save_png(&out)?;
    // The cell table: where each render sits in the grid and what it shows.
    let mut cells = String::from("row,col,model,view_deg,x0,y0,x1,y1,grid_width,grid_height,exr\n");
    for (r, row) in rows.iter().enumerate() {
        for (c, view) in args.views.iter().enumerate() {
            let s = layout.slots[r * args.views.len() + c];
            cells += &format!(
                "{r},{c},\"{}\",{view},{},{},{},{},{},{},\"{}\"\n",
                row.label.replace('\n', ", "),
                s.x0,
                s.y0,
                s.x1,
                s.y1,
                layout.width,
                layout.height,
                cell_exr(&out, r, c).display()
            );
        }
    }
    let cells_path = out.with_extension("cells.csv");
    plot::write_atomic(&cells_path, cells.as_bytes())?;
    if most_clipped.0 > 0.01 {
        eprintln!(
            "note: {:.1} % of the pixels of {} are above 1 and white in the PNG; each cell's EXR \
             holds them unclipped, or lower --exposure (now {:+} stops)",
            100.0 * most_clipped.0,
            most_clipped.1,
            args.exposure
        );
    }
    if !args.quiet {
        eprintln!(
            "wrote {} ({}×{} px), {} and one EXR per cell",
            out.display(),
            layout.width,
            layout.height,
            cells_path.display()
        );
    }
    Ok(())
}
