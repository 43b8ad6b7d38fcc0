//! Hostile input for every reader: truncated files, bit flips and headers that claim huge
//! grids must give errors, never panics or giant allocations. Also round trips of the
//! formats without a real sample in data/surfaces (GSF, SDF, BCR int16, XYZ), written here
//! by independent encoders.

use fit::ReadError;
use fit::io::{ChannelSel, Format, ReadOptions, Units, read_bytes};
use fit::rng::SplitMix64;
use std::io::Write;
use std::path::PathBuf;

mod samples;
use samples::{jpk_sample, zmg_sample, zon_sample};

fn data(name: &str) -> Vec<u8> {
    std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/surfaces")
            .join(name),
    )
    .unwrap()
}

fn fmt(name: &str) -> Format {
    Format::from_name(name).unwrap()
}

fn opts(format: Format) -> ReadOptions {
    ReadOptions {
        format: Some(format),
        units: Units::parse("m"),
        ..ReadOptions::default()
    }
}

/// Truncations at many lengths and random bit flips: must return (Ok or Err) without panicking,
/// and any Ok result must have consistent dimensions.
fn torture(name: &str, bytes: &[u8], format: Format, seed: u64, flips: usize) {
    let o = opts(format);
    let check = |b: &[u8], what: &str| {
        if let Ok(t) = read_bytes(name, b, &o) {
            assert_eq!(t.heights.len(), t.nx * t.ny, "{name} {what}");
            assert!(
                t.dx > 0.0 && t.dx.is_finite() && t.dy > 0.0 && t.dy.is_finite(),
                "{name} {what}"
            );
            assert!(
                t.heights.len() <= 8 * b.len().max(1) + 64,
                "{name} {what}: more points than bytes"
            );
        }
    };
    let n = bytes.len();
    let mut cuts: Vec<usize> = (0..64).map(|i| i * n / 64).collect();
    cuts.extend([
        1,
        2,
        7,
        80,
        81,
        82,
        100,
        2048,
        4095,
        4096,
        4097,
        40960,
        n.saturating_sub(1),
    ]);
    for c in cuts.into_iter().filter(|&c| c < n) {
        check(&bytes[..c], &format!("truncated at {c}"));
        // Formats whose header fixes the data size must reject a file cut in half (text
        // formats can legitimately hold less data). A NanoScope file cut short must be
        // refused too, even where the channel read is still whole.
        if ["x3p", "bcr", "sdf", "gsf", "nanoscope"].contains(&format.name()) && c < n / 2 {
            assert!(
                read_bytes(name, &bytes[..c], &o).is_err(),
                "{name}: truncated file at {c} accepted"
            );
        }
    }
    let mut rng = SplitMix64::new(seed);
    for i in 0..flips {
        let mut b = bytes.to_vec();
        // Flip bits, biased to the header where parsing decisions are made.
        for _ in 0..1 + (rng.next_u64() % 8) {
            let region = if rng.next_u64().is_multiple_of(2) {
                n.min(4096)
            } else {
                n
            };
            let pos = (rng.next_u64() as usize) % region;
            b[pos] ^= 1 << (rng.next_u64() % 8);
        }
        check(&b, &format!("flip variant {i}"));
    }
}

fn expect_err(name: &str, bytes: &[u8], format: Format, needle: &str) {
    match read_bytes(name, bytes, &opts(format)) {
        Err(e) => {
            let msg = e.to_string();
            println!("{name}: {msg}");
            assert!(
                msg.contains(needle),
                "{name}: `{msg}` should mention `{needle}`"
            );
            assert!(
                msg.contains("Fix:") || matches!(e, ReadError::UnknownFormat { .. }),
                "{msg}"
            );
        }
        Ok(t) => panic!("{name}: accepted a corrupt header ({} × {})", t.nx, t.ny),
    }
}

/// Replace the first `from` after the first `after`.
fn replace_after(bytes: &[u8], after: &str, from: &str, to: &str) -> Vec<u8> {
    let start = bytes
        .windows(after.len())
        .position(|w| w == after.as_bytes())
        .unwrap_or(0);
    let pos = start
        + bytes[start..]
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap_or_else(|| panic!("`{from}` not found"));
    let mut out = bytes[..pos].to_vec();
    out.extend_from_slice(to.as_bytes());
    out.extend_from_slice(&bytes[pos + from.len()..]);
    out
}

