//! `lustre fit …`: from a measured scan to a material file.
//!
//! `lustre fit <scan> [--stylus <profile>] [--cutoff 50,100,150] -o material.toml` runs the
//! whole analysis and writes the material file plus PSD/NDF plots (PNG and CSV) next to it;
//! `lustre fit stats <scan> --json` prints the headline numbers for scripting.

mod plots;

use anyhow::Context;
use fit::io::{ChannelSel, Format, ReadOptions, Units};
use fit::level::Level;
use fit::pipeline::{self, Options};
use std::path::{Path, PathBuf};

/// The metal a material file names when `--metal` is not given.
const DEFAULT_METAL: &str = "stainless_steel";

/// Arguments of the fit command.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct FitArgs {
    #[command(subcommand)]
    pub command: Option<FitCommand>,
    #[command(flatten)]
    pub material: MaterialArgs,
}

/// Subcommands of `fit`.
#[derive(clap::Subcommand)]
pub enum FitCommand {
    /// Print Sq, RMS slope, the K-correlation fit and the line PSD.
    Stats(StatsArgs),
    /// List the channels of a file (index, name, unit, whether it holds heights).
    Channels(ChannelsArgs),
}

/// Options shared by every way of reading a scan.
#[derive(clap::Args, Clone)]
pub struct ScanArgs {
    /// Channel of multi-channel files, by index or name (default: the first height
    /// channel; list them with `lustre fit channels FILE`).
    #[arg(long)]
    pub channel: Option<String>,
    /// Units for files that do not state them: `um` for lengths and heights, or
    /// `um,nm` for lengths,heights (m, mm, um/µm, nm, …).
    #[arg(long)]
    pub units: Option<String>,
    /// Pixel spacing for files without one, e.g. `0.5um` or `0.5um,0.4um` (x,y).
    #[arg(long)]
    pub pixel_size: Option<String>,
    /// Scan size for files without one, e.g. `100um` or `100um,80um` (x,y).
    #[arg(long, conflicts_with = "pixel_size")]
    pub size: Option<String>,
    #[arg(long, help = fit::io::registry::format_help())]
    pub format: Option<String>,
    /// Form removed before the analysis (default: plane for maps, line for profiles;
    /// `line` on a map levels each scan line). Curved parts need `poly2`.
    #[arg(long, value_parser = ["none", "line", "plane", "poly2", "poly3"])]
    pub level: Option<String>,
}

/// What to do with a scan that is mostly invalid or has spikes.
#[derive(clap::Args, Clone)]
pub struct CheckArgs {
    /// A scan with more than half its points invalid: `refuse` it, analyse its largest
    /// valid rectangle (`crop`), or `fill` it anyway (flagged in [reliability].invalid).
    #[arg(long, value_enum, default_value_t = InvalidArg::Refuse)]
    pub invalid: InvalidArg,
    /// Heights more than 12 robust σ from the median (spikes, corrupted values): `flag`
    /// them in [reliability].outliers and on stderr, or `mask` them as invalid points.
    #[arg(long, value_enum, default_value_t = OutliersArg::Flag)]
    pub outliers: OutliersArg,
}

/// `--invalid`.
#[derive(clap::ValueEnum, Clone, Copy)]
pub enum InvalidArg {
    Refuse,
    Crop,
    Fill,
}

/// `--outliers`.
#[derive(clap::ValueEnum, Clone, Copy, PartialEq, Eq)]
pub enum OutliersArg {
    Flag,
    Mask,
}

impl CheckArgs {
    fn checks(&self, units: Option<Units>) -> pipeline::Checks {
        use fit::quality::InvalidPolicy;
        pipeline::Checks {
            invalid: match self.invalid {
                InvalidArg::Refuse => InvalidPolicy::Refuse,
                InvalidArg::Crop => InvalidPolicy::Crop,
                InvalidArg::Fill => InvalidPolicy::Fill,
            },
            mask_outliers: self.outliers == OutliersArg::Mask,
            units,
        }
    }
}

/// `lustre fit channels <scan>`.
#[derive(clap::Args)]
pub struct ChannelsArgs {
    /// Surface file.
    pub scan: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub read: ScanArgs,
}

