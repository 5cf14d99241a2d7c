//! `#PRAGMA EXTERNAL "header = N"`: the routine header inside the string, parsed with the
//! ordinary grammar.
//!
//! Contract:
//! - The header is a PROC header (`PROC NAME (formals)`) or a FUNCTION header
//!   (`REAL32, INT FUNCTION NAME (formals)`), followed by `= N` where `N` is a decimal number
//!   (KRoC's workspace size, kept and otherwise ignored).
//! - Every span in the result (names, types, parameters) and in every diagnostic is an offset into
//!   the preprocessed text at the place of the string, so reports point into the pragma line.
//! - A malformed header gives diagnostics, never a panic.

use crate::ast::{DeclKind, External, Span};
use crate::diagnostic::{Diagnostic, Place};

/// The text of one `#PRAGMA EXTERNAL` string, as the preprocessor found it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExternalText {
    /// Index of the pragma in `Preprocessed::pragmas`.
    pub pragma: usize,
    /// The text between the quotes.
    pub text: String,
    /// Offset of the text's first byte in the preprocessed text.
    pub at: usize,
}

/// The advice given with every malformed header.
const HELP: &str = "write #PRAGMA EXTERNAL \"PROC NAME (VAL INT x) = 0\" or \"REAL32 FUNCTION NAME (VAL INT x) = 0\"";

/// Parses the header `e` into an [`External`], or returns the diagnostics that say why not.
pub fn parse(e: &ExternalText) -> Result<External, Vec<Diagnostic>> {
    let whole = Span::new(e.at, e.at + e.text.len());
    let (head, workspace) = split_workspace(&e.text, e.at)?;
    let is_function = head.split_whitespace().any(|w| w == "FUNCTION");
    if !is_function && !head.split_whitespace().any(|w| w == "PROC") {
        return Err(vec![not_a_header(whole)]);
    }
    let body = if is_function {
        " IS 0:\n"
    } else {
        "\n  SKIP\n:\n"
    };
    // Newlines up to the string's offset keep every span of the parse equal to the offset in the
    // preprocessed text, and put the header at column 0 of its own line.
    let mut padded = "\n".repeat(e.at);
    padded.push_str(head);
    padded.push_str(body);
    let parse = crate::parser::parse(&padded);
    // The first error only: the rest are usually cascades through the completed body.
    let first = parse
        .diagnostics
        .into_iter()
        .find(|d| d.severity == crate::diagnostic::Severity::Error);
    if let Some(d) = first {
        let d = clamp(d, whole, &e.text);
        let d = match d.help {
            Some(_) => d,
            None => d.with_help(HELP),
        };
        return Err(vec![d]);
    }
    let mut decls = parse.program.decls.into_iter();
    let (decl, extra) = (decls.next(), decls.next());
    let external = |name, results, params| External {
        name,
        results,
        params,
        workspace,
        header: whole,
    };
    match (decl.map(|d| d.kind), extra) {
        (Some(DeclKind::Proc { name, params, .. }), None) => Ok(external(name, Vec::new(), params)),
        (
            Some(DeclKind::Function {
                name,
                results,
                params,
                ..
            }),
            None,
        ) => Ok(external(name, results, params)),
        _ => Err(vec![not_a_header(whole)]),
    }
}

/// Splits `header = N` into the header and `N`.
fn split_workspace(text: &str, at: usize) -> Result<(&str, i64), Vec<Diagnostic>> {
    let whole = Span::new(at, at + text.len());
    let Some(eq) = text.rfind('=') else {
        let d = Diagnostic::error(
            whole,
            "an EXTERNAL header must end with `= N` (the workspace size)",
            "no `=` in this header",
        )
        .with_help(HELP);
        return Err(vec![d]);
    };
    let number = text[eq + 1..].trim();
    let Ok(workspace) = number.parse::<i64>() else {
        let span = Span::new(at + eq, at + text.len());
        let message = format!("`{number}` is not a workspace size (a decimal number)");
        return Err(vec![Diagnostic::error(span, message, "after this `=`")]);
    };
    let head = text[..eq].trim_end();
    if head.trim().is_empty() {
        return Err(vec![not_a_header(whole)]);
    }
    if head.matches('(').count() != head.matches(')').count() {
        let d = Diagnostic::error(
            Span::new(at, at + head.len()),
            "the parentheses of this EXTERNAL header do not match",
            "a formal list is `(` ... `)`",
        )
        .with_help(HELP);
        return Err(vec![d]);
    }
    Ok((head, workspace))
}

