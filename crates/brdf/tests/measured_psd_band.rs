//! The full GHS of a measured PSD that covers only a scan's band.
//! `TabulatedPsd` continues the samples below the band by the
//! K-correlation roll-off that matches the first segment in value and slope,
//! and above it by the last segment's power law; with that (C¹) continuation
//! the S̃ table agrees with the direct Hankel transform of the same
//! covariance (`numerics::hankel::s_tilde_direct`, physics.md §4.1) to 1e−3
//! (measured: ≤ 2.1e−4) wherever S̃ is above 1e−3 of its peak — held flat
//! below the band they would disagree by up to 26 %.

use std::f64::consts::PI;

use brdf::Fresnel;
use brdf::numerics::hankel;
use brdf::statistics::measured_psd::TabulatedCorrelation;
use brdf::statistics::{KcPsd, RadialPsd, TabulatedPsd};
use brdf::wave::GhsFull;

/// KC samples on `n` log-spaced frequencies of [lo, hi] rad/µm.
fn band(kc: &KcPsd, lo: f64, hi: f64, n: usize) -> TabulatedPsd {
    let z: Vec<f64> = (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect();
    let p: Vec<f64> = z.iter().map(|&z| kc.psd(z)).collect();
    TabulatedPsd::new(&z, &p).unwrap()
}

/// Largest |table/direct − 1| over the judged geometries (g at θi 0° and
/// 72.5°, a quarter of each, 450 and 650 nm; u from 0 to the hemisphere's
/// 2kL where S̃ ≥ 1e−3 of its peak).
fn worst_table_error(tab: &TabulatedPsd) -> f64 {
    let corr = TabulatedCorrelation::new(tab);
    let m = GhsFull::new(tab.clone(), Fresnel::One).unwrap();
    let (sigma, l) = (tab.sigma_um(), tab.length_um());
    let mut worst = 0.0f64;
    for lam in [450.0, 650.0] {
        let k = 2000.0 * PI / lam;
        for ci in [1.0, 0.3] {
            let gs = (2.0 * k * sigma * ci).powi(2);
            for g in [gs, 0.25 * gs, 1e-3] {
                let peak = hankel::s_tilde_direct(&corr, 0.0, g);
                for f in [0.0, 0.01, 0.03, 0.1, 0.3, 1.0] {
                    let u = f * 2.0 * k * l;
                    let want = hankel::s_tilde_direct(&corr, u, g);
                    if want >= 1e-3 * peak {
                        worst = worst.max((m.s_tilde(u, g) / want - 1.0).abs());
                    }
                }
            }
        }
    }
    worst
}

#[test]
fn band_limited_tables_agree_with_the_direct_transform() {
    // (σ, Lc, γ) and bands: a 25.6 µm scan at 0.1 µm (ζ 0.245–31.4 rad/µm),
    // a longer scan, and a band starting deep in the tail.
    let cases = [
        (0.2, 1.0, 3.0, 0.245, 31.4, 120),
        (0.2, 1.0, 3.0, 0.245, 31.4, 400),
        (0.2, 1.0, 3.0, 0.06, 31.4, 120),
        (0.2, 1.0, 3.0, 2.0, 100.0, 120),
        (0.05, 0.3, 4.0, 0.3, 60.0, 150),
        (0.1, 2.0, 2.5, 0.1, 20.0, 150),
    ];
    let mut lines = Vec::new();
    for (s, lc, g, lo, hi, n) in cases {
        let kc = KcPsd::new(s, lc, g).unwrap();
        let tab = band(&kc, lo, hi, n);
        let e = worst_table_error(&tab);
        lines.push(format!(
            "KC σ {s} Lc {lc} γ {g}, band {lo}–{hi} rad/µm ({n} samples): {e:.2e}"
        ));
        assert!(e < 1e-3, "{}", lines.last().unwrap());
    }
    println!("{}", lines.join("\n"));
}

#[test]
fn the_continuation_below_the_band_is_c1_and_flat_at_zero() {
    let kc = KcPsd::new(0.2, 1.0, 3.0).unwrap();
    let tab = band(&kc, 0.5, 30.0, 100);
    let (z0, _) = tab.band_rad_per_um();
    let slope = |z: f64| {
        let h = 1e-6;
        ((tab.psd(z * (1.0 + h))).ln() - (tab.psd(z * (1.0 - h))).ln()) / (2.0 * h)
    };
    let (below, above) = (slope(z0 * (1.0 - 1e-4)), slope(z0 * (1.0 + 1e-4)));
    assert!((below - above).abs() < 1e-3, "{below} vs {above}");
    assert!((tab.psd(z0 * (1.0 - 1e-12)) / tab.psd(z0) - 1.0).abs() < 1e-9);
    assert!(slope(1e-6 * z0).abs() < 1e-6);
    // The exponent is the fitted tail's (ζ^−4 here: β = 2).
    let (zc, beta) = tab.low_rolloff();
    assert!((beta - 2.0).abs() < 2e-2 && zc.is_finite(), "{zc} {beta}");
    assert!((tab.high_slope() + 4.0).abs() < 1e-2);
    // Sampling inverts the CDF there too.
    for i in 1..40 {
        let xi = 0.002 * i as f64;
        let z = tab.sample_zeta(xi);
        assert!((tab.cdf(z) - xi).abs() < 1e-12, "ξ {xi}: ζ {z}");
    }
    // σ² = ∫P d²ζ with the continuation: against a fine quadrature.
    let mut acc = 0.0;
    let n = 200_000;
    let (a, b) = ((1e-6f64).ln(), (1e6f64).ln());
    for i in 0..n {
        let lz = a + (b - a) * (i as f64 + 0.5) / n as f64;
        let z = lz.exp();
        acc += 2.0 * PI * z * z * tab.psd(z) * (b - a) / n as f64;
    }
    assert!(
        (acc.sqrt() / tab.sigma_um() - 1.0).abs() < 1e-6,
        "{} vs {}",
        acc.sqrt(),
        tab.sigma_um()
    );
}

#[test]
fn a_rising_or_very_steep_start_is_continued_flat() {
    // Rising first segment (a levelled scan's lowest bins): flat.
    let t = TabulatedPsd::new(&[1.0, 2.0, 4.0], &[1e-3, 2e-3, 1e-4]).unwrap();
    assert_eq!(t.low_rolloff().0, f64::INFINITY);
    assert!((t.psd(0.1) / 1e-3 - 1.0).abs() < 1e-12);
    // A first segment at ζ^−20 would need a 2^20 rise: flat instead.
    let t = TabulatedPsd::new(&[1.0, 2.0], &[1e-3, 1e-3 * 2f64.powf(-20.0)]).unwrap();
    assert_eq!(t.low_rolloff().0, f64::INFINITY);
    // ζ^−6 rises by 2^6 = 64 < 1000: rolled off.
    let t = TabulatedPsd::new(&[1.0, 2.0], &[1e-3, 1e-3 * 2f64.powf(-6.0)]).unwrap();
    assert!(t.low_rolloff().0.is_finite());
    assert!((t.psd(0.0) / 1e-3 - 64.0).abs() < 1e-9, "{}", t.psd(0.0));
}

#[test]
fn a_bounded_direct_transform_is_the_direct_transform_or_none() {
    // judge's table check asks with a budget; within it the value must be the
    // unbounded transform's, bit for bit, and past it there must be no value.
    let kc = KcPsd::new(0.2, 1.0, 3.0).unwrap();
    let corr = TabulatedCorrelation::new(&band(&kc, 0.245, 31.4, 120));
    for (u, g) in [(0.0, 0.5), (20.0, 2.0), (200.0, 30.0)] {
        let full = hankel::s_tilde_direct(&corr, u, g);
        assert_eq!(
            hankel::s_tilde_direct_within(&corr, u, g, f64::INFINITY),
            Some(full)
        );
        assert_eq!(hankel::s_tilde_direct_within(&corr, u, g, 1e8), Some(full));
        assert_eq!(
            hankel::s_tilde_direct_within(&corr, u, g, 0.0),
            None,
            "u {u}, g {g}"
        );
    }
}
