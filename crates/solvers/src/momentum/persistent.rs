//! Persistent contact: the two floors move together (δ = 0) until the force would pull.
//!
//! The contact forces λ_a ≥ 0 are linear in time over each held segment (a base step, cut
//! short by an event, and shortened by `held_accurate_length`): from the *instantaneous*
//! holding forces λ₀ = W⁻¹ δ̈_free at its start (below), computed from the state, to end
//! forces λ₁ chosen to bring every held gap to its target at the end (0, or a residual
//! within the held tolerance or twice the round-off band kept as it is: `held_target`).
//! The exact solution is linear in the forces, so the end gaps are
//! δ_end = δ_part − C λ₁, δ_part the end gaps with λ₀ falling linearly to 0, and
//! C_ab = Σ_n g_a,n g_b,n ψ_n(τ), ψ_n(τ) the displacement of mode n at τ under a load rising
//! linearly from 0 to 1 from rest (`unit_ramp_response`). Solving C λ₁ = δ_part − target
//! leaves no drift (the target is absolute). Segment lengths are controlled on two
//! measures, each held to `momentum.held_tolerance` × max(gap, 1 mm): the gaps' deviation
//! from the straight path at the middle (the mismatch between the linear and the
//! instantaneous forces, falling as τ⁴), and the jump of the force at the next segment's
//! start, estimated by the instantaneous forces' second difference |λ₀ − 2λ_mid + λ_end|
//! (λ̈τ²/4: falls as τ²) and weighed by Σₙ gₙ² τ²/(1 + (ωₙτ)²), the gap a force step moves
//! within about a segment (the static gₙ²/ωₙ² of the modes faster than the segment, which
//! the next segments cannot follow). As an adaptive integrator's step, a segment is first
//! tried at the length the previous accepted one of the same held set suggests,
//! τ·(0.7/dev)^(1/p) within [1/5, 5] of it (dev its worst measure relative to the tolerance,
//! p the power that measure was last seen to fall with, at least its own: `HeldLength`),
//! and shortened only if it fails. (Before, every segment was tried at the record step and
//! cut to at most a tenth, assuming the τ² of the jump where the measures fell as τ⁴ to τ⁵:
//! 80 % of the segments were shortened, and most ended 10 to 20 times inside the tolerance.)
//!
//! Why λ₀ is the instantaneous force and not the previous segment's end force: with λ
//! continuous and linear and δ_end = 0 imposed at each end, λ₁ = (…) − (b₀₀/b₀₁) λ₀ with
//! b₀₀/b₀₁ → 2 for small ωτ: the force error is amplified by −2 per segment (unstable).
//! Taken from the state, λ₀ carries no error from segment to segment. Before this release
//! the forces were constant over a segment, the mean force: their steps of about λ̇τ from
//! segment to segment excited the modes the holding forces did not follow, and the peaks
//! converged to the impulse method's (exact instantaneous forces) only as the tolerance's
//! cube root (random seed 7035, an undamped stiff building: 5.1e-2 at the default
//! tolerance, 8.4e-3 at 1e-8; 2.8e-3 and 4.0e-5 now). The linear forces do a little work
//! over a segment whose ends have the same gaps (−λ̇∫δ dt, against none for a constant
//! force), booked to the contact account.
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
use super::modal::Arc;
use super::stepper::{Step, Stepper};
use crate::{PersistentContact, SolverError};

/// Shortenings of a held segment for accuracy before the run stops with a reason
/// (`Stepper::held_accurate_length`).
const HELD_SHORTENINGS: usize = 40;

/// (ψ(τ), ψ'(τ)): displacement and velocity at τ of a mode (ω, ζ) under a load rising
/// linearly from 0 to 1 over τ, from rest: x'' + 2ζω x' + ω² x = t/τ, x(0) = x'(0) = 0.
///
/// For ωτ ≤ 0.5 by its Taylor series (`ramp_series`): the closed form's particular and
/// homogeneous parts are each about 1/ω² while ψ ≈ τ²/6, so it loses every digit to
/// cancellation when ωτ is small (as the constant load's closed form did on the very short
/// segments Brent's method tries while locating a release: 0 for every mode, a singular
/// force system). Otherwise by the closed form, with the transcendental part
/// [e^{−ζωτ}, sin ω_d τ, cos ω_d τ] from `trig` (every arc's of the mode at τ,
/// [`Arc::trig`]: a held trial computes it once for its arcs and ψ).
#[inline]
pub fn unit_ramp_response(
    omega: f64,
    zeta: f64,
    tau: f64,
    trig: impl FnOnce() -> [f64; 3],
) -> (f64, f64) {
    if omega * tau > 0.5 {
        Arc::new(omega, zeta, 0.0, 0.0, 0.0, 1.0, tau).xv_from(tau, trig())
    } else {
        ramp_series(omega, zeta, tau)
    }
}

