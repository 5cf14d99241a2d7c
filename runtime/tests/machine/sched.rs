//! Timeslicing: busy low-priority loops all make progress; RESCHEDULE; the frame-chain-free
//! basics of the run queue.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::sched::rt_reschedule;

use crate::common::*;

const TARGET: Word = 1_000;

/// Spins, counting its own iterations, until both counters reach TARGET (or 5 s pass).
/// Locals: 0 own counter address, 1 other counter address, 2 log, 3 tag.
unsafe extern "C" fn spinner(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        let start = std::time::Instant::now();
        let mine = *l(ws, 0) as *mut Word;
        let other = *l(ws, 1) as *const Word;
        loop {
            // Loop head = resume index 0 (nothing to initialise).
            if *mine >= TARGET && *other >= TARGET {
                (*(*l(ws, 2) as *mut Vec<Word>)).push(*l(ws, 3));
                return Status::DONE;
            }
            *mine += 1;
            if *mine % (1 << 16) == 0 && start.elapsed().as_secs() >= 5 {
                (*(*l(ws, 2) as *mut Vec<Word>)).push(-1);
                return Status::DONE;
            }
            std::hint::spin_loop();
            poll!(node, ws, 0);
        }
    }
}

#[test]
fn timeslicing_lets_two_busy_loops_progress() {
    let (mut node, _) = node();
    let mut counters = [0 as Word; 2];
    let mut log: Vec<Word> = Vec::new();
    let (a, b) = (
        &mut counters[0] as *mut Word as Word,
        &mut counters[1] as *mut Word as Word,
    );
    let logp = &mut log as *mut Vec<Word> as Word;
    spawn(&mut node, spinner, 4, &[a, b, logp, 1]);
    spawn(&mut node, spinner, 4, &[b, a, logp, 2]);
    node.run().unwrap();
    assert!(
        !log.contains(&-1),
        "a loop hit its 5 s cap: no timeslicing ({log:?})"
    );
    assert_eq!(log.len(), 2);
    assert!(
        node.stats().context_switches >= 3,
        "at least one timeslice happened"
    );
}

/// Logs `tag * 100 + i` for i = 0 .. n - 1, polling after each.
/// Locals: 0 log, 1 tag, 2 n, 3 i.
unsafe extern "C" fn stepper(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            let i = *l(ws, 3);
            if i == *l(ws, 2) {
                return Status::DONE;
            }
            (*(*l(ws, 0) as *mut Vec<Word>)).push(*l(ws, 1) * 100 + i);
            *l(ws, 3) = i + 1;
            poll!(node, ws, 0);
        }
    }
}

#[test]
fn counted_timeslices_come_every_so_many_polls() {
    let config = occ_runtime::NodeConfig {
        counted_slices: Some(3),
        ..Default::default()
    };
    let mut node = Node::new(config, Default::default(), occ_runtime::HostIo::stdio());
    let mut log: Vec<Word> = Vec::new();
    let logp = &mut log as *mut Vec<Word> as Word;
    spawn(&mut node, stepper, 4, &[logp, 1, 7, 0]);
    spawn(&mut node, stepper, 4, &[logp, 2, 7, 0]);
    node.run().unwrap();
    // Every third poll of the node's low-priority processes is a timeslice.
    let want = [
        100, 101, 102, 200, 201, 202, 103, 104, 105, 203, 204, 205, 106, 206,
    ];
    assert_eq!(log, want);
}

/// Logs its tag, RESCHEDULEs, logs tag+10.
unsafe extern "C" fn polite(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            (*(*l(ws, 0) as *mut Vec<Word>)).push(*l(ws, 1));
            set_iptr(ws, 1);
            check!(rt_reschedule(node, ws));
        }
        (*(*l(ws, 0) as *mut Vec<Word>)).push(*l(ws, 1) + 10);
        Status::DONE
    }
}

#[test]
fn reschedule_goes_to_the_back_of_the_queue() {
    let (mut node, _) = node();
    let mut log: Vec<Word> = Vec::new();
    let logp = &mut log as *mut Vec<Word> as Word;
    for t in 1..=3 {
        spawn(&mut node, polite, 2, &[logp, t]);
    }
    node.run().unwrap();
    assert_eq!(log, vec![1, 2, 3, 11, 12, 13]);
}

#[test]
fn an_empty_node_finishes() {
    let (mut node, _) = node();
    node.run().unwrap();
    assert_eq!(node.stats().processes_started, 0);
}

#[test]
fn memory_budget_is_enforced() {
    let config = occ_runtime::NodeConfig {
        memory_budget: 4096,
        timeslice: false,
        ..Default::default()
    };
    let mut node = Node::new(config, Default::default(), occ_runtime::HostIo::stdio());
    assert!(node.alloc_workspace(100).is_ok());
    let err = node.alloc_workspace(1000).expect_err("over budget");
    assert!(
        matches!(err, occ_runtime::RunError::OutOfMemory { .. }),
        "{err}"
    );
}

#[test]
fn absurd_workspace_sizes_are_errors_not_panics() {
    let (mut node, _) = node();
    for words in [usize::MAX, usize::MAX / 8, 1 << 40] {
        assert!(matches!(
            node.alloc_workspace(words),
            Err(occ_runtime::RunError::OutOfMemory { .. })
        ));
    }
}

#[test]
fn nodes_can_move_between_threads() {
    fn assert_send<T: Send>() {}
    assert_send::<Node>();
    assert_send::<Box<Node>>();
    assert_send::<occ_runtime::Network>();
}
