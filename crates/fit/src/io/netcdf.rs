//! NetCDF classic and 64-bit-offset files (`CDF\x01`, `CDF\x02`), the container
//! SurfaceTopography writes: a variable `heights(x, y)` (or `heights(x)` for a profile),
//! coordinate variables `x`, `y` whose attribute `length` is the physical size and `unit`
//! its unit, and an optional `mask` variable (non-zero where a point is invalid).
//! `_FillValue` / `missing_value` points are invalid; `scale_factor` and `add_offset`
//! are applied. The first index is x, so in the file y runs fastest and the map is
//! transposed to this crate's x-fastest layout.
//!
//! Not read: NetCDF-4 files (an HDF5 container, refused naming that), CDF-5 (`CDF\x05`)
//! and non-uniform profiles (a dimension `n` with x positions).
//!
//! Sources: the NetCDF classic format specification (Unidata, "The NetCDF Classic Format
//! Specification"), and SurfaceTopography's `IO/NC.py` for its variable names.

use super::{Ctx, Decoded, Raw, Unit, Want, binary, check_spacing, checked_grid, units};
use crate::ReadError;

/// What every classic (version 1) and 64-bit-offset (version 2) file starts with.
pub(crate) fn is_classic(bytes: &[u8]) -> bool {
    bytes.starts_with(b"CDF\x01") || bytes.starts_with(b"CDF\x02")
}

/// Read a NetCDF file (one channel, `heights`).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

const CORRUPT: &str = "the NetCDF header is corrupt; write the file again";
/// Most dimensions, attributes or variables a header may declare: far beyond any
/// topography file, and it bounds what a corrupt count can make the reader allocate.
const MAX_ITEMS: u32 = 4096;

#[derive(Debug, Clone)]
enum Value {
    Text(String),
    Numbers(Vec<f64>),
}

impl Value {
    fn number(&self) -> Option<f64> {
        match self {
            Value::Numbers(v) => v.first().copied(),
            Value::Text(t) => t.trim().parse().ok(),
        }
    }
    fn text(&self) -> Option<&str> {
        match self {
            Value::Text(t) => Some(t.trim_end_matches('\0').trim()),
            Value::Numbers(_) => None,
        }
    }
}

struct Var {
    name: String,
    dims: Vec<usize>,
    attrs: Vec<(String, Value)>,
    kind: u32,
    begin: u64,
}

impl Var {
    fn attr(&self, name: &str) -> Option<&Value> {
        self.attrs.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }
}

struct Header {
    dims: Vec<(String, u64)>,
    vars: Vec<Var>,
}

struct Parser<'a> {
    ctx: Ctx<'a>,
    c: binary::Cursor<'a>,
    offset64: bool,
}

impl Parser<'_> {
    fn short(&self, what: &str) -> ReadError {
        self.ctx.err(
            what,
            format!("the header ends at byte {} inside {what}", self.c.pos),
            "the file is truncated: re-copy or write it again",
        )
    }
    fn u32(&mut self, what: &str) -> Result<u32, ReadError> {
        self.c.u32().ok_or_else(|| self.short(what))
    }
    fn count(&mut self, what: &str) -> Result<u32, ReadError> {
        let n = self.u32(what)?;
        if n > MAX_ITEMS {
            return Err(self.ctx.err(
                what,
                format!("{n} entries, more than the {MAX_ITEMS} accepted"),
                CORRUPT,
            ));
        }
        Ok(n)
    }
    fn padded(&mut self, len: u64, what: &str) -> Result<&[u8], ReadError> {
        let padded = len.div_ceil(4) * 4;
        let n = usize::try_from(padded).map_err(|_| self.short(what))?;
        let b = self.c.bytes(n).ok_or_else(|| self.short(what))?;
        Ok(&b[..len as usize])
    }
    fn name(&mut self, what: &str) -> Result<String, ReadError> {
        let n = self.u32(what)?;
        Ok(String::from_utf8_lossy(self.padded(u64::from(n), what)?).into_owned())
    }
    /// A list's tag and count: `ABSENT` (two zeros) gives 0.
    fn list(&mut self, tag: u32, what: &str) -> Result<u32, ReadError> {
        let t = self.u32(what)?;
        let n = self.count(what)?;
        if t == 0 && n == 0 {
            return Ok(0);
        }
        if t != tag {
            return Err(self.ctx.err(
                what,
                format!("list tag {t:#x} where {tag:#x} belongs"),
                CORRUPT,
            ));
        }
        Ok(n)
    }
    fn attrs(&mut self, what: &str) -> Result<Vec<(String, Value)>, ReadError> {
        let n = self.list(0x0C, what)?;
        let mut out = Vec::new();
        for _ in 0..n {
            let name = self.name(what)?;
            let kind = self.u32(what)?;
            let count = u64::from(self.u32(what)?);
            let size = type_size(kind).ok_or_else(|| {
                self.ctx.err(
                    &format!("{what} `{name}`"),
                    format!("unknown type {kind}"),
                    CORRUPT,
                )
            })?;
            let raw = self.padded(count * size as u64, what)?;
            let value = if kind == 2 {
                Value::Text(String::from_utf8_lossy(raw).into_owned())
            } else {
                Value::Numbers(decode(raw, kind, count as usize).unwrap_or_default())
            };
            out.push((name, value));
        }
        Ok(out)
    }
}

