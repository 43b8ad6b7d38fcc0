//! The render loop: progressive passes over image tiles on a rayon pool.
//!
//! A pass renders a contiguous range of sample indices for every pixel. Only
//! complete passes are added to the film, so the film always holds the same
//! samples for every pixel; an interruption (Ctrl-C, time limit) discards the
//! pass in flight, costing at most one pass (sized to about two seconds).

use crate::error::RenderError;
use crate::film::{BandLayout, Dropped, Film, TileSums};
use crate::integrator::{sample_pixel_bands, sample_pixel_checked};
use crate::scene::Scene;
pub use rayon::ThreadPool;
use rayon::prelude::*;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const TILE: u32 = 16;

/// How to run a render.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Worker threads (default: all cores; at most [`max_threads`]).
    pub threads: Option<usize>,
    /// Stop after this long, keeping the completed passes.
    pub time_limit: Option<Duration>,
    /// Set from outside (Ctrl-C) to stop after the current tile.
    pub stop: Arc<AtomicBool>,
    /// Told how the render advances (the caller draws a bar, logs, or ignores it).
    pub progress: Option<Progress>,
    /// Where to write the film after passes, and how often.
    pub checkpoint: Option<(PathBuf, Duration)>,
    /// Target duration of one pass.
    pub pass_target: Duration,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            time_limit: None,
            stop: Arc::new(AtomicBool::new(false)),
            progress: None,
            checkpoint: None,
            pass_target: Duration::from_secs(2),
        }
    }
}

/// What the render loop reports while it runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressEvent {
    /// The render starts: `total` camera samples (pixels × samples per pixel) to go.
    Start {
        /// Camera samples this call will render if not stopped.
        total: u64,
    },
    /// A tile of a pass finished: `samples` more camera samples (from any thread).
    Advance {
        /// Camera samples just finished.
        samples: u64,
    },
    /// A pass was added to the film, which now holds `spp` samples per pixel.
    Pass {
        /// Samples per pixel in the film.
        spp: u64,
    },
    /// The render loop ended (complete or stopped).
    Finish,
}

/// A progress callback, called from the render threads (hence `Sync`).
#[derive(Clone)]
pub struct Progress(pub Arc<dyn Fn(ProgressEvent) + Send + Sync>);

impl Progress {
    /// Wraps a callback.
    pub fn new(f: impl Fn(ProgressEvent) + Send + Sync + 'static) -> Progress {
        Progress(Arc::new(f))
    }

    fn report(this: &Option<Progress>, e: ProgressEvent) {
        if let Some(p) = this {
            (p.0)(e);
        }
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress(callback)")
    }
}

/// What a render achieved.
#[derive(Clone, Debug)]
pub struct RenderOutcome {
    /// Sample indices added to the film by this call.
    pub rendered: Range<u64>,
    /// Whether the whole requested range was rendered.
    pub complete: bool,
    /// Wall time spent.
    pub elapsed: Duration,
    /// Camera samples (pixel × spp) per second.
    pub samples_per_second: f64,
    /// Samples of this call left out of the film (non-finite or negative
    /// estimates); also added to the film's own count.
    pub dropped: Dropped,
}

/// A pixel rectangle.
#[derive(Clone, Copy, Debug)]
struct Tile {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut v = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            v.push(Tile {
                x0,
                y0,
                x1: (x0 + TILE).min(width),
                y1: (y0 + TILE).min(height),
            });
        }
    }
    v
}

/// Renders one tile for samples `range`; `None` if stopped.
fn render_tile(
    scene: &Scene,
    tile: Tile,
    range: &Range<u64>,
    stop: &AtomicBool,
) -> Option<TileSums> {
    // Decided once per tile: a render without bands runs the loop below
    // with no per-sample work for them.
    if let Ok(layout) = BandLayout::new(scene.settings.spectral_bands) {
        return render_tile_bands(scene, tile, range, stop, &layout);
    }
    let mut sums = TileSums::new(tile.x0, tile.y0, tile.x1, tile.y1);
    for y in tile.y0..tile.y1 {
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        for x in tile.x0..tile.x1 {
            let samples = range
                .clone()
                .map(|s| (s, sample_pixel_checked(scene, x, y, s)));
            sums.add_pixel(x, y, samples);
        }
    }
    Some(sums)
}

/// [`render_tile`] for a film with spectral bands.
fn render_tile_bands(
    scene: &Scene,
    tile: Tile,
    range: &Range<u64>,
    stop: &AtomicBool,
    layout: &BandLayout,
) -> Option<TileSums> {
    let mut sums = TileSums::with_bands(tile.x0, tile.y0, tile.x1, tile.y1, layout.len());
    for y in tile.y0..tile.y1 {
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        for x in tile.x0..tile.x1 {
            sums.add_pixel_bands(x, y, range.clone(), |s, bands| {
                sample_pixel_bands(scene, x, y, s, layout, bands)
            });
        }
    }
    Some(sums)
}

