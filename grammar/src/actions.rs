//! Small builders called from the grammar's actions (kept here so the grammar stays readable).

use crate::ast::*;
use crate::diagnostic::Diagnostic;
use crate::lexer::Token;
use lalrpop_util::{ErrorRecovery, ParseError};

/// Builds a name.
pub fn name(text: &str, l: usize, r: usize) -> Name {
    Name {
        text: text.to_string(),
        span: Span::new(l, r),
    }
}

/// Prepends `first` to `rest`.
pub fn prepend<T>(first: T, rest: Vec<T>) -> Vec<T> {
    let mut all = Vec::with_capacity(rest.len() + 1);
    all.push(first);
    all.extend(rest);
    all
}

/// What the grammar's actions collect while parsing.
#[derive(Debug, Default)]
pub struct State {
    /// Syntax errors found so far (recovered ones and operator-mixing ones).
    pub diagnostics: Vec<Diagnostic>,
    /// Some line was skipped after a syntax error, so the tree lacks code that was written.
    pub dropped: bool,
}

/// Records a recovered syntax error (the parser skipped to the end of the line).
pub fn recovered<'a>(state: &mut State, error: ErrorRecovery<usize, Token<'a>, Box<Diagnostic>>) {
    state.dropped = true;
    state
        .diagnostics
        .push(crate::parser::syntax_error(error.error));
}

/// An operand as parsed, with the form it takes when it is not an operand in occam's sense.
///
/// occ21 reads `MOSTPOS T`, `MOSTNEG T`, `SIZE x`, a conversion (`INT x`) and a monadic
/// operator applied to an operand (`-x`, `NOT b`) as whole expressions, not operands
/// (tools/occ21/fe/syn2.c, `rexp` returns them without reading further dyadic operators, and
/// `roperand` does not read them at all): `MOSTPOS INT - 1`, `a + -b`, `INT x + 1` and
/// `- -x` are syntax errors there and need parentheses. The grammar reads them wherever an
/// operand may stand, and [`chain`] and [`monadic`] report them.
#[derive(Debug, Clone)]
pub struct Term {
    /// The expression.
    pub expr: Expr,
    /// What it is when it is a whole-expression form written without parentheses.
    pub form: Option<&'static str>,
}

/// An operand (possibly in parentheses).
pub fn operand(expr: Expr) -> Term {
    Term { expr, form: None }
}

/// A whole-expression form: `what` names it in messages ("a conversion", "MOSTPOS").
pub fn whole(expr: Expr, what: &'static str) -> Term {
    Term {
        expr,
        form: Some(what),
    }
}

/// The code of the diagnostic for a whole-expression form used as an operand.
const BARE_OPERAND: &str = "parse::BareOperand";

fn bare_operand(term: &Term, what: &'static str, user: &str) -> Diagnostic {
    Diagnostic::error(
        term.expr.span,
        format!("{what} needs parentheses to be the operand of `{user}`"),
        "I was expecting parentheses around this",
    )
    .with_help(
        "write (MOSTPOS INT) - 1, a + (-b), (INT x) + 1: in occam, MOSTPOS, MOSTNEG, SIZE, \
         conversions and monadic operators make a whole expression, not an operand",
    )
    .with_code(BARE_OPERAND)
}

/// Builds `op operand`, reporting an operand that is itself a whole-expression form.
pub fn monadic(diags: &mut Vec<Diagnostic>, op: UnOp, operand: Term, l: usize, r: usize) -> Term {
    if let Some(what) = operand.form {
        diags.push(bare_operand(&operand, what, crate::print::unop_text(op)));
    }
    let expr = Expr {
        kind: ExprKind::Unary {
            op,
            operand: Box::new(operand.expr),
        },
        span: Span::new(l, r),
    };
    whole(expr, "a monadic operator's expression")
}

/// Operators that may be repeated without parentheses (`a AND b AND c`): only `AND` and `OR`,
/// as in occ21 (tools/occ21/fe/syn2.c, `rrestofexp`: every other operator ends the chain).
fn associative(op: BinOp) -> bool {
    matches!(op, BinOp::And | BinOp::Or)
}

