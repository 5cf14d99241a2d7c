//! Issue 10: the causes of bias, each against an answer that does not depend on the solver (a
//! patch shooting from its lit part only, cause 4; a stopping rule that reaches its error target
//! in a room lit only through a doorway, cause 5; cause 1 is in `formfactors.rs`; the direct
//! light under a square lamp, whose peak the corners' average understates), and the solver
//! against the stored path-traced Cornell box reference.

use glam::Vec3;
use occ_radiosity::formfactor::{FormFactorConfig, SourceDensity, point_polygon};
use occ_radiosity::geom::Tri;
use occ_radiosity::kernels::{
    SamplePoint, shoot_batch, shoot_batch_visibility, shoot_batch_weighted,
};
use occ_radiosity::mesh::{CREASE_BAND_EDGE, Mesh, MeshConfig};
use occ_radiosity::octree::{Octree, OctreeConfig};
use occ_radiosity::output::truth::Reference;
use occ_radiosity::pathtrace::{PathTraceConfig, PathTracer};
use occ_radiosity::quadrature::MeanRule;
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

#[test]
fn a_face_at_the_foot_of_a_dark_strip_sees_the_density_as_it_lies() {
    // Issue 10: the short block's front read 0.0-3.6% high (B) at the defaults, by the seed.
    // Near a source the analytic form is the exact form factor times the weighted kernel's
    // share of the samples, a ratio of two sums over 9 samples: where the kernel peaks in a
    // dark strip at the receiver's foot and the power lies beyond it, its mean overstates what
    // the receiver sees. Here the floor triangle is dark for z < 0.2 (its edge z = 0 is the
    // foot of a face) and receivers on the face look over it. Measured at heights 0.05, 0.12,
    // 0.25, 0.01: -0.21, -0.19, -0.35, -0.14% (by the midpoint rule for the kernel's mean over the
    // density: +1.5, +1.4, -1.4, +1.9%; by the ratio over the samples: +41, +5.3, +0.5, +304%).
    let points = [(0.3, 0.05), (0.5, 0.12), (0.3, 0.25), (0.3, 0.01)];
    for (e, p) in balanced_errors(|x| if x.z < 0.2 { 0.02 } else { 1.0 }, &points) {
        assert!(e.abs() < 0.005, "at {p}: {:+.2}% off", 100.0 * e);
    }
}

#[test]
fn a_face_over_a_step_at_its_foot_sees_the_density_as_it_lies() {
    // As above, with the floor dark for x < 0.4 and the receivers' feet on that line or near
    // it, so that the density steps where the kernel peaks. Measured at heights 0.01, 0.05,
    // 0.25, 0.002 over the step and 0.02, 0.003 beside it: -0.08, -0.04, -0.26, -0.05, +0.14,
    // +0.03% (by the midpoint rule: +17.4, +1.7, -0.7, +183, +6.8, +0.5%).
    let points = [
        (0.4, 0.01),
        (0.4, 0.05),
        (0.4, 0.25),
        (0.4, 0.002),
        (0.42, 0.02),
        (0.41, 0.003),
    ];
    for (e, p) in balanced_errors(|x| if x.x < 0.4 { 0.02 } else { 1.0 }, &points) {
        assert!(e.abs() < 0.005, "at {p}: {:+.2}% off", 100.0 * e);
    }
}

#[test]
fn a_face_over_a_rising_density_sees_it_as_it_lies() {
    // As above, with the floor's density rising smoothly away from the face (0.1 + z), as an
    // element-by-element density does. Measured at heights 0.05, 0.12, 0.25, 0.01: -0.07, +0.06,
    // +0.08, -0.03% (by the midpoint rule: -0.40, +0.06, -0.75, +1.65%).
    let points = [(0.3, 0.05), (0.5, 0.12), (0.3, 0.25), (0.3, 0.01)];
    for (e, p) in balanced_errors(|x| 0.1 + x.z, &points) {
        assert!(e.abs() < 0.005, "at {p}: {:+.2}% off", 100.0 * e);
    }
}

