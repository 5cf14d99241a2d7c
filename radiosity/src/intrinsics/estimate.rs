//! `RAD.ERROR.REACHED`: the stopping rule of `--until error=F` ([`crate::estimate`]) for a
//! controller that keeps the tallies itself (carm.occ's), so that it stops where the reference
//! solver would; `RAD.OVERSHOOT.AMBIENT`: the ambient irradiance such a controller overshoots
//! by ([`crate::overshoot`]), when it does.

use glam::DVec3;
use occ_runtime::abi::Word;

use super::array;
use crate::estimate::{Tally, object_error, reached};
use crate::overshoot::Acceleration;

/// REAL64s per object in `RAD.ERROR.REACHED`'s `objects`: area, mean radiosity without the
/// ambient term (RGB), reflectance (RGB).
pub const OBJECT_REALS: usize = 7;

/// REAL64s in `RAD.ERROR.REACHED`'s `tally`: total area, mean reflectance (RGB), unshot,
/// shot, received and absorbed power (RGB each), the fields of [`Tally`] in order.
pub const TALLY_REALS: usize = 16;

/// `PROC RAD.ERROR.REACHED (VAL []REAL64 objects, VAL []REAL64 tally, VAL REAL64 target,
/// RESULT INT verdict)`: 1 when every object's estimated relative error meets `target` (the F
/// of `--until error=F`, with the reference solver's margin), 0 when not, -1 when `objects` is
/// not [`OBJECT_REALS`] per object or `tally` not [`TALLY_REALS`] long.
///
/// # Safety
/// The arrays are valid for their lengths and `verdict` for one word (the occam ABI).
pub unsafe extern "C" fn error_reached(
    objects: *const f64,
    objects_len: Word,
    tally: *const f64,
    tally_len: Word,
    target: f64,
    verdict: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let (objects, tally) = unsafe { (array(objects, objects_len), array(tally, tally_len)) };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *verdict = judge(objects, tally, target) };
}

/// The [`Tally`] laid out as [`TALLY_REALS`] REAL64s, or `None` for another length.
fn tally_of(reals: &[f64]) -> Option<Tally> {
    if reals.len() != TALLY_REALS {
        return None;
    }
    let rgb = |at: usize| DVec3::from_slice(&reals[at..at + 3]);
    Some(Tally {
        total_area: reals[0],
        rho_avg: rgb(1),
        unshot: rgb(4),
        shot: rgb(7),
        received: rgb(10),
        absorbed: rgb(13),
    })
}

fn judge(objects: &[f64], tally: &[f64], target: f64) -> Word {
    let Some(tally) = tally_of(tally).filter(|_| objects.len().is_multiple_of(OBJECT_REALS)) else {
        return -1;
    };
    let ambient = tally.ambient();
    let errors = objects.chunks_exact(OBJECT_REALS).map(|o| {
        object_error(
            o[0],
            DVec3::from_slice(&o[1..4]),
            DVec3::from_slice(&o[4..7]),
            ambient,
        )
    });
    Word::from(reached(errors, target))
}

/// `PROC RAD.OVERSHOOT.AMBIENT (VAL []REAL64 tally, VAL INT acceleration, []REAL64 ambient,
/// RESULT INT active)`: whether a solve with these tallies ([`TALLY_REALS`] REAL64s as for
/// `RAD.ERROR.REACHED`, but the unshot power summed with its signs) overshoots its next shot
/// under `acceleration` (0 off, 1 always, 2 auto: while the scene is stiff), as
/// [`Acceleration::active`] decides, and by which ambient irradiance (RGB, written to
/// `ambient` when active): the reference solver's. `active` is 1 or 0, or -1 (nothing written)
/// for a wrong length or mode.
///
/// # Safety
/// The arrays are valid for their lengths and `active` for one word (the occam ABI).
pub unsafe extern "C" fn overshoot_ambient(
    tally: *const f64,
    tally_len: Word,
    acceleration: Word,
    ambient: *mut f64,
    ambient_len: Word,
    active: *mut Word,
) {
    // SAFETY: the ABI passes valid arrays.
    let tally = unsafe { array(tally, tally_len) };
    let mode = match acceleration {
        0 => Some(Acceleration::Off),
        1 => Some(Acceleration::Ambient),
        2 => Some(Acceleration::Auto),
        _ => None,
    };
    let verdict = match (tally_of(tally), mode) {
        (Some(t), Some(mode)) if ambient_len >= 3 => {
            let (c, r) = t.closure();
            if mode.active(c * r) {
                // SAFETY: `ambient` is valid for `ambient_len` >= 3 REAL64s.
                let out = unsafe { std::slice::from_raw_parts_mut(ambient, 3) };
                out.copy_from_slice(&t.ambient().as_dvec3().to_array());
                1
            } else {
                0
            }
        }
        _ => -1,
    };
    // SAFETY: the ABI passes a valid result address.
    unsafe { *active = verdict };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box before its first shot: ambient 1 (see `estimate`), one object of radiosity
    /// 1.5 and reflectance 0.5: estimated error 0.25.
    const TALLY: [f64; TALLY_REALS] = [
        6.0, 0.5, 0.5, 0.5, 3.0, 3.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    ];
    const OBJECT: [f64; OBJECT_REALS] = [1.0, 1.5, 1.5, 1.5, 0.5, 0.5, 0.5];

    #[test]
    fn judges_as_the_solver_does() {
        // Reached when 0.25 <= margin × target.
        assert_eq!(judge(&OBJECT, &TALLY, 0.5), 1);
        assert_eq!(judge(&OBJECT, &TALLY, 0.4), 0);
    }

    #[test]
    fn wrong_lengths_answer_minus_one() {
        assert_eq!(judge(&OBJECT[..6], &TALLY, 0.5), -1);
        assert_eq!(judge(&OBJECT, &TALLY[..15], 0.5), -1);
        // No objects: nothing to be wrong about.
        assert_eq!(judge(&[], &TALLY, 0.5), 1);
    }
}
