//! # The impulse method: the paper's impact law in physical coordinates
//!
//! The momentum method's contact model (Conoscente, Hamburger & Johnson, eqs 19–24: rigid
//! impact with a coefficient of restitution, the consistent impulse with the full mass
//! matrix, persistent contact for c_r < 1) applied to the physical floor coordinates of the
//! gap element's `System` instead of modal coordinates, and integrated between events by
//! the adaptive Dormand–Prince 5(4) stepper ([`crate::gap::dopri`]) with dense output and
//! event location. Nothing in it needs modal superposition: it is the method for buildings
//! whose story springs are not linear (yielding stories, below).
//!
//! **Between events** (u, v floor displacements and velocities relative to the ground,
//! lumped M, K in story form, classical C, all as in [`crate::gap`]):
//!
//! ```text
//! M ü + C u̇ + f_s(u) = −M 1 a_g(t) − Σ_{c held} G_cᵀ λ_c     (f_s = K u when linear)
//! G_c = e_left − e_right (e_left alone for a wall),  δ_c = G_c u − gap_c
//! λ = W⁻¹ G ü_free,  W = G M⁻¹ Gᵀ (Delassus),  ü_free = M⁻¹(−C u̇ − f_s(u)) − 1 a_g
//! ```
//!
//! so that δ̈ = 0 on the contacts held together (λ > 0 compressive, N). The state carries
//! three quadratures integrated with the same stages: input ∫ −u̇ᵀM1 a_g dt, damping
//! ∫ u̇ᵀC u̇ dt and the work of the holding forces ∫ λ·δ̇ dt (zero up to the drift of δ̇).
//! Error control: rtol = `gap_element.tolerance`, atol = rtol·1e-3 (m, m/s); steps land on
//! every record point.
//!
//! **Events** (`events.rs`), located on the dense output after every accepted step (θ = ¼, ½, ¾, 1 and
//! Brent, root tolerance 2ε·t as in the momentum method; the step is cut at the first
//! event and the state taken from the interpolant):
//! - closure of an open contact: δ crosses 0 upwards, with the case analysis shared with
//!   the momentum method ([`crate::closure`]: interior maxima of δ, a contact just resolved
//!   closing again between falling ends, a contact touching at the window start; without
//!   the closed form's derivative bounds, so without its filters), the same re-arming band
//!   (a contact just resolved is found closing only at δ = 1e-10·max(gap, 1 mm) until its
//!   gap has opened beyond that band) and the same
//!   simultaneity window (closures within 1e-12 s are solved together);
//! - release of a held contact: min_c λ_c/band_c crosses −1, band_c = 1e-9 of the sizes of
//!   the terms of its free relative acceleration (|f_l|/m_l + |a_g| at each floor, f the
//!   restoring forces) over W_cc: the momentum method's round-off band. A contact whose
//!   force is already below −band_c at a step start is released there.
//!
//! **Impacts** (`impact.rs`): the momentum method's rules, with its impulse code
//! ([`crate::momentum::impulse`]) on mass-scaled velocities w = M^½ v (`contact.rs`):
//! W_AA P_A = (1 + c_r) v_A on the impacting set (small LCP), Δv = −M⁻¹Gᵀ P; a contact
//! approaching at most `momentum.capture_velocity` is touching (joins the held set if its
//! holding force is compressive, grazes otherwise); chattering (three impact intervals
//! shrinking with a remaining accumulation time below the momentum method's base step) is
//! captured by a plastic impulse into persistent contact. The kinetic energy lost goes to
//! the contact account.
//!
//! **Held contacts** (`held.rs`): after every accepted step their relative velocity and gap are
//! projected to zero (Δv = −M⁻¹Gᵀ W⁻¹ G v, Δu = −M⁻¹Gᵀ W⁻¹ δ), the mechanical energy removed
//! going to the contact account, as the momentum method projects at every held-segment end.
//!
//! **Yielding stories** (`story_law = "bilinear"`, [`crate::gap::stories`]): the restoring
//! force −f_s(u) − C u̇ takes the story law's shears, evaluated from the committed story
//! state (a pure trial at every stage, so a rejected step changes nothing). As in the
//! adaptive gap element, the yield and unloading kinks of the law are located on the dense
//! output (before the earliest contact event) and the step is cut there; the stories are
//! committed at every accepted state, and again after an impulse or a projection changes
//! the state. The holding forces and their release are evaluated with the same law.
//!
//! **Energy audit**: initial + input − damping − contact − hysteretic = final (kinetic +
//! recoverable strain), contact = impact losses + projection losses + ∫ λ·δ̇ dt (a
//! projection on yielding stories is charged net of the plastic work it does); the balance
//! error measures the integration only.
//!
//! **How it differs from the momentum method with all modes.** Free flight and impacts are
//! the same equations: the Delassus matrix G M⁻¹ Gᵀ equals the modal Σ g gᵀ (Φ Φᵀ = M⁻¹),
//! so impact times, velocities and peaks agree to the integration tolerance. In a
//! persistent-contact phase the momentum method holds each segment with a force *linear* in
//! time, from the instantaneous force at the segment start to the force that closes the held
//! gaps at its end, on segments whose lengths adapt to `momentum.held_tolerance`
//! ([`crate::momentum::persistent`]), and locates the release on that trajectory; here λ(t)
//! is the exact instantaneous constraint force. The two held motions differ by the momentum
//! method's discretisation of λ, which falls in proportion to its held tolerance
//! (`tests/impulse.rs`), so on scenes with persistent contact the answers agree to an
//! accuracy set by that tolerance, not to the integration tolerance. The momentum method
//! also judges the sign of the holding force at its segment ends only: a tensile
//! excursion shorter than a segment (a brief release followed by a slow re-impact) is
//! missed there and found here, where λ is sampled four times per adaptive step; with its
//! step refined the momentum method finds it too (aligned paper scene, c_r = 0).
//! Event location uses the dense output, not the closed form: each step is searched in four
//! windows; the explicit pair's stability keeps a step below 3.3/ω_max, so a window is
//! below T_min/7.6 and holds at most one extremum of a gap function, as the momentum
//! method's T_min/8 windows do.
//!
//! **Shape** (issue 10; the adaptive gap element's, see `crate::step`):
//! - `problem.rs`: `Problem` (the system, contact rows, re-arming bands, the
//!   chattering-capture step) and `Config` (the options it reads), fixed for a
//!   run;
//! - `stepper.rs`: `State` (y, t, committed stories, held set, grazing flags,
//!   impact times) and `ImpulseStepper::step`, which takes one trial step and
//!   reports a `StepOutcome`: `Rejected` (nothing moved), `Accepted`,
//!   `Breakpoint` (the record point reached), `Impact` (the step was cut at closures,
//!   resolved by the impact law), `ContactOpened` (cut at the release of a held contact),
//!   `StoryKink` (cut at a kink), or `Released` (a held contact already tensile at the step
//!   start was released; no step). The accepted part of each step is shown to the driver on
//!   the dense output before the state moves on. A rejected step changes nothing: the
//!   contact state changes only at an accepted state;
//! - `events.rs` (closure, release and kink location), `impact.rs` (impacts), `held.rs`
//!   (holding forces, projection, release), `contact.rs` (contact rows in mass-scaled
//!   coordinates);
//! - `driver.rs`: the one loop over the record intervals, owning the response tracker
//!   (continuous peaks and overlap maxima from the dense output with the adaptive gap
//!   element's `DenseObserver`, samples at record points and events), the history and the
//!   overlap audit.
//!
//! The contact books are not the gap element's `ContactLedger` (modes and spring
//! episodes from closure to opening, with a duration, a peak force and a penetration
//! raised while they last): a rigid impact is one instantaneous impulse with the speeds
//! just before and after it, and a contact that stays closed is a held contact with its
//! own persistent phase and release rule. They keep the momentum method's books (impacts,
//! persistent phases, the impact times of the chattering capture) and share the rule that
//! is the same: the impact-rate guard ([`crate::rules::ImpactRateGuard`]).
//!
//! **Options**: `gap_element.tolerance` (the step error tolerance, default 1e-8),
//! `momentum.persistent_contact`, `momentum.capture_velocity`, the contacts' `gap` and
//! `restitution`, `analysis.max_impact_rate`, `analysis.max_steps`. `momentum.modes` and
//! `momentum.impulse` do not apply (all floors are kept; the consistent impulse with lumped
//! masses is the paper's impulse, eqs 23–24, exactly).

