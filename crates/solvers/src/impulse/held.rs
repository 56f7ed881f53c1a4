//! Held contacts (persistent contact) of the impulse method: the held set and its Delassus
//! inverse ([`Held`]), the instantaneous holding forces λ = W⁻¹ G ü_free with their
//! round-off bands ([`force_ratio`] and [`ImpulseStepper::holding_forces`]), the projection
//! of the held contacts to zero relative velocity and gap after every step
//! ([`ImpulseStepper::project_held`]) and their release ([`ImpulseStepper::release`]).

use super::contact;
use super::problem::Problem;
use super::stepper::{restoring, ImpulseStepper};
use crate::gap::Stories;
use crate::momentum::impulse;
use crate::{PersistentContact, SolverError};

/// Relative round-off band of the holding forces (as in the momentum method).
const FORCE_BAND: f64 = 1e-9;

/// The contacts held together (persistent contact) and the inverse of their Delassus
/// matrix.
#[derive(Debug, Clone, Default)]
pub(super) struct Held {
    pub set: Vec<usize>,
    /// When each contact of `set` joined it, s.
    pub start: Vec<f64>,
    /// W⁻¹ of `set`, row-major.
    pub inv: Vec<f64>,
}

/// Relative accelerations G ü_free of the contacts `set` without contact forces, m/s², in
/// the state `y` under ground acceleration `ag` (story law from the committed `stories`),
/// and for each the round-off band of its holding force, N: 1e-9 × (|f_l|/m_l + |a_g| plus
/// the same at the right floor) / W_cc, f the restoring forces (the momentum method's band,
/// with the floors' forces in place of its modal terms).
fn free_relative(
    p: &Problem,
    stories: &Stories,
    set: &[usize],
    y: &[f64],
    ag: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (sys, n) = (p.sys, p.sys.n);
    let mut f = vec![0.0; n];
    restoring(sys, stories, &y[..n], &y[n..2 * n], &mut f);
    let mut acc = vec![0.0; n];
    for i in 0..n {
        acc[i] = (f[i] - sys.mass[i] * ag) * sys.inv_mass[i];
    }
    let mut dd = Vec::with_capacity(set.len());
    let mut tol = Vec::with_capacity(set.len());
    for &c in set {
        let cd = &sys.contacts[c];
        dd.push(cd.rel(&acc));
        let mut sc = f[cd.l].abs() * sys.inv_mass[cd.l] + ag.abs();
        if !cd.wall {
            sc += f[cd.r].abs() * sys.inv_mass[cd.r] + ag.abs();
        }
        let g = &p.geoms[c];
        tol.push(FORCE_BAND * sc / g.dot(&g.g));
    }
    (dd, tol)
}

/// Holding forces of the held set from its stored W⁻¹ (no failure possible) in the state
/// `y` under ground acceleration `ag`: the smallest λ_k / band_k and its index in the held
/// set.
pub(super) fn force_ratio(
    p: &Problem,
    stories: &Stories,
    held: &Held,
    y: &[f64],
    ag: f64,
) -> (f64, usize) {
    let k = held.set.len();
    let (dd, tol) = free_relative(p, stories, &held.set, y, ag);
    (0..k)
        .map(|a| {
            let lam: f64 = (0..k).map(|b| held.inv[a * k + b] * dd[b]).sum();
            (lam / tol[a].max(f64::MIN_POSITIVE), a)
        })
        .fold((f64::INFINITY, 0), |m, x| if x.0 < m.0 { x } else { m })
}