/// The balanced analytic form ([`shoot_batch_visibility`], mean of 4,000 seeds) from a unit
/// floor triangle, its unshot radiosity `density` (tabulated on 24 × 24 cells), to receivers
/// at `(x, height)` on a face standing at its edge `z = 0`, each as its relative error against
/// the exact integral of the kernel times the same tabulated density: each cell's exact form
/// factor times its density (a brute-force grid of 2,000² points was 0.85% off at height 0.01
/// over the step).
fn balanced_errors(density: fn(Vec3) -> f32, points: &[(f32, f32)]) -> Vec<(f64, Vec3)> {
    let patch = Tri::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
    );
    let g = 24;
    let density = SourceDensity::new(&patch, g, density).expect("not uniform");
    let config = FormFactorConfig::default();
    let n = Vec3::Z;
    let mut errors = Vec::new();
    for p in points.iter().map(|&(x, h)| Vec3::new(x, h, -1e-3)) {
        // The warp keeps a cell's edges straight (rows run along an edge, columns from the
        // apex), and every cell lies above the receiver's horizon.
        let corner = |i: u32, j: u32| patch.sample(i as f32 / g as f32, j as f32 / g as f32) - p;
        let mut truth = 0.0f64;
        for i in 0..g {
            for j in 0..g {
                let quad = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(a, b)| corner(i + a, j + b));
                let (u, v) = ((i as f32 + 0.5) / g as f32, (j as f32 + 0.5) / g as f32);
                truth += lambert(n, &quad) * density.at(u, v) as f64;
            }
        }
        let point = SamplePoint {
            pos: p.to_array(),
            normal: n.to_array(),
            eval: p.to_array(),
        };
        let (mut sum, runs) = (0.0f64, 4000);
        for seed in 0..runs {
            let mut f = [0.0f32; 1];
            shoot_batch_visibility(
                None,
                &patch,
                Some(&density),
                &[point],
                &config,
                seed,
                &mut f,
            );
            sum += f[0] as f64;
        }
        let mean = sum / runs as f64;
        let whole = point_polygon(p, n, &patch.v) as f64;
        assert!(
            (truth / whole - 1.0).abs() > 0.05,
            "the density must matter"
        );
        eprintln!(
            "at {p}: {mean} against {truth} ({:+.2}%)",
            100.0 * (mean / truth - 1.0)
        );
        errors.push((mean / truth - 1.0, p));
    }
    errors
}

/// The form factor from a point at the origin of normal `n` to the polygon `poly` (wholly
/// above its horizon), by Lambert's contour sum in f64; edges of no length are skipped.
fn lambert(n: Vec3, poly: &[Vec3]) -> f64 {
    let n = n.as_dvec3();
    let sum: f64 = (0..poly.len())
        .map(|k| {
            let a = poly[k].as_dvec3().normalize();
            let b = poly[(k + 1) % poly.len()].as_dvec3().normalize();
            let c = a.cross(b);
            let sin = c.length();
            if sin == 0.0 {
                return 0.0;
            }
            sin.atan2(a.dot(b)) * c.dot(n) / sin
        })
        .sum();
    sum.abs() / (2.0 * std::f64::consts::PI)
}

/// A white floor lit red on its left and blue on its right, and a small card facing it just
/// above the red side (the lights above the card's horizon: it sees only the floor).
const TWO_COLOURED_LIGHTS: &str = "mtllib t.mtl
o floor
usemtl white
v 2 0 0
v 0 0 0
v 0 0 2
v 2 0 2
f 1 2 3 4
o red_light
usemtl red
v 0.9 0.5 0.1
v 0.9 0.5 1.9
v 0.1 0.5 1.9
v 0.1 0.5 0.1
f 5 6 7 8
o blue_light
usemtl blue
v 1.9 0.5 0.1
v 1.9 0.5 1.9
v 1.1 0.5 1.9
v 1.1 0.5 0.1
f 9 10 11 12
o card
usemtl white
v 0.5 0.1 0.9
v 0.5 0.1 1.1
v 0.3 0.1 1.1
v 0.3 0.1 0.9
f 13 14 15 16
";

const TWO_COLOURED_LIGHTS_MTL: &str = "newmtl white
Kd 0.5 0.5 0.5
newmtl red
Kd 0 0 0
Ke 1 0 0
newmtl blue
Kd 0 0 0
Ke 0 0 1
";

