//! The conforming triangle mesh the solver works on: sample points (vertices), elements
//! (triangles) and patches (the source polygons that shoot).
//!
//! Vertices are shared between triangles of the same surface, found by position and normal, so a
//! sample point on an edge between two patches of one wall is one point. Every refinement is an
//! edge split ([`Mesh::split_edge`]) applied to *all* triangles around the edge, so the mesh
//! stays conforming (no T-junctions) and new sample points re-triangulate their neighbourhood.
//!
//! Meshing pipeline ([`Mesh::from_scene`]):
//! 1. weld vertices by position and normal;
//! 2. D0 discontinuities: T-junctions (a vertex on another coplanar triangle's edge) and the lines
//!    where triangles of different planes intersect or abut are split, so no triangle straddles one;
//! 3. patches: longest-edge bisection until every edge is at most `patch_size`;
//! 4. elements: further bisection to at most `element_size`; each element remembers its patch.

use std::collections::{BinaryHeap, HashMap};

use glam::Vec3;

use crate::geom::{Tri, plane_cut_segment};
use crate::grid::BoxGrid;
use crate::scene::Scene;

/// A sample point: where radiosity is computed and stored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// Position on the surface.
    pub pos: Vec3,
    /// Unit surface normal.
    pub normal: Vec3,
    /// Where form factors are evaluated: `pos`, moved slightly inside the surface for vertices on
    /// a surface boundary (exactly on an edge a neighbouring wall is seen edge-on).
    pub eval: Vec3,
}

/// A mesh triangle (an element, or a patch before element subdivision).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Vertex indices, counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Scene object.
    pub object: u32,
    /// Patch the element belongs to.
    pub patch: u32,
}

/// Meshing settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshConfig {
    /// Longest patch (shooter) edge, in scene units.
    pub patch_size: f32,
    /// Longest element edge, in scene units.
    pub element_size: f32,
}

impl MeshConfig {
    /// About how many elements meshing `scene` with these sizes makes: each triangle's area over
    /// that of an equilateral element of the element size, or its edge count along the longest
    /// edge for slivers, whichever is more (longest-edge bisection halves edges until they are
    /// short enough). Callers use it to refuse sizes that would not fit in memory.
    pub fn estimated_elements(&self, scene: &Scene) -> f64 {
        let e = f64::from(self.element_size.min(self.patch_size)).max(1e-30);
        scene
            .triangles
            .iter()
            .map(|t| {
                let by_area = f64::from(t.tri.area()) / (0.433 * e * e);
                let by_edge = f64::from(t.tri.longest_edge().0) / e;
                by_area.max(by_edge).max(1.0)
            })
            .sum()
    }
}

/// Counts of what meshing did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshStats {
    /// Triangles after welding (the scene's).
    pub input_triangles: usize,
    /// Scene triangles dropped because welding merged two of their corners: features smaller
    /// than the weld distance (1e-5 of the scene's diagonal), as in a scene that spans many
    /// orders of magnitude.
    pub collapsed: usize,
    /// Edge splits at T-junctions.
    pub t_junction_splits: usize,
    /// Edge splits along intersection / abutting lines between surfaces.
    pub d0_splits: usize,
    /// Patches.
    pub patches: usize,
    /// Elements.
    pub elements: usize,
    /// Sample points (vertices).
    pub vertices: usize,
}

/// The mesh.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Sample points.
    pub vertices: Vec<Vertex>,
    /// Elements.
    pub elements: Vec<Element>,
    /// Patch geometry (shooters), indexed by [`Element::patch`].
    pub patches: Vec<Tri>,
    /// Object of each patch.
    pub patch_object: Vec<u32>,
    edges: HashMap<(u32, u32), Vec<u32>>,
    /// What meshing did.
    pub stats: MeshStats,
}

/// An `f32` ordered for the heap (lengths are finite).
#[derive(Clone, Copy, PartialEq)]
struct OrdF32(f32);
impl Eq for OrdF32 {}
impl Ord for OrdF32 {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}
impl PartialOrd for OrdF32 {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

impl Mesh {
    /// Meshes a scene (see the module doc for the steps).
    pub fn from_scene(scene: &Scene, config: MeshConfig) -> Mesh {
        Mesh::build(scene, config, Search::Grid)
    }

