//! The parts of HDF5 that Zygo's DATX files use, read from the file in memory with every
//! offset, length and count checked before it is used: superblocks version 0–3 (8-byte
//! offsets and lengths), object headers version 1 and 2 with their continuation blocks,
//! groups as symbol tables (version 1 B-tree and local heap) or as link messages (compact
//! storage), datasets with contiguous, compact or chunked layout (indexed by a version 1
//! B-tree, or by HDF5 1.10's single chunk, implicit index or unpaged fixed array) and the
//! deflate and shuffle filters, and attributes with
//! fixed-point, floating-point, string (fixed or variable length, from the global heap),
//! compound and array types.
//!
//! Not read, and refused naming what it is: dense link and attribute storage (fractal
//! heaps), shared (committed) datatypes, the
//! extensible-array, version 2 B-tree and paged fixed-array chunk indexes, other filters
//! (szip, LZF, …), offsets or lengths other than 8 bytes, a superblock past byte 0.
//! Checksums are not verified.
//!
//! Sources: the HDF5 File Format Specification version 3.0 (The HDF Group; public), and
//! files written by h5py 3.16 (HDF5 library) to check the reading against.

use std::io::Read;

/// Largest number of elements of a dataset read.
pub const MAX_ELEMENTS: u64 = 1 << 31;
/// Deflate cannot expand data by more than about 1032:1.
const DEFLATE_RATIO: u64 = 1032;
/// Object-header blocks, B-tree nodes and global-heap objects visited at most for one
/// request: a loop of addresses ends there.
const MAX_VISITS: usize = 1 << 16;
const UNDEFINED: u64 = u64::MAX;

/// A parse error (the caller names the file).
pub type Error = String;
type R<T> = Result<T, Error>;

/// An HDF5 file in memory.
pub struct File<'a> {
    b: &'a [u8],
    root: u64,
}

/// An element type.
#[derive(Debug, Clone, PartialEq)]
pub enum Dtype {
    /// Integer of `size` bytes.
    Fixed { size: usize, signed: bool, be: bool },
    /// IEEE float of 4 or 8 bytes.
    Float { size: usize, be: bool },
    /// Fixed-length string of `size` bytes.
    Str { size: usize },
    /// Variable-length string (a global-heap reference of 16 bytes).
    VlenStr,
    /// Members: name, byte offset, type.
    Compound {
        size: usize,
        members: Vec<(String, usize, Dtype)>,
    },
    /// `count` elements of `base`.
    Array { count: usize, base: Box<Dtype> },
    /// Any other class (its number and size).
    Other { class: u8, size: usize },
}

impl Dtype {
    /// Bytes per element.
    pub fn size(&self) -> usize {
        match self {
            Dtype::Fixed { size, .. } | Dtype::Float { size, .. } | Dtype::Str { size } => *size,
            Dtype::VlenStr => 16,
            Dtype::Compound { size, .. } | Dtype::Other { size, .. } => *size,
            Dtype::Array { count, base } => count.saturating_mul(base.size()),
        }
    }
}

/// A value of an attribute or a compound member, as far as DATX needs them.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Numbers (of a numeric type or array).
    Numbers(Vec<f64>),
    /// A string.
    Text(String),
    /// A compound's members in order.
    Compound(Vec<(String, Value)>),
    /// Something else.
    Other,
}

struct Message<'a> {
    kind: u16,
    /// Bit 1: the message is shared (stored elsewhere; only a reference here).
    flags: u8,
    data: &'a [u8],
}

/// A dataset's description.
pub struct Dataset<'a> {
    /// Dimensions, slowest first.
    pub dims: Vec<u64>,
    /// Element type.
    pub dtype: Dtype,
    layout: &'a [u8],
    filters: Vec<u16>,
    messages: Vec<Message<'a>>,
}

fn take(b: &[u8], at: u64, len: u64) -> R<&[u8]> {
    let end = at.checked_add(len).ok_or("an offset overflows")?;
    b.get(at as usize..end as usize).ok_or_else(|| {
        format!(
            "{len} bytes at offset {at} lie beyond the end of the file ({} bytes)",
            b.len()
        )
    })
}

fn le(b: &[u8], at: usize, n: usize) -> R<u64> {
    let s = b
        .get(at..at.checked_add(n).ok_or("an offset overflows")?)
        .ok_or("a structure is truncated")?;
    Ok(s.iter().rev().fold(0u64, |v, &x| (v << 8) | u64::from(x)))
}

fn pad8(n: usize) -> usize {
    n.div_ceil(8) * 8
}

/// `[start, …)` of the next field after a NUL-terminated name at `at`.
fn cstr(b: &[u8], at: usize) -> R<(String, usize)> {
    let rest = b.get(at..).ok_or("a name is truncated")?;
    let end = rest
        .iter()
        .position(|&c| c == 0)
        .ok_or("a name is not terminated")?;
    Ok((
        String::from_utf8_lossy(&rest[..end]).into_owned(),
        at + end + 1,
    ))
}

