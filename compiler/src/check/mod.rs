//! The checking pass: one walk over the AST that resolves names, computes types and constant
//! values, and records usage for the PAR and alias rules.
//!
//! occam declares every name before its use, so resolution and typing need only one pass in
//! source order. The walk never stops at an error: a name or expression with an error gets
//! [`Type::Error`], which is compatible with everything, so one mistake gives one message.
//!
//! Invariants:
//! - every symbol is declared in `out.symbols` before anything refers to it, so symbol ids grow
//!   in declaration order and "declared outside this PAR" is `id < first id of the PAR`;
//! - `frames` always has at least one frame; accesses are recorded in the innermost;
//! - `abbreviated` lists, innermost last, the storage that a live abbreviation names.

mod asm;
mod call;
mod decl;
mod expr;
mod external;
mod io;
mod operator;
mod place;
mod process;
mod scope;
#[cfg(test)]
#[rustfmt::skip]
mod test;

use std::collections::HashSet;

use occ_grammar::ast::{self, Span};

use crate::checked::{CheckedProgram, Symbol, SymbolId, SymbolKind};
use crate::diagnostic::{Diagnostic, DiagnosticKind};
use crate::entity::EntityRef;
use crate::predefined::PREDEFINED;
use crate::types::Type;
use crate::usage::{Access, Mode, Part, may_overlap};
use scope::Scope;

/// A live constraint from an abbreviation: while it is in scope, `target` may not be used
/// directly (reference abbreviation) or changed (VAL abbreviation of a variable).
#[derive(Debug, Clone, Copy)]
struct Abbreviated {
    /// The storage the abbreviation names.
    target: Access,
    /// The abbreviation's own symbol (accesses through it are fine).
    alias: SymbolId,
    /// VAL abbreviation: only writes to the target are errors.
    val: bool,
}

/// The checker's state.
pub(crate) struct Checker {
    /// What the checker produces.
    pub out: CheckedProgram,
    /// Every diagnostic so far.
    pub diags: Vec<Diagnostic>,
    scope: Scope,
    frames: Vec<Vec<Access>>,
    /// PROCs and FUNCTIONs whose bodies are being checked (for the recursion message).
    open_procs: Vec<String>,
    shared: HashSet<String>,
    permit_aliases: HashSet<String>,
    abbreviated: Vec<Abbreviated>,
    /// Inside `SIZE` / `BYTESIN` operands, which name storage without using it.
    quiet: u32,
    options: Options,
    /// The parameter names of the FUNCTION being declared.
    param_names: Vec<ast::Name>,
    /// Inside the type of a RETYPES/RESHAPES, whose array sizes may be variables.
    dynamic_sizes: bool,
    /// Above zero while folding a FUNCTION call: expression tables are not written.
    shadow: u32,
    /// The labels of the `ASM` blocks checked so far, with their offsets in the program's code
    /// image (`LDLABELDIFF` may name a label of an earlier block).
    asm_labels: Vec<(String, usize)>,
    /// Replicators with a constant count and step whose base is a linear form (not a constant).
    repl_forms: crate::fxhash::FxHashMap<SymbolId, (crate::usage::Lin, i64, i64)>,
    /// Inside the right operand of `FALSE AND ...` / `TRUE OR ...`, which is never evaluated:
    /// constant range errors there are not errors (occ21 folds the operator first).
    dead: u32,
    /// Linear forms of VAL abbreviations of subscript-like expressions (`VAL ii IS i:`).
    val_lin: crate::fxhash::FxHashMap<SymbolId, crate::usage::Lin>,
    /// `IF i = c` guards being checked, innermost last: accesses in them happen only in the
    /// instance where the replicator `i` is `c`.
    conditions: Vec<(SymbolId, i64)>,
    /// Constants found while folding (the shadow of `out.constants`).
    shadow_constants: crate::fxhash::FxHashMap<Span, crate::consteval::Value>,
    /// The `IS` bodies of FUNCTIONs with one result, for folding calls with constant actuals.
    fn_bodies: crate::fxhash::FxHashMap<crate::checked::ProcId, (Vec<ast::Name>, ast::Expr)>,
    /// Abbreviations declared before this symbol are ignored by the alias check (see calls).
    alias_floor: Option<SymbolId>,
    /// Tables of non-linear subscripts evaluated per replicator value.
    tables: crate::usage::Tables,
    /// Index values of replicators with constant base, count and step (and a small count).
    repl_values: crate::fxhash::FxHashMap<SymbolId, Vec<i64>>,
    /// Above zero inside a VALOF (a FUNCTION body or value process): no PAR or ALT there.
    valof_depth: u32,
    /// Inside the first (high-priority) branch of a PRI PAR: no PRI PAR there.
    high_priority: bool,
    /// The workspace and vector space, in words, of each routine being checked, innermost last.
    space: Vec<(i64, i64)>,
    /// The words each local variable takes, for `PLACE x IN VECSPACE:`.
    local_words: crate::fxhash::FxHashMap<SymbolId, i64>,
    /// The finished workspace and vector space of each routine, for `WSSIZEOF` / `VSSIZEOF`.
    spaces: crate::fxhash::FxHashMap<crate::checked::ProcId, (i64, i64)>,
}

