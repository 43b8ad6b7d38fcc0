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
    /// Write the bundled scenes (samples/, psd/, preview/, assets/) from the code that defines them.
    Scenes(cmd_scenes::ScenesArgs),
    /// Render a material on the preview object under a daylight sky (or studio lights).
    Preview(cmd_preview::PreviewArgs),
    /// Judge every model against the scan's own wave-optical BRDF (and a measured one).
    Judge(cmd_judge::JudgeArgs),
}

fn main() -> std::process::ExitCode {
    if let Some(message) = misspelt_subcommand(std::env::args_os().nth(1)) {
        eprintln!("error: {message}");
        return std::process::ExitCode::from(2);
    }
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

/// The subcommands, for the suggestion below.
const SUBCOMMANDS: [&str; 9] = [
    "render", "merge", "brdf", "fit", "compare", "scenes", "preview", "judge", "help",
];

/// A first argument that is no file and not a subcommand but close to one (`rendr`,
/// `previw`): it would otherwise be taken for a scene path and fail as a missing file.
fn misspelt_subcommand(first: Option<std::ffi::OsString>) -> Option<String> {
    let word = first?.into_string().ok()?;
    if word.starts_with('-')
        || word.contains(['/', '.', '\\'])
        || SUBCOMMANDS.contains(&word.as_str())
        || std::path::Path::new(&word).exists()
    {
        return None;
    }
    let lower = word.to_lowercase();
    let (best, distance) = SUBCOMMANDS
        .iter()
        .map(|c| (*c, edit_distance(&lower, c)))
        .min_by_key(|(_, d)| *d)?;
    let close = distance <= 2 || (lower.len() >= 3 && best.starts_with(&lower));
    close.then(|| {
        format!(
            "unknown subcommand `{word}`; did you mean `{best}`? (a scene file is rendered by \
             `lustre render FILE`; `lustre --help` lists the subcommands)"
        )
    })
}

/// Levenshtein distance between two short words.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let here = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb))
                .min(row[j] + 1)
                .min(here + 1);
            prev = here;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ask(w: &str) -> Option<String> {
        misspelt_subcommand(Some(w.into()))
    }

    #[test]
    fn misspelt_subcommands_are_named() {
        for (typo, meant) in [
            ("rendr", "render"),
            ("previw", "preview"),
            ("jugde", "judge"),
            ("Render", "render"),
            ("scene", "scenes"),
            ("comp", "compare"),
        ] {
            let m = ask(typo).unwrap_or_default();
            assert!(
                m.contains(&format!("did you mean `{meant}`")),
                "{typo}: {m}"
            );
        }
        for fine in [
            "render",
            "fit",
            "--spp",
            "scene.toml",
            "a/b",
            "zzzzzzzz",
            "x",
        ] {
            assert_eq!(ask(fine), None, "{fine}");
        }
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }
}
