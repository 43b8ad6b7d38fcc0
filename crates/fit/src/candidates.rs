//! The one route from a scan's analysis to model parameters: every model the scan is fitted
//! to, each a [`Candidate`] holding a material the renderer builds (parameters brought into
//! its accepted range) and what about it is unreliable. `lustre fit`'s material file writes
//! them, `lustre judge` ranks them, `compare --material` and `preview` render them, so the
//! model a command shows is the model the others show.
//!
//! Units: the analysis is in metres; materials are in µm (physics.md §1–2).

use crate::kc::KcParams;
use crate::pipeline::Analysis;
use crate::two_scale::BetaSource;
use brdf::paper::{REFERENCE_LAMBDA_NM, short};
use brdf::spec::{
    AnisoSpec, FresnelSpec, KcSpec, MaterialSpec, MeasuredAnisoSpec, ModelKind, ModelSpec,
    RrSurface,
};
use brdf::statistics::{TabulatedPsd, epd, kc};
use brdf::wave::two_scale::CoherentPart;
use brdf::wave::wavenumber;
use brdf::wave::{GhsOptions, Polarization, PolarizationFactor};

const UM: f64 = 1e6;

/// One model fitted from the scan.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Unique key: the family, or `two_scale_<cutoff multiple>` for a two-scale split.
    pub key: String,
    /// The recipe.
    pub family: Family,
    /// Row label for reports.
    pub label: String,
    /// What the model assumes about the surface (the report's "assumes" column).
    pub assumes: &'static str,
    /// The material, in the renderer's range; `None` when nothing can be built.
    pub spec: Option<MaterialSpec>,
    /// What is unreliable about it (a degenerate fit, a parameter brought into range, a β
    /// not measured); empty when sound.
    pub problems: Vec<String>,
    /// The two-scale split this comes from: cutoff as a multiple of 550 nm and in µm.
    pub cutoff: Option<(f64, f64)>,
    /// How the measured-PSD table was made.
    pub table: Option<TableInfo>,
}

impl Candidate {
    /// Whether the candidate is sound (built, and nothing flagged).
    pub fn sound(&self) -> bool {
        self.spec.is_some() && self.problems.is_empty()
    }

    /// The problems in one sentence (`"ok"` when sound).
    pub fn problem_text(&self) -> String {
        if self.problems.is_empty() {
            "ok".into()
        } else {
            self.problems.join("; ")
        }
    }
}

/// How the measured-PSD table of a candidate was made from the analysis' radial PSD.
#[derive(Clone, Debug, PartialEq)]
pub struct TableInfo {
    /// Which PSD the table comes from (`radial 2D`, `from the line PSD`, …).
    pub source: &'static str,
    /// Points of the PSD before smoothing.
    pub points: usize,
    /// Exponent of the power-law tail the table ends in.
    pub tail_exponent: f64,
    /// Whether the fitted tail exponent was clamped into [−8, −2.5].
    pub tail_clamped: bool,
}

/// The recipes: which model a candidate is and how its parameters come from the scan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// GGX with α fitted to the measured NDF.
    Ggx,
    /// Beckmann with α fitted to the measured NDF.
    Beckmann,
    /// GGX with α from the K-correlation fit by the GGX ≡ KC identity.
    GgxKc,
    /// GHS smooth-surface approximation of the K-correlation fit.
    GhsSsa,
    /// Full GHS of the K-correlation fit.
    Ghs,
    /// Full GHS of the K-correlation fit with the Rayleigh–Rice polarisation factor Q in
    /// place of the scalar Fresnel R (unpolarised).
    GhsQ,
    /// Rayleigh–Rice (first-order vector perturbation theory) of the K-correlation fit,
    /// unpolarised.
    RayleighRice,
    /// Full GHS of an anisotropic K-correlation surface (scans flagged anisotropic).
    GhsAniso,
    /// Full GHS of the measured PSD.
    MeasuredPsd,
    /// Full GHS of the measured PSD of the de-stretched frame, stretched along the axes of
    /// the anisotropic K-correlation fit (scans flagged anisotropic).
    MeasuredPsdAniso,
    /// GHS smooth-surface approximation of the map's 2-D PSD on a grid (scans flagged
    /// anisotropic whose 2-D PSD is not elliptical).
    MeasuredPsd2dSsa,
    /// Full GHS of the map's 2-D PSD on a grid (the same scans and grid as
    /// [`Family::MeasuredPsd2dSsa`]).
    MeasuredPsd2d,
    /// Two-scale at one split of the surface.
    TwoScale,
}

