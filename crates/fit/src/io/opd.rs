//! Veeco/Bruker Wyko Vision `.opd`. After a 2-byte header, a directory of 24-byte block
//! descriptors (16-byte name, i16 type, i32 length, u16 attributes), the first of which
//! describes the directory itself; the blocks follow in order. Array blocks (`RAW DATA`,
//! `RAW_DATA`, `OPD`, `Raw`) start with u16 x and y sizes and the element size (1, 2 or
//! 4: u8, int16, float32), then the values stored column by column (y fastest, last row
//! first). `Pixel_size` [mm], `Aspect`, `Wavelength` [nm] and `Mult` scale them: heights
//! are `raw · λ / Mult` nm. Values ≥ 1e38 (float) or ≥ 32766 (int16) are invalid.

use super::binary::Cursor;
use super::{ChannelInfo, Ctx, Decoded, Raw, Unit, Want, check_spacing, checked_grid};
use crate::ReadError;

const BLOCK: usize = 24;

#[derive(Debug, Clone)]
struct Block {
    name: String,
    len: usize,
    offset: usize,
}

/// Read a Wyko OPD file.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let blocks = directory(ctx, bytes)?;
    let value = |name: &str| blocks.iter().find(|b| b.name == name && b.len > 0);
    let f32_of = |b: &Block| Cursor::le(bytes, b.offset).f32();
    let wavelength = value("Wavelength").and_then(f32_of).ok_or_else(|| {
        ctx.err(
            "Wavelength",
            "missing, so the height scale is unknown",
            "the file is incomplete; re-export it",
        )
    })?;
    let mult = value("Mult")
        .and_then(|b| Cursor::le(bytes, b.offset).u16())
        .map_or(1.0, |m| m as f64);
    let aspect = value("Aspect").and_then(f32_of).unwrap_or(1.0);
    let pixel = value("Pixel_size").and_then(f32_of);
    let arrays: Vec<&Block> = blocks
        .iter()
        .filter(|b| b.len > 6 && matches!(b.name.as_str(), "RAW DATA" | "RAW_DATA" | "OPD" | "Raw"))
        .collect();
    if arrays.is_empty() {
        return Err(ctx.err(
            "RAW_DATA",
            "no data array in the file",
            "the file holds no measurement",
        ));
    }
    let channels: Vec<ChannelInfo> = arrays
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let mut h = Cursor::le(bytes, b.offset);
            let (nx, ny) = (h.u16().unwrap_or(0), h.u16().unwrap_or(0));
            let height = matches!(b.name.as_str(), "RAW DATA" | "RAW_DATA" | "OPD" | "Raw");
            ChannelInfo {
                index: i,
                name: b.name.clone(),
                unit: if height { "nm".into() } else { String::new() },
                is_height: height,
                nx: nx as usize,
                ny: ny as usize,
            }
        })
        .collect();
    Decoded::pick(ctx, want, channels, |selected, _| {
        let b = arrays[selected];
        let mut h = Cursor::le(bytes, b.offset);
        let short_b = || ctx.short(&b.name, (b.offset + b.len) as u64, bytes.len() as u64);
        let nx = h.u16().ok_or_else(short_b)? as u64;
        let ny = h.u16().ok_or_else(short_b)? as u64;
        let elsize = h.u16().ok_or_else(short_b)? as u64;
        if !matches!(elsize, 1 | 2 | 4) {
            return Err(ctx.err(
                &b.name,
                format!("element size {elsize} is not 1, 2 or 4"),
                "the file is corrupt",
            ));
        }
        let avail = (bytes.len().saturating_sub(h.pos)).min(b.len.saturating_sub(6)) as u64;
        let n = checked_grid(ctx, &b.name, nx, ny, elsize, avail)?;
        let (nxu, nyu) = (nx as usize, ny as usize);
        let q = wavelength / mult;
        let mut heights = vec![f64::NAN; n];
        // Column by column (y fastest), the last row first.
        for x in 0..nxu {
            for j in 0..nyu {
                let v = match elsize {
                    1 => h.u8().map(f64::from),
                    2 => h
                        .i16()
                        .map(|v| if v >= 32766 { f64::NAN } else { v as f64 }),
                    _ => h.f32().map(|v| if v.abs() >= 1e38 { f64::NAN } else { v }),
                }
                .ok_or_else(short_b)?;
                let y = nyu - 1 - j;
                heights[y * nxu + x] = v * q;
            }
        }
        let pixel = pixel.ok_or_else(|| {
            ctx.err(
                "Pixel_size",
                "missing, so the lateral size is unknown",
                "pass --pixel-size",
            )
        });
        let (spacing, lateral_unit) = match pixel {
            Ok(p) => {
                let dx = check_spacing(ctx, "Pixel_size", p)?;
                (Some((dx, dx * aspect)), Unit::Known(1e-3))
            }
            Err(_) => (None, Unit::Known(1e-3)),
        };
        Ok(Raw {
            nx: nxu,
            ny: nyu,
            heights,
            height_unit: Unit::Known(1e-9),
            spacing,
            lateral_unit,
            spacing_fields: ("Pixel_size".into(), "Pixel_size × Aspect".into()),
            channel: b.name.clone(),
            notes: Vec::new(),
        })
    })
}

/// The blocks the directory lists, each checked to lie within the file.
fn directory(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Vec<Block>, ReadError> {
    let short = |need: usize| ctx.short("directory", need as u64, bytes.len() as u64);
    let mut c = Cursor::le(bytes, 2);
    let dir_name = c.text(16).ok_or_else(|| short(26))?;
    let _dir_type = c.i16().ok_or_else(|| short(26))?;
    let dir_len = c.i32().ok_or_else(|| short(26))?;
    let _attr = c.u16().ok_or_else(|| short(26))?;
    if dir_name != "Directory" {
        return Err(ctx.err(
            "Directory",
            format!("the first block is `{dir_name}`, not the directory"),
            "not a Wyko OPD file",
        ));
    }
    if dir_len <= 0 || !(dir_len as usize).is_multiple_of(BLOCK) {
        return Err(ctx.err(
            "Directory",
            format!("directory length {dir_len} is not a positive multiple of {BLOCK}"),
            "the file is corrupt",
        ));
    }
    let nblocks = dir_len as usize / BLOCK;
    let mut offset = 2 + dir_len as usize;
    let mut blocks = Vec::with_capacity(nblocks.min(4096));
    for _ in 1..nblocks {
        let name = c.text(16).ok_or_else(|| short(2 + dir_len as usize))?;
        let _kind = c.i16().ok_or_else(|| short(2 + dir_len as usize))?;
        let len = c.i32().ok_or_else(|| short(2 + dir_len as usize))?;
        let _attr = c.u16().ok_or_else(|| short(2 + dir_len as usize))?;
        let len = len.max(0) as usize;
        blocks.push(Block { name, len, offset });
        offset = offset.saturating_add(len);
    }
    // Every block, not only those read: a copy cut short holds the first arrays whole,
    // and the scale blocks missing from its end would be taken as absent (Mult = 1).
    let file_len = bytes.len() as u64;
    if let Some(b) = blocks
        .iter()
        .find(|b| b.offset.saturating_add(b.len) as u64 > file_len)
    {
        return Err(ctx.truncated(
            "Directory",
            &format!("block `{}` ({} bytes)", b.name, b.len),
            (b.offset as u64, b.offset.saturating_add(b.len) as u64),
            file_len,
        ));
    }
    Ok(blocks)
}
