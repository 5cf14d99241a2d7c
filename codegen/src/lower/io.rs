//! Channel input and output with every protocol shape (simple, sequential, counted arrays,
//! tagged with `? CASE`, ANY), and timer reads. Each protocol item is one communication; a tag is
//! one byte. Every address is recomputed after each blocking point (values do not survive one).

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_frontend::Switch;
use occ_compiler::types::{ChanProtocol, ProtocolItem, ProtocolKind, Type};
use occ_grammar::ast::{Expr, ExprKind, IoItem, Process, ProcessKind, Span, Variant};
use occ_runtime::ErrorKind;
use occ_runtime::abi::{
    Entry, NODE_COMMUNICATIONS_OFFSET, NODE_CUR_PRI_OFFSET, NODE_QUEUES_OFFSET, NOT_PROCESS,
    RUN_QUEUE_BACK, RUN_QUEUE_BYTES, RUN_QUEUE_FRONT, WORD_BYTES, priority, slot, tag, word_offset,
};

use super::{Res, Tr, mem};
use crate::layout::{WORD, is_scalar, size_of};

/// The protocol of a channel as the code generator sees it.
pub enum Proto {
    /// A list of items (simple or sequential protocol).
    Items(Vec<ProtocolItem>),
    /// A tagged protocol: each tag's items.
    Tagged(Vec<(String, Vec<ProtocolItem>)>),
    /// CHAN OF ANY: items take their own types.
    Any,
}

impl Tr<'_, '_> {
    /// The protocol of channel expression `chan`.
    pub fn proto_of(&self, chan: &Expr) -> Res<Proto> {
        let ty = self.cx.type_of(chan)?;
        let Type::Chan(p, _) = ty else {
            return Err(self.cx.internal(chan.span, "not a channel"));
        };
        Ok(match *p {
            ChanProtocol::Any => Proto::Any,
            ChanProtocol::Simple(item) => Proto::Items(vec![item]),
            ChanProtocol::Named(id) => match &self.cx.checked.types.protocols[id].kind {
                ProtocolKind::Sequential(items) => Proto::Items(items.clone()),
                ProtocolKind::Tagged(tags) => Proto::Tagged(
                    tags.iter()
                        .map(|t| (t.name.clone(), t.items.clone()))
                        .collect(),
                ),
                ProtocolKind::Unknown => Proto::Any,
            },
        })
    }

    fn chan_addr(&mut self, chan: &Expr) -> Res<Value> {
        Ok(self.place(chan)?.addr)
    }

    fn is_timer(&self, chan: &Expr) -> bool {
        matches!(self.cx.type_of(chan), Ok(Type::Timer))
    }

    /// `chan ! items`.
    pub fn output(&mut self, chan: &Expr, items: &[IoItem], span: Span) -> Res<()> {
        let proto = self.proto_of(chan)?;
        let mut rest = items;
        if let Proto::Tagged(tags) = &proto {
            let Some(IoItem::Expr(Expr {
                kind: ExprKind::Name(tag),
                ..
            })) = items.first()
            else {
                return Err(self.cx.internal(span, "tagged output without a tag"));
            };
            let idx = tags
                .iter()
                .position(|(n, _)| *n == tag.text)
                .ok_or_else(|| self.cx.internal(tag.span, "unknown tag"))?;
            let off = self.frame.alloc_word();
            let a = self.local_addr(off);
            let v = self.b.ins().iconst(types::I8, idx as i64);
            self.store_scalar(v, a);
            self.send(chan, off, 1, span)?;
            rest = &items[1..];
        }
        for item in rest {
            match item {
                IoItem::Expr(e) => self.output_expr(chan, e, span)?,
                IoItem::Counted { count, data } => self.output_counted(chan, count, data, span)?,
            }
        }
        Ok(())
    }

    fn send(&mut self, chan: &Expr, off: i32, len: i64, span: Span) -> Res<()> {
        let c = self.chan_addr(chan)?;
        let a = self.local_addr(off);
        self.communicate(true, c, a, len, span)
    }

