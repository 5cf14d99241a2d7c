//! The radiosity kernels as native intrinsics that occam programs call (issue 4): `extern "C"`
//! wrappers over plain-data kernels, listed in [`INTRINSICS`] in the ABI of
//! `occ_runtime::intrinsic` (arrays by address and length, written scalars by address).
//!
//! The occam declarations are in `stdlib/radiosity.inc` (`#INCLUDE "radiosity.inc"`), one
//! `#PRAGMA EXTERNAL` each; the code generator checks them against this table when it binds a
//! call. Every wrapper runs on the data the calling node holds and nothing else: no octree, no
//! scene, no global state, so a node can run them on its own share of the patches. A form factor
//! with occlusion takes three steps, so that the shadow rays can be answered by whichever node
//! holds the geometry: `RAD.SOURCE.SAMPLES`, then `RAD.SHADOW.RAYS` (the rays to answer), then
//! `RAD.FORM.FACTOR` with the answers.
//!
//! Contract on bad input: an intrinsic cannot halt the node, so none of them panics. A wrong
//! array length makes a form-factor kernel answer `-1.0` (a form factor is never negative) and
//! the sample and ray kernels answer a count of `-1`, writing nothing to their output arrays. Lengths are
//! checked before anything is read. Points, normals and triangles are flat `[]REAL32` arrays:
//! `x, y, z` per point, three points per triangle.

use glam::Vec3;
use occ_runtime::abi::Word;
use occ_runtime::intrinsic::{Intrinsic, ParamKind::*};

use crate::formfactor::{FormFactorConfig, faces, form_factor_with, point_polygon};
use crate::geom::Tri;
use crate::octree::VOXEL_TRI_FLOATS;
use crate::packet::{LANES, RayQuery, TriPacket};

/// Most rays `RAD.SOURCE.SAMPLES` accepts.
pub const MAX_SAMPLES: Word = 1 << 16;

/// Stream of the sample generator (the solver's kernels use the same).
pub(crate) const SAMPLE_STREAM: u64 = 0x5eed;