    fn build(scene: &Scene, config: MeshConfig, search: Search) -> Mesh {
        let eps = 1e-5 * scene.diagonal().max(1e-30);
        let mut mesh = Mesh::welded(scene, eps);
        mesh.stats.input_triangles = mesh.elements.len();
        mesh.stats.t_junction_splits = mesh.split_t_junctions(eps, search);
        mesh.stats.d0_splits = mesh.split_d0(eps, search);
        mesh.stats.t_junction_splits += mesh.split_t_junctions(eps, search);
        mesh.subdivide(config.patch_size.max(eps * 10.0));
        mesh.patches = mesh.elements.iter().map(|e| mesh.tri(e)).collect();
        mesh.patch_object = mesh.elements.iter().map(|e| e.object).collect();
        for (i, e) in mesh.elements.iter_mut().enumerate() {
            e.patch = i as u32;
        }
        mesh.subdivide(config.element_size.max(eps * 10.0));
        mesh.set_eval_points();
        mesh.stats.patches = mesh.patches.len();
        mesh.stats.elements = mesh.elements.len();
        mesh.stats.vertices = mesh.vertices.len();
        mesh
    }

    /// Returns the geometry of an element.
    pub fn tri(&self, e: &Element) -> Tri {
        Tri::new(self.pos(e.v[0]), self.pos(e.v[1]), self.pos(e.v[2]))
    }

    fn pos(&self, v: u32) -> Vec3 {
        self.vertices[v as usize].pos
    }

    /// Welds scene triangles into shared vertices (same position within `eps`, normals within
    /// about 2.5 degrees).
    fn welded(scene: &Scene, eps: f32) -> Mesh {
        let mut mesh = Mesh::default();
        let mut index: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for st in &scene.triangles {
            let n = st.tri.normal();
            let v = st.tri.v.map(|p| {
                let key = (p / (eps * 4.0)).round().as_i64vec3().to_array();
                let bucket = index.entry(key).or_default();
                let found = bucket
                    .iter()
                    .copied()
                    .find(|&i| mesh.vertices[i as usize].normal.dot(n) > 0.999);
                found.unwrap_or_else(|| {
                    mesh.vertices.push(Vertex {
                        pos: p,
                        normal: n,
                        eval: p,
                    });
                    bucket.push(mesh.vertices.len() as u32 - 1);
                    mesh.vertices.len() as u32 - 1
                })
            });
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                mesh.stats.collapsed += 1;
                continue;
            }
            mesh.push_element(Element {
                v,
                object: st.object,
                patch: 0,
            });
        }
        if mesh.stats.collapsed > 0 {
            mesh.drop_unused_vertices();
        }
        mesh
    }

    /// Removes the vertices no element uses (left by triangles that welding collapsed) and
    /// renumbers the rest in order.
    fn drop_unused_vertices(&mut self) {
        let mut used = vec![false; self.vertices.len()];
        for e in &self.elements {
            for v in e.v {
                used[v as usize] = true;
            }
        }
        let mut new_index = vec![u32::MAX; self.vertices.len()];
        let mut kept = Vec::new();
        for (i, v) in self.vertices.iter().enumerate() {
            if used[i] {
                new_index[i] = kept.len() as u32;
                kept.push(*v);
            }
        }
        self.vertices = kept;
        let elements = std::mem::take(&mut self.elements);
        self.edges.clear();
        for mut e in elements {
            e.v = e.v.map(|v| new_index[v as usize]);
            self.push_element(e);
        }
    }

    fn push_element(&mut self, e: Element) -> u32 {
        let id = self.elements.len() as u32;
        for i in 0..3 {
            self.edges
                .entry(edge_key(e.v[i], e.v[(i + 1) % 3]))
                .or_default()
                .push(id);
        }
        self.elements.push(e);
        id
    }

