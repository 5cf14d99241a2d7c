//! Unary and binary operators on constants.

use super::{ConstError, Value, in_range, wrap};
use crate::types::Prim;

pub use occ_grammar::ast::{BinOp, UnOp};

/// Returns a binary operator as occam spells it (the printer's spelling: one table for both).
pub fn bin_symbol(op: BinOp) -> &'static str {
    occ_grammar::print::binop_text(op)
}

/// Reports whether the operator's result is BOOL whatever the operand type.
pub fn is_relational(op: BinOp) -> bool {
    use BinOp::*;
    matches!(op, Eq | Ne | Lt | Gt | Le | Ge | After)
}

/// Reports whether the right operand is an INT shift count rather than the left's type.
pub fn is_shift(op: BinOp) -> bool {
    matches!(op, BinOp::Shl | BinOp::Shr)
}

/// Reports whether `prim` is an operand type the binary operator accepts.
pub fn bin_accepts(op: BinOp, prim: Prim) -> bool {
    use BinOp::*;
    match op {
        Add | Sub | Mul | Div | Rem | Lt | Gt | Le | Ge => prim.is_numeric(),
        Plus | Minus | Times | After => prim.is_integer(),
        BitAnd | BitOr | Xor | Shl | Shr => prim.is_integer(),
        And | Or => prim == Prim::Bool,
        Eq | Ne => true,
        User(_) => false,
    }
}

/// Returns a unary operator as occam spells it.
pub fn un_symbol(op: UnOp) -> &'static str {
    occ_grammar::print::unop_text(op)
}

/// Reports whether `prim` is an operand type the unary operator accepts.
pub fn un_accepts(op: UnOp, prim: Prim) -> bool {
    match op {
        UnOp::Neg => prim.is_numeric(),
        UnOp::Minus | UnOp::BitNot => prim.is_integer(),
        UnOp::Not => prim == Prim::Bool,
        UnOp::User(_) => false,
    }
}

/// Applies a unary operator in type `prim`.
pub fn unary(op: UnOp, prim: Prim, v: &Value) -> Result<Value, ConstError> {
    match (op, v) {
        (UnOp::Not, Value::Bool(b)) => Ok(Value::Bool(!b)),
        (UnOp::Neg, Value::Int(i)) => checked(prim, -i128::from(*i)),
        (UnOp::Minus, Value::Int(i)) => Ok(Value::Int(wrap(prim, -i128::from(*i)))),
        (UnOp::BitNot, Value::Int(i)) => Ok(Value::Int(wrap(prim, i128::from(!*i)))),
        (UnOp::Neg, Value::Real32(x)) => Ok(Value::Real32(-x)),
        (UnOp::Neg, Value::Real64(x)) => Ok(Value::Real64(-x)),
        _ => Err(ConstError::Unsupported),
    }
}

fn checked(prim: Prim, v: i128) -> Result<Value, ConstError> {
    in_range(prim, v)
        .map(Value::Int)
        .ok_or(ConstError::Overflow(prim))
}

/// Applies a binary operator with operands of type `prim` (for shifts, the type of the left
/// operand; the count is an INT).
pub fn binary(op: BinOp, prim: Prim, a: &Value, b: &Value) -> Result<Value, ConstError> {
    match (a, b) {
        (Value::Int(x), Value::Int(y)) => int_binary(op, prim, *x, *y),
        (Value::Real32(x), Value::Real32(y)) => real32_binary(op, *x, *y),
        (Value::Real64(x), Value::Real64(y)) => real64_binary(op, *x, *y),
        (Value::Bool(x), Value::Bool(y)) => bool_binary(op, *x, *y),
        _ => Err(ConstError::Unsupported),
    }
}

fn bool_binary(op: BinOp, x: bool, y: bool) -> Result<Value, ConstError> {
    match op {
        BinOp::And => Ok(Value::Bool(x && y)),
        BinOp::Or => Ok(Value::Bool(x || y)),
        BinOp::Eq => Ok(Value::Bool(x == y)),
        BinOp::Ne => Ok(Value::Bool(x != y)),
        _ => Err(ConstError::Unsupported),
    }
}

