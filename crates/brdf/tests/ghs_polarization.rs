//! GHS with the Rayleigh–Rice polarisation factor (`polarization_factor =
//! Q`, physics.md §13.2):
//!
//! * the scalar SSA relates to Rayleigh–Rice exactly by three factors,
//!   lustre/RR = [(1 − e^{−g})/g]·[(cosθi + cosθo)²/(4 cosθi cosθo)]·[R(θd)/Q];
//! * with Q the SSA and the full GHS tend to Rayleigh–Rice as g → 0, for every
//!   polarisation, metal and geometry tried (the deviation shrinks with g);
//! * the default (`R`) is the scalar model, bit for bit;
//! * reciprocity (unpolarised), and the energy options with Q: with the
//!   perfect conductor (`Fresnel::One`) `krywonos` gives albedo 1.

use std::f64::consts::PI;

use brdf::statistics::KcPsd;
use brdf::testing::albedo_quadrature;
use brdf::wave::{
    Energy, GhsFull, GhsOptions, GhsSsa, Polarization, PolarizationFactor, RayleighRice,
};
use brdf::{Bxdf, DVec3, Fresnel, Ior, Metal};

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// In-plane forward and back, out of plane, grazing.
fn geometries() -> Vec<(DVec3, DVec3)> {
    let mut v = Vec::new();
    for ti in [0.0, 30.0, 60.0, 80.0, 89.0] {
        for (to, po) in [
            (0.0, 0.0),
            (ti, 180.0),
            (10.0, 180.0),
            (45.0, 0.0),
            (70.0, 180.0),
            (85.0, 0.0),
            (89.0, 180.0),
            (40.0, 90.0),
            (60.0, 135.0),
        ] {
            v.push((dir(ti, 0.0), dir(to, po)));
        }
    }
    v
}

fn q_options(pol: Polarization) -> GhsOptions {
    GhsOptions {
        polarization: pol,
        polarization_factor: PolarizationFactor::Q,
        ..Default::default()
    }
}

const POLS: [Polarization; 3] = [Polarization::Unpolarized, Polarization::S, Polarization::P];

fn metals() -> [Fresnel; 3] {
    [
        Fresnel::conductor(Ior::metal(Metal::Au)),
        Fresnel::conductor(Ior::metal(Metal::Al)),
        Fresnel::One,
    ]
}

#[test]
fn scalar_ssa_over_rayleigh_rice_is_the_three_factors() {
    let psd = KcPsd::new(0.001, 2.0, 3.0).unwrap();
    let lam = 550.0;
    let k = 2000.0 * PI / lam;
    for f in metals().into_iter().take(2) {
        let ssa = GhsSsa::new(psd, f.clone()).unwrap();
        let rr = RayleighRice::new(psd, f.clone()).unwrap();
        let mut worst = 0.0f64;
        for (wi, wo) in geometries() {
            let (ci, co) = (wi.z, wo.z);
            let g = (k * 0.001 * (ci + co)).powi(2);
            let cd = (0.5 * (1.0 + wi.dot(wo))).sqrt();
            // Q from Rayleigh–Rice itself: f_RR = 4k⁴ cosθi cosθo Q P.
            let zeta = k * ((wi.x + wo.x).powi(2) + (wi.y + wo.y).powi(2)).sqrt();
            let q = rr.eval(wi, wo, lam) / (4.0 * k.powi(4) * ci * co * psd.psd(zeta));
            let want = (-(-g).exp_m1() / g) * (ci + co).powi(2) / (4.0 * ci * co)
                * f.reflectance(cd, lam)
                / q;
            let got = ssa.eval(wi, wo, lam) / rr.eval(wi, wo, lam);
            worst = worst.max((got / want - 1.0).abs());
        }
        assert!(worst < 1e-12, "{f:?}: {worst:e}");
    }
    // Grazing geometries: backscatter θi = θo = 89° (φo = 0) and
    // forward scatter 89° → 60°, at 550 nm.
    let ratio = |f: &Fresnel, wi, wo| {
        GhsSsa::new(psd, f.clone()).unwrap().eval(wi, wo, lam)
            / RayleighRice::new(psd, f.clone()).unwrap().eval(wi, wo, lam)
    };
    let back = (dir(89.0, 0.0), dir(89.0, 0.0));
    let au = ratio(&metals()[0], back.0, back.1);
    let al = ratio(&metals()[1], back.0, back.1);
    println!("grazing backscatter: scalar SSA / RR = {au:.4} (Au), {al:.5} (Al)");
    assert!(au < 0.02 && al < 0.005, "{au} {al}");
}

