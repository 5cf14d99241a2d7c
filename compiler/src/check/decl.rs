//! Declarations (occam "specifications") and types as written.

use occ_grammar::ast::{self, AbbrevMode, DeclKind, ParamMode, Span};

use super::Checker;
use crate::checked::{ChanRetype, ProcInfo, SymbolId, SymbolKind};
use crate::diagnostic::DiagnosticKind;
use crate::types::{
    ChanProtocol, Direction, Prim, Protocol, ProtocolItem, ProtocolKind, Tag, Type, TypeDef,
    TypeDefKind, bytes_in,
};
use crate::usage::{Access, Mode, Part};

/// Converts a direction specifier.
pub(super) fn direction(dir: Option<ast::Direction>) -> Direction {
    match dir {
        Some(ast::Direction::Input) => Direction::Input,
        Some(ast::Direction::Output) => Direction::Output,
        None => Direction::Both,
    }
}

/// Applies a direction specifier to a channel type or to the channels of a channel array.
pub(super) fn with_direction(ty: Type, dir: Direction) -> Type {
    match ty {
        Type::Chan(p, _) if dir != Direction::Both => Type::Chan(p, dir),
        Type::Array(n, e) => Type::Array(n, Box::new(with_direction(*e, dir))),
        other => other,
    }
}

impl Checker {
    /// Resolves a type as written.
    pub(super) fn ty(&mut self, t: &ast::Ty) -> Type {
        use ast::TyKind as K;
        match &t.kind {
            K::Bool => Type::Prim(Prim::Bool),
            K::Byte => Type::Prim(Prim::Byte),
            K::Int => Type::Prim(Prim::Int),
            K::Int16 => Type::Prim(Prim::Int16),
            K::Int32 => Type::Prim(Prim::Int32),
            K::Int64 => Type::Prim(Prim::Int64),
            K::Real32 => Type::Prim(Prim::Real32),
            K::Real64 => Type::Prim(Prim::Real64),
            K::Timer => Type::Timer,
            K::Named(name) => self.named_type(name),
            K::Array { len, elem } => {
                let n = len.as_ref().and_then(|e| self.const_len(e));
                let elem = self.ty(elem);
                Type::array(n, elem)
            }
            K::Chan(item) => Type::Chan(Box::new(self.chan_protocol(item)), Direction::Both),
            K::Port(elem) => Type::Port(Box::new(self.ty(elem))),
        }
    }

    fn named_type(&mut self, name: &ast::Name) -> Type {
        let Some(id) = self.lookup(name) else {
            return Type::Error;
        };
        match self.sym(id).kind {
            SymbolKind::DataType(def) => Type::Named(def),
            _ => {
                let found = kind_name(&self.sym(id).kind);
                let kind = DiagnosticKind::WrongKind {
                    name: name.text.clone(),
                    expected: "a type",
                    found,
                };
                self.error(kind, name.span);
                Type::Error
            }
        }
    }

    /// Evaluates an array length: a constant INT, at least 0.
    pub(super) fn const_len(&mut self, e: &ast::Expr) -> Option<u32> {
        let t = self.expr(e, Some(&Type::INT));
        self.expect_type(&Type::INT, &t.ty, e.span);
        match t.value.as_ref().and_then(|v| v.as_int()) {
            Some(n) => match u32::try_from(n) {
                Ok(n) => Some(n),
                Err(_) => {
                    let what = format!("array size {n} is negative or too large");
                    self.error(DiagnosticKind::ConstantError { what }, e.span);
                    None
                }
            },
            None => {
                if !t.ty.is_error() && !self.dynamic_sizes {
                    self.error(
                        DiagnosticKind::NotConstant {
                            context: "an array size",
                        },
                        e.span,
                    );
                }
                None
            }
        }
    }

    fn chan_protocol(&mut self, item: &ast::ProtoItem) -> ChanProtocol {
        if let ast::ProtoItemKind::Type(ast::Ty {
            kind: ast::TyKind::Named(name),
            ..
        }) = &item.kind
            && let Some(id) = self.scope_lookup_quiet(name)
            && let SymbolKind::Protocol(p) = self.sym(id).kind
        {
            self.out.names.insert(name.span, id);
            return ChanProtocol::Named(p);
        }
        match &item.kind {
            ast::ProtoItemKind::Any => ChanProtocol::Any,
            _ => ChanProtocol::Simple(self.proto_item(item)),
        }
    }

