//! Usage rules for PAR, in the style of occ21's `use1.c`-`use5.c`.
//!
//! While the checker walks a process it records every [`Access`] to a symbol: read, written,
//! input or output, with the part of the symbol touched ([`Part`]). For each PAR it collects the
//! accesses of each branch separately and compares every pair of branches:
//! - a variable written in one branch may not be read or written in another;
//! - a channel may be used for input in at most one branch, and for output in at most one;
//! - timers are exempt; names given in `#PRAGMA SHARED` are exempt.
//!
//! Parts are compared exactly when subscripts are constant, and also when they are the same
//! linear function `a*i + b` of a replicator index `i` (so `a[i]` and `a[i+1]` in one replicated
//! SEQ iteration are disjoint). For a replicated PAR, two different instances of the body are
//! compared with the PAR's own index taking different values: with a constant count every pair of
//! index values is tried; otherwise `a*i + b` and `a*j + b` (same `a`, `b`, `a != 0`) are disjoint.

#[cfg(test)]
mod test;

use occ_grammar::ast::Span;

use crate::checked::SymbolId;

/// How a symbol is accessed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Its value is used.
    Read,
    /// It is assigned or input to.
    Write,
    /// A channel is input from.
    Input,
    /// A channel is output to.
    Output,
}

/// A linear function `a*var + b` of a replicator index, or a constant when `var` is `None`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Lin {
    /// The replicator index, if any.
    pub var: Option<SymbolId>,
    /// The coefficient of `var`.
    pub a: i64,
    /// The constant term.
    pub b: i64,
}

impl Lin {
    /// A constant.
    pub fn constant(b: i64) -> Lin {
        Lin { var: None, a: 0, b }
    }

    /// Adds two linear functions of at most one (the same) replicator index.
    pub fn plus(self, o: Lin) -> Option<Lin> {
        let var = match (self.var, o.var) {
            (Some(x), Some(y)) if x != y => return None,
            (x, y) => x.or(y),
        };
        Some(Lin {
            var,
            a: self.a.checked_add(o.a)?,
            b: self.b.checked_add(o.b)?,
        })
    }

    /// Multiplies by a constant.
    pub fn scale(self, k: i64) -> Option<Lin> {
        Some(Lin {
            var: self.var,
            a: self.a.checked_mul(k)?,
            b: self.b.checked_mul(k)?,
        })
    }
}

/// The length of a part that runs to the end of its symbol (an open array, or an array slice
/// without a count): large, but far from overflowing when added to.
pub const TO_END: i64 = i64::MAX / 4;

/// Which part of a symbol an access touches, in bytes from the symbol's start, so that
/// subscripts at every depth and record fields compare alike.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Part {
    /// Somewhere in the symbol: a subscript that is not known at compile time.
    Whole,
    /// Elements (or record fields) `start .. start + len`.
    Range {
        /// The first element.
        start: Lin,
        /// How many elements.
        len: i64,
    },
    /// Elements `f(var) .. f(var) + len` where `f` is not linear (`(i + 1) \ n`) but was
    /// evaluated for every value of the replicator index `var`: `table` indexes [`Tables`].
    Mapped {
        /// The replicator index.
        var: SymbolId,
        /// The table of `(index value, first element)` pairs.
        table: u32,
        /// How many elements.
        len: i64,
    },
}

/// The tables of [`Part::Mapped`] subscripts: `(index value, first element)` pairs.
pub type Tables = Vec<Vec<(i64, i64)>>;

/// Returns the elements `(start, len)` a part touches when `index` has value `v`, if that is
/// known without other replicators.
fn concrete(tables: &Tables, p: Part, index: SymbolId, v: i64) -> Option<(i64, i64)> {
    match p {
        Part::Whole => None,
        Part::Range { start, len } => match start.var {
            None => Some((start.b, len)),
            Some(x) if x == index => Some((start.a.saturating_mul(v).saturating_add(start.b), len)),
            Some(_) => None,
        },
        Part::Mapped { var, table, len } if var == index => {
            let t = tables.get(table as usize)?;
            t.iter().find(|(x, _)| *x == v).map(|(_, s)| (*s, len))
        }
        Part::Mapped { .. } => None,
    }
}

fn ranges_overlap((s, n): (i64, i64), (t, m): (i64, i64)) -> bool {
    s < t.saturating_add(m) && t < s.saturating_add(n)
}

/// Replaces the dependence of a part on the replicator `index` by the hull of the elements it
/// touches over `values` (or the whole symbol when the values are unknown): used when the
/// replicator goes out of scope.
pub fn hull(tables: &Tables, p: Part, index: SymbolId, values: Option<&[i64]>) -> Part {
    let depends = match p {
        Part::Range { start, .. } => start.var == Some(index),
        Part::Mapped { var, .. } => var == index,
        Part::Whole => false,
    };
    if !depends {
        return p;
    }
    let Some(values) = values.filter(|v| !v.is_empty()) else {
        return Part::Whole;
    };
    let mut lo = i64::MAX;
    let mut hi = i64::MIN;
    for &v in values {
        let Some((s, n)) = concrete(tables, p, index, v) else {
            return Part::Whole;
        };
        lo = lo.min(s);
        hi = hi.max(s.saturating_add(n));
    }
    Part::Range {
        start: Lin::constant(lo),
        len: hi.saturating_sub(lo),
    }
}

