//! Full GHS at steep spectra (γ 8–100), where the tail of S̃ falls below
//! the transform's round-off long before the hemisphere ends.
//!
//! * the table against the independent direct Hankel quadrature
//!   ([`s_tilde_direct`]) near the mirror and in the tails, wherever the
//!   quadrature is above its own round-off floor;
//! * the deep tail at small g against the closed form e^{−g}·g·p₁(u)
//!   (exact to O(g²), which no transform resolves there);
//! * γ = 12, 31° off the mirror, where a table whose steps are not bounded
//!   interpolates to 2.8e17 sr⁻¹.

use std::f64::consts::PI;

use brdf::numerics::hankel::{lobe_width, s_tilde_direct};
use brdf::statistics::kc::KcPsd;
use brdf::statistics::matern::Matern;
use brdf::wave::ghs::hemisphere_u_max;
use brdf::wave::ghs_table::{GhsTable, TableResolution};
use brdf::wave::{GhsFull, GhsOptions};
use brdf::{Bxdf, Fresnel, frame};

const GAMMAS: [f64; 8] = [8.0, 10.0, 12.0, 16.0, 25.0, 40.0, 70.0, 100.0];

/// Unit KC PSD in u: p₁(u) = ν/(π(1 + u²)^{ν+1}).
fn p1(nu: f64, u: f64) -> f64 {
    nu / (PI * (1.0 + u * u).powf(nu + 1.0))
}

#[test]
fn steep_tables_match_the_direct_transform() {
    let res = TableResolution::default();
    let lc = 30.0;
    // Worst relative error in bands of S̃/peak: ≥1e−6, 1e−9…1e−6, 1e−12…1e−9.
    let mut worst = [0.0f64; 3];
    let mut checked = [0usize; 3];
    let mut below_floor = 0usize;
    for gamma in GAMMAS {
        let m = Matern::new((gamma - 1.0) / 2.0);
        let t = GhsTable::build(&m, hemisphere_u_max(lc), res).unwrap();
        for g in [1e-3, 0.03, 0.3, 1.0, 3.0, 10.0, 100.0, 1e3, 1e4] {
            let w = lobe_width(&m, g);
            let peak = s_tilde_direct(&m, 0.0, g);
            for wu in [
                0.0, 0.2, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.5, 7.0, 10.0, 15.0, 30.0, 60.0,
            ] {
                let u = wu * w;
                if u > 600.0 {
                    continue; // the direct quadrature needs O(u) panels
                }
                let want = s_tilde_direct(&m, u, g);
                let got = t.s_tilde(u, g).unwrap();
                assert!(
                    got.is_finite() && got >= 0.0 && got <= 1.0001 * peak,
                    "γ={gamma} g={g} u={u}: {got} (peak {peak})"
                );
                let rel = want / peak;
                let band = if rel >= 1e-6 {
                    0
                } else if rel >= 1e-9 {
                    1
                } else if rel >= 1e-12 {
                    2
                } else {
                    // The quadrature is at its round-off floor (~1e−14 of
                    // the peak): only bound the table there.
                    assert!(
                        got <= 1e-11 * peak,
                        "γ={gamma} g={g} u={u}: {got:e} where S̃ < 1e−12 of the peak {peak:e}"
                    );
                    below_floor += 1;
                    continue;
                };
                let e = (got / want - 1.0).abs();
                if e > worst[band] {
                    println!(
                        "γ={gamma} g={g} w={wu}: table {got:e} direct {want:e} ({rel:.1e} of peak): {e:.2e}"
                    );
                }
                worst[band] = worst[band].max(e);
                checked[band] += 1;
            }
        }
    }
    println!(
        "points: {checked:?} (+{below_floor} below the quadrature's floor); worst relative error \
         ≥1e−6: {:.2e}, 1e−9…1e−6: {:.2e}, 1e−12…1e−9: {:.2e}",
        worst[0], worst[1], worst[2]
    );
    assert!(checked.iter().sum::<usize>() >= 200);
    assert!(worst[0] < 1e-3, "{worst:?}");
    assert!(worst[1] < 1e-2, "{worst:?}");
    assert!(worst[2] < 0.3, "{worst:?}");
}

