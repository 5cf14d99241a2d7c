//! A keyboard read by a thread of its own, so that a process waiting for a key blocks only
//! itself, as under KRoC (whose keyboard process makes a blocking call outside the scheduler):
//! the rest of the program goes on running and its output reaches the screen meanwhile.
//!
//! The thread reads ahead into a buffer (a few KiB at most). An input on `keyboard` that finds
//! enough bytes there takes them at once; otherwise the process registers (descriptor, data
//! pointer, length, its node's mailbox) and blocks, and the thread, once the bytes have come,
//! copies them into its workspace and posts the descriptor, as a link's second party does (see
//! [`crate::link`]). An ALT guard on `keyboard` registers likewise and is posted an ALT-tagged
//! descriptor. The node withdraws its registrations under the same mutex when it stops, so the
//! thread never writes into a freed workspace. At end of input (or a read error) every input
//! gets [`END_OF_INPUT`] bytes.
//!
//! Only a node outside a network uses it (a network's deadlock detection counts nodes, not host
//! threads): there the keyboard is read on the node's own thread, as before.

use std::collections::VecDeque;
use std::io::Read;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

use crate::abi::Word;
use crate::host::END_OF_INPUT;
use crate::mailbox::Mailbox;

/// How far the thread reads ahead of the program.
const AHEAD: usize = 4096;

/// A process blocked on `keyboard`.
#[derive(Debug)]
struct Waiter {
    desc: Word,
    data: usize,
    len: usize,
    mailbox: Arc<Mailbox>,
}

#[derive(Debug, Default)]
struct State {
    bytes: VecDeque<u8>,
    ended: bool,
    reader: Option<Waiter>,
    alt: Option<(Word, Arc<Mailbox>)>,
}

impl State {
    /// Whether an input of `len` bytes can complete now.
    fn can_take(&self, len: usize) -> bool {
        self.ended || self.bytes.len() >= len
    }

    /// Moves `out.len()` bytes out of the buffer (END_OF_INPUT past the end of input).
    fn take(&mut self, out: &mut [u8]) {
        for b in out {
            *b = self.bytes.pop_front().unwrap_or(END_OF_INPUT);
        }
    }
}

#[derive(Debug, Default)]
struct Shared {
    state: Mutex<State>,
    /// Signalled when the program takes bytes (the thread may read ahead again).
    taken: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The keyboard of a node, read by its own thread.
#[derive(Debug, Clone)]
pub(crate) struct Keyboard {
    shared: Arc<Shared>,
}

/// What an input on the keyboard did.
pub(crate) enum Took {
    /// The bytes were there: the input is complete.
    Done,
    /// The process is registered and blocks until the thread posts it.
    Waiting,
}

impl Keyboard {
    /// Starts the thread that reads `input`. It ends at end of input; while blocked in a read it
    /// keeps the process alive no longer than the program (it is not joined).
    pub(crate) fn spawn(mut input: Box<dyn Read + Send>) -> Keyboard {
        let shared = Arc::new(Shared::default());
        let kb = Keyboard {
            shared: shared.clone(),
        };
        std::thread::spawn(move || {
            let mut chunk = [0u8; 256];
            loop {
                {
                    let mut st = shared.lock();
                    while st.bytes.len() >= AHEAD {
                        st = shared.taken.wait(st).unwrap_or_else(|p| p.into_inner());
                    }
                }
                let got = match input.read(&mut chunk) {
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Ok(0) | Err(_) => None,
                    Ok(n) => Some(n),
                };
                let mut st = shared.lock();
                match got {
                    Some(n) => st.bytes.extend(&chunk[..n]),
                    None => st.ended = true,
                }
                wake(&mut st);
                if st.ended {
                    return;
                }
            }
        });
        kb
    }

    /// An input of `len` bytes into `data` by the process `desc` of the node whose mailbox is
    /// `mailbox`.
    ///
    /// # Safety
    /// `data` is valid for `len` bytes until the process is posted or withdrawn.
    pub(crate) unsafe fn input(
        &self,
        desc: Word,
        data: *mut u8,
        len: usize,
        mailbox: &Arc<Mailbox>,
    ) -> Took {
        let mut st = self.shared.lock();
        if st.can_take(len) {
            // SAFETY: caller contract.
            st.take(unsafe { std::slice::from_raw_parts_mut(data, len) });
            self.shared.taken.notify_one();
            return Took::Done;
        }
        st.reader = Some(Waiter {
            desc,
            data: data as usize,
            len,
            mailbox: mailbox.clone(),
        });
        Took::Waiting
    }

    /// `enbc`: whether a byte is there (else the ALTer `desc` is registered to be posted).
    pub(crate) fn enable(&self, desc: Word, mailbox: &Arc<Mailbox>) -> bool {
        let mut st = self.shared.lock();
        if st.can_take(1) {
            return true;
        }
        st.alt = Some((desc, mailbox.clone()));
        false
    }

    /// `disc`: withdraws the ALTer `desc` if still registered (returning whether it was) and
    /// tells whether a byte is there.
    pub(crate) fn disable(&self, desc: Word) -> (bool, bool) {
        let mut st = self.shared.lock();
        let withdrawn = st.alt.as_ref().is_some_and(|(d, _)| *d == desc);
        if withdrawn {
            st.alt = None;
        }
        (withdrawn, st.can_take(1))
    }

    /// Removes every registration of the node owning `mailbox` (it stops); returns how many.
    pub(crate) fn withdraw(&self, mailbox: &Arc<Mailbox>) -> usize {
        let mut st = self.shared.lock();
        let mut n = 0;
        if st
            .reader
            .as_ref()
            .is_some_and(|r| Arc::ptr_eq(&r.mailbox, mailbox))
        {
            st.reader = None;
            n += 1;
        }
        if st
            .alt
            .as_ref()
            .is_some_and(|(_, m)| Arc::ptr_eq(m, mailbox))
        {
            st.alt = None;
            n += 1;
        }
        n
    }
}

/// Completes a waiting input whose bytes are there, and wakes an ALT waiting for a byte.
fn wake(st: &mut State) {
    if let Some(r) = st.reader.as_ref()
        && st.can_take(r.len)
    {
        let r = st.reader.take().expect("checked above");
        // SAFETY: a registered reader's buffer stays valid until it is posted or withdrawn,
        // and both happen under this lock.
        st.take(unsafe { std::slice::from_raw_parts_mut(r.data as *mut u8, r.len) });
        r.mailbox.post(r.desc);
    }
    if st.can_take(1)
        && let Some((desc, mailbox)) = st.alt.take()
    {
        mailbox.post(desc);
    }
}
