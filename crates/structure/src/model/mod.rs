//! Planar lumped-mass shear sticks: matrices, modes, calibration.
//!
//! A building with `n` floors has one horizontal degree of freedom per floor, `u[0]` the
//! lowest floor, all displacements relative to the ground. Story `j` (1-based) joins floor
//! `j-1` (the ground for `j = 1`) to floor `j` with stiffness `k_j`:
//!
//! ```text
//! M = diag(m_1 … m_n)
//! K_jj = k_j + k_{j+1} (k_{n+1} = 0),  K_{j,j+1} = K_{j+1,j} = −k_{j+1}
//! C = M Φ diag(2 ζ_n ω_n) Φᵀ M          (classical modal damping, paper eq. 27)
//! C = a M + b K  ⇔  ζ_n = a/(2 ω_n) + b ω_n/2   (Rayleigh damping, a special case: [`Rayleigh`])
//! story shear V_j = k_j (u_j − u_{j−1}),  u_0 = 0
//! ```

pub mod building;
pub mod calibrate;
pub mod modes;
pub mod story_law;

pub use building::{Building, Damping, Rayleigh};
pub use calibrate::{
    calibrate_first_frequency, calibrate_two_frequencies, top_to_ground, Calibration,
};
pub use modes::Modes;
pub use story_law::{Bilinear, BilinearParams, BilinearState, StoryLaw};

/// The smallest and the largest of `v` ((∞, 0) when empty): the spreads of a building's masses
/// and stiffnesses, which bound how well its eigenproblem is conditioned.
pub(crate) fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
        (lo.min(*x), hi.max(*x))
    })
}

/// Errors raised while building or analysing a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("building `{building}`: {what}")]
    Invalid { building: String, what: String },
    #[error("building `{building}`: the eigen-solver failed: {reason}")]
    Eigen { building: String, reason: String },
    #[error("calibration of building `{building}` failed: {reason}")]
    Calibration { building: String, reason: String },
}
