//! What can make a readable scan's numbers wrong: a scan mostly invalid (refused with a
//! way on: crop or fill), spikes from corrupted bytes (found, located, flagged, maskable), a
//! text export cut inside its last number, and heights or lengths read in the wrong unit.

use fit::io::{ReadOptions, Units, open_path, read_bytes};
use fit::kc::KcParams;
use fit::pipeline::{Checks, Options, analyse, summarise, summarise_checked};
use fit::quality::{self, InvalidPolicy};
use fit::{Topography, synth};

#[allow(dead_code)] // only its provenance is used here
mod common;

fn kc(n: usize, dx: f64, sigma: f64, lc: f64, seed: u64) -> Topography {
    synth::kc_surface(
        n,
        n,
        dx,
        KcParams {
            sigma,
            lc,
            gamma: 3.0,
        },
        seed,
    )
}
use std::path::PathBuf;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

fn read(name: &str) -> Topography {
    open_path(&path(name), &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .topo
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// sur-3.sur: 89 % of its points invalid. Refused by default, naming both ways on; cropped
/// to its largest valid rectangle, or filled (then as SurfaceTopography fills it), each
/// flagged.
#[test]
fn a_mostly_invalid_scan_is_refused_with_the_overrides_named() {
    let t = read("formats/sur-3.sur");
    let e = summarise(t.clone(), None).unwrap_err().to_string();
    assert!(e.contains("88.9 %"), "{e}");
    assert!(
        e.contains("--invalid crop") && e.contains("--invalid fill"),
        "{e}"
    );
    assert!(
        e.contains("largest valid rectangle (189 × 52 points, 3.7 % of the scan)"),
        "{e}"
    );

    let crop = Checks {
        invalid: InvalidPolicy::Crop,
        ..Checks::default()
    };
    let s = summarise_checked(t.clone(), None, &crop).unwrap();
    let (w, h) = (s.prepared.scan.nx, s.prepared.scan.ny);
    assert_eq!(s.prepared.filled, 0, "a valid rectangle needs no filling");
    let rect = quality::largest_valid_rectangle(&t).unwrap();
    assert_eq!((rect.2, rect.3), (w, h));
    let msg = s.quality.invalid.unwrap();
    assert!(
        msg.contains("--invalid crop") && msg.contains(&format!("{w} × {h}")),
        "{msg}"
    );

    let fill = Checks {
        invalid: InvalidPolicy::Fill,
        ..Checks::default()
    };
    let s = summarise_checked(t, None, &fill).unwrap();
    // SurfaceTopography 1.27.1 (harmonic filling, plane): Sq 7.457411280238834e-4 m.
    assert!(
        rel(s.stats.sq, 7.457411280238834e-4) < 1e-6,
        "{}",
        s.stats.sq
    );
    assert!(s.quality.invalid.unwrap().contains("--invalid fill"));
    // The material file flags it.
    let opts = Options {
        checks: fill,
        ..Options::default()
    };
    let a = analyse(read("formats/sur-3.sur"), None, &opts).unwrap();
    let doc = fit::material_file::build(&a, &common::prov("scan"));
    assert!(doc.reliability.invalid.contains("filled anyway"));
    assert!(doc.reliability.unreliable.contains(&"invalid".to_string()));
}

/// The largest valid rectangle against brute force over every rectangle of small random
/// masks.
#[test]
fn largest_valid_rectangle_is_the_largest() {
    let mut rng = fit::rng::SplitMix64::new(7);
    for _ in 0..300 {
        let nx = 1 + (rng.next_u64() % 7) as usize;
        let ny = 1 + (rng.next_u64() % 7) as usize;
        let p = (rng.next_u64() % 100) as f64 / 100.0;
        let heights: Vec<f64> = (0..nx * ny)
            .map(|_| {
                if (rng.next_u64() % 1000) as f64 / 1000.0 < p {
                    f64::NAN
                } else {
                    1.0
                }
            })
            .collect();
        let t = Topography {
            nx,
            ny,
            dx: 1.0,
            dy: 1.0,
            heights,
            channel: String::new(),
            format: "test",
        };
        let mut best = 0;
        for x0 in 0..nx {
            for y0 in 0..ny {
                for x1 in x0..nx {
                    for y1 in y0..ny {
                        let ok =
                            (y0..=y1).all(|y| (x0..=x1).all(|x| t.heights[y * nx + x].is_finite()));
                        if ok {
                            best = best.max((x1 - x0 + 1) * (y1 - y0 + 1));
                        }
                    }
                }
            }
        }
        match quality::largest_valid_rectangle(&t) {
            None => assert_eq!(best, 0),
            Some((x0, y0, w, h)) => {
                assert_eq!(w * h, best, "{nx}×{ny}");
                let c = quality::crop(&t, (x0, y0, w, h));
                assert!(c.heights.iter().all(|v| v.is_finite()));
            }
        }
    }
}

/// 8 corrupted bytes in metropro-1.dat (its last two phase values set to 0x10000000)
/// raise Sq from 13 nm to 46 µm. They are found, located, flagged in
/// the summary and the material file, and `--outliers mask` restores Sq.
#[test]
fn corrupted_values_are_found_located_and_maskable() {
    let good = std::fs::read(path("corpus/metropro-1.dat")).unwrap();
    let mut bad = good.clone();
    let n = bad.len();
    for k in [n - 8, n - 4] {
        bad[k..k + 4].copy_from_slice(&0x1000_0000i32.to_be_bytes());
    }
    let o = ReadOptions::default();
    let t_good = read_bytes("metropro-1.dat", &good, &o).unwrap();
    let t_bad = read_bytes("metropro-1.dat", &bad, &o).unwrap();
    let g = summarise(t_good, None).unwrap();
    let sq_good = g.stats.sq;
    assert!(rel(sq_good, 1.3334981370330638e-8) < 0.01);
    // The file as published has a few spikes of its own (its Sku is 52), which the
    // corrupted values, tilting the levelled plane, partly hide.
    println!("as published: {:?}", g.quality.outliers);
    let s = summarise(t_bad.clone(), None).unwrap();
    assert!(
        s.stats.sq > 100.0 * sq_good,
        "the corruption must matter: {}",
        s.stats.sq
    );
    let msg = s.quality.outliers.clone().unwrap();
    println!("corrupted: {msg}");
    assert!(msg.contains("(638, 479), (639, 479)"), "{msg}");
    let share: f64 = msg
        .split("they carry ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(share > 99.0, "{msg}");
    assert!(msg.contains("--outliers mask"), "{msg}");
    let mask = Checks {
        mask_outliers: true,
        ..Checks::default()
    };
    let m = summarise_checked(t_bad.clone(), None, &mask).unwrap();
    assert!(
        rel(m.stats.sq, sq_good) < 0.01,
        "{} vs {sq_good}",
        m.stats.sq
    );
    assert!(m.quality.outliers.unwrap().starts_with("masked"));
    let a = analyse(t_bad, None, &Options::default()).unwrap();
    let doc = fit::material_file::build(&a, &common::prov("scan"));
    assert!(doc.reliability.outliers.contains("robust σ"));
    assert!(doc.reliability.unreliable.contains(&"outliers".to_string()));
}

/// Gaussian heights of every size and roughness have no outliers at 12 robust σ (the
/// threshold cannot fire on a sound scan), and any single spike of ≥ 20 σ is found.
#[test]
fn sound_gaussian_scans_have_no_outliers_and_any_large_spike_is_found() {
    for seed in 0..6u64 {
        let (n, sigma) = (64 << (seed % 3), 1e-9 * 10f64.powi(seed as i32 % 4));
        let t = kc(n, 1e-7, sigma, 2e-6, seed);
        assert!(quality::outliers(&t).is_none(), "seed {seed}");
        let mut spiked = t.clone();
        let i = (seed as usize * 977) % (n * n);
        spiked.heights[i] += 20.0 * sigma * if seed % 2 == 0 { 1.0 } else { -1.0 };
        let o = quality::outliers(&spiked).expect("spike found");
        assert_eq!(o.indices, vec![i], "seed {seed}");
    }
}

/// A Dektak profile cut inside its last number (`16.58112` → `16.`) still parses, as would
/// a column or matrix export: such a cut is refused.
#[test]
fn a_text_export_cut_inside_its_last_number_is_refused() {
    let whole = std::fs::read(path("dektak-1.csv")).unwrap();
    let at = whole.windows(8).rposition(|w| w == b"16.58112").unwrap();
    let cut = &whole[..at + 3];
    assert!(cut.ends_with(b"16."));
    let e = read_bytes("dektak-1.csv", cut, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("ends inside a number (`16.`)") && e.contains("cut short"),
        "{e}"
    );
    assert!(e.contains("line 96"), "{e}");
    let o = ReadOptions {
        units: Units::parse("um"),
        ..ReadOptions::default()
    };
    for (name, t) in [
        ("p.xyz", "0 1\n1 2\n2 3.5e"),
        ("m.txt", "1 2 3\n4 5 6\n7 8 9."),
    ] {
        let e = read_bytes(name, t.as_bytes(), &o).unwrap_err().to_string();
        assert!(e.contains("cut short"), "{name}: {e}");
    }
    // A whole file without a final line break is still read.
    assert!(read_bytes("p.xyz", b"0 1\n1 2\n2 3.5", &o).is_ok());
}

/// `--units um` on metre heights (Sq 5.6e-14 m) and `--units m` on micrometre heights
/// (Sq 0.05 m) read without complaint. Both are flagged with
/// the factor and the `--units` that makes Sq and the slope plausible.
#[test]
fn heights_in_the_wrong_unit_are_flagged_with_the_right_units() {
    let t = kc(128, 2e-7, 5e-8, 3e-6, 1);
    let text: String = (0..128)
        .map(|y| {
            (0..128)
                .map(|x| format!("{:e}", t.heights[y * 128 + x]))
                .collect::<Vec<_>>()
                .join(" ")
                + "\n"
        })
        .collect();
    let read_as = |units: &str, values: &str| {
        let o = ReadOptions {
            units: Units::parse(units),
            pixel_size: Some((2e-7, 2e-7)),
            ..ReadOptions::default()
        };
        let scan = read_bytes("m.txt", values.as_bytes(), &o).unwrap();
        let checks = Checks {
            units: o.units,
            ..Checks::default()
        };
        summarise_checked(scan, None, &checks).unwrap()
    };
    // Metre values read as µm: Sq 5e-14 m.
    let s = read_as("um", &text);
    let msg = s.quality.units.unwrap();
    assert!(
        msg.contains("below one atom") && msg.contains("×1e6"),
        "{msg}"
    );
    assert!(msg.contains("--units um,m"), "{msg}");
    // The same numbers in µm read as metres: Sq 5e-8·1e6 m.
    let um_text: String = text
        .split_whitespace()
        .map(|v| format!("{:e} ", v.parse::<f64>().unwrap() * 1e6))
        .collect();
    let um_text = um_text
        .split(' ')
        .collect::<Vec<_>>()
        .chunks(128)
        .map(|c| c.join(" ") + "\n")
        .collect::<String>();
    let s = read_as("m", &um_text);
    let msg = s.quality.units.unwrap();
    assert!(
        msg.contains("×1e-6") && msg.contains("--units m,um"),
        "{msg}"
    );
    // Read right, nothing is flagged.
    assert!(read_as("m", &text).quality.units.is_none());
}

/// The plausibility window over its whole domain: every Sq in [0.05 nm, 1 mm] with a slope
/// at most 10 passes; outside it a rescaling is named that lands inside.
#[test]
fn implausible_units_sweep() {
    let mut k = 0;
    for e_sq in -16..=2 {
        for e_slope in -6..=9 {
            let (sq, slope) = (3.0 * 10f64.powi(e_sq), 2.0 * 10f64.powi(e_slope));
            let r = quality::implausible_units(sq, slope, 1e-7, None);
            let plausible = (5e-11..=1e-3).contains(&sq) && slope <= 10.0;
            assert_eq!(r.is_none(), plausible, "Sq {sq} slope {slope}: {r:?}");
            if let Some(m) = r {
                assert!(
                    m.contains("would give Sq") || m.contains("no rescaling"),
                    "{m}"
                );
                k += 1;
            }
        }
    }
    assert!(k > 50);
}
