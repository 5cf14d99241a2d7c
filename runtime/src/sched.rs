//! The scheduler: the T800 microcode's run queues and dispatch, in software.
//!
//! - Two FIFO run queues (high, low) linked through the `LINK` slot; a woken process goes to the
//!   **back** of the queue of its own priority.
//! - Dispatch order: the hand-off frame (the last PAR branch continuing as its parent), then the
//!   high queue, then the interrupted low-priority frame, then the low queue; when nothing can run,
//!   expired timers, the link mailbox, a sleep until the next timer, or a deadlock report.
//! - A high-priority process made ready while a low one runs sets the yield flag and, at the next
//!   runtime entry or back-edge poll, the low frame moves into the single *interrupted* slot.
//! - Low-priority timeslicing: the shared ticker sets the yield flag every millisecond; a low
//!   process polling it goes to the back of the low queue (only if someone else can run).
//! - A frame returning `DONE` with a caller continues the caller (frame chain); a root returning
//!   `DONE` ends its process.

use std::sync::atomic::Ordering;

use crate::abi::{NOT_PROCESS, ProcFn, Status, Word, Wptr, priority, slot, yield_flag};
use crate::error::{ErrorKind, RunError};
use crate::frame::{get, pri, set, wptr};
use crate::node::Node;

/// The handoff value of a node that gives way to another on its pool thread: not a process
/// descriptor (a null workspace at low priority).
const GIVE_WAY: Word = priority::LOW;

/// Dispatches between two reads of the clock for the timer queues while processes are runnable.
const TIMER_CHECK_INTERVAL: u64 = 64;

/// Why [`Node::run_until_idle`] returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Idle {
    /// Every process has ended.
    Finished,
    /// Processes wait for a timer (due in `timer`) and/or for link traffic.
    Waiting {
        /// Time until the earliest timer, if any is pending.
        timer: Option<std::time::Duration>,
    },
    /// The node has had its turn on a pool thread and gives way; processes remain runnable.
    Preempted,
}

impl Node {
    /// Makes the process `desc` (Wptr | priority) runnable at the back of its queue.
    ///
    /// A high-priority process woken while a low-priority one runs requests preemption.
    #[inline]
    pub(crate) fn schedule(&mut self, desc: Word) {
        let p = pri(desc);
        // SAFETY: descriptors on channels, timers and joins are live workspaces of this node.
        unsafe { self.enqueue(wptr(desc), p) };
        if p == priority::HIGH && self.cur_pri == priority::LOW {
            self.yield_flag
                .store(yield_flag::REQUEST, Ordering::Relaxed);
        }
    }

    /// Appends `ws` to the back of the `p` queue.
    ///
    /// # Safety
    /// `ws` is a live workspace of this node on no queue.
    #[inline]
    pub(crate) unsafe fn enqueue(&mut self, ws: Wptr, p: Word) {
        let q = &mut self.queues[p as usize];
        // SAFETY: `ws` and `q.back` are live workspaces (caller and queue invariant).
        unsafe {
            set(ws, slot::LINK, NOT_PROCESS);
            if q.front.is_null() {
                q.front = ws;
            } else {
                set(q.back, slot::LINK, ws as Word);
            }
        }
        q.back = ws;
    }

    #[inline]
    fn dequeue(&mut self, p: Word) -> Option<Wptr> {
        let q = &mut self.queues[p as usize];
        if q.front.is_null() {
            return None;
        }
        let ws = q.front;
        // SAFETY: queued frames are live workspaces.
        q.front = unsafe { get(ws, slot::LINK) } as Wptr;
        Some(ws)
    }

    /// Ends a runtime entry that may have woken a high-priority process: a low-priority caller
    /// is preempted into the interrupted slot (its `IPTR` already holds the after-op index).
    ///
    /// (The hand-off slot is always empty here: it is only set by `rt_endp`, after which the
    /// ending branch makes no further runtime call.)
    #[inline(always)]
    pub(crate) fn continue_or_preempt(&mut self, ws: Wptr) -> Status {
        if self.cur_pri == priority::LOW && !self.queues[0].front.is_null() {
            self.interrupted = ws;
            return Status::BLOCKED;
        }
        Status::DONE
    }

    /// Records that `ws` blocks on `what` (a [`crate::abi::wait`] value or channel address), for
    /// deadlock reports.
    ///
    /// # Safety
    /// `ws` is a live frame of this node.
    #[inline]
    pub(crate) unsafe fn note_blocked(&mut self, ws: Wptr, what: Word) {
        // SAFETY: `ws` and its root are live frames (caller contract, frame-chain protocol).
        unsafe {
            set(ws, slot::WAIT, what);
            set(get(ws, slot::ROOT) as Wptr, slot::INNER, ws as Word);
        }
    }

