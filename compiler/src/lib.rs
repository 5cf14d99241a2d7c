//! Semantic analysis of occam programs: name resolution, types, constant folding, usage and alias
//! checks. Every error is a `miette` diagnostic with a span. No file or process IO happens here.
