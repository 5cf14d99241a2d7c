//! Networks across MPI ranks (cargo feature `mpi`): the transport of [`crate::remote`].
//!
//! Every rank builds the same network plan and runs the nodes [`Spread`] gives it on a thread
//! pool; the calling thread (the one that initialised MPI) drives the rank's [`Relay`] and is the
//! only one that calls MPI. (OpenMPI's communicator handles are not `Send`, and OpenMPI has no
//! progress thread of its own: non-blocking operations advance only inside MPI calls, so the
//! driver polls.) It sends with non-blocking sends, so two ranks sending large messages to each
//! other cannot wait on each other, and when nothing happens it backs off from spinning to
//! yielding to sleeping on the relay's mailbox in slices of [`IDLE_SLEEP`].
//!
//! **Termination and deadlock.** A rank is *quiescent* when its pool has no node ready, running
//! or waiting for a timer, and its relay has nothing to act on. Rank 0 runs waves: it asks every
//! rank for (quiescent, messages sent, messages received), counting link messages and stop
//! notices. Two consecutive waves in which every rank is quiescent, the sums of sent and received
//! agree and no count changed show that nothing can move any more (Mattern's four-counter
//! method): rank 0 tells every rank to settle its pool, and each parked node reports its deadlock
//! as it would in one process.
//!
//! **Halting.** When a node halts, its rank's network stops and the driver tells every other rank,
//! which stops its own network; the halted node's error is the one reported.

use std::time::Duration;

use mpi::request::{Request, StaticScope};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::error::RunError;
use crate::link::Network;
use crate::node::Node;
use crate::pool::PoolView;
use crate::remote::{Msg, Relay, Spread, Transport};

/// How long an idle driver sleeps at a time (it wakes at once for local link traffic).
pub const IDLE_SLEEP: Duration = Duration::from_micros(100);

/// Idle polls that spin before the driver starts yielding, and then sleeping.
const SPIN_POLLS: u32 = 2000;
const YIELD_POLLS: u32 = 4000;

/// The minimum time between two termination waves that found work going on.
const WAVE_GAP: Duration = Duration::from_millis(1);

mod tag {
    pub const DATA: i32 = 1;
    pub const ACK: i32 = 2;
    pub const STOP: i32 = 3;
    pub const PROBE: i32 = 4;
    pub const REPLY: i32 = 5;
    pub const DONE: i32 = 6;
    pub const GATHER: i32 = 7;
}

/// This process's place among the MPI ranks.
pub struct Mpi {
    _universe: mpi::environment::Universe,
    world: SimpleCommunicator,
}

impl std::fmt::Debug for Mpi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Mpi(rank {} of {})",
            self.world.rank(),
            self.world.size()
        )
    }
}

impl Mpi {
    /// Initialises MPI (once per process). Without `mpirun` this is a singleton: one rank.
    pub fn init() -> Result<Mpi, String> {
        let (universe, _) = mpi::initialize_with_threading(mpi::Threading::Funneled)
            .ok_or_else(|| "MPI could not be initialised (or was already)".to_string())?;
        let world = universe.world();
        Ok(Mpi {
            _universe: universe,
            world,
        })
    }

    /// Plain MPI, for benchmarks to compare links against: `n` round trips of a `bytes`-byte
    /// message between rank 0 and rank `peer` (blocking send and receive; every other rank waits
    /// at a barrier). Returns the time the round trips took on rank 0 (zero elsewhere).
    pub fn raw_round_trips(&self, peer: usize, bytes: usize, n: u64) -> Duration {
        let (me, peer) = (self.world.rank(), peer as i32);
        let mut buf = vec![0u8; bytes];
        self.world.barrier();
        let start = std::time::Instant::now();
        if me == 0 || me == peer {
            let other = self.world.process_at_rank(if me == 0 { peer } else { 0 });
            for _ in 0..n {
                if me == 0 {
                    other.send(&buf[..]);
                    other.receive_into(&mut buf[..]);
                } else {
                    other.receive_into(&mut buf[..]);
                    other.send(&buf[..]);
                }
            }
        }
        let took = start.elapsed();
        self.world.barrier();
        if me == 0 { took } else { Duration::ZERO }
    }
}

impl Transport for Mpi {
    fn spread(&self) -> Spread {
        Spread {
            rank: self.world.rank() as usize,
            ranks: self.world.size() as usize,
        }
    }

