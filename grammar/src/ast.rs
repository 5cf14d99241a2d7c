//! The occam 2.1 abstract syntax tree, as the parser produces it.
//!
//! Contracts the checker relies on:
//! - Every node carries a [`Span`]: byte offsets into the *preprocessed* text (one text with every
//!   `#INCLUDE` expanded). `preprocess::SourceMap` maps a span back to the original file and line.
//! - The tree is purely syntactic. Where occam's syntax is ambiguous without knowing what a name
//!   denotes, the parser picks one shape and the checker resolves it:
//!   - `r[field]` (record field) and `a[i]` (subscript) are both [`ExprKind::Subscript`];
//!   - `T (x)` (conversion to a named type) and `f (x)` (function call) are both [`ExprKind::Call`]
//!     when the operand is parenthesised; `T x` without parentheses is [`ExprKind::Conversion`];
//!   - `CHAN OF P` where `P` is a name is [`ProtoItemKind::Type`] with a [`TyKind::Named`], whether
//!     `P` names a PROTOCOL or a data type;
//!   - `SIZE x` / `BYTESIN (x)` with a bare name are [`TypeOrExpr::Expr`], even if `x` names a type;
//!   - a PROC call `p (a, b)` is [`ProcessKind::Call`]; a tag in an output (`c ! tag; x`) is an
//!     ordinary [`ExprKind::Name`] item.
//! - Declarations are listed in source order; `VAL INT a, b` in a parameter list and `INT x, y:` in
//!   a declaration keep their shared type (parameters are expanded to one [`Param`] per name).
//! - Binary operators nest exactly as parenthesised in the source; a chain of the *same* operator
//!   (`a + b + c`) associates to the left.
//!
//! Changes to this file only add variants and fields (other crates match on these types).

use std::ops::Range;

/// A range of byte offsets into the preprocessed program text.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Span {
    /// Offset of the first byte.
    pub start: usize,
    /// Offset one past the last byte.
    pub end: usize,
}

impl Span {
    /// Creates a span from `start` to `end` (exclusive).
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }

    /// Returns the smallest span covering both `self` and `other`.
    pub fn to(self, other: Span) -> Span {
        Span::new(self.start.min(other.start), self.end.max(other.end))
    }

    /// Returns the span as a byte range.
    pub fn range(self) -> Range<usize> {
        self.start..self.end
    }
}

impl From<Span> for miette::SourceSpan {
    fn from(span: Span) -> Self {
        (span.start, span.end.saturating_sub(span.start)).into()
    }
}

/// A name as written (occam names may contain dots: `out.string`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Name {
    /// The spelling, case preserved.
    pub text: String,
    /// Where it was written.
    pub span: Span,
}

/// A whole program: the top-level declarations of the preprocessed file, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    /// Top-level declarations (PROCs, FUNCTIONs, constants, types, protocols ...).
    pub decls: Vec<Decl>,
    /// `#PRAGMA` directives the preprocessor kept for the checker, in source order.
    pub pragmas: Vec<Pragma>,
}

/// A `#PRAGMA` kept for the checker.
#[derive(Debug, Clone, PartialEq)]
pub struct Pragma {
    /// Which pragma.
    pub kind: PragmaKind,
    /// The names it applies to (`#PRAGMA SHARED c, d` gives `c` and `d`).
    pub names: Vec<Name>,
    /// The whole directive.
    pub span: Span,
    /// For `#PRAGMA EXTERNAL`, the declared routine (`None` when its header did not parse).
    pub external: Option<External>,
}

/// A routine declared by `#PRAGMA EXTERNAL "header = N"` (KRoC's form): a PROC or FUNCTION
/// header without a body, implemented by a native intrinsic the driver links in.
#[derive(Debug, Clone, PartialEq)]
pub struct External {
    /// The routine's name (its span is inside the pragma's string).
    pub name: Name,
    /// The result types: empty for a PROC, one or more for a FUNCTION.
    pub results: Vec<Ty>,
    /// The formal parameters, one per name.
    pub params: Vec<Param>,
    /// The number after `=` (KRoC's workspace size; occ ignores it).
    pub workspace: i64,
    /// The header text inside the quotes.
    pub header: Span,
}

