//! Digital Surf MountainsMap documents (`.mnt`): a compound (OLE) file whose
//! `ScopedContents` stream is a tree of tag–length–value records (u16 tag, u64 length).
//! The layout is not published; what is read here was established on real files (and
//! agrees with SurfaceTopography's description):
//!
//! * the main record (tag 1) holds the height data (record 0x2BD): a data-type byte
//!   (child 1; 12 = zero marks a point that was not measured, 39 = every value is a
//!   height) and a blob (child 2);
//! * the blob holds an axis description for x, y and then z (spacing f64 with its length
//!   unit, storage unit, ratio, offset, …; x and y then give their number of points) and
//!   the heights as int32 counts of the z spacing, x fastest, cut in zlib-compressed
//!   blocks, each after a 16-byte prefix (u64 first element, u32 element count, u32
//!   compressed size).
//!
//! Checked against `../bcrf-1.bcrf`, the same measurement exported as BCR: the counts
//! times the z spacing (1e-4 nm) reproduce its heights to float precision.
//!
//! The blocks must tile the grid exactly, so a misread layout is an error, not a wrong
//! map.

use super::{Ctx, Decoded, Raw, Sniff, Want, check_spacing, checked_grid, ole, units};
use crate::ReadError;
use std::io::Read;

/// Content check: a compound file (the directory is checked when reading).
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if ole::is_ole(b) {
        Sniff::Likely
    } else {
        Sniff::No
    }
}

/// One TLV record: tag and the byte range of its value.
#[derive(Debug, Clone, Copy)]
struct Rec {
    tag: u16,
    start: usize,
    end: usize,
}

/// Parse a run of TLV records filling `b[start..end]` exactly; `None` if they do not.
fn records(b: &[u8], start: usize, end: usize) -> Option<Vec<Rec>> {
    let mut out = Vec::new();
    let mut p = start;
    while p < end {
        let tag = u16::from_le_bytes(b.get(p..p + 2)?.try_into().ok()?);
        let len = u64::from_le_bytes(b.get(p + 2..p + 10)?.try_into().ok()?);
        let s = p + 10;
        let e = s.checked_add(usize::try_from(len).ok()?)?;
        if e > end {
            return None;
        }
        out.push(Rec {
            tag,
            start: s,
            end: e,
        });
        p = e;
        if out.len() > 1 << 20 {
            return None;
        }
    }
    Some(out)
}

fn child(b: &[u8], r: Rec, tag: u16) -> Option<Rec> {
    debug_assert!(r.end <= b.len());
    records(b, r.start, r.end)?
        .into_iter()
        .find(|c| c.tag == tag)
}

/// A length-prefixed UTF-16 string value (`04 b5 00 6d 00` = "µm").
fn ustr(v: &[u8]) -> Option<String> {
    let n = *v.first()? as usize;
    let units: Vec<u16> = v
        .get(1..1 + n)?
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    Some(String::from_utf16_lossy(&units))
}

/// An axis description: tag 1 = spacing (f64), tag 2 = its unit, tag 3 = storage unit,
/// …, then a record with tag 1 = number of points.
#[derive(Debug, Clone, Copy)]
struct Axis {
    spacing_m: f64,
    count: Option<u32>,
}

fn axes(b: &[u8]) -> Vec<Axis> {
    let mut out = Vec::new();
    let pat: [u8; 10] = {
        let mut p = [0u8; 10];
        p[0] = 1;
        p[2] = 8;
        p
    };
    let mut i = 0;
    while let Some(off) = b[i..].windows(10).position(|w| w == pat) {
        let p = i + off;
        i = p + 1;
        let Some(spacing) = b
            .get(p + 10..p + 18)
            .map(|v| f64::from_le_bytes(v.try_into().unwrap_or([0; 8])))
        else {
            break;
        };
        // Tag 2: the unit of the spacing.
        let q = p + 18;
        if b.get(q..q + 2) != Some(&[2, 0]) {
            continue;
        }
        let Some(len) = b
            .get(q + 2..q + 10)
            .map(|v| u64::from_le_bytes(v.try_into().unwrap_or([0; 8])))
        else {
            continue;
        };
        if !(2..=64).contains(&len) {
            continue;
        }
        let Some(unit) = b.get(q + 10..q + 10 + len as usize).and_then(ustr) else {
            continue;
        };
        let Some(factor) = units::length_factor(&unit) else {
            continue;
        };
        // The number of points follows within a few records: the first
        // `tag 1, len 4, u32` after the unit records.
        let tail = &b[q + 10 + len as usize..b.len().min(q + 10 + len as usize + 256)];
        let cnt_pat: [u8; 10] = {
            let mut c = [0u8; 10];
            c[0] = 1;
            c[2] = 4;
            c
        };
        let count = tail
            .windows(10)
            .position(|w| w == cnt_pat)
            .and_then(|cp| tail.get(cp + 10..cp + 14))
            .map(|v| u32::from_le_bytes(v.try_into().unwrap_or([0; 4])));
        if spacing.is_finite() && spacing > 0.0 {
            out.push(Axis {
                spacing_m: spacing * factor,
                count,
            });
        }
        if out.len() == 3 {
            break;
        }
    }
    out
}

