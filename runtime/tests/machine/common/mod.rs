//! Helpers for tests with hand-written processes in the exact shape codegen emits: an
//! `extern "C" fn(ws, node) -> Status` that dispatches on `ws[IPTR]`, keeps its state in the
//! workspace, stores the after-op index before every blocking entry and returns any non-zero
//! status at once.
#![allow(dead_code, reason = "each test file uses a different subset")]

use std::io::Write;
use std::sync::{Arc, Mutex};

use occ_runtime::abi::{Status, Word, Wptr, slot};
use occ_runtime::{HostIo, Node, NodeConfig, ProgramInfo};

/// Local `i` of frame `ws`.
///
/// # Safety
/// `ws` is a live frame with at least `i + 1` locals.
pub unsafe fn l(ws: Wptr, i: usize) -> *mut Word {
    unsafe { ws.add(i) }
}

/// The frame's resume index.
pub unsafe fn iptr(ws: Wptr) -> Word {
    unsafe { *ws.offset(slot::IPTR) }
}

/// Stores the resume index.
pub unsafe fn set_iptr(ws: Wptr, k: Word) {
    unsafe { *ws.offset(slot::IPTR) = k }
}

/// Returns from the enclosing process function if `st` is not DONE.
#[macro_export]
macro_rules! check {
    ($st:expr) => {{
        let st = $st;
        if st != occ_runtime::abi::Status::DONE {
            return st;
        }
    }};
}

/// The back-edge poll, exactly as codegen emits it.
#[macro_export]
macro_rules! poll {
    ($node:expr, $ws:expr, $k:expr) => {{
        use occ_runtime::abi::{NODE_POLLS_LEFT_OFFSET, YIELD_FLAG_OFFSET, yield_flag};
        let at = |offset: i32| ($node as *mut u8).add(offset as usize) as *mut u32;
        let flag = std::ptr::read_volatile(at(YIELD_FLAG_OFFSET));
        let mut call = flag != yield_flag::CLEAR;
        if flag == yield_flag::COUNT {
            let left = at(NODE_POLLS_LEFT_OFFSET);
            *left -= 1;
            call = *left == 0;
        }
        if call {
            $crate::common::set_iptr($ws, $k);
            $crate::check!(occ_runtime::sched::rt_timeslice($node, $ws));
        }
    }};
}

/// An in-memory host stream.
#[derive(Clone, Default)]
pub struct Capture(pub Arc<Mutex<Vec<u8>>>);

impl Capture {
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.0.lock().unwrap()).into_owned()
    }
}

impl Write for Capture {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A node with captured screen output, the given keyboard input and program tables.
pub fn node_with(program: ProgramInfo, input: &[u8], timeslice: bool) -> (Box<Node>, Capture) {
    let screen = Capture::default();
    let host = HostIo::new(
        Box::new(std::io::Cursor::new(input.to_vec())),
        Box::new(screen.clone()),
        Box::new(std::io::sink()),
    );
    let config = NodeConfig {
        timeslice,
        ..NodeConfig::default()
    };
    (Node::new(config, Arc::new(program), host), screen)
}

/// A node with no tables, no input, timeslicing on.
pub fn node() -> (Box<Node>, Capture) {
    node_with(ProgramInfo::default(), b"", true)
}

/// Allocates a workspace of `words` locals, fills the first locals with `init`, and spawns `code`.
pub fn spawn(node: &mut Node, code: occ_runtime::abi::ProcFn, words: usize, init: &[Word]) -> Wptr {
    let ws = node.alloc_workspace(words).expect("workspace");
    unsafe {
        for (i, v) in init.iter().enumerate() {
            *ws.add(i) = *v;
        }
        node.spawn(ws, code);
    }
    ws
}

/// A channel word (boxed so its address is stable).
pub fn channel() -> Box<Word> {
    Box::new(0)
}

/// The DONE status, for brevity.
pub const DONE: Status = Status::DONE;
