//! The contract between compiled occam code and the runtime.
//!
//! Everything codegen needs is in this module: the word type, the status codes, the workspace slot
//! layout, the constants stored in slots and channel words, the signature of a compiled PROC, the
//! frame-chain protocol and the runtime [`Entry`] points with their signatures
//! ([`crate::entries`] holds their implementations' addresses).
//!
//! # Compiled code
//!
//! Each PROC (and each PAR branch) compiles to a [`ProcFn`]:
//! `extern "C" fn(ws: *mut Word, node: *mut Node) -> Status`. `ws` is the frame's workspace pointer
//! (Wptr); its locals live at non-negative word offsets chosen by the compiler, the runtime's
//! [`slot`]s at negative offsets. Every workspace must reserve [`slot::HEADER_WORDS`] words below
//! Wptr. The function starts by loading `ws[slot::IPTR]` and dispatching on it (`br_table`):
//! index 0 is the entry, every other index a resume point.
//!
//! # Blocking points (the one rule)
//!
//! Before calling any entry marked [`EntrySignature::blocking`], compiled code stores into
//! `ws[slot::IPTR]` the resume index of the code that follows the call ("after-op" index). If the
//! entry returns a non-zero status, the function returns that status at once, without touching the
//! workspace again. (The non-blocking ALT entries also return a `Status`, always `DONE`; their
//! result may be ignored.) All values live across a blocking point must be in the workspace. When the process is
//! resumed, the runtime calls the frame's `ws[slot::CODE]` with the same `ws`, and the function
//! dispatches to the after-op index. Data has already been moved: the second party to a
//! communication copies, so after `rt_in` resumes, the input variable holds the value.
//!
//! # Timeslicing poll
//!
//! At every loop back-edge compiled code loads the `u32` at `node + YIELD_FLAG_OFFSET`; if it is
//! non-zero it stores the resume index of the loop head into `ws[slot::IPTR]` and calls
//! `rt_timeslice`, returning if the status is non-zero. Except when it is [`yield_flag::COUNT`]
//! (timeslicing by count): then it first decrements the `u32` at `node +
//! NODE_POLLS_LEFT_OFFSET`, and goes on to the loop head without a call unless that reached 0.
//!
//! # Frame chain (blocking PROC calls)
//!
//! A PROC call gives the callee a workspace inside the caller's: `callee = ws + k` words, `k` a
//! static offset such that the callee's header and locals fit inside the caller's frame. The
//! caller then, in this order:
//! 1. stores `callee[CODE] = callee fn`, `callee[IPTR] = 0`, `callee[CALLER] = ws`,
//!    `callee[ROOT] = ws[ROOT]`, and the parameters in the callee's locals;
//! 2. stores its own after-call index in `ws[IPTR]`;
//! 3. calls the callee natively; if the result is non-zero it returns it at once.
//!
//! Only the innermost frame ever sits on a channel, queue or timer, so resuming is O(1): the
//! runtime calls the innermost frame. When a resumed frame returns [`Status::DONE`] and its
//! `CALLER` is not null, the runtime calls the caller's `CODE` with the caller's workspace, which
//! dispatches to its after-call index (the `ret` of the T800). A frame whose `CALLER` is null is a
//! process root: `DONE` ends the process.
//!
//! # PAR
//!
//! A PAR of n branches uses a [`join`] block of two words inside the parent's workspace, and n
//! sub-workspaces for the branches. The parent stores `join[PARENT] = 0`, `join[COUNT] = n`, calls
//! `rt_startp` (or `rt_startp_pri` for PRI PAR) once per branch, each branch getting a branch
//! function and the join address in one of its own locals, then stores its after-PAR index and
//! calls `rt_par_wait`. Each branch ends with `return rt_endp(node, ws, join)`. The last branch to
//! end hands the processor straight to the parent (as the T800's `endp`).
//!
//! # ALT
//!
//! `rt_alt` (or `rt_talt` with timer guards); one `rt_enbc`/`rt_enbs`/`rt_enbt` per guard;
//! `rt_altwt` (or `rt_taltwt`, blocking point); one `rt_disc`/`rt_diss`/`rt_dist` per guard in
//! priority order (PRI ALT: textual order), each with the guard's branch number; then `rt_altend`
//! returns the selected branch number, on which the code switches. The selected channel branch
//! then performs an ordinary `rt_in`. Every guard enabled must be disabled.
//!
//! # Extended rendezvous
//!
//! `c ?? x` + P: each communication of the input is `rt_xwait` (blocking: waits for the
//! outputter as a one-guard ALT) then `rt_xin` (takes the data, leaves the outputter descheduled
//! in a workspace word `held`); before the next communication and after P, `rt_xend` releases it.
//!
//! # Emitted code, by example
//!
//! `PROC relay (CHAN INT in?, out!)` = `WHILE TRUE SEQ { in ? x; out ! x }`, locals: 0 = `in`
//! (channel address), 1 = `out`, 2 = `x`:
//!
//! ```text
//! fn relay(ws, node) -> status:
//!   switch ws[IPTR]: 0 -> L0, 1 -> L1, 2 -> L2          ; br_table, default: trap
//! L0: jump HEAD                                          ; entry
//! HEAD:
//!   ws[IPTR] = 1; st = rt_in(node, ws, ws[0], &ws[2], 8); if st != 0: return st
//! L1:
//!   ws[IPTR] = 2; st = rt_out(node, ws, ws[1], &ws[2], 8); if st != 0: return st
//! L2:                                                    ; loop back-edge: the poll
//!   flag = load.u32(node + YIELD_FLAG_OFFSET)
//!   if flag != 0:
//!     if flag == yield_flag::COUNT:
//!       left = load.u32(node + NODE_POLLS_LEFT_OFFSET) - 1; store it back
//!       if left != 0: jump HEAD
//!     ws[IPTR] = 0; st = rt_timeslice(node, ws); if st != 0: return st
//!   jump HEAD
//! ```
//!
//! (Resuming at 0 re-enters the loop head, so the back-edge poll may reuse the entry index when
//! the entry has nothing to initialise.) Rules of thumb:
//! - A frame that contains no blocking point (and calls none) needs no resume indices and may be
//!   called as a plain function; the frame-chain stores are only needed for callees that can block.
//! - Values sent must be in the workspace (a temporary local for an expression): the receiver
//!   copies from the sender's `POINTER` after the sender has returned `BLOCKED`.
//! - PRI PAR: `rt_startp_pri(.., priority::HIGH)` for the first branch, `rt_startp` (inherit) for
//!   the others; at high priority this starts every branch at high priority, as on a T800.
//! - Runtime checks: `return rt_error(node, ws, ErrorKind::X as Word, location)`; STOP is
//!   `ErrorKind::Stop` (the whole node halts, as in KRoC's default halt mode).
//! - TIMER values are microseconds for both priorities (the T800's low-priority clock ticked
//!   every 64 µs; this runtime uses one clock).

