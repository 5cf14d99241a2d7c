//! Predefines called as runtime intrinsics that return their results through `RESULT`
//! parameters (multi-result IEEE and transputer routines), and the bit and comparison predefines
//! lowered inline: REAL32EQ/GT, REAL64EQ/GT, IEEECOMPARE/DIEEECOMPARE, BITCOUNT, BITREVWORD and
//! BITREVNBITS.

use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::{InstBuilder, Value, types};
use occ_compiler::predefined::PredefinedId as P;
use occ_runtime::abi::word_offset;
use occ_runtime::intrinsic::{Intrinsic, ParamKind};

use super::{Tr, mem};

impl Tr<'_, '_> {
    /// Lowers bit or comparison predefine `id` on evaluated arguments `v`, giving `None` when it
    /// is not one of this module's.
    pub fn bits_predefine(&mut self, id: P, v: &[Value]) -> Option<Value> {
        Some(match (id, v) {
            (P::Real32Eq | P::Real64Eq, [x, y]) => self.b.ins().fcmp(FloatCC::Equal, *x, *y),
            (P::Real32Gt | P::Real64Gt, [x, y]) => self.b.ins().fcmp(FloatCC::GreaterThan, *x, *y),
            (P::IeeeCompare | P::DIeeeCompare, [x, y]) => self.ieee_compare(*x, *y),
            (P::BitCount, [w, c]) => {
                let n = self.b.ins().popcnt(*w);
                self.b.ins().iadd(n, *c)
            }
            (P::BitRevWord, [w]) => self.b.ins().bitrev(*w),
            (P::BitRevNBits, [w, n]) => self.bitrev_n(*w, *n),
            _ => return None,
        })
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

    /// Calls predefine intrinsic `i` on the evaluated arguments `v` (its non-`RESULT`
    /// parameters), with a temporary word for each `RESULT` parameter, and loads the results in
    /// order: an INT from the word's low 32 bits, a BOOL from its low byte, a REAL32 or REAL64 at
    /// its address.
    pub fn call_predefine(&mut self, i: &'static Intrinsic, v: &[Value]) -> Vec<Value> {
        let results: Vec<ParamKind> = i
            .params
            .iter()
            .copied()
            .filter(|k| k.is_written())
            .collect();
        let buf = self.frame.alloc_words(results.len().max(1));
        let mut args = Vec::new();
        let (mut vi, mut ri) = (v.iter(), 0);
        for k in i.params {
            if k.is_written() {
                let a = self.local_addr(buf + word_offset(ri));
                args.push(a);
                ri += 1;
                continue;
            }
            let Some(&x) = vi.next() else { break };
            let x = match k {
                ParamKind::ValInt if self.b.func.dfg.value_type(x) != types::I64 => {
                    self.b.ins().sextend(types::I64, x)
                }
                _ => x,
            };
            args.push(x);
        }
        let id = self.cx.jit.intrinsics[i.name];
        let f = self.func_ref(id);
        self.b.ins().call(f, &args);
        let base = self.local_addr(buf);
        results
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let ty = match r {
                    ParamKind::ResultBool => types::I8,
                    ParamKind::ResultReal32 => types::F32,
                    ParamKind::ResultReal64 => types::F64,
                    _ => types::I32,
                };
                self.b.ins().load(ty, mem(), base, word_offset(k as isize))
            })
            .collect()
    }
}
