//! The checker's diagnostics: errors are data.
//!
//! A [`Diagnostic`] is a [`DiagnosticKind`] (what went wrong, with the names and types involved)
//! plus the span of the offending text and, sometimes, a second related span. Its message, label
//! and help are derived from the kind, so that tests can assert on kinds and users read concrete
//! messages in occam's terms. Spans are byte offsets into the preprocessed program text; the CLI
//! maps them back to files and lines.

use occ_grammar::ast::Span;
pub use occ_grammar::diagnostic::Severity;

/// What went wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum DiagnosticKind {
    /// Occurs when a name is used that is not in scope. Example: `x := 1` with no `INT x:`.
    Undeclared {
        /// The name.
        name: String,
    },
    /// Occurs when a name is declared twice in one parameter list or record. Example: `PROC p (INT a, a)`.
    Duplicate {
        /// The name.
        name: String,
    },
    /// Occurs when a name denotes the wrong kind of thing. Example: `INT x:` then `x (1)` as a call.
    WrongKind {
        /// The name.
        name: String,
        /// What the context wanted ("a PROC", "a channel").
        expected: &'static str,
        /// What the name is ("a variable").
        found: &'static str,
    },
    /// Occurs when a value's type is not the type its context needs. Example: `INT x:` then `x := TRUE`.
    TypeMismatch {
        /// The type the context needs.
        expected: String,
        /// The type found.
        found: String,
    },
    /// Occurs when an operator does not apply to its operand type. Example: `TRUE + FALSE`.
    BadOperand {
        /// The operator as written.
        op: &'static str,
        /// The operand type.
        ty: String,
    },
    /// Occurs when a FUNCTION named as an operator is not one a program may define, or has the
    /// wrong number of parameters or results. Example: `INT FUNCTION "+" (VAL INT a)`.
    BadOperatorDefinition {
        /// The operator's spelling.
        op: String,
        /// What is wrong.
        why: &'static str,
    },
    /// Occurs when an operator with no built-in meaning is applied to operand types for which
    /// no definition is in scope. Example: `a ++ b` with no `FUNCTION "++"` taking their types.
    NoOperator {
        /// The operator.
        op: &'static str,
        /// The operand types, comma-separated.
        operands: String,
    },
    /// Occurs when different dyadic operators are mixed without parentheses. Example: `a + b * c`.
    NeedsParentheses,
    /// Occurs when a constant expression is an error in occam (overflow, division by zero, shift
    /// count, range). Example: `VAL INT16 x IS 32767(INT16) + 1(INT16):`.
    ConstantError {
        /// What happened ("overflow in INT16 expression").
        what: String,
    },
    /// Occurs when a REAL is converted to an integer type without ROUND or TRUNC. Example: `INT x` for a REAL32 `x`.
    NeedsRounding {
        /// The source type.
        from: &'static str,
        /// The target type.
        to: &'static str,
    },
    /// Occurs when two options of a CASE select the same value. Example: `CASE x` / `1` ... `1`.
    DuplicateOption {
        /// The value, as written.
        value: String,
    },
    /// Occurs when a CASE has more than one ELSE. Example: `ELSE` ... `ELSE` in one CASE.
    DuplicateElse,
    /// Occurs when a VALOF (a FUNCTION body or value process) holds a PAR or ALT.
    /// Example: `INT FUNCTION f () ... VALOF` / `PAR` ...
    NotInValof {
        /// `PAR` or `ALT`.
        what: &'static str,
    },
    /// Occurs when a PRI PAR is nested in the high-priority branch of another (there are only
    /// two priorities). Example: `PRI PAR` / `  PRI PAR` ...
    NestedPriPar,
    /// Occurs when an extended input `??` reads a timer or a port, which has no outputter to
    /// hold. Example: `TIMER t:` / `t ?? now` ...
    ExtendedNotChannel {
        /// `a timer` or `a port`.
        what: &'static str,
    },
    /// Occurs when the exponent of a REAL literal has no sign. Example: `1.0E5` for `1.0E+5`.
    ExponentSign,
    /// Occurs when a FUNCTION or VALOF changes or communicates on something declared outside
    /// it. Example: `INT FUNCTION f () ... VALOF total := 0 ...` with `total` a free variable.
    SideEffect {
        /// The variable or channel.
        name: String,
    },
    /// Occurs when a constant is required and the expression is not one. Example: `[n]INT a:` with a variable `n`.
    NotConstant {
        /// Where a constant was needed ("array size", "CASE option").
        context: &'static str,
    },
    /// Occurs when something is assigned or input to that cannot change. Example: `VAL INT x IS 1:` then `x := 2`.
    NotAssignable {
        /// The name.
        name: String,
    },
    /// Occurs when a call has the wrong number of actual parameters. Example: `p (1, 2)` for `PROC p (INT a)`.
    ArgumentCount {
        /// The PROC or FUNCTION.
        name: String,
        /// Formal parameters.
        expected: usize,
        /// Actual parameters.
        found: usize,
    },
    /// Occurs when the number of values differs from the number of targets. Example: `a, b := 1`.
    ValueCount {
        /// Targets or results expected.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// Occurs when a communication does not match the channel's protocol. Example: `c ! 1; 2` on a `CHAN OF INT`.
    Protocol {
        /// What is wrong, concretely.
        what: String,
    },
    /// Occurs when a channel is used against its direction specifier. Example: `c ! 1` for a parameter `CHAN INT c?`.
    Direction {
        /// The channel.
        name: String,
        /// "input" or "output": what was attempted.
        used_for: &'static str,
    },
    /// Occurs when a PROC or FUNCTION calls itself (occam has no recursion). Example: `PROC p () p () :`.
    Recursion {
        /// The PROC or FUNCTION.
        name: String,
    },
    /// Occurs when a variable is assigned in one branch of a PAR and used in another. Example:
    /// `PAR` / `x := 1` / `y := x`.
    ParUsage {
        /// The variable.
        name: String,
    },
    /// Occurs when a channel is used for input (or output) in more than one branch of a PAR.
    /// Example: `PAR` / `c ? x` / `c ? y`.
    ParChannel {
        /// The channel.
        name: String,
        /// "input" or "output".
        used_for: &'static str,
    },
    /// Occurs when an abbreviated variable is used while its abbreviation is in scope, or the same
    /// variable is passed twice by reference. Example: `INT y IS x:` then `x := 1`.
    Alias {
        /// The variable.
        name: String,
    },
    /// Occurs when RETYPES sizes differ where both are known. Example: `VAL INT x RETYPES 'a':`.
    RetypeSize {
        /// Bytes of the new type.
        to: u32,
        /// Bytes of the value.
        from: u32,
    },
    /// Occurs when a construct is valid occam that this checker does not handle. Example: `PLACE x AT 0:`.
    Unsupported {
        /// What it is.
        what: &'static str,
    },
    /// Occurs when a line of an `ASM` or `GUY` block is not an instruction occ runs. Example:
    /// `ASM` with the line `FPADD`, or `J :nowhere` with no label `:nowhere`.
    Asm {
        /// What is wrong.
        what: String,
    },
    /// Occurs when a record has no field of that name. Example: `p[zz]` for a `RECORD` without `zz`.
    NoSuchField {
        /// The field.
        field: String,
        /// The record type.
        record: String,
    },
    /// Occurs when a protocol has no tag of that name. Example: `c ! nosuch` on a tagged protocol.
    NoSuchTag {
        /// The tag.
        tag: String,
        /// The protocol.
        protocol: String,
    },
    /// Occurs when a network configuration (`PLACED PAR` / `PROCESSOR`) cannot be built.
    /// Example: a PROCESSOR with channels to five others.
    Network {
        /// What is wrong, naming the processors and channels.
        what: String,
        /// How to fix it.
        help: &'static str,
    },
    /// Occurs when a constant subscript is outside the array. Example: `[4]INT a:` then `a[4]`.
    OutOfBounds {
        /// The subscript.
        index: i64,
        /// The array length.
        len: u32,
    },
}

