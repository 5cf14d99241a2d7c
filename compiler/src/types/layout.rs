//! Sizes, alignments and record field offsets, as on a 32-bit transputer.
//!
//! Rules: primitive sizes are BOOL/BYTE 1, INT16 2, INT/INT32/REAL32 4, INT64/REAL64 8. An array
//! is its element size times its length, with no padding. An unpacked record aligns each field
//! to the field's alignment (at most one word, 4 bytes) and rounds its size up to its own
//! alignment; a `PACKED RECORD` lays fields end to end.

use super::{Type, TypeDefKind, TypeTable};

/// The word size of the target, in bytes.
pub const WORD_BYTES: u32 = 4;

/// Why a size or offset cannot be computed.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum LayoutError {
    /// Occurs when the type has no static size: an open array `[]INT` or a channel of `ANY`.
    /// Example: `BYTESIN ([]INT)`.
    Unsized,
    /// Occurs when the size does not fit in an INT. Example: `[1000000][1000000]INT`.
    TooLarge,
    /// Occurs when OFFSETOF names a field the record does not have. Example: `OFFSETOF (R, nosuch)`.
    NoSuchField,
    /// Occurs when OFFSETOF is applied to something that is not a record. Example: `OFFSETOF (INT, x)`.
    NotRecord,
}

/// Returns the size in bytes of a value of type `ty` (`BYTESIN`).
pub fn bytes_in(table: &TypeTable, ty: &Type) -> Result<u32, LayoutError> {
    match table.underlying(ty) {
        Type::Prim(p) => Ok(p.bytes()),
        Type::Array(Some(n), e) => bytes_in(table, e)?
            .checked_mul(*n)
            .filter(|b| *b <= i32::MAX as u32)
            .ok_or(LayoutError::TooLarge),
        Type::Array(None, _) | Type::Error => Err(LayoutError::Unsized),
        Type::Named(id) => match table.defs.get(*id).map(|d| &d.kind) {
            Some(TypeDefKind::Record { packed, fields }) => record_size(table, *packed, fields),
            _ => Err(LayoutError::Unsized),
        },
        Type::Chan(..) | Type::Timer | Type::Port(_) => Ok(WORD_BYTES),
    }
}

/// Returns the alignment in bytes of `ty`: its largest primitive, capped at a word.
pub fn align_of(table: &TypeTable, ty: &Type) -> u32 {
    match table.underlying(ty) {
        Type::Prim(p) => p.bytes().min(WORD_BYTES),
        Type::Array(_, e) => align_of(table, e),
        Type::Named(id) => match table.defs.get(*id).map(|d| &d.kind) {
            Some(TypeDefKind::Record { packed: true, .. }) => 1,
            Some(TypeDefKind::Record { fields, .. }) => fields
                .iter()
                .map(|(_, t)| align_of(table, t))
                .max()
                .unwrap_or(1),
            _ => 1,
        },
        _ => WORD_BYTES,
    }
}

fn round_up(x: u32, align: u32) -> Option<u32> {
    x.checked_add(align - 1).map(|v| v / align * align)
}

/// Walks the fields of a record, returning each field's offset and the total size.
fn record_offsets(
    table: &TypeTable,
    packed: bool,
    fields: &[(String, Type)],
) -> Result<(Vec<u32>, u32), LayoutError> {
    let mut offsets = Vec::with_capacity(fields.len());
    let mut at = 0u32;
    let mut max_align = 1;
    for (_, ty) in fields {
        let align = if packed { 1 } else { align_of(table, ty) };
        max_align = max_align.max(align);
        at = round_up(at, align).ok_or(LayoutError::TooLarge)?;
        offsets.push(at);
        at = at
            .checked_add(bytes_in(table, ty)?)
            .ok_or(LayoutError::TooLarge)?;
    }
    let size = round_up(at, max_align).ok_or(LayoutError::TooLarge)?;
    Ok((offsets, size))
}

fn record_size(
    table: &TypeTable,
    packed: bool,
    fields: &[(String, Type)],
) -> Result<u32, LayoutError> {
    record_offsets(table, packed, fields).map(|(_, size)| size)
}

/// Returns the byte offset of `field` in record type `ty` (`OFFSETOF`).
pub fn offset_of(table: &TypeTable, ty: &Type, field: &str) -> Result<u32, LayoutError> {
    let Type::Named(id) = table.underlying(ty) else {
        return Err(LayoutError::NotRecord);
    };
    let Some(TypeDefKind::Record { packed, fields }) = table.defs.get(*id).map(|d| &d.kind) else {
        return Err(LayoutError::NotRecord);
    };
    let (offsets, _) = record_offsets(table, *packed, fields)?;
    let index = fields
        .iter()
        .position(|(name, _)| name == field)
        .ok_or(LayoutError::NoSuchField)?;
    offsets.get(index).copied().ok_or(LayoutError::NoSuchField)
}
