//! Chi-square tests of GhsFull and GhsSsa sampling against their pdf
//! (brdf::testing harness), 22 parameter sets each: g_s from ≈1e−3 to
//! ≈1e3, γ ∈ {1.2, 1.5, 2, 3, 3.5, 4, 6}, θi from 0 to 89°.

use std::collections::HashMap;
use std::sync::Arc;

use brdf::statistics::KcPsd;
use brdf::statistics::matern::Matern;
use brdf::testing::{Chi2Config, chi2_test, sidak};
use brdf::wave::ghs::hemisphere_u_max;
use brdf::wave::ghs_table::{GhsTable, TableResolution};
use brdf::wave::{GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, DVec3, Fresnel};

/// (γ, σ µm, Lc µm, θi°, λ nm)
const SETS: [(f64, f64, f64, f64, f64); 22] = [
    (1.2, 0.0014, 5.0, 0.0, 550.0),
    (1.2, 0.05, 5.0, 30.0, 550.0),
    (1.2, 0.3, 5.0, 60.0, 450.0),
    (1.2, 0.1, 5.0, 89.0, 700.0),
    (2.0, 0.0014, 2.0, 0.0, 550.0),
    (2.0, 0.1, 2.0, 45.0, 400.0),
    (2.0, 1.38, 2.0, 0.0, 550.0),
    (2.0, 0.3, 2.0, 80.0, 650.0),
    (2.0, 0.2, 2.0, 89.0, 500.0),
    (3.0, 0.0014, 5.0, 10.0, 550.0),
    (3.0, 0.28, 5.0, 45.0, 700.0),
    (3.0, 1.38, 5.0, 0.0, 550.0),
    (3.0, 0.5, 5.0, 85.0, 400.0),
    (3.0, 0.05, 5.0, 89.0, 550.0),
    (6.0, 0.0014, 1.0, 0.0, 550.0),
    (6.0, 0.027, 1.0, 40.0, 400.0),
    (6.0, 1.38, 1.0, 0.0, 550.0),
    (6.0, 0.3, 1.0, 70.0, 700.0),
    (3.5, 0.808, 10.0, 80.0, 400.0),
    (1.5, 0.091, 20.0, 0.0, 400.0),
    (4.0, 0.027, 1.0, 80.0, 550.0),
    (2.0, 0.138, 2.0, 0.0, 400.0),
];

fn wi(theta_deg: f64) -> DVec3 {
    let t = theta_deg.to_radians();
    DVec3::new(t.sin(), 0.0, t.cos())
}

fn g_specular(sigma: f64, theta_deg: f64, lambda_nm: f64) -> f64 {
    let k = 2000.0 * std::f64::consts::PI / lambda_nm;
    let t = 2.0 * k * sigma * theta_deg.to_radians().cos();
    t * t
}

/// One table per γ, sized for the largest Lc using it.
fn tables() -> HashMap<u64, Arc<GhsTable>> {
    let mut lc_max: HashMap<u64, f64> = HashMap::new();
    for s in SETS {
        let e = lc_max.entry(s.0.to_bits()).or_insert(0.0);
        *e = e.max(s.2);
    }
    lc_max
        .into_iter()
        .map(|(g, lc)| {
            let nu = (f64::from_bits(g) - 1.0) / 2.0;
            let t = GhsTable::build(
                &Matern::new(nu),
                hemisphere_u_max(lc),
                TableResolution::default(),
            )
            .unwrap();
            (g, Arc::new(t))
        })
        .collect()
}

fn config(seed: u64) -> Chi2Config {
    Chi2Config {
        samples: 120_000,
        pilot_samples: 30_000,
        seed,
        ..Default::default()
    }
}

#[test]
fn chi2_full_and_ssa() {
    let tabs = tables();
    let tests = 2 * SETS.len();
    let alpha = sidak(0.01, tests);
    let mut g_seen = (f64::INFINITY, 0.0f64);
    let mut failures = Vec::new();
    let mut lines = Vec::new();
    for (i, &(gamma, sigma, lc, th, lam)) in SETS.iter().enumerate() {
        let psd = KcPsd::new(sigma, lc, gamma).unwrap();
        let full = GhsFull::with_table(
            psd,
            Fresnel::One,
            GhsOptions::default(),
            tabs[&gamma.to_bits()].clone(),
        )
        .unwrap();
        let ssa = GhsSsa::new(psd, Fresnel::One).unwrap();
        let gs = g_specular(sigma, th, lam);
        g_seen = (g_seen.0.min(gs), g_seen.1.max(gs));
        for (name, model) in [("full", &full as &dyn Bxdf), ("ssa", &ssa as &dyn Bxdf)] {
            let rep = chi2_test(model, wi(th), lam, &config(1000 + i as u64));
            lines.push(format!(
                "{name:4} γ={gamma:<4} σ={sigma:<6} Lc={lc:<4} θi={th:<4} λ={lam} g_s={gs:.2e}: χ²={:.1} dof={} p={:.3} delta={:?} lost={:?} defects={}",
                rep.statistic, rep.dof, rep.p_value, rep.delta, rep.lost, rep.defect_count
            ));
            if !rep.passes(alpha) {
                failures.push(format!("{name} set {i}: {}", rep.check(alpha).unwrap_err()));
            }
        }
    }
    for l in &lines {
        println!("{l}");
    }
    assert!(
        g_seen.0 < 2e-3 && g_seen.1 > 5e2,
        "parameter sets must span g ≈ 1e-3 … 1e3: {g_seen:?}"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
