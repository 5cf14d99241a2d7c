//! Running many nodes on a few OS threads.
//!
//! [`Network::run_pool`] gives each worker thread a node that has work; the worker runs it with
//! [`Node::run_until_idle`] and parks it when it waits for a timer or link traffic. Mail posted to
//! a parked node makes it ready again (the node's mailbox calls the pool's waker); a parked node's
//! timer makes it ready when due. When no node is ready or running and no parked node has a
//! timer, no link can move: every parked node reports a deadlock.
//!
//! A network that spans several processes ([`Network::run_pool_driven`]) cannot judge deadlock
//! alone: a parked node may yet get mail from a link to another process. Its workers wait instead
//! until the driver, which runs on the calling thread and talks to the other processes, settles
//! the run (every process quiescent, nothing in flight) or stops it (a node elsewhere halted).
//!
//! Lost wake-ups cannot happen: a worker parks a node only under the pool lock after checking its
//! mailbox, and a poster pushes the mail before calling the waker, which takes the same lock.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicU32, Ordering};
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
    /// A driven pool's nodes can no longer get mail from elsewhere: parked nodes are deadlocked.
    settled: bool,
    /// Workers waiting on the condition variable: nobody to notify when 0 (a notification is a
    /// system call, and a message between two nodes of one pool would otherwise cost two).
    waiting: usize,
    /// Parked nodes with a timer: no clock to read for them when 0.
    timed: usize,
}

impl PoolState {
    /// Takes the node parked in slot `i` out of it (leaving `Running`), keeping `timed` true.
    fn unpark(&mut self, i: usize) -> Box<Node> {
        let Slot::Parked(node, due) = std::mem::replace(&mut self.slots[i], Slot::Running) else {
            unreachable!("callers check that slot {i} is parked");
        };
        if due.is_some() {
            self.timed -= 1;
        }
        node
    }

    /// Whether any worker waits to be notified.
    fn anyone_waiting(&self) -> bool {
        self.waiting > 0
    }
}

/// Times an idle worker looks for a ready node again, yielding its thread between looks, before
/// it sleeps while another worker runs a node.
const SPINS: u32 = 64;

/// Timeslices a node runs on a pool thread before it gives way to another ready node.
pub(crate) const TURN_SLICES: u32 = 4;

/// What nodes' mailboxes and workers share.
pub(crate) struct PoolShared {
    state: Mutex<PoolState>,
    work: Condvar,
    /// Each node's yield flag (nodes are boxed, so the addresses are stable): set on all of them
    /// when a node halts, so that running nodes reach a timeslice and stop.
    flags: Vec<usize>,
    /// Whether a driver decides when parked nodes are deadlocked (see the module doc).
    driven: bool,
}

impl PoolShared {
    fn lock(&self) -> MutexGuard<'_, PoolState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Called by a node's mailbox after mail was posted to node `i`.
    pub(crate) fn wake(&self, i: usize) {
        let mut st = self.lock();
        if let Slot::Parked(..) = st.slots[i] {
            let node = st.unpark(i);
            st.slots[i] = Slot::Ready(node);
            st.ready.push_back(i);
            if st.anyone_waiting() {
                self.work.notify_one();
            }
        }
    }

    /// Makes every running node reach a timeslice (the network has stopped).
    fn yield_all(&self) {
        for &f in &self.flags {
            // SAFETY: every node of the pool is alive (boxed, owned by a slot or a worker)
            // until `run_pool` returns.
            unsafe {
                (*(f as *const AtomicU32)).store(crate::abi::yield_flag::REQUEST, Ordering::Relaxed)
            };
        }
    }
}

/// What the driver of a pool (see [`Network::run_pool_driven`]) sees of it.
pub struct PoolView<'a> {
    pool: &'a PoolShared,
}

