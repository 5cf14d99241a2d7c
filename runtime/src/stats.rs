//! Per-node counters, printed by `occ run --stats`.

use std::fmt;

/// Counters of one node.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Processes started (roots: the main process and every PAR branch).
    pub processes_started: u64,
    /// Frames taken from a run queue or the interrupted slot to run.
    pub context_switches: u64,
    /// Completed channel communications.
    pub communications: u64,
    /// High-water mark of workspace bytes allocated from the node's arena.
    pub peak_workspace_bytes: u64,
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "processes started:     {}", self.processes_started)?;
        writeln!(f, "context switches:      {}", self.context_switches)?;
        writeln!(f, "communications:        {}", self.communications)?;
        write!(f, "peak workspace bytes:  {}", self.peak_workspace_bytes)
    }
}
