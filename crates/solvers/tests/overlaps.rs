//! The overlap audit (issue 11): facing floors without a contact of their own, and how far
//! they pass through each other beyond the gap.
//!
//! - the momentum method's maxima are continuous (closed form between samples): resampling
//!   the record 16× finer (the same piecewise-linear excitation) must not move them beyond
//!   round-off, and they are never below any history sample;
//! - the paper scene with its roof-only contact overlaps at mid-height floors, and the gap
//!   element converges to the momentum method's overlaps as k^-1/2 (penetration of a penalty
//!   spring ∝ v √(m/k));
//! - with `floors = "aligned"` every facing pair has a contact: nothing to audit.

mod common;
use common::log_log_slope;
use solvers::{gap, momentum, History, Overlap, RunOutput};
use structure::testing::{paper_scene as paper, paper_scene_aligned as paper_aligned, refined};

fn floor_pairs(o: &[Overlap]) -> Vec<(usize, usize)> {
    o.iter().map(|o| (o.left_floor, o.right_floor)).collect()
}

#[test]
fn momentum_overlap_maxima_are_continuous() {
    for over in [
        vec!["contacts.0.gap=0.10"],
        vec!["contacts.0.gap=0.05"],
        vec![
            "ground_motion.file=../../data/ground-motions/near-field/RSN1048_NORTHR-STC_122.AT2",
            "contacts.0.gap=0.03",
        ],
        // A maximum inside one sample interval whose rate has one sign at both ends (the
        // pair turns twice; defect 19): floor pair 12 near 13.25 s, 0.10612613618 m, which
        // the audit missed before, reporting 0.10612612505 m (1.05e-7 low; the modes
        // study's GAZLI case with 13 modes per building).
        vec![
            "ground_motion.file=../../data/ground-motions/near-field/RSN126_GAZLI-GAZ_267.AT2",
            "momentum.modes=13",
        ],
    ] {
        let coarse = paper(&over);
        let mut fine = coarse.clone();
        fine.ground = Some(refined(coarse.ground.as_ref().unwrap(), 16));
        let mut hist = History::default();
        let a = momentum::solve(&coarse, Some(&mut hist)).unwrap();
        let b = momentum::solve(&fine, None).unwrap();
        assert_eq!(
            floor_pairs(&a.overlaps),
            (1..=14).map(|i| (i, i)).collect::<Vec<_>>()
        );
        assert_eq!(floor_pairs(&a.overlaps), floor_pairs(&b.overlaps));
        let gap = coarse.contacts[0].gap;
        let mut interior = 0;
        for (k, (x, y)) in a.overlaps.iter().zip(&b.overlaps).enumerate() {
            assert_eq!((x.gap, x.contact), (gap, 0));
            // Relative to the relative displacement u_left − u_right at the maximum.
            let (rx, ry) = (x.max_overlap + gap, y.max_overlap + gap);
            // Round-off only (both pass at 1e-12): 1e-11 relative, 1e-9 s for the instant
            // (a flat maximum's instant is less well defined than its value).
            let d = (rx - ry).abs() / ry.abs();
            assert!(
                d < 1e-11,
                "{over:?} floor {}: {rx} vs {ry} ({d:.2e})",
                k + 1
            );
            assert!(
                (x.time - y.time).abs() < 1e-9,
                "{over:?}: {} vs {}",
                x.time,
                y.time
            );
            // Never below a history sample of the same run; above the best sample where the
            // maximum falls between samples.
            let sampled = hist
                .displacement
                .iter()
                .map(|row| row[k] - row[15 + k])
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(
                rx >= sampled - 1e-15 * rx.abs(),
                "{over:?}: {rx} < sampled {sampled}"
            );
            if rx > sampled * (1.0 + 1e-12) {
                interior += 1;
            }
        }
        assert!(interior > 0, "{over:?}: every maximum fell on a sample");
    }
}

