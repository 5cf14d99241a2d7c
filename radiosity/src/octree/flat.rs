//! The octree in the flat form a CARM node is sent: plain `[]INT` and `[]REAL32` arrays that an
//! occam program can hold, send and pass to the walk intrinsic (`RAD.RAYS.WALK`), with each
//! voxel's geometry a separate block of floats that a node holds only when it has fetched it.
//!
//! # Layout
//!
//! **`tree`** (`[]INT`, i32): records of [`RECORD_INTS`] = 8 ints. Record 0 is the header
//! `[depth, nodes, voxels, 0, 0, 0, 0, 0]`; node `n` (0 is the root) is record `n + 1`, at
//! `tree[8 (n + 1) ..]`, so `tree` has `8 (nodes + 1)` ints:
//! - interior node: `[first, -1, -1, -1, -1, -1, -1, -1]`: its children are nodes
//!   `first .. first + 8`, child `x | y << 1 | z << 2` on the high side of the axes whose bit
//!   is set;
//! - leaf: `[voxel, packets, rope 0 .. rope 5]`: `voxel` is the voxel number (`-1` for an empty
//!   leaf, which holds no geometry and is never fetched), `packets` the number of four-triangle
//!   packets its geometry takes (0 when empty); rope `f` is the neighbour of equal or greater
//!   size across face `f` (`2 axis` on the low side, `2 axis + 1` on the high side) as
//!   `node << 5 | level`, or `-1` on the root box's boundary.
//!
//! A node's box, in cells of the finest grid (`2^depth` a side), is
//! `origin .. origin + 2^(depth - level)` on each axis, the origin found by descending.
//!
//! **`frame`** (`[]REAL32`, [`FRAME_FLOATS`] = 4): the root box's low corner `x, y, z` and the
//! side of a finest cell; the root box is `lo .. lo + 2^depth cell`.
//!
//! **A voxel** (`[]REAL32`, [`voxel_floats`]`(packets)` = `24 g + 36 packets` floats,
//! `g = ceil (packets / 4)`): the octree's own storage of the leaf, one block that is sent as one
//! message. First `g` box groups of 24 floats, each the boxes of four packets (`lo.x` of the
//! four, `lo.y`, `lo.z`, `hi.x`, `hi.y`, `hi.z`; a box beyond the last packet is the point
//! (1e30, 1e30, 1e30)); then the packets, 36 floats each, four triangles as corner 0 and the
//! two edges from it, by coordinate (`v0.x` of the four, `v0.y`, `v0.z`, `e1.x`, ..., `e2.z`;
//! an unused lane is all zero). A packet's box bounds its triangles clipped to the leaf, widened
//! by the octree's margin, so most rays skip most packets ([`crate::packet`]); the walk tests
//! exactly what [`Octree::occluded`] tests. ([`Octree::voxel_floats`] is the same geometry
//! unpacked, 9 floats a triangle, as `RAD.VOXEL.OCCLUDED` takes it.)
//!
//! **A walk's cursor** (`[]INT`, [`CURSOR_INTS`] = 3 a ray): [`START`] in the first int for a
//! ray not yet walked, [`DONE`] for one answered (blocked, or out of the tree, or past `tmax`),
//! otherwise the cell `x, y, z` (each in `0 .. 2^depth`) of the leaf where the walk goes on:
//! the first leaf along the ray whose voxel the node did not hold. Going on from a cell repeats
//! exactly the steps an unbroken walk takes, so the answers do not depend on what was cached.

use glam::{UVec3, Vec3, Vec3A};

use super::{INTERIOR, NO_ROPE, Octree, Path, ROPES, Skeleton, Walker};
use crate::intrinsics::RAY_FLOATS;
use crate::packet::NO_TRIANGLE;
use crate::packet::{BoxGroup, LANES, RayQuery, TriPacket};

/// Ints per record of the `tree` array.
pub const RECORD_INTS: usize = 8;

