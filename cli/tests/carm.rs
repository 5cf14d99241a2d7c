//! carm.occ on 1, 4, 13 and 40 nodes of a ternary tree (`--threads 1`, deterministic) gives the
//! Cornell box the same solution whatever the node count, and every object a mean radiosity
//! within 1% of the reference solver's with the same settings.

use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

#[path = "common/boxes.rs"]
mod boxes;
use boxes::{BOXES_SETTINGS, boxes_scene};
mod common;
use common::{CORNELL_COARSE, LAMP, REFERENCE_AS_CARM, apart, means, scratch, solve};

/// The same settings for both solvers (`carm_subdivides_as_the_reference_solver` adds
/// adaptive subdivision's).
const SETTINGS: &[&str] = &CORNELL_COARSE;

/// Runs `occ radiosity` with `extra` flags into `out` (until 5% of the power is left unshot,
/// unless `extra` gives another `--until`); returns its report.json.
fn radiosity(out: &Path, extra: &[&str]) -> serde_json::Value {
    let until: &[&str] = if extra.contains(&"--until") {
        &[]
    } else {
        &["--until", "unshot=0.05"]
    };
    solve(out, &[SETTINGS, until].concat(), extra)
}

/// carm.occ on 4 nodes (`--threads 1`) and the reference solver, both with `extra`, into
/// scratch folders named after `name`; returns their reports (carm's first).
fn carm_and_reference(name: &str, extra: &[&str]) -> (serde_json::Value, serde_json::Value) {
    let carm_flags = ["--solver", "carm", "--nodes", "4", "--threads", "1"];
    let carm = radiosity(&scratch(name), &[&carm_flags[..], extra].concat());
    let reference = radiosity(
        &scratch(&format!("{name}-reference")),
        &[&REFERENCE_AS_CARM[..], extra].concat(),
    );
    (carm, reference)
}

/// Every object's mean radiosity in carm's report within 1% of the reference's (`what` names
/// the run in a failure).
fn assert_agree(carm: &serde_json::Value, reference: &serde_json::Value, what: &str) {
    for ((name, b), (_, r)) in means(carm).iter().zip(&means(reference)) {
        assert!(
            apart(b, r) <= 0.01,
            "{what}{name}: carm {b:?} against reference {r:?} ({:.3}% apart)",
            100.0 * apart(b, r)
        );
    }
}

/// carm.occ's reports on 1, 4, 13 and 40 nodes (run once for all the tests of this file).
fn carm_runs() -> &'static [(&'static str, serde_json::Value)] {
    static RUNS: OnceLock<Vec<(&'static str, serde_json::Value)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        ["1", "4", "13", "40"]
            .into_iter()
            .map(|nodes| {
                let dir = scratch(&format!("carm-{nodes}"));
                let report = radiosity(
                    &dir,
                    &["--solver", "carm", "--nodes", nodes, "--threads", "1"],
                );
                (nodes, report)
            })
            .collect()
    })
}

#[test]
fn carm_on_1_4_13_and_40_nodes_gives_one_solution() {
    let runs = carm_runs();
    let first = means(&runs[0].1);
    assert!(first.len() >= 5, "the Cornell box has its objects");
    for (nodes, report) in runs {
        assert_eq!(report["solver"], "carm");
        // Only the order of the sums of received power differs with the node count.
        for ((name, b), (_, r)) in means(report).iter().zip(&first) {
            assert!(
                apart(b, r) <= 1e-9,
                "{nodes} nodes: {name}: {b:?} against {r:?}"
            );
        }
        // Every sample point is held by exactly one node.
        let held: Vec<u64> = report["nodes"]
            .as_array()
            .expect("nodes")
            .iter()
            .map(|n| n["points"].as_u64().expect("points"))
            .collect();
        assert_eq!(held.len(), nodes.parse::<usize>().expect("a count"));
        assert_eq!(
            held.iter().sum::<u64>(),
            report["scene"]["final_vertices"]
                .as_u64()
                .expect("vertices")
        );
        assert_eq!(
            report["totals"]["unshot_fraction"]
                .as_f64()
                .map(|f| f <= 0.05),
            Some(true)
        );
    }
}

