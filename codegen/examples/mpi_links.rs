//! Links over MPI against plain MPI, side by side in one run (needs `--features mpi`).
//!
//! Run: `cargo build --release -p occ-codegen --features mpi --example mpi_links` and then
//! `mpirun -np 2 target/release/examples/mpi_links` (or `-np 4`; add `quick` for smaller counts;
//! as root, `--allow-run-as-root`; with more ranks than cores, `--oversubscribe`). Rank 0 prints:
//! - the 8-byte round trip and one-way time between two nodes over an MPI link (node 0 on rank
//!   0, node 1 on rank `K / 2`), and the throughput of 64 KB messages sent back and forth;
//! - plain MPI between the same two ranks (blocking send and receive): 8-byte one-way latency
//!   and 64 KB throughput;
//! - the same link programs in-process, two nodes on two threads of one rank.
//!
//! Each figure is the best of three runs; a link run's time includes starting the nodes and
//! agreeing that the network has finished.

use std::time::Duration;

use occ_codegen::network::NetworkOptions;
use occ_runtime::NodeConfig;
use occ_runtime::mpi::Mpi;
use occ_runtime::remote::Transport;
use occ_runtime::topology::Shape;

#[path = "../tests/common.rs"]
mod common;
#[path = "../benches/programs.rs"]
mod programs;

use programs::{ping_pong, quiet_host};

/// The best wall time of three runs of `n` round trips of `bytes` bytes between two nodes, over
/// `mpi` or in-process (every rank makes the same calls; the time is rank 0's).
fn link(mut mpi: Option<&mut Mpi>, n: u64, bytes: usize) -> Duration {
    let c = common::compile(&ping_pong(n, bytes));
    let pair: Shape = "pipeline:2".parse().expect("shape");
    let opts = NetworkOptions {
        node: NodeConfig::default(),
        threads: 2,
    };
    (0..3)
        .map(|_| {
            let t = mpi.as_deref_mut().map(|m| m as &mut dyn Transport);
            let o = c
                .run_topology_over(pair, &opts, quiet_host(), t)
                .expect("a node program");
            assert!(o.errors().is_empty(), "{:?}", o.errors());
            o.elapsed
        })
        .min()
        .unwrap_or_default()
}

/// Microseconds per one of `n`.
fn us(d: Duration, n: u64) -> f64 {
    d.as_secs_f64() * 1e6 / n as f64
}

/// MB/s of `n` round trips of `bytes` bytes.
fn mbs(d: Duration, n: u64, bytes: usize) -> f64 {
    2.0 * n as f64 * bytes as f64 / d.as_secs_f64() / 1e6
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let (n, m) = if quick { (2_000, 200) } else { (20_000, 2_000) };
    let mut mpi = Mpi::init().expect("MPI");
    let sp = mpi.spread();
    let peer = sp.owner(1, 2);
    let best_raw = |mpi: &Mpi, bytes, count| {
        (0..3)
            .map(|_| mpi.raw_round_trips(peer, bytes, count))
            .min()
            .unwrap_or_default()
    };
    let link8 = link(Some(&mut mpi), n, 8);
    let raw8 = best_raw(&mpi, 8, n);
    let link64 = link(Some(&mut mpi), m, 65536);
    let raw64 = best_raw(&mpi, 65536, m);
    if sp.rank != 0 {
        return;
    }
    // In-process on rank 0 alone.
    let here8 = link(None, n, 8);
    let here64 = link(None, m, 65536);
    println!(
        "{} ranks; the link's nodes on ranks 0 and {peer}; {n} 8-byte and {m} 64 KB round trips",
        sp.ranks
    );
    let line = |what: &str, d8: Duration, d64: Duration| {
        println!(
            "{what:<17} 8-byte round trip {:>8.2} us (one way {:>7.2} us); 64 KB messages {:>6.0} MB/s",
            us(d8, n),
            us(d8, 2 * n),
            mbs(d64, m, 65536)
        );
    };
    line("MPI link:", link8, link64);
    line("plain MPI:", raw8, raw64);
    line("in-process link:", here8, here64);
    println!(
        "MPI link / plain MPI: 8-byte latency {:.1}x, 64 KB throughput {:.2}x",
        link8.as_secs_f64() / raw8.as_secs_f64(),
        mbs(link64, m, 65536) / mbs(raw64, m, 65536)
    );
}
