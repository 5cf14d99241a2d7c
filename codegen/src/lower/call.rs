//! PROC declarations and calls (frame chain), FUNCTION calls (expanded inline: FUNCTIONs cannot
//! block), VALOF, and calls of native intrinsics.

use cranelift_codegen::ir::{InstBuilder, Value, types};
use cranelift_module::Module;
use occ_compiler::checked::{SymbolId, SymbolKind};
use occ_compiler::types::Type;
use occ_grammar::ast::{
    Decl, DeclKind, Expr, ExprKind, FunctionBody, Name, Param, ParamMode, Span, Valof,
};
use occ_runtime::abi::{Entry, frame, slot, word_offset};
use occ_runtime::intrinsic::{self, ParamKind};

use super::{Compiler, ProcEntry, Res, Storage, Tr, mem};
use crate::frame::Frame;
use crate::layout::{is_scalar, rank};

impl<'p> Compiler<'p> {
    /// Compiles PROC declaration `d` whose body is at lexical `depth`, and binds its name.
    pub fn compile_proc(&mut self, d: &Decl, depth: u32) -> Res<()> {
        let DeclKind::Proc {
            name, params, body, ..
        } = &d.kind
        else {
            return Err(self.internal(d.span, "not a PROC"));
        };
        let sym = self.symbol(name)?;
        let mut frame = Frame::default();
        let mut slots = Vec::new();
        let mut types = Vec::new();
        for p in params {
            let (off, by_value, ty) = self.param_slot(p, &mut frame)?;
            let psym = self.symbol(&p.name)?;
            let st = if by_value {
                Storage::Var { depth, offset: off }
            } else {
                Storage::Ref { depth, offset: off }
            };
            self.env.insert(psym, st);
            slots.push((off, by_value));
            types.push(ty);
        }
        let outer = std::mem::replace(&mut self.proc_name, name.text.clone());
        let r = self.function(&name.text, depth, frame, d.span, |tr| {
            tr.process(body)?;
            // Word 1 is 0 for a called PROC; for a PROC started directly as a PAR branch it
            // is the join block, and the PROC ends the branch.
            let j =
                tr.b.ins()
                    .load(types::I64, mem(), tr.ws, word_offset(frame::JOIN));
            let endp = tr.b.create_block();
            let done = tr.b.create_block();
            tr.b.ins().brif(j, endp, &[], done, &[]);
            tr.b.switch_to_block(endp);
            let st = tr.call_rt(Entry::Endp, &[tr.node, tr.ws, j]);
            tr.ret(st);
            tr.b.switch_to_block(done);
            let zero = tr.iconst(0);
            tr.ret(zero);
            Ok(())
        });
        self.proc_name = outer;
        let (id, size) = r?;
        let entry = ProcEntry {
            id,
            size,
            depth,
            params: slots,
            param_types: types,
        };
        self.env.insert(sym, Storage::Proc(entry));
        Ok(())
    }

    fn param_slot(&mut self, p: &Param, frame: &mut Frame) -> Res<(i32, bool, Type)> {
        let sym = self.symbol(&p.name)?;
        let ty = self.checked.symbols[sym].ty.clone();
        let by_value = p.mode == ParamMode::Val && is_scalar(&self.checked.types, &ty);
        let words = if by_value { 1 } else { 1 + rank(&ty) };
        Ok((frame.alloc_words(words), by_value, ty))
    }
}

impl Tr<'_, '_> {
    /// Lowers a PROC call.
    pub fn call_proc(&mut self, name: &Name, args: &[Expr], span: Span) -> Res<()> {
        let sym = self.cx.symbol(name)?;
        let st = self.cx.env.get(&sym).cloned();
        let entry = match st {
            Some(Storage::Proc(e)) => e,
            _ => {
                if let Some(i) = self.cx.externals.get(&sym).copied() {
                    self.call_intrinsic(i, args, span)?;
                    return Ok(());
                }
                if let SymbolKind::Predefined(p) = &self.cx.checked.symbols[sym].kind {
                    return self.predefined_proc(p, args, span);
                }
                if let Some(i) = intrinsic::intrinsic(&name.text) {
                    self.call_intrinsic(i, args, span)?;
                    return Ok(());
                }
                return Err(self
                    .cx
                    .unsupported(span, format!("call of `{}`", name.text)));
            }
        };
        // Evaluate the actuals first (they may need temporaries), then place the callee's
        // workspace above everything allocated.
        let stores = self.eval_actuals(&entry, args)?;
        self.call_with(&entry, stores, span)
    }

