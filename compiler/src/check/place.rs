//! Elements: names, subscripts, record fields and slices, as values and as targets of
//! assignment, input and reference abbreviation. Each records the access it makes.

use occ_grammar::ast::{self, BinOp, Expr, ExprKind};

use super::Checker;
use super::decl::{direction, kind_name, with_direction};
use crate::checked::SymbolKind;
use crate::consteval::Value;
use crate::diagnostic::DiagnosticKind;
use crate::types::Type;
use crate::types::{bytes_in, offset_of};
use crate::usage::{Access, Lin, Mode, Part, TO_END};

/// The part of a symbol that is all of it.
pub(super) const ENTIRE: Part = Part::Range {
    start: Lin {
        terms: [None; crate::usage::TERMS],
        b: 0,
    },
    len: TO_END,
};

/// An element after checking.
#[derive(Debug, Clone)]
pub(super) struct Placed {
    /// Its type.
    pub ty: Type,
    /// The storage it denotes, if it is storage.
    pub target: Option<Access>,
    /// Whether it may be assigned.
    pub assignable: bool,
    /// Its value, when it is a constant.
    pub value: Option<Value>,
}

impl Placed {
    fn error() -> Placed {
        Placed {
            ty: Type::Error,
            target: None,
            assignable: true,
            value: None,
        }
    }
}

/// Reports whether an expression is an element (something that may be a variable).
pub(super) fn is_element(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Name(_) => true,
        ExprKind::Subscript { base, .. } | ExprKind::Slice { base, .. } => is_element(base),
        ExprKind::Directed { chan, .. } => is_element(chan),
        _ => false,
    }
}

impl Checker {
    /// Checks an element; records an access of `mode` to it unless `mode` is `None`.
    pub(super) fn place(&mut self, e: &Expr, mode: Option<Mode>) -> Placed {
        let p = match &e.kind {
            ExprKind::Name(name) => self.place_name(name, mode),
            ExprKind::Subscript { base, index } => self.place_subscript(base, index, mode, e.span),
            ExprKind::Slice { base, from, count } => {
                self.place_slice(base, from.as_deref(), count.as_deref(), mode, e.span)
            }
            ExprKind::Directed { chan, dir } => {
                let p = self.place(chan, mode);
                Placed {
                    ty: with_direction(p.ty, direction(Some(*dir))),
                    ..p
                }
            }
            _ => {
                let t = self.expr(e, None);
                return Placed {
                    ty: t.ty,
                    target: None,
                    assignable: false,
                    value: t.value,
                };
            }
        };
        if self.shadow == 0 {
            self.out.expr_types.insert(e.span, p.ty.clone());
        }
        p
    }

    fn place_name(&mut self, name: &ast::Name, mode: Option<Mode>) -> Placed {
        let Some(id) = self.lookup(name) else {
            return Placed::error();
        };
        let sym = self.sym(id);
        let (ty, assignable) = (sym.ty.clone(), sym.assignable);
        match &sym.kind {
            SymbolKind::Val { value } => {
                let value = value.clone();
                let target = Some(Access {
                    symbol: id,
                    mode: Mode::Read,
                    part: ENTIRE,
                    span: name.span,
                    only: None,
                });
                Placed {
                    ty,
                    target,
                    assignable: false,
                    value,
                }
            }
            SymbolKind::Replicator => Placed {
                ty,
                target: None,
                assignable: false,
                value: None,
            },
            SymbolKind::Variable | SymbolKind::Abbrev { .. } | SymbolKind::Param { .. } => {
                let access = Access {
                    symbol: id,
                    mode: mode.unwrap_or(Mode::Read),
                    part: ENTIRE,
                    span: name.span,
                    only: None,
                };
                if let Some(m) = mode {
                    self.record(id, m, ENTIRE, name.span);
                }
                Placed {
                    ty,
                    target: Some(access),
                    assignable,
                    value: None,
                }
            }
            other => {
                let found = kind_name(other);
                let kind = DiagnosticKind::WrongKind {
                    name: name.text.clone(),
                    expected: "a variable or value",
                    found,
                };
                self.error(kind, name.span);
                Placed::error()
            }
        }
    }

