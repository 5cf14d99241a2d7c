//! The reference solver against analytic answers: the closed furnace box B = E / (1 - ρ), the
//! Cornell floor centre direct irradiance, energy balance, and stiff and extreme scenes.

mod common;

use glam::Vec3;
use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::gather::Gather;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::output::probe::{Probe, evaluate, gathered};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::scene::{self, Scene, cornell};
use occ_radiosity::solver::{AdaptConfig, Solver, SolverConfig, Until};

fn solve(scene: &Scene, mesh: MeshConfig, config: SolverConfig) -> Solver<'_> {
    let mut solver = Solver::new(scene, Mesh::from_scene(scene, mesh), config);
    solver.run(|_, _| {});
    solver
}

#[test]
fn closed_furnace_box_converges_to_e_over_one_minus_rho() {
    // Every face emits E = 1 (Ke = 1/π) with ρ = 0.5: B = 2 everywhere.
    for rho in [0.5f32, 0.8] {
        let scene = common::closed_box(Vec3::ZERO, Vec3::ONE, rho, |_| std::f32::consts::FRAC_1_PI);
        let config = SolverConfig {
            until: Until::Unshot(1e-5),
            ..SolverConfig::default()
        };
        let solver = solve(
            &scene,
            MeshConfig {
                patch_size: 0.4,
                element_size: 0.2,
            },
            config,
        );
        let expected = 1.0 / (1.0 - rho as f64);
        for (i, (_, b)) in solver.object_means().iter().enumerate() {
            for c in b.to_array() {
                assert!(
                    (c / expected - 1.0).abs() < 0.005,
                    "rho {rho} face {i}: B = {c}, expected {expected}"
                );
            }
        }
        assert!(
            solver.accounts.balance_error() < 1e-9,
            "{:?}",
            solver.accounts
        );
    }
}

#[test]
fn closed_furnace_room_with_a_block_in_it_converges_to_e_over_one_minus_rho() {
    // A non-convex closed scene: the unit box with a box standing in the air inside it, faces
    // outward. Every face emits E = 1 and reflects ρ = 0.8, so B = 5 everywhere; nothing can
    // escape, so the rows are closed and every shot's power stays in the scene.
    let rho = 0.8f32;
    let e = std::f32::consts::FRAC_1_PI;
    let mut scene = common::closed_box(Vec3::ZERO, Vec3::ONE, rho, |_| e);
    let block = common::closed_box(
        Vec3::new(0.3, 0.2, 0.35),
        Vec3::new(0.6, 0.5, 0.7),
        rho,
        |_| e,
    );
    let first = scene.objects.len() as u32;
    for mut o in block.objects {
        o.name = format!("block {}", o.name);
        scene.objects.push(o);
    }
    for mut t in block.triangles {
        t.tri = occ_radiosity::geom::Tri::new(t.tri.v[0], t.tri.v[2], t.tri.v[1]);
        t.object += first;
        scene.triangles.push(t);
    }
    let config = SolverConfig {
        until: Until::Unshot(1e-5),
        ..SolverConfig::default()
    };
    let mesh = MeshConfig {
        patch_size: 0.4,
        element_size: 0.2,
    };
    let solver = solve(&scene, mesh, config);
    assert!(
        !solver.analysis.convex && solver.analysis.closed && solver.stages.close_rows,
        "{:?}",
        solver.analysis
    );
    let a = solver.accounts;
    for c in 0..3 {
        assert!(a.escaped[c].abs() <= 1e-6 * a.emitted[c], "{a:?}");
    }
    let expected = 1.0 / (1.0 - rho as f64);
    let (mut sum, mut area) = (0.0, 0.0);
    let areas = solver.object_areas();
    for (i, (_, b)) in solver.object_means().iter().enumerate() {
        for c in b.to_array() {
            assert!(
                (c / expected - 1.0).abs() < 0.01,
                "{}: B = {c}, expected {expected}",
                solver.scene.objects[i].name
            );
        }
        sum += b.x * areas[i];
        area += areas[i];
    }
    assert!((sum / area / expected - 1.0).abs() < 1e-3, "{}", sum / area);
    assert!(a.balance_error() < 1e-9, "{a:?}");
}

