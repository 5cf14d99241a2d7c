//! The timeslice ticker: one thread per OS process that sets the yield flag of every running node
//! every [`TICK`], so a busy low-priority loop returns to its scheduler at the next back-edge poll.
//!
//! It is not scheduler state (each node keeps its own queues and flag); it only owns a list of
//! flag addresses, registered while a node runs. The thread sleeps (parked) while no node runs.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, OnceLock};
use std::thread::Thread;
use std::time::Duration;

/// The timeslice period.
pub const TICK: Duration = Duration::from_millis(1);

struct Ticker {
    flags: Mutex<Vec<usize>>,
    thread: Thread,
}

fn ticker() -> &'static Ticker {
    static TICKER: OnceLock<Ticker> = OnceLock::new();
    TICKER.get_or_init(|| {
        let handle = std::thread::Builder::new()
            .name("occ-ticker".into())
            .spawn(tick_loop)
            .expect("cannot start the timeslice ticker thread");
        Ticker {
            flags: Mutex::new(Vec::new()),
            thread: handle.thread().clone(),
        }
    })
}

fn lock_flags(t: &Ticker) -> std::sync::MutexGuard<'_, Vec<usize>> {
    t.flags.lock().unwrap_or_else(|p| p.into_inner())
}

fn tick_loop() {
    loop {
        let t = ticker();
        let idle = {
            let flags = lock_flags(t);
            for &f in flags.iter() {
                // SAFETY: a registered address is a node's AtomicU32 flag; the node unregisters
                // (under this lock) before the flag can be freed.
                unsafe {
                    (*(f as *const AtomicU32))
                        .store(crate::abi::yield_flag::REQUEST, Ordering::Relaxed)
                };
            }
            flags.is_empty()
        };
        if idle {
            std::thread::park();
        } else {
            std::thread::sleep(TICK);
        }
    }
}

/// A registration; dropping it unregisters the flag.
pub(crate) struct Ticket(usize);

/// Registers `flag` with the ticker until the ticket is dropped.
pub(crate) fn register(flag: &AtomicU32) -> Ticket {
    let addr = flag as *const AtomicU32 as usize;
    let t = ticker();
    lock_flags(t).push(addr);
    t.thread.unpark();
    Ticket(addr)
}

impl Drop for Ticket {
    fn drop(&mut self) {
        let mut flags = lock_flags(ticker());
        if let Some(i) = flags.iter().position(|&f| f == self.0) {
            flags.swap_remove(i);
        }
    }
}
