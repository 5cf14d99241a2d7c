//! End-to-end behaviour of `occ check`: what a user sees for a diagnostic.

use std::fs;
use std::process::Command;

/// `occ check` on `source` (written to a temporary file): exit success and stderr.
fn occ_check(name: &str, source: &str) -> (bool, String) {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("check-{name}"));
    fs::create_dir_all(&dir).expect("temporary folder");
    let file = dir.join("prog.occ");
    fs::write(&file, source).expect("program file");
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("check")
        .arg(&file)
        .env("NO_COLOR", "1")
        .output()
        .expect("the occ binary runs");
    let _ = fs::remove_dir_all(&dir);
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// A PAR usage error has two labels, one in each branch; both reach the user, with the help and
/// the code.
#[test]
fn a_par_usage_error_shows_every_label() {
    let source = "PROC p ()\n  INT x, y:\n  PAR\n    x := 1\n    y := x\n:\n";
    let (ok, stderr) = occ_check("par", source);
    assert!(!ok, "{stderr}");
    for text in [
        "`x` is written in one branch of this PAR and used in another",
        "used in this branch",
        "written in another branch",
        "give each branch its own copy of `x`",
        "check::ParUsage",
        "prog.occ:5:",
    ] {
        assert!(stderr.contains(text), "missing `{text}` in\n{stderr}");
    }
}

/// A preprocessor error points into the file with a label.
#[test]
fn a_missing_include_is_a_labelled_diagnostic() {
    let (ok, stderr) = occ_check(
        "include",
        "#INCLUDE \"no-such-file.inc\"\nPROC p ()\n  SKIP\n:\n",
    );
    assert!(!ok, "{stderr}");
    assert!(stderr.contains("prog.occ:1:"), "{stderr}");
    assert!(stderr.contains("no-such-file.inc"), "{stderr}");
}

/// An `#INCLUDE` that is found nowhere names every place looked in: the including file's folder,
/// each `-I` folder, and the standard library.
#[test]
fn a_missing_include_names_every_folder_searched() {
    // (a short path: miette wraps long ones; removed below)
    let dir = std::env::temp_dir().join(format!("occ-search-{}", std::process::id()));
    let extra = dir.join("extra");
    fs::create_dir_all(&extra).expect("temporary folders");
    let file = dir.join("prog.occ");
    fs::write(&file, "#INCLUDE \"nowhere.inc\"\nPROC p ()\n  SKIP\n:\n").expect("program");
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("check")
        .arg(&file)
        .arg("-I")
        .arg(&extra)
        .env("NO_COLOR", "1")
        .output()
        .expect("the occ binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let _ = fs::remove_dir_all(&dir);
    assert!(!output.status.success(), "{stderr}");
    // miette wraps long help lines: compare without line breaks.
    let flat: String = stderr.split_whitespace().collect::<Vec<_>>().join(" ");
    for place in [
        dir.display().to_string(),
        extra.display().to_string(),
        "the standard library built into occ".into(),
    ] {
        assert!(flat.contains(&place), "missing `{place}` in\n{stderr}");
    }
}

/// The standard library is built into the binary: a program that uses the course library
/// checks from a working folder with no `stdlib/` anywhere near it, and with the folder the
/// binary would otherwise read (`OCC_STDLIB`) empty.
#[test]
fn the_stdlib_is_found_with_no_stdlib_folder() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("embedded");
    let empty = dir.join("empty");
    fs::create_dir_all(&empty).expect("temporary folders");
    fs::write(
        dir.join("hello.occ"),
        "#INCLUDE \"course.module\"\nPROC hello (CHAN BYTE keyboard?, screen!, error!)\n  out.string (\"hi*n\", 0, screen!)\n:\n",
    )
    .expect("program");
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .current_dir(&dir)
        .arg("check")
        .arg("hello.occ")
        .env("OCC_STDLIB", &empty)
        .env("NO_COLOR", "1")
        .output()
        .expect("the occ binary runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    let _ = fs::remove_dir_all(&dir);
    assert!(output.status.success(), "{stderr}");
}

/// An `ASM` instruction occ does not run is refused at its own line, naming it.
#[test]
fn an_asm_instruction_beyond_those_that_run_is_refused_at_its_line() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("check-asm");
    fs::create_dir_all(&dir).expect("temporary folder");
    let file = dir.join("prog.occ");
    let source = "PROC p ()\n  INT x:\n  ASM\n    LD ADDRESSOF x\n    FPLDNLSN\n    ST x\n:\n";
    fs::write(&file, source).expect("program file");
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("run")
        .arg(&file)
        .env("NO_COLOR", "1")
        .output()
        .expect("the occ binary runs");
    let _ = fs::remove_dir_all(&dir);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    for text in [
        "`FPLDNLSN` is not a transputer instruction occ runs",
        "prog.occ:5:5",
    ] {
        assert!(stderr.contains(text), "missing `{text}` in\n{stderr}");
    }
}
