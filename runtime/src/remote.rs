//! Links to nodes in other processes: the local half of such a link, and the relay that stands
//! in for the far node.
//!
//! A network spread over several processes (MPI ranks) places each node on one of them
//! ([`Spread`]). A link between two nodes of one process stays an in-process link
//! ([`crate::link`]); a link between processes becomes two halves, one in each process, each a
//! link direction whose far end is played by that process's [`Relay`]:
//!
//! - On the writer's side the relay waits at the link like an ALTing reader. When the writer
//!   arrives (and blocks), the relay copies its message and sends it as [`Msg::Data`]. The writer
//!   stays blocked until the reader's side answers [`Msg::Ack`]: then the relay releases it.
//! - On the reader's side the relay takes [`Msg::Data`] and offers it at the link like a blocked
//!   writer (waking an ALT on the link, or completing a reader that waits). When the reader has
//!   taken it, the relay sends [`Msg::Ack`].
//!
//! So a writer is released only when the reader has the whole message, as occam requires. The
//! relay does not move messages itself: the transport calls [`Relay::on_mail`] and
//! [`Relay::on_msg`] and sends what they push to `out`. Statistics of a link are split: messages,
//! bytes and the reader's blocked time on the reader's half, the writer's on the writer's half.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use crate::abi::Word;
use crate::endpoint::Engine;
use crate::link::{LinkEnd, MAIL, NetState, Network, Party};
use crate::mailbox::Mailbox;
use crate::node::Node;

/// Which process (rank) each node of a network runs in: balanced blocks in node order, node `i`
/// of `nodes` on rank `i * ranks / nodes`, so that neighbours in a ring, pipeline or tree
/// mostly share a rank.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Spread {
    /// This process's rank.
    pub rank: usize,
    /// How many ranks there are (at least 1).
    pub ranks: usize,
}

impl Spread {
    /// The rank that runs node `node` of `nodes`.
    pub fn owner(&self, node: usize, nodes: usize) -> usize {
        node * self.ranks / nodes.max(1)
    }

    /// Whether this rank runs node `node` of `nodes`.
    pub fn is_local(&self, node: usize, nodes: usize) -> bool {
        self.owner(node, nodes) == self.rank
    }
}

/// A message between relays.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Msg {
    /// The message a writer outputs on link `link`.
    Data {
        /// The link's number in the network plan (the same in every process).
        link: usize,
        /// The message.
        bytes: Vec<u8>,
    },
    /// The reader of link `link` has taken the last message: release the writer.
    Ack {
        /// The link's number.
        link: usize,
    },
}

/// The local half of a link whose other end is in another process.
#[derive(Debug)]
pub(crate) struct Half {
    end: LinkEnd,
    /// The link's number in the network plan.
    link: usize,
    /// The rank of the far end.
    peer: usize,
    /// Whether the local node writes (else it reads).
    writes: bool,
    /// On the reader's side, the message offered at the link until the reader takes it.
    offered: Option<Box<[u8]>>,
}

impl Network {
    /// Gives `node` one end of link `link` (the plan's number for it, the same in every
    /// process), whose other end is on rank `peer`: the output end if `writes`, else the input
    /// end. Returns the address of the end's channel word.
    pub fn connect_remote(
        &self,
        node: &mut Node,
        writes: bool,
        name: &str,
        link: usize,
        peer: usize,
    ) -> *mut Word {
        let end = self.link(name);
        let half = Half {
            end: end.clone(),
            link,
            peer,
            writes,
            offered: None,
        };
        crate::link::lock(&self.state.remote).push(half);
        if writes {
            node.add_endpoint(Engine::LinkOut(end), &format!("{name} (link out)"))
        } else {
            node.add_endpoint(Engine::LinkIn(end), &format!("{name} (link in)"))
        }
    }

    /// Stops the network (a node in another process halted).
    pub(crate) fn stop(&self) {
        self.state.stop();
    }
}

/// Carries a network's links between processes (MPI ranks): see `mpi::Mpi` with the `mpi`
/// feature.
pub trait Transport {
    /// This process's rank and the number of ranks.
    fn spread(&self) -> Spread;
    /// Runs this rank's `nodes` (all joined to `net`, with [`Network::connect_remote`] for the
    /// links to other ranks) on `threads` pool workers, relaying links to the other ranks,
    /// until the whole network has finished, deadlocked or stopped; returns each node with its
    /// outcome, in the order given.
    #[allow(clippy::vec_box, reason = "nodes are always boxed")]
    fn run(
        &mut self,
        net: &Network,
        nodes: Vec<Box<Node>>,
        threads: usize,
    ) -> Vec<(Box<Node>, Result<(), crate::RunError>)>;
    /// Gathers every rank's `blob` at rank 0: `Some` (in rank order) there, `None` elsewhere.
    fn gather(&mut self, blob: Vec<u8>) -> Option<Vec<Vec<u8>>>;
}

/// Stands in, in one process, for every node elsewhere that its nodes have links to.
#[derive(Debug)]
pub struct Relay {
    halves: Vec<Half>,
    /// Link number to index in `halves`.
    by_link: HashMap<usize, usize>,
    /// Where links post this relay's wake-ups: the index of the half.
    mailbox: Arc<Mailbox>,
    net: Arc<NetState>,
}

