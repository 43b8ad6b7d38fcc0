//! Keyence `.zon` (VR series 3D profilometers): the magic `KPK0` or `KPK1`, a `u32` size
//! and a BMP thumbnail of that size, then a zip archive whose entries are named by fixed
//! UUIDs. `686613b8-27b5-4a29-8ffc-438c2780873e` is XML holding
//! `XYCalibration/MeterPerPixel` and `ZCalibration/MeterPerUnit`;
//! `4cdb0c75-5706-48cc-a9a1-adf395d609ae` holds the heights: `width, height, element size
//! (4), row bytes` as little-endian `i32`, then `height` rows of `row bytes` each, whose
//! first `width` elements are `i32` heights in units of `MeterPerUnit`. The optional
//! `9e7ca6dd-0e6a-4d7b-8986-f0a7b773c916` has the same layout with `u8` flags: a pixel
//! with either of the low two bits set was not measured. In `KPK1` files
//! every entry's content is in addition one zstd frame (decoded with `ruzstd`, pure Rust;
//! a frame declaring more than [`MAX_ENTRY`] bytes is refused before anything is
//! allocated, and decoding stops there whatever the frame declares).
//!
//! Sources: SurfaceTopography `IO/ZON.py` (the UUIDs, the layout, that `KPK1` wraps
//! each entry in a zstd stream; the validity flags from its version 1.27.1). No sample file could be obtained (absent from the stored
//! snapshot), so the reader is tested on files written from this description: in the
//! tests (`KPK0` and `KPK1`) and `data/surfaces/formats/zon-kpk1-synth.zon` (written by
//! `make_synthetic.py` there with the `zstandard` package, an encoder independent of the
//! decoder used here), which SurfaceTopography 1.27.1 also reads.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid};
use crate::ReadError;
use std::io::Read;

const UNITS: &str = "686613b8-27b5-4a29-8ffc-438c2780873e";
const HEIGHTS: &str = "4cdb0c75-5706-48cc-a9a1-adf395d609ae";
/// Per-pixel flags (`u8`, same layout as the heights); optional.
const VALID: &str = "9e7ca6dd-0e6a-4d7b-8986-f0a7b773c916";
/// A pixel with either of these flag bits set was not measured.
const INVALID_BITS: u8 = 0x03;
const CORRUPT: &str = "the ZON file is corrupt or truncated; export it again";
/// Largest entry read (bytes), compressed or decompressed.
pub const MAX_ENTRY: u64 = 4 << 30;
/// Largest unit-calibration XML decompressed (bytes); Keyence's are a few kB.
const MAX_XML: u64 = 16 << 20;

/// The magics of ZON files: `KPK0`, and `KPK1` with zstd-compressed entries.
pub(crate) const MAGICS: &[&[u8]] = &[b"KPK0", b"KPK1"];

/// Read a ZON file (its height map).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

fn entry<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &mut zip::ZipArchive<R>,
    name: &str,
    what: &str,
) -> Result<Vec<u8>, ReadError> {
    let f = zip.by_name(name).map_err(|_| {
        ctx.err(
            what,
            format!("the archive has no entry {name}"),
            "the ZON file is incomplete; export it again",
        )
    })?;
    let declared = f.size();
    if declared > MAX_ENTRY {
        return Err(ctx.err(what, format!("the entry claims {declared} bytes"), CORRUPT));
    }
    let mut out = Vec::with_capacity(declared.min(64 << 20) as usize);
    f.take(MAX_ENTRY)
        .read_to_end(&mut out)
        .map_err(|e| ctx.err(what, format!("cannot decompress ({e})"), CORRUPT))?;
    Ok(out)
}

/// The first `cap` bytes of the content of the one zstd frame at the start of `data` (all
/// of it when shorter). A frame declaring more than [`MAX_ENTRY`] bytes is refused before
/// anything is allocated.
fn unzstd(ctx: Ctx<'_>, what: &str, data: &[u8], cap: u64) -> Result<Vec<u8>, ReadError> {
    use ruzstd::decoding::StreamingDecoder;
    let bad = |e: String| ctx.err(what, format!("not a readable zstd frame ({e})"), CORRUPT);
    let mut source = data;
    let mut frame = StreamingDecoder::new(&mut source).map_err(|e| bad(e.to_string()))?;
    // 0 when the frame does not declare its size.
    let declared = frame.decoder.content_size();
    if declared > MAX_ENTRY {
        return Err(ctx.err(
            what,
            format!("the zstd frame declares {declared} bytes, more than the {MAX_ENTRY} read"),
            CORRUPT,
        ));
    }
    let mut out = Vec::with_capacity(declared.min(cap).min(64 << 20) as usize);
    (&mut frame)
        .take(cap)
        .read_to_end(&mut out)
        .map_err(|e| bad(e.to_string()))?;
    Ok(out)
}

