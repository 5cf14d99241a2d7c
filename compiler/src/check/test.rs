//! Checker tests: one line each. `accepts!` programs must check clean; `rejects!` programs must
//! give a diagnostic containing the text on the given line (1-based). Snapshot tests render the
//! full miette report, as users see it.

use std::collections::HashMap;

use crate::diagnostic::Diagnostic;

/// Parses and checks `src`, returning the checker's diagnostics with their 1-based lines.
fn check_src(src: &str) -> Vec<(usize, String)> {
    let parsed = occ_grammar::parse_source("t.occ", src, &mut HashMap::new());
    let parse: Vec<String> = parsed
        .diagnostics
        .iter()
        .map(|d| format!("{d:?}"))
        .collect();
    assert!(!parsed.has_errors(), "parse errors: {parse:?}");
    let (_, diags) = crate::check(&parsed.program);
    diags
        .iter()
        .map(|d| (line_of(&parsed.text, d), d.message()))
        .collect()
}

fn line_of(text: &str, d: &Diagnostic) -> usize {
    text.get(..d.span.start)
        .map_or(0, |t| t.matches('\n').count() + 1)
}

macro_rules! accepts {
    ($name:ident, $src:expr) => {
        #[test]
        fn $name() {
            let d = check_src(concat!($src, "\n"));
            assert!(d.is_empty(), "unexpected diagnostics: {d:?}");
        }
    };
}

macro_rules! rejects {
    ($name:ident, $src:expr, $line:expr, $msg:expr) => {
        #[test]
        fn $name() {
            let d = check_src(concat!($src, "\n"));
            assert!(
                d.iter().any(|(l, m)| *l == $line && m.contains($msg)),
                "wanted line {} `{}`, got {d:?}",
                $line,
                $msg
            );
        }
    };
}

// Names and scope.
accepts!(simple_proc, "PROC p ()\n  INT x:\n  x := 1\n:");
rejects!(undeclared_name, "PROC p ()\n  INT x:\n  y := 1\n:", 3, "`y` is not declared");
rejects!(scope_ends_after_process, "PROC p ()\n  SEQ\n    INT x:\n    x := 1\n    x := 2\n:", 5, "`x` is not declared");
rejects!(no_recursion, "PROC p (VAL INT n)\n  p (n)\n:", 2, "calls itself");
accepts!(shadowing, "PROC p ()\n  INT x:\n  SEQ\n    x := 1\n    BOOL x:\n    x := TRUE\n:");
rejects!(duplicate_param, "PROC p (INT a, INT a)\n  SKIP\n:", 1, "declared twice");
accepts!(nested_proc_uses_outer, "PROC p ()\n  INT x:\n  PROC q ()\n    x := 1\n  :\n  q ()\n:");

// Types and literals.
rejects!(assign_bool_to_int, "PROC p ()\n  INT x:\n  x := TRUE\n:", 3, "type mismatch: expected INT, found BOOL");
rejects!(byte_int_mix, "PROC p ()\n  INT x:\n  BYTE b:\n  x := b\n:", 4, "expected INT, found BYTE");
accepts!(untyped_literal_takes_context, "PROC p ()\n  INT16 s:\n  INT64 l:\n  REAL32 r:\n  SEQ\n    s := 5\n    l := 5\n    r := 2.5\n:");
accepts!(untyped_literals_in_expressions, "PROC p ()\n  INT16 s:\n  REAL64 r:\n  SEQ\n    s := s + 1\n    r := (r * 2.0) + 1.5\n:");
accepts!(typed_literals, "PROC p ()\n  INT64 l:\n  l := 5(INT64) + #FF(INT64)\n:");
accepts!(char_literal_takes_context, "PROC p ()\n  INT x:\n  x := 'a'\n:");
rejects!(char_literal_alone_is_byte, "PROC p ()\n  INT x:\n  BYTE b:\n  SEQ\n    x := INT ('a' + b)\n    x := b + 'a'\n:", 6, "expected INT, found BYTE");
accepts!(record_literal_untyped, "DATA TYPE R\n  RECORD\n    INT i:\n    BYTE b:\n:\nPROC p ()\n  R r:\n  r := [1, 'a']\n:");
accepts!(char_literal_decorated, "PROC p ()\n  INT x:\n  x := 'a'(INT)\n:");
rejects!(bad_operand_bool_plus, "PROC p ()\n  BOOL b:\n  b := TRUE + FALSE\n:", 3, "operator + cannot be applied to BOOL");
rejects!(real_to_int_needs_round, "PROC p ()\n  INT x:\n  REAL32 r:\n  x := INT r\n:", 4, "needs ROUND or TRUNC");
accepts!(conversions, "PROC p ()\n  INT x:\n  REAL32 r:\n  BYTE b:\n  SEQ\n    x := INT ROUND r\n    r := REAL32 TRUNC x\n    b := BYTE x\n    x := INT b\n:");
rejects!(string_to_int, "PROC p ()\n  INT x:\n  x := \"ab\"\n:", 3, "expected INT, found [2]BYTE");
accepts!(string_to_byte_array, "PROC p ()\n  [5]BYTE s:\n  s := \"hello\"\n:");
rejects!(string_wrong_length, "PROC p ()\n  [4]BYTE s:\n  s := \"hello\"\n:", 3, "expected [4]BYTE, found [5]BYTE");

