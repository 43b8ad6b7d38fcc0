//! The material file `lustre fit` writes and scenes `include`: one typed schema for the
//! writer and every reader (the renderer, `compare`, `preview`, `judge`, `brdf eval`), so a
//! renamed or misspelt key fails to compile in the writer and is an error naming its line
//! in a reader.
//!
//! `[material]` is a [`MaterialDesc`] offering every model at once (the K-correlation
//! parameters, the NDF roughness, the metal, the model the file recommends);
//! `[two_scale.NAME]` are the splits for `model = "two_scale"`, `[psd]` the table for
//! `model = "measured_psd"`. The other tables are the fit's diagnostics: a reader needs
//! none of them, so each of their keys may be missing (a file from an older `lustre fit`),
//! but no table takes keys it does not know. Units as everywhere (µm, rad/µm, µm⁴).

use super::{FileLoader, MaterialDesc, MaterialSpec, ModelKind, SpecError};
use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;
use serde::{Deserialize, Serialize};

/// The name under which a description's `psd_csv` refers to the file's own `[psd]`.
pub const OWN_PSD: &str = "[psd]";

/// The name under which `psd_csv` refers to the file's `[psd.destretched]` (the PSD of the
/// de-stretched frame the stretched measured-PSD models read).
pub const OWN_PSD_DESTRETCHED: &str = "[psd.destretched]";

/// The name under which `psd_map` refers to the file's `[psd.map]` (the 2-D PSD
/// `model = "measured_psd2d_ssa"` and `"measured_psd2d"` read).
pub const OWN_PSD_MAP: &str = "[psd.map]";

impl MaterialFile {
    /// The `[material]` a scene's `desc` builds on when it includes this file: for
    /// `two_scale`, with the split `desc.cutoff` chooses (or the only one) over it; for
    /// `measured_psd`, naming the file's own `[psd]` ([`OWN_PSD`]). Also the split's name.
    pub fn base_for(
        &self,
        desc: &MaterialDesc,
    ) -> Result<(MaterialDesc, Option<String>), SpecError> {
        let mut base = self.material.clone();
        if base.include.is_some() || base.cutoff.is_some() {
            return Err(SpecError::new(
                "include",
                "[material] of a material file cannot itself use `include` or `cutoff`",
            ));
        }
        let model = desc.model.or(base.model);
        let mut split = None;
        if model == Some(ModelKind::TwoScale) {
            let names: Vec<&str> = self.two_scale.names().collect();
            let listed = if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            };
            let chosen = match (&desc.cutoff, names.as_slice()) {
                (Some(c), _) => c.as_str(),
                (None, [only]) => only,
                (None, _) => {
                    return Err(SpecError::new(
                        "cutoff",
                        format!(
                            "choose a two-scale split with `cutoff = \"NAME\"`; the file has: {listed}"
                        ),
                    ));
                }
            };
            let Some(t) = self.two_scale.get(chosen) else {
                return Err(SpecError::new(
                    "cutoff",
                    format!("no [two_scale.{chosen}] table; the file has: {listed}"),
                ));
            };
            // The split's micro scale replaces the whole-surface fit.
            base.beta = Some(t.beta);
            base.sigma_um = Some(t.sigma_um);
            base.lc_um = Some(t.lc_um);
            base.gamma = Some(t.gamma);
            split = Some(chosen.to_string());
        }
        let measured = matches!(
            model,
            Some(
                ModelKind::MeasuredPsd
                    | ModelKind::MeasuredPsdSsaAniso
                    | ModelKind::MeasuredPsdAniso
            )
        );
        if measured && base.psd_csv.is_none() && self.psd.is_some() {
            let stretched = matches!(
                model,
                Some(ModelKind::MeasuredPsdSsaAniso | ModelKind::MeasuredPsdAniso)
            );
            base.psd_csv = Some(
                if stretched {
                    OWN_PSD_DESTRETCHED
                } else {
                    OWN_PSD
                }
                .to_string(),
            );
        }
        if matches!(
            model,
            Some(ModelKind::MeasuredPsd2dSsa | ModelKind::MeasuredPsd2d)
        ) && base.psd_map.is_none()
        {
            base.psd_map = Some(OWN_PSD_MAP.to_string());
            // The grid is in the scan's own axes: `[material].angle_deg` is the ellipse's.
            base.angle_deg = None;
        }
        Ok((base, split))
    }

    /// The typed material of a scene's `desc` over this file, as an `include` of it
    /// builds it: [`MaterialFile::base_for`], then [`MaterialDesc::resolve`], with `files`
    /// reading what the descriptions name and the file's `[psd]` answering for [`OWN_PSD`].
    pub fn resolve(
        &self,
        desc: &MaterialDesc,
        files: &mut dyn FileLoader,
    ) -> Result<MaterialSpec, SpecError> {
        let (base, _) = self.base_for(desc)?;
        desc.resolve(
            Some(&base),
            &mut WithOwnPsd {
                psd: self.psd.as_ref(),
                files,
            },
        )
    }
}