    fn run(
        &mut self,
        net: &Network,
        nodes: Vec<Box<Node>>,
        threads: usize,
    ) -> Vec<(Box<Node>, Result<(), RunError>)> {
        let mut relay = Relay::new(net);
        let world = &self.world;
        Network::run_pool_driven(nodes, threads, |pool| {
            Driver::new(world).run(&mut relay, net, &pool);
        })
    }

    fn gather(&mut self, blob: Vec<u8>) -> Option<Vec<Vec<u8>>> {
        let me = self.world.rank();
        if me != 0 {
            self.world
                .process_at_rank(0)
                .send_with_tag(&blob[..], tag::GATHER);
            return None;
        }
        let mut all = vec![blob];
        for r in 1..self.world.size() {
            let (b, _) = self
                .world
                .process_at_rank(r)
                .receive_vec_with_tag::<u8>(tag::GATHER);
            all.push(b);
        }
        Some(all)
    }
}

/// A send in progress and the buffer it reads (leaked until the send completes).
struct Sending {
    request: Request<'static, [u8], StaticScope>,
    buf: *mut [u8],
}

/// The relaying loop of one rank.
struct Driver<'a> {
    world: &'a SimpleCommunicator,
    rank: i32,
    ranks: i32,
    sending: Vec<Sending>,
    /// Link messages and stop notices sent and received.
    sent: u64,
    received: u64,
    stop_sent: bool,
    done: bool,
    /// Rank 0: the current wave, its replies, and the counts of the last all-quiescent wave.
    wave: u64,
    replies: Vec<Option<(bool, u64, u64)>>,
    waiting: bool,
    last: Option<Vec<(u64, u64)>>,
    next_wave: std::time::Instant,
}

