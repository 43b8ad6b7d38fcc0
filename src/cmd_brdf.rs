//! `lustre brdf …`: query and plot the BRDF models.

/// BRDF subcommands.
#[derive(clap::Subcommand)]
pub enum BrdfCommand {
    /// Read JSON-lines queries on stdin, write one JSON result per line.
    Eval,
}

pub fn run(_cmd: BrdfCommand) -> anyhow::Result<()> {
    anyhow::bail!("brdf eval is not built yet")
}
