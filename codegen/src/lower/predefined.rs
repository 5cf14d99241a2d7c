//! The occam predefines lowered inline: ABS/DABS, MULBY2/DIVBY2, MINUSX, COPYSIGN, ISNAN,
//! NOTFINITE, the shift and rotate routines, LONGADD/LONGSUB/LONGSUM/LONGDIFF/LONGPROD, and the
//! PROCs ASSERT, RESCHEDULE and CAUSEERROR. Others are reported as not yet supported.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::FloatCC, types};
use occ_grammar::ast::{Expr, Span};
use occ_runtime::ErrorKind;
use occ_runtime::abi::Entry;

use super::{Res, Tr};

impl Tr<'_, '_> {
    /// Lowers a call of predefined FUNCTION `name`.
    pub fn predefined_function(
        &mut self,
        name: &str,
        args: &[Expr],
        span: Span,
    ) -> Res<Vec<Value>> {
        let mut v = Vec::new();
        for a in args {
            v.push(self.expr(a)?);
        }
        if let Some(r) = self.bits_predefine(name, &v) {
            return Ok(r);
        }
        let ins = self.b.ins();
        let one = |v: Value| Ok(vec![v]);
        match (name, v.as_slice()) {
            ("ABS" | "DABS", [x]) => one(ins.fabs(*x)),
            ("MINUSX" | "DMINUSX", [x]) => one(ins.fneg(*x)),
            ("COPYSIGN" | "DCOPYSIGN", [x, y]) => one(ins.fcopysign(*x, *y)),
            ("MULBY2" | "DMULBY2", [x]) => one(ins.fadd(*x, *x)),
            ("DIVBY2" | "DDIVBY2", [x]) => {
                let t = self.b.func.dfg.value_type(*x);
                let h = if t == types::F32 {
                    self.b.ins().f32const(0.5)
                } else {
                    self.b.ins().f64const(0.5)
                };
                one(self.b.ins().fmul(*x, h))
            }
            ("ISNAN" | "DISNAN", [x]) => one(ins.fcmp(FloatCC::Unordered, *x, *x)),
            ("NOTFINITE" | "DNOTFINITE", [x]) => {
                let d = self.b.ins().fsub(*x, *x);
                one(self.b.ins().fcmp(FloatCC::Unordered, d, d))
            }
            ("ORDERED" | "DORDERED", [x, y]) => one(ins.fcmp(FloatCC::Ordered, *x, *y)),
            ("ASHIFTLEFT", [x, n]) => one(ins.ishl(*x, *n)),
            ("ASHIFTRIGHT", [x, n]) => one(ins.sshr(*x, *n)),
            ("ROTATELEFT", [x, n]) => one(ins.rotl(*x, *n)),
            ("ROTATERIGHT", [x, n]) => one(ins.rotr(*x, *n)),
            ("LONGADD", [a, b, c]) => {
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let s = self.checked_add3(*a, *b, c1, span);
                one(s)
            }
            ("LONGSUB", [a, b, c]) => {
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let (r1, o1) = self.b.ins().ssub_overflow(*a, *b);
                let (r2, o2) = self.b.ins().ssub_overflow(r1, c1);
                let o = self.b.ins().bor(o1, o2);
                let ok = self.b.ins().bxor_imm_s(o, 1);
                self.check(ok, ErrorKind::Overflow, span);
                one(r2)
            }
            ("LONGSUM", [a, b, c]) => {
                let w = |tr: &mut Self, x: Value| tr.b.ins().uextend(types::I64, x);
                let (a, b) = (w(self, *a), w(self, *b));
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let c1 = w(self, c1);
                let s = self.b.ins().iadd(a, b);
                let s = self.b.ins().iadd(s, c1);
                let hi = self.b.ins().ushr_imm_s(s, 32);
                let hi = self.b.ins().ireduce(types::I32, hi);
                let lo = self.b.ins().ireduce(types::I32, s);
                Ok(vec![hi, lo])
            }
            ("LONGDIFF", [a, b, c]) => {
                let w = |tr: &mut Self, x: Value| tr.b.ins().uextend(types::I64, x);
                let (a, b) = (w(self, *a), w(self, *b));
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let c1 = w(self, c1);
                let s = self.b.ins().isub(a, b);
                let s = self.b.ins().isub(s, c1);
                let hi = self.b.ins().ushr_imm_s(s, 32);
                let hi = self.b.ins().band_imm_s(hi, 1);
                let hi = self.b.ins().ireduce(types::I32, hi);
                let lo = self.b.ins().ireduce(types::I32, s);
                Ok(vec![hi, lo])
            }
            ("LONGPROD", [a, b, c]) => {
                let w = |tr: &mut Self, x: Value| tr.b.ins().uextend(types::I64, x);
                let (a, b, c) = (w(self, *a), w(self, *b), w(self, *c));
                let p = self.b.ins().imul(a, b);
                let p = self.b.ins().iadd(p, c);
                let hi = self.b.ins().ushr_imm_s(p, 32);
                let hi = self.b.ins().ireduce(types::I32, hi);
                let lo = self.b.ins().ireduce(types::I32, p);
                Ok(vec![hi, lo])
            }
            ("REAL32OP" | "REAL64OP", [x, op, y]) => {
                let (x, op, y) = (*x, *op, *y);
                let a = self.b.ins().fadd(x, y);
                let s = self.b.ins().fsub(x, y);
                let m = self.b.ins().fmul(x, y);
                let d = self.b.ins().fdiv(x, y);
                let mut r = d;
                for (k, v) in [(2, m), (1, s), (0, a)] {
                    let is = self.b.ins().icmp_imm_s(
                        cranelift_codegen::ir::condcodes::IntCC::Equal,
                        op,
                        k,
                    );
                    r = self.b.ins().select(is, v, r);
                }
                one(r)
            }
            ("REAL32REM" | "REAL64REM" | "DREM", [x, y]) => {
                let q = self.b.ins().fdiv(*x, *y);
                let q = self.b.ins().nearest(q);
                let m = self.b.ins().fmul(q, *y);
                one(self.b.ins().fsub(*x, m))
            }
            ("LONGDIV", [hi, lo, d]) => {
                let (hi, lo, d) = (*hi, *lo, *d);
                let ok = self.b.ins().icmp(
                    cranelift_codegen::ir::condcodes::IntCC::UnsignedLessThan,
                    hi,
                    d,
                );
                self.check(ok, ErrorKind::Overflow, span);
                let n = self.pair(hi, lo);
                let d = self.b.ins().uextend(types::I64, d);
                let q = self.b.ins().udiv(n, d);
                let r = self.b.ins().urem(n, d);
                let q = self.b.ins().ireduce(types::I32, q);
                let r = self.b.ins().ireduce(types::I32, r);
                Ok(vec![q, r])
            }
            ("SHIFTLEFT" | "SHIFTRIGHT", [hi, lo, n]) => {
                let v = self.pair(*hi, *lo);
                let n = self.b.ins().uextend(types::I64, *n);
                let big = self.b.ins().icmp_imm_s(
                    cranelift_codegen::ir::condcodes::IntCC::UnsignedGreaterThanOrEqual,
                    n,
                    64,
                );
                let r = if name == "SHIFTLEFT" {
                    self.b.ins().ishl(v, n)
                } else {
                    self.b.ins().ushr(v, n)
                };
                let zero = self.b.ins().iconst(types::I64, 0);
                let r = self.b.ins().select(big, zero, r);
                Ok(self.split(r))
            }
            ("NORMALISE", [hi, lo]) => {
                let v = self.pair(*hi, *lo);
                let z = self.b.ins().clz(v);
                let is0 =
                    self.b
                        .ins()
                        .icmp_imm_s(cranelift_codegen::ir::condcodes::IntCC::Equal, v, 0);
                let r = self.b.ins().ishl(v, z);
                let zero = self.b.ins().iconst(types::I64, 0);
                let r = self.b.ins().select(is0, zero, r);
                let places = self.b.ins().ireduce(types::I32, z);
                let mut out = vec![places];
                out.extend(self.split(r));
                Ok(out)
            }
            _ => Err(self
                .cx
                .unsupported(span, format!("the predefined FUNCTION {name}"))),
        }
    }

