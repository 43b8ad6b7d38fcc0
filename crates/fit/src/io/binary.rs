//! Decoding packed binary samples with bounds checks.

/// Binary sample types found in surface files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sample {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// IEEE single.
    F32,
    /// IEEE double.
    F64,
}

impl Sample {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            Sample::U8 | Sample::I8 => 1,
            Sample::U16 | Sample::I16 => 2,
            Sample::U32 | Sample::I32 | Sample::F32 => 4,
            Sample::F64 => 8,
        }
    }

    /// True for floating-point types.
    pub fn is_float(self) -> bool {
        matches!(self, Sample::F32 | Sample::F64)
    }

    /// The type of a TIFF image's samples from its `SampleFormat` (tag 339: 1 unsigned,
    /// 2 signed, 3 IEEE) and `BitsPerSample` (tag 258); `None` for what no reader takes.
    pub fn from_tiff(format: u64, bits: u64) -> Option<Sample> {
        Some(match (format, bits) {
            (1, 8) => Sample::U8,
            (1, 16) => Sample::U16,
            (1, 32) => Sample::U32,
            (2, 16) => Sample::I16,
            (2, 32) => Sample::I32,
            (3, 32) => Sample::F32,
            (3, 64) => Sample::F64,
            _ => return None,
        })
    }
}

/// Decode `count` samples from the start of `data`. Returns `None` if `data` is too short.
/// Non-finite floats are returned as they are (callers decide what is invalid).
pub fn decode(data: &[u8], kind: Sample, little_endian: bool, count: usize) -> Option<Vec<f64>> {
    let size = kind.size();
    let need = count.checked_mul(size)?;
    let bytes = data.get(..need)?;
    let mut out = Vec::with_capacity(count);
    for c in bytes.chunks_exact(size) {
        let v = match (kind, little_endian) {
            (Sample::U8, _) => c[0] as f64,
            (Sample::I8, _) => c[0] as i8 as f64,
            (Sample::U16, true) => u16::from_le_bytes([c[0], c[1]]) as f64,
            (Sample::U16, false) => u16::from_be_bytes([c[0], c[1]]) as f64,
            (Sample::I16, true) => i16::from_le_bytes([c[0], c[1]]) as f64,
            (Sample::I16, false) => i16::from_be_bytes([c[0], c[1]]) as f64,
            (Sample::U32, true) => u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::U32, false) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::I32, true) => i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::I32, false) => i32::from_be_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::F32, true) => f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::F32, false) => f32::from_be_bytes([c[0], c[1], c[2], c[3]]) as f64,
            (Sample::F64, le) => {
                let mut b = [0u8; 8];
                b.copy_from_slice(c);
                if le {
                    f64::from_le_bytes(b)
                } else {
                    f64::from_be_bytes(b)
                }
            }
        };
        out.push(v);
    }
    Some(out)
}

/// Read a little-endian u16 at `off`.
pub fn le_u16(data: &[u8], off: usize) -> Option<u16> {
    Some(u16::from_le_bytes(data.get(off..off + 2)?.try_into().ok()?))
}

/// Read a little-endian f64 at `off`.
pub fn le_f64(data: &[u8], off: usize) -> Option<f64> {
    Some(f64::from_le_bytes(data.get(off..off + 8)?.try_into().ok()?))
}

/// A bounds-checked reader of fixed-layout binary headers. Every getter returns `None`
/// past the end instead of panicking.
#[derive(Debug, Clone)]
pub struct Cursor<'a> {
    data: &'a [u8],
    /// Current offset.
    pub pos: usize,
    little: bool,
}

impl<'a> Cursor<'a> {
    /// A little-endian cursor at `pos`.
    pub fn le(data: &'a [u8], pos: usize) -> Self {
        Cursor {
            data,
            pos,
            little: true,
        }
    }

    /// A big-endian cursor at `pos`.
    pub fn be(data: &'a [u8], pos: usize) -> Self {
        Cursor {
            data,
            pos,
            little: false,
        }
    }

    /// Take `n` bytes.
    pub fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let b = self.data.get(self.pos..end)?;
        self.pos = end;
        Some(b)
    }

    /// Skip `n` bytes (may move to the end exactly).
    pub fn skip(&mut self, n: usize) -> Option<()> {
        self.bytes(n).map(|_| ())
    }

    fn arr<const N: usize>(&mut self) -> Option<[u8; N]> {
        let mut a: [u8; N] = self.bytes(N)?.try_into().ok()?;
        if !self.little {
            a.reverse();
        }
        Some(a)
    }

    /// Unsigned byte.
    pub fn u8(&mut self) -> Option<u8> {
        Some(self.bytes(1)?[0])
    }
    /// Unsigned 16-bit.
    pub fn u16(&mut self) -> Option<u16> {
        Some(u16::from_le_bytes(self.arr()?))
    }
    /// Signed 16-bit.
    pub fn i16(&mut self) -> Option<i16> {
        Some(i16::from_le_bytes(self.arr()?))
    }
    /// Unsigned 32-bit.
    pub fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.arr()?))
    }
    /// Signed 32-bit.
    pub fn i32(&mut self) -> Option<i32> {
        Some(i32::from_le_bytes(self.arr()?))
    }
    /// Unsigned 64-bit.
    pub fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.arr()?))
    }
    /// IEEE single.
    pub fn f32(&mut self) -> Option<f64> {
        Some(f32::from_le_bytes(self.arr()?) as f64)
    }
    /// IEEE double.
    pub fn f64(&mut self) -> Option<f64> {
        Some(f64::from_le_bytes(self.arr()?))
    }
    /// A fixed-size text field, cut at the first NUL, Latin-1, trimmed.
    pub fn text(&mut self, n: usize) -> Option<String> {
        Some(cstr(self.bytes(n)?))
    }
}

/// Latin-1 text up to the first NUL, trimmed.
pub fn cstr(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    b[..end]
        .iter()
        .map(|&c| c as char)
        .collect::<String>()
        .trim()
        .to_string()
}