impl Family {
    /// Every recipe, in report order.
    pub const ALL: [Family; 13] = [
        Family::Ggx,
        Family::Beckmann,
        Family::GgxKc,
        Family::GhsSsa,
        Family::Ghs,
        Family::GhsQ,
        Family::RayleighRice,
        Family::GhsAniso,
        Family::MeasuredPsd,
        Family::MeasuredPsdAniso,
        Family::MeasuredPsd2dSsa,
        Family::MeasuredPsd2d,
        Family::TwoScale,
    ];

    /// The key of the recipe: its model's name, `ggx_kc` for the identity.
    pub fn name(self) -> &'static str {
        match self {
            Family::GgxKc => "ggx_kc",
            Family::GhsQ => "ghs_q",
            f => f.model().name(),
        }
    }

    /// The reflection model the recipe builds.
    pub fn model(self) -> ModelKind {
        match self {
            Family::Ggx | Family::GgxKc => ModelKind::Ggx,
            Family::Beckmann => ModelKind::Beckmann,
            Family::GhsSsa => ModelKind::GhsSsa,
            Family::Ghs | Family::GhsQ => ModelKind::Ghs,
            Family::RayleighRice => ModelKind::RayleighRice,
            Family::GhsAniso => ModelKind::GhsAniso,
            Family::MeasuredPsd => ModelKind::MeasuredPsd,
            Family::MeasuredPsdAniso => ModelKind::MeasuredPsdAniso,
            Family::MeasuredPsd2dSsa => ModelKind::MeasuredPsd2dSsa,
            Family::MeasuredPsd2d => ModelKind::MeasuredPsd2d,
            Family::TwoScale => ModelKind::TwoScale,
        }
    }

    /// What the model assumes about the surface (the report's "assumes" column).
    pub fn assumes(self) -> &'static str {
        match self {
            Family::Ggx => "geometric optics, GGX slope distribution fitted to the measured NDF",
            Family::Beckmann => {
                "geometric optics, Beckmann slope distribution fitted to the measured NDF"
            }
            Family::GgxKc => {
                "GGX with α from the KC fit by the GGX ≡ KC identity (α = 1/(2kLc), 550 nm)"
            }
            Family::GhsSsa => "Gaussian heights, KC spectrum, smooth-surface (first-order) lobe",
            Family::Ghs => "Gaussian heights, KC spectrum, all orders",
            Family::GhsQ => {
                "Gaussian heights, KC spectrum, all orders, Rayleigh–Rice polarisation factor Q for R"
            }
            Family::RayleighRice => {
                "first-order vector perturbation theory (Rayleigh–Rice), KC spectrum, unpolarised"
            }
            Family::GhsAniso => {
                "Gaussian heights, KC spectrum stretched along the principal slope axes, all orders"
            }
            Family::MeasuredPsd => "Gaussian heights, measured isotropic PSD, all orders",
            Family::MeasuredPsdAniso => {
                "Gaussian heights, measured PSD constant on ellipses (one lay direction), all orders"
            }
            Family::MeasuredPsd2dSsa => {
                "Gaussian heights, measured 2-D PSD (any shape), smooth-surface (first-order) lobe"
            }
            Family::MeasuredPsd2d => "Gaussian heights, measured 2-D PSD (any shape), all orders",
            Family::TwoScale => "exponential NDF above the cutoff period, KC diffraction below it",
        }
    }
}

/// Every candidate of the analysis, in [`Family::ALL`] order (one two-scale candidate per split
/// of `a.two_scale`), with `fresnel` as their Fresnel term.
pub fn candidates(a: &Analysis, fresnel: &FresnelSpec) -> Vec<Candidate> {
    let mut out = vec![
        microfacet(a, fresnel, false),
        microfacet(a, fresnel, true),
        ggx_kc(a, fresnel),
        kc_model(a, fresnel, Family::GhsSsa),
        kc_model(a, fresnel, Family::Ghs),
        kc_model(a, fresnel, Family::GhsQ),
        kc_model(a, fresnel, Family::RayleighRice),
        ghs_aniso(a, fresnel),
        measured_psd(a, fresnel),
        measured_psd_aniso(a, fresnel),
        measured_psd2d(a, fresnel, Family::MeasuredPsd2dSsa),
        measured_psd2d(a, fresnel, Family::MeasuredPsd2d),
    ];
    out.extend(a.two_scale.iter().map(|t| two_scale(t, fresnel)));
    out
}

