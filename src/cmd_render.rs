//! `lustre [render] scene.toml` and `lustre merge`.

use anyhow::{Context, bail};
use render::film::{Film, ResumeError};
use render::{RenderOptions, Scene};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Arguments of the render command.
#[derive(clap::Args, Default)]
pub struct RenderArgs {
    /// Scene file (TOML); default scenes/default.toml.
    pub scene: Option<PathBuf>,
    /// Samples per pixel (overrides the scene's `film.spp`).
    #[arg(long)]
    pub spp: Option<u64>,
    /// Render only sample indices A..B (a shard; combine shards with `lustre merge`).
    #[arg(long, value_name = "A..B")]
    pub spp_range: Option<String>,
    /// Random seed (overrides the scene's `film.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores; at most 4 per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Stop after this long and write the image so far: `90`, `90s`, `15m`, `2h`.
    #[arg(long, value_name = "DURATION")]
    pub time_limit: Option<String>,
    /// Continue from the film checkpoint to the requested samples.
    #[arg(long)]
    pub resume: bool,
    /// EXR output (overrides the scene's `film.exr`).
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Also write N spectral bands of equal width over 360–830 nm (1..=256) as EXR channels
    /// named as pbrt-v4's SpectralFilm names them (`S0.374,688nm`), each the mean spectral
    /// radiance in its band (overrides the scene's `film.spectral_bands`).
    #[arg(long, value_name = "N")]
    pub spectral: Option<usize>,
    /// PNG output (overrides the scene's `film.png`).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Film (checkpoint / shard) file; default: the image path with extension `.film`.
    #[arg(long)]
    pub film: Option<PathBuf>,
    /// Time between checkpoints of the film while rendering: `30`, `30s`, `5m` (≥ 1 s).
    #[arg(long, value_name = "DURATION", default_value = "30")]
    pub checkpoint_every: String,
    /// Write no `.film` (no checkpoints either): for one-off renders whose images are all
    /// that is wanted. An interrupted render then keeps only its images.
    #[arg(long, conflicts_with_all = ["resume", "film"])]
    pub no_film: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// CPU seconds used by this process so far, all threads (exited ones included), to
/// the nanosecond: `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`. `/proc/self/stat` counts in
/// 10 ms ticks, 2.5 % of a 0.4 s render, too coarse for the peer comparison.
#[cfg(unix)]
fn process_cpu_seconds() -> Option<f64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

#[cfg(not(unix))]
fn process_cpu_seconds() -> Option<f64> {
    None
}

/// Arguments of the merge command.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Partial films (`.film`) to merge; they must come from the same scene and seed.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Merged film output.
    #[arg(long)]
    pub film: Option<PathBuf>,
    /// EXR output.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// PNG output.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure in stops (default: the films' own).
    #[arg(long)]
    pub exposure: Option<f64>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Parses `A..B` (B > A).
pub fn parse_range(s: &str) -> anyhow::Result<Range<u64>> {
    let (a, b) = s
        .split_once("..")
        .with_context(|| format!("--spp-range `{s}`: expected A..B, e.g. 0..64"))?;
    let a: u64 = a
        .trim()
        .parse()
        .with_context(|| format!("--spp-range `{s}`: `{a}` is not a sample index"))?;
    let b: u64 = b
        .trim()
        .parse()
        .with_context(|| format!("--spp-range `{s}`: `{b}` is not a sample index"))?;
    if b <= a {
        bail!("--spp-range `{s}`: the end must be greater than the start");
    }
    if b > render::scene::MAX_SPP {
        bail!(
            "--spp-range `{s}`: sample indices end at {}",
            render::scene::MAX_SPP
        );
    }
    Ok(a..b)
}

/// Longest duration accepted: 100 years, far beyond any render, and far
/// below where `Instant` arithmetic overflows.
const MAX_DURATION_SECS: f64 = 100.0 * 365.25 * 86400.0;

/// Parses `90`, `90s`, `1.5m`, `2h` for the option `option`.
pub fn parse_duration_for(option: &str, s: &str) -> anyhow::Result<Duration> {
    let t = s.trim();
    // The unit is a suffix (the number may be `1e3` or `inf`).
    let (num, k) = [("min", 60.0), ("s", 1.0), ("m", 60.0), ("h", 3600.0)]
        .iter()
        .find_map(|&(u, k)| t.strip_suffix(u).map(|n| (n, k)))
        .unwrap_or((t, 1.0));
    let v: f64 = num.trim().parse().with_context(|| {
        format!("{option} `{s}`: expected a number and an optional unit s, m or h, e.g. 90, 90s, 15m, 2h")
    })?;
    let secs = v * k;
    if !secs.is_finite() {
        bail!("{option} `{s}`: must be a finite duration");
    }
    if secs <= 0.0 {
        bail!("{option} `{s}`: must be positive");
    }
    if secs > MAX_DURATION_SECS {
        bail!("{option} `{s}`: longer than 100 years; leave the option out for no limit");
    }
    Ok(Duration::from_secs_f64(secs))
}

/// Parses a `--time-limit`.
pub fn parse_duration(s: &str) -> anyhow::Result<Duration> {
    parse_duration_for("--time-limit", s)
}

/// Parses `--checkpoint-every` (at least one second: a film is written whole).
pub fn parse_checkpoint_every(s: &str) -> anyhow::Result<Duration> {
    let d = parse_duration_for("--checkpoint-every", s)?;
    if d < Duration::from_secs(1) {
        bail!(
            "--checkpoint-every `{s}`: must be at least 1 s (each checkpoint writes the whole film)"
        );
    }
    Ok(d)
}

/// The warning printed after a render or merge whose film left samples out.
pub fn dropped_warning(d: &render::film::Dropped) -> Option<String> {
    (d.total() > 0).then(|| format!("warning: {d}"))
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    match path.extension() {
        Some(ext) => path.with_file_name(format!("{stem}{suffix}.{}", ext.to_string_lossy())),
        None => path.with_file_name(format!("{stem}{suffix}")),
    }
}

fn default_scene() -> PathBuf {
    let local = PathBuf::from("scenes/default.toml");
    if local.exists() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/default.toml")
    }
}

