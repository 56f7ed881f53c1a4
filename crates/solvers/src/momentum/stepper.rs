//! Problem (immutable), state (mutable) and the stepper that advances one segment.

use std::collections::VecDeque;

use structure::scene::{ImpulseVariant, Limits};
use structure::{MomentumOptions, Scene};

use super::energy::EnergyAccount;
use super::events::Locator;
use super::impulse::{self, ContactGeom};
use super::modal::{Arc, Modal, StepCoeffs};
use super::peaks;
use super::persistent;
use crate::overlap::OverlapTracker;
use crate::response::ResponseTracker;
use crate::rules::ImpactRateGuard;
use crate::{BuildingResponse, History, Impact, PersistentContact, SolverError, Stats};
use structure::ground::nigam_jennings::Propagator;

/// Simultaneity window for closures, s.
pub const SIMULTANEOUS: f64 = 1e-12;

/// Largest number of event-check windows per record step (memory: `MAX_SUB` × modes × 64
/// bytes of propagators; work: as many closed-form checks per step and contact).
pub const MAX_SUB: usize = 4096;

/// (building, mode) numbers (from 1) of the mode with circular frequency `w`.
fn stiffest_mode(modal: &Modal, w: f64) -> (usize, usize) {
    let n = modal.omega.iter().position(|&x| x == w).unwrap_or(0);
    modal
        .buildings
        .iter()
        .enumerate()
        .find(|(_, b)| b.range.contains(&n))
        .map_or((1, n + 1), |(i, b)| (i + 1, n - b.range.start + 1))
}

/// Everything that does not change during a run.
#[derive(Debug, Clone)]
pub struct Problem {
    pub modal: Modal,
    pub contacts: Vec<ContactGeom>,
    pub options: MomentumOptions,
    pub limits: Limits,
    pub duration: f64,
    /// Record step, s (without a record: T_min/8).
    pub record_dt: f64,
    /// Event-check windows per step (T_min < 8·h ⇒ ⌈8 h/T_min⌉, else 1): δ and δ̇ are
    /// checked at these interior points so that each window holds at most one extremum.
    pub sub: usize,
    /// Base step h = record_dt, s (propagation, energy, response sampling).
    pub h: f64,
    /// Propagators from a step start to its interior check points k·h/sub, k = 1 … sub−1
    /// (per point, per mode: a00 a01 b00 b01 a10 a11 b10 b11).
    pub checks: Vec<Vec<[f64; 8]>>,
    /// ω_n².
    pub omega2: Vec<f64>,
    /// √(Σ_n Γ_n²), kg^½ (norm of the modal load per unit a_g).
    pub gamma_norm: f64,
    /// √W_cc per contact (Delassus diagonal), kg^−½.
    pub sqrt_w: Vec<f64>,
    /// Number of base steps covering the duration (the last may be partial).
    pub n_steps: usize,
    /// Ground acceleration at the start and end of each base step, m/s² (zero past the record).
    pub ag_start: Vec<f64>,
    pub ag_end: Vec<f64>,
    /// Propagators and energy forms for a full base step.
    pub full: StepCoeffs,
}

impl Problem {
    pub fn new(scene: &Scene) -> Result<Problem, SolverError> {
        let modal = Modal::new(&scene.buildings, scene.momentum.modes)?;
        let contacts: Vec<ContactGeom> = scene
            .contacts
            .iter()
            .map(|c| ContactGeom::new(&modal, c))
            .collect();
        let w_max = modal.omega.iter().cloned().fold(0.0, f64::max);
        let t_min = 2.0 * std::f64::consts::PI / w_max;
        let record_dt = scene.ground.as_ref().map_or(t_min / 8.0, |g| g.dt);
        let sub_f = if t_min < 8.0 * record_dt {
            (8.0 * record_dt / t_min).ceil()
        } else {
            1.0
        };
        // Refuse, before allocating, what cannot run: the interior check table grows as
        // record step / shortest period, and the step tables as duration / record step.
        if !(sub_f <= MAX_SUB as f64) {
            let (b, n) = stiffest_mode(&modal, w_max);
            return Err(SolverError::Refused {
                reason: format!(
                    "the shortest kept period is {t_min:.3e} s (building {b}, mode {n}), \
                     {:.3e} times below the record step {record_dt:.3e} s; the momentum method \
                     checks for contact {MAX_SUB} times per record step at most (8 checks per \
                     shortest period): keep fewer modes (momentum.modes), or use the gap \
                     element (--method gap)",
                    record_dt / t_min
                ),
            });
        }
        let sub = sub_f as usize;
        let steps_f = (scene.duration / record_dt).ceil();
        if !(steps_f <= scene.limits.max_steps as f64) {
            return Err(SolverError::Refused {
                reason: format!(
                    "analysis.duration = {:.6e} s needs {steps_f:.3e} steps of {record_dt:.3e} s, \
                     more than analysis.max_steps = {}",
                    scene.duration, scene.limits.max_steps
                ),
            });
        }
        let h = record_dt;
        let checks = (1..sub)
            .map(|k| {
                let s = h * k as f64 / sub as f64;
                (0..modal.len())
                    .map(|n| {
                        let pr = Propagator::new(modal.omega[n], modal.zeta[n], s);
                        [
                            pr.a[0][0], pr.a[0][1], pr.b[0][0], pr.b[0][1], pr.a[1][0], pr.a[1][1],
                            pr.b[1][0], pr.b[1][1],
                        ]
                    })
                    .collect()
            })
            .collect();
        let n_steps = crate::rules::grid_steps(scene.duration, h) as usize;
        let mut ag_start = vec![0.0; n_steps];
        let mut ag_end = vec![0.0; n_steps];
        if let Some(g) = &scene.ground {
            for j in 0..n_steps.min(g.npts().saturating_sub(1)) {
                ag_start[j] = g.accel[j];
                ag_end[j] = g.accel[j + 1];
            }
        }
        let full = StepCoeffs::new(&modal, h);
        let omega2 = modal.omega.iter().map(|w| w * w).collect();
        let gamma_norm = modal.gamma.iter().map(|g| g * g).sum::<f64>().sqrt();
        let sqrt_w = contacts
            .iter()
            .map(|c: &ContactGeom| c.dot(&c.g).sqrt())
            .collect();
        Ok(Problem {
            omega2,
            gamma_norm,
            sqrt_w,
            modal,
            contacts,
            options: scene.momentum.clone(),
            limits: scene.limits.clone(),
            duration: scene.duration,
            record_dt,
            sub,
            h,
            checks,
            n_steps,
            ag_start,
            ag_end,
            full,
        })
    }

