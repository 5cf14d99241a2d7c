//! Micro-benchmarks of the process machine with hand-written processes in the exact shape codegen
//! emits (dispatch on the resume index, state in the workspace, after-op index stored before each
//! blocking entry, back-edge polls):
//!
//! - `commstime/seq_delta` and `commstime/par_delta`: ns per loop of KRoC's commstime (prefix,
//!   delta, succ, consume; 4 communications per loop; PAR delta adds 2 process start/ends).
//! - `alt/two_guard`: ns per PRI ALT over two channels, one of which has a sender (ALT + input).
//! - `process/start_end`: ns per PAR of one branch (startp, dispatch, endp, parent resumed).
//!
//! Run: `cargo bench -p occ-runtime --bench machine`. Each criterion iteration is one loop; a
//! sample runs a fresh node for that many loops. Times are **thread CPU time**
//! (`CLOCK_THREAD_CPUTIME_ID`), so that other load on the
//! shared 2-core machine does not inflate them; the node runs on the measuring thread.

use std::time::Duration;

use criterion::{Criterion, criterion_group};
use occ_runtime::abi::{ProcFn, Status, Word, Wptr, join, slot};
use occ_runtime::alt::{rt_alt, rt_altend, rt_altwt, rt_disc, rt_enbc};
use occ_runtime::chan::{rt_in, rt_out};
use occ_runtime::par::{rt_endp, rt_par_wait, rt_startp};
use occ_runtime::sched::rt_timeslice;
use occ_runtime::{HostIo, Node, NodeConfig, ProgramInfo};

#[inline(always)]
unsafe fn l(ws: Wptr, i: usize) -> *mut Word {
    unsafe { ws.add(i) }
}

#[inline(always)]
unsafe fn iptr(ws: Wptr) -> Word {
    unsafe { *ws.offset(slot::IPTR) }
}

#[inline(always)]
unsafe fn set_iptr(ws: Wptr, k: Word) {
    unsafe { *ws.offset(slot::IPTR) = k }
}

macro_rules! check {
    ($st:expr) => {{
        let st = $st;
        if st != Status::DONE {
            return st;
        }
    }};
}

macro_rules! poll {
    ($node:expr, $ws:expr, $k:expr) => {{
        let flag =
            ($node as *const u8).add(occ_runtime::abi::YIELD_FLAG_OFFSET as usize) as *const u32;
        if std::ptr::read_volatile(flag) != 0 {
            set_iptr($ws, $k);
            check!(rt_timeslice($node, $ws));
        }
    }};
}

unsafe fn chan(ws: Wptr, i: usize) -> *mut Word {
    unsafe { *l(ws, i) as *mut Word }
}

// Common locals: 0..=2 channels, 3 count n, 4 i, 5 value.
const N: usize = 3;
const I: usize = 4;
const X: usize = 5;

/// prefix: out a (0); (n-1) × (in d; out a); in d. Channels: 0 = d (in), 1 = a (out).
unsafe extern "C" fn prefix(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, X) = 0;
                    *l(ws, I) = 1;
                    set_iptr(ws, 1);
                    check!(rt_out(node, ws, chan(ws, 1), l(ws, X).cast(), 8));
                }
                1 => {
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, 0), l(ws, X).cast(), 8));
                }
                2 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    *l(ws, I) += 1;
                    set_iptr(ws, 3);
                    check!(rt_out(node, ws, chan(ws, 1), l(ws, X).cast(), 8));
                }
                3 => {
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// SEQ delta: n × (in a; out b; out c). Channels: 0 = a, 1 = b, 2 = c.
unsafe extern "C" fn seq_delta(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, 0), l(ws, X).cast(), 8));
                }
                2 => {
                    set_iptr(ws, 3);
                    check!(rt_out(node, ws, chan(ws, 1), l(ws, X).cast(), 8));
                }
                3 => {
                    set_iptr(ws, 4);
                    check!(rt_out(node, ws, chan(ws, 2), l(ws, X).cast(), 8));
                }
                4 => {
                    *l(ws, I) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

// PAR delta: the join block at locals 6, 7; two branch frames above.
const JOIN: usize = 6;
const BR_LOCALS: usize = 3; // 0 join, 1 channel, 2 value address
const BR0: usize = 8 + slot::HEADER_WORDS;
const BR_STRIDE: usize = slot::HEADER_WORDS + BR_LOCALS;
const PAR_DELTA_WORDS: usize = BR0 + 2 * BR_STRIDE;

/// A PAR branch `out ch ! x`, then endp.
unsafe extern "C" fn out_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            set_iptr(ws, 1);
            check!(rt_out(node, ws, chan(ws, 1), *l(ws, 2) as *mut u8, 8));
        }
        rt_endp(node, ws, *l(ws, 0) as *mut Word)
    }
}

