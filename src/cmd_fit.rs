//! `lustre fit …`: from a measured scan to a material file.

use std::path::PathBuf;

/// Arguments of the fit command.
#[derive(clap::Args)]
pub struct FitArgs {
    /// Surface scan (X3P, BCR/SDF, NanoScope .di, Gwyddion, CSV, XYZ).
    pub scan: PathBuf,
}

pub fn run(_args: FitArgs) -> anyhow::Result<()> {
    anyhow::bail!("fit is not built yet")
}
