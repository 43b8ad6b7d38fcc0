//! GGX ≡ KC (physics.md §7) against `data/reference/ghs_reference.json`
//! (`extras.ggx_kc`) and the error table of §7.
//!
//! Geometry of the error table: in the plane of incidence, θi = 30°,
//! i = (sin θi, 0, cos θi), o at polar angle θi + Δθo on the mirror side
//! (azimuth 180°), i.e. Δθo > 0 moves o away from the normal. The error does
//! not depend on λ (see `paper_relative_error`); λ = 0.55 µm is used for the
//! direct P_KC/D cross-check.

use brdf::frame::spherical;
use brdf::statistics::KcPsd;
use brdf::wave::ggx_kc::{
    ggx_d, ggx_d_via_kc, ggx_d_via_kc_paper, half_vector, kc_from_ggx, kc_from_ggx_slope_space,
    paper_relative_error, ssa_lobe_slope_space,
};
use serde_json::Value;
use std::f64::consts::PI;

fn reference() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/reference/ghs_reference.json"
    );
    let text = std::fs::read_to_string(path).expect("reference JSON in data/reference");
    serde_json::from_str(&text).expect("valid JSON")
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn in_plane(theta_i: f64, theta_o: f64) -> (glam::DVec3, glam::DVec3) {
    (spherical(theta_i, 0.0), spherical(theta_o, PI))
}

#[test]
fn d_equals_p_and_lobe_matches_reference() {
    let r = reference();
    let rows = r["extras"]["ggx_kc"].as_array().unwrap();
    assert!(rows.len() >= 3);
    let (mut worst_dp, mut worst_lobe, mut worst_ref) = (0.0f64, 0.0f64, 0.0f64);
    for row in rows {
        let alpha = row["alpha"].as_f64().unwrap();
        let lam = row["lam_um"].as_f64().unwrap();
        let ti = row["theta_i_deg"].as_f64().unwrap().to_radians();
        let k = 2.0 * PI / lam;
        // Mapping parameters against the reference.
        let paper = kc_from_ggx(alpha, k, ti.cos()).unwrap();
        assert!(rel(paper.lc_um, row["Lc_um_paper_identity"].as_f64().unwrap()) < 1e-13);
        assert!(
            rel(
                paper.sigma2,
                row["sigma2_formal_paper_identity"].as_f64().unwrap()
            ) < 1e-13
        );
        let slope = kc_from_ggx_slope_space(alpha, k, ti.cos()).unwrap();
        assert!(rel(slope.lc_um, row["Lc_um_slope_space"].as_f64().unwrap()) < 1e-13);

        // D ≡ P: the KC PSD of the wave-core module (independent code) at
        // ζ = 2k cosθd sinθh with cosθd = cosθi, the value of the identity.
        // σ_h² is a formal amplitude (µm⁻², far above any height variance
        // KcPsd accepts): the unit-σ PSD scaled by it.
        let psd = KcPsd::new(1.0, paper.lc_um, 3.0).unwrap();
        for p in row["D_vs_P"].as_array().unwrap() {
            let th = p["theta_h"].as_f64().unwrap();
            let h = spherical(th, 0.0);
            let d = ggx_d(alpha, h);
            let zeta = 2.0 * k * ti.cos() * th.sin();
            let pk = paper.sigma2 * psd.psd(zeta);
            worst_dp = worst_dp.max(rel(pk, d));
            worst_ref = worst_ref
                .max(rel(d, p["D_ggx"].as_f64().unwrap()))
                .max(rel(pk, p["P_kc_gamma3"].as_f64().unwrap()));
            assert!(rel(pk, d) < 1e-12, "α {alpha} θh {th}: P {pk} D {d}");
        }
        for p in row["lobe_vs_ggx_brdf_in_plane"].as_array().unwrap() {
            let dth = p["theta_o_minus_theta_i"].as_f64().unwrap();
            let (wi, wo) = in_plane(ti, ti + dth);
            let (h, _) = half_vector(wi, wo).unwrap();
            let f_ggx = ggx_d(alpha, h) / (4.0 * wi.z * wo.z);
            let lobe = ssa_lobe_slope_space(alpha, k, wi, wo).unwrap();
            let (rf, rl) = (
                p["f_ggx"].as_f64().unwrap(),
                p["k2_P_over_sigma2"].as_f64().unwrap(),
            );
            worst_lobe = worst_lobe.max(rel(f_ggx, rf)).max(rel(lobe, rl));
            assert!(
                rel(f_ggx, rf) < 1e-12 && rel(lobe, rl) < 1e-12,
                "α {alpha} Δ {dth}"
            );
            assert!((lobe / f_ggx - p["ratio"].as_f64().unwrap()).abs() < 1e-12);
            if dth == 0.0 {
                // The slope-space identity is exact at the mirror.
                assert!(rel(lobe, f_ggx) < 1e-13);
            }
        }
    }
    eprintln!(
        "GGX≡KC: max |P/D − 1| = {worst_dp:.2e}; vs reference: D,P {worst_ref:.2e}, lobe {worst_lobe:.2e}"
    );
}

