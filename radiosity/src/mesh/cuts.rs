//! D0 discontinuities of one face: the segments of its plane along which it must be cut, found
//! among the faces near it, and the faces that cover it.
//!
//! - A face of another plane that crosses or touches this one cuts it along the segment where
//!   it meets the plane (a block standing on a floor, water poking through a wall). When part
//!   of that face lies in front, the cut is tagged with its normal: the wall that stands there,
//!   which [`super::surface`] uses to find regions enclosed by contact.
//! - A parallel face lying close in front (between `tol` and `gap`; a light hung a hair below
//!   a ceiling, a book on a table) covers it: the face is cut along the outline of the cover
//!   (its edges not shared with a neighbour of its own plane) and the covered pieces are hidden.
//!   Two faces facing the same way within `tol` of one plane (a rug laid on a floor, a panel
//!   1e-6 above it) would both receive the same light: the one in front, or the later in the
//!   file when neither is (as a decal is drawn over what is under it), covers the other.

use glam::{DVec2, DVec3};

use super::input::Input;
use super::piece::{self, Cut, Frame, Piece, Tag};
use crate::grid::BoxGrid;

/// Normals closer than this (cosine) are parallel.
pub const PARALLEL: f64 = 0.999;

/// Everything cutting needs about the whole input.
pub struct Context<'a> {
    /// The welded input.
    pub input: &'a Input,
    /// Faces by their boxes widened by `tol`.
    pub grid: BoxGrid,
    /// Points closer than this are one point.
    pub tol: f64,
    /// Parallel faces closer than this cover each other.
    pub gap: f64,
}

impl Context<'_> {
    /// Builds the search structures over `input`.
    pub fn new(input: &Input, tol: f64, gap: f64) -> Context<'_> {
        let boxes: Vec<(glam::Vec3, glam::Vec3)> = input
            .faces
            .iter()
            .map(|f| {
                let p = f.v.map(|i| input.positions[i as usize]);
                let pad = DVec3::splat(tol);
                (
                    (p[0].min(p[1]).min(p[2]) - pad).as_vec3(),
                    (p[0].max(p[1]).max(p[2]) + pad).as_vec3(),
                )
            })
            .collect();
        Context {
            input,
            grid: BoxGrid::over(&boxes),
            tol,
            gap,
        }
    }

    fn corners(&self, f: usize) -> [DVec3; 3] {
        self.input.faces[f]
            .v
            .map(|i| self.input.positions[i as usize])
    }

    /// Cuts face `f` into pieces: the cuts and covers found among its neighbours, applied once
    /// each. Returns the pieces (`None` when the face stays whole and visible) and the number
    /// of cuts made.
    pub fn cut_face(&self, f: usize, near: &mut Vec<u32>) -> (Option<Vec<Piece>>, usize) {
        let face = &self.input.faces[f];
        let v = self.corners(f);
        if face_width(v) < self.tol {
            return (None, 0); // a sliver: never cut, only bisected along its length
        }
        let frame = Frame::of(v, face.normal);
        // What can cut the face touches its box; what can cover it lies in front within `gap`.
        let lo = v[0].min(v[1]).min(v[2]);
        let hi = v[0].max(v[1]).max(v[2]);
        let front = face.normal * self.gap;
        self.grid.query_box(
            lo.min(lo + front).as_vec3(),
            hi.max(hi + front).as_vec3(),
            near,
        );
        let mut cuts: Vec<Cut> = Vec::new();
        let mut covers: Vec<[DVec2; 3]> = Vec::new();
        for &g in near.iter() {
            let g = g as usize;
            if g == f {
                continue;
            }
            let other = &self.input.faces[g];
            let w = self.corners(g);
            let h = w.map(|p| frame.height(p));
            if face.normal.dot(other.normal).abs() > PARALLEL {
                if self.covers(f, g, h, &frame) {
                    covers.push(w.map(|p| frame.plane_point(p)));
                    self.outline(g, &frame, &mut cuts);
                }
                continue;
            }
            if let Some((a, b)) = meet(&frame, w, h, self.tol) {
                let wall = if h.iter().any(|&x| x > self.tol) {
                    other.normal.as_vec3()
                } else {
                    glam::Vec3::ZERO
                };
                cuts.push(Cut {
                    a,
                    b,
                    tag: Tag { wall },
                });
            }
        }
        let count = cuts.len();
        if count == 0 && covers.is_empty() {
            return (None, 0);
        }
        let mut pieces = vec![piece::whole(v, &frame)];
        for cut in &cuts {
            piece::apply(&mut pieces, cut, self.tol);
        }
        if !covers.is_empty() {
            for p in &mut pieces {
                let c = piece::centroid(p);
                p.hidden = covers.iter().any(|t| piece::inside_triangle(c, *t));
            }
        }
        let whole = pieces.len() == 1 && !pieces[0].hidden && count == 0;
        ((!whole).then_some(pieces), count)
    }

    /// Whether the parallel face `g`, its corners at heights `h` over the plane of face `f`
    /// (`frame`), covers `f`: it lies close in front, or it faces the same way within `tol` of
    /// the plane, overlaps `f` (not merely touches it, as the next triangle of the same surface
    /// does) and is in front (by more than rounding) or, level with it, later in the file.
    fn covers(&self, f: usize, g: usize, h: [f64; 3], frame: &Frame) -> bool {
        if h.iter().all(|&x| x > self.tol && x <= self.gap) {
            return true;
        }
        let same_way = self.input.faces[f].normal.dot(self.input.faces[g].normal) > PARALLEL;
        if !same_way || h.iter().any(|&x| x.abs() > self.tol) {
            return false;
        }
        let flat = |t: [DVec3; 3]| t.map(|p| frame.plane_point(p));
        if !overlap(flat(self.corners(f)), flat(self.corners(g)), self.tol) {
            return false;
        }
        let mean = (h[0] + h[1] + h[2]) / 3.0;
        let level = 1e-3 * self.tol;
        mean > level || (mean.abs() <= level && g > f)
    }

    /// Adds the edges of face `g` that bound its surface (no neighbour of its plane shares
    /// them), projected into `frame`, as untagged-wall cuts.
    fn outline(&self, g: usize, frame: &Frame, cuts: &mut Vec<Cut>) {
        let face = &self.input.faces[g];
        for k in 0..3 {
            let (a, b) = (face.v[k], face.v[(k + 1) % 3]);
            let shared = self.input.edge_uses(a, b).iter().any(|u| {
                let o = u.face() as usize;
                o != g && self.input.faces[o].normal.dot(face.normal) > PARALLEL
            });
            if !shared {
                let (pa, pb) = (
                    self.input.positions[a as usize],
                    self.input.positions[b as usize],
                );
                cuts.push(Cut {
                    a: frame.project(pa),
                    b: frame.project(pb),
                    tag: Tag {
                        wall: glam::Vec3::ZERO,
                    },
                });
            }
        }
    }
}

