//! `lustre brdf eval` as a stream: lines per second through the built
//! binary (process start-up included), for
//!
//! * `mixed_1000_surfaces`: 10⁵ queries drawn at random over 1000
//!   surfaces — 20 KC surfaces × 5 Fresnel choices × {ghs, ghs_ssa,
//!   ghs_ssa + krywonos, two_scale} and 120 roughnesses × 5 Fresnel
//!   choices × {ggx, beckmann} — so every model is built on first use and
//!   then served from the cache (issue 13: the old cache, cleared whole past
//!   64 entries, ran such a stream at ~22 lines per CPU-second);
//! * `one_surface`: 10⁵ queries on one GGX surface: the cost of a query
//!   once its model is built (JSON in, evaluation, JSON out).
//!
//! Wall-clock time of the child process; run on an idle machine.
//! `cargo bench --bench brdf_stream`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Duration;

const LINES: usize = 100_000;

struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The 1000 surfaces of the mixed stream, as the JSON fields before the geometry.
fn surfaces() -> Vec<String> {
    let metals = ["none", "cu", "au", "al", "brass"];
    let mut v = Vec::new();
    for i in 0..20 {
        let (s, l, g) = (
            0.02 + 0.04 * i as f64,
            1.0 + 1.5 * i as f64,
            1.5 + 0.3 * i as f64,
        );
        let kc = format!("\"sigma_um\": {s}, \"lc_um\": {l}, \"gamma\": {g}");
        for m in metals {
            v.push(format!("\"model\": \"ghs\", {kc}, \"fresnel\": \"{m}\""));
            v.push(format!(
                "\"model\": \"ghs_ssa\", {kc}, \"fresnel\": \"{m}\""
            ));
            v.push(format!(
                "\"model\": \"ghs_ssa\", {kc}, \"fresnel\": \"{m}\", \"energy\": \"krywonos\""
            ));
            v.push(format!(
                "\"model\": \"two_scale\", {kc}, \"beta\": 0.05, \"fresnel\": \"{m}\""
            ));
        }
    }
    for i in 0..120 {
        let model = if i % 2 == 1 { "ggx" } else { "beckmann" };
        for m in metals {
            v.push(format!(
                "\"model\": \"{model}\", \"alpha\": {}, \"fresnel\": \"{m}\"",
                0.02 + 0.005 * i as f64
            ));
        }
    }
    assert_eq!(v.len(), 1000);
    v
}

fn stream(surfaces: &[String], seed: u64) -> Vec<u8> {
    let mut r = XorShift(seed);
    let mut out = Vec::with_capacity(LINES * 200);
    for _ in 0..LINES {
        let s = &surfaces[(r.next() % surfaces.len() as u64) as usize];
        let l = [450, 550, 650][(r.next() % 3) as usize];
        writeln!(
            out,
            "{{{s}, \"lambda_nm\": {l}, \"theta_i_deg\": {:.3}, \"theta_o_deg\": {:.3}, \"phi_o_deg\": {:.3}}}",
            85.0 * r.uniform(),
            85.0 * r.uniform(),
            360.0 * r.uniform()
        )
        .unwrap();
    }
    out
}

fn run(input: &[u8]) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(["brdf", "eval"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("run lustre");
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    assert!(out.status.success());
    let n = out.stdout.iter().filter(|&&b| b == b'\n').count();
    assert_eq!(n, LINES);
    assert!(
        !out.stdout.windows(8).any(|w| w == b"\"error\""),
        "a query failed"
    );
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("brdf_eval_stream");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(60))
        .throughput(Throughput::Elements(LINES as u64));
    let mixed = stream(&surfaces(), 1);
    g.bench_function("mixed_1000_surfaces", |b| b.iter(|| run(&mixed)));
    let one = stream(
        &["\"model\": \"ggx\", \"alpha\": 0.1, \"fresnel\": \"cu\"".to_string()],
        2,
    );
    g.bench_function("one_surface", |b| b.iter(|| run(&one)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
