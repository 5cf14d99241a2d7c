//! A shot's form factors for a batch of receivers in two calls around one walk, the way a node
//! program drives them cheaply: `RAD.RECEIVERS.RAYS` draws every receiver's source samples and
//! writes their shadow rays, the program walks all the rays through the octree at once
//! (`RAD.RAYS.WALK`, fetching what it lacks), and `RAD.RECEIVERS.FORM.FACTORS` turns the answers
//! into one form factor per receiver. Each receiver gets exactly what the per-receiver
//! intrinsics (`RAD.RECEIVER.SAMPLES`, `RAD.SHADOW.RAYS.LIFTED`, `RAD.FORM.FACTOR.WEIGHTED`)
//! and the Rust solver give it; the batch only saves the calls, and checks the shot's arrays
//! (the density grid above all) once instead of once a receiver.

use glam::Vec3;
use occ_runtime::abi::Word;

use super::{
    MAX_SAMPLES, RAY_FLOATS, SAMPLE_STREAM, array, array_mut, facing_receiver_rays, triangle,
};
use crate::formfactor::{
    DensitySet, Facing, FormFactorConfig, SampleWeights, SourceDensity, receiver_samples,
    receiver_samples_sets, sample_grid,
};
use crate::geom::Tri;
use crate::octree::flat::{CURSOR_INTS, START};
use crate::rng::{Pcg32, SetStrides};
use crate::solver::{DENSITY_GRID, receiver_seed};

/// Floats per receiver in the `points` array: position, normal, evaluation point (the layout
/// of a node's sample points in carm.occ).
pub const RECEIVER_FLOATS: usize = 9;

/// A receiver of the batch: its normal and the point its form factors are evaluated at.
fn receiver(floats: &[f32]) -> (Vec3, Vec3) {
    (
        Vec3::from_slice(&floats[6..9]),
        Vec3::from_slice(&floats[3..6]),
    )
}

/// The written arrays of `RAD.RECEIVERS.RAYS`.
struct RaysOut<'a> {
    first: &'a mut [i32],
    samples: &'a mut [f32],
    weights: &'a mut [f32],
    rays: &'a mut [f32],
    blocked: &'a mut [u8],
    cursor: &'a mut [i32],
}

/// The settings of a shot that every receiver of `RAD.RECEIVERS.RAYS` shares.
struct Shot {
    tri: Tri,
    /// The source's normal (`tri.normal()`, once for every receiver).
    normal: Vec3,
    config: FormFactorConfig,
    density: Densities,
    seed: u64,
}

/// How `RAD.RECEIVERS.RAYS` weighs a shot's samples: by one density (none: uniform), or by the
/// four of a shot whose channels shoot apart (the channels summed, then each channel's).
enum Densities {
    One(Option<DensitySet<1>>),
    Sets(DensitySet<4>),
}

/// A density as a grid set gives it, its cell count first (`grid` of `RAD.RECEIVERS.RAYS` when
/// the channels shoot apart: four of them, [`GRID_SET`] floats each).
const GRID_SET: usize = (DENSITY_GRID * DENSITY_GRID) as usize + 1;

impl Densities {
    /// The densities `grid` holds (empty: uniform; a density's cells; four grid sets), or
    /// `None` when it is none of those.
    fn of(grid: &[f32]) -> Option<Densities> {
        if grid.is_empty() {
            return Some(Densities::One(None));
        }
        if grid.len() != 4 * GRID_SET {
            let density = SourceDensity::from_cells(grid)?;
            return Some(Densities::One(Some(DensitySet::new([Some(&density)]))));
        }
        let mut sets = [None, None, None, None];
        for (j, set) in sets.iter_mut().enumerate() {
            let at = j * GRID_SET;
            let cells = grid[at];
            if cells == 0.0 {
                continue;
            }
            let n = (cells >= 1.0 && cells < GRID_SET as f32).then_some(cells as usize)?;
            *set = Some(SourceDensity::from_cells(&grid[at + 1..at + 1 + n])?);
        }
        let grids = sets
            .iter()
            .flatten()
            .map(|d| d.cells().len())
            .collect::<Vec<_>>();
        if grids.windows(2).any(|w| w[0] != w[1]) {
            return None;
        }
        Some(Densities::Sets(DensitySet::new(
            sets.each_ref().map(Option::as_ref),
        )))
    }
}

/// `PROC RAD.RECEIVERS.RAYS (VAL []REAL32 points, VAL []INT global, VAL []REAL32 tri,
/// VAL INT rays, far.rays, VAL INT64 seed, VAL []REAL32 grid, VAL REAL32 offset, []INT first,
/// []REAL32 samples, weights, shadow, []BOOL blocked, []INT cursor, RESULT INT taken, cast)`:
/// the shadow rays of a shot from the source `tri` to r receivers (`points`: 9r floats,
/// position, normal and evaluation point each; `global`: r INTs, each receiver's index among
/// the scene's sample points, which picks its samples as the Rust solver's batches do from the
/// shot's `seed`). Receiver i's samples (3 floats each, drawn as `RAD.RECEIVER.SAMPLES` draws
/// them with `rays`, `far.rays` and the density `grid`) go to `samples`, their weights (one
/// float each, only when `grid` holds a density) to `weights`, their rays (8 floats each, lifted
/// by `offset` as `RAD.SHADOW.RAYS.LIFTED` writes them) to `shadow`, all from sample `first[i]`
/// to `first[i + 1]`; `blocked` is cleared and `cursor` set to start for each ray, ready for
/// `RAD.RAYS.WALK` over `[shadow FROM 0 FOR 8 * first[taken]]`.
///
/// Receivers are taken in order while their samples fit the arrays: `taken` receivers were
/// done (`first` needs `taken + 1` INTs), `cast` is the number of rays they cast. `taken` is
/// -1 (and `cast` 0) when an array's length is wrong (`points` not 9 floats per `global` INT,
/// `tri` not 9, `grid` neither empty nor a density), a setting is out of range (`rays` not in
/// 1..=65536, `far.rays` not in 0..=`rays`, `offset` negative or not finite, a global index
/// negative), or the first receiver does not fit.
///
/// # Safety
/// The arrays are valid for their lengths and `taken`, `cast` for one word each (the occam
/// ABI); the written arrays do not overlap.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn receivers_rays(
    points: *const f32,
    points_len: Word,
    global: *const i32,
    global_len: Word,
    tri: *const f32,
    tri_len: Word,
    rays: Word,
    far: Word,
    seed: Word,
    grid: *const f32,
    grid_len: Word,
    offset: f32,
    first: *mut i32,
    first_len: Word,
    samples: *mut f32,
    samples_len: Word,
    weights: *mut f32,
    weights_len: Word,
    shadow: *mut f32,
    shadow_len: Word,
    blocked: *mut u8,
    blocked_len: Word,
    cursor: *mut i32,
    cursor_len: Word,
    taken: *mut Word,
    cast: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays; occam's usage rules keep the written ones apart.
    let (points, global, tri, grid, mut out) = unsafe {
        (
            array(points, points_len),
            array(global, global_len),
            triangle(array(tri, tri_len)),
            array(grid, grid_len),
            RaysOut {
                first: array_mut(first, first_len),
                samples: array_mut(samples, samples_len),
                weights: array_mut(weights, weights_len),
                rays: array_mut(shadow, shadow_len),
                blocked: array_mut(blocked, blocked_len),
                cursor: array_mut(cursor, cursor_len),
            },
        )
    };
    let density = Densities::of(grid);
    let valid = (1..=MAX_SAMPLES).contains(&rays)
        && (0..=rays).contains(&far)
        && offset.is_finite()
        && offset >= 0.0
        && points.len() == RECEIVER_FLOATS * global.len()
        && global.iter().all(|&g| g >= 0);
    let shot = tri
        .zip(density)
        .filter(|_| valid)
        .map(|(tri, density)| Shot {
            tri,
            normal: tri.normal(),
            config: FormFactorConfig {
                rays: rays as u32,
                far_rays: far as u32,
                offset,
                ..FormFactorConfig::default()
            },
            density,
            seed: seed as u64,
        });
    let (done, rays_cast) = match shot {
        Some(shot) => fill_rays(&shot, points, global, &mut out),
        None => (-1, 0),
    };
    // SAFETY: the ABI passes valid result addresses.
    unsafe {
        *taken = done;
        *cast = rays_cast;
    }
}

