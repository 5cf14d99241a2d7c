//! Workspace memory: a per-node bump arena with a byte budget and free lists by size.
//!
//! Memory comes from the system in zeroed chunks (pages are only touched when used), so a large
//! budget costs nothing until processes use it.

use std::collections::HashMap;

use crate::abi::{Word, Wptr, slot};
use crate::error::RunError;

/// The offset from the address base of the first chunk: INT addresses below it are never
/// node memory.
const ADDR_GUARD: Word = 1 << 16;

/// Words per chunk requested from the system (8 MB).
const CHUNK_WORDS: usize = 1 << 20;

/// A node's workspace arena.
#[derive(Debug)]
pub(crate) struct Arena {
    chunks: Vec<Box<[Word]>>,
    /// [`ADDR_GUARD`] bytes before the first chunk's first word (0 until it exists): the base
    /// that `ASM` blocks' 32-bit addresses are offsets from (see
    /// [`crate::abi::ADDR_BASE_OFFSET`]).
    pub(crate) base: Word,
    /// The byte offsets from `base` of the first chunk's first and one past its last byte: the
    /// range `ASM` addresses are checked against first (see [`crate::abi::ADDR_LIMITS_OFFSET`];
    /// [`Arena::holds`] checks the other chunks).
    pub(crate) limits: [Word; 2],
    /// Next free word in the last chunk.
    used: usize,
    free: HashMap<usize, Vec<Wptr>>,
    budget: usize,
    in_use: usize,
    peak: usize,
}

impl Arena {
    pub(crate) fn new(budget: usize) -> Arena {
        Arena {
            chunks: Vec::new(),
            base: 0,
            limits: [0, 0],
            used: 0,
            free: HashMap::new(),
            budget,
            in_use: 0,
            peak: 0,
        }
    }

    /// Allocates `words` words above Wptr plus the header below; returns Wptr.
    pub(crate) fn alloc(&mut self, words: usize) -> Result<Wptr, RunError> {
        let too_big = RunError::OutOfMemory {
            requested: words.saturating_mul(size_of::<Word>()),
            budget: self.budget,
        };
        let Some(total) = words.max(1).checked_add(slot::HEADER_WORDS) else {
            return Err(too_big);
        };
        let bytes = total.saturating_mul(size_of::<Word>());
        if bytes > self.budget - self.in_use {
            return Err(too_big);
        }
        self.in_use += bytes;
        self.peak = self.peak.max(self.in_use);
        if let Some(ws) = self.free.get_mut(&total).and_then(Vec::pop) {
            return Ok(ws);
        }
        Ok(self.bump(total))
    }

    fn bump(&mut self, total: usize) -> Wptr {
        let fits = self
            .chunks
            .last()
            .is_some_and(|c| self.used + total <= c.len());
        if !fits {
            self.chunks
                .push(vec![0; CHUNK_WORDS.max(total)].into_boxed_slice());
            self.used = 0;
            let chunk = self.chunks.last().expect("a chunk was just pushed");
            let start = chunk.as_ptr() as Word;
            if self.base == 0 {
                // Small numbers are not addresses (unless the system puts a later chunk just
                // below the first): an INT used by mistake as one is an
                // error, not a write to the first frames.
                self.base = start - ADDR_GUARD;
                self.limits = [ADDR_GUARD, ADDR_GUARD];
            }
            if self.chunks.len() == 1 {
                let end = start - self.base + (chunk.len() * size_of::<Word>()) as Word;
                self.limits = [start - self.base, end];
            }
        }
        let chunk = self.chunks.last_mut().expect("a chunk was just ensured");
        let base = chunk[self.used..].as_mut_ptr();
        self.used += total;
        // SAFETY: `base + HEADER_WORDS` is inside the `total` words just reserved.
        unsafe { base.add(slot::HEADER_WORDS) }
    }

    /// Whether the `bytes` at `offset` from the address base lie in one chunk.
    pub(crate) fn holds(&self, offset: Word, bytes: Word) -> bool {
        let Some(end) = offset.checked_add(bytes) else {
            return false;
        };
        bytes >= 0
            && self.chunks.iter().any(|c| {
                let start = c.as_ptr() as Word - self.base;
                let stop = start + (c.len() * size_of::<Word>()) as Word;
                start <= offset && end <= stop
            })
    }

    /// Returns a workspace to its size's free list.
    ///
    /// # Safety
    /// `ws` came from `alloc(words)` on this arena and is no longer used.
    pub(crate) unsafe fn free(&mut self, ws: Wptr, words: usize) {
        let total = words.max(1) + slot::HEADER_WORDS;
        self.in_use -= total * size_of::<Word>();
        self.free.entry(total).or_default().push(ws);
    }