    fn scope_lookup_quiet(&self, name: &ast::Name) -> Option<SymbolId> {
        self.scope.lookup(&name.text)
    }

    fn proto_item(&mut self, item: &ast::ProtoItem) -> ProtocolItem {
        match &item.kind {
            ast::ProtoItemKind::Any => ProtocolItem::Data(Type::Error),
            ast::ProtoItemKind::Type(t) => ProtocolItem::Data(self.ty(t)),
            ast::ProtoItemKind::Counted { count, elem } => {
                let count_ty = self.ty(count);
                let count = match self.out.types.prim(&count_ty) {
                    Some(p) if p.is_integer() => p,
                    _ => {
                        self.expect_type(&Type::INT, &count_ty, count.span);
                        Prim::Int
                    }
                };
                let elem = match self.ty(elem) {
                    Type::Array(_, e) => *e,
                    other => other,
                };
                ProtocolItem::Counted { count, elem }
            }
        }
    }

    /// Checks declarations in the current scope, in order.
    pub(super) fn decls(&mut self, decls: &[ast::Decl]) {
        for d in decls {
            self.decl(d);
        }
    }

    /// Checks one declaration and declares its names.
    pub(super) fn decl(&mut self, d: &ast::Decl) {
        match &d.kind {
            DeclKind::Var { ty, names } => {
                let ty = self.ty(ty);
                let assignable = ty.is_data();
                for (i, name) in names.iter().enumerate() {
                    if names.iter().take(i).any(|n| n.text == name.text) {
                        self.error(
                            DiagnosticKind::Duplicate {
                                name: name.text.clone(),
                            },
                            name.span,
                        );
                    }
                    let id = self.declare(name, SymbolKind::Variable, ty.clone(), assignable);
                    self.take_workspace(id, &ty);
                }
            }
            DeclKind::Abbrev {
                mode,
                ty,
                name,
                dir,
                value,
            } => self.abbrev(*mode, ty.as_ref(), name, *dir, value),
            DeclKind::Retypes {
                kind,
                val,
                ty,
                name,
                value,
            } => self.retypes(*kind, *val, ty, name, value),
            DeclKind::DataType { name, def } => self.data_type(name, def),
            DeclKind::Protocol { name, def } => self.protocol(name, def),
            DeclKind::Proc {
                name, params, body, ..
            } => self.proc_decl(d.span, name, params, &[], None, Some(body)),
            DeclKind::Function {
                name,
                results,
                params,
                body,
                ..
            } => self.proc_decl(d.span, name, params, results, Some(body), None),
            DeclKind::Place { name, at } => {
                self.lookup(name);
                let t = self.expr(at, Some(&Type::INT));
                self.expect_type(&Type::INT, &t.ty, at.span);
            }
            DeclKind::Asm(_) => {}
            DeclKind::PlaceIn { name, area } => {
                if let Some(id) = self.lookup(name)
                    && area.text == "VECSPACE"
                {
                    self.move_to_vecspace(id);
                }
            }
        }
    }

    fn abbrev(
        &mut self,
        mode: AbbrevMode,
        ty: Option<&ast::Ty>,
        name: &ast::Name,
        dir: Option<ast::Direction>,
        value: &ast::Expr,
    ) {
        let want = ty.map(|t| self.ty(t));
        let is_element = super::place::is_element(value);
        if matches!(mode, AbbrevMode::Val | AbbrevMode::Initial) || !is_element {
            let t = self.expr(value, want.as_ref());
            let ty = self.declared_type(want, t.ty.clone(), value.span);
            if mode == AbbrevMode::Initial {
                self.declare(name, SymbolKind::Abbrev { mode }, ty, true);
                return;
            }
            let constant = t.value.is_some();
            let id = self.declare(name, SymbolKind::Val { value: t.value }, ty, false);
            if !constant && let Some(l) = self.linear(value) {
                // `VAL ii IS i:` keeps subscripts through `ii` comparable with those through `i`.
                self.val_lin.insert(id, l);
            }
            if let Some(target) = t.target {
                self.abbreviated.push(super::Abbreviated {
                    target,
                    alias: id,
                    val: true,
                });
            }
            return;
        }
        let p = self.place(value, None);
        let data = p.ty.is_data();
        if data && !p.assignable && !p.ty.is_error() {
            let name = super::process::element_name(value);
            self.error(DiagnosticKind::NotAssignable { name }, value.span);
        }
        let ty = self.declared_type(want, p.ty, value.span);
        let ty = with_direction(ty, direction(dir));
        let id = self.declare(name, SymbolKind::Abbrev { mode }, ty, data);
        if let Some(target) = p.target {
            self.out.symbols[id].alias_of = Some(target);
            // Abbreviating is a use of the target: it may not be abbreviated already.
            let (resolved, hops) = self.resolve_alias(Access {
                span: value.span,
                ..target
            });
            if self.check_alias(resolved, &hops) {
                let entry = super::Abbreviated {
                    target,
                    alias: id,
                    val: false,
                };
                self.abbreviated.push(entry);
            }
        }
    }

