//! The driver loop of the impulse method (one loop: [`run`]) and the event handlers it
//! calls: impacts ([`Run::impact`]), releases ([`Run::release`]) and the projection of held
//! contacts ([`Run::project_held`]). See the module docs of [`super`] for the equations.

use std::collections::VecDeque;

use structure::{MomentumOptions, Scene};

use super::contact;
use crate::gap::adaptive::{dense_overlaps, dense_peaks, kin};
use crate::gap::dopri::Dopri5;
use crate::gap::stories::Kink;
use crate::gap::{Segment, Stories, System};
use crate::momentum::events::Conv;
use crate::momentum::impact::restitution;
use crate::momentum::impulse::{self, ContactGeom};
use crate::momentum::problem::SIMULTANEOUS;
use crate::overlap::OverlapTracker;
use crate::response::ResponseTracker;
use crate::rules::ImpactRateGuard;
use crate::{History, Impact, PersistentContact, SolverError, Stats};

/// Samples of the dense output per step for the event search (each window holds at most one
/// extremum of a gap function: steps are far below an eighth of the shortest period).
const EVENT_SAMPLES: usize = 4;

/// Relative round-off band of the holding forces (as in the momentum method).
const FORCE_BAND: f64 = 1e-9;

/// The restoring forces −f_s(u) − C v (N) into `f` (f_s = K u for linear stories, the story
/// law from the committed `stories` state for yielding ones: a pure trial); returns the
/// damping power vᵀ C v (W).
///
/// The one place where the impulse method calls [`System::internal`].
#[inline]
fn restoring(sys: &System, stories: &Stories, u: &[f64], v: &[f64], f: &mut [f64]) -> f64 {
    sys.internal(stories, u, v, f)
}

/// Free acceleration (no contact force) into `acc`, with the ground acceleration `ag`;
/// returns (input power −vᵀ M 1 a_g, damping power vᵀ C v), W.
#[inline]
fn free_acceleration(
    sys: &System,
    stories: &Stories,
    ag: f64,
    u: &[f64],
    v: &[f64],
    acc: &mut [f64],
) -> (f64, f64) {
    let pdamp = restoring(sys, stories, u, v, acc);
    let mut pin = 0.0;
    for i in 0..sys.n {
        let f = sys.mass[i] * ag;
        acc[i] -= f;
        pin -= f * v[i];
    }
    for i in 0..sys.n {
        acc[i] *= sys.inv_mass[i];
    }
    (pin, pdamp)
}

/// The contacts held together (persistent contact) and the inverse of their Delassus
/// matrix.
#[derive(Debug, Clone, Default)]
struct Held {
    set: Vec<usize>,
    start: Vec<f64>,
    /// W⁻¹ of `set`, row-major.
    inv: Vec<f64>,
}

/// Right-hand side of y = [u; v; E_input; E_damping; W_contact] with the held contacts
/// `held` frozen: M ü = −K u − C u̇ − M 1 a_g − Σ_held G_cᵀ λ_c with λ = W⁻¹ G ü_free
/// (so that G ü = 0 on the held contacts). `buf` holds 2·|held| numbers.
#[allow(clippy::too_many_arguments)]
fn rhs(
    sys: &System,
    stories: &Stories,
    seg: &Segment,
    held: &Held,
    buf: &mut [f64],
    t: f64,
    y: &[f64],
    o: &mut [f64],
) {
    let n = sys.n;
    let (u, rest) = y.split_at(n);
    let v = &rest[..n];
    let (ou, orest) = o.split_at_mut(n);
    ou.copy_from_slice(v);
    let (acc, extra) = orest.split_at_mut(n);
    let (pin, pdamp) = free_acceleration(sys, stories, seg.at(t), u, v, acc);
    let k = held.set.len();
    let mut pc = 0.0;
    if k > 0 {
        let (dd, lam) = buf.split_at_mut(k);
        for (a, &c) in held.set.iter().enumerate() {
            dd[a] = sys.contacts[c].rel(acc);
        }
        for a in 0..k {
            lam[a] = (0..k).map(|b| held.inv[a * k + b] * dd[b]).sum();
        }
        for (a, &c) in held.set.iter().enumerate() {
            let cd = &sys.contacts[c];
            acc[cd.l] -= lam[a] * sys.inv_mass[cd.l];
            if !cd.wall {
                acc[cd.r] += lam[a] * sys.inv_mass[cd.r];
            }
            pc += lam[a] * cd.rel(v);
        }
    }
    extra[0] = pin;
    extra[1] = pdamp;
    extra[2] = pc;
}

