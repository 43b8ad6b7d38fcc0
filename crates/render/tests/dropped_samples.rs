//! Non-finite and negative camera samples are dropped, counted and located,
//! never averaged into the film: a deliberately broken material returns
//! negative values for some wavelengths and NaN weights for some samples.

use brdf::{Bxdf, BxdfSample, DVec3};
use render::film::{BadSample, Dropped, Film};
use render::integrator::sample_pixel_checked;
use render::material::DynBxdf;
use render::{RenderOptions, load_str};
use std::path::Path;

const SCENE: &str = r#"
[camera]
look_from = [0.0, 0.6, 1.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [9, 7]

[film]
spp = 24
seed = 3

[integrator]
max_depth = 3

[materials.plate]
model = "ggx"
alpha = 0.3
fresnel = "one"

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "plate"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "environment"
radiance = 1.0
"#;

/// A GGX plate that misbehaves: f < 0 below 480 nm for wo leaning to +x,
/// and a NaN sample weight for a tenth of the lobe-choice numbers.
struct Broken(DynBxdf);

impl Bxdf for Broken {
    fn eval(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
        let f = self.0.eval(wi, wo, l);
        if l < 480.0 && wo.x > 0.2 { -f } else { f }
    }
    fn pdf(&self, wi: DVec3, wo: DVec3, l: f64) -> f64 {
        self.0.pdf(wi, wo, l)
    }
    fn sample(&self, wi: DVec3, l: f64, u: [f64; 3]) -> Option<BxdfSample> {
        let mut s = self.0.sample(wi, l, u)?;
        if u[0] > 0.9 {
            s.weight = f64::NAN;
        }
        Some(s)
    }
}

fn scene(broken: bool) -> render::Scene {
    let mut s = load_str(Path::new("dropped.toml"), SCENE).unwrap();
    if broken {
        let m = &mut s.materials[0];
        let inner = std::mem::replace(
            &mut m.bxdf,
            Box::new(brdf::SmoothConductor::new(brdf::Fresnel::One).unwrap()),
        );
        m.bxdf = Box::new(Broken(inner));
        // The broken model is not Fresnel-only: its first bounce must not
        // be integrated through the split of the model it replaced.
        m.fresnel_only = None;
        m.lambda_free = false;
        // Nor is it a conductor whose sampling covers its lobe: the
        // environment must be sampled by NEE too, as `build` would decide.
        s.lights.bsdf_only_environment = false;
    }
    s
}

#[test]
fn broken_material_samples_are_counted_located_and_left_out() {
    let s = scene(true);
    let spp = s.settings.spp;
    let mut film = s.film().unwrap();
    let opts = RenderOptions {
        threads: Some(2),
        ..RenderOptions::default()
    };
    let out = render::render_range(&s, &mut film, 0..spp, &opts).unwrap();
    assert!(out.complete);

    // Brute force: every camera sample, in (sample, row, column) order.
    let mut want = Dropped::default();
    let mut sums = vec![[0.0f64; 3]; film.sums().len()];
    for smp in 0..spp {
        for y in 0..s.camera.height {
            for x in 0..s.camera.width {
                match sample_pixel_checked(&s, x, y, smp) {
                    Ok(v) => {
                        assert!(v.iter().all(|c| c.is_finite() && *c >= 0.0));
                        let p = &mut sums[(y * s.camera.width + x) as usize];
                        for k in 0..3 {
                            p[k] += v[k];
                        }
                    }
                    Err(why) => want.record(why, x, y, smp),
                }
            }
        }
    }
    assert!(want.non_finite > 0 && want.negative > 0, "{want:?}");
    assert_eq!(out.dropped, want);
    assert_eq!(film.dropped(), &want);
    let first = want.first.unwrap();
    assert!(matches!(
        sample_pixel_checked(&s, first.x, first.y, first.sample),
        Err(BadSample::NonFinite | BadSample::Negative)
    ));
    // The film holds exactly the good samples (to fixed-point rounding).
    for (i, (got, want)) in film.sums().iter().zip(&sums).enumerate() {
        for k in 0..3 {
            let g = got[k] as f64 / (1u64 << 40) as f64;
            assert!(
                (g - want[k]).abs() <= 1e-9 * (1.0 + want[k].abs()),
                "pixel {i}: {g} vs {}",
                want[k]
            );
            assert!(got[k] >= 0, "pixel {i} went negative");
        }
    }
    // The count travels through the film file.
    let back = Film::from_bytes(&film.to_bytes()).unwrap();
    assert_eq!(back.dropped(), &want);
    let msg = want.to_string();
    assert!(
        msg.contains("sample(s) dropped") && msg.contains("first at pixel"),
        "{msg}"
    );
}

#[test]
fn a_sound_render_drops_nothing() {
    let s = scene(false);
    let mut film = s.film().unwrap();
    let out = render::render_range(&s, &mut film, 0..8, &RenderOptions::default()).unwrap();
    assert_eq!(out.dropped, Dropped::default());
    assert_eq!(film.dropped().total(), 0);
    assert!(film.sums().iter().any(|p| p[1] > 0));
}

/// A sun 1° above the horizon: the sky's CIE daylight spectrum is negative
/// at the blue end for the reddish chromaticities near the sun, and those
/// samples are part of the sky's colour, not a model's failure (they were
/// dropped: 134 of 4 096 here, and sky pixels came out black).
#[test]
fn a_low_sun_sky_drops_no_sample() {
    let text = r#"
[camera]
look_from = [0.0, 0.0, 0.0]
look_at = [0.0, 0.3, -1.0]
fov_deg = 90.0
resolution = [32, 32]

[film]
spp = 4
seed = 1

[[lights]]
type = "sky"
sun_elevation_deg = 1.0
turbidity = 2.5
scale = 1e-4
"#;
    let scene = load_str(Path::new("low_sun.toml"), text).unwrap();
    // The case under test occurs: some direction's spectrum is negative.
    let negative = (0..4096).any(|i| {
        let d = DVec3::new((i % 64) as f64 / 32.0 - 1.0, (i / 64) as f64 / 200.0, -1.0).normalize();
        let render::light::LightKind::Environment(render::light::Environment::Sky(sky)) =
            &scene.lights.lights[0]
        else {
            panic!("the sky is the only light");
        };
        let c = sky.coefficients(d);
        (360..830).any(|l| sky.spectral(&c, l as f64) < 0.0)
    });
    assert!(negative, "no direction of this sky has a negative spectrum");
    let mut sum_y = 0.0;
    for y in 0..32 {
        for x in 0..32 {
            for s in 0..4 {
                let xyz = sample_pixel_checked(&scene, x, y, s)
                    .unwrap_or_else(|e| panic!("pixel ({x}, {y}) sample {s}: {e:?}"));
                sum_y += xyz[1];
            }
        }
    }
    assert!(sum_y > 0.0);
}

/// A light so bright that one sample's XYZ leaves the film's fixed-point
/// range: each such sample is dropped and counted, where the conversion used
/// to saturate and give every lit pixel the same value silently.
#[test]
fn samples_beyond_the_films_range_are_dropped_not_saturated() {
    for (intensity, beyond) in [(1e10, false), (1e30, true)] {
        let text = format!(
            r#"
[camera]
look_from = [0.0, 0.6, 1.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [9, 7]

[film]
spp = 2
seed = 3

[materials.plate]
model = "ggx"
alpha = 0.3
fresnel = "one"

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "plate"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

[[lights]]
type = "point"
position = [0.0, 1.0, 0.5]
intensity = {intensity:e}
"#
        );
        let scene = load_str(Path::new("bright.toml"), &text).unwrap();
        let (mut lit, mut dropped) = (0, 0);
        for y in 0..7 {
            for x in 0..9 {
                for s in 0..2 {
                    match sample_pixel_checked(&scene, x, y, s) {
                        Ok(xyz) => lit += usize::from(xyz[1] > 0.0),
                        Err(BadSample::NonFinite) => dropped += 1,
                        Err(e) => panic!("({x}, {y}) {s}: {e:?}"),
                    }
                }
            }
        }
        if beyond {
            assert!(
                dropped > 60 && lit == 0,
                "{intensity:e}: {dropped} dropped, {lit} lit"
            );
        } else {
            assert!(
                dropped == 0 && lit > 60,
                "{intensity:e}: {dropped} dropped, {lit} lit"
            );
        }
    }
}
