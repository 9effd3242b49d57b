//! The `splinerod` command line: `splinerod run SCENE.toml [--json OUT.json]`.
//! Errors print one line naming the field or file and exit with code 2.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "splinerod",
    version,
    about = "Adaptive mechanical B-spline rods"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Runs a scene to its end, prints a summary and optionally writes the JSON result.
    Run {
        /// The scene file (TOML; see scenes/README.md).
        scene: PathBuf,
        /// Where to write the JSON result.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    match execute(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn execute(cli: Cli) -> Result<(), splinerod::Error> {
    match cli.command {
        Command::Run { scene, json } => {
            let loaded = splinerod::Scene::load(&scene)?;
            let result = splinerod::run(&loaded)?;
            print!("{}", result.summary());
            if let Some(path) = json {
                let text = serde_json::to_string_pretty(&result)
                    .map_err(|e| splinerod::Error::Scene(e.to_string()))?;
                std::fs::write(&path, text).map_err(|source| splinerod::Error::Io {
                    path: path.display().to_string(),
                    source,
                })?;
                println!("wrote {}", path.display());
            }
            Ok(())
        }
    }
}
