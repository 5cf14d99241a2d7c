//! Vectors (arrays of 64 KB and more, taken from the node's memory as their declarations run):
//! the most a node can take, `Compiled::topology_node_bytes`, counts those its PAR branches and
//! their callees hold at once, and a budget below it is an error at a declaration.

mod common;

use occ_codegen::network::NetworkOptions;
use occ_runtime::topology::Shape;
use occ_runtime::{HostIo, NodeConfig, RunError};

/// Two branches hold 80,000 and 120,000 bytes at once (the second in a PROC it calls), then
/// four replicated branches 68,000 each, all held at once: 272,000 bytes at most, with the
/// arena's headers.
const NODE: &str = "
PROC node (VAL INT id, nodes, []CHAN OF INT in?, out!)
  PROC user (INT r)
    [30000]INT a:
    SEQ
      a[29999] := 1
      r := a[29999]
  :
  INT x, y:
  [4]INT s:
  [4]CHAN OF INT ch:
  SEQ
    PAR
      [20000]INT b:
      SEQ
        b[0] := 1
        x := b[0]
      user (y)
    -- each branch holds its vector until the last takes its value
    PAR
      PAR i = 0 FOR 4
        [17000]INT c:
        SEQ
          c[16999] := i
          ch[i] ! c[16999]
      SEQ i = 0 FOR 4
        ch[3 - i] ? s[3 - i]
:
";

fn run_with_budget(budget: usize) -> (Result<(), String>, u64) {
    let compiled = common::compile(NODE);
    let opts = NetworkOptions {
        node: NodeConfig {
            memory_budget: budget,
            ..NodeConfig::default()
        },
        threads: 1,
    };
    let host = HostIo::new(
        Box::new(std::io::empty()),
        Box::new(std::io::sink()),
        Box::new(std::io::sink()),
    );
    let outcome = compiled
        .run_topology(Shape::Tree3(1), &opts, host)
        .expect("the network runs");
    let node = &outcome.nodes[0];
    let result = node
        .result
        .as_ref()
        .map(|_| ())
        .map_err(RunError::to_string);
    (result, node.stats.peak_workspace_bytes)
}

#[test]
fn the_most_a_node_takes_counts_the_vectors_held_at_once() {
    let most = common::compile(NODE).topology_node_bytes();
    let held = 4 * (68_000 + 24);
    let (ok, peak) = run_with_budget(most);
    assert_eq!(ok, Ok(()));
    assert!(peak as usize <= most, "peak {peak} over the bound {most}");
    assert!(
        peak as usize >= held,
        "peak {peak}: the replicated branches' vectors"
    );
    // without room for the replicated branches' vectors, a declaration stops the node
    let (short, _) = run_with_budget(most - held + 1000);
    let err = short.expect_err("a declaration finds too little left");
    assert!(err.contains("out of memory"), "{err}");
}
