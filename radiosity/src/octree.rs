//! The octree over patches, flattened after building (pbrt's `flattenBVH` idea): nodes live in
//! one array with the eight children of an interior node contiguous, and each leaf (voxel) embeds
//! the geometry of its triangles in one contiguous run of [`TriPacket`]s (four triangles each,
//! tested at once) behind the boxes of those packets in [`BoxGroup`]s of four, so that a voxel is
//! one block of memory that can be shipped as one message and tested without further look-ups.
//!
//! Traversal walks the voxels a ray crosses in order. Voxels are addressed by integer location
//! codes on the finest grid (`2^depth` cells per axis), which makes neighbour finding exact:
//! - **Samet** (the default): from the current leaf, step across the exit face to the integer cell
//!   just beyond it, climb to the nearest common ancestor (its level is the number of leading bits
//!   the cell shares with the leaf's origin; the node itself is kept on the ray's root-to-leaf
//!   path, so the climb reads no memory), then descend to the leaf holding it.
//! - **Ropes**: Samet's neighbour finding done once per leaf face when the tree is built: each
//!   leaf keeps, for each of its six faces, the neighbour of equal or greater size across it (a
//!   "rope", Havran et al. 1998), so a step follows the rope and descends from there only when
//!   the neighbour is subdivided. No climb, no root-to-leaf path.
//! - **Glassner** (the comparison): the same step, but every descent starts at the root.
//!
//! Invariants:
//! - every triangle that overlaps a leaf's box widened by the octree's margin is stored in that
//!   leaf; neighbouring leaves share their face coordinates exactly (both computed from the same
//!   integer cell), so no point of space lies in no leaf. The margin covers the rounding of the
//!   walk's cell coordinates, so the leaf a walk is in holds every triangle the ray can meet
//!   there, and occlusion answers equal a brute-force test of all triangles;
//! - a node's integer box is `origin .. origin + (1 << (depth - level))` on each axis;
//! - children of node `n` are `nodes[n.first .. n.first + 8]`, ordered by `x | y << 1 | z << 2`.

use glam::{BVec3A, UVec3, Vec3, Vec3A};

use crate::geom::{Tri, ray_triangle};
use crate::packet::{BoxGroup, LANES, NO_TRIANGLE, RayQuery, TriPacket};

pub mod flat;

/// One flattened octree node.
#[derive(Clone, Copy, Debug)]
struct Node {
    origin: UVec3,
    level: u32,
    /// Interior: index of the first of 8 children. Leaf: index of its first packet (a multiple
    /// of [`LANES`]: a leaf's packets are padded to whole box groups).
    first: u32,
    /// Number of packets for a leaf; `INTERIOR` for an interior node.
    count: u32,
}

const INTERIOR: u32 = u32::MAX;

/// Floats a triangle in [`Octree::voxel_floats`]: corner 0, then the two edges from it.
pub const VOXEL_TRI_FLOATS: usize = 9;

/// A leaf face on the boundary of the root box has no neighbour.
const NO_ROPE: u64 = u64::MAX;

/// How the traversal finds the next voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// Samet's neighbour finding: climb to the common ancestor, then descend.
    Samet,
    /// Samet's neighbours precomputed per leaf face (ropes), then a descent where needed.
    Ropes,
    /// Glassner's top-down descent from the root at every step.
    Glassner,
}

impl Traversal {
    /// Every traversal, for comparisons (they all give the same answers).
    pub const ALL: [Traversal; 3] = [Traversal::Samet, Traversal::Ropes, Traversal::Glassner];
}

/// Build settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct OctreeConfig {
    /// A leaf with more triangles than this is split.
    pub max_leaf: usize,
    /// Maximum depth (at most 20).
    pub max_depth: u32,
}

impl Default for OctreeConfig {
    fn default() -> Self {
        // Large leaves: a packet's box test is cheaper than a voxel step, so with 48 triangles
        // (12 packets) a leaf the 10k-triangle Cornell box takes 7.7 steps and 3.4 packet tests
        // per ray, against 14 steps and 3.0 tests with 6 (see BENCHMARKS.md).
        OctreeConfig {
            max_leaf: 48,
            max_depth: 12,
        }
    }
}

