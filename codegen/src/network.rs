//! Networks: compiling a program's `PLACED PAR`, and running a program on a network of nodes.
//!
//! A configured program (see `occ_compiler::network`) compiles once; every node runs its last
//! PROC. At the `PLACED PAR` the code calls `rt_placement`, which stores the node's
//! [`occ_runtime::placement::Placement`] (its replicator values and link channel words) into the
//! frame and returns the `PROCESSOR` process to run; the code switches on it.
//! [`Compiled::run_network`] builds the nodes, joins the links and runs them on a thread pool.
//! [`Compiled::run_topology`] runs a plain node PROC once per node of a [`Shape`] instead.
//! With a [`Transport`] (`run_network_over`, `run_topology_over`), every process (MPI rank)
//! builds the same plan, runs the nodes its [`occ_runtime::remote::Spread`] gives it, turns the
//! links between ranks into remote halves, and rank 0 gathers the outcome (see `crate::spread`).

use std::sync::Arc;

use cranelift_codegen::ir::InstBuilder;
use cranelift_frontend::Switch;
use occ_compiler::checked::SymbolId;
use occ_compiler::types::{ChanProtocol, Prim, ProtocolItem, Type};
use occ_grammar::ast::{Process, Span};
use occ_runtime::abi::{self, Entry, WORD_BYTES, Word, Wptr};
use occ_runtime::placement::Placement;
use occ_runtime::remote::{Spread, Transport};
use occ_runtime::topology::{LINKS, Shape};
use occ_runtime::{ErrorKind, HostIo, LinkStats, Network, Node, NodeConfig, RunError, Stats};

use crate::Compiled;
use crate::lower::{Res, Storage, Tr};
use crate::spread::{self, LinkPart};

/// What the code generator learnt of a configured network: per node what `rt_placement`
/// stores, and where each link's channel word sits in the frame.
#[derive(Clone, Debug, Default)]
pub struct NetworkLayout {
    /// Per node (in processor-number order): the PROCESSOR number and its placement without
    /// link words.
    pub processors: Vec<(i64, Placement)>,
    /// Per link: its name, the writer and reader node, and the byte offset of its channel word
    /// in the frame of the program's last PROC.
    pub links: Vec<(String, usize, usize, i32)>,
}

impl Tr<'_, '_> {
    /// Lowers the program's `PLACED PAR` (see the module doc).
    pub fn placed_par(&mut self, p: &Process) -> Res<()> {
        let Some(net) = self.cx.checked.network.as_ref() else {
            return Err(self.cx.internal(p.span, "PLACED PAR without a network"));
        };
        // A frame slot for every replicator of the configuration.
        let mut slots: Vec<(SymbolId, i32)> = Vec::new();
        for b in &net.branches {
            for &r in &b.replicators {
                if !slots.iter().any(|(s, _)| *s == r) {
                    let off = self.frame.alloc_word();
                    slots.push((r, off));
                    self.cx.env.insert(
                        r,
                        Storage::Var {
                            depth: self.depth,
                            offset: off,
                        },
                    );
                }
            }
        }
        let slot = |s: SymbolId| slots.iter().find(|(r, _)| *r == s).map_or(0, |(_, o)| *o);
        let processors = net
            .processors
            .iter()
            .map(|pl| {
                let reps = &net.branches[pl.branch].replicators;
                let stores = reps
                    .iter()
                    .zip(&pl.values)
                    .map(|(&r, &v)| (slot(r), v as Word))
                    .collect();
                (
                    pl.number,
                    Placement {
                        branch: pl.branch as Word,
                        stores,
                    },
                )
            })
            .collect();
        let mut links = Vec::new();
        for l in &net.links {
            let offset = match self.cx.env.get(&l.channel) {
                Some(Storage::Var { depth, offset }) if *depth == self.depth => {
                    offset + WORD_BYTES * l.element as i32
                }
                _ => {
                    let span = self.cx.checked.symbols[l.channel].span;
                    return Err(self.cx.unsupported(span, "a link channel declared here"));
                }
            };
            links.push((l.name.clone(), l.writer, l.reader, offset));
        }
        let branches: Vec<(Span, Option<&Process>)> = net
            .branches
            .iter()
            .map(|b| (b.span, occ_compiler::network::processor_body(p, b.span)))
            .collect();
        self.cx.network = Some(NetworkLayout { processors, links });
        let k = self.call_rt(Entry::Placement, &[self.node, self.ws]);
        let done = self.b.create_block();
        let none = self.b.create_block();
        let mut sw = Switch::new();
        let mut blocks = Vec::new();
        for (i, (span, body)) in branches.into_iter().enumerate() {
            let blk = self.b.create_block();
            sw.set_entry(i as u128, blk);
            let body = body.ok_or_else(|| self.cx.internal(span, "PROCESSOR body not found"))?;
            blocks.push((blk, body));
        }
        sw.emit(&mut self.b, k, none);
        for (blk, body) in blocks {
            self.b.switch_to_block(blk);
            self.process(body)?;
            self.b.ins().jump(done, &[]);
        }
        // The program was not started as a network (no placement): a STOP at the PLACED PAR.
        self.b.switch_to_block(none);
        self.halt(ErrorKind::Stop, p.span);
        self.b.switch_to_block(done);
        Ok(())
    }
}