#[test]
fn nanoscope_survives_hostile_input() {
    let b = data("di-3.di");
    torture("di-3.di", &b, fmt("nanoscope"), 1, 150);
    // Same length keeps the header layout: 256 → 9999 points per line.
    expect_err(
        "huge.di",
        &replace_after(&b, "Ciao image list", "Samps/line: 256", "Samps/line: 9999"),
        fmt("nanoscope"),
        "Samps/line",
    );
    let huge = replace_after(
        &b,
        "Ciao image list",
        "Number of lines: 256",
        "Number of lines: 1000000000000",
    );
    expect_err("huge2.di", &huge, fmt("nanoscope"), "Samps/line");
    expect_err(
        "offset.di",
        &replace_after(
            &b,
            "Ciao image list",
            "Data offset: 40960",
            "Data offset: 99999999",
        ),
        fmt("nanoscope"),
        "Data offset",
    );
    let e = read_bytes(
        "di-3.di",
        &b,
        &ReadOptions {
            channel: Some(ChannelSel::Index(7)),
            ..opts(fmt("nanoscope"))
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("--channel"), "{e}");
    // The phase channel is not a height.
    let e = read_bytes(
        "di-3.di",
        &b,
        &ReadOptions {
            channel: Some(ChannelSel::Index(2)),
            ..opts(fmt("nanoscope"))
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("not a height") || e.to_string().contains("choose"),
        "{e}"
    );
}

#[test]
fn matrix_and_dektak_survive_hostile_input() {
    let m = data("matrix-3.txt");
    torture("matrix-3.txt", &m[..20_000], fmt("matrix"), 2, 100);
    expect_err(
        "ragged.txt",
        b"# Width: 1 um\n1 2 3\n4 5\n",
        fmt("matrix"),
        "line 3",
    );
    expect_err(
        "nowidth.txt",
        b"1 2 3 4\n4 5 6 7\n",
        fmt("matrix"),
        "--pixel-size",
    );
    let d = data("dektak-1.csv");
    torture("dektak-1.csv", &d, fmt("dektak"), 3, 100);
    expect_err(
        "nodata.csv",
        b"Scan Parameters\nfoo,bar\n",
        fmt("dektak"),
        "Scan Data",
    );
}

#[test]
fn x3p_survives_hostile_input() {
    let b = data("KautschukInfiniteFocus.x3p");
    torture("k.x3p", &b, fmt("x3p"), 4, 60);
    // Rebuild the archive with a main.xml that claims 10⁹ × 10⁹ points.
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&b[..])).unwrap();
    let mut xml = String::new();
    std::io::Read::read_to_string(&mut zip.by_name("main.xml").unwrap(), &mut xml).unwrap();
    let mut bin = Vec::new();
    std::io::Read::read_to_end(&mut zip.by_name("bindata/data.bin").unwrap(), &mut bin).unwrap();
    let build = |xml: &str, bin: &[u8]| -> Vec<u8> {
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let o = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        w.start_file("main.xml", o).unwrap();
        w.write_all(xml.as_bytes()).unwrap();
        w.start_file("bindata/data.bin", o).unwrap();
        w.write_all(bin).unwrap();
        w.finish().unwrap().into_inner()
    };
    // Sanity: the rebuilt archive reads.
    let ok = read_bytes("rebuilt.x3p", &build(&xml, &bin), &opts(fmt("x3p"))).unwrap();
    assert_eq!((ok.nx, ok.ny), (860, 634));
    let huge = xml
        .replace("<SizeX>860</SizeX>", "<SizeX>1000000000</SizeX>")
        .replace("<SizeY>634</SizeY>", "<SizeY>1000000000</SizeY>");
    expect_err(
        "huge.x3p",
        &build(&huge, &bin),
        fmt("x3p"),
        "MatrixDimension",
    );
    let short = xml.replace("<SizeX>860</SizeX>", "<SizeX>861</SizeX>");
    expect_err(
        "short.x3p",
        &build(&short, &bin),
        fmt("x3p"),
        "MatrixDimension",
    );
    let dtype = xml.replacen(
        "<DataType>F</DataType>\n      </CZ>",
        "<DataType>Q</DataType>\n      </CZ>",
        1,
    );
    assert_ne!(dtype, xml);
    expect_err("dtype.x3p", &build(&dtype, &bin), fmt("x3p"), "DataType");
    // New point data need a new checksum (or none): drop the recorded MD5.
    let xml = {
        let a = xml.find("<MD5ChecksumPointData>").unwrap();
        let b = xml.find("</MD5ChecksumPointData>").unwrap() + "</MD5ChecksumPointData>".len();
        format!("{}{}", &xml[..a], &xml[b..])
    };
    // Double data and an inline data list give the same heights.
    let f32s: Vec<f64> = bin
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
        .collect();
    let dxml = xml.replacen(
        "<DataType>F</DataType>\n      </CZ>",
        "<DataType>D</DataType>\n      </CZ>",
        1,
    );
    let dbin: Vec<u8> = f32s.iter().flat_map(|v| v.to_le_bytes()).collect();
    let d = read_bytes("double.x3p", &build(&dxml, &dbin), &opts(fmt("x3p"))).unwrap();
    for (a, b) in d.heights.iter().zip(&ok.heights) {
        assert!(a == b || (a.is_nan() && b.is_nan()));
    }
    // Integer data (I = int16) are scaled by the Z increment.
    let ixml = xml.replacen(
        "<DataType>F</DataType>\n      </CZ>",
        "<DataType>I</DataType>\n        <Increment>1e-9</Increment>\n      </CZ>",
        1,
    );
    let ibin: Vec<u8> = (0..860 * 634)
        .flat_map(|i| ((i % 1000) as i16 - 500).to_le_bytes())
        .collect();
    let it = read_bytes("int.x3p", &build(&ixml, &ibin), &opts(fmt("x3p"))).unwrap();
    assert!((it.heights[1234] - ((1234 % 1000) as f64 - 500.0) * 1e-9).abs() < 1e-20);
    assert_eq!(
        ok.invalid_count(),
        5296,
        "+Inf points of the Alicona file become NaN"
    );
}

