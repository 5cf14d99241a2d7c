//! Frame layout: every variable at a fixed byte offset in its function's workspace.
//!
//! A frame's fixed words: word 0 is the static link (the lexically enclosing function's frame;
//! for a PAR branch its parent's frame), word 1 the PAR join block address (branches only).
//! Locals follow, allocated stack-like: a scope's variables are released when the scope ends, so
//! sequential scopes share space. A callee's or PAR branch's workspace sits at the current top of
//! the caller's frame, with [`slot::HEADER_WORDS`] words for its header below its Wptr. Since occam
//! has no recursion every size is static; a frame's size is its high-water mark, including its
//! deepest callee.

use occ_runtime::abi::{WORD_BYTES, frame, slot, word_offset};

/// Byte offset of the first local (after the static link and the join word).
pub const FIRST_LOCAL: i32 = word_offset(frame::FIXED_WORDS as isize);

/// Bytes of a sub-workspace's header.
pub const HEADER_BYTES: i32 = word_offset(slot::HEADER_WORDS as isize);

/// The allocation state of one function's frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    top: i32,
    max: i32,
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            top: FIRST_LOCAL,
            max: FIRST_LOCAL,
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
    pub fn mark(&self) -> i32 {
        self.top
    }

    /// Releases everything allocated since `mark`.
    pub fn release(&mut self, mark: i32) {
        self.top = mark;
    }

    /// Reserves a sub-workspace of `words` words (plus header) at the top, without allocating
    /// it for good; returns the byte offset of its Wptr.
    pub fn sub_workspace(&mut self, words: u32) -> i32 {
        let wptr = self.top + HEADER_BYTES;
        let end = wptr + i32::try_from(words).unwrap_or(i32::MAX / 16) * WORD_BYTES;
        self.max = self.max.max(end);
        wptr
    }

    /// The frame size in words.
    pub fn words(&self) -> u32 {
        (self.max as u32).div_ceil(WORD_BYTES as u32)
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
        let w = f.sub_workspace(10);
        assert_eq!(w, FIRST_LOCAL + 8 + HEADER_BYTES);
        assert_eq!(f.words() as i32, (w + 80) / 8);
    }
}
