//! Readers for surface-topography files. Each format lives in its own module; [`read_path`]
//! and [`read_bytes`] pick one from the file's magic bytes or extension.
//!
//! Every reader takes the whole file as a byte slice, never panics on malformed input and
//! checks declared sizes against the bytes actually present before allocating.

pub mod bcr;
pub mod binary;
pub mod dektak;
pub mod gsf;
pub mod matrix;
pub mod nanoscope;
pub mod sdf;
pub mod text;
pub mod units;
pub mod x3p;
pub mod xyz;

use crate::{ReadError, Topography};
use std::path::Path;

/// Options that apply to some readers.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Channel (image) index for multi-channel files (NanoScope). Default 0.
    pub channel: Option<usize>,
    /// Length unit [m per unit] of plain column files (XYZ/CSV), and of the values of a
    /// matrix file that does not state its units. Default 1 (metres).
    pub units: Option<f64>,
    /// Force a format instead of detecting it.
    pub format: Option<Format>,
}

/// Supported file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// ISO 25178-72 X3P (zip).
    X3p,
    /// BCR-STM (`bcrstm`, `bcrf`, ASCII or UTF-16 header).
    Bcr,
    /// SDF (ISO 25178-71 / BCR SDF), binary or ASCII.
    Sdf,
    /// Bruker/Veeco NanoScope (`.di`, `.spm`, `.001`).
    NanoScope,
    /// Gwyddion "Export Text" ASCII matrix.
    Matrix,
    /// Gwyddion Simple Field `.gsf`.
    Gsf,
    /// Bruker Dektak CSV profile.
    Dektak,
    /// Plain XYZ (or XZ profile) column file.
    Xyz,
}

impl Format {
    /// Parse a format name as given on the command line.
    pub fn from_name(name: &str) -> Option<Format> {
        Some(match name.to_ascii_lowercase().as_str() {
            "x3p" => Format::X3p,
            "bcr" | "bcrf" | "bcrstm" => Format::Bcr,
            "sdf" => Format::Sdf,
            "di" | "nanoscope" | "spm" => Format::NanoScope,
            "matrix" | "txt" | "asc" => Format::Matrix,
            "gsf" => Format::Gsf,
            "dektak" => Format::Dektak,
            "xyz" | "csv" => Format::Xyz,
            _ => return None,
        })
    }
}

/// File-name context for error messages.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub file: &'a str,
}