/// Draws the receivers' samples and rays into `out` while they fit; answers the receivers
/// taken (-1 when not even the first fits) and the rays cast.
fn fill_rays(shot: &Shot, points: &[f32], global: &[i32], out: &mut RaysOut) -> (Word, Word) {
    let (mut samples, mut weights, mut sets) = (Vec::new(), Vec::new(), Vec::new());
    let mut ones: Vec<[f32; 1]> = Vec::new();
    let weighted = !matches!(shot.density, Densities::One(None));
    // the weights' planes: one, or one a density of a set
    let plane = match shot.density {
        Densities::Sets(_) => out.weights.len() / 4,
        Densities::One(_) => out.weights.len(),
    };
    let skip = 2 * u64::from(sample_grid(shot.config.rays)).pow(2);
    let strides = SetStrides::new(&Pcg32::new(0, SAMPLE_STREAM), skip);
    let (mut at, mut cast, mut taken) = (0usize, 0, 0);
    let room = |at: usize, m: usize, out: &RaysOut| {
        let end = at + m;
        3 * end <= out.samples.len()
            && (!weighted || end <= plane)
            && RAY_FLOATS * end <= out.rays.len()
            && end <= out.blocked.len()
            && CURSOR_INTS * end <= out.cursor.len()
    };
    let (source, config) = (Facing::new(&shot.tri), &shot.config);
    for (floats, &g) in points.chunks_exact(RECEIVER_FLOATS).zip(global) {
        if taken + 2 > out.first.len() {
            break;
        }
        let (p, n) = receiver(floats);
        let (seed, set) = receiver_seed(shot.seed, g as usize);
        let mut rng = Pcg32::new(seed, SAMPLE_STREAM);
        rng.leap(strides.of(set));
        match &shot.density {
            Densities::One(None) => {
                let none = None::<&SourceDensity>;
                receiver_samples(
                    (p, n),
                    &source,
                    config,
                    none,
                    &mut rng,
                    &mut samples,
                    &mut weights,
                );
            }
            Densities::One(Some(set)) => {
                receiver_samples_sets(
                    (p, n),
                    &source,
                    config,
                    set,
                    &mut rng,
                    &mut samples,
                    &mut ones,
                );
            }
            Densities::Sets(set) => {
                receiver_samples_sets(
                    (p, n),
                    &source,
                    config,
                    set,
                    &mut rng,
                    &mut samples,
                    &mut sets,
                );
            }
        }
        let m = samples.len();
        if !room(at, m, out) {
            break;
        }
        out.first[taken] = at as i32;
        for (k, s) in samples.iter().take(m).enumerate() {
            out.samples[3 * (at + k)..3 * (at + k + 1)].copy_from_slice(&s.to_array());
        }
        match shot.density {
            Densities::One(Some(_)) => {
                out.weights[at..at + m].copy_from_slice(&ones.as_flattened()[..m]);
            }
            Densities::Sets(_) => {
                for (k, w) in sets.iter().take(m).enumerate() {
                    for (j, w) in w.iter().enumerate() {
                        out.weights[j * plane + at + k] = *w;
                    }
                }
            }
            Densities::One(None) => {}
        }
        if m > 0 {
            // (samples were drawn, so the receiver faces the source)
            let ray_floats = &mut out.rays[RAY_FLOATS * at..RAY_FLOATS * (at + m)];
            let (ns, config) = (shot.normal, &shot.config);
            cast += facing_receiver_rays(p, n, ns, &samples[..m], config, ray_floats);
        }
        out.blocked[at..at + m].fill(0);
        for c in out.cursor[CURSOR_INTS * at..CURSOR_INTS * (at + m)].chunks_exact_mut(CURSOR_INTS)
        {
            c[0] = START;
        }
        at += m;
        taken += 1;
    }
    if taken == 0 && !global.is_empty() {
        return (-1, 0);
    }
    if let Some(end) = out.first.get_mut(taken) {
        *end = at as i32;
    }
    (taken as Word, cast)
}

/// `PROC RAD.RECEIVERS.FORM.FACTORS (VAL []REAL32 points, VAL []REAL32 tri, VAL []INT first,
/// VAL []REAL32 samples, weights, VAL []BOOL blocked, []REAL32 f, RESULT INT count)`: the form
/// factors from the source `tri` to the r receivers `RAD.RECEIVERS.RAYS` took (`points`: their
/// 9r floats; `first`: its r + 1 INTs), given which of their rays `RAD.RAYS.WALK` found blocked:
/// receiver i's form factor, from its samples `first[i]` to `first[i + 1]` weighted by `weights`
/// (empty for a uniform source), goes to `f[i]` (0 for a receiver with no samples), exactly as
/// `RAD.FORM.FACTOR.WEIGHTED` computes it. `count` is r, or -1 (and `f` untouched) when a
/// length is wrong: `points` not 9r floats, `tri` not 9, `first` not ascending from 0 within
/// `samples` (3 floats each), `weights` neither empty nor as long as the samples, `blocked`
/// shorter than them, or `f` shorter than r.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn receivers_form_factors(
    points: *const f32,
    points_len: Word,
    tri: *const f32,
    tri_len: Word,
    first: *const i32,
    first_len: Word,
    samples: *const f32,
    samples_len: Word,
    weights: *const f32,
    weights_len: Word,
    blocked: *const u8,
    blocked_len: Word,
    f: *mut f32,
    f_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (points, tri, first, samples, weights, blocked, f) = unsafe {
        (
            array(points, points_len),
            triangle(array(tri, tri_len)),
            array(first, first_len),
            array(samples, samples_len),
            array(weights, weights_len),
            array(blocked, blocked_len),
            array_mut(f, f_len),
        )
    };
    let end = first.last().map_or(0, |&e| e.max(0) as usize);
    let valid = (weights.is_empty() || end <= weights.len()) && end <= blocked.len();
    let batch = Taken {
        points,
        first,
        samples,
        valid,
    };
    let written = batch.each(tri, f, 1, |p, n, facing, s, span, o| {
        let w = if weights.is_empty() {
            &[][..]
        } else {
            &weights[span.clone()]
        };
        let seen = &blocked[span];
        let config = FormFactorConfig::default();
        let seen = |k: usize, _, _, _| seen[k] != 0;
        o[0] = facing.form_factor_sets(p, n, s, w, &config, seen).0.value;
    });
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.RECEIVERS.FORM.FACTORS.SETS (VAL []REAL32 points, VAL []REAL32 tri, VAL []INT
/// first, VAL []REAL32 samples, weights, VAL []INT weighted, VAL []BOOL blocked, []REAL32 f,
/// RESULT INT count)`: `RAD.RECEIVERS.FORM.FACTORS` for the four densities of a shot whose
/// channels shoot apart at once (the channels summed, then each channel's), from one pass over
/// the samples and rays: `weights` holds four planes of `SIZE weights / 4` (the planes
/// `RAD.RECEIVERS.RAYS` writes from a grid set), `weighted[j]` is 1 where plane `j` holds
/// density `j`'s weights and 0 where that density is uniform; receiver `i`'s four form factors
/// go to `f[4i .. 4i + 3]`, each exactly what `RAD.RECEIVERS.FORM.FACTORS` gives with that
/// density's weights. `count` is the receivers done, or -1 on a wrong length.
///
/// # Safety
/// As `RAD.RECEIVERS.FORM.FACTORS`.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn receivers_form_factors_sets(
    points: *const f32,
    points_len: Word,
    tri: *const f32,
    tri_len: Word,
    first: *const i32,
    first_len: Word,
    samples: *const f32,
    samples_len: Word,
    weights: *const f32,
    weights_len: Word,
    weighted: *const i32,
    weighted_len: Word,
    blocked: *const u8,
    blocked_len: Word,
    f: *mut f32,
    f_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (points, tri, first, samples, weights, weighted, blocked, f) = unsafe {
        (
            array(points, points_len),
            triangle(array(tri, tri_len)),
            array(first, first_len),
            array(samples, samples_len),
            array(weights, weights_len),
            array(weighted, weighted_len),
            array(blocked, blocked_len),
            array_mut(f, f_len),
        )
    };
    let end = first.last().map_or(0, |&e| e.max(0) as usize);
    let plane = weights.len() / 4;
    let valid = weighted.len() == 4
        && (weighted.iter().all(|&w| w == 0) || end <= plane)
        && end <= blocked.len();
    let uniform = [0, 1, 2, 3].map(|j| weighted.get(j) == Some(&0));
    let batch = Taken {
        points,
        first,
        samples,
        valid,
    };
    let written = batch.each(tri, f, 4, |p, n, facing, s, span, o| {
        let from = span.start;
        let planes = Planes {
            weights,
            plane,
            from,
            uniform,
        };
        let seen = &blocked[span];
        let config = FormFactorConfig::default();
        let (_, values) =
            facing.form_factor_sets(p, n, s, planes, &config, |k, _, _, _| seen[k] != 0);
        o.copy_from_slice(&values);
    });
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// The receivers `RAD.RECEIVERS.RAYS` took, as the form-factor entries are passed them.
struct Taken<'a> {
    points: &'a [f32],
    first: &'a [i32],
    samples: &'a [f32],
    /// The entry's own arguments agree with `first`.
    valid: bool,
}

