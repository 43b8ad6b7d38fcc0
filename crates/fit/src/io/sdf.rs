//! Surface Data File (BCR SDF / ISO 25178-71). Binary (`bBCR-1.0`, `bISO-1.0`): an 81-byte
//! little-endian header (version, manufacturer, dates, NumPoints u16, NumProfiles u16,
//! Xscale/Yscale/Zscale/Zresolution f64 in metres, compression, data type, check type)
//! followed by the data. ASCII (`aBCR-1.0`, `aISO-1.0`): `Key = value` lines, a `*` line,
//! the values, then `*`. Heights are `raw × Zscale`.

use super::{
    Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, decode_grid, header_value,
    text::parse_row,
};
use crate::ReadError;
use std::collections::HashMap;

const BINARY_HEADER: usize = 81;

/// Read the file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// Parse an SDF file (binary or ASCII).
fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    match bytes.first() {
        Some(b'b') => read_binary(ctx, bytes),
        Some(b'a') => read_ascii(ctx, bytes),
        _ => Err(ctx.err(
            "version",
            "does not start with aBCR/bBCR/aISO/bISO",
            "not an SDF file",
        )),
    }
}

fn data_kind(ctx: Ctx<'_>, code: u64) -> Result<binary::Sample, ReadError> {
    use binary::Sample::*;
    Ok(match code {
        0 => U8,
        1 => U16,
        2 => U32,
        3 => F32,
        4 => I8,
        5 => I16,
        6 => I32,
        7 => F64,
        c => {
            return Err(ctx.err(
                "DataType",
                format!("unknown data type {c}"),
                "expected 0..7",
            ));
        }
    })
}

fn read_binary(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let short = || ctx.short("header", BINARY_HEADER as u64, bytes.len() as u64);
    if bytes.len() < BINARY_HEADER {
        return Err(short());
    }
    let nx = binary::le_u16(bytes, 42).ok_or_else(short)? as u64;
    let ny = binary::le_u16(bytes, 44).ok_or_else(short)? as u64;
    let xs = binary::le_f64(bytes, 46).ok_or_else(short)?;
    let ys = binary::le_f64(bytes, 54).ok_or_else(short)?;
    let zs = binary::le_f64(bytes, 62).ok_or_else(short)?;
    let compression = bytes[78];
    if compression != 0 {
        return Err(ctx.err(
            "Compression",
            format!("compression {compression} is not supported"),
            "export uncompressed SDF",
        ));
    }
    let kind = data_kind(ctx, bytes[79] as u64)?;
    let data = &bytes[BINARY_HEADER..];
    let raw = decode_grid(
        ctx,
        "NumPoints × NumProfiles",
        (nx, ny),
        ("data", data),
        kind,
        true,
    )?;
    finish(ctx, nx, ny, xs, ys, zs, raw)
}

fn read_ascii(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines();
    lines.next(); // version line
    let mut kv = HashMap::new();
    let mut saw_star = false;
    for line in lines.by_ref() {
        let line = line.trim();
        if line.starts_with('*') {
            saw_star = true;
            break;
        }
        if let Some((k, v)) = line.split_once('=') {
            kv.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
        }
    }
    if !saw_star {
        return Err(ctx.err(
            "header",
            "no `*` line ends the header",
            "the SDF file is truncated",
        ));
    }
    const INCOMPLETE: &str = "the SDF header is incomplete";
    let int = |k: &str| header_value::<u64>(ctx, &kv, k, "missing or not an integer", INCOMPLETE);
    let float = |k: &str| header_value::<f64>(ctx, &kv, k, "missing or not a number", INCOMPLETE);
    let nx = int("numpoints")?;
    let ny = int("numprofiles")?;
    let (xs, ys, zs) = (float("xscale")?, float("yscale")?, float("zscale")?);
    let mut values = Vec::new();
    'outer: for line in lines {
        let line = line.trim();
        if line.starts_with('*') {
            break;
        }
        if line.is_empty() {
            continue;
        }
        let row = parse_row(line).ok_or_else(|| {
            ctx.err(
                "data",
                format!("`{line}` is not numeric"),
                "the SDF data block is corrupt",
            )
        })?;
        for v in row {
            values.push(v);
            if values.len() as u64 > nx.saturating_mul(ny) {
                break 'outer;
            }
        }
    }
    let n = checked_grid(
        ctx,
        "NumPoints × NumProfiles",
        nx,
        ny,
        1,
        values.len() as u64,
    )?;
    values.truncate(n);
    finish(ctx, nx, ny, xs, ys, zs, values)
}

fn finish(
    ctx: Ctx<'_>,
    nx: u64,
    ny: u64,
    xs: f64,
    ys: f64,
    zs: f64,
    raw: Vec<f64>,
) -> Result<Raw, ReadError> {
    let dx = check_spacing(ctx, "Xscale", xs)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "Yscale", ys)?
    };
    if !(zs.is_finite() && zs != 0.0) {
        return Err(ctx.err(
            "Zscale",
            format!("{zs} is not a usable scale"),
            "the SDF header is corrupt",
        ));
    }
    let heights = raw
        .into_iter()
        .map(|v| if v.is_finite() { v * zs } else { f64::NAN })
        .collect();
    Ok(Raw::si(nx as usize, ny as usize, dx, dy, heights, "sdf").spacing_from("Xscale", "Yscale"))
}
