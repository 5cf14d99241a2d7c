//! Native helpers for the predefines that are awkward in Cranelift IR: IEEE arithmetic with a
//! rounding mode, IEEE remainder, FLOATING.UNPACK, ARGUMENT.REDUCE, UNPACKSN/ROUNDSN, FRACMUL
//! and the CRC routines.
//!
//! Contract (shared with `lower::predefined`): every helper is `extern "C"`, takes its occam
//! arguments (INTs sign-extended to `i64`, REALs as `f32`/`f64`) followed by a pointer to an
//! output buffer of [`OUT_WORDS`] 64-bit words, and returns nothing. Result `k` is written to
//! word `k` as raw bits: an INT in the low 32 bits, a BOOL as 0 or 1, a REAL32 in the low 32
//! bits, a REAL64 in the whole word. Helpers never block, allocate or panic.

/// The machine type of one helper argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arg {
    /// An INT, sign-extended to 64 bits.
    Int,
    /// A REAL32.
    R32,
    /// A REAL64.
    R64,
}

/// The type of one helper result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Out {
    /// An INT or INT32 (low 32 bits of its word).
    Int,
    /// A BOOL (0 or 1).
    Bool,
    /// A REAL32 (low 32 bits of its word).
    R32,
    /// A REAL64.
    R64,
}

/// Words in a helper's output buffer.
pub const OUT_WORDS: i64 = 3;

/// One native helper.
#[derive(Clone, Copy, Debug)]
pub struct Helper {
    /// The occam predefine it implements.
    pub name: &'static str,
    /// Its arguments before the output pointer.
    pub args: &'static [Arg],
    /// Its results, in occam order.
    pub results: &'static [Out],
    /// The function's address.
    pub addr: *const u8,
}

// SAFETY: only static data and function addresses.
unsafe impl Sync for Helper {}

macro_rules! helper {
    ($name:literal, [$($a:ident),*], [$($r:ident),*], $f:path) => {
        Helper {
            name: $name,
            args: &[$(Arg::$a),*],
            results: &[$(Out::$r),*],
            addr: $f as *const u8,
        }
    };
}

/// Every native helper.
pub static HELPERS: &[Helper] = &[
    helper!("IEEE32OP", [R32, Int, Int, R32], [Bool, R32], ieee32op),
    helper!("IEEE64OP", [R64, Int, Int, R64], [Bool, R64], ieee64op),
    helper!("IEEE32REM", [R32, R32], [Bool, R32], ieee32rem),
    helper!("IEEE64REM", [R64, R64], [Bool, R64], ieee64rem),
    helper!("FLOATING.UNPACK", [R32], [Int, R32], unpack32),
    helper!("DFLOATING.UNPACK", [R64], [Int, R64], unpack64),
    helper!(
        "ARGUMENT.REDUCE",
        [R32, R32, R32],
        [Bool, Int, R32],
        reduce32
    ),
    helper!(
        "DARGUMENT.REDUCE",
        [R64, R64, R64],
        [Bool, Int, R64],
        reduce64
    ),
    helper!("UNPACKSN", [Int], [Int, Int, Int], unpacksn),
    helper!("ROUNDSN", [Int, Int, Int], [Int], roundsn),
    helper!("FRACMUL", [Int, Int], [Int], fracmul),
    helper!("CRCWORD", [Int, Int, Int], [Int], crcword),
    helper!("CRCBYTE", [Int, Int, Int], [Int], crcbyte),
];

/// Finds a helper by occam name.
pub fn helper(name: &str) -> Option<&'static Helper> {
    HELPERS.iter().find(|h| h.name == name)
}

/// The linker symbol of helper `name`.
pub fn symbol(name: &str) -> String {
    format!("occ_native_{}", name.replace('.', "_"))
}

/// Writes `vals` to the output buffer.
///
/// # Safety
/// `out` points to [`OUT_WORDS`] writable words.
unsafe fn put(out: *mut u64, vals: &[u64]) {
    for (k, v) in vals.iter().enumerate() {
        // SAFETY: the caller gives OUT_WORDS words and no helper writes more.
        unsafe { out.add(k).write_unaligned(*v) };
    }
}

fn int(v: i64) -> u64 {
    v as i32 as u32 as u64
}

