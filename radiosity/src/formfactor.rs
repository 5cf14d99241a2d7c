//! Form factors from a differential receiver (a sample point) to a source patch (a triangle).
//!
//! - **Wallace et al. 1989**: the source is sampled at `m` stratified points, each standing for a
//!   disc of area `A/m`; each sample contributes `δ_k (A/m) cosθ₁ cosθ₂ / (π r² + A/m)` where
//!   `δ_k` is the answer of a shadow ray. Exact for a coaxial parallel disc, finite as `r → 0`.
//! - **Analytic extension** (Baum, Rushmeier, Winget 1989): where the disc assumption breaks (the
//!   receiver is close to the source compared with its size), the
//!   exact unoccluded point-to-polygon form factor (Lambert's contour formula, with the source
//!   clipped to the receiver's hemisphere) times the fraction of the shadow rays that got through
//!   (weighted by the point kernel and the source's density; near a source whose density
//!   varies, the weights are balanced to the kernel's mean of the density over the whole
//!   source: `balance_weights`).
//!
//! When to switch: each Wallace term underestimates the point-sample term by the factor
//! `πr² / (πr² + ΔA)`, so its relative bias is about `ΔA / (π r²)` (about 1% for 16 rays to a unit
//! square at distance 1, as a table of ray-cast against exact form factors shows). The analytic form is used when
//! that bound at the nearest point of the source, `(A/m) / (π d_min²)`, exceeds `max_disc_bias`.
//!
//! Sources are one-sided: a receiver behind the source's plane gets zero.

use glam::{Vec3, Vec4};

use crate::geom::{Tri, clip_polygon, clip_polygon_into};
use crate::octree::{Octree, Traversal};
use crate::rng::Pcg32;

/// Receivers nearer a source than this many times the square root of its area are in its near
/// field: there the form factor varies most across the source and with the receiver's position
/// (the dim block faces see most of their light from the strip of floor at their base), so they
/// always cast [`FormFactorConfig::rays`] rays ([`FormFactorConfig::far_rays`]).
pub const NEAR_FIELD: f32 = 1.0;

/// Receivers nearer a source whose unshot radiosity varies over it than this many times the
/// square root of its area have their samples' weights balanced (`balance_weights`): there
/// the point kernel peaks within the source, and the analytic form's share of the kernel over a
/// few samples is biased (radiosity/REFERENCES.md, "The analytic form's share, balanced").
pub const BALANCE_FIELD: f32 = 2.0;

/// Settings of the form-factor kernel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FormFactorConfig {
    /// Shadow rays (source samples) per receiver and source; rounded to a square for
    /// stratification. More rays: softer, less noisy shadows, proportionally more time.
    pub rays: u32,
    /// Rays for receivers outside the source's near field ([`NEAR_FIELD`]) that see all of it
    /// above their horizon (where a receiver sees only part of it, a sample below the horizon
    /// tells nothing, and with one or two samples the analytic form's visible share would
    /// often rest on none: a bias low); 0: `rays`. The
    /// solver casts fewer for weak shots ([`crate::solver::SolverConfig::full_rays_power`]).
    /// Each receiver's samples are drawn from its own slot of `2k²` numbers of the batch's
    /// generator, `k` from `rays` ([`sample_grid`]), whatever it casts.
    pub far_rays: u32,
    /// The analytic form is used when the disc estimator's bias bound `(A/m) / (π d_min²)`
    /// exceeds this (0: always analytic; infinity: always Wallace).
    pub max_disc_bias: f32,
    /// Ray origins are lifted by this distance along the receiver normal, and rays end at the
    /// source sample lifted by this distance along the source normal. Both ends then lie off
    /// the planes they start and end on, so a ray can meet neither its receiver's surface nor
    /// its source's, however grazing (a ray stopped short *along itself* stays within rounding
    /// of the source plane at grazing angles and hits it).
    pub offset: f32,
}

impl Default for FormFactorConfig {
    fn default() -> Self {
        FormFactorConfig {
            rays: 16,
            far_rays: 0,
            max_disc_bias: 0.002,
            offset: 1e-3,
        }
    }
}

/// The result of one receiver-to-source evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FormFactor {
    /// The form factor estimate F(dA → source).
    pub value: f32,
    /// Shadow rays cast.
    pub rays: u32,
    /// Whether the analytic form was used.
    pub analytic: bool,
}

/// Returns the exact form factor from a differential area at `p` with unit normal `n` to the
/// convex planar polygon `poly`, ignoring occlusion; the part of the polygon below the receiver's
/// horizon is clipped away. Orientation of `poly` does not matter.
pub fn point_polygon(p: Vec3, n: Vec3, poly: &[Vec3]) -> f32 {
    const SMALL: usize = 8;
    if poly.len() <= SMALL {
        let mut clipped = [Vec3::ZERO; SMALL + 1];
        let k = clip_polygon_into(poly, p, n, &mut clipped);
        clipped_polygon(p, n, &clipped[..k])
    } else {
        clipped_polygon(p, n, &clip_polygon(poly, p, n))
    }
}

/// [`point_polygon`] of a polygon wholly above the receiver's horizon (Lambert's contour sum).
fn clipped_polygon(p: Vec3, n: Vec3, clipped: &[Vec3]) -> f32 {
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0f64;
    for i in 0..clipped.len() {
        let a = (clipped[i] - p).as_dvec3();
        let b = (clipped[(i + 1) % clipped.len()] - p).as_dvec3();
        let c = a.cross(b);
        let len = c.length();
        if len > 0.0 {
            let gamma = angle(len, a.dot(b));
            sum += gamma * n.as_dvec3().dot(c) / len;
        }
    }
    (sum.abs() / (2.0 * std::f64::consts::PI)) as f32
}

/// The angle in `[0, π]` between two vectors from `|a × b|` (`sin`, positive) and `a · b`
/// (`cos`): `atan2(sin, cos)` to within a few units in the last place, in about a fifth of the
/// instructions of the C library's (the contour sum takes one per edge, and the analytic form
/// one contour sum or more per near receiver). The reduction and rational approximation are
/// those of Moshier's Cephes `atan` (peak relative error 2.6e-18 on `[0, 0.66]`).
#[inline]
fn angle(sin: f64, cos: f64) -> f64 {
    #[allow(clippy::excessive_precision)]
    const P: [f64; 5] = [
        -8.750_608_600_031_904_122_785e-1,
        -1.615_753_718_733_365_076_637e1,
        -7.500_855_792_314_704_667_340e1,
        -1.228_866_684_490_136_173_410e2,
        -6.485_021_904_942_025_371_773e1,
    ];
    #[allow(clippy::excessive_precision)]
    const Q: [f64; 5] = [
        2.485_846_490_142_306_297_962e1,
        1.650_270_098_316_988_542_046e2,
        4.328_810_604_912_902_668_951e2,
        4.853_903_996_359_136_964_868e2,
        1.945_506_571_482_613_964_425e2,
    ];
    // π/2 and π/4 to more bits than an f64 holds: the part past the last place
    #[allow(clippy::excessive_precision)]
    const MORE_BITS: f64 = 6.123_233_995_736_765_886_130e-17;
    // tan(3π/8)
    #[allow(clippy::excessive_precision)]
    const TAN_3PI_8: f64 = 2.414_213_562_373_095_048_80;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    // atan(sin / |cos|), its argument brought into [−0.42, 0.66]
    let along = cos.abs();
    let (x, base, more) = if sin > TAN_3PI_8 * along {
        (-along / sin, FRAC_PI_2, MORE_BITS)
    } else if sin > 0.66 * along {
        ((sin - along) / (sin + along), FRAC_PI_4, 0.5 * MORE_BITS)
    } else {
        (sin / along, 0.0, 0.0)
    };
    let z = x * x;
    let p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    let q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    let acute = base + (x + x * z * p / q + more);
    if cos < 0.0 { PI - acute } else { acute }
}

/// Returns the stratified sample points of a source triangle for `m` rays (a jittered
/// `k × k` grid, `k = ceil(sqrt(m))`, warped onto the triangle by [`Tri::sample`]).
pub fn source_samples(src: &Tri, m: u32, rng: &mut Pcg32, out: &mut Vec<Vec3>) {
    source_samples_weighted(src, m, None::<&SourceDensity>, rng, out, &mut Vec::new());
}

