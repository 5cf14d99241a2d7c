//! Issue 13, stiff scenes: closed unit boxes whose six faces all emit E = 1 with reflectance ρ
//! (`scenes/stiff/box-ρ.obj`) must converge to B = E / (1 - ρ) within 1%, by the solver's own
//! stopping rule, with overshooting chosen automatically, and keep the energy balance.

use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::scene::{self, Scene};
use occ_radiosity::solver::{Solver, SolverConfig, Until};

fn stiff_box(rho: &str) -> Scene {
    let obj = match rho {
        "0.5" => include_str!("../../scenes/stiff/box-0.5.obj"),
        "0.9" => include_str!("../../scenes/stiff/box-0.9.obj"),
        "0.99" => include_str!("../../scenes/stiff/box-0.99.obj"),
        "0.999" => include_str!("../../scenes/stiff/box-0.999.obj"),
        _ => panic!("no stiff scene for rho {rho}"),
    };
    let mtl = include_str!("../../scenes/stiff/stiff.mtl");
    scene::load_obj(&format!("box-{rho}.obj"), obj, &|_| Ok(mtl.to_string())).expect("scene")
}

/// Solves the stiff box of reflectance `rho` until the default rule (every object within 1% by
/// the solver's estimate) holds, or `max_shots`.
fn solve(scene: &Scene, acceleration: Acceleration, max_shots: u64) -> Solver<'_> {
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
    solver.run(|_, _| {});
    solver
}

/// The worst relative error of any object's mean B against E / (1 - ρ).
fn worst_error(solver: &Solver, rho: f64) -> f64 {
    let expected = 1.0 / (1.0 - rho);
    solver
        .object_means()
        .iter()
        .flat_map(|(_, b)| b.to_array())
        .map(|c| (c / expected - 1.0).abs())
        .fold(0.0, f64::max)
}

fn converges(rho: &str) {
    let scene = stiff_box(rho);
    let solver = solve(&scene, Acceleration::Auto, 20_000);
    let r: f64 = rho.parse().expect("rho");
    let err = worst_error(&solver, r);
    assert!(
        err < 0.01,
        "rho {rho}: worst error {err} after {} shots",
        solver.stats.shots
    );
    assert!(
        solver.accounts.balance_error() < 1e-9,
        "rho {rho}: {:?}",
        solver.accounts
    );
    assert!(solver.analysis.closed, "the stiff box is closed");
    assert!(
        solver.stats.overshoots > 0,
        "rho {rho}: Auto must overshoot"
    );
}

#[test]
fn rho_0_5_converges_to_e_over_one_minus_rho() {
    converges("0.5");
}

#[test]
fn rho_0_9_converges_to_e_over_one_minus_rho() {
    converges("0.9");
}

#[test]
fn rho_0_99_converges_to_e_over_one_minus_rho() {
    converges("0.99");
}

#[test]
fn rho_0_999_converges_to_e_over_one_minus_rho() {
    converges("0.999");
}

#[test]
fn without_overshooting_rho_0_9_converges_too_but_slower() {
    let scene = stiff_box("0.9");
    let plain = solve(&scene, Acceleration::Off, 20_000);
    let over = solve(&scene, Acceleration::Auto, 20_000);
    assert!(worst_error(&plain, 0.9) < 0.01);
    assert_eq!(plain.stats.overshoots, 0);
    assert!(
        over.stats.shots * 2 < plain.stats.shots,
        "overshooting {} shots, plain {}",
        over.stats.shots,
        plain.stats.shots
    );
}