#[test]
fn a_near_receiver_sees_each_channel_from_where_the_source_holds_it() {
    // Issue 10: the dim Cornell block faces mixed their colours wrongly (the tall block's red
    // side G/B +2..+3%, R -1%) because a patch shot every channel from where the channels
    // summed were: a floor strip lit by the red wall shot its red and its blue alike. Here the
    // floor (two patches) holds red power on its left and blue on its right after the lights
    // shoot; the card above the red side must get the floor's red from the red side and
    // little blue. The truth: each floor element's radiosity (ρ times the mean of its
    // corners' irradiance, what it shoots) times the exact form factor from each card point
    // to it (nothing lies between them). Shooting every channel from where the sum is would
    // bring the card blue as bright as its red.
    let scene = scene::load_obj("lights.obj", TWO_COLOURED_LIGHTS, &|_| {
        Ok(TWO_COLOURED_LIGHTS_MTL.to_string())
    })
    .expect("scene");
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: 3.0,
            element_size: 0.25,
        },
    );
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 1024,
            ..FormFactorConfig::default()
        },
        full_rays_power: 0.0,
        ..SolverConfig::default()
    };
    let object = |name: &str| scene.objects.iter().position(|o| o.name == name).unwrap() as u32;
    let (floor, card) = (object("floor"), object("card"));
    let mut solver = Solver::new(&scene, mesh, config);
    // The lights' four patches, then the floor's two (coplanar: they bring each other nothing).
    let floor_patches: Vec<usize> = (0..solver.unshot.len())
        .filter(|&p| solver.mesh.patch_object[p] == floor)
        .collect();
    for _ in 0..6 {
        assert!(solver.shoot_once());
    }
    for &p in &floor_patches {
        assert_eq!(
            solver.unshot[p],
            glam::DVec3::ZERO,
            "floor patch {p} has shot"
        );
    }
    let mesh = &solver.mesh;
    let h = &solver.irradiance;
    let mut card_points: Vec<u32> = (mesh.elements.iter())
        .filter(|e| e.object == card)
        .flat_map(|e| e.v)
        .collect();
    card_points.sort_unstable();
    card_points.dedup();
    let (mut solved, mut exact) = (Vec3::ZERO, Vec3::ZERO);
    for &v in &card_points {
        let point = &mesh.vertices[v as usize];
        solved += h[v as usize];
        for e in mesh.elements.iter().filter(|e| e.object == floor) {
            let b = 0.5 * e.v.iter().map(|&c| h[c as usize]).sum::<Vec3>() / 3.0;
            exact += b * point_polygon(point.eval, point.normal, &mesh.tri(e).v);
        }
    }
    assert!(
        exact.x > 5.0 * exact.z,
        "the case must tell the channels apart: {exact}"
    );
    for c in [0, 2] {
        assert!(
            (solved[c] / exact[c] - 1.0).abs() < 0.03,
            "channel {c}: solved {solved}, exact {exact} (sum over the card's points)"
        );
    }
}

/// The floor's mean radiosity under the unit square lamp of [`common::light_over_floor`]
/// (a floor of the lamp's size, a unit below it), solved with `rule` and elements of `size`
/// until the lamp has shot, so that the floor holds the lamp's direct light only.
fn direct_floor_mean(rule: MeanRule, size: f32) -> f64 {
    let scene = common::light_over_floor(0.5);
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: 1.0,
            element_size: size,
        },
    );
    let lamp_patches = (mesh.patch_object.iter()).filter(|&&o| o == 0).count() as u64;
    let config = SolverConfig {
        until: Until::Shots(lamp_patches),
        element_means: rule,
        acceleration: occ_radiosity::overshoot::Acceleration::Off,
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(&scene, mesh, config);
    solver.run(|_, _| {});
    assert!(solver.unshot_fraction() < 0.3, "the lamp has shot");
    solver.object_means()[1].1.x
}

