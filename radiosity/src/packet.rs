//! Four triangles tested against one ray at once: the unit of geometry a voxel embeds.
//!
//! A [`TriPacket`] stores four triangles as a structure of arrays (one coordinate of all four
//! in each `Vec4`), so that the Möller–Trumbore test runs on all four lanes with the SIMD
//! instructions every x86-64 has, with no branch per triangle. An unused lane holds a triangle
//! with zero edges, which no ray hits (its determinant is zero).
//!
//! A [`BoxGroup`] holds the boxes of four packets (each box clipped to the voxel that holds the
//! packet and widened by a margin), tested together first: most rays that enter a voxel miss its
//! triangles' boxes, above all the rays that leave or graze a wall, whose voxels hold flat boxes.
//!
//! Contract: for every lane, [`TriPacket::intersect`] computes exactly what the scalar
//! [`ray_triangle`](crate::geom::ray_triangle) computes for that triangle (the same operations in
//! the same order, so the same rounding): a ray hits a lane here if and only if it hits the
//! triangle there. The octree's equality with a brute-force test rests on this, and on the boxes
//! being conservative (a box test may pass a packet that then misses, never the reverse).

use glam::{Vec3, Vec4};

use crate::geom::Tri;

/// Four triangles in structure-of-arrays form: corner 0 and the two edges from it.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriPacket {
    /// x, y and z of corner 0 of each lane.
    pub v0: [Vec4; 3],
    /// x, y and z of corner 1 minus corner 0.
    pub e1: [Vec4; 3],
    /// x, y and z of corner 2 minus corner 0.
    pub e2: [Vec4; 3],
}

/// Lanes in a packet (and packets in a box group).
pub const LANES: usize = 4;

/// The id an unused lane carries.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// A ray prepared for packet and box tests: every component splatted across the lanes.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    o: [Vec4; 3],
    d: [Vec4; 3],
    /// `1 / d` (where finite).
    inv: [Vec4; 3],
    /// Axes along which the ray does not move (`1 / d` infinite): there a box is met when the
    /// origin lies within its slab, whatever `t`, and the slab product would give NaN on a face.
    parallel: [bool; 3],
    any_parallel: bool,
    tmin: f32,
    tmax: f32,
}

impl RayQuery {
    /// Prepares `o + t d`, `tmin < t < tmax`.
    #[inline]
    pub fn new(o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> RayQuery {
        let inv = (Vec3::ONE / d).to_array();
        RayQuery {
            o: o.to_array().map(Vec4::splat),
            d: d.to_array().map(Vec4::splat),
            inv: inv.map(|i| Vec4::splat(if i.is_finite() { i } else { 0.0 })),
            parallel: inv.map(|i| !i.is_finite()),
            any_parallel: inv.iter().any(|i| !i.is_finite()),
            tmin,
            tmax,
        }
    }
}

impl TriPacket {
    /// A packet of four unused lanes.
    pub const EMPTY: TriPacket = TriPacket {
        v0: [Vec4::ZERO; 3],
        e1: [Vec4::ZERO; 3],
        e2: [Vec4::ZERO; 3],
    };

    /// Packs up to four triangles (extra lanes stay unused).
    pub fn pack<'a>(tris: impl IntoIterator<Item = &'a Tri>) -> TriPacket {
        let mut p = TriPacket::EMPTY;
        for (lane, t) in tris.into_iter().take(LANES).enumerate() {
            p.set_lane(lane, t.v[0], t.v[1] - t.v[0], t.v[2] - t.v[0]);
        }
        p
    }

    /// Stores corner `v0` and edges `e1`, `e2` in `lane`.
    pub fn set_lane(&mut self, lane: usize, v0: Vec3, e1: Vec3, e2: Vec3) {
        for axis in 0..3 {
            self.v0[axis][lane] = v0[axis];
            self.e1[axis][lane] = e1[axis];
            self.e2[axis][lane] = e2[axis];
        }
    }

    /// Returns corner 0 and the two edges of `lane`.
    pub fn lane(&self, lane: usize) -> (Vec3, Vec3, Vec3) {
        let get = |v: &[Vec4; 3]| Vec3::new(v[0][lane], v[1][lane], v[2][lane]);
        (get(&self.v0), get(&self.e1), get(&self.e2))
    }

