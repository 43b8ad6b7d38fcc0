//! Films with spectral bands (`--spectral N`): the bands' values against
//! quadrature of the light's spectrum, their consistency with the film's Y,
//! exact merges and resumes, the film file round trip, and the EXR channel
//! names against the names pbrt-v4 gives (`tests/data/pbrt_band_names.txt`,
//! made by `pbrt_band_names.c` from pbrt's formula).

use render::film::{BandLayout, Film};
use render::{RenderOptions, load_str};
use std::path::Path;

/// A camera that sees only a D65 environment of unit luminance.
const SKY: &str = r#"
[camera]
look_from = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
fov_deg = 40.0
resolution = [24, 16]

[film]
spp = 64
seed = 5
spectral_bands = 16

[[shapes]]
type = "sphere"
center = [0.0, 0.0, 5.0]
radius = 0.1
material = "m"

[materials.m]
model = "ggx"
metal = "cu"
alpha = 0.2

[[lights]]
type = "environment"
radiance = 1.0
spectrum = "d65"
"#;

/// A copper plate under a small blackbody light and a dim environment.
const PLATE: &str = r#"
[camera]
look_from = [0.0, 0.5, 0.8]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [13, 9]

[film]
spp = 16
seed = 2
spectral_bands = 16

[integrator]
max_depth = 3

[materials.plate]
model = "ggx"
metal = "cu"
alpha = 0.15

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "plate"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "sphere"
center = [0.0, 0.5, -0.8]
radius = 0.1
radiance = 50.0
spectrum = "blackbody(3200)"

[[lights]]
type = "environment"
radiance = 0.05
"#;

