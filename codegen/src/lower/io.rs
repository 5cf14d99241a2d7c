//! Channel input and output with every protocol shape (simple, sequential, counted arrays,
//! tagged with `? CASE`, ANY), and timer reads. Each protocol item is one communication; a tag is
//! one byte. Every address is recomputed after each blocking point (values do not survive one).

use cranelift_codegen::ir::{InstBuilder, Value, condcodes::IntCC, types};
use cranelift_frontend::Switch;
use occ_compiler::types::{ChanProtocol, ProtocolItem, ProtocolKind, Type};
use occ_grammar::ast::{Expr, ExprKind, IoItem, Span, Variant};
use occ_runtime::ErrorKind;

use super::{Res, Tr, mem};
use crate::layout::{is_scalar, size_of};

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
            let off = self.frame.alloc(8);
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
        let l = self.iconst(len);
        self.blocking("rt_out", &[self.node, self.ws, c, a, l], span)
    }

    fn output_expr(&mut self, chan: &Expr, e: &Expr, span: Span) -> Res<()> {
        let ty = self.cx.type_of(e)?;
        if is_scalar(&self.cx.checked.types, &ty) {
            let size = size_of(&self.cx.checked.types, &ty).unwrap_or(8);
            let v = self.expr(e)?;
            let off = self.frame.alloc(8);
            let a = self.local_addr(off);
            self.store_scalar(v, a);
            return self.send(chan, off, size, span);
        }
        let l = self.value_loc(e)?;
        let size = self.loc_size(&l, e.span)?;
        // Keep the address in the frame: the place may need recomputing otherwise.
        let off = self.frame.alloc(16);
        let a = self.local_addr(off);
        self.b.ins().store(mem(), l.addr, a, 0);
        self.b.ins().store(mem(), size, a, 8);
        let c = self.chan_addr(chan)?;
        let a = self.local_addr(off);
        let p = self.b.ins().load(types::I64, mem(), a, 0);
        let s = self.b.ins().load(types::I64, mem(), a, 8);
        self.blocking("rt_out", &[self.node, self.ws, c, p, s], span)
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
        self.blocking("rt_out", &[self.node, self.ws, c, l.addr, size], span)
    }

    /// `chan ? items` (or a timer read).
    pub fn input(&mut self, chan: &Expr, items: &[IoItem], span: Span) -> Res<()> {
        if self.is_timer(chan) {
            let Some(IoItem::Expr(x)) = items.first() else {
                return Err(self.cx.internal(span, "timer input without a variable"));
            };
            let t = self.call_rt("rt_timer_read", &[self.node]);
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
                let l = self.place(x)?;
                let size = self.loc_size(&l, x.span)?;
                let c = self.chan_addr(chan)?;
                self.blocking("rt_in", &[self.node, self.ws, c, l.addr, size], span)
            }
            IoItem::Counted { count, data } => {
                self.input_item(chan, &IoItem::Expr(count.clone()), span)?;
                let n = self.int_index(count)?;
                let l = self.place(data)?;
                if let Some(&dim) = l.dims.first() {
                    let ok = self.b.ins().icmp(IntCC::UnsignedLessThanOrEqual, n, dim);
                    self.check(ok, ErrorKind::Segment, span);
                }
                let es = self.elem_size(&l, span)?;
                let size = self.b.ins().imul(n, es);
                let c = self.chan_addr(chan)?;
                self.blocking("rt_in", &[self.node, self.ws, c, l.addr, size], span)
            }
        }
    }

    /// `chan ? CASE` with variants.
    pub fn case_input(&mut self, chan: &Expr, variants: &[Variant], span: Span) -> Res<()> {
        let off = self.frame.alloc(8);
        let a = self.local_addr(off);
        let c = self.chan_addr(chan)?;
        let one = self.iconst(1);
        self.blocking("rt_in", &[self.node, self.ws, c, a, one], span)?;
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
