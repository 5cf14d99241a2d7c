//! Frame layout: every variable at a fixed byte offset in its function's workspace.
//!
//! A frame's fixed words: word 0 is the static link (the lexically enclosing function's frame;
//! for a PAR branch its parent's frame), word 1 the PAR join block address (branches only).
//! Locals follow, allocated stack-like: a scope's variables are released when the scope ends, so
//! sequential scopes share space. A callee's or PAR branch's workspace sits at the current top of
//! the caller's frame, with [`slot::HEADER_WORDS`] words for its header below its Wptr. Since occam
//! has no recursion every size is static; a frame's size is its high-water mark, including its
//! deepest callee.
//!
//! Large arrays ([`VECTOR_BYTES`] and more) are not in the frame: their declaration takes them
//! from the node's memory when it runs and gives them back when its scope ends (the frame holds
//! their address), so a branch never taken costs nothing. A frame also counts the most bytes of
//! such *vectors* that can be held at once below it, its callees' and PAR branches' included:
//! with the frame, the most memory the function can take.

use occ_runtime::abi::{WORD_BYTES, frame, slot, word_offset};

/// Byte offset of the first local (after the static link and the join word).
pub const FIRST_LOCAL: i32 = word_offset(frame::FIXED_WORDS as isize);

/// Bytes of a sub-workspace's header.
pub const HEADER_BYTES: i32 = word_offset(slot::HEADER_WORDS as isize);

/// The size from which a declared array is a vector, taken from the node's memory as its
/// declaration runs rather than held in the frame.
pub const VECTOR_BYTES: i64 = 64 << 10;

/// The bytes of node memory a vector of `bytes` takes: whole words and the arena's header.
pub fn vector_cost(bytes: i64) -> i64 {
    let word = i64::from(WORD_BYTES);
    (bytes.max(1) + word - 1) / word * word + i64::from(HEADER_BYTES)
}

/// What a function needs: its frame's words and the most bytes of vectors it (with its callees
/// and branches) can hold at once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Size {
    /// Words above Wptr of the frame, its deepest callee's included.
    pub words: u32,
    /// The most bytes of vectors held at once while it runs.
    pub vectors: i64,
}

/// Where a scope started: what to restore at its end.
#[derive(Clone, Copy, Debug)]
pub struct Mark {
    top: i32,
    vectors: i64,
}

/// The allocation state of one function's frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    top: i32,
    max: i32,
    /// Bytes of vectors held by the scopes open at this point, and the most at any point.
    vectors: i64,
    vectors_max: i64,
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            top: FIRST_LOCAL,
            max: FIRST_LOCAL,
            vectors: 0,
            vectors_max: 0,
        }
    }
}

impl Frame {
    /// Allocates `bytes` (rounded up to whole words) and returns the byte offset.
    pub fn alloc(&mut self, bytes: i64) -> i32 {
        let at = self.top;
        let word = i64::from(WORD_BYTES);
        let words = (bytes.max(1) + word - 1) / word;
        self.top += i32::try_from(words * word).unwrap_or(i32::MAX / 2);
        self.max = self.max.max(self.top);
        at
    }

    /// Allocates `words` whole words and returns the byte offset.
    pub fn alloc_words(&mut self, words: usize) -> i32 {
        self.alloc(i64::from(WORD_BYTES) * words as i64)
    }

    /// Allocates one word and returns its byte offset.
    pub fn alloc_word(&mut self) -> i32 {
        self.alloc_words(1)
    }

    /// The current top, to restore at the end of a scope.
    pub fn mark(&self) -> Mark {
        Mark {
            top: self.top,
            vectors: self.vectors,
        }
    }

    /// Releases everything allocated since `mark`, vectors included.
    pub fn release(&mut self, mark: Mark) {
        self.top = mark.top;
        self.vectors = mark.vectors;
    }

    /// Counts `bytes` of vectors held until the current scope ends: a vector declared here,
    /// or the vectors of PAR branches, which are all held at once.
    pub fn hold_vectors(&mut self, bytes: i64) {
        self.vectors = self.vectors.saturating_add(bytes);
        self.vectors_max = self.vectors_max.max(self.vectors);
    }

    /// Reserves a sub-workspace for a callee of size `callee` (plus header) at the top, without
    /// allocating it for good; returns the byte offset of its Wptr.
    pub fn sub_workspace(&mut self, callee: Size) -> i32 {
        let wptr = self.top + HEADER_BYTES;
        let end = wptr + i32::try_from(callee.words).unwrap_or(i32::MAX / 16) * WORD_BYTES;
        self.max = self.max.max(end);
        self.vectors_max = self
            .vectors_max
            .max(self.vectors.saturating_add(callee.vectors));
        wptr
    }

    /// The frame's size: its words and the most vectors it holds at once.
    pub fn size(&self) -> Size {
        Size {
            words: (self.max as u32).div_ceil(WORD_BYTES as u32),
            vectors: self.vectors_max,
        }
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn scopes_reuse_space_and_callees_count_in_size() {
        let mut f = Frame::default();
        let m = f.mark();
        assert_eq!(f.alloc(4), FIRST_LOCAL);
        assert_eq!(f.alloc(9), FIRST_LOCAL + 8);
        assert_eq!(f.alloc_word(), FIRST_LOCAL + 24);
        f.release(m);
        assert_eq!(f.alloc(1), FIRST_LOCAL);
        let w = f.sub_workspace(Size {
            words: 10,
            vectors: 0,
        });
        assert_eq!(w, FIRST_LOCAL + 8 + HEADER_BYTES);
        assert_eq!(f.size().words as i32, (w + 80) / 8);
    }

    #[test]
    fn vectors_count_what_is_held_at_once() {
        let mut f = Frame::default();
        let outer = f.mark();
        f.hold_vectors(100);
        let inner = f.mark();
        f.hold_vectors(50);
        f.release(inner);
        // a callee holding 70 while the outer 100 is held
        f.sub_workspace(Size {
            words: 1,
            vectors: 70,
        });
        f.release(outer);
        f.hold_vectors(60);
        assert_eq!(f.size().vectors, 170);
    }
}
