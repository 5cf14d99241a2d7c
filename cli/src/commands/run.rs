//! `occ run`.

use std::process::ExitCode;

/// Flags of `occ run`.
#[derive(clap::Args)]
pub struct Args {
    /// Input files.
    pub files: Vec<std::path::PathBuf>,
}

/// Runs `occ run`.
pub fn execute(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("`occ run` is not built yet")
}
