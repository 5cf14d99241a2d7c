//! ALT and PRI ALT: enable every guard (channel, timer, SKIP, each with its boolean), wait,
//! disable in priority order (PRI ALT: textual; ALT: rotating from a per-site counter, for
//! fairness), then run the selected branch. Nested ALTs are flattened; a replicated ALT enables
//! and disables in loops, its branch number carrying the replication index.
//!
//! Fast path: an ALT whose guards are all unconditional inputs on channels first reads the
//! channel words, in the order disabling would take them. The first holding a waiting outputter
//! (a plain process word) is selected at once, with no enabling, waiting or disabling; an empty
//! word is passed over; a word the poll cannot judge (an endpoint, such as the keyboard
//! or a link, which may hold data) sends the ALT to the protocol at once, so that it is never
//! passed over for a later guard. A guard ready when the ALT starts may always be selected, so
//! this changes no outcome the T800 protocol allows; when no guard is ready, the protocol runs.

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_frontend::Switch;
use occ_grammar::ast::{Alt, AltKind, Alternative, Expr, ProcessKind, Replicator, Span};

use occ_runtime::abi::{Entry, NOT_PROCESS, WORD_BYTES, tag};

use super::{Res, Storage, Tr, mem};

/// One level of replication around a guard: the replicator and the declarations to lower
/// once its index is set.
#[derive(Clone)]
struct Level<'a> {
    repl: &'a Replicator,
    decls: Vec<&'a occ_grammar::ast::Decl>,
}

/// One guard group: a single alternative, or one inside (nested) replicated ALTs.
enum Group<'a> {
    Single(&'a Alternative),
    Repl(Vec<Level<'a>>, &'a Alternative),
}

