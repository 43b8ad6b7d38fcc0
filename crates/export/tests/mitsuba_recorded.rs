//! The export read by Mitsuba 3.9.1's own `measured` plugin and by
//! `export::RglTable` gives the same values.
//!
//! `validate/mitsuba_eval.json` holds, for three small tables (GGX copper,
//! full GHS of S280, anisotropic GGX gold as RGB), Mitsuba's `eval`
//! (f cosθo), `pdf` and `sample` at random directions and wavelengths,
//! written by `validate/mitsuba_check.py record` from files made with
//! `lustre brdf export`. This test rebuilds the same tables with the library
//! and evaluates them with the crate's reader: a disagreement means the
//! file or the reader departs from the format as Mitsuba reads it. (A change
//! to what the exporter writes changes the tables: record them again.)

use brdf::DVec3;
use brdf::spec::{MaterialDesc, NoFiles};
use export::{Colour, RglOptions, RglTable};
use serde_json::Value;

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn vec3(v: &Value) -> DVec3 {
    let a = f64s(v);
    DVec3::new(a[0], a[1], a[2])
}

fn pair(v: &Value) -> [usize; 2] {
    let a = f64s(v);
    [a[0] as usize, a[1] as usize]
}

fn options(o: &Value) -> RglOptions {
    RglOptions {
        theta_i_deg: f64s(&o["theta_i_deg"]),
        phi_i_nodes: o["phi_i_nodes"].as_u64().unwrap() as usize,
        sample_nodes: o["sample_nodes"].as_u64().unwrap() as usize,
        vndf_nodes: pair(&o["vndf_nodes"]),
        ndf_nodes: pair(&o["ndf_nodes"]),
        sigma_nodes: pair(&o["sigma_nodes"]),
        wavelengths_nm: f64s(&o["wavelengths_nm"]),
        colour: if o["rgb"].as_bool().unwrap() {
            Colour::Rgb
        } else {
            Colour::Spectral
        },
        drop_specular: o["drop_specular"].as_bool().unwrap(),
        check_samples: 0,
        ..RglOptions::default()
    }
}

/// |a − b| within `rel` of the larger, or below `abs`.
fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

#[test]
fn export_reads_back_in_rust_as_mitsuba_reads_it() {
    let doc: Value = serde_json::from_str(include_str!("../validate/mitsuba_eval.json")).unwrap();
    let cases = doc["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3);
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let desc: MaterialDesc = serde_json::from_value(case["material"].clone()).unwrap();
        let spec = desc.into_spec(&mut NoFiles).unwrap();
        let out = export::rgl_material(&spec, &options(&case["options"])).unwrap();
        let table = RglTable::parse(&out.bytes).unwrap();
        let rows = case["rows"].as_array().unwrap();
        let (mut worst, mut nonzero) = (0.0f64, 0);
        for (i, r) in rows.iter().enumerate() {
            let (wi, wo) = (vec3(&r["wi"]), vec3(&r["wo"]));
            let lambdas = f64s(&r["lambda"]);
            for (k, &m) in f64s(&r["f_cos"]).iter().enumerate() {
                let ours = table.eval_cos(wi, wo, lambdas[k]);
                // Mitsuba works in f32: 1e-3 relative covers its rounding
                // through the warp inversion; the absolute term values
                // near zero.
                assert!(
                    close(ours, m, 2e-3, 1e-6),
                    "{name} row {i} λ {}: ours {ours:e}, Mitsuba {m:e}",
                    lambdas[k]
                );
                if m > 0.0 {
                    worst = worst.max((ours - m).abs() / m);
                    nonzero += 1;
                }
            }
            let (ours, m) = (table.pdf(wi, wo), r["pdf"].as_f64().unwrap());
            assert!(
                close(ours, m, 2e-3, 1e-6),
                "{name} row {i}: pdf ours {ours:e}, Mitsuba {m:e}"
            );
        }
        // The comparison must not be vacuous: most rows see the lobe.
        assert!(
            nonzero > rows.len(),
            "{name}: only {nonzero} non-zero values"
        );
        eprintln!("{name}: {nonzero} values, worst relative difference {worst:.2e}");
        for (i, s) in case["samples"].as_array().unwrap().iter().enumerate() {
            let wi = vec3(&s["wi"]);
            let u = f64s(&s["u"]);
            let m_pdf = s["pdf"].as_f64().unwrap();
            // Mitsuba hands the luminance warp (u.y, u.x).
            match table.sample(wi, [u[1], u[0]]) {
                Some(ours) => {
                    let m_wo = vec3(&s["wo"]);
                    assert!(
                        (ours.wo - m_wo).length() < 1e-3,
                        "{name} sample {i}: {:?} vs {m_wo:?}",
                        ours.wo
                    );
                    assert!(
                        close(ours.pdf, m_pdf, 2e-3, 1e-6),
                        "{name} sample {i}: pdf {} vs {m_pdf}",
                        ours.pdf
                    );
                }
                // Below the horizon: Mitsuba still returns the direction, with no weight.
                None => assert!(
                    vec3(&s["wo"]).z <= 1e-6 || m_pdf == 0.0,
                    "{name} sample {i}"
                ),
            }
        }
    }
}
