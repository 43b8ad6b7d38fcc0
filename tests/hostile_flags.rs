//! Every count and float flag of every subcommand given 0, −1, NaN, ±inf,
//! 1e308 and 2⁶⁴ − 1: a clean refusal naming the flag (exit 1 or clap's 2),
//! or a run that finishes (a capped value says so) — never a panic, an abort
//! on an allocation, or a run without end.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const VALUES: [&str; 8] = [
    "0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "18446744073709551615",
];

/// Longest a run may take before it counts as one that would not end.
const LIMIT: Duration = Duration::from_secs(90);

fn run(dir: &Path, args: &[String]) -> (Option<i32>, String, Duration) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > LIMIT {
            child.kill().unwrap();
            panic!("{args:?} runs past {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        start.elapsed(),
    )
}

/// A subcommand's cheap baseline and its numeric flags.
struct Case {
    base: &'static [&'static str],
    flags: &'static [&'static str],
}

const CASES: &[Case] = &[
    Case {
        base: &["render", "s.toml", "-q", "--no-film", "--png", "o.png"],
        flags: &[
            "--spp",
            "--seed",
            "--threads",
            "--exposure",
            "--time-limit",
            "--checkpoint-every",
            "--spp-range",
        ],
    },
    Case {
        base: &["merge", "shard.film", "-q", "--png", "o.png"],
        flags: &["--exposure"],
    },
    Case {
        base: &[
            "brdf",
            "plot",
            "--samples",
            "S027",
            "--models",
            "ggx",
            "--theta-i",
            "30",
            "--points",
            "8",
            "--albedo-angles",
            "2",
            "--size",
            "480x320",
            "--quiet",
            "--out",
            "plots",
        ],
        flags: &[
            "--lambda-nm",
            "--theta-i",
            "--alpha",
            "--points",
            "--albedo-angles",
        ],
    },
    Case {
        base: &[
            "compare",
            "--sample",
            "S027",
            "--cutoffs",
            "100",
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
            "c.png",
        ],
        flags: &["--cutoffs", "--views", "--spp", "--threads"],
    },
    Case {
        base: &[
            "preview",
            "--sample",
            "S027",
            "--models",
            "ggx",
            "--size",
            "8x6",
            "--spp",
            "1",
            "--threads",
            "1",
            "--time-limit",
            "20s",
            "-q",
            "-o",
            "pv.png",
        ],
        flags: &[
            "--cutoff",
            "--sun-elevation",
            "--sun-azimuth",
            "--turbidity",
            "--spp",
            "--exposure",
            "--threads",
            "--time-limit",
        ],
    },
    Case {
        base: &["fit", "scan.txt", "--no-plots", "-o", "m.toml"],
        flags: &[
            "--stylus-segments",
            "--cutoff",
            "--lambda-nm",
            "--merge-cutoff",
            "--pixel-size",
            "--size",
        ],
    },
    Case {
        base: &[
            "judge",
            "scan.txt",
            "--no-plots",
            "--no-surrogate",
            "--theta-i",
            "0",
            "--lambda",
            "550",
            "-o",
            "j",
        ],
        flags: &[
            "--lambda",
            "--theta-i",
            "--cutoff",
            "--angles",
            "--tile",
            "--crop",
            "--upsample",
        ],
    },
];

/// `base` with `flag` set to `value` (replacing the baseline's own value).
fn with_flag(base: &[&str], flag: &str, value: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip = false;
    for a in base {
        if skip {
            skip = false;
            continue;
        }
        if *a == flag {
            skip = true;
            continue;
        }
        out.push(a.to_string());
    }
    out.push(format!("{flag}={value}"));
    out
}

fn fixture() -> PathBuf {
    let d = std::env::temp_dir().join(format!("lustre-flags-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("s.toml"), common::TINY_SCENE).unwrap();
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/data/surfaces/matrix-3.txt"),
        d.join("scan.txt"),
    )
    .unwrap();
    let (code, err, _) = run(
        &d,
        &["render", "s.toml", "-q", "--film", "shard.film"].map(String::from),
    );
    assert_eq!(code, Some(0), "{err}");
    d
}

#[test]
fn every_numeric_flag_survives_absurd_values() {
    let d = fixture();
    let mut slowest = (Duration::ZERO, Vec::new());
    let mut failures = Vec::new();
    for case in CASES {
        for flag in case.flags {
            for value in VALUES {
                let args = with_flag(case.base, flag, value);
                let (code, err, took) = run(&d, &args);
                if took > slowest.0 {
                    slowest = (took, args.clone());
                }
                let what = format!("{args:?}: exit {code:?}: {}", err.trim());
                let name = flag.trim_start_matches("--");
                if !matches!(code, Some(0..=2)) || err.contains("panicked") {
                    failures.push(what);
                } else if code != Some(0)
                    && !(err.contains(name) || err.contains(&name.replace('-', "_")))
                {
                    failures.push(format!("{what}\n  (the message does not name {flag})"));
                } else if err.contains("Some(") {
                    failures.push(format!("{what}\n  (Debug formatting)"));
                }
            }
        }
    }
    eprintln!(
        "slowest run: {:.1} s {:?}",
        slowest.0.as_secs_f64(),
        slowest.1
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&d);
}
