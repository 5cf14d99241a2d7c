//! Links between nodes, cross-node wake-ups and network-wide deadlock detection.
//!
//! A link direction is a shared `LinkShared` behind an endpoint's channel word on each node: the
//! output end on one node, the input end on the other, possibly on another OS thread. It follows
//! the soft-channel rule: the first party registers itself (descriptor, data pointer, length, its
//! node's mailbox) and blocks; the second copies the message, completes, and posts the first's
//! descriptor to the first's node mailbox; that node requeues it when it drains its mail. An
//! ALT on a link input registers in the link and is posted an ALT-tagged descriptor when a writer
//! arrives.
//!
//! Copying into another node's workspace is sound because the blocked frame's node does not touch
//! it until it has taken the descriptor from its mailbox, and the link's mutex (held while copying
//! and posting) orders the two. A node that stops withdraws its registrations under the same
//! mutex and discards its mail, so no peer writes into a workspace that is about to be freed.
//!
//! A [`Network`] counts its nodes, those idle with nothing but link waits, and mail in flight: when
//! every node is idle (or finished) and no mail is in flight, no link can move and each waiting
//! node reports a deadlock instead of waiting for ever.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering::SeqCst};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crate::abi::{Status, Word, Wptr, tag};
use crate::chan::copy;
use crate::endpoint::Engine;
use crate::error::{ErrorKind, RunError};
use crate::mailbox::Mailbox;
use crate::node::Node;

/// How often an idle node re-checks the network for deadlock.
const IDLE_POLL: Duration = Duration::from_millis(2);

/// Counters shared by the nodes of one network.
///
/// `state` packs two counters into one word so that one load is a consistent snapshot: the
/// number of idle (or finished) nodes in the low 32 bits, mail in flight in the high 32 bits.
/// A node with mail decrements its idle count before the mail's in-flight count, and a node
/// posting mail is not idle, so a snapshot with every node idle and nothing in flight is a
/// deadlock.
#[derive(Debug, Default)]
pub(crate) struct NetState {
    nodes: AtomicUsize,
    state: AtomicU64,
    /// Set when a node halts: every other node stops at its next timeslice or wait.
    stopped: AtomicBool,
    /// Every link direction, in the order connected, for statistics.
    links: Mutex<Vec<Arc<LinkShared>>>,
    /// The local halves of links to nodes in other processes (see [`crate::remote`]).
    pub(crate) remote: Mutex<Vec<crate::remote::Half>>,
}

/// One idle node in [`NetState::state`].
const IDLE: u64 = 1;
/// One mail in flight in [`NetState::state`].
pub(crate) const MAIL: u64 = 1 << 32;

impl NetState {
    pub(crate) fn add(&self, v: u64) {
        self.state.fetch_add(v, SeqCst);
    }

    pub(crate) fn sub(&self, v: u64) {
        self.state.fetch_sub(v, SeqCst);
    }

    /// Stops the network (a node has halted).
    pub(crate) fn stop(&self) {
        self.stopped.store(true, SeqCst);
    }

    /// Whether the network has been stopped.
    pub(crate) fn is_stopped(&self) -> bool {
        self.stopped.load(SeqCst)
    }

    /// Whether every node is idle or finished and no mail is in flight.
    fn deadlocked(&self) -> bool {
        let s = self.state.load(SeqCst);
        s >> 32 == 0 && (s & (MAIL - 1)) as usize == self.nodes.load(SeqCst)
    }
}

/// A set of nodes joined by links.
#[derive(Debug, Clone, Default)]
pub struct Network {
    pub(crate) state: Arc<NetState>,
}

/// One party registered at a link.
#[derive(Debug)]
pub(crate) struct Party {
    pub(crate) desc: Word,
    pub(crate) data: usize,
    pub(crate) len: Word,
    pub(crate) mailbox: Arc<Mailbox>,
    /// When it blocked, for [`LinkStats`].
    pub(crate) since: Instant,
}

#[derive(Debug, Default)]
pub(crate) struct LinkState {
    pub(crate) writer: Option<Party>,
    pub(crate) reader: Option<Party>,
    pub(crate) alt: Option<(Word, Arc<Mailbox>)>,
    pub(crate) stats: LinkStats,
}

