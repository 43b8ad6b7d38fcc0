//! What `lustre judge` ranks: the scan's candidates (`fit::candidates`, the models every
//! command fits from a scan), each built and checked before it is compared: a candidate
//! `lustre fit` flags as unreliable is skipped with its problem, a measured-PSD table (the
//! isotropic one, or the de-stretched one of the stretched model) that disagrees with the
//! direct Hankel transform is refused, and so is a model whose albedo no physical surface
//! has.

use brdf::numerics::hankel::{self, DirectTolerance};
use brdf::spec::{MaterialSpec, ModelSpec};
use brdf::statistics::elliptical::StretchedPsd;
use brdf::statistics::measured_psd::TabulatedCorrelation;
use brdf::statistics::{EllipticalPsd, RadialPsd, TabulatedPsd};
use brdf::wave::{GhsAnisotropic, GhsFull};
use brdf::{Bxdf, Fresnel};
use serde_json::{Map, Value, json};

use crate::Options;

/// A built model of the scan: one row of the report.
pub(crate) struct Candidate {
    /// Model family (`ggx`, `ggx_kc`, `ghs`, `measured_psd`, `two_scale`, …).
    pub(crate) model: String,
    /// Unique key (`two_scale_100`, …).
    pub(crate) key: String,
    pub(crate) label: String,
    pub(crate) assumes: &'static str,
    /// Parameters in the material vocabulary (µm), plus provenance fields.
    pub(crate) params: Map<String, Value>,
    pub(crate) bxdf: Box<dyn Bxdf>,
}

/// A built candidate, or its label and why it is not judged.
pub(crate) type Built = Result<Candidate, (String, String)>;

/// Builds a candidate of the scan, or says why it is not judged. `geometry` holds the
/// wavenumbers [rad/µm] and incidence cosines judged (for the measured-PSD table check).
pub(crate) fn build(c: &fit::candidates::Candidate, geometry: &[(f64, f64)]) -> Built {
    let label = c.label.clone();
    if !c.problems.is_empty() {
        return Err((label, c.problem_text()));
    }
    let Some(spec) = &c.spec else {
        return Err((label, "no model could be built".into()));
    };
    let mut params = params_of(spec);
    if let Some((m, um)) = c.cutoff {
        params.insert("cutoff_um".into(), json!(um));
        params.insert("cutoff_multiple".into(), json!(m));
    }
    let (label, bxdf): (String, Box<dyn Bxdf>) = match &spec.model {
        ModelSpec::MeasuredPsd { .. } => {
            let (m, label) = measured(spec, c, geometry, &mut params)?;
            (label, Box::new(m))
        }
        ModelSpec::MeasuredPsdAniso { .. } => {
            let (m, label) = measured_stretched(spec, c, geometry, &mut params)?;
            (label, Box::new(m))
        }
        _ => match spec.build() {
            Ok(b) => (label, b),
            Err(e) => return Err((label, e.to_string())),
        },
    };
    Ok(Candidate {
        model: c.family.name().into(),
        key: c.key.clone(),
        label,
        assumes: c.assumes,
        params,
        bxdf,
    })
}

/// The report's parameters of a material: its flat keys, without the tables.
fn params_of(spec: &MaterialSpec) -> Map<String, Value> {
    let mut m = match serde_json::to_value(spec.to_desc()) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    };
    m.remove("psd_csv");
    m.remove("nk_csv");
    m
}

/// The full GHS of the measured-PSD table, its table verified against the direct Hankel
/// transform ([`check_table`]); the label says how far it is from it.
fn measured(
    spec: &MaterialSpec,
    c: &fit::candidates::Candidate,
    geometry: &[(f64, f64)],
    params: &mut Map<String, Value>,
) -> Result<(GhsFull<TabulatedPsd>, String), (String, String)> {
    let label = c.label.clone();
    let fail = |e: String| (label.clone(), e);
    let ModelSpec::MeasuredPsd {
        zeta_rad_per_um,
        psd_um4,
        options,
    } = &spec.model
    else {
        return Err(fail("not a measured-PSD material".into()));
    };
    let table = TabulatedPsd::new(zeta_rad_per_um, psd_um4).map_err(|e| fail(e.to_string()))?;
    let sigma = table.sigma_um();
    let fresnel = spec.fresnel.build().map_err(|e| fail(e.to_string()))?;
    let m = GhsFull::with_options(table, fresnel, *options).map_err(|e| fail(e.to_string()))?;
    let table = TableUnderTest {
        psd: m.psd(),
        reach_um: m.psd().length_um(),
        s_tilde: &|u, g| m.s_tilde(u, g),
    };
    let check = check_table(&table, geometry).map_err(fail)?;
    let label = table_params(c, check, sigma, params);
    Ok((m, label))
}

