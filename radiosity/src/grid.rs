//! A uniform hash grid over boxes: which items lie near a box or along a segment, without
//! testing every pair. Meshing uses it to find intersecting triangles, the elements a cut
//! crosses and the vertices lying on edges, so that preparing a scene of n triangles costs about
//! n, not n².
//!
//! Queries are conservative: they return every item whose box meets the query (and possibly some
//! that do not); callers apply their exact test to what comes back. Results are sorted and free
//! of duplicates, so a caller that takes the first match finds the same one a full scan would.

use glam::{DVec3, IVec3, Vec3};
use rustc_hash::FxHashMap;
use smallvec::SmallVec;

/// Boxes spanning more cells than this are kept in a list that every query returns, and query
/// boxes spanning more cells return every item.
const MAX_CELLS: i64 = 512;

/// The grid, built once over a list of boxes; item `i` is the `i`th box. Each occupied cell
/// holds a run of one shared id list (no allocation per cell).
#[derive(Clone, Debug)]
pub struct BoxGrid {
    inv_cell: f32,
    /// Each occupied cell's run `(start, len)` in `ids`.
    cells: FxHashMap<IVec3, (u32, u32)>,
    ids: Vec<u32>,
    /// Items too large to enter cell by cell.
    large: Vec<u32>,
    /// The number of items.
    count: u32,
}

impl BoxGrid {
    /// A grid with cells `cell` wide (at least 1e-30) over `n` items, item `i` with box
    /// `bounds(i)`.
    pub fn build(cell: f32, n: usize, bounds: impl Fn(usize) -> (Vec3, Vec3)) -> BoxGrid {
        let mut grid = BoxGrid {
            inv_cell: 1.0 / cell.max(1e-30),
            cells: FxHashMap::default(),
            ids: Vec::new(),
            large: Vec::new(),
            count: n as u32,
        };
        // Count the items of each cell, give each cell its run, then fill the runs in id order
        // (so each cell lists its items in increasing order).
        let spans: Vec<Option<(IVec3, IVec3)>> = (0..n)
            .map(|i| {
                let (lo, hi) = bounds(i);
                grid.span(lo, hi)
            })
            .collect();
        for (i, span) in spans.iter().enumerate() {
            match span {
                Some((a, b)) => each_cell(*a, *b, |c| grid.cells.entry(c).or_insert((0, 0)).1 += 1),
                None => grid.large.push(i as u32),
            }
        }
        let mut start = 0u32;
        for run in grid.cells.values_mut() {
            let len = run.1;
            *run = (start, 0);
            start += len;
        }
        grid.ids = vec![0; start as usize];
        for (i, span) in spans.iter().enumerate() {
            if let Some((a, b)) = span {
                each_cell(*a, *b, |c| {
                    if let Some(run) = grid.cells.get_mut(&c) {
                        grid.ids[(run.0 + run.1) as usize] = i as u32;
                        run.1 += 1;
                    }
                });
            }
        }
        grid
    }

    /// A grid whose cell is the median largest extent of `boxes` (so a typical box meets a few
    /// cells), over `boxes`.
    pub fn over(boxes: &[(Vec3, Vec3)]) -> BoxGrid {
        let mut extents: Vec<f32> = boxes
            .iter()
            .map(|(lo, hi)| (*hi - *lo).max_element())
            .collect();
        let cell = if extents.is_empty() {
            1.0
        } else {
            let mid = extents.len() / 2;
            *extents.select_nth_unstable_by(mid, f32::total_cmp).1
        };
        BoxGrid::build(cell, boxes.len(), |i| boxes[i])
    }

    /// The cells a box covers, or `None` when that is more than [`MAX_CELLS`] (or not finite).
    fn span(&self, lo: Vec3, hi: Vec3) -> Option<(IVec3, IVec3)> {
        let to_cell = |p: Vec3| (p * self.inv_cell).floor();
        let (a, b) = (to_cell(lo), to_cell(hi));
        if !(a.is_finite() && b.is_finite()) || (b - a).abs().max_element() > 1e6 {
            return None;
        }
        let (a, b) = (a.as_ivec3(), b.as_ivec3());
        let n = (b - a + IVec3::ONE).as_i64vec3();
        (n.x * n.y * n.z <= MAX_CELLS).then_some((a, b))
    }

