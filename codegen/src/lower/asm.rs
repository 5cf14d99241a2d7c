//! `ASM` and `GUY` blocks (see `occ_compiler::checked::AsmCode` for the instructions and the
//! address model).
//!
//! The evaluation stack is three Cranelift variables (A, B, C) of 64 bits holding word values
//! sign-extended (INT64 and REAL64 loads keep all 64 bits); every block starts with them 0, so
//! popping an empty stack gives 0, and a push onto a full one loses C. Labels are blocks; `J`
//! and `CJ` branch to them (`CJ` jumps when A is 0, leaving the stack as it is, and pops A when
//! it does not), and a backward `J` polls for a timeslice as a loop's back-edge does.
//! `OUTWORD` and `CALL` of a PROC are blocking points: nothing is kept in the variables across
//! them (the transputer's stack is undefined after them too), so they read 0 afterwards.
//!
//! An address is an INT: its byte offset from the node's address base (`ADDR_BASE_OFFSET`),
//! checked to fit 32 bits when a pointer becomes one; every read or write through an address
//! is checked to fall in the node's workspace memory (`ADDR_LIMITS_OFFSET`), so a wild address
//! is a run-time error rather than an access outside the node.
//!
//! Numbered workspace slots are 32-bit words of an area of the frame (reserved when the
//! function starts for all the blocks in it: `RESERVELOWWS` words below the area's Wptr, the
//! highest slot used above it), so no `LDL`/`STL`/`LDLP` slot reaches memory the process does
//! not own. Constants, tables and the program's `BYTE`/`WORD` image are copied into frame
//! temporaries when their address is taken.

use cranelift_codegen::ir::{Block, InstBuilder, MemFlagsData, Value, condcodes::IntCC, types};
use cranelift_frontend::Variable;
use occ_compiler::checked::{AsmCode, AsmOp, SymbolId};
use occ_compiler::types::{Prim, Type};
use occ_grammar::ast::{Expr, ExprKind, Span};
use occ_runtime::ErrorKind;
use occ_runtime::abi::{ADDR_BASE_OFFSET, ADDR_LIMITS_OFFSET, Entry};

use super::{Res, Storage, Tr, mem};
use crate::layout::{cl_type, is_scalar};

/// Bytes of an ASM word (`TARGET.BITS.PER.WORD` is 32).
const ASM_WORD: i64 = 4;

/// The stack registers of the block being lowered.
#[derive(Clone, Copy)]
struct Regs {
    a: Variable,
    b: Variable,
    c: Variable,
}

/// The state of the block being lowered.
struct Lowering {
    r: Regs,
    /// One block per label, and whether it is placed yet (a jump to it is backward).
    labels: Vec<(Block, bool)>,
    /// The byte offset of the block's Wptr in the frame.
    wptr: i32,
    /// The byte offset of the copy of the code image, when `LDPI` needs one.
    image: Option<i32>,
}

impl Lowering {
    /// Label `i`'s block and whether it is placed.
    fn label(&self, i: usize, span: Span, tr: &Tr<'_, '_>) -> Res<(Block, bool)> {
        self.labels
            .get(i)
            .copied()
            .ok_or_else(|| tr.cx.internal(span, "an ASM label out of range"))
    }
}

impl Tr<'_, '_> {
    /// Reserves, for the function whose code is at `span`, the workspace area that the `ASM`
    /// blocks inside it use (the largest any of them needs), so that they all share one Wptr.
    pub fn reserve_asm_area(&mut self, span: Span) {
        let (mut low, mut high) = (0u32, 0u32);
        for (s, code) in &self.cx.checked.asm {
            if s.start >= span.start && s.end <= span.end {
                low = low.max(code.low_words);
                high = high.max(code.high_words);
            }
        }
        if low + high > 0 {
            let off = self.frame.alloc(i64::from(low + high) * ASM_WORD);
            self.asm_area = Some((off + (low as i32) * ASM_WORD as i32, low, high));
        }
    }

