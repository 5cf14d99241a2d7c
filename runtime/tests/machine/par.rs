//! PAR with sub-workspaces and a join block; PRI PAR preemption; the interrupted slot.

use occ_runtime::Node;
use occ_runtime::abi::{ProcFn, Status, Word, Wptr, join, priority, slot};
use occ_runtime::chan::{rt_in, rt_out};
use occ_runtime::par::{rt_endp, rt_par_wait, rt_startp, rt_startp_pri};
use occ_runtime::timer::{rt_timer_read, rt_tin};

use crate::common::*;

// Branch locals.
const B_JOIN: usize = 0;
const B_CHAN: usize = 1;
const B_LOG: usize = 2;
const B_TAG: usize = 3;
const B_BUF: usize = 4;
const B_WORDS: usize = 5;
const STRIDE: usize = occ_runtime::abi::slot::HEADER_WORDS + B_WORDS;

// Parent locals: join block, then shared words, then branch frames.
const P_CHAN: usize = 2;
const P_LOG: usize = 3;
const P_BRANCHES: usize = 4;

unsafe fn log(ws: Wptr, v: Word) {
    unsafe { (*(*l(ws, B_LOG) as *mut Vec<Word>)).push(v) }
}

unsafe fn branch(ws: Wptr, i: usize) -> Wptr {
    unsafe { ws.add(P_BRANCHES + slot::HEADER_WORDS + i * STRIDE) }
}

fn parent_words(branches: usize) -> usize {
    P_BRANCHES + branches * STRIDE
}

/// Logs its tag, then ends.
unsafe extern "C" fn tag_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        log(ws, *l(ws, B_TAG));
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

/// Waits 1 ms on the timer, logs its tag, ends.
unsafe extern "C" fn sleepy_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            let t = rt_timer_read(node) + 1000;
            set_iptr(ws, 1);
            check!(rt_tin(node, ws, t));
        }
        log(ws, *l(ws, B_TAG));
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

/// Inputs from B_CHAN, logs its tag, ends.
unsafe extern "C" fn input_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            set_iptr(ws, 1);
            check!(rt_in(
                node,
                ws,
                *l(ws, B_CHAN) as *mut Word,
                l(ws, B_BUF).cast(),
                8
            ));
        }
        log(ws, *l(ws, B_TAG));
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

/// Outputs to B_CHAN, logs its tag, ends.
unsafe extern "C" fn output_branch(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            set_iptr(ws, 1);
            check!(rt_out(
                node,
                ws,
                *l(ws, B_CHAN) as *mut Word,
                l(ws, B_BUF).cast(),
                8
            ));
        }
        log(ws, *l(ws, B_TAG));
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

/// The branches a parent starts: code and priority (None: inherit).
type Plan = &'static [(ProcFn, Option<Word>)];

/// Runs a PAR of the plan's branches (tags 0, 1, ...), sharing one channel, then logs 100.
unsafe fn par_parent(ws: Wptr, node: *mut Node, plan: Plan) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            *ws.offset(join::PARENT) = 0;
            *ws.offset(join::COUNT) = plan.len() as Word;
            *l(ws, P_CHAN) = 0;
            for (i, (code, pri)) in plan.iter().enumerate() {
                let b = branch(ws, i);
                *l(b, B_JOIN) = ws as Word;
                *l(b, B_CHAN) = l(ws, P_CHAN) as Word;
                *l(b, B_LOG) = *l(ws, P_LOG);
                *l(b, B_TAG) = i as Word;
                *l(b, B_BUF) = 42;
                // Resume index 2i+1 follows the i-th start (a start may preempt the parent).
                set_iptr(ws, 2 * i as Word + 1);
                let st = match pri {
                    Some(p) => rt_startp_pri(node, ws, b, *code, 0, *p),
                    None => rt_startp(node, ws, b, *code, 0),
                };
                assert_eq!(
                    st,
                    Status::DONE,
                    "plans start no high branch from a low parent"
                );
            }
            set_iptr(ws, 100);
            check!(rt_par_wait(node, ws, ws));
        }
        (*(*l(ws, P_LOG) as *mut Vec<Word>)).push(100);
        Status::DONE
    }
}

