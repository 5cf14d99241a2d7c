//! Meshing tests: discontinuities, T-junctions, covers and contact, bounded work on hostile
//! input, degenerate input counted.

use glam::Vec3;

use super::*;
use crate::scene::{Object, SceneTri, cornell};

/// `scene` meshed with patches and elements of at most `size`.
fn meshed(scene: &Scene, size: f32) -> Mesh {
    Mesh::from_scene(
        scene,
        MeshConfig {
            patch_size: size,
            element_size: size,
        },
    )
}

/// A scene of one object per entry, each a list of triangles.
fn scene_of(objects: &[(&str, Vec<[Vec3; 3]>)]) -> Scene {
    let mut scene = Scene::default();
    for (i, (name, tris)) in objects.iter().enumerate() {
        scene.objects.push(Object {
            name: (*name).into(),
            reflectance: Vec3::splat(0.5),
            emission: Vec3::ZERO,
        });
        for t in tris {
            scene.triangles.push(SceneTri {
                tri: Tri::new(t[0], t[1], t[2]),
                object: i as u32,
            });
        }
    }
    scene
}

/// Two triangles making the quad `a b c d` (counter-clockwise seen from the front).
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Vec<[Vec3; 3]> {
    vec![[a, b, c], [a, c, d]]
}

/// A scene of one object from triangles in the plane y = 0 given by (x, z) corners.
fn flat_scene(tris: &[[(f32, f32); 3]]) -> Scene {
    let v = |(x, z): (f32, f32)| Vec3::new(x, 0.0, z);
    scene_of(&[(
        "floor",
        tris.iter().map(|t| [v(t[0]), v(t[1]), v(t[2])]).collect(),
    )])
}

/// Total area of the elements, and of the scene's triangles.
fn areas(mesh: &Mesh, scene: &Scene) -> (f64, f64) {
    let meshed: f64 = mesh
        .elements
        .iter()
        .map(|e| mesh.tri(e).area() as f64)
        .sum();
    let input: f64 = scene.triangles.iter().map(|t| t.tri.area() as f64).sum();
    (meshed, input)
}

/// Whether some element of `object` has the segment `p..q` (in its plane) crossing its interior.
fn straddled(mesh: &Mesh, object: u32, p: Vec3, q: Vec3) -> bool {
    mesh.elements
        .iter()
        .filter(|e| e.object == object)
        .any(|e| {
            let t = mesh.tri(e);
            let m = t.normal().cross(q - p).normalize();
            let s = t.v.map(|v| m.dot(v - p));
            let crosses = s.iter().any(|&x| x > 1e-3) && s.iter().any(|&x| x < -1e-3);
            // ... and the segment's line passes between the corners within the segment's extent.
            let d = (q - p).normalize();
            let along = t.v.map(|v| d.dot(v - p));
            let len = (q - p).length();
            crosses && along.iter().any(|&a| a > 1e-3 && a < len - 1e-3)
        })
}

fn object(scene: &Scene, name: &str) -> u32 {
    scene
        .objects
        .iter()
        .position(|o| o.name == name)
        .expect(name) as u32
}

#[test]
fn cornell_floor_is_cut_along_the_block_footprints_and_the_footprints_are_hidden() {
    let scene = cornell::load(true).expect("scene");
    let mesh = meshed(&scene, 1000.0);
    assert!(mesh.stats.d0_cuts > 0, "{:?}", mesh.stats);
    let floor = object(&scene, "floor");
    // The short block's front face stands on the floor from (130, 0, 65) to (290, 0, 114).
    let (p, q) = (Vec3::new(130.0, 0.0, 65.0), Vec3::new(290.0, 0.0, 114.0));
    assert!(!straddled(&mesh, floor, p, q));
    // Its footprint (centre about (186, 0, 169)) is hidden; the floor beside it is not.
    let hidden_at = |x: f32, z: f32| {
        mesh.elements
            .iter()
            .filter(|e| e.object == floor)
            .find(|e| {
                let t = mesh.tri(e);
                let b = t.barycentric(Vec3::new(x, 0.0, z));
                b.iter().all(|&c| c > 0.0)
            })
            .map(|e| e.v.iter().all(|&v| mesh.vertices[v as usize].hidden()))
    };
    assert_eq!(hidden_at(186.0, 169.0), Some(true));
    assert_eq!(hidden_at(368.0, 351.0), Some(true), "tall block footprint");
    assert_eq!(hidden_at(100.0, 400.0), Some(false));
    let (m, s) = areas(&mesh, &scene);
    assert!((m - s).abs() < 1e-4 * s, "{m} {s}");
}