use crate::node::Node;

/// One workspace word: 8 bytes, holding an occam INT, a pointer or a tagged process descriptor.
pub type Word = i64;

/// A workspace pointer (Wptr): the address of word 0 of a frame.
pub type Wptr = *mut Word;

/// The signature of every compiled PROC and PAR branch.
///
/// # Safety
/// `ws` must point at word 0 of a workspace with [`slot::HEADER_WORDS`] reserved words below it and
/// the frame's locals above; `node` must be the node that owns the workspace.
pub type ProcFn = unsafe extern "C" fn(ws: Wptr, node: *mut Node) -> Status;

/// What a compiled function or a blocking entry reports to its caller.
///
/// A transparent `i64`, so it crosses the C ABI unchanged. Compiled code only tests it for zero.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Status(pub i64);

impl Status {
    /// The operation completed; the caller carries on.
    pub const DONE: Status = Status(0);
    /// The frame has been descheduled (it sits on a channel, queue, timer or join); return.
    pub const BLOCKED: Status = Status(1);
    /// The node has halted on a runtime error; return.
    pub const HALTED: Status = Status(2);
    /// Compiled code was resumed at an index it does not have (a corrupt `IPTR`): the runtime
    /// reports it as [`crate::RunError::BadStatus`].
    pub const BAD_RESUME: Status = Status(Status::HALTED.0 + 100);
}

