//! One-word channels: `rt_in` and `rt_out` (T800 `in`/`out`, KRoC CCSP's channel word).
//!
//! Three layers, which do not interfere: **scheduling** (blocking the caller, requeueing the
//! partner: `Node::schedule`), **channel-word manipulation** (this module) and **data movement**
//! (`copy`). Why one word: a channel is always between exactly one reader and one writer, so the
//! first party to arrive parks itself in the word and the second completes the transfer; no
//! buffer, no lock, and a channel costs 8 bytes.
//!
//! # The channel word
//!
//! ```text
//!                 in/out first                     other side arrives:
//!   +-------+  -------------------->  +-----------+  copies, clears  +-------+
//!   | EMPTY |                         | Wptr|pri  | ---------------> | EMPTY |
//!   |  (0)  |  <--------------------  +-----------+  requeues first  +-------+
//!   +-------+        disc
//!       |  enbc (ALTing reader)          ^
//!       v                                | out: overwrite with writer's Wptr|pri,
//!   +---------------+ -------------------+ ALTer State := Ready (scheduled if Waiting)
//!   | Wptr|ALT|pri  |
//!   +---------------+
//!
//!   +------------------+  permanently: a link or host endpoint; `in`/`out` go to the
//!   | endpoint|ENDPOINT|  endpoint's engine (crate::endpoint)
//!   +------------------+
//! ```
//!
//! The second party copies the data and puts the first at the **back** of its run queue, then
//! carries on (unless it is low priority and just woke a high-priority process: then it is
//! preempted). While blocked, a frame's data pointer is in its `POINTER` slot.

use crate::abi::{NOT_PROCESS, Status, Word, Wptr, alt_state, slot, tag, wait};
use crate::frame::{get, set, wptr};
use crate::node::Node;

/// Copies `len` bytes from `src` to `dst`.
///
/// # Safety
/// Both ranges are valid for `len` bytes and do not overlap (they belong to two processes).
#[inline(always)]
pub(crate) unsafe fn copy(src: *const u8, dst: *mut u8, len: Word) {
    // SAFETY: caller contract; word, INT32 and BYTE messages avoid a memcpy call.
    unsafe {
        match len {
            8 => dst
                .cast::<u64>()
                .write_unaligned(src.cast::<u64>().read_unaligned()),
            4 => dst
                .cast::<u32>()
                .write_unaligned(src.cast::<u32>().read_unaligned()),
            1 => *dst = *src,
            _ => copy_bytes(src, dst, len),
        }
    }
}

/// The general case of [`copy`], out of line to keep the channel entries small.
///
/// # Safety
/// As for [`copy`].
#[inline(never)]
unsafe fn copy_bytes(src: *const u8, dst: *mut u8, len: Word) {
    if len > 0 {
        // SAFETY: caller contract.
        unsafe { std::ptr::copy_nonoverlapping(src, dst, len as usize) };
    }
}

/// Parks the running frame `ws` in the channel word with its data pointer.
///
/// # Safety
/// `chan` is a valid channel word, `ws` the running frame.
#[inline(always)]
unsafe fn park(node: &mut Node, ws: Wptr, chan: *mut Word, data: *mut u8, what: Word) {
    // SAFETY: caller contract.
    unsafe {
        *chan = node.desc(ws);
        set(ws, slot::POINTER, data as Word);
        node.note_blocked(ws, what);
    }
}

/// Input `len` bytes from channel `chan` into `data` (T800 `in`). Blocking point.
///
/// # Safety
/// `node` is the running node, `ws` the calling frame (after-op index in `IPTR`), `chan` a channel
/// word, `data` valid for `len` bytes and inside the frame's workspace (or otherwise live until
/// the input completes).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_in(
    node: *mut Node,
    ws: Wptr,
    chan: *mut Word,
    data: *mut u8,
    len: Word,
) -> Status {
    // SAFETY: the caller passes the running node and a valid channel word.
    let (node, w) = unsafe { (&mut *node, *chan) };
    if w == NOT_PROCESS {
        // SAFETY: first to arrive; wait for the outputter.
        unsafe { park(node, ws, chan, data, chan as Word) };
        return Status::BLOCKED;
    }
    if w & tag::ENDPOINT != 0 {
        // SAFETY: an ENDPOINT word always points at one of this node's endpoints.
        return unsafe { in_endpoint(node, ws, chan, w, data, len) };
    }
    // SAFETY: an outputter is parked in the word; its POINTER slot is valid for `len` bytes.
    unsafe {
        let src = get(wptr(w), slot::POINTER) as *const u8;
        if matches!(len, 1 | 4 | 8) {
            complete(node, ws, chan, w, src, data, len)
        } else {
            complete_any(node, ws, chan, w, src, data, len)
        }
    }
}

