//! The `occ` command: `check`, `run`, `test` and `radiosity`.
//!
//! This file only parses flags and dispatches; each subcommand lives in its own module under
//! `commands/`, which owns its flags (`Args`) and its behaviour (`execute`).

mod commands;
mod frontend;
mod stdlib;
mod testsuite;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// occam 2.1 compiler, transputer-style runtime and parallel radiosity renderer.
#[derive(Parser)]
#[command(name = "occ", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check occam programs and report every diagnostic; exit 0 when clean, 1 on errors.
    Check(commands::check::Args),
    /// Compile and run an occam program (its last top-level PROC, or its PLACED PAR network).
    Run(commands::run::Args),
    /// Run a language test suite: each .occ file states its expectation in comments.
    Test(commands::test::Args),
    /// Compute a radiosity solution (the default Cornell box when no scene is given).
    Radiosity(Box<commands::radiosity::Args>),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Check(args) => commands::check::execute(args),
        Command::Run(args) => commands::run::execute(args),
        Command::Test(args) => commands::test::execute(args),
        Command::Radiosity(args) => commands::radiosity::execute(*args),
    };
    match outcome {
        Ok(code) => code,
        Err(error) => {
            eprintln!("occ: {error:#}");
            ExitCode::from(2)
        }
    }
}