    /// The items of a cell.
    fn cell(&self, c: &IVec3) -> &[u32] {
        self.cells.get(c).map_or(&[], |&(start, len)| {
            &self.ids[start as usize..(start + len) as usize]
        })
    }

    /// Puts every item into `out`.
    fn all(&self, out: &mut Vec<u32>) {
        out.clear();
        out.extend(0..self.count);
    }

    /// Puts into `out` (cleared first, sorted, deduplicated) every item whose box may meet
    /// `lo..hi`.
    pub fn query_box(&self, lo: Vec3, hi: Vec3, out: &mut Vec<u32>) {
        out.clear();
        if !self.collect_box(lo, hi, out) {
            self.all(out);
        }
        out.extend_from_slice(&self.large);
        finish(out);
    }

    /// Puts into `out` (cleared first, sorted, deduplicated) every item whose box may come
    /// within `radius` of the segment `p..q`. The segment is walked in steps of half a cell, so
    /// a long diagonal segment touches the cells along it rather than its whole bounding box.
    pub fn query_segment(&self, p: Vec3, q: Vec3, radius: f32, out: &mut Vec<u32>) {
        self.query_segment_points(p, q, radius, out);
        finish(out);
    }

    /// [`BoxGrid::query_segment`] for a grid of points (items inserted with `lo == hi`, so each
    /// in one cell): every item near the segment once, in no particular order but the same
    /// for the same query (and the large list, which a grid of points does not have).
    pub fn query_segment_points(&self, p: Vec3, q: Vec3, radius: f32, out: &mut Vec<u32>) {
        out.clear();
        let cell = 1.0 / self.inv_cell;
        let steps = ((q - p).length() / (0.5 * cell)).ceil().clamp(1.0, 1e6) as usize;
        let half = Vec3::splat(0.5 * (q - p).length() / steps as f32 + radius);
        // Each cell once: the boxes of successive steps overlap.
        let mut cells: SmallVec<[IVec3; 32]> = SmallVec::new();
        for k in 0..steps {
            let c = p.lerp(q, (k as f32 + 0.5) / steps as f32);
            let Some((a, b)) = self.span(c - half, c + half) else {
                self.all(out);
                return;
            };
            each_cell(a, b, |c| cells.push(c));
        }
        cells.sort_unstable_by_key(|c| (c.z, c.y, c.x));
        cells.dedup();
        for c in &cells {
            out.extend_from_slice(self.cell(c));
        }
        out.extend_from_slice(&self.large);
    }

    /// Appends the items of the cells `lo..hi` covers; false (appending nothing) when that is
    /// too many cells to visit, and the caller must take every item.
    fn collect_box(&self, lo: Vec3, hi: Vec3, out: &mut Vec<u32>) -> bool {
        let Some((a, b)) = self.span(lo, hi) else {
            return false;
        };
        each_cell(a, b, |c| out.extend_from_slice(self.cell(&c)));
        true
    }
}

/// Calls `f` on every cell of the block `a..=b`.
fn each_cell(a: IVec3, b: IVec3, mut f: impl FnMut(IVec3)) {
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                f(IVec3::new(x, y, z));
            }
        }
    }
}

/// Points welded within a distance: [`PointIndex::find`] returns a point already inserted
/// within `tol` of the query (and accepted by the caller's test), whatever cell boundary lies
/// between them. Cells are `2 tol` wide and a query looks at the (at most 8) cells within `tol`.
#[derive(Clone, Debug, Default)]
pub struct PointIndex {
    inv_cell: f64,
    tol: f64,
    tol2: f64,
    /// The last id inserted in each cell; `next` chains to the one before (no allocation per
    /// cell).
    cells: FxHashMap<[i64; 3], u32>,
    /// By id: the id inserted in the same cell before it, or `u32::MAX`.
    next: Vec<u32>,
}

impl PointIndex {
    /// An empty index welding points within `tol` (> 0).
    pub fn new(tol: f64) -> PointIndex {
        PointIndex {
            inv_cell: 0.5 / tol,
            tol,
            tol2: tol * tol,
            cells: FxHashMap::default(),
            next: Vec::new(),
        }
    }

    fn key(&self, p: DVec3) -> [i64; 3] {
        (p * self.inv_cell).floor().as_i64vec3().to_array()
    }

