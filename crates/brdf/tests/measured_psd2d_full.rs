//! The full GHS of a tabulated 2-D PSD (`brdf::wave::GhsPsd2d`,
//! `brdf::wave::ghs_psd2d_table`, `model = "measured_psd2d"`, physics.md §15.4):
//! S̃ of a table of an anisotropic Gaussian PSD against its closed-form Poisson
//! series (P^{*n} of a Gaussian is a Gaussian of n times the covariance), the ln g
//! interpolation against slices computed at the midpoints, the limit g → 0 (the SSA
//! model), an elliptical table against `measured_psd_aniso` of the same radial law,
//! rotation covariance and reciprocity, chi-square of sampling against the pdf at
//! g ≈ 0.1, 1, 10, the delta weight e^{−g}, finiteness over a sweep.

use std::f64::consts::PI;

use brdf::statistics::TabulatedPsd2d;
use brdf::testing::{Chi2Config, chi2_test, sidak};
use brdf::wave::ghs_psd2d_table::{Psd2dGhsTable, Psd2dResolution, second_order_share};
use brdf::wave::{GhsAnisotropic, GhsOptions, GhsPsd2d, GhsSsaPsd2d};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};

mod psd2d_support;
use psd2d_support::{
    against, crossing_lays, dir, elliptical, random_grid, sound_over_random_directions, table,
};

/// A centred Gaussian density of covariance n·Σ, Σ given by its axes (sa, sb) at φ.
struct Gauss {
    inv: [f64; 3],
    det: f64,
}

impl Gauss {
    fn new(sa: f64, sb: f64, phi: f64) -> Gauss {
        let (s, c) = phi.sin_cos();
        let (a2, b2) = (sa * sa, sb * sb);
        let (xx, yy, xy) = (
            c * c * a2 + s * s * b2,
            s * s * a2 + c * c * b2,
            c * s * (a2 - b2),
        );
        let det = xx * yy - xy * xy;
        Gauss {
            inv: [yy / det, xx / det, -xy / det],
            det,
        }
    }

    fn density(&self, n: f64, x: f64, y: f64) -> f64 {
        let q = (self.inv[0] * x * x + self.inv[1] * y * y + 2.0 * self.inv[2] * x * y) / n;
        (-0.5 * q).exp() / (2.0 * PI * n * self.det.sqrt())
    }

    /// e^{−g} Σ_{n≥1} gⁿ/n! N(ζ; nΣ).
    fn s_tilde(&self, x: f64, y: f64, g: f64) -> f64 {
        let (mut sum, mut w) = (0.0, (-g).exp());
        let top = (g + 12.0 * g.sqrt() + 30.0) as usize;
        for n in 1..=top {
            w *= g / n as f64;
            sum += w * self.density(n as f64, x, y);
        }
        sum
    }
}

fn gauss_table(res: Psd2dResolution) -> (Psd2dGhsTable, Gauss) {
    let sigma = 0.2;
    let gauss = Gauss::new(1.5, 3.0, 30f64.to_radians());
    let t = table(180, 180, 0.1, 0.1, 40.0, 0.0, |x, y| {
        sigma * sigma * gauss.density(1.0, x, y)
    });
    (Psd2dGhsTable::with_resolution(t, 50.0, res).unwrap(), gauss)
}

/// Worst |model − reference| relative to the peak of the reference, over a grid of
/// ζ off the FFT nodes.
fn worst_error(model: impl Fn(f64, f64) -> f64, reference: impl Fn(f64, f64) -> f64) -> f64 {
    let mut peak: f64 = 0.0;
    let mut pts = Vec::new();
    for i in -40..=40 {
        for j in -40..=40 {
            let (x, y) = (i as f64 * 0.237 + 0.05, j as f64 * 0.311 + 0.02);
            let r = reference(x, y);
            peak = peak.max(r);
            pts.push((model(x, y), r));
        }
    }
    pts.iter()
        .map(|(a, b)| (a - b).abs() / peak)
        .fold(0.0, f64::max)
}