    fn place_subscript(
        &mut self,
        base: &Expr,
        index: &Expr,
        mode: Option<Mode>,
        span: ast::Span,
    ) -> Placed {
        let b = self.place(base, None);
        if let (Some(fields), ExprKind::Name(field)) =
            (self.out.types.record_fields(&b.ty), &index.kind)
        {
            let found = fields.iter().position(|(n, _)| *n == field.text);
            let Some(i) = found else {
                let record = self.out.types.display(&b.ty);
                self.error(
                    DiagnosticKind::NoSuchField {
                        field: field.text.clone(),
                        record,
                    },
                    field.span,
                );
                return Placed::error();
            };
            let ty = fields.get(i).map_or(Type::Error, |(_, t)| t.clone());
            let value = match &b.value {
                Some(Value::Record(vs)) => vs.get(i).cloned(),
                _ => None,
            };
            let offset = offset_of(&self.out.types, &b.ty, &field.text).ok();
            let part = match offset {
                Some(o) => Part::Range {
                    start: Lin::constant(i64::from(o)),
                    len: self.bytes(&ty),
                },
                None => Part::Whole,
            };
            return self.finish_part(b, ty, part, value, mode, span);
        }
        let it = self.expr(index, Some(&Type::INT));
        self.expect_integer_index(&it.ty, index.span);
        let idx = it.value.as_ref().and_then(Value::as_int);
        let (len, elem) = match self.out.types.underlying(&b.ty) {
            Type::Array(n, e) => (*n, (**e).clone()),
            Type::Error => (None, Type::Error),
            other => {
                let ty = self.out.types.display(other);
                self.error(
                    DiagnosticKind::BadOperand {
                        op: "subscript",
                        ty,
                    },
                    base.span,
                );
                return Placed::error();
            }
        };
        if let (Some(i), Some(n)) = (idx, len)
            && (i < 0 || i >= i64::from(n))
        {
            self.error(DiagnosticKind::OutOfBounds { index: i, len: n }, index.span);
        }
        let value = match (&b.value, idx) {
            (Some(Value::Array(vs)), Some(i)) => {
                usize::try_from(i).ok().and_then(|i| vs.get(i).cloned())
            }
            _ => None,
        };
        let stride = self.bytes(&elem);
        let part = match self.linear(index).and_then(|l| l.scale(stride)) {
            Some(start) => Part::Range { start, len: stride },
            None => self.mapped(index, stride).unwrap_or(Part::Whole),
        };
        self.finish_part(b, elem, part, value, mode, span)
    }

    fn expect_integer_index(&mut self, ty: &Type, span: ast::Span) {
        if !matches!(self.out.types.prim(ty), Some(p) if p.is_integer()) && !ty.is_error() {
            self.expect_type(&Type::INT, ty, span);
        }
    }

    /// Narrows the base's target to `part` (first level only) and records the access.
    fn finish_part(
        &mut self,
        b: Placed,
        ty: Type,
        part: Part,
        value: Option<Value>,
        mode: Option<Mode>,
        span: ast::Span,
    ) -> Placed {
        let target = b.target.map(|t| Access {
            part: self.nest(t.part, part),
            span,
            ..t
        });
        if let (Some(m), Some(t)) = (mode, target) {
            self.record(t.symbol, m, t.part, span);
        }
        Placed {
            ty,
            target,
            assignable: b.assignable,
            value,
        }
    }