/// A flattened octree over triangles. Each lane of a packet remembers the id of its source
/// triangle (its index in the slice given to [`Octree::build`]), or [`NO_TRIANGLE`].
#[derive(Clone, Debug)]
pub struct Octree {
    lo: Vec3,
    cell: f32,
    depth: u32,
    /// How far beyond its box a leaf takes triangles (and its packets' boxes reach): about 16
    /// ulps of the root's coordinates, more than the rounding of the walk's cell coordinates.
    margin: f32,
    nodes: Vec<Node>,
    /// The traversal's copy of `nodes`: `[first, count]` only (8 bytes a node, so the whole tree
    /// stays in cache; origins and levels are recomputed from the cell being sought).
    hot: Vec<[u32; 2]>,
    /// For leaf `n`, `ropes[6 n + face]` is the neighbour of equal or greater size across `face`
    /// (`2 axis + 1` for the face on the high side) as `node << 8 | level`, or [`NO_ROPE`].
    ropes: Vec<u64>,
    packets: Vec<TriPacket>,
    ids: Vec<[u32; LANES]>,
    /// `boxes[g]` holds the boxes of `packets[LANES g .. LANES (g + 1)]`.
    boxes: Vec<BoxGroup>,
}

/// Statistics of a built octree.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct OctreeStats {
    /// All nodes.
    pub nodes: usize,
    /// Leaves (voxels).
    pub leaves: usize,
    /// Triangle references stored in leaves (a triangle overlapping several voxels counts in each).
    pub stored_triangles: usize,
    /// Packets of four lanes holding them.
    pub packets: usize,
    /// Deepest leaf level.
    pub max_level: u32,
}

