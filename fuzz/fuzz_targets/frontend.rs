//! Fuzzes the front end (preprocess + lex + parse): any input must come back as a program plus
//! diagnostics, never a panic or a hang. Run with `cargo +nightly fuzz run frontend`.
//!
//! The checker joins here once it exists (the `check` helper adds the line marked below).

#![no_main]

use libfuzzer_sys::fuzz_target;
use std::collections::HashMap;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    // An include that includes itself, to exercise the depth limit.
    let mut files: HashMap<String, String> = HashMap::new();
    files.insert("self.inc".into(), "#INCLUDE \"self.inc\"\n".into());
    let parsed = occ_grammar::parse_source("fuzz.occ", &text, &mut files);
    for diagnostic in &parsed.diagnostics {
        let _ = diagnostic.locate(&parsed.map);
    }
    let _ = occ_grammar::print::program(&parsed.program);
    let _ = occ_compiler::check(&parsed.program);
});
