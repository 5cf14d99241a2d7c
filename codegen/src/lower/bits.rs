//! Predefines lowered through [`crate::native`] helpers (multi-result IEEE and transputer
//! routines) and the bit and comparison predefines lowered inline: REAL32EQ/GT, REAL64EQ/GT,
//! IEEECOMPARE/DIEEECOMPARE, BITCOUNT, BITREVWORD and BITREVNBITS.

use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::{InstBuilder, Value, types};
use cranelift_module::Module;
use occ_runtime::abi::word_offset;

use super::{Tr, mem};
use crate::native::{self, Arg, Helper, OUT_WORDS, Out};

impl Tr<'_, '_> {
    /// Lowers predefine `name` on evaluated arguments `v` if it is one of this module's, giving
    /// `None` otherwise.
    pub fn bits_predefine(&mut self, name: &str, v: &[Value]) -> Option<Vec<Value>> {
        if let Some(h) = native::helper(name).filter(|h| h.args.len() == v.len()) {
            return Some(self.call_helper(h, v));
        }
        let r = match (name, v) {
            ("REAL32EQ" | "REAL64EQ", [x, y]) => self.b.ins().fcmp(FloatCC::Equal, *x, *y),
            ("REAL32GT" | "REAL64GT", [x, y]) => self.b.ins().fcmp(FloatCC::GreaterThan, *x, *y),
            ("IEEECOMPARE" | "DIEEECOMPARE", [x, y]) => self.ieee_compare(*x, *y),
            ("BITCOUNT", [w, c]) => {
                let n = self.b.ins().popcnt(*w);
                self.b.ins().iadd(n, *c)
            }
            ("BITREVWORD", [w]) => self.b.ins().bitrev(*w),
            ("BITREVNBITS", [w, n]) => self.bitrev_n(*w, *n),
            _ => return None,
        };
        Some(vec![r])
    }

    /// -1, 0, 1 for less, equal, greater; 2 when unordered.
    fn ieee_compare(&mut self, x: Value, y: Value) -> Value {
        let mut r = self.b.ins().iconst(types::I32, 2);
        for (cc, k) in [
            (FloatCC::Equal, 0),
            (FloatCC::GreaterThan, 1),
            (FloatCC::LessThan, -1),
        ] {
            let is = self.b.ins().fcmp(cc, x, y);
            let kv = self.b.ins().iconst(types::I32, k);
            r = self.b.ins().select(is, kv, r);
        }
        r
    }

    /// The low `n` bits of `w` reversed (0 when n is 0).
    fn bitrev_n(&mut self, w: Value, n: Value) -> Value {
        let r = self.b.ins().bitrev(w);
        let r = self.b.ins().uextend(types::I64, r);
        let n = self.b.ins().uextend(types::I64, n);
        let k = self.b.ins().iconst(types::I64, 32);
        let sh = self.b.ins().isub(k, n);
        let big = self.b.ins().icmp_imm_u(IntCC::UnsignedGreaterThan, sh, 63);
        let zero = self.b.ins().iconst(types::I64, 0);
        let s = self.b.ins().ushr(r, sh);
        let s = self.b.ins().select(big, zero, s);
        self.b.ins().ireduce(types::I32, s)
    }

    /// Calls helper `h` with a temporary output buffer and loads its results.
    fn call_helper(&mut self, h: &'static Helper, v: &[Value]) -> Vec<Value> {
        let mut args = Vec::new();
        for (a, x) in h.args.iter().zip(v) {
            let x = match a {
                Arg::Int if self.b.func.dfg.value_type(*x) != types::I64 => {
                    self.b.ins().sextend(types::I64, *x)
                }
                _ => *x,
            };
            args.push(x);
        }
        let off = self.frame.alloc_words(OUT_WORDS as usize);
        let buf = self.local_addr(off);
        args.push(buf);
        let id = self.cx.jit.natives[h.name];
        let f = self.cx.jit.module.declare_func_in_func(id, self.b.func);
        self.b.ins().call(f, &args);
        let mut out = Vec::new();
        for (k, r) in h.results.iter().enumerate() {
            let ty = match r {
                Out::Int => types::I32,
                Out::Bool => types::I8,
                Out::R32 => types::F32,
                Out::R64 => types::F64,
            };
            out.push(self.b.ins().load(ty, mem(), buf, word_offset(k as isize)));
        }
        out
    }
}
