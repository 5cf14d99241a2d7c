//! Scalar expressions: constants, variables, operators (through `ops`), conversions, SIZE,
//! BYTESIN, FUNCTION calls and VALOF; and array-valued expressions materialised in temporaries.

use cranelift_codegen::ir::{InstBuilder, Value, types};
use occ_compiler::consteval::Value as Const;
use occ_compiler::types::{Prim, Type};
use occ_grammar::ast::{Expr, ExprKind, TypeOrExpr, UnOp};

use super::{Loc, Res, Tr};
use crate::layout::{WORD, cl_type, is_scalar, size_of};

impl Tr<'_, '_> {
    /// The primitive type of expression `e`.
    pub fn prim_of(&self, e: &Expr) -> Res<Prim> {
        let ty = self.cx.type_of(e)?;
        self.cx
            .checked
            .types
            .prim(&ty)
            .ok_or_else(|| self.cx.internal(e.span, "expected a scalar expression"))
    }

    /// A scalar constant as a Cranelift value of primitive type `p`.
    pub fn const_value(&mut self, c: &Const, p: Prim) -> Option<Value> {
        let t = cl_type(p);
        Some(match c {
            Const::Bool(b) => self.b.ins().iconst(t, i64::from(*b)),
            Const::Int(i) => {
                if t.is_float() {
                    return None;
                }
                let v = if t == types::I64 {
                    *i
                } else {
                    *i & ((1i64 << t.bits()) - 1)
                };
                self.b.ins().iconst(t, v)
            }
            Const::Real32(x) => self.b.ins().f32const(*x),
            Const::Real64(x) => self.b.ins().f64const(*x),
            _ => return None,
        })
    }

