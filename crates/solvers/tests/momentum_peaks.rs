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

/// With c_r < 1 the persistent-contact phases hold the floors with a force linear over each
/// held segment (at most a base step, shorter where `momentum.held_tolerance` asks), and
/// chattering is captured on the record step's scale, so the answer depends on the grid: on
/// the paper scene at 5 cm, c_r = 0.65, the 16× finer record moves the peaks by 7.6e-7
/// (measured; 100 against 176 impacts, 12 phases each; 6.7e-7 with constant forces, 4.4e-6
/// before the held tolerance). Asserted below 2e-6: a margin of 2.6 over the measured value,
/// and fails the 4.4e-6 measured before the held tolerance.
#[test]
fn grid_dependence_with_persistent_contact() {
    let coarse = paper(&["contacts.0.gap=0.05", "contacts.0.restitution=0.65"]);
    let mut fine = coarse.clone();
    fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
    let (a, b) = (solve(&coarse, None).unwrap(), solve(&fine, None).unwrap());
    let d = peak_difference(&a, &b);
    eprintln!(
        "c_r = 0.65, 5 cm: impacts {} / {}, phases {} / {}, largest peak difference {d:.2e}",
        a.impacts.len(),
        b.impacts.len(),
        a.persistent_contacts.len(),
        b.persistent_contacts.len(),
    );
    // The scene holds contacts on both grids (what makes it grid-dependent).
    assert!(!a.persistent_contacts.is_empty() && !b.persistent_contacts.is_empty());
    assert!(d < 2e-6, "peaks differ by {d:.2e}");
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

/// A record step longer than a quarter of the shortest kept period is split into equal base
/// steps: the same run, to the last bit, as the record resampled by hand (`refined`).
#[test]
fn a_long_record_step_is_split_as_a_resampled_record_would_be() {
    // Record step 0.02 s, shortest kept period 0.0349 s: 4 × 0.02 / 0.0349 → 3 parts.
    let coarse = paper(&[
        "ground_motion.file=../../data/ground-motions/near-field/RSN1086_NORTHR-SYL_032.AT2",
        "contacts.0.gap=0.03",
    ]);
    let p = solvers::momentum::Problem::new(&coarse).unwrap();
    assert_eq!((p.split, p.h), (3, 0.02 / 3.0));
    let mut fine = coarse.clone();
    fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 3));
    assert_eq!(solvers::momentum::Problem::new(&fine).unwrap().split, 1);
    let (a, b) = (solve(&coarse, None).unwrap(), solve(&fine, None).unwrap());
    assert!(
        a.settings.contains("(record step in 3 parts, "),
        "{}",
        a.settings
    );
    assert!(!a.impacts.is_empty());
    assert_eq!(a.impacts.len(), b.impacts.len());
    for (x, y) in a.impacts.iter().zip(&b.impacts) {
        assert_eq!(x.time.to_bits(), y.time.to_bits());
    }
    for (ba, bb) in a.buildings.iter().zip(&b.buildings) {
        assert_eq!(ba.story_shear_max, bb.story_shear_max);
        assert_eq!(ba.floor_displacement_max, bb.floor_displacement_max);
    }
    // The paper's own record (0.005 s, ≥ 7 steps per kept period) is not split.
    assert_eq!(
        solvers::momentum::Problem::new(&paper(&[])).unwrap().split,
        1
    );
}

/// Stiff stories whose shortest period (0.0045 s for stories of 1e12 N/m, about 0.009 s for a roof
/// story of 5e11 N/m) is below a quarter of the record step (0.02 s): the record step is split
/// (in 18 and 9 parts), and the peaks are those of the record resampled 16× finer and of the
/// impulse method. Taken
/// whole, such steps hid the extrema of the modes the impacts set ringing: these peaks came
/// out 48 %, 66 % and 14 % low (one, 24 and 8 impacts), measured when the split was added.
#[test]
fn peaks_of_stiff_stories_under_a_coarse_record_are_continuous() {
    let stiff_left = [
        "buildings.0.target_frequencies_hz=",
        "buildings.0.story_stiffness=1e12",
    ];
    let stiff_roof = [
        "buildings.1.target_frequencies_hz=",
        "buildings.1.story_stiffness=[1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, 1e9, \
         1e9, 1e9, 1e9, 5e11]",
    ];
    for (record, stiff, gap, impacts, split) in [
        ("RSN828_CAPEMEND-PET_260", stiff_left, "0.15", 1, 18),
        ("RSN1086_NORTHR-SYL_032", stiff_left, "0.2", 24, 18),
        ("RSN828_CAPEMEND-PET_260", stiff_roof, "0.3", 8, 9),
    ] {
        let file = format!("ground_motion.file=../../data/ground-motions/near-field/{record}.AT2");
        let gap = format!("contacts.0.gap={gap}");
        let coarse = paper(&[file.as_str(), stiff[0], stiff[1], gap.as_str()]);
        let mut fine = coarse.clone();
        fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
        let p = solvers::momentum::Problem::new(&coarse).unwrap();
        assert_eq!(p.split, split, "{record} {gap}");
        let (a, b) = (solve(&coarse, None).unwrap(), solve(&fine, None).unwrap());
        assert_eq!(
            (a.impacts.len(), b.impacts.len()),
            (impacts, impacts),
            "{record} {gap}"
        );
        let d = peak_difference(&a, &b);
        eprintln!("{record} {gap}: split {}, {d:.2e}", p.split);
        // Exact method on both grids (measured up to 7.6e-13).
        assert!(d < 1e-11, "{record} {gap}: peaks differ by {d:.2e}");
        // An independent method: the impulse method (physical coordinates, Dormand–Prince
        // with error control, the same impact law) at rtol 1e-10 finds the same impacts and
        // peaks within 100 rtol (measured up to 3.8e-9; 3.3e-7 at rtol 1e-8).
        let mut tight = coarse.clone();
        tight.gap_element.tolerance = 1e-10;
        let c = solvers::run(&tight, solvers::Method::Impulse, None).unwrap();
        assert_eq!(c.impacts.len(), impacts, "{record} {gap}");
        let d = peak_difference(&a, &c);
        assert!(
            d < 1e-8,
            "{record} {gap}: momentum and impulse differ by {d:.2e}"
        );
    }
}

