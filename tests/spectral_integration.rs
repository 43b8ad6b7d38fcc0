//! The exact spectral integration of the first bounce
//! (`spectral_integration = "auto"`, `render::spectral_table`) against the
//! sampled-wavelength estimator it replaces, on scenes that reach every
//! branch: emission seen directly, next-event estimation and BSDF-sampled
//! emission off rough and smooth conductors, delta and area lights, a
//! daylight sky and a constant environment, paths that go on to further
//! bounces (with Russian roulette from the first), and a wave-optical
//! material that is not Fresnel-only; and paths integrated over λ exactly
//! past the first vertex (`integrator.rs`, `trace_flat`): grey diffuse and rough
//! plastic (a checkerboard too) under area lights, a constant environment,
//! the sky and an environment map, a conductor seen through a grey floor
//! and a grey object seen in a conductor, and two conductors in a row,
//! where the path goes on with sampled wavelengths. The two must agree in
//! the mean within their statistical error, on every XYZ channel.

#[path = "support/paired.rs"]
mod paired;

use paired::paired;
use render::Scene;
use std::path::Path;

const CAMERA: &str = r#"
[camera]
look_from = [0.0, 1.2, 1.6]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_deg = 50.0
resolution = [6, 5]

[film]
spp = 1
"#;

/// The scene: `body` continues `[integrator]`, and every scene stands on
/// a level square of side `size` made of `floor`. The emission seen
/// directly is not averaged over light outlines (`emitter_pixel_samples`
/// 1): the sampled scene has no λ tables to average it with, and the
/// pairing compares the λ integration alone.
/// (Read as the file `path`, which relative file names follow.)
fn scene_at(path: &Path, body: &str, (floor, size): (&str, f64), mode: &str) -> Scene {
    let text = format!(
        "{CAMERA}\n[integrator]\nsampler = \"independent\"\nemitter_pixel_samples = 1\nspectral_integration = \"{mode}\"\n{body}
[[shapes]]
type = \"rectangle\"
size = [{size}, {size}]
material = \"{floor}\"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}
"
    );
    render::load_str(path, &text).unwrap()
}

fn agree(name: &str, body: &str, floor: (&str, f64), spp: u64) {
    agree_at(
        Path::new("spectral_integration.toml"),
        name,
        body,
        floor,
        spp,
    );
}

fn agree_at(path: &Path, name: &str, body: &str, floor: (&str, f64), spp: u64) {
    let exact = scene_at(path, body, floor, "auto");
    let sampled = scene_at(path, body, floor, "sampled");
    assert!(exact.spectral.is_some(), "{name}: {}", exact.prepared);
    assert!(sampled.spectral.is_none(), "{name}: {}", sampled.prepared);
    for (c, (ma, mb, d, e)) in paired(&exact, &sampled, spp).into_iter().enumerate() {
        let z = d / e;
        eprintln!(
            "{name} channel {c}: exact {ma:.6}, sampled {mb:.6}, difference {d:+.2e} ± {e:.2e} (z = {z:+.2})"
        );
        // The comparison must be able to see a 1.5 % error.
        assert!(e < 3e-3 * mb.abs(), "{name}: too noisy to compare");
        assert!(z.abs() < 4.5, "{name} channel {c}: z = {z}");
    }
}

#[test]
fn copper_plate_and_its_light_seen_directly() {
    agree(
        "plate",
        r#"
max_depth = 1

[materials.plate]
model = "ggx"
metal = "cu"
alpha = 0.3

[[lights]]
type = "sphere"
center = [0.0, 0.5, -0.6]
radius = 0.25
radiance = 2.0
spectrum = "constant"
"#,
        ("plate", 3.0),
        4000,
    );
}

#[test]
fn mirror_sphere_on_a_gold_floor_under_two_lights_with_more_bounces() {
    agree(
        "bounces",
        r#"
max_depth = 4
rr_depth = 1

[materials.floor]
model = "beckmann"
metal = "au"
alpha = 0.15

[materials.ball]
model = "smooth"
metal = "ag"

[materials.chrome]
model = "ggx"
metal = "cr"
alpha_x = 0.1
alpha_y = 0.4

[[shapes]]
type = "sphere"
center = [-0.3, 0.3, 0.0]
radius = 0.3
material = "ball"

[[shapes]]
type = "sphere"
center = [0.4, 0.25, 0.2]
radius = 0.25
material = "chrome"

[[lights]]
type = "rectangle"
size = [1.0, 1.0]
radiance = 3.0
spectrum = "d65"
transform = { rotate_deg = [90.0, 0.0, 0.0], translate = [0.0, 1.5, 0.0] }

[[lights]]
type = "point"
position = [1.0, 1.0, 1.0]
intensity = 1.5
spectrum = "blackbody(3000)"
"#,
        ("floor", 4.0),
        20000,
    );
}

#[test]
fn aluminium_under_the_daylight_sky() {
    agree(
        "sky",
        r#"
max_depth = 2

[materials.plate]
model = "ggx"
metal = "al"
alpha = 0.2

[[lights]]
type = "sky"
sun_elevation_deg = 40.0
sun_azimuth_deg = 180.0
scale = 1e-4
"#,
        ("plate", 3.0),
        4000,
    );
}