    /// Lowers the `ASM` or `GUY` block at `span`.
    pub fn asm(&mut self, code: &AsmCode, span: Span) -> Res<()> {
        let mark = self.frame.mark();
        let wptr = self.asm_wptr(code);
        let image = self.asm_image(code);
        let r = Regs {
            a: self.b.declare_var(types::I64),
            b: self.b.declare_var(types::I64),
            c: self.b.declare_var(types::I64),
        };
        self.clear(r);
        let labels = code
            .ops
            .iter()
            .filter(|o| matches!(o, AsmOp::Label(_)))
            .count();
        let mut st = Lowering {
            r,
            labels: (0..labels)
                .map(|_| (self.b.create_block(), false))
                .collect(),
            wptr,
            image,
        };
        for (i, op) in code.ops.iter().enumerate() {
            let at = code.spans.get(i).copied().unwrap_or(span);
            self.asm_op(op, &mut st, at)?;
        }
        self.frame.release(mark);
        Ok(())
    }

    /// The byte offset of the block's Wptr in the frame: the function's area when it is big
    /// enough, otherwise an area of the block's own.
    fn asm_wptr(&mut self, code: &AsmCode) -> i32 {
        match self.asm_area {
            Some((off, low, high)) if code.low_words <= low && code.high_words <= high => off,
            _ => {
                let (low, high) = (code.low_words, code.high_words);
                let off = self.frame.alloc(i64::from(low + high).max(1) * ASM_WORD);
                off + (low as i32) * ASM_WORD as i32
            }
        }
    }

    /// The frame offset of a copy of the program's code image, when `LDPI` addresses it.
    fn asm_image(&mut self, code: &AsmCode) -> Option<i32> {
        let used = code.ops.iter().any(|o| matches!(o, AsmOp::Ldpi(_)));
        if !used {
            return None;
        }
        let image = self.cx.checked.asm_image.clone();
        let off = self.frame.alloc(image.len() as i64);
        for (i, byte) in image.iter().enumerate() {
            let v = self.b.ins().iconst(types::I8, i64::from(*byte));
            self.b.ins().store(mem(), v, self.ws, off + i as i32);
        }
        Some(off)
    }