/// With no room to spare (`--load-tolerance 1`), the nodes whose hash is full send sample points
/// to a re-hash's node: no node holds more than its share, and the solution is the same.
#[test]
fn carm_rehashes_points_a_full_node_cannot_take() {
    let tight = radiosity(
        &scratch("carm-tight"),
        &[
            "--solver",
            "carm",
            "--nodes",
            "13",
            "--threads",
            "1",
            "--load-tolerance",
            "1",
        ],
    );
    let nodes = tight["nodes"].as_array().expect("nodes");
    let points = tight["scene"]["final_vertices"].as_u64().expect("vertices");
    // the root keeps none: the twelve other nodes share them
    let share = points.div_ceil(12);
    let rehashed: u64 = nodes
        .iter()
        .map(|n| n["rehashed"].as_u64().expect("n"))
        .sum();
    assert!(rehashed > 0, "some points were re-hashed");
    for n in nodes {
        assert!(n["points"].as_u64().expect("points") <= share, "{n}");
    }
    assert_eq!(
        nodes[0]["points"].as_u64(),
        Some(0),
        "the root keeps no points"
    );
    let (_, roomy) = carm_runs()
        .iter()
        .find(|(n, _)| *n == "13")
        .expect("13 nodes");
    for ((name, b), (_, r)) in means(&tight).iter().zip(means(roomy).iter()) {
        assert!(apart(b, r) <= 1e-9, "{name}: {b:?} against {r:?}");
    }
}

#[test]
fn carm_on_1_4_13_and_40_nodes_agrees_with_the_reference_solver() {
    let reference = radiosity(&scratch("carm-reference"), &REFERENCE_AS_CARM);
    for (nodes, report) in carm_runs() {
        assert_agree(report, &reference, &format!("{nodes} nodes: "));
    }
}

/// Adaptive subdivision's settings: a finer start than `SETTINGS` and more rays, because a
/// midpoint whose verdict sits on its threshold can go either way with the last bit of a
/// float (carm.occ sums an element's unshot power over its corners, the reference solver per
/// element), and on a coarse mesh one point more or less moves a small face's mean by a few
/// percent, as a different seed does.
const ADAPTIVE: &[&str] = &[
    "--rays",
    "8",
    "--element-size",
    "75",
    "--until",
    "unshot=0.05",
    "--image-size",
    "16",
];

/// The sample points of each row of a run's convergence record.
fn vertices_by_row(out: &Path) -> Vec<u64> {
    let text = std::fs::read_to_string(out.join("convergence.csv")).expect("convergence.csv");
    text.lines()
        .skip(1)
        .map(|row| {
            row.split(',')
                .nth(3)
                .expect("a vertices column")
                .parse()
                .expect("a count")
        })
        .collect()
}

#[test]
fn carm_subdivides_as_the_reference_solver() {
    let reference = solve(
        &scratch("carm-adapt-reference"),
        ADAPTIVE,
        &REFERENCE_AS_CARM,
    );
    let points = |r: &serde_json::Value| r["scene"]["final_vertices"].as_u64().expect("a count");
    let mut first: Option<serde_json::Value> = None;
    for nodes in ["4", "40"] {
        let out = scratch(&format!("carm-adapt-{nodes}"));
        let carm = solve(
            &out,
            ADAPTIVE,
            &["--solver", "carm", "--nodes", nodes, "--threads", "1"],
        );
        // The mesh grew during the shots, as much as the reference solver's did.
        let rows = vertices_by_row(&out);
        assert!(
            rows.last() > rows.first(),
            "{nodes} nodes: no sample points added after the first shot: {rows:?}"
        );
        let (ours, theirs) = (points(&carm) as f64, points(&reference) as f64);
        assert!(
            (ours - theirs).abs() <= 0.01 * theirs,
            "{nodes} nodes: {ours} sample points against the reference solver's {theirs}"
        );
        assert_agree(&carm, &reference, &format!("{nodes} nodes: "));
        // The node count changes only the order of sums, not a single split.
        if let Some(first) = &first {
            assert_eq!(
                points(first),
                points(&carm),
                "{nodes} nodes split differently"
            );
            for ((name, b), (_, r)) in means(&carm).iter().zip(&means(first)) {
                assert!(
                    apart(b, r) <= 1e-9,
                    "{nodes} nodes: {name}: {b:?} against {r:?}"
                );
            }
        }
        first.get_or_insert(carm);
    }
}