/// The Taylor series of [`unit_ramp_response`]: terms a_k = x⁽ᵏ⁾(0) τᵏ/k! with
/// a_0 = a_1 = a_2 = 0, a_3 = τ²/6 and, from the equation,
/// a_{k+2} = −(2ζωτ a_{k+1})/(k+2) − (ω²τ² a_k)/((k+1)(k+2)); ψ = Σ a_k, ψ' = Σ k a_k/τ.
/// Converges for any ωτ; used for ωτ ≤ 0.5, where its terms fall at least as (ωτ)/k.
fn ramp_series(omega: f64, zeta: f64, tau: f64) -> (f64, f64) {
    let wt = omega * tau;
    let (b, c) = (2.0 * zeta * wt, wt * wt);
    // a0 holds a_k, a1 holds a_{k+1}; the next term is a_{k+2}.
    let (mut a0, mut a1) = (0.0, tau * tau / 6.0);
    let (mut sum, mut dsum) = (a1, 3.0 * a1);
    let r = &super::modal::RECIPROCALS;
    for k in 2..80 {
        let kf = k as f64;
        // (Reciprocals from the table: the divisions were most of the held trials' cost.)
        let a2 = -(b * a1) * r[k + 2] - (c * a0) * (r[k + 1] * r[k + 2]);
        sum += a2;
        dsum += (kf + 2.0) * a2;
        if a2.abs() <= 1e-18 * sum.abs() && a1.abs() <= 1e-18 * sum.abs() {
            break;
        }
        (a0, a1) = (a1, a2);
    }
    (sum, dsum / tau)
}

/// The smallest holding force relative to its tolerance, and its index.
fn weakest(lam: &[f64], tol: &[f64]) -> (f64, usize) {
    lam.iter()
        .zip(tol)
        .enumerate()
        .map(|(k, (l, t))| (l / t.max(f64::MIN_POSITIVE), k))
        .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a })
}

/// End forces λ₁ (N per unit modal mass) of forces rising linearly from 0 to λ₁ over a
/// segment on the persistent contacts `set` that move their end gaps by `delta` (the gaps
/// being δ_end = `delta` − C λ₁, C_ab = Σ_n g_a,n g_b,n ψ_n, with `psi` the modes'
/// [`unit_ramp_response`] over the segment): the solution of C λ₁ = `delta`.
pub fn ramp_end_forces(
    contacts: &[ContactGeom],
    set: &[usize],
    psi: &[f64],
    delta: &[f64],
    time: f64,
) -> Result<Vec<f64>, SolverError> {
    let c: Vec<Vec<f64>> = set
        .iter()
        .map(|&a| {
            set.iter()
                .map(|&b| {
                    (0..psi.len())
                        .map(|n| contacts[a].g[n] * contacts[b].g[n] * psi[n])
                        .sum()
                })
                .collect()
        })
        .collect();
    solve_checked(c, delta.to_vec()).ok_or_else(|| SolverError::SingularContact {
        time,
        contacts: set.to_vec(),
        context: "holding forces of a persistent-contact phase".into(),
    })
}

/// A held trial ([`Stepper::held_trial`]): the modal loads −Σ_c g_c λ_c of the holding
/// forces at its start then at its end (linear in between), the modal state at its end, and
/// the holding forces λ at its end (N per unit modal mass, one per held contact, in the
/// order of the set).
pub(super) struct HeldTrial {
    pub loads: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    /// The modal displacements at s/2, when asked for (`held_accurate_length`; empty
    /// otherwise: the release search does not need them).
    pub mid: Vec<f64>,
    /// The modal velocities at s/2, with `mid`.
    pub mid_v: Vec<f64>,
    pub forces: Vec<f64>,
}