/// The side `k` of the `k × k` grid of source samples taken for `m` rays: `⌈√m⌉` (at least 1).
/// A set of samples draws `2k²` numbers from its generator.
pub fn sample_grid(m: u32) -> u32 {
    (m.max(1) as f32).sqrt().ceil() as u32
}

/// [`source_samples`], and in `weights` the source's relative unshot radiosity at each sample
/// (`density`; all 1 when `None`, and then `weights` is left empty).
pub fn source_samples_weighted<C: AsRef<[f32]>>(
    src: &Tri,
    m: u32,
    density: Option<&SourceDensity<C>>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<f32>,
) {
    part_samples_weighted(&Part::Whole(src), m, density, rng, out, weights);
}

/// [`source_samples_weighted`] over a part of the source ([`Part`]).
fn part_samples_weighted<C: AsRef<[f32]>>(
    part: &Part,
    m: u32,
    density: Option<&SourceDensity<C>>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<f32>,
) {
    weights.clear();
    stratified_samples(part, m, rng, out, |u, v| {
        if let Some(d) = density {
            weights.push(d.at(u, v));
        }
    });
}

/// [`source_samples_weighted`] for several densities of one source at once ([`DensitySet`]):
/// the same samples, and in `weights[k][j]` the weight density `j` gives sample `k`, exactly
/// as [`source_samples_weighted`] with that density gives it (1 for a uniform one).
pub fn source_samples_sets<const N: usize>(
    src: &Tri,
    m: u32,
    densities: &DensitySet<N>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<[f32; N]>,
) {
    part_samples_sets(&Part::Whole(src), m, densities, rng, out, weights);
}

/// [`source_samples_sets`] over a part of the source ([`Part`]).
fn part_samples_sets<const N: usize>(
    part: &Part,
    m: u32,
    densities: &DensitySet<N>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<[f32; N]>,
) {
    weights.clear();
    stratified_samples(part, m, rng, out, |u, v| weights.push(densities.at(u, v)));
}

/// The jittered `k × k` grid of [`source_samples`] into `out`, over `part` of a source, calling
/// `at(u, v)` with each sample's place in the square [`Tri::sample`] warps onto the whole
/// source (where its densities are looked up).
fn stratified_samples(
    part: &Part,
    m: u32,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    mut at: impl FnMut(f32, f32),
) {
    out.clear();
    let k = sample_grid(m);
    for i in 0..k {
        for j in 0..k {
            let u = (i as f32 + rng.next_f32()) / k as f32;
            let v = (j as f32 + rng.next_f32()) / k as f32;
            match part {
                Part::Whole(src) => {
                    out.push(src.sample(u, v));
                    at(u, v);
                }
                Part::Fan { src, fan, first } => {
                    // u picks a triangle of the fan by area, then places the sample in it
                    let x = if u < *first {
                        fan[0].sample((u / first).min(1.0), v)
                    } else {
                        let u = ((u - first) / (1.0 - first)).clamp(0.0, 1.0);
                        fan[1].sample(u, v)
                    };
                    out.push(x);
                    let (su, sv) = square_point(src, x);
                    at(su, sv);
                }
            }
        }
    }
}

/// The part of a source a receiver draws its samples from ([`receiver_samples`]).
enum Part<'t> {
    /// All of it.
    Whole(&'t Tri),
    /// The part above the receiver's horizon: a triangle clipped by a plane has three or four
    /// corners, so a fan of one or two triangles, the first taking the share `first` of the
    /// part's area.
    Fan {
        src: &'t Tri,
        fan: [Tri; 2],
        first: f32,
    },
}

impl<'t> Part<'t> {
    /// The part of `src` that the receiver `(p, n)`, drawing `m` samples, draws them from: where
    /// the source reaches below the receiver's horizon and the receiver takes the analytic form
    /// (exact over the part above it, times the visible share of the samples), only the part
    /// above. Samples below the horizon count for nothing there, and a receiver at a contact
    /// line or a concave corner (a table leg under the table top, a block's face at the floor)
    /// may see only a thin strip of a large source: drawn from all of it, few or none of its
    /// samples fall in the strip, and with none the visible share is taken as 0 (a leg's face
    /// under the table top's 5 cm overhang got 0 for 0.49 on most seeds; radiosity/
    /// REFERENCES.md, "A row of points beside concave creases").
    fn of(
        (p, n): (Vec3, Vec3),
        source: &Facing<'t>,
        m: u32,
        d_min2: f32,
        config: &FormFactorConfig,
    ) -> Part<'t> {
        let src = source.src;
        let height = src.v.map(|v| n.dot(v - p));
        if height.iter().all(|&h| h > 0.0) {
            return Part::Whole(src);
        }
        let k = sample_grid(m);
        if !is_analytic(source.area, (k * k) as usize, d_min2, config) {
            return Part::Whole(src);
        }
        // the corners above the horizon and where the edges cross it, in order (as
        // `clip_polygon` keeps them)
        let (mut poly, mut count) = ([Vec3::ZERO; 4], 0);
        for i in 0..3 {
            let j = (i + 1) % 3;
            let (a, b, ha, hb) = (src.v[i], src.v[j], height[i], height[j]);
            if ha >= 0.0 {
                poly[count] = a;
                count += 1;
            }
            if (ha >= 0.0) != (hb >= 0.0) && count < 4 {
                poly[count] = a + (b - a) * (ha / (ha - hb));
                count += 1;
            }
        }
        let fan = [
            Tri {
                v: [poly[0], poly[1], poly[2]],
            },
            Tri {
                v: [poly[0], poly[2], poly[3]],
            },
        ];
        let areas = [fan[0].area(), if count == 4 { fan[1].area() } else { 0.0 }];
        let total = areas[0] + areas[1];
        if count < 3 || !(total > 0.0 && total.is_finite()) {
            return Part::Whole(src);
        }
        let first = if count == 4 { areas[0] / total } else { 1.0 };
        Part::Fan { src, fan, first }
    }
}

/// Several densities of one source side by side (a shot's channels summed and each channel,
/// [`channels_differ`]): each cell holds the `N` densities' values, 1 for a uniform one, so
/// that a sample looks its weights up once.
#[derive(Clone, Debug, PartialEq)]
pub struct DensitySet<const N: usize> {
    g: u32,
    cells: Vec<[f32; N]>,
    uniform: [bool; N],
    /// The side of a block of cells ([`BLOCK`] when it divides `g`, else 1), and each block's
    /// mean, row by row (`balance_weights` takes a block far from the receiver so).
    block: u32,
    blocks: Vec<[f32; N]>,
    /// The blocks' means again, density by density, each row of blocks padded with zeros to
    /// `lanes` (a multiple of 4), for `balance_weights` to take the far ones four at a time.
    lanes: u32,
    block_lanes: [Vec<f32>; N],
    /// Whether each block's cells hold one value, in each density.
    flat: Vec<[bool; N]>,
}

/// The side of the blocks of a density's cells that `balance_weights` may take at once.
const BLOCK: u32 = 3;

/// Beyond this many of its radii from the receiver, `balance_weights` takes a block of cells
/// at once by the kernel at its middle; nearer, by the 2 × 2 Gauss–Legendre rule
/// ([`GAUSS_2`]) where its cells hold one value or it lies beyond [`CELL_BLOCK`].
const NEAR_BLOCK: f32 = 5.0;

/// Within this many of its radii, `balance_weights` takes a block whose cells differ cell by
/// cell.
const CELL_BLOCK: f32 = 4.0;

/// Within this many of its radii of the receiver, `balance_weights` takes the kernel's
/// integral over a cell exactly (Lambert's contour sum, [`point_polygon`]).
const EXACT_CELL: f32 = 1.0;

/// Beyond [`EXACT_CELL`] and within this many of its radii, `balance_weights` takes the
/// kernel's integral over a cell by the 4 × 4 Gauss–Legendre rule ([`GAUSS_4`]).
const NEAR_CELL: f32 = 2.0;

/// Beyond [`NEAR_CELL`] and within this many of its radii, `balance_weights` takes a cell's
/// integral by the 2 × 2 rule ([`GAUSS_2`]); beyond, by the kernel at its middle.
const GAUSS_CELL: f32 = 3.0;

