//! Scenes built in code for the tests.
#![allow(dead_code, reason = "each test file uses part of the helpers")]

use glam::Vec3;
use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::geom::Tri;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::scene::{Object, Scene, SceneTri};
use occ_radiosity::solver::{Solver, SolverConfig, Until};

/// A closed axis-aligned box `lo..hi` with faces facing inward, one object per face, named
/// `-x +x -y +y -z +z`; `emission(face)` gives each face's Ke.
pub fn closed_box(lo: Vec3, hi: Vec3, reflectance: f32, emission: impl Fn(usize) -> f32) -> Scene {
    let mut scene = Scene::default();
    let names = ["-x", "+x", "-y", "+y", "-z", "+z"];
    for (f, name) in names.iter().enumerate() {
        let axis = f / 2;
        let at_hi = f % 2 == 1;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let corner = |a: bool, b: bool| {
            let mut p = lo;
            p[axis] = if at_hi { hi[axis] } else { lo[axis] };
            p[u] = if a { hi[u] } else { lo[u] };
            p[v] = if b { hi[v] } else { lo[v] };
            p
        };
        let (p0, p1, p2, p3) = (
            corner(false, false),
            corner(true, false),
            corner(true, true),
            corner(false, true),
        );
        let mut t = [Tri::new(p0, p1, p2), Tri::new(p0, p2, p3)];
        let inward = if at_hi { -1.0 } else { 1.0 };
        if t[0].normal()[axis] * inward < 0.0 {
            t = [Tri::new(p0, p2, p1), Tri::new(p0, p3, p2)];
        }
        scene.objects.push(Object {
            name: name.to_string(),
            reflectance: Vec3::splat(reflectance),
            emission: Vec3::splat(emission(f)),
        });
        for tri in t {
            scene.triangles.push(SceneTri {
                tri,
                object: f as u32,
            });
        }
    }
    scene
}

/// A square `x, z ∈ [-half, half]` at height `y` facing `up` or down, as two triangles of object
/// `object`.
pub fn square(half: f32, y: f32, up: bool, object: u32) -> [SceneTri; 2] {
    let p = [
        Vec3::new(-half, y, -half),
        Vec3::new(half, y, -half),
        Vec3::new(half, y, half),
        Vec3::new(-half, y, half),
    ];
    let mut t = [Tri::new(p[0], p[2], p[1]), Tri::new(p[0], p[3], p[2])];
    if (t[0].normal().y > 0.0) != up {
        t = [Tri::new(p[0], p[1], p[2]), Tri::new(p[0], p[2], p[3])];
    }
    t.map(|tri| SceneTri { tri, object })
}

/// A unit square light (`Ke = 1`, black) facing down at height 1 over a floor of half-width
/// `floor_half` (`Kd = 0.5`) at height 0, open all round.
pub fn light_over_floor(floor_half: f32) -> Scene {
    let mut scene = Scene::default();
    scene.objects.push(Object {
        name: "light".into(),
        reflectance: Vec3::ZERO,
        emission: Vec3::ONE,
    });
    scene.objects.push(Object {
        name: "floor".into(),
        reflectance: Vec3::splat(0.5),
        emission: Vec3::ZERO,
    });
    scene.triangles.extend(square(0.5, 1.0, false, 0));
    scene.triangles.extend(square(floor_half, 0.0, true, 1));
    scene
}

/// Solves `scene` at coarse settings (patches 1, elements 0.5, 4 rays per form factor) until
/// `until`.
pub fn solve_coarse(scene: &Scene, until: Until) -> Solver<'_> {
    let mesh = Mesh::from_scene(
        scene,
        MeshConfig {
            patch_size: 1.0,
            element_size: 0.5,
        },
    );
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 4,
            offset: 1e-6 * scene.diagonal(),
            ..FormFactorConfig::default()
        },
        until,
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(scene, mesh, config);
    solver.run(|_, _| {});
    solver
}
