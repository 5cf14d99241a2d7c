//! Declarations: variables (channels cleared to empty), abbreviations, RETYPES, nested PROCs
//! and FUNCTIONs; types and protocols need no code.

use cranelift_codegen::ir::{InstBuilder, types};
use occ_compiler::checked::SymbolKind;
use occ_compiler::types::Type;
use occ_grammar::ast::{AbbrevMode, Decl, DeclKind, Expr, ExprKind, Name};
use occ_runtime::abi::{Entry, word_offset};

use super::{Loc, Res, Storage, Tr, mem};
use crate::frame::{VECTOR_BYTES, vector_cost};
use crate::layout::{WORD, base_elem, is_scalar, rank, resolve, size_of, static_dims};

impl Tr<'_, '_> {
    /// Lowers declaration `d`: allocates and binds its names.
    pub fn decl(&mut self, d: &Decl) -> Res<()> {
        match &d.kind {
            DeclKind::Var { names, .. } => names.iter().try_for_each(|n| self.var(n)),
            DeclKind::Abbrev {
                mode, name, value, ..
            } => {
                let sym = self.cx.symbol(name)?;
                let s = &self.cx.checked.symbols[sym];
                if let SymbolKind::Val { value: Some(c) } = &s.kind {
                    self.cx.env.insert(sym, Storage::Const(c.clone()));
                    return Ok(());
                }
                let ty = s.ty.clone();
                match mode {
                    AbbrevMode::Val if is_scalar(&self.cx.checked.types, &ty) => {
                        let v = self.expr(value)?;
                        let off = self.frame.alloc_word();
                        let a = self.local_addr(off);
                        self.store_scalar(v, a);
                        self.bind(sym, off, false);
                    }
                    AbbrevMode::Initial => {
                        let off = self.alloc_var(&ty, name)?;
                        let a = self.local_addr(off);
                        self.assign_to(a, &ty, &[], value)?;
                        self.bind(sym, off, false);
                    }
                    _ => match &value.kind {
                        ExprKind::Table(items) if self.is_chan_table(&ty) => {
                            self.chan_table(sym, items)?;
                        }
                        _ => {
                            let l = self.place(value)?;
                            self.bind_ref(sym, &l);
                        }
                    },
                }
                Ok(())
            }
            DeclKind::Retypes {
                name,
                value,
                ty: written,
                ..
            } => {
                let sym = self.cx.symbol(name)?;
                let ty = crate::layout::resolve(
                    &self.cx.checked.types,
                    &self.cx.checked.symbols[sym].ty,
                );
                if let Some(kind) = self.cx.checked.chan_retypes.get(&name.span).copied() {
                    return self.chan_retype(sym, ty, kind, value);
                }
                let src = self.place(value)?;
                let size = self.loc_size(&src, value.span)?;
                self.retype(sym, ty, written, src.addr, size)
            }
            DeclKind::DataType { .. } | DeclKind::Protocol { .. } => Ok(()),
            DeclKind::Proc { name, .. } if !self.cx.needed(name)? => Ok(()),
            DeclKind::Function { name, .. } if !self.cx.needed(name)? => Ok(()),
            DeclKind::Proc { .. } => {
                let depth = self.depth + 1;
                self.cx.compile_proc(d, depth)
            }
            DeclKind::Function { name, .. } => {
                let sym = self.cx.symbol(name)?;
                self.cx
                    .env
                    .insert(sym, Storage::Function(std::rc::Rc::new(d.clone())));
                Ok(())
            }
            // A channel placed at a link address (`PLACE c AT 4:`), as Inmos configurations
            // write it: the network's links come from which processors use the channel, so
            // the address adds nothing. Placing data at a memory address is not supported.
            DeclKind::Place { name, .. } => {
                let sym = self.cx.symbol(name)?;
                let ty = &self.cx.checked.symbols[sym].ty;
                if matches!(crate::layout::base_elem(ty), Type::Chan(..)) {
                    Ok(())
                } else {
                    Err(self.cx.unsupported(d.span, "PLACE of data at an address"))
                }
            }
            DeclKind::Asm(_) => Err(self.cx.unsupported(d.span, "ASM / GUY blocks")),
            DeclKind::PlaceIn { .. } => Ok(()),
            #[allow(unreachable_patterns)]
            _ => Err(self.cx.unsupported(d.span, "this declaration")),
        }
    }

