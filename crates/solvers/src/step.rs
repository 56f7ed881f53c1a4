//! What one step of a time stepper did: the [`StepOutcome`] shared by the gap element's
//! integrators ([`crate::gap::adaptive`], [`crate::gap::newmark`]) and the impulse method
//! ([`crate::impulse`]).
//!
//! The shape (issue 10): a stepper owns the integration state and advances it by one step,
//! reporting what happened; one driver per solver owns the loop (over the record intervals,
//! or over the fixed steps), the response tracker (peaks, samples, history) and the overlap
//! audit, and reacts to the outcome: nothing moved (a rejected step, or a release at the
//! step start), a plain step, a record point reached, an event (the state there is
//! sampled), the end of the analysis. The momentum method's `momentum::Step` is the same
//! idea over its exact modal segments (kept apart: its segments, impacts and persistent
//! phases are its own).
//!
//! One enum for the three steppers rather than one each: most variants are shared, and the
//! few a stepper never reports are `unreachable!` in its driver. The contacts of an event
//! are one located contact (adaptive: events are located one at a time), a set
//! (impulse: closures within the simultaneity window are resolved together) or two sets
//! (Newmark judges every contact from the step's end state, so in one step some may close
//! while others open).
//!
//! Which stepper reports which outcome:
//!
//! | outcome | adaptive | Newmark | impulse |
//! |---|---|---|---|
//! | `Rejected` | error test failed | – | error test failed |
//! | `Accepted`, `Breakpoint` | ✓ | `Accepted` (no contact changed) | ✓ |
//! | `ContactClosed` | located closure | – | – |
//! | `ContactOpened` | located opening | – | located release of a held contact |
//! | `StoryKink` | located kink | – (kinks not located) | located kink |
//! | `Impact` | – | – | located closures, resolved by the impact law |
//! | `Released` | – | – | a held contact released at the step start |
//! | `ContactsChanged` | – | closures and openings of the step | – |
//! | `Finished` | – | the last step was taken before the call | – |
//!
//! The adaptive and impulse drivers own the record points and stop after the last one; the
//! Newmark stepper counts its fixed steps and says when they are done.

/// What one call of a stepper's `step` did. `breakpoint`: the step ended on the record
/// point it was given.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum StepOutcome {
    /// The trial step failed the error test: nothing moved, the next try is shorter.
    Rejected,
    /// The whole step was taken, ending inside the record interval (Newmark: a step in
    /// which no contact changed state).
    Accepted,
    /// The whole step was taken and ended on the record point.
    Breakpoint,
    /// The step was cut at (or ended with) the closure of contact `contact`.
    ContactClosed { contact: usize, breakpoint: bool },
    /// The step was cut at (or ended with) the opening of contact `contact` (the impulse
    /// method: the release of a held contact whose holding force turned tensile).
    ContactOpened { contact: usize, breakpoint: bool },
    /// The step was cut at a story kink (yield or unloading) before any contact event; the
    /// stories were committed there.
    StoryKink { breakpoint: bool },
    /// The impulse method: the step was cut where `contacts` close (within the simultaneity
    /// window of each other) and the impact law resolved them (impulses, contacts joining
    /// the held set, grazes).
    Impact {
        contacts: Vec<usize>,
        breakpoint: bool,
    },
    /// The impulse method: the holding force of held contact `contact` was already tensile
    /// at the step start; it was released there and no step was taken (the state did not
    /// move).
    Released { contact: usize },
    /// A fixed step (Newmark) in which contacts changed state, judged at its end: `closed`
    /// began carrying force, `opened` stopped (either may be empty, not both).
    ContactsChanged {
        closed: Vec<usize>,
        opened: Vec<usize>,
    },
    /// The last step had already been taken: nothing moved.
    Finished,
}

impl StepOutcome {
    /// Whether the step ended on the record point.
    pub fn at_breakpoint(&self) -> bool {
        match self {
            StepOutcome::Rejected
            | StepOutcome::Accepted
            | StepOutcome::Released { .. }
            | StepOutcome::ContactsChanged { .. }
            | StepOutcome::Finished => false,
            StepOutcome::Breakpoint => true,
            StepOutcome::ContactClosed { breakpoint, .. }
            | StepOutcome::ContactOpened { breakpoint, .. }
            | StepOutcome::StoryKink { breakpoint }
            | StepOutcome::Impact { breakpoint, .. } => *breakpoint,
        }
    }
}