    /// Splits edge `(a, b)` at vertex `m` in every element that has it, keeping the mesh
    /// conforming. Returns the elements that were split (each keeps its index and shrinks; the
    /// other halves are appended).
    pub fn split_edge(&mut self, a: u32, b: u32, m: u32) -> Vec<u32> {
        let around = self.edges.remove(&edge_key(a, b)).unwrap_or_default();
        for &t in &around {
            let e = self.elements[t as usize];
            // Rotate so that the split edge is v[0] -> v[1].
            let i = (0..3)
                .find(|&i| edge_key(e.v[i], e.v[(i + 1) % 3]) == edge_key(a, b))
                .unwrap_or(0);
            let (x, y, c) = (e.v[i], e.v[(i + 1) % 3], e.v[(i + 2) % 3]);
            self.elements[t as usize].v = [x, m, c];
            let t2 = self.elements.len() as u32;
            self.elements.push(Element { v: [m, y, c], ..e });
            if let Some(list) = self.edges.get_mut(&edge_key(y, c)) {
                list.iter_mut().filter(|s| **s == t).for_each(|s| *s = t2);
            }
            self.edges.entry(edge_key(x, m)).or_default().push(t);
            self.edges.entry(edge_key(m, y)).or_default().push(t2);
            self.edges
                .entry(edge_key(m, c))
                .or_default()
                .extend([t, t2]);
        }
        around
    }

    /// Adds a vertex on edge `(a, b)` at `p` (normal and inset taken from the edge's ends).
    pub fn add_edge_vertex(&mut self, a: u32, b: u32, p: Vec3) -> u32 {
        let (va, vb) = (self.vertices[a as usize], self.vertices[b as usize]);
        let s = (p - va.pos).length() / (vb.pos - va.pos).length().max(1e-30);
        let normal = (va.normal + vb.normal).normalize_or(va.normal);
        let eval = va.eval.lerp(vb.eval, s);
        self.vertices.push(Vertex {
            pos: p,
            normal,
            eval,
        });
        self.vertices.len() as u32 - 1
    }

    /// Bisects edges longer than `max_edge`, always the longest remaining one first (so it is
    /// the longest edge of every element around it: longest-edge bisection, which keeps element
    /// shapes from degrading and the mesh conforming).
    pub fn subdivide(&mut self, max_edge: f32) {
        let mut heap: BinaryHeap<(OrdF32, u32, u32)> = self
            .edges
            .keys()
            .map(|&(a, b)| (OrdF32((self.pos(a) - self.pos(b)).length()), a, b))
            .filter(|e| e.0.0 > max_edge)
            .collect();
        while let Some((_, a, b)) = heap.pop() {
            if !self.edges.contains_key(&edge_key(a, b)) {
                continue; // already split
            }
            let m = self.add_edge_vertex(a, b, (self.pos(a) + self.pos(b)) * 0.5);
            for t in self.split_edge(a, b, m) {
                let e = self.elements[t as usize];
                let c =
                    e.v.into_iter()
                        .find(|&v| v != a && v != b && v != m)
                        .unwrap_or(m);
                for (x, y) in [(a, m), (m, b), (m, c)] {
                    let len = (self.pos(x) - self.pos(y)).length();
                    if len > max_edge {
                        heap.push((OrdF32(len), x.min(y), x.max(y)));
                    }
                }
            }
        }
    }

    /// Returns the elements sharing edge `(a, b)`.
    pub fn elements_on_edge(&self, a: u32, b: u32) -> &[u32] {
        self.edges
            .get(&edge_key(a, b))
            .map_or(&[], |v| v.as_slice())
    }

    /// Returns every edge once, as `(a, b)` with `a < b`.
    pub fn edge_list(&self) -> Vec<(u32, u32)> {
        let mut list: Vec<(u32, u32)> = self.edges.keys().copied().collect();
        list.sort_unstable();
        list
    }

    /// Splits coplanar triangles' edges at vertices lying inside them (T-junctions). Each sweep
    /// splits every edge at every vertex found on it; the edges those splits create are looked
    /// at by the next sweep.
    fn split_t_junctions(&mut self, eps: f32, search: Search) -> usize {
        let mut splits = 0;
        for _sweep in 0..64 {
            let found = self.t_junctions(eps, search);
            if found.is_empty() {
                break;
            }
            for ((a, b), on_edge) in found {
                let mut from = a;
                for v in on_edge {
                    if !self.edges.contains_key(&edge_key(from, b)) {
                        break;
                    }
                    splits += self.split_edge(from, b, v).len().min(1);
                    from = v;
                }
            }
        }
        splits
    }

