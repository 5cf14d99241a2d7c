//! Intrinsics for a source that shoots unevenly (issue 10, cause 4): a patch shoots what each of
//! its elements holds, not its average, so its samples carry weights. `RAD.SOURCE.DENSITY`
//! tabulates a patch from its elements' unshot radiosity (`RAD.SOURCE.DENSITIES` several
//! densities at once), `RAD.SOURCE.SAMPLES.WEIGHTED.AT` draws the samples with their weights,
//! and `RAD.FORM.FACTOR.WEIGHTED` weighs the visible ones, each exactly as the Rust solver does
//! it ([`SourceDensity::of_parts_sets`], [`source_samples_weighted`], [`form_factor_weighted`]).
//! An empty density stands for a uniform source (no weights).

use glam::Vec3;
use occ_runtime::abi::Word;

use super::{
    MAX_SAMPLES, MAX_SKIPPED_SETS, SAMPLE_STREAM, array, array_mut, point, points, triangle,
};
use crate::formfactor::{
    Facing, FormFactorConfig, SourceDensity, form_factor_weighted, receiver_samples, sample_grid,
    source_samples_weighted,
};
use crate::geom::Tri;
use crate::rng::Pcg32;
use crate::solver::{DENSITY_GRID, far_rays};

/// Cells `RAD.SOURCE.DENSITY` writes for a non-uniform source.
pub const DENSITY_CELLS: Word = (DENSITY_GRID * DENSITY_GRID) as Word;

/// `PROC RAD.SOURCE.DENSITY (VAL []REAL32 patch, VAL []REAL32 elements, VAL []REAL32 density,
/// []REAL32 grid, RESULT INT cells)`: how the unshot radiosity of the source `patch` (9 floats)
/// varies over it, from its k elements (`elements`: 9k floats, three corners each, in the
/// solver's element order) and each element's unshot power over its area, channels summed
/// (`density`: k floats). Writes the [`DENSITY_CELLS`] cells of the grid to the start of `grid`
/// and answers their number, or 0 (grid untouched) when the source is uniform or has fewer than
/// two elements, or -1 when a length is wrong (`grid` shorter than [`DENSITY_CELLS`] included).
///
/// # Safety
/// The arrays are valid for their lengths and `cells` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn source_density(
    patch: *const f32,
    patch_len: Word,
    elements: *const f32,
    elements_len: Word,
    density: *const f32,
    density_len: Word,
    grid: *mut f32,
    grid_len: Word,
    cells: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays, and a valid result address.
    unsafe {
        let (patch, elements, density) = (
            array(patch, patch_len),
            array(elements, elements_len),
            array(density, density_len),
        );
        let grid = array_mut(grid, grid_len);
        *cells = match densities(patch, elements, density, grid) {
            Some([n]) => Word::from(n),
            None => -1,
        };
    }
}

/// `PROC RAD.SOURCE.DENSITIES (VAL []REAL32 patch, VAL []REAL32 elements, VAL []REAL32
/// densities, []REAL32 grids, []INT cells)`: `RAD.SOURCE.DENSITY` of n densities over the same
/// k elements at once (n = `SIZE cells`, 1 to 4; the controller tabulates a shot's channels
/// summed and each channel, as the reference solver does), sharing the search of which element
/// holds each cell. `densities` holds n·k floats, density j's k at `[j·k]`; density j's grid goes
/// to `grids` at `[j·DENSITY_CELLS]` and its cell count (or 0 for a uniform source) to `cells[j]`,
/// each exactly what `RAD.SOURCE.DENSITY` makes of it. Every `cells[j]` is -1 (nothing else
/// written) when a length is wrong (`grids` shorter than n·[`DENSITY_CELLS`] included).
///
/// # Safety
/// The arrays are valid for their lengths (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn source_densities(
    patch: *const f32,
    patch_len: Word,
    elements: *const f32,
    elements_len: Word,
    densities_in: *const f32,
    densities_len: Word,
    grids: *mut f32,
    grids_len: Word,
    cells: *mut i32,
    cells_len: Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (patch, elements, values, grids, cells) = unsafe {
        (
            array(patch, patch_len),
            array(elements, elements_len),
            array(densities_in, densities_len),
            array_mut(grids, grids_len),
            array_mut(cells, cells_len),
        )
    };
    let written: Option<Vec<i32>> = match cells.len() {
        1 => densities::<1>(patch, elements, values, grids).map(Vec::from),
        2 => densities::<2>(patch, elements, values, grids).map(Vec::from),
        3 => densities::<3>(patch, elements, values, grids).map(Vec::from),
        4 => densities::<4>(patch, elements, values, grids).map(Vec::from),
        _ => None,
    };
    match written {
        Some(n) => cells.copy_from_slice(&n),
        None => cells.fill(-1),
    }
}