impl DiagnosticKind {
    /// Returns the variant's name (`ParUsage`), a stable code for tools and tests.
    pub fn name(&self) -> String {
        let debug = format!("{self:?}");
        let end = debug.find([' ', '{', '(']).unwrap_or(debug.len());
        debug[..end].to_string()
    }

    /// Returns the one-line message: lower case, concrete, naming the thing.
    pub fn message(&self) -> String {
        use DiagnosticKind::*;
        match self {
            Undeclared { name } => format!("`{name}` is not declared"),
            Duplicate { name } => format!("`{name}` is declared twice here"),
            WrongKind {
                name,
                expected,
                found,
            } => {
                format!("`{name}` is {found}, but {expected} is needed here")
            }
            TypeMismatch { expected, found } => {
                format!("type mismatch: expected {expected}, found {found}")
            }
            BadOperand { op, ty } => format!("operator {op} cannot be applied to {ty}"),
            NeedsParentheses => "different operators need parentheses in occam".into(),
            BadOperatorDefinition { op, why } => {
                format!("\"{op}\" cannot be defined as an operator here: {why}")
            }
            NoOperator { op, operands } => {
                format!("no operator {op} is defined for ({operands})")
            }
            ConstantError { what } => format!("constant {what}"),
            NeedsRounding { from, to } => {
                format!("conversion from {from} to {to} needs ROUND or TRUNC")
            }
            DuplicateOption { value } => format!("CASE option {value} appears more than once"),
            DuplicateElse => "a CASE may have only one ELSE".into(),
            NotInValof { what } => {
                format!("{what} is not allowed in a FUNCTION or VALOF (a value process)")
            }
            ExtendedNotChannel { what } => format!(
                "an extended input (`??`) needs a channel, and this is {what} (it has no outputter to hold)"
            ),
            NestedPriPar => {
                "PRI PAR inside the high-priority branch of a PRI PAR (there are only two priorities)"
                    .into()
            }
            ExponentSign => {
                "the exponent of a REAL literal needs a sign: write E+n or E-n".into()
            }
            SideEffect { name } => format!(
                "`{name}` is declared outside this FUNCTION or VALOF, which may not change it or communicate on it"
            ),
            NotConstant { context } => format!("{context} must be a constant"),
            NotAssignable { name } => format!("`{name}` cannot be assigned: it is a constant"),
            ArgumentCount {
                name,
                expected,
                found,
            } => {
                format!("`{name}` takes {expected} parameters, but {found} were given")
            }
            ValueCount { expected, found } => {
                format!("expected {expected} values, found {found}")
            }
            Protocol { what } => format!("protocol mismatch: {what}"),
            Direction { name, used_for } => {
                format!("`{name}` is used for {used_for} against its direction specifier")
            }
            Recursion { name } => format!("`{name}` calls itself: occam does not allow recursion"),
            ParUsage { name } => {
                format!("`{name}` is written in one branch of this PAR and used in another")
            }
            ParChannel { name, used_for } => {
                format!("`{name}` is used for {used_for} in more than one branch of this PAR")
            }
            Alias { name } => {
                format!("`{name}` is aliased: it is used while another name for it is in scope")
            }
            RetypeSize { to, from } => {
                format!("RETYPES size mismatch: the new type has {to} bytes, the value {from}")
            }
            Unsupported { what } => format!("{what} is not supported"),
            Asm { what } => what.clone(),
            NoSuchField { field, record } => format!("record {record} has no field `{field}`"),
            NoSuchTag { tag, protocol } => format!("protocol {protocol} has no tag `{tag}`"),
            OutOfBounds { index, len } => {
                format!("subscript {index} is out of range for an array of {len} elements")
            }
            Network { what, .. } => what.clone(),
        }
    }