// Constants.
rejects!(constant_overflow_int16, "VAL INT16 x IS 32767(INT16) + 1(INT16):\nPROC p ()\n  SKIP\n:", 1, "constant overflow in INT16 expression");
rejects!(constant_division_by_zero, "VAL INT x IS 1 / 0:\nPROC p ()\n  SKIP\n:", 1, "division by zero");
rejects!(literal_out_of_range, "VAL BYTE b IS 256:\nPROC p ()\n  SKIP\n:", 1, "literal out of range for BYTE");
rejects!(shift_out_of_range, "VAL INT x IS 1 << 33:\nPROC p ()\n  SKIP\n:", 1, "shift count 33");
accepts!(mostneg_literal, "VAL INT x IS -2147483648:\nVAL INT y IS MOSTNEG INT:\nPROC p ()\n  SKIP\n:");
accepts!(modulo_ops_do_not_overflow, "VAL INT x IS (MOSTPOS INT) PLUS 1:\nPROC p ()\n  SKIP\n:");
rejects!(array_size_not_constant, "PROC p (VAL INT n)\n  [n]INT a:\n  SKIP\n:", 2, "array size must be a constant");
accepts!(array_size_from_constants, "VAL INT n IS 4:\nVAL []INT t IS [1, 2, 3]:\nPROC p ()\n  [n * (SIZE t)]INT a:\n  a[11] := 0\n:");
rejects!(constant_subscript_out_of_range, "PROC p ()\n  [4]INT a:\n  a[4] := 0\n:", 3, "out of range");
rejects!(case_duplicate, "PROC p (VAL INT x)\n  CASE x\n    1\n      SKIP\n    1\n      SKIP\n:", 5, "appears more than once");
rejects!(case_not_constant, "PROC p (VAL INT x, y)\n  CASE x\n    y\n      SKIP\n:", 3, "CASE option must be a constant");

// Assignment and abbreviations.
rejects!(assign_to_val, "PROC p (VAL INT x)\n  x := 1\n:", 2, "`x` cannot be assigned");
rejects!(assign_to_constant, "VAL INT k IS 3:\nPROC p ()\n  k := 1\n:", 3, "`k` cannot be assigned");
accepts!(multiple_assignment, "PROC p ()\n  INT a, b:\n  a, b := b, a\n:");
rejects!(multiple_assignment_count, "PROC p ()\n  INT a, b:\n  a, b := 1\n:", 3, "expected 2 values, found 1");
accepts!(multi_result_function, "INT, INT FUNCTION f (VAL INT x) IS x, x + 1:\nPROC p ()\n  INT a, b:\n  a, b := f (1)\n:");
rejects!(alias_use_while_abbreviated, "PROC p ()\n  INT x:\n  INT y IS x:\n  SEQ\n    y := 1\n    x := 2\n:", 6, "`x` is aliased");
accepts!(abbreviate_disjoint_elements, "PROC p ()\n  [4]INT a:\n  INT y IS a[0]:\n  SEQ\n    y := 1\n    a[1] := 2\n:");
rejects!(val_abbrev_then_write, "PROC p ()\n  INT x:\n  VAL INT y IS x:\n  x := y\n:", 4, "`x` is aliased");
rejects!(same_var_twice_by_reference, "PROC q (INT a, INT b)\n  a, b := 1, 2\n:\nPROC p ()\n  INT x:\n  q (x, x)\n:", 6, "`x` is aliased");
accepts!(permit_aliases_pragma, "PROC q (INT a, INT b)\n  a, b := 1, 2\n:\nPROC p ()\n  INT x:\n  #PRAGMA PERMITALIASES x\n  q (x, x)\n:");

