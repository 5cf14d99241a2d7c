//! The conforming triangle mesh the solver works on: sample points (vertices), elements
//! (triangles) and patches (the source polygons that shoot).
//!
//! Vertices are shared between triangles of the same surface, found by position and normal, so a
//! sample point on an edge between two patches of one wall is one point. Every refinement is an
//! edge split ([`Mesh::split_edge`]) applied to *all* triangles around the edge, so the mesh
//! stays conforming (no T-junctions) and new sample points re-triangulate their neighbourhood.
//!
//! Meshing pipeline ([`Mesh::from_scene`]); each step runs once and is bounded by its output:
//! 1. weld corners by position, drop collapsed and duplicate triangles, count degenerate input
//!    (`input`);
//! 2. D0 discontinuities: each triangle is cut once, into convex pieces, along the segments
//!    where faces of other planes cross or touch it and along the outlines of parallel faces
//!    close in front of it, which hide what they cover (`cuts`, `piece`);
//! 3. the pieces' points are welded by position and normal, each piece edge takes the points of
//!    its surface lying on it (T-junctions, found once, never split again), and the pieces are
//!    triangulated;
//! 4. regions enclosed by contact are hidden and sample points on discontinuities are split,
//!    one per side (`surface`);
//! 5. patches: longest-edge bisection until every edge is at most `patch_size`;
//! 6. elements: further bisection to at most `element_size`; each element remembers its patch.
//!
//! No step makes an edge shorter than the weld distance (1e-5 of the scene's diagonal), and
//! bisection never goes below ten times it, so meshing always finishes.

mod band;
mod cuts;
mod input;
mod piece;
mod surface;

pub use input::InputCounts;

use std::collections::BinaryHeap;

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use smallvec::SmallVec;

use crate::geom::Tri;
use crate::grid::{BoxGrid, PointIndex};
use crate::scene::Scene;
use piece::{Frame, Piece, Tags};

/// Parallel surfaces closer than this fraction of the scene's diagonal cover each other.
pub const COVER_GAP: f64 = 1e-3;

/// The weld distance as a fraction of the scene's diagonal.
pub const WELD: f64 = 1e-5;

/// A sample point: where radiosity is computed and stored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// Position on the surface.
    pub pos: Vec3,
    /// Unit surface normal; zero for a hidden point (covered by a surface close in front, or
    /// enclosed by contact), which receives nothing: the form factor to any source is zero.
    pub normal: Vec3,
    /// Where form factors are evaluated: `pos`, moved slightly inside the surface for vertices on
    /// a surface boundary (exactly on an edge a neighbouring wall is seen edge-on).
    pub eval: Vec3,
}

impl Vertex {
    /// Whether the point is hidden (see [`Vertex::normal`]).
    pub fn hidden(&self) -> bool {
        self.normal == Vec3::ZERO
    }
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
    /// `occ radiosity`'s default sizes for a scene of diagonal `diag`: patches a quarter of it,
    /// elements a nineteenth, with a row of points beside concave creases and contact lines
    /// ([`Mesh::band_concave_creases`] at [`CREASE_BAND_EDGE`]). With that row the Cornell box,
    /// the two rooms and the table lamp hold their tolerances at a nineteenth on every seed
    /// measured, with fewer points than at a twentieth without it (radiosity/REFERENCES.md, "The
    /// element size with the row of points").
    pub fn default_for(diag: f32) -> MeshConfig {
        MeshConfig {
            patch_size: diag / 4.0,
            element_size: diag / 19.0,
        }
    }

    /// About how many elements meshing `scene` with these sizes makes: each triangle's area over
    /// that of an equilateral element of the element size, or its edge count along the longest
    /// edge for slivers, whichever is more (longest-edge bisection halves edges until they are
    /// short enough). Discontinuity cuts add to it. Callers use it to refuse or coarsen sizes
    /// that would not fit in memory before meshing.
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

    /// These sizes scaled up together until [`MeshConfig::estimated_elements`] is at most
    /// `budget` (unchanged when it already is).
    pub fn coarsened(&self, scene: &Scene, budget: f64) -> MeshConfig {
        let mut config = *self;
        for _ in 0..200 {
            if config.estimated_elements(scene) <= budget {
                break;
            }
            config.patch_size *= 1.25;
            config.element_size *= 1.25;
        }
        config
    }
}