impl<'a> File<'a> {
    /// Parse the superblock at byte 0.
    pub fn open(b: &'a [u8]) -> R<File<'a>> {
        if !b.starts_with(b"\x89HDF\r\n\x1a\n") {
            return Err("no HDF5 signature at byte 0".into());
        }
        let version = *b.get(8).ok_or("the superblock is truncated")?;
        let (so, sl, root) = match version {
            0 | 1 => {
                let base = if version == 0 { 24 } else { 28 };
                // Base, free space, end of file, driver info; then the root group's
                // symbol-table entry: link name offset, object header address.
                (le(b, 13, 1)?, le(b, 14, 1)?, le(b, base + 40, 8)?)
            }
            2 | 3 => (le(b, 9, 1)?, le(b, 10, 1)?, le(b, 12 + 24, 8)?),
            v => return Err(format!("superblock version {v} is not known")),
        };
        if so != 8 || sl != 8 {
            return Err(format!(
                "offsets of {so} and lengths of {sl} bytes (only 8 are read)"
            ));
        }
        Ok(File { b, root })
    }

    /// The messages of the object header at `addr`, continuation blocks included.
    fn messages(&self, addr: u64) -> R<Vec<Message<'a>>> {
        let b = self.b;
        let mut out = vec![];
        // (offset, length, version 2 block?)
        let mut blocks: Vec<(u64, u64, bool)> = vec![];
        let v2 = take(b, addr, 4)? == b"OHDR";
        if v2 {
            let flags = *take(b, addr + 5, 1)?.first().ok_or("truncated")?;
            let mut at = addr + 6;
            if flags & 0x20 != 0 {
                at += 16;
            }
            if flags & 0x10 != 0 {
                at += 4;
            }
            let n = 1usize << (flags & 3);
            let size = le(take(b, at, n as u64)?, 0, n)?;
            blocks.push((at + n as u64, size, true));
            self.walk(&mut blocks, &mut out, flags & 0x04 != 0)?;
        } else {
            let h = take(b, addr, 16)?;
            if h[0] != 1 {
                return Err(format!(
                    "object header version {} at {addr} is not known",
                    h[0]
                ));
            }
            let size = le(h, 8, 4)?;
            blocks.push((addr + 16, size, false));
            self.walk(&mut blocks, &mut out, false)?;
        }
        Ok(out)
    }

    fn walk(
        &self,
        blocks: &mut Vec<(u64, u64, bool)>,
        out: &mut Vec<Message<'a>>,
        order: bool,
    ) -> R<()> {
        let mut visited = 0;
        while let Some((at, len, v2)) = blocks.pop() {
            visited += 1;
            if visited > MAX_VISITS {
                return Err("object header continuations form a loop".into());
            }
            let block = take(self.b, at, len)?;
            let mut p = 0usize;
            let head = if v2 { 4 + usize::from(order) * 2 } else { 8 };
            while p + head <= block.len() {
                let (kind, size, flags, data_at) = if v2 {
                    let (k, n, f) = (le(block, p, 1)?, le(block, p + 1, 2)?, le(block, p + 3, 1)?);
                    (k, n as usize, f as u8, p + head)
                } else {
                    let (k, n, f) = (le(block, p, 2)?, le(block, p + 2, 2)?, le(block, p + 4, 1)?);
                    (k, n as usize, f as u8, p + 8)
                };
                let data = block
                    .get(data_at..data_at + size)
                    .ok_or("an object header message is truncated")?;
                if kind == 0x10 {
                    let (o, l) = (le(data, 0, 8)?, le(data, 8, 8)?);
                    if v2 {
                        if take(self.b, o, 4)? != b"OCHK" || l < 8 {
                            return Err("a continuation block lacks its OCHK signature".into());
                        }
                        blocks.push((o + 4, l - 8, true));
                    } else {
                        blocks.push((o, l, false));
                    }
                } else if kind != 0 {
                    out.push(Message {
                        kind: kind as u16,
                        flags,
                        data,
                    });
                }
                p = data_at + size;
            }
        }
        Ok(())
    }

    /// The object header address of `path` (`/a/b`), from the root group.
    pub fn lookup(&self, path: &str) -> R<u64> {
        let mut addr = self.root;
        for name in path.split('/').filter(|s| !s.is_empty()) {
            addr = self
                .child(addr, name)?
                .ok_or_else(|| format!("no object `{name}` in the path `{path}`"))?;
        }
        Ok(addr)
    }

