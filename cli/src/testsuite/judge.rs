//! Comparing what happened with what a test file expected.

use std::path::Path;

use crate::frontend::{Checked, Diag, Severity};
use crate::testsuite::execute::Execution;
use crate::testsuite::expect::{Expectation, Kind, LineMark};

/// The outcome of one test file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Everything expected happened.
    Pass,
    /// Something else happened (or the program could not be run); the text says what was
    /// expected and what was found.
    Fail(String),
}

/// Judges the front end's diagnostics for `file` against its expectation.
///
/// Returns `Pass` when the front-end part of the expectation holds (for `run`-like tests: the
/// program compiles), or `Fail` with the differences.
pub fn front_end(file: &Path, expectation: &Expectation, checked: &Checked) -> Verdict {
    let errors: Vec<&Diag> = checked
        .diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .collect();
    let problems = match expectation.kind {
        Kind::Error => compare_errors(file, &expectation.errors, &errors),
        _ => errors
            .iter()
            .map(|d| format!("unexpected error {}", describe(file, d)))
            .collect(),
    };
    if problems.is_empty() {
        Verdict::Pass
    } else {
        let wanted = match expectation.kind {
            Kind::Error => "the marked errors",
            Kind::Accept => "no errors",
            _ => "a program that compiles",
        };
        Verdict::Fail(format!("expected {wanted}; {}", problems.join("; ")))
    }
}

/// Lists the differences between the `-- error:` markers and the errors reported.
fn compare_errors(file: &Path, marks: &[LineMark], errors: &[&Diag]) -> Vec<String> {
    let mut problems = Vec::new();
    for mark in marks {
        let found = errors
            .iter()
            .any(|d| in_file(file, d) && d.line == mark.line && contains(&d.message, &mark.text));
        if !found {
            let here: Vec<String> = errors
                .iter()
                .filter(|d| in_file(file, d) && d.line == mark.line)
                .map(|d| format!("`{}`", d.message))
                .collect();
            let actual = if here.is_empty() {
                "none".to_string()
            } else {
                here.join(", ")
            };
            problems.push(format!(
                "line {}: expected an error containing `{}`, got {actual}",
                mark.line, mark.text
            ));
        }
    }
    for diag in errors {
        let marked = in_file(file, diag) && marks.iter().any(|m| m.line == diag.line);
        if !marked {
            problems.push(format!("unexpected error {}", describe(file, diag)));
        }
    }
    problems
}

/// Judges a program run against a `run`, `runtime-error` or `deadlock` expectation.
pub fn execution(file: &Path, expectation: &Expectation, run: &Execution) -> Verdict {
    let mut problems = Vec::new();
    let check_stdout = expectation.kind == Kind::Run || !expectation.stdout.is_empty();
    if check_stdout {
        problems.extend(compare_stdout(&expectation.stdout, &run.stdout));
    }
    match expectation.kind {
        Kind::Run => {
            if run.status != Some(expectation.exit) {
                problems.push(format!(
                    "expected exit status {}, got {}; stderr: {}",
                    expectation.exit,
                    status_text(run.status),
                    run.stderr.trim()
                ));
            }
        }
        Kind::RuntimeError => problems.extend(runtime_error(file, expectation, run)),
        Kind::Deadlock => problems.extend(deadlock(&expectation.deadlock, run)),
        Kind::Accept | Kind::Error => {}
    }
    if problems.is_empty() {
        Verdict::Pass
    } else {
        Verdict::Fail(problems.join("; "))
    }
}

/// Compares the program's output with the `-- stdout:` lines.
fn compare_stdout(expected: &[String], actual: &str) -> Option<String> {
    let lines = output_lines(actual);
    if lines == expected {
        return None;
    }
    let first = (0..expected.len().max(lines.len()))
        .find(|&i| expected.get(i) != lines.get(i))
        .unwrap_or(0);
    Some(format!(
        "stdout differs at output line {}: expected {:?}, got {:?}",
        first + 1,
        expected.get(first).map(String::as_str).unwrap_or("<end>"),
        lines.get(first).map(String::as_str).unwrap_or("<end>")
    ))
}

