//! The flat walk against the octree it was made from.

use super::*;
use crate::generate::{RoomsConfig, rooms};
use crate::geom::Tri;
use crate::octree::{OctreeConfig, Traversal};
use crate::rng::Pcg32;
use crate::scene::cornell;

/// The scenes: the 10,368-triangle Cornell box, a generated scene of furnished rooms, and the
/// Cornell box with tiny leaves (a deep tree with many empty leaves).
fn scenes() -> Vec<(&'static str, Vec<Tri>, OctreeConfig)> {
    let cornell = cornell::grid_triangles(18).expect("cornell");
    let rooms: Vec<Tri> = rooms(RoomsConfig::about(6_000, 3))
        .triangles
        .iter()
        .map(|t| t.tri)
        .collect();
    let fine = OctreeConfig {
        max_leaf: 4,
        max_depth: 9,
    };
    vec![
        ("cornell", cornell.clone(), OctreeConfig::default()),
        ("rooms", rooms, OctreeConfig::default()),
        ("cornell, small leaves", cornell, fine),
    ]
}

/// A point in the scene's bounding box, widened by a quarter on each side.
fn point_near(tris: &[Tri], rng: &mut Pcg32) -> Vec3 {
    let (lo, hi) = tris
        .iter()
        .flat_map(|t| t.v)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    lo - (hi - lo) * 0.25 + u * (hi - lo) * 1.5
}

/// Rays (8 floats each) of every kind a walk meets: between two surface points (the origin
/// lifted off its surface, as shadow rays are), from free points in random directions, along
/// the axes (zero direction components), starting outside the tree, with `tmin > 0`, and
/// empty.
fn rays(tris: &[Tri], n: usize, seed: u64) -> Vec<f32> {
    let mut rng = Pcg32::new(seed, 3);
    let mut out = Vec::with_capacity(RAY_FLOATS * n);
    for k in 0..n {
        let pick = |rng: &mut Pcg32| {
            let t = &tris[rng.next_u32() as usize % tris.len()];
            (t.sample(rng.next_f32(), rng.next_f32()), t.normal())
        };
        let (o, d, tmin, tmax) = match k % 6 {
            0 | 1 => {
                let ((a, na), (b, _)) = (pick(&mut rng), pick(&mut rng));
                let o = a + na * 1e-3;
                (o, b - o, 0.0, 0.999)
            }
            2 => {
                let o = point_near(tris, &mut rng);
                (o, point_near(tris, &mut rng) - o, 0.0, 1.0)
            }
            3 => {
                let (o, _) = pick(&mut rng);
                let mut d = point_near(tris, &mut rng) - o;
                d[rng.next_u32() as usize % 3] = 0.0;
                d[rng.next_u32() as usize % 3] = 0.0;
                (o, d, 0.0, 1.0)
            }
            4 => {
                let o = point_near(tris, &mut rng);
                let d = point_near(tris, &mut rng) - o;
                (o, d, 0.25 * rng.next_f32(), 0.5 + rng.next_f32())
            }
            _ if k % 12 == 5 => (point_near(tris, &mut rng), Vec3::ZERO, 0.0, 0.0),
            _ => {
                let ((a, na), (b, _)) = (pick(&mut rng), pick(&mut rng));
                (a + na * 1e-3, (b - a) * 3.0, 0.0, 1.0)
            }
        };
        out.extend_from_slice(&o.to_array());
        out.extend_from_slice(&d.to_array());
        out.extend_from_slice(&[tmin, tmax]);
    }
    out
}

/// The octree's answers for the rays.
fn expected(tree: &Octree, rays: &[f32]) -> Vec<u8> {
    rays.as_chunks::<RAY_FLOATS>()
        .0
        .iter()
        .map(|r| {
            let (o, d) = (Vec3::from_slice(&r[0..3]), Vec3::from_slice(&r[3..6]));
            tree.occluded(o, d, r[6], r[7], Traversal::Ropes) as u8
        })
        .collect()
}

/// A fresh cursor: every ray at its start.
fn start(n: usize) -> Vec<i32> {
    vec![START; CURSOR_INTS * n]
}

