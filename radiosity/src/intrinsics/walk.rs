//! The octree walk as intrinsics: a node walks shadow rays through the flat octree it was sent
//! ([`crate::octree::flat`]), testing the voxels it holds and naming the ones it must fetch.

use glam::Vec3;
use occ_runtime::abi::Word;

use super::{array, array_mut, point};
use crate::octree::flat::FlatView;

/// `PROC RAD.RAYS.WALK (VAL []INT tree, VAL []REAL32 frame, VAL []INT slot,
/// VAL []REAL32 pool, VAL []REAL32 rays, []BOOL blocked, []INT cursor, []INT missing,
/// RESULT INT count)`: walks each unanswered shadow ray through the octree (`tree`, `frame`:
/// the flat form of [`crate::octree::flat`]), testing, in the order the ray meets them, the
/// voxels this node holds (voxel `v` at `pool[slot[v]]`, or `slot[v] < 0` when not held), as
/// [`FlatView::walk`] describes: `blocked[k]` becomes TRUE when ray `k` is blocked (a ray
/// already TRUE is not walked), `cursor` (3 INTs a ray; the first `-1` to start a ray, `-2` once
/// answered) records where each ray stopped at a voxel not held, and `missing` receives the
/// distinct voxels the stopped rays wait for, ascending, as many as fit. `count` is their number
/// (0 when every ray is answered), or -1 (nothing written) when `tree` or `frame` is not a flat
/// octree, `slot` does not have one INT per voxel, `rays` is not a multiple of 8 floats,
/// `blocked` or `cursor` is too short for the rays, or a cursor is not a cell, -1 or -2.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI); the
/// written arrays do not overlap each other.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn rays_walk(
    tree: *const i32,
    tree_len: Word,
    frame: *const f32,
    frame_len: Word,
    slot: *const i32,
    slot_len: Word,
    pool: *const f32,
    pool_len: Word,
    rays: *const f32,
    rays_len: Word,
    blocked: *mut u8,
    blocked_len: Word,
    cursor: *mut i32,
    cursor_len: Word,
    missing: *mut i32,
    missing_len: Word,
    count: *mut Word,
) {
    // The stamping walk with no stamps to set (an empty `stamp` is never written).
    // SAFETY: the caller's contract is this one's.
    unsafe {
        rays_walk_stamped(
            tree,
            tree_len,
            frame,
            frame_len,
            slot,
            slot_len,
            pool,
            pool_len,
            rays,
            rays_len,
            blocked,
            blocked_len,
            cursor,
            cursor_len,
            missing,
            missing_len,
            std::ptr::null_mut(),
            0,
            0,
            count,
        )
    }
}

/// `PROC RAD.RAYS.WALK.STAMPED (VAL []INT tree, VAL []REAL32 frame, VAL []INT slot,
/// VAL []REAL32 pool, VAL []REAL32 rays, []BOOL blocked, []INT cursor, []INT missing,
/// []INT stamp, VAL INT now, RESULT INT count)`: `RAD.RAYS.WALK`, also setting `stamp[v]` to
/// `now` for every held voxel `v` a ray tested (voxels beyond `stamp` are not stamped), so that
/// a cache can evict the least recently used ([`FlatView::walk_stamping`]).
///
/// # Safety
/// As [`rays_walk`]; `stamp` does not overlap the other written arrays.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn rays_walk_stamped(
    tree: *const i32,
    tree_len: Word,
    frame: *const f32,
    frame_len: Word,
    slot: *const i32,
    slot_len: Word,
    pool: *const f32,
    pool_len: Word,
    rays: *const f32,
    rays_len: Word,
    blocked: *mut u8,
    blocked_len: Word,
    cursor: *mut i32,
    cursor_len: Word,
    missing: *mut i32,
    missing_len: Word,
    stamp: *mut i32,
    stamp_len: Word,
    now: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays; occam's usage rules keep the written ones apart.
    let written = unsafe {
        let view = FlatView::new(array(tree, tree_len), array(frame, frame_len));
        view.and_then(|view| {
            view.walk_stamping(
                array(slot, slot_len),
                array(pool, pool_len),
                array(rays, rays_len),
                array_mut(blocked, blocked_len),
                array_mut(cursor, cursor_len),
                array_mut(missing, missing_len),
                array_mut(stamp, stamp_len),
                now as i32,
            )
        })
    };
    let value = written.map_or(-1, |n| n as Word);
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = value };
}

/// `PROC RAD.VOXEL.OF.POINT (VAL []INT tree, VAL []REAL32 frame, VAL []REAL32 p,
/// RESULT INT voxel)`: the voxel whose leaf holds the point `p` (3 floats) in the flat octree
/// (`tree`, `frame`), a point on a face between two leaves going to the one on the high side;
/// `voxel` is -2 when that leaf is empty or `p` lies outside the root box, -1 when `tree` or
/// `frame` is not a flat octree or `p` is not 3 floats.
///
/// # Safety
/// The arrays are valid for their lengths and `voxel` for one word (the occam ABI).
pub unsafe extern "C" fn voxel_of_point(
    tree: *const i32,
    tree_len: Word,
    frame: *const f32,
    frame_len: Word,
    p: *const f32,
    p_len: Word,
    voxel: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (view, p) = unsafe {
        (
            FlatView::new(array(tree, tree_len), array(frame, frame_len)),
            point(array(p, p_len)),
        )
    };
    let value = match (view, p) {
        (Some(view), Some(p)) => locate(&view, p),
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *voxel = value };
}

