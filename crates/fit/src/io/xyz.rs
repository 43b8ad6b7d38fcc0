//! Column files: `x z` (a profile) or `x y z` (a map on a regular grid, any order,
//! missing points become NaN), as CSV, TSV, `;`-separated with decimal commas or plain
//! whitespace, UTF-8 or UTF-16 with or without a BOM.
//!
//! Column titles may carry units (`X_(microns)`, `x in µm`, `z [nm]`, `Height (um)`), a
//! row of units may follow the titles (`µm;µm;nm`, or `[mm];[mm];[1/0]` over a validity
//! column as in the `.hfm` profile export `X;Y;valid`, where Y is the height), an `index`
//! column is dropped and a `valid`/`mask` column marks invalid points. A lone integer
//! between a units line and the rows is a point count (a note says when it disagrees
//! with the rows that follow). A profile whose x is not uniformly spaced
//! is resampled by linear interpolation onto the same number of points, and the notes
//! say so. Units the file does not state come from `--units`.

use super::{Ctx, Decoded, Raw, Sniff, Unit, Want, check_spacing, checked_grid, text, units};
use crate::ReadError;

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Role {
    Index,
    Valid,
    Value,
}

#[derive(Debug, Clone)]
struct Column {
    role: Role,
    title: String,
    unit: Option<f64>,
}

/// Find a length unit in a column title: `X_(microns)`, `x in µm`, `z [nm]`, `Lateral um`.
fn unit_in_title(title: &str) -> Option<f64> {
    let t = title.trim();
    for (open, close) in [('(', ')'), ('[', ']'), ('{', '}')] {
        if let (Some(a), Some(b)) = (t.rfind(open), t.rfind(close))
            && a < b
            && let Some(f) = units::length_factor(&t[a + 1..b])
        {
            return Some(f);
        }
    }
    t.split(|c: char| c.is_whitespace() || c == '_' || c == '/')
        .rev()
        .filter(|w| !w.is_empty())
        .find_map(units::length_factor)
        .filter(|_| t.split(|c: char| c.is_whitespace() || c == '_').count() > 1)
}

/// A field of a units row: a length unit, or what exporters write over a validity column
/// (`[1/0]`, `[0/1]`, `[-]`, `[]`).
fn unit_field(f: &str) -> bool {
    let inner = f
        .trim()
        .trim_matches(|c| matches!(c, '[' | ']' | '(' | ')'))
        .trim();
    units::length_factor(f).is_some() || matches!(inner, "" | "1/0" | "0/1" | "-" | "1")
}

fn role_of(title: &str) -> Role {
    let t = title.trim().to_lowercase();
    let word = t
        .split(|c: char| !c.is_alphanumeric())
        .find(|w| !w.is_empty())
        .unwrap_or("");
    match word {
        "index" | "idx" | "no" | "nr" | "n" | "point" | "points" | "sample" | "row" => Role::Index,
        "valid" | "validity" | "mask" | "flag" | "flags" | "quality" | "ok" => Role::Valid,
        _ => Role::Value,
    }
}

/// Content check: rows of 2–5 numbers, optionally after titles.
pub(crate) fn sniff(bytes: &[u8]) -> Sniff {
    let Some(t) = text::sniff_sample(bytes) else {
        return Sniff::No;
    };
    let usable = text::sample_lines(&t);
    let d = text::Dialect::guess(usable.iter().copied().filter(|l| numeric_start(l)));
    let rows: Vec<usize> = usable
        .iter()
        .filter_map(|l| d.row(l))
        .map(|r| r.len())
        .collect();
    let Some(&c) = rows.first() else {
        return Sniff::No;
    };
    if rows.len() < 2 || rows.iter().any(|&r| r != c) || !(2..=5).contains(&c) {
        return Sniff::No;
    }
    let titled = usable
        .iter()
        .take_while(|l| d.row(l).is_none())
        .any(|l| d.fields(l).iter().any(|f| unit_in_title(f).is_some()));
    if titled { Sniff::Likely } else { Sniff::Maybe }
}

