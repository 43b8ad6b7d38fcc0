//! Park Systems (PSIA) TIFF: an ordinary TIFF preview image plus private tags: 50432
//! magic 0x0E031301, 50433 version (0x1000001 or 0x1000002), 50434 the data and 50435 a
//! little-endian header (image type, UTF-16 channel name, grid, scan size [µm], data
//! gain, scale and unit; version 2 adds the data type: int16, int32 or float32). Heights
//! are `raw · scale · gain` in the data unit, x fastest.

use super::binary::{Cursor, Sample};
use super::{
    ChannelInfo, Ctx, Decoded, Raw, Sniff, Unit, Want, check_spacing, decode_grid, tiff, units,
};
use crate::ReadError;

const MAGIC: u32 = 0x0E03_1301;
const TAG_MAGIC: u16 = 50432;
const TAG_VERSION: u16 = 50433;
const TAG_DATA: u16 = 50434;
const TAG_HEADER: u16 = 50435;
/// JPK's `FileFormatVersion`, the first of the private tags JPK image scans carry.
const TAG_JPK_VERSION: u16 = 0x8000;

/// Content check: a TIFF carrying the Park magic tag (a plain TIFF is only "maybe", so
/// it gets this reader's explanation rather than "unknown format").
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if !tiff::is_tiff(b) {
        return Sniff::No;
    }
    match tiff::Tiff::parse(b) {
        Ok(t) if t.uint(TAG_MAGIC) == Some(MAGIC) => Sniff::Magic,
        _ => Sniff::Maybe,
    }
}

fn utf16(b: &[u8]) -> String {
    let units: Vec<u16> = b
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .take_while(|&u| u != 0)
        .collect();
    String::from_utf16_lossy(&units).trim().to_string()
}

/// Read a Park Systems TIFF.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let t = tiff::Tiff::parse(bytes)
        .map_err(|e| ctx.err("TIFF", e, "the file is truncated or not a TIFF"))?;
    if t.get(TAG_JPK_VERSION).is_some() {
        return Err(ctx.err(
            "tag 32768",
            "this TIFF is a JPK image scan (JPK's private tags), not a Park Systems file",
            "read it with --format jpk (or give it the .jpk extension)",
        ));
    }
    if t.uint(TAG_MAGIC) != Some(MAGIC) {
        return Err(ctx.err(
            "tag 50432",
            "this TIFF has no Park Systems data (magic tag missing)",
            "only Park Systems TIFFs hold heights; a plain image has no height scale",
        ));
    }
    let version = t.uint(TAG_VERSION).unwrap_or(0);
    let min_header = match version {
        0x0100_0001 => 356,
        0x0100_0002 => 580,
        v => {
            return Err(ctx.err(
                "tag 50433",
                format!("version 0x{v:x} is not 0x1000001 or 0x1000002"),
                "re-export the image with XEI",
            ));
        }
    };
    let header = t.get(TAG_HEADER).map(|e| e.value).unwrap_or(&[]);
    if header.len() < min_header {
        return Err(ctx.short("tag 50435 (header)", min_header as u64, header.len() as u64));
    }
    let image_type = Cursor::le(header, 0).u32().unwrap_or(u32::MAX);
    if image_type != 0 {
        return Err(ctx.err(
            "image type",
            format!("image type {image_type} is not a 2D map (0)"),
            "export a topography image",
        ));
    }
    let name = utf16(&header[4..68]);
    let at = |o: usize| Cursor::le(header, o);
    let nx = at(100).u32().unwrap_or(0) as u64;
    let ny = at(104).u32().unwrap_or(0) as u64;
    let sx = at(140).f64().unwrap_or(f64::NAN);
    let sy = at(148).f64().unwrap_or(f64::NAN);
    let gain = at(220).f64().unwrap_or(f64::NAN);
    let scale = at(228).f64().unwrap_or(f64::NAN);
    let unit = utf16(&header[244..260]);
    let kind = if version == 0x0100_0002 {
        match at(348).u32().unwrap_or(u32::MAX) {
            0 => Sample::I16,
            1 => Sample::I32,
            2 => Sample::F32,
            d => {
                return Err(ctx.err(
                    "data type",
                    format!("data type {d} is not int16, int32 or float32"),
                    "the file is corrupt",
                ));
            }
        }
    } else {
        Sample::I16
    };
    let data = t.get(TAG_DATA).map(|e| e.value).unwrap_or(&[]);
    let raw = decode_grid(
        ctx,
        "xres × yres",
        (nx, ny),
        ("tag 50434 (data)", data),
        kind,
        true,
    )?;
    let q = gain * scale;
    if !(q.is_finite() && q != 0.0) {
        return Err(ctx.err(
            "data gain/scale",
            format!("height scale {q} is not usable"),
            "the header is corrupt",
        ));
    }
    let (height_unit, is_length) = match units::length_factor(&unit) {
        Some(f) => (Unit::Known(f), true),
        None => (Unit::Unknown, false),
    };
    let dx = check_spacing(ctx, "X scan size", sx / nx as f64)?;
    let dy = check_spacing(ctx, "Y scan size", sy / ny as f64)?;
    let heights = raw.into_iter().map(|v| v * q).collect();
    let out = Raw::si(nx as usize, ny as usize, dx, dy, heights, name)
        .spacing_from("X scan size", "Y scan size")
        .in_units(height_unit, Unit::Known(1e-6));
    let info = ChannelInfo {
        unit,
        is_height: is_length,
        ..out.info(0)
    };
    Decoded::single_listed(ctx, want, info, out)
}
