//! Run time against error: how fast each model's image converges.
//!
//! Renders the paper-sample plate scenes (`scenes/samples/<sample>_<model>_<view>.toml`;
//! models GGX, Beckmann, GHS-SSA, full GHS and two-scale; views normal, 45°, grazing) at
//! a small resolution, in three configurations (`hero`: four hero wavelengths and the
//! Sobol sampler, the defaults; `single`: one λ per path; `hero-independent`: white-noise
//! samples, like the Mitsuba peer's `independent` sampler), at doubling sample counts
//! 1, 2, 4, … `EVT_MAX_SPP`. Each image is compared with a high-sample reference of the
//! same scene (defaults, `EVT_REF_SPP` spp in chunks with independent seeds), cached on
//! disk under `out/error_vs_time/cache/` and keyed by a hash of the scene text and the
//! reference settings.
//!
//! Error: RMSE over all pixels and linear-sRGB channels, divided by the reference's mean
//! (so models and renderers are comparable). Time: **CPU time of the one render thread**
//! (the machine is shared; wall time is recorded too). The film at 2n spp is the film at
//! n spp plus samples n..2n, so time(2n) is cumulative. Efficiency = 1 / (time × relMSE):
//! for a converging Monte Carlo estimator it is flat in spp and says how much error one
//! CPU second buys.
//!
//! Outputs (`out/error_vs_time/`): `error_vs_time.csv` (one row per configuration and spp),
//! `error_vs_time_<view>.png` (log-log relative RMSE against CPU time), `table.md`.
//! If `benches/peer/out/*.csv` (Mitsuba 3 timings, see `benches/peer/`) exist, their
//! series go on the same plots and the speed ratio at equal error is printed.
//!
//! Besides the plates, one material-preview scene (`scenes/preview/<EVT_PREVIEW>.toml`:
//! the preview object over a floor under the daylight sky with its sun, full GHS) is
//! measured the same way.
//!
//! Convergence checks (the run fails if one does not hold), on the relative RMSE with the
//! reference noise removed:
//!
//! * every series falls at every doubling from 1 spp to `EVT_MAX_SPP` (a rare-event tail,
//!   paths that carry many times the mean and are met once in many samples, shows as an
//!   error that stays flat or rises when such a path is first met);
//! * the least-squares slope of log error against log spp, over 4 spp and up, is
//!   −0.5 ± 0.1 for white-noise series (an unbiased estimator without fireflies converges
//!   as spp^−½; fireflies or a bias flatten it) and in [−1.6, −0.4] for Sobol series
//!   (stratification converges faster on smooth integrands, up to spp^−1.5 for scrambled
//!   nets);
//! * the preview scene's series, whose slope must lie in [−0.85, −0.35] whatever the
//!   sampler: its reference's own noise is large (relative RMSE 2.1 at 1024 spp), because
//!   rare paths that reach the sun by BSDF sampling after the object's near-mirror
//!   reflection (a caustic of the sun on the floor, which no light sample can find) carry
//!   ~10⁵ × the mean, so the corrected errors of that scene lean on the chunk-spread noise
//!   estimate and the Sobol strata do little for it. Measured (s138, 128×96, 1..64 spp):
//!   −0.456 hero, −0.505 single, −0.481 independent.
//!
//! Run: `cargo bench --bench error_vs_time` (about 30 CPU-minutes with defaults). Settings
//! via environment: `EVT_RES=128x96`, `EVT_MAX_SPP=256`, `EVT_REF_SPP=2048`,
//! `EVT_SAMPLE=s138`, `EVT_MODELS=ggx,beckmann,ghs_ssa,ghs,two_scale`,
//! `EVT_VIEWS=normal,45deg,grazing`, `EVT_PREVIEW=s138` (`none` to skip),
//! `EVT_WORKERS=2` (concurrent single-thread renders).
//! Without `--bench` (e.g. `cargo test --benches`) it runs a seconds-long smoke test
//! writing nothing.

use render::color::xyz_to_srgb;
use render::scene::desc::{SamplerKind, WavelengthMode};
use render::{Film, RenderOptions, Scene};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seed of the reference renders: different from every scene's seed, so the reference's
/// noise is independent of the images compared with it.
const REF_SEED: u64 = 0x0005_EED0_F2EF;

