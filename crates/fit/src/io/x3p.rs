//! ISO 25178-72 X3P: a zip holding `main.xml` (axes, sizes, data link) and the point data
//! (`bindata/data.bin`, x fastest) or an inline `<DataList>`. Data types D/F/L/I; integer
//! data are scaled by the Z increment. Non-finite values, points flagged in the optional
//! valid-points bit map and empty `<Datum/>` entries (ISO 5436-2's invalid point) become NaN.
//! `main.xml` may sit in a folder of the archive (a scan zipped from inside its folder,
//! beside macOS's `__MACOSX/` copies); the paths it links are then read in that folder.
//! A zip without `main.xml` is refused naming what it looks like (an Office document, a
//! SurfaceTopography container) and what it holds.
//!
//! Integrity: every entry read is checked against its zip CRC-32, the point data against
//! `Record3/DataLink/MD5ChecksumPointData` and `main.xml` against the checksum file
//! (`md5checksum.hex`); the error says which check failed.

use super::{Ctx, Decoded, Raw, Want, binary, check_spacing, checked_grid, md5};
use crate::ReadError;
use quick_xml::events::Event;
use std::collections::HashMap;
use std::io::Read;

/// Largest `main.xml` accepted (bytes).
const MAX_XML: u64 = 64 << 20;
/// Deflate cannot expand data by more than about 1032:1; a larger claim is a corrupt header.
const MAX_DEFLATE_RATIO: u64 = 1100;

/// Read an X3P file (one channel).
pub(crate) fn read(ctx: Ctx<'_>, bytes: &[u8], want: Want<'_>) -> Result<Decoded, ReadError> {
    Decoded::single(ctx, want, parse(ctx, bytes)?)
}

/// The archive of an X3P file read from memory.
type Archive<'b> = zip::ZipArchive<std::io::Cursor<&'b [u8]>>;

/// Parse an X3P file.
fn parse(ctx: Ctx<'_>, bytes: &[u8]) -> Result<Raw, ReadError> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| {
        ctx.err(
            "zip container",
            format!("not a readable zip archive ({e})"),
            "the X3P file is truncated or corrupt",
        )
    })?;
    let dir = main_xml_folder(ctx, &zip)?;
    let xml = read_entry(ctx, &mut zip, &format!("{dir}main.xml"), MAX_XML)?;
    check_header_md5(ctx, &mut zip, &dir, &xml)?;
    let xml = String::from_utf8(xml)
        .map_err(|_| ctx.err("main.xml", "not UTF-8", "the X3P file is corrupt"))?;
    let doc = parse_xml(ctx, &xml)?;
    let header = Header {
        ctx,
        fields: &doc.fields,
    };
    check_supported(&header)?;
    let (nx, ny, dx, dy) = grid(&header)?;
    let (kind, zscale) = sample_kind(&header)?;
    // Paths in main.xml are relative to its folder, with either separator.
    let in_dir = |link: &str| format!("{dir}{}", link.trim().replace('\\', "/"));
    let mut heights = if let Some(link) = header.get("Record3/DataLink/PointDataLink") {
        linked_points(&header, &mut zip, &in_dir(link), (nx, ny), kind)?
    } else if !doc.data_list.is_empty() {
        listed_points(ctx, &doc.data_list, (nx, ny))?
    } else {
        return Err(ctx.err(
            "Record3/DataLink",
            "neither a PointDataLink nor a DataList",
            "the X3P file holds no data",
        ));
    };
    for h in &mut heights {
        *h = if h.is_finite() { *h * zscale } else { f64::NAN };
    }
    if let Some(valid) = header.get("Record3/DataLink/ValidPointsLink") {
        mask_invalid_points(ctx, &mut zip, &in_dir(valid), &mut heights)?;
    }
    let channel = header.get("Record2/Comment").unwrap_or("x3p").trim();
    Ok(Raw::si(nx as usize, ny as usize, dx, dy, heights, channel)
        .spacing_from("Record1/Axes/CX/Increment", "Record1/Axes/CY/Increment"))
}