#[test]
fn bcr_survives_hostile_input() {
    let b = data("bcrf-1.bcrf");
    torture("bcrf-1.bcrf", &b[..200_000], fmt("bcr"), 5, 150);
    let utf16 = |s: &str| -> Vec<u8> { s.encode_utf16().flat_map(|u| u.to_le_bytes()).collect() };
    let mut huge = b.clone();
    let from = utf16("xpixels = 960");
    let to = utf16("xpixels = 9e9");
    let pos = huge
        .windows(from.len())
        .position(|w| w == from.as_slice())
        .unwrap();
    huge[pos..pos + to.len()].copy_from_slice(&to);
    expect_err("huge.bcrf", &huge, fmt("bcr"), "xpixels");
    let to = utf16("xpixels = 999");
    huge[pos..pos + to.len()].copy_from_slice(&to);
    expect_err("big.bcrf", &huge, fmt("bcr"), "xpixels");
}

/// An ASCII-header int16 BCR file written from scratch.
fn bcr_int16(nx: usize, ny: usize, values: &[i16]) -> Vec<u8> {
    let mut h = format!(
        "fileformat = bcrstm\nheadersize = 2048\nxpixels = {nx}\nypixels = {ny}\nxlength = {}\nylength = {}\nbit2nm = 0.5\nvoidpixels = 1\n",
        nx * 10,
        ny * 20
    )
    .into_bytes();
    h.resize(2048, b' ');
    h.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    h
}

#[test]
fn bcr_int16_round_trip_and_torture() {
    let vals: Vec<i16> = (0..12)
        .map(|i| i * 3 - 5)
        .chain([i16::MAX])
        .chain(0..3)
        .collect();
    let b = bcr_int16(4, 4, &vals);
    let t = read_bytes("x.bcr", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (4, 4));
    assert!((t.dx - 10e-9).abs() < 1e-20 && (t.dy - 20e-9).abs() < 1e-20);
    assert!((t.heights[1] - (-2.0 * 0.5e-9)).abs() < 1e-20);
    assert!(t.heights[12].is_nan(), "void pixel");
    torture("x.bcr", &b, fmt("bcr"), 6, 200);
}

/// A GSF file written from scratch.
fn gsf(nx: usize, ny: usize, values: &[f32], extra: &str) -> Vec<u8> {
    let mut h = format!("Gwyddion Simple Field 1.0\nXRes = {nx}\nYRes = {ny}\nXReal = 2e-6\nYReal = 1e-6\nZUnits = nm\n{extra}").into_bytes();
    let pad = 4 - h.len() % 4;
    h.extend(std::iter::repeat_n(0u8, pad));
    h.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    h
}

#[test]
fn gsf_round_trip_and_torture() {
    let vals: Vec<f32> = (0..20)
        .map(|i| i as f32)
        .chain([f32::NAN])
        .chain((0..3).map(|i| i as f32))
        .collect();
    let b = gsf(6, 4, &vals, "Title = test\n");
    let t = read_bytes("x.gsf", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny, t.channel.as_str()), (6, 4, "test"));
    assert!((t.dx - 2e-6 / 6.0).abs() < 1e-18 && (t.dy - 0.25e-6).abs() < 1e-18);
    assert!((t.heights[7] - 7e-9).abs() < 1e-20 && t.heights[20].is_nan());
    torture("x.gsf", &b, fmt("gsf"), 7, 200);
    let huge = String::from_utf8_lossy(&b).replace("XRes = 6", "XRes = 600000000000");
    expect_err("huge.gsf", huge.as_bytes(), fmt("gsf"), "XRes");
}