/// Whether the sample `lines` look like column data: `Some(true)` when a title before the
/// first numeric row names a length unit, `Some(false)` when the first numeric row has 2–5
/// fields, `None` otherwise.
pub(crate) fn column_layout(lines: &[&str]) -> Option<bool> {
    let d = text::Dialect::guess(lines.iter().copied().filter(|l| numeric_start(l)));
    let titled = lines
        .iter()
        .take_while(|l| d.row(l).is_none())
        .any(|l| d.fields(l).iter().any(|f| unit_in_title(f).is_some()));
    if titled {
        return Some(true);
    }
    let first = lines.iter().find_map(|l| d.row(l))?;
    (2..=5).contains(&first.len()).then_some(false)
}

/// True when some line of `lines` starts like a number.
pub(crate) fn has_numeric_line(lines: &[&str]) -> bool {
    lines.iter().any(|l| numeric_start(l))
}

fn numeric_start(l: &str) -> bool {
    l.trim()
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_digit() || c == '-' || c == '+' || c == '.')
}

/// The lines of a column file: header lines before the data, and the data rows.
struct Lines {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
    /// 1-based line of the first data row.
    first_line: usize,
    ncol: usize,
    /// Lateral and height units from `# x-unit: µm` style comment lines.
    kv_units: (Option<f64>, Option<f64>),
    /// A point count written before the rows: its line and value.
    point_count: Option<(usize, f64)>,
}

/// Read a column file.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let text = text::decode(bytes);
    text::check_not_cut(ctx, &text)?;
    let d = text::Dialect::guess(text.lines().filter(|l| numeric_start(l)));
    let lines = scan(ctx, &text, &d)?;
    if lines.rows.len() < 2 {
        return Err(ctx.err(
            "data",
            "fewer than two data lines",
            "the file holds no profile or surface",
        ));
    }
    let rows = &lines.rows;
    let ncol = lines.ncol;
    let columns = columns(&lines, &d);
    let values: Vec<usize> = (0..ncol)
        .filter(|&c| columns[c].role == Role::Value)
        .collect();
    let valid = (0..ncol).find(|&c| columns[c].role == Role::Valid);
    let mut notes = Vec::new();
    if let Some(v) = valid {
        notes.push(format!(
            "column `{}` marks invalid points",
            columns[v].title
        ));
    }
    if let Some((line, n)) = lines.point_count
        && n != rows.len() as f64
    {
        notes.push(format!(
            "line {line} gives a point count of {n}, but {} data lines follow: all are read",
            rows.len()
        ));
    }
    let is_valid = |r: &[f64]| valid.is_none_or(|v| r[v].is_finite() && r[v] != 0.0);
    let (xc, yc, zc) = match values.as_slice() {
        [x, z] => (*x, None, *z),
        [x, y, z] => (*x, Some(*y), *z),
        _ => {
            return Err(ctx.err(
                &format!("line {}", lines.first_line),
                format!("{} value columns", values.len()),
                "expected `x z` or `x y z` (plus optional index and validity columns)",
            ));
        }
    };
    // Units: per column, then `# x-unit:` style lines, then the other axis.
    let (lateral_unit, height_unit) = units_of(
        columns[xc].unit.or(lines.kv_units.0),
        columns[zc].unit.or(lines.kv_units.1),
        &mut notes,
    );
    let name = if columns[zc].title.is_empty() {
        "z".to_string()
    } else {
        columns[zc].title.clone()
    };
    let mut raw = match yc {
        None => profile(ctx, rows, xc, zc, &is_valid, &mut notes)?,
        Some(yc) => grid(ctx, rows, xc, yc, zc, &is_valid)?,
    };
    raw.height_unit = height_unit;
    raw.lateral_unit = lateral_unit;
    raw.channel = name;
    raw.notes = notes;
    Decoded::single(ctx, want, raw)
}

