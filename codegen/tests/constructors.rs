//! Array constructors `[i = base FOR n (STEP s) | e]` with a constant count.

mod common;

use common::run;

#[test]
fn constructors_with_and_without_step() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  INT k :
  SEQ
    k := 10
    VAL [5]INT squares IS [i = 0 FOR 5 | i * i] :
    SEQ j = 0 FOR 5
      SEQ
        out.int (squares[j], 0, screen!)
        screen ! ' '
    [4]INT evens :
    SEQ
      evens := [i = k FOR 4 STEP 2 | i]
      SEQ j = 0 FOR 4
        SEQ
          out.int (evens[j], 0, screen!)
          screen ! ' '
    VAL [3][2]INT pairs IS [i = 1 FOR 3 | [i, -i]] :
    out.int (pairs[2][0] + pairs[1][1], 0, screen!)
:
"#;
    assert_eq!(run(src), "0 1 4 9 16 10 12 14 16 1");
}