    fn place_slice(
        &mut self,
        base: &Expr,
        from: Option<&Expr>,
        count: Option<&Expr>,
        mode: Option<Mode>,
        span: ast::Span,
    ) -> Placed {
        let b = self.place(base, None);
        let int = |c: &mut Checker, e: Option<&Expr>| {
            e.map(|e| {
                let t = c.expr(e, Some(&Type::INT));
                c.expect_integer_index(&t.ty, e.span);
                t.value.as_ref().and_then(Value::as_int)
            })
        };
        let from_v = int(self, from);
        let count_v = int(self, count);
        let (len, elem) = match self.out.types.underlying(&b.ty) {
            Type::Array(n, e) => (*n, (**e).clone()),
            Type::Error => (None, Type::Error),
            other => {
                let ty = self.out.types.display(other);
                self.error(DiagnosticKind::BadOperand { op: "slice", ty }, base.span);
                return Placed::error();
            }
        };
        let start = from_v.unwrap_or(Some(0));
        let n = match count_v {
            Some(c) => c,
            None => start.zip(len).map(|(s, l)| i64::from(l) - s),
        };
        if let (Some(s), Some(c), Some(l)) = (start, n, len)
            && (s < 0 || c < 0 || s + c > i64::from(l))
        {
            self.error(
                DiagnosticKind::OutOfBounds {
                    index: s + c,
                    len: l,
                },
                span,
            );
        }
        let stride = self.bytes(&elem);
        let ty = Type::array(n.and_then(|c| u32::try_from(c).ok()), elem);
        let start_lin = match from {
            Some(f) => self.linear(f),
            None => Some(Lin::constant(0)),
        };
        let start_lin = start_lin.and_then(|s| s.scale(stride));
        let bytes = n.and_then(|n| n.checked_mul(stride)).unwrap_or(TO_END);
        let part = match start_lin {
            Some(start) => Part::Range { start, len: bytes },
            None => Part::Whole,
        };
        let value = match (&b.value, start, n) {
            (Some(Value::Array(vs)), Some(s), Some(c)) => {
                let (s, c) = (usize::try_from(s).ok(), usize::try_from(c).ok());
                s.zip(c)
                    .and_then(|(s, c)| vs.get(s..s + c))
                    .map(|v| Value::Array(v.to_vec()))
            }
            _ => None,
        };
        self.finish_part(b, ty, part, value, mode, span)
    }

    /// Returns a subscript as a linear function of at most one replicator index, when it is one.
    /// Relies on constants already folded for the subexpressions.
    pub(super) fn linear(&self, e: &Expr) -> Option<Lin> {
        if let Some(v) = self.out.constants.get(&e.span).and_then(Value::as_int) {
            return Some(Lin::constant(v));
        }
        match &e.kind {
            ExprKind::Name(n) => {
                let id = *self.out.names.get(&n.span)?;
                // Replicator indices, and integer names whose value cannot change where the
                // comparison is made (PAR branches may not write a name another one uses).
                if let Some(l) = self.val_lin.get(&id) {
                    return Some(*l);
                }
                let sym = self.sym(id);
                let named = match &sym.kind {
                    SymbolKind::Replicator => true,
                    SymbolKind::Variable | SymbolKind::Param { .. } | SymbolKind::Val { .. } => {
                        self.out.types.prim(&sym.ty).is_some_and(|p| p.is_integer())
                    }
                    _ => false,
                };
                named.then_some(Lin::var(id))
            }
            ExprKind::Binary { .. } | ExprKind::Unary { .. }
                if self.out.operators.contains_key(&e.span) =>
            {
                None
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let (l, r) = (self.linear(lhs)?, self.linear(rhs)?);
                combine(*op, l, r)
            }
            _ => None,
        }
    }
}

impl Checker {
    /// The size of a value of type `ty` in bytes, or [`TO_END`] when it is not known.
    fn bytes(&self, ty: &Type) -> i64 {
        bytes_in(&self.out.types, ty).map_or(TO_END, i64::from)
    }