/// The full GHS of a measured PSD stretched along two axes.
type StretchedMeasured = GhsAnisotropic<EllipticalPsd<TabulatedPsd>>;

/// The full GHS of the measured PSD stretched along two axes, its table (the isotropic S̃
/// of the de-stretched frame's PSD, over |u| up to 2k times the larger stretch) verified
/// against the direct Hankel transform of that PSD's covariance as [`measured`]'s is.
fn measured_stretched(
    spec: &MaterialSpec,
    c: &fit::candidates::Candidate,
    geometry: &[(f64, f64)],
    params: &mut Map<String, Value>,
) -> Result<(StretchedMeasured, String), (String, String)> {
    let label = c.label.clone();
    let fail = |e: String| (label.clone(), e);
    let ModelSpec::MeasuredPsdAniso { surface, options } = &spec.model else {
        return Err(fail("not a stretched measured-PSD material".into()));
    };
    let psd = surface.psd().map_err(|e| fail(e.to_string()))?;
    let sigma = psd.sigma_um();
    let fresnel = spec.fresnel.build().map_err(|e| fail(e.to_string()))?;
    let m = GhsAnisotropic::full(psd, fresnel, *options).map_err(|e| fail(e.to_string()))?;
    let table = TableUnderTest {
        psd: m.surface().radial_psd(),
        reach_um: m.surface().reach_um(),
        s_tilde: &|u, g| m.s_tilde(u, g),
    };
    let check = check_table(&table, geometry).map_err(fail)?;
    let label = table_params(c, check, sigma, params);
    Ok((m, label))
}

/// Records a checked table in the report's parameters; the candidate's label with how far
/// the table is from the direct transform.
fn table_params(
    c: &fit::candidates::Candidate,
    check: TableCheck,
    sigma: f64,
    params: &mut Map<String, Value>,
) -> String {
    let label = c.label.clone();
    if let Some(t) = &c.table {
        params.insert("psd_source".into(), json!(t.source));
        params.insert("psd_points".into(), json!(t.points));
        params.insert("psd_tail_exponent".into(), json!(t.tail_exponent));
        params.insert("psd_tail_exponent_clamped".into(), json!(t.tail_clamped));
    }
    params.insert("sigma_um".into(), json!(sigma));
    params.insert("table_max_relative_error".into(), json!(check.worst));
    let g_text = |g: f64| {
        if g >= 10.0 {
            format!("{g:.0}")
        } else {
            format!("{g:.2}")
        }
    };
    match (check.worst > 0.01, check.unverified_above) {
        (true, Some(g)) => format!(
            "{label} (table ±{:.0} %, unverified at g ≥ {})",
            100.0 * check.worst,
            g_text(g)
        ),
        (false, Some(g)) => format!("{label} (table unverified at g ≥ {})", g_text(g)),
        (true, None) => format!("{label} (table ±{:.0} %)", 100.0 * check.worst),
        (false, None) => label,
    }
}

/// An S̃ table to check: the radial PSD it was built from, the largest |u| per unit |ζ|
/// (µm; its length for an isotropic model, the larger stretch for a stretched one) and the
/// model's S̃(u; g).
struct TableUnderTest<'a> {
    psd: &'a TabulatedPsd,
    reach_um: f64,
    s_tilde: &'a dyn Fn(f64, f64) -> f64,
}

/// Largest relative error of a table this judge still ranks (0.3 ≈ 0.11 in log10, about the
/// reference's own noise floor); the measured value is reported with the model.
const TABLE_TOLERANCE: f64 = 0.3;

/// Most Bessel half-periods one direct transform of [`check_table`] may integrate (16
/// kernel evaluations each; ~0.5 s in a test build): a guard against a covariance that
/// never decays, not a budget the bundled scans reach (the bounded transform stops where
/// the rest of its integral is below [`CHECK_REST`] of the peak; corpus/al3d-1, sur-2 and
/// plu-1 are checked at every judged point). Points past it are reported as unverified
/// instead of waited for.
const CHECK_MAX_PANELS: f64 = 1e5;

