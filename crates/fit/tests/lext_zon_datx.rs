//! Olympus LEXT, Keyence ZON (KPK1, zstd) and Zygo DATX (HDF5): files written here from
//! the format descriptions in the readers' module docs, read back exactly; hostile input
//! (every truncation, bit flips, headers claiming huge grids) gives errors, never panics.
//! SurfaceTopography's reading of the synthetic sample files in `data/surfaces/formats/`
//! is compared in `formats.rs` (`every_new_format_file_matches_surface_topography`).

use fit::io::{ReadOptions, open_bytes, read_bytes};
use fit::rng::SplitMix64;
use proptest::prelude::*;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Truncations at many lengths and random bit flips: Ok or Err, never a panic, and an Ok
/// map is consistent and not larger than the bytes could hold.
fn torture(name: &str, bytes: &[u8], seed: u64, flips: usize) {
    let o = ReadOptions::default();
    let check = |b: &[u8], what: &str| {
        if let Ok(t) = read_bytes(name, b, &o) {
            assert_eq!(t.heights.len(), t.nx * t.ny, "{name} {what}");
            assert!(t.dx > 0.0 && t.dx.is_finite(), "{name} {what}");
            assert!(
                t.heights.len() <= 8 * b.len().max(1) + 64,
                "{name} {what}: more points than bytes"
            );
        }
    };
    let n = bytes.len();
    for c in (0..n).step_by((n / 300).max(1)) {
        check(&bytes[..c], &format!("truncated at {c}"));
    }
    let mut rng = SplitMix64::new(seed);
    for i in 0..flips {
        let mut b = bytes.to_vec();
        for _ in 0..1 + (rng.next_u64() % 8) {
            let region = if rng.next_u64().is_multiple_of(2) {
                n.min(1024)
            } else {
                n
            };
            let pos = (rng.next_u64() as usize) % region;
            b[pos] ^= 1 << (rng.next_u64() % 8);
        }
        check(&b, &format!("flip variant {i}"));
    }
}

// ---------------------------------------------------------------------------------------
// Olympus LEXT

/// A TIFF directory entry: tag, type, count, value bytes.
type Entry = (u16, u16, u32, Vec<u8>);

/// A little-endian directory placed at byte `base`, its long values after it.
fn ifd(base: usize, mut entries: Vec<Entry>, next: u32) -> Vec<u8> {
    entries.sort_by_key(|e| e.0);
    let extra_at = base + 2 + 12 * entries.len() + 4;
    let mut head = (entries.len() as u16).to_le_bytes().to_vec();
    let mut extra = vec![];
    for (tag, kind, count, value) in entries {
        head.extend(tag.to_le_bytes());
        head.extend(kind.to_le_bytes());
        head.extend(count.to_le_bytes());
        if value.len() <= 4 {
            let mut v = value.clone();
            v.resize(4, 0);
            head.extend(v);
        } else {
            head.extend(((extra_at + extra.len()) as u32).to_le_bytes());
            extra.extend(&value);
            if extra.len() % 2 == 1 {
                extra.push(0);
            }
        }
    }
    head.extend(next.to_le_bytes());
    head.extend(extra);
    head
}

fn long(tag: u16, v: u32) -> Entry {
    (tag, 4, 1, v.to_le_bytes().to_vec())
}

fn text(tag: u16, s: &str) -> Entry {
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    (tag, 2, v.len() as u32, v)
}

/// What a LEXT file written by [`lext`] states.
#[derive(Clone)]
struct Lext {
    nx: u32,
    ny: u32,
    /// HeightDataPerPixelX, Y, Z [pm].
    per_pixel: [f64; 3],
    /// MakerCalibrationValueX, Y, Z [millionths]; no Exif directory when `None`.
    cal: Option<[f64; 3]>,
    /// HeightDataUnitX, Y, Z.
    units: [u32; 3],
    /// The Exif XML as UNDEFINED bytes (type 7) instead of ASCII.
    undefined: bool,
}

impl Lext {
    fn new(nx: u32, ny: u32) -> Lext {
        Lext {
            nx,
            ny,
            per_pixel: [125_000.0, 130_000.0, 10.0],
            cal: Some([1_002_000.0, 999_000.0, 998_000.0]),
            units: [2, 2, 2],
            undefined: false,
        }
    }
}

