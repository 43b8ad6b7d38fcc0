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
