//! The front end never panics or hangs: random bytes, random token soup and mutated corpus files
//! all come back as a program plus diagnostics.

mod common;

use proptest::prelude::*;
use std::collections::HashMap;

fn front(text: &str) {
    let mut files: HashMap<String, String> = HashMap::new();
    files.insert("inc.inc".into(), "#INCLUDE \"inc.inc\"\n".into());
    let parsed = occ_grammar::parse_source("fuzz.occ", text, &mut files);
    for d in &parsed.diagnostics {
        let _ = d.locate(&parsed.map);
        let _ = format!("{:?}", d.to_report(&parsed.map));
    }
    let _ = occ_grammar::print::program(&parsed.program);
}

const PIECES: &[&str] = &[
    "SEQ",
    "PAR",
    "IF",
    "ALT",
    "CASE",
    "WHILE",
    "PROC",
    "FUNCTION",
    "VALOF",
    "RESULT",
    "INT",
    "x",
    "c",
    ":=",
    "!",
    "?",
    ";",
    ":",
    "::",
    ",",
    "(",
    ")",
    "[",
    "]",
    "+",
    "-",
    "AND",
    "FROM",
    "FOR",
    "IS",
    "VAL",
    "\n",
    "\n  ",
    "\n    ",
    "  ",
    "\t",
    "\"s*",
    "'",
    "#FF",
    "1.5",
    "#IF",
    "#INCLUDE \"inc.inc\"",
    "#ENDIF",
    "#ELSE",
    "#DEFINE X",
    "DEFINED (X)",
    "ASM",
    "*",
    "--",
    "(VALOF",
    "[x]",
    "|",
    "=",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn random_bytes(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        front(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn token_soup(pieces in prop::collection::vec(prop::sample::select(PIECES), 0..120)) {
        front(&pieces.join(" "));
    }

    #[test]
    fn mutated_corpus(seed in 0usize..10_000, cut in 0usize..4000, len in 0usize..40, insert in prop::sample::select(PIECES)) {
        let files = corpus();
        prop_assume!(!files.is_empty());
        let text = &files[seed % files.len()];
        let at = floor_char(text, cut.min(text.len()));
        let end = floor_char(text, (at + len).min(text.len()));
        let mutated = format!("{}{}{}", &text[..at], insert, &text[end..]);
        front(&mutated);
    }
}

fn floor_char(text: &str, mut i: usize) -> usize {
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn corpus() -> &'static Vec<String> {
    static CORPUS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    CORPUS.get_or_init(|| {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/lang");
        let mut texts = Vec::new();
        let mut stack = vec![root];
        while let Some(dir) = stack.pop() {
            let Ok(entries) = std::fs::read_dir(&dir) else {
                continue;
            };
            for entry in entries.flatten() {
                let path = entry.path();
                if path.is_dir() {
                    stack.push(path);
                } else if let Ok(text) = std::fs::read_to_string(&path) {
                    texts.push(text);
                }
            }
        }
        texts.sort();
        texts
    })
}

#[test]
fn recursive_include_is_an_error_not_a_hang() {
    let mut files: HashMap<String, String> = HashMap::new();
    files.insert("self.inc".into(), "#INCLUDE \"self.inc\"\n".into());
    let parsed = occ_grammar::parse_source("root.occ", "#INCLUDE \"self.inc\"\n", &mut files);
    assert!(
        parsed
            .diagnostics
            .iter()
            .any(|d| d.message.contains("nested too deeply"))
    );
}

#[test]
fn deeply_nested_parentheses_do_not_overflow() {
    let depth = 2000;
    let text = format!(
        "PROC p ()\n  x := {}1{}\n:\n",
        "(".repeat(depth),
        ")".repeat(depth)
    );
    front(&text);
}
