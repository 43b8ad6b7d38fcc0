//! Length-unit names as instruments write them, to metres.

/// Metres per unit for a length-unit name (`m`, `mm`, `um`, `µm`, `~m`, `nm`, `Å`, …).
/// Returns `None` for anything that is not a length.
pub fn length_factor(unit: &str) -> Option<f64> {
    let u = unit.trim();
    let exact = match u {
        "m" => Some(1.0),
        "cm" => Some(1e-2),
        "mm" => Some(1e-3),
        "um" | "µm" | "μm" | "~m" => Some(1e-6),
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
        "millimeter" | "millimeters" | "millimetre" | "millimetres" => Some(1e-3),
        "micrometer" | "micrometers" | "micrometre" | "micrometres" | "micron" | "microns" => {
            Some(1e-6)
        }
        "nanometer" | "nanometers" | "nanometre" | "nanometres" => Some(1e-9),
        "angstrom" | "angstroms" | "ångström" => Some(1e-10),
        _ => None,
    }
}

/// Split "10.00 µm" into (10.0, factor of µm).
pub fn parse_length(text: &str) -> Option<f64> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(t.len());
    let value: f64 = t[..split].trim().parse().ok()?;
    let unit = t[split..].trim();
    let factor = if unit.is_empty() {
        1.0
    } else {
        length_factor(unit)?
    };
    let v = value * factor;
    v.is_finite().then_some(v)
}