/// The pragmas the checker honours.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PragmaKind {
    /// `#PRAGMA SHARED x`: `x` may be shared between PAR branches without a usage error.
    Shared,
    /// `#PRAGMA PERMITALIASES x`: aliases of `x` are not errors.
    PermitAliases,
    /// `#PRAGMA EXTERNAL "PROC NAME (params) = N"`: declares a routine implemented natively
    /// (see [`Pragma::external`]; `names` holds its name).
    External,
}

/// A type as written.
#[derive(Debug, Clone, PartialEq)]
pub struct Ty {
    /// Which type.
    pub kind: TyKind,
    /// Where it was written.
    pub span: Span,
}

/// The shapes of occam types.
#[derive(Debug, Clone, PartialEq)]
pub enum TyKind {
    /// `BOOL`.
    Bool,
    /// `BYTE`.
    Byte,
    /// `INT` (32 bits, as on the T800).
    Int,
    /// `INT16`.
    Int16,
    /// `INT32`.
    Int32,
    /// `INT64`.
    Int64,
    /// `REAL32`.
    Real32,
    /// `REAL64`.
    Real64,
    /// `TIMER`.
    Timer,
    /// A named data type (`DATA TYPE`, `RECORD`) or, after `CHAN OF`, possibly a PROTOCOL name.
    Named(Name),
    /// `[n]T`, or `[]T` (open array: parameters and abbreviations) when `len` is `None`.
    Array {
        /// The length expression, absent for `[]T`.
        len: Option<Box<Expr>>,
        /// The element type.
        elem: Box<Ty>,
    },
    /// `CHAN OF P` or `CHAN P`.
    Chan(Box<ProtoItem>),
    /// `PORT OF T`.
    Port(Box<Ty>),
}

/// One item of a simple or sequential protocol, and the protocol of a channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ProtoItem {
    /// Which item.
    pub kind: ProtoItemKind,
    /// Where it was written.
    pub span: Span,
}

/// The shapes of a simple protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum ProtoItemKind {
    /// `ANY` (only as a whole channel protocol: `CHAN OF ANY`).
    Any,
    /// A data type, or (for a channel) a named PROTOCOL.
    Type(Ty),
    /// A counted array `count :: []elem`; `elem` is the array type as written (`[]BYTE`).
    Counted {
        /// The count's type (an integer type).
        count: Ty,
        /// The array type (usually open: `[]T`).
        elem: Ty,
    },
}

/// The definition of a PROTOCOL.
#[derive(Debug, Clone, PartialEq)]
pub enum ProtocolDef {
    /// `PROTOCOL P IS a; b; c:` (one item is a simple protocol, several a sequential one).
    Sequential(Vec<ProtoItem>),
    /// `PROTOCOL P` / `CASE` / `tag; items` ... `:`.
    Tagged(Vec<TaggedCase>),
}

/// One tag of a tagged protocol: `tag` or `tag; INT; BYTE`.
#[derive(Debug, Clone, PartialEq)]
pub struct TaggedCase {
    /// The tag.
    pub tag: Name,
    /// What follows the tag (possibly nothing).
    pub items: Vec<ProtoItem>,
    /// The whole line.
    pub span: Span,
}

/// An expression (also used for variables, channels and timers: occam's "element").
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// Which expression.
    pub kind: ExprKind,
    /// Where it was written.
    pub span: Span,
}

