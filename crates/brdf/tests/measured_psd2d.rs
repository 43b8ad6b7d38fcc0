//! The SSA of a tabulated 2-D PSD (`brdf::statistics::TabulatedPsd2d`,
//! `brdf::wave::GhsSsaPsd2d`, `model = "measured_psd2d_ssa"`, physics.md §15.4):
//! σ² of the table against the closed form of the PSD it samples, its sampler
//! against its density, an elliptical table against `measured_psd_ssa_aniso` of the
//! same radial law, rotation covariance, reciprocity, chi-square of the model's
//! sampling against its pdf on crossing lays, a streak and an ellipse, sampled =
//! cubature albedo, finiteness over a sweep.

use std::f64::consts::PI;

use brdf::statistics::{AnisotropicKc, TabulatedPsd2d};
use brdf::testing::{Chi2Config, Pcg32, albedo_quadrature, albedo_sampled, chi2_test, sidak};
use brdf::wave::{GhsAnisotropic, GhsOptions, GhsSsaPsd2d};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};

mod psd2d_support;
use psd2d_support::{
    against, crossing_lays, dir, elliptical, random_grid, sound_over_random_directions, table,
};

/// An isotropic KC with a streak: a narrow ridge along the ζ direction at 25° (the
/// power of straight edges across the plane).
fn streak(sigma_um: f64) -> impl Fn(f64, f64) -> f64 {
    let iso = AnisotropicKc::new(sigma_um, 1.0, 1.0, 0.0, 3.0).unwrap();
    let (s, c) = 25f64.to_radians().sin_cos();
    move |x, y| {
        let across = -s * x + c * y;
        let along = c * x + s * y;
        let ridge = sigma_um * sigma_um * 0.05 * (-(across * across) / 0.5).exp()
            / (1.0 + along * along).powi(2);
        iso.psd(x, y) + ridge
    }
}

fn ellipse(sigma_um: f64) -> impl Fn(f64, f64) -> f64 {
    let a = AnisotropicKc::new(sigma_um, 0.5, 4.0, 35f64.to_radians(), 2.5).unwrap();
    move |x, y| a.psd(x, y)
}

#[test]
fn sigma_and_the_tail_follow_the_closed_form() {
    // A KC of σ 0.1, tail ζ^−4: the table over |ζ| ≤ 20 with the matching tail exponent
    // holds σ² to the bilinear rule's accuracy.
    let kc = AnisotropicKc::new(0.1, 0.5, 2.0, 0.4, 3.0).unwrap();
    let t = table(100, 100, 0.2, 0.2, 4.0, 0.0, |x, y| kc.psd(x, y));
    let s2 = t.sigma_um().powi(2);
    println!(
        "σ² {s2:.6e} vs 1e-2, tail fraction {:.2e}",
        t.tail_fraction()
    );
    assert!((s2 / 1e-2 - 1.0).abs() < 0.01, "σ² {s2}");
    assert!(t.tail_fraction() > 0.0 && t.tail_fraction() < 0.01);
    // On the nodes and beyond the grid along a ray the table is the PSD.
    for (x, y) in [(1.0, 0.4), (-3.0, 2.2), (0.0, 5.0)] {
        let (p, q) = (t.psd(x, y), kc.psd(x, y));
        assert!((p / q - 1.0).abs() < 1e-9, "{x},{y}: {p} vs {q}");
    }
    // Beyond: the ray continuation of a KC (ζ^−4 asymptotically) is within 1 %.
    for (x, y) in [(40.0, 3.0), (-25.0, 70.0), (100.0, -100.0)] {
        let (p, q) = (t.psd(x, y), kc.psd(x, y));
        assert!((p / q - 1.0).abs() < 0.01, "{x},{y}: {p} vs {q}");
    }
}

