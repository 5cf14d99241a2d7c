//! Memory benchmark: a ring of P concurrent processes (default 1,000,000) passing a token for R
//! rounds (default 3), in one node. Prints the resident memory (VmRSS now, VmHWM peak, from
//! /proc/self/status), bytes per process and ns per hop.
//!
//! Run: `cargo bench -p occ-runtime --bench ring_memory [-- P R]`.

use std::time::Instant;

use occ_runtime::abi::{Status, Word, Wptr, slot};
use occ_runtime::chan::{rt_in, rt_out};
use occ_runtime::{HostIo, Node, NodeConfig, ProgramInfo};

// Locals: 0 in channel, 1 out channel, 2 rounds left, 3 token / first flag.
const WORDS: usize = 4;

macro_rules! check {
    ($st:expr) => {{
        let st = $st;
        if st != Status::DONE {
            return st;
        }
    }};
}

/// A ring member: rounds × (in; out), or for the first process rounds × (out; in).
unsafe extern "C" fn member(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        let ip = ws.offset(slot::IPTR);
        let (cin, cout) = (*ws as *mut Word, *ws.add(1) as *mut Word);
        let tok = ws.add(3).cast::<u8>();
        loop {
            match *ip {
                0 => *ip = if *ws.add(3) != 0 { 10 } else { 1 },
                // others: rounds × (in; out)
                1 => {
                    *ip = 2;
                    check!(rt_in(node, ws, cin, tok, 8));
                }
                2 => {
                    *ip = 3;
                    check!(rt_out(node, ws, cout, tok, 8));
                }
                3 => {
                    *ws.add(2) -= 1;
                    if *ws.add(2) == 0 {
                        return Status::DONE;
                    }
                    *ip = 1;
                }
                // the first: rounds × (out; in)
                10 => {
                    *ip = 11;
                    check!(rt_out(node, ws, cout, tok, 8));
                }
                11 => {
                    *ip = 12;
                    check!(rt_in(node, ws, cin, tok, 8));
                }
                12 => {
                    *ws.add(2) -= 1;
                    if *ws.add(2) == 0 {
                        return Status::DONE;
                    }
                    *ip = 10;
                }
                _ => unreachable!(),
            }
        }
    }
}

/// Reads a `kB` field of /proc/self/status.
fn status_kb(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let nums: Vec<u64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let p = *nums.first().unwrap_or(&1_000_000) as usize;
    let rounds = *nums.get(1).unwrap_or(&3) as Word;
    let before = status_kb("VmRSS:").unwrap_or(0);
    let config = NodeConfig {
        timeslice: false,
        ..NodeConfig::default()
    };
    let mut node = Node::new(
        config,
        std::sync::Arc::new(ProgramInfo::default()),
        HostIo::stdio(),
    );
    let mut chans = vec![0 as Word; p];
    let base = chans.as_mut_ptr();
    let t0 = Instant::now();
    for i in 0..p {
        let ws = node
            .alloc_workspace(WORDS)
            .expect("within the node's memory budget");
        // SAFETY: a fresh workspace of WORDS locals; channel words live in `chans`.
        unsafe {
            *ws = base.add(i) as Word;
            *ws.add(1) = base.add((i + 1) % p) as Word;
            *ws.add(2) = rounds;
            *ws.add(3) = (i == 0) as Word;
            node.spawn(ws, member);
        }
    }
    let spawned = t0.elapsed();
    let t1 = Instant::now();
    let result = node.run();
    let ran = t1.elapsed();
    let rss = status_kb("VmRSS:").unwrap_or(0);
    let hwm = status_kb("VmHWM:").unwrap_or(0);
    let hops = p as f64 * rounds as f64;
    println!("ring of {p} processes, {rounds} rounds: {result:?}");
    println!(
        "spawn {:.1} ms ({:.0} ns/process); run {:.1} ms ({:.1} ns/hop)",
        spawned.as_secs_f64() * 1e3,
        spawned.as_nanos() as f64 / p as f64,
        ran.as_secs_f64() * 1e3,
        ran.as_nanos() as f64 / hops
    );
    println!(
        "VmRSS {:.1} MB (before {:.1} MB), VmHWM {:.1} MB; {:.0} bytes/process; peak workspace {} bytes",
        rss as f64 / 1024.0,
        before as f64 / 1024.0,
        hwm as f64 / 1024.0,
        (hwm.saturating_sub(before) * 1024) as f64 / p as f64,
        node.stats().peak_workspace_bytes
    );
    println!("{}", node.stats());
    drop(chans);
}
