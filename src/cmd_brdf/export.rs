//! `lustre brdf export`: a model as a tabulated BSDF file other renderers
//! read — the RGL measured format of Mitsuba 3's and pbrt-v4's `measured`
//! plugins (`.bsdf`, spectral or RGB) or a MERL `.binary` table — with the
//! table's resolution and its measured read-back error (the `export` crate).
//!
//! The material comes from a file — a `lustre fit` material file (its
//! `[material]`, or `--model`, with `[psd]` for `measured_psd` and the
//! `[two_scale.NAME]` chosen by `--cutoff`), or a material description with
//! the keys of a scene's `[materials.NAME]` (which may `include` a fit file)
//! — or from a paper sample (`--sample S280 --model ghs`).

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail};
use brdf::spec::{MaterialDesc, MaterialSpec, ModelKind};
use render::scene::inputs::MAX_TOML_BYTES;

/// File format of the export.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// RGL measured BSDF (`.bsdf`): Mitsuba 3 and pbrt-v4 `measured`.
    Rgl,
    /// MERL `.binary` (linear sRGB, isotropic).
    Merl,
}

/// Light under which spectra become RGB.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum IlluminantArg {
    /// CIE D65 (sRGB's white point).
    D65,
    /// Equal energy.
    E,
}

/// Arguments of `lustre brdf export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Material file: a `lustre fit` file or a material description (the
    /// keys of a scene's `[materials.NAME]` table).
    #[arg(required_unless_present = "sample", conflicts_with = "sample")]
    pub material: Option<PathBuf>,
    /// A paper sample instead (S808, S280, S138, S091, S027), with its metal.
    #[arg(long)]
    pub sample: Option<String>,
    /// With --sample: the paper model (ggx, ggx_identity, beckmann, ghs_ssa,
    /// ghs, two_scale, two_scale_N, measured_psd; default ghs). With a fit
    /// file: the model to export instead of the file's own.
    #[arg(long)]
    pub model: Option<String>,
    /// With a fit file and model two_scale: the `[two_scale.NAME]` split.
    #[arg(long)]
    pub cutoff: Option<String>,
    /// With --sample: "none" (R = 1) or a metal instead of the sample's.
    #[arg(long)]
    pub fresnel: Option<String>,
    /// Output file.
    #[arg(short, long)]
    pub out: PathBuf,
    /// Format (default: from the extension, `.binary` → merl, else rgl).
    #[arg(long, value_enum)]
    pub format: Option<Format>,
    /// RGL: store linear sRGB (Mitsuba's RGB variants) instead of spectra.
    #[arg(long)]
    pub rgb: bool,
    /// RGL: incident elevations of the slices, degrees, comma-separated
    /// (default 0, 4, …, 60, 62, …, 88).
    #[arg(long, value_delimiter = ',')]
    pub theta_i: Vec<f64>,
    /// RGL: n of the n × n grid of the spectra (default 64).
    #[arg(long)]
    pub sample_nodes: Option<usize>,
    /// RGL: azimuth slices of an anisotropic model (default 17).
    #[arg(long)]
    pub phi_nodes: Option<usize>,
    /// RGL: VNDF grid per slice, U_THETA,U_PHI nodes (default 128,64).
    #[arg(long, value_delimiter = ',', num_args = 1)]
    pub vndf_nodes: Option<Vec<usize>>,
    /// RGL: NDF grid, U_THETA,U_PHI nodes (default 256,64).
    #[arg(long, value_delimiter = ',', num_args = 1)]
    pub ndf_nodes: Option<Vec<usize>>,
    /// RGL: projected-area grid, U_THETA,U_PHI nodes (default 128,64).
    #[arg(long, value_delimiter = ',', num_args = 1)]
    pub sigma_nodes: Option<Vec<usize>>,
    /// Wavelengths in nm: FIRST:STEP:LAST or a comma-separated list
    /// (default 360:10:830).
    #[arg(long)]
    pub wavelengths: Option<String>,
    /// Light for RGB colours and the luminance warp.
    #[arg(long, value_enum, default_value = "d65")]
    pub illuminant: IlluminantArg,
    /// Leave out the model's coherent (mirror) lobe, which a table cannot
    /// hold (GHS and two-scale at grazing incidence), instead of refusing.
    #[arg(long)]
    pub drop_specular: bool,
    /// Largest incidence, degrees, of the error estimate and of the
    /// coherent-lobe check (default 80).
    #[arg(long)]
    pub max_theta: Option<f64>,
    /// Monte Carlo directions per checked incidence of the error estimate
    /// (default 4096; 0 skips the estimate).
    #[arg(long)]
    pub check_samples: Option<usize>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `lustre brdf export`.
pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let spec = material(&args)?;
    let format =
        args.format
            .unwrap_or_else(|| match args.out.extension().and_then(|e| e.to_str()) {
                Some(e) if e.eq_ignore_ascii_case("binary") => Format::Merl,
                _ => Format::Rgl,
            });
    safe_io::check_output(&args.out)?;
    let out = match format {
        Format::Rgl => ::export::rgl_material(&spec, &rgl_options(&args)?)?,
        Format::Merl => {
            if args.rgb || !args.theta_i.is_empty() || args.sample_nodes.is_some() {
                bail!(
                    "--rgb, --theta-i and --sample-nodes describe an RGL table; a MERL table has a fixed layout"
                );
            }
            ::export::merl_material(&spec, &merl_options(&args)?)?
        }
    };
    ::export::write(&args.out, &out)?;
    if !args.quiet {
        println!("wrote {}", args.out.display());
        print!("{}", out.report.summary());
    }
    Ok(())
}

fn illuminant(a: IlluminantArg) -> ::export::Illuminant {
    match a {
        IlluminantArg::D65 => ::export::Illuminant::D65,
        IlluminantArg::E => ::export::Illuminant::E,
    }
}

fn pair(flag: &str, v: &Option<Vec<usize>>, default: [usize; 2]) -> anyhow::Result<[usize; 2]> {
    match v.as_deref() {
        None => Ok(default),
        Some([a, b]) => Ok([*a, *b]),
        Some(other) => bail!("{flag}: give two numbers U_THETA,U_PHI, got {other:?}"),
    }
}

fn rgl_options(a: &ExportArgs) -> anyhow::Result<::export::RglOptions> {
    let d = ::export::RglOptions::default();
    Ok(::export::RglOptions {
        theta_i_deg: if a.theta_i.is_empty() {
            d.theta_i_deg
        } else {
            a.theta_i.clone()
        },
        phi_i_nodes: a.phi_nodes.unwrap_or(d.phi_i_nodes),
        sample_nodes: a.sample_nodes.unwrap_or(d.sample_nodes),
        vndf_nodes: pair("--vndf-nodes", &a.vndf_nodes, d.vndf_nodes)?,
        ndf_nodes: pair("--ndf-nodes", &a.ndf_nodes, d.ndf_nodes)?,
        sigma_nodes: pair("--sigma-nodes", &a.sigma_nodes, d.sigma_nodes)?,
        wavelengths_nm: wavelengths(a.wavelengths.as_deref())?.unwrap_or(d.wavelengths_nm),
        colour: if a.rgb {
            ::export::Colour::Rgb
        } else {
            ::export::Colour::Spectral
        },
        illuminant: illuminant(a.illuminant),
        drop_specular: a.drop_specular,
        description: String::new(),
        check_samples: a.check_samples.unwrap_or(d.check_samples),
        check_theta_max_deg: a.max_theta.unwrap_or(d.check_theta_max_deg),
    })
}

fn merl_options(a: &ExportArgs) -> anyhow::Result<::export::MerlOptions> {
    let d = ::export::MerlOptions::default();
    Ok(::export::MerlOptions {
        wavelengths_nm: wavelengths(a.wavelengths.as_deref())?.unwrap_or(d.wavelengths_nm),
        illuminant: illuminant(a.illuminant),
        drop_specular: a.drop_specular,
        check_samples: a.check_samples.unwrap_or(d.check_samples),
        check_theta_max_deg: a.max_theta.unwrap_or(d.check_theta_max_deg),
    })
}

