//! `#PRAGMA EXTERNAL` routines bound to a test crate's own intrinsic table: every parameter
//! kind of the ABI end to end, and the link errors.

mod common;

use common::Buf;
use occ_codegen::IntrinsicSet;
use occ_runtime::abi::Word;
use occ_runtime::intrinsic::{Intrinsic, MachineType, ParamKind::*};
use occ_runtime::{HostIo, NodeConfig};

/// `REAL32 FUNCTION T.SUM32 (VAL []REAL32 xs)`.
unsafe extern "C" fn sum32(p: *const f32, n: Word) -> f32 {
    // SAFETY: the ABI passes a valid array.
    unsafe { std::slice::from_raw_parts(p, n.max(0) as usize) }
        .iter()
        .sum()
}

/// `PROC T.FILL ([]INT out, VAL INT v, VAL []BOOL flags, RESULT INT n, RESULT REAL32 r,
/// RESULT BOOL b, []REAL32 xs)`: fills `out` with `v`, counts TRUE flags into `n`, halves `r`
/// of the first `xs`, doubles every `xs`, `b` says whether any flag is set.
#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn fill(
    out: *mut i32,
    out_n: Word,
    v: Word,
    flags: *const u8,
    flags_n: Word,
    n: *mut Word,
    r: *mut f32,
    b: *mut Word,
    xs: *mut f32,
    xs_n: Word,
) {
    // SAFETY: the ABI passes valid arrays and result words.
    unsafe {
        std::slice::from_raw_parts_mut(out, out_n as usize).fill(v as i32);
        let f = std::slice::from_raw_parts(flags, flags_n as usize);
        let set = f.iter().filter(|x| **x != 0).count();
        *n = set as Word;
        *b = Word::from(set > 0);
        let xs = std::slice::from_raw_parts_mut(xs, xs_n as usize);
        *r = xs.first().copied().unwrap_or(0.0) / 2.0;
        xs.iter_mut().for_each(|x| *x *= 2.0);
    }
}

static TABLE: &[Intrinsic] = &[
    Intrinsic {
        name: "T.SUM32",
        params: &[ValReal32s],
        result: Some(MachineType::F32),
        addr: sum32 as *const u8,
    },
    Intrinsic {
        name: "T.FILL",
        params: &[
            VarInts,
            ValInt,
            ValBools,
            ResultInt,
            ResultReal32,
            ResultBool,
            VarReal32s,
        ],
        result: None,
        addr: fill as *const u8,
    },
];

/// Compiles `src` against `TABLE`; an error comes back as its diagnostics, one
/// `file:line: message` each.
fn build(src: &str) -> Result<occ_codegen::Compiled, String> {
    common::try_compile(src, &IntrinsicSet::new().with(TABLE))
}

fn run(src: &str) -> String {
    let c = build(src).unwrap_or_else(|e| panic!("{e}"));
    let out = Buf::default();
    let host = HostIo::new(
        Box::new(std::io::empty()),
        Box::new(out.clone()),
        Box::new(std::io::sink()),
    );
    let (r, _) = c.run(NodeConfig::default(), host);
    r.unwrap_or_else(|e| panic!("{e}"));
    String::from_utf8_lossy(&out.0.lock().expect("buffer")).into_owned()
}

const DECLS: &str = r#"#INCLUDE "course.module"
#PRAGMA EXTERNAL "REAL32 FUNCTION T.SUM32 (VAL []REAL32 xs) = 0"
#PRAGMA EXTERNAL "PROC T.FILL ([]INT out, VAL INT v, VAL []BOOL flags, RESULT INT n, RESULT REAL32 r, RESULT BOOL b, []REAL32 xs) = 0"
"#;

