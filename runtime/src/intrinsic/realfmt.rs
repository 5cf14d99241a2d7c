//! The occam toolset's REAL-to-text formats (REAL32TOSTRING / REAL64TOSTRING with `Ip`, `Dp`),
//! which the course library's `out.real32` and `out.real64` print with.
//!
//! - `Ip = 0, Dp = 0`: free format, left-justified: fixed point (`1.5`, `100.0`, `0.0001`) unless
//!   the integer part needs more than the precision's significant digits or more than three
//!   zeroes follow the point before the first significant digit; then exponential (`1.0E+10`).
//! - `Ip = 0, Dp > 0`: exponential, a sign place (`-` or space), `Dp` significant digits as
//!   `d.ddd` (a space and one digit when `Dp = 1`), `E`, the exponent's sign and two (REAL32) or
//!   three (REAL64) exponent digits.
//! - `Ip > 0, Dp > 0`: fixed point in `Ip + Dp + 2` characters: spaces, a sign place, at least
//!   one integer digit, the point and `Dp` decimals; a number whose integer part needs more than
//!   `Ip` digits is written in exponential form in the same width (`Ov` when even that does not
//!   fit).
//!
//! Digits beyond the 9th (REAL32) or 17th (REAL64) significant digit are written as 0. Other
//! combinations of `Ip` and `Dp` are errors (`None`).

/// The precision of the number being written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// REAL32: 9 significant digits, two exponent digits.
    Single,
    /// REAL64: 17 significant digits, three exponent digits.
    Double,
}

impl Precision {
    fn max_digits(self) -> usize {
        match self {
            Precision::Single => 9,
            Precision::Double => 17,
        }
    }

    fn exponent_digits(self) -> usize {
        match self {
            Precision::Single => 2,
            Precision::Double => 3,
        }
    }
}

/// The significant digits of `x` (positive, finite) rounded to `n` (at least 1) digits, without
/// trailing zeros, and the decimal exponent of the first digit.
fn significant(x: f64, n: usize) -> (Vec<u8>, i32) {
    let text = format!("{:.*e}", n.max(1) - 1, x);
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mut digits: Vec<u8> = mantissa.bytes().filter(u8::is_ascii_digit).collect();
    while digits.len() > 1 && digits.last() == Some(&b'0') {
        digits.pop();
    }
    (digits, exponent.parse().unwrap_or(0))
}