    fn child(&self, group: u64, name: &str) -> R<Option<u64>> {
        for m in self.messages(group)? {
            match m.kind {
                0x11 => return self.symbol_table(le(m.data, 0, 8)?, le(m.data, 8, 8)?, name),
                0x06 => {
                    if let Some((n, a)) = link(m.data)?
                        && n == name
                    {
                        return Ok(Some(a));
                    }
                }
                0x02 => {
                    let flags = le(m.data, 1, 1)?;
                    let heap = le(m.data, 2 + if flags & 1 != 0 { 8 } else { 0 }, 8)?;
                    if heap != UNDEFINED {
                        return Err("a group stores its links densely (fractal heap), which \
                                    is not read"
                            .into());
                    }
                }
                _ => {}
            }
        }
        Ok(None)
    }

    fn symbol_table(&self, btree: u64, heap: u64, name: &str) -> R<Option<u64>> {
        let h = take(self.b, heap, 32)?;
        if &h[..4] != b"HEAP" {
            return Err("a group's local heap lacks its HEAP signature".into());
        }
        let (size, data) = (le(h, 8, 8)?, le(h, 24, 8)?);
        let names = take(self.b, data, size)?;
        let mut found = None;
        self.btree((btree, 0, 8), &mut |_, child| {
            let s = take(self.b, child, 8)?;
            if s[..4] != *b"SNOD" {
                return Err("a symbol node lacks its SNOD signature".into());
            }
            let n = le(s, 6, 2)?;
            let entries = take(self.b, child + 8, n * 40)?;
            for e in entries.chunks_exact(40) {
                let (entry, _) = cstr(names, le(e, 0, 8)? as usize)?;
                if entry == name {
                    found = Some(le(e, 8, 8)?);
                }
            }
            Ok(())
        })?;
        Ok(found)
    }

    /// Visit the leaves of the version 1 B-tree at `addr` of node type `kind`: `f(key,
    /// child)` with the key's bytes before each child.
    fn btree(
        &self,
        (addr, kind, key_len): (u64, u8, u64),
        f: &mut dyn FnMut(&[u8], u64) -> R<()>,
    ) -> R<()> {
        let mut stack = vec![(addr, 64u8)];
        let mut visited = 0;
        while let Some((at, depth)) = stack.pop() {
            visited += 1;
            if visited > MAX_VISITS || depth == 0 {
                return Err("a B-tree is too deep or forms a loop".into());
            }
            let h = take(self.b, at, 24)?;
            if &h[..4] != b"TREE" || h[4] != kind {
                return Err(format!("no B-tree node of type {kind} at offset {at}"));
            }
            let (level, n) = (h[5], le(h, 6, 2)?);
            let body = take(self.b, at + 24, n * (key_len + 8) + key_len)?;
            for i in 0..n as usize {
                let k = i * (key_len as usize + 8);
                let key = &body[k..k + key_len as usize];
                let child = le(body, k + key_len as usize, 8)?;
                if level == 0 {
                    f(key, child)?;
                } else {
                    stack.push((child, depth - 1));
                }
            }
        }
        Ok(())
    }
}

/// A link message's (name, object address) for a hard link.
fn link(m: &[u8]) -> R<Option<(String, u64)>> {
    let flags = le(m, 1, 1)? as u8;
    let mut p = 2;
    let kind = if flags & 0x08 != 0 {
        p += 1;
        le(m, 2, 1)?
    } else {
        0
    };
    if flags & 0x04 != 0 {
        p += 8;
    }
    if flags & 0x10 != 0 {
        p += 1;
    }
    let n = 1usize << (flags & 3);
    let len = le(m, p, n)? as usize;
    p += n;
    let name = m.get(p..p + len).ok_or("a link name is truncated")?;
    if kind != 0 {
        return Ok(None);
    }
    Ok(Some((
        String::from_utf8_lossy(name).into_owned(),
        le(m, p + len, 8)?,
    )))
}