#[test]
fn a_light_a_hair_below_the_ceiling_hides_the_ceiling_it_covers() {
    // The Cornell light hangs 0.1 mm below the ceiling, facing down like the ceiling: the
    // ceiling is cut along the light's outline and the part behind the light is hidden.
    let scene = cornell::load(true).expect("scene");
    let mesh = meshed(&scene, 1000.0);
    let ceiling = object(&scene, "ceiling");
    let corners = [
        Vec3::new(343.0, 548.8, 227.0),
        Vec3::new(343.0, 548.8, 332.0),
        Vec3::new(213.0, 548.8, 332.0),
        Vec3::new(213.0, 548.8, 227.0),
    ];
    for i in 0..4 {
        assert!(!straddled(&mesh, ceiling, corners[i], corners[(i + 1) % 4]));
    }
    let (mut covered, mut open) = (0.0, 0.0);
    for e in mesh.elements.iter().filter(|e| e.object == ceiling) {
        let t = mesh.tri(e);
        let c = t.centroid();
        let under = c.x > 213.0 && c.x < 343.0 && c.z > 227.0 && c.z < 332.0;
        let hidden = e.v.iter().all(|&v| mesh.vertices[v as usize].hidden());
        assert_eq!(under, hidden, "ceiling element at {c}");
        if under {
            covered += t.area()
        } else {
            open += t.area()
        };
    }
    assert!((covered - 130.0 * 105.0).abs() < 1.0, "{covered}");
    assert!(open > 0.0);
    // The light itself is not hidden.
    let light = object(&scene, "light");
    assert!(
        mesh.elements
            .iter()
            .filter(|e| e.object == light)
            .all(|e| { e.v.iter().all(|&v| !mesh.vertices[v as usize].hidden()) })
    );
}

/// A 10 x 10 floor facing up with a unit-high 2 x 2 box (four walls facing out and a top) standing
/// on it at `(4..6, 4..6)`.
fn box_on_floor() -> Scene {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let mut walls = Vec::new();
    let (lo, hi) = (4.0, 6.0);
    walls.extend(quad(
        p(lo, 0.0, lo),
        p(hi, 0.0, lo),
        p(hi, 1.0, lo),
        p(lo, 1.0, lo),
    )); // -z
    walls.extend(quad(
        p(hi, 0.0, hi),
        p(lo, 0.0, hi),
        p(lo, 1.0, hi),
        p(hi, 1.0, hi),
    )); // +z
    walls.extend(quad(
        p(lo, 0.0, hi),
        p(lo, 0.0, lo),
        p(lo, 1.0, lo),
        p(lo, 1.0, hi),
    )); // -x
    walls.extend(quad(
        p(hi, 0.0, lo),
        p(hi, 0.0, hi),
        p(hi, 1.0, hi),
        p(hi, 1.0, lo),
    )); // +x
    let top = quad(
        p(lo, 1.0, lo),
        p(lo, 1.0, hi),
        p(hi, 1.0, hi),
        p(hi, 1.0, lo),
    );
    // Each wall wound so that its normal faces away from the box.
    let walls = walls
        .into_iter()
        .map(|[a, b, c]| {
            let out = (a + b + c) / 3.0 - Vec3::new(5.0, 0.5, 5.0);
            if (b - a).cross(c - a).dot(out) > 0.0 {
                [a, b, c]
            } else {
                [a, c, b]
            }
        })
        .collect();
    let mut scene = scene_of(&[
        (
            "floor",
            quad(
                p(0.0, 0.0, 0.0),
                p(0.0, 0.0, 10.0),
                p(10.0, 0.0, 10.0),
                p(10.0, 0.0, 0.0),
            ),
        ),
        ("walls", walls),
        ("top", top),
    ]);
    for t in &scene.triangles {
        if t.object != 1 {
            assert!(t.tri.normal().dot(Vec3::Y) > 0.99, "winding of {:?}", t.tri);
        }
    }
    scene.objects[0].emission = Vec3::ZERO;
    scene
}

