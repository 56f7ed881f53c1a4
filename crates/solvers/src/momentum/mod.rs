//! # The modal momentum method (Conoscente, Hamburger & Johnson, eqs 19–27)
//!
//! Each building is written in its own mass-normalised modal coordinates with classical
//! modal damping (eqs 25–27):
//!
//! ```text
//! u_b(t) = Σ_n φ_n q_n(t)                                   (26)
//! q̈_n + 2ζ_n ω_n q̇_n + ω_n² q_n = f_n(t) = −Γ_n a_g(t)     (27), Γ_n = φ_nᵀ M 1
//! q_n(0) = φ_nᵀ M u₀,  q̇_n(0) = φ_nᵀ M u̇₀
//! ```
//!
//! **Between events** a_g is piecewise linear on the record grid and every mode is
//! propagated exactly (Nigam–Jennings, [`modal`]): over a full step of length h,
//! (q, q̇)ₖ₊₁ = A(h)(q, q̇)ₖ + B(h)(f(tₖ), f(tₖ₊₁)) with A, B constant per mode (computed
//! once, [`modal::StepCoeffs`]: no trigonometric function per step). The base step h is the
//! record step `dt`, split into m = ⌈4 dt / T_min⌉ equal parts when the shortest kept period
//! T_min < 4 dt ([`problem::STEPS_PER_PERIOD`]: the peaks see one sign change per step; the
//! split is exact); when T_min < 8 h the event check looks at `sub = ⌈8 h / T_min⌉` windows
//! per step (δ, δ̇ at the interior points from precomputed partial propagators) so that each
//! window holds at most one extremum of a gap function. Past the record end a_g = 0 and the
//! same grid continues to the analysis duration. Without a record the grid is T_min/8.
//!
//! **Peaks** ([`peaks`]) are continuous maxima, not samples: floor displacements
//! u = Φq (eq. 26) and story shears k_j (u_j − u_{j−1}) are observed at every base step
//! and event instant, and an extremum between two samples (a sign change of ẏ) is refined
//! on the closed form (deferred to the end of the run, only where it can be the peak).
//! A building whose energy envelope cannot reach any of its peaks over an interval is not
//! observed at all ([`observe`]; exact).
//!
//! **Structure**: [`problem`] (the data built from a scene), [`stepper`] (the state and
//! [`Stepper::advance`], one segment with a typed [`Step`]), [`observe`] (peaks, overlaps,
//! history), [`impact`] (impact resolution), [`persistent`] (held contacts); the driver
//! loop is the private `drive` below, called by [`solve_with_diagnostics`] (through it by
//! [`solve`]) and [`solve_audited`].
//!
//! **Events** ([`events`]): contact c closes when δ_c = u_left − u_right − gap crosses 0
//! upwards (δ̇ > 0). The instant is located with Brent's method (`roots`) on the closed
//! form, to ~2ε·t; closures that open and close inside a segment are caught through the
//! interior maximum of δ.
//!
//! **Impacts** ([`impulse`]): the contact velocities jump by conservation of momentum
//! (eqs 19, 20) with the coefficient of restitution c_r (eqs 21, 22), either with the
//! Delassus value of the kept modes (`consistent`) or with the paper's floor-mass formula
//! (eqs 23–24) projected on the kept modes (`paper`). Contacts closing within 1e-12 s are
//! solved jointly, with the held contacts (plastic) and the touching neighbours (gap within
//! the round-off band) in one frictionless complementarity problem
//! ([`impulse::lcp_impulses`]): no contact leaves an impact approaching. If after a `paper`
//! impulse the floors still approach (truncated modes), the impact is recorded with the
//! paper's achieved restitution and a consistent correction impulse follows that sets
//! v⁺ = −c_r v⁻ (counted in
//! [`Diagnostics::corrections`] and in the `settings` string); so the method never loops
//! and never tunnels.
//!
//! **Impacts and touching contacts**: only a contact whose floors approach faster than
//! `capture_velocity` is an impact. One found closed while separating is ignored; one
//! touching (|δ̇| ≤ `capture_velocity`) joins a persistent-contact phase if holding it needs
//! a compressive force and grazes otherwise (its tiny approach speed is removed). A contact
//! just resolved is re-armed only once its gap has left a round-off band of 1e-10·max(gap,
//! 1 mm) m ([`crate::closure::band`]), so a touching pair is never found closing again and
//! again at one state.
//!
//! **Chattering** ([`persistent`]): when (c_r < 1) the impact intervals on a contact shrink
//! geometrically with a remaining accumulation time below one record step (the record's,
//! not the split base step, so that the split does not change what counts as chattering), and
//! `persistent_contact` is on, a plastic impulse (v⁺ = 0) starts a persistent-contact phase:
//! the floors move together. The phase ends where the instantaneous holding force turns
//! tensile, located by Brent's method (see [`persistent`]). With `persistent_contact =
//! false` the run stops with [`SolverError::EventStorm`] (impact-rate guard) or, at the
//! accumulation point, [`SolverError::Stalled`].
//!
//! **Refused scenes**: before anything is allocated, a scene whose shortest kept period
//! needs more than [`problem::MAX_SUB`] contact checks per record step (base steps times
//! check windows, about 8 dt/T_min), or whose duration
//! needs more than `analysis.max_steps` steps, is refused ([`SolverError::Refused`]).
//!
//! **Energy** ([`energy`]): input, damping, impact losses, final, balance error.
//!
//! ## Configuration (scene `[momentum]`, `[analysis]`)
//! - `momentum.modes` — modes kept per building (count; default all, clamped to floors);
//! - `momentum.impulse` — `consistent` (default) | `paper`;
//! - `momentum.persistent_contact` — bool, default true;
//! - `momentum.capture_velocity` — m/s, default 1e-4;
//! - `analysis.max_impact_rate` — impacts/s over a 0.05 s sliding window, default 2000
//!   (the same guard for every solver: [`crate::rules::ImpactRateGuard`]);
//! - `analysis.max_steps` — propagation segments, default 5e7;
//! - contacts: `gap` (m), `restitution` (dimensionless, default 1).

