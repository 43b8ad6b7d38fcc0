//! The one list of readers. Detection, `--format`, the `--help` text and the
//! "supported formats" error are all derived from [`READERS`].

use super::{Ctx, Decoded, Want};
use crate::ReadError;
use std::path::Path;

/// How sure a content check is that a file is in a reader's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Sniff {
    /// Not this format.
    No,
    /// Could be (generic text or container shape).
    Maybe,
    /// The structure checks out.
    Likely,
    /// A format-specific magic number.
    Magic,
}

/// A reader: its names, how to recognise its files, and its read function.
pub struct Reader {
    /// Name used by `--format` and in messages.
    pub name: &'static str,
    /// Other accepted `--format` names.
    pub aliases: &'static [&'static str],
    /// One-line description for `--help`.
    pub description: &'static str,
    /// File extensions (lower case, no dot).
    pub extensions: &'static [&'static str],
    /// True for binary formats: an extension match alone selects the reader, so a
    /// damaged file gets that reader's specific error.
    pub binary: bool,
    /// Content check on the whole file (it must only look at the first few kB).
    pub sniff: fn(&[u8]) -> Sniff,
    pub(crate) read: fn(Ctx<'_>, &[u8], Want<'_>) -> Result<Decoded, ReadError>,
}

impl std::fmt::Debug for Reader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// A reader chosen by name or detection.
#[derive(Debug, Clone, Copy)]
pub struct Format(&'static Reader);

impl PartialEq for Format {
    fn eq(&self, other: &Format) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}
impl Eq for Format {}

impl Format {
    /// Parse a format name or alias as given on the command line.
    pub fn from_name(name: &str) -> Option<Format> {
        let n = name.trim().to_ascii_lowercase();
        READERS
            .iter()
            .find(|r| r.name == n || r.aliases.contains(&n.as_str()))
            .map(Format)
    }

    /// The reader's `--format` name.
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// The reader.
    pub fn reader(self) -> &'static Reader {
        self.0
    }

    /// Every format, in registry order.
    pub fn all() -> impl Iterator<Item = Format> {
        READERS.iter().map(Format)
    }
}

use super::{
    al3d, bcr, dektak, frt, gsf, ibw, matrix, metropro, mi, mnt, nanoscope, nid, opd, park, plu,
    sdf, sur, tmd, wsxm, x3p, xyz,
};

/// `Magic` when the file starts with any of `magics`: some formats have variants (ASCII
/// or binary, compressed or not) that differ in their first bytes.
fn starts(bytes: &[u8], magics: &[&[u8]]) -> Sniff {
    magic_at(bytes, 0, magics)
}

/// `Magic` when any of `magics` stands at byte `offset`.
fn magic_at(bytes: &[u8], offset: usize, magics: &[&[u8]]) -> Sniff {
    let tail = bytes.get(offset..).unwrap_or(&[]);
    if magics.iter().any(|m| tail.starts_with(m)) {
        Sniff::Magic
    } else {
        Sniff::No
    }
}