#[test]
fn a_box_on_a_floor_hides_its_footprint_and_splits_its_base_line_points() {
    let scene = box_on_floor();
    let mesh = meshed(&scene, 1.0);
    for e in mesh.elements.iter().filter(|e| e.object == 0) {
        let c = mesh.tri(e).centroid();
        let inside = c.x > 4.0 && c.x < 6.0 && c.z > 4.0 && c.z < 6.0;
        let hidden = e.v.iter().all(|&v| mesh.vertices[v as usize].hidden());
        assert_eq!(inside, hidden, "floor element at {c}");
    }
    // Every floor point on the base line appears twice: a hidden copy for the footprint and a
    // visible one evaluated just outside the box.
    let on_line = |p: Vec3| {
        let inside = |x: f32| (4.0..=6.0).contains(&x);
        p.y == 0.0
            && (((p.x - 4.0).abs() < 1e-4 || (p.x - 6.0).abs() < 1e-4) && inside(p.z)
                || ((p.z - 4.0).abs() < 1e-4 || (p.z - 6.0).abs() < 1e-4) && inside(p.x))
    };
    let floor_points: Vec<&Vertex> = mesh
        .vertices
        .iter()
        .filter(|v| on_line(v.pos) && (v.hidden() || v.normal == Vec3::Y))
        .collect();
    let visible: Vec<&&Vertex> = floor_points.iter().filter(|v| !v.hidden()).collect();
    assert!(visible.len() >= 8, "{}", visible.len());
    assert_eq!(visible.len(), floor_points.len() - visible.len());
    for v in visible {
        let e = v.eval;
        let outside = e.x < 4.0 || e.x > 6.0 || e.z < 4.0 || e.z > 6.0;
        assert!(outside, "{v:?} is evaluated inside the footprint");
    }
}

#[test]
fn the_water_cut_meshes_with_bounded_work() {
    // Before each triangle was cut once, this 46-vertex scene grew without bound (past 1.5 GB
    // in 20 s); now each size meshes well inside a second, even on a loaded machine.
    let text = include_str!("../../../scenes/water-cut.obj");
    let mtl = include_str!("../../../scenes/water-cut.mtl");
    let scene =
        crate::scene::load_obj("water-cut.obj", text, &|_| Ok(mtl.to_string())).expect("scene");
    let diag = scene.diagonal();
    for size in [diag / 4.0, diag / 20.0, 0.5] {
        let start = std::time::Instant::now();
        let mesh = meshed(&scene, size);
        let took = start.elapsed();
        assert!(took.as_secs_f64() < 1.0, "{took:?} at size {size}");
        let s = mesh.stats;
        assert!(s.d0_cuts < 200 && s.pieces < 400, "{s:?}");
        let estimate = MeshConfig {
            patch_size: size,
            element_size: size,
        }
        .estimated_elements(&scene);
        assert!(
            (s.elements as f64) < 4.0 * estimate + 4.0 * s.pieces as f64,
            "{s:?} against an estimate of {estimate}"
        );
        let (m, a) = areas(&mesh, &scene);
        assert!((m - a).abs() < 1e-4 * a, "{m} {a}");
    }
}

