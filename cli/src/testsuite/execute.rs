//! The one place where running a compiled test program hooks in.
//!
//! `run`, `runtime-error` and `deadlock` tests need the code generator and the runtime. Until they
//! exist, [`run_program`] answers [`Unavailable`] and the harness counts those tests as skipped after
//! checking them with the front end. When `occ run` works, make `run_program` start the `occ` binary
//! itself (`std::env::current_exe()`, so that a crash or hang of the program under test cannot take
//! the harness down) with `run FILE -I DIR...`, feed `stdin`, enforce a time limit, and fill in an
//! [`Execution`]; [`crate::testsuite::judge`] already knows how to compare it.

use std::path::Path;

/// How a program run ended, as the harness needs to see it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Execution {
    /// Everything the program wrote to its screen channel (stdout).
    pub stdout: String,
    /// Everything written to stderr, where the runtime reports errors and deadlocks.
    pub stderr: String,
    /// The exit status; `None` when the process was killed (signal or time limit).
    pub status: Option<i32>,
}

/// Running programs is not possible yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unavailable;

/// The reason shown for tests that could not be run.
pub const SKIP_REASON: &str = "no code generator yet";

/// Runs the program in `path` with `stdin` as its keyboard input.
pub fn run_program(
    path: &Path,
    include_dirs: &[std::path::PathBuf],
    stdin: &str,
) -> Result<Execution, Unavailable> {
    let _ = (path, include_dirs, stdin);
    Err(Unavailable)
}
