//! The quadratic rule's weights for a node program that keeps the mesh in its own arrays
//! (carm.occ's controller): `RAD.ELEMENTS.AROUND` lists the elements around each vertex and
//! `RAD.ELEMENT.WEIGHTS` gives chosen elements' integrals as weights on vertices
//! ([`crate::quadrature::weights`], the reference solver's rule).

use glam::Vec3;
use occ_runtime::abi::Word;

use super::{array, array_mut};
use crate::quadrature::weights::{Support, element_weights, elements_around};

/// Floats per sample point in the controller's arrays: position, normal, evaluation point.
const POINT_FLOATS: usize = 9;

/// `PROC RAD.ELEMENTS.AROUND (VAL []INT element, []INT first, []INT around, RESULT INT count)`:
/// the elements around each vertex of the mesh `element` (three vertex indices a triangle, the
/// triangles in use only): vertex `v`'s are `around[first[v] .. first[v + 1] - 1]`, ascending,
/// for the `SIZE first - 1` vertices. `count` is the number written to `around` (three a
/// triangle), or -1 (nothing written) on a vertex index out of range or `around` too short.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn elements_around_of(
    element: *const i32,
    element_len: Word,
    first: *mut i32,
    first_len: Word,
    around: *mut i32,
    around_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (element, first, around) = unsafe {
        (
            array(element, element_len),
            array_mut(first, first_len),
            array_mut(around, around_len),
        )
    };
    let vertices = first.len().saturating_sub(1);
    let valid = !first.is_empty()
        && element.len().is_multiple_of(3)
        && around.len() >= element.len()
        && element.iter().all(|&v| v >= 0 && (v as usize) < vertices);
    let written = if valid {
        let (f, list) = elements_around(vertices, corners_of(element));
        first.iter_mut().zip(f).for_each(|(o, x)| *o = x as i32);
        around
            .iter_mut()
            .zip(&list)
            .for_each(|(o, &x)| *o = x as i32);
        list.len() as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

/// `PROC RAD.ELEMENT.WEIGHTS (VAL []INT element, VAL []REAL32 point, VAL []INT first, around,
/// which, []INT count, at, []REAL64 weight, RESULT INT n)`: the integrals (area times mean,
/// by the quadratic rule) of the elements `which` of the mesh `element` (three vertex indices
/// a triangle; `point`: 9 floats a vertex, position, normal, evaluation point, a zero normal
/// for a hidden one; `first` and `around` as `RAD.ELEMENTS.AROUND` wrote them) as weights on
/// vertices ([`element_weights`]): element `which[i]` has `count[i]` of them, its three corners
/// first, one after another in `at` (the vertex) and `weight`. `n` is the number written, or
/// -1 on a wrong length, an index out of range, or `at` or `weight` too short.
///
/// # Safety
/// The arrays are valid for their lengths and `n` for one word (the occam ABI).
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn element_weights_of(
    element: *const i32,
    element_len: Word,
    point: *const f32,
    point_len: Word,
    first: *const i32,
    first_len: Word,
    around: *const i32,
    around_len: Word,
    which: *const i32,
    which_len: Word,
    count: *mut i32,
    count_len: Word,
    at: *mut i32,
    at_len: Word,
    weight: *mut f64,
    weight_len: Word,
    n: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (element, point, first, around, which, count, at, weight) = unsafe {
        (
            array(element, element_len),
            array(point, point_len),
            array(first, first_len),
            array(around, around_len),
            array(which, which_len),
            array_mut(count, count_len),
            array_mut(at, at_len),
            array_mut(weight, weight_len),
        )
    };
    let mesh = FlatSupport {
        element,
        point,
        first,
        around,
    };
    let written = if mesh.shaped() && count.len() >= which.len() {
        write_weights(&mesh, which, count, at, weight).map_or(-1, |n| n as Word)
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *n = written };
}

/// The weights `RAD.ELEMENT.WEIGHTS` gives every element of the mesh `element` (three vertex
/// indices a triangle; `point`: 9 floats a vertex, as the controller keeps them), with the
/// elements around each vertex as `RAD.ELEMENTS.AROUND` lists them: `each(e, weights)` for
/// each element in order, its `(vertex, weight)` pairs in the intrinsic's order. So a host
/// that deals an unchanging mesh's corners for the controller gives the nodes the very weights
/// the controller would have. `None` when a vertex index is out of range or `point` is not 9
/// floats a vertex.
pub fn mesh_weights(
    element: &[i32],
    point: &[f32],
    mut each: impl FnMut(usize, &[(u32, f64)]),
) -> Option<()> {
    let vertices = point.len() / POINT_FLOATS;
    let valid = point.len().is_multiple_of(POINT_FLOATS)
        && element.len().is_multiple_of(3)
        && element.iter().all(|&v| v >= 0 && (v as usize) < vertices);
    if !valid {
        return None;
    }
    let (first, around) = elements_around(vertices, corners_of(element));
    let first: Vec<i32> = first.into_iter().map(|x| x as i32).collect();
    let around: Vec<i32> = around.into_iter().map(|x| x as i32).collect();
    let mesh = FlatSupport {
        element,
        point,
        first: &first,
        around: &around,
    };
    let mut out = Vec::new();
    for e in 0..element.len() / 3 {
        element_weights(&mesh, e as u32, &mut out);
        each(e, &out);
    }
    Some(())
}

/// `RAD.ELEMENT.WEIGHTS`'s work: the number written, or `None` when `at` or `weight` runs out.
fn write_weights(
    mesh: &FlatSupport,
    which: &[i32],
    count: &mut [i32],
    at: &mut [i32],
    weight: &mut [f64],
) -> Option<usize> {
    let elements = mesh.element.len() / 3;
    let mut out = Vec::new();
    let mut n = 0;
    for (&e, c) in which.iter().zip(count.iter_mut()) {
        if e < 0 || e as usize >= elements || !mesh.valid_around(e as u32) {
            return None;
        }
        element_weights(mesh, e as u32, &mut out);
        let (at, weight) = (
            at.get_mut(n..n + out.len())?,
            weight.get_mut(n..n + out.len())?,
        );
        for ((a, w), &(v, x)) in at.iter_mut().zip(weight.iter_mut()).zip(&out) {
            (*a, *w) = (v as i32, x);
        }
        *c = out.len() as i32;
        n += out.len();
    }
    Some(n)
}

/// The triangles of a flat element array.
fn corners_of(element: &[i32]) -> impl Iterator<Item = [u32; 3]> + Clone + '_ {
    element
        .chunks_exact(3)
        .map(|v| [v[0] as u32, v[1] as u32, v[2] as u32])
}

