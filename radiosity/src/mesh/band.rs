//! A row of sample points beside concave creases and contact lines, where two surfaces face
//! each other across a common line (a floor meeting a wall, a box standing on the floor, a
//! table leg meeting the underside of the table top).
//!
//! Beside such a line the irradiance is a corner's profile: it changes fastest where the
//! surfaces meet and flattens away from it, so the interpolant between the points on the line
//! and the next row understates the elements there. Adaptive subdivision reaches these spans
//! only where one shot lights them strongly: the legs of a table, lit only by many weak shots
//! of the floor and walls, read 2-3% low at the foot while their sample points were right
//! (radiosity/REFERENCES.md, "The table's legs"). Halving, before the solve, the edges that
//! leave such a line puts a row of points halfway to the next, whatever the shots.

use glam::Vec3;
use rustc_hash::FxHashMap;
use smallvec::SmallVec;

use super::{Mesh, edge_key};

/// A point's position as a key: the points of a crease, split one per side, share it exactly.
fn key(p: Vec3) -> [u32; 3] {
    p.to_array().map(f32::to_bits)
}

impl Mesh {
    /// Bisects, once, every edge longer than `max_edge` that leaves a crease from an element
    /// along a concave crease or a contact line ([`Mesh::at_concave_crease`]): one end on a
    /// crease (another surface has a point there), the other off every crease. Then sets the
    /// evaluation points again. Returns the sample points added (also counted in
    /// [`super::MeshStats::crease_band_points`]).
    pub fn band_concave_creases(&mut self, max_edge: f32) -> usize {
        let banded = self.at_concave_crease();
        let mut at: FxHashMap<[u32; 3], u32> = FxHashMap::default();
        for v in &self.vertices {
            *at.entry(key(v.pos)).or_default() += 1;
        }
        let on_crease: Vec<bool> = (self.vertices.iter())
            .map(|v| at[&key(v.pos)] > 1)
            .collect();
        let mut edges: Vec<(u32, u32)> = Vec::new();
        for (e, _) in (self.elements.iter()).zip(&banded).filter(|(_, b)| **b) {
            for k in 0..3 {
                let (a, b) = (e.v[k], e.v[(k + 1) % 3]);
                let leaves = on_crease[a as usize] != on_crease[b as usize];
                if leaves && (self.pos(a) - self.pos(b)).length() > max_edge {
                    edges.push(edge_key(a, b));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let before = self.vertices.len();
        for (a, b) in edges {
            // (each edge is listed once, and splitting one leaves the others whole)
            let m = self.add_edge_vertex(a, b, (self.pos(a) + self.pos(b)) * 0.5);
            self.split_edge(a, b, m);
        }
        self.set_eval_points();
        let added = self.vertices.len() - before;
        self.stats.crease_band_points += added;
        self.stats.elements = self.elements.len();
        self.stats.vertices = self.vertices.len();
        added
    }

    /// Per element, whether it meets another surface at a concave crease or a contact line: a
    /// corner of it lies where a corner of another surface's element lies (a point of the line,
    /// split one per side), and each of the two elements lies in front of the other's plane.
    /// Elements with a hidden corner, and hidden partners, do not count.
    pub fn at_concave_crease(&self) -> Vec<bool> {
        let planes: Vec<(Vec3, Vec3)> = (self.elements.iter())
            .map(|e| {
                let t = self.tri(e);
                (t.normal(), t.centroid())
            })
            .collect();
        let shown =
            |e: usize| (self.elements[e].v.iter()).all(|&v| !self.vertices[v as usize].hidden());
        let mut around: Vec<SmallVec<[u32; 6]>> = vec![SmallVec::new(); self.vertices.len()];
        for (i, e) in self.elements.iter().enumerate() {
            for &v in &e.v {
                around[v as usize].push(i as u32);
            }
        }
        let mut at: FxHashMap<[u32; 3], SmallVec<[u32; 4]>> = FxHashMap::default();
        for (v, vertex) in self.vertices.iter().enumerate() {
            if !around[v].is_empty() {
                at.entry(key(vertex.pos)).or_default().push(v as u32);
            }
        }
        // Whether elements `e` and `f` face each other across their common point `p`.
        let facing = |e: usize, f: usize, p: Vec3| {
            let ((ne, ce), (nf, cf)) = (planes[e], planes[f]);
            let ahead = |n: Vec3, c: Vec3| n.dot(c - p) > 1e-3 * (c - p).length();
            ahead(nf, ce) && ahead(ne, cf)
        };
        (0..self.elements.len())
            .map(|e| {
                shown(e)
                    && self.elements[e].v.iter().any(|&v| {
                        let p = self.vertices[v as usize].pos;
                        (at[&key(p)].iter().filter(|&&w| w != v)).any(|&w| {
                            (around[w as usize].iter())
                                .any(|&f| shown(f as usize) && facing(e, f as usize, p))
                        })
                    })
            })
            .collect()
    }
}