/// The shape of a guard.
enum Guard<'a> {
    Chan(&'a Expr),
    Timer(&'a Expr),
    Skip,
}

fn flatten<'a>(alt: &'a Alt, prefix: &[Level<'a>], out: &mut Vec<Group<'a>>) {
    for a in &alt.alternatives {
        let mut levels = prefix.to_vec();
        if let Some(r) = &alt.repl {
            levels.push(Level {
                repl: r,
                decls: Vec::new(),
            });
        }
        match &a.kind {
            AltKind::Nested(inner) => {
                // Declarations before a nested ALT: at top level they are lowered once
                // (`alt_decls`); inside a replication, once per index.
                if let Some(last) = levels.last_mut() {
                    last.decls.extend(a.decls.iter());
                }
                flatten(inner, &levels, out);
            }
            _ if levels.is_empty() => out.push(Group::Single(a)),
            _ => out.push(Group::Repl(levels, a)),
        }
    }
}

/// True when every guard is an unconditional input on a channel, outside any replication: the
/// ALTs the fast path serves.
fn plain_inputs(groups: &[Group<'_>]) -> bool {
    groups.iter().all(|g| {
        matches!(g, Group::Single(a)
            if cond_of(a).is_none() && matches!(guard_of(a), Some(Guard::Chan(_))))
    })
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
            ProcessKind::Extended { input, .. } => match &input.kind {
                ProcessKind::Input { chan, .. } | ProcessKind::CaseInput { chan, .. } => {
                    Some(Guard::Chan(chan))
                }
                _ => None,
            },
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
        flatten(alt, &[], &mut groups);
        // Where a replicated guard's indices are saved when it is selected.
        let saved: Vec<Vec<i32>> = groups
            .iter()
            .map(|g| match g {
                Group::Single(_) => Vec::new(),
                Group::Repl(levels, _) => levels.iter().map(|_| self.frame.alloc_word()).collect(),
            })
            .collect();
        let timed = groups.iter().any(|g| {
            let (Group::Single(a) | Group::Repl(_, a)) = g;
            matches!(guard_of(a), Some(Guard::Timer(_)))
        });
        // Declarations before single alternatives scope over the whole ALT.
        self.alt_decls(alt)?;
        let selected = self.b.create_block();
        self.b.append_block_param(selected, types::I64);
        // One rotation start for the poll and for disabling (plain ALT only).
        let rotation = self.rotation_start(groups.len(), alt.pri);
        if plain_inputs(&groups) {
            let protocol = self.b.create_block();
            self.poll_ready(&groups, rotation, selected, protocol)?;
            self.b.ins().jump(protocol, &[]);
            self.b.switch_to_block(protocol);
        }
        let start = if timed { Entry::Talt } else { Entry::Alt };
        self.call_rt(start, &[self.node, self.ws]);
        self.no_poll += 1;
        for (gi, g) in groups.iter().enumerate() {
            self.group(g, gi, None, span)?;
        }
        self.no_poll -= 1;
        let wait = if timed { Entry::Taltwt } else { Entry::Altwt };
        self.blocking(wait, &[self.node, self.ws], span)?;
        self.no_poll += 1;
        self.disable_all(&groups, &saved, rotation, span)?;
        self.no_poll -= 1;
        let sel = self.call_rt(Entry::Altend, &[self.node, self.ws]);
        self.b.ins().jump(selected, &[sel.into()]);
        self.b.switch_to_block(selected);
        let sel = self.b.block_params(selected)[0];
        self.run_selected(&groups, &saved, sel, span)
    }

    /// The fast path: reads each guard's channel word in disabling order and jumps to
    /// `selected` with the first ready guard's branch number, or to `protocol` at the first word
    /// holding an endpoint or an ALT tag; falls through when every word is empty.
    fn poll_ready(
        &mut self,
        groups: &[Group<'_>],
        rotation: Option<i32>,
        selected: cranelift_codegen::ir::Block,
        protocol: cranelift_codegen::ir::Block,
    ) -> Res<()> {
        self.in_order(groups.len(), rotation, |tr, gi| {
            let (Group::Single(a) | Group::Repl(_, a)) = &groups[gi];
            let Some(Guard::Chan(c)) = guard_of(a) else {
                return Err(tr
                    .cx
                    .internal(a.span, "poll of a guard that is not an input"));
            };
            let ch = tr.place(c)?.addr;
            let w = tr.b.ins().load(types::I64, mem(), ch, 0);
            let (occupied, next) = (tr.b.create_block(), tr.b.create_block());
            let waiting = tr.b.ins().icmp_imm_u(IntCC::NotEqual, w, NOT_PROCESS);
            tr.b.ins().brif(waiting, occupied, &[], next, &[]);
            tr.b.switch_to_block(occupied);
            let special = tr.b.ins().band_imm_u(w, tag::ENDPOINT | tag::ALT);
            let plain = tr.b.ins().icmp_imm_u(IntCC::Equal, special, 0);
            let branch = tr.iconst((gi as i64) << 32);
            tr.b.ins()
                .brif(plain, selected, &[branch.into()], protocol, &[]);
            tr.b.switch_to_block(next);
            Ok(())
        })
    }

    /// For a plain ALT of several groups, draws where this execution's disabling order starts
    /// from a per-site counter that advances at every execution, so that no guard is favoured
    /// for ever, and returns the frame slot holding it; `None` for a PRI ALT or a single group
    /// (textual order).
    fn rotation_start(&mut self, n: usize, pri: bool) -> Option<i32> {
        if pri || n < 2 {
            return None;
        }
        let cell = self.cx.intern(vec![0u8; WORD_BYTES as usize]);
        let cell = self.iconst(cell);
        let c = self.b.ins().load(types::I64, mem(), cell, 0);
        let c1 = self.b.ins().iadd_imm_s(c, 1);
        self.b.ins().store(mem(), c1, cell, 0);
        let first = self.b.ins().urem_imm_s(c, n as i64);
        let off = self.frame.alloc_word();
        let a = self.local_addr(off);
        self.b.ins().store(mem(), first, a, 0);
        Some(off)
    }

    /// Emits `emit(gi)` for each of `n` guard groups in disabling order: textual without a
    /// rotation, otherwise from the group in the `rotation` slot round to the one before it.
    fn in_order(
        &mut self,
        n: usize,
        rotation: Option<i32>,
        mut emit: impl FnMut(&mut Self, usize) -> Res<()>,
    ) -> Res<()> {
        let Some(off) = rotation else {
            return (0..n).try_for_each(|gi| emit(self, gi));
        };
        for pass in 0..2 {
            for gi in 0..n {
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
                emit(self, gi)?;
                self.b.ins().jump(next, &[]);
                self.b.switch_to_block(next);
            }
        }
        Ok(())
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

    fn disable_all(
        &mut self,
        groups: &[Group<'_>],
        saved: &[Vec<i32>],
        rotation: Option<i32>,
        span: Span,
    ) -> Res<()> {
        self.in_order(groups.len(), rotation, |tr, gi| {
            tr.group(&groups[gi], gi, Some(&saved[gi]), span)
        })
    }

    /// Enables (`save` is `None`) or disables one guard group; group `gi`'s branch number is
    /// `gi << 32`. When disabling selects a replicated guard, its indices are saved in `save`.
    fn group(&mut self, g: &Group<'_>, gi: usize, save: Option<&[i32]>, span: Span) -> Res<()> {
        let tag = (gi as i64) << 32;
        match g {
            Group::Single(a) => {
                let br = self.iconst(tag);
                self.guard(a, br, save.is_none())?;
                Ok(())
            }
            Group::Repl(levels, a) => self.levels(levels, 0, a, tag, save, span),
        }
    }

    fn levels(
        &mut self,
        levels: &[Level<'_>],
        at: usize,
        a: &Alternative,
        tag: i64,
        save: Option<&[i32]>,
        span: Span,
    ) -> Res<()> {
        let Some(level) = levels.get(at) else {
            for d in &a.decls {
                self.decl(d)?;
            }
            let br = self.iconst(tag);
            let hit = self.guard(a, br, save.is_none())?;
            if let (Some(slots), Some(hit)) = (save, hit) {
                let yes = self.b.create_block();
                let next = self.b.create_block();
                self.b.ins().brif(hit, yes, &[], next, &[]);
                self.b.switch_to_block(yes);
                for (l, off) in levels.iter().zip(slots) {
                    let sym = self.cx.symbol(&l.repl.name)?;
                    let Some(Storage::Var { depth, offset }) = self.cx.env.get(&sym).cloned()
                    else {
                        return Err(self.cx.internal(span, "replicator without storage"));
                    };
                    let f = self.frame_at(depth);
                    let v = self.b.ins().load(types::I32, mem(), f, offset);
                    let dst = self.local_addr(*off);
                    self.b.ins().store(mem(), v, dst, 0);
                }
                self.b.ins().jump(next, &[]);
                self.b.switch_to_block(next);
            }
            return Ok(());
        };
        self.replicated(level.repl, span, |tr| {
            for d in &level.decls {
                tr.decl(d)?;
            }
            tr.levels(levels, at + 1, a, tag, save, span)
        })
    }

    fn guard(&mut self, a: &Alternative, branch: Value, enable: bool) -> Res<Option<Value>> {
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
            (Guard::Chan(c), en) => {
                // A false boolean guard does not evaluate (or range-check) its channel.
                let yes = self.b.create_block();
                let done = self.b.create_block();
                self.b.append_block_param(done, types::I64);
                let zero = self.iconst(0);
                self.b.ins().brif(cond, yes, &[], done, &[zero.into()]);
                self.b.switch_to_block(yes);
                let ch = self.place(c)?.addr;
                let r = if en {
                    self.call_rt(Entry::Enbc, &[n, w, cond, ch]);
                    self.iconst(0)
                } else {
                    self.call_rt(Entry::Disc, &[n, w, cond, ch, branch])
                };
                self.b.ins().jump(done, &[r.into()]);
                self.b.switch_to_block(done);
                let r = self.b.block_params(done)[0];
                return Ok((!en).then_some(r));
            }
            (Guard::Timer(t), en) => {
                let v = self.expr(t)?;
                let v = self.b.ins().sextend(types::I64, v);
                if en {
                    self.call_rt(Entry::Enbt, &[n, w, cond, v]);
                } else {
                    return Ok(Some(self.call_rt(Entry::Dist, &[n, w, cond, v, branch])));
                }
            }
            (Guard::Skip, true) => {
                self.call_rt(Entry::Enbs, &[n, w, cond]);
            }
            (Guard::Skip, false) => {
                return Ok(Some(self.call_rt(Entry::Diss, &[n, w, cond, branch])));
            }
        }
        Ok(None)
    }

    fn run_selected(
        &mut self,
        groups: &[Group<'_>],
        saved: &[Vec<i32>],
        sel: Value,
        span: Span,
    ) -> Res<()> {
        let gsel = self.b.ins().sshr_imm_s(sel, 32);
        let done = self.b.create_block();
        let none = self.b.create_block();
        let mut sw = Switch::new();
        let blocks: Vec<_> = groups.iter().map(|_| self.b.create_block()).collect();
        for (i, b) in blocks.iter().enumerate() {
            sw.set_entry(i as u128, *b);
        }
        sw.emit(&mut self.b, gsel, none);
        for ((g, blk), slots) in groups.iter().zip(blocks).zip(saved) {
            self.b.switch_to_block(blk);
            let mark = self.frame.mark();
            let a = match g {
                Group::Single(a) => a,
                Group::Repl(levels, a) => {
                    // The indices saved when the guard was selected, then the declarations.
                    for (l, off) in levels.iter().zip(slots) {
                        let sym = self.cx.symbol(&l.repl.name)?;
                        self.cx.env.insert(
                            sym,
                            Storage::Var {
                                depth: self.depth,
                                offset: *off,
                            },
                        );
                        for d in &l.decls {
                            self.decl(d)?;
                        }
                    }
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
                if let ProcessKind::Input { .. }
                | ProcessKind::CaseInput { .. }
                | ProcessKind::Extended { .. } = &guard.kind
                {
                    self.process(guard)?;
                }
                self.process(body)
            }
            AltKind::CaseInput { chan, variants, .. } => self.case_input(chan, variants, a.span),
            AltKind::Nested(_) => Err(self.cx.internal(a.span, "nested ALT not flattened")),
        }
    }
}
