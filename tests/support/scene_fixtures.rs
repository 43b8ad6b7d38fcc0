//! Scene texts and scratch folders shared by the render integration tests.

// Each test crate includes this module and uses only part of it.
#![allow(dead_code)]

use std::path::PathBuf;

/// A fresh scratch folder under the system temp dir, unique per test process.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 10 m GGX plate with Fresnel = 1 and roughness `alpha`, seen at 60° from
/// the normal through a 0.5° camera of `res`×`res` pixels (every pixel sees
/// the same direction), direct light only, lit by the `[[lights]]` table
/// `light` (TOML text).
pub fn plate_at_60deg(alpha: f64, res: u32, light: &str) -> String {
    format!(
        r#"
[camera]
look_from = [0.0, 50.0, 86.60254037844386]
look_at = [0.0, 0.0, 0.0]
fov_deg = 0.5
resolution = [{res}, {res}]

[film]
spp = 1

[integrator]
max_depth = 1

[materials.m]
model = "ggx"
fresnel = "one"
alpha = {alpha}

[[shapes]]
type = "rectangle"
size = [10.0, 10.0]
material = "m"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

{light}
"#
    )
}

/// The eye of [`plate_at_45deg`].
pub const EYE_45DEG: [f64; 3] = [
    0.0,
    std::f64::consts::FRAC_1_SQRT_2,
    std::f64::consts::FRAC_1_SQRT_2,
];

/// A 2 m plate (material `m`, TOML body `material`) seen at 45° through a
/// 2° camera of 16×16 pixels, one bounce, with `integrator` lines added to
/// `[integrator]` and the `[[lights]]` table `light` (TOML text).
pub fn plate_at_45deg(integrator: &str, material: &str, light: &str) -> String {
    format!(
        r#"
[camera]
look_from = [0.0, 0.7071067811865476, 0.7071067811865476]
look_at = [0.0, 0.0, 0.0]
fov_deg = 2.0
resolution = [16, 16]

[film]
spp = 1

[integrator]
max_depth = 1
{integrator}

[materials.m]
{material}

[[shapes]]
type = "rectangle"
size = [2.0, 2.0]
material = "m"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

{light}
"#
    )
}

/// A 6 × 5 camera over the glossy-ball scene, one sample per pixel.
pub const BALL_CAMERA: &str = r#"
[camera]
look_from = [0.0, 1.4, 1.4]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_deg = 60.0
resolution = [6, 5]

[film]
spp = 1
"#;

/// A grey diffuse floor, a rough-plastic patch and a GGX copper ball on it
/// under a small D65 sphere light: light reaches the floor off the ball.
pub const BALL: &str = r#"
[materials.floor]
model = "diffuse"
reflectance = 0.8

[materials.patch]
model = "roughplastic"
alpha = 0.3
reflectance = 0.4

[materials.ball]
model = "ggx"
metal = "cu"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [4.0, 4.0]
material = "floor"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "disk"
radius = 0.3
material = "patch"
transform = { translate = [0.5, 0.001, 0.3], rotate_deg = [-90.0, 0.0, 0.0] }

[[shapes]]
type = "sphere"
center = [-0.2, 0.3, -0.2]
radius = 0.3
material = "ball"

[[lights]]
type = "sphere"
center = [-1.5, 2.0, -1.0]
radius = 0.25
radiance = 50.0
spectrum = "d65"
"#;

/// [`BALL`] with a silver mirror beside it: a delta caster.
pub fn ball_and_mirror() -> String {
    format!(
        "{BALL}\n[materials.mirror]\nmodel = \"smooth\"\nmetal = \"ag\"\n
[[shapes]]
type = \"rectangle\"
size = [0.5, 0.5]
material = \"mirror\"
transform = {{ translate = [0.5, 0.3, -0.6], rotate_deg = [-20.0, 0.0, 0.0] }}
"
    )
}
