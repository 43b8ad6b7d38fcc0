//! OBJ meshes in the BVH and EXR environment maps, end to end.

#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;
use render::integrator::sample_pixel;
use render::{Film, RenderOptions};
use scene_fixtures::{plate_at_60deg, temp_dir};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// A unit cube as 12 triangles (faces wound outward).
const CUBE_OBJ: &str = "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";

/// Two mirror cubes (Fresnel = 1) from an OBJ file, one rotated and scaled,
/// resting on a mirror floor in a unit constant environment: every path
/// returns radiance 1, so a BVH, normal or self-intersection error shows up
/// as dark or bright pixels.
#[test]
fn mirror_mesh_furnace() {
    let dir = temp_dir("mesh");
    std::fs::write(dir.join("cube.obj"), CUBE_OBJ).unwrap();
    let text = r#"
[camera]
look_from = [1.5, 1.6, 2.5]
look_at = [0.0, 0.4, 0.0]
fov_deg = 45.0
resolution = [24, 18]

[film]
spp = 32
seed = 5

[integrator]
max_depth = 64
wavelengths = "hero"

[materials.mirror]
model = "smooth"
fresnel = "one"

[[shapes]]
type = "mesh"
file = "cube.obj"
material = "mirror"
transform = { translate = [0.0, 0.5, 0.0] }

[[shapes]]
type = "mesh"
file = "cube.obj"
material = "mirror"
transform = { translate = [0.9, 0.3, -0.4], rotate_deg = [0.0, 35.0, 20.0], scale = 0.5 }

[[shapes]]
type = "disk"
radius = 3.0
material = "mirror"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "environment"
radiance = 1.0
spectrum = "constant"
"#;
    let scene = render::load_str(&dir.join("scene.toml"), text).unwrap();
    assert!(
        scene.prepared.contains("BVH over 24 triangle(s)"),
        "{}",
        scene.prepared
    );
    let mut film = Film::new(24, 18, scene.fingerprint, 5, 0.0).unwrap();
    render::render_range(&scene, &mut film, 0..32, &RenderOptions::default()).unwrap();
    let ys: Vec<f64> = (0..film.sums().len()).map(|i| film.xyz(i)[1]).collect();
    let mean = ys.iter().sum::<f64>() / ys.len() as f64;
    let worst = ys.iter().map(|y| (y - 1.0).abs()).fold(0.0, f64::max);
    eprintln!("mesh furnace: mean Y {mean:.5}, worst |Y − 1| {worst:.4}");
    assert!(
        (mean - 1.0).abs() < 0.005 && worst < 0.2,
        "mean {mean}, worst {worst}"
    );
    // The cube must actually be in view: some camera rays hit it first.
    let cam_ray = scene.camera.ray(12.0, 9.0);
    let hit = scene.shapes.intersect(&cam_ray, f64::INFINITY).unwrap();
    assert!(matches!(hit.surface, render::shapes::Surface::Material(0)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A lat-long map with strong structure, written with the renderer's own EXR writer.
fn write_map(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    let (w, h) = (32usize, 16usize);
    let px: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sun = if (10..13).contains(&x) && (3..5).contains(&y) {
                40.0
            } else {
                0.0
            };
            [
                0.2 + sun + 0.05 * x as f32,
                0.3 + sun,
                0.1 + 0.1 * y as f32 + sun,
            ]
        })
        .collect();
    render::output::write_exr(path, w as u32, h as u32, &px).unwrap();
    (w, h, px)
}

fn luminance(p: [f32; 3]) -> f64 {
    0.2126729 * p[0] as f64 + 0.7151522 * p[1] as f64 + 0.0721750 * p[2] as f64
}

/// Direction → texel, independently of the renderer: u = 0 at −z growing
/// toward +x, v = 0 at +y.
fn texel(w: usize, h: usize, d: glam::DVec3) -> usize {
    let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    let x = ((u * w as f64) as usize).min(w - 1);
    let y = ((v * h as f64) as usize).min(h - 1);
    y * w + x
}

#[test]
fn environment_map_is_seen_in_its_colours_and_lights_a_plate() {
    let dir = temp_dir("envmap");
    let (w, h, px) = write_map(&dir.join("sky.exr"));

    // 1. Looking straight into the map: XYZ → sRGB gives back the texel (exact colour lift).
    let view = r#"
[camera]
look_from = [0.0, 0.0, 0.0]
look_at = [0.3, 0.5, -1.0]
fov_deg = 1.0
resolution = [1, 1]

[film]
spp = 1

[[lights]]
type = "environment"
radiance = 1.0
file = "sky.exr"
"#;
    let scene = render::load_str(&dir.join("view.toml"), view).unwrap();
    let d = glam::DVec3::new(0.3, 0.5, -1.0).normalize();
    let want = px[texel(w, h, d)];
    let mut film = Film::new(1, 1, scene.fingerprint, 0, 0.0).unwrap();
    render::render_range(&scene, &mut film, 0..20_000, &RenderOptions::default()).unwrap();
    let got = film.rgb()[0];
    eprintln!("env texel {want:?}, rendered {got:?}");
    for k in 0..3 {
        assert!(
            (got[k] / want[k] - 1.0).abs() < 0.02,
            "channel {k}: {got:?} vs {want:?}"
        );
    }

    // 2. A rough Fresnel = 1 plate lit by the map: Y against a quadrature of f·cos·Y_env.
    let plate = plate_at_60deg(
        0.4,
        3,
        "[[lights]]\ntype = \"environment\"\nradiance = 1.0\nfile = \"sky.exr\"",
    );
    let scene = render::load_str(&dir.join("plate.toml"), &plate).unwrap();
    use brdf::{Bxdf, Distribution, Fresnel, MicrofacetConductor};
    let m = MicrofacetConductor::new(Distribution::ggx(0.4, 0.4).unwrap(), Fresnel::One).unwrap();
    // Plate local frame: t = +x, b = −z, n = +y (see the rectangle's transform).
    let wo_world = glam::DVec3::new(0.0, 0.5, 0.8660254037844386);
    let local = |v: glam::DVec3| glam::DVec3::new(v.x, -v.z, v.y);
    let (nt, np) = (600, 1200);
    let mut want = 0.0;
    for i in 0..nt {
        let th = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
        for j in 0..np {
            let ph = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
            let wi = glam::DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
            let f = m.eval(local(wi), local(wo_world), 550.0);
            want += f * th.cos() * th.sin() * luminance(px[texel(w, h, wi)]);
        }
    }
    want *= (PI / 2.0 / nt as f64) * (2.0 * PI / np as f64);
    let n = 60_000u64;
    let cie_y = render::spectrum::Cie::get().y_integral();
    let got: f64 = (0..n)
        .map(|s| sample_pixel(&scene, 1, 1, s)[1])
        .sum::<f64>()
        / (n as f64 * cie_y);
    eprintln!("env-lit plate: rendered {got:.5}, quadrature {want:.5}");
    assert!(
        (got / want - 1.0).abs() < 0.015,
        "rendered {got} vs quadrature {want}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every bundled scene loads, and one sample of each renders to a finite image.
#[test]
fn bundled_scenes_load_and_render() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files = vec![root.join("default.toml")];
    let mut samples: Vec<PathBuf> = std::fs::read_dir(root.join("samples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    samples.sort();
    // 5 samples × 3 views × 7 models.
    assert_eq!(samples.len(), 105);
    files.extend(samples);
    for f in &files {
        let scene = render::load_scene(f).unwrap_or_else(|e| panic!("{e}"));
        // One sample of a 4 × 4 pixel block at the image centre.
        let (cx, cy) = (scene.camera.width / 2, scene.camera.height / 2);
        for y in cy - 2..cy + 2 {
            for x in cx - 2..cx + 2 {
                let xyz = sample_pixel(&scene, x, y, 0);
                assert!(xyz.iter().all(|v| v.is_finite()), "{}", f.display());
            }
        }
    }
}

/// A material file as `lustre fit` writes it (provenance and fit diagnostics
/// included) is usable through `include`, for every model it can feed; keys
/// in the scene override the file's.
#[test]
fn fit_material_files_are_included() {
    let dir = temp_dir("include");
    let zeta: Vec<String> = (0..60)
        .map(|i| format!("{:.6e}", 1e-3 * 1.2f64.powi(i)))
        .collect();
    let p: Vec<String> = (0..60)
        .map(|i| {
            let z = 1e-3 * 1.2f64.powi(i);
            // KC, σ = 0.1 µm, Lc = 2 µm, γ = 2.5
            format!(
                "{:.6e}",
                0.01 * 4.0 * 1.5 / (2.0 * PI) * (1.0 + 4.0 * z * z).powf(-1.75)
            )
        })
        .collect();
    let fit = format!(
        r#"[provenance]
file = "scan.x3p"
sha256 = "00"
tool = "lustre fit"

[material]
metal = "brass"
model = "ghs"
sigma_um = 0.1
lc_um = 2.0
gamma = 2.5
alpha = 0.05
alpha_beckmann = 0.06

[fit]
sigma_um_err = 0.001

[two_scale.cutoff_4]
beta = 0.03
beta_source = "slopes"
sigma_um = 0.05
lc_um = 1.0
gamma = 2.2
cutoff_um = 4.0

[two_scale.cutoff_16]
beta = 0.05
sigma_um = 0.08
lc_um = 1.5
gamma = 2.4
cutoff_um = 16.0

[psd]
source = "welch"
zeta_rad_per_um = [{}]
p_um4 = [{}]
"#,
        zeta.join(", "),
        p.join(", ")
    );
    std::fs::write(dir.join("fit.toml"), fit).unwrap();
    let scene = |material: &str| {
        format!(
            r#"
[camera]
look_from = [0.0, 1.0, 1.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 20.0
resolution = [4, 4]

[film]
spp = 1

[materials.m]
include = "fit.toml"
{material}

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

[[lights]]
type = "point"
position = [0.0, 1.0, -1.0]
intensity = 1.0
"#
        )
    };
    let load = |m: &str| render::load_str(&dir.join("scene.toml"), &scene(m));
    let models = |s: &render::Scene| {
        s.materials
            .iter()
            .map(|m| m.model.name())
            .collect::<Vec<_>>()
    };
    assert_eq!(models(&load("").unwrap()), ["ghs"]);
    for m in ["ggx", "beckmann", "ghs_ssa", "measured_psd"] {
        assert_eq!(models(&load(&format!("model = \"{m}\"")).unwrap()), [m]);
    }
    assert_eq!(
        models(&load("model = \"two_scale\"\ncutoff = \"cutoff_16\"").unwrap()),
        ["two_scale"]
    );
    let e = load("model = \"two_scale\"").err().unwrap().to_string();
    assert!(e.contains("cutoff_16") && e.contains("cutoff_4"), "{e}");
    let e = load("model = \"two_scale\"\ncutoff = \"cutoff_9\"")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("no [two_scale.cutoff_9]"), "{e}");
    // Scene keys win: an invalid override is reported, proving it was used.
    let e = load("model = \"ggx\"\nalpha = 7.0")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("alpha"), "{e}");
    std::fs::write(dir.join("bad.toml"), "[material]\nsigma_um = \"x\"\n").unwrap();
    let e = render::load_str(
        &dir.join("scene.toml"),
        &scene("").replace("fit.toml", "bad.toml"),
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("bad.toml:2:") && e.contains("invalid type"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
