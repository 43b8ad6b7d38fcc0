//! Gwyddion's native `.gwy` (version 2, magic `GWYP`): a serialised `GwyContainer`
//! object. An object is its type name (NUL-terminated), a `u32` byte size and components;
//! a component is a name (NUL-terminated), a type character and a value: `b`/`c` one
//! byte, `i` int32, `q` int64, `d` double, `s` a NUL-terminated string, `o` an object,
//! and the capitals `C I Q D S O` arrays of those, prefixed by a `u32` count. All numbers
//! are little-endian.
//!
//! Channel `N` is the `GwyDataField` stored under `/N/data` (`xres`, `yres`, `xreal`,
//! `yreal`, `si_unit_xy` and `si_unit_z` as `GwySIUnit` objects with a `unitstr`, and
//! `data`, `xres·yres` doubles, x fastest), titled by `/N/data/title`; a field under
//! `/N/mask` marks invalid points where it is above 0.5. Channels whose z unit is not a
//! length (phase, amplitude) are listed but are not heights.
//!
//! Sources: Gwyddion's user guide, "GWY File Format" (the serialisation), and
//! SurfaceTopography's `IO/GWY.py` (channel keys, masks); tested on a file written by
//! SurfaceTopography's `to_gwy` from a real scan.

use super::units;
use super::{ChannelInfo, Ctx, Decoded, Raw, Unit, Want, binary, check_spacing, checked_grid};
use crate::ReadError;

/// What every version-2 file starts with.
pub(crate) const MAGIC: &[u8] = b"GWYP";
/// Objects nest a few levels deep in real files (container, data field, unit).
const MAX_DEPTH: usize = 16;
/// At most this many components in all: bounds what a corrupt file can make the reader
/// build (a container of many channels holds a few thousand).
const MAX_COMPONENTS: usize = 1 << 20;
const CORRUPT: &str = "the .gwy file is corrupt or truncated; save it again from Gwyddion";

#[derive(Debug)]
enum Value {
    Int(i64),
    Double(f64),
    Text(String),
    Object(Object),
    /// An array of `count` values of type `kind` starting at byte `at` (not decoded).
    Array {
        kind: u8,
        at: usize,
        count: usize,
    },
    Other,
}

#[derive(Debug)]
struct Object {
    name: String,
    components: Vec<(String, Value)>,
}

impl Object {
    fn get(&self, key: &str) -> Option<&Value> {
        self.components
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v)
    }
}

struct Parser<'a> {
    ctx: Ctx<'a>,
    b: &'a [u8],
    pos: usize,
    components: usize,
}