/// A datatype message: the type and the bytes it took.
fn dtype(b: &[u8], depth: u8) -> R<(Dtype, usize)> {
    if depth == 0 {
        return Err("a datatype nests too deeply".into());
    }
    let head = b.get(..8).ok_or("a datatype is truncated")?;
    let (class, version) = (head[0] & 0x0F, head[0] >> 4);
    let bits = le(head, 1, 3)? as u32;
    let size = le(head, 4, 4)? as usize;
    let be = bits & 1 != 0;
    Ok(match class {
        0 => (
            Dtype::Fixed {
                size,
                signed: bits & 8 != 0,
                be,
            },
            12,
        ),
        1 => (Dtype::Float { size, be }, 20),
        3 => (Dtype::Str { size }, 8),
        9 => {
            let (base, used) = dtype(&b[8..], depth - 1)?;
            let t = if bits & 0x0F == 1 || matches!(base, Dtype::Fixed { size: 1, .. }) {
                Dtype::VlenStr
            } else {
                Dtype::Other { class, size }
            };
            (t, 8 + used)
        }
        10 => {
            let rank = usize::from(*b.get(8).ok_or("an array type is truncated")?);
            let mut p = if version >= 3 { 9 } else { 12 };
            let mut count = 1usize;
            for i in 0..rank {
                count = count.saturating_mul(le(b, p + 4 * i, 4)? as usize);
            }
            p += 4 * rank;
            if version < 3 {
                p += 4 * rank;
            }
            let (base, used) = dtype(b.get(p..).ok_or("an array type is truncated")?, depth - 1)?;
            (
                Dtype::Array {
                    count,
                    base: Box::new(base),
                },
                p + used,
            )
        }
        6 => {
            let n = (bits & 0xFFFF) as usize;
            let mut p = 8;
            let mut members = Vec::with_capacity(n.min(256));
            for _ in 0..n {
                let (name, end) = cstr(b, p)?;
                p = if version >= 3 { end } else { p + pad8(end - p) };
                let offset_len = if version >= 3 {
                    match size {
                        0..=0xFF => 1,
                        0x100..=0xFFFF => 2,
                        0x1_0000..=0xFF_FFFF => 3,
                        _ => 4,
                    }
                } else {
                    4
                };
                let offset = le(b, p, offset_len)? as usize;
                p += offset_len;
                if version == 1 {
                    p += 28;
                }
                let (t, used) =
                    dtype(b.get(p..).ok_or("a compound type is truncated")?, depth - 1)?;
                p += used;
                members.push((name, offset, t));
            }
            (Dtype::Compound { size, members }, p)
        }
        _ => (Dtype::Other { class, size }, 8),
    })
}

/// A dataspace message: its dimensions (none for a scalar).
fn dataspace(b: &[u8]) -> R<Vec<u64>> {
    let version = le(b, 0, 1)?;
    let rank = le(b, 1, 1)? as usize;
    let start = match version {
        1 => 8,
        2 => {
            if le(b, 3, 1)? == 2 {
                return Ok(vec![0]);
            }
            4
        }
        v => return Err(format!("dataspace version {v} is not known")),
    };
    (0..rank).map(|i| le(b, start + 8 * i, 8)).collect()
}

