//! Literal text to constant values.

use super::{ConstError, Value, in_range};
use crate::types::Prim;

/// Parses an integer literal (`123`, `#7F`, `#FFFFFFFF`) as a value of type `prim`.
///
/// A decimal literal must lie in the type's range. A hex literal gives a bit pattern: it must fit
/// in the type's width and is read as two's complement, so `#FFFF(INT16)` is -1 and `#FF(BYTE)`
/// is 255. A REAL type accepts a decimal integer literal (occ21 treats `2(REAL32)` as `2.0`).
pub fn parse_integer_literal(text: &str, prim: Prim) -> Result<Value, ConstError> {
    let bad = ConstError::LiteralRange(prim);
    if let Some(hex) = text.strip_prefix('#') {
        let bits = u64::from_str_radix(hex, 16).map_err(|_| bad.clone())?;
        return hex_pattern(bits, prim).ok_or(bad);
    }
    let v: i128 = text.parse().map_err(|_| bad.clone())?;
    match prim {
        Prim::Real32 | Prim::Real64 => parse_real_literal(text, prim),
        Prim::Bool => Err(bad),
        _ => in_range(prim, v).map(Value::Int).ok_or(bad),
    }
}

fn hex_pattern(bits: u64, prim: Prim) -> Option<Value> {
    let width = prim.bits();
    if !prim.is_integer() || (width < 64 && bits >> width != 0) {
        return None;
    }
    if prim == Prim::Byte {
        return Some(Value::Int(bits as i64));
    }
    Some(Value::Int(super::wrap(prim, i128::from(bits))))
}

/// Parses a REAL literal (`1.5`, `2.0E+10`, `1.0E-3`) as REAL32 or REAL64, correctly rounded
/// from the decimal text in one step (REAL32 is not parsed via REAL64, which could round twice).
/// A literal that overflows the type is an error.
pub fn parse_real_literal(text: &str, prim: Prim) -> Result<Value, ConstError> {
    let bad = ConstError::LiteralRange(prim);
    match prim {
        Prim::Real32 => {
            let v: f32 = text.parse().map_err(|_| bad.clone())?;
            if v.is_finite() {
                Ok(Value::Real32(v))
            } else {
                Err(bad)
            }
        }
        Prim::Real64 => {
            let v: f64 = text.parse().map_err(|_| bad.clone())?;
            if v.is_finite() {
                Ok(Value::Real64(v))
            } else {
                Err(bad)
            }
        }
        _ => Err(bad),
    }
}