impl Taken<'_> {
    /// Calls `weigh(p, n, source, samples, span, out)` for each receiver with samples (`span`:
    /// their indices), `out` its `per` values of `f` (zeros for a receiver without samples);
    /// answers the receivers done, or -1 when the arrays do not agree.
    fn each(
        &self,
        tri: Option<Tri>,
        f: &mut [f32],
        per: usize,
        mut weigh: impl FnMut(Vec3, Vec3, &Facing, &[Vec3], std::ops::Range<usize>, &mut [f32]),
    ) -> Word {
        let Taken {
            points,
            first,
            samples,
            valid,
        } = *self;
        let r = first.len().saturating_sub(1);
        let end = first.last().map_or(0, |&e| e.max(0) as usize);
        let valid = valid
            && !first.is_empty()
            && first[0] == 0
            && first.windows(2).all(|w| w[0] <= w[1])
            && points.len() == RECEIVER_FLOATS * r
            && 3 * end <= samples.len()
            && per * r <= f.len();
        let Some(tri) = tri.filter(|_| valid) else {
            return -1;
        };
        let facing = Facing::new(&tri);
        let each = points.chunks_exact(RECEIVER_FLOATS).zip(first.windows(2));
        let mut s = Vec::new();
        for ((floats, span), o) in each.zip(f.chunks_exact_mut(per)) {
            let (a, b) = (span[0] as usize, span[1] as usize);
            if a == b {
                o.fill(0.0);
                continue;
            }
            let (p, n) = receiver(floats);
            s.clear();
            s.extend(samples[3 * a..3 * b].chunks_exact(3).map(Vec3::from_slice));
            weigh(p, n, &facing, &s, a..b, o);
        }
        r as Word
    }
}

/// Four densities' weights of one receiver's samples, in the planes of
/// `RAD.RECEIVERS.FORM.FACTORS.SETS` (sample `k` of the receiver is sample `from + k` of the
/// planes).
struct Planes<'a> {
    weights: &'a [f32],
    plane: usize,
    from: usize,
    uniform: [bool; 4],
}

impl SampleWeights<4> for Planes<'_> {
    fn uniform(&self, j: usize) -> bool {
        self.uniform[j]
    }
    fn at(&self, k: usize) -> [f32; 4] {
        [0, 1, 2, 3].map(|j| {
            if self.uniform[j] {
                1.0
            } else {
                self.weights[j * self.plane + self.from + k]
            }
        })
    }
}

