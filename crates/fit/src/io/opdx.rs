//! Bruker Dektak XT `.opdx` (Vision64), the binary behind the Dektak text export: the
//! magic `VCA DATA\x01\x00\x00\x55`, then a tree of typed items (a name of `u32` length
//! and bytes, a type byte, the value). Containers nest items up to a terminator (`0x7F`)
//! and two bytes; quantities carry a value with a unit symbol; the data are a double array
//! (a profile, `/1D_Data/<channel>/Array`) or a float32 matrix (a map,
//! `/2D_Data/<channel>/Matrix`, x fastest). `/MetaData/DataKind` says which:
//! "Surface Profile" (the first channel of `/MetaData/1D_Channels/Height`; `Extent` spans
//! first to last point, as the text export's x column shows) or "Surface Height" (`/MetaData/PrimaryData2D`, grid in `Dimension2Points`
//! × `Dimension1Points`, sizes in `Dimension2Extent`, `Dimension1Extent`). Heights are
//! the stored values times `DataScale`, in its unit.
//!
//! Sources: SurfaceTopography `IO/OPDx.py` and Gwyddion's `modules/file/dektakvca.c`
//! (the item types); SurfaceTopography's sample `opdx-3.opdx` with its text export.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, units};
use crate::ReadError;
use std::collections::HashMap;

/// What every OPDx file starts with.
pub(crate) const MAGIC: &[u8] = b"VCA DATA\x01\x00\x00\x55";
/// Containers nest no deeper than this in any file seen; deeper is corruption.
const MAX_DEPTH: usize = 32;
/// At most this many items: bounds the manifest a corrupt file can make.
const MAX_ITEMS: usize = 1 << 16;
const CORRUPT: &str = "the OPDx file is corrupt; re-export it from Vision64";

#[derive(Debug, Clone)]
enum Item {
    Int(i64),
    Float(f64),
    Text(String),
    List(Vec<String>),
    Quantity {
        value: f64,
        symbol: String,
    },
    /// A double array or a matrix: where its values start, their byte length and, for a
    /// matrix, its (x, y) size.
    Data {
        start: usize,
        len: usize,
        grid: Option<(u64, u64)>,
    },
}

struct Tree<'a> {
    ctx: Ctx<'a>,
    b: &'a [u8],
    pos: usize,
    items: HashMap<String, Item>,
}

