//! The occam 2.1 front end: preprocessor, lexer (with occam's indentation layout), grammar and AST.
//!
//! Pipeline: `preprocess` → `lexer` → `layout` → `parser` → [`ast`]. Nothing here touches the file
//! system: included files are supplied through a loader trait implemented by the caller.

#![deny(missing_docs)]

pub mod ast;