/// Output `len` bytes from `data` to channel `chan` (T800 `out`). Blocking point.
///
/// # Safety
/// As for [`rt_in`]; `data` must stay valid until the output completes (keep it in the workspace).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_out(
    node: *mut Node,
    ws: Wptr,
    chan: *mut Word,
    data: *mut u8,
    len: Word,
) -> Status {
    // SAFETY: the caller passes the running node and a valid channel word.
    let (node, w) = unsafe { (&mut *node, *chan) };
    let what = chan as Word | wait::OUTPUT;
    if w == NOT_PROCESS {
        // SAFETY: first to arrive; wait for the inputter.
        unsafe { park(node, ws, chan, data, what) };
        return Status::BLOCKED;
    }
    if w & (tag::ENDPOINT | tag::ALT) != 0 {
        // SAFETY: the word is an endpoint or an ALTing reader of this node.
        return unsafe { out_special(node, ws, chan, w, data, len) };
    }
    // SAFETY: an inputter is parked in the word; its POINTER slot is valid for `len` bytes.
    unsafe {
        let dst = get(wptr(w), slot::POINTER) as *mut u8;
        if matches!(len, 1 | 4 | 8) {
            complete(node, ws, chan, w, data, dst, len)
        } else {
            complete_any(node, ws, chan, w, data, dst, len)
        }
    }
}

/// What `rt_in`/`rt_out` do after completing a communication, for compiled code that completed
/// one inline (copied the data, emptied the channel word, counted it and put the partner, of
/// the running priority, at the back of its queue): a low-priority process gives way to a ready
/// high-priority one. Blocking point.
///
/// # Safety
/// `node` is the running node, `ws` the calling frame (after-op index in `IPTR`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_preempt(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: caller contract.
    unsafe { (*node).continue_or_preempt(ws) }
}

/// The second party's half of a communication: copy, empty the channel, requeue the first party
/// (`w`) at the back of its queue, and carry on unless preempted.
///
/// # Safety
/// `w` is the parked partner's descriptor; `src`/`dst` valid for `len` bytes.
#[inline(always)]
unsafe fn complete(
    node: &mut Node,
    ws: Wptr,
    chan: *mut Word,
    w: Word,
    src: *const u8,
    dst: *mut u8,
    len: Word,
) -> Status {
    // SAFETY: caller contract.
    unsafe {
        copy(src, dst, len);
        *chan = NOT_PROCESS;
    }
    node.stats.communications += 1;
    node.schedule(w);
    node.continue_or_preempt(ws)
}

/// [`complete`] for message lengths other than 1, 4 and 8 bytes, out of line so that the
/// common entries make no call.
///
/// # Safety
/// As for [`complete`].
#[inline(never)]
unsafe fn complete_any(
    node: &mut Node,
    ws: Wptr,
    chan: *mut Word,
    w: Word,
    src: *const u8,
    dst: *mut u8,
    len: Word,
) -> Status {
    // SAFETY: forwarded contract.
    unsafe { complete(node, ws, chan, w, src, dst, len) }
}

/// `rt_in` on an endpoint channel, out of line (a call keeps the common path a leaf).
///
/// # Safety
/// As for [`rt_in`]; `w` is the channel's ENDPOINT-tagged word.
#[inline(never)]
unsafe fn in_endpoint(
    node: &mut Node,
    ws: Wptr,
    chan: *mut Word,
    w: Word,
    data: *mut u8,
    len: Word,
) -> Status {
    // SAFETY: caller contract.
    unsafe { node.endpoint_in(ws, chan, w, data, len) }
}

/// `rt_out` on an endpoint channel or to an ALTing reader, out of line.
///
/// # Safety
/// As for [`rt_out`]; `w` is ENDPOINT- or ALT-tagged.
#[inline(never)]
unsafe fn out_special(
    node: &mut Node,
    ws: Wptr,
    chan: *mut Word,
    w: Word,
    data: *mut u8,
    len: Word,
) -> Status {
    if w & tag::ENDPOINT != 0 {
        // SAFETY: an ENDPOINT word always points at one of this node's endpoints.
        return unsafe { node.endpoint_out(ws, chan, w, data, len) };
    }
    // SAFETY: the reader is ALTing and enabled this channel; it is a live frame.
    unsafe {
        park(node, ws, chan, data, chan as Word | wait::OUTPUT);
        node.alt_guard_ready(w);
    }
    Status::BLOCKED
}

