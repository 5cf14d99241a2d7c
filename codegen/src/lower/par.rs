//! PAR, PRI PAR and replicated PAR: each branch is its own resumable function whose workspace is
//! a sub-block of the parent's frame; a two-word join block counts the branches still running.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_module::FuncId;
use occ_grammar::ast::{Process, Replicator, Span};
use occ_runtime::abi::{join, priority};

use super::{Res, Storage, Tr, mem};
use crate::frame::{FIRST_LOCAL, Frame, HEADER_BYTES};

impl Tr<'_, '_> {
    /// Compiles one PAR branch as a function at depth `self.depth + 1`; with a replicator, the
    /// index is the branch's first local. Returns the function and its frame words.
    fn branch(&mut self, body: &Process, repl: Option<&Replicator>) -> Res<(FuncId, u32)> {
        let depth = self.depth + 1;
        let mut frame = Frame::default();
        if let Some(r) = repl {
            let off = frame.alloc(8);
            debug_assert_eq!(off, FIRST_LOCAL);
            let sym = self.cx.symbol(&r.name)?;
            self.cx.env.insert(sym, Storage::Var { depth, offset: off });
        }
        self.cx
            .function("par.branch", depth, frame, body.span, |tr| {
                tr.process(body)?;
                let j = tr.b.ins().load(types::I64, mem(), tr.ws, 8);
                let st = tr.call_rt("rt_endp", &[tr.node, tr.ws, j]);
                tr.ret(st);
                Ok(())
            })
    }

    /// Sets up and starts the branch whose workspace is at `child`.
    fn start(
        &mut self,
        child: Value,
        id: FuncId,
        join_off: i32,
        high: bool,
        span: Span,
    ) -> Res<()> {
        self.b.ins().store(mem(), self.ws, child, 0);
        let j = self.local_addr(join_off);
        self.b.ins().store(mem(), j, child, 8);
        let f = self.func_ref(id);
        let code = self.b.ins().func_addr(types::I64, f);
        let zero = self.iconst(0);
        if high {
            let p = self.iconst(priority::HIGH);
            self.blocking(
                "rt_startp_pri",
                &[self.node, self.ws, child, code, zero, p],
                span,
            )
        } else {
            self.blocking("rt_startp", &[self.node, self.ws, child, code, zero], span)
        }
    }

    /// Lowers a PAR (optionally PRI, optionally replicated).
    pub fn par(
        &mut self,
        pri: bool,
        repl: Option<&Replicator>,
        body: &[Process],
        span: Span,
    ) -> Res<()> {
        let join_off = self.frame.alloc(8 * join::WORDS as i64);
        if let Some(r) = repl {
            return self.par_replicated(r, body, join_off, span);
        }
        let j = self.local_addr(join_off);
        let zero = self.iconst(0);
        self.b.ins().store(mem(), zero, j, 8 * join::PARENT as i32);
        let n = self.iconst(body.len() as i64);
        self.b.ins().store(mem(), n, j, 8 * join::COUNT as i32);
        let mut branches = Vec::new();
        for p in body {
            let (id, words) = self.branch(p, None)?;
            let at = self
                .frame
                .alloc(i64::from(HEADER_BYTES) + 8 * i64::from(words));
            branches.push((id, at + HEADER_BYTES));
        }
        for (i, (id, wptr)) in branches.into_iter().enumerate() {
            let child = self.local_addr(wptr);
            self.start(child, id, join_off, pri && i == 0, span)?;
        }
        let j = self.local_addr(join_off);
        self.blocking("rt_par_wait", &[self.node, self.ws, j], span)
    }

    fn par_replicated(
        &mut self,
        r: &Replicator,
        body: &[Process],
        join_off: i32,
        span: Span,
    ) -> Res<()> {
        let [p] = body else {
            return Err(self.cx.internal(span, "replicated PAR with several bodies"));
        };
        let count = match self.cx.checked.constants.get(&r.count.span) {
            Some(occ_compiler::consteval::Value::Int(n)) => (*n).max(0),
            _ => {
                return Err(self
                    .cx
                    .unsupported(span, "replicated PAR with a variable count"));
            }
        };
        let (id, words) = self.branch(p, Some(r))?;
        let stride = i64::from(HEADER_BYTES) + 8 * i64::from(words);
        let area = self.frame.alloc(stride * count.max(1));
        let (k_off, base_off, step_off) = (
            self.frame.alloc(8),
            self.frame.alloc(8),
            self.frame.alloc(8),
        );
        let base = self.expr(&r.base)?;
        let step = match &r.step {
            Some(s) => self.expr(s)?,
            None => self.b.ins().iconst(types::I32, 1),
        };
        for (off, v) in [(base_off, base), (step_off, step)] {
            let a = self.local_addr(off);
            self.store_scalar(v, a);
        }
        let j = self.local_addr(join_off);
        let zero = self.iconst(0);
        self.b.ins().store(mem(), zero, j, 8 * join::PARENT as i32);
        let n = self.iconst(count);
        self.b.ins().store(mem(), n, j, 8 * join::COUNT as i32);
        let ka = self.local_addr(k_off);
        self.b.ins().store(mem(), zero, ka, 0);
        let head = self.b.create_block();
        let bodyb = self.b.create_block();
        let exit = self.b.create_block();
        self.b.ins().jump(head, &[]);
        self.b.switch_to_block(head);
        let ka = self.local_addr(k_off);
        let k = self.b.ins().load(types::I64, mem(), ka, 0);
        let more = self.b.ins().icmp_imm_s(IntCC::SignedLessThan, k, count);
        self.b.ins().brif(more, bodyb, &[], exit, &[]);
        self.b.switch_to_block(bodyb);
        let off = self.b.ins().imul_imm_s(k, stride);
        let area_addr = self.local_addr(area + HEADER_BYTES);
        let child = self.b.ins().iadd(area_addr, off);
        // The index value: base + k * step.
        let ba = self.local_addr(base_off);
        let base = self.b.ins().load(types::I32, mem(), ba, 0);
        let sa = self.local_addr(step_off);
        let step = self.b.ins().load(types::I32, mem(), sa, 0);
        let k32 = self.b.ins().ireduce(types::I32, k);
        let ks = self.b.ins().imul(k32, step);
        let idx = self.b.ins().iadd(base, ks);
        self.b.ins().store(mem(), idx, child, FIRST_LOCAL);
        self.start(child, id, join_off, false, span)?;
        let ka = self.local_addr(k_off);
        let k = self.b.ins().load(types::I64, mem(), ka, 0);
        let k = self.b.ins().iadd_imm_s(k, 1);
        self.b.ins().store(mem(), k, ka, 0);
        self.b.ins().jump(head, &[]);
        self.b.switch_to_block(exit);
        let j = self.local_addr(join_off);
        self.blocking("rt_par_wait", &[self.node, self.ws, j], span)
    }
}
