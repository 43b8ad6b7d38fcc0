//! Bruker/Veeco NanoScope files (`.di`, `.spm`, `.001`): a `\`-keyword text header split in
//! `\*` sections, followed by int16 (or int32) images. Heights are
//! `raw × hard scale [V/LSB] × sensitivity [nm/V]`, with the sensitivity named inside the
//! image's `Z scale` entry (e.g. `[Sens. ZsensSens]`).

use super::{
    ChannelInfo, Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, header_end, units,
};
use crate::ReadError;

struct Section {
    name: String,
    entries: Vec<(String, String)>,
}

impl Section {
    fn get(&self, key: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }
}

/// Read a NanoScope file: list its image channels, decode the chosen one.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let end = header_end(
        ctx,
        bytes,
        "\\*File list end",
        "the file is truncated or not a NanoScope file",
    )?;
    let header = String::from_utf8_lossy(&bytes[..end]);
    let sections = parse_sections(&header);
    let images: Vec<&Section> = sections
        .iter()
        .filter(|s| s.name.eq_ignore_ascii_case("Ciao image list"))
        .collect();
    if images.is_empty() {
        return Err(ctx.err(
            "\\*Ciao image list",
            "no image in the file",
            "this reader handles image files, not force curves",
        ));
    }
    let channels: Vec<ChannelInfo> = images
        .iter()
        .enumerate()
        .map(|(i, img)| describe(ctx, i, img, &sections))
        .collect();
    // Every image, not only the one asked for: a copy cut short holds its first
    // channels whole, and reading them would hide that the file is broken.
    let file_len = bytes.len() as u64;
    for (img, info) in images.iter().zip(&channels) {
        if let Some((offset, length)) = data_range(img)
            && offset.saturating_add(length) > file_len
        {
            return Err(ctx.truncated(
                "\\Data offset + \\Data length",
                &format!(
                    "the image data of channel {} `{}` ({length} bytes)",
                    info.index, info.name
                ),
                (offset, offset.saturating_add(length)),
                file_len,
            ));
        }
    }
    Decoded::pick(ctx, want, channels, |selected, _| {
        decode(ctx, bytes, images[selected], &sections)
    })
}

/// Where an image section says its data are: `(offset, length)` in bytes, when both are
/// valid numbers (`decode` names the field that is not).
fn data_range(img: &Section) -> Option<(u64, u64)> {
    let num = |key: &str| {
        img.get(key)
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| *v >= 0.0 && v.fract() == 0.0 && *v <= 1e15)
    };
    Some((num("Data offset")? as u64, num("Data length")? as u64))
}

/// Name, unit and size of an image section, without decoding it.
fn describe(ctx: Ctx<'_>, index: usize, img: &Section, sections: &[Section]) -> ChannelInfo {
    let dim = |k: &str| {
        img.get(k)
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| *v >= 0.0 && *v < 1e9)
            .map_or(0, |v| v as usize)
    };
    let name = img
        .entries
        .iter()
        .find(|(k, _)| k.ends_with("Image Data"))
        .map(|(_, v)| {
            let quoted = v.split('"').nth(1).map(str::trim).filter(|s| !s.is_empty());
            quoted
                .or_else(|| between(v, '[', ']'))
                .unwrap_or("unknown")
                .to_string()
        })
        .unwrap_or_else(|| "unknown".into());
    let (unit, is_height) = match z_factor(ctx, img, sections) {
        Ok(_) => ("m".to_string(), true),
        Err(_) => (sensitivity_unit(img, sections).unwrap_or_default(), false),
    };
    ChannelInfo {
        index,
        name,
        unit,
        is_height,
        nx: dim("Samps/line"),
        ny: dim("Number of lines"),
    }
}

/// The unit of the sensitivity that scales an image (`nm/V` → `nm`), when stated.
fn sensitivity_unit(img: &Section, sections: &[Section]) -> Option<String> {
    let (image_key, _) = img
        .entries
        .iter()
        .find(|(k, _)| k.ends_with("Image Data"))?;
    let prefix = image_key.strip_suffix("Image Data").unwrap_or("@2:");
    let zval = img.get(&format!("{prefix}Z scale"))?;
    let sens_name = between(zval, '[', ']')?;
    let sens = find_global(sections, &format!("@{sens_name}"))?;
    let unit = sens.split_whitespace().nth(2)?;
    Some(unit.split('/').next().unwrap_or(unit).to_string())
}