    /// Lowers one instruction; `span` is its line.
    fn asm_op(&mut self, op: &AsmOp, st: &mut Lowering, span: Span) -> Res<()> {
        let (r, wptr, image) = (st.r, st.wptr, st.image);
        match op {
            AsmOp::Const(n) => {
                let v = self.iconst(*n);
                self.push(r, v);
            }
            AsmOp::Load(e) => {
                let v = self.asm_load(e)?;
                self.push(r, v);
            }
            AsmOp::Store(e) => {
                let v = self.pop(r);
                self.asm_store(e, v)?;
            }
            AsmOp::Address(e) => {
                let p = self.asm_address(e)?;
                let v = self.int_address(p, span);
                self.push(r, v);
            }
            AsmOp::ProcAddress(sym) => {
                let v = self.iconst(occ_compiler::entity::EntityRef::index(*sym) as i64);
                self.push(r, v);
            }
            AsmOp::Pop => {
                self.pop(r);
            }
            AsmOp::Rev => {
                let (a, b) = (self.b.use_var(r.a), self.b.use_var(r.b));
                self.b.def_var(r.a, b);
                self.b.def_var(r.b, a);
            }
            AsmOp::Label(i) => {
                let label = st.label(*i, span, self)?;
                st.labels[*i].1 = true;
                self.b.ins().jump(label.0, &[]);
                self.b.switch_to_block(label.0);
            }
            AsmOp::Jump(i) => {
                let (target, backward) = st.label(*i, span, self)?;
                self.asm_jump(target, backward, r, span);
            }
            AsmOp::CondJump(i) => {
                let (target, _) = st.label(*i, span, self)?;
                let a = self.b.use_var(r.a);
                let cont = self.b.create_block();
                self.b.ins().brif(a, cont, &[], target, &[]);
                self.b.switch_to_block(cont);
                self.pop(r);
            }
            AsmOp::Ldpi(pos) => {
                let base = image.unwrap_or(0);
                let p = self.b.ins().iadd_imm_s(self.ws, i64::from(base) + pos);
                let p = self.int_address(p, span);
                let a = self.b.use_var(r.a);
                let v = self.b.ins().iadd(p, a);
                let v = self.word(v);
                self.b.def_var(r.a, v);
            }
            AsmOp::Lb => {
                let p = self.use_addr(r.a, 0, 1, span);
                let v = self.b.ins().uload8(types::I64, mem(), p, 0);
                self.b.def_var(r.a, v);
            }
            AsmOp::Adc(n) => {
                let a = self.b.use_var(r.a);
                let a32 = self.word(a);
                let v = self.b.ins().iadd_imm_s(a32, *n);
                let w = self.word(v);
                let ok = self.b.ins().icmp(IntCC::Equal, v, w);
                self.check(ok, ErrorKind::Overflow, span);
                self.b.def_var(r.a, w);
            }
            AsmOp::AdcValue(e) => {
                let x = self.asm_load(e)?;
                let a = self.b.use_var(r.a);
                let a32 = self.word(a);
                let v = self.b.ins().iadd(a32, x);
                let w = self.word(v);
                let ok = self.b.ins().icmp(IntCC::Equal, v, w);
                self.check(ok, ErrorKind::Overflow, span);
                self.b.def_var(r.a, w);
            }
            AsmOp::Ldnl(n) => {
                let p = self.use_addr(r.a, *n * ASM_WORD, ASM_WORD, span);
                let v = self.b.ins().sload32(mem(), p, 0);
                self.b.def_var(r.a, v);
            }
            AsmOp::Stnl(n) => {
                let p = self.use_addr(r.a, *n * ASM_WORD, ASM_WORD, span);
                let b = self.b.use_var(r.b);
                let v = self.b.ins().ireduce(types::I32, b);
                self.b.ins().store(mem(), v, p, 0);
                self.pop(r);
                self.pop(r);
            }
            AsmOp::Wsub => {
                let (a, b) = (self.b.use_var(r.a), self.b.use_var(r.b));
                let b4 = self.b.ins().imul_imm_s(b, ASM_WORD);
                let v = self.b.ins().iadd(a, b4);
                let v = self.word(v);
                self.pop(r);
                self.b.def_var(r.a, v);
            }
            AsmOp::LoadSlot(n) => {
                let off = wptr + (*n * ASM_WORD) as i32;
                let v = self.b.ins().sload32(mem(), self.ws, off);
                self.push(r, v);
            }
            AsmOp::StoreSlot(n) => {
                let v = self.pop(r);
                let v = self.b.ins().ireduce(types::I32, v);
                self.b
                    .ins()
                    .store(mem(), v, self.ws, wptr + (*n * ASM_WORD) as i32);
            }
            AsmOp::SlotAddress(n) => {
                let p = self
                    .b
                    .ins()
                    .iadd_imm_s(self.ws, i64::from(wptr) + *n * ASM_WORD);
                let v = self.int_address(p, span);
                self.push(r, v);
            }
            AsmOp::Outword => self.outword(r, span)?,
            AsmOp::CallProc { sym, skip_link } => self.asm_call_proc(*sym, *skip_link, r, span)?,
            AsmOp::CallFunction(sym) => self.asm_call_function(*sym, r, span)?,
        }
        Ok(())
    }

    fn clear(&mut self, r: Regs) {
        let z = self.iconst(0);
        for v in [r.a, r.b, r.c] {
            self.b.def_var(v, z);
        }
    }

    /// Pushes `v` (an i64): C is lost.
    fn push(&mut self, r: Regs, v: Value) {
        let (a, b) = (self.b.use_var(r.a), self.b.use_var(r.b));
        self.b.def_var(r.c, b);
        self.b.def_var(r.b, a);
        self.b.def_var(r.a, v);
    }

    /// Pops A: B and C move up, C becomes 0.
    fn pop(&mut self, r: Regs) -> Value {
        let (a, b, c) = (
            self.b.use_var(r.a),
            self.b.use_var(r.b),
            self.b.use_var(r.c),
        );
        self.b.def_var(r.a, b);
        self.b.def_var(r.b, c);
        let z = self.iconst(0);
        self.b.def_var(r.c, z);
        a
    }

