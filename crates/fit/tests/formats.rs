//! Formats and dialects (NanoFocus NMS, Dektak OPDx, NumPy NPY,
//! NetCDF, the `.hfm` profile export, X3P zipped in a folder or with `<Datum/>` invalid
//! points, a units line followed by a point count) against SurfaceTopography's reading of
//! the same files (`data/surfaces/reference/statistics.json`), against independent
//! encoders written here, and the formats that are named instead of "unknown".

use fit::io::{ReadOptions, Units, open_bytes, open_path, read_bytes};
use fit::{ReadError, fill, level, stats};
use proptest::prelude::*;
use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;

mod samples;
use samples::tiff;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/surfaces")
        .join(name)
}

fn reference() -> Vec<Value> {
    let text = std::fs::read_to_string(path("reference/statistics.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    v["files"].as_array().unwrap().clone()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// SurfaceTopography reads the NMS pixel spacing as millimetres where it is nanometres
/// (see `fit::io::nms`): its lengths are 10⁶ times ours, its slopes 10⁶ times smaller.
fn lateral_convention(file: &str) -> f64 {
    if file.ends_with(".nms") { 1e6 } else { 1.0 }
}

/// Every uniform file of `formats/` that SurfaceTopography reads is read here with the same
/// grid and size, and after filling and levelling Sq and the RMS slope within 1 %.
#[test]
fn every_new_format_file_matches_surface_topography() {
    let mut checked = 0;
    for r in reference() {
        let file = r["file"].as_str().unwrap();
        if !file.starts_with("formats/") || r.get("error").is_some() {
            continue;
        }
        if r.get("uniform") == Some(&Value::Bool(false)) {
            // Non-uniform profiles: SurfaceTopography integrates the piecewise-linear line,
            // lustre resamples it onto a uniform grid (a note says so); see below.
            continue;
        }
        let (opts, scale) = match r["unit"].as_str() {
            Some(u) => (
                ReadOptions::default(),
                fit::io::units::length_factor(u).unwrap(),
            ),
            None => (
                ReadOptions {
                    units: Units::parse("m"),
                    ..ReadOptions::default()
                },
                1.0,
            ),
        };
        let t = open_path(&path(file), &opts)
            .unwrap_or_else(|e| panic!("{e}"))
            .topo;
        let grid: Vec<usize> = r["nb_grid_pts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        let lat = lateral_convention(file);
        let sizes: Vec<f64> = r["physical_sizes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() * scale / lat)
            .collect();
        if grid.len() == 1 {
            assert_eq!((t.nx, t.ny), (grid[0], 1), "{file}");
        } else {
            assert_eq!((t.nx, t.ny), (grid[0], grid[1]), "{file}");
            assert!(rel(t.size_y(), sizes[1]) < 1e-6, "{file}: y size");
        }
        assert!(
            rel(t.size_x(), sizes[0]) < 1e-6,
            "{file}: x size {} vs {}",
            t.size_x(),
            sizes[0]
        );
        let mut p = t.clone();
        fill::harmonic(&mut p).unwrap();
        level::plane(&mut p).unwrap();
        let s = stats::compute(&p);
        let sq = r["Sq"].as_f64().unwrap() * scale;
        let sdq = r["Sdq"].as_f64().unwrap() * lat;
        println!(
            "{file}: Sq {:.6e} vs {sq:.6e}, slope {:.6e} vs {sdq:.6e}",
            s.sq, s.sdq
        );
        let zmax = p.heights.iter().fold(0.0f64, |m, h| m.max(h.abs()));
        if sq < 1e-9 * zmax.max(1e-30) || s.sq < 1e-12 {
            // nc-1.nc is an exact plane: both are round-off.
            assert!(s.sq <= 1e-6 * t.size_x(), "{file}: Sq {}", s.sq);
            checked += 1;
            continue;
        }
        assert!(rel(s.sq, sq) < 0.01, "{file}: Sq {} vs {sq}", s.sq);
        assert!(rel(s.sdq, sdq) < 0.01, "{file}: slope {} vs {sdq}", s.sdq);
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} files compared");
}

/// The Vision64 binary and its own text export hold the same profile.
#[test]
fn opdx_agrees_with_its_text_export() {
    let bin = open_path(&path("formats/opdx-3.opdx"), &ReadOptions::default())
        .unwrap()
        .topo;
    // Columns x, z in metres, 8 significant digits (the reader would resample the x
    // rounded to 8 digits, so the columns are compared as written).
    let text = std::fs::read_to_string(path("formats/opdx-3.txt")).unwrap();
    let rows: Vec<(f64, f64)> = text
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace().map(|v| v.parse::<f64>());
            Some((f.next()?.ok()?, f.next()?.ok()?))
        })
        .collect();
    assert_eq!(bin.nx, 3001);
    assert_eq!(rows.len(), bin.nx);
    for (i, (a, (x, z))) in bin.heights.iter().zip(&rows).enumerate() {
        assert!((a - z).abs() <= 1e-7 * z.abs() + 1e-20, "{a} vs {z}");
        assert!(
            (i as f64 * bin.dx - x).abs() <= 1e-7 * x.abs() + 1e-20,
            "x {i}"
        );
    }
}

/// `X;Y;valid` with a `[mm];[mm];[1/0]` unit row is a profile whose heights are Y, not an
/// x y z map (which it would be refused as: "not one grid step apart").
#[test]
fn hfm_profiles_take_y_as_the_height() {
    let s = open_path(&path("formats/hfm-1.hfm"), &ReadOptions::default()).unwrap();
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (9600, 1));
    assert!(rel(t.dx, 0.5e-6) < 1e-9, "dx {}", t.dx);
    assert!(rel(t.heights[0], 106.606853e-3) < 1e-12, "{}", t.heights[0]);
    // A point flagged 0 is invalid.
    let text = "X;Y;valid\n[mm];[mm];[1/0]\n0.0;1.0;1\n0.5;2.0;0\n1.0;3.0;1\n1.5;4.0;1\n";
    let t = read_bytes("p.hfm", text.as_bytes(), &ReadOptions::default()).unwrap();
    assert_eq!(t.nx, 4);
    assert!(t.heights[1].is_nan() && t.heights[2] == 3e-3);
}

/// An x/y profile with a units line, then a point-count line, then the rows (xy-2): the
/// count is not a row, and the units come from the units line.
#[test]
fn a_point_count_line_after_the_units_line_is_not_data() {
    let s = open_path(&path("formats/xy-2.txt"), &ReadOptions::default()).unwrap();
    assert_eq!(s.topo.nx, 24);
    assert!(
        s.notes.iter().any(|n| n.contains("point count of 23")),
        "{:?}",
        s.notes
    );
    let text = "µm µm\n3\n0, 1\n1, 2\n2, 4\n";
    let t = read_bytes("c.txt", text.as_bytes(), &ReadOptions::default()).unwrap();
    assert_eq!(t.nx, 3);
    assert_eq!(t.heights, vec![1e-6, 2e-6, 4e-6]);
}

/// A NumPy array in C or Fortran order, any real dtype and either byte order, written by
/// an encoder of the format description.
fn npy(shape: &[usize], descr: &str, fortran: bool, values: &[f64]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let fo = if fortran { "True" } else { "False" };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': {fo}, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((header.len() as u16).to_le_bytes());
    b.extend(header.as_bytes());
    let big = descr.starts_with('>');
    for &v in values {
        match &descr[1..] {
            "f8" if big => b.extend(v.to_be_bytes()),
            "f8" => b.extend(v.to_le_bytes()),
            "f4" if big => b.extend((v as f32).to_be_bytes()),
            "f4" => b.extend((v as f32).to_le_bytes()),
            "i2" if big => b.extend((v as i16).to_be_bytes()),
            "i2" => b.extend((v as i16).to_le_bytes()),
            "i4" => b.extend((v as i32).to_le_bytes()),
            "u2" => b.extend((v as u16).to_le_bytes()),
            d => panic!("{d}"),
        }
    }
    b
}

fn flags() -> ReadOptions {
    ReadOptions {
        units: Units::parse("um"),
        pixel_size: Some((1e-6, 1e-6)),
        ..ReadOptions::default()
    }
}

#[test]
fn npy_axes_follow_surface_topography() {
    // example-2d.npy: [[0.1, 1], [4, 7]], C order, shape (nx, ny) = (2, 2): x is the
    // first index, so along x (fastest here) the first line holds 0.1 and 4.
    let t = open_path(&path("formats/example-2d.npy"), &flags())
        .unwrap()
        .topo;
    assert_eq!(t.heights, vec![0.1e-6, 4e-6, 1e-6, 7e-6]);
    // Without the flags the missing facts are named.
    let e = open_path(&path("formats/example-2d.npy"), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("--units") && e.contains("--pixel-size"), "{e}");
    // The damaged one is refused by its signature.
    let e = open_path(&path("formats/wrongnpyfile.npy"), &flags())
        .unwrap_err()
        .to_string();
    assert!(e.contains("signature") && e.contains("npy"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Any shape, dtype, byte order and memory order reads back the array written.
    #[test]
    fn npy_round_trip(nx in 2usize..9, ny in 1usize..9, d in 0usize..6, fortran: bool, seed: u64) {
        let descr = ["<f8", ">f8", "<f4", "<i2", ">i2", "<u2"][d];
        let vals: Vec<f64> = (0..nx * ny)
            .map(|k| ((seed.wrapping_mul(k as u64 + 7) >> 40) % 2000) as f64 - if descr.ends_with("u2") { 0.0 } else { 1000.0 })
            .collect();
        // vals indexed [x][y] in the order the file stores.
        let b = npy(&[nx, ny], descr, fortran, &vals);
        let t = read_bytes("a.npy", &b, &flags()).unwrap();
        prop_assert_eq!((t.nx, t.ny), (nx, ny));
        for x in 0..nx {
            for y in 0..ny {
                let stored = if fortran { vals[x + y * nx] } else { vals[x * ny + y] };
                prop_assert!((t.heights[y * nx + x] - stored * 1e-6).abs() < 1e-12);
            }
        }
    }

    /// A NetCDF file as SurfaceTopography writes it, with a mask, a fill value and a scale.
    #[test]
    fn netcdf_round_trip(nx in 2usize..9, ny in 1usize..9, masked in 0usize..4, seed: u64) {
        let vals: Vec<f64> = (0..nx * ny).map(|k| ((seed >> (k % 50)) % 1000) as f64).collect();
        let b = netcdf(nx, ny, &vals, masked);
        let t = read_bytes("a.nc", &b, &ReadOptions::default()).unwrap();
        prop_assert_eq!((t.nx, t.ny), (nx, ny));
        prop_assert!((t.dx - 3e-6 / nx as f64).abs() < 1e-18);
        if ny > 1 {
            prop_assert!((t.dy - 5e-6 / ny as f64).abs() < 1e-18);
        }
        for x in 0..nx {
            for y in 0..ny {
                let k = x * ny + y;
                let h = t.heights[y * nx + x];
                if k == masked || vals[k] == 999.0 {
                    prop_assert!(h.is_nan());
                } else {
                    prop_assert!((h - vals[k] * 2.0e-6).abs() < 1e-15, "{} vs {}", h, vals[k]);
                }
            }
        }
    }
}

/// A NetCDF classic file: `heights(x[, y])` in µm, `_FillValue` 999,
/// `mask(x, y)` set at flat index `masked`, `x:length = 3`, `x:unit = "um"`, heights
/// scaled by 2 (`scale_factor`).
fn netcdf(nx: usize, ny: usize, vals: &[f64], masked: usize) -> Vec<u8> {
    fn name(b: &mut Vec<u8>, s: &str) {
        b.extend((s.len() as u32).to_be_bytes());
        b.extend(s.as_bytes());
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
    }
    fn text_attr(b: &mut Vec<u8>, n: &str, v: &str) {
        name(b, n);
        b.extend(2u32.to_be_bytes());
        name(b, v);
    }
    fn double_attr(b: &mut Vec<u8>, n: &str, v: f64) {
        name(b, n);
        b.extend(6u32.to_be_bytes());
        b.extend(1u32.to_be_bytes());
        b.extend(v.to_be_bytes());
    }
    let two_d = ny > 1;
    let n = nx * ny;
    let mut h = b"CDF\x01".to_vec();
    h.extend(0u32.to_be_bytes());
    h.extend(0x0Au32.to_be_bytes());
    h.extend((if two_d { 2u32 } else { 1 }).to_be_bytes());
    name(&mut h, "x");
    h.extend((nx as u32).to_be_bytes());
    if two_d {
        name(&mut h, "y");
        h.extend((ny as u32).to_be_bytes());
    }
    h.extend([0u8; 8]);
    // Variables: x (attrs only, no data needed: 0 points of the x dimension are read),
    // heights, mask. Offsets are patched once the header length is known.
    let mut vars = vec![("x", 6u32, 0), ("heights", 6, 1), ("mask", 1, 2)];
    if two_d {
        vars.push(("y", 6, 3));
    }
    h.extend(0x0Bu32.to_be_bytes());
    h.extend((vars.len() as u32).to_be_bytes());
    let dims: Vec<u32> = if two_d { vec![0, 1] } else { vec![0] };
    let mut patches = Vec::new();
    for (var, kind, attrs) in vars {
        name(&mut h, var);
        let vd: &[u32] = match var {
            "x" => &dims[..1],
            "y" => &dims[1..],
            _ => &dims,
        };
        h.extend((vd.len() as u32).to_be_bytes());
        for d in vd {
            h.extend(d.to_be_bytes());
        }
        match attrs {
            0 => {
                h.extend(0x0Cu32.to_be_bytes());
                h.extend(2u32.to_be_bytes());
                double_attr(&mut h, "length", 3.0);
                text_attr(&mut h, "unit", "um");
            }
            3 => {
                h.extend(0x0Cu32.to_be_bytes());
                h.extend(1u32.to_be_bytes());
                double_attr(&mut h, "length", 5.0);
            }
            1 => {
                h.extend(0x0Cu32.to_be_bytes());
                h.extend(2u32.to_be_bytes());
                double_attr(&mut h, "_FillValue", 999.0);
                double_attr(&mut h, "scale_factor", 2.0);
            }
            _ => h.extend([0u8; 8]),
        }
        h.extend(kind.to_be_bytes());
        h.extend(0u32.to_be_bytes());
        patches.push(h.len());
        h.extend(0u32.to_be_bytes());
    }
    let xs = h.len();
    let heights = xs + 8 * nx;
    let mask = heights + 8 * n;
    // y's values (never read) would follow the mask; it points at x's.
    for (p, off) in patches.iter().zip([xs, heights, mask, xs]) {
        h[*p..*p + 4].copy_from_slice(&(off as u32).to_be_bytes());
    }
    for i in 0..nx {
        h.extend((i as f64).to_be_bytes());
    }
    for &v in vals {
        h.extend(v.to_be_bytes());
    }
    for k in 0..n {
        h.push(u8::from(k == masked));
    }
    h
}

/// The X3P dialects published scans come in.
fn x3p(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    for (n, b) in entries {
        w.start_file(*n, o).unwrap();
        w.write_all(b).unwrap();
    }
    w.finish().unwrap().into_inner()
}

fn main_xml(nx: usize, ny: usize, data: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?><p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\
         <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType><Axes>\
         <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment><Offset>0</Offset></CX>\
         <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>2e-6</Increment><Offset>0</Offset></CY>\
         <CZ><AxisType>A</AxisType><DataType>D</DataType></CZ></Axes></Record1>\
         <Record3><MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>\
         {data}</Record3></p:ISO5436_2>"
    )
}

#[test]
fn x3p_in_a_folder_beside_macos_debris_is_read() {
    let bin: Vec<u8> = (0..6)
        .flat_map(|k| (k as f64 * 1e-7).to_le_bytes())
        .collect();
    let xml = main_xml(
        3,
        2,
        "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>",
    );
    let b = x3p(&[
        ("__MACOSX/scan/._main.xml", b"\x00\x05\x16\x07junk"),
        ("scan/main.xml", xml.as_bytes()),
        ("scan/bindata/data.bin", &bin),
        ("__MACOSX/scan/bindata/._data.bin", b"junk"),
    ]);
    let t = read_bytes("forensic.x3p", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny, t.dy), (3, 2, 2e-6));
    assert_eq!(t.heights[5], 5e-7);
}

#[test]
fn x3p_empty_datum_is_an_invalid_point_and_a_short_list_counts_points() {
    let list = "<DataList><Datum>1e-6</Datum><Datum/><Datum>3e-6</Datum><Datum></Datum></DataList>";
    let b = x3p(&[("main.xml", main_xml(2, 2, list).as_bytes())]);
    let t = read_bytes("opengps.x3p", &b, &ReadOptions::default()).unwrap();
    assert_eq!(t.heights[0], 1e-6);
    assert!(t.heights[1].is_nan() && t.heights[3].is_nan());
    assert_eq!(t.heights[2], 3e-6);
    let short = "<DataList><Datum>1e-6</Datum><Datum/></DataList>";
    let b = x3p(&[("main.xml", main_xml(2, 2, short).as_bytes())]);
    let e = read_bytes("short.x3p", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("4 points") && e.contains("holds only 2") && !e.contains("bytes"),
        "{e}"
    );
}

#[test]
fn a_zip_that_is_no_x3p_says_what_it_is() {
    let b = x3p(&[("meta.yml", b"datasets: []"), ("scan.txt", b"1 2\n3 4\n")]);
    let e = read_bytes("container.zip", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("SurfaceTopography container") && e.contains("scan.txt"),
        "{e}"
    );
    assert!(!e.contains("incomplete"), "{e}");
    let b = x3p(&[
        ("[Content_Types].xml", b"<x/>"),
        ("xl/workbook.xml", b"<x/>"),
    ]);
    let e = read_bytes("m.xlsx", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("Excel workbook"), "{e}");
    let b = x3p(&[("notes.txt", b"hello")]);
    let e = read_bytes("a.x3p", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("not an X3P file (no main.xml)") && e.contains("notes.txt"),
        "{e}"
    );
}

/// A format known by its signature but not read, or no height map at all, is named.
#[test]
fn known_but_unread_formats_are_named() {
    let o = ReadOptions::default();
    let cases: &[(&str, &[u8], &[&str])] = &[
        (
            "a.png",
            b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
            &["PNG image, not a height map"],
        ),
        (
            "a.jpg",
            b"\xFF\xD8\xFF\xE0\0\x10JFIF",
            &["JPEG image, not a height map"],
        ),
        (
            "a.nc",
            b"\x89HDF\r\n\x1a\n\0\0\0\0",
            &["NetCDF-4", "NETCDF3"],
        ),
    ];
    for (name, bytes, needles) in cases {
        let e = open_bytes(name, bytes, &o).unwrap_err();
        assert!(matches!(e, ReadError::NotRead { .. }), "{name}: {e}");
        let msg = e.to_string();
        assert!(!msg.contains("unknown surface format"), "{msg}");
        for n in *needles {
            assert!(msg.contains(n), "{name}: `{msg}` lacks `{n}`");
        }
    }
}

/// A `.gwy` written by SurfaceTopography's `to_gwy` from matrix-4.txt holds the same map.
#[test]
fn gwy_written_by_surface_topography_reads_as_its_source() {
    let g = open_path(&path("formats/matrix-4-st.gwy"), &ReadOptions::default()).unwrap();
    let m = open_path(&path("formats/matrix-4.txt"), &ReadOptions::default()).unwrap();
    assert_eq!(g.format.name(), "gwy");
    assert_eq!(g.channels[0].name, "Topography");
    let (a, b) = (g.topo, m.topo);
    assert_eq!((a.nx, a.ny), (b.nx, b.ny));
    assert!(rel(a.dx, b.dx) < 1e-12 && rel(a.dy, b.dy) < 1e-12);
    assert_eq!(a.heights, b.heights);
}

/// A `.gwy` written here from Gwyddion's format description: two channels (a phase
/// channel first, so the height channel is chosen), a mask, nm heights on µm axes.
#[test]
fn gwy_channels_units_and_masks() {
    let field = |z_unit: &str, values: &[f64]| {
        let mut c = Vec::new();
        comp(&mut c, "xres", b'i', &3i32.to_le_bytes());
        comp(&mut c, "yres", b'i', &2i32.to_le_bytes());
        comp(&mut c, "xreal", b'd', &3.0f64.to_le_bytes());
        comp(&mut c, "yreal", b'd', &4.0f64.to_le_bytes());
        comp(&mut c, "si_unit_xy", b'o', &unit("µm"));
        comp(&mut c, "si_unit_z", b'o', &unit(z_unit));
        let mut d = (values.len() as u32).to_le_bytes().to_vec();
        values.iter().for_each(|v| d.extend(v.to_le_bytes()));
        comp(&mut c, "data", b'D', &d);
        object("GwyDataField", &c)
    };
    let mut top = Vec::new();
    comp(&mut top, "/0/data/title", b's', b"Phase\0");
    comp(&mut top, "/0/data", b'o', &field("deg", &[0.0; 6]));
    comp(&mut top, "/1/data/title", b's', b"Height\0");
    comp(
        &mut top,
        "/1/data",
        b'o',
        &field("nm", &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
    );
    comp(
        &mut top,
        "/1/mask",
        b'o',
        &field("", &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
    );
    let mut b = b"GWYP".to_vec();
    b.extend(object("GwyContainer", &top));
    let s = open_bytes("two.gwy", &b, &ReadOptions::default()).unwrap();
    assert_eq!(s.channel, 1);
    assert!(!s.channels[0].is_height && s.channels[1].is_height);
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (3, 2));
    assert!(rel(t.dx, 1e-6) < 1e-12 && rel(t.dy, 2e-6) < 1e-12);
    assert!(t.heights[1].is_nan());
    assert!(rel(t.heights[5], 6e-9) < 1e-12);
    // Cut anywhere, it is refused with one line, never a panic.
    for cut in 0..b.len() {
        let e = open_bytes("cut.gwy", &b[..cut], &ReadOptions::default());
        if let Err(e) = e {
            assert!(!e.to_string().contains('\n'));
        }
    }
}

fn comp(out: &mut Vec<u8>, name: &str, kind: u8, value: &[u8]) {
    out.extend(name.as_bytes());
    out.push(0);
    out.push(kind);
    out.extend(value);
}

fn object(name: &str, components: &[u8]) -> Vec<u8> {
    let mut o = name.as_bytes().to_vec();
    o.push(0);
    o.extend((components.len() as u32).to_le_bytes());
    o.extend(components);
    o
}

fn unit(s: &str) -> Vec<u8> {
    let mut c = Vec::new();
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    comp(&mut c, "unitstr", b's', &v);
    object("GwySIUnit", &c)
}

/// A VK4 file written from the format description (`fit::io::vk4`): 16-bit heights on a
/// 0.25 µm × 0.5 µm grid, 2 nm per digit.
pub fn vk4(w: u32, h: u32, bits: u32, values: &[u32]) -> Vec<u8> {
    let mut b = b"VK4_".to_vec();
    b.extend(1u32.to_le_bytes());
    b.extend(0u32.to_le_bytes());
    let conditions = 12 + 17 * 4 + 4;
    let layer = conditions + 4 * 100;
    let mut table = [0u32; 17];
    table[0] = conditions as u32;
    table[6] = layer as u32;
    table.iter().for_each(|v| b.extend(v.to_le_bytes()));
    b.extend(0u32.to_le_bytes());
    let mut cond = [0u32; 100];
    cond[0] = 400;
    cond[42] = 250_000;
    cond[43] = 500_000;
    cond[44] = 2000;
    cond.iter().for_each(|v| b.extend(v.to_le_bytes()));
    let bytes = w * h * bits / 8;
    for v in [w, h, bits, 0, bytes, 0, 0] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u8; 768]);
    for &v in values {
        match bits {
            8 => b.push(v as u8),
            16 => b.extend((v as u16).to_le_bytes()),
            _ => b.extend(v.to_le_bytes()),
        }
    }
    b
}

#[test]
fn vk4_and_its_vk6_wrapper_read_from_the_format_description() {
    for bits in [8, 16, 32] {
        let vals: Vec<u32> = (0..12).map(|i| i * 7 + 1).collect();
        let b = vk4(4, 3, bits, &vals);
        let t = read_bytes("a.vk4", &b, &ReadOptions::default()).unwrap();
        assert_eq!((t.nx, t.ny), (4, 3));
        assert!(rel(t.dx, 0.25e-6) < 1e-12 && rel(t.dy, 0.5e-6) < 1e-12);
        assert!(rel(t.heights[5], 36.0 * 2e-9) < 1e-12, "{}", t.heights[5]);
        // Cut anywhere: refused, one line, no panic.
        for cut in 0..b.len() {
            if let Err(e) = read_bytes("a.vk4", &b[..cut], &ReadOptions::default()) {
                assert!(!e.to_string().contains('\n'));
            } else {
                panic!("read cut at {cut}");
            }
        }
    }
    // VK6: its magic, then a zip whose Vk4File entry is the VK4 file.
    let inner = vk4(4, 3, 16, &[5; 12]);
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    w.start_file("Vk4File", zip::write::SimpleFileOptions::default())
        .unwrap();
    w.write_all(&inner).unwrap();
    let zipped = w.finish().unwrap().into_inner();
    let mut b = b"VK6_".to_vec();
    b.extend(zipped);
    let t = read_bytes("a.vk6", &b, &ReadOptions::default()).unwrap();
    assert_eq!(t.heights, vec![10e-9; 12]);
}

/// A KLA Zeta ZMG file written from the format description (`fit::io::zmg`).
pub fn zmg(nx: u32, ny: u32, values: &[i16]) -> Vec<u8> {
    let mut b = b"Zeta-Instruments".to_vec();
    b.resize(85, 0);
    b.extend(nx.to_le_bytes());
    b.extend(ny.to_le_bytes());
    b.extend([0u8; 4]);
    for v in [0.5f32, 0.25, 0.002] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u8; 8]);
    b.extend(5u32.to_le_bytes());
    b.resize(205, 0);
    b.extend(b"hello");
    values.iter().for_each(|v| b.extend(v.to_le_bytes()));
    b
}