impl Parser<'_> {
    fn corrupt(&self, what: &str) -> ReadError {
        self.ctx.err(
            what,
            format!(
                "the object tree breaks off at byte {} of {}",
                self.pos,
                self.b.len()
            ),
            CORRUPT,
        )
    }
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], ReadError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| self.corrupt(what))?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    fn cstr(&mut self, what: &str) -> Result<String, ReadError> {
        let rest = &self.b[self.pos.min(self.b.len())..];
        let n = rest
            .iter()
            .position(|&c| c == 0)
            .ok_or_else(|| self.corrupt(what))?;
        let s = String::from_utf8_lossy(&rest[..n]).into_owned();
        self.pos += n + 1;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<usize, ReadError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    }

    fn object(&mut self, depth: usize) -> Result<Object, ReadError> {
        if depth > MAX_DEPTH {
            return Err(self.ctx.err("object", "objects nested too deep", CORRUPT));
        }
        let name = self.cstr("object name")?;
        let size = self.u32(&name)?;
        let end = self
            .pos
            .checked_add(size)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| {
                self.ctx.truncated(
                    &name,
                    &format!("object `{name}`"),
                    (self.pos as u64, self.pos as u64 + size as u64),
                    self.b.len() as u64,
                )
            })?;
        let mut components = Vec::new();
        while self.pos < end {
            self.components += 1;
            if self.components > MAX_COMPONENTS {
                return Err(self.ctx.err(&name, "too many components", CORRUPT));
            }
            let key = self.cstr(&name)?;
            let kind = self.take(1, &key)?[0];
            let value = self.value(kind, &key, depth)?;
            components.push((key, value));
        }
        if self.pos != end {
            return Err(self.ctx.err(
                &name,
                format!("its components overrun its size ({} bytes) ", size),
                CORRUPT,
            ));
        }
        Ok(Object { name, components })
    }

    fn value(&mut self, kind: u8, key: &str, depth: usize) -> Result<Value, ReadError> {
        let le = |b: &[u8]| b.iter().rev().fold(0u64, |a, &x| (a << 8) | u64::from(x));
        Ok(match kind {
            b'b' | b'c' => {
                self.take(1, key)?;
                Value::Other
            }
            b'i' => Value::Int(le(self.take(4, key)?) as u32 as i32 as i64),
            b'q' => Value::Int(le(self.take(8, key)?) as i64),
            b'd' => Value::Double(f64::from_bits(le(self.take(8, key)?))),
            b's' => Value::Text(self.cstr(key)?),
            b'o' => Value::Object(self.object(depth + 1)?),
            b'C' | b'I' | b'Q' | b'D' => {
                let count = self.u32(key)?;
                let size = match kind {
                    b'C' => 1,
                    b'I' => 4,
                    _ => 8,
                };
                let at = self.pos;
                self.take(count.saturating_mul(size), key)?;
                Value::Array { kind, at, count }
            }
            b'S' => {
                let count = self.u32(key)?;
                for _ in 0..count {
                    self.cstr(key)?;
                }
                Value::Other
            }
            b'O' => {
                let count = self.u32(key)?;
                for _ in 0..count {
                    self.object(depth + 1)?;
                }
                Value::Other
            }
            t => {
                return Err(self.ctx.err(
                    key,
                    format!(
                        "unknown component type `{}` at byte {}",
                        t as char, self.pos
                    ),
                    CORRUPT,
                ));
            }
        })
    }
}

/// A data field's facts.
struct Field<'o> {
    obj: &'o Object,
}

impl Field<'_> {
    fn int(&self, k: &str) -> Option<i64> {
        match self.obj.get(k)? {
            Value::Int(v) => Some(*v),
            _ => None,
        }
    }
    fn double(&self, k: &str) -> Option<f64> {
        match self.obj.get(k)? {
            Value::Double(v) => Some(*v),
            _ => None,
        }
    }
    fn unit(&self, k: &str) -> Option<String> {
        match self.obj.get(k)? {
            Value::Object(u) => match u.get("unitstr") {
                Some(Value::Text(s)) => Some(s.clone()),
                _ => Some(String::new()),
            },
            _ => None,
        }
    }
}

/// The channel numbers `N` of the `/N/data` fields, in file order.
fn channels(top: &Object) -> Vec<(usize, &Object)> {
    top.components
        .iter()
        .filter_map(|(k, v)| {
            let n = k.strip_prefix('/')?.strip_suffix("/data")?.parse().ok()?;
            match v {
                Value::Object(o) if o.name == "GwyDataField" => Some((n, o)),
                _ => None,
            }
        })
        .collect()
}