/// Folds `first op e op e ...` left to right, reporting occam's parenthesis rules: two dyadic
/// operators need parentheses unless both are `AND` or both `OR`, and an operand of a dyadic
/// operator may not be a whole-expression form (see [`Term`]).
pub fn chain(diags: &mut Vec<Diagnostic>, first: Term, rest: Vec<((BinOp, Span), Term)>) -> Expr {
    if let Some(((op, _), _)) = rest.first() {
        let text = crate::print::binop_text(*op);
        for term in std::iter::once(&first).chain(rest.iter().map(|(_, t)| t)) {
            if let Some(what) = term.form {
                diags.push(bare_operand(term, what, text));
            }
        }
    }
    let mut lhs = first.expr;
    let mut previous: Option<BinOp> = None;
    for ((op, op_span), rhs) in rest {
        if let Some(prev) = previous
            && (prev != op || !associative(op))
        {
            diags.push(parenthesis_error(prev, op, op_span));
        }
        previous = Some(op);
        let rhs = rhs.expr;
        let span = lhs.span.to(rhs.span);
        lhs = Expr {
            kind: ExprKind::Binary {
                op,
                lhs: Box::new(lhs),
                rhs: Box::new(rhs),
            },
            span,
        };
    }
    lhs
}

fn parenthesis_error(prev: BinOp, op: BinOp, span: Span) -> Diagnostic {
    let (p, o) = (crate::print::binop_text(prev), crate::print::binop_text(op));
    let message = if prev == op {
        format!("`{o}` cannot be chained without parentheses")
    } else {
        format!("`{p}` and `{o}` are mixed without parentheses")
    };
    Diagnostic::error(
        span,
        message,
        "I was expecting parentheses before this operator",
    )
    .with_help(format!(
        "write (a {p} b) {o} c: occam has no precedence, and only AND and OR may be repeated \
         without parentheses"
    ))
}

/// Drops the report that the start of a constructor's replicator, `[i = -1 FOR n | ...]`, is a
/// whole-expression form: the grammar reads `i = -1` as an expression, but `-1` is the
/// replicator's start there, not an operand of `=`.
pub fn replicator_start(diags: &mut Vec<Diagnostic>, start: &Expr) {
    diags.retain(|d| {
        !(d.code.as_deref() == Some(BARE_OPERAND)
            && d.place == crate::diagnostic::Place::Output(start.span))
    });
}

/// Builds the name of an operator FUNCTION, `INT FUNCTION "+" (...)`: its spelling, which
/// must be an operator a program may define.
pub fn operator_name<'a>(
    op: Vec<u8>,
    l: usize,
    r: usize,
) -> Result<Name, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    let text = String::from_utf8_lossy(&op).into_owned();
    if operator_arity(&text).is_none() {
        let diag = Diagnostic::error(
            Span::new(l, r),
            format!("\"{text}\" is not an operator that a program may define"),
            "I was expecting a FUNCTION name, or an operator such as \"+\" or \"++\"",
        );
        return Err(ParseError::User {
            error: Box::new(diag),
        });
    }
    Ok(Name {
        text,
        span: Span::new(l, r),
    })
}

/// Builds a conversion.
pub fn conversion(ty: Ty, mode: ConvMode, operand: Expr, l: usize, r: usize) -> Expr {
    Expr {
        kind: ExprKind::Conversion {
            ty,
            mode,
            operand: Box::new(operand),
        },
        span: Span::new(l, r),
    }
}

/// Builds a slice.
pub fn slice(base: Expr, from: Option<Expr>, count: Option<Expr>, l: usize, r: usize) -> Expr {
    Expr {
        kind: ExprKind::Slice {
            base: Box::new(base),
            from: from.map(Box::new),
            count: count.map(Box::new),
        },
        span: Span::new(l, r),
    }
}

