//! INT to REAL conversions: ROUND rounds to nearest (ties to even), TRUNC toward zero.

mod common;

use common::run;

#[test]
fn int_to_real_trunc_rounds_toward_zero() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  INT x, y :
  INT64 z :
  REAL32 r :
  REAL64 d :
  SEQ
    x, y := 16777219, -16777219
    r := REAL32 TRUNC x
    out.int (INT TRUNC r, 0, screen!)
    screen ! ' '
    r := REAL32 ROUND x
    out.int (INT TRUNC r, 0, screen!)
    screen ! ' '
    r := REAL32 TRUNC y
    out.int (INT TRUNC r, 0, screen!)
    screen ! ' '
    r := REAL32 ROUND y
    out.int (INT TRUNC r, 0, screen!)
    screen ! ' '
    z := 9007199254740995 (INT64)
    d := REAL64 TRUNC z
    out.int (INT ((INT64 TRUNC d) = 9007199254740994 (INT64)), 0, screen!)
    d := REAL64 ROUND z
    out.int (INT ((INT64 TRUNC d) = 9007199254740996 (INT64)), 0, screen!)
    z := MOSTPOS INT64
    d := REAL64 TRUNC z
    out.int (INT (d < 9223372036854775807.0 (REAL64)), 0, screen!)
    r := REAL32 TRUNC z
    out.int (INT (r < 9223372036854775807.0 (REAL32)), 0, screen!)
:
"#;
    assert_eq!(run(src), "16777218 16777220 -16777218 -16777220 1111");
}
