//! The error estimate behind `--until error=F`, as pure functions of a solve's tallies, so that
//! the reference solver ([`crate::solver::Solver::estimated_errors`]) and carm.occ's controller
//! (through `RAD.ERROR.REACHED`, which passes the tallies it keeps) stop on the same rule.
//!
//! The power still unshot is assumed to land evenly (the ambient irradiance, Cohen et al. 1988,
//! corrected for open scenes); each object's estimated relative error is that ambient term's
//! share of its mean radiosity. That holds for power held by patches that have shot; a patch
//! that never has gives its power to its neighbours, so both solvers shoot every such patch
//! once before they stop on this rule ([`crate::solver::Solver::run`]).

use glam::{DVec3, Vec3};

/// `Until::Error(f)` stops when the estimated error is at most `ERROR_MARGIN × f`. The estimate
/// spreads the unshot power evenly; in a room lit only through a doorway, which gets less than
/// its share, the true deficit came out 1.1 times the estimate (`tests/accuracy.rs`), so the rule
/// keeps a factor of two in hand.
pub const ERROR_MARGIN: f64 = 0.5;

/// A solve's running totals, per channel, over every shot so far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tally {
    /// The surfaces' total area (the elements').
    pub total_area: f64,
    /// Their area-weighted mean reflectance.
    pub rho_avg: DVec3,
    /// The power not yet shot, summed over patches: for the error estimate their magnitudes
    /// (a bound on what is still to come where overshooting made some negative).
    pub unshot: DVec3,
    /// The power shot.
    pub shot: DVec3,
    /// The part of it the surfaces received.
    pub received: DVec3,
    /// The part of that they absorbed.
    pub absorbed: DVec3,
}

impl Tally {
    /// The received share `c` of shot power and the reflected share `r` of received power, per
    /// channel, each in [0, 1]; before the first shot `c = 1` and `r = ρ_avg`.
    pub fn closure(&self) -> (DVec3, DVec3) {
        let pick = |num: f64, den: f64, default: f64| if den > 0.0 { num / den } else { default };
        let c = DVec3::from_array(std::array::from_fn(|i| {
            pick(self.received[i], self.shot[i], 1.0)
        }));
        let r = DVec3::from_array(std::array::from_fn(|i| {
            pick(
                self.received[i] - self.absorbed[i],
                self.received[i],
                self.rho_avg[i],
            )
        }));
        (
            c.clamp(DVec3::ZERO, DVec3::ONE),
            r.clamp(DVec3::ZERO, DVec3::ONE),
        )
    }

    /// The ambient irradiance: where the unshot power would still go, spread evenly over the
    /// surfaces. Cohen et al. (1988) take `Σ unshot / Σ A × 1 / (1 - ρ_avg)`, which holds in a
    /// closed scene; here the share of shot power that surfaces have received so far (`c`, below
    /// 1 when the scene is open) and the share of that they reflected (`r`) stand for the
    /// closure and the reflectance: `c Σ unshot / Σ A × 1 / (1 - c r)`.
    pub fn ambient(&self) -> Vec3 {
        let (c, r) = self.closure();
        let spread = self.unshot * c / self.total_area;
        (spread / (DVec3::ONE - c * r).max(DVec3::splat(1e-6))).as_vec3()
    }
}

/// One object's estimated relative error: the ambient term's share of its mean radiosity,
/// `ρ H_amb / (B + ρ H_amb)`, worst channel; 0 for an object with no area or reflectance. `b`
/// is its area-weighted mean radiosity without the ambient term.
pub fn object_error(area: f64, b: DVec3, reflectance: DVec3, ambient: Vec3) -> f64 {
    let missing = reflectance * ambient.as_dvec3();
    (0..3)
        .filter(|&c| area > 0.0 && missing[c] > 0.0)
        .map(|c| missing[c] / (b[c] + missing[c]))
        .fold(0.0, f64::max)
}

/// Whether the worst of the estimated `errors` meets the target `f` of `--until error=F`.
pub fn reached(errors: impl IntoIterator<Item = f64>, f: f64) -> bool {
    errors.into_iter().fold(0.0, f64::max) <= ERROR_MARGIN * f
}

#[cfg(test)]
mod tests {
    use super::*;

    fn closed_box(shot: f64, received: f64, absorbed: f64) -> Tally {
        Tally {
            total_area: 6.0,
            rho_avg: DVec3::splat(0.5),
            unshot: DVec3::splat(3.0),
            shot: DVec3::splat(shot),
            received: DVec3::splat(received),
            absorbed: DVec3::splat(absorbed),
        }
    }

    #[test]
    fn before_the_first_shot_the_ambient_is_cohens() {
        // Σ unshot / Σ A / (1 - ρ_avg) = 3 / 6 / 0.5 = 1.
        let a = closed_box(0.0, 0.0, 0.0).ambient();
        assert!((a - Vec3::ONE).abs().max_element() < 1e-6, "{a}");
    }

    #[test]
    fn an_open_scene_counts_only_what_its_surfaces_receive() {
        // Half the shot power escapes and half of what is received is reflected:
        // c = 0.5, r = 0.5: 0.5 × 3 / 6 / (1 - 0.25) = 1/3.
        let a = closed_box(2.0, 1.0, 0.5).ambient();
        assert!(
            (a - Vec3::splat(1.0 / 3.0)).abs().max_element() < 1e-6,
            "{a}"
        );
    }

    #[test]
    fn the_error_is_the_ambient_share_of_the_radiosity() {
        // ρ H_amb = 0.5 × 1 against B = 1.5: 0.5 / 2 = 0.25 on the worst channel.
        let e = object_error(1.0, DVec3::new(1.5, 3.0, 3.0), DVec3::splat(0.5), Vec3::ONE);
        assert!((e - 0.25).abs() < 1e-12, "{e}");
        assert_eq!(object_error(0.0, DVec3::ZERO, DVec3::ONE, Vec3::ONE), 0.0);
        assert_eq!(object_error(1.0, DVec3::ZERO, DVec3::ZERO, Vec3::ONE), 0.0);
        assert!(reached([0.25, 0.1], 0.5) && !reached([0.26], 0.5));
    }
}