#[test]
fn every_parameter_kind_crosses_the_abi() {
    let src = format!(
        "{DECLS}PROC main (CHAN BYTE keyboard?, screen!, error!)
  [4]INT a:
  [3]BOOL f:
  [2]REAL32 xs:
  INT n:
  REAL32 r:
  BOOL b:
  SEQ
    f := [TRUE, FALSE, TRUE]
    xs := [3.0, 5.0]
    T.FILL (a, 7, f, n, r, b, xs)
    out.int (a[0] + a[3], 0, screen!)
    out.string (\" \", 0, screen!)
    out.int (n, 0, screen!)
    out.string (\" \", 0, screen!)
    out.int (INT ROUND (r * 10.0), 0, screen!)
    out.string (\" \", 0, screen!)
    out.bool (b, 0, screen!)
    out.string (\" \", 0, screen!)
    out.int (INT ROUND (T.SUM32 (xs)), 0, screen!)
    out.string (\" \", 0, screen!)
    out.int (INT ROUND (T.SUM32 ([1.5, 2.5])), 0, screen!)
:
"
    );
    assert_eq!(run(&src), "14 2 15 TRUE 16 4");
}

#[test]
fn a_call_of_an_unlinked_external_is_an_error_at_the_call() {
    let src = format!(
        "{DECLS}#PRAGMA EXTERNAL \"PROC T.NONE (VAL INT x) = 0\"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  T.NONE (1)
:
"
    );
    let e = build(&src).err().expect("link error");
    assert!(
        e.contains("test.occ:6:") && e.contains("no native intrinsic T.NONE is linked into occ"),
        "{e}"
    );
    // Declared but never called: no error.
    let unused = format!(
        "{DECLS}#PRAGMA EXTERNAL \"PROC T.NONE (VAL INT x) = 0\"\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  SKIP\n:\n"
    );
    assert!(build(&unused).is_ok());
}

#[test]
fn a_signature_that_disagrees_with_the_table_is_an_error_at_the_pragma() {
    for (decl, why) in [
        (
            "REAL64 FUNCTION T.SUM32 (VAL []REAL32 xs) = 0",
            "returns REAL64 here",
        ),
        (
            "REAL32 FUNCTION T.SUM32 (VAL []REAL64 xs) = 0",
            "parameter 1 is `VAL []REAL64`",
        ),
        (
            "REAL32 FUNCTION T.SUM32 (VAL []REAL32 xs, ys) = 0",
            "2 parameters here, 1",
        ),
        ("PROC T.SUM32 (VAL []REAL32 xs) = 0", "a PROC here"),
    ] {
        let src = format!(
            "#PRAGMA EXTERNAL \"{decl}\"\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  SKIP\n:\n"
        );
        let e = build(&src).err().expect("link error");
        assert!(e.contains("test.occ:1:") && e.contains(why), "{decl}: {e}");
    }
}

/// `PROC T.BUMP (INT n, REAL32 r, BOOL b)`: reference scalars are in/out.
unsafe extern "C" fn bump(n: *mut Word, r: *mut f32, b: *mut Word) {
    // SAFETY: the ABI passes valid result words.
    unsafe {
        *n += 1;
        *r *= 2.0;
        *b = 1 - *b;
    }
}

static BUMP: &[Intrinsic] = &[Intrinsic {
    name: "T.BUMP",
    params: &[ResultInt, ResultReal32, ResultBool],
    result: None,
    addr: bump as *const u8,
}];

#[test]
fn reference_scalars_are_read_and_written() {
    let src = "#INCLUDE \"course.module\"
#PRAGMA EXTERNAL \"PROC T.BUMP (INT n, REAL32 r, BOOL b) = 0\"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  INT n:
  REAL32 r:
  BOOL b:
  SEQ
    n, r, b := -5, 1.5, TRUE
    T.BUMP (n, r, b)
    out.int (n, 0, screen!)
    out.string (\" \", 0, screen!)
    out.int (INT ROUND r, 0, screen!)
    out.string (\" \", 0, screen!)
    out.bool (b, 0, screen!)
:
";
    let c =
        common::try_compile(src, &IntrinsicSet::new().with(BUMP)).unwrap_or_else(|e| panic!("{e}"));
    let out = Buf::default();
    let host = HostIo::new(
        Box::new(std::io::empty()),
        Box::new(out.clone()),
        Box::new(std::io::sink()),
    );
    let (r, _) = c.run(NodeConfig::default(), host);
    r.unwrap_or_else(|e| panic!("{e}"));
    let text = String::from_utf8_lossy(&out.0.lock().expect("buffer")).into_owned();
    assert_eq!(text, "-4 3 FALSE");
}