impl Tree<'_> {
    fn corrupt(&self, what: &str) -> ReadError {
        self.ctx.err(
            what,
            format!(
                "the item tree breaks off at byte {} of {}",
                self.pos,
                self.b.len()
            ),
            CORRUPT,
        )
    }
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], ReadError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.b.len());
        let Some(end) = end else {
            return Err(self.corrupt(what));
        };
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn uint(&mut self, n: usize, what: &str) -> Result<u64, ReadError> {
        let s = self.take(n, what)?;
        Ok(s.iter().rev().fold(0u64, |a, &b| (a << 8) | u64::from(b)))
    }
    fn f64(&mut self, what: &str) -> Result<f64, ReadError> {
        Ok(f64::from_bits(self.uint(8, what)?))
    }
    fn name(&mut self, what: &str) -> Result<String, ReadError> {
        let n = self.uint(4, what)? as usize;
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }
    fn varlen(&mut self, what: &str) -> Result<usize, ReadError> {
        match self.uint(1, what)? {
            w @ (1 | 2 | 4) => Ok(self.uint(w as usize, what)? as usize),
            w => Err(self.ctx.err(
                what,
                format!("a length of {w} bytes at byte {}", self.pos),
                CORRUPT,
            )),
        }
    }
    /// The end of a block of `len` bytes starting here, checked against the file.
    fn end_of(&self, len: usize, what: &str) -> Result<usize, ReadError> {
        self.pos
            .checked_add(len)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| {
                self.ctx.truncated(
                    what,
                    what,
                    (self.pos as u64, self.pos as u64 + len as u64),
                    self.b.len() as u64,
                )
            })
    }

    /// Read one item under `prefix`; `false` at a terminator.
    fn item(&mut self, prefix: &str, depth: usize) -> Result<bool, ReadError> {
        if depth > MAX_DEPTH || self.items.len() > MAX_ITEMS {
            return Err(self.ctx.err(
                prefix,
                "the item tree is nested too deep or too large",
                CORRUPT,
            ));
        }
        if self.pos >= self.b.len() {
            return Ok(false);
        }
        let name = self.name(prefix)?;
        let path = format!("{prefix}/{name}");
        let kind = self.uint(1, &path)?;
        let value = match kind {
            0x7F => return Ok(false),
            0x7D | 0x46 | 0x47 => {
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                while self.pos < end && self.item(&path, depth + 1)? {}
                self.pos = end;
                return Ok(true);
            }
            0x01 => Item::Int(self.uint(1, &path)? as i64),
            0x04 => Item::Int(self.uint(2, &path)? as i16 as i64),
            0x05 => Item::Int(self.uint(2, &path)? as i64),
            0x06 => Item::Int(self.uint(4, &path)? as i32 as i64),
            0x07 => Item::Int(self.uint(4, &path)? as i64),
            0x0A | 0x0B => Item::Int(self.uint(8, &path)? as i64),
            0x0C => Item::Float(f32::from_bits(self.uint(4, &path)? as u32) as f64),
            0x0D => Item::Float(self.f64(&path)?),
            0x0E => {
                self.name(&path)?;
                let len = self.varlen(&path)?;
                self.take(len, &path)?;
                return Ok(true);
            }
            0x12 => {
                let len = self.varlen(&path)?;
                Item::Text(String::from_utf8_lossy(self.take(len, &path)?).into_owned())
            }
            0x13 => {
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                let value = self.f64(&path)?;
                self.name(&path)?;
                let symbol = self.name(&path)?;
                self.pos = end;
                Item::Quantity { value, symbol }
            }
            0x15 => {
                self.take(9, &path)?;
                return Ok(true);
            }
            0x18 => {
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                self.name(&path)?;
                let symbol = self.name(&path)?;
                let value = self.f64(&path)?;
                self.pos = end;
                Item::Quantity { value, symbol }
            }
            0x40 | 0x7C => {
                self.name(&path)?;
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                let item = Item::Data {
                    start: self.pos,
                    len,
                    grid: None,
                };
                self.pos = end;
                item
            }
            0x42 => {
                self.name(&path)?;
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                let mut list = Vec::new();
                while self.pos < end {
                    list.push(self.name(&path)?);
                }
                Item::List(list)
            }
            0x00 => {
                self.name(&path)?;
                self.uint(4, &path)?;
                self.name(&path)?;
                let len = self.varlen(&path)?;
                let end = self.end_of(len, &path)?;
                let yres = self.uint(4, &path)?;
                let xres = self.uint(4, &path)?;
                let item = Item::Data {
                    start: self.pos,
                    len: end.saturating_sub(self.pos),
                    grid: Some((xres, yres)),
                };
                self.pos = end;
                item
            }
            t => {
                return Err(self.ctx.err(
                    &path,
                    format!("unknown item type {t:#04x} at byte {}", self.pos),
                    CORRUPT,
                ));
            }
        };
        self.items.insert(path, value);
        Ok(true)
    }
}

