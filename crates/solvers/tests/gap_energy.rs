//! Energy audit of the gap element and its guards.

use solvers::{gap, History, SolverError};
use structure::testing::paper_scene as paper;
use structure::testing::two_oscillators;

#[test]
fn energy_balance_closes_on_a_damped_scene_with_ground_motion_and_impacts() {
    for (law, tension) in [
        ("kelvin-voigt", "false"),
        ("kelvin-voigt", "true"),
        ("hertz-damp", "false"),
        ("linear", "false"),
    ] {
        let k = if law == "hertz-damp" { "1e11" } else { "1e10" };
        let s = paper(&[
            "contacts.0.gap=0.05",
            "contacts.0.restitution=0.65",
            &format!("gap_element.law={law}"),
            &format!("gap_element.tension={tension}"),
            &format!("gap_element.stiffness={k}"),
            "gap_element.tolerance=1e-10",
            "analysis.duration=20",
        ]);
        let out = gap::solve(&s, None).unwrap();
        let e = &out.energy;
        let rel = e.balance_error.abs() / e.input.abs().max(e.damping);
        eprintln!(
            "{law} tension={tension}: {} impacts, input {:.4e} damping {:.4e} contact {:.4e} final {:.4e} balance {:.2e} (rel {rel:.1e}); restitution {:?}",
            out.impacts.len(),
            e.input,
            e.damping,
            e.contact,
            e.final_,
            e.balance_error,
            out.impacts.iter().take(4).map(|i| (i.achieved_restitution * 1e4).round() / 1e4).collect::<Vec<_>>()
        );
        assert!(out.impacts.len() >= 2);
        // The balance's terms are integrated with the motion, so it closes to the error
        // control: 10 × rtol (measured 3–4e-11 at rtol 1e-10).
        assert!(rel < 1e-9, "{law}: relative balance error {rel:e}");
        assert!(e.damping > 0.0 && e.input.abs() > 0.0);
        if law == "linear" {
            // Stored and returned exactly by the conservative spring: what is left is the
            // integration error of its work, within 10 × rtol.
            assert!(
                e.contact.abs() < 1e-9 * e.input.abs(),
                "linear law dissipates nothing: {}",
                e.contact
            );
        } else {
            assert!(
                e.contact > 1e-4 * e.input.abs(),
                "{law} must dissipate: {}",
                e.contact
            );
        }
    }
}

#[test]
fn newmark_energy_audit_is_consistent_on_smooth_contacts() {
    // The Newmark audit sums the trapezoidal works that the average-acceleration scheme
    // conserves exactly, so it closes to the work of the residuals its Newton iterations
    // leave (`residual_work`) plus round-off: the balance within 16 ε per step (measured
    // 1.2e-13 over 20 000 steps), and the balance less the residual work within ε per step
    // (measured 9.3e-3 ε per step: 4.1e-14 of the input against a balance of 1.2e-13).
    let s = paper(&[
        "contacts.0.gap=0.05",
        "gap_element.integrator=newmark",
        "gap_element.time_step=1e-3",
        "gap_element.stiffness=1e9",
        "analysis.duration=20",
    ]);
    let out = gap::solve(&s, None).unwrap();
    let rel = out.energy.balance_error.abs() / out.energy.input.abs();
    eprintln!(
        "newmark k=1e9 dt=1e-3: balance rel {rel:.2e}, {} impacts",
        out.impacts.len()
    );
    let bound = 16.0 * out.stats.steps as f64 * f64::EPSILON;
    assert!(out.stats.steps >= 20_000);
    assert!(rel < bound, "{rel} >= {bound}");
    let e = &out.energy;
    let rest = (e.balance_error - e.residual_work.unwrap()).abs() / e.input.abs();
    assert!(
        rest <= bound / 16.0,
        "balance less residual work {rest:.3e} > ε per step"
    );
    // Only Newmark has Newton residuals: the event-driven and adaptive solvers report none.
    let short = paper(&["contacts.0.gap=0.05", "analysis.duration=2"]);
    for m in [
        solvers::Method::Gap,
        solvers::Method::Momentum,
        solvers::Method::Impulse,
    ] {
        let out = solvers::run(&short, m, None).unwrap();
        assert_eq!(out.energy.residual_work, None, "{m:?}");
    }
}

#[test]
fn history_holds_record_points_and_events_in_order() {
    let s = paper(&["analysis.duration=10", "contacts.0.gap=0.05"]);
    let mut h = History::default();
    let out = gap::solve(&s, Some(&mut h)).unwrap();
    let n_rec = (10.0f64 / 0.005).round() as usize + 1;
    assert_eq!(h.time.len(), n_rec + out.stats.events as usize);
    assert!(h.time.windows(2).all(|w| w[1] >= w[0]));
    assert_eq!(h.displacement[0].len(), 30);
    for imp in &out.impacts {
        assert!(h.time.contains(&imp.time), "closure instant sampled");
    }
}

#[test]
fn guards_report_step_budget_and_event_storm() {
    // Fewer steps allowed than record intervals (8000): refused before anything runs.
    let mut s = paper(&["analysis.max_steps=100"]);
    match gap::solve(&s, None) {
        Err(SolverError::Refused { reason }) => {
            assert!(reason.contains("analysis.max_steps = 100"), "{reason}")
        }
        other => panic!("expected Refused, got {other:?}"),
    }
    // Enough for the record intervals, not for the steps contacts add: stops at run time.
    s.limits.max_steps = 8001;
    match gap::solve(&s, None) {
        Err(SolverError::StepBudget { limit: 8001, .. }) => {}
        other => panic!("expected StepBudget, got {other:?}"),
    }
    s.gap_element.integrator = structure::scene::Integrator::Newmark;
    s.limits.max_steps = 10;
    assert!(matches!(
        gap::solve(&s, None),
        Err(SolverError::Refused { .. })
    ));

    // A ball bouncing on a heavy, stiff partner under no load keeps impacting elastically at
    // a rate set by the springs: limit the rate below it.
    let mut b = two_oscillators(1.0e3, 1.0e9, 1.0e3, 1.0e9, 1.0, 0.0, 1.0, 1.0);
    b.gap_element.law = structure::scene::ContactLaw::Linear;
    b.limits.max_impact_rate = 5.0;
    match gap::solve(&b, None) {
        Err(SolverError::EventStorm { .. }) => {}
        other => panic!("expected EventStorm, got {other:?}"),
    }
}