#[test]
fn with_every_voxel_held_one_call_answers_as_the_octree() {
    for (name, tris, config) in scenes() {
        let tree = Octree::build(&tris, config);
        let flat = tree.flat().expect("flat");
        let rays = rays(&tris, 20_000, 1);
        let n = rays.len() / RAY_FLOATS;
        let want = expected(&tree, &rays);
        let (mut blocked, mut cursor, mut missing) = (vec![0; n], start(n), [7; 4]);
        let count = flat.view().walk(
            &flat.slots(),
            flat.pool(),
            &rays,
            &mut blocked,
            &mut cursor,
            &mut missing,
        );
        assert_eq!(count, Some(0), "{name}");
        assert_eq!(missing, [7; 4], "{name}: nothing is missing");
        assert_eq!(blocked, want, "{name}");
        assert!(cursor.chunks(3).all(|c| c[0] == DONE), "{name}");
        let occluded = want.iter().filter(|&&b| b != 0).count();
        assert!(
            (n / 20..n * 19 / 20).contains(&occluded),
            "{name}: {occluded} of {n} rays blocked; the rays should test both answers"
        );
    }
}

/// Walks `rays` with the voxels in `held` cached in a pool of their own (in a shuffled order),
/// fetching the missing ones `missing_len` at a time as a node would, until every ray is
/// answered; returns the flags and the number of calls.
fn walk_fetching(
    flat: &FlatOctree,
    rays: &[f32],
    held: &mut [bool],
    missing_len: usize,
    rng: &mut Pcg32,
) -> (Vec<u8>, usize) {
    let n = rays.len() / RAY_FLOATS;
    let mut slot = vec![-1; flat.voxel_count()];
    let mut pool = vec![f32::NAN; 5];
    let mut order: Vec<usize> = (0..held.len()).filter(|&v| held[v]).collect();
    for i in (1..order.len()).rev() {
        order.swap(i, rng.next_u32() as usize % (i + 1));
    }
    let fetch = |v: usize, slot: &mut [i32], pool: &mut Vec<f32>| {
        slot[v] = pool.len() as i32;
        pool.extend_from_slice(flat.voxel(v));
        pool.push(f32::NAN);
    };
    for v in order {
        fetch(v, &mut slot, &mut pool);
    }
    let (mut blocked, mut cursor) = (vec![0; n], start(n));
    let mut missing = vec![-1; missing_len];
    for calls in 1.. {
        let count = flat
            .view()
            .walk(&slot, &pool, rays, &mut blocked, &mut cursor, &mut missing)
            .expect("well formed");
        if count == 0 {
            return (blocked, calls);
        }
        let listed = &missing[..count.min(missing_len)];
        assert!(listed.is_sorted(), "{listed:?}");
        for &v in listed {
            assert!(!held[v as usize], "voxel {v} is held but was asked for");
            held[v as usize] = true;
            fetch(v as usize, &mut slot, &mut pool);
        }
        assert!(calls <= flat.voxel_count() + 1, "no progress");
    }
    unreachable!()
}

#[test]
fn with_part_of_the_voxels_held_repeated_calls_answer_as_the_octree() {
    for (name, tris, config) in scenes() {
        let tree = Octree::build(&tris, config);
        let flat = tree.flat().expect("flat");
        let rays = rays(&tris, 5_000, 2);
        let want = expected(&tree, &rays);
        let mut rng = Pcg32::new(9, 9);
        for (fraction, missing_len) in [(0.0, 1000), (0.3, 3), (0.8, 1), (0.5, 0)] {
            let mut held: Vec<bool> = (0..flat.voxel_count())
                .map(|_| rng.next_f32() < fraction)
                .collect();
            if missing_len == 0 {
                // Nothing fits in `missing`: the count alone says what is left; fetch nothing
                // and check the count, then everything.
                let n = rays.len() / RAY_FLOATS;
                let (mut blocked, mut cursor) = (vec![0; n], start(n));
                let slot: Vec<i32> = (0..flat.voxel_count())
                    .map(|v| if held[v] { flat.slots()[v] } else { -1 })
                    .collect();
                let count = flat
                    .view()
                    .walk(
                        &slot,
                        flat.pool(),
                        &rays,
                        &mut blocked,
                        &mut cursor,
                        &mut [],
                    )
                    .expect("well formed");
                assert!(count > 0, "{name}: half the voxels cannot answer every ray");
                let all = flat.slots();
                let again =
                    flat.view()
                        .walk(&all, flat.pool(), &rays, &mut blocked, &mut cursor, &mut []);
                assert_eq!(again, Some(0), "{name}");
                assert_eq!(blocked, want, "{name}, resumed with every voxel");
                continue;
            }
            let (blocked, calls) = walk_fetching(&flat, &rays, &mut held, missing_len, &mut rng);
            assert_eq!(
                blocked, want,
                "{name}, {fraction} held, {missing_len} a call"
            );
            assert!(calls > 1, "{name}: some voxel was missing");
        }
    }
}

