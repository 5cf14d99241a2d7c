//! A node: one simulated transputer with its own scheduler, timers, memory and statistics.
//!
//! There is no global scheduler state: every entry point receives the node it runs on, so many
//! nodes can live in one OS process, each run by one thread at a time ([`Node`] is `Send`).

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use crate::abi::{NOT_PROCESS, ProcFn, Word, Wptr, priority, slot, yield_flag};
use crate::arena::Arena;
use crate::endpoint::Endpoint;
use crate::error::{Halt, RunError};
use crate::frame::set;
use crate::host::HostIo;
use crate::link::NetState;
use crate::mailbox::Mailbox;
use crate::program::ProgramInfo;
use crate::stats::Stats;

/// Settings of one node.
#[derive(Clone, Debug)]
pub struct NodeConfig {
    /// Bytes of workspace the node may allocate (like a transputer's few megabytes of RAM).
    pub memory_budget: usize,
    /// Whether low-priority processes are timesliced (a shared 1 ms ticker sets the yield flag).
    pub timeslice: bool,
    /// Timeslice by count instead of by clock: every this many loop back-edges of a
    /// low-priority process is a timeslice, so runs repeat exactly (`occ run --threads 1`).
    /// Takes precedence over `timeslice`.
    pub counted_slices: Option<u32>,
    /// The node's name in reports (`node 3`); empty for a lone node.
    pub name: String,
}

impl NodeConfig {
    /// The low-priority back-edge polls between two counted timeslices (at least 1).
    pub(crate) fn polls_per_slice(&self) -> u32 {
        self.counted_slices.unwrap_or(1).max(1)
    }
}

impl Default for NodeConfig {
    /// 256 MB of workspace, timeslicing on.
    fn default() -> Self {
        NodeConfig {
            memory_budget: 256 << 20,
            timeslice: true,
            counted_slices: None,
            name: String::new(),
        }
    }
}

/// A FIFO run queue linked through the `LINK` slot.
#[repr(C)]
#[derive(Debug)]
pub(crate) struct Queue {
    pub(crate) front: Wptr,
    pub(crate) back: Wptr,
}

/// One simulated transputer. Always boxed: compiled code holds its address while it runs.
#[repr(C)]
pub struct Node {
    /// Timeslice / preemption flag polled by compiled code at [`crate::abi::YIELD_FLAG_OFFSET`].
    pub(crate) yield_flag: AtomicU32,
    /// The yield flag's resting value at low priority: [`yield_flag::CLEAR`], or
    /// [`yield_flag::COUNT`] when timeslicing by count, so that every back-edge poll counts
    /// down `polls_left`. Kept beside the flag (read at every switch to low priority) rather
    /// than derived from the config each time.
    pub(crate) flag_rest: u32,
    /// When timeslicing by count: the low-priority back-edge polls left before the next
    /// counted timeslice, counted down by compiled code at
    /// [`crate::abi::NODE_POLLS_LEFT_OFFSET`] (and by `rt_timeslice` for a poll that a
    /// request sent there instead); never 0 between polls.
    pub(crate) polls_left: u32,
    /// Priority of the running process.
    pub(crate) cur_pri: Word,
    /// Run queues, indexed by priority.
    pub(crate) queues: [Queue; 2],
    /// The preempted low-priority frame, resumed before the low queue.
    pub(crate) interrupted: Wptr,
    /// A descriptor to run next, before any queue (the last `endp` continuing as the parent).
    pub(crate) handoff: Word,
    /// Timer queue heads, indexed by priority, linked through `TLINK`, sorted by `TIME`.
    pub(crate) timers: [Wptr; 2],
    /// Live process roots, linked through `LIVE_NEXT`/`LIVE_PREV`.
    pub(crate) live: Wptr,
    pub(crate) stats: Stats,
    pub(crate) halt: Option<Halt>,
    pub(crate) epoch: Instant,
    pub(crate) arena: Arena,
    pub(crate) program: Arc<ProgramInfo>,
    pub(crate) host: HostIo,
    /// Endpoints; boxed because channel words hold their addresses.
    #[allow(
        clippy::vec_box,
        reason = "endpoint addresses must not move when the Vec grows"
    )]
    pub(crate) endpoints: Vec<Box<Endpoint>>,
    /// Frames blocked on a link, to be woken through the mailbox.
    pub(crate) link_waiters: usize,
    pub(crate) mailbox: Arc<Mailbox>,
    /// The network this node belongs to, if linked.
    pub(crate) net: Option<Arc<NetState>>,
    /// Whether this node already counts as idle for good in its network.
    pub(crate) net_finished: bool,
    pub(crate) config: NodeConfig,
    /// What the program's `PLACED PAR` binds on this node (see [`crate::placement`]).
    pub(crate) placement: Option<crate::placement::Placement>,
    /// Timeslices taken since the node last had its turn on a pool thread.
    pub(crate) slices: u32,
    /// Set by a timeslice when the node has had its turn: the pool gives the thread to another.
    pub(crate) give_way: bool,
    /// Whether a thread pool runs the node (so it gives way after [`crate::pool::TURN_SLICES`]).
    pub(crate) pooled: bool,
    /// Time spent running processes (the pool measures each turn).
    pub(crate) busy: std::time::Duration,
}