/// Read a `.gwy` file (multi-channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if bytes.starts_with(b"GWYO") {
        return Err(ctx.err(
            "magic",
            "a Gwyddion 1 file (`GWYO`), which is not read",
            "open it in Gwyddion 2 and save it again (.gwy) or as .gsf",
        ));
    }
    if !bytes.starts_with(MAGIC) {
        return Err(ctx.err(
            "magic",
            "the file does not start with `GWYP`",
            "not a .gwy file",
        ));
    }
    let mut p = Parser {
        ctx,
        b: bytes,
        pos: MAGIC.len(),
        components: 0,
    };
    let top = p.object(0)?;
    let fields = channels(&top);
    if fields.is_empty() {
        return Err(ctx.err(
            "/0/data",
            "the container holds no image channel (no `/N/data` data field)",
            "save an image channel from Gwyddion (graphs and spectra are not height maps)",
        ));
    }
    let list: Vec<ChannelInfo> = fields
        .iter()
        .enumerate()
        .map(|(i, (n, o))| {
            let f = Field { obj: o };
            let unit = f.unit("si_unit_z").unwrap_or_default();
            let title = match top.get(&format!("/{n}/data/title")) {
                Some(Value::Text(t)) => t.clone(),
                _ => format!("channel {n}"),
            };
            ChannelInfo {
                index: i,
                name: title,
                is_height: units::length_factor(&unit).is_some(),
                unit,
                nx: f.int("xres").unwrap_or(0).max(0) as usize,
                ny: f.int("yres").unwrap_or(0).max(0) as usize,
            }
        })
        .collect();
    Decoded::pick(ctx, want, list, |i, info| {
        let (n, obj) = fields[i];
        let mask = match top.get(&format!("/{n}/mask")) {
            Some(Value::Object(m)) if m.name == "GwyDataField" => Some(m),
            _ => None,
        };
        field(ctx, bytes, n, obj, mask, info)
    })
}

fn field(
    ctx: Ctx<'_>,
    bytes: &[u8],
    n: usize,
    obj: &Object,
    mask: Option<&Object>,
    info: &ChannelInfo,
) -> Result<Raw, ReadError> {
    let f = Field { obj };
    let key = |k: &str| format!("/{n}/data {k}");
    let res = |k: &str| -> Result<u64, ReadError> {
        f.int(k)
            .filter(|&v| v > 0)
            .map(|v| v as u64)
            .ok_or_else(|| ctx.err(&key(k), "missing or not a positive integer", CORRUPT))
    };
    let (nx, ny) = (res("xres")?, res("yres")?);
    let real = |k: &str| -> Result<f64, ReadError> {
        f.double(k)
            .ok_or_else(|| ctx.err(&key(k), "missing or not a number", CORRUPT))
    };
    let xy = f.unit("si_unit_xy").unwrap_or_default();
    let lateral = units::length_factor(&xy).ok_or_else(|| {
        ctx.err(
            &key("si_unit_xy"),
            format!("lateral unit `{xy}` is not a length"),
            "the data field's lateral axes must be lengths",
        )
    })?;
    let z = units::length_factor(&info.unit).ok_or_else(|| {
        ctx.err(
            &key("si_unit_z"),
            format!("values in `{}`, not a length", info.unit),
            "choose a height channel with --channel",
        )
    })?;
    let dx = check_spacing(ctx, &key("xreal"), real("xreal")? / nx as f64)?;
    let dy = check_spacing(ctx, &key("yreal"), real("yreal")? / ny as f64)?;
    let data = |o: &Object, what: &str| -> Result<Vec<f64>, ReadError> {
        let Some(Value::Array {
            kind: b'D',
            at,
            count,
        }) = o.get("data")
        else {
            return Err(ctx.err(what, "no array of doubles `data`", CORRUPT));
        };
        let m = checked_grid(ctx, what, nx, ny, 8, (*count as u64).saturating_mul(8))?;
        binary::decode(&bytes[*at..], binary::Sample::F64, true, m)
            .ok_or_else(|| ctx.short(what, m as u64 * 8, bytes.len().saturating_sub(*at) as u64))
    };
    let mut heights = data(obj, &key("data"))?;
    if let Some(m) = mask {
        let mvals = data(m, &format!("/{n}/mask"))?;
        for (h, m) in heights.iter_mut().zip(mvals) {
            if m > 0.5 {
                *h = f64::NAN;
            }
        }
    }
    for h in &mut heights {
        if !h.is_finite() {
            *h = f64::NAN;
        }
    }
    Ok(
        Raw::si(nx as usize, ny as usize, dx, dy, heights, info.name.clone())
            .in_units(Unit::Known(z), Unit::Known(lateral))
            .spacing_from(key("xreal"), key("yreal")),
    )
}
