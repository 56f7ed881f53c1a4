//! Convergence of the gap-element integrators on yielding buildings (issue 13).
//!
//! The paper pair with bilinear stories (yield shear low enough that most stories yield
//! several times under the record), contact gap wide enough that they never touch, so the
//! only non-smoothness is the story law's kinks.
//!
//! - Adaptive: the kinks are located as events, so the error in the peak drifts falls with
//!   the tolerance as on a smooth problem: the global error of the error-per-step controlled
//!   5(4) pair is proportional to rtol (steps h ∝ rtol^(1/5), error ∝ h⁵). Fitted on
//!   rtol = 1e-7 … 1e-11 (tighter than 1e-7 the steps are set by the error control, not by
//!   the 0.01 s record points) against rtol = 1e-13: the slope of log error against log rtol
//!   lies in [0.8, 1.25]. A straddled kink leaves a local error O(h²) (the force's
//!   derivative jumps), i.e. an error ∝ rtol^(2/5): slope near 0.4. (The slope against the
//!   number of f evaluations is printed, not asserted: the record-point steps are a floor
//!   of work that does not shrink with the tolerance.)
//! - Newmark (average acceleration, second order): the peak drifts at Δt and Δt/2 approach
//!   the adaptive reference with a ratio of errors near 4.

use solvers::gap;
use structure::scene::Integrator;
use structure::testing::paper_scene;
use structure::Scene;

fn scene(extra: &[&str]) -> Scene {
    let mut o = vec![
        "contacts.0.gap=1.0",
        "analysis.duration=6",
        "buildings.0.story_law=bilinear",
        "buildings.0.yield_shear=3e7",
        "buildings.1.story_law=bilinear",
        "buildings.1.yield_shear=3e7",
        "buildings.1.hardening_ratio=0.05",
    ];
    o.extend_from_slice(extra);
    paper_scene(&o)
}

/// All peak drifts and the residual drifts, m.
fn drifts(out: &solvers::RunOutput) -> Vec<f64> {
    out.buildings
        .iter()
        .flat_map(|b| b.story_drift_max.iter().chain(&b.residual_drift).copied())
        .collect()
}

fn max_err(a: &[f64], r: &[f64]) -> f64 {
    let scale = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(r)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

/// Least-squares slope of y against x.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn adaptive_converges_at_the_method_order_and_newmark_at_second_order() {
    let reference = gap::solve(&scene(&["gap_element.tolerance=1e-13"]), None).unwrap();
    let r = drifts(&reference);
    let mu: f64 = reference
        .buildings
        .iter()
        .flat_map(|b| b.ductility.clone().unwrap())
        .fold(0.0, f64::max);
    assert!(mu > 2.0, "the stories yield: ductility {mu}");
    assert!(reference.stats.story_kinks > 20, "{:?}", reference.stats);
    assert!(reference.impacts.is_empty());

    let (mut lt, mut lw, mut le) = (vec![], vec![], vec![]);
    for tol in [1e-7f64, 1e-8, 1e-9, 1e-10, 1e-11] {
        let s = scene(&[&format!("gap_element.tolerance={tol:e}")]);
        let out = gap::solve(&s, None).unwrap();
        let e = max_err(&drifts(&out), &r);
        eprintln!(
            "tol {tol:e}: error {e:.3e}, {} f evaluations, {} kinks, {} rejected",
            out.stats.rhs_evaluations, out.stats.story_kinks, out.stats.rejected_steps
        );
        lt.push(tol.ln());
        lw.push((out.stats.rhs_evaluations as f64).ln());
        le.push(e.ln());
    }
    let (st, sw) = (slope(&lt, &le), slope(&lw, &le));
    eprintln!("slope against rtol {st:.3}, against f evaluations {sw:.3}");
    assert!((0.8..=1.25).contains(&st), "error ∝ rtol^{st}");

    let mut errs = vec![];
    for dt in [1e-3, 5e-4, 2.5e-4] {
        let mut s = scene(&[&format!("gap_element.time_step={dt:e}")]);
        s.gap_element.integrator = Integrator::Newmark;
        let out = gap::solve(&s, None).unwrap();
        errs.push(max_err(&drifts(&out), &r));
    }
    eprintln!("Newmark errors {errs:?}");
    for w in errs.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (3.0..=5.5).contains(&ratio),
            "Newmark error ratio {ratio} ({errs:?})"
        );
    }
}
