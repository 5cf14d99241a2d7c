//! ALT: enable, wait, disable (T800 `alt`/`talt`, `enbc`/`enbs`/`enbt`, `altwt`/`taltwt`,
//! `disc`/`diss`/`dist`, `altend`).
//!
//! The `STATE` slot goes Enabling → (Waiting →) Ready. Enabling a channel guard whose channel is
//! empty parks `Wptr|ALT|pri` in the channel word; an outputter finding that tag overwrites it with
//! itself and makes the ALTer Ready (`Node::alt_guard_ready`). A timer guard records the earliest
//! time in `TIME` (`TLINK` = TimeSet); `taltwt` puts the ALTer on the timer queue, and a firing
//! timer makes it Ready. Disabling runs in the order codegen emits (PRI ALT: textual order): the
//! first ready guard disabled is selected, and every enabled channel word still holding the ALT tag
//! is cleared. Boolean guards are the `guard` arguments (0 = false); replicated ALTs enable and
//! disable in loops; a SKIP guard is `rt_enbs`/`rt_diss`.

use crate::abi::{
    NONE_SELECTED, NOT_PROCESS, Status, Word, Wptr, alt_state, slot, tag, time_state, wait,
};
use crate::frame::{get, set, wptr};
use crate::node::Node;
use crate::timer::after;

/// Starts an ALT: State := Enabling.
///
/// # Safety
/// `ws` is the calling frame; `node` the running node.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_alt(_node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: `ws` is a live frame.
    unsafe {
        set(ws, slot::STATE, alt_state::ENABLING);
        set(ws, slot::SELECT, NONE_SELECTED);
    }
    Status::DONE
}

/// Starts an ALT with timer guards: State := Enabling, TLink := TimeNotSet.
///
/// # Safety
/// As for [`rt_alt`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_talt(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: forwarded contract.
    unsafe {
        set(ws, slot::TLINK, time_state::NOT_SET);
        rt_alt(node, ws)
    }
}

/// Enables a channel guard.
///
/// # Safety
/// As for [`rt_alt`]; `chan` is a channel word.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_enbc(
    node: *mut Node,
    ws: Wptr,
    guard: Word,
    chan: *mut Word,
) -> Status {
    if guard == 0 {
        return Status::DONE;
    }
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        let w = *chan;
        let me = node.desc(ws) | tag::ALT;
        if w == NOT_PROCESS {
            *chan = me;
        } else if w & tag::ENDPOINT != 0 {
            if node.endpoint_enable(ws, w) {
                set(ws, slot::STATE, alt_state::READY);
            }
        } else if w != me {
            set(ws, slot::STATE, alt_state::READY);
        }
    }
    Status::DONE
}

/// Enables a SKIP guard: a true guard makes the ALT Ready.
///
/// # Safety
/// As for [`rt_alt`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_enbs(_node: *mut Node, ws: Wptr, guard: Word) -> Status {
    if guard != 0 {
        // SAFETY: `ws` is a live frame.
        unsafe { set(ws, slot::STATE, alt_state::READY) };
    }
    Status::DONE
}

/// Enables a timer guard `tim ? AFTER time`, keeping the earliest time.
///
/// # Safety
/// As for [`rt_alt`], after [`rt_talt`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_enbt(_node: *mut Node, ws: Wptr, guard: Word, time: Word) -> Status {
    if guard == 0 {
        return Status::DONE;
    }
    // SAFETY: `ws` is a live frame.
    unsafe {
        if get(ws, slot::TLINK) == time_state::NOT_SET {
            set(ws, slot::TLINK, time_state::SET);
            set(ws, slot::TIME, time);
        } else if after(get(ws, slot::TIME), time) {
            set(ws, slot::TIME, time);
        }
    }
    Status::DONE
}

