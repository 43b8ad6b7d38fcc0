//! `lustre`: render metal surfaces from their measured micro-geometry.
//!
//! Argument parsing and error reporting only; each subcommand lives in its
//! own module and calls into the workspace crates.

mod cmd_brdf;
mod cmd_brdf_plot;
mod cmd_compare;
mod cmd_fit;
mod cmd_judge;
mod cmd_preview;
mod cmd_render;
mod cmd_scenes;
mod flags;
mod models;
mod outputs;
mod progress;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "lustre",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Scene file to render (default: scenes/default.toml).
    #[command(flatten)]
    render: cmd_render::RenderArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file (the default when no subcommand is given).
    Render(cmd_render::RenderArgs),
    /// Combine partial films rendered with `--spp-range` into one image.
    Merge(cmd_render::MergeArgs),
    /// Query, plot and compare the BRDF models.
    #[command(subcommand)]
    Brdf(cmd_brdf::BrdfCommand),
    /// Turn a measured surface scan into model parameters and a material file.
    Fit(cmd_fit::FitArgs),
    /// Render one surface with every model at three viewing angles into a labelled image grid.
    Compare(cmd_compare::CompareArgs),
    /// Write the bundled paper-sample scenes (scenes/samples, scenes/psd) from `brdf::paper`.
    Scenes(cmd_scenes::ScenesArgs),
    /// Render a material on the preview object under a daylight sky (or studio lights).
    Preview(cmd_preview::PreviewArgs),
    /// Judge every model against the scan's own wave-optical BRDF (and a measured one).
    Judge(cmd_judge::JudgeArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    // No output of this run may replace a file it read, under any name.
    safe_io::protect_inputs();
    let result = match cli.command {
        None => cmd_render::render(cli.render),
        Some(Command::Render(args)) => cmd_render::render(args),
        Some(Command::Merge(args)) => cmd_render::merge(args),
        Some(Command::Brdf(cmd)) => cmd_brdf::run(cmd),
        Some(Command::Fit(args)) => cmd_fit::run(args),
        Some(Command::Compare(args)) => cmd_compare::run(args),
        Some(Command::Scenes(args)) => cmd_scenes::run(args),
        Some(Command::Preview(args)) => cmd_preview::run(args),
        Some(Command::Judge(args)) => cmd_judge::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", report(&err));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", leaving out a cause whose text the message
/// before it already holds (the library errors quote their I/O cause in their own text).
fn report(err: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if !out.contains(&text) {
            if !out.is_empty() {
                out.push_str(": ");
            }
            out.push_str(&text);
        }
    }
    out
}
