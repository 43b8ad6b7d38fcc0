//! Every writer of every command, given each kind of target that must not be
//! replaced: a character device (made with `mknod`), a FIFO, a directory, a
//! symbolic link to the command's input and a hard link to it. A device or
//! FIFO is written into (or, with nobody reading the FIFO, refused) and stays
//! what it was; a directory and both links are refused before the work, the
//! input byte for byte intact. Never a panic.

#![cfg(unix)]

mod common;

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lustre(dir: &Path, args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run lustre")
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-outputs-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A real AFM map (256², text matrix), small enough to fit and judge in a second.
fn scan_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/surfaces/matrix-3.txt"
    ))
    .unwrap()
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    CharDevice,
    Fifo,
    Directory,
    SymlinkToInput,
    HardLinkToInput,
}

/// Makes `target` as `kind`; false when the platform refuses (mknod needs root).
fn make(kind: Kind, target: &Path, input: &Path) -> bool {
    let c = |p: &Path| std::ffi::CString::new(p.to_str().unwrap()).unwrap();
    match kind {
        // The device numbers of /dev/null: writes go nowhere.
        Kind::CharDevice => unsafe {
            libc::mknod(
                c(target).as_ptr(),
                libc::S_IFCHR | 0o666,
                libc::makedev(1, 3),
            ) == 0
        },
        Kind::Fifo => unsafe { libc::mkfifo(c(target).as_ptr(), 0o600) == 0 },
        Kind::Directory => std::fs::create_dir(target).is_ok(),
        Kind::SymlinkToInput => std::os::unix::fs::symlink(input, target).is_ok(),
        Kind::HardLinkToInput => std::fs::hard_link(input, target).is_ok(),
    }
}

fn still(kind: Kind, target: &Path) -> bool {
    let Ok(link) = std::fs::symlink_metadata(target) else {
        return false;
    };
    let t = link.file_type();
    match kind {
        Kind::CharDevice => t.is_char_device(),
        Kind::Fifo => t.is_fifo(),
        Kind::Directory => t.is_dir(),
        Kind::SymlinkToInput => t.is_symlink(),
        Kind::HardLinkToInput => t.is_file(),
    }
}

/// One writer: the command line writing to `target`, run in `dir`, and the
/// input file it reads.
struct Writer {
    name: &'static str,
    /// File name of the target inside the run's folder.
    target: &'static str,
    /// The file it reads, for the link cases (none: those cases do not apply).
    input: Option<&'static str>,
    args: fn(&Path) -> Vec<String>,
}

fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

fn p(t: &Path) -> String {
    t.to_str().unwrap().to_string()
}