impl Octree {
    /// Builds the octree over `tris`.
    pub fn build(tris: &[Tri], config: OctreeConfig) -> Octree {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in tris {
            for v in t.v {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if tris.is_empty() {
            (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        }
        let size = (hi - lo).max_element().max(1e-20) * 1.001;
        let pad = size * 0.0005;
        let depth = config.max_depth.min(20);
        let root_lo = lo - Vec3::splat(pad);
        let mut tree = Octree {
            lo: root_lo,
            cell: (size + 2.0 * pad) / (1u32 << depth) as f32,
            depth,
            margin: 1e-6 * (root_lo.abs().max_element() + size + 2.0 * pad),
            nodes: vec![Node {
                origin: UVec3::ZERO,
                level: 0,
                first: 0,
                count: 0,
            }],
            hot: Vec::new(),
            ropes: Vec::new(),
            packets: Vec::new(),
            ids: Vec::new(),
            boxes: Vec::new(),
        };
        let all: Vec<u32> = (0..tris.len() as u32).collect();
        tree.build_node(0, tris, all, config);
        tree.hot = tree.nodes.iter().map(|n| [n.first, n.count]).collect();
        tree.ropes = (0..tree.nodes.len() * 6)
            .map(|i| tree.rope(i / 6, i % 6))
            .collect();
        tree
    }

    /// Returns the world-space box of node `n`.
    fn node_box(&self, n: &Node) -> (Vec3, Vec3) {
        let face = |cell: UVec3| self.lo + cell.as_vec3() * self.cell;
        (
            face(n.origin),
            face(n.origin + (1u32 << (self.depth - n.level))),
        )
    }

    /// Samet's neighbour of leaf `n` across `face` (see [`Octree::ropes`]): the deepest node no
    /// deeper than the leaf whose box holds the cell just across the face.
    fn rope(&self, n: usize, face: usize) -> u64 {
        let node = self.nodes[n];
        if node.count == INTERIOR {
            return NO_ROPE;
        }
        let (axis, high) = (face / 2, face % 2 == 1);
        let size = 1u32 << (self.depth - node.level);
        let mut q = node.origin;
        q[axis] = if high {
            q[axis] + size
        } else {
            q[axis].wrapping_sub(1)
        };
        if q[axis] >= 1 << self.depth {
            return NO_ROPE;
        }
        let mut path = [0u32; 21];
        let (mut level, mut m) = (0, 0);
        while level < node.level && self.nodes[m as usize].count == INTERIOR {
            (level, m) = self.child_towards(&mut path, level, m, q);
        }
        ((m as u64) << 8) | level as u64
    }

    /// Fills node `index` with `members` (split or leaf).
    fn build_node(&mut self, index: usize, tris: &[Tri], members: Vec<u32>, config: OctreeConfig) {
        let node = self.nodes[index];
        if members.len() > config.max_leaf && node.level < self.depth {
            let half = 1u32 << (self.depth - node.level - 1);
            let children: Vec<(UVec3, Vec<u32>)> = (0..8u32)
                .map(|c| {
                    let origin = node.origin + UVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1) * half;
                    let child = Node {
                        origin,
                        level: node.level + 1,
                        first: 0,
                        count: 0,
                    };
                    let (blo, bhi) = self.node_box(&child);
                    let m = Vec3::splat(self.margin);
                    let (blo, bhi) = (blo - m, bhi + m);
                    let inside = members
                        .iter()
                        .copied()
                        .filter(|&i| tri_overlaps_box(&tris[i as usize], blo, bhi))
                        .collect();
                    (origin, inside)
                })
                .collect();
            // A child as full as the parent means its triangles all meet in it (a shared vertex
            // or edge): splitting further gains nothing there and would recurse to max depth.
            if children.iter().all(|(_, m)| m.len() < members.len()) {
                let first = self.nodes.len();
                self.nodes[index].first = first as u32;
                self.nodes[index].count = INTERIOR;
                for (origin, _) in &children {
                    let level = node.level + 1;
                    self.nodes.push(Node {
                        origin: *origin,
                        level,
                        first: 0,
                        count: 0,
                    });
                }
                for (c, (_, inside)) in children.into_iter().enumerate() {
                    self.build_node(first + c, tris, inside, config);
                }
                return;
            }
        }
        self.nodes[index].first = self.packets.len() as u32;
        self.nodes[index].count = members.len().div_ceil(LANES) as u32;
        // Each packet's box is clipped to the leaf widened by the margin (a hit outside it is
        // found in the leaf that holds it) and widened by the margin again, so that the walk's
        // rounding never drops a hit; it stays under the offset that lifts ray origins off
        // their surfaces (1e-3 mm in the Cornell box, where the margin is 5.6e-4 mm).
        let (lo, hi) = self.node_box(&node);
        let margin = self.margin;
        let (lo, hi) = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
        for chunk in members.chunks(LANES) {
            let packet = TriPacket::pack(chunk.iter().map(|&i| &tris[i as usize]));
            let (blo, bhi) = packet.bounds(chunk.len());
            let lane = self.packets.len() % LANES;
            if lane == 0 {
                self.boxes.push(BoxGroup::EMPTY);
            }
            let group = self.boxes.last_mut().expect("a group was pushed");
            group.set_lane(lane, blo.max(lo), bhi.min(hi), margin);
            self.packets.push(packet);
            let mut ids = [NO_TRIANGLE; LANES];
            ids[..chunk.len()].copy_from_slice(chunk);
            self.ids.push(ids);
        }
        while !self.packets.len().is_multiple_of(LANES) {
            self.packets.push(TriPacket::EMPTY);
            self.ids.push([NO_TRIANGLE; LANES]);
        }
    }

    /// Returns statistics of the tree.
    pub fn stats(&self) -> OctreeStats {
        let leaves = self.nodes.iter().filter(|n| n.count != INTERIOR);
        OctreeStats {
            nodes: self.nodes.len(),
            leaves: leaves.clone().count(),
            stored_triangles: self
                .ids
                .iter()
                .flatten()
                .filter(|&&i| i != NO_TRIANGLE)
                .count(),
            packets: self.packets.len(),
            max_level: leaves.map(|n| n.level).max().unwrap_or(0),
        }
    }

    /// Returns the packets embedded in leaf (voxel) `leaf` and their source ids; empty for an
    /// interior node or an index out of range.
    pub fn voxel(&self, leaf: usize) -> (&[TriPacket], &[[u32; LANES]]) {
        match self.nodes.get(leaf) {
            Some(n) if n.count != INTERIOR => {
                let r = n.first as usize..(n.first + n.count) as usize;
                (&self.packets[r.clone()], &self.ids[r])
            }
            _ => (&[], &[]),
        }
    }

    /// The leaves (voxels) that hold triangles, by node index.
    pub fn voxels(&self) -> impl Iterator<Item = usize> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.count != INTERIOR && n.count > 0)
            .map(|(i, _)| i)
    }