/// A Gauss–Legendre rule on `[-1/2, 1/2]`: its nodes and weights (summing to 1).
type Rule = (&'static [f32], &'static [f32]);

/// The two-point Gauss–Legendre rule ([`Rule`]).
const GAUSS_2: Rule = (&[-0.288_675_13, 0.288_675_13], &[0.5, 0.5]);

/// The four-point Gauss–Legendre rule ([`Rule`]).
const GAUSS_4: Rule = (
    &[-0.430_568_16, -0.169_990_52, 0.169_990_52, 0.430_568_16],
    &[0.173_927_42, 0.326_072_58, 0.326_072_58, 0.173_927_42],
);

impl<const N: usize> DensitySet<N> {
    /// The set of `densities` (`None`: uniform); those given must share their grid, as
    /// [`SourceDensity::of_parts_sets`] makes them.
    pub fn new<C: AsRef<[f32]>>(densities: [Option<&SourceDensity<C>>; N]) -> DensitySet<N> {
        let g = densities.iter().flatten().map(|d| d.g).next().unwrap_or(1);
        debug_assert!(densities.iter().flatten().all(|d| d.g == g));
        let cells: Vec<[f32; N]> = (0..(g * g) as usize)
            .map(|i| densities.map(|d| d.map_or(1.0, |d| d.cells.as_ref()[i])))
            .collect();
        let block = if g % BLOCK == 0 { BLOCK } else { 1 };
        let side = g / block;
        let share = 1.0 / (block * block) as f32;
        let blocks = (0..side * side)
            .map(|b| {
                let (bi, bj) = (b / side, b % side);
                let mut mean = [0.0f32; N];
                let first = cells[(bi * block * g + bj * block) as usize];
                let mut flat = [true; N];
                for i in bi * block..(bi + 1) * block {
                    for j in bj * block..(bj + 1) * block {
                        let d = cells[(i * g + j) as usize];
                        for c in 0..N {
                            mean[c] += d[c] * share;
                            flat[c] &= d[c] == first[c];
                        }
                    }
                }
                (mean, flat)
            })
            .collect::<Vec<_>>();
        let flat = blocks.iter().map(|b| b.1).collect();
        let blocks: Vec<[f32; N]> = blocks.into_iter().map(|b| b.0).collect();
        let lanes = side.div_ceil(4) * 4;
        let block_lanes = std::array::from_fn(|c| {
            let mut lane = vec![0.0; (side * lanes) as usize];
            for (b, mean) in blocks.iter().enumerate() {
                let (bi, bj) = (b as u32 / side, b as u32 % side);
                lane[(bi * lanes + bj) as usize] = mean[c];
            }
            lane
        });
        DensitySet {
            g,
            cells,
            uniform: densities.map(|d| d.is_none()),
            block,
            blocks,
            lanes,
            block_lanes,
            flat,
        }
    }

    /// The densities at `(u, v)` in [0,1)², each as [`SourceDensity::at`] gives it.
    pub fn at(&self, u: f32, v: f32) -> [f32; N] {
        let cell = |x: f32| ((x * self.g as f32) as u32).min(self.g - 1);
        self.cells[(cell(u) * self.g + cell(v)) as usize]
    }

    /// Which densities are uniform.
    pub fn uniform(&self) -> [bool; N] {
        self.uniform
    }
}

/// How a source's unshot radiosity varies over it, relative to its mean: a `g × g` grid of cells
/// over the square `(u, v)` that [`Tri::sample`] maps onto the triangle, each holding the
/// density at its centre over the mean (so a uniform source is 1 everywhere).
///
/// This lets a patch shoot what each of its elements holds rather than its average: a floor
/// patch half in a block's shadow shoots from its lit half only, which the block's face, close
/// by, sees very differently (issue 10, cause 4). Far receivers average the same samples.
/// Where the channels are spread differently over the patch (a floor strip lit mostly by a red
/// wall), each channel shoots with its own ([`channels_differ`]).
///
/// The cells are owned (`Vec<f32>`, as the solver tabulates them) or borrowed (`&[f32]`, as an
/// intrinsic is passed them, [`SourceDensity::from_cells`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SourceDensity<C = Vec<f32>> {
    g: u32,
    cells: C,
}

impl SourceDensity {
    /// Tabulates `density(point)` (any scale, non-negative) over `src` on a `g × g` grid and
    /// divides by its area-weighted mean; `None` when the mean is not positive or the density
    /// is uniform within a part in a million (no weights needed).
    pub fn new(src: &Tri, g: u32, density: impl Fn(Vec3) -> f32) -> Option<SourceDensity> {
        let g = g.max(1);
        let mut cells = Vec::with_capacity((g * g) as usize);
        for i in 0..g {
            for j in 0..g {
                let (u, v) = ((i as f32 + 0.5) / g as f32, (j as f32 + 0.5) / g as f32);
                cells.push(density(src.sample(u, v)));
            }
        }
        SourceDensity::from_values(g, cells)
    }

    /// The density of the `g × g` values at the cells' centres (row by row, any scale; a
    /// negative value counts as 0), as [`SourceDensity::new`] describes.
    fn from_values(g: u32, mut cells: Vec<f32>) -> Option<SourceDensity> {
        cells.iter_mut().for_each(|c| *c = c.max(0.0));
        // The warp preserves area, so every cell stands for the same area.
        let mean = cells.iter().map(|&c| c as f64).sum::<f64>() / cells.len() as f64;
        let (lo, hi) = cells
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &c| (a.min(c), b.max(c)));
        if mean.is_nan() || mean <= 0.0 || (hi - lo) as f64 <= 1e-6 * mean {
            return None;
        }
        cells
            .iter_mut()
            .for_each(|c| *c = (*c as f64 / mean) as f32);
        Some(SourceDensity { g, cells })
    }

    /// The density of a patch `src` made of `parts`, each a triangle of it with its unshot
    /// radiosity (unshot power over area, channels summed): at each grid cell, the first part
    /// (in `parts` order) that contains the cell's centre ([`Tri::contains`]), or the nearest
    /// part for a centre beside every part. `None` with fewer than two parts, or as [`SourceDensity::new`]. The
    /// solver and the `RAD.SOURCE.DENSITY` and `RAD.SOURCE.DENSITIES` intrinsics tabulate a
    /// shooting patch with this ([`SourceDensity::of_parts_sets`] for several densities).
    ///
    /// The cells are found part by part: a cell centre `src.sample(u, v)` has the barycentric
    /// coordinates `(1 - s, v s, (1 - v) s)` with `s = √u`, so a part covers the centres of the
    /// rows whose `s` and the columns whose `v s` lie within its own range of the two, and only
    /// those are tested (about the grid's cells in all, where a search of every part per cell
    /// costs their product).
    pub fn of_parts(src: &Tri, g: u32, parts: &[(Tri, f32)]) -> Option<SourceDensity> {
        let parts: Vec<(Tri, [f32; 1])> = parts.iter().map(|&(t, d)| (t, [d])).collect();
        let [density] = SourceDensity::of_parts_sets(src, g, &parts);
        density
    }

    /// [`SourceDensity::of_parts`] of several densities over the same parts at once (each part
    /// with one value per density: the solver tabulates a shot's channels sum and each channel,
    /// [`channels_differ`]); `[j]` is exactly what [`SourceDensity::of_parts`] makes of the
    /// parts with their `j`-th values.
    pub fn of_parts_sets<const N: usize>(
        src: &Tri,
        g: u32,
        parts: &[(Tri, [f32; N])],
    ) -> [Option<SourceDensity>; N] {
        if parts.len() < 2 {
            return std::array::from_fn(|_| None);
        }
        let g = g.max(1);
        let gf = g as f32;
        let centre = |i: u32, j: u32| src.sample((i as f32 + 0.5) / gf, (j as f32 + 0.5) / gf);
        let mut owner: Vec<Option<usize>> = vec![None; (g * g) as usize];
        // Ranges are widened by a margin: the test itself is exact, the range only selects.
        const MARGIN: f32 = 1e-3;
        for (k, (part, _)) in parts.iter().enumerate() {
            let (mut s_lo, mut s_hi, mut t_lo, mut t_hi) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
            for &corner in &part.v {
                let [a, b, _] = src.barycentric(corner);
                let s = 1.0 - a;
                (s_lo, s_hi) = (s_lo.min(s), s_hi.max(s));
                (t_lo, t_hi) = (t_lo.min(b), t_hi.max(b));
            }
            if !(s_lo.is_finite() && s_hi.is_finite() && t_lo.is_finite() && t_hi.is_finite()) {
                continue;
            }
            let (s_lo, s_hi) = ((s_lo - MARGIN).max(0.0), s_hi + MARGIN);
            let (t_lo, t_hi) = (t_lo - MARGIN, t_hi + MARGIN);
            // Row i's s is √((i + ½) / g): rows from g s_lo² - ½ to g s_hi² - ½.
            let rows = index_range(gf * s_lo * s_lo - 0.5, gf * s_hi * s_hi - 0.5, g);
            for i in rows {
                let s = ((i as f32 + 0.5) / gf).sqrt();
                // Column j's v s is (j + ½) s / g.
                for j in index_range(gf * t_lo / s - 0.5, gf * t_hi / s - 0.5, g) {
                    let cell = &mut owner[(i * g + j) as usize];
                    if cell.is_none() && part.contains(centre(i, j)) {
                        *cell = Some(k);
                    }
                }
            }
        }
        let mut cells: [Vec<f32>; N] = std::array::from_fn(|_| Vec::with_capacity(owner.len()));
        for i in 0..g {
            for j in 0..g {
                let k = owner[(i * g + j) as usize].unwrap_or_else(|| {
                    let x = centre(i, j);
                    parts
                        .iter()
                        .map(|(t, _)| (t.closest_point(x) - x).length_squared())
                        .enumerate()
                        .fold((0, f32::MAX), |b, c| if c.1 < b.1 { c } else { b })
                        .0
                });
                for (set, &value) in cells.iter_mut().zip(&parts[k].1) {
                    set.push(value);
                }
            }
        }
        cells.map(|c| SourceDensity::from_values(g, c))
    }
}

