//! White-furnace and environment-lighting checks of the path tracer.

#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;
use render::integrator::sample_pixel;
use render::{Film, RenderOptions};
use scene_fixtures::plate_at_60deg;
use std::path::PathBuf;

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join(name)
}

/// A mirror sphere over a mirror plate, both with Fresnel = 1, inside a
/// constant environment of unit luminance: every path returns the
/// environment's radiance, so every pixel's Y is 1 up to wavelength noise.
fn furnace_scene(mode: &str) -> String {
    format!(
        r#"
[camera]
look_from = [0.0, 1.0, 3.0]
look_at = [0.0, 0.3, 0.0]
fov_deg = 50.0
resolution = [24, 16]

[film]
spp = 64
seed = 3

[integrator]
max_depth = 64
wavelengths = "{mode}"

[materials.mirror]
model = "smooth"
fresnel = "one"

[[shapes]]
type = "sphere"
center = [0.0, 0.5, 0.0]
radius = 0.5
material = "mirror"

[[shapes]]
type = "rectangle"
size = [3.0, 3.0]
material = "mirror"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

[[lights]]
type = "environment"
radiance = 1.0
spectrum = "constant"
"#
    )
}

fn check_furnace(mode: &str, tol: f64, pixel_tol: f64) {
    let scene = render::load_str(&scene_path("furnace.toml"), &furnace_scene(mode)).unwrap();
    let mut film = Film::new(24, 16, scene.fingerprint, 3, 0.0).unwrap();
    render::render_range(
        &scene,
        &mut film,
        0..64,
        &RenderOptions {
            threads: Some(2),
            ..Default::default()
        },
    )
    .unwrap();
    let n = film.sums().len();
    let ys: Vec<f64> = (0..n).map(|i| film.xyz(i)[1]).collect();
    let mean = ys.iter().sum::<f64>() / n as f64;
    let worst = ys.iter().map(|y| (y - 1.0).abs()).fold(0.0, f64::max);
    eprintln!("{mode}: mean Y = {mean:.5}, worst pixel |Y − 1| = {worst:.4}");
    // 24·16·64 = 24 576 samples: the mean is within ~0.3 % of 1 at 3σ.
    assert!((mean - 1.0).abs() < tol, "{mode}: mean Y = {mean}");
    // Per pixel (64 samples) the wavelength noise allows ~4σ ≈ 0.4 (single), 0.15 (hero).
    assert!(worst < pixel_tol, "{mode}: worst pixel {worst}");
    // XYZ of an equal-energy spectrum is (1, 1, 1) with this normalisation.
    let x_mean = (0..n).map(|i| film.xyz(i)[0]).sum::<f64>() / n as f64;
    let z_mean = (0..n).map(|i| film.xyz(i)[2]).sum::<f64>() / n as f64;
    assert!(
        (x_mean - 1.0).abs() < 2.0 * tol && (z_mean - 1.0).abs() < 4.0 * tol,
        "X {x_mean} Z {z_mean}"
    );
}

#[test]
fn furnace_single_wavelength() {
    check_furnace("single", 0.006, 0.45);
}

#[test]
fn furnace_hero_wavelengths() {
    check_furnace("hero", 0.004, 0.15);
}

/// Directional albedo of GGX (α = 0.3, F = 1) by brute-force quadrature
/// over the hemisphere, for viewing direction at `theta_o`.
fn ggx_albedo(theta_o: f64) -> f64 {
    use brdf::{Bxdf, Distribution, Fresnel, MicrofacetConductor};
    let m = MicrofacetConductor::new(Distribution::ggx(0.3, 0.3).unwrap(), Fresnel::One).unwrap();
    let wo = brdf::frame::spherical(theta_o, 0.0);
    let (nt, np) = (2000, 400);
    let mut sum = 0.0;
    for i in 0..nt {
        // cosθ-uniform grid: dω cosθ = d(cos²θ/2) dφ
        let c2 = (i as f64 + 0.5) / nt as f64;
        let th = c2.sqrt().acos();
        for j in 0..np {
            let ph = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
            sum += m.eval(brdf::frame::spherical(th, ph), wo, 550.0);
        }
    }
    sum * std::f64::consts::PI / (nt * np) as f64
}

