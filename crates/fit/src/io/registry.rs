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
    /// damaged file gets that reader's specific error (unless the format has a
    /// [`signature`](Self::signature) and the file lacks it).
    pub binary: bool,
    /// What every file of this format carries, when the format has such a thing; `None`
    /// for formats without one (text exports, Sensofar's date-string header).
    pub signature: Option<Signature>,
    /// Content check on the whole file (it must only look at the first few kB).
    pub sniff: fn(&[u8]) -> Sniff,
    pub(crate) read: fn(Ctx<'_>, &[u8], Want<'_>) -> Result<Decoded, ReadError>,
}

impl std::fmt::Debug for Reader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The bytes every file of a format carries, so a file named like that format but
/// without them is refused as damaged or misnamed instead of being parsed as garbage.
pub struct Signature {
    /// Byte offset the signature stands at.
    pub offset: usize,
    /// The signature as messages show it.
    pub describe: &'static str,
    /// True when the file carries it. Looser than the format's sniff where a dialect or
    /// a version the reader explains (Igor version 2, a NanoScope force curve) would
    /// otherwise be called damaged.
    pub present: fn(&[u8]) -> bool,
}

impl std::fmt::Debug for Signature {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe)
    }
}

/// The signature standing first in the file, one of several spellings.
macro_rules! prefix {
    ($describe:expr, $magics:expr) => {
        Some(Signature {
            offset: 0,
            describe: $describe,
            present: |b| starts(b, $magics) == Sniff::Magic,
        })
    };
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
    al3d, bcr, datx, dektak, frt, gsf, gwy, ibw, jpk, lext, matrix, metropro, mi, mnt, nanoscope,
    netcdf, nid, nms, npy, opd, opdx, park, plu, sdf, sur, tmd, vk4, wsxm, x3p, xyz, zmg, zon,
};

/// `Magic` when the file starts with any of `magics`: some formats have variants (ASCII
/// or binary, compressed or not) that differ in their first bytes.
fn starts(bytes: &[u8], magics: &[&[u8]]) -> Sniff {
    magic_at(bytes, 0, magics)
}

/// What a NanoScope file starts with: images, electrochemistry images and force curves
/// (which the reader names as such rather than calling them damaged).
const NANOSCOPE: &[&[u8]] = &[b"\\*File list", b"\\*EC File list", b"\\*Force file list"];

