//! Semantic analysis of occam programs: name resolution, types, constant folding, usage and alias
//! checks. Every error is a diagnostic with a span ([`Diagnostic::to_diagnostic`] gives the
//! one type every pass of occ produces). No file or process IO happens here.
//!
//! Passes (one directory each, `mod.rs` + `test.rs`):
//! - [`types`]: occam types and their T800 layout (`BYTESIN`, `OFFSETOF`);
//! - [`consteval`]: constant folding with exact occam semantics (overflow is an error);
//! - `check`: one walk in source order that resolves names, types every expression (untyped
//!   literals take their type from context), folds constants, checks communications against
//!   protocols and calls against parameters, and records every access for the usage rules;
//! - [`usage`]: the PAR usage rules (occ21 style, per branch, subscripts compared exactly where
//!   they are constant or the same linear function of replicator indices);
//! - [`predefined`]: the signatures of the occam predefined routines.
//!
//! The result is a [`CheckedProgram`]: side tables over the AST for the code generator.
//!
//! [`check_source`] is the driver every tool goes through: it preprocesses, parses and checks a
//! program whose included files come through a [`Loader`](occ_grammar::preprocess::Loader) (a
//! `HashMap` of names to texts will do), with the checks its `#OPTION` directives switch off
//! switched off.
//!
//! # Example
//!
//! ```
//! let source = "PROC p (CHAN OF INT c)\n  INT x, y:\n  PAR\n    c ? x\n    c ? y\n:\n";
//! let front = occ_compiler::check_source("p.occ", source, &mut std::collections::HashMap::new());
//! assert!(front.checked.is_none());
//! assert_eq!(
//!     front.diagnostics[0].message,
//!     "`c` is used for input in more than one branch of this PAR"
//! );
//! ```

#![deny(missing_docs)]
#![deny(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

mod check;
pub mod checked;
pub mod consteval;
pub mod diagnostic;
pub mod entity;
pub mod front;
mod fxhash;
pub mod network;
pub mod predefined;
pub mod types;
pub mod usage;

pub use check::Options;
pub use checked::CheckedProgram;
pub use diagnostic::{Diagnostic, DiagnosticKind, Severity};
pub use front::{Front, check_source};

/// Checks a parsed program: resolves names, computes types and constants, and applies the usage
/// and alias rules.
///
/// Returns the checked program when there are no errors, and every diagnostic found (the walk
/// never stops at the first error). Spans in the diagnostics are offsets into the preprocessed
/// text the program was parsed from. Never panics, whatever the AST.
pub fn check(program: &occ_grammar::ast::Program) -> (Option<CheckedProgram>, Vec<Diagnostic>) {
    check_with(program, Options::default())
}

/// [`check`] with some checks switched off (see [`Options::from_letters`] for `#OPTION`).
pub fn check_with(
    program: &occ_grammar::ast::Program,
    options: Options,
) -> (Option<CheckedProgram>, Vec<Diagnostic>) {
    let (mut checked, mut diags) = check::run(program, options);
    let mut ok = diags.iter().all(|d| d.severity != Severity::Error);
    if ok {
        let (network, more) = network::configure(program, &checked);
        ok = more.is_empty();
        checked.network = network;
        diags.extend(more);
    }
    (ok.then_some(checked), diags)
}
