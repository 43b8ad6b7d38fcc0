//! The material file: a TOML document the renderer can `include`, holding every model's
//! parameters (lengths in µm, angles in degrees) and the provenance of the fit.
//!
//! Length conventions: `lc_um` is the Matérn range Lc of physics.md §2 (rad convention);
//! the reference-table length of the 1D form is `2π·lc_um` and is written as
//! `[fit].l_1d_um`. The `[psd]` table is the isotropic 2D PSD in rad/µm with
//! `∫ P d²ζ = σ²` (µm⁴).

use crate::pipeline::Analysis;
use crate::two_scale::BetaSource;
use crate::{FitError, sha256};
use serde::Serialize;
use std::path::Path;

const UM: f64 = 1e6;

/// Inputs that are not part of the analysis.
#[derive(Debug, Clone)]
pub struct Provenance<'a> {
    /// Scan file name as given.
    pub file: &'a str,
    /// Raw bytes of the scan file (for the checksum).
    pub bytes: &'a [u8],
    /// Stylus profile file and bytes, if merged.
    pub stylus: Option<(&'a str, &'a [u8])>,
    /// Merge cutoff [rad/µm].
    pub merge_cutoff_rad_per_um: f64,
    /// Metal name for `[material].metal`.
    pub metal: &'a str,
    /// Model name for `[material].model`.
    pub model: &'a str,
}

/// The TOML document.
#[derive(Debug, Serialize)]
pub struct MaterialFile {
    /// Where the numbers come from.
    pub provenance: ProvenanceTable,
    /// The renderer's material keys.
    pub material: MaterialTable,
    /// Fit diagnostics: uncertainties, residuals, statistics.
    pub fit: FitTable,
    /// K-correlation fit of the radial 2D PSD (maps only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_2d: Option<KcTable>,
    /// One table per cutoff, `cutoff_50` etc., in the order given.
    pub two_scale: Ordered<TwoScaleTable>,
    /// Tabulated PSD for the measured-PSD model.
    pub psd: PsdTable,
}