fn run_plan(code: ProcFn, branches: usize, log: &mut Vec<Word>) -> Box<Node> {
    let (mut node, _) = node();
    let ws = node.alloc_workspace(parent_words(branches)).unwrap();
    unsafe {
        *l(ws, P_LOG) = log as *mut Vec<Word> as Word;
        node.spawn(ws, code);
    }
    node.run().expect("runs");
    node
}

#[test]
fn par_joins_after_all_branches() {
    unsafe extern "C" fn parent(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            par_parent(
                ws,
                node,
                &[
                    (tag_branch, None),
                    (sleepy_branch, None),
                    (tag_branch, None),
                ],
            )
        }
    }
    let mut log = Vec::new();
    let node = run_plan(parent, 3, &mut log);
    assert_eq!(
        log,
        vec![0, 2, 1, 100],
        "the parent continues only after every branch"
    );
    assert_eq!(node.stats().processes_started, 4);
}

#[test]
fn par_branches_communicate() {
    unsafe extern "C" fn parent(ws: Wptr, node: *mut Node) -> Status {
        unsafe { par_parent(ws, node, &[(input_branch, None), (output_branch, None)]) }
    }
    let mut log = Vec::new();
    let node = run_plan(parent, 2, &mut log);
    // The inputter blocks first; the outputter completes, requeues it, logs, ends; then the
    // inputter logs and, as the last branch, hands over to the parent.
    assert_eq!(log, vec![1, 0, 100]);
    assert_eq!(node.stats().communications, 1);
}

/// Launcher for the preemption test: starts H (high, inputs), then L1 (outputs to H) and L2.
unsafe extern "C" fn launcher(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *ws.offset(join::PARENT) = 0;
                    *ws.offset(join::COUNT) = 3;
                    *l(ws, P_CHAN) = 0;
                    for i in 0..3 {
                        let b = branch(ws, i);
                        *l(b, B_JOIN) = ws as Word;
                        *l(b, B_CHAN) = l(ws, P_CHAN) as Word;
                        *l(b, B_LOG) = *l(ws, P_LOG);
                        *l(b, B_TAG) = i as Word;
                    }
                    set_iptr(ws, 1);
                    // PRI PAR: the first branch at high priority; the low parent is preempted.
                    let st =
                        rt_startp_pri(node, ws, branch(ws, 0), input_branch, 0, priority::HIGH);
                    (*(*l(ws, P_LOG) as *mut Vec<Word>)).push(if st == Status::BLOCKED {
                        -1
                    } else {
                        -2
                    });
                    check!(st);
                }
                1 => {
                    rt_startp(node, ws, branch(ws, 1), output_branch, 0);
                    rt_startp(node, ws, branch(ws, 2), tag_branch, 0);
                    set_iptr(ws, 2);
                    check!(rt_par_wait(node, ws, ws));
                }
                _ => {
                    (*(*l(ws, P_LOG) as *mut Vec<Word>)).push(100);
                    return Status::DONE;
                }
            }
        }
    }
}

#[test]
fn pri_par_high_branch_preempts_low_at_once() {
    let mut log = Vec::new();
    run_plan(launcher, 3, &mut log);
    // -1: starting the high branch preempted the low launcher. Then H blocks; the launcher starts
    // L1 and L2; L1's output wakes H, which preempts L1 at once (H logs 0 before L1 logs 1); L1,
    // in the interrupted slot, resumes before L2 (logs 1 before 2); the last branch resumes the
    // parent (100).
    assert_eq!(log, vec![-1, 0, 1, 2, 100]);
}

// Busy-loop test: a low process spins (polling at its back-edge) until a high-priority process,
// woken by its timer, sets a flag. Without preemption the low loop would spin until its 5 s cap.

/// Locals: B_JOIN, B_CHAN (flag address), B_LOG, B_TAG, B_BUF (iterations).
unsafe extern "C" fn busy_low(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        let start = std::time::Instant::now();
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, B_BUF) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *(*l(ws, B_CHAN) as *const Word) != 0 {
                        log(ws, *l(ws, B_TAG));
                        return rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word);
                    }
                    *l(ws, B_BUF) += 1;
                    if *l(ws, B_BUF) % (1 << 20) == 0 && start.elapsed().as_secs() >= 5 {
                        log(ws, -99);
                        return rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word);
                    }
                    poll!(node, ws, 1);
                }
                _ => unreachable!(),
            }
        }
    }
}

