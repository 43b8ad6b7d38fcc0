//! Inputs that cannot give honest numbers are refused with the reason and the fix, or
//! flagged: mostly invalid maps, constant heights, single points; single columns are
//! profiles like single rows; text files no sniffer accepts get their reader's own error.

use fit::io::{ReadOptions, Units, read_bytes};
use fit::pipeline::{Options, analyse, summarise};
use fit::{FitError, Topography};

fn map(nx: usize, ny: usize, f: impl Fn(usize, usize) -> f64) -> Topography {
    Topography {
        nx,
        ny,
        dx: 1e-7,
        dy: 1e-7,
        heights: (0..nx * ny).map(|i| f(i % nx, i / nx)).collect(),
        channel: "test".into(),
        format: "test",
    }
}

/// Rough, deterministic heights of about 10 nm.
fn rough(x: usize, y: usize) -> f64 {
    let h = (x as u64 * 7919 + y as u64 * 104_729) % 1009;
    1e-8 * (h as f64 / 1009.0 - 0.5) + 1e-9 * ((x * 3 + y) as f64).sin()
}

fn gsf(nx: usize, ny: usize, values: &[f32]) -> Vec<u8> {
    let mut b = format!(
        "Gwyddion Simple Field 1.0\nXRes = {nx}\nYRes = {ny}\nXReal = 1e-5\nYReal = 1e-5\n\
         XYUnits = m\nZUnits = m\n"
    )
    .into_bytes();
    b.push(0);
    while b.len() % 4 != 0 {
        b.push(0);
    }
    for v in values {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

#[test]
fn a_mostly_invalid_map_is_refused_with_its_invalid_fraction() {
    // 90 % NaN: filling it halves Sq while the fit still looks sound.
    let t = map(40, 40, |x, y| {
        if (x + 40 * y) % 10 == 0 {
            rough(x, y)
        } else {
            f64::NAN
        }
    });
    for e in [
        summarise(t.clone(), None).unwrap_err(),
        analyse(t, None, &Options::default()).unwrap_err(),
    ] {
        let msg = e.to_string();
        assert!(
            msg.contains("90.0 %") && msg.contains("Fix:") && msg.contains("crop"),
            "{msg}"
        );
    }
}

#[test]
fn a_partly_invalid_map_is_kept_with_a_note() {
    let t = map(40, 40, |x, y| if x < 12 { f64::NAN } else { rough(x, y) });
    let a = analyse(t.clone(), None, &Options::default()).unwrap();
    assert!(
        a.notes
            .iter()
            .any(|n| n.contains("30.0 % of the points were invalid")),
        "{:?}",
        a.notes
    );
    let s = summarise(t, None).unwrap();
    assert!(
        s.notes.iter().any(|n| n.contains("30.0 %")),
        "{:?}",
        s.notes
    );
}

#[test]
fn constant_heights_are_refused() {
    let exact = map(32, 32, |_, _| 3e-7);
    // Rounding noise only: a constant written in decimal and read back.
    let rounded = map(32, 32, |x, y| {
        1e-7 * (1.0 + f64::EPSILON * ((x * y) % 3) as f64)
    });
    let plane = map(32, 32, |x, y| 2e-7 + 1e-9 * x as f64 - 3e-9 * y as f64);
    let profile = map(64, 1, |_, _| 0.0);
    for (name, t) in [
        ("exact", exact),
        ("rounded", rounded),
        ("plane", plane),
        ("profile", profile),
    ] {
        let msg = analyse(t.clone(), None, &Options::default())
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("constant (to rounding)") && msg.contains("Fix:"),
            "{name}: {msg}"
        );
        // Statistics of a flat surface are true (Sq ≈ 0); they come with the reason.
        let s = summarise(t, None).unwrap();
        assert!(
            s.flat.as_deref().is_some_and(|f| f.contains("constant")),
            "{name}"
        );
    }
    // Real roughness on a large offset is not mistaken for rounding.
    let offset = map(32, 32, |x, y| 1e-3 + rough(x, y));
    assert!(summarise(offset.clone(), None).unwrap().flat.is_none());
    assert!(analyse(offset, None, &Options::default()).is_ok());
}

#[test]
fn a_single_column_is_a_profile_and_a_single_point_is_refused() {
    let col = map(1, 64, |_, y| rough(y, 0));
    let row = map(64, 1, |x, _| rough(x, 0));
    let a = summarise(col, None).unwrap();
    let b = summarise(row, None).unwrap();
    assert_eq!((a.prepared.scan.nx, a.prepared.scan.ny), (64, 1));
    assert_eq!(a.stats.sq, b.stats.sq);
    assert!(summarise(map(1, 1, |_, _| 1e-8), None).is_err());

    // The same through a reader: an x spacing for one column means nothing.
    let v: Vec<f32> = (0..64).map(|y| rough(y, 0) as f32).collect();
    let t = read_bytes("c.gsf", &gsf(1, 64, &v), &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (64, 1));
    assert!((t.dx - 1e-5 / 64.0).abs() < 1e-18 && t.dx == t.dy);
    let e = read_bytes("p.gsf", &gsf(1, 1, &[1e-8]), &ReadOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("p.gsf") && msg.contains("single point"),
        "{msg}"
    );
}

#[test]
fn stylus_errors_are_told_apart_from_scan_errors() {
    let scan = map(64, 64, rough);
    let flat = map(256, 1, |_, _| 1e-6);
    let e = analyse(scan, Some(flat), &Options::default()).unwrap_err();
    assert!(matches!(e, FitError::Stylus(_)), "{e}");
    assert!(e.to_string().starts_with("stylus profile: "), "{e}");
}

#[test]
fn undetected_text_files_get_their_readers_own_error() {
    let row: Vec<String> = (0..32).map(|x| format!("{:e}", rough(x, 0))).collect();
    let header = "# Channel: Test\n# Width: 10 µm\n# Height: 10 µm\n# Value units: m\n";
    // A one-row matrix is a profile.
    let one_row = format!("{header}{}\n", row.join("\t"));
    let t = read_bytes("r.txt", one_row.as_bytes(), &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (32, 1));
    // A ragged matrix: the row that is short, not "unknown format".
    let mut ragged = header.to_string();
    for y in 0..12 {
        let n = if y == 5 { 29 } else { 32 };
        ragged.push_str(&row[..n].join("\t"));
        ragged.push('\n');
    }
    let e = read_bytes("g.txt", ragged.as_bytes(), &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("has 29 values"), "{e}");
    // A one-value matrix reaches the single-point check.
    let one = format!("{header}1e-8\n");
    let e = read_bytes("o.txt", one.as_bytes(), &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("single point"), "{e}");
    // A two-point x,z profile is a column file.
    let m = ReadOptions {
        units: Units::parse("um"),
        ..ReadOptions::default()
    };
    let two = "x (um),z (um)\n0.0,-0.015\n0.1,0.021\n";
    let t = read_bytes("t.csv", two.as_bytes(), &m).unwrap();
    assert_eq!((t.nx, t.ny), (2, 1));
    let e = read_bytes("t.csv", &two.as_bytes()[..25], &m).unwrap_err();
    assert!(e.to_string().contains("fewer than two data lines"), "{e}");
    // Text without numbers and binary junk are still of unknown format.
    for (name, b) in [
        ("n.txt", &b"hello\nworld\n"[..]),
        ("x.bin", &[0u8, 1, 2, 3, 255][..]),
    ] {
        let e = read_bytes(name, b, &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, fit::ReadError::UnknownFormat { .. }), "{e}");
    }
}
