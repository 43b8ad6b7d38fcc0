//! GHS models against data/reference/ghs_reference.json (physics.md §12):
//! scattered BRDF values (full and SSA), specular weights, directional
//! albedos (white furnace against the reference albedos, not against 1),
//! and the Krywonos K. R ≡ 1 throughout, raw energy unless stated.

use brdf::statistics::KcPsd;
use brdf::wave::energy::hemispherical_integral;
use brdf::wave::{Energy, GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Fresnel};
use serde_json::Value;

fn reference() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/reference/ghs_reference.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).expect("reference json")).expect("parse")
}

fn num(v: &Value, k: &str) -> f64 {
    v[k].as_f64().unwrap_or_else(|| panic!("field {k}"))
}

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

struct Surface {
    name: String,
    full: GhsFull,
    ssa: GhsSsa,
}

fn surfaces(r: &Value) -> Vec<Surface> {
    let mut out: Vec<Surface> = Vec::new();
    for row in r["albedo"].as_array().unwrap() {
        let name = row["surface"].as_str().unwrap().to_string();
        if out.iter().any(|s| s.name == name) {
            continue;
        }
        let psd = KcPsd::new(num(row, "sigma_um"), num(row, "Lc_um"), num(row, "gamma")).unwrap();
        out.push(Surface {
            name,
            full: GhsFull::new(psd, Fresnel::One).unwrap(),
            ssa: GhsSsa::new(psd, Fresnel::One).unwrap(),
        });
    }
    out
}

fn find<'a>(s: &'a [Surface], name: &str) -> &'a Surface {
    s.iter().find(|x| x.name == name).unwrap()
}

#[test]
fn brdf_rows_full_and_ssa() {
    let r = reference();
    let s = surfaces(&r);
    let (mut worst_full, mut worst_ssa) = (0.0f64, 0.0f64);
    for row in r["brdf"].as_array().unwrap() {
        let m = find(&s, row["surface"].as_str().unwrap());
        let lam = num(row, "lambda_um") * 1000.0;
        let wi = dir(num(row, "theta_i_deg"), 0.0);
        let wo = dir(num(row, "theta_o_deg"), num(row, "phi_o_deg"));
        let full = m.full.eval(wi, wo, lam);
        let ssa = m.ssa.eval(wi, wo, lam);
        let (want_full, want_ssa) = (num(row, "brdf_full"), num(row, "brdf_ssa"));
        let ef = (full / want_full - 1.0).abs();
        let es = (ssa / want_ssa - 1.0).abs();
        assert!(ef < 1e-3, "{row}: full {full} vs {want_full} ({ef:.2e})");
        assert!(es < 1e-10, "{row}: ssa {ssa} vs {want_ssa} ({es:.2e})");
        worst_full = worst_full.max(ef);
        worst_ssa = worst_ssa.max(es);
    }
    println!("max relative error: full {worst_full:.2e}, ssa {worst_ssa:.2e}");
}

#[test]
fn specular_weights_and_albedos() {
    let r = reference();
    let s = surfaces(&r);
    let mut worst = [0.0f64; 4];
    for row in r["albedo"].as_array().unwrap() {
        let m = find(&s, row["surface"].as_str().unwrap());
        let lam = num(row, "lambda_um") * 1000.0;
        let wi = dir(num(row, "theta_i_deg"), 0.0);
        let a_s = num(row, "A_specular");
        for spec in [m.full.specular(wi, lam), m.ssa.specular(wi, lam)] {
            let e = if a_s > 1e-300 {
                (spec.weight / a_s - 1.0).abs()
            } else {
                spec.weight
            };
            assert!(e < 1e-12, "{row}: specular {} vs {a_s}", spec.weight);
        }
        let kl = 2.0 * std::f64::consts::PI / num(row, "lambda_um") * num(row, "Lc_um");
        let full = hemispherical_integral(wi, 1.0 / kl, |o| m.full.eval(wi, o, lam));
        let ssa = hemispherical_integral(wi, 1.0 / kl, |o| m.ssa.eval(wi, o, lam));
        let cases = [
            (full, num(row, "albedo_scat_full")),
            (ssa, num(row, "albedo_scat_ssa")),
            (a_s + full, num(row, "albedo_total_full")),
            (a_s + ssa, num(row, "albedo_total_ssa")),
        ];
        for (i, (got, want)) in cases.iter().enumerate() {
            let e = (got / want - 1.0).abs();
            assert!(
                e < 1e-3,
                "{row}: albedo case {i}: {got} vs {want} ({e:.2e})"
            );
            worst[i] = worst[i].max(e);
        }
    }
    println!(
        "max relative albedo error: full {:.2e} ssa {:.2e} total-full {:.2e} total-ssa {:.2e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

#[test]
fn krywonos_factor_matches_reference_and_conserves_energy() {
    let r = reference();
    let opts = GhsOptions {
        energy: Energy::Krywonos,
        ..Default::default()
    };
    let mut worst_k = 0.0f64;
    let mut worst_total = 0.0f64;
    let mut done: Vec<String> = Vec::new();
    for row in r["albedo"].as_array().unwrap() {
        let name = row["surface"].as_str().unwrap().to_string();
        if done.contains(&name) {
            continue;
        }
        done.push(name.clone());
        let psd = KcPsd::new(num(row, "sigma_um"), num(row, "Lc_um"), num(row, "gamma")).unwrap();
        let full = GhsFull::with_options(psd, Fresnel::One, opts).unwrap();
        let ssa = GhsSsa::with_options(psd, Fresnel::One, opts).unwrap();
        for row in r["albedo"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| x["surface"] == name.as_str())
        {
            let lam = num(row, "lambda_um") * 1000.0;
            let wi = dir(num(row, "theta_i_deg"), 0.0);
            let kl = 2.0 * std::f64::consts::PI / num(row, "lambda_um") * num(row, "Lc_um");
            for (model, kref, raw) in [
                (
                    &full as &dyn Bxdf,
                    num(row, "K_renorm_full"),
                    num(row, "albedo_scat_full"),
                ),
                (
                    &ssa as &dyn Bxdf,
                    num(row, "K_renorm_ssa"),
                    num(row, "albedo_scat_ssa"),
                ),
            ] {
                let a = hemispherical_integral(wi, 1.0 / kl, |o| model.eval(wi, o, lam));
                let spec = model.specular(wi, lam).weight;
                // K realised by the model = renormalised albedo / raw albedo
                let k = a / raw;
                let ek = (k / kref - 1.0).abs();
                worst_k = worst_k.max(ek);
                worst_total = worst_total.max((spec + a - 1.0).abs());
                assert!(ek < 5e-3, "{row}: K {k} vs {kref}");
                assert!(spec + a <= 1.0 + 5e-3, "{row}: total {}", spec + a);
            }
        }
    }
    println!("Krywonos: max |K/K_ref − 1| = {worst_k:.2e}, max |total − 1| = {worst_total:.2e}");
}