    /// Returns the bounding box `(lo, hi)` of the used lanes (`lanes` of them).
    pub fn bounds(&self, lanes: usize) -> (Vec3, Vec3) {
        (0..lanes.min(LANES)).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), lane| {
            let (v0, e1, e2) = self.lane(lane);
            let (v1, v2) = (v0 + e1, v0 + e2);
            (lo.min(v0).min(v1).min(v2), hi.max(v0).max(v1).max(v2))
        })
    }

    /// Returns the lanes hit by the ray within `tmin < t < tmax` as a bit mask (bit `i` for
    /// lane `i`), and the hit parameter of every lane (meaningful only where the bit is set).
    #[inline(always)]
    pub fn intersect(&self, r: &RayQuery) -> (u32, Vec4) {
        let [dx, dy, dz] = r.d;
        let [e1x, e1y, e1z] = self.e1;
        let [e2x, e2y, e2z] = self.e2;
        // p = d × e2, det = e1 · p
        let px = dy * e2z - e2y * dz;
        let py = dz * e2x - e2z * dx;
        let pz = dx * e2y - e2x * dy;
        let det = (e1x * px) + (e1y * py) + (e1z * pz);
        let inv = Vec4::ONE / det;
        // s = o - v0, u = (s · p) / det
        let sx = r.o[0] - self.v0[0];
        let sy = r.o[1] - self.v0[1];
        let sz = r.o[2] - self.v0[2];
        let u = ((sx * px) + (sy * py) + (sz * pz)) * inv;
        // q = s × e1, v = (d · q) / det, t = (e2 · q) / det
        let qx = sy * e1z - e1y * sz;
        let qy = sz * e1x - e1z * sx;
        let qz = sx * e1y - e1x * sy;
        let v = ((dx * qx) + (dy * qy) + (dz * qz)) * inv;
        let t = ((e2x * qx) + (e2y * qy) + (e2z * qz)) * inv;
        let hit = det.abs().cmpge(Vec4::splat(1e-20))
            & u.cmpge(Vec4::ZERO)
            & u.cmple(Vec4::ONE)
            & v.cmpge(Vec4::ZERO)
            & (u + v).cmple(Vec4::ONE)
            & t.cmpgt(Vec4::splat(r.tmin))
            & t.cmplt(Vec4::splat(r.tmax));
        (hit.bitmask(), t)
    }
}

/// The boxes of four packets in structure-of-arrays form.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxGroup {
    /// x, y and z of the low corners (`sides[0]`) and of the high corners (`sides[1]`).
    pub sides: [[Vec4; 3]; 2],
}

impl BoxGroup {
    /// A group whose boxes no ray meets: each is the point (1e30, 1e30, 1e30), whose parameter
    /// along any ray from inside a scene is beyond ±1e25 (and if a pathological ray did meet
    /// it, the unused packet behind it has no triangle to hit).
    ///
    /// [`BoxGroup::hits`] is exact for flat boxes (`lo == hi` on an axis) and for rays parallel
    /// to a face, including rays lying in the face.
    pub const EMPTY: BoxGroup = BoxGroup {
        sides: [[Vec4::splat(1e30); 3]; 2],
    };

    /// Sets box `lane` to `lo..hi` widened by `margin` on every side.
    pub fn set_lane(&mut self, lane: usize, lo: Vec3, hi: Vec3, margin: f32) {
        for axis in 0..3 {
            self.sides[0][axis][lane] = lo[axis] - margin;
            self.sides[1][axis][lane] = hi[axis] + margin;
        }
    }

    /// Returns the boxes the ray's segment `tmin < t < tmax` may meet, as a bit mask (slab test).
    #[inline(always)]
    pub fn hits(&self, r: &RayQuery) -> u32 {
        if r.any_parallel {
            return self.hits_parallel(r);
        }
        self.hits_by(r, |axis| self.slab(r, axis))
    }

