//! FRT MicroProf `.frt`: `FRTM_GLIDERV1.00` (or `1.01`), a u16 block count, then blocks
//! of (u16 id, u32 size — u64 in version 1.01, data). Block 0x66 gives the grid and
//! bits per pixel (16: uint16, 32: int32), 0x67 the scan size [m], 0x6c the height
//! scale [m per count], 0x0b the height image (x fastest). The value 1 marks points
//! that were not measured.

use super::binary::{Cursor, Sample};
use super::{Ctx, Decoded, Raw, Want, check_spacing, decode_grid};
use crate::ReadError;
use std::collections::HashMap;

const MAGIC: &[u8] = b"FRTM_GLIDERV";

/// Read an FRT file (the topography image).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if !bytes.starts_with(MAGIC) || bytes.len() < MAGIC.len() + 6 {
        return Err(ctx.err("magic", "missing `FRTM_GLIDERV`", "not an FRT file"));
    }
    let version = &bytes[MAGIC.len()..MAGIC.len() + 4];
    let wide = match version {
        b"1.00" => false,
        b"1.01" => true,
        v => {
            return Err(ctx.err(
                "version",
                format!(
                    "version `{}` is not 1.00 or 1.01",
                    String::from_utf8_lossy(v)
                ),
                "export the measurement from a MicroProf version this reader knows",
            ));
        }
    };
    let mut c = Cursor::le(bytes, MAGIC.len() + 4);
    let nblocks = c.u16().unwrap_or(0);
    let mut blocks: HashMap<u16, (usize, usize)> = HashMap::new();
    let head = if wide { 10 } else { 6 };
    for i in 0..nblocks {
        // A file cut between blocks still reads the blocks before the cut; the block
        // count says more were written.
        let at = c.pos;
        let header = |c: &mut Cursor<'_>| {
            let id = c.u16()?;
            let size = if wide {
                c.u64()
            } else {
                c.u32().map(u64::from)
            };
            Some((id, size?))
        };
        let Some((id, size)) = header(&mut c) else {
            return Err(ctx.truncated(
                "block count",
                &format!("block {}'s id and size ({nblocks} blocks counted)", i + 1),
                (at as u64, at as u64 + head),
                bytes.len() as u64,
            ));
        };
        let start = c.pos;
        let Some(end) = usize::try_from(size)
            .ok()
            .and_then(|size| start.checked_add(size))
            .filter(|&e| e <= bytes.len())
        else {
            return Err(ctx.truncated(
                &format!("block 0x{id:04x}"),
                &format!("block 0x{id:04x} ({size} bytes)"),
                (start as u64, (start as u64).saturating_add(size)),
                bytes.len() as u64,
            ));
        };
        blocks.entry(id).or_insert((start, end));
        c.pos = end;
    }
    let block = |id: u16, what: &str| -> Result<&[u8], ReadError> {
        blocks.get(&id).map(|&(s, e)| &bytes[s..e]).ok_or_else(|| {
            ctx.err(
                &format!("block 0x{id:04x}"),
                format!("{what} missing"),
                "the file is incomplete; re-export it",
            )
        })
    };
    let grid = block(0x66, "grid")?;
    let mut g = Cursor::le(grid, 0);
    let short = || ctx.err("block 0x0066", "too short", "the file is corrupt");
    let nx = g.u32().ok_or_else(short)? as u64;
    let ny = g.u32().ok_or_else(short)? as u64;
    let bpp = g.u32().ok_or_else(short)?;
    let size = block(0x67, "scan size")?;
    let mut s = Cursor::le(size, 0);
    let sx = s.f64().ok_or_else(short)?;
    let sy = s.f64().ok_or_else(short)?;
    let scale = block(0x6c, "height scale")?;
    let q = Cursor::le(scale, 4).f64().ok_or_else(short)?;
    let kind = match bpp {
        16 => Sample::U16,
        32 => Sample::I32,
        b => {
            return Err(ctx.err(
                "block 0x0066",
                format!("{b} bits per pixel is not supported"),
                "expected 16 or 32",
            ));
        }
    };
    let data = block(0x0b, "topography image")?;
    let raw = decode_grid(
        ctx,
        "block 0x0066 grid",
        (nx, ny),
        ("topography", data),
        kind,
        true,
    )?;
    if !(q.is_finite() && q != 0.0) {
        return Err(ctx.err(
            "block 0x006c",
            format!("height scale {q} is not usable"),
            "the file is corrupt",
        ));
    }
    let dx = check_spacing(ctx, "block 0x0067", sx / nx as f64)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "block 0x0067", sy / ny as f64)?
    };
    let heights = raw
        .into_iter()
        .map(|v| if v == 1.0 { f64::NAN } else { v * q })
        .collect();
    let out = Raw::si(nx as usize, ny as usize, dx, dy, heights, "topography")
        .spacing_from("block 0x0067", "block 0x0067");
    Decoded::single(ctx, want, out)
}