/// The fields of `main.xml` by their record path, with errors naming the path.
struct Header<'h> {
    ctx: Ctx<'h>,
    fields: &'h HashMap<String, String>,
}

impl<'h> Header<'h> {
    fn get(&self, path: &str) -> Option<&'h str> {
        self.fields.get(path).map(String::as_str)
    }

    fn need(&self, path: &str) -> Result<&'h str, ReadError> {
        self.get(path).ok_or_else(|| {
            self.ctx.err(
                path,
                "missing from main.xml",
                "the X3P file is incomplete; re-export it",
            )
        })
    }

    fn num(&self, path: &str) -> Result<f64, ReadError> {
        self.need(path)?.trim().parse::<f64>().map_err(|_| {
            self.ctx
                .err(path, "not a number", "the X3P header is corrupt")
        })
    }

    fn count(&self, path: &str) -> Result<u64, ReadError> {
        self.need(path)?.trim().parse::<u64>().map_err(|_| {
            self.ctx.err(
                path,
                "not a non-negative integer",
                "the X3P header is corrupt",
            )
        })
    }
}

/// Refuse what this reader does not read: point clouds and absolute lateral axes.
fn check_supported(header: &Header<'_>) -> Result<(), ReadError> {
    let feature = header.get("Record1/FeatureType").unwrap_or("SUR");
    if feature == "PCL" {
        return Err(header.ctx.err(
            "Record1/FeatureType",
            "point clouds (PCL) are not supported",
            "export the surface as a regular grid (SUR)",
        ));
    }
    for axis in ["CX", "CY"] {
        let t = header
            .get(&format!("Record1/Axes/{axis}/AxisType"))
            .unwrap_or("I");
        if t != "I" {
            return Err(header.ctx.err(
                &format!("Record1/Axes/{axis}/AxisType"),
                format!("axis type `{t}` (absolute coordinates) is not supported"),
                "export with incremental (regular-grid) lateral axes",
            ));
        }
    }
    Ok(())
}

/// `(nx, ny, dx, dy)` of the one-layer grid, spacings in the file's unit (metres).
fn grid(header: &Header<'_>) -> Result<(u64, u64, f64, f64), ReadError> {
    let ctx = header.ctx;
    let nx = header.count("Record3/MatrixDimension/SizeX")?;
    let ny = header.count("Record3/MatrixDimension/SizeY")?;
    let nz = header
        .get("Record3/MatrixDimension/SizeZ")
        .map(|s| s.trim().parse::<u64>())
        .unwrap_or(Ok(1));
    if nz != Ok(1) {
        return Err(ctx.err(
            "Record3/MatrixDimension/SizeZ",
            "only SizeZ = 1 (one layer) is supported",
            "export a single layer",
        ));
    }
    let dx = check_spacing(
        ctx,
        "Record1/Axes/CX/Increment",
        header.num("Record1/Axes/CX/Increment")?,
    )?;
    let dy = if ny == 1 {
        dx
    } else {
        check_spacing(
            ctx,
            "Record1/Axes/CY/Increment",
            header.num("Record1/Axes/CY/Increment")?,
        )?
    };
    Ok((nx, ny, dx, dy))
}

/// The stored sample type and the factor to metres (the Z increment of integer data).
fn sample_kind(header: &Header<'_>) -> Result<(binary::Sample, f64), ReadError> {
    let ctx = header.ctx;
    let kind = match header.need("Record1/Axes/CZ/DataType")?.trim() {
        "D" => binary::Sample::F64,
        "F" => binary::Sample::F32,
        "L" => binary::Sample::I32,
        "I" => binary::Sample::I16,
        t => {
            return Err(ctx.err(
                "Record1/Axes/CZ/DataType",
                format!("unknown data type `{t}`"),
                "expected D, F, L or I",
            ));
        }
    };
    if kind.is_float() {
        return Ok((kind, 1.0));
    }
    let zscale = match header.get("Record1/Axes/CZ/Increment") {
        Some(s) => s
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v != 0.0)
            .ok_or_else(|| {
                ctx.err(
                    "Record1/Axes/CZ/Increment",
                    "not a usable number",
                    "the X3P header is corrupt",
                )
            })?,
        None => 1.0,
    };
    Ok((kind, zscale))
}

