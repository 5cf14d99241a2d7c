//! Parser tests on small snippets: what must parse (with its shape) and what must be rejected
//! (with its line and message).

mod common;

use common::{errors, parse_ok};
use occ_grammar::ast::*;

/// Wraps process lines in a PROC so that they can be parsed as a program.
fn proc_body(lines: &str) -> String {
    let body: String = lines.lines().map(|l| format!("  {l}\n")).collect();
    format!("PROC p ()\n{body}:\n")
}

fn body_of(program: &Program) -> &Process {
    match &program.decls[0].kind {
        DeclKind::Proc { body, .. } => body,
        other => panic!("not a PROC: {other:?}"),
    }
}

fn process(lines: &str) -> Process {
    body_of(&parse_ok(&proc_body(lines))).clone()
}

macro_rules! accepts {
    ($name:ident, $text:expr) => {
        #[test]
        fn $name() {
            parse_ok(&proc_body($text));
        }
    };
}

macro_rules! accepts_top {
    ($name:ident, $text:expr) => {
        #[test]
        fn $name() {
            parse_ok($text);
        }
    };
}

/// Asserts an error on `line` (of the PROC-wrapped text: body line n is line n + 1) whose text
/// contains `needle`.
macro_rules! rejects {
    ($name:ident, $text:expr, $line:expr, $needle:expr) => {
        #[test]
        fn $name() {
            let errs = errors(&proc_body($text));
            assert!(
                errs.iter()
                    .any(|(l, m)| *l == $line + 1 && m.contains($needle)),
                "expected {:?} on body line {}, got {errs:#?}",
                $needle,
                $line
            );
        }
    };
}

