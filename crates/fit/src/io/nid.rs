//! Nanosurf easyScan `.nid`/`.ezd`: an INI-style Latin-1 header (`[DataSet]` with
//! `GroupCount`, `Gr{i}-Count`, `Gr{i}-Ch{j}` naming the data-set sections), then `#!`
//! and the binary blocks of every listed data set in that order. A data-set section gives
//! `Points`, `Lines`, `Dim0Range`/`Dim1Range` (scan size, `Dim0Unit`), `Dim2Name`,
//! `Dim2Unit`, `Dim2Range`, and the sample format (`SaveBits`, `SaveSign`, `SaveOrder`).
//! Values are `raw · Dim2Range / 2^bits`, x fastest.

use super::binary::Sample;
use super::{
    ChannelInfo, Ctx, Decoded, MAX_POINTS, Raw, Unit, Want, check_spacing, decode_grid, units,
};
use crate::ReadError;
use std::collections::HashMap;

struct DataSet {
    /// Its header section (`DataSet-0:1`).
    section: String,
    name: String,
    unit: String,
    nx: u64,
    ny: u64,
    kind: Sample,
    little: bool,
    bits: u32,
    range_x: f64,
    range_y: f64,
    xy_unit: String,
    z_range: f64,
    offset: u64,
}

/// The header's sections, `[name]` → key → value; lines before the first section belong
/// to `DataSet`.
type Sections = HashMap<String, HashMap<String, String>>;

/// Read a Nanosurf file.
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    let marker = bytes
        .windows(3)
        .position(|w| w == b"\n#!")
        .map(|p| p + 1)
        .ok_or_else(|| {
            ctx.err(
                "#!",
                "the binary data marker is missing",
                "the file is truncated or not a Nanosurf file",
            )
        })?;
    let header: String = bytes[..marker].iter().map(|&b| b as char).collect();
    let data = &bytes[marker + 2..];
    let sets = data_sets(ctx, &sections(&header))?;
    if sets.is_empty() {
        return Err(ctx.err("[DataSet]", "no data set listed", "the file holds no image"));
    }
    let channels: Vec<ChannelInfo> = sets
        .iter()
        .enumerate()
        .map(|(i, s)| ChannelInfo {
            index: i,
            name: s.name.clone(),
            unit: s.unit.clone(),
            is_height: units::length_factor(&s.unit).is_some(),
            nx: s.nx as usize,
            ny: s.ny as usize,
        })
        .collect();
    check_complete(
        ctx,
        &sets,
        &channels,
        (marker + 2) as u64,
        bytes.len() as u64,
    )?;
    Decoded::pick(ctx, want, channels, |selected, _| {
        let s = &sets[selected];
        let block = data
            .get(s.offset.min(data.len() as u64) as usize..)
            .unwrap_or(&[]);
        let raw = decode_grid(
            ctx,
            "Points × Lines",
            (s.nx, s.ny),
            ("data", block),
            s.kind,
            s.little,
        )?;
        let zu = units::length_factor(&s.unit).unwrap_or(1.0);
        let xu = units::length_factor(&s.xy_unit).ok_or_else(|| {
            ctx.err(
                "Dim0Unit",
                format!("`{}` is not a length unit", s.xy_unit),
                "the header is corrupt",
            )
        })?;
        let q = s.z_range / 2f64.powi(s.bits as i32);
        let dx = check_spacing(ctx, "Dim0Range", s.range_x * xu / s.nx as f64)?;
        let dy = if s.ny == 1 || !s.range_y.is_finite() {
            dx
        } else {
            check_spacing(ctx, "Dim1Range", s.range_y * xu / s.ny as f64)?
        };
        let heights = raw.into_iter().map(|v| v * q).collect();
        let out = Raw::si(s.nx as usize, s.ny as usize, dx, dy, heights, &s.name)
            .spacing_from("Dim0Range", "Dim1Range");
        Ok(out.in_units(Unit::Known(zu), Unit::Known(1.0)))
    })
}

/// The INI-style header as [`Sections`].
fn sections(header: &str) -> Sections {
    let mut sections = Sections::new();
    let mut current = String::from("DataSet");
    for line in header.lines() {
        let l = line.trim();
        if l.starts_with('[') && l.ends_with(']') {
            current = l[1..l.len() - 1].to_string();
            continue;
        }
        if let Some((k, v)) = l.split_once('=') {
            sections
                .entry(current.clone())
                .or_default()
                .insert(k.trim().to_string(), v.trim().to_string());
        }
    }
    sections
}

fn int(m: &HashMap<String, String>, k: &str) -> Option<u64> {
    m.get(k)?.trim().parse().ok()
}

