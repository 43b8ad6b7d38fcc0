//! Exports read back as the renderers read them equal the model within the
//! error each export states, at incidences, azimuths and wavelengths the
//! exporter did not check; and the stated errors are small.

use brdf::spec::{FresnelSpec, MaterialSpec, ModelSpec};
use brdf::{Bxdf, DVec3, Metal};
use export::check::{self, Rng, Sides};
use export::{Colour, ExportError, MerlOptions, MerlTable, RglOptions, RglTable};

/// A table small enough for a test (tens of ms to build) that still
/// resolves a lobe of α ≳ 0.1.
fn small() -> RglOptions {
    RglOptions {
        theta_i_deg: (0..=10)
            .map(|k| 6.0 * k as f64)
            .chain([64.0, 68.0, 72.0, 76.0, 80.0, 84.0, 88.0])
            .collect(),
        sample_nodes: 40,
        vndf_nodes: [64, 32],
        ndf_nodes: [128, 32],
        sigma_nodes: [64, 32],
        phi_i_nodes: 9,
        check_samples: 2048,
        ..RglOptions::default()
    }
}

fn ggx(alpha_x: f64, alpha_y: f64, metal: Metal) -> MaterialSpec {
    MaterialSpec {
        model: ModelSpec::Ggx {
            alpha_x,
            alpha_y,
            angle_deg: 0.0,
        },
        fresnel: FresnelSpec::Metal(metal),
    }
}

/// Relative L1 error of the table's lobe against the model's at `wi`,
/// `lambda`, from `n` directions drawn independently of the exporter's own
/// estimate (another generator, other angles).
fn l1(table: &RglTable, model: &dyn Bxdf, wi: DVec3, lambda: f64, n: usize, seed: u64) -> [f64; 4] {
    let ts = |u: [f64; 2]| table.sample(wi, u).map(|s| s.wo);
    let tp = |wo: DVec3| table.pdf(wi, wo);
    let truth = |wo: DVec3, out: &mut [f64]| out[0] = model.eval(wi, wo, lambda);
    let approx = |wo: DVec3, out: &mut [f64]| out[0] = table.eval(wi, wo, lambda);
    let sides = Sides {
        model,
        sample_lambda_nm: lambda,
        table_sample: &ts,
        table_pdf: &tp,
        truth: &truth,
        approx: &approx,
    };
    check::estimate(wi, &sides, 1, n, &mut Rng::new(seed))[0]
}

fn random_direction(rng: &mut Rng, theta_max_deg: f64) -> DVec3 {
    let t = rng.uniform() * theta_max_deg.to_radians();
    let p = (rng.uniform() * 2.0 - 1.0) * core::f64::consts::PI;
    export::param::direction(t, p)
}

#[test]
fn ggx_copper_reads_back_within_its_stated_error() {
    let spec = ggx(0.2, 0.2, Metal::Cu);
    let out = export::rgl_material(&spec, &small()).unwrap();
    let stated = out.report.max_rel_l1();
    // The budget a table this size meets (a broken table is off by O(1)).
    assert!(stated < 0.01, "{}", out.report.summary());
    assert!(
        out.report.max_albedo_error() < 0.005,
        "{}",
        out.report.summary()
    );
    let table = RglTable::parse(&out.bytes).unwrap();
    let model = spec.build().unwrap();
    let mut rng = Rng::new(99);
    for _ in 0..12 {
        let wi = random_direction(&mut rng, 80.0);
        let lambda = 400.0 + 300.0 * rng.uniform();
        let [a, b, e, se] = l1(&table, &*model, wi, lambda, 3000, rng.uniform().to_bits());
        assert!(
            e <= 1.5 * stated + 3.0 * se,
            "θi {:.1}°: L1 {e:.2e} ± {se:.1e} > stated {stated:.2e}",
            wi.z.acos().to_degrees()
        );
        assert!((b / a - 1.0).abs() < 1.5 * out.report.max_albedo_error() + 3.0 * se + 1e-3);
    }
}