    /// The triangles embedded in voxel `leaf` as the flat array a voxel message carries (and
    /// `RAD.VOXEL.OCCLUDED` takes): [`VOXEL_TRI_FLOATS`] a triangle, corner 0 then the edges
    /// to corners 1 and 2, exactly as the voxel stores them, so that a test on this array
    /// answers exactly as the octree does. Empty for an interior node or an index out of range.
    pub fn voxel_floats(&self, leaf: usize) -> Vec<f32> {
        let (packets, ids) = self.voxel(leaf);
        let mut out = Vec::new();
        for (p, ids) in packets.iter().zip(ids) {
            for lane in (0..LANES).filter(|&l| ids[l] != NO_TRIANGLE) {
                let (v0, e1, e2) = p.lane(lane);
                for v in [v0, e1, e2] {
                    out.extend_from_slice(&v.to_array());
                }
            }
        }
        out
    }

    /// Calls `f(packet index)` for each packet of `leaf` (`[first, count]`) whose box the ray
    /// may meet, until `f` returns true; returns whether it did.
    #[inline(always)]
    fn candidates(&self, leaf: [u32; 2], r: &RayQuery, mut f: impl FnMut(usize) -> bool) -> bool {
        let g0 = leaf[0] as usize / LANES;
        for g in g0..g0 + (leaf[1] as usize).div_ceil(LANES) {
            let mut m = self.boxes[g].hits(r);
            while m != 0 {
                let lane = m.trailing_zeros() as usize;
                m &= m - 1;
                if f(g * LANES + lane) {
                    return true;
                }
            }
        }
        false
    }

    /// Returns true when some triangle is hit by `o + t d` with `tmin < t < tmax`.
    pub fn occluded(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32, mode: Traversal) -> bool {
        let r = RayQuery::new(o, d, tmin, tmax);
        let mut hit = false;
        self.walk(o, d, tmin, tmax, mode, |leaf, _| {
            hit = self.candidates(leaf, &r, |i| self.packets[i].intersect(&r).0 != 0);
            hit
        });
        hit
    }

    /// Returns `(leaves visited, box groups tested, packets tested)` for an occlusion query
    /// (for measurements).
    pub fn occlusion_cost(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mode: Traversal,
    ) -> (u32, u32, u32) {
        let r = RayQuery::new(o, d, tmin, tmax);
        let (mut leaves, mut groups, mut tested) = (0, 0, 0);
        self.walk(o, d, tmin, tmax, mode, |leaf, _| {
            leaves += 1;
            groups += leaf[1].div_ceil(LANES as u32);
            self.candidates(leaf, &r, |i| {
                tested += 1;
                self.packets[i].intersect(&r).0 != 0
            })
        });
        (leaves, groups, tested)
    }

    /// Returns the nearest hit `(t, triangle id)` of `o + t d` with `tmin < t < tmax`.
    pub fn first_hit(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mode: Traversal,
    ) -> Option<(f32, u32)> {
        let r = RayQuery::new(o, d, tmin, tmax);
        let mut best: Option<(f32, u32)> = None;
        self.walk(o, d, tmin, tmax, mode, |leaf, t_exit| {
            self.candidates(leaf, &r, |i| {
                let (mut mask, t) = self.packets[i].intersect(&r);
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if best.is_none_or(|b| t[lane] < b.0) {
                        best = Some((t[lane], self.ids[i][lane]));
                    }
                }
                false
            });
            best.is_some_and(|b| b.0 <= t_exit)
        });
        best
    }

    /// Visits the leaves crossed by the ray in order; `visit([first packet, packet count],
    /// t_exit)` returns true to stop.
    #[inline]
    fn walk(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mode: Traversal,
        visit: impl FnMut([u32; 2], f32) -> bool,
    ) {
        let mut path = [0u32; 21];
        let Some(mut w) = Walker::start(self, &mut path, o, d, tmin, tmax) else {
            return;
        };
        // One loop per traversal, so that the step is specialised and the choice is not made
        // again at every voxel.
        match mode {
            Traversal::Samet => w.run::<SAMET>(self, &mut path, visit),
            Traversal::Ropes => w.run::<ROPES>(self, &mut path, visit),
            Traversal::Glassner => w.run::<GLASSNER>(self, &mut path, visit),
        }
    }
}

