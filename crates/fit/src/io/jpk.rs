//! JPK (Bruker) image scans `.jpk`: a TIFF whose first page is a preview and whose further
//! pages are channels, each carrying JPK's private tags: `0x8050` the channel name,
//! `0x8052` its display name, `0x8051` retrace, `0x8081` the default slot, and per slot
//! `i` (tags `+ 0x30·i`): `0x8090` its name, `0x80A2` the encoder unit, `0x80A3` the scaling
//! type, `0x80A4` the multiplier and `0x80A5` the offset (doubles). The first page holds
//! the scan size: `0x8042` GridULength and `0x8043` GridVLength [m]. A channel's values are
//! its page's samples (uncompressed strips; integers or floats) times the default slot's
//! multiplier plus its offset, in its encoder unit; channels whose unit is not a length
//! (volts, newtons) are listed but are not heights.
//!
//! Sources: SurfaceTopography `IO/JPK.py` (the tags, the default slot's linear scaling)
//! and Gwyddion's `modules/file/jpkscan.c`. No sample file could be obtained (absent from
//! the stored snapshot of SurfaceTopography), so the reader is tested on files written
//! from this description.

use super::{ChannelInfo, Ctx, Decoded, Raw, Unit, Want, binary, check_spacing, checked_grid};
use super::{tiff, units};
use crate::ReadError;

/// JPK's `FileFormatVersion` tag: a TIFF carrying it is a JPK file.
pub(crate) const TAG_VERSION: u16 = 0x8000;
const TAG_CHANNEL: u16 = 0x8050;
const TAG_RETRACE: u16 = 0x8051;
const TAG_FANCY: u16 = 0x8052;
const TAG_DEFAULT_SLOT: u16 = 0x8081;
const TAG_GRID_U: u16 = 0x8042;
const TAG_GRID_V: u16 = 0x8043;
/// Pages read at most: a scan has tens of channels; a loop of directories ends here.
const MAX_PAGES: usize = 1024;
const CORRUPT: &str = "the JPK file is corrupt or truncated; export it again";

/// True for a TIFF carrying JPK's tags.
pub(crate) fn is_jpk(b: &[u8]) -> bool {
    tiff::Tiff::parse(b).is_ok_and(|t| t.get(TAG_VERSION).is_some())
}

struct Channel<'a> {
    page: tiff::Tiff<'a>,
    info: ChannelInfo,
    scale: (f64, f64),
}

/// Read a JPK image scan (multi-channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let err = |e: String| ctx.err("TIFF", e, CORRUPT);
    let (first, mut next) = tiff::Tiff::parse_at(bytes, None).map_err(err)?;
    if first.get(TAG_VERSION).is_none() {
        return Err(ctx.err(
            "tag 32768",
            "this TIFF carries no JPK tags",
            "not a JPK image scan",
        ));
    }
    let length = |tag: u16, name: &str| {
        first
            .double(tag)
            .ok_or_else(|| ctx.err(name, "missing from the first page", CORRUPT))
    };
    let (lu, lv) = (
        length(TAG_GRID_U, "GridULength")?,
        length(TAG_GRID_V, "GridVLength")?,
    );
    let mut channels: Vec<Channel<'_>> = Vec::new();
    let mut seen = vec![];
    while next != 0 && seen.len() < MAX_PAGES {
        if seen.contains(&next) {
            return Err(ctx.err("TIFF", "its directories form a loop", CORRUPT));
        }
        seen.push(next);
        let (page, after) = tiff::Tiff::parse_at(bytes, Some(next)).map_err(err)?;
        next = after;
        if page.get(TAG_CHANNEL).is_none() {
            continue;
        }
        let index = channels.len();
        let (name, unit, scale) = describe(&page);
        channels.push(Channel {
            info: ChannelInfo {
                index,
                name,
                is_height: units::length_factor(&unit).is_some(),
                unit,
                nx: page.uint(256).unwrap_or(0) as usize,
                ny: page.uint(257).unwrap_or(0) as usize,
            },
            page,
            scale,
        });
    }
    if channels.is_empty() {
        return Err(ctx.err(
            "tag 0x8050",
            "no page of the file is a channel",
            "export the scan's channels from the JPK software",
        ));
    }
    let list = channels.iter().map(|c| c.info.clone()).collect();
    Decoded::pick(ctx, want, list, |i, info| {
        let c = &channels[i];
        decode(ctx, bytes, c, info, (lu, lv))
    })
}