/// The length the last accepted held segment suggests for the next one of the same held set
/// (`Stepper::held_accurate_length`), as a step-size controller's next step: its length
/// τ·(0.7/dev)^(1/p) within [1/5, 5] of it, dev its worst deviation relative to the
/// tolerance and p the exponent the deviation was last seen to fall with.
#[derive(Debug, Clone)]
pub(super) struct HeldLength {
    /// s.
    pub length: f64,
    /// From the last shortened segment's failed and accepted trials; `None` before one.
    pub exponent: Option<f64>,
    /// The held set (contact indices) it was measured on; another set starts afresh.
    pub set: Vec<usize>,
}

/// Buffers of the held trials, kept between them ([`Stepper::held_trial`]).
#[derive(Debug, Default)]
pub(super) struct HeldScratch {
    /// The length τ that `psi` and `dpsi` belong to (NaN before the first).
    psi_len: f64,
    /// ψ_n(τ), ψ'_n(τ) ([`unit_ramp_response`]) of the last length asked for (a release
    /// search or a segment after a shortened trial asks for it again).
    psi: Vec<f64>,
    dpsi: Vec<f64>,
    /// Every mode's (ζω, ω_d) as `Arc::new` forms them, once per run.
    cd: Vec<(f64, f64)>,
    /// The arguments −ζ_nω_n s, ω_dn s and [`Arc::trig`]'s values of every mode at the
    /// trial's end, then at its middle.
    p: Vec<f64>,
    q: Vec<f64>,
    e: Vec<f64>,
    sn: Vec<f64>,
    cs: Vec<f64>,
    e_mid: Vec<f64>,
    sn_mid: Vec<f64>,
    cs_mid: Vec<f64>,
    /// The held set whose Delassus matrix `delassus` holds, eliminated.
    delassus_set: Vec<usize>,
    delassus: Option<impulse::Factored>,
}

impl HeldScratch {
    pub(super) fn new() -> HeldScratch {
        HeldScratch {
            psi_len: f64::NAN,
            ..Default::default()
        }
    }

