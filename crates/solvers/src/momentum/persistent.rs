//! Persistent contact: the two floors move together (δ = 0) until the force would pull.
//!
//! The contact forces λ_a ≥ 0 are taken constant over each segment (record sub-step or
//! partial segment). The exact solution is linear in λ, so the gap at the segment end is
//! δ_end = δ_free − C λ with C_ab = Σ_n g_a,n g_b,n χ_n(τ), χ_n(τ) the displacement of mode
//! n at τ under a unit constant load from rest. Solving C λ = δ_free keeps δ = 0 at every
//! segment end (no drift: the target is absolute). A constant force over a segment whose
//! ends both have δ = 0 does no work, so the phase conserves energy to round-off.
//!
//! Why constant and not piecewise-linear λ: with λ linear in time and δ_end = 0 imposed
//! at each end, λ₁ = (…) − (b₀₀/b₀₁) λ₀ and b₀₀/b₀₁ → 2 for small ωτ: the multiplier
//! error is amplified by −2 per step (unstable). With λ constant the velocity error only
//! alternates in sign (bounded) and λ matches the mean force over the segment.
//!
//! Release (see `Stepper::persistent_segment`): the *instantaneous* holding force
//! λ(t) = W⁻¹ δ̈_free(t) (W the Delassus matrix of the held set, δ̈_free the relative
//! acceleration the floors would have without the contact) is checked at every segment start
//! and end; where it turns tensile inside a segment the instant is located with Brent's
//! method on the held trajectory, the phase ends there, and the contact is released with
//! δ̇ = 0. At every held-segment end the relative velocity of the held contacts is projected
//! to zero (a plastic micro-impulse whose energy goes to the contact account), so that a
//! release leaves the floors touching at rest, not drifting together.

use super::impulse::{solve_checked, ContactGeom};
use super::modal::{Arc, Modal};
use crate::SolverError;

/// Constant forces (N) on the persistent contacts `set` over a segment of length `tau`,
/// given the free (λ = 0) end gaps `delta_free`.
pub fn contact_forces(
    modal: &Modal,
    contacts: &[ContactGeom],
    set: &[usize],
    tau: f64,
    delta_free: &[f64],
    time: f64,
) -> Result<Vec<f64>, SolverError> {
    let chi: Vec<f64> = (0..modal.len())
        .map(|n| {
            Arc::new(modal.omega[n], modal.zeta[n], 0.0, 0.0, 1.0, 1.0, tau)
                .xv(tau)
                .0
        })
        .collect();
    let c: Vec<Vec<f64>> = set
        .iter()
        .map(|&a| {
            set.iter()
                .map(|&b| {
                    (0..modal.len())
                        .map(|n| contacts[a].g[n] * contacts[b].g[n] * chi[n])
                        .sum()
                })
                .collect()
        })
        .collect();
    solve_checked(c, delta_free.to_vec()).ok_or_else(|| SolverError::SingularContact {
        time,
        contacts: set.to_vec(),
        context: "holding forces of a persistent-contact phase".into(),
    })
}
