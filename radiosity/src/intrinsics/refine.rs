//! Adaptive subdivision for a node program that keeps the mesh in its own arrays (carm.occ's
//! controller): `RAD.REFINE.EDGES` finds the edges a shot makes steep and their midpoints,
//! `RAD.REFINE.SPLIT` splits the edges the program decided to split. The rules are
//! [`crate::refine`]'s and the split is [`crate::mesh::Connectivity`]'s, the reference solver's
//! own, so both refine the same edges the same way.

use occ_runtime::abi::Word;

use super::{array, array_mut};
use crate::kernels::SamplePoint;
use crate::mesh::{Connectivity, ElementCorners};
use crate::refine::{self, EdgeEnds, EdgeTest};

/// Floats per sample point in the controller's arrays: position, normal, evaluation point.
const POINT_FLOATS: usize = 9;

/// INTs per record of `RAD.REFINE.SPLIT`: the element split, its new half, then the split
/// element's corners x, y, c (the edge was x -> y) and the new vertex m.
pub const SPLIT_RECORD_INTS: usize = 6;

fn sample_point(points: &[f32], v: u32) -> SamplePoint {
    let p = &points[POINT_FLOATS * v as usize..][..POINT_FLOATS];
    SamplePoint {
        pos: [p[0], p[1], p[2]],
        normal: [p[3], p[4], p[5]],
        eval: [p[6], p[7], p[8]],
    }
}

/// Whether every INT of `element` (three a triangle) names one of `points` points.
fn corners_valid(element: &[i32], points: usize) -> bool {
    element.len().is_multiple_of(3) && element.iter().all(|&v| v >= 0 && (v as usize) < points)
}

/// `PROC RAD.REFINE.EDGES (VAL []INT element, VAL []REAL32 point, factor, irradiance, test,
/// []INT edge, []REAL32 mid, RESULT INT count)`: the edges of the mesh (`element`: three vertex
/// indices a triangle; `point`: 9 floats a vertex, position, normal and evaluation point) that
/// this shot makes steep ([`refine::candidates`]: `factor` is the shot's form factor at each
/// vertex, `irradiance` what each has gathered before it, channels summed, `test` holds the
/// shot's radiosity change db (channels summed), the difference and the minimum edge), steepest
/// first: as many as `edge` holds (two INTs each, the ends) go to `edge` and their midpoints
/// ([`refine::midpoint`], 9 floats each) to `mid`. `count` is the number written, or -1
/// (nothing written) on a wrong length or a vertex index out of range.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn refine_edges(
    element: *const i32,
    element_len: Word,
    point: *const f32,
    point_len: Word,
    factor: *const f32,
    factor_len: Word,
    irradiance: *const f32,
    irradiance_len: Word,
    test: *const f32,
    test_len: Word,
    edge: *mut i32,
    edge_len: Word,
    mid: *mut f32,
    mid_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (element, point, factor, irradiance, test, edge, mid) = unsafe {
        (
            array(element, element_len),
            array(point, point_len),
            array(factor, factor_len),
            array(irradiance, irradiance_len),
            array(test, test_len),
            array_mut(edge, edge_len),
            array_mut(mid, mid_len),
        )
    };
    let points = factor.len();
    let valid = point.len() == POINT_FLOATS * points
        && irradiance.len() == points
        && test.len() == 3
        && corners_valid(element, points)
        && mid.len() >= POINT_FLOATS * (edge.len() / 2);
    let written = if valid {
        let corners = element
            .chunks_exact(3)
            .map(|v| [v[0] as u32, v[1] as u32, v[2] as u32]);
        let pos = |v: u32| glam::Vec3::from_slice(&point[POINT_FLOATS * v as usize..][..3]);
        let edges = refine::element_edges(corners).map(|(a, b)| EdgeEnds {
            ends: (a, b),
            length: (pos(a) - pos(b)).length(),
            factors: (factor[a as usize], factor[b as usize]),
            irradiance: (irradiance[a as usize], irradiance[b as usize]),
        });
        let rule = EdgeTest {
            difference: test[1],
            min_edge: test[2],
        };
        let found = refine::candidates(edges, test[0], rule);
        let n = found.len().min(edge.len() / 2);
        for (k, &(a, b)) in found[..n].iter().enumerate() {
            edge[2 * k] = a as i32;
            edge[2 * k + 1] = b as i32;
            let m = refine::midpoint(&sample_point(point, a), &sample_point(point, b));
            let out = &mut mid[POINT_FLOATS * k..][..POINT_FLOATS];
            out[..3].copy_from_slice(&m.pos);
            out[3..6].copy_from_slice(&m.normal);
            out[6..].copy_from_slice(&m.eval);
        }
        n as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// The controller's element array as [`ElementCorners`]: the first `count` triangles in use,
/// room after them; a copy that finds no room is counted in `overflow` and not made.
struct FlatElements<'a> {
    corners: &'a mut [i32],
    count: usize,
    overflow: bool,
}