/// The points of the binary entry `link`, checked against the grid and their MD5.
fn linked_points(
    header: &Header<'_>,
    zip: &mut Archive<'_>,
    link: &str,
    (nx, ny): (u64, u64),
    kind: binary::Sample,
) -> Result<Vec<f64>, ReadError> {
    let ctx = header.ctx;
    let size = entry_size(ctx, zip, link)?;
    let n = checked_grid(
        ctx,
        "Record3/MatrixDimension",
        nx,
        ny,
        kind.size() as u64,
        size,
    )?;
    let need = n as u64 * kind.size() as u64;
    if size > need.saturating_mul(2).saturating_add(1 << 20) {
        return Err(ctx.err(
            link,
            format!("the entry holds {size} bytes but the header implies {need}"),
            "the X3P file is corrupt; re-export it",
        ));
    }
    let data = read_entry(ctx, zip, link, size)?;
    if let Some(want) = header.get("Record3/DataLink/MD5ChecksumPointData") {
        let have = md5::hex(&data);
        if !have.eq_ignore_ascii_case(want.trim()) {
            return Err(ctx.err(
                "Record3/DataLink/MD5ChecksumPointData",
                format!(
                    "MD5 check failed: {link} has MD5 {have}, main.xml records {}",
                    want.trim()
                ),
                "the point data are corrupt; re-export or re-copy the file",
            ));
        }
    }
    binary::decode(&data, kind, true, n)
        .ok_or_else(|| ctx.short(link, (n * kind.size()) as u64, data.len() as u64))
}

/// The points of an inline `<DataList>`; an empty datum is an invalid point.
fn listed_points(
    ctx: Ctx<'_>,
    data_list: &[String],
    (nx, ny): (u64, u64),
) -> Result<Vec<f64>, ReadError> {
    let n = checked_grid(ctx, "Record3/MatrixDimension", nx, ny, 0, 0)?;
    if data_list.len() < n {
        return Err(ctx.err(
            "Record3/DataList",
            format!(
                "the header implies {n} points ({nx} × {ny}) but the data list holds only {}",
                data_list.len()
            ),
            "the file is truncated or its header is corrupt; re-export it",
        ));
    }
    data_list[..n]
        .iter()
        .map(|d| {
            // A datum holds the z value, or "x;y;z" for absolute axes.
            let last = d.rsplit(';').next().unwrap_or("").trim();
            if last.is_empty() {
                Ok(f64::NAN)
            } else {
                last.parse::<f64>()
            }
        })
        .collect::<Result<Vec<f64>, _>>()
        .map_err(|_| {
            ctx.err(
                "Record3/DataList/Datum",
                "a datum is not a number",
                "the X3P data list is corrupt",
            )
        })
}

/// NaN where the valid-points bit map `valid` (one bit per point, LSB first) has a 0.
fn mask_invalid_points(
    ctx: Ctx<'_>,
    zip: &mut Archive<'_>,
    valid: &str,
    heights: &mut [f64],
) -> Result<(), ReadError> {
    let n = heights.len();
    let size = entry_size(ctx, zip, valid)?;
    let need_bytes = n.div_ceil(8) as u64;
    if size < need_bytes {
        return Err(ctx.short(valid, need_bytes, size));
    }
    if size > need_bytes.saturating_mul(2).saturating_add(1 << 20) {
        return Err(ctx.short(valid, need_bytes, size));
    }
    let bits = read_entry(ctx, zip, valid, size)?;
    for (i, h) in heights.iter_mut().enumerate() {
        if bits.get(i / 8).is_some_and(|b| b & (1 << (i % 8)) == 0) {
            *h = f64::NAN;
        }
    }
    Ok(())
}