#[test]
fn triangles_crossing_each_other_many_times_mesh_within_the_arrangement_bound() {
    // 40 blades through a common axis and 40 random triangles in a cube.
    let mut rng = crate::rng::Pcg32::new(5, 3);
    let mut tris = Vec::new();
    for i in 0..40 {
        let a = i as f32 * std::f32::consts::PI / 40.0;
        let d = Vec3::new(a.cos(), 0.0, a.sin());
        tris.push([
            -d * 3.0 + Vec3::Y * 0.1 * i as f32,
            d * 3.0,
            Vec3::Y * 4.0 + d * 0.5,
        ]);
    }
    let mut r = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0;
    for _ in 0..40 {
        tris.push([r(), r(), r()]);
    }
    let scene = scene_of(&[("tangle", tris)]);
    let mesh = meshed(&scene, 1e3);
    let n = scene.triangles.len();
    let k = n - 1; // at most one cut per other triangle
    let bound = n * (1 + k + k * (k - 1) / 2);
    let s = mesh.stats;
    assert!(s.d0_cuts > 1000, "{s:?}");
    assert!(s.pieces <= bound, "{s:?} bound {bound}");
    let (m, a) = areas(&mesh, &scene);
    assert!((m - a).abs() < 1e-4 * a, "{m} {a}");
}

#[test]
fn every_t_junction_along_a_long_edge_is_split() {
    // A 100 x 10 strip (two triangles) under a strip cut into 100 columns: 99 vertices lie
    // inside the first strip's top edge; all must be inserted, leaving a conforming mesh.
    let mut tris = vec![
        [(0.0, 0.0), (0.0, 10.0), (100.0, 10.0)],
        [(0.0, 0.0), (100.0, 10.0), (100.0, 0.0)],
    ];
    for i in 0..100 {
        let (x0, x1) = (i as f32, i as f32 + 1.0);
        tris.push([(x0, 10.0), (x0, 20.0), (x1, 20.0)]);
        tris.push([(x0, 10.0), (x1, 20.0), (x1, 10.0)]);
    }
    let mesh = meshed(&flat_scene(&tris), 1e3);
    assert_eq!(mesh.stats.t_junction_splits, 99);
    for (a, b) in mesh.edge_list() {
        let n = mesh.elements_on_edge(a, b).len();
        let mid = (mesh.vertices[a as usize].pos + mesh.vertices[b as usize].pos) * 0.5;
        let outer = mid.x == 0.0 || mid.x == 100.0 || mid.z == 0.0 || mid.z == 20.0;
        assert_eq!(n, if outer { 1 } else { 2 }, "edge {a}-{b} at {mid}");
    }
}

#[test]
fn t_junction_is_split() {
    // A square: the lower-left half is one triangle; the upper-right half is two triangles
    // meeting at the midpoint of the diagonal, which is a T-junction on the first.
    let tris = [
        [(0.0, 0.0), (0.0, 2.0), (2.0, 0.0)],
        [(0.0, 2.0), (2.0, 2.0), (1.0, 1.0)],
        [(2.0, 2.0), (2.0, 0.0), (1.0, 1.0)],
    ];
    let mesh = meshed(&flat_scene(&tris), 10.0);
    assert_eq!(mesh.stats.t_junction_splits, 1);
    assert_eq!(mesh.elements.len(), 4);
    assert_eq!(mesh.vertices.len(), 5);
}

#[test]
fn triangles_below_the_weld_distance_are_left_out_not_meshed_forever() {
    // A scene 1e8 across with a triangle 0.5 across: welding (1e-5 of the diagonal) merges
    // its corners; it is counted and left out, and leaves no sample point behind.
    let scene = flat_scene(&[
        [(0.0, 0.0), (0.0, 1e8), (1e8, 0.0)],
        [(1.0, 1.0), (1.0, 1.5), (1.5, 1.0)],
    ]);
    let mesh = meshed(&scene, 5e7);
    assert_eq!(mesh.stats.input.collapsed, 1);
    assert!(mesh.elements.len() < 100, "{}", mesh.elements.len());
    let mut used = vec![false; mesh.vertices.len()];
    mesh.elements
        .iter()
        .flat_map(|e| e.v)
        .for_each(|v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u));
}

