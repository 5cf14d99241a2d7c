//! Operators with occam semantics: `+ - * / \` checked (overflow, division by zero), `PLUS MINUS
//! TIMES` modulo, shifts checked, short-circuit `AND`/`OR`, `AFTER`, and range-checked
//! conversions with ROUND/TRUNC.

use cranelift_codegen::ir::{
    InstBuilder, Value,
    condcodes::{FloatCC, IntCC},
    types,
};
use occ_compiler::types::Prim;
use occ_grammar::ast::{BinOp, ConvMode, Expr, ExprKind, Span};
use occ_runtime::ErrorKind;

use super::{Res, Tr};
use crate::layout::cl_type;

impl Tr<'_, '_> {
    /// Lowers a binary operator expression `e`.
    pub fn binary(&mut self, op: BinOp, lhs: &Expr, rhs: &Expr, e: &Expr) -> Res<Value> {
        if matches!(op, BinOp::And | BinOp::Or) {
            return self.short_circuit(op == BinOp::And, lhs, rhs);
        }
        if let (ExprKind::List(ls), ExprKind::List(rs)) = (&lhs.kind, &rhs.kind)
            && matches!(op, BinOp::Eq | BinOp::Ne)
            && ls.len() == rs.len()
        {
            return self.list_equal(op == BinOp::Eq, ls, rs, e);
        }
        let p = self.prim_of(lhs)?;
        let a = self.expr(lhs)?;
        let a = self.coerce(a, cl_type(p));
        let b = self.expr(rhs)?;
        let b = if matches!(op, BinOp::Shl | BinOp::Shr) {
            b
        } else {
            self.coerce(b, cl_type(p))
        };
        match op {
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Gt | BinOp::Le | BinOp::Ge => {
                Ok(self.compare(op, p, a, b))
            }
            BinOp::After => {
                let d = self.b.ins().isub(a, b);
                Ok(self.b.ins().icmp_imm_s(IntCC::SignedGreaterThan, d, 0))
            }
            BinOp::Shl | BinOp::Shr => self.shift(op, p, a, b, e.span),
            BinOp::User(_) => Err(self.cx.internal(e.span, "undefined operator")),
            _ => self.arith(op, p, a, b, e.span),
        }
    }

    /// `(a, b) = (c, d)`: every pair equal (`<>`: some pair different). Each side is
    /// evaluated in full; expressions have no side effects.
    fn list_equal(&mut self, eq: bool, ls: &[Expr], rs: &[Expr], e: &Expr) -> Res<Value> {
        let mut all = self.b.ins().iconst(types::I8, 1);
        for (l, r) in ls.iter().zip(rs) {
            let v = self.binary(BinOp::Eq, l, r, e)?;
            all = self.b.ins().band(all, v);
        }
        Ok(if eq {
            all
        } else {
            self.b.ins().bxor_imm_s(all, 1)
        })
    }

    /// Makes `v` a value of Cranelift type `t` (sign-extending or truncating integers, promoting
    /// or demoting floats); the checker's types and the stored widths agree, so this only
    /// bridges context-typed constants.
    pub fn coerce(&mut self, v: Value, t: types::Type) -> Value {
        let vt = self.b.func.dfg.value_type(v);
        if vt == t {
            return v;
        }
        match (vt.is_float(), t.is_float()) {
            (false, false) if vt.bits() < t.bits() => self.b.ins().sextend(t, v),
            (false, false) => self.b.ins().ireduce(t, v),
            (true, true) if vt.bits() < t.bits() => self.b.ins().fpromote(t, v),
            (true, true) => self.b.ins().fdemote(t, v),
            (false, true) => self.b.ins().fcvt_from_sint(t, v),
            (true, false) => self.b.ins().fcvt_to_sint_sat(t, v),
        }
    }

    fn short_circuit(&mut self, and: bool, lhs: &Expr, rhs: &Expr) -> Res<Value> {
        let a = self.expr(lhs)?;
        let done = self.b.create_block();
        self.b.append_block_param(done, types::I8);
        let more = self.b.create_block();
        if and {
            self.b.ins().brif(a, more, &[], done, &[a.into()]);
        } else {
            self.b.ins().brif(a, done, &[a.into()], more, &[]);
        }
        self.b.switch_to_block(more);
        let b = self.expr(rhs)?;
        self.b.ins().jump(done, &[b.into()]);
        self.b.switch_to_block(done);
        Ok(self.b.block_params(done)[0])
    }

