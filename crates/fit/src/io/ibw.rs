//! Igor binary waves (`.ibw`, version 5; Asylum Research AFMs). A 64-byte binary header
//! (version, checksum, section sizes) and a 320-byte wave header (point count, data type,
//! dimension sizes, per-dimension scale `sfA`, units) whose 16-bit words sum to zero
//! with the binary header; then the data (x fastest, one layer per channel), the
//! formula, the note (Asylum: `Key: value` lines such as `HeightRetraceUnit`), extended
//! units and the dimension labels (32 bytes each; the third dimension's labels name the
//! channels). Byte order follows the version word.

use super::binary::{Sample, decode};
use super::{
    ChannelInfo, Ctx, Decoded, Raw, Sniff, Unit, Want, check_spacing, checked_grid, units,
};
use crate::ReadError;

const HEADERS: usize = 64 + 320;

/// Content check: version 5 and a zero header checksum.
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if b.len() < HEADERS {
        return Sniff::No;
    }
    let little = b[0] != 0;
    let version = if little {
        b[0] as u16 | (b[1] as u16) << 8
    } else {
        b[1] as u16 | (b[0] as u16) << 8
    };
    if version == 5 && checksum(&b[..HEADERS], little) == 0 {
        Sniff::Magic
    } else {
        Sniff::No
    }
}

/// A version word of an Igor binary wave (1, 2, 3 or 5) in either byte order: the
/// format's signature, looser than [`sniff`] so that a file of an older version gets the
/// reader's explanation rather than being called damaged.
pub(crate) fn has_version_word(b: &[u8]) -> bool {
    match b {
        [0, v, ..] | [v, 0, ..] => matches!(v, 1 | 2 | 3 | 5),
        _ => false,
    }
}

fn checksum(h: &[u8], little: bool) -> u16 {
    h.chunks_exact(2).fold(0u16, |s, c| {
        let w = if little {
            u16::from_le_bytes([c[0], c[1]])
        } else {
            u16::from_be_bytes([c[0], c[1]])
        };
        s.wrapping_add(w)
    })
}

struct Reader<'a> {
    b: &'a [u8],
    little: bool,
}

impl Reader<'_> {
    fn u16(&self, o: usize) -> u16 {
        let c = [self.b[o], self.b[o + 1]];
        if self.little {
            u16::from_le_bytes(c)
        } else {
            u16::from_be_bytes(c)
        }
    }
    fn u32(&self, o: usize) -> u32 {
        let c = [self.b[o], self.b[o + 1], self.b[o + 2], self.b[o + 3]];
        if self.little {
            u32::from_le_bytes(c)
        } else {
            u32::from_be_bytes(c)
        }
    }
    fn f64(&self, o: usize) -> f64 {
        let mut c = [0u8; 8];
        c.copy_from_slice(&self.b[o..o + 8]);
        if self.little {
            f64::from_le_bytes(c)
        } else {
            f64::from_be_bytes(c)
        }
    }
    fn text(&self, o: usize, n: usize) -> String {
        super::binary::cstr(&self.b[o..o + n])
    }
}

/// Units Asylum writes, and the usual ones for channel names it leaves without a unit.
fn channel_unit(name: &str, note: &[(String, String)], wave_unit: &str) -> String {
    let key = format!("{name}Unit");
    if let Some((_, v)) = note.iter().find(|(k, _)| k.eq_ignore_ascii_case(&key)) {
        return v.clone();
    }
    let n = name.to_ascii_lowercase();
    if n.starts_with("phase") {
        "deg".into()
    } else if n.contains("potential") || n.contains("bias") || n.contains("voltage") {
        "V".into()
    } else if n.contains("current") {
        "A".into()
    } else if n.starts_with("height")
        || n.starts_with("zsensor")
        || n.starts_with("amplitude")
        || n.starts_with("deflection")
    {
        "m".into()
    } else {
        wave_unit.to_string()
    }
}

/// Heights are the channels named like heights (or, for a single unnamed channel, the
/// wave itself when its unit is a length).
fn is_height_name(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.starts_with("height") || n.starts_with("zsensor") || n.starts_with("topograph")
}

/// The fields of the binary and wave headers this reader uses.
struct Headers {
    little: bool,
    /// Bytes of the wave header and data.
    wfm_size: u64,
    formula: u64,
    note_size: u64,
    data_e_units: u64,
    dim_e_units: [u64; 4],
    dim_labels: [u64; 4],
    npts: u64,
    kind: Sample,
    dims: [u64; 4],
    /// Per-dimension spacing.
    sfa: [f64; 4],
    data_unit: String,
    dim_unit: [String; 4],
}