/// The rest a direct transform of [`check_table`] may leave out, relative to the row's peak
/// (or to S̃(0) itself, for the peak): 1e−6 of S̃ where S̃ is judged (≥ 1e−3 of the peak).
const CHECK_REST: f64 = 1e-9;

/// Compares the model's S̃ table with the direct Hankel transform of the same covariance
/// (`brdf::numerics::hankel::s_tilde_direct_bounded`, the reference method of physics.md §4.1,
/// stopped where the rest of its integral is bounded, §14) at the
/// judged specular g = (2kσ cosθi)² and a quarter of it, for u from 0 to the hemisphere's
/// 2k·reach (2kL for an isotropic table), where S̃ is above 1e−3 of its peak. Returns the largest relative error; a table off by
/// more than [`TABLE_TOLERANCE`] is refused (the judge would rank the table, not the model).
/// Where the direct transform itself fails (large g, see the body) or would cost more than
/// [`CHECK_MAX_PANELS`], the table is reported as unverified there instead of being judged
/// against noise or waited for.
fn check_table(m: &TableUnderTest<'_>, geometry: &[(f64, f64)]) -> Result<TableCheck, String> {
    let psd = m.psd;
    let corr = TabulatedCorrelation::new(psd);
    let (sigma, l) = (psd.sigma_um(), m.reach_um);
    let mut check = TableCheck::default();
    for &(k, ci) in geometry {
        let gs = (2.0 * k * sigma * ci).powi(2);
        for g in [gs, 0.25 * gs] {
            if g < 1e-6 {
                continue;
            }
            // At large g the direct transform of a tabulated covariance cancels to noise
            // (on KautschukInfiniteFocus at g 9.3e3 its S̃(0) came out −2.1e−2, where the
            // lobe's own scale is ~1e−5): a reference that is not positive is no reference.
            let unverified = |check: &mut TableCheck| {
                check.unverified_above = Some(check.unverified_above.map_or(g, |v| v.min(g)));
            };
            let peak_tol = DirectTolerance {
                relative: CHECK_REST,
                absolute: 0.0,
                max_panels: CHECK_MAX_PANELS,
            };
            let peak = hankel::s_tilde_direct_bounded(&corr, 0.0, g, peak_tol).map(|v| v.value);
            let Some(peak) = peak.filter(|p| p.is_finite() && *p > 0.0) else {
                unverified(&mut check);
                continue;
            };
            for f in [0.0, 0.01, 0.03, 0.1, 0.3, 1.0] {
                let u = f * 2.0 * k * l;
                let tol = DirectTolerance {
                    absolute: CHECK_REST * peak,
                    ..peak_tol
                };
                let Some(want) = hankel::s_tilde_direct_bounded(&corr, u, g, tol).map(|v| v.value)
                else {
                    unverified(&mut check);
                    continue;
                };
                if !(want.is_finite() && want >= 1e-3 * peak) {
                    continue;
                }
                let got = (m.s_tilde)(u, g);
                let err = (got / want - 1.0).abs();
                check.worst = check.worst.max(err);
                if err.is_nan() || err > TABLE_TOLERANCE {
                    return Err(format!(
                        "its full-GHS table disagrees with the direct Hankel transform: \
                         S̃(u {u:.3}, g {g:.3e}) = {got:.4e} vs {want:.4e} \
                         (brdf::wave table of a measured PSD)"
                    ));
                }
            }
        }
    }
    Ok(check)
}

/// What [`check_table`] could verify.
#[derive(Default)]
struct TableCheck {
    /// Largest relative error where the direct transform is a usable reference.
    worst: f64,
    /// Smallest judged g where the direct transform was not, or was too costly (see
    /// [`check_table`]).
    unverified_above: Option<f64>,
}

/// The Fresnel factor of the judge's metal (R ≡ 1 without one).
pub(crate) fn fresnel_of(opts: &Options) -> Fresnel {
    match opts.metal {
        Some(m) => Fresnel::conductor(brdf::Ior::metal(m)),
        None => Fresnel::One,
    }
}

