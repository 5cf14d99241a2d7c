//! The octree over patches, flattened after building (pbrt's `flattenBVH` idea): nodes live in
//! one array with the eight children of an interior node contiguous, and each leaf (voxel) embeds
//! the geometry of its triangles in one contiguous run of [`PackedTri`]s, so that a voxel is one
//! block of memory that can be shipped as one message and tested without further look-ups.
//!
//! Traversal walks the voxels a ray crosses in order. Voxels are addressed by integer location
//! codes on the finest grid (`2^depth` cells per axis), which makes neighbour finding exact:
//! - **Samet** (the default): from the current leaf, step across the exit face to the integer cell
//!   just beyond it, climb to the nearest common ancestor (its level is the number of leading bits
//!   the cell shares with the leaf's origin; the node itself is kept on the ray's root-to-leaf
//!   path, so the climb reads no memory), then descend to the leaf holding it.
//! - **Glassner** (the comparison): the same step, but every descent starts at the root.
//!
//! Invariants:
//! - every triangle that overlaps a leaf's box is stored in that leaf (conservative, so occlusion
//!   answers equal a brute-force test of all triangles);
//! - a node's integer box is `origin .. origin + (1 << (depth - level))` on each axis;
//! - children of node `n` are `nodes[n.first .. n.first + 8]`, ordered by `x | y << 1 | z << 2`.

use glam::{UVec3, Vec3};

use crate::geom::{Tri, ray_triangle};

/// A triangle as a voxel stores it: one corner and the two edges from it (36 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackedTri {
    /// Corner 0.
    pub v0: Vec3,
    /// Corner 1 minus corner 0.
    pub e1: Vec3,
    /// Corner 2 minus corner 0.
    pub e2: Vec3,
}

/// One flattened octree node.
#[derive(Clone, Copy, Debug)]
struct Node {
    origin: UVec3,
    level: u32,
    /// Interior: index of the first of 8 children. Leaf: index of the first packed triangle.
    first: u32,
    /// Number of triangles for a leaf; `INTERIOR` for an interior node.
    count: u32,
}

const INTERIOR: u32 = u32::MAX;

/// How the traversal finds the next voxel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// Samet's neighbour finding: climb to the common ancestor, then descend.
    Samet,
    /// Glassner's top-down descent from the root at every step.
    Glassner,
}

/// Build settings.
#[derive(Clone, Copy, Debug)]
pub struct OctreeConfig {
    /// A leaf with more triangles than this is split.
    pub max_leaf: usize,
    /// Maximum depth (at most 20).
    pub max_depth: u32,
}

impl Default for OctreeConfig {
    fn default() -> Self {
        OctreeConfig {
            max_leaf: 6,
            max_depth: 12,
        }
    }
}

