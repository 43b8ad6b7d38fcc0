//! Scan files written from their formats' descriptions, shared by the damaged-file and
//! hostile-input tests (each damages or truncates them its own way), and the TIFF writer
//! the format tests use too.

// Each test binary that includes this module uses a part of it.
#![allow(dead_code)]

/// A 32 × 24 KLA Zeta ZMG file written from the format description.
pub fn zmg_sample() -> Vec<u8> {
    let mut b = b"Zeta-Instruments".to_vec();
    b.resize(85, 0);
    b.extend(32u32.to_le_bytes());
    b.extend(24u32.to_le_bytes());
    b.extend([0u8; 4]);
    for v in [0.5f32, 0.5, 0.01] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u8; 8]);
    b.extend(0u32.to_le_bytes());
    b.resize(205, 0);
    for i in 0..32 * 24i32 {
        b.extend((((i * 71) % 301 - 150) as i16).to_le_bytes());
    }
    b
}

/// A 16 × 12 Keyence ZON (KPK0) file written from the format description.
pub fn zon_sample() -> Vec<u8> {
    use std::io::Write as _;
    let mut zw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    zw.start_file("686613b8-27b5-4a29-8ffc-438c2780873e", o)
        .unwrap();
    zw.write_all(b"<C><XYCalibration><MeterPerPixel>1e-6</MeterPerPixel></XYCalibration><ZCalibration><MeterPerUnit>1e-9</MeterPerUnit></ZCalibration></C>").unwrap();
    zw.start_file("4cdb0c75-5706-48cc-a9a1-adf395d609ae", o)
        .unwrap();
    for v in [16i32, 12, 4, 64] {
        zw.write_all(&v.to_le_bytes()).unwrap();
    }
    for i in 0..16 * 12i32 {
        zw.write_all(&((i * 37) % 1001 - 500).to_le_bytes())
            .unwrap();
    }
    let mut b = b"KPK0".to_vec();
    b.extend(4u32.to_le_bytes());
    b.extend([0u8; 4]);
    b.extend(zw.finish().unwrap().into_inner());
    b
}

/// A 16 × 8 JPK scan (preview page, one int32 height channel) written from the format
/// description, as in tests/formats.rs.
pub fn jpk_sample() -> Vec<u8> {
    let ascii = |s: &str| {
        let mut v = s.as_bytes().to_vec();
        v.push(0);
        (2u16, v.len() as u32, v)
    };
    let d = |v: f64| (12u16, 1u32, v.to_le_bytes().to_vec());
    let u = |v: u32| (4u16, 1u32, v.to_le_bytes().to_vec());
    let (nx, ny) = (16u32, 8u32);
    type Value = (u16, u32, Vec<u8>);
    type Page = (Vec<(u16, Value)>, Vec<u8>);
    let pages: Vec<Page> = vec![
        (
            vec![
                (256, u(1)),
                (257, u(1)),
                (258, u(8)),
                (0x8000, ascii("1")),
                (0x8042, d(4e-6)),
                (0x8043, d(2e-6)),
            ],
            vec![0],
        ),
        (
            vec![
                (256, u(nx)),
                (257, u(ny)),
                (258, u(32)),
                (339, u(2)),
                (0x8050, ascii("height")),
                (0x8081, ascii("nominal")),
                (0x8090, ascii("nominal")),
                (0x80A2, ascii("m")),
                (0x80A3, ascii("LinearScaling")),
                (0x80A4, d(1e-9)),
            ],
            (0..nx * ny)
                .flat_map(|i| ((i * 37 % 101) as i32).to_le_bytes())
                .collect(),
        ),
    ];
    let pages: Vec<TiffPage> = pages
        .into_iter()
        .map(|(entries, strip)| {
            let entries = entries.into_iter().map(|(t, (k, c, v))| (t, k, c, v));
            (entries.collect(), strip)
        })
        .collect();
    tiff(&pages)
}

/// A TIFF directory entry: tag, type, count, value bytes.
pub type TiffEntry = (u16, u16, u32, Vec<u8>);
/// A TIFF page: its entries and its one strip.
pub type TiffPage = (Vec<TiffEntry>, Vec<u8>);

/// A little-endian TIFF from pages of `(tag, type, count, value bytes)` entries, each page's
/// strip given as bytes (tag 273/279 are filled in): for JPK files written from its
/// description.
pub fn tiff(pages: &[TiffPage]) -> Vec<u8> {
    let mut b = b"II*\0\x08\0\0\0".to_vec();
    // Lay out: each page's IFD, then its out-of-line values and its strip.
    for (k, (entries, strip)) in pages.iter().enumerate() {
        let mut entries = entries.clone();
        entries.push((273, 4, 1, vec![0; 4]));
        entries.push((279, 4, 1, (strip.len() as u32).to_le_bytes().to_vec()));
        entries.sort_by_key(|e| e.0);
        let ifd = b.len();
        let n = entries.len();
        let extra_start = ifd + 2 + 12 * n + 4;
        let mut extra: Vec<u8> = Vec::new();
        let mut dir: Vec<u8> = (n as u16).to_le_bytes().to_vec();
        let mut strip_slot = 0;
        for (tag, kind, count, value) in &entries {
            dir.extend(tag.to_le_bytes());
            dir.extend(kind.to_le_bytes());
            dir.extend(count.to_le_bytes());
            if *tag == 273 {
                strip_slot = dir.len();
            }
            if value.len() <= 4 {
                let mut v = value.clone();
                v.resize(4, 0);
                dir.extend(v);
            } else {
                dir.extend(((extra_start + extra.len()) as u32).to_le_bytes());
                extra.extend(value);
                if extra.len() % 2 == 1 {
                    extra.push(0);
                }
            }
        }
        let strip_at = extra_start + extra.len();
        dir[strip_slot..strip_slot + 4].copy_from_slice(&(strip_at as u32).to_le_bytes());
        let next = if k + 1 < pages.len() {
            strip_at + strip.len()
        } else {
            0
        };
        dir.extend((next as u32).to_le_bytes());
        b.extend(dir);
        b.extend(extra);
        b.extend(strip);
    }
    b
}
