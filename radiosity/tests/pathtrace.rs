//! The path tracer (the ground truth) against exact answers: the irradiance under a square light
//! (Lambert's contour integral, the catalogue closed forms: Howell C-11, Incropera Table 13.2), the closed furnace box
//! `B = E / (1 - ρ)`, and its own stored Cornell box reference. Tolerances are in standard errors
//! of the estimate under test (4σ: a correct estimator fails one check in about 16,000).

mod common;

use glam::Vec3;
use occ_radiosity::output::probe::Probe;
use occ_radiosity::pathtrace::{Estimate, PathTraceConfig, PathTracer};

/// Asserts `|estimate - exact| <= 4σ` per channel, and that σ is below `max_rel` of the value
/// (so that the check has teeth).
fn assert_within(what: &str, e: &Estimate, exact: [f64; 3], max_rel: f64) {
    for ((&m, &s), &x) in e.mean.iter().zip(&e.std_err).zip(&exact) {
        assert!(
            s <= max_rel * x,
            "{what}: standard error {s} too large for {x}"
        );
        assert!((m - x).abs() <= 4.0 * s, "{what}: {m} ± {s}, exact {x}");
    }
}

#[test]
fn irradiance_under_a_square_light_matches_the_contour_integral() {
    // B = ρ π Lₑ F with F from the closed forms: 0.239456 under the centre of a unit square at
    // height 1, 0.138532 under a corner. The light is black and the floor sees nothing else.
    let scene = common::light_over_floor(2.0);
    let tracer = PathTracer::new(&scene);
    let config = PathTraceConfig {
        samples: 40_000,
        ..PathTraceConfig::default()
    };
    let probes = [
        (Vec3::new(0.0, 0.0, 0.0), 0.239456),
        (Vec3::new(0.5, 0.0, 0.5), 0.138532),
    ];
    let found = tracer.probes(
        &probes.map(|(pos, _)| Probe {
            pos,
            normal: Vec3::Y,
        }),
        &config,
    );
    for ((pos, f), e) in probes.iter().zip(found) {
        let e = e.expect("the probe lies on the floor");
        let exact = 0.5 * std::f64::consts::PI * f;
        assert_within(&format!("probe at {pos}"), &e, [exact; 3], 0.005);
    }
}

#[test]
fn closed_furnace_box_gives_e_over_one_minus_rho() {
    // Every face emits E = π Lₑ = 1 with ρ = 0.8: B = 5 everywhere, after many bounces.
    let scene = common::closed_box(Vec3::ZERO, Vec3::ONE, 0.8, |_| std::f32::consts::FRAC_1_PI);
    let tracer = PathTracer::new(&scene);
    let config = PathTraceConfig {
        samples: 60_000,
        ..PathTraceConfig::default()
    };
    for (i, e) in tracer.object_means(&config).iter().enumerate() {
        assert_within(&format!("face {i}"), e, [5.0; 3], 0.01);
    }
}

#[test]
fn a_light_with_nothing_to_see_keeps_only_its_emission() {
    // One face-down square light over nothing: B = π Lₑ exactly, no variance.
    let mut scene = common::light_over_floor(2.0);
    scene.triangles.truncate(2);
    scene.objects.truncate(1);
    let tracer = PathTracer::new(&scene);
    let e = tracer.object_means(&PathTraceConfig {
        samples: 100,
        ..PathTraceConfig::default()
    })[0];
    for c in 0..3 {
        assert!((e.mean[c] - std::f64::consts::PI).abs() < 1e-12, "{e:?}");
        assert!(e.std_err[c] < 1e-12, "{e:?}");
    }
}
