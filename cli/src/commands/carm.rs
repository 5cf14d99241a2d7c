//! The host side of `programs/carm.occ` (`occ radiosity --solver carm`): the `occ` process plays
//! the transputer host. It compiles the node program, writes the meshed scene into the root's
//! keyboard channel in the host protocol of `programs/README.md`, runs the program on a ternary
//! tree of `--nodes` simulated transputers, reads the convergence record and the results back
//! from the root's screen channel, and books them into a [`Solver`] so that the outputs are
//! written exactly as for the reference solver.
//!
//! The host does no radiosity: it sends the reference solver's octree in its flat form (tree,
//! frame, voxels) and the mesh, and books what the nodes report (per shot, the power each patch
//! received; at the end, the irradiance at every sample point).

use std::collections::VecDeque;
use std::f64::consts::PI;
use std::fs::File;
use std::io::{Cursor, Read, Seek, SeekFrom};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use glam::{DVec3, Vec3};
use occ_codegen::network::{NetworkOptions, NetworkOutcome};
use occ_radiosity::intrinsics::weights::mesh_weights;
use occ_radiosity::mesh::Mesh;
use occ_radiosity::octree::flat::{FlatOctree, MAX_NAMED_TRIANGLES, NAMED_TRIANGLE_FLOATS};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::quadrature::MeanRule;
use occ_radiosity::quadrature::weights::Supports;
use occ_radiosity::solver::{ConvergencePoint, Solver, Until};
use occ_runtime::remote::Transport;
use occ_runtime::topology::Shape;
use occ_runtime::{HostIo, NodeConfig};

use crate::frontend::{self, Options};

/// The node program, embedded so that `occ radiosity` works from any folder.
pub const PROGRAM: &str = include_str!("../../../programs/carm.occ");

/// The files carm.occ includes from `programs/` (the parts it shares with carm-named.occ),
/// embedded with it. A `--program FILE` finds its includes beside FILE instead.
const PROGRAM_INCLUDES: &[(&str, &str)] = &[
    (
        "carm-common.inc",
        include_str!("../../../programs/carm-common.inc"),
    ),
    (
        "carm-worker-state.inc",
        include_str!("../../../programs/carm-worker-state.inc"),
    ),
    (
        "carm-worker-arrays.inc",
        include_str!("../../../programs/carm-worker-arrays.inc"),
    ),
    (
        "carm-worker-shots.inc",
        include_str!("../../../programs/carm-worker-shots.inc"),
    ),
    (
        "carm-node.inc",
        include_str!("../../../programs/carm-node.inc"),
    ),
];

/// Most nodes carm.occ takes (its `MAX.NODES`; each node's arrays take about 9 MB).
const MAX_NODES: usize = 1024;

/// The backing store's file name in the output folder: every voxel's block of REAL32s,
/// little-endian, in voxel order.
pub const BACKING_STORE: &str = "backing-store.bin";

/// carm.occ's fixed limits that spreading the voxels must respect (its `FETCHES` and
/// `MAX.QUEUE`): the voxels a node asks for at a time, and a link queue's messages. A link
/// queue's REAL32s (its capacity `QUEUE.FLOATS`) hold every node's fetches of the largest voxel,
/// at most [`QUEUE_FLOATS_MOST`]; its voxel pool, `MAX.POOL`, is sized from `--node-memory`.
const FETCHES: usize = 8;

/// carm.occ's `MAX.PROBES`: the midpoints one round of adaptive subdivision evaluates; a round
/// adds at most ten element corners to a node and two elements a midpoint (its `ROUND.CORNERS`,
/// `ROUND.ELEMENTS`), the room it keeps free.
const MAX_PROBES: usize = 256;
const MAX_QUEUE: usize = FETCHES * MAX_NODES;
const QUEUE_FLOATS_MOST: usize = 262_144;

/// The patches one part of a shot's report names at most (carm.occ's `PART.PATCHES`; the
/// program refuses a `MAX.REPORT` that cannot hold a part), and the likely next shooters whose
/// elements the last part carries (its `CANDIDATES`).
const PART_PATCHES: usize = 4096;
const CANDIDATES: usize = 4;

/// The INTs of a node's counters (carm.occ's `COUNTERS`).
const COUNTERS: usize = 15;

/// Most INTs of a program's own counters after those (`MAX.COUNTERS` less `COUNTERS`).
const MAX_MORE_COUNTERS: usize = 9;

/// Loop back-edges per timeslice when `--threads 1` makes runs repeat exactly (as `occ run`).
const COUNTED_SLICE: u32 = 1024;

/// Host protocol tags the root writes (programs/README.md, "Host protocol").
mod tag {
    pub const END: i32 = 0;
    pub const SHOT: i32 = 1;
    pub const RESULT: i32 = 2;
    pub const COUNTERS: i32 = 3;
    pub const PATCHES: i32 = 4;
    pub const REFUSED: i32 = 5;
    pub const READ: i32 = 6;
    pub const REHASHED: i32 = 7;
    pub const SPLIT: i32 = 8;
    pub const MORE_COUNTERS: i32 = 9;
    pub const RECEIVED: i32 = 10;
    pub const SOURCE: i32 = 11;
}

/// How to run carm.occ.
#[derive(Clone, Debug)]
pub struct CarmSettings {
    /// Nodes of the ternary tree.
    pub nodes: usize,
    /// OS threads running the nodes (1: deterministic timeslicing).
    pub threads: usize,
    /// The node program to run instead of carm.occ (its file name and text): any program that
    /// speaks the same host protocol.
    pub program: Option<(String, String)>,
    /// A node holds at most this many times its even share of the sample points (and of their
    /// element corners); a point whose hash names a full node is re-hashed to another.
    pub load_tolerance: f64,
    /// Worker tasks a node runs at high priority (`--tasks`, at least 1).
    pub tasks: usize,
    /// Worker threads a node runs at low priority (`--worker-threads`).
    pub worker_threads: usize,
    /// Task poaching: a node that runs out of receivers in a shot asks its neighbours for some
    /// of theirs (`--no-poach`: false).
    pub poach: bool,
    /// Each channel of a shot from where its own unshot power lies when the channels lie
    /// differently over the shooter, as the reference solver shoots (`--summed-density`:
    /// false, every channel from the channels' summed density).
    pub channel_grids: bool,
    /// The voxels spread over the nodes (`--node-memory`, `--cache`); `None`: every voxel on
    /// every node.
    pub memory: Option<Memory>,
}

/// How the voxels are spread: each node keeps a share and a cache, the rest stays on the
/// backing store.
#[derive(Clone, Debug)]
pub struct Memory {
    /// Bytes of voxels a node may keep, share and cache together (`--node-memory`).
    pub node: u64,
    /// Bytes of a node's cache (`--cache`).
    pub cache: u64,
    /// The backing store file the host writes and serves voxel reads from.
    pub store: PathBuf,
}

/// The most worker tasks and threads a node runs together: each holds its batch's scratch
/// (about 0.8 MB), and its parked batch is kept by the database manager (as much again).
const MOST_WALKERS: usize = 16;

/// The most receivers one node lends another at once when poaching (carm.occ's `LOAN`).
const LOAN: usize = 256;

/// The default [`CarmSettings::load_tolerance`].
pub const LOAD_TOLERANCE: f64 = 1.25;

/// Called after each shot with the shots so far and the unshot fraction before the last one.
pub type OnShot = Box<dyn FnMut(u64, f64) + Send>;

/// One node's counters, as carm.occ reports them and the runtime measured them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct NodeCounters {
    /// Node number.
    pub node: usize,
    /// Sample points it owns.
    pub points: u64,
    /// Element corners at those points.
    pub corners: u64,
    /// Form factors it computed.
    pub form_factors: u64,
    /// Shadow rays it cast.
    pub rays: u64,
    /// Voxels of the octree it held at the end.
    pub voxels: u64,
    /// Their bytes.
    pub voxel_bytes: u64,
    /// Sample points it took as a later choice, their first choice being full.
    pub rehashed: u64,
    /// The most bytes of voxels it held at once (its share and its cache).
    pub voxel_bytes_peak: u64,
    /// The bytes of voxels it may hold (`--node-memory`; absent when every node holds every
    /// voxel).
    pub voxel_budget: Option<u64>,
    /// Its share's bytes: the voxels it keeps for the others and never evicts.
    pub share_bytes: u64,
    /// Walks of a receiver's shadow rays (one `RAD.RAYS.WALK` to the end, fetching on the way).
    pub walks: u64,
    /// Walks answered from the voxels held, with no fetch (cache hits, counted per walk).
    pub cache_hits: u64,
    /// Voxels it fetched (cache misses, counted per voxel; a voxel that several rays of a walk
    /// wait for is fetched once).
    pub cache_misses: u64,
    /// Of those, the voxels the host read from the backing store.
    pub store_reads: u64,
    /// Fetches it answered from its share.
    pub fetches_served: u64,
    /// Task poaching (programs/README.md, "Task poaching"): the times it ran out of receivers
    /// in a shot and asked a neighbour for some.
    pub poaches: u64,
    /// Receivers its neighbours lent it, whose form factors it computed (poached tasks).
    pub poached: u64,
    /// Its own receivers it lent its neighbours.
    pub lent: u64,
    /// Channel communications (soft and link) it made.
    pub communications: u64,
    /// Fraction of the wall time it spent running processes.
    pub busy: f64,
    /// Peak workspace, bytes.
    pub peak_bytes: u64,
    /// The naming scheme's caches (carm-named.occ), absent for carm.occ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub named: Option<NamedCounters>,
}