#[test]
fn deep_tail_at_small_g_is_the_first_order_term() {
    // S̃ = e^{−g}(g p₁ + g²/2 p₂ + …) with p₂ ≈ 2p₁ in the tail: to O(g),
    // S̃/(e^{−g} g p₁) − 1 ≈ g. The transform's round-off is ~1e−15 of the
    // peak; these values reach 1e−170 of it.
    let res = TableResolution::default();
    let lc = 30.0;
    let u_max = hemisphere_u_max(lc);
    let mut worst: f64 = 0.0;
    for gamma in GAMMAS {
        let nu = (gamma - 1.0) / 2.0;
        let m = Matern::new(nu);
        let t = GhsTable::build(&m, u_max, res).unwrap();
        for g in [1.2e-4f64, 1e-3, 4e-3] {
            let mut u = 3.0;
            while u < u_max {
                let want = (-g).exp() * g * p1(nu, u);
                if want < 1e-280 {
                    break; // relative accuracy ends in the subnormals
                }
                let got = t.s_tilde(u, g).unwrap();
                let e = (got / want - 1.0).abs();
                worst = worst.max(e);
                assert!(
                    e < 4.0 * g + 2e-3,
                    "γ={gamma} g={g} u={u}: table {got:e}, first order {want:e}"
                );
                u *= 1.7;
            }
        }
    }
    println!("worst relative deviation from e^(−g) g p₁ in the deep tail: {worst:.2e}");
}

#[test]
fn steep_tail_off_the_mirror_is_the_transform() {
    // {"model":"ghs","fresnel":"none","sigma_um":0.01,"lc_um":1.667,
    //  "gamma":12,"lambda_nm":550,"theta_i_deg":30,"theta_o_deg":61}
    let psd = KcPsd::new(0.01, 1.667, 12.0).unwrap();
    let model = GhsFull::with_options(psd, Fresnel::One, GhsOptions::default()).unwrap();
    let wi = frame::spherical(30f64.to_radians(), 0.0);
    let wo = frame::spherical(61f64.to_radians(), 0.0);
    let lam = 550.0;
    let f = model.eval(wi, wo, lam);
    let k = 2000.0 * PI / lam;
    let g = (k * 0.01 * (wi.z + wo.z)).powi(2);
    let u = k * 1.667 * (wi.x + wo.x).hypot(wi.y + wo.y);
    let kl2 = (k * 1.667).powi(2);
    let peak = kl2 * s_tilde_direct(&Matern::new(5.5), 0.0, g);
    // 1e−18 of the peak: below the quadrature's round-off, where S̃ is
    // e^{−g}(g p₁ + O(g²)) with the O(g²) part ≈ g²p₁ (p₂ ≈ 2p₁ in the tail).
    let first = kl2 * (-g).exp() * g * p1(5.5, u);
    let bound = k * k * (-(-g).exp_m1()) * 1.667f64.powi(2) * 11.0 / (2.0 * PI);
    println!("f = {f:e} (peak {peak:e}), first order {first:e}, bound {bound:e}");
    assert!(f <= bound, "{f} > {bound}");
    assert!((f / first - 1.0).abs() < 3.0 * g, "{f} vs {first}");
}

#[test]
fn heavy_tails_match_the_direct_transform() {
    // γ → 1.05: the orders sit 2^{20} apart in scale, the lobe is up to
    // 1e33 wide and in the hemisphere only the low orders remain, at
    // e^{−g} of the bound. The contract: 1e−3 relative, or 1e−12 of the
    // bound (1 − e^{−g}) p(0) where S̃ is below what that resolves.
    let res = TableResolution::default();
    let lc = 5.0;
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for gamma in [1.05, 1.08, 1.15, 1.3] {
        let nu = (gamma - 1.0) / 2.0;
        let m = Matern::new(nu);
        let t = GhsTable::build(&m, hemisphere_u_max(lc), res).unwrap();
        for g in [0.01f64, 0.5, 3.0, 10.0, 30.0, 37.5, 45.0, 200.0, 3e3] {
            let bound = -(-g).exp_m1() * p1(nu, 0.0);
            for u in [0.0, 1e-3, 0.1, 1.0, 5.0, 30.0, 150.0] {
                let want = s_tilde_direct(&m, u, g);
                let got = t.s_tilde(u, g).unwrap();
                let e = (got - want).abs() / (want.abs() + 1e-9 * bound);
                assert!(
                    (got - want).abs() <= 1e-3 * want.abs() + 1e-12 * bound,
                    "γ={gamma} g={g} u={u}: table {got:e}, direct {want:e} (bound {bound:e})"
                );
                worst = worst.max(e);
                checked += 1;
            }
        }
    }
    println!("{checked} points, worst |Δ|/(S̃ + 1e−9 bound) {worst:.2e}");
}