    /// The descriptor of the running frame `ws`.
    #[inline]
    pub(crate) fn desc(&self, ws: Wptr) -> Word {
        ws as Word | self.cur_pri
    }

    /// Picks the next frame to run and sets the current priority; `None` when nothing is
    /// runnable, or when the node gives way ([`GIVE_WAY`] in the handoff slot).
    fn next_frame(&mut self) -> Option<Wptr> {
        if self.handoff != NOT_PROCESS {
            let d = std::mem::replace(&mut self.handoff, NOT_PROCESS);
            if d == GIVE_WAY {
                return None;
            }
            if pri(d) == priority::LOW && !self.queues[0].front.is_null() {
                // The parent continues the low branch that just ended: a ready high process
                // preempts it, so it waits in the interrupted slot.
                self.interrupted = wptr(d);
            } else {
                self.run_at(pri(d));
                return Some(wptr(d));
            }
        }
        if self
            .stats
            .context_switches
            .is_multiple_of(TIMER_CHECK_INTERVAL)
        {
            self.poll_events();
        }
        let next = self.dequeue_next();
        if next.is_some() {
            self.stats.context_switches += 1;
        }
        next
    }

    /// Switches the running priority to `p`. When it changes, the yield flag takes its resting
    /// value at `p`, so that timeslicing by count counts low-priority polls only (a request
    /// pending at the old priority is dropped, as the high priority never acts on one and the
    /// low priority gets one at its next tick or count).
    #[inline(always)]
    fn run_at(&mut self, p: Word) {
        if self.cur_pri != p {
            self.cur_pri = p;
            self.yield_flag.store(self.flag_rest(), Ordering::Relaxed);
        }
    }

    /// Takes the next frame from the high queue, the interrupted slot or the low queue.
    #[inline(always)]
    fn dequeue_next(&mut self) -> Option<Wptr> {
        if let Some(ws) = self.dequeue(priority::HIGH) {
            self.run_at(priority::HIGH);
            return Some(ws);
        }
        self.cur_pri = priority::LOW;
        self.yield_flag.store(self.flag_rest(), Ordering::Relaxed);
        if !self.interrupted.is_null() {
            return Some(std::mem::replace(
                &mut self.interrupted,
                std::ptr::null_mut(),
            ));
        }
        self.dequeue(priority::LOW)
    }

    /// Fires expired timers and drains the link mailbox.
    pub(crate) fn poll_events(&mut self) {
        if !self.timers[0].is_null() || !self.timers[1].is_null() {
            let now = self.now();
            self.fire_timers(now);
        }
        if self.link_waiters > 0 {
            self.drain_mailbox();
        }
    }

    /// The main loop of [`Node::run`]: runs until idle, waits for a timer or link traffic (or
    /// reports a network deadlock), and so on until every process has ended.
    pub(crate) fn run_loop(&mut self) -> Result<(), RunError> {
        loop {
            match self.run_until_idle()? {
                Idle::Finished => return Ok(()),
                Idle::Preempted => {}
                Idle::Waiting { timer } => self.wait_for_events(timer)?,
            }
        }
    }

    /// Runs processes until none is runnable, without blocking the OS thread.
    ///
    /// Returns [`Idle::Finished`] when every process has ended, [`Idle::Waiting`] when the
    /// remaining processes wait for a timer or for link traffic (another node's mail), and a
    /// local deadlock as an error. The caller decides how to wait: [`Node::run`] sleeps on the
    /// node's mailbox; a pool of threads runs other nodes meanwhile.
    pub fn run_until_idle(&mut self) -> Result<Idle, RunError> {
        loop {
            while let Some(ws) = self.next_frame() {
                self.dispatch(ws)?;
            }
            if self.give_way {
                self.give_way = false;
                self.slices = 0;
                return Ok(Idle::Preempted);
            }
            self.poll_events();
            if !self.queues[0].front.is_null() || !self.queues[1].front.is_null() {
                continue;
            }
            if self.timers[0].is_null() && self.timers[1].is_null() && self.link_waiters == 0 {
                if self.live.is_null() {
                    return Ok(Idle::Finished);
                }
                return Err(RunError::Deadlock(self.deadlock_report()));
            }
            return Ok(Idle::Waiting {
                timer: self.time_to_next_timer(),
            });
        }
    }