/// A node's figures of the naming scheme (programs/README.md, "The naming scheme"): its
/// voxel cache (assembled voxels) and its triangle cache.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct NamedCounters {
    /// Assembled voxels its walks tested (counted once a walk pass).
    pub voxel_hits: u64,
    /// Voxels it assembled (each a miss of the voxel cache).
    pub voxel_misses: u64,
    /// Name blocks it fetched from other nodes or the backing store (the others came from its
    /// share).
    pub names_fetched: u64,
    /// Triangles the assembled voxels named that it held (share or triangle cache).
    pub triangle_hits: u64,
    /// Triangles it fetched, one request each (triangle cache misses).
    pub triangle_misses: u64,
}

/// One link direction's traffic.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LinkCounters {
    /// Which link.
    pub link: String,
    /// Messages carried.
    pub messages: u64,
    /// Bytes carried.
    pub bytes: u64,
}

/// What a carm.occ run reported beside the solution it booked.
#[derive(Clone, Debug, Default)]
pub struct CarmReport {
    /// Per node.
    pub nodes: Vec<NodeCounters>,
    /// Per link direction.
    pub links: Vec<LinkCounters>,
    /// The PROCs, FUNCTIONs and intrinsics of the program that nothing calls, not compiled.
    pub left_out: occ_codegen::reach::LeftOut,
    /// The parts of shots' reports that reached the host before their shot's message (a
    /// report naming more than carm.occ's `PART.PATCHES` patches comes in parts).
    pub report_parts: u64,
}

/// Runs carm.occ on `solver`'s scene and mesh and books its solution into `solver` (irradiance,
/// unshot power, accounts, convergence record, counters). The solver must be fresh (no shot yet)
/// and without adaptive subdivision. `on_shot` hears of each shot as the root reports it.
///
/// With a `transport` (MPI), every process calls this with the same scene, mesh and settings
/// and runs its share of the nodes; the one holding node 0 (rank 0) plays the host, books the
/// solution and gets the report of every node and link, the others get `None`.
pub fn solve(
    solver: &mut Solver,
    settings: &CarmSettings,
    on_shot: OnShot,
    transport: Option<&mut dyn Transport>,
) -> anyhow::Result<Option<CarmReport>> {
    anyhow::ensure!(
        (1..=MAX_NODES).contains(&settings.nodes),
        "--nodes {}: carm.occ runs on 1 to {MAX_NODES} nodes",
        settings.nodes
    );
    let host_here = transport.as_deref().is_none_or(|t| t.spread().rank == 0);
    let flat = solver
        .octree
        .flat()
        .map_err(|e| anyhow::anyhow!("carm.occ cannot take the scene's octree: {e}"))?;
    let named = settings
        .program
        .as_ref()
        .is_some_and(|(_, text)| declares(text, "MAX.TRIANGLES"));
    if let Some((name, text)) = &settings.program {
        anyhow::ensure!(
            solver.config().element_means == MeanRule::Linear || declares(text, "QUADRATIC"),
            "--program {name} does not book by the quadratic rule (it declares no QUADRATIC \
             capacity, programs/README.md, \"Quadratic booking\"): run it with --element-means linear"
        );
        anyhow::ensure!(
            solver.config().element_means == MeanRule::Linear
                || mesh_kept(solver)
                || declares(text, "MESH.KEPT"),
            "--program {name} cannot take the corner weights the host deals where no point can \
             be added (it declares no MESH.KEPT capacity, programs/README.md, \"The mesh at the \
             host\"): run it with --element-means linear, or with points to add (--max-vertices)"
        );
    }
    let items = if named {
        Items::named(solver, &flat)?
    } else {
        Items::voxels(&flat)
    };
    // the points each element keeps corners at on the nodes, by the rule it books by
    let supports = Supports::new(&solver.mesh, solver.config().element_means);
    let corners_at = supports.at_vertices(solver.mesh.vertices.len());
    // how the controller deals the points: the corners at each, and the coherence grid
    let dealing = (
        corners_at.as_slice(),
        coherence_grid(&solver.mesh, settings),
    );
    let (input, store, sources) = if host_here {
        host_input(solver, &flat, &items, settings, dealing)?
    } else {
        (Vec::new(), None, None)
    };
    let capacities = capacities(solver, &flat, &items, settings, &supports, dealing)?;
    let shares = store.as_ref().map(|s| s.shares.clone());
    let reads = store.as_ref().map(|s| s.reads.clone());
    let answers = Pipe::default();
    let compiled = match &settings.program {
        Some((name, text)) => compile(name, &sized(text, &capacities).0, false)?,
        None => {
            let (text, found) = sized(PROGRAM, &capacities);
            anyhow::ensure!(
                found == capacities.len(),
                "carm.occ declares {found} of its {} capacities",
                capacities.len()
            );
            compile("carm.occ", &text, true)?
        }
    };
    let shape: Shape = format!("tree3:{}", settings.nodes)
        .parse()
        .map_err(|e| anyhow::anyhow!("--nodes {}: {e}", settings.nodes))?;
    let screen = SharedBuf::default();
    let errors = SharedBuf::default();
    let tap = Screen {
        bytes: screen.clone(),
        decoded: 0,
        broken: false,
        on_shot,
        store,
        sources,
        answers: answers.clone(),
    };
    let keyboard = Keyboard {
        first: Cursor::new(input),
        more: answers,
    };
    let host = HostIo::new(Box::new(keyboard), Box::new(tap), Box::new(errors.clone())).binary();
    // Every node's processes live in the program's frame, sized for the scene by its
    // capacities: a node gets the room that takes (more than the runtime's default only for
    // large scenes), reported as its peak_bytes.
    let mut node = NodeConfig::default();
    node.memory_budget = node.memory_budget.max(compiled.topology_node_bytes());
    if settings.threads == 1 {
        node.counted_slices = Some(COUNTED_SLICE);
    }
    let opts = NetworkOptions {
        node,
        threads: settings.threads,
    };
    let outcome = compiled
        .run_topology_over(shape, &opts, host, transport)
        .map_err(|e| anyhow::anyhow!("carm.occ: {e}"))?;
    if !host_here {
        return Ok(None);
    }
    let out = screen.take();
    if out.starts_with(&tag::REFUSED.to_le_bytes()) {
        // The controller refused the scene and stopped; the other nodes' fate is no news.
        book(solver, &out)?;
    }
    let failed: Vec<String> = outcome
        .errors()
        .iter()
        .map(|(name, e)| format!("{name}: {e}"))
        .collect();
    let text = String::from_utf8_lossy(&errors.take()).into_owned();
    anyhow::ensure!(
        failed.is_empty(),
        "carm.occ failed:\n{}{}",
        failed.join("\n"),
        text
    );
    let booked = book(solver, &out)?;
    let memory = settings
        .memory
        .as_ref()
        .zip(shares)
        .zip(reads)
        .map(|((m, shares), reads)| {
            let reads = reads.lock().unwrap_or_else(|e| e.into_inner()).clone();
            (m.node, shares, reads)
        });
    Ok(Some(CarmReport {
        left_out: compiled.left_out,
        ..report(&outcome, booked, memory)
    }))
}