/// Checks that a program can switch off, as occ21's `#OPTION` letters do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Apply the PAR usage rules (`#OPTION "N"` switches them off).
    pub usage: bool,
    /// Apply the alias rules (`#OPTION "A"` switches them off).
    pub alias: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            usage: true,
            alias: true,
        }
    }
}

impl Options {
    /// Reads the letters of a program's `#OPTION` directives, as the preprocessor records them
    /// ([`occ_grammar::Parsed::options`]): `A` switches alias checking off and `N` usage
    /// checking, as in occ21. Other letters are accepted and ignored.
    pub fn from_letters(letters: &str) -> Options {
        let mut o = Options::default();
        for ch in letters.chars() {
            match ch.to_ascii_uppercase() {
                'A' => o.alias = false,
                'N' => o.usage = false,
                _ => {}
            }
        }
        o
    }
}

/// Checks a program; see [`crate::check`].
pub(crate) fn run(program: &ast::Program, options: Options) -> (CheckedProgram, Vec<Diagnostic>) {
    let mut c = Checker::new(program);
    c.options = options;
    // Size the span tables from the text size once rather than rehashing as they grow
    // (about one expression per 10 bytes of occam).
    let bytes = program.decls.iter().map(|d| d.span.end).max().unwrap_or(0);
    c.out.expr_types.reserve(bytes / 10);
    c.out.names.reserve(bytes / 14);
    c.out.constants.reserve(bytes / 40);
    c.externals(&program.pragmas);
    c.scope.open();
    for decl in &program.decls {
        c.decl(decl);
    }
    c.scope.close();
    (c.out, c.diags)
}

impl Checker {
    fn new(program: &ast::Program) -> Self {
        let mut c = Checker {
            out: CheckedProgram::default(),
            diags: Vec::new(),
            scope: Scope::default(),
            frames: vec![Vec::new()],
            open_procs: Vec::new(),
            shared: HashSet::new(),
            permit_aliases: HashSet::new(),
            abbreviated: Vec::new(),
            quiet: 0,
            options: Options::default(),
            alias_floor: None,
            dynamic_sizes: false,
            param_names: Vec::new(),
            shadow: 0,
            asm_labels: Vec::new(),
            repl_forms: Default::default(),
            dead: 0,
            conditions: Vec::new(),
            val_lin: Default::default(),
            shadow_constants: Default::default(),
            fn_bodies: Default::default(),
            tables: Vec::new(),
            repl_values: Default::default(),
            valof_depth: 0,
            high_priority: false,
            space: Vec::new(),
            local_words: Default::default(),
            spaces: Default::default(),
        };
        for pragma in &program.pragmas {
            let set = match pragma.kind {
                ast::PragmaKind::Shared => &mut c.shared,
                ast::PragmaKind::PermitAliases => &mut c.permit_aliases,
                ast::PragmaKind::External => continue,
            };
            set.extend(pragma.names.iter().map(|n| n.text.clone()));
        }
        c.scope.open();
        for p in PREDEFINED {
            let kind = SymbolKind::Predefined(p);
            let id = c.new_symbol(p.name, Span::default(), kind, Type::Error, false);
            c.scope.declare(p.name, id);
        }
        c
    }

