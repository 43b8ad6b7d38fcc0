//! `lustre preview`: a material on the bundled preview object, over a
//! checkered floor, under a daylight sky with its sun (and/or a studio of
//! rectangle lights), the way renderer users judge a material; one image per
//! model, side by side in a labelled grid when there are several.
//!
//! The scene (object, floor, sky or studio lights) is
//! `render::scene::presets::PreviewScene`; `lustre scenes` writes the
//! committed copies of its assets under `scenes/assets/` and the bundled
//! scenes `scenes/preview/<sample>.toml` (one per paper sample of
//! `brdf::paper`). A preview run writes, next to
//! its PNG, the scene file of every image (and the assets they use), so any
//! image can be re-rendered longer with `lustre render`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow, bail};
use plot::ImageGrid;
use render::scene::presets::{PreviewLight, PreviewScene, preview_assets};
use render::{Film, RenderOptions};

use crate::cmd_brdf_plot::parse_size;
use crate::cmd_render::parse_duration;
use brdf::paper::PaperModel;
use brdf::spec::ModelKind;

use crate::models::{self, Surface};

/// Lighting of the preview.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lighting {
    /// The Preetham daylight sky with its sun.
    Sky,
    /// Three rectangle lights (key, fill, rim) over a dim uniform surround.
    Studio,
    /// The sky and the studio lights together.
    Both,
}