/// Split the file into header lines and rows of equally many numbers; comment lines only
/// contribute the units they state.
fn scan(ctx: Ctx<'_>, text: &str, d: &text::Dialect) -> Result<Lines, ReadError> {
    let mut lines = Lines {
        header: Vec::new(),
        rows: Vec::new(),
        first_line: 0,
        ncol: 0,
        kv_units: (None, None),
        point_count: None,
    };
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() {
            continue;
        }
        if t.starts_with('#') || t.starts_with('%') || t.starts_with("//") {
            comment_units(t, &mut lines.kv_units);
            continue;
        }
        match d.row(t) {
            Some(r) => {
                let rows = &mut lines.rows;
                // A lone integer before rows of x z: the point count some exporters
                // write after the units line.
                let count_line = lines.ncol == 1
                    && rows.len() == 1
                    && r.len() >= 2
                    && rows[0][0] >= 0.0
                    && rows[0][0].fract() == 0.0;
                if count_line {
                    lines.point_count = Some((lines.first_line, rows[0][0]));
                    rows.clear();
                    lines.ncol = 0;
                }
                if lines.ncol == 0 {
                    lines.ncol = r.len();
                    lines.first_line = i + 1;
                } else if r.len() != lines.ncol {
                    return Err(ctx.err(
                        &format!("line {}", i + 1),
                        format!("{} columns, earlier lines have {}", r.len(), lines.ncol),
                        "every line needs the same number of columns",
                    ));
                }
                rows.push(r);
            }
            None if lines.rows.is_empty() => lines.header.push(t.to_string()),
            None => {
                return Err(ctx.err(
                    &format!("line {}", i + 1),
                    format!(
                        "`{}` is not numeric",
                        t.chars().take(40).collect::<String>()
                    ),
                    "remove stray text; titles and units go before the data",
                ));
            }
        }
    }
    Ok(lines)
}

/// The lateral or height unit a comment line states (`# z-unit: nm`), into `kv_units`.
fn comment_units(t: &str, kv_units: &mut (Option<f64>, Option<f64>)) {
    let Some((k, v)) = text::key_value(t) else {
        return;
    };
    let k = k.to_lowercase();
    if k.contains("unit") {
        let f = units::length_factor(&v);
        if k.starts_with('z') || k.contains("height") || k.contains("value") {
            kv_units.1 = f.or(kv_units.1);
        } else if k.starts_with('x') || k.contains("lateral") || k.contains("length") {
            kv_units.0 = f.or(kv_units.0);
        }
    }
}

/// Title, role and unit of each column. The titles are the last header line with as many
/// fields as there are columns, possibly followed by a row of units.
fn columns(lines: &Lines, d: &text::Dialect) -> Vec<Column> {
    let ncol = lines.ncol;
    let mut columns: Vec<Column> = (0..ncol)
        .map(|_| Column {
            role: Role::Value,
            title: String::new(),
            unit: None,
        })
        .collect();
    let split = |l: &str| -> Vec<String> {
        d.fields(l)
            .into_iter()
            .map(|s| s.trim().trim_matches('"').to_string())
            .collect()
    };
    // A header line may be split by spaces where the rows use commas (`µm µm` over
    // `1.3e+01, 1.7e+01`).
    let fitting: Vec<Vec<String>> = lines
        .header
        .iter()
        .map(|l| {
            let f = split(l);
            if f.len() == ncol {
                f
            } else {
                l.split_whitespace().map(str::to_string).collect()
            }
        })
        .filter(|f| f.len() == ncol)
        .collect();
    if let Some(last) = fitting.last() {
        let unit_row = last.iter().all(|f| f.is_empty() || unit_field(f))
            && last.iter().any(|f| units::length_factor(f).is_some());
        let titles = if unit_row && fitting.len() >= 2 {
            &fitting[fitting.len() - 2]
        } else {
            last
        };
        for (c, t) in columns.iter_mut().zip(titles) {
            c.title = t.clone();
            c.role = role_of(t);
            c.unit = unit_in_title(t);
        }
        if unit_row {
            for (c, u) in columns.iter_mut().zip(last) {
                if let Some(f) = units::length_factor(u) {
                    c.unit = Some(f);
                }
            }
        }
    }
    // Without titles, a first column counting 0, 1, 2, … is an index.
    if columns.iter().all(|c| c.title.is_empty())
        && ncol >= 3
        && lines
            .rows
            .iter()
            .enumerate()
            .all(|(i, r)| r[0] == i as f64 || r[0] == i as f64 + 1.0)
        && ncol > 3
    {
        columns[0].role = Role::Index;
    }
    columns
}