#[test]
fn exact_identity_holds_everywhere_paper_version_only_at_the_mirror() {
    let k = 2.0 * PI / 0.55;
    let mut worst = 0.0f64;
    for &alpha in &[0.005, 0.05, 0.2, 0.6, 0.99] {
        for &ti_deg in &[0.0, 30.0, 60.0, 85.0] {
            let wi = spherical(f64::to_radians(ti_deg), 0.0);
            for j in 0..40 {
                let wo = spherical(0.039 * j as f64, 0.5 + 0.157 * j as f64);
                let (h, _) = half_vector(wi, wo).unwrap();
                let d = ggx_d(alpha, h);
                worst = worst.max(rel(ggx_d_via_kc(alpha, k, wi, wo).unwrap(), d));
            }
            // Paper's version at the mirror: exact.
            let s = brdf::frame::reflect_z(wi);
            let (h, _) = half_vector(wi, s).unwrap();
            let d = ggx_d(alpha, h);
            assert!(rel(ggx_d_via_kc_paper(alpha, k, wi, s).unwrap(), d) < 1e-12);
        }
    }
    eprintln!("exact half-vector identity: max |P/D − 1| = {worst:.2e}");
    assert!(worst < 1e-12);
}

#[test]
fn error_table_of_physics_section_7() {
    // Rows of physics.md §7, to two significant digits.
    let table: [(f64, [f64; 4]); 2] = [
        (0.05, [1.2e-7, 1.1e-4, 1.2e-2, 0.23]),
        (0.2, [6.9e-9, 6.9e-6, 8.7e-4, 0.049]),
    ];
    let dthetas = [1e-3, 1e-2, 5e-2, 0.2];
    let ti = 30f64.to_radians();
    let k = 2.0 * PI / 0.55;
    for (alpha, want) in table {
        for (j, &dth) in dthetas.iter().enumerate() {
            let (wi, wo) = in_plane(ti, ti + dth);
            let e = paper_relative_error(alpha, wi, wo).unwrap();
            // Independent path: the two KC evaluations divided by D.
            let (h, _) = half_vector(wi, wo).unwrap();
            let direct = ggx_d_via_kc_paper(alpha, k, wi, wo).unwrap() / ggx_d(alpha, h) - 1.0;
            assert!(
                (e - direct).abs() <= 1e-9 * direct.abs().max(1e-6),
                "{e} vs {direct}"
            );
            // Two significant digits: within half a unit of the second digit.
            let tol = 0.05 * 10f64.powf(want[j].log10().floor());
            eprintln!(
                "α = {alpha}, Δθo = {dth}: paper relative error {e:.3e} (table {})",
                want[j]
            );
            assert!(
                (e - want[j]).abs() <= tol,
                "α {alpha} Δθo {dth}: {e} vs {}",
                want[j]
            );
        }
    }
}
