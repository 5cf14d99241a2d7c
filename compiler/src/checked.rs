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

use occ_grammar::ast::{self, AbbrevMode, ParamMode, Span};

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
    /// `ASM` and `GUY` blocks (see [`AsmCode`]), by the block's span.
    pub asm: FxHashMap<Span, AsmCode>,
    /// The program's code image: the bytes of every block's `BYTE` and `WORD` lines, in order
    /// (what `LDPI` addresses; labels are offsets in it).
    pub asm_image: Vec<u8>,
    /// RETYPES between a channel and an INT (its address, as `ASM` blocks see addresses), by
    /// the span of the new name.
    pub chan_retypes: FxHashMap<Span, ChanRetype>,
}

/// A RETYPES between a channel and an INT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChanRetype {
    /// `VAL INT x RETYPES c :`: the channel's address as an INT.
    ToInt,
    /// `CHAN OF P d RETYPES x :`: the channel whose address is the INT `x`.
    FromInt,
}

/// A checked `ASM` or `GUY` block: its instructions and the room they need.
///
/// The address model: an address is an INT, the signed byte offset of the memory from the
/// node's address base (`occ_runtime::abi::ADDR_BASE_OFFSET`); words are 32 bits
/// (`TARGET.BITS.PER.WORD`), so `LDNL n` reads the word `4n` bytes past A. The numbered
/// workspace slots of `LDL`/`STL`/`LDLP` are 32-bit words of an area that the enclosing frame
/// reserves for its blocks (slot 0 at the area's Wptr, `RESERVELOWWS n` reserving n words below
/// it); `AJW` moves the block's Wptr within that area at compile time.
#[derive(Debug, Clone, PartialEq)]
pub struct AsmCode {
    /// The instructions, in order.
    pub ops: Vec<AsmOp>,
    /// The span of each instruction's line (for run-time errors).
    pub spans: Vec<Span>,
    /// Words of the area the block may use below its Wptr (`RESERVELOWWS`, negative slots).
    pub low_words: u32,
    /// Words of the area at and above its Wptr (the highest slot used, plus one).
    pub high_words: u32,
}

/// One instruction of an `ASM` or `GUY` block over the evaluation stack (A, B, C).
/// `LDAB a, b` and `LDABC a, b, c` are pushes of the operands in reverse order (so that A holds
/// `a`); `STAB` and `STABC` are stores in order.
#[derive(Debug, Clone, PartialEq)]
pub enum AsmOp {
    /// Push a constant (`LDC n`, `LD n`, `LDLABELDIFF :a - :b`).
    Const(i64),
    /// Push the value of an expression (`LD e`, GUY's `LDL x`): a channel pushes its address.
    Load(ast::Expr),
    /// Store A in an element and pop (`ST x`, `STL x`).
    Store(ast::Expr),
    /// Push the address of an element, a constant or a table (`LD ADDRESSOF x`, `LDLP x`).
    Address(ast::Expr),
    /// Push a number naming a PROC (`LD ADDRESSOF p`): occ's code is not in node memory.
    ProcAddress(SymbolId),
    /// Pop A (`POP`).
    Pop,
    /// Swap A and B (`REV`).
    Rev,
    /// A label (`:name`), numbered in the block.
    Label(usize),
    /// `J :label`.
    Jump(usize),
    /// `CJ :label`: jump if A is 0 (the stack unchanged), otherwise pop A.
    CondJump(usize),
    /// `LDPI`: A := the address of the program's code image at byte `.0` plus A.
    Ldpi(i64),
    /// `LB`: A := the byte at address A.
    Lb,
    /// `ADC n`: A := A + n (overflow is an error).
    Adc(i64),
    /// `ADC x` of a variable or other expression: A := A + x (overflow is an error).
    AdcValue(ast::Expr),
    /// `LDNL n`: A := the word at A + 4n.
    Ldnl(i64),
    /// `STNL n`: the word at A + 4n := B; pop both.
    Stnl(i64),
    /// `WSUB`: A := A + 4B, pop B.
    Wsub,
    /// `LDL n`: push workspace slot n (after `AJW`s).
    LoadSlot(i64),
    /// `STL n`: store A in workspace slot n and pop.
    StoreSlot(i64),
    /// `LDLP n`: push the address of workspace slot n.
    SlotAddress(i64),
    /// `OUTWORD`: output the word A on the channel whose address is B (a blocking point).
    Outword,
    /// `CALL p`: call PROC `sym` with A, B, C as its parameters (after dropping A, the static
    /// link occ21 passes to a PROC that uses variables declared outside it; occ passes its own);
    /// a blocking point.
    CallProc {
        /// The PROC.
        sym: SymbolId,
        /// Whether A is a static link to drop.
        skip_link: bool,
    },
    /// `CALL f`: call FUNCTION `sym` with A, B, C as its parameters; its result is left in A.
    CallFunction(SymbolId),
}
