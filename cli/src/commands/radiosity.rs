//! `occ radiosity`: reads the scene (or takes the embedded Cornell box), runs carm.occ (the
//! default, [`super::carm`]) or the reference solver (`--solver reference`) and writes its outputs (report,
//! convergence, image, mesh; see the README) into `--out`. All the radiosity is in
//! `occ-radiosity` or carm.occ; this module only parses flags, reads and writes files and shows
//! progress.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::mesh::{CREASE_BAND_EDGE, Mesh, MeshConfig};
use occ_radiosity::octree::OctreeConfig;
use occ_radiosity::output::compare;
use occ_radiosity::output::{image, plot, ply, probe, report, truth};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::pathtrace::{PathTraceConfig, PathTracer};
use occ_radiosity::quadrature::MeanRule;
use occ_radiosity::scene::{self, Scene};
use occ_radiosity::solver::{AdaptConfig, Solver, SolverConfig, Until};

use super::carm;

/// Which solver to run.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum SolverKind {
    /// The sequential Rust reference solver.
    Reference,
    /// programs/carm.occ on a ternary tree of `--nodes` simulated transputers.
    Carm,
}

/// Flags of `occ radiosity`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    /// `compare RUN...`: overlay the convergence of earlier runs.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scene (Wavefront OBJ + MTL); the embedded Cornell box when omitted.
    pub scene: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "radiosity-out")]
    pub out: PathBuf,
    /// Stopping rule: error=FRACTION (every object's mean B within it, by the solver's
    /// estimate), unshot=FRACTION (of the emitted power), shots=N or time=SECONDS.
    #[arg(long, default_value = "error=0.01")]
    pub until: Until,
    /// A report.json to measure the error against (matched by object name): convergence.csv/png
    /// then carry the RMS and largest relative error per row.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Solve to a converged reference for --reference: stop at error=0.0001 by the solver's
    /// estimate (whatever --until says), with at least 64 rays per form factor.
    #[arg(long, conflicts_with = "solver")]
    pub converge: bool,
    /// Seconds between rows of convergence.csv (rows are also written at shots 1, 2, 4, 8, ...
    /// and at the end).
    #[arg(long, default_value_t = 0.05)]
    pub record_every: f64,
    /// Run every stage even where the scene does not need it (what is otherwise left out is
    /// listed on the console and under `left_out` in report.json).
    #[arg(long)]
    pub all_stages: bool,
    /// Overshooting by the ambient estimate: auto (when the scene is stiff), ambient (always)
    /// or off.
    #[arg(long, default_value = "auto")]
    pub acceleration: Acceleration,
    /// Probe points, one `x y z nx ny nz` per line; writes probe.csv.
    #[arg(long)]
    pub probe: Option<PathBuf>,
    /// Shadow rays per form factor (time against accuracy of shadows); shots carrying under
    /// --full-rays-power of the emitted power cast fewer to receivers far from them.
    #[arg(long, default_value_t = 8)]
    pub rays: u32,
    /// Shots carrying at least this fraction of the emitted power cast --rays rays to every
    /// receiver; weaker ones cast fewer, in proportion to their power, to receivers outside
    /// their near field (0: every shot casts them all).
    #[arg(long, default_value_t = occ_radiosity::solver::FULL_RAYS_POWER)]
    pub full_rays_power: f64,
    /// Solver: carm.occ on `--nodes` simulated transputers, or the Rust reference solver.
    #[arg(long, value_enum, default_value = "carm")]
    pub solver: SolverKind,
    /// Nodes of the ternary tree carm.occ runs on (`--solver carm`).
    #[arg(long, default_value_t = 13)]
    pub nodes: usize,
    /// OS threads running carm.occ's nodes (default: one per core); 1 repeats runs exactly.
    #[arg(long)]
    pub threads: Option<usize>,
    /// The node program `--solver carm` runs instead of the embedded carm.occ: any occam
    /// program that speaks its host protocol (programs/README.md).
    #[arg(long, value_name = "FILE.occ")]
    pub program: Option<PathBuf>,
    /// `--solver carm`: a node holds at most this many times its even share of the sample
    /// points (and of their element corners); a point whose hash names a full node is re-hashed.
    #[arg(long, value_name = "F", default_value_t = carm::LOAD_TOLERANCE)]
    pub load_tolerance: f64,
    /// `--solver carm`: worker tasks a node runs at high priority (the paper's worker
    /// processes); each takes receivers in turn and has the node's database manager walk their
    /// shadow rays, and while one waits for voxels from other nodes the others go on.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub tasks: usize,
    /// `--solver carm`: worker threads a node runs at low priority, beside its tasks: they use
    /// the processor while every task waits for voxels.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub worker_threads: usize,
    /// `--solver carm`: no task poaching (a node that runs out of receivers in a shot does not
    /// ask its neighbours for some of theirs).
    #[arg(long)]
    pub no_poach: bool,
    /// Every channel of a shot from the channels' summed unshot power over the source (by
    /// default each channel shoots from where its own power lies when they lie differently:
    /// radiosity/REFERENCES.md, "The dim faces' colours"); both solvers.
    #[arg(long)]
    pub summed_density: bool,
    /// How a shot's power into an element, and an object's mean, are taken from the values at
    /// the element's corners: quadratic (the default, with the curvature the neighbouring
    /// vertices show: radiosity/REFERENCES.md, "Element means exact for quadratics"; carm.occ's
    /// nodes keep each element's weights on its support, about four corners an element:
    /// programs/README.md, "Quadratic booking") or linear (the corners' average).
    #[arg(long)]
    pub element_means: Option<MeanRule>,
    /// Where carm.occ's nodes run: inproc (this process) or mpi (spread over the ranks of
    /// `mpirun`, rank 0 playing the host and writing the outputs; needs a build with
    /// --features mpi).
    #[arg(long, value_enum, default_value = "inproc")]
    pub transport: super::transport::Kind,
    /// Bytes of voxels a carm.occ node may keep, its share of the octree and its cache together
    /// (`--solver carm`; a K, M or G suffix multiplies by 1024, 1024², 1024³). Without it every
    /// node holds every voxel.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes, requires = "cache")]
    pub node_memory: Option<u64>,
    /// Bytes of a carm.occ node's voxel cache, part of --node-memory (`--solver carm`).
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes, requires = "node_memory")]
    pub cache: Option<u64>,
    /// Most triangles an octree voxel holds before it is split (the solution does not depend
    /// on it). Smaller voxels let `--node-memory` spread a small scene's geometry finely: each
    /// voxel must fit a node's cache.
    #[arg(long, default_value_t = OctreeConfig::default().max_leaf as u32,
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub voxel_triangles: u32,
    /// Longest patch (shooter) edge; default: scene diagonal / 4.
    #[arg(long)]
    pub patch_size: Option<f32>,
    /// Longest element edge; default: scene diagonal / 19.
    #[arg(long)]
    pub element_size: Option<f32>,
    /// Leave out the row of sample points that halves the edges leaving concave creases and
    /// contact lines, where surfaces meet face to face (radiosity/REFERENCES.md, "A row of
    /// points beside concave creases")
    #[arg(long)]
    pub no_crease_band: bool,
    /// Turn adaptive subdivision off.
    #[arg(long)]
    pub no_adapt: bool,
    /// Adaptive subdivision: relative form-factor difference along an edge that triggers a test.
    #[arg(long, default_value_t = 0.3)]
    pub adapt_difference: f32,
    /// Adaptive subdivision: relative departure from linearity at the midpoint that splits.
    #[arg(long, default_value_t = 0.1)]
    pub adapt_nonlinearity: f32,
    /// Adaptive subdivision stops adding sample points beyond this many.
    #[arg(long, default_value_t = 8_000)]
    pub max_vertices: usize,
    /// Overshooting factor (1 = none).
    #[arg(long, default_value_t = 1.0)]
    pub overshoot: f64,
    /// Seed of the source sampling.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 512)]
    pub image_size: u32,
    /// Exposure applied to radiance before the sRGB curve.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// View for image.png: "pos X Y Z look X Y Z up X Y Z fov DEG" (look: a point looked at;
    /// `dir X Y Z` may replace it). Default: the scene's `# camera:` comment, else a view chosen
    /// to see into the scene.
    #[arg(long)]
    pub camera: Option<String>,
    /// Most elements to mesh the scene into (about 250 bytes each with their sample points).
    /// Over it, default sizes are coarsened until the estimate fits; sizes given with
    /// --patch-size / --element-size are refused.
    #[arg(long, default_value_t = 4_000_000)]
    pub max_elements: usize,
    /// Run only the path tracer (the ground truth): each object's mean B and the probes' B with
    /// standard errors, into `pathtrace.json`.
    #[arg(long, conflicts_with = "reference_mc")]
    pub pathtrace: bool,
    /// Run the path tracer beside the solver: report.json gets each object's error against it,
    /// convergence.csv/png the RMS error against it over time.
    #[arg(long, conflicts_with = "reference")]
    pub reference_mc: bool,
    /// Path tracer: paths per object and per probe (the standard error falls as 1/sqrt).
    #[arg(long, default_value_t = 65_536)]
    pub pt_samples: u64,
    /// Path tracer: most bounces a path makes (1: direct light only).
    #[arg(long, default_value_t = 1000)]
    pub pt_max_bounces: u32,
}

