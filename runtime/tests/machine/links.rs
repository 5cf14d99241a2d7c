//! Two nodes on two OS threads joined by links; network-wide deadlock detection.

use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::chan::{rt_in, rt_out};
use occ_runtime::{Network, Node, RunError};

use crate::common::*;

/// Sends i = 0..n over local 0, reads a reply over local 1 each time, sums the replies in 5.
/// Locals: 0 out, 1 in, 2 n, 3 i, 4 buffer, 5 sum.
unsafe extern "C" fn pinger(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    *l(ws, 5) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return Status::DONE;
                    }
                    *l(ws, 4) = *l(ws, 3);
                    set_iptr(ws, 2);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 4).cast(), 8));
                }
                2 => {
                    set_iptr(ws, 3);
                    check!(rt_in(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                _ => {
                    *l(ws, 5) += *l(ws, 4);
                    *l(ws, 3) += 1;
                    set_iptr(ws, 1);
                }
            }
        }
    }
}

/// Reads a value over local 1 and replies with twice it over local 0, n times.
/// Locals: 0 out, 1 in, 2 n, 3 i, 4 buffer.
unsafe extern "C" fn doubler(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                2 => {
                    *l(ws, 4) *= 2;
                    *l(ws, 3) += 1;
                    set_iptr(ws, 1);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 4).cast(), 8));
                }
                _ => unreachable!(),
            }
        }
    }
}

fn run_on_thread(
    mut node: Box<Node>,
) -> std::thread::JoinHandle<(Box<Node>, Result<(), RunError>)> {
    std::thread::spawn(move || {
        let r = node.run();
        (node, r)
    })
}

#[test]
fn ping_pong_over_links_between_two_threads() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    let (b_out, a_in) = net.connect(&mut b, &mut a, "b->a");
    let n = 1000;
    let wa = spawn(&mut a, pinger, 6, &[a_out as Word, a_in as Word, n]) as usize;
    spawn(&mut b, doubler, 5, &[b_out as Word, b_in as Word, n]);
    let (ha, hb) = (run_on_thread(a), run_on_thread(b));
    let (a, ra) = ha.join().unwrap();
    let (b, rb) = hb.join().unwrap();
    ra.unwrap();
    rb.unwrap();
    let sum = unsafe { *l(wa as Wptr, 5) };
    assert_eq!(sum, (0..n).map(|i| 2 * i).sum::<Word>());
    assert_eq!(
        a.stats().communications + b.stats().communications,
        2 * n as u64
    );
}

#[test]
fn network_deadlock_is_reported_by_every_waiting_node() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (_a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    let (_b_out, a_in) = net.connect(&mut b, &mut a, "b->a");
    // Both nodes input first: neither ever outputs.
    spawn(&mut a, doubler, 5, &[0, a_in as Word, 1]);
    spawn(&mut b, doubler, 5, &[0, b_in as Word, 1]);
    let (ha, hb) = (run_on_thread(a), run_on_thread(b));
    for (h, name) in [(ha, "b->a (link in)"), (hb, "a->b (link in)")] {
        let (_, r) = h.join().unwrap();
        let err = r.expect_err("deadlock");
        let text = err.to_string();
        assert!(matches!(err, RunError::Deadlock(_)));
        assert!(
            text.contains(&format!("input from channel {name}")),
            "{text}"
        );
    }
}

#[test]
fn a_finished_node_does_not_keep_its_peer_waiting() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (_a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    spawn(&mut b, doubler, 5, &[0, b_in as Word, 1]);
    // a has no process at all: it finishes at once; b must then report deadlock, not hang.
    let (ha, hb) = (run_on_thread(a), run_on_thread(b));
    assert!(ha.join().unwrap().1.is_ok());
    assert!(matches!(hb.join().unwrap().1, Err(RunError::Deadlock(_))));
}

#[test]
fn alt_on_a_link_input_is_woken_by_the_remote_writer() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    // b: PRI ALT { link ? x; tim ? AFTER now + 5 s }; a: wait 1 ms, then output 77.
    let out = Box::into_raw(Box::new((-1 as Word, -1 as Word)));
    spawn(
        &mut b,
        crate::timers::timed_alter,
        7,
        &[b_in as Word, 5_000_000, 0, out as Word],
    );
    spawn(
        &mut a,
        crate::timers::late_sender,
        3,
        &[a_out as Word, 77, 1000],
    );
    let (ha, hb) = (run_on_thread(a), run_on_thread(b));
    ha.join().unwrap().1.unwrap();
    hb.join().unwrap().1.unwrap();
    // SAFETY: both nodes have finished; `out` was written by b's process.
    let (sel, waited) = unsafe { *Box::from_raw(out) };
    assert_eq!(sel, 0, "the link guard was selected");
    assert!(waited < 4_000_000, "the timer did not fire ({waited} µs)");
}

