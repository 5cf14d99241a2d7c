//! String conversion and array intrinsics (examples of array and RESULT parameters).

use crate::abi::Word;

/// Writes `text` into the byte array (`ptr`, `cap`) and its length into `*len`; if it does not
/// fit, `*len` is -1 and the array is untouched.
///
/// # Safety
/// `len` is a valid INT; `ptr` valid for `cap` bytes.
pub(super) unsafe fn put_string(len: *mut Word, ptr: *mut u8, cap: Word, text: &str) {
    let n = text.len();
    // SAFETY: caller contract.
    unsafe {
        if n as Word > cap {
            *len = -1;
            return;
        }
        std::ptr::copy_nonoverlapping(text.as_ptr(), ptr, n);
        *len = n as Word;
    }
}

/// [`put_string`] for a text that may be missing (`*len` is then -1).
///
/// # Safety
/// As for [`put_string`].
pub(super) unsafe fn put_text(len: *mut Word, ptr: *mut u8, cap: Word, text: Option<&str>) {
    // SAFETY: caller contract.
    unsafe {
        match text {
            Some(t) => put_string(len, ptr, cap, t),
            None => *len = -1,
        }
    }
}

/// `INTTOSTRING (RESULT INT len, []BYTE string, VAL INT n)`: decimal digits of `n`.
///
/// # Safety
/// As for [`put_string`].
pub(super) unsafe extern "C" fn int_to_string(len: *mut Word, ptr: *mut u8, cap: Word, n: Word) {
    // SAFETY: forwarded contract.
    unsafe { put_string(len, ptr, cap, &n.to_string()) }
}

/// `REAL64TOSTRING (RESULT INT len, []BYTE string, VAL REAL64 x, VAL INT Ip, Dp)`: with
/// `Ip = Dp = 0` the shortest decimal that reads back as `x`; otherwise fixed point with `Dp`
/// decimals (`Ip` is not used for padding).
///
/// # Safety
/// As for [`put_string`].
pub(super) unsafe extern "C" fn real64_to_string(
    len: *mut Word,
    ptr: *mut u8,
    cap: Word,
    x: f64,
    ip: Word,
    dp: Word,
) {
    let text = if ip == 0 && dp == 0 {
        format!("{x:?}")
    } else {
        format!("{x:.prec$}", prec = dp.clamp(0, 30) as usize)
    };
    // SAFETY: forwarded contract.
    unsafe { put_string(len, ptr, cap, &text) }
}

/// `REAL64 FUNCTION SUM.REAL64 (VAL []REAL64 xs)`: the sum of the elements.
///
/// # Safety
/// `ptr` valid for `n` REAL64s.
pub(super) unsafe extern "C" fn sum_real64(ptr: *const f64, n: Word) -> f64 {
    if n <= 0 {
        return 0.0;
    }
    // SAFETY: caller contract.
    unsafe { std::slice::from_raw_parts(ptr, n as usize) }
        .iter()
        .sum()
}