fn repo_file(rel: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// (λ, values…) rows of a CSV with a header line.
fn csv(rel: &str) -> Vec<Vec<f64>> {
    repo_file(rel)
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
        .collect()
}

/// Column `c` of `rows` interpolated linearly at `l` (0 outside).
fn interp(rows: &[Vec<f64>], c: usize, l: f64) -> f64 {
    let i = rows.partition_point(|r| r[0] <= l);
    if i == 0 || i == rows.len() {
        return if i > 0 && rows[i - 1][0] == l {
            rows[i - 1][c]
        } else {
            0.0
        };
    }
    let (a, b) = (&rows[i - 1], &rows[i]);
    let t = (l - a[0]) / (b[0] - a[0]);
    a[c] + t * (b[c] - a[c])
}

/// ∫ f over [a, b] by the midpoint rule on 0.01 nm steps (the tables are
/// piecewise linear on 1 nm, so this is exact to ~10⁻⁸ relative).
fn integral(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let n = ((b - a) / 0.01).ceil() as usize;
    let h = (b - a) / n as f64;
    (0..n).map(|i| f(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
}

fn render(text: &str, bands: Option<usize>, range: std::ops::Range<u64>) -> Film {
    let mut scene = load_str(Path::new("t.toml"), text).unwrap();
    if let Some(n) = bands {
        scene.set_spectral_bands(n).unwrap();
    }
    let mut film = scene.film().unwrap();
    let opts = RenderOptions {
        threads: Some(2),
        ..RenderOptions::default()
    };
    render::render_range(&scene, &mut film, range, &opts).unwrap();
    film
}

/// Image means of Y and of every band.
fn image_means(film: &Film) -> (f64, Vec<f64>) {
    let n = film.bands();
    let pixels = (film.width() * film.height()) as usize;
    let y = (0..pixels).map(|i| film.xyz(i)[1]).sum::<f64>() / pixels as f64;
    let means = film.band_means();
    let bands = (0..n)
        .map(|b| means.iter().skip(b).step_by(n).sum::<f64>() / pixels as f64)
        .collect();
    (y, bands)
}

/// The bands of a camera that sees a D65 sky of unit luminance are the D65
/// spectrum's band means (scaled to unit luminance), and integrating them
/// against ȳ gives the film's Y up to the discretisation error of
/// piecewise-constant bands, computed here by quadrature.
#[test]
fn bands_are_the_mean_spectral_radiance_and_reproduce_y() {
    let cie = csv("data/spectra/cie1931_2deg_xyz.csv");
    let d65 = csv("data/spectra/illuminant_D65.csv");
    let ybar = |l: f64| interp(&cie, 2, l);
    let y_int = integral(360.0, 830.0, ybar);
    let lum = integral(360.0, 830.0, |l| interp(&d65, 1, l) * ybar(l)) / y_int;
    let s = |l: f64| interp(&d65, 1, l) / lum;
    for n in [16usize, 47, 256] {
        let film = render(SKY, Some(n), 0..64);
        assert_eq!(film.bands(), n);
        let layout = film.band_layout().unwrap();
        let (y, bands) = image_means(&film);
        assert!((y - 1.0).abs() < 1e-3, "n {n}: Y = {y}");
        let mut worst: f64 = 0.0;
        let (mut y_bands, mut y_exact_bands) = (0.0, 0.0);
        for (b, &got) in bands.iter().enumerate() {
            let (lo, hi) = layout.bounds_nm(b);
            let want = integral(lo, hi, s) / (hi - lo);
            worst = worst.max((got - want).abs() / want);
            let ybar_b = integral(lo, hi, ybar);
            y_bands += got * ybar_b / y_int;
            y_exact_bands += want * ybar_b / y_int;
        }
        // The expected Y of the bands differs from the film's by the
        // discretisation: Σ_b [(1/Δ)∫_b S · ∫_b ȳ − ∫_b S ȳ] / ∫ȳ.
        let discretisation = y_exact_bands - 1.0;
        eprintln!(
            "n {n}: worst band {worst:.2e}, Y {y:.6}, Y of bands {y_bands:.6}, \
             discretisation {discretisation:.2e}"
        );
        // Monte Carlo noise per band grows as the bands narrow (observed
        // 0.6 %, 1.3 % and 10 % at the worst band).
        let tol = match n {
            16 => 0.02,
            47 => 0.04,
            _ => 0.2,
        };
        assert!(worst < tol, "n {n}: a band is off by {worst}");
        // Observed within 3·10⁻⁵; the discretisation at 16 bands is 8·10⁻⁴.
        assert!(
            (y_bands - y - discretisation).abs() < 2e-4,
            "n {n}: Y of the bands {y_bands} vs film Y {y} + discretisation {discretisation}"
        );
    }
}

#[test]
fn shards_merge_and_resume_bit_for_bit_with_bands() {
    let whole = render(PLATE, None, 0..16);
    assert_eq!(whole.bands(), 16);
    assert!(whole.band_sums().iter().any(|&v| v != 0));
    let mut merged = render(PLATE, None, 8..16);
    merged.merge(&render(PLATE, None, 0..5)).unwrap();
    merged.merge(&render(PLATE, None, 5..8)).unwrap();
    assert_eq!(merged.to_bytes(), whole.to_bytes());

    // A checkpoint after 6 samples, through its file bytes, resumed to 16.
    let checkpoint = Film::from_bytes(&render(PLATE, None, 0..6).to_bytes()).unwrap();
    let scene = load_str(Path::new("t.toml"), PLATE).unwrap();
    let mut film = scene.film().unwrap();
    let todo = film.resume(checkpoint, 0..16).unwrap();
    assert_eq!(todo, 6..16);
    render::render_range(&scene, &mut film, todo, &RenderOptions::default()).unwrap();
    assert_eq!(film.to_bytes(), whole.to_bytes());

    // Other band counts are another render: refused, both counts named.
    let other = render(PLATE, Some(8), 16..20);
    let e = merged.clone().merge(&other).unwrap_err();
    assert!(e.contains("8 spectral bands differ from 16"), "{e}");
    let e = other.clone().merge(&merged).unwrap_err();
    assert!(e.contains("16 spectral bands differ from 8"), "{e}");
}

#[test]
fn film_files_with_bands_are_format_3_and_without_format_2() {
    let with = render(PLATE, None, 0..2);
    let bytes = with.to_bytes();
    assert_eq!(&bytes[..12], b"LUSTREFILM3\n");
    assert_eq!(Film::from_bytes(&bytes).unwrap(), with);
    let plain = PLATE.replace("spectral_bands = 16", "");
    let without = render(&plain, None, 0..2);
    assert_eq!(without.bands(), 0);
    assert_eq!(&without.to_bytes()[..12], b"LUSTREFILM2\n");
    // The band count is no part of the fingerprint (`--spectral N` equals
    // `spectral_bands = N`), but a film with bands samples λ at every
    // bounce: the XYZ sums differ, and the band check keeps them apart.
    assert_eq!(with.fingerprint(), without.fingerprint());
    assert_ne!(with.sums(), without.sums());
    let by_flag = render(&plain, Some(16), 0..2);
    assert_eq!(by_flag.to_bytes(), bytes);
}

#[test]
fn channel_names_are_pbrt_v4s() {
    let reference = repo_file("crates/render/tests/data/pbrt_band_names.txt");
    let mut checked = 0;
    for line in reference.lines() {
        let mut f = line.split(' ');
        let n: usize = f.next().unwrap().parse().unwrap();
        let i: usize = f.next().unwrap().parse().unwrap();
        let name = f.next().unwrap();
        assert_eq!(
            BandLayout::new(n).unwrap().channel_name(i),
            name,
            "{n} bands, band {i}"
        );
        checked += 1;
    }
    assert_eq!(checked, 782);
}

#[test]
fn exr_holds_rgb_and_the_bands_under_pbrts_names() {
    use exr::prelude::*;
    let film = render(PLATE, Some(7), 0..2);
    let layout = film.band_layout().unwrap();
    let dir = std::env::temp_dir().join(format!("lustre-spectral-exr-{}", std::process::id()));
    let path = dir.join("a.exr");
    let rgb = film.rgb();
    let bands: Vec<f32> = film.band_means().iter().map(|&v| v as f32).collect();
    render::output::write_exr_spectral(&path, 13, 9, &rgb, &layout, &bands).unwrap();
    // The bytes do not depend on the process (no hash-map order leaks in).
    let first = std::fs::read(&path).unwrap();
    for _ in 0..8 {
        render::output::write_exr_spectral(&path, 13, 9, &rgb, &layout, &bands).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), first);
    }
    let image = read_all_flat_layers_from_file(&path).unwrap();
    let layer = &image.layer_data[0];
    let mut names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    names.sort();
    let mut want: Vec<String> = ["R", "G", "B"].iter().map(|s| s.to_string()).collect();
    want.extend((0..7).map(|i| layout.channel_name(i)));
    want.sort();
    assert_eq!(names, want);
    let attribute = |k: &str| {
        let k = Text::from(k);
        (layer.attributes.other.get(&k)).or(image.attributes.other.get(&k))
    };
    let text = |k: &str| match attribute(k) {
        Some(AttributeValue::Text(t)) => t.to_string(),
        other => panic!("{k}: {other:?}"),
    };
    assert_eq!(text("spectralLayoutVersion"), "1.0");
    assert_eq!(text("emissiveUnits"), "W.m^-2.sr^-1");
    for c in &layer.channel_data.list {
        let FlatSamples::F32(v) = &c.sample_data else {
            panic!("{} is not f32", c.name)
        };
        let name = c.name.to_string();
        let (k, stride, src): (usize, usize, Vec<f32>) = match name.as_str() {
            "R" => (0, 1, rgb.iter().map(|p| p[0]).collect()),
            "G" => (0, 1, rgb.iter().map(|p| p[1]).collect()),
            "B" => (0, 1, rgb.iter().map(|p| p[2]).collect()),
            _ => {
                let b = (0..7).find(|&i| layout.channel_name(i) == name).unwrap();
                (b, 7, bands.clone())
            }
        };
        let expected: Vec<f32> = src.iter().skip(k).step_by(stride).copied().collect();
        assert_eq!(v, &expected, "channel {name}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
