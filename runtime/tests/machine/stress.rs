//! Many processes at once: a fan-in of senders (some high priority, some yielding at random)
//! into one replicated ALT, and a long pipeline; every message must arrive exactly once.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr, join, priority, slot};
use occ_runtime::alt::*;
use occ_runtime::chan::{rt_in, rt_out};
use occ_runtime::par::{rt_endp, rt_par_wait, rt_startp, rt_startp_pri};
use occ_runtime::sched::rt_reschedule;

use crate::common::*;

/// A tiny deterministic generator (xorshift) kept in a workspace word.
unsafe fn next_random(state: *mut Word) -> Word {
    unsafe {
        let mut x = *state as u64;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        *state = x as Word;
        (x >> 33) as Word
    }
}

// Sender branch locals: 0 join, 1 chan, 2 count, 3 i, 4 value, 5 random state.
const S_WORDS: usize = 6;

/// Sends count values (id * 1_000_000 + i), rescheduling at random in between.
unsafe extern "C" fn fan_sender(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return rt_endp(node, ws, *l(ws, 0) as *mut Word);
                    }
                    *l(ws, 4) += 1;
                    set_iptr(ws, 2);
                    check!(rt_out(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                2 => {
                    *l(ws, 3) += 1;
                    set_iptr(ws, 1);
                    if next_random(l(ws, 5)) % 3 == 0 {
                        check!(rt_reschedule(node, ws));
                    }
                }
                _ => unreachable!(),
            }
        }
    }
}

// Receiver branch locals: 0 join, 1 chans base, 2 n chans, 3 total expected, 4 received,
// 5 sum, 6 buffer, 7 selected.
const R_WORDS: usize = 8;

/// Replicated ALT over n channels until `total` messages arrive; sums them.
unsafe extern "C" fn fan_receiver(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        let n = *l(ws, 2);
        let ch = |i: Word| (*l(ws, 1) as *mut Word).add(i as usize);
        loop {
            match iptr(ws) {
                0 => {
                    if *l(ws, 4) == *l(ws, 3) {
                        return rt_endp(node, ws, *l(ws, 0) as *mut Word);
                    }
                    rt_alt(node, ws);
                    for i in 0..n {
                        rt_enbc(node, ws, 1, ch(i));
                    }
                    set_iptr(ws, 1);
                    check!(rt_altwt(node, ws));
                }
                1 => {
                    // Rotate the disable order for fairness, as a plain ALT may.
                    let start = *l(ws, 4) % n;
                    for k in 0..n {
                        let i = (start + k) % n;
                        rt_disc(node, ws, 1, ch(i), i);
                    }
                    *l(ws, 7) = rt_altend(node, ws);
                    assert!(*l(ws, 7) >= 0);
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, ch(*l(ws, 7)), l(ws, 6).cast(), 8));
                }
                _ => {
                    *l(ws, 5) += *l(ws, 6);
                    *l(ws, 4) += 1;
                    set_iptr(ws, 0);
                }
            }
        }
    }
}

const SENDERS: usize = 24;
const PER_SENDER: Word = 200;
const STRIDE: usize = slot::HEADER_WORDS + if S_WORDS > R_WORDS { S_WORDS } else { R_WORDS };
const CHANS: usize = 2; // parent locals 2 .. 2 + SENDERS: channel words
const NEXT: usize = CHANS + SENDERS; // next sender to start
const FRAMES: usize = NEXT + 1 + slot::HEADER_WORDS;

