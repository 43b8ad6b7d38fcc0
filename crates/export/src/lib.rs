//! # export — lustre's models as tabulated BSDF files other renderers read
//!
//! * [`rgl`] / [`rgl_material`]: the RGL measured-BSDF format of Dupuy &
//!   Jakob 2018, which Mitsuba 3's and pbrt-v4's `measured` plugins read
//!   (spectral, or linear sRGB for Mitsuba's RGB variants). See [`rgl`]'s
//!   module for the fields and how each is computed from the model.
//! * [`merl`] / [`merl_material`]: a MERL `.binary` table (Matusik et al.
//!   2003; 90 × 90 × 180 half/difference-angle cells, linear sRGB), which
//!   many BRDF tools read. See [`merl`]'s module.
//!
//! Every export reads its own bytes back as the renderers do ([`RglTable`],
//! [`MerlTable`]) and returns, with the bytes, a [`Report`]: the table's
//! resolution and the estimated error of the read-back against the model
//! (relative L1 error of the reflected lobe and albedo error per incidence
//! and wavelength or channel). A table holds glossy reflection only: a
//! model's coherent delta lobe (GHS at grazing incidence, `smooth`) is
//! refused unless the options drop it, and the report says how much was
//! dropped.
//!
//! ```no_run
//! use brdf::spec::{FresnelSpec, MaterialSpec, ModelSpec};
//! let copper = MaterialSpec {
//!     model: ModelSpec::Ggx { alpha_x: 0.2, alpha_y: 0.2, angle_deg: 0.0 },
//!     fresnel: FresnelSpec::Metal(brdf::Metal::Cu),
//! };
//! let out = export::rgl_material(&copper, &export::RglOptions::default())?;
//! println!("{}", out.report.summary());
//! export::write(std::path::Path::new("copper.bsdf"), &out)?;
//! # Ok::<(), export::ExportError>(())
//! ```

pub mod check;
pub mod color;
mod marginal;
pub mod merl;
pub mod ndf;
pub mod param;
pub mod rgl;
pub mod tensor;

use brdf::Bxdf;
use brdf::spec::{MaterialSpec, ModelSpec, SpecError};

pub use check::CheckPoint;
pub use color::Illuminant;
pub use merl::{MerlOptions, MerlTable};
pub use ndf::NdfSource;
pub use rgl::{Colour, RglOptions, RglTable};

/// Most Monte Carlo directions per check an export accepts.
pub const MAX_CHECK_SAMPLES: usize = 1 << 22;

/// Largest coherent (delta) reflectance, as a fraction of the incident
/// light, an export leaves out without being told to.
pub const DELTA_TOLERANCE: f64 = 1e-3;

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// An option out of range.
    #[error("export option `{field}`: {message}")]
    Option {
        /// The option's name.
        field: &'static str,
        /// What is wrong and what is valid.
        message: String,
    },
    /// The material does not build.
    #[error("material: {0}")]
    Spec(#[from] SpecError),
    /// The model cannot be tabulated as asked.
    #[error("{0}")]
    Model(String),
    /// The model has a delta lobe a table cannot hold.
    #[error(
        "the model reflects {weight:.3e} of the incident light into its coherent (mirror, \
         delta) lobe at θi {theta_i_deg}°, {lambda_nm} nm; a tabulated BSDF holds glossy \
         reflection only, so export with drop_specular (CLI: --drop-specular) to leave it out, \
         or lower the checked incidence (check_theta_max_deg, CLI: --max-theta)"
    )]
    Specular {
        /// The coherent reflectance.
        weight: f64,
        /// Where.
        theta_i_deg: f64,
        /// At which wavelength.
        lambda_nm: f64,
    },
    /// A file being read back is malformed.
    #[error("{what}: {message}")]
    Parse {
        /// The format.
        what: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] safe_io::WriteError),
}

/// An exported table and what it is worth.
#[derive(Clone, Debug)]
pub struct Exported {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// Its resolution and measured error.
    pub report: Report,
}

