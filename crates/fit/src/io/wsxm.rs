//! WSxM `.stp`/`.top` images: text lines `WSxM file copyright …`, `SxM Image file`,
//! `Image header size: N`, then `[Section]` blocks of `key: value` lines up to
//! `[Header end]`, then the data (little-endian `double`, `float`, or 16-bit `short`/
//! `integer`), x fastest. `Control/X Amplitude` and `Y Amplitude` give the scan size
//! with their unit; heights are scaled so their range equals `General Info/Z Amplitude`
//! (as WSxM and Gwyddion display them).

use super::binary::Sample;
use super::{Ctx, Decoded, Raw, Unit, Want, check_spacing, decode_grid, header_end, units};
use crate::ReadError;
use std::collections::HashMap;

const END: &str = "[Header end]";

/// Read a WSxM image.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let end = header_end(ctx, bytes, END, "the file is truncated or not a WSxM file")?;
    let mut start = end + END.len();
    while start < bytes.len()
        && matches!(bytes[start], b'\r' | b'\n')
        && start < end + END.len() + 2
    {
        start += 1;
    }
    let header: String = bytes[..end].iter().map(|&b| b as char).collect();
    let mut meta: HashMap<String, String> = HashMap::new();
    let mut section = String::new();
    for line in header.lines() {
        let l = line.trim();
        if l.starts_with('[') && l.ends_with(']') {
            section = l[1..l.len() - 1].to_string();
        } else if let Some((k, v)) = l.split_once(':') {
            meta.insert(format!("{section}/{}", k.trim()), v.trim().to_string());
        }
    }
    let get = |k: &str| -> Result<&String, ReadError> {
        meta.get(k)
            .ok_or_else(|| ctx.err(k, "missing", "the WSxM header is incomplete"))
    };
    let count = |k: &str| -> Result<u64, ReadError> {
        get(k)?
            .parse::<u64>()
            .map_err(|_| ctx.err(k, "not a count", "the WSxM header is corrupt"))
    };
    let nx = count("General Info/Number of columns")?;
    let ny = count("General Info/Number of rows")?;
    let kind = match get("General Info/Image Data Type")
        .map(String::as_str)
        .unwrap_or("integer")
    {
        "double" => Sample::F64,
        "float" => Sample::F32,
        "short" | "integer" => Sample::I16,
        t => {
            return Err(ctx.err(
                "General Info/Image Data Type",
                format!("`{t}` is not supported"),
                "expected double, float, short or integer",
            ));
        }
    };
    let data = &bytes[start.min(bytes.len())..];
    let raw = decode_grid(ctx, "columns × rows", (nx, ny), ("data", data), kind, true)?;
    let amplitude = |k: &str| -> Result<(f64, f64), ReadError> {
        let v = get(k)?;
        let (x, u) = units::split_number(v)
            .ok_or_else(|| ctx.err(k, format!("`{v}` is not a length"), "the header is corrupt"))?;
        let f = units::length_factor(u).ok_or_else(|| {
            ctx.err(
                k,
                format!("`{u}` is not a length unit"),
                "the header is corrupt",
            )
        })?;
        Ok((x, f))
    };
    let (sx, fx) = amplitude("Control/X Amplitude")?;
    let (sy, fy) = amplitude("Control/Y Amplitude").unwrap_or((sx, fx));
    let (za, zf) = amplitude("General Info/Z Amplitude")?;
    let (lo, hi) = raw
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let q = if hi > lo { za / (hi - lo) } else { 1.0 };
    let dx = check_spacing(ctx, "X Amplitude", sx * fx / nx as f64)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "Y Amplitude", sy * fy / ny as f64)?
    };
    let heights = raw.into_iter().map(|v| v * q).collect();
    let channel = meta
        .get("General Info/Acquisition channel")
        .map_or("topography", String::as_str);
    let out = Raw::si(nx as usize, ny as usize, dx, dy, heights, channel)
        .spacing_from("X Amplitude", "Y Amplitude")
        .in_units(Unit::Known(zf), Unit::Known(1.0));
    Decoded::single(ctx, want, out)
}
