//! The paper's five samples and the rules that turn a K-correlation surface
//! into parameters for every model (GGX α, two-scale splits), shared by
//! `lustre brdf plot` and `lustre compare`. Models are built through the same
//! JSON-field builder as `lustre brdf eval` (`cmd_brdf::model_spec`), so a
//! plotted curve and an `eval` query of the same parameters are one code path.

use anyhow::anyhow;
use brdf::Bxdf;
use serde_json::{Map, Value, json};

/// Wavelength at which the GGX α and the two-scale cutoffs are fixed (nm);
/// `lustre fit` uses the same default for its cutoffs.
pub const REFERENCE_LAMBDA_NM: f64 = 550.0;

/// One of the paper's samples (physics.md §12; metals as scenes/generate.py).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Name as in physics.md, e.g. "S280".
    pub name: &'static str,
    /// rms height σ, µm.
    pub sigma_um: f64,
    /// KC correlation length Lc, µm.
    pub lc_um: f64,
    /// KC exponent γ.
    pub gamma: f64,
    /// `brdf::Metal` name.
    pub metal: &'static str,
}

/// The five samples of Avolio, d'Eon & Steinberg.
pub const SAMPLES: [Sample; 5] = [
    Sample {
        name: "S808",
        sigma_um: 0.808,
        lc_um: 10.0,
        gamma: 3.5,
        metal: "stainless_steel",
    },
    Sample {
        name: "S280",
        sigma_um: 0.280,
        lc_um: 5.0,
        gamma: 3.0,
        metal: "brass",
    },
    Sample {
        name: "S138",
        sigma_um: 0.138,
        lc_um: 2.0,
        gamma: 2.0,
        metal: "brass",
    },
    Sample {
        name: "S091",
        sigma_um: 0.091,
        lc_um: 20.0,
        gamma: 1.5,
        metal: "brass",
    },
    Sample {
        name: "S027",
        sigma_um: 0.027,
        lc_um: 1.0,
        gamma: 4.0,
        metal: "stainless_steel",
    },
];

/// Looks a sample up by name (case-insensitive), listing the valid names otherwise.
pub fn sample(name: &str) -> anyhow::Result<Sample> {
    SAMPLES
        .iter()
        .copied()
        .find(|s| s.name.eq_ignore_ascii_case(name))
        .ok_or_else(|| {
            let names: Vec<&str> = SAMPLES.iter().map(|s| s.name).collect();
            anyhow!(
                "unknown sample {name:?}; the paper samples are {}",
                names.join(", ")
            )
        })
}

/// k = 2π/λ in rad/µm.
pub fn wavenumber(lambda_nm: f64) -> f64 {
    2000.0 * std::f64::consts::PI / lambda_nm
}

/// GGX α of a KC surface by the slope-space identity of physics.md §7,
/// Lc = 1/(2kα cosθi), at `lambda_nm` and normal incidence: the α whose GGX
/// lobe equals the SSA lobe at the mirror direction.
pub fn ggx_alpha(lc_um: f64, lambda_nm: f64) -> anyhow::Result<f64> {
    Ok(brdf::wave::ggx_kc::ggx_alpha_from_kc_slope_space(
        lc_um,
        wavenumber(lambda_nm),
        1.0,
    )?)
}

