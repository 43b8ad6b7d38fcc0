//! NanoFocus µsurf `.nms` (confocal): a 3468-byte little-endian header, then `nx·ny`
//! unsigned 16-bit heights, x fastest (a grey-scale intensity image may follow). The
//! header holds the height range `zmin, zmax` [µm] (two doubles at byte 16), the grid
//! (two u32 at byte 1368) and the pixel spacing (two doubles at byte 1376, in nm). A
//! height is `zmin + raw / 65534 · (zmax − zmin)`.
//!
//! The pixel spacing is read in nanometres, as surfalize (`file/nms.py`) does: the two
//! sample files then span 160 µm with 312.5 nm pixels, a confocal field of view.
//! SurfaceTopography 1.27 (`IO/NMS.py`) reads the same number as millimetres, a field of
//! 160 m, so its slopes are 10⁶ times smaller than these; its heights (and Sq) agree.
//!
//! Sources: SurfaceTopography `IO/NMS.py` and surfalize `file/nms.py` (the header
//! offsets); the two public sample files `nms-1.nms`, `nms-2.nms` of SurfaceTopography.

use super::{Ctx, Decoded, Raw, Sniff, Unit, Want, binary, check_spacing, decode_grid};
use crate::ReadError;

const HEADER: usize = 3468;
const OFFSET_Z: usize = 16;
const OFFSET_POINTS: usize = 1368;
const OFFSET_SPACING: usize = 1376;
/// The measurement-type tag the sample files carry at byte 32 (`OM_MS_2.0`).
const TAG: &[u8] = b"OM_MS_";

/// Content check: the `OM_MS_` tag at byte 32 of a header at least 3468 bytes long.
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if b.len() >= HEADER.min(64) && b.get(32..32 + TAG.len()) == Some(TAG) {
        Sniff::Likely
    } else {
        Sniff::No
    }
}

/// Read an NMS file (the height channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if bytes.len() < HEADER {
        return Err(ctx.truncated(
            "header",
            "the 3468-byte header",
            (0, HEADER as u64),
            bytes.len() as u64,
        ));
    }
    let f64_at = |off: usize| binary::le_f64(bytes, off).unwrap_or(f64::NAN);
    let u32_at = |off: usize| {
        u32::from_le_bytes([bytes[off], bytes[off + 1], bytes[off + 2], bytes[off + 3]])
    };
    let (zmin, zmax) = (f64_at(OFFSET_Z), f64_at(OFFSET_Z + 8));
    if !(zmin.is_finite() && zmax.is_finite() && zmax >= zmin) {
        return Err(ctx.err(
            "zmin, zmax (byte 16)",
            format!("height range {zmin} … {zmax} µm is not a finite interval"),
            "the header is corrupt; re-export the measurement",
        ));
    }
    let (nx, ny) = (u32_at(OFFSET_POINTS), u32_at(OFFSET_POINTS + 4));
    let dx = check_spacing(ctx, "dx (byte 1376)", f64_at(OFFSET_SPACING))?;
    let dy = check_spacing(ctx, "dy (byte 1384)", f64_at(OFFSET_SPACING + 8))?;
    let raw = decode_grid(
        ctx,
        "nx × ny (byte 1368)",
        (u64::from(nx), u64::from(ny)),
        ("height data", &bytes[HEADER..]),
        binary::Sample::U16,
        true,
    )?;
    let scale = (zmax - zmin) / 65534.0;
    let heights = raw.into_iter().map(|v| zmin + v * scale).collect();
    Ok(
        Raw::si(nx as usize, ny as usize, dx, dy, heights, "Confocal height")
            .in_units(Unit::Known(1e-6), Unit::Known(1e-9))
            .spacing_from("dx (byte 1376)", "dy (byte 1384)"),
    )
}
