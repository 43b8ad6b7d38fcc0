//! `lustre judge <scan>`: which scattering model is right for this surface, and what each
//! assumption costs.
//!
//! Every model is fitted from the same scan, as `lustre fit` fits it (`fit::pipeline`), and
//! compared in log space with the scan's own scalar-diffraction BRDF (`fit::explicit_brdf`:
//! the Kirchhoff / Harvey–Shack far field of the levelled height map, averaged over tiles,
//! with a confidence band) over the angular window where that reference can be trusted.
//! Each model is smoothed with the tile window's spectral kernel before the comparison, so
//! both sides have the same angular resolution.
//!
//! The models form one table ([`RECIPES`]); each row says what it assumes, so the differences
//! between rows price the assumptions: Gaussian heights (the explicit BRDF of a Gaussian
//! surrogate with the map's own spectrum, `fit::surrogate`), the K-correlation shape (full GHS
//! with the KC fit against full GHS with the measured PSD), first-order truncation (SSA against
//! full GHS), the two-scale split, and microfacet geometric optics.
//!
//! Geometry: the plane of incidence is the scan's x axis; i = (sinθi, 0, cosθi), the in-plane
//! slice has φo = 180° on the specular side (signed θo > 0) and 0° on the backscatter side; the
//! cross-plane slice passes through the mirror direction along y. For a profile the reference
//! is the in-plane BRDF integrated over the out-of-plane direction cosine, and every model is
//! integrated the same way (isotropy assumed). Outputs (atomic): `judge.json`, `judge_table.md`,
//! `judge_points.csv`, `judge_slices.png` (in-plane slices with the band) and
//! `judge_errors.png` (error against θi per model) in `-o`.

mod compare;
mod recipes;
mod reference;
mod report;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use brdf::Metal;
use fit::explicit_brdf::{ExplicitBrdf, TileOptions};
use fit::io::ReadOptions;
use fit::pipeline::{self, Options};
use fit::two_scale::TwoScale as Split;
use serde_json::Value;

use crate::cmd_fit::ScanArgs;
use compare::{Judged, angle_set, judge};
use recipes::{Fitted, RECIPES, energy_check, fresnel_of, two_scale_candidate};
use reference::judge_reference;
use report::Report;

/// Arguments of `lustre judge`.
#[derive(clap::Args)]
pub struct JudgeArgs {
    /// Surface scan (any format `lustre fit` reads).
    pub scan: PathBuf,
    /// Metal for the Fresnel factor of every model and of the explicit BRDF (default: none,
    /// R ≡ 1, which judges the geometry alone).
    #[arg(long)]
    pub metal: Option<String>,
    /// Wavelengths [nm].
    #[arg(long, value_delimiter = ',', default_values_t = vec![450.0, 550.0, 650.0])]
    pub lambda: Vec<f64>,
    /// Incidence angles [deg].
    #[arg(long = "theta-i", value_delimiter = ',', default_values_t = vec![0.0, 45.0, 80.0])]
    pub theta_i: Vec<f64>,
    /// Print the report as JSON on stdout (it is always written to judge.json).
    #[arg(long)]
    pub json: bool,
    /// Measured BRDF to rank the models against as well: CSV with a header naming
    /// theta_i_deg, theta_o_deg, phi_o_deg, lambda_nm, brdf (any order).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Output directory.
    #[arg(short = 'o', long, default_value = "out/judge")]
    pub out: PathBuf,
    /// Two-scale cutoffs as multiples of 550 nm (the best cutoff is searched as well).
    #[arg(long, value_delimiter = ',', default_values_t = vec![50.0, 100.0, 150.0])]
    pub cutoff: Vec<f64>,
    /// Directions per slice (in-plane; the cross-plane slice gets half as many).
    #[arg(long, default_value_t = 90)]
    pub angles: usize,
    /// Tile edge in pixels for the speckle average (default: a quarter of the shorter side).
    #[arg(long)]
    pub tile: Option<usize>,
    /// Use only the central N × N pixels (N points of a profile) for the explicit BRDF (the
    /// models are still fitted from the whole scan).
    #[arg(long)]
    pub crop: Option<usize>,
    /// Band-limited upsampling of the (cropped) map for the explicit BRDF, for scans whose
    /// pixels are coarse against λ/(2·rms slope) (see `fit::resample`).
    #[arg(long, default_value_t = 1)]
    pub upsample: usize,
    /// Skip the Gaussian-surrogate reference (halves the explicit computation).
    #[arg(long)]
    pub no_surrogate: bool,
    /// Skip the PNG figures.
    #[arg(long)]
    pub no_plots: bool,
    #[command(flatten)]
    pub read: ScanArgs,
}

