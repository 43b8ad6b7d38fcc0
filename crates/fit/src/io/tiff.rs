//! The parts of TIFF (baseline, 6.0) that instrument formats hide their data in: the
//! header, the image file directories (pages) and their entries' values. Every offset is
//! checked against the file; a corrupt directory is an error, never a panic.

/// One directory entry with its raw value bytes.
#[derive(Debug, Clone)]
pub struct Entry<'a> {
    /// Tag number.
    pub tag: u16,
    /// Field type (1 BYTE, 2 ASCII, 3 SHORT, 4 LONG, 7 UNDEFINED, 11 FLOAT, 12 DOUBLE, …).
    pub kind: u16,
    /// Number of values.
    pub count: u32,
    /// The value bytes (inline or at the offset).
    pub value: &'a [u8],
}

/// A TIFF file's first directory.
#[derive(Debug, Clone)]
pub struct Tiff<'a> {
    /// Byte order of the file.
    pub little: bool,
    /// Entries of the first directory.
    pub entries: Vec<Entry<'a>>,
    /// True if further directories (pages) follow.
    pub more_pages: bool,
}

fn type_size(kind: u16) -> Option<u64> {
    Some(match kind {
        1 | 2 | 6 | 7 => 1,
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16 | 17 | 18 => 8,
        _ => return None,
    })
}

/// True for the two TIFF byte-order marks.
pub fn is_tiff(b: &[u8]) -> bool {
    b.starts_with(b"II*\0") || b.starts_with(b"MM\0*")
}

impl<'a> Tiff<'a> {
    /// Parse the header and the first directory.
    pub fn parse(b: &'a [u8]) -> Result<Tiff<'a>, String> {
        Tiff::parse_at(b, None).map(|(t, _)| t)
    }

    /// Parse the directory at byte `ifd` (the first one for `None`), with the offset of the
    /// next directory (0 at the last).
    pub fn parse_at(b: &'a [u8], ifd: Option<usize>) -> Result<(Tiff<'a>, usize), String> {
        if !is_tiff(b) {
            return Err("not a TIFF file".into());
        }
        let little = b[0] == b'I';
        let u16_at = |o: usize| -> Option<u16> {
            let c: [u8; 2] = b.get(o..o + 2)?.try_into().ok()?;
            Some(if little {
                u16::from_le_bytes(c)
            } else {
                u16::from_be_bytes(c)
            })
        };
        let u32_at = |o: usize| -> Option<u32> {
            let c: [u8; 4] = b.get(o..o + 4)?.try_into().ok()?;
            Some(if little {
                u32::from_le_bytes(c)
            } else {
                u32::from_be_bytes(c)
            })
        };
        let ifd = match ifd {
            Some(o) => o,
            None => u32_at(4).ok_or("header truncated")? as usize,
        };
        let n = u16_at(ifd).ok_or("the first directory lies beyond the end")? as usize;
        let mut entries = Vec::with_capacity(n);
        for i in 0..n {
            let e = ifd + 2 + 12 * i;
            let tag = u16_at(e).ok_or("directory truncated")?;
            let kind = u16_at(e + 2).ok_or("directory truncated")?;
            let count = u32_at(e + 4).ok_or("directory truncated")?;
            let Some(size) = type_size(kind) else {
                continue;
            };
            let len = size.saturating_mul(count as u64);
            let value = if len <= 4 {
                b.get(e + 8..e + 8 + len as usize)
                    .ok_or("directory truncated")?
            } else {
                let off = u32_at(e + 8).ok_or("directory truncated")? as u64;
                let end = off.saturating_add(len);
                if end > b.len() as u64 {
                    return Err(format!(
                        "tag {tag}: {len} bytes at offset {off} lie beyond the end of the file ({} bytes)",
                        b.len()
                    ));
                }
                &b[off as usize..end as usize]
            };
            entries.push(Entry {
                tag,
                kind,
                count,
                value,
            });
        }
        let next = u32_at(ifd + 2 + 12 * n).unwrap_or(0);
        Ok((
            Tiff {
                little,
                entries,
                more_pages: next != 0,
            },
            next as usize,
        ))
    }

    /// The first value of a DOUBLE (or FLOAT) entry.
    pub fn double(&self, tag: u16) -> Option<f64> {
        let e = self.get(tag)?;
        match e.kind {
            12 => {
                let c: [u8; 8] = e.value.get(..8)?.try_into().ok()?;
                Some(if self.little {
                    f64::from_le_bytes(c)
                } else {
                    f64::from_be_bytes(c)
                })
            }
            11 => {
                let c: [u8; 4] = e.value.get(..4)?.try_into().ok()?;
                Some(f64::from(if self.little {
                    f32::from_le_bytes(c)
                } else {
                    f32::from_be_bytes(c)
                }))
            }
            _ => None,
        }
    }

    /// An ASCII entry as text (up to its first NUL).
    pub fn text(&self, tag: u16) -> Option<String> {
        let e = self.get(tag).filter(|e| e.kind == 2)?;
        let end = e
            .value
            .iter()
            .position(|&c| c == 0)
            .unwrap_or(e.value.len());
        Some(String::from_utf8_lossy(&e.value[..end]).trim().to_string())
    }

    /// Every value of a SHORT or LONG entry (strip offsets and byte counts).
    pub fn uints(&self, tag: u16) -> Option<Vec<u64>> {
        let e = self.get(tag)?;
        let size = match e.kind {
            3 => 2,
            4 => 4,
            _ => return None,
        };
        Some(
            e.value
                .chunks_exact(size)
                .map(|c| {
                    let mut v = 0u64;
                    for (i, &x) in c.iter().enumerate() {
                        let shift = if self.little {
                            8 * i
                        } else {
                            8 * (size - 1 - i)
                        };
                        v |= u64::from(x) << shift;
                    }
                    v
                })
                .collect(),
        )
    }

    /// The entry with this tag.
    pub fn get(&self, tag: u16) -> Option<&Entry<'a>> {
        self.entries.iter().find(|e| e.tag == tag)
    }

    /// The first value of a SHORT or LONG entry.
    pub fn uint(&self, tag: u16) -> Option<u32> {
        let e = self.get(tag)?;
        match e.kind {
            3 => {
                let c: [u8; 2] = e.value.get(..2)?.try_into().ok()?;
                Some(if self.little {
                    u16::from_le_bytes(c)
                } else {
                    u16::from_be_bytes(c)
                } as u32)
            }
            4 => {
                let c: [u8; 4] = e.value.get(..4)?.try_into().ok()?;
                Some(if self.little {
                    u32::from_le_bytes(c)
                } else {
                    u32::from_be_bytes(c)
                })
            }
            _ => None,
        }
    }
}
