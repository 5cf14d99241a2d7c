//! `occ test`.

use std::process::ExitCode;

/// Flags of `occ test`.
#[derive(clap::Args)]
pub struct Args {
    /// Input files.
    pub files: Vec<std::path::PathBuf>,
}

/// Runs `occ test`.
pub fn execute(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("`occ test` is not built yet")
}
