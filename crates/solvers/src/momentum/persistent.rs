//! Persistent contact: the two floors move together (δ = 0) until the force would pull.
//!
//! The contact forces λ_a ≥ 0 are taken constant over each held segment: a base step, cut
//! short by an event, and shortened until the held gaps stray at most
//! `momentum.held_tolerance` × max(gap, 1 mm) at its middle (`held_accurate_length`; they
//! close at its ends only, and in between stray by the mismatch between the mean and the
//! instantaneous forces, which falls as τ³). The exact solution is linear in λ, so the gap at the segment end is
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
//! release leaves the floors touching at rest, not drifting together. A segment cut short by
//! another contact's closure leaves the held gaps open (the forces close them at the planned
//! end only): they are closed by the least modal displacement that moves no other contact
//! through (`Stepper::close_held_gaps`). An impact with held neighbours includes them as
//! plastic participants (`Stepper::impact`). A contact account that turns negative (held
//! contacts and impacts did net work on the buildings) stops the run
//! (`Stepper::check_contact_account`).

use super::impulse::{self, solve_checked, ContactGeom};
use super::modal::{Arc, Modal};
use super::stepper::{Step, Stepper};
use crate::{PersistentContact, SolverError};

/// Shortenings of a held segment for accuracy before the run stops with a reason
/// (`Stepper::held_accurate_length`).
const HELD_SHORTENINGS: usize = 40;

/// χ(τ): displacement at τ of a mode (ω, ζ) under a unit constant load from rest,
/// x'' + 2ζω x' + ω² x = 1, x(0) = x'(0) = 0.
///
/// For ωτ ≤ 0.5 by its Taylor series, whose terms a_k = x⁽ᵏ⁾(0) τᵏ/k! follow from the
/// equation: a_0 = a_1 = 0, a_2 = τ²/2, a_{k+2} = −(2ζωτ a_{k+1})/(k+2) − (ω²τ² a_k)/((k+1)(k+2)).
/// The closed form 1/ω² − (homogeneous part) loses every digit to cancellation when ωτ is
/// small (χ ≈ τ²/2 ≪ 1/ω²): on the very short segments that Brent's method tries while
/// locating a release it returned 0 for every mode and made the force system singular.
pub fn unit_load_displacement(omega: f64, zeta: f64, tau: f64) -> f64 {
    if omega * tau > 0.5 {
        Arc::new(omega, zeta, 0.0, 0.0, 1.0, 1.0, tau).xv(tau).0
    } else {
        unit_load_series(omega, zeta, tau)
    }
}

/// The Taylor series of [`unit_load_displacement`] (converges for any ωτ; used for ωτ ≤ 0.5,
/// where its terms fall at least as (ωτ)/k).
fn unit_load_series(omega: f64, zeta: f64, tau: f64) -> f64 {
    let wt = omega * tau;
    let (b, c) = (2.0 * zeta * wt, wt * wt);
    // a0 holds a_k, a1 holds a_{k+1}; the next term is a_{k+2}.
    let (mut a0, mut a1) = (0.0, 0.5 * tau * tau);
    let mut sum = a1;
    for k in 1..80 {
        let kf = k as f64;
        let a2 = -(b * a1) / (kf + 2.0) - (c * a0) / ((kf + 1.0) * (kf + 2.0));
        sum += a2;
        if a2.abs() <= 1e-18 * sum.abs() && a1.abs() <= 1e-18 * sum.abs() {
            break;
        }
        (a0, a1) = (a1, a2);
    }
    sum
}

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
        .map(|n| unit_load_displacement(modal.omega[n], modal.zeta[n], tau))
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

/// A held trial ([`Stepper::held_trial`]): the modal loads −Σ_c g_c λ_c of the holding
/// forces, the modal state at its end, and the holding forces λ (N, one per held contact,
/// in the order of the set).
pub(super) struct HeldTrial {
    pub loads: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    /// The modal displacements at s/2, when asked for (`held_accurate_length`; empty
    /// otherwise: the release search does not need them).
    pub mid: Vec<f64>,
    pub forces: Vec<f64>,
}