/// One material a file offers: what a scene writes over an `include` of the file to draw
/// it (`model`, and `cutoff` for a two-scale split).
#[derive(Clone, Debug, PartialEq)]
pub struct Offer {
    /// `ggx`, …, `two_scale cutoff_50`; `[material] (ghs)` for the file's own model.
    pub name: String,
    /// The model; `None` for the file's own (a bare include).
    pub model: Option<ModelKind>,
    /// The two-scale split.
    pub cutoff: Option<String>,
}

impl Offer {
    /// The description a scene gives over the include.
    pub fn desc(&self) -> MaterialDesc {
        MaterialDesc {
            model: self.model,
            cutoff: self.cutoff.clone(),
            ..MaterialDesc::default()
        }
    }
}

impl MaterialFile {
    /// Every material the file offers: its own model, GGX, Beckmann, GHS SSA, the full GHS
    /// where γ ≥ 1.05 (below, its series is not representable), the anisotropic full GHS
    /// where the file has the two correlation lengths, the measured PSD when the table is
    /// usable, and two-scale at each split.
    pub fn offered(&self) -> Vec<Offer> {
        let offer = |m: ModelKind, cutoff: Option<&str>| Offer {
            name: match cutoff {
                Some(c) => format!("{} {c}", m.name()),
                None => m.name().to_string(),
            },
            model: Some(m),
            cutoff: cutoff.map(str::to_string),
        };
        let mut out = Vec::new();
        if let Some(m) = self.material.model {
            out.push(Offer {
                name: format!("[material] ({})", m.name()),
                model: None,
                cutoff: None,
            });
        }
        let full_ok =
            (self.material.gamma).is_some_and(|g| g >= crate::statistics::kc::GAMMA_MIN_FULL);
        for m in [
            ModelKind::Ggx,
            ModelKind::Beckmann,
            ModelKind::GhsSsa,
            ModelKind::Ghs,
        ] {
            if m != ModelKind::Ghs || full_ok {
                out.push(offer(m, None));
            }
        }
        if full_ok && self.material.lx_um.is_some() && self.material.ly_um.is_some() {
            out.push(offer(ModelKind::GhsAniso, None));
        }
        if self.psd.as_ref().is_some_and(|p| p.usable) {
            out.push(offer(ModelKind::MeasuredPsd, None));
        }
        let destretched = (self.psd.as_ref())
            .and_then(|p| p.destretched.as_ref())
            .is_some_and(|d| d.usable);
        if destretched && self.material.lx_um.is_some() && self.material.ly_um.is_some() {
            out.push(offer(ModelKind::MeasuredPsdAniso, None));
        }
        let map = (self.psd.as_ref())
            .and_then(|p| p.map.as_ref())
            .is_some_and(|m| m.usable);
        if map {
            out.push(offer(ModelKind::MeasuredPsd2dSsa, None));
            out.push(offer(ModelKind::MeasuredPsd2d, None));
        }
        for name in self.two_scale.names() {
            out.push(offer(ModelKind::TwoScale, Some(name)));
        }
        out
    }
}

/// A loader that answers [`OWN_PSD`] with the file's `[psd]` and passes the rest on.
pub struct WithOwnPsd<'a> {
    /// The file's table.
    pub psd: Option<&'a PsdTable>,
    /// Everything else.
    pub files: &'a mut dyn FileLoader,
}

impl FileLoader for WithOwnPsd<'_> {
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
        self.files.nk_table(path)
    }
    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
        match self.psd {
            Some(t) if path == OWN_PSD => Ok((t.zeta_rad_per_um.clone(), t.p_um4.clone())),
            Some(t) if path == OWN_PSD_DESTRETCHED => match &t.destretched {
                Some(d) => Ok((d.zeta_rad_per_um.clone(), d.p_um4.clone())),
                None => Err(format!(
                    "the file has no {OWN_PSD_DESTRETCHED} table (`lustre fit` writes one for \
                     maps it flags anisotropic)"
                )),
            },
            _ => self.files.psd_table(path),
        }
    }
    fn reflectance_table(&mut self, path: &str) -> Result<Vec<[f64; 2]>, String> {
        self.files.reflectance_table(path)
    }
    fn psd_map(&mut self, path: &str) -> Result<super::Psd2dSpec, String> {
        match self.psd.map(|t| &t.map) {
            Some(Some(m)) if path == OWN_PSD_MAP => Ok(m.spec()),
            Some(None) if path == OWN_PSD_MAP => Err(format!(
                "the file has no {OWN_PSD_MAP} table (`lustre fit` writes one for maps whose \
                 2-D PSD is not elliptical: [reliability].psd_destretched)"
            )),
            _ => self.files.psd_map(path),
        }
    }
}

