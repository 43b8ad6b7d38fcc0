//! `[integrator] caustic_guiding` (`render::guide`): diffuse and rough-plastic
//! vertices that aim a share of their BSDF samples at glossy objects
//! render the same image, in the mean, as vertices that sample their BSDF
//! alone, on scenes where the aimed samples matter: a glossy ball and a
//! mirror disk lighting a grey floor and a plastic patch under a small
//! light and an environment, a glossy mesh, paths that go on for several
//! bounces with Russian roulette, λ-exact and sampled-wavelength paths.
//! And the aimed samples find the caustic: the error of the floor's
//! estimate falls.

#[path = "support/paired.rs"]
mod paired;
#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;

use paired::{batch_variance, paired};
use render::Scene;
use scene_fixtures::{BALL, BALL_CAMERA as CAMERA, ball_and_mirror};
use std::path::Path;

fn scene(body: &str, share: f64) -> Scene {
    let text = format!(
        "{CAMERA}\n[integrator]\nsampler = \"independent\"\ncaustic_guiding = {share}\n{body}"
    );
    render::load_str(Path::new("caustic_guiding.toml"), &text).unwrap()
}

/// The guided and unguided renders agree within 4.5 standard errors of
/// their paired difference on every channel.
fn agree(name: &str, body: &str, share: f64, spp: u64) {
    let (off, on) = (scene(body, 0.0), scene(body, share));
    assert!(off.casters.is_empty(), "{name}: {}", off.prepared);
    assert!(!on.casters.is_empty(), "{name}: {}", on.prepared);
    for (c, (ma, mb, d, e)) in paired(&on, &off, spp).into_iter().enumerate() {
        let z = d / e;
        eprintln!(
            "{name} channel {c}: guided {ma:.6}, unguided {mb:.6}, difference {d:+.2e} ± {e:.2e} (z = {z:+.2})"
        );
        // The comparison must be able to see a 3 % error.
        assert!(e < 6e-3 * mb.abs(), "{name}: too noisy to compare");
        assert!(z.abs() < 4.5, "{name} channel {c}: z = {z}");
    }
}

#[test]
fn a_ball_and_a_mirror_lighting_the_floor() {
    agree(
        "ball and mirror",
        &format!("max_depth = 3\n{}", ball_and_mirror()),
        0.5,
        3000,
    );
}

#[test]
fn more_bounces_under_an_environment_with_roulette_from_the_first() {
    agree(
        "environment, roulette",
        &format!(
            "max_depth = 6\nrr_depth = 1\n{}
[[lights]]
type = \"environment\"
radiance = 0.2
spectrum = \"a\"
",
            ball_and_mirror()
        ),
        0.9,
        3000,
    );
}

#[test]
fn sampled_wavelengths_and_the_power_of_balance() {
    // Every path with sampled wavelengths (the mixture's density carried
    // to the other wavelengths, `Pending`), and the balance heuristic.
    agree(
        "sampled, balance",
        &format!(
            "max_depth = 3\nspectral_integration = \"sampled\"\nmis = \"balance\"\n{}",
            ball_and_mirror()
        ),
        0.3,
        3000,
    );
}

#[test]
fn a_light_as_wide_as_the_lobes() {
    // Under a wide light both strategies' weights matter at every vertex,
    // so the mixture's density must enter next-event estimation's weight
    // too (λ-exact and sampled-wavelength paths).
    let wide = format!(
        "{BALL}
[[lights]]
type = \"sphere\"
center = [1.0, 1.5, 1.0]
radius = 1.0
radiance = 2.0
spectrum = \"d65\"
"
    );
    for mode in ["auto", "sampled"] {
        agree(
            &format!("wide light, {mode}"),
            &format!("max_depth = 3\nspectral_integration = \"{mode}\"\n{wide}"),
            0.6,
            3000,
        );
    }
}

#[test]
fn a_glossy_mesh() {
    let body = r#"
max_depth = 3

[materials.floor]
model = "diffuse"
reflectance = 0.7

[materials.gold]
model = "beckmann"
metal = "au"
alpha = 0.1

[[shapes]]
type = "rectangle"
size = [4.0, 4.0]
material = "floor"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "mesh"
file = "../scenes/assets/preview_object.obj"
material = "gold"
transform = { scale = 0.5, translate = [0.2, 0.0, -0.3] }

[[lights]]
type = "sphere"
center = [1.0, 2.0, -1.5]
radius = 0.1
radiance = 300.0
spectrum = "d65"
"#;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/caustic_guiding.toml");
    let load = |share: f64| {
        let text = format!(
            "{CAMERA}\n[integrator]\nsampler = \"independent\"\ncaustic_guiding = {share}\n{body}"
        );
        render::load_str(&path, &text).unwrap()
    };
    let (off, on) = (load(0.0), load(0.5));
    assert_eq!(on.casters.len(), 1, "{}", on.prepared);
    for (c, (ma, mb, d, e)) in paired(&on, &off, 2000).into_iter().enumerate() {
        let z = d / e;
        eprintln!("mesh channel {c}: {ma:.6} vs {mb:.6}, {d:+.2e} ± {e:.2e} (z = {z:+.2})");
        assert!(e < 6e-3 * mb.abs() && z.abs() < 4.5, "channel {c}: z = {z}");
    }
}

/// Mean squared error of 16-sample pixel estimates against the mean of
/// many, over the floor pixels of a caustic: the aimed samples must lower it.
#[test]
fn aimed_samples_lower_the_caustics_error() {
    // The camera looks straight down at floor beside the ball, which it
    // does not see: the floor's light is the small light's (next-event
    // estimation) and the ball's glint (BSDF samples only).
    let body = format!("max_depth = 2\n{BALL}");
    let load = |share: f64| {
        let text = format!(
            "[camera]\nlook_from = [0.7, 1.5, 0.1]\nlook_at = [0.7, 0.0, 0.1]\nup = [0.0, 0.0, -1.0]\n\
             fov_deg = 30.0\nresolution = [6, 5]\n[film]\nspp = 1\n\
             [integrator]\nsampler = \"independent\"\ncaustic_guiding = {share}\n{body}"
        );
        render::load_str(Path::new("caustic_guiding.toml"), &text).unwrap()
    };
    let (off, on) = (load(0.0), load(0.5));
    let error = |s: &Scene| batch_variance(s, 400, 16);
    let (e_off, e_on) = (error(&off), error(&on));
    eprintln!("variance of a 16-spp pixel (Y): unguided {e_off:.4e}, guided {e_on:.4e}");
    assert!(e_on < 0.7 * e_off, "{e_on} vs {e_off}");
}

#[test]
fn out_of_range_shares_are_refused() {
    for bad in ["-0.1", "0.95", "nan", "inf"] {
        let text = format!("{CAMERA}\n[integrator]\ncaustic_guiding = {bad}\n{BALL}");
        let e = render::load_str(Path::new("bad.toml"), &text)
            .err()
            .unwrap_or_else(|| panic!("{bad} accepted"))
            .to_string();
        assert!(e.contains("caustic_guiding") && e.contains("0.9"), "{e}");
    }
}
