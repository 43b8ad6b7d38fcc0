//! Keyence `.zon` (VR series 3D profilometers): the magic `KPK0`, a `u32` size and a BMP
//! thumbnail of that size, then a zip archive whose entries are named by fixed UUIDs.
//! `686613b8-27b5-4a29-8ffc-438c2780873e` is XML holding `XYCalibration/MeterPerPixel` and
//! `ZCalibration/MeterPerUnit`; `4cdb0c75-5706-48cc-a9a1-adf395d609ae` holds the heights:
//! `width, height, element size (4), row bytes` as little-endian `i32`, then `height` rows
//! of `row bytes` each, whose first `width` elements are `i32` heights in units of
//! `MeterPerUnit`.
//!
//! Not read: `KPK1` files, whose entries are zstd-compressed (refused naming that).
//!
//! Sources: SurfaceTopography `IO/ZON.py` (the UUIDs and the layout). No sample file could
//! be obtained (absent from the stored snapshot), so the reader is tested on files written
//! from this description.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid};
use crate::ReadError;
use std::io::Read;

const UNITS: &str = "686613b8-27b5-4a29-8ffc-438c2780873e";
const HEIGHTS: &str = "4cdb0c75-5706-48cc-a9a1-adf395d609ae";
const CORRUPT: &str = "the ZON file is corrupt or truncated; export it again";
/// Largest entry read (bytes).
const MAX_ENTRY: u64 = 4 << 30;

/// The magics of ZON files (`KPK1` is recognised to be refused by name).
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

/// The text of the first element named `tag` inside an element named `parent`.
fn xml_value(xml: &str, parent: &str, tag: &str) -> Option<f64> {
    let p = xml.find(&format!("<{parent}"))?;
    let rest = &xml[p..];
    let open = rest.find(&format!("<{tag}>"))? + tag.len() + 2;
    let close = rest[open..].find(&format!("</{tag}>"))?;
    rest[open..open + close].trim().parse().ok()
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if bytes.starts_with(b"KPK1") {
        return Err(ctx.err(
            "magic",
            "a Keyence ZON file with zstd-compressed entries (KPK1), which is not read yet",
            "export the measurement from the Keyence software as CSV heights or X3P",
        ));
    }
    if !bytes.starts_with(b"KPK0") {
        return Err(ctx.err(
            "magic",
            "the file does not start with `KPK0`",
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
    let xml = entry(ctx, &mut zip, UNITS, "unit calibration")?;
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
    let data = entry(ctx, &mut zip, HEIGHTS, "height data")?;
    let mut c = binary::Cursor::le(&data, 0);
    let mut int = || {
        c.i32()
            .ok_or_else(|| ctx.short("height data header", 16, data.len() as u64))
    };
    let (w, h, elem, row) = (int()?, int()?, int()?, int()?);
    if elem != 4 || w <= 0 || h <= 0 || (row as i64) < 4 * w as i64 {
        return Err(ctx.err(
            "height data header",
            format!("width {w}, height {h}, element size {elem}, row bytes {row}"),
            CORRUPT,
        ));
    }
    let (w, h, row) = (w as usize, h as usize, row as usize);
    let rows = &data[16..];
    checked_grid(
        ctx,
        "height data",
        row as u64,
        h as u64,
        1,
        rows.len() as u64,
    )?;
    let mut heights = Vec::with_capacity(w * h);
    for y in 0..h {
        let line = &rows[y * row..y * row + 4 * w];
        heights.extend(
            line.chunks_exact(4)
                .map(|b| f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])) * per_unit),
        );
    }
    Ok(Raw::si(w, h, d, d, heights, "height")
        .spacing_from("XYCalibration/MeterPerPixel", "XYCalibration/MeterPerPixel"))
}
