//! `lustre brdf plot`: the figures scatterometry papers show — in-plane BRDF
//! slices on a log scale against θo or against β − β0 (direction cosines
//! sinθo − sinθi), and the directional albedo / total integrated scatter
//! against θi — for chosen surfaces, models, wavelengths and incidence angles.
//!
//! Per surface it writes `<name>_slices.{png,csv}` and `<name>_albedo.{png,csv}`
//! into `--out`, plus `panel.png` (one row per surface: slices | albedo) when
//! several surfaces are plotted. All files are written atomically.
//!
//! CSV columns carry every input of the evaluation (model fields, λ, θi, θo,
//! φo), so each row can be recomputed with `lustre brdf eval` or the `brdf`
//! crate. Geometry as `brdf eval`: i at azimuth 0, the in-plane forward
//! (specular) side is φo = 180°; the signed θo of the plots is negative on the
//! backscatter side (φo = 0°).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow, bail};
use brdf::{Bxdf, DVec3};
use plot::{Axis, ImageGrid, Legend, LineStyle, Marker, Plot, Rgb, Series};

use crate::models::{self, Labelled, Surface};

/// Horizontal axis of the slice plots.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceAxis {
    /// Signed outgoing angle θo in degrees (negative: backscatter side).
    Theta,
    /// β − β0 = sinθo − sinθi (signed direction cosine offset from the mirror direction).
    Beta,
}