#[test]
fn rays_are_stopped_at_their_first_missing_voxel_in_order() {
    // One ray along x through a row of leaves, nothing held: it asks for the first voxel on its
    // way, then (that one held) the next, and so on, each once.
    let tris = cornell::grid_triangles(6).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let view = flat.view();
    let (o, d) = (Vec3::new(1.0, 500.0, 280.0), Vec3::new(554.0, 0.0, 0.0));
    let ray = [o.x, o.y, o.z, d.x, d.y, d.z, 0.0, 1.0];
    let mut met = Vec::new();
    tree.walk(o, d, 0.0, 1.0, Traversal::Ropes, |leaf, _| {
        if leaf[1] > 0 {
            let n = (0..tree.nodes.len()).find(|&n| tree.hot[n] == leaf);
            let v = flat.leaves.iter().position(|&l| Some(l) == n);
            met.push(v.expect("a voxel") as i32);
        }
        false
    });
    assert!(met.len() >= 2, "{met:?}");
    let mut slot = vec![-1; flat.voxel_count()];
    let (mut blocked, mut cursor, mut missing) = ([0], start(1), [0]);
    let mut asked = Vec::new();
    loop {
        let count = view
            .walk(
                &slot,
                flat.pool(),
                &ray,
                &mut blocked,
                &mut cursor,
                &mut missing,
            )
            .expect("well formed");
        if count == 0 {
            break;
        }
        assert_eq!(count, 1);
        asked.push(missing[0]);
        slot[missing[0] as usize] = flat.slots()[missing[0] as usize];
    }
    assert_eq!(asked, met);
    assert_eq!(blocked, [0], "the ray runs between the walls");
}

#[test]
fn a_voxel_is_the_octree_leaf_packed_as_documented() {
    let tris = cornell::grid_triangles(18).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let view = flat.view();
    assert_eq!(flat.voxel_count(), tree.voxels().count());
    assert_eq!(flat.tree.len(), RECORD_INTS * (tree.nodes.len() + 1));
    for v in 0..flat.voxel_count() {
        let leaf = flat.leaf(v).expect("a voxel");
        let floats = flat.voxel(v);
        let packets = view.hot(leaf as u32)[1] as usize;
        assert_eq!(view.hot(leaf as u32)[0], v as u32);
        assert_eq!(floats.len(), voxel_floats(packets));
        assert_eq!(flat.voxel_bytes(v), 4 * floats.len());
        // The triangles, unpacked lane by lane, are the leaf's, as `voxel_floats` gives them.
        let groups = packets.div_ceil(LANES) * BOX_GROUP_FLOATS;
        let mut unpacked = Vec::new();
        for p in floats[groups..].chunks_exact(PACKET_FLOATS) {
            for lane in 0..LANES {
                let tri: Vec<f32> = (0..9).map(|i| p[4 * i + lane]).collect();
                if tri[3..].iter().any(|&x| x != 0.0) {
                    unpacked.extend(tri);
                }
            }
        }
        assert_eq!(unpacked, tree.voxel_floats(leaf), "voxel {v}");
    }
    // Every leaf's record names its voxel or none.
    let empty = (0..tree.nodes.len())
        .filter(|&n| tree.nodes[n].count == 0)
        .count();
    assert!(empty > 0);
    for n in 0..tree.nodes.len() {
        let r = view.records[n + 1];
        match tree.nodes[n].count {
            INTERIOR => assert_eq!((r[0], r[1]), (tree.nodes[n].first as i32, -1)),
            0 => assert_eq!((r[0], r[1]), (-1, 0)),
            _ => assert_eq!(flat.leaf(r[0] as usize), Some(n)),
        }
    }
}

#[test]
fn the_voxel_at_a_point_is_the_leaf_whose_box_holds_it() {
    let tris = cornell::grid_triangles(18).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let view = flat.view();
    let mut rng = Pcg32::new(4, 4);
    for (n, node) in tree.nodes.iter().enumerate() {
        if node.count == INTERIOR {
            continue;
        }
        let (lo, hi) = tree.node_box(node);
        let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let inside = lo + (hi - lo) * (0.01 + 0.98 * u);
        let want = flat
            .leaves
            .iter()
            .position(|&l| l == n)
            .map_or(-1, |v| v as i32);
        assert_eq!(view.voxel_at(inside), Some(want), "node {n}");
    }
    let (lo, hi) = tree.node_box(&tree.nodes[0]);
    assert_eq!(view.voxel_at(lo - Vec3::X), None);
    assert_eq!(view.voxel_at(hi), None);
    assert_eq!(view.voxel_at(Vec3::NAN), None);
}