/// `lustre fit <scan> …`.
#[derive(clap::Args)]
pub struct MaterialArgs {
    /// Surface file (see --format for the formats read).
    pub scan: Option<PathBuf>,
    /// Stylus profile whose PSD replaces the scan's below the merge cutoff.
    #[arg(long)]
    pub stylus: Option<PathBuf>,
    /// Welch segments for the stylus profile (more = smoother PSD, less low-frequency reach).
    #[arg(long, default_value_t = 4)]
    pub stylus_segments: usize,
    /// Two-scale cutoff periods as multiples of --lambda-nm.
    #[arg(long, value_delimiter = ',', default_values_t = vec![50.0, 100.0, 150.0])]
    pub cutoff: Vec<f64>,
    /// Wavelength for the two-scale cutoffs [nm].
    #[arg(long, default_value_t = 550.0)]
    pub lambda_nm: f64,
    /// AFM/stylus merge cutoff [rad/µm].
    #[arg(long, default_value_t = 1.0)]
    pub merge_cutoff: f64,
    /// Metal written to [material].metal (without it, stainless_steel, said in a note).
    #[arg(long)]
    pub metal: Option<String>,
    /// Model written to [material].model; `auto` picks GHS when the K-correlation fit is
    /// sound, else the measured PSD, else GGX.
    #[arg(long, default_value = "auto", value_parser = model_names())]
    pub model: String,
    /// Output material file.
    #[arg(short, long, default_value = "material.toml")]
    pub output: PathBuf,
    /// Skip the PNG/CSV plots.
    #[arg(long)]
    pub no_plots: bool,
    #[command(flatten)]
    pub read: ScanArgs,
    #[command(flatten)]
    pub checks: CheckArgs,
}

/// `auto` and every model a fit file can recommend for any scan, for `--model`: the
/// conductor models but the anisotropic ones (their two correlation lengths exist only for
/// a scan flagged anisotropic, where the file offers `ghs_aniso` and `measured_psd_aniso`
/// beside its own model).
fn model_names() -> clap::builder::PossibleValuesParser {
    use brdf::spec::ModelKind;
    let drawable = (ModelKind::ALL.iter())
        .filter(|m| m.conductor() && !m.stretched())
        .map(|m| m.name());
    let names = std::iter::once("auto").chain(drawable);
    clap::builder::PossibleValuesParser::new(names.collect::<Vec<_>>())
}

/// `lustre fit stats <scan> --json`.
#[derive(clap::Args)]
pub struct StatsArgs {
    /// Surface scan.
    pub scan: PathBuf,
    /// Print JSON (the only output format).
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub read: ScanArgs,
    #[command(flatten)]
    pub checks: CheckArgs,
}

pub fn run(args: FitArgs) -> anyhow::Result<()> {
    match args.command {
        Some(FitCommand::Stats(s)) => stats(s),
        Some(FitCommand::Channels(c)) => channels(c),
        None => material(args.material),
    }
}

/// `0.5um` or `0.5um,0.4um` (the second defaults to the first), in metres.
fn parse_pair(flag: &str, v: &str) -> anyhow::Result<(f64, f64)> {
    let one = |t: &str| -> anyhow::Result<f64> {
        let (x, unit) = fit::io::units::split_number(t)
            .with_context(|| format!("{flag} {v}: `{t}` is not a number with a unit"))?;
        anyhow::ensure!(
            !unit.is_empty(),
            "{flag} {v}: give a unit, e.g. `{flag} 0.5um`"
        );
        let f = fit::io::units::length_factor(unit)
            .with_context(|| format!("{flag} {v}: `{unit}` is not a length unit"))?;
        let m = x * f;
        anyhow::ensure!(m.is_finite() && m > 0.0, "{flag} {v}: must be positive");
        Ok(m)
    };
    let mut it = v.split(',');
    let a = one(it.next().unwrap_or(""))?;
    let b = match it.next() {
        Some(t) => one(t)?,
        None => a,
    };
    anyhow::ensure!(it.next().is_none(), "{flag} {v}: at most two values (x,y)");
    Ok((a, b))
}