accepts!(skip_and_stop, "SEQ\n  SKIP\n  STOP");
accepts!(multiple_assignment, "INT a, b:\na, b := b, a");
accepts!(output_sequential, "c ! 1; 2; 'x'");
accepts!(output_counted, "c ! n :: buf");
accepts!(input_counted, "c ? n :: buf");
accepts!(
    case_input,
    "c ? CASE\n  tag.a; x\n    SKIP\n  tag.b\n    SKIP"
);
accepts!(one_line_case_input, "c ? CASE tag.a; x");
accepts!(delay, "tim ? AFTER t PLUS 100");
accepts!(timer_read, "tim ? t");
accepts!(replicated_seq_step, "SEQ i = 0 FOR 10 STEP 2\n  SKIP");
accepts!(pri_par, "PRI PAR\n  SKIP\n  SKIP");
accepts!(placed_par, "PLACED PAR\n  PROCESSOR 1\n    SKIP");
accepts!(replicated_par, "PAR i = 0 FOR n\n  c[i] ! i");
accepts!(
    if_nested_replicated,
    "IF\n  x > 0\n    SKIP\n  IF i = 0 FOR n\n    a[i] = 0\n      SKIP\n  TRUE\n    SKIP"
);
accepts!(
    alt_guards,
    "ALT\n  in ? x\n    SKIP\n  b & in ? x\n    SKIP\n  tim ? AFTER t\n    SKIP\n  TRUE & SKIP\n    SKIP"
);
accepts!(
    pri_alt_replicated,
    "PRI ALT i = 0 FOR n\n  in[i] ? x\n    SKIP"
);
accepts!(
    alt_case_input_guard,
    "ALT\n  b & c ? CASE\n    t1\n      SKIP"
);
accepts!(
    case_several_values,
    "CASE x\n  1, 2, 3\n    SKIP\n  'a'\n    SKIP\n  ELSE\n    SKIP"
);
accepts!(while_loop, "WHILE x < 10\n  x := x + 1");
accepts!(call_with_directions, "p (c!, d?, a[i], 3)");
accepts!(declarations_before_process, "INT x:\nVAL y IS 3:\nx := y");
accepts!(abbreviation_of_slice, "[]INT b IS [a FROM 1 FOR 2]:\nSKIP");
accepts!(
    slice_forms,
    "SEQ\n  x := [a FROM 1]\n  y := [a FOR 2]\n  z := [a FROM i FOR n]"
);
accepts!(
    table_and_string,
    "VAL t IS [1, 2, 3]:\nVAL s IS \"hello*n\":\nSKIP"
);
accepts!(one_element_table, "VAL t IS [7]:\np (0, [1])");
accepts!(array_constructor, "VAL sq IS [i = 0 FOR 10 | i * i]:\nSKIP");
accepts!(
    conversions,
    "SEQ\n  x := INT y\n  r := REAL32 ROUND y\n  i := INT TRUNC r\n  b := BYTE 65"
);
accepts!(
    named_conversion,
    "SEQ\n  m := MYTYPE f (x)\n  m := MYTYPE 5\n  m := MYTYPE ROUND r"
);
accepts!(
    typed_literals,
    "SEQ\n  a := 5(INT64)\n  b := 2.0(REAL32)\n  c := 'a'(BYTE)\n  d := 85 (MYINT)"
);
accepts!(typed_table, "p := [3, 4](POINT)");
accepts!(
    most_pos_neg,
    "SEQ\n  x := MOSTPOS INT\n  y := MOSTNEG INT64"
);
accepts!(
    size_bytesin_offsetof,
    "SEQ\n  x := SIZE a\n  y := BYTESIN (INT)\n  z := BYTESIN (r)\n  w := OFFSETOF (POINT, y)"
);
accepts!(
    modulo_operators,
    "SEQ\n  x := a PLUS b\n  y := a TIMES b\n  z := MINUS a\n  t := a AFTER b"
);
accepts!(
    bit_operators,
    "SEQ\n  x := a /\\ b\n  y := a \\/ b\n  z := a >< b\n  w := ~a\n  v := a << 2\n  u := a BITAND b"
);
accepts!(
    and_or_chains,
    "SEQ\n  x := p AND q AND r\n  y := p OR q OR r"
);
rejects!(same_operator_chain, "x := a + b + c", 1, "parentheses");
accepts!(remainder, "SEQ\n  x := a \\ b\n  y := a REM b");
accepts!(
    retypes_reshapes,
    "VAL INT x RETYPES r:\n[4]BYTE b RETYPES i:\n[2][2]INT m RESHAPES v:\nSKIP"
);
accepts!(
    result_and_initial,
    "RESULT INT r IS x:\nINITIAL INT i IS 3:\nSKIP"
);
accepts!(
    channel_declarations,
    "CHAN OF INT c:\nCHAN INT d:\n[4]CHAN OF BYTE cs:\nCHAN OF ANY any:\nTIMER t:\nPORT OF INT16 port:\nSKIP"
);
accepts!(channel_abbreviation_direction, "CHAN INT out! IS c!:\nSKIP");
accepts!(place_at, "INT x:\nPLACE x AT #100:\nSKIP");
accepts!(
    valof_expression,
    "x := (VALOF\n        SKIP\n        RESULT 3\n      )"
);
accepts!(record_field, "SEQ\n  p[x] := 3\n  y := q[pos][x]");
accepts!(string_subscript, "b := \"abc\"[1]");

accepts_top!(
    proc_params,
    "PROC p (VAL INT a, b, INT c, RESULT REAL32 r, CHAN OF BYTE in?, out!, []INT v)\n  SKIP\n:\n"
);
accepts_top!(inline_proc, "INLINE PROC p ()\n  SKIP\n:\n");
accepts_top!(
    function_valof,
    "INT FUNCTION f (VAL INT x)\n  INT r:\n  VALOF\n    r := x + 1\n    RESULT r\n:\n"
);
accepts_top!(
    function_is,
    "INT, INT FUNCTION two (VAL INT x) IS x, x + 1:\n"
);
accepts_top!(
    named_result_function,
    "MY, INT FUNCTION f (VAL MY x) IS x, 1:\n"
);
accepts_top!(inline_function, "INT INLINE FUNCTION f (VAL INT x) IS x:\n");
accepts_top!(
    user_defined_operator,
    "INT64 FUNCTION \"+\" (VAL INT64 a, b) IS a PLUS b:\n"
);
accepts_top!(data_type_alias, "DATA TYPE MY IS INT32:\n");
accepts_top!(
    data_type_record,
    "DATA TYPE POINT\n  RECORD\n    INT x, y:\n    REAL32 w:\n:\n"
);
accepts_top!(
    packed_record,
    "DATA TYPE P\n  PACKED RECORD\n    BYTE a:\n    INT16 b:\n:\n"
);
accepts_top!(
    protocols,
    "PROTOCOL A IS INT:\nPROTOCOL B IS INT; BYTE; [4]REAL64:\nPROTOCOL C IS INT::[]BYTE:\nPROTOCOL D\n  CASE\n    go; INT\n    stop\n:\n"
);

