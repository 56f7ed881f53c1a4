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
//!
//! # Example
//!
//! The paper's scene: each building is calibrated to two target frequencies (its first two
//! modes in the impact direction, paper Table 1), which its modes reproduce:
//!
//! ```
//! use structure::Scene;
//! use std::path::Path;
//!
//! let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../studies/paper/scene.toml");
//! let scene = Scene::from_file(&file)?;
//! let modes = scene.buildings[0].modes()?;
//! let f = modes.frequencies_hz();
//! assert_eq!(f.len(), 15);
//! // f₂/f₁ by a root search to 1e-14, f₁ by scaling the stiffness: both to the eigen-solver's
//! // rounding (about 1e-14 here), well inside 1e-12:
//! assert!((f[0] / 0.67 - 1.0).abs() < 1e-12 && (f[1] / 2.23 - 1.0).abs() < 1e-12);
//! // Mass-normalised: φ₁ᵀ M φ₁ = 1 (kg·(kg^-½)² = 1).
//! let m1: f64 = (0..15).map(|i| modes.masses[i] * modes.phi[(i, 0)].powi(2)).sum();
//! assert!((m1 - 1.0).abs() < 1e-12);
//! println!("building 1: {:.3} and {:.3} Hz, record PGA {:.3} g",
//!     f[0], f[1], scene.ground.as_ref().unwrap().pga() / structure::G);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

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
