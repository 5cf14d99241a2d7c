//! Semantic analysis of occam programs: name resolution, types, constant folding, usage and alias
//! checks. Every error is a `miette` diagnostic with a span. No file or process IO happens here.

#![deny(missing_docs)]
#![deny(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

mod check;
pub mod checked;
pub mod consteval;
pub mod diagnostic;
pub mod entity;
mod fxhash;
pub mod predefined;
pub mod types;
pub mod usage;

pub use check::Options;
pub use checked::CheckedProgram;
pub use diagnostic::{Diagnostic, DiagnosticKind, Severity};

/// Checks a parsed program: resolves names, computes types and constants, and applies the usage
/// and alias rules.
///
/// Returns the checked program when there are no errors, and every diagnostic found (the walk
/// never stops at the first error). Spans in the diagnostics are offsets into the preprocessed
/// text the program was parsed from. Never panics, whatever the AST.
pub fn check(program: &occ_grammar::ast::Program) -> (Option<CheckedProgram>, Vec<Diagnostic>) {
    check_with(program, Options::default())
}

/// [`check`] with some checks switched off (see [`Options::from_source`] for `#OPTION`).
pub fn check_with(
    program: &occ_grammar::ast::Program,
    options: Options,
) -> (Option<CheckedProgram>, Vec<Diagnostic>) {
    let (checked, diags) = check::run(program, options);
    let ok = diags.iter().all(|d| d.severity != Severity::Error);
    (ok.then_some(checked), diags)
}
