//! Length-unit names as instruments write them, to metres.

/// Metres per unit for a length-unit name (`m`, `mm`, `um`, `µm`, `~m`, `nm`, `Å`,
/// `microns`, `[mm]`, `(µm)`, …). Returns `None` for anything that is not a length.
pub fn length_factor(unit: &str) -> Option<f64> {
    let u = unit
        .trim()
        .trim_matches(|c| matches!(c, '[' | ']' | '(' | ')' | '{' | '}' | '"' | '\''))
        .trim();
    // A micro sign decoded as Latin-1 from UTF-8 bytes ("Âµm").
    let u = u.replace("Âµ", "µ");
    let exact = match u.as_str() {
        "m" => Some(1.0),
        "cm" => Some(1e-2),
        "mm" => Some(1e-3),
        "um" | "µm" | "μm" | "~m" | "mkm" => Some(1e-6),
        "nm" => Some(1e-9),
        "pm" => Some(1e-12),
        "A" | "Å" | "\u{212b}" => Some(1e-10),
        _ => None,
    };
    if exact.is_some() {
        return exact;
    }
    match u.to_lowercase().as_str() {
        "meter" | "meters" | "metre" | "metres" => Some(1.0),
        "centimeter" | "centimeters" | "centimetre" | "centimetres" => Some(1e-2),
        "millimeter" | "millimeters" | "millimetre" | "millimetres" => Some(1e-3),
        "micrometer" | "micrometers" | "micrometre" | "micrometres" | "micron" | "microns"
        | "mikrometer" => Some(1e-6),
        "nanometer" | "nanometers" | "nanometre" | "nanometres" => Some(1e-9),
        "picometer" | "picometers" | "picometre" | "picometres" => Some(1e-12),
        "angstrom" | "angstroms" | "ångström" | "ang" => Some(1e-10),
        "inch" | "inches" => Some(0.0254),
        "mil" | "mils" => Some(25.4e-6),
        "uin" | "µin" | "microinch" | "microinches" => Some(25.4e-9),
        _ => None,
    }
}

/// A readable name for a factor in metres (`µm` for 1e-6); other values as `1.5e-7 m`.
pub fn name_of(f: f64) -> String {
    let named = [
        (1.0, "m"),
        (1e-2, "cm"),
        (1e-3, "mm"),
        (1e-6, "µm"),
        (1e-9, "nm"),
        (1e-10, "Å"),
        (1e-12, "pm"),
    ];
    for (v, n) in named {
        if (f / v - 1.0).abs() < 1e-9 {
            return n.to_string();
        }
    }
    format!("{f:e} m")
}

/// Split "10.00 µm" into metres (`10e-6`). A decimal comma is accepted.
pub fn parse_length(text: &str) -> Option<f64> {
    let (value, unit) = split_number(text)?;
    let factor = if unit.is_empty() {
        1.0
    } else {
        length_factor(unit)?
    };
    let v = value * factor;
    v.is_finite().then_some(v)
}

/// Split "12,34 µm" or "1.5e-6m" into the number and the rest (trimmed).
pub fn split_number(text: &str) -> Option<(f64, &str)> {
    let t = text.trim();
    let mut end = 0;
    let bytes = t.as_bytes();
    while end < bytes.len() {
        let c = bytes[end];
        let ok = c.is_ascii_digit()
            || matches!(c, b'.' | b',' | b'-' | b'+')
            || ((c == b'e' || c == b'E')
                && end > 0
                && bytes[end - 1].is_ascii_digit()
                && bytes
                    .get(end + 1)
                    .is_some_and(|n| n.is_ascii_digit() || *n == b'-' || *n == b'+'));
        if !ok {
            break;
        }
        end += 1;
    }
    let num = t[..end].trim_end_matches(',').replace(',', ".");
    let value: f64 = num.parse().ok()?;
    Some((value, t[end..].trim()))
}