#[test]
fn degenerate_input_is_counted() {
    let p = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    let t = [p(0.0, 0.0), p(0.0, 1.0), p(1.0, 0.0)];
    let flipped = [t[0], t[2], t[1]];
    let neighbour_same_way = [p(1.0, 0.0), p(0.0, 1.0), p(1.0, 1.0)]; // runs (0,1)->(1,0)? no
    let sliver = [p(5.0, 0.0), p(6.0, 0.0), p(5.5, 1e-9)];
    let fin = [p(0.0, 0.0), p(1.0, 0.0), Vec3::new(0.5, 1.0, 0.0)];
    let scene = scene_of(&[
        ("a", vec![t, t, flipped, neighbour_same_way]),
        ("b", vec![sliver, fin]),
        (
            "c",
            vec![[p(0.0, 0.0), p(1.0, 0.0), Vec3::new(0.5, -1.0, 0.0)]],
        ),
    ]);
    let mesh = meshed(&scene, 10.0);
    let c = mesh.stats.input;
    assert_eq!(c.duplicates, 1, "{c:?}");
    assert_eq!(c.two_sided, 1, "{c:?}");
    assert_eq!(c.slivers, 1, "{c:?}");
    // The edge (0,0)-(1,0) has t, flipped, the fin and c's triangle around it.
    assert!(c.non_manifold_edges >= 1, "{c:?}");
    let (m, a) = areas(&mesh, &scene);
    // The duplicate is dropped: the mesh has one copy less of t.
    assert!((m - (a - 0.5)).abs() < 1e-5, "{m} {a}");
}

#[test]
fn a_flipped_neighbour_is_counted() {
    let p = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    // Two triangles of a square sharing the diagonal; the second runs it the same way.
    let a = [p(0.0, 0.0), p(0.0, 1.0), p(1.0, 1.0)];
    let b = [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)];
    let scene = scene_of(&[("square", vec![a, b])]);
    assert_eq!(meshed(&scene, 10.0).stats.input.flipped_edges, 1);
    let fixed = scene_of(&[("square", vec![a, [b[0], b[2], b[1]]])]);
    assert_eq!(meshed(&fixed, 10.0).stats.input.flipped_edges, 0);
}

#[test]
fn mesh_is_conforming_every_edge_has_one_or_two_elements() {
    let scene = cornell::load(true).expect("scene");
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: 150.0,
            element_size: 60.0,
        },
    );
    for (a, b) in mesh.edge_list() {
        let n = mesh.elements_on_edge(a, b).len();
        assert!(n == 1 || n == 2, "edge {a}-{b} has {n} elements");
    }
    let (m, s) = areas(&mesh, &scene);
    assert!((m - s).abs() < 1e-4 * s);
}

/// The twelve triangles of the unit cube, facing out.
fn cube() -> Vec<[Vec3; 3]> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    [
        quad(v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)), // bottom, -y
        quad(v(0., 1., 0.), v(0., 1., 1.), v(1., 1., 1.), v(1., 1., 0.)), // top, +y
        quad(v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)), // -z
        quad(v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)), // +z
        quad(v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)), // -x
        quad(v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)), // +x
    ]
    .concat()
}

