//! ALT: outputter first or second, PRI ALT order by disable order, boolean and SKIP guards,
//! replicated ALT over an array of channels.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::alt::*;
use occ_runtime::chan::{rt_in, rt_out};

use crate::common::*;

/// Outputs one value. Locals: 0 chan, 1 value.
pub unsafe extern "C" fn send1(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            set_iptr(ws, 1);
            check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 1).cast(), 8));
        }
        Status::DONE
    }
}

// ALTer locals.
const CHANS: usize = 0; // address of an array of channel words
const N: usize = 1; // number of channel guards
const SKIP: usize = 2; // non-zero: a SKIP guard after the channels
const BUF: usize = 3;
const LOG: usize = 4; // *mut Vec<Word>: branch*1000 + value, or -1 for SKIP
const ROUNDS: usize = 5;
const SEL: usize = 6;
const MASK: usize = 7; // bit i set: guard i's boolean is TRUE
const REVERSE: usize = 8; // non-zero: disable in reverse order
const WORDS: usize = 9;

unsafe fn chan(ws: Wptr, i: Word) -> *mut Word {
    unsafe { (*l(ws, CHANS) as *mut Word).add(i as usize) }
}

unsafe fn guard(ws: Wptr, i: Word) -> Word {
    unsafe { (*l(ws, MASK) >> i) & 1 }
}

/// A (replicated) PRI ALT over `N` channels and an optional SKIP, repeated `ROUNDS` times.
unsafe extern "C" fn alter(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        let n = *l(ws, N);
        loop {
            match iptr(ws) {
                0 => {
                    rt_alt(node, ws);
                    for i in 0..n {
                        rt_enbc(node, ws, guard(ws, i), chan(ws, i));
                    }
                    if *l(ws, SKIP) != 0 {
                        rt_enbs(node, ws, 1);
                    }
                    set_iptr(ws, 1);
                    check!(rt_altwt(node, ws));
                }
                1 => {
                    let order: Vec<Word> = if *l(ws, REVERSE) != 0 {
                        (0..n).rev().collect()
                    } else {
                        (0..n).collect()
                    };
                    for i in order {
                        rt_disc(node, ws, guard(ws, i), chan(ws, i), i);
                    }
                    if *l(ws, SKIP) != 0 {
                        rt_diss(node, ws, 1, n);
                    }
                    let sel = rt_altend(node, ws);
                    assert!(sel >= 0, "a ready guard must be selected");
                    *l(ws, SEL) = sel;
                    if sel == n {
                        (*(*l(ws, LOG) as *mut Vec<Word>)).push(-1);
                        set_iptr(ws, 3);
                        continue;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, chan(ws, sel), l(ws, BUF).cast(), 8));
                }
                2 => {
                    let v = *l(ws, SEL) * 1000 + *l(ws, BUF);
                    (*(*l(ws, LOG) as *mut Vec<Word>)).push(v);
                    set_iptr(ws, 3);
                }
                3 => {
                    *l(ws, ROUNDS) -= 1;
                    if *l(ws, ROUNDS) == 0 {
                        return Status::DONE;
                    }
                    set_iptr(ws, 0);
                }
                _ => unreachable!(),
            }
        }
    }
}

struct AltSetup {
    chans: Vec<Word>,
    log: Vec<Word>,
}

impl AltSetup {
    fn new(n: usize) -> Box<AltSetup> {
        Box::new(AltSetup {
            chans: vec![0; n],
            log: Vec::new(),
        })
    }

    fn chan(&mut self, i: usize) -> Word {
        &mut self.chans[i] as *mut Word as Word
    }

    fn spawn_alter(
        &mut self,
        node: &mut Node,
        skip: bool,
        rounds: Word,
        mask: Word,
        reverse: bool,
    ) {
        let init = [
            self.chans.as_mut_ptr() as Word,
            self.chans.len() as Word,
            skip as Word,
            0,
            &mut self.log as *mut Vec<Word> as Word,
            rounds,
            0,
            mask,
            reverse as Word,
        ];
        spawn(node, alter, WORDS, &init);
    }

