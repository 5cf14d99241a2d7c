//! The file-system edge of the front end: read an occam file, load its includes, run the one
//! IO-free front end (`occ_codegen::front_end`: preprocess, parse, check, bind EXTERNALs) and
//! return its diagnostics located in files, in a form both `occ check` and `occ test` use.
//!
//! Contract (relied on by `commands::check` and the `occ test` harness):
//! - `check_file` never panics and never hangs on any input; every problem is a `Diag`.
//! - `Diag::line` is the 1-based line in `Diag::file` (the file the problem is in, which may be an
//!   included file), after mapping back through `#INCLUDE` re-indentation.
//!
//! - A program that checks clean is also linked: every `#PRAGMA EXTERNAL` routine it calls must
//!   be in [`intrinsics`] with the signature its pragma gives (`occ_codegen::bind`), so these
//!   errors come out of `occ check` and `occ test` with lines like the checker's.
//!
//! Include search order: the including file's folder, then the `-I` folders, then `stdlib/`
//! (from `OCC_STDLIB`, else the `stdlib/` folder of the workspace the executable was built in or
//! sits in), then the standard library built into the binary ([`crate::stdlib`]). A file not
//! found is reported with every place looked in.

use occ_grammar::diagnostic::Diagnostic;
use occ_grammar::preprocess::Loader;
use occ_grammar::source_map::SourceMap;
use std::path::{Path, PathBuf};

/// Options shared by `occ check`, `occ run` and `occ test`.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Extra `#INCLUDE`/`#USE` search folders (`-I`), searched after the including file's folder
    /// and before `stdlib/`.
    pub include_dirs: Vec<PathBuf>,
}

pub use occ_grammar::diagnostic::Severity;

/// One diagnostic, located in the original source file and rendered.
#[derive(Debug)]
pub struct Diag {
    /// Error or warning.
    pub severity: Severity,
    /// The file the problem is in.
    pub file: PathBuf,
    /// 1-based line in `file` (0 for a problem of the whole program).
    pub line: usize,
    /// The one-line message (without the rendering).
    pub message: String,
    /// The full miette report, with every label, help and code.
    pub report: miette::Report,
}

impl Diag {
    /// Locates `d` through `map` and renders it.
    pub fn new(d: &Diagnostic, map: &SourceMap) -> Diag {
        let (file, line) = d.file_line(map).unwrap_or_default();
        Diag {
            severity: d.severity,
            file: PathBuf::from(file),
            line,
            message: d.message.clone(),
            report: d.to_report(map),
        }
    }
}

/// The result of checking one program.
#[derive(Debug, Default)]
pub struct Checked {
    /// Every diagnostic, errors and warnings, in source order.
    pub diagnostics: Vec<Diag>,
}

impl Checked {
    /// Reports whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics
            .iter()
            .any(|d| d.severity == Severity::Error)
    }
}

/// A program that passed the front end: its parse (AST and source map) and the checker's tables.
pub struct Front {
    /// The preprocessed, parsed program.
    pub parsed: occ_grammar::Parsed,
    /// The checker's side tables for `parsed.program`.
    pub checked: occ_compiler::CheckedProgram,
}

/// Checks the occam program rooted at `path`.
pub fn check_file(path: &Path, options: &Options) -> Checked {
    load(path, options).1
}

/// Loads, preprocesses, parses and checks the program rooted at `path`.
///
/// Returns the checked program when there are no errors, and every diagnostic (warnings too).
pub fn load(path: &Path, options: &Options) -> (Option<Front>, Checked) {
    let text = match std::fs::read(path) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(error) => return (None, unreadable(path, &error)),
    };
    load_text(&path.display().to_string(), &text, options)
}

/// [`load`] for a program held in memory under the file name `name` (programs embedded in
/// `occ`, such as carm.occ); its includes are searched for as those of a file `name`.
pub fn load_text(name: &str, text: &str, options: &Options) -> (Option<Front>, Checked) {
    let mut loader = FsLoader::new(options);
    let front = occ_codegen::front_end(name, text, &mut loader, &intrinsics());
    let map = &front.parsed.map;
    let mut diagnostics: Vec<Diag> = front
        .diagnostics
        .iter()
        .map(|d| Diag::new(d, map))
        .collect();
    diagnostics.sort_by(|a, b| (&a.file, a.line).cmp(&(&b.file, b.line)));
    let checked = Checked { diagnostics };
    let passed = front.checked.map(|checked| Front {
        parsed: front.parsed,
        checked,
    });
    (passed, checked)
}

/// The native intrinsics occ links programs against: the runtime's own and the radiosity
/// kernels (`#INCLUDE "radiosity.inc"` declares them).
pub fn intrinsics() -> occ_codegen::IntrinsicSet {
    occ_codegen::IntrinsicSet::new().with(occ_radiosity::intrinsics::INTRINSICS)
}

fn unreadable(path: &Path, error: &std::io::Error) -> Checked {
    let message = format!("cannot read {}: {error}", path.display());
    Checked {
        diagnostics: vec![Diag {
            severity: Severity::Error,
            file: path.to_path_buf(),
            line: 0,
            report: miette::miette!("{message}"),
            message,
        }],
    }
}

/// Loads included files from the search path.
struct FsLoader {
    dirs: Vec<PathBuf>,
}

impl FsLoader {
    fn new(options: &Options) -> Self {
        let mut dirs = options.include_dirs.clone();
        dirs.extend(stdlib_dir());
        FsLoader { dirs }
    }
}

impl Loader for FsLoader {
    fn load(&mut self, name: &str, from: &str) -> Option<(String, String)> {
        let found = self
            .folders(from)
            .into_iter()
            .map(|dir| dir.join(name))
            .find(|candidate| candidate.is_file());
        let Some(found) = found else {
            let text = crate::stdlib::get(name)?;
            return Some((
                format!("{}/{name}", crate::stdlib::PREFIX),
                text.to_string(),
            ));
        };
        let bytes = std::fs::read(&found).ok()?;
        let text = String::from_utf8_lossy(&bytes).into_owned();
        Some((found.display().to_string(), text))
    }

    fn searched(&self, from: &str) -> Vec<String> {
        let mut places: Vec<String> = self
            .folders(from)
            .iter()
            .map(|dir| {
                if dir.as_os_str().is_empty() {
                    "the working folder".to_string()
                } else {
                    dir.display().to_string()
                }
            })
            .collect();
        places.push("the standard library built into occ".into());
        places
    }
}

impl FsLoader {
    /// The folders searched for a file included from `from`, in order: its folder, then the
    /// `-I` folders and `stdlib/`.
    fn folders(&self, from: &str) -> Vec<PathBuf> {
        let here = Path::new(from).parent().map(Path::to_path_buf);
        here.into_iter().chain(self.dirs.iter().cloned()).collect()
    }
}

/// Finds `stdlib/`: `OCC_STDLIB`, else beside the executable's workspace, else the workspace the
/// binary was built from.
fn stdlib_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("OCC_STDLIB") {
        return Some(PathBuf::from(dir));
    }
    let exe = std::env::current_exe().ok();
    let from_exe = exe
        .iter()
        .flat_map(|exe| exe.ancestors().skip(1))
        .map(|dir| dir.join("stdlib"))
        .find(|dir| dir.is_dir());
    from_exe.or_else(|| {
        let built = Path::new(env!("CARGO_MANIFEST_DIR")).join("../stdlib");
        built.is_dir().then_some(built)
    })
}
