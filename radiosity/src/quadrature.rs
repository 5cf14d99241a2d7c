//! Element means of a field known at the mesh's vertices, exact for quadratic fields.
//!
//! A shot's form factors (and the irradiance they add up to) are computed at the vertices; an
//! element's received power is its area times its mean. The mean of the linear interpolant,
//! the corners' average, is exact only where the field is linear: under a light the irradiance
//! is a concave peak, and the corners' average understates it by about `h² |∂²f| / 24`. On the
//! Cornell box at the default element size (48 mm) that put the directly lit surfaces 0.3-0.6%
//! low (the tall block's top 0.39% against the path-traced direct light), and every bounce
//! inherited it (radiosity/REFERENCES.md, "Element means exact for quadratics").
//!
//! For a quadratic `f` on a triangle with corners `p₀ p₁ p₂`, the mean is
//! `(f₀ + f₁ + f₂)/3 + (1/24) Σᵢ ∇f(pᵢ) · (pᵢ₊₁ + pᵢ₋₁ − 2pᵢ)` (the edge-midpoint rule with each
//! midpoint value written through the gradients at the edge's ends). The gradients at the
//! vertices are recovered from the same samples: the area-weighted mean of the gradients of
//! the linear interpolant over the elements around each vertex (exact for a quadratic at an
//! interior vertex of a symmetric patch of elements). No form factor more is computed.
//!
//! Elements with a hidden corner ([`crate::mesh::Vertex::hidden`]) keep the corners' average
//! and lend no gradient: what they cover receives nothing, and a gradient across the edge of a
//! covered region would be a jump, not a slope. The rule stays linear in the values, so that a
//! row closed to the power shot ([`crate::analysis::row_scale`]) books exactly that power: an
//! element beside a bright one, in the dark, may get a mean a little below zero, as a
//! quadrature of a positive field may.

use std::ops::{Add, Mul};
use std::sync::OnceLock;

use glam::{DVec3, Vec3};

use crate::mesh::Mesh;

pub mod weights;

/// A value the means are taken of: a form factor (`f32`, the same in every channel) or an RGB
/// irradiance (`Vec3`).
pub trait Field: Copy + Default + PartialEq + Add<Output = Self> + Mul<f32, Output = Self> {
    /// The value per channel, in `f64`.
    fn wide(self) -> DVec3;
}

impl Field for f32 {
    fn wide(self) -> DVec3 {
        DVec3::splat(self as f64)
    }
}

impl Field for Vec3 {
    fn wide(self) -> DVec3 {
        self.as_dvec3()
    }
}

/// How the elements' means are taken.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum MeanRule {
    /// The corners' average (exact for linear fields).
    Linear,
    /// With the curvature the recovered vertex gradients show (exact for quadratic fields).
    #[default]
    Quadratic,
}

impl std::str::FromStr for MeanRule {
    type Err = String;
    /// Parses `quadratic` or `linear`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "quadratic" => Ok(MeanRule::Quadratic),
            "linear" => Ok(MeanRule::Linear),
            _ => Err(format!("`{s}`: expected quadratic or linear")),
        }
    }
}

/// One element's part in the quadratic rule, kept small (the passes of a shot stream it):
/// corner 0's gradient and reach are minus the sum of the other two's.
#[derive(Clone, Copy, Debug, Default)]
struct Stencil {
    /// Area (the weight of its gradient at its corners); 0: none, the corners' average (a
    /// hidden corner, or a degenerate element).
    area: f32,
    /// Gradients of corners 1 and 2's barycentric coordinates (in the element's plane).
    grad: [Vec3; 2],
    /// Per corner `i` (1 and 2), `(pᵢ₊₁ + pᵢ₋₁ − 2pᵢ) / 24`: what the gradient at corner `i`
    /// adds to the mean.
    reach: [Vec3; 2],
}

impl Stencil {
    /// Whether the element takes part (else it keeps the corners' average).
    fn some(&self) -> bool {
        self.area > 0.0
    }

    /// The gradients of the three corners' barycentric coordinates.
    fn grads(&self) -> [Vec3; 3] {
        [-(self.grad[0] + self.grad[1]), self.grad[0], self.grad[1]]
    }

