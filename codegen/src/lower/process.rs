//! Sequential processes: the translator's one `match` over process kinds, with SEQ, IF, WHILE,
//! CASE, assignment, SKIP/STOP and scopes here; the other families delegate to their modules.

use cranelift_codegen::ir::{Block, InstBuilder, Value, condcodes::IntCC, types};
use cranelift_frontend::Switch;
use occ_compiler::types::Type;
use occ_grammar::ast::{
    CaseOption, Choice, ChoiceKind, Expr, ExprKind, Process, ProcessKind, Replicator, Span,
};
use occ_runtime::ErrorKind;
use occ_runtime::abi::Entry;

use super::{Res, Storage, Tr};
use crate::layout::is_scalar;

impl Tr<'_, '_> {
    /// Lowers process `p`; temporaries it allocates are released afterwards.
    pub fn process(&mut self, p: &Process) -> Res<()> {
        let mark = self.frame.mark();
        self.process_kind(p)?;
        self.frame.release(mark);
        Ok(())
    }

    fn process_kind(&mut self, p: &Process) -> Res<()> {
        match &p.kind {
            ProcessKind::Skip => Ok(()),
            ProcessKind::Stop => {
                self.halt(ErrorKind::Stop, p.span);
                let dead = self.b.create_block();
                self.b.switch_to_block(dead);
                Ok(())
            }
            ProcessKind::Scope { decls, body } => {
                let open = self.vectors.len();
                for d in decls {
                    self.scope_decl(d)?;
                }
                self.process(body)?;
                self.free_vectors(open);
                Ok(())
            }
            ProcessKind::Assign { lhs, rhs } => self.assign(lhs, rhs, p.span),
            ProcessKind::Output { chan, items } => self.output(chan, items, p.span),
            ProcessKind::Input { chan, items } => self.input(chan, items, p.span),
            ProcessKind::CaseInput { chan, variants } => self.case_input(chan, variants, p.span),
            ProcessKind::Extended {
                input,
                during,
                after,
            } => self.extended(input, during, after.as_deref(), p.span),
            ProcessKind::Delay { time, .. } => {
                let t = self.expr(time)?;
                let t = self.b.ins().sextend(types::I64, t);
                self.blocking(Entry::Tin, &[self.node, self.ws, t], p.span)
            }
            ProcessKind::Seq { repl, body } => match repl {
                None => body.iter().try_for_each(|q| self.process(q)),
                Some(r) => {
                    self.replicated(r, p.span, |tr| body.iter().try_for_each(|q| tr.process(q)))
                }
            },
            ProcessKind::If { repl, choices } => {
                let done = self.b.create_block();
                let none = self.b.create_block();
                self.if_choices(repl.as_deref(), choices, done, none, p.span)?;
                self.b.switch_to_block(none);
                self.halt(ErrorKind::IfNoBranch, p.span);
                self.b.switch_to_block(done);
                Ok(())
            }
            ProcessKind::While { cond, body } => self.while_loop(cond, body, p.span),
            ProcessKind::Case { selector, options } => self.case(selector, options, p.span),
            ProcessKind::Call { name, args } => self.call_proc(name, args, p.span),
            ProcessKind::Par { placed: true, .. } => self.placed_par(p),
            ProcessKind::Par {
                pri, repl, body, ..
            } => self.par(*pri, repl.as_deref(), body, p.span),
            ProcessKind::Alt(alt) => self.alt(alt, p.span),
            ProcessKind::Processor { .. } => {
                Err(self.cx.unsupported(p.span, "PLACED PAR / PROCESSOR"))
            }
            ProcessKind::Asm(_) => match self.cx.checked.asm.get(&p.span).cloned() {
                Some(code) => self.asm(&code, p.span),
                None => Err(self.cx.internal(p.span, "an ASM block was not checked")),
            },
        }
    }

