//! Benchmarks of networks of nodes (a bench binary: each figure is the best of a few runs,
//! taken side by side in one process so that the ratios hold on a shared machine).
//!
//! Run: `cargo bench -p occ-codegen --bench network` (add `-- quick` for smaller counts).
//! Prints:
//! - the speed-up of an embarrassingly parallel node program on a ternary tree of 13 nodes
//!   from one worker thread to two;
//! - the round trip of an 8-byte message over an in-process link between two nodes (one per
//!   thread), and the throughput of 64 KB messages sent back and forth over it.

use std::time::{Duration, Instant};

use occ_codegen::network::{NetworkOptions, NetworkOutcome};
use occ_runtime::NodeConfig;
use occ_runtime::topology::Shape;

#[path = "../tests/common.rs"]
mod common;
#[path = "programs.rs"]
mod programs;

use programs::{ping_pong, quiet_host};

fn options(threads: usize) -> NetworkOptions {
    NetworkOptions {
        node: NodeConfig::default(),
        threads,
    }
}

fn check(name: &str, o: &NetworkOutcome) {
    let errors = o.errors();
    assert!(errors.is_empty(), "{name}: {errors:?}");
}

/// Every node spins through `work` iterations, then the sums go up the tree to the root.
fn parallel_work(work: u64) -> String {
    r"PROC node (VAL INT id, nodes, []CHAN OF INT in?, out!, CHAN BYTE keyboard?, screen!, error!)
  INT sum:
  SEQ
    sum := 0
    SEQ i = 0 FOR WORK
      sum := (sum + (i /\ 255)) /\ #FFFFFF
    SEQ k = 1 FOR 3
      IF
        ((3 * id) + k) < nodes
          INT v:
          SEQ
            in[k] ? v
            sum := (sum + v) /\ #FFFFFF
        TRUE
          SKIP
    IF
      id > 0
        out[0] ! sum
      TRUE
        SKIP
:
"
    .replace("WORK", &work.to_string())
}

/// The best wall time of `runs` runs of `src` on `shape` with `threads` worker threads.
fn best(src: &str, shape: Shape, threads: usize, runs: usize) -> Duration {
    let c = common::compile(src);
    (0..runs)
        .map(|_| {
            let o = c
                .run_topology(shape, &options(threads), quiet_host())
                .expect("a node program");
            check("run", &o);
            o.elapsed
        })
        .min()
        .unwrap_or_default()
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let work: u64 = if quick { 2_000_000 } else { 20_000_000 };
    let tree: Shape = "tree3:13".parse().expect("shape");
    let src = parallel_work(work);
    // Alternate the two settings so that both see the same machine load.
    let (mut one, mut two) = (Duration::MAX, Duration::MAX);
    for _ in 0..3 {
        one = one.min(best(&src, tree, 1, 1));
        two = two.min(best(&src, tree, 2, 1));
    }
    println!(
        "13 nodes x {work} iterations: 1 thread {:.3} s, 2 threads {:.3} s, speed-up {:.2}x",
        one.as_secs_f64(),
        two.as_secs_f64(),
        one.as_secs_f64() / two.as_secs_f64()
    );
    let pair: Shape = "pipeline:2".parse().expect("shape");
    let n: u64 = if quick { 20_000 } else { 200_000 };
    let t = best(&ping_pong(n, 8), pair, 2, 3);
    println!(
        "in-process link, 2 nodes on 2 threads: 8-byte round trip {:.2} us ({n} round trips)",
        t.as_secs_f64() * 1e6 / n as f64
    );
    let m: u64 = if quick { 2_000 } else { 20_000 };
    let t = best(&ping_pong(m, 65536), pair, 2, 3);
    println!(
        "in-process link, 2 nodes on 2 threads: 64 KB messages {:.0} MB/s ({m} round trips)",
        (2.0 * m as f64 * 65536.0) / t.as_secs_f64() / 1e6
    );
    let start = Instant::now();
    let _ = best(&ping_pong(n, 8), pair, 1, 1);
    println!(
        "in-process link, 2 nodes on 1 thread: 8-byte round trip {:.2} us",
        start.elapsed().as_secs_f64() * 1e6 / n as f64
    );
}
