//! Continuous peaks of the momentum method (issue 10): the same piecewise-linear ground
//! acceleration given on a 16× finer grid must not change any peak, since the method is
//! exact between events and its peaks are continuous maxima, not samples.

use solvers::momentum::solve;
use structure::testing::{paper_scene as paper, refined};

/// Largest relative difference of all peak story shears and floor displacements.
fn peak_difference(a: &solvers::RunOutput, b: &solvers::RunOutput) -> f64 {
    let mut worst: f64 = 0.0;
    for (ba, bb) in a.buildings.iter().zip(&b.buildings) {
        for (x, y) in ba.story_shear_max.iter().zip(&bb.story_shear_max).chain(
            ba.floor_displacement_max
                .iter()
                .zip(&bb.floor_displacement_max),
        ) {
            worst = worst.max((x - y).abs() / y.abs().max(f64::MIN_POSITIVE));
        }
    }
    worst
}

#[test]
fn peaks_do_not_move_when_the_record_is_resampled_16_times_finer() {
    for over in [
        vec!["contacts.0.gap=0.10"],
        vec!["contacts.0.gap=0.05"],
        vec![
            "ground_motion.file=../../data/ground-motions/near-field/RSN1048_NORTHR-STC_122.AT2",
            "contacts.0.gap=0.03",
        ],
    ] {
        let coarse = paper(&over);
        let mut fine = coarse.clone();
        fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
        let (a, b) = (solve(&coarse, None).unwrap(), solve(&fine, None).unwrap());
        assert_eq!(a.impacts.len(), b.impacts.len(), "{over:?}");
        let d = peak_difference(&a, &b);
        eprintln!("{over:?}: {d:.2e}");
        // Exact method, instants located to ~2ε·t: round-off only (measured up to 3.1e-13;
        // issue 10 asked for 1e-6 or better).
        assert!(d < 1e-11, "{over:?}: peaks differ by {d:.2e}");
    }
}

/// With c_r < 1 the persistent-contact phases hold the floors with a constant force over each
/// record sub-step, so the answer depends on the grid; how much is measured here, not
/// asserted to a tolerance (reported in the README).
#[test]
#[ignore = "measurement: cargo test --release -- --ignored --nocapture"]
fn grid_dependence_with_persistent_contact() {
    let coarse = paper(&["contacts.0.gap=0.05", "contacts.0.restitution=0.65"]);
    let mut fine = coarse.clone();
    fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
    let (a, b) = (solve(&coarse, None).unwrap(), solve(&fine, None).unwrap());
    eprintln!(
        "c_r = 0.65, 5 cm: impacts {} / {}, phases {} / {}, largest peak difference {:.2e}",
        a.impacts.len(),
        b.impacts.len(),
        a.persistent_contacts.len(),
        b.persistent_contacts.len(),
        peak_difference(&a, &b)
    );
}

/// The adaptive gap element takes its peaks from the dense output between steps: resampling
/// the record 16× finer changes its step sequence, so its peaks agree to the integration
/// tolerance (here 1e-10), not to round-off.
#[test]
fn gap_element_peaks_do_not_move_with_a_finer_record_beyond_its_tolerance() {
    for gap in ["0.10", "0.05"] {
        let coarse = paper(&[
            &format!("contacts.0.gap={gap}"),
            "gap_element.stiffness=1e10",
            "gap_element.tolerance=1e-10",
        ]);
        let mut fine = coarse.clone();
        fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
        let a = solvers::gap::solve(&coarse, None).unwrap();
        let b = solvers::gap::solve(&fine, None).unwrap();
        assert_eq!(a.impacts.len(), b.impacts.len());
        let d = peak_difference(&a, &b);
        eprintln!("gap element, {gap} m: {d:.2e}");
        // Within 10 × rtol (measured 2.5e-10).
        assert!(d < 1e-9, "gap {gap}: peaks differ by {d:.2e}");
    }
}

/// The observation skips a building whose energy envelope cannot reach any of its peaks
/// over an interval, except when a history is recorded (every sample is then observed).
/// The skip is exact: peaks, overlap maxima and their instants are bit-identical with and
/// without a history (paper scene at two gaps, and the aligned scene with its audit).
#[test]
fn energy_envelope_skip_leaves_every_peak_unchanged() {
    let scenes = [
        paper(&["contacts.0.gap=0.10"]),
        paper(&["contacts.0.gap=0.05"]),
        structure::testing::paper_scene_aligned(&["contacts.0.gap=0.05"]),
    ];
    for s in scenes {
        let plain = solve(&s, None).unwrap();
        let mut h = solvers::History::default();
        let full = solve(&s, Some(&mut h)).unwrap();
        assert!(!h.time.is_empty());
        for (a, b) in plain.buildings.iter().zip(&full.buildings) {
            assert_eq!(a.story_shear_max, b.story_shear_max, "{}", s.name);
            assert_eq!(
                a.floor_displacement_max, b.floor_displacement_max,
                "{}",
                s.name
            );
        }
        assert_eq!(plain.overlaps.len(), full.overlaps.len());
        for (a, b) in plain.overlaps.iter().zip(&full.overlaps) {
            assert_eq!(
                (a.max_overlap, a.time),
                (b.max_overlap, b.time),
                "{}",
                s.name
            );
        }
    }
}
