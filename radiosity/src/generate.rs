//! Large test scenes: a grid of furnished rooms, of any size from a thousand triangles to tens
//! of millions, for tests and the meshing benchmark (`examples/gen_scene.rs` writes one as
//! OBJ + MTL).
//!
//! Each room (5 × 3 × 4 m, in metres) has a floor, a ceiling and four walls facing in, a light
//! panel hung 1 cm below the ceiling (a close parallel cover), a table on four legs and four
//! chairs standing on the floor (contact lines and footprints), and a shelf against a wall.
//! Rooms stand 10 cm apart, back to back. Every box face is cut into `subdivision²` quads, two
//! triangles each, which sets the triangle count; placement is jittered from a seed.

use glam::Vec3;

use crate::geom::Tri;
use crate::rng::Pcg32;
use crate::scene::{Object, Scene, SceneTri};

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoomsConfig {
    /// Rooms along x.
    pub rooms_x: u32,
    /// Rooms along z.
    pub rooms_z: u32,
    /// Each box face is cut into `subdivision × subdivision` quads.
    pub subdivision: u32,
    /// Seed of the furniture placement.
    pub seed: u64,
}

impl RoomsConfig {
    /// Triangles one room makes: 32 boxes (the room, the light, a table top on four legs, four
    /// chairs of a seat, four legs and a back, a shelf) of six faces, two triangles per quad.
    pub fn triangles_per_room(subdivision: u32) -> u64 {
        32 * 6 * 2 * u64::from(subdivision).pow(2)
    }

    /// A square grid of rooms with at least `triangles` triangles in all (four quads a side per
    /// face, or fewer for small scenes).
    pub fn about(triangles: u64, seed: u64) -> RoomsConfig {
        let subdivision = if triangles < 20_000 { 1 } else { 4 };
        let rooms = triangles
            .div_ceil(Self::triangles_per_room(subdivision))
            .max(1);
        let side = (rooms as f64).sqrt().ceil() as u32;
        let rooms_z = (rooms as u32).div_ceil(side);
        RoomsConfig {
            rooms_x: side,
            rooms_z,
            subdivision,
            seed,
        }
    }
}

const ROOM: Vec3 = Vec3::new(5.0, 3.0, 4.0);
const GAP: f32 = 0.1;

/// Object indices of the materials.
const WALL: u32 = 0;
const FLOOR: u32 = 1;
const WOOD: u32 = 2;
const LIGHT: u32 = 3;

/// Generates the rooms.
pub fn rooms(config: RoomsConfig) -> Scene {
    let mut scene = Scene {
        objects: vec![
            object("wall", Vec3::new(0.75, 0.74, 0.70), Vec3::ZERO),
            object("floor", Vec3::new(0.45, 0.40, 0.35), Vec3::ZERO),
            object("wood", Vec3::new(0.55, 0.35, 0.20), Vec3::ZERO),
            object("light", Vec3::splat(0.8), Vec3::new(5.0, 4.8, 4.5)),
        ],
        ..Scene::default()
    };
    let mut rng = Pcg32::new(config.seed, 7);
    let s = config.subdivision.max(1);
    for i in 0..config.rooms_x {
        for j in 0..config.rooms_z {
            let origin = Vec3::new(i as f32 * (ROOM.x + GAP), 0.0, j as f32 * (ROOM.z + GAP));
            furnish(&mut scene, origin, s, &mut rng);
        }
    }
    scene
}

fn object(name: &str, reflectance: Vec3, emission: Vec3) -> Object {
    Object {
        name: name.into(),
        reflectance,
        emission,
    }
}

/// One room at `origin` (its low corner).
fn furnish(scene: &mut Scene, origin: Vec3, s: u32, rng: &mut Pcg32) {
    let at = |v: Vec3| origin + v;
    // The room: faces looking in; the floor and walls as separate materials.
    boxed(scene, at(Vec3::ZERO), at(ROOM), s, true, |face| {
        if face == 2 { FLOOR } else { WALL }
    });
    let mut j = || rng.next_f32() - 0.5;
    let light_lo = Vec3::new(2.0 + 0.3 * j(), ROOM.y - 0.06, 1.6 + 0.3 * j());
    boxed(
        scene,
        at(light_lo),
        at(light_lo + Vec3::new(1.0, 0.05, 0.8)),
        s,
        false,
        |_| LIGHT,
    );
    // A table: a top on four legs, somewhere near the middle.
    let table = Vec3::new(1.5 + 0.4 * j(), 0.0, 1.2 + 0.4 * j());
    let (tw, td, th) = (1.6, 1.0, 0.75);
    boxed(
        scene,
        at(table + Vec3::new(0.0, th - 0.04, 0.0)),
        at(table + Vec3::new(tw, th, td)),
        s,
        false,
        |_| WOOD,
    );
    for (x, z) in [
        (0.05, 0.05),
        (tw - 0.1, 0.05),
        (0.05, td - 0.1),
        (tw - 0.1, td - 0.1),
    ] {
        let leg = table + Vec3::new(x, 0.0, z);
        boxed(
            scene,
            at(leg),
            at(leg + Vec3::new(0.05, th - 0.04, 0.05)),
            s,
            false,
            |_| WOOD,
        );
    }
    // Four chairs around it: a seat on four legs and a back.
    for k in 0..4 {
        let side = if k < 2 { -0.55 } else { td + 0.1 };
        let chair = table + Vec3::new(0.2 + 0.7 * (k % 2) as f32 + 0.1 * j(), 0.0, side);
        let (cw, seat) = (0.45, 0.45);
        boxed(
            scene,
            at(chair + Vec3::new(0.0, seat - 0.03, 0.0)),
            at(chair + Vec3::new(cw, seat, cw)),
            s,
            false,
            |_| WOOD,
        );
        for (x, z) in [
            (0.0, 0.0),
            (cw - 0.04, 0.0),
            (0.0, cw - 0.04),
            (cw - 0.04, cw - 0.04),
        ] {
            let leg = chair + Vec3::new(x, 0.0, z);
            boxed(
                scene,
                at(leg),
                at(leg + Vec3::new(0.04, seat - 0.03, 0.04)),
                s,
                false,
                |_| WOOD,
            );
        }
        let back_z = if k < 2 { 0.0 } else { cw - 0.03 };
        boxed(
            scene,
            at(chair + Vec3::new(0.0, seat, back_z)),
            at(chair + Vec3::new(cw, seat + 0.45, back_z + 0.03)),
            s,
            false,
            |_| WOOD,
        );
    }
    // A shelf against the far wall.
    let shelf = Vec3::new(0.5 + 2.0 * (j() + 0.5), 0.0, ROOM.z - 0.4);
    boxed(
        scene,
        at(shelf),
        at(shelf + Vec3::new(1.2, 1.8, 0.4)),
        s,
        false,
        |_| WOOD,
    );
}

