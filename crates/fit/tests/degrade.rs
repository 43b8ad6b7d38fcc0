//! Analysis that degrades instead of dying: levelling choices
//! and form detection, tiny maps, fits that do not converge or hit a bound, anisotropy,
//! and material files whose every parameter the renderer accepts.

use brdf::spec::ModelKind;
use fit::io::{ReadOptions, read_path};
use fit::kc::{Degeneracy, KcParams};
use fit::level::{self, Level};
use fit::material_file::{self as material, Provenance};
use fit::pipeline::{Options, analyse, summarise};
use fit::rng::Normal;
use fit::{Topography, stats, synth};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

fn prov<'a>(file: &'a str, bytes: &'a [u8], notes: &'a [String]) -> Provenance<'a> {
    Provenance {
        file,
        bytes,
        stylus: None,
        merge_cutoff_rad_per_um: 1.0,
        metal: "stainless_steel",
        model: "auto",
        notes,
    }
}

/// Every number the renderer reads from a material file must pass the renderer's own
/// constructors.
fn assert_renderer_accepts(doc: &brdf::spec::MaterialFile, what: &str) {
    let m = &doc.material;
    let v = |x: Option<f64>| x.unwrap_or(f64::NAN);
    brdf::statistics::KcPsd::new(v(m.sigma_um), v(m.lc_um), v(m.gamma))
        .unwrap_or_else(|e| panic!("{what}: [material] KC rejected: {e}"));
    brdf::Distribution::ggx(v(m.alpha), v(m.alpha)).unwrap_or_else(|e| panic!("{what}: alpha {e}"));
    brdf::Distribution::beckmann(v(m.alpha_beckmann), v(m.alpha_beckmann))
        .unwrap_or_else(|e| panic!("{what}: alpha_beckmann {e}"));
    if let (Some(x), Some(y)) = (m.alpha_x, m.alpha_y) {
        brdf::Distribution::ggx(x, y).unwrap_or_else(|e| panic!("{what}: alpha_x/y {e}"));
    }
    for (name, t) in &doc.two_scale.0 {
        brdf::statistics::KcPsd::new(t.sigma_um, t.lc_um, t.gamma)
            .unwrap_or_else(|e| panic!("{what}: {name} KC {e}"));
        assert!(t.lc_um <= 1e5, "{what}: {name} lc {}", t.lc_um);
        brdf::statistics::epd::ExponentialNdf::new(t.beta)
            .unwrap_or_else(|e| panic!("{what}: {name} β {e}"));
    }
    let usable = doc.psd.as_ref().is_some_and(|p| p.usable);
    if let Some(p) = doc.psd.as_ref().filter(|p| p.usable) {
        brdf::statistics::TabulatedPsd::new(&p.zeta_rad_per_um, &p.p_um4)
            .unwrap_or_else(|e| panic!("{what}: psd {e}"));
    }
    if m.model == Some(ModelKind::MeasuredPsd) {
        assert!(usable, "{what}: model measured_psd with an unusable table");
    }
    // Every model of the file builds through brdf::spec, as a scene include does.
    let built = material::check(doc).unwrap_or_else(|e| panic!("{what}: check: {e}"));
    assert!(
        built.len() >= 4 + doc.two_scale.0.len(),
        "{what}: {} built",
        built.len()
    );
    // The document round-trips through TOML, value for value.
    let text = material::to_toml(doc).unwrap();
    // (TOML tables come back sorted by name: compare the splits in that order.)
    let mut back: brdf::spec::MaterialFile = toml::from_str(&text).unwrap();
    let mut want = doc.clone();
    want.two_scale.0.sort_by(|a, b| a.0.cmp(&b.0));
    back.two_scale.0.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(
        back == want,
        "{what}: the file does not read back as written"
    );
}