/// A LEXT file from the description in `fit::io::lext`: a colour page with the XML, an
/// intensity page and the HEIGHT page (u32 counts), the Exif directory before them.
fn lext(l: &Lext, counts: &[u32]) -> Vec<u8> {
    let [px, py, pz] = l.per_pixel;
    let [ux, uy, uz] = l.units;
    let desc = format!(
        "<?xml version=\"1.0\"?><TiffTagDescData><ColorInfo><ColorDataPerPixelX>1\
         </ColorDataPerPixelX></ColorInfo><HeightInfo><HeightDataPerPixelX>{px}\
         </HeightDataPerPixelX><HeightDataPerPixelY>{py}</HeightDataPerPixelY>\
         <HeightDataPerPixelZ>{pz}</HeightDataPerPixelZ><HeightDataUnitX>{ux}\
         </HeightDataUnitX><HeightDataUnitY>{uy}</HeightDataUnitY><HeightDataUnitZ>{uz}\
         </HeightDataUnitZ></HeightInfo></TiffTagDescData>"
    );
    let mut b = b"II*\0\0\0\0\0".to_vec();
    let heights: Vec<u8> = counts.iter().flat_map(|c| c.to_le_bytes()).collect();
    let h_at = b.len() as u32;
    b.extend(&heights);
    let i_at = b.len() as u32;
    b.extend(vec![7u8; (l.nx * l.ny) as usize]);
    let mut exif_at = None;
    if let Some([cx, cy, cz]) = l.cal {
        let xml = format!(
            "<?xml version=\"1.0\"?><ExifTagDescData><ImageCommonSettingsInfo>\
             <MakerCalibrationValueX>{cx}</MakerCalibrationValueX><MakerCalibrationValueY>{cy}\
             </MakerCalibrationValueY><MakerCalibrationValueZ>{cz}</MakerCalibrationValueZ>\
             </ImageCommonSettingsInfo></ExifTagDescData>"
        );
        let mut e = text(41995, &xml);
        if l.undefined {
            e.1 = 7;
        }
        if b.len() % 2 == 1 {
            b.push(0);
        }
        exif_at = Some(b.len() as u32);
        b.extend(ifd(b.len(), vec![e], 0));
    }
    let page = |desc: Entry, bits: u32, at: u32, len: usize| {
        vec![
            long(256, l.nx),
            long(257, l.ny),
            long(258, bits),
            long(259, 1),
            long(277, 1),
            long(278, l.ny),
            long(273, at),
            long(279, len as u32),
            desc,
        ]
    };
    let mut first = page(text(270, &desc), 8, i_at, (l.nx * l.ny) as usize);
    if let Some(at) = exif_at {
        first.push(long(34665, at));
    }
    let pages = [
        first,
        page(text(270, "INTENSITY"), 8, i_at, (l.nx * l.ny) as usize),
        page(text(270, "HEIGHT"), 32, h_at, heights.len()),
    ];
    let first_at = b.len() + b.len() % 2;
    let mut at = first_at;
    let mut dirs = vec![];
    for (k, p) in pages.iter().enumerate() {
        let len = ifd(at, p.clone(), 0).len();
        let next = if k + 1 < pages.len() {
            (at + len + len % 2) as u32
        } else {
            0
        };
        dirs.push((at, ifd(at, p.clone(), next)));
        at = next as usize;
    }
    b[4..8].copy_from_slice(&(first_at as u32).to_le_bytes());
    for (at, d) in dirs {
        b.resize(at, 0);
        b.extend(d);
    }
    b
}

