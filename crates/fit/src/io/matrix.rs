//! Text matrices: one row of heights per scan line, after an optional header in any of
//! the dialects instruments write: Gwyddion "Export Text" (`# Width: 10.00 µm`, in the
//! English or German locale: `Breite`, `Höhe`, `Kanal`, decimal commas), `key = value`
//! and `key: value` lines (`x-length`, `y-length`, `x-unit`, `z-unit`, `pixel size`,
//! `height conversion factor (-> µm) = 0.001`, `Value units`), any separator, UTF-8 or
//! UTF-16. Invalid points may be written as `NaN`, `bad`, `inf` or empty fields.
//!
//! What the header leaves out (pixel size, units) is left unknown here and supplied by the
//! user's flags, or named in the error.

use super::{ChannelInfo, Ctx, Decoded, Raw, Sniff, Unit, Want, text, units};
use crate::ReadError;

/// What a header key means.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Key {
    SizeX,
    SizeY,
    PixelSize,
    LateralUnit,
    HeightUnit,
    HeightFactor,
    Channel,
    PixelsX,
    PixelsY,
}

fn classify(key: &str) -> Option<Key> {
    let k = key
        .trim()
        .to_lowercase()
        .replace(['_', '-'], " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    Some(match k.as_str() {
        "width" | "breite" | "x length" | "xlength" | "xreal" | "x size" | "scan size x"
        | "x range" | "x scan size" | "length x" | "size x" => Key::SizeX,
        "height" | "höhe" | "hoehe" | "y length" | "ylength" | "yreal" | "y size"
        | "scan size y" | "y range" | "y scan size" | "length y" | "size y" => Key::SizeY,
        "pixel size" | "pixelsize" | "pixel spacing" | "spacing" | "sampling" | "dx"
        | "x pixel size" | "lateral resolution" => Key::PixelSize,
        "x unit" | "xunit" | "xy unit" | "xy units" | "xyunits" | "lateral unit"
        | "lateral units" | "length unit" | "x units" => Key::LateralUnit,
        "value units"
        | "value unit"
        | "z unit"
        | "zunit"
        | "z units"
        | "zunits"
        | "height unit"
        | "height units"
        | "wertebereich einheit"
        | "einheit" => Key::HeightUnit,
        "channel" | "kanal" | "title" | "name" => Key::Channel,
        "x pixels" | "xpixels" | "xres" | "columns" | "number of columns" | "points" => {
            Key::PixelsX
        }
        "y pixels" | "ypixels" | "yres" | "rows" | "number of rows" | "lines" => Key::PixelsY,
        _ if k.starts_with("height conversion factor")
            || k.starts_with("z scale")
            || k.starts_with("zscale")
            || k.starts_with("z factor")
            || k.starts_with("height scale") =>
        {
            Key::HeightFactor
        }
        _ => return None,
    })
}

/// Content check: numeric rows (≥ 4 columns or a recognised header).
pub(crate) fn sniff(bytes: &[u8]) -> Sniff {
    let Some(t) = text::sniff_sample(bytes) else {
        return Sniff::No;
    };
    let usable = text::sample_lines(&t);
    let dialect = text::Dialect::guess(usable.iter().copied().filter(|l| looks_numeric(l)));
    let mut header = false;
    let mut cols = Vec::new();
    for l in &usable {
        if let Some(r) = dialect.row(l) {
            cols.push(r.len());
        } else if text::key_value(l).is_some_and(|(k, _)| classify(&k).is_some()) {
            header = true;
        }
    }
    let Some(&first) = cols.first() else {
        return Sniff::No;
    };
    let consistent = cols.iter().all(|&c| c == first);
    match (header, consistent, first) {
        (true, true, _) => Sniff::Likely,
        (false, true, c) if c >= 4 || (c == 1 && cols.len() >= 4) => Sniff::Maybe,
        _ => Sniff::No,
    }
}

/// True when a line of `lines` is a header key this reader understands (`Width: 10 µm`).
pub(crate) fn has_header_key(lines: &[&str]) -> bool {
    lines
        .iter()
        .any(|l| text::key_value(l).is_some_and(|(k, _)| classify(&k).is_some()))
}

fn looks_numeric(l: &str) -> bool {
    let t = l.trim();
    !t.is_empty()
        && t.chars()
            .all(|c| c.is_ascii_digit() || " \t,;.eE+-".contains(c) || c.is_ascii_alphabetic())
        && t.chars()
            .next()
            .is_some_and(|c| c.is_ascii_digit() || c == '-' || c == '+' || c == '.')
}