/// Bytes of one value of a NetCDF classic type.
fn type_size(kind: u32) -> Option<usize> {
    match kind {
        1 | 2 => Some(1),
        3 => Some(2),
        4 | 5 => Some(4),
        6 => Some(8),
        _ => None,
    }
}

fn sample(kind: u32) -> Option<binary::Sample> {
    match kind {
        1 => Some(binary::Sample::I8),
        3 => Some(binary::Sample::I16),
        4 => Some(binary::Sample::I32),
        5 => Some(binary::Sample::F32),
        6 => Some(binary::Sample::F64),
        _ => None,
    }
}

fn decode(raw: &[u8], kind: u32, count: usize) -> Option<Vec<f64>> {
    binary::decode(raw, sample(kind)?, false, count)
}

fn header(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Header, ReadError> {
    let offset64 = bytes.get(3) == Some(&2);
    let mut p = Parser {
        ctx,
        c: binary::Cursor::be(bytes, 4),
        offset64,
    };
    let _numrecs = p.u32("numrecs")?;
    let ndims = p.list(0x0A, "dimensions")?;
    let mut dims = Vec::new();
    for _ in 0..ndims {
        let name = p.name("dimensions")?;
        let len = u64::from(p.u32("dimensions")?);
        dims.push((name, len));
    }
    p.attrs("global attributes")?;
    let nvars = p.list(0x0B, "variables")?;
    let mut vars = Vec::new();
    for _ in 0..nvars {
        let name = p.name("variables")?;
        let nd = p.count("variables")?;
        let mut ids = Vec::new();
        for _ in 0..nd {
            let id = p.u32("variables")? as usize;
            if id >= dims.len() {
                return Err(ctx.err(
                    &format!("variable `{name}`"),
                    format!("dimension id {id} of {} declared", dims.len()),
                    CORRUPT,
                ));
            }
            ids.push(id);
        }
        let attrs = p.attrs(&format!("attributes of `{name}`"))?;
        let kind = p.u32("variables")?;
        let _vsize = p.u32("variables")?;
        let begin = if p.offset64 {
            p.c.u64().ok_or_else(|| p.short("variables"))?
        } else {
            u64::from(p.u32("variables")?)
        };
        vars.push(Var {
            name,
            dims: ids,
            attrs,
            kind,
            begin,
        });
    }
    Ok(Header { dims, vars })
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if bytes.starts_with(b"CDF\x05") {
        return Err(ctx.err(
            "magic",
            "a CDF-5 (64-bit data) NetCDF file, which is not read yet",
            "write it as NetCDF classic or 64-bit offset (format NETCDF3_CLASSIC or \
             NETCDF3_64BIT_OFFSET)",
        ));
    }
    if !is_classic(bytes) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `CDF\\x01` or `CDF\\x02`",
            "not a NetCDF classic file",
        ));
    }
    let h = header(ctx, bytes)?;
    let var = |name: &str| h.vars.iter().find(|v| v.name == name);
    let heights = var("heights").ok_or_else(|| {
        let names: Vec<&str> = h.vars.iter().map(|v| v.name.as_str()).collect();
        ctx.err(
            "heights",
            format!("no variable `heights` (variables: {})", names.join(", ")),
            "SurfaceTopography's NetCDF files hold the map in `heights`; write it there",
        )
    })?;
    if h.dims.iter().any(|(n, _)| n == "n") {
        return Err(ctx.err(
            "n",
            "a non-uniform profile (x positions in a dimension `n`), which is not read yet",
            "export the profile on a uniform grid, or as x z columns of text",
        ));
    }
    let shape: Vec<u64> = heights.dims.iter().map(|&d| h.dims[d].1).collect();
    let (nx, ny) = match shape[..] {
        [n] => (n, 1),
        [a, b] => (a, b),
        _ => {
            return Err(ctx.err(
                "heights",
                format!("{} dimensions", shape.len()),
                "write a 2-D map heights(x, y) or a profile heights(x)",
            ));
        }
    };
    if shape.contains(&0) {
        return Err(ctx.err(
            "heights",
            "it uses the unlimited (record) dimension, which is not read yet",
            "write the map with fixed dimensions",
        ));
    }
    let values = variable(ctx, bytes, heights, nx, ny)?;
    let mask = match var("mask") {
        Some(m) => Some(variable(ctx, bytes, m, nx, ny)?),
        None => None,
    };
    let fill: Vec<f64> = ["_FillValue", "missing_value"]
        .iter()
        .filter_map(|a| heights.attr(a).and_then(Value::number))
        .collect();
    let scale = heights
        .attr("scale_factor")
        .and_then(Value::number)
        .unwrap_or(1.0);
    let offset = heights
        .attr("add_offset")
        .and_then(Value::number)
        .unwrap_or(0.0);
    let (nxu, nyu) = (nx as usize, ny as usize);
    let n = nxu * nyu;
    let mut z = Vec::with_capacity(n);
    for k in 0..n {
        // File index: x slowest.
        let f = if nyu == 1 {
            k
        } else {
            (k % nxu) * nyu + k / nxu
        };
        let v = values[f];
        let masked = mask.as_ref().is_some_and(|m| m[f] != 0.0);
        z.push(if masked || !v.is_finite() || fill.contains(&v) {
            f64::NAN
        } else {
            v * scale + offset
        });
    }
    let unit_of = |v: Option<&Var>| -> Result<Option<f64>, ReadError> {
        match v.and_then(|v| v.attr("unit")).and_then(Value::text) {
            None | Some("") => Ok(None),
            Some(u) => units::length_factor(u).map(Some).ok_or_else(|| {
                ctx.err(
                    "unit",
                    format!("`{u}` is not a length unit"),
                    "the unit attribute must name a length (m, µm, nm)",
                )
            }),
        }
    };
    let lateral = unit_of(var("x"))?;
    let height = unit_of(Some(heights))?.or(lateral);
    let length = |name: &str| {
        var(name)
            .and_then(|v| v.attr("length"))
            .and_then(Value::number)
    };
    let spacing = match (length("x"), ny) {
        (Some(lx), 1) => {
            let d = check_spacing(ctx, "x:length", lx / nx as f64)?;
            Some((d, d))
        }
        (Some(lx), _) => match length("y") {
            Some(ly) => Some((
                check_spacing(ctx, "x:length", lx / nx as f64)?,
                check_spacing(ctx, "y:length", ly / ny as f64)?,
            )),
            None => None,
        },
        (None, _) => None,
    };
    let known = |f: Option<f64>| f.map_or(Unit::Unknown, Unit::Known);
    let mut raw = Raw::si(nxu, nyu, 1.0, 1.0, z, "heights")
        .in_units(known(height), known(lateral))
        .spacing_from("x:length", "y:length");
    raw.spacing = spacing;
    Ok(raw)
}

/// The values of a fixed-size variable over the `nx × ny` grid, checked against the file.
fn variable(ctx: Ctx<'_>, bytes: &[u8], v: &Var, nx: u64, ny: u64) -> Result<Vec<f64>, ReadError> {
    let kind = sample(v.kind).ok_or_else(|| {
        ctx.err(
            &v.name,
            format!("type {} is not a number type", v.kind),
            "store heights as numbers (double, float or integers)",
        )
    })?;
    let start = v.begin;
    let data = bytes.get(start as usize..).unwrap_or(&[]);
    let size = kind.size() as u64;
    let n = checked_grid(ctx, &v.name, nx, ny, 0, 0)?;
    let need = n as u64 * size;
    if need > data.len() as u64 {
        return Err(ctx.truncated(
            &v.name,
            &format!("variable `{}`", v.name),
            (start, start.saturating_add(need)),
            bytes.len() as u64,
        ));
    }
    binary::decode(data, kind, false, n)
        .ok_or_else(|| ctx.short(&v.name, n as u64 * size, data.len() as u64))
}
