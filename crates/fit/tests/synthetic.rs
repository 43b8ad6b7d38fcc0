//! Independent checks of the analysis on synthetic data: Welch against a brute-force DFT,
//! K-correlation parameters recovered from spectrally synthesised surfaces, NDF fits on
//! sampled slopes, the Gaussian filter's transmission, the PSD conversion, SHA-256.

use fit::kc::{self, KcParams};
use fit::psd::{self, Psd1d, WelchOptions};
use fit::rng::{Normal, SplitMix64};
use fit::{Topography, ndf, sha256, synth, two_scale};
use std::f64::consts::PI;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// One-sided Welch estimate computed literally from its definition with an O(N²) DFT.
fn brute_welch(t: &Topography, nperseg: usize, noverlap: usize) -> Vec<f64> {
    let step = nperseg - noverlap;
    let nseg = (t.nx - nperseg) / step + 1;
    let w: Vec<f64> = (0..nperseg)
        .map(|i| (PI * i as f64 / nperseg as f64).sin().powi(2))
        .collect();
    let wss: f64 = w.iter().map(|v| v * v).sum();
    let mut out = vec![0.0; nperseg / 2 + 1];
    for y in 0..t.ny {
        for s in 0..nseg {
            let seg = &t.line(y)[s * step..s * step + nperseg];
            let mean = seg.iter().sum::<f64>() / nperseg as f64;
            for (k, o) in out.iter_mut().enumerate() {
                let (mut re, mut im) = (0.0, 0.0);
                for (n, v) in seg.iter().enumerate() {
                    let ph = -2.0 * PI * (k * n) as f64 / nperseg as f64;
                    re += (v - mean) * w[n] * ph.cos();
                    im += (v - mean) * w[n] * ph.sin();
                }
                let two = if k == 0 || 2 * k == nperseg { 1.0 } else { 2.0 };
                *o += two * (re * re + im * im) * t.dx / wss;
            }
        }
    }
    out.iter().map(|v| v / (nseg * t.ny) as f64).collect()
}

#[test]
fn welch_matches_brute_force_dft() {
    let mut rng = SplitMix64::new(7);
    let t = Topography {
        nx: 100,
        ny: 3,
        dx: 2e-8,
        dy: 2e-8,
        heights: (0..300).map(|_| rng.normal() * 1e-9 + 3e-9).collect(),
        channel: String::new(),
        format: "test",
    };
    for (nperseg, noverlap) in [(32, 16), (33, 10), (100, 50)] {
        let w = psd::welch(
            &t,
            &WelchOptions {
                nperseg: Some(nperseg),
                noverlap: Some(noverlap),
            },
        )
        .unwrap();
        let b = brute_welch(&t, nperseg, noverlap);
        assert_eq!(w.p.len(), b.len());
        for (k, (x, y)) in w.p.iter().zip(&b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-10 * y.abs() + 1e-40,
                "nperseg {nperseg} bin {k}: {x} vs {y}"
            );
            assert!((w.f[k] - k as f64 / (nperseg as f64 * t.dx)).abs() <= 1e-12 * w.f[k]);
        }
    }
}

#[test]
fn welch_of_a_sinusoid_integrates_to_its_variance() {
    // Amplitude a at an exact bin: the one-sided density integrates to a²/2.
    let (n, dx, a) = (256usize, 1e-7, 3e-9);
    let k0 = 20.0;
    let t = Topography {
        nx: n,
        ny: 1,
        dx,
        dy: dx,
        heights: (0..n)
            .map(|i| a * (2.0 * PI * k0 * i as f64 / n as f64).sin())
            .collect(),
        channel: String::new(),
        format: "test",
    };
    let w = psd::welch(&t, &WelchOptions::default()).unwrap();
    let df = 1.0 / (n as f64 * dx);
    let total: f64 = w.p.iter().sum::<f64>() * df;
    assert!(
        rel(total, a * a / 2.0) < 1e-12,
        "{total} vs {}",
        a * a / 2.0
    );
}