/// Binary SDF written from scratch (81-byte header).
fn sdf_binary(nx: u16, ny: u16, values: &[i16]) -> Vec<u8> {
    let mut h = Vec::new();
    h.extend_from_slice(b"bISO-1.0");
    h.extend_from_slice(b"lustre    ");
    h.extend_from_slice(b"010120250000");
    h.extend_from_slice(b"010120250000");
    h.extend_from_slice(&nx.to_le_bytes());
    h.extend_from_slice(&ny.to_le_bytes());
    for v in [1e-6f64, 2e-6, 1e-9, 1e-9] {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h.extend_from_slice(&[0, 5, 0]); // uncompressed, int16, no checksum
    assert_eq!(h.len(), 81);
    h.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    h
}

#[test]
fn sdf_round_trip_and_torture() {
    let vals: Vec<i16> = (0..15).map(|i| i * 100 - 700).collect();
    let b = sdf_binary(5, 3, &vals);
    let t = read_bytes("x.sdf", &b, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (5, 3));
    assert!((t.dx - 1e-6).abs() < 1e-18 && (t.dy - 2e-6).abs() < 1e-18);
    assert!((t.heights[4] - (-300e-9)).abs() < 1e-18);
    torture("x.sdf", &b, fmt("sdf"), 8, 200);
    let mut huge = b.clone();
    huge[42..46].copy_from_slice(&[0xff, 0xff, 0xff, 0xff]);
    expect_err("huge.sdf", &huge, fmt("sdf"), "NumPoints");

    let ascii = "aISO-1.0\nManufacID = lustre\nNumPoints = 3\nNumProfiles = 2\nXscale = 1e-6\nYscale = 1e-6\nZscale = 1e-9\nDataType = 7\n*\n1 2 3\n4 5 6\n*\n";
    let t = read_bytes("a.sdf", ascii.as_bytes(), &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (3, 2));
    assert!((t.heights[5] - 6e-9).abs() < 1e-20);
    torture("a.sdf", ascii.as_bytes(), fmt("sdf"), 9, 200);
    expect_err(
        "huge-a.sdf",
        ascii
            .replace("NumPoints = 3", "NumPoints = 300000000")
            .as_bytes(),
        fmt("sdf"),
        "NumPoints",
    );
}

#[test]
fn xyz_round_trip_and_torture() {
    let mut s = String::from("x,y,z\n");
    for y in 0..4 {
        for x in 0..5 {
            if (x, y) != (2, 2) {
                s.push_str(&format!(
                    "{},{},{}\n",
                    x as f64 * 0.5,
                    y as f64 * 0.5,
                    x * 10 + y
                ));
            }
        }
    }
    let o = ReadOptions {
        units: Units::parse("um"),
        ..ReadOptions::default()
    };
    let t = read_bytes("x.xyz", s.as_bytes(), &o).unwrap();
    assert_eq!((t.nx, t.ny), (5, 4));
    assert!((t.dx - 0.5e-6).abs() < 1e-18);
    assert!((t.heights[3 * 5 + 4] - 43e-6).abs() < 1e-15);
    assert!(t.heights[2 * 5 + 2].is_nan(), "missing grid point is NaN");
    torture("x.xyz", s.as_bytes(), fmt("xyz"), 10, 300);
    let prof = "0 1\n1 2\n2 3\n3 5\n";
    let m = ReadOptions {
        units: Units::parse("m"),
        ..ReadOptions::default()
    };
    let t = read_bytes("p.xyz", prof.as_bytes(), &m).unwrap();
    assert_eq!((t.nx, t.ny, t.dx), (4, 1, 1.0));
    // A far-away point cannot make the grid explode.
    let sparse = "0 0 1\n1 0 1\n0 1 1\n1e6 1e6 1\n";
    assert!(read_bytes("s.xyz", sparse.as_bytes(), &m).is_err());
}

#[test]
fn unknown_formats_are_reported() {
    let e = read_bytes("x.bin", &[0u8, 1, 2, 3, 255], &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, ReadError::UnknownFormat { .. }), "{e}");
}