/// The independent reference: S̃ of a table of an anisotropic Gaussian (σ 0.2 µm,
/// axes 1.5 and 3 rad/µm at 30°, step 0.1 rad/µm) against its closed-form series.
#[test]
fn a_gaussian_table_follows_the_closed_form_series() {
    for (n_max, bound) in [(256, 6e-3), (512, 2.5e-3)] {
        let res = Psd2dResolution {
            n_max,
            ..Default::default()
        };
        let (t, gauss) = gauss_table(res);
        for g in [0.02, 0.3, 1.0, 3.0, 10.0, 30.0] {
            let e = worst_error(|x, y| t.s_tilde(x, y, g), |x, y| gauss.s_tilde(x, y, g));
            // The orders n ≥ 2 alone, against their own peak.
            let e2 = worst_error(
                |x, y| second_order_share(g) * t.higher_density(x, y, g),
                |x, y| gauss.s_tilde(x, y, g) - (-g).exp() * g * gauss.density(1.0, x, y),
            );
            println!("N ≤ {n_max}, g {g}: worst |ΔS̃|/max S̃ {e:.2e}, orders ≥ 2 {e2:.2e}");
            assert!(e < bound, "g {g}: {e}");
        }
    }
}

/// Between slices, S̃ interpolated in ln g against the slice computed at that g.
#[test]
fn ln_g_interpolation_error() {
    let t =
        Psd2dGhsTable::new(table(40, 30, 0.6, 0.7, 4.0, 0.0, crossing_lays(0.1)), 50.0).unwrap();
    let mut worst: f64 = 0.0;
    for j in 0..t.slice_count() - 1 {
        let g = 0.01 * ((j as f64 + 0.5) / 8.0).exp();
        if g > 50.0 {
            break;
        }
        let direct = t.direct_slice(g).unwrap().unwrap();
        let m2 = second_order_share(g);
        let mut peak: f64 = 0.0;
        let mut err: f64 = 0.0;
        for i in -30..=30 {
            for k in -30..=30 {
                let (x, y) = (i as f64 * 0.83, k as f64 * 0.91);
                let s = t.s_tilde(x, y, g);
                let first = (-g).exp() * g * t.psd().unit_psd(x, y);
                let exact = first + m2 * direct.psd(x, y);
                peak = peak.max(exact);
                err = err.max((s - exact).abs());
            }
        }
        worst = worst.max(err / peak);
    }
    println!("ln g interpolation (8 slices per unit): worst |ΔS̃|/max S̃ {worst:.2e}");
    assert!(worst < 3e-3, "{worst}");
}