/// Lateral and height units; an axis without one takes the other's, with a note.
fn units_of(lat: Option<f64>, hgt: Option<f64>, notes: &mut Vec<String>) -> (Unit, Unit) {
    match (lat, hgt) {
        (Some(l), Some(h)) => (Unit::Known(l), Unit::Known(h)),
        (Some(l), None) => {
            notes.push(format!(
                "heights taken in {}, the unit the file gives for x",
                units::name_of(l)
            ));
            (Unit::Known(l), Unit::Known(l))
        }
        (None, Some(h)) => {
            notes.push(format!(
                "lengths taken in {}, the unit the file gives for heights",
                units::name_of(h)
            ));
            (Unit::Known(h), Unit::Known(h))
        }
        (None, None) => (Unit::Unknown, Unit::Unknown),
    }
}

/// A profile: sorted by x, duplicates averaged, resampled when not uniformly spaced.
fn profile(
    ctx: Ctx<'_>,
    rows: &[Vec<f64>],
    xc: usize,
    zc: usize,
    is_valid: &dyn Fn(&[f64]) -> bool,
    notes: &mut Vec<String>,
) -> Result<Raw, ReadError> {
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(rows.len());
    for r in rows {
        if !r[xc].is_finite() {
            return Err(ctx.err(
                "x column",
                "an x value is missing or not a number",
                "every row needs an x value",
            ));
        }
        pts.push((r[xc], if is_valid(r) { r[zc] } else { f64::NAN }));
    }
    if pts.windows(2).any(|w| w[1].0 < w[0].0) {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        notes.push("rows sorted by x".into());
    }
    // Average repeated x values.
    let mut merged: Vec<(f64, f64, usize)> = Vec::with_capacity(pts.len());
    for (x, z) in pts {
        match merged.last_mut() {
            Some(last) if x == last.0 => {
                if z.is_finite() {
                    if last.1.is_finite() {
                        last.1 += z;
                        last.2 += 1;
                    } else {
                        last.1 = z;
                        last.2 = 1;
                    }
                }
            }
            _ => merged.push((x, z, 1)),
        }
    }
    if merged.len() < rows.len() {
        notes.push(format!(
            "{} rows with a repeated x averaged",
            rows.len() - merged.len()
        ));
    }
    let pts: Vec<(f64, f64)> = merged
        .into_iter()
        .map(|(x, z, c)| (x, if c > 1 { z / c as f64 } else { z }))
        .collect();
    let n = pts.len();
    if n < 2 {
        return Err(ctx.err(
            "x column",
            "a single x value",
            "the profile needs two points",
        ));
    }
    let span = pts[n - 1].0 - pts[0].0;
    let dx = check_spacing(ctx, "x column", span / (n - 1) as f64)?;
    let worst = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (p.0 - (pts[0].0 + i as f64 * dx)).abs())
        .fold(0.0, f64::max);
    // Uniform if every x is where a uniform grid puts it, up to the rounding of the
    // printed values (both ends and the point itself: one unit of the last digit).
    // Rounding explains deviations only when the printed digits resolve the step.
    let quantum = print_quantum(pts.iter().map(|p| p.0).take(500));
    let quantum = if quantum <= 0.1 * dx { quantum } else { 0.0 };
    let heights = if worst <= 1.01 * quantum + 1e-9 * span.abs() {
        pts.iter().map(|p| p.1).collect()
    } else {
        let (lo, hi) = pts.windows(2).fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
            let s = w[1].0 - w[0].0;
            (lo.min(s), hi.max(s))
        });
        notes.push(format!(
            "x is not uniformly spaced (steps {lo:.4e} to {hi:.4e}): resampled {n} points \
             by linear interpolation onto {n} points {dx:.4e} apart (same span)"
        ));
        let mut out = Vec::with_capacity(n);
        let mut j = 0;
        for i in 0..n {
            let x = if i == n - 1 {
                pts[n - 1].0
            } else {
                pts[0].0 + i as f64 * dx
            };
            while j + 2 < n && pts[j + 1].0 < x {
                j += 1;
            }
            let (a, b) = (pts[j], pts[j + 1]);
            let t = ((x - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
            out.push(a.1 + t * (b.1 - a.1));
        }
        out
    };
    Ok(Raw {
        nx: n,
        ny: 1,
        heights,
        height_unit: Unit::Unknown,
        spacing: Some((dx, dx)),
        lateral_unit: Unit::Unknown,
        spacing_fields: ("x column".into(), "x column".into()),
        channel: String::new(),
        notes: Vec::new(),
    })
}