fn blank(family: Family, label: String) -> Candidate {
    Candidate {
        key: family.name().to_string(),
        family,
        label,
        assumes: family.assumes(),
        spec: None,
        problems: Vec::new(),
        cutoff: None,
        table: None,
    }
}

/// GGX (or Beckmann) with the roughness fitted to the measured NDF.
fn microfacet(a: &Analysis, fresnel: &FresnelSpec, beckmann: bool) -> Candidate {
    let (family, name, fitted) = if beckmann {
        (Family::Beckmann, "Beckmann", a.ndf.alpha_beckmann.0)
    } else {
        (Family::Ggx, "GGX", a.ndf.alpha_ggx.0)
    };
    let (alpha, problem) = renderer_alpha(fitted);
    let mut c = blank(family, format!("{name}, NDF fit (α {})", short(alpha)));
    c.problems.extend(problem);
    let model = if beckmann {
        ModelSpec::Beckmann {
            alpha_x: alpha,
            alpha_y: alpha,
            angle_deg: 0.0,
        }
    } else {
        ModelSpec::Ggx {
            alpha_x: alpha,
            alpha_y: alpha,
            angle_deg: 0.0,
        }
    };
    c.spec = Some(MaterialSpec {
        model,
        fresnel: fresnel.clone(),
    });
    c
}

/// The K-correlation fit in µm, in the renderer's range, and its problems.
fn kc_surface(a: &Analysis) -> (KcSpec, Vec<String>) {
    let ((sigma_um, lc_um, gamma), range) = renderer_kc(&a.kc.params);
    let mut problems = Vec::new();
    if let Some(r) = a.kc.reason {
        problems.push(format!(
            "degenerate K-correlation fit: {} (γ {:.3})",
            r.describe(),
            a.kc.params.gamma
        ));
    }
    problems.extend(range);
    (
        KcSpec {
            sigma_um,
            lc_um,
            gamma,
        },
        problems,
    )
}

/// GGX with α from the K-correlation fit by the GGX ≡ KC identity at 550 nm.
fn ggx_kc(a: &Analysis, fresnel: &FresnelSpec) -> Candidate {
    let (surface, problems) = kc_surface(a);
    let mut c = blank(Family::GgxKc, "GGX ≡ KC identity".into());
    c.problems = problems;
    match brdf::wave::ggx_kc::ggx_alpha_from_kc_slope_space(
        surface.lc_um,
        wavenumber(REFERENCE_LAMBDA_NM),
        1.0,
    ) {
        Ok(alpha) => {
            let (alpha, problem) = renderer_alpha(alpha);
            c.problems.extend(problem);
            c.label = format!("GGX ≡ KC (α {} = 1/(2kLc))", short(alpha));
            c.spec = Some(MaterialSpec {
                model: ModelSpec::Ggx {
                    alpha_x: alpha,
                    alpha_y: alpha,
                    angle_deg: 0.0,
                },
                fresnel: fresnel.clone(),
            });
        }
        Err(e) => c.problems.push(e.to_string()),
    }
    c
}

/// A wave-optical model of the K-correlation fit as it is: GHS SSA, full GHS (with R or Q)
/// or Rayleigh–Rice.
fn kc_model(a: &Analysis, fresnel: &FresnelSpec, family: Family) -> Candidate {
    let (surface, problems) = kc_surface(a);
    let options = GhsOptions::default();
    let (name, model) = match family {
        Family::Ghs => ("full GHS", ModelSpec::Ghs { surface, options }),
        Family::GhsQ => (
            "full GHS with Q",
            ModelSpec::Ghs {
                surface,
                options: GhsOptions {
                    polarization_factor: PolarizationFactor::Q,
                    ..options
                },
            },
        ),
        Family::RayleighRice => (
            "Rayleigh–Rice",
            ModelSpec::RayleighRice {
                surface: RrSurface::Kc(surface),
                polarization: Polarization::Unpolarized,
            },
        ),
        _ => ("GHS SSA", ModelSpec::GhsSsa { surface, options }),
    };
    let mut c = blank(family, format!("{name}, KC fit"));
    c.problems = problems;
    let spec = MaterialSpec {
        model,
        fresnel: fresnel.clone(),
    };
    // The full GHS needs γ ≥ 1.05 (its series spans more decades than f64 holds below).
    match spec.validate() {
        Ok(()) => c.spec = Some(spec),
        Err(e) => c.problems.push(e.to_string()),
    }
    c
}