/// Bytes in a [`Word`].
pub const WORD_BYTES: i32 = std::mem::size_of::<Word>() as i32;

/// The byte offset of word `w` from a word-aligned address (a workspace slot, a join-block word, a
/// frame word).
pub const fn word_offset(w: isize) -> i32 {
    w as i32 * WORD_BYTES
}

/// Byte offset, from the `node` pointer, of the `u32` timeslice/preemption flag.
pub const YIELD_FLAG_OFFSET: i32 = 0;

/// Byte offset, from the `node` pointer, of the `u32` count of back-edge polls left before the
/// next counted timeslice (see [`yield_flag::COUNT`]).
pub const NODE_POLLS_LEFT_OFFSET: i32 = std::mem::offset_of!(Node, polls_left) as i32;

/// The values of the yield flag at [`YIELD_FLAG_OFFSET`].
pub mod yield_flag {
    /// Nothing to do: the back-edge poll falls through to the loop head.
    pub const CLEAR: u32 = 0;
    /// A timeslice (the shared ticker), a preemption (a high-priority process became ready) or
    /// a stop is requested: the poll calls `rt_timeslice`.
    pub const REQUEST: u32 = 1;
    /// Timeslicing by count, at low priority: the poll decrements the `u32` at
    /// [`super::NODE_POLLS_LEFT_OFFSET`] and calls `rt_timeslice` only when it reaches 0
    /// (every `NodeConfig::counted_slices`-th poll), so that counting costs no call.
    pub const COUNT: u32 = 2;
}

/// Byte offset, from the `node` pointer, of the node's address base (a word): the start of its
/// first workspace chunk. `ASM` blocks see an address as a 32-bit INT, its signed byte offset
/// from this base, so an address stored in an INT and loaded back still works; converting a
/// pointer more than 2 GB from the base is the run-time error
/// [`ErrorKind::AddressRange`](crate::ErrorKind::AddressRange).
pub const ADDR_BASE_OFFSET: i32 =
    (std::mem::offset_of!(Node, arena) + std::mem::offset_of!(crate::arena::Arena, base)) as i32;

/// Byte offset, from the `node` pointer, of two words: the first and one past the last offset
/// from the address base of the node's first workspace chunk. Compiled `ASM` code checks every
/// address it reads or writes through against them, and asks [`Entry::AddrOk`] (the node's
/// other chunks) for one outside them, so a wild address is the run-time error
/// [`ErrorKind::AddressRange`](crate::ErrorKind::AddressRange), never an access outside the
/// node's memory.
pub const ADDR_LIMITS_OFFSET: i32 =
    (std::mem::offset_of!(Node, arena) + std::mem::offset_of!(crate::arena::Arena, limits)) as i32;