// Calls.
rejects!(argument_count, "PROC q (VAL INT a)\n  SKIP\n:\nPROC p ()\n  q (1, 2)\n:", 5, "takes 1 parameters, but 2 were given");
rejects!(argument_type, "PROC q (VAL INT a)\n  SKIP\n:\nPROC p ()\n  q (TRUE)\n:", 5, "expected INT, found BOOL");
rejects!(val_passed_by_reference, "PROC q (INT a)\n  a := 1\n:\nPROC p (VAL INT v)\n  q (v)\n:", 5, "`v` cannot be assigned");
accepts!(open_array_parameter, "PROC q (VAL []BYTE s)\n  SKIP\n:\nPROC p ()\n  q (\"hello\")\n:");
accepts!(predefines_are_declared, "PROC p ()\n  INT hi, lo:\n  REAL32 r:\n  SEQ\n    hi, lo := LONGPROD (3, 4, 0)\n    r := SQRT (2.0)\n    ASSERT (TRUE)\n:");
accepts!(predefine_may_be_redeclared, "INT FUNCTION ABS (VAL INT x) IS x:\nPROC p ()\n  INT y:\n  y := ABS (3)\n:");
rejects!(proc_used_as_function, "PROC q ()\n  SKIP\n:\nPROC p ()\n  INT x:\n  x := q ()\n:", 6, "a FUNCTION is needed");

// Records, types, protocols.
accepts!(record_fields, "DATA TYPE P\n  RECORD\n    INT x, y:\n:\nPROC p ()\n  P a:\n  SEQ\n    a[x] := 1\n    a[y] := a[x]\n:");
rejects!(record_no_field, "DATA TYPE P\n  RECORD\n    INT x:\n:\nPROC p ()\n  P a:\n  a[z] := 1\n:", 7, "has no field `z`");
accepts!(named_type_needs_conversion, "DATA TYPE M IS INT:\nPROC p ()\n  M m:\n  INT i:\n  SEQ\n    m := M (i)\n    i := INT m\n    m := 3\n:");
rejects!(named_types_are_distinct, "DATA TYPE M IS INT:\nPROC p ()\n  M m:\n  INT i:\n  m := i\n:", 5, "expected M, found INT");
accepts!(bytesin_and_offsetof, "DATA TYPE P\n  RECORD\n    BYTE b:\n    INT x:\n:\nVAL INT n IS BYTESIN (P):\nVAL INT o IS OFFSETOF (P, x):\nPROC p ()\n  [n + o]BYTE buf:\n  buf[7] := 0\n:");
accepts!(sequential_protocol, "PROTOCOL P IS INT; BYTE:\nPROC p (CHAN OF P c)\n  INT x:\n  BYTE b:\n  SEQ\n    c ! 1; 'a'\n    c ? x; b\n:");
rejects!(sequential_protocol_count, "PROTOCOL P IS INT; BYTE:\nPROC p (CHAN OF P c)\n  c ! 1\n:", 3, "protocol mismatch");
accepts!(counted_protocol, "PROC p (CHAN OF INT::[]BYTE c)\n  [10]BYTE buf:\n  INT n:\n  SEQ\n    c ! 5 :: \"hello\"\n    c ? n :: buf\n:");
accepts!(tagged_protocol, "PROTOCOL T\n  CASE\n    a; INT\n    b\n:\nPROC p (CHAN OF T c)\n  INT x:\n  SEQ\n    c ! a; 1\n    c ! b\n    c ? CASE\n      a; x\n        SKIP\n      b\n        SKIP\n:");
rejects!(tagged_protocol_bad_tag, "PROTOCOL T\n  CASE\n    a; INT\n:\nPROC p (CHAN OF T c)\n  c ! z; 1\n:", 6, "has no tag `z`");
rejects!(output_wrong_type, "PROC p (CHAN OF INT c)\n  c ! TRUE\n:", 2, "protocol mismatch: expected INT, found BOOL");
rejects!(direction_respected, "PROC p (CHAN OF INT c?)\n  c ! 1\n:", 2, "against its direction specifier");
accepts!(timer_read_and_delay, "PROC p ()\n  TIMER t:\n  INT now:\n  SEQ\n    t ? now\n    t ? AFTER now PLUS 100\n:");
accepts!(chan_of_any, "PROC p (CHAN OF ANY c)\n  INT x:\n  SEQ\n    c ! 1\n    c ? x\n:");

