//! Small geometric routines on triangles and planar polygons: areas, normals, closest points,
//! ray-triangle intersection, clipping a polygon against a plane and the segment in which two
//! triangles meet. Geometry is `f32` ([`Vec3`]); nothing here allocates except polygon clipping.

use glam::Vec3;

/// A triangle given by its three corners, counter-clockwise when seen from the front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tri {
    /// The corners.
    pub v: [Vec3; 3],
}

impl Tri {
    /// Builds a triangle from three corners.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Tri { v: [a, b, c] }
    }

    /// Returns the cross product of the two edges from corner 0 (twice the area, along the normal).
    pub fn cross(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }

    /// Returns the area.
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// Returns the unit front-face normal (zero for a degenerate triangle).
    pub fn normal(&self) -> Vec3 {
        self.cross().normalize_or_zero()
    }

    /// Returns the centroid.
    pub fn centroid(&self) -> Vec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }

    /// Returns the length of the longest edge and the index `i` of its first corner (edge i→i+1).
    pub fn longest_edge(&self) -> (f32, usize) {
        (0..3)
            .map(|i| ((self.v[(i + 1) % 3] - self.v[i]).length(), i))
            .fold((0.0, 0), |best, e| if e.0 > best.0 { e } else { best })
    }

    /// Returns the point at barycentric-square coordinates `(u, v)` in [0,1)², mapped uniformly
    /// onto the triangle (Shirley's square-to-triangle warp).
    pub fn sample(&self, u: f32, v: f32) -> Vec3 {
        let su = u.sqrt();
        let b0 = 1.0 - su;
        let b1 = v * su;
        self.v[0] * b0 + self.v[1] * b1 + self.v[2] * (1.0 - b0 - b1)
    }

    /// Returns the point of the triangle closest to `p` (Ericson, Real-Time Collision Detection 5.1.5).
    pub fn closest_point(&self, p: Vec3) -> Vec3 {
        let [a, b, c] = self.v;
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * (d1 / (d1 - d3));
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * (d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        let denom = 1.0 / (va + vb + vc);
        a + ab * (vb * denom) + ac * (vc * denom)
    }

    /// The `4^levels` triangles of splitting into [`Tri::quarters`] `levels` times.
    pub fn split(&self, levels: u32) -> Vec<Tri> {
        let mut tris = vec![*self];
        for _ in 0..levels {
            tris = tris.iter().flat_map(Tri::quarters).collect();
        }
        tris
    }

    /// The four triangles the midpoints of the edges cut this one into: one at each corner,
    /// then the middle one.
    pub fn quarters(&self) -> [Tri; 4] {
        let [a, b, c] = self.v;
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        [
            Tri::new(a, ab, ca),
            Tri::new(ab, b, bc),
            Tri::new(ca, bc, c),
            Tri::new(ab, bc, ca),
        ]
    }

    /// Returns the barycentric coordinates of `p` (assumed in the triangle's plane); `[1, 0, 0]`
    /// for a degenerate triangle.
    pub fn barycentric(&self, p: Vec3) -> [f32; 3] {
        self.barycentric_of_area(p).unwrap_or([1.0, 0.0, 0.0])
    }

    /// Whether `p` (in the triangle's plane) lies in the triangle, edges included: its
    /// [`Tri::barycentric`] coordinates are all non-negative. A degenerate triangle contains
    /// nothing.
    pub fn contains(&self, p: Vec3) -> bool {
        self.barycentric_of_area(p)
            .is_some_and(|w| w.iter().all(|&x| x >= 0.0))
    }

    /// The barycentric coordinates of `p`, `None` for a degenerate triangle.
    fn barycentric_of_area(&self, p: Vec3) -> Option<[f32; 3]> {
        let [a, b, c] = self.v;
        let (v0, v1, v2) = (b - a, c - a, p - a);
        let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
        let (d20, d21) = (v2.dot(v0), v2.dot(v1));
        let denom = d00 * d11 - d01 * d01;
        if denom == 0.0 {
            return None;
        }
        let v = (d11 * d20 - d01 * d21) / denom;
        let w = (d00 * d21 - d01 * d20) / denom;
        Some([1.0 - v - w, v, w])
    }
}

