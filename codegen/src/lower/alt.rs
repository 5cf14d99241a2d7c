//! ALT and PRI ALT: enable every guard (channel, timer, SKIP, each with its boolean), wait,
//! disable in priority order (PRI ALT: textual; ALT: rotating from a per-site counter, for
//! fairness), then run the selected branch. Nested ALTs are flattened; a replicated ALT enables
//! and disables in loops, its branch number carrying the replication index.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_frontend::Switch;
use occ_grammar::ast::{Alt, AltKind, Alternative, Expr, ProcessKind, Replicator, Span};

use super::{Res, Tr, mem};

/// One guard group: a single alternative, or a replicated one.
enum Group<'a> {
    Single(&'a Alternative),
    Repl(&'a Replicator, &'a Alternative),
}

/// The shape of a guard.
enum Guard<'a> {
    Chan(&'a Expr),
    Timer(&'a Expr),
    Skip,
}

fn flatten<'a>(alt: &'a Alt, out: &mut Vec<Group<'a>>) -> Result<(), Span> {
    for a in &alt.alternatives {
        match (&alt.repl, &a.kind) {
            (Some(r), AltKind::Nested(inner)) if inner.repl.is_none() => {
                // A plain ALT inside a replicated one: each of its guards is replicated.
                for ia in &inner.alternatives {
                    if matches!(ia.kind, AltKind::Nested(_)) {
                        return Err(ia.span);
                    }
                    out.push(Group::Repl(r, ia));
                }
            }
            (Some(_), AltKind::Nested(_)) => return Err(a.span),
            (Some(r), _) => out.push(Group::Repl(r, a)),
            (None, AltKind::Nested(inner)) => flatten(inner, out)?,
            (None, _) => out.push(Group::Single(a)),
        }
    }
    Ok(())
}

fn cond_of(a: &Alternative) -> Option<&Expr> {
    match &a.kind {
        AltKind::Guarded { cond, .. } | AltKind::CaseInput { cond, .. } => cond.as_ref(),
        AltKind::Nested(_) => None,
    }
}

fn guard_of(a: &Alternative) -> Option<Guard<'_>> {
    match &a.kind {
        AltKind::Guarded { guard, .. } => match &guard.kind {
            ProcessKind::Input { chan, .. } | ProcessKind::CaseInput { chan, .. } => {
                Some(Guard::Chan(chan))
            }
            ProcessKind::Delay { time, .. } => Some(Guard::Timer(time)),
            ProcessKind::Skip => Some(Guard::Skip),
            _ => None,
        },
        AltKind::CaseInput { chan, .. } => Some(Guard::Chan(chan)),
        AltKind::Nested(_) => None,
    }
}

impl Tr<'_, '_> {
    /// Lowers an ALT or PRI ALT.
    pub fn alt(&mut self, alt: &Alt, span: Span) -> Res<()> {
        let mut groups = Vec::new();
        flatten(alt, &mut groups)
            .map_err(|s| self.cx.unsupported(s, "this nesting of replicated ALTs"))?;
        let timed = groups.iter().any(|g| {
            let (Group::Single(a) | Group::Repl(_, a)) = g;
            matches!(guard_of(a), Some(Guard::Timer(_)))
        });
        // Declarations before single alternatives scope over the whole ALT.
        self.alt_decls(alt)?;
        let start = if timed { "rt_talt" } else { "rt_alt" };
        self.call_rt(start, &[self.node, self.ws]);
        self.no_poll += 1;
        for (gi, g) in groups.iter().enumerate() {
            self.group(g, gi, true, span)?;
        }
        self.no_poll -= 1;
        let wait = if timed { "rt_taltwt" } else { "rt_altwt" };
        self.blocking(wait, &[self.node, self.ws], span)?;
        self.no_poll += 1;
        self.disable_all(&groups, alt.pri, span)?;
        self.no_poll -= 1;
        let sel = self.call_rt("rt_altend", &[self.node, self.ws]);
        self.run_selected(&groups, sel, span)
    }

    /// Lowers the declarations before the alternatives of an unreplicated ALT (and of the ALTs
    /// nested in it); they scope over the whole ALT.
    fn alt_decls(&mut self, alt: &Alt) -> Res<()> {
        if alt.repl.is_some() {
            return Ok(());
        }
        for a in &alt.alternatives {
            for d in &a.decls {
                self.decl(d)?;
            }
            if let AltKind::Nested(inner) = &a.kind {
                self.alt_decls(inner)?;
            }
        }
        Ok(())
    }