/// Formats `x` as the occam toolset does (see the module documentation); `None` for a
/// meaningless `ip`, `dp`.
pub fn format(x: f64, precision: Precision, ip: i64, dp: i64) -> Option<String> {
    if ip < 0 || dp < 0 || (ip > 0 && dp == 0) {
        return None;
    }
    let (ip, dp) = (ip as usize, dp as usize);
    let expw = precision.exponent_digits();
    let negative = x.is_sign_negative();
    let mut out = String::new();
    let sign = |out: &mut String| {
        if negative {
            out.push('-');
        } else if dp != 0 {
            out.push(' ');
        }
    };
    if !x.is_finite() {
        if x.is_infinite() && negative {
            out.push('-');
        } else if dp != 0 {
            out.push(' ');
        }
        out.push_str(if x.is_nan() { "NaN" } else { "Inf" });
        let pad = if ip != 0 {
            (ip + dp).saturating_sub(2)
        } else if dp != 0 {
            dp + expw
        } else {
            0
        };
        out.extend(std::iter::repeat_n(' ', pad));
        return Some(out);
    }
    if x == 0.0 {
        if ip > 0 {
            out.extend(std::iter::repeat_n(' ', ip - 1));
        }
        sign(&mut out);
        if dp == 0 {
            out.push_str("0.0");
        } else if ip != 0 {
            out.push_str("0.");
            out.extend(std::iter::repeat_n('0', dp));
        } else {
            out.push_str(if dp == 1 { " 0" } else { "0." });
            out.extend(std::iter::repeat_n('0', dp.saturating_sub(1)));
            out.push_str("E+");
            out.extend(std::iter::repeat_n('0', expw));
        }
        return Some(out);
    }
    let ax = x.abs();
    let max = precision.max_digits();
    let n = if dp != 0 { (ip + dp).min(max) } else { max };
    let (digits, log) = significant(ax, n);
    let wants_fixed =
        |log: i32| (ip != 0 && log < ip as i32) || (dp == 0 && (-4..n as i32).contains(&log));
    if wants_fixed(log) {
        if dp == 0 {
            sign(&mut out);
            free_fixed(&mut out, &digits, log);
            return Some(out);
        }
        let (int_part, frac) = fixed_digits(ax, dp, log, n);
        let log = if int_part == "0" {
            -1
        } else {
            int_part.len() as i32 - 1
        };
        if wants_fixed(log) {
            out.extend(std::iter::repeat_n(' ', ip.saturating_sub(int_part.len())));
            sign(&mut out);
            out.push_str(&int_part);
            out.push('.');
            out.push_str(&frac);
            return Some(out);
        }
    }
    // Exponential form.
    sign(&mut out);
    let mut n = dp;
    let (mut digits, mut log) = (digits, log);
    if ip != 0 {
        let width = ip + dp + 2;
        if width < 4 + expw {
            out.push_str("Ov");
            out.extend(std::iter::repeat_n(' ', (ip + dp).saturating_sub(1)));
            return Some(out);
        }
        n = width - (4 + expw);
        if n == 1 {
            out.push(' ');
        }
        n = n.max(1);
        (digits, log) = significant(ax, n.min(max));
    } else if n == 1 {
        out.push(' ');
    }
    out.push(digits[0] as char);
    if n != 1 {
        out.push('.');
    }
    if n != 0 {
        for i in 1..n {
            out.push(digits.get(i).map_or('0', |&d| d as char));
        }
    } else if digits.len() <= 1 {
        out.push('0');
    } else {
        out.extend(digits[1..].iter().map(|&d| d as char));
    }
    out.push('E');
    out.push(if log < 0 { '-' } else { '+' });
    let e = log.unsigned_abs() as usize;
    out.push_str(&format!("{e:0expw$}"));
    Some(out)
}

/// Free format in fixed point: the digits placed around the point, `.0` when nothing follows it.
fn free_fixed(out: &mut String, digits: &[u8], log: i32) {
    if log < 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', (-log - 1) as usize));
        out.extend(digits.iter().map(|&d| d as char));
        return;
    }
    let int_len = log as usize + 1;
    for i in 0..int_len {
        out.push(digits.get(i).map_or('0', |&d| d as char));
    }
    out.push('.');
    if digits.len() > int_len {
        out.extend(digits[int_len..].iter().map(|&d| d as char));
    } else {
        out.push('0');
    }
}

/// The integer part and `dp` decimals of `ax` rounded to `dp` places, with digits beyond the
/// `n` significant ones the precision allows written as 0.
fn fixed_digits(ax: f64, dp: usize, log: i32, n: usize) -> (String, String) {
    let needed = dp as i32 + log + 1;
    let text = if needed <= n as i32 {
        format!("{ax:.dp$}")
    } else {
        // More digits than the precision holds: the first `n`, then zeros.
        let (digits, log) = significant(ax, n);
        let mut s = String::new();
        let int_len = (log + 1).max(0) as usize;
        for i in 0..int_len {
            s.push(digits.get(i).map_or('0', |&d| d as char));
        }
        if int_len == 0 {
            s.push('0');
        }
        s.push('.');
        for k in 0..dp {
            // Position of this decimal among the significant digits.
            let i = int_len as i64 + k as i64 - (if log < 0 { (-log - 1) as i64 } else { 0 });
            let d = if log < 0 && (k as i64) < (-log - 1) as i64 {
                '0'
            } else {
                usize::try_from(i)
                    .ok()
                    .and_then(|i| digits.get(i))
                    .map_or('0', |&d| d as char)
            };
            s.push(d);
        }
        s
    };
    let (int_part, frac) = text.split_once('.').unwrap_or((&text, ""));
    (int_part.to_string(), frac.to_string())
}