/// Returns the ray parameter `t` at which the ray `o + t d` crosses the triangle `(v0, e1, e2)`
/// (corner and two edges), Möller–Trumbore, both sides counted; `None` when it misses.
#[inline(always)]
pub fn ray_triangle(o: Vec3, d: Vec3, v0: Vec3, e1: Vec3, e2: Vec3) -> Option<f32> {
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// Clips a convex planar polygon to the half-space `n·(x - p) >= 0` (Sutherland–Hodgman).
pub fn clip_polygon(poly: &[Vec3], p: Vec3, n: Vec3) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    clip_each(poly, p, n, |x| out.push(x));
    out
}

/// [`clip_polygon`] into `out`, which must hold `poly.len() + 1` points; returns how many it
/// holds (no allocation).
pub fn clip_polygon_into(poly: &[Vec3], p: Vec3, n: Vec3, out: &mut [Vec3]) -> usize {
    let mut k = 0;
    clip_each(poly, p, n, |x| {
        out[k] = x;
        k += 1;
    });
    k
}

/// The vertices of [`clip_polygon`], in order, each passed to `push`.
fn clip_each(poly: &[Vec3], p: Vec3, n: Vec3, mut push: impl FnMut(Vec3)) {
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (n.dot(a - p), n.dot(b - p));
        if da >= 0.0 {
            push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            push(a + (b - a) * (da / (da - db)));
        }
    }
}

/// Returns the part of triangle `b`'s intersection with the plane of triangle `a` that lies
/// inside `a`, as a segment, when it has positive length. `eps` is the distance under which a
/// corner counts as lying in the plane (so that touching triangles, such as a box standing on a
/// floor, meet along the shared edge).
pub fn plane_cut_segment(a: &Tri, b: &Tri, eps: f32) -> Option<(Vec3, Vec3)> {
    let n = a.normal();
    if n == Vec3::ZERO {
        return None;
    }
    let d: [f32; 3] = std::array::from_fn(|i| {
        let s = n.dot(b.v[i] - a.v[0]);
        if s.abs() <= eps { 0.0 } else { s }
    });
    let mut pts: Vec<Vec3> = Vec::with_capacity(3);
    for i in 0..3 {
        let j = (i + 1) % 3;
        if d[i] == 0.0 {
            pts.push(b.v[i]);
        } else if d[j] != 0.0 && (d[i] > 0.0) != (d[j] > 0.0) {
            pts.push(b.v[i] + (b.v[j] - b.v[i]) * (d[i] / (d[i] - d[j])));
        }
    }
    if pts.len() != 2 || d.iter().all(|&x| x == 0.0) {
        return None; // coplanar triangles or a single touching point
    }
    clip_segment_to_triangle(a, n, pts[0], pts[1], eps)
}

/// Clips a segment lying in the plane of `t` (normal `n`) to the triangle.
fn clip_segment_to_triangle(
    t: &Tri,
    n: Vec3,
    mut p: Vec3,
    mut q: Vec3,
    eps: f32,
) -> Option<(Vec3, Vec3)> {
    for i in 0..3 {
        let (a, b) = (t.v[i], t.v[(i + 1) % 3]);
        let inward = n.cross(b - a).normalize_or_zero();
        let (dp, dq) = (inward.dot(p - a), inward.dot(q - a));
        if dp < -eps && dq < -eps {
            return None;
        }
        if dp < 0.0 && dq > 0.0 {
            p += (q - p) * (dp / (dp - dq));
        } else if dq < 0.0 && dp > 0.0 {
            q += (p - q) * (dq / (dq - dp));
        }
    }
    ((q - p).length() > eps).then_some((p, q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_inside_and_outside() {
        let t = Tri::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(
            t.closest_point(Vec3::new(0.25, 0.25, 1.0)),
            Vec3::new(0.25, 0.25, 0.0)
        );
        assert_eq!(t.closest_point(Vec3::new(-1.0, -1.0, 0.0)), Vec3::ZERO);
    }

    #[test]
    fn touching_triangles_meet_along_the_edge() {
        let floor = Tri::new(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 0.0),
        );
        let wall = Tri::new(
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(3.0, 0.0, 1.0),
            Vec3::new(1.0, 2.0, 1.0),
        );
        let (p, q) = plane_cut_segment(&floor, &wall, 1e-4).expect("segment");
        assert!((p - q).length() > 1.9);
    }
}
