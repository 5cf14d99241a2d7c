//! Runtime errors, STOP, and the errors [`crate::Node::run`] returns.
//!
//! Compiled code halts the node with `return rt_error(node, ws, kind, location)`: `kind` is an
//! [`ErrorKind`] code and `location` an index into [`crate::ProgramInfo::locations`]. The node stops
//! at once (no other process runs) and `run` returns [`RunError::Halted`] naming file, line, kind
//! and PROC.

use std::fmt;

use crate::abi::{Status, Word, Wptr, slot};
use crate::deadlock::DeadlockReport;
use crate::frame::get;
use crate::node::Node;
use crate::program::SourceLoc;

/// The kind of a runtime error; the `u32` code is what compiled code passes to `rt_error`.
#[non_exhaustive]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum ErrorKind {
    /// Occurs when a STOP process is executed.
    Stop = 0,
    /// Occurs when no condition of an IF is true.
    IfNoBranch = 1,
    /// Occurs when no option of a CASE matches and there is no ELSE.
    CaseNoMatch = 2,
    /// Occurs when an array subscript is outside the array.
    Subscript = 3,
    /// Occurs when a segment `[a FROM i FOR n]` is not inside the array.
    Segment = 4,
    /// Occurs when a conversion's value does not fit the target type.
    Conversion = 5,
    /// Occurs when `+ - * /` or a negation overflows.
    Overflow = 6,
    /// Occurs when dividing (`/` or `\`) by zero.
    DivideByZero = 7,
    /// Occurs when a shift count is negative or larger than the word.
    Shift = 8,
    /// Occurs when an ASSERT's condition is false.
    Assert = 9,
    /// Occurs when a message's length does not match the input's (counted arrays, links).
    MessageLength = 10,
    /// Occurs when a host or intrinsic operation fails (for example writing stdout).
    Host = 11,
    /// Occurs on every other node of a network when one node halts: the network stops.
    Stopped = 12,
    /// Occurs when a REAL division has a zero divisor (occam's REAL arithmetic is checked).
    Floating = 13,
    /// Occurs when a replicator's count is negative.
    ReplicatorCount = 14,
    /// Occurs when an `ASM` block takes the address of memory more than 2 GB from the node's
    /// address base, which an INT (32 bits) cannot hold (see [`crate::abi::ADDR_BASE_OFFSET`]),
    /// or reads or writes through an address outside the node's memory.
    AddressRange = 15,
    /// Occurs when a large array's declaration (a vector, taken from the node's memory as the
    /// declaration runs) needs more than the node's memory budget has left.
    Memory = 16,
}

impl ErrorKind {
    /// The kind with code `code`.
    pub fn from_code(code: Word) -> Option<ErrorKind> {
        use ErrorKind::*;
        const ALL: [ErrorKind; 17] = [
            Stop,
            IfNoBranch,
            CaseNoMatch,
            Subscript,
            Segment,
            Conversion,
            Overflow,
            DivideByZero,
            Shift,
            Assert,
            MessageLength,
            Host,
            Stopped,
            Floating,
            ReplicatorCount,
            AddressRange,
            Memory,
        ];
        usize::try_from(code).ok().and_then(|i| ALL.get(i).copied())
    }

    /// A short description, used in messages. It contains the word the test corpus names the
    /// kind by (`stop`, `bounds`, `conversion`, `overflow`, `division`, `assert`): an IF or CASE
    /// with no way through is a STOP, as in KRoC.
    pub fn describe(self) -> &'static str {
        match self {
            ErrorKind::Stop => "STOP executed",
            ErrorKind::IfNoBranch => "STOP: no condition of IF is true",
            ErrorKind::CaseNoMatch => "STOP: no option of CASE matches",
            ErrorKind::Subscript => "array subscript out of bounds",
            ErrorKind::Segment => "array segment out of bounds",
            ErrorKind::Conversion => "conversion out of range",
            ErrorKind::Overflow => "arithmetic overflow",
            ErrorKind::DivideByZero => "division by zero",
            ErrorKind::Shift => "shift count out of range",
            ErrorKind::Assert => "ASSERT failed",
            ErrorKind::MessageLength => "message length mismatch",
            ErrorKind::Host => "host I/O failed",
            ErrorKind::Stopped => "stopped because another node of the network failed",
            ErrorKind::Floating => "floating-point error: REAL division by zero",
            ErrorKind::ReplicatorCount => "negative replicator count",
            ErrorKind::AddressRange => "ASM address out of range: outside the node's memory",
            ErrorKind::Memory => {
                "out of memory: an array's declaration needs more than the node's memory budget \
                 has left"
            }
        }
    }
}

