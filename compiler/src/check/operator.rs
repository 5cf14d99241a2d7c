//! User-defined operators, as KRoC's occ21 has them: `INT FUNCTION "+" (VAL INT a, VAL INT32 b)`
//! declares an operator, and `a + b` calls it when its operand types are the FUNCTION's
//! parameter types. Definitions overload one another and the built-in operator by operand type
//! (occ21 names each definition after its operator and parameter types, `udo.ADD.INTINT32`, and
//! looks that name up at each use): the innermost visible definition whose parameter types
//! match is called; when none matches, the built-in operator applies, as if none were declared.
//!
//! Matching compares types as occ21's names do: array lengths are not part of them, so a
//! `VAL []INT` parameter takes a `[2]INT` operand and a `VAL [2]INT` one a `[3]INT`.

use occ_grammar::ast::{self, Arity, BinOp, Expr, ExprKind, LitKind, UnOp, UserOp, operator_arity};

use super::Checker;
use super::expr::{Typed, is_untyped};
use crate::checked::SymbolKind;
use crate::diagnostic::DiagnosticKind;
use crate::types::Type;

/// Reports whether a FUNCTION's name is an operator's spelling rather than a name.
pub(super) fn is_operator_name(name: &str) -> bool {
    !name.starts_with(|c: char| c.is_ascii_alphabetic())
        || occ_grammar::lexer::keyword(name).is_some()
}

/// A visible operator FUNCTION chosen for an operator expression.
struct Operator {
    id: crate::checked::SymbolId,
    pid: crate::checked::ProcId,
    formals: Vec<Type>,
    result: Type,
}

/// The type an untyped literal expression takes when no context gives one.
fn literal_default(e: &Expr) -> Type {
    match &e.kind {
        ExprKind::Literal(l) => match l.kind {
            LitKind::Byte(_) => Type::BYTE,
            LitKind::Real(_) => Type::Prim(crate::types::Prim::Real64),
            _ => Type::INT,
        },
        ExprKind::Unary { operand, .. } => literal_default(operand),
        ExprKind::Binary { lhs, .. } => literal_default(lhs),
        _ => Type::INT,
    }
}

/// Reports whether an operand of type `actual` fits a parameter of type `formal`: the same
/// type, with array lengths left out of the comparison.
fn fits(formal: &Type, actual: &Type) -> bool {
    match (formal, actual) {
        (Type::Array(_, f), Type::Array(_, a)) => fits(f, a),
        _ => formal == actual,
    }
}

impl Checker {
    /// Checks the declaration of an operator FUNCTION: a spelling occ21 lets a program define,
    /// with one or two parameters as the operator takes, and one result.
    pub(super) fn operator_declaration(&mut self, name: &ast::Name, params: usize, results: usize) {
        let why = match operator_arity(&name.text) {
            None => Some("it is not an operator that a program may define"),
            Some(Arity::Dyadic) if params != 2 => Some("this operator takes two operands"),
            Some(Arity::Monadic) if params != 1 => Some("this operator takes one operand"),
            Some(Arity::Either) if !(1..=2).contains(&params) => {
                Some("an operator takes one or two operands")
            }
            _ if results != 1 => Some("an operator has exactly one result"),
            _ => None,
        };
        if let Some(why) = why {
            let kind = DiagnosticKind::BadOperatorDefinition {
                op: name.text.clone(),
                why,
            };
            self.error(kind, name.span);
        }
    }

    /// Finds the innermost visible operator FUNCTION spelled `spelling` whose parameter types
    /// take `operands`.
    fn find_operator(&self, spelling: &str, operands: &[&Type]) -> Option<Operator> {
        if operands.iter().any(|t| t.is_error()) {
            return None;
        }
        self.scope.lookup_all(spelling).find_map(|id| {
            let SymbolKind::Function(pid) = self.sym(id).kind else {
                return None;
            };
            let info = &self.out.procs[pid];
            let formals: Vec<Type> = info
                .params
                .iter()
                .map(|&p| self.sym(p).ty.clone())
                .collect();
            let matches = formals.len() == operands.len()
                && formals.iter().zip(operands).all(|(f, a)| fits(f, a));
            matches.then(|| Operator {
                id,
                pid,
                formals,
                result: info.results.first().cloned().unwrap_or(Type::Error),
            })
        })
    }