/// The edges longer than this fraction of the element size that leave a concave crease or a
/// contact line are halved ([`Mesh::band_concave_creases`]).
pub const CREASE_BAND_EDGE: f32 = 0.5;

/// Counts of what meshing did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshStats {
    /// Scene triangles given to the mesher.
    pub input_triangles: usize,
    /// Degenerate and irregular input found by welding.
    #[serde(flatten)]
    pub input: InputCounts,
    /// Discontinuity segments applied to triangles (each cuts the pieces it crosses).
    pub d0_cuts: usize,
    /// Convex pieces the triangles were cut into.
    pub pieces: usize,
    /// Points inserted into piece edges where a point of the same surface lay on them.
    pub t_junction_splits: usize,
    /// Elements hidden (covered or enclosed by contact) before subdivision.
    pub hidden_pieces: usize,
    /// Sample points split along discontinuities, one per side.
    pub split_points: usize,
    /// Patches.
    pub patches: usize,
    /// Elements.
    pub elements: usize,
    /// Sample points (vertices).
    pub vertices: usize,
    /// Sample points added by the band along concave creases and contact lines
    /// ([`Mesh::band_concave_creases`]; included in `vertices`).
    pub crease_band_points: usize,
}

/// The elements around each edge, by [`edge_key`].
type EdgeMap = FxHashMap<(u32, u32), SmallVec<[u32; 2]>>;

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
    edges: EdgeMap,
    /// What meshing did.
    pub stats: MeshStats,
    /// Each meshing step with its wall-clock and processor seconds (all threads; zero where
    /// the system does not say), in order: for benchmarks, never in reports, which must not
    /// depend on the machine.
    pub stage_seconds: Vec<StageTime>,
}

/// The time one meshing step took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageTime {
    /// The step.
    pub name: &'static str,
    /// Wall-clock seconds.
    pub wall: f64,
    /// Processor seconds of the whole process (user and system, all threads).
    pub cpu: f64,
}

/// Records the times of successive steps.
struct Stopwatch(std::time::Instant, f64);

impl Stopwatch {
    fn start() -> Stopwatch {
        Stopwatch(std::time::Instant::now(), process_cpu_seconds())
    }

    /// Ends step `name` (begun at the previous call) in `out`.
    fn lap(&mut self, name: &'static str, out: &mut Vec<StageTime>) {
        let (now, cpu) = (std::time::Instant::now(), process_cpu_seconds());
        out.push(StageTime {
            name,
            wall: (now - self.0).as_secs_f64(),
            cpu: cpu - self.1,
        });
        *self = Stopwatch(now, cpu);
    }
}

/// The processor time the process has used (user and system), from `/proc/self/stat` in
/// clock ticks of 10 ms; zero where there is no such file.
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields 14 and 15 (utime, stime) follow the parenthesised command name.
    let after = stat.rsplit(')').next().unwrap_or("");
    let ticks: f64 = after
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|w| w.parse::<f64>().ok())
        .sum();
    ticks / 100.0
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

/// The edge map of elements given by their corners, in order: each edge lists its elements by
/// ascending index.
fn edge_map_of(elements: impl ExactSizeIterator<Item = [u32; 3]>) -> EdgeMap {
    let mut edges = EdgeMap::default();
    // About three edges for every two elements in a connected mesh.
    edges.reserve(elements.len() * 3 / 2);
    for (i, v) in elements.enumerate() {
        for k in 0..3 {
            edges
                .entry(edge_key(v[k], v[(k + 1) % 3]))
                .or_default()
                .push(i as u32);
        }
    }
    edges
}

/// Where a mesh's elements keep their corners: the mesh's own elements, or a flat array of
/// three vertex indices an element (carm.occ's controller, through `RAD.REFINE.SPLIT`).
pub trait ElementCorners {
    /// The corners of element `t`.
    fn corners(&self, t: u32) -> [u32; 3];
    /// Gives element `t` the corners `v`.
    fn set_corners(&mut self, t: u32, v: [u32; 3]);
    /// Appends a copy of element `of` (its patch, object) with the corners `v`; returns its index.
    fn push_copy(&mut self, of: u32, v: [u32; 3]) -> u32;
}