impl ImpulseStepper<'_> {
    /// Instantaneous holding forces λ = W⁻¹ G ü_free (N, > 0 compressive) of `set` in the
    /// state `y` under ground acceleration `ag`, with their round-off bands.
    pub(super) fn holding_forces(
        &self,
        set: &[usize],
        y: &[f64],
        ag: f64,
        time: f64,
    ) -> Result<(Vec<f64>, Vec<f64>), SolverError> {
        let (dd, tol) = free_relative(&self.p, &self.s.stories, set, y, ag);
        let lam = impulse::solve_delassus(&self.p.geoms, set, dd, time, "holding forces")?;
        Ok((lam, tol))
    }

    /// Holding forces of the held contacts per scene contact (history output), N.
    pub(super) fn contact_forces(&self, ag: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.p.sys.contacts.len()];
        let held = &self.s.held;
        let k = held.set.len();
        if k > 0 {
            let (dd, _) = free_relative(&self.p, &self.s.stories, &held.set, &self.s.y, ag);
            for (a, &c) in held.set.iter().enumerate() {
                out[c] = (0..k).map(|b| held.inv[a * k + b] * dd[b]).sum();
            }
        }
        out
    }

    /// Recomputes W⁻¹ after the held set changed.
    pub(super) fn held_changed(&mut self) -> Result<(), SolverError> {
        self.s.held.inv = contact::delassus_inverse(&self.p.geoms, &self.s.held.set, self.s.t)?;
        self.buf = vec![0.0; 2 * self.s.held.set.len()];
        Ok(())
    }

    /// Contact `c` joins the held set now (its impact history is cleared).
    pub(super) fn join_held(&mut self, c: usize) {
        if !self.s.held.set.contains(&c) {
            self.s.held.set.push(c);
            self.s.held.start.push(self.s.t);
            self.s.last_impacts[c].clear();
        }
    }

    /// Sets the relative velocity and the gap of the contacts `set` to zero: a plastic
    /// micro-impulse Δv = −M⁻¹Gᵀ W⁻¹ G v and the mass-weighted position correction
    /// Δu = −M⁻¹Gᵀ W⁻¹ δ; the mechanical energy they remove goes to the contact account
    /// (for a yielding story, net of the plastic work the correction does: the stories are
    /// committed at the corrected state). The stories must be committed at the current state.
    pub(super) fn project_held(&mut self, set: &[usize]) -> Result<(), SolverError> {
        if set.is_empty() {
            return Ok(());
        }
        let (sys, n) = (self.p.sys, self.p.sys.n);
        let t = self.s.t;
        let vrel: Vec<f64> = set.iter().map(|&c| self.rel_velocity(c)).collect();
        let p = impulse::solve_delassus(&self.p.geoms, set, vrel, t, "held contacts")?;
        let imp: Vec<(usize, f64)> = set.iter().copied().zip(p).collect();
        self.contact_loss += self.apply_impulses(&imp);
        let dgap: Vec<f64> = set
            .iter()
            .map(|&c| sys.contacts[c].rel(&self.s.y[..n]) - sys.contacts[c].gap)
            .collect();
        let x = impulse::solve_delassus(&self.p.geoms, set, dgap, t, "held contacts")?;
        let e0 = self.energy_with_hysteresis();
        let mut ws = contact::scale(sys, &self.s.y[..n]);
        let corr: Vec<(usize, f64)> = set.iter().copied().zip(x).collect();
        impulse::apply(&self.p.geoms, &corr, &mut ws);
        contact::unscale(sys, &ws, &mut self.s.y[..n]);
        self.commit(None);
        self.contact_loss += e0 - self.energy_with_hysteresis();
        Ok(())
    }

    /// Ends the persistent phase of `contact` now (its holding force turned tensile).
    pub(super) fn release(&mut self, contact: usize) -> Result<(), SolverError> {
        self.end_phase(contact, "tension");
        self.stats.events += 1;
        self.held_changed()
    }

    /// Removes `contact` from the held set and records its phase, ended by `why` (the
    /// caller updates the held set's Delassus inverse).
    pub(super) fn end_phase(&mut self, contact: usize, why: &str) {
        let t = self.s.t;
        if let Some(i) = self.s.held.set.iter().position(|&c| c == contact) {
            self.s.held.set.remove(i);
            let start = self.s.held.start.remove(i);
            if t > start {
                self.phases.push(PersistentContact {
                    contact,
                    start,
                    end: t,
                    released_by: why.into(),
                });
            }
        }
        self.s.grazing[contact] = true;
    }
}
