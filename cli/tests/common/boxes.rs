//! A generated scene the carm test files share: a room of boxes, an octree of many voxels.

use std::path::Path;

/// The settings the boxes scene is solved with (after the scene's path): a coarse mesh, few
/// rays and an early stop, so that a debug build spreads it over the nodes in seconds; every
/// triangle in the octree (`--all-stages`: the room's walls can hide nothing and would be left
/// out), for the tests of spread geometry.
pub const BOXES_SETTINGS: [&str; 10] = [
    "--all-stages",
    "--no-adapt",
    "--rays",
    "4",
    "--element-size",
    "1",
    "--until",
    "unshot=0.2",
    "--image-size",
    "16",
];

/// A room with a grid of `k` x `k` boxes on its floor under a lamp panel (metres, y up), for an
/// octree of many voxels; written with the rooms' materials into `dir`, whose path it returns.
pub fn boxes_scene(dir: &Path, k: usize) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).expect("a scratch folder");
    let mtl = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/rooms.mtl");
    std::fs::copy(mtl, dir.join("rooms.mtl")).expect("rooms.mtl copied");
    let mut obj = String::from("mtllib rooms.mtl\n");
    let mut n = 0;
    // A quad wound to face along `facing`.
    let mut quad = |obj: &mut String, mut c: [[f64; 3]; 4], facing: [f64; 3]| {
        let u = [0, 1, 2].map(|i| c[1][i] - c[0][i]);
        let v = [0, 1, 2].map(|i| c[2][i] - c[0][i]);
        let normal = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        if (0..3).map(|i| normal[i] * facing[i]).sum::<f64>() < 0.0 {
            c.reverse();
        }
        for p in c {
            obj.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
        }
        obj.push_str(&format!("f {} {} {} {}\n", n + 1, n + 2, n + 3, n + 4));
        n += 4;
    };
    let (up, down) = ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0]);
    obj.push_str("o light\nusemtl lamp\n");
    let y = 2.4;
    quad(
        &mut obj,
        [[1.7, y, 1.7], [2.3, y, 1.7], [2.3, y, 2.3], [1.7, y, 2.3]],
        down,
    );
    obj.push_str("o floor\nusemtl floor\n");
    quad(
        &mut obj,
        [
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [4.0, 0.0, 4.0],
            [0.0, 0.0, 4.0],
        ],
        up,
    );
    obj.push_str("o ceiling\nusemtl white\n");
    quad(
        &mut obj,
        [
            [0.0, 2.5, 0.0],
            [4.0, 2.5, 0.0],
            [4.0, 2.5, 4.0],
            [0.0, 2.5, 4.0],
        ],
        down,
    );
    obj.push_str("o walls\nusemtl white\n");
    for (x, facing) in [(0.0, 1.0), (4.0, -1.0)] {
        quad(
            &mut obj,
            [[x, 0.0, 0.0], [x, 2.5, 0.0], [x, 2.5, 4.0], [x, 0.0, 4.0]],
            [facing, 0.0, 0.0],
        );
        let z = x;
        quad(
            &mut obj,
            [[0.0, 0.0, z], [4.0, 0.0, z], [4.0, 2.5, z], [0.0, 2.5, z]],
            [0.0, 0.0, facing],
        );
    }
    obj.push_str("o boxes\nusemtl wood\n");
    let (s, h) = (0.12, 0.3);
    for i in 0..k {
        for j in 0..k {
            let at = |i: usize| 0.4 + i as f64 * 3.2 / (k - 1) as f64;
            let (x0, x1, z0, z1) = (at(i) - s, at(i) + s, at(j) - s, at(j) + s);
            quad(
                &mut obj,
                [[x0, h, z0], [x1, h, z0], [x1, h, z1], [x0, h, z1]],
                up,
            );
            for (x, f) in [(x0, -1.0), (x1, 1.0)] {
                quad(
                    &mut obj,
                    [[x, 0.0, z0], [x, h, z0], [x, h, z1], [x, 0.0, z1]],
                    [f, 0.0, 0.0],
                );
            }
            for (z, f) in [(z0, -1.0), (z1, 1.0)] {
                quad(
                    &mut obj,
                    [[x0, 0.0, z], [x1, 0.0, z], [x1, h, z], [x0, h, z]],
                    [0.0, 0.0, f],
                );
            }
        }
    }
    let path = dir.join("boxes.obj");
    std::fs::write(&path, obj).expect("the scene written");
    path
}