impl ElementCorners for Vec<Element> {
    fn corners(&self, t: u32) -> [u32; 3] {
        self[t as usize].v
    }
    fn set_corners(&mut self, t: u32, v: [u32; 3]) {
        self[t as usize].v = v;
    }
    fn push_copy(&mut self, of: u32, v: [u32; 3]) -> u32 {
        self.push(Element {
            v,
            ..self[of as usize]
        });
        self.len() as u32 - 1
    }
}

/// A conforming mesh's connectivity over elements kept elsewhere: splits edges exactly as
/// [`Mesh::split_edge`] does (it is the same code), for a program that keeps the elements
/// itself.
pub struct Connectivity<C: ElementCorners> {
    edges: EdgeMap,
    /// The elements.
    pub elements: C,
}

impl<C: ElementCorners> Connectivity<C> {
    /// The connectivity of `count` elements around the edges `wanted` (each `(lower, higher)`),
    /// the only edges [`Connectivity::split_edge`] may then split: enough for splitting a set of
    /// edges of the mesh, in any order, without mapping the others.
    pub fn around(elements: C, count: usize, wanted: impl Iterator<Item = (u32, u32)>) -> Self {
        let mut edges: EdgeMap = wanted.map(|e| (e, SmallVec::new())).collect();
        for t in 0..count as u32 {
            let v = elements.corners(t);
            for k in 0..3 {
                if let Some(list) = edges.get_mut(&edge_key(v[k], v[(k + 1) % 3])) {
                    list.push(t);
                }
            }
        }
        edges.retain(|_, list| !list.is_empty());
        Connectivity { edges, elements }
    }

    /// Splits edge `(a, b)` at vertex `m` ([`Mesh::split_edge`]'s contract).
    pub fn split_edge(&mut self, a: u32, b: u32, m: u32) -> Vec<u32> {
        split_edge_in(&mut self.edges, &mut self.elements, a, b, m)
    }
}

/// Splits edge `(a, b)` at vertex `m` in every element of `elements` that has it: each such
/// element `(x, y, c)` (rotated so that the edge is `x -> y`) becomes `(x, m, c)` and a new
/// element `(m, y, c)` is appended. Returns the split elements, in the order their halves were
/// appended.
fn split_edge_in<C: ElementCorners>(
    edges: &mut EdgeMap,
    elements: &mut C,
    a: u32,
    b: u32,
    m: u32,
) -> Vec<u32> {
    let mut around = edges.remove(&edge_key(a, b)).unwrap_or_default();
    // In index order, so that the halves are numbered alike however the map was built.
    around.sort_unstable();
    let mut split = Vec::with_capacity(around.len());
    for &t in &around {
        let v = elements.corners(t);
        // Rotate so that the split edge is v[0] -> v[1].
        let Some(i) = (0..3).find(|&i| edge_key(v[i], v[(i + 1) % 3]) == edge_key(a, b)) else {
            continue;
        };
        let (x, y, c) = (v[i], v[(i + 1) % 3], v[(i + 2) % 3]);
        elements.set_corners(t, [x, m, c]);
        let t2 = elements.push_copy(t, [m, y, c]);
        if let Some(list) = edges.get_mut(&edge_key(y, c)) {
            list.iter_mut().filter(|s| **s == t).for_each(|s| *s = t2);
        }
        edges.entry(edge_key(x, m)).or_default().push(t);
        edges.entry(edge_key(m, y)).or_default().push(t2);
        edges.entry(edge_key(m, c)).or_default().extend([t, t2]);
        split.push(t);
    }
    split
}

/// Points with normals closer than this (cosine) belong to one surface.
const SAME_SURFACE: f64 = 0.999;

/// A piece of a face with its points welded into vertices.
struct Welded {
    face: u32,
    ids: SmallVec<[u32; 4]>,
    /// Per edge, or empty when no edge has any.
    tags: Vec<Tags>,
    hidden: bool,
}

