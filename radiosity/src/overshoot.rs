//! Overshooting for stiff scenes (reflectance near 1), after Feda and Purgathofer ("Accelerating
//! radiosity by overshooting", Eurographics Workshop on Rendering 1992).
//!
//! Progressive refinement is Southwell iteration (Gortler, Cohen, Slusallek 1993): in a closed
//! room of reflectance ρ each round of shots leaves about ρ of the unshot power, so reaching a
//! fraction `f` of it takes about `ln f / ln ρ` rounds: 460 for ρ = 0.99, 4,600 for ρ = 0.999.
//! What is slow is the mean: light bouncing back and forth, spread ever more evenly. The ambient
//! term of Cohen et al. (1988) estimates exactly that part, the irradiance `H_amb` still to come
//! ([`crate::solver::Solver::ambient`]). So a shooting patch sends, besides its unshot power,
//! the power it will reflect of that ambient, `ρ A H_amb`, now; its unshot power becomes that
//! amount negated, and the light it later receives pays it back. Where the estimate is right the
//! mean is solved in one round; where it is wrong the negative unshot power is shot like any
//! other, so the iteration still converges to the same solution (only the order of the shots
//! changes, not the fixed point).
//!
//! Contract with the solver (the hook in `Solver::shoot_once`): before a shot, the patch's
//! elements get [`element_amounts`] added to their unshot power (and the patch the sum); after
//! it, the same amounts are taken away. The energy accounts see both, so
//! `emitted = absorbed + escaped + unshot` still holds, with unshot power that may be negative.
//! Errors are of the solution itself: the overshoot changes what is shot, never what is shown.

use glam::DVec3;

/// Whether shots overshoot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Acceleration {
    /// Plain progressive refinement.
    Off,
    /// Every shot overshoots by the ambient estimate.
    Ambient,
    /// Overshoot while the scene is stiff: while the measured share of shot power that comes
    /// back as unshot power (received × reflected, [`crate::solver::Solver::reflected_share`])
    /// is at least [`AUTO_REFLECTED_SHARE`] in some channel.
    #[default]
    Auto,
}

impl std::str::FromStr for Acceleration {
    type Err = String;
    /// Parses `auto`, `ambient` or `off`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Acceleration::Auto),
            "ambient" => Ok(Acceleration::Ambient),
            "off" => Ok(Acceleration::Off),
            _ => Err(format!("`{s}`: expected auto, ambient or off")),
        }
    }
}

/// [`Acceleration::Auto`] overshoots when at least this share of the power shot comes back to be
/// shot again (a bounce series `1 / (1 - s)` of 2 or more). Below it plain shooting converges in
/// a few rounds and the ambient estimate (spread evenly) would misplace more than it saves: in
/// the open Cornell box (s about 0.35) overshooting took more shots to the same error.
pub const AUTO_REFLECTED_SHARE: f64 = 0.5;

impl Acceleration {
    /// Whether to overshoot now, given the measured share `reflected_share` (per channel) of
    /// shot power that comes back as unshot power.
    pub fn active(self, reflected_share: DVec3) -> bool {
        match self {
            Acceleration::Off => false,
            Acceleration::Ambient => true,
            Acceleration::Auto => reflected_share.max_element() >= AUTO_REFLECTED_SHARE,
        }
    }
}

/// The overshoot of a patch of reflectance `rho` and area `area` by the ambient irradiance
/// `ambient`: the power it will still reflect of it, `ρ A H_amb`. A patch shoots (and is
/// chosen by) its unshot power plus this.
pub fn patch_amount(rho: DVec3, area: f64, ambient: DVec3) -> DVec3 {
    rho * ambient * area
}

/// The overshoot of each element of a shooting patch: the power it will still reflect of the
/// ambient irradiance, `ρ_e A_e H_amb`, from `(reflectance, area)` per element.
pub fn element_amounts(ambient: DVec3, elements: &[(DVec3, f64)]) -> Vec<DVec3> {
    elements
        .iter()
        .map(|&(rho, area)| patch_amount(rho, area, ambient))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_overshoots_only_stiff_scenes() {
        assert!(!Acceleration::Auto.active(DVec3::new(0.3, 0.2, 0.1)));
        assert!(Acceleration::Auto.active(DVec3::new(0.3, 0.6, 0.1)));
        assert!(Acceleration::Ambient.active(DVec3::ZERO));
        assert!(!Acceleration::Off.active(DVec3::ONE));
    }

    #[test]
    fn amounts_are_reflectance_times_area_times_ambient() {
        let a = element_amounts(
            DVec3::new(2.0, 1.0, 0.0),
            &[(DVec3::splat(0.5), 3.0), (DVec3::new(1.0, 0.0, 1.0), 1.0)],
        );
        assert_eq!(
            a,
            vec![DVec3::new(3.0, 1.5, 0.0), DVec3::new(2.0, 0.0, 0.0)]
        );
    }
}
