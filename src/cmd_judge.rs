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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use brdf::wave::{GhsFull, GhsOptions, TabulatedPsd};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};
use fit::explicit_brdf::{AngularWindow, Estimate, ExplicitBrdf, TileOptions, Validity};
use fit::io::{Format, ReadOptions};
use fit::pipeline::{self, Analysis, Options};
use fit::two_scale::{BetaSource, TwoScale as Split};
use plot::{Axis, ImageGrid, Legend, LineStyle, Marker, Plot, Rgb, Series};
use serde_json::{Map, Value, json};

use crate::cmd_fit::ScanArgs;
use crate::models::{self, ModelSpec};

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
const REFERENCE_LAMBDA_NM: f64 = models::REFERENCE_LAMBDA_NM;
/// Log-spaced points of the denoised measured-PSD table.
const PSD_NODES: usize = 120;

/// A built model of the scan: one row of the report.
struct Candidate {
    /// Model family (`ggx`, `ggx_kc`, `ghs`, `measured_psd`, `two_scale`, …).
    model: String,
    /// Unique key (`two_scale_100`, …).
    key: String,
    label: String,
    assumes: &'static str,
    /// Parameters in the `brdf eval` vocabulary (µm), plus provenance fields.
    params: Map<String, Value>,
    bxdf: Box<dyn Bxdf>,
}

/// What the recipes build from.
struct Fitted<'a> {
    analysis: &'a Analysis,
    /// Two-scale splits by cutoff multiple (errors kept as text).
    splits: Vec<(f64, Result<Split, String>)>,
    fresnel: String,
}

type Built = Result<Candidate, (String, String)>;

/// One entry of the model table: the family, what it assumes, and how to fit it from the
/// scan. (A typed `brdf::spec::ModelSpec` can replace the `params` maps later; the table
/// stays the list of rows.)
struct Recipe {
    model: &'static str,
    assumes: &'static str,
    make: fn(&Fitted, &[f64]) -> Vec<Built>,
}

const RECIPES: [Recipe; 7] = [
    Recipe {
        model: "ggx",
        assumes: "geometric optics, GGX slope distribution fitted to the measured NDF",
        make: make_ggx,
    },
    Recipe {
        model: "beckmann",
        assumes: "geometric optics, Beckmann slope distribution fitted to the measured NDF",
        make: make_beckmann,
    },
    Recipe {
        model: "ggx_kc",
        assumes: "GGX with α from the KC fit by the GGX ≡ KC identity (α = 1/(2kLc), 550 nm)",
        make: make_ggx_kc,
    },
    Recipe {
        model: "ghs_ssa",
        assumes: "Gaussian heights, KC spectrum, smooth-surface (first-order) lobe",
        make: make_ghs_ssa,
    },
    Recipe {
        model: "ghs",
        assumes: "Gaussian heights, KC spectrum, all orders",
        make: make_ghs,
    },
    Recipe {
        model: "measured_psd",
        assumes: "Gaussian heights, measured isotropic PSD, all orders",
        make: make_measured_psd,
    },
    Recipe {
        model: "two_scale",
        assumes: "exponential NDF above the cutoff period, KC diffraction below it",
        make: make_two_scale,
    },
];

fn spec(fields: Value, label: String) -> ModelSpec {
    ModelSpec {
        label,
        fields: fields.as_object().cloned().unwrap_or_default(),
    }
}

fn candidate(model: &str, key: String, assumes: &'static str, s: ModelSpec) -> Built {
    match s.build() {
        Ok(bxdf) => Ok(Candidate {
            model: model.into(),
            key,
            label: s.label.clone(),
            assumes,
            params: s.fields,
            bxdf,
        }),
        Err(e) => Err((s.label, format!("{e:#}"))),
    }
}

fn make_ggx(f: &Fitted, _: &[f64]) -> Vec<Built> {
    let a = f.analysis.ndf.alpha_ggx.0;
    vec![candidate(
        "ggx",
        "ggx".into(),
        RECIPES[0].assumes,
        spec(
            json!({"model": "ggx", "alpha": a, "fresnel": f.fresnel}),
            format!("GGX, NDF fit (α {})", models::short(a)),
        ),
    )]
}

fn make_beckmann(f: &Fitted, _: &[f64]) -> Vec<Built> {
    let a = f.analysis.ndf.alpha_beckmann.0;
    vec![candidate(
        "beckmann",
        "beckmann".into(),
        RECIPES[1].assumes,
        spec(
            json!({"model": "beckmann", "alpha": a, "fresnel": f.fresnel}),
            format!("Beckmann, NDF fit (α {})", models::short(a)),
        ),
    )]
}

/// The KC fit in µm, or why it cannot be used.
fn kc_um(f: &Fitted) -> Result<(f64, f64, f64), String> {
    let k = &f.analysis.kc;
    if k.degenerate {
        return Err(format!(
            "the K-correlation fit is degenerate (γ {:.3}); see `lustre fit`",
            k.params.gamma
        ));
    }
    Ok((k.params.sigma * 1e6, k.params.lc * 1e6, k.params.gamma))
}

fn make_ggx_kc(f: &Fitted, _: &[f64]) -> Vec<Built> {
    let label = "GGX ≡ KC identity".to_string();
    let (_, lc, _) = match kc_um(f) {
        Ok(v) => v,
        Err(e) => return vec![Err((label, e))],
    };
    let a = match models::ggx_alpha(lc, REFERENCE_LAMBDA_NM) {
        Ok(a) => a,
        Err(e) => return vec![Err((label, format!("{e:#}")))],
    };
    let mut s = spec(
        json!({"model": "ggx", "alpha": a, "fresnel": f.fresnel}),
        format!("GGX ≡ KC (α {} = 1/(2kLc))", models::short(a)),
    );
    s.fields.insert("lc_um".into(), json!(lc));
    vec![candidate("ggx_kc", "ggx_kc".into(), RECIPES[2].assumes, s)]
}

fn kc_fields(model: &str, f: &Fitted) -> Result<Value, String> {
    let (s, l, g) = kc_um(f)?;
    Ok(
        json!({"model": model, "sigma_um": s, "lc_um": l, "gamma": g,
              "energy": "raw", "fresnel": f.fresnel}),
    )
}

fn make_ghs_ssa(f: &Fitted, _: &[f64]) -> Vec<Built> {
    match kc_fields("ghs_ssa", f) {
        Ok(v) => vec![candidate(
            "ghs_ssa",
            "ghs_ssa".into(),
            RECIPES[3].assumes,
            spec(v, "GHS SSA, KC fit".into()),
        )],
        Err(e) => vec![Err(("GHS SSA".into(), e))],
    }
}

