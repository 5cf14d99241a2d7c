//! Criterion benchmarks of the kernels, single thread:
//! - occlusion rays/s on the Cornell box with each quad split 18 × 18 (10,368 triangles), rays
//!   between random surface points (origin lifted 1e-3 mm, tmax 0.999), as measured for
//!   Embree 4 (`rtcOccluded1`, through the `embreex` Python binding) in `BENCHMARKS.md`; Samet, ropes and Glassner traversal;
//! - the same rays through the flat octree walk a CARM node runs (`RAD.RAYS.WALK`, every voxel
//!   held), 16 and 256 rays a call, beside `Octree::occluded` with ropes;
//! - form factors/s (16 shadow rays each, Cornell box, light as source);
//! - a shooting patch's density grid (`SourceDensity::of_parts`, 24 × 24 cells) over 64 and
//!   256 elements, beside the search it replaced (the last cell's element, else every
//!   element's closest point);
//! - the analytic form near a source whose power lies away from the receivers (a face at the
//!   foot of a dark strip of floor, `balance_weights`), beside the same source uniform;
//! - time to a converged Cornell box (reference solver; rayon uses the pool it is given, see
//!   the `solve` group note).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use occ_radiosity::formfactor::{FormFactorConfig, SourceDensity};
use occ_radiosity::geom::Tri;
use occ_radiosity::intrinsics::RAY_FLOATS;
use occ_radiosity::kernels::{SamplePoint, shoot_batch, shoot_batch_visibility};
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::octree::flat::{CURSOR_INTS, START};
use occ_radiosity::octree::{Octree, OctreeConfig, Traversal};
use occ_radiosity::quadrature::MeanRule;
use occ_radiosity::rng::Pcg32;
use occ_radiosity::scene::cornell;
use occ_radiosity::solver::{Solver, SolverConfig, Until};

/// Random rays between area-weighted random surface points.
fn ray_set(tris: &[Tri], n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut cdf = Vec::with_capacity(tris.len());
    let mut total = 0.0;
    for t in tris {
        total += t.area();
        cdf.push(total);
    }
    let mut rng = Pcg32::new(seed, 1);
    let pick = |rng: &mut Pcg32| {
        let x = rng.next_f32() * total;
        let i = cdf.partition_point(|&c| c < x).min(tris.len() - 1);
        (
            tris[i].sample(rng.next_f32(), rng.next_f32()),
            tris[i].normal(),
        )
    };
    (0..n)
        .map(|_| {
            let (a, na) = pick(&mut rng);
            let (b, _) = pick(&mut rng);
            let o = a + na * 1e-3;
            (o, b - o)
        })
        .collect()
}

fn occlusion(c: &mut Criterion) {
    let tris = cornell::grid_triangles(18).expect("cornell");
    assert_eq!(tris.len(), 10_368);
    let tree = Octree::build(&tris, OctreeConfig::default());
    eprintln!("octree: {:?}", tree.stats());
    let rays = ray_set(&tris, 100_000, 7);
    let occluded = rays
        .iter()
        .filter(|(o, d)| tree.occluded(*o, *d, 0.0, 0.999, Traversal::Samet))
        .count();
    eprintln!(
        "occluded fraction: {:.3}",
        occluded as f64 / rays.len() as f64
    );
    let mut group = c.benchmark_group("occlusion_cornell_10k");
    group.throughput(Throughput::Elements(rays.len() as u64));
    group.sample_size(20);
    for (name, mode) in [
        ("samet", Traversal::Samet),
        ("ropes", Traversal::Ropes),
        ("glassner", Traversal::Glassner),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for (o, d) in &rays {
                    hits += tree.occluded(*o, *d, 0.0, 0.999, mode) as u32;
                }
                black_box(hits)
            })
        });
    }
    group.finish();
    c.bench_function("octree_build_cornell_10k", |b| {
        b.iter(|| Octree::build(black_box(&tris), OctreeConfig::default()))
    });
}