fn writers() -> Vec<Writer> {
    vec![
        Writer {
            name: "render --film",
            target: "out.film",
            input: Some("s.toml"),
            args: |t| [s(&["render", "s.toml", "-q", "--film"]), vec![p(t)]].concat(),
        },
        Writer {
            name: "render --exr",
            target: "out.exr",
            input: Some("s.toml"),
            args: |t| {
                [
                    s(&["render", "s.toml", "-q", "--no-film", "--exr"]),
                    vec![p(t)],
                ]
                .concat()
            },
        },
        Writer {
            name: "render --png",
            target: "out.png",
            input: Some("s.toml"),
            args: |t| {
                [
                    s(&["render", "s.toml", "-q", "--no-film", "--png"]),
                    vec![p(t)],
                ]
                .concat()
            },
        },
        Writer {
            name: "merge --film",
            target: "merged.film",
            input: Some("shard.film"),
            args: |t| [s(&["merge", "shard.film", "-q", "--film"]), vec![p(t)]].concat(),
        },
        Writer {
            name: "merge --exr",
            target: "merged.exr",
            input: Some("shard.film"),
            args: |t| [s(&["merge", "shard.film", "-q", "--exr"]), vec![p(t)]].concat(),
        },
        Writer {
            name: "fit -o",
            target: "m.toml",
            input: Some("scan.txt"),
            args: |t| [s(&["fit", "scan.txt", "--no-plots", "-o"]), vec![p(t)]].concat(),
        },
        Writer {
            name: "fit plot",
            target: "fm_psd.png",
            input: Some("scan.txt"),
            args: |_| s(&["fit", "scan.txt", "-o", "fm.toml"]),
        },
        Writer {
            name: "judge -o",
            target: "judge.json",
            input: Some("scan.txt"),
            args: |t| {
                let dir = p(t.parent().unwrap());
                [
                    s(&[
                        "judge",
                        "scan.txt",
                        "--no-plots",
                        "--no-surrogate",
                        "--theta-i",
                        "0",
                        "--lambda",
                        "550",
                        "-o",
                    ]),
                    vec![dir],
                ]
                .concat()
            },
        },
        Writer {
            name: "preview -o",
            target: "pv.png",
            input: Some("mat.toml"),
            args: |t| {
                [
                    s(&[
                        "preview",
                        "mat.toml",
                        "--size",
                        "8x6",
                        "--spp",
                        "1",
                        "--threads",
                        "1",
                        "-o",
                    ]),
                    vec![p(t)],
                ]
                .concat()
            },
        },
        Writer {
            name: "compare --out",
            target: "cmp.png",
            input: Some("mat.toml"),
            args: |t| {
                [
                    s(&[
                        "compare",
                        "--material",
                        "mat.toml",
                        "--views",
                        "0",
                        "--size",
                        "8x6",
                        "--spp",
                        "1",
                        "--threads",
                        "1",
                        "--quiet",
                        "--out",
                    ]),
                    vec![p(t)],
                ]
                .concat()
            },
        },
        Writer {
            name: "brdf plot --out",
            target: "s027_slices.png",
            input: None,
            args: |t| {
                let dir = p(t.parent().unwrap());
                [
                    s(&[
                        "brdf",
                        "plot",
                        "--samples",
                        "S027",
                        "--theta-i",
                        "30",
                        "--points",
                        "8",
                        "--albedo-angles",
                        "2",
                        "--quiet",
                        "--out",
                    ]),
                    vec![dir],
                ]
                .concat()
            },
        },
        Writer {
            name: "brdf export -o",
            target: "out.binary",
            input: Some("mat.toml"),
            args: |t| {
                let line = ["brdf", "export", "mat.toml", "--model", "ggx"];
                [
                    s(&line),
                    s(&["--check-samples", "4", "-q", "-o"]),
                    vec![p(t)],
                ]
                .concat()
            },
        },
        Writer {
            name: "scenes --out",
            target: "psd/s138_kc.csv",
            input: None,
            args: |t| {
                let dir = p(t.parent().unwrap().parent().unwrap());
                [s(&["scenes", "-q", "--out"]), vec![dir]].concat()
            },
        },
    ]
}