/// Named tables serialised as a map in insertion order.
#[derive(Debug)]
pub struct Ordered<T>(pub Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// `[provenance]`.
#[derive(Debug, Serialize)]
pub struct ProvenanceTable {
    /// Scan file.
    pub file: String,
    /// SHA-256 of the scan file.
    pub sha256: String,
    /// Frequency range of the material KC fit [cycles/m].
    pub fit_f_range_per_m: [f64; 2],
    /// Tool and version.
    pub tool: String,
    /// Reader used.
    pub format: String,
    /// Channel read.
    pub channel: String,
    /// Grid size `[nx, ny]`.
    pub grid: [usize; 2],
    /// Pixel spacing `[dx, dy]` [µm].
    pub pixel_um: [f64; 2],
    /// Preparation steps.
    pub levelling: String,
    /// Invalid points filled by harmonic interpolation.
    pub filled_points: usize,
    /// Stylus profile merged below the cutoff.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stylus_file: Option<String>,
    /// SHA-256 of the stylus file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stylus_sha256: Option<String>,
    /// AFM/stylus merge cutoff [rad/µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_cutoff_rad_per_um: Option<f64>,
}

/// `[material]`.
#[derive(Debug, Serialize)]
pub struct MaterialTable {
    /// Metal name.
    pub metal: String,
    /// Default model.
    pub model: String,
    /// KC σ [µm].
    pub sigma_um: f64,
    /// KC Matérn range Lc [µm].
    pub lc_um: f64,
    /// KC γ.
    pub gamma: f64,
    /// GGX α.
    pub alpha: f64,
    /// Beckmann α.
    pub alpha_beckmann: f64,
}

/// `[fit]`.
#[derive(Debug, Serialize)]
pub struct FitTable {
    /// Standard error of σ [µm].
    pub sigma_um_err: f64,
    /// Standard error of Lc [µm].
    pub lc_um_err: f64,
    /// Standard error of γ.
    pub gamma_err: f64,
    /// README 1D-form length `L = 2π·Lc` [µm].
    pub l_1d_um: f64,
    /// Rms natural-log residual of the KC fit.
    pub kc_rms_log_residual: f64,
    /// PSD points in the KC fit.
    pub kc_points: usize,
    /// True if the KC fit is not meaningful.
    pub kc_degenerate: bool,
    /// Sq (Rq for profiles) [µm].
    pub sq_um: f64,
    /// Rms slope (Sdq; Rdq for profiles).
    pub rms_slope: f64,
    /// Rms log residual of the GGX NDF fit.
    pub alpha_ggx_rms_log_residual: f64,
    /// Rms log residual of the Beckmann NDF fit.
    pub alpha_beckmann_rms_log_residual: f64,
    /// Beckmann α from the slope second moment.
    pub alpha_beckmann_moment: f64,
}

/// `[kc_2d]`.
#[derive(Debug, Serialize)]
pub struct KcTable {
    /// σ [µm].
    pub sigma_um: f64,
    /// Lc [µm].
    pub lc_um: f64,
    /// γ.
    pub gamma: f64,
    /// Standard errors `[σ µm, Lc µm, γ]`.
    pub stderr: [f64; 3],
    /// Fitted ζ range [rad/µm].
    pub fit_zeta_range_rad_per_um: [f64; 2],
    /// Rms log residual.
    pub rms_log_residual: f64,
    /// Degenerate flag.
    pub degenerate: bool,
}

/// `[two_scale.cutoff_N]`.
#[derive(Debug, Serialize)]
pub struct TwoScaleTable {
    /// Exponential-NDF β of the large scale.
    pub beta: f64,
    /// `map`, `psd` or `unresolved`.
    pub beta_source: String,
    /// Residual KC σ [µm].
    pub sigma_um: f64,
    /// Residual KC Lc [µm].
    pub lc_um: f64,
    /// Residual KC γ.
    pub gamma: f64,
    /// Cutoff period [µm].
    pub cutoff_um: f64,
    /// Residual KC fit range [cycles/m].
    pub fit_f_range_per_m: [f64; 2],
    /// Degenerate flag of the residual fit.
    pub kc_degenerate: bool,
}

/// `[psd]`.
#[derive(Debug, Serialize)]
pub struct PsdTable {
    /// How the table was made.
    pub source: String,
    /// ∫ P d²ζ over the tabulated range (trapezoid, µm²); compare with `sq_um²`.
    pub integral_um2: f64,
    /// Radial frequency ζ [rad/µm].
    pub zeta_rad_per_um: Vec<f64>,
    /// Isotropic 2D PSD [µm⁴].
    pub p_um4: Vec<f64>,
}

fn finite(v: f64) -> f64 {
    if v.is_finite() { v } else { -1.0 }
}

/// Build the document.
pub fn build(a: &Analysis, prov: &Provenance<'_>) -> MaterialFile {
    let k = a.kc.params;
    let zeta: Vec<f64> = a.table.0.zeta.iter().map(|z| z / UM).collect();
    let p: Vec<f64> = a.table.0.p.iter().map(|p| p * UM.powi(4)).collect();
    let mut integral = 0.0;
    for i in 1..zeta.len() {
        let f = |j: usize| 2.0 * std::f64::consts::PI * zeta[j] * p[j];
        integral += 0.5 * (f(i) + f(i - 1)) * (zeta[i] - zeta[i - 1]);
    }
    let two_scale = Ordered(
        a.two_scale
            .iter()
            .map(|t| {
                (
                    format!("cutoff_{}", t.multiple.round() as i64),
                    TwoScaleTable {
                        beta: t.beta,
                        beta_source: match t.beta_source {
                            BetaSource::Map => "map",
                            BetaSource::Psd => "psd",
                            BetaSource::Unresolved => "unresolved",
                        }
                        .into(),
                        sigma_um: t.kc.params.sigma * UM,
                        lc_um: t.kc.params.lc * UM,
                        gamma: t.kc.params.gamma,
                        cutoff_um: t.cutoff * UM,
                        fit_f_range_per_m: [t.kc.range.0, t.kc.range.1],
                        kc_degenerate: t.kc.degenerate,
                    },
                )
            })
            .collect(),
    );
    MaterialFile {
        provenance: ProvenanceTable {
            file: prov.file.to_string(),
            sha256: sha256::hex(prov.bytes),
            fit_f_range_per_m: [a.kc.range.0, a.kc.range.1],
            tool: format!("lustre fit {}", env!("CARGO_PKG_VERSION")),
            format: a.scan.format.to_string(),
            channel: a.scan.channel.clone(),
            grid: [a.scan.nx, a.scan.ny],
            pixel_um: [a.scan.dx * UM, a.scan.dy * UM],
            levelling: "harmonic fill of invalid points, least-squares plane".into(),
            filled_points: a.filled,
            stylus_file: prov.stylus.map(|s| s.0.to_string()),
            stylus_sha256: prov.stylus.map(|s| sha256::hex(s.1)),
            merge_cutoff_rad_per_um: prov.stylus.map(|_| prov.merge_cutoff_rad_per_um),
        },
        material: MaterialTable {
            metal: prov.metal.to_string(),
            model: prov.model.to_string(),
            sigma_um: k.sigma * UM,
            lc_um: k.lc * UM,
            gamma: k.gamma,
            alpha: a.ndf.alpha_ggx.0,
            alpha_beckmann: a.ndf.alpha_beckmann.0,
        },
        fit: FitTable {
            sigma_um_err: finite(a.kc.stderr.sigma * UM),
            lc_um_err: finite(a.kc.stderr.lc * UM),
            gamma_err: finite(a.kc.stderr.gamma),
            l_1d_um: k.l_cycles() * UM,
            kc_rms_log_residual: a.kc.rms_log_residual,
            kc_points: a.kc.points,
            kc_degenerate: a.kc.degenerate,
            sq_um: a.stats.sq * UM,
            rms_slope: a.stats.rms_slope(),
            alpha_ggx_rms_log_residual: a.ndf.alpha_ggx.1,
            alpha_beckmann_rms_log_residual: a.ndf.alpha_beckmann.1,
            alpha_beckmann_moment: a.ndf.alpha_beckmann_moment,
        },
        kc_2d: a.kc_2d.map(|f| KcTable {
            sigma_um: f.params.sigma * UM,
            lc_um: f.params.lc * UM,
            gamma: f.params.gamma,
            stderr: [
                finite(f.stderr.sigma * UM),
                finite(f.stderr.lc * UM),
                finite(f.stderr.gamma),
            ],
            fit_zeta_range_rad_per_um: [f.range.0 / UM, f.range.1 / UM],
            rms_log_residual: f.rms_log_residual,
            degenerate: f.degenerate,
        }),
        two_scale,
        psd: PsdTable {
            source: a.table.1.to_string(),
            integral_um2: integral,
            zeta_rad_per_um: zeta,
            p_um4: p,
        },
    }
}

/// Serialise with the header comment.
pub fn to_toml(doc: &MaterialFile) -> Result<String, FitError> {
    let body = toml::to_string(doc).map_err(|e| FitError::data("material file", e.to_string()))?;
    let mut out = String::from(
        "# written by lustre fit\n\
         # Units: lengths in µm, angles in degrees, PSD in rad/µm with ∫P d²ζ = σ² (physics.md §1–2).\n\
         # lc_um is the Matérn range Lc; the 1D-form length of the data README is 2π·lc_um.\n",
    );
    if doc.fit.kc_degenerate {
        out.push_str("# WARNING: the K-correlation fit is degenerate (see [fit]); prefer model = \"measured_psd\".\n");
    }
    out.push_str(&body);
    Ok(out)
}

/// Write `text` to `path` atomically (temporary file in the same directory, then rename).
pub fn write_atomic(path: &Path, text: &str) -> Result<(), FitError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "material".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let err = |source| FitError::Write {
        file: path.to_path_buf(),
        source,
    };
    std::fs::write(&tmp, text).map_err(err)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        err(e)
    })
}