/// The radiosity intrinsics, for the driver's `IntrinsicSet`.
pub static INTRINSICS: &[Intrinsic] = &[
    Intrinsic {
        name: "RAD.POINT.POLYGON.FF",
        params: &[ValReal32s, ValReal32s, ValReal32s, ResultReal32],
        result: None,
        addr: point_polygon_ff as *const u8,
    },
    Intrinsic {
        name: "RAD.SOURCE.SAMPLES",
        params: &[ValReal32s, ValInt, ValInt, VarReal32s, ResultInt],
        result: None,
        addr: source_samples_into as *const u8,
    },
    Intrinsic {
        name: "RAD.SOURCE.SAMPLES.AT",
        params: &[ValReal32s, ValInt, ValInt, ValInt, VarReal32s, ResultInt],
        result: None,
        addr: source_samples_at as *const u8,
    },
    Intrinsic {
        name: "RAD.FORM.FACTOR",
        params: &[
            ValReal32s,
            ValReal32s,
            ValReal32s,
            ValReal32s,
            ValBools,
            ResultReal32,
        ],
        result: None,
        addr: form_factor_visible as *const u8,
    },
    Intrinsic {
        name: "RAD.SHADOW.RAYS",
        params: &[
            ValReal32s, ValReal32s, ValReal32s, ValReal32s, VarReal32s, ResultInt,
        ],
        result: None,
        addr: shadow_rays as *const u8,
    },
    Intrinsic {
        name: "RAD.SHADOW.RAYS.LIFTED",
        params: &[
            ValReal32s, ValReal32s, ValReal32s, ValReal32s, ValReal32, VarReal32s, ResultInt,
        ],
        result: None,
        addr: shadow_rays_lifted as *const u8,
    },
    Intrinsic {
        name: "RAD.SHOOT.BATCH",
        params: &[
            ValReal32s, ValReal32s, ValReal32s, ValReal32s, ValBools, VarReal32s, ResultInt,
        ],
        result: None,
        addr: shoot_batch as *const u8,
    },
    Intrinsic {
        name: "RAD.SHADOW.RAYS.BATCH",
        params: &[
            ValReal32s, ValReal32s, ValReal32s, ValReal32s, VarReal32s, ResultInt,
        ],
        result: None,
        addr: shadow_rays_batch as *const u8,
    },
    Intrinsic {
        name: "RAD.SOURCE.DENSITY",
        params: &[ValReal32s, ValReal32s, ValReal32s, VarReal32s, ResultInt],
        result: None,
        addr: weighted::source_density as *const u8,
    },
    Intrinsic {
        name: "RAD.SOURCE.DENSITIES",
        params: &[ValReal32s, ValReal32s, ValReal32s, VarReal32s, VarInts],
        result: None,
        addr: weighted::source_densities as *const u8,
    },
    Intrinsic {
        name: "RAD.SOURCE.SAMPLES.WEIGHTED.AT",
        params: &[
            ValReal32s, ValInt, ValInt, ValInt, ValReal32s, VarReal32s, VarReal32s, ResultInt,
        ],
        result: None,
        addr: weighted::source_samples_weighted_at as *const u8,
    },
    Intrinsic {
        name: "RAD.SHOT.RAYS",
        params: &[ValInt, ValReal64, ValReal64, ResultInt],
        result: None,
        addr: weighted::shot_rays as *const u8,
    },
    Intrinsic {
        name: "RAD.RECEIVER.SAMPLES",
        params: &[
            ValReal32s, ValReal32s, ValReal32s, ValInt, ValInt, ValInt, ValInt, ValReal32s,
            VarReal32s, VarReal32s, ResultInt,
        ],
        result: None,
        addr: weighted::receiver_samples_at as *const u8,
    },
    Intrinsic {
        name: "RAD.FORM.FACTOR.WEIGHTED",
        params: &[
            ValReal32s,
            ValReal32s,
            ValReal32s,
            ValReal32s,
            ValReal32s,
            ValBools,
            ResultReal32,
        ],
        result: None,
        addr: weighted::form_factor_weighted_visible as *const u8,
    },
    Intrinsic {
        name: "RAD.VOXEL.OCCLUDED",
        params: &[ValReal32s, ValReal32s, VarBools, ResultInt],
        result: None,
        addr: voxel_occluded as *const u8,
    },
    Intrinsic {
        name: "RAD.RAYS.WALK",
        params: &[
            ValInts, ValReal32s, ValInts, ValReal32s, ValReal32s, VarBools, VarInts, VarInts,
            ResultInt,
        ],
        result: None,
        addr: walk::rays_walk as *const u8,
    },
    Intrinsic {
        name: "RAD.VOXEL.ASSEMBLE",
        params: &[ValReal32s, ValReal32s, VarReal32s, ResultInt],
        result: None,
        addr: assemble::voxel_assemble as *const u8,
    },
    Intrinsic {
        name: "RAD.RAYS.WALK.STAMPED",
        params: &[
            ValInts, ValReal32s, ValInts, ValReal32s, ValReal32s, VarBools, VarInts, VarInts,
            VarInts, ValInt, ResultInt,
        ],
        result: None,
        addr: walk::rays_walk_stamped as *const u8,
    },
    Intrinsic {
        name: "RAD.VOXEL.OF.POINT",
        params: &[ValInts, ValReal32s, ValReal32s, ResultInt],
        result: None,
        addr: walk::voxel_of_point as *const u8,
    },
    Intrinsic {
        name: "RAD.ERROR.REACHED",
        params: &[ValReal64s, ValReal64s, ValReal64, ResultInt],
        result: None,
        addr: estimate::error_reached as *const u8,
    },
    Intrinsic {
        name: "RAD.OVERSHOOT.AMBIENT",
        params: &[ValReal64s, ValInt, VarReal64s, ResultInt],
        result: None,
        addr: estimate::overshoot_ambient as *const u8,
    },
    Intrinsic {
        name: "RAD.RECEIVERS.RAYS",
        params: &[
            ValReal32s, ValInts, ValReal32s, ValInt, ValInt, ValInt, ValReal32s, ValReal32,
            VarInts, VarReal32s, VarReal32s, VarReal32s, VarBools, VarInts, ResultInt, ResultInt,
        ],
        result: None,
        addr: batch::receivers_rays as *const u8,
    },
    Intrinsic {
        name: "RAD.RECEIVERS.FORM.FACTORS",
        params: &[
            ValReal32s, ValReal32s, ValInts, ValReal32s, ValReal32s, ValBools, VarReal32s,
            ResultInt,
        ],
        result: None,
        addr: batch::receivers_form_factors as *const u8,
    },
    Intrinsic {
        name: "RAD.RECEIVERS.FORM.FACTORS.SETS",
        params: &[
            ValReal32s, ValReal32s, ValInts, ValReal32s, ValReal32s, ValInts, ValBools, VarReal32s,
            ResultInt,
        ],
        result: None,
        addr: batch::receivers_form_factors_sets as *const u8,
    },
    Intrinsic {
        name: "RAD.POINTS.RECEIVE",
        params: &[ValReal32s, ValReal32s, VarReal32s, ResultInt],
        result: None,
        addr: batch::points_receive as *const u8,
    },
    Intrinsic {
        name: "RAD.POINTS.RECEIVE.GATHERED",
        params: &[ValReal32s, ValReal32s, VarReal32s, VarReal64s, ResultInt],
        result: None,
        addr: batch::points_receive_gathered as *const u8,
    },
    Intrinsic {
        name: "RAD.CORNERS.RECEIVE",
        params: &[
            ValInts, ValInts, ValReal64s, ValReal32s, ValReal32s, ValReal32s, VarReal64s,
            VarReal64s, ResultInt,
        ],
        result: None,
        addr: batch::corners_receive as *const u8,
    },
    Intrinsic {
        name: "RAD.CORNERS.RECEIVE.SETS",
        params: &[
            ValInts, ValInts, ValReal64s, ValReal32s, ValReal32s, ValReal32s, VarReal64s,
            VarReal64s, ResultInt,
        ],
        result: None,
        addr: batch::corners_receive_sets as *const u8,
    },
    Intrinsic {
        name: "RAD.CORNERS.GATHER",
        params: &[
            ValInt, ValInts, ValInts, ValInts, ValReal64s, ValReal32s, ValReal64s, VarReal64s,
            VarReal64s, ValReal64, VarReal64s, ResultInt,
        ],
        result: None,
        addr: gather::corners_gather as *const u8,
    },
    Intrinsic {
        name: "RAD.PATCHES.TAKE",
        params: &[ValInts, VarReal64s, VarInts, VarReal64s, ResultInt],
        result: None,
        addr: batch::patches_take as *const u8,
    },
    Intrinsic {
        name: "RAD.REFINE.EDGES",
        params: &[
            ValInts, ValReal32s, ValReal32s, ValReal32s, ValReal32s, VarInts, VarReal32s, ResultInt,
        ],
        result: None,
        addr: refine::refine_edges as *const u8,
    },
    Intrinsic {
        name: "RAD.REFINE.SPLIT",
        params: &[
            ValInts, VarInts, ValInt, ValReal32s, VarInts, VarReal64s, ResultInt, ResultInt,
        ],
        result: None,
        addr: refine::refine_split as *const u8,
    },
    Intrinsic {
        name: "RAD.ELEMENTS.AROUND",
        params: &[ValInts, VarInts, VarInts, ResultInt],
        result: None,
        addr: weights::elements_around_of as *const u8,
    },
    Intrinsic {
        name: "RAD.ELEMENT.WEIGHTS",
        params: &[
            ValInts, ValReal32s, ValInts, ValInts, ValInts, VarInts, VarInts, VarReal64s, ResultInt,
        ],
        result: None,
        addr: weights::element_weights_of as *const u8,
    },
    Intrinsic {
        name: "RAD.POINTS.ORDER",
        params: &[ValReal32s, VarInts, ResultInt],
        result: None,
        addr: order::points_order as *const u8,
    },
    Intrinsic {
        name: "RAD.CORNERS.ROW",
        params: &[ValInts, ValReal64s, ValReal32s, VarReal64s, ResultInt],
        result: None,
        addr: batch::corners_row as *const u8,
    },
];