/// An array entry's header, checked for elements of `size` bytes: `(width, height, row
/// bytes)`.
fn grid_header(
    ctx: Ctx<'_>,
    what: &str,
    data: &[u8],
    size: i32,
) -> Result<(usize, usize, usize), ReadError> {
    let mut c = binary::Cursor::le(data, 0);
    let mut int = || {
        c.i32()
            .ok_or_else(|| ctx.short(&format!("{what} header"), 16, data.len() as u64))
    };
    let (w, h, elem, row) = (int()?, int()?, int()?, int()?);
    if elem != size || w <= 0 || h <= 0 || (row as i64) < i64::from(size) * w as i64 {
        return Err(ctx.err(
            &format!("{what} header"),
            format!("width {w}, height {h}, element size {elem}, row bytes {row}"),
            CORRUPT,
        ));
    }
    // Rows of at most MAX_POINTS bytes in all, before any is decompressed.
    checked_grid(ctx, what, row as u64, h as u64, 1, u64::MAX)?;
    Ok((w as usize, h as usize, row as usize))
}

/// An array entry (`name`, zstd-compressed or not) of `size`-byte elements (`i32` heights,
/// `u8` validity flags): `(width, height, values)`, the row padding dropped.
fn array<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &mut zip::ZipArchive<R>,
    (name, zstd): (&str, bool),
    what: &str,
    size: i32,
) -> Result<(usize, usize, Vec<f64>), ReadError> {
    let mut data = entry(ctx, zip, name, what)?;
    if zstd {
        // The header first, so that no more than the grid it declares is decompressed.
        let (_, h, row) = grid_header(ctx, what, &unzstd(ctx, what, &data, 16)?, size)?;
        data = unzstd(ctx, what, &data, 16 + (h * row) as u64)?;
    }
    let (w, h, row) = grid_header(ctx, what, &data, size)?;
    let rows = &data[16..];
    checked_grid(ctx, what, row as u64, h as u64, 1, rows.len() as u64)?;
    let size = size as usize;
    let mut values = Vec::with_capacity(w * h);
    for y in 0..h {
        let line = &rows[y * row..y * row + size * w];
        values.extend(line.chunks_exact(size).map(|b| match *b {
            [a, b, c, d] => f64::from(i32::from_le_bytes([a, b, c, d])),
            [a] => f64::from(a),
            _ => f64::NAN,
        }));
    }
    Ok((w, h, values))
}

/// The text of the first element named `tag` inside an element named `parent`.
fn xml_value(xml: &str, parent: &str, tag: &str) -> Option<f64> {
    let p = xml.find(&format!("<{parent}"))?;
    let rest = &xml[p..];
    let open = rest.find(&format!("<{tag}>"))? + tag.len() + 2;
    let close = rest[open..].find(&format!("</{tag}>"))?;
    rest[open..open + close].trim().parse().ok()
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let zstd = bytes.starts_with(b"KPK1");
    if !zstd && !bytes.starts_with(b"KPK0") {
        return Err(ctx.err(
            "magic",
            "the file does not start with `KPK0` or `KPK1`",
            "not a ZON file",
        ));
    }
    let bmp = binary::Cursor::le(bytes, 4)
        .u32()
        .ok_or_else(|| ctx.truncated("thumbnail size", "the header", (0, 8), bytes.len() as u64))?
        as u64;
    let start = 8 + bmp;
    if start > bytes.len() as u64 {
        return Err(ctx.truncated(
            "thumbnail size",
            "the thumbnail",
            (8, start),
            bytes.len() as u64,
        ));
    }
    let mut zip =
        zip::ZipArchive::new(std::io::Cursor::new(&bytes[start as usize..])).map_err(|e| {
            ctx.err(
                "zip container",
                format!("not a readable archive ({e})"),
                CORRUPT,
            )
        })?;
    let mut xml = entry(ctx, &mut zip, UNITS, "unit calibration")?;
    if zstd {
        xml = unzstd(ctx, "unit calibration", &xml, MAX_XML)?;
    }
    let xml = String::from_utf8_lossy(&xml);
    let per_pixel = xml_value(&xml, "XYCalibration", "MeterPerPixel").ok_or_else(|| {
        ctx.err(
            "XYCalibration/MeterPerPixel",
            "missing or not a number",
            CORRUPT,
        )
    })?;
    let per_unit = xml_value(&xml, "ZCalibration", "MeterPerUnit")
        .filter(|v| v.is_finite() && *v != 0.0)
        .ok_or_else(|| {
            ctx.err(
                "ZCalibration/MeterPerUnit",
                "missing or not a usable number",
                CORRUPT,
            )
        })?;
    let d = check_spacing(ctx, "XYCalibration/MeterPerPixel", per_pixel)?;
    let (w, h, mut heights) = array(ctx, &mut zip, (HEIGHTS, zstd), "height data", 4)?;
    for v in &mut heights {
        *v *= per_unit;
    }
    if zip.by_name(VALID).is_ok() {
        let (mw, mh, mask) = array(ctx, &mut zip, (VALID, zstd), "validity mask", 1)?;
        if (mw, mh) != (w, h) {
            return Err(ctx.err(
                "validity mask",
                format!("the mask is {mw} × {mh}, the heights {w} × {h}"),
                CORRUPT,
            ));
        }
        for (v, m) in heights.iter_mut().zip(mask) {
            if m as u8 & INVALID_BITS != 0 {
                *v = f64::NAN;
            }
        }
    }
    Ok(Raw::si(w, h, d, d, heights, "height")
        .spacing_from("XYCalibration/MeterPerPixel", "XYCalibration/MeterPerPixel"))
}