/// The indices `0..g` from `ceil(lo)` to `floor(hi)`.
fn index_range(lo: f32, hi: f32, g: u32) -> std::ops::Range<u32> {
    // (A NaN bound widens the range to the grid's edge: `max` and `min` ignore it.)
    let first = lo.ceil().max(0.0);
    let last = hi.floor().min(g as f32 - 1.0);
    if first > last {
        return 0..0;
    }
    first as u32..last as u32 + 1
}

impl<'a> SourceDensity<&'a [f32]> {
    /// A density from its `g × g` cells as [`SourceDensity::cells`] lists them, borrowed (an
    /// intrinsic takes one per receiver); `None` unless there are `g²` cells for some `g ≥ 1`,
    /// each finite and non-negative.
    pub fn from_cells(cells: &'a [f32]) -> Option<Self> {
        let g = (cells.len() as f64).sqrt().round() as u32;
        let fits = g >= 1 && (g * g) as usize == cells.len();
        let valid = cells.iter().all(|c| c.is_finite() && *c >= 0.0);
        (fits && valid).then_some(SourceDensity { g, cells })
    }
}

impl<C: AsRef<[f32]>> SourceDensity<C> {
    /// The cells, row by row (`u` major), each the density at its centre over the mean.
    pub fn cells(&self) -> &[f32] {
        self.cells.as_ref()
    }

    /// The relative density at `(u, v)` in [0,1)².
    pub fn at(&self, u: f32, v: f32) -> f32 {
        let cell = |x: f32| ((x * self.g as f32) as u32).min(self.g - 1);
        self.cells.as_ref()[(cell(u) * self.g + cell(v)) as usize]
    }
}

/// Whether the receiver `(p, n)` can see any of the (one-sided) source `src`: it is in front of
/// the source's plane by more than the rounding of their coordinates and some of the source is
/// above its horizon. When not, every form factor to `src` from `(p, n)` is zero and no shadow
/// ray is cast.
///
/// A receiver in the source's plane sees it edge-on (form factor 0), but the contour formula
/// ([`point_polygon`]) gives 1/2 for a point on the polygon's boundary: a sample point on the
/// fold of a slightly non-planar wall lies within rounding of the neighbouring triangle's plane
/// and on its edge, and would see it at 1/2. (Points on a surface's boundary are evaluated a
/// thousandth of their shortest edge inside it ([`crate::mesh::Vertex::eval`]), far more than
/// rounding: a floor point at a wall's foot still sees the wall.)
pub fn faces(p: Vec3, n: Vec3, src: &Tri) -> bool {
    Facing::new(src).faced_by(p, n)
}

/// Shadow rays the receiver `(p, n)` casts to the source `src`: none when it does not face it
/// ([`faces`]); [`FormFactorConfig::far_rays`] when that is fewer than `rays` (and not 0) and
/// the receiver is outside the source's near field ([`NEAR_FIELD`]) and sees all of it above
/// its horizon; else [`FormFactorConfig::rays`]. The solver's kernels and
/// `RAD.RECEIVER.SAMPLES` ask this.
pub fn receiver_rays(p: Vec3, n: Vec3, src: &Tri, config: &FormFactorConfig) -> u32 {
    Facing::new(src)
        .rays(p, n, config)
        .map_or(0, |(rays, _)| rays)
}

/// Draws the weighted samples of the `source` ([`source_samples_weighted`]; its normal and
/// area worked out once for a batch's receivers) that the receiver `(p, n)` casts its rays
/// to, [`receiver_rays`] of them (rounded up to a square); none when it does not face the
/// source. Every receiver owns a slot of `2k²` numbers of `rng`, `k` =
/// [`sample_grid`]`(config.rays)`, draws from its start and leaves `rng` at the next slot, so
/// the receivers of a batch draw from one generator in order and a node holding one of them
/// draws the same set by skipping to its slot (`RAD.RECEIVER.SAMPLES`). A near receiver's
/// weights are balanced (`balance_weights`). Returns the rays.
pub fn receiver_samples<C: AsRef<[f32]>>(
    receiver: (Vec3, Vec3),
    source: &Facing,
    config: &FormFactorConfig,
    density: Option<&SourceDensity<C>>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<f32>,
) -> u32 {
    weights.clear();
    let slot = receiver_slot(
        receiver,
        source,
        config,
        rng,
        out,
        |part, rays, rng, out| part_samples_weighted(part, rays, density, rng, out, weights),
    );
    let Some((rays, nearest)) = slot else {
        return 0;
    };
    if let Some(d) = density {
        let (planes, _) = weights.as_chunks_mut::<1>();
        let densities = DensitySet::new([Some(d)]);
        balance_weights(receiver, source, nearest, out, planes, &densities, config);
    }
    rays
}

/// [`receiver_samples`] with the weights of several densities of the source
/// ([`source_samples_sets`]).
pub fn receiver_samples_sets<const N: usize>(
    receiver: (Vec3, Vec3),
    source: &Facing,
    config: &FormFactorConfig,
    densities: &DensitySet<N>,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    weights: &mut Vec<[f32; N]>,
) -> u32 {
    weights.clear();
    let slot = receiver_slot(
        receiver,
        source,
        config,
        rng,
        out,
        |part, rays, rng, out| part_samples_sets(part, rays, densities, rng, out, weights),
    );
    let Some((rays, nearest)) = slot else {
        return 0;
    };
    balance_weights(receiver, source, nearest, out, weights, densities, config);
    rays
}

/// The receiver's slot of `rng` ([`receiver_samples`]): `draw(part, rays, rng, out)` takes
/// its samples of the part of the source it sees ([`Part::of`]) from the slot's start, and
/// `rng` is left at the next slot. Returns the rays and the source's point nearest the
/// receiver, or `None` where the receiver does not face the source.
fn receiver_slot<'t>(
    (p, n): (Vec3, Vec3),
    source: &Facing<'t>,
    config: &FormFactorConfig,
    rng: &mut Pcg32,
    out: &mut Vec<Vec3>,
    draw: impl FnOnce(&Part<'t>, u32, &mut Pcg32, &mut Vec<Vec3>),
) -> Option<(u32, Vec3)> {
    let slot = 2 * u64::from(sample_grid(config.rays)).pow(2);
    let Some((rays, nearest)) = source.rays(p, n, config) else {
        out.clear();
        rng.advance(slot);
        return None;
    };
    let part = Part::of((p, n), source, rays, (nearest - p).length_squared(), config);
    draw(&part, rays, rng, out);
    rng.advance(slot - 2 * out.len() as u64);
    Some((rays, nearest))
}