/// Subdivision stops at `--max-vertices` as the reference solver's does, on 13 nodes whose
/// arrays the host sized for that many points.
#[test]
fn carm_subdivides_up_to_the_point_budget() {
    let out = scratch("carm-adapt-budget");
    let carm = solve(
        &out,
        &[SETTINGS[1..].to_vec(), vec!["--until", "unshot=0.05"]].concat(),
        &[
            "--solver",
            "carm",
            "--nodes",
            "13",
            "--threads",
            "1",
            "--max-vertices",
            "1000",
        ],
    );
    assert_eq!(carm["scene"]["final_vertices"], 1000);
}

/// A scene whose octree has several voxels, so that shadow rays walk from voxel to voxel.
#[test]
fn carm_walks_a_many_voxel_octree_as_the_reference_solver() {
    let settings = LAMP;
    let reference = solve(&scratch("carm-lamp-reference"), &settings, &[]);
    let leaves = reference["scene"]["octree"]["leaves"]
        .as_u64()
        .expect("leaves");
    assert!(leaves > 1, "the table lamp's octree has {leaves} leaf");
    let carm = solve(
        &scratch("carm-lamp"),
        &settings,
        &["--solver", "carm", "--nodes", "4", "--threads", "1"],
    );
    // Every node holds every voxel (geometry is replicated), and says so.
    for node in carm["nodes"].as_array().expect("nodes") {
        let voxels = node["voxels"].as_u64().expect("voxels");
        assert!(voxels > 1 && voxels <= leaves, "{node}");
        assert!(
            node["voxel_bytes"].as_u64().expect("voxel bytes") > 0,
            "{node}"
        );
        assert_eq!(node["voxels"], carm["nodes"][0]["voxels"]);
        assert_eq!(node["voxel_bytes"], carm["nodes"][0]["voxel_bytes"]);
    }
    assert_agree(&carm, &reference, "");
}

/// A shot's channels shoot from their own densities where they lie differently over the
/// shooter (the Cornell box's coloured walls make them), or all from the channels' summed
/// density (`--summed-density`): carm.occ makes the reference solver's shots either way (the
/// same power left unshot, every object's mean to float rounding), and the two ways differ.
#[test]
fn carm_shoots_the_channels_as_the_reference_solver_does() {
    let (split, split_ref) = carm_and_reference("carm-channels", &[]);
    let summed = ["--summed-density"];
    let (together, together_ref) = carm_and_reference("carm-channels-summed", &summed);
    let left = |r: &serde_json::Value| r["totals"]["unshot_fraction"].as_f64().expect("a number");
    for (carm, reference, what) in [
        (&split, &split_ref, "apart"),
        (&together, &together_ref, "summed"),
    ] {
        assert!(
            (left(carm) - left(reference)).abs() <= 1e-6 * left(reference),
            "{what}: carm left {} unshot, the reference {}",
            left(carm),
            left(reference)
        );
        for ((name, b), (_, r)) in means(carm).iter().zip(&means(reference)) {
            assert!(
                apart(b, r) <= 1e-6,
                "{what} {name}: carm {b:?} against {r:?}"
            );
        }
    }
    let most = means(&split)
        .iter()
        .zip(&means(&together))
        .map(|((_, a), (_, b))| apart(a, b))
        .fold(0.0, f64::max);
    assert!(
        most > 1e-3,
        "the channels apart and summed differ by {most} at most"
    );
}

#[test]
fn carm_stops_on_the_error_estimate_where_the_reference_solver_does() {
    let (carm, reference) = carm_and_reference("carm-error", &["--until", "error=0.05"]);
    let left = |r: &serde_json::Value| r["totals"]["unshot_fraction"].as_f64().expect("a number");
    // The same shots: the same power left, up to the order of the sums of received power
    // (parts in 1e8 here; one shot more or less would move it by parts in 100).
    assert!(
        (left(&carm) - left(&reference)).abs() <= 1e-6 * left(&reference),
        "carm left {} unshot, the reference {}",
        left(&carm),
        left(&reference)
    );
    // Stopped on the estimate, with power still unshot.
    assert!(left(&reference) > 0.0);
    assert_agree(&carm, &reference, "");
}

/// The rms_error column of a run's convergence.csv, by shot.
fn rms_by_shot(out: &Path) -> Vec<(u64, f64)> {
    let text = std::fs::read_to_string(out.join("convergence.csv")).expect("convergence.csv");
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).expect(name);
    let (shots, rms) = (col("shots"), col("rms_error"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let rms = f[rms]
                .parse()
                .unwrap_or_else(|_| panic!("no rms_error in {l}"));
            (f[shots].parse().expect("shots"), rms)
        })
        .collect()
}