/// Subcommands of `occ radiosity`.
#[derive(clap::Subcommand)]
pub enum Command {
    /// Overlay the convergence of earlier runs (their output folders) in one plot
    /// (compare.png) and one table (compare.md, also printed).
    Compare(CompareArgs),
}

/// Flags of `occ radiosity compare`.
#[derive(clap::Args)]
pub struct CompareArgs {
    /// Output folders of earlier runs (each holding convergence.csv).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Folder for compare.png and compare.md (created if missing).
    #[arg(long, default_value = "radiosity-compare")]
    pub out: PathBuf,
}

/// Runs `occ radiosity compare`.
fn execute_compare(args: &CompareArgs) -> anyhow::Result<ExitCode> {
    let mut runs = Vec::new();
    for dir in &args.runs {
        let path = dir.join("convergence.csv");
        let rows = compare::parse_csv(&path.display().to_string(), &read(&path)?)?;
        let name = dir
            .file_name()
            .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into());
        runs.push(compare::Run { name, rows });
    }
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let table = compare::table(&runs);
    let labels = plot::register_system_font();
    let png =
        compare::compare_png(&runs, labels).or_else(|_| compare::compare_png(&runs, false))?;
    for (file, bytes) in [("compare.md", table.as_bytes()), ("compare.png", &png)] {
        std::fs::write(out.join(file), bytes)
            .with_context(|| format!("cannot write {}", out.join(file).display()))?;
    }
    print!("{table}");
    println!(
        "compared {} runs; compare.png and compare.md in {}",
        runs.len(),
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// Runs `occ radiosity`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    if let Some(Command::Compare(compare)) = &args.command {
        return execute_compare(compare);
    }
    check_args(&args)?;
    let mut transport = super::transport::Chosen::new(args.transport)?;
    // Under MPI every rank loads and meshes the scene (the same way) and runs its share of the
    // nodes; only rank 0, which holds the host's channels, speaks and writes.
    let reports = transport.reports();
    let progress = Progress::new(reports);
    let t0 = Instant::now();
    progress.stage("loading", "");
    let (name, mut scene) = load_scene(args.scene.as_deref())?;
    if let Some(text) = &args.camera {
        scene.camera = Some(scene::parse_camera(text).with_context(|| {
            format!("--camera `{text}`: expected \"pos X Y Z look X Y Z up X Y Z fov DEG\"")
        })?);
    }
    let load = t0.elapsed().as_secs_f64();
    let probes = match &args.probe {
        Some(path) => Some(probe::parse_probes(
            &path.display().to_string(),
            &read(path)?,
        )?),
        None => None,
    };
    let truth = if reports && (args.pathtrace || args.reference_mc) {
        let probes = probes.as_deref().unwrap_or_default();
        Some(path_trace(&args, &name, &scene, probes)?)
    } else {
        None
    };
    if args.pathtrace {
        return Ok(ExitCode::SUCCESS);
    }
    let t1 = Instant::now();
    let mesh_config = mesh_config(&args, &name, &scene)?;
    progress.stage(
        "meshing",
        &format!(
            "{} triangles, patches {:.4}, elements {:.4}",
            scene.triangles.len(),
            mesh_config.patch_size,
            mesh_config.element_size
        ),
    );
    let mut mesh = Mesh::from_scene(&scene, mesh_config);
    if !args.no_crease_band {
        mesh.band_concave_creases(mesh_config.element_size * CREASE_BAND_EDGE);
    }
    anyhow::ensure!(
        mesh.stats.elements <= args.max_elements,
        "{name}: meshing made {} elements, more than --max-elements {} (discontinuity cuts add \
         to the estimate); give larger --patch-size / --element-size or a larger --max-elements",
        mesh.stats.elements,
        args.max_elements
    );
    let diag = scene.diagonal();
    if reports {
        print_left_out(&name, &scene, &mesh, diag);
    }
    let mesh_time = t1.elapsed().as_secs_f64();
    progress.stage(
        "octree",
        &format!(
            "{} patches, {} elements, {} sample points",
            mesh.stats.patches, mesh.stats.elements, mesh.stats.vertices
        ),
    );
    let t2 = Instant::now();
    let mut solver = Solver::new(
        &scene,
        mesh,
        solver_config(&args, diag, mesh_config.element_size),
    );
    let octree_time = t2.elapsed().as_secs_f64();
    if reports {
        print_stages(&solver);
    }
    let mut reference_probes = Vec::new();
    if let Some(path) = &args.reference {
        let text = read(path)?;
        reference_probes = truth::Reference::probes_of(&path.display().to_string(), &text)?;
        let names: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
        let file = path.display().to_string();
        for warning in report::reference_mismatch(
            &file,
            &text,
            &solver
                .object_means()
                .iter()
                .zip(&names)
                .map(|((area, _), n)| (n.clone(), *area))
                .collect::<Vec<_>>(),
        ) {
            eprintln!("warning: {warning}");
        }
        solver.reference = Some(report::reference_means(&file, &text, &names)?);
    }
    if let Some(truth) = &truth {
        let names: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
        solver.reference = Some(
            names
                .iter()
                .map(|n| truth.object(n).map(|o| o.mean_b.into()))
                .collect(),
        );
    }
    let t3 = Instant::now();
    let network = match args.solver {
        SolverKind::Reference => {
            progress.stage("shooting", &format!("until {:?}", solver.config().until));
            solve(&mut solver, &progress);
            None
        }
        SolverKind::Carm => {
            let threads = args.threads.unwrap_or_else(|| {
                std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
            });
            progress.stage(
                "shooting",
                &format!(
                    "carm.occ on {} nodes, {threads} threads, until {:?}",
                    args.nodes, args.until
                ),
            );
            let program = match &args.program {
                Some(path) => {
                    let text = std::fs::read_to_string(path)
                        .with_context(|| format!("--program: cannot read {}", path.display()))?;
                    Some((path.display().to_string(), text))
                }
                None => None,
            };
            let settings = carm::CarmSettings {
                nodes: args.nodes,
                threads,
                program,
                load_tolerance: args.load_tolerance,
                tasks: args.tasks,
                worker_threads: args.worker_threads,
                poach: !args.no_poach,
                channel_grids: !args.summed_density,
                memory: args
                    .node_memory
                    .zip(args.cache)
                    .map(|(node, cache)| carm::Memory {
                        node,
                        cache,
                        store: args.out.join(carm::BACKING_STORE),
                    }),
            };
            let on_shot = Box::new(progress.on_shot());
            let Some(report) = carm::solve(&mut solver, &settings, on_shot, transport.transport())?
            else {
                // A rank without the host: its nodes are done, rank 0 writes the outputs.
                return Ok(ExitCode::SUCCESS);
            };
            progress.done();
            if let Some(line) = carm_left_out(&args, &report).filter(|_| reports) {
                eprintln!("note: left out: {line}");
            }
            Some(report)
        }
    };
    let timings = report::Timings {
        load,
        mesh: mesh_time,
        octree: octree_time,
        solve: t3.elapsed().as_secs_f64(),
    };
    let probes = probes.as_deref().map(|probes| Probes {
        probes,
        truth: truth.as_ref().map_or(&reference_probes, |t| &t.probes),
    });
    write_outputs(
        &args,
        &solver,
        &name,
        timings,
        probes,
        truth.as_ref(),
        network.as_ref(),
    )?;
    Ok(ExitCode::SUCCESS)
}

