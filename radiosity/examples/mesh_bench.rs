//! Meshing time and peak memory against triangle count, on generated rooms:
//!
//!     cargo run --release -p occ-radiosity --example mesh_bench -- TRIANGLES [ELEMENT_SIZE]
//!
//! Meshes one generated scene of about TRIANGLES triangles (patches 2 m, elements 1 m unless
//! given) and prints the triangle and element counts, the meshing time and the process's peak
//! resident memory (VmHWM, which includes the generated scene). Run one size per process so
//! that each peak is its own.

use std::time::Instant;

use occ_radiosity::generate::{RoomsConfig, rooms};
use occ_radiosity::mesh::{Mesh, MeshConfig};

fn peak_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let triangles: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let element: f32 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(1.0);
    let scene = rooms(RoomsConfig::about(triangles, 1));
    let before = peak_kib().unwrap_or(0);
    let start = Instant::now();
    let mesh = Mesh::from_scene(
        &scene,
        MeshConfig {
            patch_size: element * 2.0,
            element_size: element,
        },
    );
    let seconds = start.elapsed().as_secs_f64();
    let peak = peak_kib().unwrap_or(0);
    let n = scene.triangles.len();
    println!(
        "triangles {n} elements {} vertices {} pieces {} hidden {} seconds {seconds:.2} \
         peak_MiB {:.0} scene_MiB {:.0} bytes_per_triangle {:.0}",
        mesh.stats.elements,
        mesh.stats.vertices,
        mesh.stats.pieces,
        mesh.stats.hidden_pieces,
        peak as f64 / 1024.0,
        before as f64 / 1024.0,
        (peak.saturating_sub(before) * 1024) as f64 / n as f64
    );
    let stages: Vec<String> = mesh
        .stage_seconds
        .iter()
        .map(|s| format!("{} {:.2}/{:.2}", s.name, s.wall, s.cpu))
        .collect();
    println!("  stages (wall/cpu s): {}", stages.join(", "));
}