/// Byte offsets into the node that compiled code's inline channel fast path reads and writes
/// (see `rt_preempt`): the running priority (a word), the two run queues (`[front, back]` word
/// pairs, high priority first) and the communications counter (a `u64`).
pub const NODE_CUR_PRI_OFFSET: i32 = std::mem::offset_of!(Node, cur_pri) as i32;
/// See [`NODE_CUR_PRI_OFFSET`].
pub const NODE_QUEUES_OFFSET: i32 = std::mem::offset_of!(Node, queues) as i32;
/// Bytes of one run queue in the node's array of queues (indexed by priority).
pub const RUN_QUEUE_BYTES: i32 = std::mem::size_of::<crate::node::Queue>() as i32;
/// Byte offset of a run queue's front (a [`Wptr`], null when empty) inside the queue.
pub const RUN_QUEUE_FRONT: i32 = std::mem::offset_of!(crate::node::Queue, front) as i32;
/// Byte offset of a run queue's back (a [`Wptr`]) inside the queue.
pub const RUN_QUEUE_BACK: i32 = std::mem::offset_of!(crate::node::Queue, back) as i32;
/// See [`NODE_CUR_PRI_OFFSET`].
pub const NODE_COMMUNICATIONS_OFFSET: i32 = (std::mem::offset_of!(Node, stats)
    + std::mem::offset_of!(crate::stats::Stats, communications))
    as i32;

/// Word offsets, from Wptr, of the runtime's slots in every workspace.
///
/// Compatible in spirit with KRoC CCSP (`ccsp_consts.h`): Iptr -1, Link -2, Pointer/State -4,
/// TLink -5, Time -6; the slots below are this runtime's additions.
pub mod slot {
    /// Resume index while descheduled (0 = entry).
    pub const IPTR: isize = -1;
    /// Next frame on a run queue.
    pub const LINK: isize = -2;
    /// The frame's [`super::ProcFn`].
    pub const CODE: isize = -3;
    /// Data pointer while blocked on a channel (alias of [`STATE`]).
    pub const POINTER: isize = -4;
    /// ALT state while ALTing: [`super::alt_state`].
    pub const STATE: isize = -4;
    /// Next frame on a timer queue, or [`super::time_state`] during a timer ALT.
    pub const TLINK: isize = -5;
    /// Time waited for.
    pub const TIME: isize = -6;
    /// Calling frame, or 0 for a process root.
    pub const CALLER: isize = -7;
    /// The process root frame (itself for a root).
    pub const ROOT: isize = -8;
    /// ALT selection (the T800's Temp): the selected branch or [`super::NONE_SELECTED`].
    pub const SELECT: isize = -9;
    /// What the frame waits on, for deadlock reports: see [`super::wait`].
    pub const WAIT: isize = -10;
    /// Root only: the innermost frame at the process's last blocking point.
    pub const INNER: isize = -11;
    /// Root only: previous live process on the node.
    pub const LIVE_PREV: isize = -12;
    /// Root only: next live process on the node.
    pub const LIVE_NEXT: isize = -13;
    /// Words every workspace reserves below Wptr.
    pub const HEADER_WORDS: usize = 13;
}

/// Word offsets, from Wptr, of the fixed words at the bottom of every compiled frame (its locals
/// follow them). Whoever starts an entry PROC sets both to 0.
pub mod frame {
    /// The static link: the lexically enclosing function's frame (0 for an outermost PROC; a PAR
    /// branch's parent frame).
    pub const STATIC_LINK: isize = 0;
    /// The PAR join block's address (PAR branches only; 0 otherwise).
    pub const JOIN: isize = 1;
    /// The fixed words.
    pub const FIXED_WORDS: usize = 2;
    /// Words allocated for an entry PROC's frame beyond the frame size codegen reports (spare).
    pub const ENTRY_SPARE_WORDS: usize = 2;
}

/// Word offsets inside a PAR join block.
pub mod join {
    /// 0 until the parent waits (`rt_par_wait`), then its descriptor (Wptr | priority), resumed
    /// when the count reaches zero.
    pub const PARENT: isize = 0;
    /// Branches still running.
    pub const COUNT: isize = 1;
    /// Size of a join block in words.
    pub const WORDS: usize = 2;
}

/// An empty channel word, an empty queue link.
pub const NOT_PROCESS: Word = 0;

/// Priorities, as stored in bit 0 of a process descriptor.
pub mod priority {
    use super::Word;
    /// High priority (PRI PAR first branch); never timesliced.
    pub const HIGH: Word = 0;
    /// Low priority, the default; timesliced at loop back-edges.
    pub const LOW: Word = 1;
}