/// Where the data lie and how they are shaped.
struct Layout {
    nx: u64,
    ny: u64,
    /// Channels (layers).
    nch: u64,
    /// Points per channel.
    per: u64,
    data_start: u64,
    data_end: u64,
}

/// What the sections after the data say: the note's key-value pairs, the wave's unit,
/// the lateral unit and the channel names.
struct Trailer {
    note: Vec<(String, String)>,
    wave_unit: String,
    lateral_unit: String,
    names: Vec<String>,
}

/// Read an Igor binary wave.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let h = headers(ctx, bytes)?;
    let l = layout(ctx, &h, bytes)?;
    let t = trailer(bytes, &h, &l);
    let (nx, ny) = (l.nx, l.ny);
    let named = t.names.iter().any(|n| !n.starts_with("channel "));
    let channels: Vec<ChannelInfo> = t
        .names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let unit = channel_unit(n, &t.note, &t.wave_unit);
            let is_height = if named {
                is_height_name(n) && units::length_factor(&unit).is_some()
            } else {
                // Unnamed channels: a height if the unit is a length or not stated.
                unit.is_empty() || units::length_factor(&unit).is_some()
            };
            ChannelInfo {
                index: i,
                name: n.clone(),
                unit,
                is_height,
                nx: nx as usize,
                ny: ny as usize,
            }
        })
        .collect();
    let (kind, per, data_end) = (h.kind, l.per, l.data_end);
    Decoded::pick(ctx, want, channels, |selected, channel| {
        let size = kind.size() as u64;
        let off = l.data_start + per * size * selected as u64;
        let block = &bytes[off as usize..data_end as usize];
        let heights = decode(block, kind, h.little, per as usize)
            .ok_or_else(|| ctx.short("wave data", off + per * size, data_end))?;
        let hu = match units::length_factor(&channel.unit) {
            Some(f) => Unit::Known(f),
            None => Unit::Unknown,
        };
        let lu = match units::length_factor(&t.lateral_unit) {
            Some(f) => Unit::Known(f),
            None => Unit::Unknown,
        };
        let dx = check_spacing(ctx, "sfA[0]", h.sfa[0].abs())?;
        let dy = if ny == 1 {
            dx
        } else {
            check_spacing(ctx, "sfA[1]", h.sfa[1].abs())?
        };
        let raw = Raw::si(nx as usize, ny as usize, dx, dy, heights, &channel.name)
            .spacing_from("sfA[0]", "sfA[1]");
        Ok(raw.in_units(hu, lu))
    })
}

