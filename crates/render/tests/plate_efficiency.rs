//! Efficiency of the 45° copper plate of `benches/peer/plate_scenes.toml`
//! (3 cm sphere light at 1 m, 256², direct light only) with its material
//! swapped: GGX α 0.2, full GHS, two-scale with a delta coherent lobe and
//! the measured-PSD model (σ 0.138 µm, Lc 2 µm, γ 2; the PSD table is that
//! surface's, `scenes/psd/s138_kc.csv`).
//!
//! A measurement, not a check: ignored by default, and it asserts nothing
//! about time. Run in release:
//!
//! ```text
//! cargo test -p render --release --test plate_efficiency -- --ignored --nocapture
//! ```
//!
//! Settings through the environment: `PLATE_MODELS` (comma list of ggx,
//! ghs, two_scale, measured_psd), `PLATE_REF_SPP` (default 2048, rendered
//! as two halves with their own seeds), `PLATE_SPP` (default 16,64,256),
//! `PLATE_SEEDS` (default 2), `PLATE_THREADS` (default 2), `PLATE_CACHE`
//! (directory of the reference films, default `target/plate_efficiency`;
//! a reference is reused while its scene text is the same) and
//! `PLATE_EXTRA` (lines appended to `[integrator]`, e.g.
//! `hero_wavelengths = 16`). A reference made before a change of the
//! renderer is kept on purpose: the images after the change are compared
//! with the converged image before it, which is the unbiasedness check.
//!
//! Per image it prints the relative RMSE over all pixels and linear-sRGB
//! channels (the reference's own noise, estimated from its two halves,
//! removed), the CPU seconds of the whole process during the render, the
//! efficiency 1 / (relRMSE² · CPU s), the share of squared error in the
//! brightest 4 % of pixels (the mirror image of the light) and, per
//! brightness region, the ratio of the image's mean to the reference's.

use render::color::xyz_to_srgb;
use render::{Film, RenderOptions, Scene};
use std::path::{Path, PathBuf};

const BRIGHT_SHARE: f64 = 0.04;

fn material(model: &str, root: &Path) -> String {
    let kc = "sigma_um = 0.138\nlc_um = 2.0\ngamma = 2.0\n";
    match model {
        "ggx" => "model = \"ggx\"\nmetal = \"cu\"\nalpha = 0.2\n".into(),
        "ghs" => format!("model = \"ghs\"\nmetal = \"cu\"\n{kc}"),
        "two_scale" => format!(
            "model = \"two_scale\"\nmetal = \"cu\"\n{kc}beta = 0.05\ncoherent = \"delta\"\n"
        ),
        "measured_psd" => format!(
            "model = \"measured_psd\"\nmetal = \"cu\"\npsd_csv = \"{}\"\n",
            root.join("scenes/psd/s138_kc.csv").display()
        ),
        other => panic!("unknown model {other}"),
    }
}

fn scene_text(model: &str, root: &Path, seed: u64, extra: &str) -> String {
    format!(
        "[film]\nspp = 1\nseed = {seed}\n\
         [camera]\nlook_from = [0.0, 0.707107, 0.707107]\nlook_at = [0.0, 0.0, 0.0]\n\
         up = [0.0, 1.0, 0.0]\nfov_deg = 32.0\nresolution = [256, 256]\n\
         [integrator]\nmax_depth = 1\nwavelengths = \"hero\"\n{extra}\n\
         [materials.plate]\n{}\
         [[shapes]]\ntype = \"rectangle\"\nsize = [0.5, 0.5]\nmaterial = \"plate\"\n\
         transform = {{ rotate_deg = [-90.0, 0.0, 0.0] }}\n\
         [[lights]]\ntype = \"sphere\"\ncenter = [0.0, 0.707107, -0.707107]\nradius = 0.03\n\
         radiance = 150.0\nspectrum = \"constant\"\n",
        material(model, root)
    )
}

fn env(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// CPU seconds of every thread of this process so far (Linux).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    // Fields after the command name, which is in parentheses.
    let rest = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line (11, 12 here).
    let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
    ticks / 100.0
}

fn load(text: &str, root: &Path) -> Scene {
    render::load_str(&root.join("plate.toml"), text).expect("scene")
}

fn rgb(film: &Film) -> Vec<[f64; 3]> {
    (0..(film.width() * film.height()) as usize)
        .map(|i| xyz_to_srgb(film.xyz(i)))
        .collect()
}

fn render(scene: &Scene, film: &mut Film, range: std::ops::Range<u64>, threads: usize) -> f64 {
    let opts = RenderOptions {
        threads: Some(threads),
        ..Default::default()
    };
    let t0 = cpu_seconds();
    render::render_range(scene, film, range, &opts).expect("render");
    cpu_seconds() - t0
}