/// The meshing sizes: given, or defaults ([`MeshConfig::default_for`])
/// coarsened until the element estimate fits --max-elements. Given sizes over it are refused.
fn mesh_config(args: &Args, name: &str, scene: &Scene) -> anyhow::Result<MeshConfig> {
    let diag = scene.diagonal();
    let default = MeshConfig::default_for(diag);
    let config = MeshConfig {
        patch_size: args.patch_size.unwrap_or(default.patch_size),
        element_size: args.element_size.unwrap_or(default.element_size),
    };
    let budget = args.max_elements as f64;
    let estimate = config.estimated_elements(scene);
    if estimate <= budget {
        return Ok(config);
    }
    anyhow::ensure!(
        args.patch_size.is_none() && args.element_size.is_none(),
        "{name}: meshing with patch size {} and element size {} would make about {estimate:.3e} \
         elements, more than --max-elements {}; give a larger --patch-size / --element-size \
         (or a larger --max-elements if memory allows, about 250 bytes an element)",
        config.patch_size,
        config.element_size,
        args.max_elements
    );
    let coarse = config.coarsened(scene, budget);
    eprintln!(
        "note: {name}: the default sizes would make about {estimate:.3e} elements, more than \
         --max-elements {}; meshing with patch size {:.4} and element size {:.4} instead",
        args.max_elements, coarse.patch_size, coarse.element_size
    );
    Ok(coarse)
}