    /// `v` wrapped to a 32-bit word, sign-extended.
    fn word(&mut self, v: Value) -> Value {
        let w = self.b.ins().ireduce(types::I32, v);
        self.b.ins().sextend(types::I64, w)
    }

    /// The address base of the node.
    fn addr_base(&mut self) -> Value {
        self.b.ins().load(
            types::I64,
            MemFlagsData::trusted(),
            self.node,
            ADDR_BASE_OFFSET,
        )
    }

    /// The INT address of pointer `p`; a run-time error when it does not fit 32 bits.
    pub(super) fn int_address(&mut self, p: Value, span: Span) -> Value {
        let base = self.addr_base();
        let off = self.b.ins().isub(p, base);
        let w = self.word(off);
        let ok = self.b.ins().icmp(IntCC::Equal, off, w);
        self.check(ok, ErrorKind::AddressRange, span);
        w
    }

    /// The pointer `disp` bytes past the INT address in register `v`, checked to be `bytes`
    /// of node memory.
    fn use_addr(&mut self, v: Variable, disp: i64, bytes: i64, span: Span) -> Value {
        let a = self.b.use_var(v);
        self.int_pointer(a, disp, bytes, span)
    }

    /// The pointer `disp` bytes past INT address `v` (of any integer width): a run-time error
    /// unless the `bytes` there are node memory (see `ADDR_LIMITS_OFFSET`).
    pub(super) fn int_pointer(&mut self, v: Value, disp: i64, bytes: i64, span: Span) -> Value {
        let v = match self.b.func.dfg.value_type(v) {
            types::I64 => v,
            _ => self.b.ins().sextend(types::I64, v),
        };
        let w = self.word(v);
        let off = self.b.ins().iadd_imm_s(w, disp);
        let flags = MemFlagsData::trusted();
        let low = self
            .b
            .ins()
            .load(types::I64, flags, self.node, ADDR_LIMITS_OFFSET);
        let high = self
            .b
            .ins()
            .load(types::I64, flags, self.node, ADDR_LIMITS_OFFSET + 8);
        let end = self.b.ins().iadd_imm_s(off, bytes);
        let above = self.b.ins().icmp(IntCC::SignedGreaterThanOrEqual, off, low);
        let below = self.b.ins().icmp(IntCC::SignedLessThanOrEqual, end, high);
        let fast = self.b.ins().band(above, below);
        // Outside the first chunk: the runtime looks through the node's other chunks.
        let slow = self.b.create_block();
        let done = self.b.create_block();
        self.b.append_block_param(done, types::I8);
        self.b.ins().brif(fast, done, &[fast.into()], slow, &[]);
        self.b.set_cold_block(slow);
        self.b.switch_to_block(slow);
        let n = self.iconst(bytes);
        let held = self.call_rt(Entry::AddrOk, &[self.node, off, n]);
        let held = self.b.ins().icmp_imm_s(IntCC::NotEqual, held, 0);
        self.b.ins().jump(done, &[held.into()]);
        self.b.switch_to_block(done);
        let ok = self.b.block_params(done)[0];
        self.check(ok, ErrorKind::AddressRange, span);
        let base = self.addr_base();
        self.b.ins().iadd(base, off)
    }

    /// A backward `J` polls for a timeslice. The stack is empty after it, whether or not the
    /// process was timesliced (a resume point cannot keep it), so a loop that keeps values on
    /// the stack across `J` fails every time, not only when a timeslice lands (on a T800 the
    /// stack is undefined after `J`).
    fn asm_jump(&mut self, target: Block, backward: bool, r: Regs, span: Span) {
        if backward {
            self.clear(r);
            if self.in_expr == 0 && self.no_poll == 0 {
                let (idx, resumed) = self.new_resume(span);
                self.poll(idx, resumed);
                self.b.switch_to_block(resumed);
                self.clear(r);
            }
        }
        self.b.ins().jump(target, &[]);
        let dead = self.b.create_block();
        self.b.switch_to_block(dead);
    }