/// A flipped byte anywhere in the X3P's compressed point data or header is
/// caught by the zip CRC-32 or the file's MD5 checksums, never read as heights.
#[test]
fn x3p_checksums_catch_flipped_bytes() {
    let b = data("KautschukInfiniteFocus.x3p");
    let good = read_bytes("k.x3p", &b, &ReadOptions::default()).unwrap();
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&b[..])).unwrap();
    let (start, len) = {
        let f = zip.by_name("bindata/data.bin").unwrap();
        (
            f.data_start().unwrap() as usize,
            f.compressed_size() as usize,
        )
    };
    let mut caught = 0;
    for k in 0..200 {
        let pos = start + (k * 7919) % len;
        let mut m = b.clone();
        m[pos] ^= 0x10;
        match read_bytes("k.x3p", &m, &ReadOptions::default()) {
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    msg.contains("CRC") || msg.contains("decompress") || msg.contains("MD5"),
                    "{msg}"
                );
                caught += 1;
            }
            Ok(t) => assert!(
                t.heights
                    .iter()
                    .zip(&good.heights)
                    .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())),
                "flip at {pos} changed the heights silently"
            ),
        }
    }
    println!("{caught} of 200 flips in the point data rejected");
    assert!(caught >= 190, "{caught}");

    // Uncompressed archives: the CRC names the entry, the MD5 the point data.
    let mut xml = String::new();
    std::io::Read::read_to_string(&mut zip.by_name("main.xml").unwrap(), &mut xml).unwrap();
    let mut bin = Vec::new();
    std::io::Read::read_to_end(&mut zip.by_name("bindata/data.bin").unwrap(), &mut bin).unwrap();
    let mut md5 = Vec::new();
    std::io::Read::read_to_end(&mut zip.by_name("md5checksum.hex").unwrap(), &mut md5).unwrap();
    let build = |xml: &str, bin: &[u8], md5: &[u8]| -> Vec<u8> {
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let o = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        w.start_file("main.xml", o).unwrap();
        w.write_all(xml.as_bytes()).unwrap();
        w.start_file("bindata/data.bin", o).unwrap();
        w.write_all(bin).unwrap();
        w.start_file("md5checksum.hex", o).unwrap();
        w.write_all(md5).unwrap();
        w.finish().unwrap().into_inner()
    };
    let stored = build(&xml, &bin, &md5);
    read_bytes("stored.x3p", &stored, &ReadOptions::default()).unwrap();
    // One byte of the stored data flipped in place: the zip CRC fails.
    let at = stored
        .windows(16)
        .position(|w| w == &bin[1000..1016])
        .unwrap();
    let mut m = stored.clone();
    m[at + 3] ^= 0x40;
    let e = read_bytes("crc.x3p", &m, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        e.contains("CRC-32") && e.contains("bindata/data.bin"),
        "{e}"
    );
    // A consistent archive whose data no longer match MD5ChecksumPointData.
    let mut bad = bin.clone();
    bad[4000] ^= 0x01;
    let e = read_bytes("md5.x3p", &build(&xml, &bad, &md5), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        e.contains("MD5ChecksumPointData") && e.contains("MD5 check failed"),
        "{e}"
    );
    // A header edited without updating md5checksum.hex.
    let edited = xml.replacen("<Comment>", "<Comment>x", 1);
    let edited = if edited == xml {
        xml.replacen("</Record1>", " </Record1>", 1)
    } else {
        edited
    };
    let e = read_bytes(
        "hdr.x3p",
        &build(&edited, &bin, &md5),
        &ReadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    println!("{e}");
    assert!(
        e.contains("md5checksum.hex") && e.contains("main.xml"),
        "{e}"
    );
}

/// Truncated, cut or garbled Dektak profiles are errors naming the problem.
#[test]
fn dektak_truncation_and_garbling_are_detected() {
    let d = data("dektak-1.csv");
    let text = String::from_utf8_lossy(&d).into_owned();
    let lines: Vec<&str> = text.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.starts_with("Scan Data"))
        .unwrap()
        + 2;
    let n = lines.len();
    let o = opts(fmt("dektak"));
    let join = |ls: &[&str]| ls.join("\n").into_bytes();
    // The whole file reads.
    read_bytes("dektak-1.csv", &d, &o).unwrap();
    // Cut anywhere in the data (by rows or mid-row), ≥ 1 % short: rejected.
    for frac in [0.1, 0.5, 0.9, 0.98] {
        let cut = start + ((n - start) as f64 * frac) as usize;
        let e = read_bytes("cut.csv", &join(&lines[..cut]), &o)
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
    }
    let mut cut_bytes = d.clone();
    cut_bytes.truncate(d.len() * 3 / 4);
    let e = read_bytes("cut2.csv", &cut_bytes, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("truncated") || e.contains("garbled"), "{e}");
    // Rows missing in the middle.
    let mut holes = lines.clone();
    holes.drain(start + 3000..start + 3040);
    let e = read_bytes("holes.csv", &join(&holes), &o)
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(e.contains("missing") && e.contains("line"), "{e}");
    // A garbled row.
    let mut garbled = lines.clone();
    let bad = format!("{}#x", lines[start + 5000]);
    garbled[start + 5000] = &bad;
    let e = read_bytes("garbled.csv", &join(&garbled), &o)
        .unwrap_err()
        .to_string();
    println!("{e}");
    assert!(
        e.contains(&format!("line {}", start + 5001)) && e.contains("garbled"),
        "{e}"
    );
    // Rows out of order.
    let mut swapped = lines.clone();
    swapped.swap(start + 100, start + 700);
    let e = read_bytes("swap.csv", &join(&swapped), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("out of order"), "{e}");
}

