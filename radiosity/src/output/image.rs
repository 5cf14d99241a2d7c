//! `image.png`: a view of the solution from the scene camera (or a default view), drawn by a
//! small software rasteriser with a z-buffer and Gouraud interpolation of the vertex radiosities
//! (with the ambient term), tone mapped as radiance × exposure through the sRGB curve.

use glam::Vec3;

use super::{OutputError, encode_png, srgb_byte};
use crate::scene::Camera;
use crate::solver::Solver;

/// Returns the camera to use: the scene's, or one looking at the bounding box from -z.
pub fn camera_for(solver: &Solver) -> Camera {
    solver.scene.camera.unwrap_or_else(|| {
        let (lo, hi) = solver.scene.bounds();
        let centre = (lo + hi) * 0.5;
        let size = (hi - lo).max_element();
        Camera {
            pos: centre - Vec3::Z * (size * 2.2),
            dir: Vec3::Z,
            up: Vec3::Y,
            fov_deg: 40.0,
        }
    })
}

/// Renders the solution to RGB8 pixels (`width × height`).
pub fn render(solver: &Solver, camera: &Camera, width: u32, height: u32, exposure: f32) -> Vec<u8> {
    let aspect = width as f32 / height as f32;
    let tan_x = (camera.fov_deg.to_radians() * 0.5).tan();
    let tan_y = tan_x / aspect;
    let near = 1e-3 * solver.scene.diagonal();
    let right = camera.dir.cross(camera.up).normalize();
    let up = right.cross(camera.dir);
    let (w, h) = (width as usize, height as usize);
    let mut depth = vec![f32::INFINITY; w * h];
    let mut colour = vec![Vec3::ZERO; w * h];
    let ambient = solver.ambient();
    for (i, e) in solver.mesh.elements.iter().enumerate() {
        let tri = solver.mesh.tri(e);
        let b = solver.element_corner_radiosity(i, ambient);
        let cam = tri.v.map(|v| {
            let r = v - camera.pos;
            Vec3::new(r.dot(right), r.dot(up), r.dot(camera.dir))
        });
        if cam.iter().any(|q| q.z < near) {
            continue; // behind or too close to the eye: not clipped, simply skipped
        }
        // Screen x, y and -1/z (interpolates linearly in screen space; smaller is nearer).
        let s = cam.map(|q| {
            Vec3::new(
                (q.x / q.z / tan_x * 0.5 + 0.5) * w as f32,
                (0.5 - q.y / q.z / tan_y * 0.5) * h as f32,
                -1.0 / q.z,
            )
        });
        raster_triangle(&s, &b, w, h, &mut depth, &mut colour);
    }
    let scale = exposure / std::f32::consts::PI;
    colour
        .iter()
        .flat_map(|c| (*c * scale).to_array().map(srgb_byte))
        .collect()
}

/// Fills one screen-space triangle with interpolated colours where it is nearest.
fn raster_triangle(
    s: &[Vec3; 3],
    c: &[Vec3; 3],
    w: usize,
    h: usize,
    depth: &mut [f32],
    colour: &mut [Vec3],
) {
    let area = edge(s[0], s[1], s[2]);
    if area.abs() < 1e-12 {
        return;
    }
    let lo = s[0].min(s[1]).min(s[2]).max(Vec3::ZERO);
    let hi = s[0]
        .max(s[1])
        .max(s[2])
        .min(Vec3::new(w as f32 - 1.0, h as f32 - 1.0, 0.0));
    for y in lo.y.floor() as usize..=hi.y.max(0.0).ceil() as usize {
        for x in lo.x.floor() as usize..=hi.x.max(0.0).ceil() as usize {
            if x >= w || y >= h {
                continue;
            }
            let p = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, 0.0);
            let b = [
                edge(s[1], s[2], p) / area,
                edge(s[2], s[0], p) / area,
                edge(s[0], s[1], p) / area,
            ];
            if b.iter().any(|&v| v < -1e-6) {
                continue;
            }
            let z = b[0] * s[0].z + b[1] * s[1].z + b[2] * s[2].z;
            let k = y * w + x;
            if z < depth[k] {
                depth[k] = z;
                colour[k] = c[0] * b[0] + c[1] * b[1] + c[2] * b[2];
            }
        }
    }
}

fn edge(a: Vec3, b: Vec3, p: Vec3) -> f32 {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
}

/// Renders and encodes `image.png`.
pub fn image_png(
    solver: &Solver,
    width: u32,
    height: u32,
    exposure: f32,
) -> Result<Vec<u8>, OutputError> {
    let camera = camera_for(solver);
    encode_png(
        &render(solver, &camera, width, height, exposure),
        width,
        height,
    )
}