/// A rough plate under a unit constant environment, seen at 60°: each pixel
/// shows the plate's directional albedo, against an independent quadrature.
/// Both ways of lighting it: BSDF sampling alone (what a conductor-only
/// scene does) and environment NEE combined with it by MIS (what a scene
/// with any other material does).
#[test]
fn rough_plate_in_environment_shows_its_albedo() {
    let text = plate_at_60deg(
        0.3,
        4,
        "[[lights]]\ntype = \"environment\"\nradiance = 1.0\nspectrum = \"constant\"",
    );
    let mut scene = render::load_str(&scene_path("env_plate.toml"), &text).unwrap();
    assert!(scene.lights.bsdf_only_environment);
    let want = ggx_albedo(60f64.to_radians());
    let cie_y = render::spectrum::Cie::get().y_integral();
    let n = 40_000u64;
    let mut errors = Vec::new();
    for bsdf_only in [true, false] {
        scene.lights.bsdf_only_environment = bsdf_only;
        let ys: Vec<f64> = (0..n)
            .map(|s| sample_pixel(&scene, 1, 2, s)[1] / cie_y)
            .collect();
        let y = ys.iter().sum::<f64>() / n as f64;
        let var = ys.iter().map(|v| (v - y) * (v - y)).sum::<f64>() / (n - 1) as f64;
        eprintln!(
            "albedo, BSDF only {bsdf_only}: rendered {y:.5} (sample σ {:.4}), quadrature {want:.5}",
            var.sqrt()
        );
        assert!(
            (y / want - 1.0).abs() < 0.01,
            "BSDF only {bsdf_only}: rendered {y} vs quadrature {want}"
        );
        errors.push(var.sqrt());
    }
    // The point of leaving it to BSDF sampling: less noise per sample.
    assert!(errors[0] < errors[1], "σ {errors:?}");
}

/// Y of pixel (`x`, `y`) over `n` samples: (mean, sample σ), in units of
/// the luminance of a unit constant spectrum.
fn pixel_y(scene: &render::Scene, x: u32, y: u32, n: u64) -> (f64, f64) {
    let cie_y = render::spectrum::Cie::get().y_integral();
    let ys: Vec<f64> = (0..n)
        .map(|s| sample_pixel(scene, x, y, s)[1] / cie_y)
        .collect();
    let mean = ys.iter().sum::<f64>() / n as f64;
    let var = ys.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}

/// Lambertian and roughplastic plates leave a constant environment to
/// their BSDF sampling too. Alone under a unit environment the Lambertian
/// plate shows ρ (every cosine-sampled direction escapes); under the
/// environment and a sphere light both plates render the same with and
/// without environment NEE (the estimator is unbiased either way), and
/// with less noise without it, where next-event estimation draws only the
/// sphere.
#[test]
fn diffuse_and_plastic_plates_leave_a_constant_environment_to_bsdf_sampling() {
    use scene_fixtures::plate_at_45deg;
    let env = "[[lights]]\ntype = \"environment\"\nradiance = 1.0\nspectrum = \"constant\"";
    let sphere = "[[lights]]\ntype = \"sphere\"\ncenter = [0.3, 1.0, -0.6]\nradius = 0.1\n\
                  radiance = 20.0\nspectrum = \"constant\"";
    let diffuse = "model = \"diffuse\"\nreflectance = 0.5";
    let plastic = "model = \"roughplastic\"\nalpha = 0.15\nint_ior = 1.49\nreflectance = 0.7";
    let n = 40_000u64;

    let text = plate_at_45deg("", diffuse, env);
    let scene = render::load_str(&scene_path("env_diffuse.toml"), &text).unwrap();
    assert!(scene.lights.bsdf_only_environment);
    let (y, sigma) = pixel_y(&scene, 5, 9, n);
    eprintln!("diffuse ρ 0.5 under a unit environment: Y {y:.5} (σ {sigma:.4})");
    assert!((y - 0.5).abs() < 0.002, "Y {y}");

    // A wave-optical model is not among the materials whose sampling is
    // known to cover the lobe: its scene keeps environment NEE.
    let ghs = "model = \"ghs_ssa\"\nmetal = \"brass\"\nsigma_um = 0.02\nlc_um = 2.0\ngamma = 3.0";
    let text = plate_at_45deg("", ghs, env);
    let scene = render::load_str(&scene_path("env_ghs.toml"), &text).unwrap();
    assert!(!scene.lights.bsdf_only_environment);

    for (name, material) in [("diffuse", diffuse), ("roughplastic", plastic)] {
        let text = plate_at_45deg("", material, &format!("{env}\n\n{sphere}"));
        let mut scene = render::load_str(&scene_path("env_sphere.toml"), &text).unwrap();
        assert!(scene.lights.bsdf_only_environment, "{name}");
        let (a, b) = with_and_without_environment_nee(&mut scene, name, n);
        assert!(a.1 < b.1, "{name}: σ {} not below {}", a.1, b.1);
    }
}