/// Tabulates `N` densities of the k elements (`elements`: 9k floats; `values`: N·k, density j's
/// at `[j·k]`) over `patch` (9 floats) into `grids` (density j's at `[j·DENSITY_CELLS]`), as
/// [`SourceDensity::of_parts_sets`]; answers each density's cell count (0: uniform, its grid
/// untouched), or `None`, writing nothing, when a length is wrong.
fn densities<const N: usize>(
    patch: &[f32],
    elements: &[f32],
    values: &[f32],
    grids: &mut [f32],
) -> Option<[i32; N]> {
    let patch = triangle(patch)?;
    let k = elements.len() / 9;
    let cells = DENSITY_CELLS as usize;
    if elements.len() != 9 * k || values.len() != N * k || grids.len() < N * cells {
        return None;
    }
    let parts = (elements.chunks_exact(9).enumerate())
        .map(|(i, t)| Some((triangle(t)?, std::array::from_fn(|j| values[j * k + i]))))
        .collect::<Option<Vec<(Tri, [f32; N])>>>()?;
    let tabled = SourceDensity::of_parts_sets(&patch, DENSITY_GRID, &parts);
    let mut written = [0; N];
    for ((d, grid), n) in tabled
        .iter()
        .zip(grids.chunks_exact_mut(cells))
        .zip(&mut written)
    {
        if let Some(d) = d {
            grid[..d.cells().len()].copy_from_slice(d.cells());
            *n = DENSITY_CELLS as i32;
        }
    }
    Some(written)
}