/// The sampler's histogram on a ζ grid against ∫ P₂/σ² over each bin (the bilinear
/// interpolant integrated by a 4 × 4 midpoint rule inside each bin), with the mass
/// beyond the window in one bin: a chi-square.
#[test]
fn the_sampler_draws_the_table() {
    let t = table(12, 8, 0.5, 0.75, 3.5, 20.0, crossing_lays(0.1));
    let (n, w) = (16usize, 16.0);
    let bin = 2.0 * w / n as f64;
    let idx = |x: f64| ((x + w) / bin).floor();
    let mut counts = vec![0.0; n * n + 1];
    let mut rng = Pcg32::new(5, 1);
    let draws = 400_000;
    for _ in 0..draws {
        let (x, y) = t.sample_zeta(rng.next_f64(), rng.next_f64());
        let (i, j) = (idx(x), idx(y));
        if (0.0..n as f64).contains(&i) && (0.0..n as f64).contains(&j) {
            counts[j as usize * n + i as usize] += 1.0;
        } else {
            counts[n * n] += 1.0;
        }
    }
    let mut expect = vec![0.0; n * n + 1];
    let m = 24;
    let h = bin / m as f64;
    for j in 0..n {
        for i in 0..n {
            let mut s = 0.0;
            for b in 0..m {
                for a in 0..m {
                    let x = -w + (i as f64) * bin + (a as f64 + 0.5) * h;
                    let y = -w + (j as f64) * bin + (b as f64 + 0.5) * h;
                    s += t.unit_psd(x, y);
                }
            }
            expect[j * n + i] = s * h * h * draws as f64;
        }
    }
    expect[n * n] = draws as f64 - expect[..n * n].iter().sum::<f64>();
    let (mut chi2, mut dof) = (0.0, 0usize);
    for (c, e) in counts.iter().zip(&expect) {
        if *e > 20.0 {
            chi2 += (c - e) * (c - e) / e;
            dof += 1;
        } else {
            assert!(*c < 60.0 + 5.0 * e, "count {c} where {e} expected");
        }
    }
    let p = brdf::testing::chi2_survival(chi2, dof - 1);
    println!("χ² {chi2:.1} dof {} p {p:.3}", dof - 1);
    assert!(p > 1e-3, "χ² {chi2} over {dof} bins: p {p}");
}

/// A table of an elliptical PSD is `measured_psd_ssa_aniso` of its radial law to the
/// bilinear interpolation's accuracy (grid step 0.1 rad/µm).
#[test]
fn an_elliptical_table_is_the_stretched_radial_model() {
    let e = elliptical(1e-4);
    let fresnel = || Fresnel::conductor(Ior::metal(Metal::Cu));
    let stretched = GhsAnisotropic::ssa(e.clone(), fresnel(), GhsOptions::default()).unwrap();
    let t = table(300, 300, 0.1, 0.1, 5.0, 0.0, |x, y| e.psd(x, y));
    let s_ratio = t.sigma_um() / e.radial_psd().sigma_um();
    println!("σ table/radial {s_ratio:.5}");
    assert!((s_ratio - 1.0).abs() < 0.005);
    let m = GhsSsaPsd2d::new(t, fresnel(), GhsOptions::default()).unwrap();
    let (worst, albedos) = against(&m, &stretched);
    for (ti, _, qa, qb) in albedos {
        println!("θi {ti}: albedo {qa:.6} vs {qb:.6}");
        assert!((qa / qb - 1.0).abs() < 0.01, "{qa} vs {qb}");
    }
    println!("worst relative difference at |ζ| ≥ 1.5: {worst:.2e}");
    assert!(worst < 0.02, "{worst}");
}

