//! Radiosity kernels and the sequential reference solver for CARM: scene loading (OBJ + MTL),
//! meshing with D0 discontinuities and adaptive subdivision, a flattened octree traversed with
//! Samet's neighbour finding, Wallace ray-cast form factors with an analytic near-field extension,
//! progressive refinement with f64 energy accounts, and the outputs (report, convergence plot,
//! image, PLY, probes), and an independent path tracer that is the ground truth (`pathtrace`).
//!
//! # Example
//! ```
//! use occ_radiosity::{mesh::{Mesh, MeshConfig}, scene::cornell, solver::{Solver, SolverConfig, Until}};
//! let scene = cornell::load(true).unwrap();
//! let mesh = Mesh::from_scene(&scene, MeshConfig { patch_size: 300.0, element_size: 150.0 });
//! let config = SolverConfig { until: Until::Shots(3), ..SolverConfig::default() };
//! let mut solver = Solver::new(&scene, mesh, config);
//! solver.run(|_, _| {});
//! assert!(solver.accounts.balance_error() < 1e-9);
//! ```
#![deny(missing_docs)]

pub mod analysis;
pub mod convergence;
pub mod estimate;
pub mod formfactor;
pub mod gather;
pub mod generate;
pub mod geom;
pub mod grid;
pub mod intrinsics;
pub mod kernels;
pub mod mesh;
pub mod octree;
pub mod output;
pub mod overshoot;
pub mod packet;
pub mod pathtrace;
pub mod quadrature;
pub mod refine;
pub mod rng;
pub mod scene;
pub mod solver;