#[test]
fn wrong_lengths_and_cursors_answer_none_and_write_nothing() {
    let tris = cornell::grid_triangles(4).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let view = flat.view();
    let slots = flat.slots();
    let rays = rays(&tris, 4, 5);
    let check = |slot: &[i32], rays: &[f32], blocked_len: usize, cursor: &[i32]| {
        let (mut blocked, mut cur, mut missing) = (vec![9; blocked_len], cursor.to_vec(), [9]);
        let got = view.walk(
            slot,
            flat.pool(),
            rays,
            &mut blocked,
            &mut cur,
            &mut missing,
        );
        assert_eq!(got, None);
        assert!(blocked.iter().all(|&b| b == 9) && cur == cursor && missing == [9]);
    };
    check(&slots[1..], &rays, 4, &start(4));
    check(&slots, &rays[1..], 4, &start(4));
    check(&slots, &rays, 3, &start(4));
    check(&slots, &rays, 4, &start(3));
    let mut bad = start(4);
    bad[3..6].copy_from_slice(&[0, 1 << tree.depth, 0]);
    check(&slots, &rays, 4, &bad);
    bad[3..6].copy_from_slice(&[-3, 0, 0]);
    check(&slots, &rays, 4, &bad);
    // Headers and frames that do not fit.
    let mut tree_ints = flat.tree.clone();
    assert!(FlatView::new(&tree_ints[..tree_ints.len() - 1], &flat.frame).is_none());
    assert!(FlatView::new(&tree_ints, &flat.frame[..3]).is_none());
    assert!(FlatView::new(&tree_ints, &[0.0, 0.0, 0.0, 0.0]).is_none());
    assert!(FlatView::new(&[], &flat.frame).is_none());
    tree_ints[0] = 21;
    assert!(FlatView::new(&tree_ints, &flat.frame).is_none());
}

#[test]
fn a_malformed_tree_neither_panics_nor_loops() {
    let tris = cornell::grid_triangles(6).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let flat = tree.flat().expect("flat");
    let rays = rays(&tris, 200, 6);
    let n = rays.len() / RAY_FLOATS;
    let mut rng = Pcg32::new(8, 8);
    for round in 0..200 {
        let mut ints = flat.tree.clone();
        for _ in 0..1 + round % 20 {
            let i = RECORD_INTS + rng.next_u32() as usize % (ints.len() - RECORD_INTS);
            ints[i] = match rng.next_u32() % 4 {
                0 => -1,
                1 => rng.next_u32() as i32,
                2 => (rng.next_u32() % 64) as i32,
                _ => i32::MAX,
            };
        }
        let view = FlatView::new(&ints, &flat.frame).expect("the header is intact");
        let (mut blocked, mut cursor, mut missing) = (vec![0; n], start(n), [0; 8]);
        let slot = flat.slots();
        let pool = &flat.pool()[..flat.pool().len() / 2];
        let count = view.walk(&slot, pool, &rays, &mut blocked, &mut cursor, &mut missing);
        assert!(count.is_some());
        let _ = view.voxel_at(Vec3::splat(200.0));
    }
}

#[test]
fn a_stamping_walk_stamps_the_voxels_its_rays_test_and_answers_the_same() {
    for (name, tris, config) in scenes() {
        let tree = Octree::build(&tris, config);
        let flat = tree.flat().expect("flat");
        let rays = rays(&tris, 300, 5);
        for ray in rays.chunks(RAY_FLOATS) {
            // Nothing held: the walk asks for the voxels the ray tests, one at a time, in order.
            let mut met = Vec::new();
            let mut slot = vec![-1; flat.voxel_count()];
            let mut pool = Vec::new();
            let (mut blocked, mut cursor, mut missing) = (vec![0], start(1), [0]);
            while flat
                .view()
                .walk(&slot, &pool, ray, &mut blocked, &mut cursor, &mut missing)
                .expect("well formed")
                > 0
            {
                met.push(missing[0]);
                slot[missing[0] as usize] = pool.len() as i32;
                pool.extend_from_slice(flat.voxel(missing[0] as usize));
            }
            // Everything held: the same voxels are stamped, and the same answer given.
            let mut stamp = vec![0; flat.voxel_count()];
            let (mut again, mut cursor) = (vec![0], start(1));
            let count = flat.view().walk_stamping(
                &flat.slots(),
                flat.pool(),
                ray,
                &mut again,
                &mut cursor,
                &mut [],
                &mut stamp,
                7,
            );
            assert_eq!(count, Some(0), "{name}");
            assert_eq!(again, blocked, "{name}");
            let stamped: Vec<i32> = (0..stamp.len() as i32)
                .filter(|&v| stamp[v as usize] == 7)
                .collect();
            met.sort_unstable();
            assert_eq!(stamped, met, "{name}");
        }
    }
}
