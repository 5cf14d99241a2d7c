//! Comparison of parenthesised expression lists: `(a, b) = (c, d)` and `<>`.

mod common;

use common::run;

#[test]
fn list_equality_compares_every_pair() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  INT a, b, c, d :
  SEQ
    a, b, c, d := 5, 6, 5, 2
    out.int (INT ((a, b) = (c, d)), 0, screen!)
    out.int (INT ((a, b) <> (c, d)), 0, screen!)
    d := 6
    out.int (INT ((a, b) = (c, d)), 0, screen!)
    out.int (INT ((a, b) <> (c, d)), 0, screen!)
:
"#;
    assert_eq!(run(src), "0110");
}
