//! The language test corpus, run through the same harness users run: `occ test tests/lang`.

use std::process::Command;

/// Runs `occ test` on `tests/lang` and asserts that nothing failed.
#[test]
fn language_corpus_passes() {
    let corpus = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/lang");
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .args(["test", corpus])
        .output()
        .expect("the occ binary runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "occ test {corpus} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
}
