//! Keysight/Agilent (Molecular Imaging) PicoView `.mi` images: a text header of
//! 14-character keys followed by values (`xPixels`, `yPixels`, `xLength`, `yLength` in
//! metres, `scanUp`), then one `bufferLabel` block per channel (`bufferRange`,
//! `bufferUnit`), then a `data` line (`BINARY` int16, `BINARY_32` int32, or ASCII) and
//! the channels one after another, x fastest. Values are `raw / 2^15 (or 2^31) ·
//! bufferRange` in `bufferUnit`.

use super::{
    ChannelInfo, Ctx, Decoded, MAX_POINTS, Raw, Unit, Want, binary, check_spacing, checked_grid,
    units,
};
use crate::ReadError;

struct Buffer {
    label: String,
    range: f64,
    unit: String,
    direction: String,
}

/// The text header: global keys, the channel blocks, the `data` line's value and the
/// offset of the values after it.
struct Header {
    global: Vec<(String, String)>,
    buffers: Vec<Buffer>,
    data_kind: Option<String>,
    data_start: usize,
}

/// Read a PicoView image.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let Header {
        global,
        buffers,
        data_kind,
        data_start: pos,
    } = header(bytes);
    let kind = data_kind.ok_or_else(|| {
        ctx.err(
            "data",
            "the `data` line that starts the values is missing",
            "the file is truncated",
        )
    })?;
    if buffers.is_empty() {
        return Err(ctx.err(
            "bufferLabel",
            "no channel in the file",
            "the file holds no image",
        ));
    }
    let get = |k: &str| global.iter().find(|(g, _)| g == k).map(|(_, v)| v.as_str());
    let num = |k: &str| -> Result<f64, ReadError> {
        get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| ctx.err(k, "missing or not a number", "the header is incomplete"))
    };
    let nx = num("xPixels")?;
    let ny = num("yPixels")?;
    if !(nx >= 1.0 && ny >= 1.0 && nx < 1e9 && ny < 1e9) {
        return Err(ctx.err(
            "xPixels/yPixels",
            "not a positive grid",
            "the header is corrupt",
        ));
    }
    let (nx, ny) = (nx as u64, ny as u64);
    let channels: Vec<ChannelInfo> = buffers
        .iter()
        .enumerate()
        .map(|(i, b)| ChannelInfo {
            index: i,
            name: if b.direction.is_empty() {
                b.label.clone()
            } else {
                format!("{} ({})", b.label, b.direction)
            },
            unit: b.unit.clone(),
            is_height: units::length_factor(&b.unit).is_some(),
            nx: nx as usize,
            ny: ny as usize,
        })
        .collect();
    let format = match kind.as_str() {
        "BINARY" => Some((binary::Sample::I16, 32768.0)),
        "BINARY_32" => Some((binary::Sample::I32, 2147483648.0)),
        _ => None,
    };
    if let Some((sample, _)) = format {
        check_complete(ctx, &channels, (nx, ny), sample, &kind, (pos, bytes.len()))?;
    }
    Decoded::pick(ctx, want, channels, |selected, channel| {
        let (sample, full) = match format {
            Some(f) => f,
            None => {
                let k = kind.as_str();
                return Err(ctx.err(
                    "data",
                    format!("`{k}` data are not supported (only BINARY and BINARY_32)"),
                    "save the image in binary format from PicoView",
                ));
            }
        };
        let size = sample.size() as u64;
        let data = &bytes[pos..];
        let per = checked_grid(ctx, "xPixels × yPixels", nx, ny, 1, u64::MAX)? as u64;
        let need = per.saturating_mul(size).saturating_mul(selected as u64 + 1);
        if need > data.len() as u64 {
            return Err(ctx.short("channel data", need, data.len() as u64));
        }
        let block = &data[(per * size * selected as u64) as usize..];
        let raw = binary::decode(block, sample, true, per as usize)
            .ok_or_else(|| ctx.short("channel data", need, data.len() as u64))?;
        let b = &buffers[selected];
        let q = b.range / full;
        let zu = units::length_factor(&b.unit).unwrap_or(1.0);
        let dx = check_spacing(ctx, "xLength", num("xLength")? / nx as f64)?;
        let dy = if ny == 1 {
            dx
        } else {
            check_spacing(ctx, "yLength", num("yLength")? / ny as f64)?
        };
        let heights = raw.into_iter().map(|v| v * q).collect();
        let out = Raw::si(nx as usize, ny as usize, dx, dy, heights, &channel.name)
            .spacing_from("xLength", "yLength");
        Ok(out.in_units(Unit::Known(zu), Unit::Known(1.0)))
    })
}

/// The header lines up to and including `data`: keys fill the first 14 bytes, values are
/// Latin-1; lines after a `bufferLabel` describe that channel.
fn header(bytes: &[u8]) -> Header {
    let mut pos = 0usize;
    let mut global: Vec<(String, String)> = Vec::new();
    let mut buffers: Vec<Buffer> = Vec::new();
    let mut data_kind = None;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |e| pos + e);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if raw.first() == Some(&b' ') || raw.len() < 2 {
            continue;
        }
        let text = |b: &[u8]| {
            b.iter()
                .map(|&c| c as char)
                .collect::<String>()
                .trim()
                .to_string()
        };
        let (k, v) = if raw.len() > 14 {
            (text(&raw[..14]), text(&raw[14..]))
        } else {
            (text(raw), String::new())
        };
        let (k, v) = (k.as_str(), v.as_str());
        if k == "data" {
            data_kind = Some(v.to_string());
            break;
        }
        if k == "bufferLabel" {
            buffers.push(Buffer {
                label: v.to_string(),
                range: f64::NAN,
                unit: String::new(),
                direction: String::new(),
            });
            continue;
        }
        match buffers.last_mut() {
            Some(b) => match k {
                "bufferRange" => b.range = v.parse().unwrap_or(f64::NAN),
                "bufferUnit" => b.unit = v.to_string(),
                "direction" => b.direction = v.to_string(),
                _ => {}
            },
            None => global.push((k.to_string(), v.to_string())),
        }
    }
    Header {
        global,
        buffers,
        data_kind,
        data_start: pos,
    }
}

/// Every channel's block lies in the file, not only the one asked for: a copy cut short
/// holds its first channels whole, and reading them would hide that the file is broken.
/// (A grid beyond the supported size is `checked_grid`'s to report.)
fn check_complete(
    ctx: Ctx<'_>,
    channels: &[ChannelInfo],
    (nx, ny): (u64, u64),
    sample: binary::Sample,
    kind: &str,
    (data_start, file_len): (usize, usize),
) -> Result<(), ReadError> {
    if nx.saturating_mul(ny) > MAX_POINTS {
        return Ok(());
    }
    let block = nx.saturating_mul(ny).saturating_mul(sample.size() as u64);
    let file_len = file_len as u64;
    for c in channels {
        let start = (data_start as u64).saturating_add(block.saturating_mul(c.index as u64));
        let end = start.saturating_add(block);
        if end > file_len {
            return Err(ctx.truncated(
                "data",
                &format!(
                    "channel {} `{}` ({nx} × {ny} {kind} values)",
                    c.index, c.name
                ),
                (start, end),
                file_len,
            ));
        }
    }
    Ok(())
}