#[test]
fn kc_parameters_are_recovered_from_synthetic_maps() {
    // Roll-off inside the band: L·f spans ~0.4 … 30 over bins 3 … nx/4.
    let truth = KcParams {
        sigma: 5e-9,
        lc: 0.1e-6,
        gamma: 4.0,
    };
    let t = synth::kc_surface(512, 512, 10e-9, truth, 42);
    let p = psd::welch(&t, &WelchOptions::default()).unwrap();
    let f = kc::fit_bins(&p, 3, t.nx / 4).unwrap();
    let k = f.params;
    println!(
        "1D: {k:?} ± {:?}, rms log res {}",
        f.stderr, f.rms_log_residual
    );
    assert!(!f.degenerate);
    assert!(rel(k.sigma, truth.sigma) < 0.05, "σ {}", k.sigma);
    assert!(rel(k.lc, truth.lc) < 0.05, "Lc {}", k.lc);
    assert!(rel(k.gamma, truth.gamma) < 0.05, "γ {}", k.gamma);
    // The reported uncertainty must be consistent with the actual error.
    assert!(
        (k.gamma - truth.gamma).abs() < 5.0 * f.stderr.gamma + 0.02,
        "γ error vs stderr {}",
        f.stderr.gamma
    );

    // The radial fit sees few samples in the low-ζ bins, so it needs a larger map.
    let t = synth::kc_surface(1024, 1024, 10e-9, truth, 43);
    let r = psd::radial(&t).unwrap();
    let zmax = *r.zeta.last().unwrap();
    let f2 = kc::fit_weighted(
        kc::PsdForm::Radial2d,
        &r.zeta,
        &r.p,
        Some(&r.count),
        r.zeta[2] * 0.999,
        zmax / 2.0,
    )
    .unwrap();
    println!("2D: {:?} ± {:?}", f2.params, f2.stderr);
    let (k2, e2) = (f2.params, f2.stderr);
    for (name, got, want, err) in [
        ("σ", k2.sigma, truth.sigma, e2.sigma),
        ("Lc", k2.lc, truth.lc, e2.lc),
        ("γ", k2.gamma, truth.gamma, e2.gamma),
    ] {
        assert!(rel(got, want) < 0.05, "2D {name} {got} vs {want}");
        assert!(
            (got - want).abs() < 3.0 * err + 0.01 * want,
            "2D {name}: error {} vs stderr {err}",
            got - want
        );
    }

    // ∫ P d²ζ over the radial bins equals the map variance (window power-normalised).
    let var = t.heights.iter().map(|h| h * h).sum::<f64>() / t.heights.len() as f64;
    let mut integral = 0.0;
    for i in 1..r.zeta.len() {
        integral += 0.5
            * (r.zeta[i] * r.p[i] + r.zeta[i - 1] * r.p[i - 1])
            * 2.0
            * PI
            * (r.zeta[i] - r.zeta[i - 1]);
    }
    println!("∫P d²ζ = {integral:e}, variance {var:e}");
    assert!(rel(integral, var) < 0.05, "{integral} vs {var}");
}

#[test]
fn kc_parameters_are_recovered_from_synthetic_profiles() {
    for (truth, seed) in [
        (
            KcParams {
                sigma: 2e-8,
                lc: 0.5e-6,
                gamma: 3.0,
            },
            1,
        ),
        (
            KcParams {
                sigma: 1e-7,
                lc: 1e-6,
                gamma: 6.0,
            },
            2,
        ),
    ] {
        // Average 64 profiles for a smooth PSD.
        let mut sum: Option<Psd1d> = None;
        for s in 0..64 {
            let t = synth::kc_profile(4096, 50e-9, truth, seed * 1000 + s);
            let p = psd::welch(&t, &WelchOptions::default()).unwrap();
            sum = Some(match sum {
                None => p,
                Some(mut a) => {
                    for (x, y) in a.p.iter_mut().zip(&p.p) {
                        *x += y;
                    }
                    a
                }
            });
        }
        let mut p = sum.unwrap();
        p.p.iter_mut().for_each(|v| *v /= 64.0);
        let f = kc::fit_bins(&p, 3, 1024).unwrap();
        println!("profile truth {truth:?} → {:?} ± {:?}", f.params, f.stderr);
        assert!(rel(f.params.sigma, truth.sigma) < 0.05);
        assert!(rel(f.params.lc, truth.lc) < 0.05);
        assert!(rel(f.params.gamma, truth.gamma) < 0.05);
    }
}

