//! The occam 2.1 front end: preprocessor, lexer (with occam's indentation layout), grammar and AST.
//!
//! Pipeline: [`preprocess`] → [`lexer`] → [`layout`] → [`parser`] → [`ast`]. Nothing here touches
//! the file system: included files are supplied through a [`preprocess::Loader`] implemented by
//! the caller.
//!
//! # Example
//!
//! ```
//! let source = "PROC hello (CHAN OF BYTE out!)\n  out ! 'h'\n:\n";
//! let front = occ_grammar::parse_source("hello.occ", source, &mut std::collections::HashMap::new());
//! assert!(front.diagnostics.is_empty());
//! assert_eq!(front.program.decls.len(), 1);
//! ```

#![deny(missing_docs)]

mod actions;
pub mod ast;
pub mod diagnostic;
pub mod external;
pub mod layout;
pub mod lexer;
pub mod parser;
pub mod preprocess;
pub mod print;
pub mod source_map;

use diagnostic::Diagnostic;
use source_map::SourceMap;

/// A preprocessed and parsed program with everything needed to report on it.
#[derive(Debug)]
pub struct Parsed {
    /// The program (partial when there are errors).
    pub program: ast::Program,
    /// The preprocessed text the spans point into.
    pub text: String,
    /// The way from spans back to the original files.
    pub map: SourceMap,
    /// Preprocessor, lexer and parser diagnostics, in order.
    pub diagnostics: Vec<Diagnostic>,
    /// The letters of the `#OPTION` directives that took effect (see
    /// [`preprocess::Preprocessed::options`]).
    pub options: String,
    /// The program holds all the code written (no file missing, no token or line dropped), so a
    /// checker may run on it even when there are errors (such as a missing pair of
    /// parentheses) and report its own errors in the same run.
    pub complete: bool,
}

impl Parsed {
    /// Reports whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics
            .iter()
            .any(|d| d.severity == diagnostic::Severity::Error)
    }
}

/// Preprocesses and parses the file `path` whose text is `text`.
pub fn parse_source(path: &str, text: &str, loader: &mut dyn preprocess::Loader) -> Parsed {
    let pre = preprocess::preprocess(path, text, loader);
    let parse = parser::parse(&pre.text);
    let mut program = parse.program;
    let mut pragmas = pre.pragmas;
    let externals_parsed = parse_externals(&pre.externals, &mut pragmas);
    program.pragmas = pragmas;
    let preprocessed_all = pre
        .diagnostics
        .iter()
        .all(|d| d.severity != diagnostic::Severity::Error);
    let mut diagnostics = pre.diagnostics;
    diagnostics.extend(parse.diagnostics);
    let externals_ok = externals_parsed.is_empty();
    diagnostics.extend(externals_parsed);
    Parsed {
        program,
        text: pre.text,
        map: pre.map,
        diagnostics,
        options: pre.options,
        complete: preprocessed_all && parse.complete && externals_ok,
    }
}

/// Parses the header of every `#PRAGMA EXTERNAL` into its pragma; returns the diagnostics of
/// the headers that did not parse. A program with a bad header is not complete (its calls
/// would all be "not declared").
fn parse_externals(
    texts: &[external::ExternalText],
    pragmas: &mut [ast::Pragma],
) -> Vec<Diagnostic> {
    let mut errors = Vec::new();
    for t in texts {
        match (external::parse(t), pragmas.get_mut(t.pragma)) {
            (Ok(e), Some(p)) => {
                p.names = vec![e.name.clone()];
                p.external = Some(e);
            }
            (Err(mut found), _) => errors.append(&mut found),
            (Ok(_), None) => {}
        }
    }
    errors
}