    /// Returns each edge `(a, b)` (in edge order) with the vertices of the same surface lying
    /// inside it, ordered from `a` to `b`.
    fn t_junctions(&self, eps: f32, search: Search) -> Vec<((u32, u32), Vec<u32>)> {
        let edges = self.edge_list();
        let mut lengths: Vec<f32> = edges
            .iter()
            .map(|&(a, b)| (self.pos(a) - self.pos(b)).length())
            .collect();
        if lengths.is_empty() {
            return Vec::new();
        }
        let mid = lengths.len() / 2;
        let cell = lengths
            .select_nth_unstable_by(mid, f32::total_cmp)
            .1
            .max(eps);
        let mut grid = BoxGrid::new(cell);
        for (v, vert) in self.vertices.iter().enumerate() {
            grid.insert(v as u32, vert.pos, vert.pos);
        }
        let mut near = Vec::new();
        let mut found = Vec::new();
        for (a, b) in edges {
            let (pa, pb) = (self.pos(a), self.pos(b));
            let n = self.vertices[a as usize].normal;
            let ab = pb - pa;
            match search {
                Search::Grid => grid.query_segment(pa, pb, eps, &mut near),
                Search::Everything => near = (0..self.vertices.len() as u32).collect(),
            }
            let mut on_edge: Vec<(f32, u32)> = near
                .iter()
                .copied()
                .filter(|&v| v != a && v != b)
                .filter(|&v| self.vertices[v as usize].normal.dot(n) >= 0.999)
                .filter_map(|v| {
                    let p = self.pos(v);
                    let s = (p - pa).dot(ab) / ab.length_squared();
                    (s > 1e-4 && s < 1.0 - 1e-4 && (pa + ab * s - p).length() < eps)
                        .then_some((s, v))
                })
                .collect();
            if !on_edge.is_empty() {
                on_edge.sort_by(|x, y| x.0.total_cmp(&y.0));
                found.push(((a, b), on_edge.into_iter().map(|(_, v)| v).collect()));
            }
        }
        found
    }

    /// Splits triangles along the segments where triangles of other planes cut or touch them.
    fn split_d0(&mut self, eps: f32, search: Search) -> usize {
        let base: Vec<Tri> = self.elements.iter().map(|e| self.tri(e)).collect();
        let boxes: Vec<(Vec3, Vec3)> = base.iter().map(|t| padded_box(t, eps)).collect();
        let grid = BoxGrid::over(&boxes);
        let mut near = Vec::new();
        let mut cuts: Vec<(Vec3, Vec3, Vec3)> = Vec::new(); // (p, q, plane normal)
        for (i, a) in base.iter().enumerate() {
            match search {
                Search::Grid => grid.query_box(boxes[i].0, boxes[i].1, &mut near),
                Search::Everything => near = (0..base.len() as u32).collect(),
            }
            for &j in &near {
                let b = &base[j as usize];
                if i == j as usize
                    || a.normal().dot(b.normal()).abs() > 0.999
                    || !boxes_touch(a, b, eps)
                {
                    continue;
                }
                if let Some((p, q)) = plane_cut_segment(a, b, eps) {
                    cuts.push((p, q, a.normal()));
                }
            }
        }
        let mut index = ElementIndex::new(self, eps);
        let mut splits = 0;
        for (p, q, n) in cuts {
            for _guard in 0..256 {
                match search {
                    Search::Grid => index.candidates(self, p, q, &mut near),
                    Search::Everything => near = (0..self.elements.len() as u32).collect(),
                }
                let Some(t) = self.find_straddler(&near, p, q, n, eps) else {
                    break;
                };
                splits += self.cut_element(t, p, q, n, eps);
            }
        }
        splits
    }

    /// Finds the first of `candidates` in the plane of segment `(p, q)` whose interior the
    /// segment crosses.
    fn find_straddler(
        &self,
        candidates: &[u32],
        p: Vec3,
        q: Vec3,
        n: Vec3,
        eps: f32,
    ) -> Option<usize> {
        let m = n.cross(q - p).normalize_or_zero();
        candidates.iter().map(|&c| c as usize).find(|&c| {
            let t = self.tri(&self.elements[c]);
            let tn = t.normal();
            if tn.dot(n) < 0.999 || tn.dot(p - t.v[0]).abs() > eps || tn.dot(q - t.v[0]).abs() > eps
            {
                return false;
            }
            let s = t.v.map(|v| m.dot(v - p));
            if s.iter().all(|&x| x <= eps) || s.iter().all(|&x| x >= -eps) {
                return false;
            }
            segment_crosses_interior(&t, p, q, eps)
        })
    }