/// Pixel (5, 9)'s Y as (mean, σ) with the environment left to BSDF sampling
/// and with environment NEE, asserted equal within 4 standard errors of the
/// difference of the two independent means.
fn with_and_without_environment_nee(
    scene: &mut render::Scene,
    name: &str,
    n: u64,
) -> ((f64, f64), (f64, f64)) {
    let mut got = Vec::new();
    for bsdf_only in [true, false] {
        scene.lights.bsdf_only_environment = bsdf_only;
        let (y, sigma) = pixel_y(scene, 5, 9, n);
        eprintln!("{name}, BSDF only {bsdf_only}: Y {y:.5} (σ {sigma:.4})");
        got.push((y, sigma));
    }
    let (a, b) = (got[0], got[1]);
    let tol = 4.0 * (a.1 * a.1 + b.1 * b.1).sqrt() / (n as f64).sqrt();
    assert!(
        (a.0 - b.0).abs() < tol,
        "{name}: {a:?} vs {b:?} (tolerance {tol})"
    );
    (a, b)
}

/// Environment NEE and BSDF samples that escape to the environment weigh a
/// direction with the same light count on every kind of first vertex (a
/// conductor whose λ integral is exact, a tabulated diffuse reflectance on
/// sampled wavelengths, a constant one on a λ-flat path): with and without
/// environment NEE the pixel is the same. At these lobes (1/π, and GGX α
/// 0.9's peak) a sphere light's density would count three times; one site
/// counting it so and the other not biased the NEE render by 11 % and 40 %.
#[test]
fn environment_weights_agree_on_every_kind_of_vertex() {
    use scene_fixtures::plate_at_45deg;
    let csv = std::env::temp_dir().join(format!("lustre_env_mis_{}.csv", std::process::id()));
    std::fs::write(
        &csv,
        "wavelength_nm,reflectance\n380,0.2\n500,0.7\n780,0.4\n",
    )
    .unwrap();
    let env = "[[lights]]\ntype = \"environment\"\nradiance = 1.0\nspectrum = \"constant\"";
    let sphere = "[[lights]]\ntype = \"sphere\"\ncenter = [0.3, 1.0, -0.6]\nradius = 0.1\n\
                  radiance = 20.0\nspectrum = \"constant\"";
    let materials = [
        (
            "rough copper",
            "model = \"ggx\"\nmetal = \"cu\"\nalpha = 0.9".to_string(),
        ),
        (
            "tabulated diffuse",
            format!(
                "model = \"diffuse\"\nreflectance_csv = {:?}",
                csv.display().to_string()
            ),
        ),
        (
            "constant diffuse",
            "model = \"diffuse\"\nreflectance = 0.6".to_string(),
        ),
    ];
    let n = 40_000u64;
    for (name, material) in &materials {
        let text = plate_at_45deg("", material, &format!("{env}\n\n{sphere}"));
        let mut scene = render::load_str(&scene_path("env_mis.toml"), &text).unwrap();
        with_and_without_environment_nee(&mut scene, name, n);
    }
    let _ = std::fs::remove_file(&csv);
}
