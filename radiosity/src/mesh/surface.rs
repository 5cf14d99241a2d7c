//! After cutting, on the mesh of elements: regions enclosed by contact are hidden (the floor
//! under a block), and sample points on discontinuity lines are split, one per side, so that
//! each side is evaluated just inside itself (a floor point on a block's base line must not
//! see the block's face edge-on, nor share its value with the footprint).

use glam::Vec3;
use rustc_hash::FxHashMap;

use super::piece::Tags;
use super::{Mesh, edge_key};

/// The discontinuity tags of element edges, by edge key.
pub type EdgeTags = FxHashMap<(u32, u32), Tags>;

/// Union-find over `0..n`.
struct Sets(Vec<u32>);

impl Sets {
    fn new(n: usize) -> Sets {
        Sets((0..n as u32).collect())
    }

    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let up = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = up;
            x = up;
        }
        x
    }

    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
    }
}

/// Whether edge `key` joins its two elements into one smooth region: exactly two elements
/// share it and it lies on no discontinuity.
fn smooth(mesh: &Mesh, tags: &EdgeTags, key: (u32, u32)) -> bool {
    mesh.elements_on_edge(key.0, key.1).len() == 2 && !tags.contains_key(&key)
}

/// Marks hidden the regions enclosed by contact: a region of elements joined by smooth edges
/// is enclosed when each of its boundary edges has a surface standing on it with the region
/// behind (a block's faces around its footprint), not merely the edge of the surface. Returns
/// the elements newly hidden.
pub fn hide_enclosed(mesh: &Mesh, tags: &EdgeTags, hidden: &mut [bool]) -> usize {
    let n = mesh.elements.len();
    let mut sets = Sets::new(n);
    for (&key, around) in &mesh.edges {
        if around.len() == 2 && !tags.contains_key(&key) {
            sets.union(around[0], around[1]);
        }
    }
    let mut open = vec![false; n];
    for (i, e) in mesh.elements.iter().enumerate() {
        let centre = mesh.tri(e).centroid();
        for k in 0..3 {
            let key = edge_key(e.v[k], e.v[(k + 1) % 3]);
            if smooth(mesh, tags, key) {
                continue;
            }
            let mid = (mesh.pos(key.0) + mesh.pos(key.1)) * 0.5;
            let behind = tags.get(&key).is_some_and(|t| {
                t.iter()
                    .any(|w| w.wall != Vec3::ZERO && w.wall.dot(centre - mid) < 0.0)
            });
            if !behind {
                let root = sets.find(i as u32);
                open[root as usize] = true;
            }
        }
    }
    let mut count = 0;
    for (i, h) in hidden.iter_mut().enumerate() {
        let root = sets.find(i as u32);
        if !open[root as usize] && !*h {
            *h = true;
            count += 1;
        }
    }
    count
}

/// Splits sample points along discontinuities and between hidden and visible elements: the
/// corners of elements that meet across a smooth edge (and are both hidden or both visible)
/// share a point, others get a copy of their own. Hidden copies get a zero normal, which the
/// form factor kernel reads as "receives nothing". Then drops the vertices no element uses and
/// rebuilds the edge map. Returns the copies made.
pub fn split_points(mesh: &mut Mesh, tags: &EdgeTags, hidden: &[bool]) -> usize {
    let n = mesh.elements.len();
    let mut sets = Sets::new(3 * n);
    let corner = |mesh: &Mesh, e: u32, v: u32| {
        let k = mesh.elements[e as usize].v.iter().position(|&x| x == v);
        3 * e + k.unwrap_or(0) as u32
    };
    for (&key, around) in &mesh.edges {
        if around.len() != 2 || tags.contains_key(&key) {
            continue;
        }
        let (e, f) = (around[0], around[1]);
        if hidden[e as usize] != hidden[f as usize] {
            continue;
        }
        for v in [key.0, key.1] {
            sets.union(corner(mesh, e, v), corner(mesh, f, v));
        }
    }
    // The first class met for a vertex keeps it; later classes get copies.
    let mut copy_of_class: FxHashMap<u32, u32> = FxHashMap::default();
    let mut owner = vec![u32::MAX; mesh.vertices.len()];
    let mut copies = 0;
    for e in 0..n {
        for k in 0..3 {
            let v = mesh.elements[e].v[k];
            let class = sets.find((3 * e + k) as u32);
            let id = if owner[v as usize] == u32::MAX {
                owner[v as usize] = class;
                copy_of_class.insert(class, v);
                v
            } else if let Some(&c) = copy_of_class.get(&class) {
                c
            } else {
                mesh.vertices.push(mesh.vertices[v as usize]);
                let c = mesh.vertices.len() as u32 - 1;
                copy_of_class.insert(class, c);
                copies += 1;
                c
            };
            mesh.elements[e].v[k] = id;
        }
    }
    for (e, _) in hidden.iter().enumerate().filter(|h| *h.1) {
        for v in mesh.elements[e].v {
            mesh.vertices[v as usize].normal = Vec3::ZERO;
        }
    }
    mesh.drop_unused_vertices();
    copies
}