/// Every reader. Order breaks ties in detection (more specific first).
pub static READERS: &[Reader] = &[
    Reader {
        name: "x3p",
        aliases: &[],
        description: "ISO 25178-72 X3P (zip with main.xml)",
        extensions: &["x3p"],
        binary: true,
        sniff: |b| starts(b, &[b"PK\x03\x04"]),
        read: x3p::read,
    },
    Reader {
        name: "sdf",
        aliases: &[],
        description: "Surface Data File (BCR/ISO 25178-71 SDF, binary or ASCII)",
        extensions: &["sdf"],
        binary: true,
        sniff: |b| starts(b, &[b"aBCR-", b"bBCR-", b"aISO-", b"bISO-"]),
        read: sdf::read,
    },
    Reader {
        name: "bcr",
        aliases: &["bcrf", "bcrstm"],
        description: "BCR-STM (bcrstm/bcrf, ASCII or UTF-16 header)",
        extensions: &["bcr", "bcrf", "bcrstm"],
        binary: true,
        // The UTF-16LE variant spells `fileformat` with NULs between the letters.
        sniff: |b| starts(b, &[b"fileformat", b"f\0i\0l\0e\0f\0o\0r\0m\0a\0t\0"]),
        read: bcr::read,
    },
    Reader {
        name: "gsf",
        aliases: &[],
        description: "Gwyddion Simple Field .gsf",
        extensions: &["gsf"],
        binary: true,
        sniff: |b| starts(b, &[b"Gwyddion Simple Field"]),
        read: gsf::read,
    },
    Reader {
        name: "nanoscope",
        aliases: &["di", "spm"],
        description: "Bruker/Veeco NanoScope .di/.spm/.001 (multi-channel)",
        extensions: &["di", "spm", "001", "002", "003", "004"],
        binary: true,
        sniff: |b| starts(b, &[b"\\*File list"]),
        read: nanoscope::read,
    },
    Reader {
        name: "plu",
        aliases: &["sensofar"],
        description: "Sensofar .plu/.apx (confocal/interferometric)",
        extensions: &["plu", "apx"],
        binary: true,
        sniff: plu::sniff,
        read: plu::read,
    },
    Reader {
        name: "sur",
        aliases: &["digitalsurf"],
        description: "Digital Surf .sur (MountainsMap)",
        extensions: &["sur"],
        binary: true,
        sniff: |b| starts(b, &[b"DIGITAL SURF", b"DSCOMPRESSED"]),
        read: sur::read,
    },
    Reader {
        name: "mnt",
        aliases: &["mountains"],
        description: "Digital Surf MountainsMap document .mnt (OLE compound file)",
        extensions: &["mnt"],
        binary: true,
        sniff: mnt::sniff,
        read: mnt::read,
    },
    Reader {
        name: "metropro",
        aliases: &["zygo"],
        description: "Zygo MetroPro .dat",
        extensions: &["dat"],
        binary: true,
        sniff: metropro::sniff,
        read: metropro::read,
    },
    Reader {
        name: "opd",
        aliases: &["wyko"],
        description: "Veeco/Bruker Wyko Vision .opd",
        extensions: &["opd"],
        binary: true,
        // After the 2-byte header, the directory's own descriptor names itself.
        sniff: |b| magic_at(b, 2, &[b"Directory"]),
        read: opd::read,
    },
    Reader {
        name: "al3d",
        aliases: &["alicona"],
        description: "Alicona Imaging .al3d",
        extensions: &["al3d"],
        binary: true,
        sniff: |b| starts(b, &[b"AliconaImaging"]),
        read: al3d::read,
    },
    Reader {
        name: "nid",
        aliases: &["nanosurf", "ezd"],
        description: "Nanosurf easyScan .nid/.ezd (multi-channel)",
        extensions: &["nid", "ezd"],
        binary: true,
        sniff: |b| starts(b, &[b"[DataSet]"]),
        read: nid::read,
    },
    Reader {
        name: "ibw",
        aliases: &["igor", "asylum"],
        description: "Igor binary wave .ibw (Asylum Research; multi-channel)",
        extensions: &["ibw"],
        binary: true,
        sniff: ibw::sniff,
        read: ibw::read,
    },
    Reader {
        name: "park",
        aliases: &["psia", "tiff", "tif"],
        description: "Park Systems TIFF (private tags 50432–50435)",
        extensions: &["tiff", "tif"],
        binary: true,
        sniff: park::sniff,
        read: park::read,
    },
    Reader {
        name: "mi",
        aliases: &["picoview", "keysight"],
        description: "Keysight/Agilent PicoView .mi (multi-channel)",
        extensions: &["mi"],
        binary: true,
        sniff: |b| starts(b, &[b"fileType      Image"]),
        read: mi::read,
    },
    Reader {
        name: "wsxm",
        aliases: &["stp", "top"],
        description: "WSxM .stp/.top",
        extensions: &["stp", "top", "tom"],
        binary: true,
        sniff: |b| starts(b, &[b"WSxM file copyright"]),
        read: wsxm::read,
    },
    Reader {
        name: "frt",
        aliases: &["microprof"],
        description: "FRT MicroProf .frt",
        extensions: &["frt"],
        binary: true,
        sniff: |b| starts(b, &[b"FRTM_GLIDERV"]),
        read: frt::read,
    },
    Reader {
        name: "tmd",
        aliases: &["truemap"],
        description: "TrueMap .tmd",
        extensions: &["tmd"],
        binary: true,
        sniff: |b| starts(b, &[b"Binary TrueMap Data File"]),
        read: tmd::read,
    },
    Reader {
        name: "dektak",
        aliases: &[],
        description: "Bruker Dektak CSV profile",
        extensions: &["csv"],
        binary: false,
        sniff: dektak::sniff,
        read: dektak::read,
    },
    Reader {
        name: "matrix",
        aliases: &["asc", "txt", "gwyddion"],
        description: "text matrix (Gwyddion export in any locale, key=value / key: value headers)",
        extensions: &["txt", "asc", "dat", "csv"],
        binary: false,
        sniff: matrix::sniff,
        read: matrix::read,
    },
    Reader {
        name: "xyz",
        aliases: &["csv", "columns"],
        description: "column text: x z profiles or x y z maps (CSV/TSV, unit headers, UTF-16)",
        extensions: &["xyz", "csv", "txt", "asc", "dat", "prf"],
        binary: false,
        sniff: xyz::sniff,
        read: xyz::read,
    },
];

