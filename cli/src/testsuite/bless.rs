//! `OCC_BLESS=1`: rewriting a test's `-- stdout:` lines from the output it actually produced.
//!
//! Like Cranelift's `CRANELIFT_TEST_BLESS`: the old `-- stdout:` lines are removed and the new ones
//! are written where the first old one stood (or just after the `-- test:` header when there was
//! none). Nothing else in the file changes.

/// Reports whether blessing was asked for in the environment.
pub fn requested() -> bool {
    std::env::var_os("OCC_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

/// Reports whether a line is a whole-line `-- stdout:` marker.
fn is_stdout_line(line: &str) -> bool {
    line.trim_start()
        .strip_prefix("--")
        .is_some_and(|rest| rest.trim_start().starts_with("stdout:"))
}

/// Reports whether a line is the `-- test:` header.
fn is_header_line(line: &str) -> bool {
    line.trim_start()
        .strip_prefix("--")
        .is_some_and(|rest| rest.trim_start().starts_with("test:"))
}

/// Returns `source` with its `-- stdout:` lines replaced by `output_lines`.
pub fn rewrite(source: &str, output_lines: &[String]) -> String {
    let new_markers: Vec<String> = output_lines
        .iter()
        .map(|l| {
            if l.is_empty() {
                "-- stdout:".to_string()
            } else {
                format!("-- stdout: {l}")
            }
        })
        .collect();
    let lines: Vec<&str> = source.lines().collect();
    let insert_at = lines
        .iter()
        .position(|l| is_stdout_line(l))
        .or_else(|| lines.iter().position(|l| is_header_line(l)).map(|i| i + 1))
        .unwrap_or(0);
    let mut out: Vec<String> = Vec::with_capacity(lines.len() + new_markers.len());
    for (index, line) in lines.iter().enumerate() {
        if index == insert_at {
            out.extend(new_markers.iter().cloned());
        }
        if !is_stdout_line(line) {
            out.push((*line).to_string());
        }
    }
    if insert_at >= lines.len() {
        out.extend(new_markers);
    }
    let mut text = out.join("\n");
    if source.ends_with('\n') {
        text.push('\n');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn owned(lines: &[&str]) -> Vec<String> {
        lines.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn replaces_old_lines_in_place() {
        let src = "-- test: run\n-- stdout: old\n-- stdout: older\nPROC p ()\n  SKIP\n:\n";
        let got = rewrite(src, &owned(&["new", "", "x"]));
        assert_eq!(
            got,
            "-- test: run\n-- stdout: new\n-- stdout:\n-- stdout: x\nPROC p ()\n  SKIP\n:\n"
        );
    }

    #[test]
    fn inserts_after_header_when_none() {
        let src = "-- test: run\nPROC p ()\n  SKIP\n:\n";
        let got = rewrite(src, &owned(&["hello"]));
        assert_eq!(
            got,
            "-- test: run\n-- stdout: hello\nPROC p ()\n  SKIP\n:\n"
        );
    }

    #[test]
    fn empty_output_removes_lines() {
        let src = "-- test: run\n-- stdout: stale\nSKIP\n";
        assert_eq!(rewrite(src, &[]), "-- test: run\nSKIP\n");
    }

    #[test]
    fn round_trips_through_the_parser() {
        let src = "-- test: run\n-- stdout: a\nSKIP\n";
        let out = owned(&["one", "", "  two"]);
        let parsed = crate::testsuite::expect::parse(&rewrite(src, &out)).unwrap();
        assert_eq!(parsed.stdout, out);
    }
}