    fn compare(&mut self, op: BinOp, p: Prim, a: Value, b: Value) -> Value {
        if p.is_real() {
            let cc = match op {
                BinOp::Eq => FloatCC::Equal,
                BinOp::Ne => FloatCC::NotEqual,
                BinOp::Lt => FloatCC::LessThan,
                BinOp::Gt => FloatCC::GreaterThan,
                BinOp::Le => FloatCC::LessThanOrEqual,
                _ => FloatCC::GreaterThanOrEqual,
            };
            return self.b.ins().fcmp(cc, a, b);
        }
        let unsigned = matches!(p, Prim::Byte | Prim::Bool);
        let cc = match (op, unsigned) {
            (BinOp::Eq, _) => IntCC::Equal,
            (BinOp::Ne, _) => IntCC::NotEqual,
            (BinOp::Lt, false) => IntCC::SignedLessThan,
            (BinOp::Gt, false) => IntCC::SignedGreaterThan,
            (BinOp::Le, false) => IntCC::SignedLessThanOrEqual,
            (BinOp::Ge, false) => IntCC::SignedGreaterThanOrEqual,
            (BinOp::Lt, true) => IntCC::UnsignedLessThan,
            (BinOp::Gt, true) => IntCC::UnsignedGreaterThan,
            (BinOp::Le, true) => IntCC::UnsignedLessThanOrEqual,
            _ => IntCC::UnsignedGreaterThanOrEqual,
        };
        self.b.ins().icmp(cc, a, b)
    }

    fn shift(&mut self, op: BinOp, p: Prim, a: Value, n: Value, span: Span) -> Res<Value> {
        let t = cl_type(p);
        let bits = i64::from(t.bits());
        let n64 = if self.b.func.dfg.value_type(n) == types::I64 {
            n
        } else {
            self.b.ins().sextend(types::I64, n)
        };
        let ok = self
            .b
            .ins()
            .icmp_imm_s(IntCC::UnsignedLessThanOrEqual, n64, bits);
        self.check(ok, ErrorKind::Shift, span);
        let full = self.b.ins().icmp_imm_s(IntCC::Equal, n64, bits);
        let r = if op == BinOp::Shl {
            self.b.ins().ishl(a, n64)
        } else {
            self.b.ins().ushr(a, n64)
        };
        let zero = self.b.ins().iconst(t, 0);
        Ok(self.b.ins().select(full, zero, r))
    }

    /// An arithmetic or bitwise operator in type `p`.
    pub fn arith(&mut self, op: BinOp, p: Prim, a: Value, b: Value, span: Span) -> Res<Value> {
        let ins = self.b.ins();
        if p.is_real() {
            return Ok(match op {
                BinOp::Add | BinOp::Plus => ins.fadd(a, b),
                BinOp::Sub | BinOp::Minus => ins.fsub(a, b),
                BinOp::Mul | BinOp::Times => ins.fmul(a, b),
                BinOp::Div => {
                    let zero = match p {
                        Prim::Real32 => ins.f32const(0.0),
                        _ => ins.f64const(0.0),
                    };
                    let nz = self.b.ins().fcmp(FloatCC::NotEqual, b, zero);
                    self.check(nz, ErrorKind::Floating, span);
                    self.b.ins().fdiv(a, b)
                }
                BinOp::Rem => {
                    let q = ins.fdiv(a, b);
                    // IEEE remainder: the quotient rounded to nearest (ties to even).
                    let q = self.b.ins().nearest(q);
                    let m = self.b.ins().fmul(q, b);
                    self.b.ins().fsub(a, m)
                }
                _ => return Err(self.cx.internal(span, "bad REAL operator")),
            });
        }
        Ok(match op {
            BinOp::Plus => ins.iadd(a, b),
            BinOp::Minus => ins.isub(a, b),
            BinOp::Times => ins.imul(a, b),
            BinOp::BitAnd => ins.band(a, b),
            BinOp::BitOr => ins.bor(a, b),
            BinOp::Xor => ins.bxor(a, b),
            BinOp::Add | BinOp::Sub | BinOp::Mul => self.checked(op, p, a, b, span),
            BinOp::Div | BinOp::Rem => self.divide(op, p, a, b, span),
            _ => return Err(self.cx.internal(span, "bad integer operator")),
        })
    }