/// PAR { receiver; PAR i = 0 FOR SENDERS: sender(i) }, every third sender at high priority.
/// Locals: 0, 1 join block; CHANS.. channel words; NEXT; then the branch frames.
unsafe extern "C" fn fan_parent(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *ws.offset(join::PARENT) = 0;
                    *ws.offset(join::COUNT) = SENDERS as Word + 1;
                    for i in 0..SENDERS {
                        *l(ws, CHANS + i) = 0;
                    }
                    let r = ws.add(FRAMES);
                    *l(r, 0) = ws as Word;
                    *l(r, 1) = l(ws, CHANS) as Word;
                    *l(r, 2) = SENDERS as Word;
                    *l(r, 3) = SENDERS as Word * PER_SENDER;
                    *l(r, 4) = 0;
                    *l(r, 5) = 0;
                    rt_startp(node, ws, r, fan_receiver, 0);
                    *l(ws, NEXT) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    let i = *l(ws, NEXT) as usize;
                    if i == SENDERS {
                        set_iptr(ws, 2);
                        check!(rt_par_wait(node, ws, ws));
                        continue;
                    }
                    let s = ws.add(FRAMES + (i + 1) * STRIDE);
                    *l(s, 0) = ws as Word;
                    *l(s, 1) = l(ws, CHANS + i) as Word;
                    *l(s, 2) = PER_SENDER;
                    *l(s, 4) = i as Word * 1_000_000;
                    *l(s, 5) = 0x9E37_79B9 + i as Word;
                    *l(ws, NEXT) += 1;
                    let pri = if i.is_multiple_of(3) {
                        priority::HIGH
                    } else {
                        priority::LOW
                    };
                    check!(rt_startp_pri(node, ws, s, fan_sender, 0, pri));
                }
                _ => return Status::DONE,
            }
        }
    }
}

#[test]
fn fan_in_through_a_replicated_alt_delivers_every_message_once() {
    let (mut node, _) = node();
    let ws = spawn(&mut node, fan_parent, FRAMES + (SENDERS + 1) * STRIDE, &[]);
    node.run().unwrap();
    let r = unsafe { ws.add(FRAMES) };
    let expected: Word = (0..SENDERS as Word)
        .map(|i| (1..=PER_SENDER).map(|k| i * 1_000_000 + k).sum::<Word>())
        .sum();
    unsafe {
        assert_eq!(*l(r, 4), SENDERS as Word * PER_SENDER);
        assert_eq!(*l(r, 5), expected);
        for i in 0..SENDERS {
            assert_eq!(*l(ws, CHANS + i), 0, "channel {i} left non-empty");
        }
    }
    assert_eq!(
        node.stats().communications,
        SENDERS as u64 * PER_SENDER as u64
    );
    assert_eq!(node.stats().processes_started, SENDERS as u64 + 2);
}

#[test]
fn long_pipeline_of_relays() {
    // 2,000 relays between a sender and a receiver, 50 messages: sums must match.
    const K: usize = 2_000;
    let (mut node, _) = node();
    let mut chans = vec![0 as Word; K + 1];
    let mut log: Vec<Word> = Vec::new();
    let c = |chans: &mut Vec<Word>, i: usize| &mut chans[i] as *mut Word as Word;
    let first = c(&mut chans, 0);
    spawn(&mut node, crate::chan::sender, 4, &[first, 50]);
    for i in 0..K {
        let (a, b) = (c(&mut chans, i), c(&mut chans, i + 1));
        spawn(&mut node, relay, 5, &[a, b, 50]);
    }
    let last = c(&mut chans, K);
    spawn(
        &mut node,
        crate::chan::receiver,
        5,
        &[last, 50, 0, 0, &mut log as *mut _ as Word],
    );
    node.run().unwrap();
    assert_eq!(log, (0..50).map(|i| i * 10).collect::<Vec<Word>>());
    assert_eq!(node.stats().communications, 50 * (K as u64 + 1));
}

/// n × (in a; out b). Locals: 0 a, 1 b, 2 n, 3 i, 4 buffer.
unsafe extern "C" fn relay(ws: Wptr, node: *mut Node) -> Status {
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
                    check!(rt_in(node, ws, *l(ws, 0) as *mut Word, l(ws, 4).cast(), 8));
                }
                2 => {
                    *l(ws, 3) += 1;
                    set_iptr(ws, 1);
                    check!(rt_out(node, ws, *l(ws, 1) as *mut Word, l(ws, 4).cast(), 8));
                }
                _ => unreachable!(),
            }
        }
    }
}