/// Prints what the loader left out and the irregular input meshing found (also in report.json).
fn print_left_out(name: &str, scene: &Scene, mesh: &Mesh, diag: f32) {
    for note in &scene.left_out {
        eprintln!("note: {note}");
    }
    if scene.dropped_degenerate > 0 {
        eprintln!(
            "note: {name}: {} zero-area triangles dropped",
            scene.dropped_degenerate
        );
    }
    let c = mesh.stats.input;
    let counts = [
        (c.collapsed, "smaller than the weld distance, left out"),
        (c.duplicates, "duplicates, left out"),
        (
            c.two_sided,
            "two-sided pairs, meshed as two one-sided surfaces",
        ),
        (
            c.slivers,
            "slivers narrower than the weld distance, not cut",
        ),
        (c.non_manifold_edges, "non-manifold edges"),
        (
            c.flipped_edges,
            "edges between triangles of one object facing opposite ways",
        ),
        (
            c.reoriented,
            "triangles turned over to face the way their surface (or the file's normals) does",
        ),
    ];
    for (n, what) in counts.into_iter().filter(|c| c.0 > 0) {
        eprintln!(
            "note: {name}: {n} {what} (weld distance {:.3e}, 1e-5 of the diagonal)",
            1e-5 * diag
        );
    }
}

