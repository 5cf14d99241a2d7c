//! What a scene needs: the solver's stages that a scene's shape makes unnecessary, found before
//! the first shot ([`SceneAnalysis::of`]), and what is left out for it ([`Stages`]).
//!
//! - **Convex enclosure** (every patch faces inward and lies on the hull: no vertex of the scene
//!   is behind the plane of any patch, by more than the weld distance): the segment between two
//!   points of the surface runs inside the hull, so no patch can hide another and shadow rays
//!   are left out (their answer is always "visible").
//! - **Closed** (a convex enclosure whose patches cover the hull: the winding number of the
//!   surface around its centre, the patches' signed solid angles over 4π, is 1): every direction
//!   from every point meets a surface, so all the power a shot sends must be received. Each
//!   shot's form factors are then scaled so that the receivers get exactly the power sent (the
//!   sum of a form-factor row is 1), instead of booking the quadrature error of the receivers'
//!   sampling as escaped power. In a closed room of reflectance ρ that error is multiplied by
//!   `1 / (1 - ρ)`: 0.1% of leak is 50% of error at ρ = 0.999.
//!
//! Adaptive subdivision and the analytic near-field form factor need no scene-level decision:
//! the first tests linearity edge by edge each shot, the second is chosen per receiver by its
//! distance to the source (`crate::formfactor`).
//!
//! Invariants:
//! - a stage is left out only when its answer is known without running it (the same scene with
//!   every stage on, `all_stages`, agrees within the convergence tolerance: `tests/stages.rs`);
//! - the analysis looks at the patches the solver shoots from (after meshing), not at the file.

use glam::Vec3;

use crate::geom::Tri;

/// Scenes with more distinct patch planes than this are not tested for convexity (the test costs
/// planes × vertices); they keep every stage.
pub const MAX_PLANES: usize = 256;

/// The winding number of a closed surface around its centre must be 1 within this.
const WINDING_TOLERANCE: f64 = 1e-4;

/// What the analysis found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SceneAnalysis {
    /// Every patch faces inward and lies on the convex hull.
    pub convex: bool,
    /// A convex enclosure with no opening.
    pub closed: bool,
    /// Distinct planes of the patches (0 when there were more than [`MAX_PLANES`]).
    pub planes: usize,
}

impl SceneAnalysis {
    /// Analyses the patches of a scene whose bounding-box diagonal is `diagonal`.
    pub fn of(patches: &[Tri], diagonal: f32) -> SceneAnalysis {
        let eps = 1e-5 * diagonal.max(f32::MIN_POSITIVE);
        let Some(planes) = distinct_planes(patches, eps) else {
            return SceneAnalysis::default();
        };
        let vertices = distinct_vertices(patches);
        let convex = !planes.is_empty()
            && planes
                .iter()
                .all(|(n, d)| vertices.iter().all(|v| n.dot(*v) - d >= -eps));
        let closed = convex && {
            let centre = vertices.iter().fold(Vec3::ZERO, |s, v| s + *v) / vertices.len() as f32;
            (winding_number(patches, centre) - 1.0).abs() < WINDING_TOLERANCE
        };
        SceneAnalysis {
            convex,
            closed,
            planes: planes.len(),
        }
    }
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
    let p = p.as_dvec3();
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

/// The stages a solve runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Stages {
    /// Cast shadow rays (off: every source sample is visible).
    pub shadow_rays: bool,
    /// Scale each shot's form factors so that the receivers get all the power sent.
    pub close_rows: bool,
}

impl Stages {
    /// The stages `analysis` calls for; `all_stages` keeps the shadow rays whatever the scene.
    /// Row closing is a correction, not a saving, so it follows the analysis either way.
    pub fn for_scene(analysis: &SceneAnalysis, all_stages: bool) -> Stages {
        Stages {
            shadow_rays: all_stages || !analysis.convex,
            close_rows: analysis.closed,
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
        }
        out
    }

    /// What is added and why.
    pub fn added(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.close_rows {
            out.push(
                "form-factor rows closed: the scene is a closed convex enclosure, so every \
                 shot's power is received (none booked as escaped)"
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

    #[test]
    fn a_closed_box_is_a_closed_convex_enclosure() {
        let a = SceneAnalysis::of(&cube(2.0, false), 3.5);
        assert_eq!(
            a,
            SceneAnalysis {
                convex: true,
                closed: true,
                planes: 6
            }
        );
        assert!((winding_number(&cube(2.0, false), Vec3::splat(0.3)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn an_open_box_is_convex_but_not_closed() {
        let a = SceneAnalysis::of(&cube(1.0, true), 1.7);
        assert!(a.convex && !a.closed, "{a:?}");
    }

    #[test]
    fn a_block_inside_or_a_hung_light_makes_it_concave() {
        let mut tris = cube(1.0, false);
        // A small quad facing down just under the ceiling: the ceiling is behind it.
        let y = 0.99;
        tris.push(Tri::new(
            Vec3::new(0.4, y, 0.4),
            Vec3::new(0.6, y, 0.4),
            Vec3::new(0.6, y, 0.6),
        ));
        assert!(tris.last().unwrap().normal().y < 0.0);
        let a = SceneAnalysis::of(&tris, 1.7);
        assert!(!a.convex && !a.closed, "{a:?}");
        let stages = Stages::for_scene(&a, false);
        assert!(stages.shadow_rays && stages.left_out().is_empty());
    }

    #[test]
    fn all_stages_keeps_the_shadow_rays() {
        let a = SceneAnalysis::of(&cube(1.0, false), 1.7);
        assert!(!Stages::for_scene(&a, false).shadow_rays);
        assert!(Stages::for_scene(&a, true).shadow_rays);
        assert_eq!(Stages::for_scene(&a, false).left_out().len(), 1);
    }
}