    /// Records that the operator expression at `span` calls `op`, and returns its result.
    fn call_operator(&mut self, op: Operator, span: ast::Span) -> Typed {
        if self.shadow == 0 {
            self.out.operators.insert(span, op.id);
        }
        self.free_variables_of(op.pid, span);
        Typed {
            ty: op.result,
            value: None,
            target: None,
        }
    }

    /// Checks `lhs op rhs` where some operator FUNCTION spelled as `op` is visible: `Ok` with
    /// the call when one takes the operand types, else `Err` with the operands typed as the
    /// built-in operator types them. An untyped literal operand counts as its default type
    /// (INT, BYTE, REAL64) in the search, as occ21's does, and then takes the parameter's type.
    pub(super) fn user_binary(
        &mut self,
        op: BinOp,
        lhs: &Expr,
        rhs: &Expr,
        span: ast::Span,
    ) -> Result<Typed, Box<(Typed, Typed)>> {
        let shift = crate::consteval::is_shift(op);
        let lt = (!is_untyped(lhs)).then(|| self.expr(lhs, None));
        let rt = (!is_untyped(rhs)).then(|| self.expr(rhs, None));
        let guess_l = lt
            .as_ref()
            .map_or_else(|| literal_default(lhs), |t| t.ty.clone());
        let guess_r = rt
            .as_ref()
            .map_or_else(|| literal_default(rhs), |t| t.ty.clone());
        let spelling = binary_spelling(op);
        if let Some(found) = self.find_operator(spelling, &[&guess_l, &guess_r]) {
            if lt.is_none() {
                self.expr(lhs, found.formals.first());
            }
            if rt.is_none() {
                self.expr(rhs, found.formals.get(1));
            }
            return Ok(self.call_operator(found, span));
        }
        let lt = match lt {
            Some(t) => t,
            None => {
                let want = rt.as_ref().filter(|_| !shift).map(|t| t.ty.clone());
                self.expr(lhs, want.as_ref())
            }
        };
        let rt = match rt {
            Some(t) => t,
            None => {
                let want = if shift { Type::INT } else { lt.ty.clone() };
                self.expr(rhs, Some(&want))
            }
        };
        Err(Box::new((lt, rt)))
    }

    /// Checks `op operand` against the visible operator FUNCTIONs spelled as `op`: the call
    /// when one takes the operand's type, else `Err` with the operand typed for the built-in
    /// operator.
    pub(super) fn user_unary(
        &mut self,
        op: UnOp,
        operand: &Expr,
        want: Option<&Type>,
        span: ast::Span,
    ) -> Result<Typed, Box<Typed>> {
        let spelling = unary_spelling(op);
        if is_untyped(operand) {
            let guess = literal_default(operand);
            if let Some(found) = self.find_operator(spelling, &[&guess]) {
                self.expr(operand, found.formals.first());
                return Ok(self.call_operator(found, span));
            }
            return Err(Box::new(self.expr(operand, want)));
        }
        let t = self.expr(operand, want);
        match self.find_operator(spelling, &[&t.ty]) {
            Some(found) => Ok(self.call_operator(found, span)),
            None => Err(Box::new(t)),
        }
    }

    /// Reports an operator that has no built-in meaning applied where no definition matches.
    pub(super) fn undefined_operator(&mut self, op: UserOp, operands: &[&Type], span: ast::Span) {
        if operands.iter().any(|t| t.is_error()) {
            return;
        }
        let types: Vec<String> = operands.iter().map(|t| self.out.types.display(t)).collect();
        let kind = DiagnosticKind::NoOperator {
            op: op.text(),
            operands: types.join(", "),
        };
        self.error(kind, span);
    }
}

/// The spelling under which a dyadic operator's definitions are declared.
pub(super) fn binary_spelling(op: BinOp) -> &'static str {
    crate::consteval::bin_symbol(op)
}

/// The spelling under which a monadic operator's definitions are declared.
pub(super) fn unary_spelling(op: UnOp) -> &'static str {
    crate::consteval::un_symbol(op)
}