/// A Keyence ZON (KPK0) file written from the format description (`fit::io::zon`): a
/// 10-byte thumbnail, then the zip with the unit XML and the heights (rows padded to 4
/// extra bytes).
pub fn zon(w: i32, h: i32, values: &[i32]) -> Vec<u8> {
    let mut zw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    zw.start_file("686613b8-27b5-4a29-8ffc-438c2780873e", o)
        .unwrap();
    zw.write_all(b"<?xml version=\"1.0\"?><Calibration><XYCalibration><MeterPerPixel>2.5e-7</MeterPerPixel></XYCalibration><ZCalibration><MeterPerUnit>1e-9</MeterPerUnit></ZCalibration></Calibration>").unwrap();
    zw.start_file("4cdb0c75-5706-48cc-a9a1-adf395d609ae", o)
        .unwrap();
    let row = 4 * w + 4;
    for v in [w, h, 4, row] {
        zw.write_all(&v.to_le_bytes()).unwrap();
    }
    for y in 0..h as usize {
        for x in 0..w as usize {
            zw.write_all(&values[y * w as usize + x].to_le_bytes())
                .unwrap();
        }
        zw.write_all(&[0xEE; 4]).unwrap();
    }
    let zipped = zw.finish().unwrap().into_inner();
    let mut b = b"KPK0".to_vec();
    b.extend(10u32.to_le_bytes());
    b.extend([0x42u8; 10]);
    b.extend(zipped);
    b
}