/// With --reference, every shot's row has its errors, from the power each object has received
/// (carm.occ reports the irradiance at its points only at the end): the row of shot 30 of a
/// longer run is the final answer of a run that stops at shot 30.
#[test]
fn carm_reports_error_against_run_time_at_every_shot() {
    let reference = scratch("carm-rows-reference");
    radiosity(&reference, &[]);
    let against = reference.join("report.json");
    let against = against.to_str().expect("a UTF-8 path");
    let run = |name: &str, shots: &str| {
        let out = scratch(name);
        let until = format!("shots={shots}");
        radiosity(
            &out,
            &[
                "--solver",
                "carm",
                "--nodes",
                "4",
                "--threads",
                "1",
                "--until",
                &until,
                "--reference",
                against,
            ],
        );
        rms_by_shot(&out)
    };
    let (short, long) = (run("carm-rows-30", "30"), run("carm-rows-40", "40"));
    assert_eq!(long.len(), 40, "a row a shot");
    assert!(long[0].1 > 2.0 * long[39].1, "the error falls: {long:?}");
    let (at_30, end_30) = (long[29], short[29]);
    assert_eq!((at_30.0, end_30.0), (30, 30));
    assert!(
        (at_30.1 - end_30.1).abs() <= 1e-5 * end_30.1,
        "shot 30 of the longer run {} against the end of the shorter {}",
        at_30.1,
        end_30.1
    );
}

/// By the corners' average (`--element-means linear`) carm.occ's nodes keep three corners an
/// element and book as the reference solver does by that rule; the two rules' solutions differ.
#[test]
fn carm_books_by_the_corners_average_as_the_reference_solver_does() {
    let linear = ["--element-means", "linear"];
    let (carm, reference) = carm_and_reference("carm-linear", &linear);
    assert_agree(&carm, &reference, "linear: ");
    let quadratic = &carm_runs()[1].1;
    let differ = (means(&carm).iter().zip(&means(quadratic))).any(|((_, a), (_, b))| a != b);
    assert!(differ, "the linear rule's solution is the quadratic rule's");
}

/// Overshooting by the ambient estimate, always on: carm.occ lends and takes back the overshoot
/// as the reference solver does.
#[test]
fn carm_overshoots_by_the_ambient_estimate_as_the_reference_solver() {
    let (carm, reference) = carm_and_reference("carm-ambient", &["--acceleration", "ambient"]);
    assert_agree(&carm, &reference, "");
}

/// A copy of carm.occ in `out` (as `name`) without its capacity `capacity` (refused before it
/// is compiled, so it needs no includes beside it); its path.
fn carm_without(out: &std::path::Path, name: &str, capacity: &str) -> String {
    let program =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../programs/carm.occ"))
            .expect("carm.occ");
    let declaration = format!("VAL INT {capacity} IS");
    let without: String = (program.lines())
        .filter(|l| !l.starts_with(&declaration))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(
        without.len() < program.len(),
        "carm.occ declares {capacity}"
    );
    let path = out.join(name);
    std::fs::write(&path, without).expect("the copy");
    path.to_str().expect("a UTF-8 path").to_owned()
}

#[test]
fn carm_refuses_what_it_cannot_do_clearly() {
    let out = scratch("carm-refusals");
    std::fs::create_dir_all(&out).expect("a scratch folder");
    let bare = carm_without(&out, "no-quadratic.occ", "QUADRATIC");
    let bare = bare.as_str();
    // (without MESH.KEPT the host's weights would be read as the next element)
    let unkept = carm_without(&out, "no-mesh-kept.occ", "MESH.KEPT");
    let unkept = unkept.as_str();
    for (flags, says) in [
        (
            &["--solver", "carm", "--no-adapt", "--until", "time=1"][..],
            "takes --until error=F, unshot=F or shots=N",
        ),
        (
            &[
                "--solver",
                "carm",
                "--no-adapt",
                "--until",
                "unshot=0.01",
                "--nodes",
                "1025",
            ][..],
            "carm.occ runs on 1 to 1024 nodes",
        ),
        // A node program that cannot book by the quadratic rule, asked to.
        (
            &["--solver", "carm", "--program", bare][..],
            "does not book by the quadratic rule",
        ),
        // One that keeps the mesh, where the host deals the weights.
        (
            &["--solver", "carm", "--program", unkept, "--no-adapt"][..],
            "declares no MESH.KEPT capacity",
        ),
        // More rays per form factor than carm.occ's fixed arrays take.
        (
            &[
                "--solver",
                "carm",
                "--no-adapt",
                "--until",
                "unshot=0.01",
                "--rays",
                "2000",
            ][..],
            "over carm.occ's capacities",
        ),
        (
            &[
                "--solver",
                "carm",
                "--no-adapt",
                "--until",
                "unshot=0.01",
                "--load-tolerance",
                "0.5",
            ][..],
            "--load-tolerance 0.5",
        ),
        (
            &["--solver", "carm", "--no-adapt", "--tasks", "0"][..],
            "--tasks 0 --worker-threads 0: a node runs 1 to 16 tasks",
        ),
        (
            &["--solver", "carm", "--no-adapt", "--worker-threads", "16"][..],
            "at most 16 tasks and threads together",
        ),
    ] {
        let output = Command::new(env!("CARGO_BIN_EXE_occ"))
            .arg("radiosity")
            .arg("--out")
            .arg(&out)
            .args(flags)
            .output()
            .expect("the occ binary runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{flags:?} should fail");
        assert!(stderr.contains(says), "{flags:?}: {stderr}");
    }
}

