//! Cost of the wave-optical models against GGX, and the full-GHS table's
//! evaluation time against its error as the table resolution varies.
//!
//! * criterion groups `ggx_cu`, `ghs_full_cu`, `ghs_ssa_cu`: `eval`,
//!   `eval+pdf` and `sample` per call, each iteration on one input from a
//!   ring of 1024 random (wi, wo, λ, u) with wo drawn by the model itself
//!   (the renderer's case). Targets (issue 3): full GHS eval ≤ 3× GGX eval,
//!   sample ≤ 5× GGX sample.
//! * before criterion runs, a plain table is printed: for several table
//!   resolutions, build time, memory, the measured max relative error of S̃
//!   against freshly transformed rows (midway between rows, quarter points
//!   between columns, values ≥ 1e−9 of the peak) and the mean eval time.
//!
//! Run: `cargo bench --bench ghs`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use brdf::microfacet::{Distribution, MicrofacetConductor};
use brdf::statistics::KcPsd;
use brdf::statistics::matern::Matern;
use brdf::wave::ghs::hemisphere_u_max;
use brdf::wave::ghs_table::{GhsTable, TableResolution};
use brdf::wave::{GhsFull, GhsOptions, GhsSsa};
use brdf::{Bxdf, Fresnel, Ior, Metal};
use criterion::{Criterion, criterion_group, criterion_main};

#[path = "support/ring.rs"]
mod ring;
use ring::{Input, RING, inputs};

fn bench_model(c: &mut Criterion, name: &str, model: &dyn Bxdf) {
    let ring = inputs(model, Some(0.999_999));
    let mut g = c.benchmark_group(name);
    g.bench_function("eval", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (RING - 1);
            let x = &ring[i];
            black_box(model.eval(black_box(x.wi), black_box(x.wo), black_box(x.lambda)))
        })
    });
    g.bench_function("eval+pdf", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (RING - 1);
            let x = &ring[i];
            let (wi, wo, l) = (black_box(x.wi), black_box(x.wo), black_box(x.lambda));
            black_box(model.eval_pdf(wi, wo, l))
        })
    });
    g.bench_function("sample", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & (RING - 1);
            let x = &ring[i];
            black_box(model.sample(black_box(x.wi), black_box(x.lambda), black_box(x.u)))
        })
    });
    g.finish();
}

fn cu() -> Fresnel {
    Fresnel::conductor(Ior::metal(Metal::Cu))
}

/// The S280 surface of the reference set (σ 0.28 µm, Lc 5 µm, γ 3).
fn s280() -> KcPsd {
    KcPsd::new(0.28, 5.0, 3.0).unwrap()
}

fn mean_eval_ns(model: &dyn Bxdf, ring: &[Input]) -> f64 {
    let reps = 400;
    let t = Instant::now();
    let mut acc = 0.0;
    for _ in 0..reps {
        for x in ring {
            acc += model.eval(black_box(x.wi), black_box(x.wo), black_box(x.lambda));
        }
    }
    black_box(acc);
    t.elapsed().as_nanos() as f64 / (reps * ring.len()) as f64
}

fn resolution_table() {
    println!(
        "\nfull GHS table: resolution vs build time, memory, max relative error of S̃, eval time"
    );
    println!(
        "{:>5} {:>9} {:>6} {:>7} | {:>5} {:>9} {:>9} {:>9} {:>10}",
        "rows", "cols/dec", "fft_n", "fft_dt", "γ", "build ms", "memory kB", "max err", "eval ns"
    );
    let resolutions = [
        (6.0, 16.0, 4096, 0.025),
        (8.0, 24.0, 4096, 0.025),
        (12.0, 24.0, 8192, 0.0125),
        (12.0, 40.0, 8192, 0.0125),
        (16.0, 48.0, 8192, 0.0125),
        (24.0, 64.0, 8192, 0.0125),
    ];
    let surfaces = [(1.5, 20.0), (3.0, 5.0), (3.5, 10.0), (6.0, 1.0)];
    for (rows, cols, n, dt) in resolutions {
        let res = TableResolution {
            rows_per_decade: rows,
            cols_per_decade: cols,
            fft_n: n,
            fft_dt: dt,
        };
        for (gamma, lc) in surfaces {
            let m = Matern::new((gamma - 1.0) / 2.0);
            let t0 = Instant::now();
            let table = GhsTable::build(&m, hemisphere_u_max(lc), res).unwrap();
            let build = t0.elapsed().as_secs_f64() * 1e3;
            let err = table.measure_error(&m, res, 1e-9);
            let mem = table.memory_bytes() as f64 / 1024.0;
            let psd = KcPsd::new(0.28, lc, gamma).unwrap();
            let model =
                GhsFull::with_table(psd, cu(), GhsOptions::default(), std::sync::Arc::new(table))
                    .unwrap();
            let ring = inputs(&model, Some(0.999_999));
            let ns = mean_eval_ns(&model, &ring);
            println!(
                "{rows:>5} {cols:>9} {n:>6} {dt:>7} | {gamma:>5} {build:>9.1} {mem:>9.0} {err:>9.2e} {ns:>10.1}"
            );
        }
    }
    let ggx = MicrofacetConductor::new(Distribution::ggx(0.2, 0.2).unwrap(), cu()).unwrap();
    let ring = inputs(&ggx, Some(0.999_999));
    println!(
        "GGX (α = 0.2, Cu) eval for comparison: {:.1} ns\n",
        mean_eval_ns(&ggx, &ring)
    );
}

fn models(c: &mut Criterion) {
    resolution_table();
    let ggx = MicrofacetConductor::new(Distribution::ggx(0.2, 0.2).unwrap(), cu()).unwrap();
    bench_model(c, "ggx_cu", &ggx);
    let full = GhsFull::new(s280(), cu()).unwrap();
    bench_model(c, "ghs_full_cu", &full);
    let ssa = GhsSsa::new(s280(), cu()).unwrap();
    bench_model(c, "ghs_ssa_cu", &ssa);
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
}

criterion_group! { name = benches; config = config(); targets = models }
criterion_main!(benches);