    /// The part `inner` (bytes from the start of `base`) of the part `base` of a symbol.
    pub(super) fn nest(&mut self, base: Part, inner: Part) -> Part {
        match (base, inner) {
            (Part::Range { start: sb, len: bl }, Part::Range { start: si, len: il }) => {
                match sb.plus(si) {
                    Some(start) => Part::Range {
                        start,
                        len: il.min(bl),
                    },
                    None => Part::Whole,
                }
            }
            (Part::Range { start: sb, .. }, Part::Mapped { var, table, len })
                if sb.as_const().is_some() =>
            {
                let Some(t) = self.tables.get(table as usize) else {
                    return Part::Whole;
                };
                let shifted: Vec<(i64, i64)> = t
                    .iter()
                    .map(|(v, s)| (*v, s.saturating_add(sb.b)))
                    .collect();
                self.tables.push(shifted);
                let table = u32::try_from(self.tables.len() - 1).unwrap_or(u32::MAX);
                Part::Mapped { var, table, len }
            }
            _ => Part::Whole,
        }
    }

    /// Evaluates a non-linear subscript for every value of the one replicator it depends on,
    /// when that replicator's values are known (occ21 unrolls such replicators).
    fn mapped(&mut self, e: &Expr, stride: i64) -> Option<Part> {
        let var = self.repl_var(e)?;
        let values = self.repl_values.get(&var)?;
        let table: Option<Vec<(i64, i64)>> = values
            .iter()
            .map(|&v| {
                self.eval_with(e, var, v)
                    .and_then(|s| Some((v, s.checked_mul(stride)?)))
            })
            .collect();
        self.tables.push(table?);
        let table = u32::try_from(self.tables.len() - 1).ok()?;
        Some(Part::Mapped {
            var,
            table,
            len: stride,
        })
    }

    /// Finds a replicator index used in `e`.
    fn repl_var(&self, e: &Expr) -> Option<crate::checked::SymbolId> {
        match &e.kind {
            ExprKind::Name(n) => {
                let id = *self.out.names.get(&n.span)?;
                matches!(self.sym(id).kind, SymbolKind::Replicator).then_some(id)
            }
            ExprKind::Binary { lhs, rhs, .. } => self.repl_var(lhs).or_else(|| self.repl_var(rhs)),
            ExprKind::Unary { operand, .. } => self.repl_var(operand),
            _ => None,
        }
    }

    /// Evaluates an INT expression with the replicator `var` set to `v`.
    fn eval_with(&self, e: &Expr, var: crate::checked::SymbolId, v: i64) -> Option<i64> {
        use crate::types::Prim;
        if let Some(c) = self.out.constants.get(&e.span).and_then(Value::as_int) {
            return Some(c);
        }
        if self.out.operators.contains_key(&e.span) {
            return None;
        }
        match &e.kind {
            ExprKind::Name(n) => (self.out.names.get(&n.span) == Some(&var)).then_some(v),
            ExprKind::Binary { op, lhs, rhs } => {
                let (l, r) = (self.eval_with(lhs, var, v)?, self.eval_with(rhs, var, v)?);
                crate::consteval::binary(*op, Prim::Int, &Value::Int(l), &Value::Int(r))
                    .ok()?
                    .as_int()
            }
            ExprKind::Unary { op, operand } => {
                let x = self.eval_with(operand, var, v)?;
                crate::consteval::unary(*op, Prim::Int, &Value::Int(x))
                    .ok()?
                    .as_int()
            }
            _ => None,
        }
    }
}

fn combine(op: BinOp, l: Lin, r: Lin) -> Option<Lin> {
    match op {
        BinOp::Add | BinOp::Plus => l.plus(r),
        BinOp::Sub | BinOp::Minus => l.plus(r.scale(-1)?),
        BinOp::Mul | BinOp::Times => match (l.as_const(), r.as_const()) {
            (_, Some(k)) => l.scale(k),
            (Some(k), _) => r.scale(k),
            _ => None,
        },
        _ => None,
    }
}
