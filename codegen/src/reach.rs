//! Which routines a program needs: the PROCs, FUNCTIONs and `#PRAGMA EXTERNAL` intrinsics
//! reachable from its entry PROC. Code generation compiles only these, so that a program
//! including a whole library (the course library, `stdlib/radiosity.inc`) pays for the few
//! routines it uses.
//!
//! A routine is reachable if its name occurs (called, or named in any other way) in the body of
//! a reachable routine, or outside every routine (a top-level constant). The names are the
//! checker's: every occurrence of a name and every call of a user-defined operator, each
//! attributed to the innermost PROC or FUNCTION whose declaration contains it. occam 2.1 has
//! no recursion and no PROC values, so this call graph is exact up to dead branches: a
//! `PLACED PAR`'s node programs are called in the entry PROC's body, a FUNCTION used in a
//! constant expression is named where it is used.

use std::collections::HashSet;

use occ_compiler::CheckedProgram;
use occ_compiler::checked::{SymbolId, SymbolKind};
use occ_grammar::ast::Span;

/// How many routines of a program were compiled and how many left out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeftOut {
    /// PROCs (declared in occam, at any depth) not compiled, of `procs`.
    pub procs_left_out: usize,
    /// Every PROC declared in occam.
    pub procs: usize,
    /// FUNCTIONs nothing calls, of `functions`. FUNCTIONs are expanded at each call, so one that
    /// nothing calls never had code; it is counted for the whole picture.
    pub functions_left_out: usize,
    /// Every FUNCTION declared in occam (user-defined operators included).
    pub functions: usize,
    /// `#PRAGMA EXTERNAL` routines not bound to an intrinsic, of `externals`.
    pub externals_left_out: usize,
    /// Every `#PRAGMA EXTERNAL` routine.
    pub externals: usize,
}

impl LeftOut {
    /// One line for the console and `report.json`, or `None` when nothing was left out:
    /// "`name`: 12 of 40 PROCs and FUNCTIONs and 9 of 31 intrinsics not compiled: nothing
    /// calls them".
    pub fn describe(&self, name: &str) -> Option<String> {
        let routines = self.procs_left_out + self.functions_left_out;
        if routines == 0 && self.externals_left_out == 0 {
            return None;
        }
        let mut parts = Vec::new();
        if routines > 0 {
            parts.push(format!(
                "{routines} of {} PROCs and FUNCTIONs",
                self.procs + self.functions
            ));
        }
        if self.externals_left_out > 0 {
            parts.push(format!(
                "{} of {} intrinsics",
                self.externals_left_out, self.externals
            ));
        }
        Some(format!(
            "{name}: {} not compiled: nothing calls them",
            parts.join(" and ")
        ))
    }
}

/// The routines of `checked` reachable from `entry`, and the count of those left out.
#[derive(Debug, Default)]
pub struct Reach {
    live: HashSet<SymbolId>,
    /// The counts.
    pub left_out: LeftOut,
}

impl Reach {
    /// Whether routine `sym` is needed (any symbol that is not a routine is).
    pub fn needs(&self, checked: &CheckedProgram, sym: SymbolId) -> bool {
        !is_routine(&checked.symbols[sym].kind) || self.live.contains(&sym)
    }
}

fn is_routine(kind: &SymbolKind) -> bool {
    matches!(
        kind,
        SymbolKind::Proc(_) | SymbolKind::Function(_) | SymbolKind::External(_)
    )
}

impl Reach {
    /// Every routine of `checked`, reachable or not: nothing is left out.
    pub fn everything(checked: &CheckedProgram) -> Reach {
        let live = checked
            .symbols
            .iter()
            .filter(|(_, s)| is_routine(&s.kind))
            .map(|(id, _)| id)
            .collect();
        Reach {
            live,
            left_out: LeftOut::default(),
        }
    }
}

/// Finds the routines of `checked` reachable from the routine `entry`.
pub fn reach(checked: &CheckedProgram, entry: SymbolId) -> Reach {
    // The declarations of the PROCs and FUNCTIONs, outermost first where they nest, each with
    // the index of the innermost one around it.
    let mut decls: Vec<(Span, SymbolId)> = checked
        .procs
        .iter()
        .filter_map(|(_, p)| p.symbol.map(|s| (p.span, s)))
        .filter(|(_, s)| !matches!(checked.symbols[*s].kind, SymbolKind::External(_)))
        .collect();
    decls.sort_by_key(|(span, _)| (span.start, std::cmp::Reverse(span.end)));
    let mut parent: Vec<Option<usize>> = Vec::with_capacity(decls.len());
    let mut open: Vec<usize> = Vec::new();
    for (i, (span, _)) in decls.iter().enumerate() {
        while open.last().is_some_and(|&o| decls[o].0.end <= span.start) {
            open.pop();
        }
        parent.push(open.last().copied());
        open.push(i);
    }
    let owner = |at: Span| -> Option<SymbolId> {
        let k = decls.partition_point(|(s, _)| s.start <= at.start);
        let mut i = k.checked_sub(1)?;
        loop {
            if decls[i].0.end >= at.end {
                return Some(decls[i].1);
            }
            i = parent[i]?;
        }
    };
    // Each routine's references to routines; references outside every routine are roots.
    let mut edges: Vec<(Option<SymbolId>, SymbolId)> = Vec::new();
    let uses = checked.names.iter().map(|(s, t)| (*s, *t));
    let operators = checked.operators.iter().map(|(s, t)| (*s, *t));
    for (at, target) in uses.chain(operators) {
        let sym = &checked.symbols[target];
        if !is_routine(&sym.kind) || at == sym.span {
            continue;
        }
        edges.push((owner(at), target));
    }
    edges.sort_unstable();
    edges.dedup();
    let mut live = HashSet::new();
    let mut work: Vec<SymbolId> = edges
        .iter()
        .filter(|(from, _)| from.is_none())
        .map(|e| e.1)
        .collect();
    work.push(entry);
    while let Some(s) = work.pop() {
        if !live.insert(s) {
            continue;
        }
        let from = edges.partition_point(|e| e.0 < Some(s));
        work.extend(
            edges[from..]
                .iter()
                .take_while(|e| e.0 == Some(s))
                .map(|e| e.1),
        );
    }
    let mut left_out = LeftOut::default();
    for (id, sym) in checked.symbols.iter() {
        let dead = usize::from(!live.contains(&id));
        let (n, total) = match sym.kind {
            SymbolKind::Proc(_) => (&mut left_out.procs_left_out, &mut left_out.procs),
            SymbolKind::Function(_) => (&mut left_out.functions_left_out, &mut left_out.functions),
            SymbolKind::External(_) => (&mut left_out.externals_left_out, &mut left_out.externals),
            _ => continue,
        };
        *n += dead;
        *total += 1;
    }
    Reach { live, left_out }
}