/// A node halted by a runtime error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Halt {
    /// What went wrong (`None` for an unknown code).
    pub kind: Option<ErrorKind>,
    /// The raw kind code passed to `rt_error`.
    pub code: Word,
    /// Where, if the location index was registered.
    pub location: Option<SourceLoc>,
    /// In which PROC, if its code was registered.
    pub proc_name: Option<String>,
    /// What the kind alone does not say (how much memory was asked for and left).
    pub detail: Option<String>,
}

impl fmt::Display for Halt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(loc) = &self.location {
            write!(f, "{}:{}: ", loc.file, loc.line)?;
        }
        match self.kind {
            Some(k) => write!(f, "runtime error: {}", k.describe())?,
            None => write!(f, "runtime error: unknown kind {}", self.code)?,
        }
        if let Some(d) = &self.detail {
            write!(f, ": {d}")?;
        }
        if let Some(p) = &self.proc_name {
            write!(f, " (in PROC {p})")?;
        }
        Ok(())
    }
}

/// Why [`crate::Node::run`] did not finish normally.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Occurs when compiled code calls `rt_error` (a run-time check failed, or STOP).
    #[error("{0}")]
    Halted(Halt),
    /// Occurs when processes remain but none can run and nothing (timer, link) can wake one.
    #[error("{0}")]
    Deadlock(DeadlockReport),
    /// Occurs when a workspace allocation would exceed the node's memory budget.
    #[error(
        "out of memory: {requested} bytes of workspace requested, over the node's budget of {budget} bytes"
    )]
    OutOfMemory {
        /// Bytes asked for.
        requested: usize,
        /// The node's budget.
        budget: usize,
    },
    /// Occurs when compiled code returns a status other than DONE, BLOCKED or HALTED.
    #[error("compiled code returned invalid status {0}")]
    BadStatus(i64),
    /// Occurs when host output cannot be written or flushed.
    #[error("host I/O: {0}")]
    HostIo(#[from] std::io::Error),
    /// The error of a node that ran in another process (an MPI rank), as that process
    /// reported it.
    #[error("{0}")]
    Remote(String),
}

impl Node {
    /// Builds the error for a halted node.
    pub(crate) fn halt_error(&mut self) -> RunError {
        match self.halt.take() {
            Some(h) => RunError::Halted(h),
            None => RunError::BadStatus(Status::HALTED.0),
        }
    }
}

/// Halts the node with error `kind` (an [`ErrorKind`] code) at `location` (an index into
/// [`crate::ProgramInfo::locations`]). Returns `HALTED`; compiled code returns it.
///
/// # Safety
/// `node` is the running node, `ws` the calling frame.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_error(node: *mut Node, ws: Wptr, kind: Word, location: Word) -> Status {
    // SAFETY: caller contract.
    let node = unsafe { &mut *node };
    // SAFETY: `ws` is a live frame whose CODE slot holds its function.
    let code = unsafe { get(ws, slot::CODE) } as usize;
    let program = node.program.clone();
    node.halt = Some(Halt {
        kind: ErrorKind::from_code(kind),
        code: kind,
        location: u32::try_from(location)
            .ok()
            .and_then(|l| program.location(l))
            .cloned(),
        proc_name: program.proc_by_code(code).map(|p| p.name.clone()),
        detail: None,
    });
    Status::HALTED
}