#[test]
fn declarations_merge_into_one_scope() {
    let p = process("INT x:\nINT y:\nx := y");
    let ProcessKind::Scope { decls, body } = p.kind else {
        panic!("expected a scope");
    };
    assert_eq!(decls.len(), 2);
    assert!(matches!(body.kind, ProcessKind::Assign { .. }));
}

#[test]
fn shared_parameter_types_expand() {
    let program = parse_ok("PROC p (VAL INT a, b, CHAN INT c?, d!)\n  SKIP\n:\n");
    let DeclKind::Proc { params, .. } = &program.decls[0].kind else {
        panic!()
    };
    let summary: Vec<(ParamMode, &str, Option<Direction>)> = params
        .iter()
        .map(|p| (p.mode, p.name.text.as_str(), p.dir))
        .collect();
    assert_eq!(
        summary,
        vec![
            (ParamMode::Val, "a", None),
            (ParamMode::Val, "b", None),
            (ParamMode::Ref, "c", Some(Direction::Input)),
            (ParamMode::Ref, "d", Some(Direction::Output)),
        ]
    );
    assert_eq!(params[1].ty.kind, TyKind::Int);
}

#[test]
fn and_chain_is_left_associative() {
    let p = process("x := a - b");
    let ProcessKind::Assign { rhs, .. } = p.kind else {
        panic!()
    };
    assert!(matches!(
        rhs[0].kind,
        ExprKind::Binary { op: BinOp::Sub, .. }
    ));
    let p = process("x := a AND b AND c");
    let ProcessKind::Assign { rhs, .. } = p.kind else {
        panic!()
    };
    let ExprKind::Binary { lhs, .. } = &rhs[0].kind else {
        panic!()
    };
    assert!(matches!(lhs.kind, ExprKind::Binary { op: BinOp::And, .. }));
}

#[test]
fn hex_literal_keeps_its_form() {
    let p = process("x := #FFFFFFFF");
    let ProcessKind::Assign { rhs, .. } = p.kind else {
        panic!()
    };
    assert_eq!(
        rhs[0].kind,
        ExprKind::Literal(Literal {
            kind: LitKind::Int {
                value: 0xFFFF_FFFF,
                hex: true
            },
            ty: None
        })
    );
}

#[test]
fn every_node_span_is_inside_the_text() {
    let text = proc_body("SEQ i = 0 FOR 3\n  c ! i * 2");
    let program = parse_ok(&text);
    let body = body_of(&program);
    assert!(body.span.end <= text.len() && body.span.start < body.span.end);
    assert_eq!(&text[body.span.start..body.span.start + 3], "SEQ");
}

rejects!(
    mixed_operators_need_parentheses,
    "x := a + b * c",
    1,
    "write (a + b) * c"
);
rejects!(non_associative_chain, "x := a - b - c", 1, "parentheses");
rejects!(missing_expression, "x := ]", 1, "unexpected");
rejects!(
    bad_indentation,
    "SEQ\n   SKIP",
    2,
    "indented more than one level"
);
rejects!(unknown_character, "x := 1 $ 2", 1, "not an occam token");
rejects!(unclosed_string, "x := \"abc", 1, "not closed");
rejects!(
    expected_list_in_occam_terms,
    "SEQ\n  x := ]",
    2,
    "expected one of"
);

#[test]
fn several_errors_in_one_run() {
    let errs = errors(&proc_body(
        "SEQ\n  x := a + b * c\n  y := ]\n  z := p AND q OR r",
    ));
    let lines: Vec<usize> = errs.iter().map(|(l, _)| *l).collect();
    assert!(
        lines.contains(&3) && lines.contains(&4) && lines.contains(&5),
        "{errs:#?}"
    );
}

