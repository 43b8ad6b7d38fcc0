//! `lustre judge <scan>`: the arguments of the `judge` crate's judgement, and its printing
//! (the judgement itself, its report and figures are `crates/judge`). Outputs (atomic):
//! `judge.json`, `judge_table.md`, `judge_points.csv`, `judge_slices.png` and
//! `judge_errors.png` in `-o`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::anyhow;
use brdf::Metal;

use crate::cmd_fit::ScanArgs;

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

impl JudgeArgs {
    /// The judgement's options; flag names in the library's messages are the options'.
    fn options(&self) -> anyhow::Result<judge::Options> {
        let metal = match self.metal.as_deref() {
            None => None,
            Some(m) if m.eq_ignore_ascii_case("none") => None,
            Some(m) => Some(Metal::from_name(m).ok_or_else(|| {
                anyhow!(
                    "--metal {m}: unknown; use cu, au, ag, al, fe, cr, brass or stainless_steel"
                )
            })?),
        };
        let opts = judge::Options {
            metal,
            lambda_nm: self.lambda.clone(),
            theta_i_deg: self.theta_i.clone(),
            cutoff_multiples: self.cutoff.clone(),
            angles: self.angles,
            tile: self.tile,
            crop: self.crop,
            upsample: self.upsample,
            surrogate: !self.no_surrogate,
            level: crate::cmd_fit::level_of(&self.read),
            reference: self.reference.clone(),
        };
        opts.check().map_err(as_flags)?;
        Ok(opts)
    }
}

/// The library's message with its option names as this command's flags.
fn as_flags(e: judge::JudgeError) -> anyhow::Error {
    const NAMES: [(&str, &str); 8] = [
        ("theta_i", "--theta-i"),
        ("lambda", "--lambda"),
        ("cutoff", "--cutoff"),
        ("angles", "--angles"),
        ("tile", "--tile"),
        ("crop", "--crop"),
        ("upsample", "--upsample"),
        ("reference", "--reference"),
    ];
    let msg = e.to_string();
    let mut out = String::with_capacity(msg.len() + 16);
    for (i, word) in msg.split(' ').enumerate() {
        if i > 0 {
            out.push(' ');
        }
        match NAMES.iter().find(|(n, _)| *n == word) {
            Some((_, flag)) => out.push_str(flag),
            None => out.push_str(word),
        }
    }
    anyhow!(out)
}

/// Runs `lustre judge`.
pub fn run(args: JudgeArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let opts = args.options()?;
    let bytes = fit::io::read_scan_file(&args.scan)?;
    if let Some(r) = &args.reference {
        safe_io::register_input(r);
    }
    let outputs: Vec<(PathBuf, &str)> = judge::Judgement::outputs(&args.out, !args.no_plots)
        .into_iter()
        .map(|p| (p, "output"))
        .collect();
    crate::outputs::check(&outputs)?;
    let name = args.scan.display().to_string();
    let topo = fit::io::read_bytes(&name, &bytes, &crate::cmd_fit::read_options(&args.read)?)?;
    // Before the minute of analysis: a crop or upsampling the scan cannot take.
    judge::check_explicit_size(&opts, topo.nx, topo.ny, topo.is_profile())
        .map_err(|e| as_flags(e).context(name.clone()))?;
    let j = judge::judge(&name, topo, &opts, &mut |line| eprintln!("{line}"))?;
    j.write(&args.out, !args.no_plots)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&j.json())?);
    } else {
        print!("{}", j.markdown());
    }
    eprintln!(
        "judge: wrote {} ({:.1} s)",
        args.out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