fn make_ghs(f: &Fitted, _: &[f64]) -> Vec<Built> {
    match kc_fields("ghs", f) {
        Ok(v) => vec![candidate(
            "ghs",
            "ghs".into(),
            RECIPES[4].assumes,
            spec(v, "full GHS, KC fit".into()),
        )],
        Err(e) => vec![Err(("full GHS".into(), e))],
    }
}

/// The `[psd]` table of `lustre fit` in µm units, denoised for `TabulatedPsd`: ln P averaged
/// over ±0.05 decades of ζ and resampled to at most [`PSD_NODES`] log-spaced points (a
/// periodogram's bins scatter by ±100 %, and a converted profile PSD has local slopes of
/// ±1000, which the Hankel transform of the table does not survive), plus a power-law tail:
/// `TabulatedPsd` extends a table by its last segment, so the exponent is set to the
/// least-squares slope of the top third of the table, clamped to [−8, −2.5] (finite σ; no
/// scan here resolves a steeper tail), carried by one extra point at 1.5× the last
/// frequency. Returns the table, the tail exponent and whether it was clamped.
fn measured_table(a: &Analysis) -> Result<(TabulatedPsd, f64, bool), String> {
    let pts: Vec<(f64, f64)> = a
        .table
        .0
        .zeta
        .iter()
        .zip(&a.table.0.p)
        .filter(|(z, p)| z.is_finite() && **z > 0.0 && p.is_finite() && **p > 0.0)
        .map(|(z, p)| ((z * 1e-6).ln(), (p * 1e24).ln()))
        .collect();
    if pts.len() < 8 {
        return Err(format!(
            "the measured PSD has only {} usable points",
            pts.len()
        ));
    }
    let (lo, hi) = (pts[0].0, pts[pts.len() - 1].0);
    let half = 0.05 * std::f64::consts::LN_10;
    let nodes = PSD_NODES.min(pts.len());
    let mut lz = Vec::with_capacity(nodes);
    let mut lp = Vec::with_capacity(nodes);
    for j in 0..nodes {
        let x = lo + (hi - lo) * j as f64 / (nodes - 1) as f64;
        let (mut s, mut n, mut sx) = (0.0, 0usize, 0.0);
        for &(zx, py) in pts.iter().filter(|(zx, _)| (zx - x).abs() <= half) {
            s += py;
            sx += zx;
            n += 1;
        }
        if n > 0 && lz.last().is_none_or(|l: &f64| sx / (n as f64) > *l + 1e-9) {
            lz.push(sx / n as f64);
            lp.push(s / n as f64);
        }
    }
    let n = lz.len();
    if n < 8 {
        return Err(format!(
            "the measured PSD has only {n} distinct frequencies"
        ));
    }
    let (tx, ty) = (&lz[2 * n / 3..], &lp[2 * n / 3..]);
    let mx = tx.iter().sum::<f64>() / tx.len() as f64;
    let my = ty.iter().sum::<f64>() / ty.len() as f64;
    let sxx: f64 = tx.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = tx.iter().zip(ty).map(|(x, y)| (x - mx) * (y - my)).sum();
    let fitted = sxy / sxx;
    let slope = fitted.clamp(-8.0, -2.5);
    let mut z: Vec<f64> = lz.iter().map(|v| v.exp()).collect();
    let mut p: Vec<f64> = lp.iter().map(|v| v.exp()).collect();
    let (zl, pl) = (z[n - 1], p[n - 1]);
    z.push(1.5 * zl);
    p.push(pl * 1.5f64.powf(slope));
    TabulatedPsd::new(&z, &p)
        .map(|t| (t, slope, slope != fitted))
        .map_err(|e| format!("measured PSD table: {e}"))
}

fn make_measured_psd(f: &Fitted, _: &[f64]) -> Vec<Built> {
    let label = "full GHS, measured PSD".to_string();
    let (table, tail, clamped) = match measured_table(f.analysis) {
        Ok(v) => v,
        Err(e) => return vec![Err((label, e))],
    };
    let fresnel = match fresnel_of(&f.fresnel) {
        Ok(fr) => fr,
        Err(e) => return vec![Err((label, format!("{e:#}")))],
    };
    let sigma = table.sigma_um();
    match GhsFull::with_options(table, fresnel, GhsOptions::default()) {
        Ok(m) => {
            let params = json!({"model": "measured_psd", "fresnel": f.fresnel,
                "psd_source": f.analysis.table.1, "psd_points": f.analysis.table.0.zeta.len(),
                "psd_tail_exponent": tail, "psd_tail_exponent_clamped": clamped,
                "sigma_um": sigma, "energy": "raw"});
            vec![Ok(Candidate {
                model: "measured_psd".into(),
                key: "measured_psd".into(),
                label,
                assumes: RECIPES[5].assumes,
                params: params.as_object().cloned().unwrap_or_default(),
                bxdf: Box::new(m),
            })]
        }
        Err(e) => vec![Err((label, e.to_string()))],
    }
}

fn two_scale_candidate(f: &Fitted, m: f64) -> Built {
    let label = format!("two-scale {m}λ");
    let split = match f.splits.iter().find(|(c, _)| *c == m) {
        Some((_, Ok(s))) => s,
        Some((_, Err(e))) => return Err((label, e.clone())),
        None => return Err((label, "split not computed".into())),
    };
    if split.beta_source == BetaSource::Unresolved || split.beta <= 0.0 {
        return Err((
            label,
            "the map is too small for this cutoff period and no PSD below it".into(),
        ));
    }
    if split.kc.degenerate {
        return Err((label, "the residual K-correlation fit is degenerate".into()));
    }
    let k = split.kc.params;
    let mut s = spec(
        json!({"model": "two_scale", "beta": split.beta, "sigma_um": k.sigma * 1e6,
               "lc_um": k.lc * 1e6, "gamma": k.gamma, "fresnel": f.fresnel}),
        format!("two-scale {m}λ (β {})", models::short(split.beta)),
    );
    s.fields
        .insert("cutoff_um".into(), json!(split.cutoff * 1e6));
    s.fields.insert("cutoff_multiple".into(), json!(m));
    candidate("two_scale", format!("two_scale_{m}"), RECIPES[6].assumes, s)
}

fn make_two_scale(f: &Fitted, cutoffs: &[f64]) -> Vec<Built> {
    cutoffs.iter().map(|&m| two_scale_candidate(f, m)).collect()
}

fn fresnel_of(name: &str) -> anyhow::Result<Fresnel> {
    if name == "none" {
        return Ok(Fresnel::One);
    }
    let metal = Metal::from_name(name).ok_or_else(|| {
        anyhow!("--metal {name}: unknown; use cu, au, ag, al, fe, cr, brass or stainless_steel")
    })?;
    Ok(Fresnel::conductor(Ior::metal(metal)))
}