/// The folder of the archive that holds `main.xml` (`""` at the root, `scan/` for one
/// zipped from inside a folder), ignoring the `__MACOSX/` resource-fork copies macOS adds.
/// An archive without `main.xml` is named for what it is instead.
fn main_xml_folder<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &zip::ZipArchive<R>,
) -> Result<String, ReadError> {
    if zip.index_for_name("main.xml").is_some() {
        return Ok(String::new());
    }
    let names: Vec<String> = zip
        .file_names()
        .filter_map(Result::ok)
        .map(|n| n.into_owned())
        .collect();
    let mut found: Vec<&String> = names
        .iter()
        .filter(|n| {
            let debris = n.starts_with("__MACOSX/")
                || n.rsplit('/').next().is_some_and(|f| f.starts_with("._"));
            n.ends_with("/main.xml") && !debris
        })
        .collect();
    found.sort_by_key(|n| n.matches('/').count());
    match found.first() {
        Some(n) => Ok(n[..n.len() - "main.xml".len()].to_string()),
        None => Err(not_x3p(ctx, &names)),
    }
}

/// The refusal of a zip archive that holds no `main.xml`: what it looks like instead.
fn not_x3p(ctx: Ctx<'_>, names: &[String]) -> ReadError {
    let has = |n: &str| names.iter().any(|e| e.eq_ignore_ascii_case(n));
    let what = if has("[Content_Types].xml") {
        let kind = if names.iter().any(|n| n.starts_with("xl/")) {
            "an Excel workbook (.xlsx)"
        } else if names.iter().any(|n| n.starts_with("word/")) {
            "a Word document (.docx)"
        } else {
            "an Office Open XML document"
        };
        format!("{kind}, not a height map")
    } else if has("meta.yml") {
        "a SurfaceTopography container (meta.yml and the files it lists), not an X3P file"
            .to_string()
    } else if has("mimetype") {
        "an OpenDocument file, not a height map".to_string()
    } else {
        "a zip archive that is not an X3P file (no main.xml)".to_string()
    };
    let shown: Vec<&str> = names.iter().map(String::as_str).take(6).collect();
    let more = if names.len() > shown.len() {
        ", …"
    } else {
        ""
    };
    ctx.err(
        "zip container",
        format!(
            "{what}; it holds {} entries: {}{more}",
            names.len(),
            shown.join(", ")
        ),
        "unzip it and read the height file inside, or export the scan as X3P",
    )
}

fn entry<'z, R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &'z mut zip::ZipArchive<R>,
    name: &str,
) -> Result<zip::read::ZipFile<'z, R>, ReadError> {
    zip.by_name(name).map_err(|e| {
        ctx.err(
            name,
            format!("entry missing from the archive ({e})"),
            "the X3P file is incomplete",
        )
    })
}

fn entry_size<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &mut zip::ZipArchive<R>,
    name: &str,
) -> Result<u64, ReadError> {
    let f = entry(ctx, zip, name)?;
    Ok(f.size().min(
        f.compressed_size()
            .saturating_mul(MAX_DEFLATE_RATIO)
            .saturating_add(4096),
    ))
}

