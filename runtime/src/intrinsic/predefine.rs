//! The predefined routines that are awkward in Cranelift IR, as intrinsics: IEEE arithmetic with a
//! rounding mode, IEEE remainder, FLOATING.UNPACK, ARGUMENT.REDUCE, UNPACKSN/ROUNDSN, FRACMUL and
//! the CRC routines.
//!
//! They are [`Intrinsic`]s like the others, with one difference of use: the occam predefine's
//! results are `RESULT` parameters after its arguments (the caller passes the address of a word
//! for each and loads it after the call). They are not in [`super::INTRINSICS`]: a program cannot
//! bind them with `#PRAGMA EXTERNAL`, only call the predefines. They never block, allocate or
//! panic.

use super::Intrinsic;
use super::ParamKind::{
    ResultBool, ResultInt, ResultReal32, ResultReal64, ValInt, ValReal32, ValReal64,
};
use crate::abi::Word;

/// Declares each predefine intrinsic once, as a constant and in [`PREDEFINES`].
macro_rules! predefines {
    ($($(#[$doc:meta])* $id:ident = $name:literal, [$($p:expr),*], $f:path;)*) => {
        $(
            $(#[$doc])*
            pub const $id: Intrinsic = Intrinsic {
                name: $name,
                params: &[$($p),*],
                result: None,
                addr: $f as *const u8,
            };
        )*

        /// Every predefine intrinsic.
        pub static PREDEFINES: &[Intrinsic] = &[$($id),*];
    };
}

predefines! {
    /// `IEEE32OP`: (error, value).
    IEEE32OP = "IEEE32OP",
        [ValReal32, ValInt, ValInt, ValReal32, ResultBool, ResultReal32], ieee32op;
    /// `IEEE64OP`: (error, value).
    IEEE64OP = "IEEE64OP",
        [ValReal64, ValInt, ValInt, ValReal64, ResultBool, ResultReal64], ieee64op;
    /// `IEEE32REM`: (error, value).
    IEEE32REM = "IEEE32REM", [ValReal32, ValReal32, ResultBool, ResultReal32], ieee32rem;
    /// `IEEE64REM`: (error, value).
    IEEE64REM = "IEEE64REM", [ValReal64, ValReal64, ResultBool, ResultReal64], ieee64rem;
    /// `FLOATING.UNPACK`: (exponent, fraction).
    FLOATING_UNPACK = "FLOATING.UNPACK", [ValReal32, ResultInt, ResultReal32], unpack32;
    /// `DFLOATING.UNPACK`: (exponent, fraction).
    DFLOATING_UNPACK = "DFLOATING.UNPACK", [ValReal64, ResultInt, ResultReal64], unpack64;
    /// `ARGUMENT.REDUCE`: (ok, N, remainder).
    ARGUMENT_REDUCE = "ARGUMENT.REDUCE",
        [ValReal32, ValReal32, ValReal32, ResultBool, ResultInt, ResultReal32], reduce32;
    /// `DARGUMENT.REDUCE`: (ok, N, remainder).
    DARGUMENT_REDUCE = "DARGUMENT.REDUCE",
        [ValReal64, ValReal64, ValReal64, ResultBool, ResultInt, ResultReal64], reduce64;
    /// `UNPACKSN`: (fraction, exponent, type).
    UNPACKSN = "UNPACKSN", [ValInt, ResultInt, ResultInt, ResultInt], unpacksn;
    /// `ROUNDSN`: the REAL32 bits.
    ROUNDSN = "ROUNDSN", [ValInt, ValInt, ValInt, ResultInt], roundsn;
    /// `FRACMUL`: the product.
    FRACMUL = "FRACMUL", [ValInt, ValInt, ResultInt], fracmul;
    /// `CRCWORD`: the CRC.
    CRCWORD = "CRCWORD", [ValInt, ValInt, ValInt, ResultInt], crcword;
    /// `CRCBYTE`: the CRC.
    CRCBYTE = "CRCBYTE", [ValInt, ValInt, ValInt, ResultInt], crcbyte;
}

/// An INT result: the low 32 bits, sign-extended to a word.
fn int(v: i64) -> Word {
    v as i32 as Word
}

/// IEEE arithmetic on one float type with an explicit rounding mode.
macro_rules! ieee_ops {
    ($t:ty, $op:ident, $rem:ident, $unpack:ident, $reduce:ident) => {
        /// `IEEExxOP(X, Rm, Op, Y)`: Op 0 +, 1 -, 2 *, 3 /; Rm 0 nearest, 1 toward zero,
        /// 2 toward +inf, 3 toward -inf. Results: (error, value); error is TRUE when the
        /// result is NaN, or infinite from finite operands.
        ///
        /// # Safety
        /// `error` and `value` are writable.
        pub unsafe extern "C" fn $op(
            x: $t,
            rm: i64,
            op: i64,
            y: $t,
            error: *mut Word,
            value: *mut $t,
        ) {
            let (r, err) = match op {
                0 => two_sum!($t, x, y),
                1 => two_sum!($t, x, -y),
                2 => {
                    let r = x * y;
                    (r, x.mul_add(y, -r))
                }
                _ => {
                    let r = x / y;
                    let rem = (-r).mul_add(y, x);
                    (r, if y < 0.0 { -rem } else { rem })
                }
            };
            let r = if x.is_finite() && y.is_finite() {
                directed!($t, r, err, rm)
            } else {
                r
            };
            let bad = r.is_nan() || (r.is_infinite() && x.is_finite() && y.is_finite());
            // SAFETY: forwarded from the caller.
            unsafe {
                *error = bad as Word;
                *value = r;
            }
        }

        /// `IEEExxREM(X, Y)`: the IEEE remainder X - N*Y with N the nearest integer to X/Y
        /// (ties to even), exact. Results: (error, value); error is TRUE for a NaN result.
        ///
        /// # Safety
        /// `error` and `value` are writable.
        pub unsafe extern "C" fn $rem(x: $t, y: $t, error: *mut Word, value: *mut $t) {
            let r = ieee_rem!($t, x, y);
            // SAFETY: forwarded from the caller.
            unsafe {
                *error = r.is_nan() as Word;
                *value = r;
            }
        }

        /// `FLOATING.UNPACK(X)`: (n, f) with X = f * 2^n and 1 <= |f| < 2 for finite nonzero X;
        /// zero, infinities and NaN give (0, X).
        ///
        /// # Safety
        /// `exp` and `frac` are writable.
        pub unsafe extern "C" fn $unpack(x: $t, exp: *mut Word, frac: *mut $t) {
            let (mut n, mut f) = (0i64, x);
            if x.is_finite() && x != 0.0 {
                while f.abs() >= 2.0 {
                    f /= 2.0;
                    n += 1;
                }
                while f.abs() < 1.0 {
                    f *= 2.0;
                    n -= 1;
                }
            }
            // SAFETY: forwarded from the caller.
            unsafe {
                *exp = int(n);
                *frac = f;
            }
        }

        /// `ARGUMENT.REDUCE(X, Y, Y.err)`: (ok, N, X - N*(Y + Y.err)) with N the nearest integer
        /// to X/Y; ok is FALSE when N does not fit an INT32 or an operand is not finite.
        ///
        /// # Safety
        /// `ok`, `quotient` and `rem` are writable.
        pub unsafe extern "C" fn $reduce(
            x: $t,
            y: $t,
            yerr: $t,
            ok_out: *mut Word,
            quotient: *mut Word,
            rem: *mut $t,
        ) {
            let q = (x / y).round_ties_even();
            let ok = x.is_finite() && y.is_finite() && q.abs() <= i32::MAX as $t;
            let (n, r) = if ok {
                let r = (-q).mul_add(y, x);
                (q as i64, (-q).mul_add(yerr, r))
            } else {
                (0, x)
            };
            // SAFETY: forwarded from the caller.
            unsafe {
                *ok_out = ok as Word;
                *quotient = int(n);
                *rem = r;
            }
        }
    };
}

/// The rounded sum and the sign-carrying error of `a + b` (Knuth's TwoSum).
macro_rules! two_sum {
    ($t:ty, $a:expr, $b:expr) => {{
        let (a, b): ($t, $t) = ($a, $b);
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }};
}

/// Moves the nearest-rounded `r` (exact value r + err) to the rounding mode `rm`.
macro_rules! directed {
    ($t:ty, $r:expr, $err:expr, $rm:expr) => {{
        let (r, err): ($t, $t) = ($r, $err);
        if r.is_infinite() {
            match ($rm, r > 0.0) {
                (1, true) | (3, true) => <$t>::MAX,
                (1, false) | (2, false) => <$t>::MIN,
                _ => r,
            }
        } else {
            match $rm {
                1 if err != 0.0 && (err < 0.0) != (r < 0.0) && r != 0.0 => {
                    if r > 0.0 {
                        r.next_down()
                    } else {
                        r.next_up()
                    }
                }
                2 if err > 0.0 => r.next_up(),
                3 if err < 0.0 => r.next_down(),
                _ => r,
            }
        }
    }};
}

/// The exact IEEE remainder (as in fdlibm's `remainder`, built on the exact `%`).
macro_rules! ieee_rem {
    ($t:ty, $x:expr, $y:expr) => {{
        let (x, y): ($t, $t) = ($x, $y);
        if y == 0.0 || !x.is_finite() || y.is_nan() {
            <$t>::NAN
        } else if y.is_infinite() {
            x
        } else {
            let p = y.abs();
            let mut r = if p <= <$t>::MAX / 2.0 { x % (p + p) } else { x };
            let neg = r < 0.0;
            r = r.abs();
            if p < <$t>::MIN_POSITIVE * 2.0 {
                if r + r > p {
                    r -= p;
                    if r + r >= p {
                        r -= p;
                    }
                }
            } else {
                let h = 0.5 * p;
                if r > h {
                    r -= p;
                    if r >= h {
                        r -= p;
                    }
                }
            }
            if neg { -r } else { r }
        }
    }};
}

ieee_ops!(f32, ieee32op, ieee32rem, unpack32, reduce32);
ieee_ops!(f64, ieee64op, ieee64rem, unpack64, reduce64);

/// `UNPACKSN(X)` (transputer `unpacksn`): (frac, exp, type) of the REAL32 bits X: frac is the
/// mantissa (with the implied bit for normal numbers) shifted left 8, exp the biased exponent
/// (1 for denormals), type 0 zero, 1 number, 2 infinity, 3 NaN.
///
/// # Safety
/// `frac_out`, `exp_out` and `ty_out` are writable.
pub unsafe extern "C" fn unpacksn(
    x: i64,
    frac_out: *mut Word,
    exp_out: *mut Word,
    ty_out: *mut Word,
) {
    let x = x as u32;
    let e = (x >> 23) & 0xFF;
    let m = x & 0x7F_FFFF;
    let (frac, exp, ty) = match (e, m) {
        (0, 0) => (0, 0, 0),
        (0, m) => (m << 8, 1, 1),
        (0xFF, 0) => (0, 0xFF, 2),
        (0xFF, m) => (m << 8, 0xFF, 3),
        (e, m) => ((m | 0x80_0000) << 8, e, 1),
    };
    // SAFETY: forwarded from the caller.
    unsafe {
        *frac_out = int(frac as i64);
        *exp_out = int(exp as i64);
        *ty_out = ty;
    }
}

/// `ROUNDSN(Yexp, Yfrac, Yguard)` (transputer `roundsn`): packs a biased exponent and a
/// mantissa left-justified by 8 bits into REAL32 bits, rounding to nearest even on the low 8
/// bits of Yfrac and the guard word; overflow gives infinity. The sign is not represented.
///
/// # Safety
/// `out` is writable.
pub unsafe extern "C" fn roundsn(exp: i64, frac: i64, guard: i64, out: *mut Word) {
    let frac = frac as u32;
    let low = frac & 0xFF;
    let mut v = ((exp as i32 - 1).max(0) as u32)
        .wrapping_shl(23)
        .wrapping_add(frac >> 8);
    if low > 0x80 || (low == 0x80 && (guard as u32 != 0 || v & 1 == 1)) {
        v = v.wrapping_add(1);
    }
    if exp >= 0xFF || v >= 0x7F80_0000 {
        v = 0x7F80_0000;
    }
    // SAFETY: forwarded from the caller.
    unsafe { *out = int(v as i64) };
}

/// `FRACMUL(X, Y)`: the product of two fractions scaled by 2^31, rounded to nearest even,
/// wrapping as the transputer's `fmul` does for MOSTNEG INT * MOSTNEG INT.
///
/// # Safety
/// `out` is writable.
pub unsafe extern "C" fn fracmul(x: i64, y: i64, out: *mut Word) {
    let p = (x as i32 as i64)
        .wrapping_mul(y as i32 as i64)
        .wrapping_shl(1);
    let hi = (p >> 32) as i32;
    let lo = p as i32;
    let up = lo < 0 && (lo != i32::MIN || hi & 1 == 1);
    let r = if up { hi.wrapping_add(1) } else { hi };
    // SAFETY: forwarded from the caller.
    unsafe { *out = int(r as i64) };
}

/// Shifts `data` into the CRC `crc` (generator `generator`) `bits` bits at a time from the
/// most significant bit of the word.
fn crc(data: i64, crc: i64, generator: i64, bits: u32) -> i64 {
    let (mut d, mut c, g) = (data as u32, crc as u32, generator as u32);
    for _ in 0..bits {
        let top = c & 0x8000_0000 != 0;
        c = (c << 1) | (d >> 31);
        d <<= 1;
        if top {
            c ^= g;
        }
    }
    c as i32 as i64
}

/// `CRCWORD(data, CRCIn, generator)`: the CRC after shifting in all 32 bits of data.
///
/// # Safety
/// `out` is writable.
pub unsafe extern "C" fn crcword(data: i64, c: i64, g: i64, out: *mut Word) {
    // SAFETY: forwarded from the caller.
    unsafe { *out = int(crc(data, c, g, 32)) };
}

/// `CRCBYTE(data, CRCIn, generator)`: the CRC after shifting in the most significant byte of
/// data.
///
/// # Safety
/// `out` is writable.
pub unsafe extern "C" fn crcbyte(data: i64, c: i64, g: i64, out: *mut Word) {
    // SAFETY: forwarded from the caller.
    unsafe { *out = int(crc(data, c, g, 8)) };
}

#[cfg(test)]
mod test {
    use super::*;

    /// Calls the predefine intrinsic `i`, all of whose parameters are INTs, with the argument
    /// words `args`, and returns its results' low 32 bits.
    fn call_ints(i: &Intrinsic, args: &[i64]) -> Vec<u32> {
        let n = i.params.iter().filter(|k| k.is_written()).count();
        assert_eq!(args.len() + n, i.params.len(), "{}", i.name);
        let mut out = [0 as Word; 3];
        let p = out.as_mut_ptr();
        // SAFETY: the table says these take `args.len()` INTs and a word pointer per result.
        unsafe {
            type W = *mut Word;
            let f = i.addr;
            match (args, n) {
                ([a], 3) => std::mem::transmute::<*const u8, extern "C" fn(i64, W, W, W)>(f)(
                    *a,
                    p,
                    p.add(1),
                    p.add(2),
                ),
                ([a, b], 1) => {
                    std::mem::transmute::<*const u8, extern "C" fn(i64, i64, W)>(f)(*a, *b, p)
                }
                ([a, b, c], 1) => {
                    std::mem::transmute::<*const u8, extern "C" fn(i64, i64, i64, W)>(f)(
                        *a, *b, *c, p,
                    )
                }
                _ => panic!("arity"),
            }
        }
        out[..n].iter().map(|w| *w as u32).collect()
    }

    #[test]
    fn unpacksn_and_roundsn_match_the_inmos_examples() {
        assert_eq!(call_ints(&UNPACKSN, &[0x4049_0FDB]), [0xC90F_DB00, 0x80, 1]);
        assert_eq!(call_ints(&UNPACKSN, &[1]), [0x100, 1, 1]);
        assert_eq!(call_ints(&UNPACKSN, &[0x7FC0_0001]), [0x4000_0100, 0xFF, 3]);
        assert_eq!(call_ints(&UNPACKSN, &[0x7F80_0000])[2], 2);
        assert_eq!(call_ints(&UNPACKSN, &[0])[2], 0);
        let r = |e, f: u32, g| call_ints(&ROUNDSN, &[e, f as i32 as i64, g])[0];
        assert_eq!(r(0x80, 0xC90F_DB00, 0), 0x4049_0FDB);
        assert_eq!(r(0x80, 0xC90F_DB80, 0), 0x4049_0FDC);
        assert_eq!(r(0x80, 0xC90F_DA80, 0), 0x4049_0FDA);
        assert_eq!(r(0x80, 0xC90F_DA80, 0x3000), 0x4049_0FDB);
        assert_eq!(r(1, 0x100, 0), 1);
    }

    #[test]
    fn fracmul_rounds_like_the_transputer() {
        let f = |x: i64, y: i64| call_ints(&FRACMUL, &[x, y])[0] as i32;
        assert_eq!(f(1 << 30, 1 << 30), 1 << 29); // 0.5 * 0.5
        assert_eq!(f(-(1 << 30), 1 << 30), -(1 << 29));
        assert_eq!(f(1, 1), 0); // 2^-62 rounds to 0
        assert_eq!(f(0x4000_0000, 3), 2); // 1.5 ulp: ties to even
    }

    #[test]
    fn crc_word_and_byte() {
        // Shifting in zero data with a zero CRC gives zero; a set top bit feeds the generator.
        assert_eq!(call_ints(&CRCWORD, &[0, 0, 0x1021])[0], 0);
        assert_eq!(
            call_ints(&CRCBYTE, &[0, i32::MIN as i64, 0x1021])[0],
            0x1021 << 7
        );
        assert_eq!(call_ints(&CRCWORD, &[1, 0, 0x1021])[0], 1);
    }

    #[test]
    fn results_follow_the_arguments_and_no_name_is_bindable() {
        for i in PREDEFINES {
            let first = i.params.iter().position(|k| k.is_written());
            assert!(first.is_some(), "{} has results", i.name);
            assert!(
                i.params[first.unwrap_or(0)..]
                    .iter()
                    .all(|k| k.is_written()),
                "{}",
                i.name
            );
            assert!(super::super::intrinsic(i.name).is_none(), "{}", i.name);
        }
    }
}
