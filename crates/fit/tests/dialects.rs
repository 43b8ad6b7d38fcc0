//! The text dialects instruments and spreadsheets write, each checked value by value:
//! `key=value`, `key: value` and `# key: value` headers (English and German), height
//! conversion factors, decimal commas, tabs and semicolons, unit titles and unit rows,
//! validity columns, UTF-16 with and without BOM, non-uniform profiles, and the flags
//! for what a file leaves out.

use fit::io::{ReadOptions, Units, open_bytes};

fn read(name: &str, text: &[u8], o: &ReadOptions) -> fit::io::Scan {
    open_bytes(name, text, o).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1e-30)
}

fn utf16(s: &str, little: bool, bom: bool) -> Vec<u8> {
    let mut out = Vec::new();
    if bom {
        out.extend(if little { [0xff, 0xfe] } else { [0xfe, 0xff] });
    }
    for u in s.encode_utf16() {
        out.extend(if little {
            u.to_le_bytes()
        } else {
            u.to_be_bytes()
        });
    }
    out
}

#[test]
fn key_value_header_with_height_conversion_factor() {
    let f = "Surface export\nx-pixels = 4\ny-pixels = 3\npixel size = 0.5 um\n\
             height conversion factor (-> um) = 0.001\n\
             1 2 3 4\n5 6 7 8\n9 10 11 12\n";
    let s = read("kv.asc", f.as_bytes(), &ReadOptions::default());
    assert_eq!(s.format.name(), "matrix");
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (4, 3));
    assert!(close(t.dx, 0.5e-6) && close(t.dy, 0.5e-6));
    assert!(close(t.heights[5], 6e-9), "{}", t.heights[5]);
}

#[test]
fn colon_header_without_hash_and_decimal_commas_in_tabs() {
    let f = "Width: 10 um\nHeight: 4 um\nValue units: nm\n1,5\t2,5\t3,5\n4,5\t5,5\t6,5\n";
    let t = read("colon.txt", f.as_bytes(), &ReadOptions::default()).topo;
    assert_eq!((t.nx, t.ny), (3, 2));
    assert!(close(t.dx, 10e-6 / 3.0) && close(t.dy, 2e-6));
    assert!(close(t.heights[4], 5.5e-9), "{}", t.heights[4]);
}

#[test]
fn german_gwyddion_export_with_decimal_commas() {
    let f = "# Kanal: Höhe\n# Breite: 12,34 µm\n# Höhe: 5,6789 µm\n# Value units: nm\n\
             1,5 3\n-2 0,25\n";
    let t = read("de.txt", f.as_bytes(), &ReadOptions::default()).topo;
    assert_eq!((t.nx, t.ny, t.channel.as_str()), (2, 2, "Höhe"));
    assert!(close(t.dx, 6.17e-6) && close(t.dy, 5.6789e-6 / 2.0));
    assert!(close(t.heights[0], 1.5e-9) && close(t.heights[3], 0.25e-9));
}

#[test]
fn phase_channels_are_not_heights() {
    let f = "# Channel: Phase\n# Width: 1 um\n# Value units: deg\n1 2 3 4\n5 6 7 8\n";
    let e = open_bytes("phase.txt", f.as_bytes(), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("deg") && e.contains("not a height"), "{e}");
}

#[test]
fn semicolon_csv_with_a_unit_row_and_decimal_commas() {
    let f = "x;y;z\nµm;µm;nm\n0,0;0,0;1,5\n0,5;0,0;2,5\n1,0;0,0;3,5\n\
             0,0;0,25;4,5\n0,5;0,25;5,5\n1,0;0,25;6,5\n";
    let s = read("semi.csv", f.as_bytes(), &ReadOptions::default());
    assert_eq!(s.format.name(), "xyz");
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (3, 2));
    assert!(close(t.dx, 0.5e-6) && close(t.dy, 0.25e-6));
    assert!(close(t.heights[5], 6.5e-9));
}

fn profile_with_validity() -> String {
    "x [mm],z [um],valid\n0.000,1.0,1\n0.001,2.0,1\n0.002,30.0,0\n0.003,4.0,1\n0.004,5.0,1\n"
        .to_string()
}