/// The data sets `[DataSet]` lists, group by group, each at its offset in the binary part
/// (the blocks follow each other in that order).
fn data_sets(ctx: Ctx<'_>, sections: &Sections) -> Result<Vec<DataSet>, ReadError> {
    let global = sections.get("DataSet").ok_or_else(|| {
        ctx.err(
            "[DataSet]",
            "section missing",
            "not a Nanosurf file, or a corrupt one",
        )
    })?;
    let groups = int(global, "GroupCount")
        .ok_or_else(|| ctx.err("GroupCount", "missing", "the header is incomplete"))?;
    let mut sets = Vec::new();
    let mut offset = 0u64;
    for g in 0..groups.min(1000) {
        let count = int(global, &format!("Gr{g}-Count")).unwrap_or(0);
        for j in 0..count.min(1000) {
            let Some(name) = global.get(&format!("Gr{g}-Ch{j}")) else {
                continue;
            };
            let Some(s) = sections.get(name) else {
                continue;
            };
            let set = data_set(ctx, name, s, offset)?;
            offset = offset.saturating_add(
                set.nx
                    .saturating_mul(set.ny)
                    .saturating_mul(set.bits as u64 / 8),
            );
            sets.push(set);
        }
    }
    Ok(sets)
}

/// One data set from its section `[name]` (`s`), its block starting at `offset`.
fn data_set(
    ctx: Ctx<'_>,
    name: &str,
    s: &HashMap<String, String>,
    offset: u64,
) -> Result<DataSet, ReadError> {
    let field = |k: &str| -> Result<&String, ReadError> {
        s.get(k).ok_or_else(|| {
            ctx.err(
                &format!("[{name}] {k}"),
                "missing",
                "the header is incomplete",
            )
        })
    };
    let num = |k: &str| -> Result<f64, ReadError> {
        field(k)?.parse::<f64>().map_err(|_| {
            ctx.err(
                &format!("[{name}] {k}"),
                "not a number",
                "the header is corrupt",
            )
        })
    };
    if field("SaveMode")? != "Binary" {
        return Err(ctx.err(
            &format!("[{name}] SaveMode"),
            "only binary data sets are supported",
            "save the measurement in binary mode",
        ));
    }
    let nx =
        int(s, "Points").ok_or_else(|| ctx.err("Points", "missing", "the header is incomplete"))?;
    let ny =
        int(s, "Lines").ok_or_else(|| ctx.err("Lines", "missing", "the header is incomplete"))?;
    let bits = int(s, "SaveBits").unwrap_or(32) as u32;
    let signed = s.get("SaveSign").map(String::as_str) != Some("Unsigned");
    let kind = match (bits, signed) {
        (8, true) => Sample::I8,
        (8, false) => Sample::U8,
        (16, true) => Sample::I16,
        (16, false) => Sample::U16,
        (32, true) => Sample::I32,
        (32, false) => Sample::U32,
        _ => {
            return Err(ctx.err(
                &format!("[{name}] SaveBits"),
                format!("{bits}-bit samples are not supported"),
                "expected 8, 16 or 32",
            ));
        }
    };
    let frame = s.get("Frame").cloned().unwrap_or_default();
    let dim2 = s.get("Dim2Name").cloned().unwrap_or_default();
    Ok(DataSet {
        section: name.to_string(),
        name: format!("{frame} ({dim2})"),
        unit: s.get("Dim2Unit").cloned().unwrap_or_default(),
        nx,
        ny,
        kind,
        little: s.get("SaveOrder").is_none_or(|v| v == "Intel"),
        bits,
        range_x: num("Dim0Range")?,
        range_y: num("Dim1Range").unwrap_or(f64::NAN),
        xy_unit: s.get("Dim0Unit").cloned().unwrap_or_else(|| "m".into()),
        z_range: num("Dim2Range")?,
        offset,
    })
}

/// Every data set's block lies in the file, not only the one asked for: a copy cut short
/// holds its first channels whole, and reading them would hide that the file is broken.
/// (A grid beyond the supported size is `checked_grid`'s to report.)
fn check_complete(
    ctx: Ctx<'_>,
    sets: &[DataSet],
    channels: &[ChannelInfo],
    data_start: u64,
    file_len: u64,
) -> Result<(), ReadError> {
    for (s, c) in sets.iter().zip(channels) {
        if s.nx.saturating_mul(s.ny) > MAX_POINTS {
            continue;
        }
        let start = data_start.saturating_add(s.offset);
        let end = start.saturating_add(s.nx * s.ny * (s.bits as u64 / 8));
        if end > file_len {
            return Err(ctx.truncated(
                &format!("[{}] Points × Lines", s.section),
                &format!(
                    "data set {} `{}` ({} × {} {}-bit values)",
                    c.index, c.name, s.nx, s.ny, s.bits
                ),
                (start, end),
                file_len,
            ));
        }
    }
    Ok(())
}
