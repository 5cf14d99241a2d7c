//! Communication: `!`, `?`, `? CASE`, timers, and protocol agreement.

use occ_grammar::ast::{self, Expr, ExprKind, IoItem};

use super::Checker;
use crate::diagnostic::DiagnosticKind;
use crate::types::{ChanProtocol, Prim, ProtocolItem, ProtocolKind, Tag, Type};
use crate::usage::Mode;

/// What is at the other end of a `!` or `?`.
enum End {
    Chan(ChanProtocol),
    Timer,
    Port(Type),
    Unknown,
}

impl Checker {
    /// Checks the channel (or timer, or port) of a communication and records its use.
    fn end(&mut self, chan: &Expr, mode: Mode) -> End {
        let p = self.place(chan, Some(mode));
        self.check_direction(&p.ty, mode, chan);
        match self.out.types.underlying(&p.ty).clone() {
            Type::Chan(proto, _) => End::Chan(*proto),
            Type::Timer if mode == Mode::Input => End::Timer,
            Type::Port(t) => End::Port(*t),
            Type::Error => End::Unknown,
            _ => {
                let expected = if mode == Mode::Input {
                    "a channel or timer"
                } else {
                    "a channel"
                };
                let name = super::process::element_name(chan);
                let kind = DiagnosticKind::WrongKind {
                    name,
                    expected,
                    found: "a variable",
                };
                self.error(kind, chan.span);
                End::Unknown
            }
        }
    }

    /// Checks `chan ! items`.
    pub(super) fn output(&mut self, chan: &Expr, items: &[IoItem], span: ast::Span) {
        let end = self.end(chan, Mode::Output);
        self.communicate(end, items, false, span);
    }

    /// Checks `chan ? items` (also a timer read).
    pub(super) fn input(&mut self, chan: &Expr, items: &[IoItem], span: ast::Span) {
        let end = self.end(chan, Mode::Input);
        self.communicate(end, items, true, span);
    }

    /// Checks the input of an extended rendezvous, `chan ?? items`: as `chan ? items`, on a
    /// channel only.
    pub(super) fn extended_input(&mut self, chan: &Expr, items: &[IoItem], span: ast::Span) {
        let end = self.end(chan, Mode::Input);
        let what = match end {
            End::Timer => Some("a timer"),
            End::Port(_) => Some("a port"),
            _ => None,
        };
        if let Some(what) = what {
            self.error(DiagnosticKind::ExtendedNotChannel { what }, chan.span);
            return;
        }
        self.communicate(end, items, true, span);
    }

    fn communicate(&mut self, end: End, items: &[IoItem], input: bool, span: ast::Span) {
        match end {
            End::Chan(ChanProtocol::Any) | End::Unknown => {
                for item in items {
                    self.any_item(item, input);
                }
            }
            End::Chan(ChanProtocol::Simple(spec)) => {
                self.sequence(std::slice::from_ref(&spec), items, input, span)
            }
            End::Timer | End::Port(_) => {
                let ty = match end {
                    End::Port(t) => t,
                    _ => Type::INT,
                };
                self.sequence(&[ProtocolItem::Data(ty)], items, input, span);
            }
            End::Chan(ChanProtocol::Named(pid)) => {
                let Some(proto) = self.out.types.protocols.get(pid).cloned() else {
                    return;
                };
                match proto.kind {
                    ProtocolKind::Sequential(specs) => self.sequence(&specs, items, input, span),
                    ProtocolKind::Tagged(tags) => {
                        self.tagged(&proto.name, &tags, items, input, span)
                    }
                    ProtocolKind::Unknown => items.iter().for_each(|i| self.any_item(i, input)),
                }
            }
        }
    }

    /// Checks items against a sequence of protocol items.
    fn sequence(&mut self, specs: &[ProtocolItem], items: &[IoItem], input: bool, span: ast::Span) {
        if specs.len() != items.len() {
            let what = format!(
                "the protocol has {} items, but {} are given here",
                specs.len(),
                items.len()
            );
            self.error(DiagnosticKind::Protocol { what }, span);
        }
        for (spec, item) in specs.iter().zip(items) {
            self.item(spec, item, input);
        }
        for item in items.iter().skip(specs.len()) {
            self.any_item(item, input);
        }
    }

