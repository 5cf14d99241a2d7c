//! Fuzzes the front end (preprocess, lex, parse, check: `occ_compiler::check_source`, the
//! driver every tool goes through) and the diagnostic renderer: any input must come back as a
//! program plus diagnostics, never a panic or a hang. Run with `cargo +nightly fuzz run frontend`.
//! The binding of EXTERNALs that `occ_codegen::front_end` adds is left out: it would build
//! Cranelift into the fuzzer.

#![no_main]

use libfuzzer_sys::fuzz_target;
use std::collections::HashMap;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    // An include that includes itself, to exercise the depth limit.
    let mut files: HashMap<String, String> = HashMap::new();
    files.insert("self.inc".into(), "#INCLUDE \"self.inc\"\n".into());
    let front = occ_compiler::check_source("fuzz.occ", &text, &mut files);
    for diagnostic in &front.diagnostics {
        let _ = format!("{:?}", diagnostic.to_report(&front.parsed.map));
    }
    let _ = occ_grammar::print::program(&front.parsed.program);
});