impl Ctx<'_> {
    pub fn err(
        &self,
        field: &str,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> ReadError {
        ReadError::Invalid {
            file: self.file.to_string(),
            field: field.to_string(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    /// Error for a truncated or inconsistent data block.
    pub fn short(&self, field: &str, need: u64, have: u64) -> ReadError {
        self.err(
            field,
            format!("the header implies {need} bytes of data but the file holds only {have}"),
            "the file is truncated or its header is corrupt; re-export it from the instrument software",
        )
    }
}

/// Largest grid accepted by any reader (points). Larger headers are reported as corrupt.
pub const MAX_POINTS: u64 = 1 << 31;

/// Check `nx·ny` against the hard limit and against `available` samples; returns `nx·ny`.
pub(crate) fn checked_grid(
    ctx: Ctx<'_>,
    field: &str,
    nx: u64,
    ny: u64,
    bytes_per_point: u64,
    available_bytes: u64,
) -> Result<usize, ReadError> {
    if nx == 0 || ny == 0 {
        return Err(ctx.err(
            field,
            format!("grid {nx} × {ny} is empty"),
            "check the header",
        ));
    }
    let n = nx
        .checked_mul(ny)
        .filter(|&n| n <= MAX_POINTS)
        .ok_or_else(|| {
            ctx.err(
                field,
                format!("grid {nx} × {ny} is larger than the supported {MAX_POINTS} points"),
                "the header is corrupt; re-export the file",
            )
        })?;
    let need = n.saturating_mul(bytes_per_point);
    if need > available_bytes {
        return Err(ctx.short(field, need, available_bytes));
    }
    usize::try_from(n)
        .map_err(|_| ctx.err(field, "grid does not fit in memory", "use a 64-bit build"))
}

/// Check a pixel spacing: finite and positive.
pub(crate) fn check_spacing(ctx: Ctx<'_>, field: &str, d: f64) -> Result<f64, ReadError> {
    if d.is_finite() && d > 0.0 {
        Ok(d)
    } else {
        Err(ctx.err(
            field,
            format!("pixel spacing {d} m is not a positive finite number"),
            "check the scan-size fields of the header",
        ))
    }
}

/// Read and parse a file. The format comes from `opts.format` or is detected.
pub fn read_path(path: &Path, opts: &ReadOptions) -> Result<Topography, ReadError> {
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let name = path.display().to_string();
    read_bytes(&name, &bytes, opts)
}

/// Parse a file already in memory; `name` is used for format detection (extension) and
/// messages.
pub fn read_bytes(name: &str, bytes: &[u8], opts: &ReadOptions) -> Result<Topography, ReadError> {
    let format = match opts.format {
        Some(f) => f,
        None => detect(name, bytes).ok_or_else(|| ReadError::UnknownFormat {
            file: name.to_string(),
            fix: "supported: .x3p, .bcr/.bcrf, .sdf, NanoScope .di/.spm, Gwyddion text matrix \
                  and .gsf, Dektak .csv, XYZ columns; force one with --format"
                .into(),
        })?,
    };
    let ctx = Ctx { file: name };
    match format {
        Format::X3p => x3p::read(ctx, bytes),
        Format::Bcr => bcr::read(ctx, bytes),
        Format::Sdf => sdf::read(ctx, bytes),
        Format::NanoScope => nanoscope::read(ctx, bytes, opts.channel.unwrap_or(0)),
        Format::Matrix => matrix::read(ctx, bytes, opts.units),
        Format::Gsf => gsf::read(ctx, bytes),
        Format::Dektak => dektak::read(ctx, bytes),
        Format::Xyz => xyz::read(ctx, bytes, opts.units.unwrap_or(1.0)),
    }
}

/// Guess the format from magic bytes, then content, then extension.
pub fn detect(name: &str, bytes: &[u8]) -> Option<Format> {
    let head = &bytes[..bytes.len().min(64)];
    if head.starts_with(b"PK\x03\x04") {
        return Some(Format::X3p);
    }
    if head.starts_with(b"\\*File list") {
        return Some(Format::NanoScope);
    }
    if head.starts_with(b"Gwyddion Simple Field") {
        return Some(Format::Gsf);
    }
    for magic in [&b"aBCR-"[..], b"bBCR-", b"aISO-", b"bISO-"] {
        if head.starts_with(magic) {
            return Some(Format::Sdf);
        }
    }
    if head.starts_with(b"fileformat") || head.starts_with(b"f\0i\0l\0e\0f\0o\0r\0m\0a\0t\0") {
        return Some(Format::Bcr);
    }
    let ext = Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "x3p" => return Some(Format::X3p),
        "bcr" | "bcrf" => return Some(Format::Bcr),
        "sdf" => return Some(Format::Sdf),
        "gsf" => return Some(Format::Gsf),
        "di" | "spm" => return Some(Format::NanoScope),
        _ => {}
    }
    let text_head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
    if text_head.contains("Scan Parameters") || text_head.contains("Scan Data") {
        return Some(Format::Dektak);
    }
    if text_head.starts_with('#')
        && (text_head.contains("Width:") || text_head.contains("Channel:"))
    {
        return Some(Format::Matrix);
    }
    // Plain numbers: a matrix has many columns, XYZ has two or three.
    let first_data = text_head
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#') && text::parse_row(l).is_some())?;
    let cols = text::parse_row(first_data)?.len();
    match cols {
        2 | 3 => Some(Format::Xyz),
        c if c > 3 => Some(Format::Matrix),
        _ => None,
    }
}