impl Stepper<'_> {
    /// Instantaneous holding forces λ = W⁻¹ δ̈_free (N per unit modal mass, > 0 compressive)
    /// of the contacts `set` in the state (x, v) under ground acceleration `a_g`, and for
    /// each a round-off tolerance (1e-9 of the magnitude of the terms of δ̈_free, over W_cc).
    pub(super) fn holding_forces(
        &self,
        set: &[usize],
        x: &[f64],
        v: &[f64],
        a_g: f64,
        time: f64,
    ) -> Result<(Vec<f64>, Vec<f64>), SolverError> {
        let (p, m) = (self.p, &self.p.modal);
        let mut acc = vec![0.0; set.len()];
        let mut tol = vec![0.0; set.len()];
        for (k, &c) in set.iter().enumerate() {
            let ct = &p.contacts[c];
            let (mut a, mut sc) = (0.0, 0.0);
            for n in 0..m.len() {
                let g = ct.g[n];
                if g != 0.0 {
                    let w = m.omega[n];
                    let (f, d, s) = (-m.gamma[n] * a_g, 2.0 * m.zeta[n] * w * v[n], w * w * x[n]);
                    a += g * (f - d - s);
                    sc += g.abs() * (f.abs() + d.abs() + s.abs());
                }
            }
            acc[k] = a;
            tol[k] = 1e-9 * sc / ct.dot(&ct.g);
        }
        let lam = impulse::solve_delassus(&p.contacts, set, acc, time, "holding forces")?;
        Ok((lam, tol))
    }

    /// The held trajectory over [0, s] from the current state: constant forces that bring
    /// every held gap back to δ = 0 at s (see [`persistent`]).
    pub(super) fn held_trial(
        &self,
        set: &[usize],
        s: f64,
        with_mid: bool,
    ) -> Result<HeldTrial, SolverError> {
        let (p, m) = (self.p, &self.p.modal);
        let (a0, a1) = (
            p.ground(self.s.j, self.s.t),
            p.ground(self.s.j, self.s.t + s),
        );
        let arc = |n: usize, extra: f64| {
            m.arc(
                n,
                self.s.x[n],
                self.s.v[n],
                -m.gamma[n] * a0 + extra,
                -m.gamma[n] * a1 + extra,
                s,
            )
        };
        let free_end: Vec<f64> = (0..m.len()).map(|n| arc(n, 0.0).xv(s).0).collect();
        let dfree: Vec<f64> = set
            .iter()
            .map(|&c| p.contacts[c].delta(&free_end))
            .collect();
        let lam = contact_forces(m, &p.contacts, set, s, &dfree, self.s.t)?;
        let mut fc = vec![0.0; m.len()];
        for (k, &c) in set.iter().enumerate() {
            for (f, g) in fc.iter_mut().zip(&p.contacts[c].g) {
                *f -= g * lam[k];
            }
        }
        let (mut x, mut v) = (vec![0.0; m.len()], vec![0.0; m.len()]);
        let mut mid = Vec::with_capacity(if with_mid { m.len() } else { 0 });
        for n in 0..m.len() {
            let a = arc(n, fc[n]);
            (x[n], v[n]) = a.xv(s);
            if with_mid {
                mid.push(a.xv(0.5 * s).0);
            }
        }
        Ok(HeldTrial {
            loads: fc,
            x,
            v,
            mid,
            forces: lam,
        })
    }

    /// Smallest holding force (relative to its tolerance) at the end of the held trial of
    /// length s, and the contact (index into `set`) it belongs to.
    pub(super) fn held_end_force(
        &self,
        set: &[usize],
        s: f64,
    ) -> Result<(f64, usize), SolverError> {
        if s > 0.0 {
            let t = self.held_trial(set, s, false)?;
            self.force_at(set, s, &t.x, &t.v)
        } else {
            self.force_at(set, s, &self.s.x, &self.s.v)
        }
    }

    /// Smallest holding force (relative to its tolerance) in the state (x, v) at s from the
    /// segment start, and the contact (index into `set`) it belongs to.
    fn force_at(
        &self,
        set: &[usize],
        s: f64,
        x: &[f64],
        v: &[f64],
    ) -> Result<(f64, usize), SolverError> {
        let a1 = self.p.ground(self.s.j, self.s.t + s);
        let (lam, tol) = self.holding_forces(set, x, v, a1, self.s.t + s)?;
        Ok(lam
            .iter()
            .zip(&tol)
            .enumerate()
            .map(|(k, (l, t))| (l / t.max(f64::MIN_POSITIVE), k))
            .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a }))
    }

    /// The longest held segment up to `tau` whose gaps stray at most
    /// `momentum.held_tolerance` × max(gap, 1 mm) from the straight path at its middle.
    ///
    /// The holding forces are constant over a segment, so the held gaps close at its ends
    /// only and in between stray by the mismatch between the mean and the instantaneous
    /// forces: up to 4 mm over a 13 ms segment on random scenes, which a segment cut there
    /// by another contact's closure then had to project away. The deviation falls as τ³.
    fn held_accurate_length(
        &mut self,
        set: &[usize],
        mut tau: f64,
    ) -> Result<(f64, HeldTrial), SolverError> {
        let p = self.p;
        let tol = p.options.held_tolerance;
        let d0: Vec<f64> = set
            .iter()
            .map(|&c| p.contacts[c].delta(&self.s.x))
            .collect();
        let deviation = |trial: &HeldTrial| {
            set.iter()
                .zip(&d0)
                .map(|(&c, d0)| {
                    let ct = &p.contacts[c];
                    (ct.delta(&trial.mid) - 0.5 * d0).abs() / (tol * ct.gap.max(1e-3))
                })
                .fold(0.0, f64::max)
        };
        let mut trial = self.held_trial(set, tau, true)?;
        let mut dev = deviation(&trial);
        for _ in 0..HELD_SHORTENINGS {
            if dev <= 1.0 {
                return Ok((tau, trial));
            }
            // The deviation falls as τ³: aim at 0.7 of the tolerance, within [1/10, 1/2].
            tau *= (0.7 / dev).cbrt().clamp(0.1, 0.5);
            self.diag.held_subdivisions += 1;
            trial = self.held_trial(set, tau, true)?;
            dev = deviation(&trial);
        }
        if dev <= 1.0 {
            return Ok((tau, trial));
        }
        // Never reached on 4 000 random scenes at the default tolerance or at 1e-8: each
        // shortening at least halves τ, so after 40 of them the segment is 1e-12 of the
        // record step and the deviation is round-off, which a tolerance below it cannot meet.
        Err(SolverError::Stalled {
            time: self.s.t,
            reason: format!(
                "held contacts {set:?}: a held segment cannot meet momentum.held_tolerance = \
                 {tol:e}; after {HELD_SHORTENINGS} shortenings to {tau:.3e} s its gaps still \
                 stray {dev:.3e} times the tolerance at its middle (round-off; raise \
                 momentum.held_tolerance)"
            ),
        })
    }

    /// Caps the next held segments while a touching contact is found closing at once.
    ///
    /// The holding forces are the mean forces over a segment, not the instantaneous ones
    /// that decide whether a touching contact joins the held set ([`Stepper::impact`]).
    /// Where a contact is coupled to a held one about as strongly as to itself, the
    /// difference can flip its sign: the instantaneous forces let it separate (it grazes),
    /// the mean force over the next segment pushes it closed, and it is found closing at the
    /// segment's start again, without time advancing (random seed 1898: held 1.335e6 N
    /// instantaneous, 1.490e6 N mean over 5 ms, the grazing contact 3 at −1.2 m/s² and
    /// +7.9 m/s² under them). The mean tends to the instantaneous force as the segment
    /// shortens, so such a closure quarters the next held segments' length, and a held
    /// segment that reaches its end doubles it back, up to the record grid.
    fn adapt_held_cap(&mut self, step: &Step, t0: f64, s_hold: f64, tau_grid: f64) {
        match step {
            Step::ContactClosed { contacts, time }
                if *time - t0 <= 1e-9 * s_hold
                    && contacts.iter().all(|&c| {
                        self.grazing[c]
                            && self.p.contacts[c].dot(&self.s.v).abs()
                                <= self.p.options.capture_velocity
                    }) =>
            {
                self.held_cap = Some(0.25 * s_hold);
            }
            Step::Reached => {
                self.held_cap = self.held_cap.map(|c| 2.0 * c).filter(|&c| c < tau_grid);
            }
            _ => {}
        }
    }

    /// Ends the persistent phase of `set[k]` now.
    pub(super) fn release(&mut self, contact: usize) -> Step {
        self.end_phase(contact, "tension");
        self.stats.events += 1;
        Step::Released {
            contact,
            time: self.s.t,
        }
    }

    /// Removes `contact` from the held set now and records its phase, ended by `why`.
    pub(super) fn end_phase(&mut self, contact: usize, why: &str) {
        let t = self.s.t;
        if let Some(i) = self.s.persistent.iter().position(|&(c, _)| c == contact) {
            let (c, start) = self.s.persistent.remove(i);
            if t > start {
                self.phases.push(PersistentContact {
                    contact: c,
                    start,
                    end: t,
                    released_by: why.into(),
                });
            }
        }
        self.grazing[contact] = true;
    }

    /// A segment with contacts held together (δ = 0). The phase of a contact ends where its
    /// instantaneous holding force turns tensile: at the segment start if it already is,
    /// else at the instant located by Brent's method on the held trajectory.
    pub(super) fn persistent_segment(
        &mut self,
        tau_grid: f64,
        t_end: f64,
    ) -> Result<Step, SolverError> {
        let p = self.p;
        let t0 = self.s.t;
        let set: Vec<usize> = self.s.persistent.iter().map(|&(c, _)| c).collect();
        let a0 = p.ground(self.s.j, self.s.t);
        let (lam0, tol0) = self.holding_forces(&set, &self.s.x, &self.s.v, a0, self.s.t)?;
        if let Some(k) = (0..set.len())
            .filter(|&k| lam0[k] < -tol0[k])
            .min_by(|&a, &b| (lam0[a] / tol0[a]).total_cmp(&(lam0[b] / tol0[b])))
        {
            return Ok(self.release(set[k]));
        }
        let (tau, trial) =
            self.held_accurate_length(&set, self.held_cap.map_or(tau_grid, |c| c.min(tau_grid)))?;
        let (f_end, k_end) = self.force_at(&set, tau, &trial.x, &trial.v)?;
        let (s_hold, release) = if f_end < -1.0 {
            // The force turns tensile inside: locate where (f(0) ≥ −1 ≥ f(τ)).
            let err = std::cell::RefCell::new(None);
            let f = |s: f64| match self.held_end_force(&set, s) {
                Ok((v, _)) => v + 1.0,
                Err(e) => {
                    err.borrow_mut().get_or_insert(e);
                    f64::NAN
                }
            };
            let mut conv = crate::closure::Conv {
                tol: 2.0 * f64::EPSILON * (self.s.t + tau) + 1e-300,
                iterations: 0,
            };
            let r = crate::closure::find_root_brent(0.0, tau, f, &mut conv);
            if let Some(e) = err.into_inner() {
                return Err(e);
            }
            self.stats.root_iterations += conv.iterations as u64 + 1;
            (r.unwrap_or(0.0).clamp(0.0, tau), Some(set[k_end]))
        } else {
            (tau, None)
        };
        if s_hold <= 0.0 {
            if let Some(c) = release {
                return Ok(self.release(c));
            }
        }
        let HeldTrial {
            loads: fc,
            forces: lam,
            ..
        } = if s_hold == tau {
            trial
        } else {
            self.held_trial(&set, s_hold, false)?
        };
        let full = s_hold == tau_grid;
        let t_stop = if full { t_end } else { self.s.t + s_hold };
        for (&c, &l) in set.iter().zip(&lam) {
            self.held_force[c] = l;
        }
        let step = self.segment(s_hold, t_stop, Some(&fc), full);
        self.held_force.fill(0.0);
        let step = step?;
        self.project_held(&set)?;
        let closing: &[usize] = match &step {
            Step::ContactClosed { contacts, .. } => contacts,
            _ => &[],
        };
        self.close_held_gaps(&set, closing)?;
        self.check_contact_account()?;
        self.adapt_held_cap(&step, t0, s_hold, tau_grid);
        match (step, release) {
            (Step::Reached, Some(c)) => Ok(self.release(c)),
            (step, _) => Ok(step),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The series agrees with the closed form where the latter is accurate (ωτ ≥ 0.3, at
    /// most a factor 1/(ωτ)² ≈ 11 of cancellation), matches the first three Taylor terms
    /// for tiny τ (where the closed form returns 0), and is exact for the undamped mode.
    #[test]
    fn unit_load_displacement_is_accurate_for_short_and_long_segments() {
        let (w, z) = (20.0, 0.05);
        for wt in [0.3, 0.4, 0.5, 1.0, 3.0] {
            let tau = wt / w;
            let closed = Arc::new(w, z, 0.0, 0.0, 1.0, 1.0, tau).xv(tau).0;
            let series = unit_load_series(w, z, tau);
            assert!(
                (series - closed).abs() <= 1e-13 * closed,
                "ωτ = {wt}: {series} vs {closed}"
            );
        }
        for tau in [1e-17, 1e-10, 1e-6] {
            let x = unit_load_displacement(w, z, tau);
            let wt = w * tau;
            // τ²/2 − ζωτ³/3 + (4ζ² − 1)ω²τ⁴/24; the next term is O((ωτ)³) relative.
            let taylor =
                0.5 * tau * tau * (1.0 - 2.0 * z * wt / 3.0 + (4.0 * z * z - 1.0) * wt * wt / 12.0);
            assert!(
                x > 0.0 && (x - taylor).abs() <= (wt.powi(3) + 1e-15) * taylor,
                "{tau}: {x} vs {taylor}"
            );
        }
        // Undamped, ωτ = 0.5: (1 − cos ωτ)/ω² = 2 sin²(ωτ/2)/ω².
        let x = unit_load_displacement(w, 0.0, 0.5 / w);
        let exact = 2.0 * (0.25f64).sin().powi(2) / (w * w);
        assert!(
            (x - exact).abs() <= 4.0 * f64::EPSILON * exact,
            "{x} vs {exact}"
        );
    }
}