/// Tag bits in the low three bits of a channel word (workspaces are 8-byte aligned).
///
/// A channel word is 0 (empty); `Wptr | pri` (a process waits with its data pointer in
/// `POINTER`); `Wptr | TAG_ALT | pri` (an ALTing process has enabled it); or
/// `endpoint | TAG_ENDPOINT` (a link or host endpoint stands behind the channel).
pub mod tag {
    use super::Word;
    /// Bit 0: the waiting process is low priority.
    pub const LOW: Word = 1;
    /// Bit 1: the waiting process is ALTing.
    pub const ALT: Word = 2;
    /// Bit 2: the word points at an endpoint, not a workspace.
    pub const ENDPOINT: Word = 4;
    /// All tag bits.
    pub const MASK: Word = 7;
}

/// Values of the `STATE` slot while ALTing.
pub mod alt_state {
    use super::Word;
    /// Guards are being enabled.
    pub const ENABLING: Word = 1;
    /// Descheduled in `altwt`/`taltwt`.
    pub const WAITING: Word = 2;
    /// At least one guard is ready.
    pub const READY: Word = 3;
}

/// Values of the `TLINK` slot during a timer ALT (any other value: on a timer queue).
pub mod time_state {
    use super::Word;
    /// An enabled timer guard has set `TIME`.
    pub const SET: Word = 1;
    /// No timer guard enabled yet.
    pub const NOT_SET: Word = 2;
}

/// The `SELECT` value before any guard has been selected.
pub const NONE_SELECTED: Word = -1;

/// Values of the `WAIT` slot. A channel address (8-aligned) means blocked on that channel,
/// `| OUTPUT` when outputting.
pub mod wait {
    use super::Word;
    /// Not blocked.
    pub const NOTHING: Word = 0;
    /// Added to a channel address when the frame is outputting.
    pub const OUTPUT: Word = 1;
    /// Waiting in an ALT.
    pub const ALT: Word = 2;
    /// Waiting on a timer.
    pub const TIMER: Word = 3;
    /// Waiting for the branches of a PAR.
    pub const JOIN: Word = 4;
    /// Stopped with `rt_stopp`.
    pub const STOPPED: Word = 5;
}

/// The machine type of an ABI parameter or result (all are `I64` in Cranelift on x86-64).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbiType {
    /// A pointer (node, workspace, channel, data).
    Ptr,
    /// A [`Word`] value.
    Word,
    /// A [`Status`] result.
    Status,
}

/// The signature of one runtime entry point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntrySignature {
    /// Symbol name (codegen declares an import of this name).
    pub name: &'static str,
    /// Parameter types, in order.
    pub params: &'static [AbiType],
    /// Result type.
    pub ret: AbiType,
    /// Whether the entry may deschedule: codegen must store the after-op index first.
    pub blocking: bool,
}