    fn spawn_sender(&mut self, node: &mut Node, i: usize, value: Word) {
        let c = self.chan(i);
        spawn(node, send1, 2, &[c, value]);
    }
}

#[test]
fn alt_outputter_arrives_first() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(2);
    s.spawn_sender(&mut node, 1, 5);
    s.spawn_alter(&mut node, false, 1, 0b11, false);
    node.run().unwrap();
    assert_eq!(s.log, vec![1005]);
    assert_eq!(s.chans, vec![0, 0], "disabling clears every channel word");
}

#[test]
fn alt_outputter_arrives_second() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(2);
    s.spawn_alter(&mut node, false, 1, 0b11, false);
    s.spawn_sender(&mut node, 0, 7);
    node.run().unwrap();
    assert_eq!(s.log, vec![7]);
    assert_eq!(s.chans, vec![0, 0]);
}

#[test]
fn pri_alt_takes_first_ready_guard_in_disable_order() {
    for reverse in [false, true] {
        let (mut node, _) = node();
        let mut s = AltSetup::new(3);
        s.spawn_sender(&mut node, 2, 2);
        s.spawn_sender(&mut node, 1, 1);
        s.spawn_sender(&mut node, 0, 0);
        s.spawn_alter(&mut node, false, 3, 0b111, reverse);
        node.run().unwrap();
        let expected = if reverse {
            vec![2002, 1001, 0]
        } else {
            vec![0, 1001, 2002]
        };
        assert_eq!(s.log, expected, "reverse = {reverse}");
    }
}

#[test]
fn false_boolean_guard_is_never_ready() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(2);
    s.spawn_sender(&mut node, 0, 9);
    s.spawn_sender(&mut node, 1, 8);
    // Guard 0 is FALSE: only channel 1 can be taken; channel 0's sender stays blocked.
    s.spawn_alter(&mut node, false, 1, 0b10, false);
    let err = node
        .run()
        .expect_err("the sender on the FALSE guard deadlocks");
    assert!(matches!(err, occ_runtime::RunError::Deadlock(ref d) if d.blocked.len() == 1));
    assert_eq!(s.log, vec![1008]);
}

#[test]
fn skip_guard_taken_only_when_nothing_before_it_is_ready() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(1);
    s.spawn_alter(&mut node, true, 1, 0b1, false);
    node.run().unwrap();
    assert_eq!(s.log, vec![-1], "no channel ready: SKIP");
    assert_eq!(s.chans, vec![0]);

    let (mut node, _) = crate::common::node();
    let mut s = AltSetup::new(1);
    s.spawn_sender(&mut node, 0, 4);
    s.spawn_alter(&mut node, true, 1, 0b1, false);
    node.run().unwrap();
    assert_eq!(
        s.log,
        vec![4],
        "PRI ALT: the ready channel before SKIP wins"
    );
}

#[test]
fn replicated_alt_over_channel_array() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(8);
    s.spawn_alter(&mut node, false, 3, 0xff, false);
    s.spawn_sender(&mut node, 5, 50);
    s.spawn_sender(&mut node, 2, 20);
    s.spawn_sender(&mut node, 7, 70);
    node.run().unwrap();
    // The ALT waits; the sender on 5 wakes it, and the senders on 2 and 7 also find their
    // channels enabled before the ALTer runs again, so all three are ready when it disables:
    // PRI order takes 2, 5, 7.
    assert_eq!(s.log, vec![2020, 5050, 7070]);
    assert!(s.chans.iter().all(|&w| w == 0));
}

#[test]
fn looping_pri_alt_serves_every_message() {
    let (mut node, _) = node();
    let mut s = AltSetup::new(2);
    for i in 0..2 {
        let c = s.chan(i);
        spawn(&mut node, crate::chan::sender, 4, &[c, 3]);
    }
    s.spawn_alter(&mut node, false, 6, 0b11, false);
    node.run().unwrap();
    let mut got = s.log.clone();
    got.sort();
    assert_eq!(got, vec![0, 10, 20, 1000, 1010, 1020]);
}
