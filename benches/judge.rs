//! Speed of the explicit-surface BRDF and of `lustre judge` (issue 16 targets, 2 cores):
//!
//! * `explicit/slice_1024_90`: one in-plane slice of 90 exit angles at one wavelength on a
//!   1024² map (`fit::explicit_brdf`, default tiles: 49 tiles of 256², exact q and ζ per
//!   direction). Target ≤ 5 s.
//! * `judge/di6_512_3x3`: the whole `lustre judge data/surfaces/di-6.di` (a 512² AFM map)
//!   at 3 incidence angles × 3 wavelengths, defaults otherwise (Gaussian surrogate, all
//!   models, the two-scale cutoff search, figures), as a subprocess. Target ≤ 60 s.
//!
//! Run: `cargo bench --bench judge`. The machine is shared: note `/proc/loadavg` with the
//! numbers (printed before the groups run).

use std::hint::black_box;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use fit::explicit_brdf::{ExplicitBrdf, TileOptions};
use fit::kc::KcParams;
use fit::sampled_kc::PointSampledKc;

fn bench(c: &mut Criterion) {
    if let Ok(l) = std::fs::read_to_string("/proc/loadavg") {
        eprintln!("load average at start: {}", l.trim());
    }
    eprintln!(
        "rayon threads: {}",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );

    // A 1024² Gaussian KC map, 20 nm pixels (AFM-like): σ 15 nm, Lc 0.1 µm, γ 4.
    let map = PointSampledKc::new(
        1024,
        1024,
        20e-9,
        KcParams {
            sigma: 15e-9,
            lc: 0.1e-6,
            gamma: 4.0,
        },
    )
    .realise(7);
    let e = ExplicitBrdf::new(&map, &TileOptions::default()).unwrap();
    let lambda = 550e-9;
    let ti = 30f64.to_radians();
    let wi = [ti.sin(), 0.0, ti.cos()];
    let wos: Vec<[f64; 3]> = (0..90)
        .map(|j| {
            let t = (-89.0 + 178.0 * j as f64 / 89.0f64).to_radians();
            [-t.sin(), 0.0, t.cos()]
        })
        .collect();
    let mut g = c.benchmark_group("explicit");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("slice_1024_90", |b| {
        b.iter(|| black_box(e.scattered_many(black_box(wi), &wos, lambda)))
    });
    g.finish();

    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bench-judge");
    let mut g = c.benchmark_group("judge");
    g.sample_size(10).measurement_time(Duration::from_secs(120));
    g.bench_function("di6_512_3x3", |b| {
        b.iter(|| {
            let o = Command::new(env!("CARGO_BIN_EXE_lustre"))
                .args([
                    "judge",
                    root.join("data/surfaces/di-6.di").to_str().unwrap(),
                    "--theta-i",
                    "0,45,80",
                    "--lambda",
                    "450,550,650",
                    "-o",
                    out.to_str().unwrap(),
                ])
                .output()
                .expect("running lustre judge");
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        })
    });
    g.finish();
    if let Ok(l) = std::fs::read_to_string("/proc/loadavg") {
        eprintln!("load average at end: {}", l.trim());
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