/// `x3p, sdf, …` for error messages.
pub fn supported_list() -> String {
    READERS
        .iter()
        .map(|r| {
            if r.extensions.is_empty() {
                r.name.to_string()
            } else {
                format!("{} (.{})", r.name, r.extensions.join("/."))
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The `--format` help text.
pub fn format_help() -> String {
    let mut s = String::from("Force the file format instead of detecting it:");
    for r in READERS {
        s.push_str(&format!("\n  {:<10} {}", r.name, r.description));
    }
    s
}

/// Guess the format: a magic number wins, then content checks (with the extension as
/// tie-breaker), then the extension of a binary format alone.
pub fn detect(name: &str, bytes: &[u8]) -> Option<Format> {
    sniffed(name, bytes).or_else(|| by_extension(name))
}

fn extension(name: &str) -> String {
    Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// The format whose magic number or content check accepts `bytes` (the extension breaks ties).
pub(crate) fn sniffed(name: &str, bytes: &[u8]) -> Option<Format> {
    let ext = extension(name);
    let head = &bytes[..bytes.len().min(1 << 16)];
    let mut best: Option<(u8, &'static Reader)> = None;
    for r in READERS {
        let s = (r.sniff)(head);
        if s == Sniff::No {
            continue;
        }
        let score = 2 * s as u8 + u8::from(r.extensions.contains(&ext.as_str()));
        if best.is_none_or(|(b, _)| score > b) {
            best = Some((score, r));
        }
    }
    best.map(|(_, r)| Format(r))
}

/// The binary format that uses the extension of `name`.
pub(crate) fn by_extension(name: &str) -> Option<Format> {
    let ext = extension(name);
    READERS
        .iter()
        .find(|r| r.binary && r.extensions.contains(&ext.as_str()))
        .map(Format)
}

/// The text reader a text file with numbers most resembles, for when [`detect`] finds none:
/// reading it with that reader gives either the data or that reader's own, specific
/// complaint (a ragged row, a single data line), where "unknown format" helps nobody.
/// A matrix header key means a matrix; unit titles or rows of 2–5 numbers mean columns;
/// any other numbers are taken as a matrix. `None` for binary files and text without numbers.
pub fn text_fallback(bytes: &[u8]) -> Option<Format> {
    use super::text::SNIFF_LEN;
    let sample = super::text::sniff_sample(bytes)?;
    // The sniffers drop the sample's last line in case the cut split it; a short file is
    // whole, and its last line may be its only data line.
    let lines: Vec<&str> = if bytes.len() <= SNIFF_LEN {
        sample.lines().collect()
    } else {
        super::text::sample_lines(&sample)
    };
    let name = if matrix::has_header_key(&lines) {
        "matrix"
    } else if !xyz::has_numeric_line(&lines) {
        return None;
    } else if xyz::column_layout(&lines).is_some() {
        "xyz"
    } else {
        "matrix"
    };
    Format::from_name(name)
}
