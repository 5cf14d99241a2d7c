//! Cutting one scene triangle into convex pieces along segments in its plane, and triangulating
//! a piece. Everything is in the triangle's own 2D frame, in `f64`.
//!
//! Robustness comes from one rule applied once per decision: a point within `tol` of a cut line
//! is *on* it (it goes to both sides and no point is made near it). So every point a cut makes
//! lies at least `tol` from the points it was made between, a cut never leaves a chord shorter
//! than `tol`, and no edge shorter than `tol` is ever made: cutting finishes, and `k` cuts make
//! at most `1 + k + k(k-1)/2` pieces (the regions of `k` lines in a convex region).

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

/// What a piece edge lies on: a discontinuity line, and the normal of the surface that stands
/// on it in front of the cut face (zero when there is none: the surface lies behind, or the
/// line is the outline of a covering surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tag {
    /// Normal of the surface standing on the line in front, or zero.
    pub wall: glam::Vec3,
}

/// The tags of one edge (most edges have none).
pub type Tags = SmallVec<[Tag; 1]>;

/// A point of a piece: in the face's 2D frame and in 3D.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pt {
    /// In the face's frame.
    pub q: DVec2,
    /// In space.
    pub p: DVec3,
}

/// A convex piece of a face, counter-clockwise; `tags[i]` belongs to the edge from point `i` to
/// point `i + 1`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Piece {
    /// Corners (and points lying on its edges).
    pub pts: Vec<Pt>,
    /// Tags per edge.
    pub tags: Vec<Tags>,
    /// Covered by a parallel surface close in front of it.
    pub hidden: bool,
}

/// A face's 2D frame: origin and two unit axes in its plane, counter-clockwise seen from the
/// front.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Origin.
    pub o: DVec3,
    /// First axis.
    pub u: DVec3,
    /// Second axis (normal × u).
    pub w: DVec3,
    /// Unit normal.
    pub n: DVec3,
}

impl Frame {
    /// The frame of triangle `v` with unit normal `n`.
    pub fn of(v: [DVec3; 3], n: DVec3) -> Frame {
        let u = (v[1] - v[0]).normalize();
        Frame {
            o: v[0],
            u,
            w: n.cross(u),
            n,
        }
    }

    /// `p` (projected onto the plane) in frame coordinates.
    pub fn plane_point(&self, p: DVec3) -> DVec2 {
        let r = p - self.o;
        DVec2::new(r.dot(self.u), r.dot(self.w))
    }

    /// Signed distance of `p` from the plane (positive in front).
    pub fn height(&self, p: DVec3) -> f64 {
        self.n.dot(p - self.o)
    }

    /// The point of the plane under `p`.
    pub fn project(&self, p: DVec3) -> Pt {
        Pt {
            q: self.plane_point(p),
            p: p - self.n * self.height(p),
        }
    }
}

/// A cut: the segment `a..b` of the face plane (frame coordinates and space), with its tag.
#[derive(Clone, Copy, Debug)]
pub struct Cut {
    /// One end.
    pub a: Pt,
    /// The other end.
    pub b: Pt,
    /// What the line is.
    pub tag: Tag,
}

/// The triangle itself as one piece.
pub fn whole(v: [DVec3; 3], frame: &Frame) -> Piece {
    Piece {
        pts: v
            .map(|p| Pt {
                q: frame.plane_point(p),
                p,
            })
            .to_vec(),
        tags: vec![Tags::new(); 3],
        hidden: false,
    }
}

/// Applies `cut` to every piece it crosses (pieces made by this cut are not cut again by it).
pub fn apply(pieces: &mut Vec<Piece>, cut: &Cut, tol: f64) {
    let len = (cut.b.q - cut.a.q).length();
    if len <= tol {
        return;
    }
    for i in 0..pieces.len() {
        if let Some(other) = split(&mut pieces[i], cut, len, tol) {
            pieces.push(other);
        }
    }
}

/// Which side of the line a distance puts a point: 1, -1, or 0 (within `tol`: on the line).
fn side(s: f64, tol: f64) -> i8 {
    if s > tol {
        1
    } else if s < -tol {
        -1
    } else {
        0
    }
}

