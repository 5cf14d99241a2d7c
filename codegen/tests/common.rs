//! Helpers for the end-to-end tests: compile an occam program in-process (with the course library
//! available) and run it with captured output.

#![allow(dead_code)]

use std::path::Path;
use std::sync::{Arc, Mutex};

use occ_codegen::IntrinsicSet;
use occ_grammar::diagnostic::Diagnostic;
use occ_runtime::{HostIo, NodeConfig, RunError, Stats};

/// A shared byte buffer usable as host output.
#[derive(Clone, Default)]
pub struct Buf(pub Arc<Mutex<Vec<u8>>>);

impl std::io::Write for Buf {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("buffer").extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Loads includes from the workspace's `stdlib/`.
pub struct StdlibLoader;

impl occ_grammar::preprocess::Loader for StdlibLoader {
    fn load(&mut self, name: &str, _from: &str) -> Option<(String, String)> {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../stdlib")
            .join(name);
        std::fs::read_to_string(&p)
            .ok()
            .map(|t| (p.to_string_lossy().into_owned(), t))
    }
}

/// Compiles `src` through the one front end against `set`; an error comes back as its
/// diagnostics, one `file:line: message` each.
pub fn try_compile(src: &str, set: &IntrinsicSet) -> Result<occ_codegen::Compiled, String> {
    let front = occ_codegen::front_end("test.occ", src, &mut StdlibLoader, set);
    let parsed = &front.parsed;
    let located = |d: &Diagnostic| {
        let (file, line) = d.file_line(&parsed.map).unwrap_or(("?", 0));
        format!("{file}:{line}: {}", d.message)
    };
    let lines = |found: &[Diagnostic]| found.iter().map(located).collect::<Vec<_>>().join("\n");
    let Some(checked) = &front.checked else {
        return Err(lines(&front.diagnostics));
    };
    occ_codegen::compile_with(&parsed.program, checked, &parsed.map, set)
        .map_err(|e| lines(&e.diagnostics()))
}

/// Compiles `src` with the runtime's own intrinsics; panics with the diagnostics if it does not
/// compile.
pub fn compile(src: &str) -> occ_codegen::Compiled {
    try_compile(src, &IntrinsicSet::new()).unwrap_or_else(|e| panic!("{e}"))
}

/// The outcome of running a program.
pub struct Outcome {
    pub result: Result<(), RunError>,
    pub stdout: String,
    pub stats: Stats,
}

/// Compiles and runs `src` with `input` on the keyboard channel.
pub fn run_with(src: &str, input: &str) -> Outcome {
    let c = compile(src);
    let out = Buf::default();
    let host = HostIo::new(
        Box::new(std::io::Cursor::new(input.as_bytes().to_vec())),
        Box::new(out.clone()),
        Box::new(std::io::sink()),
    );
    let (result, stats) = c.run(NodeConfig::default(), host);
    let stdout = String::from_utf8_lossy(&out.0.lock().expect("buffer")).into_owned();
    Outcome {
        result,
        stdout,
        stats,
    }
}

/// Compiles and runs `src`, expecting normal termination; returns stdout.
pub fn run(src: &str) -> String {
    let o = run_with(src, "");
    if let Err(e) = &o.result {
        panic!("run failed: {e}\nstdout so far: {}", o.stdout);
    }
    o.stdout
}

/// Compiles and runs `src`, expecting a runtime error; returns its message.
pub fn run_error(src: &str) -> String {
    let o = run_with(src, "");
    match o.result {
        Ok(()) => panic!("expected an error, got success: {}", o.stdout),
        Err(e) => e.to_string(),
    }
}