/// How to run a network.
#[derive(Clone, Debug)]
pub struct NetworkOptions {
    /// Settings every node gets (its `name` is set per node).
    pub node: NodeConfig,
    /// Worker threads (at least 1).
    pub threads: usize,
}

/// What one node did.
#[derive(Debug)]
pub struct NodeOutcome {
    /// Its name in reports: `node 3`, or `PROCESSOR 7` for a configured network.
    pub name: String,
    /// How it ended.
    pub result: Result<(), RunError>,
    /// Its counters.
    pub stats: Stats,
    /// Time it spent running processes.
    pub busy: std::time::Duration,
}

/// What a network run did. Spread over ranks, rank 0 holds the whole run's outcome and the
/// other ranks an empty one.
#[derive(Debug)]
pub struct NetworkOutcome {
    /// Per node, in node order.
    pub nodes: Vec<NodeOutcome>,
    /// Per link direction.
    pub links: Vec<LinkStats>,
    /// Wall time of the run.
    pub elapsed: std::time::Duration,
}

impl NetworkOutcome {
    /// The errors that ended the run, one per failed node, leaving out the nodes stopped only
    /// because another failed: (node name, error).
    pub fn errors(&self) -> Vec<(&str, &RunError)> {
        self.nodes
            .iter()
            .filter_map(|n| match &n.result {
                Ok(()) => None,
                Err(RunError::Halted(h)) if h.kind == Some(ErrorKind::Stopped) => None,
                Err(e) => Some((n.name.as_str(), e)),
            })
            .collect()
    }
}

/// Nodes joined into one network, each with the words its links left on it.
struct Built {
    net: Network,
    #[allow(
        clippy::vec_box,
        reason = "nodes are always boxed: compiled code and links hold their addresses"
    )]
    nodes: Vec<Box<Node>>,
    /// Which nodes run in this process, when the network is spread over several.
    spread: Option<Spread>,
    /// Per link made here, in the order made: its number in the plan and which part is here.
    parts: Vec<(usize, LinkPart)>,
    /// The plan number of the next link.
    next_link: usize,
}

impl Built {
    /// `count` nodes named by `name`; node 0 gets `host`, the others host channels that are not
    /// connected.
    fn new(
        count: usize,
        info: &Arc<occ_runtime::ProgramInfo>,
        opts: &NetworkOptions,
        mut host: Option<HostIo>,
        spread: Option<Spread>,
        name: impl Fn(usize) -> String,
    ) -> Built {
        let net = Network::new();
        let nodes = (0..count)
            .map(|i| {
                let config = NodeConfig {
                    name: name(i),
                    ..opts.node.clone()
                };
                let io = host.take().unwrap_or_else(|| {
                    HostIo::new(
                        Box::new(std::io::empty()),
                        Box::new(std::io::sink()),
                        Box::new(std::io::sink()),
                    )
                });
                let mut node = Node::new(config, info.clone(), io);
                net.join(&mut node);
                node
            })
            .collect();
        Built {
            net,
            nodes,
            spread,
            parts: Vec::new(),
            next_link: 0,
        }
    }

    /// Whether node `i` runs in this process.
    fn is_local(&self, i: usize) -> bool {
        self.spread
            .is_none_or(|sp| sp.is_local(i, self.nodes.len()))
    }