// PAR usage rules.
rejects!(par_write_read, "PROC p ()\n  INT x, y:\n  PAR\n    x := 1\n    y := x\n:", 5, "`x` is written in one branch of this PAR and used in another");
rejects!(par_two_inputs, "PROC p (CHAN OF INT c)\n  INT x, y:\n  PAR\n    c ? x\n    c ? y\n:", 5, "`c` is used for input in more than one branch of this PAR");
accepts!(par_one_input_one_output, "PROC p ()\n  CHAN OF INT c:\n  INT x:\n  PAR\n    c ! 1\n    c ? x\n:");
accepts!(par_disjoint_elements, "PROC p ()\n  [4]INT a:\n  PAR\n    a[0] := 1\n    a[1] := 2\n:");
rejects!(par_same_element, "PROC p ()\n  [4]INT a:\n  PAR\n    a[1] := 1\n    a[1] := 2\n:", 5, "`a` is written");
rejects!(par_variable_subscript, "PROC p (VAL INT i)\n  [4]INT a:\n  PAR\n    a[i] := 1\n    a[0] := 2\n:", 5, "`a` is written");
accepts!(replicated_par_by_index, "PROC p ()\n  [4]INT a:\n  PAR i = 0 FOR 4\n    a[i] := i\n:");
rejects!(replicated_par_shared_write, "PROC p ()\n  INT x:\n  PAR i = 0 FOR 4\n    x := i\n:", 4, "`x` is written");
rejects!(replicated_par_neighbour, "PROC p ()\n  [5]INT a:\n  PAR i = 0 FOR 4\n    a[i] := a[i + 1]\n:", 4, "`a` is written");
accepts!(replicated_par_channels, "PROC p ([4]CHAN OF INT c)\n  PAR i = 0 FOR 4\n    c[i] ! i\n:");
accepts!(par_slices_disjoint, "PROC p ()\n  [8]INT a:\n  PAR\n    [a FROM 0 FOR 4] := [1, 2, 3, 4]\n    [a FROM 4 FOR 4] := [1, 2, 3, 4]\n:");
rejects!(par_through_proc_call, "PROC w (INT v)\n  v := 1\n:\nPROC p ()\n  INT x, y:\n  PAR\n    w (x)\n    y := x\n:", 8, "`x` is written");
rejects!(par_free_variable_in_proc, "INT g:\nPROC w ()\n  g := 1\n:\nPROC p ()\n  PAR\n    w ()\n    w ()\n:", 8, "`g` is written");
rejects!(par_channel_through_proc, "PROC r (CHAN OF INT c)\n  INT x:\n  c ? x\n:\nPROC p (CHAN OF INT c)\n  PAR\n    r (c)\n    r (c)\n:", 8, "used for input in more than one branch");
accepts!(par_timers_exempt, "PROC p ()\n  TIMER t:\n  INT a, b:\n  PAR\n    t ? a\n    t ? b\n:");
accepts!(par_shared_pragma, "PROC p ()\n  INT x:\n  #PRAGMA SHARED x\n  PAR\n    x := 1\n    x := 2\n:");
accepts!(par_locals_are_private, "PROC p ()\n  PAR\n    INT x:\n    x := 1\n    INT x:\n    x := 2\n:");
rejects!(par_through_abbreviation, "PROC p ()\n  [4]INT a:\n  INT y IS a[1]:\n  PAR\n    y := 1\n    y := 2\n:", 6, "`a` is written");