impl PoolView<'_> {
    /// Whether no node is ready or running and no parked node waits for a timer: until mail
    /// arrives from the driver, no node of this pool will run again.
    pub fn quiescent(&self) -> bool {
        let st = self.pool.lock();
        st.running == 0 && st.ready.is_empty() && earliest_due(&st).is_none()
    }

    /// Whether every node has stopped.
    pub fn all_done(&self) -> bool {
        all_done(&self.pool.lock())
    }

    /// No mail will come from elsewhere any more: parked nodes report deadlock and the workers
    /// return.
    pub fn settle(&self) {
        self.pool.lock().settled = true;
        self.pool.work.notify_all();
    }

    /// A node elsewhere halted: `net` (this pool's network) stops, and so does every node.
    pub fn stop(&self, net: &Network) {
        net.stop();
        self.pool.yield_all();
        stop_parked(&mut self.pool.lock());
        self.pool.work.notify_all();
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
        Self::pool(nodes, threads, None::<fn(PoolView<'_>)>)
    }

    /// As [`Network::run_pool`] for the nodes of a network that spans several processes:
    /// `drive` runs on the calling thread meanwhile and must return only after it has settled
    /// or stopped the pool (see [`PoolView`]).
    pub fn run_pool_driven(
        nodes: Vec<Box<Node>>,
        threads: usize,
        drive: impl FnOnce(PoolView<'_>),
    ) -> Vec<(Box<Node>, Result<(), RunError>)> {
        Self::pool(nodes, threads, Some(drive))
    }

    #[allow(
        clippy::vec_box,
        reason = "nodes are always boxed: compiled code, links and wakers hold their addresses"
    )]
    fn pool(
        nodes: Vec<Box<Node>>,
        threads: usize,
        drive: Option<impl FnOnce(PoolView<'_>)>,
    ) -> Vec<(Box<Node>, Result<(), RunError>)> {
        let n = nodes.len();
        let pool = Arc::new(PoolShared {
            state: Mutex::new(PoolState {
                slots: Vec::with_capacity(n),
                ready: (0..n).collect(),
                running: 0,
                settled: false,
                waiting: 0,
                timed: 0,
            }),
            work: Condvar::new(),
            flags: nodes
                .iter()
                .map(|n| n.yield_flag.as_ptr() as usize)
                .collect(),
            driven: drive.is_some(),
        });
        let mut tickets = Vec::new();
        {
            let mut st = pool.lock();
            for (i, mut node) in nodes.into_iter().enumerate() {
                node.mailbox.set_waker(Waker {
                    pool: pool.clone(),
                    index: i,
                });
                if node.clock_slices() {
                    tickets.push(crate::ticker::register(&node.yield_flag));
                }
                node.pooled = true;
                node.yield_flag.store(node.flag_rest(), Ordering::Relaxed);
                st.slots.push(Slot::Ready(node));
            }
        }
        std::thread::scope(|s| {
            for _ in 0..threads.max(1) {
                s.spawn(|| worker(&pool));
            }
            if let Some(drive) = drive {
                drive(PoolView { pool: &pool });
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
        if st.timed > 0 {
            wake_due_timers(&mut st);
        }
        if let Some(i) = st.ready.pop_front() {
            let Slot::Ready(mut node) = std::mem::replace(&mut st.slots[i], Slot::Running) else {
                unreachable!("ready nodes are in Ready slots");
            };
            st.running += 1;
            drop(st);
            let outcome = if node.network_stopped() {
                Err(RunError::Halted(node.stopped_halt()))
            } else {
                let start = Instant::now();
                let r = node.run_until_idle();
                node.busy += start.elapsed();
                r
            };
            if let Err(RunError::Halted(h)) = &outcome
                && h.kind != Some(crate::ErrorKind::Stopped)
            {
                node.stop_network();
                pool.yield_all();
            }
            st = pool.lock();
            st.running -= 1;
            if node.network_stopped() {
                stop_parked(&mut st);
            }
            settle(&mut st, i, node, outcome);
            if st.anyone_waiting() {
                pool.work.notify_all();
            }
            continue;
        }
        if st.running == 0 {
            let next_due = earliest_due(&st);
            match next_due {
                None if pool.driven && !st.settled => {
                    st = wait_for(pool, st, Duration::from_millis(50));
                }
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
            // Another worker runs a node, which will likely make one ready soon (a message
            // between two nodes readies its partner): look again a few times before sleeping,
            // since a sleep and its wake-up cost far more than a message.
            let mut spins = 0;
            while spins < SPINS && st.ready.is_empty() && st.running > 0 {
                drop(st);
                std::thread::yield_now();
                st = pool.lock();
                spins += 1;
            }
            if st.ready.is_empty() {
                let wait = earliest_due(&st)
                    .map(|d| d.saturating_duration_since(Instant::now()))
                    .unwrap_or(Duration::from_millis(50));
                st = wait_for(pool, st, wait);
            }
        }
        if all_done(&st) {
            return;
        }
    }
}

fn wait_for<'a>(
    pool: &'a PoolShared,
    mut st: MutexGuard<'a, PoolState>,
    d: Duration,
) -> MutexGuard<'a, PoolState> {
    st.waiting += 1;
    let mut st = pool
        .work
        .wait_timeout(st, d)
        .unwrap_or_else(|p| p.into_inner())
        .0;
    st.waiting -= 1;
    st
}

/// Puts a node that returned from `run_until_idle` back in its slot.
fn settle(st: &mut PoolState, i: usize, node: Box<Node>, outcome: Result<Idle, RunError>) {
    st.slots[i] = match outcome {
        Ok(Idle::Waiting { timer }) => {
            if node.mailbox.has_mail() {
                st.ready.push_back(i);
                Slot::Ready(node)
            } else {
                if timer.is_some() {
                    st.timed += 1;
                }
                Slot::Parked(node, timer.map(|d| Instant::now() + d))
            }
        }
        Ok(Idle::Preempted) => {
            st.ready.push_back(i);
            Slot::Ready(node)
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
    if st.timed == 0 {
        return None;
    }
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
            let node = st.unpark(i);
            st.slots[i] = Slot::Ready(node);
            st.ready.push_back(i);
        }
    }
}

/// The network has stopped: every parked node stops too.
fn stop_parked(st: &mut PoolState) {
    for i in 0..st.slots.len() {
        if let Slot::Parked(..) = st.slots[i] {
            let node = st.unpark(i);
            let halt = RunError::Halted(node.stopped_halt());
            st.slots[i] = finish(node, Err(halt));
        }
    }
}

/// No node is ready or running and no parked node has a timer: each parked node is deadlocked.
fn report_deadlocks(st: &mut PoolState) {
    for i in 0..st.slots.len() {
        if let Slot::Parked(..) = st.slots[i] {
            let node = st.unpark(i);
            let report = RunError::Deadlock(node.deadlock_report());
            st.slots[i] = finish(node, Err(report));
        }
    }
}

fn all_done(st: &PoolState) -> bool {
    st.slots.iter().all(|s| matches!(s, Slot::Done(..)))
}