pub(crate) fn read_options(a: &ScanArgs) -> anyhow::Result<ReadOptions> {
    let units = match &a.units {
        Some(u) => Some(Units::parse(u).with_context(|| {
            format!(
                "--units {u}: not a length unit (use m, mm, um, nm, or `um,nm` for lengths,heights)"
            )
        })?),
        None => None,
    };
    let format = match &a.format {
        Some(f) => Some(Format::from_name(f).with_context(|| {
            format!(
                "--format {f}: unknown; supported: {}",
                Format::all()
                    .map(|f| f.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })?),
        None => None,
    };
    Ok(ReadOptions {
        channel: a.channel.as_deref().map(ChannelSel::parse),
        units,
        pixel_size: a
            .pixel_size
            .as_deref()
            .map(|v| parse_pair("--pixel-size", v))
            .transpose()?,
        size: a
            .size
            .as_deref()
            .map(|v| parse_pair("--size", v))
            .transpose()?,
        format,
    })
}

fn load(path: &Path, opts: &ReadOptions) -> anyhow::Result<(Vec<u8>, fit::io::Scan)> {
    let bytes = fit::io::read_scan_file(path)?;
    let scan = fit::io::open_bytes(&path.display().to_string(), &bytes, opts)?;
    for n in &scan.notes {
        eprintln!("note: {}: {n}", path.display());
    }
    Ok((bytes, scan))
}

fn channels(args: ChannelsArgs) -> anyhow::Result<()> {
    let bytes = fit::io::read_scan_file(&args.scan)?;
    let name = args.scan.display().to_string();
    let (format, list) = fit::io::list_channels(&name, &bytes, &read_options(&args.read)?)?;
    let default = list.iter().position(|c| c.is_height);
    if args.json {
        let json = serde_json::json!({
            "file": name,
            "format": format.name(),
            "default": default,
            "channels": list.iter().map(|c| serde_json::json!({
                "index": c.index, "name": c.name, "unit": c.unit,
                "height": c.is_height, "grid": [c.nx, c.ny],
            })).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string(&json)?);
        return Ok(());
    }
    println!(
        "{name}: {} ({} channel{})",
        format.name(),
        list.len(),
        if list.len() == 1 { "" } else { "s" }
    );
    for c in &list {
        println!(
            "{:>3}  {:<32} {:<6} {:>5} × {:<5} {}{}",
            c.index,
            c.name,
            c.unit,
            c.nx,
            c.ny,
            if c.is_height { "height" } else { "" },
            if Some(c.index) == default {
                " (default)"
            } else {
                ""
            }
        );
    }
    Ok(())
}

pub(crate) fn level_of(a: &ScanArgs) -> Option<Level> {
    a.level.as_deref().and_then(Level::from_name)
}

fn stats(args: StatsArgs) -> anyhow::Result<()> {
    let ropts = read_options(&args.read)?;
    let (_, scan) = load(&args.scan, &ropts)?;
    let fit::io::Scan {
        topo,
        format,
        channels,
        channel,
        notes: read_notes,
    } = scan;
    let checks = args.checks.checks(ropts.units);
    let s = pipeline::summarise_checked(topo, level_of(&args.read), &checks)
        .map_err(|e| in_file(e, &args.scan, None))?;
    let file = args.scan.display().to_string();
    let source = fit::stats_report::Source {
        file: &file,
        format: format.name(),
        channel,
        channel_name: channels.get(channel).map(|c| c.name.as_str()),
        notes: &read_notes,
    };
    let report = fit::stats_report::report(&source, &s);
    for w in &report.warnings {
        eprintln!("warning: {}: {w}", args.scan.display());
    }
    if !args.json {
        eprintln!("note: only JSON output is implemented; printing JSON");
    }
    println!("{}", serde_json::to_string(&report.json)?);
    Ok(())
}

/// An analysis error prefixed with the file it concerns: the library knows the step that
/// failed, not the file name.
fn in_file(e: fit::FitError, scan: &Path, stylus: Option<&Path>) -> anyhow::Error {
    let file = match (&e, stylus) {
        (fit::FitError::Stylus(_), Some(p)) => p,
        _ => scan,
    };
    anyhow::Error::new(e).context(file.display().to_string())
}

fn material(args: MaterialArgs) -> anyhow::Result<()> {
    let scan_path = args
        .scan
        .clone()
        .context("missing <SCAN>: usage `lustre fit <scan> -o material.toml`")?;
    // `lustre fit s.txt -o s.txt` replaced the raw scan with the material file; a scan named
    // like a plot (`m_psd.csv` for `-o m.toml`) went the same way.
    let mut outputs = vec![(args.output.clone(), "material file (-o)")];
    if !args.no_plots {
        outputs.extend(plots::paths(&args.output).into_iter().map(|p| (p, "plot")));
    }
    for input in std::iter::once(&scan_path).chain(args.stylus.as_ref()) {
        safe_io::register_input(input);
    }
    crate::outputs::check(&outputs)?;
    let ropts = read_options(&args.read)?;
    let (bytes, topo) = load(&scan_path, &ropts)?;
    let stylus = match &args.stylus {
        Some(p) => Some(load(
            p,
            &ReadOptions {
                channel: None,
                ..ropts.clone()
            },
        )?),
        None => None,
    };
    anyhow::ensure!(
        args.lambda_nm > 0.0 && args.lambda_nm.is_finite(),
        "--lambda-nm must be positive"
    );
    anyhow::ensure!(
        args.merge_cutoff > 0.0 && args.merge_cutoff.is_finite(),
        "--merge-cutoff must be positive"
    );
    anyhow::ensure!(
        args.cutoff.iter().all(|c| *c > 0.0 && c.is_finite()),
        "--cutoff values must be positive"
    );
    let opts = Options {
        cutoff_multiples: args.cutoff.clone(),
        wavelength: args.lambda_nm * 1e-9,
        merge_cutoff: args.merge_cutoff * 1e6,
        stylus_segments: args.stylus_segments,
        level: level_of(&args.read),
        checks: args.checks.checks(ropts.units),
        ..Options::default()
    };
    let fit::io::Scan {
        topo: scan_topo,
        notes: read_notes,
        ..
    } = topo;
    // Moved, not cloned: a second copy of a large map is a large share of the peak memory.
    let (stylus, stylus_topo) = match stylus {
        Some((b, s)) => (Some(b), Some(s.topo)),
        None => (None, None),
    };
    let analysis = pipeline::analyse(scan_topo, stylus_topo, &opts)
        .map_err(|e| in_file(e, &scan_path, args.stylus.as_deref()))?;
    let scan_name = scan_path.display().to_string();
    let stylus_name = args.stylus.as_ref().map(|p| p.display().to_string());
    let prov = fit::material_file::Provenance {
        file: &scan_name,
        bytes: &bytes,
        stylus: stylus_name.as_deref().zip(stylus.as_deref()),
        merge_cutoff_rad_per_um: args.merge_cutoff,
        metal: args.metal.as_deref().unwrap_or(DEFAULT_METAL),
        model: &args.model,
        notes: &read_notes,
    };
    let doc = fit::material_file::build(&analysis, &prov);
    // Every model the file offers must build as a scene `include` of it would.
    fit::material_file::check(&doc)
        .with_context(|| format!("{}: the material fitted to it", scan_path.display()))?;
    let text = fit::material_file::to_toml(&doc)?;
    plot::write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    let m = &doc.material;
    let n = |v: Option<f64>| v.unwrap_or(f64::NAN);
    eprintln!(
        "wrote {}: model {}, Sq {:.4} µm, rms slope {:.4}, KC σ {:.4} µm Lc {:.4} µm γ {:.3}{}, GGX α {:.4}, Beckmann α {:.4}",
        args.output.display(),
        m.model.map_or("none", |m| m.name()),
        analysis.stats.sq * 1e6,
        analysis.stats.rms_slope(),
        n(m.sigma_um),
        n(m.lc_um),
        n(m.gamma),
        if analysis.kc.degenerate {
            " (DEGENERATE: bounded estimate)"
        } else {
            ""
        },
        n(m.alpha),
        n(m.alpha_beckmann),
    );
    for n in &analysis.notes {
        eprintln!("note: {n}");
    }
    if args.metal.is_none() {
        eprintln!(
            "note: no --metal: [material].metal = \"{DEFAULT_METAL}\"; give the sample's metal \
             (--metal cu, au, ag, al, …) or set `metal` in the scene over the include"
        );
    }
    let r = &doc.reliability;
    for (part, state) in [
        ("kc", &r.kc),
        ("alpha", &r.alpha),
        ("psd", &r.psd),
        ("two_scale", &r.two_scale),
        ("form", &r.form),
        ("anisotropy", &r.anisotropy),
        ("variance", &r.variance),
        ("invalid", &r.invalid),
        ("outliers", &r.outliers),
        ("units", &r.units),
    ] {
        if state != "ok" {
            eprintln!("warning: {part}: {state}");
        }
    }
    eprintln!("model: {}", r.model);
    if !args.no_plots {
        // The material file is written; a plot that cannot be drawn is only a warning.
        match plots::write(&analysis, &args.output) {
            Ok(paths) => {
                for path in paths {
                    eprintln!("wrote {}", path.display());
                }
            }
            Err(e) => eprintln!("warning: plots not written: plot: {e}"),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analysis_errors_name_the_file_they_concern() {
        let err = || fit::FitError::Data {
            what: "levelling",
            problem: "singular".into(),
        };
        let (scan, stylus) = (Path::new("a/scan.gsf"), Path::new("b/stylus.csv"));
        let msg = format!("{:#}", in_file(err(), scan, Some(stylus)));
        assert_eq!(msg, "a/scan.gsf: levelling: singular");
        let msg = format!(
            "{:#}",
            in_file(fit::FitError::Stylus(Box::new(err())), scan, Some(stylus))
        );
        assert_eq!(msg, "b/stylus.csv: stylus profile: levelling: singular");
    }
}