/// Says in one line which stages the scene does not need and are left out (and how to force
/// them back on), and what the analysis added.
fn print_stages(solver: &Solver) {
    let left_out = solver.stages.left_out();
    if !left_out.is_empty() {
        eprintln!(
            "note: left out: {} (--all-stages runs them)",
            left_out.join("; ")
        );
    }
    for added in solver.stages.added() {
        eprintln!("note: {added}");
    }
}

/// What code generation left out of the node program (carm.occ or `--program`), in one line.
fn carm_left_out(args: &Args, net: &carm::CarmReport) -> Option<String> {
    let name = args
        .program
        .as_ref()
        .map_or_else(|| "carm.occ".to_string(), |p| p.display().to_string());
    net.left_out.describe(&name)
}

/// Progress on stderr: a line per stage, and during shooting a line that rewrites itself on a
/// terminal or a new line every few seconds otherwise.
struct Progress {
    /// Whether to print at all (not on the MPI ranks other than 0).
    shown: bool,
    terminal: bool,
    start: Instant,
}

impl Progress {
    fn new(shown: bool) -> Progress {
        Progress {
            shown,
            terminal: std::io::stderr().is_terminal(),
            start: Instant::now(),
        }
    }

    /// What to call after each shot with the shots so far and the unshot fraction: it shows a
    /// line that rewrites itself ten times a second on a terminal, otherwise a line every five
    /// seconds.
    fn on_shot(&self) -> impl FnMut(u64, f64) + Send + 'static {
        let terminal = self.terminal;
        let start = Instant::now();
        let mut last = 0.0;
        let every = if terminal { 0.1 } else { 5.0 };
        move |shots, unshot| {
            let now = start.elapsed().as_secs_f64();
            if now - last > every {
                last = now;
                let line = format!(
                    "  shot {shots:>6}  unshot {:>8.5}%  {now:>6.1} s",
                    unshot * 100.0
                );
                if terminal {
                    eprint!("\r{line} ");
                    let _ = std::io::stderr().flush();
                } else {
                    eprintln!("{line}");
                }
            }
        }
    }

    /// Ends the progress line.
    fn done(&self) {
        if self.shown && self.terminal {
            eprintln!();
        }
    }

    fn stage(&self, stage: &str, detail: &str) {
        if !self.shown {
            return;
        }
        eprintln!(
            "[{:>7.1} s] {stage}{}{detail}",
            self.start.elapsed().as_secs_f64(),
            if detail.is_empty() { "" } else { ": " }
        );
    }
}