/// A `lustre fit` material file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    /// Where the numbers come from.
    #[serde(default)]
    pub provenance: Provenance,
    /// The material keys (every model's parameters; `model` the recommended one).
    pub material: MaterialDesc,
    /// Fit diagnostics: uncertainties, residuals, statistics.
    #[serde(default)]
    pub fit: FitDiagnostics,
    /// Which parts are unreliable, and why.
    #[serde(default)]
    pub reliability: Reliability,
    /// What levelling removed.
    #[serde(default)]
    pub form: Form,
    /// Direction dependence (maps only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anisotropy: Option<Anisotropy>,
    /// K-correlation fit of the radial 2D PSD (maps only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kc_2d: Option<Kc2d>,
    /// The two-scale splits, `cutoff_50` etc., in the order written.
    #[serde(default)]
    pub two_scale: Named<Split>,
    /// The tabulated PSD for `model = "measured_psd"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd: Option<PsdTable>,
}

/// Named tables (`[two_scale.cutoff_50]`, …) kept in the order they are written.
#[derive(Clone, Debug, PartialEq)]
pub struct Named<T>(pub Vec<(String, T)>);

impl<T> Default for Named<T> {
    fn default() -> Self {
        Named(Vec::new())
    }
}

impl<T> Named<T> {
    /// The table of that name.
    pub fn get(&self, name: &str) -> Option<&T> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, t)| t)
    }

    /// The names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(n, _)| n.as_str())
    }
}

impl<T: Serialize> Serialize for Named<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Named<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(core::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for V<T> {
            type Value = Named<T>;
            fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
                f.write_str("a table of named tables")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut m: A,
            ) -> Result<Named<T>, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = m.next_entry::<String, T>()? {
                    if out.iter().any(|(n, _): &(String, T)| *n == k) {
                        return Err(serde::de::Error::custom(alloc::format!(
                            "the table `{k}` is given twice"
                        )));
                    }
                    out.push((k, v));
                }
                Ok(Named(out))
            }
        }
        d.deserialize_map(V(core::marker::PhantomData))
    }
}

/// `[provenance]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Provenance {
    /// Scan file.
    pub file: String,
    /// SHA-256 of the scan file.
    pub sha256: String,
    /// Frequency range of the material KC fit [cycles/m] (absent when the fit had none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_f_range_per_m: Option<[f64; 2]>,
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
    /// What the reader and the analysis had to assume, change or skip.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
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

/// `[fit]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitDiagnostics {
    /// Standard error of σ [µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma_um_err: Option<f64>,
    /// Standard error of Lc [µm].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lc_um_err: Option<f64>,
    /// Standard error of γ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_err: Option<f64>,
    /// 1D-form length `L = 2π·Lc` [µm] of the data README.
    pub l_1d_um: f64,
    /// Rms natural-log residual of the KC fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_rms_log_residual: Option<f64>,
    /// PSD points in the KC fit.
    pub kc_points: usize,
    /// True if the KC fit is not meaningful.
    pub kc_degenerate: bool,
    /// Why, when degenerate; `[material]` then holds the bounded best estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_reason: Option<String>,
    /// High-frequency power law of the fitted band.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kc_asymptote: Option<Asymptote>,
    /// Sq (Rq for profiles) [µm].
    pub sq_um: f64,
    /// Rms slope (Sdq; Rdq for profiles).
    pub rms_slope: f64,
    /// Rms log residual of the GGX NDF fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_ggx_rms_log_residual: Option<f64>,
    /// Rms log residual of the Beckmann NDF fit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_beckmann_rms_log_residual: Option<f64>,
    /// Beckmann α from the slope second moment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_beckmann_moment: Option<f64>,
}

/// `[fit.kc_asymptote]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Asymptote {
    /// `P1 ∝ f^(−exponent)` over the top half of the fitted band.
    pub exponent: f64,
    /// Prefactor A of `P1 = A·f^(−exponent)`, SI (P1 in m³, f in cycles/m).
    pub prefactor_si: f64,
    /// Frequencies used [cycles/m].
    pub f_range_per_m: [f64; 2],
}

