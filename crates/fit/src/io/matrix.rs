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

/// Read a text matrix.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let text = text::decode(bytes);
    text::check_not_cut(ctx, &text)?;
    let dialect = text::Dialect::guess(text.lines().filter(|l| looks_numeric(l)));
    let mut size_x = None;
    let mut size_y = None;
    let mut pixel = None;
    // The keys as the header spells them (x size, y size, pixel size), for messages.
    let mut keys = (String::new(), String::new(), String::new());
    let mut lateral_unit: Option<f64> = None;
    let mut height_unit: Option<Result<f64, String>> = None;
    let mut factor: Option<(f64, Option<f64>)> = None;
    let mut pixels: (Option<usize>, Option<usize>) = (None, None);
    let mut channel = String::from("matrix");
    let mut values: Vec<f64> = Vec::new();
    let (mut nx, mut ny) = (0usize, 0usize);
    let mut data_ended = false;
    for (lineno, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() {
            if ny > 0 {
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
            if nx == 0 {
                nx = row.len();
            } else if row.len() != nx {
                return Err(ctx.err(
                    &format!("line {}", lineno + 1),
                    format!("has {} values but the first row has {nx}", row.len()),
                    "every row of the matrix must have the same length",
                ));
            }
            values.extend_from_slice(&row);
            ny += 1;
            continue;
        }
        if ny > 0 && !t.starts_with('#') {
            return Err(ctx.err(
                &format!("line {}", lineno + 1),
                format!(
                    "`{}` is not a row of numbers",
                    t.chars().take(40).collect::<String>()
                ),
                "remove stray text; header lines go before the data",
            ));
        }
        let Some((k, v)) = text::key_value(t) else {
            continue;
        };
        let Some(key) = classify(&k) else {
            continue;
        };
        match key {
            Key::SizeX => {
                size_x = Some(header_length(ctx, &k, &v)?);
                keys.0 = k.trim().to_string();
            }
            Key::SizeY => {
                size_y = Some(header_length(ctx, &k, &v)?);
                keys.1 = k.trim().to_string();
            }
            Key::PixelSize => {
                pixel = Some(header_length(ctx, &k, &v)?);
                keys.2 = k.trim().to_string();
            }
            Key::LateralUnit => {
                lateral_unit = Some(units::length_factor(&v).ok_or_else(|| {
                    ctx.err(
                        &k,
                        format!("`{v}` is not a length unit"),
                        "use m, mm, µm or nm",
                    )
                })?)
            }
            Key::HeightUnit => {
                height_unit = Some(units::length_factor(&v).ok_or_else(|| v.trim().to_string()))
            }
            Key::HeightFactor => {
                let (f, unit_in_value) = units::split_number(&v)
                    .map(|(f, u)| (f, units::length_factor(u)))
                    .ok_or_else(|| {
                        ctx.err(&k, format!("`{v}` is not a number"), "write e.g. `= 0.001`")
                    })?;
                // "height conversion factor (-> µm) = 0.001": the unit sits in the key.
                let unit_in_key = k
                    .split("->")
                    .nth(1)
                    .map(|u| u.trim_end_matches(')').trim())
                    .and_then(units::length_factor);
                factor = Some((f, unit_in_value.or(unit_in_key)));
            }
            Key::Channel => channel = v.to_string(),
            Key::PixelsX => pixels.0 = v.trim().parse().ok(),
            Key::PixelsY => pixels.1 = v.trim().parse().ok(),
        }
    }
    if nx == 0 || ny == 0 {
        return Err(ctx.err(
            "data",
            "no rows of numbers",
            "this is not a height matrix; check the file or force another format with --format",
        ));
    }
    // A single column is a profile written one value per line.
    let (nx, ny) = if nx == 1 { (ny, 1) } else { (nx, ny) };
    if let (Some(px), Some(py)) = pixels
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
    let (height_unit, is_height, unit_name) = match (&height_unit, factor) {
        (Some(Err(u)), _) => (Unit::Unknown, false, u.clone()),
        (_, Some((f, Some(u)))) => (Unit::Known(f * u), true, units::name_of(u)),
        (Some(Ok(u)), Some((f, None))) => (Unit::Known(f * u), true, units::name_of(*u)),
        (None, Some((f, None))) => {
            for v in &mut values {
                *v *= f;
            }
            (Unit::Unknown, true, String::new())
        }
        (Some(Ok(u)), None) => (Unit::Known(*u), true, units::name_of(*u)),
        (None, None) => (Unit::Unknown, true, String::new()),
    };
    // Lateral spacing and its unit.
    let lat = |u: Option<f64>| u.or(lateral_unit);
    let (spacing, lunit) = if let Some((p, u)) = pixel {
        (Some((p, p)), lat(u))
    } else if let Some((sx, ux)) = size_x {
        let (sy, uy) = match size_y {
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
    } else {
        (None, lateral_unit)
    };
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
    let spacing_fields = if pixel.is_some() {
        (keys.2.clone(), keys.2)
    } else if size_y.is_some() {
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
        channel,
        notes,
    };
    let info = ChannelInfo {
        unit: unit_name,
        is_height,
        ..raw.info(0)
    };
    Decoded::single_listed(ctx, want, info, raw)
}
