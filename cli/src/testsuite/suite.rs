//! Running a list of test files in parallel and counting the outcomes.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use crate::frontend::{self, Checked, Options};
use crate::testsuite::bless;
use crate::testsuite::execute;
use crate::testsuite::expect::{self, Expectation, Kind};
use crate::testsuite::judge::{self, Verdict};

/// How to run a suite.
#[derive(Debug, Clone)]
pub struct Config {
    /// `-I` folders given on the command line, searched after each file's own `-- include:` ones.
    pub include_dirs: Vec<PathBuf>,
    /// How many files to work on at once (at least 1).
    pub jobs: usize,
    /// The longest one file may take before it counts as failed (a hang).
    pub timeout: Duration,
    /// Rewrite `-- stdout:` lines from actual output (`OCC_BLESS=1`).
    pub bless: bool,
    /// The `occ` binary that runs `run`, `runtime-error` and `deadlock` tests.
    pub runner: PathBuf,
}

/// The outcome of one file.
#[derive(Debug, Clone)]
pub struct FileResult {
    /// The test file.
    pub path: PathBuf,
    /// Its expectation kind, when the header could be read.
    pub kind: Option<Kind>,
    /// What happened.
    pub verdict: Verdict,
}

/// Counts of outcomes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Summary {
    /// Files whose expectation held.
    pub passed: usize,
    /// Files whose expectation did not hold (or could not be read, or run).
    pub failed: usize,
}

impl Summary {
    /// Counts the verdicts in `results`.
    pub fn of(results: &[FileResult]) -> Summary {
        let mut summary = Summary::default();
        for result in results {
            match result.verdict {
                Verdict::Pass => summary.passed += 1,
                Verdict::Fail(_) => summary.failed += 1,
            }
        }
        summary
    }

    /// The closing line: `N passed, N failed`.
    pub fn line(&self) -> String {
        format!("{} passed, {} failed", self.passed, self.failed)
    }
}

/// Runs every file, `config.jobs` at a time; results come back in the order of `files`.
pub fn run_all(files: &[PathBuf], config: &Config) -> Vec<FileResult> {
    let next = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<FileResult>>> = Mutex::new(vec![None; files.len()]);
    let workers = config.jobs.max(1).min(files.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let index = next.fetch_add(1, Ordering::Relaxed);
                    let Some(path) = files.get(index) else { break };
                    let result = run_one(path, config);
                    if let Ok(mut slots) = slots.lock() {
                        slots[index] = Some(result);
                    }
                }
            });
        }
    });
    let slots = slots
        .into_inner()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    slots
        .into_iter()
        .zip(files)
        .map(|(slot, path)| {
            slot.unwrap_or_else(|| FileResult {
                path: path.clone(),
                kind: None,
                verdict: Verdict::Fail("the harness lost this file's result".to_string()),
            })
        })
        .collect()
}

/// Runs one test file.
pub fn run_one(path: &Path, config: &Config) -> FileResult {
    let (kind, verdict) = match load(path) {
        Ok((source, expectation)) => (
            Some(expectation.kind),
            judge_file(path, &source, &expectation, config),
        ),
        Err(problem) => (None, Verdict::Fail(problem)),
    };
    FileResult {
        path: path.to_path_buf(),
        kind,
        verdict,
    }
}

/// Reads a file and parses its expectation comments.
fn load(path: &Path) -> Result<(String, Expectation), String> {
    let source = std::fs::read_to_string(path).map_err(|e| format!("cannot read: {e}"))?;
    let expectation =
        expect::parse(&source).map_err(|e| format!("bad expectation comments: {e}"))?;
    Ok((source, expectation))
}

/// Checks, and where possible runs, one parsed test file.
fn judge_file(path: &Path, source: &str, expectation: &Expectation, config: &Config) -> Verdict {
    let include_dirs = include_dirs(path, expectation, config);
    let checked = match check_guarded(path, &include_dirs, config.timeout) {
        Ok(checked) => checked,
        Err(problem) => return Verdict::Fail(problem),
    };
    let verdict = judge::front_end(path, expectation, &checked);
    if verdict != Verdict::Pass || !expectation.kind.runs() {
        return verdict;
    }
    let stdin = input_text(&expectation.stdin);
    match execute::run_program(
        &config.runner,
        path,
        &include_dirs,
        &expectation.args,
        &stdin,
    ) {
        Err(why) => Verdict::Fail(why),
        Ok(run) => {
            if config.bless && expectation.kind == Kind::Run {
                bless_file(path, source, &run.stdout);
            }
            judge::execution(path, expectation, &run)
        }
    }
}

/// The `-I` folders for one file: its `-- include:` folders (relative to it), then the global ones.
fn include_dirs(path: &Path, expectation: &Expectation, config: &Config) -> Vec<PathBuf> {
    let base = path.parent().unwrap_or(Path::new("."));
    expectation
        .includes
        .iter()
        .map(|dir| base.join(dir))
        .chain(config.include_dirs.iter().cloned())
        .collect()
}

/// The keyboard input for a run: each `-- stdin:` line followed by a newline.
fn input_text(lines: &[String]) -> String {
    lines.iter().map(|l| format!("{l}\n")).collect()
}

/// Rewrites the file's `-- stdout:` lines; a write failure is reported on stderr, not fatal.
fn bless_file(path: &Path, source: &str, stdout: &str) {
    let text = bless::rewrite(source, &judge::output_lines(stdout));
    if text == source {
        return;
    }
    if let Err(error) = std::fs::write(path, text) {
        eprintln!("{}: cannot bless: {error}", path.display());
    }
}

/// Runs the front end on another thread, so that a panic or a hang becomes a failure, not a crash.
fn check_guarded(
    path: &Path,
    include_dirs: &[PathBuf],
    timeout: Duration,
) -> Result<Checked, String> {
    let (sender, receiver) = mpsc::channel();
    let owned_path = path.to_path_buf();
    let options = Options {
        include_dirs: include_dirs.to_vec(),
    };
    let spawned = std::thread::Builder::new()
        .name(format!("check {}", path.display()))
        .spawn(move || {
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                frontend::check_file(&owned_path, &options)
            }));
            let _ = sender.send(outcome.map_err(|_| ()));
        });
    if let Err(error) = spawned {
        return Err(format!("cannot start a checker thread: {error}"));
    }
    match receiver.recv_timeout(timeout) {
        Ok(Ok(checked)) => Ok(checked),
        Ok(Err(())) => Err("the front end panicked".to_string()),
        Err(mpsc::RecvTimeoutError::Timeout) => Err(format!(
            "the front end did not finish within {} s (a hang)",
            timeout.as_secs()
        )),
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            Err("the front end thread ended without an answer".to_string())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closing_line_forms() {
        let s = Summary {
            passed: 3,
            failed: 1,
        };
        assert_eq!(s.line(), "3 passed, 1 failed");
    }

    #[test]
    fn input_lines_end_with_newlines() {
        assert_eq!(input_text(&["1".into(), "".into()]), "1\n\n");
    }
}
