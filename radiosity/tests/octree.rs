//! Seeded property tests of the octree: it answers exactly as a brute-force test of all
//! triangles under every traversal (Samet, ropes, Glassner) and build setting, including rays
//! that graze walls (where the packets' flat boxes decide), and rays leaving a patch never hit it.

use glam::Vec3;
use occ_radiosity::analysis::occluders;
use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::geom::Tri;
use occ_radiosity::octree::{Octree, OctreeConfig, Traversal, occluded_brute_force};
use occ_radiosity::rng::Pcg32;
use occ_radiosity::scene::cornell;

fn random_point(tris: &[Tri], rng: &mut Pcg32) -> (usize, Vec3) {
    let i = (rng.next_u32() as usize) % tris.len();
    (i, tris[i].sample(rng.next_f32(), rng.next_f32()))
}

const MODES: [Traversal; 3] = Traversal::ALL;

/// Build settings from many small voxels to few large ones.
const SETTINGS: [(usize, u32); 3] = [(4, 10), (6, 12), (48, 5)];

fn build(tris: &[Tri], max_leaf: usize, max_depth: u32) -> Octree {
    Octree::build(
        tris,
        OctreeConfig {
            max_leaf,
            max_depth,
        },
    )
}

#[test]
fn octree_equals_brute_force_between_random_surface_points() {
    let tris = cornell::grid_triangles(6).expect("cornell");
    for (max_leaf, max_depth) in SETTINGS {
        let tree = build(&tris, max_leaf, max_depth);
        let mut rng = Pcg32::new(42, 1);
        let mut occluded = 0;
        for _ in 0..3000 {
            let (i, a) = random_point(&tris, &mut rng);
            let (_, b) = random_point(&tris, &mut rng);
            let o = a + tris[i].normal() * 1e-3;
            let d = b - o;
            let expected = occluded_brute_force(&tris, o, d, 0.0, 0.999);
            for mode in MODES {
                assert_eq!(
                    tree.occluded(o, d, 0.0, 0.999, mode),
                    expected,
                    "{mode:?} {max_leaf}/{max_depth}: {o} -> {b}"
                );
            }
            occluded += expected as u32;
        }
        // The set mixes both answers (the blocks occlude a good share of the pairs).
        assert!(occluded > 300 && occluded < 2700, "{occluded}");
    }
}

#[test]
fn rays_grazing_walls_equal_brute_force() {
    // Rays parallel to the floor at heights from 1e-4 mm to 1 mm (and some exactly in it),
    // along the floor's grid lines and across them: the voxels they cross hold the floor's flat
    // boxes, and the answer must still be the brute-force one.
    let tris = cornell::grid_triangles(6).expect("cornell");
    let floor_y = tris
        .iter()
        .flat_map(|t| t.v)
        .map(|v| v.y)
        .fold(f32::INFINITY, f32::min);
    for (max_leaf, max_depth) in SETTINGS {
        let tree = build(&tris, max_leaf, max_depth);
        let mut rng = Pcg32::new(77, 3);
        for k in 0..2000 {
            let h = [0.0, 1e-4, 1e-3, 1e-2, 1.0][k % 5];
            let o = Vec3::new(
                rng.next_f32() * 500.0 + 20.0,
                floor_y + h,
                rng.next_f32() * 500.0 + 20.0,
            );
            let d = if k % 3 == 0 {
                Vec3::X * 600.0
            } else {
                Vec3::new(rng.next_f32() - 0.5, 0.0, rng.next_f32() - 0.5) * 800.0
            };
            let expected = occluded_brute_force(&tris, o, d, 0.0, 0.999);
            for mode in MODES {
                assert_eq!(
                    tree.occluded(o, d, 0.0, 0.999, mode),
                    expected,
                    "{mode:?} {max_leaf}/{max_depth}: {o} + t {d}"
                );
            }
        }
    }
}

