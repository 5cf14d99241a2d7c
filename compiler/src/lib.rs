//! Semantic analysis of occam programs: name resolution, types, constant folding, usage and alias
//! checks. Every error is a `miette` diagnostic with a span. No file or process IO happens here.

#![deny(missing_docs)]
#![deny(unsafe_code)]
#![deny(clippy::unwrap_used)]

pub mod consteval;
pub mod diagnostic;
pub mod entity;
pub mod predefined;
pub mod types;