/// `[reliability]`: one entry per part, `"ok"` or the reason it should not be trusted.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Reliability {
    /// The K-correlation parameters of `[material]`.
    pub kc: String,
    /// The NDF roughness `alpha`/`alpha_beckmann` (and `alpha_x`/`alpha_y`).
    pub alpha: String,
    /// The `[psd]` table for `model = "measured_psd"`.
    pub psd: String,
    /// What `model = "measured_psd"` assumes outside the band the `[psd]` table covers
    /// (the renderer continues it there; see `crate::statistics::TabulatedPsd`).
    pub psd_extrapolation: String,
    /// The `[psd.destretched]` table for `model = "measured_psd_aniso"`: `"ok"`, why it
    /// should not be trusted (e.g. a 2-D PSD that is not constant on ellipses), or why it
    /// was not written.
    pub psd_destretched: String,
    /// The two-scale tables.
    pub two_scale: String,
    /// Form left in the residual after levelling.
    pub form: String,
    /// Anisotropy that the isotropic models ignore.
    pub anisotropy: String,
    /// Whether the K-correlation σ accounts for the measured height variance (Sq²).
    pub variance: String,
    /// Why `[material].model` is what it is.
    pub model: String,
    /// A scan mostly invalid, cropped or filled on request (`--invalid`).
    pub invalid: String,
    /// Heights far outside the distribution (spikes, corrupted values), flagged or masked.
    pub outliers: String,
    /// An Sq or RMS slope implausible for a metal surface: a unit is probably wrong.
    pub units: String,
    /// The parts flagged above, for scripts.
    pub unreliable: Vec<String>,
}

/// `[form]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Form {
    /// `none`, `line`, `plane`, `poly2` or `poly3`.
    pub level: String,
    /// Rms of what was removed [µm].
    pub removed_rms_um: f64,
    /// Fitted terms `[i, j, c]`: `c·Xⁱ·Yʲ` with X, Y in µm from the map centre and c in
    /// µm^(1−i−j).
    pub terms: Vec<[f64; 3]>,
    /// Fraction of the residual variance the next polynomial degree would remove.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_form_fraction: Option<f64>,
    /// Set when the residual still shows form.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// `[anisotropy]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Anisotropy {
    /// Rms slope along x.
    pub rms_slope_x: f64,
    /// Rms slope along y.
    pub rms_slope_y: f64,
    /// Larger over smaller of the two.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio_xy: Option<f64>,
    /// Principal rms slopes `[steepest, across it]`.
    pub principal_rms_slopes: [f64; 2],
    /// Principal ratio (> 1.5: anisotropic).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    /// Direction of the steepest slope (`alpha_ggx[0]`), degrees from +x towards +y; close
    /// to `[material].angle_deg`, the axis of `alpha_x` (which is the 2-D PSD fit's φ₀
    /// where that fit was made).
    pub slope_direction_deg: f64,
    /// Direction of the lay (grooves, `alpha_ggx[1]`), degrees from +x towards +y.
    pub lay_direction_deg: f64,
    /// Rms slopes along x and y from the x- and y-PSDs.
    pub psd_rms_slopes: [f64; 2],
    /// True when the 2-D PSD fit's Ly/Lx exceeds 1.5 (where that fit is sound; else `ratio`).
    pub anisotropic: bool,
    /// GGX α along the principal axes (`[material].alpha_x`/`alpha_y` are the same split
    /// along `[material].angle_deg`).
    pub alpha_ggx: [f64; 2],
    /// Beckmann α along the principal axes (`beckmann` reads the principal Beckmann pair
    /// from here only by hand: `alpha_x`, `alpha_y` and `angle_deg = slope_direction_deg`).
    pub alpha_beckmann: [f64; 2],
    /// Set for anisotropic surfaces.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
}

/// `[kc_2d]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Kc2d {
    /// σ [µm].
    pub sigma_um: f64,
    /// Lc [µm].
    pub lc_um: f64,
    /// γ.
    pub gamma: f64,
    /// Standard errors `[σ µm, Lc µm, γ]` (absent unless all three are known).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stderr: Option<[f64; 3]>,
    /// Fitted ζ range [rad/µm].
    pub fit_zeta_range_rad_per_um: [f64; 2],
    /// Rms log residual.
    pub rms_log_residual: f64,
    /// Degenerate flag.
    pub degenerate: bool,
}