/// Exponential-NDF β of the large scale when a KC surface is split at cutoff
/// period Λ = `cutoff_um`: the mean-square slope of the spectrum below
/// ζc = 2π/Λ, ⟨|∇h|²⟩ = ∫_{ζ<ζc} ζ² P(ζ) d²ζ, equals 6β² (as `fit`'s
/// PSD branch). With P = σ²Lc²(γ−1)/(2π)·(1+Lc²ζ²)^−(γ+1)/2 and x = Lc²ζ²:
/// ⟨|∇h|²⟩ = σ²(γ−1)/(2Lc²)·∫₀^X x(1+x)^−(γ+1)/2 dx, X = (Lc ζc)², integrated
/// in s = ln(1+x) (integrand expm1(s)·e^{s(1−γ)/2}, no cancellation) by
/// composite Simpson.
pub fn two_scale_beta(sigma_um: f64, lc_um: f64, gamma: f64, cutoff_um: f64) -> f64 {
    let zc = 2.0 * std::f64::consts::PI / cutoff_um;
    let x_max = (lc_um * zc).powi(2);
    let s_max = x_max.ln_1p();
    // x (1+x)^{-(γ+1)/2} dx with x = e^s − 1, dx = e^s ds: (e^s − 1) e^{s(1−γ)/2} ds.
    let c = (1.0 - gamma) * 0.5;
    let g = |s: f64| s.exp_m1() * (c * s).exp();
    const N: usize = 4096;
    let h = s_max / N as f64;
    let mut acc = g(0.0) + g(s_max);
    for j in 1..N {
        acc += g(j as f64 * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
    }
    let integral = acc * h / 3.0;
    let slope2 = sigma_um * sigma_um * (gamma - 1.0) / (2.0 * lc_um * lc_um) * integral;
    (slope2 / 6.0).sqrt()
}

/// One model of one surface, as `brdf eval` JSON fields plus a legend label.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    /// Legend / row label.
    pub label: String,
    /// `brdf eval` query fields (model, parameters, fresnel), without geometry.
    pub fields: Map<String, Value>,
}

impl ModelSpec {
    /// Builds the model through `brdf eval`'s builder.
    pub fn build(&self) -> anyhow::Result<Box<dyn Bxdf>> {
        let (_, build) = crate::cmd_brdf::model_spec(&self.fields)
            .map_err(|e| anyhow!("{}: field `{}`: {}", self.label, e.field, e.message))?;
        build().map_err(|e| anyhow!("{}: {e}", self.label))
    }

    /// A numeric field (NaN when absent), for CSV columns.
    pub fn num(&self, field: &str) -> f64 {
        self.fields
            .get(field)
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN)
    }

    /// A string field ("" when absent).
    pub fn text(&self, field: &str) -> &str {
        self.fields.get(field).and_then(Value::as_str).unwrap_or("")
    }

    /// Width of the lobe in projected-direction (o⊥) units, for the albedo quadrature.
    pub fn lobe_rho(&self, lambda_nm: f64) -> f64 {
        let wave = 1.0 / (wavenumber(lambda_nm) * self.num("lc_um"));
        let rho = match self.text("model") {
            "ggx" | "beckmann" => self.num("alpha"),
            "two_scale" => self.num("beta").max(wave),
            _ => wave,
        };
        if rho.is_finite() && rho > 0.0 {
            rho.clamp(1e-6, 1.0)
        } else {
            1e-3
        }
    }
}

/// Three significant digits for labels, in exponent form below 0.01.
pub fn short(x: f64) -> String {
    if x.abs() >= 0.01 || x == 0.0 {
        format!("{x:.3}")
    } else {
        format!("{x:.2e}")
    }
}

/// Model names `plot` and `compare` understand.
pub const MODEL_NAMES: [&str; 5] = ["ggx", "beckmann", "ghs_ssa", "ghs", "two_scale"];

/// Parameters of a KC surface for building its models.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Name for titles and file names.
    pub name: String,
    /// σ, µm.
    pub sigma_um: f64,
    /// Lc, µm.
    pub lc_um: f64,
    /// γ.
    pub gamma: f64,
    /// `"none"` or a metal name.
    pub fresnel: String,
    /// GGX/Beckmann α (default: [`ggx_alpha`] at [`REFERENCE_LAMBDA_NM`]).
    pub alpha: f64,
}

impl Surface {
    /// A paper sample with its metal and the slope-space GGX α.
    pub fn from_sample(s: Sample) -> anyhow::Result<Surface> {
        Ok(Surface {
            name: s.name.to_string(),
            sigma_um: s.sigma_um,
            lc_um: s.lc_um,
            gamma: s.gamma,
            fresnel: s.metal.to_string(),
            alpha: ggx_alpha(s.lc_um, REFERENCE_LAMBDA_NM)?,
        })
    }

    fn kc_fields(&self, model: &str) -> Map<String, Value> {
        let v = json!({
            "model": model, "sigma_um": self.sigma_um, "lc_um": self.lc_um,
            "gamma": self.gamma, "fresnel": self.fresnel,
        });
        v.as_object().cloned().unwrap_or_default()
    }