    /// The type of an abbreviation: the written one (checked against the value) or the value's.
    fn declared_type(&mut self, want: Option<Type>, found: Type, span: ast::Span) -> Type {
        match want {
            Some(w) => {
                self.expect_type(&w, &found, span);
                match (&w, &found) {
                    (Type::Array(None, _), Type::Array(Some(_), _)) => found,
                    _ => w,
                }
            }
            None => found,
        }
    }

    fn retypes(
        &mut self,
        kind: ast::RetypeKind,
        val: bool,
        ty: &ast::Ty,
        name: &ast::Name,
        value: &ast::Expr,
    ) {
        self.dynamic_sizes = true;
        let to = self.ty(ty);
        self.dynamic_sizes = false;
        if self.chan_int_retype(&to, name, value) {
            return;
        }
        // A channel is not a value: `VAL CHAN OF p c RETYPES d` names channel `d` under another
        // protocol, as the non-VAL form does (occ21 accepts both).
        let channel = root_type(self, value)
            .is_some_and(|r| matches!(self.out.types.underlying(elem_of(&r)), Type::Chan(..)));
        let (from, target, assignable) = if (val && !channel) || !super::place::is_element(value) {
            let t = self.expr(value, None);
            (t.ty, None, false)
        } else {
            let p = self.place(value, None);
            (p.ty, p.target, p.assignable)
        };
        if kind == ast::RetypeKind::Retypes {
            self.retype_sizes(&to, &from, value.span);
        }
        let sym_kind = if val {
            SymbolKind::Val { value: None }
        } else {
            SymbolKind::Abbrev {
                mode: AbbrevMode::Ref,
            }
        };
        let id = self.declare(name, sym_kind, to, assignable && !val);
        if let Some(t) = target {
            let whole = Access {
                mode: Mode::Read,
                ..t
            };
            self.out.symbols[id].alias_of = Some(whole);
            self.abbreviated.push(super::Abbreviated {
                target: whole,
                alias: id,
                val: false,
            });
        }
    }

    /// A RETYPES of a channel to an INT or of an INT to a channel (addresses as `ASM` blocks
    /// see them, as occ21 allowed): declares `name` and reports whether it was one.
    fn chan_int_retype(&mut self, to: &Type, name: &ast::Name, value: &ast::Expr) -> bool {
        let int =
            |c: &Checker, t: &Type| matches!(c.out.types.underlying(t), Type::Prim(Prim::Int));
        let chan = |c: &Checker, t: &Type| matches!(c.out.types.underlying(t), Type::Chan(..));
        let root = place_type(self, value);
        let kind = match root {
            Some(r) if int(self, to) && chan(self, &r) => ChanRetype::ToInt,
            Some(r) if chan(self, to) && int(self, &r) => ChanRetype::FromInt,
            _ => return false,
        };
        let p = self.place(value, None);
        if kind == ChanRetype::FromInt
            && let Some(t) = &p.target
        {
            self.record(t.symbol, Mode::Read, t.part, t.span);
        }
        let sym_kind = match kind {
            ChanRetype::ToInt => SymbolKind::Val { value: None },
            ChanRetype::FromInt => SymbolKind::Abbrev {
                mode: AbbrevMode::Ref,
            },
        };
        self.declare(name, sym_kind, to.clone(), false);
        if self.shadow == 0 {
            self.out.chan_retypes.insert(name.span, kind);
        }
        true
    }