/// Waits until a guard is Ready. Blocking point.
///
/// # Safety
/// As for [`rt_alt`]; `IPTR` holds the after-wait index.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_altwt(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: caller contract.
    unsafe {
        if get(ws, slot::STATE) == alt_state::READY {
            return Status::DONE;
        }
        set(ws, slot::STATE, alt_state::WAITING);
        (*node).note_blocked(ws, wait::ALT);
    }
    Status::BLOCKED
}

/// Waits until a guard is Ready or the earliest enabled time has passed. Blocking point.
///
/// # Safety
/// As for [`rt_altwt`], after [`rt_talt`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_taltwt(node: *mut Node, ws: Wptr) -> Status {
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        if get(ws, slot::STATE) == alt_state::READY {
            return Status::DONE;
        }
        if get(ws, slot::TLINK) == time_state::SET {
            let t = get(ws, slot::TIME);
            if after(node.now(), t) {
                set(ws, slot::STATE, alt_state::READY);
                return Status::DONE;
            }
            node.timer_insert(ws, t.wrapping_add(1));
        }
        set(ws, slot::STATE, alt_state::WAITING);
        node.note_blocked(ws, wait::ALT);
    }
    Status::BLOCKED
}

/// Selects `branch` if nothing is selected yet; returns 1 if it did.
///
/// # Safety
/// `ws` is a live frame.
unsafe fn select(ws: Wptr, branch: Word) -> Word {
    // SAFETY: caller contract.
    unsafe {
        if get(ws, slot::SELECT) == NONE_SELECTED {
            set(ws, slot::SELECT, branch);
            return 1;
        }
    }
    0
}

/// Disables a channel guard; selects `branch` if the channel is ready and nothing is selected.
/// Returns 1 if this guard was selected.
///
/// # Safety
/// As for [`rt_enbc`], after the wait.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_disc(
    node: *mut Node,
    ws: Wptr,
    guard: Word,
    chan: *mut Word,
    branch: Word,
) -> Word {
    if guard == 0 {
        return 0;
    }
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        let w = *chan;
        if w == NOT_PROCESS {
            return 0;
        }
        if w & tag::ENDPOINT != 0 {
            if !node.endpoint_disable(ws, w) {
                return 0;
            }
        } else if w & tag::ALT != 0 {
            debug_assert_eq!(wptr(w), ws, "a channel enabled by another ALT");
            *chan = NOT_PROCESS;
            return 0;
        }
        select(ws, branch)
    }
}

/// Disables a SKIP guard; selects `branch` if the guard is true and nothing is selected.
///
/// # Safety
/// As for [`rt_enbs`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_diss(_node: *mut Node, ws: Wptr, guard: Word, branch: Word) -> Word {
    if guard == 0 {
        return 0;
    }
    // SAFETY: caller contract.
    unsafe { select(ws, branch) }
}

/// Disables a timer guard: takes the ALTer off the timer queue if it is still there, and selects
/// `branch` if the timer is after `time` and nothing is selected.
///
/// # Safety
/// As for [`rt_enbt`], after the wait.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_dist(
    node: *mut Node,
    ws: Wptr,
    guard: Word,
    time: Word,
    branch: Word,
) -> Word {
    if guard == 0 {
        return 0;
    }
    // SAFETY: caller contract.
    unsafe {
        let node = &mut *node;
        let tl = get(ws, slot::TLINK);
        if tl != time_state::SET && tl != time_state::NOT_SET {
            node.timer_remove(ws);
            set(ws, slot::TLINK, time_state::SET);
        }
        if !after(node.now(), time) {
            return 0;
        }
        select(ws, branch)
    }
}

/// Ends the ALT: returns the selected branch (or [`NONE_SELECTED`] if, against the protocol, no
/// ready guard was disabled).
///
/// # Safety
/// As for [`rt_alt`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_altend(_node: *mut Node, ws: Wptr) -> Word {
    // SAFETY: `ws` is a live frame.
    unsafe {
        set(ws, slot::WAIT, wait::NOTHING);
        get(ws, slot::SELECT)
    }
}