/// Runs the path tracer on the scene and probes, writes `pathtrace.json` into `--out` and prints
/// the per-object means; returns the reference.
fn path_trace(
    args: &Args,
    name: &str,
    scene: &Scene,
    probes: &[probe::Probe],
) -> anyhow::Result<truth::Reference> {
    let config = PathTraceConfig {
        samples: args.pt_samples,
        seed: args.seed,
        max_bounces: args.pt_max_bounces,
    };
    let start = Instant::now();
    let tracer = PathTracer::new(scene);
    let means = tracer.object_means(&config);
    let at_probes = tracer.probes(probes, &config);
    let seconds = start.elapsed().as_secs_f64();
    // The program's own path says nothing about the run; the arguments do.
    let command = std::iter::once("occ".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let pairs: Vec<_> = probes.iter().copied().zip(at_probes).collect();
    let reference =
        truth::Reference::new((name, scene), &command, &config, seconds, &means, &pairs);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let path = args.out.join("pathtrace.json");
    std::fs::write(&path, serde_json::to_string_pretty(&reference)?)
        .with_context(|| format!("cannot write {}", path.display()))?;
    for o in &reference.objects {
        let rel = |c: usize| 100.0 * o.std_err[c] / o.mean_b[c].max(f64::MIN_POSITIVE);
        println!(
            "{:<24} B = {:9.5} {:9.5} {:9.5}   std err {:.2}% {:.2}% {:.2}%",
            o.name,
            o.mean_b[0],
            o.mean_b[1],
            o.mean_b[2],
            rel(0),
            rel(1),
            rel(2)
        );
    }
    println!(
        "{name}: path traced, {} paths per object, {seconds:.2} s; written to {}",
        config.samples,
        path.display()
    );
    Ok(reference)
}

fn check_args(args: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.pt_samples >= 2,
        "--pt-samples must be at least 2 (a standard error needs two samples)"
    );
    anyhow::ensure!(
        args.rays >= 1 && args.rays <= 65_536,
        "--rays must be between 1 and 65536"
    );
    anyhow::ensure!(
        (0.0..=1.0).contains(&args.full_rays_power),
        "--full-rays-power must lie in [0, 1]"
    );
    anyhow::ensure!(
        args.overshoot > 0.0 && args.overshoot < 2.0,
        "--overshoot must lie in (0, 2)"
    );
    anyhow::ensure!(
        args.image_size >= 8 && args.image_size <= 8192,
        "--image-size must be between 8 and 8192"
    );
    anyhow::ensure!(args.nodes >= 1, "--nodes must be at least 1");
    if let SolverKind::Carm = args.solver {
        anyhow::ensure!(
            !matches!(args.until, Until::Seconds(_)),
            "--solver carm (the default) takes --until error=F, unshot=F or shots=N; --solver reference takes the others"
        );
    }
    anyhow::ensure!(
        args.transport == super::transport::Kind::Inproc || matches!(args.solver, SolverKind::Carm),
        "--transport mpi spreads carm.occ's nodes: not with --solver reference"
    );
    anyhow::ensure!(args.threads != Some(0), "--threads must be at least 1");
    anyhow::ensure!(
        args.record_every.is_finite() && args.record_every >= 0.0,
        "--record-every must be a number of seconds >= 0"
    );
    anyhow::ensure!(
        args.program.is_none() || matches!(args.solver, SolverKind::Carm),
        "--program names a node program for carm.occ's place: not with --solver reference"
    );
    anyhow::ensure!(
        args.node_memory.is_none() || matches!(args.solver, SolverKind::Carm),
        "--node-memory and --cache spread carm.occ's voxels: not with --solver reference"
    );
    for (flag, v) in [
        ("--patch-size", args.patch_size),
        ("--element-size", args.element_size),
    ] {
        if let Some(v) = v {
            anyhow::ensure!(v.is_finite() && v > 0.0, "{flag} must be a positive number");
        }
    }
    Ok(())
}