    fn disable_all(&mut self, groups: &[Group<'_>], pri: bool, span: Span) -> Res<()> {
        if pri || groups.len() < 2 {
            for (gi, g) in groups.iter().enumerate() {
                self.group(g, gi, false, span)?;
            }
            return Ok(());
        }
        // Fairness: start disabling at a rotating group.
        let cell = self.cx.intern(vec![0u8; 8]);
        let cell = self.iconst(cell);
        let c = self.b.ins().load(types::I64, mem(), cell, 0);
        let c1 = self.b.ins().iadd_imm_s(c, 1);
        self.b.ins().store(mem(), c1, cell, 0);
        let n = groups.len() as i64;
        let first = self.b.ins().urem_imm_s(c, n);
        let off = self.frame.alloc(8);
        let a = self.local_addr(off);
        self.b.ins().store(mem(), first, a, 0);
        for pass in 0..2 {
            for (gi, g) in groups.iter().enumerate() {
                let a = self.local_addr(off);
                let first = self.b.ins().load(types::I64, mem(), a, 0);
                let cc = if pass == 0 {
                    IntCC::SignedLessThanOrEqual
                } else {
                    IntCC::SignedGreaterThan
                };
                let gv = self.iconst(gi as i64);
                let take = self.b.ins().icmp(cc, first, gv);
                let yes = self.b.create_block();
                let next = self.b.create_block();
                self.b.ins().brif(take, yes, &[], next, &[]);
                self.b.switch_to_block(yes);
                self.group(g, gi, false, span)?;
                self.b.ins().jump(next, &[]);
                self.b.switch_to_block(next);
            }
        }
        Ok(())
    }

    /// Enables (`enable`) or disables one guard group; group `gi`'s branch numbers are
    /// `gi << 32 | k` for replication `k`.
    fn group(&mut self, g: &Group<'_>, gi: usize, enable: bool, span: Span) -> Res<()> {
        let tag = (gi as i64) << 32;
        match g {
            Group::Single(a) => {
                let br = self.iconst(tag);
                self.guard(a, br, enable)
            }
            Group::Repl(r, a) => {
                let a = *a;
                let k_off = self.frame.alloc(8);
                let ka = self.local_addr(k_off);
                let zero = self.iconst(0);
                self.b.ins().store(mem(), zero, ka, 0);
                self.replicated(r, span, |tr| {
                    for d in &a.decls {
                        tr.decl(d)?;
                    }
                    let ka = tr.local_addr(k_off);
                    let k = tr.b.ins().load(types::I64, mem(), ka, 0);
                    let br = tr.b.ins().iadd_imm_s(k, tag);
                    tr.guard(a, br, enable)?;
                    let ka = tr.local_addr(k_off);
                    let k = tr.b.ins().load(types::I64, mem(), ka, 0);
                    let k = tr.b.ins().iadd_imm_s(k, 1);
                    tr.b.ins().store(mem(), k, ka, 0);
                    Ok(())
                })
            }
        }
    }

    fn guard(&mut self, a: &Alternative, branch: Value, enable: bool) -> Res<()> {
        let cond = match cond_of(a) {
            Some(c) => {
                let v = self.expr(c)?;
                self.b.ins().uextend(types::I64, v)
            }
            None => self.iconst(1),
        };
        let g = guard_of(a).ok_or_else(|| self.cx.unsupported(a.span, "this ALT guard"))?;
        let (n, w) = (self.node, self.ws);
        match (g, enable) {
            (Guard::Chan(c), true) => {
                let ch = self.place(c)?.addr;
                self.call_rt("rt_enbc", &[n, w, cond, ch]);
            }
            (Guard::Chan(c), false) => {
                let ch = self.place(c)?.addr;
                self.call_rt("rt_disc", &[n, w, cond, ch, branch]);
            }
            (Guard::Timer(t), en) => {
                let v = self.expr(t)?;
                let v = self.b.ins().sextend(types::I64, v);
                if en {
                    self.call_rt("rt_enbt", &[n, w, cond, v]);
                } else {
                    self.call_rt("rt_dist", &[n, w, cond, v, branch]);
                }
            }
            (Guard::Skip, true) => {
                self.call_rt("rt_enbs", &[n, w, cond]);
            }
            (Guard::Skip, false) => {
                self.call_rt("rt_diss", &[n, w, cond, branch]);
            }
        }
        Ok(())
    }

    fn run_selected(&mut self, groups: &[Group<'_>], sel: Value, span: Span) -> Res<()> {
        let sel_off = self.frame.alloc(8);
        let a = self.local_addr(sel_off);
        self.b.ins().store(mem(), sel, a, 0);
        let gsel = self.b.ins().sshr_imm_s(sel, 32);
        let done = self.b.create_block();
        let none = self.b.create_block();
        let mut sw = Switch::new();
        let blocks: Vec<_> = groups.iter().map(|_| self.b.create_block()).collect();
        for (i, b) in blocks.iter().enumerate() {
            sw.set_entry(i as u128, *b);
        }
        sw.emit(&mut self.b, gsel, none);
        for (g, blk) in groups.iter().zip(blocks) {
            self.b.switch_to_block(blk);
            let mark = self.frame.mark();
            let a = match g {
                Group::Single(a) => a,
                Group::Repl(r, a) => {
                    // Set the index to base + k * step.
                    let sa = self.local_addr(sel_off);
                    let s = self.b.ins().load(types::I64, mem(), sa, 0);
                    let k = self.b.ins().ireduce(types::I32, s);
                    let base = self.expr(&r.base)?;
                    let step = match &r.step {
                        Some(st) => self.expr(st)?,
                        None => self.b.ins().iconst(types::I32, 1),
                    };
                    let ks = self.b.ins().imul(k, step);
                    let idx = self.b.ins().iadd(base, ks);
                    let off = self.frame.alloc(8);
                    let ia = self.local_addr(off);
                    self.store_scalar(idx, ia);
                    let sym = self.cx.symbol(&r.name)?;
                    self.cx.env.insert(
                        sym,
                        super::Storage::Var {
                            depth: self.depth,
                            offset: off,
                        },
                    );
                    for d in &a.decls {
                        self.decl(d)?;
                    }
                    a
                }
            };
            self.run_alternative(a)?;
            self.frame.release(mark);
            self.b.ins().jump(done, &[]);
        }
        self.b.switch_to_block(none);
        self.halt(occ_runtime::ErrorKind::Stop, span);
        self.b.switch_to_block(done);
        Ok(())
    }

    fn run_alternative(&mut self, a: &Alternative) -> Res<()> {
        match &a.kind {
            AltKind::Guarded { guard, body, .. } => {
                if let ProcessKind::Input { .. } | ProcessKind::CaseInput { .. } = &guard.kind {
                    self.process(guard)?;
                }
                self.process(body)
            }
            AltKind::CaseInput { chan, variants, .. } => self.case_input(chan, variants, a.span),
            AltKind::Nested(_) => Err(self.cx.internal(a.span, "nested ALT not flattened")),
        }
    }
}