fn map(nx: usize, ny: usize, dx: f64, f: impl Fn(f64, f64) -> f64) -> Topography {
    let mut h = Vec::with_capacity(nx * ny);
    for y in 0..ny {
        for x in 0..nx {
            h.push(f(x as f64 * dx, y as f64 * dx));
        }
    }
    Topography {
        nx,
        ny,
        dx,
        dy: dx,
        heights: h,
        channel: "test".into(),
        format: "synthetic",
    }
}

/// `bcrf-1.bcrf`: an unbounded fit runs to γ = 72007. The fit is bounded and flagged, and
/// the material file holds only values the renderer accepts.
#[test]
fn bcrf_fit_is_bounded_flagged_and_renderable() {
    let path = data("bcrf-1.bcrf");
    let bytes = std::fs::read(&path).unwrap();
    let scan = read_path(&path, &ReadOptions::default()).unwrap();
    let a = analyse(scan, None, &Options::default()).unwrap();
    println!(
        "bcrf KC: {:?} degenerate {} {:?} asymptote {:?}",
        a.kc.params, a.kc.degenerate, a.kc.reason, a.kc.asymptote
    );
    assert!(a.kc.degenerate);
    assert!(a.kc.params.gamma <= 100.0 && a.kc.params.gamma >= 1.001);
    let asym = a.kc.asymptote.unwrap();
    assert!(asym.exponent.is_finite() && asym.prefactor > 0.0);
    let doc = material::build(&a, &prov("bcrf-1.bcrf", &bytes, &[]));
    assert_renderer_accepts(&doc, "bcrf-1");
    assert!(doc.fit.kc_degenerate && doc.fit.kc_reason.is_some());
    assert!(doc.reliability.unreliable.contains(&"kc".to_string()));
    assert_ne!(
        doc.material.model,
        ModelKind::from_name("ghs"),
        "auto must not pick GHS on a degenerate fit"
    );
    let text = material::to_toml(&doc).unwrap();
    assert!(text.contains("# WARNING: unreliable parts: kc"), "{text}");
}

/// Every real file of data/surfaces gives a renderable material file.
#[test]
fn material_files_of_the_real_scans_are_renderable() {
    for f in [
        "di-3.di",
        "di-6.di",
        "matrix-3.txt",
        "dektak-1.csv",
        "KautschukInfiniteFocus.x3p",
        "corpus/txt_example.txt",
        "corpus/example_ps.tiff",
        "corpus/frt-1.frt",
        "corpus/sur-2.sur",
    ] {
        let path = data(f);
        let bytes = std::fs::read(&path).unwrap();
        let scan = read_path(&path, &ReadOptions::default()).unwrap();
        let a = analyse(scan, None, &Options::default()).unwrap_or_else(|e| panic!("{f}: {e}"));
        let doc = material::build(&a, &prov(f, &bytes, &[]));
        println!(
            "{f}: model {:?} KC {} unreliable {:?}",
            doc.material.model, doc.reliability.kc, doc.reliability.unreliable
        );
        assert_renderer_accepts(&doc, f);
    }
}

/// A 6 × 3 map (and a 2 × 2 one) gives statistics, a PSD and a material file.
#[test]
fn tiny_maps_give_statistics_and_a_psd() {
    let t = read_path(&data("corpus/txt_example.txt"), &ReadOptions::default()).unwrap();
    let s = summarise(t.clone(), None).unwrap();
    assert!(s.stats.sq > 0.0 && s.stats.sdq > 0.0);
    assert_eq!(s.line_psd.f.len(), 4);
    assert!(s.line_psd.p.iter().all(|p| p.is_finite()));
    assert_eq!(s.kc.reason, Some(Degeneracy::TooFewPoints));
    // The fallback: σ = Sq.
    assert!((s.kc.params.sigma / s.stats.sq - 1.0).abs() < 1e-12);
    let a = analyse(t, None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov("txt_example.txt", b"", &[]));
    assert_renderer_accepts(&doc, "txt_example");
    // On a 2 × 2 grid y² = y, so this is a plane: nothing is left once it is removed.
    let plane = map(2, 2, 1e-6, |x, y| {
        1e-9 * (x * 1e6 + 2.0 * y * 1e6 * y * 1e6)
    });
    let s = summarise(plane.clone(), Some(Level::None)).unwrap();
    assert!(s.stats.sq > 0.0 && s.flat.is_none());
    let e = analyse(plane, None, &Options::default()).unwrap_err();
    assert!(e.to_string().contains("constant (to rounding)"), "{e}");
    let tiny = map(2, 2, 1e-6, |x, y| 1e-9 * (x * 1e6 + 3.0 * x * y * 1e12));
    analyse(tiny, None, &Options::default()).unwrap();
}