/// What a walk reads of a tree: the grid (root corner, finest cell, depth), each node's
/// `[first, count]` (`count` is [`INTERIOR`] for an interior node, whose children are
/// `first .. first + 8`) and each leaf face's rope. The octree reads its own arrays; the flat
/// form a node is sent ([`flat`]) reads the arrays it was passed. One walk over both, so that
/// they visit the same leaves with the same arithmetic.
pub(crate) trait Skeleton {
    /// The low corner of the root box.
    fn lo(&self) -> Vec3;
    /// The side of a finest cell.
    fn cell(&self) -> f32;
    /// The depth of the finest grid (`2^depth` cells a side), at most 20.
    fn depth(&self) -> u32;
    /// `[first, count]` of node `n`.
    fn hot(&self, n: u32) -> [u32; 2];
    /// The rope of leaf `n` across `face` (`2 axis + 1` for the high side): the neighbour of
    /// equal or greater size across it, as `(level, node)`.
    fn neighbour(&self, n: u32, face: usize) -> (u32, u32);

    /// Returns the parameter at which the ray enters the root box within `[tmin, tmax]`.
    ///
    /// A zero direction component makes a slab NaN only for an origin on the root box's face;
    /// `min`/`max` then take the other bound, and since the box is padded beyond all geometry,
    /// such a ray (lying in the face) has nothing to hit either way.
    #[inline]
    fn enter(&self, o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        let size = Vec3::splat((1u32 << self.depth()) as f32 * self.cell());
        let a = (self.lo() - o) * inv;
        let b = (self.lo() + size - o) * inv;
        let t_near = a.min(b).max_element().max(tmin);
        let t_far = a.max(b).min_element().min(tmax);
        (t_near <= t_far).then_some(t_near)
    }

    /// Returns the level of the deepest ancestor of the leaf at (`level`, `origin`) whose box
    /// contains cell `q`: the number of leading bits that `q` and `origin` share on every axis.
    #[inline]
    fn common_level(&self, level: u32, origin: UVec3, q: UVec3) -> u32 {
        let diff = (q ^ origin).max_element();
        let shared = diff.leading_zeros().saturating_sub(32 - self.depth());
        shared.min(level)
    }

    /// Descends from node `n` at `level` to the leaf containing cell `q`, recording the nodes
    /// passed in `path`; returns the leaf's level and index.
    #[inline(always)]
    fn descend(&self, path: &mut Path, mut level: u32, mut n: u32, q: UVec3) -> (u32, u32) {
        while level < self.depth() && self.hot(n)[1] == INTERIOR {
            (level, n) = self.child_towards(path, level, n, q);
        }
        (level, n)
    }

    /// Steps from interior node `n` at `level` to its child holding cell `q`, recording it in
    /// `path`.
    #[inline(always)]
    fn child_towards(&self, path: &mut Path, level: u32, n: u32, q: UVec3) -> (u32, u32) {
        let shift = self.depth() - level - 1;
        let b = (q >> shift) & UVec3::ONE;
        let child = self.hot(n)[0] + (b.x | (b.y << 1) | (b.z << 2));
        path[level as usize + 1] = child;
        (level + 1, child)
    }
}

impl Skeleton for Octree {
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
        self.hot[n as usize]
    }

    #[inline(always)]
    fn neighbour(&self, n: u32, face: usize) -> (u32, u32) {
        let rope = self.ropes[6 * n as usize + face];
        ((rope & 255) as u32, (rope >> 8) as u32)
    }
}

/// [`Traversal`]s as const parameters of [`Walker::run`].
const SAMET: u8 = 0;
const ROPES: u8 = 1;
const GLASSNER: u8 = 2;