    /// The three corners' reaches.
    fn reaches(&self) -> [Vec3; 3] {
        [
            -(self.reach[0] + self.reach[1]),
            self.reach[0],
            self.reach[1],
        ]
    }
}

/// The means of a mesh's elements: built for a mesh, and kept fitting it as refinement splits
/// elements ([`ElementMeans::fit`]).
#[derive(Clone, Debug)]
pub struct ElementMeans {
    rule: MeanRule,
    /// Per element: the corners it was fitted with, and its stencil.
    corners: Vec<[u32; 3]>,
    stencils: Vec<Stencil>,
    /// Per vertex: one over the summed area of the elements that lend it a gradient (0: none).
    inverse_weight: Vec<f32>,
    /// Per vertex: that summed area.
    weight: Vec<f32>,
    /// Per vertex: its weight in the integral over the mesh ([`ElementMeans::integral`]),
    /// worked out when first asked for after a fit (only scenes whose rows are closed ask).
    integral: OnceLock<Vec<f64>>,
}

impl ElementMeans {
    /// The means of `mesh`'s elements by `rule`.
    pub fn new(mesh: &Mesh, rule: MeanRule) -> ElementMeans {
        let mut means = ElementMeans {
            rule,
            corners: Vec::new(),
            stencils: Vec::new(),
            inverse_weight: Vec::new(),
            weight: Vec::new(),
            integral: OnceLock::new(),
        };
        means.fit(mesh);
        means
    }

    /// Whether these means fit `mesh` as it is now.
    pub fn fits(&self, mesh: &Mesh) -> bool {
        self.rule == MeanRule::Linear
            || (self.weight.len() == mesh.vertices.len()
                && self.corners.len() == mesh.elements.len()
                && (self.corners.iter().zip(&mesh.elements)).all(|(c, e)| *c == e.v))
    }

    /// Fits the means to `mesh` after refinement (which splits elements in place, each keeping
    /// its index, appends the other halves and adds vertices, never removing any): only the
    /// elements whose corners changed are fitted again.
    pub fn fit(&mut self, mesh: &Mesh) {
        if self.rule == MeanRule::Linear {
            return;
        }
        self.weight.resize(mesh.vertices.len(), 0.0);
        let mut touched = Vec::new();
        for (i, e) in mesh.elements.iter().enumerate() {
            if self.corners.get(i) == Some(&e.v) {
                continue;
            }
            if let (Some(corners), Some(old)) = (self.corners.get(i), self.stencils.get(i)) {
                for &v in corners.iter().filter(|_| old.some()) {
                    self.weight[v as usize] -= old.area;
                    touched.push(v);
                }
            }
            let fitted = element_stencil(mesh, e.v).unwrap_or_default();
            for &v in e.v.iter().filter(|_| fitted.some()) {
                self.weight[v as usize] += fitted.area;
                touched.push(v);
            }
            if i < self.corners.len() {
                (self.corners[i], self.stencils[i]) = (e.v, fitted);
            } else {
                self.corners.push(e.v);
                self.stencils.push(fitted);
            }
        }
        self.inverse_weight.resize(mesh.vertices.len(), 0.0);
        if !touched.is_empty() {
            self.integral = OnceLock::new();
        }
        for v in touched {
            let w = self.weight[v as usize];
            self.inverse_weight[v as usize] = if w > 0.0 { 1.0 / w } else { 0.0 };
        }
    }

    /// The integral over `mesh` of a field known at the vertices, `Σ_e A_e mean_e` (in
    /// `f64`): what summing [`ElementMeans::means`] over the elements gives. By the linear rule it is
    /// summed element by element, as a node program sums its corners; by the quadratic rule as
    /// `Σ_v w_v values[v]` with each vertex's weight fitted to the mesh.
    pub fn integral(&self, mesh: &Mesh, values: &[f32]) -> f64 {
        if self.rule == MeanRule::Linear {
            return (mesh.elements.iter())
                .map(|e| {
                    let sum = e.v.iter().map(|&v| values[v as usize] as f64).sum::<f64>();
                    mesh.tri(e).area() as f64 * sum / 3.0
                })
                .sum();
        }
        debug_assert!(self.fits(mesh));
        let weights = self.integral.get_or_init(|| self.quadratic_integral(mesh));
        (weights.iter().zip(values))
            .map(|(&w, &f)| w * f as f64)
            .sum()
    }