/// The anisotropic K-correlation fit of a scan flagged anisotropic, or the candidate's
/// problem.
fn aniso_fit<'a>(a: &'a Analysis, c: &mut Candidate) -> Option<&'a crate::kc2d::AnisoKcFit> {
    let Some(an) = a.anisotropy.as_ref().filter(|an| an.anisotropic) else {
        let why = a.anisotropy.as_ref().map_or_else(
            || "no anisotropy analysis (a profile)".to_string(),
            |an| an.flag_source.clone(),
        );
        c.problems
            .push(format!("the scan is not flagged anisotropic: {why}"));
        return None;
    };
    let fit = match &an.kc {
        Some(Ok(f)) => f,
        Some(Err(e)) => {
            c.problems
                .push(format!("anisotropic K-correlation fit: {e}"));
            return None;
        }
        None => {
            c.problems
                .push("no anisotropic K-correlation fit of the 2-D PSD".into());
            return None;
        }
    };
    if let Some(p) = &fit.problem {
        c.problems
            .push(format!("anisotropic K-correlation fit: {p}"));
    }
    Some(fit)
}

/// Full GHS of an anisotropic K-correlation surface, for a scan flagged anisotropic: the
/// stretched K-correlation (σ, Lx, Ly, φ₀, γ) fitted to the map's 2-D PSD
/// ([`crate::kc2d`]), in the map's axes, which are the renderer's tangent axes.
fn ghs_aniso(a: &Analysis, fresnel: &FresnelSpec) -> Candidate {
    let mut c = blank(Family::GhsAniso, "full GHS, anisotropic KC".into());
    let Some(fit) = aniso_fit(a, &mut c) else {
        return c;
    };
    let p = &fit.params;
    c.label = format!(
        "full GHS, anisotropic KC fit (Ly/Lx {:.2}, φ₀ {:.1}°)",
        p.ratio(),
        p.angle_rad.to_degrees()
    );
    let spec = MaterialSpec {
        model: ModelSpec::GhsAniso {
            surface: AnisoSpec {
                sigma_um: p.sigma * UM,
                lx_um: p.lx * UM,
                ly_um: p.ly * UM,
                angle_deg: p.angle_rad.to_degrees(),
                gamma: p.gamma,
            },
            options: GhsOptions::default(),
        },
        fresnel: fresnel.clone(),
    };
    match spec.validate() {
        Ok(()) => c.spec = Some(spec),
        Err(e) => c.problems.push(e.to_string()),
    }
    c
}

/// Rms ln residual of the elliptical measured model against the 2-D periodogram's polar
/// cells above which the map's PSD is called not elliptical: on stretched synthetic maps it
/// is the sampling scatter of the cells, 0.2–0.3 (physics.md §15.2).
pub const NON_ELLIPTICAL_LOG_RESIDUAL: f64 = 0.5;

/// Full GHS of the measured PSD of the de-stretched frame ([`crate::kc2d::destretched_radial`]),
/// stretched back along the axes of the anisotropic K-correlation fit, for a scan flagged
/// anisotropic.
fn measured_psd_aniso(a: &Analysis, fresnel: &FresnelSpec) -> Candidate {
    let mut c = blank(
        Family::MeasuredPsdAniso,
        "full GHS, measured PSD on ellipses".into(),
    );
    let Some(fit) = aniso_fit(a, &mut c) else {
        return c;
    };
    let p = &fit.params;
    // A 2-D PSD that is not elliptical is stated in `[reliability].psd_destretched` and
    // in the label, not made a problem: the model is then an approximation to rank, as the
    // isotropic models are on an anisotropic scan.
    let (ratio, angle_deg) = (p.ratio(), p.angle_rad.to_degrees());
    c.label = format!(
        "full GHS, measured PSD on ellipses (Ly/Lx {ratio:.2}, φ₀ {angle_deg:.1}°, ellipse \
         residual {:.2} ln)",
        fit.rms_log_residual_elliptical
    );
    let (zeta, psd, info) = match smoothed_table(&fit.destretched, DESTRETCHED_SOURCE) {
        Ok(t) => t,
        Err(e) => {
            c.problems.push(format!("de-stretched PSD: {e}"));
            return c;
        }
    };
    c.table = Some(info);
    let spec = MaterialSpec {
        model: ModelSpec::MeasuredPsdAniso {
            surface: MeasuredAnisoSpec {
                zeta_rad_per_um: zeta,
                psd_um4: psd,
                // The stretched K-correlation's axes (only their ratio is read), so that
                // `[material]` holds one set for both stretched models.
                lx_um: p.lx * UM,
                ly_um: p.ly * UM,
                angle_deg,
            },
            options: GhsOptions::default(),
        },
        fresnel: fresnel.clone(),
    };
    match spec.validate() {
        Ok(()) => c.spec = Some(spec),
        Err(e) => c.problems.push(e.to_string()),
    }
    c
}

