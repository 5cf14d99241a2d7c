//! Processes, including the PAR usage checks.

use occ_grammar::ast::{self, Expr, ExprKind, Process, ProcessKind};

use super::Checker;
use crate::consteval::Value;
use crate::diagnostic::{Diagnostic, DiagnosticKind};
use crate::types::Type;
use crate::usage::{self, Access, Conflict, Mode};

/// The name at the root of an element (`a` in `a[i][j]`), for messages.
pub(super) fn element_name(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Name(n) => n.text.clone(),
        ExprKind::Subscript { base, .. } | ExprKind::Slice { base, .. } => element_name(base),
        ExprKind::Directed { chan, .. } => element_name(chan),
        _ => "this expression".into(),
    }
}

impl Checker {
    /// Checks a process.
    pub(super) fn process(&mut self, p: &Process) {
        match &p.kind {
            ProcessKind::Skip | ProcessKind::Stop => {}
            ProcessKind::Asm(block) => self.asm(block, p.span),
            ProcessKind::Scope { decls, body } => {
                let mark = self.open_scope();
                self.decls(decls);
                self.process(body);
                self.close_scope(mark);
            }
            ProcessKind::Assign { lhs, rhs } => self.assign(lhs, rhs, p.span),
            ProcessKind::Output { chan, items } => self.output(chan, items, p.span),
            ProcessKind::Input { chan, items } => self.input(chan, items, p.span),
            ProcessKind::CaseInput { chan, variants } => self.case_input(chan, variants),
            ProcessKind::Extended {
                input,
                during,
                after,
            } => {
                match &input.kind {
                    ProcessKind::Input { chan, items } => {
                        self.extended_input(chan, items, input.span)
                    }
                    _ => self.process(input),
                }
                self.process(during);
                if let Some(after) = after {
                    self.process(after);
                }
            }
            ProcessKind::Delay { timer, time } => self.delay(timer, time),
            ProcessKind::Seq { repl, body } => {
                let mark = self.open_scope();
                let frame = self.frame_mark();
                let r = repl.as_ref().map(|r| self.replicator(r));
                body.iter().for_each(|b| self.process(b));
                if let Some(r) = r {
                    self.hull_since(frame, r.id);
                }
                self.close_scope(mark);
            }
            ProcessKind::Par {
                repl, body, pri, ..
            } => {
                self.not_in_valof("PAR", p.span);
                if *pri && self.high_priority {
                    self.error(DiagnosticKind::NestedPriPar, p.span);
                }
                self.par(repl.as_deref(), body, *pri);
            }
            ProcessKind::Processor { number, body } => {
                self.condition(number, &Type::INT);
                self.process(body);
            }
            ProcessKind::If { repl, choices } => self.if_(repl.as_deref(), choices),
            ProcessKind::Alt(alt) => {
                self.not_in_valof("ALT", p.span);
                self.alt(alt);
            }
            ProcessKind::Case { selector, options } => self.case(selector, options),
            ProcessKind::While { cond, body } => {
                self.condition(cond, &Type::BOOL);
                self.process(body);
            }
            ProcessKind::Call { name, args } => self.proc_call(name, args, p.span),
        }
    }

    /// Reports `what` (PAR or ALT) when it is inside a VALOF, where occam does not allow it.
    fn not_in_valof(&mut self, what: &'static str, span: ast::Span) {
        if self.valof_depth > 0 {
            self.error(DiagnosticKind::NotInValof { what }, span);
        }
    }

    /// Checks an expression that must have type `ty`.
    fn condition(&mut self, e: &Expr, ty: &Type) {
        let t = self.expr(e, Some(ty));
        self.expect_type(ty, &t.ty, e.span);
    }

    fn delay(&mut self, timer: &Expr, time: &Expr) {
        let p = self.place(timer, Some(Mode::Input));
        if !matches!(p.ty, Type::Timer | Type::Error) {
            let found = self.out.types.display(&p.ty);
            self.error(
                DiagnosticKind::TypeMismatch {
                    expected: "TIMER".into(),
                    found,
                },
                timer.span,
            );
        }
        self.condition(time, &Type::INT);
    }

    fn assign(&mut self, lhs: &[Expr], rhs: &[Expr], span: ast::Span) {
        if let ([_, _, ..], [single]) = (lhs, rhs)
            && let Some(tys) = self.multi_result(single, lhs)
        {
            if tys.len() != lhs.len() {
                self.error(
                    DiagnosticKind::ValueCount {
                        expected: lhs.len(),
                        found: tys.len(),
                    },
                    single.span,
                );
            }
            for (target, ty) in lhs.iter().zip(tys) {
                let p = self.target(target);
                self.expect_type(&p, &ty, target.span);
            }
            return;
        }
        if lhs.len() != rhs.len() {
            self.error(
                DiagnosticKind::ValueCount {
                    expected: lhs.len(),
                    found: rhs.len(),
                },
                span,
            );
        }
        let targets: Vec<Type> = lhs.iter().map(|t| self.target(t)).collect();
        for (i, e) in rhs.iter().enumerate() {
            let want = targets.get(i);
            let t = self.expr(e, want);
            if let Some(w) = want {
                self.expect_type(w, &t.ty, e.span);
            }
        }
    }