    /// One communication of `len` bytes at `data` on channel word `chan`.
    ///
    /// Messages of 1, 4 or 8 bytes take an inline fast path when the partner is already waiting
    /// in the channel word as a plain process of the running priority: copy straight to or from
    /// its `POINTER`, empty the word, count the communication, put the partner at the back of
    /// its run queue and carry on (through `rt_preempt` when a low-priority process must give
    /// way), exactly what `rt_in`/`rt_out` do for this case but with no call. Every other case
    /// (first to arrive, an ALTing reader, an endpoint, another priority) calls
    /// `rt_in`/`rt_out`.
    fn communicate(
        &mut self,
        output: bool,
        chan: Value,
        data: Value,
        len: i64,
        span: Span,
    ) -> Res<()> {
        let rt = if output { Entry::Out } else { Entry::In };
        let ty = match len {
            1 => types::I8,
            4 => types::I32,
            8 => types::I64,
            _ => {
                let l = self.iconst(len);
                return self.blocking(rt, &[self.node, self.ws, chan, data, l], span);
            }
        };
        let (fast, slow, done) = (
            self.b.create_block(),
            self.b.create_block(),
            self.b.create_block(),
        );
        let w = self.b.ins().load(types::I64, mem(), chan, 0);
        let special = self.b.ins().band_imm_u(w, tag::ENDPOINT | tag::ALT);
        let plain = self.b.ins().icmp_imm_u(IntCC::Equal, special, 0);
        let waiting = self.b.ins().icmp_imm_u(IntCC::NotEqual, w, NOT_PROCESS);
        let p = self.b.ins().band_imm_u(w, tag::LOW);
        let cur = self
            .b
            .ins()
            .load(types::I64, mem(), self.node, NODE_CUR_PRI_OFFSET);
        let same = self.b.ins().icmp(IntCC::Equal, p, cur);
        let ok = self.b.ins().band(plain, waiting);
        let ok = self.b.ins().band(ok, same);
        self.b.ins().brif(ok, fast, &[], slow, &[]);

        self.b.switch_to_block(fast);
        let partner = self.b.ins().band_imm_u(w, !tag::MASK);
        let theirs = self
            .b
            .ins()
            .load(types::I64, mem(), partner, word_offset(slot::POINTER));
        let (src, dst) = if output {
            (data, theirs)
        } else {
            (theirs, data)
        };
        let v = self.b.ins().load(ty, mem(), src, 0);
        self.b.ins().store(mem(), v, dst, 0);
        let empty = self.iconst(NOT_PROCESS);
        self.b.ins().store(mem(), empty, chan, 0);
        let n = self
            .b
            .ins()
            .load(types::I64, mem(), self.node, NODE_COMMUNICATIONS_OFFSET);
        let n = self.b.ins().iadd_imm_s(n, 1);
        self.b
            .ins()
            .store(mem(), n, self.node, NODE_COMMUNICATIONS_OFFSET);
        self.enqueue_partner(partner, p);
        // A low-priority process gives way to a high-priority one that is ready.
        let high_front = self.b.ins().load(
            types::I64,
            mem(),
            self.node,
            NODE_QUEUES_OFFSET + RUN_QUEUE_BYTES * priority::HIGH as i32 + RUN_QUEUE_FRONT,
        );
        let high_ready = self.b.ins().icmp_imm_u(IntCC::NotEqual, high_front, 0);
        let low = self.b.ins().icmp_imm_u(IntCC::Equal, cur, priority::LOW);
        let give_way = self.b.ins().band(high_ready, low);
        let preempt = self.b.create_block();
        self.b.ins().brif(give_way, preempt, &[], done, &[]);
        self.b.switch_to_block(preempt);
        self.blocking(Entry::Preempt, &[self.node, self.ws], span)?;
        self.b.ins().jump(done, &[]);

        self.b.switch_to_block(slow);
        let l = self.iconst(len);
        self.blocking(rt, &[self.node, self.ws, chan, data, l], span)?;
        self.b.ins().jump(done, &[]);
        self.b.switch_to_block(done);
        Ok(())
    }

    /// Appends `partner` to the back of run queue `p` (0: high, 1: low), as `Node::enqueue`,
    /// without a branch: the partner's address goes into the queue's front when it is empty,
    /// else into the `LINK` slot of the process at its back.
    fn enqueue_partner(&mut self, partner: Value, p: Value) {
        let (front_at, back_at) = (
            NODE_QUEUES_OFFSET + RUN_QUEUE_FRONT,
            NODE_QUEUES_OFFSET + RUN_QUEUE_BACK,
        );
        let q = self.b.ins().imul_imm_s(p, i64::from(RUN_QUEUE_BYTES));
        let q = self.b.ins().iadd(self.node, q);
        let zero = self.iconst(0);
        self.b
            .ins()
            .store(mem(), zero, partner, word_offset(slot::LINK));
        let front = self.b.ins().load(types::I64, mem(), q, front_at);
        let back = self.b.ins().load(types::I64, mem(), q, back_at);
        let empty = self.b.ins().icmp_imm_u(IntCC::Equal, front, 0);
        let front_slot = self.b.ins().iadd_imm_s(q, i64::from(front_at));
        let back_link = self
            .b
            .ins()
            .iadd_imm_s(back, i64::from(word_offset(slot::LINK)));
        let at = self.b.ins().select(empty, front_slot, back_link);
        self.b.ins().store(mem(), partner, at, 0);
        self.b.ins().store(mem(), partner, q, back_at);
    }

