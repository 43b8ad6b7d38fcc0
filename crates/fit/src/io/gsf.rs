//! Gwyddion Simple Field (`.gsf`): the line `Gwyddion Simple Field 1.0`, `Key = Value`
//! lines (XRes, YRes, XReal, YReal, XYUnits, ZUnits), NUL padding to a multiple of 4 bytes,
//! then XRes·YRes little-endian float32 values. NaN marks invalid points.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, header_value, units};
use crate::ReadError;
use std::collections::HashMap;

const MAGIC: &[u8] = b"Gwyddion Simple Field 1.0";

/// Read the file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// Parse a GSF file.
fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "missing `Gwyddion Simple Field 1.0`",
            "not a GSF file",
        ));
    }
    let nul = bytes.iter().position(|&b| b == 0).ok_or_else(|| {
        ctx.err(
            "header",
            "no NUL padding ends the header",
            "the file is truncated",
        )
    })?;
    let header = String::from_utf8_lossy(&bytes[..nul]);
    let data_start = (nul / 4 + 1) * 4;
    if data_start > bytes.len() {
        return Err(ctx.short("header padding", data_start as u64, bytes.len() as u64));
    }
    let mut kv = HashMap::new();
    for line in header.lines().skip(1) {
        if let Some((k, v)) = line.split_once('=') {
            kv.insert(k.trim().to_string(), v.trim().to_string());
        }
    }
    const INCOMPLETE: &str = "the GSF header is incomplete";
    let int = |k: &str| header_value::<u64>(ctx, &kv, k, "missing or not an integer", INCOMPLETE);
    let nx = int("XRes")?;
    let ny = int("YRes")?;
    let unit = |k: &str| -> Result<f64, ReadError> {
        match kv.get(k) {
            Some(u) if !u.is_empty() => units::length_factor(u).ok_or_else(|| {
                ctx.err(
                    k,
                    format!("`{u}` is not a length unit"),
                    "heights and lengths must be lengths (m, µm, nm)",
                )
            }),
            _ => Ok(1.0),
        }
    };
    let (xyu, zu) = (unit("XYUnits")?, unit("ZUnits")?);
    let real = |k: &str| {
        let fix = format!("add `{k} = <size in XYUnits>` to the header");
        header_value::<f64>(ctx, &kv, k, "missing, so the pixel size is unknown", &fix)
    };
    let data = &bytes[data_start..];
    let n = checked_grid(ctx, "XRes × YRes", nx, ny, 4, data.len() as u64)?;
    let dx = check_spacing(ctx, "XReal", real("XReal")? * xyu / nx as f64)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "YReal", real("YReal")? * xyu / ny as f64)?
    };
    let raw = binary::decode(data, binary::Sample::F32, true, n)
        .ok_or_else(|| ctx.short("data", n as u64 * 4, data.len() as u64))?;
    let heights = raw
        .into_iter()
        .map(|v| if v.is_finite() { v * zu } else { f64::NAN })
        .collect();
    let channel = kv.get("Title").map_or("gsf", String::as_str);
    Ok(Raw::si(nx as usize, ny as usize, dx, dy, heights, channel).spacing_from("XReal", "YReal"))
}
