//! What a scene needs: the solver's stages that a scene's shape makes unnecessary, found before
//! the first shot ([`SceneAnalysis::of`]), and what is left out for it ([`Stages`]).
//!
//! - **Convex enclosure** (every patch faces inward and lies on the hull: no vertex of the scene
//!   is behind the plane of any patch, by more than the weld distance): the segment between two
//!   points of the surface runs inside the hull, so no patch can hide another and shadow rays
//!   are left out (their answer is always "visible").
//! - **Closed** (no ray leaving the front of a patch escapes: the patches, sheets apart, bound
//!   the air; [`SceneAnalysis::of`] says how this is decided for convex and non-convex scenes):
//!   all the power a shot sends must land on a surface. Each shot's form factors are then
//!   scaled so that the receivers get exactly the power sent (a form-factor row sums to one)
//!   less the share that lands on the backs of sheets ([`back_shares`]: a lamp panel hung
//!   below a ceiling takes what the ceiling sends it on its back, and absorbs it, as the path
//!   tracer does), instead of booking the quadrature error of the receivers' sampling as
//!   escaped power. In a closed room of reflectance ρ that error is multiplied by
//!   `1 / (1 - ρ)`: 0.1% of leak is 50% of error at ρ = 0.999.
//!
//! Convexity and closure are separate facts: shadow rays are left out only for a convex
//! enclosure, rows are closed for any closed scene.
//!
//! Adaptive subdivision and the analytic near-field form factor need no scene-level decision:
//! the first tests linearity edge by edge each shot, the second is chosen per receiver by its
//! distance to the source (`crate::formfactor`).
//!
//! Invariants:
//! - a stage is left out only when its answer is known without running it (the same scene with
//!   every stage on, `all_stages`, agrees within the convergence tolerance: `tests/stages.rs`);
//! - the analysis looks at the patches the solver shoots from (after meshing), not at the file.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::geom::Tri;
use crate::octree::{Octree, OctreeConfig, Traversal};
use crate::rng::Pcg32;

/// Scenes with more distinct patch planes than this are not tested for convexity (the test costs
/// planes × vertices); they keep every stage.
pub const MAX_PLANES: usize = 256;

/// Non-convex scenes with more patches than this are not tested for closure (the test costs
/// up to about 6 × patches² solid angles); they are taken to be open.
pub const MAX_ENCLOSURE_PATCHES: usize = 2048;

/// The winding number of a closed surface around its centre must be 1 within this.
pub const WINDING_TOLERANCE: f64 = 1e-4;

/// What the analysis found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SceneAnalysis {
    /// Every patch faces inward and lies on the convex hull.
    pub convex: bool,
    /// No ray leaving the front of a patch escapes: the surface, sheets apart, bounds the air
    /// (see [`SceneAnalysis::of`]).
    pub closed: bool,
    /// Distinct planes of the patches (0 when there were more than [`MAX_PLANES`]).
    pub planes: usize,
    /// Patches hung in the air, both sides facing it (a lamp panel below a ceiling): what they
    /// are sent on their backs is lost, as it is in the path tracer.
    pub sheets: usize,
}

