//! Writes a generated scene of furnished rooms (see `occ_radiosity::generate`) as OBJ + MTL:
//!
//!     cargo run --release -p occ-radiosity --example gen_scene -- TRIANGLES OUT.obj [SEED]
//!
//! The MTL is written beside the OBJ with the same stem.

use occ_radiosity::generate::{RoomsConfig, rooms, to_obj};

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: gen_scene TRIANGLES OUT.obj [SEED]";
    let triangles: u64 = args.first().and_then(|a| a.parse().ok()).ok_or(usage)?;
    let out = std::path::PathBuf::from(args.get(1).ok_or(usage)?);
    let seed: u64 = args
        .get(2)
        .map_or(Ok(1), |s| s.parse())
        .map_err(|_| usage)?;
    let scene = rooms(RoomsConfig::about(triangles, seed));
    let mtl_path = out.with_extension("mtl");
    let mtl_name = mtl_path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or("the output needs a file name")?;
    let (obj, mtl) = to_obj(&scene, mtl_name);
    std::fs::write(&out, obj).map_err(|e| format!("{}: {e}", out.display()))?;
    std::fs::write(&mtl_path, mtl).map_err(|e| format!("{}: {e}", mtl_path.display()))?;
    println!("{}: {} triangles", out.display(), scene.triangles.len());
    Ok(())
}
