//! Bad scenes get an error, never a panic: the loader is fed the Cornell box's OBJ and MTL with
//! seeded random damage (lines deleted, duplicated or swapped, characters replaced, numbers
//! made huge, NaN or negative, face indices pushed out of range) and must return `Ok` or an
//! error naming the file, for every input. Meshing and the octree then run on every scene that
//! loads, so a damaged but loadable scene cannot crash what follows either.

use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::octree::{Octree, OctreeConfig};
use occ_radiosity::rng::Pcg32;
use occ_radiosity::scene::load_obj;

const OBJ: &str = include_str!("../../scenes/cornell-box.obj");
const MTL: &str = include_str!("../../scenes/cornell-box.mtl");

/// Replacement words that stress number parsing and indexing.
const NASTY: [&str; 12] = [
    "nan", "inf", "-inf", "1e39", "-1e39", "0", "-0", "99999999", "-7", "1/2/3", "//", "",
];

fn damage(text: &str, rng: &mut Pcg32) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.next_u32() % 4 {
        if lines.is_empty() {
            break;
        }
        let i = rng.next_u32() as usize % lines.len();
        match rng.next_u32() % 5 {
            0 => {
                lines.remove(i);
            }
            1 => {
                let l = lines[i].clone();
                lines.insert(i, l);
            }
            2 => {
                let j = rng.next_u32() as usize % lines.len();
                lines.swap(i, j);
            }
            3 => {
                let mut words: Vec<String> =
                    lines[i].split_whitespace().map(str::to_string).collect();
                if !words.is_empty() {
                    let w = rng.next_u32() as usize % words.len();
                    words[w] = NASTY[rng.next_u32() as usize % NASTY.len()].to_string();
                }
                lines[i] = words.join(" ");
            }
            _ => {
                let mut chars: Vec<char> = lines[i].chars().collect();
                if !chars.is_empty() {
                    let c = rng.next_u32() as usize % chars.len();
                    chars[c] =
                        ['1', '-', '.', 'e', ' ', '/', '#', '\u{e9}'][rng.next_u32() as usize % 8];
                }
                lines[i] = chars.into_iter().collect();
            }
        }
    }
    lines.join("\n")
}

#[test]
fn damaged_scenes_load_or_fail_cleanly() {
    let mut rng = Pcg32::new(2026, 11);
    let (mut loaded, mut failed) = (0, 0);
    for round in 0..3000 {
        let obj = if round % 3 == 2 {
            OBJ.to_string()
        } else {
            damage(OBJ, &mut rng)
        };
        let mtl = if round % 3 == 0 {
            MTL.to_string()
        } else {
            damage(MTL, &mut rng)
        };
        let library = |_: &str| -> Result<String, String> { Ok(mtl.clone()) };
        match load_obj("damaged.obj", &obj, &library) {
            Ok(scene) => {
                loaded += 1;
                // Meshing and the octree run on whatever loads, with the default sizes (relative
                // to the scene) and within the element budget the CLI enforces.
                let diag = scene.diagonal();
                let config = MeshConfig {
                    patch_size: diag / 4.0,
                    element_size: diag / 8.0,
                };
                if round % 10 == 0 && config.estimated_elements(&scene) < 1e6 {
                    let mesh = Mesh::from_scene(&scene, config);
                    let tris: Vec<_> = mesh.elements.iter().map(|e| mesh.tri(e)).collect();
                    let _ = Octree::build(&tris, OctreeConfig::default());
                }
            }
            Err(e) => {
                failed += 1;
                // The message starts with the file at fault: the OBJ, or a library it names.
                let message = e.to_string();
                let mut files = obj
                    .lines()
                    .filter_map(|l| l.trim().strip_prefix("mtllib"))
                    .flat_map(str::split_whitespace)
                    .chain(["damaged.obj"]);
                assert!(files.any(|f| message.starts_with(f)), "{message}");
            }
        }
    }
    // The damage is varied enough to produce both outcomes.
    assert!(
        loaded > 300 && failed > 300,
        "loaded {loaded}, failed {failed}"
    );
}
