//! `occ run FILE.occ [-I DIR] [--stats] [--all-routines] [--topology SHAPE | --nodes N] [--threads T]
//! [--node-memory BYTES] [--link-speed RATE] [--transport inproc|mpi]`: preprocess, parse, check, compile with Cranelift
//! and run.
//!
//! - A program whose last PROC takes the host's byte channels runs on one node, keyboard, screen
//!   and error bound to stdin, stdout and stderr.
//! - A program whose last PROC ends in a `PLACED PAR` runs on its network: one node per
//!   PROCESSOR, the lowest-numbered holding the host's channels.
//! - With `--topology` (or `--nodes N`, a ternary tree), the last PROC is a node program
//!   `(VAL INT id, nodes, []CHAN OF P in?, out!, ...)` run once per node of the shape.
//!
//! - With `--transport mpi` under `mpirun`, a network's nodes are spread over the ranks (see
//!   [`super::transport`]); rank 0 prints.
//!
//! Exit status: 0 when the program terminates, 1 on compile errors, a runtime error, STOP or
//! deadlock (with a message naming node, file, line and kind, or the deadlock report per node).

use std::path::PathBuf;
use std::process::ExitCode;

use occ_codegen::network::{NetworkOptions, NetworkOutcome};
use occ_runtime::topology::Shape;
use occ_runtime::{HostIo, NodeConfig, RunError};

use crate::frontend::{self, Options};

/// Loop back-edges per timeslice when `--threads 1` makes runs repeat exactly.
const COUNTED_SLICE: u32 = 1024;

/// Flags of `occ run`.
#[derive(clap::Args)]
pub struct Args {
    /// The program to run.
    pub file: PathBuf,
    /// Extra `#INCLUDE`/`#USE` search folders.
    #[arg(short = 'I', value_name = "DIR")]
    pub include: Vec<PathBuf>,
    /// Print per-node counters (processes, context switches, communications, busy time, peak
    /// memory) and per-link traffic.
    #[arg(long)]
    pub stats: bool,
    /// Compile every PROC and bind every `#PRAGMA EXTERNAL` intrinsic, even those nothing
    /// calls (by default they are left out; `--stats` counts them).
    #[arg(long)]
    pub all_routines: bool,
    /// Run the last PROC as a node program on this network shape: tree3:N, pipeline:N,
    /// ring:N, grid:WxH or hypercube:D.
    #[arg(long, value_name = "SHAPE", conflicts_with = "nodes")]
    pub topology: Option<Shape>,
    /// Shorthand for --topology tree3:N.
    #[arg(long, value_name = "N")]
    pub nodes: Option<usize>,
    /// OS threads that run the nodes (default: one per core). With 1, runs repeat exactly:
    /// timeslices are counted in loop iterations instead of timed.
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
    /// Memory of each node, in bytes (suffixes K, M, G), like a transputer's few megabytes.
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes)]
    pub node_memory: Option<usize>,
    /// Report the time the link traffic would have taken on transputer links of this speed
    /// (e.g. 20Mbit, 10Mbit): 11-bit data packets per byte.
    #[arg(long, value_name = "RATE", value_parser = parse_rate)]
    pub link_speed: Option<f64>,
    /// Where a network's nodes run: inproc (this process) or mpi (the ranks of mpirun; needs a
    /// build with --features mpi).
    #[arg(long, value_enum, default_value_t)]
    pub transport: super::transport::Kind,
}

/// Runs `occ run`.
pub fn execute(args: Args) -> anyhow::Result<ExitCode> {
    let options = Options {
        include_dirs: args.include.clone(),
    };
    let mut transport = super::transport::Chosen::new(args.transport)?;
    let reports = transport.reports();
    let (front, checked) = frontend::load(&args.file, &options);
    for diag in checked.diagnostics.iter().filter(|_| reports) {
        eprintln!("{:?}", diag.report);
    }
    let Some(front) = front else {
        return Ok(ExitCode::from(1));
    };
    let (program, map) = (&front.parsed.program, &front.parsed.map);
    let set = frontend::intrinsics();
    let started = std::time::Instant::now();
    let compiled =
        occ_codegen::compile_keeping(program, &front.checked, map, &set, args.all_routines);
    let compiled = match compiled {
        Ok(compiled) if args.stats && reports => {
            let file = args.file.display().to_string();
            eprintln!(
                "code generation: {:.1} ms",
                started.elapsed().as_secs_f64() * 1e3
            );
            if let Some(line) = compiled.left_out.describe(&file) {
                eprintln!("left out: {line}");
            }
            compiled
        }
        Ok(compiled) => compiled,
        Err(error) => {
            for d in error.diagnostics().iter().filter(|_| reports) {
                eprintln!("{:?}", d.to_report(map));
            }
            return Ok(ExitCode::from(1));
        }
    };
    let shape = match (args.topology, args.nodes) {
        (Some(s), _) => Some(s),
        (None, Some(n)) => Some(format!("tree3:{n}").parse::<Shape>()?),
        (None, None) => None,
    };
    let mut node = NodeConfig::default();
    if let Some(bytes) = args.node_memory {
        node.memory_budget = bytes;
    }
    let threads = args.threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    if threads == 0 {
        anyhow::bail!("--threads must be at least 1");
    }
    if threads == 1 {
        node.counted_slices = Some(COUNTED_SLICE);
    }
    let opts = NetworkOptions { node, threads };
    let outcome = if let Some(shape) = shape {
        if compiled.network.is_some() {
            anyhow::bail!(
                "{} configures its own network (PLACED PAR): run it without --topology or --nodes",
                args.file.display()
            );
        }
        match compiled.run_topology_over(shape, &opts, HostIo::stdio(), transport.transport()) {
            Ok(o) => o,
            Err(why) => anyhow::bail!("{why}"),
        }
    } else if let Some(o) = compiled.run_network_over(&opts, HostIo::stdio(), transport.transport())
    {
        o
    } else if compiled.is_node_program() {
        anyhow::bail!(
            "PROC {} is a node program: give --topology SHAPE (tree3:N, pipeline:N, ring:N, grid:WxH, hypercube:D) or --nodes N",
            compiled.entry_name
        );
    } else if !reports {
        // A program that is not a network runs on rank 0 alone.
        return Ok(ExitCode::SUCCESS);
    } else {
        let (result, stats) = compiled.run(opts.node, HostIo::stdio());
        if args.stats {
            eprintln!("{stats}");
        }
        return Ok(report_one(result));
    };
    if !reports {
        return Ok(ExitCode::SUCCESS);
    }
    if args.stats {
        eprint!("{}", network_stats(&outcome, args.link_speed));
    }
    let errors = outcome.errors();
    for (name, error) in &errors {
        eprintln!("{name}: {error}");
    }
    Ok(if errors.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn report_one(result: Result<(), RunError>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(1)
        }
    }
}