/// Brent's method on [a, b] with absolute tolerance `tol`; without a bracket (round-off at
/// an end) the end where |f| is smaller.
fn brent(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, tol: f64, iters: &mut u64) -> f64 {
    let mut conv = Conv { tol, iterations: 0 };
    let r = roots::find_root_brent(a, b, &mut f, &mut conv);
    *iters += conv.iterations as u64 + 1;
    match r {
        Ok(s) => s.clamp(a, b),
        Err(_) => {
            if f(a).abs() <= f(b).abs() {
                a
            } else {
                b
            }
        }
    }
}

/// The first closure θ in the window [lo, hi] of the dense output, given (δ, δ̇) at both
/// ends: the momentum method's case analysis ([`crate::momentum::events`]) on the
/// interpolant instead of the closed form (the interior maximum is located by Brent on δ̇
/// whenever δ̇ turns from + to −, without the closed form's rigorous filter).
#[allow(clippy::too_many_arguments)]
fn closure_in(
    f: impl Fn(f64) -> (f64, f64),
    lo: f64,
    hi: f64,
    (d0, dd0): (f64, f64),
    (d1, dd1): (f64, f64),
    tol: f64,
    iters: &mut u64,
) -> Option<f64> {
    let d = |s: f64| f(s).0;
    let dd = |s: f64| f(s).1;
    if d0 >= 0.0 {
        if dd0 > 0.0 {
            return if d1 >= 0.0 { Some(lo) } else { None };
        }
        if dd1 <= 0.0 {
            return None;
        }
        let s_min = brent(dd, lo, hi, tol, iters);
        if d(s_min) >= 0.0 {
            return Some(s_min);
        }
        if d1 >= 0.0 {
            return Some(brent(d, s_min, hi, tol, iters));
        }
        return None;
    }
    if d1 >= 0.0 {
        if dd0 < 0.0 && dd1 > 0.0 {
            let s_min = brent(dd, lo, hi, tol, iters);
            return Some(brent(d, s_min, hi, tol, iters));
        }
        return Some(brent(d, lo, hi, tol, iters));
    }
    if dd0 > 0.0 && dd1 < 0.0 {
        let s_max = brent(dd, lo, hi, tol, iters);
        if d(s_max) >= 0.0 {
            return Some(brent(d, lo, s_max, tol, iters));
        }
    }
    None
}

/// The state of a run and its accumulated results.
pub(crate) struct Run<'a> {
    sys: &'a System,
    opts: MomentumOptions,
    geoms: Vec<ContactGeom>,
    /// y = [u; v; E_input; E_damping; W_contact].
    pub y: Vec<f64>,
    /// Committed state of the yielding stories (empty for linear buildings).
    pub stories: Stories,
    pub t: f64,
    held: Held,
    buf: Vec<f64>,
    /// Per contact: just resolved and not yet re-armed (see the momentum method's stepper).
    grazing: Vec<bool>,
    /// Round-off band of each gap, m: 1e-9 · max(gap, 1 mm).
    pen: Vec<f64>,
    last_impacts: Vec<VecDeque<f64>>,
    guard: ImpactRateGuard,
    /// The momentum method's base step h (record step, or T_min/8 without a record): the
    /// chattering-capture rule compares impact intervals with it.
    capture_h: f64,
    /// Energy lost in impacts and in the projections of held contacts, J.
    pub contact_loss: f64,
    pub impacts: Vec<Impact>,
    pub phases: Vec<PersistentContact>,
    pub stats: Stats,
}

impl<'a> Run<'a> {
    fn n(&self) -> usize {
        self.sys.n
    }