/// `PROC RAD.POINTS.RECEIVE (VAL []REAL32 factor, db, []REAL32 irradiance, RESULT INT count)`:
/// books a shot of `db` (RGB radiosity) at n sample points: point i's irradiance (3 REAL32s)
/// gains `db · factor[i]`, channel by channel, in REAL32 as the Rust solver adds it. `count` is
/// n, or -1 (nothing written) when `db` is not 3 floats or `irradiance` not 3n.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn points_receive(
    factor: *const f32,
    factor_len: Word,
    db: *const f32,
    db_len: Word,
    irradiance: *mut f32,
    irradiance_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (factor, db, irradiance) = unsafe {
        (
            array(factor, factor_len),
            array(db, db_len),
            array_mut(irradiance, irradiance_len),
        )
    };
    let written = if db.len() == 3 && irradiance.len() == 3 * factor.len() {
        for (&f, h) in factor.iter().zip(irradiance.chunks_exact_mut(3)) {
            for j in 0..3 {
                h[j] += db[j] * f;
            }
        }
        factor.len() as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.POINTS.RECEIVE.GATHERED (VAL []REAL32 factor, db, []REAL32 irradiance, []REAL64
/// gathered, RESULT INT count)`: `RAD.POINTS.RECEIVE` that also keeps what each point has
/// gathered in REAL64 (the sum over shots of `db · factor`, from which carm.occ settles its
/// corners' unshot power lazily). `factor` holds one form factor a point (n) or one a channel
/// (3n: point i's channel j at `3i + j`, a shot whose channels shoot apart); with `f` point i's
/// factor for channel j, `irradiance[3i + j]` gains `db[j] · f` in REAL32 and, where `f` is not
/// 0, `gathered[3i + j]` gains `db[j] · f` in REAL64. `count` is n, or -1 (nothing written) when
/// `db` is not 3 floats, or `irradiance` and `gathered` are not both 3n.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI); the
/// written arrays do not overlap.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn points_receive_gathered(
    factor: *const f32,
    factor_len: Word,
    db: *const f32,
    db_len: Word,
    irradiance: *mut f32,
    irradiance_len: Word,
    gathered: *mut f64,
    gathered_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (factor, db, irradiance, gathered) = unsafe {
        (
            array(factor, factor_len),
            array(db, db_len),
            array_mut(irradiance, irradiance_len),
            array_mut(gathered, gathered_len),
        )
    };
    let n = irradiance.len() / 3;
    let per_channel = factor.len() == 3 * n;
    let valid = db.len() == 3
        && irradiance.len() == 3 * n
        && gathered.len() == 3 * n
        && (per_channel || factor.len() == n);
    let written = if valid {
        let at = |i: usize, j: usize| {
            if per_channel {
                factor[3 * i + j]
            } else {
                factor[i]
            }
        };
        let each = irradiance
            .chunks_exact_mut(3)
            .zip(gathered.chunks_exact_mut(3));
        for (i, (h, g)) in each.enumerate() {
            for j in 0..3 {
                let f = at(i, j);
                h[j] += db[j] * f;
                if f != 0.0 {
                    g[j] += f64::from(db[j]) * f64::from(f);
                }
            }
        }
        n as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.CORNERS.RECEIVE (VAL []INT point, patch, VAL []REAL64 weight, VAL []REAL32 factor,
/// VAL []REAL32 db, rho, []REAL64 received, unshot, RESULT INT count)`: books a shot of `db`
/// (RGB radiosity) at the n element corners a node holds. Corner c sits at sample point
/// `point[c]`, whose form factor to the source is `factor[point[c]]`, belongs to patch
/// `patch[c]` and weighs `weight[c]` (a third of its element's area): the power
/// `db · factor · weight` is added to the patch's `received` (3 REAL64s a patch) and, times the
/// patch's reflectance `rho` (3 REAL32s a patch), to the corner's `unshot` (3 REAL64s a corner;
/// or, `unshot` empty, only to `received`: a program that keeps the corners' power by another
/// way, carm.occ's weights per patch and point). Corners whose factor is 0 are skipped. `count`
/// is n, or -1 (nothing written) when the corner arrays differ in length, `unshot` is neither
/// 3n nor empty, `db` not 3, `rho` and `received` not the same multiple of 3, or an index is out
/// of range.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI); the
/// written arrays do not overlap.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn corners_receive(
    point: *const i32,
    point_len: Word,
    patch: *const i32,
    patch_len: Word,
    weight: *const f64,
    weight_len: Word,
    factor: *const f32,
    factor_len: Word,
    db: *const f32,
    db_len: Word,
    rho: *const f32,
    rho_len: Word,
    received: *mut f64,
    received_len: Word,
    unshot: *mut f64,
    unshot_len: Word,
    count: *mut Word,
) {
    // SAFETY: the caller's (the ABI's) arrays.
    unsafe {
        corners_receive_by(
            1,
            (point, point_len, patch, patch_len, weight, weight_len),
            (factor, factor_len, db, db_len, rho, rho_len),
            (received, received_len, unshot, unshot_len, count),
        )
    }
}

/// `PROC RAD.CORNERS.RECEIVE.SETS`, `RAD.CORNERS.RECEIVE`'s arguments: the same booking when a
/// shot's channels shoot apart, `factor` holding each point's three channels' form factors
/// (`factor[3p + j]`); each channel as `RAD.CORNERS.RECEIVE` with that channel's factors and
/// `db` zero in the others books it, to the bit.
///
/// # Safety
/// As `RAD.CORNERS.RECEIVE`.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn corners_receive_sets(
    point: *const i32,
    point_len: Word,
    patch: *const i32,
    patch_len: Word,
    weight: *const f64,
    weight_len: Word,
    factor: *const f32,
    factor_len: Word,
    db: *const f32,
    db_len: Word,
    rho: *const f32,
    rho_len: Word,
    received: *mut f64,
    received_len: Word,
    unshot: *mut f64,
    unshot_len: Word,
    count: *mut Word,
) {
    // SAFETY: the caller's (the ABI's) arrays.
    unsafe {
        corners_receive_by(
            3,
            (point, point_len, patch, patch_len, weight, weight_len),
            (factor, factor_len, db, db_len, rho, rho_len),
            (received, received_len, unshot, unshot_len, count),
        )
    }
}

/// `RAD.CORNERS.RECEIVE` (`channels` 1: a form factor a point) and `.SETS` (3: each channel's):
/// the ABI's arrays unpacked and the corners booked.
///
/// # Safety
/// As `RAD.CORNERS.RECEIVE`.
#[allow(
    clippy::type_complexity,
    reason = "the occam ABI: address and length per array, grouped"
)]
unsafe fn corners_receive_by(
    channels: usize,
    (point, point_len, patch, patch_len, weight, weight_len): (
        *const i32,
        Word,
        *const i32,
        Word,
        *const f64,
        Word,
    ),
    (factor, factor_len, db, db_len, rho, rho_len): (
        *const f32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
    ),
    (received, received_len, unshot, unshot_len, count): (
        *mut f64,
        Word,
        *mut f64,
        Word,
        *mut Word,
    ),
) {
    // SAFETY: the ABI passes valid arrays; occam's usage rules keep the written ones apart.
    let (point, patch, weight, factor, db, rho, received, unshot) = unsafe {
        (
            array(point, point_len),
            array(patch, patch_len),
            array(weight, weight_len),
            array(factor, factor_len),
            array(db, db_len),
            array(rho, rho_len),
            array_mut(received, received_len),
            array_mut(unshot, unshot_len),
        )
    };
    let corners = Corners {
        point,
        patch,
        weight,
        rho,
    };
    let valid = indices_below(point, factor.len() / channels);
    let written = if channels == 1 {
        book_corners(&corners, valid, db, received, unshot, |p, _| factor[p])
    } else {
        book_corners(&corners, valid, db, received, unshot, |p, j| {
            factor[3 * p + j]
        })
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// A node's element corners as `RAD.CORNERS.RECEIVE` is passed them.
struct Corners<'a> {
    point: &'a [i32],
    patch: &'a [i32],
    weight: &'a [f64],
    rho: &'a [f32],
}

/// Books a shot at `corners` (`valid`: the factors cover their points), channel `j` of point
/// `p` receiving `factor(p, j)`; answers the corners booked, or -1 on a wrong length.
fn book_corners(
    corners: &Corners,
    valid: bool,
    db: &[f32],
    received: &mut [f64],
    unshot: &mut [f64],
    factor: impl Fn(usize, usize) -> f32,
) -> Word {
    let Corners {
        point,
        patch,
        weight,
        rho,
    } = *corners;
    let n = point.len();
    let patches = rho.len() / 3;
    let valid = valid
        && patch.len() == n
        && weight.len() == n
        && (unshot.len() == 3 * n || unshot.is_empty())
        && db.len() == 3
        && rho.len() == 3 * patches
        && received.len() == rho.len()
        && indices_below(patch, patches);
    if !valid {
        return -1;
    }
    let db = [db[0], db[1], db[2]].map(f64::from);
    // A node's corners come patch by patch (but for those adaptive subdivision added), so a
    // run of corners of one patch adds to its sums in registers instead of in memory: the same
    // additions in the same order.
    let mut start = 0;
    for run in patch.chunk_by(|a, b| a == b) {
        let at = 3 * run[0] as usize;
        let mut sums = [received[at], received[at + 1], received[at + 2]];
        let rho = [rho[at], rho[at + 1], rho[at + 2]].map(f64::from);
        for c in start..start + run.len() {
            let p = point[c] as usize;
            // (at scale most points receive nothing from a shot: their corners' weights are
            // not read)
            let f = [0, 1, 2].map(|j| factor(p, j));
            // A corner of weight 0 only keeps power for its element (adaptive subdivision).
            if f == [0.0; 3] || weight[c] == 0.0 {
                continue;
            }
            for (j, &f) in f.iter().enumerate() {
                if f == 0.0 {
                    continue;
                }
                let power = db[j] * (f64::from(f) * weight[c]);
                sums[j] += power;
                if let Some(u) = unshot.get_mut(3 * c + j) {
                    *u += power * rho[j];
                }
            }
        }
        received[at..at + 3].copy_from_slice(&sums);
        start += run.len();
    }
    n as Word
}

/// `PROC RAD.PATCHES.TAKE (VAL []INT patches, []REAL64 received, []INT got, []REAL64 packed,
/// RESULT INT count)`: takes what the given patches received (3 REAL64s a patch in `received`,
/// as [`corners_receive`] books it) and leaves 0 in its place: the patches whose power is not
/// zero, in the order given, into `got`, and their power into `packed` (3 each). `count` is how
/// many, or -1 (nothing written) when `received` is not a multiple of 3, a patch is out of its
/// range, or `got` and `packed` lack room for every patch given.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI); the
/// written arrays do not overlap.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn patches_take(
    patches: *const i32,
    patches_len: Word,
    received: *mut f64,
    received_len: Word,
    got: *mut i32,
    got_len: Word,
    packed: *mut f64,
    packed_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays; occam's usage rules keep the written ones apart.
    let (patches, received, got, packed) = unsafe {
        (
            array(patches, patches_len),
            array_mut(received, received_len),
            array_mut(got, got_len),
            array_mut(packed, packed_len),
        )
    };
    let n = received.len() / 3;
    let valid = received.len() % 3 == 0
        && got.len() >= patches.len()
        && packed.len() >= 3 * patches.len()
        && indices_below(patches, n);
    let written = if valid {
        let mut k = 0;
        for &p in patches {
            let at = 3 * p as usize;
            let power = [received[at], received[at + 1], received[at + 2]];
            if power != [0.0; 3] {
                got[k] = p;
                packed[3 * k..3 * k + 3].copy_from_slice(&power);
                k += 1;
            }
            received[at..at + 3].fill(0.0);
        }
        k as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.CORNERS.ROW (VAL []INT point, VAL []REAL64 weight, VAL []REAL32 factor,
/// []REAL64 row, RESULT INT count)`: the share of a shot's form-factor row that the n element
/// corners a node holds received, `Σ weight[c] · factor[point[c]]` (a corner weighs a third of
/// its element's area), into `row[0]`; summed over the nodes it is the row that
/// [`row_scale`](crate::analysis::row_scale) closes. `count` is n, or -1 (`row` untouched) when
/// `weight` is not n long, `row` is empty or a point is out of range.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn corners_row(
    point: *const i32,
    point_len: Word,
    weight: *const f64,
    weight_len: Word,
    factor: *const f32,
    factor_len: Word,
    row: *mut f64,
    row_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (point, weight, factor, row) = unsafe {
        (
            array(point, point_len),
            array(weight, weight_len),
            array(factor, factor_len),
            array_mut(row, row_len),
        )
    };
    let valid =
        weight.len() == point.len() && !row.is_empty() && indices_below(point, factor.len());
    let written = if valid {
        row[0] = point
            .iter()
            .zip(weight)
            .map(|(&p, &w)| w * f64::from(factor[p as usize]))
            .sum();
        point.len() as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// Whether every index is in `0..n`: one pass without early exit, which the compiler turns
/// into vector compares (the booking intrinsics check tens of thousands a shot).
fn indices_below(indices: &[i32], n: usize) -> bool {
    indices
        .iter()
        .fold(true, |ok, &i| ok & ((i64::from(i) as u64) < n as u64))
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::intrinsics::test::address as entry;
    use crate::kernels::{SamplePoint, shoot_batch_visibility};
    use crate::mesh::{Mesh, MeshConfig};
    use crate::octree::flat::FlatView;
    use crate::octree::{Octree, OctreeConfig};
    use crate::scene::cornell;
    use crate::solver::RECEIVER_BATCH;

    type Rays = unsafe extern "C" fn(
        *const f32,
        Word,
        *const i32,
        Word,
        *const f32,
        Word,
        Word,
        Word,
        Word,
        *const f32,
        Word,
        f32,
        *mut i32,
        Word,
        *mut f32,
        Word,
        *mut f32,
        Word,
        *mut f32,
        Word,
        *mut u8,
        Word,
        *mut i32,
        Word,
        *mut Word,
        *mut Word,
    );

    type Factors = unsafe extern "C" fn(
        *const f32,
        Word,
        *const f32,
        Word,
        *const i32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *const u8,
        Word,
        *mut f32,
        Word,
        *mut Word,
    );

    /// The batch's written arrays, sized for `receivers` and `rays` samples in all.
    struct Scratch {
        first: Vec<i32>,
        samples: Vec<f32>,
        weights: Vec<f32>,
        rays: Vec<f32>,
        blocked: Vec<u8>,
        cursor: Vec<i32>,
    }

    impl Scratch {
        fn new(receivers: usize, rays: usize) -> Scratch {
            Scratch {
                first: vec![0; receivers + 1],
                samples: vec![0.0; 3 * rays],
                weights: vec![0.0; rays],
                rays: vec![0.0; RAY_FLOATS * rays],
                blocked: vec![0; rays],
                cursor: vec![0; CURSOR_INTS * rays],
            }
        }
    }

    /// Calls RAD.RECEIVERS.RAYS through the table; answers (taken, cast).
    fn rays_call(
        points: &[f32],
        global: &[i32],
        tri: &[f32],
        (rays, far, seed): (Word, Word, u64),
        grid: &[f32],
        out: &mut Scratch,
    ) -> (Word, Word) {
        // SAFETY: the table says this is the signature.
        let f: Rays = unsafe { std::mem::transmute(entry("RAD.RECEIVERS.RAYS")) };
        let (mut taken, mut cast) = (0, 0);
        // SAFETY: valid slices and results.
        unsafe {
            f(
                points.as_ptr(),
                points.len() as Word,
                global.as_ptr(),
                global.len() as Word,
                tri.as_ptr(),
                tri.len() as Word,
                rays,
                far,
                seed as Word,
                grid.as_ptr(),
                grid.len() as Word,
                1e-3,
                out.first.as_mut_ptr(),
                out.first.len() as Word,
                out.samples.as_mut_ptr(),
                out.samples.len() as Word,
                out.weights.as_mut_ptr(),
                out.weights.len() as Word,
                out.rays.as_mut_ptr(),
                out.rays.len() as Word,
                out.blocked.as_mut_ptr(),
                out.blocked.len() as Word,
                out.cursor.as_mut_ptr(),
                out.cursor.len() as Word,
                &mut taken,
                &mut cast,
            )
        };
        (taken, cast)
    }

    /// Calls RAD.RECEIVERS.FORM.FACTORS through the table (uniform source).
    fn factors_call(
        points: &[f32],
        tri: &[f32],
        first: &[i32],
        samples: &[f32],
        blocked: &[u8],
        f: &mut [f32],
    ) -> Word {
        // SAFETY: the table says this is the signature.
        let call: Factors = unsafe { std::mem::transmute(entry("RAD.RECEIVERS.FORM.FACTORS")) };
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            call(
                points.as_ptr(),
                points.len() as Word,
                tri.as_ptr(),
                tri.len() as Word,
                first.as_ptr(),
                first.len() as Word,
                samples.as_ptr(),
                samples.len() as Word,
                std::ptr::null(),
                0,
                blocked.as_ptr(),
                blocked.len() as Word,
                f.as_mut_ptr(),
                f.len() as Word,
                &mut count,
            )
        };
        count
    }

    #[test]
    fn a_batch_gives_the_solver_s_form_factors_bit_for_bit() {
        let scene = cornell::load(true).expect("cornell");
        let mesh = Mesh::from_scene(
            &scene,
            MeshConfig {
                patch_size: 240.0,
                element_size: 60.0,
            },
        );
        let floats: Vec<f32> = mesh
            .vertices
            .iter()
            .flat_map(|v| {
                [v.pos, v.normal, v.eval]
                    .into_iter()
                    .flat_map(|x| x.to_array())
            })
            .collect();
        let tris: Vec<_> = scene.triangles.iter().map(|t| t.tri).collect();
        let octree = Octree::build(&tris, OctreeConfig::default());
        let flat = octree.flat().expect("flat");
        let view = FlatView::new(&flat.tree, &flat.frame).expect("view");
        let (mut slot, mut pool) = (Vec::new(), Vec::new());
        for v in 0..flat.voxel_count() {
            slot.push(pool.len() as i32);
            pool.extend_from_slice(flat.voxel(v));
        }
        // The light: a patch that every receiver below it faces.
        let src = *mesh
            .patches
            .iter()
            .max_by(|a, b| a.centroid().y.total_cmp(&b.centroid().y))
            .expect("patches");
        let tri: Vec<f32> = src.v.iter().flat_map(|v| v.to_array()).collect();
        let config = FormFactorConfig {
            rays: 16,
            far_rays: 4,
            offset: 1e-3,
            ..FormFactorConfig::default()
        };
        let seed = 0x1234_5678_u64;
        // The solver's answer for the first 300 receivers: two of its batches.
        let n = 300;
        let points: Vec<SamplePoint> = mesh.vertices[..n].iter().map(SamplePoint::from).collect();
        let mut want = Vec::new();
        for (b, chunk) in points.chunks(RECEIVER_BATCH).enumerate() {
            let mut out = vec![0.0; chunk.len()];
            let (s, _) = receiver_seed(seed, RECEIVER_BATCH * b);
            shoot_batch_visibility(Some(&octree), &src, None, chunk, &config, s, &mut out);
            want.extend(out);
        }
        // The node's: receivers in a scrambled order, several calls as the arrays fill.
        let order: Vec<usize> = (0..n).map(|i| (i * 7) % n).collect();
        let mut got = vec![f32::NAN; n];
        let mut s = Scratch::new(n, 600);
        let (mut next, mut calls) = (0, 0);
        while next < n {
            let idx = &order[next..];
            let pts: Vec<f32> = idx
                .iter()
                .flat_map(|&i| floats[9 * i..9 * i + 9].to_vec())
                .collect();
            let global: Vec<i32> = idx.iter().map(|&i| i as i32).collect();
            let (taken, _) = rays_call(&pts, &global, &tri, (16, 4, seed), &[], &mut s);
            assert!(taken > 0, "taken {taken}");
            let taken = taken as usize;
            let end = s.first[taken] as usize;
            let mut missing = [0i32; 1];
            let left = view.walk(
                &slot,
                &pool,
                &s.rays[..RAY_FLOATS * end],
                &mut s.blocked[..end],
                &mut s.cursor[..CURSOR_INTS * end],
                &mut missing,
            );
            assert_eq!(left, Some(0));
            let mut f = vec![0.0; taken];
            let r = factors_call(
                &pts[..9 * taken],
                &tri,
                &s.first[..=taken],
                &s.samples,
                &s.blocked,
                &mut f,
            );
            assert_eq!(r, taken as Word);
            for (k, &i) in idx[..taken].iter().enumerate() {
                got[i] = f[k];
            }
            next += taken;
            calls += 1;
        }
        assert!(calls > 1, "the arrays filled: {calls} calls");
        assert!(want.iter().any(|&f| f > 0.0));
        let bits = |xs: &[f32]| xs.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&want));
    }

    #[test]
    fn wrong_lengths_answer_minus_one_and_write_nothing() {
        // Four floor points under a downward-facing ceiling triangle.
        let pts: Vec<f32> = (0..4)
            .flat_map(|i| {
                let x = 100.0 + 50.0 * i as f32;
                [x, 0.0, 200.0, 0.0, 1.0, 0.0, x, 0.01, 200.0]
            })
            .collect();
        let tri = [0.0, 548.0, 0.0, 556.0, 548.0, 0.0, 0.0, 548.0, 559.0];
        let mut s = Scratch::new(4, 64);
        s.first.fill(-7);
        let all = [0, 1, 2, 3];
        // one INT short of the points
        assert_eq!(
            rays_call(&pts, &all[..3], &tri, (16, 4, 1), &[], &mut s).0,
            -1
        );
        // far rays over rays, a grid that is no density, a negative index
        assert_eq!(rays_call(&pts, &all, &tri, (16, 17, 1), &[], &mut s).0, -1);
        assert_eq!(
            rays_call(&pts, &all, &tri, (16, 4, 1), &[1.0; 5], &mut s).0,
            -1
        );
        assert_eq!(
            rays_call(&pts, &[0, 1, -2, 3], &tri, (16, 4, 1), &[], &mut s).0,
            -1
        );
        assert!(s.first.iter().all(|&x| x == -7));
        // too little room for the first receiver's samples
        let mut tiny = Scratch::new(4, 2);
        assert_eq!(
            rays_call(&pts, &all, &tri, (16, 4, 1), &[], &mut tiny).0,
            -1
        );
        // room for two receivers' samples: two taken, all 32 rays cast
        let mut two = Scratch::new(4, 32);
        assert_eq!(
            rays_call(&pts, &all, &tri, (16, 16, 1), &[], &mut two),
            (2, 32)
        );
        assert_eq!(&two.first[..3], &[0, 16, 32]);
        // the form factors refuse `first` not starting at 0
        let mut f = [5.0f32; 4];
        assert_eq!(
            factors_call(&pts, &tri, &[-7; 5], &s.samples, &s.blocked, &mut f),
            -1
        );
        assert!(f.iter().all(|&x| x == 5.0));
        // and answer the two receivers that were taken
        let r = factors_call(
            &pts[..18],
            &tri,
            &two.first[..3],
            &two.samples,
            &two.blocked,
            &mut f,
        );
        assert_eq!(r, 2);
        assert!(f[0] > 0.0 && f[1] > 0.0 && f[2] == 5.0);
    }

    type Receive = unsafe extern "C" fn(
        *const i32,
        Word,
        *const i32,
        Word,
        *const f64,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *mut f64,
        Word,
        *mut f64,
        Word,
        *mut Word,
    );

    /// Calls RAD.CORNERS.RECEIVE through the table with db = (1, 2, 4).
    fn receive(
        (point, patch, weight): (&[i32], &[i32], &[f64]),
        factor: &[f32],
        rho: &[f32],
        received: &mut [f64],
        unshot: &mut [f64],
    ) -> Word {
        // SAFETY: the table says this is the signature.
        let f: Receive = unsafe { std::mem::transmute(entry("RAD.CORNERS.RECEIVE")) };
        let db = [1.0f32, 2.0, 4.0];
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                point.as_ptr(),
                point.len() as Word,
                patch.as_ptr(),
                patch.len() as Word,
                weight.as_ptr(),
                weight.len() as Word,
                factor.as_ptr(),
                factor.len() as Word,
                db.as_ptr(),
                3,
                rho.as_ptr(),
                rho.len() as Word,
                received.as_mut_ptr(),
                received.len() as Word,
                unshot.as_mut_ptr(),
                unshot.len() as Word,
                &mut count,
            )
        };
        count
    }

    #[test]
    fn corners_book_power_into_their_patches_and_their_unshot() {
        // Three corners: two of patch 1 at points 0 and 2, one of patch 0 at point 1 (F = 0).
        let corners: (&[i32], &[i32], &[f64]) = (&[0, 1, 2], &[1, 0, 1], &[2.0, 3.0, 4.0]);
        let factor = [0.5f32, 0.0, 0.25];
        let rho = [0.1f32, 0.1, 0.1, 0.5, 0.5, 0.5];
        let (mut received, mut unshot) = (vec![0.0; 6], vec![1.0; 9]);
        assert_eq!(
            receive(corners, &factor, &rho, &mut received, &mut unshot),
            3
        );
        // patch 1 gets db * (0.5 * 2 + 0.25 * 4) = 2 db; patch 0 nothing
        assert_eq!(received, [0.0, 0.0, 0.0, 2.0, 4.0, 8.0]);
        assert_eq!(unshot, [1.5, 2.0, 3.0, 1.0, 1.0, 1.0, 1.5, 2.0, 3.0]);
        // a point or patch out of range, or a short unshot: -1, nothing written
        let (mut r, mut u) = (vec![7.0; 6], vec![7.0; 9]);
        let bad_point: (&[i32], &[i32], &[f64]) = (&[0, 3, 2], corners.1, corners.2);
        assert_eq!(receive(bad_point, &factor, &rho, &mut r, &mut u), -1);
        let bad_patch: (&[i32], &[i32], &[f64]) = (corners.0, &[1, 2, 1], corners.2);
        assert_eq!(receive(bad_patch, &factor, &rho, &mut r, &mut u), -1);
        assert_eq!(receive(corners, &factor, &rho, &mut r, &mut u[..8]), -1);
        assert!(r.iter().chain(&u).all(|&x| x == 7.0));
    }

    #[test]
    fn points_receive_gathered_books_as_the_points_and_gathers_in_real64() {
        type Receive = unsafe extern "C" fn(
            *const f32,
            Word,
            *const f32,
            Word,
            *mut f32,
            Word,
            *mut f64,
            Word,
            *mut Word,
        );
        // SAFETY: the table says this is the signature.
        let f: Receive = unsafe { std::mem::transmute(entry("RAD.POINTS.RECEIVE.GATHERED")) };
        let call = |factor: &[f32], db: &[f32], h: &mut [f32], g: &mut [f64]| {
            let mut count = 0;
            // SAFETY: valid slices and result.
            unsafe {
                f(
                    factor.as_ptr(),
                    factor.len() as Word,
                    db.as_ptr(),
                    db.len() as Word,
                    h.as_mut_ptr(),
                    h.len() as Word,
                    g.as_mut_ptr(),
                    g.len() as Word,
                    &mut count,
                )
            };
            count
        };
        let db = [2.0, 4.0, 0.1];
        // one factor a point: the same irradiance as RAD.POINTS.RECEIVE, gathered in REAL64
        let (mut h, mut g) = ([1.0, 2.0, 3.0, 0.0, 0.0, 0.0], [0.5; 6]);
        assert_eq!(call(&[0.3, 0.0], &db, &mut h, &mut g), 2);
        assert_eq!(
            h,
            [
                1.0 + 2.0 * 0.3,
                2.0 + 4.0 * 0.3,
                3.0 + 0.1 * 0.3,
                0.0,
                0.0,
                0.0
            ]
        );
        let want = |d: f32, f: f32| 0.5 + f64::from(d) * f64::from(f);
        assert_eq!(
            g,
            [
                want(2.0, 0.3),
                want(4.0, 0.3),
                want(0.1, 0.3),
                0.5,
                0.5,
                0.5
            ]
        );
        // one a channel
        let (mut h, mut g) = ([0.0; 6], [0.0; 6]);
        let factor = [0.25, 0.0, 0.5, 1.0, 2.0, 0.0];
        assert_eq!(call(&factor, &db, &mut h, &mut g), 2);
        assert_eq!(h, [0.5, 0.0, 0.05, 2.0, 8.0, 0.0]);
        assert_eq!(g, [0.5, 0.0, f64::from(0.1f32) * 0.5, 2.0, 8.0, 0.0]);
        // refused: db short, irradiance and gathered apart, a factor count neither n nor 3n
        let (mut h, mut g) = ([7.0; 6], [7.0; 6]);
        assert_eq!(call(&[0.5, 0.5], &db[..2], &mut h, &mut g), -1);
        assert_eq!(call(&[0.5, 0.5], &db, &mut h, &mut g[..3]), -1);
        assert_eq!(call(&[0.5; 4], &db, &mut h, &mut g), -1);
        assert!(h.iter().all(|&x| x == 7.0) && g.iter().all(|&x| x == 7.0));
    }

    #[test]
    fn points_receive_adds_the_shot_to_each_point_and_refuses_bad_lengths() {
        type Receive =
            unsafe extern "C" fn(*const f32, Word, *const f32, Word, *mut f32, Word, *mut Word);
        // SAFETY: the table says this is the signature.
        let f: Receive = unsafe { std::mem::transmute(entry("RAD.POINTS.RECEIVE")) };
        let call = |factor: &[f32], db: &[f32], irradiance: &mut [f32]| {
            let mut count = 0;
            // SAFETY: valid slices and result.
            unsafe {
                f(
                    factor.as_ptr(),
                    factor.len() as Word,
                    db.as_ptr(),
                    db.len() as Word,
                    irradiance.as_mut_ptr(),
                    irradiance.len() as Word,
                    &mut count,
                )
            };
            count
        };
        let mut h = [1.0, 2.0, 3.0, 0.0, 0.0, 0.0];
        assert_eq!(call(&[0.5, 0.25], &[2.0, 4.0, 8.0], &mut h), 2);
        assert_eq!(h, [2.0, 4.0, 7.0, 0.5, 1.0, 2.0]);
        assert_eq!(call(&[0.5, 0.25], &[2.0, 4.0], &mut h), -1);
        assert_eq!(call(&[0.5], &[2.0, 4.0, 8.0], &mut h), -1);
        assert_eq!(
            h,
            [2.0, 4.0, 7.0, 0.5, 1.0, 2.0],
            "nothing written when refused"
        );
    }

    #[test]
    fn corners_sum_the_row_they_received() {
        type Row = unsafe extern "C" fn(
            *const i32,
            Word,
            *const f64,
            Word,
            *const f32,
            Word,
            *mut f64,
            Word,
            *mut Word,
        );
        // SAFETY: the table says this is the signature.
        let f: Row = unsafe { std::mem::transmute(entry("RAD.CORNERS.ROW")) };
        let call = |point: &[i32], weight: &[f64], factor: &[f32], row: &mut [f64]| {
            let mut count = 0;
            // SAFETY: valid slices and result.
            unsafe {
                f(
                    point.as_ptr(),
                    point.len() as Word,
                    weight.as_ptr(),
                    weight.len() as Word,
                    factor.as_ptr(),
                    factor.len() as Word,
                    row.as_mut_ptr(),
                    row.len() as Word,
                    &mut count,
                )
            };
            count
        };
        let mut row = [7.0];
        // 2 * 0.5 + 3 * 0 + 4 * 0.25
        assert_eq!(
            call(&[0, 1, 2], &[2.0, 3.0, 4.0], &[0.5, 0.0, 0.25], &mut row),
            3
        );
        assert_eq!(row, [2.0]);
        let mut row = [7.0];
        assert_eq!(call(&[0, 3], &[1.0, 1.0], &[0.5, 0.0, 0.25], &mut row), -1);
        assert_eq!(call(&[0], &[1.0, 1.0], &[0.5], &mut row), -1);
        assert_eq!(row, [7.0]);
    }

    #[test]
    fn patches_take_packs_what_they_received_and_leaves_zero() {
        type Take = unsafe extern "C" fn(
            *const i32,
            Word,
            *mut f64,
            Word,
            *mut i32,
            Word,
            *mut f64,
            Word,
            *mut Word,
        );
        // SAFETY: the table says this is the signature.
        let f: Take = unsafe { std::mem::transmute(entry("RAD.PATCHES.TAKE")) };
        let call = |patches: &[i32], received: &mut [f64], got: &mut [i32], packed: &mut [f64]| {
            let mut count = 0;
            // SAFETY: valid slices and result.
            unsafe {
                f(
                    patches.as_ptr(),
                    patches.len() as Word,
                    received.as_mut_ptr(),
                    received.len() as Word,
                    got.as_mut_ptr(),
                    got.len() as Word,
                    packed.as_mut_ptr(),
                    packed.len() as Word,
                    &mut count,
                )
            };
            count
        };
        // Five patches; patch 3 received nothing, patch 4 only blue.
        let mut received: Vec<f64> = (0..15).map(f64::from).collect();
        received[9..12].fill(0.0);
        received[12..14].fill(0.0);
        let (mut got, mut packed) = ([-1; 3], [-1.0; 9]);
        assert_eq!(call(&[1, 3, 4], &mut received, &mut got, &mut packed), 2);
        assert_eq!(got[..2], [1, 4]);
        assert_eq!(packed[..6], [3.0, 4.0, 5.0, 0.0, 0.0, 14.0]);
        // The patches taken are left at 0, the others untouched.
        let mut left: Vec<f64> = (0..15).map(f64::from).collect();
        left[3..6].fill(0.0);
        left[9..15].fill(0.0);
        assert_eq!(received, left);
        // A patch out of range, or too little room: nothing written.
        let before = received.clone();
        assert_eq!(call(&[0, 5], &mut received, &mut got, &mut packed), -1);
        assert_eq!(
            call(&[0, 1, 2, 3], &mut received, &mut got, &mut packed),
            -1
        );
        assert_eq!(received, before);
    }

    /// A grid of 576 cells: a density varying with `phase` (mean about 1).
    fn varying(phase: f32) -> Vec<f32> {
        (0..576)
            .map(|i| 1.0 + 0.5 * (i as f32 * 0.1 + phase).sin())
            .collect()
    }

    #[test]
    fn channel_sets_weigh_and_book_as_the_one_density_calls_do() {
        let tri = [0.0f32, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0];
        let points: Vec<f32> = (0..3)
            .flat_map(|i| {
                let x = 0.2 + 0.3 * i as f32;
                [x, 0.0, 0.3, 0.0, 1.0, 0.0, x, 0.0, 0.3]
            })
            .collect();
        let global = [5i32, 17, 300];
        // the summed density and channels 0 and 2 vary, channel 1 is uniform
        let grids = [
            Some(varying(0.0)),
            Some(varying(1.0)),
            None,
            Some(varying(2.0)),
        ];
        let mut set = Vec::new();
        for g in &grids {
            set.push(if g.is_some() { 576.0 } else { 0.0 });
            set.extend(g.clone().unwrap_or_else(|| vec![0.0; 576]));
        }
        let n = 3 * 64;
        let call = |grid: &[f32], planes: usize| {
            let mut out = Scratch::new(3, n);
            out.weights = vec![0.0; planes * n];
            let got = rays_call(&points, &global, &tri, (16, 16, 77), grid, &mut out);
            assert_eq!(got.0, 3);
            out
        };
        let sets = call(&set, 4);
        let end = sets.first[3] as usize;
        // the same samples and rays; each plane the weights its density alone gives
        for (j, g) in grids.iter().enumerate() {
            let one = call(g.as_deref().unwrap_or(&[]), 1);
            assert_eq!(one.first, sets.first);
            assert_eq!(one.samples, sets.samples);
            assert_eq!(one.rays, sets.rays);
            if g.is_some() {
                assert_eq!(one.weights[..end], sets.weights[j * n..j * n + end]);
            }
        }
        // four form factors a receiver in one pass, each the one-density call's to the bit
        let blocked: Vec<u8> = (0..n).map(|k| u8::from(k % 5 == 0)).collect();
        let weighted = grids.each_ref().map(|g| i32::from(g.is_some()));
        let mut f4 = vec![0.0f32; 12];
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            receivers_form_factors_sets(
                points.as_ptr(),
                points.len() as Word,
                tri.as_ptr(),
                9,
                sets.first.as_ptr(),
                4,
                sets.samples.as_ptr(),
                sets.samples.len() as Word,
                sets.weights.as_ptr(),
                sets.weights.len() as Word,
                weighted.as_ptr(),
                4,
                blocked.as_ptr(),
                blocked.len() as Word,
                f4.as_mut_ptr(),
                12,
                &mut count,
            )
        };
        assert_eq!(count, 3);
        for (j, g) in grids.iter().enumerate() {
            let w: &[f32] = if g.is_some() {
                &sets.weights[j * n..j * n + end]
            } else {
                &[]
            };
            let mut f = [0.0f32; 3];
            // SAFETY: valid slices and result.
            unsafe {
                receivers_form_factors(
                    points.as_ptr(),
                    points.len() as Word,
                    tri.as_ptr(),
                    9,
                    sets.first.as_ptr(),
                    4,
                    sets.samples.as_ptr(),
                    sets.samples.len() as Word,
                    w.as_ptr(),
                    w.len() as Word,
                    blocked.as_ptr(),
                    blocked.len() as Word,
                    f.as_mut_ptr(),
                    3,
                    &mut count,
                )
            };
            assert_eq!(count, 3);
            for i in 0..3 {
                assert_eq!(
                    f4[4 * i + j].to_bits(),
                    f[i].to_bits(),
                    "density {j} receiver {i}"
                );
            }
            assert!(f.iter().any(|&x| x > 0.0));
        }
        // booking each channel's factors at once is booking them one channel at a time
        let (point, patch, weight) = ([0i32, 1, 2, 1], [0i32, 0, 1, 1], [0.5f64, 1.5, 2.0, 0.0]);
        let factor: Vec<f32> = (0..3)
            .flat_map(|i| [f4[4 * i + 1], f4[4 * i + 2], f4[4 * i + 3]])
            .collect();
        let (db, rho) = ([2.0f32, 3.0, 5.0], [0.3f32, 0.5, 0.7, 0.2, 0.4, 0.6]);
        let book =
            |sets: bool, factor: &[f32], db: &[f32], received: &mut [f64], unshot: &mut [f64]| {
                let entry = if sets {
                    corners_receive_sets
                } else {
                    corners_receive
                };
                let mut count = 0;
                // SAFETY: valid slices and result.
                unsafe {
                    entry(
                        point.as_ptr(),
                        4,
                        patch.as_ptr(),
                        4,
                        weight.as_ptr(),
                        4,
                        factor.as_ptr(),
                        factor.len() as Word,
                        db.as_ptr(),
                        3,
                        rho.as_ptr(),
                        6,
                        received.as_mut_ptr(),
                        6,
                        unshot.as_mut_ptr(),
                        12,
                        &mut count,
                    )
                };
                assert_eq!(count, 4);
            };
        let (mut received, mut unshot) = (vec![0.25f64; 6], vec![0.5f64; 12]);
        book(true, &factor, &db, &mut received, &mut unshot);
        let (mut r1, mut u1) = (vec![0.25f64; 6], vec![0.5f64; 12]);
        for c in 0..3 {
            let mut masked = [0.0f32; 3];
            masked[c] = db[c];
            let one: Vec<f32> = (0..3).map(|i| factor[3 * i + c]).collect();
            book(false, &one, &masked, &mut r1, &mut u1);
        }
        assert_eq!(received, r1);
        assert_eq!(unshot, u1);
        assert!(received.iter().any(|&x| x != 0.25));
    }
}
