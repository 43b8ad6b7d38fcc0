//! Readers for surface-topography files, behind one registry ([`registry::READERS`]).
//!
//! Every reader takes the whole file as a byte slice, never panics on malformed input and
//! checks declared sizes against the bytes actually present before allocating. A reader
//! decodes one channel into a [`Raw`] map in the file's own units; [`open_bytes`] then
//! applies what the user supplied for the facts the file leaves out (`--units`,
//! `--pixel-size`, `--size`) and names the missing fact and its flag when neither the
//! file nor the user gives it.

pub mod al3d;
pub mod bcr;
pub mod binary;
pub mod datx;
pub mod dektak;
pub mod frt;
pub mod gsf;
pub mod gwy;
pub mod hdf5;
pub mod ibw;
pub mod jpk;
pub mod lext;
pub mod matrix;
pub mod md5;
pub mod metropro;
pub mod mi;
pub mod mnt;
pub mod nanoscope;
pub mod netcdf;
pub mod nid;
pub mod nms;
pub mod npy;
pub mod ole;
pub mod opd;
pub mod opdx;
pub mod park;
pub mod plu;
pub mod registry;
pub mod sdf;
pub mod sur;
pub mod text;
pub mod tiff;
pub mod tmd;
pub mod units;
pub mod vk4;
pub mod wsxm;
pub mod x3p;
pub mod xyz;
pub mod zmg;
pub mod zon;

pub use registry::{Format, READERS, Sniff};

use crate::{ReadError, Topography};
use std::collections::HashMap;
use std::path::Path;

/// A channel chosen on the command line: by 0-based index or by name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ChannelSel {
    /// 0-based position in the file's channel list.
    Index(usize),
    /// Channel name (case-insensitive; a unique substring is enough).
    Name(String),
}

impl ChannelSel {
    /// `"3"` is an index, anything else a name.
    pub fn parse(s: &str) -> ChannelSel {
        match s.trim().parse::<usize>() {
            Ok(i) => ChannelSel::Index(i),
            Err(_) => ChannelSel::Name(s.trim().to_string()),
        }
    }
}

/// Units supplied by the user for files that do not state them [metres per unit].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Lateral (x, y) unit.
    pub lateral: f64,
    /// Height unit.
    pub height: f64,
}

impl Units {
    /// Parse `um` (both) or `um,nm` (lateral, height).
    pub fn parse(s: &str) -> Option<Units> {
        let mut parts = s.split(',').map(str::trim);
        let a = units::length_factor(parts.next()?)?;
        let b = match parts.next() {
            Some(p) => units::length_factor(p)?,
            None => a,
        };
        if parts.next().is_some() {
            return None;
        }
        Some(Units {
            lateral: a,
            height: b,
        })
    }
}

/// Options that apply to some readers.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Channel of multi-channel files; default: the first height channel.
    pub channel: Option<ChannelSel>,
    /// Units for files that do not state them (ignored, with a note, where they do).
    pub units: Option<Units>,
    /// Pixel spacing `(dx, dy)` [m]; overrides the file's.
    pub pixel_size: Option<(f64, f64)>,
    /// Scan size `(x, y)` [m] (`dx = x / nx`); overrides the file's.
    pub size: Option<(f64, f64)>,
    /// Force a format instead of detecting it.
    pub format: Option<Format>,
}

/// One channel of a file as listed by `lustre fit channels`.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelInfo {
    /// 0-based index (the `--channel` value).
    pub index: usize,
    /// Name as stored in the file.
    pub name: String,
    /// Unit of the values as stated by the file (empty when it states none).
    pub unit: String,
    /// True when the channel holds heights (a length), so it can be analysed.
    pub is_height: bool,
    /// Points along x.
    pub nx: usize,
    /// Lines.
    pub ny: usize,
}

/// A file read and converted to SI, with what the reader had to assume or change.
#[derive(Debug, Clone)]
pub struct Scan {
    /// The height map in metres.
    pub topo: Topography,
    /// Reader used.
    pub format: Format,
    /// Every channel of the file.
    pub channels: Vec<ChannelInfo>,
    /// Index of the channel read.
    pub channel: usize,
    /// Things the user should know (resampling, flags ignored or used, assumed units).
    pub notes: Vec<String>,
}

/// A unit stated by the file, or not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Unit {
    /// Metres per stored unit.
    Known(f64),
    /// The file does not say.
    Unknown,
}