/// Ring member on its own node: inputs from local 1, adds 1, outputs on local 0; `n` times.
/// The first node starts by outputting. Locals: 0 out, 1 in, 2 n, 3 i, 4 buffer, 5 first.
unsafe extern "C" fn ring_node(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    set_iptr(ws, if *l(ws, 5) != 0 { 2 } else { 1 });
                }
                1 => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                2 => {
                    *l(ws, 4) += 1;
                    set_iptr(ws, 3);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 4).cast(), 8));
                }
                3 => {
                    *l(ws, 3) += 1;
                    // The first node inputs the token back after each output.
                    set_iptr(ws, if *l(ws, 5) != 0 { 5 } else { 1 });
                }
                5 => {
                    set_iptr(ws, 4);
                    check!(rt_in(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                _ => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                }
            }
        }
    }
}

/// Builds a ring of `nodes` nodes passing a token `rounds` times; runs it with `run`; checks the
/// token's final value.
fn ring_of_nodes(
    nodes: usize,
    rounds: Word,
    run: impl FnOnce(Vec<Box<Node>>) -> Vec<(Box<Node>, Result<(), RunError>)>,
) {
    let net = Network::new();
    let mut all: Vec<Box<Node>> = (0..nodes).map(|_| node().0).collect();
    for n in all.iter_mut() {
        net.join(n);
    }
    let mut ends = Vec::new(); // (out of i, in of i+1)
    for i in 0..nodes {
        let j = (i + 1) % nodes;
        let (from, to) = if i < j {
            let (a, b) = all.split_at_mut(j);
            (&mut a[i], &mut b[0])
        } else {
            let (a, b) = all.split_at_mut(i);
            (&mut b[0], &mut a[j])
        };
        ends.push(net.connect(from, to, &format!("{i}->{j}")));
    }
    let mut first_ws = 0usize;
    for (i, n) in all.iter_mut().enumerate() {
        let out = ends[i].0 as Word;
        let inp = ends[(i + nodes - 1) % nodes].1 as Word;
        let ws = spawn(n, ring_node, 6, &[out, inp, rounds, 0, 0, (i == 0) as Word]);
        if i == 0 {
            first_ws = ws as usize;
        }
    }
    let results = run(all);
    let outcomes: Vec<String> = results
        .iter()
        .map(|(n, r)| format!("{r:?} comms={}", n.stats().communications))
        .collect();
    for (_, r) in &results {
        assert!(r.is_ok(), "{outcomes:#?}");
    }
    // Each node adds 1 per round.
    unsafe { assert_eq!(*l(first_ws as Wptr, 4), nodes as Word * rounds) };
}

#[test]
fn a_ring_of_eight_nodes_passes_a_token() {
    ring_of_nodes(8, 50, Network::run_all);
}

#[test]
fn a_ring_of_64_nodes_on_a_pool_of_two_threads() {
    ring_of_nodes(64, 20, |n| Network::run_pool(n, 2));
}

#[test]
fn a_ring_of_nodes_on_a_single_thread() {
    ring_of_nodes(16, 10, |n| Network::run_pool(n, 1));
}

#[test]
fn pool_reports_a_network_deadlock() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (_a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    let (_b_out, a_in) = net.connect(&mut b, &mut a, "b->a");
    spawn(&mut a, doubler, 5, &[0, a_in as Word, 1]);
    spawn(&mut b, doubler, 5, &[0, b_in as Word, 1]);
    for (_, r) in Network::run_pool(vec![a, b], 2) {
        assert!(matches!(r, Err(RunError::Deadlock(_))), "{r:?}");
    }
}

#[test]
fn pool_wakes_nodes_for_timers_and_mail() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    let out = Box::into_raw(Box::new((-1 as Word, -1 as Word)));
    spawn(
        &mut b,
        crate::timers::timed_alter,
        7,
        &[b_in as Word, 5_000_000, 0, out as Word],
    );
    spawn(
        &mut a,
        crate::timers::late_sender,
        3,
        &[a_out as Word, 77, 2000],
    );
    for (_, r) in Network::run_pool(vec![a, b], 1) {
        assert!(r.is_ok(), "{r:?}");
    }
    // SAFETY: both nodes have finished; `out` was written by b's process.
    let (sel, waited) = unsafe { *Box::from_raw(out) };
    assert_eq!(sel, 0, "the link guard was selected");
    assert!(waited < 4_000_000, "{waited} µs");
}

#[test]
fn a_dropped_node_does_not_keep_its_peer_waiting() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (_a_out, b_in) = net.connect(&mut a, &mut b, "a->b");
    spawn(&mut b, doubler, 5, &[0, b_in as Word, 1]);
    let hb = run_on_thread(b);
    drop(a);
    assert!(matches!(hb.join().unwrap().1, Err(RunError::Deadlock(_))));
}

/// Halts the node at once (an unregistered location).
unsafe extern "C" fn halts(ws: Wptr, node: *mut Node) -> Status {
    unsafe { occ_runtime::error::rt_error(node, ws, occ_runtime::ErrorKind::Stop as Word, -1) }
}