/// A channel page's name, the unit of its default slot and that slot's (multiplier, offset).
fn describe(page: &tiff::Tiff<'_>) -> (String, String, (f64, f64)) {
    let mut name = page
        .text(TAG_FANCY)
        .or_else(|| page.text(TAG_CHANNEL))
        .unwrap_or_else(|| "channel".into());
    if page.uint(TAG_RETRACE).is_some_and(|r| r != 0) {
        name.push_str(" (retrace)");
    }
    let default = page.text(TAG_DEFAULT_SLOT).unwrap_or_default();
    let slot = (0..32u16)
        .find(|i| page.text(0x8090 + 0x30 * i).is_some_and(|n| n == default))
        .unwrap_or(0);
    let at = |t: u16| t + 0x30 * slot;
    let unit = page.text(at(0x80A2)).unwrap_or_default();
    let linear = page
        .text(at(0x80A3))
        .is_none_or(|t| t.eq_ignore_ascii_case("LinearScaling"));
    let scale = if linear {
        (
            page.double(at(0x80A4)).unwrap_or(1.0),
            page.double(at(0x80A5)).unwrap_or(0.0),
        )
    } else {
        (f64::NAN, f64::NAN)
    };
    (name, unit, scale)
}

fn decode(
    ctx: Ctx<'_>,
    bytes: &[u8],
    c: &Channel<'_>,
    info: &ChannelInfo,
    (lu, lv): (f64, f64),
) -> Result<Raw, ReadError> {
    let p = &c.page;
    let z = units::length_factor(&info.unit).ok_or_else(|| {
        ctx.err(
            "EncoderUnit",
            format!(
                "channel `{}` is in `{}`, not a length",
                info.name, info.unit
            ),
            "choose a height channel with --channel",
        )
    })?;
    if !(c.scale.0.is_finite() && c.scale.0 != 0.0) {
        return Err(ctx.err(
            "ScalingType",
            "the default slot's scaling is not linear (or its multiplier is 0)",
            "export the channel with its nominal or calibrated scaling",
        ));
    }
    if p.uint(259).unwrap_or(1) != 1 || p.uint(277).unwrap_or(1) != 1 {
        return Err(ctx.err(
            "Compression",
            "the channel's page is compressed or has several samples per pixel",
            "export the scan uncompressed",
        ));
    }
    let bits = p.uint(258).unwrap_or(0);
    let format = p.uint(339).unwrap_or(1);
    let Some(kind) = binary::Sample::from_tiff(u64::from(format), u64::from(bits)) else {
        return Err(ctx.err(
            "BitsPerSample",
            format!("{bits}-bit samples of format {format}"),
            CORRUPT,
        ));
    };
    let (nx, ny) = (info.nx as u64, info.ny as u64);
    let offsets = p.uints(273).unwrap_or_default();
    let counts = p.uints(279).unwrap_or_default();
    if offsets.len() != counts.len() || offsets.is_empty() {
        return Err(ctx.err(
            "StripOffsets",
            "strip offsets and byte counts disagree",
            CORRUPT,
        ));
    }
    let total: u64 = counts.iter().fold(0u64, |a, c| a.saturating_add(*c));
    let n = checked_grid(
        ctx,
        "ImageWidth × ImageLength",
        nx,
        ny,
        kind.size() as u64,
        total,
    )?;
    let mut data = Vec::with_capacity(n * kind.size());
    for (&o, &len) in offsets.iter().zip(&counts) {
        let end = o.saturating_add(len);
        let strip = bytes.get(o as usize..end as usize).ok_or_else(|| {
            ctx.truncated("StripOffsets", "a strip", (o, end), bytes.len() as u64)
        })?;
        data.extend_from_slice(strip);
    }
    let raw = binary::decode(&data, kind, p.little, n)
        .ok_or_else(|| ctx.short("strips", (n * kind.size()) as u64, data.len() as u64))?;
    let (m, o) = c.scale;
    let heights = raw
        .into_iter()
        .map(|v| if v.is_finite() { v * m + o } else { f64::NAN })
        .collect();
    let dx = check_spacing(ctx, "GridULength", lu / nx as f64)?;
    let dy = check_spacing(ctx, "GridVLength", lv / ny as f64)?;
    Ok(
        Raw::si(nx as usize, ny as usize, dx, dy, heights, info.name.clone())
            .in_units(Unit::Known(z), Unit::Known(1.0))
            .spacing_from("GridULength", "GridVLength"),
    )
}