/// Twice the area over the longest edge: how narrow a triangle is.
fn face_width(v: [DVec3; 3]) -> f64 {
    let longest = (0..3)
        .map(|i| (v[(i + 1) % 3] - v[i]).length())
        .fold(0.0, f64::max);
    (v[1] - v[0]).cross(v[2] - v[0]).length() / longest.max(f64::MIN_POSITIVE)
}

/// The segment where triangle `w` (heights `h` over the plane of `frame`) meets that plane,
/// when it has two distinct points: corners within `tol` of the plane lie in it.
fn meet(frame: &Frame, w: [DVec3; 3], h: [f64; 3], tol: f64) -> Option<(piece::Pt, piece::Pt)> {
    let s = h.map(|x| {
        if x > tol {
            1
        } else if x < -tol {
            -1
        } else {
            0
        }
    });
    if s.iter().all(|&x| x == 0) {
        return None;
    }
    let mut pts: smallvec::SmallVec<[DVec3; 3]> = smallvec::SmallVec::new();
    for i in 0..3 {
        let j = (i + 1) % 3;
        if s[i] == 0 {
            pts.push(w[i]);
        } else if s[i] * s[j] < 0 {
            let (lo, hi) = if (w[i].x, w[i].y, w[i].z) < (w[j].x, w[j].y, w[j].z) {
                (i, j)
            } else {
                (j, i)
            };
            pts.push(w[lo].lerp(w[hi], h[lo] / (h[lo] - h[hi])));
        }
    }
    if pts.len() != 2 || (pts[0] - pts[1]).length() <= tol {
        return None;
    }
    Some((frame.project(pts[0]), frame.project(pts[1])))
}

/// Whether two triangles of one plane overlap by more than `tol` (separating axes: an edge of
/// either along which they are apart, or touch within `tol`, separates them).
fn overlap(a: [DVec2; 3], b: [DVec2; 3], tol: f64) -> bool {
    let apart = |t: [DVec2; 3], u: [DVec2; 3]| {
        (0..3).any(|i| {
            let e = t[(i + 1) % 3] - t[i];
            let n = DVec2::new(-e.y, e.x).normalize_or_zero();
            if n == DVec2::ZERO {
                return false;
            }
            let range = |p: [DVec2; 3]| {
                p.iter()
                    .map(|q| n.dot(*q))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                        (lo.min(x), hi.max(x))
                    })
            };
            let ((t0, t1), (u0, u1)) = (range(t), range(u));
            t1 <= u0 + tol || u1 <= t0 + tol
        })
    };
    !apart(a, b) && !apart(b, a)
}