/// Floats per ray written by `RAD.SHADOW.RAYS`: origin (3), direction (3), tmin, tmax (the
/// layout of [`crate::kernels::Ray`]).
pub const RAY_FLOATS: usize = 8;

/// Views an occam array passed by address and length (empty when the length is not positive
/// or the address is null).
///
/// # Safety
/// When `n > 0` and `p` is not null, `p` is valid for `n` elements for `'a`.
unsafe fn array<'a, T>(p: *const T, n: Word) -> &'a [T] {
    if n <= 0 || p.is_null() {
        return &[];
    }
    // SAFETY: caller contract.
    unsafe { std::slice::from_raw_parts(p, n as usize) }
}

/// Views a written occam array passed by address and length (empty when the length is not
/// positive or the address is null).
///
/// # Safety
/// When `n > 0` and `p` is not null, `p` is valid for writing `n` elements for `'a`, and no
/// other view of them is alive.
unsafe fn array_mut<'a, T>(p: *mut T, n: Word) -> &'a mut [T] {
    if n <= 0 || p.is_null() {
        return &mut [];
    }
    // SAFETY: caller contract.
    unsafe { std::slice::from_raw_parts_mut(p, n as usize) }
}

/// Reads the points of a flat `x, y, z` array (`None` unless its length is a multiple of 3).
fn points(xs: &[f32]) -> Option<Vec<Vec3>> {
    xs.len()
        .is_multiple_of(3)
        .then(|| xs.chunks_exact(3).map(Vec3::from_slice).collect())
}