    fn retype_sizes(&mut self, to: &Type, from: &Type, span: ast::Span) {
        let Ok(from_bytes) = bytes_in(&self.out.types, from) else {
            return;
        };
        let to_bytes = match to {
            Type::Array(None, e) => match bytes_in(&self.out.types, e) {
                Ok(b) if b > 0 && from_bytes % b == 0 => return,
                Ok(b) => b,
                Err(_) => return,
            },
            _ => match bytes_in(&self.out.types, to) {
                Ok(b) => b,
                Err(_) => return,
            },
        };
        if to_bytes != from_bytes {
            self.error(
                DiagnosticKind::RetypeSize {
                    to: to_bytes,
                    from: from_bytes,
                },
                span,
            );
        }
    }

    fn data_type(&mut self, name: &ast::Name, def: &ast::DataTypeDef) {
        let kind = match def {
            ast::DataTypeDef::Alias(t) => TypeDefKind::Alias(self.ty(t)),
            ast::DataTypeDef::Record { packed, fields } => {
                let mut out: Vec<(String, crate::types::Type)> = Vec::new();
                for f in fields {
                    let ty = self.ty(&f.ty);
                    for n in &f.names {
                        if out.iter().any(|(x, _)| *x == n.text) {
                            self.error(
                                DiagnosticKind::Duplicate {
                                    name: n.text.clone(),
                                },
                                n.span,
                            );
                        }
                        out.push((n.text.clone(), ty.clone()));
                    }
                }
                TypeDefKind::Record {
                    packed: *packed,
                    fields: out,
                }
            }
        };
        let id = self.out.types.defs.push(TypeDef {
            name: name.text.clone(),
            kind,
        });
        self.declare(name, SymbolKind::DataType(id), Type::Error, false);
    }

    fn protocol(&mut self, name: &ast::Name, def: &ast::ProtocolDef) {
        let kind = match def {
            ast::ProtocolDef::Sequential(items) => {
                ProtocolKind::Sequential(items.iter().map(|i| self.proto_item(i)).collect())
            }
            ast::ProtocolDef::Tagged(cases) => ProtocolKind::Tagged(
                cases
                    .iter()
                    .map(|c| Tag {
                        name: c.tag.text.clone(),
                        items: c.items.iter().map(|i| self.proto_item(i)).collect(),
                    })
                    .collect(),
            ),
        };
        let id = self.out.types.protocols.push(Protocol {
            name: name.text.clone(),
            kind,
        });
        self.declare(name, SymbolKind::Protocol(id), Type::Error, false);
    }

    fn proc_decl(
        &mut self,
        span: Span,
        name: &ast::Name,
        params: &[ast::Param],
        results: &[ast::Ty],
        function: Option<&ast::FunctionBody>,
        body: Option<&ast::Process>,
    ) {
        if function.is_some() && super::operator::is_operator_name(&name.text) {
            self.operator_declaration(name, params.len(), results.len());
        }
        let results: Vec<Type> = results.iter().map(|t| self.ty(t)).collect();
        let info = ProcInfo {
            name: name.text.clone(),
            symbol: None,
            span,
            params: Vec::new(),
            results,
            usage: Vec::new(),
        };
        let pid = self.out.procs.push(info);
        let mark = self.open_scope();
        let first = self.next_symbol();
        let all_val = params.iter().all(|p| p.mode == ParamMode::Val);
        let names: Vec<ast::Name> = params.iter().map(|p| p.name.clone()).collect();
        self.space.push((0, 0));
        let params: Vec<SymbolId> = params
            .iter()
            .enumerate()
            .map(|(i, p)| self.param(p, pid, i, first))
            .collect();
        let param_words: i64 = params.iter().map(|&p| param_words(&self.sym(p).ty)).sum();
        if let Some(top) = self.space.last_mut() {
            top.0 += param_words;
        }
        self.open_procs.push(name.text.clone());
        self.push_frame();
        if let Some(body) = body {
            // A PROC's body is checked where it is declared, not where it runs.
            let outer = (self.valof_depth, self.high_priority);
            (self.valof_depth, self.high_priority) = (0, false);
            self.process(body);
            (self.valof_depth, self.high_priority) = outer;
        }
        if let Some(f) = function {
            self.param_names = if all_val { names.clone() } else { Vec::new() };
            let wanted = all_val;
            self.function_body(pid, f);
            if !wanted {
                self.fn_bodies.remove(&pid);
            }
        }
        let usage = self.pop_frame();
        if let Some(space) = self.space.pop() {
            self.spaces.insert(pid, space);
        }
        if function.is_some() {
            self.no_side_effects(&usage, first);
        }
        self.open_procs.pop();
        self.close_scope(mark);
        let usage = summarise(usage, first, &params);
        let kind = if function.is_some() {
            SymbolKind::Function(pid)
        } else {
            SymbolKind::Proc(pid)
        };
        let id = self.declare(name, kind, Type::Error, false);
        let info = &mut self.out.procs[pid];
        info.symbol = Some(id);
        info.params = params;
        info.usage = usage;
    }