/// A length in a header: `12.34 µm`, `12,34 µm` or a bare number (unit unknown).
fn header_length(ctx: Ctx<'_>, field: &str, v: &str) -> Result<(f64, Option<f64>), ReadError> {
    let (num, unit) = units::split_number(v).ok_or_else(|| {
        ctx.err(
            field,
            format!("`{v}` is not a length"),
            "write it as `<number> <unit>`, e.g. `10.00 µm`",
        )
    })?;
    if unit.is_empty() {
        return Ok((num, None));
    }
    let f = units::length_factor(unit).ok_or_else(|| {
        ctx.err(
            field,
            format!("`{unit}` is not a length unit"),
            "use m, mm, µm (um) or nm",
        )
    })?;
    Ok((num, Some(f)))
}

/// What the header lines state; `None` where they are silent.
#[derive(Default)]
struct Header {
    /// Lengths with the unit written beside them, if any.
    size_x: Option<(f64, Option<f64>)>,
    size_y: Option<(f64, Option<f64>)>,
    pixel: Option<(f64, Option<f64>)>,
    /// The keys as the header spells them (x size, y size, pixel size), for messages.
    keys: (String, String, String),
    lateral_unit: Option<f64>,
    /// A length unit, or the unit text when it is not one (the values are not heights).
    height_unit: Option<Result<f64, String>>,
    /// A height factor and the unit it converts to, when it names one.
    factor: Option<(f64, Option<f64>)>,
    pixels: (Option<usize>, Option<usize>),
    channel: Option<String>,
}

impl Header {
    /// Record one `key: value` line the reader understands.
    fn take(&mut self, ctx: Ctx<'_>, key: Key, k: &str, v: &str) -> Result<(), ReadError> {
        match key {
            Key::SizeX => {
                self.size_x = Some(header_length(ctx, k, v)?);
                self.keys.0 = k.trim().to_string();
            }
            Key::SizeY => {
                self.size_y = Some(header_length(ctx, k, v)?);
                self.keys.1 = k.trim().to_string();
            }
            Key::PixelSize => {
                self.pixel = Some(header_length(ctx, k, v)?);
                self.keys.2 = k.trim().to_string();
            }
            Key::LateralUnit => {
                self.lateral_unit = Some(units::length_factor(v).ok_or_else(|| {
                    ctx.err(
                        k,
                        format!("`{v}` is not a length unit"),
                        "use m, mm, µm or nm",
                    )
                })?)
            }
            Key::HeightUnit => {
                self.height_unit = Some(units::length_factor(v).ok_or_else(|| v.trim().to_string()))
            }
            Key::HeightFactor => {
                let (f, unit_in_value) = units::split_number(v)
                    .map(|(f, u)| (f, units::length_factor(u)))
                    .ok_or_else(|| {
                        ctx.err(k, format!("`{v}` is not a number"), "write e.g. `= 0.001`")
                    })?;
                // "height conversion factor (-> µm) = 0.001": the unit sits in the key.
                let unit_in_key = k
                    .split("->")
                    .nth(1)
                    .map(|u| u.trim_end_matches(')').trim())
                    .and_then(units::length_factor);
                self.factor = Some((f, unit_in_value.or(unit_in_key)));
            }
            Key::Channel => self.channel = Some(v.to_string()),
            Key::PixelsX => self.pixels.0 = v.trim().parse().ok(),
            Key::PixelsY => self.pixels.1 = v.trim().parse().ok(),
        }
        Ok(())
    }
}

/// The rows of numbers: `ny` rows of `nx` values, x fastest.
struct Rows {
    values: Vec<f64>,
    nx: usize,
    ny: usize,
}

/// Read a text matrix.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let text = text::decode(bytes);
    text::check_not_cut(ctx, &text)?;
    let (Rows { mut values, nx, ny }, header) = scan(ctx, &text)?;
    if nx == 0 || ny == 0 {
        return Err(ctx.err(
            "data",
            "no rows of numbers",
            "this is not a height matrix; check the file or force another format with --format",
        ));
    }
    // A single column is a profile written one value per line.
    let (nx, ny) = if nx == 1 { (ny, 1) } else { (nx, ny) };
    if let (Some(px), Some(py)) = header.pixels
        && (px, py) != (nx, ny)
        && (py, px) != (nx, ny)
    {
        return Err(ctx.err(
            "pixels",
            format!("the header states {px} × {py} points but the data are {nx} × {ny}"),
            "the file is truncated or its header is wrong",
        ));
    }
    let mut notes = Vec::new();
    let (height_unit, is_height, unit_name) = height_unit(&header, &mut values);
    let (spacing, lunit) = lateral_spacing(&header, (nx, ny), &mut notes);
    let lateral_unit = match (lunit, height_unit, spacing) {
        (Some(u), _, _) => Unit::Known(u),
        (None, Unit::Known(u), Some(_)) if is_height => {
            notes.push(format!(
                "lengths taken in {}, the unit the header gives for heights",
                units::name_of(u)
            ));
            Unit::Known(u)
        }
        _ => Unit::Unknown,
    };
    let keys = header.keys;
    let spacing_fields = if header.pixel.is_some() {
        (keys.2.clone(), keys.2)
    } else if header.size_y.is_some() {
        (keys.0, keys.1)
    } else {
        (keys.0.clone(), keys.0)
    };
    let raw = Raw {
        nx,
        ny,
        heights: values,
        height_unit,
        spacing,
        lateral_unit,
        spacing_fields,
        channel: header.channel.unwrap_or_else(|| String::from("matrix")),
        notes,
    };
    let info = ChannelInfo {
        unit: unit_name,
        is_height,
        ..raw.info(0)
    };
    Decoded::single_listed(ctx, want, info, raw)
}