/// Splits program output into lines the way `-- stdout:` lines describe it.
pub fn output_lines(output: &str) -> Vec<String> {
    let body = output.strip_suffix('\n').unwrap_or(output);
    if output.is_empty() {
        return Vec::new();
    }
    body.split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l).to_string())
        .collect()
}

/// Checks a runtime-error halt: non-zero status, and a report naming the kind and the line.
fn runtime_error(file: &Path, expectation: &Expectation, run: &Execution) -> Vec<String> {
    let Some(mark) = &expectation.runtime_error else {
        return vec!["no `-- runtime-error:` marker".to_string()];
    };
    let mut problems = Vec::new();
    if run.status == Some(0) {
        problems.push("expected a runtime error, but the program ended normally".to_string());
    }
    if !contains(&run.stderr, &mark.text) {
        problems.push(format!("error report does not mention `{}`", mark.text));
    }
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned());
    let names_line = [format!(":{}", mark.line), format!("line {}", mark.line)]
        .iter()
        .any(|needle| run.stderr.contains(needle.as_str()));
    if !names_line || !name.is_some_and(|n| run.stderr.contains(&n)) {
        problems.push(format!(
            "error report does not name {}:{}",
            file.display(),
            mark.line
        ));
    }
    if !problems.is_empty() {
        problems.push(format!("stderr was: {}", run.stderr.trim()));
    }
    problems
}

/// Checks a deadlock: non-zero status and a report containing every expected text.
fn deadlock(texts: &[String], run: &Execution) -> Vec<String> {
    let mut problems = Vec::new();
    if run.status == Some(0) {
        problems.push("expected a deadlock, but the program ended normally".to_string());
    }
    if !contains(&run.stderr, "deadlock") {
        problems.push("no deadlock report on stderr".to_string());
    }
    for text in texts {
        if !run.stderr.contains(text.as_str()) {
            problems.push(format!("deadlock report does not contain `{text}`"));
        }
    }
    if !problems.is_empty() {
        problems.push(format!("stderr was: {}", run.stderr.trim()));
    }
    problems
}

/// Reports whether `haystack` contains `needle`, ignoring ASCII case.
fn contains(haystack: &str, needle: &str) -> bool {
    haystack
        .to_ascii_lowercase()
        .contains(&needle.to_ascii_lowercase())
}