    /// Checks a tagged communication: the first item is the tag.
    fn tagged(
        &mut self,
        protocol: &str,
        tags: &[Tag],
        items: &[IoItem],
        input: bool,
        span: ast::Span,
    ) {
        let Some(IoItem::Expr(Expr {
            kind: ExprKind::Name(tag),
            ..
        })) = items.first()
        else {
            let what = format!("a communication on {protocol} must start with a tag");
            self.error(DiagnosticKind::Protocol { what }, span);
            return;
        };
        match tags.iter().find(|t| t.name == tag.text) {
            Some(t) => self.sequence(&t.items, items.get(1..).unwrap_or(&[]), input, span),
            None => {
                let kind = DiagnosticKind::NoSuchTag {
                    tag: tag.text.clone(),
                    protocol: protocol.into(),
                };
                self.error(kind, tag.span);
            }
        }
    }

    /// Checks one item against one protocol item.
    fn item(&mut self, spec: &ProtocolItem, item: &IoItem, input: bool) {
        match (spec, item) {
            (ProtocolItem::Data(ty), IoItem::Expr(e)) => self.value_item(ty, e, input),
            (ProtocolItem::Counted { count, elem }, IoItem::Counted { count: c, data }) => {
                self.value_item(&Type::Prim(*count), c, input);
                self.value_item(&Type::array(None, elem.clone()), data, input);
            }
            (ProtocolItem::Data(_), IoItem::Counted { count, .. }) => {
                let what =
                    "a counted array `n :: a` is given where the protocol has a single value"
                        .into();
                self.error(DiagnosticKind::Protocol { what }, count.span);
            }
            (ProtocolItem::Counted { .. }, IoItem::Expr(e)) => {
                let what = "the protocol has a counted array here: write `n :: a`".into();
                self.error(DiagnosticKind::Protocol { what }, e.span);
            }
        }
    }

    /// Checks a value sent, or a variable received into, of type `ty`.
    fn value_item(&mut self, ty: &Type, e: &Expr, input: bool) {
        if input {
            let p = self.place(e, Some(Mode::Write));
            self.expect_item(ty, &p.ty, e.span);
            if !p.assignable {
                let name = super::process::element_name(e);
                self.error(DiagnosticKind::NotAssignable { name }, e.span);
            }
        } else {
            let t = self.expr(e, Some(ty));
            self.expect_item(ty, &t.ty, e.span);
        }
    }

    /// Reports an item whose type is not the protocol's.
    fn expect_item(&mut self, want: &Type, found: &Type, span: ast::Span) {
        if !self.out.types.compatible(want, found) {
            let (w, f) = (self.out.types.display(want), self.out.types.display(found));
            let what = format!("expected {w}, found {f}");
            self.error(DiagnosticKind::Protocol { what }, span);
        }
    }

    /// Checks an item on a `CHAN OF ANY` (or after an error): any data.
    fn any_item(&mut self, item: &IoItem, input: bool) {
        match item {
            IoItem::Expr(e) if input => {
                self.place(e, Some(Mode::Write));
            }
            IoItem::Expr(e) => {
                self.expr(e, None);
            }
            IoItem::Counted { count, data } => {
                self.value_item(&Type::Prim(Prim::Int), count, input);
                if input {
                    self.place(data, Some(Mode::Write));
                } else {
                    self.expr(data, None);
                }
            }
        }
    }

    /// Checks `chan ? CASE` with its variants.
    pub(super) fn case_input(&mut self, chan: &Expr, variants: &[ast::Variant]) {
        let end = self.end(chan, Mode::Input);
        let tags = match &end {
            End::Chan(ChanProtocol::Named(pid)) => {
                self.out
                    .types
                    .protocols
                    .get(*pid)
                    .and_then(|p| match &p.kind {
                        ProtocolKind::Tagged(tags) => Some((p.name.clone(), tags.clone())),
                        _ => None,
                    })
            }
            _ => None,
        };
        if tags.is_none() && !matches!(end, End::Unknown) {
            let what = "`? CASE` needs a channel with a tagged PROTOCOL".into();
            self.error(DiagnosticKind::Protocol { what }, chan.span);
        }
        for v in variants {
            let mark = self.open_scope();
            self.decls(&v.decls);
            match &tags {
                Some((name, tags)) => match tags.iter().find(|t| t.name == v.tag.text) {
                    Some(t) => self.sequence(&t.items, &v.items, true, v.span),
                    None => {
                        let kind = DiagnosticKind::NoSuchTag {
                            tag: v.tag.text.clone(),
                            protocol: name.clone(),
                        };
                        self.error(kind, v.tag.span);
                    }
                },
                None => v.items.iter().for_each(|i| self.any_item(i, true)),
            }
            self.process(&v.body);
            self.close_scope(mark);
        }
    }
}