#[test]
fn zmg_and_zon_read_from_the_format_descriptions() {
    let vals: Vec<i16> = (0..12).map(|i| i * 3 - 10).collect();
    let b = zmg(4, 3, &vals);
    let t = read_bytes("a.zmg", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (4, 3));
    assert!(rel(t.dx, 0.5e-6) < 1e-7 && rel(t.dy, 0.25e-6) < 1e-7);
    assert!(
        rel(t.heights[11], 23.0 * 0.002e-6) < 1e-6,
        "{}",
        t.heights[11]
    );
    for cut in 0..b.len() {
        assert!(read_bytes("a.zmg", &b[..cut], &ReadOptions::default()).is_err());
    }
    let vals: Vec<i32> = (0..15).map(|i| i * 1000 - 7000).collect();
    let b = zon(5, 3, &vals);
    let t = read_bytes("a.zon", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (5, 3));
    assert!(rel(t.dx, 2.5e-7) < 1e-12);
    assert!(rel(t.heights[14], 7000e-9) < 1e-12, "{}", t.heights[14]);
    assert!(rel(t.heights[5], -2000e-9) < 1e-12, "{}", t.heights[5]);
    for cut in 0..b.len() {
        if let Err(e) = read_bytes("a.zon", &b[..cut], &ReadOptions::default()) {
            assert!(!e.to_string().contains('\n'));
        } else {
            panic!("read cut at {cut}");
        }
    }
}