/// Rays per call of the walk intrinsic: one receiver's shadow rays, and a batch of receivers'.
const WALK_BATCHES: [usize; 2] = [16, 256];

/// The octree walk a node runs (`FlatView::walk`, what `RAD.RAYS.WALK` calls) with every voxel
/// held, against `Octree::occluded` with ropes on the same rays, in one run.
fn walk(c: &mut Criterion) {
    let tris = cornell::grid_triangles(18).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let (view, slots) = (flat.view(), flat.slots());
    let rays: Vec<f32> = ray_set(&tris, 100_000, 7)
        .iter()
        .flat_map(|(o, d)| {
            o.to_array()
                .into_iter()
                .chain(d.to_array())
                .chain([0.0, 0.999])
        })
        .collect();
    let n = rays.len() / RAY_FLOATS;
    let mut group = c.benchmark_group("walk_cornell_10k");
    group.throughput(Throughput::Elements(n as u64));
    group.sample_size(20);
    group.bench_function("octree_ropes", |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for r in rays.chunks_exact(RAY_FLOATS) {
                let (o, d) = (Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..6]));
                hits += tree.occluded(o, d, r[6], r[7], Traversal::Ropes) as u32;
            }
            black_box(hits)
        })
    });
    for batch in WALK_BATCHES {
        let (mut blocked, mut cursor) = (vec![0u8; batch], vec![START; CURSOR_INTS * batch]);
        group.bench_function(format!("flat_walk_{batch}_per_call"), |b| {
            b.iter(|| {
                let mut hits = 0u32;
                for r in rays.chunks(RAY_FLOATS * batch) {
                    let k = r.len() / RAY_FLOATS;
                    blocked[..k].fill(0);
                    cursor[..CURSOR_INTS * k].fill(START);
                    let count = view.walk(
                        &slots,
                        flat.pool(),
                        r,
                        &mut blocked[..k],
                        &mut cursor[..CURSOR_INTS * k],
                        &mut [],
                    );
                    assert_eq!(count, Some(0));
                    hits += blocked[..k].iter().map(|&x| x as u32).sum::<u32>();
                }
                black_box(hits)
            })
        });
    }
    group.finish();
}

fn form_factors(c: &mut Criterion) {
    let scene = cornell::load(true).expect("cornell");
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: 150.0,
            element_size: 40.0,
        },
    );
    let tris: Vec<Tri> = scene.triangles.iter().map(|t| t.tri).collect();
    let tree = Octree::build(&tris, OctreeConfig::default());
    let light = scene
        .objects
        .iter()
        .position(|o| o.name == "light")
        .expect("light") as u32;
    let source = scene
        .triangles
        .iter()
        .find(|t| t.object == light)
        .expect("light tri")
        .tri;
    let points: Vec<SamplePoint> = mesh.vertices.iter().map(SamplePoint::from).collect();
    let mut out = vec![0.0; points.len()];
    let mut group = c.benchmark_group("form_factors_cornell");
    group.throughput(Throughput::Elements(points.len() as u64));
    group.sample_size(20);
    for rays in [4u32, 16, 64] {
        let config = FormFactorConfig {
            rays,
            offset: 1e-3,
            ..FormFactorConfig::default()
        };
        group.bench_function(format!("{rays}_rays"), |b| {
            b.iter(|| shoot_batch(&tree, &source, black_box(&points), &config, 1, &mut out))
        });
    }
    group.finish();
}

