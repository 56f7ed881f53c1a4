//! The modal momentum method.
use crate::{History, RunOutput, SolverError};
use structure::Scene;
/// Runs the momentum method.
pub fn solve(_scene: &Scene, _history: Option<&mut History>) -> Result<RunOutput, SolverError> {
    todo!()
}
