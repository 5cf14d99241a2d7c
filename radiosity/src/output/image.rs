//! `image.png`: a view of the solution from the scene camera (or a default view that sees the
//! scene, [`default_camera`]), drawn by a
//! small software rasteriser with a z-buffer and Gouraud interpolation of the vertex radiosities
//! (with the ambient term), tone mapped as radiance × exposure through the sRGB curve.

use glam::Vec3;

use super::{OutputError, encode_png, srgb_byte};
use crate::scene::{Camera, Scene};
use crate::solver::Solver;

/// Returns the camera to use: the scene's, or [`default_camera`].
pub fn camera_for(solver: &Solver) -> Camera {
    solver
        .scene
        .camera
        .unwrap_or_else(|| default_camera(solver.scene))
}

/// A camera that sees the scene when the file names none. Candidates look at the centre of
/// the bounds from outside, along the six axes and the eight diagonals, and from inside, from
/// near each of the eight corners; each is scored by a small depth-buffered view of the scene
/// triangles, counting the pixels where the nearest surface faces the camera and subtracting
/// twice those where it turns its back (the outside of a closed room). An outside view that
/// sees into the scene through an open side (at least a third of the pixels front-facing) is
/// taken first; otherwise the best view from inside a corner.
pub fn default_camera(scene: &Scene) -> Camera {
    let (lo, hi) = scene.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-30);
    let up_for = |d: Vec3| {
        if d.normalize().y.abs() > 0.9 {
            Vec3::Z
        } else {
            Vec3::Y
        }
    };
    let fov = 40.0f32;
    let distance = radius / (fov.to_radians() * 0.5).tan() * 1.05;
    let mut outside = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut d = Vec3::ZERO;
            d[axis] = sign;
            outside.push(d);
        }
    }
    for corner in 0..8 {
        let pick = |bit: u32| if corner & (1 << bit) != 0 { 1.0 } else { -1.0 };
        outside.push(Vec3::new(pick(0), pick(1) * 0.5, pick(2)).normalize());
    }
    // Front views first, so that ties keep the classic view from -z.
    outside.sort_by_key(|d| d.z >= 0.0);
    let view = |pos: Vec3, fov_deg: f32| {
        let dir = (centre - pos).normalize();
        Camera {
            pos,
            dir,
            up: up_for(dir),
            fov_deg,
        }
    };
    const PIXELS: usize = 48 * 48;
    let best = |cams: Vec<Camera>| {
        cams.into_iter()
            .map(|c| (facing_score(scene, &c, 48), c))
            .fold(None, |b: Option<(i64, Camera)>, x| match b {
                Some(b) if b.0 >= x.0 => Some(b),
                _ => Some(x),
            })
    };
    let from_outside = best(
        outside
            .iter()
            .map(|&d| view(centre + d * distance, fov))
            .collect(),
    );
    if let Some((score, cam)) = from_outside
        && score >= (PIXELS / 3) as i64
    {
        return cam;
    }
    let inside = (0..8)
        .map(|corner| {
            let pick = |bit: u32, a: f32, b: f32| if corner & (1 << bit) != 0 { b } else { a };
            let p = Vec3::new(
                pick(0, lo.x, hi.x),
                pick(1, lo.y, hi.y),
                pick(2, lo.z, hi.z),
            );
            view(centre + (p - centre) * 0.85, 70.0)
        })
        .collect();
    match (best(inside), from_outside) {
        (Some(i), Some(o)) if i.0 > o.0 => i.1,
        (_, Some(o)) => o.1,
        (Some(i), None) => i.1,
        (None, None) => view(centre - Vec3::Z * distance, fov),
    }
}

/// Pixels (of `size × size`) whose nearest scene triangle faces the camera, minus twice those
/// whose nearest triangle turns its back. Large scenes are sampled (at most 200,000 triangles).
fn facing_score(scene: &Scene, camera: &Camera, size: usize) -> i64 {
    let tan = (camera.fov_deg.to_radians() * 0.5).tan();
    let near = 1e-4 * scene.diagonal();
    let right = camera.dir.cross(camera.up).normalize();
    let up = right.cross(camera.dir);
    let mut depth = vec![f32::INFINITY; size * size];
    let mut facing = vec![Vec3::ZERO; size * size];
    let stride = (scene.triangles.len() / 200_000).max(1);
    for t in scene.triangles.iter().step_by(stride) {
        let cam = t.tri.v.map(|v| {
            let r = v - camera.pos;
            Vec3::new(r.dot(right), r.dot(up), r.dot(camera.dir))
        });
        if cam.iter().any(|q| q.z < near) {
            continue;
        }
        let s = cam.map(|q| {
            Vec3::new(
                (q.x / q.z / tan * 0.5 + 0.5) * size as f32,
                (0.5 - q.y / q.z / tan * 0.5) * size as f32,
                -1.0 / q.z,
            )
        });
        let front = t.tri.normal().dot(camera.pos - t.tri.v[0]) > 0.0;
        let c = if front { Vec3::X } else { Vec3::Y };
        raster_triangle(&s, &[c; 3], size, size, &mut depth, &mut facing);
    }
    facing
        .iter()
        .map(|f| {
            if f.x > 0.5 {
                1
            } else if f.y > 0.5 {
                -2
            } else {
                0
            }
        })
        .sum()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, MeshConfig};
    use crate::scene::cornell;
    use crate::solver::{SolverConfig, Until};

    #[test]
    fn the_default_camera_looks_into_an_open_box_and_the_image_is_not_one_colour() {
        // The Cornell box opens towards -z; turn it around so that it opens towards +z, and
        // drop the file's camera: the default view must find the opening.
        let mut scene = cornell::load(true).expect("scene");
        for t in &mut scene.triangles {
            for v in &mut t.tri.v {
                v.z = 559.2 - v.z;
                v.x = 556.0 - v.x;
            }
        }
        scene.camera = None;
        let cam = default_camera(&scene);
        assert!(cam.dir.z < -0.5, "{cam:?}");
        let mesh = Mesh::from_scene(
            &scene,
            MeshConfig {
                patch_size: 300.0,
                element_size: 100.0,
            },
        );
        let config = SolverConfig {
            until: Until::Shots(4),
            ..SolverConfig::default()
        };
        let mut solver = Solver::new(&scene, mesh, config);
        solver.run(|_, _| {});
        let pixels = render(&solver, &camera_for(&solver), 64, 64, 1.0);
        let mut colours: Vec<[u8; 3]> = pixels.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        colours.sort_unstable();
        colours.dedup();
        assert!(colours.len() > 50, "{} colours", colours.len());
    }

    #[test]
    fn a_closed_room_is_seen_from_inside_a_corner() {
        let mut scene = cornell::load(false).expect("scene");
        // Close the front with a wall facing in.
        let (a, b, c, d) = (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(552.8, 0.0, 0.0),
            Vec3::new(556.0, 548.8, 0.0),
            Vec3::new(0.0, 548.8, 0.0),
        );
        for tri in [
            crate::geom::Tri::new(a, b, c),
            crate::geom::Tri::new(a, c, d),
        ] {
            assert!(tri.normal().z > 0.9);
            scene
                .triangles
                .push(crate::scene::SceneTri { tri, object: 1 });
        }
        scene.camera = None;
        let cam = default_camera(&scene);
        let (lo, hi) = scene.bounds();
        assert!(
            cam.pos.cmpgt(lo).all() && cam.pos.cmplt(hi).all(),
            "{cam:?}"
        );
    }
}
