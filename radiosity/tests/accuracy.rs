//! Issue 10: the causes of bias, each against an answer that does not depend on the solver (a
//! patch shooting from its lit part only, cause 4; a stopping rule that reaches its error target
//! in a room lit only through a doorway, cause 5; cause 1 is in `formfactors.rs`), and the
//! solver against the stored path-traced Cornell box reference.

use glam::Vec3;
use occ_radiosity::formfactor::{FormFactorConfig, SourceDensity, point_polygon};
use occ_radiosity::geom::Tri;
use occ_radiosity::kernels::{SamplePoint, shoot_batch, shoot_batch_weighted};
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::octree::{Octree, OctreeConfig};
use occ_radiosity::output::truth::Reference;
use occ_radiosity::pathtrace::{PathTraceConfig, PathTracer};
use occ_radiosity::scene::{self, Scene};
use occ_radiosity::solver::{AdaptConfig, Solver, SolverConfig, Until};

mod common;

#[test]
fn a_near_receiver_sees_only_the_lit_part_of_a_half_shadowed_patch() {
    // Issue 10, cause 4. A floor patch (the right triangle x, z in [0, 1], facing up) whose
    // unshot radiosity is 0 for x < 0.5 (in shadow) and uniform beyond. Receivers facing it
    // just above the dark part see little of the lit part: the shot must bring them the form
    // factor to the lit part times the lit density (4 times the mean: it is a quarter of the
    // area), not the form factor to the whole patch times the mean.
    let patch = Tri::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
    );
    assert!(patch.normal().y > 0.0);
    let lit = |x: Vec3| if x.x < 0.5 { 0.0 } else { 1.0 };
    let density = SourceDensity::new(&patch, 64, lit).expect("not uniform");
    // The lit part is the triangle x >= 0.5 (a quarter of the area): density 4 there.
    let lit_part = [
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let octree = Octree::build(&[patch], OctreeConfig::default());
    let config = FormFactorConfig {
        rays: 256,
        ..FormFactorConfig::default()
    };
    for p in [Vec3::new(0.2, 0.05, 0.2), Vec3::new(0.1, 0.1, 0.6)] {
        let n = -Vec3::Y;
        let point = SamplePoint {
            pos: p.to_array(),
            normal: n.to_array(),
            eval: p.to_array(),
        };
        let exact = 4.0 * point_polygon(p, n, &lit_part);
        let mut weighted = [0.0f32; 1];
        let (mut sum, runs) = (0.0, 64);
        for seed in 0..runs {
            shoot_batch_weighted(
                &octree,
                &patch,
                Some(&density),
                &[point],
                &config,
                seed,
                &mut weighted,
            );
            sum += weighted[0];
        }
        let mean = sum / runs as f32;
        assert!(
            (mean / exact - 1.0).abs() < 0.03,
            "at {p}: weighted {mean}, exact {exact}"
        );
        // The patch shooting its average would bring this much instead.
        let mut uniform = [0.0f32; 1];
        shoot_batch(&octree, &patch, &[point], &config, 1, &mut uniform);
        let whole = point_polygon(p, n, &patch.v);
        assert!((uniform[0] / whole - 1.0).abs() < 0.05);
        assert!(whole > 1.5 * exact, "the case must tell the two apart");
    }
}

fn two_rooms() -> Scene {
    let obj = include_str!("../../scenes/two-rooms.obj");
    let mtl = include_str!("../../scenes/rooms.mtl");
    scene::load_obj("two-rooms.obj", obj, &|_| Ok(mtl.to_string())).expect("scene")
}

/// The worst relative difference of any object's mean B (any channel) from `truth`'s.
fn worst_difference(solver: &Solver, truth: &Solver) -> (f64, String) {
    let mut worst = (0.0, String::new());
    for ((o, (_, b)), (_, t)) in solver
        .scene
        .objects
        .iter()
        .zip(solver.object_means())
        .zip(truth.object_means())
    {
        for c in 0..3 {
            let d = (b[c] / t[c] - 1.0).abs();
            if d > worst.0 {
                worst = (d, o.name.clone());
            }
        }
    }
    worst
}

#[test]
fn fewer_far_rays_leave_near_and_part_horizon_receivers_as_they_were() {
    // A weak shot casts fewer rays to far receivers that see the whole source above their
    // horizon (`FormFactorConfig::far_rays`); every receiver keeps its own slot of samples, so
    // near receivers and receivers that see only part of the source get exactly the answers of
    // a shot casting all its rays, and the far ones the same answers on average.
    let src = Tri::new(Vec3::ZERO, Vec3::Z, Vec3::X);
    let octree = Octree::build(&[src], OctreeConfig::default());
    let point = |p: Vec3, n: Vec3| SamplePoint {
        pos: p.to_array(),
        normal: n.to_array(),
        eval: p.to_array(),
    };
    let near = point(Vec3::new(0.3, 0.1, 0.3), -Vec3::Y);
    let part = point(
        Vec3::new(0.3, 1.0, 0.3),
        Vec3::new(0.0, -1.0, 2.0).normalize(),
    );
    let far = point(Vec3::new(0.3, 3.0, 0.3), -Vec3::Y);
    let points = [near, far, part];
    let full = FormFactorConfig {
        rays: 16,
        ..FormFactorConfig::default()
    };
    let few = FormFactorConfig {
        far_rays: 1,
        ..full
    };
    let (mut sum_full, mut sum_few) = (0.0f64, 0.0f64);
    let runs = 400;
    for seed in 0..runs {
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        let sa = shoot_batch(&octree, &src, &points, &full, seed, &mut a);
        let sb = shoot_batch(&octree, &src, &points, &few, seed, &mut b);
        assert_eq!((a[0], a[2]), (b[0], b[2]), "seed {seed}");
        assert!(sb.rays < sa.rays);
        sum_full += f64::from(a[1]);
        sum_few += f64::from(b[1]);
    }
    let exact = f64::from(point_polygon(Vec3::from(far.pos), -Vec3::Y, &src.v));
    for sum in [sum_full, sum_few] {
        let mean = sum / runs as f64;
        assert!((mean / exact - 1.0).abs() < 0.01, "{mean} against {exact}");
    }
}

