//! Placement: what a node of a configured network binds when its program reaches the
//! `PLACED PAR`.
//!
//! Every node of a network runs the program's last PROC from the start: the declarations before
//! its `PLACED PAR` give each node its own copy of the configuration's channels. At the
//! `PLACED PAR`, compiled code calls [`rt_placement`], which stores this node's [`Placement`] into
//! the frame (the values of the replicator indices of the `PROCESSOR` it runs, and the channel
//! words of the links that join it to other nodes, over the soft channel words the declarations
//! made) and returns which `PROCESSOR` process of the text to run.

use crate::abi::{Word, Wptr};
use crate::node::Node;

/// What one node binds at the `PLACED PAR`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Placement {
    /// The `PROCESSOR` process to run, by its textual index.
    pub branch: Word,
    /// Words to store in the frame first: (byte offset from Wptr, value).
    pub stores: Vec<(i32, Word)>,
}

impl Node {
    /// Sets what this node binds at the program's `PLACED PAR`.
    pub fn set_placement(&mut self, p: Placement) {
        self.placement = Some(p);
    }
}

/// The `PLACED PAR` entry: stores this node's placement into frame `ws` and returns the index
/// of the `PROCESSOR` process to run, or -1 when the node has no placement (the program was
/// not started as a network).
///
/// # Safety
/// `node` is the running node and `ws` the frame of the program's last PROC, in which every
/// offset of the placement lies.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn rt_placement(node: *mut Node, ws: Wptr) -> Word {
    // SAFETY: caller contract.
    let node = unsafe { &mut *node };
    let Some(p) = node.placement.take() else {
        return -1;
    };
    for &(offset, value) in &p.stores {
        // SAFETY: the offsets come from the compiler's layout of this very frame.
        unsafe { *ws.byte_offset(offset as isize) = value };
    }
    p.branch
}
