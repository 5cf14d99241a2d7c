//! PROC and FUNCTION calls, VALOF, and replicators.

use occ_grammar::ast::{self, Expr, ParamMode};

use super::Checker;
use super::expr::Typed;
use crate::checked::{ProcId, SymbolId, SymbolKind};
use crate::consteval::Value;
use crate::diagnostic::{Diagnostic, DiagnosticKind};
use crate::predefined::Predefined;
use crate::types::{Direction, Type};
use crate::usage::{Access, Mode, may_overlap};

/// A formal parameter as the call site sees it.
struct Formal {
    mode: ParamMode,
    ty: Type,
    /// The accesses the callee makes through this parameter.
    modes: Vec<Mode>,
}

/// A checked replicator.
pub(super) struct Repl {
    /// The index symbol.
    pub id: SymbolId,
    /// The first value, when constant.
    pub base: Option<i64>,
    /// The count, when constant.
    pub count: Option<i64>,
    /// The step, when constant (1 when absent).
    pub step: Option<i64>,
}

impl Repl {
    /// The index values, when base, count and step are constant and the count is small.
    pub fn values(&self, limit: i64) -> Option<Vec<i64>> {
        let (b, n, s) = (self.base?, self.count?, self.step?);
        (0..=limit).contains(&n).then(|| {
            (0..n)
                .map(|k| b.saturating_add(k.saturating_mul(s)))
                .collect()
        })
    }
}

impl Checker {
    /// Checks a replicator and declares its index in the current scope.
    pub(super) fn replicator(&mut self, r: &ast::Replicator) -> Repl {
        let int = |c: &mut Checker, e: &Expr| {
            let t = c.expr(e, Some(&Type::INT));
            c.expect_type(&Type::INT, &t.ty, e.span);
            t.value.as_ref().and_then(crate::consteval::Value::as_int)
        };
        let base = int(self, &r.base);
        let count = int(self, &r.count);
        let step = match &r.step {
            Some(s) => int(self, s),
            None => Some(1),
        };
        if let Some(n) = count.filter(|n| *n < 0) {
            let what = format!("replicator count {n} is negative");
            self.error(DiagnosticKind::ConstantError { what }, r.count.span);
        }
        let id = self.declare(&r.name, SymbolKind::Replicator, Type::INT, false);
        let repl = Repl {
            id,
            base,
            count,
            step,
        };
        if let Some(values) = repl.values(256) {
            self.repl_values.insert(id, values);
        } else if let (Some(n), Some(s), Some(b)) = (count, step, self.linear(&r.base)) {
            // `SEQ j = i * 10 FOR 5`: the values are `base + k*step`, base a linear form.
            self.repl_forms.insert(id, (b, n, s));
        }
        repl
    }

    /// Checks a VALOF and returns its result types, checking them against `wants` when given.
    pub(super) fn valof_types(&mut self, v: &ast::Valof, wants: &[Type]) -> Vec<Type> {
        let mark = self.open_scope();
        self.valof_depth += 1;
        self.decls(&v.decls);
        self.process(&v.body);
        self.valof_depth -= 1;
        let mut tys = Vec::with_capacity(v.results.len());
        for (i, r) in v.results.iter().enumerate() {
            let want = wants.get(i);
            let t = self.expr(r, want);
            if let Some(w) = want {
                self.expect_type(w, &t.ty, r.span);
            }
            tys.push(t.ty);
        }
        self.close_scope(mark);
        tys
    }

    /// Checks a VALOF body of a FUNCTION against its result types; returns the result count.
    pub(super) fn valof(&mut self, v: &ast::Valof, wants: &[Type]) -> usize {
        self.valof_types(v, wants).len()
    }

    /// Checks a FUNCTION call (or `T (x)` conversion) in an expression.
    pub(super) fn call_expr(
        &mut self,
        name: &ast::Name,
        args: &[Expr],
        want: Option<&Type>,
        span: ast::Span,
    ) -> Typed {
        if let Some(id) = self.scope.lookup(&name.text)
            && let SymbolKind::DataType(d) = self.sym(id).kind
            && let [arg] = args
        {
            self.out.names.insert(name.span, id);
            return self.conversion(Type::Named(d), ast::ConvMode::Plain, arg, span);
        }
        let _ = want;
        if matches!(name.text.as_str(), "WSSIZEOF" | "VSSIZEOF")
            && self.scope.lookup(&name.text).is_none()
            && let [arg] = args
        {
            let value = self.space_of(&name.text, arg).map(Value::Int);
            return Typed {
                ty: if value.is_some() {
                    Type::INT
                } else {
                    Type::Error
                },
                value,
                target: None,
            };
        }
        let results = self.call_function(name, args, span);
        match results.as_deref() {
            Some([one]) => Typed {
                ty: one.clone(),
                value: self.fold_call(name, args),
                target: None,
            },
            Some(many) => {
                self.error(
                    DiagnosticKind::ValueCount {
                        expected: 1,
                        found: many.len(),
                    },
                    span,
                );
                Typed {
                    ty: Type::Error,
                    value: None,
                    target: None,
                }
            }
            None => Typed {
                ty: Type::Error,
                value: None,
                target: None,
            },
        }
    }

