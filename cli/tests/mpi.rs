//! The network programs of `tests/lang/network` under `mpirun -np 4 ... --transport mpi` agree
//! byte for byte with their in-process runs: stdout, the errors and deadlock reports on stderr
//! (a runtime error on one rank stops all), and the exit status. Needs a build with `--features mpi` and OpenMPI's `mpirun` on the path
//! (`cargo test -p occ --features mpi --test mpi`); without the feature this file is empty.
#![cfg(feature = "mpi")]

use std::process::{Command, Output};

/// Ranks every program runs on.
const RANKS: &str = "4";

/// (program in tests/lang/network, extra `occ run` arguments).
const PROGRAMS: &[(&str, &[&str])] = &[
    ("token_ring", &[]),
    ("tree_broadcast_sum", &["--topology", "tree3:13"]),
    ("link_multiplexer", &[]),
    ("pipeline_sort", &[]),
    ("alt_links_timeout", &[]),
    ("deadlock_two_nodes", &[]),
    ("halt_stops_ring", &[]),
];

fn occ(mpi: bool, file: &str, extra: &[&str]) -> Output {
    let occ = env!("CARGO_BIN_EXE_occ");
    let path = format!(
        "{}/../tests/lang/network/{file}.occ",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut args: Vec<&str> = vec!["run", &path, "--threads", "1"];
    args.extend(extra);
    let mut cmd = if mpi {
        let mut c = Command::new("mpirun");
        // Root in CI containers, and more ranks than cores.
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .args(["--oversubscribe", "-np", RANKS, occ])
            .args(&args)
            .args(["--transport", "mpi"]);
        c
    } else {
        let mut c = Command::new(occ);
        c.args(&args);
        c
    };
    cmd.output()
        .unwrap_or_else(|e| panic!("cannot start {cmd:?} (is OpenMPI installed?): {e}"))
}

/// Stderr without mpirun's own notice of a non-zero exit (a block between lines of dashes).
fn own_stderr(o: &Output) -> String {
    let s = String::from_utf8_lossy(&o.stderr);
    s.lines()
        .take_while(|l| !l.starts_with("-----"))
        .map(|l| format!("{l}\n"))
        .collect()
}

#[test]
fn network_programs_agree_across_four_ranks() {
    for (file, extra) in PROGRAMS {
        let here = occ(false, file, extra);
        let there = occ(true, file, extra);
        assert_eq!(
            String::from_utf8_lossy(&there.stdout),
            String::from_utf8_lossy(&here.stdout),
            "{file}: stdout under mpirun"
        );
        assert_eq!(own_stderr(&there), own_stderr(&here), "{file}: stderr");
        assert_eq!(
            there.status.code(),
            here.status.code(),
            "{file}: exit status"
        );
    }
}

#[test]
fn deadlock_across_ranks_is_reported_per_node() {
    let o = occ(true, "deadlock_two_nodes", &[]);
    let err = own_stderr(&o);
    for want in [
        "PROCESSOR 1",
        "PROCESSOR 2",
        "input from channel down",
        "input from channel up",
    ] {
        assert!(err.contains(want), "missing {want:?} in {err}");
    }
    assert_eq!(o.status.code(), Some(1));
}

/// `occ radiosity --solver carm` on 13 nodes (`--threads 1`) into `out`, with `extra` settings,
/// in this process or spread over four MPI ranks; returns report.json's per-object mean B and
/// rank 0's stderr, and the report.
fn carm(
    mpi: bool,
    out: &std::path::Path,
    extra: &[&str],
) -> (Vec<serde_json::Value>, String, serde_json::Value) {
    let _ = std::fs::remove_dir_all(out);
    let occ = env!("CARGO_BIN_EXE_occ");
    let args = [
        "radiosity",
        "--solver",
        "carm",
        "--nodes",
        "13",
        "--threads",
        "1",
        "--no-adapt",
        "--rays",
        "4",
        "--element-size",
        "150",
        "--image-size",
        "16",
        "--out",
    ];
    let mut cmd = if mpi {
        let mut c = Command::new("mpirun");
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
            .args(["--oversubscribe", "-np", RANKS, occ])
            .args(args)
            .arg(out)
            .args(extra)
            .args(["--transport", "mpi"]);
        c
    } else {
        let mut c = Command::new(occ);
        c.args(args).arg(out).args(extra);
        c
    };
    let o = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot start {cmd:?} (is OpenMPI installed?): {e}"));
    let err = own_stderr(&o);
    assert!(o.status.success(), "{cmd:?} failed:\n{err}");
    let text = std::fs::read_to_string(out.join("report.json")).expect("report.json written");
    let report: serde_json::Value = serde_json::from_str(&text).expect("report.json parses");
    let means = report["objects"]
        .as_array()
        .expect("objects")
        .iter()
        .map(|o| o["mean_b"].clone())
        .collect();
    assert_eq!(report["solver"], "carm");
    assert_eq!(
        report["nodes"].as_array().map(Vec::len),
        Some(13),
        "every node's counters reach rank 0"
    );
    (means, err, report)
}

#[test]
fn carm_across_four_ranks_gives_the_in_process_solution() {
    let tmp = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let until = ["--until", "unshot=0.05"];
    let (here, _, _) = carm(false, &tmp.join("carm-inproc"), &until);
    let (there, err, _) = carm(true, &tmp.join("carm-mpi"), &until);
    // The same sums in the same order on every node: the same numbers, bit for bit.
    assert_eq!(there, here, "per-object means under mpirun");
    // Only rank 0 speaks: one "shooting" stage line, not one per rank.
    assert_eq!(err.matches("shooting").count(), 1, "{err}");
}

/// The geometry spread (the Cornell box in voxels of at most 8 triangles, all 32 of them, an
/// eighth a node), so that voxels are fetched from nodes on other ranks and from the backing
/// store at rank 0, and sample points dealt by their regions ("Coherent placement"): the
/// in-process solution, bit for bit.
#[test]
fn carm_spread_across_four_ranks_gives_the_in_process_solution() {
    let tmp = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let spread = [
        "--until",
        "shots=20",
        "--voxel-triangles",
        "8",
        "--all-stages",
        "--node-memory",
        "2094",
        "--cache",
        "1047",
    ];
    let (here, _, _) = carm(false, &tmp.join("carm-spread-inproc"), &spread);
    let (there, _, report) = carm(true, &tmp.join("carm-spread-mpi"), &spread);
    assert_eq!(there, here, "per-object means under mpirun");
    let nodes = report["nodes"].as_array().expect("nodes");
    let sum = |k: &str| nodes.iter().map(|n| n[k].as_u64().expect(k)).sum::<u64>();
    assert!(
        sum("cache_misses") > 0 && sum("store_reads") > 0,
        "{report}"
    );
    for n in nodes {
        assert!(
            n["voxel_bytes_peak"].as_u64() <= n["voxel_budget"].as_u64(),
            "{n}"
        );
    }
}