impl Mesh {
    /// Meshes a scene (see the module doc for the steps).
    pub fn from_scene(scene: &Scene, config: MeshConfig) -> Mesh {
        let mut clock = Stopwatch::start();
        let mut laps = Vec::new();
        let diag = f64::from(scene.diagonal()).max(1e-30);
        let tol = WELD * diag;
        let mut input = input::weld(scene, tol);
        clock.lap("weld input", &mut laps);
        let context = cuts::Context::new(&input, tol, COVER_GAP * diag);
        clock.lap("search structures", &mut laps);
        let cut: Vec<(Option<Vec<Piece>>, usize)> = (0..input.faces.len())
            .into_par_iter()
            .map_init(Vec::new, |near, f| context.cut_face(f, near))
            .collect();
        drop(context);
        input.edges = Vec::new();
        clock.lap("cut faces", &mut laps);
        let mut mesh = Mesh::default();
        mesh.stats.input_triangles = scene.triangles.len();
        mesh.stats.input = input.counts;
        mesh.stats.d0_cuts = cut.iter().map(|c| c.1).sum();
        let welded = mesh.weld_pieces(&input, cut, tol);
        mesh.stats.pieces = welded.len();
        clock.lap("weld pieces", &mut laps);
        let (tags, mut hidden) = mesh.triangulate(&input, welded, tol);
        clock.lap("triangulate", &mut laps);
        mesh.stats.hidden_pieces = hidden.iter().filter(|&&h| h).count();
        mesh.stats.hidden_pieces += surface::hide_enclosed(&mesh, &tags, &mut hidden);
        mesh.stats.split_points = surface::split_points(&mut mesh, &tags, &hidden);
        drop((tags, hidden));
        clock.lap("hide and split", &mut laps);
        let floor = (tol * 10.0) as f32;
        mesh.subdivide(config.patch_size.max(floor));
        mesh.patches = mesh.elements.iter().map(|e| mesh.tri(e)).collect();
        mesh.patch_object = mesh.elements.iter().map(|e| e.object).collect();
        for (i, e) in mesh.elements.iter_mut().enumerate() {
            e.patch = i as u32;
        }
        clock.lap("patches", &mut laps);
        mesh.subdivide(config.element_size.max(floor));
        mesh.set_eval_points();
        clock.lap("elements", &mut laps);
        mesh.stats.patches = mesh.patches.len();
        mesh.stats.elements = mesh.elements.len();
        mesh.stats.vertices = mesh.vertices.len();
        mesh.stage_seconds = laps;
        mesh
    }

    /// Returns the geometry of an element.
    pub fn tri(&self, e: &Element) -> Tri {
        Tri::new(self.pos(e.v[0]), self.pos(e.v[1]), self.pos(e.v[2]))
    }

    fn pos(&self, v: u32) -> Vec3 {
        self.vertices[v as usize].pos
    }

    /// Gives every point of every piece a vertex: one per position (within `tol`) and surface.
    /// Faces left whole become one piece of their corners.
    fn weld_pieces(
        &mut self,
        input: &input::Input,
        cut: Vec<(Option<Vec<Piece>>, usize)>,
        tol: f64,
    ) -> Vec<Welded> {
        let mut welder = Welder {
            index: PointIndex::new(tol),
            exact: vec![SmallVec::new(); input.positions.len()],
            at: Vec::new(),
            normals: Vec::new(),
        };
        let mut out = Vec::with_capacity(input.faces.len());
        for (f, (face, (pieces, _))) in input.faces.iter().zip(cut).enumerate() {
            let corner = |p: DVec3| {
                face.v
                    .into_iter()
                    .find(|&c| input.positions[c as usize] == p)
            };
            let Some(pieces) = pieces else {
                let ids = face
                    .v
                    .map(|c| welder.vertex(self, input.positions[c as usize], face.normal, Some(c)))
                    .into_iter()
                    .collect();
                out.push(Welded {
                    face: f as u32,
                    ids,
                    tags: Vec::new(),
                    hidden: false,
                });
                continue;
            };
            for p in pieces {
                let ids = p
                    .pts
                    .iter()
                    .map(|x| welder.vertex(self, x.p, face.normal, corner(x.p)))
                    .collect();
                out.push(Welded {
                    face: f as u32,
                    ids,
                    tags: p.tags,
                    hidden: p.hidden,
                });
            }
        }
        out
    }

