//! Bruker Dektak CSV profiles: a "Scan Parameters" block (`Length,1500.0 um`,
//! `Resolution,0.156 um/sample`, …), the instrument's results, then "Scan Data" with a
//! column header such as `Lateral um,Raw Micrometer`. The x column is rounded in the
//! export, so the spacing is taken as `(x_last − x_first)/(n − 1)`.
//!
//! A profile is accepted only if it is whole: every row is `x,z`, x advances by one
//! sample per row (within the export's rounding), and the profile spans the `Length`
//! the header states. A truncated, cut or garbled file is an error naming the line.

use super::{Ctx, Decoded, Raw, Sniff, Want, check_spacing, text, units};
use crate::ReadError;

/// Content check: the section titles of a Dektak export.
pub(crate) fn sniff(bytes: &[u8]) -> Sniff {
    let t = text::decode(&bytes[..bytes.len().min(8192)]);
    if t.contains("Scan Data") && (t.contains("Scan Parameters") || t.contains("Lateral")) {
        Sniff::Magic
    } else {
        Sniff::No
    }
}

/// The numbered lines of the file.
type Lines<'t> = std::iter::Enumerate<std::str::Lines<'t>>;

/// Read a Dektak CSV profile.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let text = text::decode(bytes);
    text::check_not_cut(ctx, &text)?;
    let mut lines = text.lines().enumerate();
    let Some((length, resolution)) = scan_parameters(&mut lines) else {
        return Err(ctx.err(
            "Scan Data",
            "section not found",
            "export the profile with its data section",
        ));
    };
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
    let (xs, zs, lineno) = rows(ctx, lines, xu, zu)?;
    if xs.len() < 2 {
        return Err(ctx.err(
            "Scan Data",
            "fewer than two points",
            "the profile is empty or truncated",
        ));
    }
    let n = xs.len();
    let span = xs[n - 1] - xs[0];
    let dx = check_spacing(ctx, "lateral column", span / (n - 1) as f64)?;
    check_regular(ctx, &xs, &lineno, dx)?;
    check_header_agrees(ctx, span, dx, length, resolution)?;
    let raw = Raw::si(
        n,
        1,
        dx,
        dx,
        zs,
        cols.get(1).copied().unwrap_or("height").to_string(),
    )
    .spacing_from("lateral column", "lateral column");
    Decoded::single(ctx, want, raw)
}

/// The `Length` and `Resolution` of the "Scan Parameters" block, reading up to the
/// "Scan Data" title; `None` when there is no such title.
fn scan_parameters(lines: &mut Lines<'_>) -> Option<(Option<f64>, Option<f64>)> {
    let mut length = None;
    let mut resolution = None;
    for (_, l) in lines.by_ref() {
        let t = l.trim().trim_end_matches(',');
        if t.eq_ignore_ascii_case("Scan Data") {
            return Some((length, resolution));
        }
        let mut f = t.splitn(2, ',');
        let (k, v) = (f.next().unwrap_or("").trim(), f.next().unwrap_or("").trim());
        match k.to_ascii_lowercase().as_str() {
            "length" => length = units::parse_length(v.split(',').next().unwrap_or("")),
            "resolution" => {
                resolution = units::parse_length(v.split('/').next().unwrap_or(""));
            }
            _ => {}
        }
    }
    None
}

/// x and z in metres, and the 1-based line number of each row.
type Rows = (Vec<f64>, Vec<f64>, Vec<usize>);

/// The `x,z` rows in metres (x scaled by `xu`, z by `zu`) and their 1-based line numbers.
fn rows(ctx: Ctx<'_>, lines: Lines<'_>, xu: f64, zu: f64) -> Result<Rows, ReadError> {
    let mut xs = Vec::new();
    let mut zs = Vec::new();
    let mut lineno = Vec::new();
    for (i, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let mut f = line.split(',');
        let x = f.next().and_then(|v| v.trim().parse::<f64>().ok());
        let z = f.next().and_then(|v| v.trim().parse::<f64>().ok());
        let rest_ok = f.all(|v| v.trim().is_empty() || v.trim().parse::<f64>().is_ok());
        match (x, z) {
            (Some(x), Some(z)) if x.is_finite() && rest_ok => {
                xs.push(x * xu);
                zs.push(if z.is_finite() { z * zu } else { f64::NAN });
                lineno.push(i + 1);
            }
            _ => {
                return Err(ctx.err(
                    &format!("line {}", i + 1),
                    format!("`{line}` is not `x,z`: the profile is garbled"),
                    "re-export the profile; the data section must hold two numeric columns",
                ));
            }
        }
    }
    Ok((xs, zs, lineno))
}

/// Every x within half a sample (plus the export's rounding) of the regular grid from the
/// first x with spacing `dx`.
fn check_regular(ctx: Ctx<'_>, xs: &[f64], lineno: &[usize], dx: f64) -> Result<(), ReadError> {
    // The export rounds x to a few decimals; allow half a sample plus that rounding.
    let rounding = xs
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min)
        .min(dx);
    let tol = 0.5 * dx + 0.5 * rounding;
    for (i, &x) in xs.iter().enumerate() {
        let expect = xs[0] + i as f64 * dx;
        if (x - expect).abs() > tol {
            return Err(ctx.err(
                &format!("line {}", lineno[i]),
                format!(
                    "x = {:.6} µm where the regular spacing puts {:.6} µm: rows are missing, \
                     repeated or out of order",
                    x * 1e6,
                    expect * 1e6
                ),
                "the profile is garbled; re-export it",
            ));
        }
    }
    Ok(())
}

/// The data span the header's `Length` and are spaced by its `Resolution`, where it
/// states them.
fn check_header_agrees(
    ctx: Ctx<'_>,
    span: f64,
    dx: f64,
    length: Option<f64>,
    resolution: Option<f64>,
) -> Result<(), ReadError> {
    if let Some(len) = length.filter(|l| *l > 0.0) {
        let res = resolution.filter(|r| *r > 0.0).unwrap_or(dx);
        let expected_span = len - res;
        if (span - expected_span).abs() > 2.0 * res + 0.002 * len {
            return Err(ctx.err(
                "Length",
                format!(
                    "the data span {:.3} µm but the header states a {:.3} µm scan: the profile \
                     is truncated",
                    span * 1e6,
                    len * 1e6
                ),
                "re-export the whole profile",
            ));
        }
    }
    if let Some(res) = resolution.filter(|r| *r > 0.0)
        && ((dx / res) - 1.0).abs() > 0.05
    {
        return Err(ctx.err(
            "Resolution",
            format!(
                "the data are spaced {:.5} µm but the header states {:.5} µm/sample: rows \
                 are missing or the file is garbled",
                dx * 1e6,
                res * 1e6
            ),
            "re-export the profile",
        ));
    }
    Ok(())
}
