//! The glossy control variate of a wave-optical first vertex
//! (`render::glossy_lambda_table`): the models it is built for are
//! isotropic, its table holds the model at its nodes, its per-node λ
//! integrals are the interpolant's (by a quadrature that shares nothing
//! with the builder's), and the renders it changes agree in the mean with
//! sampled wavelengths, sample by sample.

// The paired comparison of the workspace's end-to-end tests.
#[path = "../../../tests/support/paired.rs"]
mod paired;

use glam::DVec3;
use paired::paired;
use render::Scene;
use render::glossy_lambda_table::{
    GEOMETRIC_NODES, LAMBDA_NODES, corners, lambda_node, node_directions, node_geometry,
};
use render::light::{Emission, LightKind};
use render::spectrum::{Cie, LAMBDA_MAX, LAMBDA_MIN};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every model the table is built for, as `[materials.plate]` bodies.
fn models() -> Vec<(&'static str, String)> {
    let kc = "metal = \"cu\"\nsigma_um = 0.138\nlc_um = 2.0\ngamma = 2.0\n";
    vec![
        ("ghs", format!("model = \"ghs\"\n{kc}")),
        ("ghs_ssa", format!("model = \"ghs_ssa\"\n{kc}")),
        (
            "two_scale",
            format!("model = \"two_scale\"\n{kc}beta = 0.05\ncoherent = \"delta\"\n"),
        ),
        (
            "measured_psd",
            format!(
                "model = \"measured_psd\"\nmetal = \"cu\"\npsd_csv = \"{}\"\n",
                root().join("scenes/psd/s138_kc.csv").display()
            ),
        ),
        (
            "rayleigh_rice",
            "model = \"rayleigh_rice\"\nmetal = \"au\"\nsigma_um = 0.02\nlc_um = 2.0\ngamma = 2.5\n"
                .into(),
        ),
    ]
}

/// A plate of `material` under a sphere light of radius `radius` and
/// `spectrum`, with `integrator` lines; `extra` more scene text.
fn plate(material: &str, integrator: &str, radius: f64, spectrum: &str, extra: &str) -> Scene {
    plate_lit(
        material,
        integrator,
        radius,
        spectrum,
        extra,
        "0.0, 0.707107, -0.707107",
    )
}

/// [`plate`] with the light's centre at `center`.
fn plate_lit(
    material: &str,
    integrator: &str,
    radius: f64,
    spectrum: &str,
    extra: &str,
    center: &str,
) -> Scene {
    // The control variate is opt-in; a test asking for another mode says so.
    let integrator = if integrator.contains("spectral_integration") {
        integrator.to_string()
    } else {
        format!("spectral_integration = \"glossy\"\n{integrator}")
    };
    let text = format!(
        "[camera]\nlook_from = [0.0, 0.707107, 0.707107]\nlook_at = [0.0, 0.0, 0.0]\n\
         fov_deg = 32.0\nresolution = [6, 5]\n[film]\nspp = 1\n\
         [integrator]\n{integrator}\n[materials.plate]\n{material}\n\
         [[shapes]]\ntype = \"rectangle\"\nsize = [0.5, 0.5]\nmaterial = \"plate\"\n\
         transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}\n\
         [[lights]]\ntype = \"sphere\"\ncenter = [{center}]\nradius = {radius}\n\
         radiance = 150.0\nspectrum = \"{spectrum}\"\n{extra}"
    );
    render::load_str(&root().join("glossy_cv.toml"), &text).unwrap()
}

/// Asserts that two renders agree in the mean, channel by channel, over
/// `samples` paired camera samples (|z| < 4.5), with the difference's
/// standard error under 1 % of the mean so that the comparison can fail.
fn assert_same_mean(name: &str, [la, lb]: [&str; 2], a: &Scene, b: &Scene, samples: u64) {
    for (c, (ma, mb, d, e)) in paired(a, b, samples).into_iter().enumerate() {
        let z = d / e;
        eprintln!(
            "{name} channel {c}: {la} {ma:.6}, {lb} {mb:.6}, difference {d:+.2e} ± {e:.2e} (z = {z:+.2})"
        );
        assert!(e < 1e-2 * mb.abs(), "{name}: too noisy to compare");
        assert!(z.abs() < 4.5, "{name} channel {c}: z = {z}");
    }
}

fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn direction(u: &mut impl FnMut() -> f64) -> DVec3 {
    let z = 0.02 + 0.98 * u();
    let phi = std::f64::consts::TAU * u();
    let s = (1.0 - z * z).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// The lobe depends on the directions only through (cosθi, cosθo,
/// |wi_xy + wo_xy|): the same under a common rotation about the normal and
/// a mirror image, at random directions and wavelengths. Anisotropic
/// surfaces fail this (checked: `ghs_aniso` differs by up to 50 %).
#[test]
fn the_tabulated_models_are_isotropic() {
    let mut u = xorshift(0x9e37_79b9_7f4a_7c15);
    let mut all = models();
    all.push((
        "ghs_aniso (must differ)",
        "model = \"ghs_aniso\"\nmetal = \"cu\"\nsigma_um = 0.138\nlx_um = 2.0\nly_um = 6.0\ngamma = 2.0\n"
            .into(),
    ));
    for (name, body) in all {
        let s = plate(&body, "", 0.03, "d65", "");
        let bxdf = &s.materials[0].bxdf;
        let mut worst = 0.0f64;
        for _ in 0..300 {
            let (wi, wo) = (direction(&mut u), direction(&mut u));
            let lambda = 360.0 + 470.0 * u();
            let a = std::f64::consts::TAU * u();
            let rot = |v: DVec3| {
                DVec3::new(
                    v.x * a.cos() - v.y * a.sin(),
                    v.x * a.sin() + v.y * a.cos(),
                    v.z,
                )
            };
            let mirror = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
            let f = bxdf.eval(wi, wo, lambda);
            for (i, o) in [(rot(wi), rot(wo)), (mirror(wi), mirror(wo))] {
                let g = bxdf.eval(i, o, lambda);
                worst = worst.max((f - g).abs() / (f.abs().max(g.abs()) + 1e-300));
            }
        }
        eprintln!("{name}: largest relative change {worst:.2e}");
        if name.contains("must differ") {
            assert!(worst > 1e-3, "{name}: {worst}");
        } else {
            assert!(worst < 1e-9, "{name}: {worst}");
        }
    }
}

/// Near the mirror direction, where a narrow lobe peaks, the interpolant
/// f̃ follows f·cosθo: the relative RMS residual over directions within
/// 0.03 rad (the 3 cm light at 1 m) of the 45° mirror direction and λ over
/// 380–780 nm. The peak at ρ = 0 is reachable only at cosθo = cosθi; with
/// the other corners of a cell clamped to the smallest ρ their cosines
/// allow (instead of continued below it) the residual was 0.09–0.25.
#[test]
fn the_interpolant_follows_the_lobe_at_the_mirror_direction() {
    let mut u = xorshift(11);
    for (name, body) in models() {
        let s = plate(&body, "", 0.03, "d65", "");
        let t = s.spectral.as_ref().unwrap().glossy(0).unwrap();
        let bxdf = &s.materials[0].bxdf;
        let (mut se, mut sf) = (0.0, 0.0);
        for _ in 0..4000 {
            let ti = std::f64::consts::FRAC_PI_4 + 0.02 * (u() - 0.5);
            let wi = DVec3::new(ti.sin(), 0.0, ti.cos());
            let (dx, dy) = (0.06 * (u() - 0.5), 0.06 * (u() - 0.5));
            let wo = DVec3::new(-wi.x + dx, dy, wi.z).normalize();
            let lambda = 380.0 + 400.0 * u();
            let f = bxdf.eval(wi, wo, lambda) * wo.z;
            let r = f - t.interpolant(&**bxdf, &corners(wi, wo), lambda);
            se += r * r;
            sf += f * f;
        }
        let rel = (se / sf).sqrt();
        eprintln!("{name}: relative RMS residual {rel:.2e}");
        assert!(rel < 0.02, "{name}: {rel}");
    }
}

/// The table holds the model's f·cosθo at its nodes (to f32 rounding), for
/// every model, at random nodes whose geometry is one the cosines allow.
#[test]
fn the_table_holds_the_model_at_its_nodes() {
    let mut u = xorshift(7);
    for (name, body) in models() {
        let s = plate(&body, "", 0.03, "d65", "");
        let t = s.spectral.as_ref().unwrap().glossy(0).unwrap_or_else(|| {
            panic!("{name}: no glossy table: {}", s.prepared);
        });
        eprintln!("{name}: {}", s.prepared);
        let bxdf = &s.materials[0].bxdf;
        for _ in 0..200 {
            let g = (u() * GEOMETRIC_NODES as f64) as usize;
            let k = (u() * LAMBDA_NODES as f64) as usize;
            let (ci, co, rho) = node_geometry(g);
            let (wi, wo) = node_directions(ci, co, rho);
            let want = bxdf.eval(wi, wo, lambda_node(k)) * wo.z;
            let got = t.node_value(&**bxdf, g, k);
            assert!(
                (got - want).abs() <= 1e-6 * want.abs() + 1e-30,
                "{name}: node {g} λ {k}: {got} vs {want}"
            );
            // The directions have the node's coordinates where allowed.
            let c = corners(wi, wo);
            let w: f64 = c.w.iter().sum();
            assert!((w - 1.0).abs() < 1e-12);
        }
    }
}

/// ∫ Le f̃ cmf dλ from the per-node integrals against a 0.01 nm midpoint
/// rule over the interpolant itself, at random geometries, for several
/// emission spectra (a flat one, D65's 5 nm table, a blackbody and a
/// narrow table with knots off every grid).
#[test]
fn the_exact_part_is_the_interpolants_integral() {
    let narrow = root().join("target/glossy_cv_narrow.csv");
    std::fs::create_dir_all(narrow.parent().unwrap()).unwrap();
    std::fs::write(
        &narrow,
        "wavelength_nm,value\n512.3,0\n530.7,2\n548.25,0.5\n561.9,0\n",
    )
    .unwrap();
    let spectra = [
        "constant".to_string(),
        "d65".into(),
        "blackbody(2700)".into(),
        format!("csv({})", narrow.display()),
    ];
    let (_, ghs) = &models()[0];
    let mut u = xorshift(11);
    let cie = Cie::get();
    for spectrum in &spectra {
        let s = plate(ghs, "", 0.03, spectrum, "");
        let tables = s.spectral.as_ref().unwrap();
        let t = tables.glossy(0).unwrap();
        let bxdf = &*s.materials[0].bxdf;
        let LightKind::Sphere { spectrum: sp, .. } = &s.lights.lights[0] else {
            unreachable!()
        };
        let em = Emission::Spectrum(sp, 1.3, 0);
        for _ in 0..40 {
            let (wi, mut wo) = (direction(&mut u), direction(&mut u));
            if u() < 0.5 {
                // Near the mirror direction, where the lobe peaks.
                wo = DVec3::new(-wi.x, -wi.y, wi.z) + 0.05 * (direction(&mut u) - DVec3::Z);
                wo = DVec3::new(wo.x, wo.y, wo.z.abs().max(0.01)).normalize();
            }
            let c = corners(wi, wo);
            let got = tables.glossy_exact(t, bxdf, &c, &em);
            let h = 0.01;
            let steps = ((LAMBDA_MAX - LAMBDA_MIN) / h).round() as usize;
            let mut want = [0.0; 3];
            for i in 0..steps {
                let l = LAMBDA_MIN + (i as f64 + 0.5) * h;
                let v = em.eval(l) * t.interpolant(bxdf, &c, l) * h;
                let m = cie.xyz(l);
                for k in 0..3 {
                    want[k] += v * m[k];
                }
            }
            let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for k in 0..3 {
                assert!(
                    (got[k] - want[k]).abs() <= 1e-6 * scale + 1e-300,
                    "{spectrum}: {got:?} vs {want:?}"
                );
            }
        }
    }
}

/// The control variate against sampled wavelengths, sample by sample, on
/// the plate under a light wide enough for both strategies to reach it
/// (0.45 rad off the mirror direction of the image's centre, so that the
/// sampled delta lobe's noise does not hide the comparison),
/// with a constant environment and two more bounces (roulette from the
/// first): next-event estimation, BSDF-sampled emission and the path's
/// continuation all pass through the new first vertex.
#[test]
fn the_control_variate_agrees_with_sampled_wavelengths() {
    let integrator = "sampler = \"independent\"\nmax_depth = 3\nrr_depth = 1\n";
    let env = "[[lights]]\ntype = \"environment\"\nradiance = 0.5\nspectrum = \"a\"\n\
               [[shapes]]\ntype = \"sphere\"\ncenter = [0.1, 0.1, 0.0]\nradius = 0.08\nmaterial = \"plate\"\n";
    for (name, body) in models().into_iter().filter(|(n, _)| *n != "measured_psd") {
        let lit = |mode: &str| {
            plate_lit(
                &body,
                &format!("{integrator}spectral_integration = \"{mode}\"\n"),
                0.25,
                "blackbody(3200)",
                env,
                "0.45, 0.55, -0.7",
            )
        };
        let (auto, sampled) = (lit("glossy"), lit("sampled"));
        assert!(
            auto.spectral.as_ref().and_then(|t| t.glossy(0)).is_some(),
            "{name}: {}",
            auto.prepared
        );
        assert_same_mean(name, ["control variate", "sampled"], &auto, &sampled, 4000);
    }
}

/// The cells are built as lookups need them: a 45° plate under a small
/// light builds a few of the 256 (cosθi, cosθo) cells, not the whole grid.
#[test]
fn a_plate_builds_only_the_cells_it_uses() {
    let (_, ghs) = &models()[0];
    let s = plate(ghs, "max_depth = 1\n", 0.03, "constant", "");
    let t = s.spectral.as_ref().unwrap().glossy(0).unwrap();
    let empty = t.bytes();
    let mut film = s.film().unwrap();
    let opts = render::RenderOptions {
        threads: Some(1),
        ..Default::default()
    };
    render::render_range(&s, &mut film, 0..16, &opts).unwrap();
    let per_cell = render::glossy_lambda_table::RHO_NODES
        * (render::glossy_lambda_table::LAMBDA_NODES * 4 + 24);
    let cells = (t.bytes() - empty) / per_cell;
    eprintln!(
        "cells built: {cells} of {}, {} bytes",
        render::glossy_lambda_table::COS_NODES.pow(2),
        t.bytes()
    );
    assert!((1..=64).contains(&cells), "{cells} cells");
}

/// The control variate is opt-in: the default (`auto`) builds no glossy table and keeps
/// the scene's estimates unsigned, so a low-spp image holds no negative pixel.
#[test]
fn the_default_builds_no_glossy_table() {
    let ghs = &models()[0].1;
    let s = plate(ghs, "spectral_integration = \"auto\"\n", 0.03, "d65", "");
    assert!(
        s.spectral.as_ref().is_none_or(|t| t.glossy(0).is_none()) && !s.signed_radiance,
        "{}",
        s.prepared
    );
    let g = plate(ghs, "", 0.03, "d65", "");
    assert!(g.spectral.as_ref().and_then(|t| t.glossy(0)).is_some() && g.signed_radiance);
}

/// The residual roulette (`glossy_residual = p`: a light sample evaluates
/// f − f̃ with probability p and weight 1/p) keeps the mean: paired sample
/// by sample with p = 1 on a plate under a light wide enough for the
/// residual to matter away from the mirror direction. Seen to fail with
/// the weight 1 in place of 1/p.
#[test]
fn the_rouletted_residual_keeps_the_mean() {
    for (name, body) in models() {
        let lit = |p: f64| {
            plate_lit(
                &body,
                &format!("max_depth = 1\nglossy_residual = {p}\n"),
                0.25,
                "blackbody(3200)",
                "",
                "0.45, 0.55, -0.7",
            )
        };
        let (rouletted, full) = (lit(0.25), lit(1.0));
        assert_same_mean(name, ["rouletted", "full"], &rouletted, &full, 2000);
    }
}

/// A residual probability outside (0.001, 1] is an error naming the key
/// and its range, not a panic or a silent 1/0 weight.
#[test]
fn out_of_range_residual_probabilities_are_refused() {
    for bad in ["0", "-0.5", "1.5", "0.0001", "nan", "inf"] {
        let text = format!(
            "[film]\nspp = 1\n[camera]\nlook_from = [0.0, 1.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 30.0\nresolution = [4, 4]\n\
             [integrator]\nglossy_residual = {bad}\n[materials.m]\nmodel = \"ggx\"\n\
             metal = \"cu\"\nalpha = 0.2\n[[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.1\n\
             material = \"m\"\n[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\n\
             intensity = 1.0\n"
        );
        let e = render::load_str(&root().join("bad.toml"), &text)
            .err()
            .unwrap_or_else(|| panic!("{bad} accepted"))
            .to_string();
        assert!(
            e.contains("glossy_residual") && e.contains("0.001"),
            "{bad}: {e}"
        );
    }
}