/// A pure power law (the roll-off far below the band) and white noise: the fit is
/// degenerate with a reason, the statistics stand, and the high-frequency asymptote of
/// the power law is its exponent.
#[test]
fn power_laws_and_noise_degrade_to_bounded_estimates() {
    let truth = KcParams {
        sigma: 10e-9,
        lc: 1.0,
        gamma: 3.0,
    };
    let t = synth::kc_profile(8192, 10e-9, truth, 7);
    let s = summarise(t, None).unwrap();
    println!(
        "power law: {:?} {:?} {:?}",
        s.kc.params, s.kc.reason, s.kc.asymptote
    );
    assert!(s.kc.degenerate);
    let asym = s.kc.asymptote.unwrap();
    assert!((asym.exponent - 3.0).abs() < 0.15, "{}", asym.exponent);
    // White noise: a flat line PSD.
    let mut rng = fit::rng::SplitMix64::new(3);
    let noise = Topography {
        nx: 4096,
        ny: 1,
        dx: 1e-7,
        dy: 1e-7,
        heights: (0..4096).map(|_| 1e-9 * rng.normal()).collect(),
        channel: "noise".into(),
        format: "synthetic",
    };
    let s = summarise(noise.clone(), None).unwrap();
    println!(
        "noise: {:?} {:?} {:?}",
        s.kc.params, s.kc.reason, s.kc.asymptote
    );
    assert!((s.stats.sq / 1e-9 - 1.0).abs() < 0.05);
    assert!(s.kc.degenerate, "white noise is no K-correlation surface");
    assert!(s.kc.asymptote.unwrap().exponent.abs() < 0.5);
    let a = analyse(noise, None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov("noise", b"", &[]));
    assert_renderer_accepts(&doc, "noise");
}

