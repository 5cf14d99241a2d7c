use super::*;
use crate::entity::EntityRef;

fn sym(i: usize) -> SymbolId {
    SymbolId::new(i)
}

fn acc(s: usize, mode: Mode, part: Part) -> Access {
    Access {
        symbol: sym(s),
        mode,
        part,
        span: Span::default(),
        only: None,
    }
}

fn elem(b: i64) -> Part {
    Part::Range {
        start: Lin::constant(b),
        len: 1,
    }
}

fn lin(var: usize, a: i64, b: i64) -> Part {
    Part::Range {
        start: Lin::var(sym(var))
            .scale(a)
            .and_then(|l| l.plus(Lin::constant(b)))
            .unwrap(),
        len: 1,
    }
}

const T: Tables = Vec::new();
const NONE: &dyn Fn(SymbolId) -> bool = &|_| false;

#[test]
fn written_and_read_in_two_branches_conflict() {
    let c = conflicts(
        &T,
        &[acc(0, Mode::Write, Part::Whole)],
        &[acc(0, Mode::Read, Part::Whole)],
        None,
        NONE,
    );
    assert_eq!(c.len(), 1);
    let c = conflicts(
        &T,
        &[acc(0, Mode::Read, Part::Whole)],
        &[acc(0, Mode::Read, Part::Whole)],
        None,
        NONE,
    );
    assert!(c.is_empty());
}

#[test]
fn channels_conflict_only_on_the_same_end() {
    let c = conflicts(
        &T,
        &[acc(0, Mode::Input, Part::Whole)],
        &[acc(0, Mode::Output, Part::Whole)],
        None,
        NONE,
    );
    assert!(c.is_empty());
    let c = conflicts(
        &T,
        &[acc(0, Mode::Input, Part::Whole)],
        &[acc(0, Mode::Input, Part::Whole)],
        None,
        NONE,
    );
    assert_eq!(c.len(), 1);
}

#[test]
fn constant_subscripts_are_compared_exactly() {
    let c = conflicts(
        &T,
        &[acc(0, Mode::Write, elem(1))],
        &[acc(0, Mode::Write, elem(2))],
        None,
        NONE,
    );
    assert!(c.is_empty());
    let slice = Part::Range {
        start: Lin::constant(0),
        len: 2,
    };
    let c = conflicts(
        &T,
        &[acc(0, Mode::Write, slice)],
        &[acc(0, Mode::Write, elem(1))],
        None,
        NONE,
    );
    assert_eq!(c.len(), 1);
    let c = conflicts(
        &T,
        &[acc(0, Mode::Write, Part::Whole)],
        &[acc(0, Mode::Write, elem(1))],
        None,
        NONE,
    );
    assert_eq!(c.len(), 1);
}

#[test]
fn same_linear_subscripts_in_one_instance() {
    assert!(!may_overlap(&T, lin(5, 1, 0), lin(5, 1, 1)));
    assert!(may_overlap(&T, lin(5, 1, 0), lin(5, 1, 0)));
    assert!(may_overlap(&T, lin(5, 1, 0), lin(6, 1, 1)));
}

#[test]
fn replicated_par_instances() {
    let i = sym(5);
    // a[i] in every instance: disjoint, with or without known values.
    assert!(!may_overlap_across(&T, lin(5, 1, 0), lin(5, 1, 0), i, None));
    assert!(!may_overlap_across(
        &T,
        lin(5, 1, 0),
        lin(5, 1, 0),
        i,
        Some(&[0, 1, 2])
    ));
    // a[i] written, a[i+1] read: instance 0 reads what instance 1 writes.
    assert!(may_overlap_across(
        &T,
        lin(5, 1, 0),
        lin(5, 1, 1),
        i,
        Some(&[0, 1, 2])
    ));
    // a[2*i] and a[(2*i)+1]: never the same element.
    assert!(!may_overlap_across(
        &T,
        lin(5, 2, 0),
        lin(5, 2, 1),
        i,
        Some(&[0, 1, 2, 3])
    ));
    // x (whole) written in each instance.
    assert!(may_overlap_across(
        &T,
        Part::Whole,
        Part::Whole,
        i,
        Some(&[0, 1])
    ));
}

#[test]
fn exempt_symbols_are_skipped() {
    let c = conflicts(
        &T,
        &[acc(0, Mode::Write, Part::Whole)],
        &[acc(0, Mode::Write, Part::Whole)],
        None,
        &|s| s == sym(0),
    );
    assert!(c.is_empty());
}

#[test]
fn mapped_subscripts_compare_per_index_value() {
    let tables: Tables = vec![vec![(0, 1), (1, 2), (2, 0)]]; // (i + 1) \ 3
    let i = sym(5);
    let mapped = Part::Mapped {
        var: i,
        table: 0,
        len: 1,
    };
    assert!(!may_overlap_across(
        &tables,
        mapped,
        mapped,
        i,
        Some(&[0, 1, 2])
    ));
    assert!(may_overlap_across(
        &tables,
        mapped,
        lin(5, 1, 0),
        i,
        Some(&[0, 1, 2])
    ));
    assert!(!may_overlap(&tables, mapped, lin(5, 1, 0)));
}

#[test]
fn hull_covers_every_instance() {
    let i = sym(5);
    assert_eq!(
        hull(&T, lin(5, 1, 1), i, Some(&[0, 1, 2])),
        Part::Range {
            start: Lin::constant(1),
            len: 3
        }
    );
    assert_eq!(hull(&T, lin(5, 1, 1), i, None), Part::Whole);
    assert_eq!(hull(&T, elem(4), i, None), elem(4));
}