/// Decode one image section into metres.
fn decode(
    ctx: Ctx<'_>,
    bytes: &[u8],
    img: &Section,
    sections: &[Section],
) -> Result<Raw, ReadError> {
    let num = |key: &str| -> Result<f64, ReadError> {
        img.get(key)
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| {
                ctx.err(
                    key,
                    "missing or not a number",
                    "the header is incomplete; re-export the file",
                )
            })
    };
    let offset = num("Data offset")?;
    let length = num("Data length")?;
    let bpp = img
        .get("Bytes/pixel")
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(2);
    let nx = num("Samps/line")?;
    let ny = num("Number of lines")?;
    if !(offset >= 0.0 && length >= 0.0 && nx >= 1.0 && ny >= 1.0)
        || [offset, length, nx, ny]
            .iter()
            .any(|v| v.fract() != 0.0 || *v > 1e15)
    {
        return Err(ctx.err(
            "Data offset/length/Samps/line",
            "not valid non-negative integers",
            "the header is corrupt",
        ));
    }
    let (offset, length, nx, ny) = (offset as u64, length as u64, nx as u64, ny as u64);
    let kind = match bpp {
        2 => binary::Sample::I16,
        4 => binary::Sample::I32,
        b => {
            return Err(ctx.err(
                "Bytes/pixel",
                format!("{b} bytes per pixel is not supported"),
                "expected 2 or 4",
            ));
        }
    };
    let file_len = bytes.len() as u64;
    let block_end = offset.saturating_add(length);
    if block_end > file_len {
        return Err(ctx.short("Data offset + Data length", block_end, file_len));
    }
    let n = checked_grid(ctx, "Samps/line × Number of lines", nx, ny, bpp, length)?;
    let data = &bytes[offset as usize..block_end as usize];
    let raw = binary::decode(data, kind, true, n)
        .ok_or_else(|| ctx.short("image data", n as u64 * bpp, length))?;

    // Lateral size: "\Scan Size: 10 10 ~m" (x y unit) or older "10000 nm".
    let scan = img
        .get("Scan Size")
        .or_else(|| find_global(sections, "Scan Size"))
        .ok_or_else(|| ctx.err("Scan Size", "missing", "the header is incomplete"))?;
    let (sx, sy) = parse_scan_size(scan).ok_or_else(|| {
        ctx.err(
            "Scan Size",
            format!("cannot parse `{scan}`"),
            "expected `<x> <y> <unit>` or `<size> <unit>`",
        )
    })?;
    let dx = check_spacing(ctx, "Scan Size", sx / nx as f64)?;
    let dy = check_spacing(ctx, "Scan Size", sy / ny as f64)?;

    let (name, zfactor) = z_factor(ctx, img, sections)?;
    // The scale is per 16-bit LSB; a 32-bit LSB is 2^16 times smaller.
    let zfactor = if bpp == 4 { zfactor / 65536.0 } else { zfactor };
    // NanoScope stores the bottom line first; flip so row 0 is the top line (as Gwyddion
    // and its text exports do).
    let nxu = nx as usize;
    let heights = raw
        .chunks_exact(nxu)
        .rev()
        .flat_map(|line| line.iter().map(|v| v * zfactor))
        .collect();
    Ok(Raw::si(nx as usize, ny as usize, dx, dy, heights, name)
        .spacing_from("Scan Size", "Scan Size"))
}

fn parse_sections(header: &str) -> Vec<Section> {
    let mut out: Vec<Section> = Vec::new();
    for line in header.split('\n') {
        let line = line.trim_end_matches('\r');
        let Some(rest) = line.strip_prefix('\\') else {
            continue;
        };
        if let Some(name) = rest.strip_prefix('*') {
            out.push(Section {
                name: name.trim().to_string(),
                entries: Vec::new(),
            });
        } else if let Some((k, v)) = split_key(rest)
            && let Some(s) = out.last_mut()
        {
            s.entries.push((k.trim().to_string(), v.trim().to_string()));
        }
    }
    out
}

/// Split `key: value`; keys like `@2:Z scale` keep their `@<group>:` prefix.
fn split_key(rest: &str) -> Option<(&str, &str)> {
    let first = rest.find(':')?;
    let group = &rest[..first];
    let is_group =
        group.len() > 1 && group.starts_with('@') && group[1..].bytes().all(|b| b.is_ascii_digit());
    if is_group {
        let second = rest[first + 1..].find(':')? + first + 1;
        Some((&rest[..second], &rest[second + 1..]))
    } else {
        Some((&rest[..first], &rest[first + 1..]))
    }
}

