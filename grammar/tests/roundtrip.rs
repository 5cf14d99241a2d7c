//! Pretty-print then re-parse: the AST must come back unchanged (spans aside), for generated
//! programs (proptest) and for every accepted file of the language corpus.

mod common;

use common::{assert_round_trip, parse};
use proptest::prelude::*;

fn name() -> impl Strategy<Value = String> {
    prop::sample::select(vec!["a", "b", "x.y", "count", "c1"]).prop_map(str::to_string)
}

fn literal() -> impl Strategy<Value = String> {
    prop_oneof![
        (0u64..1_000_000).prop_map(|v| v.to_string()),
        (0u64..0xFFFF).prop_map(|v| format!("#{v:X}")),
        Just("'*n'".to_string()),
        Just("\"a*\"b\"".to_string()),
        Just("1.5E+3".to_string()),
        Just("TRUE".to_string()),
        (0u64..100).prop_map(|v| format!("{v}(INT64)")),
    ]
}

/// Random expressions, parenthesised as occam requires.
fn expr() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![name(), literal()];
    leaf.prop_recursive(4, 24, 3, |inner| {
        let op = prop::sample::select(vec![
            "+", "-", "*", "/", "\\", "PLUS", "MINUS", "TIMES", "/\\", "\\/", "><", "<<", ">>",
            "AND", "OR", "=", "<>", "<", ">", "<=", ">=", "AFTER",
        ]);
        prop_oneof![
            (inner.clone(), op, inner.clone()).prop_map(|(a, o, b)| format!("({a}) {o} ({b})")),
            inner.clone().prop_map(|a| format!("- ({a})")),
            inner.clone().prop_map(|a| format!("NOT ({a})")),
            inner.clone().prop_map(|a| format!("INT ROUND ({a})")),
            (name(), inner.clone()).prop_map(|(n, i)| format!("{n}[{i}]")),
            (name(), inner.clone(), inner.clone())
                .prop_map(|(n, a, b)| format!("[{n} FROM {a} FOR {b}]")),
            (name(), inner.clone()).prop_map(|(n, a)| format!("f ({n}, {a})")),
            prop::collection::vec(inner.clone(), 1..4).prop_map(|v| format!("[{}]", v.join(", "))),
            inner.prop_map(|a| format!("SIZE ({a})")),
        ]
    })
}

/// Random processes at a given indentation depth.
fn process() -> impl Strategy<Value = Vec<String>> {
    let leaf = prop_oneof![
        Just(vec!["SKIP".to_string()]),
        (name(), expr()).prop_map(|(n, e)| vec![format!("{n} := {e}")]),
        (name(), expr(), expr()).prop_map(|(n, a, b)| vec![format!("{n} ! {a}; {b}")]),
        (name(), name()).prop_map(|(c, x)| vec![format!("{c} ? {x}")]),
        (name(), expr()).prop_map(|(n, e)| vec![format!("p ({n}, {e})")]),
    ];
    leaf.prop_recursive(3, 16, 3, |inner| {
        let indent = |lines: Vec<String>| {
            lines
                .into_iter()
                .map(|l| format!("  {l}"))
                .collect::<Vec<_>>()
        };
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..3).prop_map(move |ps| {
                let mut out = vec!["SEQ".to_string()];
                for p in ps {
                    out.extend(p.into_iter().map(|l| format!("  {l}")));
                }
                out
            }),
            (expr(), inner.clone()).prop_map(move |(c, p)| {
                let mut out = vec![format!("WHILE {c}")];
                out.extend(indent(p));
                out
            }),
            (expr(), inner.clone()).prop_map(|(c, p)| {
                let mut out = vec!["IF".to_string(), format!("  {c}")];
                out.extend(p.into_iter().map(|l| format!("    {l}")));
                out
            }),
            (name(), expr(), inner.clone()).prop_map(|(n, e, p)| {
                let mut out = vec![format!("PAR i = 0 FOR {e}"), format!("  INT {n}:")];
                out.extend(p.into_iter().map(|l| format!("  {l}")));
                out
            }),
            (name(), inner).prop_map(|(c, p)| {
                let mut out = vec!["ALT".to_string(), format!("  {c} ? x")];
                out.extend(p.into_iter().map(|l| format!("    {l}")));
                out
            }),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn generated_programs_round_trip(body in process()) {
        let text: String = std::iter::once("PROC q (INT a, CHAN INT c)".to_string())
            .chain(body.into_iter().map(|l| format!("  {l}")))
            .chain(std::iter::once(":".to_string()))
            .map(|l| l + "\n")
            .collect();
        let parsed = parse(&text);
        prop_assume!(parsed.diagnostics.is_empty());
        assert_round_trip(&parsed.program);
    }
}

#[test]
fn corpus_files_round_trip() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/lang");
    let mut files = Vec::new();
    collect(&root, &mut files);
    let mut checked = 0;
    for file in files {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        if text.contains("#INCLUDE") || text.contains("#USE") {
            continue;
        }
        let parsed = parse(&text);
        if !parsed.diagnostics.is_empty() {
            continue;
        }
        assert_round_trip(&parsed.program);
        checked += 1;
    }
    eprintln!("{checked} corpus files round-tripped");
}

fn collect(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "occ") {
            out.push(path);
        }
    }
}

/// The classic cgtests (kept outside the repository): every one that parses must round-trip.
/// Run with `OCC_CGTESTS=/path/to/cgtests cargo test -p occ-grammar --test roundtrip -- --ignored`.
#[test]
#[ignore = "needs the cgtests, which are not part of the repository (set OCC_CGTESTS)"]
fn cgtests_round_trip() {
    let dir = std::path::PathBuf::from(std::env::var("OCC_CGTESTS").expect("set OCC_CGTESTS"));
    let mut loader = Dir(dir.clone());
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("cgtests folder").flatten() {
        let path = entry.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("")
            .to_string();
        if !name.starts_with("cgtest") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("readable");
        let parsed = occ_grammar::parse_source(&name, &text, &mut loader);
        if parsed.has_errors() {
            eprintln!("{name}: does not parse");
            continue;
        }
        assert_round_trip(&parsed.program);
        count += 1;
    }
    eprintln!("{count} cgtests round-tripped");
}

struct Dir(std::path::PathBuf);

impl occ_grammar::preprocess::Loader for Dir {
    fn load(&mut self, name: &str, _from: &str) -> Option<(String, String)> {
        let text = std::fs::read_to_string(self.0.join(name)).ok()?;
        Some((name.to_string(), text))
    }
}
