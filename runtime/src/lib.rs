//! The process machine: T800-style workspaces, run queues, one-word channels, ALT, timers, PAR,
//! runtime errors and deadlock detection; nodes, links and network transports.
//!
//! Compiled occam (from `occ-codegen`) is a set of [`abi::ProcFn`]s that call the runtime's
//! [`abi::Entry`] points ([`entries`] gives their addresses); [`abi`] states the whole contract. A [`Node`] runs them: its scheduler
//! ([`sched`]), channels ([`chan`]), ALT ([`alt`]), timers ([`timer`]), PAR ([`par`]), errors
//! ([`error`]) and deadlock reports ([`deadlock`]). Nodes own all their state, so many run in one
//! OS process; [`Network`] joins them with links, and [`Network::run_all`] (one thread per node)
//! or [`Network::run_pool`] (a few threads for many nodes) runs them.
//!
//! # What codegen registers
//!
//! [`ProgramInfo`] (shared by every node running the program) makes reports readable at no run-time
//! cost: `locations` (the `location` argument of `rt_error` indexes it), and per compiled function
//! a [`CodeInfo`] with its PROC name, its address, the location of each resume index (deadlock
//! reports show where a process is blocked) and the channels declared in its workspace (deadlock
//! reports name the channel a process waits on, found in the frames of the blocked processes and
//! their callers).
//!
//! # Running a compiled program
//!
//! ```text
//! let mut node = Node::new(NodeConfig::default(), program_info, HostIo::stdio());
//! let [keyboard, screen, error] = node.host_channels();
//! unsafe { node.launch(main_proc, main_frame_words, &[keyboard as Word, screen as Word, error as Word])? };
//! node.run()?;                       // Err: RunError::Halted / Deadlock / OutOfMemory / ...
//! eprintln!("{}", node.stats());     // occ run --stats
//! ```
//!
//! # Example
//!
//! A process written by hand in the shape codegen emits: it outputs one byte on `screen`.
//!
//! ```
//! use occ_runtime::abi::{slot, Status, Word, Wptr};
//! use occ_runtime::{chan::rt_out, HostIo, Node, NodeConfig, ProgramInfo};
//! use std::sync::{Arc, Mutex};
//!
//! // locals: [0] = screen channel address, [1] = the byte to send
//! unsafe extern "C" fn hello(ws: Wptr, node: *mut Node) -> Status {
//!     unsafe {
//!         match *ws.offset(slot::IPTR) {
//!             0 => {
//!                 *ws.add(1) = b'!' as Word;
//!                 *ws.offset(slot::IPTR) = 1; // after-op index
//!                 let st = rt_out(node, ws, *ws as *mut Word, ws.add(1).cast(), 1);
//!                 if st != Status::DONE { return st; }
//!                 Status::DONE
//!             }
//!             _ => Status::DONE,
//!         }
//!     }
//! }
//!
//! #[derive(Clone, Default)]
//! struct Buf(Arc<Mutex<Vec<u8>>>);
//! impl std::io::Write for Buf {
//!     fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
//!         self.0.lock().unwrap().extend_from_slice(b);
//!         Ok(b.len())
//!     }
//!     fn flush(&mut self) -> std::io::Result<()> { Ok(()) }
//! }
//!
//! let out = Buf::default();
//! let host = HostIo::new(Box::new(std::io::empty()), Box::new(out.clone()), Box::new(std::io::sink()));
//! let mut node = Node::new(NodeConfig::default(), Arc::new(ProgramInfo::default()), host);
//! let [_, screen, _] = node.host_channels();
//! let ws = node.alloc_workspace(2).unwrap();
//! unsafe {
//!     *ws = screen as Word;
//!     node.spawn(ws, hello);
//! }
//! node.run().unwrap();
//! assert_eq!(out.0.lock().unwrap().as_slice(), b"!");
//! ```

#![deny(missing_docs)]

pub mod abi;
pub mod alt;
mod arena;
pub mod chan;
pub mod deadlock;
mod endpoint;
pub mod entries;
pub mod error;
mod frame;
pub mod host;
pub mod intrinsic;
mod keyboard;
pub mod link;
mod mailbox;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod native;
pub mod node;
pub mod par;
pub mod placement;
mod pool;
pub mod program;
pub mod remote;
pub mod sched;
pub mod stats;
mod terminal;
mod ticker;
pub mod timer;
pub mod topology;

pub use deadlock::{BlockedProcess, DeadlockReport, WaitsOn};
pub use error::{ErrorKind, Halt, RunError};
pub use host::HostIo;
pub use link::{LinkStats, Network};
pub use node::{Node, NodeConfig};
pub use pool::PoolView;
pub use program::{ChannelName, CodeInfo, ProgramInfo, SourceLoc};
pub use sched::Idle;
pub use stats::Stats;