/// Multiples of 550 nm searched for the two-scale cutoff that fits best.
const CUTOFF_SEARCH: [f64; 13] = [
    2.0, 3.0, 5.0, 10.0, 20.0, 35.0, 50.0, 75.0, 100.0, 150.0, 200.0, 300.0, 500.0,
];
/// Kernel quadrature nodes per axis and their reach in tile frequency steps.
const KERNEL_NODES: usize = 9;
const KERNEL_REACH: f64 = 2.5;
/// Values below this fraction of the slice's largest explicit value are floored before taking
/// logarithms (a model that is zero there is wrong by at least this much, not infinitely).
const LOG_FLOOR: f64 = 1e-6;
const REFERENCE_LAMBDA_NM: f64 = brdf::paper::REFERENCE_LAMBDA_NM;
/// Most directions per slice: the run time is linear in them (`--angles 100000` ran for hours).
const MAX_ANGLES: usize = 1000;
/// Most points of the (cropped, upsampled) map the explicit BRDF is computed on: 2048² takes
/// about 1.5 min on 2 cores (twice that with the surrogate), 4096² more than 5 min;
/// `--upsample 16` of a 512² map (8192²) ran for half an hour.
const MAX_EXPLICIT_SIDE: usize = 2048;
const MAX_EXPLICIT_POINTS: usize = MAX_EXPLICIT_SIDE * MAX_EXPLICIT_SIDE;
/// Log-spaced points of the denoised measured-PSD table.
const PSD_NODES: usize = 120;

/// The scan flags read exactly as `lustre fit` reads them.
fn read_options(a: &ScanArgs) -> anyhow::Result<ReadOptions> {
    crate::cmd_fit::read_options(a)
}

fn check_args(args: &JudgeArgs) -> anyhow::Result<()> {
    if args.lambda.is_empty() || args.theta_i.is_empty() {
        bail!("--lambda and --theta-i each need at least one value");
    }
    crate::models::check_wavelengths("--lambda", &args.lambda)?;
    crate::models::check_incidence(&args.theta_i, 89.0)?;
    for &c in &args.cutoff {
        if !(c.is_finite() && c > 0.0) {
            bail!("--cutoff {c}: must be a positive multiple of 550 nm");
        }
    }
    if !(8..=MAX_ANGLES).contains(&args.angles) {
        bail!(
            "--angles {}: must lie in 8..={MAX_ANGLES} (the run time grows with it: 360 takes \
             ~30 s on a 512 × 512 map, and the explicit BRDF resolves no finer than its tiles)",
            args.angles
        );
    }
    if let Some(r) = &args.reference
        && !r.is_file()
    {
        // Checked before the minute of analysis that precedes reading it.
        bail!(
            "--reference {}: no such file. Fix: give the measured-BRDF CSV (header theta_i_deg, \
             theta_o_deg, phi_o_deg, lambda_nm, brdf)",
            r.display()
        );
    }
    if let Some(t) = args.tile
        && t < 8
    {
        bail!("--tile {t}: need at least 8 pixels");
    }
    if let Some(c) = args.crop
        && c < 16
    {
        bail!("--crop {c}: need at least 16 pixels");
    }
    if !(1..=16).contains(&args.upsample) {
        bail!("--upsample {}: must lie in 1..=16", args.upsample);
    }
    Ok(())
}

