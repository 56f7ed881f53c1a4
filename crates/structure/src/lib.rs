//! # structure — models, matrices, modes and ground motions for `pound`
//!
//! Everything the three pounding solvers (momentum, gap element, impulse) share lives here,
//! so that differences between their answers come from the contact treatment alone:
//!
//! - [`model`]: the planar lumped-mass shear stick ([`model::Building`]), its mass, stiffness
//!   and classical damping matrices, mass-normalised modes ([`model::Modes`]) and calibration
//!   from target frequencies ([`model::calibrate`]).
//! - [`ground`]: ground-motion records (PEER AT2, two-column, one-column), scaling,
//!   piecewise-linear interpolation, the exact Nigam–Jennings propagator and response spectra.
//! - [`scene`]: the TOML scene file (buildings, contacts, ground motion, solver options) with
//!   `--set` style overrides and validation that names the offending key.
//! - [`testing`]: small scenes with closed-form answers shared by tests and benchmarks.
//!
//! SI units throughout: kg, N/m, m, s, m/s².

pub mod ground;
pub mod model;
pub mod scene;
pub mod testing;

/// Standard gravity, m/s².
pub const G: f64 = 9.80665;

/// `n` and a noun in the singular or the plural as `n` asks (`1 entry`, `2 entries`, `0
/// records`), for messages and reports (the `studies` crate's too).
pub fn count<T: std::fmt::Display + PartialEq + From<u8>>(n: T, one: &str, many: &str) -> String {
    let noun = if n == T::from(1) { one } else { many };
    format!("{n} {noun}")
}

pub use ground::{GroundMotion, RecordError, RecordFormat, Units};
pub use model::{Building, Damping, ModelError, Modes};
pub use scene::{Contact, GapElementOptions, MomentumOptions, Purpose, Scene, SceneError};
