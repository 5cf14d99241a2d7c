//! PAR and process life cycle: `startp`, `runp` at a given priority (PRI PAR), `endp` with a join
//! block `{parent, count}`, the parent's wait for the join, and `stopp`.
//!
//! Branch workspaces are sub-blocks of the parent's workspace (sizes are static), so starting a
//! process costs no allocation: it fills in the branch's header, links it into the node's live list
//! and appends it to the run queue. The last branch to end hands the processor straight to the
//! parent, which resumes at the after-PAR index it stored before `rt_par_wait`.

use crate::abi::{ProcFn, Status, Word, Wptr, join, priority, wait};
use crate::frame::{pri, wptr};
use crate::node::Node;

/// Starts branch `child` running `code` from resume index `entry`, at the caller's priority
/// (T800 `startp`).
///
/// # Safety
/// `node` is the running node; `child` a workspace (header reserved) disjoint from every live
/// frame, valid until the branch ends; `code` a [`ProcFn`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_startp(
    node: *mut Node,
    _ws: Wptr,
    child: Wptr,
    code: ProcFn,
    entry: Word,
) -> Status {
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        let p = node.cur_pri;
        node.start_root(child, code, entry, p);
    }
    Status::DONE
}

/// Starts branch `child` at priority `pri` ([`priority::HIGH`] for the first branch of a PRI
/// PAR). Blocking point: a low-priority caller starting a high-priority branch is preempted.
///
/// # Safety
/// As for [`rt_startp`]; the caller's after-op index is in `IPTR`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_startp_pri(
    node: *mut Node,
    ws: Wptr,
    child: Wptr,
    code: ProcFn,
    entry: Word,
    pri: Word,
) -> Status {
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        node.start_root(child, code, entry, pri & priority::LOW);
        node.continue_or_preempt(ws)
    }
}

/// Ends a PAR branch (T800 `endp`): decrements the join count; the last branch hands over to the
/// parent. Returns `DONE` (the branch's process has ended); compiled code returns it.
///
/// # Safety
/// `node` is the running node, `ws` the branch's root frame, `join` the parent's join block.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_endp(node: *mut Node, _ws: Wptr, join: *mut Word) -> Status {
    // SAFETY: caller contract: the join block lives in the parent's workspace.
    unsafe {
        let node = &mut *node;
        let count = join.offset(join::COUNT);
        *count -= 1;
        let parent = *join.offset(join::PARENT);
        if *count == 0 && parent != 0 {
            node.join_parent(parent);
        }
    }
    Status::DONE
}

/// The parent of a PAR waits for its branches. Blocking point (`DONE` if all have ended).
///
/// # Safety
/// `node` is the running node, `ws` the parent frame (after-PAR index in `IPTR`), `join` its join
/// block (`PARENT` = 0 when the branches were started).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_par_wait(node: *mut Node, ws: Wptr, join: *mut Word) -> Status {
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        if *join.offset(join::COUNT) == 0 {
            return Status::DONE;
        }
        *join.offset(join::PARENT) = node.desc(ws);
        node.note_blocked(ws, wait::JOIN);
    }
    Status::BLOCKED
}

/// Deschedules the caller for good (T800 `stopp`); it shows in deadlock reports as stopped.
///
/// # Safety
/// `node` is the running node, `ws` the calling frame.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_stopp(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: caller contract.
    unsafe { (*node).note_blocked(ws, wait::STOPPED) };
    Status::BLOCKED
}

impl Node {
    /// Resumes a PAR's parent when its last branch ends: directly (hand-off) when it has the
    /// running priority, else through its run queue.
    fn join_parent(&mut self, parent: Word) {
        if pri(parent) == self.cur_pri && self.handoff == 0 {
            self.handoff = parent;
        } else {
            self.schedule(wptr(parent) as Word | pri(parent));
        }
    }
}