    /// The result types of a multi-result FUNCTION call or VALOF on the right of `a, b := ...`.
    fn multi_result(&mut self, e: &Expr, lhs: &[Expr]) -> Option<Vec<Type>> {
        match &e.kind {
            ExprKind::Call { name, args } => {
                let is_type = self.scope.lookup(&name.text).is_some_and(|id| {
                    matches!(self.sym(id).kind, crate::checked::SymbolKind::DataType(_))
                });
                if is_type {
                    return None;
                }
                Some(
                    self.call_function(name, args, e.span)
                        .unwrap_or_else(|| vec![Type::Error; lhs.len()]),
                )
            }
            ExprKind::Valof(v) => Some(self.valof_types(v, &[])),
            _ => None,
        }
    }

    /// Checks an assignment target and returns its type.
    fn target(&mut self, e: &Expr) -> Type {
        let p = self.place(e, Some(Mode::Write));
        if !p.assignable && !p.ty.is_error() {
            self.error(
                DiagnosticKind::NotAssignable {
                    name: element_name(e),
                },
                e.span,
            );
        }
        p.ty
    }

    fn if_(&mut self, repl: Option<&ast::Replicator>, choices: &[ast::Choice]) {
        let mark = self.open_scope();
        let frame = self.frame_mark();
        let r = repl.map(|r| self.replicator(r));
        for c in choices {
            let inner = self.open_scope();
            self.decls(&c.decls);
            match &c.kind {
                ast::ChoiceKind::Guarded { cond, body } => {
                    self.condition(cond, &Type::BOOL);
                    let instance = self.instance_guard(cond);
                    if let Some(g) = instance {
                        self.conditions.push(g);
                    }
                    self.process(body);
                    if instance.is_some() {
                        self.conditions.pop();
                    }
                }
                ast::ChoiceKind::Nested(p) => self.process(p),
            }
            self.close_scope(inner);
        }
        if let Some(r) = r {
            self.hull_since(frame, r.id);
        }
        self.close_scope(mark);
    }

    /// Recognises a guard `i = c` (or `c = i`) on a replicator index `i` with known values: the
    /// guarded process runs only in the instance where `i` is `c`.
    fn instance_guard(&self, cond: &Expr) -> Option<(crate::checked::SymbolId, i64)> {
        let ExprKind::Binary {
            op: ast::BinOp::Eq,
            lhs,
            rhs,
        } = &cond.kind
        else {
            return None;
        };
        let side = |name: &Expr, value: &Expr| {
            let ExprKind::Name(n) = &name.kind else {
                return None;
            };
            let id = *self.out.names.get(&n.span)?;
            let known = self.repl_values.contains_key(&id);
            let c = self
                .out
                .constants
                .get(&value.span)
                .and_then(Value::as_int)?;
            known.then_some((id, c))
        };
        side(lhs, rhs).or_else(|| side(rhs, lhs))
    }

    fn alt(&mut self, alt: &ast::Alt) {
        let mark = self.open_scope();
        let frame = self.frame_mark();
        let r = alt.repl.as_ref().map(|r| self.replicator(r));
        for a in &alt.alternatives {
            let inner = self.open_scope();
            self.decls(&a.decls);
            match &a.kind {
                ast::AltKind::Guarded { cond, guard, body } => {
                    if let Some(c) = cond {
                        self.condition(c, &Type::BOOL);
                    }
                    self.process(guard);
                    self.process(body);
                }
                ast::AltKind::CaseInput {
                    cond,
                    chan,
                    variants,
                } => {
                    if let Some(c) = cond {
                        self.condition(c, &Type::BOOL);
                    }
                    self.case_input(chan, variants);
                }
                ast::AltKind::Nested(inner_alt) => self.alt(inner_alt),
            }
            self.close_scope(inner);
        }
        if let Some(r) = r {
            self.hull_since(frame, r.id);
        }
        self.close_scope(mark);
    }