/// A guard against a stepper that takes steps without advancing time (a contact or kink
/// state it cannot resolve, each step ending where it began): after [`Progress::WINDOW`]
/// steps over which time advanced less than [`Progress::MIN_ADVANCE`], the run stops with
/// `SolverError::Stalled` naming the instant, where it used to spin until
/// `analysis.max_steps` (minutes) and then report a spent budget.
#[derive(Debug, Clone, Copy, Default)]
pub struct Progress {
    /// Time of the last check that found progress, s.
    t: f64,
    /// Steps taken at that check.
    steps: u64,
}

impl Progress {
    /// Steps allowed without progress (a legitimate run advances by ≥ 1e-9 s far sooner:
    /// its steps are bounded below by the record step over at most 4096 check windows, or by
    /// the adaptive step's underflow limit).
    pub const WINDOW: u64 = 100_000;
    /// Advance that counts as progress, s.
    pub const MIN_ADVANCE: f64 = 1e-9;

    /// Checks the run at time `t` after `steps` steps; `Stalled` at `t` when it is stuck.
    pub fn check(&mut self, t: f64, steps: u64) -> Result<(), crate::SolverError> {
        if t > self.t + Self::MIN_ADVANCE || steps < self.steps {
            self.t = t;
            self.steps = steps;
            return Ok(());
        }
        if steps - self.steps > Self::WINDOW {
            let reason = format!(
                "time advanced less than {:e} s over {} steps (from t = {:.9} s): the contact or yield state cannot be resolved there; \
                 try another tolerance or time step, or check the scene for degenerate values (tiny masses or yield shears, extreme stiffness ratios)",
                Self::MIN_ADVANCE,
                steps - self.steps,
                self.t
            );
            return Err(crate::SolverError::Stalled { time: t, reason });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The guard every stepper calls (momentum, adaptive gap element, impulse method): no
    /// error while time advances or within [`Progress::WINDOW`] steps of the last advance;
    /// `Stalled` at the instant once more steps than that advance less than
    /// [`Progress::MIN_ADVANCE`]; an advance resets the count. (The momentum method's own
    /// stalls on random scenes, seeds 651, 2331, 3927 and 21091 refined 3×, have all been
    /// mended; the impulse method's end-to-end case is `momentum_robust.rs`'s
    /// `runs_that_stop_advancing_time_stall_with_a_reason`.)
    #[test]
    fn progress_stalls_after_a_window_of_steps_without_advance() {
        let mut p = Progress::default();
        let t = 1.25;
        for steps in 1..=1000 {
            p.check(t * steps as f64 / 1000.0, steps).unwrap();
        }
        // Stuck at t: tolerated for WINDOW steps, tiny advances included.
        let s0 = 1000;
        for k in 1..=Progress::WINDOW {
            p.check(
                t + 0.5 * Progress::MIN_ADVANCE * (k as f64 / Progress::WINDOW as f64),
                s0 + k,
            )
            .unwrap();
        }
        match p.check(t, s0 + Progress::WINDOW + 1) {
            Err(crate::SolverError::Stalled { time, reason }) => {
                assert_eq!(time, t);
                assert!(reason.contains("time advanced less than"), "{reason}");
                assert!(
                    reason.contains(&format!("over {} steps", Progress::WINDOW + 1)),
                    "{reason}"
                );
            }
            other => panic!("expected Stalled, got {other:?}"),
        }
        // An advance resets it.
        let mut p = Progress::default();
        p.check(t, 1).unwrap();
        p.check(t, Progress::WINDOW).unwrap();
        p.check(t + 2.0 * Progress::MIN_ADVANCE, Progress::WINDOW + 1)
            .unwrap();
        p.check(t + 2.0 * Progress::MIN_ADVANCE, 2 * Progress::WINDOW + 1)
            .unwrap();
    }
}
