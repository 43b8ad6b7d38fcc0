//! Keyence VK-X laser confocal `.vk4` (and `.vk3`), and `.vk6`/`.vk7`, which wrap a VK4
//! file as the zip entry `Vk4File` after their own magic. A VK4 file is the magic `VK4_`,
//! a 4-byte DLL version and 4 zero bytes, then a table of 17 little-endian `u32` offsets
//! (the measurement conditions first, the first height layer seventh). The measurement
//! conditions hold, as `u32` words from their start, `x_length_per_pixel` (word 42),
//! `y_length_per_pixel` (43) and `z_length_per_digit` (44), all in picometres. A layer is
//! `width, height, bit depth (8, 16 or 32), compression, byte size, palette min, max`, a
//! 768-byte palette, then `width·height` unsigned integers, x fastest. Heights are
//! `raw · z_length_per_digit`.
//!
//! The pixel spacing is `x_length_per_pixel`, as Gwyddion (`modules/file/keyence.c`) and
//! surfalize (`file/vk.py`) read it; SurfaceTopography 1.27 (`IO/VK.py`) takes the scan
//! size as `(width − 1)` pixels, so its spacing is `(width − 1)/width` of this one.
//!
//! No sample file could be obtained (the stored snapshots of SurfaceTopography and
//! surfalize lack their VK examples), so the reader is tested on files written from this
//! description in `crates/fit/tests/formats.rs`.

use super::{Ctx, Decoded, Raw, Unit, Want, binary, check_spacing, decode_grid};
use crate::ReadError;
use std::io::Read;

/// The magic of the formats read here.
pub(crate) const MAGICS: &[&[u8]] = &[b"VK4_", b"VK3_", b"VK6", b"VK7"];
const CORRUPT: &str = "the VK file is corrupt or truncated; save it again from the VK software";
/// Largest `Vk4File` entry read from a VK6/VK7 archive.
const MAX_ENTRY: u64 = 4 << 30;

/// Read a VK3/VK4/VK6/VK7 file (its first height layer).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if bytes.starts_with(b"VK6") || bytes.starts_with(b"VK7") {
        let inner = vk4_entry(ctx, bytes)?;
        return Decoded::single(ctx, want, parse(ctx, &inner)?);
    }
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// The `Vk4File` entry of a VK6/VK7 archive.
fn vk4_entry(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Vec<u8>, ReadError> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| {
        ctx.err(
            "zip container",
            format!("the archive after the VK6/VK7 magic is not readable ({e})"),
            CORRUPT,
        )
    })?;
    let f = zip.by_name("Vk4File").map_err(|_| {
        ctx.err(
            "Vk4File",
            "the archive holds no Vk4File entry",
            "export the measurement again as .vk4",
        )
    })?;
    let declared = f.size();
    if declared > MAX_ENTRY {
        return Err(ctx.err(
            "Vk4File",
            format!("the entry claims {declared} bytes"),
            CORRUPT,
        ));
    }
    let mut out = Vec::with_capacity(declared.min(64 << 20) as usize);
    f.take(MAX_ENTRY)
        .read_to_end(&mut out)
        .map_err(|e| ctx.err("Vk4File", format!("cannot decompress ({e})"), CORRUPT))?;
    Ok(out)
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if !(bytes.starts_with(b"VK4_") || bytes.starts_with(b"VK3_")) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `VK4_`",
            "not a VK4 file",
        ));
    }
    let word = |off: usize, what: &str| -> Result<u32, ReadError> {
        bytes
            .get(off..off + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| {
                ctx.truncated(what, what, (off as u64, off as u64 + 4), bytes.len() as u64)
            })
    };
    if word(8, "magic")? != 0 {
        return Err(ctx.err(
            "magic",
            "the 4 bytes after the version are not zero",
            CORRUPT,
        ));
    }
    let conditions = word(12, "offset table (measurement conditions)")? as usize;
    let height = word(12 + 6 * 4, "offset table (height layer)")? as usize;
    let cond = |i: usize, what: &str| word(conditions.saturating_add(4 * i), what);
    let px = f64::from(cond(42, "x_length_per_pixel")?);
    let py = f64::from(cond(43, "y_length_per_pixel")?);
    let pz = f64::from(cond(44, "z_length_per_digit")?);
    let dx = check_spacing(ctx, "x_length_per_pixel", px)?;
    let dy = check_spacing(ctx, "y_length_per_pixel", py)?;
    if pz == 0.0 {
        return Err(ctx.err("z_length_per_digit", "the height scale is 0", CORRUPT));
    }
    let layer = |i: usize, what: &str| word(height.saturating_add(4 * i), what);
    let (w, h) = (layer(0, "layer width")?, layer(1, "layer height")?);
    let bits = layer(2, "layer bit depth")?;
    let kind = match bits {
        8 => binary::Sample::U8,
        16 => binary::Sample::U16,
        32 => binary::Sample::U32,
        b => {
            return Err(ctx.err(
                "layer bit depth",
                format!("{b} bits per point, not 8, 16 or 32"),
                CORRUPT,
            ));
        }
    };
    if layer(3, "layer compression")? != 0 {
        return Err(ctx.err(
            "layer compression",
            "the height layer is compressed, which is not read",
            "export the measurement uncompressed",
        ));
    }
    let start = height.saturating_add(28 + 768);
    let data = bytes.get(start..).unwrap_or(&[]);
    let raw = decode_grid(
        ctx,
        "layer width × height",
        (u64::from(w), u64::from(h)),
        ("height layer", data),
        kind,
        true,
    )?;
    let heights = raw.into_iter().map(|v| v * pz).collect();
    Ok(Raw::si(w as usize, h as usize, dx, dy, heights, "height")
        .in_units(Unit::Known(1e-12), Unit::Known(1e-12))
        .spacing_from("x_length_per_pixel", "y_length_per_pixel"))
}