/// Rejects a model whose directional albedo (hemispherical integral of the glossy part plus
/// the specular weight, R as given) is not finite or exceeds 2 at any requested (θi, λ): raw
/// GHS may exceed 1 a little at grazing incidence (physics.md §5), nothing physical exceeds 2.
/// This catches tables a model could not build faithfully (e.g. the full-GHS table of a
/// measured PSD with steep segments at large g) instead of ranking nonsense.
fn energy_check(c: Candidate, args: &JudgeArgs) -> Built {
    for &t in &args.theta_i {
        for &l in &args.lambda {
            let wi = brdf::frame::spherical(t.to_radians(), 0.0);
            let a = brdf::wave::energy::hemispherical_integral(wi, 0.05, |o| c.bxdf.eval(wi, o, l))
                + c.bxdf.specular(wi, l).weight;
            if !(a.is_finite() && a <= 2.0) {
                return Err((
                    c.label,
                    format!(
                        "fails the energy check: directional albedo {a:.3e} at θi {t}°, {l} nm \
                         (the model's table is not faithful for these parameters)"
                    ),
                ));
            }
        }
    }
    Ok(c)
}

/// Which slice a direction belongs to.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum SliceKind {
    InPlane,
    CrossPlane,
}

/// One evaluated direction.
struct Point {
    kind: SliceKind,
    /// Signed θo [deg] (in-plane, > 0 on the specular side) or o_y (cross-plane).
    coord: f64,
    wo: [f64; 3],
    explicit: Estimate,
    surrogate: Option<f64>,
    validity: Validity,
}

/// Everything computed for one (θi, λ).
struct AngleSet {
    theta_i: f64,
    lambda_nm: f64,
    wi: [f64; 3],
    window: AngularWindow,
    coherent: Estimate,
    points: Vec<Point>,
    floor: f64,
}

/// In-plane exits: half uniform in signed θo over ±88°, half at geometric offsets from
/// the mirror direction (resolution … 1 in direction cosine).
fn in_plane_dirs(theta_i: f64, n: usize, res: f64) -> Vec<(f64, [f64; 3])> {
    let s_max = 88f64.to_radians().sin();
    let mirror = -theta_i.to_radians().sin();
    let mut ox: Vec<f64> = Vec::new();
    let n_uni = (n / 2).max(2);
    for j in 0..n_uni {
        let t = (-88.0 + 176.0 * j as f64 / (n_uni - 1) as f64).to_radians();
        ox.push(-t.sin());
    }
    let n_side = ((n - n / 2) / 2).max(1);
    let lo = res.max(1e-5);
    for j in 0..n_side {
        let d = lo * (1.0 / lo).powf(j as f64 / (n_side.max(2) - 1) as f64);
        ox.extend([mirror - d, mirror + d]);
    }
    ox.retain(|v| v.abs() <= s_max);
    ox.sort_by(|a, b| b.total_cmp(a));
    ox.dedup();
    ox.iter()
        .map(|&x| ((-x).asin().to_degrees(), [x, 0.0, (1.0 - x * x).sqrt()]))
        .collect()
}

/// Cross-plane exits through the mirror direction: o = (−sinθi, o_y, ·).
fn cross_plane_dirs(theta_i: f64, n: usize, res: f64) -> Vec<(f64, [f64; 3])> {
    let sx = -theta_i.to_radians().sin();
    let y_max = (1.0 - sx * sx).sqrt() * 88f64.to_radians().sin();
    let mut oy: Vec<f64> = Vec::new();
    let n_uni = (n / 2).max(2);
    for j in 0..n_uni {
        oy.push(-y_max + 2.0 * y_max * j as f64 / (n_uni - 1) as f64);
    }
    let n_side = ((n - n / 2) / 2).max(1);
    let lo = res.max(1e-5);
    for j in 0..n_side {
        let d = lo * (y_max / lo).powf(j as f64 / (n_side.max(2) - 1) as f64);
        oy.extend([-d, d]);
    }
    oy.retain(|v| v.abs() <= y_max);
    oy.sort_by(f64::total_cmp);
    oy.dedup();
    oy.iter()
        .map(|&y| (y, [sx, y, (1.0 - sx * sx - y * y).max(0.0).sqrt()]))
        .collect()
}

/// cosθd = i·h = sqrt((1 + i·o)/2), the Fresnel angle of the scattered part.
fn cos_d(wi: [f64; 3], wo: [f64; 3]) -> f64 {
    (0.5 * (1.0 + wi[0] * wo[0] + wi[1] * wo[1] + wi[2] * wo[2]))
        .max(0.0)
        .sqrt()
}

fn dvec(v: [f64; 3]) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

/// `f` integrated over the out-of-plane direction cosine at in-plane `ox` (profiles):
/// 2∫₀^Y f do_y (isotropic models are even in o_y when i is in the x–z plane), on geometric
/// panels from 1e−5·Y with 4-point Gauss–Legendre.
fn marginal(m: &dyn Bxdf, wi: DVec3, ox: f64, lambda_nm: f64) -> f64 {
    let y_max = (1.0 - ox * ox).max(0.0).sqrt();
    if y_max <= 0.0 {
        return 0.0;
    }
    let (x, w) = brdf::wave::hankel::gauss_legendre::<2>();
    let mut edges = vec![0.0];
    let mut e = 1e-5 * y_max;
    while e < y_max {
        edges.push(e);
        e *= 2.0;
    }
    edges.push(y_max);
    let mut s = 0.0;
    for p in edges.windows(2) {
        let (a, b) = (p[0], p[1]);
        let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
        for (xi, wi_) in x.iter().zip(&w) {
            for oy in [c - h * xi, c + h * xi] {
                let oz2 = 1.0 - ox * ox - oy * oy;
                if oz2 > 0.0 {
                    s += wi_ * h * m.eval(wi, DVec3::new(ox, oy, oz2.sqrt()), lambda_nm);
                }
            }
        }
    }
    2.0 * s
}

/// A model value as the explicit estimate sees it: smoothed by the tile kernel (`nodes`, ξ in
/// rad/m, k in rad/m), and for profiles integrated over o_y.
fn model_value(
    m: &dyn Bxdf,
    wi: [f64; 3],
    wo: [f64; 3],
    lambda_nm: f64,
    k: f64,
    nodes: &[(f64, f64, f64)],
    profile: bool,
) -> f64 {
    let wi_v = dvec(wi);
    let mut s = 0.0;
    for &(xx, xy, w) in nodes {
        let ox = wo[0] + xx / k;
        if profile {
            if ox.abs() < 1.0 {
                s += w * marginal(m, wi_v, ox, lambda_nm);
            }
            continue;
        }
        let oy = wo[1] + xy / k;
        let r2 = ox * ox + oy * oy;
        if r2 < 1.0 {
            s += w * m.eval(wi_v, DVec3::new(ox, oy, (1.0 - r2).sqrt()), lambda_nm);
        }
    }
    s
}