    /// The value of `e` as a stack word: sign-extended INTs, zero-extended BYTEs and BOOLs,
    /// REALs as their bits; a channel is its address.
    fn asm_load(&mut self, e: &Expr) -> Res<Value> {
        let ty = self.cx.type_of(e)?;
        let ty = self.cx.checked.types.underlying(&ty).clone();
        if matches!(ty, Type::Chan(..)) {
            let p = self.place(e)?.addr;
            return Ok(self.int_address(p, e.span));
        }
        let v = self.expr(e)?;
        Ok(self.widen_word(v, &ty))
    }

    fn widen_word(&mut self, v: Value, ty: &Type) -> Value {
        let vt = self.b.func.dfg.value_type(v);
        match ty {
            Type::Prim(Prim::Bool | Prim::Byte) => self.b.ins().uextend(types::I64, v),
            Type::Prim(Prim::Real32) => {
                let bits = self.b.ins().bitcast(types::I32, MemFlagsData::new(), v);
                self.b.ins().sextend(types::I64, bits)
            }
            Type::Prim(Prim::Real64) => self.b.ins().bitcast(types::I64, MemFlagsData::new(), v),
            _ if vt == types::I64 => v,
            _ => self.b.ins().sextend(types::I64, v),
        }
    }

    /// `v` (a stack word) as a value of primitive `p`.
    fn narrow_word(&mut self, v: Value, p: Prim) -> Value {
        match p {
            Prim::Int64 => v,
            Prim::Real64 => self.b.ins().bitcast(types::F64, MemFlagsData::new(), v),
            Prim::Real32 => {
                let w = self.b.ins().ireduce(types::I32, v);
                self.b.ins().bitcast(types::F32, MemFlagsData::new(), w)
            }
            _ => self.b.ins().ireduce(cl_type(p), v),
        }
    }

    fn asm_store(&mut self, e: &Expr, v: Value) -> Res<()> {
        let l = self.place(e)?;
        let p = self
            .cx
            .checked
            .types
            .prim(&l.ty)
            .ok_or_else(|| self.cx.internal(e.span, "an ASM store into a non-scalar"))?;
        let v = self.narrow_word(v, p);
        self.store_scalar(v, l.addr);
        Ok(())
    }

    /// The address of `e`: a variable's own; a channel's is the address of a word holding the
    /// channel's address (occ21 reaches a channel through a pointer); a constant or table is
    /// copied into a frame temporary first.
    fn asm_address(&mut self, e: &Expr) -> Res<Value> {
        let ty = self.cx.type_of(e)?;
        let ty = self.cx.checked.types.underlying(&ty).clone();
        if matches!(ty, Type::Chan(..)) {
            let c = self.place(e)?.addr;
            let c = self.int_address(c, e.span);
            let c = self.b.ins().ireduce(types::I32, c);
            let off = self.frame.alloc_word();
            self.b.ins().store(mem(), c, self.ws, off);
            return Ok(self.local_addr(off));
        }
        if self.has_storage(e) {
            return Ok(self.place(e)?.addr);
        }
        let l = self.place(e)?;
        let size = crate::layout::size_of(&self.cx.checked.types, &l.ty).ok_or_else(|| {
            self.cx
                .unsupported(e.span, "ADDRESSOF a value of unknown size")
        })?;
        let off = self.frame.alloc(size);
        let dst = self.local_addr(off);
        if is_scalar(&self.cx.checked.types, &l.ty) {
            let v = self.load_scalar(&l.ty, l.addr, e.span)?;
            self.store_scalar(v, dst);
        } else {
            let n = self.iconst(size);
            self.copy_bytes(dst, l.addr, n);
        }
        Ok(dst)
    }