/// The unit of the last printed digit of a column (1e-4 for `0.0386`, 1e-7 for
/// `1.3381669e+01`), found as the coarsest power of ten all values are multiples of.
fn print_quantum(values: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    for k in -6i32..=17 {
        let q = 10f64.powi(-k);
        if v.iter().all(|x| {
            let m = x / q;
            (m - m.round()).abs() <= 1e-9 * m.abs().max(1.0)
        }) {
            return q;
        }
    }
    0.0
}

/// Distinct values of a coordinate on a regular lattice: (origin, spacing, count).
fn axis(ctx: Ctx<'_>, field: &str, mut v: Vec<f64>) -> Result<(f64, f64, usize), ReadError> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return Err(ctx.err(field, "no values", "every row needs coordinates"));
    }
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
    if let Some(w) = v.windows(2).find(|w| ((w[1] - w[0]) - d).abs() > 0.25 * d) {
        return Err(ctx.err(
            field,
            format!(
                "values {} and {} are not one grid step ({d}) apart",
                w[0], w[1]
            ),
            "the points must lie on a regular grid; resample the data",
        ));
    }
    Ok((v[0], d, v.len()))
}

fn grid(
    ctx: Ctx<'_>,
    rows: &[Vec<f64>],
    xc: usize,
    yc: usize,
    zc: usize,
    is_valid: &dyn Fn(&[f64]) -> bool,
) -> Result<Raw, ReadError> {
    let (x0, dx, nx) = axis(ctx, "x column", rows.iter().map(|r| r[xc]).collect())?;
    let (y0, dy, ny) = axis(ctx, "y column", rows.iter().map(|r| r[yc]).collect())?;
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
    for r in rows {
        let ix = ((r[xc] - x0) / dx).round();
        let iy = if ny == 1 {
            0.0
        } else {
            ((r[yc] - y0) / dy).round()
        };
        let off_x = (r[xc] - x0 - ix * dx).abs() > 0.25 * dx;
        let off_y = ny > 1 && (r[yc] - y0 - iy * dy).abs() > 0.25 * dy;
        if !(ix >= 0.0 && iy >= 0.0 && ix < nx as f64 && iy < ny as f64) || off_x || off_y {
            return Err(ctx.err(
                "x/y columns",
                format!("point ({}, {}) is off the regular grid", r[xc], r[yc]),
                "resample onto a regular grid",
            ));
        }
        heights[iy as usize * nx + ix as usize] = if is_valid(r) { r[zc] } else { f64::NAN };
    }
    Ok(Raw {
        nx,
        ny,
        heights,
        height_unit: Unit::Unknown,
        spacing: Some((dx, dy)),
        lateral_unit: Unit::Unknown,
        spacing_fields: ("x column".into(), "y column".into()),
        channel: String::new(),
        notes: Vec::new(),
    })
}
