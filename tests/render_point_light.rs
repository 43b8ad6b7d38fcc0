//! A single-bounce plate under a point light against the value computed
//! directly from `brdf`: L = ∫ f(λ) cosθ_i I(λ)/d² ȳ(λ) dλ / ∫ȳ dλ.
//! The reference reads the CIE and D65 tables itself and integrates at 1 nm.

use brdf::statistics::KcPsd;
use brdf::wave::GhsSsa;
use brdf::wave::two_scale::{CoherentPart, TableResolution, TwoScale, TwoScaleParams};
use brdf::{Bxdf, Distribution, Fresnel, Ior, Metal, MicrofacetConductor};
use glam::DVec3;
use render::integrator::sample_pixel;

#[path = "support/scene_fixtures.rs"]
mod scene_fixtures;
#[path = "support/spectral_reference.rs"]
mod spectral_reference;
use scene_fixtures::{EYE_45DEG, plate_at_45deg};
use spectral_reference::Spectra;
use std::path::PathBuf;

const LIGHT: [f64; 3] = [0.3, 1.2, -0.8];
const INTENSITY: f64 = 5.0;

fn scene_text(material: &str, mode: &str) -> String {
    plate_at_45deg(
        &format!("wavelengths = \"{mode}\""),
        &format!("metal = \"stainless_steel\"\n{material}"),
        &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\n\
             intensity = {INTENSITY}\nspectrum = \"d65\"",
            LIGHT[0], LIGHT[1], LIGHT[2]
        ),
    )
}

/// Reference luminance at world point `p` seen from `eye`.
fn reference(model: &dyn Bxdf, p: DVec3, eye: DVec3) -> f64 {
    let sp = Spectra::load();
    let to_light = DVec3::from(LIGHT) - p;
    let d2 = to_light.length_squared();
    // Plate normal +y; local frame (x, z, y) → (t, b, n) matches the renderer's
    // tangent = rotated +x, bitangent = rotated +y (= −z world), normal = +y.
    let local = |w: DVec3| DVec3::new(w.x, -w.z, w.y);
    let wi = local(to_light.normalize());
    let wo = local((eye - p).normalize());
    let mut sum = 0.0;
    for (i, r) in sp.cie.iter().enumerate() {
        let l = r[0];
        let f = model.eval(wi, wo, l);
        sum += sp.trapezoid_weight(i) * f * wi.z * INTENSITY * sp.d65(l) / d2 * r[2];
    }
    sum / sp.y_int
}

fn check(model_name: &str, material: &str, model: &dyn Bxdf, mode: &str, samples: u64) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/point_light.toml");
    let scene = render::load_str(&path, &scene_text(material, mode)).unwrap();
    let eye = DVec3::from(EYE_45DEG);
    let cie_y = render::spectrum::Cie::get().y_integral();
    for &(px, py) in &[(8u32, 8u32), (2, 3), (13, 12)] {
        // A pixel spans 2 mm of the plate, over which f is linear to < 0.1 %: use its centre.
        let ray = scene.camera.ray(px as f64 + 0.5, py as f64 + 0.5);
        let t = -ray.o.y / ray.d.y;
        let p = ray.o + t * ray.d;
        let want = reference(model, p, eye);
        let got: f64 = (0..samples)
            .map(|s| sample_pixel(&scene, px, py, s)[1])
            .sum::<f64>()
            / (samples as f64 * cie_y);
        let rel = got / want - 1.0;
        eprintln!(
            "{model_name}/{mode} pixel ({px},{py}): rendered {got:.6}, brdf {want:.6}, rel {rel:+.4}"
        );
        assert!(
            rel.abs() < 0.01,
            "{model_name}/{mode} pixel ({px},{py}): {got} vs {want}"
        );
    }
}

fn steel() -> Fresnel {
    Fresnel::conductor(Ior::metal(Metal::StainlessSteel))
}

#[test]
fn ggx_plate_matches_brdf_single_wavelength() {
    let m = MicrofacetConductor::new(Distribution::ggx(0.25, 0.25).unwrap(), steel()).unwrap();
    check("ggx", "model = \"ggx\"\nalpha = 0.25", &m, "single", 80_000);
}

#[test]
fn beckmann_plate_matches_brdf_hero() {
    let m = MicrofacetConductor::new(Distribution::beckmann(0.25, 0.25).unwrap(), steel()).unwrap();
    check(
        "beckmann",
        "model = \"beckmann\"\nalpha = 0.25",
        &m,
        "hero",
        8_000,
    );
}

/// A KC surface whose scattered lobe spans the plate region the pixels see,
/// so the comparison is not dominated by the delta (which NEE never sees).
const KC: &str = "sigma_um = 0.05\nlc_um = 1.5\ngamma = 2.5";

#[test]
fn ghs_ssa_plate_matches_brdf_hero() {
    let m = GhsSsa::new(KcPsd::new(0.05, 1.5, 2.5).unwrap(), steel()).unwrap();
    check(
        "ghs_ssa",
        &format!("model = \"ghs_ssa\"\n{KC}"),
        &m,
        "hero",
        8_000,
    );
}

#[test]
fn two_scale_plate_matches_brdf_hero() {
    let m = TwoScale::new(TwoScaleParams {
        beta: 0.1,
        sigma_um: 0.05,
        lc_um: 1.5,
        gamma: 2.5,
        fresnel: steel(),
        coherent: CoherentPart::MacroNdf,
        resolution: TableResolution::default(),
    })
    .unwrap();
    check(
        "two_scale",
        &format!("model = \"two_scale\"\nbeta = 0.1\n{KC}"),
        &m,
        "hero",
        8_000,
    );
}
