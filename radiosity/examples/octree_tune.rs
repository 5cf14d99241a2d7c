//! Prints occlusion throughput of the octree on the 10k-triangle Cornell box for a few build
//! settings (single thread): `cargo run --release --example octree_tune`.
//!
//! Besides wall-clock rays/s it prints rays per CPU-second of this process (from
//! `/proc/self/stat`, 10 ms ticks; Linux only), which stays meaningful when the machine is shared
//! with other jobs and the wall-clock figure mostly measures the load.

use std::time::Instant;

use occ_radiosity::octree::{Octree, OctreeConfig, Traversal};
use occ_radiosity::rng::Pcg32;
use occ_radiosity::scene::cornell;

fn main() {
    let tris = cornell::grid_triangles(18).expect("cornell");
    let mut rng = Pcg32::new(7, 1);
    let total: f32 = tris.iter().map(|t| t.area()).sum();
    let mut cdf = Vec::new();
    let mut acc = 0.0;
    for t in &tris {
        acc += t.area();
        cdf.push(acc);
    }
    let mut pick = || {
        let x = rng.next_f32() * total;
        let i = cdf.partition_point(|&c| c < x).min(tris.len() - 1);
        (
            tris[i].sample(rng.next_f32(), rng.next_f32()),
            tris[i].normal(),
        )
    };
    let rays: Vec<_> = (0..400_000)
        .map(|_| {
            let (a, n) = pick();
            let (b, _) = pick();
            let o = a + n * 1e-3;
            (o, b - o)
        })
        .collect();
    // `octree_tune MAX_LEAF DEPTH` measures one setting; no arguments, a range of them.
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let settings = match args[..] {
        [leaf, depth] => vec![(leaf as usize, depth)],
        _ => vec![
            (6, 12),
            (8, 8),
            (12, 8),
            (16, 7),
            (24, 6),
            (32, 6),
            (48, 5),
            (4, 10),
        ],
    };
    for (max_leaf, max_depth) in settings {
        let tree = Octree::build(
            &tris,
            OctreeConfig {
                max_leaf,
                max_depth,
            },
        );
        let (mut leaves, mut boxes, mut tested) = (0u64, 0u64, 0u64);
        for (o, d) in &rays {
            let (l, b, t) = tree.occlusion_cost(*o, *d, 0.0, 0.999, Traversal::Samet);
            leaves += l as u64;
            boxes += b as u64;
            tested += t as u64;
        }
        let n = rays.len() as f64;
        println!(
            "max_leaf {max_leaf} depth {max_depth} per ray: {:.1} leaves, {:.1} box groups, {:.1} packets tested",
            leaves as f64 / n,
            boxes as f64 / n,
            tested as f64 / n
        );
        for mode in Traversal::ALL {
            let (start, cpu_start) = (Instant::now(), cpu_seconds());
            // Five passes over the rays, so that the 10 ms CPU-time ticks do not dominate.
            let hits = (0..5)
                .map(|_| {
                    rays.iter()
                        .filter(|(o, d)| tree.occluded(*o, *d, 0.0, 0.999, mode))
                        .count()
                })
                .sum::<usize>()
                / 5;
            let s = start.elapsed().as_secs_f64() / 5.0;
            let cpu = cpu_seconds().zip(cpu_start).map(|(b, a)| b - a);
            let per_cpu = cpu.map_or("n/a".to_string(), |c| {
                format!("{:.2}", 5.0 * rays.len() as f64 / c / 1e6)
            });
            println!(
                "max_leaf {max_leaf:>2} depth {max_depth:>2} {mode:?}: {:.2} M rays/s wall, {per_cpu} M rays/CPU-s ({hits} occluded) {:?}",
                rays.len() as f64 / s / 1e6,
                tree.stats()
            );
        }
    }
}

/// Returns user + system CPU seconds of this process, or `None` where `/proc` is unavailable.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
