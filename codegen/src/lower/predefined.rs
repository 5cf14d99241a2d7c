//! The occam predefines, by [`PredefinedId`]: [`how`] says for every one of them whether it is
//! lowered inline (ABS/DABS, MULBY2/DIVBY2, MINUSX, COPYSIGN, ISNAN, NOTFINITE, the shift, rotate
//! and long-arithmetic routines, the comparisons and bit routines), called as a runtime intrinsic
//! (SQRT, SCALEB, LOGB, FPINT, NEXTAFTER and their D forms from the runtime's maths table; the IEEE
//! and transputer routines from `occ_runtime::intrinsic::predefine`), lowered as a process
//! (ASSERT, RESCHEDULE, CAUSEERROR) or not supported yet (the 2D block moves).

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::FloatCC, condcodes::IntCC, types};
use occ_compiler::predefined::{Predefined, PredefinedId as P};
use occ_grammar::ast::{Expr, Span};
use occ_runtime::ErrorKind;
use occ_runtime::abi::Entry;
use occ_runtime::intrinsic::{self, Intrinsic, predefine};

use super::{Res, Tr};

/// How the code generator implements a predefined routine.
enum How {
    /// Cranelift instructions in the caller.
    Inline,
    /// A call of a runtime intrinsic (a FUNCTION intrinsic, or one that returns the predefine's
    /// results through `RESULT` parameters after its arguments).
    Native(&'static Intrinsic),
    /// A PROC lowered as a process.
    Process,
    /// Not implemented yet.
    Unsupported,
}

/// How predefine `id` is implemented: every routine of the table, no default.
fn how(id: P) -> How {
    use How::*;
    match id {
        P::LongAdd
        | P::LongSub
        | P::AShiftLeft
        | P::AShiftRight
        | P::RotateLeft
        | P::RotateRight
        | P::LongSum
        | P::LongDiff
        | P::LongProd
        | P::LongDiv
        | P::ShiftLeft
        | P::ShiftRight
        | P::Normalise
        | P::Abs
        | P::DAbs
        | P::IsNan
        | P::DIsNan
        | P::NotFinite
        | P::DNotFinite
        | P::Ordered
        | P::DOrdered
        | P::MulBy2
        | P::DMulBy2
        | P::DivBy2
        | P::DDivBy2
        | P::CopySign
        | P::DCopySign
        | P::MinusX
        | P::DMinusX
        | P::Real32Op
        | P::Real64Op
        | P::Real32Rem
        | P::Real64Rem
        | P::Real32Eq
        | P::Real64Eq
        | P::Real32Gt
        | P::Real64Gt
        | P::IeeeCompare
        | P::DIeeeCompare
        | P::BitCount
        | P::BitRevWord
        | P::BitRevNBits => Inline,
        P::Sqrt => Native(&intrinsic::SQRT),
        P::DSqrt => Native(&intrinsic::DSQRT),
        P::LogB => Native(&intrinsic::LOGB),
        P::DLogB => Native(&intrinsic::DLOGB),
        P::ScaleB => Native(&intrinsic::SCALEB),
        P::DScaleB => Native(&intrinsic::DSCALEB),
        P::NextAfter => Native(&intrinsic::NEXTAFTER),
        P::DNextAfter => Native(&intrinsic::DNEXTAFTER),
        P::FpInt => Native(&intrinsic::FPINT),
        P::DFpInt => Native(&intrinsic::DFPINT),
        P::FracMul => Native(&predefine::FRACMUL),
        P::UnpackSn => Native(&predefine::UNPACKSN),
        P::RoundSn => Native(&predefine::ROUNDSN),
        P::FloatingUnpack => Native(&predefine::FLOATING_UNPACK),
        P::DFloatingUnpack => Native(&predefine::DFLOATING_UNPACK),
        P::ArgumentReduce => Native(&predefine::ARGUMENT_REDUCE),
        P::DArgumentReduce => Native(&predefine::DARGUMENT_REDUCE),
        P::Ieee32Op => Native(&predefine::IEEE32OP),
        P::Ieee64Op => Native(&predefine::IEEE64OP),
        P::Ieee32Rem => Native(&predefine::IEEE32REM),
        P::Ieee64Rem => Native(&predefine::IEEE64REM),
        P::CrcWord => Native(&predefine::CRCWORD),
        P::CrcByte => Native(&predefine::CRCBYTE),
        P::Assert | P::Reschedule | P::CauseError => Process,
        P::Move2D | P::Draw2D | P::Clip2D => Unsupported,
    }
}

impl Tr<'_, '_> {
    /// Lowers a call of predefined FUNCTION `p`.
    pub fn predefined_function(
        &mut self,
        p: &Predefined,
        args: &[Expr],
        span: Span,
    ) -> Res<Vec<Value>> {
        match how(p.id) {
            How::Native(i) if i.result.is_some() => self.call_intrinsic(i, args, span),
            How::Native(i) => {
                let v = self.eval_args(args)?;
                Ok(self.call_predefine(i, &v))
            }
            How::Inline => {
                let v = self.eval_args(args)?;
                self.inline_predefine(p, &v, span)
            }
            How::Process | How::Unsupported => Err(self
                .cx
                .unsupported(span, format!("the predefined FUNCTION {}", p.name))),
        }
    }

