//! The occam preprocessor: `#INCLUDE`, `#USE`, `#IF`/`#ELIF`/`#ELSE`/`#ENDIF`, `#DEFINE`,
//! `#UNDEF`, `#PRAGMA`, `#OPTION`, `#COMMENT`.
//!
//! Contract:
//! - The output is one text in which every included file is re-indented to the column of its
//!   `#INCLUDE`; every output line comes from exactly one input line (see [`SourceMap`]).
//! - Directive lines become lines of spaces of the same length (so `#PRAGMA` name spans stay
//!   exact); lines of inactive `#IF` branches become empty lines and are never lexed.
//! - Files may be included again (no guards); recursion deeper than [`MAX_DEPTH`] and output larger
//!   than [`MAX_OUTPUT`] are errors, so no input makes the preprocessor loop.
//! - Nothing here touches the file system: files come from a [`Loader`].

mod condition;
#[cfg(test)]
mod test;

use crate::ast::{Name, Pragma, PragmaKind, Span};
use crate::diagnostic::{Diagnostic, Place};
use crate::external::ExternalText;
use crate::source_map::{LineOrigin, Location, SourceFile, SourceMap};
use condition::Value;
use std::collections::HashMap;

/// Deepest `#INCLUDE` nesting accepted.
pub const MAX_DEPTH: usize = 64;
/// Largest preprocessed text accepted, in bytes.
pub const MAX_OUTPUT: usize = 256 << 20;

/// Supplies the text of included files.
pub trait Loader {
    /// Finds `name` as included from the file at path `from` (searching the including file's
    /// folder, then `-I` folders, then the standard library) and returns its path and text, or
    /// `None` when no such file exists.
    fn load(&mut self, name: &str, from: &str) -> Option<(String, String)>;

    /// The places [`Loader::load`] looks in for a file included from `from`, in order, for the
    /// message when a file is not found (none by default).
    fn searched(&self, _from: &str) -> Vec<String> {
        Vec::new()
    }
}

/// A loader that knows no files (for programs without includes, and tests).
impl Loader for HashMap<String, String> {
    fn load(&mut self, name: &str, _from: &str) -> Option<(String, String)> {
        self.get(name).map(|text| (name.to_string(), text.clone()))
    }
}

/// The result of preprocessing.
#[derive(Debug, Default)]
pub struct Preprocessed {
    /// The single expanded text.
    pub text: String,
    /// The way back to the original files.
    pub map: SourceMap,
    /// `#PRAGMA SHARED` / `PERMITALIASES` / `EXTERNAL` directives, spans in `text`.
    pub pragmas: Vec<Pragma>,
    /// The header strings of the `#PRAGMA EXTERNAL` directives, for [`crate::external::parse`].
    pub externals: Vec<ExternalText>,
    /// The letters of every `#OPTION "..."` that took effect (not inside a false `#IF`; in
    /// included files too), in order: occ21's compiler options (`A` no alias checks, `N` no
    /// usage checks).
    pub options: String,
    /// Errors and warnings about directives.
    pub diagnostics: Vec<Diagnostic>,
}

/// Preprocesses the file `path` with text `text`, loading includes through `loader`.
pub fn preprocess(path: &str, text: &str, loader: &mut dyn Loader) -> Preprocessed {
    let mut pp = Preprocessor {
        out: Preprocessed::default(),
        defines: predefines(),
        loader,
    };
    pp.file(path.to_string(), text.to_string(), 0, 0);
    pp.out
}

/// The letters of `#OPTION "letters"` (the text up to the closing quote, or the line's end).
fn option_letters(rest: &str) -> &str {
    let rest = rest.trim_start();
    let rest = rest.strip_prefix('"').unwrap_or(rest);
    rest.split('"').next().unwrap_or("").trim()
}