/// Refuses a `--crop` larger than the scan (it was clamped while the report claimed the
/// requested size) and a `--upsample` whose map would take many minutes (a scan
/// measured larger than that is not refused: only the upsampling is).
fn check_explicit_size(
    args: &JudgeArgs,
    nx: usize,
    ny: usize,
    profile: bool,
) -> anyhow::Result<()> {
    let scan = args.scan.display();
    let side = if profile { nx } else { nx.min(ny) };
    if let Some(c) = args.crop
        && c > side
    {
        let grid = if profile {
            format!("a profile of {nx} points")
        } else {
            format!("{nx} × {ny} points")
        };
        bail!(
            "{scan}: --crop {c}: larger than the scan ({grid}). Fix: --crop {side} or less, \
             or drop --crop to use the whole scan"
        );
    }
    let (cx, cy) = match args.crop {
        Some(c) if profile => (c, 1),
        Some(c) => (c, c),
        None => (nx, ny),
    };
    let u = args.upsample;
    let (ux, uy) = (cx * u, if profile { 1 } else { cy * u });
    // Only what upsampling adds is refused: a scan measured that large is the
    // user's data, and is computed on as it is, however long that takes.
    if u > 1 && ux.saturating_mul(uy) > MAX_EXPLICIT_POINTS.max(cx.saturating_mul(cy)) {
        bail!(
            "{scan}: --upsample {u} would compute the explicit BRDF on {ux} × {uy} points, more \
             than {MAX_EXPLICIT_SIDE}² (which already takes about 1.5 min). Fix: upsample the centre \
             only with --crop (e.g. --crop {}), or a smaller --upsample",
            (MAX_EXPLICIT_SIDE / u).min(side)
        );
    }
    Ok(())
}

