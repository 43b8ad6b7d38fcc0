//! Exact properties of the explicit-surface BRDF: a flat patch is a pure delta, a tilted facet
//! reflects into its geometric mirror direction, Parseval (scattered + coherent = 1), the
//! direct per-direction sum equals the FFT grid, reciprocity, the energy balance over the
//! hemisphere, and a calibrated tile confidence band.

use fit::Topography;
use fit::explicit_brdf::{ExplicitBrdf, TileOptions, scattering_vector};
use fit::field_spectrum::{Window, field_spectrum, hemispherical_albedo};
use fit::kc::KcParams;
use fit::sampled_kc::PointSampledKc;
use std::f64::consts::PI;

fn map(nx: usize, ny: usize, dx: f64, f: impl Fn(usize, usize) -> f64) -> Topography {
    let mut heights = Vec::with_capacity(nx * ny);
    for y in 0..ny {
        for x in 0..nx {
            heights.push(f(x, y));
        }
    }
    Topography {
        nx,
        ny,
        dx,
        dy: dx,
        heights,
        channel: "test".into(),
        format: "test",
    }
}

fn dir(theta_deg: f64, phi_deg: f64) -> [f64; 3] {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
}

fn kc_map(n: usize, dx: f64, sigma: f64, lc: f64, gamma: f64, seed: u64) -> Topography {
    PointSampledKc::new(n, n, dx, KcParams { sigma, lc, gamma }).realise(seed)
}

fn whole(window: Window, n: usize) -> TileOptions {
    TileOptions {
        size: Some(n),
        overlap: 0.0,
        window,
    }
}

#[test]
fn flat_patch_is_a_pure_delta() {
    for offset in [0.0, 3.7e-7] {
        let t = map(64, 48, 0.1e-6, |_, _| offset);
        for w in [Window::Rect, Window::Hann] {
            let s = field_spectrum(&t, 2.0e7, w).unwrap();
            assert!((s.coherent - 1.0).abs() < 1e-12, "{}", s.coherent);
            assert!(
                s.p.iter().all(|p| *p < 1e-30),
                "scattered power of a flat patch"
            );
        }
        let e = ExplicitBrdf::new(&t, &TileOptions::default()).unwrap();
        let wi = dir(30.0, 0.0);
        for (th, ph) in [(30.0, 180.0), (10.0, 0.0), (60.0, 90.0), (80.0, 200.0)] {
            let f = e.scattered(wi, dir(th, ph), 0.55e-6);
            assert!(f.value < 1e-20, "f({th}, {ph}) = {}", f.value);
        }
        let c = e.coherent(wi, 0.55e-6);
        assert!((c.value - 1.0).abs() < 1e-12, "coherent {}", c.value);
    }
}

#[test]
fn tilted_facet_reflects_into_its_mirror_direction() {
    // A plane of slope a is a pure tone exp(−i q a x): with q a = −(m Δζ) it sits on one bin,
    // at ζx = −q a (the facet's geometric mirror direction), not at +q a.
    let (n, dx) = (128, 0.2e-6);
    let lambda = 0.5e-6;
    let k = 2.0 * PI / lambda;
    let q = 2.0 * k; // normal incidence, near-normal exit
    let m = 5.0;
    let dzeta = 2.0 * PI / (n as f64 * dx);
    let a = m * dzeta / q;
    let t = map(n, n, dx, |x, _| a * x as f64 * dx);
    let s = field_spectrum(&t, q, Window::Rect).unwrap();
    let (imax, _) =
        s.p.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
    let (zx, zy) = s.zeta(imax % n, imax / n);
    assert!(
        (zx + m * dzeta).abs() < 1e-9 * dzeta && zy == 0.0,
        "peak at {zx}, {zy}"
    );
    let total = s.total() + s.coherent;
    assert!((s.p[imax] * s.cell() / total - 1.0).abs() < 1e-9);

    // The same with exact directions: scanning in-plane exits, the peak is the mirror of
    // normal incidence about the facet normal (−a, 0, 1)/|·|, i.e. θo = −2 atan(a)
    // (backscatter side for a > 0).
    let e = ExplicitBrdf::new(&t, &whole(Window::Hann, n)).unwrap();
    let wi = [0.0, 0.0, 1.0];
    let expect = -2.0 * a.atan();
    let mut best = (f64::NEG_INFINITY, 0.0);
    for j in 0..=4000 {
        let th = expect + (j as f64 / 2000.0 - 1.0) * 0.05;
        let wo = [th.sin(), 0.0, th.cos()];
        let f = e.scattered(wi, wo, lambda).value;
        if f > best.0 {
            best = (f, th);
        }
    }
    assert!(
        (best.1 - expect).abs() < 3e-5,
        "peak at {} rad, mirror direction {expect}",
        best.1
    );
}