/// PAR delta: n × (in a; PAR (out b; out c)).
unsafe extern "C" fn par_delta(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, 0), l(ws, X).cast(), 8));
                }
                2 => {
                    let j = l(ws, JOIN);
                    *j.offset(join::PARENT) = 0;
                    *j.offset(join::COUNT) = 2;
                    for k in 0..2 {
                        let b = ws.add(BR0 + k * BR_STRIDE);
                        *l(b, 0) = j as Word;
                        *l(b, 1) = *l(ws, 1 + k);
                        *l(b, 2) = l(ws, X) as Word;
                        rt_startp(node, ws, b, out_branch, 0);
                    }
                    set_iptr(ws, 3);
                    check!(rt_par_wait(node, ws, j));
                }
                3 => {
                    *l(ws, I) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// succ: n × (in c; out d (x + 1)). Channels: 0 = c, 1 = d.
unsafe extern "C" fn succ(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, 0), l(ws, X).cast(), 8));
                }
                2 => {
                    *l(ws, X) += 1;
                    set_iptr(ws, 3);
                    check!(rt_out(node, ws, chan(ws, 1), l(ws, X).cast(), 8));
                }
                3 => {
                    *l(ws, I) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// consume: n × in b. Channel 0 = b.
unsafe extern "C" fn consume(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    *l(ws, I) += 1;
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, 0), l(ws, X).cast(), 8));
                }
                2 => {
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// CPU time consumed by this thread so far.
fn thread_cpu() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid timespec out-pointer and a clock id supported by Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// Runs the node and returns the thread CPU time it took.
fn timed_run(mut node: Box<Node>) -> Duration {
    let t = thread_cpu();
    node.run().expect("benchmark ends cleanly");
    thread_cpu() - t
}

fn fresh_node() -> Box<Node> {
    Node::new(
        NodeConfig::default(),
        std::sync::Arc::new(ProgramInfo::default()),
        HostIo::stdio(),
    )
}

fn spawn(node: &mut Node, code: ProcFn, words: usize, init: &[Word]) -> Wptr {
    let ws = node.alloc_workspace(words).expect("workspace");
    // SAFETY: a fresh workspace of `words` locals.
    unsafe {
        for (i, v) in init.iter().enumerate() {
            *ws.add(i) = *v;
        }
        node.spawn(ws, code);
    }
    ws
}

/// Runs commstime for `loops` loops and returns the elapsed time.
fn commstime(loops: u64, delta: ProcFn, delta_words: usize) -> Duration {
    let mut node = fresh_node();
    let mut chans = [0 as Word; 4];
    let c: Vec<Word> = chans.iter_mut().map(|w| w as *mut Word as Word).collect();
    let (a, b, cc, d) = (c[0], c[1], c[2], c[3]);
    let n = loops as Word;
    spawn(&mut node, prefix, 6, &[d, a, 0, n]);
    spawn(&mut node, delta, delta_words, &[a, b, cc, n]);
    spawn(&mut node, succ, 6, &[cc, d, 0, n]);
    spawn(&mut node, consume, 6, &[b, 0, 0, n]);
    timed_run(node)
}

fn bench_commstime(c: &mut Criterion) {
    let mut g = c.benchmark_group("commstime");
    g.bench_function("seq_delta", |b| {
        b.iter_custom(|loops| commstime(loops, seq_delta, 6))
    });
    g.bench_function("par_delta", |b| {
        b.iter_custom(|loops| commstime(loops, par_delta, PAR_DELTA_WORDS))
    });
    g.finish();
}

/// Sends n values on channel 0.
unsafe extern "C" fn sender(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    *l(ws, I) += 1;
                    set_iptr(ws, 2);
                    check!(rt_out(node, ws, chan(ws, 0), l(ws, I).cast(), 8));
                }
                2 => {
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// n × PRI ALT { c0 ? x: SKIP; c1 ? x: SKIP }. Channels 0, 1.
unsafe extern "C" fn alter(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    rt_alt(node, ws);
                    rt_enbc(node, ws, 1, chan(ws, 0));
                    rt_enbc(node, ws, 1, chan(ws, 1));
                    set_iptr(ws, 2);
                    check!(rt_altwt(node, ws));
                }
                2 => {
                    rt_disc(node, ws, 1, chan(ws, 0), 0);
                    rt_disc(node, ws, 1, chan(ws, 1), 1);
                    let sel = rt_altend(node, ws) as usize;
                    set_iptr(ws, 3);
                    check!(rt_in(node, ws, chan(ws, sel), l(ws, X).cast(), 8));
                }
                3 => {
                    *l(ws, I) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

fn two_guard_alt(loops: u64) -> Duration {
    let mut node = fresh_node();
    let mut chans = [0 as Word; 2];
    let c0 = &mut chans[0] as *mut Word as Word;
    let c1 = &mut chans[1] as *mut Word as Word;
    let n = loops as Word;
    spawn(&mut node, alter, 6, &[c0, c1, 0, n]);
    spawn(&mut node, sender, 6, &[c1, 0, 0, n]);
    timed_run(node)
}

/// n × PAR { SKIP } with the branch as its own process: startp, endp, join.
unsafe extern "C" fn starter(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, I) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, I) == *l(ws, N) {
                        return Status::DONE;
                    }
                    let j = l(ws, JOIN);
                    *j.offset(join::PARENT) = 0;
                    *j.offset(join::COUNT) = 1;
                    let b = ws.add(BR0);
                    *l(b, 0) = j as Word;
                    rt_startp(node, ws, b, skip_branch, 0);
                    set_iptr(ws, 2);
                    check!(rt_par_wait(node, ws, j));
                }
                2 => {
                    *l(ws, I) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

unsafe extern "C" fn skip_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe { rt_endp(node, ws, *l(ws, 0) as *mut Word) }
}

fn start_end(loops: u64) -> Duration {
    let mut node = fresh_node();
    spawn(
        &mut node,
        starter,
        PAR_DELTA_WORDS,
        &[0, 0, 0, loops as Word],
    );
    timed_run(node)
}

fn bench_alt_and_processes(c: &mut Criterion) {
    c.bench_function("alt/two_guard", |b| b.iter_custom(two_guard_alt));
    c.bench_function("process/start_end", |b| b.iter_custom(start_end));
}

criterion_group!(benches, bench_commstime, bench_alt_and_processes);

/// With `OCC_BENCH_ONCE=<name>:<loops>` (name: seq, par, alt, start), runs that benchmark once
/// and exits, for instruction counting under `valgrind --tool=callgrind`; otherwise criterion.
fn main() {
    if let Some((name, loops)) = std::env::var("OCC_BENCH_ONCE")
        .ok()
        .and_then(|v| {
            v.split_once(':')
                .map(|(a, b)| (a.to_string(), b.parse::<u64>().ok()))
        })
        .and_then(|(a, b)| b.map(|b| (a, b)))
    {
        let t = match name.as_str() {
            "seq" => commstime(loops, seq_delta, 6),
            "par" => commstime(loops, par_delta, PAR_DELTA_WORDS),
            "alt" => two_guard_alt(loops),
            _ => start_end(loops),
        };
        println!("{name}: {:.1} ns/loop", t.as_nanos() as f64 / loops as f64);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
