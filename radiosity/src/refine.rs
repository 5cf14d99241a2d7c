//! Adaptive subdivision's rules (the paper's section 1.1: a new sample point where neighbours
//! differ steeply, unless the radiance is linear between them), stated once for the reference
//! solver ([`crate::solver::Solver`]) and carm.occ's controller (`RAD.REFINE.EDGES`,
//! `RAD.REFINE.SPLIT`), so that both refine the same edges.
//!
//! Every test is about one shot: `db` is its change of radiosity at the source (channels
//! summed), `f` a form factor from the source to a sample point, and the *local irradiance* of
//! an edge the larger irradiance gathered so far at its ends plus this shot's larger
//! contribution ([`local_irradiance`]).

use crate::kernels::SamplePoint;

/// The larger irradiance at the ends of an edge (`irr_a`, `irr_b`: gathered so far, channels
/// summed) plus the larger contribution of this shot there.
pub fn local_irradiance(irr_a: f32, irr_b: f32, db: f32, fa: f32, fb: f32) -> f32 {
    irr_a.max(irr_b) + db * fa.max(fb)
}

/// An edge of the mesh with what the test needs of it.
#[derive(Clone, Copy, Debug)]
pub struct EdgeEnds {
    /// The edge's vertex indices.
    pub ends: (u32, u32),
    /// Its length.
    pub length: f32,
    /// This shot's form factors at its ends.
    pub factors: (f32, f32),
    /// Irradiance gathered so far at its ends (channels summed).
    pub irradiance: (f32, f32),
}

/// The settings of the edge test.
#[derive(Clone, Copy, Debug)]
pub struct EdgeTest {
    /// Test an edge when this shot's contributions at its ends differ by more than this fraction
    /// of the local irradiance.
    pub difference: f32,
    /// Never split an edge shorter than twice this.
    pub min_edge: f32,
}

/// The edges to test by a midpoint: longer than twice the minimum and with ends that receive
/// from this shot amounts differing by more than `difference` times the local irradiance;
/// steepest first, edges equally steep by their ends (lower, higher) ascending. The order is
/// that whatever order `edges` come in, and an edge that comes more than once is listed once
/// (`ends` with the lower vertex first).
pub fn candidates(
    edges: impl Iterator<Item = EdgeEnds>,
    db: f32,
    test: EdgeTest,
) -> Vec<(u32, u32)> {
    let mut scored: Vec<(f32, (u32, u32))> = edges
        .filter_map(|e| {
            let (fa, fb) = e.factors;
            let local = local_irradiance(e.irradiance.0, e.irradiance.1, db, fa, fb);
            let steep = db * (fa - fb).abs() / local.max(f32::MIN_POSITIVE);
            (e.length > 2.0 * test.min_edge && steep > test.difference).then_some((steep, e.ends))
        })
        .collect();
    scored.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    scored.dedup_by_key(|x| x.1);
    scored.into_iter().map(|(_, e)| e).collect()
}

/// Whether an edge whose ends get `fa`, `fb` and whose midpoint gets `fm` from this shot is to
/// be split: the midpoint departs from the linear interpolation by more than `nonlinearity`
/// times the edge's `local` irradiance ([`local_irradiance`]).
pub fn nonlinear(fa: f32, fb: f32, fm: f32, local: f32, db: f32, nonlinearity: f32) -> bool {
    (db * (fm - 0.5 * (fa + fb))).abs() > nonlinearity * local
}

/// The sample point in the middle of the edge from `a` to `b`: position and evaluation point
/// halfway, the normal the normalised sum of theirs (`a`'s when they cancel).
pub fn midpoint(a: &SamplePoint, b: &SamplePoint) -> SamplePoint {
    use glam::Vec3;
    let v = |x: [f32; 3]| Vec3::from(x);
    SamplePoint {
        pos: ((v(a.pos) + v(b.pos)) * 0.5).to_array(),
        normal: (v(a.normal) + v(b.normal))
            .normalize_or(v(a.normal))
            .to_array(),
        eval: ((v(a.eval) + v(b.eval)) * 0.5).to_array(),
    }
}

/// The edges of elements given by their corners, (lower, higher) vertex, an edge once for
/// each element that has it.
pub fn element_edges(elements: impl Iterator<Item = [u32; 3]>) -> impl Iterator<Item = (u32, u32)> {
    elements.flat_map(|v| (0..3).map(move |k| (v[k].min(v[(k + 1) % 3]), v[k].max(v[(k + 1) % 3]))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(ends: (u32, u32), length: f32, factors: (f32, f32)) -> EdgeEnds {
        EdgeEnds {
            ends,
            length,
            factors,
            irradiance: (0.0, 0.0),
        }
    }

    #[test]
    fn steep_long_edges_are_candidates_steepest_first() {
        let test = EdgeTest {
            difference: 0.3,
            min_edge: 1.0,
        };
        let edges = [
            edge((0, 1), 5.0, (1.0, 0.8)), // steep 0.2: not
            edge((1, 2), 5.0, (1.0, 0.5)), // steep 0.5
            edge((2, 3), 5.0, (1.0, 0.0)), // steep 1.0
            edge((3, 4), 1.5, (1.0, 0.0)), // too short
        ];
        assert_eq!(
            candidates(edges.into_iter(), 1.0, test),
            vec![(2, 3), (1, 2)]
        );
    }

    #[test]
    fn a_linear_midpoint_does_not_split() {
        assert!(!nonlinear(1.0, 0.0, 0.5, 1.0, 1.0, 0.1));
        assert!(nonlinear(1.0, 0.0, 0.9, 1.0, 1.0, 0.1));
    }

    #[test]
    fn equally_steep_edges_come_by_their_ends_and_once() {
        let test = EdgeTest {
            difference: 0.3,
            min_edge: 1.0,
        };
        let edges = [
            edge((2, 3), 5.0, (1.0, 0.0)),
            edge((0, 1), 5.0, (1.0, 0.0)),
            edge((2, 3), 5.0, (1.0, 0.0)),
        ];
        assert_eq!(
            candidates(edges.into_iter(), 1.0, test),
            vec![(0, 1), (2, 3)]
        );
    }

    #[test]
    fn element_edges_have_the_lower_vertex_first() {
        let list: Vec<_> = element_edges([[2, 1, 0]].into_iter()).collect();
        assert_eq!(list, vec![(1, 2), (0, 1), (0, 2)]);
    }
}
