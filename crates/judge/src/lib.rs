//! # judge — which scattering model is right for a surface, and what each assumption costs
//!
//! Every model is fitted from the same scan (`fit::candidates`, the models `lustre fit`
//! writes) and compared in log space with the scan's own scalar-diffraction BRDF
//! (`fit::explicit_brdf`: the Kirchhoff / Harvey–Shack far field of the levelled height
//! map, averaged over tiles, with a confidence band) over the angular window where that
//! reference can be trusted. Each model is smoothed with the tile window's spectral kernel
//! before the comparison, so both sides have the same angular resolution.
//!
//! The candidates form one table (`fit::candidates::Family`); each row says what it
//! assumes, so the differences between rows price the assumptions: Gaussian heights (the
//! explicit BRDF of a Gaussian surrogate with the map's own spectrum, `fit::surrogate`),
//! the K-correlation shape (full GHS with the KC fit against full GHS with the measured
//! PSD), first-order truncation (SSA against full GHS), the two-scale split, microfacet
//! geometric optics, and the polarisation factor (full GHS with the Rayleigh–Rice Q
//! against the scalar Fresnel R, and first-order Rayleigh–Rice against it). The
//! explicit reference is a scalar theory: only against a measured `--reference` does
//! the Q row price the polarisation itself.
//!
//! Geometry: the plane of incidence is the scan's x axis; i = (sinθi, 0, cosθi), the
//! in-plane slice has φo = 180° on the specular side (signed θo > 0) and 0° on the
//! backscatter side; the cross-plane slice passes through the mirror direction along y. For
//! a profile the reference is the in-plane BRDF integrated over the out-of-plane direction
//! cosine, and every model is integrated the same way (isotropy assumed).
//!
//! ```no_run
//! let topo = fit::io::read_path("scan.x3p".as_ref(), &Default::default())?;
//! let opts = judge::Options::default();
//! let j = judge::judge("scan.x3p", topo, &opts, &mut |line| eprintln!("{line}"))?;
//! println!("{}", j.markdown());
//! j.write("out/judge".as_ref(), true)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod compare;
mod recipes;
mod reference;
mod report;

use std::path::{Path, PathBuf};
use std::time::Instant;

use brdf::Metal;
use brdf::spec::FresnelSpec;
use fit::explicit_brdf::{ExplicitBrdf, TileOptions};
use fit::level::Level;
use fit::pipeline::{self, Analysis};
use fit::topography::Topography;
use serde_json::Value;

use compare::{AngleSet, Judged, angle_set};
use recipes::{energy_check, fresnel_of};
use reference::{ReferenceResult, judge_reference};
use report::Report;