// The magic numbers of the formats identified by their first bytes alone (some formats
// have variants, ASCII or binary, compressed or not, that differ there).
const X3P: &[&[u8]] = &[b"PK\x03\x04"];
const SDF: &[&[u8]] = &[b"aBCR-", b"bBCR-", b"aISO-", b"bISO-"];
// The UTF-16LE variant of BCR spells `fileformat` with NULs between the letters.
const BCR: &[&[u8]] = &[b"fileformat", b"f\0i\0l\0e\0f\0o\0r\0m\0a\0t\0"];
const GSF: &[&[u8]] = &[b"Gwyddion Simple Field"];
const SUR: &[&[u8]] = &[b"DIGITAL SURF", b"DSCOMPRESSED"];
const AL3D: &[&[u8]] = &[b"AliconaImaging"];
const NID: &[&[u8]] = &[b"[DataSet]"];
const WSXM: &[&[u8]] = &[b"WSxM file copyright"];
const FRT: &[&[u8]] = &[b"FRTM_GLIDERV"];
const TMD: &[&[u8]] = &[b"Binary TrueMap Data File"];
// After OPD's 2-byte header, the directory's own descriptor names itself.
const OPD: &[&[u8]] = &[b"Directory"];
const NPY: &[&[u8]] = &[npy::MAGIC];
const GWY: &[&[u8]] = &[gwy::MAGIC, b"GWYO"];
const NETCDF: &[&[u8]] = &[b"CDF\x01", b"CDF\x02", b"CDF\x05"];
const OPDX: &[&[u8]] = &[opdx::MAGIC];
const HDF5: &[u8] = b"\x89HDF\r\n\x1a\n";

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
        signature: prefix!("`PK\\x03\\x04` (a zip archive)", X3P),
        sniff: |b| starts(b, X3P),
        read: x3p::read,
    },
    Reader {
        name: "sdf",
        aliases: &[],
        description: "Surface Data File (BCR/ISO 25178-71 SDF, binary or ASCII)",
        extensions: &["sdf"],
        binary: true,
        signature: prefix!("`aBCR-`, `bBCR-`, `aISO-` or `bISO-`", SDF),
        sniff: |b| starts(b, SDF),
        read: sdf::read,
    },
    Reader {
        name: "bcr",
        aliases: &["bcrf", "bcrstm"],
        description: "BCR-STM (bcrstm/bcrf, ASCII or UTF-16 header)",
        extensions: &["bcr", "bcrf", "bcrstm"],
        binary: true,
        signature: prefix!("`fileformat` (ASCII or UTF-16)", BCR),
        sniff: |b| starts(b, BCR),
        read: bcr::read,
    },
    Reader {
        name: "gsf",
        aliases: &[],
        description: "Gwyddion Simple Field .gsf",
        extensions: &["gsf"],
        binary: true,
        signature: prefix!("`Gwyddion Simple Field`", GSF),
        sniff: |b| starts(b, GSF),
        read: gsf::read,
    },
    Reader {
        name: "nanoscope",
        aliases: &["di", "spm"],
        description: "Bruker/Veeco NanoScope .di/.spm/.001 (multi-channel)",
        extensions: &["di", "spm", "001", "002", "003", "004"],
        binary: true,
        signature: prefix!("`\\*File list`", NANOSCOPE),
        sniff: |b| starts(b, NANOSCOPE),
        read: nanoscope::read,
    },
    Reader {
        name: "plu",
        aliases: &["sensofar"],
        description: "Sensofar .plu/.apx (confocal/interferometric)",
        extensions: &["plu", "apx"],
        binary: true,
        signature: None,
        sniff: plu::sniff,
        read: plu::read,
    },
    Reader {
        name: "sur",
        aliases: &["digitalsurf"],
        description: "Digital Surf .sur (MountainsMap)",
        extensions: &["sur"],
        binary: true,
        signature: prefix!("`DIGITAL SURF` or `DSCOMPRESSED`", SUR),
        sniff: |b| starts(b, SUR),
        read: sur::read,
    },
    Reader {
        name: "mnt",
        aliases: &["mountains"],
        description: "Digital Surf MountainsMap document .mnt (OLE compound file)",
        extensions: &["mnt"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "the compound-file (OLE) magic D0 CF 11 E0 A1 B1 1A E1",
            present: super::ole::is_ole,
        }),
        sniff: mnt::sniff,
        read: mnt::read,
    },
    Reader {
        name: "metropro",
        aliases: &["zygo"],
        description: "Zygo MetroPro .dat",
        extensions: &["dat"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "the MetroPro magic number 88 1B 03 6F, 70 or 71",
            present: |b| metropro::sniff(b) == Sniff::Magic,
        }),
        sniff: metropro::sniff,
        read: metropro::read,
    },
    Reader {
        name: "opd",
        aliases: &["wyko"],
        description: "Veeco/Bruker Wyko Vision .opd",
        extensions: &["opd"],
        binary: true,
        signature: Some(Signature {
            offset: 2,
            describe: "`Directory`",
            present: |b| magic_at(b, 2, OPD) == Sniff::Magic,
        }),
        sniff: |b| magic_at(b, 2, OPD),
        read: opd::read,
    },
    Reader {
        name: "al3d",
        aliases: &["alicona"],
        description: "Alicona Imaging .al3d",
        extensions: &["al3d"],
        binary: true,
        signature: prefix!("`AliconaImaging`", AL3D),
        sniff: |b| starts(b, AL3D),
        read: al3d::read,
    },
    Reader {
        name: "nid",
        aliases: &["nanosurf", "ezd"],
        description: "Nanosurf easyScan .nid/.ezd (multi-channel)",
        extensions: &["nid", "ezd"],
        binary: true,
        signature: prefix!("`[DataSet]`", NID),
        sniff: |b| starts(b, NID),
        read: nid::read,
    },
    Reader {
        name: "ibw",
        aliases: &["igor", "asylum"],
        description: "Igor binary wave .ibw (Asylum Research; multi-channel)",
        extensions: &["ibw"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "an Igor version word (1, 2, 3 or 5)",
            present: ibw::has_version_word,
        }),
        sniff: ibw::sniff,
        read: ibw::read,
    },
    Reader {
        name: "jpk",
        aliases: &["jpk-scan"],
        description: "JPK (Bruker) image scan .jpk (TIFF with JPK's tags; multi-channel)",
        extensions: &["jpk"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "a TIFF byte-order mark (`II*\\0` or `MM\\0*`)",
            present: super::tiff::is_tiff,
        }),
        // Any TIFF could be one (its first directory may lie past the sniffed head): the
        // .jpk extension then breaks the tie with Park's TIFF.
        sniff: |b| {
            if jpk::is_jpk(b) {
                Sniff::Magic
            } else if super::tiff::is_tiff(b) {
                Sniff::Maybe
            } else {
                Sniff::No
            }
        },
        read: jpk::read,
    },
    Reader {
        name: "park",
        aliases: &["psia", "tiff", "tif"],
        description: "Park Systems TIFF (private tags 50432–50435)",
        extensions: &["tiff", "tif"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "a TIFF byte-order mark (`II*\\0` or `MM\\0*`)",
            present: super::tiff::is_tiff,
        }),
        sniff: park::sniff,
        read: park::read,
    },
    Reader {
        name: "lext",
        aliases: &["olympus", "ols4000", "ols5000"],
        description: "Olympus LEXT .lext (OLS4000/OLS5000 laser confocal; TIFF with XML)",
        extensions: &["lext"],
        binary: true,
        signature: Some(Signature {
            offset: 0,
            describe: "a TIFF byte-order mark (`II*\\0` or `MM\\0*`)",
            present: super::tiff::is_tiff,
        }),
        // Any TIFF could be one (its first directory may lie past the sniffed head): the
        // .lext extension then breaks the tie; other TIFFs go to JPK's and Park's readers,
        // listed first.
        sniff: lext::sniff,
        read: lext::read,
    },
    Reader {
        name: "mi",
        aliases: &["picoview", "keysight"],
        description: "Keysight/Agilent PicoView .mi (multi-channel)",
        extensions: &["mi"],
        binary: true,
        signature: prefix!("`fileType`", &[b"fileType"]),
        sniff: |b| starts(b, &[b"fileType      Image"]),
        read: mi::read,
    },
    Reader {
        name: "wsxm",
        aliases: &["stp", "top"],
        description: "WSxM .stp/.top",
        extensions: &["stp", "top", "tom"],
        binary: true,
        signature: prefix!("`WSxM file copyright`", WSXM),
        sniff: |b| starts(b, WSXM),
        read: wsxm::read,
    },
    Reader {
        name: "frt",
        aliases: &["microprof"],
        description: "FRT MicroProf .frt",
        extensions: &["frt"],
        binary: true,
        signature: prefix!("`FRTM_GLIDERV`", FRT),
        sniff: |b| starts(b, FRT),
        read: frt::read,
    },
    Reader {
        name: "tmd",
        aliases: &["truemap"],
        description: "TrueMap .tmd",
        extensions: &["tmd"],
        binary: true,
        signature: prefix!("`Binary TrueMap Data File`", TMD),
        sniff: |b| starts(b, TMD),
        read: tmd::read,
    },
    Reader {
        name: "vk4",
        aliases: &["keyence", "vk3", "vk6", "vk7"],
        description: "Keyence VK-X laser confocal .vk4/.vk3 (and .vk6/.vk7 wrapping one)",
        extensions: &["vk4", "vk3", "vk6", "vk7"],
        binary: true,
        signature: prefix!("`VK4_`, `VK3_`, `VK6` or `VK7`", vk4::MAGICS),
        sniff: |b| starts(b, vk4::MAGICS),
        read: vk4::read,
    },
    Reader {
        name: "zon",
        aliases: &["keyence-zon"],
        description: "Keyence VR .zon (KPK0, and KPK1 with zstd entries)",
        extensions: &["zon"],
        binary: true,
        signature: prefix!("`KPK0` or `KPK1`", zon::MAGICS),
        sniff: |b| starts(b, zon::MAGICS),
        read: zon::read,
    },
    Reader {
        name: "datx",
        aliases: &["zygo-datx", "mx"],
        description: "Zygo Mx .datx (HDF5)",
        extensions: &["datx"],
        binary: true,
        signature: prefix!("`\\x89HDF\\r\\n\\x1a\\n` (an HDF5 file)", &[HDF5]),
        // Any HDF5 file could be one: the extension, or the reader's own check, decides.
        sniff: |b| {
            if starts(b, &[HDF5]) == Sniff::Magic {
                Sniff::Maybe
            } else {
                Sniff::No
            }
        },
        read: datx::read,
    },
    Reader {
        name: "zmg",
        aliases: &["zeta", "kla"],
        description: "KLA Zeta .zmg (optical profiler)",
        extensions: &["zmg"],
        binary: true,
        signature: prefix!("`Zeta-Instruments`", &[zmg::MAGIC]),
        sniff: |b| starts(b, &[zmg::MAGIC]),
        read: zmg::read,
    },
    Reader {
        name: "gwy",
        aliases: &["gwyddion-native"],
        description: "Gwyddion native .gwy (multi-channel, masks)",
        extensions: &["gwy"],
        binary: true,
        signature: prefix!("`GWYP`", GWY),
        sniff: |b| starts(b, GWY),
        read: gwy::read,
    },
    Reader {
        name: "opdx",
        aliases: &["vision64"],
        description: "Bruker Dektak XT .opdx (Vision64; profiles and maps)",
        extensions: &["opdx"],
        binary: true,
        signature: prefix!("`VCA DATA`", OPDX),
        sniff: |b| starts(b, OPDX),
        read: opdx::read,
    },
    Reader {
        name: "nms",
        aliases: &["nanofocus"],
        description: "NanoFocus µsurf .nms (confocal)",
        extensions: &["nms"],
        binary: true,
        signature: None,
        sniff: nms::sniff,
        read: nms::read,
    },
    Reader {
        name: "npy",
        aliases: &["numpy"],
        description: "NumPy array .npy (needs --units and --pixel-size)",
        extensions: &["npy"],
        binary: true,
        signature: prefix!("`\\x93NUMPY`", NPY),
        sniff: |b| starts(b, NPY),
        read: npy::read,
    },
    Reader {
        name: "netcdf",
        aliases: &["nc"],
        description: "NetCDF classic .nc (SurfaceTopography's container)",
        extensions: &["nc"],
        binary: true,
        signature: prefix!("`CDF\\x01` or `CDF\\x02` (NetCDF classic)", NETCDF),
        sniff: |b| starts(b, NETCDF),
        read: netcdf::read,
    },
    Reader {
        name: "dektak",
        aliases: &[],
        description: "Bruker Dektak CSV profile",
        extensions: &["csv"],
        binary: false,
        signature: None,
        sniff: dektak::sniff,
        read: dektak::read,
    },
    Reader {
        name: "matrix",
        aliases: &["asc", "txt", "gwyddion"],
        description: "text matrix (Gwyddion export in any locale, key=value / key: value headers)",
        extensions: &["txt", "asc", "dat", "csv"],
        binary: false,
        signature: None,
        sniff: matrix::sniff,
        read: matrix::read,
    },
    Reader {
        name: "xyz",
        aliases: &["csv", "columns"],
        description: "column text: x z profiles or x y z maps (CSV/TSV, unit headers, UTF-16)",
        extensions: &["xyz", "csv", "txt", "asc", "dat", "prf", "hfm"],
        binary: false,
        signature: None,
        sniff: xyz::sniff,
        read: xyz::read,
    },
];