/// `[two_scale.NAME]`: a split's parameters (what `model = "two_scale"` reads) and the
/// fit's notes on it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Split {
    /// Exponential-NDF β of the large scale.
    pub beta: f64,
    /// `map`, `psd` or `unresolved`.
    #[serde(default)]
    pub beta_source: String,
    /// Residual KC σ [µm].
    pub sigma_um: f64,
    /// Residual KC Lc [µm].
    pub lc_um: f64,
    /// Residual KC γ.
    pub gamma: f64,
    /// Cutoff period [µm].
    #[serde(default)]
    pub cutoff_um: f64,
    /// Residual KC fit range [cycles/m] (absent when the fit had none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit_f_range_per_m: Option<[f64; 2]>,
    /// Degenerate flag of the residual fit.
    #[serde(default)]
    pub kc_degenerate: bool,
    /// What is unreliable in this split (absent when it is sound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub problem: Option<String>,
}

/// `[psd]`: the table `model = "measured_psd"` reads, and the fit's notes on it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PsdTable {
    /// How the table was made.
    #[serde(default)]
    pub source: String,
    /// ∫ P d²ζ over the tabulated range (trapezoid, µm²); compare with `sq_um²`.
    #[serde(default)]
    pub integral_um2: f64,
    /// True when the renderer accepts the table (`model = "measured_psd"`).
    #[serde(default)]
    pub usable: bool,
    /// Exponent of the power-law tail the table ends in.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tail_exponent: Option<f64>,
    /// Radial frequency ζ [rad/µm].
    pub zeta_rad_per_um: Vec<f64>,
    /// Isotropic 2D PSD [µm⁴].
    pub p_um4: Vec<f64>,
    /// The radial PSD of the de-stretched frame, for the stretched measured-PSD models
    /// (maps flagged anisotropic only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub destretched: Option<DestretchedPsd>,
    /// The 2-D PSD on a grid, for `model = "measured_psd2d_ssa"` and `"measured_psd2d"`
    /// (maps whose 2-D PSD is not elliptical only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<PsdMap>,
}

/// `[psd.map]`: a map's 2-D PSD on a regular grid of its own axes (x along a scan line),
/// what `model = "measured_psd2d_ssa"` and `"measured_psd2d"` read (physics.md §15.4).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PsdMap {
    /// How the table was made.
    #[serde(default)]
    pub source: String,
    /// True when the renderer accepts the table.
    #[serde(default)]
    pub usable: bool,
    /// The share of σ² beyond the grid, in the assumed power-law continuation.
    #[serde(default)]
    pub tail_fraction: f64,
    /// Exponent α of that continuation, P ∝ s^−α along each ray from the grid's edge.
    pub tail_exponent: f64,
    /// Nodes on each half of the ζx axis (2·half_nx + 1 columns).
    pub half_nx: usize,
    /// Node rows above ζy = 0 (half_ny + 1 rows of the half plane ζy ≥ 0).
    pub half_ny: usize,
    /// Grid step along ζx [rad/µm].
    pub dzx_rad_per_um: f64,
    /// Grid step along ζy [rad/µm].
    pub dzy_rad_per_um: f64,
    /// P₂ at the nodes [µm⁴], rows ζy = 0, Δζy, …, each from ζx = −half_nx·Δζx up.
    pub p_um4: Vec<f64>,
}

impl PsdMap {
    /// The model's description of the table (in the grid's own axes).
    pub fn spec(&self) -> super::Psd2dSpec {
        super::Psd2dSpec {
            half_nx: self.half_nx,
            half_ny: self.half_ny,
            dzx_rad_per_um: self.dzx_rad_per_um,
            dzy_rad_per_um: self.dzy_rad_per_um,
            psd_um4: self.p_um4.clone(),
            tail_exponent: self.tail_exponent,
            angle_deg: 0.0,
        }
    }
}

/// `[psd.destretched]`: the radial PSD of a map seen in the frame where its fitted
/// ellipse (`[material]` `lx_um`, `ly_um`, `angle_deg`) is a circle, areas kept
/// (physics.md §15.2), what `model = "measured_psd_aniso"` reads.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DestretchedPsd {
    /// How the table was made.
    #[serde(default)]
    pub source: String,
    /// True when the renderer accepts the table.
    #[serde(default)]
    pub usable: bool,
    /// Rms in ln of the 2-D periodogram's polar cells against the elliptical model
    /// (the radial table stretched back); compare with the sampling scatter in `source`.
    #[serde(default)]
    pub rms_log_residual: f64,
    /// Radial frequency ζ of the de-stretched frame [rad/µm].
    pub zeta_rad_per_um: Vec<f64>,
    /// Its PSD [µm⁴].
    pub p_um4: Vec<f64>,
}