impl ElementCorners for FlatElements<'_> {
    fn corners(&self, t: u32) -> [u32; 3] {
        let v = &self.corners[3 * t as usize..][..3];
        [v[0] as u32, v[1] as u32, v[2] as u32]
    }
    fn set_corners(&mut self, t: u32, v: [u32; 3]) {
        let out = &mut self.corners[3 * t as usize..][..3];
        out.copy_from_slice(&v.map(|x| x as i32));
    }
    fn push_copy(&mut self, _of: u32, v: [u32; 3]) -> u32 {
        if 3 * (self.count + 1) > self.corners.len() {
            self.overflow = true;
            return u32::MAX;
        }
        self.count += 1;
        let t = (self.count - 1) as u32;
        self.set_corners(t, v);
        t
    }
}

/// `PROC RAD.REFINE.SPLIT (VAL []INT split, []INT element, VAL INT count, VAL []REAL32 point,
/// []INT record, []REAL64 area, RESULT INT elements, records)`: splits the edges `split` (three
/// INTs each: the ends a, b and the new vertex m) in order, as the reference solver's mesh
/// splits them ([`crate::mesh::Mesh::split_edge`]), in the first `count` triangles of `element`
/// (three vertex indices each; the halves are appended after them). Each element split makes a
/// record of [`SPLIT_RECORD_INTS`] INTs in `record`: the element (which keeps its index and
/// becomes x, m, c), its new half (m, y, c), then x, y, c, m; and two REAL64s in `area`, the
/// areas of the two (as the solver computes element areas from `point`, 9 floats a vertex).
/// `elements` is the new count of triangles and `records` the number of records, or both -1
/// on a wrong length, an index out of range, or arrays too short for the halves or records (the
/// triangles are then left as they were only up to the split that ran out of room).
///
/// # Safety
/// The arrays are valid for their lengths and `elements`, `records` for one word each (the
/// occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn refine_split(
    split: *const i32,
    split_len: Word,
    element: *mut i32,
    element_len: Word,
    count: Word,
    point: *const f32,
    point_len: Word,
    record: *mut i32,
    record_len: Word,
    area: *mut f64,
    area_len: Word,
    elements: *mut Word,
    records: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (split, element, point, record, area) = unsafe {
        (
            array(split, split_len),
            array_mut(element, element_len),
            array(point, point_len),
            array_mut(record, record_len),
            array_mut(area, area_len),
        )
    };
    let points = point.len() / POINT_FLOATS;
    let in_use = usize::try_from(count)
        .ok()
        .filter(|&n| 3 * n <= element.len());
    let valid = in_use.is_some_and(|n| corners_valid(&element[..3 * n], points))
        && point.len().is_multiple_of(POINT_FLOATS)
        && split.len().is_multiple_of(3)
        && split.iter().all(|&v| v >= 0 && (v as usize) < points);
    let result = match in_use {
        Some(n) if valid => split_all(split, element, n, point, record, area),
        _ => None,
    };
    let (e, r) = result.map_or((-1, -1), |(e, r)| (e as Word, r as Word));
    // SAFETY: the ABI passes valid result addresses.
    unsafe {
        *elements = e;
        *records = r;
    }
}

/// `RAD.REFINE.SPLIT`'s work: the new element count and the records written, or `None` when
/// the arrays run out of room.
fn split_all(
    split: &[i32],
    element: &mut [i32],
    count: usize,
    point: &[f32],
    record: &mut [i32],
    area: &mut [f64],
) -> Option<(usize, usize)> {
    let flat = FlatElements {
        corners: element,
        count,
        overflow: false,
    };
    let wanted = split.chunks_exact(3).map(|s| {
        let (a, b) = (s[0] as u32, s[1] as u32);
        (a.min(b), a.max(b))
    });
    let mut mesh = Connectivity::around(flat, count, wanted);
    let tri_area = |v: [u32; 3]| {
        let p = |i: usize| glam::Vec3::from_slice(&point[POINT_FLOATS * v[i] as usize..][..3]);
        crate::geom::Tri::new(p(0), p(1), p(2)).area() as f64
    };
    let mut written = 0;
    for s in split.chunks_exact(3) {
        let (a, b, m) = (s[0] as u32, s[1] as u32, s[2] as u32);
        let first_half = mesh.elements.count as u32;
        let split_elements = mesh.split_edge(a, b, m);
        if mesh.elements.overflow {
            return None;
        }
        for (k, &t) in split_elements.iter().enumerate() {
            let half = first_half + k as u32;
            let (tv, hv) = (mesh.elements.corners(t), mesh.elements.corners(half));
            // t is now (x, m, c) and half (m, y, c)
            let out = record.get_mut(SPLIT_RECORD_INTS * written..)?;
            let out = out.get_mut(..SPLIT_RECORD_INTS)?;
            out.copy_from_slice(&[t, half, tv[0], hv[1], tv[2], m].map(|x| x as i32));
            let areas = area.get_mut(2 * written..)?.get_mut(..2)?;
            areas[0] = tri_area(tv);
            areas[1] = tri_area(hv);
            written += 1;
        }
    }
    Some((mesh.elements.count, written))
}
