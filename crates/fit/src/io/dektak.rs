//! Bruker Dektak CSV profiles: a "Scan Parameters" block, the instrument's results, then
//! "Scan Data" with a column header such as `Lateral um,Raw Micrometer`. The x column is
//! rounded in the export, so the spacing is taken as `(x_last − x_first)/(n − 1)`.

use super::{Ctx, check_spacing, units};
use crate::{ReadError, Topography};

/// Parse a Dektak CSV profile.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Topography, ReadError> {
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines().enumerate();
    lines
        .by_ref()
        .find(|(_, l)| {
            l.trim()
                .trim_end_matches(',')
                .eq_ignore_ascii_case("Scan Data")
        })
        .ok_or_else(|| {
            ctx.err(
                "Scan Data",
                "section not found",
                "export the profile with its data section",
            )
        })?;
    let (_, head) = lines.next().ok_or_else(|| {
        ctx.err(
            "Scan Data",
            "column header missing",
            "the file is truncated",
        )
    })?;
    let cols: Vec<&str> = head.split(',').map(str::trim).collect();
    let unit_of = |col: Option<&&str>, name: &str| -> Result<f64, ReadError> {
        let col = col.copied().unwrap_or("");
        col.split_whitespace()
            .rev()
            .find_map(units::length_factor)
            .ok_or_else(|| {
                ctx.err(
                    name,
                    format!("cannot find a length unit in column `{col}`"),
                    "expected e.g. `Lateral um,Raw Micrometer`",
                )
            })
    };
    let xu = unit_of(cols.first(), "lateral column")?;
    let zu = unit_of(cols.get(1), "height column")?;
    let mut xs = Vec::new();
    let mut zs = Vec::new();
    for (i, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let mut f = line.split(',');
        let x = f.next().and_then(|v| v.trim().parse::<f64>().ok());
        let z = f.next().and_then(|v| v.trim().parse::<f64>().ok());
        match (x, z) {
            (Some(x), Some(z)) => {
                xs.push(x * xu);
                zs.push(if z.is_finite() { z * zu } else { f64::NAN });
            }
            _ => {
                return Err(ctx.err(
                    &format!("line {}", i + 1),
                    format!("`{line}` is not `x,z`"),
                    "the data section must contain two numeric columns",
                ));
            }
        }
    }
    if xs.len() < 2 {
        return Err(ctx.err("Scan Data", "fewer than two points", "the profile is empty"));
    }
    let n = xs.len();
    let dx = check_spacing(ctx, "lateral column", (xs[n - 1] - xs[0]) / (n - 1) as f64)?;
    Ok(Topography {
        nx: n,
        ny: 1,
        dx,
        dy: dx,
        heights: zs,
        channel: cols.get(1).unwrap_or(&"height").to_string(),
        format: "dektak",
    })
}