/// The values of carm.occ's capacities (`VAL INT NAME IS n:` in its capacities block) for
/// `solver`'s scene on `settings.nodes` nodes: the scene's counts, and per node its share of the
/// sample points (shared by the nodes but the root, when there are others) and of their
/// element corners times the load tolerance (with room for one more point's corners), beyond
/// which the controller re-hashes a point to another node, the most patches a node has corners
/// of (`node_patches`), and the worker tasks and threads a node runs. `supports` lists the points
/// each element keeps corners at, `corners_at` how many each point keeps, `grid` the coherence
/// grid the controller deals them by (`coherence_grid`).
fn capacities(
    solver: &Solver,
    flat: &FlatOctree,
    items: &Items,
    settings: &CarmSettings,
    supports: &Supports,
    (corners_at, grid): (&[usize], [f32; 4]),
) -> anyhow::Result<Vec<(&'static str, usize)>> {
    anyhow::ensure!(
        (1..=MOST_WALKERS).contains(&settings.tasks)
            && settings.tasks + settings.worker_threads <= MOST_WALKERS,
        "--tasks {} --worker-threads {}: a node runs 1 to {MOST_WALKERS} tasks, and at most \
         {MOST_WALKERS} tasks and threads together",
        settings.tasks,
        settings.worker_threads
    );
    let tolerance = settings.load_tolerance;
    anyhow::ensure!(
        tolerance.is_finite() && tolerance >= 1.0,
        "--load-tolerance {tolerance}: a node must be able to hold at least its even share (1 or more)"
    );
    let mesh = &solver.mesh;
    let rule = solver.config().element_means;
    let most_at_one = corners_at.iter().copied().max().unwrap_or(0);
    // the nodes that keep sample points: all but the root, when there are others
    let keepers = settings.nodes.saturating_sub(1).max(1);
    let share = |n: usize| (tolerance * n as f64 / keepers as f64).ceil() as usize;
    let floats = |bytes: u64| bytes.div_ceil(4) as usize;
    // Adaptive subdivision adds up to `growth` points, each splitting an edge of one or two
    // elements (two new elements), and each split element brings five corners (programs/
    // README.md, "Adaptive subdivision"), on whichever nodes keep its points.
    let points = point_budget(solver);
    let growth = points - mesh.vertices.len();
    let round = |n: usize| if growth > 0 { n * MAX_PROBES } else { 0 };
    let elements = mesh.elements.len() + 2 * growth + round(2);
    let most_at_first = most_elements_of_one_patch(mesh);
    let most_in_one = most_at_first + 2 * growth;
    let node_points = share(points).min(points);
    // (a split's corners, five by the corners' average; by the quadratic rule the new
    // elements' and the new point's weights, about 45: carm-common.inc's ROUND.CORNERS)
    let per_point = match rule {
        MeanRule::Linear => 10,
        MeanRule::Quadratic => 64,
    };
    let dealt_corners: usize = corners_at.iter().sum();
    let node_corners = share(dealt_corners + per_point * growth) + most_at_one + round(per_point);
    // where no point can be added the mesh never changes: the controller keeps none of it
    // (programs/README.md, "The mesh at the host")
    let kept = mesh_kept(solver);
    let mut capacities = vec![
        ("MAX.POINTS", points),
        ("MAX.MESH.POINTS", if kept { points } else { 1 }),
        ("MAX.MESH.ELEMENTS", if kept { elements } else { 1 }),
        // adaptive subdivision's arrays at the root: none when it can add no point
        ("MAX.REFINE.POINTS", if growth > 0 { points } else { 1 }),
        ("NODE.POINTS", node_points),
        ("NODE.CORNERS", node_corners),
        (
            "NODE.PATCHES",
            node_patches(
                mesh,
                (rule, supports, corners_at),
                grid,
                settings.nodes,
                node_points,
                node_corners,
                growth > 0,
            ),
        ),
        // the patches a node owns (carm-common.inc's patch.owner: round the nodes but the root)
        ("NODE.OWNED", mesh.patches.len().div_ceil(keepers)),
        ("MAX.ELEMENTS", elements),
        ("MAX.PATCH.ELEMENTS", most_in_one),
        ("MAX.PATCHES", mesh.patches.len()),
        // the patches' shares of their rows that land on the backs of sheets
        ("MAX.BACK", solver.back_shares().iter().map(Vec::len).sum()),
        ("MAX.TREE", flat.tree.len()),
        ("MAX.VOXELS", items.count()),
        // a node's voxels: all of them, or its share and cache within --node-memory (in the
        // naming scheme its items: all of them, or its share)
        (
            "MAX.POOL",
            settings
                .memory
                .as_ref()
                .map_or(items.floats(), |m| match items.named {
                    None => floats(m.node).min(items.floats() + floats(m.cache)),
                    Some(_) => floats(m.node - m.cache).min(items.floats()),
                }),
        ),
        ("MAX.VOXEL", items.largest()),
        // a link queue's room for voxel answers: every node's fetches of the largest voxel
        // when the voxels are spread (the check in `spread` keeps it within
        // QUEUE_FLOATS_MOST), one voxel's when every node holds them all (no fetches)
        (
            "QUEUE.FLOATS",
            items.largest().max(1)
                * match settings.memory {
                    Some(_) => (settings.nodes * FETCHES).min(MAX_QUEUE),
                    None => 1,
                },
        ),
        ("MAX.OBJECTS", solver.scene.objects.len()),
        ("TASKS", settings.tasks),
        // the nodes the controller deals points and corners to, a message's worth each
        ("DEAL.NODES", settings.nodes),
        // a part of a shot's report (3 a patch) with room for the candidates' elements, a
        // gather's (3 an element of one patch), a refining shot's (a row of 5 a sample point)
        (
            "MAX.REPORT",
            (3 * mesh.patches.len().min(PART_PATCHES) + 3 * CANDIDATES * most_at_first)
                .max(3 * most_in_one)
                .max(if growth > 0 { 5 * points } else { 0 })
                // a refinement round's form factors, each channel's too (channels apart)
                .max(if growth > 0 { 4 * MAX_PROBES } else { 0 }),
        ),
    ];
    if let Some(named) = &items.named {
        // the naming scheme's: its triangles, the largest voxel assembled, and a node's voxel
        // cache and triangle cache (every voxel assembled, or halves of --cache)
        let (walk, triangles) = settings
            .memory
            .as_ref()
            .map_or((flat.pool().len(), 1), |m| {
                let half = floats(m.cache) / 2;
                (half, (floats(m.cache) - half) / NAMED_TRIANGLE_FLOATS)
            });
        capacities.extend([
            ("MAX.TRIANGLES", named.triangles),
            ("MAX.BLOCK", named.largest_block),
            ("MAX.WALK", walk),
            ("MAX.TRI.CACHE", triangles),
        ]);
    }
    // every array holds at least one element; a node may run no worker threads, and lend
    // none of its receivers (no poaching)
    Ok(capacities
        .into_iter()
        .map(|(name, n)| (name, n.max(1)))
        .chain([
            ("THREADS", settings.worker_threads),
            ("LOAN", if settings.poach { LOAN } else { 0 }),
            ("CHANNEL.GRIDS", usize::from(settings.channel_grids)),
            ("QUADRATIC", usize::from(rule == MeanRule::Quadratic)),
            ("MESH.KEPT", usize::from(kept)),
        ])
        .collect())
}

/// The most patches a node has element corners of, as the controller deals the sample points
/// (`deal`), and with adaptive subdivision the most it can come to. By the corners' average a
/// split brings a node a patch new to it only through the new point's two corners (x, y and c
/// are corners of the element already), so a node with `c` corners of `p` patches at the start
/// has at most `p + (node_corners - c) / 2` of them (the controller keeps every node within
/// `node_corners`); by the quadratic rule a node has a corner of an element at each point of
/// its support, and any new corner may bring a new patch: `p + node_corners - c`. Never more
/// than the scene's patches; all of them when no node has room for some point (the
/// controller stops the run then).
fn node_patches(
    mesh: &Mesh,
    (rule, supports, corners_at): (MeanRule, &Supports, &[usize]),
    grid: [f32; 4],
    nodes: usize,
    node_points: usize,
    node_corners: usize,
    adapt: bool,
) -> usize {
    let all = mesh.patches.len();
    let Some(dealt) = deal(mesh, (corners_at, grid), nodes, node_points, node_corners) else {
        return all;
    };
    // The elements go grouped by patch (host_input), so a node's patches come one after another.
    let mut by_patch: Vec<usize> = (0..mesh.elements.len()).collect();
    by_patch.sort_by_key(|&e| mesh.elements[e].patch);
    let mut patches = vec![0usize; nodes];
    let mut last = vec![u32::MAX; nodes];
    for &e in &by_patch {
        let patch = mesh.elements[e].patch;
        for &v in supports.of(e) {
            let k = dealt.node[v as usize];
            if last[k] != patch {
                last[k] = patch;
                patches[k] += 1;
            }
        }
    }
    // the room adaptive subdivision may fill on node k
    let room = |k: usize| {
        let free = node_corners.saturating_sub(dealt.corners[k]);
        match (adapt, rule) {
            (false, _) => 0,
            (true, MeanRule::Linear) => free / 2,
            (true, MeanRule::Quadratic) => free,
        }
    };
    let most = (0..nodes).map(|k| patches[k] + room(k)).max().unwrap_or(0);
    most.min(all)
}

/// Where the controller's `place` (carm-common.inc) deals each sample point, and the corners
/// each node then holds.
struct Dealt {
    /// The node of each sample point.
    node: Vec<usize>,
    /// The element corners at each node's points.
    corners: Vec<usize>,
}

/// The controller's dealing of the mesh's sample points, in order: each to its hash's node
/// (`owner`, by the coherence `grid`), unless that node is full (`node_points` points, or
/// `node_corners` corners with the point's `corners_at`); then to a re-hash's, and after as many
/// re-hashes as nodes, to the next node with room (never the root when there are others).
/// `None` when no node has room for some point.
fn deal(
    mesh: &Mesh,
    (corners_at, grid): (&[usize], [f32; 4]),
    nodes: usize,
    node_points: usize,
    node_corners: usize,
) -> Option<Dealt> {
    let mut points = vec![0usize; nodes];
    let mut dealt = Dealt {
        node: Vec::with_capacity(mesh.vertices.len()),
        corners: vec![0; nodes],
    };
    for (v, &c) in mesh.vertices.iter().zip(corners_at) {
        let pn = [
            v.pos.x, v.pos.y, v.pos.z, v.normal.x, v.normal.y, v.normal.z,
        ];
        let full = |k: usize| points[k] >= node_points || dealt.corners[k] + c > node_corners;
        let mut at = owner(pn, grid, nodes, 0);
        let mut attempt = 0;
        while full(at) {
            attempt += 1;
            if attempt < nodes {
                at = owner(pn, grid, nodes, attempt);
            } else if attempt < 2 * nodes {
                at = (at + 1) % nodes;
                if at == 0 && nodes > 1 {
                    at = 1;
                }
            } else {
                return None;
            }
        }
        points[at] += 1;
        dealt.corners[at] += c;
        dealt.node.push(at);
    }
    Some(dealt)
}