    /// The vertices' weights in the integral by the quadratic rule: each element gives its
    /// corners a third of its area, and through the gradients recovered at its corners the
    /// corners' neighbours their part of its curvature term.
    fn quadratic_integral(&self, mesh: &Mesh) -> Vec<f64> {
        let mut integral = linear_integral(mesh);
        // r[u]: Σ over the elements e at u of A_e reach_e(u), over u's summed area.
        let mut r = vec![Vec3::ZERO; mesh.vertices.len()];
        for (e, s) in mesh.elements.iter().zip(&self.stencils) {
            if s.some() {
                for (&v, reach) in e.v.iter().zip(s.reaches()) {
                    r[v as usize] += reach * (s.area * self.inverse_weight[v as usize]);
                }
            }
        }
        // The gradient each element lends its corners weighs its own corners' values.
        for (e, s) in mesh.elements.iter().zip(&self.stencils) {
            if s.some() {
                let reach: Vec3 = e.v.iter().map(|&v| r[v as usize]).sum();
                for (&v, grad) in e.v.iter().zip(s.grads()) {
                    integral[v as usize] += f64::from(s.area * grad.dot(reach));
                }
            }
        }
        integral
    }

    /// Each element's mean of `values` (one per vertex; per channel, in `f64`), in the mesh's
    /// element order.
    pub fn means<T: Field>(&self, mesh: &Mesh, values: &[T]) -> Vec<DVec3> {
        // (summed in f64, as the corners' average always was)
        let linear =
            |v: [u32; 3]| v.iter().map(|&v| values[v as usize].wide()).sum::<DVec3>() / 3.0;
        if self.rule == MeanRule::Linear {
            return mesh.elements.iter().map(|e| linear(e.v)).collect();
        }
        debug_assert!(self.fits(mesh));
        // The recovered gradient at each vertex (the area-weighted mean of its elements'), one
        // component field per axis, and whether any element lent it one.
        let mut grad = vec![[T::default(); 3]; values.len()];
        let mut sloped = vec![false; values.len()];
        for (e, s) in mesh.elements.iter().zip(&self.stencils) {
            if !s.some() {
                continue;
            }
            let f = e.v.map(|v| values[v as usize]);
            if f.iter().all(|&x| x == T::default()) {
                continue; // no slope (most receivers of a shot face away from its source)
            }
            let g = gradient(s, f);
            for &v in &e.v {
                let share = s.area * self.inverse_weight[v as usize];
                let at = &mut grad[v as usize];
                for k in 0..3 {
                    at[k] = at[k] + g[k] * share;
                }
                sloped[v as usize] = true;
            }
        }
        mesh.elements
            .iter()
            .zip(&self.stencils)
            .map(|(e, s)| {
                let base = linear(e.v);
                if !s.some() || !e.v.iter().any(|&v| sloped[v as usize]) {
                    return base;
                }
                // Σᵢ gᵢ·rᵢ with r₀ = −(r₁ + r₂): (g₁ − g₀)·r₁ + (g₂ − g₀)·r₂.
                let [g0, g1, g2] = e.v.map(|v| grad[v as usize]);
                let mut curve = T::default();
                for k in 0..3 {
                    let minus = g0[k] * -1.0;
                    curve =
                        curve + (g1[k] + minus) * s.reach[0][k] + (g2[k] + minus) * s.reach[1][k];
                }
                base + curve.wide()
            })
            .collect()
    }
}

/// Each vertex's weight in the integral by the corners' average: a third of the area of each
/// element it is a corner of.
fn linear_integral(mesh: &Mesh) -> Vec<f64> {
    let mut integral = vec![0.0f64; mesh.vertices.len()];
    for e in &mesh.elements {
        let third = f64::from(mesh.tri(e).area()) / 3.0;
        e.v.iter().for_each(|&v| integral[v as usize] += third);
    }
    integral
}

