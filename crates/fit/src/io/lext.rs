//! Olympus LEXT `.lext` (OLS4000, OLS5000 laser confocal microscopes): a TIFF whose pages
//! are the colour image, the laser intensity, the height map and a mask of invalid points,
//! each named by its page's `ImageDescription` (`HEIGHT` for the heights). The first
//! page's `ImageDescription` is XML, `<TiffTagDescData>`, whose `HeightInfo` element holds
//! `HeightDataPerPixelX`, `…Y`, `…Z` (picometres per pixel, per height count) and the unit
//! indices `HeightDataUnitX`, `…Y`, `…Z`; the first page's Exif directory (tag 34665) holds
//! in its `DeviceSettingDescription` (tag 41995) more XML, `<ExifTagDescData>`, whose
//! `ImageCommonSettingsInfo` gives the maker's calibration `MakerCalibrationValueX`,
//! `…Y`, `…Z` in millionths. A point's height is its count × `HeightDataPerPixelZ` ×
//! `MakerCalibrationValueZ` × 1e-18 m, the spacing likewise along x and y.
//!
//! x runs along the height page's rows, as in SurfaceTopography 1.27.1 (which transposes
//! the page). The mask page is not applied (neither SurfaceTopography nor Gwyddion apply
//! it). A file without the Exif calibration is read with the nominal scale (calibration 1,
//! as Gwyddion reads every file), and says so.
//!
//! Sources: SurfaceTopography `IO/LEXT.py` (the XML fields, the calibration product and
//! the 1e-12 factor towards micrometres), Gwyddion `modules/file/lextfile.c` (the page
//! titles, picometre units) and surfalize `file/lext.py` (the unit index 2 of micrometres).
//! No real sample file could be obtained (SurfaceTopography's `lext-1.lext` and
//! `lext-2.lext` are absent from the stored snapshot of its repository), so the reader is
//! tested on files written from this description: in `crates/fit/tests/lext_zon_datx.rs`,
//! and `data/surfaces/formats/lext-synth.lext` (written by `make_synthetic.py` there),
//! which SurfaceTopography 1.27.1 also reads (`data/surfaces/reference/statistics.json`).

use super::{Ctx, Decoded, Raw, Sniff, Want, binary, check_spacing, checked_grid, tiff};
use crate::ReadError;

/// What the first page's description starts its XML with.
const MAGIC: &str = "<TiffTagDescData";
const TAG_DESCRIPTION: u16 = 270;
const TAG_EXIF: u16 = 34665;
const TAG_DEVICE_SETTING: u16 = 41995;
/// Pages walked at most (a LEXT file has five or six); a loop of directories ends here.
const MAX_PAGES: usize = 64;
/// Picometres per count times millionths of calibration, in metres.
const SCALE: f64 = 1e-18;
/// The calibration of a file without one: 1 in millionths.
const NOMINAL: f64 = 1e6;
const CORRUPT: &str = "the LEXT file is corrupt or truncated; export it again";

/// `Magic` for a TIFF whose first page describes itself with LEXT's XML, `Maybe` for
/// another TIFF.
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    match tiff::Tiff::parse(b) {
        Ok(t) if description(&t).is_some_and(|d| d.contains(MAGIC)) => Sniff::Magic,
        _ if tiff::is_tiff(b) => Sniff::Maybe,
        _ => Sniff::No,
    }
}

/// A page's `ImageDescription`, whatever the type it is stored as.
fn description(page: &tiff::Tiff<'_>) -> Option<String> {
    let e = page.get(TAG_DESCRIPTION)?;
    let end = e
        .value
        .iter()
        .position(|&c| c == 0)
        .unwrap_or(e.value.len());
    Some(String::from_utf8_lossy(&e.value[..end]).trim().to_string())
}

/// The number in `<tag>…</tag>` inside the first element `parent` of `xml`.
fn xml_number(xml: &str, parent: &str, tag: &str) -> Option<f64> {
    let start = xml.find(&format!("<{parent}>"))?;
    let body = &xml[start..];
    let body = &body[..body.find(&format!("</{parent}>")).unwrap_or(body.len())];
    let open = body.find(&format!("<{tag}>"))? + tag.len() + 2;
    let close = body[open..].find(&format!("</{tag}>"))?;
    body[open..open + close].trim().parse().ok()
}