/// g → 0: S̃/(1 − e^{−g}) → P₂/σ², so the model is the SSA's.
#[test]
fn the_small_g_limit_is_the_ssa() {
    let f = crossing_lays(0.1);
    let t = Psd2dGhsTable::new(table(40, 30, 0.6, 0.7, 4.0, 0.0, &f), 1.0).unwrap();
    // The departure is the orders n ≥ 2, a share ∝ g: it falls tenfold with g.
    let mut last = f64::INFINITY;
    for g in [1e-2f64, 1e-3, 1e-4] {
        let mut worst: f64 = 0.0;
        for (x, y) in [
            (0.3, 0.1),
            (2.0, -1.0),
            (-5.0, 3.0),
            (0.0, 8.0),
            (12.0, 1.0),
        ] {
            let a = t.s_tilde(x, y, g) / -(-g).exp_m1();
            let b = t.psd().unit_psd(x, y);
            worst = worst.max((a / b - 1.0).abs());
        }
        println!("g {g}: worst relative departure from the SSA {worst:.2e}");
        assert!(worst < 10.0 * g, "g {g}: {worst}");
        assert!(worst <= 0.11 * last, "g {g}: {worst} after {last}");
        last = worst;
    }
    // The models: σ 2 nm, g ≤ 0.006 at 400 nm.
    let fresnel = || Fresnel::conductor(Ior::metal(Metal::Cu));
    let full = GhsPsd2d::new(
        table(40, 30, 0.6, 0.7, 4.0, 20.0, crossing_lays(0.002)),
        fresnel(),
        GhsOptions::default(),
    )
    .unwrap();
    let ssa = GhsSsaPsd2d::new(
        table(40, 30, 0.6, 0.7, 4.0, 20.0, crossing_lays(0.002)),
        fresnel(),
        GhsOptions::default(),
    )
    .unwrap();
    for (ti, pi) in [(0.0, 0.0), (45.0, 100.0)] {
        for (to, po) in [(5.0, 10.0), (30.0, 200.0), (70.0, 45.0)] {
            let (wi, wo) = (dir(ti, pi), dir(to, po));
            let (a, b) = (full.eval(wi, wo, 400.0), ssa.eval(wi, wo, 400.0));
            let g = (2.0 * PI / 0.4 * 0.002 * (wi.z + wo.z)).powi(2);
            assert!((a / b - 1.0).abs() < 10.0 * g, "g {g}: {a} vs {b}");
            assert_eq!(full.specular(wi, 400.0), ssa.specular(wi, 400.0));
        }
    }
}

/// A table of an elliptical PSD against `measured_psd_aniso` (the radial full-GHS
/// table of the same law, stretched).
#[test]
fn an_elliptical_table_is_measured_psd_aniso() {
    let e = elliptical(4e-3);
    let fresnel = || Fresnel::conductor(Ior::metal(Metal::Cu));
    let stretched = GhsAnisotropic::full(e.clone(), fresnel(), GhsOptions::default()).unwrap();
    let t = table(300, 300, 0.1, 0.1, 5.0, 0.0, |x, y| e.psd(x, y));
    let m = GhsPsd2d::new(t, fresnel(), GhsOptions::default()).unwrap();
    let sigma = m.table().psd().sigma_um();
    let (worst, albedos) = against(&m, &stretched);
    for (ti, wi, qa, qb) in albedos {
        let g = (2.0 * 2.0 * PI / 0.55 * sigma * wi.z).powi(2);
        println!("θi {ti} (g {g:.2}): albedo {qa:.6} vs {qb:.6}");
        assert!((qa / qb - 1.0).abs() < 0.01, "{qa} vs {qb}");
    }
    println!("σ {sigma:.4} µm; worst relative difference at |ζ| ≥ 1.5: {worst:.2e}");
    assert!(worst < 0.06, "{worst}");
}

fn lays_model(sigma_um: f64, angle_deg: f64, fresnel: Fresnel) -> GhsPsd2d {
    GhsPsd2d::new(
        table(40, 30, 0.6, 0.7, 4.0, angle_deg, crossing_lays(sigma_um)),
        fresnel,
        GhsOptions::default(),
    )
    .unwrap()
}

#[test]
fn rotation_covariance_reciprocity_and_the_delta() {
    let rot = |v: DVec3, d: f64| {
        let (s, c) = d.to_radians().sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    let m0 = lays_model(0.08, 10.0, Fresnel::One);
    let m1 = lays_model(0.08, 55.0, Fresnel::One);
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
        let wi = dir(ti, pi);
        let g = (2.0 * 2.0 * PI / 0.5 * m0.table().psd().sigma_um() * wi.z).powi(2);
        let s = m0.specular(wi, 500.0);
        assert!(close(s.weight, (-g).exp(), 1e-12), "{} vs e^-{g}", s.weight);
    }
}

