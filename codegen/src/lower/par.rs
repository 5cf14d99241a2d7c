//! PAR, PRI PAR and replicated PAR: each branch is its own resumable function whose workspace is
//! a sub-block of the parent's frame; a two-word join block counts the branches still running.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_module::FuncId;
use occ_grammar::ast::{Process, Replicator, Span};
use occ_runtime::abi::{Entry, WORD_BYTES, frame, join, priority, word_offset};

use occ_grammar::ast::{Expr, ExprKind, ProcessKind};

use super::{ProcEntry, Res, Storage, Tr, mem};
use crate::frame::{FIRST_LOCAL, Frame, HEADER_BYTES, Size};

/// A PAR branch: its own function, or a PROC started directly (the branch is one call).
enum Branch<'a> {
    Func(FuncId, Size),
    Direct(ProcEntry, &'a [Expr]),
}

impl Tr<'_, '_> {
    /// A branch that is exactly one call of a compiled PROC whose reference actuals are all
    /// places: it runs as the PROC itself, saving a frame.
    fn direct<'a>(&self, p: &'a Process) -> Option<(ProcEntry, &'a [Expr])> {
        let ProcessKind::Call { name, args } = &p.kind else {
            return None;
        };
        let sym = self.cx.symbol(name).ok()?;
        let Some(Storage::Proc(e)) = self.cx.env.get(&sym) else {
            return None;
        };
        let places = args.iter().zip(&e.params).all(|(a, (_, by_value))| {
            *by_value
                || matches!(
                    a.kind,
                    ExprKind::Name(_)
                        | ExprKind::Subscript { .. }
                        | ExprKind::Slice { .. }
                        | ExprKind::Directed { .. }
                )
        });
        (places && args.len() == e.params.len()).then(|| (e.clone(), args.as_slice()))
    }

    fn make_branch<'a>(&mut self, p: &'a Process, repl: Option<&Replicator>) -> Res<Branch<'a>> {
        if let Some((e, args)) = self.direct(p) {
            return Ok(Branch::Direct(e, args));
        }
        let (id, size) = self.branch(p, repl)?;
        Ok(Branch::Func(id, size))
    }

    /// Compiles one PAR branch as a function at depth `self.depth + 1`; with a replicator, the
    /// index is the branch's first local. Returns the function and its size.
    fn branch(&mut self, body: &Process, repl: Option<&Replicator>) -> Res<(FuncId, Size)> {
        // The parent stores its own frame as the branch's static link (`prepare_func`).
        let depth = self.depth + 1;
        let mut frame = Frame::default();
        if let Some(r) = repl {
            let off = frame.alloc_word();
            debug_assert_eq!(off, FIRST_LOCAL);
            let sym = self.cx.symbol(&r.name)?;
            self.cx.env.insert(sym, Storage::Var { depth, offset: off });
        }
        self.cx
            .function("par.branch", depth, frame, body.span, |tr| {
                tr.process(body)?;
                let j =
                    tr.b.ins()
                        .load(types::I64, mem(), tr.ws, word_offset(frame::JOIN));
                let st = tr.call_rt(Entry::Endp, &[tr.node, tr.ws, j]);
                tr.ret(st);
                Ok(())
            })
    }

    /// Stores a direct branch's actuals into its frame at byte offset `wptr` (actuals are
    /// evaluated here, in the parent); returns the function to start.
    fn prepare(&mut self, b: &Branch<'_>, wptr: i32) -> Res<FuncId> {
        match b {
            Branch::Func(id, _) => {
                let child = self.local_addr(wptr);
                self.b.ins().store(mem(), self.ws, child, 0);
                Ok(*id)
            }
            Branch::Direct(e, args) => {
                let stores = self.eval_actuals(e, args)?;
                let child = self.local_addr(wptr);
                self.store_actuals(e, child, stores);
                Ok(e.id)
            }
        }
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
        let j = self.local_addr(join_off);
        self.b
            .ins()
            .store(mem(), j, child, word_offset(frame::JOIN));
        let f = self.func_ref(id);
        let code = self.b.ins().func_addr(types::I64, f);
        let zero = self.iconst(0);
        if high {
            let p = self.iconst(priority::HIGH);
            self.blocking(
                Entry::StartpPri,
                &[self.node, self.ws, child, code, zero, p],
                span,
            )
        } else {
            self.blocking(
                Entry::Startp,
                &[self.node, self.ws, child, code, zero],
                span,
            )
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
        let join_off = self.frame.alloc_words(join::WORDS);
        if let Some(r) = repl {
            return self.par_replicated(r, body, join_off, span);
        }
        let j = self.local_addr(join_off);
        let zero = self.iconst(0);
        self.b
            .ins()
            .store(mem(), zero, j, word_offset(join::PARENT));
        let n = self.iconst(body.len() as i64);
        self.b.ins().store(mem(), n, j, word_offset(join::COUNT));
        let mut branches = Vec::new();
        for p in body {
            let b = self.make_branch(p, None)?;
            let size = match &b {
                Branch::Func(_, s) => *s,
                Branch::Direct(e, _) => e.size,
            };
            // The branches run at once: their frames side by side, their vectors together.
            self.frame.hold_vectors(size.vectors);
            let at = self
                .frame
                .alloc(i64::from(HEADER_BYTES) + i64::from(WORD_BYTES) * i64::from(size.words));
            branches.push((b, at + HEADER_BYTES));
        }
        for (i, (b, wptr)) in branches.into_iter().enumerate() {
            let id = self.prepare(&b, wptr)?;
            let child = self.local_addr(wptr);
            self.start(child, id, join_off, pri && i == 0, span)?;
        }
        let j = self.local_addr(join_off);
        self.blocking(Entry::ParWait, &[self.node, self.ws, j], span)
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
        let br = self.make_branch(p, Some(r))?;
        let size = match &br {
            Branch::Func(_, s) => *s,
            Branch::Direct(e, _) => e.size,
        };
        self.frame
            .hold_vectors(size.vectors.saturating_mul(count.max(1)));
        let stride = i64::from(HEADER_BYTES) + i64::from(WORD_BYTES) * i64::from(size.words);
        let area = self.frame.alloc(stride * count.max(1));
        let (k_off, base_off, step_off) = (
            self.frame.alloc_word(),
            self.frame.alloc_word(),
            self.frame.alloc_word(),
        );
        // A direct branch's actuals are evaluated here, with the index in the parent's frame.
        let idx_off = self.frame.alloc_word();
        if let Branch::Direct(..) = br {
            let sym = self.cx.symbol(&r.name)?;
            self.cx.env.insert(
                sym,
                Storage::Var {
                    depth: self.depth,
                    offset: idx_off,
                },
            );
        }
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
        self.b
            .ins()
            .store(mem(), zero, j, word_offset(join::PARENT));
        let n = self.iconst(count);
        self.b.ins().store(mem(), n, j, word_offset(join::COUNT));
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
        let id = match &br {
            Branch::Func(id, _) => {
                self.b.ins().store(mem(), idx, child, FIRST_LOCAL);
                self.b.ins().store(mem(), self.ws, child, 0);
                *id
            }
            Branch::Direct(e, args) => {
                let ia = self.local_addr(idx_off);
                self.store_scalar(idx, ia);
                let stores = self.eval_actuals(e, args)?;
                self.store_actuals(e, child, stores);
                e.id
            }
        };
        self.start(child, id, join_off, false, span)?;
        let ka = self.local_addr(k_off);
        let k = self.b.ins().load(types::I64, mem(), ka, 0);
        let k = self.b.ins().iadd_imm_s(k, 1);
        self.b.ins().store(mem(), k, ka, 0);
        self.b.ins().jump(head, &[]);
        self.b.switch_to_block(exit);
        let j = self.local_addr(join_off);
        self.blocking(Entry::ParWait, &[self.node, self.ws, j], span)
    }
}
