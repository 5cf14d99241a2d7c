//! `RAD.POINTS.ORDER`: a spatial order of a node's sample points, so that the receivers of one
//! batch of form factors lie near each other and their shadow rays cross few voxels: with the
//! voxels spread over the nodes, each voxel a batch misses is fetched once for the whole batch
//! ("Voxel fetches" in programs/README.md), and a hashed share of the points taken in arrival
//! order scatters every batch over the whole scene.

use occ_runtime::abi::Word;

use super::{array, array_mut};

/// Bits of each coordinate in a Morton code (three of them fill 63 bits).
const BITS: u32 = 21;

/// Spreads the low [`BITS`] bits of `v` two bits apart (bit `i` to bit `3i`).
fn spread(v: u64) -> u64 {
    let mut x = v & ((1 << BITS) - 1);
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The Morton (Z-order) code of each point's position within the points' bounding box:
/// `points` holds `stride` floats a point, its position first. Non-finite coordinates count
/// as the box's low corner.
fn morton_codes(points: &[f32], stride: usize) -> Vec<u64> {
    let positions = || points.chunks_exact(stride).map(|p| [p[0], p[1], p[2]]);
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in positions() {
        for k in 0..3 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let cells = ((1u64 << BITS) - 1) as f64;
    positions()
        .map(|p| {
            (0..3).fold(0, |code, k| {
                let span = f64::from(hi[k]) - f64::from(lo[k]);
                let t = if p[k].is_finite() && span > 0.0 {
                    (f64::from(p[k]) - f64::from(lo[k])) / span
                } else {
                    0.0
                };
                code | spread((t * cells) as u64) << k
            })
        })
        .collect()
}

/// `PROC RAD.POINTS.ORDER (VAL []REAL32 points, []INT order, RESULT INT count)`: `points`
/// holds 9 REAL32s a sample point (position, normal, evaluation point); writes into `order`
/// the indices `0 .. n - 1` of the `n` points sorted along a Morton curve through their
/// bounding box (ties by index), so that points near each other in the order lie near each
/// other in space. `count` is `n`, or -1 (nothing written) when `points` is not a multiple of 9
/// or `order` has room for fewer than `n`.
///
/// # Safety
/// The arrays are valid for their lengths and `count` for one word (the occam ABI).
pub unsafe extern "C" fn points_order(
    points: *const f32,
    points_len: Word,
    order: *mut i32,
    order_len: Word,
    count: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (points, order) = unsafe { (array(points, points_len), array_mut(order, order_len)) };
    let n = points.len() / 9;
    let written = if points.len() % 9 == 0 && order.len() >= n && n <= i32::MAX as usize {
        let codes = morton_codes(points, 9);
        let mut sorted: Vec<usize> = (0..n).collect();
        sorted.sort_by_key(|&i| (codes[i], i));
        for (slot, i) in order.iter_mut().zip(sorted) {
            *slot = i as i32;
        }
        n as Word
    } else {
        -1
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *count = written };
}

#[cfg(test)]
mod test {
    use super::*;

    fn order(points: &[f32], room: usize) -> (Word, Vec<i32>) {
        let mut out = vec![-7; room];
        let mut count = 0;
        // SAFETY: valid slices and result.
        unsafe {
            points_order(
                points.as_ptr(),
                points.len() as Word,
                out.as_mut_ptr(),
                out.len() as Word,
                &mut count,
            )
        };
        (count, out)
    }

    /// A point at `p` (normal and evaluation point after it).
    fn at(p: [f32; 3]) -> [f32; 9] {
        [p[0], p[1], p[2], 0.0, 0.0, 1.0, p[0], p[1], p[2]]
    }

    #[test]
    fn spread_moves_each_bit_two_apart() {
        assert_eq!(spread(0b1011), 0b1_000_001_001);
        assert_eq!(spread((1 << BITS) - 1).count_ones(), BITS);
        assert_eq!(spread(1 << (BITS - 1)), 1 << (3 * (BITS - 1)));
    }

    #[test]
    fn points_in_two_far_clusters_come_cluster_by_cluster() {
        // Interleaved: even indices near the origin, odd ones near (100, 100, 100).
        let points: Vec<f32> = (0..40)
            .flat_map(|i| {
                let base = if i % 2 == 0 { 0.0 } else { 100.0 };
                at([base + (i % 5) as f32, base + (i % 3) as f32, base])
            })
            .collect();
        let (count, order) = order(&points, 40);
        assert_eq!(count, 40);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..40).collect::<Vec<_>>(), "a permutation");
        let cluster = |i: &i32| i % 2;
        let switches = order
            .windows(2)
            .filter(|w| cluster(&w[0]) != cluster(&w[1]))
            .count();
        assert_eq!(switches, 1, "{order:?}");
    }

    #[test]
    fn a_line_of_points_comes_in_order_along_it() {
        let points: Vec<f32> = [3.0, 0.0, 2.0, 1.0]
            .into_iter()
            .flat_map(|x| at([x, 5.0, 5.0]))
            .collect();
        assert_eq!(order(&points, 4), (4, vec![1, 3, 2, 0]));
    }

    #[test]
    fn bad_lengths_write_nothing() {
        let points: Vec<f32> = at([1.0, 2.0, 3.0])
            .into_iter()
            .chain(at([0.0; 3]))
            .collect();
        assert_eq!(order(&points[..17], 2), (-1, vec![-7, -7]));
        assert_eq!(order(&points, 1), (-1, vec![-7]));
        let nan = at([f32::NAN, 0.0, 0.0]);
        assert_eq!(order(&nan, 1), (1, vec![0]));
        assert_eq!(order(&[], 0), (0, vec![]));
    }
}