/// The shapes of expressions.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A literal, possibly typed (`5(INT64)`).
    Literal(Literal),
    /// A name: variable, constant, channel, timer, tag, or (in some positions) a type.
    Name(Name),
    /// `base[index]`: an array subscript or a record field selection (`r[field]`).
    Subscript {
        /// The array or record.
        base: Box<Expr>,
        /// The index, or the field name as an [`ExprKind::Name`].
        index: Box<Expr>,
    },
    /// `[base FROM from FOR count]`, `[base FROM from]`, `[base FOR count]`.
    Slice {
        /// The array sliced.
        base: Box<Expr>,
        /// The first index, absent for `[a FOR n]` (meaning 0).
        from: Option<Box<Expr>>,
        /// The length, absent for `[a FROM i]` (meaning to the end).
        count: Option<Box<Expr>>,
    },
    /// A monadic operator applied to an operand.
    Unary {
        /// The operator.
        op: UnOp,
        /// The operand.
        operand: Box<Expr>,
    },
    /// A dyadic operator.
    Binary {
        /// The operator.
        op: BinOp,
        /// Left operand.
        lhs: Box<Expr>,
        /// Right operand.
        rhs: Box<Expr>,
    },
    /// `T x`, `T ROUND x`, `T TRUNC x`.
    Conversion {
        /// The target type.
        ty: Ty,
        /// Plain, ROUND or TRUNC.
        mode: ConvMode,
        /// The operand.
        operand: Box<Expr>,
    },
    /// `MOSTPOS T`.
    MostPos(Ty),
    /// `MOSTNEG T`.
    MostNeg(Ty),
    /// `SIZE x` (or `SIZE T` on an array type).
    Size(Box<TypeOrExpr>),
    /// `BYTESIN (x)` or `BYTESIN (T)`.
    BytesIn(Box<TypeOrExpr>),
    /// `OFFSETOF (T, field)`.
    OffsetOf {
        /// The record type.
        ty: Ty,
        /// The field.
        field: Name,
    },
    /// `f (a, b)`: a FUNCTION call (or a conversion to a named type, see the module doc).
    Call {
        /// The function.
        name: Name,
        /// The actual parameters.
        args: Vec<Expr>,
    },
    /// A table `[a, b, c]`.
    Table(Vec<Expr>),
    /// A parenthesised expression list `(a, b)`, as compared in `(a, b) = (c, d)`.
    List(Vec<Expr>),
    /// A table decorated with a type, as a RECORD or array literal: `[3, 4](POINT)`.
    TypedTable {
        /// The elements (or fields, in order).
        items: Vec<Expr>,
        /// The decorating type.
        ty: Ty,
    },
    /// An array constructor `[i = base FOR count STEP s | value]`.
    Constructor {
        /// The replicator.
        repl: Box<Replicator>,
        /// The element value.
        value: Box<Expr>,
    },
    /// `(VALOF ... RESULT e)` (with any leading declarations).
    Valof(Box<Valof>),
    /// `c?` / `c!`: a channel with a direction specifier (actuals and abbreviations).
    Directed {
        /// The channel.
        chan: Box<Expr>,
        /// The direction.
        dir: Direction,
    },
}

/// Either a type or an expression (operand of `SIZE` and `BYTESIN`).
#[derive(Debug, Clone, PartialEq)]
pub enum TypeOrExpr {
    /// A type that cannot be an expression (`[4]INT`, `INT`).
    Type(Ty),
    /// An expression (a bare name is always this).
    Expr(Expr),
}

/// A literal with its optional type decoration.
#[derive(Debug, Clone, PartialEq)]
pub struct Literal {
    /// The value.
    pub kind: LitKind,
    /// The type in `5(INT64)`, `2.0(REAL32)`, `'a'(BYTE)`; absent for an untyped literal.
    pub ty: Option<Ty>,
}

/// The literal forms.
#[derive(Debug, Clone, PartialEq)]
pub enum LitKind {
    /// A decimal (`42`) or hexadecimal (`#2A`) integer, as an unsigned value. Hexadecimal literals
    /// are bit patterns in occam (`#FFFFFFFF` is -1 as an INT), so the form is kept.
    Int {
        /// The value as written (no sign; the `-` of `-1` is a unary operator).
        value: u64,
        /// Written with `#`.
        hex: bool,
    },
    /// A character `'c'` (escapes resolved).
    Byte(u8),
    /// A REAL literal kept as written (`1.0E+3`), so that the checker rounds it once to its type.
    Real(String),
    /// `TRUE` or `FALSE`.
    Bool(bool),
    /// A string, a `[]BYTE` (escapes resolved).
    String(Vec<u8>),
}