    /// Binds `sym` of type `ty` (as written: `written`) to the bytes at `addr` of length `size`:
    /// static dimensions as declared, written lengths evaluated, one open dimension from the size.
    fn retype(
        &mut self,
        sym: occ_compiler::checked::SymbolId,
        ty: Type,
        written: &occ_grammar::ast::Ty,
        addr: cranelift_codegen::ir::Value,
        size: cranelift_codegen::ir::Value,
    ) -> Res<()> {
        let sd = crate::layout::static_dims(&ty);
        let mut lens = Vec::new();
        let mut t = written;
        while let occ_grammar::ast::TyKind::Array { len, elem } = &t.kind {
            lens.push(len.as_deref());
            t = elem;
        }
        let base = size_of(&self.cx.checked.types, crate::layout::base_elem(&ty)).unwrap_or(1);
        let mut dims: Vec<Option<cranelift_codegen::ir::Value>> = Vec::new();
        for (i, d) in sd.iter().enumerate() {
            let v = match (d, lens.get(i).copied().flatten()) {
                (Some(n), _) => Some(self.iconst(i64::from(*n))),
                (None, Some(e)) => Some(self.int_index(e)?),
                (None, None) => None,
            };
            dims.push(v);
        }
        // The open dimension (if any) takes what is left.
        let mut known = self.iconst(base.max(1));
        for v in dims.iter().flatten() {
            known = self.b.ins().imul(known, *v);
        }
        let one = self.iconst(1);
        let known = self.b.ins().umax(known, one);
        let rest = self.b.ins().udiv(size, known);
        let dims = dims.into_iter().map(|d| d.unwrap_or(rest)).collect();
        let l = Loc { addr, ty, dims };
        self.bind_ref(sym, &l);
        Ok(())
    }

    /// A RETYPES between a channel and an INT: the channel's address as an INT (a frame word),
    /// or the channel at the address an INT holds (see `asm.rs` for the address model).
    fn chan_retype(
        &mut self,
        sym: occ_compiler::checked::SymbolId,
        ty: Type,
        kind: occ_compiler::checked::ChanRetype,
        value: &occ_grammar::ast::Expr,
    ) -> Res<()> {
        match kind {
            occ_compiler::checked::ChanRetype::ToInt => {
                let c = self.place(value)?.addr;
                let v = self.int_address(c, value.span);
                let v = self.b.ins().ireduce(types::I32, v);
                let off = self.frame.alloc_word();
                let a = self.local_addr(off);
                self.store_scalar(v, a);
                self.bind(sym, off, false);
            }
            occ_compiler::checked::ChanRetype::FromInt => {
                let v = self.expr(value)?;
                let addr = self.int_pointer(v, 0, crate::layout::WORD, value.span);
                let l = Loc {
                    addr,
                    ty,
                    dims: Vec::new(),
                };
                self.bind_ref(sym, &l);
            }
        }
        Ok(())
    }

    /// Lowers a declaration of a scope (`decl:` before a process): as [`Self::decl`], but a
    /// variable of a data array of [`VECTOR_BYTES`] or more is a vector, taken from the node's
    /// memory here and given back by [`Self::free_vectors`] when the scope ends.
    pub fn scope_decl(&mut self, d: &Decl) -> Res<()> {
        let DeclKind::Var { names, .. } = &d.kind else {
            return self.decl(d);
        };
        for n in names {
            let sym = self.cx.symbol(n)?;
            let ty = resolve(&self.cx.checked.types, &self.cx.checked.symbols[sym].ty);
            let data = !matches!(
                base_elem(&ty),
                Type::Chan(..) | Type::Timer | Type::Port(_) | Type::Error
            );
            match size_of(&self.cx.checked.types, &ty) {
                Some(bytes)
                    if data
                        && bytes >= VECTOR_BYTES
                        && self.in_expr == 0
                        && !self.asm_takes_addresses() =>
                {
                    self.vector(sym, &ty, bytes, n.span)?;
                }
                _ => self.var(n)?,
            }
        }
        Ok(())
    }

    /// Whether an `ASM` block of the program takes an address (`LD ADDRESSOF x`, `LDLP x`): an
    /// address is a 32-bit offset from the node's first workspace chunk, which a vector taken
    /// later may lie too far from, so such a program keeps its large arrays in its frames.
    fn asm_takes_addresses(&self) -> bool {
        self.cx.checked.asm.values().any(|code| {
            code.ops
                .iter()
                .any(|op| matches!(op, occ_compiler::checked::AsmOp::Address(_)))
        })
    }

    /// Binds `sym`, an array of `bytes`, to memory taken from the node as this runs.
    fn vector(
        &mut self,
        sym: occ_compiler::checked::SymbolId,
        ty: &Type,
        bytes: i64,
        span: occ_grammar::ast::Span,
    ) -> Res<()> {
        let dims = static_dims(ty);
        let off = self.frame.alloc_words(1 + dims.len());
        let a = self.local_addr(off);
        for (i, n) in dims.iter().enumerate() {
            let n = self.iconst(i64::from(n.unwrap_or(0)));
            self.b.ins().store(mem(), n, a, word_offset(i as isize + 1));
        }
        let loc = self.cx.location(span);
        let (size, loc) = (self.iconst(bytes), self.iconst(i64::from(loc)));
        self.blocking(Entry::VectorGet, &[self.node, self.ws, size, a, loc], span)?;
        self.frame.hold_vectors(vector_cost(bytes));
        self.vectors.push((off, bytes));
        self.bind(sym, off, true);
        Ok(())
    }

    /// Gives back the vectors of the scopes opened since `open` vectors were held.
    pub fn free_vectors(&mut self, open: usize) {
        for (off, bytes) in self.vectors.split_off(open).into_iter().rev() {
            let a = self.local_addr(off);
            let v = self.b.ins().load(types::I64, mem(), a, 0);
            let size = self.iconst(bytes);
            self.call_rt(Entry::VectorFree, &[self.node, v, size]);
        }
    }

