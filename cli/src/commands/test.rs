//! `occ test`: run a language test suite.
//!
//! Walks the given files and folders for `.occ` test files (never a hand-written list), checks and
//! (for `run`, `runtime-error` and `deadlock` tests) runs them in parallel, prints one line per
//! failure naming the file, what was expected and what happened, and closes with
//! `N passed, N failed`. Exits 0 only if nothing failed; a test that cannot be run fails. See
//! [`crate::testsuite`] for the file format.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use crate::testsuite::discover;
use crate::testsuite::judge::Verdict;
use crate::testsuite::suite::{self, Config, FileResult, Summary};

/// Flags of `occ test`.
#[derive(clap::Args)]
pub struct Args {
    /// Test files and folders (folders are searched recursively for `*.occ`).
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Extra `#INCLUDE`/`#USE` search folder for every test (repeatable).
    #[arg(short = 'I', long = "include", value_name = "DIR")]
    pub include_dirs: Vec<PathBuf>,
    /// Files to work on at once (default: the number of CPUs).
    #[arg(short, long)]
    pub jobs: Option<usize>,
    /// Seconds one file may take before it counts as a hang.
    #[arg(long, default_value_t = 60)]
    pub timeout: u64,
    /// Also print a line for every passed file.
    #[arg(short, long)]
    pub verbose: bool,
    /// The `occ` binary that runs each program (default: this one).
    #[arg(long, value_name = "OCC")]
    pub runner: Option<PathBuf>,
}

/// Runs `occ test`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    let files = discover::test_files(&args.paths)?;
    let jobs = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    let config = Config {
        include_dirs: args.include_dirs,
        jobs,
        timeout: Duration::from_secs(args.timeout.max(1)),
        bless: crate::testsuite::bless::requested(),
        runner: match args.runner {
            Some(runner) => runner,
            None => std::env::current_exe()?,
        },
    };
    let results = suite::run_all(&files, &config);
    let summary = Summary::of(&results);
    // A closed stdout (`occ test ... | head`) only stops the printing, never the verdict.
    let _ = print_results(&results, &summary, args.verbose);
    Ok(if summary.failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Prints one line per failure (and, when verbose, per pass), then the closing line.
fn print_results(results: &[FileResult], summary: &Summary, verbose: bool) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    for result in results {
        report(&mut out, result, verbose)?;
    }
    writeln!(out, "{}", summary.line())
}

/// Prints the line for one file, if it deserves one.
fn report(out: &mut impl Write, result: &FileResult, verbose: bool) -> std::io::Result<()> {
    let kind = result
        .kind
        .map_or_else(|| "?".to_string(), |k| k.to_string());
    let path = result.path.display();
    match &result.verdict {
        Verdict::Fail(why) => {
            // One line per failure: multi-line details (a program's stderr) are joined.
            let why = why.trim_end().replace('\n', " | ");
            writeln!(out, "FAIL {path} [{kind}]: {why}")
        }
        Verdict::Pass if verbose => writeln!(out, "ok   {path} [{kind}]"),
        _ => Ok(()),
    }
}
