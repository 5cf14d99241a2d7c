//! Front-end throughput: lines per second through preprocess + lex + layout + parse of a large
//! generated program (`cargo bench -p occ-grammar --bench frontend`). Criterion reports the
//! throughput in elements (lines) per second.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::collections::HashMap;
use std::fmt::Write;
use std::hint::black_box;

/// One PROC of about 60 lines exercising most constructs, numbered `n`.
fn proc_text(n: usize, out: &mut String) {
    let _ = write!(
        out,
        "\
-- PROC number {n}
PROC worker.{n} (CHAN OF INT in?, out!, VAL INT base, []INT data)
  INT x, y, total:
  VAL INT limit IS base + {n}:
  [16]BYTE buffer:
  TIMER tim:
  SEQ
    total := 0
    SEQ i = 0 FOR SIZE data
      total := total + (data[i] * 2)
    IF
      total > limit
        x := total - limit
      total = limit
        x := 0
      TRUE
        x := limit - total
    WHILE x > 0
      SEQ
        in ? y
        x := x - (y \\ 7)
        out ! x; y
    ALT
      in ? y
        out ! y
      tim ? AFTER y PLUS 1000
        SKIP
    CASE x
      0, 1, 2
        buffer[0] := 'a'
      ELSE
        buffer[1] := BYTE (x /\\ #FF)
    PAR
      out ! total
      in ? y
    [buffer FROM 0 FOR 4] := \"abcd\"
    y := INT ROUND (REAL32 x)
:
INT FUNCTION twice.{n} (VAL INT v)
  INT r:
  VALOF
    r := v + v
    RESULT r
:
"
    );
}

/// A program of at least `lines` lines.
fn program(lines: usize) -> String {
    let mut out = String::new();
    let mut n = 0;
    while out.lines().count() < lines {
        for _ in 0..100 {
            proc_text(n, &mut out);
            n += 1;
        }
    }
    out
}

fn frontend(c: &mut Criterion) {
    let text = program(100_000);
    let lines = text.lines().count() as u64;
    let parsed = occ_grammar::parse_source("bench.occ", &text, &mut HashMap::new());
    assert!(
        parsed.diagnostics.is_empty(),
        "{:?}",
        parsed.diagnostics.first()
    );
    let mut group = c.benchmark_group("frontend");
    group.throughput(Throughput::Elements(lines));
    group.sample_size(10);
    group.bench_function("preprocess+lex+parse", |b| {
        b.iter(|| {
            let parsed =
                occ_grammar::parse_source("bench.occ", black_box(&text), &mut HashMap::new());
            black_box(parsed.program.decls.len())
        })
    });
    group.bench_function("lex+layout", |b| {
        b.iter(|| black_box(occ_grammar::layout::tokens(black_box(&text)).0.len()))
    });
    group.finish();
}

criterion_group!(benches, frontend);
criterion_main!(benches);