struct Settings {
    width: u32,
    height: u32,
    max_spp: u64,
    ref_spp: u64,
    sample: String,
    models: Vec<String>,
    views: Vec<String>,
    /// Paper sample of the preview scene measured alongside the plates, if any.
    preview: Option<String>,
    workers: usize,
    out: Option<PathBuf>,
}

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

fn parse_env<T: std::str::FromStr>(name: &str, default: &str) -> T {
    let v = env_or(name, default);
    v.parse()
        .unwrap_or_else(|_| panic!("{name} = {v:?} is not valid (default {default})"))
}

impl Settings {
    fn from_env(smoke: bool) -> Settings {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        if smoke {
            return Settings {
                width: 16,
                height: 12,
                max_spp: 2,
                ref_spp: 8,
                sample: "s138".into(),
                models: vec!["ggx".into(), "ghs_ssa".into()],
                views: vec!["45deg".into()],
                preview: Some("s138".into()),
                workers: 2,
                out: None,
            };
        }
        let res = env_or("EVT_RES", "128x96");
        let (w, h) = res
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
            .unwrap_or_else(|| panic!("EVT_RES = {res:?}: expected WIDTHxHEIGHT"));
        let list = |name: &str, default: &str| -> Vec<String> {
            env_or(name, default)
                .split(',')
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty())
                .collect()
        };
        Settings {
            width: w,
            height: h,
            max_spp: parse_env("EVT_MAX_SPP", "256"),
            ref_spp: parse_env("EVT_REF_SPP", "2048"),
            sample: env_or("EVT_SAMPLE", "s138"),
            models: list("EVT_MODELS", "ggx,beckmann,ghs_ssa,ghs,two_scale"),
            views: list("EVT_VIEWS", "normal,45deg,grazing"),
            preview: Some(env_or("EVT_PREVIEW", "s138")).filter(|p| p != "none"),
            workers: parse_env("EVT_WORKERS", "2"),
            out: Some(root.join("out/error_vs_time")),
        }
    }
}

#[path = "support/cpu_time.rs"]
mod cpu_time;

/// Seconds of CPU time consumed by the calling thread.
fn thread_cpu_s() -> f64 {
    cpu_time::cpu_ns(cpu_time::THREAD) * 1e-9
}