/// Why a judgement could not be made: the option or the data, and what to do.
#[derive(Debug, thiserror::Error)]
pub enum JudgeError {
    /// An option is out of range, or the scan cannot be judged; the message names it and
    /// the fix.
    #[error("{0}")]
    Invalid(String),
    /// The analysis of the scan failed.
    #[error(transparent)]
    Fit(#[from] fit::FitError),
    /// A figure could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    /// The reference file could not be read.
    #[error(transparent)]
    Read(#[from] safe_io::ReadError),
    /// The report could not be encoded.
    #[error("encoding the report: {0}")]
    Json(#[from] serde_json::Error),
}

/// [`JudgeError::Invalid`] from a format string.
#[macro_export]
#[doc(hidden)]
macro_rules! invalid {
    ($($t:tt)*) => { $crate::JudgeError::Invalid(format!($($t)*)) };
}

/// Multiples of 550 nm searched for the two-scale cutoff that fits best.
pub const CUTOFF_SEARCH: [f64; 13] = [
    2.0, 3.0, 5.0, 10.0, 20.0, 35.0, 50.0, 75.0, 100.0, 150.0, 200.0, 300.0, 500.0,
];
/// Kernel quadrature nodes per axis and their reach in tile frequency steps.
const KERNEL_NODES: usize = 9;
const KERNEL_REACH: f64 = 2.5;
/// Values below this fraction of the slice's largest explicit value are floored before
/// taking logarithms (a model that is zero there is wrong by at least this much, not
/// infinitely).
pub(crate) const LOG_FLOOR: f64 = 1e-6;
/// Most directions per slice: the run time is linear in them.
pub const MAX_ANGLES: usize = 1000;
/// Most points of the (cropped, upsampled) map the explicit BRDF is computed on: 2048²
/// takes about 1.5 min on 2 cores (twice that with the surrogate), 4096² more than 5 min.
pub const MAX_EXPLICIT_SIDE: usize = 2048;
const MAX_EXPLICIT_POINTS: usize = MAX_EXPLICIT_SIDE * MAX_EXPLICIT_SIDE;

/// What to judge and how.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Metal of every model's Fresnel factor and of the explicit BRDF; `None`: R ≡ 1,
    /// which judges the geometry alone.
    pub metal: Option<Metal>,
    /// Wavelengths [nm].
    pub lambda_nm: Vec<f64>,
    /// Incidence angles [deg], below 89°.
    pub theta_i_deg: Vec<f64>,
    /// Two-scale cutoffs as multiples of 550 nm (the best cutoff of [`CUTOFF_SEARCH`] is
    /// judged as well).
    pub cutoff_multiples: Vec<f64>,
    /// Directions per slice (in-plane; the cross-plane slice gets half as many), 8..=1000.
    pub angles: usize,
    /// Tile edge in pixels for the speckle average (default: a quarter of the shorter side).
    pub tile: Option<usize>,
    /// Use only the central N × N pixels (N points of a profile) for the explicit BRDF.
    pub crop: Option<usize>,
    /// Band-limited upsampling of the (cropped) map for the explicit BRDF, 1..=16.
    pub upsample: usize,
    /// Whether to compute the Gaussian-surrogate reference (doubles the explicit work).
    pub surrogate: bool,
    /// Levelling; `None`: a plane for maps, a line for profiles.
    pub level: Option<Level>,
    /// A measured BRDF to rank the models against as well: CSV with a header naming
    /// theta_i_deg, theta_o_deg, phi_o_deg, lambda_nm, brdf (any order).
    pub reference: Option<PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            metal: None,
            lambda_nm: vec![450.0, 550.0, 650.0],
            theta_i_deg: vec![0.0, 45.0, 80.0],
            cutoff_multiples: vec![50.0, 100.0, 150.0],
            angles: 90,
            tile: None,
            crop: None,
            upsample: 1,
            surrogate: true,
            level: None,
            reference: None,
        }
    }
}

impl Options {
    /// Refuses values that cannot be judged, naming the option and its range.
    pub fn check(&self) -> Result<(), JudgeError> {
        if self.lambda_nm.is_empty() || self.theta_i_deg.is_empty() {
            return Err(invalid!("lambda and theta_i each need at least one value"));
        }
        let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
        for &l in &self.lambda_nm {
            if !(lo..=hi).contains(&l) {
                return Err(invalid!("lambda {l}: must lie in {lo}–{hi} nm"));
            }
        }
        for &t in &self.theta_i_deg {
            if !(0.0..89.0).contains(&t) {
                return Err(invalid!("theta_i {t}: must lie in [0, 89) degrees"));
            }
        }
        for &c in &self.cutoff_multiples {
            if !(c.is_finite() && c > 0.0) {
                return Err(invalid!(
                    "cutoff {c}: must be a positive multiple of 550 nm"
                ));
            }
        }
        if !(8..=MAX_ANGLES).contains(&self.angles) {
            return Err(invalid!(
                "angles {}: must lie in 8..={MAX_ANGLES} (the run time grows with it: 360 \
                 takes ~30 s on a 512 × 512 map, and the explicit BRDF resolves no finer than \
                 its tiles)",
                self.angles
            ));
        }
        if let Some(t) = self.tile.filter(|t| *t < 8) {
            return Err(invalid!("tile {t}: need at least 8 pixels"));
        }
        if let Some(c) = self.crop.filter(|c| *c < 16) {
            return Err(invalid!("crop {c}: need at least 16 pixels"));
        }
        if !(1..=16).contains(&self.upsample) {
            return Err(invalid!("upsample {}: must lie in 1..=16", self.upsample));
        }
        if let Some(r) = self.reference.as_ref().filter(|r| !r.is_file()) {
            return Err(invalid!(
                "reference {}: no such file. Fix: give the measured-BRDF CSV (header \
                 theta_i_deg, theta_o_deg, phi_o_deg, lambda_nm, brdf)",
                r.display()
            ));
        }
        Ok(())
    }