/// Cuts `piece` along the line of `cut`; returns the second half when it was split. A piece the
/// line only runs along gets the tag on that edge instead.
fn split(piece: &mut Piece, cut: &Cut, len: f64, tol: f64) -> Option<Piece> {
    let dir = (cut.b.q - cut.a.q) / len;
    let m = dir.perp();
    let n = piece.pts.len();
    let s: Vec<f64> = piece.pts.iter().map(|x| m.dot(x.q - cut.a.q)).collect();
    let c: Vec<i8> = s.iter().map(|&x| side(x, tol)).collect();
    let t = |x: &Pt| dir.dot(x.q - cut.a.q);
    if !c.contains(&1) || !c.contains(&-1) {
        tag_along(piece, &c, cut, len, tol);
        return None;
    }
    // Crossing points, each computed once from its edge's ends in a fixed order (so the same
    // edge gives the same point in every piece that has it).
    let crossing = |i: usize| {
        let j = (i + 1) % n;
        let (lo, hi) =
            if (piece.pts[i].q.x, piece.pts[i].q.y) <= (piece.pts[j].q.x, piece.pts[j].q.y) {
                (i, j)
            } else {
                (j, i)
            };
        let f = s[lo] / (s[lo] - s[hi]);
        let (a, b) = (piece.pts[lo], piece.pts[hi]);
        Pt {
            q: a.q + (b.q - a.q) * f,
            p: a.p + (b.p - a.p) * f,
        }
    };
    let mut on_line: Vec<f64> = Vec::with_capacity(2);
    let mut xs: Vec<Option<Pt>> = vec![None; n];
    for i in 0..n {
        let j = (i + 1) % n;
        if c[i] == 0 {
            on_line.push(t(&piece.pts[i]));
        }
        if c[i] * c[j] < 0 {
            let x = crossing(i);
            on_line.push(t(&x));
            xs[i] = Some(x);
        }
    }
    let lo = on_line.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = on_line.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi - lo <= tol || hi.min(len) - lo.max(0.0) <= tol {
        return None; // a chord too short to cut, or the segment misses this piece
    }
    let half = |sign: i8| {
        let mut out = Piece {
            pts: Vec::with_capacity(n + 2),
            tags: Vec::with_capacity(n + 2),
            hidden: piece.hidden,
        };
        let mut chord = usize::MAX;
        for i in 0..n {
            let j = (i + 1) % n;
            let (ci, cj) = (c[i] * sign, c[j] * sign);
            if ci >= 0 {
                if cj < 0 {
                    if ci > 0 {
                        out.pts.push(piece.pts[i]);
                        out.tags.push(piece.tags[i].clone());
                        out.pts.push(xs[i].expect("crossing"));
                    } else {
                        out.pts.push(piece.pts[i]);
                    }
                    chord = out.tags.len();
                    out.tags.push(Tags::new());
                } else {
                    out.pts.push(piece.pts[i]);
                    out.tags.push(piece.tags[i].clone());
                }
            } else if cj > 0 {
                out.pts.push(xs[i].expect("crossing"));
                out.tags.push(piece.tags[i].clone());
            }
        }
        insert_segment_ends(&mut out, chord, cut, len, tol);
        out
    };
    let plus = half(1);
    let minus = half(-1);
    *piece = plus;
    Some(minus)
}