/// Arguments of `lustre preview`.
#[derive(clap::Args, Debug)]
pub struct PreviewArgs {
    /// Material file (as written by `lustre fit`) to preview.
    pub material: Option<PathBuf>,
    /// Paper sample instead of a material file: S808, S280, S138, S091 or S027.
    #[arg(long, conflicts_with = "material")]
    pub sample: Option<String>,
    /// Models to show side by side. For a sample: ggx (slope-based α),
    /// ggx_identity (GGX ≡ KC α), beckmann, ghs_ssa, ghs, two_scale,
    /// two_scale_N (cutoff N wavelengths), measured_psd; default
    /// ggx,ghs_ssa,ghs,two_scale. For a material file: model names
    /// (ggx, beckmann, ghs_ssa, ghs, two_scale, measured_psd); default its own.
    #[arg(long, value_delimiter = ',')]
    pub models: Vec<String>,
    /// Two-scale cutoff of a paper sample, as a multiple of 550 nm.
    #[arg(long, default_value_t = 100.0)]
    pub cutoff: f64,
    /// Lighting.
    #[arg(long, value_enum, default_value = "sky")]
    pub light: Lighting,
    /// Sun elevation above the horizon, degrees.
    #[arg(long, default_value_t = DEFAULT_SUN_ELEVATION)]
    pub sun_elevation: f64,
    /// Sun azimuth, degrees (0: behind the object, 180: behind the camera, 270: camera's left).
    #[arg(long, default_value_t = DEFAULT_SUN_AZIMUTH)]
    pub sun_azimuth: f64,
    /// Atmospheric turbidity of the sky, 2 (very clear) to 10 (hazy).
    #[arg(long, default_value_t = 2.5)]
    pub turbidity: f64,
    /// Size of the image (one model) or of each grid cell, WIDTHxHEIGHT
    /// (default 400x300, or 288x216 per cell for several models).
    #[arg(long)]
    pub size: Option<String>,
    /// Samples per pixel (fewer if the time limit comes first).
    #[arg(long, default_value_t = 64)]
    pub spp: u64,
    /// Wall-clock budget for all images together, e.g. 40s, 2m.
    #[arg(long, default_value = "40s")]
    pub time_limit: String,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output PNG (default out/preview/<name>.png); EXRs and scene files go beside it.
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Default sun elevation, degrees: high enough for a clear sky, low enough
/// for a long shadow and a highlight in the upper half of the bulb.
pub const DEFAULT_SUN_ELEVATION: f64 = 35.0;
/// Default sun azimuth, degrees: in front of the object, to the camera's left.
pub const DEFAULT_SUN_AZIMUTH: f64 = 220.0;

impl From<Lighting> for PreviewLight {
    fn from(l: Lighting) -> PreviewLight {
        match l {
            Lighting::Sky => PreviewLight::Sky,
            Lighting::Studio => PreviewLight::Studio,
            Lighting::Both => PreviewLight::Both,
        }
    }
}

/// The scene text of a preview ([`PreviewScene`]) whose object has the
/// `[materials.object]` body `material`, with `header` as its first comment.
pub fn scene_text(scene: PreviewScene, material: &str, header: String) -> anyhow::Result<String> {
    let material = toml::from_str(material).context("the preview's material")?;
    let mut file = PreviewScene { material, ..scene }.file();
    file.comments.header = header;
    Ok(file.to_toml()?)
}

/// One image of a preview: its label, the `[materials.object]` body, and a
/// data file the material reads (a measured PSD table), written beside it.
struct Cell {
    label: String,
    file: String,
    material: String,
    data: Option<(String, String)>,
}

fn sample_cells(s: &Surface, names: &[String], cutoff: f64) -> anyhow::Result<Vec<Cell>> {
    let models = models::paper_models(names)?;
    names
        .iter()
        .zip(models)
        .map(|(n, m)| {
            // `two_scale` without a number splits at --cutoff.
            let m = match m {
                PaperModel::TwoScale(_) if n.trim() == "two_scale" => PaperModel::TwoScale(cutoff),
                m => m,
            };
            let l = s.material(m);
            let file = format!("{}_{}", s.name.to_lowercase(), n.trim());
            let psd = format!("{file}_psd.csv");
            let data = match &l.spec.model {
                brdf::spec::ModelSpec::MeasuredPsd {
                    zeta_rad_per_um,
                    psd_um4,
                    ..
                } => Some((psd.clone(), models::psd_csv_text(zeta_rad_per_um, psd_um4))),
                _ => None,
            };
            Ok(Cell {
                label: l.label.clone(),
                file,
                material: models::material_toml(&l.spec, Some(&psd))?,
                data,
            })
        })
        .collect()
}

fn material_cells(path: &Path, names: &[String]) -> anyhow::Result<(String, Vec<Cell>)> {
    let fit = models::read_fit_file(path)?;
    let name = path
        .file_stem()
        .map_or_else(|| "material".into(), |s| s.to_string_lossy().into_owned());
    let kinds: Vec<ModelKind> = if names.is_empty() {
        vec![fit.file.material.model.unwrap_or(ModelKind::Ggx)]
    } else {
        (names.iter())
            .map(|n| {
                ModelKind::from_name(n.trim()).ok_or_else(|| {
                    anyhow!("--models {n}: unknown model; use {}", ModelKind::names())
                })
            })
            .collect::<anyhow::Result<_>>()?
    };
    let offers = fit.file.offered();
    let mut cells = Vec::new();
    for kind in kinds {
        let of_kind: Vec<_> = offers.iter().filter(|o| o.model == Some(kind)).collect();
        if kind == ModelKind::TwoScale && fit.file.material.beta.is_none() && of_kind.is_empty() {
            bail!(
                "{}: two_scale needs a [two_scale.NAME] table (lustre fit writes them)",
                path.display()
            );
        }
        if of_kind.is_empty() {
            // A model the file does not offer: let the scene build say why.
            cells.push(Cell {
                label: kind.name().into(),
                file: format!("{name}_{}", kind.name()),
                material: models::desc_toml(&brdf::spec::MaterialDesc {
                    include: Some(fit.abs.display().to_string()),
                    model: Some(kind),
                    ..Default::default()
                })?,
                data: None,
            });
        }
        for o in of_kind {
            let (label, file) = match &o.cutoff {
                Some(c) => (format!("two-scale {c}"), format!("{name}_two_scale_{c}")),
                None => (kind.name().to_string(), format!("{name}_{}", kind.name())),
            };
            cells.push(Cell {
                label,
                file,
                material: fit.material_toml(o)?,
                data: None,
            });
        }
    }
    Ok((name, cells))
}

/// Linear sRGB → 8-bit sRGB (IEC 61966-2-1 transfer curve, clamped).
pub fn to_srgb8(v: f32) -> u8 {
    let x = f64::from(v).clamp(0.0, 1.0);
    let e = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0 + 0.5) as u8
}