#[test]
fn parseval_scattered_plus_coherent_is_one() {
    let t = kc_map(128, 0.05e-6, 0.05e-6, 0.4e-6, 3.0, 11);
    for q in [1e6, 1e7, 4e7, 2e8] {
        let s = field_spectrum(&t, q, Window::Rect).unwrap();
        assert!(
            (s.total() + s.coherent - 1.0).abs() < 1e-12,
            "q {q}: {} + {}",
            s.total(),
            s.coherent
        );
        let h = field_spectrum(&t, q, Window::Hann).unwrap();
        assert!((h.total() / h.windowed_variance - 1.0).abs() < 1e-12);
    }
    // Profile.
    let p = map(1000, 1, 0.1e-6, |x, _| {
        1e-7 * ((x as f64 * 0.07).sin() + 0.3 * (x as f64 * 0.41).cos())
    });
    let s = field_spectrum(&p, 3e7, Window::Rect).unwrap();
    assert!((s.total() + s.coherent - 1.0).abs() < 1e-12);
}

#[test]
fn direct_sum_equals_the_fft_grid() {
    let n = 64;
    let t = kc_map(n, 0.05e-6, 0.08e-6, 0.3e-6, 2.5, 3);
    let q = 3e7;
    for w in [Window::Rect, Window::Hann] {
        let grid = field_spectrum(&t, q, w).unwrap();
        let e = ExplicitBrdf::new(&t, &whole(w, n)).unwrap();
        for (ix, iy) in [(1, 0), (0, 3), (5, 7), (60, 2), (32, 32), (17, 50)] {
            let (zx, zy) = grid.zeta(ix, iy);
            let d = e.spectrum((zx, zy), q).value;
            let g = grid.at(ix, iy);
            assert!(
                (d / g - 1.0).abs() < 1e-9,
                "{w:?} bin ({ix},{iy}): {d} vs {g}"
            );
        }
    }
    // Profile: 1-D, both windows.
    let p = map(300, 1, 0.1e-6, |x, _| {
        2e-7 * (x as f64 * 0.113).sin() * (x as f64 * 0.021).cos()
    });
    for w in [Window::Rect, Window::Hann] {
        let grid = field_spectrum(&p, q, w).unwrap();
        let e = ExplicitBrdf::new(&p, &whole(w, 300)).unwrap();
        for ix in [1, 2, 9, 77, 150, 299] {
            let (zx, _) = grid.zeta(ix, 0);
            let d = e.spectrum((zx, 123.0), q).value;
            assert!((d / grid.at(ix, 0) - 1.0).abs() < 1e-9, "{w:?} {ix}");
        }
    }
}

#[test]
fn explicit_brdf_is_reciprocal() {
    // A skewed, anisotropic surface: cubed heights, stretched along x.
    let base = kc_map(96, 0.1e-6, 0.1e-6, 0.5e-6, 3.5, 5);
    let t = map(96, 96, 0.1e-6, |x, y| {
        let h = base.heights[y * 96 + (x / 2 + 20 * (y % 2))];
        h * h * h / 1e-14
    });
    let t = Topography { dy: 0.13e-6, ..t };
    let e = ExplicitBrdf::new(&t, &TileOptions::default()).unwrap();
    let mut rng = fit::rng::SplitMix64::new(9);
    for _ in 0..40 {
        let wi = dir(85.0 * rng.uniform(), 360.0 * rng.uniform());
        let wo = dir(85.0 * rng.uniform(), 360.0 * rng.uniform());
        for lambda in [0.4e-6, 0.7e-6] {
            let a = e.scattered(wi, wo, lambda);
            let b = e.scattered(wo, wi, lambda);
            assert!(
                (a.value - b.value).abs() <= 1e-12 * a.value.abs().max(1e-300),
                "{a:?} vs {b:?}"
            );
            assert_eq!(
                scattering_vector(1.0, wi, wo),
                scattering_vector(1.0, wo, wi)
            );
        }
    }
}

