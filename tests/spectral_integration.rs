//! The exact spectral integration of the first bounce
//! (`spectral_integration = "auto"`, `render::spectral_table`) against the
//! sampled-wavelength estimator it replaces, on scenes that reach every
//! branch: emission seen directly, next-event estimation and BSDF-sampled
//! emission off rough and smooth conductors, delta and area lights, a
//! daylight sky and a constant environment, paths that go on to further
//! bounces (with Russian roulette from the first), and a wave-optical
//! material that is not Fresnel-only. The two must agree in the mean within
//! their statistical error, on every XYZ channel.

use render::Scene;
use render::integrator::sample_pixel;
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
/// a level square of side `size` made of `floor`.
fn scene(body: &str, (floor, size): (&str, f64), mode: &str) -> Scene {
    let text = format!(
        "{CAMERA}\n[integrator]\nsampler = \"independent\"\nspectral_integration = \"{mode}\"\n{body}
[[shapes]]
type = \"rectangle\"
size = [{size}, {size}]
material = \"{floor}\"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}
"
    );
    render::load_str(Path::new("spectral_integration.toml"), &text).unwrap()
}

/// Per channel over the image: the means of the two scenes' estimates and
/// the mean of their difference with its standard error. Both draw the same
/// random numbers for the same sample (the wavelengths have their own
/// reserved draw), so the difference is paired: its error is that of the
/// part of the estimate that differs (the spectral noise), which makes the
/// comparison far sharper than two independent means would be. The error
/// comes from per-pixel variances, so pixel-to-pixel differences do not
/// inflate it.
fn paired(a: &Scene, b: &Scene, spp: u64) -> [(f64, f64, f64, f64); 3] {
    let (w, h) = (a.camera.width, a.camera.height);
    let pixels = (w * h) as f64;
    let mut out = [(0.0, 0.0, 0.0, 0.0); 3];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [[0.0; 3]; 3];
            let mut sq = [0.0; 3];
            for s in 0..spp {
                let va = sample_pixel(a, x, y, s);
                let vb = sample_pixel(b, x, y, s);
                for c in 0..3 {
                    let d = va[c] - vb[c];
                    sum[0][c] += va[c];
                    sum[1][c] += vb[c];
                    sum[2][c] += d;
                    sq[c] += d * d;
                }
            }
            let n = spp as f64;
            for c in 0..3 {
                let mean = sum[2][c] / n;
                let var = (sq[c] / n - mean * mean).max(0.0) * n / (n - 1.0);
                out[c].0 += sum[0][c] / n / pixels;
                out[c].1 += sum[1][c] / n / pixels;
                out[c].2 += mean / pixels;
                out[c].3 += var / n / (pixels * pixels);
            }
        }
    }
    out.map(|(ma, mb, d, v)| (ma, mb, d, v.sqrt()))
}

fn agree(name: &str, body: &str, floor: (&str, f64), spp: u64) {
    let exact = scene(body, floor, "auto");
    let sampled = scene(body, floor, "sampled");
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
