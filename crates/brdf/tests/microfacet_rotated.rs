//! GGX and Beckmann with their anisotropic frame turned about the normal
//! (`brdf::microfacet::Rotated`, αx along the axis at φ from the tangent x
//! towards y, as `ghs_aniso`'s φ₀): a turned material equals the unturned one
//! at turned directions; by 90° it is the material with αx and αy swapped
//! (a closed-form check of the convention), by 180° the material itself;
//! reciprocal; chi-square of its sampling against its pdf.

use brdf::microfacet::Rotated;
use brdf::testing::{Chi2Config, chi2_test, sidak};
use brdf::{Bxdf, DVec3, Distribution, Fresnel, Ior, Metal, MicrofacetConductor};

fn dir(theta_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn turn(v: DVec3, deg: f64) -> DVec3 {
    let (s, c) = deg.to_radians().sin_cos();
    DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

fn conductor(beckmann: bool, ax: f64, ay: f64) -> MicrofacetConductor {
    let d = if beckmann {
        Distribution::beckmann(ax, ay)
    } else {
        Distribution::ggx(ax, ay)
    }
    .unwrap();
    MicrofacetConductor::new(d, Fresnel::conductor(Ior::metal(Metal::Cu))).unwrap()
}

fn pairs() -> Vec<(DVec3, DVec3)> {
    let mut v = Vec::new();
    for (ti, pi) in [(0.0, 0.0), (30.0, 20.0), (60.0, 200.0), (85.0, 110.0)] {
        for (to, po) in [(10.0, 0.0), (ti, pi + 180.0), (40.0, 75.0), (70.0, 300.0)] {
            v.push((dir(ti, pi), dir(to, po)));
        }
    }
    v
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn a_turned_material_is_the_material_at_turned_directions() {
    for beckmann in [false, true] {
        let base = conductor(beckmann, 0.05, 0.4);
        for angle in [0.0, 30.0, -75.0, 123.0] {
            let r = Rotated::new(base.clone(), f64::to_radians(angle)).unwrap();
            for (wi, wo) in pairs() {
                let (a, pa) = base.eval_pdf(wi, wo, 550.0);
                let (b, pb) = r.eval_pdf(turn(wi, angle), turn(wo, angle), 550.0);
                assert!(
                    close(a, b, 1e-12) && close(pa, pb, 1e-12),
                    "{a} {b} {pa} {pb}"
                );
                // Reciprocity.
                let c = r.eval(turn(wo, angle), turn(wi, angle), 550.0);
                assert!(close(b, c, 1e-12), "{b} vs {c}");
            }
        }
    }
}

#[test]
fn a_quarter_turn_swaps_the_axes_and_a_half_turn_is_the_identity() {
    for beckmann in [false, true] {
        let (ax, ay) = (0.08, 0.3);
        let quarter = Rotated::new(conductor(beckmann, ax, ay), f64::to_radians(90.0)).unwrap();
        let half = Rotated::new(conductor(beckmann, ax, ay), f64::to_radians(180.0)).unwrap();
        let (swapped, same) = (conductor(beckmann, ay, ax), conductor(beckmann, ax, ay));
        for (wi, wo) in pairs() {
            let (a, pa) = quarter.eval_pdf(wi, wo, 450.0);
            let (b, pb) = swapped.eval_pdf(wi, wo, 450.0);
            assert!(close(a, b, 1e-12) && close(pa, pb, 1e-12), "{a} {b}");
            let (c, pc) = half.eval_pdf(wi, wo, 450.0);
            let (d, pd) = same.eval_pdf(wi, wo, 450.0);
            assert!(close(c, d, 1e-12) && close(pc, pd, 1e-12), "{c} {d}");
        }
        // αx = 0.08 now lies along y and αy = 0.3 along x: the lobe is wide along x.
        let wi = dir(0.0, 0.0);
        let (along_x, along_y) = (dir(15.0, 0.0), dir(15.0, 90.0));
        assert!(quarter.eval(wi, along_x, 550.0) > 3.0 * quarter.eval(wi, along_y, 550.0));
    }
}

#[test]
fn sampling_matches_the_pdf() {
    let sets = [
        (false, 0.05, 0.4, 30.0, (0.0, 0.0)),
        (false, 0.3, 0.02, -60.0, (50.0, 40.0)),
        (true, 0.1, 0.5, 75.0, (70.0, 200.0)),
        (true, 0.6, 0.15, 10.0, (30.0, 300.0)),
    ];
    let alpha = sidak(0.01, sets.len());
    let mut failures = Vec::new();
    for (i, &(beckmann, ax, ay, angle, (ti, pi))) in sets.iter().enumerate() {
        let r = Rotated::new(conductor(beckmann, ax, ay), f64::to_radians(angle)).unwrap();
        let cfg = Chi2Config {
            samples: 120_000,
            pilot_samples: 30_000,
            seed: 900 + i as u64,
            ..Default::default()
        };
        let rep = chi2_test(&r, dir(ti, pi), 550.0, &cfg);
        println!(
            "set {i}: χ² {:.1} dof {} p {:.3}",
            rep.statistic, rep.dof, rep.p_value
        );
        if !rep.passes(alpha) {
            failures.push(format!("set {i}: {}", rep.check(alpha).unwrap_err()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
