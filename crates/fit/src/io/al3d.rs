//! Alicona Imaging `.al3d` (focus variation). The magic `AliconaImaging\0\r\n`, then
//! 52-byte tags (20-byte key, 30-byte value, CR LF): `Version`, `TagCount`, then
//! `TagCount` tags such as `Cols`, `Rows`, `PixelSizeXMeter`, `PixelSizeYMeter`,
//! `DepthImageOffset`, `InvalidPixelValue`. The depth image is float32 metres, one row
//! per scan line, each row padded to a multiple of 8 bytes. NaN or the invalid-pixel
//! value mark points that were not measured.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, header_value};
use crate::ReadError;
use std::collections::HashMap;

const MAGIC: &[u8] = b"AliconaImaging\x00\r\n";
const TAG: usize = 52;

/// Read an AL3D file (its depth image).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "missing `AliconaImaging`",
            "not an Alicona AL3D file",
        ));
    }
    let tag_at = |i: usize| -> Option<(String, String)> {
        let off = MAGIC.len() + i * TAG;
        let t = bytes.get(off..off + TAG)?;
        if &t[50..52] != b"\r\n" {
            return None;
        }
        Some((binary::cstr(&t[..20]), binary::cstr(&t[20..50])))
    };
    let corrupt = |what: &str| {
        ctx.err(
            what,
            "missing or malformed header tag",
            "the AL3D file is truncated or corrupt",
        )
    };
    let (k0, _version) = tag_at(0).ok_or_else(|| corrupt("Version"))?;
    let (k1, count) = tag_at(1).ok_or_else(|| corrupt("TagCount"))?;
    if k0 != "Version" || k1 != "TagCount" {
        return Err(corrupt("Version/TagCount"));
    }
    let count: usize = count
        .trim()
        .parse()
        .ok()
        .filter(|&c: &usize| c < 10_000)
        .ok_or_else(|| corrupt("TagCount"))?;
    let mut tags = HashMap::new();
    for i in 0..count {
        let (k, v) = tag_at(2 + i).ok_or_else(|| corrupt(&format!("tag {}", i + 2)))?;
        tags.insert(k, v);
    }
    const INCOMPLETE: &str = "the AL3D header is incomplete";
    let num = |k: &str| header_value::<f64>(ctx, &tags, k, "missing or not a number", INCOMPLETE);
    let count_of = |k: &str| {
        header_value::<u64>(
            ctx,
            &tags,
            k,
            "missing or not a non-negative integer",
            INCOMPLETE,
        )
    };
    let nx = count_of("Cols")?;
    let ny = count_of("Rows")?;
    let offset = count_of("DepthImageOffset")?;
    let invalid = tags
        .get("InvalidPixelValue")
        .and_then(|v| v.trim().parse::<f64>().ok())
        .unwrap_or(f64::NAN);
    let stride = nx.saturating_mul(4).div_ceil(8).saturating_mul(8);
    let avail = (bytes.len() as u64).saturating_sub(offset);
    if offset > bytes.len() as u64 {
        return Err(ctx.short("DepthImageOffset", offset, bytes.len() as u64));
    }
    // The last row needs only its values, not its padding.
    let need_rows = |ny: u64| ny.saturating_sub(1).saturating_mul(stride) + nx * 4;
    checked_grid(ctx, "Cols × Rows", nx, ny, 1, u64::MAX)?;
    if need_rows(ny) > avail {
        return Err(ctx.short("depth image", need_rows(ny), avail));
    }
    let data = &bytes[offset as usize..];
    let mut heights = Vec::with_capacity((nx * ny) as usize);
    for y in 0..ny as usize {
        let row = &data[y * stride as usize..];
        let vals = binary::decode(row, binary::Sample::F32, true, nx as usize)
            .ok_or_else(|| ctx.short("depth image", need_rows(ny), avail))?;
        heights.extend(vals.into_iter().map(|v| {
            let bad = !v.is_finite()
                || (invalid.is_finite() && (v - invalid).abs() <= 1.5e-7 * invalid.abs());
            if bad { f64::NAN } else { v }
        }));
    }
    // The texture planes follow the depth image to the end of the file, one byte or more
    // per pixel (their sample size is not stated): a file cut inside them holds the depth
    // image whole, and reading it would hide that the copy is broken.
    let texture = count_of("TextureImageOffset").unwrap_or(0);
    let planes = count_of("NumberOfPlanes").unwrap_or(0);
    if texture > 0 && planes > 0 {
        let end = planes
            .saturating_mul(ny)
            .saturating_mul(nx)
            .saturating_add(texture);
        if end > bytes.len() as u64 {
            return Err(ctx.truncated(
                "TextureImageOffset",
                &format!("{planes} texture planes of {nx} × {ny} pixels"),
                (texture, end),
                bytes.len() as u64,
            ));
        }
    }
    let dx = check_spacing(ctx, "PixelSizeXMeter", num("PixelSizeXMeter")?)?;
    let dy = check_spacing(ctx, "PixelSizeYMeter", num("PixelSizeYMeter")?)?;
    let raw = Raw::si(nx as usize, ny as usize, dx, dy, heights, "depth")
        .spacing_from("PixelSizeXMeter", "PixelSizeYMeter");
    Decoded::single(ctx, want, raw)
}
