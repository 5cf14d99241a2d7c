//! End-to-end behaviour of the `occ test` harness itself, on small suites written to a temporary
//! folder: discovery, the closing line, running programs and the exit status.

use std::fs;
use std::path::PathBuf;
use std::process::{Command, Output};

/// A fresh, empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("harness-{name}"));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

fn occ_test(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("test")
        .args(args)
        .output()
        .expect("the occ binary runs")
}

fn last_line(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .last()
        .unwrap_or_default()
        .to_string()
}

const ACCEPT: &str =
    "-- test: accept\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  SKIP\n:\n";
const RUN: &str = "-- test: run\n-- stdout: A\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  screen ! 'A'\n:\n";

/// A `run` test runs its program and passes on the expected output.
#[test]
fn run_tests_run() {
    let dir = scratch("run");
    fs::write(dir.join("ok.occ"), ACCEPT).unwrap();
    fs::create_dir_all(dir.join("sub")).unwrap();
    fs::write(dir.join("sub").join("prints.occ"), RUN).unwrap();
    fs::write(dir.join("helper.inc"), "-- not a test\n").unwrap();
    let output = occ_test(&["-v", dir.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("ok   "), "{stdout}");
    assert_eq!(last_line(&output), "2 passed, 0 failed", "{stdout}");
    assert!(!stdout.contains("helper.inc"), "only .occ files are tests");
    assert!(output.status.success());
}

/// A `run` test whose program cannot be started fails the suite: it is never skipped, and never
/// counted as passed without running.
#[test]
fn a_run_that_cannot_start_fails() {
    let dir = scratch("nostart");
    fs::write(dir.join("ok.occ"), ACCEPT).unwrap();
    fs::write(dir.join("prints.occ"), RUN).unwrap();
    let runner = dir.join("no-such-occ");
    let output = occ_test(&["--runner", runner.to_str().unwrap(), dir.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("FAIL") && stdout.contains("prints.occ [run]: cannot start"),
        "{stdout}"
    );
    assert_eq!(last_line(&output), "1 passed, 1 failed", "{stdout}");
    assert!(!output.status.success());
}

#[test]
fn a_file_without_header_fails_the_suite() {
    let dir = scratch("header");
    fs::write(dir.join("ok.occ"), ACCEPT).unwrap();
    fs::write(dir.join("bare.occ"), "PROC p ()\n  SKIP\n:\n").unwrap();
    let output = occ_test(&[dir.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(last_line(&output), "1 passed, 1 failed");
    assert!(stdout.contains("bare.occ") && stdout.contains("no `-- test:` header"));
    assert!(!output.status.success());
}

#[test]
fn a_missing_path_is_an_error_not_an_empty_pass() {
    let output = occ_test(&["/nonexistent/occ/tests"]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("no such file or folder"));
}