fn int_binary(op: BinOp, prim: Prim, x: i64, y: i64) -> Result<Value, ConstError> {
    let (a, b) = (i128::from(x), i128::from(y));
    let bits = i128::from(prim.bits());
    let unsigned = |v: i64| (v as u64) & mask(prim);
    match op {
        BinOp::Add => checked(prim, a + b),
        BinOp::Sub => checked(prim, a - b),
        BinOp::Mul => checked(prim, a * b),
        BinOp::Div if b == 0 => Err(ConstError::DivisionByZero),
        BinOp::Div => checked(prim, a / b),
        BinOp::Rem if b == 0 => Err(ConstError::DivisionByZero),
        BinOp::Rem => Ok(Value::Int((a % b) as i64)),
        BinOp::Plus => Ok(Value::Int(wrap(prim, a + b))),
        BinOp::Minus => Ok(Value::Int(wrap(prim, a - b))),
        BinOp::Times => Ok(Value::Int(wrap(prim, a * b))),
        BinOp::BitAnd => Ok(Value::Int(x & y)),
        BinOp::BitOr => Ok(Value::Int(x | y)),
        BinOp::Xor => Ok(Value::Int(wrap(prim, a ^ b))),
        BinOp::Shl | BinOp::Shr if !(0..=bits).contains(&b) => Err(ConstError::ShiftCount(y)),
        BinOp::Shl => Ok(Value::Int(wrap(prim, i128::from(unsigned(x)) << b))),
        BinOp::Shr => Ok(Value::Int(wrap(prim, i128::from(unsigned(x)) >> b))),
        // AFTER reads the wrapped difference as signed, BYTE included (whose values are unsigned).
        BinOp::After => Ok(Value::Bool(signed_difference(prim, a - b) > 0)),
        _ => compare(op, a.cmp(&b)),
    }
}

/// Wraps `v` to `prim`'s width and reads it as a signed number of that width (for BYTE too,
/// whose values are otherwise unsigned): the difference that AFTER compares with zero.
fn signed_difference(prim: Prim, v: i128) -> i64 {
    let wrapped = wrap(prim, v);
    if prim == Prim::Byte && wrapped >= 128 {
        wrapped - 256
    } else {
        wrapped
    }
}

fn mask(prim: Prim) -> u64 {
    if prim.bits() >= 64 {
        u64::MAX
    } else {
        (1u64 << prim.bits()) - 1
    }
}

fn compare(op: BinOp, ord: std::cmp::Ordering) -> Result<Value, ConstError> {
    use std::cmp::Ordering::*;
    let r = match op {
        BinOp::Eq => ord == Equal,
        BinOp::Ne => ord != Equal,
        BinOp::Lt => ord == Less,
        BinOp::Gt => ord == Greater,
        BinOp::Le => ord != Greater,
        BinOp::Ge => ord != Less,
        _ => return Err(ConstError::Unsupported),
    };
    Ok(Value::Bool(r))
}

macro_rules! real_binary {
    ($name:ident, $t:ty, $variant:ident, $prim:expr) => {
        fn $name(op: BinOp, x: $t, y: $t) -> Result<Value, ConstError> {
            let r = match op {
                BinOp::Add => x + y,
                BinOp::Sub => x - y,
                BinOp::Mul => x * y,
                BinOp::Div if y == 0.0 => return Err(ConstError::DivisionByZero),
                BinOp::Div => x / y,
                BinOp::Rem if y == 0.0 => return Err(ConstError::DivisionByZero),
                BinOp::Rem => ieee_remainder(f64::from(x), f64::from(y)) as $t,
                _ => {
                    return match x.partial_cmp(&y) {
                        Some(ord) => compare(op, ord),
                        None => Ok(Value::Bool(op == BinOp::Ne)),
                    };
                }
            };
            if r.is_finite() || !(x.is_finite() && y.is_finite()) {
                Ok(Value::$variant(r))
            } else {
                Err(ConstError::Overflow($prim))
            }
        }
    };
}

real_binary!(real32_binary, f32, Real32, Prim::Real32);
real_binary!(real64_binary, f64, Real64, Prim::Real64);

/// Returns the IEEE 754 remainder `x - n*y`, `n` the integer nearest `x/y` (ties to even), which
/// is what occam's `\` computes on REALs. The result is exact, so computing a REAL32 remainder in
/// REAL64 and narrowing does not round.
pub fn ieee_remainder(x: f64, y: f64) -> f64 {
    let y = y.abs();
    let r = x % y; // exact, sign of x, |r| < y
    let twice = x % (2.0 * y); // tells whether the truncated quotient is odd
    let odd = twice.abs() >= y;
    let half = y / 2.0;
    if r.abs() > half || (r.abs() == half && odd) {
        r - y.copysign(x)
    } else {
        r
    }
}
