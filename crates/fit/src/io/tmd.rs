//! TrueMap `.tmd`: a 32-byte magic (`Binary TrueMap Data File v2.0`), a 24-byte comment,
//! u32 columns and rows, float32 lengths x and y and offsets (mm), then float32 heights
//! in mm, x fastest. Non-finite values are invalid.

use super::binary::{Cursor, Sample};
use super::{Ctx, Decoded, Raw, Unit, Want, check_spacing, decode_grid};
use crate::ReadError;

const HEADER: usize = 32 + 24 + 4 + 4 + 4 * 4;

/// Read a TrueMap file.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if !bytes.starts_with(b"Binary TrueMap Data File") {
        return Err(ctx.err(
            "magic",
            "missing `Binary TrueMap Data File`",
            "not a TrueMap file",
        ));
    }
    if bytes.len() < HEADER {
        return Err(ctx.short("header", HEADER as u64, bytes.len() as u64));
    }
    let mut c = Cursor::le(bytes, 56);
    let short = || ctx.short("header", HEADER as u64, bytes.len() as u64);
    let nx = c.u32().ok_or_else(short)? as u64;
    let ny = c.u32().ok_or_else(short)? as u64;
    let lx = c.f32().ok_or_else(short)?;
    let ly = c.f32().ok_or_else(short)?;
    let data = &bytes[HEADER..];
    let raw = decode_grid(
        ctx,
        "columns × rows",
        (nx, ny),
        ("data", data),
        Sample::F32,
        true,
    )?;
    let dx = check_spacing(ctx, "x length", lx / nx as f64)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "y length", ly / ny as f64)?
    };
    let out = Raw::si(nx as usize, ny as usize, dx, dy, raw, "height")
        .spacing_from("x length", "y length")
        .in_units(Unit::Known(1e-3), Unit::Known(1e-3));
    Decoded::single(ctx, want, out)
}
