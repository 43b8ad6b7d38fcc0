//! Files damaged on the way from the instrument: cut short by a failed copy, their first
//! bytes overwritten, or a header whose physical size is absurd. Each is refused with an
//! error that names the file, the field and the fix, rather than read silently, parsed as
//! something else, or given a `null` RMS slope.

use fit::ReadError;
use fit::io::{ChannelSel, Format, ReadOptions, Units, list_channels, read_bytes};
use fit::stats;
use std::path::PathBuf;

mod samples;
use samples::{jpk_sample, zmg_sample, zon_sample};

fn data(name: &str) -> Vec<u8> {
    std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../data/surfaces")
            .join(name),
    )
    .unwrap()
}

fn formats(name: &str) -> Vec<u8> {
    data(&format!("formats/{name}"))
}

fn corpus(name: &str) -> Vec<u8> {
    data(&format!("corpus/{name}"))
}

/// The error of reading `bytes` as `name`, which must fail; also checks that listing the
/// channels fails the same way.
fn refused(name: &str, bytes: &[u8], o: &ReadOptions) -> String {
    let e = match read_bytes(name, bytes, o) {
        Ok(t) => panic!("{name}: accepted ({} × {})", t.nx, t.ny),
        Err(e) => e.to_string(),
    };
    println!("{e}");
    assert!(!e.contains('\n'), "{name}: not one line: {e}");
    assert!(
        e.starts_with(name),
        "{name}: the message does not start with the file: {e}"
    );
    assert!(e.contains("Fix:"), "{name}: no fix: {e}");
    e
}

/// `bytes` with every `from` replaced by `to`, of the same length.
fn replace_all(bytes: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let mut out = bytes.to_vec();
    let mut n = 0;
    let mut i = 0;
    while let Some(p) = out[i..].windows(from.len()).position(|w| w == from) {
        out[i + p..i + p + to.len()].copy_from_slice(to);
        i += p + to.len();
        n += 1;
    }
    assert!(n > 0, "`{}` not found", String::from_utf8_lossy(from));
    out
}

fn assert_mentions(e: &str, needles: &[&str]) {
    for n in needles {
        assert!(e.contains(n), "`{e}` should mention `{n}`");
    }
}

// ---- 1. Files cut short ----------------------------------------------------------------

/// di-3.di holds four 256 × 256 channels (data at 40960, 172032, 303104 and 434176, 131072
/// bytes each). Cut in half, its first channel is still whole, so a reader that checked
/// only the channel it reads would not notice.
#[test]
fn a_nanoscope_file_cut_in_half_is_refused_naming_the_channel_and_byte_range() {
    let b = data("di-3.di");
    let cut = &b[..b.len() / 2];
    assert_eq!(cut.len(), 282_624);
    for o in [
        ReadOptions::default(),
        ReadOptions {
            channel: Some(ChannelSel::Index(0)),
            ..ReadOptions::default()
        },
    ] {
        let e = refused("di-3.di", cut, &o);
        assert_mentions(
            &e,
            &[
                "\\Data offset + \\Data length",
                "channel 1 `Amplitude Error`",
                "bytes 172032..303104",
                "the file is only 282624 bytes long",
                "the file is truncated: re-export or re-copy it",
            ],
        );
    }
    let e = list_channels("di-3.di", cut, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("truncated"), "{e}");
    // The whole file still reads, every channel of it.
    for c in [0, 3] {
        let o = ReadOptions {
            channel: Some(ChannelSel::Index(c)),
            ..ReadOptions::default()
        };
        read_bytes("di-3.di", &b, &o).unwrap();
    }
}

