//! `occ run FILE.occ [-I DIR] [--stats]`: preprocess, parse, check, compile with Cranelift and
//! run the file's last top-level PROC on one node, its three byte channels bound to stdin, stdout
//! and stderr. Exit status: 0 when the program terminates, 1 on compile errors, a runtime error,
//! STOP or deadlock (with a message naming file, line and kind, or the deadlock report).

use std::path::PathBuf;
use std::process::ExitCode;

use occ_runtime::{HostIo, NodeConfig, RunError};

use crate::frontend::{self, Options};

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

/// Runs `occ run`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    let options = Options {
        include_dirs: args.include,
    };
    let (front, checked) = frontend::load(&args.file, &options);
    for diag in &checked.diagnostics {
        eprintln!("{:?}", diag.report);
    }
    let Some(front) = front else {
        return Ok(ExitCode::from(1));
    };
    let (program, map) = (&front.parsed.program, &front.parsed.map);
    let set = frontend::intrinsics();
    let compiled = match occ_codegen::compile_with(program, &front.checked, map, &set) {
        Ok(compiled) => compiled,
        Err(error) => {
            for d in error.diagnostics() {
                eprintln!("{:?}", d.to_report(map));
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
