//! Code generation errors: what the code generator cannot (yet) compile, and JIT failures. Each
//! becomes diagnostics of the one type every pass produces ([`CodegenError::diagnostics`]), with
//! a span where the problem has one.

use occ_grammar::ast::Span;
use occ_grammar::diagnostic::Diagnostic;

/// Why a checked program could not be compiled to native code.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CodegenError {
    /// Occurs when the program uses a construct the code generator does not lower yet.
    #[error("not yet supported by the code generator: {what}")]
    Unsupported {
        /// The construct's text.
        span: Span,
        /// The construct.
        what: String,
    },
    /// Occurs when a fact the code generator needs is missing from the checker's tables
    /// (a checker/codegen disagreement, reported instead of a panic).
    #[error("internal code generator error: {what}")]
    Internal {
        /// The text being compiled.
        span: Span,
        /// What was missing.
        what: String,
    },
    /// Occurs when `#PRAGMA EXTERNAL` routines are called but no linked intrinsic table has
    /// them, or when their occam signatures disagree with the table's (see `crate::bind`):
    /// every such problem, in source order.
    #[error("{}", .0.iter().map(|d| d.message.as_str()).collect::<Vec<_>>().join("; "))]
    Link(Vec<Diagnostic>),
    /// Occurs when the program has no top-level PROC to run.
    #[error("the program has no top-level PROC to run")]
    NoEntry,
    /// Occurs when the entry PROC's parameters are not the three byte channels.
    #[error("the entry PROC {name} must take (CHAN BYTE keyboard?, screen!, error!)")]
    BadEntry {
        /// The entry PROC.
        name: String,
        /// Its name in its declaration.
        span: Span,
    },
    /// Occurs when Cranelift rejects a generated function (a code generator bug).
    #[error("Cranelift: {0}")]
    Cranelift(String),
}

impl CodegenError {
    /// The error as diagnostics, located where the problem is.
    pub fn diagnostics(&self) -> Vec<Diagnostic> {
        let message = self.to_string();
        let one = match self {
            CodegenError::Link(found) => return found.clone(),
            CodegenError::Unsupported { span, .. } => {
                Diagnostic::error(*span, message, "this construct")
                    .with_code("codegen::unsupported")
            }
            CodegenError::Internal { span, .. } => {
                Diagnostic::error(*span, message, "while compiling this")
                    .with_code("codegen::internal")
            }
            CodegenError::BadEntry { span, .. } => {
                Diagnostic::error(*span, message, "the last top-level PROC")
                    .with_code("codegen::entry")
            }
            CodegenError::NoEntry => Diagnostic::program(message).with_code("codegen::entry"),
            CodegenError::Cranelift(_) => {
                Diagnostic::program(message).with_code("codegen::internal")
            }
        };
        vec![one]
    }
}