/// Floats of the `frame` array.
pub const FRAME_FLOATS: usize = 4;

/// Floats of a box group in a voxel.
pub const BOX_GROUP_FLOATS: usize = 24;

/// Floats of a packet in a voxel.
pub const PACKET_FLOATS: usize = 36;

/// Ints per ray of a walk's cursor.
pub const CURSOR_INTS: usize = 3;

/// A cursor's first int for a ray not yet walked.
pub const START: i32 = -1;

/// A cursor's first int for a ray answered.
pub const DONE: i32 = -2;

/// Most nodes the flat form holds (a rope packs a node index into 26 bits).
pub const MAX_NODES: usize = 1 << 26;

// A voxel's blocks are read in place as the structs the octree stores (see `read`).
const _: () = assert!(size_of::<BoxGroup>() == 4 * BOX_GROUP_FLOATS);
const _: () = assert!(size_of::<TriPacket>() == 4 * PACKET_FLOATS);

/// Floats of a voxel with `packets` packets.
pub const fn voxel_floats(packets: usize) -> usize {
    packets.div_ceil(LANES) * BOX_GROUP_FLOATS + packets * PACKET_FLOATS
}

/// Why an octree has no flat form.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FlatError {
    /// More nodes than a rope can name.
    #[error("the octree has {0} nodes, more than the flat form's {MAX_NODES}")]
    TooManyNodes(usize),
    /// The voxels take more floats than an INT offset reaches.
    #[error("the voxels take {0} floats, more than an INT offset reaches")]
    PoolTooLarge(usize),
}

/// An octree in flat form (see the module documentation for the layout), with all its voxels
/// back to back in one pool, as the host holds them.
#[derive(Clone, Debug)]
pub struct FlatOctree {
    /// The `tree` array.
    pub tree: Vec<i32>,
    /// The `frame` array.
    pub frame: Vec<f32>,
    /// Every voxel's floats, voxel 0 first.
    pool: Vec<f32>,
    /// Voxel `v` is `pool[offsets[v] .. offsets[v + 1]]`.
    offsets: Vec<usize>,
    /// The octree node (leaf) of each voxel.
    leaves: Vec<usize>,
}

impl FlatOctree {
    /// The number of voxels (leaves that hold geometry).
    pub fn voxel_count(&self) -> usize {
        self.leaves.len()
    }

    /// The floats of voxel `v` (empty when out of range).
    pub fn voxel(&self, v: usize) -> &[f32] {
        match (self.offsets.get(v), self.offsets.get(v + 1)) {
            (Some(&a), Some(&b)) => &self.pool[a..b],
            _ => &[],
        }
    }

    /// The size of voxel `v` in bytes, as a node's cache counts it.
    pub fn voxel_bytes(&self, v: usize) -> usize {
        4 * self.voxel(v).len()
    }

    /// The octree node (leaf) that is voxel `v`, for [`Octree::voxel_floats`].
    pub fn leaf(&self, v: usize) -> Option<usize> {
        self.leaves.get(v).copied()
    }

    /// All voxels back to back (a pool holding every voxel, at [`FlatOctree::slots`]).
    pub fn pool(&self) -> &[f32] {
        &self.pool
    }

    /// The offset of every voxel in [`FlatOctree::pool`]: the `slot` array of a node that
    /// holds them all.
    pub fn slots(&self) -> Vec<i32> {
        // `flat` checked that every offset fits.
        self.offsets[..self.leaves.len()]
            .iter()
            .map(|&o| o as i32)
            .collect()
    }

    /// The arrays as a walk reads them.
    pub fn view(&self) -> FlatView<'_> {
        FlatView::new(&self.tree, &self.frame).expect("a flat octree is well formed")
    }
}