/// Formats recognised by their signature (or, for containers shared by several formats,
/// their extension) that no reader reads: the file is named for what it is instead of
/// "unknown surface format". `(what it is, the fix)`.
pub fn unread_format(name: &str, bytes: &[u8]) -> Option<(String, String)> {
    let ext = extension(name);
    let not_yet =
        |what: &str, fix: &str| Some((format!("{what} is not read yet"), fix.to_string()));
    const EXPORT: &str = "export the scan from the instrument software as X3P, SDF or a \
                          text matrix (all read here)";
    if bytes.starts_with(HDF5) {
        return match ext.as_str() {
            "datx" => None,
            "nc" => not_yet(
                "NetCDF-4 (an HDF5 container)",
                "write it as NetCDF classic (format NETCDF3_64BIT_OFFSET), which is read",
            ),
            _ => not_yet("an HDF5 file", EXPORT),
        };
    }
    let images: &[(&[u8], &str)] = &[
        (b"\x89PNG\r\n\x1a\n", "a PNG image"),
        (b"\xFF\xD8\xFF", "a JPEG image"),
        (b"GIF87a", "a GIF image"),
        (b"GIF89a", "a GIF image"),
        (b"%PDF", "a PDF document"),
    ];
    if let Some((_, what)) = images.iter().find(|(m, _)| bytes.starts_with(m)) {
        return Some((
            format!(
                "this is {what}, not a height map: its pixels are colours with no height scale"
            ),
            "read the instrument's own file or export the heights (X3P, SDF, text matrix)".into(),
        ));
    }
    if bytes.starts_with(b"BM") && ext == "bmp" {
        return Some((
            "this is a BMP image, not a height map: its pixels are colours with no height scale"
                .into(),
            "read the instrument's own file or export the heights (X3P, SDF, text matrix)".into(),
        ));
    }
    let signed: &[(&[u8], &str, &str)] = &[
        (
            b"MATLAB 5.0 MAT-file",
            "a MATLAB .mat file",
            "save the heights with numpy.save (.npy) or as a text matrix",
        ),
        (b"OS3D", "Olympus OS3D", EXPORT),
    ];
    if let Some((_, what, fix)) = signed.iter().find(|(m, _, _)| bytes.starts_with(m)) {
        return not_yet(what, fix);
    }
    match ext.as_str() {
        "poir" | "oir" => not_yet("Olympus OIR", EXPORT),
        "plux" => not_yet(
            "Sensofar .plux",
            "export it from SensoSCAN as .plu, X3P or SDF",
        ),
        "sflz" => not_yet(
            "surfalize .sflz",
            "save the surface from surfalize as X3P or SDF",
        ),
        "xlsx" | "xls" => Some((
            "this is a spreadsheet, not a height map".into(),
            "save the sheet's height columns as CSV (x z or x y z)".into(),
        )),
        _ => None,
    }
}

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
/// tie-breaker), then the extension of a binary format alone; `None` also for a file
/// whose extension names a format with a signature the file lacks.
pub fn detect(name: &str, bytes: &[u8]) -> Option<Format> {
    let found = sniffed(name, bytes);
    match found {
        Some((f, Sniff::Magic)) => Some(f),
        _ if signature_mismatch(name, bytes, found.map(|(f, _)| f)).is_some() => None,
        _ => found.map(|(f, _)| f).or_else(|| by_extension(name)),
    }
}