/// One sample file per reader of the registry (real corpus files where there is one,
/// files written here otherwise).
fn samples() -> Vec<(&'static str, String, Vec<u8>)> {
    let corpus = |f: &str| data(&format!("corpus/{f}"));
    let formats = |f: &str| data(&format!("formats/{f}"));
    let vals: Vec<i16> = (0..15).map(|i| i * 100 - 700).collect();
    let gvals: Vec<f32> = (0..24).map(|i| i as f32).collect();
    let mut s: Vec<(&'static str, String, Vec<u8>)> = vec![
        ("x3p", "k.x3p".into(), data("KautschukInfiniteFocus.x3p")),
        ("sdf", "x.sdf".into(), sdf_binary(5, 3, &vals)),
        (
            "sdf",
            "a.sdf".into(),
            b"aISO-1.0\nNumPoints = 3\nNumProfiles = 2\nXscale = 1e-6\nYscale = 1e-6\nZscale = 1e-9\nDataType = 7\n*\n1 2 3\n4 5 6\n*\n".to_vec(),
        ),
        ("bcr", "x.bcr".into(), bcr_int16(4, 4, &[1; 16])),
        ("bcr", "bcrf-1.bcrf".into(), data("bcrf-1.bcrf")),
        ("gsf", "x.gsf".into(), gsf(6, 4, &gvals, "")),
        ("nanoscope", "di-5.di".into(), corpus("di-5.di")),
        ("plu", "plu-1.plu".into(), corpus("plu-1.plu")),
        ("sur", "sur-2.sur".into(), corpus("sur-2.sur")),
        ("mnt", "mnt-1.mnt".into(), corpus("mnt-1.mnt")),
        ("metropro", "metropro-1.dat".into(), corpus("metropro-1.dat")),
        ("opd", "opd-1.opd".into(), corpus("opd-1.opd")),
        ("al3d", "al3d-1.al3d".into(), corpus("al3d-1.al3d")),
        ("nid", "nid-1.nid".into(), corpus("nid-1.nid")),
        ("ibw", "spot.ibw".into(), corpus("spot_1-1000nm.ibw")),
        (
            "ibw",
            "10x10.ibw".into(),
            corpus("10x10-one_channel_without_name.ibw"),
        ),
        ("park", "example_ps.tiff".into(), corpus("example_ps.tiff")),
        ("mi", "mi-1.mi".into(), corpus("mi-1.mi")),
        ("wsxm", "stp-1.stp".into(), corpus("stp-1.stp")),
        ("frt", "frt-1.frt".into(), corpus("frt-1.frt")),
        ("tmd", "tmd-1.tmd".into(), corpus("tmd-1.tmd")),
        ("dektak", "dektak-1.csv".into(), data("dektak-1.csv")),
        (
            "matrix",
            "english.txt".into(),
            corpus("gwyddion-export-english.txt"),
        ),
        ("matrix", "txt_example.txt".into(), corpus("txt_example.txt")),
        ("matrix", "matrix-3.txt".into(), data("matrix-3.txt")[..30_000].to_vec()),
        ("xyz", "csv-2.csv".into(), corpus("csv-2.csv")),
        ("xyz", "xy-1.txt".into(), corpus("xy-1.txt")),
        ("xyz", "csv-1.csv".into(), corpus("csv-1.csv")),
        ("xyz", "hfm-1.hfm".into(), formats("hfm-1.hfm")[..20_000].to_vec()),
        ("opdx", "opdx-3.opdx".into(), formats("opdx-3.opdx")),
        ("nms", "nms-1.nms".into(), formats("nms-1.nms")),
        ("npy", "example-2d.npy".into(), formats("example-2d.npy")),
        ("netcdf", "nc-1.nc".into(), formats("nc-1.nc")),
        ("gwy", "matrix-4-st.gwy".into(), formats("matrix-4-st.gwy")),
        ("vk4", "a.vk4".into(), vk4_sample()),
        ("zmg", "a.zmg".into(), zmg_sample()),
        ("zon", "a.zon".into(), zon_sample()),
        ("jpk", "a.jpk".into(), jpk_sample()),
        ("lext", "lext-synth.lext".into(), formats("lext-synth.lext")),
        ("datx", "datx-synth.datx".into(), formats("datx-synth.datx")),
    ];
    // Every reader of the registry has a sample.
    for f in Format::all() {
        assert!(
            s.iter().any(|(n, _, _)| *n == f.name()),
            "no hostile-input sample for {}",
            f.name()
        );
    }
    s.sort_by_key(|x| x.0);
    s
}