/// Reads exactly one point.
fn point(xs: &[f32]) -> Option<Vec3> {
    (xs.len() == 3).then(|| Vec3::from_slice(xs))
}

/// Reads exactly one triangle.
fn triangle(xs: &[f32]) -> Option<Tri> {
    match points(xs)?.as_slice() {
        [a, b, c] => Some(Tri::new(*a, *b, *c)),
        _ => None,
    }
}

/// `PROC RAD.POINT.POLYGON.FF (VAL []REAL32 p, n, VAL []REAL32 poly, RESULT REAL32 f)`: the
/// exact form factor from a differential area at `p` with unit normal `n` to the convex planar
/// polygon `poly` (3k floats, k ≥ 3), without occlusion, the part below the receiver's horizon
/// clipped away ([`point_polygon`]). `f` is -1.0 when `p` or `n` is not 3 floats or `poly` not
/// 3k floats with k ≥ 3.
///
/// # Safety
/// The arrays are valid for their lengths and `f` for one REAL32 (the occam ABI).
pub unsafe extern "C" fn point_polygon_ff(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    poly: *const f32,
    poly_len: Word,
    f: *mut f32,
) {
    // SAFETY: the ABI passes valid arrays.
    let (p, n, poly) = unsafe { (array(p, p_len), array(n, n_len), array(poly, poly_len)) };
    let value = match (point(p), point(n), points(poly)) {
        (Some(p), Some(n), Some(poly)) if poly.len() >= 3 => point_polygon(p, n, &poly),
        _ => -1.0,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *f = value };
}

/// `PROC RAD.SOURCE.SAMPLES (VAL []REAL32 tri, VAL INT m, VAL INT seed, []REAL32 out,
/// RESULT INT count)`: the stratified sample points of the source triangle `tri` (9 floats) for
/// `m` rays, as the solver takes them ([`crate::formfactor::source_samples`]: a jittered k × k grid, k = ⌈√m⌉,
/// warped onto the triangle, from the generator seeded with `seed`). Writes `count` = k² points
/// (3k² floats) to the start of `out`; `count` is -1 and `out` untouched when `tri` is not 9
/// floats, `m` is not in 1..=65536, or `out` is shorter than 3k² floats.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn source_samples_into(
    tri: *const f32,
    tri_len: Word,
    m: Word,
    seed: Word,
    out: *mut f32,
    out_len: Word,
    count: *mut Word,
) {
    // SAFETY: the caller's contract is this one's.
    unsafe { source_samples_at(tri, tri_len, m, seed, 0, out, out_len, count) }
}