fn extension(name: &str) -> String {
    Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// The format whose magic number or content check accepts `bytes` (the extension breaks
/// ties), with how sure that check is.
pub(crate) fn sniffed(name: &str, bytes: &[u8]) -> Option<(Format, Sniff)> {
    let ext = extension(name);
    let head = &bytes[..bytes.len().min(1 << 16)];
    let mut best: Option<(u8, Sniff, &'static Reader)> = None;
    for r in READERS {
        let s = (r.sniff)(head);
        if s == Sniff::No {
            continue;
        }
        let score = 2 * s as u8 + u8::from(r.extensions.contains(&ext.as_str()));
        if best.is_none_or(|(b, _, _)| score > b) {
            best = Some((score, s, r));
        }
    }
    best.map(|(_, s, r)| (Format(r), s))
}

/// The refusal of a file whose extension names a format with a signature (magic bytes)
/// that the file does not carry, when no format's magic was found in it either
/// (`found` is the best weaker content match). Extensions that text formats share (a
/// text `.dat` is no MetroPro file) let a text file through to those formats.
pub(crate) fn signature_mismatch(
    name: &str,
    bytes: &[u8],
    found: Option<Format>,
) -> Option<ReadError> {
    let ext = extension(name);
    let named: Vec<&'static Reader> = READERS
        .iter()
        .filter(|r| r.extensions.contains(&ext.as_str()))
        .collect();
    let (reader, sig) = named
        .iter()
        .find_map(|r| r.signature.as_ref().map(|s| (*r, s)))?;
    let carried = named
        .iter()
        .filter_map(|r| r.signature.as_ref())
        .any(|s| (s.present)(bytes));
    if carried {
        return None;
    }
    let shared_with_text = named.iter().any(|r| r.signature.is_none());
    let taken_as_text = found.is_some_and(|f| named.iter().any(|r| std::ptr::eq(*r, f.0)))
        || text_fallback(bytes).is_some();
    if shared_with_text && taken_as_text {
        return None;
    }
    Some(ReadError::Signature {
        file: name.to_string(),
        extension: ext,
        format: reader.name,
        expected: sig.describe,
        offset: sig.offset,
        found: shown(bytes, sig.offset),
    })
}

/// The first bytes at `offset` as a message shows them: quoted when printable ASCII,
/// in hex otherwise.
fn shown(bytes: &[u8], offset: usize) -> String {
    let Some(tail) = bytes.get(offset..).filter(|t| !t.is_empty()) else {
        return format!("nothing (the file is {} bytes long)", bytes.len());
    };
    let head = &tail[..tail.len().min(16)];
    let more = if tail.len() > head.len() { " …" } else { "" };
    if head.iter().all(|b| (0x20..0x7f).contains(b)) {
        format!("`{}`{more}", String::from_utf8_lossy(head))
    } else {
        let hex: Vec<String> = head.iter().map(|b| format!("{b:02X}")).collect();
        format!("{}{more}", hex.join(" "))
    }
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
