use occ_radiosity::formfactor::FormFactorConfig;
use occ_radiosity::mesh::{Mesh, MeshConfig};
use occ_radiosity::overshoot::Acceleration;
use occ_radiosity::scene;
use occ_radiosity::solver::{Solver, SolverConfig, Until};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rho = &args[1];
    let acc: Acceleration = args[2].parse().unwrap();
    let obj = std::fs::read_to_string(format!("scenes/stiff/box-{rho}.obj")).unwrap();
    let mtl = std::fs::read_to_string("scenes/stiff/stiff.mtl").unwrap();
    let scene = scene::load_obj("x", &obj, &|_| Ok(mtl.clone())).unwrap();
    let config = SolverConfig {
        form_factor: FormFactorConfig {
            rays: 4,
            offset: 1e-6,
            ..FormFactorConfig::default()
        },
        acceleration: acc,
        until: Until::Shots(args[3].parse().unwrap()),
        ..SolverConfig::default()
    };
    let mesh = MeshConfig {
        patch_size: 0.5,
        element_size: 0.25,
    };
    let mut s = Solver::new(&scene, Mesh::from_scene(&scene, mesh), config);
    println!("{:?} patches {}", s.analysis, s.mesh.patches.len());
    let every: u64 = args[4].parse().unwrap();
    for i in 0.. {
        if !s.shoot_once() || i > args[3].parse::<u64>().unwrap() {
            break;
        }
        if i % every == 0 {
            let signed: f64 = s.unshot.iter().map(|u| u.x).sum();
            let means = s.object_means();
            let b: Vec<f64> = means.iter().map(|m| m.1.x).collect();
            println!(
                "{i} unshot {:.4e} signed {:.4e} amb {:.4} err {:.4} share {:.4} B {:?}",
                s.unshot_fraction(),
                signed / s.accounts.emitted[0],
                s.ambient().x,
                s.estimated_error(),
                s.reflected_share().x,
                b
            );
        }
    }
}