/// Waits 2 ms, sets the flag, logs, ends.
unsafe extern "C" fn timed_high(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            let t = rt_timer_read(node) + 2000;
            set_iptr(ws, 1);
            check!(rt_tin(node, ws, t));
        }
        *(*l(ws, B_CHAN) as *mut Word) = 1;
        log(ws, *l(ws, B_TAG));
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

#[test]
fn pri_par_preempts_a_busy_low_process() {
    unsafe extern "C" fn parent(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            if iptr(ws) == 0 {
                *ws.offset(join::PARENT) = 0;
                *ws.offset(join::COUNT) = 2;
                *l(ws, P_CHAN) = 0;
                for i in 0..2 {
                    let b = branch(ws, i);
                    *l(b, B_JOIN) = ws as Word;
                    *l(b, B_CHAN) = l(ws, P_CHAN) as Word;
                    *l(b, B_LOG) = *l(ws, P_LOG);
                    *l(b, B_TAG) = i as Word;
                }
                set_iptr(ws, 1);
                check!(rt_startp_pri(
                    node,
                    ws,
                    branch(ws, 0),
                    timed_high,
                    0,
                    priority::HIGH
                ));
            }
            if iptr(ws) == 1 {
                rt_startp(node, ws, branch(ws, 1), busy_low, 0);
                set_iptr(ws, 2);
                check!(rt_par_wait(node, ws, ws));
            }
            (*(*l(ws, P_LOG) as *mut Vec<Word>)).push(100);
            Status::DONE
        }
    }
    let mut log = Vec::new();
    run_plan(parent, 2, &mut log);
    assert_eq!(
        log,
        vec![0, 1, 100],
        "the high process ran while the low one was busy"
    );
}

/// A high branch that runs a PAR of one child (started with rt_startp: inherits high priority),
/// then logs its tag and ends. Its own frame is branch-shaped; the child frame sits above it.
unsafe extern "C" fn high_parent_branch(ws: Wptr, node: *mut Node) -> Status {
    const J: usize = B_WORDS; // join block after the branch locals
    unsafe {
        let child = ws.add(J + 2 + slot::HEADER_WORDS);
        if iptr(ws) == 0 {
            *ws.add(J).offset(join::PARENT) = 0;
            *ws.add(J).offset(join::COUNT) = 1;
            *l(child, B_JOIN) = ws.add(J) as Word;
            *l(child, B_LOG) = *l(ws, B_LOG);
            *l(child, B_TAG) = 1;
            rt_startp(node, ws, child, tag_branch, 0);
            set_iptr(ws, 1);
            check!(rt_par_wait(node, ws, ws.add(J)));
        }
        log(ws, 2);
        rt_endp(node, ws, *l(ws, B_JOIN) as *mut Word)
    }
}

#[test]
fn startp_inherits_the_priority_of_the_starting_process() {
    const BIG: usize = STRIDE + 2 + slot::HEADER_WORDS + B_WORDS;
    unsafe extern "C" fn launcher2(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            let low = ws.add(P_BRANCHES + slot::HEADER_WORDS);
            let high = low.add(STRIDE + slot::HEADER_WORDS);
            if iptr(ws) == 0 {
                *ws.offset(join::PARENT) = 0;
                *ws.offset(join::COUNT) = 2;
                for b in [low, high] {
                    *l(b, B_JOIN) = ws as Word;
                    *l(b, B_LOG) = *l(ws, P_LOG);
                }
                *l(low, B_TAG) = 3;
                rt_startp(node, ws, low, tag_branch, 0);
                set_iptr(ws, 1);
                check!(rt_startp_pri(
                    node,
                    ws,
                    high,
                    high_parent_branch,
                    0,
                    priority::HIGH
                ));
            }
            if iptr(ws) == 1 {
                set_iptr(ws, 2);
                check!(rt_par_wait(node, ws, ws));
            }
            (*(*l(ws, P_LOG) as *mut Vec<Word>)).push(100);
            Status::DONE
        }
    }
    let (mut node, _) = node();
    let mut log: Vec<Word> = Vec::new();
    let ws = node.alloc_workspace(P_BRANCHES + 2 * BIG).unwrap();
    unsafe {
        *l(ws, P_LOG) = &mut log as *mut Vec<Word> as Word;
        node.spawn(ws, launcher2);
    }
    node.run().unwrap();
    // The high branch's child (1) is high too: it runs before the low branch (3) queued earlier.
    assert_eq!(log, vec![1, 2, 3, 100]);
}