    /// [`BoxGroup::hits`] for a ray that does not move along some axis: there the slab is open
    /// where the origin lies between the faces and empty elsewhere.
    #[cold]
    fn hits_parallel(&self, r: &RayQuery) -> u32 {
        let [lo, hi] = &self.sides;
        self.hits_by(r, |axis| {
            if !r.parallel[axis] {
                return self.slab(r, axis);
            }
            let inside = lo[axis].cmple(r.o[axis]) & r.o[axis].cmple(hi[axis]);
            let open = Vec4::select(inside, Vec4::NEG_INFINITY, Vec4::INFINITY);
            (open, -open)
        })
    }

    /// The parameters at which the ray enters and leaves each box's slab on `axis`.
    #[inline(always)]
    fn slab(&self, r: &RayQuery, axis: usize) -> (Vec4, Vec4) {
        let t1 = (self.sides[0][axis] - r.o[axis]) * r.inv[axis];
        let t2 = (self.sides[1][axis] - r.o[axis]) * r.inv[axis];
        (t1.min(t2), t1.max(t2))
    }

    /// Intersects the three slabs `slab(axis)` with `tmin..tmax`; a bit for each non-empty one.
    #[inline(always)]
    fn hits_by(&self, r: &RayQuery, slab: impl Fn(usize) -> (Vec4, Vec4)) -> u32 {
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let near = nx.max(ny).max(nz).max(Vec4::splat(r.tmin));
        let far = fx.min(fy).min(fz).min(Vec4::splat(r.tmax));
        near.cmple(far).bitmask()
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::geom::ray_triangle;
    use crate::rng::Pcg32;

    fn random_vec(rng: &mut Pcg32) -> Vec3 {
        Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE
    }

    fn random_tris(rng: &mut Pcg32, n: usize) -> Vec<Tri> {
        (0..n)
            .map(|_| Tri::new(random_vec(rng), random_vec(rng), random_vec(rng)))
            .collect()
    }

    #[test]
    fn every_lane_answers_as_the_scalar_test() {
        let mut rng = Pcg32::new(3, 3);
        let mut hits = 0;
        for _ in 0..20_000 {
            let tris = random_tris(&mut rng, 3);
            let p = TriPacket::pack(&tris);
            let (o, d) = (random_vec(&mut rng) * 2.0, random_vec(&mut rng));
            let (mask, t) = p.intersect(&RayQuery::new(o, d, 0.0, 3.0));
            for (lane, tri) in tris.iter().enumerate() {
                let (v0, e1, e2) = p.lane(lane);
                let scalar = ray_triangle(o, d, v0, e1, e2).filter(|&h| h > 0.0 && h < 3.0);
                assert_eq!(mask & (1 << lane) != 0, scalar.is_some(), "{tri:?} {o} {d}");
                if let Some(h) = scalar {
                    assert_eq!(t[lane], h);
                    hits += 1;
                }
            }
            assert_eq!(mask & 0b1000, 0, "the unused lane is never hit");
        }
        assert!(hits > 500, "{hits}");
    }

    #[test]
    fn a_box_passes_every_ray_that_hits_its_packet() {
        let mut rng = Pcg32::new(5, 5);
        for _ in 0..20_000 {
            let tris = random_tris(&mut rng, 4);
            let p = TriPacket::pack(&tris);
            let mut group = BoxGroup::EMPTY;
            let (lo, hi) = p.bounds(4);
            group.set_lane(2, lo, hi, 1e-6);
            let r = RayQuery::new(random_vec(&mut rng) * 2.0, random_vec(&mut rng), 0.0, 3.0);
            if p.intersect(&r).0 != 0 {
                assert_eq!(group.hits(&r), 0b100);
            }
            assert_eq!(group.hits(&r) & 0b1011, 0, "unused boxes are never met");
        }
    }

    #[test]
    fn a_ray_parallel_to_a_flat_box_face_is_decided_without_nan() {
        let mut group = BoxGroup::EMPTY;
        group.set_lane(0, Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), 0.0);
        // In the box's plane: met. Just above it: not met.
        let along = RayQuery::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X, 0.0, 5.0);
        assert_eq!(group.hits(&along), 1);
        let above = RayQuery::new(Vec3::new(-1.0, 0.5, 1e-3), Vec3::X, 0.0, 5.0);
        assert_eq!(group.hits(&above), 0);
    }
}
