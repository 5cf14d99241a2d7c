//! `occ check`: print every diagnostic of each file with miette; exit 0 when clean, 1 on errors.

use crate::frontend::{self, Options};
use std::process::ExitCode;

/// Flags of `occ check`.
#[derive(clap::Args)]
pub struct Args {
    /// Input files.
    #[arg(required = true)]
    pub files: Vec<std::path::PathBuf>,
    /// Extra `#INCLUDE`/`#USE` search folder (repeatable), searched after the including file's
    /// folder and before `stdlib/`.
    #[arg(short = 'I', long = "include", value_name = "DIR")]
    pub include_dirs: Vec<std::path::PathBuf>,
}

/// Runs `occ check`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    let options = Options {
        include_dirs: args.include_dirs,
    };
    let mut failed = false;
    for file in &args.files {
        let checked = frontend::check_file(file, &options);
        for diag in &checked.diagnostics {
            eprintln!("{:?}", diag.report);
        }
        if checked.has_errors() {
            failed = true;
            let errors = checked
                .diagnostics
                .iter()
                .filter(|d| d.severity == frontend::Severity::Error)
                .count();
            eprintln!("{}: {errors} error(s)", file.display());
        }
    }
    Ok(if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}
