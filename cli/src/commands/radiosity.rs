//! `occ radiosity`.

use std::process::ExitCode;

/// Flags of `occ radiosity`.
#[derive(clap::Args)]
pub struct Args {
    /// Input files.
    pub files: Vec<std::path::PathBuf>,
}

/// Runs `occ radiosity`.
pub fn execute(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("`occ radiosity` is not built yet")
}