impl Driver<'_> {
    fn new(world: &SimpleCommunicator) -> Driver<'_> {
        Driver {
            world,
            rank: world.rank(),
            ranks: world.size(),
            sending: Vec::new(),
            sent: 0,
            received: 0,
            stop_sent: false,
            done: false,
            wave: 0,
            replies: Vec::new(),
            waiting: false,
            last: None,
            next_wave: std::time::Instant::now(),
        }
    }

    fn run(&mut self, relay: &mut Relay, net: &Network, pool: &PoolView<'_>) {
        let mut out = Vec::new();
        let mut idle = 0u32;
        while !self.done {
            let mut busy = false;
            if relay.has_mail() {
                relay.on_mail(&mut out);
                busy = true;
            }
            while let Some((msg, status)) = self.world.any_process().immediate_matched_probe() {
                let (t, from) = (status.tag(), status.source_rank());
                let (buf, _) = (msg, status).matched_receive_vec::<u8>();
                busy = true;
                self.on_receive(t, from, &buf, relay, net, pool, &mut out);
            }
            for (peer, m) in out.drain(..) {
                let (t, bytes) = encode(&m);
                self.send(peer as i32, t, bytes);
                self.sent += 1;
            }
            if net.stopped() && !self.stop_sent {
                self.stop_sent = true;
                let me = self.rank;
                for r in (0..self.ranks).filter(|&r| r != me) {
                    self.send(r, tag::STOP, Vec::new());
                    self.sent += 1;
                }
            }
            self.complete_sends();
            if self.rank == 0 {
                self.coordinate(relay, net, pool, out.is_empty());
            }
            if busy {
                idle = 0;
            } else {
                idle = idle.saturating_add(1);
                if idle < SPIN_POLLS {
                    std::hint::spin_loop();
                } else if idle < YIELD_POLLS {
                    std::thread::yield_now();
                } else {
                    relay.wait_mail(IDLE_SLEEP);
                }
            }
        }
        while !self.sending.is_empty() {
            self.complete_sends();
        }
        pool.settle();
    }

    #[allow(clippy::too_many_arguments, reason = "the driver's whole context")]
    fn on_receive(
        &mut self,
        t: i32,
        from: i32,
        buf: &[u8],
        relay: &mut Relay,
        net: &Network,
        pool: &PoolView<'_>,
        out: &mut Vec<(usize, Msg)>,
    ) {
        match t {
            tag::DATA | tag::ACK => {
                self.received += 1;
                if let Some(m) = decode(t, buf) {
                    relay.on_msg(m, out);
                }
            }
            tag::STOP => {
                self.received += 1;
                self.stop_sent = true;
                if !net.stopped() {
                    pool.stop(net);
                }
            }
            tag::PROBE => {
                let q = self.quiescent(relay, net, pool, out.is_empty());
                let mut r = buf.to_vec();
                r.push(q as u8);
                r.extend_from_slice(&self.sent.to_le_bytes());
                r.extend_from_slice(&self.received.to_le_bytes());
                self.send(from, tag::REPLY, r);
            }
            tag::REPLY if buf.len() == 25 => {
                let wave = word(buf, 0);
                if wave == self.wave && self.waiting {
                    self.replies[from as usize] = Some((buf[8] != 0, word(buf, 9), word(buf, 17)));
                }
            }
            tag::DONE => self.done = true,
            _ => {}
        }
    }

    /// Whether this rank will do nothing until a message comes: no node can run, and the
    /// relay has nothing to act on or to send (a stop notice included).
    fn quiescent(
        &self,
        relay: &Relay,
        net: &Network,
        pool: &PoolView<'_>,
        out_empty: bool,
    ) -> bool {
        // The pool first: a node posts to the relay, or stops the network, before it stops
        // running.
        pool.quiescent() && !relay.has_mail() && out_empty && (self.stop_sent || !net.stopped())
    }

    /// Rank 0: starts a wave when quiescent, and ends the run after two agreeing ones.
    fn coordinate(&mut self, relay: &Relay, net: &Network, pool: &PoolView<'_>, out_empty: bool) {
        if !self.waiting {
            if std::time::Instant::now() < self.next_wave
                || !self.quiescent(relay, net, pool, out_empty)
            {
                return;
            }
            self.wave += 1;
            self.waiting = true;
            self.replies = vec![None; self.ranks as usize];
            self.replies[0] = Some((true, self.sent, self.received));
            for r in 1..self.ranks {
                self.send(r, tag::PROBE, self.wave.to_le_bytes().to_vec());
            }
        }
        if self.replies.iter().any(Option::is_none) {
            return;
        }
        self.waiting = false;
        let replies: Vec<_> = self.replies.iter().flatten().copied().collect();
        let all_quiet = replies.iter().all(|r| r.0);
        let counts: Vec<(u64, u64)> = replies.iter().map(|r| (r.1, r.2)).collect();
        let balanced =
            counts.iter().map(|c| c.0).sum::<u64>() == counts.iter().map(|c| c.1).sum::<u64>();
        if all_quiet && balanced && self.last.as_ref() == Some(&counts) {
            for r in 1..self.ranks {
                self.send(r, tag::DONE, Vec::new());
            }
            self.done = true;
        } else {
            // Confirm an all-quiet balanced wave at once; after any other, let work go on.
            if !(all_quiet && balanced) {
                self.next_wave = std::time::Instant::now() + WAVE_GAP;
            }
            self.last = all_quiet.then_some(counts);
        }
    }

    fn send(&mut self, to: i32, t: i32, bytes: Vec<u8>) {
        let buf: &'static mut [u8] = Box::leak(bytes.into_boxed_slice());
        let ptr = buf as *mut [u8];
        let request = self
            .world
            .process_at_rank(to)
            .immediate_send_with_tag(StaticScope, &*buf, t);
        self.sending.push(Sending { request, buf: ptr });
    }

    fn complete_sends(&mut self) {
        let mut still = Vec::with_capacity(self.sending.len());
        for s in self.sending.drain(..) {
            match s.request.test() {
                // SAFETY: the send has completed: MPI no longer reads the buffer, which came
                // from `Box::leak` in `send`.
                Ok(_) => drop(unsafe { Box::from_raw(s.buf) }),
                Err(request) => still.push(Sending {
                    request,
                    buf: s.buf,
                }),
            }
        }
        self.sending = still;
    }
}

/// A little-endian u64 at `at` (zero if `b` is short).
fn word(b: &[u8], at: usize) -> u64 {
    b.get(at..at + 8)
        .map_or(0, |s| u64::from_le_bytes(s.try_into().unwrap_or([0; 8])))
}

fn encode(m: &Msg) -> (i32, Vec<u8>) {
    match m {
        Msg::Data { link, bytes } => {
            let mut b = Vec::with_capacity(8 + bytes.len());
            b.extend_from_slice(&(*link as u64).to_le_bytes());
            b.extend_from_slice(bytes);
            (tag::DATA, b)
        }
        Msg::Ack { link } => (tag::ACK, (*link as u64).to_le_bytes().to_vec()),
    }
}

fn decode(t: i32, b: &[u8]) -> Option<Msg> {
    if b.len() < 8 {
        return None;
    }
    let link = word(b, 0) as usize;
    match t {
        tag::DATA => Some(Msg::Data {
            link,
            bytes: b[8..].to_vec(),
        }),
        tag::ACK => Some(Msg::Ack { link }),
        _ => None,
    }
}