    /// Calls the PROC `entry` with its actuals' values stored (as [`Self::store_actuals`]
    /// takes them) in a workspace placed above everything allocated.
    pub(super) fn call_with(
        &mut self,
        entry: &ProcEntry,
        stores: Vec<(i32, Vec<Value>)>,
        span: Span,
    ) -> Res<()> {
        let cw_off = self.frame.sub_workspace(entry.size);
        let cw = self.local_addr(cw_off);
        self.store_actuals(entry, cw, stores);
        let zero = self.iconst(0);
        self.b
            .ins()
            .store(mem(), zero, cw, word_offset(frame::JOIN));
        self.enter_frame(cw, entry.id);
        self.call_native(entry.id, cw, span)
    }

    /// Evaluates the actuals of a call of `entry`: each parameter slot's words.
    pub fn eval_actuals(
        &mut self,
        entry: &ProcEntry,
        args: &[Expr],
    ) -> Res<Vec<(i32, Vec<Value>)>> {
        let mut stores = Vec::new();
        for (i, a) in args.iter().enumerate() {
            let (off, by_value) = entry.params[i];
            if by_value {
                let v = self.expr(a)?;
                let v = match self.cx.checked.types.prim(&entry.param_types[i]) {
                    Some(p) => self.coerce(v, crate::layout::cl_type(p)),
                    None => v,
                };
                stores.push((off, vec![v]));
            } else {
                let l = self.place(a)?;
                let mut vs = vec![l.addr];
                let r = rank(&entry.param_types[i]);
                for k in 0..r {
                    let d = l.dims.get(k).copied().unwrap_or_else(|| self.iconst(0));
                    vs.push(d);
                }
                stores.push((off, vs));
            }
        }
        Ok(stores)
    }

    /// Stores evaluated actuals and the static link into the callee frame `cw`.
    pub fn store_actuals(&mut self, entry: &ProcEntry, cw: Value, stores: Vec<(i32, Vec<Value>)>) {
        for (off, vs) in stores {
            for (k, v) in vs.into_iter().enumerate() {
                self.b
                    .ins()
                    .store(mem(), v, cw, off + word_offset(k as isize));
            }
        }
        let link = if entry.depth <= 1 {
            self.iconst(0)
        } else {
            self.frame_at(entry.depth - 1)
        };
        self.b.ins().store(mem(), link, cw, 0);
    }

    /// Fills in a callee frame's header: CODE, IPTR = 0, CALLER = ws, ROOT = ws[ROOT].
    pub(super) fn enter_frame(&mut self, cw: Value, id: cranelift_module::FuncId) {
        let f = self.func_ref(id);
        let code = self.b.ins().func_addr(types::I64, f);
        self.store_slot_at(cw, slot::CODE, code);
        let zero = self.iconst(0);
        self.store_slot_at(cw, slot::IPTR, zero);
        self.store_slot_at(cw, slot::CALLER, self.ws);
        let root = self.load_slot(slot::ROOT);
        self.store_slot_at(cw, slot::ROOT, root);
    }

    /// Lowers a FUNCTION call (inline expansion) and returns its results.
    pub fn call_function(&mut self, name: &Name, args: &[Expr], span: Span) -> Res<Vec<Value>> {
        let sym = self.cx.symbol(name)?;
        if let Some(i) = self.cx.externals.get(&sym).copied() {
            return self.call_intrinsic(i, args, span);
        }
        if let SymbolKind::Predefined(p) = &self.cx.checked.symbols[sym].kind {
            return self.predefined_function(p, args, span);
        }
        if let Some(i) = intrinsic::intrinsic(&name.text) {
            return self.call_intrinsic(i, args, span);
        }
        let d = match self.cx.env.get(&sym) {
            Some(Storage::Function(d)) => d.clone(),
            _ => {
                // A conversion to a named type written `T (x)`.
                if let SymbolKind::DataType(id) = &self.cx.checked.symbols[sym].kind
                    && args.len() == 1
                {
                    let to = self
                        .cx
                        .checked
                        .types
                        .prim(&Type::Named(*id))
                        .ok_or_else(|| self.cx.unsupported(span, "conversion to a record"))?;
                    let from = self.prim_of(&args[0])?;
                    let v = self.expr(&args[0])?;
                    let mode = occ_grammar::ast::ConvMode::Plain;
                    return Ok(vec![self.convert(v, from, to, mode, span)?]);
                }
                return Err(self
                    .cx
                    .unsupported(span, format!("call of `{}`", name.text)));
            }
        };
        let args: Vec<&Expr> = args.iter().collect();
        self.expand_function(&d, &args, span)
    }

