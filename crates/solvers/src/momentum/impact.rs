//! Impact resolution at a contact closure (paper eqs 19–24, see [`super::impulse`]):
//! classify the closing contacts (approaching: impact; touching: hold or graze;
//! separating: ignore), capture chattering into persistent contact, apply the
//! consistent or paper impulse (with the consistent correction after a paper impulse
//! that leaves the floors approaching), and book the kinetic-energy loss
//! ½Σ(q̇⁺² − q̇⁻²) to the contact account.

use structure::scene::ImpulseVariant;

use super::impulse;
use super::stepper::Stepper;
use crate::{Impact, SolverError};

/// Per-impact diagnostics not in the JSON output (used by tests).
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactDiagnostics {
    pub time: f64,
    pub contacts: Vec<usize>,
    /// Σ Γ_n q̇_n over all buildings before and after (physical momentum with all modes), N·s.
    pub momentum_before: f64,
    pub momentum_after: f64,
    pub kinetic_before: f64,
    pub kinetic_after: f64,
    /// A consistent correction followed the paper impulse (floors still approaching).
    pub corrected: bool,
    /// The event started a persistent-contact phase.
    pub captured: bool,
}

impl Stepper<'_> {
    /// Resolves the contacts found closing now (see [`super::impulse`]).
    ///
    /// Only an *approaching* contact is an impact. A contact found closed while its floors
    /// separate (δ̇ < −`capture_velocity`) is not: nothing happens. A contact touching
    /// (|δ̇| ≤ `capture_velocity`) is not an impact either: it joins the held set if holding
    /// it needs a compressive force, and is left to graze otherwise (with persistent contact
    /// off, a touching contact under compression is the accumulation point of chattering:
    /// [`SolverError::Stalled`]; one still approaching, 0 < δ̇ ≤ `capture_velocity`, is an
    /// impact as any other). Only impacts feed the impact-rate guard.
    pub fn impact(&mut self, closing: &[usize]) -> Result<(), SolverError> {
        let p = self.p;
        let t = self.s.t;
        self.stats.events += 1;
        let mut contacts = Vec::with_capacity(closing.len());
        let mut touching = Vec::new();
        let cap = p.options.capture_velocity;
        for &c in closing {
            let v = p.contacts[c].dot(&self.s.v);
            if v < -cap {
                // Separating: not an impact (a round-off closure while the floors part).
                self.grazing[c] = true;
            } else if v > cap || (v > 0.0 && !p.options.persistent_contact) {
                contacts.push(c);
            } else {
                touching.push(c);
            }
        }
        if !touching.is_empty() {
            let held: Vec<usize> = self.s.persistent.iter().map(|&(c, _)| c).collect();
            let mut set = held.clone();
            set.extend(&touching);
            let a_g = p.ground(self.s.j, t);
            let (lam, tol) = self.holding_forces(&set, &self.s.x, &self.s.v, a_g, t)?;
            let mut join = held;
            let mut graze = Vec::new();
            // Joins unless the force it would need is tensile beyond round-off (a force
            // within ±tol is held: harmless, and the release is then located when it turns
            // tensile, instead of grazing again and again at the same state).
            for (k, &c) in set.iter().enumerate().skip(join.len()) {
                if lam[k] >= -tol[k] && !p.options.persistent_contact {
                    return Err(stalled_without_persistence(c, t, p.contacts[c].restitution));
                }
                if lam[k] >= -tol[k] {
                    join.push(c);
                    self.s.persistent.push((c, t));
                    self.last_impacts[c].clear();
                } else {
                    graze.push(c);
                }
                self.grazing[c] = true;
            }
            // Held contacts and grazing ones lose their (at most capture_velocity) approach
            // speed: a plastic micro-impulse, so that a grazing pair separates (δ̈ < 0).
            join.extend(&graze);
            if !join.is_empty() {
                self.project_held(&join)?;
            }
        }
        if contacts.is_empty() {
            return Ok(());
        }
        let contacts = &contacts[..];
        for &c in contacts {
            let r = p.contacts[c].delta(&self.s.x).abs() / self.pen[c];
            self.diag.impact_gap_ratio = self.diag.impact_gap_ratio.max(r);
        }
        for &c in contacts {
            self.guard.record(t, || {
                format!(
                    "contact {c} (c_r = {}) keeps impacting; persistent_contact = {}",
                    p.contacts[c].restitution, p.options.persistent_contact
                )
            })?;
        }
        let v_before: Vec<f64> = contacts
            .iter()
            .map(|&c| p.contacts[c].dot(&self.s.v))
            .collect();
        let (mom0, ke0) = (self.momentum(), self.kinetic());
        // Capture into persistent contact?
        let mut captured = vec![false; contacts.len()];
        for (k, &c) in contacts.iter().enumerate() {
            let hist = &mut self.last_impacts[c];
            hist.push_back(t);
            if hist.len() > 3 {
                hist.pop_front();
            }
            // Three impacts whose intervals shrink geometrically, the last shorter than a
            // record step and the rest of the series too: chattering. The scale is the
            // record step, not the base step, so that splitting long record steps (for the
            // peaks) does not change what counts as chattering.
            let accumulating = hist.len() == 3 && {
                let (d1, d2) = (hist[1] - hist[0], hist[2] - hist[1]);
                let r = d2 / d1;
                d1 > 0.0
                    && r < 1.0
                    && d2 < p.record_dt
                    && d2 * r / (1.0 - r) < p.record_dt
                    && p.contacts[c].restitution < 1.0
            };
            captured[k] = p.options.persistent_contact
                && (v_before[k] < p.options.capture_velocity || accumulating);
        }
        let e_eff: Vec<f64> = contacts
            .iter()
            .zip(&captured)
            .map(|(&c, &cap)| if cap { 0.0 } else { p.contacts[c].restitution })
            .collect();
        let mut corrected = false;
        let mut impulses: Vec<f64> = vec![0.0; contacts.len()];
        let mut v_after_report: Vec<f64> = vec![0.0; contacts.len()];
        match p.options.impulse {
            ImpulseVariant::Consistent => {
                let mut set = contacts.to_vec();
                let mut target: Vec<f64> = v_before
                    .iter()
                    .zip(&e_eff)
                    .map(|(v, e)| (1.0 + e) * v.max(0.0))
                    .collect();
                self.with_held(&mut set, &mut target);
                let n_active = set.len();
                // Touching neighbours (gap within the band, not held): in the same problem, so
                // that an impulse pushing one into approach is resolved at once, not as a
                // sequence of impacts at one instant (random seed 2331, record refined twice).
                let touching: Vec<usize> = (0..p.contacts.len())
                    .filter(|&c| p.contacts[c].delta(&self.s.x) >= -self.pen[c])
                    .collect();
                impulse::add_touching(&mut set, &mut target, touching, |c| {
                    p.contacts[c].dot(&self.s.v)
                });
                let imp = impulse::lcp_impulses(&p.contacts, &set, &target, n_active, t)?;
                impulse::apply(&p.contacts, &imp, &mut self.s.v);
                for (c, pc) in imp {
                    if let Some(k) = contacts.iter().position(|&x| x == c) {
                        impulses[k] = pc;
                    }
                }
                for (k, &c) in contacts.iter().enumerate() {
                    v_after_report[k] = p.contacts[c].dot(&self.s.v);
                }
            }
            ImpulseVariant::Paper => {
                let normal: Vec<usize> = contacts
                    .iter()
                    .zip(&captured)
                    .filter(|(_, &cap)| !cap)
                    .map(|(&c, _)| c)
                    .collect();
                let imp = impulse::apply_paper(&p.modal, &p.contacts, &normal, &mut self.s.v);
                for (c, pc) in imp {
                    let k = contacts.iter().position(|&x| x == c).unwrap();
                    impulses[k] = pc;
                }
                for (k, &c) in contacts.iter().enumerate() {
                    v_after_report[k] = p.contacts[c].dot(&self.s.v);
                }
                // Correction: contacts still approaching (or captured) get a consistent
                // impulse to v⁺ = −e_eff v⁻.
                let mut corr_set = vec![];
                let mut target = vec![];
                for (k, &c) in contacts.iter().enumerate() {
                    let va = p.contacts[c].dot(&self.s.v);
                    if captured[k] || va > 0.0 {
                        if !captured[k] {
                            corrected = true;
                        }
                        corr_set.push(c);
                        target.push(va + e_eff[k] * v_before[k].max(0.0));
                    }
                }
                self.with_held(&mut corr_set, &mut target);
                if !corr_set.is_empty() {
                    let imp =
                        impulse::lcp_impulses(&p.contacts, &corr_set, &target, corr_set.len(), t)?;
                    impulse::apply(&p.contacts, &imp, &mut self.s.v);
                    for (c, pc) in imp {
                        let Some(k) = contacts.iter().position(|&x| x == c) else {
                            continue;
                        };
                        impulses[k] += pc;
                        if captured[k] {
                            v_after_report[k] = p.contacts[c].dot(&self.s.v);
                        }
                    }
                }
                if corrected {
                    self.diag.corrections += 1;
                }
            }
        }
        let (mom1, ke1) = (self.momentum(), self.kinetic());
        self.energy.contact += ke0 - ke1;
        self.release_separating();
        for (k, &c) in contacts.iter().enumerate() {
            let vb = v_before[k];
            let undefined = undefined_restitution(vb, p.options.capture_velocity, captured[k]);
            self.impacts.push(Impact {
                contact: c,
                time: t,
                relative_velocity_before: vb,
                relative_velocity_after: v_after_report[k],
                // Undefined for a touching contact (approach at most capture_velocity, with
                // persistent contact off) and for a chattering capture (the accumulating
                // sequence of impacts resolved as one plastic impulse): see `restitution`.
                achieved_restitution: restitution(vb, v_after_report[k], undefined),
                restitution_undefined: undefined.map(String::from),
                impulse: impulses[k],
                duration: None,
                peak_force: None,
                max_penetration: None,
            });
            self.stats.impacts += 1;
            self.grazing[c] = true;
            if captured[k] && !self.s.persistent.iter().any(|&(x, _)| x == c) {
                self.s.persistent.push((c, t));
                self.last_impacts[c].clear();
            }
        }
        self.diag.impacts.push(ImpactDiagnostics {
            time: t,
            contacts: contacts.to_vec(),
            momentum_before: mom0,
            momentum_after: mom1,
            kinetic_before: ke0,
            kinetic_after: ke1,
            corrected,
            captured: captured.iter().any(|&c| c),
        });
        if !self.s.v.iter().sum::<f64>().is_finite() {
            return Err(SolverError::NonFinite {
                time: t,
                context: "modal velocities after an impulse".into(),
            });
        }
        self.refresh_rates();
        Ok(())
    }

    /// Adds the held contacts to an impact's set, as perfectly plastic participants: target
    /// v⁺ = 0 where they approach (v > 0), no impulse otherwise (the complementarity of the
    /// impulses, [`impulse::lcp_impulses`], lets one that the impact pulls apart go).
    ///
    /// Resolving the impact alone and then the held contacts (a plastic projection) would be
    /// a sequence of impacts, not one: the projection moves the floors of the impacting
    /// contact, which then approaches again at the same instant, and so on geometrically
    /// (random seed 1898: approach speeds 0.14, 0.087, 0.065, 0.040, … m/s at one instant).
    /// Left to the next held segment instead, the relative velocity of the held contacts has
    /// to be cancelled by its constant forces, of order m·δ̇/τ: 1e14 N over the slivers of a
    /// contact rattling against held neighbours (seed 1204).
    fn with_held(&self, set: &mut Vec<usize>, target: &mut Vec<f64>) {
        let held = self.s.persistent.iter().map(|&(c, _)| c);
        impulse::add_plastic(set, target, held, |c| self.p.contacts[c].dot(&self.s.v));
    }

    /// Ends the held phase of the contacts an impact has pulled apart (separating faster than
    /// `capture_velocity`), as the release of a tensile force would.
    fn release_separating(&mut self) {
        let cap = self.p.options.capture_velocity;
        let apart: Vec<usize> = self
            .s
            .persistent
            .iter()
            .map(|&(c, _)| c)
            .filter(|&c| self.p.contacts[c].dot(&self.s.v) < -cap)
            .collect();
        for c in apart {
            self.end_phase(c, "impact");
        }
    }

    /// Sets the relative velocity of the held contacts to zero (a plastic micro-impulse;
    /// its kinetic energy goes to the contact account).
    pub(super) fn project_held(&mut self, set: &[usize]) -> Result<(), SolverError> {
        let p = self.p;
        let vrel: Vec<f64> = set.iter().map(|&c| p.contacts[c].dot(&self.s.v)).collect();
        let imp = impulse::solve_delassus(&p.contacts, set, vrel, self.s.t, "held contacts")?;
        let ke0 = self.kinetic();
        let pairs: Vec<(usize, f64)> = set.iter().copied().zip(imp).collect();
        impulse::apply(&p.contacts, &pairs, &mut self.s.v);
        self.energy.contact += ke0 - self.kinetic();
        self.refresh_rates();
        Ok(())
    }

    /// Closes the held gaps where one has left its round-off band: a held segment cut by
    /// another contact's closure (the forces close the gaps at the segment's planned end
    /// only, [`Stepper::persistent_segment`]). The least modal displacement that closes them,
    /// Δq = −Gᵀ W⁻¹ r, as the impulse method does after every step; the potential energy it
    /// changes goes to the contact account. Within the band nothing moves (a segment that
    /// reached its planned end).
    ///
    /// Other contacts must not be pushed through: the contacts `keep` (those closing at the
    /// cut), and any contact the projection would move to δ > 0 deeper than it was, take part
    /// with r = 0 and stay where they are. A projection of the held gaps alone moved a
    /// closing contact into penetration of up to 1.8 mm on random scenes, or a contact
    /// touching after an impact a moment before (7.6 µm, seed 1204), and the impact was
    /// then resolved away from the contact surface.
    pub(super) fn close_held_gaps(
        &mut self,
        set: &[usize],
        keep: &[usize],
    ) -> Result<(), SolverError> {
        let p = self.p;
        if set
            .iter()
            .all(|&c| p.contacts[c].delta(&self.s.x).abs() <= self.pen[c])
        {
            return Ok(());
        }
        let before: Vec<f64> = p.contacts.iter().map(|c| c.delta(&self.s.x)).collect();
        let mut all: Vec<usize> = set.to_vec();
        all.extend(keep.iter().copied().filter(|c| !set.contains(c)));
        let e0 = p.modal.energy(&self.s.x, &self.s.v);
        let x0 = self.s.x.clone();
        // Each pass adds the contacts pushed through by the last one: at most one per contact.
        loop {
            let r: Vec<f64> = all
                .iter()
                .enumerate()
                .map(|(k, &c)| if k < set.len() { before[c] } else { 0.0 })
                .collect();
            let dx = impulse::solve_delassus(&p.contacts, &all, r, self.s.t, "held gaps")?;
            self.s.x.copy_from_slice(&x0);
            let pairs: Vec<(usize, f64)> = all.iter().copied().zip(dx).collect();
            impulse::apply(&p.contacts, &pairs, &mut self.s.x);
            let pushed: Vec<usize> = (0..p.contacts.len())
                .filter(|c| !all.contains(c))
                .filter(|&c| {
                    let d = p.contacts[c].delta(&self.s.x);
                    d > before[c].max(0.0)
                })
                .collect();
            if pushed.is_empty() {
                break;
            }
            all.extend(pushed);
        }
        self.energy.contact += e0 - p.modal.energy(&self.s.x, &self.s.v);
        self.diag.gap_projections += 1;
        self.refresh_values();
        Ok(())
    }
}

