//! `occ check`.

use std::process::ExitCode;

/// Flags of `occ check`.
#[derive(clap::Args)]
pub struct Args {
    /// Input files.
    pub files: Vec<std::path::PathBuf>,
}

/// Runs `occ check`.
pub fn execute(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("`occ check` is not built yet")
}