    /// Returns the id whose point `at(id)` lies nearest `p` and within `tol` of it (the least
    /// id among equally near ones) of those `accept` takes.
    pub fn find(
        &self,
        p: DVec3,
        at: impl Fn(u32) -> DVec3,
        accept: impl Fn(u32) -> bool,
    ) -> Option<u32> {
        // Cells are `2 tol` wide, so the points within `tol` lie in at most two per axis.
        let (lo, hi) = (self.key(p - self.tol), self.key(p + self.tol));
        let mut best: Option<(f64, u32)> = None;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut id = self.cells.get(&[x, y, z]).copied().unwrap_or(u32::MAX);
                    while id != u32::MAX {
                        let d2 = (at(id) - p).length_squared();
                        if d2 <= self.tol2 && best.is_none_or(|b| (d2, id) < b) && accept(id) {
                            best = Some((d2, id));
                        }
                        id = self.next[id as usize];
                    }
                }
            }
        }
        best.map(|b| b.1)
    }

    /// Inserts point `p` under `id`.
    pub fn insert(&mut self, id: u32, p: DVec3) {
        if self.next.len() <= id as usize {
            self.next.resize(id as usize + 1, u32::MAX);
        }
        let key = self.key(p);
        self.next[id as usize] = self.cells.insert(key, id).unwrap_or(u32::MAX);
    }
}

fn finish(out: &mut Vec<u32>) {
    out.sort_unstable();
    out.dedup();
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::rng::Pcg32;

    fn random_box(rng: &mut Pcg32, size: f32) -> (Vec3, Vec3) {
        let lo = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 100.0;
        let ext = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * size;
        (lo, lo + ext)
    }

    fn overlaps(a: (Vec3, Vec3), b: (Vec3, Vec3)) -> bool {
        !(a.0.cmpgt(b.1).any() || b.0.cmpgt(a.1).any())
    }

    #[test]
    fn box_queries_return_every_overlapping_box() {
        let mut rng = Pcg32::new(11, 1);
        // Mostly small boxes and a few huge ones (which go to the large list).
        let boxes: Vec<_> = (0..2000)
            .map(|i| random_box(&mut rng, if i % 100 == 0 { 90.0 } else { 3.0 }))
            .collect();
        let grid = BoxGrid::over(&boxes);
        let mut out = Vec::new();
        for _ in 0..500 {
            let q = random_box(&mut rng, 10.0);
            grid.query_box(q.0, q.1, &mut out);
            let expected: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| overlaps(boxes[i as usize], q))
                .collect();
            assert!(expected.iter().all(|i| out.binary_search(i).is_ok()));
            assert!(out.windows(2).all(|w| w[0] < w[1]), "sorted, no duplicates");
        }
    }

    #[test]
    fn point_index_welds_across_cell_boundaries() {
        let points = [
            DVec3::new(0.999_999, 0.0, 0.0),
            DVec3::new(1.000_001, 0.0, 0.0),
            DVec3::new(1.1, 0.0, 0.0),
        ];
        let mut index = PointIndex::new(1e-3);
        index.insert(0, points[0]);
        let at = |i: u32| points[i as usize];
        assert_eq!(index.find(points[1], at, |_| true), Some(0));
        assert_eq!(index.find(points[1], at, |_| false), None);
        assert_eq!(index.find(points[2], at, |_| true), None);
    }

    #[test]
    fn segment_queries_return_every_box_near_the_segment() {
        let mut rng = Pcg32::new(12, 1);
        let boxes: Vec<_> = (0..3000).map(|_| random_box(&mut rng, 2.0)).collect();
        let grid = BoxGrid::over(&boxes);
        let mut out = Vec::new();
        for _ in 0..300 {
            let (p, q) = random_box(&mut rng, 80.0);
            grid.query_segment(p, q, 0.01, &mut out);
            for (i, b) in boxes.iter().enumerate() {
                // Distance from the segment to the box, by dense sampling of the segment.
                let near = (0..=400).any(|k| {
                    let c = p.lerp(q, k as f32 / 400.0);
                    overlaps(*b, (c - Vec3::splat(0.01), c + Vec3::splat(0.01)))
                });
                if near {
                    assert!(out.binary_search(&(i as u32)).is_ok(), "box {i} missed");
                }
            }
        }
    }
}