/// A flattened octree over triangles. Each packed triangle remembers the id of its source
/// triangle (its index in the slice given to [`Octree::build`]).
#[derive(Clone, Debug)]
pub struct Octree {
    lo: Vec3,
    cell: f32,
    depth: u32,
    nodes: Vec<Node>,
    /// The traversal's copy of `nodes`: `[first, count]` only (8 bytes a node, so the whole tree
    /// stays in cache; origins and levels are recomputed from the cell being sought).
    hot: Vec<[u32; 2]>,
    tris: Vec<PackedTri>,
    ids: Vec<u32>,
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
        let mut tree = Octree {
            lo: lo - Vec3::splat(pad),
            cell: (size + 2.0 * pad) / (1u32 << depth) as f32,
            depth,
            nodes: vec![Node {
                origin: UVec3::ZERO,
                level: 0,
                first: 0,
                count: 0,
            }],
            hot: Vec::new(),
            tris: Vec::new(),
            ids: Vec::new(),
        };
        let all: Vec<u32> = (0..tris.len() as u32).collect();
        tree.build_node(0, tris, all, config);
        tree.hot = tree.nodes.iter().map(|n| [n.first, n.count]).collect();
        tree
    }

    /// Returns the world-space box of node `n`.
    fn node_box(&self, n: &Node) -> (Vec3, Vec3) {
        let size = (1u32 << (self.depth - n.level)) as f32 * self.cell;
        let lo = self.lo + n.origin.as_vec3() * self.cell;
        (lo, lo + Vec3::splat(size))
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
        self.nodes[index].first = self.tris.len() as u32;
        self.nodes[index].count = members.len() as u32;
        for i in members {
            let t = &tris[i as usize];
            self.tris.push(PackedTri {
                v0: t.v[0],
                e1: t.v[1] - t.v[0],
                e2: t.v[2] - t.v[0],
            });
            self.ids.push(i);
        }
    }

    /// Returns statistics of the tree.
    pub fn stats(&self) -> OctreeStats {
        let leaves = self.nodes.iter().filter(|n| n.count != INTERIOR);
        OctreeStats {
            nodes: self.nodes.len(),
            leaves: leaves.clone().count(),
            stored_triangles: self.tris.len(),
            max_level: leaves.map(|n| n.level).max().unwrap_or(0),
        }
    }

    /// Returns the triangles embedded in leaf (voxel) `leaf` and their source ids; empty for an
    /// interior node or an index out of range.
    pub fn voxel(&self, leaf: usize) -> (&[PackedTri], &[u32]) {
        match self.nodes.get(leaf) {
            Some(n) if n.count != INTERIOR => {
                let r = n.first as usize..(n.first + n.count) as usize;
                (&self.tris[r.clone()], &self.ids[r])
            }
            _ => (&[], &[]),
        }
    }

    /// Returns true when some triangle is hit by `o + t d` with `tmin < t < tmax`.
    pub fn occluded(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32, mode: Traversal) -> bool {
        let mut hit = false;
        let mut mailbox = Mailbox::default();
        self.walk(o, d, tmin, tmax, mode, |tris, ids, _| {
            hit = tris.iter().zip(ids).any(|(t, &id)| {
                mailbox.first_visit(id)
                    && ray_triangle(o, d, t.v0, t.e1, t.e2).is_some_and(|h| h > tmin && h < tmax)
            });
            hit
        });
        hit
    }

    /// Returns `(leaves visited, triangles tested)` for an occlusion query (for measurements);
    /// a triangle skipped by the mailbox is not counted as tested.
    pub fn occlusion_cost(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mode: Traversal,
    ) -> (u32, u32) {
        let (mut leaves, mut tested) = (0, 0);
        let mut mailbox = Mailbox::default();
        self.walk(o, d, tmin, tmax, mode, |tris, ids, _| {
            leaves += 1;
            tris.iter().zip(ids).any(|(t, &id)| {
                let fresh = mailbox.first_visit(id);
                tested += fresh as u32;
                fresh && ray_triangle(o, d, t.v0, t.e1, t.e2).is_some_and(|h| h > tmin && h < tmax)
            })
        });
        (leaves, tested)
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
        let mut best: Option<(f32, u32)> = None;
        let mut mailbox = Mailbox::default();
        self.walk(o, d, tmin, tmax, mode, |tris, ids, t_exit| {
            for (t, &id) in tris.iter().zip(ids) {
                if mailbox.first_visit(id)
                    && let Some(h) = ray_triangle(o, d, t.v0, t.e1, t.e2)
                    && h > tmin
                    && h < tmax
                    && best.is_none_or(|b| h < b.0)
                {
                    best = Some((h, id));
                }
            }
            best.is_some_and(|b| b.0 <= t_exit)
        });
        best
    }

    /// Visits the leaves crossed by the ray in order; `visit(tris, ids, t_exit)` returns true to stop.
    ///
    /// `path[l]` is the node at level `l` on the way from the root to the current leaf, so that
    /// Samet's climb to the common ancestor is a look-up in `path` rather than a chain of
    /// parent links through memory.
    #[inline]
    fn walk(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        mode: Traversal,
        mut visit: impl FnMut(&[PackedTri], &[u32], f32) -> bool,
    ) {
        let inv = Vec3::ONE / d;
        let Some(t0) = self.enter(o, inv, tmin, tmax) else {
            return;
        };
        let n_cells = 1u32 << self.depth;
        let to_cell = |t: f32| ((o + d * t - self.lo) / self.cell).max(Vec3::ZERO);
        // Truncation equals floor here: the coordinates are clamped to be non-negative.
        let q = to_cell(t0).as_uvec3().min(UVec3::splat(n_cells - 1));
        let mut path = [0u32; 21];
        let mut level = self.descend(&mut path, 0, q);
        let mut origin = q & UVec3::splat(!((1u32 << (self.depth - level)) - 1));
        loop {
            let [first, count] = self.hot[path[level as usize] as usize];
            let r = first as usize..(first + count) as usize;
            let size = 1u32 << (self.depth - level);
            let blo = self.lo + origin.as_vec3() * self.cell;
            let bhi = blo + Vec3::splat(size as f32 * self.cell);
            let far = Vec3::select(d.cmpgt(Vec3::ZERO), bhi, blo);
            let texit = ((far - o) * inv).abs_nan_to_inf();
            let (t_exit, axis) = min_axis(texit);
            if visit(&self.tris[r.clone()], &self.ids[r], t_exit) || t_exit >= tmax {
                return;
            }
            let Some(next) = self.exit_cell(to_cell(t_exit), d, axis, origin, size) else {
                return;
            };
            let start = match mode {
                Traversal::Glassner => 0,
                Traversal::Samet => self.common_level(level, origin, next),
            };
            level = self.descend(&mut path, start, next);
            origin = next & UVec3::splat(!((1u32 << (self.depth - level)) - 1));
        }
    }

    /// Returns the integer cell just beyond the exit face on `axis` of the leaf at `origin`
    /// (`size` cells wide), clamped to the leaf on the other axes; `None` past the root box.
    /// `pe` is the exit point in (non-negative) cell coordinates.
    #[inline]
    fn exit_cell(&self, pe: Vec3, d: Vec3, axis: usize, origin: UVec3, size: u32) -> Option<UVec3> {
        let n_cells = 1u32 << self.depth;
        let mut next = UVec3::ZERO;
        for a in 0..3 {
            let (lo_a, hi_a) = (origin[a], origin[a] + size - 1);
            next[a] = if a != axis {
                (pe[a] as u32).clamp(lo_a, hi_a)
            } else if d[a] > 0.0 {
                (hi_a + 1 < n_cells).then_some(hi_a + 1)?
            } else {
                lo_a.checked_sub(1)?
            };
        }
        Some(next)
    }

    /// Returns the parameter at which the ray enters the root box within `[tmin, tmax]`.
    fn enter(&self, o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        let (blo, bhi) = self.node_box(&self.nodes[0]);
        let a = (blo - o) * inv;
        let b = (bhi - o) * inv;
        let t_near = a.min(b).max_element_nan_safe().max(tmin);
        let t_far = a.max(b).min_element_nan_safe().min(tmax);
        (t_near <= t_far).then_some(t_near)
    }

    /// Returns the level of the deepest ancestor of the leaf at (`level`, `origin`) whose box
    /// contains cell `q`: the number of leading bits that `q` and `origin` share on every axis.
    #[inline]
    fn common_level(&self, level: u32, origin: UVec3, q: UVec3) -> u32 {
        let diff = (q ^ origin).max_element();
        let shared = diff.leading_zeros().saturating_sub(32 - self.depth);
        shared.min(level)
    }

    /// Descends from the node `path[level]` to the leaf containing cell `q`, recording the nodes
    /// passed in `path`; returns the leaf's level.
    #[inline]
    fn descend(&self, path: &mut [u32; 21], mut level: u32, q: UVec3) -> u32 {
        let mut n = path[level as usize];
        loop {
            let [first, count] = self.hot[n as usize];
            if count != INTERIOR {
                return level;
            }
            let shift = self.depth - level - 1;
            let b = (q >> shift) & UVec3::ONE;
            n = first + (b.x | (b.y << 1) | (b.z << 2));
            level += 1;
            path[level as usize] = n;
        }
    }
}

