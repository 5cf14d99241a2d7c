//! The path tracer's own acceleration: a binary bounding-volume hierarchy over `f64` triangles,
//! split at the median centroid of the longest axis. Deliberately simple and independent of the
//! solver's octree, so that the two cannot share a bug.

use glam::DVec3;

/// A triangle in `f64`, with its precomputed edges and unit normal (right-handed winding).
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// First corner.
    pub v0: DVec3,
    /// `v1 - v0`.
    pub e1: DVec3,
    /// `v2 - v0`.
    pub e2: DVec3,
    /// Unit normal `e1 × e2 / |e1 × e2|`.
    pub normal: DVec3,
    /// Area.
    pub area: f64,
}

impl Triangle {
    /// Builds the triangle `(a, b, c)`.
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Triangle {
        let (e1, e2) = (b - a, c - a);
        let cross = e1.cross(e2);
        let len = cross.length();
        Triangle {
            v0: a,
            e1,
            e2,
            normal: if len > 0.0 { cross / len } else { DVec3::ZERO },
            area: 0.5 * len,
        }
    }

    /// Returns the point at `(u, v)` in [0,1)², mapped uniformly onto the triangle.
    pub fn sample(&self, u: f64, v: f64) -> DVec3 {
        let su = u.sqrt();
        self.v0 + self.e1 * (v * su) + self.e2 * (1.0 - su)
    }

    /// Returns the ray parameter of the hit of `o + t d` (Möller-Trumbore, either side), if any.
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let p = d.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        Some(self.e2.dot(q) * inv)
    }

    fn bounds(&self) -> (DVec3, DVec3) {
        let (a, b, c) = (self.v0, self.v0 + self.e1, self.v0 + self.e2);
        (a.min(b).min(c), a.max(b).max(c))
    }
}

/// A node: a box and either two children (`count == 0`, children at `first` and `first + 1`)
/// or a leaf of `count` triangles starting at `first` in [`Bvh::order`].
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    first: u32,
    count: u32,
}

/// The hierarchy.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// The triangles, in input order (a hit names its index here).
    pub tris: Vec<Triangle>,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF: usize = 4;

impl Bvh {
    /// Builds the hierarchy over `tris`.
    pub fn build(tris: Vec<Triangle>) -> Bvh {
        let mut bvh = Bvh {
            order: (0..tris.len() as u32).collect(),
            tris,
            nodes: Vec::new(),
        };
        bvh.nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        bvh.split(0, 0, bvh.tris.len());
        bvh
    }

    /// Makes node `at` cover `order[first..end]`, splitting it while it holds more than `LEAF`.
    fn split(&mut self, at: usize, first: usize, end: usize) {
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        let (mut clo, mut chi) = (lo, hi);
        for &t in &self.order[first..end] {
            let (a, b) = self.tris[t as usize].bounds();
            lo = lo.min(a);
            hi = hi.max(b);
            let c = (a + b) * 0.5;
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let extent = chi - clo;
        if end - first <= LEAF || extent.max_element() <= 0.0 {
            self.nodes[at] = Node {
                lo,
                hi,
                first: first as u32,
                count: (end - first) as u32,
            };
            return;
        }
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let tris = &self.tris;
        let key = |t: &u32| {
            let (a, b) = tris[*t as usize].bounds();
            (a + b)[axis]
        };
        let mid = (first + end) / 2;
        self.order[first..end]
            .select_nth_unstable_by(mid - first, |x, y| key(x).total_cmp(&key(y)));
        let left = self.nodes.len();
        self.nodes[at] = Node {
            lo,
            hi,
            first: left as u32,
            count: 0,
        };
        let empty = self.nodes[at];
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.split(left, first, mid);
        self.split(left + 1, mid, end);
    }

    /// Returns the nearest hit `(t, triangle)` of `o + t d` with `tmin < t < tmax`, skipping
    /// triangle `skip`.
    pub fn closest(
        &self,
        o: DVec3,
        d: DVec3,
        tmin: f64,
        tmax: f64,
        skip: Option<u32>,
    ) -> Option<(f64, u32)> {
        let mut best = None;
        let mut limit = tmax;
        self.walk(o, d, tmin, &mut limit, [skip, None], &mut |t, i| {
            best = Some((t, i));
            false
        });
        best
    }

    /// Whether anything other than the triangles `skip` is hit with `tmin < t < tmax`.
    pub fn occluded(
        &self,
        o: DVec3,
        d: DVec3,
        tmin: f64,
        tmax: f64,
        skip: [Option<u32>; 2],
    ) -> bool {
        let mut hit = false;
        let mut limit = tmax;
        self.walk(o, d, tmin, &mut limit, skip, &mut |_, _| {
            hit = true;
            true
        });
        hit
    }

    /// Visits the hits with `tmin < t < limit` (front to back by node, not sorted); `found`
    /// returns true to stop. `limit` shrinks to each accepted hit.
    fn walk(
        &self,
        o: DVec3,
        d: DVec3,
        tmin: f64,
        limit: &mut f64,
        skip: [Option<u32>; 2],
        found: &mut impl FnMut(f64, u32) -> bool,
    ) {
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            let t0 = (node.lo - o) * inv;
            let t1 = (node.hi - o) * inv;
            let near = t0.min(t1).max_element().max(tmin);
            let far = t0.max(t1).min_element().min(*limit);
            if near > far || near.is_nan() || far.is_nan() {
                continue;
            }
            if node.count == 0 {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
                continue;
            }
            for &i in &self.order[node.first as usize..(node.first + node.count) as usize] {
                if skip.contains(&Some(i)) {
                    continue;
                }
                if let Some(t) = self.tris[i as usize].intersect(o, d)
                    && t > tmin
                    && t < *limit
                {
                    *limit = t;
                    if found(t, i) {
                        return;
                    }
                }
            }
        }
    }
}
