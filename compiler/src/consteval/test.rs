use super::*;
use crate::types::Prim::*;

fn i(v: i64) -> Value {
    Value::Int(v)
}

fn bin(op: BinOp, p: Prim, a: i64, b: i64) -> Result<Value, ConstError> {
    binary(op, p, &i(a), &i(b))
}

#[test]
fn checked_arithmetic_overflows_per_type() {
    assert_eq!(
        bin(BinOp::Add, Int16, 32767, 1),
        Err(ConstError::Overflow(Int16))
    );
    assert_eq!(bin(BinOp::Add, Int, 32767, 1), Ok(i(32768)));
    assert_eq!(
        bin(BinOp::Mul, Int, 65536, 65536),
        Err(ConstError::Overflow(Int))
    );
    assert_eq!(bin(BinOp::Sub, Byte, 0, 1), Err(ConstError::Overflow(Byte)));
    assert_eq!(
        bin(BinOp::Add, Int64, i64::MAX, 1),
        Err(ConstError::Overflow(Int64))
    );
    assert_eq!(
        bin(BinOp::Div, Int, i32::MIN.into(), -1),
        Err(ConstError::Overflow(Int))
    );
    assert_eq!(
        unary(UnOp::Neg, Int32, &i(i32::MIN.into())),
        Err(ConstError::Overflow(Int32))
    );
}

#[test]
fn division_truncates_and_remainder_follows_the_dividend() {
    assert_eq!(bin(BinOp::Div, Int, -7, 2), Ok(i(-3)));
    assert_eq!(bin(BinOp::Rem, Int, -7, 2), Ok(i(-1)));
    assert_eq!(bin(BinOp::Rem, Int, 7, -2), Ok(i(1)));
    assert_eq!(bin(BinOp::Rem, Int64, i64::MIN, -1), Ok(i(0)));
    assert_eq!(bin(BinOp::Div, Int, 1, 0), Err(ConstError::DivisionByZero));
    assert_eq!(bin(BinOp::Rem, Int, 1, 0), Err(ConstError::DivisionByZero));
}

#[test]
fn modulo_operators_wrap() {
    assert_eq!(
        bin(BinOp::Plus, Int, i32::MAX.into(), 1),
        Ok(i(i32::MIN.into()))
    );
    assert_eq!(bin(BinOp::Minus, Int16, -32768, 1), Ok(i(32767)));
    assert_eq!(bin(BinOp::Times, Byte, 16, 17), Ok(i(16)));
    assert_eq!(bin(BinOp::Plus, Int64, i64::MAX, 1), Ok(i(i64::MIN)));
    assert_eq!(
        unary(UnOp::Minus, Int, &i(i32::MIN.into())),
        Ok(i(i32::MIN.into()))
    );
}

#[test]
fn shifts_are_logical_and_range_checked() {
    assert_eq!(bin(BinOp::Shr, Int, -1, 28), Ok(i(15)));
    assert_eq!(bin(BinOp::Shl, Int, 1, 31), Ok(i(i32::MIN.into())));
    assert_eq!(bin(BinOp::Shl, Int, 1, 32), Ok(i(0)));
    assert_eq!(
        bin(BinOp::Shl, Int16, 1, 17),
        Err(ConstError::ShiftCount(17))
    );
    assert_eq!(bin(BinOp::Shr, Int, 1, -1), Err(ConstError::ShiftCount(-1)));
    assert_eq!(bin(BinOp::Shl, Byte, 0xFF, 4), Ok(i(0xF0)));
}

#[test]
fn bit_operators_stay_in_type() {
    assert_eq!(unary(UnOp::BitNot, Byte, &i(5)), Ok(i(250)));
    assert_eq!(unary(UnOp::BitNot, Int16, &i(0)), Ok(i(-1)));
    assert_eq!(bin(BinOp::Xor, Int16, -1, 0x00FF), Ok(i(-256)));
    assert_eq!(bin(BinOp::BitAnd, Int, 12, 10), Ok(i(8)));
    assert_eq!(bin(BinOp::BitOr, Int, 12, 10), Ok(i(14)));
}

#[test]
fn after_is_modular() {
    assert_eq!(
        bin(BinOp::After, Int, i32::MIN.into(), i32::MAX.into()),
        Ok(Value::Bool(true))
    );
    assert_eq!(bin(BinOp::After, Int, 5, 5), Ok(Value::Bool(false)));
    // BYTE differences are signed modulo 2^8 (cgtest66 BY-117).
    assert_eq!(bin(BinOp::After, Byte, 6, 10), Ok(Value::Bool(false)));
    assert_eq!(bin(BinOp::After, Byte, 10, 6), Ok(Value::Bool(true)));
    assert_eq!(bin(BinOp::After, Byte, 5, 250), Ok(Value::Bool(true)));
    assert_eq!(
        bin(BinOp::Gt, Int, i32::MIN.into(), i32::MAX.into()),
        Ok(Value::Bool(false))
    );
}

#[test]
fn reals_round_once_and_overflow_is_an_error() {
    let big = Value::Real32(f32::MAX);
    assert_eq!(
        binary(BinOp::Add, Real32, &big, &big),
        Err(ConstError::Overflow(Real32))
    );
    let third = binary(BinOp::Div, Real32, &Value::Real32(1.0), &Value::Real32(3.0));
    assert_eq!(third, Ok(Value::Real32(1.0f32 / 3.0)));
    let z = Value::Real64(0.0);
    assert_eq!(
        binary(BinOp::Div, Real64, &Value::Real64(1.0), &z),
        Err(ConstError::DivisionByZero)
    );
}

