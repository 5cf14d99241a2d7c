//! Helpers shared by the grammar's integration tests.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use occ_grammar::Parsed;
use std::collections::HashMap;

/// Parses a program with no include files.
pub fn parse(text: &str) -> Parsed {
    occ_grammar::parse_source("test.occ", text, &mut HashMap::new())
}

/// Parses and asserts there is no diagnostic at all.
pub fn parse_ok(text: &str) -> occ_grammar::ast::Program {
    let parsed = parse(text);
    let messages: Vec<String> = parsed
        .diagnostics
        .iter()
        .map(|d| format!("{} ({})", d.message, d.label))
        .collect();
    assert!(
        messages.is_empty(),
        "unexpected diagnostics for\n{text}\n{messages:#?}"
    );
    parsed.program
}

/// The messages of every error diagnostic, with their 1-based lines.
pub fn errors(text: &str) -> Vec<(usize, String)> {
    let parsed = parse(text);
    parsed
        .diagnostics
        .iter()
        .filter(|d| d.severity == occ_grammar::diagnostic::Severity::Error)
        .map(|d| {
            let line = d.locate(&parsed.map).map_or(0, |l| l.line);
            (
                line,
                format!(
                    "{} | {} | {}",
                    d.message,
                    d.label,
                    d.help.clone().unwrap_or_default()
                ),
            )
        })
        .collect()
}

/// The Debug form of a value with every `Span { .. }` removed, to compare ASTs ignoring spans.
pub fn spanless<T: std::fmt::Debug>(value: &T) -> String {
    let text = format!("{value:?}");
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(i) = rest.find("Span { start: ") {
        out.push_str(&rest[..i]);
        let after = &rest[i..];
        let end = after.find('}').map_or(after.len(), |e| e + 1);
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// Prints `program`, parses the text again and asserts the ASTs agree (spans aside).
pub fn assert_round_trip(program: &occ_grammar::ast::Program) {
    let printed = occ_grammar::print::program(program);
    let again = parse(&printed);
    let messages: Vec<String> = again
        .diagnostics
        .iter()
        .map(|d| d.message.clone())
        .collect();
    assert!(
        messages.is_empty(),
        "printed text does not parse:\n{printed}\n{messages:#?}"
    );
    let (before, after) = (spanless(&program.decls), spanless(&again.program.decls));
    if before != after {
        let at = before
            .bytes()
            .zip(after.bytes())
            .position(|(a, b)| a != b)
            .unwrap_or(before.len().min(after.len()));
        let window = |s: &str| s[at.saturating_sub(300)..(at + 300).min(s.len())].to_string();
        panic!(
            "round trip changed the AST at byte {at}:\n  before: {}\n  after:  {}",
            window(&before),
            window(&after)
        );
    }
}