#[test]
fn kc_forms_are_normalised_and_consistent() {
    let k = KcParams {
        sigma: 3e-9,
        lc: 0.2e-6,
        gamma: 3.5,
    };
    // ∫ P1 df over (0, ∞) = σ², by substitution f = tan(t)/L.
    let l = k.l_cycles();
    let n = 20000;
    let mut s1 = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64 * PI / 2.0;
        let f = t.tan() / l;
        s1 += k.psd_1d(f) / (l * t.cos().powi(2)) * (PI / 2.0 / n as f64);
    }
    assert!(rel(s1, k.sigma * k.sigma) < 1e-4, "{s1}");
    // The 1D form is the line integral of the 2D form: one-sided P1(f) = 2∫_R PSD_cyc(√(f²+fy²)) dfy.
    for f in [1e5, 1e6, 1e7] {
        let mut s = 0.0;
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * PI / 2.0;
            let fy = t.tan() / l;
            let fr = (f * f + fy * fy).sqrt();
            s += 4.0 * 4.0 * PI * PI * k.psd_2d(2.0 * PI * fr) / (l * t.cos().powi(2))
                * (PI / 2.0 / n as f64);
        }
        assert!(rel(s, k.psd_1d(f)) < 1e-4, "f {f}: {s} vs {}", k.psd_1d(f));
    }
}

#[test]
fn profile_to_2d_conversion_is_exact_on_power_law_tails() {
    let k = KcParams {
        sigma: 3e-9,
        lc: 0.2e-6,
        gamma: 3.5,
    };
    let f: Vec<f64> = (1..2000).map(|i| i as f64 * 1e5).collect();
    let p1 = Psd1d {
        p: f.iter().map(|&f| k.psd_1d(f)).collect(),
        f: f.clone(),
    };
    let r = psd::radial_from_profile(&p1, 4);
    // Deep in the tail (L f ≫ 1) the local power law is exact.
    for (z, p) in r
        .zeta
        .iter()
        .zip(&r.p)
        .filter(|(z, _)| **z > 2.0 * PI * 5e7)
    {
        let exact = k.psd_2d(*z);
        assert!(rel(*p, exact) < 0.02, "ζ {z}: {p} vs {exact}");
    }
}

#[test]
fn merge_takes_stylus_below_and_afm_above_the_cutoff() {
    let low = Psd1d {
        f: vec![0.0, 1.0, 2.0, 3.0],
        p: vec![9.0, 1.0, 2.0, 3.0],
    };
    let high = Psd1d {
        f: vec![0.0, 2.5, 3.0, 4.0],
        p: vec![9.0, 20.0, 30.0, 40.0],
    };
    let m = psd::merge(&low, &high, 2.5);
    assert_eq!(m.f, vec![1.0, 2.0, 2.5, 3.0, 4.0]);
    assert_eq!(m.p, vec![1.0, 2.0, 20.0, 30.0, 40.0]);
}

