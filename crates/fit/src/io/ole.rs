//! Microsoft compound files (OLE2/CFB, the container of `.mnt` documents): a 512-byte
//! header, sectors chained through the FAT (located by the DIFAT), a directory of
//! 128-byte entries, and small streams kept in the mini stream with its own mini FAT.
//! Only reading a named stream is supported. Every chain is bounded by the number of
//! sectors, so loops in a corrupt FAT end in an error, not a hang.

const MAGIC: &[u8] = b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1";
const END_OF_CHAIN: u32 = 0xFFFF_FFFE;
const FREE: u32 = 0xFFFF_FFFF;

/// A parsed compound file.
pub struct Ole<'a> {
    data: &'a [u8],
    sector: usize,
    mini_sector: usize,
    mini_cutoff: u64,
    fat: Vec<u32>,
    minifat: Vec<u32>,
    entries: Vec<Entry>,
    ministream: Vec<u8>,
}

/// One directory entry.
#[derive(Debug, Clone)]
pub struct Entry {
    /// Name (UTF-16 in the file).
    pub name: String,
    /// 1 storage, 2 stream, 5 root.
    pub kind: u8,
    start: u32,
    /// Stream size in bytes.
    pub size: u64,
}

/// True if `b` starts with the compound-file signature.
pub fn is_ole(b: &[u8]) -> bool {
    b.starts_with(MAGIC)
}

fn u16_at(b: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(o..o + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], o: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(o..o + 8)?.try_into().ok()?))
}

impl<'a> Ole<'a> {
    /// Parse the header, FAT, directory and mini stream. Errors are short descriptions.
    pub fn parse(data: &'a [u8]) -> Result<Ole<'a>, String> {
        if !is_ole(data) || data.len() < 512 {
            return Err("not a compound (OLE) file".into());
        }
        let shift = u16_at(data, 0x1E).ok_or("header truncated")?;
        let mini_shift = u16_at(data, 0x20).ok_or("header truncated")?;
        if !(shift == 9 || shift == 12) || mini_shift != 6 {
            return Err(format!(
                "sector shift {shift}/{mini_shift} is not 9 or 12 / 6"
            ));
        }
        let sector = 1usize << shift;
        let nsectors = data.len().saturating_sub(sector) / sector + 1;
        let n_fat = u32_at(data, 0x2C).ok_or("header truncated")? as usize;
        let dir_start = u32_at(data, 0x30).ok_or("header truncated")?;
        let mini_cutoff = u32_at(data, 0x38).ok_or("header truncated")? as u64;
        let minifat_start = u32_at(data, 0x3C).ok_or("header truncated")?;
        let mut difat_sector = u32_at(data, 0x44).ok_or("header truncated")?;
        if n_fat > nsectors {
            return Err(format!("{n_fat} FAT sectors in a file of {nsectors}"));
        }
        // FAT sector list: 109 entries in the header, then DIFAT sectors.
        let mut fat_sectors = Vec::with_capacity(n_fat);
        for i in 0..109 {
            let s = u32_at(data, 0x4C + 4 * i).ok_or("header truncated")?;
            if s != FREE && fat_sectors.len() < n_fat {
                fat_sectors.push(s);
            }
        }
        let per = sector / 4;
        let mut guard = 0;
        while fat_sectors.len() < n_fat && difat_sector != END_OF_CHAIN && difat_sector != FREE {
            guard += 1;
            if guard > nsectors {
                return Err("DIFAT chain loops".into());
            }
            let off = (difat_sector as usize + 1) * sector;
            for i in 0..per - 1 {
                let s = u32_at(data, off + 4 * i).ok_or("DIFAT sector beyond the end")?;
                if s != FREE && fat_sectors.len() < n_fat {
                    fat_sectors.push(s);
                }
            }
            difat_sector = u32_at(data, off + 4 * (per - 1)).ok_or("DIFAT truncated")?;
        }
        let mut fat = Vec::with_capacity(fat_sectors.len() * per);
        for s in fat_sectors {
            let off = (s as usize + 1)
                .checked_mul(sector)
                .ok_or("FAT sector number overflows")?;
            let b = data
                .get(off..off + sector)
                .ok_or("FAT sector beyond the end of the file")?;
            fat.extend(
                b.chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            );
        }
        let mut ole = Ole {
            data,
            sector,
            mini_sector: 64,
            mini_cutoff,
            fat,
            minifat: Vec::new(),
            entries: Vec::new(),
            ministream: Vec::new(),
        };
        let dir = ole.chain(dir_start, None)?;
        for e in dir.chunks_exact(128) {
            let len = u16_at(e, 64).unwrap_or(0).min(64) as usize;
            let units: Vec<u16> = e[..len.saturating_sub(2)]
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes([c[0], c[1]]))
                .collect();
            ole.entries.push(Entry {
                name: String::from_utf16_lossy(&units),
                kind: e[66],
                start: u32_at(e, 116).unwrap_or(END_OF_CHAIN),
                // Version-3 files (512-byte sectors) keep only 32 bits of the size.
                size: u64_at(e, 120).unwrap_or(0)
                    & if sector == 512 { 0xFFFF_FFFF } else { u64::MAX },
            });
        }
        if minifat_start != END_OF_CHAIN && minifat_start != FREE {
            let mf = ole.chain(minifat_start, None)?;
            ole.minifat = mf
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
        }
        if let Some(root) = ole.entries.iter().find(|e| e.kind == 5).cloned()
            && root.start != END_OF_CHAIN
        {
            ole.ministream = ole.chain(root.start, Some(root.size))?;
        }
        Ok(ole)
    }