    /// Folds a call of a one-result `IS` FUNCTION whose actuals are all constants, by checking
    /// its body again with the parameters bound to the actuals (occ21 folds these too:
    /// `[sum (1, 2)]INT a:`). Leaves no trace: no tables written, no diagnostics kept.
    fn fold_call(&mut self, name: &ast::Name, args: &[Expr]) -> Option<Value> {
        let id = self.scope.lookup(&name.text)?;
        let SymbolKind::Function(pid) = self.sym(id).kind else {
            return None;
        };
        let (params, body) = self.fn_bodies.get(&pid)?.clone();
        let table = if self.shadow > 0 {
            &self.shadow_constants
        } else {
            &self.out.constants
        };
        let values: Option<Vec<Value>> = args.iter().map(|a| table.get(&a.span).cloned()).collect();
        let values = values.filter(|v| v.len() == params.len())?;
        if self.shadow > 8 {
            return None;
        }
        let result = self.out.procs[pid].results.first().cloned();
        let (diags, mark) = (self.diags.len(), self.open_scope());
        for ((p, v), formal) in params
            .iter()
            .zip(values)
            .zip(self.out.procs[pid].params.clone())
        {
            let ty = self.sym(formal).ty.clone();
            let sym = self.new_symbol(
                &p.text,
                p.span,
                SymbolKind::Val { value: Some(v) },
                ty,
                false,
            );
            self.scope.declare(&p.text, sym);
        }
        self.shadow += 1;
        self.quiet += 1;
        let t = self.expr(&body, result.as_ref());
        self.quiet -= 1;
        self.shadow -= 1;
        if self.shadow == 0 {
            self.shadow_constants.clear();
        }
        self.close_scope(mark);
        self.diags.truncate(diags);
        t.value
    }

    /// Checks a FUNCTION call and returns its result types (`None` after an error).
    pub(super) fn call_function(
        &mut self,
        name: &ast::Name,
        args: &[Expr],
        span: ast::Span,
    ) -> Option<Vec<Type>> {
        let Some(id) = self.lookup(name) else {
            self.unknown_args(args);
            return None;
        };
        match self.sym(id).kind.clone() {
            SymbolKind::Function(pid) => {
                let formals = self.formals(pid);
                self.args(name, &formals, args, Some(pid), span);
                Some(self.out.procs[pid].results.clone())
            }
            SymbolKind::External(pid) if !self.out.procs[pid].results.is_empty() => {
                let formals = self.formals(pid);
                self.args(name, &formals, args, Some(pid), span);
                Some(self.out.procs[pid].results.clone())
            }
            SymbolKind::Predefined(p) if !p.is_proc() => {
                self.args(name, &predefined_formals(p), args, None, span);
                Some(p.results.iter().map(|r| Type::Prim(*r)).collect())
            }
            other => {
                let found = super::decl::kind_name(&other);
                let kind = DiagnosticKind::WrongKind {
                    name: name.text.clone(),
                    expected: "a FUNCTION",
                    found,
                };
                self.error(kind, name.span);
                self.unknown_args(args);
                None
            }
        }
    }

    /// Checks a PROC call.
    pub(super) fn proc_call(&mut self, name: &ast::Name, args: &[Expr], span: ast::Span) {
        let Some(id) = self.lookup(name) else {
            self.unknown_args(args);
            return;
        };
        match self.sym(id).kind.clone() {
            SymbolKind::Proc(pid) => {
                let formals = self.formals(pid);
                self.args(name, &formals, args, Some(pid), span);
            }
            SymbolKind::External(pid) if self.out.procs[pid].results.is_empty() => {
                let formals = self.formals(pid);
                self.args(name, &formals, args, Some(pid), span);
            }
            SymbolKind::Predefined(p) if p.is_proc() => {
                self.args(name, &predefined_formals(p), args, None, span)
            }
            other => {
                let found = super::decl::kind_name(&other);
                let kind = DiagnosticKind::WrongKind {
                    name: name.text.clone(),
                    expected: "a PROC",
                    found,
                };
                self.error(kind, name.span);
                self.unknown_args(args);
            }
        }
    }

    /// Checks the actuals of a call to something unknown, for their own errors.
    fn unknown_args(&mut self, args: &[Expr]) {
        for a in args {
            if super::place::is_element(a) {
                self.place(a, None);
            } else {
                self.expr(a, None);
            }
        }
    }