/// The scene text at `width`×`height` and `spp`, without image outputs.
fn shrink(text: &str, width: u32, height: u32, spp: u64) -> String {
    text.lines()
        .filter_map(|line| {
            let key = line.split('=').next().unwrap_or("").trim();
            match key {
                "resolution" => Some(format!("resolution = [{width}, {height}]")),
                "spp" => Some(format!("spp = {spp}")),
                "exr" | "png" => None,
                _ => Some(line.to_string()),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// One scene file of the set.
#[derive(Clone)]
struct SceneSpec {
    name: String,
    model: String,
    view: String,
    path: PathBuf,
    text: String,
}

impl SceneSpec {
    fn load(&self, cfg: Config, seed: Option<u64>) -> Scene {
        let mut scene = render::load_str(&self.path, &self.text)
            .unwrap_or_else(|e| panic!("scene {}: {e}", self.name));
        scene.settings.mode = cfg.0;
        scene.settings.sampler = cfg.1;
        if let Some(s) = seed {
            scene.settings.seed = s;
        }
        scene
    }
}

/// A single-thread pool; its worker's CPU clock times the renders.
struct Worker {
    pool: render::ThreadPool,
}

impl Worker {
    fn new() -> Worker {
        Worker {
            pool: render::thread_pool(Some(1)).expect("thread pool"),
        }
    }

    /// Adds samples `range` to `film`; returns (worker CPU seconds, wall seconds).
    fn render(&self, scene: &Scene, film: &mut Film, range: std::ops::Range<u64>) -> (f64, f64) {
        let opts = RenderOptions {
            threads: Some(1),
            pass_target: Duration::from_secs(3600),
            ..RenderOptions::default()
        };
        let cpu0 = self.pool.install(thread_cpu_s);
        let t0 = Instant::now();
        let out = render::render_range_in(&self.pool, scene, film, range, &opts).expect("render");
        let wall = t0.elapsed().as_secs_f64();
        let cpu = self.pool.install(thread_cpu_s) - cpu0;
        assert!(out.complete, "render stopped early");
        (cpu, wall)
    }
}

fn new_film(scene: &Scene) -> Film {
    Film::new(
        scene.camera.width,
        scene.camera.height,
        scene.fingerprint,
        scene.settings.seed,
        0.0,
    )
    .unwrap()
}

/// Linear sRGB of every pixel, in f64.
fn rgb(film: &Film) -> Vec<[f64; 3]> {
    (0..film.sums().len())
        .map(|i| xyz_to_srgb(film.xyz(i)))
        .collect()
}

/// RMSE over pixels and channels; the same divided by the reference's mean; and that
/// with the reference's own noise subtracted from the MSE.
fn rmse(img: &[[f64; 3]], reference: &Reference) -> (f64, f64, f64) {
    let (rel, mse_noise) = (&reference.rgb, reference.mse_noise);
    let reference = rel;
    let n = (img.len() * 3) as f64;
    let mse = img
        .iter()
        .zip(reference)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).powi(2)))
        .sum::<f64>()
        / n;
    let mean = reference.iter().flatten().sum::<f64>() / n;
    let corrected = (mse - mse_noise).max(0.0).sqrt() / mean;
    (mse.sqrt(), mse.sqrt() / mean, corrected)
}

/// Reference chunks: the spread of their means estimates the reference's own noise.
const REF_CHUNKS: u64 = 8;

/// A reference image and the MSE its own Monte Carlo noise adds to every comparison
/// (estimated from the spread of `REF_CHUNKS` independent chunks).
struct Reference {
    rgb: Vec<[f64; 3]>,
    mse_noise: f64,
}

/// The cached reference of `spec`, rendered if missing.
///
/// The chunks use distinct seeds (`REF_SEED + c`, samples 0..chunk each): with the
/// Sobol sampler, consecutive sample ranges of one seed are not independent (they
/// are complementary parts of one stratified sequence), so their spread would
/// overstate the reference's noise. Distinct seeds scramble independently.
fn reference(spec: &SceneSpec, s: &Settings, worker: &Worker, cache: Option<&Path>) -> Reference {
    let key = format!(
        "{}\nref_spp={} seed={REF_SEED}+chunk mode=hero chunks={REF_CHUNKS} v2",
        spec.text, s.ref_spp
    );
    let hash = render::inputs::fnv1a(key.as_bytes(), render::inputs::FNV_OFFSET);
    let file = cache.map(|c| c.join(format!("{}_{hash:016x}.ref", spec.name)));
    let pixels = spec_pixels(spec);
    if let Some(f) = &file
        && let Some(r) = load_reference(f, pixels)
    {
        return r;
    }
    let chunk = (s.ref_spp / REF_CHUNKS).max(1);
    let mut chunks = Vec::new();
    let mut cpu = 0.0;
    for c in 0..REF_CHUNKS {
        let scene = spec.load(REF_CONFIG, Some(REF_SEED + c));
        let mut film = new_film(&scene);
        cpu += worker.render(&scene, &mut film, 0..chunk).0;
        chunks.push(rgb(&film));
    }
    // Variance of the mean of K chunk means, averaged over pixels and channels.
    let k = REF_CHUNKS as f64;
    let mut acc = 0.0;
    let n = chunks[0].len();
    let mut mean_img = vec![[0.0; 3]; n];
    for (i, m_px) in mean_img.iter_mut().enumerate() {
        for ch in 0..3 {
            let m = chunks.iter().map(|c| c[i][ch]).sum::<f64>() / k;
            let var = chunks.iter().map(|c| (c[i][ch] - m).powi(2)).sum::<f64>() / (k - 1.0);
            acc += var / k;
            m_px[ch] = m;
        }
    }
    let mse_noise = acc / (3 * n) as f64;
    eprintln!(
        "reference {} ({} spp, hero): {cpu:.1} CPU s, own noise rel. RMSE {:.4}",
        spec.name,
        chunk * REF_CHUNKS,
        mse_noise.sqrt() / (mean_img.iter().flatten().sum::<f64>() / (3 * n) as f64)
    );
    let r = Reference {
        rgb: mean_img,
        mse_noise,
    };
    if let Some(f) = &file {
        save_reference(f, &r);
    }
    r
}

/// Pixel count of a scene spec (from its loaded camera).
fn spec_pixels(spec: &SceneSpec) -> usize {
    let scene = spec.load(REF_CONFIG, None);
    (scene.camera.width * scene.camera.height) as usize
}

/// Reference cache file: the noise MSE, then the RGB image, as little-endian f64.
fn save_reference(path: &Path, r: &Reference) {
    let mut bytes = Vec::with_capacity(8 * (1 + 3 * r.rgb.len()));
    bytes.extend_from_slice(&r.mse_noise.to_le_bytes());
    for v in r.rgb.iter().flatten() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    plot::write_atomic(path, &bytes).expect("save reference");
}

fn load_reference(path: &Path, pixels: usize) -> Option<Reference> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() != 8 * (1 + 3 * pixels) {
        return None;
    }
    let mut vals = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")));
    let mse_noise = vals.next()?;
    let flat: Vec<f64> = vals.collect();
    Some(Reference {
        rgb: flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        mse_noise,
    })
}