    /// The Fresnel term of every model.
    fn fresnel_spec(&self) -> FresnelSpec {
        self.metal.map_or(FresnelSpec::One, FresnelSpec::Metal)
    }

    /// The name of the Fresnel term in reports (`none` for R ≡ 1).
    fn fresnel_name(&self) -> String {
        self.metal.map_or("none".into(), |m| m.name().to_string())
    }
}

/// Refuses a `crop` larger than the scan and an `upsample` whose map would take many
/// minutes (a scan measured larger than that is not refused: only the upsampling is).
pub fn check_explicit_size(
    opts: &Options,
    nx: usize,
    ny: usize,
    profile: bool,
) -> Result<(), JudgeError> {
    let side = if profile { nx } else { nx.min(ny) };
    if let Some(c) = opts.crop.filter(|c| *c > side) {
        let grid = if profile {
            format!("a profile of {nx} points")
        } else {
            format!("{nx} × {ny} points")
        };
        return Err(invalid!(
            "crop {c}: larger than the scan ({grid}). Fix: crop {side} or less, or no crop to \
             use the whole scan"
        ));
    }
    let (cx, cy) = match opts.crop {
        Some(c) if profile => (c, 1),
        Some(c) => (c, c),
        None => (nx, ny),
    };
    let u = opts.upsample;
    let (ux, uy) = (cx * u, if profile { 1 } else { cy * u });
    if u > 1 && ux.saturating_mul(uy) > MAX_EXPLICIT_POINTS.max(cx.saturating_mul(cy)) {
        return Err(invalid!(
            "upsample {u} would compute the explicit BRDF on {ux} × {uy} points, more than \
             {MAX_EXPLICIT_SIDE}² (which already takes about 1.5 min). Fix: upsample the \
             centre only with crop (e.g. crop {}), or a smaller upsample",
            (MAX_EXPLICIT_SIDE / u).min(side)
        ));
    }
    Ok(())
}

/// The judgement of one scan: the analysis, the reference and every model's score.
pub struct Judgement {
    scan: String,
    opts: Options,
    fresnel: String,
    analysis: Analysis,
    explicit: ExplicitBrdf,
    sets: Vec<AngleSet>,
    judged: Vec<Judged>,
    skipped: Vec<(String, String)>,
    reference: Option<ReferenceResult>,
}