fn predefines() -> HashMap<String, Value> {
    let mut defines = HashMap::new();
    defines.insert("TARGET.BITS.PER.WORD".to_string(), Value::Int(32));
    defines.insert("OCC".to_string(), Value::Bool(true));
    // As KRoC: occam-pi's extended rendezvous (`c ?? x` then a process) is supported.
    defines.insert("EXTENDED.RENDEZVOUS".to_string(), Value::Bool(true));
    defines
}

struct Preprocessor<'l> {
    out: Preprocessed,
    defines: HashMap<String, Value>,
    loader: &'l mut dyn Loader,
}

/// One open `#IF`.
struct Cond {
    /// Lines are emitted in the current branch.
    active: bool,
    /// Some branch was already taken (so later `#ELIF`/`#ELSE` are inactive).
    taken: bool,
    /// The enclosing region was active.
    parent: bool,
    /// Where the `#IF` is, for an unclosed-`#IF` error.
    at: Location,
    /// A `#RELAX` in the current branch: its lines are read two columns to the left.
    relaxed: bool,
}

/// The position of a directive line being processed.
struct Line<'a> {
    file: usize,
    line: usize,
    shift: usize,
    text: &'a str,
}

impl Line<'_> {
    /// Locates byte range `range` of this line's text in its file.
    fn at(&self, map: &SourceMap, range: std::ops::Range<usize>) -> Location {
        let start = map.files[self.file].line_start(self.line);
        Location {
            file: self.file,
            line: self.line + 1,
            range: start + range.start..start + range.end,
        }
    }

    /// Locates the whole directive (without its indentation).
    fn whole(&self, map: &SourceMap) -> Location {
        let indent = self.text.len() - self.text.trim_start().len();
        self.at(map, indent..self.text.trim_end().len().max(indent))
    }
}