/// Traffic of one link direction.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// The link's name (the channel it carries).
    pub name: String,
    /// Messages carried.
    pub messages: u64,
    /// Bytes carried.
    pub bytes: u64,
    /// Time the outputting process spent blocked waiting for the inputter.
    pub writer_blocked: Duration,
    /// Time the inputting process spent blocked waiting for the outputter.
    pub reader_blocked: Duration,
}

/// The shared state of one link direction.
#[derive(Debug)]
pub(crate) struct LinkShared {
    state: Mutex<LinkState>,
    net: Arc<NetState>,
}

/// One end of a link direction, held by an endpoint.
#[derive(Debug, Clone)]
pub(crate) struct LinkEnd {
    shared: Arc<LinkShared>,
}

impl LinkEnd {
    pub(crate) fn lock(&self) -> MutexGuard<'_, LinkState> {
        self.shared.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Removes every party registered by the node owning `mailbox`.
    fn withdraw(&self, mailbox: &Arc<Mailbox>) {
        let mut st = self.lock();
        let mine = |p: &Party| Arc::ptr_eq(&p.mailbox, mailbox);
        if st.reader.as_ref().is_some_and(mine) {
            st.reader = None;
        }
        if st.writer.as_ref().is_some_and(mine) {
            st.writer = None;
        }
        if st
            .alt
            .as_ref()
            .is_some_and(|(_, m)| Arc::ptr_eq(m, mailbox))
        {
            st.alt = None;
        }
    }

    pub(crate) fn post(&self, to: &Mailbox, desc: Word) {
        self.shared.net.add(MAIL);
        to.post(desc);
    }
}

impl Network {
    /// An empty network.
    pub fn new() -> Network {
        Network::default()
    }

    /// Adds `node` to the network (once per node, before connecting it).
    pub fn join(&self, node: &mut Node) {
        self.state.nodes.fetch_add(1, SeqCst);
        node.net = Some(self.state.clone());
    }

    /// Creates a link direction from `from` to `to` (both joined): returns the channel word on
    /// `from` to output to, and the one on `to` to input from.
    pub fn connect(&self, from: &mut Node, to: &mut Node, name: &str) -> (*mut Word, *mut Word) {
        let (out, inp) = self.ends(name);
        (
            from.add_endpoint(out, &format!("{name} (link out)")),
            to.add_endpoint(inp, &format!("{name} (link in)")),
        )
    }

    /// A link direction from `node` back to itself (a ring of one node): as
    /// [`Network::connect`] with both ends on `node`.
    pub fn connect_loop(&self, node: &mut Node, name: &str) -> (*mut Word, *mut Word) {
        let (out, inp) = self.ends(name);
        (
            node.add_endpoint(out, &format!("{name} (link out)")),
            node.add_endpoint(inp, &format!("{name} (link in)")),
        )
    }

    /// The two engines of a new link direction: its output end and its input end.
    fn ends(&self, name: &str) -> (Engine, Engine) {
        let out = self.link(name);
        let inp = out.clone();
        (Engine::LinkOut(out), Engine::LinkIn(inp))
    }

    /// A new link direction, listed for statistics, with no end yet.
    pub(crate) fn link(&self, name: &str) -> LinkEnd {
        let shared = Arc::new(LinkShared {
            state: Mutex::new(LinkState {
                stats: LinkStats {
                    name: name.to_string(),
                    ..LinkStats::default()
                },
                ..LinkState::default()
            }),
            net: self.state.clone(),
        });
        lock(&self.state.links).push(shared.clone());
        LinkEnd { shared }
    }
}

/// Locks `m`, whatever a panicking holder left.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl Network {
    /// The traffic of every link direction, in the order connected.
    pub fn link_stats(&self) -> Vec<LinkStats> {
        lock(&self.state.links)
            .iter()
            .map(|l| lock(&l.state).stats.clone())
            .collect()
    }

    /// Whether a node halted and stopped the network.
    pub fn stopped(&self) -> bool {
        self.state.is_stopped()
    }

    /// A channel word on `node` that no link stands behind: a process that inputs or outputs
    /// on it waits for ever (and is named `name` in deadlock reports); an ALT guard on it is
    /// never ready.
    pub fn unconnected(node: &mut Node, name: &str) -> *mut Word {
        node.add_endpoint(Engine::Unconnected, name)
    }
}