/// The estimated error `--converge` solves to.
const CONVERGED: f64 = 1e-4;

/// The fewest rays per form factor `--converge` uses.
const CONVERGED_RAYS: u32 = 64;

/// The rule for elements' means: as given, else quadratic (both solvers book by it).
fn element_means(args: &Args) -> MeanRule {
    args.element_means.unwrap_or_default()
}

fn solver_config(args: &Args, diag: f32, element_size: f32) -> SolverConfig {
    let adapt = (!args.no_adapt).then_some(AdaptConfig {
        difference: args.adapt_difference,
        nonlinearity: args.adapt_nonlinearity,
        min_edge: element_size / 8.0,
        min_shot_power: 0.002,
        passes: 3,
        max_vertices: args.max_vertices,
    });
    SolverConfig {
        form_factor: FormFactorConfig {
            rays: if args.converge {
                args.rays.max(CONVERGED_RAYS)
            } else {
                args.rays
            },
            offset: diag * 1e-6,
            ..FormFactorConfig::default()
        },
        adapt,
        overshoot: args.overshoot,
        acceleration: args.acceleration,
        full_rays_power: args.full_rays_power,
        until: if args.converge {
            Until::Error(CONVERGED)
        } else {
            args.until
        },
        seed: args.seed,
        all_stages: args.all_stages,
        record_every: args.record_every,
        octree: OctreeConfig {
            max_leaf: args.voxel_triangles as usize,
            ..OctreeConfig::default()
        },
        channel_densities: !args.summed_density,
        element_means: element_means(args),
        ..SolverConfig::default()
    }
}

fn read(path: &Path) -> anyhow::Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// Loads the scene at `path` (material libraries relative to it), or the embedded Cornell box.
fn load_scene(path: Option<&Path>) -> anyhow::Result<(String, Scene)> {
    let Some(path) = path else {
        return Ok((
            "cornell-box.obj (embedded)".into(),
            scene::cornell::load(true)?,
        ));
    };
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (text, latin1) = scene::decode(&bytes);
    let name = path.display().to_string();
    let mut scene = scene::load_obj_with(&name, &text, &scene::SearchFiles::beside(path))?;
    if latin1 {
        scene
            .left_out
            .push(format!("{name}: not UTF-8; read as Latin-1"));
    }
    Ok((name, scene))
}