impl<'a> File<'a> {
    /// The dataset at `path`.
    pub fn dataset(&self, path: &str) -> R<Dataset<'a>> {
        let messages = self.messages(self.lookup(path)?)?;
        if messages.iter().any(|m| m.flags & 2 != 0 && m.kind != 0x0C) {
            return Err(
                "the dataset shares a message (a committed datatype), which is not read".into(),
            );
        }
        let find = |k: u16| messages.iter().find(|m| m.kind == k).map(|m| m.data);
        let dims = dataspace(find(0x01).ok_or("the dataset has no dataspace")?)?;
        let (dtype, _) = dtype(find(0x03).ok_or("the dataset has no datatype")?, 8)?;
        let layout = find(0x08).ok_or("the dataset has no layout")?;
        let filters = match find(0x0B) {
            Some(f) => filter_ids(f)?,
            None => vec![],
        };
        Ok(Dataset {
            dims,
            dtype,
            layout,
            filters,
            messages,
        })
    }

    /// The attribute `name` of a dataset.
    pub fn attribute(&self, d: &Dataset<'a>, name: &str) -> R<Option<Value>> {
        for m in d.messages.iter().filter(|m| m.kind == 0x0C) {
            let b = m.data;
            let version = le(b, 0, 1)?;
            let (nl, tl, sl) = (
                le(b, 2, 2)? as usize,
                le(b, 4, 2)? as usize,
                le(b, 6, 2)? as usize,
            );
            let (mut p, pad): (usize, fn(usize) -> usize) = match version {
                1 => (8, pad8),
                2 => (8, |n| n),
                3 => (9, |n| n),
                v => return Err(format!("attribute message version {v} is not known")),
            };
            let (n, _) = cstr(b, p)?;
            p += pad(nl);
            if n != name {
                continue;
            }
            if version >= 2 && le(b, 1, 1)? & 3 != 0 {
                return Err(format!(
                    "attribute `{name}` has a shared (committed) type or space, which is not read"
                ));
            }
            let (t, _) = dtype(b.get(p..p + tl).ok_or("an attribute is truncated")?, 8)?;
            p += pad(tl);
            let dims = dataspace(b.get(p..p + sl).ok_or("an attribute is truncated")?)?;
            p += pad(sl);
            let count = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d));
            let count = count
                .filter(|&c| c <= 1 << 20)
                .ok_or("an attribute is too large")?;
            let data = b.get(p..).ok_or("an attribute is truncated")?;
            let size = t.size();
            let mut values = vec![];
            for i in 0..count as usize {
                let e = data
                    .get(i * size..(i + 1) * size)
                    .ok_or("an attribute's data is truncated")?;
                values.push(self.value(&t, e, 8)?);
            }
            return Ok(Some(if values.len() == 1 {
                values.remove(0)
            } else if values.iter().all(|v| matches!(v, Value::Numbers(_))) {
                Value::Numbers(
                    values
                        .into_iter()
                        .flat_map(|v| match v {
                            Value::Numbers(n) => n,
                            _ => vec![],
                        })
                        .collect(),
                )
            } else {
                values.into_iter().next().unwrap_or(Value::Other)
            }));
        }
        for m in d.messages.iter().filter(|m| m.kind == 0x15) {
            let heap = le(
                m.data,
                2 + if le(m.data, 1, 1)? & 1 != 0 { 2 } else { 0 },
                8,
            )?;
            if heap != UNDEFINED {
                return Err(format!(
                    "attribute `{name}` may be stored densely (fractal heap), which is not read"
                ));
            }
        }
        Ok(None)
    }

    fn value(&self, t: &Dtype, e: &[u8], depth: u8) -> R<Value> {
        if depth == 0 {
            return Err("a value nests too deeply".into());
        }
        Ok(match t {
            Dtype::Fixed { .. } | Dtype::Float { .. } => Value::Numbers(vec![number(t, e)?]),
            Dtype::Str { size } => {
                let s = e.get(..*size).ok_or("a string is truncated")?;
                let end = s.iter().position(|&c| c == 0).unwrap_or(s.len());
                Value::Text(String::from_utf8_lossy(&s[..end]).trim().to_string())
            }
            Dtype::VlenStr => Value::Text(self.vlen_string(e)?),
            Dtype::Array { count, base } => {
                let size = base.size();
                let mut out = vec![];
                for i in 0..*count {
                    let x = e
                        .get(i * size..(i + 1) * size)
                        .ok_or("an array value is truncated")?;
                    out.push(number(base, x)?);
                }
                Value::Numbers(out)
            }
            Dtype::Compound { members, .. } => {
                let mut out = vec![];
                for (name, offset, mt) in members {
                    let x = e
                        .get(*offset..offset.saturating_add(mt.size()))
                        .ok_or("a compound member is truncated")?;
                    out.push((name.clone(), self.value(mt, x, depth - 1)?));
                }
                Value::Compound(out)
            }
            Dtype::Other { .. } => Value::Other,
        })
    }

    /// A variable-length string: its length, then the global heap collection and index.
    fn vlen_string(&self, e: &[u8]) -> R<String> {
        let (len, heap, index) = (le(e, 0, 4)?, le(e, 4, 8)?, le(e, 12, 4)?);
        if len == 0 {
            return Ok(String::new());
        }
        let h = take(self.b, heap, 16)?;
        if &h[..4] != b"GCOL" {
            return Err("a global heap collection lacks its GCOL signature".into());
        }
        let coll = take(self.b, heap, le(h, 8, 8)?)?;
        let mut p = 16usize;
        for _ in 0..MAX_VISITS {
            let i = le(coll, p, 2)?;
            let size = le(coll, p + 8, 8)? as usize;
            if i == 0 {
                break;
            }
            let data = coll
                .get(p + 16..(p + 16).saturating_add(size))
                .ok_or("a global heap object is truncated")?;
            if i == index {
                let s = data.get(..len as usize).ok_or("a string is truncated")?;
                return Ok(String::from_utf8_lossy(s).into_owned());
            }
            p += 16 + pad8(size);
        }
        Err(format!("global heap object {index} not found"))
    }

    /// The dataset's values as numbers, row-major (last dimension fastest).
    pub fn read_numbers(&self, d: &Dataset<'a>) -> R<Vec<f64>> {
        if !matches!(d.dtype, Dtype::Fixed { .. } | Dtype::Float { .. }) {
            return Err(format!("the data's type ({:?}) is not numeric", d.dtype));
        }
        let n = d
            .dims
            .iter()
            .try_fold(1u64, |a, &x| a.checked_mul(x))
            .filter(|&n| n <= MAX_ELEMENTS)
            .ok_or_else(|| format!("dimensions {:?} exceed {MAX_ELEMENTS} elements", d.dims))?;
        let size = d.dtype.size();
        if !(1..=8).contains(&size) {
            return Err(format!("elements of {size} bytes"));
        }
        let bytes = n * size as u64;
        let raw = self.raw(d, bytes)?;
        raw.chunks_exact(size)
            .map(|e| number(&d.dtype, e))
            .collect()
    }

    /// The dataset's elements as values (strings, compounds), at most `max` of them.
    pub fn read_values(&self, d: &Dataset<'a>, max: u64) -> R<Vec<Value>> {
        let n = d
            .dims
            .iter()
            .try_fold(1u64, |a, &x| a.checked_mul(x))
            .filter(|&n| n <= max)
            .ok_or_else(|| format!("dimensions {:?} exceed {max} elements", d.dims))?;
        let size = d.dtype.size();
        if size == 0 || size > 1 << 16 {
            return Err(format!("elements of {size} bytes"));
        }
        let raw = self.raw(d, n * size as u64)?;
        raw.chunks_exact(size)
            .map(|e| self.value(&d.dtype, e, 8))
            .collect()
    }

    /// The dataset's `bytes` bytes, unfiltered.
    fn raw(&self, d: &Dataset<'a>, bytes: u64) -> R<Vec<u8>> {
        let l = d.layout;
        let version = le(l, 0, 1)?;
        if !(3..=4).contains(&version) {
            return Err(format!("data layout version {version} is not read"));
        }
        match le(l, 1, 1)? {
            0 => {
                let size = le(l, 2, 2)?;
                let data = l
                    .get(4..4 + size as usize)
                    .ok_or("compact data is truncated")?;
                Ok(data
                    .get(..bytes as usize)
                    .ok_or("compact data is short")?
                    .to_vec())
            }
            1 => {
                let (at, size) = (le(l, 2, 8)?, le(l, 10, 8)?);
                if size < bytes {
                    return Err(format!("{size} bytes of data, {bytes} needed"));
                }
                Ok(take(self.b, at, bytes)?.to_vec())
            }
            2 if version == 3 => {
                let rank = le(l, 2, 1)? as usize;
                let at = le(l, 3, 8)?;
                let chunk: Vec<u64> = (0..rank).map(|i| le(l, 11 + 4 * i, 4)).collect::<R<_>>()?;
                self.chunked(d, Index::BTree(at), &chunk, bytes)
            }
            2 => {
                let (flags, rank, enc) = (le(l, 2, 1)?, le(l, 3, 1)? as usize, le(l, 4, 1)?);
                if !(1..=8).contains(&enc) {
                    return Err(format!("chunk dimensions encoded in {enc} bytes"));
                }
                let enc = enc as usize;
                let chunk: Vec<u64> = (0..rank)
                    .map(|i| le(l, 5 + enc * i, enc))
                    .collect::<R<_>>()?;
                let p = 5 + enc * rank;
                let index = match le(l, p, 1)? {
                    1 if flags & 2 != 0 => Index::Single {
                        size: Some(le(l, p + 1, 8)?),
                        mask: le(l, p + 9, 4)?,
                        at: le(l, p + 13, 8)?,
                    },
                    1 => Index::Single {
                        size: None,
                        mask: 0,
                        at: le(l, p + 1, 8)?,
                    },
                    2 => Index::Implicit(le(l, p + 1, 8)?),
                    3 => Index::FixedArray(le(l, p + 2, 8)?),
                    4 => return Err("an extensible-array chunk index is not read".into()),
                    5 => return Err("a version 2 B-tree chunk index is not read".into()),
                    t => return Err(format!("chunk index type {t} is not known")),
                };
                self.chunked(d, index, &chunk, bytes)
            }
            c => Err(format!("data layout class {c} is not known")),
        }
    }
}