/// One decoded channel in the file's own units.
#[derive(Debug, Clone)]
pub(crate) struct Raw {
    pub nx: usize,
    pub ny: usize,
    /// Values in `height_unit`, NaN where invalid; x fastest.
    pub heights: Vec<f64>,
    pub height_unit: Unit,
    /// Pixel spacing `(dx, dy)` in `lateral_unit`; `None` when the file gives no size.
    pub spacing: Option<(f64, f64)>,
    pub lateral_unit: Unit,
    /// The header fields `spacing` comes from (x, y), named when it is refused.
    pub spacing_fields: (String, String),
    pub channel: String,
    pub notes: Vec<String>,
}

impl Raw {
    /// A channel already in metres.
    pub fn si(
        nx: usize,
        ny: usize,
        dx: f64,
        dy: f64,
        heights: Vec<f64>,
        channel: impl Into<String>,
    ) -> Raw {
        Raw {
            nx,
            ny,
            heights,
            height_unit: Unit::Known(1.0),
            spacing: Some((dx, dy)),
            lateral_unit: Unit::Known(1.0),
            spacing_fields: ("pixel size".into(), "pixel size".into()),
            channel: channel.into(),
            notes: Vec::new(),
        }
    }

    /// The same channel, its spacing taken from the header fields `x` and `y`.
    pub fn spacing_from(self, x: impl Into<String>, y: impl Into<String>) -> Raw {
        Raw {
            spacing_fields: (x.into(), y.into()),
            ..self
        }
    }

    /// The same channel with heights in `height` and spacing in `lateral` instead of metres.
    pub fn in_units(self, height: Unit, lateral: Unit) -> Raw {
        Raw {
            height_unit: height,
            lateral_unit: lateral,
            ..self
        }
    }

    fn info(&self, index: usize) -> ChannelInfo {
        ChannelInfo {
            index,
            name: self.channel.clone(),
            unit: match self.height_unit {
                Unit::Known(f) => units::name_of(f),
                Unit::Unknown => String::new(),
            },
            is_height: true,
            nx: self.nx,
            ny: self.ny,
        }
    }
}

/// What a reader returns: the channel list and, unless only the list was asked for, the
/// selected channel decoded.
#[derive(Debug)]
pub(crate) struct Decoded {
    pub channels: Vec<ChannelInfo>,
    pub selected: usize,
    pub raw: Option<Raw>,
}

impl Decoded {
    /// A single-channel file, listed as what `raw` holds: a height in its own unit.
    pub fn single(ctx: Ctx<'_>, want: Want<'_>, raw: Raw) -> Result<Decoded, ReadError> {
        Decoded::single_listed(ctx, want, raw.info(0), raw)
    }

    /// A single-channel file whose listing says more than `raw` does (the unit as the file
    /// states it, or that the channel is not a height), so `select` can refuse it.
    pub fn single_listed(
        ctx: Ctx<'_>,
        want: Want<'_>,
        info: ChannelInfo,
        raw: Raw,
    ) -> Result<Decoded, ReadError> {
        Decoded::pick(ctx, want, vec![info], |_, _| Ok(raw))
    }

    /// A multi-channel file: only the list for [`Want::List`]; otherwise the channel the
    /// user chose (or the first height channel) is decoded by `decode`, given its index
    /// and listing. Listing first means a bad `--channel` is refused before any data is
    /// touched.
    pub fn pick(
        ctx: Ctx<'_>,
        want: Want<'_>,
        channels: Vec<ChannelInfo>,
        decode: impl FnOnce(usize, &ChannelInfo) -> Result<Raw, ReadError>,
    ) -> Result<Decoded, ReadError> {
        let sel = match want {
            Want::List => {
                return Ok(Decoded {
                    selected: channels.iter().position(|c| c.is_height).unwrap_or(0),
                    channels,
                    raw: None,
                });
            }
            Want::Channel(sel) => sel,
        };
        let selected = select(ctx, &channels, sel)?;
        let raw = decode(selected, &channels[selected])?;
        Ok(Decoded {
            channels,
            selected,
            raw: Some(raw),
        })
    }
}

/// What the caller of a reader wants.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Want<'a> {
    /// Only the channel list.
    List,
    /// Decode this channel (default: the first height channel).
    Channel(Option<&'a ChannelSel>),
}

