//! ISO 25178-2 height parameters (Sa, Sz, Ssk, Sku), the ACF correlation length and the
//! height histogram of every real file in data/surfaces that SurfaceTopography reads on a
//! uniform grid, against its values (data/surfaces/reference/statistics.json, whose script
//! states the shared definitions); and the estimators against closed forms.

use fit::areal::{self, ACF_THRESHOLD};
use fit::io::{ReadOptions, Units, open_path};
use fit::kc::KcParams;
use fit::{Topography, fill, level, synth};
use serde_json::Value;
use std::path::PathBuf;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * b.abs() + abs
}

#[test]
fn height_parameters_and_correlation_length_match_surface_topography() {
    let text = std::fs::read_to_string(path("reference/statistics.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    let mut report = Vec::new();
    for r in v["files"].as_array().unwrap() {
        let file = r["file"].as_str().unwrap();
        let Some(sa_ref) = r["Sa"].as_f64() else {
            continue; // not read by SurfaceTopography, or a non-uniform profile
        };
        let (opts, scale) = match r["unit"].as_str() {
            Some(u) => (
                ReadOptions::default(),
                fit::io::units::length_factor(u).unwrap(),
            ),
            None => (
                ReadOptions {
                    units: Units::parse("um"),
                    ..ReadOptions::default()
                },
                1e-6,
            ),
        };
        // NanoFocus: SurfaceTopography's lengths are 10⁶ times lustre's (fit::io::nms).
        let lat = if file.ends_with(".nms") { 1e6 } else { 1.0 };
        let mut t = open_path(&path(file), &opts)
            .unwrap_or_else(|e| panic!("{e}"))
            .topo;
        let zmax = t
            .heights
            .iter()
            .filter(|h| h.is_finite())
            .fold(0.0f64, |m, h| m.max(h.abs()));
        fill::harmonic(&mut t).unwrap();
        level::plane(&mut t).unwrap();
        let sq_ref = r["Sq"].as_f64().unwrap();
        if sq_ref * scale < 1e-9 * zmax.max(1e-300) {
            continue; // an exact plane: the moments are of round-off
        }
        let p = areal::height_params(&t);
        let line = format!(
            "{file}: Sa {:.4e}/{:.4e} Sz {:.4e}/{:.4e} Ssk {:.4}/{:.4} Sku {:.4}/{:.4}",
            p.sa,
            sa_ref * scale,
            p.sz,
            r["Sz"].as_f64().unwrap() * scale,
            p.ssk,
            r["Ssk"].as_f64().unwrap(),
            p.sku,
            r["Sku"].as_f64().unwrap()
        );
        assert!(close(p.sa, sa_ref * scale, 0.01, 0.0), "{line}");
        assert!(
            close(p.sz, r["Sz"].as_f64().unwrap() * scale, 0.01, 0.0),
            "{line}"
        );
        assert!(
            close(p.ssk, r["Ssk"].as_f64().unwrap(), 0.01, 0.01),
            "{line}"
        );
        assert!(
            close(p.sku, r["Sku"].as_f64().unwrap(), 0.01, 0.0),
            "{line}"
        );
        let acf = areal::acf(&t).unwrap();
        let ours = acf.length(ACF_THRESHOLD);
        let theirs = r["acf_length"].as_f64().map(|l| l * scale / lat);
        let line = format!("{line} ACF length {ours:?}/{theirs:?}");
        match (ours, theirs) {
            (Some(a), Some(b)) => assert!(close(a, b, 0.01, 0.0), "{line}"),
            (None, None) => {}
            _ => panic!("{line}"),
        }
        println!("{line}");
        report.push(line);
        checked += 1;
    }
    assert!(checked >= 25, "only {checked} files compared");
}

fn kc_map(n: usize, seed: u64) -> Topography {
    let p = KcParams {
        sigma: 1e-8,
        lc: 2e-8,
        gamma: 3.0,
    };
    synth::kc_surface(n, n, 1e-8, p, seed)
}

/// Gaussian heights: Ssk ≈ 0, Sku ≈ 3, Sa ≈ √(2/π)·Sq; the histogram integrates to one and
/// its mean |z| is Sa to within a bin.
#[test]
fn gaussian_heights_have_the_gaussian_moments() {
    let t = kc_map(256, 3);
    let p = areal::height_params(&t);
    let sq = fit::stats::compute(&t).sq;
    assert!(p.ssk.abs() < 0.1, "{}", p.ssk);
    assert!((p.sku - 3.0).abs() < 0.2, "{}", p.sku);
    assert!(close(
        p.sa,
        (2.0 / std::f64::consts::PI).sqrt() * sq,
        0.03,
        0.0
    ));
    let h = areal::histogram(&t, 64).unwrap();
    let w = h.edges[1] - h.edges[0];
    let total: f64 = h.density.iter().map(|d| d * w).sum();
    assert!((total - 1.0).abs() < 1e-12);
    let mean_abs: f64 = h
        .density
        .iter()
        .enumerate()
        .map(|(i, d)| d * w * (h.edges[i] + w / 2.0).abs())
        .sum();
    assert!((mean_abs - p.sa).abs() < w, "{mean_abs} vs {}", p.sa);
    assert_eq!(h.counts.iter().sum::<usize>(), t.heights.len());
}

/// The ACF estimator against a direct double sum on small maps and profiles of every
/// shape, and its closed form for a cosine profile (ρ(r) = cos(2πr/λ) for the circular
/// part, to within the overlap weighting).
#[test]
fn acf_matches_the_direct_sum_and_a_cosine() {
    let mut rng = fit::rng::SplitMix64::new(5);
    for _ in 0..40 {
        let nx = 2 + (rng.next_u64() % 9) as usize;
        let ny = 1 + (rng.next_u64() % 7) as usize;
        let (dx, dy) = (
            1.0 + (rng.next_u64() % 3) as f64,
            1.0 + (rng.next_u64() % 2) as f64,
        );
        let heights: Vec<f64> = (0..nx * ny).map(|_| rng.uniform() - 0.5).collect();
        let t = Topography {
            nx,
            ny,
            dx,
            dy: if ny == 1 { dx } else { dy },
            heights,
            channel: String::new(),
            format: "test",
        };
        let Some(acf) = areal::acf(&t) else { continue };
        // Direct: ρ per lag, binned as documented.
        let n = (nx * ny) as f64;
        let mean = t.heights.iter().sum::<f64>() / n;
        let sq2 = t.heights.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / n;
        let step = if ny == 1 { dx } else { t.dx.min(t.dy) };
        let rmax = if ny == 1 {
            nx as f64 * dx / 2.0
        } else {
            (nx as f64 * t.dx).min(ny as f64 * t.dy) / 2.0
        };
        let mut bins: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
        let ly = ny as i64 - 1;
        for l in -ly..=ly {
            for k in 0..nx {
                let r = ((k as f64 * t.dx).powi(2) + (l as f64 * t.dy).powi(2)).sqrt();
                if r > rmax {
                    continue;
                }
                let (mut s, mut pairs) = (0.0, 0usize);
                for y in 0..ny as i64 {
                    for x in 0..nx - k {
                        let y2 = y + l;
                        if !(0..ny as i64).contains(&y2) {
                            continue;
                        }
                        let (a, b) = (y2 as usize * nx + x + k, y as usize * nx + x);
                        s += (t.heights[a] - t.heights[b]).powi(2);
                        pairs += 1;
                    }
                }
                let a = 0.5 * s / pairs as f64;
                let e = bins.entry((r / step).round() as usize).or_default();
                e.0 += 1.0 - a / sq2;
                e.1 += 1;
            }
        }
        assert_eq!(acf.rho.len(), bins.len());
        for ((b, (s, c)), (r, rho)) in bins.iter().zip(acf.r.iter().zip(&acf.rho)) {
            assert!((*b as f64 * step - r).abs() < 1e-12);
            assert!(
                (s / *c as f64 - rho).abs() < 1e-9,
                "{nx}×{ny}: {} vs {rho}",
                s / *c as f64
            );
        }
    }
    // A long cosine profile: ρ(r) ≈ cos(2πr/λ), so it falls to 0.2 at λ·acos(0.2)/2π.
    let (n, lambda) = (4096, 64.0);
    let heights: Vec<f64> = (0..n)
        .map(|i| (2.0 * std::f64::consts::PI * i as f64 / lambda).cos())
        .collect();
    let t = Topography {
        nx: n,
        ny: 1,
        dx: 1.0,
        dy: 1.0,
        heights,
        channel: String::new(),
        format: "test",
    };
    let l = areal::acf(&t).unwrap().length(ACF_THRESHOLD).unwrap();
    let expect = lambda * 0.2f64.acos() / (2.0 * std::f64::consts::PI);
    assert!((l - expect).abs() < 0.05, "{l} vs {expect}");
}