/// A shot's report naming more patches than one message holds goes up the tree in parts, each
/// pulled by the node above, merged as they come: with parts of three patches (carm.occ and its
/// includes copied, `PART.PATCHES` set to 3) the solution is the embedded program's to the bit,
/// on 4 and 13 nodes, the voxels replicated or spread, with adaptive subdivision or without.
#[test]
fn carm_reports_in_parts_give_the_same_solution() {
    let copy = programs_with("carm-parts-program", "VAL INT PART.PATCHES IS", "4096", "3");
    let program = copy.join("carm.occ");
    let program = program.to_str().expect("a UTF-8 path");
    let lamp = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/table-lamp.obj");
    let lamp = [
        lamp,
        "--all-stages",
        "--no-adapt",
        "--rays",
        "4",
        "--until",
        "unshot=0.05",
    ];
    let spread = ["--node-memory", "2112", "--cache", "1056"];
    for (name, settings, nodes) in [
        ("cornell-4", SETTINGS.to_vec(), "4"),
        ("cornell-13", SETTINGS.to_vec(), "13"),
        ("lamp-spread-4", [&lamp[..], &spread[..]].concat(), "4"),
        ("cornell-adaptive-4", ADAPTIVE.to_vec(), "4"),
    ] {
        let carm = ["--solver", "carm", "--nodes", nodes, "--threads", "1"];
        let whole = solve(
            &scratch(&format!("carm-parts-{name}-whole")),
            &settings,
            &carm,
        );
        let parts = solve(
            &scratch(&format!("carm-parts-{name}")),
            &settings,
            &[&carm[..], &["--program", program][..]].concat(),
        );
        assert_eq!(whole["report_parts"], 0, "{name}");
        assert!(
            parts["report_parts"].as_u64() > Some(1000),
            "{name}: {}",
            parts["report_parts"]
        );
        assert_eq!(means(&parts), means(&whole), "{name}");
        assert_eq!(parts["totals"], whole["totals"], "{name}");
    }
}

/// A copy of programs/ (into the scratch folder `name`) in which the constant declared once
/// as `declared value:` has the value `to`; returns the copy's folder.
fn programs_with(name: &str, declared: &str, value: &str, to: &str) -> std::path::PathBuf {
    let programs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../programs");
    let copy = scratch(name);
    std::fs::create_dir_all(&copy).expect("a scratch folder");
    let (from, to) = (format!("{declared} {value}:"), format!("{declared} {to}:"));
    let mut edited = 0;
    for entry in std::fs::read_dir(&programs).expect("programs/") {
        let path = entry.expect("an entry").path();
        let Some(file) = path.file_name() else {
            continue;
        };
        let text = std::fs::read_to_string(&path).expect("a program file");
        edited += text.matches(&from).count();
        std::fs::write(copy.join(file), text.replace(&from, &to)).expect("the copy");
    }
    assert_eq!(edited, 1, "{from} is declared once in programs/");
    copy
}

