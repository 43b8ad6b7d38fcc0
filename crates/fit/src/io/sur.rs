//! Digital Surf `.sur` (MountainsMap): a 512-byte little-endian header per object
//! ("DIGITAL SURF", object type, point size 16 or 32 bits, zmin/zmax, points per line,
//! lines, x/y spacing and z step as float32, nine 16-byte axis names and units, unit
//! ratios, comment and private-zone sizes, offsets), the comment and private zones, then
//! int16/int32 data, x fastest. Heights are `raw × z step` in the z unit. When the
//! header flags special points, values outside `[zmin, zmax]` are points that were not
//! measured. `DSCOMPRESSED` files hold the same layout with zlib-compressed data.

use super::binary::{Cursor, Sample};
use super::{Ctx, Decoded, Raw, Want, check_spacing, checked_grid, units};
use crate::ReadError;
use std::borrow::Cow;
use std::io::Read;

const HEADER: usize = 512;

/// The fields of the first object's header this reader uses.
struct Header {
    nobjects: u16,
    /// Whether values outside `[zmin, zmax]` mark points that were not measured.
    special_points: bool,
    kind: Sample,
    zmin: i32,
    zmax: i32,
    nx: i32,
    ny: i32,
    total: u32,
    /// x, y spacing and z step, each in its step unit.
    steps: (f64, f64, f64),
    /// Axis x, y, z; step units x, y, z; length units x, y, z.
    names: Vec<String>,
    compressed_size: u32,
    /// Bytes of the comment and private zones before the data.
    zones: usize,
}

/// Read a Digital Surf file (first object).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let h = header(ctx, bytes)?;
    let (nx, ny, kind) = (h.nx, h.ny, h.kind);
    let start = HEADER + h.zones;
    let body = bytes.get(start..).ok_or_else(|| {
        ctx.short(
            "comment and private zones",
            start as u64,
            bytes.len() as u64,
        )
    })?;
    let data: Cow<'_, [u8]> = if bytes.starts_with(b"DSCOMPRESSED") {
        Cow::Owned(inflate(ctx, body, &h)?)
    } else {
        Cow::Borrowed(body)
    };
    let n = checked_grid(
        ctx,
        "number of points × lines",
        nx as u64,
        ny as u64,
        kind.size() as u64,
        data.len() as u64,
    )?;
    let raw = super::binary::decode(&data, kind, true, n)
        .ok_or_else(|| ctx.short("data", (n * kind.size()) as u64, data.len() as u64))?;
    let unit = |i: usize, what: &str| -> Result<f64, ReadError> {
        let u = h.names[i].trim();
        units::length_factor(u).ok_or_else(|| {
            ctx.err(
                what,
                format!("`{u}` is not a length unit"),
                "export a topography (lengths in m, mm, µm or nm)",
            )
        })
    };
    let (ux, uy, uz) = (
        unit(3, "x step unit")?,
        unit(4, "y step unit")?,
        unit(5, "z step unit")?,
    );
    let (sx, sy, sz) = h.steps;
    let dx = check_spacing(ctx, "x spacing", sx * ux)?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(ctx, "y spacing", sy * uy)?
    };
    let q = sz * uz;
    let mut invalid = 0usize;
    let heights = raw
        .into_iter()
        .map(|v| {
            if h.special_points && (v < h.zmin as f64 || v > h.zmax as f64) {
                invalid += 1;
                f64::NAN
            } else {
                v * q
            }
        })
        .collect();
    let mut out = Raw::si(nx as usize, ny as usize, dx, dy, heights, &h.names[2])
        .spacing_from("x spacing", "y spacing");
    if invalid > 0 {
        out.notes
            .push(format!("{invalid} points were not measured"));
    }
    if h.nobjects > 1 {
        out.notes.push(format!(
            "the file holds {} objects; the first was read",
            h.nobjects
        ));
    }
    Decoded::single(ctx, want, out)
}

