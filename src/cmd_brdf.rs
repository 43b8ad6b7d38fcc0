//! `lustre brdf …`: query the BRDF models.
//!
//! `lustre brdf eval` reads JSON lines on stdin, one query per line, and
//! writes one JSON line per query on stdout, in order:
//!
//! ```text
//! {"model": "ggx"|"beckmann"|"ghs_ssa"|"ghs"|"two_scale",
//!  "lambda_nm": 550, "theta_i_deg": 30, "theta_o_deg": 30, "phi_o_deg": 180,
//!  "alpha": 0.1,                                  (ggx, beckmann)
//!  "sigma_um": 0.1, "lc_um": 5, "gamma": 2.5,     (ghs_ssa, ghs, two_scale)
//!  "energy": "raw"|"krywonos"|"sigma_rel",        (ghs_ssa, ghs; default raw)
//!  "beta": 0.1,                                   (two_scale: exponential NDF scale)
//!  "coherent": "macro_ndf"|"delta",               (two_scale; default macro_ndf)
//!  "fresnel": "none"|<metal>, "metal": <metal>}
//! → {"f": <glossy BRDF, sr⁻¹>, "specular_weight": <delta weight>, "pdf": <sampling pdf of o, sr⁻¹>}
//! ```
//!
//! Geometry follows physics.md §1: i = (sinθi, 0, cosθi) at azimuth 0,
//! o = (sinθo cosφo, sinθo sinφo, cosθo), so the mirror direction is
//! φo = 180°. Fresnel: `"fresnel": "none"` gives R ≡ 1; `"fresnel": <metal>`
//! uses that metal's measured n, κ (names as `brdf::Metal::from_name`:
//! cu, au, ag, al, fe, cr, brass, stainless_steel and aliases). Without a
//! `fresnel` field the `metal` field is used; with neither the line is an
//! error naming `fresnel` (no silent default material).
//!
//! A line that cannot be served gets `{"error": "...", "field": "<name>"}`
//! (`"field": "line"` for malformed JSON) and the stream goes on. Built
//! models are cached by their parameters, so a stream of queries on one
//! material builds its tables once.

use std::collections::HashMap;
use std::io::{BufRead, BufWriter, Write};

use anyhow::Context;
use brdf::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use brdf::wave::{Energy, GhsFull, GhsOptions, GhsSsa, KcPsd};
use brdf::{BrdfError, Bxdf, DVec3, Distribution, Fresnel, Ior, Metal, MicrofacetConductor};
use serde_json::{Map, Value, json};

/// BRDF subcommands.
// Parsed once per run: the size of the argument variants is irrelevant.
#[allow(clippy::large_enum_variant)]
#[derive(clap::Subcommand)]
pub enum BrdfCommand {
    /// Read JSON-lines queries on stdin, write one JSON result per line
    /// (see the module documentation for the fields).
    Eval,
    /// In-plane BRDF slices and directional albedo as PNG + CSV (see `cmd_brdf_plot`).
    Plot(crate::cmd_brdf_plot::PlotArgs),
}

pub fn run(cmd: BrdfCommand) -> anyhow::Result<()> {
    match cmd {
        BrdfCommand::Eval => {
            let stdin = std::io::stdin();
            let stdout = std::io::stdout();
            eval_stream(stdin.lock(), stdout.lock())
        }
        BrdfCommand::Plot(args) => crate::cmd_brdf_plot::run(args),
    }
}

/// A query that cannot be answered: the message and the field to fix.
#[derive(Debug)]
pub(crate) struct QueryError {
    pub(crate) field: &'static str,
    pub(crate) message: String,
}

impl QueryError {
    fn new(field: &'static str, message: impl Into<String>) -> QueryError {
        QueryError {
            field,
            message: message.into(),
        }
    }
}

/// Most models kept at once; the cache is cleared when full.
const CACHE_LIMIT: usize = 64;

/// Serves every line of `input`, writing one line per query to `output`.
pub fn eval_stream(input: impl BufRead, output: impl Write) -> anyhow::Result<()> {
    let mut out = BufWriter::new(output);
    let mut cache: HashMap<String, Box<dyn Bxdf>> = HashMap::new();
    for (n, line) in input.lines().enumerate() {
        let line = line.with_context(|| format!("reading line {} of stdin", n + 1))?;
        if line.trim().is_empty() {
            continue;
        }
        let reply = match answer(&line, &mut cache) {
            Ok(v) => v,
            Err(e) => json!({"error": format!("line {}: {}", n + 1, e.message), "field": e.field}),
        };
        serde_json::to_writer(&mut out, &reply)?;
        out.write_all(b"\n")?;
        // Queries may come from an interactive pipe: answer each at once.
        out.flush()?;
    }
    Ok(())
}

