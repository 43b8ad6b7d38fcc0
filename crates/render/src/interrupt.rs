//! Ctrl-C as a flag the render loop polls.

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

/// The process-wide Ctrl-C flag, installing the handler on first use.
/// A second Ctrl-C exits at once.
pub fn ctrlc_flag() -> Result<Arc<AtomicBool>, String> {
    static FLAG: OnceLock<Result<Arc<AtomicBool>, String>> = OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        let f = flag.clone();
        ctrlc::set_handler(move || {
            if f.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
            eprintln!("\ninterrupted: finishing the image so far (Ctrl-C again to abort)");
        })
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
        Ok(flag)
    })
    .clone()
}