    /// The host channels of node `i`: the real ones on node 0, unconnected ones elsewhere.
    fn host_channels(&mut self, i: usize) -> [*mut Word; 3] {
        let node = &mut self.nodes[i];
        if i == 0 {
            return node.host_channels();
        }
        ["keyboard", "screen", "error"].map(|c| {
            Network::unconnected(
                node,
                &format!("{c} (not connected: only node 0 has the host)"),
            )
        })
    }

    /// Joins a link direction from node `w` to node `r`; returns the channel words' values.
    /// Spread over ranks, only the ends on this rank's nodes are made (a word is 0 otherwise).
    fn connect(&mut self, w: usize, r: usize, name: &str) -> (Word, Word) {
        let id = self.next_link;
        self.next_link += 1;
        if let Some(sp) = self.spread {
            let n = self.nodes.len();
            let (lw, lr) = (sp.is_local(w, n), sp.is_local(r, n));
            if !(lw && lr) {
                let mut words = (0, 0);
                // SAFETY (both): `connect_remote` returns the address of the end's channel
                // word, alive as long as the node.
                if lw {
                    let c =
                        self.net
                            .connect_remote(&mut self.nodes[w], true, name, id, sp.owner(r, n));
                    words.0 = unsafe { *c };
                    self.parts.push((id, LinkPart::Writer));
                }
                if lr {
                    let c = self.net.connect_remote(
                        &mut self.nodes[r],
                        false,
                        name,
                        id,
                        sp.owner(w, n),
                    );
                    words.1 = unsafe { *c };
                    self.parts.push((id, LinkPart::Reader));
                }
                return words;
            }
        }
        self.parts.push((id, LinkPart::Whole));
        let (a, b) = if w == r {
            self.net.connect_loop(&mut self.nodes[w], name)
        } else {
            let (lo, hi) = self.nodes.split_at_mut(w.max(r));
            let (wn, rn) = if w < r {
                (&mut lo[w], &mut hi[0])
            } else {
                (&mut hi[0], &mut lo[r])
            };
            self.net.connect(wn, rn, name)
        };
        // SAFETY: `connect` returns the addresses of the endpoints' channel words, alive as long
        // as the nodes.
        unsafe { (*a, *b) }
    }

    /// Launches `entry` on every node (its frame filled by `frame(i, ws)`) and runs them all.
    fn run(
        mut self,
        c: &Compiled,
        threads: usize,
        mut transport: Option<&mut dyn Transport>,
        mut frame: impl FnMut(&mut Built, usize, Wptr) -> Result<(), RunError>,
    ) -> NetworkOutcome {
        let start = std::time::Instant::now();
        // A node that cannot start (its frame over its memory budget) still runs (with no
        // process, it finishes at once) so that its peers see it gone; its error is kept.
        let mut early: Vec<Option<RunError>> = (0..self.nodes.len()).map(|_| None).collect();
        for (i, failed) in early.iter_mut().enumerate() {
            if !self.is_local(i) {
                continue;
            }
            let words = c.entry_words as usize + abi::frame::ENTRY_SPARE_WORDS;
            let ws = match self.nodes[i].alloc_workspace(words) {
                Ok(ws) => ws,
                Err(e) => {
                    *failed = Some(e);
                    continue;
                }
            };
            // SAFETY: a fresh frame of `entry_words` words; its first two words are the static
            // link and the join word, zero for a process root.
            unsafe {
                *ws.offset(abi::frame::STATIC_LINK) = 0;
                *ws.offset(abi::frame::JOIN) = 0;
            }
            if let Err(e) = frame(&mut self, i, ws) {
                *failed = Some(e);
                continue;
            }
            // SAFETY: the frame is laid out for `c.entry` and filled.
            unsafe { self.nodes[i].spawn(ws, c.entry) };
        }
        let local: Vec<usize> = (0..self.nodes.len())
            .filter(|&i| self.is_local(i))
            .collect();
        let nodes: Vec<Box<Node>> = std::mem::take(&mut self.nodes)
            .into_iter()
            .enumerate()
            .filter_map(|(i, node)| local.contains(&i).then_some(node))
            .collect();
        let done = match transport.as_mut() {
            Some(t) => t.run(&self.net, nodes, threads),
            None => Network::run_pool(nodes, threads),
        };
        let nodes: Vec<(usize, NodeOutcome)> = done
            .into_iter()
            .zip(local)
            .map(|((node, result), i)| {
                let outcome = NodeOutcome {
                    name: node.config().name.clone(),
                    result: early[i].take().map_or(result, Err),
                    stats: node.stats().clone(),
                    busy: node.busy(),
                };
                (i, outcome)
            })
            .collect();
        let links = self.net.link_stats();
        let Some(t) = transport else {
            return NetworkOutcome {
                nodes: nodes.into_iter().map(|n| n.1).collect(),
                links,
                elapsed: start.elapsed(),
            };
        };
        let parts: Vec<_> = self
            .parts
            .iter()
            .zip(links)
            .map(|(&(id, part), l)| (id, part, l))
            .collect();
        let (nodes, links) = t
            .gather(spread::encode(&nodes, &parts))
            .map(|all| spread::merge(&all))
            .unwrap_or_default();
        NetworkOutcome {
            nodes,
            links,
            elapsed: start.elapsed(),
        }
    }
}