/// The controller's arrays as a [`Support`].
struct FlatSupport<'a> {
    element: &'a [i32],
    point: &'a [f32],
    first: &'a [i32],
    around: &'a [i32],
}

impl FlatSupport<'_> {
    /// Whether the arrays' lengths agree (each element's neighbourhood is checked as it is
    /// weighed: [`FlatSupport::valid_around`], so that a call costs its elements' supports,
    /// not the mesh).
    fn shaped(&self) -> bool {
        let vertices = self.point.len() / POINT_FLOATS;
        self.point.len().is_multiple_of(POINT_FLOATS)
            && self.element.len().is_multiple_of(3)
            && self.first.len() == vertices + 1
    }

    /// Whether everything element `e`'s weights read is in range: its corners, the lists of
    /// the elements around them, and those elements' corners.
    fn valid_around(&self, e: u32) -> bool {
        let vertices = self.point.len() / POINT_FLOATS;
        let elements = self.element.len() / 3;
        let corners_ok = |e: usize| {
            (self.element[3 * e..3 * e + 3].iter()).all(|&v| v >= 0 && (v as usize) < vertices)
        };
        corners_ok(e as usize)
            && self.element[3 * e as usize..3 * e as usize + 3]
                .iter()
                .all(|&v| {
                    let (a, b) = (self.first[v as usize], self.first[v as usize + 1]);
                    0 <= a
                        && a <= b
                        && (b as usize) <= self.around.len()
                        && self.around[a as usize..b as usize]
                            .iter()
                            .all(|&o| o >= 0 && (o as usize) < elements && corners_ok(o as usize))
                })
    }
}