/// Cells an axis of the coherence grid over the cube bounding the sample points
/// (`coherence_grid`).
/// Measured on the generated rooms spread over 13 nodes (programs/README.md, "Coherent
/// placement"): 8 fetched the fewest voxels of 4, 8, 16, 32 and 64.
pub const COHERENCE_CELLS: u32 = 8;

/// The grid whose cells' sample points the controller deals to one node (carm-common.inc's
/// `coherence.key`): its low corner and cell edge, [`COHERENCE_CELLS`] cells an axis over the
/// cube that bounds the sample points, when the voxels are spread, where a node's points that
/// lie together need fewer voxels fetched; an edge of 0 (each point dealt by its own hash,
/// spreading the work of every shot evenly) when every node holds every voxel. (Not the
/// octree's root box: it bounds only the triangles that can hide something.)
fn coherence_grid(mesh: &Mesh, settings: &CarmSettings) -> [f32; 4] {
    let (lo, hi) = mesh.vertices.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v.pos), hi.max(v.pos)),
    );
    let side = (hi - lo).max_element();
    match &settings.memory {
        Some(_) if side.is_finite() && side > 0.0 => {
            [lo.x, lo.y, lo.z, side / COHERENCE_CELLS as f32]
        }
        _ => [0.0; 4],
    }
}

/// The node of `nodes` that the controller's `owner` (carm-common.inc) names for a sample point
/// of position and normal `pn` at this attempt (0: the first choice): an FNV-style hash, as
/// occam's INT64 arithmetic computes it, of the point's coherence key (`coherence_key`) when
/// the `grid` has an edge, else of the six floats' bits, over the nodes but the root when
/// there are others.
fn owner(pn: [f32; 6], grid: [f32; 4], nodes: usize, attempt: usize) -> usize {
    let mut h = 1_469_598_103_934_665_603u64 ^ attempt as u64;
    if grid[3] > 0.0 {
        for k in coherence_key(pn, grid) {
            h = (h ^ k as u64).wrapping_mul(1_099_511_628_211);
        }
    } else {
        for x in pn {
            // INT64 of an INT32 extends its sign
            h = (h ^ i64::from(x.to_bits() as i32) as u64).wrapping_mul(1_099_511_628_211);
        }
    }
    h ^= h >> 29;
    h = h.wrapping_mul(2_654_435_761);
    h ^= h >> 32;
    if nodes > 1 {
        1 + ((h >> 1) % (nodes as u64 - 1)) as usize
    } else {
        0
    }
}

/// carm-common.inc's `coherence.key`: the cell of `grid` (low corner, edge) holding the point
/// `pn` (position, normal), each index clamped to 0 ..= 2^20, and the axis and sign its normal
/// points most along (0 to 5), in REAL32 as occam computes them.
fn coherence_key(pn: [f32; 6], grid: [f32; 4]) -> [i32; 4] {
    const TOP: i32 = 1 << 20;
    let cell = |j: usize| {
        let x = (pn[j] - grid[j]) / grid[3];
        if x.is_nan() || x <= 0.0 {
            0
        } else if x >= TOP as f32 {
            TOP
        } else {
            x as i32
        }
    };
    let most = (1..3).fold(0, |m, j| {
        if pn[3 + j].abs() > pn[3 + m].abs() {
            j
        } else {
            m
        }
    });
    let facing = 2 * most as i32 + i32::from(pn[3 + most] < 0.0);
    [cell(0), cell(1), cell(2), facing]
}

/// The most sample points the run may have: the mesh's, or with adaptive subdivision
/// `--max-vertices` when that is more (the reference solver's budget).
fn point_budget(solver: &Solver) -> usize {
    let points = solver.mesh.vertices.len();
    solver
        .config()
        .adapt
        .map_or(points, |a| a.max_vertices.max(points))
}

/// Whether the controller keeps the mesh: adaptive subdivision can add points to it. Where it
/// cannot, the host deals the corner weights and answers the shooter's elements instead
/// (programs/README.md, "The mesh at the host").
fn mesh_kept(solver: &Solver) -> bool {
    point_budget(solver) > solver.mesh.vertices.len()
}

/// The most elements of any one patch.
fn most_elements_of_one_patch(mesh: &Mesh) -> usize {
    let mut per_patch = vec![0usize; mesh.patches.len()];
    for e in &mesh.elements {
        per_patch[e.patch as usize] += 1;
    }
    per_patch.into_iter().max().unwrap_or(0)
}

/// `program` with the value of each `VAL INT NAME IS n:` line whose name `capacities` lists
/// set to its capacity, and how many of the names it found. Only whole declarations on a line
/// of their own are rewritten (a comment after the colon stays).
fn sized(program: &str, capacities: &[(&str, usize)]) -> (String, usize) {
    let mut found = 0;
    let mut out = String::with_capacity(program.len() + 64);
    for line in program.split_inclusive('\n') {
        let decl = line.strip_prefix("VAL INT ").and_then(|rest| {
            let (name, rest) = rest.split_once(" IS ")?;
            let (value, tail) = rest.split_once(':')?;
            value.trim().parse::<i64>().ok()?;
            let (_, n) = capacities.iter().find(|(c, _)| *c == name)?;
            Some(format!("VAL INT {name} IS {n}:{tail}"))
        });
        match decl {
            Some(d) => {
                found += 1;
                out.push_str(&d);
            }
            None => out.push_str(line),
        }
    }
    (out, found)
}

/// Compiles the node program `text` (named `name` in its diagnostics); `embedded`: carm.occ,
/// whose includes are embedded too, else a file whose includes are found beside it.
fn compile(name: &str, text: &str, embedded: bool) -> anyhow::Result<occ_codegen::Compiled> {
    let set = frontend::intrinsics();
    let (parsed, checked) = if embedded {
        let front = occ_codegen::front_end(name, text, &mut Embedded, &set);
        let map = &front.parsed.map;
        let diags: Vec<frontend::Diag> = front
            .diagnostics
            .iter()
            .map(|d| frontend::Diag::new(d, map))
            .collect();
        match front.checked {
            Some(checked) => (front.parsed, checked),
            None => bail_diags(name, &diags)?,
        }
    } else {
        let (front, checked) = frontend::load_text(name, text, &Options::default());
        match front {
            Some(front) => (front.parsed, front.checked),
            None => bail_diags(name, &checked.diagnostics)?,
        }
    };
    occ_codegen::compile_with(&parsed.program, &checked, &parsed.map, &set)
        .map_err(|e| anyhow::anyhow!("{name}: {e}"))
}

/// The error of a node program that does not compile.
fn bail_diags<T>(name: &str, diags: &[frontend::Diag]) -> anyhow::Result<T> {
    let lines: Vec<String> = diags
        .iter()
        .map(|d| format!("{}:{}: {}", d.file.display(), d.line, d.message))
        .collect();
    anyhow::bail!("{name} does not compile:\n{}", lines.join("\n"))
}

/// Finds carm.occ's includes among the embedded files, and the standard library's built in.
struct Embedded;

impl occ_grammar::preprocess::Loader for Embedded {
    fn load(&mut self, name: &str, _from: &str) -> Option<(String, String)> {
        match PROGRAM_INCLUDES.iter().find(|(n, _)| *n == name) {
            Some((n, text)) => Some((format!("programs/{n}"), text.to_string())),
            None => crate::stdlib::get(name).map(|text| {
                (
                    format!("{}/{name}", crate::stdlib::PREFIX),
                    text.to_string(),
                )
            }),
        }
    }
}