/// Computes the form factor from the receiver `(p, n)` to source triangle `src` using the
/// source samples `samples` (see [`source_samples`]) and shadow rays through `octree`
/// (`None`: no occlusion), walked with Samet's neighbours precomputed as ropes (the fastest
/// traversal measured; all three give the same answers).
pub fn form_factor(
    octree: Option<&Octree>,
    p: Vec3,
    n: Vec3,
    src: &Tri,
    samples: &[Vec3],
    config: &FormFactorConfig,
) -> FormFactor {
    form_factor_with(p, n, src, samples, config, |_, origin, d, tmax| {
        octree.is_some_and(|o| o.occluded(origin, d, 0.0, tmax, Traversal::Ropes))
    })
}

/// [`form_factor`] with the shadow rays answered by `occluded(k, origin, dir, tmax)`: whether
/// the ray from `origin` along `dir` (parameter 0 to `tmax`) towards sample `k` is blocked. It is
/// asked only for the samples above the receiver's horizon and in front of the source, in order.
/// (The `RAD.FORM.FACTOR` intrinsic answers from a visibility array computed elsewhere.)
pub fn form_factor_with(
    p: Vec3,
    n: Vec3,
    src: &Tri,
    samples: &[Vec3],
    config: &FormFactorConfig,
    occluded: impl FnMut(usize, Vec3, Vec3, f32) -> bool,
) -> FormFactor {
    form_factor_weighted(p, n, src, samples, &[], config, occluded)
}

/// [`form_factor_with`] for a source whose unshot radiosity is not uniform: `weights[k]` is its
/// value at sample `k` over its mean (see [`SourceDensity`]; empty: uniform). The result is the
/// form factor times the mean relative radiosity the receiver sees, so that `ΔB_mean × value` is
/// the irradiance the shot brings. Each Wallace term is weighted; the analytic form is scaled by
/// the weighted share of the visible samples, each counted by its point kernel
/// `cos θ₁ cos θ₂ / r²` (the share of the form factor near it: the nearest parts of the source,
/// which dominate near the receiver, count most; the Wallace term's disc would understate them).
pub fn form_factor_weighted(
    p: Vec3,
    n: Vec3,
    src: &Tri,
    samples: &[Vec3],
    weights: &[f32],
    config: &FormFactorConfig,
    occluded: impl FnMut(usize, Vec3, Vec3, f32) -> bool,
) -> FormFactor {
    form_factor_sets(p, n, src, samples, weights, config, occluded).0
}

/// The weights of the samples of one or more densities ([`form_factor_sets`]).
pub trait SampleWeights<const N: usize> {
    /// Whether density `j` is uniform (its weights are all 1 and the analytic form takes the
    /// share of visible samples, not their kernels' share).
    fn uniform(&self, j: usize) -> bool;
    /// Sample `k`'s weight in each density.
    fn at(&self, k: usize) -> [f32; N];
}

/// One density's weights, empty for a uniform source ([`form_factor_weighted`]).
impl SampleWeights<1> for &[f32] {
    fn uniform(&self, _: usize) -> bool {
        self.is_empty()
    }
    fn at(&self, k: usize) -> [f32; 1] {
        [self.get(k).copied().unwrap_or(1.0)]
    }
}

/// Several densities' weights, as [`source_samples_sets`] draws them, and which are uniform
/// ([`DensitySet::uniform`]).
impl<const N: usize> SampleWeights<N> for (&[[f32; N]], [bool; N]) {
    fn uniform(&self, j: usize) -> bool {
        self.1[j]
    }
    fn at(&self, k: usize) -> [f32; N] {
        self.0.get(k).copied().unwrap_or([1.0; N])
    }
}

/// [`form_factor_weighted`] for several densities' weights of the same samples at once, one
/// shadow ray each (a shot's channels, whose unshot radiosity is spread differently over the
/// source: [`channels_differ`]): `[j]` of the values returned is exactly what
/// [`form_factor_weighted`] gives with density `j`'s weights and the same answers to the
/// rays, and the [`FormFactor`]'s value is `[0]`'s.
pub fn form_factor_sets<const N: usize>(
    p: Vec3,
    n: Vec3,
    src: &Tri,
    samples: &[Vec3],
    weights: impl SampleWeights<N>,
    config: &FormFactorConfig,
    occluded: impl FnMut(usize, Vec3, Vec3, f32) -> bool,
) -> (FormFactor, [f32; N]) {
    Facing::new(src).form_factor_sets(p, n, samples, weights, config, occluded)
}

/// A source as [`form_factor_facing`] takes it: its triangle with its unit normal and area,
/// worked out once for the receivers of a batch.
#[derive(Clone, Copy, Debug)]
pub struct Facing<'t> {
    src: &'t Tri,
    normal: Vec3,
    area: f32,
}