#[test]
fn lext_scale_calibration_and_heights_from_the_description() {
    let (nx, ny) = (5u32, 3u32);
    let counts: Vec<u32> = (0..nx * ny).map(|i| 1000 + 37 * i).collect();
    let l = Lext::new(nx, ny);
    let b = lext(&l, &counts);
    let s = open_bytes("scan.lext", &b, &ReadOptions::default()).unwrap();
    assert_eq!(s.format.name(), "lext");
    let t = s.topo;
    assert_eq!((t.nx, t.ny), (5, 3));
    // pm × millionths: 125 000 pm × 1.002 = 125.25 nm.
    assert!(rel(t.dx, 125_000e-12 * 1.002) < 1e-12, "{}", t.dx);
    assert!(rel(t.dy, 130_000e-12 * 0.999) < 1e-12, "{}", t.dy);
    for (h, c) in t.heights.iter().zip(&counts) {
        assert!(rel(*h, f64::from(*c) * 10e-12 * 0.998) < 1e-12);
    }
    // Any TIFF name: the XML says what it is, before Park's and JPK's TIFF readers.
    let by_content = open_bytes("scan.tif", &b, &ReadOptions::default()).unwrap();
    assert_eq!(by_content.format.name(), "lext");
    // The Exif XML stored as UNDEFINED bytes reads the same.
    let u = lext(
        &Lext {
            undefined: true,
            ..l.clone()
        },
        &counts,
    );
    let tu = read_bytes("u.lext", &u, &ReadOptions::default()).unwrap();
    assert_eq!(tu.heights, t.heights);
    assert_eq!((tu.dx, tu.dy), (t.dx, t.dy));
}

#[test]
fn lext_without_calibration_uses_the_nominal_scale_and_says_so() {
    let l = Lext {
        cal: None,
        ..Lext::new(4, 4)
    };
    let counts: Vec<u32> = (0..16).map(|i| i * i).collect();
    let s = open_bytes("n.lext", &lext(&l, &counts), &ReadOptions::default()).unwrap();
    assert!(rel(s.topo.dx, 125e-9) < 1e-12 && rel(s.topo.dy, 130e-9) < 1e-12);
    assert!(rel(s.topo.heights[15], 225.0 * 10e-12) < 1e-12);
    assert!(
        s.notes.iter().any(|n| n.contains("no maker calibration")),
        "{:?}",
        s.notes
    );
}

#[test]
fn lext_refusals_name_the_field() {
    let counts = vec![5u32; 12];
    let mixed = Lext {
        units: [2, 2, 3],
        ..Lext::new(4, 3)
    };
    let e = read_bytes("m.lext", &lext(&mixed, &counts), &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("HeightDataUnit") && e.contains("differ"), "{e}");
    // A TIFF without the XML named .lext is refused by the LEXT reader, naming the XML.
    let bare = b"II*\0\x08\0\0\0\0\0\0\0\0\0";
    let e = open_bytes("a.lext", bare, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("TiffTagDescData") && e.contains("not an Olympus LEXT"),
        "{e}"
    );
    // No HEIGHT page: the description renamed.
    let mut b = lext(&Lext::new(4, 3), &counts);
    let p = b.windows(6).rposition(|w| w == b"HEIGHT").unwrap();
    b[p..p + 6].copy_from_slice(b"COLOUR");
    let e = read_bytes("c.lext", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("HEIGHT"), "{e}");
}

#[test]
fn lext_claiming_a_huge_grid_is_refused_before_allocating() {
    let counts = vec![5u32; 12];
    for (nx, ny) in [(u32::MAX, u32::MAX), (1 << 20, 1 << 20), (4, 1 << 30)] {
        let mut b = lext(&Lext::new(4, 3), &counts);
        // The HEIGHT page is the last directory: patch its width and length entries.
        let last = b.windows(6).rposition(|w| w == b"HEIGHT").unwrap();
        let dir = (0..last)
            .rev()
            .find(|&i| b[i..].starts_with(&[0, 1, 4, 0, 1, 0, 0, 0]))
            .unwrap();
        b[dir + 8..dir + 12].copy_from_slice(&nx.to_le_bytes());
        b[dir + 20..dir + 24].copy_from_slice(&ny.to_le_bytes());
        let e = read_bytes("h.lext", &b, &ReadOptions::default()).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("ImageWidth"), "{msg}");
    }
}