/// Judges the scan `topo` (named `scan` in reports) with `opts`; `log` receives one line
/// per stage with the time taken.
pub fn judge(
    scan: &str,
    topo: Topography,
    opts: &Options,
    log: &mut dyn FnMut(String),
) -> Result<Judgement, JudgeError> {
    opts.check()?;
    let start = Instant::now();
    let secs = || start.elapsed().as_secs_f64();
    let mut multiples = opts.cutoff_multiples.clone();
    multiples.extend(
        CUTOFF_SEARCH
            .iter()
            .filter(|m| !opts.cutoff_multiples.contains(m)),
    );
    let analysis = pipeline::analyse(
        topo,
        None,
        &pipeline::Options {
            cutoff_multiples: multiples,
            wavelength: brdf::paper::REFERENCE_LAMBDA_NM * 1e-9,
            level: opts.level,
            ..pipeline::Options::default()
        },
    )
    .map_err(|e| invalid!("{scan}: analysing the scan: {e}"))?;
    let a = &analysis;
    log(format!(
        "judge: {scan} — {} × {} points, pixel {:.4} µm, Sq {:.4} µm, rms slope {:.4} ({:.1} s)",
        a.scan.nx,
        a.scan.ny,
        a.scan.dx * 1e6,
        a.stats.sq * 1e6,
        a.stats.rms_slope(),
        secs()
    ));
    let (explicit, sets) = reference_slices(scan, &analysis, opts)?;
    log(format!(
        "judge: explicit BRDF at {} directions × {} (θi, λ), {} tiles of {}×{} px ({:.1} s)",
        sets.first().map_or(0, |s| s.points.len()),
        sets.len(),
        explicit.tiles(),
        explicit.tile_pixels().0,
        explicit.tile_pixels().1,
        secs()
    ));
    let (judged, skipped) = rank(&analysis, &explicit, &sets, opts);
    log(format!(
        "judge: {} models judged, {} skipped ({:.1} s)",
        judged.len(),
        skipped.len(),
        secs()
    ));
    // A ranking over no compared direction is no judgement.
    if judged.iter().all(|j| j.overall.n == 0) {
        return Err(invalid!(
            "{scan}: no direction of the scan's explicit BRDF could be compared with a model \
             (every value was unresolved or outside the compared range at these θi and λ): \
             the scan is too short or too coarse for its wave-optical BRDF. Fix: judge a \
             longer profile or a larger map (the explicit BRDF needs many correlation \
             lengths), or other theta_i / lambda"
        ));
    }
    let reference = match &opts.reference {
        Some(p) => Some(judge_reference(p, &judged, &explicit, &fresnel_of(opts))?),
        None => None,
    };
    Ok(Judgement {
        scan: scan.to_string(),
        opts: opts.clone(),
        fresnel: opts.fresnel_name(),
        analysis,
        explicit,
        sets,
        judged,
        skipped,
        reference,
    })
}

/// The scan's explicit BRDF (and its Gaussian surrogate's) at every (θi, λ) judged.
fn reference_slices(
    scan: &str,
    a: &Analysis,
    opts: &Options,
) -> Result<(ExplicitBrdf, Vec<AngleSet>), JudgeError> {
    let profile = a.scan.is_profile();
    check_explicit_size(opts, a.scan.nx, a.scan.ny, profile)
        .map_err(|e| invalid!("{scan}: {e}"))?;
    let tiles = TileOptions {
        size: opts.tile,
        ..TileOptions::default()
    };
    let base = match opts.crop {
        Some(c) => fit::resample::crop_center(&a.scan, c, if profile { 1 } else { c }),
        None => a.scan.clone(),
    };
    let in_scan = |what: &str, e: fit::FitError| invalid!("{scan}: {what}: {e}");
    let upsampled =
        fit::resample::upsample(&base, opts.upsample).map_err(|e| in_scan("upsampling", e))?;
    let explicit =
        ExplicitBrdf::new(&upsampled, &tiles).map_err(|e| in_scan("explicit BRDF", e))?;
    let surrogate = if opts.surrogate {
        let s = fit::surrogate::gaussian_surrogate(&base, 0x5eed)
            .map_err(|e| in_scan("Gaussian surrogate", e))?;
        let s = fit::resample::upsample(&s, opts.upsample).map_err(|e| in_scan("upsampling", e))?;
        Some(
            ExplicitBrdf::new(&s, &tiles)
                .map_err(|e| in_scan("explicit BRDF of the surrogate", e))?,
        )
    } else {
        None
    };
    let fresnel = fresnel_of(opts);
    let mut sets = Vec::new();
    for &theta_i in &opts.theta_i_deg {
        for &lambda_nm in &opts.lambda_nm {
            sets.push(angle_set(
                &explicit,
                surrogate.as_ref(),
                &fresnel,
                theta_i,
                lambda_nm,
                opts.angles,
            ));
        }
    }
    Ok((explicit, sets))
}

