//! Timers: `TIMER` reads, `tim ? AFTER t`, the timer queues and sleeping when idle.
//!
//! A node's clock counts microseconds since the node was created (monotonic), as a 32-bit INT
//! value (sign-extended into a [`Word`]): it wraps after about 71 minutes, and every comparison is
//! the modular `AFTER` (`a AFTER b` ⇔ `(a − b) mod 2³²` is positive as an INT32). `tim ? AFTER t`
//! waits until the clock is **strictly** after `t`, so a waiting frame is queued with time `t + 1`.
//! There is one timer queue per priority, linked through `TLINK`, sorted by `TIME` (ties in FIFO
//! order). The queues are examined when the node is idle, at every timeslice and every few dozen
//! dispatches; an idle node with pending timers sleeps until the earliest.

use std::time::Duration;

use crate::abi::{Status, Word, Wptr, alt_state, slot, time_state, wait};
use crate::frame::{get, set};
use crate::node::Node;

/// The occam `a AFTER b` on 32-bit timer values.
#[inline]
pub fn after(a: Word, b: Word) -> bool {
    (a as i32).wrapping_sub(b as i32) > 0
}

impl Node {
    /// The node's clock in microseconds, as a sign-extended 32-bit value.
    pub fn now(&self) -> Word {
        self.epoch.elapsed().as_micros() as u32 as i32 as Word
    }

    /// Inserts the running frame `ws` into the current priority's timer queue, to wake at `t`.
    ///
    /// # Safety
    /// `ws` is the running frame, on no timer queue.
    pub(crate) unsafe fn timer_insert(&mut self, ws: Wptr, t: Word) {
        let p = self.cur_pri as usize;
        let mut prev: Wptr = std::ptr::null_mut();
        let mut cur = self.timers[p];
        // SAFETY: timer queue entries are live frames.
        unsafe {
            while !cur.is_null() && !after(get(cur, slot::TIME), t) {
                prev = cur;
                cur = get(cur, slot::TLINK) as Wptr;
            }
            set(ws, slot::TIME, t);
            set(ws, slot::TLINK, cur as Word);
            if prev.is_null() {
                self.timers[p] = ws;
            } else {
                set(prev, slot::TLINK, ws as Word);
            }
        }
    }

    /// Removes `ws` from whichever timer queue holds it.
    ///
    /// # Safety
    /// `ws` is a live frame of this node.
    pub(crate) unsafe fn timer_remove(&mut self, ws: Wptr) {
        for head in &mut self.timers {
            let mut prev: Wptr = std::ptr::null_mut();
            let mut cur = *head;
            // SAFETY: timer queue entries are live frames.
            unsafe {
                while !cur.is_null() {
                    let next = get(cur, slot::TLINK) as Wptr;
                    if cur == ws {
                        if prev.is_null() {
                            *head = next;
                        } else {
                            set(prev, slot::TLINK, next as Word);
                        }
                        return;
                    }
                    prev = cur;
                    cur = next;
                }
            }
        }
    }

    /// Wakes every frame whose time has come.
    pub(crate) fn fire_timers(&mut self, now: Word) {
        for p in 0..2 {
            loop {
                let ws = self.timers[p];
                // SAFETY: timer queue entries are live frames.
                if ws.is_null() || after(unsafe { get(ws, slot::TIME) }, now) {
                    break;
                }
                // SAFETY: as above.
                unsafe {
                    self.timers[p] = get(ws, slot::TLINK) as Wptr;
                    self.timer_fired(ws, p as Word);
                }
            }
        }
    }

    /// A frame taken off the timer queue: a `tin` is scheduled; an ALTer becomes Ready.
    ///
    /// # Safety
    /// `ws` is a live frame just removed from the `p` timer queue.
    unsafe fn timer_fired(&mut self, ws: Wptr, p: Word) {
        // SAFETY: caller contract.
        unsafe {
            if get(ws, slot::WAIT) != wait::ALT {
                self.schedule(ws as Word | p);
                return;
            }
            set(ws, slot::TLINK, time_state::SET);
            if get(ws, slot::STATE) != alt_state::READY {
                set(ws, slot::STATE, alt_state::READY);
                self.schedule(ws as Word | p);
            }
        }
    }

    /// The time of the earliest pending timer, if any.
    fn earliest_timer(&self) -> Option<Word> {
        let mut best: Option<Word> = None;
        for &head in &self.timers {
            if head.is_null() {
                continue;
            }
            // SAFETY: timer queue heads are live frames.
            let t = unsafe { get(head, slot::TIME) };
            best = Some(match best {
                Some(b) if after(t, b) => b,
                _ => t,
            });
        }
        best
    }

    /// Time until the earliest pending timer, if any.
    pub(crate) fn time_to_next_timer(&self) -> Option<Duration> {
        self.earliest_timer().map(|t| {
            let delta = (t as i32).wrapping_sub(self.now() as i32);
            Duration::from_micros(delta.max(0) as u64)
        })
    }

    /// Blocks the OS thread until the timer (due in `timer`) or, when frames wait on links, until
    /// mail arrives; reports a network deadlock when no node can move.
    pub(crate) fn wait_for_events(
        &mut self,
        timer: Option<Duration>,
    ) -> Result<(), crate::RunError> {
        if self.link_waiters > 0 {
            self.wait_mailbox(timer)?;
        } else if let Some(d) = timer {
            std::thread::sleep(d);
        }
        Ok(())
    }
}

/// Reads the node's TIMER (microseconds, 32-bit modular).
///
/// # Safety
/// `node` is the running node.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_timer_read(node: *mut Node) -> Word {
    // SAFETY: caller contract.
    unsafe { (*node).now() }
}

/// `tim ? AFTER time`: continues if the clock is already after `time`, else waits. Blocking
/// point.
///
/// # Safety
/// `node` is the running node, `ws` the calling frame with its after-op index in `IPTR`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_tin(node: *mut Node, ws: Wptr, time: Word) -> Status {
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        if after(node.now(), time) {
            return Status::DONE;
        }
        node.timer_insert(ws, time.wrapping_add(1));
        node.note_blocked(ws, wait::TIMER);
    }
    Status::BLOCKED
}

#[cfg(test)]
mod test {
    use super::after;

    #[test]
    fn after_is_modular() {
        assert!(after(1, 0));
        assert!(!after(0, 0));
        assert!(!after(0, 1));
        assert!(after(i32::MIN as i64, i32::MAX as i64));
        assert!(after(5, -5));
    }
}