#[test]
fn hemispherical_energy_balance() {
    // All grid frequencies propagate when dx ≥ λ/√2·(1 + sinθi): then at frozen q the
    // hemispherical integral plus the coherent part is exactly 1 (Parseval).
    let lambda = 0.5e-6;
    let t = kc_map(128, 1.0e-6, 0.08e-6, 8e-6, 4.0, 21);
    let wi = dir(0.0, 0.0);
    let a = hemispherical_albedo(&t, wi, lambda, 1, Window::Rect).unwrap();
    assert!(a.evanescent_frozen.abs() < 1e-15);
    assert!((a.total() - 1.0).abs() < 1e-12, "{a:?}");
    // With evanescent frequencies (finer pixels): the account still closes at frozen q.
    let t2 = kc_map(128, 0.1e-6, 0.02e-6, 0.15e-6, 2.0, 22);
    let wi2 = dir(50.0, 0.0);
    let b = hemispherical_albedo(&t2, wi2, lambda, 1, Window::Rect).unwrap();
    assert!(b.evanescent_frozen > 1e-3, "{b:?}");
    assert!(
        (b.total() + b.evanescent_frozen - 1.0).abs() < 1e-12,
        "{b:?}"
    );
    // With each direction's own q: the banded integral converges as bands double, and the
    // scalar theory's patch reflectance stays within the obliquity effect of 1.
    let mut last = f64::NAN;
    for bands in [5, 9, 17, 33] {
        let c = hemispherical_albedo(&t, wi, lambda, bands, Window::Rect).unwrap();
        println!(
            "bands {bands}: coherent {:.6} scattered {:.6} total {:.8}",
            c.coherent,
            c.scattered,
            c.total()
        );
        if last.is_finite() {
            let change = (c.total() - last).abs();
            assert!(
                change < 2e-4 * (bands as f64 / 9.0).powi(-2) + 1e-12,
                "{bands}: {change}"
            );
        }
        last = c.total();
    }
    // rms slope ≈ 0.014: the Kirchhoff obliquity deficit is O(slope²).
    assert!((last - 1.0).abs() < 2e-3, "total {last}");
}

#[test]
fn tile_band_matches_the_scatter_between_realisations() {
    let synth = PointSampledKc::new(
        128,
        128,
        0.05e-6,
        KcParams {
            sigma: 0.05e-6,
            lc: 0.3e-6,
            gamma: 3.0,
        },
    );
    let opts = TileOptions {
        size: Some(32),
        ..TileOptions::default()
    };
    let q = 2.5e7;
    let zeta = (6e6, -3e6);
    let (mut vals, mut se2) = (Vec::new(), 0.0);
    let reps = 60;
    for r in 0..reps {
        let e = ExplicitBrdf::new(&synth.realise(100 + r), &opts).unwrap();
        let s = e.spectrum(zeta, q);
        vals.push(s.value);
        se2 += s.se * s.se;
    }
    let m = vals.iter().sum::<f64>() / reps as f64;
    let sd = (vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (reps - 1) as f64).sqrt();
    let rms_se = (se2 / reps as f64).sqrt();
    println!(
        "scatter between realisations {sd:.4e}, rms tile band {rms_se:.4e}, ratio {:.3}",
        sd / rms_se
    );
    // 59 degrees of freedom: the ratio of two such scale estimates lies within ±30 % at 99 %.
    assert!(
        (sd / rms_se - 1.0).abs() < 0.3,
        "scatter {sd} vs reported se {rms_se}"
    );
}

#[test]
fn band_limited_upsampling_reconstructs_between_pixels() {
    // A sum of sinusoids below the Nyquist frequency, even about the map edges (so the mirror
    // extension is smooth): the interpolated values equal the function between the pixels.
    let (n, dx) = (64, 0.5e-6);
    let l = n as f64 * dx;
    let f = |x: f64, y: f64| {
        1e-7 * ((2.0 * PI * 3.0 * (x + 0.5 * dx) / (2.0 * l)).cos()
            * (2.0 * PI * 7.0 * (y + 0.5 * dx) / (2.0 * l)).cos()
            + 0.4 * (2.0 * PI * 20.0 * (x + 0.5 * dx) / (2.0 * l)).cos())
    };
    let t = map(n, n, dx, |x, y| f(x as f64 * dx, y as f64 * dx));
    let u = fit::resample::upsample(&t, 4).unwrap();
    assert_eq!((u.nx, u.ny), (256, 256));
    assert!((u.dx - dx / 4.0).abs() < 1e-20);
    let mut worst = 0.0f64;
    for y in 0..u.ny {
        for x in 0..u.nx {
            let want = f(x as f64 * u.dx, y as f64 * u.dy);
            worst = worst.max((u.heights[y * u.nx + x] - want).abs());
        }
    }
    assert!(worst < 1e-19, "max error {worst}");
    // Original samples are kept; a profile is upsampled along x only.
    let p = map(100, 1, dx, |x, _| ((x * 37) % 11) as f64 * 1e-8);
    let up = fit::resample::upsample(&p, 3).unwrap();
    assert_eq!((up.nx, up.ny), (300, 1));
    for x in 0..100 {
        assert!((up.heights[3 * x] - p.heights[x]).abs() < 1e-20);
    }
    let c = fit::resample::crop_center(&t, 10, 20);
    assert_eq!((c.nx, c.ny), (10, 20));
    assert_eq!(c.heights[0], t.heights[22 * n + 27]);
}