/// The ids of the last few triangles a ray was tested against (mailboxing): a triangle lying
/// in several voxels along the ray gives the same answer each time, so it is tested once.
/// A ring of 8 misses some repeats but needs no per-triangle state, so queries stay shareable.
#[derive(Clone, Copy)]
struct Mailbox {
    ids: [u32; 8],
    next: usize,
}

impl Default for Mailbox {
    fn default() -> Self {
        Mailbox {
            ids: [u32::MAX; 8],
            next: 0,
        }
    }
}

impl Mailbox {
    /// Returns false when `id` was seen recently; otherwise records it and returns true.
    #[inline]
    fn first_visit(&mut self, id: u32) -> bool {
        if self.ids.contains(&id) {
            return false;
        }
        self.ids[self.next & 7] = id;
        self.next += 1;
        true
    }
}

/// NaN-tolerant min/max element helpers (a zero direction component gives NaN or inf slabs).
trait NanSafe {
    fn max_element_nan_safe(self) -> f32;
    fn min_element_nan_safe(self) -> f32;
    fn abs_nan_to_inf(self) -> Vec3;
}

impl NanSafe for Vec3 {
    fn max_element_nan_safe(self) -> f32 {
        self.to_array()
            .into_iter()
            .filter(|x| !x.is_nan())
            .fold(f32::NEG_INFINITY, f32::max)
    }
    fn min_element_nan_safe(self) -> f32 {
        self.to_array()
            .into_iter()
            .filter(|x| !x.is_nan())
            .fold(f32::INFINITY, f32::min)
    }
    fn abs_nan_to_inf(self) -> Vec3 {
        Vec3::from_array(self.to_array().map(|x| {
            if x.is_nan() || x < 0.0 {
                f32::INFINITY
            } else {
                x
            }
        }))
    }
}

/// Returns the smallest component and its axis.
#[inline]
fn min_axis(v: Vec3) -> (f32, usize) {
    if v.x <= v.y && v.x <= v.z {
        (v.x, 0)
    } else if v.y <= v.z {
        (v.y, 1)
    } else {
        (v.z, 2)
    }
}

/// Conservative triangle-box overlap: bounding boxes overlap and the triangle's plane crosses
/// the box.
fn tri_overlaps_box(t: &Tri, lo: Vec3, hi: Vec3) -> bool {
    let tlo = t.v[0].min(t.v[1]).min(t.v[2]);
    let thi = t.v[0].max(t.v[1]).max(t.v[2]);
    if tlo.cmpgt(hi).any() || thi.cmplt(lo).any() {
        return false;
    }
    let n = t.cross();
    let c = (lo + hi) * 0.5;
    let e = (hi - lo) * 0.5;
    let r = e.dot(n.abs());
    n.dot(c - t.v[0]).abs() <= r * 1.0001 + 1e-12
}

/// Returns true when any triangle in `tris` is hit with `tmin < t < tmax` (the brute-force
/// oracle for tests).
pub fn occluded_brute_force(tris: &[Tri], o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> bool {
    tris.iter().any(|t| {
        ray_triangle(o, d, t.v[0], t.v[1] - t.v[0], t.v[2] - t.v[0])
            .is_some_and(|h| h > tmin && h < tmax)
    })
}