/// Monadic operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UnOp {
    /// `-x`.
    Neg,
    /// `MINUS x` (modulo negation).
    Minus,
    /// `~x` or `BITNOT x`.
    BitNot,
    /// `NOT x`.
    Not,
    /// An operator with no built-in meaning, defined by the program (`?? x`).
    User(UserOp),
}

/// How many operands an operator that a program may define takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arity {
    /// Two (`+`, `AND`, `<`).
    Dyadic,
    /// One (`NOT`, `~`).
    Monadic,
    /// One or two (`-`, `MINUS`, and every [`UserOp`]).
    Either,
}

/// Returns the operand counts of the operator spelled `spelling`, when it is one a program may
/// define (`INT FUNCTION "+" (...)`), as occ21's `rnameorstring` lists them.
pub fn operator_arity(spelling: &str) -> Option<Arity> {
    const DYADIC: &[&str] = &[
        "+", "/", "*", "\\", "PLUS", "TIMES", "AFTER", "AND", "OR", "><", "/\\", "\\/", ">>", "<<",
        "=", "<>", "<", ">", "<=", ">=",
    ];
    if DYADIC.contains(&spelling) {
        return Some(Arity::Dyadic);
    }
    if matches!(spelling, "~" | "NOT") {
        return Some(Arity::Monadic);
    }
    let either =
        matches!(spelling, "-" | "MINUS") || UserOp::ALL.iter().any(|(_, text)| *text == spelling);
    either.then_some(Arity::Either)
}

/// The operator symbols KRoC's occ21 lets a program define (`INT FUNCTION "++" (...)`) and that
/// have no built-in meaning. Each may be used monadic or dyadic, as its definitions allow.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[allow(
    missing_docs,
    reason = "each variant is the operator spelled in `UserOp::text`"
)]
pub enum UserOp {
    DQuery,
    DAt,
    DDollar,
    Percent,
    DPercent,
    DAmp,
    LeftPercent,
    PercentRight,
    LeftAmp,
    AmpRight,
    RotLeft,
    RotRight,
    DPlus,
    Hat,
    DBang,
    DEq,
    LeftAt,
    AtRight,
    At,
}

impl UserOp {
    /// Every user-definable operator with its spelling.
    pub const ALL: [(UserOp, &'static str); 19] = [
        (UserOp::DQuery, "??"),
        (UserOp::DAt, "@@"),
        (UserOp::DDollar, "$$"),
        (UserOp::Percent, "%"),
        (UserOp::DPercent, "%%"),
        (UserOp::DAmp, "&&"),
        (UserOp::LeftPercent, "<%"),
        (UserOp::PercentRight, "%>"),
        (UserOp::LeftAmp, "<&"),
        (UserOp::AmpRight, "&>"),
        (UserOp::RotLeft, "<]"),
        (UserOp::RotRight, "[>"),
        (UserOp::DPlus, "++"),
        (UserOp::Hat, "^"),
        (UserOp::DBang, "!!"),
        (UserOp::DEq, "=="),
        (UserOp::LeftAt, "<@"),
        (UserOp::AtRight, "@>"),
        (UserOp::At, "@"),
    ];

    /// Returns the operator's spelling.
    pub fn text(self) -> &'static str {
        UserOp::ALL
            .iter()
            .find(|(op, _)| *op == self)
            .map_or("?", |(_, s)| s)
    }
}

