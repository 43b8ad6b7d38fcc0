//! Sensofar `.plu`/`.apx` (confocal and interferometric profilers). A 500-byte
//! little-endian header: a 128-byte date string, time, a 256-byte comment, the axes
//! calibration (`yres`, `xres`, …, µm per pixel in x and y), the measurement type
//! (3 = topography), the scan settings and `num_layers`; then per layer `yres`, `xres`
//! and `yres·xres` float32 heights in µm, x fastest. The value 1000001 marks points
//! that were not measured.

use super::binary::{Cursor, Sample, decode};
use super::{Ctx, Decoded, Raw, Sniff, Unit, Want, check_spacing, checked_grid};
use crate::ReadError;

const HEADER: usize = 500;
const UNDEFINED: f64 = 1_000_001.0;
const TOPOGRAPHY: u32 = 3;
const PROFILE: u32 = 1;

/// Content check: a printable date string, a plausible grid and a matching file size.
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if b.len() < HEADER + 8 {
        return Sniff::No;
    }
    let date = &b[..128];
    let text_end = date.iter().position(|&c| c == 0).unwrap_or(128);
    if text_end < 6 || !date[..text_end].iter().all(|c| (32..127).contains(c)) {
        return Sniff::No;
    }
    let mut c = Cursor::le(b, HEADER);
    match (c.u32(), c.u32()) {
        (Some(y), Some(x)) if (1..=100_000).contains(&x) && (1..=100_000).contains(&y) => {
            Sniff::Likely
        }
        _ => Sniff::No,
    }
}

/// Read a Sensofar file (first layer).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if bytes.len() < HEADER + 8 {
        return Err(ctx.short("header", (HEADER + 8) as u64, bytes.len() as u64));
    }
    let short = || ctx.short("header", HEADER as u64, bytes.len() as u64);
    let mut c = Cursor::le(bytes, 128 + 4 + 256);
    let _yres = c.u32().ok_or_else(short)?;
    let _xres = c.u32().ok_or_else(short)?;
    let _n_tall = c.u32().ok_or_else(short)?;
    let _dy_multip = c.f32().ok_or_else(short)?;
    let mppx = c.f32().ok_or_else(short)?;
    let mppy = c.f32().ok_or_else(short)?;
    let kind = {
        let mut m = Cursor::le(bytes, 428);
        m.u32().ok_or_else(short)?
    };
    if kind != TOPOGRAPHY && kind != PROFILE {
        return Err(ctx.err(
            "measurement type",
            format!("type {kind} is not a topography (3) or profile (1)"),
            "export the topography layer from SensoSCAN",
        ));
    }
    let num_layers = bytes[489];
    if num_layers == 0 {
        return Err(ctx.err(
            "num_layers",
            "the file holds no layer",
            "the file is incomplete; re-export it",
        ));
    }
    let mut d = Cursor::le(bytes, HEADER);
    let ny = d.u32().ok_or_else(short)? as u64;
    let nx = d.u32().ok_or_else(short)? as u64;
    let data = &bytes[HEADER + 8..];
    let n = checked_grid(ctx, "layer xres × yres", nx, ny, 4, data.len() as u64)?;
    let dx = check_spacing(ctx, "micrometers_per_pixel_x", mppx.abs())?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "micrometers_per_pixel_y", mppy.abs())?
    };
    let mut heights = decode(data, Sample::F32, true, n)
        .ok_or_else(|| ctx.short("layer data", n as u64 * 4, data.len() as u64))?;
    for h in &mut heights {
        if *h == UNDEFINED || !h.is_finite() {
            *h = f64::NAN;
        }
    }
    let mut raw = Raw::si(nx as usize, ny as usize, dx, dy, heights, "layer0")
        .spacing_from("micrometers_per_pixel_x", "micrometers_per_pixel_y")
        .in_units(Unit::Known(1e-6), Unit::Known(1e-6));
    if num_layers > 1 {
        raw.notes.push(format!(
            "the file has {num_layers} layers; the first was read"
        ));
    }
    Decoded::single(ctx, want, raw)
}
