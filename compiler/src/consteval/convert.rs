//! Type conversions (`T e`, `T ROUND e`, `T TRUNC e`) on constants, with occam's range checks.

use super::{ConstError, Value, in_range};
use crate::types::Prim;

pub use occ_grammar::ast::ConvMode;

/// Converts `v` of type `from` to type `to`.
pub fn convert(to: Prim, mode: ConvMode, from: Prim, v: &Value) -> Result<Value, ConstError> {
    let range = ConstError::ConversionRange(to);
    match (v, to) {
        (Value::Bool(b), _) if to != Prim::Bool && !to.is_real() => Ok(Value::Int(i64::from(*b))),
        (Value::Bool(b), Prim::Bool) => Ok(Value::Bool(*b)),
        (Value::Int(i), Prim::Bool) => match i {
            0 => Ok(Value::Bool(false)),
            1 => Ok(Value::Bool(true)),
            _ => Err(range),
        },
        (Value::Int(i), Prim::Real32) => Ok(Value::Real32(int_to_f32(*i, mode))),
        (Value::Int(i), Prim::Real64) => Ok(Value::Real64(int_to_f64(*i, mode))),
        (Value::Int(i), _) => in_range(to, i128::from(*i)).map(Value::Int).ok_or(range),
        (Value::Real32(x), _) => real_to(to, mode, f64::from(*x), from),
        (Value::Real64(x), _) => real_to(to, mode, *x, from),
        _ => Err(ConstError::Unsupported),
    }
}

fn real_to(to: Prim, mode: ConvMode, x: f64, from: Prim) -> Result<Value, ConstError> {
    let range = ConstError::ConversionRange(to);
    match to {
        Prim::Real64 => Ok(Value::Real64(x)),
        Prim::Real32 if from == Prim::Real32 => Ok(Value::Real32(x as f32)),
        Prim::Real32 => {
            let r = f64_to_f32(x, mode);
            if r.is_finite() || !x.is_finite() {
                Ok(Value::Real32(r))
            } else {
                Err(range)
            }
        }
        _ if to.is_integer() => {
            let r = match mode {
                ConvMode::Trunc => x.trunc(),
                _ => x.round_ties_even(),
            };
            if !r.is_finite() || r.abs() > 1.8e19 {
                return Err(range);
            }
            in_range(to, r as i128).map(Value::Int).ok_or(range)
        }
        _ => Err(ConstError::Unsupported),
    }
}

/// Narrows a REAL64 to REAL32: nearest-even for ROUND (and plain), toward zero for TRUNC.
fn f64_to_f32(x: f64, mode: ConvMode) -> f32 {
    let r = x as f32;
    if mode == ConvMode::Trunc && r.is_finite() && f64::from(r).abs() > x.abs() {
        toward_zero32(r)
    } else if mode == ConvMode::Trunc && r.is_infinite() && x.is_finite() {
        f32::MAX.copysign(r)
    } else {
        r
    }
}

fn toward_zero32(r: f32) -> f32 {
    if r > 0.0 { r.next_down() } else { r.next_up() }
}

fn int_to_f32(i: i64, mode: ConvMode) -> f32 {
    let r = i as f32; // one rounding, to nearest even
    if mode == ConvMode::Trunc && (r as i128).abs() > i128::from(i).abs() {
        toward_zero32(r)
    } else {
        r
    }
}

fn int_to_f64(i: i64, mode: ConvMode) -> f64 {
    let r = i as f64;
    if mode == ConvMode::Trunc && (r as i128).abs() > i128::from(i).abs() {
        if r > 0.0 { r.next_down() } else { r.next_up() }
    } else {
        r
    }
}
