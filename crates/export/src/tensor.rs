//! The "tensor file" container of the RGL material database: named,
//! typed, n-dimensional arrays, little-endian.
//!
//! Layout (as Mitsuba 3's `TensorFile` and pbrt-v4's `Tensor` read it):
//!
//! ```text
//! "tensor_file\0"            12 bytes
//! version                    2 × u8 = 1, 0
//! field count                u32
//! per field:  name length u16, name (UTF-8), rank u16, dtype u8,
//!             data offset u64 (from the start of the file), shape: rank × u64
//! data of each field at its offset (this writer aligns offsets to 8 bytes)
//! ```
//!
//! dtype codes: 1 u8, 2 i8, 3 u16, 4 i16, 5 u32, 6 i32, 7 u64, 8 i64,
//! 9 f16, 10 f32, 11 f64. The measured-BSDF fields use only u8 and f32, so
//! the reader here accepts those two and names any other.

use crate::ExportError;

const MAGIC: &[u8; 12] = b"tensor_file\0";
const ALIGN: usize = 8;
/// More fields than any measured-BSDF file has; bounds the header walk.
const MAX_FIELDS: u32 = 256;
/// Rank bound (the measured format's largest is 5).
const MAX_RANK: u16 = 16;

/// Element type of a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dtype {
    /// Unsigned byte (code 1).
    U8,
    /// IEEE single precision (code 10).
    F32,
}

impl Dtype {
    fn code(self) -> u8 {
        match self {
            Dtype::U8 => 1,
            Dtype::F32 => 10,
        }
    }

    fn size(self) -> usize {
        match self {
            Dtype::U8 => 1,
            Dtype::F32 => 4,
        }
    }
}

/// One named array.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Its name (`spectra`, `theta_i`, …).
    pub name: String,
    /// Element type.
    pub dtype: Dtype,
    /// Size along each dimension, slowest first.
    pub shape: Vec<usize>,
    /// The elements, little-endian, row-major.
    pub bytes: Vec<u8>,
}

impl Field {
    /// An f32 array of the given shape (`values.len()` must be its product).
    pub fn f32(name: &str, shape: &[usize], values: &[f32]) -> Field {
        debug_assert_eq!(shape.iter().product::<usize>(), values.len());
        Field {
            name: name.to_string(),
            dtype: Dtype::F32,
            shape: shape.to_vec(),
            bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    /// A u8 vector.
    pub fn u8(name: &str, values: &[u8]) -> Field {
        Field {
            name: name.to_string(),
            dtype: Dtype::U8,
            shape: vec![values.len()],
            bytes: values.to_vec(),
        }
    }

    /// The elements as f32 (the caller has checked `dtype`).
    pub fn to_f32(&self) -> Vec<f32> {
        self.bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }
}

/// The file holding `fields`, in order.
pub fn write(fields: &[Field]) -> Vec<u8> {
    let header: usize = 12
        + 2
        + 4
        + fields
            .iter()
            .map(|f| 2 + f.name.len() + 2 + 1 + 8 + 8 * f.shape.len())
            .sum::<usize>();
    let mut offsets = Vec::with_capacity(fields.len());
    let mut end = header;
    for f in fields {
        let at = end.div_ceil(ALIGN) * ALIGN;
        offsets.push(at);
        end = at + f.bytes.len();
    }
    let mut out = Vec::with_capacity(end);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    for (f, &at) in fields.iter().zip(&offsets) {
        out.extend_from_slice(&(f.name.len() as u16).to_le_bytes());
        out.extend_from_slice(f.name.as_bytes());
        out.extend_from_slice(&(f.shape.len() as u16).to_le_bytes());
        out.push(f.dtype.code());
        out.extend_from_slice(&(at as u64).to_le_bytes());
        for &s in &f.shape {
            out.extend_from_slice(&(s as u64).to_le_bytes());
        }
    }
    for (f, &at) in fields.iter().zip(&offsets) {
        out.resize(at, 0);
        out.extend_from_slice(&f.bytes);
    }
    out
}

/// A little-endian cursor over the header that names what it was reading
/// when the file ends.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ExportError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(bad(format!(
                "the file ends at byte {} inside the header ({what})",
                self.bytes.len()
            )));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u16(&mut self, what: &str) -> Result<u16, ExportError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    fn u64(&mut self, what: &str) -> Result<u64, ExportError> {
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
}

fn bad(message: String) -> ExportError {
    ExportError::Parse {
        what: "tensor file",
        message,
    }
}