impl Octree {
    /// The flat form of the tree (see [`crate::octree::flat`]); voxels are numbered in node order.
    pub fn flat(&self) -> Result<FlatOctree, FlatError> {
        let nodes = self.nodes.len();
        if nodes > MAX_NODES {
            return Err(FlatError::TooManyNodes(nodes));
        }
        let leaves: Vec<usize> = self.voxels().collect();
        let mut tree = vec![-1; RECORD_INTS * (nodes + 1)];
        tree[..3].copy_from_slice(&[self.depth as i32, nodes as i32, leaves.len() as i32]);
        tree[3..RECORD_INTS].fill(0);
        let mut voxel_of = vec![-1; nodes];
        for (v, &leaf) in leaves.iter().enumerate() {
            voxel_of[leaf] = v as i32;
        }
        for (n, node) in self.nodes.iter().enumerate() {
            let record = &mut tree[RECORD_INTS * (n + 1)..RECORD_INTS * (n + 2)];
            if node.count == INTERIOR {
                record[0] = node.first as i32;
                continue;
            }
            record[0] = voxel_of[n];
            record[1] = node.count as i32;
            for (face, r) in record[2..].iter_mut().enumerate() {
                let rope = self.ropes[6 * n + face];
                if rope != NO_ROPE {
                    *r = (((rope >> 8) << 5) | (rope & 255)) as i32;
                }
            }
        }
        let mut pool = Vec::new();
        let mut offsets = Vec::with_capacity(leaves.len() + 1);
        for &leaf in &leaves {
            offsets.push(pool.len());
            self.append_voxel(leaf, &mut pool);
        }
        offsets.push(pool.len());
        if pool.len() > i32::MAX as usize {
            return Err(FlatError::PoolTooLarge(pool.len()));
        }
        Ok(FlatOctree {
            tree,
            frame: vec![self.lo.x, self.lo.y, self.lo.z, self.cell],
            pool,
            offsets,
            leaves,
        })
    }

    /// Appends the voxel of `leaf` in the flat form's layout.
    fn append_voxel(&self, leaf: usize, out: &mut Vec<f32>) {
        let node = self.nodes[leaf];
        let (first, count) = (node.first as usize, node.count as usize);
        for g in &self.boxes[first / LANES..(first + count).div_ceil(LANES)] {
            out.extend(g.sides.iter().flatten().flat_map(|v| v.to_array()));
        }
        for p in &self.packets[first..first + count] {
            out.extend(
                [p.v0, p.e1, p.e2]
                    .iter()
                    .flatten()
                    .flat_map(|v| v.to_array()),
            );
        }
    }
}

/// The empty leaf a malformed node reads as.
const EMPTY_LEAF: [u32; 2] = [u32::MAX, 0];

/// The flat arrays as a walk reads them: the header checked, every other read bounds-checked.
/// A malformed record cannot make a walk fail or loop: a node out of range reads as an empty
/// leaf, a bad rope as the root (a descent from the top finds the same leaf).
#[derive(Clone, Copy, Debug)]
pub struct FlatView<'a> {
    /// The records; node `n` is `records[n + 1]`.
    records: &'a [[i32; RECORD_INTS]],
    lo: Vec3,
    cell: f32,
    depth: u32,
    voxels: usize,
}

