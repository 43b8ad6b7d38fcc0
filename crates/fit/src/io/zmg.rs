//! KLA Zeta `.zmg` (Zeta optical profilers): the magic `Zeta-Instruments`, a 205-byte
//! little-endian header holding the grid (`u32` at bytes 85 and 89), the pixel steps x, y
//! and the height step (`f32` at bytes 97, 101 and 105, µm) and the length of a comment
//! (`u32` at byte 117) that follows the header; then `nx·ny` signed 16-bit heights, x
//! fastest, in height steps.
//!
//! Sources: SurfaceTopography `IO/ZMG.py` and surfalize `file/zmg.py` (the same layout).
//! No sample file could be obtained (absent from the stored snapshots), so the reader is
//! tested on files written from this description.

use super::{Ctx, Decoded, Raw, Unit, Want, binary, check_spacing, decode_grid};
use crate::ReadError;

/// The magic every ZMG file starts with.
pub(crate) const MAGIC: &[u8] = b"Zeta-Instruments";
const HEADER: usize = 205;

/// Read a ZMG file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `Zeta-Instruments`",
            "not a ZMG file",
        ));
    }
    if bytes.len() < HEADER {
        return Err(ctx.truncated(
            "header",
            "the 205-byte header",
            (0, HEADER as u64),
            bytes.len() as u64,
        ));
    }
    let mut c = binary::Cursor::le(bytes, 85);
    let (nx, ny) = (c.u32().unwrap_or(0), c.u32().unwrap_or(0));
    c.skip(4);
    let (sx, sy, sz) = (
        c.f32().unwrap_or(f64::NAN),
        c.f32().unwrap_or(f64::NAN),
        c.f32().unwrap_or(f64::NAN),
    );
    c.skip(8);
    let comment = c.u32().unwrap_or(0) as usize;
    let dx = check_spacing(ctx, "step_x (byte 97)", sx)?;
    let dy = check_spacing(ctx, "step_y (byte 101)", sy)?;
    if !(sz.is_finite() && sz != 0.0) {
        return Err(ctx.err(
            "step_z (byte 105)",
            format!("height step {sz} is not usable"),
            "the header is corrupt; re-export the measurement",
        ));
    }
    let start = HEADER.saturating_add(comment);
    if start > bytes.len() {
        return Err(ctx.truncated(
            "comment_size (byte 117)",
            "the comment",
            (HEADER as u64, start as u64),
            bytes.len() as u64,
        ));
    }
    let raw = decode_grid(
        ctx,
        "nx × ny (byte 85)",
        (u64::from(nx), u64::from(ny)),
        ("height data", &bytes[start..]),
        binary::Sample::I16,
        true,
    )?;
    let heights = raw.into_iter().map(|v| v * sz).collect();
    Ok(Raw::si(nx as usize, ny as usize, dx, dy, heights, "height")
        .in_units(Unit::Known(1e-6), Unit::Known(1e-6))
        .spacing_from("step_x (byte 97)", "step_y (byte 101)"))
}