impl Preprocessor<'_> {
    fn file(&mut self, path: String, text: String, shift: usize, depth: usize) {
        let file = self.out.map.add_file(SourceFile::new(path, text.clone()));
        let mut conds: Vec<Cond> = Vec::new();
        for (number, raw) in text.split('\n').enumerate() {
            if self.out.text.len() > MAX_OUTPUT {
                let line = Line {
                    file,
                    line: number,
                    shift,
                    text: raw,
                };
                let at = line.whole(&self.out.map);
                self.error(
                    at,
                    "the program is too large after #INCLUDE expansion",
                    "here",
                );
                return;
            }
            let raw = raw.strip_suffix('\r').unwrap_or(raw);
            let line = Line {
                file,
                line: number,
                shift,
                text: raw,
            };
            let active = conds.last().is_none_or(|c| c.active);
            let relax = 2 * conds.iter().filter(|c| c.relaxed).count();
            match directive_word(raw) {
                Some(word) => self.directive(&line, word, &mut conds, active, depth),
                None if active => self.emit(&line, raw, relax),
                None => self.emit(&line, "", 0),
            }
        }
        for cond in conds {
            self.error(cond.at, "this #IF has no #ENDIF", "the #IF opened here");
        }
    }

    /// Appends one output line, expanding tabs in its indentation and taking `relax` columns
    /// off it (`#RELAX`).
    fn emit(&mut self, line: &Line, text: &str, relax: usize) {
        let body = text.trim_start_matches([' ', '\t']);
        let indent = &text[..text.len() - body.len()];
        let relaxed = relax.min(columns(indent));
        let columns = columns(indent) - relaxed;
        let origin = LineOrigin {
            file: line.file,
            line: line.line,
            shift: line.shift,
            expanded: (columns + relaxed) - indent.len(),
            relaxed,
        };
        self.out.map.push_line(self.out.text.len(), origin);
        if !body.is_empty() {
            self.out
                .text
                .extend(std::iter::repeat_n(' ', line.shift + columns));
            self.out.text.push_str(body);
        }
        self.out.text.push('\n');
    }

    /// Emits a directive line as spaces, keeping its length for exact `#PRAGMA` name spans.
    fn emit_blank(&mut self, line: &Line) {
        let origin = LineOrigin {
            file: line.file,
            line: line.line,
            shift: line.shift,
            expanded: 0,
            relaxed: 0,
        };
        self.out.map.push_line(self.out.text.len(), origin);
        self.out
            .text
            .extend(std::iter::repeat_n(' ', line.shift + line.text.len()));
        self.out.text.push('\n');
    }

    fn error(&mut self, at: Location, message: &str, label: &str) {
        let diag = Diagnostic::at(Place::File(at), message, label).with_code("preprocess");
        self.out.diagnostics.push(diag);
    }

    fn directive(
        &mut self,
        line: &Line,
        word: &str,
        conds: &mut Vec<Cond>,
        active: bool,
        depth: usize,
    ) {
        let rest = directive_rest(line.text, word);
        match word {
            "IF" => self.open_if(line, rest, conds, active),
            "ELIF" => self.elif(line, rest, conds),
            "ELSE" => self.else_(line, conds),
            "RELAX" if active => self.relax(line, conds),
            "ENDIF" => {
                if conds.pop().is_none() {
                    let at = line.whole(&self.out.map);
                    self.error(at, "#ENDIF without #IF", "nothing to close here");
                }
            }
            _ if !active => {}
            "INCLUDE" => return self.include(line, rest, depth, false),
            "USE" => return self.include(line, rest, depth, true),
            "DEFINE" => self.define(line, rest),
            "UNDEF" => {
                self.defines.remove(rest.trim());
            }
            "PRAGMA" => self.pragma(line, rest),
            "OPTION" => self.out.options.push_str(option_letters(rest)),
            "COMMENT" | "IMPORT" => {}
            _ => {
                let at = line.whole(&self.out.map);
                let message = format!("unknown directive #{word}");
                self.error(at, &message, "I do not know this directive");
            }
        }
        self.emit_blank(line);
    }

    fn open_if(&mut self, line: &Line, rest: &str, conds: &mut Vec<Cond>, active: bool) {
        let value = active && self.condition(line, rest);
        conds.push(Cond {
            active: value,
            taken: value,
            parent: active,
            at: line.whole(&self.out.map),
            relaxed: false,
        });
    }

    /// `#RELAX` (occ21): the rest of this `#IF` branch is indented one level deeper than the
    /// code around it, and is read two columns to the left. Once per branch.
    fn relax(&mut self, line: &Line, conds: &mut [Cond]) {
        let problem = match conds.last_mut() {
            None => Some("#RELAX outside #IF"),
            Some(cond) if cond.relaxed => Some("#RELAX twice in one #IF branch"),
            Some(cond) => {
                cond.relaxed = true;
                None
            }
        };
        if let Some(message) = problem {
            let at = line.whole(&self.out.map);
            self.error(at, message, "here");
        }
    }

    fn elif(&mut self, line: &Line, rest: &str, conds: &mut [Cond]) {
        let Some(parent) = conds.last().map(|c| c.parent && !c.taken) else {
            let at = line.whole(&self.out.map);
            return self.error(at, "#ELIF without #IF", "no #IF is open here");
        };
        let value = parent && self.condition(line, rest);
        if let Some(cond) = conds.last_mut() {
            cond.active = value;
            cond.taken |= value;
            cond.relaxed = false;
        }
    }

    fn else_(&mut self, line: &Line, conds: &mut [Cond]) {
        match conds.last_mut() {
            Some(cond) => {
                cond.active = cond.parent && !cond.taken;
                cond.taken = true;
                cond.relaxed = false;
            }
            None => {
                let at = line.whole(&self.out.map);
                self.error(at, "#ELSE without #IF", "no #IF is open here");
            }
        }
    }

    /// Evaluates a `#IF` condition, reporting a malformed one (which counts as FALSE).
    fn condition(&mut self, line: &Line, rest: &str) -> bool {
        match condition::evaluate(strip_comment(rest), &self.defines) {
            Ok(value) => value,
            Err(problem) => {
                let at = line.whole(&self.out.map);
                let message = format!("cannot evaluate this #IF condition: {problem}");
                self.error(at, &message, "in this directive");
                false
            }
        }
    }

    fn define(&mut self, line: &Line, rest: &str) {
        let rest = strip_comment(rest).trim();
        let (name, value) = rest.split_once([' ', '\t']).unwrap_or((rest, ""));
        if name.is_empty() {
            let at = line.whole(&self.out.map);
            return self.error(
                at,
                "#DEFINE needs a name",
                "write #DEFINE NAME or #DEFINE NAME value",
            );
        }
        let value = match value.trim() {
            "" => Value::Bool(true),
            text => condition::literal(text).unwrap_or(Value::Str(text.to_string())),
        };
        self.defines.insert(name.to_string(), value);
    }

    fn pragma(&mut self, line: &Line, rest: &str) {
        let rest = strip_comment(rest);
        let word = rest.split_whitespace().next().unwrap_or("");
        let kind = match word {
            "SHARED" => PragmaKind::Shared,
            "PERMITALIASES" => PragmaKind::PermitAliases,
            "EXTERNAL" => return self.external(line, rest),
            _ => {
                let at = line.whole(&self.out.map);
                let message = format!("#PRAGMA {word} is ignored");
                let diag =
                    Diagnostic::at(Place::File(at), message, "this pragma has no effect here")
                        .with_code("preprocess")
                        .warning();
                return self.out.diagnostics.push(diag);
            }
        };
        let line_out = self.out.text.len() + line.shift;
        let base = offset_in(line.text, rest);
        let after = rest.find(word).map_or(0, |i| i + word.len());
        let names = pragma_names(&rest[after..], line_out + base + after);
        let span = Span::new(line_out, line_out + line.text.trim_end().len());
        self.out.pragmas.push(Pragma {
            kind,
            names,
            span,
            external: None,
        });
    }

    /// Keeps `#PRAGMA EXTERNAL "header = N"` with the output offset of the header text; the
    /// header itself is parsed after preprocessing ([`crate::external`]).
    fn external(&mut self, line: &Line, rest: &str) {
        let line_out = self.out.text.len() + line.shift;
        let base = offset_in(line.text, rest);
        let open = rest.find('"');
        let close = open.and_then(|o| rest[o + 1..].find('"').map(|c| o + 1 + c));
        let (Some(open), Some(close)) = (open, close) else {
            let at = line.whole(&self.out.map);
            return self.error(
                at,
                "the EXTERNAL header must be in double quotes",
                "write #PRAGMA EXTERNAL \"PROC NAME (VAL INT x) = 0\"",
            );
        };
        let span = Span::new(line_out, line_out + line.text.trim_end().len());
        self.out.externals.push(ExternalText {
            pragma: self.out.pragmas.len(),
            text: rest[open + 1..close].to_string(),
            at: line_out + base + open + 1,
        });
        self.out.pragmas.push(Pragma {
            kind: PragmaKind::External,
            names: Vec::new(),
            span,
            external: None,
        });
    }

    fn include(&mut self, line: &Line, rest: &str, depth: usize, is_use: bool) {
        let indent = columns(&line.text[..line.text.len() - line.text.trim_start().len()]);
        let Some(name) = quoted(strip_comment(rest)) else {
            let at = line.whole(&self.out.map);
            self.error(
                at,
                "the file name must be in double quotes",
                "write #INCLUDE \"file.inc\"",
            );
            return self.emit_blank(line);
        };
        let from = self.out.map.files[line.file].path.clone();
        let loaded = if is_use {
            use_candidates(name)
                .iter()
                .find_map(|candidate| self.loader.load(candidate, &from))
        } else {
            self.loader.load(name, &from)
        };
        self.emit_blank(line);
        let at = line.whole(&self.out.map);
        match loaded {
            None => {
                let message = format!("cannot find the file \"{name}\"");
                let places = self.loader.searched(&from);
                let mut diag = Diagnostic::at(Place::File(at), &message, "included here")
                    .with_code("preprocess");
                if !places.is_empty() {
                    let names = if is_use {
                        format!("{} ", use_candidates(name).join(", "))
                    } else {
                        String::new()
                    };
                    diag = diag.with_help(format!("looked for {names}in: {}", places.join("; ")));
                }
                self.out.diagnostics.push(diag);
            }
            Some(_) if depth + 1 > MAX_DEPTH => self.error(
                at,
                "#INCLUDE nested too deeply (recursive include?)",
                "included here",
            ),
            Some((path, text)) => self.file(path, text, line.shift + indent, depth + 1),
        }
    }
}