#[test]
fn a_halted_node_withdraws_from_its_links_and_stops_its_network() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let (b_out, a_in) = net.connect(&mut b, &mut a, "b->a");
    // a: a reader waits on the link, then another process halts the node.
    spawn(&mut a, doubler, 5, &[0, a_in as Word, 1]);
    spawn(&mut a, halts, 1, &[]);
    // b: outputs on the link 20 ms later, when a has long stopped.
    spawn(
        &mut b,
        crate::timers::late_sender,
        3,
        &[b_out as Word, 1, 20_000],
    );
    let (ha, hb) = (run_on_thread(a), run_on_thread(b));
    let (a, ra) = ha.join().unwrap();
    assert!(matches!(ra, Err(RunError::Halted(_))));
    drop(a);
    // The reader's registration went with its node, and the halt stopped the network: b does
    // not wait for a reader that will never come, it stops.
    match hb.join().unwrap().1 {
        Err(RunError::Halted(h)) => assert_eq!(h.kind, Some(occ_runtime::ErrorKind::Stopped)),
        other => panic!("b should stop with the network: {other:?}"),
    }
}

// Stress: node a runs 3 senders, each sending `PER` values over its own link, rescheduling at
// random; node b ALTs over the 3 link inputs with a 200 µs timer guard, until it has every value
// (or 20,000 timeouts, so that a lost message fails the test instead of hanging it).

const LINKS: usize = 3;
const PER: Word = 300;

/// Sends PER values (k*1000 + i) on local 0, rescheduling when a random bit says so.
/// Locals: 0 chan, 1 k, 2 i, 3 value, 4 random state.
unsafe extern "C" fn jittery_sender(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 2) = 0;
                    *l(ws, 4) = 0x2545_F491 + *l(ws, 1);
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 2) == PER {
                        return Status::DONE;
                    }
                    *l(ws, 3) = *l(ws, 1) * 1000 + *l(ws, 2);
                    *l(ws, 2) += 1;
                    set_iptr(ws, 2);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 3).cast(), 8));
                }
                _ => {
                    let mut x = *l(ws, 4) as u64;
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    *l(ws, 4) = x as Word;
                    set_iptr(ws, 1);
                    if x.is_multiple_of(4) {
                        check!(occ_runtime::sched::rt_reschedule(node, ws));
                    }
                }
            }
        }
    }
}

/// Locals: 0 address of LINKS channel words, 1 received, 2 sum, 3 timeouts, 4 buffer,
/// 5 deadline, 6 selected.
unsafe extern "C" fn link_alter(ws: Wptr, node: *mut Node) -> Status {
    use occ_runtime::alt::*;
    use occ_runtime::timer::rt_timer_read;
    unsafe {
        let ch = |i: usize| *(*l(ws, 0) as *const Word).add(i) as *mut Word;
        loop {
            match iptr(ws) {
                0 => {
                    if *l(ws, 1) == LINKS as Word * PER || *l(ws, 3) == 20_000 {
                        return Status::DONE;
                    }
                    *l(ws, 5) = rt_timer_read(node) + 200;
                    rt_talt(node, ws);
                    for i in 0..LINKS {
                        rt_enbc(node, ws, 1, ch(i));
                    }
                    rt_enbt(node, ws, 1, *l(ws, 5));
                    set_iptr(ws, 1);
                    check!(rt_taltwt(node, ws));
                }
                1 => {
                    let start = (*l(ws, 1) as usize) % LINKS; // rotate for fairness
                    for k in 0..LINKS {
                        let i = (start + k) % LINKS;
                        rt_disc(node, ws, 1, ch(i), i as Word);
                    }
                    rt_dist(node, ws, 1, *l(ws, 5), LINKS as Word);
                    *l(ws, 6) = rt_altend(node, ws);
                    if *l(ws, 6) == LINKS as Word {
                        *l(ws, 3) += 1;
                        set_iptr(ws, 0);
                        continue;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, ch(*l(ws, 6) as usize), l(ws, 4).cast(), 8));
                }
                _ => {
                    *l(ws, 1) += 1;
                    *l(ws, 2) += *l(ws, 4);
                    set_iptr(ws, 0);
                }
            }
        }
    }
}

#[test]
fn alt_over_links_with_jittery_senders_receives_everything() {
    let net = Network::new();
    let (mut a, _) = node();
    let (mut b, _) = node();
    net.join(&mut a);
    net.join(&mut b);
    let mut ins: Box<[Word; LINKS]> = Box::new([0; LINKS]);
    for k in 0..LINKS {
        let (out, inp) = net.connect(&mut a, &mut b, &format!("l{k}"));
        ins[k] = inp as Word;
        spawn(&mut a, jittery_sender, 5, &[out as Word, k as Word]);
    }
    let wb = spawn(&mut b, link_alter, 7, &[ins.as_ptr() as Word]) as usize;
    let results = Network::run_pool(vec![a, b], 1);
    for (_, r) in &results {
        assert!(r.is_ok(), "{r:?}");
    }
    let expected: Word = (0..LINKS as Word)
        .map(|k| (0..PER).map(|i| k * 1000 + i).sum::<Word>())
        .sum();
    unsafe {
        assert_eq!(
            *l(wb as Wptr, 1),
            LINKS as Word * PER,
            "every message arrived"
        );
        assert_eq!(*l(wb as Wptr, 2), expected);
    }
    drop(results);
}
