//! Code generation errors: what the code generator cannot (yet) compile, and JIT failures.

/// Why a checked program could not be compiled to native code.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CodegenError {
    /// Occurs when the program uses a construct the code generator does not lower yet.
    #[error("{file}:{line}: not yet supported by the code generator: {what}")]
    Unsupported {
        /// Source file.
        file: String,
        /// 1-based line.
        line: u32,
        /// The construct.
        what: String,
    },
    /// Occurs when a fact the code generator needs is missing from the checker's tables
    /// (a checker/codegen disagreement, reported instead of a panic).
    #[error("{file}:{line}: internal code generator error: {what}")]
    Internal {
        /// Source file.
        file: String,
        /// 1-based line.
        line: u32,
        /// What was missing.
        what: String,
    },
    /// Occurs when a `#PRAGMA EXTERNAL` routine is called but no linked intrinsic table has it,
    /// or when its occam signature disagrees with the table's (see `crate::link`).
    #[error("{file}:{line}: {what}")]
    Link {
        /// Source file.
        file: String,
        /// 1-based line.
        line: u32,
        /// The problem.
        what: String,
    },
    /// Occurs when the program has no top-level PROC to run.
    #[error("the program has no top-level PROC to run")]
    NoEntry,
    /// Occurs when the entry PROC's parameters are not the three byte channels.
    #[error("the entry PROC {0} must take (CHAN BYTE keyboard?, screen!, error!)")]
    BadEntry(String),
    /// Occurs when Cranelift rejects a generated function (a code generator bug).
    #[error("Cranelift: {0}")]
    Cranelift(String),
}
