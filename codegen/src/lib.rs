//! Native code generation for checked occam programs through Cranelift: each PROC becomes a resumable
//! function over its workspace, driven by the `occ-runtime` scheduler.