#[test]
fn paper_scene_roof_only_overlaps_at_mid_height_and_the_gap_element_converges_to_it() {
    let scene = paper(&[]);
    let m = momentum::solve(&scene, None).unwrap();
    assert_eq!(m.overlaps.len(), 14);
    assert!(m.unmodelled.is_empty());
    let positive: Vec<usize> = m
        .overlaps
        .iter()
        .filter(|o| o.max_overlap > 0.0)
        .map(|o| o.left_floor)
        .collect();
    eprintln!(
        "momentum: {:?}",
        m.overlaps
            .iter()
            .map(|o| (o.left_floor, o.max_overlap))
            .collect::<Vec<_>>()
    );
    // A contiguous block of floors above the lowest ones, the worst strictly inside it.
    assert!(!positive.is_empty());
    let (lo, hi) = (positive[0], *positive.last().unwrap());
    assert_eq!(positive, (lo..=hi).collect::<Vec<_>>());
    assert!(lo > 1, "floor 1 (stiff, small drifts) should not overlap");
    let worst = solvers::overlap::worst(&m.overlaps).unwrap();
    assert!(worst.left_floor > lo && worst.left_floor < hi, "{worst:?}");
    // The gap element: its overlaps approach the momentum method's as k^-1/2 (a factor √10
    // per decade of stiffness).
    let run = |k: &str| -> RunOutput {
        gap::solve(&paper(&[&format!("gap_element.stiffness={k}")]), None).unwrap()
    };
    let (g12, g13, g14, g15) = (run("1e12"), run("1e13"), run("1e14"), run("1e15"));
    let err = |g: &RunOutput| -> Vec<f64> {
        assert_eq!(floor_pairs(&g.overlaps), floor_pairs(&m.overlaps));
        g.overlaps
            .iter()
            .zip(&m.overlaps)
            .map(|(a, b)| (a.max_overlap - b.max_overlap).abs())
            .collect()
    };
    let ks: [f64; 4] = [1e12, 1e13, 1e14, 1e15];
    let errs: Vec<f64> = [&g12, &g13, &g14, &g15]
        .iter()
        .map(|g| err(g).iter().cloned().fold(0.0, f64::max))
        .collect();
    eprintln!("gap element vs momentum, largest overlap difference at k = {ks:?}: {errs:?} m");
    // Every decade of stiffness brings it closer (measured ÷3.2 to ÷3.6).
    for w in errs.windows(2) {
        assert!(w[1] < w[0], "{errs:?}");
    }
    // Least-squares slope of log error against log k over three decades: −½ within
    // [−0.60, −0.40], which refuses k^-1/3, k^-2/3 and k^-1. Measured −0.534 (0.066 inside
    // the band); the two-point ratio from 1e12 to 1e14 it replaces (12.6) only allowed a
    // band of [4, 25] (slopes 0.3–0.7).
    let slope = log_log_slope(&ks, &errs);
    assert!(
        (-0.60..=-0.40).contains(&slope),
        "slope {slope:.3} over k = {ks:?} (errors {errs:?}), not the k^-1/2 rate"
    );
    // Same floors beyond the gap, same worst floor.
    let pos = |r: &RunOutput| -> Vec<usize> {
        r.overlaps
            .iter()
            .filter(|o| o.max_overlap > 0.0)
            .map(|o| o.left_floor)
            .collect()
    };
    assert_eq!(pos(&g14), positive);
    assert_eq!(
        solvers::overlap::worst(&g14.overlaps).unwrap().left_floor,
        worst.left_floor
    );
    // Newmark reports the maximum over its steps, with its own discretisation error: the
    // same floors, and overlaps within 1 mm of the adaptive element's at the same k
    // (measured up to 0.23 mm at Δt = 1 ms; overlaps of up to a few cm).
    let nm = gap::solve(
        &paper(&[
            "gap_element.stiffness=1e12",
            "gap_element.integrator=newmark",
            "gap_element.time_step=1e-3",
        ]),
        None,
    )
    .unwrap();
    assert_eq!(floor_pairs(&nm.overlaps), floor_pairs(&m.overlaps));
    assert_eq!(pos(&nm), positive);
    for (a, b) in nm.overlaps.iter().zip(&g12.overlaps) {
        let d = (a.max_overlap - b.max_overlap).abs();
        assert!(
            d < 1e-3,
            "floor {}: Newmark {} vs adaptive {}",
            a.left_floor,
            a.max_overlap,
            b.max_overlap
        );
    }
}

#[test]
fn aligned_floors_leave_nothing_to_audit() {
    let s = paper_aligned(&["analysis.duration=12"]);
    assert_eq!(s.contacts.len(), 15);
    let m = momentum::solve(&s, None).unwrap();
    assert!(m.overlaps.is_empty() && m.unmodelled.is_empty());
    let g = gap::solve(&s, None).unwrap();
    assert!(g.overlaps.is_empty());
    // Serialised as empty arrays (the `pound run --out` JSON).
    let v = serde_json::to_value(&m).unwrap();
    assert_eq!(v["overlaps"], serde_json::json!([]));
    assert_eq!(v["unmodelled"], serde_json::json!([]));
    let v = serde_json::to_value(momentum::solve(&paper(&[]), None).unwrap()).unwrap();
    let o = &v["overlaps"][7];
    for key in [
        "left",
        "left_floor",
        "right",
        "right_floor",
        "gap",
        "contact",
        "max_overlap",
        "time",
    ] {
        assert!(!o[key].is_null(), "{key} missing in {o}");
    }
}
