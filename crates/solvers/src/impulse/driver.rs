//! The driver of the impulse method: owns the loop over the record intervals, the response
//! tracker (continuous peaks from each accepted step's dense output, samples at record
//! points and at events), the history and the overlap audit, and reacts to the
//! [`StepOutcome`] of [`ImpulseStepper::step`]; the stepper does the integration and the
//! contact rules. The same loop as the adaptive gap element's ([`crate::gap::adaptive`]),
//! with the same observation of each dense step ([`DenseObserver`]).

use structure::Scene;

use super::stepper::ImpulseStepper;
use crate::gap::adaptive::{DenseObserver, DenseStep};
use crate::gap::System;
use crate::step::StepOutcome;
use crate::{History, RunOutput, SolverError};

/// Runs the impulse method on the assembled system `sys` of `scene`.
pub(super) fn run(
    scene: &Scene,
    sys: &System,
    mut history: Option<&mut History>,
) -> Result<RunOutput, SolverError> {
    let duration = scene.duration;
    let n_int = sys.n_intervals(duration);
    let bp = |i: usize| sys.interval_end(i, duration);
    let mut stepper = ImpulseStepper::new(scene, sys, bp(0))?;
    let keep = history.is_some();
    let mut obs = DenseObserver::new(scene, sys);
    obs.start(
        sys,
        stepper.u(),
        |t| stepper.observe(t, keep),
        history.as_deref_mut(),
    );

    let mut interval = 0usize;
    while interval < n_int {
        let outcome = stepper.step(bp(interval), &mut |s: &DenseStep| obs.dense(sys, s))?;
        let (tracker, overlaps) = (&mut obs.tracker, &mut obs.overlaps);
        match outcome {
            // Nothing moved (a release at the step start changes the held set only).
            StepOutcome::Rejected | StepOutcome::Released { .. } => continue,
            StepOutcome::Accepted | StepOutcome::Breakpoint => {}
            // An event inside the interval: the state after it is a sample.
            StepOutcome::Impact { breakpoint, .. }
            | StepOutcome::ContactOpened { breakpoint, .. }
            | StepOutcome::StoryKink { breakpoint } => {
                if !breakpoint {
                    sys.observe_overlaps(overlaps, stepper.t(), stepper.u());
                    stepper.observe(tracker, keep);
                    tracker.sample(stepper.t(), history.as_deref_mut());
                }
            }
            StepOutcome::ContactClosed { .. }
            | StepOutcome::ContactsChanged { .. }
            | StepOutcome::Finished => unreachable!("not an outcome of the impulse stepper"),
        }
        if outcome.at_breakpoint() {
            sys.observe_overlaps(overlaps, stepper.t(), stepper.u());
            stepper.observe(tracker, keep);
            tracker.sample(stepper.t(), history.as_deref_mut());
            interval += 1;
            stepper.enter_segment((interval < n_int).then(|| sys.segment(interval)));
        }
    }

    let (impacts, phases, energy, stats, stories) = stepper.finish()?;
    let m = &scene.momentum;
    let settings = format!(
        "impulse, consistent impulse on all floors, adaptive dopri5 tol={:.0e}, persistent contact {}",
        scene.gap_element.tolerance,
        if m.persistent_contact {
            format!("on (capture {:.1e} m/s)", m.capture_velocity)
        } else {
            "off".into()
        }
    );
    let mut buildings = obs.tracker.finish();
    for (bi, b) in buildings.iter_mut().enumerate() {
        b.hysteretic_energy = stories.building_hysteretic_energy(bi);
    }
    Ok(RunOutput {
        impacts,
        persistent_contacts: phases,
        ..RunOutput::on_scene(
            scene,
            "impulse",
            settings,
            buildings,
            energy,
            stats,
            obs.overlaps,
        )
    })
}
