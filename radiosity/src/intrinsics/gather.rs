//! `RAD.CORNERS.GATHER`: the unshot power a node's corners hold for one patch's elements, when
//! the corners keep it lazily (carm.occ: programs/README.md, "Quadratic booking").

use occ_runtime::abi::Word;

use super::{array, array_mut};

/// `PROC RAD.CORNERS.GATHER (VAL INT first, VAL []INT next, element, point, VAL []REAL64
/// weight, VAL []REAL32 rho, VAL []REAL64 acc, []REAL64 unshot, base, VAL REAL64 keep,
/// []REAL64 out, RESULT INT count)`: walks one patch's list of corners, from corner `first`
/// through `next` (-1 ends it), and adds each corner's unshot power to its element's three
/// REAL64s of `out` (`element[c]`, an index in the patch). A corner's power is what it holds
/// settled, `unshot[3c + j]`, and what its point gathered since, times its weight and the
/// patch's reflectance `rho` (3): `weight[c] · rho[j] · (acc[3 point[c] + j] − base[3c + j])`.
/// With `keep` < 0 nothing is written but `out`; else each corner is settled (`unshot` takes
/// its power, `base` its point's `acc`) and then keeps `keep` of it (a shooter's share), and
/// `out` may be empty (nothing added: the share kept is all that is wanted). `count`
/// is the corners walked, or -1 when an index is out of range or the list is longer than the
/// corners (a cycle): the walk stops there, part of the list added.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI); the
/// written arrays do not overlap.
#[allow(
    clippy::too_many_arguments,
    reason = "the occam ABI: address and length per array"
)]
pub unsafe extern "C" fn corners_gather(
    first: Word,
    next: *const i32,
    next_len: Word,
    element: *const i32,
    element_len: Word,
    point: *const i32,
    point_len: Word,
    weight: *const f64,
    weight_len: Word,
    rho: *const f32,
    rho_len: Word,
    acc: *const f64,
    acc_len: Word,
    unshot: *mut f64,
    unshot_len: Word,
    base: *mut f64,
    base_len: Word,
    keep: f64,
    out: *mut f64,
    out_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays, the written ones apart.
    let mut corners = unsafe {
        LazyCorners {
            next: array(next, next_len),
            element: array(element, element_len),
            point: array(point, point_len),
            weight: array(weight, weight_len),
            acc: array(acc, acc_len),
            unshot: array_mut(unshot, unshot_len),
            base: array_mut(base, base_len),
        }
    };
    // SAFETY: as above.
    let (rho, out) = unsafe { (array(rho, rho_len), array_mut(out, out_len)) };
    let keep = (keep >= 0.0).then_some(keep);
    let walked = match <[f32; 3]>::try_from(rho) {
        Ok(rho) => corners.gather(first, rho.map(f64::from), keep, out),
        Err(_) => None,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = walked.map_or(-1, |n| n as Word) };
}

/// A node's corners as `RAD.CORNERS.GATHER` is passed them.
struct LazyCorners<'a> {
    next: &'a [i32],
    element: &'a [i32],
    point: &'a [i32],
    weight: &'a [f64],
    acc: &'a [f64],
    unshot: &'a mut [f64],
    base: &'a mut [f64],
}