// SAFETY: a Node's raw pointers all point into its own arena or into workspaces it owns; they are
// only dereferenced by the thread currently running the node. Cross-node traffic goes through
// the lock-free mailbox and the link state (a Mutex).
unsafe impl Send for Node {}

impl Node {
    /// Creates a node with the given settings, program tables (for error and deadlock reports)
    /// and host I/O.
    pub fn new(config: NodeConfig, program: Arc<ProgramInfo>, host: HostIo) -> Box<Node> {
        Box::new(Node {
            yield_flag: AtomicU32::new(yield_flag::CLEAR),
            flag_rest: match config.counted_slices {
                Some(_) => yield_flag::COUNT,
                None => yield_flag::CLEAR,
            },
            polls_left: config.polls_per_slice(),
            cur_pri: priority::LOW,
            queues: [Queue::empty(), Queue::empty()],
            interrupted: std::ptr::null_mut(),
            handoff: NOT_PROCESS,
            timers: [std::ptr::null_mut(); 2],
            live: std::ptr::null_mut(),
            stats: Stats::default(),
            halt: None,
            epoch: Instant::now(),
            arena: Arena::new(config.memory_budget),
            program,
            host,
            endpoints: Vec::new(),
            link_waiters: 0,
            mailbox: Arc::new(Mailbox::default()),
            net: None,
            net_finished: false,
            config,
            placement: None,
            slices: 0,
            give_way: false,
            pooled: false,
            busy: std::time::Duration::ZERO,
        })
    }

    /// Creates a node with default settings, empty program tables and the process's own
    /// stdin/stdout/stderr.
    pub fn with_defaults() -> Box<Node> {
        Node::new(
            NodeConfig::default(),
            Arc::new(ProgramInfo::default()),
            HostIo::stdio(),
        )
    }

    /// Allocates a workspace of `words` words above Wptr (plus the header) from the node's arena.
    ///
    /// Fails with [`RunError::OutOfMemory`] when the budget would be exceeded.
    pub fn alloc_workspace(&mut self, words: usize) -> Result<Wptr, RunError> {
        let ws = self.arena.alloc(words)?;
        self.stats.peak_workspace_bytes = self.arena.peak_bytes();
        Ok(ws)
    }

    /// Returns a workspace from [`Node::alloc_workspace`] (with the same `words`) to the arena.
    ///
    /// # Safety
    /// `ws` must come from this node's `alloc_workspace(words)` and no process may still use it.
    pub unsafe fn free_workspace(&mut self, ws: Wptr, words: usize) {
        // SAFETY: forwarded contract.
        unsafe { self.arena.free(ws, words) }
    }

    /// Makes `ws` a new low-priority process root running `code` from resume index 0.
    ///
    /// # Safety
    /// `ws` must be a workspace with the header reserved below it, large enough for `code`'s
    /// frame, that stays valid until the process ends.
    pub unsafe fn spawn(&mut self, ws: Wptr, code: ProcFn) {
        // SAFETY: forwarded contract.
        unsafe { self.start_root(ws, code, 0, priority::LOW) }
    }