    /// Lowers an operator expression `e` that calls the user-defined operator FUNCTION `sym`
    /// (the checker's `operators` table) and returns its results.
    pub fn call_operator(&mut self, sym: SymbolId, e: &Expr) -> Res<Vec<Value>> {
        let args: Vec<&Expr> = match &e.kind {
            ExprKind::Unary { operand, .. } => vec![operand],
            ExprKind::Binary { lhs, rhs, .. } => vec![lhs, rhs],
            _ => return Err(self.cx.internal(e.span, "operator call of a non-operator")),
        };
        let Some(Storage::Function(d)) = self.cx.env.get(&sym).cloned() else {
            return Err(self.cx.internal(e.span, "operator FUNCTION not compiled"));
        };
        self.expand_function(&d, &args, e.span)
    }

    /// Expands the FUNCTION declared by `d` inline with the actuals `args`.
    fn expand_function(&mut self, d: &Decl, args: &[&Expr], span: Span) -> Res<Vec<Value>> {
        let DeclKind::Function { params, .. } = &d.kind else {
            return Err(self.cx.internal(span, "not a FUNCTION"));
        };
        let mut binds = Vec::new();
        for (p, a) in params.iter().zip(args) {
            let psym = self.cx.symbol(&p.name)?;
            let ty = self.cx.checked.symbols[psym].ty.clone();
            if is_scalar(&self.cx.checked.types, &ty) {
                binds.push((psym, None, Some(self.expr(a)?)));
            } else {
                binds.push((psym, Some(self.place(a)?), None));
            }
        }
        self.expand_bound(d, binds, span)
    }

    /// Expands the FUNCTION declared by `d` inline with scalar actuals already evaluated
    /// (an `ASM` block's `CALL`).
    pub(super) fn expand_function_values(
        &mut self,
        d: &Decl,
        values: &[Value],
        span: Span,
    ) -> Res<Vec<Value>> {
        let DeclKind::Function { params, .. } = &d.kind else {
            return Err(self.cx.internal(span, "not a FUNCTION"));
        };
        let mut binds = Vec::new();
        for (p, v) in params.iter().zip(values) {
            binds.push((self.cx.symbol(&p.name)?, None, Some(*v)));
        }
        self.expand_bound(d, binds, span)
    }

    /// Expands FUNCTION `d` with its formals bound: references to places, values to frame
    /// words.
    fn expand_bound(
        &mut self,
        d: &Decl,
        binds: Vec<(SymbolId, Option<super::Loc>, Option<Value>)>,
        span: Span,
    ) -> Res<Vec<Value>> {
        let DeclKind::Function { body, .. } = &d.kind else {
            return Err(self.cx.internal(span, "not a FUNCTION"));
        };
        let result_exprs = match body {
            FunctionBody::Is(es) => &es[..],
            FunctionBody::Valof(v) => &v.results[..],
        };
        let slots = self.result_slots(result_exprs)?;
        let mark = self.frame.mark();
        for (psym, l, v) in binds {
            match (l, v) {
                (Some(l), _) => self.bind_ref(psym, &l),
                (None, Some(v)) => {
                    let off = self.frame.alloc_word();
                    let a = self.local_addr(off);
                    self.store_scalar(v, a);
                    self.cx.env.insert(
                        psym,
                        Storage::Var {
                            depth: self.depth,
                            offset: off,
                        },
                    );
                }
                _ => {}
            }
        }
        let out = match body {
            FunctionBody::Is(es) => self.results(es, &slots)?,
            FunctionBody::Valof(v) => self.valof_into(v, &slots)?,
        };
        self.frame.release(mark);
        Ok(out)
    }

    /// Frame temporaries for the array- and record-valued results among `results` (`None` for
    /// scalars), allocated before the FUNCTION's or VALOF's own locals so that they outlive them.
    fn result_slots(&mut self, results: &[Expr]) -> Res<Vec<Option<Value>>> {
        let mut slots = Vec::with_capacity(results.len());
        for e in results {
            let ty = self.cx.type_of(e)?;
            if is_scalar(&self.cx.checked.types, &ty) {
                slots.push(None);
                continue;
            }
            let size = crate::layout::size_of(&self.cx.checked.types, &ty).ok_or_else(|| {
                self.cx
                    .unsupported(e.span, "an array-valued result whose size is not constant")
            })?;
            let off = self.frame.alloc(size);
            slots.push(Some(self.local_addr(off)));
        }
        Ok(slots)
    }