// Expressions.
accepts!(size_of_array, "PROC p ([]INT a)\n  SEQ i = 0 FOR SIZE a\n    a[i] := 0\n:");
accepts!(slices_and_tables, "PROC p ()\n  [10]INT a:\n  VAL []INT t IS [1, 2, 3]:\n  SEQ\n    [a FROM 2 FOR 3] := t\n    [a FOR 3] := [a FROM 7]\n:");
accepts!(function_valof, "INT FUNCTION sq (VAL INT x)\n  INT r:\n  VALOF\n    r := x * x\n    RESULT r\n:\nPROC p ()\n  INT y:\n  y := sq (3)\n:");
rejects!(function_result_type, "INT FUNCTION f (VAL INT x) IS TRUE:\nPROC p ()\n  SKIP\n:", 1, "expected INT, found BOOL");
accepts!(if_while_case, "PROC p (VAL INT n)\n  INT x:\n  SEQ\n    x := 0\n    WHILE x < n\n      x := x + 1\n    IF\n      x = n\n        SKIP\n      TRUE\n        STOP\n    CASE x\n      0, 1\n        SKIP\n      ELSE\n        SKIP\n:");
rejects!(while_needs_bool, "PROC p ()\n  INT x:\n  WHILE x\n    SKIP\n:", 3, "expected BOOL, found INT");
accepts!(alt_guards, "PROC p (CHAN OF INT a, b)\n  TIMER t:\n  INT x, now:\n  SEQ\n    t ? now\n    ALT\n      a ? x\n        SKIP\n      (x > 0) & b ? x\n        SKIP\n      t ? AFTER now\n        SKIP\n      TRUE & SKIP\n        SKIP\n:");
accepts!(replicated_alt, "PROC p ([4]CHAN OF INT c)\n  INT x:\n  ALT i = 0 FOR 4\n    c[i] ? x\n      SKIP\n:");
rejects!(retypes_size, "PROC p ()\n  INT x:\n  [2]BYTE b RETYPES x:\n  SKIP\n:", 3, "RETYPES size mismatch");
accepts!(retypes_ok, "PROC p ()\n  INT x:\n  [4]BYTE b RETYPES x:\n  VAL INT32 y RETYPES 1.0(REAL32):\n  b[0] := 1\n:");

accepts!(table_typed_by_its_typed_item, "DATA TYPE int IS INT:\nVAL a IS [2, 4(int)]:\nVAL b IS [2(int), 4]:\nPROC p ()\n  [2]int c:\n  c := a\n:");
accepts!(function_call_folded, "INT FUNCTION sum (VAL INT x, y) IS x + y:\nINT FUNCTION inc (VAL INT x) IS sum (x, 1):\nPROC p ()\n  [inc (sum (1, 2))]INT a:\n  a[3] := 0\n:");
accepts!(reshapes_with_variable_sizes, "PROC p (VAL INT x, y, []BYTE buf)\n  [x][y]BYTE bb RESHAPES buf:\n  bb[0][0] := 1\n:");
accepts!(call_alias_only_after_proc, "PROC p ()\n  [10]INT x:\n  INT y IS x[9]:\n  PROC q ()\n    y := 1\n  :\n  q ()\n:");
accepts!(same_variable_subscript_disjoint, "PROC p ()\n  [3][3]INT c:\n  INT b:\n  SEQ\n    b := 2\n    d IS c[b][0]:\n    e IS c[b][1]:\n    d, e := 1, 2\n:");
accepts!(channel_table_abbreviation, "PROC p ()\n  CHAN OF INT c0, c1:\n  INT x:\n  PAR\n    c1 ! 1\n    d IS [c0, c1]:\n    ALT i = 0 FOR 2\n      d[i] ? x\n        SKIP\n:");
accepts!(two_dimensional_par, "PROC p ()\n  [4][2]INT res:\n  SEQ i = 0 FOR 4\n    PAR k = 0 FOR 2\n      res[i][k] := k\n:");