    /// The unsigned 64-bit value `hi:lo` of two INTs.
    fn pair(&mut self, hi: Value, lo: Value) -> Value {
        let h = self.b.ins().uextend(types::I64, hi);
        let h = self.b.ins().ishl_imm_s(h, 32);
        let l = self.b.ins().uextend(types::I64, lo);
        self.b.ins().bor(h, l)
    }

    /// Splits a 64-bit value into (hi, lo) INTs.
    fn split(&mut self, v: Value) -> Vec<Value> {
        let h = self.b.ins().ushr_imm_s(v, 32);
        let h = self.b.ins().ireduce(types::I32, h);
        let l = self.b.ins().ireduce(types::I32, v);
        vec![h, l]
    }

    fn checked_add3(&mut self, a: Value, b: Value, c: Value, span: Span) -> Value {
        let (r1, o1) = self.b.ins().sadd_overflow(a, b);
        let (r2, o2) = self.b.ins().sadd_overflow(r1, c);
        let o = self.b.ins().bor(o1, o2);
        let ok = self.b.ins().bxor_imm_s(o, 1);
        self.check(ok, ErrorKind::Overflow, span);
        r2
    }

    /// Lowers a call of predefined PROC `name`.
    pub fn predefined_proc(&mut self, name: &str, args: &[Expr], span: Span) -> Res<()> {
        match (name, args) {
            ("ASSERT", [c]) => {
                let v = self.expr(c)?;
                self.check(v, ErrorKind::Assert, span);
                Ok(())
            }
            ("RESCHEDULE", []) => self.blocking(Entry::Reschedule, &[self.node, self.ws], span),
            ("CAUSEERROR", []) => {
                self.halt(ErrorKind::Stop, span);
                let dead = self.b.create_block();
                self.b.switch_to_block(dead);
                Ok(())
            }
            _ => Err(self
                .cx
                .unsupported(span, format!("the predefined PROC {name}"))),
        }
    }
}