impl Node {
    /// An ALTing process `w` (tagged descriptor) has a ready guard: Enabling or Waiting become
    /// Ready; a Waiting one is scheduled.
    ///
    /// # Safety
    /// `w` is the descriptor of a live ALTing frame of this node.
    pub(crate) unsafe fn alt_guard_ready(&mut self, w: Word) {
        let alter = wptr(w);
        // SAFETY: caller contract.
        unsafe {
            match get(alter, slot::STATE) {
                alt_state::WAITING => {
                    set(alter, slot::STATE, alt_state::READY);
                    self.schedule(w & !tag::ALT);
                }
                alt_state::ENABLING => set(alter, slot::STATE, alt_state::READY),
                _ => {}
            }
        }
    }
}

/// Extended rendezvous (occam-pi `c ?? x`), first step: waits until an outputter is parked in
/// channel `chan`, without taking its data. Blocking point.
///
/// An empty word is enabled as a one-guard ALT (the word holds the caller's descriptor tagged
/// `ALT`, the caller is Waiting): the outputter that arrives sees an ALTing reader, parks itself
/// and makes the caller ready, exactly as for an ALT, so outputters need no extended form. After
/// this returns (or the caller resumes), [`rt_xin`] finds the outputter in the word. An endpoint
/// word needs no wait.
///
/// # Safety
/// As for [`rt_in`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_xwait(node: *mut Node, ws: Wptr, chan: *mut Word) -> Status {
    // SAFETY: the caller passes the running node and a valid channel word.
    let (node, w) = unsafe { (&mut *node, *chan) };
    if w != NOT_PROCESS {
        return Status::DONE;
    }
    // SAFETY: `ws` is the running frame; it waits as a one-guard ALT.
    unsafe {
        *chan = node.desc(ws) | tag::ALT;
        set(ws, slot::STATE, alt_state::WAITING);
        node.note_blocked(ws, chan as Word);
    }
    Status::BLOCKED
}

/// Extended rendezvous, second step: takes `len` bytes from the outputter parked in `chan` (after
/// [`rt_xwait`]) into `data` and empties the word, but does not reschedule the outputter: its
/// descriptor goes to `*held`, for [`rt_xend`] once the extended process has ended. Blocking
/// point (an endpoint word performs an ordinary input, and a channel to another node cannot hold
/// its outputter: `*held` is then [`NOT_PROCESS`]).
///
/// # Safety
/// As for [`rt_in`]; [`rt_xwait`] has returned for `chan` with no other input since, and `held`
/// is a workspace word holding [`NOT_PROCESS`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_xin(
    node: *mut Node,
    ws: Wptr,
    chan: *mut Word,
    data: *mut u8,
    len: Word,
    held: *mut Word,
) -> Status {
    // SAFETY: the caller passes the running node and a valid channel word.
    let (node, w) = unsafe { (&mut *node, *chan) };
    if w & tag::ENDPOINT != 0 {
        // SAFETY: an ENDPOINT word always points at one of this node's endpoints.
        return unsafe { in_endpoint(node, ws, chan, w, data, len) };
    }
    debug_assert!(
        w != NOT_PROCESS && w & tag::ALT == 0,
        "rt_xin without an outputter"
    );
    // SAFETY: an outputter is parked in the word; its POINTER slot is valid for `len` bytes.
    unsafe {
        let src = get(wptr(w), slot::POINTER) as *const u8;
        copy(src, data, len);
        *chan = NOT_PROCESS;
        *held = w;
    }
    node.stats.communications += 1;
    Status::DONE
}

/// Extended rendezvous, last step: releases the outputter that [`rt_xin`] left in `*held` (at
/// the back of its run queue) and empties `*held`; nothing if it is empty. Blocking point (a
/// low-priority process gives way to a released high-priority one).
///
/// # Safety
/// `node` is the running node, `ws` the calling frame, `held` a workspace word that holds
/// [`NOT_PROCESS`] or a descriptor that [`rt_xin`] stored.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_xend(node: *mut Node, ws: Wptr, held: *mut Word) -> Status {
    // SAFETY: caller contract.
    let (node, w) = unsafe { (&mut *node, *held) };
    if w == NOT_PROCESS {
        return Status::DONE;
    }
    // SAFETY: caller contract.
    unsafe { *held = NOT_PROCESS };
    node.schedule(w);
    node.continue_or_preempt(ws)
}
