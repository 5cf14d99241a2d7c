//! Expressions: types (with untyped literals taking their type from context, as occ21 does),
//! constant folding, and the accesses they make.

use occ_grammar::ast::{self, BinOp, Expr, ExprKind, LitKind, TypeOrExpr};

use super::Checker;
use crate::checked::SymbolKind;
use crate::consteval::{self, ConstError, Value};
use crate::diagnostic::DiagnosticKind;
use crate::types::{Prim, Type, bytes_in, offset_of};
use crate::usage::Access;

/// An expression after checking.
#[derive(Debug, Clone)]
pub(super) struct Typed {
    /// Its type.
    pub ty: Type,
    /// Its value, when it is a compile-time constant.
    pub value: Option<Value>,
    /// The storage it denotes, when it is an element.
    pub target: Option<Access>,
}

impl Typed {
    fn of(ty: Type) -> Typed {
        Typed {
            ty,
            value: None,
            target: None,
        }
    }

    fn constant(ty: Type, value: Option<Value>) -> Typed {
        Typed {
            ty,
            value,
            target: None,
        }
    }
}

/// Reports whether an expression's type comes only from context (untyped literals).
pub(super) fn is_untyped(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Literal(l) => {
            l.ty.is_none()
                && matches!(
                    l.kind,
                    LitKind::Int { .. } | LitKind::Byte(_) | LitKind::Real(_)
                )
        }
        ExprKind::Unary { operand, .. } => is_untyped(operand),
        ExprKind::Binary { lhs, rhs, op } => {
            !consteval::is_relational(*op) && is_untyped(lhs) && is_untyped(rhs)
        }
        _ => false,
    }
}

/// Describes a constant error for the message "constant ...".
pub(super) fn const_error_text(e: &ConstError) -> String {
    match e {
        ConstError::Overflow(p) => format!("overflow in {} expression", p.name()),
        ConstError::DivisionByZero => "division by zero".into(),
        ConstError::ShiftCount(n) => format!("shift count {n} is out of range"),
        ConstError::ConversionRange(p) => {
            format!("value out of range in conversion to {}", p.name())
        }
        ConstError::LiteralRange(p) => format!("literal out of range for {}", p.name()),
        _ => "expression is not valid".into(),
    }
}

impl Checker {
    /// Checks an expression; `want` is the type the context needs, which untyped literals take.
    pub(super) fn expr(&mut self, e: &Expr, want: Option<&Type>) -> Typed {
        let t = self.expr_kind(e, want);
        if self.shadow > 0 {
            if let Some(v) = &t.value {
                self.shadow_constants.insert(e.span, v.clone());
            }
            return t;
        }
        self.out.expr_types.insert(e.span, t.ty.clone());
        if let Some(v) = &t.value {
            self.out.constants.insert(e.span, v.clone());
        }
        t
    }