pub mod audit;
pub mod energy;
pub mod events;
pub mod impact;
pub mod impulse;
pub mod modal;
pub mod observe;
pub mod peaks;
pub mod persistent;
pub mod problem;
pub mod stepper;
pub mod trig;

pub use audit::ContactAudit;
pub use impact::ImpactDiagnostics;
pub use problem::Problem;
pub use stepper::{Diagnostics, State, Step, Stepper, AUDIT_TOLERANCE};

use structure::scene::ImpulseVariant;
use structure::Scene;

use crate::{ContactFlexibility, History, RunOutput, SolverError};

/// Runs the momentum method.
pub fn solve(scene: &Scene, history: Option<&mut History>) -> Result<RunOutput, SolverError> {
    solve_with_diagnostics(scene, history).map(|(o, _)| o)
}

/// Runs the momentum method and returns per-impact diagnostics as well (momentum and
/// kinetic energy before/after every impact, corrections).
pub fn solve_with_diagnostics(
    scene: &Scene,
    history: Option<&mut History>,
) -> Result<(RunOutput, Diagnostics), SolverError> {
    drive(scene, history, false).map(|(o, d, _)| (o, d))
}

/// Runs the momentum method with the contact audit on ([`audit`]: every integrated interval
/// sampled for open contacts gone through each other; 55–61 times the cost of a run on the
/// paper scene).
pub fn solve_audited(scene: &Scene) -> Result<(RunOutput, Diagnostics, ContactAudit), SolverError> {
    drive(scene, None, true).map(|(o, d, a)| (o, d, a.unwrap_or_default()))
}

/// The driver: one loop over the stepper's typed steps, then the run's output.
fn drive(
    scene: &Scene,
    history: Option<&mut History>,
    audit: bool,
) -> Result<(RunOutput, Diagnostics, Option<ContactAudit>), SolverError> {
    let clock = std::time::Instant::now();
    let problem = Problem::new(scene)?;
    let mut st = Stepper::new(&problem, scene, history)?;
    st.audit = audit.then(ContactAudit::new);
    loop {
        match st.advance()? {
            Step::Finished => break,
            Step::Reached | Step::Released { .. } => {}
            Step::ContactClosed { contacts, .. } => st.impact(&contacts)?,
        }
    }
    let final_e = st.finish()?;
    let p = &problem;
    let r_n = scene
        .contacts
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (bl, br) = (&p.modal.buildings[c.left], &p.modal.buildings[c.right]);
            let r = |b: usize, dof: usize| {
                let row = p.modal.floor_row(b, dof);
                p.modal.buildings[b].masses[dof] * row.iter().map(|x| x * x).sum::<f64>()
            };
            ContactFlexibility {
                contact: i,
                modes_left: bl.range.len(),
                // A wall has no modes and no flexibility.
                modes_right: if c.wall { 0 } else { br.range.len() },
                r_n_left: r(c.left, c.left_dof),
                r_n_right: if c.wall { 0.0 } else { r(c.right, c.right_dof) },
            }
        })
        .collect();
    let modes: Vec<String> = p
        .modal
        .buildings
        .iter()
        .map(|b| format!("{}/{}", b.range.len(), b.available))
        .collect();
    let mut settings = format!(
        "{} impulse, modes {}, h = {:.4e} s ({}{} per step), persistent contact {}",
        match p.options.impulse {
            ImpulseVariant::Consistent => "consistent",
            ImpulseVariant::Paper => "paper",
        },
        modes.join(" + "),
        p.h,
        if p.split > 1 {
            format!("record step in {} parts, ", p.split)
        } else {
            String::new()
        },
        structure::count(p.sub, "event-check window", "event-check windows"),
        if p.options.persistent_contact {
            format!("on (capture {:.1e} m/s)", p.options.capture_velocity)
        } else {
            "off".into()
        }
    );
    if st.diag.corrections > 0 {
        settings.push_str(&format!(
            ", {} impacts corrected after the paper impulse",
            st.diag.corrections
        ));
    }
    let mut stats = st.stats.clone();
    if !stats.min_step.is_finite() {
        stats.min_step = 0.0;
    }
    stats.wall_seconds = clock.elapsed().as_secs_f64();
    let energy = st.energy.finish(final_e);
    let diag = std::mem::take(&mut st.diag);
    let impacts = std::mem::take(&mut st.impacts);
    let phases = std::mem::take(&mut st.phases);
    let buildings = st.peaks(scene);
    let overlaps = std::mem::take(&mut st.overlaps);
    let audit = st.audit.take();
    Ok((
        RunOutput {
            impacts,
            persistent_contacts: phases,
            r_n,
            ..RunOutput::on_scene(
                scene, "momentum", settings, buildings, energy, stats, overlaps,
            )
        },
        diag,
        audit,
    ))
}