/// Decompress the chain of blocks that tiles `n` int32 values.
fn blocks(ctx: Ctx<'_>, b: &[u8], n: usize) -> Result<Vec<u8>, ReadError> {
    let prefix = |p: usize| -> Option<(u64, u32, u32)> {
        let pre = b.get(p.checked_sub(16)?..p)?;
        Some((
            u64::from_le_bytes(pre[..8].try_into().ok()?),
            u32::from_le_bytes(pre[8..12].try_into().ok()?),
            u32::from_le_bytes(pre[12..16].try_into().ok()?),
        ))
    };
    let plausible = |p: usize| -> Option<(u64, u32, u32)> {
        let (first, count, size) = prefix(p)?;
        let ok = b.get(p) == Some(&0x78)
            && b.get(p + 1)
                .is_some_and(|c| [0x01, 0x5e, 0x9c, 0xda].contains(c))
            && count > 0
            && first.checked_add(count as u64)? <= n as u64
            && size > 0
            && p.checked_add(size as usize)? <= b.len();
        ok.then_some((first, count, size))
    };
    let inflate = |p: usize, count: u32, size: u32| -> Option<Vec<u8>> {
        let want = count as u64 * 4;
        let mut out = Vec::with_capacity((want as usize).min(size as usize * 64));
        flate2::read::ZlibDecoder::new(&b[p..p + size as usize])
            .take(want + 1)
            .read_to_end(&mut out)
            .ok()?;
        (out.len() as u64 == want).then_some(out)
    };
    // Blocks are kept as decoded and assembled only once they cover the grid, so a
    // corrupt header cannot make us allocate more than the file really holds.
    let mut parts: Vec<(usize, Vec<u8>)> = Vec::new();
    let mut covered: Vec<(usize, usize)> = Vec::new();
    let mut filled = 0usize;
    let mut failures = 0usize;
    let mut p = 16;
    while p < b.len() && filled < n {
        let Some((first, count, size)) = plausible(p) else {
            p += 1;
            continue;
        };
        let Some(out) = inflate(p, count, size) else {
            // Bound the work a crafted file can cause.
            failures += 1;
            if failures > 4096 {
                break;
            }
            p += 1;
            continue;
        };
        let (s, e) = (first as usize, first as usize + count as usize);
        // Blocks of another layer may repeat points already read: keep the first.
        if !covered.iter().any(|&(a, b)| s < b && a < e) {
            covered.push((s, e));
            parts.push((s, out));
            filled += count as usize;
        }
        p += size as usize + 16;
    }
    if filled != n {
        return Err(ctx.err(
            "height data",
            format!("the compressed blocks hold {filled} of the {n} points"),
            "the file is truncated or uses a layout this reader does not know",
        ));
    }
    let mut data = vec![0u8; n * 4];
    for (s, out) in parts {
        data[s * 4..s * 4 + out.len()].copy_from_slice(&out);
    }
    Ok(data)
}

/// Read a MountainsMap document (its surface).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let doc = ole::Ole::parse(bytes).map_err(|e| {
        ctx.err(
            "compound file",
            e,
            "the .mnt file is truncated or corrupt; re-save it from MountainsMap",
        )
    })?;
    let s = doc.stream("ScopedContents").map_err(|e| {
        ctx.err(
            "ScopedContents",
            e,
            "not a MountainsMap document, or a corrupt one",
        )
    })?;
    let bad = |what: &str| {
        ctx.err(
            "ScopedContents",
            format!("{what} not found"),
            "the document is corrupt or from a MountainsMap version this reader does not know; \
             export the surface as .sur or .x3p",
        )
    };
    let top = records(&s, 8, s.len()).ok_or_else(|| bad("a valid record tree"))?;
    let main = top
        .iter()
        .copied()
        .find(|r| r.tag == 1)
        .ok_or_else(|| bad("the main record"))?;
    let hd = child(&s, main, 0x2BD).ok_or_else(|| bad("the height data (record 0x2BD)"))?;
    let dtype = child(&s, hd, 1)
        .and_then(|r| s.get(r.start).copied())
        .ok_or_else(|| bad("the data type (record 0x2BD/1)"))?;
    let blob = child(&s, hd, 2).ok_or_else(|| bad("the data blob (record 0x2BD/2)"))?;
    let blob = &s[blob.start..blob.end];
    let zero_invalid = match dtype {
        12 => true,
        39 => false,
        t => {
            return Err(ctx.err(
                "height data type",
                format!("data type {t} is not known (12 or 39)"),
                "export the surface as .sur or .x3p from MountainsMap",
            ));
        }
    };
    let ax = axes(blob);
    let [x, y, z] = ax[..] else {
        return Err(bad("the x, y and z axis descriptions"));
    };
    let (Some(nx), Some(ny)) = (x.count, y.count) else {
        return Err(bad("the number of points along x and y"));
    };
    let n = checked_grid(
        ctx,
        "axis point counts",
        nx as u64,
        ny as u64,
        1,
        (blob.len() as u64).saturating_mul(1100),
    )?;
    let data = blocks(ctx, blob, n)?;
    let q = z.spacing_m;
    let mut invalid = 0;
    let heights = data
        .chunks_exact(4)
        .map(|c| {
            let v = i32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            if zero_invalid && v == 0 {
                invalid += 1;
                f64::NAN
            } else {
                v as f64 * q
            }
        })
        .collect();
    let dx = check_spacing(ctx, "x spacing", x.spacing_m)?;
    let dy = check_spacing(ctx, "y spacing", y.spacing_m)?;
    let mut raw = Raw::si(nx as usize, ny as usize, dx, dy, heights, "surface")
        .spacing_from("x spacing", "y spacing");
    if invalid > 0 {
        raw.notes
            .push(format!("{invalid} points were not measured"));
    }
    Decoded::single(ctx, want, raw)
}