    fn output_expr(&mut self, chan: &Expr, e: &Expr, span: Span) -> Res<()> {
        let ty = self.cx.type_of(e)?;
        if is_scalar(&self.cx.checked.types, &ty) {
            let size = size_of(&self.cx.checked.types, &ty).unwrap_or(WORD);
            let v = self.expr(e)?;
            let off = self.frame.alloc_word();
            let a = self.local_addr(off);
            self.store_scalar(v, a);
            return self.send(chan, off, size, span);
        }
        let l = self.value_loc(e)?;
        let size = self.loc_size(&l, e.span)?;
        // Keep the address in the frame: the place may need recomputing otherwise.
        let off = self.frame.alloc_words(2);
        let a = self.local_addr(off);
        self.b.ins().store(mem(), l.addr, a, 0);
        self.b.ins().store(mem(), size, a, WORD_BYTES);
        let c = self.chan_addr(chan)?;
        let a = self.local_addr(off);
        let p = self.b.ins().load(types::I64, mem(), a, 0);
        let s = self.b.ins().load(types::I64, mem(), a, WORD_BYTES);
        self.blocking(Entry::Out, &[self.node, self.ws, c, p, s], span)
    }

    fn output_counted(&mut self, chan: &Expr, count: &Expr, data: &Expr, span: Span) -> Res<()> {
        self.output_expr(chan, count, span)?;
        let n = self.int_index(count)?;
        let l = self.place(data)?;
        if let Some(&dim) = l.dims.first() {
            let ok = self.b.ins().icmp(IntCC::UnsignedLessThanOrEqual, n, dim);
            self.check(ok, ErrorKind::Segment, span);
        }
        let es = self.elem_size(&l, span)?;
        let size = self.b.ins().imul(n, es);
        let c = self.chan_addr(chan)?;
        self.blocking(Entry::Out, &[self.node, self.ws, c, l.addr, size], span)
    }

    /// `chan ? items` (or a timer read).
    pub fn input(&mut self, chan: &Expr, items: &[IoItem], span: Span) -> Res<()> {
        if self.is_timer(chan) {
            let Some(IoItem::Expr(x)) = items.first() else {
                return Err(self.cx.internal(span, "timer input without a variable"));
            };
            let t = self.call_rt(Entry::TimerRead, &[self.node]);
            let t = self.b.ins().ireduce(types::I32, t);
            let l = self.place(x)?;
            self.store_scalar(t, l.addr);
            return Ok(());
        }
        for item in items {
            self.input_item(chan, item, span)?;
        }
        Ok(())
    }

    /// Inputs one item into its place.
    pub fn input_item(&mut self, chan: &Expr, item: &IoItem, span: Span) -> Res<()> {
        match item {
            IoItem::Expr(x) => {
                self.extended_ready(chan, span)?;
                let ty = self.cx.type_of(x)?;
                let l = self.place(x)?;
                if is_scalar(&self.cx.checked.types, &ty) {
                    let len = size_of(&self.cx.checked.types, &ty).unwrap_or(WORD);
                    let c = self.chan_addr(chan)?;
                    if self.held.is_some() {
                        let len = self.iconst(len);
                        return self.receive(c, l.addr, len, span);
                    }
                    return self.communicate(false, c, l.addr, len, span);
                }
                let size = self.loc_size(&l, x.span)?;
                let c = self.chan_addr(chan)?;
                self.receive(c, l.addr, size, span)
            }
            IoItem::Counted { count, data } => {
                self.input_item(chan, &IoItem::Expr(count.clone()), span)?;
                self.extended_ready(chan, span)?;
                let n = self.int_index(count)?;
                let l = self.place(data)?;
                if let Some(&dim) = l.dims.first() {
                    let ok = self.b.ins().icmp(IntCC::UnsignedLessThanOrEqual, n, dim);
                    self.check(ok, ErrorKind::Segment, span);
                }
                let es = self.elem_size(&l, span)?;
                let size = self.b.ins().imul(n, es);
                let c = self.chan_addr(chan)?;
                self.receive(c, l.addr, size, span)
            }
        }
    }

    /// One input of `len` bytes into `data` from channel word `chan` through the runtime: `rt_in`,
    /// or inside an extended input `rt_xin`, which leaves the outputter held.
    fn receive(&mut self, chan: Value, data: Value, len: Value, span: Span) -> Res<()> {
        match self.held {
            None => self.blocking(Entry::In, &[self.node, self.ws, chan, data, len], span),
            Some(off) => {
                let held = self.local_addr(off);
                let args = [self.node, self.ws, chan, data, len, held];
                self.blocking(Entry::Xin, &args, span)
            }
        }
    }