    fn checked(&mut self, op: BinOp, p: Prim, a: Value, b: Value, span: Span) -> Value {
        let t = cl_type(p);
        if t.bits() >= 32 {
            let (r, of) = match op {
                BinOp::Add => self.b.ins().sadd_overflow(a, b),
                BinOp::Sub => self.b.ins().ssub_overflow(a, b),
                _ => self.b.ins().smul_overflow(a, b),
            };
            let ok = self.b.ins().bxor_imm_s(of, 1);
            self.check(ok, ErrorKind::Overflow, span);
            return r;
        }
        let unsigned = p == Prim::Byte;
        let (wa, wb) = if unsigned {
            (
                self.b.ins().uextend(types::I32, a),
                self.b.ins().uextend(types::I32, b),
            )
        } else {
            (
                self.b.ins().sextend(types::I32, a),
                self.b.ins().sextend(types::I32, b),
            )
        };
        let r = match op {
            BinOp::Add => self.b.ins().iadd(wa, wb),
            BinOp::Sub => self.b.ins().isub(wa, wb),
            _ => self.b.ins().imul(wa, wb),
        };
        let (lo, hi) = p.int_range().unwrap_or((0, 255));
        self.range_check_i32(r, lo, hi, ErrorKind::Overflow, span);
        self.b.ins().ireduce(t, r)
    }

