//! Preprocessor tests: includes (re-indented, re-includable, searched through the loader),
//! conditionals, defines, pragmas and the line map back to the original files.

use super::*;
use crate::diagnostic::Severity;

fn run(root: &str, files: &[(&str, &str)]) -> Preprocessed {
    let mut loader: HashMap<String, String> = files
        .iter()
        .map(|(n, t)| (n.to_string(), t.to_string()))
        .collect();
    preprocess("root.occ", root, &mut loader)
}

fn messages(out: &Preprocessed) -> Vec<String> {
    out.diagnostics.iter().map(|d| d.message.clone()).collect()
}

/// The output with blank lines removed, for comparing texts.
fn lines(out: &Preprocessed) -> Vec<String> {
    out.text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_string)
        .collect()
}

#[test]
fn include_is_reindented_to_the_directive_column() {
    let out = run(
        "PROC p ()\n  #INCLUDE \"body.inc\"\n:\n",
        &[("body.inc", "SEQ\n  SKIP\n")],
    );
    assert!(out.diagnostics.is_empty(), "{:?}", messages(&out));
    assert_eq!(lines(&out), ["PROC p ()", "  SEQ", "    SKIP", ":"]);
}

#[test]
fn include_twice_is_allowed() {
    let out = run(
        "#INCLUDE \"a.inc\"\n#INCLUDE \"a.inc\"\n",
        &[("a.inc", "VAL x IS 1:\n")],
    );
    assert_eq!(lines(&out), ["VAL x IS 1:", "VAL x IS 1:"]);
}

#[test]
fn spans_map_back_to_the_included_file_and_line() {
    let out = run(
        "PROC p ()\n  #INCLUDE \"body.inc\"\n:\n",
        &[("body.inc", "SEQ\n  bad.line\n")],
    );
    let at = out.text.find("bad.line").expect("included text");
    let location = out.map.locate(Span::new(at, at + 8)).expect("mapped");
    assert_eq!(out.map.files[location.file].path, "body.inc");
    assert_eq!(location.line, 2);
    assert_eq!(
        &out.map.files[location.file].text[location.range],
        "bad.line"
    );
}

#[test]
fn leading_tabs_expand_to_eight_columns() {
    let out = run("SEQ\n\tSKIP\n", &[]);
    assert_eq!(lines(&out), ["SEQ", "        SKIP"]);
    let at = out.text.find("SKIP").expect("text");
    let location = out.map.locate(Span::new(at, at + 4)).expect("mapped");
    assert_eq!(&out.map.files[0].text[location.range], "SKIP");
}

#[test]
fn missing_include_is_an_error_on_its_line() {
    let out = run("SKIP\n#INCLUDE \"nowhere.inc\"\n", &[]);
    assert_eq!(messages(&out), ["cannot find the file \"nowhere.inc\""]);
    let Place::File(location) = &out.diagnostics[0].place else {
        panic!("preprocessor errors point into files");
    };
    assert_eq!(location.line, 2);
}

#[test]
fn use_finds_module_then_inc_then_occ() {
    let out = run(
        "#USE \"lib\"\n",
        &[("lib.inc", "VAL a IS 1:\n"), ("lib.occ", "VAL b IS 2:\n")],
    );
    assert_eq!(lines(&out), ["VAL a IS 1:"]);
    let out = run(
        "#USE \"course.lib\"\n",
        &[("course.module", "VAL c IS 3:\n")],
    );
    assert_eq!(lines(&out), ["VAL c IS 3:"]);
}

#[test]
fn if_else_selects_one_branch_and_skips_the_other_unlexed() {
    let text = "#IF DEFINED (OCC)\nyes\n#ELSE\n$$ not occam $$\n#ENDIF\n";
    let out = run(text, &[]);
    assert_eq!(lines(&out), ["yes"]);
}

#[test]
fn elif_chain() {
    let text = "#IF FALSE\na\n#ELIF (TARGET.BITS.PER.WORD = 32) AND NOT DEFINED (NOPE)\nb\n#ELSE\nc\n#ENDIF\n";
    assert_eq!(lines(&run(text, &[])), ["b"]);
}

#[test]
fn define_with_value_and_string_comparison() {
    let text =
        "#DEFINE MODE \"fast\"\n#DEFINE N 4\n#IF (MODE = \"fast\") AND (N > 3)\nok\n#ENDIF\n";
    assert_eq!(lines(&run(text, &[])), ["ok"]);
}