impl<'a> FlatView<'a> {
    /// Views `tree` and `frame`; `None` unless the header is consistent (`tree` has
    /// `8 (nodes + 1)` ints with `nodes >= 1`, `depth <= 20`, `voxels >= 0`) and `frame` is 4
    /// finite floats with a positive cell.
    pub fn new(tree: &'a [i32], frame: &[f32]) -> Option<FlatView<'a>> {
        let (records, rest) = tree.as_chunks::<RECORD_INTS>();
        let header = records.first()?;
        let [depth, nodes, voxels] = [header[0], header[1], header[2]].map(|x| x as usize);
        let frame: [f32; FRAME_FLOATS] = frame.try_into().ok()?;
        let fits = rest.is_empty()
            && header.iter().all(|&x| x >= 0)
            && depth <= 20
            && nodes >= 1
            && records.len() == nodes + 1
            && frame.iter().all(|x| x.is_finite())
            && frame[3] > 0.0;
        fits.then(|| FlatView {
            records,
            lo: Vec3::new(frame[0], frame[1], frame[2]),
            cell: frame[3],
            depth: depth as u32,
            voxels,
        })
    }

    /// The number of voxels.
    pub fn voxel_count(&self) -> usize {
        self.voxels
    }

    /// The voxel holding point `p`: `Some(v)`, or `Some(-1)` for an empty leaf; `None` outside
    /// the root box. A point on a face between two leaves belongs to the one on its high side.
    pub fn voxel_at(&self, p: Vec3) -> Option<i32> {
        let q = (p - self.lo) / self.cell;
        let cells = (1u32 << self.depth) as f32;
        if !(q.cmpge(Vec3::ZERO).all() && q.cmplt(Vec3::splat(cells)).all()) {
            return None;
        }
        let mut path: Path = [0; 21];
        let (_, leaf) = self.descend(&mut path, 0, 0, q.as_uvec3());
        Some(self.hot(leaf)[0] as i32)
    }

    /// Walks each unanswered ray through the leaves it crosses, in order, testing the voxels the
    /// node holds, until the ray is blocked, leaves the tree or passes `tmax`, or reaches a voxel
    /// the node does not hold (then its cursor records where it stopped).
    ///
    /// - `slot[v]` is the offset in `pool` of voxel `v`, or negative when the node does not hold
    ///   it (a slot whose voxel would not fit inside `pool` counts as not held);
    /// - `rays`: [`RAY_FLOATS`] a ray (origin, direction, tmin, tmax); a ray is blocked when a
    ///   triangle lies at `tmin < t < tmax`; an empty ray (not `tmin < tmax`) is answered at once;
    /// - `blocked[k]`: set to 1 when ray `k` is found blocked; a ray already flagged is not
    ///   walked (so flags accumulate over calls, and over `RAD.VOXEL.OCCLUDED`);
    /// - `cursor`: [`CURSOR_INTS`] a ray (see the module documentation), updated;
    /// - `missing`: receives the distinct voxels the stopped rays wait for, ascending, as many
    ///   as fit.
    ///
    /// Returns the number of those voxels (0 when every ray is answered; it may exceed
    /// `missing.len()`), or `None`, writing nothing, when `slot` does not have one int per
    /// voxel, `rays` is not a multiple of 8 floats, `blocked` or `cursor` is too short for the
    /// rays, or a cursor holds neither a cell of the grid nor [`START`] / [`DONE`].
    pub fn walk(
        &self,
        slot: &[i32],
        pool: &[f32],
        rays: &[f32],
        blocked: &mut [u8],
        cursor: &mut [i32],
        missing: &mut [i32],
    ) -> Option<usize> {
        self.walk_stamping(slot, pool, rays, blocked, cursor, missing, &mut [], 0)
    }

    /// [`FlatView::walk`], also setting `stamp[v]` to `now` for every held voxel `v` a ray
    /// tested (as far as `stamp` reaches), so that a cache can tell which voxels were used last.
    #[allow(
        clippy::too_many_arguments,
        reason = "the walk's arrays and the stamps"
    )]
    pub fn walk_stamping(
        &self,
        slot: &[i32],
        pool: &[f32],
        rays: &[f32],
        blocked: &mut [u8],
        cursor: &mut [i32],
        missing: &mut [i32],
        stamp: &mut [i32],
        now: i32,
    ) -> Option<usize> {
        let (rays, rest) = rays.as_chunks::<RAY_FLOATS>();
        let n = rays.len();
        let cells = 1i32 << self.depth;
        let cursor = cursor
            .get_mut(..CURSOR_INTS * n)?
            .as_chunks_mut::<CURSOR_INTS>()
            .0;
        let cursor_ok = |c: &[i32; CURSOR_INTS]| {
            c[0] == START || c[0] == DONE || c.iter().all(|x| (0..cells).contains(x))
        };
        if !rest.is_empty()
            || slot.len() != self.voxels
            || blocked.len() < n
            || !cursor.iter().all(cursor_ok)
        {
            return None;
        }
        let mut waiting = Vec::new();
        let mut path: Path = [0; 21];
        for ((ray, flag), at) in rays.iter().zip(blocked.iter_mut()).zip(cursor.iter_mut()) {
            if at[0] == DONE || *flag != 0 {
                at[0] = DONE;
                continue;
            }
            match self.walk_ray(ray, *at, (slot, pool), &mut path, (&mut *stamp, now)) {
                Step::Blocked => {
                    *flag = 1;
                    at[0] = DONE;
                }
                Step::Clear => at[0] = DONE,
                Step::Missing(v, cell) => {
                    waiting.push(v);
                    *at = cell;
                }
            }
        }
        waiting.sort_unstable();
        waiting.dedup();
        for (m, v) in missing.iter_mut().zip(&waiting) {
            *m = *v;
        }
        Some(waiting.len())
    }

    /// One ray's walk from its cursor `at` (not [`DONE`]) through the held voxels (`slot`,
    /// `pool`), stamping each it tests (`stamp`, `now`).
    fn walk_ray(
        &self,
        ray: &[f32; RAY_FLOATS],
        at: [i32; CURSOR_INTS],
        (slot, pool): (&[i32], &[f32]),
        path: &mut Path,
        (stamp, now): (&mut [i32], i32),
    ) -> Step {
        let o = Vec3::new(ray[0], ray[1], ray[2]);
        let d = Vec3::new(ray[3], ray[4], ray[5]);
        let (tmin, tmax) = (ray[6], ray[7]);
        // An empty ray, or one with a NaN bound, is answered at once.
        if tmin.partial_cmp(&tmax) != Some(std::cmp::Ordering::Less) {
            return Step::Clear;
        }
        let Some(mut w) = Walker::start(self, path, o, d, tmin, tmax) else {
            return Step::Clear;
        };
        if at[0] != START {
            let cell = Vec3A::new(at[0] as f32, at[1] as f32, at[2] as f32);
            w.enter(self, path, 0, 0, cell);
        }
        let r = RayQuery::new(o, d, tmin, tmax);
        let mut stop = None;
        // A walk in a well-formed tree crosses at most one leaf per finest-cell face it passes;
        // the bound only keeps a malformed tree from walking for ever.
        let mut budget = 4u64 << self.depth;
        w.run::<ROPES>(self, path, |[voxel, packets], _| {
            budget -= 1;
            if budget == 0 {
                return true;
            }
            let v = voxel as usize;
            let Some(&offset) = slot.get(v) else {
                // An empty leaf (or a voxel number out of range, read as empty).
                return false;
            };
            let held = usize::try_from(offset)
                .ok()
                .and_then(|a| pool.get(a..a.checked_add(voxel_floats(packets as usize))?));
            if held.is_some()
                && let Some(s) = stamp.get_mut(v)
            {
                *s = now;
            }
            match held {
                Some(floats) if blocks(floats, packets as usize, &r) => {
                    stop = Some(None);
                    true
                }
                Some(_) => false,
                None => {
                    stop = Some(Some(voxel as i32));
                    true
                }
            }
        });
        match stop {
            None => Step::Clear,
            Some(None) => Step::Blocked,
            Some(Some(v)) => {
                // The walker is in the leaf of the missing voxel; its low corner is a cell of it.
                let o: UVec3 = w.origin.as_uvec3();
                Step::Missing(v, [o.x as i32, o.y as i32, o.z as i32])
            }
        }
    }
}