/// `FIRST:STEP:LAST` (at most 1024 values) or a comma-separated list.
fn wavelengths(s: Option<&str>) -> anyhow::Result<Option<Vec<f64>>> {
    let Some(s) = s else { return Ok(None) };
    let num = |t: &str| -> anyhow::Result<f64> {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| anyhow!("--wavelengths {s:?}: {t:?} is not a finite number"))
    };
    if let [a, b, c] = s.split(':').collect::<Vec<_>>()[..] {
        let (first, step, last) = (num(a)?, num(b)?, num(c)?);
        if step.is_nan() || step <= 0.0 || last < first || (last - first) / step > 1023.5 {
            bail!(
                "--wavelengths {s:?}: FIRST:STEP:LAST needs STEP > 0, LAST ≥ FIRST and at most 1024 values"
            );
        }
        let n = ((last - first) / step + 1e-9).floor() as usize + 1;
        return Ok(Some((0..n).map(|k| first + step * k as f64).collect()));
    }
    s.split(',')
        .map(num)
        .collect::<anyhow::Result<Vec<f64>>>()
        .map(Some)
}

/// The material of the arguments.
fn material(args: &ExportArgs) -> anyhow::Result<MaterialSpec> {
    if let Some(name) = &args.sample {
        if args.cutoff.is_some() {
            bail!("--cutoff picks a split of a fit file; with --sample use --model two_scale_N");
        }
        let sample = crate::models::sample(name)?;
        let model = crate::models::paper_models(&[args.model.clone().unwrap_or("ghs".into())])?[0];
        let fresnel = match &args.fresnel {
            Some(f) => crate::models::fresnel_from_name(f)?,
            None => brdf::spec::FresnelSpec::Metal(sample.metal),
        };
        return Ok(model.material(&sample.surface, fresnel));
    }
    if args.fresnel.is_some() {
        bail!("--fresnel goes with --sample; a material file names its own metal");
    }
    let path = args
        .material
        .as_deref()
        .ok_or_else(|| anyhow!("give a material file or --sample"))?;
    let model = match &args.model {
        Some(m) => Some(
            ModelKind::from_name(m.trim())
                .ok_or_else(|| anyhow!("--model {m:?}: one of {}", ModelKind::names()))?,
        ),
        None => None,
    };
    material_file(path, model, args.cutoff.as_deref())
}

/// The file's text.
fn read_text(path: &Path, what: &str) -> anyhow::Result<String> {
    let bytes = safe_io::read_input(path, what, MAX_TOML_BYTES)?;
    String::from_utf8(bytes).map_err(|_| anyhow!("{}: not UTF-8 text", path.display()))
}