    /// Evaluates scalar expression `e`.
    pub fn expr(&mut self, e: &Expr) -> Res<Value> {
        if let Some(c) = self.cx.checked.constants.get(&e.span).cloned()
            && let Ok(p) = self.prim_of(e)
            && let Some(v) = self.const_value(&c, p)
        {
            return Ok(v);
        }
        if let Some(&sym) = self.cx.checked.operators.get(&e.span) {
            let vals = self.call_operator(sym, e)?;
            return vals
                .into_iter()
                .next()
                .ok_or_else(|| self.cx.internal(e.span, "operator without result"));
        }
        match &e.kind {
            ExprKind::Name(_) | ExprKind::Subscript { .. } => {
                let l = self.place(e)?;
                self.load_scalar(&l.ty, l.addr, e.span)
            }
            ExprKind::Unary { op, operand } => self.unary(*op, operand, e),
            ExprKind::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs, e),
            ExprKind::Conversion { mode, operand, .. } => {
                let to = self.prim_of(e)?;
                let from = self.prim_of(operand)?;
                let v = self.expr(operand)?;
                self.convert(v, from, to, *mode, e.span)
            }
            ExprKind::Size(te) => match &**te {
                TypeOrExpr::Expr(x) => {
                    let l = self.place(x)?;
                    let n = l
                        .dims
                        .first()
                        .copied()
                        .ok_or_else(|| self.cx.internal(e.span, "SIZE of a non-array"))?;
                    Ok(self.b.ins().ireduce(types::I32, n))
                }
                TypeOrExpr::Type(_) => Err(self.cx.internal(e.span, "SIZE of a type")),
            },
            ExprKind::BytesIn(te) => match &**te {
                TypeOrExpr::Expr(x) => {
                    let l = self.place(x)?;
                    let s = self.loc_size(&l, e.span)?;
                    Ok(self.b.ins().ireduce(types::I32, s))
                }
                TypeOrExpr::Type(_) => Err(self.cx.internal(e.span, "BYTESIN of a type")),
            },
            ExprKind::Call { name, args } => {
                let vals = self.call_function(name, args, e.span)?;
                vals.into_iter()
                    .next()
                    .ok_or_else(|| self.cx.internal(e.span, "FUNCTION without result"))
            }
            ExprKind::Valof(v) => {
                let vals = self.valof(v)?;
                vals.into_iter()
                    .next()
                    .ok_or_else(|| self.cx.internal(e.span, "VALOF without result"))
            }
            ExprKind::Literal(_) | ExprKind::MostPos(_) | ExprKind::MostNeg(_) => {
                Err(self.cx.internal(e.span, "literal without a constant value"))
            }
            ExprKind::Directed { chan, .. } => self.expr(chan),
            _ => Err(self.cx.unsupported(e.span, "this expression form")),
        }
    }

    fn unary(&mut self, op: UnOp, x: &Expr, e: &Expr) -> Res<Value> {
        let _ = e;
        let p = self.prim_of(x)?;
        let v = self.expr(x)?;
        Ok(match op {
            UnOp::Not => self.b.ins().bxor_imm_s(v, 1),
            UnOp::BitNot => self.b.ins().bnot(v),
            UnOp::Minus => self.b.ins().ineg(v),
            UnOp::User(_) => return Err(self.cx.internal(e.span, "undefined operator")),
            UnOp::Neg => {
                if p.is_real() {
                    self.b.ins().fneg(v)
                } else {
                    let t = self.b.func.dfg.value_type(v);
                    let zero = self.b.ins().iconst(t, 0);
                    self.arith(occ_grammar::ast::BinOp::Sub, p, zero, v, e.span)?
                }
            }
        })
    }

    /// Evaluates an array- or record-valued expression into a place: variables in place, other
    /// values (constants, tables, FUNCTION results) into a temporary.
    pub fn value_loc(&mut self, e: &Expr) -> Res<Loc> {
        let ty = self.cx.type_of(e)?;
        if let Some(c) = self.cx.checked.constants.get(&e.span).cloned() {
            return self.const_loc(&c, ty, e.span);
        }
        match &e.kind {
            ExprKind::Name(_)
            | ExprKind::Subscript { .. }
            | ExprKind::Slice { .. }
            | ExprKind::Directed { .. } => self.place(e),
            ExprKind::Table(items) => self.table(items, ty, e),
            ExprKind::Constructor { repl, value } => self.constructor(repl, value, ty, e),
            ExprKind::TypedTable { items, .. } => {
                match crate::layout::record_fields(&self.cx.checked.types, &ty) {
                    Some(fields) => self.record_value(items, fields, ty, e),
                    None => self.table(items, ty, e),
                }
            }
            ExprKind::Unary { .. } | ExprKind::Binary { .. }
                if !is_scalar(&self.cx.checked.types, &ty) =>
            {
                let Some(&sym) = self.cx.checked.operators.get(&e.span) else {
                    return Err(self.cx.internal(e.span, "array-valued built-in operator"));
                };
                let vals = self.call_operator(sym, e)?;
                self.result_loc(vals, ty, e)
            }
            ExprKind::Call { name, args } if !is_scalar(&self.cx.checked.types, &ty) => {
                let vals = self.call_function(name, args, e.span)?;
                self.result_loc(vals, ty, e)
            }
            ExprKind::Valof(v) if !is_scalar(&self.cx.checked.types, &ty) => {
                let vals = self.valof(v)?;
                self.result_loc(vals, ty, e)
            }
            _ if is_scalar(&self.cx.checked.types, &ty) => {
                let v = self.expr(e)?;
                let size = size_of(&self.cx.checked.types, &ty).unwrap_or(WORD);
                let off = self.frame.alloc(size);
                let addr = self.local_addr(off);
                self.store_scalar(v, addr);
                Ok(Loc {
                    addr,
                    ty,
                    dims: vec![],
                })
            }
            _ => Err(self
                .cx
                .unsupported(e.span, "this array- or record-valued expression")),
        }
    }

    /// The place of a FUNCTION's or VALOF's single array- or record-valued result.
    fn result_loc(&mut self, vals: Vec<Value>, ty: Type, e: &Expr) -> Res<Loc> {
        let [addr] = vals[..] else {
            return Err(self.cx.internal(e.span, "one result expected"));
        };
        let ty = crate::layout::resolve(&self.cx.checked.types, &ty);
        let dims = crate::layout::static_dims(&ty)
            .into_iter()
            .map(|d| self.iconst(i64::from(d.unwrap_or(0))))
            .collect();
        Ok(Loc { addr, ty, dims })
    }

    fn record_value(
        &mut self,
        items: &[Expr],
        fields: Vec<(String, i64, Type)>,
        ty: Type,
        e: &Expr,
    ) -> Res<Loc> {
        let size = size_of(&self.cx.checked.types, &ty)
            .ok_or_else(|| self.cx.internal(e.span, "record size"))?;
        let off = self.frame.alloc(size);
        let base = self.local_addr(off);
        for (it, (_, foff, fty)) in items.iter().zip(fields) {
            let at = self.b.ins().iadd_imm_s(base, foff);
            self.assign_to(at, &fty, &[], it)?;
        }
        Ok(Loc {
            addr: base,
            ty,
            dims: vec![],
        })
    }

    fn table(&mut self, items: &[Expr], ty: Type, e: &Expr) -> Res<Loc> {
        // A table whose context wants a RECORD (`COMPLEX FUNCTION f () IS [x, y]`) builds it.
        if let Some(fields) = crate::layout::record_fields(&self.cx.checked.types, &ty) {
            return self.record_value(items, fields, ty, e);
        }
        let ty = crate::layout::resolve(&self.cx.checked.types, &ty);
        let Some(elem) = ty.elem().cloned() else {
            return Err(self.cx.internal(e.span, "table of non-array type"));
        };
        let es = size_of(&self.cx.checked.types, &elem)
            .ok_or_else(|| self.cx.unsupported(e.span, "a table of open arrays"))?;
        let off = self.frame.alloc(es * items.len() as i64);
        let base = self.local_addr(off);
        for (i, it) in items.iter().enumerate() {
            let at = self.b.ins().iadd_imm_s(base, es * i as i64);
            self.assign_to(at, &elem, &[], it)?;
        }
        let mut dims = vec![self.iconst(items.len() as i64)];
        for d in crate::layout::static_dims(&elem) {
            dims.push(self.iconst(i64::from(d.unwrap_or(0))));
        }
        Ok(Loc {
            addr: base,
            ty: Type::Array(Some(items.len() as u32), Box::new(elem)),
            dims,
        })
    }

    /// Stores the value of `e` into the place at `addr` of type `ty` (dims for open arrays).
    pub fn assign_to(&mut self, addr: Value, ty: &Type, dims: &[Value], e: &Expr) -> Res<()> {
        if let Some(p) = self.cx.checked.types.prim(ty) {
            let v = self.expr(e)?;
            let v = self.coerce(v, cl_type(p));
            self.store_scalar(v, addr);
            return Ok(());
        }
        let src = self.value_loc(e)?;
        let size = self.loc_size(&src, e.span)?;
        if !dims.is_empty() {
            let dst_size = self.size_of_loc(ty, dims, e.span)?;
            let ok = self.b.ins().icmp(
                cranelift_codegen::ir::condcodes::IntCC::Equal,
                size,
                dst_size,
            );
            self.check(ok, occ_runtime::ErrorKind::Segment, e.span);
        }
        self.copy_bytes(addr, src.addr, size);
        Ok(())
    }
}