fn find_global<'a>(sections: &'a [Section], key: &str) -> Option<&'a str> {
    sections
        .iter()
        .filter(|s| !s.name.eq_ignore_ascii_case("Ciao image list"))
        .find_map(|s| s.get(key))
}

fn parse_scan_size(v: &str) -> Option<(f64, f64)> {
    let toks: Vec<&str> = v.split_whitespace().collect();
    let (x, y, unit) = match toks.as_slice() {
        [x, y, unit] => (x.parse::<f64>().ok()?, y.parse::<f64>().ok()?, *unit),
        [x, unit] => {
            let x = x.parse::<f64>().ok()?;
            (x, x, *unit)
        }
        _ => return None,
    };
    let f = units::length_factor(unit)?;
    Some((x * f, y * f))
}

/// Channel name and metres per LSB for an image section.
fn z_factor(ctx: Ctx<'_>, img: &Section, sections: &[Section]) -> Result<(String, f64), ReadError> {
    // "\@2:Image Data: S [ZSensor] "Height Sensor""
    let (image_key, image_val) = img
        .entries
        .iter()
        .find(|(k, _)| k.ends_with("Image Data"))
        .ok_or_else(|| {
            ctx.err(
                "Image Data",
                "missing in the image section",
                "the header is incomplete",
            )
        })?;
    let prefix = image_key.strip_suffix("Image Data").unwrap_or("@2:");
    let name = between(image_val, '[', ']')
        .unwrap_or("unknown")
        .to_string();
    // "\@2:Z scale: V [Sens. ZsensSens] (0.000375 V/LSB) 24.57 V"
    let zkey = format!("{prefix}Z scale");
    let zval = img.get(&zkey).ok_or_else(|| {
        ctx.err(
            &zkey,
            "missing in the image section",
            "the header is incomplete",
        )
    })?;
    let sens_name = between(zval, '[', ']').ok_or_else(|| {
        ctx.err(
            &zkey,
            format!("no sensitivity name in `{zval}`"),
            "the header is incomplete",
        )
    })?;
    let hard = between(zval, '(', ')')
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| {
            ctx.err(
                &zkey,
                format!("no hard scale `(… V/LSB)` in `{zval}`"),
                "the header is incomplete",
            )
        })?;
    // Full-scale value after the parenthesis ("… V/LSB) 24.57563 V"): Gwyddion divides it
    // by 2^16, which agrees with its own text exports to 1e-7; the rounded per-LSB value in
    // parentheses is only a fallback.
    let full_scale = zval
        .rfind(')')
        .and_then(|i| zval[i + 1..].split_whitespace().next())
        .and_then(|s| s.parse::<f64>().ok());
    let hard = match full_scale {
        Some(v) if v.is_finite() && v != 0.0 => v / 65536.0,
        _ => hard,
    };
    let sens_key = format!("@{sens_name}");
    let sens = find_global(sections, &sens_key).ok_or_else(|| {
        ctx.err(
            &sens_key,
            format!(
                "channel `{name}` is scaled by `{sens_name}`, which the header does not define"
            ),
            "choose a height channel with --channel",
        )
    })?;
    // "V 790.3658 nm/V"
    let toks: Vec<&str> = sens.split_whitespace().collect();
    let (value, unit) = match toks.as_slice() {
        [_, v, rest @ ..] => (v.parse::<f64>().ok(), rest.first().copied().unwrap_or("")),
        _ => (None, ""),
    };
    let value = value.ok_or_else(|| {
        ctx.err(
            &sens_key,
            format!("cannot parse `{sens}`"),
            "the header is corrupt",
        )
    })?;
    let length_unit = unit.split('/').next().unwrap_or("");
    let f = units::length_factor(length_unit).ok_or_else(|| {
        ctx.err(
            "channel",
            format!("channel `{name}` is in `{unit}`, not a height"),
            "choose a height channel (Height, ZSensor) with --channel",
        )
    })?;
    let z = hard * value * f;
    if !z.is_finite() || z == 0.0 {
        return Err(ctx.err(
            &zkey,
            format!("scale factor {z} is not usable"),
            "the header is corrupt",
        ));
    }
    Ok((name, z))
}

fn between(s: &str, open: char, close: char) -> Option<&str> {
    let a = s.find(open)?;
    let b = s[a + 1..].find(close)? + a + 1;
    Some(s[a + 1..b].trim())
}