/// Every field of a tensor file. Sizes are checked against the file's
/// length before anything is copied, so a corrupt header is an error, never
/// a huge allocation.
pub fn read(bytes: &[u8]) -> Result<Vec<Field>, ExportError> {
    let mut c = Cursor { bytes, at: 0 };
    if c.take(12, "magic")? != MAGIC {
        return Err(bad(
            "not a tensor file: it does not start with \"tensor_file\\0\"".into(),
        ));
    }
    let version = c.take(2, "version")?;
    if version != [1, 0] {
        return Err(bad(format!(
            "version {}.{}: only 1.0 is defined",
            version[0], version[1]
        )));
    }
    let n = {
        let b = c.take(4, "field count")?;
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    };
    if n > MAX_FIELDS {
        return Err(bad(format!("{n} fields: more than {MAX_FIELDS}")));
    }
    let mut fields: Vec<Field> = Vec::with_capacity(n as usize);
    for i in 0..n {
        let len = c.u16("field name length")? as usize;
        let name = std::str::from_utf8(c.take(len, "field name")?)
            .map_err(|_| bad(format!("field {i}: its name is not UTF-8")))?
            .to_string();
        let rank = c.u16("rank")?;
        if rank > MAX_RANK {
            return Err(bad(format!("field {name:?}: rank {rank} above {MAX_RANK}")));
        }
        let code = c.take(1, "dtype")?[0];
        let dtype = match code {
            1 => Dtype::U8,
            10 => Dtype::F32,
            _ => {
                return Err(bad(format!(
                    "field {name:?}: dtype code {code}; a measured BSDF holds only u8 (1) and \
                     f32 (10)"
                )));
            }
        };
        let offset = c.u64("data offset")?;
        let mut shape = Vec::with_capacity(rank as usize);
        let mut count: u64 = 1;
        for _ in 0..rank {
            let s = c.u64("shape")?;
            count = count
                .checked_mul(s)
                .ok_or_else(|| bad(format!("field {name:?}: its shape overflows")))?;
            shape.push(s);
        }
        let size = count
            .checked_mul(dtype.size() as u64)
            .ok_or_else(|| bad(format!("field {name:?}: its size overflows")))?;
        let end = offset
            .checked_add(size)
            .filter(|&e| e <= bytes.len() as u64);
        let Some(end) = end else {
            return Err(bad(format!(
                "field {name:?}: {size} bytes at offset {offset} run past the end of the \
                 {}-byte file (truncated?)",
                bytes.len()
            )));
        };
        if fields.iter().any(|f| f.name == name) {
            return Err(bad(format!("field {name:?} appears twice")));
        }
        fields.push(Field {
            name,
            dtype,
            shape: shape.iter().map(|&s| s as usize).collect(),
            bytes: bytes[offset as usize..end as usize].to_vec(),
        });
    }
    Ok(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_alignment() {
        let fields = vec![
            Field::u8("description", b"abc"),
            Field::f32("theta_i", &[2], &[0.0, 1.5]),
            Field::f32("ndf", &[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
        ];
        let bytes = write(&fields);
        assert_eq!(read(&bytes).unwrap(), fields);
        // Each field's data offset is a multiple of 8.
        let back = read(&bytes).unwrap();
        assert_eq!(back[2].to_f32(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(&bytes[..12], MAGIC);
        let first_offset = u64::from_le_bytes(
            bytes[12 + 2 + 4 + 2 + 11 + 2 + 1..][..8]
                .try_into()
                .unwrap(),
        );
        assert_eq!(first_offset % 8, 0);
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let bytes = write(&[
            Field::u8("jacobian", &[1]),
            Field::f32("spectra", &[1, 2, 2], &[1.0; 4]),
        ]);
        for n in 0..bytes.len() {
            assert!(read(&bytes[..n]).is_err(), "prefix of {n} bytes");
        }
    }

    #[test]
    fn a_huge_shape_is_refused_before_allocating() {
        let mut bytes = write(&[Field::f32("x", &[1], &[1.0])]);
        // shape[0] sits right after name (1 byte), rank, dtype and offset.
        let at = 12 + 2 + 4 + 2 + 1 + 2 + 1 + 8;
        bytes[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let e = read(&bytes).unwrap_err().to_string();
        assert!(e.contains("overflows"), "{e}");
        bytes[at..at + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
        let e = read(&bytes).unwrap_err().to_string();
        assert!(e.contains("run past the end"), "{e}");
    }
}
