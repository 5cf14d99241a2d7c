//! The table of shots and time against reflectance for the stiff scenes (`scenes/stiff/`):
//! closed unit boxes whose faces all emit E = 1, where B = E / (1 - ρ) everywhere. Each box is
//! solved by the default stopping rule (every object within 1% by the solver's estimate) three
//! ways: as plain progressive refinement (no row closing, no overshooting), with the form-factor
//! rows closed, and with both (the default). Prints a Markdown table.
//!
//!     cargo run --release -p occ-radiosity --example stiff_table [-- MAX_SHOTS]

use std::time::Instant;

use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::scene::{self, Scene};
use occ_radiosity::solver::{Solver, SolverConfig, Until};

const SCENES: [(&str, &str); 4] = [
    ("0.5", include_str!("../../scenes/stiff/box-0.5.obj")),
    ("0.9", include_str!("../../scenes/stiff/box-0.9.obj")),
    ("0.99", include_str!("../../scenes/stiff/box-0.99.obj")),
    ("0.999", include_str!("../../scenes/stiff/box-0.999.obj")),
];

/// One way of solving: its name, whether rows are closed, the acceleration.
const WAYS: [(&str, bool, Acceleration); 3] = [
    ("plain", false, Acceleration::Off),
    ("rows closed", true, Acceleration::Off),
    ("rows closed + overshoot", true, Acceleration::Auto),
];

fn main() {
    let max_shots: u64 = std::env::args()
        .nth(1)
        .map_or(200_000, |s| s.parse().expect("MAX_SHOTS is a number"));
    let mtl = include_str!("../../scenes/stiff/stiff.mtl");
    println!("| rho | solver | shots | seconds | worst error of B | energy balance | rule met |");
    println!("| --- | --- | ---: | ---: | ---: | ---: | --- |");
    for (rho, obj) in SCENES {
        let scene = scene::load_obj(&format!("box-{rho}.obj"), obj, &|_| Ok(mtl.to_string()))
            .expect("stiff scene");
        let r: f64 = rho.parse().expect("rho");
        for (name, close, acceleration) in WAYS {
            let (solver, seconds) = solve(&scene, close, acceleration, max_shots);
            let expected = 1.0 / (1.0 - r);
            let worst = solver
                .object_means()
                .iter()
                .flat_map(|(_, b)| b.to_array())
                .map(|c| (c / expected - 1.0).abs())
                .fold(0.0, f64::max);
            println!(
                "| {rho} | {name} | {} | {seconds:.3} | {:.2}% | {:.1e} | {} |",
                solver.stats.shots,
                worst * 100.0,
                solver.accounts.balance_error(),
                if solver.stats.shots < max_shots {
                    "yes"
                } else {
                    "no (shot limit)"
                }
            );
        }
    }
}

fn solve(
    scene: &Scene,
    close: bool,
    acceleration: Acceleration,
    max_shots: u64,
) -> (Solver<'_>, f64) {
    let mesh = MeshConfig {
        patch_size: 0.5,
        element_size: 0.25,
    };
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 4,
            offset: 1e-6,
            ..FormFactorConfig::default()
        },
        acceleration,
        until: Until::Error(0.01),
        max_shots,
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(scene, Mesh::from_scene(scene, mesh), config);
    solver.stages.close_rows = close;
    let start = Instant::now();
    solver.run(|_, _| {});
    (solver, start.elapsed().as_secs_f64())
}