#[test]
fn nested_if_inside_inactive_branch_stays_inactive() {
    let text = "#IF FALSE\n#IF TRUE\nno\n#ENDIF\n#ELSE\nyes\n#ENDIF\n";
    assert_eq!(lines(&run(text, &[])), ["yes"]);
}

#[test]
fn unbalanced_conditionals_are_errors() {
    assert_eq!(messages(&run("#ENDIF\n", &[])), ["#ENDIF without #IF"]);
    assert_eq!(messages(&run("#ELSE\n", &[])), ["#ELSE without #IF"]);
    assert_eq!(
        messages(&run("#IF TRUE\n", &[])),
        ["this #IF has no #ENDIF"]
    );
}

#[test]
fn bad_condition_is_an_error() {
    let out = run("#IF (\nx\n#ENDIF\n", &[]);
    assert!(messages(&out)[0].starts_with("cannot evaluate this #IF condition"));
}

#[test]
fn unknown_directive_is_an_error() {
    assert_eq!(
        messages(&run("#FROBNICATE\n", &[])),
        ["unknown directive #FROBNICATE"]
    );
}

#[test]
fn hex_literal_at_line_start_is_not_a_directive() {
    let out = run("x := y +\n  #FF\n", &[]);
    assert!(out.diagnostics.is_empty());
    assert_eq!(lines(&out), ["x := y +", "  #FF"]);
}

#[test]
fn pragmas_are_kept_with_exact_name_spans() {
    let out = run(
        "#PRAGMA SHARED chan.a, chan.b\n#PRAGMA PERMITALIASES x\n",
        &[],
    );
    assert_eq!(out.pragmas.len(), 2);
    assert_eq!(out.pragmas[0].kind, PragmaKind::Shared);
    let names: Vec<&str> = out.pragmas[0]
        .names
        .iter()
        .map(|n| n.text.as_str())
        .collect();
    assert_eq!(names, ["chan.a", "chan.b"]);
    let span = out.pragmas[0].names[1].span;
    let location = out.map.locate(span).expect("mapped");
    assert_eq!(&out.map.files[0].text[location.range], "chan.b");
    assert_eq!(out.pragmas[1].kind, PragmaKind::PermitAliases);
}

#[test]
fn other_pragmas_warn_and_option_comment_are_accepted() {
    let out = run(
        "#PRAGMA ASSUMECONSTANT x\n#OPTION \"W\"\n#COMMENT \"hi\"\n",
        &[],
    );
    assert_eq!(out.diagnostics.len(), 1);
    assert_eq!(out.diagnostics[0].severity, Severity::Warning);
}

#[test]
fn recursive_include_stops_at_the_depth_limit() {
    let out = run(
        "#INCLUDE \"me.inc\"\n",
        &[("me.inc", "#INCLUDE \"me.inc\"\n")],
    );
    assert!(
        messages(&out)
            .iter()
            .any(|m| m.contains("nested too deeply"))
    );
}

#[test]
fn external_pragmas_keep_the_header_text_and_its_offset() {
    let text = "PROC p ()\n  #PRAGMA EXTERNAL \"PROC X (VAL INT a) = 0\" -- note\n  SKIP\n:\n";
    let out = preprocess("main.occ", text, &mut HashMap::new());
    assert!(out.diagnostics.is_empty(), "{:?}", out.diagnostics);
    assert_eq!(out.pragmas.len(), 1);
    assert_eq!(out.pragmas[0].kind, PragmaKind::External);
    let e = &out.externals[0];
    assert_eq!(e.text, "PROC X (VAL INT a) = 0");
    assert_eq!(&text[e.at..e.at + e.text.len()], e.text);
    let bad = preprocess(
        "m.occ",
        "#PRAGMA EXTERNAL PROC X () = 0\n",
        &mut HashMap::new(),
    );
    assert!(bad.diagnostics[0].message.contains("double quotes"));
}

#[test]
fn shared_pragma_name_spans_survive_a_trailing_comment() {
    let text = "#PRAGMA SHARED abc -- why\n";
    let out = preprocess("main.occ", text, &mut HashMap::new());
    let span = out.pragmas[0].names[0].span;
    assert_eq!(&text[span.start..span.end], "abc");
}

#[test]
fn option_letters_are_recorded_where_they_take_effect() {
    let out = run(
        "#OPTION \"A\"\n#IF FALSE\n#OPTION \"N\"\n#ENDIF\n#INCLUDE \"opts.inc\"\n",
        &[("opts.inc", "#OPTION \"EV\" -- a comment\n")],
    );
    assert!(out.diagnostics.is_empty(), "{:?}", messages(&out));
    assert_eq!(out.options, "AEV");
}