/// Adds the box `lo..hi`, each face cut into `s × s` quads, facing in (a room) or out. `object`
/// maps a face (0..6: -x, +x, -y, +y, -z, +z) to its object.
fn boxed(
    scene: &mut Scene,
    lo: Vec3,
    hi: Vec3,
    s: u32,
    inward: bool,
    object: impl Fn(usize) -> u32,
) {
    for face in 0..6 {
        let axis = face / 2;
        let high = face % 2 == 1;
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let point = |a: f32, b: f32| {
            let mut p = lo;
            p[axis] = if high { hi[axis] } else { lo[axis] };
            p[u] = lo[u] + (hi[u] - lo[u]) * a;
            p[v] = lo[v] + (hi[v] - lo[v]) * b;
            p
        };
        // Outward normal of this face is +axis when high; flip for a room.
        let mut out = Vec3::ZERO;
        out[axis] = if high { 1.0 } else { -1.0 };
        let facing = if inward { -out } else { out };
        for a in 0..s {
            for b in 0..s {
                let (a0, a1) = (a as f32 / s as f32, (a + 1) as f32 / s as f32);
                let (b0, b1) = (b as f32 / s as f32, (b + 1) as f32 / s as f32);
                let q = [point(a0, b0), point(a1, b0), point(a1, b1), point(a0, b1)];
                for t in [Tri::new(q[0], q[1], q[2]), Tri::new(q[0], q[2], q[3])] {
                    let t = if t.cross().dot(facing) < 0.0 {
                        Tri::new(t.v[0], t.v[2], t.v[1])
                    } else {
                        t
                    };
                    scene.triangles.push(SceneTri {
                        tri: t,
                        object: object(face),
                    });
                }
            }
        }
    }
}

/// The scene as OBJ and MTL text (`mtl_name` is the library the OBJ names). Vertices are
/// written per triangle, as many exporters do; the loader welds them.
pub fn to_obj(scene: &Scene, mtl_name: &str) -> (String, String) {
    use std::fmt::Write;
    let mut obj = format!(
        "# generated rooms: {} triangles\nmtllib {mtl_name}\n",
        scene.triangles.len()
    );
    let mut mtl = String::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (r, e) = (o.reflectance, o.emission);
        let _ = writeln!(
            mtl,
            "newmtl {}\nKd {} {} {}\nKe {} {} {}",
            o.name, r.x, r.y, r.z, e.x, e.y, e.z
        );
        let _ = writeln!(obj, "o {}\nusemtl {}", o.name, o.name);
        for t in scene.triangles.iter().filter(|t| t.object == i as u32) {
            for v in t.tri.v {
                let _ = writeln!(obj, "v {} {} {}", v.x, v.y, v.z);
            }
            let _ = writeln!(obj, "f -3 -2 -1");
        }
    }
    (obj, mtl)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, MeshConfig};

    #[test]
    fn rooms_have_the_triangles_asked_for_and_mesh_with_their_footprints_hidden() {
        let config = RoomsConfig::about(3_000, 1);
        let scene = rooms(config);
        let per_room = RoomsConfig::triangles_per_room(config.subdivision);
        let rooms = u64::from(config.rooms_x * config.rooms_z);
        assert_eq!(scene.triangles.len() as u64, rooms * per_room);
        assert!(scene.triangles.len() >= 3_000);
        let mesh = Mesh::from_scene(
            &scene,
            MeshConfig {
                patch_size: 2.0,
                element_size: 1.0,
            },
        );
        let s = mesh.stats;
        // Table and chair legs, chairs and shelf stand on the floor: their footprints are
        // hidden, as is the ceiling behind each light.
        assert!(s.hidden_pieces as u64 >= 2 * rooms, "{s:?}");
        assert!(s.d0_cuts > 0 && s.split_points > 0, "{s:?}");
        let meshed: f64 = mesh.object_areas(scene.objects.len()).iter().sum();
        let input: f64 = scene.triangles.iter().map(|t| t.tri.area() as f64).sum();
        assert!((meshed - input).abs() < 1e-4 * input, "{meshed} {input}");
    }

    #[test]
    fn the_obj_text_loads_back() {
        let scene = rooms(RoomsConfig {
            rooms_x: 1,
            rooms_z: 1,
            subdivision: 1,
            seed: 2,
        });
        let (obj, mtl) = to_obj(&scene, "rooms.mtl");
        let back = crate::scene::load_obj("rooms.obj", &obj, &|_| Ok(mtl.clone())).expect("load");
        assert_eq!(back.triangles.len(), scene.triangles.len());
        assert_eq!(back.objects.len(), 4);
    }
}