impl Compiled {
    /// Runs a configured program (one with a `PLACED PAR`) on its network: one node per
    /// PROCESSOR instance, node 0 (the lowest number) holding `host`. `None` when the program
    /// configures no network.
    pub fn run_network(&self, opts: &NetworkOptions, host: HostIo) -> Option<NetworkOutcome> {
        self.run_network_over(opts, host, None)
    }

    /// As [`Compiled::run_network`], spread over the processes of `transport` if given (every
    /// process calls this with the same program and options).
    pub fn run_network_over(
        &self,
        opts: &NetworkOptions,
        host: HostIo,
        transport: Option<&mut dyn Transport>,
    ) -> Option<NetworkOutcome> {
        let layout = self.network.as_ref()?;
        let spread = transport.as_deref().map(|t| t.spread());
        let mut built = Built::new(
            layout.processors.len(),
            &self.info,
            opts,
            Some(host),
            spread,
            |i| format!("PROCESSOR {}", layout.processors[i].0),
        );
        let mut stores: Vec<Placement> = layout.processors.iter().map(|p| p.1.clone()).collect();
        for (name, w, r, offset) in &layout.links {
            let (out, inp) = built.connect(*w, *r, name);
            stores[*w].stores.push((*offset, out));
            stores[*r].stores.push((*offset, inp));
        }
        for (node, p) in built.nodes.iter_mut().zip(stores) {
            node.set_placement(p);
        }
        let params = self.entry_params.clone();
        Some(built.run(self, opts.threads, transport, |b, i, ws| {
            let chans = b.host_channels(i);
            // SAFETY: the parameter offsets are inside the entry frame.
            unsafe {
                for (off, ch) in params.iter().zip(chans) {
                    *ws.byte_offset(*off as isize) = ch as Word;
                }
            }
            Ok(())
        }))
    }

    /// The most bytes of memory [`Compiled::run_topology`] can take on a node: the entry
    /// PROC's frame, which holds every process it runs (workspaces are static), the node's link
    /// channel words, each with its header, and the most bytes of large arrays its processes
    /// can hold at once (taken as their declarations run, so a node whose processes do not
    /// declare them takes less). A node's memory budget below the frame and links fails at the
    /// start, below the rest when a declaration finds too little left.
    pub fn topology_node_bytes(&self) -> usize {
        let header = abi::slot::HEADER_WORDS;
        let frame = self.entry_words as usize + abi::frame::ENTRY_SPARE_WORDS + header;
        let links = 2 * LINKS + header;
        (frame + links) * WORD_BYTES as usize + usize::try_from(self.entry_vectors).unwrap_or(0)
    }

    /// Runs the program's last PROC once per node of `shape`. It must take
    /// `(VAL INT id, nodes, []CHAN OF P in?, out!, ...)` with up to three byte channels after:
    /// `id` is the node's number, `nodes` their count, `in[k]`/`out[k]` link `k` (numbered as
    /// [`occ_runtime::topology`] says; an unconnected link never communicates), and the byte
    /// channels the host's keyboard, screen and error on node 0 (unconnected elsewhere).
    pub fn run_topology(
        &self,
        shape: Shape,
        opts: &NetworkOptions,
        host: HostIo,
    ) -> Result<NetworkOutcome, String> {
        self.run_topology_over(shape, opts, host, None)
    }

