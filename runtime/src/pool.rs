//! Running many nodes on a few OS threads.
//!
//! [`Network::run_pool`] gives each worker thread a node that has work; the worker runs it with
//! [`Node::run_until_idle`] and parks it when it waits for a timer or link traffic. Mail posted to
//! a parked node makes it ready again (the node's mailbox calls the pool's waker); a parked node's
//! timer makes it ready when due. When no node is ready or running and no parked node has a
//! timer, no link can move: every parked node reports a deadlock.
//!
//! Lost wake-ups cannot happen: a worker parks a node only under the pool lock after checking its
//! mailbox, and a poster pushes the mail before calling the waker, which takes the same lock.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::error::RunError;
use crate::link::Network;
use crate::node::Node;
use crate::sched::Idle;

/// Where one node is.
enum Slot {
    /// Waiting for a worker (in `ready`).
    Ready(Box<Node>),
    /// Being run by a worker.
    Running,
    /// Waiting for mail, and for its timer if `due` is set.
    Parked(Box<Node>, Option<Instant>),
    /// Stopped.
    Done(Box<Node>, Result<(), RunError>),
}

struct PoolState {
    slots: Vec<Slot>,
    ready: VecDeque<usize>,
    running: usize,
}

/// What nodes' mailboxes and workers share.
pub(crate) struct PoolShared {
    state: Mutex<PoolState>,
    work: Condvar,
}

impl PoolShared {
    fn lock(&self) -> MutexGuard<'_, PoolState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Called by a node's mailbox after mail was posted to node `i`.
    pub(crate) fn wake(&self, i: usize) {
        let mut st = self.lock();
        if let Slot::Parked(..) = st.slots[i] {
            let Slot::Parked(node, _) = std::mem::replace(&mut st.slots[i], Slot::Running) else {
                unreachable!("checked above");
            };
            st.slots[i] = Slot::Ready(node);
            st.ready.push_back(i);
            self.work.notify_one();
        }
    }
}

/// The waker a mailbox calls: the pool and the node's index.
pub(crate) struct Waker {
    pub(crate) pool: Arc<PoolShared>,
    pub(crate) index: usize,
}

impl Network {
    /// Runs `nodes` (every node of this network, each joined) on `threads` worker threads until
    /// all have stopped; returns each node with its outcome, in the order given.
    pub fn run_pool(
        nodes: Vec<Box<Node>>,
        threads: usize,
    ) -> Vec<(Box<Node>, Result<(), RunError>)> {
        let n = nodes.len();
        let pool = Arc::new(PoolShared {
            state: Mutex::new(PoolState {
                slots: Vec::with_capacity(n),
                ready: (0..n).collect(),
                running: 0,
            }),
            work: Condvar::new(),
        });
        let mut tickets = Vec::new();
        {
            let mut st = pool.lock();
            for (i, node) in nodes.into_iter().enumerate() {
                node.mailbox.set_waker(Waker {
                    pool: pool.clone(),
                    index: i,
                });
                if node.config.timeslice {
                    tickets.push(crate::ticker::register(&node.yield_flag));
                }
                st.slots.push(Slot::Ready(node));
            }
        }
        std::thread::scope(|s| {
            for _ in 0..threads.max(1) {
                s.spawn(|| worker(&pool));
            }
        });
        drop(tickets);
        let slots = std::mem::take(&mut pool.lock().slots);
        slots
            .into_iter()
            .map(|slot| match slot {
                Slot::Done(node, r) => {
                    node.mailbox.clear_waker();
                    (node, r)
                }
                _ => unreachable!("every node is done when the workers return"),
            })
            .collect()
    }
}

/// A worker: takes ready nodes and runs them until no node can ever run again.
fn worker(pool: &PoolShared) {
    let mut st = pool.lock();
    loop {
        wake_due_timers(&mut st);
        if let Some(i) = st.ready.pop_front() {
            let Slot::Ready(mut node) = std::mem::replace(&mut st.slots[i], Slot::Running) else {
                unreachable!("ready nodes are in Ready slots");
            };
            st.running += 1;
            drop(st);
            let outcome = node.run_until_idle();
            st = pool.lock();
            st.running -= 1;
            settle(&mut st, i, node, outcome);
            pool.work.notify_all();
            continue;
        }
        if st.running == 0 {
            let next_due = earliest_due(&st);
            match next_due {
                None => {
                    report_deadlocks(&mut st);
                    pool.work.notify_all();
                    return;
                }
                Some(due) => {
                    let wait = due.saturating_duration_since(Instant::now());
                    st = wait_for(pool, st, wait);
                }
            }
        } else {
            let wait = earliest_due(&st)
                .map(|d| d.saturating_duration_since(Instant::now()))
                .unwrap_or(Duration::from_millis(50));
            st = wait_for(pool, st, wait);
        }
        if all_done(&st) {
            return;
        }
    }
}

fn wait_for<'a>(
    pool: &'a PoolShared,
    st: MutexGuard<'a, PoolState>,
    d: Duration,
) -> MutexGuard<'a, PoolState> {
    pool.work
        .wait_timeout(st, d)
        .unwrap_or_else(|p| p.into_inner())
        .0
}

/// Puts a node that returned from `run_until_idle` back in its slot.
fn settle(st: &mut PoolState, i: usize, node: Box<Node>, outcome: Result<Idle, RunError>) {
    st.slots[i] = match outcome {
        Ok(Idle::Waiting { timer }) => {
            if node.mailbox.has_mail() {
                st.ready.push_back(i);
                Slot::Ready(node)
            } else {
                Slot::Parked(node, timer.map(|d| Instant::now() + d))
            }
        }
        Ok(Idle::Finished) => finish(node, Ok(())),
        Err(e) => finish(node, Err(e)),
    };
}

fn finish(mut node: Box<Node>, r: Result<(), RunError>) -> Slot {
    node.leave_network();
    let r = r.and(node.host.flush());
    Slot::Done(node, r)
}

fn earliest_due(st: &PoolState) -> Option<Instant> {
    st.slots
        .iter()
        .filter_map(|s| match s {
            Slot::Parked(_, due) => *due,
            _ => None,
        })
        .min()
}

fn wake_due_timers(st: &mut PoolState) {
    let now = Instant::now();
    for i in 0..st.slots.len() {
        if matches!(st.slots[i], Slot::Parked(_, Some(due)) if due <= now) {
            let Slot::Parked(node, _) = std::mem::replace(&mut st.slots[i], Slot::Running) else {
                unreachable!("checked above");
            };
            st.slots[i] = Slot::Ready(node);
            st.ready.push_back(i);
        }
    }
}

/// No node is ready or running and no parked node has a timer: each parked node is deadlocked.
fn report_deadlocks(st: &mut PoolState) {
    for slot in st.slots.iter_mut() {
        if let Slot::Parked(..) = slot {
            let Slot::Parked(node, _) = std::mem::replace(slot, Slot::Running) else {
                unreachable!("checked above");
            };
            let report = RunError::Deadlock(node.deadlock_report());
            *slot = finish(node, Err(report));
        }
    }
}

fn all_done(st: &PoolState) -> bool {
    st.slots.iter().all(|s| matches!(s, Slot::Done(..)))
}
