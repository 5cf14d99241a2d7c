//! How occam values are stored and held: Cranelift value types of primitives and the storage size
//! of every type in a workspace.
//!
//! Data types use the T800 layout of `occ_compiler::types` (INT 4 bytes, packed arrays, padded
//! records), so that `BYTESIN` and RETYPES agree with it. Channels, timers and ports take one
//! runtime [`occ_runtime::abi::Word`] (8 bytes) each, as the runtime's channel word is a word.

use cranelift_codegen::ir::types;
use occ_compiler::types::{Prim, Type, TypeTable, bytes_in};

/// Bytes of a runtime word.
pub const WORD: i64 = occ_runtime::abi::WORD_BYTES as i64;

/// The Cranelift type that holds a value of primitive type `p` (BOOL is 0 or 1 in an `i8`).
pub fn cl_type(p: Prim) -> types::Type {
    match p {
        Prim::Bool | Prim::Byte => types::I8,
        Prim::Int16 => types::I16,
        Prim::Int | Prim::Int32 => types::I32,
        Prim::Int64 => types::I64,
        Prim::Real32 => types::F32,
        Prim::Real64 => types::F64,
    }
}

/// The storage size in bytes of a value of `ty`, or `None` for an open array.
pub fn size_of(table: &TypeTable, ty: &Type) -> Option<i64> {
    match table.underlying(ty) {
        Type::Prim(p) => Some(i64::from(p.bytes())),
        Type::Array(Some(n), e) => Some(i64::from(*n) * size_of(table, e)?),
        Type::Array(None, _) => None,
        Type::Named(_) => bytes_in(table, ty).ok().map(i64::from),
        Type::Chan(..) | Type::Timer | Type::Port(_) => Some(WORD),
        Type::Error => None,
    }
}

/// `ty` with every `DATA TYPE` alias resolved, at the top and inside arrays (records stay named).
pub fn resolve(table: &TypeTable, ty: &Type) -> Type {
    match table.underlying(ty) {
        Type::Array(n, e) => Type::Array(*n, Box::new(resolve(table, e))),
        t => t.clone(),
    }
}

/// The innermost element type of an array type (the type itself for a non-array).
pub fn base_elem(ty: &Type) -> &Type {
    match ty {
        Type::Array(_, e) => base_elem(e),
        t => t,
    }
}

/// The number of array dimensions of `ty`.
pub fn rank(ty: &Type) -> usize {
    match ty {
        Type::Array(_, e) => 1 + rank(e),
        _ => 0,
    }
}

/// The static dimension lengths of `ty` (`None` for an open dimension).
pub fn static_dims(ty: &Type) -> Vec<Option<u32>> {
    let mut out = Vec::new();
    let mut t = ty;
    while let Type::Array(n, e) = t {
        out.push(*n);
        t = e;
    }
    out
}

/// Reports whether values of `ty` are held in a Cranelift value (a primitive) rather than by
/// address (arrays and records).
pub fn is_scalar(table: &TypeTable, ty: &Type) -> bool {
    matches!(table.underlying(ty), Type::Prim(_))
}

/// The fields of record `ty` with their byte offsets and types.
pub fn record_fields(table: &TypeTable, ty: &Type) -> Option<Vec<(String, i64, Type)>> {
    let fields = table.record_fields(ty)?;
    fields
        .iter()
        .map(|(name, t)| {
            occ_compiler::types::offset_of(table, ty, name)
                .ok()
                .map(|o| (name.clone(), i64::from(o), t.clone()))
        })
        .collect()
}