impl Support for FlatSupport<'_> {
    fn corners(&self, e: u32) -> [u32; 3] {
        let v = &self.element[3 * e as usize..][..3];
        [v[0] as u32, v[1] as u32, v[2] as u32]
    }
    fn pos(&self, v: u32) -> Vec3 {
        Vec3::from_slice(&self.point[POINT_FLOATS * v as usize..][..3])
    }
    fn hidden(&self, v: u32) -> bool {
        Vec3::from_slice(&self.point[POINT_FLOATS * v as usize + 3..][..3]) == Vec3::ZERO
    }
    fn around(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        let (a, b) = (self.first[v as usize], self.first[v as usize + 1]);
        self.around[a as usize..b as usize]
            .iter()
            .map(|&e| e as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing an edge, in the plane z = 0: points 0..4 (9 floats each).
    fn square() -> (Vec<i32>, Vec<f32>) {
        let element = vec![0, 1, 2, 0, 2, 3];
        let mut point = Vec::new();
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            point.extend([x, y, 0.0, 0.0, 0.0, 1.0, x, y, 0.0]);
        }
        (element, point)
    }

    #[test]
    fn the_weights_of_listed_elements_come_with_their_corners_first() {
        let (element, point) = square();
        let (first, around) = elements_around(4, corners_of(&element));
        let (first, around): (Vec<i32>, Vec<i32>) = (
            first.iter().map(|&x| x as i32).collect(),
            around.iter().map(|&x| x as i32).collect(),
        );
        let mesh = FlatSupport {
            element: &element,
            point: &point,
            first: &first,
            around: &around,
        };
        let (mut count, mut at, mut weight) = ([0; 2], [0; 16], [0.0; 16]);
        let n = write_weights(&mesh, &[1, 0], &mut count, &mut at, &mut weight);
        assert_eq!(n, Some(count.iter().sum::<i32>() as usize));
        assert_eq!(at[..3], [0, 2, 3]);
        let sum: f64 = weight[..count[0] as usize].iter().sum();
        assert!(
            (sum - 0.5).abs() < 1e-6,
            "a constant field's integral is the area: {sum}"
        );
        // no room for both elements' weights
        assert_eq!(
            write_weights(&mesh, &[1, 0], &mut count, &mut at[..5], &mut weight),
            None
        );
    }

    /// A 4 x 4 grid of points, bent so that the quadratic rule has curvature to weigh, in 18
    /// triangles.
    fn bent_grid() -> (Vec<i32>, Vec<f32>) {
        let mut point = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let (x, y) = (i as f32, j as f32);
                let z = 0.1 * x * x + 0.05 * x * y;
                point.extend([x, y, z, 0.0, 0.0, 1.0, x, y, z]);
            }
        }
        let mut element = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                let v = 4 * j + i;
                element.extend([v, v + 1, v + 5, v, v + 5, v + 4]);
            }
        }
        (element, point)
    }

    #[test]
    fn the_host_deals_the_weights_the_controller_would_work_out() {
        let (element, point) = bent_grid();
        // the controller's way: the intrinsics over its arrays, all elements in one call
        let (mut first, mut around, mut listed) = (vec![0i32; 17], vec![0i32; element.len()], 0);
        // SAFETY: valid arrays for their lengths, and a valid result address.
        unsafe {
            elements_around_of(
                element.as_ptr(),
                element.len() as Word,
                first.as_mut_ptr(),
                first.len() as Word,
                around.as_mut_ptr(),
                around.len() as Word,
                &mut listed,
            )
        };
        assert_eq!(listed, element.len() as Word);
        let which: Vec<i32> = (0..18).collect();
        let (mut count, mut at, mut weight, mut n) =
            (vec![0i32; 18], vec![0i32; 1024], vec![0.0f64; 1024], 0);
        // SAFETY: as above.
        unsafe {
            element_weights_of(
                element.as_ptr(),
                element.len() as Word,
                point.as_ptr(),
                point.len() as Word,
                first.as_ptr(),
                first.len() as Word,
                around.as_ptr(),
                around.len() as Word,
                which.as_ptr(),
                which.len() as Word,
                count.as_mut_ptr(),
                count.len() as Word,
                at.as_mut_ptr(),
                at.len() as Word,
                weight.as_mut_ptr(),
                weight.len() as Word,
                &mut n,
            )
        };
        assert!(n > 3 * 18, "curvature weights beyond the corners: {n}");
        // the host's way
        let mut dealt = Vec::new();
        mesh_weights(&element, &point, |e, ws| {
            assert_eq!(e, dealt.len());
            dealt.push(ws.to_vec());
        })
        .expect("a valid mesh");
        let mut k = 0;
        for (e, ws) in dealt.iter().enumerate() {
            assert_eq!(ws.len(), count[e] as usize, "element {e}'s weight count");
            for &(v, x) in ws {
                assert_eq!((v as i32, x.to_bits()), (at[k], weight[k].to_bits()));
                k += 1;
            }
        }
        assert_eq!(k, n as usize);
        // a corner out of range is refused
        assert!(mesh_weights(&[0, 1, 99], &point, |_, _| {}).is_none());
    }

    #[test]
    fn an_element_listed_around_a_point_that_does_not_exist_is_refused() {
        let (element, point) = square();
        let first = [0, 2, 3, 5, 6];
        let around = [0, 1, 0, 0, 9, 1];
        let mesh = FlatSupport {
            element: &element,
            point: &point,
            first: &first,
            around: &around,
        };
        assert!(mesh.shaped());
        let (mut count, mut at, mut weight) = ([0; 1], [0; 16], [0.0; 16]);
        assert_eq!(
            write_weights(&mesh, &[0], &mut count, &mut at, &mut weight),
            None
        );
    }
}