#[test]
fn bracket_units_and_a_validity_column() {
    let s = read(
        "v.csv",
        profile_with_validity().as_bytes(),
        &ReadOptions::default(),
    );
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (5, 1));
    assert!(close(t.dx, 1e-6));
    assert!(close(t.heights[1], 2e-6) && t.heights[2].is_nan());
    assert!(s.notes.iter().any(|n| n.contains("valid")), "{:?}", s.notes);
}

#[test]
fn utf16_with_and_without_bom_in_both_byte_orders() {
    let text = profile_with_validity();
    for (little, bom) in [(true, true), (true, false), (false, true), (false, false)] {
        let b = utf16(&text, little, bom);
        let t = read("u16.csv", &b, &ReadOptions::default()).topo;
        assert_eq!(t.nx, 5, "little {little} bom {bom}");
        assert!(close(t.heights[3], 4e-6) && t.heights[2].is_nan());
    }
}

#[test]
fn tab_titles_with_parenthesised_units() {
    let f = "Lateral (µm)\tHeight (nm)\n0\t1\n0.2\t2\n0.4\t3\n0.6\t4\n";
    let t = read("tab.txt", f.as_bytes(), &ReadOptions::default()).topo;
    assert!(close(t.dx, 0.2e-6) && close(t.heights[3], 4e-9));
}

#[test]
fn missing_units_need_the_flag_and_the_flag_supplies_them() {
    let f = "0 1\n1 2\n2 3\n3 5\n";
    let e = open_bytes("bare.txt", f.as_bytes(), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("bare.txt") && e.contains("--units"), "{e}");
    let o = ReadOptions {
        units: Units::parse("um,nm"),
        ..ReadOptions::default()
    };
    let t = read("bare.txt", f.as_bytes(), &o).topo;
    assert!(close(t.dx, 1e-6) && close(t.heights[3], 5e-9));
}

#[test]
fn flags_override_or_are_ignored_and_say_so() {
    let f = "# Width: 10 um\n# Value units: nm\n1 2 3 4\n5 6 7 8\n";
    let o = ReadOptions {
        pixel_size: Some((1e-6, 2e-6)),
        units: Units::parse("mm"),
        ..ReadOptions::default()
    };
    let s = read("m.txt", f.as_bytes(), &o);
    assert!(close(s.topo.dx, 1e-6) && close(s.topo.dy, 2e-6));
    // The file's nm win over --units mm.
    assert!(close(s.topo.heights[1], 2e-9));
    assert!(s.notes.iter().any(|n| n.contains("--pixel-size overrides")));
    assert!(s.notes.iter().any(|n| n.contains("--units ignored")));
    let o = ReadOptions {
        size: Some((40e-6, 20e-6)),
        ..ReadOptions::default()
    };
    let t = read("m.txt", f.as_bytes(), &o).topo;
    assert!(close(t.dx, 10e-6) && close(t.dy, 10e-6));
}

#[test]
fn non_uniform_profiles_are_resampled_exactly_for_a_line() {
    let f = "x (um),z (um)\n0,0\n1,1\n3,3\n4,4\n";
    let s = read("nu.csv", f.as_bytes(), &ReadOptions::default());
    assert!(
        s.notes.iter().any(|n| n.contains("resampled")),
        "{:?}",
        s.notes
    );
    let t = s.topo;
    assert_eq!(t.nx, 4);
    assert!(close(t.dx, 4e-6 / 3.0));
    for (i, h) in t.heights.iter().enumerate() {
        assert!((h - i as f64 * 4e-6 / 3.0).abs() < 1e-18, "{i}: {h}");
    }
    // Rounded but uniform x (printed to 4 decimals) is not resampled.
    let r: String = (0..50)
        .map(|i| format!("{:.4},{}\n", i as f64 / 3.0, i % 3))
        .collect();
    let s = read(
        "r.csv",
        format!("x (mm),z (um)\n{r}").as_bytes(),
        &ReadOptions::default(),
    );
    assert!(
        !s.notes.iter().any(|n| n.contains("resampled")),
        "{:?}",
        s.notes
    );
}

#[test]
fn index_columns_are_dropped() {
    let f = "index,x in µm,y in µm\n0,10,1\n1,10.5,2\n2,11,3\n";
    let t = read("idx.csv", f.as_bytes(), &ReadOptions::default()).topo;
    assert_eq!((t.nx, t.ny), (3, 1));
    assert!(close(t.dx, 0.5e-6) && close(t.heights[2], 3e-6));
}