/// Puts the segment's ends on edge `e` of `piece` (which lies on the cut line) where they fall
/// strictly inside it, and tags the part of the edge the segment covers.
fn insert_segment_ends(piece: &mut Piece, e: usize, cut: &Cut, len: f64, tol: f64) {
    let n = piece.pts.len();
    let (x, y) = (piece.pts[e], piece.pts[(e + 1) % n]);
    let dir = (cut.b.q - cut.a.q) / len;
    let t = |q: DVec2| dir.dot(q - cut.a.q);
    let (tx, ty) = (t(x.q), t(y.q));
    let mut inner: SmallVec<[(f64, Pt); 2]> = SmallVec::new();
    for tc in [0.0, len] {
        let f = (tc - tx) / (ty - tx);
        if (tc - tx).abs() > tol && (tc - ty).abs() > tol && f > 0.0 && f < 1.0 {
            inner.push((
                f,
                Pt {
                    q: x.q.lerp(y.q, f),
                    p: x.p.lerp(y.p, f),
                },
            ));
        }
    }
    inner.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut pts: SmallVec<[Pt; 4]> = SmallVec::new();
    pts.push(x);
    pts.extend(inner.iter().map(|p| p.1));
    pts.push(y);
    let mut tags: SmallVec<[Tags; 3]> = SmallVec::new();
    for k in 0..pts.len() - 1 {
        let mid = 0.5 * (t(pts[k].q) + t(pts[k + 1].q));
        let mut tg = piece.tags[e].clone();
        if mid > 0.0 && mid < len {
            tg.push(cut.tag);
        }
        tags.push(tg);
    }
    piece.tags.splice(e..=e, tags);
    piece
        .pts
        .splice(e + 1..e + 1, inner.into_iter().map(|p| p.1));
}

/// Tags the edges of `piece` that lie on the cut line (both ends within `tol` of it) where the
/// segment covers them.
fn tag_along(piece: &mut Piece, c: &[i8], cut: &Cut, len: f64, tol: f64) {
    let n = piece.pts.len();
    let dir = (cut.b.q - cut.a.q) / len;
    let t = |q: DVec2| dir.dot(q - cut.a.q);
    // From the last edge down, so insertions do not shift edges still to look at.
    for e in (0..n).rev() {
        let f = (e + 1) % n;
        if c[e] != 0 || c[f] != 0 {
            continue;
        }
        let (te, tf) = (t(piece.pts[e].q), t(piece.pts[f].q));
        if te.max(tf).min(len) - te.min(tf).max(0.0) > tol {
            insert_segment_ends(piece, e, cut, len, tol);
        }
    }
}

/// Whether 2D point `q` lies inside triangle `t` (counter-clockwise or not).
pub fn inside_triangle(q: DVec2, t: [DVec2; 3]) -> bool {
    let d: [f64; 3] = std::array::from_fn(|i| (t[(i + 1) % 3] - t[i]).perp_dot(q - t[i]));
    d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0)
}

/// Whether 2D point `q` lies inside the counter-clockwise triangle `t` or within `tol` of it.
fn near_triangle(q: DVec2, t: [DVec2; 3], tol: f64) -> bool {
    (0..3).all(|i| {
        let e = t[(i + 1) % 3] - t[i];
        e.perp_dot(q - t[i]) >= -tol * e.length()
    })
}

/// The centroid of a piece's corners.
pub fn centroid(piece: &Piece) -> DVec2 {
    piece.pts.iter().map(|p| p.q).sum::<DVec2>() / piece.pts.len() as f64
}

