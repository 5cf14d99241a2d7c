//! Parsing the expectation comments of one test file.
//!
//! Markers are occam comments of the form `-- key: value`. They may stand alone on a line or trail
//! code; `error` and `runtime-error` markers take their line number from the line they are on.

use std::fmt;
use std::path::PathBuf;

/// What a test file expects as a whole (its `-- test:` header).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `-- test: accept`: the front end reports no error.
    Accept,
    /// `-- test: error`: rejected, with the errors listed by `-- error:` markers.
    Error,
    /// `-- test: run`: compiles, runs and prints the `-- stdout:` lines.
    Run,
    /// `-- test: runtime-error`: compiles, then halts at the `-- runtime-error:` line.
    RuntimeError,
    /// `-- test: deadlock`: compiles, then deadlocks with a report naming the `-- deadlock:` texts.
    Deadlock,
}

impl Kind {
    /// Parses the word after `-- test:`.
    fn parse(word: &str) -> Option<Kind> {
        match word {
            "accept" => Some(Kind::Accept),
            "error" => Some(Kind::Error),
            "run" => Some(Kind::Run),
            "runtime-error" => Some(Kind::RuntimeError),
            "deadlock" => Some(Kind::Deadlock),
            _ => None,
        }
    }

    /// Reports whether the test needs the program to be executed.
    pub fn runs(self) -> bool {
        matches!(self, Kind::Run | Kind::RuntimeError | Kind::Deadlock)
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Kind::Accept => "accept",
            Kind::Error => "error",
            Kind::Run => "run",
            Kind::RuntimeError => "runtime-error",
            Kind::Deadlock => "deadlock",
        })
    }
}

/// One `-- error: <text>` or `-- runtime-error: <kind>` marker, with its 1-based line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineMark {
    /// The line the marker is on.
    pub line: usize,
    /// The text after the colon, trimmed.
    pub text: String,
}

/// Everything one test file expects.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Expectation {
    /// The `-- test:` header.
    pub kind: Kind,
    /// `-- error:` markers (for `error` tests).
    pub errors: Vec<LineMark>,
    /// `-- stdout:` lines, in order.
    pub stdout: Vec<String>,
    /// `-- stdin:` lines, in order.
    pub stdin: Vec<String>,
    /// `-- exit: N`, default 0.
    pub exit: i32,
    /// The `-- runtime-error:` marker (for `runtime-error` tests).
    pub runtime_error: Option<LineMark>,
    /// `-- deadlock:` texts the deadlock report must contain.
    pub deadlock: Vec<String>,
    /// `-- include:` folders, as written (relative to the test file's folder).
    pub includes: Vec<PathBuf>,
    /// `-- args:` words passed to `occ run` after the file (`--topology ring:13 --threads 1`).
    pub args: Vec<String>,
}

/// Why a file's expectation comments cannot be understood.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExpectError {
    /// Occurs when a file has no `-- test:` header.
    MissingHeader,
    /// Occurs when a file has more than one `-- test:` header.
    DuplicateHeader { line: usize },
    /// Occurs when the word after `-- test:` is not a known kind.
    UnknownKind { line: usize, word: String },
    /// Occurs when `-- exit:` is not followed by an integer.
    BadExit { line: usize, text: String },
    /// Occurs when a marker that needs text (error, runtime-error, deadlock, include) has none.
    EmptyMarker { line: usize, key: &'static str },
    /// Occurs when an `error` test has no `-- error:` marker, so it could never fail.
    NoErrorMarkers,
    /// Occurs when a `runtime-error` test has no `-- runtime-error:` marker, or more than one.
    RuntimeErrorMarkers { count: usize },
    /// Occurs when a marker does not belong to the file's kind (say `-- error:` in a `run` test).
    MisplacedMarker {
        line: usize,
        key: &'static str,
        kind: Kind,
    },
}

impl fmt::Display for ExpectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ExpectError::MissingHeader => write!(f, "no `-- test:` header"),
            ExpectError::DuplicateHeader { line } => {
                write!(f, "line {line}: a second `-- test:` header")
            }
            ExpectError::UnknownKind { line, word } => write!(
                f,
                "line {line}: unknown test kind `{word}` (accept, error, run, runtime-error, deadlock)"
            ),
            ExpectError::BadExit { line, text } => {
                write!(
                    f,
                    "line {line}: `-- exit:` needs an integer, found `{text}`"
                )
            }
            ExpectError::EmptyMarker { line, key } => {
                write!(f, "line {line}: `-- {key}:` needs a text after the colon")
            }
            ExpectError::NoErrorMarkers => {
                write!(f, "an `error` test needs at least one `-- error:` marker")
            }
            ExpectError::RuntimeErrorMarkers { count } => write!(
                f,
                "a `runtime-error` test needs exactly one `-- runtime-error:` marker, found {count}"
            ),
            ExpectError::MisplacedMarker { line, key, kind } => {
                write!(
                    f,
                    "line {line}: `-- {key}:` does not belong in a `{kind}` test"
                )
            }
        }
    }
}

