//! Only what the entry PROC reaches is compiled: unused PROCs, FUNCTIONs and EXTERNALs are
//! left out and counted, and the program still runs.

mod common;

use occ_codegen::IntrinsicSet;
use occ_codegen::reach::LeftOut;

/// A used PROC with a used nested PROC and an unused one, a FUNCTION used only in a constant,
/// an operator FUNCTION, and an unused PROC and FUNCTION at the top.
const PROGRAM: &str = r#"PROC unused (CHAN BYTE out!)
  out ! 'x'
:
INT FUNCTION twice (VAL INT n) IS 2 * n :
INT FUNCTION never (VAL INT n) IS n - 1 :
INT FUNCTION "+" (VAL BOOL a, VAL BOOL b) IS 7 :
PROC shout (VAL INT n, CHAN BYTE out!)
  PROC dead (CHAN BYTE o!)
    o ! 'd'
  :
  PROC letter (VAL BYTE b, CHAN BYTE o!)
    o ! b
  :
  SEQ i = 0 FOR n
    letter ('a', out!)
:
PROC main (CHAN BYTE keyboard?, screen!, error!)
  VAL INT three IS twice (2) - 1 :
  SEQ
    shout (three, screen!)
    shout (TRUE + FALSE, screen!)
:
"#;

#[test]
fn unused_procs_and_functions_are_left_out_and_counted() {
    let c = common::compile(PROGRAM);
    assert_eq!(
        c.left_out,
        LeftOut {
            procs_left_out: 2,
            procs: 5,
            functions_left_out: 1,
            functions: 3,
            externals_left_out: 0,
            externals: 0,
        }
    );
    assert_eq!(
        c.left_out.describe("p.occ").as_deref(),
        Some("p.occ: 3 of 8 PROCs and FUNCTIONs not compiled: nothing calls them")
    );
    // The left-out PROCs have no code: the runtime's tables name only what was compiled.
    let names: Vec<&str> = c.info.procs.iter().map(|p| p.name.as_str()).collect();
    assert!(
        !names.contains(&"unused") && !names.contains(&"dead"),
        "{names:?}"
    );
    assert!(
        names.contains(&"letter") && names.contains(&"shout"),
        "{names:?}"
    );
    assert_eq!(common::run(PROGRAM), "aaaaaaaaaa");
}

#[test]
fn a_program_that_uses_everything_leaves_nothing_out() {
    let src = "PROC say (CHAN BYTE o!)\n  o ! 'k'\n:\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  say (screen!)\n:\n";
    let c = common::compile(src);
    assert_eq!(c.left_out.procs_left_out, 0);
    assert_eq!(c.left_out.procs, 2);
    assert_eq!(c.left_out.describe("p.occ"), None);
    assert_eq!(common::run(src), "k");
}

#[test]
fn the_course_library_costs_only_what_is_called() {
    let src = "#INCLUDE \"course.module\"\nPROC main (CHAN BYTE keyboard?, screen!, error!)\n  out.int (42, 0, screen!)\n:\n";
    let c = common::compile(src);
    let l = c.left_out;
    assert!(l.procs > 20, "{l:?}");
    // main, out.int and what out.int calls.
    assert!(l.procs - l.procs_left_out < 6, "{l:?}");
    assert_eq!(common::run(src), "42");
}

/// An EXTERNAL that no table links, called only in a PROC nothing calls.
const UNLINKED: &str = r#"#PRAGMA EXTERNAL "PROC NO.SUCH.INTRINSIC (VAL INT n) = 0"
PROC never (VAL INT n)
  NO.SUCH.INTRINSIC (n)
:
PROC main (CHAN BYTE keyboard?, screen!, error!)
  screen ! 'y'
:
"#;

/// Binding errors stay the front end's: `occ check` and `occ run` still refuse a call of an
/// intrinsic that is not linked in, wherever it is (as a linker refuses an unresolved name in
/// any module it links). Code generation binds only what it compiles, so given the checked
/// program it compiles the rest.
#[test]
fn an_unlinked_intrinsic_in_dead_code_is_reported_but_not_compiled() {
    let err = common::try_compile(UNLINKED, &IntrinsicSet::new())
        .err()
        .expect("the front end reports the unbound call");
    assert!(
        err.contains("no native intrinsic NO.SUCH.INTRINSIC"),
        "{err}"
    );
    assert!(err.contains("test.occ:3:"), "{err}");

    let front = occ_compiler::check_source("test.occ", UNLINKED, &mut common::StdlibLoader);
    let checked = front.checked.as_ref().expect("the checker accepts it");
    let p = &front.parsed;
    let c = occ_codegen::compile_with(&p.program, checked, &p.map, &IntrinsicSet::new())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((c.left_out.procs_left_out, c.left_out.procs), (1, 2));
    assert_eq!(
        (c.left_out.externals_left_out, c.left_out.externals),
        (1, 1)
    );

    // Called from the entry, the same intrinsic stops code generation.
    let live = UNLINKED.replace("  screen ! 'y'", "  never (1)");
    let front = occ_compiler::check_source("test.occ", &live, &mut common::StdlibLoader);
    let checked = front.checked.as_ref().expect("the checker accepts it");
    let p = &front.parsed;
    let e = occ_codegen::compile_with(&p.program, checked, &p.map, &IntrinsicSet::new())
        .err()
        .expect("an unbound call in live code");
    let found: Vec<String> = e.diagnostics().iter().map(|d| d.message.clone()).collect();
    assert_eq!(
        found,
        ["no native intrinsic NO.SUCH.INTRINSIC is linked into occ"]
    );
}
