//! Conductor Fresnel and spectral n, k tables through the public API,
//! against the repository's CSV data, the data README's check values and an
//! independent complex-arithmetic Fresnel.

use std::path::PathBuf;

use brdf::{BrdfError, Fresnel, Ior, Metal};

fn csv_path(metal: Metal) -> PathBuf {
    let file = match metal {
        Metal::Cu => "ior_Cu.csv",
        Metal::Au => "ior_Au.csv",
        Metal::Ag => "ior_Ag.csv",
        Metal::Al => "ior_Al.csv",
        Metal::Fe => "ior_Fe.csv",
        Metal::Cr => "ior_Cr.csv",
        Metal::BrassCu70Zn30 => "ior_brass_Cu70Zn30.csv",
        Metal::StainlessSteel => "ior_stainless_steel_austenitic.csv",
    };
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/spectra")
        .join(file)
}

fn read_csv(metal: Metal) -> Vec<[f64; 3]> {
    let path = csv_path(metal);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("wavelength_nm,n,k"),
        "{}",
        path.display()
    );
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// Linear interpolation written independently of `Ior::at`.
fn interp(rows: &[[f64; 3]], l: f64) -> (f64, f64) {
    let i = rows
        .iter()
        .position(|r| r[0] >= l)
        .expect("λ beyond the table");
    if rows[i][0] == l || i == 0 {
        return (rows[i][1], rows[i][2]);
    }
    let (a, b) = (rows[i - 1], rows[i]);
    let t = (l - a[0]) / (b[0] - a[0]);
    ((1.0 - t) * a[1] + t * b[1], (1.0 - t) * a[2] + t * b[2])
}

fn normal_incidence(n: f64, k: f64) -> f64 {
    ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
}

#[test]
fn built_in_tables_equal_the_csv_files() {
    for m in Metal::ALL {
        let csv = read_csv(m);
        assert_eq!(
            m.table(),
            csv.as_slice(),
            "{m:?}: ior_data.rs differs from {}",
            csv_path(m).display()
        );
        let ior = Ior::metal(m);
        ior.check_covers(360.0, 830.0).unwrap();
        for i in 0..=940 {
            let l = 360.0 + 0.5 * i as f64;
            let (n, k) = ior.at(l);
            let (n2, k2) = interp(&csv, l);
            assert!(
                (n - n2).abs() < 1e-12 && (k - k2).abs() < 1e-12,
                "{m:?} at {l} nm: ({n}, {k}) vs ({n2}, {k2})"
            );
        }
    }
}

#[test]
fn normal_incidence_reflectance_matches_data_readme() {
    // data/spectra/README.md "Check values", rounded to 3 decimals.
    let table: [(Metal, [f64; 5]); 8] = [
        (Metal::Cu, [0.469, 0.538, 0.624, 0.935, 0.955]),
        (Metal::Au, [0.407, 0.408, 0.792, 0.957, 0.971]),
        (Metal::Ag, [0.964, 0.980, 0.983, 0.990, 0.993]),
        (Metal::Al, [0.924, 0.922, 0.915, 0.906, 0.897]),
        (Metal::Fe, [0.479, 0.496, 0.512, 0.531, 0.543]),
        (Metal::Cr, [0.532, 0.555, 0.555, 0.556, 0.562]),
        (Metal::BrassCu70Zn30, [0.374, 0.434, 0.789, 0.887, 0.906]),
        (Metal::StainlessSteel, [0.570, 0.603, 0.641, 0.667, 0.676]),
    ];
    for (m, want) in table {
        let f = Fresnel::conductor(Ior::metal(m));
        for (l, w) in [400.0, 450.0, 550.0, 650.0, 700.0].into_iter().zip(want) {
            let r = f.reflectance(1.0, l);
            assert!(
                (r - w).abs() <= 5.0001e-4,
                "{m:?} at {l} nm: R = {r}, README {w}"
            );
            let (n, k) = Ior::metal(m).at(l);
            assert!((r - normal_incidence(n, k)).abs() < 1e-14);
        }
    }
}

#[test]
fn copper_and_aluminium_known_values() {
    // Known values: Cu at 550 nm R ≈ 0.62, Al ≈ 0.91 (normal incidence).
    let cu = Fresnel::conductor(Ior::metal(Metal::Cu)).reflectance(1.0, 550.0);
    let al = Fresnel::conductor(Ior::metal(Metal::Al)).reflectance(1.0, 550.0);
    assert!((cu - 0.62).abs() < 0.01, "Cu: {cu}");
    assert!((al - 0.91).abs() < 0.01, "Al: {al}");
    // Copper's red-over-blue reflectance is what makes it look copper.
    let cu_red = Fresnel::conductor(Ior::metal(Metal::Cu)).reflectance(1.0, 650.0);
    assert!(cu_red > cu + 0.25, "{cu_red} vs {cu}");
}

