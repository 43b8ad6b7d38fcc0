//! Plain column files: `x z` (a profile) or `x y z` (a map on a regular grid, any order,
//! missing points become NaN). Separators: whitespace, comma or semicolon; lines starting
//! with `#`, `%` or `//` and leading non-numeric header lines are skipped. All columns are
//! in the unit given by the caller (metres per unit).

use super::{Ctx, check_spacing, checked_grid, text::parse_row};
use crate::{ReadError, Topography};

/// Parse a column file; `unit` converts every column to metres.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], unit: f64) -> Result<Topography, ReadError> {
    if !(unit.is_finite() && unit > 0.0) {
        return Err(ctx.err(
            "units",
            format!("{unit} is not a valid unit factor"),
            "pass --units m|mm|um|nm",
        ));
    }
    let text = String::from_utf8_lossy(bytes);
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut ncol = 0;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty()
            || line.starts_with('#')
            || line.starts_with('%')
            || line.starts_with("//")
        {
            continue;
        }
        match parse_row(line) {
            Some(r) => {
                if ncol == 0 {
                    ncol = r.len();
                    if !(2..=3).contains(&ncol) {
                        return Err(ctx.err(
                            &format!("line {}", i + 1),
                            format!("{ncol} columns"),
                            "expected `x z` or `x y z`",
                        ));
                    }
                } else if r.len() != ncol {
                    return Err(ctx.err(
                        &format!("line {}", i + 1),
                        format!("{} columns, earlier lines have {ncol}", r.len()),
                        "every line needs the same number of columns",
                    ));
                }
                rows.push(r.into_iter().map(|v| v * unit).collect());
            }
            None if rows.is_empty() => continue, // column titles
            None => {
                return Err(ctx.err(
                    &format!("line {}", i + 1),
                    format!("`{line}` is not numeric"),
                    "remove stray text",
                ));
            }
        }
    }
    if rows.len() < 2 {
        return Err(ctx.err(
            "data",
            "fewer than two data lines",
            "the file holds no surface",
        ));
    }
    if ncol == 2 {
        return profile(ctx, rows);
    }
    grid(ctx, rows)
}

fn profile(ctx: Ctx<'_>, mut rows: Vec<Vec<f64>>) -> Result<Topography, ReadError> {
    rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let n = rows.len();
    let dx = check_spacing(
        ctx,
        "x column",
        (rows[n - 1][0] - rows[0][0]) / (n - 1) as f64,
    )?;
    for (i, r) in rows.iter().enumerate() {
        let expect = rows[0][0] + i as f64 * dx;
        if (r[0] - expect).abs() > 0.25 * dx {
            return Err(ctx.err(
                "x column",
                format!("x = {} is off the regular spacing {dx} m", r[0]),
                "resample the profile onto a regular grid",
            ));
        }
    }
    Ok(Topography {
        nx: n,
        ny: 1,
        dx,
        dy: dx,
        heights: rows.into_iter().map(|r| r[1]).collect(),
        channel: "z".into(),
        format: "xyz",
    })
}

/// Distinct values of a coordinate on a regular lattice: (origin, spacing, count).
fn axis(ctx: Ctx<'_>, field: &str, mut v: Vec<f64>) -> Result<(f64, f64, usize), ReadError> {
    v.sort_by(f64::total_cmp);
    let span = v[v.len() - 1] - v[0];
    let scale = v[0].abs().max(v[v.len() - 1].abs());
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    v.dedup_by(|a, b| (*a - *b).abs() <= tol);
    if v.len() == 1 {
        return Ok((v[0], f64::NAN, 1));
    }
    let d = span / (v.len() - 1) as f64;
    let d = check_spacing(ctx, field, d)?;
    // Every step between distinct values must be one lattice spacing.
    if let Some(w) = v.windows(2).find(|w| ((w[1] - w[0]) - d).abs() > 0.25 * d) {
        return Err(ctx.err(
            field,
            format!(
                "values {} and {} are not one grid step ({d} m) apart",
                w[0], w[1]
            ),
            "the points must lie on a regular grid; resample the data",
        ));
    }
    Ok((v[0], d, v.len()))
}

fn grid(ctx: Ctx<'_>, rows: Vec<Vec<f64>>) -> Result<Topography, ReadError> {
    let (x0, dx, nx) = axis(ctx, "x column", rows.iter().map(|r| r[0]).collect())?;
    let (y0, dy, ny) = axis(ctx, "y column", rows.iter().map(|r| r[1]).collect())?;
    if nx < 2 {
        return Err(ctx.err(
            "x column",
            "a single x value",
            "the x column must vary along the fast axis",
        ));
    }
    let dy = if ny == 1 { dx } else { dy };
    let n = checked_grid(
        ctx,
        "grid",
        nx as u64,
        ny as u64,
        1,
        (rows.len() as u64).saturating_mul(16),
    )?;
    let mut heights = vec![f64::NAN; n];
    for r in &rows {
        let ix = ((r[0] - x0) / dx).round();
        let iy = if ny == 1 {
            0.0
        } else {
            ((r[1] - y0) / dy).round()
        };
        let off_x = (r[0] - x0 - ix * dx).abs() > 0.25 * dx;
        let off_y = ny > 1 && (r[1] - y0 - iy * dy).abs() > 0.25 * dy;
        if off_x || off_y || ix < 0.0 || iy < 0.0 || ix >= nx as f64 || iy >= ny as f64 {
            return Err(ctx.err(
                "x/y columns",
                format!("point ({}, {}) is off the regular grid", r[0], r[1]),
                "resample onto a regular grid",
            ));
        }
        heights[iy as usize * nx + ix as usize] = r[2];
    }
    Ok(Topography {
        nx,
        ny,
        dx,
        dy,
        heights,
        channel: "z".into(),
        format: "xyz",
    })
}