impl<'t> Facing<'t> {
    /// `src` with its normal and area.
    pub fn new(src: &'t Tri) -> Facing<'t> {
        Facing {
            src,
            normal: src.normal(),
            area: src.area(),
        }
    }

    /// [`faces`]: whether the receiver `(p, n)` can see any of the source.
    fn faced_by(&self, p: Vec3, n: Vec3) -> bool {
        let v = &self.src.v;
        let rounding = 8.0 * f32::EPSILON * (p.abs().max_element() + v[0].abs().max_element());
        self.normal.dot(p - v[0]) > rounding && v.iter().any(|v| n.dot(*v - p) > 0.0)
    }

    /// [`form_factor_sets`] from the receiver `(p, n)` to this source (worked out once for a
    /// batch of receivers).
    pub fn form_factor_sets<const N: usize>(
        &self,
        p: Vec3,
        n: Vec3,
        samples: &[Vec3],
        weights: impl SampleWeights<N>,
        config: &FormFactorConfig,
        occluded: impl FnMut(usize, Vec3, Vec3, f32) -> bool,
    ) -> (FormFactor, [f32; N]) {
        if !self.faced_by(p, n) {
            return (FormFactor::default(), [0.0; N]);
        }
        form_factor_facing(p, n, self, samples, weights, config, occluded)
    }

    /// [`receiver_rays`] of the receiver `(p, n)` and the source's point nearest it, or `None`
    /// where it does not face the source.
    fn rays(&self, p: Vec3, n: Vec3, config: &FormFactorConfig) -> Option<(u32, Vec3)> {
        if !self.faced_by(p, n) {
            return None;
        }
        let nearest = self.src.closest_point(p);
        let near2 = NEAR_FIELD * NEAR_FIELD * self.area;
        let far = (1..config.rays).contains(&config.far_rays)
            && self.src.v.iter().all(|v| n.dot(*v - p) > 0.0)
            && (nearest - p).length_squared() >= near2;
        Some((if far { config.far_rays } else { config.rays }, nearest))
    }
}

/// [`form_factor_sets`] for a receiver known to face the source ([`faces`]; as one that
/// [`receiver_rays`] gives rays is): the same answer, without asking again.
pub fn form_factor_facing<const N: usize>(
    p: Vec3,
    n: Vec3,
    facing: &Facing,
    samples: &[Vec3],
    weights: impl SampleWeights<N>,
    config: &FormFactorConfig,
    mut occluded: impl FnMut(usize, Vec3, Vec3, f32) -> bool,
) -> (FormFactor, [f32; N]) {
    let (src, ns, area) = (facing.src, facing.normal, facing.area);
    let d_min2 = (src.closest_point(p) - p).length_squared();
    let sub_area = area / samples.len() as f32;
    let analytic = is_analytic(area, samples.len(), d_min2, config);
    let origin = p + n * config.offset;
    let (mut wallace, mut rays) = ([0.0f32; N], 0u32);
    let (mut visible, mut above) = (0u32, 0u32);
    let (mut kernel_visible, mut kernel_above) = ([0.0f32; N], 0.0f32);
    for (k, &x) in samples.iter().enumerate() {
        let Some((cos1, cos2, len2)) = cosines(p, n, ns, x) else {
            continue;
        };
        let term = sub_area * cos1 * cos2 / (std::f32::consts::PI * len2 + sub_area);
        let kernel = cos1 * cos2 / len2.max(f32::MIN_POSITIVE);
        above += 1;
        kernel_above += kernel;
        let d = x + ns * config.offset - origin;
        rays += 1;
        if occluded(k, origin, d, 1.0) {
            continue;
        }
        visible += 1;
        let w = weights.at(k);
        for j in 0..N {
            wallace[j] += term * w[j];
            kernel_visible[j] += kernel * w[j];
        }
    }
    let values = if !analytic {
        wallace
    } else if visible == 0 {
        [0.0; N]
    } else {
        let whole = point_polygon(p, n, &src.v);
        std::array::from_fn(|j| {
            if weights.uniform(j) {
                whole * visible as f32 / above as f32
            } else {
                whole * kernel_visible[j] / kernel_above
            }
        })
    };
    let value = values.first().copied().unwrap_or(0.0);
    let f = FormFactor {
        value,
        rays,
        analytic,
    };
    (f, values)
}

/// Whether [`form_factor_facing`] takes the analytic form for a receiver whose nearest point of
/// the source (of `area`) is `d_min2` away squared, with `m` samples: when the disc estimator's
/// bias bound `(A/m) / (π d_min²)` exceeds [`FormFactorConfig::max_disc_bias`].
fn is_analytic(area: f32, m: usize, d_min2: f32, config: &FormFactorConfig) -> bool {
    area / m as f32 > config.max_disc_bias * std::f32::consts::PI * d_min2
}

/// `(cos θ₁, cos θ₂, r²)` from the receiver `(p, n)` to the point `x` of a source of unit normal
/// `ns`; `None` where either cosine is not positive (below the receiver's horizon, or behind the
/// source): the samples [`form_factor_facing`] counts.
#[inline]
fn cosines(p: Vec3, n: Vec3, ns: Vec3, x: Vec3) -> Option<(f32, f32, f32)> {
    let r = x - p;
    let len2 = r.length_squared();
    let len = len2.sqrt();
    let (cos1, cos2) = (n.dot(r) / len, -ns.dot(r) / len);
    (cos1 > 0.0 && cos2 > 0.0).then_some((cos1, cos2, len2))
}

/// The point kernel `cos θ₁ cos θ₂ / r²` at `x` ([`cosines`]), as [`form_factor_facing`] weighs
/// the analytic form's samples.
#[inline]
fn point_kernel(p: Vec3, n: Vec3, ns: Vec3, x: Vec3) -> Option<f32> {
    cosines(p, n, ns, x).map(|(cos1, cos2, len2)| cos1 * cos2 / len2.max(f32::MIN_POSITIVE))
}

/// Balances the weights of a near receiver's samples, so that the analytic form takes the
/// kernel's mean of the density over the whole source, not over the samples.
///
/// Near a source the analytic form is the exact unoccluded form factor times the weighted
/// kernel's share of the visible samples, `Σ_vis k w / Σ k` (sums over the samples above the
/// horizon). With a non-uniform density that is a ratio of two sums over a few samples, and its
/// mean is not the ratio of their means: where the kernel peaks at one end of the source and
/// the density at the other (a block face standing in the dark strip of floor at its foot, the
/// floor's power out in the light) the few samples overstate the density the receiver sees, by
/// up to 3% of the dim faces' radiosity, falling as the rays grow. So the weights are scaled
/// (per density) by `W Σ k / Σ k w`, where `W` is the kernel's mean of the density over the
/// source: the form factor becomes the exact one
/// times `W` times the weighted kernel's visible share `Σ_vis k w / Σ k w` (exactly `W` when
/// nothing is occluded). Where no sample above the horizon has weight, each weighs `W`.
///
/// Only receivers within [`BALANCE_FIELD`] of the source that take the analytic form are
/// balanced (farther, the kernel is nearly flat over the source and the ratio nearly
/// unbiased). `nearest` is the source's point nearest the receiver; `weights[k][j]` is sample
/// `k`'s weight in density `j` of `densities` (a uniform one is left alone). `W` is worked out
/// as `d₀ + ∫ k (d − d₀) / ∫ k`, `d₀` the densities at the kernel's peak (`nearest`) and `∫ k`
/// exact (Lambert's contour sum), so that where the density about the peak is `d₀` the rule's
/// error there, where the kernel changes fastest, counts for nothing. The integral goes over the
/// densities' cells (a density is constant over a cell, so no step of it falls within one;
/// [`Tri::sample`] keeps areas, so cells weigh alike), by rules that grow cheaper with the
/// distance in radii: [`BLOCK`]² cells at once beyond [`NEAR_BLOCK`] of the block's radii (the
/// kernel at its middle, its mean density), or nearer where its cells hold one value or it
/// lies beyond [`CELL_BLOCK`] (2 × 2 Gauss–Legendre); otherwise cell by cell, exactly within
/// [`EXACT_CELL`] of the cell's radii, by 4 × 4 and 2 × 2 Gauss–Legendre within [`NEAR_CELL`]
/// and [`GAUSS_CELL`], by the kernel at its middle beyond. Against the exact integral of the
/// same density (tests/accuracy.rs, receivers on a face at the foot of a unit floor triangle,
/// heights 0.002 to 0.25) the form reads within 0.35% over a dark strip, a step at the
/// receivers' feet and a smoothly rising density, where the midpoint rule alone (cell by cell
/// near the peak, by blocks elsewhere) read up to 1.9%, 183% and 1.7% off (radiosity/
/// REFERENCES.md, "The kernel's mean by the density's cells").
fn balance_weights<const N: usize>(
    (p, n): (Vec3, Vec3),
    source: &Facing,
    nearest: Vec3,
    samples: &[Vec3],
    weights: &mut [[f32; N]],
    densities: &DensitySet<N>,
    config: &FormFactorConfig,
) {
    let uniform = densities.uniform;
    if uniform.iter().all(|&u| u) || samples.is_empty() {
        return;
    }
    let (src, area, ns) = (source.src, source.area, source.normal);
    let d_min2 = (nearest - p).length_squared();
    if weights.len() != samples.len()
        || d_min2 >= BALANCE_FIELD * BALANCE_FIELD * area
        || !is_analytic(area, samples.len(), d_min2, config)
    {
        return;
    }
    let (mut k_sum, mut kw_sum) = (0.0f32, [0.0f32; N]);
    for (&x, w) in samples.iter().zip(weights.iter()) {
        if let Some(k) = point_kernel(p, n, ns, x) {
            k_sum += k;
            (0..N).for_each(|j| kw_sum[j] += k * w[j]);
        }
    }
    if k_sum <= 0.0 {
        return;
    }
    // W, by the rules above.
    let (g, f) = (densities.g, densities.block);
    let blocks = g / f;
    let rows = Rows::new(p, n, ns, src);
    let mid = |i: u32, cells: u32| (i as f32 + 0.5) / cells as f32;
    let (cu, cv) = square_point(src, nearest);
    let cell = |x: f32| ((x * g as f32) as u32).min(g - 1);
    let d0 = densities.cells[(cell(cu) * g + cell(cv)) as usize];
    // a form factor in the unit of the rules (the kernel's integral over a cell's area)
    let unit = std::f32::consts::PI * (g * g) as f32 / area;
    // ∫ k over the source
    let whole = unit * point_polygon(p, n, &src.v);
    if whole <= 0.0 {
        return;
    }
    let [v0, v1, v2] = src.v;
    let (along, across) = (
        (v1 - v2).length(),
        (v2 - v0).length().max((v1 - v0).length()),
    );
    // a bound on the radius² of the cells in row `i` of a `cells × cells` grid: a row runs
    // along `v₁ − v₂`, `√u` of it, and rows stand `Δ√u` apart, at most `across` times that
    let radius2 = |i: u32, cells: u32| {
        let s = |i: u32| (i as f32 / cells as f32).sqrt();
        (0.5 * (along * s(i + 1) / cells as f32 + across * (s(i + 1) - s(i)))).powi(2)
    };
    // `rule` over cell (i, j) of a `cells × cells` grid, in the unit of the cell's area
    let gauss = |i: u32, j: u32, cells: u32, (nodes, weights): Rule| {
        let at = |i: u32, s: f32| (i as f32 + 0.5 + s) / cells as f32;
        (nodes.iter().zip(weights))
            .map(|(&su, &wu)| {
                let row = rows.at(at(i, su));
                let along = nodes.iter().zip(weights);
                wu * along
                    .map(|(&sv, &wv)| wv * row.kernel(at(j, sv)))
                    .sum::<f32>()
            })
            .sum::<f32>()
    };
    // the exact integral over cell (i, j), from its corners as [`Tri::sample`] warps them (the
    // warp keeps a cell's edges straight)
    let exact = |i: u32, j: u32| {
        let corner = |i: u32, j: u32| src.sample(i as f32 / g as f32, j as f32 / g as f32);
        let quad = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(a, b)| corner(i + a, j + b));
        unit * point_polygon(p, n, &quad)
    };
    // (each density takes the rules its own cells choose, so that a density in a set reads
    // what it reads alone, to the bit)
    let mut integral = [0.0f32; N];
    let mut add = |k: f32, d: [f32; N], taken: [bool; N]| {
        for c in 0..N {
            // (adding 0 where not taken leaves the sum as it is, to the bit)
            integral[c] += k * (d[c] - d0[c]) * if taken[c] { 1.0 } else { 0.0 };
        }
    };
    let block_area = (f * f) as f32;
    let squared = |radii: f32| radii * radii;
    let (near_block2, cell_block2) = (squared(NEAR_BLOCK), squared(CELL_BLOCK));
    let (exact2, near2, gauss2) = (squared(EXACT_CELL), squared(NEAR_CELL), squared(GAUSS_CELL));
    // The far blocks (most of them) four at a time, as `Σ k mean` per density and `Σ k`, in
    // the unit of a block's area; the near ones, as their lanes show them, one by one.
    let (mut far_km, mut far_k) = ([Vec4::ZERO; N], Vec4::ZERO);
    let lanes = densities.lanes;
    let steps = Vec4::new(0.5, 1.5, 2.5, 3.5);
    for bi in 0..blocks {
        let (row, r2) = (rows.at(mid(bi, blocks)), radius2(bi, blocks));
        let far2 = Vec4::splat(near_block2 * r2);
        // the block row's rows of cells, and their radii², once a block of it is taken so
        let mut cell_rows = None;
        for bj0 in (0..blocks).step_by(4) {
            let v = (Vec4::splat(bj0 as f32) + steps) / blocks as f32;
            let (k, d2) = row.kernels_and_distances2(v);
            let inside = Vec4::new(0.0, 1.0, 2.0, 3.0).cmplt(Vec4::splat((blocks - bj0) as f32));
            let is_far = d2.cmpge(far2) & inside;
            let k_far = Vec4::select(is_far, k, Vec4::ZERO);
            let at = (bi * lanes + bj0) as usize;
            for (km, means) in far_km.iter_mut().zip(&densities.block_lanes) {
                *km += k_far * Vec4::from_slice(&means[at..at + 4]);
            }
            far_k += k_far;
            let mut near = (!is_far & inside).bitmask();
            while near != 0 {
                let lane = near.trailing_zeros();
                near &= near - 1;
                let bj = bj0 + lane;
                let (b, d2) = ((bi * blocks + bj) as usize, d2[lane as usize]);
                let mean = densities.blocks[b];
                // the densities with nothing to add (one value throughout, the peak's), those to
                // take the block at once by (a block of one cell is taken as a cell), and by cell
                let flat = densities.flat[b];
                let done: [bool; N] = std::array::from_fn(|c| flat[c] && mean[c] == d0[c]);
                let whole_block = d2 >= cell_block2 * r2;
                let at_once =
                    std::array::from_fn(|c| !done[c] && (whole_block || (flat[c] && f > 1)));
                let by_cell: [bool; N] = std::array::from_fn(|c| !done[c] && !at_once[c]);
                if at_once.contains(&true) {
                    add(block_area * gauss(bi, bj, blocks, GAUSS_2), mean, at_once);
                }
                if !by_cell.contains(&true) {
                    continue;
                }
                let cell_rows = cell_rows.get_or_insert_with(|| {
                    std::array::from_fn::<_, { BLOCK as usize }, _>(|di| {
                        // (rows past `f` go unused; clamped, they stay in the grid)
                        let i = (bi * f + di as u32).min(g - 1);
                        (i, rows.at(mid(i, g)), radius2(i, g))
                    })
                });
                for &(i, ref row, r2) in &cell_rows[..f as usize] {
                    for j in bj * f..(bj + 1) * f {
                        let d = densities.cells[(i * g + j) as usize];
                        if d == d0 {
                            continue;
                        }
                        let v = mid(j, g);
                        let d2 = row.distance2(v);
                        let k = if d2 < exact2 * r2 {
                            exact(i, j)
                        } else if d2 < near2 * r2 {
                            gauss(i, j, g, GAUSS_4)
                        } else if d2 < gauss2 * r2 {
                            gauss(i, j, g, GAUSS_2)
                        } else {
                            row.kernel(v)
                        };
                        add(k, d, by_cell);
                    }
                }
            }
        }
    }
    for j in (0..N).filter(|&j| !uniform[j]) {
        let far = far_km[j].element_sum() - d0[j] * far_k.element_sum();
        let mean = (d0[j] + (integral[j] + block_area * far) / whole).max(0.0);
        if kw_sum[j] > 0.0 {
            let scale = mean * k_sum / kw_sum[j];
            weights.iter_mut().for_each(|w| w[j] *= scale);
        } else {
            weights.iter_mut().for_each(|w| w[j] = mean);
        }
    }
}

