//! The first vertex's delta lobe integrated over λ exactly
//! (`spectral_table.rs`, `integrator::exact_delta`): the tables against an
//! independent quadrature, the lobe's dependence on cosθi alone that they
//! rely on, and the rendered estimate against the sampled one it replaces.

use brdf::Bxdf;
use glam::DVec3;
use proptest::prelude::*;
use render::light::{Emission, LightKind};
use render::spectrum::{Cie, LAMBDA_MAX, LAMBDA_MIN};
use render::{Scene, integrator};
use std::path::PathBuf;

/// Every model with a delta lobe, in its variants that change the lobe's
/// weight (energy tables, a tabulated PSD, anisotropy).
fn materials() -> Vec<(&'static str, String)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let psd = root.join("scenes/psd/s138_kc.csv");
    let kc = "sigma_um = 0.138\nlc_um = 2.0\ngamma = 2.0\n";
    let aniso = "sigma_um = 0.2\nlx_um = 1.0\nly_um = 4.0\ngamma = 2.5\nangle_deg = 30.0\n";
    let map = psd_map_file();
    vec![
        ("ghs", format!("model = \"ghs\"\nmetal = \"cu\"\n{kc}")),
        (
            "ghs krywonos au",
            format!("model = \"ghs\"\nmetal = \"au\"\n{kc}energy = \"krywonos\"\n"),
        ),
        (
            "ghs_ssa sigma_rel",
            "model = \"ghs_ssa\"\nmetal = \"al\"\nsigma_um = 0.05\nlc_um = 0.5\ngamma = 3.0\nenergy = \"sigma_rel\"\n".to_string(),
        ),
        (
            "two_scale delta",
            format!(
                "model = \"two_scale\"\nmetal = \"cu\"\n{kc}beta = 0.05\ncoherent = \"delta\"\n"
            ),
        ),
        (
            "measured_psd",
            format!(
                "model = \"measured_psd\"\nmetal = \"ag\"\npsd_csv = \"{}\"\n",
                psd.display()
            ),
        ),
        (
            "rayleigh_rice",
            "model = \"rayleigh_rice\"\nmetal = \"cu\"\nsigma_um = 0.03\nlc_um = 2.0\ngamma = 2.0\n".to_string(),
        ),
        (
            "ghs_aniso",
            format!("model = \"ghs_aniso\"\nmetal = \"cu\"\n{aniso}"),
        ),
        (
            "ghs_ssa_aniso",
            format!("model = \"ghs_ssa_aniso\"\nmetal = \"cu\"\n{aniso}"),
        ),
        (
            "measured_psd_aniso",
            format!(
                "model = \"measured_psd_aniso\"\nmetal = \"au\"\npsd_csv = \"{}\"\nlx_um = 1.0\nly_um = 4.0\nangle_deg = 30.0\n",
                psd.display()
            ),
        ),
        (
            "measured_psd2d_ssa",
            format!(
                "model = \"measured_psd2d_ssa\"\ninclude = \"{}\"\nangle_deg = 20.0\n",
                map.display()
            ),
        ),
        (
            "measured_psd_ssa_aniso",
            format!(
                "model = \"measured_psd_ssa_aniso\"\nmetal = \"cu\"\npsd_csv = \"{}\"\nlx_um = 2.0\nly_um = 3.0\nangle_deg = -70.0\n",
                psd.display()
            ),
        ),
    ]
}

