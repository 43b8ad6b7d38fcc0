//! `[integrator] emitter_pixel_samples` (`render::emitter_edges`,
//! `integrator::emission_over_pixel`): on the pixels a directly seen
//! light's outline crosses, the emission seen directly is averaged over
//! several positions in the pixel. Against an independent reference, each
//! pixel's share of rays that see the light (a dense grid of camera rays
//! through the pixel) times the light's colour, on a sphere light and a
//! rectangle light partly hidden by black occluders: the means agree and
//! the outline pixels' variance falls.

use render::Scene;
use render::integrator::sample_pixel;
use render::shapes::Surface;
use std::path::Path;

const SCENE: &str = r#"
[camera]
look_from = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_deg = 20.0
resolution = [14, 12]

[film]
spp = 1

[materials.black]
model = "diffuse"
reflectance = 0.0

[[shapes]]
type = "sphere"
center = [0.12, -0.08, 1.5]
radius = 0.1
material = "black"

[[shapes]]
type = "rectangle"
size = [0.1, 0.5]
material = "black"
transform = { translate = [-0.3, 0.0, 1.0], rotate_deg = [0.0, 0.0, 20.0] }

[[lights]]
type = "sphere"
center = [0.15, 0.05, 0.0]
radius = 0.22
radiance = 3.0
spectrum = "constant"

[[lights]]
type = "rectangle"
size = [0.5, 0.4]
radiance = 2.0
spectrum = "d65"
transform = { translate = [-0.4, -0.15, 0.2], rotate_deg = [10.0, 20.0, 0.0] }
"#;

fn scene(samples: u32) -> Scene {
    let text = SCENE.replace(
        "[film]",
        &format!("[integrator]\nemitter_pixel_samples = {samples}\n\n[film]"),
    );
    render::load_str(Path::new("emitter_edges.toml"), &text).unwrap()
}

/// Per pixel, the share of a 48 × 48 grid of camera rays that meet light
/// `light` first, and whether any of them meets a surface (an occluder).
fn coverage(scene: &Scene, x: u32, y: u32, light: u32) -> (f64, bool) {
    let n = 48;
    let (mut k, mut blocked) = (0, false);
    for i in 0..n {
        for j in 0..n {
            let (px, py) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            let r = scene.camera.ray(x as f64 + px, y as f64 + py);
            let hit = scene.shapes.intersect(&r, f64::INFINITY);
            k += usize::from(hit.is_some_and(|h| h.surface == Surface::Emitter(light)));
            blocked |= hit.is_some_and(|h| matches!(h.surface, Surface::Material(_)));
        }
    }
    (k as f64 / (n * n) as f64, blocked)
}

/// The XYZ of a camera ray that sees light `light` (every sample of a pixel
/// wholly covered by it: no variance).
fn colour(scene: &Scene, light: u32) -> [f64; 3] {
    for y in 0..scene.camera.height {
        for x in 0..scene.camera.width {
            if coverage(scene, x, y, light).0 == 1.0 {
                return sample_pixel(scene, x, y, 0);
            }
        }
    }
    panic!("no pixel wholly on light {light}");
}

/// Mean and variance of the pixel's estimate over `spp` camera samples.
fn moments(scene: &Scene, x: u32, y: u32, spp: u64) -> ([f64; 3], [f64; 3]) {
    let (mut s, mut q) = ([0.0; 3], [0.0; 3]);
    for i in 0..spp {
        let v = sample_pixel(scene, x, y, i);
        for c in 0..3 {
            s[c] += v[c];
            q[c] += v[c] * v[c];
        }
    }
    let n = spp as f64;
    let mean = s.map(|v| v / n);
    (
        mean,
        std::array::from_fn(|c| (q[c] / n - mean[c] * mean[c]).max(0.0) * n / (n - 1.0)),
    )
}

#[test]
fn outline_pixels_average_to_the_lights_coverage_with_less_variance() {
    let (plain, averaged) = (scene(1), scene(16));
    assert!(plain.emitter_edges.is_none(), "{}", plain.prepared);
    let edges = averaged.emitter_edges.as_ref().expect("outlines in view");
    let colours = [colour(&plain, 0), colour(&plain, 1)];
    let spp = 256;
    let (mut outline, mut var_plain, mut var_avg, mut worst) = (0, 0.0, 0.0, 0.0f64);
    for y in 0..plain.camera.height {
        for x in 0..plain.camera.width {
            let (c0, b0) = coverage(&plain, x, y, 0);
            let (c1, _) = coverage(&plain, x, y, 1);
            let cover = [c0, c1];
            let expect: [f64; 3] =
                std::array::from_fn(|c| cover[0] * colours[0][c] + cover[1] * colours[1][c]);
            let (m1, v1) = moments(&plain, x, y, spp);
            let (m16, v16) = moments(&averaged, x, y, spp);
            for (m, v) in [(m1, v1), (m16, v16)] {
                for c in 0..3 {
                    // The grid's coverage is itself within ~1/48 of a pixel
                    // edge's length of the truth.
                    let tol =
                        4.5 * (v[c] / spp as f64).sqrt() + 0.01 * colours[0][c].max(colours[1][c]);
                    let z = (m[c] - expect[c]).abs();
                    worst = worst.max(z / tol);
                    assert!(
                        z <= tol,
                        "pixel ({x}, {y}) channel {c}: {} against {}",
                        m[c],
                        expect[c]
                    );
                }
            }
            // An occluder's edge across a light is not a light's outline:
            // the mask, drawn from the camera and the lights alone, leaves it.
            if cover.iter().any(|&k| k > 0.02 && k < 0.98) && !b0 {
                outline += 1;
                assert!(edges.contains(x, y), "outline pixel ({x}, {y}) unmarked");
                var_plain += v1[1];
                var_avg += v16[1];
            }
        }
    }
    assert!(outline >= 8, "{outline} outline pixels");
    // 16 stratified positions against one: the variance of a pixel's
    // coverage falls by far more than 16×; 8× is the bound checked.
    assert!(
        var_avg * 8.0 < var_plain,
        "outline variance {var_avg:.3e} (16 positions) against {var_plain:.3e} (1); worst {worst:.2}"
    );
}

#[test]
fn out_of_range_sample_counts_are_refused() {
    for bad in ["0", "65", "-1", "2.5"] {
        let text = SCENE.replace(
            "[film]",
            &format!("[integrator]\nemitter_pixel_samples = {bad}\n\n[film]"),
        );
        let e = render::load_str(Path::new("bad.toml"), &text)
            .err()
            .expect(bad)
            .to_string();
        // The line of the key; in range checks also its name and range.
        assert!(e.contains("bad.toml:10:"), "{bad}: {e}");
        if bad == "0" || bad == "65" {
            assert!(
                e.contains("emitter_pixel_samples = ") && e.contains("1..=64"),
                "{e}"
            );
        }
    }
}