impl SceneAnalysis {
    /// Analyses the patches of a scene whose bounding-box diagonal is `diagonal`; `hidden`
    /// marks the patches that never shoot (covered, or enclosed by contact).
    ///
    /// Closed means that every ray leaving the front of a patch meets a surface. A convex
    /// enclosure is closed when its winding number about its centre is 1 (it covers the hull).
    /// Otherwise the test is the winding number `w` of the patches (Van Oosterom and Strackee's
    /// solid angles over 4π), which is an integer off an oriented surface without boundary
    /// (every edge's two sides cancel, T-junctions and all), changes by 1 across each patch,
    /// and is fractional wherever a rim is left: at the edge of a hole and at the rim of a
    /// sheet. The surface is the visible patches (the hidden ones lie where surfaces touch: a
    /// table leg that is an open tube closes on the floor and the table's underside, whose
    /// pieces under it are hidden) or, failing that, all of them (a panel a hair below a
    /// ceiling hides the part of the ceiling it covers, which closes the ceiling); every patch
    /// either counts stops a ray, so either is a proof.
    /// 1. Sheets are found first: a patch whose two sides both face the air has `w` about 1.5
    ///    just in front and 0.5 just behind (its own half-space of solid angle either way),
    ///    while a patch bounding the air has about 1 and 0: the mean of the two, over 0.75,
    ///    marks a sheet ([`sheets`]).
    /// 2. The rest must bound the air: with the sheets left out, `w` is 1 within
    ///    [`WINDING_TOLERANCE`] just in front of every patch that shoots and on both sides of
    ///    every sheet. Then a ray from the front of a patch starts where `w` is 1 and can only
    ///    reach infinity, where `w` is 0, by crossing a patch: nothing escapes. A hole leaves
    ///    `w` short of 1 by the solid angle it subtends over 4π at every probe (an open box, a
    ///    missing wall, a gap under a door), a sheet taken for a wall leaves a rim: either
    ///    fails the test, so an error can only cost the closure, never close an open scene.
    ///
    /// Why not rays: a census of rays cast from the patches finds only the holes it happens to
    /// hit, and f32 rays slip through the seams between patches (a few in 10⁵ in a closed
    /// convex room), so "no ray escaped" is neither sufficient nor exact. Why not edges: the
    /// patches of neighbouring surfaces meet with T-junctions and welded corners, so matching
    /// edges needs the overlap arithmetic the winding number does without.
    pub fn of(patches: &[Tri], hidden: &[bool], diagonal: f32) -> SceneAnalysis {
        Self::with_sheets(patches, hidden, diagonal).0
    }

    /// [`SceneAnalysis::of`], and which patches are sheets (all false unless the scene is
    /// closed).
    pub fn with_sheets(
        patches: &[Tri],
        hidden: &[bool],
        diagonal: f32,
    ) -> (SceneAnalysis, Vec<bool>) {
        let no_sheets = vec![false; patches.len()];
        let eps = 1e-5 * diagonal.max(f32::MIN_POSITIVE);
        let Some(planes) = distinct_planes(patches, eps) else {
            return (SceneAnalysis::default(), no_sheets);
        };
        let vertices = distinct_vertices(patches);
        let convex = !planes.is_empty()
            && planes
                .iter()
                .all(|(n, d)| vertices.iter().all(|v| n.dot(*v) - d >= -eps));
        let analysis = SceneAnalysis {
            convex,
            closed: false,
            planes: planes.len(),
            sheets: 0,
        };
        if convex {
            let centre = vertices.iter().fold(Vec3::ZERO, |s, v| s + *v) / vertices.len() as f32;
            let closed = (winding_number(patches, centre) - 1.0).abs() < WINDING_TOLERANCE;
            return (SceneAnalysis { closed, ..analysis }, no_sheets);
        }
        if patches.len() > MAX_ENCLOSURE_PATCHES {
            return (analysis, no_sheets);
        }
        // The air is bounded by the visible patches (hidden ones lie in contact, where open
        // tubes such as table legs stand) or, failing that, by all of them (a panel a hair
        // below a ceiling hides the part of it that it covers): either way every patch counted
        // stops a ray.
        for surface in [Surface::Visible, Surface::All] {
            let counted = |p: usize| surface == Surface::All || !hidden[p];
            let sheet = sheets(patches, hidden, &counted, diagonal);
            let bounds: Vec<Tri> = (0..patches.len())
                .filter(|&p| counted(p) && !sheet[p])
                .map(|p| patches[p])
                .collect();
            let bounds_the_air = (0..patches.len()).into_par_iter().all(|p| {
                let [front, back] = probes(&patches[p], diagonal);
                let air = |q: DVec3| (winding_at(&bounds, q) - 1.0).abs() < WINDING_TOLERANCE;
                hidden[p] || (air(front) && (!sheet[p] || air(back)))
            });
            if bounds_the_air {
                let sheets = sheet.iter().filter(|&&s| s).count();
                let analysis = SceneAnalysis {
                    closed: true,
                    sheets,
                    ..analysis
                };
                return (analysis, sheet);
            }
        }
        (analysis, no_sheets)
    }
}

