//! `lustre [render] scene.toml` and `lustre merge`.

use std::path::PathBuf;

/// Arguments of the render command.
#[derive(clap::Args, Default)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: Option<PathBuf>,
}

/// Arguments of the merge command.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Partial films to merge.
    pub inputs: Vec<PathBuf>,
}

pub fn render(_args: RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("the renderer is not built yet")
}

pub fn merge(_args: MergeArgs) -> anyhow::Result<()> {
    anyhow::bail!("merge is not built yet")
}