impl Network {
    /// Runs every node on its own OS thread until all have stopped; returns each node with its
    /// outcome, in the order given. (A pool with fewer threads than nodes needs nodes that yield
    /// their thread when idle: not yet implemented.)
    pub fn run_all(nodes: Vec<Box<Node>>) -> Vec<(Box<Node>, Result<(), RunError>)> {
        std::thread::scope(|s| {
            let handles: Vec<_> = nodes
                .into_iter()
                .map(|mut node| {
                    s.spawn(move || {
                        let r = node.run();
                        (node, r)
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect()
        })
    }
}

impl Node {
    /// Output on a link.
    ///
    /// # Safety
    /// `ws` is the running frame; `data` valid for `len` bytes and live until the output ends.
    pub(crate) unsafe fn link_out(
        &mut self,
        end: &LinkEnd,
        ws: Wptr,
        what: Word,
        data: *mut u8,
        len: Word,
    ) -> Status {
        let mut st = end.lock();
        if let Some(r) = st.reader.take() {
            st.stats.reader_blocked += r.since.elapsed();
            // SAFETY: the reader is blocked; its buffer is valid for `r.len` bytes while it is
            // registered, and the lock (held until the copy and the post are done) keeps its
            // node from withdrawing and freeing it meanwhile.
            return unsafe { self.link_complete(end, &mut st, ws, r, data, len, true) };
        }
        st.writer = Some(self.party(ws, data, len));
        if let Some((alter, mailbox)) = st.alt.take() {
            end.post(&mailbox, alter);
        }
        drop(st);
        // SAFETY: `ws` is the running frame.
        unsafe { self.note_blocked(ws, what) };
        self.link_waiters += 1;
        Status::BLOCKED
    }

    /// Input from a link.
    ///
    /// # Safety
    /// As for [`Node::link_out`].
    pub(crate) unsafe fn link_in(
        &mut self,
        end: &LinkEnd,
        ws: Wptr,
        what: Word,
        data: *mut u8,
        len: Word,
    ) -> Status {
        let mut st = end.lock();
        if let Some(w) = st.writer.take() {
            st.stats.writer_blocked += w.since.elapsed();
            // SAFETY: as in `link_out`, with the roles swapped.
            return unsafe { self.link_complete(end, &mut st, ws, w, data, len, false) };
        }
        st.reader = Some(self.party(ws, data, len));
        drop(st);
        // SAFETY: `ws` is the running frame.
        unsafe { self.note_blocked(ws, what) };
        self.link_waiters += 1;
        Status::BLOCKED
    }

    fn party(&self, ws: Wptr, data: *mut u8, len: Word) -> Party {
        Party {
            desc: self.desc(ws),
            data: data as usize,
            len,
            mailbox: self.mailbox.clone(),
            since: Instant::now(),
        }
    }

    /// The second party moves the data and wakes the first.
    ///
    /// # Safety
    /// `other` is blocked with a buffer of `other.len` bytes; `mine` is ours, `len` bytes.
    #[allow(clippy::too_many_arguments, reason = "one communication's whole state")]
    unsafe fn link_complete(
        &mut self,
        end: &LinkEnd,
        st: &mut LinkState,
        ws: Wptr,
        other: Party,
        mine: *mut u8,
        len: Word,
        outputting: bool,
    ) -> Status {
        if other.len != len {
            // SAFETY: `ws` is the running frame.
            return unsafe {
                crate::error::rt_error(self, ws, ErrorKind::MessageLength as Word, -1)
            };
        }
        // SAFETY: caller contract.
        unsafe {
            if outputting {
                copy(mine, other.data as *mut u8, len);
            } else {
                copy(other.data as *const u8, mine, len);
            }
        }
        end.post(&other.mailbox, other.desc);
        st.stats.messages += 1;
        st.stats.bytes += len as u64;
        self.stats.communications += 1;
        Status::DONE
    }

    /// `enbc` on a link input: ready if a writer waits, else registers the ALTer.
    pub(crate) fn link_enable(&mut self, end: &LinkEnd, ws: Wptr) -> bool {
        let mut st = end.lock();
        if st.writer.is_some() {
            return true;
        }
        st.alt = Some((self.desc(ws) | tag::ALT, self.mailbox.clone()));
        self.link_waiters += 1;
        false
    }

    /// `disc` on a link input: unregisters the ALTer (withdrawing a wake-up already posted) and
    /// reports whether a writer waits.
    pub(crate) fn link_disable(&mut self, end: &LinkEnd, ws: Wptr) -> bool {
        let me = self.desc(ws) | tag::ALT;
        let (withdrawn, ready) = {
            let mut st = end.lock();
            let withdrawn = st.alt.as_ref().is_some_and(|(d, _)| *d == me);
            if withdrawn {
                st.alt = None;
            }
            (withdrawn, st.writer.is_some())
        };
        if withdrawn {
            self.link_waiters -= 1;
        } else {
            // Either this ALT never registered (the writer was already there), or a writer took
            // the registration and posted the wake-up under the link lock, so it is in the
            // mailbox by now: deliver the mail, dropping this ALT's own wake-up.
            let mail = self.mailbox.take_all();
            self.deliver(mail, Some(me));
        }
        ready
    }

    /// Delivers the mail posted so far, dropping `skip` (a withdrawn ALT wake-up).
    pub(crate) fn deliver_mail_except(&mut self, skip: Word) {
        let mail = self.mailbox.take_all();
        self.deliver(mail, Some(skip));
    }

    /// Requeues every descriptor posted by other nodes.
    pub(crate) fn drain_mailbox(&mut self) {
        if self.mailbox.has_mail() {
            let mail = self.mailbox.take_all();
            self.deliver(mail, None);
        }
    }

    /// Acts on taken mail: schedules plain descriptors, makes ALTers Ready; a descriptor equal to
    /// `skip` (a withdrawn ALT wake-up) is dropped.
    fn deliver(&mut self, mail: Vec<Word>, skip: Option<Word>) {
        for &desc in &mail {
            self.link_waiters -= 1;
            if Some(desc) == skip {
                continue;
            }
            if desc & tag::ALT != 0 {
                // SAFETY: an ALT-tagged mail names a live ALTing frame of this node that
                // registered at a link and has not disabled it (disable withdraws the mail).
                unsafe { self.alt_guard_ready(desc) };
            } else {
                self.schedule(desc);
            }
        }
        if let Some(net) = &self.net {
            net.sub(MAIL * mail.len() as u64);
        }
    }

    /// Waits for mail (or until `timeout`, when a timer is due). Without a timer the node counts
    /// as idle in its network; if the whole network is idle with no mail in flight, reports a
    /// deadlock.
    pub(crate) fn wait_mailbox(&mut self, timeout: Option<Duration>) -> Result<(), RunError> {
        let Some(net) = self.net.clone() else {
            // Links without a network cannot happen (connect needs one): just wait.
            self.mailbox.wait(timeout.unwrap_or(IDLE_POLL));
            return Ok(());
        };
        if let Some(d) = timeout {
            self.mailbox.wait(d);
            return Ok(());
        }
        net.add(IDLE);
        while !self.mailbox.wait(IDLE_POLL) {
            if net.is_stopped() {
                net.sub(IDLE);
                return Err(RunError::Halted(self.stopped_halt()));
            }
            if net.deadlocked() {
                // `run` calls `leave_network`, which counts this node idle for good.
                net.sub(IDLE);
                return Err(RunError::Deadlock(self.deadlock_report()));
            }
        }
        net.sub(IDLE);
        Ok(())
    }

    /// Counts this node as idle for good in its network (it has stopped): withdraws every
    /// registration its frames still have at links (their workspaces are about to go) and
    /// discards mail posted to it.
    pub(crate) fn leave_network(&mut self) {
        let Some(net) = self.net.clone() else {
            return;
        };
        if self.net_finished {
            return;
        }
        self.net_finished = true;
        for ext in &self.endpoints {
            if let Engine::LinkIn(end) | Engine::LinkOut(end) = &ext.engine {
                end.withdraw(&self.mailbox);
            }
        }
        let discarded = self.mailbox.take_all().len();
        net.sub(MAIL * discarded as u64);
        net.add(IDLE);
    }
}

impl Node {
    /// Whether this node's network has been stopped by a halting node.
    pub(crate) fn network_stopped(&self) -> bool {
        self.net.as_ref().is_some_and(|n| n.is_stopped())
    }

    /// Stops this node's network (it has halted).
    pub(crate) fn stop_network(&self) {
        if let Some(n) = &self.net {
            n.stop();
        }
    }

    /// The halt of a node stopped because another node failed.
    pub(crate) fn stopped_halt(&self) -> crate::error::Halt {
        crate::error::Halt {
            kind: Some(ErrorKind::Stopped),
            code: ErrorKind::Stopped as Word,
            location: None,
            proc_name: None,
            detail: None,
        }
    }
}