/// One access to a symbol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Access {
    /// The symbol (after following reference abbreviations).
    pub symbol: SymbolId,
    /// How.
    pub mode: Mode,
    /// Which part.
    pub part: Part,
    /// Where (for the diagnostic).
    pub span: Span,
}

/// Reports whether two parts may overlap, with both evaluated in the same instance.
pub fn may_overlap(tables: &Tables, p: Part, q: Part) -> bool {
    match (p, q) {
        // Same function of the same index: compare the constant offsets.
        (Part::Range { start: s, len: n }, Part::Range { start: t, len: m })
            if s.var == t.var && s.a == t.a =>
        {
            ranges_overlap((s.b, n), (t.b, m))
        }
        (Part::Mapped { var, .. }, _) | (_, Part::Mapped { var, .. }) => {
            let Some(t) = mapped_values(tables, p).or_else(|| mapped_values(tables, q)) else {
                return true;
            };
            t.iter().any(
                |&v| match (concrete(tables, p, var, v), concrete(tables, q, var, v)) {
                    (Some(a), Some(b)) => ranges_overlap(a, b),
                    _ => true,
                },
            )
        }
        _ => true,
    }
}

fn mapped_values(tables: &Tables, p: Part) -> Option<Vec<i64>> {
    match p {
        Part::Mapped { table, .. } => Some(
            tables
                .get(table as usize)?
                .iter()
                .map(|(v, _)| *v)
                .collect(),
        ),
        _ => None,
    }
}

/// Reports whether `p` in one instance and `q` in another instance of a replicated PAR over
/// `index` may overlap. `values` are the index values when the count is a (small) constant.
pub fn may_overlap_across(
    tables: &Tables,
    p: Part,
    q: Part,
    index: SymbolId,
    values: Option<&[i64]>,
) -> bool {
    if let Some(vals) = values {
        return vals.iter().enumerate().any(|(k, &i)| {
            vals.iter().enumerate().any(|(l, &j)| {
                k != l
                    && match (concrete(tables, p, index, i), concrete(tables, q, index, j)) {
                        (Some(a), Some(b)) => ranges_overlap(a, b),
                        _ => {
                            depends_on_other(p, index)
                                || depends_on_other(q, index)
                                || may_overlap(tables, p, q)
                        }
                    }
            })
        });
    }
    match (p, q) {
        (Part::Range { start: s, len: n }, Part::Range { start: t, len: m })
            if s.var == Some(index) && t.var == Some(index) =>
        {
            !(s.a == t.a && s.b == t.b && n == m && s.a.unsigned_abs() >= n.unsigned_abs())
        }
        _ => true,
    }
}

/// Reports whether a part depends on a replicator other than `index` (then it cannot be
/// compared across instances and counts as overlapping).
fn depends_on_other(p: Part, index: SymbolId) -> bool {
    match p {
        Part::Range { start, .. } => start.var.is_some_and(|v| v != index),
        Part::Mapped { var, .. } => var != index,
        Part::Whole => true,
    }
}

/// A conflict found between two branches of a PAR.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Conflict {
    /// The access in the later branch (the one reported).
    pub here: Access,
    /// The conflicting access in the earlier branch.
    pub other: Access,
}

/// Reports whether access modes in two branches conflict.
fn modes_conflict(a: Mode, b: Mode) -> bool {
    use Mode::*;
    matches!(
        (a, b),
        (Write, Write) | (Write, Read) | (Read, Write) | (Input, Input) | (Output, Output)
    )
}

/// Compares two branches' accesses; `across` gives the replicated PAR's index and values when
/// the two sets are two instances of one replicated body. Returns at most one conflict per
/// symbol.
pub fn conflicts(
    tables: &Tables,
    first: &[Access],
    second: &[Access],
    across: Option<(SymbolId, Option<&[i64]>)>,
    exempt: &dyn Fn(SymbolId) -> bool,
) -> Vec<Conflict> {
    let mut found: Vec<Conflict> = Vec::new();
    for b in second {
        if exempt(b.symbol) || found.iter().any(|c| c.here.symbol == b.symbol) {
            continue;
        }
        let hit = first.iter().find(|a| {
            a.symbol == b.symbol
                && modes_conflict(a.mode, b.mode)
                && match across {
                    Some((index, values)) => {
                        may_overlap_across(tables, a.part, b.part, index, values)
                    }
                    None => may_overlap(tables, a.part, b.part),
                }
        });
        if let Some(a) = hit {
            found.push(Conflict {
                here: *b,
                other: *a,
            });
        }
    }
    found
}

/// Removes repeated accesses (same symbol, mode and part), keeping the first.
pub fn dedup(accesses: &mut Vec<Access>) {
    let mut seen = std::collections::HashSet::new();
    accesses.retain(|a| seen.insert((a.symbol, a.mode, a.part)));
}