/// Most sets `RAD.SOURCE.SAMPLES.AT` skips.
pub const MAX_SKIPPED_SETS: Word = 1 << 16;

/// `PROC RAD.SOURCE.SAMPLES.AT (VAL []REAL32 tri, VAL INT m, VAL INT seed, VAL INT set,
/// []REAL32 out, RESULT INT count)`: `RAD.SOURCE.SAMPLES` for the `set`-th set of samples the
/// generator seeded with `seed` draws (set 0 is `RAD.SOURCE.SAMPLES`'s). The Rust solver draws
/// one set per receiver from one generator per batch of receivers, so a node that holds a
/// receiver without its batch-mates takes its samples with this. `count` is -1 (and `out`
/// untouched) as for `RAD.SOURCE.SAMPLES`, and when `set` is not in 0..=65536.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn source_samples_at(
    tri: *const f32,
    tri_len: Word,
    m: Word,
    seed: Word,
    set: Word,
    out: *mut f32,
    out_len: Word,
    count: *mut Word,
) {
    // The weighted sampler with a uniform source (no grid) draws the same points and no weights.
    // SAFETY: the caller's contract is this one's; the empty arrays are never read or written.
    unsafe {
        weighted::source_samples_weighted_at(
            tri,
            tri_len,
            m,
            seed,
            set,
            std::ptr::null(),
            0,
            out,
            out_len,
            std::ptr::null_mut(),
            0,
            count,
        )
    }
}

/// `PROC RAD.FORM.FACTOR (VAL []REAL32 point, normal, VAL []REAL32 tri, VAL []REAL32 samples,
/// VAL []BOOL visible, RESULT REAL32 f)`: the form factor from the differential receiver
/// (`point`, unit `normal`) to the source triangle `tri`, given the source samples (3m floats,
/// from `RAD.SOURCE.SAMPLES`) and which of their shadow rays got through (`visible`, m flags):
/// Wallace's disc estimate, or the analytic point-to-polygon value times the visible fraction
/// near the source, exactly as the Rust solver's `form_factor` (one implementation:
/// [`form_factor_with`], default [`FormFactorConfig`]). `f` is -1.0 when `point`, `normal` or
/// `tri` has the wrong length, `samples` is not 3m floats with m ≥ 1, or `visible` is not m
/// flags.
///
/// # Safety
/// The arrays are valid for their lengths and `f` for one REAL32 (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn form_factor_visible(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    visible: *const u8,
    visible_len: Word,
    f: *mut f32,
) {
    // SAFETY: the ABI passes valid arrays.
    let (p, n, tri, samples, visible) = unsafe {
        (
            point(array(p, p_len)),
            point(array(n, n_len)),
            triangle(array(tri, tri_len)),
            points(array(samples, samples_len)),
            array(visible, visible_len),
        )
    };
    let value = match (p, n, tri, samples) {
        (Some(p), Some(n), Some(tri), Some(s)) if !s.is_empty() && s.len() == visible.len() => {
            visible_form_factor(p, n, &tri, &s, visible)
        }
        _ => -1.0,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *f = value };
}

/// `PROC RAD.SHADOW.RAYS (VAL []REAL32 point, normal, VAL []REAL32 tri, VAL []REAL32 samples,
/// []REAL32 rays, RESULT INT count)`: the shadow rays `RAD.FORM.FACTOR` needs answered for the
/// receiver (`point`, unit `normal`), the source triangle `tri` and its samples (3m floats): for
/// sample k, floats `8k .. 8k+7` of `rays` get origin (3), direction (3), tmin, tmax, the ray the
/// Rust solver would cast (one implementation: [`form_factor_with`] asks for exactly these). A
/// sample that needs no ray (below the receiver's horizon, or the receiver behind the source)
/// gets an empty ray (direction 0, tmin = tmax = 0), whose flag `RAD.FORM.FACTOR` ignores.
/// `count` is the number of rays to cast, or -1 (and `rays` untouched) when `point`, `normal`
/// or `tri` has the wrong length, `samples` is not 3m floats with m >= 1, or `rays` is shorter
/// than 8m floats.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn shadow_rays(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    rays: *mut f32,
    rays_len: Word,
    count: *mut Word,
) {
    let offset = FormFactorConfig::default().offset;
    // SAFETY: the caller's contract is this one's.
    unsafe {
        shadow_rays_lifted(
            p,
            p_len,
            n,
            n_len,
            tri,
            tri_len,
            samples,
            samples_len,
            offset,
            rays,
            rays_len,
            count,
        )
    }
}