    fn formals(&self, pid: ProcId) -> Vec<Formal> {
        let info = &self.out.procs[pid];
        info.params
            .iter()
            .map(|&p| {
                let sym = self.sym(p);
                let mode = match sym.kind {
                    SymbolKind::Param { mode, .. } => mode,
                    _ => ParamMode::Val,
                };
                let modes = info
                    .usage
                    .iter()
                    .filter(|a| a.symbol == p)
                    .map(|a| a.mode)
                    .collect();
                Formal {
                    mode,
                    ty: sym.ty.clone(),
                    modes,
                }
            })
            .collect()
    }

    /// Checks actuals against formals, records the accesses the call makes (through reference
    /// parameters and to the callee's free variables) and checks reference actuals for aliasing.
    fn args(
        &mut self,
        name: &ast::Name,
        formals: &[Formal],
        args: &[Expr],
        pid: Option<ProcId>,
        span: ast::Span,
    ) {
        if formals.len() != args.len() {
            let kind = DiagnosticKind::ArgumentCount {
                name: name.text.clone(),
                expected: formals.len(),
                found: args.len(),
            };
            self.error(kind, span);
        }
        let mut refs: Vec<Access> = Vec::new();
        for (i, a) in args.iter().enumerate() {
            let Some(f) = formals.get(i) else {
                self.unknown_args(std::slice::from_ref(a));
                continue;
            };
            if let Some(t) = self.actual(f, a) {
                refs.push(t);
            }
        }
        self.check_ref_aliases(&refs);
        if let Some(pid) = pid {
            self.free_variables_of(pid, span);
        }
    }

    /// Records, at a call of `pid`, the accesses its body makes to variables declared outside it.
    pub(super) fn free_variables_of(&mut self, pid: ProcId, span: ast::Span) {
        let first_param = self.out.procs[pid].params.first().copied();
        let free: Vec<Access> = self.out.procs[pid]
            .usage
            .iter()
            .filter(|a| first_param.is_none_or(|p| a.symbol < p))
            .copied()
            .collect();
        // The body was checked against the abbreviations in scope where it was declared;
        // only those declared since can be aliased by this call.
        self.alias_floor = self.out.procs[pid].symbol;
        for a in free {
            self.record(a.symbol, a.mode, a.part, span);
        }
        self.alias_floor = None;
    }

    /// Checks one actual; returns the storage a data reference parameter names.
    fn actual(&mut self, f: &Formal, a: &Expr) -> Option<Access> {
        if f.mode == ParamMode::Val {
            let t = self.expr(a, Some(&f.ty));
            self.expect_type(&f.ty, &t.ty, a.span);
            return None;
        }
        let p = self.place(a, None);
        self.expect_type(&f.ty, &p.ty, a.span);
        let data = f.ty.is_data();
        if data && !p.assignable {
            let name = super::process::element_name(a);
            self.error(DiagnosticKind::NotAssignable { name }, a.span);
        }
        let target = p.target?;
        let mut modes = f.modes.clone();
        if data && modes.is_empty() {
            modes.push(if f.mode == ParamMode::Result {
                Mode::Write
            } else {
                Mode::Read
            });
        }
        for m in modes {
            self.check_direction(&p.ty, m, a);
            self.record(target.symbol, m, target.part, a.span);
        }
        data.then_some(Access {
            span: a.span,
            ..target
        })
    }

    /// Reports a channel end used against the direction of the actual channel.
    pub(super) fn check_direction(&mut self, ty: &Type, mode: Mode, at: &Expr) {
        let Type::Chan(_, dir) = ty else { return };
        let bad = match mode {
            Mode::Input => *dir == Direction::Output,
            Mode::Output => *dir == Direction::Input,
            _ => false,
        };
        if bad {
            let used_for = if mode == Mode::Input {
                "input"
            } else {
                "output"
            };
            let name = super::process::element_name(at);
            self.error(DiagnosticKind::Direction { name, used_for }, at.span);
        }
    }

    /// Two reference actuals naming overlapping storage are aliases.
    fn check_ref_aliases(&mut self, refs: &[Access]) {
        if !self.options.alias {
            return;
        }
        for (i, a) in refs.iter().enumerate() {
            let name = self.sym(a.symbol).name.clone();
            if self.permit_aliases.contains(&name) {
                continue;
            }
            if let Some(b) = refs
                .iter()
                .take(i)
                .find(|b| b.symbol == a.symbol && may_overlap(&self.tables, a.part, b.part))
            {
                let d = Diagnostic::error(DiagnosticKind::Alias { name }, a.span)
                    .with_related(b.span, "also passed here");
                self.diags.push(d);
            }
        }
    }
}

fn predefined_formals(p: &Predefined) -> Vec<Formal> {
    p.params
        .iter()
        .map(|(by_ref, t)| Formal {
            mode: if *by_ref {
                ParamMode::Ref
            } else {
                ParamMode::Val
            },
            ty: t.to_type(),
            modes: if *by_ref {
                vec![Mode::Write]
            } else {
                Vec::new()
            },
        })
        .collect()
}
