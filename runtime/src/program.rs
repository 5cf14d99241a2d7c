//! Program tables registered by codegen: source locations, PROC names, resume-point locations and
//! channel names. They cost nothing at run time; error and deadlock reports read them.

use crate::abi::{ProcFn, Word};

/// A source position.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceLoc {
    /// Source file name, as given to the compiler.
    pub file: String,
    /// 1-based line.
    pub line: u32,
}

/// A named channel (or array of channels) declared in a PROC's workspace.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelName {
    /// Word offset of the (first) channel word from the frame's Wptr.
    pub offset: i64,
    /// Number of channel words (1 for a single channel).
    pub count: u32,
    /// The occam name.
    pub name: String,
}

/// What the runtime knows about one compiled function (a PROC or a PAR branch).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CodeInfo {
    /// The PROC's name (branches: the enclosing PROC's name).
    pub name: String,
    /// The function's address.
    pub code: usize,
    /// For each resume index, the index into [`ProgramInfo::locations`] of its blocking point.
    pub resume_locations: Vec<u32>,
    /// Channels declared in this function's workspace.
    pub channels: Vec<ChannelName>,
}

impl CodeInfo {
    /// Describes function `code` named `name`, with no locations or channels yet.
    pub fn new(name: &str, code: ProcFn) -> CodeInfo {
        CodeInfo {
            name: name.to_string(),
            code: code as usize,
            resume_locations: Vec::new(),
            channels: Vec::new(),
        }
    }
}

/// All tables of one program; shared (read-only) by every node running it.
#[derive(Clone, Debug, Default)]
pub struct ProgramInfo {
    /// Source locations, indexed by the `location` codes passed to `rt_error`.
    pub locations: Vec<SourceLoc>,
    /// Compiled functions.
    pub procs: Vec<CodeInfo>,
}

impl ProgramInfo {
    /// Adds a location and returns its index.
    pub fn add_location(&mut self, file: &str, line: u32) -> u32 {
        self.locations.push(SourceLoc {
            file: file.to_string(),
            line,
        });
        (self.locations.len() - 1) as u32
    }

    /// The location with index `id`.
    pub fn location(&self, id: u32) -> Option<&SourceLoc> {
        self.locations.get(id as usize)
    }

    /// The function whose address is `code`.
    pub fn proc_by_code(&self, code: usize) -> Option<&CodeInfo> {
        self.procs.iter().find(|p| p.code == code)
    }

    /// The location of resume index `iptr` of function `code`.
    pub fn resume_location(&self, code: usize, iptr: Word) -> Option<&SourceLoc> {
        let p = self.proc_by_code(code)?;
        let id = *p.resume_locations.get(usize::try_from(iptr).ok()?)?;
        self.location(id)
    }
}
