//! The first step of meshing: the scene's triangles with their corners welded by position, and
//! degenerate input dropped or counted (see [`InputCounts`]).

use glam::DVec3;
use rustc_hash::FxHashMap;

use crate::grid::PointIndex;
use crate::scene::Scene;

/// A scene triangle after welding: corner indices into [`Input::positions`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    /// Corners, counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Scene object.
    pub object: u32,
    /// Unit front normal.
    pub normal: DVec3,
}

/// What welding found in the input, counted for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct InputCounts {
    /// Triangles dropped because welding merged two of their corners: features smaller than
    /// the weld distance (1e-5 of the scene's diagonal).
    pub collapsed: usize,
    /// Triangles dropped because another triangle of the same object has the same corners
    /// and the same orientation.
    pub duplicates: usize,
    /// Pairs of triangles with the same corners and opposite orientations: a two-sided
    /// surface, meshed as two one-sided ones.
    pub two_sided: usize,
    /// Triangles narrower than the weld distance (their height over the longest edge): never
    /// cut, only bisected along their length.
    pub slivers: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges where two triangles of one object meet with inconsistent orientations (one of
    /// them faces the other way: a flipped normal), as found in the input.
    pub flipped_edges: usize,
    /// Triangles turned over to face the way their connected surface does (see `reorient`).
    pub reoriented: usize,
}

/// The welded input.
pub struct Input {
    /// Corner positions.
    pub positions: Vec<DVec3>,
    /// Triangles kept.
    pub faces: Vec<Face>,
    /// Every side of every face, sorted by edge (see [`Input::edge_uses`]).
    pub edges: Vec<EdgeUse>,
    /// What was found.
    pub counts: InputCounts,
}

/// A face's side: edge `(a, b)` with `a < b`, and the face, which runs it from `a` to `b` or
/// back (packed in 12 bytes: there are millions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeUse {
    /// The edge, `a < b`.
    pub key: (u32, u32),
    /// The face in the low 31 bits; the top bit set when it runs the edge from `b` to `a`.
    face_back: u32,
}

impl EdgeUse {
    const BACK: u32 = 1 << 31;

    /// The face.
    pub fn face(&self) -> u32 {
        self.face_back & !Self::BACK
    }

    /// Whether the face runs the edge from `a` to `b` (the lower index first).
    pub fn forward(&self) -> bool {
        self.face_back & Self::BACK == 0
    }
}

impl Input {
    /// The sides of faces on edge `(a, b)` (either order).
    pub fn edge_uses(&self, a: u32, b: u32) -> &[EdgeUse] {
        let key = (a.min(b), a.max(b));
        let lo = self.edges.partition_point(|e| e.key < key);
        let len = self.edges[lo..].partition_point(|e| e.key == key);
        &self.edges[lo..lo + len]
    }
}

/// The sides of `faces`, sorted by edge.
fn edge_uses(faces: &[Face]) -> Vec<EdgeUse> {
    let mut edges: Vec<EdgeUse> = faces
        .iter()
        .enumerate()
        .flat_map(|(i, f)| {
            (0..3).map(move |k| {
                let (a, b) = (f.v[k], f.v[(k + 1) % 3]);
                EdgeUse {
                    key: (a.min(b), a.max(b)),
                    face_back: i as u32 | if a < b { 0 } else { EdgeUse::BACK },
                }
            })
        })
        .collect();
    edges.sort_unstable();
    edges
}

/// Welds the scene's triangle corners within `tol`, drops collapsed and duplicate triangles and
/// counts the rest of what [`InputCounts`] lists.
pub fn weld(scene: &Scene, tol: f64) -> Input {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut index = PointIndex::new(tol);
    let mut faces = Vec::with_capacity(scene.triangles.len());
    let mut counts = InputCounts::default();
    let mut seen: FxHashMap<([u32; 3], u32), bool> = FxHashMap::default();
    // The file's vertex normals (mean per kept face; zero where there are none).
    let mut hints: Vec<DVec3> = Vec::new();
    for (i, t) in scene.triangles.iter().enumerate() {
        let v = t.tri.v.map(|p| {
            let p = p.as_dvec3();
            index
                .find(p, |i| positions[i as usize], |_| true)
                .unwrap_or_else(|| {
                    positions.push(p);
                    let id = positions.len() as u32 - 1;
                    index.insert(id, p);
                    id
                })
        });
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            counts.collapsed += 1;
            continue;
        }
        let [a, b, c] = v.map(|i| positions[i as usize]);
        let cross = (b - a).cross(c - a);
        if cross.length_squared() == 0.0 {
            counts.collapsed += 1;
            continue;
        }
        // The same corners: a duplicate if the cyclic order is the same, two-sided if reversed.
        let mut sorted = v;
        sorted.sort_unstable();
        let even = cyclic_rank(v) == cyclic_rank(sorted);
        match seen.get(&(sorted, t.object)) {
            Some(&e) if e == even => {
                counts.duplicates += 1;
                continue;
            }
            Some(_) => counts.two_sided += 1,
            None => {
                seen.insert((sorted, t.object), even);
            }
        }
        let longest = [(a, b), (b, c), (c, a)]
            .iter()
            .map(|(p, q)| (*q - *p).length())
            .fold(0.0, f64::max);
        if cross.length() / longest < tol {
            counts.slivers += 1;
        }
        faces.push(Face {
            v,
            object: t.object,
            normal: cross.normalize(),
        });
        if let Some(h) = scene.normal_hints.get(i) {
            hints.resize(faces.len() - 1, DVec3::ZERO);
            hints.push(h.as_dvec3());
        }
    }
    hints.resize(faces.len(), DVec3::ZERO);
    let mut edges = edge_uses(&faces);
    count_edges(&faces, &edges, &mut counts);
    counts.reoriented = reorient(&positions, &mut faces, &mut edges, &hints);
    Input {
        positions,
        faces,
        edges,
        counts,
    }
}

