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

use crate::formfactor::{FormFactorConfig, form_factor_with, point_polygon, source_samples};
use crate::geom::Tri;
use crate::rng::Pcg32;

/// Most rays `RAD.SOURCE.SAMPLES` accepts.
pub const MAX_SAMPLES: Word = 1 << 16;

/// Stream of the sample generator (the solver's kernels use the same).
const SAMPLE_STREAM: u64 = 0x5eed;

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
/// `m` rays, as the solver takes them ([`source_samples`]: a jittered k × k grid, k = ⌈√m⌉,
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
    // SAFETY: the ABI passes a valid array.
    let tri = triangle(unsafe { array(tri, tri_len) });
    let mut samples = Vec::new();
    if let Some(tri) = tri.filter(|_| (1..=MAX_SAMPLES).contains(&m)) {
        let mut rng = Pcg32::new(seed as u64, SAMPLE_STREAM);
        source_samples(&tri, m as u32, &mut rng, &mut samples);
    }
    let floats = 3 * samples.len();
    let written = if samples.is_empty() || floats as Word > out_len {
        -1
    } else {
        // SAFETY: `out` is valid for `out_len` ≥ `floats` floats.
        let out = unsafe { std::slice::from_raw_parts_mut(out, floats) };
        for (o, s) in out.chunks_exact_mut(3).zip(&samples) {
            o.copy_from_slice(&s.to_array());
        }
        samples.len() as Word
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
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
            let config = FormFactorConfig::default();
            form_factor_with(p, n, &tri, &s, &config, |k, _, _, _| visible[k] == 0).value
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
            if !s.is_empty() && (RAY_FLOATS * s.len()) as Word <= rays_len =>
        {
            // SAFETY: `rays` is valid for `rays_len` >= 8m floats.
            let out = unsafe { std::slice::from_raw_parts_mut(rays, RAY_FLOATS * s.len()) };
            let mut cast = 0;
            for (ray, x) in out.chunks_exact_mut(RAY_FLOATS).zip(&s) {
                ray.fill(0.0);
                ray[..3].copy_from_slice(&x.to_array());
            }
            let config = FormFactorConfig::default();
            form_factor_with(p, n, &tri, &s, &config, |k, origin, dir, tmax| {
                let ray = &mut out[RAY_FLOATS * k..RAY_FLOATS * (k + 1)];
                ray[..3].copy_from_slice(&origin.to_array());
                ray[3..6].copy_from_slice(&dir.to_array());
                ray[6] = 0.0;
                ray[7] = tmax;
                cast += 1;
                false
            });
            cast
        }
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

#[cfg(test)]
mod test {
    use super::*;

    type PointPolygon =
        unsafe extern "C" fn(*const f32, Word, *const f32, Word, *const f32, Word, *mut f32);
    type Samples = unsafe extern "C" fn(*const f32, Word, Word, Word, *mut f32, Word, *mut Word);
    type FormFactor = unsafe extern "C" fn(
        *const f32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *const f32,
        Word,
        *const u8,
        Word,
        *mut f32,
    );

    fn entry(name: &str) -> &'static Intrinsic {
        INTRINSICS.iter().find(|i| i.name == name).expect(name)
    }

    /// Calls RAD.POINT.POLYGON.FF through the table.
    fn pp(p: &[f32], n: &[f32], poly: &[f32]) -> f32 {
        let e = entry("RAD.POINT.POLYGON.FF");
        assert_eq!(e.machine_params().len(), 7);
        // SAFETY: the table says this is the signature.
        let f: PointPolygon = unsafe { std::mem::transmute(e.addr) };
        let mut out = 0.0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                p.as_ptr(),
                p.len() as Word,
                n.as_ptr(),
                n.len() as Word,
                poly.as_ptr(),
                poly.len() as Word,
                &mut out,
            )
        };
        out
    }

    /// A unit square at height `h` centred over the origin.
    fn square(h: f32) -> Vec<f32> {
        vec![-0.5, h, -0.5, 0.5, h, -0.5, 0.5, h, 0.5, -0.5, h, 0.5]
    }

    #[test]
    fn point_polygon_matches_the_closed_forms() {
        let (p, n) = ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert!((pp(&p, &n, &square(1.0)) - 0.239456).abs() < 1e-5);
        assert!((pp(&p, &n, &square(0.1)) - 0.968340).abs() < 1e-5);
        assert_eq!(pp(&p[..2], &n, &square(1.0)), -1.0);
        assert_eq!(pp(&p, &n, &square(1.0)[..11]), -1.0);
        assert_eq!(pp(&p, &n, &square(1.0)[..6]), -1.0);
    }

    fn samples(tri: &[f32], m: Word, seed: Word, out: &mut [f32]) -> Word {
        let e = entry("RAD.SOURCE.SAMPLES");
        // SAFETY: the table says this is the signature.
        let f: Samples = unsafe { std::mem::transmute(e.addr) };
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                tri.as_ptr(),
                tri.len() as Word,
                m,
                seed,
                out.as_mut_ptr(),
                out.len() as Word,
                &mut count,
            )
        };
        count
    }

    const TRI: [f32; 9] = [0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0];

    #[test]
    fn samples_are_the_solvers_and_bad_lengths_write_nothing() {
        let mut out = [9.0f32; 3 * 25];
        assert_eq!(samples(&TRI, 16, 7, &mut out), 16);
        let mut rng = Pcg32::new(7, SAMPLE_STREAM);
        let mut want = Vec::new();
        source_samples(&triangle(&TRI).expect("tri"), 16, &mut rng, &mut want);
        let got = points(&out[..48]).expect("points");
        assert_eq!(got, want);
        assert!(out[48..].iter().all(|x| *x == 9.0));
        assert_eq!(samples(&TRI, 17, 7, &mut out), 25);
        let mut short = [9.0f32; 3 * 16];
        assert_eq!(samples(&TRI, 17, 7, &mut short), -1);
        assert_eq!(samples(&TRI, 0, 7, &mut short), -1);
        assert_eq!(samples(&TRI[..8], 4, 7, &mut short), -1);
        assert!(short.iter().all(|x| *x == 9.0));
    }

    /// A source triangle at height 1 facing down (-y), towards the receivers below.
    const SOURCE: [f32; 9] = [0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0];

    fn ff(s: &[f32], visible: &[u8]) -> f32 {
        let e = entry("RAD.FORM.FACTOR");
        // SAFETY: the table says this is the signature.
        let f: FormFactor = unsafe { std::mem::transmute(e.addr) };
        let (p, n) = ([0.3f32, 0.0, 0.3], [0.0f32, 1.0, 0.0]);
        let tri = SOURCE;
        let mut out = 0.0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                p.as_ptr(),
                3,
                n.as_ptr(),
                3,
                tri.as_ptr(),
                9,
                s.as_ptr(),
                s.len() as Word,
                visible.as_ptr(),
                visible.len() as Word,
                &mut out,
            )
        };
        out
    }

    fn shadow(s: &[f32], p: [f32; 3], rays: &mut [f32]) -> Word {
        let e = entry("RAD.SHADOW.RAYS");
        type F = unsafe extern "C" fn(
            *const f32,
            Word,
            *const f32,
            Word,
            *const f32,
            Word,
            *const f32,
            Word,
            *mut f32,
            Word,
            *mut Word,
        );
        // SAFETY: the table says this is the signature.
        let f: F = unsafe { std::mem::transmute(e.addr) };
        let (n, tri) = ([0.0f32, 1.0, 0.0], SOURCE);
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            f(
                p.as_ptr(),
                3,
                n.as_ptr(),
                3,
                tri.as_ptr(),
                9,
                s.as_ptr(),
                s.len() as Word,
                rays.as_mut_ptr(),
                rays.len() as Word,
                &mut count,
            )
        };
        count
    }

    #[test]
    fn shadow_rays_are_the_ones_the_form_factor_asks_for() {
        let mut s = [0.0f32; 48];
        assert_eq!(samples(&SOURCE, 16, 5, &mut s), 16);
        let mut rays = [7.0f32; 8 * 16];
        assert_eq!(shadow(&s, [0.3, 0.0, 0.3], &mut rays), 16);
        let pts = points(&s).expect("samples");
        let (p, n) = (Vec3::new(0.3, 0.0, 0.3), Vec3::Y);
        let mut asked = Vec::new();
        let src = triangle(&SOURCE).expect("tri");
        let config = FormFactorConfig::default();
        form_factor_with(p, n, &src, &pts, &config, |k, o, d, t| {
            asked.push((k, o, d, t));
            false
        });
        assert_eq!(asked.len(), 16);
        for (k, o, d, t) in asked {
            let r = &rays[8 * k..8 * k + 8];
            assert_eq!(r[..3], o.to_array());
            assert_eq!(r[3..6], d.to_array());
            assert_eq!((r[6], r[7]), (0.0, t));
            // The ray ends just short of its sample.
            assert!((o + d * t - pts[k]).length() < 2e-3);
        }
        // Behind the source: no rays, every slot empty.
        assert_eq!(shadow(&s, [0.3, 2.0, 0.3], &mut rays), 0);
        assert!(rays.chunks(8).all(|r| r[3..].iter().all(|x| *x == 0.0)));
        let mut short = [7.0f32; 8 * 16 - 1];
        assert_eq!(shadow(&s, [0.3, 0.0, 0.3], &mut short), -1);
        assert!(short.iter().all(|x| *x == 7.0));
    }

    #[test]
    fn form_factor_scales_with_the_visible_rays() {
        let tri = SOURCE;
        let mut s = [0.0f32; 48];
        assert_eq!(samples(&tri, 16, 3, &mut s), 16);
        let full = ff(&s, &[1; 16]);
        let exact = point_polygon(
            Vec3::new(0.3, 0.0, 0.3),
            Vec3::Y,
            &points(&tri).expect("tri"),
        );
        // Near the source the analytic form is used: exact when every ray gets through.
        assert!(full > 0.0 && (full - exact).abs() < 1e-6, "{full} {exact}");
        let mut half = [0u8; 16];
        half[..8].fill(1);
        assert!((ff(&s, &half) - full / 2.0).abs() < 1e-6);
        assert_eq!(ff(&s, &[0; 16]), 0.0);
        assert_eq!(ff(&s, &[1; 15]), -1.0);
        assert_eq!(ff(&s[..47], &[1; 16]), -1.0);
        assert_eq!(ff(&[], &[]), -1.0);
    }
}