    /// Whether element `e` denotes workspace storage (not a constant).
    fn has_storage(&self, e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Name(n) => self.cx.symbol(n).ok().is_some_and(|s| {
                matches!(
                    self.cx.env.get(&s),
                    Some(Storage::Var { .. } | Storage::Ref { .. })
                )
            }),
            ExprKind::Subscript { base, .. } | ExprKind::Slice { base, .. } => {
                self.has_storage(base)
            }
            _ => false,
        }
    }

    /// `OUTWORD`: the word A on the channel at address B, from a frame temporary.
    fn outword(&mut self, r: Regs, span: Span) -> Res<()> {
        let a = self.b.use_var(r.a);
        let a = self.b.ins().ireduce(types::I32, a);
        let off = self.frame.alloc_word();
        self.b.ins().store(mem(), a, self.ws, off);
        let chan = self.use_addr(r.b, 0, 8, span);
        let data = self.local_addr(off);
        let len = self.iconst(ASM_WORD);
        self.blocking(Entry::Out, &[self.node, self.ws, chan, data, len], span)?;
        self.clear(r);
        Ok(())
    }

    /// The PROC or FUNCTION's parameters' types, in order.
    fn param_prims(&self, sym: SymbolId, span: Span) -> Res<Vec<(Prim, bool)>> {
        let info = self
            .cx
            .checked
            .procs
            .iter()
            .find(|(_, p)| p.symbol == Some(sym))
            .map(|(_, p)| p.clone())
            .ok_or_else(|| self.cx.internal(span, "CALL of an unknown routine"))?;
        info.params
            .iter()
            .map(|p| {
                let s = &self.cx.checked.symbols[*p];
                let by_value = matches!(
                    s.kind,
                    occ_compiler::checked::SymbolKind::Param {
                        mode: occ_grammar::ast::ParamMode::Val,
                        ..
                    }
                );
                let prim = self.cx.checked.types.prim(&s.ty).ok_or_else(|| {
                    self.cx
                        .internal(span, "CALL of a routine with a non-scalar parameter")
                })?;
                Ok((prim, by_value))
            })
            .collect()
    }

    /// The stack values that are the parameters of a CALL (after the dropped static link).
    fn call_values(&mut self, r: Regs, skip: bool, n: usize) -> Vec<Value> {
        let all = [r.a, r.b, r.c].map(|v| self.b.use_var(v));
        all.into_iter().skip(usize::from(skip)).take(n).collect()
    }

    /// `CALL p` of a PROC: A, B, C are its actuals (values, or addresses for reference
    /// parameters), through the frame chain as an ordinary call.
    fn asm_call_proc(&mut self, sym: SymbolId, skip: bool, r: Regs, span: Span) -> Res<()> {
        let Some(Storage::Proc(entry)) = self.cx.env.get(&sym).cloned() else {
            return Err(self
                .cx
                .unsupported(span, "CALL of a PROC that is not compiled code"));
        };
        let prims = self.param_prims(sym, span)?;
        let vals = self.call_values(r, skip, prims.len());
        let mut stores = Vec::new();
        for (((off, by_value), (p, _)), v) in entry.params.iter().zip(&prims).zip(vals) {
            let v = if *by_value {
                self.narrow_word(v, *p)
            } else {
                let bytes = i64::from(p.bytes());
                self.int_pointer(v, 0, bytes, span)
            };
            stores.push((*off, vec![v]));
        }
        self.call_with(&entry, stores, span)?;
        self.clear(r);
        Ok(())
    }

    /// `CALL f` of a FUNCTION: expanded inline with A, B, C as its actuals; the result is
    /// left in A.
    fn asm_call_function(&mut self, sym: SymbolId, r: Regs, span: Span) -> Res<()> {
        let Some(Storage::Function(d)) = self.cx.env.get(&sym).cloned() else {
            return Err(self
                .cx
                .unsupported(span, "CALL of a FUNCTION that is not occam code"));
        };
        let prims = self.param_prims(sym, span)?;
        let vals = self.call_values(r, false, prims.len());
        let vals: Vec<Value> = vals
            .into_iter()
            .zip(&prims)
            .map(|(v, (p, _))| self.narrow_word(v, *p))
            .collect();
        let results = self.expand_function_values(&d, &vals, span)?;
        let result_ty = self
            .cx
            .checked
            .procs
            .iter()
            .find(|(_, p)| p.symbol == Some(sym))
            .and_then(|(_, p)| p.results.first().cloned())
            .unwrap_or(Type::Error);
        let result_ty = self.cx.checked.types.underlying(&result_ty).clone();
        let v = results
            .first()
            .copied()
            .ok_or_else(|| self.cx.internal(span, "a FUNCTION without a result"))?;
        let v = self.widen_word(v, &result_ty);
        self.clear(r);
        self.b.def_var(r.a, v);
        Ok(())
    }
}