/// Builds an array constructor `[i = b FOR n STEP s | v]` from its head `i = b`.
pub fn constructor<'a>(
    diags: &mut Vec<Diagnostic>,
    head: Expr,
    count: Expr,
    step: Option<Expr>,
    value: Expr,
    l: usize,
    r: usize,
) -> Result<Expr, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    let ExprKind::Binary {
        op: BinOp::Eq,
        lhs,
        rhs,
    } = head.kind
    else {
        let diag = Diagnostic::error(
            head.span,
            "an array constructor starts with a replicator",
            "I was expecting `name = start` here",
        )
        .with_help("write [i = 0 FOR n | value]");
        return Err(ParseError::User {
            error: Box::new(diag),
        });
    };
    let ExprKind::Name(name) = lhs.kind else {
        let diag = Diagnostic::error(lhs.span, "the replicator index must be a name", "here");
        return Err(ParseError::User {
            error: Box::new(diag),
        });
    };
    replicator_start(diags, &rhs);
    let repl = Replicator {
        name,
        base: *rhs,
        count,
        step,
        span: Span::new(l + 1, value.span.start),
    };
    Ok(Expr {
        kind: ExprKind::Constructor {
            repl: Box::new(repl),
            value: Box::new(value),
        },
        span: Span::new(l, r),
    })
}

/// Wraps `d` around process `p`, merging consecutive declarations into one scope.
pub fn scope(d: Decl, p: Process, l: usize, r: usize) -> Process {
    let (decls, body) = match p.kind {
        ProcessKind::Scope { decls, body } => (prepend(d, decls), body),
        kind => (vec![d], Box::new(Process { kind, span: p.span })),
    };
    Process {
        kind: ProcessKind::Scope { decls, body },
        span: Span::new(l, r),
    }
}

/// Adds a leading declaration to a VALOF.
pub fn valof_scope(d: Decl, mut v: Valof, l: usize, r: usize) -> Valof {
    v.decls.insert(0, d);
    v.span = Span::new(l, r);
    v
}

/// Adds a leading declaration to a `? CASE` variant.
pub fn variant_scope(d: Decl, mut v: Variant, l: usize, r: usize) -> Variant {
    v.decls.insert(0, d);
    v.span = Span::new(l, r);
    v
}

/// Adds a leading declaration to an IF choice.
pub fn choice_scope(d: Decl, mut c: Choice, l: usize, r: usize) -> Choice {
    c.decls.insert(0, d);
    c.span = Span::new(l, r);
    c
}

/// Adds a leading declaration to an ALT alternative.
pub fn alternative_scope(d: Decl, mut a: Alternative, l: usize, r: usize) -> Alternative {
    a.decls.insert(0, d);
    a.span = Span::new(l, r);
    a
}

/// Adds a leading declaration to a CASE option.
pub fn option_scope(d: Decl, mut o: CaseOption, l: usize, r: usize) -> CaseOption {
    o.decls.insert(0, d);
    o.span = Span::new(l, r);
    o
}

/// Builds the one-line tagged input `c ? CASE tag; x` as a one-variant case input with a SKIP body.
pub fn one_variant(chan: Expr, tag: Name, items: Vec<IoItem>, l: usize, r: usize) -> ProcessKind {
    let body = Process {
        kind: ProcessKind::Skip,
        span: Span::new(r, r),
    };
    let variant = Variant {
        decls: Vec::new(),
        tag,
        items,
        body,
        span: Span::new(l, r),
    };
    ProcessKind::CaseInput {
        chan,
        variants: vec![variant],
    }
}

/// A formal parameter as written: with its own mode and type, or sharing the previous one's.
pub enum ParamItem {
    /// `VAL INT x`.
    Full {
        /// VAL, RESULT or reference.
        mode: ParamMode,
        /// The type.
        ty: Ty,
        /// The name.
        name: Name,
        /// A direction specifier.
        dir: Option<Direction>,
        /// The whole item.
        span: Span,
    },
    /// `y` after `VAL INT x,`.
    Bare {
        /// The name.
        name: Name,
        /// A direction specifier.
        dir: Option<Direction>,
        /// The name's span.
        span: Span,
    },
}