fn models(sigma_um: f64, fresnel: impl Fn() -> Fresnel) -> Vec<(&'static str, GhsSsaPsd2d)> {
    let opts = GhsOptions::default();
    vec![
        (
            "lays",
            GhsSsaPsd2d::new(
                table(40, 30, 0.6, 0.7, 4.0, 0.0, crossing_lays(sigma_um)),
                fresnel(),
                opts,
            )
            .unwrap(),
        ),
        (
            "streak",
            GhsSsaPsd2d::new(
                table(32, 32, 0.5, 0.5, 4.0, 10.0, streak(sigma_um)),
                fresnel(),
                opts,
            )
            .unwrap(),
        ),
        (
            "ellipse",
            GhsSsaPsd2d::new(
                table(25, 40, 0.8, 0.5, 3.5, -30.0, ellipse(sigma_um)),
                fresnel(),
                opts,
            )
            .unwrap(),
        ),
    ]
}

#[test]
fn rotation_covariance_and_reciprocity() {
    let rot = |v: DVec3, d: f64| {
        let (s, c) = d.to_radians().sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    let f = crossing_lays(0.05);
    let m0 = GhsSsaPsd2d::new(
        table(40, 30, 0.6, 0.7, 4.0, 10.0, &f),
        Fresnel::One,
        GhsOptions::default(),
    )
    .unwrap();
    let m1 = GhsSsaPsd2d::new(
        table(40, 30, 0.6, 0.7, 4.0, 55.0, &f),
        Fresnel::One,
        GhsOptions::default(),
    )
    .unwrap();
    let close = |a: f64, b: f64, rel: f64| (a - b).abs() <= rel * a.abs().max(b.abs());
    for (ti, pi) in [(0.0, 0.0), (30.0, 20.0), (60.0, 200.0), (85.0, 110.0)] {
        for (to, po) in [(10.0, 0.0), (40.0, 75.0), (70.0, 300.0), (ti, pi + 181.0)] {
            let (wi, wo) = (dir(ti, pi), dir(to, po));
            let a = m0.eval(wi, wo, 500.0);
            let b = m1.eval(rot(wi, 45.0), rot(wo, 45.0), 500.0);
            assert!(close(a, b, 1e-9), "{a} vs {b}");
            let c = m0.eval(wo, wi, 500.0);
            assert!(close(a, c, 1e-12), "{a} vs {c}");
            assert!(a > 0.0);
        }
    }
}

#[test]
fn sampling_matches_the_pdf() {
    let sets = [(0.0, 0.0, 550.0), (40.0, 30.0, 450.0), (75.0, 200.0, 650.0)];
    let alpha = sidak(0.01, 3 * sets.len());
    let mut failures = Vec::new();
    for (k, (name, m)) in models(0.03, || Fresnel::One).into_iter().enumerate() {
        for (i, &(ti, pi, lam)) in sets.iter().enumerate() {
            let cfg = Chi2Config {
                samples: 120_000,
                pilot_samples: 30_000,
                seed: 900 + (10 * k + i) as u64,
                ..Default::default()
            };
            let rep = chi2_test(&m, dir(ti, pi), lam, &cfg);
            println!(
                "{name} θi {ti}: χ² {:.1} dof {} p {:.3}",
                rep.statistic, rep.dof, rep.p_value
            );
            if !rep.passes(alpha) {
                failures.push(format!("{name} θi {ti}: {}", rep.check(alpha).unwrap_err()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn sampled_albedo_equals_the_cubature() {
    for (name, m) in models(0.05, || Fresnel::conductor(Ior::metal(Metal::Cu))) {
        let wi = dir(35.0, 60.0);
        let q = albedo_quadrature(&m, wi, 500.0, 1e-6);
        let s = albedo_sampled(&m, wi, 500.0, 200_000, 3);
        println!(
            "{name}: sampled {:.5} ± {:.5}, cubature {:.5}",
            s.mean, s.std_error, q.value
        );
        assert!(
            (s.mean - q.value).abs() < 5.0 * s.std_error + 1e-5,
            "{name}"
        );
    }
}

/// Random directions and wavelengths: finite, non-negative, pdf > 0 wherever f > 0,
/// and f ≤ k² (1 − e^{−g}) max P₂/σ² (R ≤ 1).
#[test]
fn finite_and_bounded_over_a_sweep() {
    let mut rng = Pcg32::new(77, 3);
    for (name, m) in models(0.2, || Fresnel::One) {
        let pmax = (0..200_000)
            .map(|_| {
                let (x, y) = (rng.next_f64() * 60.0 - 30.0, rng.next_f64() * 60.0 - 30.0);
                m.table().unit_psd(x, y)
            })
            .fold(m.table().unit_psd(0.0, 0.0), f64::max);
        for _ in 0..20_000 {
            let [a, b, c] = rng.uniform3();
            let wi = dir(89.9 * a, 360.0 * b);
            let [d, e, _] = rng.uniform3();
            let wo = dir(89.9 * d, 360.0 * e);
            let lam = 360.0 + 470.0 * c;
            let (f, pdf) = m.eval_pdf(wi, wo, lam);
            assert!(
                f.is_finite() && f >= 0.0 && pdf.is_finite() && pdf >= 0.0,
                "{name}"
            );
            assert!(f == 0.0 || pdf > 0.0, "{name}");
            let k = 2.0 * PI / (lam * 1e-3);
            assert!(f <= 1.0001 * k * k * pmax, "{name}: {f}");
            let s = m.sample(wi, lam, rng.uniform3());
            if let Some(s) = s {
                assert!(
                    s.weight.is_finite() && s.weight >= 0.0 && s.wo.z >= 0.0,
                    "{name}"
                );
            }
        }
    }
}

/// `model = "measured_psd2d_ssa"` through the material-file route scenes, `brdf eval`,
/// `compare` and `judge` use: the file's `[psd.map]` is found by default, offered, built
/// into the model of the same table; without it, or with a broken one, the error names
/// `psd_map`; energy other than `raw` is refused naming `energy`.
#[test]
fn a_material_file_with_a_map_offers_and_builds_the_model() {
    use brdf::spec::{MaterialDesc, MaterialFile, ModelKind, NoFiles};
    let (mx, my, dx, dy) = (6usize, 5usize, 0.8, 0.9);
    let f = crossing_lays(0.02);
    let mut p = Vec::new();
    for j in 0..=my {
        for i in 0..=2 * mx {
            p.push(f((i as f64 - mx as f64) * dx, j as f64 * dy));
        }
    }
    let map = serde_json::json!({
        "source": "test", "usable": true, "tail_fraction": 0.1, "tail_exponent": 4.0,
        "half_nx": mx, "half_ny": my, "dzx_rad_per_um": dx, "dzy_rad_per_um": dy, "p_um4": p,
    });
    let file = |map: Option<serde_json::Value>| -> MaterialFile {
        let mut psd = serde_json::json!({"zeta_rad_per_um": [1.0, 2.0], "p_um4": [1.0, 0.01]});
        if let Some(m) = map {
            psd["map"] = m;
        }
        serde_json::from_value(serde_json::json!({
            "material": {"model": "ghs_ssa", "metal": "cu", "sigma_um": 0.02, "lc_um": 1.0,
                         "gamma": 3.0, "angle_deg": 33.0},
            "psd": psd,
        }))
        .unwrap()
    };
    assert_eq!(
        ModelKind::from_name("measured_psd2d_ssa"),
        Some(ModelKind::MeasuredPsd2dSsa)
    );
    let with = file(Some(map.clone()));
    assert!(
        with.offered()
            .iter()
            .any(|o| o.model == Some(ModelKind::MeasuredPsd2dSsa))
    );
    let desc: MaterialDesc =
        serde_json::from_value(serde_json::json!({"model": "measured_psd2d_ssa"})).unwrap();
    let spec = with.resolve(&desc, &mut NoFiles).unwrap();
    let m = spec.build().unwrap();
    let direct = GhsSsaPsd2d::new(
        TabulatedPsd2d::new(mx, my, dx, dy, &p, 4.0, 0.0).unwrap(),
        Fresnel::conductor(Ior::metal(Metal::Cu)),
        GhsOptions::default(),
    )
    .unwrap();
    for (wi, wo) in [
        (dir(0.0, 0.0), dir(20.0, 40.0)),
        (dir(50.0, 10.0), dir(30.0, 250.0)),
    ] {
        assert_eq!(m.eval(wi, wo, 550.0), direct.eval(wi, wo, 550.0));
    }
    // A scene's angle_deg turns the grid (the file's [material].angle_deg is the ellipse's).
    let turned: MaterialDesc = serde_json::from_value(
        serde_json::json!({"model": "measured_psd2d_ssa", "angle_deg": 30.0}),
    )
    .unwrap();
    let t = with
        .resolve(&turned, &mut NoFiles)
        .unwrap()
        .build()
        .unwrap();
    let rot = |v: DVec3| {
        let (s, c) = 30f64.to_radians().sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    let (wi, wo) = (dir(40.0, 10.0), dir(25.0, 120.0));
    let (a, b) = (m.eval(wi, wo, 550.0), t.eval(rot(wi), rot(wo), 550.0));
    assert!((a - b).abs() <= 1e-9 * a, "{a} vs {b}");

    let without = file(None);
    assert!(
        !without
            .offered()
            .iter()
            .any(|o| o.model == Some(ModelKind::MeasuredPsd2dSsa))
    );
    let e = without.resolve(&desc, &mut NoFiles).unwrap_err();
    assert_eq!(e.field, "psd_map", "{e}");
    let mut broken = map.clone();
    broken["p_um4"] = serde_json::json!([1.0, 2.0]);
    let e = file(Some(broken)).resolve(&desc, &mut NoFiles).unwrap_err();
    assert_eq!(e.field, "psd_map", "{e}");
    assert!(e.message.contains("half_nx"), "{e}");
    let krywonos: MaterialDesc = serde_json::from_value(
        serde_json::json!({"model": "measured_psd2d_ssa", "energy": "krywonos"}),
    )
    .unwrap();
    let e = with.resolve(&krywonos, &mut NoFiles).unwrap_err();
    assert_eq!(e.field, "energy", "{e}");
    // Without a material file there is no table to read.
    let bare: MaterialDesc =
        serde_json::from_value(serde_json::json!({"model": "measured_psd2d_ssa", "metal": "cu"}))
            .unwrap();
    let e = bare.into_spec(&mut NoFiles).unwrap_err();
    assert_eq!(e.field, "psd_map", "{e}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 96, ..Default::default() })]
    /// Any grid the constructor accepts — half sizes 1–12, steps 0.01–100 rad/µm, tail
    /// exponents just above 2 to 40, any angle, values over 14 decades with zeros among
    /// them —: σ² finite and positive; over random directions and wavelengths f and pdf
    /// finite and ≥ 0, pdf > 0 wherever f > 0, reciprocal; a sample carries a finite weight
    /// and lands where the pdf is positive.
    #[test]
    fn every_accepted_grid_gives_a_sound_model(
        mx in 1usize..=12,
        my in 1usize..=12,
        ldx in -2.0f64..2.0,
        ldy in -2.0f64..2.0,
        alpha in 2.001f64..40.0,
        angle_deg in -400.0f64..400.0,
        lscale in -12.0f64..2.0,
        seed in 0u64..1_000_000,
    ) {
        let mut rng = Pcg32::new(seed, 5);
        let t = random_grid(&mut rng, (mx, my), (ldx, ldy), alpha, angle_deg, lscale);
        let s = t.sigma_um();
        proptest::prop_assert!(s.is_finite() && s > 0.0, "σ {s} µm");
        let m = GhsSsaPsd2d::new(t, Fresnel::conductor(Ior::metal(Metal::Au)), GhsOptions::default())
            .unwrap();
        let sound = sound_over_random_directions(&m, &mut rng, 64);
        proptest::prop_assert!(sound.is_ok(), "{}", sound.unwrap_err());
    }
}
