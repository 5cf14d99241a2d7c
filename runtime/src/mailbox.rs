//! A node's mailbox: the lock-free inbox through which other nodes (other OS threads) hand it
//! descriptors of its frames to requeue.
//!
//! Posting pushes onto a Treiber stack with one compare-and-swap; the owning node takes the whole
//! stack with one swap and restores posting order. Only a node that has nothing else to do sleeps
//! on the mailbox's condition variable, and a poster takes the mutex only when the owner has
//! announced that it sleeps (a Dekker-style handshake on `sleeping`, both sides `SeqCst`), so a
//! wake-up is never lost and the common path takes no lock.

use std::sync::atomic::{AtomicBool, AtomicPtr, Ordering::SeqCst};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

use crate::abi::Word;
use crate::pool::Waker;

/// One posted descriptor.
struct Mail {
    desc: Word,
    next: *mut Mail,
}

/// The inbox of one node.
#[derive(Debug, Default)]
pub(crate) struct Mailbox {
    head: AtomicPtr<Mail>,
    sleeping: AtomicBool,
    lock: Mutex<()>,
    wake: Condvar,
    /// Set while a thread pool runs the node: called after each post instead of the condvar.
    waker: AtomicPtr<Waker>,
}

impl std::fmt::Debug for Mail {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mail({})", self.desc)
    }
}

impl Mailbox {
    /// Posts `desc` (from any thread) and wakes the owner if it sleeps.
    pub(crate) fn post(&self, desc: Word) {
        let mail = Box::into_raw(Box::new(Mail {
            desc,
            next: std::ptr::null_mut(),
        }));
        let mut head = self.head.load(SeqCst);
        loop {
            // SAFETY: `mail` is ours until the CAS publishes it.
            unsafe { (*mail).next = head };
            match self.head.compare_exchange_weak(head, mail, SeqCst, SeqCst) {
                Ok(_) => break,
                Err(h) => head = h,
            }
        }
        let waker = self.waker.load(SeqCst);
        if !waker.is_null() {
            // SAFETY: a waker stays valid until `clear_waker`, which runs only when no node of
            // the pool runs any more (so nothing posts).
            let w = unsafe { &*waker };
            w.pool.wake(w.index);
        } else if self.sleeping.load(SeqCst) {
            let _guard = self.lock.lock().unwrap_or_else(|p| p.into_inner());
            self.wake.notify_one();
        }
    }

    /// Routes wake-ups to a thread pool (see [`crate::Network::run_pool`]).
    pub(crate) fn set_waker(&self, w: Waker) {
        let old = self.waker.swap(Box::into_raw(Box::new(w)), SeqCst);
        if !old.is_null() {
            // SAFETY: `old` came from Box::into_raw here and nothing uses it (the previous pool
            // has finished).
            drop(unsafe { Box::from_raw(old) });
        }
    }

    /// Stops routing wake-ups to a pool.
    ///
    /// Only called when no node that could post here is running.
    pub(crate) fn clear_waker(&self) {
        let old = self.waker.swap(std::ptr::null_mut(), SeqCst);
        if !old.is_null() {
            // SAFETY: as in `set_waker`.
            drop(unsafe { Box::from_raw(old) });
        }
    }

    /// Takes every posted descriptor, oldest first (owner only).
    pub(crate) fn take_all(&self) -> Vec<Word> {
        let mut p = self.head.swap(std::ptr::null_mut(), SeqCst);
        let mut out = Vec::new();
        while !p.is_null() {
            // SAFETY: the swap made this list ours; each node came from Box::into_raw in `post`.
            let mail = unsafe { Box::from_raw(p) };
            out.push(mail.desc);
            p = mail.next;
        }
        out.reverse();
        out
    }

    /// Whether anything has been posted.
    pub(crate) fn has_mail(&self) -> bool {
        !self.head.load(SeqCst).is_null()
    }

    /// Waits up to `d` for mail (owner only); returns whether there is some.
    pub(crate) fn wait(&self, d: Duration) -> bool {
        let guard = self.lock.lock().unwrap_or_else(|p| p.into_inner());
        self.sleeping.store(true, SeqCst);
        if !self.has_mail() {
            let _ = self
                .wake
                .wait_timeout(guard, d)
                .unwrap_or_else(|p| p.into_inner());
        }
        self.sleeping.store(false, SeqCst);
        self.has_mail()
    }
}

impl Drop for Mailbox {
    fn drop(&mut self) {
        drop(self.take_all());
        self.clear_waker();
    }
}

// SAFETY: the raw `Mail` pointers are owned by the stack and only dereferenced by the thread that
// won them (the poster before publishing, the owner after swapping the stack out).
unsafe impl Send for Mailbox {}
// SAFETY: as above; all shared state is atomic or behind the mutex.
unsafe impl Sync for Mailbox {}

#[cfg(test)]
mod test {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn mail_comes_out_in_posting_order() {
        let m = Mailbox::default();
        assert!(!m.has_mail());
        for d in [8, 16, 24] {
            m.post(d);
        }
        assert_eq!(m.take_all(), vec![8, 16, 24]);
        assert!(m.take_all().is_empty());
    }

    #[test]
    fn many_posters_and_a_sleeping_owner_lose_nothing() {
        let m = Arc::new(Mailbox::default());
        let posters: Vec<_> = (0..4)
            .map(|t| {
                let m = m.clone();
                std::thread::spawn(move || {
                    for i in 0..10_000 {
                        m.post((t * 100_000 + i) * 8);
                    }
                })
            })
            .collect();
        let mut got = Vec::new();
        while got.len() < 40_000 {
            if m.wait(Duration::from_millis(50)) {
                got.extend(m.take_all());
            }
        }
        for p in posters {
            p.join().unwrap();
        }
        got.sort();
        got.dedup();
        assert_eq!(got.len(), 40_000);
    }
}
