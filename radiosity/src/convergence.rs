//! Error against run time, whatever the solver: when to record a row of the convergence record
//! ([`Cadence`]) and the error of a solution's per-object means against a reference
//! ([`Errors::of`]).
//!
//! Both take plain numbers (seconds, shots, each object's area and mean radiosity), so the
//! reference solver and carm.occ (which reports its irradiance to the host) record the same rows
//! the same way.
//!
//! The error of object `o` in channel `c` is relative: `|B_oc - R_oc| / R_oc`. A channel in which
//! the reference has no light at all is left out; an object whose reference is below
//! [`DARK`] times the brightest object's (in that channel) is measured against that floor, so
//! that a nearly black object does not dominate with a huge relative error of a tiny value. The
//! RMS is area-weighted over objects and channels; the maximum is over both.

use glam::DVec3;
use serde::Serialize;

/// References below this fraction of the brightest object's (per channel) count as this
/// fraction: the floor of a relative error's denominator.
pub const DARK: f64 = 1e-6;

/// The error of one solution against a reference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Errors {
    /// Area-weighted RMS of the relative errors over objects and channels.
    pub rms: f64,
    /// The largest relative error of any object in any channel.
    pub max: f64,
    /// Area-weighted RMS of the relative errors over objects, per channel.
    pub rms_channel: [f64; 3],
    /// The largest relative error per channel.
    pub max_channel: [f64; 3],
    /// Each object's relative error per channel (`None`: no reference for it; `NaN`: the
    /// reference has no light in that channel).
    pub objects: Vec<Option<[f64; 3]>>,
}

impl Errors {
    /// The errors of `means` (each object's area and mean B) against `reference` (each object's
    /// mean B, `None` where the reference lacks the object); `None` when no object with area has
    /// a reference with light in some channel.
    pub fn of(means: &[(f64, DVec3)], reference: &[Option<DVec3>]) -> Option<Errors> {
        let brightest = reference
            .iter()
            .flatten()
            .fold(DVec3::ZERO, |m, r| m.max(r.abs()));
        let objects: Vec<Option<[f64; 3]>> = means
            .iter()
            .zip(reference)
            .map(|((_, b), r)| {
                r.map(|r| {
                    std::array::from_fn(|c| {
                        if brightest[c] > 0.0 {
                            (b[c] - r[c]).abs() / r[c].abs().max(DARK * brightest[c])
                        } else {
                            f64::NAN
                        }
                    })
                })
            })
            .collect();
        let mut sum = [0.0f64; 3];
        let mut weight = [0.0f64; 3];
        let mut max_channel = [0.0f64; 3];
        for ((area, _), e) in means.iter().zip(&objects) {
            let Some(e) = e else { continue };
            for c in 0..3 {
                if e[c].is_finite() && *area > 0.0 {
                    sum[c] += area * e[c] * e[c];
                    weight[c] += area;
                    max_channel[c] = max_channel[c].max(e[c]);
                }
            }
        }
        let total: f64 = weight.iter().sum();
        if total <= 0.0 {
            return None;
        }
        let rms_channel = std::array::from_fn(|c| {
            if weight[c] > 0.0 {
                (sum[c] / weight[c]).sqrt()
            } else {
                0.0
            }
        });
        Some(Errors {
            rms: (sum.iter().sum::<f64>() / total).sqrt(),
            max: max_channel.iter().copied().fold(0.0, f64::max),
            rms_channel,
            max_channel,
            objects,
        })
    }
}

/// When to record a row: at regular intervals of `every` seconds, and at shots 1, 2, 4, 8, ...
/// so that the start of a run shows on a log time axis. The last row of a run is recorded by
/// the caller whatever the cadence.
#[derive(Clone, Copy, Debug)]
pub struct Cadence {
    every: f64,
    next_seconds: f64,
    next_shots: u64,
}

impl Cadence {
    /// A row every `every` seconds (0: every shot).
    pub fn new(every: f64) -> Cadence {
        Cadence {
            every: every.max(0.0),
            next_seconds: every.max(0.0),
            next_shots: 1,
        }
    }

    /// Whether a row is due after `shots` shots at `seconds`; when it is, the next one is
    /// scheduled.
    pub fn due(&mut self, shots: u64, seconds: f64) -> bool {
        let by_time = seconds >= self.next_seconds;
        let by_shots = shots >= self.next_shots;
        if by_time {
            // The next interval boundary after now (a slow shot can span several).
            let passed = if self.every > 0.0 {
                (seconds / self.every).floor() + 1.0
            } else {
                0.0
            };
            self.next_seconds = passed * self.every;
        }
        while shots >= self.next_shots {
            self.next_shots = self.next_shots.saturating_mul(2);
        }
        by_time || by_shots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_relative_area_weighted_and_skip_what_has_no_reference() {
        let means = [
            (3.0, DVec3::new(1.1, 2.0, 0.0)),
            (1.0, DVec3::new(0.5, 2.0, 0.0)),
            (5.0, DVec3::new(9.0, 9.0, 9.0)),
        ];
        let reference = [
            Some(DVec3::new(1.0, 2.0, 0.0)),
            Some(DVec3::new(1.0, 2.0, 0.0)),
            None,
        ];
        let e = Errors::of(&means, &reference).expect("errors");
        // Red: 10% on area 3, 50% on area 1; green exact; blue has no light in the reference.
        let red = ((3.0 * 0.01 + 0.25) / 4.0f64).sqrt();
        assert!((e.rms_channel[0] - red).abs() < 1e-12, "{e:?}");
        assert_eq!(e.rms_channel[1], 0.0);
        assert!((e.rms - ((3.0 * 0.01 + 0.25) / 8.0f64).sqrt()).abs() < 1e-12);
        assert!((e.max - 0.5).abs() < 1e-12);
        assert!(e.objects[0].unwrap()[2].is_nan() && e.objects[2].is_none());
    }

    #[test]
    fn no_reference_no_errors() {
        let means = [(1.0, DVec3::ONE)];
        assert_eq!(Errors::of(&means, &[None]), None);
        assert_eq!(Errors::of(&means, &[Some(DVec3::ZERO)]), None);
    }

    #[test]
    fn a_dark_object_is_measured_against_the_floor() {
        let means = [(1.0, DVec3::splat(1.0)), (1.0, DVec3::splat(2e-6))];
        let reference = [Some(DVec3::splat(1.0)), Some(DVec3::splat(1e-9))];
        let e = Errors::of(&means, &reference).expect("errors");
        assert!((e.max - (2e-6 - 1e-9) / 1e-6).abs() < 1e-9, "{e:?}");
    }

    #[test]
    fn the_cadence_records_doubling_shots_and_regular_times() {
        let mut c = Cadence::new(1.0);
        let rows: Vec<u64> = (1..=40u64).filter(|&s| c.due(s, s as f64 * 0.1)).collect();
        // Shots 1, 2, 4, 8, 16, 32, and every second (shots 10, 20, 30, 40).
        assert_eq!(rows, vec![1, 2, 4, 8, 10, 16, 20, 30, 32, 40]);
        let mut every_shot = Cadence::new(0.0);
        assert!((1..=5).all(|s| every_shot.due(s, 0.0)));
    }
}