    fn eval_args(&mut self, args: &[Expr]) -> Res<Vec<Value>> {
        let mut v = Vec::new();
        for a in args {
            v.push(self.expr(a)?);
        }
        Ok(v)
    }

    /// Lowers predefine `p` inline on its evaluated arguments `v`.
    fn inline_predefine(&mut self, p: &Predefined, v: &[Value], span: Span) -> Res<Vec<Value>> {
        let ins = self.b.ins();
        let one = |v: Value| Ok(vec![v]);
        match (p.id, v) {
            (P::Abs | P::DAbs, [x]) => one(ins.fabs(*x)),
            (P::MinusX | P::DMinusX, [x]) => one(ins.fneg(*x)),
            (P::CopySign | P::DCopySign, [x, y]) => one(ins.fcopysign(*x, *y)),
            (P::MulBy2 | P::DMulBy2, [x]) => one(ins.fadd(*x, *x)),
            (P::DivBy2 | P::DDivBy2, [x]) => {
                let t = self.b.func.dfg.value_type(*x);
                let h = if t == types::F32 {
                    self.b.ins().f32const(0.5)
                } else {
                    self.b.ins().f64const(0.5)
                };
                one(self.b.ins().fmul(*x, h))
            }
            (P::IsNan | P::DIsNan, [x]) => one(ins.fcmp(FloatCC::Unordered, *x, *x)),
            (P::NotFinite | P::DNotFinite, [x]) => {
                let d = self.b.ins().fsub(*x, *x);
                one(self.b.ins().fcmp(FloatCC::Unordered, d, d))
            }
            (P::Ordered | P::DOrdered, [x, y]) => one(ins.fcmp(FloatCC::Ordered, *x, *y)),
            (P::AShiftLeft, [x, n]) => one(ins.ishl(*x, *n)),
            (P::AShiftRight, [x, n]) => one(ins.sshr(*x, *n)),
            (P::RotateLeft, [x, n]) => one(ins.rotl(*x, *n)),
            (P::RotateRight, [x, n]) => one(ins.rotr(*x, *n)),
            (P::LongAdd, [a, b, c]) => {
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let s = self.checked_add3(*a, *b, c1, span);
                one(s)
            }
            (P::LongSub, [a, b, c]) => {
                let c1 = self.b.ins().band_imm_s(*c, 1);
                let (r1, o1) = self.b.ins().ssub_overflow(*a, *b);
                let (r2, o2) = self.b.ins().ssub_overflow(r1, c1);
                let o = self.b.ins().bor(o1, o2);
                let ok = self.b.ins().bxor_imm_s(o, 1);
                self.check(ok, ErrorKind::Overflow, span);
                one(r2)
            }
            (P::LongSum, [a, b, c]) => {
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
            (P::LongDiff, [a, b, c]) => {
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
            (P::LongProd, [a, b, c]) => {
                let w = |tr: &mut Self, x: Value| tr.b.ins().uextend(types::I64, x);
                let (a, b, c) = (w(self, *a), w(self, *b), w(self, *c));
                let p = self.b.ins().imul(a, b);
                let p = self.b.ins().iadd(p, c);
                let hi = self.b.ins().ushr_imm_s(p, 32);
                let hi = self.b.ins().ireduce(types::I32, hi);
                let lo = self.b.ins().ireduce(types::I32, p);
                Ok(vec![hi, lo])
            }
            (P::Real32Op | P::Real64Op, [x, op, y]) => {
                let (x, op, y) = (*x, *op, *y);
                let a = self.b.ins().fadd(x, y);
                let s = self.b.ins().fsub(x, y);
                let m = self.b.ins().fmul(x, y);
                let d = self.b.ins().fdiv(x, y);
                let mut r = d;
                for (k, v) in [(2, m), (1, s), (0, a)] {
                    let is = self.b.ins().icmp_imm_s(IntCC::Equal, op, k);
                    r = self.b.ins().select(is, v, r);
                }
                one(r)
            }
            (P::Real32Rem | P::Real64Rem, [x, y]) => {
                let q = self.b.ins().fdiv(*x, *y);
                let q = self.b.ins().nearest(q);
                let m = self.b.ins().fmul(q, *y);
                one(self.b.ins().fsub(*x, m))
            }
            (P::LongDiv, [hi, lo, d]) => {
                let (hi, lo, d) = (*hi, *lo, *d);
                let ok = self.b.ins().icmp(IntCC::UnsignedLessThan, hi, d);
                self.check(ok, ErrorKind::Overflow, span);
                let n = self.pair(hi, lo);
                let d = self.b.ins().uextend(types::I64, d);
                let q = self.b.ins().udiv(n, d);
                let r = self.b.ins().urem(n, d);
                let q = self.b.ins().ireduce(types::I32, q);
                let r = self.b.ins().ireduce(types::I32, r);
                Ok(vec![q, r])
            }
            (P::ShiftLeft | P::ShiftRight, [hi, lo, n]) => {
                let v = self.pair(*hi, *lo);
                let n = self.b.ins().uextend(types::I64, *n);
                let big = self
                    .b
                    .ins()
                    .icmp_imm_s(IntCC::UnsignedGreaterThanOrEqual, n, 64);
                let r = if p.id == P::ShiftLeft {
                    self.b.ins().ishl(v, n)
                } else {
                    self.b.ins().ushr(v, n)
                };
                let zero = self.b.ins().iconst(types::I64, 0);
                let r = self.b.ins().select(big, zero, r);
                Ok(self.split(r))
            }
            (P::Normalise, [hi, lo]) => {
                let v = self.pair(*hi, *lo);
                let z = self.b.ins().clz(v);
                let is0 = self.b.ins().icmp_imm_s(IntCC::Equal, v, 0);
                let r = self.b.ins().ishl(v, z);
                let zero = self.b.ins().iconst(types::I64, 0);
                let r = self.b.ins().select(is0, zero, r);
                let places = self.b.ins().ireduce(types::I32, z);
                let mut out = vec![places];
                out.extend(self.split(r));
                Ok(out)
            }
            _ => match self.bits_predefine(p.id, v) {
                Some(r) => Ok(vec![r]),
                None => Err(self
                    .cx
                    .unsupported(span, format!("the predefined FUNCTION {}", p.name))),
            },
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

    /// Lowers a call of predefined PROC `p`.
    pub fn predefined_proc(&mut self, p: &Predefined, args: &[Expr], span: Span) -> Res<()> {
        match (p.id, args) {
            (P::Assert, [c]) => {
                let v = self.expr(c)?;
                self.check(v, ErrorKind::Assert, span);
                Ok(())
            }
            (P::Reschedule, []) => self.blocking(Entry::Reschedule, &[self.node, self.ws], span),
            (P::CauseError, []) => {
                self.halt(ErrorKind::Stop, span);
                let dead = self.b.create_block();
                self.b.switch_to_block(dead);
                Ok(())
            }
            _ => Err(self
                .cx
                .unsupported(span, format!("the predefined PROC {}", p.name))),
        }
    }
}