/// The byte offset of `part`, a slice of `whole`, in `whole` (so a trailing comment stripped
/// from `part` does not shift it).
fn offset_in(whole: &str, part: &str) -> usize {
    (part.as_ptr() as usize).saturating_sub(whole.as_ptr() as usize)
}

/// The display width of leading white space (tab stops every eight columns).
fn columns(indent: &str) -> usize {
    indent.chars().fold(0, |col, c| {
        if c == '\t' {
            (col / 8 + 1) * 8
        } else {
            col + 1
        }
    })
}

/// Returns the directive word of a line whose first non-blank character is `#` followed by a
/// letter (hexadecimal literals like `#FF` at the start of a continuation line are not
/// directives unless the word is a directive name).
fn directive_word(line: &str) -> Option<&str> {
    let rest = line.trim_start().strip_prefix('#')?;
    let end = rest
        .find(|c: char| !c.is_ascii_alphabetic())
        .unwrap_or(rest.len());
    let word = &rest[..end];
    let is_hex = !word.is_empty() && word.chars().all(|c| c.is_ascii_hexdigit());
    (!word.is_empty() && !is_hex).then_some(word)
}

fn directive_rest<'a>(line: &'a str, word: &str) -> &'a str {
    let start = line.len() - line.trim_start().len() + 1 + word.len();
    line.get(start..).unwrap_or("")
}