/// The stencil of the element of `mesh` with corners `v`; `None` where one is hidden (it lends
/// no gradient and keeps the corners' average) or the element is degenerate.
fn element_stencil(mesh: &Mesh, v: [u32; 3]) -> Option<Stencil> {
    let corners = v.map(|v| mesh.vertices[v as usize]);
    if corners.iter().any(|c| c.hidden()) {
        return None;
    }
    stencil(corners.map(|c| c.pos))
}

/// The stencil of the element with corners `p`; `None` for a degenerate one.
fn stencil(p: [Vec3; 3]) -> Option<Stencil> {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    let twice_area = n.length();
    if !(twice_area > 0.0 && twice_area.is_finite()) {
        return None;
    }
    let unit = n / twice_area;
    // ∇λᵢ points from the opposite edge towards corner i, of length 1 / height.
    let grad = [1, 2].map(|i| unit.cross(p[(i + 2) % 3] - p[(i + 1) % 3]) / twice_area);
    let reach = [1, 2].map(|i| (p[(i + 1) % 3] + p[(i + 2) % 3] - 2.0 * p[i]) / 24.0);
    Some(Stencil {
        area: 0.5 * twice_area,
        grad,
        reach,
    })
}

/// The gradient of the linear interpolant of `f` over the element of `s`, per axis:
/// `Σᵢ fᵢ ∇λᵢ = (f₁ − f₀) ∇λ₁ + (f₂ − f₀) ∇λ₂`.
fn gradient<T: Field>(s: &Stencil, f: [T; 3]) -> [T; 3] {
    let (d1, d2) = (f[1] + f[0] * -1.0, f[2] + f[0] * -1.0);
    let axis = |k: usize| d1 * s.grad[0][k] + d2 * s.grad[1][k];
    [axis(0), axis(1), axis(2)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Element, Mesh, Vertex};

    /// A square `[0, n]²` in the plane z = 0 cut into `2n²` right triangles, facing +z.
    pub(super) fn grid(n: u32) -> Mesh {
        let mut mesh = Mesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let pos = Vec3::new(i as f32, j as f32, 0.0);
                mesh.vertices.push(Vertex {
                    pos,
                    normal: Vec3::Z,
                    eval: pos,
                });
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                for v in [[a, b, c], [a, c, d]] {
                    mesh.elements.push(Element {
                        v,
                        object: 0,
                        patch: 0,
                    });
                }
            }
        }
        mesh
    }

    /// Splits element `e` of `mesh` at the middle of its first edge, as refinement does: it
    /// keeps its index and shrinks, the other half is appended.
    pub(super) fn split_first_edge(mesh: &mut Mesh, e: usize) {
        let [a, b, c] = mesh.elements[e].v;
        let pos = (mesh.vertices[a as usize].pos + mesh.vertices[b as usize].pos) * 0.5;
        mesh.vertices.push(Vertex {
            pos,
            normal: Vec3::Z,
            eval: pos,
        });
        let m = mesh.vertices.len() as u32 - 1;
        mesh.elements[e].v = [a, m, c];
        mesh.elements.push(Element {
            v: [m, b, c],
            object: 0,
            patch: 0,
        });
    }

    /// The area-weighted mean over the mesh of the elements' means of `f` at the vertices.
    fn mean_of(mesh: &Mesh, rule: MeanRule, f: impl Fn(Vec3) -> f32) -> f64 {
        let values: Vec<f32> = mesh.vertices.iter().map(|v| f(v.pos)).collect();
        let means = ElementMeans::new(mesh, rule).means(mesh, &values);
        let (mut sum, mut area) = (0.0f64, 0.0f64);
        for (e, m) in mesh.elements.iter().zip(means) {
            let a = mesh.tri(e).area() as f64;
            sum += a * m.x;
            area += a;
        }
        sum / area
    }

    #[test]
    fn both_rules_are_exact_for_linear_fields() {
        let mesh = grid(6);
        let f = |p: Vec3| 2.0 + 0.5 * p.x - 0.25 * p.y;
        for rule in [MeanRule::Linear, MeanRule::Quadratic] {
            assert!((mean_of(&mesh, rule, f) - 2.75).abs() < 1e-5, "{rule:?}");
        }
    }

    #[test]
    fn the_quadratic_rule_finds_a_peaks_mean_that_the_corners_understate() {
        // A concave peak over [0, n]², positive everywhere (0.5 at the corners): its mean is
        // 1 - 1/6; the corners' average understates it by 1/(3n²) for unit cells.
        let mut left = Vec::new();
        for n in [8u32, 16] {
            let mesh = grid(n);
            let c = n as f32 / 2.0;
            let f = |p: Vec3| 1.0 - ((p.x - c).powi(2) + (p.y - c).powi(2)) / (n * n) as f32;
            let exact = 1.0 - 1.0 / 6.0;
            let linear = mean_of(&mesh, MeanRule::Linear, f);
            let quadratic = mean_of(&mesh, MeanRule::Quadratic, f);
            let cells = f64::from(n * n);
            assert!(
                ((exact - linear) * 3.0 * cells - 1.0).abs() < 1e-3,
                "n {n}: linear {linear} against {exact}"
            );
            // The gradients recovered at the square's edge are one-sided, so the boundary
            // elements are corrected less than the interior ones, which are corrected exactly:
            // what is left is a fraction of the linear rule's error, the smaller the fewer of
            // the elements are at the edge.
            left.push((quadratic - exact).abs() / (exact - linear));
            assert!(
                left[left.len() - 1] < 0.2,
                "n {n}: quadratic {quadratic} against {exact} (linear {linear})"
            );
        }
        assert!(left[1] < 0.6 * left[0], "{left:?}");
    }

    #[test]
    fn the_integral_weights_sum_the_elements_means() {
        let mesh = grid(5);
        let values: Vec<f32> = (mesh.vertices.iter())
            .map(|v| 3.0 + (v.pos.x * 0.7).sin() + 0.2 * v.pos.y * v.pos.y)
            .collect();
        for rule in [MeanRule::Linear, MeanRule::Quadratic] {
            let means = ElementMeans::new(&mesh, rule);
            let summed: f64 = (mesh.elements.iter().zip(means.means(&mesh, &values)))
                .map(|(e, m)| mesh.tri(e).area() as f64 * m.x)
                .sum();
            let integral = means.integral(&mesh, &values);
            assert!(
                (integral - summed).abs() < 1e-5 * summed,
                "{rule:?}: {integral} {summed}"
            );
        }
    }

    #[test]
    fn fitting_after_a_split_gives_what_a_fresh_build_gives() {
        let mut mesh = grid(4);
        let mut means = ElementMeans::new(&mesh, MeanRule::Quadratic);
        split_first_edge(&mut mesh, 9);
        assert!(!means.fits(&mesh));
        means.fit(&mesh);
        assert!(means.fits(&mesh));
        let fresh = ElementMeans::new(&mesh, MeanRule::Quadratic);
        let values: Vec<f32> = (mesh.vertices.iter())
            .map(|v| 1.0 + v.pos.x * v.pos.y)
            .collect();
        for (x, y) in means
            .means(&mesh, &values)
            .iter()
            .zip(fresh.means(&mesh, &values))
        {
            assert!((x.x - y.x).abs() < 1e-5, "{x} {y}");
        }
        assert!((means.integral(&mesh, &values) - fresh.integral(&mesh, &values)).abs() < 1e-4);
    }

    #[test]
    fn hidden_corners_keep_the_corners_average() {
        let mut mesh = grid(4);
        mesh.vertices[0].normal = Vec3::ZERO;
        let values: Vec<f32> = (mesh.vertices.iter())
            .map(|v| (v.pos.x - 2.0).powi(2) + 1.0)
            .collect();
        let quadratic = ElementMeans::new(&mesh, MeanRule::Quadratic).means(&mesh, &values);
        let linear = ElementMeans::new(&mesh, MeanRule::Linear).means(&mesh, &values);
        assert_eq!(quadratic[0], linear[0]);
        assert_ne!(quadratic[10], linear[10]);
    }
}