/// 0 or 1: the parity of the rotation that sorts three distinct indices.
fn cyclic_rank(v: [u32; 3]) -> u32 {
    // Rotate the smallest first; the order of the other two gives the orientation.
    let i = (0..3).min_by_key(|&i| v[i]).unwrap_or(0);
    u32::from(v[(i + 1) % 3] > v[(i + 2) % 3])
}

/// Counts non-manifold edges and edges of one object whose two triangles disagree on
/// orientation (both run the edge the same way).
fn count_edges(faces: &[Face], edges: &[EdgeUse], counts: &mut InputCounts) {
    for around in edges.chunk_by(|x, y| x.key == y.key) {
        if around.len() > 2 {
            counts.non_manifold_edges += 1;
        } else if let [x, y] = around
            && x.forward() == y.forward()
            && faces[x.face() as usize].object == faces[y.face() as usize].object
        {
            counts.flipped_edges += 1;
        }
    }
}

/// Turns over the faces that disagree with their connected surface, and returns how many.
///
/// Faces joined by manifold edges (exactly two faces) form surfaces; across such an edge two
/// consistently oriented faces run it in opposite directions. Each surface is oriented from
/// one face outwards; then the orientation the file's vertex normals (`hints`, zero for none)
/// favour, weighted by area, is kept, or without normals the orientation of the larger area
/// (an exact tie, as a quad of two triangles one flipped, is left as given). Faces that
/// disagree with it are turned over: two corners swapped, normal negated, and their sides in
/// `edges` reversed.
pub fn reorient(
    positions: &[DVec3],
    faces: &mut [Face],
    edges: &mut [EdgeUse],
    hints: &[DVec3],
) -> usize {
    let n = faces.len();
    // Each face's neighbours across manifold edges, and whether they run the edge the same
    // way (then one of the two is flipped).
    let mut adj = vec![[(u32::MAX, false); 3]; n];
    for around in edges.chunk_by(|x, y| x.key == y.key) {
        if let [x, y] = around {
            let same = x.forward() == y.forward();
            for (me, other) in [(x, y), (y, x)] {
                if let Some(slot) = adj[me.face() as usize].iter_mut().find(|s| s.0 == u32::MAX) {
                    *slot = (other.face(), same);
                }
            }
        }
    }
    // Orientation of each face relative to the first face of its surface: 0 same, 1 opposite.
    let mut rel = vec![u8::MAX; n];
    let mut flip = vec![false; n];
    let mut queue = Vec::new();
    let mut surface = Vec::new();
    for seed in 0..n {
        if rel[seed] != u8::MAX {
            continue;
        }
        rel[seed] = 0;
        queue.push(seed as u32);
        surface.clear();
        while let Some(f) = queue.pop() {
            surface.push(f);
            for &(g, same) in &adj[f as usize] {
                if g != u32::MAX && rel[g as usize] == u8::MAX {
                    rel[g as usize] = rel[f as usize] ^ u8::from(same);
                    queue.push(g);
                }
            }
        }
        let (mut area, mut vote) = ([0.0f64; 2], 0.0f64);
        for &f in &surface {
            let face = &faces[f as usize];
            let p = face.v.map(|i| positions[i as usize]);
            let a = (p[1] - p[0]).cross(p[2] - p[0]).length();
            let r = rel[f as usize] as usize;
            area[r] += a;
            // Positive: the normals favour the first face's orientation.
            let sign = if r == 0 { 1.0 } else { -1.0 };
            vote += sign * a * face.normal.dot(hints[f as usize]);
        }
        let wrong = if vote > 0.0 {
            1
        } else if vote < 0.0 {
            0
        } else if area[1] < area[0] {
            1
        } else if area[0] < area[1] {
            0
        } else {
            continue;
        };
        for &f in &surface {
            flip[f as usize] = rel[f as usize] == wrong;
        }
    }
    let mut count = 0;
    for (face, _) in faces.iter_mut().zip(&flip).filter(|(_, f)| **f) {
        face.v.swap(1, 2);
        face.normal = -face.normal;
        count += 1;
    }
    for e in edges.iter_mut() {
        if flip[e.face() as usize] {
            e.face_back ^= EdgeUse::BACK;
        }
    }
    count
}
