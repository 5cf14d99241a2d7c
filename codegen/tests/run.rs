//! End-to-end tests: occam programs compiled with Cranelift and run in-process.

mod common;

use common::{run, run_error, run_with};

#[test]
fn hello_world_through_the_course_library() {
    let src = r#"#INCLUDE "course.module"
PROC hello (CHAN BYTE keyboard?, screen!, error!)
  SEQ
    out.string ("Hello, world!*n", 0, screen!)
:
"#;
    assert_eq!(run(src), "Hello, world!\n");
}

#[test]
fn arithmetic_and_loops() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  INT sum:
  SEQ
    sum := 0
    SEQ i = 1 FOR 10
      sum := sum + (i * i)
    out.int (sum, 0, screen!)
    screen ! '*n'
    INT x:
    SEQ
      x := -17
      out.int (x / 5, 0, screen!)
      screen ! ' '
      out.int (x \ 5, 0, screen!)
      screen ! ' '
      out.int ((MOSTPOS INT) PLUS 1, 0, screen!)
      screen ! '*n'
:
"#;
    assert_eq!(run(src), "385\n-3 -2 -2147483648\n");
}

#[test]
fn par_and_channels() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  CHAN INT c:
  INT total:
  PAR
    SEQ i = 0 FOR 5
      c ! i
    SEQ
      total := 0
      SEQ i = 0 FOR 5
        INT v:
        SEQ
          c ? v
          total := total + v
      out.int (total, 0, screen!)
      screen ! '*n'
:
"#;
    assert_eq!(run(src), "10\n");
}

#[test]
fn alt_selects_ready_channels() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  CHAN INT a, b:
  PAR
    SEQ
      a ! 1
      b ! 2
      a ! 3
    INT sum:
    SEQ
      sum := 0
      SEQ i = 0 FOR 3
        INT x:
        ALT
          a ? x
            sum := sum + x
          b ? x
            sum := sum + (10 * x)
      out.int (sum, 0, screen!)
:
"#;
    assert_eq!(run(src), "24");
}

#[test]
fn timers_and_after() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  TIMER tim:
  INT t0, t1:
  SEQ
    tim ? t0
    tim ? AFTER t0 PLUS 2000
    tim ? t1
    IF
      (t1 MINUS t0) >= 2000
        out.string ("ok", 0, screen!)
      TRUE
        out.string ("early", 0, screen!)
:
"#;
    assert_eq!(run(src), "ok");
}

#[test]
fn proc_calls_with_reference_and_array_parameters() {
    let src = r#"#INCLUDE "course.module"
PROC double (INT x)
  x := x * 2
:
PROC fill ([]INT a, VAL INT v)
  SEQ i = 0 FOR SIZE a
    a[i] := v + i
:
PROC main (CHAN BYTE keyboard?, screen!, error!)
  [4]INT xs:
  INT y:
  SEQ
    y := 21
    double (y)
    fill (xs, 100)
    out.int (y, 0, screen!)
    screen ! ' '
    out.int (xs[3], 0, screen!)
:
"#;
    assert_eq!(run(src), "42 103");
}

#[test]
fn overflow_is_a_runtime_error_with_its_line() {
    let src = "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  INT x:\n  SEQ\n    x := MOSTPOS INT\n    x := x + 1\n:\n";
    let e = run_error(src);
    assert!(e.contains("test.occ:5"), "{e}");
    assert!(e.contains("overflow"), "{e}");
}

#[test]
fn subscript_out_of_range_is_a_runtime_error() {
    let src = "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  [3]INT a:\n  INT i:\n  SEQ\n    i := 3\n    a[i] := 0\n:\n";
    let e = run_error(src);
    assert!(e.contains("test.occ:6") && e.contains("subscript"), "{e}");
}

#[test]
fn stop_halts_with_its_line() {
    let src = "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  SEQ\n    SKIP\n    STOP\n:\n";
    let e = run_error(src);
    assert!(e.contains("test.occ:4") && e.contains("STOP"), "{e}");
}

#[test]
fn deadlock_is_reported() {
    let src =
        "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT c:\n  INT x:\n  c ? x\n:\n";
    let o = run_with(src, "");
    match o.result {
        Err(occ_runtime::RunError::Deadlock(_)) => {}
        other => panic!("expected deadlock, got {other:?}"),
    }
}

#[test]
fn echo_keyboard_to_screen() {
    let src = r#"PROC main (CHAN BYTE keyboard?, screen!, error!)
  BYTE ch:
  SEQ
    ch := ' '
    WHILE ch <> '.'
      SEQ
        keyboard ? ch
        screen ! ch
:
"#;
    let o = run_with(src, "abc.");
    assert!(o.result.is_ok());
    assert_eq!(o.stdout, "abc.");
}

#[test]
fn par_branches_calling_nested_procs_keep_their_static_links() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  PROC P ()
    [4]INT a :
    #PRAGMA SHARED a
    PROC Q (VAL INT i)
      a[i] := i + 1
    :
    SEQ
      SEQ i = 0 FOR 4
        a[i] := 0
      PAR
        SKIP
        PAR i = 0 FOR 4
          Q(i)
      SEQ i = 0 FOR 4
        out.int (a[i], 0, screen!)
  :
  SEQ
    P()
    P()
:
"#;
    assert_eq!(run(src), "12341234");
}

/// The tests compile through the one front end, so `#OPTION` acts here as in `occ run`: with
/// `#OPTION "N"` a PAR the usage rules refuse (a variable subscript against a constant one)
/// compiles and runs; without it, it is refused.
#[test]
fn option_n_switches_the_usage_rules_off() {
    let program = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  [2]INT a:
  INT i:
  SEQ
    i := 1
    PAR
      a[0] := 10
      a[i] := 20
    out.int (a[0] + a[1], 0, screen!)
:
"#;
    let refused = common::try_compile(program, &occ_codegen::IntrinsicSet::new());
    let Err(message) = refused else {
        panic!("the usage rules should refuse the PAR");
    };
    assert!(
        message.contains("test.occ:9:") && message.contains("`a`"),
        "{message}"
    );
    assert_eq!(run(&format!("#OPTION \"N\"\n{program}")), "30");
}