    /// Evaluates result expressions: scalars as values, arrays and records copied into their
    /// slot, whose address stands for them.
    fn results(&mut self, es: &[Expr], slots: &[Option<Value>]) -> Res<Vec<Value>> {
        let mut out = Vec::with_capacity(es.len());
        for (e, slot) in es.iter().zip(slots) {
            match slot {
                None => out.push(self.expr(e)?),
                Some(dst) => {
                    let src = self.value_loc(e)?;
                    let size = self.loc_size(&src, e.span)?;
                    self.copy_bytes(*dst, src.addr, size);
                    out.push(*dst);
                }
            }
        }
        Ok(out)
    }

    /// Lowers a VALOF and returns its results: scalars as values, arrays and records as the
    /// address of a copy that outlives the VALOF's locals.
    pub fn valof(&mut self, v: &Valof) -> Res<Vec<Value>> {
        let slots = self.result_slots(&v.results)?;
        self.valof_into(v, &slots)
    }

    fn valof_into(&mut self, v: &Valof, slots: &[Option<Value>]) -> Res<Vec<Value>> {
        self.in_expr += 1;
        let mark = self.frame.mark();
        let r = (|| {
            for d in &v.decls {
                self.decl(d)?;
            }
            self.process(&v.body)?;
            self.results(&v.results, slots)
        })();
        self.frame.release(mark);
        self.in_expr -= 1;
        r
    }

    /// Calls a native intrinsic with occam actuals (arrays by address and length, written
    /// scalars through a word temporary copied back after the call).
    pub fn call_intrinsic(
        &mut self,
        i: &'static intrinsic::Intrinsic,
        args: &[Expr],
        span: Span,
    ) -> Res<Vec<Value>> {
        if args.len() != i.params.len() {
            return Err(self.cx.internal(span, "intrinsic argument count"));
        }
        let mut vals = Vec::new();
        for (k, a) in i.params.iter().zip(args) {
            match k {
                ParamKind::ValInt | ParamKind::ValByte | ParamKind::ValBool => {
                    let v = self.expr(a)?;
                    vals.push(self.widen_i64(v, a));
                }
                ParamKind::ValReal32 | ParamKind::ValReal64 => vals.push(self.expr(a)?),
                ParamKind::ResultInt
                | ParamKind::ResultReal32
                | ParamKind::ResultReal64
                | ParamKind::ResultBool => {
                    // The intrinsic reads and writes a temporary word holding the variable's
                    // value (so a reference `INT x` is in/out); it is copied back below.
                    let off = self.frame.alloc_word();
                    let t = self.local_addr(off);
                    let zero = self.iconst(0);
                    self.b.ins().store(mem(), zero, t, 0);
                    let v = self.expr(a)?;
                    let v = match k {
                        ParamKind::ResultReal32 | ParamKind::ResultReal64 => v,
                        _ => self.widen_i64(v, a),
                    };
                    self.b.ins().store(mem(), v, t, 0);
                    vals.push(t);
                }
                _ => {
                    let l = self.place(a)?;
                    vals.push(l.addr);
                    vals.push(l.dims.first().copied().unwrap_or_else(|| self.iconst(0)));
                }
            }
        }
        let Some(&id) = self.cx.jit.intrinsics.get(i.name) else {
            return Err(self.cx.internal(span, "intrinsic not declared in the JIT"));
        };
        let f = self.cx.jit.module.declare_func_in_func(id, self.b.func);
        let c = self.b.ins().call(f, &vals);
        let results = self.b.inst_results(c).to_vec();
        self.copy_back(i, args, &vals)?;
        Ok(results)
    }

    /// Copies written scalar results from their temporaries to the actual variables.
    fn copy_back(&mut self, i: &intrinsic::Intrinsic, args: &[Expr], vals: &[Value]) -> Res<()> {
        let mut vi = 0;
        for (k, a) in i.params.iter().zip(args) {
            let v = match k {
                ParamKind::ResultInt => {
                    let w = self.b.ins().load(types::I64, mem(), vals[vi], 0);
                    let t = crate::layout::cl_type(self.prim_of(a)?);
                    Some(if t == types::I64 {
                        w
                    } else {
                        self.b.ins().ireduce(t, w)
                    })
                }
                ParamKind::ResultBool => {
                    let w = self.b.ins().load(types::I64, mem(), vals[vi], 0);
                    Some(self.b.ins().ireduce(types::I8, w))
                }
                ParamKind::ResultReal32 => Some(self.b.ins().load(types::F32, mem(), vals[vi], 0)),
                ParamKind::ResultReal64 => Some(self.b.ins().load(types::F64, mem(), vals[vi], 0)),
                _ => None,
            };
            if let Some(v) = v {
                let l = self.place(a)?;
                self.store_scalar(v, l.addr);
            }
            vi += k.machine().len();
        }
        Ok(())
    }
}