/// The host protocol's input: header, the octree's frame and tree, its voxels, patches, sample
/// points, elements (little-endian; INT is 4 bytes, INT64 and REAL64 8, REAL32 4). The octree is
/// the reference solver's own, in its flat form, so the nodes' shadow rays meet what its rays do.
fn host_input(
    solver: &Solver,
    flat: &FlatOctree,
    items: &Items,
    settings: &CarmSettings,
    (corners_at, grid): (&[usize], [f32; 4]),
) -> anyhow::Result<(Vec<u8>, Option<Store>, Option<Sources>)> {
    let config = solver.config();
    let (scene, mesh) = (solver.scene, &solver.mesh);
    // Negative: not a stopping rule of this run.
    let (until_unshot, until_error, max_shots) = match config.until {
        Until::Unshot(f) => (f, -1.0, config.max_shots),
        Until::Error(f) => (-1.0, f, config.max_shots),
        Until::Shots(n) => (-1.0, -1.0, n.min(config.max_shots)),
        Until::Seconds(_) => {
            anyhow::bail!("--solver carm takes --until error=F, unshot=F or shots=N")
        }
    };
    let int = |n: usize, what: &str| {
        i32::try_from(n).map_err(|_| anyhow::anyhow!("{what} ({n}) is too many for carm.occ"))
    };
    let voxels = items.count();
    let largest = items.largest();
    let spread = match &settings.memory {
        Some(memory) => Some(spread(items, memory, settings.nodes)?),
        None => None,
    };
    let mut w = Writer::default();
    w.int(int(flat.tree.len(), "the octree's tree INTs")?);
    w.int(int(voxels, "voxels")?);
    w.int(int(items.floats(), "the voxels' REAL32s")?);
    w.int(int(largest, "the largest voxel's REAL32s")?);
    w.int(int(mesh.patches.len(), "patches")?);
    w.int(int(mesh.vertices.len(), "sample points")?);
    w.int(int(mesh.elements.len(), "elements")?);
    // The elements go grouped by patch (in mesh order within each), as the controller keeps them.
    let mut by_patch: Vec<usize> = (0..mesh.elements.len()).collect();
    by_patch.sort_by_key(|&e| mesh.elements[e].patch);
    w.int(int(
        most_elements_of_one_patch(mesh),
        "elements in one patch",
    )?);
    w.int(config.form_factor.rays as i32);
    w.int64(config.seed as i64);
    w.real32(config.form_factor.offset);
    w.int(int(max_shots.min(i32::MAX as u64) as usize, "shots")?);
    w.real64(until_unshot);
    w.real64(config.overshoot);
    w.real64(until_error);
    w.int(int(scene.objects.len(), "objects")?);
    // What the error estimate needs (occ_radiosity::estimate): the surfaces' area and mean
    // reflectance, and per object its area, emitted radiosity and reflectance.
    let tally = solver.tally();
    w.real64(tally.total_area);
    for c in 0..3 {
        w.real64(tally.rho_avg[c]);
    }
    w.real64(config.full_rays_power);
    // Overshooting by the ambient estimate: off, always, or while the scene is stiff.
    w.int(match config.acceleration {
        Acceleration::Off => 0,
        Acceleration::Ambient => 1,
        Acceleration::Auto => 2,
    });
    // Closing each shot's form-factor row where the reference solver does (a closed scene:
    // every shot's power lands on its surfaces, or on the backs of sheets).
    w.int(i32::from(solver.stages.close_rows));
    // Casting shadow rays, unless no surface can hide another (a convex enclosure).
    w.int(i32::from(solver.stages.shadow_rays));
    // The cache's REAL32s, or -1: every voxel on every node.
    w.int(
        settings
            .memory
            .as_ref()
            .map_or(-1, |m| (m.cache / 4) as i32),
    );
    // Adaptive subdivision (the reference solver's settings), or 0 for none.
    match config.adapt {
        Some(adapt) => {
            w.int(1);
            w.real32(adapt.difference);
            w.real32(adapt.nonlinearity);
            w.real32(adapt.min_edge);
            w.real64(adapt.min_shot_power);
            w.int(int(adapt.passes as usize, "refinement passes")?);
            w.int(int(point_budget(solver), "--max-vertices")?);
        }
        None => {
            w.int(0);
            (0..3).for_each(|_| w.real32(0.0));
            w.real64(0.0);
            w.int(0);
            w.int(int(mesh.vertices.len(), "sample points")?);
        }
    }
    let mut object_area = vec![0.0f64; scene.objects.len()];
    for e in &mesh.elements {
        object_area[e.object as usize] += mesh.tri(e).area() as f64;
    }
    for (o, area) in scene.objects.iter().zip(object_area) {
        w.real64(area);
        let emitted = (o.emission * std::f32::consts::PI).as_dvec3();
        for c in 0..3 {
            w.real64(emitted[c]);
        }
        for c in 0..3 {
            w.real64(o.reflectance[c] as f64);
        }
    }
    for &x in &flat.frame {
        w.real32(x);
    }
    for &x in &flat.tree {
        w.int(x);
    }
    if let Some((home, _)) = &spread {
        for (v, &h) in home.iter().enumerate() {
            w.int(h);
            w.int(items.item(v).len() as i32);
        }
    }
    for v in 0..voxels {
        if spread.as_ref().is_some_and(|(home, _)| home[v] < 0) {
            continue;
        }
        let block = items.item(v);
        w.int(block.len() as i32);
        for &x in block {
            w.real32(x);
        }
    }
    for (((p, &o), u), back) in mesh
        .patches
        .iter()
        .zip(&mesh.patch_object)
        .zip(&solver.unshot)
        .zip(solver.back_shares())
    {
        for v in p.v {
            w.vec3(v);
        }
        w.real64(p.area() as f64);
        w.vec3(scene.objects[o as usize].reflectance);
        for c in 0..3 {
            w.real64(u[c]);
        }
        w.int(o as i32);
        w.int(back.len() as i32);
        back.iter().for_each(|&x| w.real32(x));
    }
    for x in grid {
        w.real32(x);
    }
    for (v, &c) in mesh.vertices.iter().zip(corners_at) {
        w.vec3(v.pos);
        w.vec3(v.normal);
        w.vec3(v.eval);
        w.int(int(c, "element corners at one sample point")?);
    }
    // Where no point can be added the controller keeps no mesh (programs/README.md, "The mesh
    // at the host"): each element comes with its corner weights by the quadratic rule, and the
    // host answers the shooter's elements' triangles and areas (`Sources`).
    let kept = mesh_kept(solver);
    let mut sources = (!kept).then(|| Sources {
        first: vec![0; mesh.patches.len()],
        count: vec![0; mesh.patches.len()],
        tris: Vec::with_capacity(by_patch.len()),
        areas: Vec::with_capacity(by_patch.len()),
    });
    // Element i (in the order sent), with its weights when it carries them.
    let mut element = |i: usize, weights: Option<&[(u32, f64)]>| {
        let e = &mesh.elements[by_patch[i]];
        for v in e.v {
            w.int(v as i32);
        }
        w.int(e.patch as i32);
        let area = mesh.tri(e).area() as f64;
        w.real64(area);
        let emitted = scene.objects[e.object as usize].emission.as_dvec3() * PI * area;
        for c in 0..3 {
            w.real64(emitted[c]);
        }
        if let Some(ws) = weights {
            // (an element's support: its corners and the elements around them, far below
            // i32::MAX)
            w.int(ws.len() as i32);
            for &(v, x) in ws {
                w.int(v as i32);
                w.real64(x);
            }
        }
        if let Some(s) = &mut sources {
            let p = e.patch as usize;
            if s.count[p] == 0 {
                s.first[p] = i;
            }
            s.count[p] += 1;
            s.tris
                .push(e.v.map(|v| mesh.vertices[v as usize].pos.to_array()));
            s.areas.push(area);
        }
    };
    if !kept && config.element_means == MeanRule::Quadratic {
        // over the arrays the controller would have weighed them over
        let corners: Vec<i32> = by_patch
            .iter()
            .flat_map(|&e| mesh.elements[e].v.map(|v| v as i32))
            .collect();
        let point: Vec<f32> = mesh
            .vertices
            .iter()
            .flat_map(|v| [v.pos, v.normal, v.eval])
            .flat_map(|v| v.to_array())
            .collect();
        mesh_weights(&corners, &point, |i, ws| element(i, Some(ws)))
            .ok_or_else(|| anyhow::anyhow!("the mesh's corner weights: a vertex out of range"))?;
    } else {
        (0..by_patch.len()).for_each(|i| element(i, None));
    }
    let store = match (&settings.memory, spread) {
        (Some(memory), Some((_, shares))) => Some(Store::write(&memory.store, items, shares)?),
        _ => None,
    };
    Ok((w.0, store, sources))
}

/// The mesh's elements as the host sends them (grouped by patch), for the controller's reads
/// of a shooter's elements when it keeps no mesh (host protocol, tag 11): patch p's are
/// `first[p] ..` for `count[p]`, each its triangle's corners and its area.
struct Sources {
    first: Vec<usize>,
    count: Vec<usize>,
    tris: Vec<[[f32; 3]; 3]>,
    areas: Vec<f64>,
}

impl Sources {
    /// The answer to a read of patch p's elements: INT k, then per element 9 REAL32 and a
    /// REAL64; k = -1 for a patch that does not exist.
    fn answer(&self, p: i32) -> Vec<u8> {
        let mut w = Writer::default();
        match usize::try_from(p).ok().filter(|&p| p < self.first.len()) {
            None => w.int(-1),
            Some(p) => {
                let range = self.first[p]..self.first[p] + self.count[p];
                w.int(self.count[p] as i32);
                for (tri, &area) in self.tris[range.clone()].iter().zip(&self.areas[range]) {
                    tri.iter().flatten().for_each(|&x| w.real32(x));
                    w.real64(area);
                }
            }
        }
        w.0
    }
}

/// The geometry the host sends in the host protocol's places for voxels: carm.occ's voxel
/// blocks, or the naming scheme's items (programs/README.md, "The naming scheme"): every
/// voxel's name block, then every triangle.
struct Items {
    /// Every item's REAL32s, item 0 first.
    pool: Vec<f32>,
    /// Item `i` is `pool[offsets[i] .. offsets[i + 1]]`.
    offsets: Vec<usize>,
    /// The naming scheme's sizes; `None` for carm.occ's voxels.
    named: Option<NamedSizes>,
}

