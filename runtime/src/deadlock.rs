//! Deadlock reports: when nothing is runnable, no timer is pending and no link can still move,
//! every live process is blocked for good. The report lists each one: its PROC, the source line
//! of the blocking point, and what it waits on (a channel, by name when registered; an ALT; a PAR
//! join; a timer; STOP).
//!
//! Finding the blocked processes costs nothing while running: each process root is on the node's
//! live list, and every blocking entry records the blocked frame in its root's `INNER` slot and
//! what it waits on in the frame's `WAIT` slot.

use std::fmt;

use crate::abi::{Word, Wptr, slot, tag, wait};
use crate::frame::get;
use crate::node::Node;
use crate::program::{ProgramInfo, SourceLoc};

/// What a blocked process waits on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum WaitsOn {
    /// Inputting from a channel (its name, if registered).
    Input(Option<String>),
    /// Outputting to a channel (its name, if registered).
    Output(Option<String>),
    /// An ALT with no ready guard.
    Alt,
    /// A timer (cannot be deadlocked, listed for completeness in network reports).
    Timer,
    /// The branches of a PAR.
    ParJoin,
    /// Stopped for good.
    Stopped,
}

/// One blocked process.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockedProcess {
    /// The PROC of the blocked (innermost) frame, if registered.
    pub proc_name: Option<String>,
    /// The source location of its blocking point, if registered.
    pub location: Option<SourceLoc>,
    /// What it waits on.
    pub waits_on: WaitsOn,
}

/// All processes of a deadlocked node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeadlockReport {
    /// The blocked processes, most recently started first.
    pub blocked: Vec<BlockedProcess>,
}

impl fmt::Display for WaitsOn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = |n: &Option<String>| n.clone().unwrap_or_else(|| "(unnamed)".into());
        match self {
            WaitsOn::Input(n) => write!(f, "input from channel {}", name(n)),
            WaitsOn::Output(n) => write!(f, "output to channel {}", name(n)),
            WaitsOn::Alt => write!(f, "ALT"),
            WaitsOn::Timer => write!(f, "timer"),
            WaitsOn::ParJoin => write!(f, "PAR join"),
            WaitsOn::Stopped => write!(f, "stopped"),
        }
    }
}

impl fmt::Display for DeadlockReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "deadlock: {} process(es) blocked", self.blocked.len())?;
        for b in &self.blocked {
            write!(f, "\n  ")?;
            match &b.location {
                Some(l) => write!(f, "{}:{}: ", l.file, l.line)?,
                None => write!(f, "?: ")?,
            }
            match &b.proc_name {
                Some(p) => write!(f, "PROC {p}")?,
                None => write!(f, "PROC ?")?,
            }
            write!(f, " blocked on {}", b.waits_on)?;
        }
        Ok(())
    }
}

impl Node {
    /// Builds the report from the live list.
    pub(crate) fn deadlock_report(&self) -> DeadlockReport {
        let frames = self.blocked_frames();
        let all: Vec<Wptr> = frames.iter().flat_map(|f| frame_chain(*f)).collect();
        let blocked = frames
            .iter()
            .map(|&f| describe(&self.program, f, &all))
            .collect();
        DeadlockReport { blocked }
    }

    /// The innermost frame of every live process.
    fn blocked_frames(&self) -> Vec<Wptr> {
        let mut out = Vec::new();
        let mut root = self.live;
        while !root.is_null() {
            // SAFETY: live-list roots are live workspaces; INNER is one of their frames.
            unsafe {
                out.push(get(root, slot::INNER) as Wptr);
                root = get(root, slot::LIVE_NEXT) as Wptr;
            }
        }
        out
    }
}

/// `frame` and its callers up to the root.
fn frame_chain(mut frame: Wptr) -> Vec<Wptr> {
    let mut out = Vec::new();
    while !frame.is_null() {
        out.push(frame);
        // SAFETY: CALLER links point at live frames (frame-chain protocol).
        frame = unsafe { get(frame, slot::CALLER) } as Wptr;
    }
    out
}

fn describe(program: &ProgramInfo, frame: Wptr, all: &[Wptr]) -> BlockedProcess {
    // SAFETY: `frame` is a live blocked frame.
    let (code, iptr, what) = unsafe {
        (
            get(frame, slot::CODE) as usize,
            get(frame, slot::IPTR),
            get(frame, slot::WAIT),
        )
    };
    BlockedProcess {
        proc_name: program.proc_by_code(code).map(|p| p.name.clone()),
        location: program.resume_location(code, iptr).cloned(),
        waits_on: waits_on(program, what, all),
    }
}

fn waits_on(program: &ProgramInfo, what: Word, all: &[Wptr]) -> WaitsOn {
    match what {
        wait::ALT => WaitsOn::Alt,
        wait::TIMER => WaitsOn::Timer,
        wait::JOIN => WaitsOn::ParJoin,
        wait::STOPPED | wait::NOTHING => WaitsOn::Stopped,
        _ => {
            let chan = what & !tag::MASK;
            // SAFETY: a WAIT slot holding an address holds a live channel word's address.
            let word = unsafe { *(chan as *const Word) };
            let name = if word & tag::ENDPOINT != 0 {
                // SAFETY: ENDPOINT words point at this node's endpoints.
                Some(unsafe { crate::endpoint::endpoint_name(word) })
            } else {
                channel_name(program, chan, all)
            };
            if what & wait::OUTPUT != 0 {
                WaitsOn::Output(name)
            } else {
                WaitsOn::Input(name)
            }
        }
    }
}

/// The registered name of the channel word at address `chan`, searched in the workspaces of
/// `frames`.
pub(crate) fn channel_name(program: &ProgramInfo, chan: Word, frames: &[Wptr]) -> Option<String> {
    for &f in frames {
        // SAFETY: `f` is a live frame.
        let code = unsafe { get(f, slot::CODE) } as usize;
        let Some(info) = program.proc_by_code(code) else {
            continue;
        };
        for c in &info.channels {
            let first = f as Word + c.offset * 8;
            let index = (chan - first) / 8;
            if chan >= first && index < c.count as Word {
                return Some(match c.count {
                    1 => c.name.clone(),
                    _ => format!("{}[{}]", c.name, index),
                });
            }
        }
    }
    None
}
