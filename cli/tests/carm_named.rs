//! carm-named.occ, the naming scheme of the CARM paper's section 3 (voxels hold their
//! triangles' names; triangles are fetched one by one into a second cache area), gives the
//! same solution as carm.occ and, within 1%, the reference solver's: on the Cornell box with
//! every item on every node, and on the table lamp and a room of boxes with the items spread so
//! that no node holds more than an eighth of the geometry; its caches' hits and misses reach
//! report.json per node.

mod common;
use common::{CORNELL_COARSE, LAMP, apart, balance_error, means, run, scratch, solve};

#[path = "common/boxes.rs"]
mod boxes;
use boxes::{BOXES_SETTINGS, boxes_scene};

/// The naming scheme's node program.
const NAMED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../programs/carm-named.occ");

/// carm on 4 nodes, deterministic.
const CARM: [&str; 6] = ["--solver", "carm", "--nodes", "4", "--threads", "1"];

/// Every object's mean radiosity in `run` within `tolerance` of `against`'s.
fn assert_means(run: &serde_json::Value, against: &serde_json::Value, tolerance: f64, what: &str) {
    let (a, b) = (means(run), means(against));
    assert_eq!(a.len(), b.len());
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            apart(x, y) <= tolerance,
            "{what}: {name}: {x:?} against {y:?} ({:.3e} apart)",
            apart(x, y)
        );
    }
}

/// A node's naming-scheme counter.
fn named(node: &serde_json::Value, key: &str) -> u64 {
    node["named"][key]
        .as_u64()
        .unwrap_or_else(|| panic!("named.{key} in {node}"))
}

/// Solves `settings` with carm.occ (replicated), the reference solver and carm-named.occ with
/// `flags`; checks the named run's means against both and returns its report.
fn named_agrees(name: &str, settings: &[&str], flags: &[&str]) -> serde_json::Value {
    let carm = solve(&scratch(&format!("{name}-carm")), settings, &CARM);
    let reference = solve(&scratch(&format!("{name}-reference")), settings, &[]);
    let program = ["--program", NAMED];
    let out = scratch(name);
    let named_run = solve(&out, settings, &[&CARM[..], &program, flags].concat());
    assert_means(&named_run, &carm, 1e-9, "carm-named.occ against carm.occ");
    assert_means(
        &named_run,
        &reference,
        0.01,
        "carm-named.occ against the reference",
    );
    assert!(balance_error(&named_run) < 1e-9, "{}", named_run["totals"]);
    // every node assembles voxels for its walks but the root, which keeps no sample points
    for node in named_run["nodes"].as_array().expect("nodes").iter().skip(1) {
        assert!(
            named(node, "voxel_misses") > 0,
            "no voxel assembled: {node}"
        );
        assert!(named(node, "triangle_hits") > 0, "{node}");
    }
    named_run
}

/// Spreads the items with `--node-memory node --cache cache`: every node within its budget,
/// name blocks and triangles fetched from other nodes and the backing store, shares serving.
fn assert_spread(report: &serde_json::Value, node: u64) {
    let (mut triangles, mut names, mut reads, mut served, mut hits) = (0, 0, 0, 0, 0);
    for n in report["nodes"].as_array().expect("nodes") {
        let get = |k: &str| n[k].as_u64().unwrap_or_else(|| panic!("{k} in {n}"));
        assert_eq!(get("voxel_budget"), node, "{n}");
        assert!(get("voxel_bytes_peak") <= node, "over its budget: {n}");
        triangles += named(n, "triangle_misses");
        names += named(n, "names_fetched");
        hits += named(n, "voxel_hits");
        reads += get("store_reads");
        served += get("fetches_served");
        // every fetch is of a name block or a triangle, one request each
        assert_eq!(
            get("cache_misses"),
            named(n, "triangle_misses") + named(n, "names_fetched"),
            "{n}"
        );
    }
    assert!(triangles > 0 && names > 0 && hits > 0, "{report}");
    assert!(reads > 0 && served > 0, "{report}");
}

/// The Cornell box with every item on every node: each node assembles every voxel.
#[test]
fn named_solves_the_cornell_box_as_carm_and_the_reference() {
    let settings = [&CORNELL_COARSE[..], &["--until", "unshot=0.05"]].concat();
    named_agrees("named-cornell", &settings, &[]);
}

/// The table lamp's eight voxels spread: a node's caches hold two voxels' worth (each half the
/// largest voxel, 1056 bytes), its share 256 bytes of the items (names take less room than
/// triangles: the items of all eight voxels take 3,752 bytes), the rest stays on the backing
/// store.
#[test]
fn named_spreads_the_table_lamp() {
    let settings = LAMP;
    let flags = ["--node-memory", "2368", "--cache", "2112"];
    let report = named_agrees("named-lamp-spread", &settings, &flags);
    assert_spread(&report, 2368);
}

/// A room of boxes, an octree of dozens of voxels, spread so that no node holds more than an
/// eighth of the geometry (its caches seven eighths of that).
#[test]
fn named_spreads_a_many_voxel_scene_with_an_eighth_of_it_a_node() {
    let scene = boxes_scene(&scratch("named-boxes-scene"), 6);
    let scene = scene.to_str().expect("a UTF-8 path");
    let settings = [&[scene][..], &BOXES_SETTINGS].concat();
    // every voxel's bytes, as carm.occ's replicated run holds them
    let carm = solve(&scratch("named-boxes-size"), &settings, &CARM);
    let all = carm["nodes"][0]["voxel_bytes"].as_u64().expect("bytes");
    let (node, cache) = (all / 8, all / 8 * 7 / 8);
    let flags = [
        "--node-memory".to_string(),
        node.to_string(),
        "--cache".to_string(),
        cache.to_string(),
    ];
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let report = named_agrees("named-boxes-spread", &settings, &flags);
    assert_spread(&report, node);
    assert!(report["scene"]["octree"]["leaves"].as_u64() > Some(16));
}

/// A cache too small for the two halves is refused, naming the setting.
#[test]
fn named_refuses_a_cache_too_small_for_its_halves() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/table-lamp.obj");
    let settings = [scene, "--all-stages", "--no-adapt", "--until", "shots=1"];
    let flags = [
        "--program",
        NAMED,
        "--node-memory",
        "4096",
        "--cache",
        "2000",
    ];
    let error = run(
        &scratch("named-refusal"),
        &settings,
        &[&CARM[..], &flags].concat(),
    )
    .expect_err("refused");
    assert!(
        error.contains("--cache 2000") && error.contains("1056 bytes"),
        "{error}"
    );
}