/// Expands shared-type parameters (`VAL INT a, b`) to one [`Param`] per name.
pub fn params<'a>(
    items: Vec<ParamItem>,
) -> Result<Vec<Param>, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    let mut out: Vec<Param> = Vec::with_capacity(items.len());
    for item in items {
        let param = match item {
            ParamItem::Full {
                mode,
                ty,
                name,
                dir,
                span,
            } => Param {
                mode,
                ty,
                name,
                dir,
                span,
            },
            ParamItem::Bare { name, dir, span } => {
                let Some(previous) = out.last() else {
                    let diag = Diagnostic::error(span, "this parameter has no type", "here")
                        .with_help("write a type before the first parameter: (VAL INT x, y)");
                    return Err(ParseError::User {
                        error: Box::new(diag),
                    });
                };
                Param {
                    mode: previous.mode,
                    ty: previous.ty.clone(),
                    name,
                    dir,
                    span,
                }
            }
        };
        out.push(param);
    }
    Ok(out)
}

/// Builds `PLACE x IN WORKSPACE:` (the word must be `IN`).
pub fn place_in<'a>(
    name: Name,
    word: &str,
    area: Name,
) -> Result<DeclKind, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    if word != "IN" {
        let diag = Diagnostic::error(
            area.span,
            "expected PLACE x AT address or PLACE x IN WORKSPACE",
            "here",
        );
        return Err(ParseError::User {
            error: Box::new(diag),
        });
    }
    Ok(DeclKind::PlaceIn { name, area })
}

/// Applies subscripts `[i][j]` to an operand that is not an element (`"abc"[i]`).
pub fn subscripts(base: Expr, indices: Vec<(Expr, usize)>, _r: usize) -> Expr {
    indices.into_iter().fold(base, |base, (index, end)| {
        let span = Span::new(base.span.start, end);
        Expr {
            kind: ExprKind::Subscript {
                base: Box::new(base),
                index: Box::new(index),
            },
            span,
        }
    })
}

/// Accepts the operator token of an extended input: only `??` (`c ?? x`) starts one.
pub fn ext_query<'a>(
    u: UserOp,
    l: usize,
    r: usize,
) -> Result<(), ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    if u == UserOp::DQuery {
        return Ok(());
    }
    let diag = Diagnostic::error(
        Span::new(l, r),
        "this operator cannot follow a channel here",
        "I was expecting `?` (input), `??` (extended input) or `!` (output)",
    );
    Err(ParseError::User {
        error: Box::new(diag),
    })
}

/// The body of a variant of `c ?? CASE`: an [`ProcessKind::Extended`] whose input is SKIP (the
/// variant's own items are the input), so that `during` runs while the outputter is held and
/// `after` once it is released.
pub fn held_body(during: Process, after: Option<Process>) -> Process {
    let start = during.span.start;
    let end = after.as_ref().map_or(during.span.end, |a| a.span.end);
    Process {
        kind: ProcessKind::Extended {
            input: Box::new(Process {
                kind: ProcessKind::Skip,
                span: Span::new(start, start),
            }),
            during: Box::new(during),
            after: after.map(Box::new),
        },
        span: Span::new(start, end),
    }
}

/// `c ?? CASE` with indented variants: an extended input whose input is the case input and whose
/// own processes are SKIP; each variant's body is a [`held_body`].
pub fn held_case(chan: Expr, variants: Vec<Variant>) -> ProcessKind {
    let end = variants.last().map_or(chan.span.end, |v| v.span.end);
    let span = Span::new(chan.span.start, end);
    ProcessKind::Extended {
        input: Box::new(Process {
            kind: ProcessKind::CaseInput { chan, variants },
            span,
        }),
        during: Box::new(Process {
            kind: ProcessKind::Skip,
            span: Span::new(end, end),
        }),
        after: None,
    }
}