    /// High-water mark of allocated bytes.
    pub(crate) fn peak_bytes(&self) -> u64 {
        self.peak as u64
    }
}

/// `rt_addr_ok(node, offset, bytes)`: see [`crate::abi::Entry::AddrOk`].
///
/// # Safety
/// `node` is the running node.
pub(crate) unsafe extern "C" fn rt_addr_ok(
    node: *mut crate::Node,
    offset: Word,
    bytes: Word,
) -> Word {
    // SAFETY: caller contract.
    Word::from(unsafe { (*node).arena.holds(offset, bytes) })
}

/// The words above Wptr of a vector of `bytes`.
fn vector_words(bytes: Word) -> usize {
    usize::try_from(bytes)
        .unwrap_or(0)
        .div_ceil(size_of::<Word>())
}

/// `rt_vector_get(node, ws, bytes, at, location)`: see [`crate::abi::Entry::VectorGet`].
///
/// # Safety
/// `node` is the running node, `ws` its running frame and `at` a word of it.
pub(crate) unsafe extern "C" fn rt_vector_get(
    node: *mut crate::Node,
    ws: Wptr,
    bytes: Word,
    at: *mut Word,
    location: Word,
) -> crate::abi::Status {
    // SAFETY: caller contract.
    let n = unsafe { &mut *node };
    match n.alloc_workspace(vector_words(bytes)) {
        Ok(v) => {
            // SAFETY: `at` is a word of the running frame.
            unsafe { *at = v as Word };
            crate::abi::Status::DONE
        }
        Err(_) => {
            let detail = format!(
                "{bytes} bytes asked for, {} left of the node's budget of {} bytes",
                n.arena.budget - n.arena.in_use,
                n.arena.budget
            );
            // SAFETY: caller contract (the frame's CODE slot names its function).
            let st = unsafe {
                crate::error::rt_error(node, ws, crate::ErrorKind::Memory as Word, location)
            };
            // SAFETY: caller contract; `rt_error` has just set the halt.
            if let Some(h) = unsafe { &mut (*node).halt } {
                h.detail = Some(detail);
            }
            st
        }
    }
}

/// `rt_vector_free(node, address, bytes)`: see [`crate::abi::Entry::VectorFree`].
///
/// # Safety
/// `node` is the running node; `address` came from its `rt_vector_get` of `bytes`, and its
/// array's scope has ended.
pub(crate) unsafe extern "C" fn rt_vector_free(
    node: *mut crate::Node,
    address: Wptr,
    bytes: Word,
) -> Word {
    // SAFETY: caller contract.
    unsafe { (*node).free_workspace(address, vector_words(bytes)) };
    0
}

#[cfg(test)]
mod test {
    use super::*;

    /// Every workspace is node memory as `ASM` addresses see it (a later chunk may lie below
    /// the first, at a negative offset): in a chunk the arena holds, however many chunks there are; the fast limits are the first
    /// chunk's; what lies between chunks is not node memory.
    #[test]
    fn workspaces_fall_inside_the_address_limits() {
        let mut arena = Arena::new(64 << 20);
        assert_eq!(arena.base, 0, "no base before the first chunk");
        let mut spans = Vec::new();
        for words in [10, CHUNK_WORDS - 100, 50, CHUNK_WORDS] {
            let ws = arena.alloc(words).expect("within the budget") as Word;
            spans.push((ws, words));
        }
        assert!(arena.chunks.len() >= 2, "the test spans chunks");
        for (ws, words) in spans {
            let off = ws - arena.base;
            let end = off + (words * size_of::<Word>()) as Word;
            assert!(arena.holds(off, end - off), "{off}..{end}");
        }
        let first = arena.chunks[0].as_ptr() as Word;
        assert_eq!(first - arena.base, ADDR_GUARD);
        let first_end = ADDR_GUARD + (arena.chunks[0].len() * size_of::<Word>()) as Word;
        assert_eq!(arena.limits, [ADDR_GUARD, first_end]);
        // Bytes that straddle a chunk's end are not node memory, nor is a negative length.
        assert!(arena.chunks.iter().all(|c| {
            let end = c.as_ptr() as Word - arena.base + (c.len() * size_of::<Word>()) as Word;
            !arena.holds(end - 4, 8) || arena.holds(end, 4)
        }));
        assert!(!arena.holds(ADDR_GUARD, -1));
    }
}