fn write_images(
    film: &Film,
    exr: Option<&Path>,
    png: Option<&Path>,
    quiet: bool,
) -> anyhow::Result<()> {
    let rgb = film.rgb();
    if let Some(p) = exr {
        match film.band_layout() {
            None => render::output::write_exr(p, film.width(), film.height(), &rgb)?,
            Some(layout) => {
                let bands: Vec<f32> = film.band_means().iter().map(|&v| v as f32).collect();
                render::output::write_exr_spectral(
                    p,
                    film.width(),
                    film.height(),
                    &rgb,
                    &layout,
                    &bands,
                )?
            }
        }
        if !quiet {
            eprintln!("wrote {}", p.display());
        }
    }
    if let Some(p) = png {
        render::output::write_png(p, film.width(), film.height(), &rgb)?;
        if !quiet {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// Where a render's samples and images go: the sample range, the image
/// names (the scene's, or the flags') and the film.
struct Outputs {
    target: Range<u64>,
    exr: Option<PathBuf>,
    png: Option<PathBuf>,
    film: PathBuf,
}

impl Outputs {
    /// The outputs of rendering `spp` samples (or the `--spp-range` shard)
    /// of the scene at `scene_path`, whose own image names are `settings`'.
    fn new(
        args: &RenderArgs,
        settings: &render::scene::Settings,
        scene_path: &Path,
        spp: u64,
    ) -> anyhow::Result<Outputs> {
        let shard = args.spp_range.as_deref().map(parse_range).transpose()?;
        let target = shard.clone().unwrap_or(0..spp);
        // Shards get their own output names unless given explicitly.
        let suffix = shard.as_ref().map(|r| format!(".spp{}-{}", r.start, r.end));
        let name = |cli: &Option<PathBuf>, scene_value: &Option<PathBuf>| -> Option<PathBuf> {
            cli.clone().or_else(|| {
                scene_value.as_ref().map(|p| {
                    suffix
                        .as_deref()
                        .map_or_else(|| p.clone(), |s| with_suffix(p, s))
                })
            })
        };
        let exr = name(&args.exr, &settings.exr);
        let png = name(&args.png, &settings.png);
        let film = args.film.clone().unwrap_or_else(|| {
            let base = exr.clone().or_else(|| png.clone()).unwrap_or_else(|| {
                let stem = scene_path
                    .file_stem()
                    .map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
                let p = PathBuf::from(format!("{stem}.film"));
                suffix
                    .as_deref()
                    .map_or_else(|| p.clone(), |s| with_suffix(&p, s))
            });
            let film = base.with_extension("film");
            // A shard's film is named after its range even when the image name was given, so
            // two shards written with the same --exr never overwrite each other's samples.
            match (&suffix, args.exr.is_some() || args.png.is_some()) {
                (Some(s), true) => with_suffix(&film, s),
                _ => film,
            }
        });
        Ok(Outputs {
            target,
            exr,
            png,
            film,
        })
    }
}

/// With `--resume`: adopts the checkpoint at `path` into `film` when there
/// is one, and returns the samples of `target` still to render.
fn resume(
    film: &mut Film,
    path: &Path,
    target: Range<u64>,
    quiet: bool,
) -> anyhow::Result<Range<u64>> {
    if !path.exists() {
        if !quiet {
            eprintln!(
                "note: no checkpoint at {}; starting from sample {}",
                path.display(),
                target.start
            );
        }
        return Ok(target);
    }
    let old = Film::load_checkpoint(path)?;
    let todo = match film.resume(old, target) {
        Ok(todo) => todo,
        Err(e @ ResumeError::Incompatible(_)) => bail!(
            "{}: {e}; remove it or choose another --film",
            path.display()
        ),
        Err(e @ ResumeError::NotAPrefix { .. }) => {
            bail!("{}: {e}; use `lustre merge` for shards", path.display())
        }
    };
    if !quiet {
        eprintln!(
            "resuming from {}: {} spp done, {} to go",
            path.display(),
            film.spp(),
            todo.end.saturating_sub(todo.start)
        );
    }
    Ok(todo)
}

/// Renders a scene file.
pub fn render(args: RenderArgs) -> anyhow::Result<()> {
    let scene_path = args.scene.clone().unwrap_or_else(default_scene);
    let mut scene: Scene = render::load_scene(&scene_path)?;
    if let Some(seed) = args.seed {
        scene.settings.seed = seed;
    }
    if let Some(n) = args.spectral {
        if n == 0 || n > render::film::MAX_BANDS {
            bail!(
                "--spectral {n}: expected 1..={} bands",
                render::film::MAX_BANDS
            );
        }
        scene
            .set_spectral_bands(n)
            .map_err(|m| anyhow::anyhow!("--spectral {n}: {m}"))?;
    }
    if !args.quiet {
        eprintln!("{}", scene.prepared);
    }
    let spp = args.spp.unwrap_or(scene.settings.spp);
    if spp == 0 || spp > render::scene::MAX_SPP {
        bail!("--spp {spp}: expected 1..={}", render::scene::MAX_SPP);
    }
    let out = Outputs::new(&args, &scene.settings, &scene_path, spp)?;
    let (exr, png, film_path) = (out.exr.as_deref(), out.png.as_deref(), &out.film);
    if args.no_film && exr.is_none() && png.is_none() {
        bail!(
            "--no-film: the scene names no `exr` or `png` output and none was given; nothing would be written"
        );
    }
    // The scene build recorded every file it read, so these checks refuse all of them.
    let film_out = (!args.no_film).then_some(film_path.as_path());
    check_outputs(exr, png, film_out)?;
    if exr.is_none() && png.is_none() && !args.quiet {
        eprintln!(
            "note: the scene names no `exr` or `png` output; only the film {} is written",
            film_path.display()
        );
    }

    let time_limit = args.time_limit.as_deref().map(parse_duration).transpose()?;
    let checkpoint_every = parse_checkpoint_every(&args.checkpoint_every)?;
    let threads = crate::flags::thread_count(args.threads, args.quiet)?;
    render::memory::check_fits_with_bands(
        scene.camera.width,
        scene.camera.height,
        scene.settings.spectral_bands,
    )
    .map_err(|m| anyhow::anyhow!("{}: {m}", scene_path.display()))?;
    let mut film = scene.film().map_err(anyhow::Error::msg)?;
    let todo = if args.resume {
        resume(&mut film, film_path, out.target.clone(), args.quiet)?
    } else {
        out.target.clone()
    };

    let stop = render::interrupt::ctrlc_flag().map_err(anyhow::Error::msg)?;
    let opts = RenderOptions {
        threads,
        time_limit,
        stop,
        progress: crate::progress::bar(!args.quiet),
        checkpoint: (!args.no_film).then(|| (film_path.clone(), checkpoint_every)),
        ..RenderOptions::default()
    };
    let cpu0 = process_cpu_seconds();
    let outcome = if todo.is_empty() {
        None
    } else {
        Some(render::render_range(
            &scene,
            &mut film,
            todo.clone(),
            &opts,
        )?)
    };
    let cpu = match (cpu0, process_cpu_seconds()) {
        (Some(a), Some(b)) => format!(", {:.3} CPU s", b - a),
        _ => String::new(),
    };
    if film.spp() == 0 {
        // Stopped before the first pass finished: there is nothing to keep, and an
        // earlier film or image at these names stays as it was.
        eprintln!("stopped before any sample was complete; nothing written");
        return Ok(());
    }
    if !args.no_film {
        film.save(film_path)?;
    }
    write_images(&film, exr, png, args.quiet)?;
    if !args.quiet {
        report(outcome.as_ref(), &film, &todo, &out, args.no_film, &cpu);
    }
    // Printed even with --quiet: the image is wrong where these samples fell.
    if let Some(w) = dropped_warning(film.dropped()) {
        if args.no_film {
            eprintln!("{w}");
        } else {
            eprintln!("{w} (film {})", film_path.display());
        }
    }
    Ok(())
}

/// The summary of a render: what was rendered, how fast, and whether it
/// stopped early (`outcome` is `None` when the film already held `todo`).
fn report(
    outcome: Option<&render::RenderOutcome>,
    film: &Film,
    todo: &Range<u64>,
    out: &Outputs,
    no_film: bool,
    cpu: &str,
) {
    let Some(o) = outcome else {
        eprintln!(
            "nothing to render: the film already holds samples up to {}",
            out.target.end
        );
        return;
    };
    eprintln!(
        "rendered samples {}..{} ({} spp in the film) in {:.2} s wall{cpu}: {:.3e} samples/s; {}",
        o.rendered.start,
        o.rendered.end,
        film.spp(),
        o.elapsed.as_secs_f64(),
        o.samples_per_second,
        if no_film {
            "no film written".to_string()
        } else {
            format!("film {}", out.film.display())
        }
    );
    if !o.complete {
        eprintln!(
            "stopped early at sample {} of {}; {}",
            o.rendered.end,
            todo.end,
            if no_film {
                "the images hold what was rendered (--no-film: nothing to resume from)"
            } else {
                "continue with `--resume`"
            }
        );
    }
}

/// Merges partial films.
pub fn merge(args: MergeArgs) -> anyhow::Result<()> {
    // Recorded before they are read, so a bad output is refused before any film is loaded.
    for p in &args.inputs {
        safe_io::register_input(p);
    }
    check_outputs(
        args.exr.as_deref(),
        args.png.as_deref(),
        args.film.as_deref(),
    )?;
    let mut inputs = args.inputs.iter();
    let first = inputs.next().context("give at least one film")?;
    let mut film = Film::load(first)?;
    for p in inputs {
        let f = Film::load(p)?;
        if f.bands() != film.bands() {
            bail!(
                "{}: cannot merge: it holds {} spectral bands and {} holds {}; render the shards \
                 with the same `--spectral`",
                p.display(),
                f.bands(),
                first.display(),
                film.bands()
            );
        }
        film.merge(&f)
            .map_err(|m| anyhow::anyhow!("{}: cannot merge: {m}", p.display()))?;
    }
    if let Some(e) = args.exposure {
        film.set_exposure(e)
            .map_err(|m| anyhow::anyhow!("--exposure: {m}"))?;
    }
    if !args.quiet {
        eprintln!(
            "merged {} film(s): samples {:?}, {} spp",
            args.inputs.len(),
            film.ranges(),
            film.spp()
        );
    }
    if let Some(w) = dropped_warning(film.dropped()) {
        eprintln!("{w}");
    }
    if let Some(p) = &args.film {
        film.save(p)?;
        if !args.quiet {
            eprintln!("wrote {}", p.display());
        }
    }
    if args.exr.is_none() && args.png.is_none() && args.film.is_none() {
        bail!("nothing to write: give --exr, --png and/or --film");
    }
    write_images(&film, args.exr.as_deref(), args.png.as_deref(), args.quiet)
}

/// Refuses outputs that would overwrite an input of this process, a
/// directory or each other, and image names whose extension says another
/// format than the one written (an EXR written as `x.png` opens as a broken
/// PNG).
fn check_outputs(
    exr: Option<&Path>,
    png: Option<&Path>,
    film: Option<&Path>,
) -> anyhow::Result<()> {
    for (p, ext, flag) in [(exr, "exr", "--exr / `exr`"), (png, "png", "--png / `png`")] {
        if let Some(p) = p {
            let ok = p
                .extension()
                .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext));
            if !ok {
                bail!(
                    "{flag} {}: the file would hold {} data; give it a name ending in .{ext}",
                    p.display(),
                    ext.to_uppercase()
                );
            }
        }
    }
    let outputs: Vec<(&str, &Path)> = [("EXR", exr), ("PNG", png), ("film", film)]
        .into_iter()
        .filter_map(|(k, p)| p.map(|p| (k, p)))
        .collect();
    for (i, (kind, p)) in outputs.iter().enumerate() {
        safe_io::check_output(p).with_context(|| format!("the {kind} output"))?;
        for (other, q) in &outputs[..i] {
            if safe_io::same_file(p, q) {
                bail!(
                    "the {other} and {kind} outputs are both {}: one would overwrite the other; give them different names",
                    p.display()
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_never_overwrite_inputs_or_each_other() {
        let dir = std::env::temp_dir().join(format!("lustre_outputs_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("a.toml");
        std::fs::write(&scene, "").unwrap();
        safe_io::protect_inputs();
        safe_io::register_input(&scene);
        let p = |s: &str| dir.join(s);
        // Sound: distinct names with their formats' extensions (any case).
        check_outputs(Some(&p("a.exr")), Some(&p("a.PNG")), Some(&p("a.film"))).unwrap();
        check_outputs(None, None, Some(&p("a.film"))).unwrap();
        let err = |exr: Option<PathBuf>, png: Option<PathBuf>, film: Option<PathBuf>| {
            format!(
                "{:#}",
                check_outputs(exr.as_deref(), png.as_deref(), film.as_deref()).unwrap_err()
            )
        };
        // The scene file, also reached through `..` or `.`.
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let via = dir.join("sub").join("..").join(".").join("a.toml");
        assert!(err(None, None, Some(via)).contains("is the input"));
        assert!(err(None, None, Some(scene.clone())).contains("would destroy it"));
        // A directory.
        assert!(err(None, None, Some(dir.join("sub"))).contains("a directory"));
        // Two outputs on one file.
        assert!(err(Some(p("b.exr")), None, Some(p("b.exr"))).contains("the EXR and film outputs"));
        // A format under another's extension, or none.
        assert!(err(Some(p("x.png")), None, None).contains("ending in .exr"));
        assert!(err(None, Some(p("x")), None).contains("ending in .png"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn parses_ranges_and_durations() {
        assert_eq!(parse_range("0..64").unwrap(), 0..64);
        assert!(parse_range("64..0").is_err());
        assert!(parse_range("x").is_err());
        assert_eq!(parse_duration("90").unwrap(), Duration::from_secs(90));
        assert_eq!(parse_duration("1.5m").unwrap(), Duration::from_secs(90));
        assert_eq!(parse_duration("2h").unwrap(), Duration::from_secs(7200));
        assert!(parse_duration("5 parsecs").is_err());
        assert!(parse_duration("-1").is_err());
        // Past u64 seconds `Duration` overflows (a panic unless refused).
        for bad in ["inf", "infs", "1e30", "1e300h", "nan", "-inf", "0"] {
            let e = parse_duration(bad).unwrap_err().to_string();
            assert!(e.starts_with("--time-limit"), "{bad}: {e}");
        }
        for bad in ["inf", "0.5", "1e20", "x"] {
            let e = parse_checkpoint_every(bad).unwrap_err().to_string();
            assert!(e.starts_with("--checkpoint-every"), "{bad}: {e}");
        }
        assert_eq!(
            parse_checkpoint_every("30").unwrap(),
            Duration::from_secs(30)
        );
        assert_eq!(
            parse_checkpoint_every("2m").unwrap(),
            Duration::from_secs(120)
        );
        assert!(crate::flags::thread_count(Some(0), true).is_err());
        assert_eq!(
            crate::flags::thread_count(Some(10_000), true).unwrap(),
            Some(render::max_threads())
        );
        assert_eq!(crate::flags::thread_count(Some(1), true).unwrap(), Some(1));
        assert_eq!(
            with_suffix(Path::new("out/a.exr"), ".spp0-8"),
            PathBuf::from("out/a.spp0-8.exr")
        );
    }
}