    /// The model `name` of this surface; two-scale splits at `cutoff_multiple`
    /// × [`REFERENCE_LAMBDA_NM`] by the rule of [`two_scale_beta`], with the
    /// surface's own KC as the micro scale (what `fit` recovers when it fits a
    /// KC above the cutoff of an exact KC spectrum).
    pub fn model(&self, name: &str, cutoff_multiple: f64) -> anyhow::Result<ModelSpec> {
        let (label, fields) = match name {
            "ggx" | "beckmann" => {
                let v = json!({"model": name, "alpha": self.alpha, "fresnel": self.fresnel});
                let pretty = if name == "ggx" { "GGX" } else { "Beckmann" };
                (
                    format!("{pretty} (α {})", short(self.alpha)),
                    v.as_object().cloned().unwrap_or_default(),
                )
            }
            "ghs_ssa" => ("GHS SSA".to_string(), self.kc_fields(name)),
            "ghs" => ("full GHS".to_string(), self.kc_fields(name)),
            "two_scale" => {
                let cutoff_um = cutoff_multiple * REFERENCE_LAMBDA_NM * 1e-3;
                let beta = two_scale_beta(self.sigma_um, self.lc_um, self.gamma, cutoff_um);
                let mut f = self.kc_fields(name);
                f.insert("beta".into(), json!(beta));
                (
                    format!("two-scale {cutoff_multiple}λ (β {})", short(beta)),
                    f,
                )
            }
            other => {
                return Err(anyhow!(
                    "unknown model {other:?}; use {}",
                    MODEL_NAMES.join(", ")
                ));
            }
        };
        Ok(ModelSpec { label, fields })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms of ∫₀^X x(1+x)^−a dx: a = 2 (γ = 3) gives ln T + 1/T − 1,
    /// otherwise (T^{2−a} − 1)/(2−a) − (T^{1−a} − 1)/(1−a), T = 1 + X.
    fn beta_closed(sigma: f64, lc: f64, gamma: f64, cutoff: f64) -> f64 {
        let x = (lc * 2.0 * std::f64::consts::PI / cutoff).powi(2);
        let t = 1.0 + x;
        let a = (gamma + 1.0) / 2.0;
        let i = if gamma == 3.0 {
            t.ln() + 1.0 / t - 1.0
        } else {
            (t.powf(2.0 - a) - 1.0) / (2.0 - a) - (t.powf(1.0 - a) - 1.0) / (1.0 - a)
        };
        (sigma * sigma * (gamma - 1.0) / (2.0 * lc * lc) * i / 6.0).sqrt()
    }

    #[test]
    fn two_scale_beta_matches_closed_forms() {
        for s in SAMPLES {
            for m in [50.0, 100.0, 150.0] {
                let cut = m * 0.55;
                let got = two_scale_beta(s.sigma_um, s.lc_um, s.gamma, cut);
                let want = beta_closed(s.sigma_um, s.lc_um, s.gamma, cut);
                assert!(
                    (got / want - 1.0).abs() < 1e-9,
                    "{} {m}: {got} vs {want}",
                    s.name
                );
            }
        }
    }

    #[test]
    fn two_scale_beta_tends_to_full_slope_for_gamma_above_3() {
        // γ > 3: the full mean-square slope 2σ²/(Lc²(γ−3)) = 6β² as Λ → 0.
        let s = SAMPLES[0];
        let full = (2.0 * s.sigma_um.powi(2) / (s.lc_um.powi(2) * (s.gamma - 3.0)) / 6.0).sqrt();
        let b = two_scale_beta(s.sigma_um, s.lc_um, s.gamma, 1e-8);
        assert!((b / full - 1.0).abs() < 1e-3, "{b} vs {full}");
    }

    #[test]
    fn ggx_alpha_is_slope_space_identity() {
        let a = ggx_alpha(5.0, 550.0).unwrap();
        assert!((a - 0.55 / (4.0 * std::f64::consts::PI * 5.0)).abs() < 1e-15);
    }
}