    /// Ground acceleration at time t inside base step j, m/s².
    #[inline]
    pub fn ground(&self, j: usize, t: f64) -> f64 {
        let j = j.min(self.n_steps - 1);
        let r = ((t - j as f64 * self.h) / self.h).clamp(0.0, 1.0);
        self.ag_start[j] + r * (self.ag_end[j] - self.ag_start[j])
    }

    /// Start time of base step j.
    #[inline]
    pub fn grid(&self, j: usize) -> f64 {
        (j as f64 * self.h).min(self.duration)
    }
}

/// The mutable state: time, modal coordinates, contacts held together.
#[derive(Debug, Clone)]
pub struct State {
    pub t: f64,
    /// Base step containing t (t ∈ [grid(j), grid(j+1))).
    pub j: usize,
    /// Whether t is exactly grid(j).
    pub on_grid: bool,
    /// Modal displacements q and velocities q̇ (all buildings, flat).
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    /// Contacts in a persistent-contact phase, with the phase start, s.
    pub persistent: Vec<(usize, f64)>,
}

/// What one call of [`Stepper::advance`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Reached the end of the segment (a record sub-step point or the analysis end).
    Reached,
    /// These contacts close at `time` (state is at `time`, before the impulse).
    ContactClosed { contacts: Vec<usize>, time: f64 },
    /// A persistent contact was released at `time` (force would turn tensile).
    Released { contact: usize, time: f64 },
    /// The analysis end is reached.
    Finished,
}

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

/// Extra results of a run (tests).
#[derive(Debug, Clone, Default)]
pub struct Diagnostics {
    pub impacts: Vec<ImpactDiagnostics>,
    pub corrections: u64,
    pub sub_steps: usize,
    pub base_step: f64,
    pub final_x: Vec<f64>,
    pub final_v: Vec<f64>,
}

/// Advances the state one segment at a time; owns the accumulated results.
pub struct Stepper<'a> {
    pub p: &'a Problem,
    pub s: State,
    pub energy: EnergyAccount,
    pub tracker: ResponseTracker,
    pub history: Option<&'a mut History>,
    pub impacts: Vec<Impact>,
    pub phases: Vec<PersistentContact>,
    pub stats: Stats,
    pub diag: Diagnostics,
    guard: ImpactRateGuard,
    last_impacts: Vec<VecDeque<f64>>,
    /// Per contact: just resolved (impact, release, graze) and not yet re-armed. Such a
    /// contact's closure is detected at δ = `pen` instead of 0, until its gap has opened
    /// beyond −`pen`: a contact left touching at rest is not found closing again and again
    /// at the same state by round-off.
    grazing: Vec<bool>,
    /// Round-off band of each gap, m: 1e-9 · max(gap, 1 mm).
    pen: Vec<f64>,
    xn: Vec<f64>,
    vn: Vec<f64>,
    disp_max: Vec<Vec<f64>>,
    /// Per-mode energy sums of the fast path (input, damping), J; folded in by `finish`.
    win_acc: Vec<f64>,
    dmp_acc: Vec<f64>,
    win_step: Vec<f64>,
    dmp_step: Vec<f64>,
    shear_max: Vec<Vec<f64>>,
    stiffness: Vec<Vec<f64>>,
    u: Vec<Vec<f64>>,
    arcs: Vec<Arc>,
    /// Floor velocities at the current and at the previous sample, per building.
    ud: Vec<Vec<f64>>,
    u_prev: Vec<Vec<f64>>,
    ud_prev: Vec<Vec<f64>>,
    /// The interval integrated since the previous sample (continuous peaks, [`peaks`]).
    interval: peaks::Interval,
    /// Story-shear coefficients c_n = k_j (φ_n[j] − φ_n[j−1]) per building, story-major.
    shear_rows: Vec<Vec<f64>>,
    /// Scratch: the coefficients of one response quantity.
    coef: Vec<f64>,
    /// Contact forces of the segment being integrated, N, one per scene contact: the
    /// holding forces of held contacts, 0 otherwise (history output).
    held_force: Vec<f64>,
    /// Overlap audit of facing floors without a contact ([`crate::overlap`]).
    pub overlaps: OverlapTracker,
    /// Per audited pair: coefficients of u_left − u_right on all modes (φ_left − φ_right).
    overlap_rows: Vec<Vec<f64>>,
}