/// The bundled scenes `<sample>.toml`: full GHS of each paper sample under
/// the sky (written by `lustre scenes`).
pub fn bundled_scenes() -> anyhow::Result<Vec<(String, String)>> {
    brdf::paper::SAMPLES
        .iter()
        .map(|smp| {
            let s = Surface::from_sample(smp);
            let l = s.material(PaperModel::Ghs);
            let stem = s.name.to_lowercase();
            let header = format!(
                "Material preview: paper sample {} ({}), full GHS,\n\
                 on the preview object over a checkered floor under a Preetham sky with its sun.\n\
                 Written by `lustre scenes` (src/cmd_preview.rs); assets in ../assets.",
                s.name,
                s.describe()
            );
            let scene = PreviewScene {
                width: 400,
                height: 300,
                spp: 64,
                material: Default::default(),
                light: PreviewLight::Sky,
                sun_elevation_deg: DEFAULT_SUN_ELEVATION,
                sun_azimuth_deg: DEFAULT_SUN_AZIMUTH,
                turbidity: 2.5,
                exposure: 0.0,
                assets: "../assets".into(),
                outputs: Some((
                    format!("preview_{stem}.exr").into(),
                    format!("preview_{stem}.png").into(),
                )),
            };
            let text = scene_text(scene, &models::material_toml(&l.spec, None)?, header)?;
            Ok((format!("{stem}.toml"), text))
        })
        .collect()
}

/// Writes the preview's assets into `dir/assets` (creating both), each
/// only when it differs from what is there, so that the fingerprint of a
/// scene reading them stays put between runs.
fn write_assets(dir: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let assets_dir = dir.join("assets");
    std::fs::create_dir_all(&assets_dir)
        .with_context(|| format!("creating {}", assets_dir.display()))?;
    for (file, text) in preview_assets() {
        let p = assets_dir.join(file);
        let old = safe_io::read_regular(&p, "preview asset", render::inputs::MAX_CSV_BYTES);
        if old.ok().as_deref() != Some(text.as_bytes()) {
            plot::write_atomic(&p, text.as_bytes())?;
        }
    }
    Ok(())
}

/// The scene of one preview image, written as `dir/<stem>.toml` (with the
/// data file its material reads) and loaded.
fn cell_scene(
    args: &PreviewArgs,
    cell: &Cell,
    stem: &str,
    (width, height): (u32, u32),
    title: &str,
    dir: &Path,
) -> anyhow::Result<render::Scene> {
    let scene = PreviewScene {
        width,
        height,
        spp: args.spp,
        material: Default::default(),
        light: args.light.into(),
        sun_elevation_deg: args.sun_elevation,
        // One turn is all that matters.
        sun_azimuth_deg: args.sun_azimuth.rem_euclid(360.0),
        turbidity: args.turbidity,
        exposure: args.exposure,
        assets: "assets".into(),
        outputs: Some((format!("{stem}.exr").into(), format!("{stem}.png").into())),
    };
    let header = format!(
        "lustre preview: {} ({}); render again with `lustre render` from this directory.",
        cell.label.replace('\n', ", "),
        title.replace('\n', " ")
    );
    let text = scene_text(scene, &cell.material, header)?;
    if let Some((file, text)) = &cell.data {
        plot::write_atomic(&dir.join(file), text.as_bytes())?;
    }
    let scene_path = dir.join(format!("{stem}.toml"));
    plot::write_atomic(&scene_path, text.as_bytes())?;
    render::load_str(&scene_path, &text)
        .map_err(|e| anyhow!("{}: {e}", cell.label.replace('\n', ", ")))
}

