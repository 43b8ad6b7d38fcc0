//! `judge` on the five synthetic K-correlation maps whose measured-PSD tables
//! `crates/brdf/tests/measured_psd_maps.rs` checks: the measured-PSD model must be ranked,
//! not refused for a table that disagrees with the direct Hankel transform. Slow (the
//! explicit BRDF of five maps): `cargo test -p judge --test measured_psd_maps -- --ignored
//! --nocapture` prints each ranking.

use fit::kc::KcParams;
use fit::sampled_kc::PointSampledKc;

/// The maps of `crates/fit/tests/measured_psd_tables.rs`: (name, n, pixel µm, σ µm, Lc µm,
/// γ, seed).
const MAPS: [(&str, usize, f64, f64, f64, f64, u64); 5] = [
    ("kc_s0.01_256", 256, 0.1, 0.01, 1.0, 3.0, 11),
    ("kc_s0.05_256", 256, 0.05, 0.05, 0.5, 4.0, 12),
    ("kc_s0.1_512", 512, 0.1, 0.1, 2.0, 2.5, 13),
    ("kc_s0.2_512", 512, 0.2, 0.2, 5.0, 3.5, 14),
    ("kc_s0.5_512", 512, 0.05, 0.5, 1.0, 3.0, 15),
];

#[test]
#[ignore = "slow: the explicit BRDF of five maps"]
fn judge_ranks_the_measured_psd_model_on_synthetic_maps() {
    let only = std::env::var("ONLY").unwrap_or_default();
    let mut refused = Vec::new();
    for (name, n, dx, s, lc, g, seed) in MAPS {
        if !name.contains(&only) {
            continue;
        }
        let params = KcParams {
            sigma: s * 1e-6,
            lc: lc * 1e-6,
            gamma: g,
        };
        let topo = PointSampledKc::new(n, n, dx * 1e-6, params).realise(seed);
        let j = judge::judge(name, topo, &judge::Options::default(), &mut |_| {}).unwrap();
        let json = j.json();
        println!("## {name}\n{}", j.markdown());
        let skipped = json["skipped"].to_string();
        if skipped.contains("measured PSD") {
            refused.push(format!("{name}: {skipped}"));
        }
    }
    assert!(refused.is_empty(), "{refused:#?}");
}