/// `REAL32TOSTRING (RESULT INT len, []BYTE string, VAL REAL32 x, VAL INT Ip, Dp)`, the toolset's
/// format; `len` is -1 when `Ip`, `Dp` are meaningless or the text does not fit.
///
/// # Safety
/// As for [`super::strings::put_string`].
pub(super) unsafe extern "C" fn real32_to_string(
    len: *mut crate::abi::Word,
    ptr: *mut u8,
    cap: crate::abi::Word,
    x: f32,
    ip: crate::abi::Word,
    dp: crate::abi::Word,
) {
    let text = format(f64::from(x), Precision::Single, ip, dp);
    // SAFETY: forwarded contract.
    unsafe { super::strings::put_text(len, ptr, cap, text.as_deref()) }
}

/// `REAL64TOSTRING` in the toolset's format, as [`real32_to_string`].
///
/// # Safety
/// As for [`super::strings::put_string`].
pub(super) unsafe extern "C" fn real64_to_string(
    len: *mut crate::abi::Word,
    ptr: *mut u8,
    cap: crate::abi::Word,
    x: f64,
    ip: crate::abi::Word,
    dp: crate::abi::Word,
) {
    let text = format(x, Precision::Double, ip, dp);
    // SAFETY: forwarded contract.
    unsafe { super::strings::put_text(len, ptr, cap, text.as_deref()) }
}

#[cfg(test)]
mod test {
    use super::{Precision::*, format};

    fn f32s(x: f32, ip: i64, dp: i64) -> String {
        format(f64::from(x), Single, ip, dp).unwrap()
    }

    #[test]
    fn free_format_is_fixed_point_when_it_fits() {
        assert_eq!(f32s(1.5, 0, 0), "1.5");
        assert_eq!(f32s(100.0, 0, 0), "100.0");
        assert_eq!(f32s(0.25, 0, 0), "0.25");
        assert_eq!(f32s(-0.125, 0, 0), "-0.125");
        assert_eq!(f32s(0.0005, 0, 0), "0.000500000024");
        assert_eq!(f32s(0.0001, 0, 0), "9.99999975E-05");
        assert_eq!(f32s(0.1, 0, 0), "0.100000001");
        assert_eq!(f32s(0.0, 0, 0), "0.0");
    }

    #[test]
    fn free_format_turns_exponential_for_large_and_tiny_numbers() {
        assert_eq!(f32s(1.0e10, 0, 0), "1.0E+10");
        assert_eq!(f32s(1.0 / 65536.0, 0, 0), "1.52587891E-05");
        assert_eq!(format(1.0e20, Double, 0, 0).unwrap(), "1.0E+020");
    }

    #[test]
    fn fixed_point_has_ip_plus_dp_plus_two_characters() {
        assert_eq!(f32s(4.56789, 2, 3), "  4.568");
        assert_eq!(f32s(-2.5, 1, 1), "-2.5");
        assert_eq!(f32s(0.0, 3, 2), "   0.00");
        assert_eq!(f32s(99.5, 2, 1), " 99.5");
        assert_eq!(format(1234.5678, Double, 6, 2).unwrap(), "   1234.57");
    }

    #[test]
    fn fixed_point_too_wide_becomes_exponential_in_the_same_width() {
        let s = f32s(123456.0, 2, 4);
        assert_eq!(s.len(), 8);
        assert_eq!(s, " 1.2E+05");
        assert_eq!(f32s(9.9996, 1, 3), " 1E+01");
        assert_eq!(f32s(123456.0, 1, 1), " Ov ");
    }

    #[test]
    fn exponential_format() {
        assert_eq!(f32s(1234.5, 0, 3), " 1.23E+03");
        assert_eq!(f32s(-0.05, 0, 1), "- 5E-02");
        assert_eq!(format(1234.56, Double, 0, 4).unwrap(), " 1.235E+003");
    }

    #[test]
    fn beyond_the_precision_digits_are_zero() {
        assert_eq!(f32s(0.1, 1, 12), " 0.100000001000");
    }

    #[test]
    fn infinities_and_nans() {
        assert_eq!(f32s(f32::INFINITY, 0, 0), "Inf");
        assert_eq!(f32s(f32::NEG_INFINITY, 2, 2), "-Inf  ");
        assert_eq!(f32s(f32::NAN, 0, 2), " NaN    ");
    }

    #[test]
    fn meaningless_combinations_are_refused() {
        assert_eq!(format(1.0, Single, 3, 0), None);
        assert_eq!(format(1.0, Single, -1, 2), None);
    }
}