/// A material file with a `[psd.map]` (two crossing lays on a 13 × 6 grid of
/// the half plane), as `lustre fit` writes for a PSD that is not elliptical.
fn psd_map_file() -> PathBuf {
    let (mx, my, d) = (6usize, 5usize, 0.8);
    let mut p = Vec::new();
    for j in 0..=my {
        for i in 0..=2 * mx {
            let (x, y) = ((i as f64 - mx as f64) * d, j as f64 * d);
            let lay = |a: f64, b: f64| 1e-4 / (1.0 + a * a + 9.0 * b * b).powi(2);
            p.push(format!(
                "{:e}",
                lay(x, y) + lay(0.34 * x + 0.94 * y, 0.94 * x - 0.34 * y)
            ));
        }
    }
    let text = format!(
        "[material]\nmodel = \"ghs_ssa\"\nmetal = \"cu\"\nsigma_um = 0.05\nlc_um = 1.0\ngamma = 3.0\n\n\
         [psd]\nzeta_rad_per_um = [1.0, 2.0]\np_um4 = [1.0, 0.01]\n\n\
         [psd.map]\nusable = true\ntail_exponent = 4.0\nhalf_nx = {mx}\nhalf_ny = {my}\n\
         dzx_rad_per_um = {d}\ndzy_rad_per_um = {d}\np_um4 = [{}]\n",
        p.join(", ")
    );
    let path = std::env::temp_dir().join(format!(
        "lustre-delta-exact-map-{}.toml",
        std::process::id()
    ));
    std::fs::write(&path, text).unwrap();
    path
}

/// The 45° plate of `benches/peer/plate_scenes.toml` (3 cm sphere light at
/// 1 m in the mirror direction) at `res`², with `material` and `extra`
/// lines in `[integrator]`.
fn plate(material: &str, res: u32, spectrum: &str, extra: &str) -> Scene {
    let text = format!(
        "[film]\nspp = 1\n\
         [camera]\nlook_from = [0.0, 0.707107, 0.707107]\nlook_at = [0.0, 0.0, 0.0]\n\
         up = [0.0, 1.0, 0.0]\nfov_deg = 4.0\nresolution = [{res}, {res}]\n\
         [integrator]\nmax_depth = 1\n{extra}\n\
         [materials.plate]\n{material}\
         [[shapes]]\ntype = \"rectangle\"\nsize = [0.5, 0.5]\nmaterial = \"plate\"\n\
         transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}\n\
         [[lights]]\ntype = \"sphere\"\ncenter = [0.0, 0.707107, -0.707107]\nradius = 0.03\n\
         radiance = 150.0\nspectrum = \"{spectrum}\"\n"
    );
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    render::load_str(&root.join("plate.toml"), &text).expect("scene")
}

/// ∫ Le(λ) w(λ, cosθi) cmf(λ) dλ by the midpoint rule on 0.01 nm steps, w
/// the lobe's weight at azimuth `phi`: shares nothing with the tables'
/// knot-aware Gauss–Legendre grid in cosθi.
fn brute(scene: &Scene, cos: f64, phi: f64) -> [f64; 3] {
    let LightKind::Sphere { spectrum, .. } = &scene.lights.lights[0] else {
        panic!("a sphere light");
    };
    let bxdf = &scene.materials[0].bxdf;
    let sin = (1.0 - cos * cos).sqrt();
    let wi = DVec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    let h = 0.01;
    let steps = ((LAMBDA_MAX - LAMBDA_MIN) / h).round() as usize;
    let cie = Cie::get();
    let mut out = [0.0; 3];
    for i in 0..steps {
        let l = LAMBDA_MIN + (i as f64 + 0.5) * h;
        let v = bxdf.specular(wi, l).weight * spectrum.eval(l) * h;
        let c = cie.xyz(l);
        for k in 0..3 {
            out[k] += v * c[k];
        }
    }
    out
}

fn table_value(scene: &Scene, cos: f64) -> [f64; 3] {
    let tables = scene.spectral.as_ref().expect("tables");
    let id = tables.delta(0).expect("a delta table");
    let LightKind::Sphere { spectrum, .. } = &scene.lights.lights[0] else {
        panic!("a sphere light");
    };
    tables.reflected(id, cos * cos, 1.0, &Emission::Spectrum(spectrum, 1.0, 0))
}

