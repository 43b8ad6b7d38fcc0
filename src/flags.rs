//! Checks of command-line values shared by the commands, each naming its flag.

use anyhow::bail;

/// Most samples per pixel of a figure cell (`compare`, `preview`): a million
/// samples of each cell already take days.
pub const MAX_FIGURE_SPP: u64 = 1 << 20;

/// The worker-thread count to use: `--threads 0` is refused, a count above
/// [`render::max_threads`] is capped with a note (unless `quiet`).
pub fn thread_count(requested: Option<usize>, quiet: bool) -> anyhow::Result<Option<usize>> {
    match requested {
        Some(0) => bail!("--threads must be ≥ 1"),
        Some(n) if n > render::max_threads() => {
            let cap = render::max_threads();
            if !quiet {
                eprintln!(
                    "note: --threads {n} capped at {cap} (4 per core): more threads than that \
                     only add start-up and scheduling cost"
                );
            }
            Ok(Some(cap))
        }
        other => Ok(other),
    }
}

/// `--spp` within 1..=`max`.
pub fn check_spp(spp: u64, max: u64) -> anyhow::Result<()> {
    if spp == 0 || spp > max {
        bail!("--spp {spp}: expected 1..={max} samples per pixel");
    }
    Ok(())
}

/// `--exposure` finite and within the film's ±[`render::film::MAX_EXPOSURE_STOPS`].
pub fn check_exposure(stops: f64) -> anyhow::Result<()> {
    let m = render::film::MAX_EXPOSURE_STOPS;
    if !(stops.is_finite() && stops.abs() <= m) {
        bail!("--exposure {stops}: expected stops within ±{m}");
    }
    Ok(())
}
