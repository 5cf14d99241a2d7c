//! The IEEE, transputer-arithmetic and bit predefines: the native helpers called directly, and
//! occam programs that use them end to end.

mod common;

use common::run;
use occ_codegen::native;

/// Calls helper `name` with the given argument words (INTs only) and returns its output words.
fn call_ints(name: &str, args: &[i64]) -> [u64; 3] {
    let h = native::helper(name).expect("helper");
    let mut out = [0u64; 3];
    let p = out.as_mut_ptr();
    // SAFETY: the table says these helpers take `args.len()` i64s and the output pointer.
    unsafe {
        match args {
            [a] => std::mem::transmute::<*const u8, extern "C" fn(i64, *mut u64)>(h.addr)(*a, p),
            [a, b] => std::mem::transmute::<*const u8, extern "C" fn(i64, i64, *mut u64)>(h.addr)(
                *a, *b, p,
            ),
            [a, b, c] => std::mem::transmute::<*const u8, extern "C" fn(i64, i64, i64, *mut u64)>(
                h.addr,
            )(*a, *b, *c, p),
            _ => panic!("arity"),
        }
    }
    out
}

#[test]
fn unpacksn_and_roundsn_match_the_inmos_examples() {
    assert_eq!(
        call_ints("UNPACKSN", &[0x4049_0FDB]),
        [0xC90F_DB00, 0x80, 1]
    );
    assert_eq!(call_ints("UNPACKSN", &[1]), [0x100, 1, 1]);
    assert_eq!(
        call_ints("UNPACKSN", &[0x7FC0_0001]),
        [0x4000_0100, 0xFF, 3]
    );
    assert_eq!(call_ints("UNPACKSN", &[0x7F80_0000])[2], 2);
    assert_eq!(call_ints("UNPACKSN", &[0])[2], 0);
    let r = |e, f: u32, g| call_ints("ROUNDSN", &[e, f as i32 as i64, g])[0];
    assert_eq!(r(0x80, 0xC90F_DB00, 0), 0x4049_0FDB);
    assert_eq!(r(0x80, 0xC90F_DB80, 0), 0x4049_0FDC);
    assert_eq!(r(0x80, 0xC90F_DA80, 0), 0x4049_0FDA);
    assert_eq!(r(0x80, 0xC90F_DA80, 0x3000), 0x4049_0FDB);
    assert_eq!(r(1, 0x100, 0), 1);
}

#[test]
fn fracmul_rounds_like_the_transputer() {
    let f = |x: i64, y: i64| call_ints("FRACMUL", &[x, y])[0] as u32 as i32;
    assert_eq!(f(1 << 30, 1 << 30), 1 << 29); // 0.5 * 0.5
    assert_eq!(f(-(1 << 30), 1 << 30), -(1 << 29));
    assert_eq!(f(1, 1), 0); // 2^-62 rounds to 0
    assert_eq!(f(0x4000_0000, 3), 2); // 1.5 ulp: ties to even
}

#[test]
fn crc_word_and_byte() {
    // Shifting in zero data with a zero CRC gives zero; a set top bit feeds the generator.
    assert_eq!(call_ints("CRCWORD", &[0, 0, 0x1021])[0], 0);
    assert_eq!(
        call_ints("CRCBYTE", &[0, i32::MIN as i64, 0x1021])[0],
        0x1021 << 7
    );
    assert_eq!(call_ints("CRCWORD", &[1, 0, 0x1021])[0], 1);
}

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