/// Every binary reader whose header says how much data follows refuses a copy cut at half
/// and at two thirds of its length. NanoScope, PicoView, Nanosurf, Wyko and Alicona files
/// cut there still hold their first channel (or the depth image) whole.
#[test]
fn every_binary_reader_refuses_a_file_cut_short() {
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("di-2.di", corpus("di-2.di")),
        ("di-5.di", corpus("di-5.di")),
        ("di-6.di", data("di-6.di")),
        ("mi-1.mi", corpus("mi-1.mi")),
        ("nid-1.nid", corpus("nid-1.nid")),
        ("opd-1.opd", corpus("opd-1.opd")),
        ("al3d-1.al3d", corpus("al3d-1.al3d")),
        ("frt-1.frt", corpus("frt-1.frt")),
        ("spot_1-1000nm.ibw", corpus("spot_1-1000nm.ibw")),
        ("metropro-1.dat", corpus("metropro-1.dat")),
        ("sur-2.sur", corpus("sur-2.sur")),
        ("mnt-1.mnt", corpus("mnt-1.mnt")),
        ("tmd-1.tmd", corpus("tmd-1.tmd")),
        ("stp-1.stp", corpus("stp-1.stp")),
        ("example_ps.tiff", corpus("example_ps.tiff")),
        ("bcrf-1.bcrf", data("bcrf-1.bcrf")),
        (
            "KautschukInfiniteFocus.x3p",
            data("KautschukInfiniteFocus.x3p"),
        ),
    ];
    let o = ReadOptions::default();
    for (name, b) in &files {
        read_bytes(name, b, &o).unwrap_or_else(|e| panic!("{name} whole: {e}"));
        for cut in [b.len() / 2, b.len() * 2 / 3] {
            let e = refused(name, &b[..cut], &o);
            assert!(
                e.contains("truncated") || e.contains("beyond the end"),
                "{name} cut at {cut}: `{e}` does not say the file is truncated"
            );
        }
    }
    // Sensofar states only the first layer's size; what follows it (the colour image) has
    // no declared length, so only a cut inside the layer can be told.
    let plu = corpus("plu-1.plu");
    refused("plu-1.plu", &plu[..plu.len() / 2], &o);
}

/// Files whose channel read is still whole: the error names the channel or block and the
/// byte range.
#[test]
fn truncation_errors_name_what_is_missing_and_where() {
    let o = ReadOptions::default();
    let mi = corpus("mi-1.mi");
    let e = refused("mi-1.mi", &mi[..mi.len() / 2], &o);
    assert_mentions(
        &e,
        &[
            "channel 1 `Deflection (Trace)`",
            "bytes 267217..529361",
            "truncated: re-export",
        ],
    );
    let nid = corpus("nid-1.nid");
    let e = refused("nid-1.nid", &nid[..nid.len() / 2], &o);
    assert_mentions(&e, &["[DataSet-", "Points × Lines", "data set ", "bytes "]);
    let opd = corpus("opd-1.opd");
    let e = refused("opd-1.opd", &opd[..opd.len() / 2], &o);
    assert_mentions(
        &e,
        &[
            "field `Directory`",
            "block `SecArr_0` (1228806 bytes) at bytes 1252830..2481636",
            "2010435 bytes long",
        ],
    );
    let al3d = corpus("al3d-1.al3d");
    let e = refused("al3d-1.al3d", &al3d[..al3d.len() * 2 / 3], &o);
    assert_mentions(
        &e,
        &[
            "TextureImageOffset",
            "4 texture planes of 200 × 296",
            "238061..",
        ],
    );
    let ibw = corpus("spot_1-1000nm.ibw");
    let end = 384 + 2_097_472 - 320 + 100; // inside the note, after the wave data
    let e = refused("spot.ibw", &ibw[..end], &o);
    assert_mentions(&e, &["noteSize", "15145 bytes"]);
}

/// An FRT file cut between two blocks, after the ones the reader decodes: the block count
/// in its header says 58 blocks were written.
#[test]
fn an_frt_file_cut_between_blocks_is_refused() {
    let b = corpus("frt-1.frt");
    let mut starts = Vec::new();
    let mut p = 18usize;
    let n = u16::from_le_bytes([b[16], b[17]]);
    assert_eq!(n, 58);
    for _ in 0..n {
        starts.push(p);
        let size = u32::from_le_bytes(b[p + 2..p + 6].try_into().unwrap()) as usize;
        p += 6 + size;
    }
    assert_eq!(p, b.len());
    let last = *starts.last().unwrap();
    let o = ReadOptions::default();
    for cut in [last, last + 3] {
        let e = refused("frt-1.frt", &b[..cut], &o);
        assert_mentions(
            &e,
            &[
                "field `block count`",
                "block 58's id and size (58 blocks counted)",
                &format!("bytes {last}..{}", last + 6),
            ],
        );
    }
}