#[test]
fn full_ghs_reads_back_within_its_stated_error() {
    // S280 (brass, σ 0.28 µm, Lc 5 µm, γ 3): no microfacet model, so the
    // table is parameterised by the distribution of its retro-reflection.
    let spec = brdf::paper::find_sample("S280")
        .unwrap()
        .material(brdf::paper::PaperModel::Ghs);
    let o = RglOptions {
        drop_specular: true,
        check_theta_max_deg: 60.0,
        ..small()
    };
    let out = export::rgl_material(&spec, &o).unwrap();
    let stated = out.report.max_rel_l1();
    assert!(stated < 0.03, "{}", out.report.summary());
    // The coherent lobe at 60°, 830 nm: R e^{−(2kσ cos60°)²} = 0.94 e^{−4.5}.
    let expect = 0.94 * (-(2.0 * 2.0 * core::f64::consts::PI / 0.83 * 0.28 * 0.5f64).powi(2)).exp();
    assert!(
        (out.report.dropped_specular / expect - 1.0).abs() < 0.05,
        "{}",
        out.report.dropped_specular
    );
    let table = RglTable::parse(&out.bytes).unwrap();
    let model = spec.build().unwrap();
    let mut rng = Rng::new(7);
    for _ in 0..6 {
        let wi = random_direction(&mut rng, 60.0);
        let lambda = 420.0 + 280.0 * rng.uniform();
        let [_, _, e, se] = l1(&table, &*model, wi, lambda, 2000, rng.uniform().to_bits());
        assert!(
            e <= 1.5 * stated + 3.0 * se,
            "θi {:.1}°: L1 {e:.2e} ± {se:.1e} > stated {stated:.2e}",
            wi.z.acos().to_degrees()
        );
    }
}

#[test]
fn anisotropic_ggx_keeps_its_azimuths() {
    let spec = ggx(0.1, 0.3, Metal::Au);
    let o = RglOptions {
        wavelengths_nm: (0..=12).map(|k| 400.0 + 25.0 * k as f64).collect(),
        check_samples: 1024,
        ..small()
    };
    let out = export::rgl_material(&spec, &o).unwrap();
    let table = RglTable::parse(&out.bytes).unwrap();
    assert!(!table.is_isotropic());
    // Linear interpolation across 45° of incident azimuth: a few % on
    // average, 10 % at grazing incidence between the azimuth nodes.
    let r = &out.report;
    assert!(
        r.mean_rel_l1() < 0.03 && r.max_rel_l1() < 0.15,
        "{}",
        r.summary()
    );
    // The lobe is three times wider along y: 20° off the normal, seen along
    // the normal, f along y and along x differ by the model's factor.
    let model = spec.build().unwrap();
    let n = DVec3::Z;
    let (x, y) = (
        export::param::direction(0.35, 0.0),
        export::param::direction(0.35, core::f64::consts::FRAC_PI_2),
    );
    let rm = model.eval(n, y, 550.0) / model.eval(n, x, 550.0);
    let rt = table.eval(n, y, 550.0) / table.eval(n, x, 550.0);
    assert!(
        rm > 5.0 && (rt / rm - 1.0).abs() < 0.02,
        "model ratio {rm}, table {rt}"
    );
}

#[test]
fn rgb_of_a_white_reflector_is_grey_and_equals_the_spectral_value() {
    let spec = MaterialSpec {
        fresnel: FresnelSpec::One,
        ..ggx(0.3, 0.3, Metal::Cu)
    };
    let o = RglOptions {
        colour: Colour::Rgb,
        check_samples: 0,
        ..small()
    };
    let table = RglTable::parse(&export::rgl_material(&spec, &o).unwrap().bytes).unwrap();
    assert!(!table.is_spectral());
    let o = RglOptions {
        colour: Colour::Spectral,
        ..o
    };
    let spectral = RglTable::parse(&export::rgl_material(&spec, &o).unwrap().bytes).unwrap();
    let mut rng = Rng::new(3);
    let mut lit = 0;
    for _ in 0..300 {
        let (wi, wo) = (
            random_direction(&mut rng, 75.0),
            random_direction(&mut rng, 85.0),
        );
        let rgb = [0.0, 1.0, 2.0].map(|c| table.eval(wi, wo, c));
        // A flat spectrum under D65 is sRGB (1, 1, 1) to 1e-4 (color.rs), so
        // every channel is the spectral table's value at any wavelength.
        let s = spectral.eval(wi, wo, 400.0 + 300.0 * rng.uniform());
        for c in rgb {
            assert!((c - s).abs() <= 1e-3 * s + 1e-9, "{rgb:?} vs {s}");
        }
        lit += (s > 0.0) as usize;
    }
    assert!(lit > 250, "{lit}");
}