fn ascii(s: &str) -> (u16, u32, Vec<u8>) {
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    (2, v.len() as u32, v)
}

/// A JPK scan: a preview page with the scan size (3 µm × 2 µm), a height channel (int32,
/// default slot "calibrated": 2 nm per count plus 1 µm) and an error-signal channel in V.
pub fn jpk(nx: u32, ny: u32, counts: &[i32]) -> Vec<u8> {
    let e = |tag: u16, (kind, count, v): (u16, u32, Vec<u8>)| (tag, kind, count, v);
    let d = |v: f64| (12u16, 1u32, v.to_le_bytes().to_vec());
    let u = |v: u32| (4u16, 1u32, v.to_le_bytes().to_vec());
    let preview = vec![
        e(256, u(1)),
        e(257, u(1)),
        e(258, u(8)),
        e(0x8000, ascii("jpk 1.0")),
        e(0x8042, d(3e-6)),
        e(0x8043, d(2e-6)),
    ];
    let channel = |name: &str, unit: &str, bits: u32, format: u32| {
        vec![
            e(256, u(nx)),
            e(257, u(ny)),
            e(258, u(bits)),
            e(339, u(format)),
            e(0x8050, ascii(name)),
            e(0x8052, ascii(&format!("{name} (measured)"))),
            e(0x8081, ascii("calibrated")),
            e(0x8090, ascii("nominal")),
            e(0x80A2, ascii(unit)),
            e(0x80A3, ascii("LinearScaling")),
            e(0x80A4, d(1e-9)),
            e(0x80C0, ascii("calibrated")),
            e(0x80D2, ascii(unit)),
            e(0x80D3, ascii("LinearScaling")),
            e(0x80D4, d(2e-9)),
            e(0x80D5, d(1e-6)),
        ]
    };
    let strip: Vec<u8> = counts.iter().flat_map(|c| c.to_le_bytes()).collect();
    let volts: Vec<u8> = counts
        .iter()
        .flat_map(|c| (*c as f32).to_le_bytes())
        .collect();
    tiff(&[
        (preview, vec![0]),
        (channel("vDeflection", "V", 32, 3), volts),
        (channel("height", "m", 32, 2), strip),
    ])
}