/// What an export holds and how far its read-back is from the model.
#[derive(Clone, Debug)]
pub struct Report {
    /// The format written.
    pub format: &'static str,
    /// The table's resolution, in words.
    pub resolution: String,
    /// Where the microfacet distribution came from (RGL), or the colour
    /// conversion (MERL).
    pub ndf: &'static str,
    /// Size of the file.
    pub bytes: usize,
    /// Largest coherent reflectance left out (0 without a delta lobe).
    pub dropped_specular: f64,
    /// Table nodes whose value could not be represented (the NDF vanishes
    /// where the model still reflects, or the value overflows f32).
    pub unrepresented_nodes: usize,
    /// Largest incidence the checks cover, degrees.
    pub check_theta_max_deg: f64,
    /// The error estimates.
    pub checks: Vec<CheckPoint>,
}

impl Report {
    /// The largest relative L1 error of the lobe over the checks.
    pub fn max_rel_l1(&self) -> f64 {
        self.checks.iter().map(|c| c.rel_l1).fold(0.0, f64::max)
    }

    /// The mean relative L1 error over the checks.
    pub fn mean_rel_l1(&self) -> f64 {
        let n = self.checks.len().max(1) as f64;
        self.checks.iter().map(|c| c.rel_l1).sum::<f64>() / n
    }

    /// The largest relative error of the directional albedo over the checks
    /// (incidences where the model reflects less than 1 % ignored).
    pub fn max_albedo_error(&self) -> f64 {
        self.checks
            .iter()
            .filter(|c| c.albedo_model > 0.01)
            .map(|c| (c.albedo_table / c.albedo_model - 1.0).abs())
            .fold(0.0, f64::max)
    }

    /// The check with the largest relative L1 error.
    pub fn worst(&self) -> Option<&CheckPoint> {
        self.checks
            .iter()
            .max_by(|a, b| a.rel_l1.total_cmp(&b.rel_l1))
    }

    /// A few lines for people.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}: {} ({} bytes)\nparameterisation: {}\n",
            self.format, self.resolution, self.bytes, self.ndf
        );
        if let Some(w) = self.worst() {
            s += &format!(
                "read-back vs model, θi 0–{}° ({} checks): relative L1 error of the lobe mean \
                 {:.2e}, max {:.2e} (± {:.1e}) at θi {:.1}°{} {}; albedo error max {:.2e}\n",
                self.check_theta_max_deg,
                self.checks.len(),
                self.mean_rel_l1(),
                w.rel_l1,
                w.rel_l1_se,
                w.theta_i_deg,
                if w.phi_i_deg != 0.0 {
                    format!(" φi {:.1}°", w.phi_i_deg)
                } else {
                    String::new()
                },
                channel_name(w.lambda),
                self.max_albedo_error()
            );
        }
        if self.dropped_specular > 0.0 {
            s += &format!(
                "left out: the coherent (delta) lobe, up to {:.3e} of the incident light\n",
                self.dropped_specular
            );
        }
        if self.unrepresented_nodes > 0 {
            s += &format!(
                "{} table nodes could not hold the model's value (the distribution vanishes there)\n",
                self.unrepresented_nodes
            );
        }
        s
    }
}

fn channel_name(l: f64) -> String {
    match l {
        0.0 => "R".into(),
        1.0 => "G".into(),
        2.0 => "B".into(),
        _ => format!("{l} nm"),
    }
}

/// `f(0), …, f(n − 1)` on the machine's cores, in order.
pub(crate) fn par_map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .clamp(1, 64)
        .min(n.max(1));
    if threads == 1 {
        return (0..n).map(f).collect();
    }
    let f = &f;
    let mut parts: Vec<Vec<(usize, T)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| s.spawn(move || (t..n).step_by(threads).map(|i| (i, f(i))).collect()))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let mut out: Vec<Option<T>> = (0..n).map(|_| None).collect();
    for part in parts.iter_mut() {
        for (i, v) in part.drain(..) {
            out[i] = Some(v);
        }
    }
    out.into_iter().flatten().collect()
}