/// The triangles that can hide something: all but those lying in a face of the scene's
/// bounding box and facing into it (the floor, walls and ceiling of a room that bounds the
/// scene), unless some triangle in that face faces out.
///
/// A shadow ray runs between two points of the scene's surfaces, each lifted off its surface
/// along that surface's normal; every such point lies in the box, and on the inner side of a
/// face whose triangles all face in (a point in the face is lifted inward, one elsewhere is
/// inside already). The segment between two points on the inner side of a plane meets the
/// plane nowhere, so no triangle of that face can block it: testing them costs every ray and
/// answers nothing (the Cornell box: 8 of its 32 triangles). `diagonal` is the box's; a
/// triangle lies in a face when its corners are within 10⁻⁵ of it of the face.
pub fn occluders(triangles: &[Tri], diagonal: f32) -> Vec<Tri> {
    let eps = 1e-5 * diagonal.max(f32::MIN_POSITIVE);
    let (lo, hi) = triangles.iter().flat_map(|t| t.v).fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v), hi.max(v)),
    );
    // The face (axis, 0 = low side, 1 = high) a triangle lies in, and whether it faces in.
    let face = |t: &Tri| -> Option<(usize, usize, bool)> {
        let n = t.normal();
        (0..3).find_map(|axis| {
            let side = [lo[axis], hi[axis]]
                .iter()
                .position(|&b| t.v.iter().all(|v| (v[axis] - b).abs() <= eps))?;
            let inward = if side == 0 { n[axis] } else { -n[axis] };
            Some((axis, side, inward > 1.0 - 1e-4))
        })
    };
    let faces: Vec<_> = triangles.iter().map(face).collect();
    let mut mixed = [[false; 2]; 3];
    for &(axis, side, inward) in faces.iter().flatten() {
        mixed[axis][side] |= !inward;
    }
    (triangles.iter().zip(&faces))
        .filter(|(_, f)| !f.is_some_and(|(axis, side, inward)| inward && !mixed[axis][side]))
        .map(|(t, _)| *t)
        .collect()
}

/// Which patches the closure test counts as the surface.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Surface {
    Visible,
    All,
}

/// The patches hung in the air: the mean winding number of the `counted` patches just in front of
/// and just behind the patch is over 0.75 (about 1 for a sheet, whose sides both face the air,
/// about 0.5 for a patch between the air and a solid or the outside; see
/// [`SceneAnalysis::of`]). Hidden patches are never sheets, and neither is a side of a two-sided
/// surface (a patch whose centroid lies on a patch facing the other way): what meets its back
/// meets the other side's front.
pub fn sheets(
    patches: &[Tri],
    hidden: &[bool],
    counted: &(dyn Fn(usize) -> bool + Sync),
    diagonal: f32,
) -> Vec<bool> {
    let surface: Vec<Tri> = (0..patches.len())
        .filter(|&p| counted(p))
        .map(|p| patches[p])
        .collect();
    let eps = 1e-5 * diagonal;
    let backed = |t: &Tri| {
        let (c, n) = (t.centroid(), t.normal());
        surface.iter().any(|r| {
            r.normal().dot(n) < -0.999 && r.normal().dot(c - r.v[0]).abs() <= eps && r.contains(c)
        })
    };
    (0..patches.len())
        .into_par_iter()
        .map(|p| {
            let [front, back] = probes(&patches[p], diagonal);
            !hidden[p]
                && winding_at(&surface, front) + winding_at(&surface, back) > 1.5
                && !backed(&patches[p])
        })
        .collect()
}