/// The point kernel `k = cos θ₁ cos θ₂ / r²` from a receiver over the square `(u, v)` that
/// [`Tri::sample`] warps onto a source, a row (`u` fixed) at a time: along a row the warped
/// point is `a + t b` with `t = v √u` and `b = v₁ − v₂`, so the cosines' numerators are linear
/// in `t` and `r²` quadratic: `k = (n·r)(−ns·r) / r⁴`.
struct Rows {
    p: Vec3,
    n: Vec3,
    ns: Vec3,
    v0: Vec3,
    v2: Vec3,
    b: Vec3,
    /// `n·b`, `ns·b`, `b·b`
    nb: f32,
    nsb: f32,
    bb: f32,
}

/// One row of [`Rows`]: `√u`, `n·a`, `ns·a`, `a·a`, `2 a·b`.
struct Row<'r> {
    rows: &'r Rows,
    su: f32,
    na: f32,
    nsa: f32,
    aa: f32,
    ab2: f32,
}

impl Rows {
    /// The kernel from the receiver `(p, n)` over `src` (of unit normal `ns`).
    fn new(p: Vec3, n: Vec3, ns: Vec3, src: &Tri) -> Rows {
        let [v0, v1, v2] = src.v;
        let b = v1 - v2;
        let (nb, nsb, bb) = (n.dot(b), ns.dot(b), b.dot(b));
        Rows {
            p,
            n,
            ns,
            v0,
            v2,
            b,
            nb,
            nsb,
            bb,
        }
    }

    /// The row at `u`.
    fn at(&self, u: f32) -> Row<'_> {
        let su = u.sqrt();
        let a = self.v0 * (1.0 - su) + self.v2 * su - self.p;
        Row {
            rows: self,
            su,
            na: self.n.dot(a),
            nsa: self.ns.dot(a),
            aa: a.dot(a),
            ab2: 2.0 * a.dot(self.b),
        }
    }
}

impl Row<'_> {
    /// The kernel at `v` (0 below the receiver's horizon or behind the source).
    #[inline]
    fn kernel(&self, v: f32) -> f32 {
        let r = self.rows;
        let t = v * self.su;
        let (c1, c2) = (self.na + t * r.nb, -(self.nsa + t * r.nsb));
        let len2 = self.distance2(v);
        if c1 > 0.0 && c2 > 0.0 {
            c1 * c2 / (len2 * len2).max(f32::MIN_POSITIVE)
        } else {
            0.0
        }
    }

    /// [`Row::kernel`] and [`Row::distance2`] at four `v` at once.
    #[inline]
    fn kernels_and_distances2(&self, v: Vec4) -> (Vec4, Vec4) {
        let r = self.rows;
        let t = v * self.su;
        let c1 = Vec4::splat(self.na) + t * r.nb;
        let c2 = -(Vec4::splat(self.nsa) + t * r.nsb);
        let len2 = Vec4::splat(self.aa) + t * (Vec4::splat(self.ab2) + t * r.bb);
        let k = c1 * c2 / (len2 * len2).max(Vec4::splat(f32::MIN_POSITIVE));
        let seen = c1.cmpgt(Vec4::ZERO) & c2.cmpgt(Vec4::ZERO);
        (Vec4::select(seen, k, Vec4::ZERO), len2)
    }

    /// The squared distance from the receiver to the point at `v`.
    #[inline]
    fn distance2(&self, v: f32) -> f32 {
        let t = v * self.su;
        self.aa + t * (self.ab2 + t * self.rows.bb)
    }
}