/// Reports whether a diagnostic is located in the test file itself (not in an included file).
fn in_file(file: &Path, diag: &Diag) -> bool {
    if diag.file == file {
        return true;
    }
    match (diag.file.canonicalize(), file.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// `line N: message`, or `other-file:N: message` for a diagnostic in an included file.
fn describe(file: &Path, diag: &Diag) -> String {
    if in_file(file, diag) {
        format!("at line {}: `{}`", diag.line, diag.message)
    } else {
        format!(
            "at {}:{}: `{}`",
            diag.file.display(),
            diag.line,
            diag.message
        )
    }
}

/// An exit status for messages.
fn status_text(status: Option<i32>) -> String {
    status.map_or_else(|| "killed".to_string(), |s| s.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testsuite::expect::parse;
    use std::path::PathBuf;

    fn diag(line: usize, message: &str) -> Diag {
        Diag {
            severity: Severity::Error,
            file: PathBuf::from("t.occ"),
            line,
            message: message.to_string(),
            report: miette::miette!("{message}"),
        }
    }

    fn checked(diags: Vec<Diag>) -> Checked {
        Checked { diagnostics: diags }
    }

    #[test]
    fn accept_passes_without_errors_and_fails_with_one() {
        let e = parse("-- test: accept\n").unwrap();
        let file = Path::new("t.occ");
        assert_eq!(front_end(file, &e, &checked(vec![])), Verdict::Pass);
        let v = front_end(file, &e, &checked(vec![diag(3, "bad")]));
        assert!(matches!(v, Verdict::Fail(ref s) if s.contains("line 3") && s.contains("bad")));
    }

    #[test]
    fn error_markers_match_line_and_text_ignoring_case() {
        let e = parse("-- test: error\n\nx -- error: Undeclared\n").unwrap();
        let file = Path::new("t.occ");
        let ok = checked(vec![diag(3, "`x` is undeclared here")]);
        assert_eq!(front_end(file, &e, &ok), Verdict::Pass);
        let wrong_line = checked(vec![diag(2, "`x` is undeclared here")]);
        assert!(matches!(front_end(file, &e, &wrong_line), Verdict::Fail(_)));
        let wrong_text = checked(vec![diag(3, "type mismatch")]);
        assert!(matches!(front_end(file, &e, &wrong_text), Verdict::Fail(_)));
    }

    #[test]
    fn extra_error_on_unmarked_line_fails() {
        let e = parse("-- test: error\n\nx -- error: undeclared\n").unwrap();
        let file = Path::new("t.occ");
        let extra = checked(vec![diag(3, "undeclared"), diag(5, "something else")]);
        let v = front_end(file, &e, &extra);
        assert!(matches!(v, Verdict::Fail(ref s) if s.contains("unexpected error at line 5")));
    }

    #[test]
    fn warnings_do_not_count() {
        let e = parse("-- test: accept\n").unwrap();
        let mut w = diag(2, "unused");
        w.severity = Severity::Warning;
        assert_eq!(
            front_end(Path::new("t.occ"), &e, &checked(vec![w])),
            Verdict::Pass
        );
    }

    fn ran(stdout: &str, stderr: &str, status: Option<i32>) -> Execution {
        Execution {
            stdout: stdout.into(),
            stderr: stderr.into(),
            status,
        }
    }

    #[test]
    fn run_compares_lines_and_status() {
        let e = parse("-- test: run\n-- stdout: a\n-- stdout:\n-- stdout: b\n").unwrap();
        let file = Path::new("t.occ");
        assert_eq!(
            execution(file, &e, &ran("a\n\nb\n", "", Some(0))),
            Verdict::Pass
        );
        assert_eq!(
            execution(file, &e, &ran("a\n\nb", "", Some(0))),
            Verdict::Pass
        );
        assert!(matches!(
            execution(file, &e, &ran("a\nb\n", "", Some(0))),
            Verdict::Fail(_)
        ));
        assert!(matches!(
            execution(file, &e, &ran("a\n\nb\n", "", Some(1))),
            Verdict::Fail(_)
        ));
    }

    #[test]
    fn empty_output_matches_no_stdout_lines() {
        let e = parse("-- test: run\n").unwrap();
        assert_eq!(
            execution(Path::new("t.occ"), &e, &ran("", "", Some(0))),
            Verdict::Pass
        );
        assert!(matches!(
            execution(Path::new("t.occ"), &e, &ran("\n", "", Some(0))),
            Verdict::Fail(_)
        ));
    }

    #[test]
    fn runtime_error_needs_kind_file_and_line() {
        let e = parse("-- test: runtime-error\n\nx := y / 0 -- runtime-error: division\n").unwrap();
        let file = Path::new("tests/t.occ");
        let good = ran("", "error: division by zero at t.occ:3\n", Some(1));
        assert_eq!(execution(file, &e, &good), Verdict::Pass);
        let wrong_line = ran("", "error: division by zero at t.occ:4\n", Some(1));
        assert!(matches!(execution(file, &e, &wrong_line), Verdict::Fail(_)));
        let clean = ran("", "", Some(0));
        assert!(matches!(execution(file, &e, &clean), Verdict::Fail(_)));
    }

    #[test]
    fn deadlock_needs_report_texts() {
        let e = parse("-- test: deadlock\n-- deadlock: chan.a\n").unwrap();
        let file = Path::new("t.occ");
        let good = ran(
            "",
            "deadlock: PROC main blocked on chan.a (t.occ:5)\n",
            Some(2),
        );
        assert_eq!(execution(file, &e, &good), Verdict::Pass);
        let missing = ran("", "deadlock: PROC main blocked on c (t.occ:5)\n", Some(2));
        assert!(matches!(execution(file, &e, &missing), Verdict::Fail(_)));
    }
}