/// GHS SSA (`family` [`Family::MeasuredPsd2dSsa`]) or full GHS ([`Family::MeasuredPsd2d`])
/// of the map's 2-D PSD on a grid ([`crate::psd_map`]), for a scan flagged anisotropic
/// whose 2-D PSD is not constant on ellipses ([`non_elliptical`]); the tail beyond the
/// grid takes the exponent of the isotropic measured table's tail.
fn measured_psd2d(a: &Analysis, fresnel: &FresnelSpec, family: Family) -> Candidate {
    let full = family == Family::MeasuredPsd2d;
    let what = if full { "full GHS" } else { "GHS SSA" };
    let mut c = blank(family, format!("{what}, measured 2-D PSD"));
    let Some(fit) = aniso_fit(a, &mut c) else {
        return c;
    };
    // The map's grid does not depend on the stretched K-correlation: its problems are
    // not this model's.
    c.problems.clear();
    if non_elliptical(fit).is_none() {
        c.problems.push(format!(
            "not written: the 2-D PSD is elliptical (ellipse residual {:.2} ≤ {:.1} in ln),              which measured_psd_aniso holds",
            fit.rms_log_residual_elliptical, NON_ELLIPTICAL_LOG_RESIDUAL
        ));
        return c;
    }
    let tail_exponent = match measured_table(a) {
        Ok((_, _, info)) => -info.tail_exponent,
        Err(e) => {
            c.problems
                .push(format!("no tail exponent (isotropic table: {e})"));
            return c;
        }
    };
    let grid = match crate::psd_map::psd_map(&a.scan) {
        Ok(g) => g,
        Err(e) => {
            c.problems.push(format!("2-D PSD grid: {e}"));
            return c;
        }
    };
    c.label = format!(
        "{what}, measured 2-D PSD ({}×{} nodes of the half plane, ellipse residual {:.2} ln)",
        2 * grid.half_nx + 1,
        grid.half_ny + 1,
        fit.rms_log_residual_elliptical
    );
    c.table = Some(TableInfo {
        source: crate::psd_map::MAP_SOURCE,
        points: (2 * grid.half_nx + 1) * (grid.half_ny + 1),
        tail_exponent: -tail_exponent,
        tail_clamped: false,
    });
    let surface = brdf::spec::Psd2dSpec {
        half_nx: grid.half_nx,
        half_ny: grid.half_ny,
        dzx_rad_per_um: grid.dzx_rad_per_um,
        dzy_rad_per_um: grid.dzy_rad_per_um,
        psd_um4: grid.p_um4,
        tail_exponent,
        angle_deg: 0.0,
    };
    let options = GhsOptions::default();
    let spec = MaterialSpec {
        model: if full {
            ModelSpec::MeasuredPsd2d { surface, options }
        } else {
            ModelSpec::MeasuredPsd2dSsa { surface, options }
        },
        fresnel: fresnel.clone(),
    };
    match spec.validate() {
        Ok(()) => c.spec = Some(spec),
        Err(e) => c.problems.push(e.to_string()),
    }
    c
}

/// How the de-stretched table is made (`[psd.destretched].source`).
pub const DESTRETCHED_SOURCE: &str = "2D periodogram of the map averaged over the ellipses of \
     the anisotropic K-correlation fit's axes (areas kept)";