fn light_patches(solver: &Solver) -> u64 {
    let light = solver
        .scene
        .objects
        .iter()
        .position(|o| o.name == "light")
        .expect("light") as u32;
    solver
        .mesh
        .patch_object
        .iter()
        .filter(|&&o| o == light)
        .count() as u64
}

/// The Cornell box without its blocks, meshed coarsely, before any shot.
fn open_cornell_solver(scene: &Scene) -> Solver<'_> {
    let mesh = MeshConfig {
        patch_size: 120.0,
        element_size: 30.0,
    };
    Solver::new(
        scene,
        Mesh::from_scene(scene, mesh),
        SolverConfig::default(),
    )
}

/// The centre of the Cornell box's floor.
const FLOOR_CENTRE: Probe = Probe {
    pos: Vec3::new(278.0, 0.0, 279.6),
    normal: Vec3::Y,
};

/// Asserts that `b`, the floor's radiosity at its centre, is the floor's reflectance times the
/// direct irradiance there within `tolerance` (relative): H = (0.7590, 0.5358, 0.1786), F =
/// 0.014212 to the light times L = (17, 12, 4) π, which Mitsuba with direct lighting only
/// reproduces (0.7589, 0.5359, 0.1786).
fn assert_direct_light_at_the_floor_centre(scene: &Scene, b: Vec3, tolerance: f32) {
    let floor = (scene.objects.iter())
        .find(|o| o.name == "floor")
        .expect("floor");
    let h = b / floor.reflectance;
    let expected = Vec3::new(0.7590, 0.5358, 0.1786);
    for c in 0..3 {
        assert!(
            (h[c] / expected[c] - 1.0).abs() < tolerance,
            "H = {h}, expected {expected}"
        );
    }
}

#[test]
fn cornell_floor_centre_direct_irradiance() {
    // Blocks removed; after every light patch has shot once, the floor's centre holds the direct
    // light within 1%.
    let scene = cornell::load(false).expect("scene");
    let mut solver = open_cornell_solver(&scene);
    for _ in 0..light_patches(&solver) {
        assert!(solver.shoot_once());
    }
    let b = evaluate(&solver, &FLOOR_CENTRE).expect("probe on the floor");
    assert_direct_light_at_the_floor_centre(&scene, b, 0.01);
}

#[test]
fn a_gather_before_any_shot_is_the_direct_light() {
    // Before any shot only the light has radiosity, so the radiosity gathered at the floor's
    // centre is the direct light's. Gathered with 1,024 rays to each light patch, it holds
    // to a fifth of a percent, where the mesh, which nothing has reached, reads it dark.
    let scene = cornell::load(false).expect("scene");
    let solver = open_cornell_solver(&scene);
    let gather = Gather::new(&solver);
    let b = gathered(&solver, &gather, &FLOOR_CENTRE, 1).expect("probe on the floor");
    assert_direct_light_at_the_floor_centre(&scene, b, 0.002);
    assert_eq!(evaluate(&solver, &FLOOR_CENTRE), Some(Vec3::ZERO));
}

#[test]
fn cornell_box_energy_balance_and_convergence() {
    let scene = cornell::load(true).expect("scene");
    let adapt = AdaptConfig {
        difference: 0.3,
        nonlinearity: 0.1,
        min_edge: 5.0,
        min_shot_power: 0.01,
        passes: 2,
        max_vertices: 5000,
    };
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 4,
            ..FormFactorConfig::default()
        },
        adapt: Some(adapt),
        until: Until::Unshot(0.1),
        ..SolverConfig::default()
    };
    let solver = solve(
        &scene,
        MeshConfig {
            patch_size: 200.0,
            element_size: 80.0,
        },
        config,
    );
    assert!(solver.unshot_fraction() <= 0.1);
    assert!(
        solver.accounts.balance_error() < 1e-9,
        "{:?}",
        solver.accounts
    );
    assert!(
        solver.stats.adaptive_splits > 0,
        "the block shadows must be refined"
    );
    // The box is open at the front: some power escapes, most is absorbed.
    let a = solver.accounts;
    for c in 0..3 {
        assert!(
            a.escaped[c] > 0.05 * a.emitted[c] && a.absorbed[c] > 0.5 * a.emitted[c],
            "{a:?}"
        );
    }
    // Colour bleeding: the red wall is red, the green wall green.
    let means = solver.object_means();
    let by = |n: &str| {
        means[scene
            .objects
            .iter()
            .position(|o| o.name == n)
            .expect("object")]
        .1
    };
    assert!(by("red_wall").x > 3.0 * by("red_wall").y);
    assert!(by("green_wall").y > 2.0 * by("green_wall").x);
}

