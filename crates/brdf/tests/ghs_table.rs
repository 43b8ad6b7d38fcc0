//! The default full-GHS table resolution holds S̃ to ≤ 1e−3 relative
//! over g ∈ [1e−4, 1e4] and u ≤ 2k(360 nm)Lc, measured
//! against freshly transformed rows half-way between the table's rows and at
//! quarter points between its columns, for values ≥ 1e−9 of the peak (below
//! that both generators sit at their ~1e−18 absolute round-off floor).
//! Also: table rows against the independent direct Hankel transform.

use brdf::numerics::hankel::{lobe_width, s_tilde_direct};
use brdf::statistics::matern::Matern;
use brdf::wave::ghs::hemisphere_u_max;
use brdf::wave::ghs_table::{GhsTable, TableResolution};

#[test]
fn default_table_error_is_below_1e3() {
    let res = TableResolution::default();
    for (gamma, lc) in [
        (1.2, 5.0),
        (1.5, 20.0),
        (1.8, 3.0),
        (2.0, 2.0),
        (3.0, 5.0),
        (3.5, 10.0),
        (6.0, 1.0),
    ] {
        let m = Matern::new((gamma - 1.0) / 2.0);
        let t = GhsTable::build(&m, hemisphere_u_max(lc), res).unwrap();
        let (e, g, u, rel) = t.measure_error_at(&m, res, 1e-9, 0.5);
        let (e0, ..) = t.measure_error_at(&m, res, 1e-9, 0.0);
        println!(
            "γ={gamma} Lc={lc}: shape {:?}, {} kB, max err {e:.2e} (at g={g:.3e}, u={u:.3e}, S̃/peak={rel:.1e}), on rows {e0:.2e}",
            t.shape(),
            t.memory_bytes() / 1024
        );
        assert!(e < 1e-3 && e0 < 1e-3, "γ={gamma}: {e} {e0}");
    }
}

#[test]
fn table_matches_direct_transform() {
    let res = TableResolution::default();
    for gamma in [1.5, 3.0, 4.5] {
        let m = Matern::new((gamma - 1.0) / 2.0);
        let t = GhsTable::build(&m, hemisphere_u_max(3.0), res).unwrap();
        for g in [2e-4, 0.03, 0.9, 13.0, 170.0, 2500.0] {
            let w = lobe_width(&m, g);
            let peak = s_tilde_direct(&m, 0.0, g);
            for wu in [0.0, 0.1, 0.7, 2.0, 6.0] {
                let u = (wu * w).min(100.0);
                let want = s_tilde_direct(&m, u, g);
                if want < 1e-9 * peak {
                    continue;
                }
                let got = t.s_tilde(u, g).unwrap();
                assert!(
                    (got / want - 1.0).abs() < 1e-3,
                    "γ={gamma} g={g} u={u}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn truncated_table_agrees_and_is_guarded() {
    // A model's table stops at the g its surface reaches, (2k(360 nm)σ)²;
    // inside that range it is the full table (same rows), and a shared table
    // too short for a rougher surface is refused.
    use brdf::Fresnel;
    use brdf::statistics::kc::KcPsd;
    use brdf::wave::GhsOptions;
    use brdf::wave::ghs::{GhsFull, hemisphere_g_max};
    use std::sync::Arc;
    let res = TableResolution::default();
    let m = Matern::new(0.75);
    let full = GhsTable::build(&m, hemisphere_u_max(3.0), res).unwrap();
    let g_max = hemisphere_g_max(0.1);
    let cut = GhsTable::build_up_to(&m, hemisphere_u_max(3.0), g_max, res).unwrap();
    assert!(
        cut.shape().0 < full.shape().0,
        "{:?} vs {:?}",
        cut.shape(),
        full.shape()
    );
    assert!((cut.g_max() - g_max).abs() < 1e-12 * g_max);
    for g in [1e-4, 2e-3, 0.3, 0.5 * g_max, g_max] {
        for u in [0.0, 0.3, 3.0, 30.0] {
            let (a, b) = (cut.s_tilde(u, g).unwrap(), full.s_tilde(u, g).unwrap());
            assert!((a / b - 1.0).abs() < 1e-9, "g {g} u {u}: {a} vs {b}");
        }
    }
    let cut = Arc::new(cut);
    let psd = |sigma| KcPsd::new(sigma, 3.0, 2.5).unwrap();
    assert!(
        GhsFull::with_table(psd(0.1), Fresnel::One, GhsOptions::default(), cut.clone()).is_ok()
    );
    let Err(err) = GhsFull::with_table(psd(0.5), Fresnel::One, GhsOptions::default(), cut) else {
        panic!("a table for σ = 0.1 µm must not serve σ = 0.5 µm");
    };
    assert!(err.to_string().contains("g_max"), "{err}");
}
