//! The gap-element method.
use crate::{History, RunOutput, SolverError};
use structure::Scene;
/// Runs the gap-element method.
pub fn solve(_scene: &Scene, _history: Option<&mut History>) -> Result<RunOutput, SolverError> {
    todo!()
}