#[test]
fn lext_survives_hostile_input() {
    let counts: Vec<u32> = (0..48 * 32).map(|i| (i * 7919) % 100_000).collect();
    let b = lext(&Lext::new(48, 32), &counts);
    torture("t.lext", &b, 36, 400);
    // All but the last byte, the padding after the last string.
    for cut in 0..b.len() - 1 {
        assert!(
            read_bytes("t.lext", &b[..cut], &ReadOptions::default()).is_err(),
            "read cut at {cut}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn lext_round_trip(nx in 2u32..12, ny in 2u32..12, px in 1e3f64..1e7, py in 1e3f64..1e7,
                       pz in 0.1f64..100.0, c in 0.9e6f64..1.1e6, seed: u64) {
        let mut rng = SplitMix64::new(seed);
        let counts: Vec<u32> = (0..nx * ny).map(|_| (rng.next_u64() >> 40) as u32).collect();
        let l = Lext { per_pixel: [px, py, pz], cal: Some([c, 2e6 - c, c]), ..Lext::new(nx, ny) };
        let t = read_bytes("p.lext", &lext(&l, &counts), &ReadOptions::default()).unwrap();
        prop_assert_eq!((t.nx, t.ny), (nx as usize, ny as usize));
        prop_assert!(rel(t.dx, px * c * 1e-18) < 1e-12);
        prop_assert!(rel(t.dy, py * (2e6 - c) * 1e-18) < 1e-12);
        for (h, k) in t.heights.iter().zip(&counts) {
            let want = f64::from(*k) * pz * c * 1e-18;
            prop_assert!((h - want).abs() <= 1e-12 * want.abs().max(1e-30));
        }
    }
}

// ---------------------------------------------------------------------------------------
// Keyence ZON

/// A ZON array entry: width, height, element size, row bytes (rows padded by 4 bytes).
fn zon_array(w: usize, h: usize, elem: usize, values: &[u8]) -> Vec<u8> {
    let row = w * elem + 4;
    let mut out = vec![];
    for v in [w, h, elem, row] {
        out.extend((v as i32).to_le_bytes());
    }
    for line in values.chunks(w * elem) {
        out.extend(line);
        out.extend([0xEE; 4]);
    }
    out
}

/// A Keyence ZON file from the description in `fit::io::zon`: `KPK1` entries are zstd
/// frames (compressed here by `ruzstd`'s encoder), with an optional validity mask.
fn zon(kpk1: bool, w: usize, h: usize, counts: &[i32], flags: Option<&[u8]>) -> Vec<u8> {
    use std::io::Write;
    let pack = |b: Vec<u8>| {
        if kpk1 {
            ruzstd::encoding::compress_to_vec(&b[..], ruzstd::encoding::CompressionLevel::Fastest)
        } else {
            b
        }
    };
    let mut zw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    let xml = b"<?xml version=\"1.0\"?><Calibration><XYCalibration><MeterPerPixel>2.5e-7\
                </MeterPerPixel></XYCalibration><ZCalibration><MeterPerUnit>1e-9</MeterPerUnit>\
                </ZCalibration></Calibration>";
    zw.start_file("686613b8-27b5-4a29-8ffc-438c2780873e", o)
        .unwrap();
    zw.write_all(&pack(xml.to_vec())).unwrap();
    let bytes: Vec<u8> = counts.iter().flat_map(|c| c.to_le_bytes()).collect();
    zw.start_file("4cdb0c75-5706-48cc-a9a1-adf395d609ae", o)
        .unwrap();
    zw.write_all(&pack(zon_array(w, h, 4, &bytes))).unwrap();
    if let Some(f) = flags {
        zw.start_file("9e7ca6dd-0e6a-4d7b-8986-f0a7b773c916", o)
            .unwrap();
        zw.write_all(&pack(zon_array(w, h, 1, f))).unwrap();
    }
    let zipped = zw.finish().unwrap().into_inner();
    let mut b = if kpk1 { b"KPK1" } else { b"KPK0" }.to_vec();
    b.extend(6u32.to_le_bytes());
    b.extend(b"BM\0\0\0\0");
    b.extend(zipped);
    b
}

#[test]
fn zon_kpk1_reads_as_kpk0_with_its_validity_flags() {
    let (w, h) = (6, 4);
    let counts: Vec<i32> = (0..24).map(|i| i * 1000 - 9000).collect();
    let mut flags = vec![0u8; 24];
    flags[3] = 1;
    flags[10] = 2;
    flags[17] = 4; // not one of the two "not measured" bits
    let plain = read_bytes(
        "a.zon",
        &zon(false, w, h, &counts, None),
        &ReadOptions::default(),
    )
    .unwrap();
    let packed = zon(true, w, h, &counts, Some(&flags));
    assert_eq!(&packed[..4], b"KPK1");
    let t = read_bytes("b.zon", &packed, &ReadOptions::default()).unwrap();
    assert_eq!((t.nx, t.ny), (6, 4));
    assert!(rel(t.dx, 2.5e-7) < 1e-12);
    for (i, (h, c)) in t.heights.iter().zip(&counts).enumerate() {
        if [3, 10].contains(&i) {
            assert!(h.is_nan(), "{i}");
        } else {
            assert_eq!(*h, plain.heights[i], "{i}");
            assert!((h - f64::from(*c) * 1e-9).abs() < 1e-18);
        }
    }
    // A mask of another size is refused by name.
    let wrong = zon(true, w, h, &counts, Some(&[0u8; 12]));
    let e = read_bytes("c.zon", &wrong, &ReadOptions::default());
    assert!(e.is_err());
}

/// A zstd frame header declaring `size` bytes of content (8-byte content size; a 1 KiB
/// window, or the single-segment form whose window is the content), then garbage.
fn zstd_claiming(size: u64, single_segment: bool) -> Vec<u8> {
    let mut f = vec![0x28, 0xB5, 0x2F, 0xFD];
    if single_segment {
        f.push(0xE0);
    } else {
        f.extend([0xC0, 0x00]);
    }
    f.extend(size.to_le_bytes());
    f.extend([0u8; 16]);
    f
}

/// A KPK1 file with these (already compressed) calibration and height entries.
fn kpk1_with(units: &[u8], heights: Option<&[u8]>) -> Vec<u8> {
    use std::io::Write;
    let mut zw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    zw.start_file("686613b8-27b5-4a29-8ffc-438c2780873e", o)
        .unwrap();
    zw.write_all(units).unwrap();
    if let Some(h) = heights {
        zw.start_file("4cdb0c75-5706-48cc-a9a1-adf395d609ae", o)
            .unwrap();
        zw.write_all(h).unwrap();
    }
    let mut b = b"KPK1\0\0\0\0".to_vec();
    b.extend(zw.finish().unwrap().into_inner());
    b
}

fn zstd(b: &[u8]) -> Vec<u8> {
    ruzstd::encoding::compress_to_vec(b, ruzstd::encoding::CompressionLevel::Fastest)
}

#[test]
fn zon_kpk1_huge_claims_are_refused_before_decompressing() {
    let o = ReadOptions::default();
    // A frame declaring 1 TB of content: refused from its header.
    let e = read_bytes(
        "d.zon",
        &kpk1_with(&zstd_claiming(1 << 40, false), None),
        &o,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("declares 1099511627776 bytes"), "{e}");
    // As one segment its window is the content: ruzstd's window limit refuses it.
    let e = read_bytes("d.zon", &kpk1_with(&zstd_claiming(1 << 40, true), None), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("unit calibration") && e.contains("zstd"), "{e}");
    // A height header declaring 65536 rows of 1 MB is refused from its 16 bytes.
    let xml = zstd(
        b"<C><XYCalibration><MeterPerPixel>1e-6</MeterPerPixel></XYCalibration>\
          <ZCalibration><MeterPerUnit>1e-9</MeterPerUnit></ZCalibration></C>",
    );
    let mut head = vec![];
    for v in [1i32 << 18, 1 << 16, 4, 1 << 20] {
        head.extend(v.to_le_bytes());
    }
    let e = read_bytes("e.zon", &kpk1_with(&xml, Some(&zstd(&head))), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("larger than the supported"), "{e}");
    // The same header over a few real rows: the rows it declares are missing.
    head.extend([0u8; 4096]);
    let e = read_bytes("f.zon", &kpk1_with(&xml, Some(&zstd(&head))), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("height data"), "{e}");
}

#[test]
fn zon_kpk1_survives_hostile_input() {
    let (w, h) = (40, 30);
    let counts: Vec<i32> = (0..w * h)
        .map(|i| ((i * 7919) % 20011) as i32 - 10000)
        .collect();
    let flags: Vec<u8> = (0..w * h).map(|i| u8::from(i % 97 == 0)).collect();
    let b = zon(true, w, h, &counts, Some(&flags));
    torture("t.zon", &b, 37, 400);
}

// ---------------------------------------------------------------------------------------
// Zygo DATX

/// The synthetic DATX files and their grids: HDF5's oldest structures (chunks in a
/// version 1 B-tree), its newest with contiguous data, and its newest with chunks in a
/// fixed array and in a single chunk (chunked data shuffled and deflated).
const DATX: [(&str, usize, usize); 4] = [
    ("datx-synth.datx", 70, 50),
    ("datx-synth-latest.datx", 40, 30),
    ("datx-synth-fixed-array.datx", 36, 28),
    ("datx-synth-single-chunk.datx", 24, 20),
];

fn formats(name: &str) -> Vec<u8> {
    std::fs::read(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/surfaces/formats")
            .join(name),
    )
    .unwrap()
}

/// The synthetic files of [`DATX`] give the grid, spacing and unmeasured points
/// `make_synthetic.py` wrote; their statistics are compared with SurfaceTopography's in
/// `formats.rs`.
#[test]
fn datx_old_and_new_hdf5_structures_read_as_written() {
    for (name, nx, ny) in DATX {
        let s = open_bytes(name, &formats(name), &ReadOptions::default()).unwrap();
        assert_eq!(s.format.name(), "datx");
        let t = s.topo;
        assert_eq!((t.nx, t.ny), (nx, ny), "{name}");
        assert!(
            rel(t.dx, 1.25e-6) < 1e-12 && rel(t.dy, 1.5e-6) < 1e-12,
            "{name}"
        );
        let invalid: Vec<usize> = (0..t.heights.len())
            .filter(|&i| t.heights[i].is_nan())
            .collect();
        let mut want: Vec<usize> = (2..4)
            .flat_map(|y| (5..9).map(move |x| y * nx + x))
            .collect();
        want.push((ny - 1) * nx);
        assert_eq!(invalid, want, "{name}");
        // Heights in µm of Sq 0.05 µm: metres of that order.
        let max = t
            .heights
            .iter()
            .filter(|h| h.is_finite())
            .fold(0.0f64, |m, h| m.max(h.abs()));
        assert!(max > 0.05e-6 && max < 1e-6, "{name}: {max}");
    }
}

/// An HDF5 file that is no DATX, and the NetCDF-4 named for what it is.
#[test]
fn other_hdf5_files_are_named() {
    let b = formats("datx-synth-latest.datx");
    let e = open_bytes("x.nc", &b, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("NetCDF-4"), "{e}");
    // The surface renamed: the metadata's path leads nowhere, nor does the default one.
    let mut r = b.clone();
    for (from, to) in [(&b"Surface"[..], &b"Surfacf"[..])] {
        let mut i = 0;
        while let Some(p) = r[i..].windows(from.len()).position(|w| w == from) {
            r[i + p..i + p + from.len()].copy_from_slice(to);
            i += p + 1;
        }
    }
    let e = read_bytes("r.datx", &r, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a Zygo DATX measurement"), "{e}");
}

/// Dimensions patched to huge values are refused before anything is allocated.
#[test]
fn datx_huge_dimensions_are_refused() {
    for (name, nx, ny) in DATX {
        let b = formats(name);
        let (nx, ny) = (nx as u64, ny as u64);

        let mut dims = ny.to_le_bytes().to_vec();
        dims.extend(nx.to_le_bytes());
        let at: Vec<usize> = (0..b.len() - 16)
            .filter(|&i| b[i..i + 16] == dims[..])
            .collect();
        assert!(!at.is_empty(), "{name}: dataspace not found");
        for huge in [1u64 << 40, u64::MAX, 1 << 20] {
            let mut h = b.clone();
            for &p in &at {
                h[p..p + 8].copy_from_slice(&huge.to_le_bytes());
            }
            let e = read_bytes(name, &h, &ReadOptions::default())
                .unwrap_err()
                .to_string();
            assert!(
                [
                    "larger than the supported",
                    "too few",
                    "needed",
                    "chunk index lists"
                ]
                .iter()
                .any(|n| e.contains(n)),
                "{name} {huge}: {e}"
            );
        }
    }
}

#[test]
fn datx_survives_hostile_input() {
    for (i, (name, _, _)) in DATX.into_iter().enumerate() {
        torture(name, &formats(name), 38 + i as u64, 400);
    }
}