/// What the naming scheme's capacities need to know of its items.
struct NamedSizes {
    /// Triangles (the items after the voxels' name blocks).
    triangles: usize,
    /// The REAL32s of the largest voxel assembled.
    largest_block: usize,
}

impl Items {
    /// carm.occ's: the voxels' blocks.
    fn voxels(flat: &FlatOctree) -> Items {
        let blocks = (0..flat.voxel_count()).map(|v| flat.voxel(v).to_vec());
        Items::of(blocks, None)
    }

    /// The naming scheme's: each voxel's name block, then each triangle.
    fn named(solver: &Solver, flat: &FlatOctree) -> anyhow::Result<Items> {
        let named = solver.octree.named(flat).ok_or_else(|| {
            anyhow::anyhow!(
                "the naming scheme names at most {MAX_NAMED_TRIANGLES} triangles; the scene has more"
            )
        })?;
        let sizes = NamedSizes {
            triangles: named.triangles.len(),
            largest_block: (0..flat.voxel_count())
                .map(|v| flat.voxel(v).len())
                .max()
                .unwrap_or(0),
        };
        let triangles = named.triangles.iter().map(|t| t.to_vec());
        Ok(Items::of(
            named.voxels.into_iter().chain(triangles),
            Some(sizes),
        ))
    }

    fn of(blocks: impl Iterator<Item = Vec<f32>>, named: Option<NamedSizes>) -> Items {
        let (mut pool, mut offsets) = (Vec::new(), vec![0]);
        for b in blocks {
            pool.extend(b);
            offsets.push(pool.len());
        }
        Items {
            pool,
            offsets,
            named,
        }
    }

    /// How many items.
    fn count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Item `i`'s REAL32s.
    fn item(&self, i: usize) -> &[f32] {
        &self.pool[self.offsets[i]..self.offsets[i + 1]]
    }

    /// All items' REAL32s.
    fn floats(&self) -> usize {
        self.pool.len()
    }

    /// The largest item's REAL32s.
    fn largest(&self) -> usize {
        (0..self.count())
            .map(|i| self.item(i).len())
            .max()
            .unwrap_or(0)
    }
}

/// Whether `program` declares `name` as a capacity (a `VAL INT NAME IS n:` line).
fn declares(program: &str, name: &str) -> bool {
    program
        .lines()
        .any(|l| l.starts_with(&format!("VAL INT {name} IS ")))
}

/// Deals the voxels out in order, round the nodes, each node taking a voxel while its share
/// stays within `--node-memory` less `--cache`; a voxel no node has room for stays on the
/// backing store only. Returns each voxel's home (a node, or -1) and each node's share in bytes.
/// Refuses, naming the setting, a cache smaller than the largest voxel, a node memory smaller
/// than the cache, and link queues too small for the fetches.
fn spread(items: &Items, memory: &Memory, nodes: usize) -> anyhow::Result<(Vec<i32>, Vec<u64>)> {
    let voxels = items.count();
    let largest = 4 * items.largest() as u64;
    if let Some(named) = &items.named {
        let block = 4 * named.largest_block as u64;
        anyhow::ensure!(
            memory.cache / 2 >= block.max(4),
            "--cache {}: the naming scheme halves it into a voxel cache and a triangle cache, and \
             each must hold the scene's largest voxel assembled ({block} bytes)",
            memory.cache
        );
    }
    anyhow::ensure!(
        memory.cache >= largest.max(4),
        "--cache {}: smaller than the scene's largest voxel ({largest} bytes); a walk needs one \
         voxel in the cache at a time",
        memory.cache
    );
    anyhow::ensure!(
        memory.node >= memory.cache,
        "--node-memory {} is smaller than --cache {}: the cache is part of the node's memory",
        memory.node,
        memory.cache
    );
    let floats = (largest / 4).max(1) as usize;
    anyhow::ensure!(
        nodes * FETCHES <= MAX_QUEUE.min(QUEUE_FLOATS_MOST / floats),
        "--node-memory: carm.occ's link queues hold {} bytes of voxel answers, too few for {nodes} \
         nodes each fetching {FETCHES} voxels of up to {largest} bytes (fewer --nodes, or a scene \
         with smaller voxels)",
        4 * QUEUE_FLOATS_MOST
    );
    let room = memory.node - memory.cache;
    let mut shares = vec![0u64; nodes];
    let mut next = 0;
    let home = (0..voxels)
        .map(|v| {
            let bytes = 4 * items.item(v).len() as u64;
            let taker = (0..nodes)
                .map(|k| (next + k) % nodes)
                .find(|&n| shares[n] + bytes <= room);
            match taker {
                Some(n) => {
                    shares[n] += bytes;
                    next = n + 1;
                    n as i32
                }
                None => -1,
            }
        })
        .collect();
    Ok((home, shares))
}

/// The backing store: the host's file of every voxel, which it reads a voxel from when the
/// root asks (host protocol tag 6), counting the reads per asking node.
struct Store {
    file: File,
    /// Each voxel's offset in the file (bytes) and REAL32s.
    at: Vec<(u64, usize)>,
    /// Each node's share in bytes.
    shares: Vec<u64>,
    /// Voxels read for each node.
    reads: Arc<Mutex<Vec<u64>>>,
}

impl Store {
    /// Writes every item (voxel) to `path` (creating its folder).
    fn write(path: &std::path::Path, items: &Items, shares: Vec<u64>) -> anyhow::Result<Store> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
        }
        let fail = |e: std::io::Error| anyhow::anyhow!("backing store {}: {e}", path.display());
        let mut bytes = Vec::with_capacity(4 * items.floats());
        let mut at = Vec::with_capacity(items.count());
        for v in 0..items.count() {
            let block = items.item(v);
            at.push((bytes.len() as u64, block.len()));
            for x in block {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        std::fs::write(path, &bytes).map_err(fail)?;
        let file = File::open(path).map_err(fail)?;
        let nodes = shares.len();
        Ok(Store {
            file,
            at,
            shares,
            reads: Arc::new(Mutex::new(vec![0; nodes])),
        })
    }

    /// The answer to a read of voxel `v` for node `asker`: INT n, then n REAL32s (n = -1 for a
    /// voxel that does not exist, which the root refuses).
    fn answer(&mut self, asker: i32, v: i32) -> std::io::Result<Vec<u8>> {
        let Some(&(offset, n)) = usize::try_from(v).ok().and_then(|v| self.at.get(v)) else {
            return Ok((-1i32).to_le_bytes().to_vec());
        };
        let mut out = vec![0u8; 4 + 4 * n];
        out[..4].copy_from_slice(&(n as i32).to_le_bytes());
        self.file.seek(SeekFrom::Start(offset))?;
        self.file.read_exact(&mut out[4..])?;
        let mut reads = self.reads.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(r) = usize::try_from(asker).ok().and_then(|a| reads.get_mut(a)) {
            *r += 1;
        }
        Ok(out)
    }
}

/// One message the root writes to the host (programs/README.md, "Host protocol").
#[derive(Clone, Debug, PartialEq)]
enum Message {
    /// A shot: shots so far, source patch, form factors, rays, microseconds since the first
    /// shot, power shot, the unshot fraction before it, the power (RGB) each patch that
    /// received some received (patches ascending).
    Shot {
        shots: u64,
        src: usize,
        form_factors: u64,
        rays: u64,
        micros: u32,
        shot: DVec3,
        unshot_fraction: f64,
        /// The overshoot lent to the shooter before the shot and taken back after it.
        lent: DVec3,
        received: Vec<(usize, DVec3)>,
    },
    /// The irradiance at sample point `0`.
    Result(usize, Vec3),
    /// A node's counters: node, points, corners, form factors, rays, voxels held at the end,
    /// their bytes, the most bytes of voxels held, walks, walks that fetched, voxels fetched,
    /// fetches served, poaches sent, receivers poached, receivers lent.
    Counters([u64; COUNTERS]),
    /// The program's own counters of the node whose [`Message::Counters`] came last.
    MoreCounters(Vec<u64>),
    /// A part of the next shot's report, when it was too long for one message: the power
    /// (RGB) each of these patches received (ascending, below the next part's).
    Received(Vec<(usize, DVec3)>),
    /// A read of voxel `1` from the backing store for node `0`.
    Read(i32, i32),
    /// A read of this patch's elements (their triangles and areas) for the shooter's source.
    Source(i32),
    /// The unshot power left on some patches (their owner's), each with its index.
    Patches(Vec<(usize, DVec3)>),
    /// The scene is over the program's capacities: its limits on the tree's INTs, voxels, the
    /// voxels' REAL32s, one voxel's REAL32s, patches, sample points, rays, nodes, elements,
    /// elements of one patch and objects.
    Refused([i32; 11]),
    /// The sample points each node took as a later choice (re-hashed).
    Rehashed(Vec<u64>),
    /// Adaptive subdivision split edge (`0`, `1`) at its midpoint, new sample point `2`.
    Split(u32, u32, u32),
    /// The end.
    End,
}