/// The folder a writer runs in: the scene, a shard film, the scan and a
/// material fitted to it.
fn fixture() -> PathBuf {
    let d = scratch("fixture");
    std::fs::write(d.join("s.toml"), common::TINY_SCENE).unwrap();
    std::fs::write(d.join("scan.txt"), scan_text()).unwrap();
    for args in [
        s(&["render", "s.toml", "-q", "--film", "shard.film"]),
        s(&["fit", "scan.txt", "--no-plots", "-o", "mat.toml"]),
    ] {
        let out = lustre(&d, &args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    d
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

#[test]
fn no_writer_replaces_a_device_a_fifo_a_directory_or_its_input() {
    let fixture = fixture();
    let kinds = [
        Kind::CharDevice,
        Kind::Fifo,
        Kind::Directory,
        Kind::SymlinkToInput,
        Kind::HardLinkToInput,
    ];
    let mut skipped = Vec::new();
    for w in writers() {
        for kind in kinds {
            let d = scratch("run");
            copy_dir(&fixture, &d);
            let target = d.join(w.target);
            std::fs::create_dir_all(target.parent().unwrap()).unwrap();
            let input = match (w.input, kind) {
                (Some(i), _) => d.join(i),
                (None, Kind::SymlinkToInput | Kind::HardLinkToInput) => continue,
                (None, _) => d.join("s.toml"),
            };
            let before = std::fs::read(&input).unwrap();
            if !make(kind, &target, &input) {
                skipped.push(format!("{} {kind:?}", w.name));
                continue;
            }
            let out = lustre(&d, &(w.args)(&target));
            let err = String::from_utf8_lossy(&out.stderr);
            let what = format!("{} into {kind:?}: exit {:?}: {err}", w.name, out.status);
            assert!(matches!(out.status.code(), Some(0 | 1)), "{what}");
            assert!(still(kind, &target), "{what}: the target was replaced");
            assert_eq!(
                std::fs::read(&input).unwrap(),
                before,
                "{what}: input changed"
            );
            match kind {
                // Written into, as cp would.
                Kind::CharDevice => assert_eq!(out.status.code(), Some(0), "{what}"),
                // Nobody reads the FIFO: refused at once rather than waiting forever.
                Kind::Fifo => {
                    if out.status.code() == Some(1) {
                        assert!(err.contains("no process is reading"), "{what}");
                    }
                }
                Kind::Directory => {
                    assert_eq!(out.status.code(), Some(1), "{what}");
                    assert!(err.contains("is a directory"), "{what}");
                    assert!(err.contains(w.target), "{what}: the path is not named");
                }
                Kind::SymlinkToInput | Kind::HardLinkToInput => {
                    assert_eq!(out.status.code(), Some(1), "{what}");
                    assert!(err.contains("is the input"), "{what}");
                }
            }
            let _ = std::fs::remove_dir_all(&d);
        }
    }
    // mknod needs root; everything else runs anywhere.
    assert!(
        skipped.iter().all(|s| s.ends_with("CharDevice")),
        "{skipped:?}"
    );
    let _ = std::fs::remove_dir_all(&fixture);
}

#[test]
fn a_fifo_with_a_reader_receives_the_output() {
    let d = scratch("fifo-reader");
    std::fs::write(d.join("s.toml"), common::TINY_SCENE).unwrap();
    let fifo = d.join("out.png");
    assert!(make(Kind::Fifo, &fifo, &fifo));
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read(fifo).unwrap())
    };
    // The reader may not have opened its end yet: the writer refuses rather than
    // waits, so try again until it has.
    let mut tries = 0;
    loop {
        let out = lustre(
            &d,
            &s(&["render", "s.toml", "-q", "--no-film", "--png", "out.png"]),
        );
        if out.status.success() {
            break;
        }
        tries += 1;
        assert!(tries < 50, "{}", String::from_utf8_lossy(&out.stderr));
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let bytes = reader.join().unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(still(Kind::Fifo, &fifo));
    let _ = std::fs::remove_dir_all(&d);
}

/// The audit's reproducer: a scan named like judge's report, judged into its own folder.
#[test]
fn judge_never_writes_over_its_scan_or_reference() {
    let d = scratch("judge-self");
    let scan = scan_text();
    std::fs::write(d.join("judge.json"), &scan).unwrap();
    let out = lustre(
        &d,
        &s(&[
            "judge",
            "judge.json",
            "--format",
            "matrix",
            "--no-plots",
            "-o",
            ".",
        ]),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("is the input"), "{err}");
    assert_eq!(std::fs::read_to_string(d.join("judge.json")).unwrap(), scan);
    // A reference BRDF named like the point table.
    std::fs::write(d.join("scan.txt"), &scan).unwrap();
    let table = "theta_i_deg,theta_o_deg,phi_o_deg,lambda_nm,brdf\n0,10,0,550,1.0\n";
    std::fs::write(d.join("judge_points.csv"), table).unwrap();
    let out = lustre(
        &d,
        &s(&[
            "judge",
            "scan.txt",
            "--reference",
            "judge_points.csv",
            "--no-plots",
            "-o",
            ".",
        ]),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("is the input"), "{err}");
    assert_eq!(
        std::fs::read_to_string(d.join("judge_points.csv")).unwrap(),
        table
    );
    let _ = std::fs::remove_dir_all(&d);
}