    /// Reports a constant error at `span` and returns no value.
    fn fold(&mut self, r: Result<Value, ConstError>, span: ast::Span) -> Option<Value> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.error(
                    DiagnosticKind::ConstantError {
                        what: const_error_text(&e),
                    },
                    span,
                );
                None
            }
        }
    }

    fn expr_kind(&mut self, e: &Expr, want: Option<&Type>) -> Typed {
        match &e.kind {
            ExprKind::Literal(l) => self.literal(l, want, e.span, false),
            ExprKind::Directed { .. } => {
                let p = self.place(e, None);
                Typed {
                    ty: p.ty,
                    value: None,
                    target: p.target,
                }
            }
            ExprKind::List(items) => match items.as_slice() {
                [single] => self.expr(single, want),
                _ => {
                    // Only meaningful as an operand of `=` / `<>` (handled in `binary`).
                    for item in items {
                        self.expr(item, None);
                    }
                    let kind = DiagnosticKind::Unsupported {
                        what: "an expression list outside `=` or `<>`",
                    };
                    self.error(kind, e.span);
                    Typed::of(Type::Error)
                }
            },
            ExprKind::TypedTable { items, ty } => {
                let ty = self.ty(ty);
                self.typed_table(items, ty, e.span)
            }
            ExprKind::Name(_) | ExprKind::Subscript { .. } | ExprKind::Slice { .. } => {
                let p = self.place(e, Some(crate::usage::Mode::Read));
                if !p.ty.is_data() {
                    let found = match p.ty {
                        Type::Timer => "a timer",
                        Type::Port(_) => "a port",
                        _ => "a channel",
                    };
                    let name = super::process::element_name(e);
                    let kind = DiagnosticKind::WrongKind {
                        name,
                        expected: "a value",
                        found,
                    };
                    self.error(kind, e.span);
                    return Typed::of(Type::Error);
                }
                Typed {
                    ty: p.ty,
                    value: p.value,
                    target: p.target,
                }
            }
            ExprKind::Unary { op, operand } => self.unary(*op, operand, want, e.span),
            ExprKind::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs, want, e.span),
            ExprKind::Conversion { ty, mode, operand } => {
                let to = self.ty(ty);
                self.conversion(to, *mode, operand, e.span)
            }
            ExprKind::MostPos(t) | ExprKind::MostNeg(t) => {
                let ty = self.ty(t);
                let pos = matches!(e.kind, ExprKind::MostPos(_));
                let prim = self.out.types.prim(&ty).filter(|p| *p != Prim::Bool);
                let value = prim.and_then(|p| {
                    if pos {
                        consteval::most_pos(p)
                    } else {
                        consteval::most_neg(p)
                    }
                });
                if value.is_none() && !ty.is_error() {
                    let op = if pos { "MOSTPOS" } else { "MOSTNEG" };
                    self.error(
                        DiagnosticKind::BadOperand {
                            op,
                            ty: self.out.types.display(&ty),
                        },
                        t.span,
                    );
                }
                Typed::constant(ty, value)
            }
            ExprKind::Size(toe) => self.size(toe, e.span),
            ExprKind::BytesIn(toe) => {
                let ty = self.type_or_expr(toe);
                let value = bytes_in(&self.out.types, &ty)
                    .ok()
                    .map(|b| Value::Int(i64::from(b)));
                Typed::constant(Type::INT, value)
            }
            ExprKind::OffsetOf { ty, field } => {
                let ty = self.ty(ty);
                let r = offset_of(&self.out.types, &ty, &field.text);
                if r.is_err() && !ty.is_error() {
                    let record = self.out.types.display(&ty);
                    self.error(
                        DiagnosticKind::NoSuchField {
                            field: field.text.clone(),
                            record,
                        },
                        field.span,
                    );
                }
                Typed::constant(Type::INT, r.ok().map(|b| Value::Int(i64::from(b))))
            }
            ExprKind::Call { name, args } => self.call_expr(name, args, want, e.span),
            ExprKind::Table(items) => self.table(items, want, e.span),
            ExprKind::Constructor { repl, value } => {
                let mark = self.open_scope();
                let r = self.replicator(repl);
                let elem_want = want.and_then(Type::elem);
                let t = self.expr(value, elem_want);
                self.close_scope(mark);
                let n = r.count.and_then(|c| u32::try_from(c).ok());
                Typed::of(Type::array(n, t.ty))
            }
            ExprKind::Valof(v) => {
                let wants: Vec<Type> = want.into_iter().cloned().collect();
                let first = self.next_symbol();
                self.push_frame();
                let tys = self.valof_types(v, &wants);
                let usage = self.pop_frame();
                self.no_side_effects(&usage, first);
                self.extend_frame(usage.into_iter().filter(|a| a.symbol < first));
                if tys.len() != 1 {
                    self.error(
                        DiagnosticKind::ValueCount {
                            expected: 1,
                            found: tys.len(),
                        },
                        e.span,
                    );
                }
                Typed::of(tys.into_iter().next().unwrap_or(Type::Error))
            }
        }
    }

    /// Types a literal: its written type, else the wanted type when it fits, else the default.
    fn literal(
        &mut self,
        l: &ast::Literal,
        want: Option<&Type>,
        span: ast::Span,
        negate: bool,
    ) -> Typed {
        let written = l.ty.as_ref().map(|t| self.ty(t));
        let ctx = written.clone().or_else(|| want.cloned());
        let ctx_prim = ctx.as_ref().and_then(|t| self.out.types.prim(t));
        let (ty, r) = match &l.kind {
            LitKind::Bool(b) => (Type::BOOL, Ok(Value::Bool(*b))),
            LitKind::String(bytes) => {
                let n = u32::try_from(bytes.len()).unwrap_or(u32::MAX);
                (Type::array(Some(n), Type::BYTE), Ok(Value::string(bytes)))
            }
            // A character takes an integer type from context, like any untyped literal
            // (cgtest59: `i := 'a'` for an INT `i`).
            LitKind::Byte(b) => match ctx_prim.filter(|p| p.is_integer()) {
                Some(p) => (
                    ctx.unwrap_or(Type::BYTE),
                    integer(u64::from(*b), false, negate, p),
                ),
                None => (Type::BYTE, Ok(Value::Int(i64::from(*b)))),
            },
            LitKind::Int { value, hex } => match ctx_prim.filter(|p| p.is_numeric()) {
                Some(p) => (ctx.unwrap_or(Type::INT), integer(*value, *hex, negate, p)),
                None => (Type::INT, integer(*value, *hex, negate, Prim::Int)),
            },
            LitKind::Real(text) => {
                if text
                    .find(['E', 'e'])
                    .is_some_and(|e| !text[e + 1..].starts_with(['+', '-']))
                {
                    self.error(DiagnosticKind::ExponentSign, span);
                }
                let p = ctx_prim.filter(|p| p.is_real()).unwrap_or(Prim::Real64);
                let text = if negate {
                    format!("-{text}")
                } else {
                    text.clone()
                };
                let ty = ctx
                    .filter(|_| ctx_prim.is_some_and(Prim::is_real))
                    .unwrap_or(Type::Prim(p));
                (ty, consteval::parse_real_literal(&text, p))
            }
        };
        if let Some(w) = &written
            && written.as_ref() != Some(&ty)
        {
            self.expect_type(w, &ty, span);
        }
        let value = self.fold(r, span);
        Typed::constant(ty, value)
    }

    fn unary(
        &mut self,
        op: ast::UnOp,
        operand: &Expr,
        want: Option<&Type>,
        span: ast::Span,
    ) -> Typed {
        let spelling = super::operator::unary_spelling(op);
        let defined = self.scope.lookup_all(spelling).next().is_some();
        if op == ast::UnOp::Neg
            && !defined
            && let ExprKind::Literal(l) = &operand.kind
            && matches!(l.kind, LitKind::Int { hex: false, .. } | LitKind::Real(_))
        {
            // `-2147483648` is MOSTNEG INT: fold the sign into the literal.
            let t = self.literal(l, want, span, true);
            self.out.expr_types.insert(operand.span, t.ty.clone());
            return t;
        }
        let want = if op == ast::UnOp::Not {
            Some(&Type::BOOL)
        } else {
            want
        };
        let t = if defined {
            match self.user_unary(op, operand, want, span) {
                Ok(called) => return called,
                Err(t) => *t,
            }
        } else {
            self.expr(operand, want)
        };
        if let ast::UnOp::User(u) = op {
            self.undefined_operator(u, &[&t.ty], span);
            return Typed::of(Type::Error);
        }
        let Some(prim) = self.operand_prim(&t.ty, consteval::un_symbol(op), operand.span) else {
            return Typed::of(t.ty);
        };
        if !consteval::un_accepts(op, prim) {
            let ty = self.out.types.display(&t.ty);
            self.error(
                DiagnosticKind::BadOperand {
                    op: consteval::un_symbol(op),
                    ty,
                },
                span,
            );
            return Typed::of(Type::Error);
        }
        let value = t.value.map(|v| consteval::unary(op, prim, &v));
        let value = value.and_then(|r| self.fold(r, span));
        Typed::constant(t.ty, value)
    }

    /// Returns the primitive representation of an operand type, reporting non-primitive types.
    fn operand_prim(&mut self, ty: &Type, op: &'static str, span: ast::Span) -> Option<Prim> {
        let prim = self.out.types.prim(ty);
        if prim.is_none() && !ty.is_error() {
            self.error(
                DiagnosticKind::BadOperand {
                    op,
                    ty: self.out.types.display(ty),
                },
                span,
            );
        }
        prim
    }

    fn binary(
        &mut self,
        op: BinOp,
        lhs: &Expr,
        rhs: &Expr,
        want: Option<&Type>,
        span: ast::Span,
    ) -> Typed {
        if let (ExprKind::List(ls), ExprKind::List(rs), BinOp::Eq | BinOp::Ne) =
            (&lhs.kind, &rhs.kind, op)
        {
            return self.list_compare(op, ls, rs, span);
        }
        let spelling = super::operator::binary_spelling(op);
        let (lt, rt) = if self.scope.lookup_all(spelling).next().is_some() {
            match self.user_binary(op, lhs, rhs, span) {
                Ok(called) => return called,
                Err(operands) => *operands,
            }
        } else {
            match self.binary_operands(op, lhs, rhs, want) {
                Ok(operands) => operands,
                Err(decided) => return *decided,
            }
        };
        if let BinOp::User(u) = op {
            self.undefined_operator(u, &[&lt.ty, &rt.ty], span);
            return Typed::of(Type::Error);
        }
        if consteval::is_shift(op) {
            self.expect_type(&Type::INT, &rt.ty, rhs.span);
        } else if !self.expect_type(&lt.ty, &rt.ty, rhs.span) {
            return Typed::of(Type::Error);
        }
        self.builtin_binary(op, lt, rt, span)
    }

    /// Types the operands of a built-in dyadic operator; `Err` with the whole expression's
    /// value when `FALSE AND e` or `TRUE OR e` is decided by its left operand.
    fn binary_operands(
        &mut self,
        op: BinOp,
        lhs: &Expr,
        rhs: &Expr,
        want: Option<&Type>,
    ) -> Result<(Typed, Typed), Box<Typed>> {
        let boolean = matches!(op, BinOp::And | BinOp::Or);
        let want = if boolean {
            Some(&Type::BOOL)
        } else if consteval::is_relational(op) {
            None
        } else {
            want
        };
        let (lt, rt) = if boolean {
            let lt = self.expr(lhs, want);
            // `FALSE AND e` and `TRUE OR e` never evaluate `e`.
            let decided = lt.value.as_ref().and_then(Value::as_bool) == Some(op == BinOp::Or);
            self.dead += u32::from(decided);
            let rt = self.expr(rhs, want);
            self.dead -= u32::from(decided);
            if decided {
                let value = lt.value.clone();
                self.expect_type(&Type::BOOL, &rt.ty, rhs.span);
                return Err(Box::new(Typed::constant(Type::BOOL, value)));
            }
            (lt, rt)
        } else if consteval::is_shift(op) {
            let lt = self.expr(lhs, want);
            let rt = self.expr(rhs, Some(&Type::INT));
            (lt, rt)
        } else if is_untyped(lhs) && !is_untyped(rhs) {
            let rt = self.expr(rhs, want);
            (self.expr(lhs, Some(&rt.ty)), rt)
        } else {
            let lt = self.expr(lhs, want);
            let rt = self.expr(rhs, Some(&lt.ty));
            (lt, rt)
        };
        Ok((lt, rt))
    }

    /// Applies a built-in dyadic operator to checked operands of matching types.
    fn builtin_binary(&mut self, op: BinOp, lt: Typed, rt: Typed, span: ast::Span) -> Typed {
        let sym = consteval::bin_symbol(op);
        let result = if consteval::is_relational(op) {
            Type::BOOL
        } else {
            lt.ty.clone()
        };
        let operand_ty = if lt.ty.is_error() {
            rt.ty.clone()
        } else {
            lt.ty.clone()
        };
        let Some(prim) = self.operand_prim(&operand_ty, sym, span) else {
            return Typed::of(result);
        };
        if !consteval::bin_accepts(op, prim) {
            let ty = self.out.types.display(&operand_ty);
            self.error(DiagnosticKind::BadOperand { op: sym, ty }, span);
            return Typed::of(result);
        }
        let value = match (&lt.value, &rt.value) {
            (Some(a), Some(b)) => {
                let r = consteval::binary(op, prim, a, b);
                self.fold(r, span)
            }
            _ => None,
        };
        Typed::constant(result, value)
    }

    /// Checks `(a, b) = (c, d)`: item by item, equal when every item is.
    fn list_compare(&mut self, op: BinOp, ls: &[Expr], rs: &[Expr], span: ast::Span) -> Typed {
        if ls.len() != rs.len() {
            self.error(
                DiagnosticKind::ValueCount {
                    expected: ls.len(),
                    found: rs.len(),
                },
                span,
            );
        }
        let mut all_equal = Some(true);
        for (l, r) in ls.iter().zip(rs) {
            let t = self.binary(BinOp::Eq, l, r, None, l.span.to(r.span));
            all_equal = match (all_equal, t.value.as_ref().and_then(Value::as_bool)) {
                (Some(acc), Some(eq)) => Some(acc && eq),
                _ => None,
            };
        }
        let value = all_equal.map(|eq| Value::Bool(if op == BinOp::Eq { eq } else { !eq }));
        Typed::constant(Type::BOOL, value)
    }

    /// Checks `T e`, `T ROUND e`, `T TRUNC e` (and `T (e)` for a named type).
    pub(super) fn conversion(
        &mut self,
        to: Type,
        mode: ast::ConvMode,
        operand: &Expr,
        span: ast::Span,
    ) -> Typed {
        let t = self.expr(operand, None);
        let (Some(to_p), Some(from_p)) = (self.out.types.prim(&to), self.out.types.prim(&t.ty))
        else {
            if !to.is_error() && !t.ty.is_error() {
                let ty = self.out.types.display(&t.ty);
                self.error(
                    DiagnosticKind::BadOperand {
                        op: "conversion",
                        ty,
                    },
                    span,
                );
            }
            return Typed::of(to);
        };
        let inexact = (from_p.is_real() && !to_p.is_real())
            || (!from_p.is_real() && to_p.is_real())
            || (from_p == Prim::Real64 && to_p == Prim::Real32);
        if inexact && mode == ast::ConvMode::Plain {
            self.error(
                DiagnosticKind::NeedsRounding {
                    from: from_p.name(),
                    to: to_p.name(),
                },
                span,
            );
            return Typed::of(to);
        }
        let value = t.value.map(|v| consteval::convert(to_p, mode, from_p, &v));
        let value = value.and_then(|r| self.fold(r, span));
        Typed::constant(to, value)
    }

    /// The type of a `SIZE` / `BYTESIN` operand: a type, or the type of an expression.
    fn type_or_expr(&mut self, toe: &TypeOrExpr) -> Type {
        self.quiet += 1;
        let ty = self.type_or_expr_inner(toe);
        self.quiet -= 1;
        ty
    }

    fn type_or_expr_inner(&mut self, toe: &TypeOrExpr) -> Type {
        match toe {
            TypeOrExpr::Type(t) => self.ty(t),
            TypeOrExpr::Expr(Expr {
                kind: ExprKind::Name(n),
                ..
            }) if self
                .scope
                .lookup(&n.text)
                .is_some_and(|id| matches!(self.sym(id).kind, SymbolKind::DataType(_))) =>
            {
                let id = self.lookup(n);
                match id.map(|id| self.sym(id).kind.clone()) {
                    Some(SymbolKind::DataType(d)) => Type::Named(d),
                    _ => Type::Error,
                }
            }
            TypeOrExpr::Expr(e) if super::place::is_element(e) => self.place(e, None).ty,
            TypeOrExpr::Expr(e) => self.expr(e, None).ty,
        }
    }

    fn size(&mut self, toe: &TypeOrExpr, span: ast::Span) -> Typed {
        let ty = self.type_or_expr(toe);
        match self.out.types.underlying(&ty) {
            Type::Array(n, _) => Typed::constant(Type::INT, n.map(|n| Value::Int(i64::from(n)))),
            Type::Error => Typed::of(Type::INT),
            other => {
                let ty = self.out.types.display(other);
                self.error(DiagnosticKind::BadOperand { op: "SIZE", ty }, span);
                Typed::of(Type::INT)
            }
        }
    }

    fn table(&mut self, items: &[Expr], want: Option<&Type>, span: ast::Span) -> Typed {
        if let Some(w) = want
            && self.out.types.record_fields(w).is_some()
        {
            return self.typed_table(items, w.clone(), span);
        }
        let want_under = want.map(|w| self.out.types.underlying(w).clone());
        let mut elem = want_under.as_ref().and_then(Type::elem).cloned();
        // Typed items first, so that `[2, 4(int)]` is a table of `int`.
        let typed = items.iter().enumerate().filter(|(_, i)| !is_untyped(i));
        let untyped_items = items.iter().enumerate().filter(|(_, i)| is_untyped(i));
        let mut found: Vec<Option<Value>> = vec![None; items.len()];
        for (k, item) in typed.chain(untyped_items) {
            let t = self.table_item(item, elem.as_ref());
            match &elem {
                // The first item fixes the sizes the context leaves open: the strings of
                // `VAL [][]BYTE s IS ["ab", "c"]:` must all have the same length.
                Some(e) => {
                    if self.expect_type(e, &t.ty, item.span) {
                        elem = Some(with_sizes_of(e, &t.ty));
                    }
                }
                None => elem = Some(t.ty.clone()),
            }
            if let Some(slot) = found.get_mut(k) {
                *slot = t.value;
            }
        }
        let values: Option<Vec<Value>> = found.into_iter().collect();
        let n = u32::try_from(items.len()).ok();
        let _ = span;
        let ty = Type::array(n, elem.unwrap_or(Type::Error));
        let fits = want_under
            .as_ref()
            .is_some_and(|u| self.out.types.compatible(u, &ty));
        // A table is a value of the named array type its context wants when its items fit:
        // `COMPLEX FUNCTION neg (VAL COMPLEX x) IS [-x[re], -x[im]]` (occ21 accepts it).
        let ty = match want {
            Some(w @ Type::Named(_)) if fits => w.clone(),
            _ => ty,
        };
        Typed::constant(ty, values.map(Value::Array))
    }

    /// Checks one item of a table: a value, or a channel or timer (`[c1, c2]` abbreviated as
    /// a channel array).
    fn table_item(&mut self, item: &Expr, want: Option<&Type>) -> Typed {
        if super::place::is_element(item) {
            let p = self.place(item, None);
            if !p.ty.is_data() {
                return Typed {
                    ty: p.ty,
                    value: None,
                    target: p.target,
                };
            }
        }
        self.expr(item, want)
    }

    /// Checks `[a, b](T)`: a RECORD literal (items against fields) or an array literal of type `T`.
    fn typed_table(&mut self, items: &[Expr], ty: Type, span: ast::Span) -> Typed {
        let Some(fields) = self.out.types.record_fields(&ty).map(<[_]>::to_vec) else {
            let t = self.table(items, Some(&ty), span);
            let under = self.out.types.underlying(&ty).clone();
            if !matches!(t.ty, Type::Named(_)) {
                self.expect_type(&under, &t.ty, span);
            }
            return Typed::constant(ty, t.value);
        };
        if fields.len() != items.len() {
            let kind = DiagnosticKind::ValueCount {
                expected: fields.len(),
                found: items.len(),
            };
            self.error(kind, span);
        }
        let mut values = Some(Vec::new());
        for (item, (_, fty)) in items.iter().zip(&fields) {
            let t = self.expr(item, Some(fty));
            self.expect_type(fty, &t.ty, item.span);
            match (&mut values, t.value) {
                (Some(vs), Some(v)) => vs.push(v),
                _ => values = None,
            }
        }
        Typed::constant(ty, values.map(Value::Record))
    }
}

/// `want` with each array size it leaves open taken from `got` (a type compatible with it).
fn with_sizes_of(want: &Type, got: &Type) -> Type {
    match (want, got) {
        (Type::Array(n, a), Type::Array(m, b)) => Type::array(n.or(*m), with_sizes_of(a, b)),
        _ => want.clone(),
    }
}

/// Folds an integer literal (with an optional leading minus) into type `p`.
fn integer(value: u64, hex: bool, negate: bool, p: Prim) -> Result<Value, ConstError> {
    let text = match (hex, negate) {
        (true, _) => format!("#{value:X}"),
        (false, true) => format!("-{value}"),
        (false, false) => value.to_string(),
    };
    consteval::parse_integer_literal(&text, p)
}
