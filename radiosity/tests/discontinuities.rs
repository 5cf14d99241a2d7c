//! Discontinuities seen through the solver (issue 10, causes 2 and 3): a light hung a hair below
//! a ceiling takes no power from the ceiling it covers, and a box standing on a floor keeps its
//! footprint dark while the floor along its base receives light.

mod common;

use glam::Vec3;
use occ_radiosity::geom::Tri;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::scene::{Object, Scene, SceneTri};
use occ_radiosity::solver::{Solver, SolverConfig, Until};

fn add_object(scene: &mut Scene, name: &str, rho: f32, ke: f32, tris: Vec<Tri>) {
    scene.objects.push(Object {
        name: name.into(),
        reflectance: Vec3::splat(rho),
        emission: Vec3::splat(ke),
    });
    let object = scene.objects.len() as u32 - 1;
    scene
        .triangles
        .extend(tris.into_iter().map(|tri| SceneTri { tri, object }));
}

/// A horizontal rectangle at height `y` facing down (`down`) or up.
fn rect(x0: f32, x1: f32, z0: f32, z1: f32, y: f32, down: bool) -> Vec<Tri> {
    let (a, b, c, d) = (
        Vec3::new(x0, y, z0),
        Vec3::new(x1, y, z0),
        Vec3::new(x1, y, z1),
        Vec3::new(x0, y, z1),
    );
    let t = [Tri::new(a, b, c), Tri::new(a, c, d)];
    t.map(|t| {
        if (t.normal().y < 0.0) == down {
            t
        } else {
            Tri::new(t.v[0], t.v[2], t.v[1])
        }
    })
    .to_vec()
}

fn solved(scene: &Scene, shots: u64) -> Solver<'_> {
    let mesh = Mesh::from_scene(
        scene,
        MeshConfig {
            patch_size: 150.0,
            element_size: 50.0,
        },
    );
    let config = SolverConfig {
        until: Until::Shots(shots),
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(scene, mesh, config);
    solver.run(|_, _| {});
    solver
}

#[test]
fn a_light_a_hair_below_a_ceiling_takes_no_power_from_the_ceiling_behind_it() {
    // A closed 556 x 549 x 559 room; the light (130 x 105) hangs 0.1 below the ceiling.
    let mut scene = common::closed_box(Vec3::ZERO, Vec3::new(556.0, 549.0, 559.0), 0.7, |_| 0.0);
    let ceiling = 3; // the +y face
    add_object(
        &mut scene,
        "light",
        0.0,
        10.0,
        rect(213.0, 343.0, 227.0, 332.0, 548.9, true),
    );
    let solver = solved(&scene, 12);
    let mesh = &solver.mesh;
    let mut behind = 0.0;
    for e in mesh.elements.iter().filter(|e| e.object == ceiling) {
        let t = mesh.tri(e);
        let c = t.centroid();
        if c.x > 213.0 && c.x < 343.0 && c.z > 227.0 && c.z < 332.0 {
            behind += t.area();
            for v in e.v {
                assert_eq!(solver.irradiance[v as usize], Vec3::ZERO, "ceiling at {c}");
            }
            assert_eq!(
                solver.unshot[e.patch as usize].length(),
                0.0,
                "ceiling at {c}"
            );
        }
    }
    // The elements behind the light are exactly its outline: none straddles it.
    assert!((behind - 130.0 * 105.0).abs() < 1.0, "{behind}");
}

#[test]
fn a_box_on_a_floor_keeps_its_footprint_dark_and_its_base_line_lit() {
    // An open floor, a 100-unit box standing on it, a light above to one side.
    let mut scene = Scene::default();
    add_object(
        &mut scene,
        "floor",
        0.5,
        0.0,
        rect(0.0, 1000.0, 0.0, 1000.0, 0.0, false),
    );
    let (lo, hi) = (Vec3::new(400.0, 0.0, 400.0), Vec3::new(600.0, 200.0, 600.0));
    let mut box_tris = rect(lo.x, hi.x, lo.z, hi.z, hi.y, false);
    let corner = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    for (a, b) in [
        ((lo.x, lo.z), (hi.x, lo.z)),
        ((hi.x, lo.z), (hi.x, hi.z)),
        ((hi.x, hi.z), (lo.x, hi.z)),
        ((lo.x, hi.z), (lo.x, lo.z)),
    ] {
        let q = [
            corner(a.0, 0.0, a.1),
            corner(b.0, 0.0, b.1),
            corner(b.0, hi.y, b.1),
            corner(a.0, hi.y, a.1),
        ];
        for t in [Tri::new(q[0], q[1], q[2]), Tri::new(q[0], q[2], q[3])] {
            let out = t.centroid() - Vec3::new(500.0, t.centroid().y, 500.0);
            box_tris.push(if t.normal().dot(out) > 0.0 {
                t
            } else {
                Tri::new(t.v[0], t.v[2], t.v[1])
            });
        }
    }
    add_object(&mut scene, "box", 0.5, 0.0, box_tris);
    add_object(
        &mut scene,
        "light",
        0.0,
        10.0,
        rect(100.0, 300.0, 450.0, 550.0, 800.0, true),
    );
    let solver = solved(&scene, 3);
    let mesh = &solver.mesh;
    let inside = |p: Vec3| p.x > lo.x && p.x < hi.x && p.z > lo.z && p.z < hi.z;
    let mut base_line_lit = 0;
    for (i, v) in mesh.vertices.iter().enumerate() {
        let on_floor = v.pos.y == 0.0 && (v.normal == Vec3::Y || v.hidden());
        if !on_floor {
            continue;
        }
        let h = solver.irradiance[i];
        if inside(v.pos) {
            assert_eq!(h, Vec3::ZERO, "footprint point {v:?}");
        }
        // The lit side of the base line faces the light (x = 400): its points receive about
        // what the floor just beside them receives, not the zero of an edge-on view.
        if (v.pos.x - lo.x).abs() < 1e-3
            && v.pos.z > lo.z + 20.0
            && v.pos.z < hi.z - 20.0
            && !v.hidden()
        {
            assert!(v.eval.x < lo.x, "{v:?} is evaluated inside the box");
            assert!(h.x > 0.0, "base line point {v:?} is dark");
            base_line_lit += 1;
        }
    }
    assert!(base_line_lit >= 2, "{base_line_lit}");
}