impl<'a> Stepper<'a> {
    pub fn new(
        p: &'a Problem,
        scene: &Scene,
        history: Option<&'a mut History>,
    ) -> Result<Self, SolverError> {
        let nm = p.modal.len();
        let mut x = vec![0.0; nm];
        let mut v = vec![0.0; nm];
        for (b, bd) in scene.buildings.iter().enumerate() {
            p.modal.project(b, &bd.initial_displacement, &mut x);
            p.modal.project(b, &bd.initial_velocity, &mut v);
        }
        let mut st = Stepper {
            p,
            s: State {
                t: 0.0,
                j: 0,
                on_grid: true,
                x,
                v,
                persistent: vec![],
            },
            energy: EnergyAccount::default(),
            tracker: ResponseTracker::new(scene),
            history,
            impacts: vec![],
            phases: vec![],
            stats: Stats {
                min_step: f64::INFINITY,
                ..Stats::default()
            },
            diag: Diagnostics {
                sub_steps: p.sub,
                base_step: p.h,
                ..Diagnostics::default()
            },
            guard: ImpactRateGuard::new(p.limits.max_impact_rate),
            last_impacts: vec![VecDeque::new(); p.contacts.len()],
            grazing: vec![false; p.contacts.len()],
            pen: p.contacts.iter().map(|c| 1e-9 * c.gap.max(1e-3)).collect(),
            xn: vec![0.0; nm],
            vn: vec![0.0; nm],
            win_acc: vec![0.0; nm],
            dmp_acc: vec![0.0; nm],
            win_step: vec![0.0; nm],
            dmp_step: vec![0.0; nm],
            disp_max: scene
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors()])
                .collect(),
            shear_max: scene
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors()])
                .collect(),
            stiffness: scene
                .buildings
                .iter()
                .map(|b| b.story_stiffness.clone())
                .collect(),
            u: p.modal
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors])
                .collect(),
            arcs: Vec::with_capacity(nm),
            ud: p
                .modal
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors])
                .collect(),
            u_prev: p
                .modal
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors])
                .collect(),
            ud_prev: p
                .modal
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors])
                .collect(),
            interval: peaks::Interval::default(),
            held_force: vec![0.0; p.contacts.len()],
            overlap_rows: Vec::new(),
            overlaps: OverlapTracker::new(scene),
            coef: vec![
                0.0;
                p.modal
                    .buildings
                    .iter()
                    .map(|b| b.range.len())
                    .max()
                    .unwrap_or(0)
            ],
            shear_rows: p
                .modal
                .buildings
                .iter()
                .zip(&scene.buildings)
                .map(|(bm, bd)| {
                    let (nf, nmb) = (bm.n_floors, bm.range.len());
                    let mut rows = vec![0.0; nf * nmb];
                    for j in 0..nf {
                        for m in 0..nmb {
                            let below = if j > 0 { bm.phi[m * nf + j - 1] } else { 0.0 };
                            rows[j * nmb + m] =
                                bd.story_stiffness[j] * (bm.phi[m * nf + j] - below);
                        }
                    }
                    rows
                })
                .collect(),
        };
        st.overlap_rows = st
            .overlaps
            .pairs
            .iter()
            .map(|op| {
                let mut row = p.modal.floor_row(op.left, op.left_dof);
                for (r, f) in row
                    .iter_mut()
                    .zip(p.modal.floor_row(op.right, op.right_dof))
                {
                    *r -= f;
                }
                row
            })
            .collect();
        st.energy.initial = p.modal.energy(&st.s.x, &st.s.v);
        for (c, ct) in p.contacts.iter().enumerate() {
            let d = ct.delta(&st.s.x);
            if d > 1e-9 * ct.gap.max(1e-3) {
                return Err(SolverError::Stalled {
                    time: 0.0,
                    reason: format!("contact {c} starts penetrated by {d:.3e} m (initial displacements exceed the gap)"),
                });
            }
        }
        st.observe();
        Ok(st)
    }

    /// Floor displacements of every building at the current instant: peaks (branch-free,
    /// vectorisable), the continuous peaks of the interval since the previous sample
    /// ([`peaks`]) and, when a history is requested, the shared [`ResponseTracker`].
    fn observe(&mut self) {
        let (x, v) = (&self.s.x, &self.s.v);
        let len = self.interval.tau_done;
        for (b, bm) in self.p.modal.buildings.iter().enumerate() {
            let u = &mut self.u[b];
            bm.to_floors2(x, v, u, &mut self.ud[b]);
            let (dm, sm, k) = (
                &mut self.disp_max[b],
                &mut self.shear_max[b],
                &self.stiffness[b],
            );
            let nf = u.len();
            let (dm, sm, k, u) = (&mut dm[..nf], &mut sm[..nf], &k[..nf], &u[..nf]);
            for i in 0..nf {
                let d = u[i].abs();
                dm[i] = if d > dm[i] { d } else { dm[i] };
            }
            let v0 = (k[0] * u[0]).abs();
            sm[0] = if v0 > sm[0] { v0 } else { sm[0] };
            for i in 1..nf {
                let vs = (k[i] * (u[i] - u[i - 1])).abs();
                sm[i] = if vs > sm[i] { vs } else { sm[i] };
            }
            if len > 0.0 {
                let (up, udp, ud) = (&self.u_prev[b], &self.ud_prev[b], &self.ud[b]);
                let (nmb, first) = (bm.range.len(), bm.range.start);
                let modal = &self.p.modal;
                // Arcs of this building's modes, built at the first candidate only.
                let mut arcs: Option<Vec<Arc>> = None;
                let coef = &mut self.coef;
                for i in 0..nf {
                    for story in [false, true] {
                        let (below, below_p, vb, vbp) = if story && i > 0 {
                            (u[i - 1], up[i - 1], ud[i - 1], udp[i - 1])
                        } else {
                            (0.0, 0.0, 0.0, 0.0)
                        };
                        let sc = if story { k[i] } else { 1.0 };
                        let (y0, yd0) = (sc * (up[i] - below_p), sc * (udp[i] - vbp));
                        let (y1, yd1) = (sc * (u[i] - below), sc * (ud[i] - vb));
                        let Some((th, h)) = peaks::hermite_extremum(y0, yd0, y1, yd1, len) else {
                            continue;
                        };
                        let peak = if story { sm[i] } else { dm[i] };
                        // Cheap filter first: the Hermite error is a small fraction of the
                        // content at the interval's frequencies ((ω len)⁴/384 ≤ 3e-3 for
                        // ω len ≤ 1), so an estimate below 90 % of the peak cannot raise it.
                        if h.abs() < 0.9 * peak {
                            continue;
                        }
                        if story {
                            coef[..nmb]
                                .copy_from_slice(&self.shear_rows[b][i * nmb..(i + 1) * nmb]);
                        } else {
                            for (m, c) in coef[..nmb].iter_mut().enumerate() {
                                *c = bm.phi[m * nf + i];
                            }
                        }
                        let a = arcs.get_or_insert_with(|| {
                            peaks::arcs(modal, bm.range.clone(), &self.interval)
                        });
                        let c = &coef[..nmb];
                        if h.abs() + peaks::hermite_error_bound(modal, first, c, a, len) < peak {
                            continue;
                        }
                        let y = peaks::refine(modal, first, c, a, len, th * len).abs();
                        if story {
                            sm[i] = sm[i].max(y);
                        } else {
                            dm[i] = dm[i].max(y);
                        }
                    }
                }
            }
            if self.history.is_some() {
                self.tracker.observe(b, u);
                self.tracker.observe_velocity(b, &self.ud[b]);
            }
        }
        if !self.overlaps.is_empty() {
            self.observe_overlaps(len);
        }
        for b in 0..self.u.len() {
            self.u_prev[b].copy_from_slice(&self.u[b]);
            self.ud_prev[b].copy_from_slice(&self.ud[b]);
        }
        if self.history.is_some() {
            self.tracker.observe_contact_forces(&self.held_force);
            self.tracker.sample(self.s.t, self.history.as_deref_mut());
        }
    }

    /// The overlap audit at the current sample: u_left − u_right of every audited pair at
    /// the sample and, when its rate changes sign from + to − over the interval since the
    /// previous sample (length `len`), at the interior maximum, found as the story-shear
    /// and displacement peaks are ([`peaks`]: Hermite estimate, cheap filter, rigorous
    /// Hermite error bound, Newton on the closed form over both buildings' modes).
    fn observe_overlaps(&mut self, len: f64) {
        let t = self.s.t;
        let (u, ud, up, udp) = (&self.u, &self.ud, &self.u_prev, &self.ud_prev);
        let mut arcs: Option<Vec<Arc>> = None;
        for k in 0..self.overlaps.pairs.len() {
            let op = &self.overlaps.pairs[k];
            let (l, i, r, j) = (op.left, op.left_dof, op.right, op.right_dof);
            let y1 = u[l][i] - u[r][j];
            self.overlaps.offer(k, t, y1);
            if len <= 0.0 {
                continue;
            }
            let (y0, yd0, yd1) = (
                up[l][i] - up[r][j],
                udp[l][i] - udp[r][j],
                ud[l][i] - ud[r][j],
            );
            if yd0 <= 0.0 {
                continue;
            }
            let Some((th, h)) = peaks::hermite_extremum(y0, yd0, y1, yd1, len) else {
                continue;
            };
            let best = self.overlaps.max[k];
            // Cheap filter, as for the peaks: the Hermite error is a small fraction of the
            // content at the interval's frequencies.
            if h + 0.1 * h.abs() < best {
                continue;
            }
            let modal = &self.p.modal;
            let a = arcs.get_or_insert_with(|| peaks::arcs(modal, 0..modal.len(), &self.interval));
            let c = &self.overlap_rows[k];
            if h + peaks::hermite_error_bound(modal, 0, c, a, len) < best {
                continue;
            }
            let (s, y) = peaks::refine_at(modal, 0, c, a, len, th * len);
            self.overlaps.offer(k, t - len + s, y);
        }
    }

    /// Records the interval about to be integrated from the current state (ground a0 → a1
    /// over `tau`, held-contact loads `fc`), for the continuous peaks of the next sample.
    fn begin_interval(&mut self, a0: f64, a1: f64, tau: f64, fc: Option<&[f64]>) {
        let iv = &mut self.interval;
        iv.x0.clone_from(&self.s.x);
        iv.v0.clone_from(&self.s.v);
        (iv.a0, iv.a1, iv.tau) = (a0, a1, tau);
        iv.fc = fc.map(|f| f.to_vec());
        iv.tau_done = 0.0;
    }

    /// The velocities changed without a sample (an impulse): the next interval's rates at its
    /// start are the new ones.
    fn refresh_rates(&mut self) {
        for (b, bm) in self.p.modal.buildings.iter().enumerate() {
            bm.to_floors(&self.s.v, &mut self.ud_prev[b]);
        }
    }

    /// Peak story shears and floor displacements per building.
    pub fn peaks(&self, scene: &Scene) -> Vec<BuildingResponse> {
        scene
            .buildings
            .iter()
            .enumerate()
            .map(|(b, bd)| BuildingResponse {
                name: bd.name.clone(),
                story_shear_max: self.shear_max[b].clone(),
                floor_displacement_max: self.disp_max[b].clone(),
                ..Default::default()
            })
            .collect()
    }

    fn count_step(&mut self, tau: f64) -> Result<(), SolverError> {
        self.stats.steps += 1;
        if tau > 0.0 {
            self.stats.min_step = self.stats.min_step.min(tau);
            self.stats.max_step = self.stats.max_step.max(tau);
        }
        if self.stats.steps > self.p.limits.max_steps {
            return Err(SolverError::StepBudget {
                time: self.s.t,
                steps: self.stats.steps,
                limit: self.p.limits.max_steps,
            });
        }
        // Checked every 64 segments (and at the end): a non-finite mode stays non-finite.
        if self.stats.steps % 64 == 0 && !self.state_is_finite() {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: "modal state after a propagation segment".into(),
            });
        }
        Ok(())
    }

    fn state_is_finite(&self) -> bool {
        self.s.x.iter().chain(&self.s.v).all(|z| z.is_finite())
    }

    /// Physical momentum Σ Γ_n q̇_n (all buildings), N·s.
    pub fn momentum(&self) -> f64 {
        self.p
            .modal
            .gamma
            .iter()
            .zip(&self.s.v)
            .map(|(g, v)| g * v)
            .sum()
    }

    fn kinetic(&self) -> f64 {
        0.5 * self.s.v.iter().map(|v| v * v).sum::<f64>()
    }

    /// Advances one segment.
    pub fn advance(&mut self) -> Result<Step, SolverError> {
        let p = self.p;
        let end_tol = 1e-12 * p.h;
        if self.s.t >= p.duration - end_tol {
            return Ok(Step::Finished);
        }
        let j = self.s.j;
        let t_end = if j + 1 >= p.n_steps {
            p.duration
        } else {
            p.grid(j + 1)
        };
        let tau = t_end - self.s.t;
        if tau <= end_tol.max(1e-15 * self.s.t) {
            // Degenerate sliver: jump to the grid point (state unchanged).
            self.finish_grid(j, t_end);
            return Ok(Step::Reached);
        }
        if !self.s.persistent.is_empty() {
            return self.persistent_segment(tau, t_end);
        }
        if self.s.on_grid && (tau - p.h).abs() <= 1e-9 * p.h {
            if let Some(step) = self.fast_step(j, t_end)? {
                return Ok(step);
            }
        }
        self.segment(tau, t_end, None, true)
    }

    fn finish_grid(&mut self, j: usize, t_end: f64) {
        self.s.t = t_end;
        self.s.j = (j + 1).min(self.p.n_steps);
        self.s.on_grid = true;
    }

    /// A full base step with precomputed propagators; `None` if an event may occur (the
    /// caller then takes the closed-form path from the unchanged state).
    fn fast_step(&mut self, j: usize, t_end: f64) -> Result<Option<Step>, SolverError> {
        let p = self.p;
        let (a0, a1) = (p.ag_start[j], p.ag_end[j]);
        let h = p.full.h;
        self.begin_interval(a0, a1, h, None);
        {
            // Structure of arrays, all sliced to `nm` so that the loop has no bounds checks
            // and no cross-mode dependency (per-mode energy accumulators): it vectorises.
            let c = &p.full;
            let nm = self.s.x.len();
            let (x, v) = (&self.s.x[..nm], &self.s.v[..nm]);
            let (xn, vn) = (&mut self.xn[..nm], &mut self.vn[..nm]);
            let (win, dmp) = (&mut self.win_step[..nm], &mut self.dmp_step[..nm]);
            let (a00, a01, a10, a11) = (&c.a00[..nm], &c.a01[..nm], &c.a10[..nm], &c.a11[..nm]);
            let (b00, b01, b10, b11) = (&c.b00[..nm], &c.b01[..nm], &c.b10[..nm], &c.b11[..nm]);
            let (tzw, iw2, gam) = (&c.two_zw[..nm], &c.inv_w2[..nm], &p.modal.gamma[..nm]);
            let q = &c.dq;
            let (q0, q1, q2, q3, q4) = (
                &q[0][..nm],
                &q[1][..nm],
                &q[2][..nm],
                &q[3][..nm],
                &q[4][..nm],
            );
            let (q5, q6, q7, q8, q9) = (
                &q[5][..nm],
                &q[6][..nm],
                &q[7][..nm],
                &q[8][..nm],
                &q[9][..nm],
            );
            let inv_h = 1.0 / h;
            for n in 0..nm {
                let f0 = -gam[n] * a0;
                let f1 = -gam[n] * a1;
                let (x0, v0) = (x[n], v[n]);
                let x1 = a00[n] * x0 + a01[n] * v0 + b00[n] * f0 + b01[n] * f1;
                let v1 = a10[n] * x0 + a11[n] * v0 + b10[n] * f0 + b11[n] * f1;
                let ix = (0.5 * (f0 + f1) * h - (v1 - v0) - tzw[n] * (x1 - x0)) * iw2[n];
                win[n] = f0 * (x1 - x0) + (f1 - f0) * (x1 - ix * inv_h);
                dmp[n] = x0 * (q0[n] * x0 + q1[n] * v0 + q2[n] * f0 + q3[n] * f1)
                    + v0 * (q4[n] * v0 + q5[n] * f0 + q6[n] * f1)
                    + f0 * (q7[n] * f0 + q8[n] * f1)
                    + q9[n] * f1 * f1;
                xn[n] = x1;
                vn[n] = v1;
            }
        }
        // Rigorous skip of far contacts: d√(2E)/dt ≤ |f| (modal load norm), so over the step
        // |δ̇| ≤ √W_c (√(2E₀) + h |a_g|max √ΣΓ²) and δ(s) ≤ δ₀ + s·max|δ̇| < 0 if δ₀ is
        // below −h times that bound.
        let e2 = {
            let nm = self.s.x.len();
            let (x, v, w2) = (&self.s.x[..nm], &self.s.v[..nm], &p.omega2[..nm]);
            let mut acc = [0.0f64; 4];
            for n in 0..nm {
                acc[n % 4] += v[n] * v[n] + w2[n] * x[n] * x[n];
            }
            acc.iter().sum::<f64>()
        };
        let vbound = e2.sqrt() + h * a0.abs().max(a1.abs()) * p.gamma_norm;
        let sub = p.sub;
        let mut arcs_built = false;
        for (ci, ct) in p.contacts.iter().enumerate() {
            // δ, δ̇ at the window ends 0, h/sub, …, h.
            let d_start = ct.delta(&self.s.x);
            if d_start < -h * p.sqrt_w[ci] * vbound * (1.0 + 1e-9) {
                continue;
            }
            let mut prev = (d_start, ct.dot(&self.s.v));
            if prev.0 >= 0.0 {
                return Ok(None);
            }
            for w in 1..=sub {
                let cur = if w == sub {
                    (ct.delta(&self.xn), ct.dot(&self.vn))
                } else {
                    let r = w as f64 / sub as f64;
                    let (mut d, mut dd) = (-ct.gap, 0.0);
                    for ((k, g), ((&x0, &v0), &gam)) in p.checks[w - 1]
                        .iter()
                        .zip(&ct.g)
                        .zip(self.s.x.iter().zip(&self.s.v).zip(&p.modal.gamma))
                    {
                        if *g != 0.0 {
                            let (f0, f1) = (-gam * a0, -gam * (a0 + r * (a1 - a0)));
                            d += g * (k[0] * x0 + k[1] * v0 + k[2] * f0 + k[3] * f1);
                            dd += g * (k[4] * x0 + k[5] * v0 + k[6] * f0 + k[7] * f1);
                        }
                    }
                    (d, dd)
                };
                if cur.0 >= 0.0 {
                    return Ok(None);
                }
                if prev.1 > 0.0 && cur.1 < 0.0 {
                    if !arcs_built {
                        self.build_arcs(a0, a1, h, None);
                        arcs_built = true;
                    }
                    let loc = Locator {
                        contact: ct,
                        arcs: &self.arcs,
                        modal: &p.modal,
                        lo: h * (w - 1) as f64 / sub as f64,
                        hi: h * w as f64 / sub as f64,
                        tol: 0.0,
                        shift: 0.0,
                        iterations: 0,
                    };
                    if !loc.surely_open(prev.0, prev.1, cur.0, cur.1) {
                        return Ok(None);
                    }
                }
                prev = cur;
            }
        }
        std::mem::swap(&mut self.s.x, &mut self.xn);
        std::mem::swap(&mut self.s.v, &mut self.vn);
        // Energy of the accepted step only (a step with a possible event is discarded).
        for (acc, w) in self.win_acc.iter_mut().zip(&self.win_step) {
            *acc += w;
        }
        for (acc, d) in self.dmp_acc.iter_mut().zip(&self.dmp_step) {
            *acc += d;
        }
        self.finish_grid(j, t_end);
        self.count_step(h)?;
        self.interval.tau_done = h;
        self.observe();
        Ok(Some(Step::Reached))
    }

    /// Arcs of every mode from the current state, ground a0 → a1 over tau, plus the
    /// constant contact loads `fc`.
    fn build_arcs(&mut self, a0: f64, a1: f64, tau: f64, fc: Option<&[f64]>) {
        let m = &self.p.modal;
        self.arcs.clear();
        for n in 0..m.len() {
            let extra = fc.map_or(0.0, |f| f[n]);
            let (f0, f1) = (-m.gamma[n] * a0 + extra, -m.gamma[n] * a1 + extra);
            self.arcs.push(Arc::new(
                m.omega[n],
                m.zeta[n],
                self.s.x[n],
                self.s.v[n],
                f0,
                f1,
                tau,
            ));
        }
    }

    /// General segment of length tau on the closed form, with event location. `grid_end`:
    /// the segment ends on the base grid point `t_end` (else at `t + tau`, inside the step).
    fn segment(
        &mut self,
        tau: f64,
        t_end: f64,
        fc: Option<&[f64]>,
        grid_end: bool,
    ) -> Result<Step, SolverError> {
        let p = self.p;
        let j = self.s.j;
        let (a0, a1) = (p.ground(j, self.s.t), p.ground(j, t_end));
        self.begin_interval(a0, a1, tau, fc);
        self.build_arcs(a0, a1, tau, fc);
        for n in 0..self.arcs.len() {
            let (x1, v1) = self.arcs[n].xv(tau);
            self.xn[n] = x1;
            self.vn[n] = v1;
        }
        let tol = 2.0 * f64::EPSILON * (self.s.t + tau) + 1e-300;
        let mut first: Option<f64> = None;
        let mut found: Vec<(usize, f64)> = vec![];
        for (ci, ct) in p.contacts.iter().enumerate() {
            if self.s.persistent.iter().any(|&(c, _)| c == ci) {
                continue;
            }
            // Windows of at most h/sub: at most one extremum of δ each.
            let m = ((tau / (p.h / p.sub as f64)) - 1e-9).ceil().max(1.0) as usize;
            let at = |s: f64, arcs: &[Arc]| {
                let (mut d, mut dd) = (-ct.gap, 0.0);
                for (g, a) in ct.g.iter().zip(arcs) {
                    if *g != 0.0 {
                        let (x, v) = a.xv(s);
                        d += g * x;
                        dd += g * v;
                    }
                }
                (d, dd)
            };
            if self.grazing[ci] && ct.delta(&self.s.x) < -self.pen[ci] {
                self.grazing[ci] = false;
            }
            let shift = if self.grazing[ci] { self.pen[ci] } else { 0.0 };
            let mut prev = (ct.delta(&self.s.x) - shift, ct.dot(&self.s.v));
            let mut r = None;
            for w in 1..=m {
                let (lo, hi) = (
                    tau * (w - 1) as f64 / m as f64,
                    if w == m {
                        tau
                    } else {
                        tau * w as f64 / m as f64
                    },
                );
                let cur = if w == m {
                    (ct.delta(&self.xn) - shift, ct.dot(&self.vn))
                } else {
                    let (d, dd) = at(hi, &self.arcs);
                    (d - shift, dd)
                };
                let mut loc = Locator {
                    contact: ct,
                    arcs: &self.arcs,
                    modal: &p.modal,
                    lo,
                    hi,
                    tol,
                    shift,
                    iterations: 0,
                };
                r = loc.locate(prev.0, prev.1, cur.0, cur.1);
                self.stats.root_iterations += loc.iterations;
                if r.is_some() {
                    break;
                }
                prev = cur;
            }
            if let Some(s) = r {
                found.push((ci, s));
                first = Some(first.map_or(s, |f: f64| f.min(s)));
            }
        }
        let (s_end, step) = match first {
            None => (tau, Step::Reached),
            Some(s) => {
                let contacts: Vec<usize> = found
                    .iter()
                    .filter(|(_, sc)| *sc <= s + SIMULTANEOUS)
                    .map(|(c, _)| *c)
                    .collect();
                (
                    s,
                    Step::ContactClosed {
                        contacts,
                        time: self.s.t + s,
                    },
                )
            }
        };
        // Commit [0, s_end] with its energy.
        let m = &p.modal;
        for n in 0..self.arcs.len() {
            let a = self.arcs[n];
            let (x1, v1) = if s_end == tau {
                (self.xn[n], self.vn[n])
            } else {
                a.xv(s_end)
            };
            if s_end > 0.0 {
                let w = a.load_work(s_end, x1, v1);
                let extra = fc.map_or(0.0, |f| f[n]);
                let wc = extra * (x1 - a.x0);
                self.energy.input += w - wc;
                self.energy.contact -= wc;
                self.energy.damping += 2.0 * m.zeta[n] * m.omega[n] * a.damping_integral(s_end);
            }
            self.s.x[n] = x1;
            self.s.v[n] = v1;
        }
        if s_end == tau && grid_end {
            self.finish_grid(j, t_end);
        } else if s_end == tau {
            self.s.t = t_end;
            self.s.on_grid = false;
        } else {
            self.s.t += s_end;
            self.s.on_grid = false;
        }
        self.count_step(s_end)?;
        self.interval.tau_done = s_end;
        self.observe();
        Ok(step)
    }

    /// Instantaneous holding forces λ = W⁻¹ δ̈_free (N per unit modal mass, > 0 compressive)
    /// of the contacts `set` in the state (x, v) under ground acceleration `a_g`, and for
    /// each a round-off tolerance (1e-9 of the magnitude of the terms of δ̈_free, over W_cc).
    fn holding_forces(
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
    /// every held gap back to δ = 0 at s (see [`persistent`]). Returns the modal loads of
    /// the forces and the state at s.
    fn held_trial(
        &self,
        set: &[usize],
        s: f64,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>), SolverError> {
        let (p, m) = (self.p, &self.p.modal);
        let (a0, a1) = (
            p.ground(self.s.j, self.s.t),
            p.ground(self.s.j, self.s.t + s),
        );
        let arc = |n: usize, extra: f64| {
            Arc::new(
                m.omega[n],
                m.zeta[n],
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
        let lam = persistent::contact_forces(m, &p.contacts, set, s, &dfree, self.s.t)?;
        let mut fc = vec![0.0; m.len()];
        for (k, &c) in set.iter().enumerate() {
            for (f, g) in fc.iter_mut().zip(&p.contacts[c].g) {
                *f -= g * lam[k];
            }
        }
        let (mut x, mut v) = (vec![0.0; m.len()], vec![0.0; m.len()]);
        for n in 0..m.len() {
            (x[n], v[n]) = arc(n, fc[n]).xv(s);
        }
        Ok((fc, x, v, lam))
    }

    /// Smallest holding force (relative to its tolerance) at the end of the held trial of
    /// length s, and the contact (index into `set`) it belongs to.
    fn held_end_force(&self, set: &[usize], s: f64) -> Result<(f64, usize), SolverError> {
        let (x, v) = if s > 0.0 {
            let (_, x, v, _) = self.held_trial(set, s)?;
            (x, v)
        } else {
            (self.s.x.clone(), self.s.v.clone())
        };
        let a1 = self.p.ground(self.s.j, self.s.t + s);
        let (lam, tol) = self.holding_forces(set, &x, &v, a1, self.s.t + s)?;
        Ok(lam
            .iter()
            .zip(&tol)
            .enumerate()
            .map(|(k, (l, t))| (l / t.max(f64::MIN_POSITIVE), k))
            .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a }))
    }

    /// Sets the relative velocity of the held contacts to zero (a plastic micro-impulse;
    /// its kinetic energy goes to the contact account).
    fn project_held(&mut self, set: &[usize]) -> Result<(), SolverError> {
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

    /// Ends the persistent phase of `set[k]` now.
    fn release(&mut self, contact: usize) -> Step {
        let t = self.s.t;
        if let Some(i) = self.s.persistent.iter().position(|&(c, _)| c == contact) {
            let (c, start) = self.s.persistent.remove(i);
            if t > start {
                self.phases.push(PersistentContact {
                    contact: c,
                    start,
                    end: t,
                    released_by: "tension".into(),
                });
            }
        }
        self.grazing[contact] = true;
        self.stats.events += 1;
        Step::Released { contact, time: t }
    }

    /// A segment with contacts held together (δ = 0). The phase of a contact ends where its
    /// instantaneous holding force turns tensile: at the segment start if it already is,
    /// else at the instant located by Brent's method on the held trajectory.
    fn persistent_segment(&mut self, tau: f64, t_end: f64) -> Result<Step, SolverError> {
        let p = self.p;
        let set: Vec<usize> = self.s.persistent.iter().map(|&(c, _)| c).collect();
        let a0 = p.ground(self.s.j, self.s.t);
        let (lam0, tol0) = self.holding_forces(&set, &self.s.x, &self.s.v, a0, self.s.t)?;
        if let Some(k) = (0..set.len())
            .filter(|&k| lam0[k] < -tol0[k])
            .min_by(|&a, &b| (lam0[a] / tol0[a]).total_cmp(&(lam0[b] / tol0[b])))
        {
            return Ok(self.release(set[k]));
        }
        let (f_end, k_end) = self.held_end_force(&set, tau)?;
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
            let mut conv = super::events::Conv {
                tol: 2.0 * f64::EPSILON * (self.s.t + tau) + 1e-300,
                iterations: 0,
            };
            let r = roots::find_root_brent(0.0, tau, f, &mut conv);
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
        let (fc, _, _, lam) = self.held_trial(&set, s_hold)?;
        let full = s_hold == tau;
        let t_stop = if full { t_end } else { self.s.t + s_hold };
        for (&c, &l) in set.iter().zip(&lam) {
            self.held_force[c] = l;
        }
        let step = self.segment(s_hold, t_stop, Some(&fc), full);
        self.held_force.fill(0.0);
        let step = step?;
        self.project_held(&set)?;
        match (step, release) {
            (Step::Reached, Some(c)) => Ok(self.release(c)),
            (step, _) => Ok(step),
        }
    }

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
                    return Err(SolverError::Stalled {
                        time: t,
                        reason: format!(
                            "contact {c} touches at rest under a compressive force (the \
                             accumulation point of chattering impacts, c_r = {}); without \
                             persistent contact (momentum.persistent_contact = false) the \
                             method cannot go on",
                            p.contacts[c].restitution
                        ),
                    });
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
            let accumulating = hist.len() == 3 && {
                let (d1, d2) = (hist[1] - hist[0], hist[2] - hist[1]);
                let r = d2 / d1;
                d1 > 0.0
                    && r < 1.0
                    && d2 < p.h
                    && d2 * r / (1.0 - r) < p.h
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
                let target: Vec<f64> = v_before
                    .iter()
                    .zip(&e_eff)
                    .map(|(v, e)| (1.0 + e) * v.max(0.0))
                    .collect();
                let imp = impulse::lcp_impulses(&p.contacts, contacts, &target, t)?;
                impulse::apply(&p.contacts, &imp, &mut self.s.v);
                for (c, pc) in imp {
                    let k = contacts.iter().position(|&x| x == c).unwrap();
                    impulses[k] = pc;
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
                if !corr_set.is_empty() {
                    let imp = impulse::lcp_impulses(&p.contacts, &corr_set, &target, t)?;
                    impulse::apply(&p.contacts, &imp, &mut self.s.v);
                    for (c, pc) in imp {
                        let k = contacts.iter().position(|&x| x == c).unwrap();
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
        for (k, &c) in contacts.iter().enumerate() {
            let vb = v_before[k];
            let undefined = if vb <= p.options.capture_velocity {
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

    /// Closes open phases and returns the final modal energy.
    pub fn finish(&mut self) -> Result<f64, SolverError> {
        if !self.state_is_finite() {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: "modal state at the end of the analysis".into(),
            });
        }
        self.energy.input += self.win_acc.iter().sum::<f64>();
        self.energy.damping += self.dmp_acc.iter().sum::<f64>();
        self.win_acc.fill(0.0);
        self.dmp_acc.fill(0.0);
        for &(c, start) in &self.s.persistent {
            self.phases.push(PersistentContact {
                contact: c,
                start,
                end: self.s.t,
                released_by: "end of analysis".into(),
            });
        }
        self.s.persistent.clear();
        self.diag.final_x = self.s.x.clone();
        self.diag.final_v = self.s.v.clone();
        Ok(self.p.modal.energy(&self.s.x, &self.s.v))
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