accepts!(instance_guard_in_replicated_par, "PROC p ()\n  BOOL b:\n  PAR i = 0 FOR 4\n    IF\n      i = 2\n        b := TRUE\n      TRUE\n        SKIP\n:");
rejects!(instance_guards_twice, "PROC p ()\n  BOOL b:\n  PAR i = 0 FOR 4\n    SEQ\n      IF\n        i = 2\n          b := TRUE\n        TRUE\n          SKIP\n      IF\n        i = 3\n          b := FALSE\n        TRUE\n          SKIP\n:", 7, "`b` is written");
accepts!(val_abbreviation_of_index, "PROC p ()\n  [4][3][2]INT a:\n  PAR i = 0 FOR 4\n    VAL ii IS i:\n    SEQ j = 0 FOR 3\n      SEQ k = 0 FOR 2\n        a[ii][j][k] := (i + j) + k\n:");

accepts!(short_circuit_skips_range_errors, "PROC p ()\n  [1]BOOL a:\n  BOOL b:\n  SEQ\n    b := FALSE AND a[1]\n    b := TRUE OR a[1]\n:");
rejects!(evaluated_operand_range_error, "PROC p ()\n  [1]BOOL a:\n  BOOL b:\n  b := TRUE AND a[1]\n:", 4, "out of range");
accepts!(replicator_with_linear_base, "PROC p ()\n  [20]CHAN OF INT a:\n  PAR i = 0 FOR 2\n    SEQ j = i * 10 FOR 5\n      a[j] ! j\n:");
rejects!(replicator_with_linear_base_overlap, "PROC p ()\n  [20]CHAN OF INT a:\n  PAR i = 0 FOR 2\n    SEQ j = i * 3 FOR 5\n      a[j] ! j\n:", 5, "used for output in more than one branch");

rejects!(function_changes_free_variable, "INT total:\nINT FUNCTION f (VAL INT x)\n  VALOF\n    total := x\n    RESULT x\n:", 4, "may not change it");
rejects!(function_communicates, "PROC p (CHAN OF INT c)\n  INT FUNCTION f (VAL INT x)\n    INT y:\n    VALOF\n      c ? y\n      RESULT y\n  :\n  SKIP\n:", 5, "`c` is declared outside");
accepts!(function_changes_its_locals, "INT FUNCTION f (VAL INT x)\n  INT y:\n  VALOF\n    SEQ\n      y := x\n      SEQ i = 0 FOR 3\n        y := y + i\n    RESULT y\n:");

#[test]
fn every_error_is_reported_not_just_the_first() {
    let d =
        check_src("PROC p ()\n  SEQ\n    a := 1\n    b := TRUE\n    INT c:\n    c := FALSE\n:\n");
    assert!(d.len() >= 3, "{d:?}");
}

/// Renders the full report of the first diagnostic, as `occ check` shows it (without colour).
fn render(src: &str) -> String {
    use miette::{GraphicalReportHandler, GraphicalTheme};
    let parsed = occ_grammar::parse_source("t.occ", src, &mut HashMap::new());
    let (_, diags) = crate::check(&parsed.program);
    let Some(d) = diags.first() else {
        return "no diagnostics".into();
    };
    let report = d.to_diagnostic().to_report(&parsed.map);
    let mut out = String::new();
    let handler =
        GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor()).with_width(100);
    let _ = handler.render_report(&mut out, report.as_ref());
    format!("----- SOURCE CODE\n{src}----- ERROR\n{out}")
}

macro_rules! snapshot {
    ($name:ident, $src:expr) => {
        #[test]
        fn $name() {
            insta::assert_snapshot!(render(concat!($src, "\n")));
        }
    };
}