/// Arguments of `lustre brdf plot`.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// Paper samples to plot, comma-separated (default: S808,S280,S138,S091,S027).
    #[arg(long, value_delimiter = ',')]
    pub samples: Vec<String>,
    /// Plot one custom K-correlation surface instead: SIGMA_UM,LC_UM,GAMMA.
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 1,
        value_name = "SIGMA,LC,GAMMA",
        conflicts_with = "samples"
    )]
    pub kc: Option<Vec<f64>>,
    /// Fresnel: "none" (R = 1) or a metal name; default the sample's metal
    /// (stainless_steel for --kc).
    #[arg(long)]
    pub fresnel: Option<String>,
    /// Models, comma-separated: ggx (slope-based α), ggx_identity (GGX ≡ KC
    /// α), beckmann, beckmann_identity, ghs_ssa, ghs, two_scale (cutoff
    /// 100λ) or two_scale_N (N wavelengths), measured_psd (the KC sampled as
    /// a table).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "ggx,ggx_identity,ghs_ssa,ghs,two_scale"
    )]
    pub models: Vec<String>,
    /// Wavelengths in nm, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "550")]
    pub lambda_nm: Vec<f64>,
    /// Incidence angles in degrees, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0,80")]
    pub theta_i: Vec<f64>,
    /// Horizontal axis of the slices.
    #[arg(long, value_enum, default_value = "theta")]
    pub x: SliceAxis,
    /// GGX/Beckmann α for every microfacet model, instead of the rules of
    /// `brdf::paper` (slope-based, or the GGX ≡ KC identity for *_identity).
    #[arg(long)]
    pub alpha: Option<f64>,
    /// Directions per slice (half uniform in θo, half clustered about the mirror direction).
    #[arg(long, default_value_t = 600)]
    pub points: usize,
    /// Incidence angles of the albedo curves, 0°..89° (0: no albedo plot).
    #[arg(long, default_value_t = 30)]
    pub albedo_angles: usize,
    /// Size of each plot in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x640")]
    pub size: String,
    /// Output directory.
    #[arg(long, default_value = "out/plots")]
    pub out: PathBuf,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| anyhow!("size {s:?}: expected WIDTHxHEIGHT, e.g. 960x640"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("size {s:?}: bad width {w:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("size {s:?}: bad height {h:?}"))?;
    if w == 0 || h == 0 {
        bail!("size {s:?}: width and height must be ≥ 1");
    }
    Ok((w, h))
}

fn surfaces(args: &PlotArgs) -> anyhow::Result<Vec<Surface>> {
    let mut out = Vec::new();
    if let Some(kc) = &args.kc {
        let [sigma, lc, gamma] = kc[..] else {
            bail!(
                "--kc needs three numbers SIGMA_UM,LC_UM,GAMMA, got {}",
                kc.len()
            );
        };
        brdf::statistics::KcPsd::new(sigma, lc, gamma).context("--kc")?;
        out.push(Surface {
            name: format!("kc_{sigma}_{lc}_{gamma}"),
            kc: brdf::spec::KcSpec {
                sigma_um: sigma,
                lc_um: lc,
                gamma,
            },
            fresnel: brdf::spec::FresnelSpec::Metal(brdf::Metal::StainlessSteel),
        });
    } else if args.samples.is_empty() {
        out.extend(brdf::paper::SAMPLES.iter().map(Surface::from_sample));
    } else {
        for name in &args.samples {
            out.push(Surface::from_sample(models::sample(name)?));
        }
    }
    if let Some(f) = &args.fresnel {
        let f = models::fresnel_from_name(f).context("--fresnel")?;
        for s in &mut out {
            s.fresnel = f.clone();
        }
    }
    Ok(out)
}

/// The labelled materials of one surface, with `--alpha` applied.
fn materials(args: &PlotArgs, s: &Surface) -> anyhow::Result<Vec<Labelled>> {
    let mut out = Vec::new();
    for m in models::paper_models(&args.models)? {
        let mut l = s.material(m);
        if let Some(a) = args.alpha {
            use brdf::spec::ModelSpec;
            if let ModelSpec::Ggx {
                alpha_x, alpha_y, ..
            }
            | ModelSpec::Beckmann {
                alpha_x, alpha_y, ..
            } = &mut l.spec.model
            {
                (*alpha_x, *alpha_y) = (a, a);
                let name = if matches!(l.spec.model, ModelSpec::Ggx { .. }) {
                    "GGX"
                } else {
                    "Beckmann"
                };
                l.label = format!("{name}, --alpha {}", brdf::paper::short(a));
            }
        }
        l.spec.validate().map_err(|e| anyhow!("{}: {e}", l.label))?;
        out.push(l);
    }
    Ok(out)
}

/// Most directions per slice: far past what a plot's width resolves.
const MAX_POINTS: usize = 100_000;
/// Most incidence angles of an albedo curve (one per 0.1° over 0°..89°).
const MAX_ALBEDO_ANGLES: usize = 891;

fn check_args(args: &PlotArgs) -> anyhow::Result<()> {
    models::check_wavelengths("--lambda-nm", &args.lambda_nm)?;
    models::check_incidence(&args.theta_i, 90.0)?;
    if args.lambda_nm.is_empty() || args.theta_i.is_empty() || args.models.is_empty() {
        bail!("--lambda-nm, --theta-i and --models each need at least one value");
    }
    if !(8..=MAX_POINTS).contains(&args.points) {
        bail!("--points {}: expected 8..={MAX_POINTS}", args.points);
    }
    if args.albedo_angles > MAX_ALBEDO_ANGLES {
        bail!(
            "--albedo-angles {}: expected 0..={MAX_ALBEDO_ANGLES} (0: no albedo plot)",
            args.albedo_angles
        );
    }
    Ok(())
}

/// Runs `lustre brdf plot`.
pub fn run(args: PlotArgs) -> anyhow::Result<()> {
    check_args(&args)?;
    let (w, h) = parse_size(&args.size)?;
    let surfaces = surfaces(&args)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating output directory {}", args.out.display()))?;
    let mut panel: Vec<(String, Vec<plot::RgbImage>)> = Vec::new();
    for s in &surfaces {
        let specs = materials(&args, s)?;
        let built: Vec<Box<dyn Bxdf>> = specs
            .iter()
            .map(|l| {
                l.spec
                    .build()
                    .map(|b| b as Box<dyn Bxdf>)
                    .map_err(|e| anyhow!("{}: {e}", l.label))
            })
            .collect::<anyhow::Result<_>>()?;
        let title = format!("{}: {}", s.name, s.describe());
        let fig = Figure {
            args: &args,
            surface: s,
            specs: &specs,
            built: &built,
            title: &title,
        };
        let mut images = Vec::new();
        let slices = slice_plot(&fig)?;
        let stem = s.name.to_lowercase();
        let png = args.out.join(format!("{stem}_slices.png"));
        let size = || format!("--size {}", args.size);
        let (img, report) = slices.0.render(w, h).with_context(size)?;
        plot::save_png(&img, &png)?;
        plot::write_atomic(
            &args.out.join(format!("{stem}_slices.csv")),
            slices.1.as_bytes(),
        )?;
        note(&args, &png, &report.skipped);
        images.push(img);
        if args.albedo_angles > 0 {
            let (p, csv) = albedo_plot(&fig)?;
            let png = args.out.join(format!("{stem}_albedo.png"));
            let (img, report) = p.render(w, h).with_context(size)?;
            plot::save_png(&img, &png)?;
            plot::write_atomic(&args.out.join(format!("{stem}_albedo.csv")), csv.as_bytes())?;
            note(&args, &png, &report.skipped);
            images.push(img);
        }
        panel.push((s.name.clone(), images));
    }
    if panel.len() > 1 {
        let cols = panel[0].1.len();
        let mut grid = ImageGrid::new(panel.len(), cols);
        for (r, (_, imgs)) in panel.into_iter().enumerate() {
            for (c, img) in imgs.into_iter().enumerate() {
                grid.set(r, c, img)?;
            }
        }
        let path = args.out.join("panel.png");
        grid.save_png(&path)?;
        if !args.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

fn note(args: &PlotArgs, png: &Path, skipped: &[plot::Skipped]) {
    if args.quiet {
        return;
    }
    eprintln!("wrote {} (+ .csv)", png.display());
    for s in skipped {
        eprintln!(
            "  {}: {} points ≤ 0 not drawn on the log axis (kept in the CSV)",
            s.label, s.count
        );
    }
}

const STYLES: [LineStyle; 4] = [
    LineStyle::Solid,
    LineStyle::Dashed,
    LineStyle::Dotted,
    LineStyle::DashDot,
];
const MARKERS: [Marker; 4] = [
    Marker::None,
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
];

/// Signed in-plane coordinates s = β (sinθo, positive on the specular side)
/// for a slice at incidence `theta_i_deg`: half uniform in θo over ±89.5°, half
/// geometric offsets 1e−6…1 about the mirror value sinθi, sorted, deduplicated.
pub fn slice_positions(theta_i_deg: f64, points: usize) -> Vec<f64> {
    let s_max = 89.5f64.to_radians().sin();
    let s0 = theta_i_deg.to_radians().sin();
    let n_uni = points / 2;
    let mut s: Vec<f64> = (0..n_uni)
        .map(|j| {
            (-89.5 + 179.0 * j as f64 / (n_uni - 1) as f64)
                .to_radians()
                .sin()
        })
        .collect();
    let n_side = (points - n_uni) / 2;
    for j in 0..n_side {
        let d = 10f64.powf(-6.0 + 6.0 * j as f64 / (n_side - 1).max(1) as f64);
        s.extend([s0 - d, s0 + d]);
    }
    s.push(s0);
    s.retain(|v| v.abs() <= s_max);
    s.sort_by(f64::total_cmp);
    s.dedup();
    s
}

/// Signed s → (θo in degrees, φo in degrees) as `brdf eval` takes them.
pub fn in_plane_angles(s: f64) -> (f64, f64) {
    (
        s.abs().asin().to_degrees(),
        if s >= 0.0 { 180.0 } else { 0.0 },
    )
}

fn direction(theta_deg: f64, phi_deg: f64) -> DVec3 {
    brdf::frame::spherical(theta_deg.to_radians(), phi_deg.to_radians())
}

/// One surface's materials, built, as both of its plots read them.
struct Figure<'a> {
    args: &'a PlotArgs,
    surface: &'a Surface,
    specs: &'a [Labelled],
    built: &'a [Box<dyn Bxdf>],
    title: &'a str,
}

/// CSV header: who (surface, model, label), the plot's own `columns`, then the material's
/// parameters, so every row can be recomputed on its own.
fn csv_header(columns: &str) -> String {
    format!("surface,model,label,{columns},fresnel,alpha,sigma_um,lc_um,gamma,beta\n")
}

/// One CSV row in the [`csv_header`] layout; `values` fill the plot's own columns.
fn csv_row(
    csv: &mut String,
    s: &Surface,
    m: &Labelled,
    values: std::fmt::Arguments<'_>,
) -> std::fmt::Result {
    writeln!(
        csv,
        "{},{},{},{values},{}",
        s.name,
        m.spec.model.kind().name(),
        quote(&m.label),
        csv_fields(m)
    )
}

/// The material's parameters as CSV columns (empty where the model has none).
fn csv_fields(m: &Labelled) -> String {
    let d = m.spec.to_desc();
    let f = |v: Option<f64>| v.map_or_else(String::new, |v| format!("{v}"));
    let alpha = d.alpha.or(d.alpha_x);
    format!(
        "{},{},{},{},{},{}",
        models::fresnel_name(&m.spec.fresnel),
        f(alpha),
        f(d.sigma_um),
        f(d.lc_um),
        f(d.gamma),
        f(d.beta)
    )
}

fn quote(s: &str) -> String {
    if s.contains([',', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn slice_plot(fig: &Figure<'_>) -> anyhow::Result<(Plot, String)> {
    let (args, s, title) = (fig.args, fig.surface, fig.title);
    let mut csv = csv_header(
        "lambda_nm,theta_i_deg,theta_o_deg,phi_o_deg,theta_o_signed_deg,beta_minus_beta0,brdf_per_sr",
    );
    let x_label = match args.x {
        SliceAxis::Theta => "θo [deg]  (< 0: backscatter side)",
        SliceAxis::Beta => "β − β0 = sinθo − sinθi",
    };
    let mut series = Vec::new();
    let mut y_max = 0.0f64;
    let multi_lambda = args.lambda_nm.len() > 1;
    for (mi, (spec, model)) in fig.specs.iter().zip(fig.built).enumerate() {
        for (ti, &theta_i) in args.theta_i.iter().enumerate() {
            for (li, &lambda) in args.lambda_nm.iter().enumerate() {
                let wi = direction(theta_i, 0.0);
                let (mut xs, mut ys) = (Vec::new(), Vec::new());
                for sv in slice_positions(theta_i, args.points) {
                    let (theta_o, phi_o) = in_plane_angles(sv);
                    let wo = direction(theta_o, phi_o);
                    let f = model.eval(wi, wo, lambda);
                    let signed = if phi_o == 180.0 { theta_o } else { -theta_o };
                    let db = -wo.x - wi.x;
                    csv_row(
                        &mut csv,
                        s,
                        spec,
                        format_args!("{lambda},{theta_i},{theta_o},{phi_o},{signed},{db},{f}"),
                    )?;
                    xs.push(if args.x == SliceAxis::Theta {
                        signed
                    } else {
                        db
                    });
                    ys.push(f);
                    y_max = y_max.max(if f.is_finite() { f } else { 0.0 });
                }
                let mut label = format!("{}, θi {theta_i}°", spec.label);
                if multi_lambda {
                    let _ = write!(label, ", {lambda} nm");
                }
                let mut ser = Series::line(label, &xs, &ys)
                    .color(Rgb::palette(mi))
                    .style(STYLES[ti % STYLES.len()]);
                if li > 0 {
                    ser = ser
                        .marker(MARKERS[li % MARKERS.len()])
                        .marker_every((xs.len() / 12).max(1));
                }
                series.push(ser);
            }
        }
    }
    // NaN-safe: a NaN maximum is as unplottable as zero.
    if y_max.is_nan() || y_max <= 0.0 {
        bail!(
            "{}: every BRDF value is zero; nothing to plot on a log axis",
            s.name
        );
    }
    // Twelve decades below the highest peak: deeper tails are numerically
    // meaningless for the figure (they stay in the CSV).
    let mut p = Plot::new(format!("{title}, in-plane BRDF, {}", lambda_text(args)))
        .x_axis(Axis::linear(x_label))
        .y_axis(Axis::log("BRDF [sr⁻¹]").range(y_max * 1e-12, y_max * 3.0))
        .legend(Legend::Outside);
    for ser in series {
        p = p.series(ser);
    }
    Ok((p, csv))
}

/// Incidence angles of the albedo curves: `n` values evenly over 0°…89°.
pub fn albedo_angles(n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![0.0];
    }
    (0..n).map(|j| 89.0 * j as f64 / (n - 1) as f64).collect()
}

fn albedo_plot(fig: &Figure<'_>) -> anyhow::Result<(Plot, String)> {
    let (args, s, title) = (fig.args, fig.surface, fig.title);
    let mut csv = csv_header(
        "lambda_nm,theta_i_deg,lobe_rho,scattered_albedo,specular_weight,total_albedo,tis",
    );
    let mut p = Plot::new(format!(
        "{title}, directional albedo, {}",
        lambda_text(args)
    ))
    .x_axis(Axis::linear("θi [deg]").range(0.0, 90.0))
    .legend(Legend::Outside);
    let mut y_max = 1.0f64;
    let multi_lambda = args.lambda_nm.len() > 1;
    for (mi, (spec, model)) in fig.specs.iter().zip(fig.built).enumerate() {
        for (li, &lambda) in args.lambda_nm.iter().enumerate() {
            let rho = spec.spec.lobe_rho(lambda);
            let (mut xs, mut total, mut tis) = (Vec::new(), Vec::new(), Vec::new());
            for theta_i in albedo_angles(args.albedo_angles) {
                let wi = direction(theta_i, 0.0);
                let a = spec.spec.albedo(model.as_ref(), wi, lambda);
                let (scattered, spec_w, t) = (a.scattered, a.specular, a.total());
                let r = if t > 0.0 { scattered / t } else { 0.0 };
                csv_row(
                    &mut csv,
                    s,
                    spec,
                    format_args!("{lambda},{theta_i},{rho},{scattered},{spec_w},{t},{r}"),
                )?;
                xs.push(theta_i);
                total.push(t);
                tis.push(r);
                y_max = y_max.max(t).max(r);
            }
            let suffix = if multi_lambda {
                format!(", {lambda} nm")
            } else {
                String::new()
            };
            let marker = MARKERS[li % MARKERS.len()];
            let every = (xs.len() / 8).max(1);
            p = p.series(
                Series::line(format!("{} albedo{suffix}", spec.label), &xs, &total)
                    .color(Rgb::palette(mi))
                    .marker(marker)
                    .marker_every(every),
            );
            p = p.series(
                Series::line(format!("{} TIS{suffix}", spec.label), &xs, &tis)
                    .color(Rgb::palette(mi))
                    .style(LineStyle::Dashed)
                    .marker(marker)
                    .marker_every(every),
            );
        }
    }
    // Up to 1 with a margin; a model that reflects more than it receives (a raw energy
    // option near grazing) stays on the figure instead of leaving it.
    let top = if y_max.is_finite() {
        1.05 * y_max
    } else {
        1.05
    };
    let p = p.y_axis(Axis::linear("albedo (solid) · TIS (dashed)").range(0.0, top));
    Ok((p, csv))
}

/// The wavelengths of a figure for its title: `λ 550 nm`, `λ 450, 550, 650 nm`.
fn lambda_text(args: &PlotArgs) -> String {
    let list: Vec<String> = args.lambda_nm.iter().map(|l| format!("{l}")).collect();
    format!("λ {} nm", list.join(", "))
}
