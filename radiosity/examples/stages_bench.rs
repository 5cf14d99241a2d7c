//! What leaving out the stages a scene does not need saves ([`occ_radiosity::analysis`]): the
//! convex room (`scenes/convex-room.obj`, no shadow rays) and the Cornell box (which needs every
//! stage), each solved by the default stopping rule (every object within 1% by the solver's
//! estimate) with the stages the analysis chooses and with every stage forced on
//! (`all_stages`, `occ radiosity --all-stages`). Default mesh sizes of `occ radiosity` (patches a
//! quarter of the diagonal, elements a twentieth), 8 rays per form factor, adaptive subdivision
//! off so that both solves shoot the same mesh. Each solve runs `REPEATS` times (default 3); the
//! table gives the fastest, and the largest difference of any object's mean B between the two.
//! Run it with `RAYON_NUM_THREADS=1` on a loaded machine: one thread is measured more steadily.
//!
//!     cargo run --release -p occ-radiosity --example stages_bench [-- REPEATS]

use std::time::Instant;

use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::scene::{self, Scene, cornell};
use occ_radiosity::solver::{Solver, SolverConfig, Until};

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .map_or(3, |s| s.parse().expect("REPEATS is a number"));
    let room = scene::load_obj(
        "convex-room.obj",
        include_str!("../../scenes/convex-room.obj"),
        &|_| Ok(include_str!("../../scenes/convex-room.mtl").to_string()),
    )
    .expect("convex room");
    let cornell = cornell::load(true).expect("Cornell box");
    println!(
        "| scene | stages | left out | shots | shadow rays | seconds (best of {repeats}) | \
         saving | largest difference of an object's B |"
    );
    println!("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |");
    for (name, scene) in [("convex room", &room), ("Cornell box", &cornell)] {
        let (lean, lean_s) = best(scene, false, repeats);
        let (full, full_s) = best(scene, true, repeats);
        let worst = lean
            .object_means()
            .iter()
            .zip(full.object_means())
            .flat_map(|((_, a), (_, b))| (0..3).map(move |c| (a[c] - b[c]).abs() / b[c].abs()))
            .filter(|d| d.is_finite())
            .fold(0.0, f64::max);
        for (stages, solver, seconds) in [
            ("as analysed", &lean, lean_s),
            ("all forced on", &full, full_s),
        ] {
            let left_out = solver.stages.left_out();
            println!(
                "| {name} | {stages} | {} | {} | {} | {seconds:.3} | {} | {} |",
                if left_out.is_empty() {
                    "nothing".to_string()
                } else {
                    left_out
                        .iter()
                        .map(|s| s.split(':').next().unwrap_or(s))
                        .collect::<Vec<_>>()
                        .join(", ")
                },
                solver.stats.shots,
                solver.stats.rays,
                if !std::ptr::eq(solver, &lean) {
                    "-".into()
                } else if left_out.is_empty() {
                    // The same solve twice: the difference is the machine's noise.
                    format!("none ({:+.0}% noise)", 100.0 * (1.0 - lean_s / full_s))
                } else {
                    format!("{:.0}%", 100.0 * (1.0 - lean_s / full_s))
                },
                if std::ptr::eq(solver, &lean) {
                    format!("{:.3}%", 100.0 * worst)
                } else {
                    "-".into()
                },
            );
        }
    }
}

/// The fastest of `repeats` solves (they are deterministic: the same seed gives the same shots).
fn best(scene: &Scene, all_stages: bool, repeats: usize) -> (Solver<'_>, f64) {
    let mut fastest: Option<(Solver<'_>, f64)> = None;
    for _ in 0..repeats.max(1) {
        let (solver, seconds) = solve(scene, all_stages);
        if fastest.as_ref().is_none_or(|(_, s)| seconds < *s) {
            fastest = Some((solver, seconds));
        }
    }
    fastest.expect("one solve at least")
}

fn solve(scene: &Scene, all_stages: bool) -> (Solver<'_>, f64) {
    let d = scene.diagonal();
    let mesh = MeshConfig {
        patch_size: d / 4.0,
        element_size: d / 20.0,
    };
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 8,
            offset: d * 1e-6,
            ..FormFactorConfig::default()
        },
        adapt: None,
        until: Until::Error(0.01),
        all_stages,
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(scene, Mesh::from_scene(scene, mesh), config);
    let start = Instant::now();
    solver.run(|_, _| {});
    (solver, start.elapsed().as_secs_f64())
}