snapshot!(snapshot_undeclared, "PROC p ()\n  x := 1\n:");
snapshot!(snapshot_type_mismatch, "PROC p ()\n  INT x:\n  x := TRUE\n:");
snapshot!(snapshot_par_usage, "PROC p ()\n  INT x, y:\n  PAR\n    x := 1\n    y := x\n:");
snapshot!(snapshot_par_channel, "PROC p (CHAN OF INT c)\n  INT x, y:\n  PAR\n    c ? x\n    c ? y\n:");
snapshot!(snapshot_constant_overflow, "VAL INT16 x IS 32767(INT16) + 1(INT16):");
snapshot!(snapshot_needs_rounding, "PROC p (VAL REAL32 r)\n  INT x:\n  x := INT r\n:");
snapshot!(snapshot_asm_label, "PROC p (INT x)\n  ASM\n    LD x\n    CJ :nowhere\n:");

// ASM and GUY blocks: operands are checked where they are written.
accepts!(asm_block, "PROC p (INT x)\n  [4]INT a:\n  ASM\n    LDAB ADDRESSOF a, x\n    STNL 1\n    :l\n    LDC 0\n    CJ :l\n:");
accepts!(guy_block, "PROC p (INT x)\n  INT y:\n  GUY\n    LDLP x\n    LDNL 0\n    STL y\n:");
rejects!(asm_operand_type, "PROC p (INT x)\n  ASM\n    LD x\n    ST x +\n      1\n:", 4, "ST needs a variable");
rejects!(asm_operand_names_are_checked, "PROC p (INT x)\n  ASM\n    LDAB x,\n      y\n:", 4, "`y` is not declared");
rejects!(asm_store_to_constant, "VAL INT k IS 3:\nPROC p ()\n  ASM\n    LDC 1\n    ST k\n:", 5, "cannot be assigned");
rejects!(asm_jump_to_another_block, "PROC p ()\n  SEQ\n    ASM\n      :a\n    ASM\n      J :a\n:", 6, "not defined in this block");
rejects!(asm_unknown_instruction, "PROC p ()\n  GUY\n    FMUL\n:", 3, "`FMUL` is not a transputer instruction");
accepts!(channel_retypes_to_int_and_back, "PROC p (CHAN OF INT c)\n  VAL INT x RETYPES c:\n  CHAN OF INT d RETYPES x:\n  d ! 1\n:");

// #PRAGMA EXTERNAL routines.
accepts!(external_proc_call, "#PRAGMA EXTERNAL \"PROC X.FILL (VAL []REAL32 a, []REAL32 out, RESULT INT n) = 0\"\nPROC p ()\n  [3]REAL32 a, b:\n  INT n:\n  X.FILL (a, b, n)\n:");
accepts!(external_function_call, "#PRAGMA EXTERNAL \"REAL32 FUNCTION X.F (VAL []REAL32 a) = 0\"\nPROC p ()\n  [3]REAL32 a:\n  REAL32 r:\n  r := X.F (a) + 1.0\n:");
accepts!(external_declared_in_a_body_is_in_scope_before_it, "PROC q ()\n  X.G (1)\n:\nPROC p ()\n  #PRAGMA EXTERNAL \"PROC X.G (VAL INT a) = 0\"\n  SKIP\n:");
rejects!(external_argument_type, "#PRAGMA EXTERNAL \"PROC X.G (VAL INT a) = 0\"\nPROC p ()\n  X.G (1.5 (REAL32))\n:", 3, "type");
rejects!(external_argument_count, "#PRAGMA EXTERNAL \"PROC X.G (VAL INT a) = 0\"\nPROC p ()\n  X.G (1, 2)\n:", 3, "X.G");
rejects!(external_written_param_needs_a_variable, "#PRAGMA EXTERNAL \"PROC X.H (RESULT INT a) = 0\"\nPROC p ()\n  VAL INT k IS 3:\n  X.H (k)\n:", 4, "k");
rejects!(external_function_is_not_a_proc, "#PRAGMA EXTERNAL \"INT FUNCTION X.F (VAL INT a) = 0\"\nPROC p ()\n  X.F (1)\n:", 3, "EXTERNAL");
rejects!(external_writes_count_in_par, "#PRAGMA EXTERNAL \"PROC X.H (RESULT INT a) = 0\"\nPROC p ()\n  INT v:\n  PAR\n    X.H (v)\n    X.H (v)\n:", 6, "v");