/// Read a whole entry (at most `limit` bytes, never trusting the declared size for
/// allocation) and verify its zip CRC-32.
fn read_entry<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &mut zip::ZipArchive<R>,
    name: &str,
    limit: u64,
) -> Result<Vec<u8>, ReadError> {
    let f = entry(ctx, zip, name)?;
    let declared = f.size();
    let crc = f.crc32();
    if declared > limit {
        return Err(ctx.err(
            name,
            format!("the entry claims {declared} bytes, more than the {limit} accepted"),
            "the X3P file is corrupt",
        ));
    }
    let cap = declared.min(
        f.compressed_size()
            .saturating_mul(MAX_DEFLATE_RATIO)
            .saturating_add(4096),
    );
    // Grow past 64 MB only as data really arrive.
    let mut out = Vec::with_capacity(usize::try_from(cap.min(64 << 20)).unwrap_or(0));
    f.take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| {
            let msg = e.to_string();
            if msg.to_ascii_lowercase().contains("checksum") {
                ctx.err(
                    name,
                    format!("zip CRC-32 check failed ({msg})"),
                    "the file is corrupt; re-export or re-copy it",
                )
            } else {
                ctx.err(
                    name,
                    format!("cannot decompress ({msg})"),
                    "the X3P file is corrupt",
                )
            }
        })?;
    if out.len() as u64 != declared {
        return Err(ctx.err(
            name,
            format!(
                "the entry holds {} bytes but its zip header declares {declared}",
                out.len()
            ),
            "the X3P file is corrupt",
        ));
    }
    let have = crc32fast::hash(&out);
    if have != crc {
        return Err(ctx.err(
            name,
            format!("zip CRC-32 check failed: the data hash to {have:08x}, the archive records {crc:08x}"),
            "the file is corrupt; re-export or re-copy it",
        ));
    }
    Ok(out)
}

/// Compare `main.xml` with its MD5 in the checksum file (`md5checksum.hex`, as
/// `<hex> *main.xml`), when the archive has one.
fn check_header_md5<R: Read + std::io::Seek>(
    ctx: Ctx<'_>,
    zip: &mut zip::ZipArchive<R>,
    dir: &str,
    xml: &[u8],
) -> Result<(), ReadError> {
    let name = format!("{dir}md5checksum.hex");
    if zip.index_for_name(&name).is_none() {
        return Ok(());
    }
    let text = read_entry(ctx, zip, &name, 4096)?;
    let text = String::from_utf8_lossy(&text);
    let Some(want) = text.split_whitespace().next() else {
        return Ok(());
    };
    let have = md5::hex(xml);
    if !have.eq_ignore_ascii_case(want) {
        return Err(ctx.err(
            "md5checksum.hex",
            format!("MD5 check failed: main.xml has MD5 {have}, md5checksum.hex records {want}"),
            "the header is corrupt; re-export or re-copy the file",
        ));
    }
    Ok(())
}

struct Doc {
    fields: HashMap<String, String>,
    data_list: Vec<String>,
}

fn parse_xml(ctx: Ctx<'_>, xml: &str) -> Result<Doc, ReadError> {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut stack: Vec<String> = Vec::new();
    let mut fields = HashMap::new();
    let mut data_list = Vec::new();
    loop {
        let ev = reader.read_event().map_err(|e| {
            ctx.err(
                "main.xml",
                format!("malformed XML ({e})"),
                "the X3P file is corrupt",
            )
        })?;
        match ev {
            // `<Datum/>` is ISO 5436-2's invalid point.
            Event::Empty(e)
                if stack.len() == 3
                    && stack[1..] == ["Record3", "DataList"]
                    && AsRef::<str>::as_ref(&e.local_name()) == "Datum" =>
            {
                data_list.push(String::new());
            }
            Event::Start(e) => {
                stack.push(AsRef::<str>::as_ref(&e.local_name()).to_string());
                if stack.len() == 4 && stack[1..] == ["Record3", "DataList", "Datum"] {
                    data_list.push(String::new());
                }
                if stack.len() > 64 {
                    return Err(ctx.err(
                        "main.xml",
                        "nesting deeper than 64 levels",
                        "the X3P file is corrupt",
                    ));
                }
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Text(t) => {
                if stack.len() < 2 {
                    continue;
                }
                let text = (*t).trim().to_string();
                if text.is_empty() {
                    continue;
                }
                let path = stack[1..].join("/");
                if path == "Record3/DataList/Datum" {
                    if let Some(last) = data_list.last_mut() {
                        *last = text;
                    }
                } else {
                    fields.entry(path).or_insert(text);
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(Doc { fields, data_list })
}