#[test]
fn with_q_the_ghs_tends_to_rayleigh_rice_as_g_vanishes() {
    let lam = 480.0;
    for f in metals() {
        for pol in POLS {
            let mut dev = Vec::new();
            for sigma in [1e-3, 1e-4] {
                let psd = KcPsd::new(sigma, 3.0, 2.5).unwrap();
                let rr = RayleighRice::with_polarization(psd, f.clone(), pol).unwrap();
                let ssa = GhsSsa::with_options(psd, f.clone(), q_options(pol)).unwrap();
                let full = GhsFull::with_options(psd, f.clone(), q_options(pol)).unwrap();
                let mut worst = 0.0f64;
                for (wi, wo) in geometries() {
                    let want = rr.eval(wi, wo, lam);
                    for m in [&ssa as &dyn Bxdf, &full] {
                        let got = m.eval(wi, wo, lam);
                        worst = worst.max((got / want - 1.0).abs());
                    }
                    // The specular lobes are the same.
                    let (a, b) = (ssa.specular(wi, lam), rr.specular(wi, lam));
                    assert!((a.weight - b.weight).abs() <= 1e-15, "{a:?} {b:?}");
                }
                dev.push(worst);
            }
            // g ≤ (2kσ)² = 6.9e−4 at σ = 1 nm: the SSA's (1 − e^{−g})/g and
            // the full GHS's table deviate by O(g); ten times smaller σ, a
            // hundred times smaller g.
            println!(
                "{f:?} {pol:?}: max |GHS_Q/RR − 1| = {:.1e} (σ 1 nm), {:.1e} (0.1 nm)",
                dev[0], dev[1]
            );
            assert!(dev[0] < 1e-3 && dev[1] < 1e-4, "{f:?} {pol:?}: {dev:?}");
            assert!(dev[1] < 0.2 * dev[0], "{f:?} {pol:?}: {dev:?}");
        }
    }
}

#[test]
fn the_default_factor_is_the_scalar_model() {
    let psd = KcPsd::new(0.05, 2.0, 2.5).unwrap();
    let f = Fresnel::conductor(Ior::metal(Metal::Cu));
    let a = GhsSsa::new(psd, f.clone()).unwrap();
    let r = GhsOptions {
        polarization_factor: PolarizationFactor::R,
        polarization: Polarization::Unpolarized,
        ..Default::default()
    };
    assert_eq!(r, GhsOptions::default());
    let b = GhsSsa::with_options(psd, f, r).unwrap();
    for (wi, wo) in geometries() {
        assert_eq!(
            a.eval(wi, wo, 550.0).to_bits(),
            b.eval(wi, wo, 550.0).to_bits()
        );
    }
}

#[test]
fn q_factor_is_reciprocal_and_scales_the_lobe_alone() {
    let psd = KcPsd::new(0.1, 2.0, 2.5).unwrap();
    let lam = 620.0;
    for f in metals() {
        let one = GhsFull::new(psd, Fresnel::One).unwrap();
        let q =
            GhsFull::with_options(psd, f.clone(), q_options(Polarization::Unpolarized)).unwrap();
        let rr = RayleighRice::new(psd, f.clone()).unwrap();
        let k = 2000.0 * PI / lam;
        for (wi, wo) in geometries() {
            let (a, b) = (q.eval(wi, wo, lam), q.eval(wo, wi, lam));
            assert!((a - b).abs() <= 1e-12 * a, "{f:?}: {a} vs {b}");
            // f_Q = f_scalar(R ≡ 1) · Q · 4 cosθi cosθo/(cosθi + cosθo)².
            let zeta = k * ((wi.x + wo.x).powi(2) + (wi.y + wo.y).powi(2)).sqrt();
            let (ci, co) = (wi.z, wo.z);
            let qq = rr.eval(wi, wo, lam) / (4.0 * k.powi(4) * ci * co * psd.psd(zeta));
            let want = one.eval(wi, wo, lam) * qq * 4.0 * ci * co / (ci + co).powi(2);
            assert!((a - want).abs() <= 1e-12 * want, "{f:?}: {a} vs {want}");
        }
    }
}

#[test]
fn krywonos_with_q_on_the_perfect_conductor_conserves_energy() {
    // Fresnel::One is the perfect conductor under Q; the tables integrate
    // its Q, so A_s + scattered = 1 as for the scalar model.
    for (s, lc, g) in [(0.05, 2.0, 2.5), (0.3, 5.0, 3.0)] {
        let psd = KcPsd::new(s, lc, g).unwrap();
        let opts = GhsOptions {
            energy: Energy::Krywonos,
            ..q_options(Polarization::P)
        };
        for m in [
            Box::new(GhsSsa::with_options(psd, Fresnel::One, opts).unwrap()) as Box<dyn Bxdf>,
            Box::new(GhsFull::with_options(psd, Fresnel::One, opts).unwrap()),
        ] {
            for th in [0.0, 45.0, 80.0, 89.0] {
                let a = albedo_quadrature(&*m, dir(th, 0.0), 500.0, 1e-6).value;
                assert!((a - 1.0).abs() < 1e-3, "σ {s} Lc {lc} θi {th}: {a}");
            }
        }
    }
}
