//! Final gather: the radiosity at a point from the solution's radiosity of every patch, by the
//! solver's own form-factor kernels and shadow rays, `B(x) = E + ρ Σ_p F(x, p) B_p`.
//!
//! A sample point's radiosity carries the noise of the few rays each shot casts to it (eight
//! at the defaults: a point in a penumbra sees a lamp's visible share in ninths), and a point
//! between sample points reads the mesh's interpolation of them. Gathered at the point itself,
//! with rays spread over the patches by what each can give it (tens of thousands in all), the
//! direct light is resolved where the point lies and the indirect light comes from the patches'
//! radiosity, which averages many points. The probes (`probe.csv`) are read this way; the mesh
//! keeps its own values beside them.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::formfactor::{DensitySet, FormFactorConfig, SourceDensity, faces, point_polygon};
use crate::geom::Tri;
use crate::kernels::{SamplePoint, shoot_batch_sets};
use crate::solver::{DENSITY_GRID, Solver};

/// Shadow rays a point casts in all at most, spread over the patches that face it in
/// proportion to the share of its unoccluded irradiance each could give it (each patch's
/// rounded up, and capped at [`MOST_RAYS`]).
pub const GATHER_RAYS: u32 = 1 << 16;

/// The most rays a point casts to one patch (a 32 × 32 grid of its samples).
pub const MOST_RAYS: u32 = 1024;

/// Below this many rays, a patch is taken as uniform over its area (its mean radiosity); from
/// it on, with how its radiosity varies over it (its elements', [`SourceDensity`]).
const DENSITY_RAYS: u32 = 16;

/// The patches as sources of a gather: each one's triangle, mean radiosity and elements.
pub struct Gather<'s> {
    solver: &'s Solver<'s>,
    patches: Vec<Source>,
    /// Each element's radiosity (RGB) and area.
    elements: Vec<(DVec3, f64)>,
}

/// A patch as a source: its triangle, its mean radiosity (area-weighted over its elements) and
/// its elements (indices into the mesh's).
struct Source {
    tri: Tri,
    mean: DVec3,
    elements: Vec<usize>,
}

impl<'s> Gather<'s> {
    /// The sources of `solver`'s solution as it stands.
    pub fn new(solver: &'s Solver<'s>) -> Gather<'s> {
        let mesh = &solver.mesh;
        let elements = solver.element_radiosity();
        let mut patches: Vec<Source> = (mesh.patches.iter())
            .map(|&tri| Source {
                tri,
                mean: DVec3::ZERO,
                elements: Vec::new(),
            })
            .collect();
        for (i, e) in mesh.elements.iter().enumerate() {
            patches[e.patch as usize].elements.push(i);
        }
        for patch in &mut patches {
            let (sum, area) = (patch.elements.iter())
                .map(|&i| elements[i])
                .fold((DVec3::ZERO, 0.0), |(s, a), (b, ea)| (s + b * ea, a + ea));
            patch.mean = if area > 0.0 { sum / area } else { DVec3::ZERO };
        }
        Gather {
            solver,
            patches,
            elements,
        }
    }

    /// The irradiance `H = Σ_p F(x, p) B_p` at the point `eval` with unit normal `normal`
    /// (RGB), `seed` choosing its samples.
    pub fn irradiance(&self, eval: Vec3, normal: Vec3, seed: u64) -> DVec3 {
        // what each patch could give the point unoccluded, a bound to spread the rays by (none
        // from a patch that does not face it, its own among them, which no ray is cast to)
        let bounds: Vec<f64> = (self.patches.par_iter())
            .map(|s| {
                if !faces(eval, normal, &s.tri) {
                    return 0.0;
                }
                f64::from(point_polygon(eval, normal, &s.tri.v)) * s.mean.max_element()
            })
            .collect();
        let total: f64 = bounds.iter().sum();
        if total <= 0.0 {
            return DVec3::ZERO;
        }
        let solver = self.solver;
        let octree = solver.stages.shadow_rays.then_some(&solver.octree);
        let point = [SamplePoint {
            pos: eval.to_array(),
            normal: normal.to_array(),
            eval: eval.to_array(),
        }];
        // (collected, then summed in the patches' order: the same answer on every run)
        let parts: Vec<DVec3> = (self.patches.par_iter().zip(&bounds).enumerate())
            .filter(|(_, (_, b))| **b > 0.0)
            .map(|(i, (source, &bound))| {
                let share = bound / total * f64::from(GATHER_RAYS);
                let rays = (share.ceil() as u32).clamp(1, MOST_RAYS);
                let config = FormFactorConfig {
                    rays,
                    far_rays: 0,
                    ..solver.config().form_factor
                };
                let densities = if rays >= DENSITY_RAYS {
                    self.density(source)
                } else {
                    [None, None, None]
                };
                let set = DensitySet::new(densities.each_ref().map(Option::as_ref));
                let mut out = [[0.0f32; 3]];
                let seed = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ i as u64;
                shoot_batch_sets(octree, &source.tri, &set, &point, &config, seed, &mut out);
                source.mean * Vec3::from(out[0]).as_dvec3()
            })
            .collect();
        parts.into_iter().sum()
    }

    /// How each channel of the patch's radiosity varies over it (`None`: uniform).
    fn density(&self, source: &Source) -> [Option<SourceDensity>; 3] {
        let parts: Vec<(Tri, [f32; 3])> = (source.elements.iter())
            .map(|&i| {
                let tri = self.solver.mesh.tri(&self.solver.mesh.elements[i]);
                (tri, self.elements[i].0.as_vec3().to_array())
            })
            .collect();
        SourceDensity::of_parts_sets(&source.tri, DENSITY_GRID, &parts)
    }
}
