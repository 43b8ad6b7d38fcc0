//! Command-line values that used to panic or run away: durations that
//! overflow, absurd thread counts, corrupt films handed to `merge` and
//! `--resume`. Each is a clean error (exit 1, a message naming the option
//! or file) or a capped run that says so — never a panic (exit 101) or an
//! abort.

use std::path::Path;
use std::process::{Command, Output};

mod common;

/// The shared tiny scene at 2 spp (a resumable film needs more than one sample).
fn scene() -> String {
    common::TINY_SCENE.replace("spp = 1", "spp = 2")
}

fn lustre(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run lustre")
}

fn fails_with(dir: &Path, args: &[&str], needle: &str) {
    let out = lustre(dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: {err}");
}

fn tempdir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-hostile-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("s.toml"), scene()).unwrap();
    d
}

#[test]
fn durations_that_overflow_are_errors() {
    let d = tempdir("dur");
    for v in ["inf", "nan", "1e30", "-5", "0", "0.5", "1e300h"] {
        let arg = format!("--checkpoint-every={v}");
        fails_with(&d, &["render", "s.toml", "-q", &arg], "--checkpoint-every");
    }
    for v in ["inf", "1e30", "1e300h", "18446744073709551616", "-1", "0"] {
        let arg = format!("--time-limit={v}");
        fails_with(&d, &["render", "s.toml", "-q", &arg], "--time-limit");
    }
    // A long but representable limit renders normally.
    let out = lustre(&d, &["render", "s.toml", "-q", "--time-limit", "876000h"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn thread_counts_are_capped_and_said_so() {
    let d = tempdir("threads");
    let out = lustre(&d, &["render", "s.toml", "--threads", "10000"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("--threads 10000 capped at"), "{err}");
    fails_with(
        &d,
        &["render", "s.toml", "-q", "--threads", "0"],
        "--threads",
    );
    // The figure commands cap and say so too.
    for args in [
        &[
            "compare",
            "--sample",
            "S027",
            "--views",
            "0",
            "--cutoffs",
            "100",
        ][..],
        &["preview", "--sample", "S027", "--models", "ggx"][..],
    ] {
        let mut args = args.to_vec();
        args.extend([
            "--size",
            "8x6",
            "--spp",
            "1",
            "--threads",
            "4294967296",
            "-o",
            "f.png",
        ]);
        let out = lustre(&d, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{args:?}: {err}");
        assert!(
            err.contains("--threads 4294967296 capped at"),
            "{args:?}: {err}"
        );
    }
    // A sun azimuth of any finite size is one turn of the sky, not a generated file's error.
    let out = lustre(
        &d,
        &[
            "preview",
            "--sample",
            "S027",
            "--models",
            "ggx",
            "--size",
            "8x6",
            "--spp",
            "1",
            "-q",
            "-o",
            "az.png",
            "--sun-azimuth=-1e308",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn corrupt_films_are_errors_naming_the_file() {
    let d = tempdir("films");
    let out = lustre(&d, &["render", "s.toml", "-q", "--film", "good.film"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let good = std::fs::read(d.join("good.film")).unwrap();
    // A flipped byte in the sums (accepted before: the image came out wrong).
    let mut flipped = good.clone();
    let n = flipped.len();
    flipped[n - 20] ^= 0x10;
    std::fs::write(d.join("flipped.film"), &flipped).unwrap();
    fails_with(
        &d,
        &["merge", "good.film", "flipped.film", "--png", "x.png"],
        "flipped.film",
    );
    fails_with(&d, &["merge", "flipped.film", "--png", "x.png"], "checksum");
    // A 48-byte format-1 header claiming 65535 × 65535 pixels and 2³² − 1
    // ranges (an attempted 206 GB allocation before).
    let mut v1 = b"LUSTREFILM1\n".to_vec();
    v1.extend_from_slice(&65535u32.to_le_bytes());
    v1.extend_from_slice(&65535u32.to_le_bytes());
    v1.extend_from_slice(&[0; 24]);
    v1.extend_from_slice(&u32::MAX.to_le_bytes());
    assert_eq!(v1.len(), 48);
    std::fs::write(d.join("crafted.film"), &v1).unwrap();
    fails_with(
        &d,
        &["merge", "crafted.film", "--png", "x.png"],
        "crafted.film",
    );
    // Truncated, and not a film at all.
    std::fs::write(d.join("cut.film"), &good[..good.len() / 2]).unwrap();
    fails_with(
        &d,
        &["merge", "good.film", "cut.film", "--png", "x.png"],
        "cut.film",
    );
    std::fs::write(d.join("text.film"), "hello").unwrap();
    fails_with(
        &d,
        &["merge", "text.film", "--png", "x.png"],
        "not a lustre film",
    );
    // --resume from a corrupt checkpoint is an error too, and leaves it alone.
    std::fs::write(d.join("ck.film"), &flipped).unwrap();
    fails_with(
        &d,
        &[
            "render", "s.toml", "-q", "--spp", "4", "--resume", "--film", "ck.film",
        ],
        "ck.film",
    );
    assert_eq!(std::fs::read(d.join("ck.film")).unwrap(), flipped);
    let _ = std::fs::remove_dir_all(&d);
}

/// `--no-film` writes the images and no film; shards given the same `--exr` get films
/// named after their ranges, so neither overwrites the other, and they merge.
#[test]
fn no_film_and_shard_films_named_after_their_range() {
    let d = tempdir("no-film");
    let out = lustre(&d, &["s.toml", "--no-film", "--png", "one.png", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("one.png").exists());
    assert!(!d.join("one.film").exists(), "--no-film wrote a film");
    // A usage error from the argument parser (exit 2), naming the conflicting flag.
    let out = lustre(&d, &["s.toml", "--no-film", "--resume"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--resume"));

    for range in ["0..1", "1..2"] {
        let out = lustre(&d, &["s.toml", "--spp-range", range, "--exr", "img.exr"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{err}");
        assert!(err.contains("CPU s"), "summary without CPU seconds: {err}");
    }
    assert!(d.join("img.spp0-1.film").exists() && d.join("img.spp1-2.film").exists());
    let out = lustre(
        &d,
        &[
            "merge",
            "img.spp0-1.film",
            "img.spp1-2.film",
            "--png",
            "merged.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The documented resolution limit, at the limit: the largest film is accepted by
/// the scene, one pixel row more is refused naming the limit, and a render the
/// process cannot hold (here under `ulimit -v`) is refused up front with the
/// numbers, never an abort on the allocation.
#[test]
fn resolution_limit_and_memory_are_checked_before_allocating() {
    let d = tempdir("resolution");
    let at_limit = scene().replace("resolution = [4, 3]", "resolution = [32768, 1024]");
    let over = scene().replace("resolution = [4, 3]", "resolution = [32768, 1025]");
    std::fs::write(d.join("limit.toml"), &at_limit).unwrap();
    std::fs::write(d.join("over.toml"), &over).unwrap();
    render::load_str(&d.join("limit.toml"), &at_limit).unwrap();
    fails_with(
        &d,
        &["render", "over.toml", "-q"],
        "at most 33554432 pixels",
    );
    let out = Command::new("sh")
        .current_dir(&d)
        .arg("-c")
        .arg(format!(
            "ulimit -v 1500000 && exec {} render limit.toml -q",
            env!("CARGO_BIN_EXE_lustre")
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("32768×1024 render needs about 2.44 GiB")
            && err.contains("lower the resolution"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