/// The points just in front of and just behind the centroid of `t`: a ten-thousandth of the
/// scene's diagonal away, and no more than a tenth of the patch's size.
fn probes(t: &Tri, diagonal: f32) -> [DVec3; 2] {
    let c = t.centroid().as_dvec3();
    let n = t.normal().as_dvec3();
    let delta = (1e-4 * f64::from(diagonal)).min(0.1 * f64::from(t.area()).sqrt());
    [c + n * delta, c - n * delta]
}

/// The patch planes `(unit normal, offset)`, merged when they agree within `eps`; `None` when
/// there are more than [`MAX_PLANES`].
fn distinct_planes(patches: &[Tri], eps: f32) -> Option<Vec<(Vec3, f32)>> {
    let mut planes: Vec<(Vec3, f32)> = Vec::new();
    for t in patches {
        let n = t.normal();
        if n == Vec3::ZERO {
            continue;
        }
        let d = n.dot(t.v[0]);
        let same = |(m, e): &(Vec3, f32)| m.dot(n) > 1.0 - 1e-6 && (e - d).abs() <= eps;
        if !planes.iter().any(same) {
            if planes.len() == MAX_PLANES {
                return None;
            }
            planes.push((n, d));
        }
    }
    Some(planes)
}

/// The patches' corners, each once.
fn distinct_vertices(patches: &[Tri]) -> Vec<Vec3> {
    let mut seen = rustc_hash::FxHashSet::default();
    patches
        .iter()
        .flat_map(|t| t.v)
        .filter(|v| seen.insert(v.to_array().map(f32::to_bits)))
        .collect()
}

/// The winding number of the triangles around `p`: their solid angles seen from `p` (positive
/// for a triangle whose front faces `p`; Van Oosterom and Strackee 1983) over 4π.
pub fn winding_number(triangles: &[Tri], p: Vec3) -> f64 {
    winding_at(triangles, p.as_dvec3())
}

/// [`winding_number`] about a point given in `f64`.
fn winding_at(triangles: &[Tri], p: DVec3) -> f64 {
    let total: f64 = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.v.map(|v| v.as_dvec3() - p);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let triple = a.dot(b.cross(c));
            let denom = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
            -2.0 * triple.atan2(denom)
        })
        .sum();
    total / (4.0 * std::f64::consts::PI)
}

/// Rays cast from each cell of a patch by [`back_shares`].
pub const BACK_RAYS_PER_CELL: u32 = 8;