/// The reference's two halves, from the cache or rendered.
fn reference(
    model: &str,
    root: &Path,
    cache: &Path,
    spp: u64,
    threads: usize,
) -> [Vec<[f64; 3]>; 2] {
    std::fs::create_dir_all(cache).unwrap();
    [0u64, 1].map(|h| {
        let text = scene_text(
            model,
            root,
            1000 + h,
            &env("PLATE_REF_EXTRA", "").replace("\\n", "\n"),
        );
        let key = {
            use std::hash::{Hash, Hasher};
            let mut s = std::collections::hash_map::DefaultHasher::new();
            (text.as_str(), spp).hash(&mut s);
            s.finish()
        };
        let path = cache.join(format!("{model}_{h}_{key:016x}.film"));
        let film = match Film::load(&path) {
            Ok(f) => f,
            Err(_) => {
                let scene = load(&text, root);
                let mut film = scene.film().unwrap();
                let cpu = render(&scene, &mut film, 0..spp / 2, threads);
                eprintln!(
                    "reference {model} half {h}: {} spp, {cpu:.1} CPU s",
                    spp / 2
                );
                film.save(&path).unwrap();
                film
            }
        };
        rgb(&film)
    })
}

struct Stats {
    rel_rmse: f64,
    bright_share: f64,
    region_ratio: [f64; 3],
}

fn compare(img: &[[f64; 3]], refs: &[Vec<[f64; 3]>; 2]) -> Stats {
    let n = img.len();
    let r: Vec<[f64; 3]> = (0..n)
        .map(|i| std::array::from_fn(|c| 0.5 * (refs[0][i][c] + refs[1][i][c])))
        .collect();
    let lum = |p: &[f64; 3]| p[0] + p[1] + p[2];
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| lum(&r[b]).total_cmp(&lum(&r[a])));
    // Regions: brightest 4 %, the next 26 %, the rest.
    let mut region = vec![0u8; n];
    for (rank, &i) in order.iter().enumerate() {
        let f = rank as f64 / n as f64;
        region[i] = if f < BRIGHT_SHARE {
            0
        } else if f < 0.3 {
            1
        } else {
            2
        };
    }
    let (mut se, mut se_ref, mut se_bright, mut sum_ref) = (0.0, 0.0, 0.0, 0.0);
    let mut sums = [[0.0f64; 2]; 3];
    for i in 0..n {
        for c in 0..3 {
            let d = img[i][c] - r[i][c];
            let h = refs[0][i][c] - refs[1][i][c];
            se += d * d;
            se_ref += h * h / 4.0;
            if region[i] == 0 {
                se_bright += d * d;
            }
            sum_ref += r[i][c];
            sums[region[i] as usize][0] += img[i][c];
            sums[region[i] as usize][1] += r[i][c];
        }
    }
    let mean = sum_ref / (3 * n) as f64;
    Stats {
        rel_rmse: ((se - se_ref).max(0.0) / (3 * n) as f64).sqrt() / mean,
        bright_share: se_bright / se,
        region_ratio: sums.map(|s| s[0] / s[1]),
    }
}

/// Writes the image and the reference's two halves as little-endian f64
/// (pixel-major, linear sRGB) for offline analysis of where the error is.
fn dump(dir: &Path, model: &str, seed: u64, spp: u64, img: &[[f64; 3]], refs: &[Vec<[f64; 3]>; 2]) {
    std::fs::create_dir_all(dir).unwrap();
    for (name, data) in [("img", img), ("ref0", &refs[0][..]), ("ref1", &refs[1][..])] {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        std::fs::write(dir.join(format!("{model}_{seed}_{spp}_{name}.bin")), bytes).unwrap();
    }
}

#[test]
#[ignore = "a measurement of minutes in release; run it by name"]
fn plate_efficiency() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let threads: usize = env("PLATE_THREADS", "2").parse().unwrap();
    let ref_spp: u64 = env("PLATE_REF_SPP", "2048").parse().unwrap();
    let seeds: u64 = env("PLATE_SEEDS", "2").parse().unwrap();
    let spps: Vec<u64> = env("PLATE_SPP", "16,64,256")
        .split(',')
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let extra = env("PLATE_EXTRA", "").replace("\\n", "\n");
    let cache = PathBuf::from(env("PLATE_CACHE", "target/plate_efficiency"));
    println!(
        "model | seed | spp | rel RMSE | CPU s | efficiency | bright SE share | mean ratio bright/mid/dark"
    );
    for model in env("PLATE_MODELS", "ggx,ghs,two_scale,measured_psd").split(',') {
        let refs = reference(model, &root, &cache, ref_spp, threads);
        for seed in 1..=seeds {
            let scene = load(&scene_text(model, &root, seed, &extra), &root);
            let mut film = scene.film().unwrap();
            let (mut cpu, mut done) = (0.0, 0);
            for &spp in &spps {
                cpu += render(&scene, &mut film, done..spp, threads);
                done = spp;
                let img = rgb(&film);
                let s = compare(&img, &refs);
                if let Ok(dir) = std::env::var("PLATE_DUMP") {
                    dump(Path::new(&dir), model, seed, spp, &img, &refs);
                }
                println!(
                    "{model} | {seed} | {spp} | {:.4e} | {cpu:.2} | {:.3e} | {:.2} | {:.4}/{:.4}/{:.4}",
                    s.rel_rmse,
                    1.0 / (s.rel_rmse * s.rel_rmse * cpu),
                    s.bright_share,
                    s.region_ratio[0],
                    s.region_ratio[1],
                    s.region_ratio[2],
                );
            }
        }
    }
}