/// What one call's walk of a ray found.
enum Step {
    Blocked,
    /// Out of the tree or past `tmax` without a hit.
    Clear,
    /// Stopped at a voxel the node does not hold, in the leaf holding the cell.
    Missing(i32, [i32; CURSOR_INTS]),
}

/// Whether a triangle of the voxel (`floats`, holding `packets` packets) blocks the ray: the
/// octree's test of a leaf (box groups, then the packets whose boxes the ray meets).
#[inline(always)]
fn blocks(floats: &[f32], packets: usize, r: &RayQuery) -> bool {
    let groups = packets.div_ceil(LANES);
    let (boxes, rest) = floats.split_at(groups * BOX_GROUP_FLOATS);
    let (boxes, _) = boxes.as_chunks::<BOX_GROUP_FLOATS>();
    let (packs, _) = rest.as_chunks::<PACKET_FLOATS>();
    for (g, b) in boxes.iter().enumerate() {
        let used = (packets - g * LANES).min(LANES);
        let mut m = read::<BoxGroup, BOX_GROUP_FLOATS>(b).hits(r) & ((1 << used) - 1);
        while m != 0 {
            let lane = m.trailing_zeros() as usize;
            m &= m - 1;
            let p = read::<TriPacket, PACKET_FLOATS>(&packs[g * LANES + lane]);
            if p.intersect(r).0 != 0 {
                return true;
            }
        }
    }
    false
}