    /// Cuts element `t` along the line through `p`, `q`; returns the edge splits made.
    fn cut_element(&mut self, t: usize, p: Vec3, q: Vec3, n: Vec3, eps: f32) -> usize {
        let m = n.cross(q - p).normalize_or_zero();
        let e = self.elements[t];
        let mut crossings = Vec::new();
        for i in 0..3 {
            let (a, b) = (e.v[i], e.v[(i + 1) % 3]);
            let (sa, sb) = (m.dot(self.pos(a) - p), m.dot(self.pos(b) - p));
            if (sa > eps && sb < -eps) || (sa < -eps && sb > eps) {
                let x = self.pos(a) + (self.pos(b) - self.pos(a)) * (sa / (sa - sb));
                crossings.push((a, b, x));
            }
        }
        for &(a, b, x) in &crossings {
            let v = self.add_edge_vertex(a, b, x);
            self.split_edge(a, b, v);
        }
        crossings.len()
    }

    /// Moves the evaluation point of boundary vertices slightly into their surface.
    fn set_eval_points(&mut self) {
        let mut pull = vec![Vec3::ZERO; self.vertices.len()];
        let mut shortest = vec![f32::INFINITY; self.vertices.len()];
        for e in &self.elements {
            let t = self.tri(e);
            let c = t.centroid();
            for k in 0..3 {
                let v = e.v[k] as usize;
                pull[v] += (c - t.v[k]).normalize_or_zero();
                shortest[v] = shortest[v].min((t.v[(k + 1) % 3] - t.v[k]).length());
            }
        }
        for (i, v) in self.vertices.iter_mut().enumerate() {
            // Interior vertices are pulled equally in all directions (|pull| small): leave them.
            let dir = pull[i];
            v.eval = if dir.length() > 0.5 {
                v.pos + dir.normalize() * shortest[i] * 1e-3
            } else {
                v.pos
            };
        }
    }

    /// Returns the total area of the elements of each object.
    pub fn object_areas(&self, objects: usize) -> Vec<f64> {
        let mut area = vec![0.0; objects];
        for e in &self.elements {
            area[e.object as usize] += self.tri(e).area() as f64;
        }
        area
    }
}

/// How D0 splitting finds candidates: through grids (the real thing), or by scanning everything
/// (the slow oracle the tests compare it with; both must give the same mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Search {
    Grid,
    #[cfg_attr(not(test), allow(dead_code))]
    Everything,
}

/// A grid over the elements, kept up to date as cuts add elements: a new half lies inside the
/// box of the element it was cut from, and a cut element only shrinks, so every element stays in
/// (at least) the cells of its own box.
struct ElementIndex {
    grid: BoxGrid,
    /// Elements `0..inserted` are in the grid.
    inserted: usize,
    eps: f32,
}

impl ElementIndex {
    fn new(mesh: &Mesh, eps: f32) -> ElementIndex {
        let boxes: Vec<(Vec3, Vec3)> = mesh
            .elements
            .iter()
            .map(|e| padded_box(&mesh.tri(e), eps))
            .collect();
        ElementIndex {
            grid: BoxGrid::over(&boxes),
            inserted: boxes.len(),
            eps,
        }
    }

    /// Puts into `out`, in increasing order, every element that may meet segment `(p, q)`.
    fn candidates(&mut self, mesh: &Mesh, p: Vec3, q: Vec3, out: &mut Vec<u32>) {
        for i in self.inserted..mesh.elements.len() {
            let (lo, hi) = padded_box(&mesh.tri(&mesh.elements[i]), self.eps);
            self.grid.insert(i as u32, lo, hi);
        }
        self.inserted = mesh.elements.len();
        self.grid.query_segment(p, q, self.eps, out);
    }
}