/// The version-5 headers, checked against their checksum.
fn headers(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Headers, ReadError> {
    if bytes.len() < HEADERS {
        return Err(ctx.short("headers", HEADERS as u64, bytes.len() as u64));
    }
    let little = bytes[0] != 0;
    let r = Reader { b: bytes, little };
    let version = r.u16(0);
    if version != 5 {
        return Err(ctx.err(
            "version",
            format!("Igor binary wave version {version}; only version 5 holds 2D data"),
            "save the wave as an Igor Pro 5+ binary wave",
        ));
    }
    if checksum(&bytes[..HEADERS], little) != 0 {
        return Err(ctx.err(
            "checksum",
            "the header checksum does not add up",
            "the file is corrupt; re-export it",
        ));
    }
    // The wave header follows the 64-byte binary header.
    let w = 64;
    let kind = match r.u16(w + 16) {
        0x02 => Sample::F32,
        0x04 => Sample::F64,
        0x08 => Sample::I8,
        0x10 => Sample::I16,
        0x20 => Sample::I32,
        0x48 => Sample::U8,
        0x50 => Sample::U16,
        0x60 => Sample::U32,
        t => {
            return Err(ctx.err(
                "type",
                format!("wave data type 0x{t:02x} is not supported (complex or text)"),
                "export a real-valued image wave",
            ));
        }
    };
    Ok(Headers {
        little,
        wfm_size: r.u32(4) as u64,
        formula: r.u32(8) as u64,
        note_size: r.u32(12) as u64,
        data_e_units: r.u32(16) as u64,
        dim_e_units: std::array::from_fn(|i| r.u32(20 + 4 * i) as u64),
        dim_labels: std::array::from_fn(|i| r.u32(36 + 4 * i) as u64),
        npts: r.u32(w + 12) as u64,
        kind,
        dims: std::array::from_fn(|i| r.u32(w + 68 + 4 * i) as u64),
        sfa: std::array::from_fn(|i| r.f64(w + 84 + 8 * i)),
        data_unit: r.text(w + 148, 4),
        dim_unit: std::array::from_fn(|i| r.text(w + 152 + 4 * i, 4)),
    })
}

/// The grid and where its data lie, checked against the point count, the wave size and
/// the file's length (the sections after the data included).
fn layout(ctx: Ctx<'_>, h: &Headers, bytes: &[u8]) -> Result<Layout, ReadError> {
    let (nx, ny) = (h.dims[0], h.dims[1].max(1));
    let nch = h.dims[2].max(1);
    if h.dims[3] > 1 {
        return Err(ctx.err(
            "nDim",
            "four-dimensional waves are not supported",
            "export one image stack",
        ));
    }
    let per = checked_grid(ctx, "nDim", nx, ny, 1, u64::MAX)? as u64;
    let total = per.saturating_mul(nch);
    let npts = h.npts;
    if total != npts {
        return Err(ctx.err(
            "npnts",
            format!("{npts} points do not match the dimensions {nx} × {ny} × {nch}"),
            "the file is corrupt",
        ));
    }
    let data_bytes = total.saturating_mul(h.kind.size() as u64);
    let wfm_size = h.wfm_size;
    if wfm_size < 320 || wfm_size - 320 < data_bytes {
        return Err(ctx.err(
            "wfmSize",
            format!("{wfm_size} bytes cannot hold {npts} points"),
            "the file is corrupt",
        ));
    }
    let data_start = HEADERS as u64;
    let data_end = data_start + (wfm_size - 320);
    if data_end > bytes.len() as u64 {
        return Err(ctx.short("wave data", data_end, bytes.len() as u64));
    }
    // Note, then extended units, then labels. They name the channels and give their
    // units, so a file cut inside them is refused rather than read with guessed ones.
    let sections = [
        ("formulaSize", h.formula),
        ("noteSize", h.note_size),
        ("dataEUnitsSize", h.data_e_units),
        ("dimEUnitsSize", h.dim_e_units.iter().sum()),
        ("dimLabelsSize", h.dim_labels.iter().sum()),
    ];
    let mut end = data_end;
    for (field, size) in sections {
        let start = end;
        end = end.saturating_add(size);
        if end > bytes.len() as u64 {
            return Err(ctx.truncated(
                field,
                &format!("{size} bytes of the wave's {field} section"),
                (start, end),
                bytes.len() as u64,
            ));
        }
    }
    Ok(Layout {
        nx,
        ny,
        nch,
        per,
        data_start,
        data_end,
    })
}

/// The note, the extended units and the channel labels after the data (their sizes
/// already checked by [`layout`]).
fn trailer(bytes: &[u8], h: &Headers, l: &Layout) -> Trailer {
    let note_start = l.data_end + h.formula;
    let note: Vec<(String, String)> = bytes
        .get(note_start as usize..(note_start + h.note_size).min(bytes.len() as u64) as usize)
        .map(|n| {
            n.iter()
                .map(|&c| c as char)
                .collect::<String>()
                .split(['\r', '\n'])
                .filter_map(|l| l.split_once(':'))
                .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
                .collect()
        })
        .unwrap_or_default();
    let mut p = note_start + h.note_size;
    let ext = |p: u64, n: u64| -> Option<String> {
        (n > 0).then(|| {
            bytes
                .get(p as usize..(p + n).min(bytes.len() as u64) as usize)
                .map(super::binary::cstr)
                .unwrap_or_default()
        })
    };
    let wave_unit = ext(p, h.data_e_units).unwrap_or_else(|| h.data_unit.clone());
    p += h.data_e_units;
    let lateral_unit = ext(p, h.dim_e_units[0]).unwrap_or_else(|| h.dim_unit[0].clone());
    p += h.dim_e_units.iter().sum::<u64>();
    p += h.dim_labels[0] + h.dim_labels[1];
    let mut names: Vec<String> = Vec::new();
    if h.dim_labels[2] >= 64 {
        let lab = bytes
            .get(p as usize..(p + h.dim_labels[2]).min(bytes.len() as u64) as usize)
            .unwrap_or(&[]);
        // The first label names the dimension itself.
        names = lab.chunks(32).skip(1).map(super::binary::cstr).collect();
    }
    names.truncate(l.nch as usize);
    while names.len() < l.nch as usize {
        names.push(format!("channel {}", names.len()));
    }
    Trailer {
        note,
        wave_unit,
        lateral_unit,
        names,
    }
}