    pub(super) fn param(
        &mut self,
        p: &ast::Param,
        owner: crate::checked::ProcId,
        index: usize,
        first: SymbolId,
    ) -> SymbolId {
        let ty = with_direction(self.ty(&p.ty), direction(p.dir));
        let assignable = p.mode != ParamMode::Val && ty.is_data();
        let kind = SymbolKind::Param {
            mode: p.mode,
            owner,
            index,
        };
        if self
            .scope
            .lookup(&p.name.text)
            .is_some_and(|id| id >= first)
        {
            self.error(
                DiagnosticKind::Duplicate {
                    name: p.name.text.clone(),
                },
                p.name.span,
            );
        }
        self.declare(&p.name, kind, ty, assignable)
    }

    fn function_body(&mut self, pid: crate::checked::ProcId, body: &ast::FunctionBody) {
        let results = self.out.procs[pid].results.clone();
        match body {
            ast::FunctionBody::Valof(v) => {
                let found = self.valof(v, &results);
                if found != results.len() {
                    self.error(
                        DiagnosticKind::ValueCount {
                            expected: results.len(),
                            found,
                        },
                        // At the RESULT, as occ21 reports it.
                        v.results.first().map_or(v.span, |e| e.span),
                    );
                }
            }
            ast::FunctionBody::Is(exprs) => {
                if exprs.len() != results.len() {
                    let span = exprs.first().map_or_else(Default::default, |e| e.span);
                    self.error(
                        DiagnosticKind::ValueCount {
                            expected: results.len(),
                            found: exprs.len(),
                        },
                        span,
                    );
                }
                for (e, want) in exprs.iter().zip(&results) {
                    let t = self.expr(e, Some(want));
                    self.expect_type(want, &t.ty, e.span);
                }
                if let [single] = exprs.as_slice() {
                    self.fn_bodies
                        .insert(pid, (self.param_names.clone(), single.clone()));
                }
            }
        }
    }
}

/// The workspace words a parameter takes: a word for its value or address, and one more for
/// the size of each open dimension of an array.
fn param_words(ty: &Type) -> i64 {
    match ty {
        Type::Array(None, e) => 1 + param_words(e),
        Type::Array(Some(_), e) => param_words(e).max(1),
        _ => 1,
    }
}

impl Checker {
    /// The words (32-bit, as `TARGET.BITS.PER.WORD` says) a local of type `ty` takes: its data
    /// rounded up to words, a word for each channel, timer or port.
    fn words(&self, ty: &Type) -> i64 {
        if let Ok(bytes) = crate::types::bytes_in(&self.out.types, ty) {
            return (i64::from(bytes) + 3) / 4;
        }
        match self.out.types.underlying(ty) {
            Type::Array(Some(n), e) => i64::from(*n).saturating_mul(self.words(e)),
            _ => 1,
        }
    }

    /// Counts a local variable in the workspace of the routine being checked.
    fn take_workspace(&mut self, id: SymbolId, ty: &Type) {
        if self.space.is_empty() || self.shadow > 0 {
            return;
        }
        let words = self.words(ty);
        self.local_words.insert(id, words);
        if let Some(top) = self.space.last_mut() {
            top.0 += words;
        }
    }