/// The marker keys the harness understands, longest first so that `runtime-error` wins over `error`.
const KEYS: [&str; 9] = [
    "runtime-error",
    "deadlock",
    "include",
    "args",
    "stdout",
    "stdin",
    "error",
    "exit",
    "test",
];

/// One marker found on a line: its key, its raw value (after the colon) and its line.
#[derive(Debug, PartialEq, Eq)]
struct Marker<'a> {
    key: &'static str,
    value: &'a str,
    line: usize,
}

/// Finds the marker on one line, if any: the first `--` followed by `key:`.
fn marker_on(text: &str, line: usize) -> Option<Marker<'_>> {
    let mut rest = text;
    while let Some(at) = rest.find("--") {
        let after = rest[at + 2..].trim_start_matches(' ');
        for key in KEYS {
            if let Some(value) = after
                .strip_prefix(key)
                .and_then(|tail| tail.strip_prefix(':'))
            {
                return Some(Marker { key, value, line });
            }
        }
        rest = &rest[at + 2..];
    }
    None
}

/// The text of a `stdout`/`stdin` line: everything after the colon, less one separating space.
fn verbatim(value: &str) -> String {
    let value = value.strip_suffix('\r').unwrap_or(value);
    value.strip_prefix(' ').unwrap_or(value).to_string()
}

/// A required, trimmed text value.
fn required(marker: &Marker<'_>) -> Result<String, ExpectError> {
    let text = marker.value.trim();
    if text.is_empty() {
        return Err(ExpectError::EmptyMarker {
            line: marker.line,
            key: marker.key,
        });
    }
    Ok(text.to_string())
}

/// Parses the expectation comments of a whole file.
pub fn parse(source: &str) -> Result<Expectation, ExpectError> {
    let markers: Vec<Marker<'_>> = source
        .lines()
        .enumerate()
        .filter_map(|(index, text)| marker_on(text, index + 1))
        .collect();
    let kind = header(&markers)?;
    let mut expectation = Expectation {
        kind,
        errors: Vec::new(),
        stdout: Vec::new(),
        stdin: Vec::new(),
        exit: 0,
        runtime_error: None,
        deadlock: Vec::new(),
        includes: Vec::new(),
        args: Vec::new(),
    };
    let mut runtime_errors = Vec::new();
    for marker in markers.iter().filter(|m| m.key != "test") {
        allowed(marker, kind)?;
        apply(marker, &mut expectation, &mut runtime_errors)?;
    }
    finish(expectation, runtime_errors)
}

