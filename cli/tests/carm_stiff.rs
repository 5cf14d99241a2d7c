//! Issue 13 on carm.occ (`occ radiosity --solver carm --no-adapt`, one node, `--threads 1`):
//! - the stiff furnace boxes (`scenes/stiff/`: closed unit boxes whose faces all emit E = 1 with
//!   reflectance ρ, so B = E / (1 - ρ) everywhere) converge to that within 1% and keep the
//!   energy balance;
//! - a lone emitter (`scenes/extreme/lone-emitter.obj`) loses all its power and keeps B = E;
//! - a scene without an emitter (`scenes/extreme/no-emitter.obj`) is refused with a message.
//!
//! As the reference solver does, carm.occ closes each shot's form-factor row in these closed
//! convex boxes and, where the scene is stiff, overshoots by the ambient estimate
//! (`--acceleration auto`): ρ = 0.999 converges in hundreds of shots, not hundreds of thousands.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{balance_error, means, rgb, scratch};

/// A scene of the repository's `scenes/` folder.
fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name)
}

/// Runs `occ radiosity SCENE --solver carm --no-adapt` with `extra` flags into `out`.
fn carm(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("radiosity")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args([
            "--solver",
            "carm",
            "--no-adapt",
            "--nodes",
            "1",
            "--threads",
            "1",
            "--image-size",
            "16",
        ])
        .args(extra)
        .output()
        .expect("the occ binary runs")
}

/// Runs carm.occ as [`carm`] does and returns its report.json.
fn report(scene: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let output = carm(scene, out, extra);
    assert!(
        output.status.success(),
        "occ radiosity {} {extra:?} failed:\n{}",
        scene.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    let text = std::fs::read_to_string(out.join("report.json")).expect("report.json written");
    serde_json::from_str(&text).expect("report.json parses")
}

/// Solves the stiff box of reflectance `rho` with carm.occ and checks every object's mean B
/// against E / (1 - ρ) within 1%, and the energy balance within 1e-9.
fn furnace(rho: &str, until: &str, overshoot: &str, acceleration: &str) {
    let out = scratch(&format!("carm-stiff-{rho}"));
    let report = report(
        &scene(&format!("stiff/box-{rho}.obj")),
        &out,
        &[
            "--rays",
            "4",
            "--patch-size",
            "0.5",
            "--element-size",
            "0.25",
            "--until",
            until,
            "--overshoot",
            overshoot,
            "--acceleration",
            acceleration,
        ],
    );
    assert_eq!(report["solver"], "carm");
    let expected = 1.0 / (1.0 - rho.parse::<f64>().expect("rho"));
    let shots = &report["nodes"][0]["stats"]["shots"];
    for (name, b) in means(&report) {
        for c in b {
            let err = (c / expected - 1.0).abs();
            assert!(
                err < 0.01,
                "rho {rho}: {name} B {b:?}, expected {expected} ({:.2}% off after {shots} shots)",
                100.0 * err
            );
        }
    }
    let balance = balance_error(&report);
    assert!(balance < 1e-9, "rho {rho}: energy balance {balance:e}");
}

#[test]
fn carm_furnace_rho_0_5_converges_to_e_over_one_minus_rho() {
    furnace("0.5", "unshot=0.001", "1", "auto");
}

#[test]
fn carm_furnace_rho_0_9_converges_to_e_over_one_minus_rho() {
    furnace("0.9", "unshot=0.001", "1", "auto");
}

#[test]
fn carm_furnace_rho_0_99_converges_to_e_over_one_minus_rho() {
    furnace("0.99", "error=0.01", "1", "auto");
}

#[test]
fn carm_furnace_rho_0_999_converges_to_e_over_one_minus_rho() {
    furnace("0.999", "error=0.01", "1", "auto");
}

#[test]
fn carm_lone_emitter_loses_all_its_power() {
    let out = scratch("carm-lone-emitter");
    let report = report(
        &scene("extreme/lone-emitter.obj"),
        &out,
        &["--rays", "4", "--until", "unshot=0.000001"],
    );
    let t = &report["totals"];
    let [emitted, absorbed, escaped] = ["emitted", "absorbed", "escaped"].map(|k| rgb(&t[k]));
    for c in 0..3 {
        assert!(
            (escaped[c] - emitted[c]).abs() <= 1e-9 * emitted[c],
            "escaped {escaped:?} of {emitted:?}"
        );
        assert_eq!(absorbed[c], 0.0);
    }
    let (name, b) = &means(&report)[0];
    assert_eq!(name, "light");
    // E = π Ke with Ke = 1, and nothing comes back.
    for c in b {
        assert!((c - std::f64::consts::PI).abs() < 1e-6, "light B {b:?}");
    }
}

#[test]
fn carm_refuses_a_scene_without_an_emitter() {
    let out = scratch("carm-no-emitter");
    let path = scene("extreme/no-emitter.obj");
    let output = carm(&path, &out, &["--until", "unshot=0.01"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "no emitter should be refused");
    assert!(
        stderr.contains("no-emitter.obj") && stderr.contains("no emitters"),
        "{stderr}"
    );
}