/// Read a LEXT file (its height page).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// The maker's calibration (x, y, z) from the Exif directory, in millionths.
fn calibration(bytes: &[u8], first: &tiff::Tiff<'_>) -> Option<[f64; 3]> {
    let at = first.uint(TAG_EXIF).or_else(|| {
        let e = first.get(TAG_EXIF).filter(|e| e.kind == 13)?;
        let c: [u8; 4] = e.value.get(..4)?.try_into().ok()?;
        Some(if first.little {
            u32::from_le_bytes(c)
        } else {
            u32::from_be_bytes(c)
        })
    })?;
    let (exif, _) = tiff::Tiff::parse_at(bytes, Some(at as usize)).ok()?;
    let xml = String::from_utf8_lossy(exif.get(TAG_DEVICE_SETTING)?.value);
    let get = |t: &str| xml_number(&xml, "ImageCommonSettingsInfo", t);
    Some([
        get("MakerCalibrationValueX")?,
        get("MakerCalibrationValueY")?,
        get("MakerCalibrationValueZ")?,
    ])
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let err = |e: String| ctx.err("TIFF", e, CORRUPT);
    let (first, mut next) = tiff::Tiff::parse_at(bytes, None).map_err(err)?;
    let xml = description(&first)
        .filter(|d| d.contains(MAGIC))
        .ok_or_else(|| {
            ctx.err(
                "ImageDescription",
                "the first page carries no `<TiffTagDescData>` XML",
                "not an Olympus LEXT file (or its first page was rewritten by another program)",
            )
        })?;
    let info = |t: &str| {
        xml_number(&xml, "HeightInfo", t).ok_or_else(|| {
            ctx.err(
                &format!("HeightInfo/{t}"),
                "missing or not a number",
                CORRUPT,
            )
        })
    };
    let per_pixel = [
        info("HeightDataPerPixelX")?,
        info("HeightDataPerPixelY")?,
        info("HeightDataPerPixelZ")?,
    ];
    let unit = |t: &str| xml_number(&xml, "HeightInfo", t);
    let (ux, uy, uz) = (
        unit("HeightDataUnitX"),
        unit("HeightDataUnitY"),
        unit("HeightDataUnitZ"),
    );
    if ux != uz || uy != uz {
        return Err(ctx.err(
            "HeightInfo/HeightDataUnitX, Y, Z",
            format!("the unit indices differ ({ux:?}, {uy:?}, {uz:?}), so the scale is unknown"),
            CORRUPT,
        ));
    }
    let (cal, nominal) = match calibration(bytes, &first) {
        Some(c) => (c, false),
        None => ([NOMINAL; 3], true),
    };
    let mut seen = vec![];
    let height = loop {
        if next == 0 || seen.len() >= MAX_PAGES {
            return Err(ctx.err(
                "ImageDescription",
                "no page of the file is described as `HEIGHT`",
                "the file holds no height map (an image-only export); save the measurement \
                 with its heights",
            ));
        }
        if seen.contains(&next) {
            return Err(ctx.err("TIFF", "its directories form a loop", CORRUPT));
        }
        seen.push(next);
        let (page, after) = tiff::Tiff::parse_at(bytes, Some(next)).map_err(err)?;
        next = after;
        if description(&page).is_some_and(|d| d.eq_ignore_ascii_case("HEIGHT")) {
            break page;
        }
    };
    let (nx, ny, counts) = samples(ctx, bytes, &height)?;
    let factor = |i: usize| per_pixel[i] * cal[i] * SCALE;
    let dx = check_spacing(ctx, "HeightDataPerPixelX", factor(0))?;
    let dy = check_spacing(ctx, "HeightDataPerPixelY", factor(1))?;
    let z = factor(2);
    if !(z.is_finite() && z != 0.0) {
        return Err(ctx.err(
            "HeightDataPerPixelZ",
            format!("height scale {z:e} m per count is not usable"),
            CORRUPT,
        ));
    }
    let heights = counts.into_iter().map(|c| c * z).collect();
    let mut raw = Raw::si(nx, ny, dx, dy, heights, "height").spacing_from(
        "HeightInfo/HeightDataPerPixelX",
        "HeightInfo/HeightDataPerPixelY",
    );
    if nominal {
        raw.notes.push(
            "the file carries no maker calibration (Exif MakerCalibrationValue): its \
             nominal scale is used"
                .into(),
        );
    }
    Ok(raw)
}

/// The samples of an uncompressed, single-sample page: `(width, length, values)`.
fn samples(
    ctx: Ctx<'_>,
    bytes: &[u8],
    p: &tiff::Tiff<'_>,
) -> Result<(usize, usize, Vec<f64>), ReadError> {
    if p.uint(259).unwrap_or(1) != 1 || p.uint(277).unwrap_or(1) != 1 {
        return Err(ctx.err(
            "Compression",
            "the height page is compressed or has several samples per pixel",
            "export the measurement again from the LEXT software",
        ));
    }
    let (format, bits) = (p.uint(339).unwrap_or(1), p.uint(258).unwrap_or(0));
    let Some(kind) = binary::Sample::from_tiff(u64::from(format), u64::from(bits)) else {
        return Err(ctx.err(
            "BitsPerSample",
            format!("{bits}-bit samples of format {format}"),
            CORRUPT,
        ));
    };
    let nx = u64::from(p.uint(256).unwrap_or(0));
    let ny = u64::from(p.uint(257).unwrap_or(0));
    let offsets = p.uints(273).unwrap_or_default();
    let counts = p.uints(279).unwrap_or_default();
    if offsets.len() != counts.len() || offsets.is_empty() {
        return Err(ctx.err(
            "StripOffsets",
            "the height page's strip offsets and byte counts disagree",
            CORRUPT,
        ));
    }
    let total = counts.iter().fold(0u64, |a, c| a.saturating_add(*c));
    let size = kind.size() as u64;
    let n = checked_grid(ctx, "ImageWidth × ImageLength", nx, ny, size, total)?;
    let mut data = Vec::with_capacity(n * kind.size());
    for (&o, &len) in offsets.iter().zip(&counts) {
        let end = o.saturating_add(len);
        let strip = bytes.get(o as usize..end as usize).ok_or_else(|| {
            ctx.truncated("StripOffsets", "a strip", (o, end), bytes.len() as u64)
        })?;
        data.extend_from_slice(strip);
    }
    let values = binary::decode(&data, kind, p.little, n)
        .ok_or_else(|| ctx.short("strips", n as u64 * size, data.len() as u64))?;
    Ok((nx as usize, ny as usize, values))
}
