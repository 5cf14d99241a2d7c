//! The intrinsics called through their table addresses, as the code generator calls them.

use super::*;
use crate::formfactor::source_samples;
use crate::rng::Pcg32;

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

/// The address of the intrinsic `name`, once its machine parameters are checked to be an
/// address and a length per array and one word per scalar (for tests that call it by a
/// function type of their own).
pub(super) fn address(name: &str) -> *const u8 {
    let e = entry(name);
    assert_eq!(
        e.machine_params().len(),
        e.params.len() + e.params.iter().filter(|p| p.is_array()).count()
    );
    e.addr
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

type SamplesAt =
    unsafe extern "C" fn(*const f32, Word, Word, Word, Word, *mut f32, Word, *mut Word);

fn samples_at(tri: &[f32], m: Word, seed: Word, set: Word, out: &mut [f32]) -> Word {
    let e = entry("RAD.SOURCE.SAMPLES.AT");
    // SAFETY: the table says this is the signature.
    let f: SamplesAt = unsafe { std::mem::transmute(e.addr) };
    let mut count = 0;
    // SAFETY: valid slices and result.
    unsafe {
        f(
            tri.as_ptr(),
            tri.len() as Word,
            m,
            seed,
            set,
            out.as_mut_ptr(),
            out.len() as Word,
            &mut count,
        )
    };
    count
}

#[test]
fn samples_at_a_set_are_the_solvers_for_that_receiver_of_a_batch() {
    // The solver's batch draws receiver after receiver from one generator: set k is the k-th.
    let seed = (1u64 << 40 | 12345) as Word;
    let mut rng = Pcg32::new(seed as u64, SAMPLE_STREAM);
    let mut want = Vec::new();
    for set in 0..5 {
        source_samples(&triangle(&TRI).expect("tri"), 8, &mut rng, &mut want);
        let mut out = [9.0f32; 3 * 9];
        assert_eq!(samples_at(&TRI, 8, seed, set, &mut out), 9);
        assert_eq!(points(&out).expect("points"), want, "set {set}");
    }
    let mut first = [0.0f32; 3 * 9];
    let mut plain = [0.0f32; 3 * 9];
    samples_at(&TRI, 8, 3, 0, &mut first);
    samples(&TRI, 8, 3, &mut plain);
    assert_eq!(first, plain);
    let mut out = [9.0f32; 3 * 9];
    assert_eq!(samples_at(&TRI, 8, 3, -1, &mut out), -1);
    assert_eq!(samples_at(&TRI, 8, 3, MAX_SKIPPED_SETS + 1, &mut out), -1);
    assert_eq!(samples_at(&TRI, 8, 3, 1, &mut out[..26]), -1);
    assert!(out.iter().all(|x| *x == 9.0));
}

/// A source triangle at height 1 facing down (-y), towards the receivers below.
const SOURCE: [f32; 9] = [0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0];

fn ff(s: &[f32], visible: &[u8]) -> f32 {
    ff_at(s, visible, [0.3, 0.0, 0.3])
}

fn ff_at(s: &[f32], visible: &[u8], p: [f32; 3]) -> f32 {
    let e = entry("RAD.FORM.FACTOR");
    // SAFETY: the table says this is the signature.
    let f: FormFactor = unsafe { std::mem::transmute(e.addr) };
    let n = [0.0f32, 1.0, 0.0];
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

/// Seeded: receivers all around random sources, many of them seeing only part of the source
/// above their horizon, get from `receiver_rays` exactly the rays `form_factor_with` asks
/// about, bit for bit, and an empty ray for every other sample.
#[test]
fn rays_are_the_ones_the_form_factor_asks_about() {
    let mut rng = Pcg32::new(42, 7);
    let mut coord = || 4.0 * rng.next_f32() - 2.0;
    let config = FormFactorConfig {
        offset: 1e-3,
        ..FormFactorConfig::default()
    };
    let (mut partial, mut none) = (0, 0);
    for i in 0..2000 {
        let mut v = || Vec3::new(coord(), coord(), coord());
        let src = Tri::new(v(), v(), v());
        let (p, n) = (v(), v().normalize_or_zero());
        let mut samples = Vec::new();
        // 16, 9, 4 and 1 samples: whole and partial groups of lanes
        let m = [16, 9, 4, 1][i % 4];
        source_samples(&src, m, &mut Pcg32::new(9, SAMPLE_STREAM), &mut samples);
        let mut rays = vec![7.0f32; RAY_FLOATS * samples.len()];
        let cast = receiver_rays(p, n, &src, &samples, &config, &mut rays);
        let mut asked = vec![None; samples.len()];
        form_factor_with(p, n, &src, &samples, &config, |k, o, d, t| {
            asked[k] = Some((o, d, t));
            false
        });
        let want = asked.iter().flatten().count();
        assert_eq!(cast as usize, want);
        match want {
            0 => none += 1,
            w if w < samples.len() => partial += 1,
            _ => {}
        }
        for (k, ray) in rays.chunks_exact(RAY_FLOATS).enumerate() {
            let bits = |xs: &[f32]| xs.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let expected: Vec<f32> = match asked[k] {
                Some((o, d, t)) => [o.to_array(), d.to_array()]
                    .concat()
                    .into_iter()
                    .chain([0.0, t])
                    .collect(),
                None => [samples[k].to_array(), [0.0; 3]]
                    .concat()
                    .into_iter()
                    .chain([0.0, 0.0])
                    .collect(),
            };
            assert_eq!(bits(ray), bits(&expected), "sample {k}");
        }
    }
    assert!(
        partial > 100 && none > 100,
        "partial {partial}, none {none}"
    );
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

type Batch = unsafe extern "C" fn(
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
    Word,
    *mut Word,
);
type RaysBatch = unsafe extern "C" fn(
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

#[test]
fn batches_equal_the_single_calls() {
    let mut s = [0.0f32; 48];
    assert_eq!(samples(&SOURCE, 16, 9, &mut s), 16);
    let pts = [0.3f32, 0.0, 0.3, 0.1, 0.2, 0.7, 0.3, 2.0, 0.3];
    let nrm = [0.0f32, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    // SAFETY: the table says these are the signatures.
    let (batch, rays_batch): (Batch, RaysBatch) = unsafe {
        (
            std::mem::transmute::<*const u8, Batch>(entry("RAD.SHOOT.BATCH").addr),
            std::mem::transmute::<*const u8, RaysBatch>(entry("RAD.SHADOW.RAYS.BATCH").addr),
        )
    };
    let mut rays = vec![0.0f32; 8 * 16 * 3];
    let mut count = 0;
    // SAFETY: valid slices and result.
    unsafe {
        rays_batch(
            pts.as_ptr(),
            9,
            nrm.as_ptr(),
            9,
            SOURCE.as_ptr(),
            9,
            s.as_ptr(),
            48,
            rays.as_mut_ptr(),
            rays.len() as Word,
            &mut count,
        )
    };
    // Receivers 0 and 1 cast every ray; receiver 2 is behind the source.
    assert_eq!(count, 32);
    let mut one = [0.0f32; 8 * 16];
    for i in 0..3 {
        let p = [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]];
        shadow(&s, p, &mut one);
        assert_eq!(one[..], rays[128 * i..128 * (i + 1)]);
    }
    // Every other ray blocked.
    let visible: Vec<u8> = (0..48).map(|k| (k % 2) as u8).collect();
    let mut f = [9.0f32; 4];
    // SAFETY: valid slices and result.
    unsafe {
        batch(
            pts.as_ptr(),
            9,
            nrm.as_ptr(),
            9,
            SOURCE.as_ptr(),
            9,
            s.as_ptr(),
            48,
            visible.as_ptr(),
            48,
            f.as_mut_ptr(),
            4,
            &mut count,
        )
    };
    assert_eq!(count, 3);
    assert_eq!(f[3], 9.0);
    for i in 0..3 {
        let single = ff_at(
            &s,
            &visible[16 * i..16 * (i + 1)],
            [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]],
        );
        assert_eq!(f[i], single, "receiver {i}");
    }
    assert!(f[0] > 0.0 && f[2] == 0.0);
    // Wrong lengths: -1, nothing written.
    let mut g = [9.0f32; 2];
    // SAFETY: valid slices and result.
    unsafe {
        batch(
            pts.as_ptr(),
            9,
            nrm.as_ptr(),
            9,
            SOURCE.as_ptr(),
            9,
            s.as_ptr(),
            48,
            visible.as_ptr(),
            48,
            g.as_mut_ptr(),
            2,
            &mut count,
        )
    };
    assert_eq!((count, g), (-1, [9.0; 2]));
    // SAFETY: valid slices and result.
    unsafe {
        batch(
            pts.as_ptr(),
            9,
            nrm.as_ptr(),
            6,
            SOURCE.as_ptr(),
            9,
            s.as_ptr(),
            48,
            visible.as_ptr(),
            48,
            f.as_mut_ptr(),
            4,
            &mut count,
        )
    };
    assert_eq!(count, -1);
    let mut short = vec![7.0f32; 8 * 16 * 3 - 1];
    // SAFETY: valid slices and result.
    unsafe {
        rays_batch(
            pts.as_ptr(),
            9,
            nrm.as_ptr(),
            9,
            SOURCE.as_ptr(),
            9,
            s.as_ptr(),
            48,
            short.as_mut_ptr(),
            short.len() as Word,
            &mut count,
        )
    };
    assert_eq!(count, -1);
    assert!(short.iter().all(|x| *x == 7.0));
}

type VoxelOccluded =
    unsafe extern "C" fn(*const f32, Word, *const f32, Word, *mut u8, Word, *mut Word);

/// Calls RAD.VOXEL.OCCLUDED through the table; returns the count.
fn voxel_occluded_call(voxel: &[f32], rays: &[f32], blocked: &mut [u8]) -> Word {
    let e = entry("RAD.VOXEL.OCCLUDED");
    // SAFETY: the table says this is the signature.
    let f: VoxelOccluded = unsafe { std::mem::transmute(e.addr) };
    let mut count = 0;
    // SAFETY: valid slices and result.
    unsafe {
        f(
            voxel.as_ptr(),
            voxel.len() as Word,
            rays.as_ptr(),
            rays.len() as Word,
            blocked.as_mut_ptr(),
            blocked.len() as Word,
            &mut count,
        )
    };
    count
}

#[test]
fn voxels_answer_together_what_the_octree_answers() {
    use crate::octree::{Octree, OctreeConfig, Traversal};
    use crate::scene::cornell;
    // Every voxel of the octree tested on its own, as nodes holding different voxels would,
    // blocks exactly the rays the octree says are blocked.
    let tris = cornell::grid_triangles(4).expect("cornell");
    let tree = Octree::build(&tris, OctreeConfig::default());
    let mut rng = Pcg32::new(31, 4);
    let mut rays = Vec::new();
    for _ in 0..400 {
        let a = &tris[rng.next_u32() as usize % tris.len()];
        let b = &tris[rng.next_u32() as usize % tris.len()];
        let o = a.sample(rng.next_f32(), rng.next_f32()) + a.normal() * 1e-3;
        let d = b.sample(rng.next_f32(), rng.next_f32()) - o;
        rays.extend(o.to_array());
        rays.extend(d.to_array());
        rays.extend([0.0, 0.999]);
    }
    let mut blocked = vec![0u8; 400];
    let mut newly = 0;
    for leaf in tree.voxels() {
        newly += voxel_occluded_call(&tree.voxel_floats(leaf), &rays, &mut blocked);
    }
    let expected: Vec<u8> = rays
        .chunks_exact(8)
        .map(|r| {
            let (o, d) = (Vec3::from_slice(&r[0..3]), Vec3::from_slice(&r[3..6]));
            tree.occluded(o, d, 0.0, 0.999, Traversal::Ropes) as u8
        })
        .collect();
    assert_eq!(blocked, expected);
    assert_eq!(newly, expected.iter().map(|&b| b as Word).sum::<Word>());
    assert!(newly > 40 && newly < 360, "{newly}");
}

#[test]
fn voxel_occluded_rejects_bad_lengths_and_writes_nothing() {
    let tri = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let ray = [0.2, 0.2, -1.0, 0.0, 0.0, 2.0, 0.0, 1.0];
    let mut blocked = [0u8; 1];
    assert_eq!(voxel_occluded_call(&tri[..8], &ray, &mut blocked), -1);
    assert_eq!(voxel_occluded_call(&tri, &ray[..7], &mut blocked), -1);
    assert_eq!(
        voxel_occluded_call(&tri, &[ray, ray].concat(), &mut blocked),
        -1
    );
    assert_eq!(blocked, [0]);
    assert_eq!(voxel_occluded_call(&tri, &ray, &mut blocked), 1);
    assert_eq!(blocked, [1]);
}

type ReceiverSamples = unsafe extern "C" fn(
    *const f32,
    Word,
    *const f32,
    Word,
    *const f32,
    Word,
    Word,
    Word,
    Word,
    Word,
    *const f32,
    Word,
    *mut f32,
    Word,
    *mut f32,
    Word,
    *mut Word,
);

/// Calls RAD.RECEIVER.SAMPLES through the table (uniform source).
fn receiver_samples_call(p: [f32; 6], rays: Word, far: Word, set: Word, out: &mut [f32]) -> Word {
    let e = entry("RAD.RECEIVER.SAMPLES");
    // SAFETY: the table says this is the signature.
    let f: ReceiverSamples = unsafe { std::mem::transmute(e.addr) };
    let (mut count, mut weights) = (0, [0.0f32; 16]);
    // SAFETY: valid slices and result.
    unsafe {
        f(
            p.as_ptr(),
            3,
            p[3..].as_ptr(),
            3,
            SOURCE.as_ptr(),
            9,
            rays,
            far,
            77,
            set,
            std::ptr::null(),
            0,
            out.as_mut_ptr(),
            out.len() as Word,
            weights.as_mut_ptr(),
            weights.len() as Word,
            &mut count,
        )
    };
    count
}

#[test]
fn receiver_samples_at_a_set_are_the_solvers_with_far_rays() {
    // A batch as the solver's kernel draws it with 9 rays, 1 to far receivers: a near receiver,
    // a far one, one behind the source (none), one that sees only part of it above its horizon.
    let receivers = [
        [0.3, 0.9, 0.3, 0.0, 1.0, 0.0],
        [0.3, -3.0, 0.3, 0.0, 1.0, 0.0],
        [0.3, 2.0, 0.3, 0.0, 1.0, 0.0],
        [0.3, 0.0, 0.3, 0.0, 0.3, -0.954],
    ];
    let config = FormFactorConfig {
        rays: 9,
        far_rays: 1,
        ..FormFactorConfig::default()
    };
    let tri = triangle(&SOURCE).expect("tri");
    let mut rng = Pcg32::new(77, SAMPLE_STREAM);
    let (mut want, mut w) = (Vec::new(), Vec::new());
    let mut drawn = Vec::new();
    for (set, r) in receivers.iter().enumerate() {
        let (p, n) = (Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..]));
        let rays = crate::formfactor::receiver_samples(
            (p, n),
            &crate::formfactor::Facing::new(&tri),
            &config,
            None::<&crate::formfactor::SourceDensity>,
            &mut rng,
            &mut want,
            &mut w,
        );
        let mut out = [9.0f32; 3 * 9];
        let count = receiver_samples_call(*r, 9, 1, set as Word, &mut out);
        assert_eq!(count as usize, want.len(), "set {set}");
        assert_eq!(points(&out[..3 * want.len()]), Some(want.clone()));
        drawn.push(rays);
    }
    assert_eq!(drawn, [9, 1, 0, 9]);
    // The far receiver draws the start of its full set.
    let (mut full, mut out) = ([0.0f32; 27], [0.0f32; 27]);
    receiver_samples_call(receivers[1], 9, 0, 1, &mut full);
    receiver_samples_call(receivers[1], 9, 1, 1, &mut out);
    assert_ne!(full[..3], out[..3], "one sample is not the first of nine");
    let mut out = [9.0f32; 27];
    assert_eq!(receiver_samples_call(receivers[0], 9, 10, 0, &mut out), -1);
    assert_eq!(receiver_samples_call(receivers[0], 0, 0, 0, &mut out), -1);
    assert_eq!(
        receiver_samples_call(receivers[0], 9, 0, 0, &mut out[..26]),
        -1
    );
    assert!(out.iter().all(|x| *x == 9.0));
}

#[test]
fn shot_rays_are_the_solvers() {
    type ShotRays = unsafe extern "C" fn(Word, f64, f64, *mut Word);
    let e = entry("RAD.SHOT.RAYS");
    // SAFETY: the table says this is the signature.
    let f: ShotRays = unsafe { std::mem::transmute(e.addr) };
    let call = |rays, share, full| {
        let mut far = 0;
        // SAFETY: a valid result address.
        unsafe { f(rays, share, full, &mut far) };
        far
    };
    assert_eq!(call(8, 0.05, 0.01), 8);
    assert_eq!(call(8, 0.005, 0.01), 4);
    assert_eq!(call(8, 1e-8, 0.01), 1);
    assert_eq!(call(8, 1e-8, 0.0), 8);
    assert_eq!(call(0, 0.01, 0.01), -1);
    assert_eq!(call(8, -0.01, 0.01), -1);
    assert_eq!(call(8, f64::NAN, 0.01), -1);
    // The share is the largest channel's: a dim red light beside a bright green one keeps its
    // rays for the red it alone emits.
    use crate::solver::shot_share;
    use glam::DVec3;
    let emitted = DVec3::new(1.0, 1e8, 0.0);
    assert_eq!(shot_share(DVec3::new(0.5, 0.0, 0.0), emitted), 0.5);
    assert_eq!(shot_share(DVec3::new(0.0, -1e6, 0.0), emitted), 0.01);
    assert_eq!(shot_share(DVec3::ONE, DVec3::ZERO), 0.0);
}
