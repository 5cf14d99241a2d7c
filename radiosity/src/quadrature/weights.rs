//! The quadratic rule ([`super`]) as weights: what each vertex's value adds to one element's
//! integral (its area times its mean), for a program that books a shot point by point.
//!
//! The rule is linear in the vertices' values, so an element's integral is `Σ_u w_u f_u` over
//! its *support*: its own corners and every corner of the elements around them (whose
//! gradients the recovered gradients at its corners average). carm.occ's nodes hold these
//! weights at their points, one element corner each, and book a shot with them exactly as they
//! book the corners' average (programs/README.md, "Quadratic booking").

use glam::Vec3;

use super::{MeanRule, Stencil, stencil};
use crate::geom::Tri;
use crate::mesh::Mesh;

/// A mesh as far as the weights need it: elements' corners, vertices' positions and whether
/// they are hidden, and the elements around each vertex.
pub trait Support {
    /// Element `e`'s corners.
    fn corners(&self, e: u32) -> [u32; 3];
    /// Vertex `v`'s position.
    fn pos(&self, v: u32) -> Vec3;
    /// Whether vertex `v` is hidden ([`crate::mesh::Vertex::hidden`]).
    fn hidden(&self, v: u32) -> bool;
    /// The elements with vertex `v` as a corner.
    fn around(&self, v: u32) -> impl Iterator<Item = u32> + '_;
}

/// Element `e`'s stencil, or `None` where it keeps the corners' average (a hidden corner, or
/// degenerate), as [`super::ElementMeans`] fits it.
fn stencil_of(mesh: &impl Support, e: u32) -> Option<Stencil> {
    let v = mesh.corners(e);
    if v.iter().any(|&v| mesh.hidden(v)) {
        return None;
    }
    stencil(v.map(|v| mesh.pos(v)))
}

/// Element `e`'s integral as weights on vertices, into `out` (cleared first): its three
/// corners first, in order, each with a third of its area (all the linear rule gives), then
/// the curvature term's weights, each vertex once. `Σ w f` over `out` is the area (as
/// [`Tri::area`] gives it, in `f64`) times the mean [`super::ElementMeans::means`] gives by the
/// quadratic rule, up to rounding.
pub fn element_weights(mesh: &impl Support, e: u32, out: &mut Vec<(u32, f64)>) {
    out.clear();
    let v = mesh.corners(e);
    let area = f64::from(Tri::new(mesh.pos(v[0]), mesh.pos(v[1]), mesh.pos(v[2])).area());
    out.extend(v.map(|v| (v, area / 3.0)));
    let Some(own) = stencil_of(mesh, e) else {
        return;
    };
    // The mean's curvature term is Σᵢ g(vᵢ)·rᵢ, where g(v) is the area-weighted mean, over the
    // elements e' around v that have a stencil, of the gradient Σₖ f(e'ₖ) ∇λₖ of e'.
    for (&corner, reach) in v.iter().zip(own.reaches()) {
        let lending = || {
            mesh.around(corner)
                .filter_map(|o| Some((o, stencil_of(mesh, o)?)))
        };
        let weight: f32 = lending().map(|(_, s)| s.area).sum();
        if weight <= 0.0 || weight.is_nan() {
            continue;
        }
        for (o, s) in lending() {
            let share = s.area / weight;
            for (&u, grad) in mesh.corners(o).iter().zip(s.grads()) {
                let w = area * f64::from(share * grad.dot(reach));
                match out.iter_mut().find(|(x, _)| *x == u) {
                    Some((_, sum)) => *sum += w,
                    None => out.push((u, w)),
                }
            }
        }
    }
}

/// A [`Mesh`] with the elements around each vertex.
pub struct MeshSupport<'a> {
    mesh: &'a Mesh,
    /// Vertex `v`'s elements are `list[first[v] .. first[v + 1]]`.
    first: Vec<u32>,
    list: Vec<u32>,
}

impl<'a> MeshSupport<'a> {
    /// The elements around each of `mesh`'s vertices.
    pub fn new(mesh: &'a Mesh) -> MeshSupport<'a> {
        let (first, list) = elements_around(mesh.vertices.len(), mesh.elements.iter().map(|e| e.v));
        MeshSupport { mesh, first, list }
    }
}

/// The vertices each element's integral weighs by a rule, as lists: element `e`'s are
/// `points[first[e] .. first[e + 1]]`, its corners first. By the corners' average its three
/// corners; by the quadratic rule its support. A node program keeps an element corner at each
/// (carm.occ: programs/README.md, "Quadratic booking").
pub struct Supports {
    first: Vec<usize>,
    points: Vec<u32>,
}

impl Supports {
    /// Every element's of `mesh` by `rule`.
    pub fn new(mesh: &Mesh, rule: MeanRule) -> Supports {
        let mut supports = Supports {
            first: vec![0],
            points: Vec::new(),
        };
        match rule {
            MeanRule::Linear => {
                for e in &mesh.elements {
                    supports.points.extend(e.v);
                    supports.first.push(supports.points.len());
                }
            }
            MeanRule::Quadratic => {
                let support = MeshSupport::new(mesh);
                let mut out = Vec::new();
                for e in 0..mesh.elements.len() as u32 {
                    element_weights(&support, e, &mut out);
                    supports.points.extend(out.iter().map(|&(v, _)| v));
                    supports.first.push(supports.points.len());
                }
            }
        }
        supports
    }