/// Plane + paraboloid + K-correlation roughness: `poly2` removes the form and recovers σ
/// within 2 %; a plane leaves form, and the output says so.
#[test]
fn poly2_levelling_recovers_sigma_under_a_curved_form() {
    let truth = KcParams {
        sigma: 5e-9,
        lc: 20e-9,
        gamma: 4.0,
    };
    let n = 512;
    let dx = 10e-9;
    let mut t = synth::kc_surface(n, n, dx, truth, 11);
    let c = 0.5 * (n - 1) as f64 * dx;
    for y in 0..n {
        for x in 0..n {
            let (u, v) = (x as f64 * dx - c, y as f64 * dx - c);
            // 2 mrad tilt and a 50 µm radius bowl (≈ 65 nm deep over the scan, 13 σ).
            t.heights[y * n + x] += 2e-3 * u - 1e-3 * v + (u * u + 0.6 * v * v) / (2.0 * 0.05e-3);
        }
    }
    let mut plane = t.clone();
    let f1 = level::apply(&mut plane, Level::Plane).unwrap();
    let mut quad = t.clone();
    let f2 = level::apply(&mut quad, Level::Poly2).unwrap();
    let (s1, s2) = (stats::compute(&plane), stats::compute(&quad));
    println!(
        "plane: Sq {:e}, residual form {:?}, {:?}\npoly2: Sq {:e}, residual form {:?}",
        s1.sq,
        f1.residual_form,
        f1.warning(),
        s2.sq,
        f2.residual_form
    );
    assert!(
        (s2.sq / truth.sigma - 1.0).abs() < 0.02,
        "Sq {} vs σ {}",
        s2.sq,
        truth.sigma
    );
    assert!(s1.sq > 3.0 * truth.sigma);
    let w = f1.warning().expect("a plane leaves the bowl");
    assert!(w.contains("--level poly2"), "{w}");
    assert!(f2.warning().is_none(), "{:?}", f2.warning());
    // The fitted form is the imposed one plus the roughness's own low-order content
    // (levelling is linear): tilt 2e-3 and −1e-3, c₂₀ = 1/(2R), c₀₂ = 0.6/(2R).
    let mut rough = synth::kc_surface(n, n, dx, truth, 11);
    let fr = level::apply(&mut rough, Level::Poly2).unwrap();
    let term = |f: &level::Form, i, j| f.terms.iter().find(|t| t.i == i && t.j == j).unwrap().c;
    let imposed = |i, j| term(&f2, i, j) - term(&fr, i, j);
    let r = 0.05e-3;
    for (i, j, want) in [
        (1, 0, 2e-3),
        (0, 1, -1e-3),
        (2, 0, 1.0 / (2.0 * r)),
        (0, 2, 0.6 / (2.0 * r)),
        (1, 1, 0.0),
    ] {
        let got = imposed(i, j);
        assert!(
            (got - want).abs() <= 1e-7 * want.abs().max(1.0),
            "term x^{i} y^{j}: {got} vs {want}"
        );
    }
    // The KC fit of the poly2-levelled map recovers σ as well.
    let s = summarise(t, Some(Level::Poly2)).unwrap();
    println!("KC after poly2: {:?}", s.kc.params);
    assert!(!s.kc.degenerate);
    // Random surfaces with Lc ≪ scan show no form after a plane either.
    let mut r = synth::kc_surface(256, 256, dx, truth, 5);
    let f = level::apply(&mut r, Level::Plane).unwrap();
    assert!(f.warning().is_none(), "{:?}", f.residual_form);
}

/// Grooves along 30° (a brushed surface): the anisotropy report finds the lay, the ratio
/// and gives anisotropic α; an isotropic surface is not flagged.
#[test]
fn anisotropy_finds_the_lay_of_a_grooved_surface() {
    let theta = 30f64.to_radians();
    let (c, s) = (theta.cos(), theta.sin());
    let mut rng = fit::rng::SplitMix64::new(9);
    let waves: Vec<(f64, f64, f64)> = (0..40)
        .map(|k| {
            let lambda = 0.2e-6 * (1.0 + k as f64 * 0.37);
            (
                2.0 * std::f64::consts::PI / lambda,
                2.0 * std::f64::consts::PI * rng.uniform(),
                1e-9 * lambda / 1e-6,
            )
        })
        .collect();
    let grooved = map(256, 256, 20e-9, |x, y| {
        // Across the grooves: the direction perpendicular to the lay (at 30° + 90°).
        let u = -x * s + y * c;
        waves
            .iter()
            .map(|(k, p, a)| a * (k * u + p).sin())
            .sum::<f64>()
    });
    let mut g = grooved.clone();
    level::apply(&mut g, Level::Plane).unwrap();
    let a = summarise(g.clone(), Some(Level::None))
        .unwrap()
        .anisotropy
        .unwrap();
    println!(
        "grooved: slopes x {:.4} y {:.4}, principal {:?}, ratio {:.2}, slope dir {:.2}°, lay {:.2}°; {}; {:?}",
        a.rms_slope_x,
        a.rms_slope_y,
        a.principal,
        a.ratio,
        a.slope_direction_deg,
        a.lay_direction_deg(),
        a.flag_source,
        a.kc.as_ref()
            .map(|k| k.as_ref().map(|f| (f.params, f.rms_log_residual)))
    );
    assert!(a.anisotropic && a.ratio > 10.0);
    assert!(
        (a.lay_direction_deg() - 30.0).abs() < 1.0,
        "{}",
        a.lay_direction_deg()
    );
    let (ax, ay) = a.beckmann();
    assert!(ax > 10.0 * ay);
    // Material file: anisotropic α and the warning.
    let an = analyse(grooved, None, &Options::default()).unwrap();
    let doc = material::build(&an, &prov("grooved", b"", &[]));
    assert_renderer_accepts(&doc, "grooved");
    assert!(doc.material.alpha_x.is_some() && doc.material.alpha_y.is_some());
    let at = doc.anisotropy.as_ref().unwrap();
    assert!(at.warning.as_ref().unwrap().contains("approximation"));
    assert!(
        doc.reliability
            .unreliable
            .contains(&"anisotropy".to_string())
    );
    // Isotropic: ratio near 1.
    let iso = synth::kc_surface(
        256,
        256,
        10e-9,
        KcParams {
            sigma: 5e-9,
            lc: 30e-9,
            gamma: 4.0,
        },
        2,
    );
    let a = summarise(iso, None).unwrap().anisotropy.unwrap();
    println!("isotropic: ratio {:.3}, x/y {:.3}", a.ratio, a.ratio_xy);
    assert!(!a.anisotropic && a.ratio < 1.2);
    // The PSD slopes agree with the finite-difference ones to the band limit.
    assert!((a.psd_slopes.0 / a.rms_slope_x - 1.0).abs() < 0.25);
}