    fn range_check_i32(&mut self, r: Value, lo: i64, hi: i64, kind: ErrorKind, span: Span) {
        let a = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, r, lo);
        let b = self.b.ins().icmp_imm_s(IntCC::SignedLessThanOrEqual, r, hi);
        let ok = self.b.ins().band(a, b);
        self.check(ok, kind, span);
    }

    fn divide(&mut self, op: BinOp, p: Prim, a: Value, b: Value, span: Span) -> Value {
        let t = cl_type(p);
        let nz = self.b.ins().icmp_imm_s(IntCC::NotEqual, b, 0);
        self.check(nz, ErrorKind::DivideByZero, span);
        if p == Prim::Byte {
            return if op == BinOp::Div {
                self.b.ins().udiv(a, b)
            } else {
                self.b.ins().urem(a, b)
            };
        }
        let min = if t.bits() == 64 {
            i64::MIN
        } else {
            -(1i64 << (t.bits() - 1))
        };
        let is_m1 = self.b.ins().icmp_imm_s(IntCC::Equal, b, -1);
        if op == BinOp::Div {
            let is_min = self.b.ins().icmp_imm_s(IntCC::Equal, a, min);
            let bad = self.b.ins().band(is_min, is_m1);
            let ok = self.b.ins().bxor_imm_s(bad, 1);
            self.check(ok, ErrorKind::Overflow, span);
            self.b.ins().sdiv(a, b)
        } else {
            // x \ -1 is 0; avoid the MIN \ -1 trap of the hardware instruction.
            let one = self.b.ins().iconst(t, 1);
            let d = self.b.ins().select(is_m1, one, b);
            self.b.ins().srem(a, d)
        }
    }

    /// Converts `v` from `from` to `to` (range-checked; ROUND/TRUNC for reals).
    pub fn convert(
        &mut self,
        v: Value,
        from: Prim,
        to: Prim,
        mode: ConvMode,
        span: Span,
    ) -> Res<Value> {
        let (ft, tt) = (cl_type(from), cl_type(to));
        let v = self.coerce(v, ft);
        if from == to
            || (ft == tt
                && !matches!((from, to), (Prim::Bool, _) | (_, Prim::Bool))
                && from != Prim::Byte
                && to != Prim::Byte)
        {
            return Ok(v);
        }
        match (from.is_real(), to.is_real()) {
            (false, false) => Ok(self.int_convert(v, from, to, span)),
            (false, true) => Ok(if from == Prim::Byte || from == Prim::Bool {
                self.b.ins().fcvt_from_uint(tt, v)
            } else if mode == ConvMode::Trunc {
                self.int_to_real_trunc(v, tt)
            } else {
                self.b.ins().fcvt_from_sint(tt, v)
            }),
            (true, true) if tt.bits() > ft.bits() => Ok(self.b.ins().fpromote(tt, v)),
            (true, true) if mode == ConvMode::Trunc => Ok(self.demote_trunc(v)),
            (true, true) => Ok(self.b.ins().fdemote(tt, v)),
            (true, false) => Ok(self.real_to_int(v, from, to, mode, span)),
        }
    }

    /// REAL64 to REAL32 rounding toward zero: demote to nearest, then step one unit toward zero
    /// if that rounded away from zero.
    fn demote_trunc(&mut self, v: Value) -> Value {
        let r = self.b.ins().fdemote(types::F32, v);
        let back = self.b.ins().fpromote(types::F64, r);
        let ab = self.b.ins().fabs(back);
        let av = self.b.ins().fabs(v);
        let away = self.b.ins().fcmp(FloatCC::GreaterThan, ab, av);
        let bits = self
            .b
            .ins()
            .bitcast(types::I32, cranelift_codegen::ir::MemFlagsData::new(), r);
        let bits = self.b.ins().iadd_imm_s(bits, -1);
        let r2 = self
            .b
            .ins()
            .bitcast(types::F32, cranelift_codegen::ir::MemFlagsData::new(), bits);
        self.b.ins().select(away, r2, r)
    }

    /// A signed integer to REAL rounding toward zero: convert to nearest, then step one unit
    /// toward zero if that rounded away from zero (found by converting back, saturating).
    fn int_to_real_trunc(&mut self, v: Value, tt: types::Type) -> Value {
        let w = if self.b.func.dfg.value_type(v) == types::I64 {
            v
        } else {
            self.b.ins().sextend(types::I64, v)
        };
        let r = self.b.ins().fcvt_from_sint(tt, w);
        let back = self.b.ins().fcvt_to_sint_sat(types::I64, r);
        let pos = self.b.ins().icmp_imm_s(IntCC::SignedGreaterThan, w, 0);
        let above = self.b.ins().icmp(IntCC::SignedGreaterThan, back, w);
        let lim = if tt == types::F32 {
            self.b.ins().f32const(2f32.powi(63))
        } else {
            self.b.ins().f64const(2f64.powi(63))
        };
        let sat = self.b.ins().fcmp(FloatCC::GreaterThanOrEqual, r, lim);
        let up = self.b.ins().bor(above, sat);
        let up = self.b.ins().band(pos, up);
        let neg = self.b.ins().icmp_imm_s(IntCC::SignedLessThan, w, 0);
        let below = self.b.ins().icmp(IntCC::SignedLessThan, back, w);
        let down = self.b.ins().band(neg, below);
        let away = self.b.ins().bor(up, down);
        let it = if tt == types::F32 {
            types::I32
        } else {
            types::I64
        };
        let flags = cranelift_codegen::ir::MemFlagsData::new();
        let bits = self.b.ins().bitcast(it, flags, r);
        let bits = self.b.ins().iadd_imm_s(bits, -1);
        let r2 = self.b.ins().bitcast(tt, flags, bits);
        self.b.ins().select(away, r2, r)
    }

    fn int_convert(&mut self, v: Value, from: Prim, to: Prim, span: Span) -> Value {
        let tt = cl_type(to);
        let unsigned = matches!(from, Prim::Byte | Prim::Bool);
        let w = if self.b.func.dfg.value_type(v) == types::I64 {
            v
        } else if unsigned {
            self.b.ins().uextend(types::I64, v)
        } else {
            self.b.ins().sextend(types::I64, v)
        };
        let (lo, hi) = match to {
            Prim::Bool => (0, 1),
            p => p.int_range().unwrap_or((i64::MIN, i64::MAX)),
        };
        if lo != i64::MIN || hi != i64::MAX {
            let a = self
                .b
                .ins()
                .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, w, lo);
            let b = self.b.ins().icmp_imm_s(IntCC::SignedLessThanOrEqual, w, hi);
            let ok = self.b.ins().band(a, b);
            self.check(ok, ErrorKind::Conversion, span);
        }
        if tt == types::I64 {
            w
        } else {
            self.b.ins().ireduce(tt, w)
        }
    }

    fn real_to_int(&mut self, v: Value, from: Prim, to: Prim, mode: ConvMode, span: Span) -> Value {
        let r = if mode == ConvMode::Trunc {
            self.b.ins().trunc(v)
        } else {
            self.b.ins().nearest(v)
        };
        let r64 = if from == Prim::Real32 {
            self.b.ins().fpromote(types::F64, r)
        } else {
            r
        };
        let (lo, hi) = to.int_range().unwrap_or((0, 1));
        let flo = self.b.ins().f64const(lo as f64);
        let fhi = self.b.ins().f64const(hi as f64 + 1.0);
        let a = self.b.ins().fcmp(FloatCC::GreaterThanOrEqual, r64, flo);
        let b = self.b.ins().fcmp(FloatCC::LessThan, r64, fhi);
        let ok = self.b.ins().band(a, b);
        self.check(ok, ErrorKind::Conversion, span);
        let tt = cl_type(to);
        if tt.bits() >= 32 {
            self.b.ins().fcvt_to_sint(tt, r64)
        } else {
            let i = self.b.ins().fcvt_to_sint(types::I32, r64);
            self.b.ins().ireduce(tt, i)
        }
    }
}