/// The part of an rms log error not explained by `noise` (both rms, in quadrature).
fn excess(rms: f64, noise: f64) -> f64 {
    if rms.is_finite() && noise.is_finite() {
        (rms * rms - noise * noise).max(0.0).sqrt()
    } else {
        f64::NAN
    }
}

fn ln10_floor(v: f64, floor: f64) -> f64 {
    v.max(floor).log10()
}

/// Log-space comparison of one model with the explicit reference over the valid points.
#[derive(Clone, Debug, Default)]
struct Score {
    sum2: f64,
    n: usize,
}

impl Score {
    fn add(&mut self, d: f64) {
        self.sum2 += d * d;
        self.n += 1;
    }
    fn merge(&mut self, o: &Score) {
        self.sum2 += o.sum2;
        self.n += o.n;
    }
    fn rms(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            (self.sum2 / self.n as f64).sqrt()
        }
    }
}

fn score_model(set: &AngleSet, values: &[f64]) -> Score {
    let mut s = Score::default();
    for (p, v) in set.points.iter().zip(values) {
        if p.validity == Validity::Valid {
            s.add(ln10_floor(*v, set.floor) - ln10_floor(p.explicit.value, set.floor));
        }
    }
    s
}

/// Model values at every point of every angle set.
fn evaluate(
    c: &Candidate,
    sets: &[AngleSet],
    nodes: &[(f64, f64, f64)],
    profile: bool,
) -> Vec<Vec<f64>> {
    sets.iter()
        .map(|set| {
            let k = 2.0 * std::f64::consts::PI / (set.lambda_nm * 1e-9);
            set.points
                .iter()
                .map(|p| {
                    model_value(
                        c.bxdf.as_ref(),
                        set.wi,
                        p.wo,
                        set.lambda_nm,
                        k,
                        nodes,
                        profile,
                    )
                })
                .collect()
        })
        .collect()
}

/// A judged model: the candidate, its values and its scores.
struct Judged {
    c: Candidate,
    values: Vec<Vec<f64>>,
    per_angle: Vec<Score>,
    overall: Score,
}

fn judge(c: Candidate, sets: &[AngleSet], nodes: &[(f64, f64, f64)], profile: bool) -> Judged {
    let values = evaluate(&c, sets, nodes, profile);
    let per_angle: Vec<Score> = sets
        .iter()
        .zip(&values)
        .map(|(s, v)| score_model(s, v))
        .collect();
    let mut overall = Score::default();
    for s in &per_angle {
        overall.merge(s);
    }
    Judged {
        c,
        values,
        per_angle,
        overall,
    }
}

fn read_options(a: &ScanArgs) -> anyhow::Result<ReadOptions> {
    let units = match &a.units {
        Some(u) => Some(
            fit::io::units::length_factor(u)
                .with_context(|| format!("--units {u}: not a length unit (use m, mm, um, nm)"))?,
        ),
        None => None,
    };
    let format = match &a.format {
        Some(f) => Some(Format::from_name(f).with_context(|| {
            format!("--format {f}: unknown (use x3p, bcr, sdf, di, matrix, gsf, dektak, xyz)")
        })?),
        None => None,
    };
    Ok(ReadOptions {
        channel: a.channel,
        units,
        format,
    })
}