/// The filter identifiers of a filter pipeline message.
fn filter_ids(b: &[u8]) -> R<Vec<u16>> {
    let version = le(b, 0, 1)?;
    let n = le(b, 1, 1)? as usize;
    let mut p = if version == 1 { 8 } else { 2 };
    let mut ids = vec![];
    for _ in 0..n {
        let id = le(b, p, 2)? as u16;
        let (name_len, values) = if version == 1 || id >= 256 {
            (le(b, p + 2, 2)? as usize, le(b, p + 6, 2)? as usize)
        } else {
            (0, le(b, p + 4, 2)? as usize)
        };
        p += if version == 1 || id >= 256 { 8 } else { 6 };
        p += if version == 1 {
            pad8(name_len)
        } else {
            name_len
        };
        p += 4 * values;
        if version == 1 && values % 2 == 1 {
            p += 4;
        }
        ids.push(id);
    }
    Ok(ids)
}

fn number(t: &Dtype, e: &[u8]) -> R<f64> {
    let get = |n: usize, be: bool| -> R<u64> {
        let s = e.get(..n).ok_or("a number is truncated")?;
        Ok(if be {
            s.iter().fold(0u64, |v, &x| (v << 8) | u64::from(x))
        } else {
            s.iter().rev().fold(0u64, |v, &x| (v << 8) | u64::from(x))
        })
    };
    Ok(match *t {
        Dtype::Float { size: 8, be } => f64::from_bits(get(8, be)?),
        Dtype::Float { size: 4, be } => f64::from(f32::from_bits(get(4, be)? as u32)),
        Dtype::Fixed { size, signed, be } if (1..=8).contains(&size) => {
            let v = get(size, be)?;
            if signed {
                let shift = 64 - 8 * size as u32;
                (((v << shift) as i64) >> shift) as f64
            } else {
                v as f64
            }
        }
        _ => return Err(format!("{t:?} is not a number type read here")),
    })
}