/// One ray's walk through the leaves, in cell units (the finest grid), where a leaf's faces are
/// integers: `c(t) = oc + dc t`. Cell indices are held as integer-valued `f32`s in SIMD vectors
/// (exact, as the grid has at most 2^20 cells a side; the ray's position in cell units is
/// rounded, which the octree's margin covers), so a step is a handful of vector instructions;
/// integers appear only for the descent.
///
/// The walk keeps `path[l]`, the node at level `l` on the way from the root to the current leaf
/// (outside the walker, so that it is not copied), so that Samet's climb to the common ancestor
/// is a look-up in `path` rather than a chain of parent links through memory.
#[derive(Clone, Copy)]
struct Walker {
    /// Where the ray enters the tree (its parameter) and that point in cell units.
    t0: f32,
    oc: Vec3A,
    dc: Vec3A,
    inv_c: Vec3A,
    /// 1 on the axes along which the ray moves forward, 0 elsewhere.
    forward01: Vec3A,
    forward: BVec3A,
    moving: BVec3A,
    /// Cells a side of the grid.
    cells: f32,
    tmax: f32,
    level: u32,
    /// The current leaf's node index.
    node: u32,
    /// The current leaf's low corner and size, in cells.
    origin: Vec3A,
    size: f32,
    /// The current leaf's `[first packet, packet count]`.
    leaf: [u32; 2],
    /// Where the ray leaves the current leaf.
    t_exit: f32,
    /// The axis of the face it leaves through: the first axis whose face the ray reaches at
    /// `t_exit` (an exit through an edge or corner steps across one face; the next step leaves
    /// at once across the other).
    axis: usize,
}

/// The nodes from the root to the current leaf, by level.
type Path = [u32; 21];