fn check_args(args: &JudgeArgs) -> anyhow::Result<()> {
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    if args.lambda.is_empty() || args.theta_i.is_empty() {
        bail!("--lambda and --theta-i each need at least one value");
    }
    for &l in &args.lambda {
        if !(lo..=hi).contains(&l) {
            bail!("--lambda {l}: must lie in {lo}–{hi} nm");
        }
    }
    for &t in &args.theta_i {
        if !(0.0..89.0).contains(&t) {
            bail!("--theta-i {t}: must lie in [0, 89) degrees");
        }
    }
    for &c in &args.cutoff {
        if !(c.is_finite() && c > 0.0) {
            bail!("--cutoff {c}: must be a positive multiple of 550 nm");
        }
    }
    if args.angles < 8 {
        bail!("--angles {}: need at least 8", args.angles);
    }
    if let Some(t) = args.tile
        && t < 8
    {
        bail!("--tile {t}: need at least 8 pixels");
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
    let bytes = std::fs::read(&args.scan)
        .with_context(|| format!("cannot read {}", args.scan.display()))?;
    let topo = fit::io::read_bytes(
        &args.scan.display().to_string(),
        &bytes,
        &read_options(&args.read)?,
    )?;
    let opts = Options {
        cutoff_multiples: Vec::new(),
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
    let fitted = Fitted {
        analysis: &analysis,
        splits,
        fresnel: fresnel_name.clone(),
    };

    // The explicit reference (and its Gaussian surrogate).
    let tiles = TileOptions {
        size: args.tile,
        ..TileOptions::default()
    };
    let explicit = ExplicitBrdf::new(&analysis.scan, &tiles)?;
    let surrogate = if args.no_surrogate {
        None
    } else {
        let s = fit::surrogate::gaussian_surrogate(&analysis.scan, 0x5eed)?;
        Some(ExplicitBrdf::new(&s, &tiles)?)
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
            models::short(
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

fn angle_set(
    e: &ExplicitBrdf,
    surrogate: Option<&ExplicitBrdf>,
    fresnel: &Fresnel,
    theta_i: f64,
    lambda_nm: f64,
    n: usize,
) -> AngleSet {
    let lambda = lambda_nm * 1e-9;
    let t = theta_i.to_radians();
    let wi = [t.sin(), 0.0, t.cos()];
    let window = e.angular_window(wi, lambda);
    let mut dirs: Vec<(SliceKind, f64, [f64; 3])> = in_plane_dirs(theta_i, n, window.resolution)
        .into_iter()
        .map(|(c, w)| (SliceKind::InPlane, c, w))
        .collect();
    if !e.is_profile() {
        dirs.extend(
            cross_plane_dirs(theta_i, n / 2, window.resolution)
                .into_iter()
                .map(|(c, w)| (SliceKind::CrossPlane, c, w)),
        );
    }
    let wos: Vec<[f64; 3]> = dirs.iter().map(|d| d.2).collect();
    let raw = e.scattered_many(wi, &wos, lambda);
    let sur = surrogate.map(|s| s.scattered_many(wi, &wos, lambda));
    let mut points = Vec::with_capacity(dirs.len());
    for (j, (kind, coord, wo)) in dirs.into_iter().enumerate() {
        let spectrum = raw[j].value
            / if e.is_profile() {
                2.0 * std::f64::consts::PI / lambda
            } else {
                (2.0 * std::f64::consts::PI / lambda).powi(2)
            };
        let validity = window.classify(wi, wo, spectrum);
        let r = fresnel.reflectance(cos_d(wi, wo), lambda_nm);
        points.push(Point {
            kind,
            coord,
            wo,
            explicit: Estimate {
                value: raw[j].value * r,
                se: raw[j].se * r,
                n: raw[j].n,
            },
            surrogate: sur.as_ref().map(|s| s[j].value * r),
            validity,
        });
    }
    let c = e.coherent(wi, lambda);
    let rs = fresnel.reflectance(wi[2], lambda_nm);
    let top = points
        .iter()
        .filter(|p| p.validity == Validity::Valid)
        .map(|p| p.explicit.value)
        .fold(0.0, f64::max);
    AngleSet {
        theta_i,
        lambda_nm,
        wi,
        window,
        coherent: Estimate {
            value: c.value * rs,
            se: c.se * rs,
            n: c.n,
        },
        points,
        floor: LOG_FLOOR * if top > 0.0 { top } else { 1.0 },
    }
}

/// The comparison against a measured BRDF file.
struct ReferenceResult {
    file: String,
    rows: usize,
    skipped_rows: usize,
    /// (key, label, score); the explicit BRDF of the scan as key "explicit".
    scores: Vec<(String, String, Score)>,
}

fn judge_reference(
    path: &Path,
    judged: &[Judged],
    e: &ExplicitBrdf,
    fresnel: &Fresnel,
) -> anyhow::Result<ReferenceResult> {
    let rows = read_reference(path)?;
    let usable: Vec<&[f64; 5]> = rows.iter().filter(|r| r[4] > 0.0).collect();
    if usable.is_empty() {
        bail!(
            "{}: no row with a positive brdf value to compare in log space",
            path.display()
        );
    }
    let mut scores: Vec<(String, String, Score)> = judged
        .iter()
        .map(|j| (j.c.key.clone(), j.c.label.clone(), Score::default()))
        .collect();
    let mut ex = Score::default();
    for r in &usable {
        let (ti, to, po, lam, f) = (
            r[0].to_radians(),
            r[1].to_radians(),
            r[2].to_radians(),
            r[3],
            r[4],
        );
        let wi = [ti.sin(), 0.0, ti.cos()];
        let wo = [to.sin() * po.cos(), to.sin() * po.sin(), to.cos()];
        let lf = f.log10();
        for (j, s) in judged.iter().zip(scores.iter_mut()) {
            let v = j.c.bxdf.eval(dvec(wi), dvec(wo), lam);
            s.2.add(ln10_floor(v, f * LOG_FLOOR) - lf);
        }
        let w = e.angular_window(wi, lam * 1e-9);
        let est = e.scattered(wi, wo, lam * 1e-9);
        let k = 2.0 * std::f64::consts::PI / (lam * 1e-9);
        let spec = est.value / if e.is_profile() { k } else { k * k };
        if !e.is_profile() && w.classify(wi, wo, spec) == Validity::Valid {
            let v = est.value * fresnel.reflectance(cos_d(wi, wo), lam);
            ex.add(ln10_floor(v, f * LOG_FLOOR) - lf);
        }
    }
    scores.push((
        "explicit".into(),
        "explicit BRDF of the scan (inside its window)".into(),
        ex,
    ));
    scores.sort_by(|a, b| {
        let (x, y) = (a.2.rms(), b.2.rms());
        x.is_nan().cmp(&y.is_nan()).then(x.total_cmp(&y))
    });
    Ok(ReferenceResult {
        file: path.display().to_string(),
        rows: rows.len(),
        skipped_rows: rows.len() - usable.len(),
        scores,
    })
}

/// Rows `[θi, θo, φo, λ, brdf]` of a reference CSV.
fn read_reference(path: &Path) -> anyhow::Result<Vec<[f64; 5]>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the reference {}", path.display()))?;
    let names = [
        "theta_i_deg",
        "theta_o_deg",
        "phi_o_deg",
        "lambda_nm",
        "brdf",
    ];
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (hline, header) = lines
        .next()
        .ok_or_else(|| anyhow!("{}: empty file", path.display()))?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_ascii_lowercase())
        .collect();
    let mut idx = [0usize; 5];
    for (i, n) in names.iter().enumerate() {
        idx[i] = cols.iter().position(|c| c == n).ok_or_else(|| {
            anyhow!(
                "{}:{}: header has no column `{n}` (need {}; got {})",
                path.display(),
                hline + 1,
                names.join(", "),
                cols.join(", ")
            )
        })?;
    }
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    let mut rows = Vec::new();
    for (ln, line) in lines {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let mut r = [0.0; 5];
        for (i, &c) in idx.iter().enumerate() {
            let s = f.get(c).copied().unwrap_or("");
            r[i] = s
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    anyhow!(
                        "{}:{}: column `{}` = {s:?} is not a finite number",
                        path.display(),
                        ln + 1,
                        names[i]
                    )
                })?;
        }
        let bad = |what: &str| anyhow!("{}:{}: {what}", path.display(), ln + 1);
        if !(0.0..90.0).contains(&r[0]) || !(0.0..90.0).contains(&r[1]) {
            return Err(bad("theta_i_deg and theta_o_deg must lie in [0, 90)"));
        }
        if !(lo..=hi).contains(&r[3]) {
            return Err(bad(&format!("lambda_nm must lie in {lo}–{hi} nm")));
        }
        if r[4] < 0.0 {
            return Err(bad("brdf must not be negative"));
        }
        rows.push(r);
    }
    if rows.is_empty() {
        bail!("{}: no data rows after the header", path.display());
    }
    Ok(rows)
}

/// Everything the outputs are made from.
struct Report<'a> {
    args: &'a JudgeArgs,
    analysis: &'a Analysis,
    explicit: &'a ExplicitBrdf,
    sets: &'a [AngleSet],
    judged: &'a [Judged],
    skipped: &'a [(String, String)],
    reference: Option<&'a ReferenceResult>,
    fresnel: &'a str,
}