/// The 512-byte header, refusing objects that are not a profile or surface of 16- or
/// 32-bit points on a positive grid.
fn header(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Header, ReadError> {
    if bytes.len() < HEADER {
        return Err(ctx.short("header", HEADER as u64, bytes.len() as u64));
    }
    let short = || ctx.short("header", HEADER as u64, bytes.len() as u64);
    let mut c = Cursor::le(bytes, 12);
    let _format = c.u16().ok_or_else(short)?;
    let nobjects = c.u16().ok_or_else(short)?;
    let _version = c.u16().ok_or_else(short)?;
    let object_type = c.u16().ok_or_else(short)?;
    c.skip(60).ok_or_else(short)?; // object and operator names
    let _material = c.u16().ok_or_else(short)?;
    let _acquisition = c.u16().ok_or_else(short)?;
    let _range = c.u16().ok_or_else(short)?;
    let special_points = c.u16().ok_or_else(short)?;
    let _absolute = c.u16().ok_or_else(short)?;
    c.skip(8).ok_or_else(short)?;
    let bits = c.u16().ok_or_else(short)?;
    let zmin = c.i32().ok_or_else(short)?;
    let zmax = c.i32().ok_or_else(short)?;
    let nx = c.i32().ok_or_else(short)?;
    let ny = c.i32().ok_or_else(short)?;
    let total = c.u32().ok_or_else(short)?;
    let sx = c.f32().ok_or_else(short)?;
    let sy = c.f32().ok_or_else(short)?;
    let sz = c.f32().ok_or_else(short)?;
    let mut names = Vec::new();
    for _ in 0..9 {
        names.push(c.text(16).ok_or_else(short)?);
    }
    c.skip(12 + 6 + 12).ok_or_else(short)?; // unit ratios, imprint/inversion/levelling, obsolete
    c.skip(14 + 4).ok_or_else(short)?; // date, duration
    let compressed_size = c.u32().ok_or_else(short)?;
    c.skip(6).ok_or_else(short)?;
    let comment = c.u16().ok_or_else(short)? as usize;
    let private = c.u16().ok_or_else(short)? as usize;
    if !(object_type == 1 || object_type == 2) {
        return Err(ctx.err(
            "object type",
            format!("object type {object_type} is not a profile (1) or surface (2)"),
            "export the topography as a single surface from MountainsMap",
        ));
    }
    let kind = match bits {
        16 => Sample::I16,
        32 => Sample::I32,
        b => {
            return Err(ctx.err(
                "size of points",
                format!("{b}-bit points are not supported"),
                "expected 16 or 32",
            ));
        }
    };
    if nx <= 0 || ny <= 0 {
        return Err(ctx.err(
            "number of points",
            format!("grid {nx} × {ny} is not positive"),
            "the header is corrupt",
        ));
    }
    if total as u64 != nx as u64 * ny as u64 {
        return Err(ctx.err(
            "total number of points",
            format!("{total} ≠ {nx} × {ny}"),
            "the header is corrupt",
        ));
    }
    Ok(Header {
        nobjects,
        special_points: special_points != 0,
        kind,
        zmin,
        zmax,
        nx,
        ny,
        total,
        steps: (sx, sy, sz),
        names,
        compressed_size,
        zones: comment + private,
    })
}

/// The zlib-compressed data of a `DSCOMPRESSED` file, refusing a claimed size the
/// compressed bytes cannot hold before allocating it.
fn inflate(ctx: Ctx<'_>, body: &[u8], h: &Header) -> Result<Vec<u8>, ReadError> {
    let cs = (h.compressed_size as usize).min(body.len());
    let need = (h.total as u64).saturating_mul(h.kind.size() as u64);
    if need > (cs as u64).saturating_mul(1100).saturating_add(4096) {
        return Err(ctx.short("compressed data", need, cs as u64));
    }
    let mut out = Vec::with_capacity((need as usize).min(cs.saturating_mul(16)));
    flate2::read::ZlibDecoder::new(&body[..cs])
        .take(need)
        .read_to_end(&mut out)
        .map_err(|e| {
            ctx.err(
                "compressed data",
                format!("cannot decompress ({e})"),
                "the file is corrupt",
            )
        })?;
    Ok(out)
}