/// Runs `lustre judge`.
pub fn run(args: JudgeArgs) -> anyhow::Result<()> {
    check_args(&args)?;
    let start = Instant::now();
    let fresnel_name = match &args.metal {
        None => "none".to_string(),
        Some(m) if m.eq_ignore_ascii_case("none") => "none".to_string(),
        Some(m) => Metal::from_name(m)
            .map(|x| x.name().to_string())
            .ok_or_else(|| {
                anyhow!(
                    "--metal {m}: unknown; use cu, au, ag, al, fe, cr, brass or stainless_steel"
                )
            })?,
    };
    let fresnel = fresnel_of(&fresnel_name)?;
    let bytes = fit::io::read_scan_file(&args.scan)?;
    if let Some(r) = &args.reference {
        safe_io::register_input(r);
    }
    let mut outputs = vec![
        (args.out.join("judge.json"), "report"),
        (args.out.join("judge_table.md"), "table"),
        (args.out.join("judge_points.csv"), "point table"),
    ];
    if !args.no_plots {
        outputs.push((args.out.join("judge_slices.png"), "figure"));
    }
    crate::outputs::check(&outputs)?;
    let topo = fit::io::read_bytes(
        &args.scan.display().to_string(),
        &bytes,
        &read_options(&args.read)?,
    )?;
    let opts = Options {
        cutoff_multiples: Vec::new(),
        level: crate::cmd_fit::level_of(&args.read),
        ..Options::default()
    };
    let analysis = pipeline::analyse(topo, None, &opts)
        .with_context(|| format!("{}: analysing the scan", args.scan.display()))?;
    let profile = analysis.scan.is_profile();
    eprintln!(
        "judge: {} — {} × {} points, pixel {:.4} µm, Sq {:.4} µm, rms slope {:.4} ({:.1} s)",
        args.scan.display(),
        analysis.scan.nx,
        analysis.scan.ny,
        analysis.scan.dx * 1e6,
        analysis.stats.sq * 1e6,
        analysis.stats.rms_slope(),
        start.elapsed().as_secs_f64()
    );

    // Two-scale splits at the requested cutoffs and the search grid.
    let mut multiples: Vec<f64> = args.cutoff.clone();
    for m in CUTOFF_SEARCH {
        if !multiples.contains(&m) {
            multiples.push(m);
        }
    }
    let range = analysis.kc.range;
    let splits: Vec<(f64, Result<Split, String>)> = multiples
        .iter()
        .map(|&m| {
            (
                m,
                fit::two_scale::split(
                    &analysis.scan,
                    &analysis.fit_psd,
                    m,
                    REFERENCE_LAMBDA_NM * 1e-9,
                    (range.0 * (1.0 - 1e-9), range.1 * (1.0 + 1e-9)),
                )
                .map_err(|e| e.to_string()),
            )
        })
        .collect();
    let mut geometry = Vec::new();
    for &l in &args.lambda {
        for &t in &args.theta_i {
            geometry.push((brdf::paper::wavenumber(l), t.to_radians().cos()));
        }
    }
    let fitted = Fitted {
        analysis: &analysis,
        splits,
        fresnel: fresnel_name.clone(),
        geometry,
    };

    // The explicit reference (and its Gaussian surrogate).
    let tiles = TileOptions {
        size: args.tile,
        ..TileOptions::default()
    };
    check_explicit_size(&args, analysis.scan.nx, analysis.scan.ny, profile)?;
    let base = match args.crop {
        Some(c) => fit::resample::crop_center(&analysis.scan, c, if profile { 1 } else { c }),
        None => analysis.scan.clone(),
    };
    // The explicit-BRDF steps report what failed, not on which file.
    let in_scan = || args.scan.display().to_string();
    let explicit = ExplicitBrdf::new(
        &fit::resample::upsample(&base, args.upsample).with_context(in_scan)?,
        &tiles,
    )
    .with_context(|| format!("{}: explicit BRDF", args.scan.display()))?;
    let surrogate = if args.no_surrogate {
        None
    } else {
        let s = fit::surrogate::gaussian_surrogate(&base, 0x5eed)
            .with_context(|| format!("{}: Gaussian surrogate", args.scan.display()))?;
        Some(
            ExplicitBrdf::new(
                &fit::resample::upsample(&s, args.upsample).with_context(in_scan)?,
                &tiles,
            )
            .with_context(|| format!("{}: explicit BRDF of the surrogate", args.scan.display()))?,
        )
    };
    let mut sets = Vec::new();
    for &theta_i in &args.theta_i {
        for &lambda_nm in &args.lambda {
            sets.push(angle_set(
                &explicit,
                surrogate.as_ref(),
                &fresnel,
                theta_i,
                lambda_nm,
                args.angles,
            ));
        }
    }
    eprintln!(
        "judge: explicit BRDF at {} directions × {} (θi, λ), {} tiles of {}×{} px ({:.1} s)",
        sets.first().map_or(0, |s| s.points.len()),
        sets.len(),
        explicit.tiles(),
        explicit.tile_pixels().0,
        explicit.tile_pixels().1,
        start.elapsed().as_secs_f64()
    );

    // Models.
    let nodes = explicit.kernel_nodes(KERNEL_NODES, KERNEL_REACH);
    let mut judged = Vec::new();
    let mut skipped: Vec<(String, String)> = Vec::new();
    for r in &RECIPES {
        for b in (r.make)(&fitted, &args.cutoff)
            .into_iter()
            .map(|b| b.and_then(|c| energy_check(c, &args)))
        {
            match b {
                Ok(c) => judged.push(judge(c, &sets, &nodes, profile)),
                Err((label, reason)) => skipped.push((format!("{label} [{}]", r.model), reason)),
            }
        }
    }
    // The two-scale cutoff that fits best, over the search grid.
    let mut best: Option<Judged> = None;
    for &m in &multiples {
        if let Ok(c) = two_scale_candidate(&fitted, m).and_then(|c| energy_check(c, &args)) {
            let j = judge(c, &sets, &nodes, profile);
            let better = match &best {
                None => j.overall.n > 0,
                Some(b) => j.overall.rms() < b.overall.rms(),
            };
            if better {
                best = Some(j);
            }
        }
    }
    if let Some(mut b) = best {
        let m = b.c.params.get("cutoff_multiple").and_then(Value::as_f64);
        b.c.key = "two_scale_best".into();
        b.c.label = format!(
            "two-scale, best cutoff {}λ (β {})",
            m.unwrap_or(f64::NAN),
            brdf::paper::short(
                b.c.params
                    .get("beta")
                    .and_then(Value::as_f64)
                    .unwrap_or(f64::NAN)
            )
        );
        judged.push(b);
    } else {
        skipped.push((
            "two-scale, best cutoff".into(),
            "no cutoff could be fitted".into(),
        ));
    }
    judged.sort_by(|a, b| {
        let (x, y) = (a.overall.rms(), b.overall.rms());
        x.is_nan().cmp(&y.is_nan()).then(x.total_cmp(&y))
    });
    eprintln!(
        "judge: {} models judged, {} skipped ({:.1} s)",
        judged.len(),
        skipped.len(),
        start.elapsed().as_secs_f64()
    );
    // A ranking over no compared direction is no judgement (an 8-point
    // profile gave one, and a plot error for its empty series).
    if judged.iter().all(|j| j.overall.n == 0) {
        bail!(
            "{}: no direction of the scan's explicit BRDF could be compared with a model (every \
             value was unresolved or outside the compared range at these θi and λ): the scan is \
             too short or too coarse for its wave-optical BRDF. Fix: judge a longer profile or a \
             larger map (the explicit BRDF needs many correlation lengths), or other --theta-i / \
             --lambda",
            args.scan.display()
        );
    }

    let reference = match &args.reference {
        Some(p) => Some(judge_reference(p, &judged, &explicit, &fresnel)?),
        None => None,
    };
    let report = Report {
        args: &args,
        analysis: &analysis,
        explicit: &explicit,
        sets: &sets,
        judged: &judged,
        skipped: &skipped,
        reference: reference.as_ref(),
        fresnel: &fresnel_name,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating output directory {}", args.out.display()))?;
    let json_text = serde_json::to_string_pretty(&report.json())?;
    plot::write_atomic(&args.out.join("judge.json"), json_text.as_bytes())?;
    let table = report.markdown();
    plot::write_atomic(&args.out.join("judge_table.md"), table.as_bytes())?;
    plot::write_atomic(&args.out.join("judge_points.csv"), report.csv().as_bytes())?;
    if !args.no_plots {
        report.plots(&args.out)?;
    }
    if args.json {
        println!("{json_text}");
    } else {
        print!("{table}");
    }
    eprintln!(
        "judge: wrote {} ({:.1} s)",
        args.out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        judge: JudgeArgs,
    }

    fn args(extra: &[&str]) -> JudgeArgs {
        let mut argv = vec!["judge", "scan.x3p"];
        argv.extend_from_slice(extra);
        Cli::try_parse_from(argv).expect("valid flags").judge
    }

    /// The size limit is on what `--upsample` adds: a scan measured at
    /// 4096² is computed on as it is, while upsampling a 512² scan to
    /// 8192² (half an hour) is refused, and so is a crop past the scan.
    #[test]
    fn only_upsampling_past_the_limit_is_refused_not_a_large_scan() {
        assert!(check_explicit_size(&args(&[]), 4096, 4096, false).is_ok());
        assert!(check_explicit_size(&args(&[]), 1 << 20, 1, true).is_ok());
        assert!(check_explicit_size(&args(&["--upsample", "2"]), 1024, 1024, false).is_ok());
        let e = check_explicit_size(&args(&["--upsample", "16"]), 512, 512, false).unwrap_err();
        assert!(e.to_string().contains("--crop 128"), "{e}");
        assert!(check_explicit_size(&args(&["--upsample", "2"]), 4096, 4096, false).is_err());
        assert!(check_explicit_size(&args(&["--crop", "600"]), 512, 512, false).is_err());
    }
}