/// Choose a channel: the user's choice, or the first height channel.
pub(crate) fn select(
    ctx: Ctx<'_>,
    channels: &[ChannelInfo],
    sel: Option<&ChannelSel>,
) -> Result<usize, ReadError> {
    let list = || {
        channels
            .iter()
            .map(|c| {
                let unit = if c.unit.is_empty() {
                    String::new()
                } else {
                    format!(" [{}]", c.unit)
                };
                format!("{} {}{unit}", c.index, c.name)
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen = match sel {
        None => {
            return channels.iter().position(|c| c.is_height).ok_or_else(|| {
                ctx.err(
                    "channel",
                    format!(
                        "no channel holds heights (channels: {}); values in deg, V, N, … are \
                         not a height",
                        list()
                    ),
                    "export a height channel, or choose one with --channel and give its unit \
                     with --units if it is a length",
                )
            });
        }
        Some(ChannelSel::Index(i)) => {
            if *i >= channels.len() {
                return Err(ctx.err(
                    "channel",
                    format!(
                        "channel {i} requested but the file has {} (channels: {})",
                        channels.len(),
                        list()
                    ),
                    format!("choose --channel 0..{}", channels.len().saturating_sub(1)),
                ));
            }
            *i
        }
        Some(ChannelSel::Name(n)) => {
            let lower = n.to_lowercase();
            let exact: Vec<usize> = channels
                .iter()
                .filter(|c| c.name.to_lowercase() == lower)
                .map(|c| c.index)
                .collect();
            let partial: Vec<usize> = channels
                .iter()
                .filter(|c| c.name.to_lowercase().contains(&lower))
                .map(|c| c.index)
                .collect();
            match (exact.as_slice(), partial.as_slice()) {
                ([i, ..], _) => *i,
                ([], [i]) => *i,
                ([], []) => {
                    return Err(ctx.err(
                        "channel",
                        format!("no channel named `{n}` (channels: {})", list()),
                        "choose a channel by index or name with --channel",
                    ));
                }
                ([], _) => {
                    return Err(ctx.err(
                        "channel",
                        format!("`{n}` matches several channels (channels: {})", list()),
                        "choose it by index with --channel",
                    ));
                }
            }
        }
    };
    let c = &channels[chosen];
    if !c.is_height {
        return Err(ctx.err(
            "channel",
            format!(
                "channel {} `{}` is in `{}`, not a height (channels: {})",
                c.index,
                c.name,
                c.unit,
                list()
            ),
            "choose a height channel with --channel",
        ));
    }
    Ok(chosen)
}

/// File-name context for error messages.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub file: &'a str,
}

/// Text taken from a file, made fit for a one-line message: control characters become
/// spaces, runs of spaces collapse, and at most `max` characters are kept.
pub fn clean(s: &str, max: usize) -> String {
    let mut out = String::with_capacity(s.len().min(max));
    let mut space = false;
    for c in s.chars() {
        let c = if c.is_control() { ' ' } else { c };
        if c == ' ' && space {
            continue;
        }
        space = c == ' ';
        if out.chars().count() >= max {
            out.push('…');
            break;
        }
        out.push(c);
    }
    out.trim().to_string()
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
            field: clean(field, 120),
            problem: clean(&problem.into(), 600),
            fix: clean(&fix.into(), 300),
        }
    }

    /// Error for data that the header places beyond the end of the file: `what` (a
    /// channel, a block) at bytes `start..end` of a file `file_len` bytes long. A file cut
    /// short can still hold the part a reader needs whole; reading that part would hide
    /// that the copy is broken.
    pub fn truncated(
        &self,
        field: &str,
        what: &str,
        (start, end): (u64, u64),
        file_len: u64,
    ) -> ReadError {
        self.err(
            field,
            format!(
                "the header puts {what} at bytes {start}..{end}, but the file is only \
                 {file_len} bytes long"
            ),
            "the file is truncated: re-export or re-copy it",
        )
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

/// The value of `key` in a parsed `key = value` header, as a `T`. A missing value and one
/// that does not parse are both reported as `problem`, with `fix`.
pub(crate) fn header_value<T: std::str::FromStr>(
    ctx: Ctx<'_>,
    header: &HashMap<String, String>,
    key: &str,
    problem: &str,
    fix: &str,
) -> Result<T, ReadError> {
    header
        .get(key)
        .and_then(|v| v.trim().parse::<T>().ok())
        .ok_or_else(|| ctx.err(key, problem, fix))
}

/// Where the text header of a file ends: the position of `marker`; `fix` says what its
/// absence means for this format.
pub(crate) fn header_end(
    ctx: Ctx<'_>,
    bytes: &[u8],
    marker: &str,
    fix: &str,
) -> Result<usize, ReadError> {
    bytes
        .windows(marker.len())
        .position(|w| w == marker.as_bytes())
        .ok_or_else(|| ctx.err(marker, "header end marker not found", fix))
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

/// Decode the `nx × ny` samples at the start of a data block, `(name, bytes)`, once
/// [`checked_grid`] has found the grid within the limit and the block long enough.
pub(crate) fn decode_grid(
    ctx: Ctx<'_>,
    grid_field: &str,
    (nx, ny): (u64, u64),
    (name, data): (&str, &[u8]),
    kind: binary::Sample,
    little_endian: bool,
) -> Result<Vec<f64>, ReadError> {
    let size = kind.size() as u64;
    let n = checked_grid(ctx, grid_field, nx, ny, size, data.len() as u64)?;
    binary::decode(data, kind, little_endian, n)
        .ok_or_else(|| ctx.short(name, n as u64 * size, data.len() as u64))
}

/// Pixel spacings a surface scan can have [m]. Finer than a femtometre or coarser than a
/// metre is a header that is corrupt or in the wrong unit, and no statistic of such a map
/// means anything: at 1e-300 m the slopes Δz/Δx overflow to infinity (RMS slope `null`).
pub const PIXEL_SIZE_RANGE: (f64, f64) = (1e-15, 1.0);

/// Largest height magnitude a surface scan can have [m]. A kilometre is far beyond any
/// profilometer (the corpus's largest are test files of a few metres); past it the header's
/// height scale or unit is corrupt, and squares of such heights overflow to infinity
/// (Sq `inf`, a material file of nothing but bounds).
pub const HEIGHT_MAX: f64 = 1e3;

/// Check a pixel spacing in metres, `d` along `axis`, against [`PIXEL_SIZE_RANGE`]: the one
/// check every reader's spacing and the `--pixel-size`, `--size` and `--units` flags go
/// through. `field` is where the value came from; `fix` how to correct it there.
fn check_pixel_size(
    ctx: Ctx<'_>,
    field: &str,
    axis: &str,
    d: f64,
    fix: &str,
) -> Result<f64, ReadError> {
    let (lo, hi) = PIXEL_SIZE_RANGE;
    if d.is_finite() && (lo..=hi).contains(&d) {
        return Ok(d);
    }
    let why = if !(d.is_finite() && d > 0.0) {
        "is not a positive finite length".to_string()
    } else if d < lo {
        format!("is below {lo:e} m, finer than any instrument resolves")
    } else {
        format!("is above {hi} m, coarser than any surface scan")
    };
    Err(ctx.err(
        field,
        format!("the pixel spacing along {axis}, {d:e} m, {why}"),
        fix,
    ))
}

/// Check a pixel spacing in the file's units: finite and positive.
pub(crate) fn check_spacing(ctx: Ctx<'_>, field: &str, d: f64) -> Result<f64, ReadError> {
    if d.is_finite() && d > 0.0 {
        Ok(d)
    } else {
        Err(ctx.err(
            field,
            format!("pixel spacing {d} is not a positive finite number"),
            "check the scan-size fields of the header",
        ))
    }
}

/// Largest scan file read: 4 GiB, above any instrument's export (a 16 384² map of
/// 8-byte heights is 2 GiB; text exports run to ~1 GiB).
pub const MAX_SCAN_BYTES: u64 = 4 << 30;

/// The bytes of the scan file at `path`: a regular file of at most [`MAX_SCAN_BYTES`]
/// (a FIFO, device or directory is refused by name rather than read forever).
pub fn read_scan_file(path: &Path) -> Result<Vec<u8>, ReadError> {
    Ok(safe_io::read_input(path, "scan file", MAX_SCAN_BYTES)?)
}

/// Read and convert a file. The format comes from `opts.format` or is detected.
pub fn open_path(path: &Path, opts: &ReadOptions) -> Result<Scan, ReadError> {
    let bytes = read_scan_file(path)?;
    open_bytes(&path.display().to_string(), &bytes, opts)
}

/// Read and convert a file already in memory; `name` is used for format detection
/// (extension) and messages.
pub fn open_bytes(name: &str, bytes: &[u8], opts: &ReadOptions) -> Result<Scan, ReadError> {
    let (format, guessed) = format_of(name, bytes, opts)?;
    let ctx = Ctx { file: name };
    let d = (format.reader().read)(ctx, bytes, Want::Channel(opts.channel.as_ref()))?;
    let raw = d.raw.ok_or_else(|| {
        ctx.err(
            "channel",
            "the reader returned no data",
            "report this file as a bug",
        )
    })?;
    let (mut topo, mut notes) = finish(ctx, raw, opts, format)?;
    if guessed {
        notes.insert(
            0,
            format!(
                "format not recognised from its content; read as `{}` from its layout of \
                 numbers (force another with --format)",
                format.name()
            ),
        );
    }
    topo.channel = clean(&topo.channel, 80);
    Ok(Scan {
        topo,
        format,
        channels: cleaned(d.channels),
        channel: d.selected,
        notes: notes.iter().map(|n| clean(n, 400)).collect(),
    })
}

/// The channels of a file, without decoding any.
pub fn list_channels(
    name: &str,
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<(Format, Vec<ChannelInfo>), ReadError> {
    let (format, _) = format_of(name, bytes, opts)?;
    let d = (format.reader().read)(Ctx { file: name }, bytes, Want::List)?;
    Ok((format, cleaned(d.channels)))
}

fn cleaned(mut channels: Vec<ChannelInfo>) -> Vec<ChannelInfo> {
    for c in &mut channels {
        c.name = clean(&c.name, 80);
        c.unit = clean(&c.unit, 24);
    }
    channels
}

/// Read a file into metres (see [`open_path`] for the details and notes).
pub fn read_path(path: &Path, opts: &ReadOptions) -> Result<Topography, ReadError> {
    open_path(path, opts).map(|s| s.topo)
}

/// Parse a file already in memory (see [`open_bytes`]).
pub fn read_bytes(name: &str, bytes: &[u8], opts: &ReadOptions) -> Result<Topography, ReadError> {
    open_bytes(name, bytes, opts).map(|s| s.topo)
}

/// The format to read with, and whether it was only guessed by [`registry::text_fallback`].
fn format_of(name: &str, bytes: &[u8], opts: &ReadOptions) -> Result<(Format, bool), ReadError> {
    if let Some(f) = opts.format {
        return Ok((f, false));
    }
    let found = registry::sniffed(name, bytes);
    if let Some((f, Sniff::Magic)) = found {
        return Ok((f, false));
    }
    // A format known by its signature or extension that no reader reads (a JPK TIFF that
    // the Park reader would half-recognise, an image) is named for what it is.
    if let Some((what, fix)) = registry::unread_format(name, bytes) {
        return Err(ReadError::NotRead {
            file: name.to_string(),
            what,
            fix,
        });
    }
    // Checked before the weaker content matches: a NanoScope header whose first bytes
    // were overwritten is still text with numbers, and would be read as a matrix.
    if let Some(e) = registry::signature_mismatch(name, bytes, found.map(|(f, _)| f)) {
        return Err(e);
    }
    if let Some((f, _)) = found {
        return Ok((f, false));
    }
    // Numbers in a text file say more than a binary format's extension (a text `.dat`).
    if let Some(f) = registry::text_fallback(bytes) {
        return Ok((f, true));
    }
    registry::by_extension(name)
        .map(|f| (f, false))
        .ok_or_else(|| ReadError::UnknownFormat {
            file: name.to_string(),
            fix: format!(
                "supported: {}; force one with --format",
                registry::supported_list()
            ),
        })
}

/// Apply the user's units and sizes to a decoded channel; name every missing fact.
fn finish(
    ctx: Ctx<'_>,
    raw: Raw,
    opts: &ReadOptions,
    format: Format,
) -> Result<(Topography, Vec<String>), ReadError> {
    let Raw {
        nx,
        ny,
        mut heights,
        height_unit,
        spacing,
        lateral_unit,
        spacing_fields,
        channel,
        mut notes,
    } = raw;
    check_grid(ctx, nx, ny, heights.len())?;
    let mut missing = Missing::default();
    let z = height_factor(height_unit, opts, &mut notes, &mut missing);
    let (dx, dy) = spacing_in_metres(
        (nx, ny),
        spacing,
        lateral_unit,
        opts,
        &mut notes,
        &mut missing,
    );
    if !missing.facts.is_empty() {
        return Err(ctx.err(
            "units",
            format!("the file does not state {}", missing.facts.join(", nor ")),
            format!("pass {}", missing.fixes.join(" and ")),
        ));
    }
    let (range_fields, range_fixes) = spacing_sources(opts, lateral_unit, spacing_fields);
    // A single column is a profile along y, as a single row is one along x: its x spacing
    // means nothing and is not checked.
    let column = nx == 1;
    let dx = if column {
        f64::NAN
    } else {
        check_pixel_size(ctx, &range_fields.0, "x", dx, &range_fixes.0)?
    };
    let dy = if ny == 1 {
        dx
    } else {
        check_pixel_size(ctx, &range_fields.1, "y", dy, &range_fixes.1)?
    };
    let (nx, ny, dx) = if column {
        notes.push(format!(
            "a single column of {ny} points: read as a profile along y"
        ));
        (ny, 1, dy)
    } else {
        (nx, ny, dx)
    };
    if !(z.is_finite() && z != 0.0) {
        return Err(ctx.err(
            "height scale",
            format!("scale factor {z} is not usable"),
            "the header is corrupt",
        ));
    }
    scale_heights(ctx, &mut heights, z, height_unit)?;
    Ok((
        Topography {
            nx,
            ny,
            dx,
            dy,
            heights,
            channel,
            format: format.name(),
        },
        notes,
    ))
}

/// A grid that holds its values and more than one point.
fn check_grid(ctx: Ctx<'_>, nx: usize, ny: usize, values: usize) -> Result<(), ReadError> {
    if values != nx.saturating_mul(ny) || nx == 0 || ny == 0 {
        return Err(ctx.err(
            "data",
            format!("{values} values for a {nx} × {ny} grid"),
            "the file is corrupt",
        ));
    }
    if nx == 1 && ny == 1 {
        return Err(ctx.err(
            "data",
            "the file holds a single point (a 1 × 1 grid)",
            "a roughness fit needs a profile or a map; export the whole scan",
        ));
    }
    Ok(())
}

/// The facts a file does not state and the flags that supply them, gathered so that one
/// error names them all.
#[derive(Default)]
struct Missing {
    facts: Vec<&'static str>,
    fixes: Vec<&'static str>,
}

/// Metres per stored height unit: the file's, else `--units`'; NaN (and a missing fact)
/// when neither says.
fn height_factor(
    height_unit: Unit,
    opts: &ReadOptions,
    notes: &mut Vec<String>,
    missing: &mut Missing,
) -> f64 {
    match (height_unit, opts.units) {
        (Unit::Known(f), Some(u)) => {
            if (u.height / f - 1.0).abs() > 1e-9 {
                notes.push(format!(
                    "--units ignored for heights: the file states them in {}",
                    units::name_of(f)
                ));
            }
            f
        }
        (Unit::Known(f), None) => f,
        (Unit::Unknown, Some(u)) => {
            notes.push(format!(
                "heights taken in {} (--units)",
                units::name_of(u.height)
            ));
            u.height
        }
        (Unit::Unknown, None) => {
            missing.facts.push("the unit of its heights");
            missing
                .fixes
                .push("--units um (or m, mm, nm; `--units um,nm` for lateral,height)");
            f64::NAN
        }
    }
}

/// The file's spacing in metres, in its unit or the one `--units` gives; `None` when
/// neither says.
fn lateral_in_metres(
    d: (f64, f64),
    lateral_unit: Unit,
    opts: &ReadOptions,
    notes: &mut Vec<String>,
) -> Option<(f64, f64)> {
    match (lateral_unit, opts.units) {
        (Unit::Known(f), Some(u)) => {
            if (u.lateral / f - 1.0).abs() > 1e-9 {
                notes.push(format!(
                    "--units ignored for lengths: the file states them in {}",
                    units::name_of(f)
                ));
            }
            Some((d.0 * f, d.1 * f))
        }
        (Unit::Known(f), None) => Some((d.0 * f, d.1 * f)),
        (Unit::Unknown, Some(u)) => {
            notes.push(format!(
                "lengths taken in {} (--units)",
                units::name_of(u.lateral)
            ));
            Some((d.0 * u.lateral, d.1 * u.lateral))
        }
        (Unit::Unknown, None) => None,
    }
}

/// Pixel spacing `(dx, dy)` [m]: `--pixel-size`, else `--size` over the grid, else the
/// file's; NaN (and a missing fact) when none gives it.
fn spacing_in_metres(
    (nx, ny): (usize, usize),
    spacing: Option<(f64, f64)>,
    lateral_unit: Unit,
    opts: &ReadOptions,
    notes: &mut Vec<String>,
    missing: &mut Missing,
) -> (f64, f64) {
    if let Some(p) = opts.pixel_size {
        if spacing.is_some() {
            notes.push("--pixel-size overrides the file's pixel size".into());
        }
        p
    } else if let Some(s) = opts.size {
        if spacing.is_some() {
            notes.push("--size overrides the file's scan size".into());
        }
        (
            s.0 / nx as f64,
            if ny > 1 {
                s.1 / ny as f64
            } else {
                s.0 / nx as f64
            },
        )
    } else if let Some(d) = spacing {
        match lateral_in_metres(d, lateral_unit, opts, notes) {
            Some(d) => d,
            None => {
                missing.facts.push("the unit of its lengths");
                if !missing.fixes.iter().any(|f| f.starts_with("--units")) {
                    missing.fixes.push("--units um (or m, mm, nm)");
                }
                (f64::NAN, f64::NAN)
            }
        }
    } else {
        missing.facts.push("its pixel size or scan size");
        missing
            .fixes
            .push("--pixel-size 0.5um (or --size 100um,80um)");
        (f64::NAN, f64::NAN)
    }
}

/// Where the spacing comes from, for the range check: a flag, or header fields (read in
/// the unit --units gave when the file states none); `((x field, y field), (x fix, y fix))`.
fn spacing_sources(
    opts: &ReadOptions,
    lateral_unit: Unit,
    header_fields: (String, String),
) -> ((String, String), (String, String)) {
    let flag_fix = |flag: &str| {
        let (lo, hi) = PIXEL_SIZE_RANGE;
        format!("give {flag} as a length with its unit within {lo:e} m … {hi} m, e.g. {flag} 0.5um")
    };
    let from_units = matches!(lateral_unit, Unit::Unknown) && opts.units.is_some();
    let file_fix = |field: &str| {
        if from_units {
            format!(
                "`{field}` is in the lateral unit --units gives: pass the unit it is really in, \
                 or override the spacing with --pixel-size or --size"
            )
        } else {
            format!(
                "the header's `{field}` is corrupt or in the wrong unit: correct it, or override \
                 it with --pixel-size or --size"
            )
        }
    };
    if opts.pixel_size.is_some() {
        let f = "--pixel-size".to_string();
        (
            (f.clone(), f),
            (flag_fix("--pixel-size"), flag_fix("--pixel-size")),
        )
    } else if opts.size.is_some() {
        let f = "--size".to_string();
        ((f.clone(), f), (flag_fix("--size"), flag_fix("--size")))
    } else {
        let (x, y) = header_fields;
        let fixes = (file_fix(&x), file_fix(&y));
        ((x, y), fixes)
    }
}

/// Heights into metres (`z` per stored unit); invalid values become NaN. A height that
/// overflows or exceeds [`HEIGHT_MAX`] is a wrong scale, named with its likely cause.
fn scale_heights(
    ctx: Ctx<'_>,
    heights: &mut [f64],
    z: f64,
    height_unit: Unit,
) -> Result<(), ReadError> {
    let mut overflowed = 0usize;
    let mut largest = 0.0f64;
    for h in heights.iter_mut() {
        if h.is_finite() {
            *h *= z;
            if h.is_finite() {
                largest = largest.max(h.abs());
            } else {
                overflowed += 1;
                *h = f64::NAN;
            }
        } else {
            *h = f64::NAN;
        }
    }
    if overflowed > 0 || largest > HEIGHT_MAX {
        let what = if overflowed > 0 {
            format!("{overflowed} heights overflow to infinity")
        } else {
            format!("the heights reach {largest:.4e} m")
        };
        let fix = if matches!(height_unit, Unit::Unknown) {
            "the file states no height unit: pass the one it is in with --units \
             (`--units um,nm` for lateral,height)"
        } else {
            "the header's height scale (sensitivity, multiplier or unit) is corrupt: \
             re-export the scan"
        };
        return Err(ctx.err(
            "height scale",
            format!("{what}, above {HEIGHT_MAX:e} m: no surface scan is that tall"),
            fix,
        ));
    }
    Ok(())
}