/// The share of each patch's power (of its form-factor row) that lands on the backs of the
/// `sheet` patches, cell by cell of the `grid × grid` cells of the patch that a shot's source
/// density uses ([`crate::formfactor::SourceDensity`]: cell `(i, j)` is the image of
/// `[i, i + 1) × [j, j + 1) / grid` under [`Tri::sample`]), so that a shot weighs them by where
/// its power comes from (the part of a ceiling patch behind a lamp panel sends nearly all of
/// its little power into the panel's back, the rest of the patch almost none).
///
/// [`BACK_RAYS_PER_CELL`] rays from each cell: points uniform in it (kept a thousandth of the
/// way in from the patch's edges, so that no ray starts on the wall standing on one),
/// directions cosine-distributed, a fixed generator per patch (the shares do not depend on the
/// solve's seed). Hits on the back of any other patch are rays slipping through a seam and are
/// not counted. An empty list for a hidden patch and, without rays, for a patch that no sheet
/// turns its back to (none has a corner in front of the patch with a corner of the patch
/// behind it).
pub fn back_shares(
    patches: &[Tri],
    hidden: &[bool],
    sheet: &[bool],
    diagonal: f32,
    grid: u32,
) -> Vec<Vec<f32>> {
    let sheets: Vec<&Tri> = (patches.iter().zip(sheet))
        .filter(|(_, s)| **s)
        .map(|(t, _)| t)
        .collect();
    if sheets.is_empty() {
        return vec![Vec::new(); patches.len()];
    }
    let in_front = |t: &Tri, q: &Tri| q.v.iter().any(|v| t.normal().dot(*v - t.v[0]) > 0.0);
    let behind = |t: &Tri, q: &Tri| q.v.iter().any(|v| t.normal().dot(*v - t.v[0]) < 0.0);
    let octree = Octree::build(patches, OctreeConfig::default());
    let reach = 2.0 * diagonal;
    let tmin = 1e-6 * diagonal;
    let g = grid.max(1);
    let share = |p: usize| {
        let t = &patches[p];
        let normal = t.normal();
        let turned_to = |s: &&Tri| in_front(t, s) && behind(s, t);
        if hidden[p] || normal == Vec3::ZERO || !sheets.iter().any(turned_to) {
            return Vec::new();
        }
        let c = t.centroid();
        let inset = Tri {
            v: t.v.map(|v| c + (v - c) * 0.999),
        };
        let mut rng = Pcg32::new(0x5eed_c105, p as u64);
        let mut cells = Vec::with_capacity((g * g) as usize);
        for i in 0..g {
            for j in 0..g {
                let mut backs = 0u32;
                for _ in 0..BACK_RAYS_PER_CELL {
                    let u = (i as f32 + rng.next_f32()) / g as f32;
                    let v = (j as f32 + rng.next_f32()) / g as f32;
                    let o = inset.sample(u.min(1.0), v.min(1.0));
                    let d = cosine_direction(normal, &mut rng);
                    if let Some((_, q)) = octree.first_hit(o, d, tmin, reach, Traversal::Ropes) {
                        let q = q as usize;
                        backs += u32::from(sheet[q] && patches[q].normal().dot(d) > 0.0);
                    }
                }
                cells.push(backs as f32 / BACK_RAYS_PER_CELL as f32);
            }
        }
        if cells.iter().all(|&b| b == 0.0) {
            cells.clear();
        }
        cells
    };
    (0..patches.len()).into_par_iter().map(share).collect()
}

/// A direction about the unit normal `n` with density `cos θ / π` (Malley's method on the basis
/// of Duff et al. 2017).
fn cosine_direction(n: Vec3, rng: &mut Pcg32) -> Vec3 {
    let n = n.as_dvec3();
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let s = DVec3::new(b, sign + n.y * n.y * a, -n.y);
    let r = f64::from(rng.next_f32()).sqrt();
    let phi = 2.0 * std::f64::consts::PI * f64::from(rng.next_f32());
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    (t * x + s * y + n * z).as_vec3()
}

/// The stages a solve runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Stages {
    /// Cast shadow rays (off: every source sample is visible).
    pub shadow_rays: bool,
    /// Scale each shot's form factors so that the receivers get all the power sent.
    pub close_rows: bool,
    /// Triangles left out of the shadow-ray tests ([`occluders`]: they can hide nothing).
    pub inert_triangles: usize,
}

impl Stages {
    /// The stages `analysis` calls for; `all_stages` keeps the shadow rays whatever the scene.
    /// Row closing is a correction, not a saving, so it follows the analysis either way.
    /// `inert_triangles` is how many triangles the shadow rays' octree left out ([`occluders`];
    /// none with `all_stages`).
    pub fn for_scene(analysis: &SceneAnalysis, all_stages: bool, inert_triangles: usize) -> Stages {
        Stages {
            shadow_rays: all_stages || !analysis.convex,
            close_rows: analysis.closed,
            inert_triangles,
        }
    }

    /// What is left out and why (for `report.json`'s `left_out` and the console).
    pub fn left_out(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.shadow_rays {
            out.push(
                "shadow rays: the scene is a convex enclosure (every surface faces inward and \
                 lies on the hull), so no surface can hide another"
                    .to_string(),
            );
        } else if self.inert_triangles > 0 {
            out.push(format!(
                "shadow-ray tests against {} triangles: they lie in faces of the scene's \
                 bounding box and face into it, so they can hide nothing",
                self.inert_triangles
            ));
        }
        out
    }

    /// What is added and why.
    pub fn added(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.close_rows {
            out.push(
                "form-factor rows closed: the scene is closed, so every shot's power is \
                 received (none booked as escaped) but what lands on the backs of sheets"
                    .to_string(),
            );
        }
        out
    }
}