    /// Allocates a workspace of `words` locals, stores `params` in its first locals (for the main
    /// PROC: its parameters, for example the addresses from [`Node::host_channels`]), and spawns
    /// `code` there as a low-priority process. Returns the workspace.
    ///
    /// # Safety
    /// `code` must be a [`ProcFn`] whose frame (including every sub-workspace) fits in `words`
    /// locals and whose parameters are `params`.
    pub unsafe fn launch(
        &mut self,
        code: ProcFn,
        words: usize,
        params: &[Word],
    ) -> Result<Wptr, RunError> {
        let ws = self.alloc_workspace(words.max(params.len()))?;
        // SAFETY: a fresh workspace with at least `params.len()` locals; caller contract for code.
        unsafe {
            for (i, p) in params.iter().enumerate() {
                *ws.add(i) = *p;
            }
            self.spawn(ws, code);
        }
        Ok(ws)
    }

    /// Makes `ws` a process root at `entry` with priority `pri` and puts it on the run queue.
    ///
    /// # Safety
    /// As for [`Node::spawn`].
    pub(crate) unsafe fn start_root(&mut self, ws: Wptr, code: ProcFn, entry: Word, pri: Word) {
        // SAFETY: the caller guarantees `ws` has a reserved header.
        unsafe {
            set(ws, slot::IPTR, entry);
            set(ws, slot::CODE, code as usize as Word);
            set(ws, slot::CALLER, 0);
            set(ws, slot::ROOT, ws as Word);
            set(ws, slot::INNER, ws as Word);
            set(ws, slot::WAIT, 0);
            self.live_insert(ws);
            self.stats.processes_started += 1;
            self.schedule(ws as Word | pri);
        }
    }

    /// Runs the node until every process has ended (`Ok`), a runtime error halts it, or it
    /// deadlocks. Host output is flushed in every case.
    pub fn run(&mut self) -> Result<(), RunError> {
        let ticket = self
            .clock_slices()
            .then(|| crate::ticker::register(&self.yield_flag));
        let result = self.run_loop();
        self.withdraw_keyboard();
        if let Err(RunError::Halted(h)) = &result
            && h.kind != Some(crate::ErrorKind::Stopped)
        {
            self.stop_network();
        }
        drop(ticket);
        self.leave_network();
        let flushed = self.host.flush();
        result?;
        flushed
    }

    /// The node's counters.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// The node's settings.
    pub fn config(&self) -> &NodeConfig {
        &self.config
    }

    /// Time spent running processes while a thread pool ran the node.
    pub fn busy(&self) -> std::time::Duration {
        self.busy
    }

    /// Whether the shared clock ticker timeslices this node.
    pub(crate) fn clock_slices(&self) -> bool {
        self.config.timeslice && self.config.counted_slices.is_none()
    }

    /// The yield flag's resting value at the running priority: [`yield_flag::CLEAR`] at high
    /// priority (never timesliced, and its polls are not counted), else the `flag_rest` field.
    #[inline(always)]
    pub(crate) fn flag_rest(&self) -> u32 {
        if self.cur_pri == priority::HIGH {
            yield_flag::CLEAR
        } else {
            self.flag_rest
        }
    }

    /// The program tables used in reports.
    pub fn program(&self) -> &Arc<ProgramInfo> {
        &self.program
    }

    /// Address of the yield flag (equal to `node + YIELD_FLAG_OFFSET`).
    pub fn yield_flag_ptr(&self) -> *const u32 {
        self.yield_flag.as_ptr()
    }

    /// Sets the yield flag, as the ticker does (for tests and embedders).
    pub fn request_yield(&self) {
        self.yield_flag
            .store(yield_flag::REQUEST, Ordering::Relaxed);
    }
}

impl Drop for Node {
    /// A node dropped without running still counts as stopped in its network, so that its
    /// peers can detect a deadlock instead of waiting for it.
    fn drop(&mut self) {
        self.withdraw_keyboard();
        self.leave_network();
    }
}

impl Queue {
    const fn empty() -> Queue {
        Queue {
            front: std::ptr::null_mut(),
            back: std::ptr::null_mut(),
        }
    }
}