/// Reads a box group or packet stored as `N` floats.
#[inline(always)]
fn read<T: Copy, const N: usize>(floats: &[f32; N]) -> T {
    const { assert!(size_of::<T>() == 4 * N) };
    // SAFETY: `T` is a box group or packet, `repr(C)` structs of exactly `N` floats (checked
    // above) in which any bit pattern is valid; the read needs no alignment.
    unsafe { std::ptr::read_unaligned(floats.as_ptr().cast::<T>()) }
}

impl Skeleton for FlatView<'_> {
    #[inline(always)]
    fn lo(&self) -> Vec3 {
        self.lo
    }

    #[inline(always)]
    fn cell(&self) -> f32 {
        self.cell
    }

    #[inline(always)]
    fn depth(&self) -> u32 {
        self.depth
    }

    #[inline(always)]
    fn hot(&self, n: u32) -> [u32; 2] {
        match self.records.get(n as usize + 1) {
            Some(&[first, -1, ..]) if first < 0 => EMPTY_LEAF,
            Some(r) => [r[0] as u32, r[1] as u32],
            None => EMPTY_LEAF,
        }
    }

    #[inline(always)]
    fn neighbour(&self, n: u32, face: usize) -> (u32, u32) {
        match self.records.get(n as usize + 1).map(|r| r[2 + face]) {
            Some(rope) if rope >= 0 && (rope & 31) as u32 <= self.depth => {
                ((rope & 31) as u32, (rope >> 5) as u32)
            }
            _ => (0, 0),
        }
    }
}

#[cfg(test)]
mod test;

/// Floats of a triangle in the naming scheme: corner 0 and the two edges from it, as a
/// packet's lane holds them.
pub const NAMED_TRIANGLE_FLOATS: usize = 9;

/// Most triangles the naming scheme names (a name is a REAL32 holding the index exactly).
pub const MAX_NAMED_TRIANGLES: usize = 1 << 24;

/// The octree's geometry in the naming scheme of the CARM paper's section 3 (programs/
/// README.md, "The naming scheme"): each voxel holds the names of its triangles instead of
/// the triangles, and each triangle is a record of its own.
///
/// A voxel's **name block** (`[]REAL32`): the packet count `p` (a REAL32 holding it exactly),
/// then the voxel's `g = ceil (p / 4)` box groups as in its flat block, then `4 p` names, one a
/// packet lane in lane order: the index of the lane's triangle (exact in a REAL32), or -1 for an
/// unused lane. A **triangle** is [`NAMED_TRIANGLE_FLOATS`] REAL32s: `v0`, `e1`, `e2` (x, y, z
/// each). [`assemble`] makes the flat block back from a name block and its triangles.
#[derive(Clone, Debug)]
pub struct NamedGeometry {
    /// Each voxel's name block, voxel order as [`FlatOctree`]'s.
    pub voxels: Vec<Vec<f32>>,
    /// Each triangle, by name.
    pub triangles: Vec<[f32; NAMED_TRIANGLE_FLOATS]>,
}