impl Walker {
    /// Positions a walk at the leaf where `o + t d` enters the tree within `[tmin, tmax]`.
    #[inline(always)]
    fn start(
        tree: &impl Skeleton,
        path: &mut Path,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<Walker> {
        let inv = Vec3::ONE / d;
        let t0 = tree.enter(o, inv, tmin, tmax)?;
        // The walk starts from the point where the ray enters, so that cell coordinates are
        // small numbers even for an origin far outside the tree.
        let start = Vec3A::from(o) + Vec3A::from(d) * t0;
        let d = Vec3A::from(d);
        let forward = d.cmpgt(Vec3A::ZERO);
        let mut w = Walker {
            oc: (start - Vec3A::from(tree.lo())) / tree.cell(),
            t0,
            dc: d / tree.cell(),
            inv_c: Vec3A::from(inv) * tree.cell(),
            forward01: Vec3A::select(forward, Vec3A::ONE, Vec3A::ZERO),
            forward,
            moving: d.cmpne(Vec3A::ZERO),
            cells: (1u32 << tree.depth()) as f32,
            tmax,
            level: 0,
            node: 0,
            origin: Vec3A::ZERO,
            size: 0.0,
            leaf: [0, 0],
            t_exit: 0.0,
            axis: 0,
        };
        let q = w.cell_at(t0, Vec3A::ZERO, Vec3A::splat(w.cells - 1.0));
        w.enter(tree, path, 0, 0, q);
        Some(w)
    }

    /// The cell holding the ray's point at `t`, clamped to the cells `lo ..= hi` (before the
    /// truncation, so nothing overflows; truncation is floor, as `lo` is not negative).
    #[inline(always)]
    fn cell_at(&self, t: f32, lo: Vec3A, hi: Vec3A) -> Vec3A {
        trunc((self.oc + self.dc * (t - self.t0)).clamp(lo, hi))
    }

    /// Descends from node `n` at `level` to the leaf holding cell `q` and computes where the
    /// ray leaves it.
    #[inline(always)]
    fn enter(&mut self, tree: &impl Skeleton, path: &mut Path, level: u32, n: u32, q: Vec3A) {
        (self.level, self.node) = tree.descend(path, level, n, q.as_uvec3());
        self.size = (1u32 << (tree.depth() - self.level)) as f32;
        // Exact: the size is a power of two.
        self.origin = trunc(q * (1.0 / self.size)) * self.size;
        self.leaf = tree.hot(self.node);
        let far = self.origin + self.forward01 * self.size;
        let t = Vec3A::select(
            self.moving,
            ((far - self.oc) * self.inv_c).max(Vec3A::ZERO),
            Vec3A::INFINITY,
        );
        let local = t.min_element();
        self.t_exit = self.t0 + local;
        self.axis = t.cmpeq(Vec3A::splat(local)).bitmask().trailing_zeros() as usize;
    }

    /// Visits the leaves from here on; `visit([first packet, packet count], t_exit)` returns
    /// true to stop.
    #[inline(always)]
    fn run<const MODE: u8>(
        &mut self,
        tree: &impl Skeleton,
        path: &mut Path,
        mut visit: impl FnMut([u32; 2], f32) -> bool,
    ) {
        while !visit(self.leaf, self.t_exit) && self.advance::<MODE>(tree, path) {}
    }

    /// Steps to the next leaf along the ray; false when the ray has left the tree or passed
    /// `tmax`.
    #[inline(always)]
    fn advance<const MODE: u8>(&mut self, tree: &impl Skeleton, path: &mut Path) -> bool {
        if self.t_exit >= self.tmax {
            return false;
        }
        let axis = self.axis;
        // The cell just beyond the exit face, clamped to the leaf on the other axes so that
        // it is always a face neighbour; past the root box it ends.
        let across = Vec3A::select(
            self.forward,
            self.origin + self.size,
            self.origin - Vec3A::ONE,
        );
        let inside = self.cell_at(self.t_exit, self.origin, self.origin + (self.size - 1.0));
        let next = Vec3A::select(EXIT[axis], across, inside);
        if (next.cmplt(Vec3A::ZERO) | next.cmpge(Vec3A::splat(self.cells))).any() {
            return false;
        }
        let (level, n) = match MODE {
            SAMET => {
                let level = tree.common_level(self.level, self.origin.as_uvec3(), next.as_uvec3());
                (level, path[level as usize])
            }
            ROPES => {
                let face = 2 * axis + ((self.forward.bitmask() >> axis) & 1) as usize;
                tree.neighbour(self.node, face)
            }
            _ => (0, 0),
        };
        self.enter(tree, path, level, n, next);
        true
    }
}

/// Masks selecting one axis.
const EXIT: [BVec3A; 3] = [
    BVec3A::new(true, false, false),
    BVec3A::new(false, true, false),
    BVec3A::new(false, false, true),
];

/// Truncates non-negative integer-valued-or-not coordinates below 2^31 (two instructions on
/// x86-64, where glam's general `trunc` takes many).
#[inline(always)]
fn trunc(v: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtepi32_ps, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of the x86-64 baseline.
        unsafe { Vec3A::from(_mm_cvtepi32_ps(_mm_cvttps_epi32(v.into()))) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        v.trunc()
    }
}

/// Triangle-box overlap by the separating axis theorem (Akenine-Möller 2001): the box's three
/// axes, the triangle's normal and the nine cross products of box axes and triangle edges. Each
/// test keeps a small relative slack, so a triangle touching the box (or just missing it by
/// rounding) is kept: the octree must be conservative, never the reverse.
fn tri_overlaps_box(t: &Tri, lo: Vec3, hi: Vec3) -> bool {
    let c = (lo + hi) * 0.5;
    let e = (hi - lo) * 0.5;
    let v = t.v.map(|p| p - c);
    let separated = |axis: Vec3| {
        let p = v.map(|p| p.dot(axis));
        let r = e.dot(axis.abs());
        let slack = 1e-5 * (r + p[0].abs().max(p[1].abs()).max(p[2].abs())) + 1e-30;
        p[0].min(p[1]).min(p[2]) > r + slack || p[0].max(p[1]).max(p[2]) < -r - slack
    };
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let box_axes = [Vec3::X, Vec3::Y, Vec3::Z];
    if box_axes.into_iter().any(separated) || separated(edges[0].cross(edges[1])) {
        return false;
    }
    !box_axes
        .iter()
        .flat_map(|a| edges.map(|f| a.cross(f)))
        .any(separated)
}

/// Returns true when any triangle in `tris` is hit with `tmin < t < tmax` (the brute-force
/// oracle for tests).
pub fn occluded_brute_force(tris: &[Tri], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> bool {
    tris.iter().any(|t| {
        ray_triangle(o, d, t.v[0], t.v[1] - t.v[0], t.v[2] - t.v[0])
            .is_some_and(|h| h > tmin && h < tmax)
    })
}

#[cfg(test)]
mod test {
    use super::*;

    const MODES: [Traversal; 3] = Traversal::ALL;

    /// A small triangle at `c` (to set the root's bounds).
    fn speck(c: Vec3) -> Tri {
        Tri::new(c, c + Vec3::X * 0.01, c + Vec3::Y * 0.01)
    }

    /// A wall facing x at `x`, 0.02 wide around `(y, z)`.
    fn wall(x: f32, y: f32, z: f32) -> Tri {
        Tri::new(
            Vec3::new(x, y - 0.01, z - 0.01),
            Vec3::new(x, y + 0.01, z - 0.01),
            Vec3::new(x, y, z + 0.01),
        )
    }

    #[test]
    fn walls_on_and_beside_cell_faces_are_found_by_rays_starting_just_before_them() {
        // A root of 2000 units at depth 12, and walls on and a few ulps either side of faces
        // between two finest cells far from 0. Specks force the walls' cells to split at every
        // level down to those two cells (a staircase: at each level, one speck in the wall's
        // cell but not in the wall's half of it). There the rounding of face coordinates and
        // of the walk's cell coordinates bites; the rays start 4e-5 before their wall.
        let mut tris = vec![speck(Vec3::splat(-1000.0)), speck(Vec3::splat(1000.0))];
        let config = OctreeConfig {
            max_leaf: 1,
            max_depth: 12,
        };
        let probe = Octree::build(&tris, config);
        let (lo, cell) = (probe.lo, probe.cell);
        let mut rays = Vec::new();
        for j in 0..12 {
            let xf = lo.x + (2289 + 2 * j) as f32 * cell;
            for ulps in -6i32..=6 {
                let x = f32::from_bits((xf.to_bits() as i32 + ulps) as u32);
                let (y, z) = (-900.0 + 150.0 * j as f32 + 9.0 * ulps as f32, 26.686157);
                tris.push(wall(x, y, z));
                for level in 0..11 {
                    let size = cell * (1u32 << (12 - level)) as f32;
                    let y0 = lo.y + ((y - lo.y) / size).floor() * size;
                    let other_half = if y - y0 < 0.5 * size { 0.75 } else { 0.25 };
                    tris.push(speck(Vec3::new(xf + 0.5 * cell, y0 + other_half * size, z)));
                }
                tris.push(speck(Vec3::new(xf + 0.5 * cell, y, z)));
                rays.push((Vec3::new(x - 4e-5, y, z), Vec3::X));
            }
        }
        let tree = Octree::build(&tris, config);
        assert_eq!((tree.lo, tree.cell), (lo, cell));
        assert_eq!(tree.stats().max_level, 12);
        for (o, d) in rays {
            let expected = occluded_brute_force(&tris, o, d, 0.0, 1e-3);
            assert!(expected, "the ray at {o} meets its wall");
            for mode in MODES {
                assert_eq!(
                    tree.occluded(o, d, 0.0, 1e-3, mode),
                    expected,
                    "{mode:?} {o}"
                );
            }
        }
    }

    #[test]
    fn rays_from_far_outside_the_tree_find_what_they_meet() {
        let tris = vec![
            speck(Vec3::splat(-1.0)),
            speck(Vec3::splat(1.0)),
            wall(0.25, 0.3, 0.3),
        ];
        let tree = Octree::build(&tris, OctreeConfig::default());
        for far in [1e3f32, 1e5, 1e7] {
            let o = Vec3::new(-far, 0.3, 0.3);
            let d = Vec3::X * (2.0 * far);
            let expected = occluded_brute_force(&tris, o, d, 0.0, 1.0);
            for mode in MODES {
                assert_eq!(
                    tree.occluded(o, d, 0.0, 1.0, mode),
                    expected,
                    "{mode:?} {far}"
                );
            }
        }
    }
}
