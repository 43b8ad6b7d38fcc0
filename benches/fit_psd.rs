//! Welch PSD and K-correlation fit of a 1024 × 1024 map (target ≤ 0.5 s on 2 cores).

use criterion::{Criterion, criterion_group, criterion_main};
use fit::kc::{self, KcParams};
use fit::psd::{self, WelchOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let truth = KcParams {
        sigma: 5e-9,
        lc: 0.1e-6,
        gamma: 4.0,
    };
    let map = fit::synth::kc_surface(1024, 1024, 10e-9, truth, 1);
    let mut g = c.benchmark_group("fit_psd");
    g.sample_size(20);
    g.bench_function("welch_1024x1024", |b| {
        b.iter(|| psd::welch(black_box(&map), &WelchOptions::default()).unwrap())
    });
    let p = psd::welch(&map, &WelchOptions::default()).unwrap();
    g.bench_function("kc_fit_256_bins", |b| {
        b.iter(|| kc::fit_bins(black_box(&p), 3, 256).unwrap())
    });
    g.bench_function("welch_and_kc_fit_1024x1024", |b| {
        b.iter(|| {
            let p = psd::welch(black_box(&map), &WelchOptions::default()).unwrap();
            kc::fit_bins(&p, 3, 256).unwrap()
        })
    });
    g.bench_function("radial_psd_and_2d_fit_1024x1024", |b| {
        b.iter(|| {
            let r = psd::radial(black_box(&map)).unwrap();
            let zmax = *r.zeta.last().unwrap();
            kc::fit(
                kc::Form::Radial2d,
                &r.zeta,
                &r.p,
                r.zeta[2] * 0.999,
                zmax / 2.0,
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
