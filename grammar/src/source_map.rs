//! The map from the preprocessed text back to the original files.
//!
//! The preprocessor emits one output line per input line it reads (directive lines and inactive
//! `#IF` branches become blank or space-filled lines), each shifted right by the indentation of the
//! `#INCLUDE` that brought it in. So an output offset maps to exactly one (file, line, column) with
//! a constant column shift per line.

use crate::ast::Span;
use std::ops::Range;
use std::sync::Arc;

/// One original source file.
#[derive(Debug, Clone)]
pub struct SourceFile {
    /// The path as the loader reported it (used for display).
    pub path: String,
    /// The full original text.
    pub text: String,
    line_starts: Vec<usize>,
    /// The same text, shared by every report that shows it (so many diagnostics on a large file
    /// do not copy it many times).
    shared: Arc<str>,
}

impl SourceFile {
    /// Creates a source file and indexes its lines.
    pub fn new(path: String, text: String) -> Self {
        let line_starts = line_starts(&text);
        let shared = Arc::from(text.as_str());
        SourceFile {
            path,
            text,
            line_starts,
            shared,
        }
    }

    /// Returns the text as a cheaply clonable shared string (for miette reports).
    pub fn shared_text(&self) -> Arc<str> {
        Arc::clone(&self.shared)
    }

    /// Returns the byte offset where 0-based `line` starts (the end of the text past the last line).
    pub fn line_start(&self, line: usize) -> usize {
        self.line_starts
            .get(line)
            .copied()
            .unwrap_or(self.text.len())
    }

    /// Returns the 0-based line holding byte `offset`.
    pub fn line_of(&self, offset: usize) -> usize {
        self.line_starts
            .partition_point(|&s| s <= offset)
            .saturating_sub(1)
    }
}

fn line_starts(text: &str) -> Vec<usize> {
    let mut starts = vec![0];
    starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
    starts
}

/// Where one output line came from.
#[derive(Debug, Clone, Copy)]
pub struct LineOrigin {
    /// Index into [`SourceMap::files`].
    pub file: usize,
    /// 0-based line in that file.
    pub line: usize,
    /// Spaces added in front of the line by `#INCLUDE` re-indentation.
    pub shift: usize,
    /// Bytes added by expanding leading tabs to spaces (tab stops every eight columns).
    pub expanded: usize,
    /// Columns taken off the line's indentation by `#RELAX`.
    pub relaxed: usize,
}

/// A location in an original file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// Index into [`SourceMap::files`].
    pub file: usize,
    /// 1-based line.
    pub line: usize,
    /// Byte range in the original file's text (clipped to one line).
    pub range: Range<usize>,
}

/// The original files and the origin of every output line.
#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    /// Every file read, the root first. A file included twice appears twice.
    pub files: Vec<SourceFile>,
    lines: Vec<LineOrigin>,
    out_starts: Vec<usize>,
}

impl SourceMap {
    /// Records that the output line starting at `out_start` came from `origin`.
    pub fn push_line(&mut self, out_start: usize, origin: LineOrigin) {
        self.out_starts.push(out_start);
        self.lines.push(origin);
    }

    /// Adds a file and returns its index.
    pub fn add_file(&mut self, file: SourceFile) -> usize {
        self.files.push(file);
        self.files.len() - 1
    }

    /// Maps a span of the output text to its original file, line and byte range.
    /// Returns `None` only when the map is empty.
    pub fn locate(&self, span: Span) -> Option<Location> {
        let index = self
            .out_starts
            .partition_point(|&s| s <= span.start)
            .checked_sub(1)?;
        let origin = self.lines.get(index)?;
        let file = self.files.get(origin.file)?;
        let col = (span.start - self.out_starts[index] + origin.relaxed)
            .saturating_sub(origin.shift + origin.expanded);
        let line_start = file.line_start(origin.line);
        let line_end = file
            .text
            .get(line_start..)
            .and_then(|rest| rest.find('\n'))
            .map_or(file.text.len(), |n| line_start + n);
        let start = (line_start + col).min(line_end);
        let end = (start + span.end.saturating_sub(span.start)).min(line_end);
        Some(Location {
            file: origin.file,
            line: origin.line + 1,
            range: start..end.max(start),
        })
    }
}