/// How much the energy envelope skips, pinned (building samples over an interval, of them
/// skipped, overlap audits skipped) on three scenes: the counts are deterministic (exact
/// operations, one thread), and a change that stops the envelope from skipping (it would
/// leave every peak as it is, `energy_envelope_skip_leaves_every_peak_unchanged`) shows only
/// here and in the benchmarks.
#[test]
fn energy_envelope_skip_counts_are_pinned() {
    let cases = [
        (paper(&["contacts.0.gap=0.10"]), [16102, 4933, 2849]),
        (paper(&["contacts.0.gap=0.05"]), [16224, 4314, 2172]),
        // A contact at every facing floor: no pair to audit.
        (
            structure::testing::paper_scene_aligned(&["contacts.0.gap=0.05"]),
            [16184, 3277, 0],
        ),
    ];
    for (s, want) in cases {
        let (_, d) = solvers::momentum::solve_with_diagnostics(&s, None).unwrap();
        let got = [
            d.building_samples,
            d.building_samples_skipped,
            d.overlap_audits_skipped,
        ];
        assert_eq!(got, want, "{}", s.name);
        // c_r = 1: no held phase, so no held-gap projection and no shortened held segment;
        // every impact on the contact surface (within 1.01 × the round-off band).
        assert_eq!(
            (d.gap_projections, d.held_subdivisions),
            (0, 0),
            "{}",
            s.name
        );
        assert!(
            d.impact_gap_ratio <= 1.01,
            "{}: {}",
            s.name,
            d.impact_gap_ratio
        );
    }
}

/// The overlap audit's envelope must bound u_left − u_right, whose running maximum the
/// tracker keeps, not the overlap u_left − u_right − gap. A resonant harmonic ground motion
/// and a 1 m gap (no impact): the pairs' maxima grow cycle after cycle, far below the gap.
/// An envelope that compared the bound with maximum + gap would skip the audit from the first
/// cycles on and freeze the maxima (a build with that rule failed here); the maxima must be
/// those of the run that observes every sample (with a history).
#[test]
fn overlap_maxima_under_resonance_are_those_of_every_sample() {
    let mut s = paper(&["contacts.0.gap=1.0", "analysis.duration=20"]);
    let w = solvers::momentum::Problem::new(&s).unwrap().modal.omega[0];
    let dt = 0.005;
    let accel = (0..=4000)
        .map(|i| 0.5 * (w * i as f64 * dt).sin())
        .collect();
    s.ground = Some(structure::GroundMotion::new("resonant sine", dt, accel).unwrap());
    let (plain, d) = solvers::momentum::solve_with_diagnostics(&s, None).unwrap();
    let mut h = solvers::History::default();
    let full = solve(&s, Some(&mut h)).unwrap();
    assert!(plain.impacts.is_empty());
    assert_eq!(plain.overlaps.len(), 14);
    for (a, b) in plain.overlaps.iter().zip(&full.overlaps) {
        assert_eq!((a.max_overlap, a.time), (b.max_overlap, b.time));
    }
    // The maxima kept growing: the largest is reached in the last 5 s.
    let last = plain
        .overlaps
        .iter()
        .map(|o| o.time)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(last > 15.0, "{last}");
    eprintln!(
        "audits skipped {} of {} samples; largest u_l - u_r - gap {:.3e} m at {last:.2} s",
        d.overlap_audits_skipped,
        d.building_samples / 2,
        plain
            .overlaps
            .iter()
            .map(|o| o.max_overlap)
            .fold(f64::NEG_INFINITY, f64::max)
    );
}
