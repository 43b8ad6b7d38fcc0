//! Gwyddion "Export Text" ASCII matrix: `# Key: value` header lines (Channel, Width,
//! Height, Value units), then one row of values per scan line.

use super::{Ctx, check_spacing, text::parse_row, units};
use crate::{ReadError, Topography};

/// Parse a text matrix. `units` (m per unit) applies to values when the header gives none.
pub(crate) fn read(
    ctx: Ctx<'_>,
    bytes: &[u8],
    units: Option<f64>,
) -> Result<Topography, ReadError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        ctx.err(
            "text",
            format!("not UTF-8 text ({e})"),
            "save the matrix as UTF-8",
        )
    })?;
    let mut width = None;
    let mut height = None;
    let mut zunit = None;
    let mut channel = String::from("matrix");
    let mut rows: Vec<f64> = Vec::new();
    let mut nx = 0usize;
    let mut ny = 0usize;
    for (lineno, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(h) = line.strip_prefix('#') {
            if let Some((k, v)) = h.split_once(':') {
                let v = v.trim();
                match k.trim().to_ascii_lowercase().as_str() {
                    "width" => width = Some(parse_len(ctx, "Width", v)?),
                    "height" => height = Some(parse_len(ctx, "Height", v)?),
                    "value units" => {
                        zunit = Some(units::length_factor(v).ok_or_else(|| {
                            ctx.err(
                                "Value units",
                                format!("`{v}` is not a length unit"),
                                "export a height channel (units m, µm or nm)",
                            )
                        })?)
                    }
                    "channel" => channel = v.to_string(),
                    _ => {}
                }
            }
            continue;
        }
        let row = parse_row(line).ok_or_else(|| {
            ctx.err(
                &format!("line {}", lineno + 1),
                "contains a field that is not a number",
                "remove stray text; header lines must start with '#'",
            )
        })?;
        if nx == 0 {
            nx = row.len();
        } else if row.len() != nx {
            return Err(ctx.err(
                &format!("line {}", lineno + 1),
                format!("has {} values but the first row has {nx}", row.len()),
                "every row of the matrix must have the same length",
            ));
        }
        rows.extend_from_slice(&row);
        ny += 1;
    }
    if nx == 0 || ny == 0 {
        return Err(ctx.err("data", "no numeric rows", "the file holds no matrix"));
    }
    let width = width.ok_or_else(|| {
        ctx.err(
            "Width",
            "missing, so the pixel size is unknown",
            "add a header line `# Width: 10 µm`",
        )
    })?;
    let height = height.unwrap_or(width * ny as f64 / nx as f64);
    let dx = check_spacing(ctx, "Width", width / nx as f64)?;
    let dy = check_spacing(ctx, "Height", height / ny as f64)?;
    let z = zunit.or(units).unwrap_or(1.0);
    for v in &mut rows {
        *v *= z;
    }
    Ok(Topography {
        nx,
        ny,
        dx,
        dy: if ny == 1 { dx } else { dy },
        heights: rows,
        channel,
        format: "gwyddion-matrix",
    })
}

fn parse_len(ctx: Ctx<'_>, field: &str, v: &str) -> Result<f64, ReadError> {
    units::parse_length(v).ok_or_else(|| {
        ctx.err(
            field,
            format!("`{v}` is not a length"),
            "write it as `<number> <unit>`, e.g. `10.00 µm`",
        )
    })
}