    fn case(&mut self, selector: &Expr, options: &[ast::CaseOption]) {
        let t = self.expr(selector, None);
        let ok = self
            .out
            .types
            .prim(&t.ty)
            .is_some_and(|p| p.is_integer() || p == crate::types::Prim::Bool);
        if !ok && !t.ty.is_error() {
            let ty = self.out.types.display(&t.ty);
            self.error(DiagnosticKind::BadOperand { op: "CASE", ty }, selector.span);
        }
        let mut seen: Vec<Value> = Vec::new();
        for extra in options.iter().filter(|o| o.values.is_none()).skip(1) {
            self.error(DiagnosticKind::DuplicateElse, extra.span);
        }
        for o in options {
            let mark = self.open_scope();
            self.decls(&o.decls);
            for v in o.values.iter().flatten() {
                let vt = self.expr(v, Some(&t.ty));
                self.expect_type(&t.ty, &vt.ty, v.span);
                match vt.value {
                    Some(val) if seen.contains(&val) => {
                        let value = self
                            .out
                            .constants
                            .get(&v.span)
                            .map_or_else(String::new, show);
                        self.error(DiagnosticKind::DuplicateOption { value }, v.span);
                    }
                    Some(val) => seen.push(val),
                    None if !vt.ty.is_error() => self.error(
                        DiagnosticKind::NotConstant {
                            context: "a CASE option",
                        },
                        v.span,
                    ),
                    None => {}
                }
            }
            self.process(&o.body);
            self.close_scope(mark);
        }
    }

    /// Checks a PAR: each branch separately, then every pair of branches (and, for a
    /// replicated PAR, every pair of instances) against the usage rules.
    /// Checks a PAR's branches and the usage rules between them; in a PRI PAR the first
    /// branch runs at high priority.
    fn par(&mut self, repl: Option<&ast::Replicator>, body: &[Process], pri: bool) {
        let first = self.next_symbol();
        let mark = self.open_scope();
        let r = repl.map(|r| self.replicator(r));
        let mut branches: Vec<Vec<Access>> = Vec::with_capacity(body.len());
        let outer = self.high_priority;
        for (k, p) in body.iter().enumerate() {
            self.push_frame();
            self.high_priority = outer || (pri && repl.is_none() && k == 0);
            self.process(p);
            self.high_priority = outer;
            let mut accesses = self.pop_frame();
            accesses.retain(|a| a.symbol < first);
            usage::dedup(&mut accesses);
            branches.push(accesses);
        }
        let mut found = Vec::new();
        for (j, later) in branches.iter().enumerate() {
            for earlier in branches.iter().take(j) {
                found.extend(usage::conflicts(&self.tables, earlier, later, None, &|s| {
                    self.exempt(s)
                }));
            }
            if let Some(r) = &r {
                let values = r.values(256);
                let across = Some((r.id, values.as_deref()));
                found.extend(usage::conflicts(&self.tables, later, later, across, &|s| {
                    self.exempt(s)
                }));
            }
        }
        self.report_conflicts(&found);
        self.close_scope(mark);
        let frame = self.frame_mark();
        for branch in branches {
            self.extend_frame(branch);
        }
        if let Some(r) = r {
            self.hull_since(frame, r.id);
        }
    }

    /// Reports whether a symbol is exempt from the PAR rules: timers and `#PRAGMA SHARED` names.
    fn exempt(&self, s: crate::checked::SymbolId) -> bool {
        let sym = self.sym(s);
        let mut ty = &sym.ty;
        while let Type::Array(_, e) = ty {
            ty = e;
        }
        matches!(ty, Type::Timer) || self.shared.contains(&sym.name)
    }

    fn report_conflicts(&mut self, found: &[Conflict]) {
        if !self.options.usage {
            return;
        }
        let mut reported: Vec<crate::checked::SymbolId> = Vec::new();
        for c in found {
            if reported.contains(&c.here.symbol) {
                continue;
            }
            reported.push(c.here.symbol);
            let name = self.sym(c.here.symbol).name.clone();
            let kind = match c.here.mode {
                Mode::Input => DiagnosticKind::ParChannel {
                    name,
                    used_for: "input",
                },
                Mode::Output => DiagnosticKind::ParChannel {
                    name,
                    used_for: "output",
                },
                _ => DiagnosticKind::ParUsage { name },
            };
            let verb = |m: Mode| match m {
                Mode::Write => "written",
                Mode::Read => "used",
                Mode::Input => "input",
                Mode::Output => "output",
            };
            let d = Diagnostic::error(kind, c.here.span)
                .with_label(format!("{} in this branch", verb(c.here.mode)))
                .with_related(
                    c.other.span,
                    format!("{} in another branch", verb(c.other.mode)),
                );
            self.diags.push(d);
        }
    }
}

/// Renders a constant for messages.
fn show(v: &Value) -> String {
    match v {
        Value::Bool(b) => if *b { "TRUE" } else { "FALSE" }.into(),
        Value::Int(i) => i.to_string(),
        Value::Real32(x) => x.to_string(),
        Value::Real64(x) => x.to_string(),
        Value::Array(_) | Value::Record(_) => "(table)".into(),
    }
}