/// The point of the square `(u, v)` that [`Tri::sample`] warps onto `src` to the point `x` of
/// it (the warp's inverse: `√u = 1 − b₀`, `v = b₁ / √u` for `x`'s barycentric coordinates).
fn square_point(src: &Tri, x: Vec3) -> (f32, f32) {
    let [v0, v1, v2] = src.v;
    let (e1, e2, d) = (v1 - v0, v2 - v0, x - v0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det.is_nan() || det <= 0.0 {
        return (0.5, 0.5);
    }
    let b1 = ((d22 * d1 - d12 * d2) / det).clamp(0.0, 1.0);
    let b2 = ((d11 * d2 - d12 * d1) / det).clamp(0.0, 1.0);
    let su = (b1 + b2).clamp(0.0, 1.0);
    let v = if su > 0.0 { b1 / su } else { 0.5 };
    (su * su, v.clamp(0.0, 1.0))
}

/// Whether a shot's channels must be shot each with its own density: whether any of the
/// `channels` ([`SourceDensity::of_parts_sets`] of the source's elements' unshot radiosity per
/// channel) departs from `sum` (that of the channels summed) by more than [`CHANNEL_SPREAD`]
/// in some cell, or is uniform where it is not (or the reverse). Where the light a patch
/// received is of one colour all over it, the channels' densities are the sum's and one form
/// factor serves them all; where it is not (a floor strip lit mostly by a red wall, beside a
/// floor lit by the white light), each channel shoots from where its own power is (issue 10:
/// the channels' mixture of the dim block faces was off by up to 3%).
pub fn channels_differ(sum: Option<&SourceDensity>, channels: &[Option<SourceDensity>]) -> bool {
    channels.iter().any(|c| match (sum, c) {
        (None, None) => false,
        (Some(s), Some(c)) => {
            (s.cells.iter().zip(&c.cells)).any(|(a, b)| (a - b).abs() > CHANNEL_SPREAD)
        }
        _ => true,
    })
}

/// How far (in units of the mean density) a channel's density may depart from the channels'
/// sum's before the channels shoot apart ([`channels_differ`]): a departure this small moves
/// a channel's form factor by at most this fraction of the source's unweighted one.
pub const CHANNEL_SPREAD: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;

    fn square(h: f32, x0: f32, x1: f32, z0: f32, z1: f32) -> [Tri; 2] {
        // Unit-ish square at height h facing down (-y).
        let a = Vec3::new(x0, h, z0);
        let b = Vec3::new(x1, h, z0);
        let c = Vec3::new(x1, h, z1);
        let d = Vec3::new(x0, h, z1);
        [Tri::new(a, b, c), Tri::new(a, c, d)]
    }

    #[test]
    fn angle_is_the_library_atan2() {
        let mut rng = Pcg32::new(7, 1);
        let mut worst = 0.0f64;
        let mut check = |sin: f64, cos: f64| {
            let (got, want) = (angle(sin, cos), sin.atan2(cos));
            worst = worst.max((got - want).abs() / want.max(f64::MIN_POSITIVE));
        };
        // the reduction's boundaries, the axes, and vectors of every direction and scale
        for (sin, cos) in [
            (1.0, 0.0),
            (1.0, -0.0),
            (1e-300, 1.0),
            (1e-300, -1.0),
            (1.0, 1e300),
        ] {
            check(sin, cos);
        }
        for t in [0.66f64, 2.414_213_562_373_095, 1.0] {
            for cos in [1.0, -1.0] {
                for ulps in -2..=2 {
                    check(f64::from_bits(t.to_bits().wrapping_add_signed(ulps)), cos);
                }
            }
        }
        for _ in 0..200_000 {
            let theta = rng.next_f32() as f64 * std::f64::consts::PI;
            let scale = 10f64.powi((rng.next_f32() * 12.0) as i32 - 6);
            check(theta.sin().abs() * scale, theta.cos() * scale);
        }
        assert!(worst < 4.0 * f64::EPSILON, "worst relative error {worst:e}");
    }

    #[test]
    fn contour_formula_matches_the_closed_forms() {
        // Point 1.0 under the centre of a unit square: 0.239456; under a corner: 0.138532.
        let centre = point_polygon(
            Vec3::ZERO,
            Vec3::Y,
            &[
                Vec3::new(-0.5, 1.0, -0.5),
                Vec3::new(0.5, 1.0, -0.5),
                Vec3::new(0.5, 1.0, 0.5),
                Vec3::new(-0.5, 1.0, 0.5),
            ],
        );
        assert!((centre - 0.239456).abs() < 1e-5, "{centre}");
        let [t0, t1] = square(1.0, 0.0, 1.0, 0.0, 1.0);
        let corner =
            point_polygon(Vec3::ZERO, Vec3::Y, &t0.v) + point_polygon(Vec3::ZERO, Vec3::Y, &t1.v);
        assert!((corner - 0.138532).abs() < 1e-5, "{corner}");
    }

    #[test]
    fn source_facing_away_gives_zero() {
        let [t0, _] = square(1.0, 0.0, 1.0, 0.0, 1.0);
        let flipped = Tri::new(t0.v[0], t0.v[2], t0.v[1]); // faces +y, receiver is below
        let mut rng = Pcg32::new(1, 1);
        let mut s = Vec::new();
        source_samples(&flipped, 16, &mut rng, &mut s);
        let f = form_factor(
            None,
            Vec3::ZERO,
            Vec3::Y,
            &flipped,
            &s,
            &FormFactorConfig::default(),
        );
        assert_eq!(f.value, 0.0);
    }

    /// `tri` split `levels` times into four by its edges' midpoints, each part with a value.
    fn split_parts(tri: &Tri, levels: u32) -> Vec<(Tri, f32)> {
        // Values that differ from part to part (and repeat rarely).
        tri.split(levels)
            .into_iter()
            .enumerate()
            .map(|(k, t)| (t, 1.0 + ((k * 7919) % 101) as f32))
            .collect()
    }

    /// The contract of `of_parts`, by searching every part at every cell.
    fn density_by_search(src: &Tri, g: u32, parts: &[(Tri, f32)]) -> Option<SourceDensity> {
        SourceDensity::new(src, g, |x| {
            let first = parts.iter().position(|(t, _)| t.contains(x));
            let k = first.unwrap_or_else(|| {
                parts
                    .iter()
                    .map(|(t, _)| (t.closest_point(x) - x).length_squared())
                    .enumerate()
                    .fold((0, f32::MAX), |b, c| if c.1 < b.1 { c } else { b })
                    .0
            });
            parts[k].1
        })
    }

    #[test]
    fn a_patch_density_takes_the_part_holding_each_cell_centre() {
        let src = Tri::new(
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(2.3, 0.2, 0.1),
            Vec3::new(0.7, 1.9, -0.4),
        );
        for levels in 1..=4 {
            let parts = split_parts(&src, levels);
            let found = SourceDensity::of_parts(&src, 24, &parts).expect("not uniform");
            assert_eq!(
                Some(found),
                density_by_search(&src, 24, &parts),
                "{levels} levels"
            );
        }
        // Parts in another order, and a hole: centres in it take the nearest part.
        let mut parts = split_parts(&src, 3);
        parts.reverse();
        parts.remove(17);
        let found = SourceDensity::of_parts(&src, 24, &parts).expect("not uniform");
        assert_eq!(Some(found), density_by_search(&src, 24, &parts));
        // A degenerate patch: no part contains anything, every centre takes the nearest.
        let flat = Tri::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        let parts = split_parts(&flat, 2);
        assert_eq!(
            SourceDensity::of_parts(&flat, 8, &parts),
            density_by_search(&flat, 8, &parts)
        );
    }
}
