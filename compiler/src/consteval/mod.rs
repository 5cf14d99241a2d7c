//! Constant folding with exact occam semantics.
//!
//! Every operation takes the primitive type it is performed in and returns either the value or a
//! [`ConstError`] saying why occam defines the operation as an error: `+ - * /` and `\` overflow
//! or divide by zero, `PLUS`/`MINUS`/`TIMES` wrap, shifts by more than the width are an error,
//! conversions are range checked, `ROUND` rounds to nearest even and `TRUNC` toward zero. A
//! constant expression that is an error is a compile-time error in occam, so the checker turns
//! every `ConstError` into a diagnostic with the expression's span.
//!
//! Integer values of every width (BYTE included) are held in an `i64` that is always in range for
//! the type; REAL32 values are `f32` so that each operation rounds once, as the hardware does.

mod convert;
mod literal;
mod ops;
#[cfg(test)]
mod test;

pub use convert::{ConvMode, convert};
pub use literal::{parse_integer_literal, parse_real_literal};
pub use ops::{
    BinOp, UnOp, bin_accepts, bin_symbol, binary, is_relational, is_shift, un_accepts, un_symbol,
    unary,
};

use crate::types::Prim;

/// A constant value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// TRUE or FALSE.
    Bool(bool),
    /// A BYTE or INT-family value, in range for its type.
    Int(i64),
    /// A REAL32 value.
    Real32(f32),
    /// A REAL64 value.
    Real64(f64),
    /// A constant array (a table or string), element by element.
    Array(Vec<Value>),
    /// A constant record, field by field.
    Record(Vec<Value>),
}

impl Value {
    /// Returns the integer, if this is an integer value.
    pub fn as_int(&self) -> Option<i64> {
        match self {
            Value::Int(i) => Some(*i),
            _ => None,
        }
    }

    /// Returns the boolean, if this is a boolean value.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }

    /// Returns the number of elements of an array value (`SIZE`).
    pub fn size(&self) -> Option<usize> {
        match self {
            Value::Array(items) => Some(items.len()),
            _ => None,
        }
    }

    /// Builds a `[]BYTE` value from the bytes of a string literal.
    pub fn string(bytes: &[u8]) -> Value {
        Value::Array(bytes.iter().map(|b| Value::Int(i64::from(*b))).collect())
    }
}

/// Why a constant operation is an error in occam.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConstError {
    /// Occurs when `+ - *`, unary `-` or `/` leave the range of the type. Example: `VAL INT16 x IS 32767(INT16) + 1(INT16):`.
    Overflow(Prim),
    /// Occurs when `/` or `\` divides by zero. Example: `VAL INT x IS 1 / 0:`.
    DivisionByZero,
    /// Occurs when a shift count is negative or greater than the width. Example: `#1 << 33`.
    ShiftCount(i64),
    /// Occurs when a conversion's value does not fit the target type. Example: `BYTE 256`.
    ConversionRange(Prim),
    /// Occurs when a literal does not fit its type or is malformed. Example: `300(BYTE)`.
    LiteralRange(Prim),
    /// Occurs when the operation does not apply to the type (the type checker reports these
    /// first; this is a safety net). Example: `TRUE + FALSE`.
    Unsupported,
}

/// Returns `MOSTPOS T`.
pub fn most_pos(prim: Prim) -> Option<Value> {
    match prim {
        Prim::Real32 => Some(Value::Real32(f32::MAX)),
        Prim::Real64 => Some(Value::Real64(f64::MAX)),
        _ => prim.int_range().map(|(_, hi)| Value::Int(hi)),
    }
}

/// Returns `MOSTNEG T`.
pub fn most_neg(prim: Prim) -> Option<Value> {
    match prim {
        Prim::Real32 => Some(Value::Real32(-f32::MAX)),
        Prim::Real64 => Some(Value::Real64(-f64::MAX)),
        _ => prim.int_range().map(|(lo, _)| Value::Int(lo)),
    }
}

/// Checks that `v` is in range for the integer type `prim`.
pub(crate) fn in_range(prim: Prim, v: i128) -> Option<i64> {
    let (lo, hi) = prim.int_range()?;
    (i128::from(lo)..=i128::from(hi))
        .contains(&v)
        .then_some(v as i64)
}

/// Reduces `v` modulo 2^bits of `prim` into its range (two's complement wrap).
pub(crate) fn wrap(prim: Prim, v: i128) -> i64 {
    let bits = prim.bits();
    let mask = if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    };
    let low = (v as u64) & mask;
    if prim == Prim::Byte {
        return low as i64;
    }
    let sign = 1u64 << (bits - 1);
    if bits < 64 && low & sign != 0 {
        (low | !mask) as i64
    } else {
        low as i64
    }
}
