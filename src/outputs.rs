//! The commands' up-front output check: a file the writer would refuse at the end of a run
//! (an input of this run under any name, a directory, a socket) is refused before the work.

use anyhow::Context;
use std::path::PathBuf;

/// Checks every `(path, what it is)` a command is about to write; inputs must be recorded
/// first (`safe_io::read_input` does it, or `safe_io::register_input`).
pub fn check(outputs: &[(PathBuf, &str)]) -> anyhow::Result<()> {
    for (out, what) in outputs {
        safe_io::check_output(out).with_context(|| format!("the {what} {}", out.display()))?;
    }
    Ok(())
}
