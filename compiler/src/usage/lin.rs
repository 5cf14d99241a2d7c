//! Linear subscript forms: `c1*x1 + ... + b` over a few index names (enough for the
//! subscripts of a three-dimensional array inside replicators).

use crate::checked::SymbolId;

/// The most names a linear form may mention.
pub const TERMS: usize = 4;

/// A linear function of at most [`TERMS`] names (replicator indices or integer variables), with
/// terms kept sorted and non-zero, so that equal functions compare equal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Lin {
    /// The terms `(name, coefficient)`, sorted by name, `None` after the last.
    pub terms: [Option<(SymbolId, i64)>; TERMS],
    /// The constant term.
    pub b: i64,
}

impl Lin {
    /// A constant.
    pub fn constant(b: i64) -> Lin {
        Lin {
            terms: [None; TERMS],
            b,
        }
    }

    /// The name itself.
    pub fn var(id: SymbolId) -> Lin {
        let mut terms = [None; TERMS];
        terms[0] = Some((id, 1));
        Lin { terms, b: 0 }
    }

    /// Returns the constant, when this has no terms.
    pub fn as_const(self) -> Option<i64> {
        self.terms[0].is_none().then_some(self.b)
    }

    /// Returns the coefficient of `id` (0 when absent).
    pub fn coef(self, id: SymbolId) -> i64 {
        self.terms
            .iter()
            .flatten()
            .find(|(v, _)| *v == id)
            .map_or(0, |(_, c)| *c)
    }

    /// Reports whether `id` appears.
    pub fn mentions(self, id: SymbolId) -> bool {
        self.coef(id) != 0
    }

    /// Reports whether every name that appears is `id` (or none does).
    pub fn only(self, id: SymbolId) -> bool {
        self.terms.iter().flatten().all(|(v, _)| *v == id)
    }

    /// The same function without the term in `id`.
    pub fn without(self, id: SymbolId) -> Lin {
        // Removing a term keeps the others sorted: shift them down, no allocation.
        let mut terms = [None; TERMS];
        let kept = self.terms.iter().flatten().filter(|(v, _)| *v != id);
        for (slot, term) in terms.iter_mut().zip(kept) {
            *slot = Some(*term);
        }
        Lin { terms, b: self.b }
    }

    /// The function with `id` set to `v`.
    pub fn subst(self, id: SymbolId, v: i64) -> Option<Lin> {
        let c = self.coef(id);
        let mut r = self.without(id);
        r.b = r.b.checked_add(c.checked_mul(v)?)?;
        Some(r)
    }

    /// Reports whether both have the same terms (so they differ by a constant).
    pub fn same_terms(self, o: Lin) -> bool {
        self.terms == o.terms
    }

    fn build(terms: &[(SymbolId, i64)], b: i64) -> Option<Lin> {
        let mut t: Vec<(SymbolId, i64)> = Vec::with_capacity(TERMS);
        for &(v, c) in terms {
            match t.iter_mut().find(|(x, _)| *x == v) {
                Some(e) => e.1 = e.1.checked_add(c)?,
                None => t.push((v, c)),
            }
        }
        t.retain(|(_, c)| *c != 0);
        t.sort_by_key(|(v, _)| *v);
        if t.len() > TERMS {
            return None;
        }
        let mut terms = [None; TERMS];
        for (slot, term) in terms.iter_mut().zip(t) {
            *slot = Some(term);
        }
        Some(Lin { terms, b })
    }

    /// Adds two functions (`None` when the result needs more than two names, or overflows).
    pub fn plus(self, o: Lin) -> Option<Lin> {
        let terms: Vec<(SymbolId, i64)> = self
            .terms
            .iter()
            .chain(o.terms.iter())
            .flatten()
            .copied()
            .collect();
        Lin::build(&terms, self.b.checked_add(o.b)?)
    }

    /// Multiplies by a constant.
    pub fn scale(self, k: i64) -> Option<Lin> {
        let mut terms = Vec::with_capacity(2);
        for (v, c) in self.terms.iter().flatten() {
            terms.push((*v, c.checked_mul(k)?));
        }
        Lin::build(&terms, self.b.checked_mul(k)?)
    }
}