#[test]
fn top_level_error_recovery_continues() {
    let errs = errors("PROC p ()\n  SKIP\n:\nINT x y:\nPROC q ()\n  x := ]\n:\n");
    let lines: Vec<usize> = errs.iter().map(|(l, _)| *l).collect();
    assert!(lines.contains(&4) && lines.contains(&6), "{errs:#?}");
}

#[test]
fn operator_errors_leave_the_tree_complete_but_dropped_lines_do_not() {
    let soft = common::parse(&proc_body("x := a + b * c"));
    assert!(soft.has_errors() && soft.complete);
    let hard = common::parse(&proc_body("SEQ\n  x := ]\n  SKIP"));
    assert!(hard.has_errors() && !hard.complete);
    let bad_token = common::parse(&proc_body("x := 1 $ 2"));
    assert!(!bad_token.complete);
    let missing = occ_grammar::parse_source(
        "m.occ",
        "#INCLUDE \"gone.inc\"\n",
        &mut std::collections::HashMap::new(),
    );
    assert!(!missing.complete);
    assert!(common::parse(&proc_body("SKIP")).complete);
}

#[test]
fn asm_and_guy_blocks_are_opaque() {
    let p = process("SEQ\n  ASM\n    LDC #0\n    ST x -- $$ not occam\n  GUY\n    LDL 1\n  SKIP");
    let ProcessKind::Seq { body, .. } = p.kind else {
        panic!()
    };
    let ProcessKind::Asm(block) = &body[0].kind else {
        panic!("{:?}", body[0].kind)
    };
    assert_eq!(block.lines, ["LDC #0", "ST x -- $$ not occam"]);
    assert!(matches!(
        &body[1].kind,
        ProcessKind::Asm(AsmBlock { guy: true, .. })
    ));
    assert!(matches!(body[2].kind, ProcessKind::Skip));
}

#[test]
fn valof_block_opening_on_the_line_of_its_parenthesis() {
    let text = "SEQ\n  []INT b IS [a FROM 1 FOR (INT r :\n                            VALOF\n                              r := 2\n                              RESULT r\n                           )] :\n  SKIP";
    let p = process(text);
    let ProcessKind::Seq { body, .. } = p.kind else {
        panic!()
    };
    let ProcessKind::Scope { decls, .. } = &body[0].kind else {
        panic!()
    };
    let DeclKind::Abbrev { value, .. } = &decls[0].kind else {
        panic!()
    };
    let ExprKind::Slice {
        count: Some(count), ..
    } = &value.kind
    else {
        panic!()
    };
    let ExprKind::Valof(v) = &count.kind else {
        panic!("{:?}", count.kind)
    };
    assert_eq!(v.decls.len(), 1);
}

/// An ASM block keeps its lines and where each is; `parse_expression` reads an operand written
/// over several of them (a VALOF inside a subscript) with spans into the program text.
#[test]
fn asm_operand_over_lines_parses_with_its_spans() {
    let text = "PROC p ()\n  ASM\n    ST ar[(INT r :\n           VALOF\n             r := 1\n             RESULT r\n          )]\n:\n";
    let program = parse_ok(text);
    let ProcessKind::Asm(block) = &body_of(&program).kind else {
        panic!("not an ASM block");
    };
    assert_eq!(block.lines.len(), 5);
    let operand = |i: usize| {
        let s = block.line_spans[i];
        (s.start, &text[s.start..s.end])
    };
    let (first_at, first) = operand(0);
    assert_eq!(first, "ST ar[(INT r :");
    // The operand starts after `ST `: its line is given from the kept column, blanked.
    let mut lines = vec![(first_at, format!("   {}", &first[3..]))];
    lines.extend((1..5).map(|i| (operand(i).0, operand(i).1.to_string())));
    let refs: Vec<(usize, &str)> = lines.iter().map(|(a, s)| (*a, s.as_str())).collect();
    let e = occ_grammar::parser::parse_expression(&refs).expect("the operand parses");
    assert!(matches!(e.kind, ExprKind::Subscript { .. }));
    assert_eq!(
        &text[e.span.start..e.span.end].lines().next(),
        &Some("ar[(INT r :")
    );
    let bad = occ_grammar::parser::parse_expression(&[(first_at, "   x +)")]);
    assert!(bad.is_err());
}