/// The factor that makes a shot from a source of area `source_area` deliver all its power, when
/// its receivers' form factors sum (area-weighted) to `received_area`; 1 when nothing was
/// received (nothing to scale).
pub fn row_scale(source_area: f64, received_area: f64) -> f64 {
    if received_area > 0.0 {
        source_area / received_area
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The six faces of the box `0..s`, inward, two triangles each; `open` leaves out the top.
    fn cube(s: f32, open: bool) -> Vec<Tri> {
        let mut out = Vec::new();
        for axis in 0..3 {
            for hi in [false, true] {
                if open && axis == 1 && hi {
                    continue;
                }
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |a: f32, b: f32| {
                    let mut p = Vec3::ZERO;
                    p[axis] = if hi { s } else { 0.0 };
                    p[u] = a;
                    p[v] = b;
                    p
                };
                let q = [
                    corner(0.0, 0.0),
                    corner(s, 0.0),
                    corner(s, s),
                    corner(0.0, s),
                ];
                let mut t = [Tri::new(q[0], q[1], q[2]), Tri::new(q[0], q[2], q[3])];
                let inward = if hi { -1.0 } else { 1.0 };
                if t[0].normal()[axis] * inward < 0.0 {
                    t = [Tri::new(q[0], q[2], q[1]), Tri::new(q[0], q[3], q[2])];
                }
                out.extend(t);
            }
        }
        out
    }

    /// The outward faces of the box `lo..hi` (a solid standing in the air), two triangles each.
    fn block(lo: Vec3, hi: Vec3) -> Vec<Tri> {
        let inward = cube(1.0, false);
        inward
            .iter()
            .map(|t| Tri::new(t.v[0], t.v[2], t.v[1]))
            .map(|t| Tri {
                v: t.v.map(|p| lo + p * (hi - lo)),
            })
            .collect()
    }

    fn analyse(tris: &[Tri], diagonal: f32) -> SceneAnalysis {
        SceneAnalysis::of(tris, &vec![false; tris.len()], diagonal)
    }

    /// A room shaped like an L seen from above: the box `0..2 × 0..1 × 0..2` without the
    /// quarter `1..2 × 0..1 × 1..2`, faces inward; `open` leaves out one of the ceiling's
    /// triangles.
    fn l_room(open: bool) -> Vec<Tri> {
        let y = Vec3::Y;
        let at = |x: f32, z: f32| Vec3::new(x, 0.0, z);
        let outline = [
            at(0.0, 0.0),
            at(2.0, 0.0),
            at(2.0, 1.0),
            at(1.0, 1.0),
            at(1.0, 2.0),
            at(0.0, 2.0),
        ];
        let mut out = Vec::new();
        // Walls: counter-clockwise outline seen from above, so (b - a) × up points inward.
        for i in 0..6 {
            let (a, b) = (outline[i], outline[(i + 1) % 6]);
            out.push(Tri::new(a, b, b + y));
            out.push(Tri::new(a, b + y, a + y));
        }
        // Floor and ceiling: the two rectangles 0..2 × 0..1 and 0..1 × 1..2.
        let rects = [(at(0.0, 0.0), at(2.0, 1.0)), (at(0.0, 1.0), at(1.0, 2.0))];
        for (lo, hi) in rects {
            let q = [
                lo,
                Vec3::new(hi.x, 0.0, lo.z),
                hi,
                Vec3::new(lo.x, 0.0, hi.z),
            ];
            out.push(Tri::new(q[0], q[2], q[1]));
            out.push(Tri::new(q[0], q[3], q[2]));
            out.push(Tri::new(q[0] + y, q[1] + y, q[2] + y));
            if !open {
                out.push(Tri::new(q[0] + y, q[2] + y, q[3] + y));
            }
        }
        out
    }

    #[test]
    fn a_closed_box_is_a_closed_convex_enclosure() {
        let a = analyse(&cube(2.0, false), 3.5);
        assert_eq!(
            a,
            SceneAnalysis {
                convex: true,
                closed: true,
                planes: 6,
                sheets: 0,
            }
        );
        assert!((winding_number(&cube(2.0, false), Vec3::splat(0.3)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn an_open_box_is_convex_but_not_closed() {
        let a = analyse(&cube(1.0, true), 1.7);
        assert!(a.convex && !a.closed, "{a:?}");
    }

    #[test]
    fn a_block_inside_or_a_hung_light_makes_it_concave_but_leaves_it_closed() {
        let mut tris = cube(1.0, false);
        // A small quad facing down just under the ceiling: the ceiling is behind it, and what
        // the ceiling sends it lands on its back (a sheet).
        let y = 0.99;
        tris.push(Tri::new(
            Vec3::new(0.4, y, 0.4),
            Vec3::new(0.6, y, 0.4),
            Vec3::new(0.6, y, 0.6),
        ));
        assert!(tris.last().unwrap().normal().y < 0.0);
        let a = analyse(&tris, 1.7);
        assert!(!a.convex && a.closed && a.sheets == 1, "{a:?}");
        let stages = Stages::for_scene(&a, false, 0);
        assert!(stages.shadow_rays && stages.left_out().is_empty() && stages.close_rows);
        // A block standing in the air: no sheet, still closed.
        let mut tris = cube(1.0, false);
        tris.extend(block(Vec3::new(0.2, 0.1, 0.3), Vec3::new(0.5, 0.4, 0.6)));
        let a = analyse(&tris, 1.7);
        assert!(!a.convex && a.closed && a.sheets == 0, "{a:?}");
    }

    #[test]
    fn a_two_sided_partition_in_a_box_is_no_sheet() {
        // A square partition standing in the box, one triangle pair facing each way: what meets
        // the back of one side meets the front of the other.
        let mut tris = cube(1.0, false);
        let q = [0.2, 0.8].map(|y| [0.2, 0.8].map(|z| Vec3::new(0.5, y, z)));
        let side = [
            Tri::new(q[0][0], q[1][0], q[1][1]),
            Tri::new(q[0][0], q[1][1], q[0][1]),
        ];
        tris.extend(side);
        tris.extend(side.map(|t| Tri::new(t.v[0], t.v[2], t.v[1])));
        let a = analyse(&tris, 1.7);
        assert!(!a.convex && a.closed && a.sheets == 0, "{a:?}");
        // One side alone is a sheet.
        tris.truncate(14);
        let a = analyse(&tris, 1.7);
        assert!(a.closed && a.sheets == 2, "{a:?}");
    }

    #[test]
    fn an_l_shaped_room_is_closed_and_with_a_hole_it_is_not() {
        let a = analyse(&l_room(false), 3.0);
        assert!(!a.convex && a.closed && a.sheets == 0, "{a:?}");
        let a = analyse(&l_room(true), 3.0);
        assert!(!a.convex && !a.closed, "{a:?}");
    }

    #[test]
    fn a_room_open_to_the_outside_is_not_closed_whatever_it_holds() {
        // The open box with a block in it, and with a sheet hung in it.
        let mut tris = cube(1.0, true);
        tris.extend(block(Vec3::new(0.2, 0.0, 0.3), Vec3::new(0.5, 0.4, 0.6)));
        let a = analyse(&tris, 1.7);
        assert!(!a.convex && !a.closed, "{a:?}");
        let mut tris = cube(1.0, true);
        tris.push(Tri::new(
            Vec3::new(0.4, 0.5, 0.4),
            Vec3::new(0.6, 0.5, 0.4),
            Vec3::new(0.6, 0.5, 0.6),
        ));
        let a = analyse(&tris, 1.7);
        assert!(!a.convex && !a.closed && a.sheets == 0, "{a:?}");
        // A closed box but for a hole of 0.1 × 0.1 in its floor, and a block in it.
        let mut tris = cube(1.0, false);
        tris.retain(|t| t.normal().y < 0.5);
        let at = |x: f32, z: f32| Vec3::new(x, 0.0, z);
        for (lo, hi) in [(0.0, 0.45), (0.55, 1.0)] {
            for (x0, x1, z0, z1) in [(lo, hi, 0.0, 1.0), (0.45, 0.55, lo, hi)] {
                tris.push(Tri::new(at(x0, z0), at(x1, z1), at(x1, z0)));
                tris.push(Tri::new(at(x0, z0), at(x0, z1), at(x1, z1)));
            }
        }
        assert!(tris[tris.len() - 8..].iter().all(|t| t.normal().y > 0.5));
        let whole = analyse(&tris, 1.7);
        tris.extend(block(Vec3::new(0.2, 0.1, 0.3), Vec3::new(0.5, 0.4, 0.6)));
        let a = analyse(&tris, 1.7);
        assert!(!whole.closed && !a.convex && !a.closed, "{whole:?} {a:?}");
    }

    #[test]
    fn a_hung_sheet_takes_on_its_back_the_ceilings_form_factor_to_it() {
        // A square panel 0.3..0.7 facing down at height 0.8 in the unit box: each ceiling
        // triangle sends it, on its back, the mean over the triangle of the point form factor
        // to the square (nothing lies between them).
        let mut tris = cube(1.0, false);
        let y = 0.8;
        let q = [0.3, 0.7].map(|x| [0.3, 0.7].map(|z| Vec3::new(x, y, z)));
        tris.push(Tri::new(q[0][0], q[1][0], q[1][1]));
        tris.push(Tri::new(q[0][0], q[1][1], q[0][1]));
        assert!(tris[12..].iter().all(|t| t.normal().y < 0.0));
        let hidden = vec![false; tris.len()];
        let (a, sheet) = SceneAnalysis::with_sheets(&tris, &hidden, 1.7);
        assert!(a.closed && a.sheets == 2 && sheet[12] && sheet[13], "{a:?}");
        let g = 64;
        let shares = back_shares(&tris, &hidden, &sheet, 1.7, g);
        let square = [q[0][0], q[1][0], q[1][1], q[0][1]];
        let mut ceilings = 0;
        for (t, cells) in tris.iter().zip(&shares) {
            let mean = cells.iter().map(|&b| f64::from(b)).sum::<f64>() / f64::from(g * g);
            if t.normal().y.abs() < 0.5 {
                // The walls see the back at a grazing angle from above y = 0.8.
                assert!(mean > 0.0 && mean < 0.05, "{t:?}: {mean}");
                continue;
            }
            if t.normal().y > -0.5 || t.centroid().y < 0.9 {
                // The floor and the panel cannot see it: no rays cast.
                assert!(cells.is_empty(), "{t:?}");
                continue;
            }
            ceilings += 1;
            let n = 200;
            let exact = (0..n * n)
                .map(|k| {
                    let (u, v) = ((k / n) as f32 + 0.5, (k % n) as f32 + 0.5);
                    let p = t.sample(u / n as f32, v / n as f32);
                    f64::from(crate::formfactor::point_polygon(p, t.normal(), &square))
                })
                .sum::<f64>()
                / f64::from(n * n);
            let rays = f64::from(g * g * BACK_RAYS_PER_CELL);
            let std_err = (exact * (1.0 - exact) / rays).sqrt();
            assert!(
                exact > 0.1 && (mean - exact).abs() < 4.0 * std_err,
                "{mean} against {exact} ± {std_err}"
            );
        }
        assert_eq!(ceilings, 2);
    }

    #[test]
    fn all_stages_keeps_the_shadow_rays() {
        let a = analyse(&cube(1.0, false), 1.7);
        assert!(!Stages::for_scene(&a, false, 0).shadow_rays);
        assert!(Stages::for_scene(&a, true, 0).shadow_rays);
        assert_eq!(Stages::for_scene(&a, false, 0).left_out().len(), 1);
    }
}
