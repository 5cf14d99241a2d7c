//! The data-driven language test harness behind `occ test` (and `cargo test` through
//! `cli/tests/lang.rs`).
//!
//! Each `.occ` file under the given paths states its own expectation in comments (`tests/README.md`):
//!
//! - `-- test: accept` — the front end finds no errors.
//! - `-- test: error` — every line carrying `-- error: <text>` gets an error containing `<text>`
//!   (case-insensitive), and no other line gets an error.
//! - `-- test: run` — compiles, runs, stdout equals the `-- stdout:` lines; `-- stdin:` lines feed
//!   input, `-- exit: N` gives the status (default 0).
//! - `-- test: runtime-error` — compiles, then halts with `-- runtime-error: <kind>` on its line.
//! - `-- test: deadlock` — deadlocks; the report contains every `-- deadlock: <text>`.
//! - `-- include: DIR` adds a `-I` folder (relative to the test file).
//!
//! The pieces: [`expect`] parses the comments, [`discover`] walks folders, [`judge`] compares what
//! the front end (and, later, the machine) did with what was expected, [`execute`] is the single place
//! where running a compiled program hooks in, [`bless`] rewrites `-- stdout:` lines under
//! `OCC_BLESS=1`, and [`suite`] runs files in parallel and counts outcomes.

pub mod bless;
pub mod discover;
pub mod execute;
pub mod expect;
pub mod judge;
pub mod suite;