impl Message {
    /// Decodes the message at the start of `bytes`: `Ok(None)` when they end before it does,
    /// otherwise the message and its length in bytes.
    fn decode(bytes: &[u8]) -> anyhow::Result<Option<(Message, usize)>> {
        let mut r = Reader {
            bytes,
            at: 0,
            short: false,
        };
        match Message::read(&mut r) {
            Ok(m) => Ok(Some((m, r.at))),
            Err(Short) if r.short => Ok(None),
            Err(Short) => anyhow::bail!(
                "carm.occ wrote an unknown host message tag at byte 0 (first bytes {:?})",
                &bytes[..bytes.len().min(64)]
            ),
        }
    }

    /// A list of patches that received power: their count, the patches, the power of each.
    fn received(r: &mut Reader) -> Result<Vec<(usize, DVec3)>, Short> {
        let count = usize::try_from(r.int()?).map_err(|_| Short)?;
        let patches = (0..count)
            .map(|_| r.int().map(|p| p as usize))
            .collect::<Result<Vec<_>, _>>()?;
        patches
            .into_iter()
            .map(|p| Ok((p, DVec3::new(r.real64()?, r.real64()?, r.real64()?))))
            .collect()
    }

    fn read(r: &mut Reader) -> Result<Message, Short> {
        let rgb64 =
            |r: &mut Reader| Ok::<_, Short>(DVec3::new(r.real64()?, r.real64()?, r.real64()?));
        Ok(match r.int()? {
            tag::END => Message::End,
            tag::SHOT => {
                let [shots, src, form_factors, rays, micros] = [(); 5].map(|_| r.int());
                let (shot, unshot_fraction, lent) = (rgb64(r)?, r.real64()?, rgb64(r)?);
                let received = Message::received(r)?;
                Message::Shot {
                    shots: shots? as u64,
                    src: src? as usize,
                    form_factors: form_factors? as u64,
                    rays: rays? as u64,
                    micros: micros? as u32,
                    shot,
                    unshot_fraction,
                    lent,
                    received,
                }
            }
            tag::RESULT => {
                let g = r.int()? as usize;
                Message::Result(g, Vec3::new(r.real32()?, r.real32()?, r.real32()?))
            }
            tag::RECEIVED => Message::Received(Message::received(r)?),
            tag::READ => Message::Read(r.int()?, r.int()?),
            tag::SOURCE => Message::Source(r.int()?),
            tag::SPLIT => {
                let [a, b, m] = [(); 3].map(|_| r.int().map(|v| v as u32));
                Message::Split(a?, b?, m?)
            }
            tag::COUNTERS => {
                let mut c = [0u64; COUNTERS];
                for x in &mut c {
                    *x = r.int()? as u64;
                }
                Message::Counters(c)
            }
            tag::MORE_COUNTERS => {
                let count = usize::try_from(r.int()?).map_err(|_| Short)?;
                let more = (0..count.min(MAX_MORE_COUNTERS))
                    .map(|_| r.int().map(|x| x as u64))
                    .collect::<Result<_, _>>()?;
                Message::MoreCounters(more)
            }
            tag::PATCHES => Message::Patches(Message::received(r)?),
            tag::REHASHED => {
                let count = usize::try_from(r.int()?).map_err(|_| Short)?;
                let each = (0..count).map(|_| r.int().map(|n| n as u64));
                Message::Rehashed(each.collect::<Result<_, _>>()?)
            }
            tag::REFUSED => {
                let mut limits = [0i32; 11];
                for x in &mut limits {
                    *x = r.int()?;
                }
                Message::Refused(limits)
            }
            _ => return Err(Short),
        })
    }
}

/// What the root reported of its nodes besides the solution.
struct Booked {
    /// Each node's own counters ([`Message::Counters`]).
    nodes: Vec<[u64; COUNTERS]>,
    /// The sample points each node took as a later choice.
    rehashed: Vec<u64>,
    /// Each node's counters of the program's own ([`Message::MoreCounters`]), by node.
    more: std::collections::BTreeMap<u64, Vec<u64>>,
    /// The parts of shots' reports that came before their shot ([`Message::Received`]).
    parts: u64,
}

/// Books what the root wrote into `solver`; returns what it reported of the nodes.
fn book(solver: &mut Solver, bytes: &[u8]) -> anyhow::Result<Booked> {
    let rho: Vec<DVec3> = solver
        .mesh
        .patch_object
        .iter()
        .map(|&o| solver.scene.objects[o as usize].reflectance.as_dvec3())
        .collect();
    let patches = rho.len();
    // Each object's received power so far, for the error rows of a run with --reference.
    let areas = solver.object_areas();
    let mut by_object = vec![DVec3::ZERO; areas.len()];
    let mut nodes = Vec::new();
    let mut rehashed = Vec::new();
    let mut more = std::collections::BTreeMap::new();
    let mut results = 0;
    // the patches whose unshot power their owners reported at the end
    let mut left = vec![false; patches];
    // the parts of the next shot's report so far, and how many parts came in all
    let mut pending = Vec::new();
    let mut parts = 0u64;
    let mut at = 0;
    loop {
        let Some((message, len)) = Message::decode(&bytes[at..])
            .map_err(|e| anyhow::anyhow!("{e} (at byte {at} of its output)"))?
        else {
            anyhow::bail!("carm.occ's output ends early (at byte {at})");
        };
        at += len;
        match message {
            Message::End => break,
            Message::Read(..) | Message::Source(_) => {}
            Message::Received(part) => {
                parts += 1;
                pending.extend(part);
            }
            Message::Shot {
                shots,
                src,
                form_factors,
                rays,
                micros,
                shot,
                lent,
                received: last,
                ..
            } => {
                // the parts that came before the shot's message, then its own
                let mut received = std::mem::take(&mut pending);
                received.extend(last);
                let ascending = received.windows(2).all(|w| w[0].0 < w[1].0);
                anyhow::ensure!(
                    src < patches && ascending && received.last().is_none_or(|r| r.0 < patches),
                    "carm.occ reported a shot of patch {src} with the power received by {} \
                     patches, not all of the scene's {patches} in ascending order",
                    received.len()
                );
                let mut total = DVec3::ZERO;
                let mut absorbed = DVec3::ZERO;
                solver.unshot[src] += lent;
                solver.unshot[src] -= shot;
                for &(p, power) in &received {
                    total += power;
                    absorbed += power * (DVec3::ONE - rho[p]);
                    solver.unshot[p] += power * rho[p];
                    by_object[solver.mesh.patch_object[p] as usize] += power;
                }
                solver.unshot[src] -= lent;
                solver.book_totals(shot, total, absorbed);
                solver.stats.shots = shots;
                solver.stats.form_factors += form_factors;
                solver.stats.rays += rays;
                solver.history.push(ConvergencePoint {
                    shots,
                    seconds: micros as f64 * 1e-6,
                    unshot_fraction: solver.unshot_fraction(),
                    vertices: solver.mesh.vertices.len(),
                    errors: solver.errors_of_received(&areas, &by_object),
                });
            }
            Message::Result(g, h) => {
                let slot = solver.irradiance.get_mut(g).ok_or_else(|| {
                    anyhow::anyhow!("carm.occ reported sample point {g}, which does not exist")
                })?;
                *slot = h;
                results += 1;
            }
            Message::Split(a, b, m) => {
                let points = solver.mesh.vertices.len() as u32;
                anyhow::ensure!(
                    a < points && b < points && a != b && m == points,
                    "carm.occ split edge ({a}, {b}) at new sample point {m} of a mesh of {points}"
                );
                solver.split_edge_at_midpoint(a, b);
            }
            Message::Counters(c) => nodes.push(c),
            Message::MoreCounters(c) => {
                let node = nodes.last().map(|n| n[0]).ok_or_else(|| {
                    anyhow::anyhow!("carm.occ reported a node's own counters before its counters")
                })?;
                more.insert(node, c);
            }
            Message::Rehashed(r) => rehashed = r,
            Message::Patches(theirs) => {
                for (p, theirs) in theirs {
                    let u = solver.unshot.get(p).ok_or_else(|| {
                        anyhow::anyhow!(
                            "carm.occ reported the unshot power of patch {p}, which does not exist"
                        )
                    })?;
                    anyhow::ensure!(
                        !left[p],
                        "carm.occ reported the unshot power of patch {p} twice"
                    );
                    anyhow::ensure!(
                        theirs == *u,
                        "carm.occ's unshot power of patch {p} ({theirs}) disagrees with its shot \
                         record ({u})"
                    );
                    left[p] = true;
                }
            }
            Message::Refused([t, x, f, b, p, v, s, n, e, k, o]) => anyhow::bail!(
                "the scene is over carm.occ's capacities: at most an octree of {t} tree INTs and \
                 {x} voxels of {f} REAL32s in all ({b} in one), {p} patches, {v} sample points, \
                 {e} elements ({k} in one patch), {o} objects, {s} rays per form factor and {n} \
                 nodes"
            ),
        }
    }
    let reported = left.iter().filter(|&&l| l).count();
    anyhow::ensure!(
        reported == patches,
        "carm.occ reported the unshot power of {reported} of {patches} patches"
    );
    anyhow::ensure!(
        results == solver.irradiance.len(),
        "carm.occ returned {results} of {} sample points",
        solver.irradiance.len()
    );
    // The last row's errors from the irradiance carm.occ reports at the end.
    let errors = solver.errors();
    if let Some(last) = solver.history.last_mut() {
        last.errors = errors;
    }
    nodes.sort_by_key(|c| c[0]);
    anyhow::ensure!(
        pending.is_empty(),
        "carm.occ sent part of a shot's report and no shot after it"
    );
    Ok(Booked {
        nodes,
        rehashed,
        more,
        parts,
    })
}