#[test]
fn a_triangle_wound_against_its_closed_surface_is_turned_over() {
    let centre = Vec3::splat(0.5);
    for t in &cube() {
        let tri = Tri::new(t[0], t[1], t[2]);
        assert!(
            tri.normal().dot(tri.centroid() - centre) > 0.0,
            "cube faces out"
        );
    }
    let mut tris = cube();
    tris[5].swap(1, 2);
    let mesh = meshed(&scene_of(&[("cube", tris)]), 10.0);
    let c = mesh.stats.input;
    assert_eq!((c.flipped_edges, c.reoriented), (3, 1), "{c:?}");
    for e in &mesh.elements {
        let t = mesh.tri(e);
        assert!(
            t.normal().dot(t.centroid() - centre) > 0.0,
            "{t:?} faces in"
        );
    }
}

#[test]
fn vertex_normals_decide_which_way_a_surface_faces() {
    let p = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    // A square wound to face down (-y), but with vertex normals up (+y).
    let down = quad(p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0));
    let mut scene = scene_of(&[("square", down)]);
    assert!(scene.triangles[0].tri.normal().y < 0.0);
    let plain = meshed(&scene, 10.0);
    assert_eq!(plain.stats.input.reoriented, 0);
    scene.normal_hints = vec![Vec3::Y; 2];
    let mesh = meshed(&scene, 10.0);
    assert_eq!(mesh.stats.input.reoriented, 2);
    assert!(mesh.elements.iter().all(|e| mesh.tri(e).normal().y > 0.0));
}

#[test]
fn the_band_takes_the_elements_along_a_box_s_base_and_not_along_its_convex_edges() {
    let scene = box_on_floor();
    let mut mesh = meshed(&scene, 1.0);
    let marked = mesh.at_concave_crease();
    let near_base = |e: &Element| {
        let t = mesh.tri(e);
        let touches = |p: Vec3| {
            let on_side = (p.x - 4.0).abs() < 1e-4
                || (p.x - 6.0).abs() < 1e-4
                || (p.z - 4.0).abs() < 1e-4
                || (p.z - 6.0).abs() < 1e-4;
            let within = (4.0..=6.0).contains(&p.x) && (4.0..=6.0).contains(&p.z);
            p.y == 0.0 && on_side && within
        };
        t.v.iter().any(|&p| touches(p))
    };
    let shown = |e: &Element| e.v.iter().all(|&v| !mesh.vertices[v as usize].hidden());
    let (mut walls, mut floor) = (0, 0);
    for (e, &m) in mesh.elements.iter().zip(&marked) {
        match e.object {
            // the box's top meets its walls at convex edges only
            2 => assert!(!m, "a top element is marked"),
            // a wall is marked along its foot (its top edge is convex)
            1 => {
                assert_eq!(
                    m,
                    near_base(e),
                    "wall element at {}",
                    mesh.tri(e).centroid()
                );
                walls += m as usize;
            }
            // the floor is marked beside the base, never in the footprint
            _ => {
                assert_eq!(
                    m,
                    near_base(e) && shown(e),
                    "floor element at {}",
                    mesh.tri(e).centroid()
                );
                floor += m as usize;
            }
        }
    }
    assert!(walls >= 8 && floor >= 8, "walls {walls}, floor {floor}");
    // Banding halves the long edges that leave the base line from the marked elements.
    let before = mesh.vertices.len();
    let added = mesh.band_concave_creases(0.5);
    assert_eq!(mesh.vertices.len(), before + added);
    assert_eq!(mesh.stats.crease_band_points, added);
    assert!(added > 0);
    // (each new point halves an edge from the line: within an element of it, and off it)
    for v in &mesh.vertices[before..] {
        let p = v.pos;
        let near = p.y <= 1.0 && (3.0..=7.0).contains(&p.x) && (3.0..=7.0).contains(&p.z);
        assert!(near, "a band point far from the base line: {p:?}");
        let on_line = p.y == 0.0
            && ((p.x == 4.0 || p.x == 6.0) && (4.0..=6.0).contains(&p.z)
                || (p.z == 4.0 || p.z == 6.0) && (4.0..=6.0).contains(&p.x));
        assert!(!on_line, "a band point on the base line: {p:?}");
    }
}