impl Octree {
    /// The naming scheme's form of the voxels of `flat` (this octree's flat form): `None` when
    /// the octree names more than [`MAX_NAMED_TRIANGLES`] triangles.
    pub fn named(&self, flat: &FlatOctree) -> Option<NamedGeometry> {
        let mut triangles: Vec<[f32; NAMED_TRIANGLE_FLOATS]> = Vec::new();
        let mut voxels = Vec::with_capacity(flat.voxel_count());
        for &leaf in &flat.leaves {
            let node = self.nodes[leaf];
            let (first, count) = (node.first as usize, node.count as usize);
            let mut block = vec![count as f32];
            for g in &self.boxes[first / LANES..(first + count).div_ceil(LANES)] {
                block.extend(g.sides.iter().flatten().flat_map(|v| v.to_array()));
            }
            for (p, ids) in self.packets[first..first + count]
                .iter()
                .zip(&self.ids[first..first + count])
            {
                for (lane, &id) in ids.iter().enumerate() {
                    if id == NO_TRIANGLE {
                        block.push(-1.0);
                        continue;
                    }
                    let id = id as usize;
                    if id >= MAX_NAMED_TRIANGLES {
                        return None;
                    }
                    if triangles.len() <= id {
                        triangles.resize(id + 1, [0.0; NAMED_TRIANGLE_FLOATS]);
                    }
                    let (v0, e1, e2) = p.lane(lane);
                    for (k, v) in [v0, e1, e2].iter().enumerate() {
                        triangles[id][3 * k..3 * k + 3].copy_from_slice(&v.to_array());
                    }
                    block.push(id as f32);
                }
            }
            voxels.push(block);
        }
        Some(NamedGeometry { voxels, triangles })
    }
}

/// The packets of a name block of `floats` REAL32s (`None` when no packet count fits).
pub fn named_packets(floats: usize) -> Option<usize> {
    let named = |p: usize| 1 + p.div_ceil(LANES) * BOX_GROUP_FLOATS + LANES * p;
    (0..=floats)
        .find(|&p| named(p) >= floats)
        .filter(|&p| named(p) == floats)
}

/// A voxel's flat block made from its name block `named` and `tris`, the triangles it names
/// in name order ([`NAMED_TRIANGLE_FLOATS`] a name; those of unused lanes are not read), into
/// `out`: the number of floats written, [`voxel_floats`] of its packets, or `None` (nothing
/// written) when `named` is not a name block whose packet count its first float gives, `tris`
/// is not one triangle a name or `out` is too short.
pub fn assemble(named: &[f32], tris: &[f32], out: &mut [f32]) -> Option<usize> {
    let packets = named_packets(named.len())?;
    if named.first() != Some(&(packets as f32)) {
        return None;
    }
    let boxes = packets.div_ceil(LANES) * BOX_GROUP_FLOATS;
    let floats = voxel_floats(packets);
    let names = &named[1 + boxes..];
    if tris.len() != NAMED_TRIANGLE_FLOATS * names.len() || out.len() < floats {
        return None;
    }
    out[..boxes].copy_from_slice(&named[1..1 + boxes]);
    for (k, packet) in out[boxes..floats]
        .chunks_exact_mut(PACKET_FLOATS)
        .enumerate()
    {
        for lane in 0..LANES {
            let n = LANES * k + lane;
            let tri = &tris[NAMED_TRIANGLE_FLOATS * n..NAMED_TRIANGLE_FLOATS * (n + 1)];
            // corner 0, edge 1, edge 2 (which), each x, y, z (axis), by lane
            for which in 0..3 {
                for axis in 0..3 {
                    packet[12 * which + LANES * axis + lane] = if names[n] < 0.0 {
                        0.0
                    } else {
                        tri[3 * which + axis]
                    };
                }
            }
        }
    }
    Some(floats)
}
