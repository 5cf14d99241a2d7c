//! The default command, `occ radiosity` (carm.occ on 13 nodes, every setting at its default),
//! holds every surface of the Cornell box to the stored path-traced reference: within 1% per
//! channel (2% where the channel is below a tenth of the scene's area-weighted mean, the light
//! included: the dim block faces), plus three of the reference's standard errors, as the
//! reference solver's own test holds it (`radiosity/tests/accuracy.rs`). By the corners'
//! average carm.occ's ceiling read 1.4-1.7% low here (programs/README.md, "Quadratic booking").
//! Its probes (`scenes/references/cornell-box.probes`, every one away from the edges) read
//! within 3% of the path tracer's.

mod common;
use std::path::PathBuf;
use std::sync::OnceLock;

use common::{means, scratch, solve};
use occ_radiosity::output::truth::Reference;

/// The path-traced reference of the Cornell box.
fn reference() -> Reference {
    let text = include_str!("../../scenes/references/cornell-box.pathtrace.json");
    Reference::parse("cornell-box.pathtrace.json", text).expect("the reference")
}

/// The default command's report and output directory, run once for the tests here.
fn default_run() -> &'static (serde_json::Value, PathBuf) {
    static RUN: OnceLock<(serde_json::Value, PathBuf)> = OnceLock::new();
    RUN.get_or_init(|| {
        let out = scratch("carm-accuracy");
        let probes = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/references/cornell-box.probes"
        );
        let report = solve(&out, &["--image-size", "16", "--probe", probes], &[]);
        (report, out)
    })
}

#[test]
fn the_default_command_holds_every_cornell_surface_to_the_path_tracer() {
    let reference = reference();
    let (report, _) = default_run();
    assert_eq!(report["solver"], "carm");
    let mut checked = 0;
    for (name, b) in means(report) {
        if name == "light" {
            continue;
        }
        let r = reference
            .object(&name)
            .expect("the object in the reference");
        for (c, ours) in b.into_iter().enumerate() {
            let truth = r.mean_b[c];
            assert!(
                (ours - truth).abs() <= reference.tolerance(r, c),
                "{name} channel {c}: carm.occ {ours} against path-traced {truth} ± {} ({:+.2}%)",
                r.std_err[c],
                100.0 * (ours - truth) / truth
            );
        }
        checked += 1;
    }
    assert_eq!(
        checked,
        reference.objects.len() - 1,
        "every surface checked"
    );
}

#[test]
fn the_default_command_reads_the_cornell_probes_within_3_percent() {
    // Gathered at each probe (`b_*`); the mesh's interpolation (`mesh_*`) read 3-20% off at
    // three of them, in the blocks' penumbrae and beside the walls, before the gather.
    let reference = reference();
    let (_, out) = default_run();
    let csv = std::fs::read_to_string(out.join("probe.csv")).expect("probe.csv written");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let b = ["b_r", "b_g", "b_b"].map(column);
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), reference.probes.len(), "a row per probe");
    for (row, truth) in rows.iter().zip(&reference.probes) {
        let truth = truth.b.as_ref().expect("the probe on a surface");
        for c in 0..3 {
            let (ours, t) = (row[b[c]], truth.mean[c]);
            assert!(
                (ours - t).abs() <= 0.03 * t,
                "probe at {:?} channel {c}: {ours} against path-traced {t} ({:+.2}%)",
                &row[..3],
                100.0 * (ours - t) / t
            );
        }
    }
}

#[test]
fn the_default_command_reads_the_two_rooms_probes_within_3_percent() {
    // Room B is lit only through the doorway; report.json holds each probe against the
    // path-traced reference given with `--reference`.
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes");
    let (scene, probes, reference) = (
        format!("{dir}/two-rooms.obj"),
        format!("{dir}/references/two-rooms.probes"),
        format!("{dir}/references/two-rooms-probes.pathtrace.json"),
    );
    let report = solve(
        &scratch("carm-accuracy-two-rooms"),
        &[&scene, "--image-size", "16", "--probe", &probes],
        &["--reference", &reference],
    );
    let errors = report["probes"].as_array().expect("the probes' errors");
    assert_eq!(errors.len(), 16, "every probe held to the reference");
    for e in errors {
        for c in 0..3 {
            let error = e["relative_error"][c].as_f64().expect("an error");
            assert!(
                error.abs() <= 0.03,
                "probe at {}: {:+.2}%",
                e["pos"],
                100.0 * error
            );
        }
    }
}
