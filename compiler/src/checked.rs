//! The checked program: what the checker hands to the code generator.
//!
//! It is the AST (not copied: the code generator walks the same [`occ_grammar::ast::Program`])
//! plus side tables keyed by the span of the node they describe:
//! - `names`: every name occurrence that denotes a symbol, to its [`SymbolId`];
//! - `expr_types`: the type of every expression;
//! - `constants`: the value of every expression that is a compile-time constant;
//! - `operators`: the operator expressions that call a user-defined operator FUNCTION;
//! - `procs`: every PROC and FUNCTION with its parameters and usage summary.
//!
//! Spans are unique per node in the preprocessed text, except that a name and the expression
//! consisting of just that name share a span (and then describe the same thing).

pub use crate::fxhash::FxHashMap;

use occ_grammar::ast::{AbbrevMode, ParamMode, Span};

use crate::consteval::Value;
use crate::entity::PrimaryMap;
use crate::entity_ref;
use crate::predefined::Predefined;
use crate::types::{ProtocolId, Type, TypeDefId, TypeTable};
use crate::usage::Access;

entity_ref!(
    /// A declared name: variable, constant, channel, PROC, type ...
    SymbolId
);
entity_ref!(
    /// A PROC or FUNCTION.
    ProcId
);

/// What a symbol denotes.
#[derive(Debug, Clone, PartialEq)]
pub enum SymbolKind {
    /// A declared variable, channel, timer or port (`INT x:`, `CHAN OF INT c:`).
    Variable,
    /// A `VAL` abbreviation or a constant; `value` when known at compile time.
    Val {
        /// The constant value, if the abbreviated expression is constant.
        value: Option<Value>,
    },
    /// A reference abbreviation (`x IS a[2]:`), RESULT or INITIAL abbreviation, or RETYPES.
    Abbrev {
        /// How it was declared.
        mode: AbbrevMode,
    },
    /// A formal parameter.
    Param {
        /// VAL, reference or RESULT.
        mode: ParamMode,
        /// The PROC or FUNCTION it belongs to.
        owner: ProcId,
        /// Its position in the parameter list.
        index: usize,
    },
    /// A replicator index (a VAL INT in the replicated process).
    Replicator,
    /// A PROC.
    Proc(ProcId),
    /// A FUNCTION.
    Function(ProcId),
    /// A `DATA TYPE` or `RECORD`.
    DataType(TypeDefId),
    /// A `PROTOCOL`.
    Protocol(ProtocolId),
    /// A predefined routine.
    Predefined(&'static Predefined),
    /// A routine declared by `#PRAGMA EXTERNAL` (a PROC when its [`ProcInfo::results`] is
    /// empty, else a FUNCTION), implemented by a native intrinsic the driver links in.
    External(ProcId),
}

/// One declared name.
#[derive(Debug, Clone, PartialEq)]
pub struct Symbol {
    /// The name as declared.
    pub name: String,
    /// Where it was declared (the name itself).
    pub span: Span,
    /// What it is.
    pub kind: SymbolKind,
    /// Its type (`Type::Error` for PROCs, types and protocols).
    pub ty: Type,
    /// Whether it may be assigned or input to.
    pub assignable: bool,
    /// For a reference abbreviation, the storage it names (accesses through it count as
    /// accesses to this).
    pub alias_of: Option<Access>,
}

/// A PROC or FUNCTION.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcInfo {
    /// Its name.
    pub name: String,
    /// Its symbol.
    pub symbol: Option<SymbolId>,
    /// The whole declaration, from `PROC` or the result types to the closing `:` (for an
    /// EXTERNAL, the header in its pragma): every name used in its body is inside.
    pub span: Span,
    /// The formal parameters' symbols, in order.
    pub params: Vec<SymbolId>,
    /// The result types (empty for a PROC).
    pub results: Vec<Type>,
    /// Its usage summary: accesses to its parameters and to free variables, for PAR checks at
    /// its call sites (occ21's bottom-up PROC summaries).
    pub usage: Vec<Access>,
}

/// The checker's output for a program without errors.
#[derive(Debug, Clone, Default)]
pub struct CheckedProgram {
    /// Named types and protocols.
    pub types: TypeTable,
    /// Every symbol.
    pub symbols: PrimaryMap<SymbolId, Symbol>,
    /// Every PROC and FUNCTION.
    pub procs: PrimaryMap<ProcId, ProcInfo>,
    /// Name occurrences (by span) to symbols.
    pub names: FxHashMap<Span, SymbolId>,
    /// Expression types, by expression span.
    pub expr_types: FxHashMap<Span, Type>,
    /// Constant values, by expression span.
    pub constants: FxHashMap<Span, Value>,
    /// Operator expressions (`a + b`, `?? a`) that call a user-defined operator FUNCTION, by the
    /// span of the whole expression, to that FUNCTION's symbol.
    pub operators: FxHashMap<Span, SymbolId>,
    /// The network configured by the last PROC's `PLACED PAR`, if it has one.
    pub network: Option<crate::network::Network>,
    /// `ASM` blocks written in the subset that runs here (see [`AsmOp`]), by the block's span.
    pub asm: FxHashMap<Span, Vec<AsmOp>>,
}

/// One transputer instruction of an `ASM` block in the subset that runs on this machine: the
/// evaluation stack (A, B, C) as word values, loaded from constants and INT variables and stored
/// back to INT variables. `LDAB a, b` and `LDABC a, b, c` are pushes of the operands in reverse
/// order (so that A holds `a`); `STAB` and `STABC` are stores in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AsmOp {
    /// Push a constant (`LDC n`, `LD n`).
    Const(i64),
    /// Push an INT variable's value (`LD x`).
    Load(SymbolId),
    /// Store A in an INT variable and pop (`ST x`).
    Store(SymbolId),
    /// Pop A (`POP`).
    Pop,
    /// Swap A and B (`REV`).
    Rev,
}