#[test]
fn jpk_channels_slots_and_scaling_from_the_description() {
    let counts: Vec<i32> = (0..12).map(|i| i * 5 - 20).collect();
    let b = jpk(4, 3, &counts);
    let s = open_bytes("scan.jpk", &b, &ReadOptions::default()).unwrap();
    assert_eq!(s.format.name(), "jpk");
    assert_eq!(s.channel, 1, "the height channel, not the deflection");
    assert_eq!(s.channels[0].unit, "V");
    assert!(!s.channels[0].is_height && s.channels[1].is_height);
    assert_eq!(s.channels[1].name, "height (measured)");
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (4, 3));
    assert!(rel(t.dx, 0.75e-6) < 1e-12 && rel(t.dy, 2e-6 / 3.0) < 1e-12);
    assert!(
        rel(t.heights[11], 35.0 * 2e-9 + 1e-6) < 1e-12,
        "{}",
        t.heights[11]
    );
    // Named .tif it still reads by content; the Park reader, forced, points to jpk.
    assert_eq!(
        open_bytes("scan.tif", &b, &ReadOptions::default())
            .unwrap()
            .format
            .name(),
        "jpk"
    );
    let park = ReadOptions {
        format: fit::io::Format::from_name("park"),
        ..ReadOptions::default()
    };
    let e = open_bytes("scan.tif", &b, &park).unwrap_err().to_string();
    assert!(e.contains("--format jpk"), "{e}");
    for cut in 0..b.len() {
        if let Err(e) = open_bytes("scan.jpk", &b[..cut], &ReadOptions::default()) {
            assert!(!e.to_string().contains('\n'));
        } else {
            panic!("read cut at {cut}");
        }
    }
}