/// Textbook complex Fresnel (s and p amplitudes, principal square root).
fn complex_fresnel(cos_i: f64, n: f64, k: f64) -> f64 {
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: C| {
        let r = a.0.hypot(a.1);
        C(
            (0.5 * (r + a.0)).sqrt(),
            (0.5 * (r - a.0)).sqrt().copysign(a.1),
        )
    };
    let eta = C(n, k);
    let sin2 = 1.0 - cos_i * cos_i;
    // cosθt = sqrt(1 − sin²θi / η²)
    let q = div(C(sin2, 0.0), mul(eta, eta));
    let cos_t = sqrt(C(1.0 - q.0, -q.1));
    let e_ct = mul(eta, cos_t);
    let rs = div(C(cos_i - e_ct.0, -e_ct.1), C(cos_i + e_ct.0, e_ct.1));
    let e_ci = C(n * cos_i, k * cos_i);
    let rp = div(
        C(e_ci.0 - cos_t.0, e_ci.1 - cos_t.1),
        C(e_ci.0 + cos_t.0, e_ci.1 + cos_t.1),
    );
    0.5 * (rs.0 * rs.0 + rs.1 * rs.1 + rp.0 * rp.0 + rp.1 * rp.1)
}

#[test]
fn oblique_incidence_matches_complex_form() {
    for m in Metal::ALL {
        for l in [380.0, 550.0, 800.0] {
            let (n, k) = Ior::metal(m).at(l);
            let f = Fresnel::conductor(Ior::metal(m));
            for i in 1..=200 {
                let c = i as f64 / 200.0;
                let (r, want) = (f.reflectance(c, l), complex_fresnel(c, n, k));
                assert!(
                    (r - want).abs() < 1e-12,
                    "{m:?} {l} nm cos {c}: {r} vs {want}"
                );
            }
        }
    }
    // A constant dielectric-like index too (k = 0, total internal reflection excluded).
    let f = Fresnel::conductor(Ior::constant(1.5, 0.0).unwrap());
    assert!((f.reflectance(1.0, 500.0) - 0.04).abs() < 1e-15);
    assert!((f.reflectance(0.5, 500.0) - complex_fresnel(0.5, 1.5, 0.0)).abs() < 1e-13);
}

#[test]
fn bounded_and_grazing_limit_over_the_whole_range() {
    for m in Metal::ALL {
        let f = Fresnel::conductor(Ior::metal(m));
        for i in 0..=470 {
            let l = 360.0 + i as f64;
            assert_eq!(f.reflectance(0.0, l), 1.0, "{m:?} {l}");
            assert!(f.reflectance(1e-9, l) > 1.0 - 1e-7, "{m:?} {l}");
            for c in [
                1e-300,
                1e-12,
                0.01,
                0.3,
                0.7,
                0.999_999,
                1.0,
                1.5,
                -0.3,
                f64::NAN,
            ] {
                let r = f.reflectance(c, l);
                assert!((0.0..=1.0).contains(&r), "{m:?} {l} nm cos {c}: {r}");
            }
        }
    }
    assert_eq!(Fresnel::One.reflectance(0.3, 500.0), 1.0);
    assert!(Fresnel::One.check_covers(1.0, 1e6).is_ok());
}

#[test]
fn user_tables_interpolate_and_reject_bad_rows() {
    let t = Ior::table(vec![
        [400.0, 1.0, 2.0],
        [500.0, 2.0, 4.0],
        [700.0, 0.5, 5.0],
    ])
    .unwrap();
    assert_eq!(t.at(450.0), (1.5, 3.0));
    assert_eq!(t.at(600.0), (1.25, 4.5));
    assert_eq!(t.at(300.0), (1.0, 2.0), "held, not extrapolated");
    assert_eq!(t.range_nm(), (400.0, 700.0));
    let f = Fresnel::conductor(t.clone());
    assert!((f.reflectance(1.0, 450.0) - normal_incidence(1.5, 3.0)).abs() < 1e-15);
    assert_eq!(
        f.check_covers(360.0, 830.0),
        Err(BrdfError::WavelengthOutOfRange {
            lambda_nm: 360.0,
            min_nm: 400.0,
            max_nm: 700.0
        })
    );

    let bad_order = Ior::table(vec![
        [400.0, 1.0, 1.0],
        [500.0, 1.0, 1.0],
        [450.0, 1.0, 1.0],
    ])
    .unwrap_err();
    assert!(
        matches!(bad_order, BrdfError::InvalidTable { row: Some(2), .. }),
        "{bad_order:?}"
    );
    let bad_n = Ior::table(vec![[400.0, 1.0, 1.0], [500.0, -1.0, 1.0]]).unwrap_err();
    assert!(
        matches!(bad_n, BrdfError::InvalidTable { row: Some(1), .. }),
        "{bad_n:?}"
    );
    assert!(bad_n.to_string().contains("row"), "{bad_n}");
    assert!(Ior::table(vec![[400.0, 1.0, f64::NAN], [500.0, 1.0, 1.0]]).is_err());
    assert!(Ior::table(vec![[400.0, 1.0, 1.0]]).is_err());

    for (n, k, name) in [
        (0.0, 1.0, "n"),
        (f64::NAN, 1.0, "n"),
        (1.0, -1.0, "k"),
        (1.0, f64::INFINITY, "k"),
    ] {
        match Ior::constant(n, k) {
            Err(BrdfError::OutOfRange { name: got, .. }) => assert_eq!(got, name),
            other => panic!("({n}, {k}): {other:?}"),
        }
    }
}

#[test]
fn metal_names_round_trip() {
    for m in Metal::ALL {
        assert_eq!(Metal::from_name(m.name()), Some(m));
        assert_eq!(Metal::from_name(&m.name().to_uppercase()), Some(m));
    }
    assert_eq!(Metal::from_name("copper"), Some(Metal::Cu));
    assert_eq!(Metal::from_name("Aluminum"), Some(Metal::Al));
    assert_eq!(Metal::from_name("unobtainium"), None);
}