    /// Runs `body` for each value of replicator `r` (base FOR count [STEP s]), with a timeslice
    /// poll at the back-edge. The index lives in the frame.
    pub fn replicated(
        &mut self,
        r: &Replicator,
        span: Span,
        body: impl FnOnce(&mut Self) -> Res<()>,
    ) -> Res<()> {
        let (idx_off, left_off) = (self.frame.alloc_word(), self.frame.alloc_word());
        let base = self.expr(&r.base)?;
        let count = self.expr(&r.count)?;
        let counts = self
            .b
            .ins()
            .icmp_imm_s(IntCC::SignedGreaterThanOrEqual, count, 0);
        self.check(counts, ErrorKind::ReplicatorCount, r.count.span);
        let step_off = self.frame.alloc_word();
        let step = match &r.step {
            Some(s) => self.expr(s)?,
            None => self.b.ins().iconst(types::I32, 1),
        };
        let sym = self.cx.symbol(&r.name)?;
        self.cx.env.insert(
            sym,
            Storage::Var {
                depth: self.depth,
                offset: idx_off,
            },
        );
        let a = self.local_addr(idx_off);
        self.store_scalar(base, a);
        let a = self.local_addr(left_off);
        self.store_scalar(count, a);
        let a = self.local_addr(step_off);
        self.store_scalar(step, a);
        let (hidx, head) = self.loop_head(span);
        let exit = self.b.create_block();
        let bodyb = self.b.create_block();
        self.b.ins().jump(head, &[]);
        self.b.switch_to_block(head);
        let a = self.local_addr(left_off);
        let left = self.b.ins().load(types::I32, super::mem(), a, 0);
        let more = self.b.ins().icmp_imm_s(IntCC::SignedGreaterThan, left, 0);
        self.b.ins().brif(more, bodyb, &[], exit, &[]);
        self.b.switch_to_block(bodyb);
        body(self)?;
        let a = self.local_addr(left_off);
        let left = self.b.ins().load(types::I32, super::mem(), a, 0);
        let left = self.b.ins().iadd_imm_s(left, -1);
        self.b.ins().store(super::mem(), left, a, 0);
        let ia = self.local_addr(idx_off);
        let i = self.b.ins().load(types::I32, super::mem(), ia, 0);
        let sa = self.local_addr(step_off);
        let st = self.b.ins().load(types::I32, super::mem(), sa, 0);
        let i = self.b.ins().iadd(i, st);
        self.b.ins().store(super::mem(), i, ia, 0);
        self.poll(hidx, head);
        self.b.switch_to_block(exit);
        Ok(())
    }

    fn while_loop(&mut self, cond: &Expr, body: &Process, span: Span) -> Res<()> {
        let (hidx, head) = self.loop_head(span);
        let bodyb = self.b.create_block();
        let exit = self.b.create_block();
        self.b.ins().jump(head, &[]);
        self.b.switch_to_block(head);
        let c = self.expr(cond)?;
        self.b.ins().brif(c, bodyb, &[], exit, &[]);
        self.b.switch_to_block(bodyb);
        self.process(body)?;
        self.poll(hidx, head);
        self.b.switch_to_block(exit);
        Ok(())
    }

    /// Lowers IF choices: the first true one runs and jumps to `done`; if none is true control
    /// goes to `none`.
    fn if_choices(
        &mut self,
        repl: Option<&Replicator>,
        choices: &[Choice],
        done: Block,
        none: Block,
        span: Span,
    ) -> Res<()> {
        if let Some(r) = repl {
            self.replicated(r, span, |tr| {
                let next = tr.b.create_block();
                tr.if_list(choices, done, next)?;
                tr.b.switch_to_block(next);
                Ok(())
            })?;
            self.b.ins().jump(none, &[]);
            return Ok(());
        }
        let next = self.b.create_block();
        self.if_list(choices, done, next)?;
        self.b.switch_to_block(next);
        self.b.ins().jump(none, &[]);
        Ok(())
    }

    fn if_list(&mut self, choices: &[Choice], done: Block, none: Block) -> Res<()> {
        for ch in choices {
            let mark = self.frame.mark();
            for d in &ch.decls {
                self.decl(d)?;
            }
            let next = self.b.create_block();
            match &ch.kind {
                ChoiceKind::Guarded { cond, body } => {
                    let c = self.expr(cond)?;
                    let run = self.b.create_block();
                    self.b.ins().brif(c, run, &[], next, &[]);
                    self.b.switch_to_block(run);
                    self.process(body)?;
                    self.b.ins().jump(done, &[]);
                }
                ChoiceKind::Nested(p) => {
                    let ProcessKind::If { repl, choices } = &p.kind else {
                        return Err(self.cx.internal(p.span, "nested choice is not an IF"));
                    };
                    self.if_choices(repl.as_deref(), choices, done, next, p.span)?;
                }
            }
            self.b.switch_to_block(next);
            self.frame.release(mark);
        }
        self.b.ins().jump(none, &[]);
        let dead = self.b.create_block();
        self.b.switch_to_block(dead);
        Ok(())
    }