#[test]
fn overshooting_converges_with_fewer_shots() {
    let scene = common::closed_box(
        Vec3::ZERO,
        Vec3::ONE,
        0.9,
        |f| if f == 3 { 1.0 } else { 0.0 },
    );
    let mesh = MeshConfig {
        patch_size: 0.5,
        element_size: 0.5,
    };
    let plain = solve(
        &scene,
        mesh,
        SolverConfig {
            until: Until::Unshot(1e-3),
            acceleration: Acceleration::Off,
            ..SolverConfig::default()
        },
    );
    // A fixed over-relaxation factor (Gortler et al. 1993), without the ambient overshoot.
    let over = SolverConfig {
        until: Until::Unshot(1e-3),
        overshoot: 1.5,
        acceleration: Acceleration::Off,
        ..SolverConfig::default()
    };
    let over = solve(&scene, mesh, over);
    assert!(over.accounts.balance_error() < 1e-9);
    assert!(
        over.stats.shots < plain.stats.shots,
        "{} vs {}",
        over.stats.shots,
        plain.stats.shots
    );
}

fn load_scene_file(obj: &str, name: &str) -> Scene {
    let mtl = include_str!("../../scenes/test-scenes.mtl");
    scene::load_obj(name, obj, &|_| Ok(mtl.to_string())).expect("scene")
}

/// Solves a scene from `scenes/` and checks it stays finite and balanced.
fn stable(obj: &str, name: &str, mesh_fraction: f32, until: Until) -> f64 {
    let scene = load_scene_file(obj, name);
    let d = scene.diagonal();
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 4,
            offset: d * 1e-6,
            ..FormFactorConfig::default()
        },
        until,
        max_shots: 20_000,
        ..SolverConfig::default()
    };
    let solver = solve(
        &scene,
        MeshConfig {
            patch_size: d * mesh_fraction,
            element_size: d * mesh_fraction,
        },
        config,
    );
    assert!(
        solver.accounts.balance_error() < 1e-9,
        "{name}: {:?}",
        solver.accounts
    );
    for (_, b) in solver.object_means() {
        assert!(b.is_finite() && b.min_element() >= 0.0, "{name}: {b}");
    }
    solver.unshot_fraction()
}

#[test]
fn stiff_scene_with_reflectance_near_one_converges() {
    let f = stable(
        include_str!("../../scenes/stiff-box.obj"),
        "stiff-box.obj",
        0.3,
        Until::Unshot(0.01),
    );
    assert!(f <= 0.01);
}

#[test]
fn huge_and_tiny_scales_give_the_same_answer() {
    let huge = load_scene_file(include_str!("../../scenes/huge-box.obj"), "huge-box.obj");
    let tiny = load_scene_file(include_str!("../../scenes/tiny-box.obj"), "tiny-box.obj");
    let mut results = Vec::new();
    for scene in [&huge, &tiny] {
        let d = scene.diagonal();
        let config = SolverConfig {
            form_factor: FormFactorConfig {
                rays: 4,
                offset: d * 1e-6,
                ..FormFactorConfig::default()
            },
            until: Until::Unshot(1e-3),
            ..SolverConfig::default()
        };
        let solver = solve(
            scene,
            MeshConfig {
                patch_size: d * 0.3,
                element_size: d * 0.3,
            },
            config,
        );
        assert!(solver.accounts.balance_error() < 1e-9);
        // Radiosity does not depend on scale: compare mean B per object.
        results.push(
            solver
                .object_means()
                .iter()
                .map(|(_, b)| *b)
                .collect::<Vec<_>>(),
        );
    }
    // The scales differ by a power of two, so every operation rounds the same way: the answers
    // must agree to rounding, not just roughly.
    for (a, b) in results[0].iter().zip(&results[1]) {
        assert!(
            (*a - *b).length() <= 1e-6 * a.length().max(1e-9),
            "{a} vs {b}"
        );
    }
}

#[test]
fn long_thin_triangles_stay_stable() {
    let f = stable(
        include_str!("../../scenes/slivers.obj"),
        "slivers.obj",
        10.0,
        Until::Unshot(0.05),
    );
    assert!(f <= 0.05);
}
