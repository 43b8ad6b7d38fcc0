//! BCR-STM files (`fileformat = bcrstm | bcrf`, with `_unicode` variants): a 2048-character
//! `key = value` header (UTF-16LE for the unicode variants, so 4096 bytes), then int16
//! (`bcrstm`) or float32 (`bcrf`) data, x fastest. Lateral units default to nm; heights are
//! `raw × bit2nm` nm for integers and `raw` in `zunit` (default nm) for floats.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, decode_grid, header_value, units};
use crate::ReadError;
use std::collections::HashMap;

const HEADER_CHARS: usize = 2048;

/// Read the file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// Parse a BCR file.
fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let unicode = bytes.len() >= 2 && bytes[1] == 0 && bytes[0] != 0;
    let char_bytes = if unicode { 2 } else { 1 };
    let head_len = (HEADER_CHARS * char_bytes).min(bytes.len());
    let header: String = if unicode {
        let units16: Vec<u16> = bytes[..head_len]
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        String::from_utf16_lossy(&units16)
    } else {
        String::from_utf8_lossy(&bytes[..head_len]).into_owned()
    };
    let mut kv = HashMap::new();
    for line in header.split(['\n', '\r']) {
        if let Some((k, v)) = line.split_once('=') {
            kv.insert(
                k.trim().to_ascii_lowercase(),
                v.trim().trim_matches('\0').trim().to_string(),
            );
        }
    }
    let get = |k: &str| kv.get(k).map(String::as_str);
    let fileformat = get("fileformat").ok_or_else(|| {
        ctx.err(
            "fileformat",
            "missing",
            "not a BCR file, or the header is corrupt",
        )
    })?;
    let kind = match fileformat.to_ascii_lowercase().as_str() {
        "bcrstm" | "bcrstm_unicode" => binary::Sample::I16,
        "bcrf" | "bcrf_unicode" => binary::Sample::F32,
        f => {
            return Err(ctx.err(
                "fileformat",
                format!("`{f}` is not supported"),
                "expected bcrstm, bcrf or their _unicode variants",
            ));
        }
    };
    let int = |k: &str| {
        let problem = "missing or not a non-negative integer";
        header_value::<u64>(ctx, &kv, k, problem, "the BCR header is incomplete")
    };
    let float = |k: &str, default: Option<f64>| -> Result<f64, ReadError> {
        match get(k) {
            Some(v) => v.parse::<f64>().map_err(|_| {
                ctx.err(
                    k,
                    format!("`{v}` is not a number"),
                    "the BCR header is corrupt",
                )
            }),
            None => default.ok_or_else(|| ctx.err(k, "missing", "the BCR header is incomplete")),
        }
    };
    let nx = int("xpixels")?;
    let ny = int("ypixels")?;
    let header_chars = get("headersize")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(HEADER_CHARS);
    let data_start = header_chars.saturating_mul(char_bytes);
    if data_start > bytes.len() {
        return Err(ctx.short("headersize", data_start as u64, bytes.len() as u64));
    }
    let little = get("intelmode").map(|v| v != "0").unwrap_or(true);
    let unit = |k: &str| -> Result<f64, ReadError> {
        match get(k) {
            Some(u) => units::length_factor(u).ok_or_else(|| {
                ctx.err(k, format!("`{u}` is not a length unit"), "use nm, um or m")
            }),
            None => Ok(1e-9),
        }
    };
    let (xu, yu, zu) = (unit("xunit")?, unit("yunit")?, unit("zunit")?);
    let xlen = float("xlength", None)? * xu;
    let ylen = float("ylength", Some(f64::NAN))? * yu;
    let data = &bytes[data_start..];
    let raw = decode_grid(
        ctx,
        "xpixels × ypixels",
        (nx, ny),
        ("data", data),
        kind,
        little,
    )?;
    let dx = check_spacing(ctx, "xlength", xlen / nx as f64)?;
    let dy = if ny == 1 || !ylen.is_finite() {
        dx
    } else {
        check_spacing(ctx, "ylength", ylen / ny as f64)?
    };
    let heights = if kind.is_float() {
        // Void pixels are stored as FLT_MAX (the header's `voidpixels` value).
        raw.into_iter()
            .map(|v| {
                if v.is_finite() && v.abs() < 1e38 {
                    v * zu
                } else {
                    f64::NAN
                }
            })
            .collect()
    } else {
        let bit2nm = float("bit2nm", Some(1.0))?;
        let has_void = float("voidpixels", Some(0.0))? > 0.0;
        let q = bit2nm * if get("zunit").is_some() { zu } else { 1e-9 };
        raw.into_iter()
            .map(|v| {
                if has_void && v == i16::MAX as f64 {
                    f64::NAN
                } else {
                    v * q
                }
            })
            .collect()
    };
    // Without a `ylength` the pixels are square: y's spacing is x's.
    let y_field = if ylen.is_finite() {
        "ylength"
    } else {
        "xlength"
    };
    Ok(
        Raw::si(nx as usize, ny as usize, dx, dy, heights, fileformat)
            .spacing_from("xlength", y_field),
    )
}