// ---- 2. Signatures overwritten -----------------------------------------------------------

/// A GSF file written from scratch.
fn gsf(nx: usize, ny: usize, x_real: &str, y_real: &str) -> Vec<u8> {
    let mut h = format!(
        "Gwyddion Simple Field 1.0\nXRes = {nx}\nYRes = {ny}\nXReal = {x_real}\nYReal = {y_real}\n\
         XYUnits = m\nZUnits = m\n"
    )
    .into_bytes();
    let pad = 4 - h.len() % 4;
    h.extend(std::iter::repeat_n(0u8, pad));
    for i in 0..nx * ny {
        // Deterministic roughness of a few nanometres.
        let v = ((i * 7919 % 101) as f32 - 50.0) * 1e-10;
        h.extend_from_slice(&v.to_le_bytes());
    }
    h
}

/// A binary SDF file with pixel spacing `dx` × `dy` [m].
fn sdf(dx: f64, dy: f64) -> Vec<u8> {
    let mut h = Vec::new();
    h.extend_from_slice(b"bISO-1.0");
    h.extend_from_slice(b"lustre    ");
    h.extend_from_slice(b"010120250000");
    h.extend_from_slice(b"010120250000");
    h.extend_from_slice(&4u16.to_le_bytes());
    h.extend_from_slice(&3u16.to_le_bytes());
    for v in [dx, dy, 1e-9, 1e-9] {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h.extend_from_slice(&[0, 5, 0]);
    h.extend((0..12i16).flat_map(|v| (v * v - 3 * v).to_le_bytes()));
    h
}

/// One file of every format that has a signature, named with its format's extension.
fn signed_samples() -> Vec<(&'static str, String, Vec<u8>)> {
    vec![
        ("x3p", "k.x3p".into(), data("KautschukInfiniteFocus.x3p")),
        ("sdf", "s.sdf".into(), sdf(1e-6, 1e-6)),
        ("bcr", "bcrf-1.bcrf".into(), data("bcrf-1.bcrf")),
        ("gsf", "g.gsf".into(), gsf(8, 8, "1e-5", "1e-5")),
        ("nanoscope", "di-3.di".into(), data("di-3.di")),
        ("sur", "sur-2.sur".into(), corpus("sur-2.sur")),
        ("mnt", "mnt-1.mnt".into(), corpus("mnt-1.mnt")),
        (
            "metropro",
            "metropro-1.dat".into(),
            corpus("metropro-1.dat"),
        ),
        ("opd", "opd-1.opd".into(), corpus("opd-1.opd")),
        ("al3d", "al3d-1.al3d".into(), corpus("al3d-1.al3d")),
        ("nid", "nid-1.nid".into(), corpus("nid-1.nid")),
        ("ibw", "spot.ibw".into(), corpus("spot_1-1000nm.ibw")),
        ("park", "example_ps.tiff".into(), corpus("example_ps.tiff")),
        ("mi", "mi-1.mi".into(), corpus("mi-1.mi")),
        ("wsxm", "stp-1.stp".into(), corpus("stp-1.stp")),
        ("frt", "frt-1.frt".into(), corpus("frt-1.frt")),
        ("tmd", "tmd-1.tmd".into(), corpus("tmd-1.tmd")),
        ("opdx", "opdx-3.opdx".into(), formats("opdx-3.opdx")),
        ("npy", "example-2d.npy".into(), formats("example-2d.npy")),
        ("netcdf", "nc-1.nc".into(), formats("nc-1.nc")),
        ("gwy", "matrix-4-st.gwy".into(), formats("matrix-4-st.gwy")),
        ("vk4", "a.vk4".into(), vk4_sample()),
        ("zmg", "a.zmg".into(), zmg_sample()),
        ("zon", "a.zon".into(), zon_sample()),
        ("jpk", "a.jpk".into(), jpk_sample()),
        ("lext", "lext-synth.lext".into(), formats("lext-synth.lext")),
        ("datx", "datx-synth.datx".into(), formats("datx-synth.datx")),
    ]
}

/// Zeroing a file's first 16 bytes leaves its extension naming a format it no longer
/// carries the signature of. NanoScope, PicoView and Digital Surf files could still be read
/// (the data lie past the damage), Nanosurf and WSxM files look like text matrices, and
/// the others would be refused for some other field.
#[test]
fn a_file_whose_signature_is_overwritten_is_refused_naming_extension_and_format() {
    let o = ReadOptions::default();
    let samples = signed_samples();
    // Every format with a signature has a sample here.
    for f in Format::all() {
        let has = f.reader().signature.is_some();
        let sampled = samples.iter().any(|(n, _, _)| *n == f.name());
        assert_eq!(
            has,
            sampled,
            "{}: signature {has}, sample {sampled}",
            f.name()
        );
    }
    for (format, name, bytes) in samples {
        // An array states neither unit nor pixel size.
        let whole = if format == "npy" {
            ReadOptions {
                units: fit::io::Units::parse("um"),
                pixel_size: Some((1e-6, 1e-6)),
                ..ReadOptions::default()
            }
        } else {
            o.clone()
        };
        read_bytes(&name, &bytes, &whole).unwrap_or_else(|e| panic!("{name} whole: {e}"));
        let mut b = bytes.clone();
        b[..16].fill(0);
        let ext = name.rsplit('.').next().unwrap();
        match read_bytes(&name, &b, &o) {
            Err(ReadError::Signature {
                file,
                extension,
                format: f,
                offset,
                found,
                ..
            }) => {
                assert_eq!((file.as_str(), extension.as_str()), (name.as_str(), ext));
                assert_eq!(f, format);
                assert!(found.starts_with("00 00"), "{name}: found {found}");
                assert_eq!(offset, if format == "opd" { 2 } else { 0 });
            }
            Err(e) => panic!("{name}: not a signature error: {e}"),
            Ok(t) => panic!("{name}: read without its signature ({} × {})", t.nx, t.ny),
        }
        let e = refused(&name, &b, &o);
        assert_mentions(
            &e,
            &[
                "the file's signature does not match its extension",
                &format!("`.{ext}` names the `{format}` format, whose files have"),
                "re-copy or re-export it",
            ],
        );
        let listed = list_channels(&name, &b, &o).unwrap_err();
        assert!(matches!(listed, ReadError::Signature { .. }), "{listed}");
    }
    // The message shows what stands there instead, and where the signature belongs.
    let mut di = data("di-3.di");
    di[..16].copy_from_slice(b"hello world, hi!");
    let e = refused("di-3.di", &di, &o);
    assert_mentions(
        &e,
        &[
            "`\\*File list` at byte 0",
            "but this file has `hello world, hi!` …",
        ],
    );
    let e = refused("empty.frt", b"", &o);
    assert_mentions(&e, &["nothing (the file is 0 bytes long)"]);
}

/// What the signature check must let through: a text `.dat` (MetroPro's extension, a
/// text format's too), a NanoScope force curve and an old Igor wave (their readers explain
/// them), a plain TIFF (Park's reader explains it), a Sensofar file (no signature: its
/// header starts with a date), a file whose content is another format's (the content
/// wins), and `--format`, which the user means.
#[test]
fn dialects_and_explained_variants_still_reach_their_readers() {
    let o = ReadOptions::default();
    let text = corpus("gwyddion-export-english.txt");
    let a = read_bytes("export.txt", &text, &o).unwrap();
    let b = read_bytes("export.dat", &text, &o).unwrap();
    assert_eq!(
        (a.nx, a.ny, a.dx, &a.heights),
        (b.nx, b.ny, b.dx, &b.heights)
    );

    let force = b"\\*Force file list\r\n\\Version: 0x05120005\r\n\\*File list end\r\n";
    let e = refused("curve.001", force, &o);
    assert_mentions(&e, &["force curves"]);

    let mut igor2 = vec![0u8; 400];
    igor2[0] = 2;
    let e = refused("old.ibw", &igor2, &o);
    assert_mentions(&e, &["version 2"]);

    let mut tiff = b"II*\0\x08\0\0\0\0\0\0\0\0\0".to_vec();
    tiff.resize(64, 0);
    let e = refused("plain.tif", &tiff, &o);
    assert_mentions(&e, &["tag 50432", "no Park Systems data"]);

    let mut plu = corpus("plu-1.plu");
    let whole = read_bytes("plu-1.plu", &plu, &o).unwrap();
    plu[..16].fill(0);
    let t = read_bytes("plu-1.plu", &plu, &o).unwrap();
    assert_eq!(t.heights, whole.heights);

    let g = gsf(8, 8, "1e-5", "1e-5");
    assert_eq!(read_bytes("misnamed.di", &g, &o).unwrap().nx, 8);

    let mut di = data("di-3.di");
    di[..16].fill(0);
    let forced = ReadOptions {
        format: Format::from_name("nanoscope"),
        ..ReadOptions::default()
    };
    read_bytes("di-3.di", &di, &forced).unwrap();
}

// ---- 3. Physical sizes out of range -----------------------------------------------------

/// XReal = 1e-300 m over 64 points is a 1.6e-302 m pixel: Δz/Δx overflows to infinity
/// and `fit stats` would print `"rms_slope": null`. Such a size is refused, naming the field.
#[test]
fn a_pixel_spacing_outside_the_physical_range_is_refused_naming_the_field() {
    let o = ReadOptions::default();
    let e = refused("tiny.gsf", &gsf(64, 64, "1e-300", "1e-5"), &o);
    assert_mentions(
        &e,
        &[
            "field `XReal`",
            "the pixel spacing along x, 1.5625e-302 m, is below 1e-15 m",
            "the header's `XReal` is corrupt or in the wrong unit",
            "--pixel-size or --size",
        ],
    );
    let e = refused("huge.gsf", &gsf(64, 64, "1e-5", "1e300"), &o);
    assert_mentions(&e, &["field `YReal`", "along y", "is above 1 m"]);
    let e = refused("tiny.sdf", &sdf(1e-300, 1e-6), &o);
    assert_mentions(&e, &["field `Xscale`", "1e-300 m"]);
    // Same length, so the header keeps its layout: 1e-99 µm over 256 points.
    let di = replace_all(
        &data("di-3.di"),
        b"Scan Size: 10 10 ~m",
        b"Scan Size: 1e-99 ~m",
    );
    let e = refused("tiny.di", &di, &o);
    assert_mentions(&e, &["field `Scan Size`", "is below 1e-15 m"]);

    // The flags go through the same check.
    let flag = |pixel_size, size, units| ReadOptions {
        pixel_size,
        size,
        units,
        ..ReadOptions::default()
    };
    let ok = gsf(64, 64, "1e-5", "1e-5");
    let e = refused("ok.gsf", &ok, &flag(Some((1e-20, 1e-20)), None, None));
    assert_mentions(&e, &["field `--pixel-size`", "e.g. --pixel-size 0.5um"]);
    let e = refused("ok.gsf", &ok, &flag(None, Some((1e3, 1e3)), None));
    assert_mentions(&e, &["field `--size`", "is above 1 m"]);
    let xy = corpus("xy-1.txt");
    let e = refused("xy-1.txt", &xy, &flag(None, None, Units::parse("m")));
    assert_mentions(
        &e,
        &["field `x column`", "in the lateral unit --units gives"],
    );
    read_bytes("xy-1.txt", &xy, &flag(None, None, Units::parse("um"))).unwrap();

    // At the ends of the range the map reads and its RMS slope is finite.
    for (x_real, dx) in [("6.4e-14", 1e-15), ("64", 1.0)] {
        let t = read_bytes("edge.gsf", &gsf(64, 64, x_real, x_real), &o).unwrap();
        assert!((t.dx / dx - 1.0).abs() < 1e-12, "{x_real}: dx {}", t.dx);
        let s = stats::compute(&t);
        assert!(s.sdq.is_finite() && s.sdq > 0.0, "{x_real}: Sdq {}", s.sdq);
    }
}

/// A NanoScope Z sensitivity of 2.2e300 nm/V gives heights near 1e290 m, whose squares
/// overflow: unchecked, `fit` would write Sq `inf`, σ 0 and α at its floor. Heights
/// are bounded like pixel spacings; the test files of a few metres still read.
#[test]
fn heights_beyond_any_scan_are_refused_naming_the_height_scale() {
    let o = ReadOptions::default();
    let huge = replace_all(
        &data("di-6.di"),
        b"Zsens: V 22.02707 nm/V",
        b"Zsens: V 2.20e300 nm/V",
    );
    let e = refused("huge.di", &huge, &o);
    assert_mentions(
        &e,
        &["field `height scale`", "above 1e3 m", "re-export the scan"],
    );
    // A 1e11 times larger sensitivity: nanometre heights become kilometres.
    let tall = replace_all(
        &data("di-6.di"),
        b"Zsens: V 22.02707 nm/V",
        b"Zsens: V 2.202e12 nm/V",
    );
    let e = refused("tall.di", &tall, &o);
    assert_mentions(&e, &["the heights reach", "above 1e3 m"]);
    // Heights of a file without units, taken in the unit --units gives: the fix names it.
    let text: String = (0..16)
        .map(|y| {
            (0..16)
                .map(|x| format!("{}", 5000 + (x * 7 + y * 3) % 11))
                .collect::<Vec<_>>()
                .join(" ")
                + "\n"
        })
        .collect();
    let in_metres = ReadOptions {
        units: Units::parse("m"),
        pixel_size: Some((1e-6, 1e-6)),
        ..ReadOptions::default()
    };
    let e = refused("nm_as_m.txt", text.as_bytes(), &in_metres);
    assert_mentions(&e, &["the heights reach 5.0100e3 m", "--units"]);
    let in_nm = ReadOptions {
        units: Units::parse("nm"),
        ..in_metres
    };
    read_bytes("nm.txt", text.as_bytes(), &in_nm).unwrap();
    // The Gwyddion test exports hold heights of up to 9 m, stated in metres: still read.
    for f in ["gwyddion-export-english.txt", "gwyddion-export-german.txt"] {
        let t = read_bytes(f, &corpus(f), &o).unwrap();
        let max = t.heights.iter().fold(0.0f64, |m, h| m.max(h.abs()));
        assert!(max > 1.0 && max <= 1e3, "{f}: {max}");
    }
}

/// A 16 × 16 VK4 file written from the format description (as in tests/formats.rs).
fn vk4_sample() -> Vec<u8> {
    let mut b = b"VK4_".to_vec();
    b.extend([1, 0, 0, 0, 0, 0, 0, 0]);
    let (conditions, layer) = (84u32, 84 + 400);
    for i in 0..17u32 {
        let v = match i {
            0 => conditions,
            6 => layer,
            _ => 0,
        };
        b.extend(v.to_le_bytes());
    }
    b.extend(0u32.to_le_bytes());
    for i in 0..100u32 {
        let v = match i {
            42 | 43 => 250_000u32,
            44 => 1000,
            _ => 0,
        };
        b.extend(v.to_le_bytes());
    }
    for v in [16u32, 16, 16, 0, 512, 0, 0] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u8; 768]);
    for i in 0..256u16 {
        b.extend((i * 13 % 97).to_le_bytes());
    }
    b
}