/// One measured point.
#[derive(Clone, Copy)]
struct Point {
    spp: u64,
    cpu_s: f64,
    wall_s: f64,
    rmse: f64,
    rel_rmse: f64,
    /// Relative RMSE with the reference's own noise removed.
    rel_corr: f64,
}

impl Point {
    fn efficiency(&self) -> f64 {
        1.0 / (self.cpu_s * self.rel_corr * self.rel_corr)
    }
}

/// Renders `spec` in `mode` at 1, 2, 4, … max_spp, cumulatively.
fn convergence(
    spec: &SceneSpec,
    cfg: Config,
    s: &Settings,
    worker: &Worker,
    reference: &Reference,
) -> Vec<Point> {
    let scene = spec.load(cfg, None);
    let mut film = new_film(&scene);
    let (mut cpu, mut wall) = (0.0, 0.0);
    let mut points = Vec::new();
    let mut done = 0;
    let mut next = 1;
    while next <= s.max_spp {
        let (c, w) = worker.render(&scene, &mut film, done..next);
        cpu += c;
        wall += w;
        done = next;
        let (e, rel, rel_corr) = rmse(&rgb(&film), reference);
        points.push(Point {
            spp: done,
            cpu_s: cpu,
            wall_s: wall,
            rmse: e,
            rel_rmse: rel,
            rel_corr,
        });
        next *= 2;
    }
    points
}

/// A renderer configuration measured: wavelength mode and sampler.
type Config = (WavelengthMode, SamplerKind);

/// The configurations every scene is measured in: the defaults (hero, Sobol), one
/// wavelength per path, and white-noise samples (what the Mitsuba peer uses).
const CONFIGS: [Config; 3] = [
    (WavelengthMode::Hero, SamplerKind::Sobol),
    (WavelengthMode::Single, SamplerKind::Sobol),
    (WavelengthMode::Hero, SamplerKind::Independent),
];

/// References: the defaults, with independent seeds per chunk.
const REF_CONFIG: Config = (WavelengthMode::Hero, SamplerKind::Sobol);

fn mode_name(cfg: Config) -> &'static str {
    match cfg {
        (WavelengthMode::Hero, SamplerKind::Sobol) => "hero",
        (WavelengthMode::Single, SamplerKind::Sobol) => "single",
        (WavelengthMode::Hero, SamplerKind::Independent) => "hero-independent",
        (WavelengthMode::Single, SamplerKind::Independent) => "single-independent",
    }
}