/// Read an OPDx file (its primary height channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `VCA DATA`",
            "not an OPDx file",
        ));
    }
    let mut t = Tree {
        ctx,
        b: bytes,
        pos: MAGIC.len(),
        items: HashMap::new(),
    };
    while t.item("", 0)? {}
    let items = t.items;
    let get = |k: &str| {
        items
            .get(k)
            .ok_or_else(|| ctx.err(k, "missing from the file", CORRUPT))
    };
    let text = |k: &str| match get(k)? {
        Item::Text(s) => Ok(s.clone()),
        Item::List(l) if !l.is_empty() => Ok(l[0].clone()),
        _ => Err(ctx.err(k, "not a text", CORRUPT)),
    };
    let quantity = |k: &str| match get(k)? {
        Item::Quantity { value, symbol } => {
            let f = units::length_factor(symbol).ok_or_else(|| {
                ctx.err(
                    k,
                    format!("`{symbol}` is not a length unit"),
                    "export a height channel",
                )
            })?;
            Ok(value * f)
        }
        _ => Err(ctx.err(k, "not a quantity", CORRUPT)),
    };
    let count = |k: &str| match get(k)? {
        Item::Int(n) if *n > 0 => Ok(*n as u64),
        Item::Float(f) if *f >= 1.0 => Ok(*f as u64),
        _ => Err(ctx.err(k, "not a positive count", CORRUPT)),
    };
    let kind = text("/MetaData/DataKind")?;
    match kind.as_str() {
        "Surface Profile" => {
            let channel = text("/MetaData/1D_Channels/Height")?;
            let p = format!("/1D_Data/{channel}");
            let n = count(&format!("{p}/NumPoints"))?;
            let length = quantity(&format!("{p}/Extent"))?;
            let scale = quantity(&format!("{p}/DataScale"))?;
            let Item::Data { start, len, .. } = get(&format!("{p}/Array"))? else {
                return Err(ctx.err(&format!("{p}/Array"), "not a data array", CORRUPT));
            };
            // The array's first 5 bytes precede its values.
            let data = bytes.get(start + 5..start + len).unwrap_or(&[]);
            let n = checked_grid(ctx, &format!("{p}/NumPoints"), n, 1, 8, data.len() as u64)?;
            let z = binary::decode(data, binary::Sample::F64, true, n)
                .ok_or_else(|| ctx.short(&p, n as u64 * 8, data.len() as u64))?;
            // The extent spans first to last point (the text export's x column ends there).
            let dx = check_spacing(ctx, &format!("{p}/Extent"), length / (n.max(2) - 1) as f64)?;
            let heights = z
                .into_iter()
                .map(|v| if v.is_finite() { v * scale } else { f64::NAN })
                .collect();
            Ok(Raw::si(n, 1, dx, dx, heights, channel)
                .spacing_from(format!("{p}/Extent"), format!("{p}/Extent")))
        }
        "Surface Height" => {
            let channel = text("/MetaData/PrimaryData2D")?;
            let p = format!("/2D_Data/{channel}");
            let ny = count(&format!("{p}/Dimension1Points"))?;
            let nx = count(&format!("{p}/Dimension2Points"))?;
            let ly = quantity(&format!("{p}/Dimension1Extent"))?;
            let lx = quantity(&format!("{p}/Dimension2Extent"))?;
            let scale = quantity(&format!("{p}/DataScale"))?;
            let Item::Data { start, len, grid } = get(&format!("{p}/Matrix"))? else {
                return Err(ctx.err(&format!("{p}/Matrix"), "not a matrix", CORRUPT));
            };
            if grid.is_some_and(|g| g != (nx, ny)) {
                return Err(ctx.err(
                    &format!("{p}/Matrix"),
                    format!(
                        "a {:?} matrix for a {nx} × {ny} grid",
                        grid.unwrap_or_default()
                    ),
                    CORRUPT,
                ));
            }
            let data = &bytes[*start..start + len];
            let n = checked_grid(
                ctx,
                &format!("{p}/Dimension2Points"),
                nx,
                ny,
                4,
                data.len() as u64,
            )?;
            let z = binary::decode(data, binary::Sample::F32, true, n)
                .ok_or_else(|| ctx.short(&p, n as u64 * 4, data.len() as u64))?;
            let dx = check_spacing(ctx, &format!("{p}/Dimension2Extent"), lx / nx as f64)?;
            let dy = check_spacing(ctx, &format!("{p}/Dimension1Extent"), ly / ny as f64)?;
            let heights = z
                .into_iter()
                .map(|v| if v.is_finite() { v * scale } else { f64::NAN })
                .collect();
            Ok(
                Raw::si(nx as usize, ny as usize, dx, dy, heights, channel).spacing_from(
                    format!("{p}/Dimension2Extent"),
                    format!("{p}/Dimension1Extent"),
                ),
            )
        }
        k => Err(ctx.err(
            "/MetaData/DataKind",
            format!("data of kind `{k}`, not a surface profile or height map"),
            "export a Surface Profile or Surface Height measurement",
        )),
    }
}