/// Where a chunked dataset lists its chunks.
enum Index {
    /// A version 1 B-tree (node type 1) at this address.
    BTree(u64),
    /// One chunk (its stored size and filter mask when filtered).
    Single {
        at: u64,
        size: Option<u64>,
        mask: u64,
    },
    /// Unfiltered chunks back to back from this address, in chunk order.
    Implicit(u64),
    /// A fixed array (its header's address), one entry per chunk in chunk order.
    FixedArray(u64),
}

/// A chunk: its offsets (elements, per dimension), stored size, filter mask, address.
struct Chunk {
    offsets: Vec<u64>,
    size: u64,
    mask: u64,
    at: u64,
}

impl<'a> File<'a> {
    /// A chunked dataset through its version 1 B-tree (node type 1); `chunk` holds the
    /// chunk's dimensions and, last, the element size.
    fn chunked(&self, d: &Dataset<'a>, index: Index, chunk: &[u64], bytes: u64) -> R<Vec<u8>> {
        let rank = d.dims.len();
        let esize = d.dtype.size() as u64;
        if chunk.len() != rank + 1 || chunk[rank] != esize || rank == 0 {
            return Err(format!(
                "chunk dimensions {chunk:?} do not fit the data {:?}",
                d.dims
            ));
        }
        let elems = chunk[..rank]
            .iter()
            .try_fold(1u64, |a, &c| a.checked_mul(c))
            .filter(|&n| n > 0 && n <= MAX_ELEMENTS)
            .ok_or("a chunk's dimensions are zero or too large")?;
        let chunk_bytes = elems * esize;
        let chunks = self.chunk_list(d, index, &chunk[..rank], chunk_bytes)?;
        for &f in &d.filters {
            if f != 1 && f != 2 {
                return Err(format!(
                    "HDF5 filter {f} (only deflate and shuffle are read)"
                ));
            }
        }
        let ratio = if d.filters.contains(&1) {
            DEFLATE_RATIO
        } else {
            1
        };
        let stored = chunks.iter().fold(0u64, |a, c| a.saturating_add(c.size));
        if bytes > stored.saturating_mul(ratio) {
            return Err(format!(
                "the chunks hold {stored} bytes, too few for the {bytes} bytes of the data"
            ));
        }
        let mut out = vec![0u8; bytes as usize];
        for c in &chunks {
            let data = self.unfilter(d, c, chunk_bytes)?;
            place(
                &mut out,
                &d.dims,
                &chunk[..rank],
                &c.offsets,
                esize as usize,
                &data,
            )?;
        }
        Ok(out)
    }

    /// The chunks `index` lists: their element offsets, stored sizes and addresses.
    fn chunk_list(
        &self,
        d: &Dataset<'a>,
        index: Index,
        chunk: &[u64],
        chunk_bytes: u64,
    ) -> R<Vec<Chunk>> {
        let rank = chunk.len();
        // Chunks along each dimension, and their number, for the indexes in chunk order.
        let across: Vec<u64> = d
            .dims
            .iter()
            .zip(chunk)
            .map(|(n, c)| n.div_ceil(*c))
            .collect();
        let count = across
            .iter()
            .try_fold(1u64, |a, &c| a.checked_mul(c))
            .filter(|&n| n <= MAX_ELEMENTS)
            .ok_or("too many chunks")?;
        let offsets = |mut i: u64| {
            let mut o = vec![0u64; rank];
            for k in (0..rank).rev() {
                o[k] = (i % across[k]) * chunk[k];
                i /= across[k];
            }
            o
        };
        let mut chunks = vec![];
        match index {
            Index::BTree(at) => {
                self.btree((at, 1, 8 + 8 * (rank as u64 + 1)), &mut |key, at| {
                    if chunks.len() as u64 >= count {
                        return Err("the chunk B-tree lists more chunks than the data has".into());
                    }
                    chunks.push(Chunk {
                        size: le(key, 0, 4)?,
                        mask: le(key, 4, 4)?,
                        offsets: (0..rank).map(|i| le(key, 8 + 8 * i, 8)).collect::<R<_>>()?,
                        at,
                    });
                    Ok(())
                })?;
            }
            Index::Single { at, size, mask } => chunks.push(Chunk {
                offsets: vec![0; rank],
                size: size.unwrap_or(chunk_bytes),
                mask,
                at,
            }),
            Index::Implicit(at) => {
                if !d.filters.is_empty() {
                    return Err("an implicit chunk index with filters".into());
                }
                take(self.b, at, count.saturating_mul(chunk_bytes))?;
                for i in 0..count {
                    chunks.push(Chunk {
                        offsets: offsets(i),
                        size: chunk_bytes,
                        mask: 0,
                        at: at + i * chunk_bytes,
                    });
                }
            }
            Index::FixedArray(at) => {
                let h = take(self.b, at, 28)?;
                if &h[..4] != b"FAHD" {
                    return Err("a fixed-array chunk index lacks its FAHD signature".into());
                }
                let (filtered, entry, page_bits) = (h[5] == 1, usize::from(h[6]), h[7]);
                let (n, block) = (le(h, 8, 8)?, le(h, 16, 8)?);
                if n != count {
                    return Err(format!(
                        "the chunk index lists {n} chunks, the data has {count}"
                    ));
                }
                if page_bits < 64 && n > 1u64 << page_bits {
                    return Err("a paged fixed-array chunk index is not read".into());
                }
                let want = if filtered { 13 } else { 8 };
                if entry < want {
                    return Err(format!("chunk index entries of {entry} bytes"));
                }
                let b = take(self.b, block, 14 + n * entry as u64)?;
                if &b[..4] != b"FADB" {
                    return Err("a fixed-array data block lacks its FADB signature".into());
                }
                for i in 0..n as usize {
                    let e = &b[14 + i * entry..14 + (i + 1) * entry];
                    let at = le(e, 0, 8)?;
                    if at == UNDEFINED {
                        continue;
                    }
                    let (size, mask) = if filtered {
                        (le(e, 8, entry - 12)?, le(e, entry - 4, 4)?)
                    } else {
                        (chunk_bytes, 0)
                    };
                    chunks.push(Chunk {
                        offsets: offsets(i as u64),
                        size,
                        mask,
                        at,
                    });
                }
            }
        }
        Ok(chunks)
    }