    /// The derivative at the current state into `k0` (the first stage of the next step):
    /// a restart of the FSAL chain after the state, the held set or the ground piece changed.
    fn restart(&mut self, seg: &Segment, k0: &mut [f64]) {
        rhs(
            self.sys,
            &self.stories,
            seg,
            &self.held,
            &mut self.buf,
            self.t,
            &self.y,
            k0,
        );
        self.stats.rhs_evaluations += 1;
    }

    /// Kinetic energy ½ vᵀ M v, J.
    fn kinetic(&self) -> f64 {
        let n = self.n();
        0.5 * self.y[n..2 * n]
            .iter()
            .zip(&self.sys.mass)
            .map(|(v, m)| m * v * v)
            .sum::<f64>()
    }

    /// Relative accelerations G ü_free of the contacts `set` without contact forces, m/s²,
    /// and for each the round-off band of its holding force, N: 1e-9 × (|f_l|/m_l + |a_g|
    /// plus the same at the right floor) / W_cc, f the restoring forces (the momentum
    /// method's band, with the floors' forces in place of its modal terms).
    fn free_relative(&self, set: &[usize], y: &[f64], ag: f64) -> (Vec<f64>, Vec<f64>) {
        let (sys, n) = (self.sys, self.n());
        let mut f = vec![0.0; n];
        restoring(sys, &self.stories, &y[..n], &y[n..2 * n], &mut f);
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
            let g = &self.geoms[c];
            tol.push(FORCE_BAND * sc / g.dot(&g.g));
        }
        (dd, tol)
    }

    /// Instantaneous holding forces λ = W⁻¹ G ü_free (N, > 0 compressive) of `set` in the
    /// state `y` under ground acceleration `ag`, with their round-off bands.
    fn holding_forces(
        &self,
        set: &[usize],
        y: &[f64],
        ag: f64,
        time: f64,
    ) -> Result<(Vec<f64>, Vec<f64>), SolverError> {
        let (dd, tol) = self.free_relative(set, y, ag);
        let lam = impulse::solve_delassus(&self.geoms, set, dd, time, "holding forces")?;
        Ok((lam, tol))
    }

    /// Holding forces of the held set from its stored W⁻¹ (no failure possible): the
    /// smallest λ_k / band_k and its index in the held set.
    fn held_force_ratio(&self, y: &[f64], ag: f64) -> (f64, usize) {
        let k = self.held.set.len();
        let (dd, tol) = self.free_relative(&self.held.set, y, ag);
        (0..k)
            .map(|a| {
                let lam: f64 = (0..k).map(|b| self.held.inv[a * k + b] * dd[b]).sum();
                (lam / tol[a].max(f64::MIN_POSITIVE), a)
            })
            .fold((f64::INFINITY, 0), |m, x| if x.0 < m.0 { x } else { m })
    }

    /// Holding forces of the held contacts per scene contact (history output).
    fn contact_forces(&self, ag: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.sys.contacts.len()];
        let k = self.held.set.len();
        if k > 0 {
            let (dd, _) = self.free_relative(&self.held.set, &self.y, ag);
            for (a, &c) in self.held.set.iter().enumerate() {
                out[c] = (0..k).map(|b| self.held.inv[a * k + b] * dd[b]).sum();
            }
        }
        out
    }

    /// Recomputes W⁻¹ after the held set changed.
    fn held_changed(&mut self) -> Result<(), SolverError> {
        self.held.inv = contact::delassus_inverse(&self.geoms, &self.held.set, self.t)?;
        self.buf = vec![0.0; 2 * self.held.set.len()];
        Ok(())
    }

    fn join_held(&mut self, c: usize) {
        if !self.held.set.contains(&c) {
            self.held.set.push(c);
            self.held.start.push(self.t);
            self.last_impacts[c].clear();
        }
    }

    /// Applies impulses (contact, P) to the velocities, returning the kinetic energy lost.
    fn apply_impulses(&mut self, imp: &[(usize, f64)]) -> f64 {
        let n = self.n();
        let ke0 = self.kinetic();
        let mut w = contact::scale(self.sys, &self.y[n..2 * n]);
        impulse::apply(&self.geoms, imp, &mut w);
        contact::unscale(self.sys, &w, &mut self.y[n..2 * n]);
        ke0 - self.kinetic()
    }

    /// Relative velocity u̇_l − u̇_r of contact c, m/s.
    fn rel_velocity(&self, c: usize) -> f64 {
        let n = self.n();
        self.sys.contacts[c].rel(&self.y[n..2 * n])
    }

    /// Commits the yielding stories at the current state (`kink`: the story kink located
    /// at this state, if any). Called for every accepted state and after every change of the
    /// state by an event (impulse, projection), never for a trial.
    fn commit(&mut self, kink: Option<&Kink>) {
        let n = self.n();
        self.stories.commit(&self.y[..n], &self.y[n..2 * n], kink);
    }

    /// Mechanical energy (kinetic + recoverable strain) plus the hysteretic energy
    /// dissipated so far, J, with the committed story state.
    fn energy_with_hysteresis(&self) -> f64 {
        let n = self.n();
        self.sys
            .mech_energy(&self.stories, &self.y[..n], &self.y[n..2 * n])
            + self.stories.hysteretic_energy()
    }

    /// Sets the relative velocity and the gap of the contacts `set` to zero: a plastic
    /// micro-impulse Δv = −M⁻¹Gᵀ W⁻¹ G v and the mass-weighted position correction
    /// Δu = −M⁻¹Gᵀ W⁻¹ δ; the mechanical energy they remove goes to the contact account
    /// (for a yielding story, net of the plastic work the correction does: the stories are
    /// committed at the corrected state). The stories must be committed at the current state.
    fn project_held(&mut self, set: &[usize]) -> Result<(), SolverError> {
        if set.is_empty() {
            return Ok(());
        }
        let (sys, n) = (self.sys, self.n());
        let vrel: Vec<f64> = set.iter().map(|&c| self.rel_velocity(c)).collect();
        let p = impulse::solve_delassus(&self.geoms, set, vrel, self.t, "held contacts")?;
        let imp: Vec<(usize, f64)> = set.iter().copied().zip(p).collect();
        self.contact_loss += self.apply_impulses(&imp);
        let dgap: Vec<f64> = set
            .iter()
            .map(|&c| sys.contacts[c].rel(&self.y[..n]) - sys.contacts[c].gap)
            .collect();
        let x = impulse::solve_delassus(&self.geoms, set, dgap, self.t, "held contacts")?;
        let e0 = self.energy_with_hysteresis();
        let mut ws = contact::scale(sys, &self.y[..n]);
        let corr: Vec<(usize, f64)> = set.iter().copied().zip(x).collect();
        impulse::apply(&self.geoms, &corr, &mut ws);
        contact::unscale(sys, &ws, &mut self.y[..n]);
        self.commit(None);
        self.contact_loss += e0 - self.energy_with_hysteresis();
        Ok(())
    }

    /// Ends the persistent phase of `contact` now (its holding force turned tensile).
    fn release(&mut self, contact: usize) -> Result<(), SolverError> {
        let t = self.t;
        if let Some(i) = self.held.set.iter().position(|&c| c == contact) {
            self.held.set.remove(i);
            let start = self.held.start.remove(i);
            if t > start {
                self.phases.push(PersistentContact {
                    contact,
                    start,
                    end: t,
                    released_by: "tension".into(),
                });
            }
        }
        self.grazing[contact] = true;
        self.stats.events += 1;
        self.held_changed()
    }

    /// Resolves the contacts found closing now: the momentum method's rules
    /// ([`crate::momentum::Stepper::impact`]) on the physical velocities. Only an
    /// approaching contact (δ̇ > `capture_velocity`) is an impact; a separating one is
    /// ignored; a touching one joins the held set if holding it needs a compressive force
    /// and grazes otherwise. Impacts get the consistent impulse W_AA P_A = (1 + e) v_A
    /// (small LCP), with e = 0 for a chattering capture.
    fn impact(&mut self, closing: &[usize], ag: f64) -> Result<(), SolverError> {
        let t = self.t;
        let opts = self.opts.clone();
        self.stats.events += 1;
        let cap = opts.capture_velocity;
        let mut contacts = Vec::with_capacity(closing.len());
        let mut touching = Vec::new();
        for &c in closing {
            let v = self.rel_velocity(c);
            if v < -cap {
                self.grazing[c] = true;
            } else if v > cap || (v > 0.0 && !opts.persistent_contact) {
                contacts.push(c);
            } else {
                touching.push(c);
            }
        }
        let mut set_changed = false;
        if !touching.is_empty() {
            let held = self.held.set.clone();
            let mut set = held.clone();
            set.extend(&touching);
            let y = self.y.clone();
            let (lam, tol) = self.holding_forces(&set, &y, ag, t)?;
            let mut join = held.clone();
            let mut graze = Vec::new();
            for (k, &c) in set.iter().enumerate().skip(held.len()) {
                if lam[k] >= -tol[k] && !opts.persistent_contact {
                    return Err(crate::momentum::impact::stalled_without_persistence(
                        c,
                        t,
                        self.geoms[c].restitution,
                    ));
                }
                if lam[k] >= -tol[k] {
                    join.push(c);
                    self.join_held(c);
                    set_changed = true;
                } else {
                    graze.push(c);
                }
                self.grazing[c] = true;
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

    /// The impacts proper of [`Self::impact`].
    fn impulses(&mut self, contacts: &[usize], set_changed: &mut bool) -> Result<(), SolverError> {
        let t = self.t;
        let opts = self.opts.clone();
        for &c in contacts {
            let cr = self.geoms[c].restitution;
            let pc = opts.persistent_contact;
            self.guard.record(t, || {
                format!("contact {c} (c_r = {cr}) keeps impacting; persistent_contact = {pc}")
            })?;
        }
        let v_before: Vec<f64> = contacts.iter().map(|&c| self.rel_velocity(c)).collect();
        let mut captured = vec![false; contacts.len()];
        for (k, &c) in contacts.iter().enumerate() {
            let hist = &mut self.last_impacts[c];
            hist.push_back(t);
            if hist.len() > 3 {
                hist.pop_front();
            }
            let h = self.capture_h;
            let accumulating = hist.len() == 3 && {
                let (d1, d2) = (hist[1] - hist[0], hist[2] - hist[1]);
                let r = d2 / d1;
                d1 > 0.0
                    && r < 1.0
                    && d2 < h
                    && d2 * r / (1.0 - r) < h
                    && self.geoms[c].restitution < 1.0
            };
            captured[k] =
                opts.persistent_contact && (v_before[k] < opts.capture_velocity || accumulating);
        }
        let target: Vec<f64> = contacts
            .iter()
            .zip(&captured)
            .zip(&v_before)
            .map(|((&c, &cap), v)| {
                let e = if cap { 0.0 } else { self.geoms[c].restitution };
                (1.0 + e) * v.max(0.0)
            })
            .collect();
        let imp = impulse::lcp_impulses(&self.geoms, contacts, &target, t)?;
        self.contact_loss += self.apply_impulses(&imp);
        for (k, &c) in contacts.iter().enumerate() {
            let vb = v_before[k];
            let va = self.rel_velocity(c);
            let p = imp.iter().find(|(x, _)| *x == c).map_or(0.0, |&(_, p)| p);
            let undefined = if vb <= opts.capture_velocity {
                Some("touching: approach speed at most momentum.capture_velocity")
            } else if captured[k] {
                Some("chattering capture: the accumulating impacts resolved as one plastic impulse")
            } else {
                None
            };
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
            self.grazing[c] = true;
            if captured[k] && !self.held.set.contains(&c) {
                self.join_held(c);
                *set_changed = true;
            }
        }
        if !self.y.iter().all(|x| x.is_finite()) {
            return Err(SolverError::NonFinite {
                time: t,
                context: "floor velocities after an impulse".into(),
            });
        }
        Ok(())
    }
}

/// The earliest event of an accepted step: its θ and what it is.
#[derive(Debug, Clone)]
enum Event {
    Closure(Vec<usize>),
    Release(usize),
    /// A kink of a yielding story (yield or unloading) before any contact event.
    Kink(Kink),
}

/// Runs the impulse method on the assembled system.
pub(crate) fn run<'a>(
    scene: &Scene,
    sys: &'a System,
    mut history: Option<&mut History>,
) -> Result<(Run<'a>, ResponseTracker, OverlapTracker), SolverError> {
    let n = sys.n;
    let dim = 2 * n + 3;
    let tol = scene.gap_element.tolerance;
    let mut dp = Dopri5::new(dim, 2 * n, tol, vec![tol * 1e-3; 2 * n]);
    let duration = scene.duration;
    let limits = &scene.limits;
    let geoms = contact::geometry(sys, scene);
    let nc = geoms.len();
    let capture_h = match &scene.ground {
        Some(g) => g.dt,
        None => 2.0 * std::f64::consts::PI / sys.omega_max / 8.0,
    };
    let mut y = vec![0.0; dim];
    y[..n].copy_from_slice(&sys.u0);
    y[n..2 * n].copy_from_slice(&sys.v0);
    let mut r = Run {
        sys,
        opts: scene.momentum.clone(),
        pen: geoms.iter().map(|c| 1e-9 * c.gap.max(1e-3)).collect(),
        geoms,
        y,
        stories: sys.stories(),
        t: 0.0,
        held: Held::default(),
        buf: Vec::new(),
        grazing: vec![false; nc],
        last_impacts: vec![VecDeque::new(); nc],
        guard: ImpactRateGuard::new(limits.max_impact_rate),
        capture_h,
        contact_loss: 0.0,
        impacts: Vec::new(),
        phases: Vec::new(),
        stats: Stats {
            min_step: f64::INFINITY,
            ..Stats::default()
        },
    };
    for (c, cd) in sys.contacts.iter().enumerate() {
        let d = cd.rel(&r.y[..n]) - cd.gap;
        if d > r.pen[c] {
            return Err(SolverError::Stalled {
                time: 0.0,
                reason: format!(
                    "contact {c} starts penetrated by {d:.3e} m (initial displacements exceed the gap)"
                ),
            });
        }
    }

    // An initial drift beyond yield starts its story on the yield surface (as the gap
    // element's integrators do), before the initial energy is taken.
    {
        let (u0, v0) = r.y[..2 * n].split_at(n);
        r.stories.start(u0, v0);
    }
    let mut tracker = ResponseTracker::new(scene);
    let mut overlaps = OverlapTracker::new(scene);
    let observe = |r: &Run, tracker: &mut ResponseTracker, history: Option<&mut History>, ag| {
        let (u, v) = (&r.y[..n], &r.y[n..2 * n]);
        if history.is_some() {
            sys.observe_sample(&r.stories, tracker, u, v, &r.contact_forces(ag));
        } else {
            sys.observe(&r.stories, tracker, u);
        }
        tracker.sample(r.t, history);
    };
    sys.observe_overlaps(&mut overlaps, 0.0, &r.y[..n]);
    observe(&r, &mut tracker, history.as_deref_mut(), sys.ground_at(0.0));

    let n_int = sys.n_intervals(duration);
    let bp = |i: usize| {
        if i + 1 >= n_int {
            duration
        } else {
            (i + 1) as f64 * sys.sample_dt
        }
    };
    let mut interval = 0usize;
    let mut seg = sys.segment(0);

    r.restart(&seg, &mut dp.k[0]);
    let mut h = {
        let (stories, held, buf) = (&r.stories, &r.held, &mut r.buf);
        let mut f =
            |tt: f64, yy: &[f64], o: &mut [f64]| rhs(sys, stories, &seg, held, buf, tt, yy, o);
        dp.initial_step(&mut f, r.t, &r.y.clone(), bp(0) - r.t)
    };
    r.stats.rhs_evaluations += 1;
    let mut rejected_before = false;
    let mut total_steps: u64 = 0;
    let mut scratch = vec![0.0; dim];
    let mut y_end = vec![0.0; dim];

    while interval < n_int {
        // A held contact whose force is already tensile is released before stepping.
        if !r.held.set.is_empty() {
            let (ratio, k) = r.held_force_ratio(&r.y, seg.at(r.t));
            if ratio < -1.0 {
                let c = r.held.set[k];
                r.release(c)?;
                r.restart(&seg, &mut dp.k[0]);
                continue;
            }
        }
        let t = r.t;
        let t_bp = bp(interval);
        let mut hs = h;
        let mut land = false;
        if t + 1.01 * hs >= t_bp {
            hs = t_bp - t;
            land = true;
        }
        total_steps += 1;
        if total_steps > limits.max_steps {
            return Err(SolverError::StepBudget {
                time: t,
                steps: total_steps - 1,
                limit: limits.max_steps,
            });
        }
        let err = {
            let (stories, held, buf) = (&r.stories, &r.held, &mut r.buf);
            let mut f =
                |tt: f64, yy: &[f64], o: &mut [f64]| rhs(sys, stories, &seg, held, buf, tt, yy, o);
            dp.try_step(&mut f, t, &r.y, hs)
        };
        r.stats.rhs_evaluations += 6;
        let (ok, hnew) = dp.control(err, hs, rejected_before);
        if !ok {
            r.stats.rejected_steps += 1;
            rejected_before = true;
            h = hnew;
            let hmin = 1e-14 * (1.0 + t);
            if h < hmin {
                if err.is_nan() {
                    return Err(SolverError::NonFinite {
                        time: t,
                        context: format!(
                            "the trial step of {hs:.3e} s produced a non-finite state \
                             (held contacts: {:?})",
                            r.held.set
                        ),
                    });
                }
                return Err(SolverError::StepSizeUnderflow {
                    time: t,
                    step: h,
                    min_step: hmin,
                    context: format!(
                        "error norm {err:.3e} after {} rejections; held contacts: {:?}",
                        r.stats.rejected_steps, r.held.set
                    ),
                });
            }
            continue;
        }
        rejected_before = false;
        dp.prepare_dense(t, &r.y, hs);

        // --- event search on the dense output -------------------------------------------
        // Root tolerance: 2ε·t in time (the momentum method's), in units of θ.
        let th_tol = (2.0 * f64::EPSILON * (t + hs) + 1e-300) / hs;
        let mut closures: Vec<(f64, usize)> = Vec::new();
        for (ci, cd) in sys.contacts.iter().enumerate() {
            if r.held.set.contains(&ci) {
                continue;
            }
            if r.grazing[ci] && cd.rel(&r.y[..n]) - cd.gap < -r.pen[ci] {
                r.grazing[ci] = false;
            }
            let shift = if r.grazing[ci] { r.pen[ci] } else { 0.0 };
            let right = (!cd.wall).then_some(cd.r);
            let f = |th: f64| kin(&dp, n, cd.l, right, cd.gap + shift, th);
            let mut prev = f(0.0);
            for j in 1..=EVENT_SAMPLES {
                let (lo, hi) = (
                    (j - 1) as f64 / EVENT_SAMPLES as f64,
                    j as f64 / EVENT_SAMPLES as f64,
                );
                let cur = f(hi);
                if let Some(th) =
                    closure_in(f, lo, hi, prev, cur, th_tol, &mut r.stats.root_iterations)
                {
                    closures.push((th, ci));
                    break;
                }
                prev = cur;
            }
        }
        let mut release: Option<(f64, usize)> = None;
        if !r.held.set.is_empty() {
            let ratio = |th: f64, scratch: &mut [f64]| {
                dp.dense_all(th, scratch);
                r.held_force_ratio(scratch, seg.at(t + th * hs))
            };
            let mut th_a = 0.0;
            let mut iters = 0;
            for j in 1..=EVENT_SAMPLES {
                let th_b = j as f64 / EVENT_SAMPLES as f64;
                let (fb, kb) = ratio(th_b, &mut scratch);
                if fb < -1.0 {
                    let th = brent(
                        |th| ratio(th, &mut scratch).0 + 1.0,
                        th_a,
                        th_b,
                        th_tol,
                        &mut iters,
                    );
                    release = Some((th, r.held.set[kb]));
                    break;
                }
                th_a = th_b;
            }
            r.stats.root_iterations += iters;
        }
        let first_closure = closures.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
        let event = match release {
            Some((th, c)) if th <= first_closure => Some((th, Event::Release(c))),
            _ if first_closure.is_finite() => {
                let simultaneous = SIMULTANEOUS / hs;
                let set: Vec<usize> = closures
                    .iter()
                    .filter(|(th, _)| *th <= first_closure + simultaneous)
                    .map(|&(_, c)| c)
                    .collect();
                Some((first_closure, Event::Closure(set)))
            }
            _ => None,
        };
        // Kinks of yielding stories before the earliest contact event (the gap element's
        // search, [`Stories::locate_kink`]): the step is cut there, so that no step
        // straddles a kink of the story law.
        let event = if r.stories.is_empty() {
            event
        } else {
            let limit = event.as_ref().map_or(1.0, |(th, _)| *th);
            match r
                .stories
                .locate_kink(&dp, 0, n, limit, &mut r.stats.root_iterations)
            {
                Some(k) => Some((k.theta, Event::Kink(k))),
                None => event,
            }
        };

        // --- peaks over the part of the step taken, then commit ------------------------
        let th_end = event.as_ref().map_or(1.0, |(th, _)| th.min(1.0));
        if th_end < 1.0 {
            dp.dense_all(th_end, &mut y_end);
        } else {
            y_end.copy_from_slice(&dp.y1);
        }
        dense_peaks(
            sys,
            &r.stories,
            &dp,
            &r.y,
            &y_end,
            th_end,
            &mut tracker,
            &mut scratch,
        );
        if !overlaps.is_empty() {
            dense_overlaps(sys, &dp, t, &r.y, &y_end, th_end, &mut overlaps);
        }
        let full = th_end >= 1.0;
        if full && event.is_none() && r.held.set.is_empty() {
            dp.accept_full(&mut r.y);
        } else {
            r.y.copy_from_slice(&y_end);
        }
        r.t = if full {
            if land {
                t_bp
            } else {
                t + hs
            }
        } else {
            t + th_end * hs
        };
        let taken = r.t - t;
        if taken > 0.0 {
            r.stats.min_step = r.stats.min_step.min(taken);
        }
        r.stats.max_step = r.stats.max_step.max(taken);
        r.stats.steps += 1;
        h = hnew;

        let mut restart = !(full && event.is_none() && r.held.set.is_empty());
        // The accepted state: commit the yielding stories there (once the peaks over the
        // step, which need the start-of-step law, are taken).
        let kink = match &event {
            Some((_, Event::Kink(k))) => Some(*k),
            _ => None,
        };
        r.commit(kink.as_ref());
        // Held contacts: relative velocity and gap back to zero after every step.
        let held = r.held.set.clone();
        r.project_held(&held)?;
        let ag = seg.at(r.t);
        match &event {
            Some((_, Event::Release(c))) => r.release(*c)?,
            Some((_, Event::Closure(set))) => r.impact(set, ag)?,
            Some((_, Event::Kink(_))) => r.stats.story_kinks += 1,
            None => {}
        }
        let landed = land && full;
        if event.is_some() && !landed {
            sys.observe_overlaps(&mut overlaps, r.t, &r.y[..n]);
            observe(&r, &mut tracker, history.as_deref_mut(), ag);
        }
        if landed {
            sys.observe_overlaps(&mut overlaps, r.t, &r.y[..n]);
            observe(&r, &mut tracker, history.as_deref_mut(), ag);
            interval += 1;
            if interval < n_int {
                let next = sys.segment(interval);
                let (a_new, a_old) = (next.at(r.t), seg.at(r.t));
                if (a_new - a_old).abs() > 1e-9 * (a_new.abs() + a_old.abs()) {
                    restart = true;
                }
                seg = next;
            }
        }
        if restart {
            r.restart(&seg, &mut dp.k[0]);
        }
    }

    for (&c, &start) in r.held.set.iter().zip(&r.held.start) {
        r.phases.push(PersistentContact {
            contact: c,
            start,
            end: r.t,
            released_by: "end of analysis".into(),
        });
    }
    if r.stats.min_step == f64::INFINITY {
        r.stats.min_step = 0.0;
    }
    Ok((r, tracker, overlaps))
}
