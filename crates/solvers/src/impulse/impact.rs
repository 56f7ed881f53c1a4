//! Impacts of the impulse method: the contacts found closing are resolved by the momentum
//! method's rules ([`crate::momentum::Stepper::impact`]) on the physical velocities, with
//! its impulse code on mass-scaled coordinates ([`super::contact`]): impact, touching
//! (joins the held set or grazes), separating (ignored), chattering captured into
//! persistent contact.
//!
//! The books are the momentum method's, not the gap element's
//! [`crate::gap::ledger::ContactLedger`]: a rigid impact is instantaneous, one impulse with
//! the speeds just before and after it (no episode with a duration, a peak force or a
//! penetration to raise while it lasts), and a contact that stays closed is a held
//! contact with its own phase ([`crate::PersistentContact`]), not an open episode. What is
//! shared is the rule: the impact-rate guard ([`crate::rules::ImpactRateGuard`]).

use super::contact;
use super::stepper::ImpulseStepper;
use crate::momentum::impact::restitution;
use crate::momentum::impulse;
use crate::{Impact, SolverError};

impl ImpulseStepper<'_> {
    /// Resolves the contacts found closing now: the momentum method's rules
    /// ([`crate::momentum::Stepper::impact`]) on the physical velocities. Only an
    /// approaching contact (δ̇ > `capture_velocity`) is an impact; a separating one is
    /// ignored; a touching one joins the held set if holding it needs a compressive force
    /// (ground acceleration `ag`, m/s²) and grazes otherwise. Impacts get the consistent
    /// impulse W_AA P_A = (1 + e) v_A (small LCP), with e = 0 for a chattering capture.
    pub(super) fn impact(&mut self, closing: &[usize], ag: f64) -> Result<(), SolverError> {
        let t = self.s.t;
        let cfg = self.cfg;
        self.stats.events += 1;
        let cap = cfg.capture_velocity;
        let mut contacts = Vec::with_capacity(closing.len());
        let mut touching = Vec::new();
        for &c in closing {
            let v = self.rel_velocity(c);
            if v < -cap {
                self.s.grazing[c] = true;
            } else if v > cap || (v > 0.0 && !cfg.persistent_contact) {
                contacts.push(c);
            } else {
                touching.push(c);
            }
        }
        let mut set_changed = false;
        if !touching.is_empty() {
            let held = self.s.held.set.clone();
            let mut set = held.clone();
            set.extend(&touching);
            let y = self.s.y.clone();
            let (lam, tol) = self.holding_forces(&set, &y, ag, t)?;
            let mut join = held.clone();
            let mut graze = Vec::new();
            for (k, &c) in set.iter().enumerate().skip(held.len()) {
                if lam[k] >= -tol[k] && !cfg.persistent_contact {
                    return Err(crate::momentum::impact::stalled_without_persistence(
                        c,
                        t,
                        self.p.geoms[c].restitution,
                    ));
                }
                if lam[k] >= -tol[k] {
                    join.push(c);
                    self.join_held(c);
                    set_changed = true;
                } else {
                    graze.push(c);
                }
                self.s.grazing[c] = true;
            }
            join.extend(&graze);
            self.project_held(&join)?;
        }
        if !contacts.is_empty() {
            self.impulses(&contacts, &mut set_changed)?;
        }
        // The velocities changed: the flow flags of yielding stories follow.
        self.commit(None);
        if set_changed {
            self.held_changed()?;
        }
        Ok(())
    }

    /// The impacts proper of [`Self::impact`]: the impact-rate guard, the chattering
    /// capture (three impact intervals shrinking with a remaining accumulation time below
    /// the momentum method's base step, c_r < 1), the impulses and their [`Impact`]s.
    fn impulses(&mut self, contacts: &[usize], set_changed: &mut bool) -> Result<(), SolverError> {
        let t = self.s.t;
        let cfg = self.cfg;
        for &c in contacts {
            let cr = self.p.geoms[c].restitution;
            let pc = cfg.persistent_contact;
            self.guard.record(t, || {
                format!("contact {c} (c_r = {cr}) keeps impacting; persistent_contact = {pc}")
            })?;
        }
        let v_before: Vec<f64> = contacts.iter().map(|&c| self.rel_velocity(c)).collect();
        let mut captured = vec![false; contacts.len()];
        for (k, &c) in contacts.iter().enumerate() {
            let hist = &mut self.s.last_impacts[c];
            hist.push_back(t);
            if hist.len() > 3 {
                hist.pop_front();
            }
            let h = self.p.capture_h;
            let accumulating = hist.len() == 3 && {
                let (d1, d2) = (hist[1] - hist[0], hist[2] - hist[1]);
                let r = d2 / d1;
                d1 > 0.0
                    && r < 1.0
                    && d2 < h
                    && d2 * r / (1.0 - r) < h
                    && self.p.geoms[c].restitution < 1.0
            };
            captured[k] =
                cfg.persistent_contact && (v_before[k] < cfg.capture_velocity || accumulating);
        }
        let target: Vec<f64> = contacts
            .iter()
            .zip(&captured)
            .zip(&v_before)
            .map(|((&c, &cap), v)| {
                let e = if cap {
                    0.0
                } else {
                    self.p.geoms[c].restitution
                };
                (1.0 + e) * v.max(0.0)
            })
            .collect();
        // The held contacts take part as perfectly plastic participants, as in the momentum
        // method (`momentum::Stepper::impact`, `with_held`): one LCP, not an impact followed
        // by a projection that makes the impacting contact approach again.
        let mut set = contacts.to_vec();
        let mut target = target;
        let held = self.s.held.set.iter().copied();
        impulse::add_plastic(&mut set, &mut target, held, |c| self.rel_velocity(c));
        // Touching neighbours (gap within the band, not held), as in the momentum method.
        let n_active = set.len();
        let n = self.p.sys.n;
        let touching: Vec<usize> = (0..self.p.sys.contacts.len())
            .filter(|&c| {
                let cd = &self.p.sys.contacts[c];
                cd.rel(&self.s.y[..n]) - cd.gap >= -self.p.pen[c]
            })
            .collect();
        impulse::add_touching(&mut set, &mut target, touching, |c| self.rel_velocity(c));
        let imp = impulse::lcp_impulses(&self.p.geoms, &set, &target, n_active, t)?;
        self.contact_loss += self.apply_impulses(&imp);
        for (k, &c) in contacts.iter().enumerate() {
            let vb = v_before[k];
            let va = self.rel_velocity(c);
            let p = imp.iter().find(|(x, _)| *x == c).map_or(0.0, |&(_, p)| p);
            let undefined = crate::momentum::impact::undefined_restitution(
                vb,
                cfg.capture_velocity,
                captured[k],
            );
            self.impacts.push(Impact {
                contact: c,
                time: t,
                relative_velocity_before: vb,
                relative_velocity_after: va,
                achieved_restitution: restitution(vb, va, undefined),
                restitution_undefined: undefined.map(String::from),
                impulse: p,
                duration: None,
                peak_force: None,
                max_penetration: None,
            });
            self.stats.impacts += 1;
            self.s.grazing[c] = true;
            if captured[k] && !self.s.held.set.contains(&c) {
                self.join_held(c);
                *set_changed = true;
            }
        }
        if !self.s.y.iter().all(|x| x.is_finite()) {
            return Err(SolverError::NonFinite {
                time: t,
                context: "floor velocities after an impulse".into(),
            });
        }
        // Held contacts the impact pulled apart leave the held set.
        let apart: Vec<usize> = self
            .s
            .held
            .set
            .iter()
            .copied()
            .filter(|&c| self.rel_velocity(c) < -cfg.capture_velocity)
            .collect();
        for c in apart {
            self.end_phase(c, "impact");
            *set_changed = true;
        }
        Ok(())
    }

    /// Applies impulses (contact, P) to the velocities, returning the kinetic energy lost.
    pub(super) fn apply_impulses(&mut self, imp: &[(usize, f64)]) -> f64 {
        let n = self.p.sys.n;
        let ke0 = self.kinetic();
        let mut w = contact::scale(self.p.sys, &self.s.y[n..2 * n]);
        impulse::apply(&self.p.geoms, imp, &mut w);
        contact::unscale(self.p.sys, &w, &mut self.s.y[n..2 * n]);
        ke0 - self.kinetic()
    }
}