/// The grid of `n` images (up to three in a row, else two rows) titled
/// with `title`, the lighting and the image size; and its column count.
fn image_grid(n: usize, title: &str, light: Lighting, (w, h): (u32, u32)) -> (ImageGrid, usize) {
    let cols = if n <= 3 { n } else { n.div_ceil(2) };
    let rows = n.div_ceil(cols);
    let grid = ImageGrid::new(rows, cols).title(format!(
        "{title}\n{} lighting, {w}×{h} px",
        match light {
            Lighting::Sky => "sky",
            Lighting::Studio => "studio",
            Lighting::Both => "sky + studio",
        }
    ));
    (grid, cols)
}

/// The sky's parameters, checked as the flags they came from: the scene
/// built from them would otherwise report them at a line of a generated file.
fn check_sky_flags(args: &PreviewArgs) -> anyhow::Result<()> {
    if matches!(args.light, Lighting::Studio) {
        return Ok(());
    }
    let e = args.sun_elevation;
    if !(e.is_finite() && e > 0.0 && e <= 90.0) {
        bail!("--sun-elevation {e}: expected degrees in (0, 90] (the sky model has no night)");
    }
    if !args.sun_azimuth.is_finite() {
        bail!(
            "--sun-azimuth {}: expected a finite angle in degrees",
            args.sun_azimuth
        );
    }
    let t = args.turbidity;
    if !(t.is_finite() && (2.0..=10.0).contains(&t)) {
        bail!("--turbidity {t}: the Preetham sky covers 2 (very clear) to 10 (hazy)");
    }
    Ok(())
}

/// Renders every image to the same number of samples, in rounds over all of them (1 sample
/// each, then as many again, doubling while the budget allows): a round is started only when
/// its projected end lies within `budget`, so every image stops at the same count (`spp` at
/// most; the first round always runs, so no image is black). Returns the count.
fn render_equally(
    pool: &render::ThreadPool,
    scenes: &[render::Scene],
    films: &mut [Film],
    (spp, budget): (u64, Duration),
    opts: &RenderOptions,
) -> anyhow::Result<u64> {
    let start = Instant::now();
    let mut done = 0u64;
    let mut step = 1u64;
    while step > 0 && done < spp {
        let next = done + step.min(spp - done);
        let t0 = Instant::now();
        for (scene, film) in scenes.iter().zip(films.iter_mut()) {
            let outcome = render::render_range_in(pool, scene, film, done..next, opts)?;
            if !outcome.complete {
                bail!("interrupted");
            }
        }
        let per_sample = t0.elapsed().as_secs_f64() / (next - done) as f64;
        done = next;
        let left = budget.saturating_sub(start.elapsed()).as_secs_f64();
        let affordable = if per_sample > 0.0 {
            (left / per_sample).floor().min(u64::MAX as f64) as u64
        } else {
            u64::MAX
        };
        step = done.min(affordable);
    }
    Ok(done)
}