    /// `PLACE x IN VECSPACE:`: the words of `x` move from the workspace to the vector space.
    fn move_to_vecspace(&mut self, id: SymbolId) {
        if let Some(words) = self.local_words.remove(&id)
            && let Some(top) = self.space.last_mut()
        {
            top.0 -= words;
            top.1 += words;
        }
    }

    /// `WSSIZEOF(r)` / `VSSIZEOF(r)`: the workspace or vector space, in words, of a routine
    /// declared before this point, counted from the data it declares (its parameters and
    /// locals; a local placed `IN VECSPACE` counts in the vector space).
    pub(super) fn space_of(&mut self, which: &str, arg: &ast::Expr) -> Option<i64> {
        let ast::ExprKind::Name(n) = &arg.kind else {
            let op = if which == "WSSIZEOF" {
                "WSSIZEOF"
            } else {
                "VSSIZEOF"
            };
            self.error(
                DiagnosticKind::BadOperand {
                    op,
                    ty: "an expression: it takes the name of a PROC or FUNCTION".into(),
                },
                arg.span,
            );
            return None;
        };
        let id = self.lookup(n)?;
        let pid = match self.sym(id).kind {
            SymbolKind::Proc(pid) | SymbolKind::Function(pid) => pid,
            ref other => {
                let found = kind_name(other);
                self.error(
                    DiagnosticKind::WrongKind {
                        name: n.text.clone(),
                        expected: "a PROC or FUNCTION",
                        found,
                    },
                    arg.span,
                );
                return None;
            }
        };
        let (ws, vs) = self.spaces.get(&pid).copied().unwrap_or_default();
        Some(if which == "WSSIZEOF" { ws } else { vs })
    }
}

/// Keeps the accesses that matter outside a PROC body: to its parameters and to variables
/// declared before it. Subscripts that depend on the body's own replicators become whole.
fn summarise(mut usage: Vec<Access>, first: SymbolId, params: &[SymbolId]) -> Vec<Access> {
    usage.retain(|a| a.symbol < first || params.contains(&a.symbol));
    for a in &mut usage {
        match a.part {
            Part::Range { start, .. } if start.as_const().is_none() => a.part = Part::Whole,
            Part::Mapped { .. } => a.part = Part::Whole,
            _ => {}
        }
    }
    crate::usage::dedup(&mut usage);
    usage
}

/// Names a kind of symbol for messages ("a variable").
pub(super) fn kind_name(kind: &SymbolKind) -> &'static str {
    match kind {
        SymbolKind::Variable | SymbolKind::Abbrev { .. } | SymbolKind::Param { .. } => "a variable",
        SymbolKind::Val { .. } | SymbolKind::Replicator => "a constant",
        SymbolKind::Proc(_) => "a PROC",
        SymbolKind::Function(_) => "a FUNCTION",
        SymbolKind::DataType(_) => "a data type",
        SymbolKind::Protocol(_) => "a PROTOCOL",
        SymbolKind::Predefined(p) if p.is_proc() => "a predefined PROC",
        SymbolKind::Predefined(_) => "a predefined FUNCTION",
        SymbolKind::External(_) => "an EXTERNAL routine",
    }
}

/// The type of a name or a subscript of one (`[4]CHAN INT` for `cs`, `CHAN INT` for `cs[i]`),
/// from the declarations alone.
fn place_type(c: &Checker, e: &ast::Expr) -> Option<Type> {
    match &e.kind {
        ast::ExprKind::Name(n) => c.scope.lookup(&n.text).map(|id| c.sym(id).ty.clone()),
        ast::ExprKind::Subscript { base, .. } => match place_type(c, base)? {
            Type::Array(_, e) => Some(*e),
            _ => None,
        },
        _ => None,
    }
}

/// The declared type of the name an element starts from (`c` of `c[i][j]`).
fn root_type(c: &Checker, e: &ast::Expr) -> Option<Type> {
    match &e.kind {
        ast::ExprKind::Name(n) => c.scope.lookup(&n.text).map(|id| c.sym(id).ty.clone()),
        ast::ExprKind::Subscript { base, .. } => root_type(c, base),
        _ => None,
    }
}

/// The innermost element type of an array type.
fn elem_of(t: &Type) -> &Type {
    match t {
        Type::Array(_, e) => elem_of(e),
        t => t,
    }
}