    /// Returns the label text put under the offending span.
    pub fn label(&self) -> String {
        use DiagnosticKind::*;
        match self {
            Undeclared { .. } => "not found in scope".into(),
            TypeMismatch { found, .. } => format!("this is {found}"),
            NeedsParentheses => "this mixes operators".into(),
            ParUsage { .. } | ParChannel { .. } => "in this branch".into(),
            _ => "here".into(),
        }
    }

    /// Returns help in occam terms where the fix is clear.
    pub fn help(&self) -> Option<String> {
        use DiagnosticKind::*;
        match self {
            NeedsParentheses => Some(
                "write (a + b) * c: occam needs parentheses between different operators".into(),
            ),
            Undeclared { name } => Some(format!(
                "declare `{name}` before this process, for example `INT {name}:`"
            )),
            ParUsage { name } => Some(format!(
                "give each branch its own copy of `{name}`, or communicate it over a channel"
            )),
            ParChannel { .. } => Some(
                "each channel has one reader and one writer in a PAR: use a channel per branch"
                    .into(),
            ),
            Recursion { .. } => {
                Some("rewrite the recursion as a loop (WHILE) with an explicit stack".into())
            }
            NoOperator { op, operands } => Some(format!(
                "declare it, for example `INT FUNCTION \"{op}\" (...)` taking ({operands})"
            )),
            NeedsRounding { to, .. } => Some(format!(
                "write `{to} ROUND x` (nearest) or `{to} TRUNC x` (toward zero)"
            )),
            NotAssignable { name } => Some(format!(
                "declare `{name}` as a variable (`INT {name}:`) rather than a VAL"
            )),
            Network { help, .. } => Some((*help).into()),
            _ => None,
        }
    }
}

