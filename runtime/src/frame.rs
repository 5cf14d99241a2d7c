//! Reading and writing the runtime's slots in a workspace, and process descriptors.
//!
//! All slot access goes through [`get`] and [`set`], so the one assumption they rest on (a valid
//! workspace with its header reserved) is stated once.

use crate::abi::{Word, Wptr, tag};

/// Reads slot `s` (a word offset, usually negative, see [`crate::abi::slot`]) of `ws`.
///
/// # Safety
/// `ws` must be a live workspace with [`crate::abi::slot::HEADER_WORDS`] words reserved below it,
/// owned by the calling node.
#[inline(always)]
pub(crate) unsafe fn get(ws: Wptr, s: isize) -> Word {
    // SAFETY: the caller guarantees `ws + s` lies in the workspace's reserved header.
    unsafe { *ws.offset(s) }
}

/// Writes slot `s` of `ws`.
///
/// # Safety
/// As for [`get`].
#[inline(always)]
pub(crate) unsafe fn set(ws: Wptr, s: isize, v: Word) {
    // SAFETY: the caller guarantees `ws + s` lies in the workspace's reserved header.
    unsafe { *ws.offset(s) = v }
}

/// The workspace pointer of a descriptor or tagged channel word.
#[inline(always)]
pub(crate) fn wptr(desc: Word) -> Wptr {
    (desc & !tag::MASK) as Wptr
}

/// The priority bit of a descriptor.
#[inline(always)]
pub(crate) fn pri(desc: Word) -> Word {
    desc & tag::LOW
}