/// Dyadic operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinOp {
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `*`.
    Mul,
    /// `/`.
    Div,
    /// `\` or `REM`.
    Rem,
    /// `PLUS` (modulo).
    Plus,
    /// `MINUS` (modulo).
    Minus,
    /// `TIMES` (modulo).
    Times,
    /// `/\` or `BITAND`.
    BitAnd,
    /// `\/` or `BITOR`.
    BitOr,
    /// `><`.
    Xor,
    /// `<<`.
    Shl,
    /// `>>`.
    Shr,
    /// `AND`.
    And,
    /// `OR`.
    Or,
    /// `=`.
    Eq,
    /// `<>`.
    Ne,
    /// `<`.
    Lt,
    /// `>`.
    Gt,
    /// `<=`.
    Le,
    /// `>=`.
    Ge,
    /// `AFTER` (modulo comparison of times).
    After,
    /// An operator with no built-in meaning, defined by the program (`a ++ b`).
    User(UserOp),
}

/// The three forms of conversion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConvMode {
    /// `T x`.
    Plain,
    /// `T ROUND x`.
    Round,
    /// `T TRUNC x`.
    Trunc,
}

/// A channel direction specifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// `c?`: this end only inputs.
    Input,
    /// `c!`: this end only outputs.
    Output,
}

/// `name = base FOR count` or `name = base FOR count STEP step`.
#[derive(Debug, Clone, PartialEq)]
pub struct Replicator {
    /// The index name (a VAL INT in the body).
    pub name: Name,
    /// The first value.
    pub base: Expr,
    /// How many replications.
    pub count: Expr,
    /// The step between index values (1 when absent).
    pub step: Option<Expr>,
    /// The whole replicator.
    pub span: Span,
}

/// `VALOF process RESULT e1, e2`, possibly preceded by declarations.
#[derive(Debug, Clone, PartialEq)]
pub struct Valof {
    /// Declarations in scope for the body and the results.
    pub decls: Vec<Decl>,
    /// The value process.
    pub body: Process,
    /// The result expressions.
    pub results: Vec<Expr>,
    /// From the first declaration (or `VALOF`) to the last result.
    pub span: Span,
}

/// A declaration (occam's "specification"): it scopes over what follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct Decl {
    /// Which declaration.
    pub kind: DeclKind,
    /// From its first token to its closing `:`.
    pub span: Span,
}

/// The shapes of declarations.
#[derive(Debug, Clone, PartialEq)]
pub enum DeclKind {
    /// `T a, b:` — variables, channels (`CHAN OF P c:`), timers, ports, arrays of them.
    Var {
        /// The declared type.
        ty: Ty,
        /// The names declared.
        names: Vec<Name>,
    },
    /// `VAL T x IS e:`, `T x IS v:`, `RESULT T x IS v:`, `INITIAL T x IS e:` (type optional).
    Abbrev {
        /// VAL, plain (reference), RESULT or INITIAL.
        mode: AbbrevMode,
        /// The declared type, if written.
        ty: Option<Ty>,
        /// The new name.
        name: Name,
        /// A direction specifier on the new name (`CHAN INT out! IS c!:`).
        dir: Option<Direction>,
        /// The abbreviated expression or element.
        value: Expr,
    },
    /// `VAL T x RETYPES e:`, `T x RETYPES v:` and the RESHAPES forms.
    Retypes {
        /// RETYPES or RESHAPES.
        kind: RetypeKind,
        /// Written with VAL.
        val: bool,
        /// The new type.
        ty: Ty,
        /// The new name.
        name: Name,
        /// The retyped expression or element.
        value: Expr,
    },
    /// `DATA TYPE X IS T:` or `DATA TYPE X` / `RECORD` / fields `:`.
    DataType {
        /// The new type's name.
        name: Name,
        /// Its definition.
        def: DataTypeDef,
    },
    /// `PROTOCOL P IS ...:` or a tagged `PROTOCOL P` / `CASE` ... `:`.
    Protocol {
        /// The protocol's name.
        name: Name,
        /// Its definition.
        def: ProtocolDef,
    },
    /// `PROC p (params)` / body / `:` (optionally `INLINE PROC`).
    Proc {
        /// The PROC's name.
        name: Name,
        /// Written `INLINE PROC`.
        inline: bool,
        /// The formal parameters, one per name.
        params: Vec<Param>,
        /// The body.
        body: Box<Process>,
    },
    /// `T1, T2 FUNCTION f (params)` with a VALOF body or an `IS` expression list.
    Function {
        /// The FUNCTION's name.
        name: Name,
        /// Written `INLINE FUNCTION`.
        inline: bool,
        /// The result types.
        results: Vec<Ty>,
        /// The formal parameters (all VAL in occam 2.1), one per name.
        params: Vec<Param>,
        /// The body.
        body: FunctionBody,
    },
    /// `PLACE x AT e:`.
    Place {
        /// The placed name.
        name: Name,
        /// The address.
        at: Expr,
    },
    /// A transputer `ASM` / `GUY` block kept as opaque text (it cannot run here).
    Asm(AsmBlock),
    /// `PLACE x IN WORKSPACE:` / `PLACE x IN VECSPACE:` (an allocation hint; no effect here).
    PlaceIn {
        /// The placed name.
        name: Name,
        /// `WORKSPACE` or `VECSPACE`.
        area: Name,
    },
}