/// Make an Igor header checksum add up again, so mutations reach past it.
fn fix_ibw_checksum(b: &mut [u8]) {
    if b.len() < 384 || b[0] == 0 {
        return;
    }
    b[2] = 0;
    b[3] = 0;
    let sum = b[..384].chunks_exact(2).fold(0u16, |s, c| {
        s.wrapping_add(u16::from_le_bytes([c[0], c[1]]))
    });
    b[2..4].copy_from_slice(&0u16.wrapping_sub(sum).to_le_bytes());
}

/// `n` mutations of a sample: truncations, bit flips (mostly in the header) and header
/// numbers replaced by huge, negative, zero or non-finite ones. No panic, no abort, and
/// any result read must be self-consistent.
fn mutate_and_read(format: &str, name: &str, bytes: &[u8], n: usize, seed: u64) -> (usize, usize) {
    let fmt = fmt(format);
    let o = opts(fmt);
    let mut rng = SplitMix64::new(seed);
    let len = bytes.len();
    let head = len.min(4096);
    let (mut ok, mut err) = (0, 0);
    let huge_text = [
        "99999999999",
        "4294967295",
        "-1",
        "0",
        "1e308",
        "nan",
        "-0",
        "2147483648",
    ];
    let huge_bin: [u32; 5] = [0xFFFF_FFFF, 0x7FFF_FFFF, 0x8000_0000, 0, 0x0001_0000];
    for i in 0..n {
        let mut b = bytes.to_vec();
        let what = match rng.next_u64() % 10 {
            0..=2 => {
                let cut = (rng.next_u64() as usize) % len.max(1);
                b.truncate(cut);
                format!("truncated at {cut}")
            }
            3..=6 => {
                let k = 1 + rng.next_u64() % 8;
                for _ in 0..k {
                    let region = if rng.next_u64().is_multiple_of(4) {
                        len
                    } else {
                        head
                    };
                    let pos = (rng.next_u64() as usize) % region.max(1);
                    b[pos] ^= 1 << (rng.next_u64() % 8);
                }
                format!("{k} bit flips")
            }
            _ => {
                // Replace a run of ASCII digits in the header, or a binary word.
                let start = (rng.next_u64() as usize) % head.max(1);
                let digits = b[start..head]
                    .iter()
                    .position(|c| c.is_ascii_digit())
                    .map(|p| start + p);
                if let Some(p) = digits.filter(|_| rng.next_u64().is_multiple_of(2)) {
                    let end = p + b[p..]
                        .iter()
                        .take_while(|c| c.is_ascii_digit() || **c == b'.')
                        .count();
                    let rep = huge_text[(rng.next_u64() as usize) % huge_text.len()];
                    b.splice(p..end, rep.bytes());
                    format!("number at {p} → {rep}")
                } else {
                    let p = ((rng.next_u64() as usize) % head.saturating_sub(4).max(1)) & !3;
                    let v = huge_bin[(rng.next_u64() as usize) % huge_bin.len()];
                    if p + 4 <= b.len() {
                        b[p..p + 4].copy_from_slice(&v.to_le_bytes());
                    }
                    format!("word at {p} → {v:#x}")
                }
            }
        };
        if format == "ibw" && !rng.next_u64().is_multiple_of(3) {
            fix_ibw_checksum(&mut b);
        }
        let r = std::panic::catch_unwind(|| {
            let listed = fit::io::list_channels(name, &b, &o);
            (listed.is_ok(), read_bytes(name, &b, &o))
        });
        match r {
            Err(_) => panic!("{format} {name}: mutation {i} ({what}) panicked"),
            Ok((_, Ok(t))) => {
                assert_eq!(t.heights.len(), t.nx * t.ny, "{name} {what}");
                assert!(
                    t.dx > 0.0 && t.dx.is_finite() && t.dy > 0.0 && t.dy.is_finite(),
                    "{name} {what}: spacing {} {}",
                    t.dx,
                    t.dy
                );
                assert!(
                    t.heights.len() <= 8 * b.len().max(1) + 64
                        || format == "mnt"
                        || format == "x3p"
                        || format == "sur",
                    "{name} {what}: more points than bytes"
                );
                ok += 1;
            }
            Ok((_, Err(e))) => {
                let msg = e.to_string();
                assert!(
                    !msg.is_empty() && !msg.contains('\n'),
                    "{name} {what}: {msg}"
                );
                err += 1;
            }
        }
    }
    (ok, err)
}

fn hostile_suite(n: usize) {
    for (i, (format, name, bytes)) in samples().into_iter().enumerate() {
        let t0 = std::time::Instant::now();
        let (ok, err) = mutate_and_read(format, &name, &bytes, n, 1000 + i as u64);
        println!(
            "{format:<10} {name:<22} {n} mutations: {ok} read, {err} rejected ({:.1} s)",
            t0.elapsed().as_secs_f64()
        );
    }
}