/// Removes a trailing `-- comment` that is not inside a string.
fn strip_comment(text: &str) -> &str {
    let mut in_string = false;
    let bytes = text.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => in_string = !in_string,
            b'-' if !in_string && bytes.get(i + 1) == Some(&b'-') => return &text[..i],
            _ => {}
        }
    }
    text
}

fn quoted(text: &str) -> Option<&str> {
    let text = text.trim();
    text.strip_prefix('"')?.strip_suffix('"')
}

/// The files `#USE "m"` may mean, in order of preference.
fn use_candidates(name: &str) -> Vec<String> {
    let stem = name
        .strip_suffix(".lib")
        .or_else(|| name.strip_suffix(".module"))
        .unwrap_or(name);
    let mut candidates: Vec<String> = ["module", "inc", "occ"]
        .iter()
        .map(|ext| format!("{stem}.{ext}"))
        .collect();
    candidates.push(name.to_string());
    candidates
}

/// Reads the comma- or space-separated names after `#PRAGMA SHARED`; `offset` is the output
/// offset of `text`.
fn pragma_names(text: &str, offset: usize) -> Vec<Name> {
    let mut names = Vec::new();
    let mut start = None;
    for (i, c) in text
        .char_indices()
        .chain(std::iter::once((text.len(), ' ')))
    {
        let part_of_name = c.is_ascii_alphanumeric() || c == '.' || c == '_';
        match (part_of_name, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                names.push(Name {
                    text: text[s..i].to_string(),
                    span: Span::new(offset + s, offset + i),
                });
                start = None;
            }
            _ => {}
        }
    }
    names
}