/// VAL, reference, RESULT or INITIAL.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AbbrevMode {
    /// `VAL`: a constant view of a value.
    Val,
    /// No keyword: a reference to an element (variable, channel, timer, array part).
    Ref,
    /// `RESULT`: a reference that is only written.
    Result,
    /// `INITIAL`: a new variable initialised from the value.
    Initial,
}

/// RETYPES or RESHAPES.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RetypeKind {
    /// `RETYPES`: reinterpret the bits.
    Retypes,
    /// `RESHAPES`: change the array shape over the same elements.
    Reshapes,
}

/// The definition of a DATA TYPE.
#[derive(Debug, Clone, PartialEq)]
pub enum DataTypeDef {
    /// `DATA TYPE X IS T:`.
    Alias(Ty),
    /// `RECORD` or `PACKED RECORD` with its fields.
    Record {
        /// Written `PACKED RECORD`.
        packed: bool,
        /// The fields in order.
        fields: Vec<Field>,
    },
}

/// One field line of a RECORD: `T a, b:`.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// The fields' type.
    pub ty: Ty,
    /// The field names.
    pub names: Vec<Name>,
    /// The whole line.
    pub span: Span,
}

/// The body of a FUNCTION.
#[derive(Debug, Clone, PartialEq)]
pub enum FunctionBody {
    /// The VALOF form.
    Valof(Box<Valof>),
    /// `IS e1, e2:`.
    Is(Vec<Expr>),
}

/// One formal parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// VAL, reference or RESULT.
    pub mode: ParamMode,
    /// Its type (shared types `VAL INT a, b` are repeated for each name).
    pub ty: Ty,
    /// Its name.
    pub name: Name,
    /// A direction specifier on a channel parameter (`CHAN INT in?`).
    pub dir: Option<Direction>,
    /// The name (and its type when written for this parameter).
    pub span: Span,
}

/// How a parameter is passed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamMode {
    /// `VAL T x`.
    Val,
    /// `T x` (by reference).
    Ref,
    /// `RESULT T x`.
    Result,
}

/// An opaque `ASM` or `GUY` block.
#[derive(Debug, Clone, PartialEq)]
pub struct AsmBlock {
    /// `GUY` rather than `ASM`.
    pub guy: bool,
    /// The indented lines, as written (indentation removed).
    pub lines: Vec<String>,
    /// Where each line's kept text is (so `lines[i][k]` is at `line_spans[i].start + k`), for
    /// diagnostics on one line of the block.
    pub line_spans: Vec<Span>,
}

/// A process.
#[derive(Debug, Clone, PartialEq)]
pub struct Process {
    /// Which process.
    pub kind: ProcessKind,
    /// Where it was written (including its body).
    pub span: Span,
}