/// Runs `lustre preview`.
pub fn run(args: PreviewArgs) -> anyhow::Result<()> {
    crate::flags::check_spp(args.spp, crate::flags::MAX_FIGURE_SPP)?;
    crate::flags::check_exposure(args.exposure)?;
    let threads = crate::flags::thread_count(args.threads, args.quiet)?;
    let budget = parse_duration(&args.time_limit)?;
    check_sky_flags(&args)?;
    let (name, title, cells) = match &args.material {
        Some(path) => {
            let (name, cells) = material_cells(path, &args.models)?;
            (name.clone(), format!("{name} ({})", path.display()), cells)
        }
        None => {
            let s = Surface::from_sample(models::sample(args.sample.as_deref().unwrap_or("S280"))?);
            let names: Vec<String> = if args.models.is_empty() {
                ["ggx", "ghs_ssa", "ghs", "two_scale"]
                    .map(String::from)
                    .to_vec()
            } else {
                args.models.clone()
            };
            if !(args.cutoff.is_finite() && args.cutoff > 0.0) {
                bail!(
                    "--cutoff {}: must be a positive multiple of 550 nm",
                    args.cutoff
                );
            }
            let title = format!("{}: {}", s.name, s.describe());
            (
                s.name.to_lowercase(),
                title,
                sample_cells(&s, &names, args.cutoff)?,
            )
        }
    };
    let grid = cells.len() > 1;
    let (w, h) = match &args.size {
        Some(s) => parse_size(s)?,
        None if grid => (288, 216),
        None => (400, 300),
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/preview/{name}.png")));
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let stem_of = |cell: &Cell| {
        if grid {
            cell.file.clone()
        } else {
            out.file_stem()
                .map_or_else(|| name.clone(), |s| s.to_string_lossy().into_owned())
        }
    };
    if let Some(material) = &args.material {
        let mut outputs = vec![(out.clone(), "preview PNG")];
        for cell in &cells {
            let stem = stem_of(cell);
            outputs.push((dir.join(format!("{stem}.toml")), "preview scene file"));
            outputs.push((dir.join(format!("{stem}.exr")), "preview EXR"));
        }
        safe_io::register_input(material);
        crate::outputs::check(&outputs)?;
    }
    write_assets(&dir)?;

    let stop = render::interrupt::ctrlc_flag().map_err(anyhow::Error::msg)?;
    let pool = render::thread_pool(threads)?;
    let (mut image_grid, cols) = image_grid(cells.len(), &title, args.light, (w, h));
    let start = Instant::now();
    let mut scenes = Vec::with_capacity(cells.len());
    let mut films = Vec::with_capacity(cells.len());
    for cell in &cells {
        let scene = cell_scene(&args, cell, &stem_of(cell), (w, h), &title, &dir)?;
        films.push(
            Film::new(w, h, scene.fingerprint, scene.settings.seed, args.exposure)
                .map_err(anyhow::Error::msg)?,
        );
        scenes.push(scene);
    }
    let opts = RenderOptions {
        threads,
        stop: stop.clone(),
        ..RenderOptions::default()
    };
    let spp = render_equally(&pool, &scenes, &mut films, (args.spp, budget), &opts)?;
    let mut single_rgb = None;
    for (i, (cell, film)) in cells.iter().zip(&films).enumerate() {
        let rgb = film.rgb();
        let exr = dir.join(format!("{}.exr", stem_of(cell)));
        render::output::write_exr(&exr, w, h, &rgb)?;
        if grid {
            let px: Vec<u8> = rgb.iter().flat_map(|p| p.map(to_srgb8)).collect();
            let (r, c) = (i / cols, i % cols);
            image_grid.set_rgb8(r, c, w, h, px)?;
            image_grid.caption(r, c, format!("{} ({spp} spp)", cell.label))?;
        } else {
            single_rgb = Some(rgb);
        }
        if !args.quiet {
            eprintln!(
                "  {}: {spp} spp → {}",
                cell.label.replace('\n', ", "),
                exr.display()
            );
        }
    }
    if spp < args.spp && !args.quiet {
        eprintln!(
            "note: the time limit ({}) allowed {spp} of {} spp per image, the same for every image",
            args.time_limit, args.spp
        );
    }
    match single_rgb {
        Some(rgb) => render::output::write_png(&out, w, h, &rgb)?,
        None => {
            image_grid.save_png(&out)?;
        }
    }
    if !args.quiet {
        eprintln!(
            "wrote {} in {:.1} s (scenes, EXRs and assets in {})",
            out.display(),
            start.elapsed().as_secs_f64(),
            dir.display()
        );
    }
    Ok(())
}