/// The RGL measured-BSDF file of `model`, parameterised by `ndf`.
pub fn rgl(
    model: &(dyn Bxdf + Sync),
    ndf: &NdfSource,
    options: &RglOptions,
) -> Result<Exported, ExportError> {
    rgl::build(model, ndf, options)
}

/// The RGL measured-BSDF file of a material: GGX and Beckmann through their
/// own distribution, every other model through the distribution derived
/// from its retro-reflection.
pub fn rgl_material(spec: &MaterialSpec, options: &RglOptions) -> Result<Exported, ExportError> {
    let model = glossy(spec)?;
    let ndf = ndf_of(spec)?;
    let mut o = options.clone();
    if o.description.is_empty() {
        o.description = describe(spec);
    }
    rgl::build(&*model, &ndf, &o)
}

/// The MERL table of `model` (isotropic models only).
pub fn merl(model: &(dyn Bxdf + Sync), options: &MerlOptions) -> Result<Exported, ExportError> {
    merl::build(model, options)
}

/// The MERL table of a material (refused for an anisotropic one).
pub fn merl_material(spec: &MaterialSpec, options: &MerlOptions) -> Result<Exported, ExportError> {
    let model = glossy(spec)?;
    merl::build(&*model, options)
}

/// Whether `model` is isotropic: unchanged, to 1e-9, when both directions
/// turn together about the normal (probed at three incidences, three
/// rotations and four outgoing directions each, at 550 nm). The exports
/// that assume isotropy (MERL, and RGL tables parameterised by the
/// retro-reflection) ask this of the model itself rather than of its kind.
pub fn is_isotropic(model: &dyn Bxdf) -> bool {
    use param::direction;
    for theta_i in [0.35f64, 0.9, 1.25] {
        let wi = direction(theta_i, 0.0);
        for (t, p) in [
            (theta_i, core::f64::consts::PI),
            (theta_i + 0.05, 3.1),
            (0.5 * theta_i, 2.0),
            (0.3, 0.6),
        ] {
            let wo = direction(t, p);
            let f = model.eval(wi, wo, 550.0);
            for psi in [0.5f64, core::f64::consts::FRAC_PI_2, 2.4] {
                let rot = |w: brdf::DVec3| {
                    let (s, c) = psi.sin_cos();
                    brdf::DVec3::new(c * w.x - s * w.y, s * w.x + c * w.y, w.z)
                };
                let g = model.eval(rot(wi), rot(wo), 550.0);
                if (f - g).abs() > 1e-9 * f.abs().max(g.abs()) + 1e-300 {
                    return false;
                }
            }
        }
    }
    true
}

/// The built model, refusing one that is all delta.
fn glossy(spec: &MaterialSpec) -> Result<brdf::spec::DynBxdf, ExportError> {
    if let ModelSpec::Smooth = spec.model {
        return Err(ExportError::Model(
            "model `smooth` is a perfect mirror: all of its reflection is a delta lobe, which a \
             tabulated BSDF cannot hold (Mitsuba's `conductor` and pbrt's `conductor` with \
             roughness 0 render it exactly)"
                .into(),
        ));
    }
    Ok(spec.build()?)
}

/// The distribution that parameterises a material's RGL table.
pub fn ndf_of(spec: &MaterialSpec) -> Result<NdfSource, ExportError> {
    Ok(match spec.model.microfacet()? {
        Some((d, angle_rad)) => NdfSource::Microfacet(d, angle_rad),
        None => NdfSource::Backscatter,
    })
}

/// `lustre <version>: <material as flat TOML keys>` for the description.
pub fn describe(spec: &MaterialSpec) -> String {
    let keys = toml::to_string(&spec.to_desc())
        .unwrap_or_default()
        .lines()
        .collect::<Vec<_>>()
        .join("; ");
    format!("lustre {} export: {keys}", env!("CARGO_PKG_VERSION"))
}

/// Writes an export atomically (never over one of the program's inputs).
pub fn write(path: &std::path::Path, exported: &Exported) -> Result<(), ExportError> {
    safe_io::write_atomic(path, &exported.bytes)?;
    Ok(())
}