impl Process {
    /// The body of a variant of `c ?? CASE` (an [`ProcessKind::Extended`] with a SKIP input):
    /// the process run while the outputter is held and the one run after its release.
    pub fn held_parts(&self) -> Option<(&Process, Option<&Process>)> {
        match &self.kind {
            ProcessKind::Extended {
                input,
                during,
                after,
            } if matches!(input.kind, ProcessKind::Skip) => Some((during, after.as_deref())),
            _ => None,
        }
    }

    /// Whether this, the input of an [`ProcessKind::Extended`], is `c ?? CASE` with indented
    /// variants, each of whose bodies has [`Process::held_parts`].
    pub fn is_held_case(&self) -> bool {
        match &self.kind {
            ProcessKind::CaseInput { variants, .. } => {
                !variants.is_empty() && variants.iter().all(|v| v.body.held_parts().is_some())
            }
            _ => false,
        }
    }
}

/// The shapes of processes.
#[derive(Debug, Clone, PartialEq)]
pub enum ProcessKind {
    /// `SKIP`.
    Skip,
    /// `STOP`.
    Stop,
    /// Declarations followed by the process they scope over.
    Scope {
        /// The declarations, in order.
        decls: Vec<Decl>,
        /// The process in their scope.
        body: Box<Process>,
    },
    /// `a, b := e1, e2` (one or more on each side; the right may be one multi-result call).
    Assign {
        /// The assigned variables.
        lhs: Vec<Expr>,
        /// The values.
        rhs: Vec<Expr>,
    },
    /// `c ! e1; e2` (a tag is an item too).
    Output {
        /// The channel.
        chan: Expr,
        /// The items, in order.
        items: Vec<IoItem>,
    },
    /// `c ? x; y` (also a timer read `t ? now`).
    Input {
        /// The channel or timer.
        chan: Expr,
        /// The items, in order.
        items: Vec<IoItem>,
    },
    /// occam-pi's extended rendezvous: `c ?? x; y` (or `c ?? CASE tag; x`) then an indented
    /// process `during` and optionally a second, `after`. The inputter receives, runs `during`
    /// while the outputter stays blocked, releases the outputter, then runs `after`.
    Extended {
        /// The input, a [`ProcessKind::Input`] or a one-variant [`ProcessKind::CaseInput`].
        input: Box<Process>,
        /// The process run while the outputter is held.
        during: Box<Process>,
        /// The process run after the outputter is released.
        after: Option<Box<Process>>,
    },
    /// `c ? CASE` with indented variants, or the one-line `c ? CASE tag; x` (one variant, body SKIP).
    CaseInput {
        /// The channel.
        chan: Expr,
        /// The variants.
        variants: Vec<Variant>,
    },
    /// `t ? AFTER e`.
    Delay {
        /// The timer.
        timer: Expr,
        /// The time to wait until.
        time: Expr,
    },
    /// `SEQ` (possibly replicated).
    Seq {
        /// The replicator, if any.
        repl: Option<Box<Replicator>>,
        /// The component processes.
        body: Vec<Process>,
    },
    /// `PAR`, `PRI PAR`, `PLACED PAR` (possibly replicated).
    Par {
        /// Written `PRI PAR`.
        pri: bool,
        /// Written `PLACED PAR`.
        placed: bool,
        /// The replicator, if any.
        repl: Option<Box<Replicator>>,
        /// The component processes.
        body: Vec<Process>,
    },
    /// `PROCESSOR n` inside a PLACED PAR.
    Processor {
        /// The processor number.
        number: Expr,
        /// The process placed there.
        body: Box<Process>,
    },
    /// `IF` (possibly replicated).
    If {
        /// The replicator, if any.
        repl: Option<Box<Replicator>>,
        /// The choices in order.
        choices: Vec<Choice>,
    },
    /// `ALT` or `PRI ALT` (possibly replicated).
    Alt(Box<Alt>),
    /// `CASE selector` with its options.
    Case {
        /// The selector.
        selector: Expr,
        /// The options in order.
        options: Vec<CaseOption>,
    },
    /// `WHILE cond`.
    While {
        /// The condition.
        cond: Expr,
        /// The body.
        body: Box<Process>,
    },
    /// `p (a, b)`: a PROC call.
    Call {
        /// The PROC.
        name: Name,
        /// The actuals.
        args: Vec<Expr>,
    },
    /// An `ASM` / `GUY` block used as a process.
    Asm(AsmBlock),
}