impl LazyCorners<'_> {
    /// Adds the list's power into `out` (settling each corner and scaling it by `keep`, if
    /// given); the corners walked, or `None` on an index out of range or a cycle.
    fn gather(
        &mut self,
        first: Word,
        rho: [f64; 3],
        keep: Option<f64>,
        out: &mut [f64],
    ) -> Option<usize> {
        let n = self.next.len();
        let valid = self.element.len() == n
            && self.point.len() == n
            && self.weight.len() == n
            && self.unshot.len() == 3 * n
            && self.base.len() == 3 * n;
        if !valid {
            return None;
        }
        let mut walked = 0;
        let mut c = first;
        while c >= 0 {
            let i = usize::try_from(c).ok().filter(|&i| i < n && walked < n)?;
            let e = 3 * usize::try_from(self.element[i]).ok()?;
            let p = 3 * usize::try_from(self.point[i]).ok()?;
            let acc = self.acc.get(p..p + 3)?;
            let mut out = match (out.is_empty(), keep) {
                (true, Some(_)) => None,
                _ => Some(out.get_mut(e..e + 3)?),
            };
            for j in 0..3 {
                let at = 3 * i + j;
                let power = self.unshot[at] + self.weight[i] * rho[j] * (acc[j] - self.base[at]);
                if let Some(out) = out.as_mut() {
                    out[j] += power;
                }
                if let Some(keep) = keep {
                    self.unshot[at] = power * keep;
                    self.base[at] = acc[j];
                }
            }
            walked += 1;
            c = Word::from(self.next[i]);
        }
        Some(walked)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Corners 0 -> 2 of a patch (1 is another patch's): element 1 at point 0, element 0 at
    /// point 1, with `unshot` and `base` as given; point 0 gathered 1, point 1 gathered 4.
    fn patch<'a>(unshot: &'a mut [f64; 9], base: &'a mut [f64; 9]) -> LazyCorners<'a> {
        LazyCorners {
            next: &[2, -1, -1],
            element: &[1, 0, 0],
            point: &[0, 1, 1],
            weight: &[2.0, 9.0, 0.5],
            acc: &[1.0, 1.0, 1.0, 4.0, 4.0, 4.0],
            unshot,
            base,
        }
    }

    #[test]
    fn the_list_adds_each_corner_s_settled_and_lazy_power_to_its_element() {
        let mut unshot = [0.1, 0.2, 0.3, 9.0, 9.0, 9.0, 1.0, 1.0, 1.0];
        let mut base = [0.5, 0.5, 0.5, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0];
        let rho = [0.5, 0.25, 1.0];
        for keep in [None, Some(0.5)] {
            let mut out = [0.0; 6];
            let walked = patch(&mut unshot, &mut base).gather(0, rho, keep, &mut out);
            assert_eq!(walked, Some(2));
            // element 0: 1 + 0.5 * rho * (4 - 2); element 1: unshot + 2 * rho * (1 - 0.5)
            assert_eq!(out, [1.5, 1.25, 2.0, 0.6, 0.45, 1.3]);
        }
        // settled, then half kept: corner 2 holds half its power, its base its point's acc
        assert_eq!(unshot[6..], [0.75, 0.625, 1.0]);
        assert_eq!(base[6..], [4.0; 3]);
        let other = &unshot[3..6];
        assert_eq!(other, [9.0; 3], "another patch's corner is left alone");
        // the share kept alone, nothing added anywhere
        let walked = patch(&mut unshot, &mut base).gather(0, rho, Some(0.5), &mut []);
        assert_eq!(walked, Some(2));
        assert_eq!(unshot[6..], [0.375, 0.3125, 0.5]);
    }

    #[test]
    fn a_cycle_or_an_index_out_of_range_is_refused() {
        let (mut unshot, mut base) = ([1.0; 6], [0.0; 6]);
        let mut corners = LazyCorners {
            next: &[1, 0],
            element: &[0, 0],
            point: &[0, 0],
            weight: &[1.0, 1.0],
            acc: &[1.0; 3],
            unshot: &mut unshot,
            base: &mut base,
        };
        let mut out = [0.0; 3];
        assert_eq!(corners.gather(0, [1.0; 3], None, &mut out), None);
        assert_eq!(corners.gather(5, [1.0; 3], None, &mut out), None);
        let mut corners = LazyCorners {
            next: &[-1],
            element: &[7],
            point: &[0],
            weight: &[1.0],
            acc: &[1.0; 3],
            unshot: &mut [0.0; 3],
            base: &mut [0.0; 3],
        };
        assert_eq!(corners.gather(0, [1.0; 3], None, &mut out), None);
    }
}