fn not_a_header(span: Span) -> Diagnostic {
    Diagnostic::error(
        span,
        "an EXTERNAL pragma must hold one PROC or FUNCTION header",
        "this is not a PROC or FUNCTION header",
    )
    .with_help(HELP)
}

/// Keeps a diagnostic of the header's parse inside the header (the parse also saw the body
/// the header was completed with), on character boundaries of `text` (which starts at offset
/// `whole.start`).
fn clamp(mut d: Diagnostic, whole: Span, text: &str) -> Diagnostic {
    if let Place::Output(span) = &mut d.place {
        let floor = |offset: usize| {
            let mut k = offset.clamp(whole.start, whole.end) - whole.start;
            while k > 0 && !text.is_char_boundary(k) {
                k -= 1;
            }
            whole.start + k
        };
        let start = floor(span.start.min(whole.end.saturating_sub(1)));
        let end = floor(span.end).max(start);
        *span = Span::new(start, end);
    }
    d
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::ast::ParamMode;

    fn text(t: &str, at: usize) -> ExternalText {
        ExternalText {
            pragma: 0,
            text: t.to_string(),
            at,
        }
    }

    #[test]
    fn a_proc_header_keeps_its_spans() {
        let t = "PROC RAD.X (VAL []REAL32 p, n, RESULT REAL32 f) = 0";
        let e = parse(&text(t, 40)).expect("parses");
        assert_eq!(e.name.text, "RAD.X");
        assert_eq!(e.name.span, Span::new(45, 50));
        assert!(e.results.is_empty());
        assert_eq!(e.params.len(), 3);
        assert_eq!(e.params[1].name.text, "n");
        assert_eq!(e.params[2].mode, ParamMode::Result);
        assert_eq!(e.header, Span::new(40, 40 + t.len()));
    }

    #[test]
    fn a_function_header_may_have_several_results() {
        let e = parse(&text("REAL32, INT FUNCTION F.G (VAL INT x) = 120", 3)).expect("parses");
        assert_eq!(e.name.text, "F.G");
        assert_eq!(e.results.len(), 2);
        assert_eq!(e.workspace, 120);
    }

    #[test]
    fn malformed_headers_are_diagnostics_inside_the_string() {
        for (t, needle) in [
            ("PROC X (VAL INT x)", "must end with `= N`"),
            ("PROC X (VAL INT x) = lots", "not a workspace size"),
            ("PROC X (VAL INT x = 0", "parentheses"),
            (" = 0", "one PROC or FUNCTION header"),
            ("INT x: = 0", "one PROC or FUNCTION header"),
            ("X (VAL INT x) = 0", "one PROC or FUNCTION header"),
            ("PROC X (VAL INT x) PROC Y () = 0", ""),
            ("PROC (VAL INT x) = 0", ""),
        ] {
            let errors = parse(&text(t, 10)).expect_err(t);
            assert!(!errors.is_empty());
            assert!(errors[0].message.contains(needle), "{t}: {errors:?}");
            assert_eq!(errors.len(), 1, "{t}: {errors:?}");
            for d in errors {
                let Place::Output(s) = d.place else { panic!() };
                assert!(s.start >= 10 && s.end <= 10 + t.len(), "{t}: {s:?}");
            }
        }
    }

    #[test]
    fn mangled_headers_never_panic_and_spans_stay_on_characters() {
        let base = "REAL32, INT FUNCTION RAD.F (VAL []REAL32 p, n, RESULT BOOL é) = 0";
        for cut in 0..=base.len() {
            for (a, b) in [(0, cut), (cut, base.len())] {
                let (Some(t), true) = (base.get(a..b), base.is_char_boundary(cut)) else {
                    continue;
                };
                for text in [t.to_string(), format!("{t}é"), format!("PROC {t}")] {
                    if let Err(errors) = parse(&self::text(&text, 5)) {
                        for d in errors {
                            let Place::Output(s) = d.place else { panic!() };
                            assert!(s.start >= 5 && s.end <= 5 + text.len() && s.start <= s.end);
                            assert!(text.is_char_boundary(s.start - 5), "{text}: {s:?}");
                            assert!(text.is_char_boundary(s.end - 5), "{text}: {s:?}");
                        }
                    }
                }
            }
        }
    }
}