mod contact;
mod driver;
mod events;
mod held;
mod impact;
mod problem;
mod stepper;

use structure::Scene;

use crate::gap::System;
use crate::{History, RunOutput, SolverError};

/// Runs the impulse method.
pub fn solve(scene: &Scene, history: Option<&mut History>) -> Result<RunOutput, SolverError> {
    let clock = std::time::Instant::now();
    let sys = System::new(scene)?;
    refuse_too_long(scene, &sys)?;
    let mut out = driver::run(scene, &sys, history)?;
    out.stats.wall_seconds = clock.elapsed().as_secs_f64();
    Ok(out)
}

/// Refuses, before anything is integrated, a run whose step count surely exceeds
/// `analysis.max_steps`: at least one step per record interval and, for the stability of
/// the explicit pair, one per 3.3/ω_max s.
fn refuse_too_long(scene: &Scene, sys: &System) -> Result<(), SolverError> {
    let steps = (scene.duration / sys.sample_dt).max(scene.duration * sys.omega_max / 3.3);
    if steps.is_finite() && steps <= scene.limits.max_steps as f64 {
        return Ok(());
    }
    Err(SolverError::Refused {
        reason: format!(
            "analysis.duration = {:.6e} s needs at least {steps:.3e} steps (record intervals of \
             {:.3e} s, explicit stability at ω_max = {:.3e} rad/s), more than \
             analysis.max_steps = {}",
            scene.duration, sys.sample_dt, sys.omega_max, scene.limits.max_steps
        ),
    })
}