/// Why the restitution of a rigid impact is not reported, if it is not: a touching contact
/// (approach speed `vb` at most `capture`, m/s) or a chattering capture (`captured`). Shared
/// by the momentum and impulse methods.
pub(crate) fn undefined_restitution(vb: f64, capture: f64, captured: bool) -> Option<&'static str> {
    if vb <= capture {
        Some("touching: approach speed at most momentum.capture_velocity")
    } else if captured {
        Some("chattering capture: the accumulating impacts resolved as one plastic impulse")
    } else {
        None
    }
}

/// The restitution an impact achieved, −v⁺/v⁻, or NaN when `undefined` gives a reason.
/// Values outside [0, 1] by no more than 1e-12 (round-off of v⁺ = −c_r v⁻) are put on the
/// interval; a larger excursion is reported as computed.
pub(crate) fn restitution(v_before: f64, v_after: f64, undefined: Option<&str>) -> f64 {
    if undefined.is_some() {
        return f64::NAN;
    }
    let r = -v_after / v_before;
    if (-1e-12..=0.0).contains(&r) {
        0.0
    } else if r > 1.0 && r <= 1.0 + 1e-12 {
        1.0
    } else {
        r
    }
}

/// The error of a contact that touches at rest under a compressive force (the accumulation
/// point of chattering impacts) when persistent contact is switched off: the impact law
/// cannot go on (shared by the momentum and impulse methods). `t` in s, `restitution` c_r.
pub(crate) fn stalled_without_persistence(contact: usize, t: f64, restitution: f64) -> SolverError {
    SolverError::Stalled {
        time: t,
        reason: format!(
            "contact {contact} touches at rest under a compressive force (the accumulation \
             point of chattering impacts, c_r = {restitution}); without persistent contact \
             (momentum.persistent_contact = false) the method cannot go on"
        ),
    }
}