/// One finding of the checker: a kind, where it is, and related places. It becomes the one
/// diagnostic type of occ ([`occ_grammar::diagnostic::Diagnostic`]) through
/// [`Diagnostic::to_diagnostic`], which every renderer uses; tests assert on its kind.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    /// What went wrong.
    pub kind: DiagnosticKind,
    /// The offending text.
    pub span: Span,
    /// Related places ("the other branch", "declared here"), each with its label.
    pub related: Vec<(Span, String)>,
    /// Error or warning.
    pub severity: Severity,
    /// A label for `span` more specific than the kind's (see [`DiagnosticKind::label`]).
    pub label: Option<String>,
}

impl Diagnostic {
    /// Creates an error at `span`.
    pub fn error(kind: DiagnosticKind, span: Span) -> Self {
        Diagnostic {
            kind,
            span,
            related: Vec::new(),
            severity: Severity::Error,
            label: None,
        }
    }

    /// Replaces the label under the main span.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    /// Returns the label under the main span.
    pub fn label(&self) -> String {
        self.label.clone().unwrap_or_else(|| self.kind.label())
    }

    /// Adds a related span with its label.
    pub fn with_related(mut self, span: Span, label: impl Into<String>) -> Self {
        self.related.push((span, label.into()));
        self
    }

    /// Returns the one-line message.
    pub fn message(&self) -> String {
        self.kind.message()
    }

    /// The diagnostic users see: message, every label, help, and the kind's name as its code.
    pub fn to_diagnostic(&self) -> occ_grammar::diagnostic::Diagnostic {
        let mut d =
            occ_grammar::diagnostic::Diagnostic::error(self.span, self.message(), self.label())
                .with_code(format!("check::{}", self.kind.name()));
        d.severity = self.severity;
        d.help = self.kind.help();
        for (span, label) in &self.related {
            d = d.with_related(*span, label.clone());
        }
        d
    }
}

impl From<&Diagnostic> for occ_grammar::diagnostic::Diagnostic {
    fn from(d: &Diagnostic) -> Self {
        d.to_diagnostic()
    }
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.kind.message())
    }
}

impl std::error::Error for Diagnostic {}