fn num(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

impl Report<'_> {
    fn valid_counts(set: &AngleSet) -> Map<String, Value> {
        let mut m = Map::new();
        for v in [
            Validity::Valid,
            Validity::NearSpecular,
            Validity::BeyondNyquist,
            Validity::Aliased,
            Validity::Shadowed,
            Validity::BelowHorizon,
        ] {
            let n = set.points.iter().filter(|p| p.validity == v).count();
            m.insert(v.name().into(), json!(n));
        }
        m
    }

    /// rms of the explicit estimate's own log10 standard error over the valid points.
    fn noise(&self) -> (f64, Vec<f64>) {
        let (mut all, mut n_all) = (0.0, 0usize);
        let per = self
            .sets
            .iter()
            .map(|s| {
                let (mut a, mut n) = (0.0, 0usize);
                for p in s.points.iter().filter(|p| p.validity == Validity::Valid) {
                    let r = std::f64::consts::LOG10_E * p.explicit.relative_se().min(10.0);
                    a += r * r;
                    n += 1;
                }
                all += a;
                n_all += n;
                if n > 0 {
                    (a / n as f64).sqrt()
                } else {
                    f64::NAN
                }
            })
            .collect();
        let overall = if n_all > 0 {
            (all / n_all as f64).sqrt()
        } else {
            f64::NAN
        };
        (overall, per)
    }

    /// rms log10 distance of the Gaussian surrogate's explicit BRDF from the map's.
    fn surrogate_score(&self) -> Option<(Score, Vec<Score>)> {
        self.sets.first()?.points.first()?.surrogate?;
        let mut all = Score::default();
        let per = self
            .sets
            .iter()
            .map(|s| {
                let mut sc = Score::default();
                for p in s.points.iter().filter(|p| p.validity == Validity::Valid) {
                    if let Some(v) = p.surrogate {
                        sc.add(ln10_floor(v, s.floor) - ln10_floor(p.explicit.value, s.floor));
                    }
                }
                all.merge(&sc);
                sc
            })
            .collect();
        Some((all, per))
    }

    fn find(&self, key: &str) -> Option<&Judged> {
        self.judged.iter().find(|j| j.c.key == key)
    }

    /// (assumption, from, to, Δ of the log10 error in excess of the reference's noise).
    fn costs(&self) -> Vec<(String, String, String, f64)> {
        let mut out = Vec::new();
        let (noise, _) = self.noise();
        if let Some((s, _)) = self.surrogate_score() {
            // Both sides of this comparison carry the tile noise.
            out.push((
                "Gaussian heights (explicit BRDF of a Gaussian surrogate with the map's spectrum)"
                    .to_string(),
                "explicit".to_string(),
                "surrogate".to_string(),
                excess(s.rms(), std::f64::consts::SQRT_2 * noise),
            ));
        }
        let pairs = [
            (
                "K-correlation shape instead of the measured PSD",
                "measured_psd",
                "ghs",
            ),
            (
                "first-order (SSA) lobe instead of all orders",
                "ghs",
                "ghs_ssa",
            ),
            (
                "two-scale split (best cutoff) instead of one KC spectrum",
                "ghs",
                "two_scale_best",
            ),
            ("microfacet GGX (NDF fit) instead of full GHS", "ghs", "ggx"),
        ];
        for (what, a, b) in pairs {
            if let (Some(x), Some(y)) = (self.find(a), self.find(b)) {
                out.push((
                    what.to_string(),
                    a.to_string(),
                    b.to_string(),
                    excess(y.overall.rms(), noise) - excess(x.overall.rms(), noise),
                ));
            }
        }
        out
    }

    fn json(&self) -> Value {
        let e = self.explicit;
        let (noise, noise_per) = self.noise();
        let windows: Vec<Value> = self
            .sets
            .iter()
            .map(|s| {
                let w = &s.window;
                json!({
                    "theta_i_deg": s.theta_i, "lambda_nm": s.lambda_nm,
                    "resolution_dsin": w.resolution,
                    "nyquist_dsin": [w.nyquist.0, w.nyquist.1],
                    "max_dsin": [w.max_offset.0, w.max_offset.1],
                    "alias_floor": num(w.alias_floor),
                    "phase_step_rad": w.phase_step,
                    "smith_g1_incidence": w.g1_incidence,
                    "points": s.points.len(),
                    "by_validity": Value::Object(Self::valid_counts(s)),
                    "coherent_explicit": num(s.coherent.value),
                    "coherent_explicit_se": num(s.coherent.se),
                })
            })
            .collect();
        let models: Vec<Value> = self
            .judged
            .iter()
            .map(|j| {
                let per: Vec<Value> = self
                    .sets
                    .iter()
                    .zip(&j.per_angle)
                    .map(|(s, sc)| {
                        let spec = j.c.bxdf.specular(dvec(s.wi), s.lambda_nm).weight;
                        json!({"theta_i_deg": s.theta_i, "lambda_nm": s.lambda_nm,
                               "log10_rms_error": num(sc.rms()), "points": sc.n,
                               "specular_weight": num(spec),
                               "coherent_explicit": num(s.coherent.value)})
                    })
                    .collect();
                json!({
                    "model": j.c.model, "key": j.c.key, "label": j.c.label,
                    "assumes": j.c.assumes,
                    "log10_rms_error": num(j.overall.rms()),
                    "log10_excess_over_noise": num(excess(j.overall.rms(), noise)),
                    "points": j.overall.n,
                    "params": Value::Object(j.c.params.clone()),
                    "per_angle": per,
                })
            })
            .collect();
        let skipped: Vec<Value> = self
            .skipped
            .iter()
            .map(|(l, r)| json!({"label": l, "reason": r}))
            .collect();
        let costs: Vec<Value> = self
            .costs()
            .into_iter()
            .map(|(a, f, t, d)| json!({"assumption": a, "from": f, "to": t, "delta_log10_rms": num(d)}))
            .collect();
        let surrogate = self.surrogate_score().map(|(s, per)| {
            json!({"log10_rms_distance": num(s.rms()), "points": s.n,
                   "per_angle": per.iter().map(|x| num(x.rms())).collect::<Vec<_>>()})
        });
        let reference = self.reference.map(|r| {
            json!({"file": r.file, "rows": r.rows, "skipped_rows": r.skipped_rows,
                   "models": r.scores.iter().map(|(k, l, s)| json!({
                       "key": k, "label": l, "log10_rms_error": num(s.rms()), "points": s.n
                   })).collect::<Vec<_>>()})
        });
        let (tx, ty) = e.tile_size();
        let (dx, dy) = e.pixel();
        let a = self.analysis;
        json!({
            "scan": self.args.scan.display().to_string(),
            "grid": [a.scan.nx, a.scan.ny],
            "fresnel": self.fresnel,
            "window": {
                "pixel_um": [dx * 1e6, dy * 1e6],
                "tile_px": [e.tile_pixels().0, e.tile_pixels().1],
                "tile_um": [tx * 1e6, ty * 1e6],
                "tiles": e.tiles(),
                "overlap_variance_factor": e.overlap_factor(),
                "rms_slope": e.rms_slope(),
                "shadowing": "directions with Smith G1(θi)·G1(θo) < 0.9 (Beckmann, α = rms slope) are excluded",
                "per_angle": windows,
                "noise_floor_log10": num(noise),
                "noise_floor_log10_per_angle": noise_per.into_iter().map(num).collect::<Vec<_>>(),
            },
            "models": models,
            "skipped": skipped,
            "gaussian_surrogate": surrogate,
            "assumption_costs_note": "differences of the log10 rms error in excess of the reference's own noise floor (in quadrature); the surrogate row has the noise of both estimates",
            "assumption_costs": costs,
            "reference": reference,
            "fit": {
                "sq_um": a.stats.sq * 1e6, "rms_slope": a.stats.rms_slope(),
                "kc": {"sigma_um": a.kc.params.sigma * 1e6, "lc_um": a.kc.params.lc * 1e6,
                       "gamma": a.kc.params.gamma, "degenerate": a.kc.degenerate},
            },
        })
    }

    fn markdown(&self) -> String {
        let mut s = String::new();
        let e = self.explicit;
        let a = self.analysis;
        let _ = writeln!(
            s,
            "# lustre judge: {}\n\n{} × {} points, pixel {:.4} µm, Sq {:.4} µm, rms slope {:.4}; \
             KC fit σ {:.4} µm, Lc {:.4} µm, γ {:.3}{}; Fresnel: {}.\n\
             Reference: explicit Kirchhoff BRDF of the map, {} tiles of {} × {} px (Hann, 50 % overlap).\n",
            self.args.scan.display(),
            a.scan.nx,
            a.scan.ny,
            a.scan.dx * 1e6,
            a.stats.sq * 1e6,
            a.stats.rms_slope(),
            a.kc.params.sigma * 1e6,
            a.kc.params.lc * 1e6,
            a.kc.params.gamma,
            if a.kc.degenerate { " (degenerate)" } else { "" },
            if self.fresnel == "none" {
                "none (R ≡ 1)"
            } else {
                self.fresnel
            },
            e.tiles(),
            e.tile_pixels().0,
            e.tile_pixels().1
        );
        let _ = writeln!(
            s,
            "## Valid window\n\n| θi | λ nm | resolution Δsinθ | max Δsinθ (x, y) | phase step/px rad | G1(θi) | coherent | valid / points |\n|---|---|---|---|---|---|---|---|"
        );
        for set in self.sets {
            let w = &set.window;
            let valid = set
                .points
                .iter()
                .filter(|p| p.validity == Validity::Valid)
                .count();
            let _ = writeln!(
                s,
                "| {} | {} | {:.2e} | {:.3}, {:.3} | {:.2} | {:.3} | {:.3e} ± {:.1e} | {} / {} |",
                set.theta_i,
                set.lambda_nm,
                w.resolution,
                w.max_offset.0,
                w.max_offset.1,
                w.phase_step,
                w.g1_incidence,
                set.coherent.value,
                set.coherent.se,
                valid,
                set.points.len()
            );
        }
        let (noise, noise_per) = self.noise();
        let _ = write!(
            s,
            "\n## Log10 rms error against the explicit BRDF (best first)\n\n| rank | model | overall | excess over noise |"
        );
        for set in self.sets {
            let _ = write!(s, " {}°/{} |", set.theta_i, set.lambda_nm);
        }
        let _ = write!(s, "\n|---|---|---|---|");
        for _ in self.sets {
            s.push_str("---|");
        }
        s.push('\n');
        let cell = |x: f64| {
            if x.is_finite() {
                format!("{x:.3}")
            } else {
                "–".into()
            }
        };
        for (r, j) in self.judged.iter().enumerate() {
            let _ = write!(
                s,
                "| {} | {} | {} | {} |",
                r + 1,
                j.c.label,
                cell(j.overall.rms()),
                cell(excess(j.overall.rms(), noise))
            );
            for sc in &j.per_angle {
                let _ = write!(s, " {} |", cell(sc.rms()));
            }
            s.push('\n');
        }
        if let Some((sc, per)) = self.surrogate_score() {
            let _ = write!(
                s,
                "| – | Gaussian surrogate (explicit) | {} | {} |",
                cell(sc.rms()),
                cell(excess(sc.rms(), std::f64::consts::SQRT_2 * noise))
            );
            for p in per {
                let _ = write!(s, " {} |", cell(p.rms()));
            }
            s.push('\n');
        }
        let _ = write!(
            s,
            "| – | noise floor of the reference | {} | – |",
            cell(noise)
        );
        for p in noise_per {
            let _ = write!(s, " {} |", cell(p));
        }
        s.push('\n');
        let _ = writeln!(
            s,
            "\n## What each assumption costs (change in the log10 error in excess of the noise)\n\n| assumption | from → to | Δ |\n|---|---|---|"
        );
        for (what, f, t, d) in self.costs() {
            let _ = writeln!(s, "| {what} | {f} → {t} | {} |", cell(d));
        }
        if !self.skipped.is_empty() {
            let _ = writeln!(s, "\nNot judged:\n");
            for (l, r) in self.skipped {
                let _ = writeln!(s, "* {l}: {r}");
            }
        }
        if let Some(r) = self.reference {
            let _ = writeln!(
                s,
                "\n## Against the measured BRDF {} ({} rows, {} without a positive value)\n\n| rank | model | log10 rms error | points |\n|---|---|---|---|",
                r.file, r.rows, r.skipped_rows
            );
            for (i, (_, l, sc)) in r.scores.iter().enumerate() {
                let _ = writeln!(s, "| {} | {l} | {} | {} |", i + 1, cell(sc.rms()), sc.n);
            }
        }
        s
    }

    fn csv(&self) -> String {
        let mut s = String::from(
            "theta_i_deg,lambda_nm,slice,coord,ox,oy,oz,validity,explicit,explicit_se,surrogate",
        );
        for j in self.judged {
            let _ = write!(s, ",{}", j.c.key);
        }
        s.push('\n');
        for (k, set) in self.sets.iter().enumerate() {
            for (i, p) in set.points.iter().enumerate() {
                let _ = write!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{},{}",
                    set.theta_i,
                    set.lambda_nm,
                    match p.kind {
                        SliceKind::InPlane => "in_plane",
                        SliceKind::CrossPlane => "cross_plane",
                    },
                    p.coord,
                    p.wo[0],
                    p.wo[1],
                    p.wo[2],
                    p.validity.name(),
                    p.explicit.value,
                    p.explicit.se,
                    p.surrogate.map(|v| v.to_string()).unwrap_or_default()
                );
                for j in self.judged {
                    let _ = write!(s, ",{}", j.values[k][i]);
                }
                s.push('\n');
            }
        }
        s
    }

    fn plots(&self, out: &Path) -> anyhow::Result<()> {
        let thetas: Vec<f64> = dedup(self.sets.iter().map(|s| s.theta_i));
        let lambdas: Vec<f64> = dedup(self.sets.iter().map(|s| s.lambda_nm));
        let mut grid = ImageGrid::new(thetas.len(), lambdas.len());
        // Best few models only, so the slices stay readable.
        let shown: Vec<usize> = (0..self.judged.len().min(6)).collect();
        for (k, set) in self.sets.iter().enumerate() {
            let r = thetas.iter().position(|t| *t == set.theta_i).unwrap_or(0);
            let c = lambdas
                .iter()
                .position(|l| *l == set.lambda_nm)
                .unwrap_or(0);
            let img = self.slice_plot(k, set, &shown, k == 0)?;
            grid.set(r, c, img)?;
        }
        grid.save_png(out.join("judge_slices.png"))?;
        self.error_plot(out, &thetas)?;
        Ok(())
    }

    fn slice_plot(
        &self,
        k: usize,
        set: &AngleSet,
        shown: &[usize],
        legend: bool,
    ) -> anyhow::Result<plot::RgbImage> {
        let pts: Vec<(usize, &Point)> = set
            .points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.kind == SliceKind::InPlane)
            .collect();
        let xs: Vec<f64> = pts.iter().map(|(_, p)| p.coord).collect();
        let valid = |p: &Point| p.validity == Validity::Valid;
        let y_of = |f: &dyn Fn(&Point) -> f64, only_valid: bool| -> Vec<f64> {
            pts.iter()
                .map(|(_, p)| {
                    if valid(p) == only_valid {
                        f(p)
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        };
        let top = pts
            .iter()
            .map(|(_, p)| p.explicit.value)
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        if top <= 0.0 {
            bail!(
                "θi {}° λ {} nm: the explicit BRDF is zero on the whole slice",
                set.theta_i,
                set.lambda_nm
            );
        }
        let bottom = pts
            .iter()
            .filter(|(_, p)| valid(p))
            .map(|(_, p)| p.explicit.value)
            .filter(|v| *v > 0.0)
            .fold(top, f64::min);
        let mut p = Plot::new(format!("θi {}°, {} nm", set.theta_i, set.lambda_nm))
            .x_axis(Axis::linear("θo [deg] (< 0: backscatter)").range(-90.0, 90.0))
            .y_axis(Axis::log("BRDF [sr⁻¹]").range((bottom / 30.0).max(top * 1e-6), top * 5.0))
            .legend(if legend {
                Legend::BottomLeft
            } else {
                Legend::Hidden
            })
            .font_px(11.0);
        p = add(
            p,
            Series::points(
                "scan (explicit)",
                &xs,
                &y_of(&|p: &Point| p.explicit.value, true),
            )
            .color(Rgb(0, 0, 0))
            .marker(Marker::Circle)
            .marker_size(3.0),
        );
        for sign in [-2.0, 2.0] {
            p = add(
                p,
                Series::line(
                    if sign > 0.0 { "±2 se" } else { "" },
                    &xs,
                    &y_of(&|q: &Point| q.explicit.value + sign * q.explicit.se, true),
                )
                .color(Rgb(120, 120, 120))
                .style(LineStyle::Dotted)
                .width(1.0),
            );
        }
        p = add(
            p,
            Series::points(
                "outside window",
                &xs,
                &y_of(&|p: &Point| p.explicit.value, false),
            )
            .color(Rgb(190, 190, 190))
            .marker(Marker::Cross)
            .marker_size(3.0),
        );
        for &m in shown {
            let j = &self.judged[m];
            let ys: Vec<f64> = pts.iter().map(|(i, _)| j.values[k][*i]).collect();
            p = add(
                p,
                Series::line(j.c.label.clone(), &xs, &ys)
                    .color(Rgb::palette(m))
                    .width(1.5),
            );
        }
        let (img, _) = p.render(560, 400)?;
        Ok(img)
    }

    fn error_plot(&self, out: &Path, thetas: &[f64]) -> anyhow::Result<()> {
        let mut p = Plot::new(format!(
            "{}: log10 rms error against the scan's explicit BRDF",
            self.args
                .scan
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default()
        ))
        .x_axis(Axis::linear("θi [deg]"))
        .y_axis(Axis::log("log10 rms error (all λ)"))
        .legend(Legend::Outside)
        .font_px(12.0);
        let per_theta = |per: &dyn Fn(usize) -> Option<f64>| -> Vec<f64> {
            thetas
                .iter()
                .map(|t| {
                    let (mut a, mut n) = (0.0, 0usize);
                    for (i, s) in self.sets.iter().enumerate() {
                        if s.theta_i == *t
                            && let Some(v) = per(i)
                            && v.is_finite()
                        {
                            a += v * v;
                            n += 1;
                        }
                    }
                    if n > 0 {
                        (a / n as f64).sqrt()
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        };
        let (_, noise_per) = self.noise();
        p = add(
            p,
            Series::line(
                "noise floor of the reference",
                thetas,
                &per_theta(&|i| Some(noise_per[i])),
            )
            .color(Rgb(0, 0, 0))
            .style(LineStyle::Dashed),
        );
        if let Some((_, sur)) = self.surrogate_score() {
            p = add(
                p,
                Series::line(
                    "Gaussian surrogate (explicit)",
                    thetas,
                    &per_theta(&|i| Some(sur[i].rms())),
                )
                .color(Rgb(120, 120, 120))
                .style(LineStyle::Dotted)
                .marker(Marker::Diamond),
            );
        }
        for (m, j) in self.judged.iter().enumerate() {
            let ys: Vec<f64> = thetas
                .iter()
                .map(|t| {
                    let mut acc = Score::default();
                    for (s, sc) in self.sets.iter().zip(&j.per_angle) {
                        if s.theta_i == *t {
                            acc.merge(sc);
                        }
                    }
                    acc.rms()
                })
                .collect();
            p = add(
                p,
                Series::line(j.c.label.clone(), thetas, &ys)
                    .color(Rgb::palette(m))
                    .marker(Marker::Circle),
            );
        }
        let (img, _) = p.render(760, 380)?;
        plot::save_png(&img, out.join("judge_errors.png"))?;
        Ok(())
    }
}

/// Adds `s` unless it has no point a log axis can show (the plot crate rejects such series).
fn add(p: Plot, s: Series) -> Plot {
    if s.ys().iter().any(|y| y.is_finite() && *y > 0.0) {
        p.series(s)
    } else {
        p
    }
}

fn dedup(it: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::new();
    for x in it {
        if !v.contains(&x) {
            v.push(x);
        }
    }
    v
}
