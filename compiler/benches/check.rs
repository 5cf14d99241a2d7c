//! Front-end throughput: lines per second through the whole `occ check` pipeline (preprocess,
//! lex, parse, check) on a large generated program.
//!
//! Run: `cargo bench -p occ-compiler --bench check`. The figure is criterion's
//! "thrpt" in elements (source lines) per second.

use std::collections::HashMap;
use std::fmt::Write;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

/// Generates `procs` PROCs of typical occam: declarations, SEQ/PAR/IF/WHILE/ALT, arithmetic,
/// arrays, channels with a protocol, and calls between PROCs. About 40 lines per PROC.
fn program(procs: usize) -> String {
    let mut s =
        String::from("PROTOCOL MSG\n  CASE\n    data; INT; INT\n    stop\n:\nVAL INT N IS 16:\n");
    for k in 0..procs {
        let _ = write!(
            s,
            "PROC worker.{k} (CHAN OF MSG in?, CHAN OF INT out!, VAL INT seed)
  [N]INT a:
  INT x, y, total:
  BOOL running:
  SEQ
    total := seed
    SEQ i = 0 FOR N
      a[i] := (i * 3) + seed
    running := TRUE
    WHILE running
      in ? CASE
        data; x; y
          IF
            x > y
              total := total + (x - y)
            x = y
              total := total PLUS 1
            TRUE
              SEQ
                a[x /\\ (N - 1)] := y
                total := total + a[0]
        stop
          running := FALSE
    PAR i = 0 FOR N
      a[i] := a[i] * 2
    out ! total
:
"
        );
        if k > 0 {
            let _ = write!(
                s,
                "PROC pair.{k} (CHAN OF MSG in?, CHAN OF INT out!)
  CHAN OF INT mid:
  INT r:
  PAR
    worker.{k} (in?, mid!, {k})
    SEQ
      mid ? r
      out ! r + 1
:
"
            );
        }
    }
    s
}

fn bench(c: &mut Criterion) {
    let text = program(4000);
    let lines = text.lines().count() as u64;
    let mut group = c.benchmark_group("frontend");
    group.throughput(Throughput::Elements(lines));
    group.sample_size(10);
    group.bench_function(format!("occ check ({lines} lines)"), |b| {
        b.iter(|| {
            let front = occ_compiler::check_source("big.occ", &text, &mut HashMap::new());
            assert!(front.diagnostics.is_empty() && front.checked.is_some());
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
