//! REAL intrinsics: the occam REAL predefines and the Inmos maths library, single and double.

use crate::abi::Word;

/// Defines `extern "C"` wrappers `$f32(x: f32) -> f32` and `$f64(x: f64) -> f64` calling the
/// float method `$m`.
macro_rules! unary {
    ($($f32:ident, $f64:ident => $m:ident;)*) => {
        $(
            pub(super) extern "C" fn $f32(x: f32) -> f32 {
                x.$m()
            }
            pub(super) extern "C" fn $f64(x: f64) -> f64 {
                x.$m()
            }
        )*
    };
}

unary! {
    sqrt32, sqrt64 => sqrt;
    sin32, sin64 => sin;
    cos32, cos64 => cos;
    tan32, tan64 => tan;
    asin32, asin64 => asin;
    acos32, acos64 => acos;
    atan32, atan64 => atan;
    sinh32, sinh64 => sinh;
    cosh32, cosh64 => cosh;
    tanh32, tanh64 => tanh;
    exp32, exp64 => exp;
    ln32, ln64 => ln;
    log10_32, log10_64 => log10;
    fpint32, fpint64 => round_ties_even;
}

pub(super) extern "C" fn pow32(x: f32, y: f32) -> f32 {
    x.powf(y)
}

pub(super) extern "C" fn pow64(x: f64, y: f64) -> f64 {
    x.powf(y)
}

/// `DATAN2 (U, V)`: the angle of the point (U, V), as the Inmos library defines it: NaN when
/// both are zero or both infinite, π (not −π) on the negative U axis.
pub(super) extern "C" fn atan2_64(u: f64, v: f64) -> f64 {
    if u.is_nan() || v.is_nan() {
        return u + v;
    }
    if (!u.is_finite() && !v.is_finite()) || (u == 0.0 && v == 0.0) {
        return f64::NAN;
    }
    if u < 0.0 && v == 0.0 {
        return std::f64::consts::PI;
    }
    v.atan2(u)
}

/// `ATAN2 (U, V)`, as [`atan2_64`].
pub(super) extern "C" fn atan2_32(u: f32, v: f32) -> f32 {
    atan2_64(f64::from(u), f64::from(v)) as f32
}

/// `DSCALEB (X, n)`: X × 2ⁿ.
pub(super) extern "C" fn scaleb64(x: f64, n: Word) -> f64 {
    // Scale in steps so that 2^n itself never overflows or underflows.
    let mut r = x;
    let mut n = n.clamp(-4000, 4000);
    while n != 0 {
        let step = n.clamp(-1000, 1000);
        r *= 2f64.powi(step as i32);
        n -= step;
    }
    r
}

/// `SCALEB (X, n)`: X × 2ⁿ.
pub(super) extern "C" fn scaleb32(x: f32, n: Word) -> f32 {
    scaleb64(f64::from(x), n) as f32
}

/// `DLOGB (X)`: the unbiased exponent of X as a REAL (−∞ for 0, +∞ for ±∞, NaN for NaN).
pub(super) extern "C" fn logb64(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x == 0.0 {
        return f64::NEG_INFINITY;
    }
    if x.is_infinite() {
        return f64::INFINITY;
    }
    let (m, adjust) = if x.abs() < f64::MIN_POSITIVE {
        (x * 2f64.powi(64), 64)
    } else {
        (x, 0)
    };
    let biased = ((m.to_bits() >> 52) & 0x7ff) as i64;
    (biased - 1023 - adjust) as f64
}

/// `LOGB (X)`: as [`logb64`] for REAL32 (subnormal REAL32s are normal REAL64s, so the exponent
/// is exact).
pub(super) extern "C" fn logb32(x: f32) -> f32 {
    logb64(f64::from(x)) as f32
}

/// `DNEXTAFTER (X, Y)`: the next REAL64 after X in the direction of Y.
pub(super) extern "C" fn nextafter64(x: f64, y: f64) -> f64 {
    if x.is_nan() || y.is_nan() {
        return x + y;
    }
    if x == y {
        return x;
    }
    if x < y { x.next_up() } else { x.next_down() }
}

/// `NEXTAFTER (X, Y)`: the next REAL32 after X in the direction of Y.
pub(super) extern "C" fn nextafter32(x: f32, y: f32) -> f32 {
    if x.is_nan() || y.is_nan() {
        return x + y;
    }
    if x == y {
        return x;
    }
    if x < y { x.next_up() } else { x.next_down() }
}

#[cfg(test)]
mod test {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn atan2_follows_the_inmos_argument_order() {
        assert_eq!(atan2_64(1.0, 1.0), PI / 4.0);
        assert_eq!(atan2_64(0.0, 2.0), PI / 2.0, "the point (0, 2) is at 90°");
        assert_eq!(atan2_64(-1.0, 0.0), PI);
        assert_eq!(atan2_64(-1.0, -0.0), PI);
        assert!(atan2_64(0.0, 0.0).is_nan());
        assert!((atan2_32(-1.0, -1.0) as f64 + 3.0 * PI / 4.0).abs() < 1e-6);
    }

    #[test]
    fn ieee_helpers() {
        assert_eq!(scaleb64(3.0, 4), 48.0);
        assert_eq!(scaleb64(1.0, -1074), f64::from_bits(1));
        assert_eq!(scaleb32(1.5, 2), 6.0);
        assert_eq!(logb64(8.0), 3.0);
        assert_eq!(logb64(0.75), -1.0);
        assert_eq!(logb64(f64::from_bits(1)), -1074.0);
        assert_eq!(logb64(0.0), f64::NEG_INFINITY);
        assert_eq!(logb32(-1024.0), 10.0);
        assert_eq!(fpint64(2.5), 2.0);
        assert_eq!(fpint64(3.5), 4.0);
        assert_eq!(fpint32(-0.5), -0.0);
        assert_eq!(nextafter64(1.0, 2.0), 1.0 + f64::EPSILON);
        assert_eq!(nextafter32(1.0, 0.0), 1.0 - f32::EPSILON / 2.0);
        assert_eq!(nextafter64(5.0, 5.0), 5.0);
    }

    #[test]
    fn library_functions() {
        assert_eq!(pow64(2.0, 10.0), 1024.0);
        assert_eq!(ln64(1.0), 0.0);
        assert_eq!(log10_32(1000.0), 3.0);
        assert!(sqrt64(-1.0).is_nan(), "domain errors give NaN");
        assert!((sin32(std::f32::consts::PI / 2.0) - 1.0).abs() < 1e-6);
    }
}
