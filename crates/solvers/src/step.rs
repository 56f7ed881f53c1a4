//! What one step of a time stepper did: the [`StepOutcome`] shared by the gap element's
//! integrators ([`crate::gap::adaptive`], [`crate::gap::newmark`]).
//!
//! The shape (issue 10): a stepper owns the integration state and advances it by one step,
//! reporting what happened; one driver per solver owns the loop (over the record intervals,
//! or over the fixed steps), the response tracker (peaks, samples, history) and the overlap
//! audit, and reacts to the outcome: nothing moved (rejected step), a plain step, a record
//! point reached, an event (the state there is sampled), the end of the analysis. The momentum method's `momentum::Step` is the same idea over its
//! exact modal segments.
//!
//! Which stepper reports which outcome:
//!
//! | outcome | adaptive | Newmark |
//! |---|---|---|
//! | `Rejected` | error test failed | – |
//! | `Accepted`, `Breakpoint` | ✓ | `Accepted` (no contact changed) |
//! | `ContactClosed` | located closure | – |
//! | `ContactOpened` | located opening | – |
//! | `StoryKink` | located kink | – (kinks not located) |
//! | `ContactsChanged` | – | closures and openings of the step |
//! | `Finished` | – | the last step was taken before the call |
//!
//! The adaptive driver owns the record points and stops after the last one; the
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
            | StepOutcome::ContactsChanged { .. }
            | StepOutcome::Finished => false,
            StepOutcome::Breakpoint => true,
            StepOutcome::ContactClosed { breakpoint, .. }
            | StepOutcome::ContactOpened { breakpoint, .. }
            | StepOutcome::StoryKink { breakpoint } => *breakpoint,
        }
    }
}
