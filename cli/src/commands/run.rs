//! `occ run FILE.occ [-I DIR] [--stats]`: preprocess, parse, check, compile with Cranelift and
//! run the file's last top-level PROC on one node, its three byte channels bound to stdin, stdout
//! and stderr. Exit status: 0 when the program terminates, 1 on compile errors, a runtime error,
//! STOP or deadlock (with a message naming file, line and kind, or the deadlock report).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use occ_runtime::{HostIo, NodeConfig, RunError};

/// Flags of `occ run`.
#[derive(clap::Args)]
pub struct Args {
    /// The program to run.
    pub file: PathBuf,
    /// Extra `#INCLUDE`/`#USE` search folders.
    #[arg(short = 'I', value_name = "DIR")]
    pub include: Vec<PathBuf>,
    /// Print processes started, context switches, communications and peak workspace bytes.
    #[arg(long)]
    pub stats: bool,
}

/// Finds included files: the including file's folder, then `-I` folders, then `stdlib/`.
pub struct FileLoader {
    /// Folders searched after the including file's.
    pub dirs: Vec<PathBuf>,
}

impl FileLoader {
    /// A loader searching `include` and then the standard library.
    pub fn new(include: &[PathBuf]) -> FileLoader {
        let mut dirs = include.to_vec();
        if let Ok(d) = std::env::var("OCC_STDLIB") {
            dirs.push(PathBuf::from(d));
        }
        dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../stdlib"));
        FileLoader { dirs }
    }
}

impl occ_grammar::preprocess::Loader for FileLoader {
    fn load(&mut self, name: &str, from: &str) -> Option<(String, String)> {
        let here = Path::new(from).parent().map(Path::to_path_buf);
        let candidates = here.into_iter().chain(self.dirs.iter().cloned());
        for d in candidates {
            let p = d.join(name);
            if let Ok(text) = std::fs::read_to_string(&p) {
                return Some((p.to_string_lossy().into_owned(), text));
            }
        }
        None
    }
}

/// Why a program could not be run.
#[derive(Debug)]
pub enum Failure {
    /// Occurs when the program has parse, check or code generation errors (messages).
    Compile(Vec<String>),
    /// Occurs when the file cannot be read.
    Read(String),
}

/// Loads, parses, checks and compiles `file`.
pub fn build(file: &Path, include: &[PathBuf]) -> Result<occ_codegen::Compiled, Failure> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| Failure::Read(format!("{}: {e}", file.display())))?;
    let path = file.to_string_lossy().into_owned();
    let mut loader = FileLoader::new(include);
    let parsed = occ_grammar::parse_source(&path, &text, &mut loader);
    let at = |span| match parsed.map.locate(span) {
        Some(l) => format!(
            "{}:{}",
            parsed
                .map
                .files
                .get(l.file)
                .map_or("?", |f| f.path.as_str()),
            l.line
        ),
        None => path.clone(),
    };
    if parsed.has_errors() {
        let msgs = parsed
            .diagnostics
            .iter()
            .filter(|d| d.severity == occ_grammar::diagnostic::Severity::Error)
            .map(|d| match &d.place {
                occ_grammar::diagnostic::Place::Output(s) => format!("{}: {}", at(*s), d.message),
                _ => d.message.clone(),
            })
            .collect();
        return Err(Failure::Compile(msgs));
    }
    let options = occ_compiler::Options::from_source(&text);
    let (checked, diags) = occ_compiler::check_with(&parsed.program, options);
    let Some(checked) = checked else {
        let msgs = diags
            .iter()
            .filter(|d| d.severity == occ_compiler::Severity::Error)
            .map(|d| format!("{}: {}", at(d.span), d.message()))
            .collect();
        return Err(Failure::Compile(msgs));
    };
    occ_codegen::compile(&parsed.program, &checked, &parsed.map)
        .map_err(|e| Failure::Compile(vec![e.to_string()]))
}

/// Runs `occ run`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    let compiled = match build(&args.file, &args.include) {
        Ok(c) => c,
        Err(Failure::Read(m)) => anyhow::bail!(m),
        Err(Failure::Compile(msgs)) => {
            for m in msgs {
                eprintln!("{m}");
            }
            return Ok(ExitCode::from(1));
        }
    };
    let (result, stats) = compiled.run(NodeConfig::default(), HostIo::stdio());
    if args.stats {
        eprintln!("{stats}");
    }
    Ok(match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(RunError::Deadlock(report)) => {
            eprintln!("{report}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(1)
        }
    })
}
