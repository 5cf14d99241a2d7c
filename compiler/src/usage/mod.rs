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

mod lin;
#[cfg(test)]
mod test;

pub use lin::{Lin, TERMS};

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

/// Sets the replicator `index` to `v` in a part.
fn subst(tables: &Tables, p: Part, index: SymbolId, v: i64) -> Part {
    match p {
        Part::Range { start, len } => match start.subst(index, v) {
            Some(start) => Part::Range { start, len },
            None => Part::Whole,
        },
        Part::Mapped { var, table, len } if var == index => {
            let entry = tables
                .get(table as usize)
                .and_then(|t| t.iter().find(|(x, _)| *x == v));
            match entry {
                Some((_, s)) => Part::Range {
                    start: Lin::constant(*s),
                    len,
                },
                None => Part::Whole,
            }
        }
        other => other,
    }
}

fn ranges_overlap((s, n): (i64, i64), (t, m): (i64, i64)) -> bool {
    s < t.saturating_add(m) && t < s.saturating_add(n)
}

/// Reports whether a part depends on the replicator `index`.
fn mentions(p: Part, index: SymbolId) -> bool {
    match p {
        Part::Range { start, .. } => start.mentions(index),
        Part::Mapped { var, .. } => var == index,
        Part::Whole => false,
    }
}

/// Like [`hull`] for a replicator whose values are `base + k*step` for `k` in `0..count`, with
/// `base` a linear form of other names (`SEQ j = i * 10 FOR 5`).
pub fn hull_symbolic(p: Part, index: SymbolId, base: Lin, count: i64, step: i64) -> Part {
    let Part::Range { start, len } = p else {
        return if mentions(p, index) { Part::Whole } else { p };
    };
    let c = start.coef(index);
    if c == 0 {
        return p;
    }
    let spread = c
        .saturating_mul(step)
        .saturating_mul(count.saturating_sub(1).max(0));
    let from = base.scale(c).and_then(|b| b.plus(start.without(index)));
    match from {
        Some(s) => Part::Range {
            start: Lin {
                b: s.b.saturating_add(spread.min(0)),
                ..s
            },
            len: len.saturating_add(spread.abs()),
        },
        None => Part::Whole,
    }
}

/// Replaces the dependence of a part on the replicator `index` by the hull of the elements it
/// touches over `values` (or the whole symbol when the values are unknown): used when the
/// replicator goes out of scope.
pub fn hull(tables: &Tables, p: Part, index: SymbolId, values: Option<&[i64]>) -> Part {
    if !mentions(p, index) {
        return p;
    }
    let Some(values) = values.filter(|v| !v.is_empty()) else {
        return Part::Whole;
    };
    let (rest, len) = match p {
        Part::Range { start, len } => (start.without(index), len),
        Part::Mapped { len, .. } => (Lin::constant(0), len),
        Part::Whole => return Part::Whole,
    };
    let mut lo = i64::MAX;
    let mut hi = i64::MIN;
    for &v in values {
        let offset = match subst(tables, p, index, v) {
            Part::Range { start, .. } => start.b.saturating_sub(rest.b),
            _ => return Part::Whole,
        };
        lo = lo.min(offset);
        hi = hi.max(offset.saturating_add(len));
    }
    let start = Lin {
        b: rest.b.saturating_add(lo),
        ..rest
    };
    Part::Range {
        start,
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
    /// Set when the access happens only in the instance of a replicated process where the
    /// index has this value (inside `IF i = 3`, occ21 evaluates such guards per instance).
    pub only: Option<(SymbolId, i64)>,
}

/// Reports whether two parts may overlap, with both evaluated in the same instance (so a name
/// that appears in both has the same value in both).
pub fn may_overlap(tables: &Tables, p: Part, q: Part) -> bool {
    match (p, q) {
        (Part::Range { start: s, len: n }, Part::Range { start: t, len: m }) if s.same_terms(t) => {
            ranges_overlap((s.b, n), (t.b, m))
        }
        (Part::Mapped { var, table, .. }, _) | (_, Part::Mapped { var, table, .. }) => {
            let Some(t) = tables.get(table as usize) else {
                return true;
            };
            t.iter().any(
                |&(v, _)| match (subst(tables, p, var, v), subst(tables, q, var, v)) {
                    (Part::Mapped { .. }, _) | (_, Part::Mapped { .. }) => true,
                    (a, b) => may_overlap(tables, a, b),
                },
            )
        }
        _ => true,
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
    if values.is_some_and(|v| v.len() < 2) {
        return false; // one instance: nothing to share with
    }
    if !mentions(p, index) && !mentions(q, index) {
        return may_overlap(tables, p, q);
    }
    if let (Some(vals), Part::Range { start: s, len: n }, Part::Range { start: t, len: m }) =
        (values, p, q)
        && s.without(index).same_terms(t.without(index))
    {
        // Same function apart from the index: plain arithmetic per pair of instances.
        let (cs, ct) = (s.coef(index), t.coef(index));
        return vals.iter().enumerate().any(|(k, &i)| {
            vals.iter().enumerate().any(|(l, &j)| {
                let a = s.b.saturating_add(cs.saturating_mul(i));
                let b = t.b.saturating_add(ct.saturating_mul(j));
                k != l && ranges_overlap((a, n), (b, m))
            })
        });
    }
    if let Some(vals) = values {
        return vals.iter().enumerate().any(|(k, &i)| {
            vals.iter().enumerate().any(|(l, &j)| {
                k != l
                    && may_overlap(
                        tables,
                        subst(tables, p, index, i),
                        subst(tables, q, index, j),
                    )
            })
        });
    }
    match (p, q) {
        (Part::Range { start: s, len: n }, Part::Range { start: t, len: m }) => {
            let c = s.coef(index);
            let disjoint =
                s.same_terms(t) && s.b == t.b && n == m && c.unsigned_abs() >= n.unsigned_abs();
            !disjoint
        }
        _ => true,
    }
}

/// Reports whether access `a` in one instance and `b` in another instance of a replicated PAR
/// over `index` may touch the same storage, taking `IF index = c` restrictions into account.
fn across_instances(
    tables: &Tables,
    a: &Access,
    b: &Access,
    index: SymbolId,
    values: Option<&[i64]>,
) -> bool {
    let only = |x: &Access| x.only.filter(|(v, _)| *v == index).map(|(_, c)| c);
    let (ca, cb) = (only(a), only(b));
    if ca.is_none() && cb.is_none() {
        return may_overlap_across(tables, a.part, b.part, index, values);
    }
    let Some(vals) = values else {
        return match (ca, cb) {
            (Some(x), Some(y)) => {
                x != y
                    && may_overlap(
                        tables,
                        subst(tables, a.part, index, x),
                        subst(tables, b.part, index, y),
                    )
            }
            _ => may_overlap_across(tables, a.part, b.part, index, values),
        };
    };
    vals.iter().enumerate().any(|(k, &i)| {
        vals.iter().enumerate().any(|(l, &j)| {
            k != l
                && ca.is_none_or(|x| x == i)
                && cb.is_none_or(|y| y == j)
                && may_overlap(
                    tables,
                    subst(tables, a.part, index, i),
                    subst(tables, b.part, index, j),
                )
        })
    })
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
                    Some((index, values)) => across_instances(tables, a, b, index, values),
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
    accesses.retain(|a| seen.insert((a.symbol, a.mode, a.part, a.only)));
}
