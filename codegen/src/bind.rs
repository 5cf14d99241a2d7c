//! Binding `#PRAGMA EXTERNAL` routines to native intrinsics.
//!
//! One place for each fact: the occam signature is the pragma (checked as a
//! `SymbolKind::External`), the machine ABI is the Rust table entry
//! (`occ_runtime::intrinsic::Intrinsic`). [`bind_externals`] finds each EXTERNAL in the
//! [`IntrinsicSet`] the driver gives and checks that the two agree:
//! - the name is in no linked table: an error at every call (an EXTERNAL that is never called
//!   needs no intrinsic, so a program may include a whole library of declarations);
//! - the parameter kinds or the result differ: an error at the pragma's name.

use std::collections::HashMap;

use occ_compiler::CheckedProgram;
use occ_compiler::checked::{SymbolId, SymbolKind};
use occ_compiler::types::{Prim, Type, TypeTable};
use occ_grammar::ast::{ParamMode, Span};
use occ_grammar::diagnostic::Diagnostic;
use occ_runtime::intrinsic::{Intrinsic, IntrinsicSet, MachineType, ParamKind};

/// The code of a call to an EXTERNAL that no linked table has.
const UNBOUND: &str = "bind::unbound";
/// The code of an EXTERNAL whose signature disagrees with its table entry.
const MISMATCH: &str = "bind::mismatch";

/// The EXTERNAL routines of a checked program bound to their intrinsics, and the problems.
#[derive(Debug, Default)]
pub struct Bindings {
    /// Each bound EXTERNAL symbol's intrinsic.
    pub bound: HashMap<SymbolId, &'static Intrinsic>,
    /// Unbound calls (at the call) and signature disagreements (at the pragma's name), in
    /// source order.
    pub errors: Vec<Diagnostic>,
}

/// Binds every EXTERNAL of `checked` to an intrinsic of `set`.
pub fn bind_externals(checked: &CheckedProgram, set: &IntrinsicSet) -> Bindings {
    bind_some(checked, set, |_| true)
}

/// Binds the EXTERNALs of `checked` that `wanted` accepts to intrinsics of `set`; the others
/// are neither bound nor checked. Code generation binds only those its program calls
/// ([`crate::reach`]); the front end checks them all.
pub fn bind_some(
    checked: &CheckedProgram,
    set: &IntrinsicSet,
    wanted: impl Fn(SymbolId) -> bool,
) -> Bindings {
    let mut out = Bindings::default();
    for (id, sym) in checked.symbols.iter() {
        let SymbolKind::External(pid) = sym.kind else {
            continue;
        };
        if !wanted(id) {
            continue;
        }
        let Some(i) = set.find(&sym.name) else {
            let mut uses: Vec<Span> = checked
                .names
                .iter()
                .filter(|(span, s)| **s == id && **span != sym.span)
                .map(|(span, _)| *span)
                .collect();
            uses.sort_by_key(|s| s.start);
            let message = format!("no native intrinsic {} is linked into occ", sym.name);
            out.errors.extend(uses.into_iter().map(|span| {
                Diagnostic::error(span, message.clone(), "called here").with_code(UNBOUND)
            }));
            continue;
        };
        let info = &checked.procs[pid];
        let params: Vec<(ParamMode, &Type)> = info
            .params
            .iter()
            .map(|p| {
                let s = &checked.symbols[*p];
                let mode = match s.kind {
                    SymbolKind::Param { mode, .. } => mode,
                    _ => ParamMode::Val,
                };
                (mode, &s.ty)
            })
            .collect();
        match disagreement(&checked.types, &params, &info.results, i) {
            Some(why) => {
                let message = format!(
                    "EXTERNAL {} does not match the linked intrinsic: {why}",
                    sym.name
                );
                let d = Diagnostic::error(sym.span, message, "declared here").with_code(MISMATCH);
                out.errors.push(d);
            }
            None => {
                out.bound.insert(id, i);
            }
        }
    }
    out.errors.sort_by_key(|e| e.span().map_or(0, |s| s.start));
    out
}

/// Says how the pragma's signature differs from the table entry `i`, if it does.
fn disagreement(
    types: &TypeTable,
    params: &[(ParamMode, &Type)],
    results: &[Type],
    i: &Intrinsic,
) -> Option<String> {
    if params.len() != i.params.len() {
        return Some(format!(
            "it has {} parameters here, {} in the table",
            params.len(),
            i.params.len()
        ));
    }
    for (k, ((mode, ty), want)) in params.iter().zip(i.params).enumerate() {
        let have = param_kind(types, *mode, ty);
        if have != Some(*want) {
            let here = have.map_or("a type the intrinsic ABI cannot pass", ParamKind::occam);
            return Some(format!(
                "parameter {} is `{here}` here, `{}` in the table",
                k + 1,
                want.occam()
            ));
        }
    }
    let result = match results {
        [] => None,
        [one] => match result_type(types, one) {
            Some(m) => Some(m),
            None => return Some("its result type cannot be returned by an intrinsic".into()),
        },
        _ => return Some("an intrinsic FUNCTION returns one result".into()),
    };
    (result != i.result).then(|| match (result, i.result) {
        (None, Some(_)) => "it is a PROC here, a FUNCTION in the table".to_string(),
        (Some(_), None) => "it is a FUNCTION here, a PROC in the table".to_string(),
        (Some(r), Some(w)) => format!("it returns {} here, {} in the table", r.occam(), w.occam()),
        (None, None) => String::new(),
    })
}

/// The ABI kind of an occam parameter, if the ABI can pass it.
pub fn param_kind(types: &TypeTable, mode: ParamMode, ty: &Type) -> Option<ParamKind> {
    use ParamKind::*;
    use Prim::*;
    let written = mode != ParamMode::Val;
    match (types.underlying(ty), written) {
        (Type::Prim(p), false) => Some(match p {
            Int | Int16 | Int32 | Int64 => ValInt,
            Byte => ValByte,
            Bool => ValBool,
            Real32 => ValReal32,
            Real64 => ValReal64,
        }),
        (Type::Prim(p), true) => match p {
            Int | Int16 | Int32 | Int64 => Some(ResultInt),
            Bool => Some(ResultBool),
            Real32 => Some(ResultReal32),
            _ => None,
        },
        (Type::Array(_, e), w) => match (types.prim(e)?, w) {
            (Byte, false) => Some(ValBytes),
            (Byte, true) => Some(VarBytes),
            (Int | Int32, false) => Some(ValInts),
            (Int | Int32, true) => Some(VarInts),
            (Real32, false) => Some(ValReal32s),
            (Real32, true) => Some(VarReal32s),
            (Real64, false) => Some(ValReal64s),
            (Real64, true) => Some(VarReal64s),
            (Bool, false) => Some(ValBools),
            (Bool, true) => Some(VarBools),
            _ => None,
        },
        _ => None,
    }
}

/// The machine type of a FUNCTION result.
fn result_type(types: &TypeTable, ty: &Type) -> Option<MachineType> {
    match types.prim(ty)? {
        Prim::Real32 => Some(MachineType::F32),
        Prim::Real64 => Some(MachineType::F64),
        _ => Some(MachineType::I64),
    }
}