/// The scenes of `benches/peer/plate_scenes.toml` (shared with the Mitsuba peer), at the
/// resolution given there (the peer's default), as lustre scene texts.
fn peer_scenes(root: &Path, spp: u64) -> Vec<SceneSpec> {
    let path = root.join("benches/peer/plate_scenes.toml");
    let Ok(text) = std::fs::read_to_string(&path) else {
        eprintln!("no {}: peer scenes skipped", path.display());
        return Vec::new();
    };
    let table: toml::Table =
        toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let Some(toml::Value::Array(scenes)) = table.get("scene") else {
        panic!("{}: expected [[scene]] entries", path.display());
    };
    let mut out = Vec::new();
    for sc in scenes {
        let Some(mut t) = sc.as_table().cloned() else {
            continue;
        };
        let name = t
            .remove("name")
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_else(|| panic!("{}: a [[scene]] has no name", path.display()));
        t.remove("description");
        let mut film = toml::Table::new();
        film.insert("spp".into(), toml::Value::Integer(spp as i64));
        film.insert("seed".into(), toml::Value::Integer(1));
        t.insert("film".into(), toml::Value::Table(film));
        let model = t
            .get("materials")
            .and_then(|m| m.get("plate"))
            .and_then(|p| p.get("model"))
            .and_then(|v| v.as_str())
            .unwrap_or("?")
            .to_string();
        let view = name.rsplit('_').next().unwrap_or("").to_string();
        out.push(SceneSpec {
            name,
            model: format!("peer {model}"),
            view: format!("peer_{view}"),
            path: path.clone(),
            text: t.to_string(),
        });
    }
    out
}