    fn case(&mut self, selector: &Expr, options: &[CaseOption], span: Span) -> Res<()> {
        let v = self.expr(selector)?;
        let v = self.widen_i64(v, selector);
        let done = self.b.create_block();
        let mut sw = Switch::new();
        let mut default = None;
        let mut bodies = Vec::new();
        for opt in options {
            let blk = self.b.create_block();
            match &opt.values {
                None => default = Some(blk),
                Some(vals) => {
                    for e in vals {
                        let c = self.case_const(e)?;
                        sw.set_entry(c as u64 as u128, blk);
                    }
                }
            }
            bodies.push((blk, opt));
        }
        let nomatch = self.b.create_block();
        sw.emit(&mut self.b, v, default.unwrap_or(nomatch));
        for (blk, opt) in bodies {
            self.b.switch_to_block(blk);
            let mark = self.frame.mark();
            for d in &opt.decls {
                self.decl(d)?;
            }
            self.process(&opt.body)?;
            self.frame.release(mark);
            self.b.ins().jump(done, &[]);
        }
        self.b.switch_to_block(nomatch);
        self.halt(ErrorKind::CaseNoMatch, span);
        self.b.switch_to_block(done);
        Ok(())
    }

    fn case_const(&self, e: &Expr) -> Res<i64> {
        match self.cx.checked.constants.get(&e.span) {
            Some(occ_compiler::consteval::Value::Int(i)) => Ok(*i),
            Some(occ_compiler::consteval::Value::Bool(b)) => Ok(i64::from(*b)),
            _ => Err(self.cx.internal(e.span, "CASE option is not a constant")),
        }
    }

    fn assign(&mut self, lhs: &[Expr], rhs: &[Expr], span: Span) -> Res<()> {
        if lhs.len() == 1 && rhs.len() == 1 {
            // The value first: it may call a PROC (in a VALOF), after which only values
            // computed later may be used.
            let ty = self
                .cx
                .type_of(&lhs[0])
                .or_else(|_| self.cx.type_of(&rhs[0]))?;
            if let Some(p) = self.cx.checked.types.prim(&ty) {
                let v = self.expr(&rhs[0])?;
                let v = self.coerce(v, crate::layout::cl_type(p));
                let l = self.place(&lhs[0])?;
                self.store_scalar(v, l.addr);
                return Ok(());
            }
            let src = self.value_loc(&rhs[0])?;
            let size = self.loc_size(&src, span)?;
            let l = self.place(&lhs[0])?;
            let dims = self.open_dims(&l);
            if !dims.is_empty() {
                let dst = self.loc_size(&l, span)?;
                let ok = self.b.ins().icmp(IntCC::Equal, size, dst);
                self.check(ok, ErrorKind::Segment, span);
            }
            self.copy_bytes(l.addr, src.addr, size);
            return Ok(());
        }
        // Multiple assignment: evaluate every value first, then store.
        let vals: Vec<(Value, Type)> = if rhs.len() == 1 && lhs.len() > 1 {
            let vs = match &rhs[0].kind {
                ExprKind::Call { name, args } => self.call_function(name, args, span)?,
                ExprKind::Valof(v) => self.valof(v)?,
                _ => return Err(self.cx.internal(span, "multiple assignment from one value")),
            };
            vs.into_iter().map(|v| (v, Type::Error)).collect()
        } else {
            let mut out = Vec::new();
            for e in rhs {
                let ty = self.cx.type_of(e)?;
                if is_scalar(&self.cx.checked.types, &ty) {
                    out.push((self.expr(e)?, ty));
                } else {
                    let src = self.value_loc(e)?;
                    let size = self.loc_size(&src, e.span)?;
                    let off = self
                        .frame
                        .alloc(crate::layout::size_of(&self.cx.checked.types, &ty).unwrap_or(0));
                    let tmp = self.local_addr(off);
                    self.copy_bytes(tmp, src.addr, size);
                    out.push((tmp, ty));
                }
            }
            out
        };
        for (l, (v, ty)) in lhs.iter().zip(vals) {
            let dst = self.place(l)?;
            if let Some(p) = self.cx.checked.types.prim(&dst.ty) {
                let v = self.coerce(v, crate::layout::cl_type(p));
                self.store_scalar(v, dst.addr);
            } else {
                let size = self.loc_size(&dst, span)?;
                let _ = ty;
                self.copy_bytes(dst.addr, v, size);
            }
        }
        Ok(())
    }

    /// The dimension lengths of `l` when its type has an open dimension (for length checks).
    pub fn open_dims(&self, l: &super::Loc) -> Vec<Value> {
        if crate::layout::size_of(&self.cx.checked.types, &l.ty).is_some() {
            Vec::new()
        } else {
            l.dims.clone()
        }
    }
}
