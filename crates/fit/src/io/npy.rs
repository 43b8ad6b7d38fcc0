//! NumPy `.npy` arrays, as SurfaceTopography and scripts save height maps: the magic
//! `\x93NUMPY`, a version (1.0: a 2-byte header length; 2.0 and 3.0: 4 bytes), a Python
//! dict literal (`descr`, `fortran_order`, `shape`) padded with spaces, then the array.
//!
//! Axes follow SurfaceTopography: the first index is x, so `shape = (nx, ny)`; in C order
//! y runs fastest in the file and the map is transposed to this crate's x-fastest layout.
//! A 1-D array is a profile. An array carries no unit and no pixel size: `--units` and
//! `--pixel-size` (or `--size`) supply them. Non-finite values are invalid points.
//!
//! Source: the NumPy format description (`numpy.lib.format`, NEP 1) and SurfaceTopography's
//! `IO/NPY.py` for the axis convention.

use super::{Ctx, Decoded, Raw, Unit, Want, binary, checked_grid};
use crate::ReadError;

/// The first bytes of every `.npy` file.
pub(crate) const MAGIC: &[u8] = b"\x93NUMPY";

/// Read an `.npy` file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

const CORRUPT: &str = "the .npy header is corrupt; save the array again with numpy.save";

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `\\x93NUMPY`",
            "not a NumPy .npy file (or its first bytes are damaged)",
        ));
    }
    let major = *bytes.get(6).ok_or_else(|| ctx.short("version", 8, 6))?;
    let (len, start) = match major {
        1 => (binary::le_u16(bytes, 8).map(u64::from), 10),
        2 | 3 => (
            bytes
                .get(8..12)
                .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))),
            12,
        ),
        v => {
            return Err(ctx.err(
                "version",
                format!("format version {v} is not 1, 2 or 3"),
                CORRUPT,
            ));
        }
    };
    let len = len.ok_or_else(|| ctx.short("header length", start as u64, bytes.len() as u64))?;
    let end = start as u64 + len;
    if end > bytes.len() as u64 {
        return Err(ctx.truncated(
            "header",
            "the header",
            (start as u64, end),
            bytes.len() as u64,
        ));
    }
    let header = String::from_utf8_lossy(&bytes[start..end as usize]).into_owned();
    let descr = dict_value(&header, "descr")
        .ok_or_else(|| ctx.err("descr", "missing from the header", CORRUPT))?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let (kind, little) = dtype(descr).ok_or_else(|| {
        ctx.err(
            "descr",
            format!("data type `{descr}` is not a real number type"),
            "save the heights as float64, float32 or an integer type",
        )
    })?;
    let fortran = match dict_value(&header, "fortran_order").as_deref() {
        Some("True") => true,
        Some("False") | None => false,
        Some(v) => {
            return Err(ctx.err(
                "fortran_order",
                format!("`{v}` is not True or False"),
                CORRUPT,
            ));
        }
    };
    let shape = dict_value(&header, "shape")
        .ok_or_else(|| ctx.err("shape", "missing from the header", CORRUPT))?;
    let dims: Vec<u64> = shape
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            ctx.err(
                "shape",
                format!("`{shape}` is not a tuple of sizes"),
                CORRUPT,
            )
        })?;
    let (nx, ny) = match dims[..] {
        [n] => (n, 1),
        [a, b] => (a, b),
        _ => {
            return Err(ctx.err(
                "shape",
                format!("an array of {} dimensions", dims.len()),
                "save a 2-D height map (nx, ny) or a 1-D profile",
            ));
        }
    };
    let data = &bytes[end as usize..];
    let n = checked_grid(ctx, "shape", nx, ny, kind.size() as u64, data.len() as u64)?;
    let values = binary::decode(data, kind, little, n)
        .ok_or_else(|| ctx.short("data", (n * kind.size()) as u64, data.len() as u64))?;
    let (nx, ny) = (nx as usize, ny as usize);
    // x is the first index: contiguous in Fortran order, strided by ny in C order.
    let heights: Vec<f64> = if fortran || ny == 1 {
        values
    } else {
        (0..n).map(|k| values[(k % nx) * ny + k / nx]).collect()
    };
    let heights = heights
        .into_iter()
        .map(|v| if v.is_finite() { v } else { f64::NAN })
        .collect();
    let mut raw = Raw::si(nx, ny, 1.0, 1.0, heights, "npy").in_units(Unit::Unknown, Unit::Unknown);
    raw.spacing = None;
    Ok(raw)
}

/// The value of `key` in a Python dict literal: a quoted string, a tuple or a word.
fn dict_value(header: &str, key: &str) -> Option<String> {
    let at = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = header[at + key.len() + 2..].trim_start();
    let rest = rest.strip_prefix(':')?.trim_start();
    let end = match rest.chars().next()? {
        '(' => rest.find(')')? + 1,
        q @ ('\'' | '"') => rest[1..].find(q)? + 2,
        _ => rest.find([',', '}']).unwrap_or(rest.len()),
    };
    Some(rest[..end].trim().to_string())
}

/// A NumPy type string (`<f8`, `>i2`, `|u1`) as a sample type and byte order.
fn dtype(descr: &str) -> Option<(binary::Sample, bool)> {
    use binary::Sample::*;
    let cut = descr.len().checked_sub(2)?;
    let (order, code) = (descr.get(..cut)?, descr.get(cut..)?);
    let little = match order {
        "<" | "|" | "=" | "" => true,
        ">" => false,
        _ => return None,
    };
    let kind = match code {
        "f8" => F64,
        "f4" => F32,
        "i4" => I32,
        "u4" => U32,
        "i2" => I16,
        "u2" => U16,
        "i1" => I8,
        "u1" => U8,
        _ => return None,
    };
    Some((kind, little))
}