#[test]
fn sampling_matches_the_pdf() {
    // σ for g_s = (2kσ)² ≈ 0.1, 1, 10 at 550 nm and normal incidence.
    let k = 2.0 * PI / 0.55;
    let sets = [(0.0, 0.0), (40.0, 30.0)];
    let gs: [f64; 3] = [0.1, 1.0, 10.0];
    let alpha = sidak(0.01, sets.len() * gs.len());
    let mut failures = Vec::new();
    for (a, &g) in gs.iter().enumerate() {
        let sigma = g.sqrt() / (2.0 * k);
        let m = lays_model(sigma, 15.0, Fresnel::One);
        for (i, &(ti, pi)) in sets.iter().enumerate() {
            let cfg = Chi2Config {
                samples: 120_000,
                pilot_samples: 30_000,
                seed: 700 + (10 * a + i) as u64,
                ..Default::default()
            };
            let rep = chi2_test(&m, dir(ti, pi), 550.0, &cfg);
            println!(
                "g_s {g} θi {ti}: χ² {:.1} dof {} p {:.3}",
                rep.statistic, rep.dof, rep.p_value
            );
            if !rep.passes(alpha) {
                failures.push(format!("g {g} θi {ti}: {}", rep.check(alpha).unwrap_err()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Random directions and wavelengths: finite, non-negative, pdf > 0 where f > 0.
#[test]
fn finite_over_a_sweep() {
    let mut rng = brdf::testing::Pcg32::new(11, 3);
    for sigma in [0.005, 0.05, 0.3] {
        let m = lays_model(sigma, 33.0, Fresnel::conductor(Ior::metal(Metal::Cu)));
        for _ in 0..3000 {
            let wi = dir(89.9 * rng.next_f64(), 360.0 * rng.next_f64());
            let wo = dir(89.9 * rng.next_f64(), 360.0 * rng.next_f64());
            let lam = 360.0 + 470.0 * rng.next_f64();
            let (f, pdf) = m.eval_pdf(wi, wo, lam);
            assert!(f.is_finite() && f >= 0.0 && pdf.is_finite() && pdf >= 0.0);
            assert!(f <= 0.0 || pdf > 0.0, "{wi} {wo} {lam}: f {f} pdf {pdf}");
            if let Some(s) = m.sample(wi, lam, [rng.next_f64(), rng.next_f64(), rng.next_f64()]) {
                assert!(s.weight.is_finite() && s.weight >= 0.0);
            }
        }
    }
}

/// `model = "measured_psd2d"` through the material-file route scenes, `brdf eval`,
/// `compare`, `preview` and `judge` use: a file with a `[psd.map]` offers it and builds
/// the model of the same table; energy other than `raw` is refused naming `energy`;
/// without a table the error names `psd_map`.
#[test]
fn a_material_file_with_a_map_offers_and_builds_the_full_model() {
    use brdf::spec::{MaterialDesc, MaterialFile, ModelKind, NoFiles};
    let (mx, my, dx, dy) = (6usize, 5usize, 0.8, 0.9);
    let f = crossing_lays(0.05);
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
    let file: MaterialFile = serde_json::from_value(serde_json::json!({
        "material": {"model": "ghs_ssa", "metal": "cu", "sigma_um": 0.05, "lc_um": 1.0,
                     "gamma": 3.0},
        "psd": {"zeta_rad_per_um": [1.0, 2.0], "p_um4": [1.0, 0.01], "map": map},
    }))
    .unwrap();
    assert_eq!(
        ModelKind::from_name("measured_psd2d"),
        Some(ModelKind::MeasuredPsd2d)
    );
    assert!(
        file.offered()
            .iter()
            .any(|o| o.model == Some(ModelKind::MeasuredPsd2d))
    );
    let desc: MaterialDesc =
        serde_json::from_value(serde_json::json!({"model": "measured_psd2d"})).unwrap();
    let m = file.resolve(&desc, &mut NoFiles).unwrap().build().unwrap();
    let direct = GhsPsd2d::new(
        TabulatedPsd2d::new(mx, my, dx, dy, &p, 4.0, 0.0).unwrap(),
        Fresnel::conductor(Ior::metal(Metal::Cu)),
        GhsOptions::default(),
    )
    .unwrap();
    for (wi, wo) in [
        (dir(0.0, 0.0), dir(20.0, 40.0)),
        (dir(50.0, 10.0), dir(30.0, 250.0)),
    ] {
        let a = m.eval(wi, wo, 550.0);
        assert!(a > 0.0);
        assert_eq!(a, direct.eval(wi, wo, 550.0));
    }
    let krywonos: MaterialDesc = serde_json::from_value(
        serde_json::json!({"model": "measured_psd2d", "energy": "krywonos"}),
    )
    .unwrap();
    let e = file.resolve(&krywonos, &mut NoFiles).unwrap_err();
    assert_eq!(e.field, "energy", "{e}");
    let bare: MaterialDesc =
        serde_json::from_value(serde_json::json!({"model": "measured_psd2d", "metal": "cu"}))
            .unwrap();
    let e = bare.into_spec(&mut NoFiles).unwrap_err();
    assert_eq!(e.field, "psd_map", "{e}");
    assert!(e.message.contains("measured_psd2d"), "{e}");
}

/// The ends of the accepted steps: one node per half axis 100 rad/µm apart (coarser than
/// the kept square) and 0.01 rad/µm apart (finer than the FFT grid).
#[test]
fn extreme_steps_build_sound_models() {
    for (d, sigma) in [(100.0, 1.0), (0.01, 1e-3), (100.0, 1e-4), (0.01, 30.0)] {
        let p = vec![sigma * sigma / (4.0 * d * d); 6];
        let t = TabulatedPsd2d::new(1, 1, d, d, &p, 3.0, 0.2).unwrap();
        let m = GhsPsd2d::new(t, Fresnel::One, GhsOptions::default()).unwrap();
        let mut rng = brdf::testing::Pcg32::new(3, 9);
        for _ in 0..200 {
            let [a, b, c] = rng.uniform3();
            let (wi, wo) = (dir(89.0 * a, 360.0 * b), dir(89.0 * c, 360.0 * a * b));
            let (f, pdf) = m.eval_pdf(wi, wo, 500.0);
            assert!(f.is_finite() && f >= 0.0 && pdf.is_finite() && pdf >= 0.0);
            assert!(f <= 0.0 || pdf > 0.0, "step {d}: f {f} pdf {pdf}");
            if let Some(s) = m.sample(wi, 500.0, rng.uniform3()) {
                assert!(s.weight.is_finite() && s.weight >= 0.0);
            }
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 12, ..Default::default() })]
    /// Any grid the table accepts — half sizes 1–12, steps 0.01–100 rad/µm, tail exponents
    /// just above 2 to 40, any angle, values over 14 decades with zeros among them (σ up to
    /// ~100 µm, g to 1e7) —: over random directions and wavelengths f and pdf finite and ≥ 0,
    /// pdf > 0 wherever f > 0, reciprocal; a sample carries a finite weight and lands where
    /// the pdf is positive.
    #[test]
    fn every_accepted_grid_gives_a_sound_full_model(
        mx in 1usize..=12,
        my in 1usize..=12,
        ldx in -2.0f64..2.0,
        ldy in -2.0f64..2.0,
        alpha in 2.001f64..40.0,
        angle_deg in -400.0f64..400.0,
        lscale in -12.0f64..2.0,
        seed in 0u64..1_000_000,
    ) {
        let mut rng = brdf::testing::Pcg32::new(seed, 5);
        let t = random_grid(&mut rng, (mx, my), (ldx, ldy), alpha, angle_deg, lscale);
        let m = GhsPsd2d::new(t, Fresnel::conductor(Ior::metal(Metal::Au)), GhsOptions::default())
            .unwrap();
        let sound = sound_over_random_directions(&m, &mut rng, 48);
        proptest::prop_assert!(sound.is_ok(), "{}", sound.unwrap_err());
    }
}
