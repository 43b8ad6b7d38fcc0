//! A checkerboard reflectance (`checker_reflectance`, `checker_tiles`): each
//! surface point takes the material of its square, on rectangles, disks,
//! spheres and meshes, following the texture coordinates Mitsuba gives
//! those shapes.

use render::{RenderOptions, load_str};
use std::path::Path;

/// A Lambertian square seen from straight above under a uniform white
/// environment (radiance 1, unit luminance): a pixel's Y is the ρ of the
/// surface it sees, whatever the noise of the estimator (one bounce).
fn floor_scene(material: &str) -> String {
    format!(
        r#"
[camera]
look_from = [0.0, 3.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_deg = 15.0
resolution = [40, 40]

[film]
spp = 16
seed = 5

[integrator]
max_depth = 1

[materials.floor]
{material}

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "floor"
transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}

[[lights]]
type = "environment"
radiance = 1.0
spectrum = "constant"
"#
    )
}

/// Y of every pixel, row by row from the top.
fn luminance(text: &str) -> Vec<f64> {
    let scene = load_str(Path::new("checker.toml"), text).unwrap();
    let mut film = scene.film().unwrap();
    let opts = RenderOptions {
        threads: Some(2),
        ..RenderOptions::default()
    };
    render::render_range(&scene, &mut film, 0..16, &opts).unwrap();
    (0..40 * 40).map(|i| film.xyz(i)[1]).collect()
}

/// The (u, v) a pixel centre's ray meets on the floor: camera 3 above the
/// origin, vertical fov 15°, image right = +x = u, image top = −z = v.
fn floor_uv(col: usize, row: usize) -> [f64; 2] {
    let t = (7.5f64).to_radians().tan();
    let x = (2.0 * (col as f64 + 0.5) / 40.0 - 1.0) * t;
    let y = (1.0 - 2.0 * (row as f64 + 0.5) / 40.0) * t;
    [3.0 * x + 0.5, 3.0 * y + 0.5]
}

/// Checks every pixel whose footprint lies inside one square of a
/// `tiles` checkerboard (ρ0 where ⌊u·t₀⌋ + ⌊v·t₁⌋ is even) against that ρ;
/// returns how many pixels were checked.
fn check_squares(y: &[f64], tiles: [f64; 2], rho: [f64; 2]) -> usize {
    // A pixel spans 3·2·tan 7.5°/40 ≈ 0.02 in u and v.
    let margin = 0.03;
    let mut checked = 0;
    for row in 0..40 {
        for col in 0..40 {
            let [u, v] = floor_uv(col, row);
            if !(margin..1.0 - margin).contains(&u) || !(margin..1.0 - margin).contains(&v) {
                continue;
            }
            let (su, sv) = (u * tiles[0], v * tiles[1]);
            let near_edge = |s: f64, t: f64| (s - s.round()).abs() < margin * t;
            if near_edge(su, tiles[0]) || near_edge(sv, tiles[1]) {
                continue;
            }
            let odd = (su.floor() + sv.floor()).rem_euclid(2.0) == 1.0;
            let want = if odd { rho[1] } else { rho[0] };
            let got = y[row * 40 + col];
            assert!(
                (got / want - 1.0).abs() < 0.15,
                "pixel ({col}, {row}) at (u, v) = ({u:.3}, {v:.3}): Y {got:.4}, square ρ {want}"
            );
            checked += 1;
        }
    }
    checked
}

/// Mean Y over 14 × 14 pixels well inside one quadrant of the image.
fn quadrant(y: &[f64], right: bool, bottom: bool) -> f64 {
    let (x0, y0) = (if right { 23 } else { 3 }, if bottom { 23 } else { 3 });
    let mut sum = 0.0;
    for r in y0..y0 + 14 {
        for c in x0..x0 + 14 {
            sum += y[r * 40 + c];
        }
    }
    sum / 196.0
}