/// The K-correlation σ is the model's rms height over all frequencies; where a sound fit
/// leaves most of the measured variance outside its band the material file must say so
/// (σ far below Sq renders the surface smoother than measured), and a surface the model
/// describes must not be flagged.
#[test]
fn sigma_far_from_sq_is_flagged_and_a_kc_surface_is_not() {
    let truth = KcParams {
        sigma: 5e-9,
        lc: 20e-9,
        gamma: 4.0,
    };
    let (n, dx) = (256, 10e-9);
    let kc = synth::kc_surface(n, n, dx, truth, 3);
    let a = analyse(kc.clone(), None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov("kc", b"", &[]));
    println!(
        "KC surface: σ {:?} µm, Sq {} µm, variance {}",
        doc.material.sigma_um, doc.fit.sq_um, doc.reliability.variance
    );
    assert_eq!(doc.reliability.variance, "ok");
    assert!(!doc.reliability.unreliable.contains(&"variance".into()));

    // A real AFM scan whose sound K-correlation fit (bins 3 … n/4) holds under 1 % of the
    // measured variance: the rest is at longer wavelengths (SurfaceTopography's Sq for it
    // is 7.1 nm, the fit's σ 0.63 nm).
    let f = "corpus/nid-1.nid";
    let path = data(f);
    let bytes = std::fs::read(&path).unwrap();
    let a = analyse(
        read_path(&path, &ReadOptions::default()).unwrap(),
        None,
        &Options::default(),
    )
    .unwrap();
    let doc = material::build(&a, &prov(f, &bytes, &[]));
    let v = &doc.reliability.variance;
    println!(
        "{f}: σ {:?} µm, Sq {} µm, model {:?}, kc {}, variance {v}",
        doc.material.sigma_um, doc.fit.sq_um, doc.material.model, doc.reliability.kc
    );
    assert_eq!(doc.reliability.kc, "ok");
    assert!(doc.fit.sq_um > 4.0 * doc.material.sigma_um.unwrap());
    assert!(
        v.contains("holds") && v.contains("% of the measured height"),
        "{v}"
    );
    assert!(doc.reliability.unreliable.contains(&"variance".into()));
    assert_eq!(doc.material.model, ModelKind::from_name("ghs"));
    assert!(doc.reliability.model.contains("[reliability].variance"));
    let text = material::to_toml(&doc).unwrap();
    assert!(
        text.lines()
            .any(|l| l.starts_with("variance = ") && l.contains("the K-correlation σ")),
        "{text}"
    );
    assert_renderer_accepts(&doc, f);

    // The threshold is a factor 2 either way, and values that are not positive and
    // finite are not judged.
    let band = (1e5, 1e7);
    assert!(material::variance_mismatch(1.0, 1.9, band, true).is_none());
    assert!(material::variance_mismatch(1.9, 1.0, band, true).is_none());
    let low = material::variance_mismatch(1.0, 2.1, band, true).unwrap();
    assert!(
        low.contains("22.68 %") && low.contains("1.000e-1–1.000e1 µm"),
        "{low}"
    );
    let high = material::variance_mismatch(2.1, 1.0, band, true).unwrap();
    assert!(high.contains("2.10×"), "{high}");
    // The measured PSD is suggested only where its table builds.
    assert!(low.contains("measured_psd") && high.contains("measured_psd"));
    for (s, q) in [(1.0, 2.1), (2.1, 1.0)] {
        let w = material::variance_mismatch(s, q, band, false).unwrap();
        assert!(!w.contains("measured_psd"), "{w}");
    }
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(material::variance_mismatch(bad, 1.0, band, true).is_none());
        assert!(material::variance_mismatch(1.0, bad, band, true).is_none());
    }
    let no_band = material::variance_mismatch(1.0, 3.0, (f64::NAN, 1.0), true).unwrap();
    assert!(!no_band.contains("(wavelengths"), "{no_band}");
}