/// In a closed scene with sheets (the two rooms: their lamp panels hang below the ceilings)
/// carm.occ closes each shot's row as the reference solver does, to all the shot sends but what
/// lands on the backs of the sheets, weighted by the shot's density: the same solution to float
/// rounding (closing to all of it puts some objects 1.5% apart).
#[test]
fn carm_closes_rows_leaving_out_the_backs_of_sheets() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/two-rooms.obj");
    let settings = [scene, "--no-adapt", "--rays", "4", "--until", "unshot=0.05"];
    let reference = solve(&scratch("carm-sheets-reference"), &settings, &[]);
    let carm = solve(
        &scratch("carm-sheets"),
        &settings,
        &["--solver", "carm", "--nodes", "4", "--threads", "1"],
    );
    assert_eq!(carm["analysis"]["closed"], true, "{}", carm["analysis"]);
    assert!(
        carm["analysis"]["sheets"].as_u64() > Some(0),
        "{}",
        carm["analysis"]
    );
    assert_eq!(carm["stages"]["close_rows"], true);
    for ((obj, b), (_, r)) in means(&carm).iter().zip(&means(&reference)) {
        assert!(
            apart(b, r) <= 1e-5,
            "{obj}: carm {b:?} against reference {r:?}"
        );
    }
}

/// The bytes of all the voxels of a replicated run (each node holds them all).
fn all_voxel_bytes(report: &serde_json::Value) -> u64 {
    report["nodes"][0]["voxel_bytes"]
        .as_u64()
        .expect("voxel bytes")
}

/// Spreads `scene`'s voxels with `--node-memory node --cache cache` on 4 nodes and checks the
/// run against carm's replicated run (the same solution: the same shots and rays) and the
/// reference solver (within 1%), with the caches and the backing store at work and every node
/// within its budget. Returns the spread run's report.
fn assert_spread_agrees(
    name: &str,
    settings: &[&str],
    budget: impl Fn(u64) -> (u64, u64),
) -> serde_json::Value {
    let carm = ["--solver", "carm", "--nodes", "4", "--threads", "1"];
    let reference = solve(&scratch(&format!("{name}-reference")), settings, &[]);
    let replicated = solve(&scratch(&format!("{name}-replicated")), settings, &carm);
    let all = all_voxel_bytes(&replicated);
    let (node, cache) = budget(all);
    let (node_s, cache_s) = (node.to_string(), cache.to_string());
    let spread_flags = [
        "--node-memory",
        node_s.as_str(),
        "--cache",
        cache_s.as_str(),
    ];
    let out = scratch(name);
    let spread = solve(&out, settings, &[&carm[..], &spread_flags[..]].concat());
    assert!(
        out.join("backing-store.bin")
            .metadata()
            .expect("the backing store")
            .len()
            == all,
        "the backing store holds every voxel"
    );
    let (mut misses, mut reads, mut served) = (0, 0, 0);
    for n in spread["nodes"].as_array().expect("nodes") {
        let get = |k: &str| n[k].as_u64().unwrap_or_else(|| panic!("{k} in {n}"));
        assert_eq!(get("voxel_budget"), node, "{n}");
        assert!(get("voxel_bytes_peak") <= node, "over its budget: {n}");
        assert!(get("share_bytes") <= node - cache, "{n}");
        // every node walks rays; the root, which keeps no sample points, only those of the
        // receivers it poached
        assert_eq!(
            get("walks") > 0,
            get("node") > 0 || get("poached") > 0,
            "{n}"
        );
        misses += get("cache_misses");
        reads += get("store_reads");
        served += get("fetches_served");
    }
    assert!(misses > 0 && reads > 0, "{spread}");
    assert!(reads <= misses, "{spread}");
    assert!(
        served > 0,
        "no node served a fetch from its share: {spread}"
    );
    for ((obj, b), (_, r)) in means(&spread).iter().zip(&means(&replicated)) {
        assert!(
            apart(b, r) <= 1e-9,
            "{obj}: spread {b:?} against replicated {r:?}"
        );
    }
    assert_agree(&spread, &reference, "");
    spread
}

/// The table lamp's eight voxels spread so that a node keeps at most two voxels' worth (its
/// largest voxel is more than an eighth of them all).
#[test]
fn carm_spreads_the_table_lamps_voxels_over_caches_and_the_backing_store() {
    let settings = LAMP;
    assert_spread_agrees("carm-lamp-spread", &settings, |_| (2112, 1056));
}

