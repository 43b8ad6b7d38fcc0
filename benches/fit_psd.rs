//! `fit` on a 1024 × 1024 map. Targets (issue 14, 2 cores): the whole `lustre fit stats`
//! analysis — read, level, Welch PSD, K-correlation fit (and the anisotropy report it
//! prints) — ≤ 0.3 s; the Welch PSD alone ≤ 25 ms; the radial 2D PSD ≤ 60 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use fit::io::{ReadOptions, open_bytes};
use fit::kc::{self, KcParams};
use fit::psd::{self, WelchOptions};
use std::hint::black_box;

/// The map as a Gwyddion Simple Field file (float32), so the bench includes reading.
fn gsf_bytes(t: &fit::Topography) -> Vec<u8> {
    let mut h = format!(
        "Gwyddion Simple Field 1.0\nXRes = {}\nYRes = {}\nXReal = {:e}\nYReal = {:e}\nXYUnits = m\nZUnits = m\n",
        t.nx,
        t.ny,
        t.size_x(),
        t.size_y()
    )
    .into_bytes();
    let pad = 4 - h.len() % 4;
    h.extend(std::iter::repeat_n(0u8, pad));
    h.extend(t.heights.iter().flat_map(|v| (*v as f32).to_le_bytes()));
    h
}

fn bench(c: &mut Criterion) {
    let truth = KcParams {
        sigma: 5e-9,
        lc: 0.1e-6,
        gamma: 4.0,
    };
    let mut map = fit::synth::kc_surface(1024, 1024, 10e-9, truth, 1);
    // A tilt, so levelling has work to do.
    for y in 0..1024 {
        for x in 0..1024 {
            map.heights[y * 1024 + x] += 1e-3 * (x as f64 - 0.7 * y as f64) * 10e-9;
        }
    }
    let file = gsf_bytes(&map);
    let mut g = c.benchmark_group("fit_psd");
    g.sample_size(20);
    g.bench_function("fit_stats_1024x1024", |b| {
        b.iter(|| {
            let scan = open_bytes("bench.gsf", black_box(&file), &ReadOptions::default()).unwrap();
            fit::pipeline::summarise(scan.topo, None).unwrap()
        })
    });
    // Parts of the above.
    g.bench_function("read_gsf_1024x1024", |b| {
        b.iter(|| open_bytes("bench.gsf", black_box(&file), &ReadOptions::default()).unwrap())
    });
    g.bench_function("level_plane_and_form_check_1024x1024", |b| {
        b.iter(|| {
            let mut t = map.clone();
            fit::level::apply(black_box(&mut t), fit::level::Level::Plane).unwrap()
        })
    });
    g.bench_function("anisotropy_1024x1024", |b| {
        let p = psd::welch(&map, &WelchOptions::default()).unwrap();
        b.iter(|| fit::anisotropy::analyse(black_box(&map), p.clone()).unwrap())
    });
    g.bench_function("welch_1024x1024", |b| {
        b.iter(|| psd::welch(black_box(&map), &WelchOptions::default()).unwrap())
    });
    g.bench_function("radial_psd_1024x1024", |b| {
        b.iter(|| psd::radial(black_box(&map)).unwrap())
    });
    let p = psd::welch(&map, &WelchOptions::default()).unwrap();
    g.bench_function("kc_fit_256_bins", |b| {
        b.iter(|| kc::fit_bins(black_box(&p), 3, 256).unwrap())
    });
    g.bench_function("radial_psd_and_2d_fit_1024x1024", |b| {
        b.iter(|| {
            let r = psd::radial(black_box(&map)).unwrap();
            let zmax = *r.zeta.last().unwrap();
            kc::fit(
                kc::PsdForm::Radial2d,
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
