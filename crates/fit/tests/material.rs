//! The full pipeline on real files and the material file it writes: every key the renderer
//! reads is present with the documented units, the tabulated PSD integrates to σ², the
//! two-scale tables come in order, stylus merging uses the stylus below the cutoff.

use fit::io::{ReadOptions, read_path};
use fit::material_file::{self as material, Provenance};
use fit::pipeline::{Options, analyse};
use fit::two_scale::BetaSource;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

fn prov<'a>(file: &'a str, bytes: &'a [u8], stylus: Option<(&'a str, &'a [u8])>) -> Provenance<'a> {
    Provenance {
        file,
        bytes,
        stylus,
        merge_cutoff_rad_per_um: 1.0,
        metal: "stainless_steel",
        model: "ghs",
        notes: &[],
    }
}

#[test]
fn material_file_of_a_map_has_every_key_with_units() {
    let path = data("di-6.di");
    let bytes = std::fs::read(&path).unwrap();
    let scan = read_path(&path, &ReadOptions::default()).unwrap();
    let a = analyse(scan, None, &Options::default()).unwrap();
    let doc = material::build(&a, &prov("di-6.di", &bytes, None));
    let text = material::to_toml(&doc).unwrap();
    assert!(text.starts_with("# written by lustre fit\n"));
    let v: toml::Table = text.parse().unwrap();
    let m = v["material"].as_table().unwrap();
    assert_eq!(m["metal"].as_str(), Some("stainless_steel"));
    assert_eq!(m["model"].as_str(), Some("ghs"));
    let sigma_um = m["sigma_um"].as_float().unwrap();
    let lc_um = m["lc_um"].as_float().unwrap();
    // README reference (1D form, cycles): σ 1.42e-8 m, L 4.38e-7 m ⇒ Lc = L/2π.
    assert!((sigma_um / 1.42e-2 - 1.0).abs() < 0.05, "{sigma_um}");
    assert!(
        (lc_um / (4.38e-1 / (2.0 * std::f64::consts::PI)) - 1.0).abs() < 0.05,
        "{lc_um}"
    );
    assert!((m["gamma"].as_float().unwrap() / 5.166 - 1.0).abs() < 0.05);
    let (ag, ab) = (
        m["alpha"].as_float().unwrap(),
        m["alpha_beckmann"].as_float().unwrap(),
    );
    assert!(ag > 0.05 && ag < 0.5 && ab > 0.05 && ab < 0.5, "{ag} {ab}");
    let p = v["provenance"].as_table().unwrap();
    assert_eq!(
        p["sha256"].as_str(),
        Some("f6c49496857e8c1adb41caadeeda042c0a9b83b5cc24f418e1ddcc358f665295")
    );
    let range = p["fit_f_range_per_m"].as_array().unwrap();
    assert!((range[0].as_float().unwrap() / 3.0e5 - 1.0).abs() < 1e-6);
    assert!((range[1].as_float().unwrap() / 1.28e7 - 1.0).abs() < 1e-6);
    // Tables are written in the order of the cutoffs (the parsed table is sorted).
    let pos = |k: &str| {
        text.find(&format!("[two_scale.{k}]"))
            .unwrap_or_else(|| panic!("{k} missing"))
    };
    assert!(pos("cutoff_50") < pos("cutoff_100") && pos("cutoff_100") < pos("cutoff_150"));
    for t in v["two_scale"].as_table().unwrap().values() {
        for k in ["beta", "sigma_um", "lc_um", "gamma", "cutoff_um"] {
            assert!(t[k].as_float().is_some(), "two_scale key {k}");
        }
    }
    // A 10 µm AFM scan cannot resolve a 27.5 µm cutoff.
    assert!(
        a.two_scale
            .iter()
            .all(|t| t.beta_source == BetaSource::Unresolved)
    );
    // Tabulated PSD: rad/µm and µm⁴, ∫P d²ζ ≈ Sq² (the table misses only the DC bin).
    let psd = v["psd"].as_table().unwrap();
    let z = psd["zeta_rad_per_um"].as_array().unwrap();
    let pp = psd["p_um4"].as_array().unwrap();
    assert_eq!(z.len(), pp.len());
    let integral = psd["integral_um2"].as_float().unwrap();
    let sq_um = a.stats.sq * 1e6;
    assert!(
        (integral / (sq_um * sq_um) - 1.0).abs() < 0.1,
        "{integral} vs {}",
        sq_um * sq_um
    );
}

#[test]
fn large_optical_map_resolves_the_two_scale_cutoffs() {
    // The Alicona map is 1.96 mm wide: every cutoff (27.5–82.5 µm) is resolved by the map.
    let scan = read_path(&data("KautschukInfiniteFocus.x3p"), &ReadOptions::default()).unwrap();
    let a = analyse(scan, None, &Options::default()).unwrap();
    assert_eq!(a.filled, 5296);
    let mut last_beta = f64::INFINITY;
    for t in &a.two_scale {
        println!(
            "Λ {:.1} µm: β {:.4}, residual KC {:?}",
            t.cutoff * 1e6,
            t.beta,
            t.kc.params
        );
        assert_eq!(t.beta_source, BetaSource::Map);
        // A longer cutoff keeps less of the surface in the large scale: β decreases.
        assert!(
            t.beta > 0.0 && t.beta < last_beta,
            "β {} after {last_beta}",
            t.beta
        );
        last_beta = t.beta;
        // The residual (high-pass) surface has less height variance than the whole.
        assert!(t.kc.params.sigma < 2.0 * a.kc.params.sigma);
    }
}

#[test]
fn stylus_profile_supplies_the_psd_below_the_merge_cutoff() {
    let scan = read_path(&data("di-3.di"), &ReadOptions::default()).unwrap();
    let stylus = read_path(&data("dektak-1.csv"), &ReadOptions::default()).unwrap();
    let a = analyse(scan, Some(stylus), &Options::default()).unwrap();
    let sp = a.stylus_psd.as_ref().unwrap();
    let f_cut = 1e6 / (2.0 * std::f64::consts::PI);
    for (f, p) in a.fit_psd.f.iter().zip(&a.fit_psd.p) {
        let src = if *f < f_cut { sp } else { &a.line_psd };
        let i = src
            .f
            .iter()
            .position(|g| g == f)
            .expect("merged bin comes from a source PSD");
        assert_eq!(src.p[i], *p);
    }
    // The fit range starts at the stylus bin 3 and ends at the AFM bin nx/4.
    assert!(
        (a.kc.range.0 / sp.f[3] - 1.0).abs() < 1e-9,
        "{:?}",
        a.kc.range
    );
    assert!(
        (a.kc.range.1 / 6.4e6 - 1.0).abs() < 1e-9,
        "{:?}",
        a.kc.range
    );
    // The 1.5 mm profile resolves the cutoffs through its PSD.
    assert!(
        a.two_scale
            .iter()
            .all(|t| t.beta_source == BetaSource::Psd && t.beta > 0.0)
    );
    assert!(a.table.1.contains("stylus"));
}

#[test]
fn profiles_get_marginal_slope_fits() {
    let scan = read_path(&data("dektak-1.csv"), &ReadOptions::default()).unwrap();
    let a = analyse(scan, None, &Options::default()).unwrap();
    assert!(a.ndf.ndf.is_none());
    // Beckmann moment: isotropic α = √2·Rdq.
    assert!((a.ndf.alpha_beckmann_moment / (2f64.sqrt() * 0.00946) - 1.0).abs() < 0.01);
    assert!(a.ndf.alpha_beckmann.0 > 0.0 && a.ndf.alpha_ggx.0 > 0.0);
}