/// The `--stats` table of a network run.
fn network_stats(o: &NetworkOutcome, link_speed: Option<f64>) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let wall = o.elapsed.as_secs_f64();
    let _ = writeln!(
        s,
        "network: {} nodes, {} link directions, {:.3} s wall",
        o.nodes.len(),
        o.links.len(),
        wall
    );
    let _ = writeln!(
        s,
        "{:<16} {:>10} {:>12} {:>12} {:>6} {:>12}",
        "node", "processes", "switches", "comms", "busy", "peak bytes"
    );
    for n in &o.nodes {
        let busy = if wall > 0.0 {
            100.0 * n.busy.as_secs_f64() / wall
        } else {
            0.0
        };
        let _ = writeln!(
            s,
            "{:<16} {:>10} {:>12} {:>12} {:>5.1}% {:>12}",
            n.name,
            n.stats.processes_started,
            n.stats.context_switches,
            n.stats.communications,
            busy,
            n.stats.peak_workspace_bytes
        );
    }
    let _ = writeln!(
        s,
        "{:<40} {:>9} {:>11} {:>12} {:>12}{}",
        "link",
        "messages",
        "bytes",
        "writer wait",
        "reader wait",
        if link_speed.is_some() {
            "    link time"
        } else {
            ""
        }
    );
    for l in &o.links {
        let model = link_speed.map_or(String::new(), |bps| {
            format!(" {:>10.3} ms", 1e3 * link_seconds(l.bytes, bps))
        });
        let _ = writeln!(
            s,
            "{:<40} {:>9} {:>11} {:>9.3} ms {:>9.3} ms{model}",
            l.name,
            l.messages,
            l.bytes,
            1e3 * l.writer_blocked.as_secs_f64(),
            1e3 * l.reader_blocked.as_secs_f64(),
        );
    }
    if let Some(bps) = link_speed {
        let busiest = o
            .links
            .iter()
            .map(|l| link_seconds(l.bytes, bps))
            .fold(0.0, f64::max);
        let _ = writeln!(
            s,
            "link model: {:.1} Mbit/s, 11 bits per byte; busiest link {:.3} ms against {:.3} s wall",
            bps / 1e6,
            1e3 * busiest,
            wall
        );
    }
    s
}

/// Seconds `bytes` take on a transputer link of `bps` bits per second: each byte travels as an
/// 11-bit data packet (start, flag, 8 data bits, stop); the 2-bit acknowledges travel on the
/// other wire, overlapped with data as on the T800.
pub fn link_seconds(bytes: u64, bps: f64) -> f64 {
    bytes as f64 * 11.0 / bps
}

/// Parses a byte count with an optional K, M or G suffix (powers of 1024).
fn parse_bytes(s: &str) -> Result<usize, String> {
    let t = s.trim();
    let (num, mul) = match t.char_indices().last() {
        Some((i, 'K' | 'k')) => (&t[..i], 1usize << 10),
        Some((i, 'M' | 'm')) => (&t[..i], 1 << 20),
        Some((i, 'G' | 'g')) => (&t[..i], 1 << 30),
        _ => (t, 1),
    };
    num.trim()
        .parse::<usize>()
        .ok()
        .and_then(|n| n.checked_mul(mul))
        .ok_or_else(|| format!("`{s}` is not a byte count (e.g. 4M, 512K, 1048576)"))
}

/// Parses a link rate: `20Mbit`, `10Mbit/s`, `1.5Mbit`, `500kbit` or plain bits per second.
fn parse_rate(s: &str) -> Result<f64, String> {
    let t = s.trim().trim_end_matches("/s").to_ascii_lowercase();
    let (num, mul) = if let Some(n) = t.strip_suffix("mbit") {
        (n, 1e6)
    } else if let Some(n) = t.strip_suffix("kbit") {
        (n, 1e3)
    } else if let Some(n) = t.strip_suffix("bit") {
        (n, 1.0)
    } else {
        (t.as_str(), 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v * mul),
        _ => Err(format!("`{s}` is not a link speed (e.g. 20Mbit, 10Mbit)")),
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn byte_counts_and_rates_parse() {
        assert_eq!(parse_bytes("4M"), Ok(4 << 20));
        assert_eq!(parse_bytes("512k"), Ok(512 << 10));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("lots").is_err());
        assert_eq!(parse_rate("20Mbit"), Ok(20e6));
        assert_eq!(parse_rate("10Mbit/s"), Ok(10e6));
        assert!(parse_rate("fast").is_err());
        // One 1000-byte message at 20 Mbit/s: 11,000 bits, 0.55 ms.
        assert!((link_seconds(1000, 20e6) - 0.00055).abs() < 1e-12);
    }
}