/// Runs the solver, showing its progress.
fn solve(solver: &mut Solver, progress: &Progress) {
    solver.run(progress.on_shot());
    progress.done();
}

/// The probes to read (`--probe`), and the path tracer's at the same points, if any
/// (`--reference`, `--reference-mc`).
struct Probes<'p> {
    probes: &'p [probe::Probe],
    truth: &'p [truth::ProbeTruth],
}

fn write_outputs(
    args: &Args,
    solver: &Solver,
    name: &str,
    timings: report::Timings,
    probes: Option<Probes>,
    truth: Option<&truth::Reference>,
    network: Option<&carm::CarmReport>,
) -> anyhow::Result<()> {
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let write = |file: &str, bytes: &[u8]| {
        std::fs::write(out.join(file), bytes)
            .with_context(|| format!("cannot write {}", out.join(file).display()))
    };
    let mut rep = report::build(solver, name, timings);
    if let Some(truth) = truth {
        let names: Vec<String> = solver
            .scene
            .objects
            .iter()
            .map(|o| o.name.clone())
            .collect();
        let means: Vec<_> = solver.object_means().into_iter().map(|(_, b)| b).collect();
        let errors = truth::object_errors(&names, &means, truth);
        print!("{}", truth::error_table(&errors));
        rep.truth = Some(errors);
    }
    let values = probes.as_ref().map(|p| probe::values(solver, p.probes));
    if let (Some(values), Some(p)) = (&values, &probes) {
        rep.probes = truth::probe_errors(values, p.truth);
        if !rep.probes.is_empty() {
            print!("{}", truth::probe_summary(&rep.probes));
        }
    }
    if let Some(line) = network.and_then(|net| carm_left_out(args, net)) {
        rep.left_out.push(line);
    }
    // carm.occ's report: the same, with its nodes' and links' counters.
    let mut json = serde_json::to_value(&rep)?;
    if let Some(net) = network {
        json["solver"] = "carm".into();
        json["nodes"] = serde_json::to_value(&net.nodes)?;
        json["links"] = serde_json::to_value(&net.links)?;
        json["report_parts"] = net.report_parts.into();
    }
    write(
        "report.json",
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    let names: Vec<String> = (solver.scene.objects.iter())
        .map(|o| o.name.clone())
        .collect();
    write(
        "convergence.csv",
        plot::convergence_csv(&solver.history, &names).as_bytes(),
    )?;
    let labels = plot::register_system_font();
    let png = plot::convergence_png(&solver.history, labels)
        .or_else(|_| plot::convergence_png(&solver.history, false))?;
    write("convergence.png", &png)?;
    write(
        "image.png",
        &image::image_png(solver, args.image_size, args.image_size, args.exposure)?,
    )?;
    write(
        "solution.ply",
        ply::solution_ply(solver, args.exposure).as_bytes(),
    )?;
    if let Some(values) = &values {
        write("probe.csv", probe::probe_csv(values).as_bytes())?;
    }
    let t = &rep.totals;
    println!(
        "{}: {} shots, {} sample points, unshot {:.4}%, energy balance error {:.2e}, {:.2} s; outputs in {}",
        name,
        solver.stats.shots,
        solver.mesh.vertices.len(),
        t.unshot_fraction * 100.0,
        t.energy_balance_error,
        rep.timings.solve,
        out.display()
    );
    Ok(())
}

/// A byte count: digits, optionally followed by K, M or G (powers of 1024).
fn parse_bytes(s: &str) -> Result<u64, String> {
    let (digits, unit) = match s.trim().char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&s.trim()[..i], c.to_ascii_uppercase()),
        _ => (s.trim(), 'B'),
    };
    let shift = match unit {
        'B' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        _ => return Err(format!("{s}: a byte count takes the suffix K, M or G")),
    };
    let n: u64 = digits
        .parse()
        .map_err(|_| format!("{s}: not a byte count (digits, then K, M or G)"))?;
    n.checked_mul(1 << shift)
        .ok_or_else(|| format!("{s}: too many bytes"))
}