/// The material of a file as a scene would draw it (render's `resolve_spec`, one route): a
/// fit file is a bare `include` of it with `--model`/`--cutoff` over it; a material
/// description (which may `include` a fit file, relative to it) is a scene's
/// `[materials.NAME]`, with `--model`/`--cutoff` replacing its own.
fn material_file(
    path: &Path,
    model: Option<ModelKind>,
    cutoff: Option<&str>,
) -> anyhow::Result<MaterialSpec> {
    let text = read_text(path, "material file")?;
    let at = |e: toml::de::Error| {
        let pos = e.span().map(|s| render::error::line_column(&text, s.start));
        match pos {
            Some((l, c)) => anyhow!("{}:{l}:{c}: {}", path.display(), e.message().trim()),
            None => anyhow!("{}: {}", path.display(), e.message().trim()),
        }
    };
    let doc: toml::Table = toml::from_str(&text).map_err(at)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut desc = if doc.contains_key("material") {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        MaterialDesc {
            include: Some(name.into_owned()),
            ..MaterialDesc::default()
        }
    } else {
        toml::from_str::<MaterialDesc>(&text).map_err(at)?
    };
    if model.is_some() {
        desc.model = model;
    }
    if cutoff.is_some() {
        desc.cutoff = cutoff.map(str::to_string);
    }
    let mut inputs = render::inputs::Inputs::new(dir);
    render::material::resolve_spec(&desc, dir, &mut inputs)
        .map_err(|e| anyhow!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::spec::ModelSpec;
    use clap::Parser;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: ExportArgs,
    }

    fn args(line: &[&str]) -> ExportArgs {
        let mut v = vec!["export"];
        v.extend_from_slice(line);
        Cli::try_parse_from(v).unwrap().args
    }

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lustre_export_{name}_{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn wavelength_ranges_and_lists() {
        assert_eq!(
            wavelengths(Some("400:50:600")).unwrap().unwrap(),
            vec![400.0, 450.0, 500.0, 550.0, 600.0]
        );
        assert_eq!(
            wavelengths(Some("500, 600")).unwrap().unwrap(),
            vec![500.0, 600.0]
        );
        assert_eq!(wavelengths(None).unwrap(), None);
        for bad in [
            "400:0:500",
            "400:10:300",
            "400:nan:500",
            "a,b",
            "360:0.1:830",
        ] {
            assert!(wavelengths(Some(bad)).is_err(), "{bad}");
        }
    }

    /// A fit file as `lustre fit` writes its material tables (diagnostic
    /// tables left out).
    const FIT: &str = "[material]\nmetal = \"cu\"\nmodel = \"ghs\"\nsigma_um = 0.1\nlc_um = 2.0\n\
        gamma = 3.5\nalpha = 0.1\nalpha_beckmann = 0.12\n\n[two_scale.cutoff_50]\nbeta = 0.05\n\
        sigma_um = 0.05\nlc_um = 1.0\ngamma = 3.0\n\n[psd]\nzeta_rad_per_um = [0.1, 1.0, 10.0]\n\
        p_um4 = [1e-3, 1e-4, 1e-8]\n";

    #[test]
    fn fit_files_descriptions_and_includes_resolve() {
        let d = dir("resolve");
        let fit = d.join("fit.toml");
        std::fs::write(&fit, FIT).unwrap();
        let own = material_file(&fit, None, None).unwrap();
        assert!(matches!(own.model, ModelSpec::Ghs { surface, .. } if surface.sigma_um == 0.1));
        let b = material_file(&fit, Some(ModelKind::Beckmann), None).unwrap();
        assert_eq!(
            b.model,
            ModelSpec::Beckmann {
                alpha_x: 0.12,
                alpha_y: 0.12,
                angle_deg: 0.0,
            }
        );
        let ts = material_file(&fit, Some(ModelKind::TwoScale), None).unwrap();
        assert!(matches!(ts.model, ModelSpec::TwoScale { beta, .. } if beta == 0.05));
        let psd = material_file(&fit, Some(ModelKind::MeasuredPsd), None).unwrap();
        assert!(
            matches!(psd.model, ModelSpec::MeasuredPsd { ref zeta_rad_per_um, .. } if zeta_rad_per_um.len() == 3)
        );
        let e = material_file(&fit, Some(ModelKind::TwoScale), Some("cutoff_7")).unwrap_err();
        assert!(e.to_string().contains("cutoff_50"), "{e}");
        // A description including the fit file, with its own key over it.
        let inc = d.join("inc.toml");
        std::fs::write(
            &inc,
            "include = \"fit.toml\"\nmodel = \"ggx\"\nalpha = 0.3\n",
        )
        .unwrap();
        let g = material_file(&inc, None, None).unwrap();
        assert_eq!(
            g.model,
            ModelSpec::Ggx {
                alpha_x: 0.3,
                alpha_y: 0.3,
                angle_deg: 0.0,
            }
        );
        // nk_csv relative to the description.
        std::fs::write(
            d.join("nk.csv"),
            "wavelength_nm,n,k\n300,0.2,3\n900,0.3,4\n",
        )
        .unwrap();
        let flat = d.join("flat.toml");
        std::fs::write(&flat, "model = \"ggx\"\nalpha = 0.2\nnk_csv = \"nk.csv\"\n").unwrap();
        assert!(
            matches!(material_file(&flat, None, None).unwrap().fresnel, brdf::spec::FresnelSpec::Table(ref r) if r.len() == 2)
        );
        let bad = d.join("bad.toml");
        std::fs::write(&bad, "model = \"ggx\"\n\nalpah = 0.2\nmetal = \"cu\"\n").unwrap();
        let e = material_file(&bad, None, None).unwrap_err().to_string();
        assert!(e.contains("bad.toml:3:1") && e.contains("alpah"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn hostile_numbers_are_refused_or_run_briefly() {
        let d = dir("hostile");
        let out = d.join("h.bsdf");
        let o = out.to_str().unwrap();
        let values = [
            "0",
            "-1",
            "nan",
            "inf",
            "-inf",
            "1e308",
            "-1e308",
            "18446744073709551615",
        ];
        let flags = [
            "--theta-i",
            "--sample-nodes",
            "--phi-nodes",
            "--vndf-nodes",
            "--ndf-nodes",
            "--sigma-nodes",
            "--wavelengths",
            "--max-theta",
            "--check-samples",
        ];
        for flag in flags {
            for v in values {
                let v = if flag.ends_with("-nodes")
                    && flag != "--sample-nodes"
                    && flag != "--phi-nodes"
                {
                    format!("{v},8")
                } else {
                    v.to_string()
                };
                let mut line = vec!["--sample", "S280", "--model", "ggx", "-o", o, "-q"];
                for (f, default) in [
                    ("--theta-i", "0,60"),
                    ("--sample-nodes", "6"),
                    ("--vndf-nodes", "8,6"),
                    ("--ndf-nodes", "16,4"),
                    ("--sigma-nodes", "8,4"),
                    ("--wavelengths", "500,600"),
                    ("--check-samples", "16"),
                ] {
                    if f != flag {
                        line.extend([f, default]);
                    }
                }
                line.extend([flag, v.as_str()]);
                let start = std::time::Instant::now();
                let parsed =
                    Cli::try_parse_from(std::iter::once("export").chain(line.iter().copied()));
                if let Ok(cli) = parsed {
                    let _ = run(cli.args);
                }
                assert!(
                    start.elapsed().as_secs() < 20,
                    "{flag} {v}: {:?}",
                    start.elapsed()
                );
            }
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn exports_a_sample_and_refuses_what_does_not_apply() {
        let d = dir("run");
        let out = d.join("s280.bsdf");
        let o = out.to_str().unwrap();
        let small = [
            "--theta-i",
            "0,40,80",
            "--sample-nodes",
            "8",
            "--vndf-nodes",
            "16,8",
            "--wavelengths",
            "500,600",
            "--check-samples",
            "64",
            "-q",
        ];
        let mut line = vec!["--sample", "S280", "--model", "ggx", "-o", o];
        line.extend_from_slice(&small);
        run(args(&line)).unwrap();
        let t = ::export::RglTable::parse(&std::fs::read(&out).unwrap()).unwrap();
        assert_eq!(t.theta_i().len(), 3);
        assert!(t.description().contains("ggx"), "{}", t.description());
        // Full GHS of S280 reflects coherently at grazing incidence.
        let e = run(args(&[
            "--sample",
            "S280",
            "-o",
            o,
            "--check-samples",
            "0",
            "--sample-nodes",
            "8",
        ]))
        .unwrap_err();
        assert!(e.to_string().contains("--drop-specular"), "{e}");
        let m = d.join("x.binary");
        let e = run(args(&[
            "--sample",
            "S280",
            "--model",
            "ggx",
            "--rgb",
            "-o",
            m.to_str().unwrap(),
        ]))
        .unwrap_err();
        assert!(e.to_string().contains("MERL"), "{e}");
        assert!(!m.exists());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
