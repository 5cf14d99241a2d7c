//! Routines declared by `#PRAGMA EXTERNAL` (implemented by native intrinsics).
//!
//! Contract:
//! - Every EXTERNAL is declared at the outermost level (just inside the predefined routines),
//!   before the program's first declaration, wherever its pragma stands; so a program may call it
//!   from anywhere and may redeclare its name.
//! - Its symbol is [`SymbolKind::External`] with a [`crate::checked::ProcInfo`] like a PROC's or
//!   FUNCTION's: calls are checked the same way (count, types, modes).
//! - Its usage summary says it writes every non-VAL parameter and touches nothing else (an
//!   intrinsic sees only its parameters).
//! - Parameter and result types must be primitive or arrays of primitives (named types are not
//!   in scope at the outermost level).

use occ_grammar::ast::{self, ParamMode};

use super::Checker;
use crate::checked::{ProcInfo, SymbolKind};
use crate::types::Type;
use crate::usage::{Access, Mode, Part};

impl Checker {
    /// Declares the routine of every `#PRAGMA EXTERNAL` whose header parsed.
    pub(super) fn externals(&mut self, pragmas: &[ast::Pragma]) {
        for e in pragmas.iter().filter_map(|p| p.external.as_ref()) {
            self.external(e);
        }
    }

    fn external(&mut self, e: &ast::External) {
        let results: Vec<Type> = e.results.iter().map(|t| self.ty(t)).collect();
        let pid = self.out.procs.push(ProcInfo {
            name: e.name.text.clone(),
            symbol: None,
            span: e.header,
            params: Vec::new(),
            results,
            usage: Vec::new(),
        });
        let mark = self.open_scope();
        let first = self.next_symbol();
        let params: Vec<_> = e
            .params
            .iter()
            .enumerate()
            .map(|(i, p)| self.param(p, pid, i, first))
            .collect();
        self.close_scope(mark);
        let usage = e
            .params
            .iter()
            .zip(&params)
            .filter(|(p, _)| p.mode != ParamMode::Val)
            .map(|(p, &symbol)| Access {
                symbol,
                mode: Mode::Write,
                part: Part::Whole,
                span: p.span,
                only: None,
            })
            .collect();
        let id = self.declare(&e.name, SymbolKind::External(pid), Type::Error, false);
        let info = &mut self.out.procs[pid];
        info.symbol = Some(id);
        info.params = params;
        info.usage = usage;
    }
}
