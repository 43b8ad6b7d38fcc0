//! The terminal progress bar of `render` and `preview`: the render loop only
//! reports [`ProgressEvent`]s; drawing them is the command line's job.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use render::{Progress, ProgressEvent};

/// A bar on stderr when it is a terminal and `show` is set; `None` otherwise
/// (no callback: the render loop then reports nothing).
pub fn bar(show: bool) -> Option<Progress> {
    if !show || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return None;
    }
    let b = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr_with_hz(4));
    b.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {percent:>3}% {msg} ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    Some(Progress::new(move |e| match e {
        ProgressEvent::Start { total } => {
            b.set_length(total);
            b.set_position(0);
        }
        ProgressEvent::Advance { samples } => b.inc(samples),
        ProgressEvent::Pass { spp } => b.set_message(format!("{spp} spp")),
        ProgressEvent::Finish => b.finish_and_clear(),
    }))
}