#[test]
fn the_error_rule_reaches_its_target_in_a_room_lit_through_a_door() {
    // Issue 10, cause 5. The same solver and mesh run far (unshot 1e-5) is the answer here, so
    // that only the stopping rule differs. A fixed unshot fraction of 1% stops with room B
    // several percent short; the error rule stops when every object is within its target.
    let scene = two_rooms();
    let truth = common::solve_coarse(&scene, Until::Unshot(1e-5));
    let target = 0.01;
    let by_error = common::solve_coarse(&scene, Until::Error(target));
    let (worst, name) = worst_difference(&by_error, &truth);
    assert!(
        worst <= target,
        "error rule: {name} off by {:.2}%",
        worst * 100.0
    );
    let by_unshot = common::solve_coarse(&scene, Until::Unshot(0.01));
    let (worst, name) = worst_difference(&by_unshot, &truth);
    assert!(
        worst > target,
        "unshot 1% was expected to stop short ({name} off by {:.2}%)",
        worst * 100.0
    );
}

/// The stored path-traced reference of the Cornell box (`scenes/references/`).
fn cornell_reference() -> Reference {
    let text = include_str!("../../scenes/references/cornell-box.pathtrace.json");
    Reference::parse("cornell-box.pathtrace.json", text).expect("reference")
}

#[test]
fn the_path_tracer_reproduces_its_stored_cornell_reference() {
    // A fresh, independent estimate (another seed, 1/128 of the paths) must agree with the stored
    // one within 4 combined standard errors on every object and channel.
    let reference = cornell_reference();
    let scene = scene::cornell::load(true).expect("cornell");
    let config = PathTraceConfig {
        samples: reference.samples_per_object / 128,
        seed: reference.seed + 1,
        ..PathTraceConfig::default()
    };
    let fresh = PathTracer::new(&scene).object_means(&config);
    for (o, e) in scene.objects.iter().zip(fresh) {
        let r = reference.object(&o.name).expect("object in the reference");
        for c in 0..3 {
            let sigma = (r.std_err[c].powi(2) + e.std_err[c].powi(2)).sqrt();
            assert!(
                (e.mean[c] - r.mean_b[c]).abs() <= 4.0 * sigma,
                "{} channel {c}: {} ± {} against {} ± {}",
                o.name,
                e.mean[c],
                e.std_err[c],
                r.mean_b[c],
                r.std_err[c]
            );
        }
    }
}

#[test]
fn cornell_surfaces_are_within_one_percent_of_the_path_tracer_at_the_defaults() {
    // The command's defaults (patches diagonal / 4, elements diagonal / 20, adaptive
    // subdivision, 8 rays, error=0.01). The large surfaces and the block tops must be within 1%
    // of the path-traced reference per channel, plus 3 of its standard errors (0.1-0.4% here).
    // Not yet asserted: the dim block faces, which are still up to 2.2% off (see BENCHMARKS.md).
    let reference = cornell_reference();
    let scene = scene::cornell::load(true).expect("cornell");
    let diag = scene.diagonal();
    let element_size = diag / 20.0;
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: diag / 4.0,
            element_size,
        },
    );
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 8,
            offset: 1e-6 * diag,
            ..FormFactorConfig::default()
        },
        adapt: Some(AdaptConfig {
            difference: 0.3,
            nonlinearity: 0.1,
            min_edge: element_size / 8.0,
            min_shot_power: 0.002,
            passes: 3,
            max_vertices: 8_000,
        }),
        until: Until::Error(0.01),
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(&scene, mesh, config);
    solver.run(|_, _| {});
    let large = [
        "floor",
        "ceiling",
        "back_wall",
        "green_wall",
        "red_wall",
        "short_block_top",
        "tall_block_top",
    ];
    for (o, (_, b)) in scene.objects.iter().zip(solver.object_means()) {
        if !large.contains(&o.name.as_str()) {
            continue;
        }
        let r = reference.object(&o.name).expect("object in the reference");
        for c in 0..3 {
            let tolerance = 0.01 * r.mean_b[c] + 3.0 * r.std_err[c];
            assert!(
                (b[c] - r.mean_b[c]).abs() <= tolerance,
                "{} channel {c}: solver {} against path-traced {} ± {}",
                o.name,
                b[c],
                r.mean_b[c],
                r.std_err[c]
            );
        }
    }
}