/// The ALT alternative `[cond &] c ?? CASE` with indented variants (see [`held_case`]); `q` is
/// the operator after the channel and where it is.
pub fn held_case_alternative<'a>(
    cond: Option<Expr>,
    chan: Term,
    q: (UserOp, usize, usize),
    variants: Vec<Variant>,
    l: usize,
    r: usize,
) -> Result<Alternative, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    ext_query(q.0, q.1, q.2)?;
    let chan = chan.expr;
    let span = Span::new(chan.span.start, r);
    Ok(Alternative {
        decls: Vec::new(),
        kind: AltKind::Guarded {
            cond,
            guard: Box::new(Process {
                kind: held_case(chan, variants),
                span,
            }),
            body: Box::new(Process {
                kind: ProcessKind::Skip,
                span: Span::new(r, r),
            }),
        },
        span: Span::new(l, r),
    })
}

/// The ALT alternative `[cond &] c ?? CASE tag; x` (one line) with its process run while the
/// outputter is held and, if written, its process run after the release; `variant` is the tag,
/// the items and where they end.
#[allow(
    clippy::too_many_arguments,
    reason = "one per part of the alternative as written"
)]
pub fn held_tag_alternative<'a>(
    cond: Option<Expr>,
    chan: Term,
    q: (UserOp, usize, usize),
    variant: (Name, Vec<IoItem>, usize),
    during: Process,
    after: Option<Process>,
    l: usize,
    r: usize,
) -> Result<Alternative, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    ext_query(q.0, q.1, q.2)?;
    let chan = chan.expr;
    let start = chan.span.start;
    let (tag, items, end) = variant;
    let input = Process {
        kind: one_variant(chan, tag, items, start, end),
        span: Span::new(start, end),
    };
    Ok(extended_guard(cond, input, during, after, l, r))
}

/// Builds the ALT alternative `[cond &] c ?? x` with its process run while the outputter is
/// held and, if written, its process run after the release. The grammar reads `c ?? x` as the
/// expression it also spells (a guard's condition is an expression too); `data` is the array of
/// a counted first item (`c ?? n::a`), `items` the rest.
#[allow(
    clippy::too_many_arguments,
    reason = "one per part of the alternative as written"
)]
pub fn extended_alternative<'a>(
    cond: Option<Expr>,
    x: Expr,
    data: Option<Expr>,
    mut items: Vec<IoItem>,
    during: Process,
    after: Option<Process>,
    l: usize,
    r: usize,
) -> Result<Alternative, ParseError<usize, Token<'a>, Box<Diagnostic>>> {
    let span = x.span;
    let ExprKind::Binary {
        op: BinOp::User(UserOp::DQuery),
        lhs,
        rhs,
    } = x.kind
    else {
        let diag = Diagnostic::error(
            span,
            "this is not a guard",
            "I was expecting an input `c ? x`, an extended input `c ?? x`, a delay or SKIP",
        );
        return Err(ParseError::User {
            error: Box::new(diag),
        });
    };
    let first = match data {
        Some(data) => IoItem::Counted { count: *rhs, data },
        None => IoItem::Expr(*rhs),
    };
    items.insert(0, first);
    let input = Process {
        kind: ProcessKind::Input { chan: *lhs, items },
        span,
    };
    Ok(extended_guard(cond, input, during, after, l, r))
}

/// The ALT alternative `[cond &]` extended `input` as its guard, holding the outputter while
/// `during` runs, with `after` (SKIP if not written) as its body; from `l` to `r`.
fn extended_guard(
    cond: Option<Expr>,
    input: Process,
    during: Process,
    after: Option<Process>,
    l: usize,
    r: usize,
) -> Alternative {
    let body = after.unwrap_or(Process {
        kind: ProcessKind::Skip,
        span: Span::new(r, r),
    });
    let guard = Process {
        span: input.span.to(during.span),
        kind: ProcessKind::Extended {
            input: Box::new(input),
            during: Box::new(during),
            after: None,
        },
    };
    Alternative {
        decls: Vec::new(),
        kind: AltKind::Guarded {
            cond,
            guard: Box::new(guard),
            body: Box::new(body),
        },
        span: Span::new(l, r),
    }
}