/// The header lines and the one block of equal-length rows after them.
fn scan(ctx: Ctx<'_>, text: &str) -> Result<(Rows, Header), ReadError> {
    let dialect = text::Dialect::guess(text.lines().filter(|l| looks_numeric(l)));
    let mut header = Header::default();
    let mut rows = Rows {
        values: Vec::new(),
        nx: 0,
        ny: 0,
    };
    let mut data_ended = false;
    for (lineno, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() {
            if rows.ny > 0 {
                data_ended = true;
            }
            continue;
        }
        if let Some(row) = dialect.row(t) {
            if data_ended {
                return Err(ctx.err(
                    &format!("line {}", lineno + 1),
                    "data continue after a blank line",
                    "a matrix must be one block of rows; remove the blank line or split the file",
                ));
            }
            if rows.nx == 0 {
                rows.nx = row.len();
            } else if row.len() != rows.nx {
                return Err(ctx.err(
                    &format!("line {}", lineno + 1),
                    format!("has {} values but the first row has {}", row.len(), rows.nx),
                    "every row of the matrix must have the same length",
                ));
            }
            rows.values.extend_from_slice(&row);
            rows.ny += 1;
            continue;
        }
        if rows.ny > 0 && !t.starts_with('#') {
            return Err(ctx.err(
                &format!("line {}", lineno + 1),
                format!(
                    "`{}` is not a row of numbers",
                    t.chars().take(40).collect::<String>()
                ),
                "remove stray text; header lines go before the data",
            ));
        }
        if let Some((k, v)) = text::key_value(t)
            && let Some(key) = classify(&k)
        {
            header.take(ctx, key, &k, &v)?;
        }
    }
    Ok((rows, header))
}

/// The unit of the values, whether they are heights, and the unit's name for listings. A
/// factor with no unit is applied to `values` here, leaving the unit to the user.
fn height_unit(header: &Header, values: &mut [f64]) -> (Unit, bool, String) {
    match (&header.height_unit, header.factor) {
        (Some(Err(u)), _) => (Unit::Unknown, false, u.clone()),
        (_, Some((f, Some(u)))) => (Unit::Known(f * u), true, units::name_of(u)),
        (Some(Ok(u)), Some((f, None))) => (Unit::Known(f * u), true, units::name_of(*u)),
        (None, Some((f, None))) => {
            for v in values.iter_mut() {
                *v *= f;
            }
            (Unit::Unknown, true, String::new())
        }
        (Some(Ok(u)), None) => (Unit::Known(*u), true, units::name_of(*u)),
        (None, None) => (Unit::Unknown, true, String::new()),
    }
}

/// Pixel spacing in the header's lateral unit, and that unit: from the pixel size, else
/// from the scan size over the grid.
fn lateral_spacing(
    header: &Header,
    (nx, ny): (usize, usize),
    notes: &mut Vec<String>,
) -> (Option<(f64, f64)>, Option<f64>) {
    let lat = |u: Option<f64>| u.or(header.lateral_unit);
    if let Some((p, u)) = header.pixel {
        return (Some((p, p)), lat(u));
    }
    let Some((sx, ux)) = header.size_x else {
        return (None, header.lateral_unit);
    };
    let (sy, uy) = match header.size_y {
        Some((sy, uy)) => (sy, uy),
        None if ny > 1 => {
            notes.push("the header gives no height (y size): square pixels assumed".into());
            (sx * ny as f64 / nx as f64, ux)
        }
        None => (sx, ux),
    };
    let (ux, uy) = (lat(ux), lat(uy));
    // Mixed units (`Width: 12.34 µm`, `Height: 5678.9 nm`) are folded into x's unit.
    let sy = match (ux, uy) {
        (Some(a), Some(b)) => sy * b / a,
        _ => sy,
    };
    (
        Some((
            sx / nx as f64,
            if ny > 1 {
                sy / ny as f64
            } else {
                sx / nx as f64
            },
        )),
        ux.or(uy),
    )
}