/// ≥ 100 mutations of every reader's sample in the normal run.
#[test]
fn every_reader_survives_mutations() {
    hostile_suite(100);
}

/// ≥ 2000 mutations per sample: `cargo test -p fit --test hostile -- --ignored`.
#[test]
#[ignore]
fn every_reader_survives_many_mutations() {
    hostile_suite(2000);
}

/// Headers that claim enormous grids are errors before any allocation.
#[test]
fn oversized_headers_of_the_new_formats_are_rejected() {
    let corpus = |f: &str| data(&format!("corpus/{f}"));
    let o = ReadOptions::default();
    let expect = |name: &str, b: &[u8], needle: &str| {
        let e = match read_bytes(name, b, &o) {
            Ok(t) => panic!("{name}: accepted ({} × {})", t.nx, t.ny),
            Err(e) => e.to_string(),
        };
        println!("{e}");
        assert!(
            e.contains(needle),
            "{name}: `{e}` should mention `{needle}`"
        );
    };
    // PLU: layer 100000 × 100000.
    let mut b = corpus("plu-1.plu");
    b[500..508].copy_from_slice(&[0xa0, 0x86, 1, 0, 0xa0, 0x86, 1, 0]);
    expect("big.plu", &b, "xres × yres");
    // SUR: 2³¹ − 1 points per line.
    let mut b = corpus("sur-2.sur");
    b[108..112].copy_from_slice(&i32::MAX.to_le_bytes());
    expect("big.sur", &b, "total number of points");
    // MetroPro: 65535 × 65535 phase points.
    let mut b = corpus("metropro-1.dat");
    b[68..72].copy_from_slice(&[0xff; 4]);
    expect("big.dat", &b, "cn_org_width");
    // TMD: u32::MAX columns.
    let mut b = corpus("tmd-1.tmd");
    b[56..60].copy_from_slice(&[0xff; 4]);
    expect("big.tmd", &b, "columns");
    // IBW: 65536 × 65536 × 8 points with a consistent checksum.
    let mut b = corpus("spot_1-1000nm.ibw");
    b[64 + 68..64 + 72].copy_from_slice(&65536u32.to_le_bytes());
    b[64 + 72..64 + 76].copy_from_slice(&65536u32.to_le_bytes());
    fix_ibw_checksum(&mut b);
    expect("big.ibw", &b, "nDim");
    // MI: 10⁸ pixels per line.
    let b = String::from_utf8_lossy(&corpus("mi-1.mi")).replacen(
        "xPixels       256",
        "xPixels       100000000",
        1,
    );
    let b: Vec<u8> = b.chars().map(|c| c as u32 as u8).collect();
    assert!(read_bytes("big.mi", &b, &o).is_err());
    // WSxM: 10⁹ columns.
    let t = corpus("stp-1.stp");
    let pos = t
        .windows(22)
        .position(|w| w == b"Number of columns: 256")
        .unwrap();
    let mut b = t[..pos].to_vec();
    b.extend_from_slice(b"Number of columns: 999999999");
    b.extend_from_slice(&t[pos + 22..]);
    expect("big.stp", &b, "columns × rows");
    // NID: 10⁹ points.
    let t = corpus("nid-1.nid");
    let sec = t.windows(13).position(|w| w == b"[DataSet-0:1]").unwrap();
    let pos = sec
        + t[sec..]
            .windows(10)
            .position(|w| w == b"Points=256")
            .unwrap();
    let mut b = t[..pos].to_vec();
    b.extend_from_slice(b"Points=999999999");
    b.extend_from_slice(&t[pos + 10..]);
    expect("big.nid", &b, "Points × Lines");
    // FRT: 2³² − 1 points per line.
    let t = corpus("frt-1.frt");
    let mut b = t.clone();
    let g = 500u32.to_le_bytes();
    let p = t
        .windows(8)
        .position(|w| w[..4] == g && w[4..] == g)
        .unwrap();
    b[p..p + 4].copy_from_slice(&[0xff; 4]);
    expect("big.frt", &b, "grid");
}

/// A 64 × 48 VK4 file written from the format description (as in tests/formats.rs).
fn vk4_sample() -> Vec<u8> {
    let (w, h) = (64u32, 48u32);
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
    cond[42] = 250_000;
    cond[43] = 250_000;
    cond[44] = 1000;
    cond.iter().for_each(|v| b.extend(v.to_le_bytes()));
    for v in [w, h, 16, 0, w * h * 2, 0, 0] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u8; 768]);
    for i in 0..w * h {
        b.extend((((i * 37) % 4001) as u16).to_le_bytes());
    }
    b
}
