//! The two geometry protocols of CARM compared on the same scene: carm.occ (a voxel's block
//! embeds its triangles) and carm-named.occ (the naming scheme of the paper's section 3: a
//! voxel holds its triangles' names, each triangle is fetched on its own), both on 4 nodes
//! with the geometry spread so that no node holds more than an eighth of it; and carm.occ
//! with every voxel on every node for scale (a node holds 1 / D of the geometry with
//! D = 8 by default, its caches seven eighths of that). Prints, per run, the messages and bytes over the
//! links between nodes, the fetches, the backing-store reads and the time.
//!
//! ```text
//! cargo build --release -p occ && cargo run --release -p occ --example carm_protocols [-- K [D]]
//! ```
//!
//! The scene is the room of K x K boxes of the tests (default 6), written to a temporary
//! folder; the runs use the `occ` binary built beside this example.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../tests/common/boxes.rs"]
mod boxes;

/// The nodes every run takes (the settings are the tests' spread boxes scene's).
const NODES: [&str; 4] = ["--nodes", "4", "--threads", "1"];

fn main() -> Result<(), String> {
    let k: usize = match std::env::args().nth(1) {
        Some(k) => k
            .parse()
            .map_err(|_| format!("K {k}: a number of boxes a side"))?,
        None => 6,
    };
    let d: u64 = match std::env::args().nth(2) {
        Some(d) => d
            .parse()
            .ok()
            .filter(|&d| d > 0)
            .ok_or(format!("D {d}: a node holds 1 / D of the geometry"))?,
        None => 8,
    };
    let occ = occ_binary()?;
    let dir = std::env::temp_dir().join(format!("carm-protocols-{}", std::process::id()));
    let scene = boxes::boxes_scene(&dir, k);
    let named = concat!(env!("CARGO_MANIFEST_DIR"), "/../programs/carm-named.occ");
    let replicated = run(&occ, &scene, &dir.join("replicated"), &[])?;
    let all = replicated["nodes"][0]["voxel_bytes"]
        .as_u64()
        .ok_or("no voxel bytes in the report")?;
    // 1 / D of the geometry a node; the naming scheme halves its cache into a voxel cache and
    // a triangle cache, each of which must hold the largest voxel.
    let (node, cache) = (all / d, all / d * 7 / 8);
    let spread = [
        "--node-memory".to_string(),
        node.to_string(),
        "--cache".to_string(),
        cache.to_string(),
    ];
    let spread: Vec<&str> = spread.iter().map(String::as_str).collect();
    let embedded = run(&occ, &scene, &dir.join("embedded"), &spread)?;
    let program = [&["--program", named][..], &spread].concat();
    let by_name = run(&occ, &scene, &dir.join("named"), &program)?;
    println!(
        "boxes scene, {k} x {k} boxes: {} voxels, {all} bytes of voxels; spread: --node-memory \
         {node} --cache {cache}, 4 nodes, --threads 1",
        replicated["scene"]["octree"]["leaves"]
    );
    println!("| run | messages | bytes | fetches | backing-store reads | shots (s) | solve (s) |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (what, report, out) in [
        ("carm.occ, replicated", &replicated, dir.join("replicated")),
        ("carm.occ, spread", &embedded, dir.join("embedded")),
        ("carm-named.occ, spread", &by_name, dir.join("named")),
    ] {
        let links = report["links"].as_array().ok_or("no links")?;
        let sum = |key: &str, of: &[serde_json::Value]| -> u64 {
            of.iter().filter_map(|x| x[key].as_u64()).sum()
        };
        let nodes = report["nodes"].as_array().ok_or("no nodes")?;
        println!(
            "| {what} | {} | {} | {} | {} | {:.2} | {:.2} |",
            sum("messages", links),
            sum("bytes", links),
            sum("cache_misses", nodes),
            sum("store_reads", nodes),
            shots_seconds(&out)?,
            report["timings"]["solve"].as_f64().unwrap_or(f64::NAN),
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The `occ` binary of this build (beside the examples folder).
fn occ_binary() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let occ = exe
        .parent()
        .and_then(Path::parent)
        .map(|dir| dir.join(format!("occ{}", std::env::consts::EXE_SUFFIX)))
        .filter(|occ| occ.is_file())
        .ok_or("no occ binary beside this example: build it first (cargo build -p occ)")?;
    Ok(occ)
}

/// Runs `occ radiosity` on `scene` with the shared settings and `extra` into `out`; returns
/// its report.
fn run(occ: &Path, scene: &Path, out: &Path, extra: &[&str]) -> Result<serde_json::Value, String> {
    let output = Command::new(occ)
        .arg("radiosity")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(boxes::BOXES_SETTINGS)
        .args(NODES)
        .args(extra)
        .output()
        .map_err(|e| format!("{}: {e}", occ.display()))?;
    if !output.status.success() {
        return Err(format!(
            "occ radiosity {extra:?} failed:\n{}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    let text = std::fs::read_to_string(out.join("report.json")).map_err(|e| e.to_string())?;
    serde_json::from_str(&text).map_err(|e| e.to_string())
}

/// The time from the first shot to the last (convergence.csv's last row).
fn shots_seconds(out: &Path) -> Result<f64, String> {
    let text = std::fs::read_to_string(out.join("convergence.csv")).map_err(|e| e.to_string())?;
    let last = text.lines().last().ok_or("an empty convergence.csv")?;
    last.split(',')
        .next()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| format!("convergence.csv: {last}"))
}