/// `PROC RAD.SOURCE.SAMPLES.WEIGHTED.AT (VAL []REAL32 tri, VAL INT m, VAL INT64 seed,
/// VAL INT set, VAL []REAL32 grid, []REAL32 out, []REAL32 weights, RESULT INT count)`:
/// `RAD.SOURCE.SAMPLES.AT` (the same points) and, when `grid` holds a density from
/// `RAD.SOURCE.DENSITY`, the relative unshot radiosity at each sample in `weights` (one float per
/// sample; `weights` untouched when `grid` is empty). `count` is -1 (and nothing written) as for
/// `RAD.SOURCE.SAMPLES.AT`, and when `grid` is neither empty nor a density, or `weights` is
/// shorter than the samples.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn source_samples_weighted_at(
    tri: *const f32,
    tri_len: Word,
    m: Word,
    seed: Word,
    set: Word,
    grid: *const f32,
    grid_len: Word,
    out: *mut f32,
    out_len: Word,
    weights: *mut f32,
    weights_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (tri, grid) = unsafe { (triangle(array(tri, tri_len)), array(grid, grid_len)) };
    let density = SourceDensity::from_cells(grid);
    let valid = (1..=MAX_SAMPLES).contains(&m)
        && (0..=MAX_SKIPPED_SETS).contains(&set)
        && (grid.is_empty() || density.is_some());
    let (mut samples, mut w) = (Vec::new(), Vec::new());
    if let Some(tri) = tri.filter(|_| valid) {
        let mut rng = Pcg32::new(seed as u64, SAMPLE_STREAM);
        // Each set draws two numbers per sample of a k x k grid, weighted or not.
        let k = u64::from(sample_grid(m as u32));
        rng.advance(set as u64 * 2 * k * k);
        source_samples_weighted(
            &tri,
            m as u32,
            density.as_ref(),
            &mut rng,
            &mut samples,
            &mut w,
        );
    }
    let written = if samples.is_empty() {
        -1
    } else {
        // SAFETY: the ABI passes `out` and `weights` valid for their lengths.
        unsafe { write_samples(&samples, &w, out, out_len, weights, weights_len) }
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.FORM.FACTOR.WEIGHTED (VAL []REAL32 point, normal, VAL []REAL32 tri,
/// VAL []REAL32 samples, weights, VAL []BOOL visible, RESULT REAL32 f)`: `RAD.FORM.FACTOR` for
/// a source whose samples carry the weights `RAD.SOURCE.SAMPLES.WEIGHTED.AT` gave them (m
/// floats, or none for a uniform source): the form factor times the mean relative radiosity the
/// receiver sees, as the Rust solver computes it. `f` is -1.0 when a length is wrong.
///
/// # Safety
/// The arrays are valid for their lengths and `f` for one REAL32 (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn form_factor_weighted_visible(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    weights: *const f32,
    weights_len: Word,
    visible: *const u8,
    visible_len: Word,
    f: *mut f32,
) {
    // SAFETY: the ABI passes valid arrays.
    let (p, n, tri, samples, weights, visible) = unsafe {
        (
            point(array(p, p_len)),
            point(array(n, n_len)),
            triangle(array(tri, tri_len)),
            points(array(samples, samples_len)),
            array(weights, weights_len),
            array(visible, visible_len),
        )
    };
    let value = match (p, n, tri, samples) {
        (Some(p), Some(n), Some(tri), Some(s))
            if !s.is_empty()
                && s.len() == visible.len()
                && (weights.is_empty() || weights.len() == s.len()) =>
        {
            weighted_form_factor(p, n, &tri, &s, weights, visible)
        }
        _ => -1.0,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *f = value };
}

/// One receiver's weighted form factor given the visibility flag of each sample's ray.
fn weighted_form_factor(
    p: Vec3,
    n: Vec3,
    tri: &Tri,
    samples: &[Vec3],
    weights: &[f32],
    visible: &[u8],
) -> f32 {
    let config = FormFactorConfig::default();
    form_factor_weighted(p, n, tri, samples, weights, &config, |k, _, _, _| {
        visible[k] == 0
    })
    .value
}

/// `PROC RAD.SHOT.RAYS (VAL INT rays, VAL REAL64 share, full.power, RESULT INT far)`: the
/// rays per far form factor of a shot carrying `share` of the emitted power (in the channel
/// where it is largest, [`shot_share`](crate::solver::shot_share)) when shots of at least
/// `full.power` cast all `rays` ([`far_rays`]; the solver's `full_rays_power`, 0: always
/// `rays`): the `far.rays` argument of `RAD.RECEIVER.SAMPLES`. `far` is -1 when `rays` is not
/// in 1..=65536 or a share is negative or not finite.
///
/// # Safety
/// `far` is valid for one word (the occam ABI).
pub unsafe extern "C" fn shot_rays(rays: Word, share: f64, full_power: f64, far: *mut Word) {
    let valid = (1..=MAX_SAMPLES).contains(&rays)
        && [share, full_power]
            .iter()
            .all(|x| x.is_finite() && *x >= 0.0);
    let value = if valid {
        far_rays(rays as u32, share, full_power) as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *far = value };
}

/// `PROC RAD.RECEIVER.SAMPLES (VAL []REAL32 point, normal, tri, VAL INT rays, far.rays,
/// VAL INT64 seed, VAL INT set, VAL []REAL32 grid, []REAL32 out, []REAL32 weights,
/// RESULT INT count)`: the samples of the source `tri` that the receiver `(point, normal)`, the
/// `set`-th of its batch, casts its rays to, as the solver draws them ([`receiver_samples`]):
/// `rays` per form factor, `far.rays` to a receiver outside the source's near field that sees
/// all of it (0: `rays`; `RAD.SHOT.RAYS` gives it), and none to a receiver that does not face
/// the source (its form factor is 0). Writes `count` points to `out` and, when `grid` holds a
/// density, their weights to `weights`, as `RAD.SOURCE.SAMPLES.WEIGHTED.AT` does; `count` is 0
/// for a receiver that does not face the source, and -1 (nothing written) for the wrong
/// lengths or ranges that `RAD.SOURCE.SAMPLES.WEIGHTED.AT` refuses, or `far.rays` not in
/// 0..=`rays`.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn receiver_samples_at(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    tri: *const f32,
    tri_len: Word,
    rays: Word,
    far: Word,
    seed: Word,
    set: Word,
    grid: *const f32,
    grid_len: Word,
    out: *mut f32,
    out_len: Word,
    weights: *mut f32,
    weights_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (p, n, tri, grid) = unsafe {
        (
            point(array(p, p_len)),
            point(array(n, n_len)),
            triangle(array(tri, tri_len)),
            array(grid, grid_len),
        )
    };
    let density = SourceDensity::from_cells(grid);
    let valid = (1..=MAX_SAMPLES).contains(&rays)
        && (0..=rays).contains(&far)
        && (0..=MAX_SKIPPED_SETS).contains(&set)
        && (grid.is_empty() || density.is_some());
    let drawn = match (p, n, tri) {
        (Some(p), Some(n), Some(tri)) if valid => {
            let config = FormFactorConfig {
                rays: rays as u32,
                far_rays: far as u32,
                ..FormFactorConfig::default()
            };
            let mut rng = Pcg32::new(seed as u64, SAMPLE_STREAM);
            rng.advance(set as u64 * 2 * u64::from(sample_grid(config.rays)).pow(2));
            let (mut samples, mut w) = (Vec::new(), Vec::new());
            let density = density.as_ref();
            receiver_samples(
                (p, n),
                &Facing::new(&tri),
                &config,
                density,
                &mut rng,
                &mut samples,
                &mut w,
            );
            Some((samples, w))
        }
        _ => None,
    };
    let written = match drawn {
        // SAFETY: the ABI passes `out` and `weights` valid for their lengths.
        Some((samples, w)) => unsafe {
            write_samples(&samples, &w, out, out_len, weights, weights_len)
        },
        None => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// Writes `samples` (3 floats each) to `out` and their weights `w` to `weights` and answers how
/// many samples, or -1 (nothing written) when either array is too short.
///
/// # Safety
/// `out` is valid for `out_len` floats and `weights` for `weights_len`.
unsafe fn write_samples(
    samples: &[Vec3],
    w: &[f32],
    out: *mut f32,
    out_len: Word,
    weights: *mut f32,
    weights_len: Word,
) -> Word {
    let floats = 3 * samples.len();
    if floats as Word > out_len || w.len() as Word > weights_len {
        return -1;
    }
    // SAFETY: `out` is valid for `out_len` >= `floats` floats.
    let out = unsafe { std::slice::from_raw_parts_mut(out, floats) };
    for (o, s) in out.chunks_exact_mut(3).zip(samples) {
        o.copy_from_slice(&s.to_array());
    }
    if !w.is_empty() {
        // SAFETY: `weights` is valid for `weights_len` >= `w.len()` floats.
        unsafe { std::slice::from_raw_parts_mut(weights, w.len()) }.copy_from_slice(w);
    }
    samples.len() as Word
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square's patch split into a fan of elements around an inner point.
    fn fan() -> (Vec<f32>, Vec<f32>) {
        let [a, b, c] = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let m = Vec3::new(0.3, 0.3, 0.0);
        let patch: Vec<f32> = [a, b, c].iter().flat_map(|v| v.to_array()).collect();
        let elements = [[a, b, m], [b, c, m], [c, a, m]]
            .iter()
            .flatten()
            .flat_map(|v| v.to_array())
            .collect();
        (patch, elements)
    }

    fn one(patch: &[f32], elements: &[f32], density: &[f32]) -> (Word, Vec<f32>) {
        let (mut grid, mut cells) = (vec![7.0; DENSITY_CELLS as usize], 0);
        // SAFETY: valid arrays and result.
        unsafe {
            source_density(
                patch.as_ptr(),
                patch.len() as Word,
                elements.as_ptr(),
                elements.len() as Word,
                density.as_ptr(),
                density.len() as Word,
                grid.as_mut_ptr(),
                grid.len() as Word,
                &mut cells,
            )
        };
        (cells, grid)
    }

    fn many(patch: &[f32], elements: &[f32], values: &[f32], n: usize) -> (Vec<i32>, Vec<f32>) {
        let (mut grids, mut cells) = (vec![7.0; n * DENSITY_CELLS as usize], vec![5; n]);
        // SAFETY: valid arrays.
        unsafe {
            source_densities(
                patch.as_ptr(),
                patch.len() as Word,
                elements.as_ptr(),
                elements.len() as Word,
                values.as_ptr(),
                values.len() as Word,
                grids.as_mut_ptr(),
                grids.len() as Word,
                cells.as_mut_ptr(),
                n as Word,
            )
        };
        (cells, grids)
    }

    #[test]
    fn densities_at_once_are_each_density_alone() {
        let (patch, elements) = fan();
        // the sum of the channels, then three channels: one uniform, two not
        let sets = [
            [3.0, 1.0, 2.0],
            [1.0, 1.0, 1.0],
            [1.5, 0.0, 0.5],
            [0.5, 0.0, 0.5],
        ];
        let values: Vec<f32> = sets.iter().flatten().copied().collect();
        let (cells, grids) = many(&patch, &elements, &values, 4);
        for (j, set) in sets.iter().enumerate() {
            let (alone, grid) = one(&patch, &elements, set);
            assert_eq!(Word::from(cells[j]), alone, "density {j}'s cells");
            let at = j * DENSITY_CELLS as usize;
            assert_eq!(
                &grids[at..at + DENSITY_CELLS as usize],
                &grid[..],
                "density {j}"
            );
        }
        let full = DENSITY_CELLS as i32;
        assert_eq!(cells, [full, 0, full, full]);
    }

    #[test]
    fn densities_of_wrong_lengths_write_nothing() {
        let (patch, elements) = fan();
        let untouched = vec![7.0; 2 * DENSITY_CELLS as usize];
        // one value short, and five densities
        for (values, n) in [(vec![1.0; 5], 2), (vec![1.0; 15], 5)] {
            let (cells, grids) = many(&patch, &elements, &values, n);
            assert!(cells.iter().all(|&c| c == -1), "{cells:?}");
            assert_eq!(&grids[..2 * DENSITY_CELLS as usize], &untouched[..]);
        }
        // grids one cell short
        let values = [1.0, 2.0, 3.0];
        let (mut grids, mut cells) = (vec![7.0; DENSITY_CELLS as usize - 1], [5]);
        // SAFETY: valid arrays.
        unsafe {
            source_densities(
                patch.as_ptr(),
                9,
                elements.as_ptr(),
                27,
                values.as_ptr(),
                3,
                grids.as_mut_ptr(),
                grids.len() as Word,
                cells.as_mut_ptr(),
                1,
            )
        };
        assert_eq!(cells, [-1]);
    }
}