/// States every runtime entry once: its handle, symbol, blocking flag, parameters and result.
macro_rules! entries {
    ($($(#[$doc:meta])* $v:ident = $sym:literal, $blocking:expr, [$($p:ident),*] -> $ret:ident;)*) => {
        /// A runtime entry point that compiled code may call: a typed handle, so that calling an
        /// entry that does not exist is a compile error. [`crate::entries::address`] gives each
        /// one's implementation.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Entry {
            $($(#[$doc])* $v,)*
        }

        impl Entry {
            /// Every entry, in declaration order (`Entry::ALL[e as usize] == e`).
            pub const ALL: &'static [Entry] = &[$(Entry::$v),*];

            /// The entry's signature.
            pub const fn signature(self) -> EntrySignature {
                match self {
                    $(Entry::$v => EntrySignature {
                        name: $sym,
                        params: &[$($p),*],
                        ret: $ret,
                        blocking: $blocking,
                    },)*
                }
            }
        }
    };
}

use AbiType::{Ptr, Status as St, Word as W};

// Parameter names by entry (all start with `node`, and `ws` is the calling frame) are in the
// docs of each variant; `kind` of `rt_error` is an [`crate::ErrorKind`] code and `location` an
// index into [`crate::ProgramInfo::locations`].
entries! {
    /// `rt_in(node, ws, chan, data, len) -> Status`
    In = "rt_in", true, [Ptr, Ptr, Ptr, Ptr, W] -> St;
    /// `rt_out(node, ws, chan, data, len) -> Status`
    Out = "rt_out", true, [Ptr, Ptr, Ptr, Ptr, W] -> St;
    /// `rt_preempt(node, ws) -> Status`
    Preempt = "rt_preempt", true, [Ptr, Ptr] -> St;
    /// `rt_startp(node, ws, child, code, entry) -> Status`
    Startp = "rt_startp", true, [Ptr, Ptr, Ptr, Ptr, W] -> St;
    /// `rt_startp_pri(node, ws, child, code, entry, pri) -> Status`
    StartpPri = "rt_startp_pri", true, [Ptr, Ptr, Ptr, Ptr, W, W] -> St;
    /// `rt_endp(node, ws, join) -> Status`
    Endp = "rt_endp", true, [Ptr, Ptr, Ptr] -> St;
    /// `rt_par_wait(node, ws, join) -> Status`
    ParWait = "rt_par_wait", true, [Ptr, Ptr, Ptr] -> St;
    /// `rt_stopp(node, ws) -> Status`
    Stopp = "rt_stopp", true, [Ptr, Ptr] -> St;
    /// `rt_timeslice(node, ws) -> Status`
    Timeslice = "rt_timeslice", true, [Ptr, Ptr] -> St;
    /// `rt_reschedule(node, ws) -> Status`
    Reschedule = "rt_reschedule", true, [Ptr, Ptr] -> St;
    /// `rt_timer_read(node) -> Word`
    TimerRead = "rt_timer_read", false, [Ptr] -> W;
    /// `rt_tin(node, ws, time) -> Status`
    Tin = "rt_tin", true, [Ptr, Ptr, W] -> St;
    /// `rt_alt(node, ws) -> Status`
    Alt = "rt_alt", false, [Ptr, Ptr] -> St;
    /// `rt_talt(node, ws) -> Status`
    Talt = "rt_talt", false, [Ptr, Ptr] -> St;
    /// `rt_enbc(node, ws, guard, chan) -> Status`
    Enbc = "rt_enbc", false, [Ptr, Ptr, W, Ptr] -> St;
    /// `rt_enbs(node, ws, guard) -> Status`
    Enbs = "rt_enbs", false, [Ptr, Ptr, W] -> St;
    /// `rt_enbt(node, ws, guard, time) -> Status`
    Enbt = "rt_enbt", false, [Ptr, Ptr, W, W] -> St;
    /// `rt_altwt(node, ws) -> Status`
    Altwt = "rt_altwt", true, [Ptr, Ptr] -> St;
    /// `rt_taltwt(node, ws) -> Status`
    Taltwt = "rt_taltwt", true, [Ptr, Ptr] -> St;
    /// `rt_disc(node, ws, guard, chan, branch) -> Word`
    Disc = "rt_disc", false, [Ptr, Ptr, W, Ptr, W] -> W;
    /// `rt_diss(node, ws, guard, branch) -> Word`
    Diss = "rt_diss", false, [Ptr, Ptr, W, W] -> W;
    /// `rt_dist(node, ws, guard, time, branch) -> Word`
    Dist = "rt_dist", false, [Ptr, Ptr, W, W, W] -> W;
    /// `rt_altend(node, ws) -> Word`
    Altend = "rt_altend", false, [Ptr, Ptr] -> W;
    /// `rt_error(node, ws, kind, location) -> Status`
    Error = "rt_error", true, [Ptr, Ptr, W, W] -> St;
    /// `rt_placement(node, ws) -> Word`
    Placement = "rt_placement", false, [Ptr, Ptr] -> W;
    /// `rt_xwait(node, ws, chan) -> Status`
    Xwait = "rt_xwait", true, [Ptr, Ptr, Ptr] -> St;
    /// `rt_xin(node, ws, chan, data, len, held) -> Status`
    Xin = "rt_xin", true, [Ptr, Ptr, Ptr, Ptr, W, Ptr] -> St;
    /// `rt_xend(node, ws, held) -> Status`
    Xend = "rt_xend", true, [Ptr, Ptr, Ptr] -> St;
    /// `rt_addr_ok(node, offset, bytes) -> Word`: 1 when the `bytes` at `offset` from the
    /// node's address base lie in one of its workspace chunks, else 0 (the check an `ASM`
    /// address outside [`ADDR_LIMITS_OFFSET`]'s first chunk falls back to).
    AddrOk = "rt_addr_ok", false, [Ptr, W, W] -> W;
    /// `rt_vector_get(node, ws, bytes, at, location) -> Status`: takes `bytes` for a large
    /// array from the node's memory and stores their address at `at`; when the budget has not
    /// that much left, halts the node with [`crate::ErrorKind::Memory`] at `location`.
    VectorGet = "rt_vector_get", true, [Ptr, Ptr, W, Ptr, W] -> St;
    /// `rt_vector_free(node, address, bytes) -> Word`: gives back what `rt_vector_get` took for
    /// `bytes` at `address`; returns 0.
    VectorFree = "rt_vector_free", false, [Ptr, Ptr, W] -> W;
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn entries_are_consistent() {
        for (i, e) in Entry::ALL.iter().enumerate() {
            assert_eq!(Entry::ALL[*e as usize], *e);
            let s = e.signature();
            assert!(s.name.starts_with("rt_"), "{}", s.name);
            assert!(
                Entry::ALL[..i].iter().all(|o| o.signature().name != s.name),
                "duplicate {}",
                s.name
            );
            assert!(s.params.len() <= 6, "{} has too many parameters", s.name);
            assert_eq!(
                s.params[0],
                AbiType::Ptr,
                "{}: the node comes first",
                s.name
            );
            if s.blocking {
                assert_eq!(
                    s.ret,
                    AbiType::Status,
                    "{} blocks: it returns a Status",
                    s.name
                );
            }
        }
        assert_eq!(Entry::In.signature().params.len(), 5);
    }

    #[test]
    fn layout_constants_match_the_types() {
        assert_eq!(WORD_BYTES as usize, std::mem::size_of::<Word>());
        assert_eq!(word_offset(slot::LINK), -2 * WORD_BYTES);
        assert_eq!(RUN_QUEUE_BYTES, 2 * WORD_BYTES);
        assert_eq!(
            (RUN_QUEUE_FRONT, RUN_QUEUE_BACK),
            (0, WORD_BYTES),
            "a run queue is [front, back]"
        );
        assert!(![Status::DONE, Status::BLOCKED, Status::HALTED].contains(&Status::BAD_RESUME));
    }

    #[test]
    fn slots_are_distinct_and_inside_the_header() {
        let all = [
            slot::IPTR,
            slot::LINK,
            slot::CODE,
            slot::STATE,
            slot::TLINK,
            slot::TIME,
            slot::CALLER,
            slot::ROOT,
            slot::SELECT,
            slot::WAIT,
            slot::INNER,
            slot::LIVE_PREV,
            slot::LIVE_NEXT,
        ];
        for (i, s) in all.iter().enumerate() {
            assert!(*s < 0 && -*s <= slot::HEADER_WORDS as isize);
            assert!(!all[..i].contains(s));
        }
        assert_eq!(slot::POINTER, slot::STATE);
    }
}