/// Finds the single `-- test:` header.
fn header(markers: &[Marker<'_>]) -> Result<Kind, ExpectError> {
    let mut headers = markers.iter().filter(|m| m.key == "test");
    let first = headers.next().ok_or(ExpectError::MissingHeader)?;
    if let Some(second) = headers.next() {
        return Err(ExpectError::DuplicateHeader { line: second.line });
    }
    let word = first.value.trim();
    Kind::parse(word).ok_or_else(|| ExpectError::UnknownKind {
        line: first.line,
        word: word.to_string(),
    })
}

/// Rejects markers that make no sense for the file's kind.
fn allowed(marker: &Marker<'_>, kind: Kind) -> Result<(), ExpectError> {
    let fits = match marker.key {
        "error" => kind == Kind::Error,
        "stdout" | "stdin" | "exit" | "args" => kind.runs(),
        "runtime-error" => kind == Kind::RuntimeError,
        "deadlock" => kind == Kind::Deadlock,
        _ => true,
    };
    if fits {
        Ok(())
    } else {
        Err(ExpectError::MisplacedMarker {
            line: marker.line,
            key: marker.key,
            kind,
        })
    }
}

/// Records one marker in the expectation.
fn apply(
    marker: &Marker<'_>,
    expectation: &mut Expectation,
    runtime_errors: &mut Vec<LineMark>,
) -> Result<(), ExpectError> {
    let line = marker.line;
    match marker.key {
        "error" => expectation.errors.push(LineMark {
            line,
            text: required(marker)?,
        }),
        "runtime-error" => runtime_errors.push(LineMark {
            line,
            text: required(marker)?,
        }),
        "stdout" => expectation.stdout.push(verbatim(marker.value)),
        "stdin" => expectation.stdin.push(verbatim(marker.value)),
        "deadlock" => expectation.deadlock.push(required(marker)?),
        "include" => expectation.includes.push(PathBuf::from(required(marker)?)),
        "args" => expectation
            .args
            .extend(required(marker)?.split_whitespace().map(str::to_string)),
        "exit" => {
            let text = marker.value.trim();
            expectation.exit = text.parse().map_err(|_| ExpectError::BadExit {
                line,
                text: text.to_string(),
            })?;
        }
        _ => {}
    }
    Ok(())
}

/// Checks the per-kind completeness rules.
fn finish(
    mut expectation: Expectation,
    mut runtime_errors: Vec<LineMark>,
) -> Result<Expectation, ExpectError> {
    match expectation.kind {
        Kind::Error if expectation.errors.is_empty() => Err(ExpectError::NoErrorMarkers),
        Kind::RuntimeError if runtime_errors.len() != 1 => Err(ExpectError::RuntimeErrorMarkers {
            count: runtime_errors.len(),
        }),
        _ => {
            expectation.runtime_error = runtime_errors.pop();
            Ok(expectation)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accept_header_alone() {
        let e = parse("-- test: accept\nPROC p ()\n  SKIP\n:\n").unwrap();
        assert_eq!(e.kind, Kind::Accept);
        assert!(e.errors.is_empty() && e.stdout.is_empty());
    }

    #[test]
    fn error_markers_take_their_line() {
        let src =
            "-- test: error\nPROC p ()\n  x := 1 -- error: undeclared\n  y := 2  --error: Y\n:\n";
        let e = parse(src).unwrap();
        assert_eq!(
            e.errors,
            vec![
                LineMark {
                    line: 3,
                    text: "undeclared".into()
                },
                LineMark {
                    line: 4,
                    text: "Y".into()
                },
            ]
        );
    }

    #[test]
    fn stdout_lines_keep_order_spaces_and_empties() {
        let src = "-- test: run\n-- stdout: hello\n-- stdout:\n-- stdout:   indented\n-- exit: 3\n";
        let e = parse(src).unwrap();
        assert_eq!(e.stdout, vec!["hello", "", "  indented"]);
        assert_eq!(e.exit, 3);
    }

    #[test]
    fn stdin_and_include() {
        let e = parse("-- test: run\n-- stdin: 42\n-- include: ../lib\n").unwrap();
        assert_eq!(e.stdin, vec!["42"]);
        assert_eq!(e.includes, vec![PathBuf::from("../lib")]);
    }

    #[test]
    fn runtime_error_beats_error_prefix() {
        let e = parse("-- test: runtime-error\n  x := a / b -- runtime-error: division\n").unwrap();
        assert_eq!(e.kind, Kind::RuntimeError);
        assert_eq!(
            e.runtime_error,
            Some(LineMark {
                line: 2,
                text: "division".into()
            })
        );
        assert!(e.errors.is_empty());
    }

    #[test]
    fn deadlock_texts() {
        let e = parse("-- test: deadlock\n-- deadlock: c\n-- deadlock: PROC main\n").unwrap();
        assert_eq!(e.deadlock, vec!["c", "PROC main"]);
    }

    #[test]
    fn missing_and_duplicate_headers() {
        assert_eq!(
            parse("PROC p ()\n  SKIP\n:\n"),
            Err(ExpectError::MissingHeader)
        );
        assert_eq!(
            parse("-- test: accept\n-- test: run\n"),
            Err(ExpectError::DuplicateHeader { line: 2 })
        );
    }

    #[test]
    fn unknown_kind_and_bad_exit() {
        assert!(matches!(
            parse("-- test: compile\n"),
            Err(ExpectError::UnknownKind { line: 1, .. })
        ));
        assert!(matches!(
            parse("-- test: run\n-- exit: many\n"),
            Err(ExpectError::BadExit { line: 2, .. })
        ));
    }

    #[test]
    fn error_test_without_markers_is_refused() {
        assert_eq!(
            parse("-- test: error\nSTOP\n"),
            Err(ExpectError::NoErrorMarkers)
        );
    }

    #[test]
    fn runtime_error_needs_exactly_one_marker() {
        assert_eq!(
            parse("-- test: runtime-error\nSTOP\n"),
            Err(ExpectError::RuntimeErrorMarkers { count: 0 })
        );
    }

    #[test]
    fn misplaced_markers_are_refused() {
        assert!(matches!(
            parse("-- test: accept\n  x := 1 -- error: oops\n"),
            Err(ExpectError::MisplacedMarker { key: "error", .. })
        ));
        assert!(matches!(
            parse("-- test: error\n-- stdout: hi\nx -- error: y\n"),
            Err(ExpectError::MisplacedMarker { key: "stdout", .. })
        ));
    }

    #[test]
    fn empty_required_marker_is_refused() {
        assert!(matches!(
            parse("-- test: error\n  x := 1 -- error:\n"),
            Err(ExpectError::EmptyMarker {
                key: "error",
                line: 2
            })
        ));
    }

    #[test]
    fn ordinary_comments_are_ignored() {
        let e =
            parse("-- test: accept\n-- note: errors are fine here\n-- the error: word\n").unwrap();
        assert_eq!(e.kind, Kind::Accept);
    }

    #[test]
    fn crlf_line_endings() {
        let e = parse("-- test: run\r\n-- stdout: hi\r\n").unwrap();
        assert_eq!(e.kind, Kind::Run);
        assert_eq!(e.stdout, vec!["hi"]);
    }
}
