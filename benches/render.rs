//! Renderer speed: samples per second on the default scene (1 and 2 threads,
//! whose ratio is the 2-thread scaling) and scene start-up time (parse, build
//! materials and lights) for scenes without meshes.
//!
//! `cargo bench --bench render`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use render::{Film, RenderOptions, Scene};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn scene_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn render_spp(pool: &render::render::ThreadPool, scene: &Scene, spp: u64) -> Film {
    let mut film = Film::new(
        scene.camera.width,
        scene.camera.height,
        scene.fingerprint,
        1,
        0.0,
    );
    let opts = RenderOptions {
        pass_target: Duration::from_secs(3600),
        ..RenderOptions::default()
    };
    render::render_range_in(pool, scene, &mut film, 0..spp, &opts).expect("render");
    film
}

fn throughput(c: &mut Criterion) {
    let scene = render::load_scene(&scene_path("scenes/default.toml")).expect("default scene");
    let spp = 2;
    let samples = scene.camera.width as u64 * scene.camera.height as u64 * spp;
    let mut g = c.benchmark_group("default_scene");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.throughput(Throughput::Elements(samples));
    for threads in [1usize, 2] {
        let pool = render::render::thread_pool(Some(threads)).expect("pool");
        g.bench_function(format!("{threads}_threads"), |b| {
            b.iter(|| black_box(render_spp(&pool, &scene, spp)))
        });
    }
    g.finish();
}

fn startup(c: &mut Criterion) {
    let mut g = c.benchmark_group("startup");
    g.sample_size(20);
    for rel in [
        "scenes/default.toml",
        "scenes/samples/s138_ghs_ssa_45deg.toml",
        "scenes/samples/s138_ghs_45deg.toml",
        "scenes/samples/s091_measured_psd_45deg.toml",
    ] {
        let path = scene_path(rel);
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        g.bench_function(name, |b| {
            b.iter(|| black_box(render::load_scene(&path).expect("scene")))
        });
    }
    g.finish();
}

criterion_group!(benches, throughput, startup);
criterion_main!(benches);