/// A room of boxes, an octree of dozens of voxels, spread so that no node keeps more than an
/// eighth of them.
#[test]
fn carm_spreads_a_many_voxel_scene_with_an_eighth_of_it_a_node() {
    let scene = boxes_scene(&scratch("carm-boxes-scene"), 6);
    let scene = scene.to_str().expect("a UTF-8 path");
    let settings = [&[scene][..], &BOXES_SETTINGS].concat();
    let spread = assert_spread_agrees("carm-boxes-spread", &settings, |all| (all / 8, all / 16));
    assert!(
        spread["scene"]["octree"]["leaves"].as_u64() > Some(16),
        "{}",
        spread["scene"]["octree"]
    );
}

/// The Cornell box in voxels of at most eight triangles (`--voxel-triangles`; its default
/// octree is one voxel), every triangle in them (`--all-stages`: the box's walls can hide
/// nothing, and would be left out), spread so that no node keeps more than an eighth of them.
#[test]
fn carm_spreads_the_cornell_box_with_an_eighth_of_it_a_node() {
    let settings = [SETTINGS, &["--voxel-triangles", "8", "--all-stages"][..]].concat();
    let spread = assert_spread_agrees("carm-cornell-spread", &settings, |all| (all / 8, all / 16));
    assert!(
        spread["scene"]["octree"]["leaves"].as_u64() > Some(16),
        "{}",
        spread["scene"]["octree"]
    );
}

/// Task poaching: a node that runs out of receivers in a shot asks its neighbours for some, and
/// computes the form factors to those they lend it (programs/README.md, "Task poaching"). A
/// node lends only when it has two batches' worth left, so the programs are run with batches of
/// 32 receivers (`MAX.BATCH`; the table lamp's nodes have about a thousand each). With the lamp
/// spread over 4 nodes (`--threads 1`: the same loans every run), both geometry protocols, with
/// one task a node or two tasks and a thread, and the Cornell box spread (its coloured walls
/// make shots whose channels shoot apart, so loans repay each channel's form factors too), give
/// the solution they give with `--no-poach`, to the bit, with receivers lent: the root, which
/// keeps none of its own, computes some of its children's; every receiver lent is computed
/// once, and the form factors are those of the run without poaching.
#[test]
fn carm_poaching_moves_receivers_and_not_the_solution() {
    let copy = programs_with("carm-poach-programs", "VAL INT MAX.BATCH IS", "1024", "32");
    let (carm, named) = (copy.join("carm.occ"), copy.join("carm-named.occ"));
    let nodes = ["--solver", "carm", "--nodes", "4", "--threads", "1"];
    let walkers = ["--tasks", "2", "--worker-threads", "1"];
    let (carm_spread, named_spread) = (
        ["--node-memory", "2112", "--cache", "1056"],
        ["--node-memory", "4224", "--cache", "2112"],
    );
    // the Cornell box in voxels of at most 8 triangles, all 32 of them (16,752 bytes), an
    // eighth a node
    let cornell = [
        SETTINGS,
        &[
            "--until",
            "unshot=0.05",
            "--voxel-triangles",
            "8",
            "--all-stages",
        ],
    ]
    .concat();
    let cornell_spread = ["--node-memory", "2094", "--cache", "1047"];
    for (name, program, scene, spread, walkers) in [
        ("carm", &carm, &LAMP[..], &carm_spread[..], &[][..]),
        ("named", &named, &LAMP, &named_spread, &[][..]),
        ("named-walkers", &named, &LAMP, &named_spread, &walkers[..]),
        ("carm-cornell", &carm, &cornell, &cornell_spread, &[][..]),
    ] {
        let program = program.to_str().expect("a UTF-8 path");
        let mut flags = [&nodes[..], spread, walkers, &["--program", program]].concat();
        let poaching = solve(&scratch(&format!("carm-poach-{name}")), scene, &flags);
        flags.push("--no-poach");
        let alone = solve(&scratch(&format!("carm-poach-{name}-not")), scene, &flags);
        assert_eq!(means(&poaching), means(&alone), "{name}");
        assert_eq!(poaching["totals"], alone["totals"], "{name}");
        let sum = |report: &serde_json::Value, key: &str| -> u64 {
            let nodes = report["nodes"].as_array().expect("nodes");
            nodes.iter().map(|n| n[key].as_u64().expect(key)).sum()
        };
        for key in ["poaches", "poached", "lent"] {
            assert_eq!(sum(&alone, key), 0, "{name}: {key} without poaching");
        }
        assert_eq!(sum(&poaching, "poached"), sum(&poaching, "lent"), "{name}");
        assert_eq!(
            sum(&poaching, "form_factors"),
            sum(&alone, "form_factors"),
            "{name}"
        );
        let root = &poaching["nodes"][0];
        assert_eq!(root["points"], 0, "{name}: {root}");
        assert!(root["poached"].as_u64() > Some(0), "{name}: {root}");
        assert_eq!(root["form_factors"], root["poached"], "{name}: {root}");
    }
}