/// Runs `jobs` on `workers` threads, each with its own single-thread render pool.
fn run_parallel<J: Sync, R: Send>(
    jobs: &[J],
    workers: usize,
    f: impl Fn(&J, &Worker) -> R + Sync,
) -> Vec<R> {
    let next = Mutex::new(0usize);
    let results: Mutex<Vec<Option<R>>> = Mutex::new((0..jobs.len()).map(|_| None).collect());
    std::thread::scope(|sc| {
        for _ in 0..workers.max(1) {
            sc.spawn(|| {
                let worker = Worker::new();
                loop {
                    let i = {
                        let mut n = next.lock().expect("job counter");
                        let i = *n;
                        *n += 1;
                        i
                    };
                    if i >= jobs.len() {
                        break;
                    }
                    let r = f(&jobs[i], &worker);
                    results.lock().expect("results")[i] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .expect("results")
        .into_iter()
        .map(|r| r.expect("job finished"))
        .collect()
}

/// A peer renderer's convergence series read from `benches/peer/out/*.csv`.
struct PeerSeries {
    label: String,
    scene: String,
    points: Vec<(f64, f64)>,
}

/// Reads every `benches/peer/out/*.csv` with columns `scene`, `variant`, `spp`, `time_s`
/// and `rel_rmse` (extra columns ignored; with `rmse` and `rmse_corrected` the relative
/// error with the peer reference's noise removed is used); one series per (scene, variant).
fn peer_series(root: &Path) -> Vec<PeerSeries> {
    let dir = root.join("benches/peer/out");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    let mut by_key: BTreeMap<(String, String), Vec<(f64, f64)>> = BTreeMap::new();
    for f in files {
        let Ok(text) = std::fs::read_to_string(&f) else {
            continue;
        };
        let mut lines = text.lines();
        let Some(header) = lines.next() else { continue };
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let idx = |name: &str| cols.iter().position(|c| *c == name);
        let (Some(is), Some(iv), Some(it), Some(ie)) =
            (idx("scene"), idx("variant"), idx("time_s"), idx("rel_rmse"))
        else {
            eprintln!(
                "{}: skipped (needs columns scene, variant, time_s, rel_rmse)",
                f.display()
            );
            continue;
        };
        for line in lines {
            let v: Vec<&str> = line.split(',').map(str::trim).collect();
            let get = |i: usize| v.get(i).copied().unwrap_or("");
            let corrected = match (idx("rmse"), idx("rmse_corrected")) {
                (Some(ir), Some(ic)) => get(ic)
                    .parse::<f64>()
                    .ok()
                    .zip(get(ir).parse::<f64>().ok())
                    .zip(get(ie).parse::<f64>().ok())
                    .and_then(|((c, r), rel)| (r > 0.0).then(|| c * rel / r)),
                _ => None,
            };
            if let (Ok(t), Ok(e)) = (get(it).parse::<f64>(), get(ie).parse::<f64>()) {
                let e = corrected.unwrap_or(e);
                by_key
                    .entry((get(is).to_string(), get(iv).to_string()))
                    .or_default()
                    .push((t, e));
            }
        }
    }
    by_key
        .into_iter()
        .map(|((scene, variant), mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            PeerSeries {
                label: format!("Mitsuba {variant}"),
                scene,
                points,
            }
        })
        .collect()
}

/// Time to reach relative RMSE `target`, interpolating log-log between measured points
/// (None outside the measured range).
fn time_at_error(points: &[(f64, f64)], target: f64) -> Option<f64> {
    points.windows(2).find_map(|w| {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        let (lo, hi) = (e0.min(e1), e0.max(e1));
        if !(lo..=hi).contains(&target) || e0 == e1 {
            return None;
        }
        let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
        Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
    })
}

fn main() {
    let smoke = !std::env::args().any(|a| a == "--bench");
    let s = Settings::from_env(smoke);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cache = s.out.as_ref().map(|o| o.join("cache"));
    if let Some(c) = &cache {
        std::fs::create_dir_all(c).expect("create out/error_vs_time/cache");
    }

    let mut specs = Vec::new();
    for model in &s.models {
        for view in &s.views {
            let name = format!("{}_{model}_{view}", s.sample);
            let path = root.join(format!("scenes/samples/{name}.toml"));
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            specs.push(SceneSpec {
                name,
                model: model.clone(),
                view: view.clone(),
                path,
                text: shrink(&text, s.width, s.height, s.max_spp),
            });
        }
    }
    if let Some(p) = &s.preview {
        let path = root.join(format!("scenes/preview/{p}.toml"));
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        specs.push(SceneSpec {
            name: format!("preview_{p}"),
            model: "preview ghs".into(),
            view: "preview".into(),
            path,
            text: shrink(&text, s.width, s.height, s.max_spp),
        });
    }
    if !smoke && env_or("EVT_PEER", "1") == "1" {
        specs.extend(peer_scenes(root, s.max_spp));
    }
    eprintln!(
        "error_vs_time: {} scenes at {}×{}, 1..{} spp in {} configurations, references {} spp; {} worker(s) of 1 thread",
        specs.len(),
        s.width,
        s.height,
        s.max_spp,
        CONFIGS.len(),
        s.ref_spp,
        s.workers
    );

    let refs = run_parallel(&specs, s.workers, |spec, w| {
        reference(spec, &s, w, cache.as_deref())
    });
    let jobs: Vec<(usize, Config)> = (0..specs.len())
        .flat_map(|i| CONFIGS.map(|c| (i, c)))
        .collect();
    let results = run_parallel(&jobs, s.workers, |&(i, mode), w| {
        let p = convergence(&specs[i], mode, &s, w, &refs[i]);
        eprintln!(
            "{} {}: {} spp in {:.2} CPU s, rel. RMSE (ref. noise removed) {:.4}",
            specs[i].name,
            mode_name(mode),
            s.max_spp,
            p.last().map_or(0.0, |p| p.cpu_s),
            p.last().map_or(0.0, |p| p.rel_corr)
        );
        p
    });
    if smoke {
        for p in results.iter().flatten() {
            assert!(p.rel_rmse.is_finite() && p.cpu_s >= 0.0);
        }
        eprintln!("error_vs_time: smoke run passed (run with `cargo bench` for measurements)");
        return;
    }
    let out = s.out.as_ref().expect("output directory");

    // Convergence slopes: least squares of ln(rel. RMSE, reference noise removed) on ln spp.
    let mut slopes = String::from(
        "\nConvergence slope d ln(rel. RMSE) / d ln spp, over 4 spp and up (−0.5 for spp^−½):\n\n\
         | scene | mode | slope |\n|---|---|---|\n",
    );
    let mut slope_failures = Vec::new();
    for (&(i, mode), points) in jobs.iter().zip(&results) {
        let Some(slope) = convergence_slope(points) else {
            continue;
        };
        let _ = writeln!(
            slopes,
            "| {} | {} | {slope:.3} |",
            specs[i].name,
            mode_name(mode)
        );
        let (lo, hi) = slope_bounds(specs[i].view == "preview", mode.1);
        if !(lo..=hi).contains(&slope) {
            slope_failures.push(format!(
                "{} {}: slope {slope:.3} outside [{lo}, {hi}]",
                specs[i].name,
                mode_name(mode)
            ));
        }
    }
    for (&(i, mode), points) in jobs.iter().zip(&results) {
        for pair in points.windows(2) {
            // An error lost in the reference's noise (corrected to 0) says nothing.
            if pair[1].rel_corr > 0.0 && pair[1].rel_corr >= pair[0].rel_corr {
                slope_failures.push(format!(
                    "{} {}: error does not fall from {} to {} spp ({:.4e} -> {:.4e})",
                    specs[i].name,
                    mode_name(mode),
                    pair[0].spp,
                    pair[1].spp,
                    pair[0].rel_corr,
                    pair[1].rel_corr
                ));
            }
        }
    }
    eprint!("{slopes}");

    // CSV, one row per (scene, mode, spp).
    let mut csv = String::from(
        "scene,model,view,mode,spp,cpu_s,wall_s,rmse,rel_rmse,rel_rmse_corrected,efficiency\n",
    );
    for (&(i, mode), points) in jobs.iter().zip(&results) {
        for p in points {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{:.6},{:.6},{:.6e},{:.6e},{:.6e},{:.6e}",
                specs[i].name,
                specs[i].model,
                specs[i].view,
                mode_name(mode),
                p.spp,
                p.cpu_s,
                p.wall_s,
                p.rmse,
                p.rel_rmse,
                p.rel_corr,
                p.efficiency()
            );
        }
    }
    plot::write_atomic(&out.join("error_vs_time.csv"), csv.as_bytes()).expect("write CSV");

    // Summary table: per configuration, the top spp and the efficiency there.
    let mut table = format!(
        "Resolution {}×{}, reference {} spp (hero, independent seed); CPU seconds of one thread.\n\n\
         Rel. RMSE = RMSE / mean of the reference; corrected = with the reference's own noise \
         (from {REF_CHUNKS} chunks) subtracted from the MSE; efficiency uses the corrected value.\n\n\
         | scene | mode | spp | CPU s | wall s | rel. RMSE | corrected | efficiency 1/(s·relMSE) |\n|---|---|---|---|---|---|---|---|\n",
        s.width, s.height, s.ref_spp
    );
    for (&(i, mode), points) in jobs.iter().zip(&results) {
        for p in points
            .iter()
            .filter(|p| p.spp == 1 || p.spp == s.max_spp || p.spp * 4 == s.max_spp)
        {
            let _ = writeln!(
                table,
                "| {} | {} | {} | {:.3} | {:.3} | {:.4} | {:.4} | {:.3e} |",
                specs[i].name,
                mode_name(mode),
                p.spp,
                p.cpu_s,
                p.wall_s,
                p.rel_rmse,
                p.rel_corr,
                p.efficiency()
            );
        }
    }

    // Peer comparison at equal error.
    let peers = peer_series(root);
    let mut peer_text = String::new();
    for peer in &peers {
        let Some(k) = specs.iter().position(|sp| sp.name == peer.scene) else {
            let _ = writeln!(
                peer_text,
                "peer series {} for scene {}: no such scene here",
                peer.label, peer.scene
            );
            continue;
        };
        for (&(i, mode), points) in jobs.iter().zip(&results) {
            if i != k {
                continue;
            }
            let ours: Vec<(f64, f64)> = points.iter().map(|p| (p.cpu_s, p.rel_corr)).collect();
            for &(t_peer, e) in &peer.points {
                if let Some(t_ours) = time_at_error(&ours, e) {
                    let _ = writeln!(
                        peer_text,
                        "{} {} vs {}: rel. RMSE {e:.4}: lustre {t_ours:.3} s, peer {t_peer:.3} s, speed ratio {:.2}×",
                        peer.scene,
                        mode_name(mode),
                        peer.label,
                        t_peer / t_ours
                    );
                }
            }
        }
    }
    if peers.is_empty() {
        peer_text.push_str("no peer CSVs in benches/peer/out/: Mitsuba comparison skipped\n");
    }
    table.push('\n');
    table.push_str(&peer_text);
    table.push_str(&slopes);
    plot::write_atomic(&out.join("table.md"), table.as_bytes()).expect("write table");
    println!("{table}");

    // One log-log plot per view.
    let mut models: Vec<&String> = Vec::new();
    let mut views: Vec<&String> = Vec::new();
    for sp in &specs {
        if !models.contains(&&sp.model) {
            models.push(&sp.model);
        }
        if !views.contains(&&sp.view) {
            views.push(&sp.view);
        }
    }
    for view in views {
        let mut p = plot::Plot::new(format!("{view} view: error against CPU time"))
            .x_axis(plot::Axis::log("CPU time of one thread [s]"))
            .y_axis(plot::Axis::log("relative RMSE (reference noise removed)"))
            .legend(plot::Legend::Outside);
        for (&(i, mode), points) in jobs.iter().zip(&results) {
            if &specs[i].view != view {
                continue;
            }
            let m = models
                .iter()
                .position(|m| **m == specs[i].model)
                .unwrap_or(0);
            let xs: Vec<f64> = points.iter().map(|p| p.cpu_s).collect();
            let ys: Vec<f64> = points.iter().map(|p| p.rel_corr).collect();
            let (style, marker) = match mode {
                (WavelengthMode::Single, _) => (plot::LineStyle::Dashed, plot::Marker::Square),
                (WavelengthMode::Hero, SamplerKind::Sobol) => {
                    (plot::LineStyle::Solid, plot::Marker::Circle)
                }
                (WavelengthMode::Hero, SamplerKind::Independent) => {
                    (plot::LineStyle::Dotted, plot::Marker::Triangle)
                }
            };
            p = p.series(
                plot::Series::line(format!("{} {}", specs[i].model, mode_name(mode)), &xs, &ys)
                    .color(plot::Rgb::palette(m))
                    .style(style)
                    .marker(marker),
            );
        }
        for (j, peer) in peers.iter().enumerate() {
            if !specs
                .iter()
                .any(|sp| &sp.view == view && sp.name == peer.scene)
            {
                continue;
            }
            let xs: Vec<f64> = peer.points.iter().map(|p| p.0).collect();
            let ys: Vec<f64> = peer.points.iter().map(|p| p.1).collect();
            p = p.series(
                plot::Series::line(format!("{} ({})", peer.label, peer.scene), &xs, &ys)
                    .color(plot::Rgb::palette(models.len() + j))
                    .style(plot::LineStyle::Dotted)
                    .marker(plot::Marker::Triangle),
            );
        }
        let file = out.join(format!("error_vs_time_{view}.png"));
        p.save_png(&file, 1100, 650)
            .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        eprintln!("wrote {}", file.display());
    }
    assert!(
        slope_failures.is_empty(),
        "not converging as it should (see the module documentation):\n{}",
        slope_failures.join("\n")
    );
}

/// Accepted convergence slopes: spp^−½ ± 0.1 for white noise, steeper (up to spp^−1.5)
/// for Sobol points; the preview scene's rare caustic paths leave its Sobol series near
/// spp^−½ and its reference noisy, hence one wider band for all its series.
fn slope_bounds(preview: bool, sampler: SamplerKind) -> (f64, f64) {
    match (preview, sampler) {
        (true, _) => (-0.85, -0.35),
        (false, SamplerKind::Independent) => (-0.6, -0.4),
        (false, SamplerKind::Sobol) => (-1.6, -0.4),
    }
}

/// Least-squares slope of ln(rel. RMSE with the reference noise removed) against ln spp
/// over the points at 4 spp and up (fewer samples are not yet in the asymptotic regime).
fn convergence_slope(points: &[Point]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.spp >= 4 && p.rel_corr > 0.0)
        .map(|p| ((p.spp as f64).ln(), p.rel_corr.ln()))
        .collect();
    if xy.len() < 3 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx).powi(2)).sum();
    Some(sxy / sxx)
}