    /// Reports an error.
    fn error(&mut self, kind: DiagnosticKind, span: Span) {
        let range = matches!(
            kind,
            DiagnosticKind::OutOfBounds { .. } | DiagnosticKind::ConstantError { .. }
        );
        if self.dead > 0 && range {
            return;
        }
        self.diags.push(Diagnostic::error(kind, span));
    }

    /// Reports a type mismatch unless `found` may be used where `expected` is needed.
    fn expect_type(&mut self, expected: &Type, found: &Type, span: Span) -> bool {
        if self.out.types.compatible(expected, found) {
            return true;
        }
        let kind = DiagnosticKind::TypeMismatch {
            expected: self.out.types.display(expected),
            found: self.out.types.display(found),
        };
        self.error(kind, span);
        false
    }

    /// Creates a symbol without declaring it in scope.
    fn new_symbol(
        &mut self,
        name: &str,
        span: Span,
        kind: SymbolKind,
        ty: Type,
        assignable: bool,
    ) -> SymbolId {
        self.out.symbols.push(Symbol {
            name: name.to_string(),
            span,
            kind,
            ty,
            assignable,
            alias_of: None,
        })
    }

    /// Creates a symbol and declares it in the innermost scope.
    fn declare(
        &mut self,
        name: &ast::Name,
        kind: SymbolKind,
        ty: Type,
        assignable: bool,
    ) -> SymbolId {
        let id = self.new_symbol(&name.text, name.span, kind, ty, assignable);
        self.scope.declare(&name.text, id);
        self.out.names.insert(name.span, id);
        id
    }

    /// Resolves a name, reporting it when undeclared.
    fn lookup(&mut self, name: &ast::Name) -> Option<SymbolId> {
        match self.scope.lookup(&name.text) {
            Some(id) => {
                if self.shadow == 0 {
                    self.out.names.insert(name.span, id);
                }
                Some(id)
            }
            None => {
                let kind = if self.open_procs.contains(&name.text) {
                    DiagnosticKind::Recursion {
                        name: name.text.clone(),
                    }
                } else {
                    DiagnosticKind::Undeclared {
                        name: name.text.clone(),
                    }
                };
                self.error(kind, name.span);
                None
            }
        }
    }

    /// Returns the symbol.
    fn sym(&self, id: SymbolId) -> &Symbol {
        &self.out.symbols[id]
    }

    /// The id the next symbol will get: everything below it is declared already.
    fn next_symbol(&self) -> SymbolId {
        SymbolId::new(self.out.symbols.len())
    }

    /// Opens a scope (for declarations).
    fn open_scope(&mut self) -> usize {
        self.scope.open();
        self.abbreviated.len()
    }

    /// Closes a scope opened by [`Checker::open_scope`].
    fn close_scope(&mut self, mark: usize) {
        self.scope.close();
        self.abbreviated.truncate(mark);
    }

    /// Records an access, following reference abbreviations to the storage they name, and
    /// checks it against live abbreviations.
    fn record(&mut self, symbol: SymbolId, mode: Mode, part: Part, span: Span) {
        if self.quiet > 0 {
            return;
        }
        let only = self.conditions.last().copied();
        let (access, hops) = self.resolve_alias(Access {
            symbol,
            mode,
            part,
            span,
            only,
        });
        self.check_alias(access, &hops);
        if let Some(frame) = self.frames.last_mut() {
            frame.push(access);
        }
    }