    /// [`Arc::trig`] of every mode at s into (e, sn, cs) (the same bits, in vectors).
    fn trig_at(&mut self, m: &super::modal::Modal, s: f64, mid: bool) {
        let nm = m.len();
        if self.cd.len() != nm {
            // The expressions of `Arc::new`.
            self.cd = (0..nm)
                .map(|n| {
                    let (w, z) = (m.omega[n], m.zeta[n]);
                    (z * w, w * (1.0 - z * z).sqrt())
                })
                .collect();
        }
        self.p.clear();
        self.q.clear();
        for &(c, d) in &self.cd {
            // `Arc::trig`'s arguments (−c s, d s).
            self.p.push(-c * s);
            self.q.push(d * s);
        }
        let (e, sn, cs) = if mid {
            (&mut self.e_mid, &mut self.sn_mid, &mut self.cs_mid)
        } else {
            (&mut self.e, &mut self.sn, &mut self.cs)
        };
        for b in [&mut *e, &mut *sn, &mut *cs] {
            b.resize(nm, 0.0);
        }
        super::trig::exp_sin_cos_slices(&self.p, &self.q, e, sn, cs);
    }
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
        // The Delassus matrix changes only with the held set: eliminated once per set (the
        // same operations, and bits, as `impulse::solve_delassus` per call).
        let mut sc = self.held_scratch.borrow_mut();
        if sc.delassus_set != set || sc.delassus.is_none() {
            sc.delassus = impulse::Factored::new(impulse::delassus(&p.contacts, set));
            sc.delassus_set = set.to_vec();
        }
        let lam = sc
            .delassus
            .as_ref()
            .and_then(|f| f.solve(acc))
            .ok_or_else(|| SolverError::SingularContact {
                time,
                contacts: set.to_vec(),
                context: "holding forces".into(),
            })?;
        Ok((lam, tol))
    }

    /// The held trajectory over [0, s] from the current state: forces linear in time from
    /// the instantaneous holding forces `lam0` at the start to the end forces that bring
    /// every held gap to its target at s ([`Stepper::held_target`]; see [`super::persistent`]).
    pub(super) fn held_trial(
        &self,
        set: &[usize],
        lam0: &[f64],
        s: f64,
        with_mid: bool,
    ) -> Result<HeldTrial, SolverError> {
        let (p, m) = (self.p, &self.p.modal);
        let nm = m.len();
        let (a0, a1) = (
            p.ground(self.s.j, self.s.t),
            p.ground(self.s.j, self.s.t + s),
        );
        let arc = |n: usize, e0: f64, e1: f64| {
            m.held_arc(
                n,
                self.s.x[n],
                self.s.v[n],
                -m.gamma[n] * a0 + e0,
                -m.gamma[n] * a1 + e1,
                s,
            )
        };
        // Modal loads −Σ_c g_c λ_c at the start (the instantaneous forces) and at the end.
        fn forces<'l>(set: &'l [usize], lam: &'l [f64]) -> impl Iterator<Item = (usize, f64)> + 'l {
            set.iter().copied().zip(lam.iter().copied())
        }
        let mut loads = vec![0.0; 2 * nm];
        impulse::apply_set(&p.contacts, forces(set, lam0), &mut loads[..nm]);
        // The transcendental part of every mode's arcs at s (the end, shared by the start
        // forces' arc and ψ) and at s/2 (the middle), computed once per trial in vectors.
        let mut guard = self.held_scratch.borrow_mut();
        let sc = &mut *guard;
        sc.trig_at(m, s, false);
        let trig = |sc: &HeldScratch, n: usize| [sc.e[n], sc.sn[n], sc.cs[n]];
        // The end state with the start forces falling to 0 over s; the end forces, rising
        // from 0, close the gaps, and add ψ_n(s), ψ'_n(s) per unit modal load to it.
        let (mut x, mut v) = (vec![0.0; nm], vec![0.0; nm]);
        for n in 0..nm {
            (x[n], v[n]) = arc(n, loads[n], 0.0).xv_from(s, trig(sc, n));
        }
        let part_end = &x;
        // Each held gap's target at the end: its start value if within the held tolerance
        // (closing such a residual over a short segment would take forces growing as 1/s²),
        // else 0.
        let dpart: Vec<f64> = set
            .iter()
            .map(|&c| p.contacts[c].delta(part_end) - self.held_target(c))
            .collect();
        if sc.psi_len != s {
            sc.psi.clear();
            sc.dpsi.clear();
            for n in 0..nm {
                let t = trig(sc, n);
                let (r, dr) = unit_ramp_response(m.omega[n], m.zeta[n], s, || t);
                sc.psi.push(r);
                sc.dpsi.push(dr);
            }
            sc.psi_len = s;
        }
        let lam = ramp_end_forces(&p.contacts, set, &sc.psi, &dpart, self.s.t)?;
        impulse::apply_set(&p.contacts, forces(set, &lam), &mut loads[nm..]);
        for n in 0..nm {
            x[n] += loads[nm + n] * sc.psi[n];
            v[n] += loads[nm + n] * sc.dpsi[n];
        }
        let mut mid = Vec::with_capacity(if with_mid { nm } else { 0 });
        let mut mid_v = Vec::with_capacity(if with_mid { nm } else { 0 });
        if with_mid {
            let h = 0.5 * s;
            sc.trig_at(m, h, true);
            for n in 0..nm {
                let t = [sc.e_mid[n], sc.sn_mid[n], sc.cs_mid[n]];
                let (xm, vm) = arc(n, loads[n], loads[nm + n]).xv_from(h, t);
                mid.push(xm);
                mid_v.push(vm);
            }
        }
        Ok(HeldTrial {
            loads,
            x,
            v,
            mid,
            mid_v,
            forces: lam,
        })
    }

    /// The gap a held segment brings held contact `c` to at its end: its present value if
    /// within `momentum.held_tolerance` × max(gap, 1 mm), the distance the held gaps may stray
    /// anyway, or within twice the contact's round-off band, else 0 (m). A residual left by
    /// an event (a segment cut by a closure, whose held gaps [`Stepper::close_held_gaps`]
    /// closes to the band's edge: seen 1e-18 m outside it after round-off) is so kept
    /// rather than closed by forces that grow as 1/τ² on a short segment (and whose path
    /// strays from the straight one by 3/8 of the residual at the middle whatever τ: below a
    /// tolerance of about 1e-9 that stopped runs); the velocity projection at every segment
    /// end keeps it from drifting.
    fn held_target(&self, c: usize) -> f64 {
        let ct = &self.p.contacts[c];
        let d = ct.delta(&self.s.x);
        if d.abs() <= (self.p.options.held_tolerance * ct.gap.max(1e-3)).max(2.0 * self.pen[c]) {
            d
        } else {
            0.0
        }
    }

    /// Smallest holding force (relative to its tolerance) at the end of the held trial of
    /// length s, and the contact (index into `set`) it belongs to.
    pub(super) fn held_end_force(
        &self,
        set: &[usize],
        lam0: &[f64],
        s: f64,
    ) -> Result<(f64, usize), SolverError> {
        if s > 0.0 {
            let t = self.held_trial(set, lam0, s, false)?;
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
        Ok(weakest(&lam, &tol))
    }

    /// A held segment up to `tau` whose gaps stray at most `momentum.held_tolerance` ×
    /// max(gap, 1 mm) from the straight path at its middle, and whose force jump at the next
    /// segment's start moves the gaps at most as much: first tried at the length the last
    /// accepted segment of this held set suggests ([`HeldLength`]), then shortened (aiming at
    /// 0.7 of the tolerance, within [1/10, 1/2] of the length) until it meets both.
    ///
    /// The holding forces are linear over a segment, from the instantaneous forces at its
    /// start to the end forces that close the gaps at its end, so the gaps close at its ends
    /// and in between stray by the mismatch between the linear and the instantaneous forces,
    /// which falls as τ⁴ (as τ³ with the constant forces of the release before: up to 4 mm
    /// over a 13 ms segment on random scenes). At the end the linear force misses the
    /// instantaneous one by about λ̈τ²/4, estimated as |λ₀ − 2λ_mid + λ_end| from the
    /// instantaneous forces along the trial, and the next segment starts from the
    /// instantaneous one: that jump, a step load, is what excites the modes the holding force
    /// does not follow. Weighed by Σₙ gₙ² τ²/(1 + (ωₙτ)²), the gap it moves within about a
    /// segment, it falls as τ² (the modes faster than the segment) to τ⁴ (slower ones). (The
    /// static Σₙ gₙ²/ωₙ² for every mode was tried first: the next segments follow the slow
    /// modes, yet it asked for segments of 13 µs, 46 times as many, on a random scene.)
    fn held_accurate_length(
        &mut self,
        set: &[usize],
        lam0: &[f64],
        mut tau: f64,
    ) -> Result<(f64, HeldTrial, (f64, usize)), SolverError> {
        let p = self.p;
        let m = &p.modal;
        let tol = p.options.held_tolerance;
        // The straight path's middle: halfway from the start gaps to their targets.
        let d_mid: Vec<f64> = set
            .iter()
            .map(|&c| 0.5 * (p.contacts[c].delta(&self.s.x) + self.held_target(c)))
            .collect();
        // The gap a jump of unit force moves within about a segment: Σₙ gₙ² τ²/(1 + (ωₙτ)²),
        // the static displacement gₙ²/ωₙ² of the modes faster than the segment, which the
        // next segments cannot follow, and gₙ²τ² of the slower ones, which they do.
        let flex = |s: f64| -> Vec<f64> {
            set.iter()
                .map(|&c| {
                    let g = &p.contacts[c].g;
                    (0..m.len())
                        .map(|n| g[n] * g[n] * s * s / (1.0 + (m.omega[n] * s).powi(2)))
                        .sum()
                })
                .collect()
        };
        // (ratio to the tolerance, the power of τ it falls with) of the worst criterion, and
        // the weakest holding force at the trial's end ([`Stepper::force_at`]'s value, for
        // the release check of the segment taken).
        type Deviation = ((f64, f64), (f64, usize));
        let deviation = |st: &Self, trial: &HeldTrial, s: f64| -> Result<Deviation, SolverError> {
            let (t, t_mid) = (st.s.t + s, st.s.t + 0.5 * s);
            let (a1, am) = (p.ground(st.s.j, t), p.ground(st.s.j, t_mid));
            let (lam_end, tol_end) = st.holding_forces(set, &trial.x, &trial.v, a1, t)?;
            let (lam_mid, _) = st.holding_forces(set, &trial.mid, &trial.mid_v, am, t_mid)?;
            let mut worst = (0.0, 4.0);
            let flex = flex(s);
            for (k, &c) in set.iter().enumerate() {
                let ct = &p.contacts[c];
                let scale = tol * ct.gap.max(1e-3);
                let mid = (ct.delta(&trial.mid) - d_mid[k]).abs() / scale;
                let jump = (2.0 * lam_mid[k] - lam0[k] - lam_end[k]).abs() * flex[k] / scale;
                for r in [(mid, 4.0), (jump, 2.0)] {
                    if r.0 > worst.0 {
                        worst = r;
                    }
                }
            }
            Ok((worst, weakest(&lam_end, &tol_end)))
        };
        let tau_asked = tau;
        // The first trial: the length the last accepted segment of this held set suggested
        // (`HeldLength`), within the cap.
        let mut exponent = None;
        if let Some(next) = self.held_next.as_ref().filter(|n| n.set == set) {
            tau = tau.min(next.length);
            exponent = next.exponent;
        }
        let mut trial = self.held_trial(set, lam0, tau, true)?;
        let ((mut dev, mut power), mut end) = deviation(self, &trial, tau)?;
        let mut shortenings = 0;
        let mut failed: Option<(f64, f64)> = None;
        // A segment under 1e-12 of the length asked for is refused even where it meets the
        // tolerance: there the state barely changes in floating point (at a tolerance of
        // 1e-20 a segment of 1e-16 s met it with every gap unchanged, and the run crept on
        // until the driver's no-progress guard stopped it 100 000 segments later).
        while tau >= 1e-12 * tau_asked {
            if dev <= 1.0 {
                // The exponent seen between the failed trial and this one, at least the
                // criterion's own (the deviations fall faster than their leading power over
                // the lengths tried: τ^4 to τ^5 where τ² was assumed, on the paper scene).
                if let (Some((tf, df)), true) = (failed, dev > 0.0) {
                    exponent = Some(((df / dev).ln() / (tf / tau).ln()).clamp(power, 8.0));
                }
                let p = exponent.unwrap_or(power).max(power);
                let grow = if dev > 0.0 {
                    (0.7 / dev).powf(1.0 / p).clamp(0.2, 5.0)
                } else {
                    5.0
                };
                self.held_next = Some(HeldLength {
                    length: tau * grow,
                    exponent,
                    set: set.to_vec(),
                });
                self.diag.held_segments += 1;
                return Ok((tau, trial, end));
            }
            if shortenings == HELD_SHORTENINGS {
                break;
            }
            // Aim at 0.7 of the tolerance, within [1/10, 1/2] of the length.
            let p = exponent.unwrap_or(power).max(power);
            failed = Some((tau, dev));
            tau *= (0.7 / dev).powf(1.0 / p).clamp(0.1, 0.5);
            shortenings += 1;
            self.diag.held_subdivisions += 1;
            trial = self.held_trial(set, lam0, tau, true)?;
            ((dev, power), end) = deviation(self, &trial, tau)?;
        }
        // Never reached on 4 000 random scenes at the default tolerance or at 1e-8: each
        // shortening at least halves τ, so after 40 of them the segment is 1e-12 of the
        // record step and the deviation is round-off, which a tolerance below it cannot meet.
        Err(SolverError::Stalled {
            time: self.s.t,
            reason: format!(
                "held contacts {set:?}: a held segment cannot meet momentum.held_tolerance = \
                 {tol:e}; after {shortenings} shortenings to {tau:.3e} s (of {tau_asked:.3e} s \
                 asked for) its gaps still stray {dev:.3e} times the tolerance at its middle, \
                 or the segment is too short to resolve (round-off; raise \
                 momentum.held_tolerance)"
            ),
        })
    }

    /// Caps the next held segments while a touching contact is found closing at once.
    ///
    /// The holding forces over a segment are not the instantaneous ones that decide whether
    /// a touching contact joins the held set ([`Stepper::impact`]): with the constant (mean)
    /// forces of the release before, the difference was of order λ̇τ; with linear forces
    /// from the instantaneous ones it is smaller, and the cap is kept as the safety net.
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
        let cap = self.held_cap.map_or(tau_grid, |c| c.min(tau_grid));
        let (tau, trial, (f_end, k_end)) = self.held_accurate_length(&set, &lam0, cap)?;
        let (s_hold, release) = if f_end < -1.0 {
            // The force turns tensile inside: locate where (f(0) ≥ −1 ≥ f(τ)).
            let err = std::cell::RefCell::new(None);
            let f = |s: f64| match self.held_end_force(&set, &lam0, s) {
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
            self.held_trial(&set, &lam0, s_hold, false)?
        };
        let full = s_hold == tau_grid;
        let t_stop = if full { t_end } else { self.s.t + s_hold };
        for (k, &c) in set.iter().enumerate() {
            (self.held_force_start[c], self.held_force[c]) = (lam0[k], lam[k]);
        }
        let step = self.segment(s_hold, t_stop, Some(&fc), full);
        self.held_force.fill(0.0);
        self.held_force_start.fill(0.0);
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

    /// The ramp's series (displacement and velocity) agrees with the closed form where the
    /// latter is accurate (ωτ ≥ 0.3: ψ ≈ τ²/6 against parts of 1/ω², at most a factor
    /// 6/(ωτ)² ≈ 67 of cancellation; ψ' ≈ τ/2, a factor 2/(ωτ)² ≈ 22); a constant load is the
    /// sum of a rising and a falling ramp (χ = ψ + φ, χ and φ by the closed form); and the
    /// undamped mode is exact down to τ = 1e-17 s, where the closed form returns 0:
    /// ψ = Σ_k (−1)^k ω^{2k} τ^{2k+2}/(2k+3)!, ψ' = Σ_k (−1)^k ω^{2k} τ^{2k+1}/(2k+2)!
    /// (no cancellation).
    #[test]
    fn unit_ramp_response_is_accurate_for_short_and_long_segments() {
        let unit_ramp_response = |w: f64, z: f64, tau: f64| {
            let trig = Arc::new(w, z, 0.0, 0.0, 0.0, 1.0, tau).trig(tau);
            super::unit_ramp_response(w, z, tau, || trig)
        };
        let (w, z) = (20.0, 0.05);
        for wt in [0.3, 0.4, 0.5, 1.0, 3.0] {
            let tau = wt / w;
            let closed = Arc::new(w, z, 0.0, 0.0, 0.0, 1.0, tau).xv(tau);
            let series = ramp_series(w, z, tau);
            assert!(
                (series.0 - closed.0).abs() <= 1e-13 * closed.0,
                "ωτ = {wt}: {series:?} vs {closed:?}"
            );
            assert!(
                (series.1 - closed.1).abs() <= 1e-13 * closed.1,
                "ωτ = {wt}: {series:?} vs {closed:?}"
            );
            let falling = Arc::new(w, z, 0.0, 0.0, 1.0, 0.0, tau).xv(tau).0;
            let chi = Arc::new(w, z, 0.0, 0.0, 1.0, 1.0, tau).xv(tau).0;
            let psi = unit_ramp_response(w, z, tau).0;
            assert!(
                (psi + falling - chi).abs() <= 1e-13 * chi,
                "ωτ = {wt}: {psi} + {falling} vs {chi}"
            );
        }
        for tau in [1e-17, 1e-10, 1e-6, 0.5 / w, 0.02 / w] {
            let (x, v) = unit_ramp_response(w, 0.0, tau);
            let (mut term, mut exact) = (tau * tau / 6.0, 0.0);
            let (mut vterm, mut vexact) = (0.5 * tau, 0.0);
            for k in 0..30 {
                exact += term;
                vexact += vterm;
                let kf = k as f64;
                term *= -(w * tau).powi(2) / ((2.0 * kf + 4.0) * (2.0 * kf + 5.0));
                vterm *= -(w * tau).powi(2) / ((2.0 * kf + 3.0) * (2.0 * kf + 4.0));
            }
            assert!(
                x > 0.0 && (x - exact).abs() <= 4.0 * f64::EPSILON * exact,
                "{tau}: {x} vs {exact}"
            );
            assert!(
                v > 0.0 && (v - vexact).abs() <= 4.0 * f64::EPSILON * vexact,
                "{tau}: {v} vs {vexact}"
            );
        }
    }
}
