//! The naming scheme's assembly as an intrinsic: a node that holds a voxel's name block and
//! the triangles it names makes the voxel's flat block, which the walk reads
//! ([`crate::octree::flat::assemble`]).

use occ_runtime::abi::Word;

use super::{array, array_mut};
use crate::octree::flat::assemble;

/// `PROC RAD.VOXEL.ASSEMBLE (VAL []REAL32 named, VAL []REAL32 tris, []REAL32 block,
/// RESULT INT floats)`: the flat block of the voxel whose name block is `named`, from `tris`
/// (9 REAL32s a name, in name order; those of unused lanes are not read), into `block`;
/// `floats` is the block's length, or -1 (nothing written) when `named` is not a name block,
/// `tris` not 9 floats a name or `block` too short.
///
/// # Safety
/// The arrays are valid for their lengths and `floats` for one word (the occam ABI); `block`
/// does not overlap the others.
pub unsafe extern "C" fn voxel_assemble(
    named: *const f32,
    named_len: Word,
    tris: *const f32,
    tris_len: Word,
    block: *mut f32,
    block_len: Word,
    floats: *mut Word,
) {
    // SAFETY: the caller's contract.
    let (named, tris, block) = unsafe {
        (
            array(named, named_len),
            array(tris, tris_len),
            array_mut(block, block_len),
        )
    };
    let n = assemble(named, tris, block).map_or(-1, |n| n as Word);
    // SAFETY: the caller's contract.
    unsafe { *floats = n };
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::octree::flat::{NAMED_TRIANGLE_FLOATS, named_packets};
    use crate::octree::{Octree, OctreeConfig};
    use crate::scene::cornell;

    /// The triangles a name block names, in name order (zeros for unused lanes).
    fn named_triangles(named: &[f32], triangles: &[[f32; NAMED_TRIANGLE_FLOATS]]) -> Vec<f32> {
        let p = named_packets(named.len()).expect("a name block");
        named[named.len() - 4 * p..]
            .iter()
            .flat_map(|&t| {
                if t < 0.0 {
                    [0.0; NAMED_TRIANGLE_FLOATS]
                } else {
                    triangles[t as usize]
                }
            })
            .collect()
    }

    /// Calls `RAD.VOXEL.ASSEMBLE` on a name block and its triangles; returns its count.
    fn assemble(named: &[f32], triangles: &[f32], out: &mut [f32]) -> Word {
        let mut n: Word = 0;
        // SAFETY: the arrays are valid for their lengths, `n` for one word.
        unsafe {
            voxel_assemble(
                named.as_ptr(),
                named.len() as Word,
                triangles.as_ptr(),
                triangles.len() as Word,
                out.as_mut_ptr(),
                out.len() as Word,
                &mut n,
            );
        }
        n
    }

    #[test]
    fn every_voxel_assembles_bit_equal_to_the_hosts_block() {
        let fine = OctreeConfig {
            max_leaf: 4,
            max_depth: 9,
        };
        for config in [OctreeConfig::default(), fine] {
            let tris = cornell::grid_triangles(8).expect("cornell");
            let tree = Octree::build(&tris, config);
            let flat = tree.flat().expect("flat");
            let named = tree.named(&flat).expect("named");
            assert_eq!(named.voxels.len(), flat.voxel_count());
            assert!(named.triangles.len() <= tris.len());
            for (v, block) in named.voxels.iter().enumerate() {
                let gathered = named_triangles(block, &named.triangles);
                let want = flat.voxel(v);
                let mut out = vec![f32::NAN; want.len() + 3];
                let n = assemble(block, &gathered, &mut out);
                assert_eq!(n as usize, want.len(), "voxel {v}");
                let bits = |xs: &[f32]| xs.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&out[..want.len()]), bits(want), "voxel {v}");
                // the names' blocks are smaller than the blocks, whose triangles they name
                assert!(block.len() < want.len());
            }
        }
    }

    #[test]
    fn a_wrong_length_answers_minus_one_and_writes_nothing() {
        let tris = cornell::grid_triangles(4).expect("cornell");
        let tree = Octree::build(&tris, OctreeConfig::default());
        let flat = tree.flat().expect("flat");
        let named = tree.named(&flat).expect("named");
        let block = &named.voxels[0];
        let gathered = named_triangles(block, &named.triangles);
        let want = flat.voxel(0).len();
        let cases: [(&[f32], &[f32], usize); 4] = [
            (&block[1..], &gathered, want),
            (block, &gathered[1..], want),
            (block, &gathered, want - 1),
            (&[], &[], want),
        ];
        for (named, tris, room) in cases {
            let mut out = vec![7.0f32; room];
            let n = assemble(named, tris, &mut out);
            assert_eq!(n, -1);
            assert!(out.iter().all(|&x| x == 7.0));
        }
    }
}