/// A map that varies along one direction only (ideal grooves) has an infinite principal
/// slope ratio: the material file says what that means instead of "ratio inf", and leaves
/// the unknown numbers out instead of writing `inf`, `nan` or a −1 sentinel.
#[test]
fn a_map_flat_along_its_lay_has_no_inf_or_sentinel_in_its_material_file() {
    let (n, dx) = (128, 10e-9);
    let mut rng = fit::rng::SplitMix64::new(4);
    // Random grooves along y: the same random profile on every line.
    let profile: Vec<f64> = (0..n).map(|_| 2e-9 * rng.normal()).collect();
    let t = map(n, n, dx, |x, _| profile[(x / dx).round() as usize]);
    let a = analyse(t, None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov("grooves", b"", &[]));
    let text = material::to_toml(&doc).unwrap();
    let an = doc
        .anisotropy
        .as_ref()
        .expect("a map has an anisotropy table");
    assert!(an.anisotropic);
    assert_eq!(an.ratio, None, "an infinite ratio is left out");
    let w = an.warning.as_ref().unwrap();
    assert!(w.contains("no slope at all along the lay"), "{w}");
    for line in text.lines() {
        let value = line.split_once(" = ").map_or("", |(_, v)| v);
        assert!(
            !(value.contains("inf") || value.contains("nan") || value.trim() == "-1.0"),
            "{line}"
        );
    }
    assert_renderer_accepts(&doc, "grooves");
}

/// `[reliability].psd_extrapolation` says which band the `[psd]` table measures and what the
/// measured-PSD model assumes outside it, with the numbers the renderer uses.
#[test]
fn the_psd_tails_the_renderer_assumes_are_stated() {
    let truth = KcParams {
        sigma: 5e-9,
        lc: 20e-9,
        gamma: 4.0,
    };
    let (n, dx) = (256, 10e-9);
    let a = analyse(
        synth::kc_surface(n, n, dx, truth, 3),
        None,
        &Options::default(),
    )
    .unwrap();
    let doc = material::build(&a, &prov("kc", b"", &[]));
    let e = &doc.reliability.psd_extrapolation;
    println!("{e}");
    let psd = doc.psd.as_ref().unwrap();
    assert!(psd.usable);
    let t = brdf::statistics::TabulatedPsd::new(&psd.zeta_rad_per_um, &psd.p_um4).unwrap();
    let (lo, hi) = t.band_rad_per_um();
    assert!(e.starts_with("assumed, not measured"), "{e}");
    assert!(
        e.contains(&format!("{lo:.4}–{hi:.4} rad/µm"))
            && e.contains(&format!("ζ^{:.3}", t.high_slope())),
        "{e}"
    );
    let text = material::to_toml(&doc).unwrap();
    assert!(
        text.lines().any(|l| l.starts_with("psd_extrapolation = ")),
        "{text}"
    );
}
