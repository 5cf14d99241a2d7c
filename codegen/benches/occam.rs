//! Benchmarks of compiled occam (a bench binary, not criterion: each figure is one long run).
//!
//! Run: `cargo bench -p occ-codegen --bench occam` (add `-- quick` for smaller counts).
//! Prints ns per loop for commstime (SEQ and PAR delta), a 2-guard ALT, process start+end, the
//! resident memory of a ring of 1,000,000 processes passing a token, and the compile time of a
//! generated 10,000-line program.

use std::time::Instant;

use occ_runtime::{HostIo, NodeConfig};

#[path = "../tests/common.rs"]
mod common;

fn time_run(name: &str, src: &str, loops: u64) -> f64 {
    let c = common::compile(src);
    let host = HostIo::new(
        Box::new(std::io::empty()),
        Box::new(std::io::sink()),
        Box::new(std::io::sink()),
    );
    let t = Instant::now();
    let (r, stats) = c.run(NodeConfig::default(), host);
    let dt = t.elapsed();
    match r {
        // The generators of commstime and the ALT benchmark never end: once the consumer is
        // done, the rest is a (reported) deadlock, which is the normal end here.
        Ok(()) | Err(occ_runtime::RunError::Deadlock(_)) => {}
        Err(e) => panic!("{name}: {e}"),
    }
    let ns = dt.as_nanos() as f64 / loops as f64;
    println!(
        "{name:<28} {ns:>9.1} ns/loop   ({loops} loops, {} switches, {} comms)",
        stats.context_switches, stats.communications
    );
    ns
}

fn commstime(par_delta: bool, n: u64) -> String {
    let delta = if par_delta {
        "PROC delta (CHAN INT in?, out.1!, out.2!)\n  WHILE TRUE\n    INT x:\n    SEQ\n      in ? x\n      PAR\n        out.1 ! x\n        out.2 ! x\n:\n"
    } else {
        "PROC delta (CHAN INT in?, out.1!, out.2!)\n  WHILE TRUE\n    INT x:\n    SEQ\n      in ? x\n      out.1 ! x\n      out.2 ! x\n:\n"
    };
    format!(
        "PROC prefix (VAL INT n, CHAN INT in?, out!)\n  SEQ\n    out ! n\n    WHILE TRUE\n      INT x:\n      SEQ\n        in ? x\n        out ! x\n:\n\
{delta}\
PROC succ (CHAN INT in?, out!)\n  WHILE TRUE\n    INT x:\n    SEQ\n      in ? x\n      out ! x PLUS 1\n:\n\
PROC consume (VAL INT n, CHAN INT in?)\n  INT x:\n  SEQ i = 0 FOR n\n    in ? x\n:\n\
PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT a, b, c, d:\n  PAR\n    consume ({n}, d?)\n    PAR\n      prefix (0, b?, a!)\n      delta (a?, c!, d!)\n      succ (c?, b!)\n:\n"
    )
}

fn alt2(n: u64) -> String {
    format!(
        "PROC gen (CHAN INT out!)\n  WHILE TRUE\n    out ! 1\n:\n\
PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT a, b:\n  PAR\n    INT x:\n    SEQ i = 0 FOR {n}\n      ALT\n        a ? x\n          SKIP\n        b ? x\n          SKIP\n    PAR\n      gen (a!)\n      gen (b!)\n:\n"
    )
}

fn startp(n: u64) -> String {
    let outer = n / 100;
    format!(
        "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  SEQ i = 0 FOR {outer}\n    PAR j = 0 FOR 100\n      SKIP\n:\n"
    )
}

fn ring(n: u64) -> String {
    format!(
        "PROC node (CHAN INT in?, out!)\n  INT t:\n  SEQ\n    in ? t\n    out ! t + 1\n:\n\
PROC main (CHAN BYTE keyboard?, screen!, error!)\n  VAL INT N IS {n}:\n  [N + 1]CHAN INT ring:\n  #PRAGMA SHARED ring\n  PAR\n    ring[0] ! 0\n    PAR i = 0 FOR N\n      node (ring[i]?, ring[i + 1]!)\n    INT t:\n    SEQ\n      ring[N] ? t\n      ASSERT (t = N)\n:\n"
    )
}

fn big_program(lines: usize) -> String {
    let mut s = String::new();
    let procs = lines / 10;
    for p in 0..procs {
        s.push_str(&format!(
            "PROC p{p} (INT x, CHAN INT out!)\n  INT y:\n  SEQ\n    y := x + {p}\n    IF\n      y > 100\n        x := y - 1\n      TRUE\n        out ! y\n:\n"
        ));
    }
    s.push_str("PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT c:\n  INT x:\n  PAR\n    SEQ\n      x := 1000\n");
    for p in 0..procs.min(50) {
        s.push_str(&format!("      p{p} (x, c!)\n"));
    }
    s.push_str("    SKIP\n:\n");
    s
}

fn vm_hwm_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let n = if quick { 200_000 } else { 2_000_000 };
    time_run("commstime SEQ delta", &commstime(false, n), n);
    time_run("commstime PAR delta", &commstime(true, n), n);
    time_run("ALT, 2 guards", &alt2(n), n);
    time_run("process start+end", &startp(n), n);
    let big = big_program(10_000);
    let t = Instant::now();
    let c = common::compile(&big);
    let dt = t.elapsed();
    drop(c);
    println!(
        "compile {} lines               {:>9.1} ms (parse + check + Cranelift to running code)",
        big.lines().count(),
        dt.as_secs_f64() * 1e3
    );
    let ring_n = if quick { 100_000 } else { 1_000_000 };
    let before = vm_hwm_kb();
    time_run("ring token pass", &ring(ring_n), ring_n);
    println!(
        "ring of {ring_n} processes: peak RSS {} MB (before: {} MB)",
        vm_hwm_kb() / 1024,
        before / 1024
    );
}