/// One item of an input or output.
#[derive(Debug, Clone, PartialEq)]
pub enum IoItem {
    /// An expression (output) or a variable (input).
    Expr(Expr),
    /// `count :: data`.
    Counted {
        /// The count.
        count: Expr,
        /// The array.
        data: Expr,
    },
}

/// One variant of a `? CASE`: `tag; x; y` then an indented process.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// Declarations before the variant line.
    pub decls: Vec<Decl>,
    /// The tag.
    pub tag: Name,
    /// The input items after the tag.
    pub items: Vec<IoItem>,
    /// The process run after the input.
    pub body: Process,
    /// The whole variant.
    pub span: Span,
}

/// One choice of an IF.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    /// Declarations before the choice.
    pub decls: Vec<Decl>,
    /// A guarded choice or a nested IF.
    pub kind: ChoiceKind,
    /// The whole choice.
    pub span: Span,
}

/// A guarded choice or a nested IF.
#[derive(Debug, Clone, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "the guarded form is by far the common one; boxing it would change a shape other crates match on"
)]
pub enum ChoiceKind {
    /// `cond` then an indented process.
    Guarded {
        /// The boolean condition.
        cond: Expr,
        /// The process run when it is the first TRUE condition.
        body: Process,
    },
    /// A nested (possibly replicated) IF: a [`ProcessKind::If`].
    Nested(Box<Process>),
}

/// An ALT or PRI ALT.
#[derive(Debug, Clone, PartialEq)]
pub struct Alt {
    /// Written `PRI ALT`.
    pub pri: bool,
    /// The replicator, if any.
    pub repl: Option<Replicator>,
    /// The alternatives in order.
    pub alternatives: Vec<Alternative>,
}

/// One alternative of an ALT.
#[derive(Debug, Clone, PartialEq)]
pub struct Alternative {
    /// Declarations before the alternative.
    pub decls: Vec<Decl>,
    /// The guard and body, or a nested ALT.
    pub kind: AltKind,
    /// The whole alternative.
    pub span: Span,
}

/// The shapes of alternatives.
#[derive(Debug, Clone, PartialEq)]
pub enum AltKind {
    /// `[cond &] guard` then an indented process. `guard` is a [`ProcessKind::Input`],
    /// [`ProcessKind::Delay`] or [`ProcessKind::Skip`], or a [`ProcessKind::Extended`] input
    /// (`c ?? x` and its first process; `body` is then its second process, or SKIP).
    Guarded {
        /// The boolean pre-condition (`cond & ...`).
        cond: Option<Expr>,
        /// The input, delay or SKIP.
        guard: Box<Process>,
        /// The process run when chosen.
        body: Box<Process>,
    },
    /// `[cond &] c ? CASE` with indented variants.
    CaseInput {
        /// The boolean pre-condition.
        cond: Option<Expr>,
        /// The channel.
        chan: Expr,
        /// The variants.
        variants: Vec<Variant>,
    },
    /// A nested (possibly replicated) ALT.
    Nested(Box<Alt>),
}

/// One option of a CASE.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseOption {
    /// Declarations before the option.
    pub decls: Vec<Decl>,
    /// The selecting constants, or `None` for `ELSE`.
    pub values: Option<Vec<Expr>>,
    /// The process run when selected.
    pub body: Process,
    /// The whole option.
    pub span: Span,
}