#[test]
fn a_two_by_two_checkerboard_puts_rho0_where_both_indices_are_even_or_odd() {
    // Bottom-left square (i, j) = (0, 0) is even: ρ0; top-left (0, 1) is ρ1.
    let y = luminance(&floor_scene(
        "model = \"diffuse\"\nchecker_reflectance = [0.8, 0.1]",
    ));
    let n = check_squares(&y, [2.0, 2.0], [0.8, 0.1]);
    assert!(n > 1000, "only {n} pixels inside squares");
    let (tl, tr) = (quadrant(&y, false, false), quadrant(&y, true, false));
    let (bl, br) = (quadrant(&y, false, true), quadrant(&y, true, true));
    for (name, got, want) in [
        ("TL", tl, 0.1),
        ("TR", tr, 0.8),
        ("BL", bl, 0.8),
        ("BR", br, 0.1),
    ] {
        assert!(
            (got / want - 1.0).abs() < 0.02,
            "{name}: Y {got}, want {want}"
        );
    }
}

#[test]
fn tiles_set_the_squares_along_u_and_v() {
    // 5 squares along u, 3 along v.
    let y = luminance(&floor_scene(
        "model = \"diffuse\"\nchecker_reflectance = [0.05, 0.6]\nchecker_tiles = [5.0, 3.0]",
    ));
    let n = check_squares(&y, [5.0, 3.0], [0.05, 0.6]);
    assert!(n > 600, "only {n} pixels inside squares");
}

#[test]
fn a_plain_reflectance_is_one_colour() {
    // The control: without a checkerboard every pixel is ρ (so the checks
    // above see the texture, not the estimator's noise).
    let y = luminance(&floor_scene("model = \"diffuse\"\nreflectance = 0.8"));
    assert!(check_squares(&y, [2.0, 2.0], [0.8, 0.8]) > 1000);
    assert!(std::panic::catch_unwind(|| check_squares(&y, [2.0, 2.0], [0.8, 0.1])).is_err());
}

#[test]
fn roughplastic_takes_a_checkerboard_base() {
    // The coat reflects the same in both squares; the bases differ by ρ.
    let plastic = |rho: &str| {
        luminance(&floor_scene(&format!(
            "model = \"roughplastic\"\nalpha = 0.3\n{rho}"
        )))
    };
    let checker = plastic("checker_reflectance = [0.7, 0.2]");
    let (a, b) = (plastic("reflectance = 0.7"), plastic("reflectance = 0.2"));
    let mut checked = 0;
    for row in 0..40 {
        for col in 0..40 {
            let [u, v] = floor_uv(col, row);
            let inside = |s: f64| (0.05..0.45).contains(&s) || (0.55..0.95).contains(&s);
            if !(inside(u) && inside(v)) {
                continue;
            }
            let odd = ((2.0 * u).floor() + (2.0 * v).floor()).rem_euclid(2.0) == 1.0;
            let want = if odd {
                b[row * 40 + col]
            } else {
                a[row * 40 + col]
            };
            let got = checker[row * 40 + col];
            assert!(
                (got / want - 1.0).abs() < 1e-12,
                "pixel ({col}, {row}): {got} vs {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000);
}

#[test]
fn checkerboard_mistakes_are_refused_naming_the_key() {
    let refused = |material: &str, key: &str| {
        let e = load_str(Path::new("checker.toml"), &floor_scene(material))
            .err()
            .unwrap_or_else(|| panic!("accepted: {material}"))
            .to_string();
        assert!(e.contains(key), "{material}: {e}");
    };
    refused(
        "model = \"ggx\"\nalpha = 0.2\nmetal = \"cu\"\nchecker_reflectance = [0.8, 0.1]",
        "checker_reflectance",
    );
    refused(
        "model = \"diffuse\"\nreflectance = 0.5\nchecker_reflectance = [0.8, 0.1]",
        "not both",
    );
    refused(
        "model = \"diffuse\"\nchecker_reflectance = [0.8, 1.1]",
        "[0, 1]",
    );
    refused(
        "model = \"diffuse\"\nchecker_reflectance = [0.8, 0.1, 0.3]",
        "exactly two",
    );
    refused(
        "model = \"diffuse\"\nreflectance = 0.5\nchecker_tiles = [2.0, 2.0]",
        "checker_tiles",
    );
    refused(
        "model = \"diffuse\"\nchecker_reflectance = [0.8, 0.1]\nchecker_tiles = [0.0, 2.0]",
        "checker_tiles",
    );
    refused(
        "model = \"diffuse\"\nchecker_reflectance = [0.8, 0.1]\nchecker_tiles = [2.0, inf]",
        "checker_tiles",
    );
}