/// Rejects a model whose directional albedo (hemispherical integral of the glossy part plus
/// the specular weight, R as given) is not finite or exceeds 2 at any requested (θi, λ): raw
/// GHS may exceed 1 a little at grazing incidence (physics.md §5), nothing physical exceeds 2.
/// This catches tables a model could not build faithfully (e.g. the full-GHS table of a
/// measured PSD with steep segments at large g) instead of ranking nonsense.
pub(crate) fn energy_check(c: Candidate, opts: &Options) -> Built {
    for &t in &opts.theta_i_deg {
        for &l in &opts.lambda_nm {
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

#[cfg(test)]
mod tests {
    use super::*;
    use brdf::spec::{FresnelSpec, MeasuredAnisoSpec};
    use brdf::statistics::KcPsd;
    use brdf::wave::GhsOptions;

    /// 550 nm at 0° and 45°, as `judge`'s defaults.
    fn geometry() -> Vec<(f64, f64)> {
        let k = brdf::paper::wavenumber(550.0);
        vec![(k, 1.0), (k, std::f64::consts::FRAC_1_SQRT_2)]
    }

    /// A K-correlation PSD tabulated (σ 0.04 µm: g ≈ 0.8 at normal incidence), stretched by
    /// Ly/Lx = 6 along 30°.
    fn stretched() -> GhsAnisotropic<EllipticalPsd<TabulatedPsd>> {
        let kc = KcPsd::new(0.04, 0.8, 3.0).unwrap();
        let zeta: Vec<f64> = (0..120).map(|i| 0.02 * 1.08f64.powi(i)).collect();
        let p: Vec<f64> = zeta.iter().map(|&z| kc.psd(z)).collect();
        let spec = MeasuredAnisoSpec {
            zeta_rad_per_um: zeta,
            psd_um4: p,
            lx_um: 0.5,
            ly_um: 3.0,
            angle_deg: 30.0,
        };
        GhsAnisotropic::full(spec.psd().unwrap(), Fresnel::One, GhsOptions::default()).unwrap()
    }

    /// The stretched table agrees with the direct transform of its de-stretched PSD's
    /// covariance over the stretched reach, and a table off by 40 % is refused: the check
    /// can fail.
    #[test]
    fn the_stretched_measured_table_is_checked_against_the_direct_transform() {
        let m = stretched();
        let psd = m.surface().radial_psd();
        assert!(m.surface().reach_um() > 2.0 * psd.length_um());
        let table = TableUnderTest {
            psd,
            reach_um: m.surface().reach_um(),
            s_tilde: &|u, g| m.s_tilde(u, g),
        };
        let check = check_table(&table, &geometry()).unwrap();
        println!(
            "stretched table: worst {:.2e}, unverified above {:?}",
            check.worst, check.unverified_above
        );
        assert!(check.worst > 0.0 && check.worst < 0.01, "{}", check.worst);
        assert_eq!(check.unverified_above, None);
        let off = TableUnderTest {
            s_tilde: &|u, g| 1.4 * m.s_tilde(u, g),
            ..table
        };
        let e = check_table(&off, &geometry()).err().unwrap();
        assert!(
            e.contains("disagrees with the direct Hankel transform"),
            "{e}"
        );
    }

    /// `judge` builds the stretched measured-PSD candidate of a stretched map through the
    /// check, and reports the table's error with it.
    #[test]
    fn the_stretched_candidate_of_a_scan_reports_its_table_check() {
        let params = fit::kc2d::AnisoKcParams {
            sigma: 0.04e-6,
            lx: 0.25e-6,
            ly: 1.0e-6,
            angle_rad: 30f64.to_radians(),
            gamma: 3.0,
        };
        let t = fit::kc2d::synth_surface(256, 256, 20e-6 / 256.0, params, 11);
        let a = fit::pipeline::analyse(t, None, &fit::pipeline::Options::default()).unwrap();
        let cands = fit::candidates::candidates(&a, &FresnelSpec::Metal(brdf::Metal::Cu));
        let c = (cands.iter())
            .find(|c| matches!(c.family, fit::candidates::Family::MeasuredPsdAniso))
            .unwrap();
        let built = build(c, &geometry()).map_err(|e| e.1).unwrap();
        let worst = built.params["table_max_relative_error"].as_f64().unwrap();
        println!("{}: table worst {worst:.2e}", built.label);
        assert!(worst.is_finite() && worst < TABLE_TOLERANCE, "{worst}");
        assert!(built.params.contains_key("psd_source"));
    }
}