    /// Element `e`'s vertices.
    pub fn of(&self, e: usize) -> &[u32] {
        &self.points[self.first[e]..self.first[e + 1]]
    }

    /// How many elements weigh each of `vertices` vertices: the corners kept at it.
    pub fn at_vertices(&self, vertices: usize) -> Vec<usize> {
        let mut count = vec![0; vertices];
        self.points.iter().for_each(|&v| count[v as usize] += 1);
        count
    }
}

impl Support for MeshSupport<'_> {
    fn corners(&self, e: u32) -> [u32; 3] {
        self.mesh.elements[e as usize].v
    }
    fn pos(&self, v: u32) -> Vec3 {
        self.mesh.vertices[v as usize].pos
    }
    fn hidden(&self, v: u32) -> bool {
        self.mesh.vertices[v as usize].hidden()
    }
    fn around(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        let (a, b) = (self.first[v as usize], self.first[v as usize + 1]);
        self.list[a as usize..b as usize].iter().copied()
    }
}

/// The elements around each of `vertices` vertices, given each element's corners in order:
/// `(first, list)`, vertex `v`'s elements being `list[first[v] .. first[v + 1]]`, ascending.
pub fn elements_around(
    vertices: usize,
    corners: impl Iterator<Item = [u32; 3]> + Clone,
) -> (Vec<u32>, Vec<u32>) {
    let mut first = vec![0u32; vertices + 1];
    for v in corners.clone() {
        v.iter().for_each(|&v| first[v as usize + 1] += 1);
    }
    for i in 0..vertices {
        first[i + 1] += first[i];
    }
    let mut next = first.clone();
    let mut list = vec![0u32; first[vertices] as usize];
    for (e, v) in corners.enumerate() {
        for &v in &v {
            list[next[v as usize] as usize] = e as u32;
            next[v as usize] += 1;
        }
    }
    (first, list)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::{ElementMeans, MeanRule};

    /// [`crate::quadrature::tests::grid`]'s square with one edge split (refinement's way), so
    /// that the vertices' degrees differ.
    fn mesh(n: u32) -> Mesh {
        let mut mesh = crate::quadrature::tests::grid(n);
        crate::quadrature::tests::split_first_edge(&mut mesh, 7);
        mesh
    }

    #[test]
    fn the_weights_give_each_element_its_quadratic_mean() {
        let mut mesh = mesh(5);
        mesh.vertices[3].normal = Vec3::ZERO;
        let values: Vec<f32> = (mesh.vertices.iter())
            .map(|v| 2.0 + (0.9 * v.pos.x).sin() + 0.3 * v.pos.y * v.pos.y)
            .collect();
        let means = ElementMeans::new(&mesh, MeanRule::Quadratic).means(&mesh, &values);
        let support = MeshSupport::new(&mesh);
        let mut out = Vec::new();
        let mut curved = 0;
        for (e, mean) in means.iter().enumerate() {
            element_weights(&support, e as u32, &mut out);
            let corners = mesh.elements[e].v;
            assert_eq!(out[..3].iter().map(|w| w.0).collect::<Vec<_>>(), corners);
            let area = f64::from(mesh.tri(&mesh.elements[e]).area());
            let booked: f64 = out
                .iter()
                .map(|&(v, w)| w * f64::from(values[v as usize]))
                .sum();
            assert!(
                (booked - area * mean.x).abs() < 1e-5 * area * mean.x,
                "element {e}: {booked} against {}",
                area * mean.x
            );
            curved += usize::from(out.len() > 3);
        }
        // every element but those at the hidden vertex has a support beyond its corners
        assert!(curved >= mesh.elements.len() - 6, "{curved}");
    }

    #[test]
    fn an_element_at_a_hidden_vertex_keeps_its_corners_thirds() {
        let mut mesh = mesh(3);
        mesh.vertices[0].normal = Vec3::ZERO;
        let support = MeshSupport::new(&mesh);
        let mut out = Vec::new();
        element_weights(&support, 0, &mut out);
        let third = f64::from(mesh.tri(&mesh.elements[0]).area()) / 3.0;
        assert_eq!(out.len(), 3);
        assert!(out.iter().all(|&(_, w)| w == third));
    }

    #[test]
    fn the_supports_count_every_element_s_weights() {
        let mesh = mesh(4);
        let support = MeshSupport::new(&mesh);
        let quadratic = Supports::new(&mesh, MeanRule::Quadratic);
        let mut out = Vec::new();
        let mut total = 0;
        for e in 0..mesh.elements.len() {
            element_weights(&support, e as u32, &mut out);
            assert!(out.iter().map(|w| w.0).eq(quadratic.of(e).iter().copied()));
            total += out.len();
        }
        let counts = quadratic.at_vertices(mesh.vertices.len());
        assert_eq!(counts.iter().sum::<usize>(), total);
        // an interior element of a regular grid reaches the twelve vertices around its corners
        assert!(total > 9 * mesh.elements.len(), "{total}");
        let linear = Supports::new(&mesh, MeanRule::Linear);
        assert_eq!(linear.of(7), mesh.elements[7].v);
        assert_eq!(
            linear
                .at_vertices(mesh.vertices.len())
                .iter()
                .sum::<usize>(),
            3 * mesh.elements.len()
        );
    }
}
