//! Helpers the carm.occ test files share: scratch folders, what they read from report.json, the
//! table lamp's settings. (Each file uses part of them.)
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh scratch folder named `name` under cargo's temporary folder for tests.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Three numbers of a JSON array (RGB).
pub fn rgb(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|c| v[c].as_f64().expect("a number"))
}

/// Per object of a report: name and mean B.
pub fn means(report: &serde_json::Value) -> Vec<(String, [f64; 3])> {
    (report["objects"].as_array().expect("objects").iter())
        .map(|o| (o["name"].as_str().expect("name").into(), rgb(&o["mean_b"])))
        .collect()
}

/// The energy balance of a report's totals, relative to the emitted power (worst channel that
/// emits).
pub fn balance_error(report: &serde_json::Value) -> f64 {
    let t = &report["totals"];
    let [e, a, x, u] = ["emitted", "absorbed", "escaped", "unshot"].map(|k| rgb(&t[k]));
    (0..3)
        .filter(|&c| e[c] > 0.0)
        .map(|c| (e[c] - a[c] - x[c] - u[c]).abs() / e[c])
        .fold(0.0, f64::max)
}

/// The reference solver, which books each shot as carm.occ's nodes do (both by the quadratic
/// rule unless told `--element-means linear`): what carm.occ is held to.
pub const REFERENCE_AS_CARM: [&str; 2] = ["--solver", "reference"];

/// The Cornell box's settings for both solvers: a coarse mesh and few rays so that a debug
/// build solves in seconds; no adaptive subdivision (the tests that want it say so).
pub const CORNELL_COARSE: [&str; 7] = [
    "--no-adapt",
    "--rays",
    "4",
    "--element-size",
    "150",
    "--image-size",
    "16",
];

/// The table lamp (an octree of eight voxels) at the settings both solvers run it with. Its
/// room's walls, floor and ceiling can hide nothing, and the octree would leave them out (one
/// voxel); `--all-stages` keeps every triangle in it, for the tests of spread geometry.
pub const LAMP: [&str; 11] = [
    concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/table-lamp.obj"),
    "--all-stages",
    "--no-adapt",
    "--rays",
    "4",
    "--element-size",
    "1",
    "--until",
    "unshot=0.05",
    "--image-size",
    "16",
];

/// Runs `occ radiosity` with `settings`, then `extra`, into `out`; returns its report.json, or
/// the error output when it fails.
pub fn run(out: &Path, settings: &[&str], extra: &[&str]) -> Result<serde_json::Value, String> {
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("radiosity")
        .arg("--out")
        .arg(out)
        .args(settings)
        .args(extra)
        .output()
        .expect("the occ binary runs");
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).into_owned());
    }
    let text = std::fs::read_to_string(out.join("report.json")).expect("report.json written");
    Ok(serde_json::from_str(&text).expect("report.json parses"))
}

/// [`run`], which must succeed.
pub fn solve(out: &Path, settings: &[&str], extra: &[&str]) -> serde_json::Value {
    run(out, settings, extra).unwrap_or_else(|e| panic!("occ radiosity {extra:?} failed:\n{e}"))
}

/// The relative difference `|b - r| / |r|` of two RGB means (0 when both are zero).
pub fn apart(b: &[f64; 3], r: &[f64; 3]) -> f64 {
    let diff = (0..3).map(|c| (b[c] - r[c]).powi(2)).sum::<f64>().sqrt();
    let size = (0..3).map(|c| r[c].powi(2)).sum::<f64>().sqrt();
    if size > 0.0 { diff / size } else { diff }
}