/// Most worker threads a render starts: four per core. More only add
/// start-up and scheduling cost (ten thousand threads make a 0.05 s render
/// take a minute).
pub fn max_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get()) * 4
}

/// Creates the worker pool; `threads` above [`max_threads`] is capped.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, RenderError> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err(RenderError::Options("--threads must be ≥ 1".into()));
        }
        b = b.num_threads(n.min(max_threads()));
    }
    b.build()
        .map_err(|e| RenderError::Options(format!("cannot start worker threads: {e}")))
}

/// Adds samples `range` of every pixel to `film`, in passes.
pub fn render_range(
    scene: &Scene,
    film: &mut Film,
    range: Range<u64>,
    opts: &RenderOptions,
) -> Result<RenderOutcome, RenderError> {
    let pool = thread_pool(opts.threads)?;
    render_range_in(&pool, scene, film, range, opts)
}

/// [`render_range`] on an existing pool.
pub fn render_range_in(
    pool: &rayon::ThreadPool,
    scene: &Scene,
    film: &mut Film,
    range: Range<u64>,
    opts: &RenderOptions,
) -> Result<RenderOutcome, RenderError> {
    let start = Instant::now();
    let (w, h) = (scene.camera.width, scene.camera.height);
    if (film.width(), film.height()) != (w, h) {
        return Err(RenderError::Options(format!(
            "film is {}×{} but the scene renders {w}×{h}",
            film.width(),
            film.height()
        )));
    }
    let tiles = tiles(w, h);
    let pixels = w as u64 * h as u64;
    Progress::report(
        &opts.progress,
        ProgressEvent::Start {
            total: pixels.saturating_mul(range.end - range.start),
        },
    );

    let mut next = range.start;
    let mut pass_spp = 1u64;
    let mut last_checkpoint = Instant::now();
    // A limit too far away to represent is no limit.
    let deadline = opts.time_limit.and_then(|t| start.checked_add(t));
    let stop = opts.stop.clone();
    // A timer thread turns the deadline into the same stop flag Ctrl-C uses.
    let local_stop = Arc::new(AtomicBool::new(false));
    let watcher = {
        let local = local_stop.clone();
        let ext = stop.clone();
        let done = Arc::new(AtomicBool::new(false));
        let d2 = done.clone();
        let handle = std::thread::spawn(move || {
            while !d2.load(Ordering::Relaxed) {
                if ext.load(Ordering::Relaxed) || deadline.is_some_and(|d| Instant::now() >= d) {
                    local.store(true, Ordering::Relaxed);
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        });
        (done, handle)
    };

    let mut result = Ok(());
    let mut dropped = Dropped::default();
    while next < range.end && !local_stop.load(Ordering::Relaxed) {
        let pass = next..next.saturating_add(pass_spp).min(range.end);
        let t0 = Instant::now();
        let results: Vec<Option<TileSums>> = pool.install(|| {
            tiles
                .par_iter()
                .map(|&t| {
                    let r = render_tile(scene, t, &pass, &local_stop);
                    Progress::report(
                        &opts.progress,
                        ProgressEvent::Advance {
                            samples: ((t.x1 - t.x0) * (t.y1 - t.y0)) as u64
                                * (pass.end - pass.start),
                        },
                    );
                    r
                })
                .collect()
        });
        let Some(done) = results.into_iter().collect::<Option<Vec<TileSums>>>() else {
            break;
        };
        match film.add_pass(pass.clone(), &done) {
            Ok(d) => dropped.add(&d),
            Err(m) => {
                result = Err(RenderError::Options(m));
                break;
            }
        }
        next = pass.end;
        Progress::report(&opts.progress, ProgressEvent::Pass { spp: film.spp() });
        if let Some((path, every)) = &opts.checkpoint
            && last_checkpoint.elapsed() >= *every
            && next < range.end
        {
            film.save(path)?;
            last_checkpoint = Instant::now();
        }
        // Size the next pass to about `pass_target`, growing at most 4× at a time.
        let per_spp = t0.elapsed().as_secs_f64() / (pass.end - pass.start) as f64;
        let mut target = opts.pass_target.as_secs_f64();
        if let Some(d) = deadline {
            target = target.min(d.saturating_duration_since(Instant::now()).as_secs_f64());
        }
        let want = (target / per_spp.max(1e-9)).floor() as u64;
        pass_spp = want.clamp(1, pass_spp.saturating_mul(4));
    }
    watcher.0.store(true, Ordering::Relaxed);
    let _ = watcher.1.join();
    Progress::report(&opts.progress, ProgressEvent::Finish);
    result?;
    let elapsed = start.elapsed();
    let done = next - range.start;
    Ok(RenderOutcome {
        rendered: range.start..next,
        complete: next == range.end,
        elapsed,
        samples_per_second: done as f64 * pixels as f64 / elapsed.as_secs_f64().max(1e-12),
        dropped,
    })
}