/// The report's per-node and per-link figures; `memory` is the node memory, each node's share
/// and the backing-store reads for each node when the voxels were spread.
fn report(
    outcome: &NetworkOutcome,
    booked: Booked,
    memory: Option<(u64, Vec<u64>, Vec<u64>)>,
) -> CarmReport {
    let wall = outcome.elapsed.as_secs_f64();
    let rehashed = |node: u64| booked.rehashed.get(node as usize).copied().unwrap_or(0);
    let nodes = outcome
        .nodes
        .iter()
        .zip(booked.nodes)
        .map(|(n, c)| NodeCounters {
            node: c[0] as usize,
            points: c[1],
            corners: c[2],
            form_factors: c[3],
            rays: c[4],
            voxels: c[5],
            voxel_bytes: c[6],
            rehashed: rehashed(c[0]),
            voxel_bytes_peak: c[7],
            voxel_budget: memory.as_ref().map(|m| m.0),
            share_bytes: memory
                .as_ref()
                .and_then(|m| m.1.get(c[0] as usize).copied())
                .unwrap_or(c[6]),
            walks: c[8],
            cache_hits: c[8] - c[9].min(c[8]),
            cache_misses: c[10],
            store_reads: memory
                .as_ref()
                .and_then(|m| m.2.get(c[0] as usize).copied())
                .unwrap_or(0),
            fetches_served: c[11],
            poaches: c[12],
            poached: c[13],
            lent: c[14],
            communications: n.stats.communications,
            busy: if wall > 0.0 {
                n.busy.as_secs_f64() / wall
            } else {
                0.0
            },
            peak_bytes: n.stats.peak_workspace_bytes,
            named: booked.more.get(&c[0]).map(|m| {
                let at = |i: usize| m.get(i).copied().unwrap_or(0);
                NamedCounters {
                    voxel_hits: at(0),
                    voxel_misses: at(1),
                    names_fetched: at(2),
                    triangle_hits: at(3),
                    triangle_misses: at(4),
                }
            }),
        })
        .collect();
    let links = outcome
        .links
        .iter()
        .map(|l| LinkCounters {
            link: l.name.clone(),
            messages: l.messages,
            bytes: l.bytes,
        })
        .collect();
    CarmReport {
        nodes,
        links,
        report_parts: booked.parts,
        ..CarmReport::default()
    }
}

/// Little-endian writer of the host protocol.
#[derive(Default)]
struct Writer(Vec<u8>);

impl Writer {
    fn int(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn int64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn real32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn real64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn vec3(&mut self, v: Vec3) {
        for x in v.to_array() {
            self.0.extend_from_slice(&x.to_le_bytes());
        }
    }
}

/// The root's output ended inside a message (or, with `Reader::short` false, held an unknown tag).
struct Short;

/// Little-endian reader of the root's output.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    /// Whether a read ran past the end.
    short: bool,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Short> {
        let Some(b) = self.bytes.get(self.at..self.at + N) else {
            self.short = true;
            return Err(Short);
        };
        self.at += N;
        Ok(b.try_into().expect("N bytes"))
    }
    fn int(&mut self) -> Result<i32, Short> {
        Ok(i32::from_le_bytes(self.take()?))
    }
    fn real32(&mut self) -> Result<f32, Short> {
        Ok(f32::from_le_bytes(self.take()?))
    }
    fn real64(&mut self) -> Result<f64, Short> {
        Ok(f64::from_le_bytes(self.take()?))
    }
}

/// The root's screen: keeps every byte for [`book`], tells `on_shot` of each shot as it
/// arrives and answers the backing-store reads (until the output stops making sense, which
/// [`book`] then reports).
struct Screen {
    bytes: SharedBuf,
    /// Bytes decoded so far.
    decoded: usize,
    /// Whether the output stopped making sense.
    broken: bool,
    on_shot: OnShot,
    /// The backing store, when the voxels are spread.
    store: Option<Store>,
    /// The mesh's elements, when the controller keeps none (no point can be added).
    sources: Option<Sources>,
    /// Where the answers to reads go: the keyboard's input after the scene.
    answers: Pipe,
}

impl std::io::Write for Screen {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        let mut bytes = self.bytes.0.lock().unwrap_or_else(|e| e.into_inner());
        bytes.extend_from_slice(b);
        while !self.broken {
            match Message::decode(&bytes[self.decoded..]) {
                Ok(Some((message, len))) => {
                    self.decoded += len;
                    match message {
                        Message::Shot {
                            shots,
                            unshot_fraction,
                            ..
                        } => (self.on_shot)(shots, unshot_fraction),
                        Message::Read(asker, v) => {
                            // With no backing store, the root hears of the end of input.
                            if let Some(store) = &mut self.store {
                                let answer = store.answer(asker, v)?;
                                self.answers.push(&answer);
                            }
                        }
                        Message::Source(p) => {
                            // Without the mesh's elements, the root hears of the end of input.
                            if let Some(sources) = &self.sources {
                                self.answers.push(&sources.answer(p));
                            }
                        }
                        _ => {}
                    }
                }
                Ok(None) => break,
                Err(_) => self.broken = true,
            }
        }
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Bytes for the keyboard that the host produces as the run goes (answers to reads).
#[derive(Clone, Default)]
struct Pipe(Arc<Mutex<VecDeque<u8>>>);

impl Pipe {
    fn push(&self, b: &[u8]) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).extend(b);
    }
}

/// The root's keyboard: the scene, then the answers to its reads. The root writes a read to
/// the screen before it reads the answer, and the screen is flushed (so answered) before every
/// keyboard read; a read with nothing to answer it sees the end of input.
struct Keyboard {
    first: Cursor<Vec<u8>>,
    more: Pipe,
}

impl Read for Keyboard {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.first.read(buf)?;
        if n > 0 || buf.is_empty() {
            return Ok(n);
        }
        // VecDeque's Read copies whole slices
        self.more
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .read(buf)
    }
}

/// A byte buffer the runtime writes into and the host reads afterwards.
#[derive(Clone, Default)]
struct SharedBuf(Arc<Mutex<Vec<u8>>>);

impl SharedBuf {
    fn take(&self) -> Vec<u8> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

impl std::io::Write for SharedBuf {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRID: [f32; 4] = [-1.0, -1.0, -1.0, 0.5];

    #[test]
    fn a_coherence_key_is_the_cell_and_the_facing() {
        let up = [0.2, 0.9, 0.3];
        let at =
            |p: [f32; 3], n: [f32; 3]| coherence_key([p[0], p[1], p[2], n[0], n[1], n[2]], GRID);
        // (-1, -1, -1) is the grid's corner: cells of 0.5
        assert_eq!(at([0.1, -0.9, 0.4], up), [2, 0, 2, 2]);
        assert_eq!(
            at([0.4, -0.6, 0.1], up),
            [2, 0, 2, 2],
            "the same cell and facing"
        );
        assert_eq!(at([0.6, -0.9, 0.4], up), [3, 0, 2, 2], "the next cell in x");
        // the axis and sign the normal points most along: +x 0, -x 1, +y 2, -y 3, +z 4, -z 5
        for (n, facing) in [
            ([0.9, 0.1, 0.0], 0),
            ([-0.9, 0.1, 0.0], 1),
            ([0.1, -0.9, 0.2], 3),
            ([0.1, 0.2, 0.9], 4),
            ([0.1, 0.2, -0.9], 5),
        ] {
            assert_eq!(at([0.0; 3], n)[3], facing, "{n:?}");
        }
        // outside the grid, or not a number: clamped
        assert_eq!(at([-5.0, 1e30, f32::NAN], up), [0, 1 << 20, 0, 2]);
    }

    #[test]
    fn the_points_of_a_region_share_every_choice_of_node() {
        let point = |x: f32, z: f32| [x, -0.9, z, 0.0, 1.0, 0.0];
        let (a, b) = (point(0.05, 0.05), point(0.45, 0.3));
        assert_eq!(coherence_key(a, GRID), coherence_key(b, GRID));
        for attempt in 0..13 {
            assert_eq!(owner(a, GRID, 13, attempt), owner(b, GRID, 13, attempt));
        }
        // without a grid each point is hashed by its own bits, never to the root
        let keepers: std::collections::BTreeSet<_> = (0..64)
            .map(|i| owner(point(0.01 * i as f32, 0.1), [0.0; 4], 13, 0))
            .collect();
        assert!(keepers.len() > 6 && !keepers.contains(&0), "{keepers:?}");
        assert_eq!(owner(a, GRID, 1, 0), 0, "one node keeps them all");
    }
}