    /// Follows reference abbreviations from an access to the storage it touches; returns that
    /// access and the abbreviations passed through.
    fn resolve_alias(&mut self, mut access: Access) -> (Access, Vec<SymbolId>) {
        let mut hops: Vec<SymbolId> = Vec::new();
        for _ in 0..32 {
            match self.sym(access.symbol).alias_of {
                Some(target) => {
                    hops.push(access.symbol);
                    let part = self.nest(target.part, access.part);
                    access = Access {
                        symbol: target.symbol,
                        part,
                        ..access
                    };
                }
                None => break,
            }
        }
        (access, hops)
    }

    /// Reports a direct use of storage that a live abbreviation names.
    /// Returns `false` when it reported one.
    fn check_alias(&mut self, access: Access, hops: &[SymbolId]) -> bool {
        if !self.options.alias {
            return true;
        }
        let name = &self.sym(access.symbol).name;
        if self.permit_aliases.contains(name) {
            return true;
        }
        let clash = self.abbreviated.iter().rev().find(|a| {
            a.target.symbol == access.symbol
                && self.alias_floor.is_none_or(|f| a.alias > f)
                && !hops.contains(&a.alias)
                && (!a.val || access.mode == Mode::Write)
                && may_overlap(&self.tables, a.target.part, access.part)
        });
        if let Some(a) = clash {
            let alias_span = self.sym(a.alias).span;
            let d = Diagnostic::error(DiagnosticKind::Alias { name: name.clone() }, access.span)
                .with_related(alias_span, "abbreviated here");
            self.diags.push(d);
            return false;
        }
        true
    }

    /// Starts collecting accesses separately (a PAR branch or a PROC body).
    fn push_frame(&mut self) {
        self.frames.push(Vec::new());
    }

    /// Stops collecting separately and returns what was collected.
    fn pop_frame(&mut self) -> Vec<Access> {
        self.frames.pop().unwrap_or_default()
    }

    /// Returns a mark for [`Checker::hull_since`].
    fn frame_mark(&self) -> usize {
        self.frames.last().map_or(0, Vec::len)
    }

    /// When a replicator goes out of scope, replaces the parts of the accesses recorded since
    /// `mark` that depend on its index by the hull of what they touch over all its values.
    fn hull_since(&mut self, mark: usize, index: SymbolId) {
        let values = self.repl_values.get(&index);
        let form = self.repl_forms.get(&index).copied();
        let Some(frame) = self.frames.last_mut() else {
            return;
        };
        for a in frame.iter_mut().skip(mark) {
            if a.only.is_some_and(|(v, _)| v == index) {
                a.only = None;
            }
            a.part = match (values, form) {
                (None, Some((base, count, step))) => {
                    crate::usage::hull_symbolic(a.part, index, base, count, step)
                }
                _ => crate::usage::hull(&self.tables, a.part, index, values.map(Vec::as_slice)),
            };
        }
    }

    /// Reports changes to storage declared outside a FUNCTION body or VALOF (before symbol
    /// `first`): occam expressions have no side effects. Timers are exempt.
    fn no_side_effects(&mut self, usage: &[Access], first: SymbolId) {
        let mut reported: Vec<SymbolId> = Vec::new();
        for a in usage {
            let outside = a.symbol < first && a.mode != Mode::Read;
            if !outside
                || reported.contains(&a.symbol)
                || matches!(self.sym(a.symbol).ty, Type::Timer)
            {
                continue;
            }
            reported.push(a.symbol);
            let name = self.sym(a.symbol).name.clone();
            self.error(DiagnosticKind::SideEffect { name }, a.span);
        }
    }

    /// Adds accesses to the innermost frame.
    fn extend_frame(&mut self, accesses: impl IntoIterator<Item = Access>) {
        if let Some(frame) = self.frames.last_mut() {
            frame.extend(accesses);
        }
    }
}