/// A node's tasks and threads take its receivers in turn, and its database manager walks their
/// rays, parking a batch that waits for voxels while the others go on: with the Cornell box
/// spread (an eighth of it a node, every triangle in the octree), two tasks and two threads a
/// node give the very solution one task gives, and every node's walks still fetch.
#[test]
fn carm_tasks_and_threads_give_the_same_solution() {
    let settings = [SETTINGS, &["--voxel-triangles", "8", "--all-stages"][..]].concat();
    let carm = ["--solver", "carm", "--nodes", "4", "--threads", "1"];
    let replicated = solve(&scratch("carm-walkers-replicated"), &settings, &carm);
    let all = all_voxel_bytes(&replicated);
    let (node, cache) = ((all / 8).to_string(), (all / 16).to_string());
    let spread = [&carm[..], &["--node-memory", &node, "--cache", &cache]].concat();
    let one = solve(&scratch("carm-walkers-one"), &settings, &spread);
    let many = [&spread[..], &["--tasks", "2", "--worker-threads", "2"]].concat();
    let four = solve(&scratch("carm-walkers-four"), &settings, &many);
    assert_eq!(means(&one), means(&four));
    assert_eq!(one["totals"], four["totals"]);
    // the receivers went out in smaller batches, one at a time to each walker
    let nodes = |r: &serde_json::Value| r["nodes"].as_array().expect("nodes").clone();
    for (a, b) in nodes(&one).iter().zip(&nodes(&four)).skip(1) {
        assert!(b["walks"].as_u64() > a["walks"].as_u64(), "{a}\n{b}");
        assert!(b["cache_misses"].as_u64() > Some(0), "{b}");
    }
}

#[test]
fn carm_refuses_bad_voxel_budgets_by_name() {
    let out = scratch("carm-budget-refusals");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/table-lamp.obj");
    let carm = [
        scene,
        "--all-stages",
        "--solver",
        "carm",
        "--no-adapt",
        "--until",
        "shots=1",
    ];
    for (flags, says) in [
        (
            &["--node-memory", "4096", "--cache", "1000"][..],
            "--cache 1000: smaller than the scene's largest voxel (1056 bytes)",
        ),
        (
            &["--node-memory", "1K", "--cache", "2K"][..],
            "--node-memory 1024 is smaller than --cache 2048",
        ),
        (
            &["--node-memory", "4K", "--cache", "2K", "--nodes", "200"][..],
            "too few for 200 nodes each fetching 8 voxels of up to 1056 bytes",
        ),
        (&["--node-memory", "4096"][..], "--cache"),
        (&["--node-memory", "4096", "--cache", "2Q"][..], "K, M or G"),
    ] {
        let output = Command::new(env!("CARGO_BIN_EXE_occ"))
            .arg("radiosity")
            .arg("--out")
            .arg(&out)
            .args(carm)
            .args(flags)
            .output()
            .expect("the occ binary runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{flags:?} should fail");
        assert!(stderr.contains(says), "{flags:?}: {stderr}");
    }
    // The reference solver holds the whole scene: the settings are carm's.
    let output = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("radiosity")
        .arg("--out")
        .arg(&out)
        .args([
            "--solver",
            "reference",
            "--node-memory",
            "4096",
            "--cache",
            "2048",
        ])
        .output()
        .expect("the occ binary runs");
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("not with --solver reference"));
}

/// report.json lists the intrinsics of `radiosity.inc` that carm.occ never calls, left out of
/// its compiled program.
#[test]
fn carm_lists_the_intrinsics_it_does_not_call() {
    let (_, report) = &carm_runs()[0];
    let left_out: Vec<&str> = report["left_out"]
        .as_array()
        .expect("left_out is a list")
        .iter()
        .filter_map(|v| v.as_str())
        .filter(|l| l.starts_with("carm.occ: "))
        .collect();
    assert_eq!(left_out.len(), 1, "{report}");
    assert!(
        left_out[0].contains(" intrinsics not compiled: nothing calls them"),
        "{}",
        left_out[0]
    );
}
