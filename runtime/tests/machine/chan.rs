//! Rendezvous on a one-word channel, in both arrival orders.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::chan::{rt_in, rt_out};

use crate::common::*;

/// Outputs 0, 10, 20, ... (n values). Locals: 0 chan, 1 n, 2 i, 3 buffer.
pub unsafe extern "C" fn sender(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 2) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 2) >= *l(ws, 1) {
                        return Status::DONE;
                    }
                    *l(ws, 3) = *l(ws, 2) * 10;
                    set_iptr(ws, 2);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 3).cast(), 8));
                }
                2 => {
                    *l(ws, 2) += 1;
                    set_iptr(ws, 1);
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// Inputs n values and appends them to a log. Locals: 0 chan, 1 n, 2 i, 3 buffer, 4 *mut Vec.
pub unsafe extern "C" fn receiver(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 2) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 2) >= *l(ws, 1) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, *l(ws, 0) as *mut Word, l(ws, 3).cast(), 8));
                }
                2 => {
                    (*(*l(ws, 4) as *mut Vec<Word>)).push(*l(ws, 3));
                    *l(ws, 2) += 1;
                    set_iptr(ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

fn rendezvous(reader_first: bool) {
    let (mut node, _) = node();
    let mut c = channel();
    let mut log: Vec<Word> = Vec::new();
    let chan = &mut *c as *mut Word as Word;
    let logp = &mut log as *mut Vec<Word> as Word;
    if reader_first {
        spawn(&mut node, receiver, 5, &[chan, 5, 0, 0, logp]);
        spawn(&mut node, sender, 4, &[chan, 5]);
    } else {
        spawn(&mut node, sender, 4, &[chan, 5]);
        spawn(&mut node, receiver, 5, &[chan, 5, 0, 0, logp]);
    }
    node.run().expect("runs to completion");
    assert_eq!(log, vec![0, 10, 20, 30, 40]);
    assert_eq!(*c, 0, "channel word is empty after the last communication");
    assert_eq!(node.stats().communications, 5);
    assert_eq!(node.stats().processes_started, 2);
}

#[test]
fn rendezvous_reader_first() {
    rendezvous(true);
}

#[test]
fn rendezvous_writer_first() {
    rendezvous(false);
}

/// Bytes of any length are copied whole (a 3-word record).
#[test]
fn multi_word_message() {
    unsafe extern "C" fn out3(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            if iptr(ws) == 0 {
                *l(ws, 1) = 7;
                *l(ws, 2) = -8;
                *l(ws, 3) = 9;
                set_iptr(ws, 1);
                check!(rt_out(
                    node,
                    ws,
                    *l(ws, 0) as *mut Word,
                    l(ws, 1).cast(),
                    24
                ));
            }
            Status::DONE
        }
    }
    unsafe extern "C" fn in3(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            if iptr(ws) == 0 {
                set_iptr(ws, 1);
                check!(rt_in(node, ws, *l(ws, 0) as *mut Word, l(ws, 1).cast(), 24));
            }
            let v = *l(ws, 4) as *mut [Word; 3];
            *v = [*l(ws, 1), *l(ws, 2), *l(ws, 3)];
            Status::DONE
        }
    }
    let (mut node, _) = node();
    let mut c = channel();
    let mut got = [0 as Word; 3];
    let chan = &mut *c as *mut Word as Word;
    spawn(
        &mut node,
        in3,
        5,
        &[chan, 0, 0, 0, got.as_mut_ptr() as Word],
    );
    spawn(&mut node, out3, 4, &[chan]);
    node.run().unwrap();
    assert_eq!(got, [7, -8, 9]);
}
