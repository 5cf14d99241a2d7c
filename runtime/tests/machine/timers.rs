//! Timers: `tim ? AFTER t`, the timer queue order, and timer guards in ALT.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::alt::*;
use occ_runtime::chan::rt_in;
use occ_runtime::timer::{after, rt_timer_read, rt_tin};

use crate::common::*;

/// Waits until after now + delay; logs (tag, time waited). Locals: 0 delay, 1 log, 2 tag,
/// 3 start, 4 deadline.
unsafe extern "C" fn sleeper(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            *l(ws, 3) = rt_timer_read(node);
            *l(ws, 4) = *l(ws, 3) + *l(ws, 0);
            set_iptr(ws, 1);
            check!(rt_tin(node, ws, *l(ws, 4)));
        }
        let now = rt_timer_read(node);
        assert!(after(now, *l(ws, 4)), "woke strictly after the deadline");
        (*(*l(ws, 1) as *mut Vec<(Word, Word)>)).push((*l(ws, 2), now - *l(ws, 3)));
        Status::DONE
    }
}

#[test]
fn timer_queue_wakes_in_time_order() {
    let (mut node, _) = node();
    let mut log: Vec<(Word, Word)> = Vec::new();
    let logp = &mut log as *mut _ as Word;
    for (tag, delay) in [(1, 3000), (2, 1000), (3, 2000), (4, -5)] {
        spawn(&mut node, sleeper, 5, &[delay, logp, tag]);
    }
    node.run().unwrap();
    let order: Vec<Word> = log.iter().map(|e| e.0).collect();
    assert_eq!(order, vec![4, 2, 3, 1]);
    for (tag, waited) in log {
        let delay = [0, 3000, 1000, 2000, 0][tag as usize];
        assert!(waited > delay.max(0) - 1, "tag {tag} waited {waited} µs");
    }
}

// Timer-guard ALTer locals.
const CHAN: usize = 0;
const DELAY: usize = 1;
const BUF: usize = 2;
const OUT: usize = 3; // *mut (selected, waited µs)
const START: usize = 4;
const DEADLINE: usize = 5;
const SEL: usize = 6;

/// PRI ALT { chan ? x; tim ? AFTER start + delay }.
pub(crate) unsafe extern "C" fn timed_alter(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, START) = rt_timer_read(node);
                    *l(ws, DEADLINE) = *l(ws, START) + *l(ws, DELAY);
                    rt_talt(node, ws);
                    rt_enbc(node, ws, 1, *l(ws, CHAN) as *mut Word);
                    rt_enbt(node, ws, 1, *l(ws, DEADLINE));
                    set_iptr(ws, 1);
                    check!(rt_taltwt(node, ws));
                }
                1 => {
                    rt_disc(node, ws, 1, *l(ws, CHAN) as *mut Word, 0);
                    rt_dist(node, ws, 1, *l(ws, DEADLINE), 1);
                    *l(ws, SEL) = rt_altend(node, ws);
                    set_iptr(ws, 2);
                    if *l(ws, SEL) == 0 {
                        check!(rt_in(
                            node,
                            ws,
                            *l(ws, CHAN) as *mut Word,
                            l(ws, BUF).cast(),
                            8
                        ));
                    }
                }
                _ => {
                    let waited = rt_timer_read(node) - *l(ws, START);
                    *(*l(ws, OUT) as *mut (Word, Word)) = (*l(ws, SEL), waited);
                    return Status::DONE;
                }
            }
        }
    }
}

/// Sleeps `delay` µs, then outputs. Locals: 0 chan, 1 value, 2 delay.
pub(crate) unsafe extern "C" fn late_sender(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            let t = rt_timer_read(node) + *l(ws, 2);
            set_iptr(ws, 1);
            check!(rt_tin(node, ws, t));
        }
        if iptr(ws) == 1 {
            set_iptr(ws, 2);
            check!(occ_runtime::chan::rt_out(
                node,
                ws,
                *l(ws, 0) as *mut Word,
                l(ws, 1).cast(),
                8
            ));
        }
        Status::DONE
    }
}

#[test]
fn timer_guard_fires_when_no_channel_is_ready() {
    let (mut node, _) = node();
    let mut c = channel();
    let mut out: (Word, Word) = (-1, -1);
    let init = [
        &mut *c as *mut Word as Word,
        3000,
        0,
        &mut out as *mut _ as Word,
    ];
    spawn(&mut node, timed_alter, 7, &init);
    node.run().unwrap();
    assert_eq!(out.0, 1, "the timer guard was selected");
    assert!(out.1 > 3000, "waited {} µs", out.1);
    assert_eq!(*c, 0, "the channel guard was disabled");
}

#[test]
fn channel_guard_beats_a_later_timer() {
    let (mut node, _) = node();
    let mut c = channel();
    let mut out: (Word, Word) = (-1, -1);
    let chan = &mut *c as *mut Word as Word;
    spawn(
        &mut node,
        timed_alter,
        7,
        &[chan, 10_000_000, 0, &mut out as *mut _ as Word],
    );
    spawn(&mut node, late_sender, 3, &[chan, 77, 1000]);
    node.run().unwrap();
    assert_eq!(out.0, 0, "the channel was selected");
    assert!(
        out.1 < 5_000_000,
        "did not wait for the timer ({} µs)",
        out.1
    );
}

#[test]
fn timer_guard_already_past_is_ready_at_once() {
    let (mut node, _) = node();
    let mut c = channel();
    let mut out: (Word, Word) = (-1, -1);
    let init = [
        &mut *c as *mut Word as Word,
        -10,
        0,
        &mut out as *mut _ as Word,
    ];
    spawn(&mut node, timed_alter, 7, &init);
    node.run().unwrap();
    assert_eq!(out.0, 1);
}

#[test]
fn pri_alt_prefers_the_ready_channel_over_an_expired_timer_before_it_in_order() {
    let (mut node, _) = node();
    let mut c = channel();
    let mut out: (Word, Word) = (-1, -1);
    let chan = &mut *c as *mut Word as Word;
    // The sender is already waiting and the timer has expired: both guards are ready; the
    // channel is disabled first, so it wins.
    spawn(&mut node, late_sender, 3, &[chan, 5, -100]);
    spawn(
        &mut node,
        timed_alter,
        7,
        &[chan, -10, 0, &mut out as *mut _ as Word],
    );
    node.run().unwrap();
    assert_eq!(out.0, 0);
}