/// Each model's table at cosθi from near grazing to normal (and azimuths
/// the table never sees) against the independent quadrature, for a flat
/// spectrum, a 2700 K blackbody and D65's 5 nm table: within 10⁻⁵ of the
/// channel's largest value (the table is refined to 10⁻⁶; the rest is the
/// midpoint rule's own error).
#[test]
fn delta_tables_are_the_integral_by_an_independent_quadrature() {
    let coss = [0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0];
    for (name, m) in materials() {
        for spectrum in ["constant", "blackbody(2700)", "d65"] {
            let scene = plate(&m, 4, spectrum, "");
            let want: Vec<[f64; 3]> = coss
                .iter()
                .enumerate()
                .map(|(i, &c)| brute(&scene, c, 0.7 * i as f64))
                .collect();
            let mut scale = [0.0f64; 3];
            for w in &want {
                for c in 0..3 {
                    scale[c] = scale[c].max(w[c].abs());
                }
            }
            assert!(scale[1] > 0.0, "{name}: no delta lobe");
            for (&cos, w) in coss.iter().zip(&want) {
                let got = table_value(&scene, cos);
                for c in 0..3 {
                    assert!(
                        (got[c] - w[c]).abs() <= 1e-5 * scale[c],
                        "{name}, {spectrum}, cosθi {cos}, channel {c}: table {} vs quadrature {}",
                        got[c],
                        w[c]
                    );
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// The tables take the lobe's weight at azimuth 0 for every azimuth:
    /// each model's weight depends on wi only through cosθi, at any λ.
    #[test]
    fn delta_weight_depends_on_cos_theta_only(
        cos in 1e-3f64..=1.0,
        phi in 0.0f64..std::f64::consts::TAU,
        lambda in LAMBDA_MIN..=LAMBDA_MAX,
    ) {
        for (name, m) in materials_built() {
            let sin = (1.0 - cos * cos).sqrt();
            let at = |p: f64| m.specular(DVec3::new(sin * p.cos(), sin * p.sin(), cos), lambda).weight;
            let (a, b) = (at(0.0), at(phi));
            prop_assert!((a - b).abs() <= 1e-12 * a.abs().max(1e-300), "{name}: {a} vs {b}");
        }
    }
}

fn materials_built() -> &'static [(&'static str, Scene)] {
    static BUILT: std::sync::OnceLock<Vec<(&'static str, Scene)>> = std::sync::OnceLock::new();
    BUILT.get_or_init(|| {
        materials()
            .into_iter()
            .map(|(n, m)| (n, plate(&m, 4, "constant", "")))
            .collect()
    })
}

trait FirstBxdf {
    fn specular(&self, wi: DVec3, lambda: f64) -> brdf::Specular;
}

impl FirstBxdf for Scene {
    fn specular(&self, wi: DVec3, lambda: f64) -> brdf::Specular {
        self.materials[0].bxdf.specular(wi, lambda)
    }
}

/// Sample by sample, the exact delta lobe against the sampled wavelengths'
/// estimate it replaces (`spectral_integration = "sampled"`; the same
/// draws otherwise, so the paired difference is the sampled estimate's
/// noise alone) over pixels inside the light's mirror image: their mean
/// difference within 4 standard errors of zero, and that standard error
/// small against the delta lobe's own contribution there (so a table a
/// few per cent off fails).
#[test]
fn the_exact_delta_lobe_is_the_sampled_estimate_in_expectation() {
    let spp: u64 = std::env::var("DELTA_SPP").map_or(1024, |s| s.parse().unwrap());
    for (name, m) in materials() {
        // 0.25° per pixel: the light's mirror image (0.86° in radius, seen
        // 2 m away) covers the central 4 × 4 pixels whole.
        let auto = plate(&m, 16, "blackbody(3200)", "");
        let sampled = plate(
            &m,
            16,
            "blackbody(3200)",
            "spectral_integration = \"sampled\"",
        );
        // The delta lobe's Y there (cosθi within 0.5° of 45°).
        let delta_y = table_value(&auto, std::f64::consts::FRAC_1_SQRT_2)[1];
        let (mut sum, mut sum2, mut total, mut n) = (0.0, 0.0, 0.0, 0.0);
        for y in 6..10 {
            for x in 6..10 {
                for s in 0..spp {
                    let a = integrator::sample_pixel(&auto, x, y, s)[1];
                    let b = integrator::sample_pixel(&sampled, x, y, s)[1];
                    let d = a - b;
                    sum += d;
                    sum2 += d * d;
                    total += a;
                    n += 1.0;
                }
            }
        }
        let mean = sum / n;
        let se = ((sum2 / n - mean * mean) / (n - 1.0)).sqrt();
        let mean_y = total / n;
        println!(
            "{name}: paired mean {mean:.3e} ± {se:.3e}, delta Y {delta_y:.3e}, pixel Y {mean_y:.3e}"
        );
        assert!(
            mean.abs() <= 4.0 * se,
            "{name}: mean paired difference {mean} (standard error {se}, delta lobe's Y {delta_y})"
        );
        assert!(
            se <= 0.01 * delta_y && delta_y < mean_y,
            "{name}: standard error {se}, delta lobe's Y {delta_y}, pixel Y {mean_y}"
        );
    }
}

/// `delta_pixel_samples = 8` against the default 1, camera sample by camera
/// sample with the same draws (so the paired difference is the sub-pixel
/// points' estimate of the delta term minus the camera ray's own): on a
/// GHS plate whose coherent lobe is about half its reflectance (σ 0.05 µm)
/// and whose light's mirror image has its edge inside the 16² image,
/// the image's mean Y agrees within 4.5 standard errors, that standard
/// error below 2 % of the delta lobe's share of the image (so counting it
/// twice, or the points weighted 1/(k − 1), fails), and the per-pixel
/// sample variance summed over the image falls below half (the edge's
/// hit-or-miss noise is most of it).
#[test]
fn the_delta_lobe_over_the_pixel_is_unbiased_and_less_noisy() {
    let m = "model = \"ghs\"\nmetal = \"cu\"\nsigma_um = 0.05\nlc_um = 2.0\ngamma = 2.0\n";
    let common = "sampler = \"independent\"";
    let one = plate(m, 16, "constant", common);
    let eight = plate(
        m,
        16,
        "constant",
        &format!("{common}\ndelta_pixel_samples = 8"),
    );
    let spp = 64u64;
    let (mut d_sum, mut d_sq, mut mean_one, mut n) = (0.0, 0.0, 0.0, 0.0);
    let (mut var_one, mut var_eight) = (0.0, 0.0);
    for y in 0..16 {
        for x in 0..16 {
            let mut s1 = [0.0; 2];
            let mut s8 = [0.0; 2];
            for s in 0..spp {
                let a = integrator::sample_pixel(&one, x, y, s)[1];
                let b = integrator::sample_pixel(&eight, x, y, s)[1];
                d_sum += b - a;
                d_sq += (b - a) * (b - a);
                mean_one += a;
                n += 1.0;
                s1 = [s1[0] + a, s1[1] + a * a];
                s8 = [s8[0] + b, s8[1] + b * b];
            }
            let k = spp as f64;
            var_one += s1[1] / k - (s1[0] / k).powi(2);
            var_eight += s8[1] / k - (s8[0] / k).powi(2);
        }
    }
    let d = d_sum / n;
    let se = ((d_sq / n - d * d) / n).sqrt();
    let delta_y = table_value(&one, std::f64::consts::FRAC_1_SQRT_2)[1];
    // The mirror image: 0.86° in radius at 0.25° per pixel, 37 of 256 pixels.
    let delta_share = delta_y * std::f64::consts::PI * 3.44f64.powi(2) / 256.0;
    eprintln!(
        "mean Y {:.5}, paired difference {d:.3e} ± {se:.1e}, delta share ≈ {delta_share:.3e}, \
         summed variance {var_one:.4e} -> {var_eight:.4e}",
        mean_one / n
    );
    assert!(d.abs() < 4.5 * se, "{d} ± {se}");
    assert!(se < 0.02 * delta_share, "{se} against {delta_share}");
    assert!(var_eight < 0.5 * var_one, "{var_eight} against {var_one}");
}
