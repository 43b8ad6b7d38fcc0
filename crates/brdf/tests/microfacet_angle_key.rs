//! The `angle_deg` key of `ggx` and `beckmann` (αx along the axis at `angle_deg` from
//! the tangent x towards y, the convention of the `_aniso` models), through the one
//! material description every entry point reads: a material turned by φ equals the
//! unturned one at directions turned by φ (value and pdf, over α pairs, angles and
//! directions); 90° swaps αx and αy; 0 or absent builds the same bits as a material
//! written before the key; sampling matches the pdf; reciprocity; bad values and misuse
//! name the key; an included fit file's angle turns its own pair only.

use brdf::spec::{FresnelSpec, MaterialDesc, MaterialSpec, ModelKind, ModelSpec, NoFiles};
use brdf::testing::{Chi2Config, chi2_test, sidak};
use brdf::{Bxdf, DVec3, Distribution, Fresnel, Metal, MicrofacetConductor};
use proptest::prelude::*;

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// R(φ) v, written here independently of `brdf::microfacet::Rotated`.
fn turn(v: DVec3, deg: f64) -> DVec3 {
    let (s, c) = deg.to_radians().sin_cos();
    DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

fn model(beckmann: bool, alpha_x: f64, alpha_y: f64, angle_deg: f64) -> ModelSpec {
    if beckmann {
        ModelSpec::Beckmann {
            alpha_x,
            alpha_y,
            angle_deg,
        }
    } else {
        ModelSpec::Ggx {
            alpha_x,
            alpha_y,
            angle_deg,
        }
    }
}

fn material(beckmann: bool, ax: f64, ay: f64, angle_deg: f64) -> MaterialSpec {
    MaterialSpec {
        model: model(beckmann, ax, ay, angle_deg),
        fresnel: FresnelSpec::Metal(Metal::Au),
    }
}

fn desc(json: &str) -> MaterialDesc {
    serde_json::from_str(json).unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The key as written in a description, built, equals the unturned material at
    /// turned directions, and is reciprocal.
    #[test]
    fn a_turned_material_is_the_material_at_turned_directions(
        beckmann in any::<bool>(),
        ax in 0.005f64..1.0,
        ay in 0.005f64..1.0,
        angle in -400.0f64..400.0,
        (ti, pi) in (0.0f64..89.0, 0.0f64..360.0),
        (to, po) in (0.0f64..89.0, 0.0f64..360.0),
        lambda in 360.0f64..830.0,
    ) {
        let turned = MaterialDesc {
            model: Some(if beckmann { ModelKind::Beckmann } else { ModelKind::Ggx }),
            metal: Some("au".into()),
            alpha_x: Some(ax),
            alpha_y: Some(ay),
            angle_deg: Some(angle),
            ..MaterialDesc::default()
        }
        .into_spec(&mut NoFiles)
        .unwrap();
        prop_assert_eq!(&turned, &material(beckmann, ax, ay, angle));
        let turned = turned.build().unwrap();
        let flat = material(beckmann, ax, ay, 0.0).build().unwrap();
        let (wi, wo) = (dir(ti, pi), dir(to, po));
        let (f, p) = flat.eval_pdf(wi, wo, lambda);
        let (g, q) = turned.eval_pdf(turn(wi, angle), turn(wo, angle), lambda);
        prop_assert!(close(f, g, 1e-9) && close(p, q, 1e-9), "f {f} {g} pdf {p} {q}");
        let r = turned.eval(turn(wo, angle), turn(wi, angle), lambda);
        prop_assert!(close(g, r, 1e-9), "reciprocity {g} {r}");
        // A sample of the turned material is the turned sample of the unturned one (an
        // isotropic pair is not turned: its samples differ, their distribution does not).
        let u = [0.31, 0.77, 0.52];
        let a = flat.sample(wi, lambda, u);
        let b = turned.sample(turn(wi, angle), lambda, u);
        prop_assert_eq!(a.is_some(), b.is_some());
        if let (Some(a), Some(b), true) = (a, b, ax != ay) {
            prop_assert!((turn(a.wo, angle) - b.wo).length() < 1e-9);
            prop_assert!(close(a.weight, b.weight, 1e-9) && close(a.pdf, b.pdf, 1e-9));
        }
    }

    /// A quarter turn swaps the axes; a half turn is the material itself.
    #[test]
    fn a_quarter_turn_swaps_the_axes(
        beckmann in any::<bool>(),
        ax in 0.005f64..1.0,
        ay in 0.005f64..1.0,
        (ti, pi) in (0.0f64..89.0, 0.0f64..360.0),
        (to, po) in (0.0f64..89.0, 0.0f64..360.0),
    ) {
        let quarter = material(beckmann, ax, ay, 90.0).build().unwrap();
        let swapped = material(beckmann, ay, ax, 0.0).build().unwrap();
        let half = material(beckmann, ax, ay, -180.0).build().unwrap();
        let same = material(beckmann, ax, ay, 0.0).build().unwrap();
        let (wi, wo) = (dir(ti, pi), dir(to, po));
        let (a, pa) = quarter.eval_pdf(wi, wo, 550.0);
        let (b, pb) = swapped.eval_pdf(wi, wo, 550.0);
        prop_assert!(close(a, b, 1e-9) && close(pa, pb, 1e-9), "{a} {b}");
        let (c, pc) = half.eval_pdf(wi, wo, 550.0);
        let (d, pd) = same.eval_pdf(wi, wo, 550.0);
        prop_assert!(close(c, d, 1e-9) && close(pc, pd, 1e-9), "{c} {d}");
    }
}

/// αx = 0.05 at 30°: the lobe at normal incidence is narrow along 30° and wide along
/// 120° (a closed-form check of the direction of the turn, not only of its consistency).
#[test]
fn the_narrow_axis_lies_at_the_angle() {
    for beckmann in [false, true] {
        let m = material(beckmann, 0.05, 0.4, 30.0).build().unwrap();
        let wi = dir(0.0, 0.0);
        let along = m.eval(wi, dir(10.0, 30.0), 550.0);
        let across = m.eval(wi, dir(10.0, 120.0), 550.0);
        assert!(across > 5.0 * along, "{along} {across}");
        // …and 30° is not −30°.
        let mirror = m.eval(wi, dir(10.0, -30.0), 550.0);
        assert!(mirror > 2.0 * along, "{along} {mirror}");
    }
}

/// `angle_deg = 0`, `-0.0` or absent: the same bits as the material without the key, for
/// value, pdf and samples; an isotropic pair is not turned at all.
#[test]
fn zero_or_absent_is_bit_identical() {
    for name in ["ggx", "beckmann"] {
        for pair in [r#""alpha_x": 0.07, "alpha_y": 0.45"#, r#""alpha": 0.2"#] {
            let base = format!(r#"{{"model": "{name}", "metal": "cu", {pair}"#);
            let built: Vec<_> = [
                format!("{base}}}"),
                format!(r#"{base}, "angle_deg": 0}}"#),
                format!(r#"{base}, "angle_deg": -0.0}}"#),
            ]
            .iter()
            .map(|j| desc(j).into_spec(&mut NoFiles).unwrap().build().unwrap())
            .collect();
            // What the spec built before the key: the conductor itself.
            let (ax, ay) = if pair.contains(r#""alpha""#) {
                (0.2, 0.2)
            } else {
                (0.07, 0.45)
            };
            let dist = if name == "ggx" {
                Distribution::ggx(ax, ay)
            } else {
                Distribution::beckmann(ax, ay)
            };
            let before: brdf::spec::DynBxdf = Box::new(
                MicrofacetConductor::new(
                    dist.unwrap(),
                    Fresnel::conductor(brdf::Ior::metal(Metal::Cu)),
                )
                .unwrap(),
            );
            let iso_turned = (pair.contains(r#""alpha""#)).then(|| {
                desc(&format!(r#"{base}, "angle_deg": 33}}"#))
                    .into_spec(&mut NoFiles)
                    .unwrap()
                    .build()
                    .unwrap()
            });
            for (ti, pi) in [(0.0, 0.0), (35.0, 10.0), (70.0, 250.0), (88.0, 95.0)] {
                for (to, po) in [(5.0, 40.0), (ti, pi + 180.0), (60.0, 300.0)] {
                    let (wi, wo) = (dir(ti, pi), dir(to, po));
                    let bits = |m: &brdf::spec::DynBxdf| {
                        let (f, p) = m.eval_pdf(wi, wo, 500.0);
                        let s = m.sample(wi, 500.0, [0.2, 0.6, 0.9]).unwrap();
                        [f, p, s.wo.x, s.wo.y, s.wo.z, s.weight, s.pdf].map(f64::to_bits)
                    };
                    let want = bits(&before);
                    for m in &built {
                        assert_eq!(bits(m), want, "{name} {pair}");
                    }
                    if let Some(m) = &iso_turned {
                        assert_eq!(bits(m), want, "{name} {pair} turned");
                    }
                }
            }
        }
    }
    // The description writes no key at 0, as a material written before the key.
    let flat = material(false, 0.1, 0.3, 0.0).to_desc();
    assert_eq!(flat.angle_deg, None);
    let turned = material(true, 0.1, 0.3, -15.0);
    assert_eq!(turned.to_desc().angle_deg, Some(-15.0));
    assert_eq!(turned.to_desc().into_spec(&mut NoFiles).unwrap(), turned);
}

#[test]
fn sampling_matches_the_pdf() {
    let sets = [
        (false, 0.05, 0.4, 30.0, (0.0, 0.0)),
        (false, 0.3, 0.02, -60.0, (50.0, 40.0)),
        (true, 0.1, 0.5, 75.0, (70.0, 200.0)),
        (true, 0.6, 0.15, 200.0, (30.0, 300.0)),
    ];
    let alpha = sidak(0.01, sets.len());
    let mut failures = Vec::new();
    for (i, &(beckmann, ax, ay, angle, (ti, pi))) in sets.iter().enumerate() {
        let m = material(beckmann, ax, ay, angle).build().unwrap();
        let cfg = Chi2Config {
            samples: 120_000,
            pilot_samples: 30_000,
            seed: 4100 + i as u64,
            ..Default::default()
        };
        let rep = chi2_test(m.as_ref(), dir(ti, pi), 550.0, &cfg);
        println!(
            "set {i}: χ² {:.1} dof {} p {:.3}",
            rep.statistic, rep.dof, rep.p_value
        );
        if !rep.passes(alpha) {
            failures.push(format!("set {i}: {}", rep.check(alpha).unwrap_err()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// A bad angle names `angle_deg` with the words of the stretched models' check.
#[test]
fn bad_values_and_misuse_name_the_key() {
    for bad in [f64::NAN, f64::INFINITY, -1e300] {
        for beckmann in [false, true] {
            let e = material(beckmann, 0.1, 0.3, bad).validate().unwrap_err();
            assert_eq!(e.field, "angle_deg", "{e}");
            assert!(material(beckmann, 0.1, 0.3, bad).build().is_err());
            let aniso = MaterialSpec {
                model: ModelSpec::GhsAniso {
                    surface: brdf::spec::AnisoSpec {
                        sigma_um: 0.05,
                        lx_um: 1.0,
                        ly_um: 3.0,
                        angle_deg: bad,
                        gamma: 2.5,
                    },
                    options: Default::default(),
                },
                fresnel: FresnelSpec::One,
            };
            assert_eq!(aniso.validate().unwrap_err(), e);
        }
    }
    let e = desc(r#"{"model": "ggx", "metal": "cu", "alpha": 0.1, "angle_deg": 1e300}"#)
        .into_spec(&mut NoFiles)
        .unwrap_err();
    assert_eq!(e.field, "angle_deg", "{e}");
    let e = serde_json::from_str::<MaterialDesc>(r#"{"model": "ggx", "angle_deg": "30"}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid type"), "{e}");
    // The models without an axis still refuse it, by name.
    for keys in [
        r#""model": "smooth""#,
        r#""model": "ghs_ssa", "sigma_um": 0.1, "lc_um": 1, "gamma": 2"#,
        r#""model": "two_scale", "beta": 0.1, "sigma_um": 0.1, "lc_um": 1, "gamma": 2"#,
        r#""model": "roughplastic", "alpha": 0.1"#,
        r#""model": "diffuse", "reflectance": 0.5"#,
    ] {
        let e = desc(&format!(r#"{{{keys}, "angle_deg": 10}}"#))
            .into_spec(&mut NoFiles)
            .unwrap_err();
        assert_eq!(e.field, "angle_deg", "{keys}: {e}");
        assert!(e.message.contains("does not use"), "{keys}: {e}");
    }
}

/// A fit file carries `alpha_x`, `alpha_y` and their `angle_deg`: an include takes the
/// three together; a pair set over it is along the tangent axes unless turned there too;
/// an angle alone set over it turns the file's pair.
#[test]
fn an_included_angle_turns_the_files_pair_only() {
    let file = desc(
        r#"{"model": "ghs", "metal": "cu", "alpha": 0.2, "alpha_x": 0.3, "alpha_y": 0.1,
            "angle_deg": 40, "sigma_um": 0.05, "lx_um": 1, "ly_um": 3}"#,
    );
    let over = |json: &str| desc(json).resolve(Some(&file), &mut NoFiles).unwrap().model;
    assert_eq!(over(r#"{"model": "ggx"}"#), model(false, 0.3, 0.1, 40.0));
    assert_eq!(
        over(r#"{"model": "beckmann"}"#),
        model(true, 0.3, 0.1, 40.0)
    );
    assert_eq!(
        over(r#"{"model": "ggx", "alpha_x": 0.5, "alpha_y": 0.05}"#),
        model(false, 0.5, 0.05, 0.0)
    );
    assert_eq!(
        over(r#"{"model": "ggx", "alpha_x": 0.5, "alpha_y": 0.05, "angle_deg": 5}"#),
        model(false, 0.5, 0.05, 5.0)
    );
    assert_eq!(
        over(r#"{"model": "ggx", "angle_deg": -50}"#),
        model(false, 0.3, 0.1, -50.0)
    );
    assert_eq!(
        over(r#"{"model": "ggx", "alpha": 0.05}"#),
        model(false, 0.05, 0.05, 0.0)
    );
    // The stretched models keep taking the file's angle with its lengths.
    let ModelSpec::GhsSsaAniso { surface, .. } =
        over(r#"{"model": "ghs_ssa_aniso", "gamma": 2.5}"#)
    else {
        panic!()
    };
    assert_eq!(surface.angle_deg, 40.0);
    // Which file a merged value came from.
    let own = desc(r#"{"model": "ggx", "alpha_x": 0.5, "alpha_y": 0.05}"#);
    assert!(!own.inherits(&file, "angle_deg"));
    assert!(desc(r#"{"model": "ggx"}"#).inherits(&file, "angle_deg"));
    assert!(!desc(r#"{"angle_deg": 3}"#).inherits(&file, "angle_deg"));
}