    /// A chunk's bytes with its filters undone (last applied first).
    fn unfilter(&self, d: &Dataset<'a>, c: &Chunk, chunk_bytes: u64) -> R<Vec<u8>> {
        let mut data = take(self.b, c.at, c.size)?.to_vec();
        for (i, &f) in d.filters.iter().enumerate().rev() {
            if c.mask & (1 << i) != 0 {
                continue;
            }
            data = match f {
                1 => {
                    let mut out = Vec::with_capacity(chunk_bytes.min(64 << 20) as usize);
                    flate2::read::ZlibDecoder::new(&data[..])
                        .take(chunk_bytes)
                        .read_to_end(&mut out)
                        .map_err(|e| format!("a chunk does not inflate ({e})"))?;
                    out
                }
                _ => unshuffle(&data, d.dtype.size()),
            };
        }
        if (data.len() as u64) < chunk_bytes {
            return Err(format!(
                "a chunk holds {} bytes, {chunk_bytes} expected",
                data.len()
            ));
        }
        Ok(data)
    }
}

/// Undo the shuffle filter: byte `j` of every element was stored in the `j`-th plane.
fn unshuffle(data: &[u8], size: usize) -> Vec<u8> {
    let n = data.len() / size.max(1);
    if size <= 1 || n == 0 {
        return data.to_vec();
    }
    let mut out = data.to_vec();
    for j in 0..size {
        for i in 0..n {
            out[i * size + j] = data[j * n + i];
        }
    }
    out
}

/// Copy a chunk (dimensions `chunk`, at element `offsets`) into the row-major array of
/// dimensions `dims`, dropping what lies past the array's edges.
fn place(
    out: &mut [u8],
    dims: &[u64],
    chunk: &[u64],
    offsets: &[u64],
    esize: usize,
    data: &[u8],
) -> R<()> {
    let rank = dims.len();
    if offsets.iter().zip(dims).any(|(o, d)| o >= d) {
        return Err(format!(
            "a chunk at {offsets:?} lies outside the data {dims:?}"
        ));
    }
    let last = rank - 1;
    let run = chunk[last].min(dims[last] - offsets[last]) as usize * esize;
    // Odometer over the chunk's rows (all dimensions but the last).
    let mut idx = vec![0u64; last];
    loop {
        if idx
            .iter()
            .enumerate()
            .all(|(k, &i)| offsets[k] + i < dims[k])
        {
            let (mut src, mut dst) = (0u64, 0u64);
            for k in 0..rank {
                let (ci, gi) = if k < last {
                    (idx[k], offsets[k] + idx[k])
                } else {
                    (0, offsets[k])
                };
                src = src * chunk[k] + ci;
                dst = dst * dims[k] + gi;
            }
            let (s, t) = (src as usize * esize, dst as usize * esize);
            let from = data.get(s..s + run).ok_or("a chunk is short")?;
            out.get_mut(t..t + run)
                .ok_or("a chunk lies outside the data")?
                .copy_from_slice(from);
        }
        let mut k = last;
        loop {
            if k == 0 {
                return Ok(());
            }
            k -= 1;
            idx[k] += 1;
            if idx[k] < chunk[k] {
                break;
            }
            idx[k] = 0;
        }
    }
}