#[test]
fn the_direct_light_under_a_lamp_is_booked_with_its_peak() {
    // Directly opposed unit squares a unit apart: F = 0.199825 (Howell C-11), so the floor,
    // of reflectance 0.5, averages B = 0.5 π F under a lamp of unit radiance. Its form factors
    // at the vertices are exact (analytic: the lamp is near), so what is left is how an
    // element's mean is taken from its corners: the irradiance peaks under the lamp's centre,
    // and the corners' average understates a peak by the curvature (cause of the directly lit
    // surfaces' deficit at the Cornell defaults: REFERENCES.md, "Element means exact for
    // quadratics"). Measured: elements 0.5, -3.70% against -0.63%; 0.25, -0.93% against -0.05%.
    let exact = 0.5 * std::f64::consts::PI * 0.199825;
    for size in [0.5, 0.25] {
        let linear = direct_floor_mean(MeanRule::Linear, size) / exact - 1.0;
        let quadratic = direct_floor_mean(MeanRule::Quadratic, size) / exact - 1.0;
        assert!(
            linear < -0.005,
            "elements {size}: the case must show the peak ({linear})"
        );
        assert!(
            quadratic.abs() < 0.2 * linear.abs(),
            "elements {size}: {quadratic} (linear {linear})"
        );
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

/// Asserts that `scene` at coarse settings, stopped on the error rule with `target`, is within
/// it of the same solver and mesh run far (unshot 1e-5), so that only the stopping rule
/// differs; returns that far solve.
fn assert_error_rule_reaches(scene: &Scene, target: f64) -> Solver<'_> {
    let truth = common::solve_coarse(scene, Until::Unshot(1e-5));
    let by_error = common::solve_coarse(scene, Until::Error(target));
    let (worst, name) = worst_difference(&by_error, &truth);
    assert!(
        worst <= target,
        "error rule: {name} off by {:.2}%",
        worst * 100.0
    );
    truth
}

#[test]
fn the_error_rule_reaches_its_target_in_a_room_lit_through_a_door() {
    // Issue 10, cause 5. A fixed unshot fraction of 1% stops with room B several percent
    // short; the error rule stops when every object is within its target.
    let scene = two_rooms();
    let target = 0.01;
    let truth = assert_error_rule_reaches(&scene, target);
    let by_unshot = common::solve_coarse(&scene, Until::Unshot(0.01));
    let (worst, name) = worst_difference(&by_unshot, &truth);
    assert!(
        worst > target,
        "unshot 1% was expected to stop short ({name} off by {:.2}%)",
        worst * 100.0
    );
}

fn table_lamp() -> Scene {
    let obj = include_str!("../../scenes/table-lamp.obj");
    let mtl = include_str!("../../scenes/rooms.mtl");
    scene::load_obj("table-lamp.obj", obj, &|_| Ok(mtl.to_string())).expect("scene")
}

#[test]
fn the_error_rule_waits_for_the_patches_it_never_chose() {
    // The estimate spreads the unshot power evenly, but the small pieces that the table's legs
    // cut from the underside of its top are never the patch with the most unshot power, and
    // what they hold lands on the legs' tops, which see them with form factors near 1/2.
    // Stopped on the error rule without those pieces shooting, the legs were 1.17% off.
    assert_error_rule_reaches(&table_lamp(), 0.01);
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
    // The command's defaults (`MeshConfig::default_for` with its row of points, adaptive
    // subdivision, 8 rays, error=0.01). Every surface must be within 1% of the path-traced
    // reference per channel (2% where the channel is below a tenth of the scene's area-weighted
    // mean, the light included: the dim block faces), plus 3 of its standard errors (0.1-0.4%
    // here). Seeds 1-11 of the command hold this (radiosity/REFERENCES.md); before the row of
    // points and the samples in the part a receiver sees, the short block's red side was out
    // on three of them.
    let reference = cornell_reference();
    let scene = scene::cornell::load(true).expect("cornell");
    let diag = scene.diagonal();
    let sizes = MeshConfig::default_for(diag);
    let element_size = sizes.element_size;
    let mut mesh = Mesh::from_scene(&scene, sizes);
    mesh.band_concave_creases(element_size * CREASE_BAND_EDGE);
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
    for (o, (_, b)) in scene.objects.iter().zip(solver.object_means()) {
        if o.emission != Vec3::ZERO {
            continue;
        }
        let r = reference.object(&o.name).expect("object in the reference");
        for c in 0..3 {
            assert!(
                (b[c] - r.mean_b[c]).abs() <= reference.tolerance(r, c),
                "{} channel {c}: solver {} against path-traced {} ± {}",
                o.name,
                b[c],
                r.mean_b[c],
                r.std_err[c]
            );
        }
    }
}