    /// Follow a chain of big sectors; `size` truncates the result.
    fn chain(&self, start: u32, size: Option<u64>) -> Result<Vec<u8>, String> {
        let limit = size.unwrap_or(u64::MAX);
        if limit != u64::MAX && limit > self.data.len() as u64 {
            return Err(format!(
                "a stream claims {limit} bytes in a {} byte file",
                self.data.len()
            ));
        }
        let mut out = Vec::new();
        let mut s = start;
        let mut steps = 0;
        while s != END_OF_CHAIN {
            steps += 1;
            if steps > self.fat.len() + 1 {
                return Err("sector chain loops".into());
            }
            let off = (s as usize + 1)
                .checked_mul(self.sector)
                .ok_or("sector number overflows")?;
            let b = self
                .data
                .get(off..off + self.sector)
                .or_else(|| self.data.get(off..))
                .filter(|b| !b.is_empty())
                .ok_or_else(|| format!("sector {s} lies beyond the end of the file"))?;
            out.extend_from_slice(b);
            if out.len() as u64 >= limit {
                break;
            }
            s = *self
                .fat
                .get(s as usize)
                .ok_or_else(|| format!("sector {s} is not in the FAT"))?;
        }
        if limit != u64::MAX {
            if (out.len() as u64) < limit {
                return Err("a stream is shorter than its directory entry says".into());
            }
            out.truncate(limit as usize);
        }
        Ok(out)
    }

    fn mini_chain(&self, start: u32, size: u64) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        let mut s = start;
        let mut steps = 0;
        while s != END_OF_CHAIN && (out.len() as u64) < size {
            steps += 1;
            if steps > self.minifat.len() + 1 {
                return Err("mini sector chain loops".into());
            }
            let off = s as usize * self.mini_sector;
            let b = self
                .ministream
                .get(off..off + self.mini_sector)
                .ok_or("mini sector beyond the mini stream")?;
            out.extend_from_slice(b);
            s = *self
                .minifat
                .get(s as usize)
                .ok_or("mini sector not in the mini FAT")?;
        }
        if (out.len() as u64) < size {
            return Err("a small stream is shorter than its directory entry says".into());
        }
        out.truncate(size as usize);
        Ok(out)
    }

    /// The directory entries.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// The contents of the first stream called `name`.
    pub fn stream(&self, name: &str) -> Result<Vec<u8>, String> {
        let e = self
            .entries
            .iter()
            .find(|e| e.kind == 2 && e.name == name)
            .ok_or_else(|| format!("no `{name}` stream"))?;
        if e.size < self.mini_cutoff {
            self.mini_chain(e.start, e.size)
        } else {
            self.chain(e.start, Some(e.size))
        }
    }
}
