//! The public test corpus of data/surfaces/corpus (28 real instrument files) against
//! REFERENCE.json (SurfaceTopography 1.27): grid and physical size exact, Sq/Sdq (Rq/Rdq
//! for profiles) within 1 % after harmonic filling and plane (line) levelling; the
//! broken files give one-line errors that name the file, what is missing and the fix.

use fit::io::{ReadOptions, Units, list_channels, open_path};
use fit::{fill, level, stats};
use serde_json::Value;
use std::path::PathBuf;

fn corpus(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces/corpus")
        .join(name)
}

fn reference() -> Vec<Value> {
    let text = std::fs::read_to_string(corpus("REFERENCE.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    v["files"].as_array().unwrap().clone()
}

fn unit_factor(u: &str) -> f64 {
    fit::io::units::length_factor(u).unwrap_or_else(|| panic!("unit {u}"))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// SurfaceTopography's uniformity test for column profiles: every x step within 1e-6
/// (file units) of the mean step.
fn st_uniform(file: &str) -> bool {
    let bytes = std::fs::read(corpus(file)).unwrap();
    let text = fit::io::text::decode(&bytes).into_owned();
    let d = fit::io::text::Dialect::guess(text.lines());
    let x: Vec<f64> = text
        .lines()
        .filter_map(|l| d.row(l))
        .map(|r| if r.len() == 3 { r[1] } else { r[0] })
        .collect();
    let step = (x[x.len() - 1] - x[0]) / (x.len() - 1) as f64;
    x.windows(2).all(|w| ((w[1] - w[0]) - step).abs() < 1e-6)
}

/// Files whose x and z units come from their column titles (µm); the reference, which
/// ignores those titles, reports their raw numbers.
const TITLE_UNITS: &[&str] = &["csv-1.csv", "csv-2.csv"];

#[test]
fn every_readable_corpus_file_matches_the_reference() {
    let mut report = Vec::new();
    for r in reference() {
        let file = r["file"].as_str().unwrap();
        if r.get("error").is_some() {
            continue;
        }
        let unitless = r["unit"].is_null();
        let mut opts = ReadOptions::default();
        let scale = if unitless && !TITLE_UNITS.contains(&file) {
            // Unitless numbers are read as micrometres: read as metres, xy-1's steps of
            // 1.4 would be 1.4 m pixels, which no surface scan has and the readers refuse.
            opts.units = Some(Units {
                lateral: 1e-6,
                height: 1e-6,
            });
            1e-6
        } else if unitless {
            1e-6
        } else {
            unit_factor(r["unit"].as_str().unwrap())
        };
        let scan = open_path(&corpus(file), &opts).unwrap_or_else(|e| panic!("{e}"));
        let t = scan.topo;
        let grid: Vec<usize> = r["nb_grid_pts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        let sizes: Vec<f64> = r["physical_sizes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() * scale)
            .collect();
        if grid.len() == 1 {
            assert_eq!((t.nx, t.ny), (grid[0], 1), "{file}: grid");
            // Column profiles: SurfaceTopography gives n·dx when the steps agree to 1e-6
            // (in file units) and the x span (n − 1)·dx otherwise; compare spans.
            let n = grid[0] as f64;
            let ref_span = if st_uniform(file) {
                sizes[0] * (n - 1.0) / n
            } else {
                sizes[0]
            };
            let span = (t.nx - 1) as f64 * t.dx;
            assert!(
                rel(span, ref_span) < 1e-6,
                "{file}: span {span:e} vs {ref_span:e}"
            );
        } else {
            assert_eq!((t.nx, t.ny), (grid[0], grid[1]), "{file}: grid");
            assert!(
                rel(t.size_x(), sizes[0]) < 1e-6 && rel(t.size_y(), sizes[1]) < 1e-6,
                "{file}: size {:e} × {:e} vs {:e} × {:e}",
                t.size_x(),
                t.size_y(),
                sizes[0],
                sizes[1]
            );
        }
        let Some(sq_ref) = r["Sq_m"].as_f64() else {
            report.push(format!("{file}: grid and size exact (no height reference)"));
            continue;
        };
        let sdq_ref = r["Sdq"].as_f64().unwrap();
        let mut p = t.clone();
        fill::harmonic(&mut p).unwrap();
        level::plane(&mut p).unwrap();
        let s = stats::compute(&p);
        let line = format!(
            "{file}: Sq {:.6e} m vs {sq_ref:.6e} ({:+.4} %), Sdq {:.6e} vs {sdq_ref:.6e} ({:+.4} %)",
            s.sq,
            100.0 * (s.sq / sq_ref - 1.0),
            s.sdq,
            100.0 * (s.sdq / sdq_ref - 1.0)
        );
        println!("{line}");
        report.push(line);
        // matrix-6 is an exact plane: both residuals are round-off, zero to 1e-12 of the
        // heights.
        let zmax = t.heights.iter().fold(0.0f64, |m, h| m.max(h.abs()));
        if sq_ref < 1e-12 * zmax {
            assert!(s.sq < 1e-12 * zmax, "{file}: Sq {} is not round-off", s.sq);
            continue;
        }
        assert!(rel(s.sq, sq_ref) < 0.01, "{file}: Sq {} vs {sq_ref}", s.sq);
        assert!(
            rel(s.sdq, sdq_ref) < 0.01,
            "{file}: Sdq {} vs {sdq_ref}",
            s.sdq
        );
    }
    println!("{}", report.join("\n"));
}

/// The corpus files that cannot be read as they are: each gives a one-line error that
/// names the file, what is missing and the flag or fix.
#[test]
fn broken_and_incomplete_files_explain_themselves() {
    let cases: &[(&str, &[&str])] = &[
        ("di_corrupted.di", &["di_corrupted.di"]),
        (
            "nonsense_txt_file.txt",
            &["nonsense_txt_file.txt", "--format"],
        ),
        (
            "matrix-5.txt",
            &["matrix-5.txt", "pixel size", "--pixel-size", "--units"],
        ),
        (
            "10x10-one_channel_without_name.ibw",
            &["10x10-one_channel_without_name.ibw", "unit", "--units"],
        ),
        ("xy-4.txt", &["xy-4.txt", "unit", "--units"]),
        ("xy-1.txt", &["xy-1.txt", "--units"]),
        ("nonuniform.asc", &["nonuniform.asc", "--units"]),
    ];
    for (file, needles) in cases {
        let e = open_path(&corpus(file), &ReadOptions::default())
            .err()
            .unwrap_or_else(|| panic!("{file}: accepted"));
        let msg = e.to_string();
        println!("{msg}");
        assert!(!msg.contains('\n'), "{file}: not one line: {msg}");
        for n in *needles {
            assert!(msg.contains(n), "{file}: `{msg}` should mention `{n}`");
        }
        assert!(msg.contains("Fix:"), "{msg}");
    }
    // With the facts supplied, the incomplete ones read.
    let o = ReadOptions {
        pixel_size: Some((1e-6, 1e-6)),
        units: Units::parse("um"),
        ..ReadOptions::default()
    };
    let t = open_path(&corpus("matrix-5.txt"), &o).unwrap().topo;
    assert_eq!((t.nx, t.ny), (10, 10));
    assert!((t.heights[0] - 2e-6).abs() < 1e-18 && t.heights[99] == 0.0);
}

#[test]
fn nonuniform_profiles_are_resampled_and_say_so() {
    let o = ReadOptions {
        units: Units::parse("um"),
        ..ReadOptions::default()
    };
    for file in ["xy-1.txt", "nonuniform.asc"] {
        let s = open_path(&corpus(file), &o).unwrap();
        assert!(
            s.notes.iter().any(|n| n.contains("resampled")),
            "{file}: {:?}",
            s.notes
        );
    }
    let s = open_path(&corpus("xy-4.txt"), &o).unwrap();
    assert!(
        !s.notes.iter().any(|n| n.contains("resampled")),
        "{:?}",
        s.notes
    );
}

#[test]
fn multi_channel_files_list_their_channels_and_default_to_height() {
    let cases: &[(&str, usize, &str)] = &[
        ("di-2.di", 3, ""),
        ("di-5.di", 2, ""),
        ("mi-1.mi", 4, "Topography"),
        ("nid-1.nid", 8, "Z-Axis"),
        ("spot_1-1000nm.ibw", 8, "HeightTrace"),
    ];
    for (file, n, default) in cases {
        let bytes = std::fs::read(corpus(file)).unwrap();
        let (_, ch) = list_channels(file, &bytes, &ReadOptions::default()).unwrap();
        println!(
            "{file}: {}",
            ch.iter()
                .map(|c| format!(
                    "{} {} [{}]{}",
                    c.index,
                    c.name,
                    c.unit,
                    if c.is_height { " height" } else { "" }
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        assert_eq!(ch.len(), *n, "{file}");
        let s = open_path(&corpus(file), &ReadOptions::default()).unwrap();
        assert!(ch[s.channel].is_height);
        assert!(
            s.topo.channel.contains(default),
            "{file}: {}",
            s.topo.channel
        );
        // A non-height channel, chosen explicitly, is refused with the list.
        if let Some(c) = ch.iter().find(|c| !c.is_height) {
            let e = open_path(
                &corpus(file),
                &ReadOptions {
                    channel: Some(fit::io::ChannelSel::Index(c.index)),
                    ..ReadOptions::default()
                },
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains("not a height") && e.contains("--channel"), "{e}");
        }
        // By name.
        let by_name = open_path(
            &corpus(file),
            &ReadOptions {
                channel: Some(fit::io::ChannelSel::Name(ch[s.channel].name.clone())),
                ..ReadOptions::default()
            },
        )
        .unwrap();
        assert_eq!(by_name.channel, s.channel);
    }
}

/// `mnt-1.mnt` and `../bcrf-1.bcrf` are one measurement in two formats.
#[test]
fn mnt_and_bcrf_agree() {
    let a = open_path(&corpus("mnt-1.mnt"), &ReadOptions::default())
        .unwrap()
        .topo;
    let b = open_path(&corpus("../bcrf-1.bcrf"), &ReadOptions::default())
        .unwrap()
        .topo;
    assert_eq!((a.nx, a.ny), (b.nx, b.ny));
    // The BCR export writes the span of the pixel centres as its length, so its pixel is
    // smaller by (n − 1)/n; the MNT stores the pixel itself.
    assert!(
        rel(a.dx * (a.nx - 1) as f64 / a.nx as f64, b.dx) < 1e-5,
        "{} {}",
        a.dx,
        b.dx
    );
    let prep = |mut t: fit::Topography| {
        fill::harmonic(&mut t).unwrap();
        level::plane(&mut t).unwrap();
        t
    };
    let (a, b) = (prep(a), prep(b));
    let (sa, sb) = (stats::compute(&a), stats::compute(&b));
    println!(
        "mnt Sq {:e} Sdq {:e}; bcrf Sq {:e} Sdq {:e}",
        sa.sq, sa.sdq, sb.sq, sb.sdq
    );
    assert!(rel(sa.sq, sb.sq) < 1e-3 && rel(sa.sdq, sb.sdq) < 2e-3);
    let d = a
        .heights
        .iter()
        .zip(&b.heights)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        / a.heights.len() as f64;
    println!("point rms difference {:e} m", d.sqrt());
    assert!(d.sqrt() < 0.01 * sa.sq, "the two files hold different maps");
}
