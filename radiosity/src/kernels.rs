//! The kernels the Rust solver runs, as plain functions over plain data; the occam-callable
//! forms (extern "C" wrappers declared in `stdlib/radiosity.inc`) are in
//! [`crate::intrinsics`]:
//! - [`shoot_batch`]: form factors from a batch of sample points to one source patch;
//! - [`occlusion_batch`]: answers for a batch of shadow rays;
//! - [`Octree::voxel`](crate::octree::Octree::voxel): the geometry a voxel embeds.
//!
//! The structs that cross into occam are `#[repr(C)]` and hold only `f32`s.

use glam::Vec3;

use crate::formfactor::{
    DensitySet, Facing, FormFactorConfig, SourceDensity, form_factor_facing, receiver_samples_sets,
};
use crate::geom::Tri;
use crate::mesh::Vertex;
use crate::octree::{Octree, Traversal};
use crate::rng::Pcg32;

/// A sample point as a kernel receives it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SamplePoint {
    /// Position on the surface.
    pub pos: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Where the form factor is evaluated (see [`Vertex::eval`]).
    pub eval: [f32; 3],
}

impl From<&Vertex> for SamplePoint {
    fn from(v: &Vertex) -> Self {
        SamplePoint {
            pos: v.pos.to_array(),
            normal: v.normal.to_array(),
            eval: v.eval.to_array(),
        }
    }
}

/// A shadow ray: from `origin` towards `origin + dir`, hits counted for `tmin < t < tmax`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: [f32; 3],
    /// Direction (not necessarily unit).
    pub dir: [f32; 3],
    /// Lower parameter bound.
    pub tmin: f32,
    /// Upper parameter bound.
    pub tmax: f32,
}

/// What a batch did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BatchStats {
    /// Form factors computed.
    pub form_factors: u64,
    /// Shadow rays cast.
    pub rays: u64,
    /// Form factors that used the analytic form.
    pub analytic: u64,
}

/// Computes the form factor from each point of `points` to the source triangle `source`, into
/// `out` (same length as `points`; extra entries are left alone). The source samples are drawn
/// from `seed`, so a batch is reproducible.
pub fn shoot_batch(
    octree: &Octree,
    source: &Tri,
    points: &[SamplePoint],
    config: &FormFactorConfig,
    seed: u64,
    out: &mut [f32],
) -> BatchStats {
    shoot_batch_weighted(octree, source, None, points, config, seed, out)
}

/// [`shoot_batch`] for a source whose unshot radiosity varies as `density` says (see
/// [`crate::formfactor::form_factor_weighted`]; `None`: uniform, the same answers as
/// [`shoot_batch`]).
pub fn shoot_batch_weighted(
    octree: &Octree,
    source: &Tri,
    density: Option<&SourceDensity>,
    points: &[SamplePoint],
    config: &FormFactorConfig,
    seed: u64,
    out: &mut [f32],
) -> BatchStats {
    shoot_batch_visibility(Some(octree), source, density, points, config, seed, out)
}

/// [`shoot_batch_weighted`] with shadow rays through `octree`, or none (`None`: every source
/// sample is visible, as in a convex enclosure; no rays are counted).
pub fn shoot_batch_visibility(
    octree: Option<&Octree>,
    source: &Tri,
    density: Option<&SourceDensity>,
    points: &[SamplePoint],
    config: &FormFactorConfig,
    seed: u64,
    out: &mut [f32],
) -> BatchStats {
    // A set of one density: the same samples, weights and answers as one density alone.
    let set = DensitySet::new([density]);
    let (out, _) = out.as_chunks_mut::<1>();
    shoot_batch_sets(octree, source, &set, points, config, seed, out)
}

/// [`shoot_batch_visibility`] for several densities of the source at once (a shot's channels
/// summed and each channel: [`crate::formfactor::channels_differ`]): the same samples and
/// shadow rays, and in `out[i][j]` the form factor of point `i` weighted by density `j`,
/// exactly as [`shoot_batch_visibility`] with that density gives it.
pub fn shoot_batch_sets<const N: usize>(
    octree: Option<&Octree>,
    source: &Tri,
    densities: &DensitySet<N>,
    points: &[SamplePoint],
    config: &FormFactorConfig,
    seed: u64,
    out: &mut [[f32; N]],
) -> BatchStats {
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut samples = Vec::with_capacity(config.rays as usize + 8);
    let mut weights = Vec::with_capacity(config.rays as usize + 8);
    let mut stats = BatchStats::default();
    let facing = Facing::new(source);
    for (p, o) in points.iter().zip(out.iter_mut()) {
        stats.form_factors += 1;
        let (eval, normal) = (Vec3::from(p.eval), Vec3::from(p.normal));
        let rays = receiver_samples_sets(
            (eval, normal),
            &facing,
            config,
            densities,
            &mut rng,
            &mut samples,
            &mut weights,
        );
        if rays == 0 {
            *o = [0.0; N];
            continue;
        }
        // (a receiver given rays faces the source)
        let (f, values) = form_factor_facing(
            eval,
            normal,
            &facing,
            &samples,
            (weights.as_slice(), densities.uniform()),
            config,
            |_, origin, d, tmax| {
                octree.is_some_and(|o| o.occluded(origin, d, 0.0, tmax, Traversal::Ropes))
            },
        );
        *o = values;
        stats.rays += if octree.is_some() { f.rays as u64 } else { 0 };
        stats.analytic += f.analytic as u64;
    }
    stats
}

/// Answers a batch of shadow rays into `out` (true: occluded).
pub fn occlusion_batch(octree: &Octree, rays: &[Ray], mode: Traversal, out: &mut [bool]) {
    for (r, o) in rays.iter().zip(out.iter_mut()) {
        *o = octree.occluded(
            Vec3::from(r.origin),
            Vec3::from(r.dir),
            r.tmin,
            r.tmax,
            mode,
        );
    }
}