#[test]
fn a_wave_optical_plate_keeps_sampled_wavelengths_beside_a_conductor() {
    agree(
        "mixed",
        r#"
max_depth = 3

[materials.ghs]
model = "ghs_ssa"
metal = "cu"
sigma_um = 0.02
lc_um = 2.0
gamma = 2.5

[materials.ball]
model = "ggx"
metal = "brass"
alpha = 0.25

[[shapes]]
type = "sphere"
center = [0.0, 0.35, 0.0]
radius = 0.35
material = "ball"

[[lights]]
type = "environment"
radiance = 1.0
spectrum = "a"
"#,
        ("ghs", 3.0),
        4000,
    );
}

/// Grey materials under coloured lights, and a ball on the floor: every
/// path λ-free, several bounces with Russian roulette from the first.
const GREY: &str = r#"
[materials.floor]
model = "diffuse"
reflectance = 0.7

[materials.ball]
model = "roughplastic"
alpha = 0.2
reflectance = 0.5

[[shapes]]
type = "sphere"
center = [0.0, 0.35, 0.0]
radius = 0.35
material = "ball"
"#;

#[test]
fn grey_diffuse_and_plastic_over_several_bounces() {
    agree(
        "grey",
        &format!(
            r#"
max_depth = 5
rr_depth = 1
{GREY}
[[lights]]
type = "sphere"
center = [0.8, 1.2, 0.6]
radius = 0.2
radiance = 3.0
spectrum = "blackbody(3000)"

[[lights]]
type = "environment"
radiance = 0.2
spectrum = "d65"
"#
        ),
        ("floor", 3.0),
        4000,
    );
}

#[test]
fn a_grey_checkerboard_under_the_sky() {
    agree(
        "checker sky",
        r#"
max_depth = 3

[materials.floor]
model = "roughplastic"
alpha = 0.3
checker_reflectance = [0.8, 0.1]
checker_tiles = [4.0, 4.0]

[materials.ball]
model = "diffuse"
reflectance = 0.6

[[shapes]]
type = "sphere"
center = [0.0, 0.35, 0.0]
radius = 0.35
material = "ball"

[[lights]]
type = "sky"
sun_elevation_deg = 35.0
sun_azimuth_deg = 120.0
scale = 1e-4
"#,
        ("floor", 3.0),
        4000,
    );
}

/// A conductor ball on a grey floor under a small light: the floor sees
/// the light in the ball (floor → conductor → light, the Fresnel factor at
/// the second vertex), and the ball sees the lit floor (conductor →
/// floor → light, at the first).
#[test]
fn a_copper_ball_on_a_grey_floor() {
    agree(
        "copper ball",
        r#"
max_depth = 4

[materials.floor]
model = "diffuse"
reflectance = 0.8

[materials.ball]
model = "ggx"
metal = "cu"
alpha = 0.1

[[shapes]]
type = "sphere"
center = [0.0, 0.35, 0.0]
radius = 0.35
material = "ball"

[[lights]]
type = "sphere"
center = [-0.6, 1.0, -0.8]
radius = 0.15
radiance = 20.0
spectrum = "d65"

[[lights]]
type = "environment"
radiance = 0.1
spectrum = "a"
"#,
        ("floor", 3.0),
        4000,
    );
}

/// A mirror ball on a gold floor: paths from the floor into the ball meet a
/// second conductor and go on with sampled wavelengths; the ball's delta
/// lobe and the floor's glossy one, under a light and the environment.
#[test]
fn two_conductors_in_a_row_hand_over_to_sampled_wavelengths() {
    agree(
        "two conductors",
        r#"
max_depth = 4
rr_depth = 2

[materials.floor]
model = "ggx"
metal = "au"
alpha = 0.3

[materials.ball]
model = "smooth"
metal = "cu"

[materials.grey]
model = "diffuse"
reflectance = 0.5

[[shapes]]
type = "sphere"
center = [0.0, 0.35, 0.0]
radius = 0.35
material = "ball"

[[shapes]]
type = "sphere"
center = [0.6, 0.2, 0.3]
radius = 0.2
material = "grey"

[[lights]]
type = "sphere"
center = [-0.6, 1.0, -0.8]
radius = 0.25
radiance = 8.0
spectrum = "d65"

[[lights]]
type = "environment"
radiance = 0.3
spectrum = "blackbody(6000)"
"#,
        ("floor", 3.0),
        4000,
    );
}

/// A lat-long map with a bright patch, through the renderer's own writer.
fn write_map(path: &Path) {
    let (w, h) = (16usize, 8usize);
    let px: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sun = if (5..7).contains(&x) && (2..4).contains(&y) {
                20.0
            } else {
                0.0
            };
            [0.3 + sun, 0.2 + 0.05 * x as f32, 0.1 + 0.1 * y as f32 + sun]
        })
        .collect();
    render::output::write_exr(path, w as u32, h as u32, &px).unwrap();
}

#[test]
fn grey_materials_and_a_conductor_under_an_environment_map() {
    let dir = std::env::temp_dir().join(format!("lustre_flat_envmap_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write_map(&dir.join("map.exr"));
    agree_at(
        &dir.join("s.toml"),
        "environment map",
        &format!(
            r#"
max_depth = 4
{GREY}
[materials.plate]
model = "beckmann"
metal = "ag"
alpha = 0.2

[[shapes]]
type = "sphere"
center = [0.6, 0.2, 0.3]
radius = 0.2
material = "plate"

[[lights]]
type = "environment"
radiance = 1.0
file = "map.exr"
"#
        ),
        ("floor", 3.0),
        4000,
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