/// `PROC RAD.SHADOW.RAYS.LIFTED (VAL []REAL32 point, normal, VAL []REAL32 tri,
/// VAL []REAL32 samples, VAL REAL32 offset, []REAL32 rays, RESULT INT count)`:
/// `RAD.SHADOW.RAYS` with the ray origins lifted by `offset` along the normal, and the rays
/// stopping that far short of the source, instead of the default 1e-3 (the Rust solver takes
/// a millionth of the scene's diagonal). `count` is -1 as for `RAD.SHADOW.RAYS`, and when
/// `offset` is negative or not finite.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn shadow_rays_lifted(
    p: *const f32,
    p_len: Word,
    n: *const f32,
    n_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    offset: f32,
    rays: *mut f32,
    rays_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (p, n, tri, samples) = unsafe {
        (
            point(array(p, p_len)),
            point(array(n, n_len)),
            triangle(array(tri, tri_len)),
            points(array(samples, samples_len)),
        )
    };
    let written = match (p, n, tri, samples) {
        (Some(p), Some(n), Some(tri), Some(s))
            if !s.is_empty()
                && (RAY_FLOATS * s.len()) as Word <= rays_len
                && offset.is_finite()
                && offset >= 0.0 =>
        {
            // SAFETY: `rays` is valid for `rays_len` >= 8m floats.
            let out = unsafe { std::slice::from_raw_parts_mut(rays, RAY_FLOATS * s.len()) };
            let config = FormFactorConfig {
                offset,
                ..FormFactorConfig::default()
            };
            receiver_rays(p, n, &tri, &s, &config, out)
        }
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// One receiver's form factor given the visibility flag of each sample's ray
/// (`visible.len() == samples.len()`).
fn visible_form_factor(p: Vec3, n: Vec3, tri: &Tri, samples: &[Vec3], visible: &[u8]) -> f32 {
    let config = FormFactorConfig::default();
    form_factor_with(p, n, tri, samples, &config, |k, _, _, _| visible[k] == 0).value
}

/// Writes one receiver's shadow rays into `out` (`RAY_FLOATS` per sample, empty rays where none
/// is cast) and returns how many are cast: none when the receiver does not face the source
/// ([`faces`]), else [`facing_receiver_rays`].
fn receiver_rays(
    p: Vec3,
    n: Vec3,
    tri: &Tri,
    samples: &[Vec3],
    config: &FormFactorConfig,
    out: &mut [f32],
) -> Word {
    if faces(p, n, tri) {
        facing_receiver_rays(p, n, tri.normal(), samples, config, out)
    } else {
        empty_rays(samples, out);
        0
    }
}

/// [`receiver_rays`] for a receiver known to face the source (one that
/// [`crate::formfactor::receiver_samples`] drew samples for), whose normal is `ns`: the rays
/// that [`form_factor_with`] asks about, written without computing the form factor. A sample
/// gets a ray when it lies above the receiver's horizon and in front of the source, tested as
/// the kernel tests it (`test::rays_are_the_ones_the_form_factor_asks_about` holds the two to
/// the same rays, bit for bit).
fn facing_receiver_rays(
    p: Vec3,
    n: Vec3,
    ns: Vec3,
    samples: &[Vec3],
    config: &FormFactorConfig,
    out: &mut [f32],
) -> Word {
    let origin = p + n * config.offset;
    let mut cast = 0;
    for (&x, ray) in samples.iter().zip(out.chunks_exact_mut(RAY_FLOATS)) {
        let r = x - p;
        let len = r.length_squared().sqrt();
        let (cos1, cos2) = (n.dot(r) / len, -ns.dot(r) / len);
        if cos1 <= 0.0 || cos2 <= 0.0 {
            empty_rays(&[x], ray);
            continue;
        }
        let d = x + ns * config.offset - origin;
        let [ox, oy, oz] = origin.to_array();
        let [dx, dy, dz] = d.to_array();
        ray.copy_from_slice(&[ox, oy, oz, dx, dy, dz, 0.0, 1.0]);
        cast += 1;
    }
    cast
}

/// Empty rays, one a sample (`RAY_FLOATS` floats: the sample, then zeros), as far as `out` goes.
fn empty_rays(samples: &[Vec3], out: &mut [f32]) {
    for (ray, x) in out.chunks_exact_mut(RAY_FLOATS).zip(samples) {
        let [x, y, z] = x.to_array();
        ray.copy_from_slice(&[x, y, z, 0.0, 0.0, 0.0, 0.0, 0.0]);
    }
}

/// The receivers of a batch: `r` points and `r` normals (3r floats each, r ≥ 1).
fn receivers(points_: &[f32], normals: &[f32]) -> Option<Vec<(Vec3, Vec3)>> {
    let (p, n) = (points(points_)?, points(normals)?);
    (!p.is_empty() && p.len() == n.len()).then(|| p.into_iter().zip(n).collect())
}

/// `PROC RAD.SHOOT.BATCH (VAL []REAL32 points, normals, VAL []REAL32 tri,
/// VAL []REAL32 samples, VAL []BOOL visible, []REAL32 f, RESULT INT count)`: `RAD.FORM.FACTOR`
/// for r receivers at once (`points`, `normals`: 3r floats), all seeing the source `tri` through
/// the same m samples (3m floats); receiver i's flags are `visible[i*m .. i*m + m - 1]` (r·m in
/// all), its form factor goes to `f[i]`. `count` is r, or -1 (and `f` untouched) when a length
/// is wrong (`points` and `normals` not both 3r floats with r ≥ 1, `tri` not 9, `samples` not 3m
/// with m ≥ 1, `visible` not r·m, `f` shorter than r). Unlike the Rust solver's
/// `kernels::shoot_batch`, which draws fresh samples per receiver, the batch shares one set.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn shoot_batch(
    points_: *const f32,
    points_len: Word,
    normals: *const f32,
    normals_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    visible: *const u8,
    visible_len: Word,
    f: *mut f32,
    f_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (rs, tri, samples, visible) = unsafe {
        (
            receivers(array(points_, points_len), array(normals, normals_len)),
            triangle(array(tri, tri_len)),
            points(array(samples, samples_len)),
            array(visible, visible_len),
        )
    };
    let written = match (rs, tri, samples) {
        (Some(rs), Some(tri), Some(s))
            if !s.is_empty()
                && visible.len() == rs.len() * s.len()
                && f_len >= rs.len() as Word =>
        {
            // SAFETY: `f` is valid for `f_len` >= r floats.
            let f = unsafe { std::slice::from_raw_parts_mut(f, rs.len()) };
            let flags = visible.chunks_exact(s.len());
            for ((&(p, n), v), o) in rs.iter().zip(flags).zip(f.iter_mut()) {
                *o = visible_form_factor(p, n, &tri, &s, v);
            }
            rs.len() as Word
        }
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.SHADOW.RAYS.BATCH (VAL []REAL32 points, normals, VAL []REAL32 tri,
/// VAL []REAL32 samples, []REAL32 rays, RESULT INT count)`: `RAD.SHADOW.RAYS` for r receivers
/// (`points`, `normals`: 3r floats) and one set of m samples: receiver i's rays are
/// `rays[8m*i .. 8m*i + 8m - 1]` (8·r·m floats in all), in the order `RAD.SHOOT.BATCH` reads
/// their flags. `count` is the number of rays cast in all, or -1 (and `rays` untouched) when a
/// length is wrong or `rays` is shorter than 8·r·m floats.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn shadow_rays_batch(
    points_: *const f32,
    points_len: Word,
    normals: *const f32,
    normals_len: Word,
    tri: *const f32,
    tri_len: Word,
    samples: *const f32,
    samples_len: Word,
    rays: *mut f32,
    rays_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (rs, tri, samples) = unsafe {
        (
            receivers(array(points_, points_len), array(normals, normals_len)),
            triangle(array(tri, tri_len)),
            points(array(samples, samples_len)),
        )
    };
    let written = match (rs, tri, samples) {
        (Some(rs), Some(tri), Some(s))
            if !s.is_empty()
                && ((RAY_FLOATS * s.len()) as Word).saturating_mul(rs.len() as Word)
                    <= rays_len =>
        {
            let per = RAY_FLOATS * s.len();
            // SAFETY: `rays` is valid for `rays_len` >= 8·r·m floats.
            let out = unsafe { std::slice::from_raw_parts_mut(rays, per * rs.len()) };
            let each = rs.iter().zip(out.chunks_exact_mut(per));
            let config = FormFactorConfig::default();
            each.map(|(&(p, n), o)| receiver_rays(p, n, &tri, &s, &config, o))
                .sum()
        }
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

mod assemble;
mod batch;
pub mod estimate;
mod gather;
mod order;
mod refine;
#[cfg(test)]
mod test;
pub mod weighted;
pub mod weights;

mod walk;

/// `RAD.VOXEL.OCCLUDED (VAL []REAL32 voxel, VAL []REAL32 rays, []BOOL blocked, RESULT INT
/// count)`: the rays (8 floats each, as `RAD.SHADOW.RAYS` writes them) that the triangles of one
/// voxel block (9 floats each, as [`Octree::voxel_floats`](crate::octree::Octree::voxel_floats)
/// gives them). `blocked[k]` becomes TRUE when ray `k` meets a triangle and is left alone
/// otherwise, so the answers of the voxels a ray crosses accumulate; `count` is the number of
/// rays newly blocked, or -1 (nothing written) when `voxel` is not a multiple of 9 floats,
/// `rays` not a multiple of 8, or `blocked` shorter than the number of rays. The triangle test
/// is the octree's packet test, but not clipped to the voxel: a voxel may report a hit that lies
/// in a neighbouring voxel. So the verdict accumulated over all the voxels a ray crosses is the
/// octree's verdict, while one voxel's verdict alone may be more than what lies inside it.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn voxel_occluded(
    voxel: *const f32,
    voxel_len: Word,
    rays: *const f32,
    rays_len: Word,
    blocked: *mut u8,
    blocked_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (voxel, rays) = unsafe { (array(voxel, voxel_len), array(rays, rays_len)) };
    let n_rays = rays.len() / RAY_FLOATS;
    let fits = voxel.len().is_multiple_of(VOXEL_TRI_FLOATS)
        && rays.len().is_multiple_of(RAY_FLOATS)
        && n_rays as Word <= blocked_len;
    let written = if fits {
        // SAFETY: `blocked` is valid for `blocked_len` >= n_rays flags.
        let blocked = unsafe { std::slice::from_raw_parts_mut(blocked, n_rays) };
        block_rays(&voxel_packets(voxel), rays, blocked)
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// Packs a voxel's flat triangles four to a packet.
fn voxel_packets(voxel: &[f32]) -> Vec<TriPacket> {
    voxel
        .chunks(VOXEL_TRI_FLOATS * LANES)
        .map(|four| {
            let mut p = TriPacket::EMPTY;
            for (lane, t) in four.chunks_exact(VOXEL_TRI_FLOATS).enumerate() {
                let v = |i: usize| Vec3::from_slice(&t[3 * i..3 * i + 3]);
                p.set_lane(lane, v(0), v(1), v(2));
            }
            p
        })
        .collect()
}

/// Sets the flag of each ray a packet blocks; returns how many flags it set.
fn block_rays(packets: &[TriPacket], rays: &[f32], blocked: &mut [u8]) -> Word {
    let mut newly = 0;
    for (r, b) in rays.chunks_exact(RAY_FLOATS).zip(blocked) {
        if *b != 0 {
            continue;
        }
        let q = RayQuery::new(
            Vec3::from_slice(&r[0..3]),
            Vec3::from_slice(&r[3..6]),
            r[6],
            r[7],
        );
        if packets.iter().any(|p| p.intersect(&q).0 != 0) {
            *b = 1;
            newly += 1;
        }
    }
    newly
}