fn solve(c: &mut Criterion) {
    // One thread, so the figure is comparable with the other single-thread figures.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let scene = cornell::load(true).expect("cornell");
    let mut group = c.benchmark_group("solve_cornell");
    group.sample_size(10);
    // The default element means (quadratic) against the corners' average: the rule's cost.
    for (rule, name) in [
        (MeanRule::Quadratic, ""),
        (MeanRule::Linear, "_linear_means"),
    ] {
        let until = 0.01;
        group.bench_function(format!("unshot_{until}_1_thread{name}"), |b| {
            b.iter(|| {
                pool.install(|| {
                    let mesh = Mesh::from_scene(
                        &scene,
                        MeshConfig {
                            patch_size: 240.0,
                            element_size: 48.0,
                        },
                    );
                    let form_factor = FormFactorConfig {
                        rays: 8,
                        ..FormFactorConfig::default()
                    };
                    let config = SolverConfig {
                        form_factor,
                        until: Until::Unshot(until),
                        element_means: rule,
                        ..SolverConfig::default()
                    };
                    let mut solver = Solver::new(&scene, mesh, config);
                    solver.run(|_, _| {});
                    black_box(solver.stats.shots)
                })
            })
        });
    }
    group.finish();
}

/// `tri` split `levels` times into four at its edges' midpoints, each part with a value.
fn split_parts(tri: &Tri, levels: u32) -> Vec<(Tri, f32)> {
    tri.split(levels)
        .into_iter()
        .enumerate()
        .map(|(k, t)| (t, 1.0 + (k % 13) as f32))
        .collect()
}

fn source_density(c: &mut Criterion) {
    let src = Tri::new(
        Vec3::new(0.0, 548.0, 0.0),
        Vec3::new(556.0, 548.0, 0.0),
        Vec3::new(556.0, 548.0, 559.0),
    );
    let mut group = c.benchmark_group("source_density");
    for levels in [3u32, 4] {
        let parts = split_parts(&src, levels);
        let n = parts.len();
        group.bench_function(format!("{n}_elements"), |b| {
            b.iter(|| SourceDensity::of_parts(&src, 24, black_box(&parts)))
        });
        // The search of_parts replaced: the part of the last cell's centre, else the nearest.
        group.bench_function(format!("{n}_elements_search"), |b| {
            b.iter(|| {
                let last = std::cell::Cell::new(0);
                SourceDensity::new(&src, 24, |x| {
                    if !parts[last.get()].0.contains(x) {
                        let nearest = parts
                            .iter()
                            .map(|(t, _)| (t.closest_point(x) - x).length_squared())
                            .enumerate()
                            .fold((0, f32::MAX), |b, c| if c.1 < b.1 { c } else { b })
                            .0;
                        last.set(nearest);
                    }
                    parts[last.get()].1
                })
            })
        });
    }
    group.finish();
}

/// The analytic form from a floor triangle to 64 receivers on a face standing at its edge
/// (heights 0.005 to 0.5 of the triangle's side), no occluder: with the floor dark within 0.2
/// of the face (the balanced analytic form, its `W` integral of the density) and uniform.
fn balanced(c: &mut Criterion) {
    let patch = Tri::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
    );
    let dark = SourceDensity::new(&patch, 24, |x| if x.z < 0.2 { 0.02 } else { 1.0 })
        .expect("not uniform");
    let points: Vec<SamplePoint> = (0..64)
        .map(|k| {
            let p = [
                0.05 + 0.9 * (k % 8) as f32 / 7.0,
                0.005 * 100f32.powf((k / 8) as f32 / 7.0),
                -1e-3,
            ];
            SamplePoint {
                pos: p,
                normal: [0.0, 0.0, 1.0],
                eval: p,
            }
        })
        .collect();
    let config = FormFactorConfig::default();
    let mut out = vec![0.0; points.len()];
    let mut group = c.benchmark_group("analytic_near");
    group.throughput(Throughput::Elements(points.len() as u64));
    for (name, density) in [("dark_strip", Some(&dark)), ("uniform", None)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                let points = black_box(&points);
                shoot_batch_visibility(None, &patch, density, points, &config, 1, &mut out)
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    occlusion,
    walk,
    form_factors,
    source_density,
    balanced,
    solve
);
criterion_main!(benches);