    /// As [`Compiled::run_topology`], spread over the processes of `transport` if given (every
    /// process calls this with the same program, shape and options).
    pub fn run_topology_over(
        &self,
        shape: Shape,
        opts: &NetworkOptions,
        host: HostIo,
        transport: Option<&mut dyn Transport>,
    ) -> Result<NetworkOutcome, String> {
        let slots = self.topology_slots()?;
        let n = shape.nodes();
        let spread = transport.as_deref().map(|t| t.spread());
        let mut built = Built::new(n, &self.info, opts, Some(host), spread, |i| {
            format!("node {i}")
        });
        // Each node's link channel words: [in 0..4, out 0..4].
        let mut words: Vec<[Word; 2 * LINKS]> = vec![[0; 2 * LINKS]; n];
        for ((a, ka), (b, kb)) in shape.directions() {
            let (out, inp) =
                built.connect(a, b, &format!("node {a} link {ka} -> node {b} link {kb}"));
            words[a][LINKS + ka] = out;
            words[b][kb] = inp;
        }
        for (i, w) in words.iter_mut().enumerate() {
            for (k, word) in w.iter_mut().enumerate() {
                if *word == 0 {
                    let (dir, link) = if k < LINKS {
                        ("in", k)
                    } else {
                        ("out", k - LINKS)
                    };
                    let name = format!("{dir}[{link}] (link {link} of node {i} is not connected)");
                    // SAFETY: the endpoint's channel word is alive as long as the node.
                    *word = unsafe { *Network::unconnected(&mut built.nodes[i], &name) };
                }
            }
        }
        Ok(built.run(self, opts.threads, transport, |b, i, ws| {
            // The link channel words live in their own workspace on the node.
            let arr = b.nodes[i].alloc_workspace(2 * LINKS)?;
            let chans = b.host_channels(i);
            // SAFETY: `arr` has `2 * LINKS` words; the parameter slots are inside the entry frame (array
            // parameters are an address word followed by a length word).
            unsafe {
                for (k, w) in words[i].iter().enumerate() {
                    *arr.add(k) = *w;
                }
                let put = |off: i32, v: Word| *ws.byte_offset(off as isize) = v;
                put(slots.id, i as Word);
                put(slots.nodes, n as Word);
                put(slots.links_in, arr as Word);
                put(slots.links_in + WORD_BYTES, LINKS as Word);
                put(slots.links_out, arr.add(LINKS) as Word);
                put(slots.links_out + WORD_BYTES, LINKS as Word);
                for (off, ch) in slots.host.iter().zip(chans) {
                    put(*off, ch as Word);
                }
            }
            Ok(())
        }))
    }

    /// The parameter slots of a node PROC, or why its signature does not fit.
    fn topology_slots(&self) -> Result<TopologySlots, String> {
        let want = format!(
            "PROC {} must take (VAL INT id, nodes, []CHAN OF P in?, out!) and then up to three CHAN BYTE (keyboard, screen, error) to run on a topology",
            self.entry_name
        );
        let p = &self.entry_param_slots;
        if p.len() < 4 || p.len() > 7 {
            return Err(want);
        }
        let int = |t: &Type| matches!(t, Type::Prim(Prim::Int));
        let links = |t: &Type| matches!(t, Type::Array(None, e) if matches!(**e, Type::Chan(..)));
        let ok = p[0].1
            && int(&p[0].2)
            && p[1].1
            && int(&p[1].2)
            && !p[2].1
            && links(&p[2].2)
            && !p[3].1
            && links(&p[3].2)
            && p[4..].iter().all(|s| is_byte_chan(&s.2));
        if !ok {
            return Err(want);
        }
        Ok(TopologySlots {
            id: p[0].0,
            nodes: p[1].0,
            links_in: p[2].0,
            links_out: p[3].0,
            host: p[4..].iter().map(|s| s.0).collect(),
        })
    }
}

/// Where a node PROC's parameters go in its frame (byte offsets).
struct TopologySlots {
    id: i32,
    nodes: i32,
    links_in: i32,
    links_out: i32,
    host: Vec<i32>,
}

/// Whether `t` is a channel the host can stand behind (`CHAN BYTE` or `CHAN OF ANY`).
pub(crate) fn is_byte_chan(t: &Type) -> bool {
    match t {
        Type::Chan(p, _) => matches!(
            **p,
            ChanProtocol::Simple(ProtocolItem::Data(Type::Prim(Prim::Byte))) | ChanProtocol::Any
        ),
        _ => false,
    }
}
