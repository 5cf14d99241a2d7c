//! `solution.ply`: the mesh with per-vertex radiosity, ASCII PLY readable by MeshLab and Blender.
//! Each element gets its own three corners (a vertex shared by two objects of different
//! reflectance has two radiosities), with float `b_r b_g b_b` (B, not tone mapped) and 8-bit
//! sRGB `red green blue` for viewers.

use std::fmt::Write;

use glam::Vec3;

use crate::solver::Solver;

/// Returns the PLY text; `exposure` scales B/π before the sRGB colours are made.
pub fn solution_ply(solver: &Solver, exposure: f32) -> String {
    let mesh = &solver.mesh;
    let ambient = Vec3::ZERO;
    let n = mesh.elements.len();
    let mut s = String::with_capacity(n * 3 * 80);
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\ncomment occ radiosity solution: b_* is radiosity B = pi * radiance\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float b_r\nproperty float b_g\nproperty float b_b\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {n}\nproperty list uchar int vertex_indices\nend_header\n",
        n * 3
    );
    for i in 0..n {
        let b = solver.element_corner_radiosity(i, ambient);
        let tri = mesh.tri(&mesh.elements[i]);
        for (p, c) in tri.v.into_iter().zip(b) {
            let rgb = (c / std::f32::consts::PI * exposure)
                .to_array()
                .map(super::srgb_byte);
            let _ = writeln!(
                s,
                "{} {} {} {} {} {} {} {} {}",
                p.x, p.y, p.z, c.x, c.y, c.z, rgb[0], rgb[1], rgb[2]
            );
        }
    }
    for i in 0..n {
        let _ = writeln!(s, "3 {} {} {}", 3 * i, 3 * i + 1, 3 * i + 2);
    }
    s
}