/// The problem when the map's 2-D PSD is not constant on ellipses: the elliptical model's
/// cell residual above [`NON_ELLIPTICAL_LOG_RESIDUAL`].
pub fn non_elliptical(fit: &crate::kc2d::AnisoKcFit) -> Option<String> {
    let r = fit.rms_log_residual_elliptical;
    if r.is_finite() && r <= NON_ELLIPTICAL_LOG_RESIDUAL {
        return None;
    }
    Some(format!(
        "the 2-D PSD is not constant on ellipses: the elliptical measured model misses the \
         periodogram's polar cells by {r:.2} in ln (rms; sampling scatter 0.2–0.3, isotropic \
         measured table {:.2}, stretched K-correlation {:.2}): more than one lay, or streaks \
         (straight edges, scan-line artefacts), which no elliptical model holds",
        fit.rms_log_residual_radial, fit.rms_log_residual
    ))
}

/// Full GHS with the measured PSD, as [`measured_table`] tabulates it.
fn measured_psd(a: &Analysis, fresnel: &FresnelSpec) -> Candidate {
    let mut c = blank(Family::MeasuredPsd, "full GHS, measured PSD".into());
    match measured_table(a) {
        Ok((zeta, p, info)) => {
            c.table = Some(info);
            c.spec = Some(MaterialSpec {
                model: ModelSpec::MeasuredPsd {
                    zeta_rad_per_um: zeta,
                    psd_um4: p,
                    options: GhsOptions::default(),
                },
                fresnel: fresnel.clone(),
            });
        }
        Err(e) => c.problems.push(e),
    }
    c
}

/// Most log-spaced points of the measured-PSD table.
pub const PSD_NODES: usize = 120;

/// The analysis' tabulated PSD in µm units, denoised for `TabulatedPsd`: ln P averaged over
/// ±0.05 decades of ζ and resampled to at most [`PSD_NODES`] log-spaced points (a
/// periodogram's bins scatter by ±100 %, and a converted profile PSD has local slopes of
/// ±1000, which the Hankel transform of the table does not survive), plus a power-law tail:
/// `TabulatedPsd` extends a table by its last segment, so the exponent is set to the
/// least-squares slope of the top third of the table, clamped to [−8, −2.5] (finite σ; no
/// scan resolves a steeper tail), carried by one extra point at 1.5× the last frequency.
pub fn measured_table(a: &Analysis) -> Result<(Vec<f64>, Vec<f64>, TableInfo), String> {
    smoothed_table(&a.table.0, a.table.1)
}

/// [`measured_table`] of any radial PSD table (rad/m, m⁴), e.g. the de-stretched one of
/// [`crate::kc2d::destretched_radial`].
pub fn smoothed_table(
    table: &crate::psd::RadialPsdTable,
    source: &'static str,
) -> Result<(Vec<f64>, Vec<f64>, TableInfo), String> {
    let pts: Vec<(f64, f64)> = (table.zeta.iter().zip(&table.p))
        .filter(|(z, p)| z.is_finite() && **z > 0.0 && p.is_finite() && **p > 0.0)
        .map(|(z, p)| ((z / UM).ln(), (p * UM.powi(4)).ln()))
        .collect();
    if pts.len() < 8 {
        return Err(format!(
            "the measured PSD has only {} usable points",
            pts.len()
        ));
    }
    let (lz, lp) = log_smoothed(&pts);
    let n = lz.len();
    if n < 8 {
        return Err(format!(
            "the measured PSD has only {n} distinct frequencies"
        ));
    }
    let fitted = tail_slope(&lz[2 * n / 3..], &lp[2 * n / 3..]);
    let slope = fitted.clamp(-8.0, -2.5);
    let mut z: Vec<f64> = lz.iter().map(|v| v.exp()).collect();
    let mut p: Vec<f64> = lp.iter().map(|v| v.exp()).collect();
    let (zl, pl) = (z[n - 1], p[n - 1]);
    z.push(1.5 * zl);
    p.push(pl * 1.5f64.powf(slope));
    TabulatedPsd::new(&z, &p).map_err(|e| format!("the measured PSD table: {e}"))?;
    let info = TableInfo {
        source,
        points: table.zeta.len(),
        tail_exponent: slope,
        tail_clamped: slope != fitted,
    };
    Ok((z, p, info))
}

/// `(ln ζ, ln P)` averaged over ±0.05 decades at up to [`PSD_NODES`] log-spaced nodes.
fn log_smoothed(pts: &[(f64, f64)]) -> (Vec<f64>, Vec<f64>) {
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
    (lz, lp)
}

