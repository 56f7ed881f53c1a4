//! # solvers — three ways of modelling pounding, side by side
//!
//! - [`momentum`]: the paper's method (Conoscente, Hamburger & Johnson). Each building in its
//!   own mass-normalised modal coordinates, integrated exactly between events for
//!   piecewise-linear ground acceleration; at impact the contact velocities jump by
//!   conservation of momentum with a coefficient of restitution (paper eqs 19–27).
//! - [`gap`]: the practice. Physical coordinates, a compression-only contact element
//!   (linear, Kelvin–Voigt or Hertz-damp law), integrated by an adaptive embedded
//!   Runge–Kutta pair with event location, or by fixed-step Newmark with Newton iterations.
//! - [`impulse`]: the paper's impact law on the physical floor coordinates, integrated
//!   between events by the gap element's adaptive pair with event location. It needs no
//!   modal superposition, so it runs the yielding stories that [`momentum`] refuses.
//!
//! All three read a [`structure::Scene`], use the same M, K and classical C, and return the
//! same [`RunOutput`] (serialised as the JSON of `pound run --out`, its keys and units in
//! docs/cli.md), so any difference between their answers comes from the contact treatment
//! alone.
//!
//! # Example
//!
//! The paper's scene (two 15-story buildings, roof contact, 10 cm gap, Capitola 000 at
//! 0.40 g), its first 10 s, by the momentum method and by a stiff gap element, which must
//! agree with it (the penalty solution converges to the rigid-impact one as the spring
//! stiffens; the stiffness study charts how fast):
//!
//! ```
//! use solvers::{run, Method};
//! use structure::Scene;
//! use std::path::Path;
//!
//! let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../studies/paper/scene.toml");
//! let set = ["analysis.duration=10".to_string(), "gap_element.stiffness=1e12".to_string()];
//! let scene = Scene::from_file_with_overrides(&file, &set)?;
//! let momentum = run(&scene, Method::Momentum, None)?;
//! let gap = run(&scene, Method::Gap, None)?;
//! // Peak story shears (N), story 1 at index 0; building 2's top story:
//! let top = |out: &solvers::RunOutput| *out.buildings[1].story_shear_max.last().unwrap();
//! let (m, g) = (top(&momentum), top(&gap));
//! println!("momentum {m:.4e} N, gap element {g:.4e} N");
//! assert!(momentum.stats.impacts > 0);
//! assert!((m - g).abs() < 0.01 * m); // 0.18 % apart here
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod closure;
pub mod gap;
pub mod impulse;
pub mod momentum;
pub mod output;
pub mod overlap;
pub mod response;
pub mod rules;
pub(crate) mod step;

pub use output::{
    BuildingResponse, ContactFlexibility, EnergyAudit, History, Impact, Overlap, PersistentContact,
    RunOutput, Stats,
};

use structure::{ModelError, Scene};

/// Which solver to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The paper's modal momentum method.
    Momentum,
    /// The gap element (penalty) method.
    Gap,
    /// The paper's impact law on the physical floor coordinates, adaptive integration.
    Impulse,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Momentum => "momentum",
            Method::Gap => "gap",
            Method::Impulse => "impulse",
        })
    }
}

/// Why a solver could not go on. Every variant carries the simulated time at which it
/// stopped and what it was doing, except [`SolverError::Refused`]: a scene refused before
/// anything is allocated or integrated (an input error, exit code 2 in the CLI), because its
/// estimated work or memory exceeds the limits.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolverError {
    #[error("step size underflow at t = {time:.9} s: step {step:.3e} s is below the minimum {min_step:.3e} s ({context})")]
    StepSizeUnderflow {
        time: f64,
        step: f64,
        min_step: f64,
        context: String,
    },
    #[error("non-finite state at t = {time:.9} s: {context}")]
    NonFinite { time: f64, context: String },
    #[error("Newton iterations failed at t = {time:.9} s after {iterations} iterations (residual {residual:.3e} N): {context}")]
    NewtonFailure {
        time: f64,
        iterations: usize,
        residual: f64,
        context: String,
    },
    /// `context`: the state when the budget ran out (the step size, the contacts closed or
    /// held, the impacts so far).
    #[error("step budget exhausted at t = {time:.9} s: {steps} steps taken, limit {limit} (analysis.max_steps); {context}")]
    StepBudget {
        time: f64,
        steps: u64,
        limit: u64,
        context: String,
    },
    #[error("event storm at t = {time:.9} s: {impacts} impacts in {window:.3e} s exceed the limit of {limit} impacts per second (analysis.max_impact_rate); {context}")]
    EventStorm {
        time: f64,
        impacts: usize,
        window: f64,
        limit: f64,
        context: String,
    },
    #[error("singular contact system at t = {time:.9} s: contacts {contacts:?} ({context}); are two contacts acting on the same floor pair?")]
    SingularContact {
        time: f64,
        contacts: Vec<usize>,
        context: String,
    },
    #[error("the scene cannot be run with this method: {reason}")]
    Refused { reason: String },
    #[error("the solver cannot go on at t = {time:.9} s: {reason}")]
    Stalled { time: f64, reason: String },
    #[error(transparent)]
    Model(#[from] ModelError),
}

/// Runs `scene` with `method`, using the options in the scene (`[momentum]` or
/// `[gap_element]`). When `history` is given it receives floor displacements at every record
/// point and at every event instant.
pub fn run(
    scene: &Scene,
    method: Method,
    history: Option<&mut History>,
) -> Result<RunOutput, SolverError> {
    if method == Method::Momentum {
        refuse_yielding(scene)?;
    }
    match method {
        Method::Momentum => momentum::solve(scene, history).map(|mut out| {
            for (b, bd) in out.buildings.iter_mut().zip(&scene.buildings) {
                b.drifts_from_shears(&bd.story_stiffness);
            }
            out
        }),
        Method::Gap => gap::solve(scene, history),
        Method::Impulse => impulse::solve(scene, history),
    }
}

/// The momentum method superposes the modes of linear buildings (the paper's eq. 5 takes M
/// and K constant): a scene with yielding stories is refused, naming the building and the
/// methods that apply.
pub fn refuse_yielding(scene: &Scene) -> Result<(), SolverError> {
    match scene.buildings.iter().find(|b| b.story_law.is_yielding()) {
        None => Ok(()),
        Some(b) => Err(SolverError::Refused {
            reason: format!(
                "building `{}` has yielding stories (story_law = \"bilinear\"): the momentum \
                 method superposes the modes of linear buildings and does not apply; use \
                 --method gap (adaptive or newmark) or --method impulse",
                b.name
            ),
        }),
    }
}