fn answer(line: &str, cache: &mut HashMap<String, Box<dyn Bxdf>>) -> Result<Value, QueryError> {
    let v: Value = serde_json::from_str(line)
        .map_err(|e| QueryError::new("line", format!("not valid JSON: {e}")))?;
    let q = v
        .as_object()
        .ok_or_else(|| QueryError::new("line", "a query must be a JSON object"))?;
    let lambda_nm = number(q, "lambda_nm")?;
    // `number` already rejected NaN and infinities.
    if lambda_nm <= 0.0 {
        return Err(QueryError::new(
            "lambda_nm",
            format!("must be > 0 nm, got {lambda_nm}"),
        ));
    }
    let (lo, hi) = (brdf::WAVELENGTH_MIN_NM, brdf::WAVELENGTH_MAX_NM);
    if !(lo..=hi).contains(&lambda_nm) {
        return Err(QueryError::new(
            "lambda_nm",
            format!("{lambda_nm} nm is outside the supported range {lo}–{hi} nm"),
        ));
    }
    let theta_i = angle(q, "theta_i_deg", 0.0, 90.0)?;
    let theta_o = angle(q, "theta_o_deg", 0.0, 90.0)?;
    let phi_o = angle(q, "phi_o_deg", -360.0, 360.0)?;
    let (key, build) = model_spec(q)?;
    if !cache.contains_key(&key) {
        let model = build().map_err(|e| brdf_error(e, "model"))?;
        if cache.len() >= CACHE_LIMIT {
            cache.clear();
        }
        cache.insert(key.clone(), model);
    }
    let model = &cache[&key];
    let wi = spherical(theta_i, 0.0);
    let wo = spherical(theta_o, phi_o);
    let f = model.eval(wi, wo, lambda_nm);
    let pdf = model.pdf(wi, wo, lambda_nm);
    let spec = model.specular(wi, lambda_nm).weight;
    Ok(json!({"f": f, "specular_weight": spec, "pdf": pdf}))
}

/// Unit direction at polar angle θ and azimuth φ, both in degrees.
fn spherical(theta_deg: f64, phi_deg: f64) -> DVec3 {
    brdf::frame::spherical(theta_deg.to_radians(), phi_deg.to_radians())
}

fn number(q: &Map<String, Value>, field: &'static str) -> Result<f64, QueryError> {
    match q.get(field) {
        None | Some(Value::Null) => Err(QueryError::new(field, format!("missing `{field}`"))),
        Some(v) => v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
            QueryError::new(field, format!("`{field}` must be a finite number, got {v}"))
        }),
    }
}

fn angle(q: &Map<String, Value>, field: &'static str, lo: f64, hi: f64) -> Result<f64, QueryError> {
    let x = number(q, field)?;
    if (lo..=hi).contains(&x) {
        Ok(x)
    } else {
        Err(QueryError::new(
            field,
            format!("`{field}` = {x} must lie in [{lo}, {hi}] degrees"),
        ))
    }
}

fn text<'a>(q: &'a Map<String, Value>, field: &'static str) -> Result<Option<&'a str>, QueryError> {
    match q.get(field) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.as_str())),
        Some(v) => Err(QueryError::new(
            field,
            format!("`{field}` must be a string, got {v}"),
        )),
    }
}

/// Maps a library error to the query field the user has to change.
fn brdf_error(e: BrdfError, fallback: &'static str) -> QueryError {
    let field = match &e {
        // The query has one isotropic `alpha`.
        BrdfError::OutOfRange { name, .. } if name.starts_with("alpha") => "alpha",
        BrdfError::OutOfRange { name, .. } => name,
        BrdfError::WavelengthOutOfRange { .. } => "lambda_nm",
        _ => fallback,
    };
    QueryError::new(field, e.to_string())
}

fn fresnel(q: &Map<String, Value>) -> Result<(String, Fresnel), QueryError> {
    let (field, name) = match (text(q, "fresnel")?, text(q, "metal")?) {
        (Some(f), _) => ("fresnel", f),
        (None, Some(m)) => ("metal", m),
        (None, None) => {
            return Err(QueryError::new(
                "fresnel",
                "missing `fresnel`: give \"none\" (R = 1) or a metal name (cu, au, ag, al, fe, cr, brass, stainless_steel), or a `metal` field",
            ));
        }
    };
    if name.eq_ignore_ascii_case("none") {
        return Ok(("none".into(), Fresnel::One));
    }
    let metal = Metal::from_name(name).ok_or_else(|| {
        QueryError::new(
            field,
            format!("unknown metal {name:?}; use \"none\" or one of cu, au, ag, al, fe, cr, brass, stainless_steel"),
        )
    })?;
    Ok((metal.name().into(), Fresnel::conductor(Ior::metal(metal))))
}