    /// Puts into each piece's edges the vertices of its surface lying on them (T-junctions),
    /// triangulates the pieces into elements, and returns the discontinuity tags of element
    /// edges and whether each element is hidden.
    fn triangulate(
        &mut self,
        input: &input::Input,
        pieces: Vec<Welded>,
        tol: f64,
    ) -> (surface::EdgeTags, Vec<bool>) {
        let mut lengths: Vec<f32> = input
            .faces
            .iter()
            .map(|f| {
                let p = f.v.map(|i| input.positions[i as usize]);
                (p[1] - p[0]).length().max((p[2] - p[1]).length()) as f32
            })
            .collect();
        let cell = if lengths.is_empty() {
            1.0
        } else {
            let mid = lengths.len() / 2;
            *lengths.select_nth_unstable_by(mid, f32::total_cmp).1
        };
        let grid = BoxGrid::build(cell.max(tol as f32 * 4.0), self.vertices.len(), |i| {
            (self.vertices[i].pos, self.vertices[i].pos)
        });
        let mesh = &*self;
        let done: Vec<Triangulated> = pieces
            .par_chunks(1024)
            .map(|chunk| {
                let mut out = Triangulated::default();
                let mut near = Vec::new();
                for piece in chunk {
                    mesh.triangulate_piece(input, piece, &grid, tol, &mut near, &mut out);
                }
                out
            })
            .collect();
        drop(pieces);
        let mut tags = surface::EdgeTags::default();
        let total: usize = done.iter().map(|d| d.elements.len()).sum();
        let mut hidden = Vec::with_capacity(total);
        self.elements.reserve(total);
        self.edges.reserve(total * 3 / 2);
        for d in done {
            self.stats.t_junction_splits += d.inserted;
            for (e, h) in d.elements.into_iter().zip(d.hidden) {
                self.push_element(e);
                hidden.push(h);
            }
            for (key, t) in d.tags {
                tags.entry(key).or_default().extend(t);
            }
        }
        (tags, hidden)
    }

    /// One piece: T-junction points into its edges, then ear clipping in its face's frame.
    fn triangulate_piece(
        &self,
        input: &input::Input,
        piece: &Welded,
        grid: &BoxGrid,
        tol: f64,
        near: &mut Vec<u32>,
        out: &mut Triangulated,
    ) {
        let face = &input.faces[piece.face as usize];
        let n = piece.ids.len();
        let none = Tags::new();
        let mut ids: SmallVec<[u32; 8]> = SmallVec::new();
        let mut tags: SmallVec<[&Tags; 8]> = SmallVec::new();
        for i in 0..n {
            let (a, b) = (piece.ids[i], piece.ids[(i + 1) % n]);
            let tag = piece.tags.get(i).unwrap_or(&none);
            ids.push(a);
            tags.push(tag);
            let on = self.points_on_edge(a, b, face.normal, grid, tol, near);
            out.inserted += on.len();
            for v in on {
                ids.push(v);
                tags.push(tag);
            }
        }
        let corners = face.v.map(|c| input.positions[c as usize]);
        let frame = Frame::of(corners, face.normal);
        let q: SmallVec<[DVec2; 8]> = ids
            .iter()
            .map(|&v| frame.plane_point(self.pos(v).as_dvec3()))
            .collect();
        let min_area = tol * tol;
        let tris = if ids.len() == 3 {
            vec![[0, 1, 2]]
        } else {
            piece::triangulate(&q, min_area, tol)
        };
        for t in tris {
            out.elements.push(Element {
                v: t.map(|k| ids[k]),
                object: face.object,
                patch: 0,
            });
            out.hidden.push(piece.hidden);
        }
        let m = ids.len();
        for i in 0..m {
            if !tags[i].is_empty() {
                out.tags
                    .push((edge_key(ids[i], ids[(i + 1) % m]), tags[i].clone()));
            }
        }
    }

    /// The vertices of the surface with normal `n` lying on edge `(a, b)` (within `tol` of it,
    /// farther than `tol` from its ends), ordered from `a` to `b`.
    fn points_on_edge(
        &self,
        a: u32,
        b: u32,
        n: DVec3,
        grid: &BoxGrid,
        tol: f64,
        near: &mut Vec<u32>,
    ) -> SmallVec<[u32; 2]> {
        let (pa, pb) = (self.pos(a).as_dvec3(), self.pos(b).as_dvec3());
        let ab = pb - pa;
        let len2 = ab.length_squared();
        if len2 <= 4.0 * tol * tol {
            return SmallVec::new();
        }
        grid.query_segment_points(self.pos(a), self.pos(b), tol as f32, near);
        let mut on: SmallVec<[(f64, u32); 2]> = near
            .iter()
            .copied()
            .filter(|&v| v != a && v != b)
            .filter_map(|v| {
                let vx = &self.vertices[v as usize];
                if vx.normal.as_dvec3().dot(n) <= SAME_SURFACE {
                    return None;
                }
                let p = vx.pos.as_dvec3();
                let s = (p - pa).dot(ab) / len2;
                let inside = s > 0.0
                    && s < 1.0
                    && (pa + ab * s - p).length() <= tol
                    && (p - pa).length() > tol
                    && (p - pb).length() > tol;
                inside.then_some((s, v))
            })
            .collect();
        on.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        on.into_iter().map(|(_, v)| v).collect()
    }