    fn alloc_var(&mut self, ty: &Type, name: &Name) -> Res<i32> {
        let size = size_of(&self.cx.checked.types, ty).ok_or_else(|| {
            self.cx
                .internal(name.span, format!("`{}` has no static size", name.text))
        })?;
        Ok(self.frame.alloc(size))
    }

    fn var(&mut self, n: &Name) -> Res<()> {
        let sym = self.cx.symbol(n)?;
        let ty = self.cx.checked.symbols[sym].ty.clone();
        let off = self.alloc_var(&ty, n)?;
        if matches!(crate::layout::base_elem(&ty), Type::Chan(..)) {
            // Channel words start empty.
            let size = size_of(&self.cx.checked.types, &ty).unwrap_or(WORD);
            self.channels.push(occ_runtime::program::ChannelName {
                offset: i64::from(off) / WORD,
                count: (size / WORD) as u32,
                name: n.text.clone(),
            });
            if size <= 64 {
                let zero = self.iconst(0);
                for i in 0..size / WORD {
                    let a = self.local_addr(off + word_offset(i as isize));
                    self.b.ins().store(mem(), zero, a, 0);
                }
            } else {
                let a = self.local_addr(off);
                let zero = self.b.ins().iconst(types::I8, 0);
                let n = self.iconst(size);
                let cfg = self.cx.jit.module_target_config();
                self.b.call_memset(cfg, a, zero, n);
            }
        }
        self.bind(sym, off, false);
        Ok(())
    }

    fn bind(&mut self, sym: occ_compiler::checked::SymbolId, offset: i32, by_ref: bool) {
        let st = if by_ref {
            Storage::Ref {
                depth: self.depth,
                offset,
            }
        } else {
            Storage::Var {
                depth: self.depth,
                offset,
            }
        };
        self.cx.env.insert(sym, st);
    }

    /// Reports whether `ty` is a one-dimensional array of channels.
    fn is_chan_table(&self, ty: &Type) -> bool {
        let ty = crate::layout::resolve(&self.cx.checked.types, ty);
        matches!(ty.elem(), Some(Type::Chan(..)))
    }

    /// Binds `sym` to a table of the addresses of the channels `items`.
    fn chan_table(&mut self, sym: occ_compiler::checked::SymbolId, items: &[Expr]) -> Res<()> {
        if self.consecutive_channels(items) {
            // `[a[0], a[1], a[2]]` is the segment `[a FROM 0 FOR 3]`: bound as that segment,
            // it can be passed whole as an array of channels.
            let first = self.place(&items[0])?;
            let ty = Type::Array(Some(items.len() as u32), Box::new(first.ty));
            let n = self.iconst(items.len() as i64);
            let l = Loc {
                addr: first.addr,
                ty,
                dims: vec![n],
            };
            self.bind_ref(sym, &l);
            return Ok(());
        }
        let off = self.frame.alloc_words(items.len());
        for (k, item) in items.iter().enumerate() {
            let l = self.place(item)?;
            let a = self.local_addr(off);
            self.b
                .ins()
                .store(mem(), l.addr, a, word_offset(k as isize));
        }
        let st = Storage::ChanTable {
            depth: self.depth,
            offset: off,
            len: items.len() as u32,
        };
        self.cx.env.insert(sym, st);
        Ok(())
    }

    /// Whether `items` are `a[k]`, `a[k + 1]`, ... of one array `a` of channels, with constant
    /// subscripts.
    fn consecutive_channels(&self, items: &[Expr]) -> bool {
        let mut prev: Option<(occ_compiler::checked::SymbolId, i64)> = None;
        for item in items {
            let ExprKind::Subscript { base, index } = &item.kind else {
                return false;
            };
            let ExprKind::Name(n) = &base.kind else {
                return false;
            };
            let (Ok(sym), Some(k)) = (
                self.cx.symbol(n),
                self.cx
                    .checked
                    .constants
                    .get(&index.span)
                    .and_then(|c| c.as_int()),
            ) else {
                return false;
            };
            if prev.is_some_and(|(s, j)| s != sym || j + 1 != k) {
                return false;
            }
            prev = Some((sym, k));
        }
        prev.is_some()
    }

    /// Binds `sym` by reference to place `l` (address and dimension lengths in the frame).
    pub fn bind_ref(&mut self, sym: occ_compiler::checked::SymbolId, l: &Loc) {
        let words = 1 + rank(&l.ty).max(l.dims.len());
        let off = self.frame.alloc_words(words);
        let a = self.local_addr(off);
        self.b.ins().store(mem(), l.addr, a, 0);
        for (i, d) in l.dims.iter().enumerate() {
            let d = if self.b.func.dfg.value_type(*d) == types::I64 {
                *d
            } else {
                self.b.ins().sextend(types::I64, *d)
            };
            self.b.ins().store(mem(), d, a, word_offset(i as isize + 1));
        }
        self.bind(sym, off, true);
    }
}