/// Every candidate judged (best first) and those skipped with the reason; the two-scale
/// cutoff that fits best over [`CUTOFF_SEARCH`] is judged as a row of its own.
fn rank(
    a: &Analysis,
    explicit: &ExplicitBrdf,
    sets: &[AngleSet],
    opts: &Options,
) -> (Vec<Judged>, Vec<(String, String)>) {
    let profile = a.scan.is_profile();
    let nodes = explicit.kernel_nodes(KERNEL_NODES, KERNEL_REACH);
    let mut geometry = Vec::new();
    for &l in &opts.lambda_nm {
        for &t in &opts.theta_i_deg {
            geometry.push((brdf::paper::wavenumber(l), t.to_radians().cos()));
        }
    }
    let all = fit::candidates::candidates(a, &opts.fresnel_spec());
    let asked = |c: &&fit::candidates::Candidate| match c.cutoff {
        Some((m, _)) => opts.cutoff_multiples.contains(&m),
        None => true,
    };
    let built = |c: &fit::candidates::Candidate| {
        recipes::build(c, &geometry).and_then(|b| energy_check(b, opts))
    };
    let mut judged = Vec::new();
    let mut skipped = Vec::new();
    for c in all.iter().filter(asked) {
        match built(c) {
            Ok(b) => judged.push(compare::judge(b, sets, &nodes, profile)),
            Err((label, reason)) => {
                skipped.push((format!("{label} [{}]", c.family.name()), reason))
            }
        }
    }
    let mut best: Option<Judged> = None;
    for c in all.iter().filter(|c| c.cutoff.is_some()) {
        if let Ok(b) = built(c) {
            let j = compare::judge(b, sets, &nodes, profile);
            let better = match &best {
                None => j.overall.n > 0,
                Some(b) => j.overall.rms() < b.overall.rms(),
            };
            if better {
                best = Some(j);
            }
        }
    }
    match best {
        Some(mut b) => {
            let get = |k: &str| {
                b.c.params
                    .get(k)
                    .and_then(Value::as_f64)
                    .unwrap_or(f64::NAN)
            };
            let (m, beta) = (get("cutoff_multiple"), get("beta"));
            b.c.key = format!("{}_best", fit::candidates::Family::TwoScale.name());
            b.c.label = format!(
                "two-scale, best cutoff {m}λ (β {})",
                brdf::paper::short(beta)
            );
            judged.push(b);
        }
        None => skipped.push((
            "two-scale, best cutoff".into(),
            "no cutoff could be fitted".into(),
        )),
    }
    judged.sort_by(|a, b| {
        let (x, y) = (a.overall.rms(), b.overall.rms());
        x.is_nan().cmp(&y.is_nan()).then(x.total_cmp(&y))
    });
    (judged, skipped)
}

impl Judgement {
    fn report(&self) -> Report<'_> {
        Report {
            scan: &self.scan,
            crop: self.opts.crop,
            upsample: self.opts.upsample,
            analysis: &self.analysis,
            explicit: &self.explicit,
            sets: &self.sets,
            judged: &self.judged,
            skipped: &self.skipped,
            reference: self.reference.as_ref(),
            fresnel: &self.fresnel,
        }
    }

    /// The report as JSON (what `judge.json` holds).
    pub fn json(&self) -> Value {
        self.report().json()
    }

    /// The ranking as a Markdown table (`judge_table.md`).
    pub fn markdown(&self) -> String {
        self.report().markdown()
    }

    /// Every compared point of every model (`judge_points.csv`).
    pub fn csv(&self) -> String {
        self.report().csv()
    }

    /// The files [`Judgement::write`] writes into `dir`.
    pub fn outputs(dir: &Path, figures: bool) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = ["judge.json", "judge_table.md", "judge_points.csv"]
            .iter()
            .map(|f| dir.join(f))
            .collect();
        if figures {
            v.extend(["judge_slices.png", "judge_errors.png"].map(|f| dir.join(f)));
        }
        v
    }

    /// Writes the report, table, points and (with `figures`) the figures into `dir`
    /// (created if missing), each atomically.
    pub fn write(&self, dir: &Path, figures: bool) -> Result<(), JudgeError> {
        std::fs::create_dir_all(dir)
            .map_err(|e| invalid!("creating output directory {}: {e}", dir.display()))?;
        let report = self.report();
        let json = serde_json::to_string_pretty(&report.json())?;
        plot::write_atomic(&dir.join("judge.json"), json.as_bytes())?;
        plot::write_atomic(&dir.join("judge_table.md"), report.markdown().as_bytes())?;
        plot::write_atomic(&dir.join("judge_points.csv"), report.csv().as_bytes())?;
        if figures {
            report.plots(dir)?;
        }
        Ok(())
    }
}