#[test]
fn merl_of_ggx_reads_back_within_its_stated_error_and_cell_by_cell() {
    let spec = ggx(0.25, 0.25, Metal::Cu);
    let o = MerlOptions {
        wavelengths_nm: (0..=9).map(|k| 380.0 + 40.0 * k as f64).collect(),
        check_samples: 1024,
        ..MerlOptions::default()
    };
    let out = export::merl_material(&spec, &o).unwrap();
    assert_eq!(out.bytes.len(), 12 + 3 * 90 * 90 * 180 * 8);
    assert!(out.report.max_rel_l1() < 0.05, "{}", out.report.summary());
    assert!(
        out.report.max_albedo_error() < 0.01,
        "{}",
        out.report.summary()
    );
    let table = MerlTable::parse(&out.bytes).unwrap();
    let model = spec.build().unwrap();
    let w = export::color::srgb_weights(&o.wavelengths_nm, o.illuminant);
    let rgb = |wi: DVec3, wo: DVec3| {
        let f: Vec<f64> = o
            .wavelengths_nm
            .iter()
            .map(|&l| model.eval(wi, wo, l))
            .collect();
        [0, 1, 2].map(|c| w.iter().zip(&f).map(|(wk, fk)| wk[c] * fk).sum::<f64>())
    };
    // Any pair reads the model's value at the centre of its cell.
    let mut rng = Rng::new(11);
    for _ in 0..300 {
        let (wi, wo) = (
            random_direction(&mut rng, 85.0),
            random_direction(&mut rng, 85.0),
        );
        let (th, td, pd) = export::merl::half_diff(wi, wo).unwrap();
        let i = export::merl::cell(th, td, pd);
        let (ih, id, ip) = (i / (90 * 180), (i / 180) % 90, i % 180);
        let (a, b) = export::merl::from_half_diff(
            export::merl::cell_centre(ih, id, ip).0,
            export::merl::cell_centre(ih, id, ip).1,
            export::merl::cell_centre(ih, id, ip).2,
        );
        let want = if a.z > 0.0 && b.z > 0.0 {
            rgb(a, b)
        } else {
            [0.0; 3]
        };
        let got = table.eval(wi, wo);
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() <= 1e-12 * want[c].abs().max(1e-300) + 1e-15,
                "{got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn what_a_table_cannot_hold_is_refused_by_name() {
    let smooth = MaterialSpec {
        model: ModelSpec::Smooth,
        fresnel: FresnelSpec::Metal(Metal::Ag),
    };
    let e = export::rgl_material(&smooth, &small())
        .unwrap_err()
        .to_string();
    assert!(e.contains("smooth") && e.contains("delta"), "{e}");
    // S027 (σ 27 nm) reflects most light coherently even at normal incidence.
    let s027 = brdf::paper::find_sample("S027")
        .unwrap()
        .material(brdf::paper::PaperModel::Ghs);
    match export::rgl_material(&s027, &small()) {
        Err(ExportError::Specular {
            weight,
            theta_i_deg,
            ..
        }) => {
            assert!(weight > 0.1 && theta_i_deg <= 80.0);
        }
        other => panic!("{other:?}"),
    }
    let e = export::merl_material(&ggx(0.1, 0.2, Metal::Cu), &MerlOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("anisotropic") && e.contains("MERL"), "{e}");
    // Isotropy is asked of the model, not of its kind: a generic anisotropic
    // BRDF is refused by MERL and by the retro-reflection parameterisation.
    let aniso = ggx(0.1, 0.2, Metal::Cu).build().unwrap();
    assert!(!export::is_isotropic(&*aniso));
    assert!(export::is_isotropic(
        &*ggx(0.2, 0.2, Metal::Cu).build().unwrap()
    ));
    assert!(export::is_isotropic(&*s027.build().unwrap()));
    let e = export::rgl(&*aniso, &export::NdfSource::Backscatter, &small())
        .unwrap_err()
        .to_string();
    assert!(e.contains("anisotropic"), "{e}");
    assert!(export::merl(&*aniso, &MerlOptions::default()).is_err());
    for (o, field) in [
        (
            RglOptions {
                theta_i_deg: vec![10.0, 5.0],
                ..small()
            },
            "theta_i_deg",
        ),
        (
            RglOptions {
                theta_i_deg: vec![95.0],
                ..small()
            },
            "theta_i_deg",
        ),
        (
            RglOptions {
                sample_nodes: 1,
                ..small()
            },
            "sample_nodes",
        ),
        (
            RglOptions {
                wavelengths_nm: vec![300.0],
                ..small()
            },
            "wavelengths_nm",
        ),
        (
            RglOptions {
                vndf_nodes: [1, 8],
                ..small()
            },
            "vndf_nodes",
        ),
        (
            RglOptions {
                check_theta_max_deg: f64::NAN,
                ..small()
            },
            "check_theta_max_deg",
        ),
        (
            RglOptions {
                sample_nodes: 1024,
                wavelengths_nm: (0..400).map(|k| 400.0 + k as f64).collect(),
                ..small()
            },
            "sample_nodes",
        ),
    ] {
        match export::rgl_material(&ggx(0.2, 0.2, Metal::Cu), &o) {
            Err(ExportError::Option { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {other:?}"),
        }
    }
}

/// An anisotropic microfacet material turned by `angle_deg` exports with its distribution
/// turned too: seen along the normal, the lobe is narrow along the turned αx axis and wide
/// across it, by the model's factor, and the table reproduces the model as the unturned one
/// does.
#[test]
fn a_turned_anisotropic_microfacet_material_keeps_its_axes() {
    let angle_deg = 30.0;
    let spec = MaterialSpec {
        model: ModelSpec::Beckmann {
            alpha_x: 0.1,
            alpha_y: 0.3,
            angle_deg,
        },
        fresnel: FresnelSpec::Metal(Metal::Au),
    };
    let o = RglOptions {
        wavelengths_nm: (0..=12).map(|k| 400.0 + 25.0 * k as f64).collect(),
        check_samples: 1024,
        ..small()
    };
    let out = export::rgl_material(&spec, &o).unwrap();
    let table = RglTable::parse(&out.bytes).unwrap();
    assert!(!table.is_isotropic());
    let r = &out.report;
    assert!(
        r.mean_rel_l1() < 0.03 && r.max_rel_l1() < 0.15,
        "{}",
        r.summary()
    );
    let model = spec.build().unwrap();
    let n = DVec3::Z;
    let phi = angle_deg.to_radians();
    let (along_x, along_y) = (
        export::param::direction(0.35, phi),
        export::param::direction(0.35, phi + core::f64::consts::FRAC_PI_2),
    );
    let rm = model.eval(n, along_y, 550.0) / model.eval(n, along_x, 550.0);
    let rt = table.eval(n, along_y, 550.0) / table.eval(n, along_x, 550.0);
    assert!(
        rm > 5.0 && (rt / rm - 1.0).abs() < 0.02,
        "model ratio {rm}, table {rt}"
    );
    // Along the tangent axes (where an unturned distribution would put them) the ratio is
    // far smaller: the table did turn.
    let (x, y) = (
        export::param::direction(0.35, 0.0),
        export::param::direction(0.35, core::f64::consts::FRAC_PI_2),
    );
    let rt_tangent = table.eval(n, y, 550.0) / table.eval(n, x, 550.0);
    assert!(
        rt_tangent < 0.5 * rt,
        "tangent-axis ratio {rt_tangent} vs {rt}"
    );
}