#[test]
fn first_hit_equals_brute_force_nearest() {
    let tris = cornell::grid_triangles(4).expect("cornell");
    let tree = build(&tris, 4, 10);
    let mut rng = Pcg32::new(9, 2);
    for _ in 0..2000 {
        let o = Vec3::new(
            rng.next_f32() * 556.0,
            rng.next_f32() * 548.0,
            rng.next_f32() * 559.0,
        );
        let d = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        ) * 2000.0;
        let brute = tris
            .iter()
            .enumerate()
            .filter_map(|(i, t)| {
                occ_radiosity::geom::ray_triangle(o, d, t.v[0], t.v[1] - t.v[0], t.v[2] - t.v[0])
                    .filter(|&h| h > 0.0 && h < 1.0)
                    .map(|h| (h, i as u32))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        for mode in MODES {
            let got = tree.first_hit(o, d, 0.0, 1.0, mode);
            assert_eq!(got.map(|g| g.1), brute.map(|b| b.1), "{mode:?} ray {o} {d}");
        }
    }
}

#[test]
fn rays_leaving_a_patch_never_hit_it() {
    let tris = cornell::grid_triangles(3).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let mut rng = Pcg32::new(1234, 7);
    for _ in 0..5000 {
        let (i, p) = random_point(&tris, &mut rng);
        let n = tris[i].normal();
        // A direction in the patch's front hemisphere, from just above the patch (lifted 1e-3 mm
        // along the normal, as the form-factor kernel lifts its ray origins).
        let mut d = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        );
        if d.dot(n) < 0.0 {
            d = -d;
        }
        if d.dot(n) < 1e-3 {
            continue;
        }
        let d = d.normalize() * 2000.0;
        if let Some((_, id)) = tree.first_hit(p + n * 1e-3, d, 0.0, 1.0, Traversal::Samet) {
            assert_ne!(id as usize, i, "ray from patch {i} at {p} hit itself");
        }
    }
}

#[test]
fn axis_parallel_and_degenerate_rays_terminate() {
    let tris = cornell::grid_triangles(2).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    // Above both blocks: walls, floor, ceiling and back wall are hit; the front is open.
    let o = Vec3::new(150.0, 450.0, 300.0);
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let expected = d != -Vec3::Z;
        for mode in MODES {
            assert_eq!(
                tree.occluded(o, d * 1000.0, 0.0, 1.0, mode),
                expected,
                "{mode:?} {d}"
            );
        }
    }
    for mode in MODES {
        assert!(!tree.occluded(o, Vec3::ZERO, 0.0, 1.0, mode));
        let outside = Vec3::new(-1e4, -1e4, -1e4);
        assert!(!tree.occluded(outside, -Vec3::ONE, 0.0, 1e6, mode));
    }
}

#[test]
fn the_faces_of_the_bounding_box_hide_nothing_and_are_left_out() {
    // `occluders` leaves out the triangles lying in a face of the scene's box and facing in:
    // a shadow ray runs between points lifted off their surfaces along their normals, which
    // lie on the inner side of such a face, so none of them can block it. The Cornell box's
    // floor, ceiling, back and one side wall are such faces (the other side wall is not quite
    // axis-aligned in the measured data, so it stays); the blocks and the light stay.
    let scene = cornell::load(true).expect("cornell box");
    let tris: Vec<Tri> = scene.triangles.iter().map(|t| t.tri).collect();
    let kept = occluders(&tris, scene.diagonal());
    assert_eq!((tris.len(), kept.len()), (32, 24));
    let lift = FormFactorConfig::default().offset;
    let mut rng = Pcg32::new(7, 3);
    let mut blocked = 0;
    for _ in 0..20000 {
        let (i, a) = random_point(&tris, &mut rng);
        let (j, b) = random_point(&tris, &mut rng);
        let (o, e) = (a + tris[i].normal() * lift, b + tris[j].normal() * lift);
        let all = occluded_brute_force(&tris, o, e - o, 0.0, 1.0);
        assert_eq!(
            occluded_brute_force(&kept, o, e - o, 0.0, 1.0),
            all,
            "{o} -> {e}"
        );
        blocked += all as u32;
    }
    assert!(blocked > 2000, "the blocks must hide some pairs: {blocked}");
    let kept = occluders(&tris, scene.diagonal());
    // A triangle in the floor's plane facing out (down): a point on it is lifted below the
    // floor, and a ray from it may cross the floor, so no floor triangle is left out.
    let floor = |t: &Tri| t.v.iter().all(|v| v.y.abs() < 1e-3) && t.normal().y > 0.5;
    let floors = tris.iter().filter(|t| floor(t)).count();
    assert!(floors >= 2);
    assert_eq!(kept.iter().filter(|t| floor(t)).count(), 0);
    let mut with_out = tris.clone();
    let [a, b, c] = tris.iter().find(|t| floor(t)).expect("a floor").v;
    with_out.push(Tri::new(a, c, b));
    let kept = occluders(&with_out, scene.diagonal());
    assert_eq!(kept.iter().filter(|t| floor(t)).count(), floors);
}