/// Triangulates a convex polygon given by 2D points (which may include points lying on its
/// edges) by clipping ears: each ear is a corner turning left by more than `min_area` (twice
/// the triangle's area) with no other point inside it or within `tol` of its sides. Returns
/// index triples; ears that cannot be found (a polygon made degenerate by rounding) end it
/// early, dropping at most an area of `min_area` per point left.
pub fn triangulate(q: &[DVec2], min_area: f64, tol: f64) -> Vec<[usize; 3]> {
    let mut ring: Vec<usize> = (0..q.len()).collect();
    let mut out = Vec::with_capacity(q.len().saturating_sub(2));
    let turn = |a: usize, b: usize, c: usize| (q[b] - q[a]).perp_dot(q[c] - q[b]);
    let mut start = 0;
    while ring.len() > 3 {
        let n = ring.len();
        let ear = (0..n).map(|k| (start + k) % n).find(|&i| {
            let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            turn(a, b, c) > min_area
                && ring.iter().all(|&x| {
                    x == a || x == b || x == c || !near_triangle(q[x], [q[a], q[b], q[c]], tol)
                })
        });
        let Some(i) = ear else {
            return out;
        };
        out.push([ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]]);
        ring.remove(i);
        start = i % ring.len();
    }
    if ring.len() == 3 && turn(ring[0], ring[1], ring[2]) > min_area {
        out.push([ring[0], ring[1], ring[2]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> (Frame, [DVec3; 3]) {
        let v = [
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(0.0, 4.0, 0.0),
        ];
        (Frame::of(v, DVec3::Z), v)
    }

    fn cut(f: &Frame, a: (f64, f64), b: (f64, f64)) -> Cut {
        let p = |(x, y): (f64, f64)| f.project(DVec3::new(x, y, 0.0));
        Cut {
            a: p(a),
            b: p(b),
            tag: Tag {
                wall: glam::Vec3::Y,
            },
        }
    }

    fn area(piece: &Piece) -> f64 {
        let q: Vec<DVec2> = piece.pts.iter().map(|p| p.q).collect();
        (0..q.len())
            .map(|i| q[i].perp_dot(q[(i + 1) % q.len()]))
            .sum::<f64>()
            / 2.0
    }

    #[test]
    fn a_cut_splits_in_two_and_tags_only_the_segment() {
        let (f, v) = frame();
        let mut pieces = vec![whole(v, &f)];
        // A segment from (1, 1) to (2, 1): the chord runs from x = 0 to x = 3 at y = 1.
        apply(&mut pieces, &cut(&f, (1.0, 1.0), (2.0, 1.0)), 1e-9);
        assert_eq!(pieces.len(), 2);
        assert!((pieces.iter().map(area).sum::<f64>() - 8.0).abs() < 1e-12);
        for p in &pieces {
            assert!(area(p) > 0.0);
            // The chord holds the segment's ends; only the part between them is tagged.
            let tagged: Vec<usize> = (0..p.tags.len())
                .filter(|&i| !p.tags[i].is_empty())
                .collect();
            assert_eq!(tagged.len(), 1, "{p:?}");
            let i = tagged[0];
            let (a, b) = (p.pts[i].q, p.pts[(i + 1) % p.pts.len()].q);
            assert!((a.x.min(b.x) - 1.0).abs() < 1e-12 && (a.x.max(b.x) - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn points_within_tol_of_the_line_are_on_it() {
        let (f, v) = frame();
        let mut pieces = vec![whole(v, &f)];
        // A line through the corner (0, 0) within 1e-7: no point is made near that corner.
        apply(&mut pieces, &cut(&f, (1e-7, 0.0), (2.0, 2.0)), 1e-6);
        assert_eq!(pieces.len(), 2);
        for p in &pieces {
            assert_eq!(p.pts.len(), 3, "{p:?}");
        }
        // A segment that only nicks the piece within tol does nothing.
        let before = pieces.clone();
        apply(
            &mut pieces,
            &cut(&f, (4.0 + 5e-7, -1.0), (4.0 + 5e-7, 1.0)),
            1e-6,
        );
        assert_eq!(pieces, before);
    }

    #[test]
    fn many_crossing_cuts_stay_within_the_arrangement_bound() {
        let (f, v) = frame();
        let mut pieces = vec![whole(v, &f)];
        let k = 12;
        for i in 0..k {
            let a = i as f64 * 0.37;
            apply(
                &mut pieces,
                &cut(
                    &f,
                    (0.2 + a.cos(), 0.2 + a.sin()),
                    (2.0 - a.sin(), 1.0 + a.cos()),
                ),
                1e-9,
            );
        }
        assert!(pieces.len() <= 1 + k + k * (k - 1) / 2, "{}", pieces.len());
        assert!((pieces.iter().map(area).sum::<f64>() - 8.0).abs() < 1e-9);
        for p in &pieces {
            let q: Vec<DVec2> = p.pts.iter().map(|x| x.q).collect();
            let tris = triangulate(&q, 1e-18, 1e-9);
            let sum: f64 = tris
                .iter()
                .map(|t| (q[t[1]] - q[t[0]]).perp_dot(q[t[2]] - q[t[0]]) / 2.0)
                .sum();
            assert!((sum - area(p)).abs() < 1e-9 * area(p).max(1.0));
        }
    }

    #[test]
    fn triangulation_handles_points_on_edges() {
        // A triangle with a point in the middle of each side: 4 triangles, none degenerate.
        let q = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 2.0),
            DVec2::new(0.0, 1.0),
        ];
        let tris = triangulate(&q, 1e-12, 1e-9);
        assert_eq!(tris.len(), 4);
    }
}