    /// Runs `ws` and, while frames finish, their callers.
    fn dispatch(&mut self, mut ws: Wptr) -> Result<(), RunError> {
        loop {
            // SAFETY: runnable frames are live workspaces whose CODE slot holds a ProcFn stored by
            // `start_root` or by the caller (frame-chain protocol).
            let status = unsafe {
                let code: ProcFn =
                    std::mem::transmute::<usize, ProcFn>(get(ws, slot::CODE) as usize);
                code(ws, self)
            };
            match status {
                Status::DONE => {
                    // SAFETY: `ws` is still live: it just returned.
                    let caller = unsafe { get(ws, slot::CALLER) } as Wptr;
                    if caller.is_null() {
                        // SAFETY: a root that returned DONE has ended.
                        unsafe { self.end_root(ws) };
                        return Ok(());
                    }
                    ws = caller;
                }
                Status::BLOCKED => return Ok(()),
                Status::HALTED => return Err(self.halt_error()),
                Status(other) => return Err(RunError::BadStatus(other)),
            }
        }
    }

    /// Adds a root to the live list.
    ///
    /// # Safety
    /// `ws` is a root workspace not on the list.
    pub(crate) unsafe fn live_insert(&mut self, ws: Wptr) {
        // SAFETY: `ws` and the current head are live roots.
        unsafe {
            set(ws, slot::LIVE_PREV, 0);
            set(ws, slot::LIVE_NEXT, self.live as Word);
            if !self.live.is_null() {
                set(self.live, slot::LIVE_PREV, ws as Word);
            }
        }
        self.live = ws;
    }

    /// Removes an ended root from the live list.
    ///
    /// # Safety
    /// `ws` is on the live list.
    pub(crate) unsafe fn end_root(&mut self, ws: Wptr) {
        // SAFETY: list neighbours are live roots.
        unsafe {
            let prev = get(ws, slot::LIVE_PREV) as Wptr;
            let next = get(ws, slot::LIVE_NEXT) as Wptr;
            if prev.is_null() {
                self.live = next;
            } else {
                set(prev, slot::LIVE_NEXT, next as Word);
            }
            if !next.is_null() {
                set(next, slot::LIVE_PREV, prev as Word);
            }
        }
    }
}

/// Back-edge poll target, called when the yield flag is set (when it is
/// [`yield_flag::COUNT`], only when the polls left reach 0).
///
/// Resets the flag. At high priority: `DONE` (high processes are never timesliced). At low
/// priority: preempted into the interrupted slot if a high process is ready; when a thread pool
/// runs the node and it has had its turn (`pool::TURN_SLICES` timeslices), put at the
/// back of the low queue with the node giving way; put at the back of the low queue if anything
/// else could run; otherwise `DONE`. When timeslicing by count, only every
/// [`crate::NodeConfig::counted_slices`]-th low-priority poll is a timeslice: one that a
/// request sent here counts itself, and unless it is that one, only checks for a ready high
/// process. A node whose network has stopped halts here.
///
/// # Safety
/// `node` is the running node and `ws` the calling frame, its `IPTR` holding the loop-head index.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_timeslice(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: the caller passes the running node.
    let node = unsafe { &mut *node };
    // Resetting the flag is safe at either priority: at high priority it can only hold a tick
    // (nothing preempts high), and a low process is re-flagged at the next tick.
    node.yield_flag.store(node.flag_rest(), Ordering::Relaxed);
    if node.cur_pri == priority::HIGH {
        return Status::DONE;
    }
    if node.config.counted_slices.is_some() {
        // Compiled code counted this poll and called when none were left, or a request sent
        // it here uncounted.
        if node.polls_left != 0 {
            node.polls_left -= 1;
        }
        if node.polls_left != 0 {
            return node.continue_or_preempt(ws);
        }
        node.polls_left = node.config.polls_per_slice();
    }
    if node.network_stopped() {
        // SAFETY: `ws` is the running frame.
        return unsafe { crate::error::rt_error(node, ws, ErrorKind::Stopped as Word, -1) };
    }
    node.poll_events();
    if node.continue_or_preempt(ws) == Status::BLOCKED {
        return Status::BLOCKED;
    }
    if node.pooled {
        node.slices += 1;
        if node.slices >= crate::pool::TURN_SLICES && node.handoff == NOT_PROCESS {
            // Handing off to no process ends the dispatch loop at no cost to it.
            node.give_way = true;
            node.handoff = GIVE_WAY;
            // SAFETY: `ws` is the running frame, on no queue.
            unsafe { node.enqueue(ws, priority::LOW) };
            return Status::BLOCKED;
        }
    }
    if node.queues[1].front.is_null() {
        return Status::DONE;
    }
    // SAFETY: `ws` is the running frame, on no queue.
    unsafe { node.enqueue(ws, priority::LOW) };
    Status::BLOCKED
}

/// The RESCHEDULE predefine: the caller goes to the back of its priority's run queue.
///
/// # Safety
/// As for [`rt_timeslice`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_reschedule(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: the caller passes the running node and its running frame.
    unsafe {
        let node = &mut *node;
        let p = node.cur_pri;
        node.enqueue(ws, p);
    }
    Status::BLOCKED
}