/// The triangle's bounding box, widened by `eps`.
fn padded_box(t: &Tri, eps: f32) -> (Vec3, Vec3) {
    let e = Vec3::splat(eps);
    (
        t.v[0].min(t.v[1]).min(t.v[2]) - e,
        t.v[0].max(t.v[1]).max(t.v[2]) + e,
    )
}

fn boxes_touch(a: &Tri, b: &Tri, eps: f32) -> bool {
    let (alo, ahi) = (
        a.v[0].min(a.v[1]).min(a.v[2]),
        a.v[0].max(a.v[1]).max(a.v[2]),
    );
    let (blo, bhi) = (
        b.v[0].min(b.v[1]).min(b.v[2]),
        b.v[0].max(b.v[1]).max(b.v[2]),
    );
    !(alo.cmpgt(bhi + Vec3::splat(eps)).any() || blo.cmpgt(ahi + Vec3::splat(eps)).any())
}

/// True when the segment `(p, q)` (in the triangle's plane) has a piece of positive length
/// strictly inside the triangle.
fn segment_crosses_interior(t: &Tri, p: Vec3, q: Vec3, eps: f32) -> bool {
    let n = t.normal();
    let (mut s0, mut s1) = (0.0f32, 1.0f32);
    for i in 0..3 {
        let (a, b) = (t.v[i], t.v[(i + 1) % 3]);
        let inward = n.cross(b - a).normalize_or_zero();
        let (dp, dq) = (inward.dot(p - a) - eps, inward.dot(q - a) - eps);
        if dp < 0.0 && dq < 0.0 {
            return false;
        }
        if dp < 0.0 {
            s0 = s0.max(dp / (dp - dq));
        } else if dq < 0.0 {
            s1 = s1.min(dp / (dp - dq));
        }
    }
    (s1 - s0) * (q - p).length() > eps
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::cornell;

    #[test]
    fn cornell_floor_is_cut_along_the_block_footprints() {
        let scene = cornell::load(true).expect("scene");
        let mesh = meshed(&scene, 1000.0);
        assert!(mesh.stats.d0_splits > 0, "{:?}", mesh.stats);
        // No floor element straddles the line of the short block's front face (z from 65 to 114).
        let (p, q) = (Vec3::new(130.0, 0.0, 65.0), Vec3::new(290.0, 0.0, 114.0));
        let all: Vec<u32> = (0..mesh.elements.len() as u32).collect();
        assert!(mesh.find_straddler(&all, p, q, Vec3::Y, 1e-3).is_none());
    }

    /// `scene` meshed with patches and elements of at most `size`.
    fn meshed(scene: &Scene, size: f32) -> Mesh {
        Mesh::from_scene(
            scene,
            MeshConfig {
                patch_size: size,
                element_size: size,
            },
        )
    }

    /// A scene of one object from triangles in the plane y = 0 given by (x, z) corners.
    fn flat_scene(tris: &[[(f32, f32); 3]]) -> Scene {
        use crate::scene::{Object, SceneTri};
        let v = |(x, z): (f32, f32)| Vec3::new(x, 0.0, z);
        Scene {
            objects: vec![Object {
                name: "floor".into(),
                reflectance: Vec3::splat(0.5),
                emission: Vec3::ZERO,
            }],
            triangles: tris
                .iter()
                .map(|t| SceneTri {
                    tri: Tri::new(v(t[0]), v(t[1]), v(t[2])),
                    object: 0,
                })
                .collect(),
            ..Scene::default()
        }
    }

    /// A 100 x 10 strip (two triangles) under a strip cut into 100 columns: 99 vertices lie
    /// inside the first strip's top edge.
    fn strip_scene() -> Scene {
        let mut tris = vec![
            [(0.0, 0.0), (0.0, 10.0), (100.0, 10.0)],
            [(0.0, 0.0), (100.0, 10.0), (100.0, 0.0)],
        ];
        for i in 0..100 {
            let (x0, x1) = (i as f32, i as f32 + 1.0);
            tris.push([(x0, 10.0), (x0, 20.0), (x1, 20.0)]);
            tris.push([(x0, 10.0), (x1, 20.0), (x1, 10.0)]);
        }
        flat_scene(&tris)
    }

    #[test]
    fn grid_search_meshes_exactly_as_scanning_everything() {
        let config = MeshConfig {
            patch_size: 1e6,
            element_size: 1e6,
        };
        for scene in [cornell::load(true).expect("scene"), strip_scene()] {
            let fast = Mesh::build(&scene, config, Search::Grid);
            let slow = Mesh::build(&scene, config, Search::Everything);
            assert!(
                fast.stats.d0_splits + fast.stats.t_junction_splits > 10,
                "{:?}",
                fast.stats
            );
            assert_eq!(fast.stats, slow.stats);
            assert_eq!(fast.vertices, slow.vertices);
            assert_eq!(fast.elements, slow.elements);
        }
    }

    #[test]
    fn every_t_junction_along_a_long_edge_is_split() {
        // All 99 T-junctions must be split, leaving a conforming mesh.
        let mesh = meshed(&strip_scene(), 1e3);
        assert_eq!(mesh.stats.t_junction_splits, 99);
        for (a, b) in mesh.edge_list() {
            let n = mesh.elements_on_edge(a, b).len();
            let mid = (mesh.vertices[a as usize].pos + mesh.vertices[b as usize].pos) * 0.5;
            let outer = mid.x == 0.0 || mid.x == 100.0 || mid.z == 0.0 || mid.z == 20.0;
            assert_eq!(n, if outer { 1 } else { 2 }, "edge {a}-{b} at {mid}");
        }
    }

    #[test]
    fn triangles_below_the_weld_distance_are_left_out_not_meshed_forever() {
        // A scene 1e8 across with a triangle 0.5 across: welding (1e-5 of the diagonal) merges
        // its corners. Meshing it would split a zero-length edge without end; it is counted
        // and left out instead.
        let scene = flat_scene(&[
            [(0.0, 0.0), (0.0, 1e8), (1e8, 0.0)],
            [(1.0, 1.0), (1.0, 1.5), (1.5, 1.0)],
        ]);
        let mesh = meshed(&scene, 5e7);
        assert_eq!(mesh.stats.collapsed, 1);
        assert!(mesh.elements.len() < 100, "{}", mesh.elements.len());
        // The collapsed triangle leaves no sample point behind.
        let mut used = vec![false; mesh.vertices.len()];
        mesh.elements
            .iter()
            .flat_map(|e| e.v)
            .for_each(|v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u));
    }

    #[test]
    fn t_junction_is_split() {
        // A square: the lower-left half is one triangle; the upper-right half is two triangles
        // meeting at the midpoint of the diagonal, which is a T-junction on the first.
        let tris = [
            [(0.0, 0.0), (0.0, 2.0), (2.0, 0.0)],
            [(0.0, 2.0), (2.0, 2.0), (1.0, 1.0)],
            [(2.0, 2.0), (2.0, 0.0), (1.0, 1.0)],
        ];
        let scene = flat_scene(&tris);
        let mesh = meshed(&scene, 10.0);
        assert_eq!(mesh.stats.t_junction_splits, 1);
        assert_eq!(mesh.elements.len(), 4);
        assert_eq!(mesh.vertices.len(), 5);
        for (a, b) in mesh.edge_list() {
            let n = mesh.elements_on_edge(a, b).len();
            let boundary = (mesh.vertices[a as usize].pos + mesh.vertices[b as usize].pos) * 0.5;
            let on_boundary = [boundary.x, boundary.z]
                .iter()
                .any(|&c| c == 0.0 || c == 2.0);
            assert_eq!(n, if on_boundary { 1 } else { 2 }, "edge {a}-{b}");
        }
    }

    #[test]
    fn mesh_is_conforming_every_edge_has_one_or_two_elements() {
        let scene = cornell::load(true).expect("scene");
        let mesh = Mesh::from_scene(
            &scene,
            MeshConfig {
                patch_size: 150.0,
                element_size: 60.0,
            },
        );
        for (a, b) in mesh.edge_list() {
            let n = mesh.elements_on_edge(a, b).len();
            assert!(n == 1 || n == 2, "edge {a}-{b} has {n} elements");
        }
        let total: f64 = mesh.object_areas(scene.objects.len()).iter().sum();
        let scene_area: f64 = scene.triangles.iter().map(|t| t.tri.area() as f64).sum();
        assert!((total - scene_area).abs() < 1e-4 * scene_area);
    }
}