pub(crate) type Builder = Box<dyn FnOnce() -> Result<Box<dyn Bxdf>, BrdfError>>;

/// The cache key and a builder for the model a query names.
pub(crate) fn model_spec(q: &Map<String, Value>) -> Result<(String, Builder), QueryError> {
    let model = text(q, "model")?.ok_or_else(|| {
        QueryError::new(
            "model",
            "missing `model`: one of ggx, beckmann, ghs_ssa, ghs, two_scale",
        )
    })?;
    let (fresnel_name, fresnel) = fresnel(q)?;
    // Bit patterns make the key exact: equal parameters share a model.
    let bits = |x: f64| format!("{:016x}", x.to_bits());
    match model {
        "ggx" | "beckmann" => {
            let alpha = number(q, "alpha")?;
            let key = format!("{model}/{}/{fresnel_name}", bits(alpha));
            let ggx = model == "ggx";
            let build: Builder = Box::new(move || {
                let d = if ggx {
                    Distribution::ggx(alpha, alpha)?
                } else {
                    Distribution::beckmann(alpha, alpha)?
                };
                Ok(Box::new(MicrofacetConductor::new(d, fresnel)?) as Box<dyn Bxdf>)
            });
            Ok((key, build))
        }
        "ghs_ssa" | "ghs" => {
            let psd = kc(q)?;
            let energy = match text(q, "energy")?.unwrap_or("raw") {
                "raw" => Energy::Raw,
                "krywonos" => Energy::Krywonos,
                "sigma_rel" => Energy::SigmaRel,
                other => {
                    return Err(QueryError::new(
                        "energy",
                        format!("unknown energy option {other:?}; use raw, krywonos or sigma_rel"),
                    ));
                }
            };
            let opts = GhsOptions {
                energy,
                ..GhsOptions::default()
            };
            let key = format!(
                "{model}/{}/{}/{}/{energy:?}/{fresnel_name}",
                bits(psd.sigma_um()),
                bits(psd.lc_um()),
                bits(psd.gamma())
            );
            let full = model == "ghs";
            let build: Builder = Box::new(move || {
                Ok(if full {
                    Box::new(GhsFull::with_options(psd, fresnel, opts)?) as Box<dyn Bxdf>
                } else {
                    Box::new(GhsSsa::with_options(psd, fresnel, opts)?) as Box<dyn Bxdf>
                })
            });
            Ok((key, build))
        }
        "two_scale" => {
            let psd = kc(q)?;
            let beta = number(q, "beta")?;
            let coherent = match text(q, "coherent")?.unwrap_or("macro_ndf") {
                "macro_ndf" => CoherentPart::MacroNdf,
                "delta" => CoherentPart::Delta,
                other => {
                    return Err(QueryError::new(
                        "coherent",
                        format!("unknown coherent option {other:?}; use macro_ndf or delta"),
                    ));
                }
            };
            let key = format!(
                "two_scale/{}/{}/{}/{}/{coherent:?}/{fresnel_name}",
                bits(beta),
                bits(psd.sigma_um()),
                bits(psd.lc_um()),
                bits(psd.gamma())
            );
            let build: Builder = Box::new(move || {
                let m = TwoScale::new(TwoScaleParams {
                    beta,
                    sigma_um: psd.sigma_um(),
                    lc_um: psd.lc_um(),
                    gamma: psd.gamma(),
                    fresnel,
                    coherent,
                    resolution: TableResolution::default(),
                })?;
                Ok(Box::new(m) as Box<dyn Bxdf>)
            });
            Ok((key, build))
        }
        other => Err(QueryError::new(
            "model",
            format!("unknown model {other:?}; use ggx, beckmann, ghs_ssa, ghs or two_scale"),
        )),
    }
}

/// The KC surface of a query, validated (errors name sigma_um, lc_um or gamma).
fn kc(q: &Map<String, Value>) -> Result<KcPsd, QueryError> {
    let sigma = number(q, "sigma_um")?;
    let lc = number(q, "lc_um")?;
    let gamma = number(q, "gamma")?;
    KcPsd::new(sigma, lc, gamma).map_err(|e| brdf_error(e, "sigma_um"))
}
