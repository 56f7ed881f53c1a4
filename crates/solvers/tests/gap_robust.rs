//! The gap element on scenes that used to stop it (issue 9): Newmark's Newton iteration at a
//! clamped dashpot, achieved restitution outside [0, 1], step counts of decimal inputs, and
//! scenes too stiff or too long for the chosen integrator.

use solvers::gap::solve;
use solvers::{RunOutput, SolverError};
use structure::scene::Integrator;
use structure::testing::paper_scene as paper;
use structure::testing::paper_scene_path;
use structure::Scene;

/// The paper scene with `base` overrides on near-field record `rec`, gap (m) and c_r.
fn near_field(base: &[&str], rec: &str, gap: &str, cr: &str) -> Scene {
    let mut o: Vec<String> = base.iter().map(|s| s.to_string()).collect();
    o.push(format!(
        "ground_motion.file=../../data/ground-motions/near-field/{rec}.AT2"
    ));
    o.push(format!("contacts.0.gap={gap}"));
    o.push(format!("contacts.0.restitution={cr}"));
    Scene::from_file_with_overrides(&paper_scene_path(), &o).expect("paper scene")
}

/// Every restitution is in [0, 1] or null with a reason; the balance closes.
fn assert_sound(out: &RunOutput, energy_tol: f64) {
    for i in &out.impacts {
        let r = i.achieved_restitution;
        if r.is_nan() {
            assert!(i.restitution_undefined.is_some(), "{i:?}");
        } else {
            assert!((0.0..=1.0).contains(&r), "{i:?}");
            assert!(i.relative_velocity_before > 0.0, "{i:?}");
        }
    }
    let e = &out.energy;
    assert!(e.balance_error.abs() < energy_tol * e.input.abs(), "{e:?}");
}

/// Relative energy-balance bound of a Newmark run: its audit sums the trapezoidal works the
/// average-acceleration scheme conserves exactly, so the balance closes to round-off, 16 ε
/// per step as in `gap_energy.rs` (measured here 1.4e-15 to 1.6e-13 over 30 000–48 000 steps,
/// against bounds of 1.1–1.7e-10).
fn newmark_bound(out: &RunOutput) -> f64 {
    16.0 * out.stats.steps as f64 * f64::EPSILON
}

const NEWMARK_KV: [&str; 4] = [
    "gap_element.law=kelvin-voigt",
    "gap_element.stiffness=1e10",
    "gap_element.integrator=newmark",
    "gap_element.time_step=1e-3",
];

/// Three of the 40 Newmark runs (of 720) that stopped with "Newton iterations failed after
/// 50 iterations", the residual equal to the contact force: the clamped Kelvin–Voigt force
/// has a kink and Newton flipped between open and closed. With the active-set iteration
/// they finish at Δt = 1 ms, and say how often the contact states were revised.
#[test]
fn newmark_settles_the_clamped_dashpot_at_1_ms() {
    for (rec, gap, cr) in [
        ("RSN1004_NORTHR-0637_032", "0.05", "0.65"),
        ("RSN1004_NORTHR-0637_122", "0.01", "0.3"),
        ("RSN1048_NORTHR-STC_122", "0.05", "0.3"),
    ] {
        let s = near_field(&NEWMARK_KV, rec, gap, cr);
        let out = solve(&s, None).unwrap_or_else(|e| panic!("{rec}: {e}"));
        assert!(
            out.stats.active_set_iterations > 0,
            "{rec}: {:?}",
            out.stats
        );
        assert!(!out.impacts.is_empty());
        // Newmark's trapezoidal energy sums close to round-off (see gap_energy.rs).
        assert_sound(&out, newmark_bound(&out));
    }
}

/// The Kelvin–Voigt law with tension (`tension = true`), floors touching at t = 0 (zero
/// gap) and approaching: Newton used to fail at such contacts; with the active-set
/// iteration the run finishes, the first episode closing in the first step.
#[test]
fn newmark_with_tension_and_floors_touching_at_the_start_finishes() {
    let mut s = paper(&NEWMARK_KV);
    s.gap_element.tension = true;
    s.contacts[0].gap = 0.0;
    s.contacts[0].restitution = 0.65;
    s.buildings[0].initial_velocity = vec![0.2; 15];
    let out = solve(&s, None).unwrap();
    assert_eq!(out.impacts[0].time, 1e-3);
    assert_sound(&out, newmark_bound(&out));
}

/// Adaptive and Newmark on near-field records at c_r < 1: every achieved restitution in
/// [0, 1], or null with the reason (grazing, separating at closure, ground-driven).
#[test]
fn gap_restitution_is_in_the_unit_interval_or_null_with_a_reason() {
    let adaptive = ["gap_element.law=kelvin-voigt", "gap_element.stiffness=1e10"];
    for integ in [&adaptive[..], &NEWMARK_KV[..]] {
        for (rec, gap) in [
            ("RSN292_ITALY-A-STU_223", "0.01"),
            ("RSN1165_KOCAELI-IZT_270", "0.01"),
        ] {
            for cr in ["0.65", "0.3"] {
                let s = near_field(integ, rec, gap, cr);
                let out = solve(&s, None).unwrap_or_else(|e| panic!("{rec}: {e}"));
                assert!(!out.impacts.is_empty(), "{rec}");
                // Newmark: round-off. Adaptive: the balance's terms are integrated with the
                // motion, so it closes to the error control, 10 × rtol = 1e-7 at the scene's
                // rtol 1e-8 (measured 1.3–2.6e-9).
                let tol = match s.gap_element.integrator {
                    Integrator::Newmark => newmark_bound(&out),
                    Integrator::Adaptive => 10.0 * s.gap_element.tolerance,
                };
                assert_sound(&out, tol);
            }
        }
    }
}

/// One step-count rule: 0.035 s at Δt = 0.005 s is 7 steps, not 8 (0.035 / 0.005 =
/// 7.000000000000001 in floating point).
#[test]
fn newmark_step_count_ignores_decimal_round_off() {
    // The precondition, checked by the compiler in floating point: the quotient is above 7.
    #[allow(clippy::assertions_on_constants)]
    const _: () = assert!(0.035 / 0.005 > 7.0, "the case exercises the round-off");
    let s = paper(&[
        "gap_element.integrator=newmark",
        "gap_element.time_step=0.005",
        "analysis.duration=0.035",
    ]);
    assert_eq!(solve(&s, None).unwrap().stats.steps, 7);
}

/// A wall-like neighbour (story stiffness 1e22 N/m) limits an explicit step to ~1e-8 s:
/// refused at once with the way out (Newmark), which then runs.
#[test]
fn stiff_scene_is_refused_by_the_explicit_integrator_and_runs_with_newmark() {
    let mut s = paper(&["contacts.0.restitution=0.65"]);
    s.buildings[1] = structure::Building::new("wall", vec![2.4e6; 15], vec![1.0e22; 15], 0.05);
    match solve(&s, None) {
        Err(SolverError::Refused { reason }) => assert!(reason.contains("newmark"), "{reason}"),
        other => panic!("expected Refused, got {other:?}"),
    }
    s.gap_element.integrator = structure::scene::Integrator::Newmark;
    s.gap_element.time_step = 1e-3;
    let out = solve(&s, None).unwrap();
    // The floors do meet the wall (8 contact episodes measured), and the run is sound.
    assert!(!out.impacts.is_empty());
    assert_sound(&out, newmark_bound(&out));
    s.duration = 1e300;
    assert!(matches!(solve(&s, None), Err(SolverError::Refused { .. })));
}