#[test]
fn real_remainder_is_ieee() {
    assert_eq!(ops::ieee_remainder(5.0, 2.0), 1.0);
    assert_eq!(ops::ieee_remainder(7.0, 2.0), -1.0);
    assert_eq!(ops::ieee_remainder(6.0, 4.0), -2.0);
    assert_eq!(ops::ieee_remainder(10.0, 4.0), 2.0);
    assert_eq!(ops::ieee_remainder(-5.5, 2.0), 0.5);
}

#[test]
fn conversions_are_range_checked() {
    assert_eq!(
        convert(Byte, ConvMode::Plain, Int, &i(256)),
        Err(ConstError::ConversionRange(Byte))
    );
    assert_eq!(
        convert(Int16, ConvMode::Plain, Int, &i(-32768)),
        Ok(i(-32768))
    );
    assert_eq!(
        convert(Bool, ConvMode::Plain, Int, &i(2)),
        Err(ConstError::ConversionRange(Bool))
    );
    assert_eq!(
        convert(Int, ConvMode::Plain, Bool, &Value::Bool(true)),
        Ok(i(1))
    );
    let huge = Value::Real64(3.0e9);
    assert_eq!(
        convert(Int, ConvMode::Round, Real64, &huge),
        Err(ConstError::ConversionRange(Int))
    );
    let nan = Value::Real32(f32::NAN);
    assert_eq!(
        convert(Int, ConvMode::Trunc, Real32, &nan),
        Err(ConstError::ConversionRange(Int))
    );
}

#[test]
fn round_is_nearest_even_and_trunc_toward_zero() {
    let r = |x: f64| convert(Int, ConvMode::Round, Real64, &Value::Real64(x));
    let t = |x: f64| convert(Int, ConvMode::Trunc, Real64, &Value::Real64(x));
    assert_eq!(
        (r(2.5), r(3.5), r(-2.5), r(-2.6)),
        (Ok(i(2)), Ok(i(4)), Ok(i(-2)), Ok(i(-3)))
    );
    assert_eq!((t(2.9), t(-2.9)), (Ok(i(2)), Ok(i(-2))));
}

#[test]
fn int_to_real_rounds_or_truncates() {
    let v = i(16_777_217); // 2^24 + 1: not a REAL32
    assert_eq!(
        convert(Real32, ConvMode::Round, Int, &v),
        Ok(Value::Real32(16_777_216.0))
    );
    let v = i(16_777_219); // halfway above 2^24+2: nearest even is 2^24+4
    assert_eq!(
        convert(Real32, ConvMode::Round, Int, &v),
        Ok(Value::Real32(16_777_220.0))
    );
    assert_eq!(
        convert(Real32, ConvMode::Trunc, Int, &v),
        Ok(Value::Real32(16_777_218.0))
    );
    assert_eq!(
        convert(Real32, ConvMode::Trunc, Int, &i(-16_777_219)),
        Ok(Value::Real32(-16_777_218.0))
    );
}

#[test]
fn real64_to_real32_narrows_with_mode() {
    let x = Value::Real64(1.0 + f64::EPSILON);
    assert_eq!(
        convert(Real32, ConvMode::Round, Real64, &x),
        Ok(Value::Real32(1.0))
    );
    let x = Value::Real64(1.0 - f64::EPSILON);
    assert_eq!(
        convert(Real32, ConvMode::Trunc, Real64, &x),
        Ok(Value::Real32(1.0f32.next_down()))
    );
    let x = Value::Real64(1.0e300);
    assert_eq!(
        convert(Real32, ConvMode::Round, Real64, &x),
        Err(ConstError::ConversionRange(Real32))
    );
}

#[test]
fn integer_literals_decimal_and_hex() {
    assert_eq!(parse_integer_literal("255", Byte), Ok(i(255)));
    assert_eq!(
        parse_integer_literal("256", Byte),
        Err(ConstError::LiteralRange(Byte))
    );
    assert_eq!(parse_integer_literal("#FFFF", Int16), Ok(i(-1)));
    assert_eq!(parse_integer_literal("#FFFFFFFF", Int), Ok(i(-1)));
    assert_eq!(
        parse_integer_literal("#100000000", Int),
        Err(ConstError::LiteralRange(Int))
    );
    assert_eq!(
        parse_integer_literal("#8000000000000000", Int64),
        Ok(i(i64::MIN))
    );
    assert_eq!(
        parse_integer_literal("2147483648", Int),
        Err(ConstError::LiteralRange(Int))
    );
    assert_eq!(parse_integer_literal("2", Real32), Ok(Value::Real32(2.0)));
}

#[test]
fn real32_literal_is_rounded_once_from_decimal() {
    // Rounding this decimal to REAL64 first lands exactly halfway between two REAL32s, and the
    // second rounding then goes the wrong way; the direct rounding gives the larger neighbour.
    let text = "1.00000005960464477550";
    let direct = parse_real_literal(text, Real32);
    let double: f64 = text.parse().unwrap();
    assert_eq!(direct, Ok(Value::Real32(1.0f32.next_up())));
    assert_ne!(direct, Ok(Value::Real32(double as f32)));
    assert_eq!(
        parse_real_literal("1.0E+39", Real32),
        Err(ConstError::LiteralRange(Real32))
    );
    assert_eq!(
        parse_real_literal("1.0E+39", Real64),
        Ok(Value::Real64(1.0e39))
    );
}

#[test]
fn most_pos_and_most_neg() {
    assert_eq!(most_pos(Int16), Some(i(32767)));
    assert_eq!(most_neg(Int), Some(i(i32::MIN.into())));
    assert_eq!(most_pos(Byte), Some(i(255)));
    assert_eq!(most_neg(Real32), Some(Value::Real32(-f32::MAX)));
    assert_eq!(most_pos(Bool), None);
}