/// IEEE arithmetic on one float type with an explicit rounding mode.
macro_rules! ieee_ops {
    ($t:ty, $op:ident, $rem:ident, $unpack:ident, $reduce:ident, $bits:ident) => {
        /// `IEEExxOP(X, Rm, Op, Y)`: Op 0 +, 1 -, 2 *, 3 /; Rm 0 nearest, 1 toward zero,
        /// 2 toward +inf, 3 toward -inf. Results: (error, value); error is TRUE when the
        /// result is NaN, or infinite from finite operands.
        ///
        /// # Safety
        /// `out` points to [`OUT_WORDS`] writable words.
        pub unsafe extern "C" fn $op(x: $t, rm: i64, op: i64, y: $t, out: *mut u64) {
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
            unsafe { put(out, &[bad as u64, $bits(r)]) };
        }

        /// `IEEExxREM(X, Y)`: the IEEE remainder X - N*Y with N the nearest integer to X/Y
        /// (ties to even), exact. Results: (error, value); error is TRUE for a NaN result.
        ///
        /// # Safety
        /// `out` points to [`OUT_WORDS`] writable words.
        pub unsafe extern "C" fn $rem(x: $t, y: $t, out: *mut u64) {
            let r = ieee_rem!($t, x, y);
            // SAFETY: forwarded from the caller.
            unsafe { put(out, &[r.is_nan() as u64, $bits(r)]) };
        }

        /// `FLOATING.UNPACK(X)`: (n, f) with X = f * 2^n and 1 <= |f| < 2 for finite nonzero X;
        /// zero, infinities and NaN give (0, X).
        ///
        /// # Safety
        /// `out` points to [`OUT_WORDS`] writable words.
        pub unsafe extern "C" fn $unpack(x: $t, out: *mut u64) {
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
            unsafe { put(out, &[int(n), $bits(f)]) };
        }

        /// `ARGUMENT.REDUCE(X, Y, Y.err)`: (ok, N, X - N*(Y + Y.err)) with N the nearest integer
        /// to X/Y; ok is FALSE when N does not fit an INT32 or an operand is not finite.
        ///
        /// # Safety
        /// `out` points to [`OUT_WORDS`] writable words.
        pub unsafe extern "C" fn $reduce(x: $t, y: $t, yerr: $t, out: *mut u64) {
            let q = (x / y).round_ties_even();
            let ok = x.is_finite() && y.is_finite() && q.abs() <= i32::MAX as $t;
            let (n, r) = if ok {
                let r = (-q).mul_add(y, x);
                (q as i64, (-q).mul_add(yerr, r))
            } else {
                (0, x)
            };
            // SAFETY: forwarded from the caller.
            unsafe { put(out, &[ok as u64, int(n), $bits(r)]) };
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

fn bits32(v: f32) -> u64 {
    v.to_bits() as u64
}

fn bits64(v: f64) -> u64 {
    v.to_bits()
}

ieee_ops!(f32, ieee32op, ieee32rem, unpack32, reduce32, bits32);
ieee_ops!(f64, ieee64op, ieee64rem, unpack64, reduce64, bits64);

/// `UNPACKSN(X)` (transputer `unpacksn`): (frac, exp, type) of the REAL32 bits X: frac is the
/// mantissa (with the implied bit for normal numbers) shifted left 8, exp the biased exponent
/// (1 for denormals), type 0 zero, 1 number, 2 infinity, 3 NaN.
///
/// # Safety
/// `out` points to [`OUT_WORDS`] writable words.
pub unsafe extern "C" fn unpacksn(x: i64, out: *mut u64) {
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
    unsafe { put(out, &[frac as u64, exp as u64, ty]) };
}

/// `ROUNDSN(Yexp, Yfrac, Yguard)` (transputer `roundsn`): packs a biased exponent and a
/// mantissa left-justified by 8 bits into REAL32 bits, rounding to nearest even on the low 8
/// bits of Yfrac and the guard word; overflow gives infinity. The sign is not represented.
///
/// # Safety
/// `out` points to [`OUT_WORDS`] writable words.
pub unsafe extern "C" fn roundsn(exp: i64, frac: i64, guard: i64, out: *mut u64) {
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
    unsafe { put(out, &[v as u64]) };
}

/// `FRACMUL(X, Y)`: the product of two fractions scaled by 2^31, rounded to nearest even,
/// wrapping as the transputer's `fmul` does for MOSTNEG INT * MOSTNEG INT.
///
/// # Safety
/// `out` points to [`OUT_WORDS`] writable words.
pub unsafe extern "C" fn fracmul(x: i64, y: i64, out: *mut u64) {
    let p = (x as i32 as i64)
        .wrapping_mul(y as i32 as i64)
        .wrapping_shl(1);
    let hi = (p >> 32) as i32;
    let lo = p as i32;
    let up = lo < 0 && (lo != i32::MIN || hi & 1 == 1);
    let r = if up { hi.wrapping_add(1) } else { hi };
    // SAFETY: forwarded from the caller.
    unsafe { put(out, &[int(r as i64)]) };
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
/// `out` points to [`OUT_WORDS`] writable words.
pub unsafe extern "C" fn crcword(data: i64, c: i64, g: i64, out: *mut u64) {
    // SAFETY: forwarded from the caller.
    unsafe { put(out, &[int(crc(data, c, g, 32))]) };
}

/// `CRCBYTE(data, CRCIn, generator)`: the CRC after shifting in the most significant byte of
/// data.
///
/// # Safety
/// `out` points to [`OUT_WORDS`] writable words.
pub unsafe extern "C" fn crcbyte(data: i64, c: i64, g: i64, out: *mut u64) {
    // SAFETY: forwarded from the caller.
    unsafe { put(out, &[int(crc(data, c, g, 8))]) };
}