#[test]
fn ndf_fits_recover_alpha_from_sampled_slopes() {
    let mut rng = SplitMix64::new(3);
    let n = 400_000;
    for alpha in [0.05, 0.2, 0.5] {
        // Beckmann: slopes are normal with variance α²/2 per axis.
        let (sx, sy): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|_| {
                (
                    rng.normal() * alpha / 2f64.sqrt(),
                    rng.normal() * alpha / 2f64.sqrt(),
                )
            })
            .unzip();
        let tmax = ndf::theta_max_for(&sx, &sy);
        let h = ndf::histogram(&sx, &sy, 90, tmax, tmax / 90.0);
        let (ab, res) = ndf::fit_alpha(&h, ndf::beckmann);
        println!("Beckmann α {alpha}: fit {ab} (res {res})");
        assert!(rel(ab, alpha) < 0.02, "{ab}");
        // The histogram is a normalised NDF: Σ D π(sin²θ₁ − sin²θ₀) = 1 up to the tail.
        let total: f64 = h.mass.iter().sum();
        assert!(total > 0.99 && total <= 1.0 + 1e-12, "{total}");
        // GGX: |s| = α √(u/(1−u)).
        let (sx, sy): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|_| {
                let u = rng.uniform();
                let r = alpha * (u / (1.0 - u)).sqrt();
                let phi = 2.0 * PI * rng.uniform();
                (r * phi.cos(), r * phi.sin())
            })
            .unzip();
        let tmax = ndf::theta_max_for(&sx, &sy);
        let h = ndf::histogram(&sx, &sy, 90, tmax, tmax / 90.0);
        let (ag, res) = ndf::fit_alpha(&h, ndf::ggx);
        println!("GGX α {alpha}: fit {ag} (res {res})");
        assert!(rel(ag, alpha) < 0.03, "{ag}");
        // The wrong model fits worse.
        assert!(ndf::fit_alpha(&h, ndf::beckmann).1 > 2.0 * res);
    }
}

#[test]
fn exponential_beta_is_recovered() {
    let mut rng = SplitMix64::new(11);
    let beta = 0.07;
    let (sx, sy): (Vec<f64>, Vec<f64>) = (0..200_000)
        .map(|_| {
            let r = -beta * (rng.uniform() * rng.uniform()).ln();
            let phi = 2.0 * PI * rng.uniform();
            (r * phi.cos(), r * phi.sin())
        })
        .unzip();
    let b = ndf::exponential_beta(&sx, &sy);
    assert!(rel(b, beta) < 0.01, "{b}");
}

#[test]
fn gaussian_filter_transmits_half_at_the_cutoff() {
    let (n, dx) = (2048usize, 0.1e-6);
    let cutoff = 25.6e-6; // 256 samples: an exact bin of the mirrored signal
    for (period, expect) in [
        (cutoff, 0.5),
        (cutoff / 2.0, 0.5f64.powi(4)),
        (cutoff * 4.0, 0.5f64.powf(1.0 / 16.0)),
    ] {
        let t = Topography {
            nx: n,
            ny: 1,
            dx,
            dy: dx,
            heights: (0..n)
                .map(|i| (2.0 * PI * (i as f64 + 0.5) * dx / period).cos())
                .collect(),
            channel: String::new(),
            format: "test",
        };
        let low = two_scale::gaussian_lowpass(&t, cutoff);
        // Amplitude in the middle half (away from the mirrored ends).
        let num: f64 = (n / 4..3 * n / 4)
            .map(|i| low.heights[i] * t.heights[i])
            .sum();
        let den: f64 = (n / 4..3 * n / 4)
            .map(|i| t.heights[i] * t.heights[i])
            .sum();
        let gain = num / den;
        println!("period {period:e}: gain {gain} (expect {expect})");
        assert!((gain - expect).abs() < 0.01, "{gain} vs {expect}");
    }
}