    /// Inside an extended input, before each communication: releases the outputter that the
    /// previous one held (only the last stays held: it is the end of the outputter's output)
    /// and waits until the outputter is in the channel. Nothing outside one. Addresses computed
    /// before this call do not survive it.
    fn extended_ready(&mut self, chan: &Expr, span: Span) -> Res<()> {
        let Some(off) = self.held else {
            return Ok(());
        };
        let held = self.local_addr(off);
        self.blocking(Entry::Xend, &[self.node, self.ws, held], span)?;
        let c = self.chan_addr(chan)?;
        self.blocking(Entry::Xwait, &[self.node, self.ws, c], span)
    }

    /// occam-pi's extended rendezvous, `c ?? x` then `during` and `after`: the input holds the
    /// outputter (each communication goes through `rt_xwait` and `rt_xin`), `during` runs,
    /// `rt_xend` releases the outputter, then `after` runs.
    pub fn extended(
        &mut self,
        input: &Process,
        during: &Process,
        after: Option<&Process>,
        span: Span,
    ) -> Res<()> {
        if let ProcessKind::Skip = input.kind {
            return self.held_variant(during, after, span);
        }
        let off = self.frame.alloc_word();
        let held = self.local_addr(off);
        let empty = self.iconst(NOT_PROCESS);
        self.b.ins().store(mem(), empty, held, 0);
        let outer = self.held.replace(off);
        let received = self.process(input);
        self.held = outer;
        received?;
        self.process(during)?;
        let held = self.local_addr(off);
        self.blocking(Entry::Xend, &[self.node, self.ws, held], span)?;
        match after {
            Some(after) => self.process(after),
            None => Ok(()),
        }
    }

    /// The body of a variant of `c ?? CASE` (the tag and the variant's items have been input
    /// with the outputter held in `self.held`): `during`, the release, then `after`.
    fn held_variant(&mut self, during: &Process, after: Option<&Process>, span: Span) -> Res<()> {
        let Some(off) = self.held.take() else {
            return Err(self.cx.internal(span, "a `??` variant outside `c ?? CASE`"));
        };
        let ran = self.process(during).and_then(|()| {
            let held = self.local_addr(off);
            self.blocking(Entry::Xend, &[self.node, self.ws, held], span)?;
            after.map_or(Ok(()), |a| self.process(a))
        });
        // The next variant's items are still input with the outputter held.
        self.held = Some(off);
        ran
    }

    /// `chan ? CASE` with variants.
    pub fn case_input(&mut self, chan: &Expr, variants: &[Variant], span: Span) -> Res<()> {
        let off = self.frame.alloc_word();
        self.extended_ready(chan, span)?;
        let a = self.local_addr(off);
        let c = self.chan_addr(chan)?;
        let one = self.iconst(1);
        self.receive(c, a, one, span)?;
        self.tag_dispatch(chan, off, variants, span)
    }

    /// Switches on the tag byte at frame offset `off` and runs the matching variant.
    pub fn tag_dispatch(
        &mut self,
        chan: &Expr,
        off: i32,
        variants: &[Variant],
        span: Span,
    ) -> Res<()> {
        let Proto::Tagged(tags) = self.proto_of(chan)? else {
            return Err(self.cx.internal(span, "CASE input on an untagged channel"));
        };
        let a = self.local_addr(off);
        let t = self.b.ins().load(types::I8, mem(), a, 0);
        let t = self.b.ins().uextend(types::I64, t);
        let done = self.b.create_block();
        let nomatch = self.b.create_block();
        let mut sw = Switch::new();
        let mut blocks = Vec::new();
        for v in variants {
            let idx = tags
                .iter()
                .position(|(n, _)| *n == v.tag.text)
                .ok_or_else(|| self.cx.internal(v.tag.span, "unknown tag"))?;
            let blk = self.b.create_block();
            sw.set_entry(idx as u128, blk);
            blocks.push((blk, v));
        }
        sw.emit(&mut self.b, t, nomatch);
        for (blk, v) in blocks {
            self.b.switch_to_block(blk);
            let mark = self.frame.mark();
            for d in &v.decls {
                self.decl(d)?;
            }
            for item in &v.items {
                self.input_item(chan, item, v.span)?;
            }
            self.process(&v.body)?;
            self.frame.release(mark);
            self.b.ins().jump(done, &[]);
        }
        self.b.switch_to_block(nomatch);
        self.halt(ErrorKind::CaseNoMatch, span);
        self.b.switch_to_block(done);
        Ok(())
    }
}
