//! Runtime tests with hand-written processes in the exact shape codegen emits.

#[macro_use]
mod common;

mod alt;
mod chan;
mod errors;
mod frames;
mod host;
mod links;
mod par;
mod sched;
mod stress;
mod timers;