    /// Removes the vertices no element uses (left by triangles that welding collapsed and by
    /// point splitting), renumbers the rest in order and rebuilds the edge map.
    fn drop_unused_vertices(&mut self) {
        let mut used = vec![false; self.vertices.len()];
        for e in &self.elements {
            for v in e.v {
                used[v as usize] = true;
            }
        }
        let mut new_index = vec![u32::MAX; self.vertices.len()];
        let mut kept = 0;
        for i in 0..self.vertices.len() {
            if used[i] {
                new_index[i] = kept as u32;
                self.vertices[kept] = self.vertices[i];
                kept += 1;
            }
        }
        self.vertices.truncate(kept);
        for e in &mut self.elements {
            e.v = e.v.map(|v| new_index[v as usize]);
        }
        self.rebuild_edges();
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

    /// Rebuilds the edge map from the elements.
    fn rebuild_edges(&mut self) {
        self.edges = edge_map_of(self.elements.iter().map(|e| e.v));
    }

    /// Splits edge `(a, b)` at vertex `m` in every element that has it, keeping the mesh
    /// conforming. Returns the elements that were split (each keeps its index and shrinks; the
    /// other halves are appended, in the order of the returned list).
    pub fn split_edge(&mut self, a: u32, b: u32, m: u32) -> Vec<u32> {
        split_edge_in(&mut self.edges, &mut self.elements, a, b, m)
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

    /// Every edge once, as `(a, b)` with `a < b`, in no particular order.
    pub fn edges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.edges.keys().copied()
    }

    /// Returns every edge once, as `(a, b)` with `a < b`, ascending.
    pub fn edge_list(&self) -> Vec<(u32, u32)> {
        let mut list: Vec<(u32, u32)> = self.edges.keys().copied().collect();
        list.sort_unstable();
        list
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

    /// Whether each patch is hidden: every corner of every element of it is (covered, or
    /// enclosed by contact; it receives nothing, so it never shoots).
    pub fn hidden_patches(&self) -> Vec<bool> {
        let mut hidden = vec![true; self.patches.len()];
        for e in &self.elements {
            if e.v.iter().any(|&v| !self.vertices[v as usize].hidden()) {
                hidden[e.patch as usize] = false;
            }
        }
        hidden
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

/// Assigns vertices to points: exact matches with a scene corner first, then any point within
/// the weld distance of the same surface.
struct Welder {
    index: PointIndex,
    /// Vertices made at each scene corner.
    exact: Vec<SmallVec<[u32; 1]>>,
    at: Vec<DVec3>,
    normals: Vec<DVec3>,
}

impl Welder {
    fn vertex(&mut self, mesh: &mut Mesh, p: DVec3, n: DVec3, corner: Option<u32>) -> u32 {
        let normals = &self.normals;
        let same = |v: u32| normals[v as usize].dot(n) > SAME_SURFACE;
        let exact = corner.and_then(|c| self.exact[c as usize].iter().copied().find(|&v| same(v)));
        if let Some(v) = exact {
            return v;
        }
        let found = self.index.find(p, |i| self.at[i as usize], same);
        let v = found.unwrap_or_else(|| {
            mesh.vertices.push(Vertex {
                pos: p.as_vec3(),
                normal: n.as_vec3(),
                eval: p.as_vec3(),
            });
            self.normals.push(n);
            self.at.push(p);
            let v = self.at.len() as u32 - 1;
            self.index.insert(v, p);
            v
        });
        if let Some(c) = corner {
            self.exact[c as usize].push(v);
        }
        v
    }
}

/// What triangulating a run of pieces made.
#[derive(Default)]
struct Triangulated {
    elements: Vec<Element>,
    hidden: Vec<bool>,
    tags: Vec<((u32, u32), Tags)>,
    inserted: usize,
}

#[cfg(test)]
mod tests;
