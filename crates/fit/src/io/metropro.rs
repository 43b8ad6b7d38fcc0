//! Zygo MetroPro `.dat` (interferometers). A big-endian header (834 bytes for formats 1
//! and 2, 4096 for format 3) with the intensity and phase ("connected") array sizes, the
//! interferometric scale factor S, wavelength λ [m], obliquity factor O, lateral
//! resolution [m/pixel], phase resolution code R and sign; then the intensity data
//! (int16 × buckets) and the phase data (int32, x fastest). Heights are
//! `raw · S · O · λ / R` with R = 4096, 32768 or 131072; values ≥ 2147483640 mark
//! points that were not measured.

use super::binary::Cursor;
use super::{Ctx, Decoded, Raw, Sniff, Want, check_spacing, checked_grid};
use crate::ReadError;

const MAGICS: [[u8; 4]; 3] = [
    [0x88, 0x1b, 0x03, 0x6f],
    [0x88, 0x1b, 0x03, 0x70],
    [0x88, 0x1b, 0x03, 0x71],
];
const INVALID: i32 = 2_147_483_640;

/// Content check: one of the three magic numbers.
pub(crate) fn sniff(b: &[u8]) -> Sniff {
    if b.len() >= 4 && MAGICS.iter().any(|m| b[..4] == m[..]) {
        Sniff::Magic
    } else {
        Sniff::No
    }
}

/// Read a MetroPro file (the phase map).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    if sniff(bytes) == Sniff::No {
        return Err(ctx.err(
            "magic",
            "not a MetroPro file (magic number missing)",
            "check the file, or force another format with --format",
        ));
    }
    let expected_header = if bytes[3] == 0x71 { 4096 } else { 834 };
    let short = || ctx.short("header", expected_header as u64, bytes.len() as u64);
    let mut c = Cursor::be(bytes, 4);
    let _format = c.u16().ok_or_else(short)?;
    let header_size = c.u32().ok_or_else(short)? as usize;
    if header_size != expected_header {
        return Err(ctx.err(
            "header_size",
            format!("{header_size} bytes, the format implies {expected_header}"),
            "the file is corrupt",
        ));
    }
    if bytes.len() < header_size {
        return Err(short());
    }
    let at = |off: usize| Cursor::be(bytes, off);
    let ac_w = at(52).u16().ok_or_else(short)? as u64;
    let ac_h = at(54).u16().ok_or_else(short)? as u64;
    let buckets = at(56).u16().ok_or_else(short)? as u64;
    let cn_w = at(68).u16().ok_or_else(short)? as u64;
    let cn_h = at(70).u16().ok_or_else(short)? as u64;
    let scale = at(164).f32().ok_or_else(short)?;
    let wavelength = at(168).f32().ok_or_else(short)?;
    let obliquity = at(176).f32().ok_or_else(short)?;
    let lateral = at(184).f32().ok_or_else(short)?;
    let phase_res = at(218).i16().ok_or_else(short)?;
    let sign = at(232).i16().ok_or_else(short)?;
    let r = match phase_res {
        0 => 4096.0,
        1 => 32768.0,
        2 => 131072.0,
        p => {
            return Err(ctx.err(
                "phase_res",
                format!("phase resolution code {p} is not 0, 1 or 2"),
                "the file is corrupt",
            ));
        }
    };
    let intensity = ac_w
        .saturating_mul(ac_h)
        .saturating_mul(buckets)
        .saturating_mul(2);
    let start = (header_size as u64).saturating_add(intensity);
    if start > bytes.len() as u64 {
        return Err(ctx.short("intensity data", start, bytes.len() as u64));
    }
    if cn_w == 0 || cn_h == 0 {
        return Err(ctx.err(
            "cn_org_width/height",
            "the file holds no phase (height) data",
            "export the measurement with its phase data",
        ));
    }
    let data = &bytes[start as usize..];
    let n = checked_grid(
        ctx,
        "cn_org_width × height",
        cn_w,
        cn_h,
        4,
        data.len() as u64,
    )?;
    let q = scale * obliquity * wavelength / r * if sign != 0 { -1.0 } else { 1.0 };
    if !(q.is_finite() && q != 0.0) {
        return Err(ctx.err(
            "intf_scale_factor/wavelength_in/obliquity_factor",
            format!("height scale {q} m per count is not usable"),
            "the header is corrupt",
        ));
    }
    let mut c = Cursor::be(data, 0);
    let mut heights = Vec::with_capacity(n);
    for _ in 0..n {
        let v = c
            .i32()
            .ok_or_else(|| ctx.short("phase data", n as u64 * 4, data.len() as u64))?;
        heights.push(if v >= INVALID { f64::NAN } else { v as f64 * q });
    }
    let dx = check_spacing(ctx, "lateral_res", lateral)?;
    let raw = Raw::si(cn_w as usize, cn_h as usize, dx, dx, heights, "phase")
        .spacing_from("lateral_res", "lateral_res");
    Decoded::single(ctx, want, raw)
}
