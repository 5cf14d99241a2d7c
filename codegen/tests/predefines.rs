//! The IEEE, transputer-arithmetic and bit predefines: occam programs that use them end to end
//! (the runtime's tests call its predefine intrinsics directly).

mod common;

use common::run;

/// Runs an occam body that prints with `out.int`/`out.string` and returns its output.
fn occam(body: &str) -> String {
    let src = format!(
        "#INCLUDE \"course.module\"\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n{body}:\n"
    );
    run(&src)
}

#[test]
fn bit_predefines() {
    let out = occam(
        r#"  SEQ
    out.int (BITCOUNT (#555, 4), 0, screen!)
    screen ! ' '
    out.int (BITREVNBITS (#1234, 16), 0, screen!)
    screen ! ' '
    out.int (BITREVNBITS (1, 0), 0, screen!)
    screen ! ' '
    out.int (BITREVWORD (1), 0, screen!)
    screen ! ' '
    out.int (BITREVNBITS (1, 32), 0, screen!)
"#,
    );
    assert_eq!(out, "10 11336 0 -2147483648 -2147483648");
}

#[test]
fn ieee_compare_and_equality() {
    let out = occam(
        r#"  VAL INT32 quiet.nan IS #7FC00000 (INT32) :
  VAL REAL32 nan RETYPES quiet.nan :
  SEQ
    out.int (IEEECOMPARE (1.0 (REAL32), 2.0 (REAL32)), 0, screen!)
    out.int (IEEECOMPARE (2.0 (REAL32), 2.0 (REAL32)), 0, screen!)
    out.int (DIEEECOMPARE (3.0 (REAL64), 2.0 (REAL64)), 0, screen!)
    out.int (IEEECOMPARE (nan, 2.0 (REAL32)), 0, screen!)
    out.int (INT REAL32EQ (nan, nan), 0, screen!)
    out.int (INT REAL64GT (2.0 (REAL64), 1.0 (REAL64)), 0, screen!)
"#,
    );
    assert_eq!(out, "-101201");
}

#[test]
fn ieee_op_rounding_modes_and_remainder() {
    let out = occam(
        r#"  REAL32 r, dn, one, three :
  REAL64 d :
  BOOL b :
  INT32 n :
  INT e :
  SEQ
    one, three := 1.0 (REAL32), 3.0 (REAL32)
    b, r := IEEE32OP (one, 2, 3, three)
    b, dn := IEEE32OP (one, 3, 3, three)
    out.int (INT (r > dn), 0, screen!)
    out.int (INT ((r = (one / three)) OR (dn = (one / three))), 0, screen!)
    b, r := IEEE32OP (one, 0, 3, 0.0 (REAL32))
    out.int (INT b, 0, screen!)
    b, d := IEEE64REM (10.0 (REAL64), 6.0 (REAL64))
    out.int (INT ROUND d, 0, screen!)
    e, d := DFLOATING.UNPACK (12.0 (REAL64))
    out.int (e, 0, screen!)
    out.int (INT ROUND (d * 4.0 (REAL64)), 0, screen!)
    b, n, r := ARGUMENT.REDUCE (7.0 (REAL32), 3.0 (REAL32), 0.0 (REAL32))
    out.int (INT b, 0, screen!)
    out.int (INT n, 0, screen!)
    out.int (INT ROUND r, 0, screen!)
"#,
    );
    assert_eq!(out, "111-236121");
}