/// Least-squares slope of `ty` against `tx`.
fn tail_slope(tx: &[f64], ty: &[f64]) -> f64 {
    let mx = tx.iter().sum::<f64>() / tx.len() as f64;
    let my = ty.iter().sum::<f64>() / ty.len() as f64;
    let sxx: f64 = tx.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = tx.iter().zip(ty).map(|(x, y)| (x - mx) * (y - my)).sum();
    sxy / sxx
}

/// Largest Lc the two-scale model accepts [µm] (its micro scale is a `KcPsd`).
const TWO_SCALE_LC_MAX_UM: f64 = kc::LC_MAX_UM;

/// The two-scale model of one split: its β and residual K-correlation fit, in range.
fn two_scale(t: &crate::two_scale::Split, fresnel: &FresnelSpec) -> Candidate {
    let m = t.multiple;
    let mut c = blank(Family::TwoScale, String::new());
    c.key = format!("{}_{m}", Family::TwoScale.name());
    c.cutoff = Some((m, t.cutoff * UM));
    let ((sigma_um, lc_um, gamma), range) = renderer_kc(&t.kc.params);
    if let Some(r) = t.kc.reason {
        c.problems.push(format!(
            "residual K-correlation fit degenerate: {}",
            r.describe()
        ));
    }
    c.problems.extend(range);
    let lc_um = if lc_um > TWO_SCALE_LC_MAX_UM {
        c.problems.push(format!(
            "Lc {lc_um:.4e} µm clamped to the two-scale limit {TWO_SCALE_LC_MAX_UM:e} µm"
        ));
        TWO_SCALE_LC_MAX_UM
    } else {
        lc_um
    };
    let beta = if epd::ExponentialNdf::new(t.beta).is_ok() {
        t.beta
    } else {
        let b = if t.beta.is_finite() {
            t.beta.clamp(epd::BETA_MIN, epd::BETA_MAX)
        } else {
            epd::BETA_MIN
        };
        c.problems.push(format!(
            "β {:.4e} {} set to {b}",
            t.beta,
            if t.beta_source == BetaSource::Unresolved {
                "(not measured: the scan does not reach the cutoff period)"
            } else {
                "(outside 1e-4 … 10)"
            }
        ));
        b
    };
    c.label = if c.problems.is_empty() {
        format!("two-scale {m}λ (β {})", short(beta))
    } else {
        format!("two-scale {m}λ")
    };
    c.spec = Some(MaterialSpec {
        model: ModelSpec::TwoScale {
            beta,
            surface: KcSpec {
                sigma_um,
                lc_um,
                gamma,
            },
            coherent: CoherentPart::default(),
        },
        fresnel: fresnel.clone(),
    });
    c
}

/// K-correlation parameters in µm the renderer accepts; `Some(problem)` if they had to
/// be brought into range.
pub fn renderer_kc(k: &KcParams) -> ((f64, f64, f64), Option<String>) {
    let (s, l, g) = (k.sigma * UM, k.lc * UM, k.gamma);
    if brdf::statistics::KcPsd::new(s, l, g).is_ok() {
        return ((s, l, g), None);
    }
    let fix = |v: f64, lo: f64, hi: f64| if v.is_finite() { v.clamp(lo, hi) } else { lo };
    let out = (
        fix(s, 0.0, kc::SIGMA_MAX_UM),
        fix(l, kc::LC_MIN_UM, kc::LC_MAX_UM),
        fix(g, kc::GAMMA_MIN, kc::GAMMA_MAX),
    );
    (
        out,
        Some(format!(
            "σ {s:.4e} µm, Lc {l:.4e} µm, γ {g:.4} brought into the renderer's range"
        )),
    )
}

/// A microfacet α the renderer accepts (1e-4 … 1); `Some(problem)` if clamped.
pub fn renderer_alpha(a: f64) -> (f64, Option<String>) {
    if brdf::Distribution::ggx(a, a).is_ok() {
        return (a, None);
    }
    let c = if a.is_finite() {
        a.clamp(brdf::microfacet::ALPHA_MIN, brdf::microfacet::ALPHA_MAX)
    } else {
        brdf::microfacet::ALPHA_MIN
    };
    (
        c,
        Some(format!(
            "α {a:.4e} clamped to {c} (the renderer accepts 1e-4 … 1)"
        )),
    )
}