/// The voxel at `p`, or -2 for none.
fn locate(view: &FlatView, p: Vec3) -> Word {
    match view.voxel_at(p) {
        Some(v) if v >= 0 => Word::from(v),
        _ => -2,
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::intrinsics::test::address as entry;
    use crate::octree::flat::{CURSOR_INTS, START};
    use crate::octree::{Octree, OctreeConfig, Traversal};
    use crate::scene::cornell;

    type Walk = unsafe extern "C" fn(
        *const i32,
        Word,
        *const f32,
        Word,
        *const i32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *mut u8,
        Word,
        *mut i32,
        Word,
        *mut i32,
        Word,
        *mut Word,
    );

    type OfPoint =
        unsafe extern "C" fn(*const i32, Word, *const f32, Word, *const f32, Word, *mut Word);

    /// Calls RAD.RAYS.WALK through the table.
    #[allow(clippy::too_many_arguments, reason = "the intrinsic's arrays")]
    fn walk(
        tree: &[i32],
        frame: &[f32],
        slot: &[i32],
        pool: &[f32],
        rays: &[f32],
        blocked: &mut [u8],
        cursor: &mut [i32],
        missing: &mut [i32],
    ) -> Word {
        // SAFETY: the table says this is the signature.
        let f: Walk = unsafe { std::mem::transmute(entry("RAD.RAYS.WALK")) };
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                tree.as_ptr(),
                tree.len() as Word,
                frame.as_ptr(),
                frame.len() as Word,
                slot.as_ptr(),
                slot.len() as Word,
                pool.as_ptr(),
                pool.len() as Word,
                rays.as_ptr(),
                rays.len() as Word,
                blocked.as_mut_ptr(),
                blocked.len() as Word,
                cursor.as_mut_ptr(),
                cursor.len() as Word,
                missing.as_mut_ptr(),
                missing.len() as Word,
                &mut count,
            )
        };
        count
    }

    #[test]
    fn the_walk_through_the_table_fetches_and_answers_as_the_octree() {
        let tris = cornell::grid_triangles(6).expect("cornell");
        let tree = Octree::build(&tris, OctreeConfig::default());
        let flat = tree.flat().expect("flat");
        // Rays from the floor's centre to points on the ceiling, some past the blocks.
        let mut rays = Vec::new();
        for i in 0..64 {
            let o = Vec3::new(278.0, 0.01, 279.0);
            let b = Vec3::new(10.0 + 8.5 * i as f32, 548.0, 20.0 + 8.0 * i as f32);
            rays.extend((o.to_array().into_iter()).chain((b - o).to_array()));
            rays.extend([0.0, 0.999]);
        }
        let want: Vec<u8> = rays
            .chunks(8)
            .map(|r| {
                let (o, d) = (Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..6]));
                tree.occluded(o, d, r[6], r[7], Traversal::Ropes) as u8
            })
            .collect();
        assert!(want.contains(&0) && want.contains(&1));
        let n = want.len();
        let (mut blocked, mut cursor) = (vec![0u8; n], vec![START; CURSOR_INTS * n]);
        let mut missing = [0i32; 4];
        let mut slot = vec![-1; flat.voxel_count()];
        let mut pool = Vec::new();
        let mut calls = 0;
        loop {
            let count = walk(
                &flat.tree,
                &flat.frame,
                &slot,
                &pool,
                &rays,
                &mut blocked,
                &mut cursor,
                &mut missing,
            );
            calls += 1;
            assert!(count >= 0);
            if count == 0 {
                break;
            }
            for &v in &missing[..(count as usize).min(4)] {
                slot[v as usize] = pool.len() as i32;
                pool.extend_from_slice(flat.voxel(v as usize));
            }
        }
        assert!(calls > 2);
        assert_eq!(blocked, want);
        // A wrong length answers -1 and writes nothing.
        let (mut b, mut c) = (vec![5u8; n], vec![START; CURSOR_INTS * n]);
        let bad = walk(
            &flat.tree,
            &flat.frame,
            &slot[1..],
            &pool,
            &rays,
            &mut b,
            &mut c,
            &mut missing,
        );
        assert_eq!(bad, -1);
        assert!(b.iter().all(|&x| x == 5));
        let bad = walk(
            &flat.tree[1..],
            &flat.frame,
            &slot,
            &pool,
            &rays,
            &mut b,
            &mut c,
            &mut missing,
        );
        assert_eq!(bad, -1);
    }

    #[test]
    fn voxel_of_point_through_the_table() {
        let tris = cornell::grid_triangles(6).expect("cornell");
        let tree = Octree::build(&tris, OctreeConfig::default());
        let flat = tree.flat().expect("flat");
        // SAFETY: the table says this is the signature.
        let f: OfPoint = unsafe { std::mem::transmute(entry("RAD.VOXEL.OF.POINT")) };
        let call = |p: &[f32], frame: &[f32]| {
            let mut v = 0;
            // SAFETY: valid slices and result.
            unsafe {
                f(
                    flat.tree.as_ptr(),
                    flat.tree.len() as Word,
                    frame.as_ptr(),
                    frame.len() as Word,
                    p.as_ptr(),
                    p.len() as Word,
                    &mut v,
                )
            };
            v
        };
        // A point on the floor lies in a voxel holding the floor.
        let v = call(&[100.0, 0.0, 100.0], &flat.frame);
        assert!(v >= 0 && (v as usize) < flat.voxel_count());
        assert!(!flat.voxel(v as usize).is_empty());
        assert_eq!(call(&[100.0, -1e4, 100.0], &flat.frame), -2);
        assert_eq!(call(&[100.0, 0.0], &flat.frame), -1);
        assert_eq!(call(&[100.0, 0.0, 100.0], &flat.frame[..3]), -1);
    }
}