#[test]
fn sha256_matches_known_digests() {
    assert_eq!(
        sha256::hex(b"abc"),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    assert_eq!(
        sha256::hex(b""),
        "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    );
    let long = vec![b'a'; 1_000_000];
    assert_eq!(
        sha256::hex(&long),
        "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"
    );
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/surfaces");
    for (file, digest) in [
        (
            "matrix-3.txt",
            "af690c2ce65e8ccc30155998ca6e3719dd2a10e2d4f3676e49bbbc175ed23897",
        ),
        (
            "di-3.di",
            "1c65c9d1f67e057386475a02c358791f29510801095a834708b1338471cb1401",
        ),
        (
            "dektak-1.csv",
            "8f62160151af4401e09b2e478e40e53cb31548d7348d06a1db04b77ba753b79f",
        ),
    ] {
        assert_eq!(
            sha256::hex(&std::fs::read(dir.join(file)).unwrap()),
            digest,
            "{file}"
        );
    }
}

fn map(nx: usize, ny: usize, f: impl Fn(f64, f64) -> f64) -> Topography {
    let mut h = Vec::new();
    for y in 0..ny {
        for x in 0..nx {
            h.push(f(x as f64, y as f64));
        }
    }
    Topography {
        nx,
        ny,
        dx: 1e-6,
        dy: 1e-6,
        heights: h,
        channel: String::new(),
        format: "test",
    }
}

#[test]
fn harmonic_fill_reproduces_harmonic_functions() {
    // x² − y² and planes are harmonic: interior holes must be filled with their values.
    let truth = map(40, 30, |x, y| {
        1e-9 * ((x - 20.0).powi(2) - (y - 15.0).powi(2)) + 3e-9 * x
    });
    let mut t = truth.clone();
    let mut rng = SplitMix64::new(5);
    for _ in 0..150 {
        let (x, y) = (
            1 + (rng.next_u64() % 38) as usize,
            1 + (rng.next_u64() % 28) as usize,
        );
        t.heights[y * 40 + x] = f64::NAN;
    }
    for y in 10..14 {
        for x in 12..20 {
            t.heights[y * 40 + x] = f64::NAN; // a block hole
        }
    }
    let n = fit::fill::harmonic(&mut t).unwrap();
    assert!(n > 150);
    let worst = t
        .heights
        .iter()
        .zip(&truth.heights)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-15, "{worst}");
    let mut all = truth.clone();
    all.heights.iter_mut().for_each(|h| *h = f64::NAN);
    assert!(fit::fill::harmonic(&mut all).is_err());
}

#[test]
fn levelling_removes_exactly_what_it_fits() {
    let mut rng = SplitMix64::new(9);
    let noise: Vec<f64> = (0..50 * 40).map(|_| rng.normal() * 1e-9).collect();
    let base = map(50, 40, |x, y| 1e-7 + 2e-8 * x - 3e-8 * y);
    let mut t = base.clone();
    for (h, n) in t.heights.iter_mut().zip(&noise) {
        *h += n;
    }
    let mut plain = t.clone();
    plain.heights.copy_from_slice(&noise);
    fit::level::plane(&mut t).unwrap();
    fit::level::plane(&mut plain).unwrap();
    // Levelling is linear: the tilt disappears and the noise is levelled the same way.
    let worst = t
        .heights
        .iter()
        .zip(&plain.heights)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-18, "{worst}");
    // A quadratic surface is removed to rounding by the degree-2 polynomial.
    let mut q = map(50, 40, |x, y| {
        1e-9 * (x * x - 2.0 * x * y + 0.5 * y * y) + 1e-8 * x
    });
    fit::level::polynomial(&mut q, 2).unwrap();
    assert!(
        q.heights.iter().all(|h| h.abs() < 1e-18),
        "{:e}",
        q.heights.iter().fold(0.0f64, |m, h| m.max(h.abs()))
    );
    // Per-line levelling leaves every line with zero mean and zero slope.
    let mut l = map(50, 40, |x, y| 1e-9 * (x * y).sin() + 1e-8 * x * (y + 1.0));
    fit::level::per_line(&mut l, 1).unwrap();
    for y in 0..40 {
        let line = l.line(y);
        let mean = line.iter().sum::<f64>() / 50.0;
        let slope: f64 = line
            .iter()
            .enumerate()
            .map(|(i, v)| (i as f64 - 24.5) * v)
            .sum();
        assert!(
            mean.abs() < 1e-19 && slope.abs() < 1e-16,
            "line {y}: {mean} {slope}"
        );
    }
}