impl Relay {
    /// Takes over the remote halves of `net`'s links, waiting at each writer's half; returns
    /// the relay.
    pub fn new(net: &Network) -> Relay {
        let halves = std::mem::take(&mut *crate::link::lock(&net.state.remote));
        let by_link = halves
            .iter()
            .enumerate()
            .map(|(i, h)| (h.link, i))
            .collect();
        let relay = Relay {
            halves,
            by_link,
            mailbox: Arc::new(Mailbox::default()),
            net: net.state.clone(),
        };
        for i in 0..relay.halves.len() {
            if relay.halves[i].writes {
                relay.wait_for_writer(i);
            }
        }
        relay
    }

    /// Whether a link has posted a wake-up that [`Relay::on_mail`] has not taken.
    pub fn has_mail(&self) -> bool {
        self.mailbox.has_mail()
    }

    /// Sleeps up to `d` unless or until a link posts a wake-up.
    pub fn wait_mail(&self, d: std::time::Duration) {
        self.mailbox.wait(d);
    }

    /// Acts on the wake-ups links posted: a writer arrived (send its message), or a reader took
    /// an offered message (acknowledge it). Pushes (rank, message) pairs to send onto `out`.
    pub fn on_mail(&mut self, out: &mut Vec<(usize, Msg)>) {
        let mail = self.mailbox.take_all();
        self.net.sub(MAIL * mail.len() as u64);
        for token in mail {
            let i = token as usize;
            let half = &mut self.halves[i];
            if half.writes {
                let st = half.end.lock();
                if let Some(w) = &st.writer {
                    // SAFETY: the writer is blocked and registered: its buffer is valid for
                    // `w.len` bytes, and the lock keeps its node from withdrawing meanwhile.
                    let bytes = unsafe {
                        std::slice::from_raw_parts(w.data as *const u8, w.len.max(0) as usize)
                    }
                    .to_vec();
                    out.push((
                        half.peer,
                        Msg::Data {
                            link: half.link,
                            bytes,
                        },
                    ));
                }
            } else {
                half.offered = None;
                out.push((half.peer, Msg::Ack { link: half.link }));
            }
        }
    }

    /// Acts on a message from another process; pushes what to send onto `out`.
    pub fn on_msg(&mut self, msg: Msg, out: &mut Vec<(usize, Msg)>) {
        match msg {
            Msg::Data { link, bytes } => {
                if let Some(&i) = self.by_link.get(&link) {
                    self.offer(i, bytes.into_boxed_slice(), out);
                }
            }
            Msg::Ack { link } => {
                if let Some(&i) = self.by_link.get(&link) {
                    self.release_writer(i);
                }
            }
        }
    }

    /// Registers at writer half `i` like an ALTing reader: the next writer posts `i` here.
    fn wait_for_writer(&self, i: usize) {
        let half = &self.halves[i];
        let mut st = half.end.lock();
        if st.writer.is_some() {
            // A writer came before the relay waited: handle it as if it had posted.
            drop(st);
            half.end.post(&self.mailbox, i as Word);
        } else {
            st.alt = Some((i as Word, self.mailbox.clone()));
        }
    }

    /// The reader has the message of writer half `i`: release the writer and wait for the next.
    fn release_writer(&self, i: usize) {
        let half = &self.halves[i];
        {
            let mut st = half.end.lock();
            // No writer: its node stopped meanwhile.
            if let Some(w) = st.writer.take() {
                st.stats.writer_blocked += w.since.elapsed();
                half.end.post(&w.mailbox, w.desc);
            }
        }
        self.wait_for_writer(i);
    }

    /// Offers `bytes` at reader half `i` as a blocked writer would.
    fn offer(&mut self, i: usize, mut bytes: Box<[u8]>, out: &mut Vec<(usize, Msg)>) {
        let half = &mut self.halves[i];
        let mut st = half.end.lock();
        if let Some(r) = st.reader.take_if(|r| r.len as usize == bytes.len()) {
            // SAFETY: the reader is blocked with a buffer of `r.len` bytes, kept valid by the
            // lock (its node cannot withdraw meanwhile).
            unsafe {
                std::ptr::copy_nonoverlapping(bytes.as_ptr(), r.data as *mut u8, bytes.len())
            };
            st.stats.reader_blocked += r.since.elapsed();
            st.stats.messages += 1;
            st.stats.bytes += bytes.len() as u64;
            half.end.post(&r.mailbox, r.desc);
            out.push((half.peer, Msg::Ack { link: half.link }));
            return;
        }
        // The reader is not there yet. (A reader that waits with another length is left
        // waiting, unlike in-process where the writer halts: the run ends in a deadlock report.)
        st.writer = Some(Party {
            desc: i as Word,
            data: bytes.as_mut_ptr() as usize,
            len: bytes.len() as Word,
            mailbox: self.mailbox.clone(),
            since: Instant::now(),
        });
        if let Some((alter, mailbox)) = st.alt.take() {
            half.end.post(&mailbox, alter);
        }
        drop(st);
        half.offered = Some(bytes);
    }
}
