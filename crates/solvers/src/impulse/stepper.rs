//! The impulse method's stepper: the state between two steps ([`State`]), the right-hand
//! side with the held contacts ([`rhs`]) and [`ImpulseStepper::step`], which takes one
//! trial step of the gap element's Dormand–Prince pair, locates the earliest event on its
//! dense output ([`super::events`]), cuts the step there, handles the event (an impact,
//! [`super::impact`]; a release or the projection of held contacts, [`super::held`]; a
//! story kink) and reports a [`StepOutcome`]. See the module docs of [`super`] for the
//! equations and [`super::driver`] for the loop.

use std::collections::VecDeque;

use structure::Scene;

use super::events::{self, Event};
use super::held::{self, Held};
use super::problem::{Config, Problem};
use crate::gap::adaptive::DenseStep;
use crate::gap::dopri::Dopri5;
use crate::gap::stories::Kink;
use crate::gap::{Segment, Stories, System};
use crate::output::EnergyAudit;
use crate::response::ResponseTracker;
use crate::rules::ImpactRateGuard;
use crate::step::StepOutcome;
use crate::{Impact, PersistentContact, SolverError, Stats};

/// The restoring forces −f_s(u) − C v (N) into `f` (f_s = K u for linear stories, the story
/// law from the committed `stories` state for yielding ones: a pure trial); returns the
/// damping power vᵀ C v (W).
///
/// The one place where the impulse method calls [`System::internal`]. Not inlined: with
/// the story loop inlined into [`rhs`] the right-hand side runs ~8 % more instructions
/// (callgrind, paper scene), as LLVM decided once the stepper left the driver's module.
#[inline(never)]
pub(super) fn restoring(
    sys: &System,
    stories: &Stories,
    u: &[f64],
    v: &[f64],
    f: &mut [f64],
) -> f64 {
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

/// The state of the impulse method between two steps: what the integration moves and what
/// the contact rules remember.
pub(super) struct State {
    /// y = [u; v; E_input; E_damping; W_contact].
    pub y: Vec<f64>,
    /// Time, s.
    pub t: f64,
    /// Committed state of the yielding stories (empty for linear buildings).
    pub stories: Stories,
    /// The contacts held together (persistent contact) and W⁻¹ of their set.
    pub held: Held,
    /// Per contact: just resolved and not yet re-armed (see the momentum method's stepper).
    pub grazing: Vec<bool>,
    /// Per contact: the times of its last three impacts (chattering capture).
    pub last_impacts: Vec<VecDeque<f64>>,
}

/// The impulse method between two calls of [`ImpulseStepper::step`]: the problem and
/// configuration (fixed), the [`State`], the Dormand–Prince state (next step h, FSAL
/// stage, rejection flag, step count), the record piece of the ground motion, and the
/// books of the run (impacts, persistent phases, contact losses, the impact-rate guard,
/// statistics). Like the adaptive gap stepper it knows nothing of peaks, histories or
/// record points other than the one it is told to stop at.
pub(super) struct ImpulseStepper<'a> {
    pub(super) p: Problem<'a>,
    pub(super) cfg: Config,
    pub(super) s: State,
    dp: Dopri5,
    /// Next trial step, s.
    h: f64,
    seg: Segment,
    rejected_before: bool,
    total_steps: u64,
    /// Stops a run whose steps no longer advance time ([`crate::step::Progress`]).
    progress: crate::step::Progress,
    /// Scratch of the right-hand side: 2·|held| numbers.
    pub(super) buf: Vec<f64>,
    /// Scratch of one state (event search).
    scratch: Vec<f64>,
    /// The state at the end of the accepted part of a step.
    y_end: Vec<f64>,
    /// The step that landed on the record point changed the state or the held set: the
    /// FSAL stage is refreshed in [`ImpulseStepper::enter_segment`], once, with the next
    /// ground piece.
    stale: bool,
    pub(super) guard: ImpactRateGuard,
    /// Energy lost in impacts and in the projections of held contacts, J.
    pub(super) contact_loss: f64,
    pub(super) impacts: Vec<Impact>,
    pub(super) phases: Vec<PersistentContact>,
    pub(super) stats: Stats,
}

impl<'a> ImpulseStepper<'a> {
    /// The initial state of `sys` (refused if a contact starts penetrated beyond its band;
    /// an initial drift beyond yield starts its story on the yield surface), the first stage
    /// and Hairer's starting step, at most up to the first record point `t_bp` (s).
    pub fn new(scene: &Scene, sys: &'a System, t_bp: f64) -> Result<Self, SolverError> {
        let n = sys.n;
        let dim = 2 * n + 3;
        let cfg = Config::new(scene);
        let tol = cfg.tolerance;
        let dp = Dopri5::new(dim, 2 * n, tol, vec![tol * 1e-3; 2 * n]);
        let p = Problem::new(scene, sys);
        let nc = p.geoms.len();
        let mut y = vec![0.0; dim];
        y[..n].copy_from_slice(&sys.u0);
        y[n..2 * n].copy_from_slice(&sys.v0);
        for (c, cd) in sys.contacts.iter().enumerate() {
            let d = cd.rel(&y[..n]) - cd.gap;
            if d > p.pen[c] {
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
        let mut stories = sys.stories();
        {
            let (u0, v0) = y[..2 * n].split_at(n);
            stories.start(u0, v0);
        }
        let mut st = ImpulseStepper {
            p,
            cfg,
            s: State {
                y,
                t: 0.0,
                stories,
                held: Held::default(),
                grazing: vec![false; nc],
                last_impacts: vec![VecDeque::new(); nc],
            },
            dp,
            h: 0.0,
            seg: sys.segment(0),
            rejected_before: false,
            total_steps: 0,
            progress: crate::step::Progress::default(),
            buf: Vec::new(),
            scratch: vec![0.0; dim],
            y_end: vec![0.0; dim],
            stale: false,
            guard: ImpactRateGuard::new(cfg.max_impact_rate),
            contact_loss: 0.0,
            impacts: Vec::new(),
            phases: Vec::new(),
            stats: Stats {
                min_step: f64::INFINITY,
                ..Stats::default()
            },
        };
        st.restart();
        st.h = {
            let (stories, held, buf, seg) = (&st.s.stories, &st.s.held, &mut st.buf, &st.seg);
            let mut f =
                |tt: f64, yy: &[f64], o: &mut [f64]| rhs(sys, stories, seg, held, buf, tt, yy, o);
            st.dp
                .initial_step(&mut f, st.s.t, &st.s.y.clone(), t_bp - st.s.t)
        };
        st.stats.rhs_evaluations += 1;
        Ok(st)
    }

    /// Time, s.
    pub fn t(&self) -> f64 {
        self.s.t
    }

    /// Floor displacements, m.
    pub fn u(&self) -> &[f64] {
        &self.s.y[..self.p.sys.n]
    }

    /// The derivative at the current state into the first stage of the next step: a
    /// restart of the FSAL chain after the state, the held set or the ground piece changed.
    pub(super) fn restart(&mut self) {
        rhs(
            self.p.sys,
            &self.s.stories,
            &self.seg,
            &self.s.held,
            &mut self.buf,
            self.s.t,
            &self.s.y,
            &mut self.dp.k[0],
        );
        self.stats.rhs_evaluations += 1;
        self.stale = false;
    }

    /// Observes the current state for peaks and, when a history is kept, for its next
    /// sample (with the holding forces of the held contacts).
    pub fn observe(&self, tracker: &mut ResponseTracker, history: bool) {
        let sys = self.p.sys;
        let n = sys.n;
        let (u, v) = (&self.s.y[..n], &self.s.y[n..2 * n]);
        if history {
            let forces = self.contact_forces(self.seg.at(self.s.t));
            sys.observe_sample(&self.s.stories, tracker, u, v, &forces);
        } else {
            sys.observe(&self.s.stories, tracker, u);
        }
    }

    /// One step towards the record point `t_bp` (s), landing on it when within 1 %.
    ///
    /// First a held contact whose holding force is already tensile is released
    /// ([`StepOutcome::Released`], no step). Otherwise one trial step; if accepted, the
    /// earliest event on its dense output (closure, release, story kink) cuts it, `on_dense`
    /// sees the part taken before the state moves on, the stories are committed at the new
    /// state, the held contacts are projected to zero relative velocity and gap, and the
    /// event is handled (impact law, release, kink count). Errors: step budget, step-size
    /// underflow or a non-finite trial state, a singular contact system, the impact-rate
    /// guard, a stall without persistent contact.
    ///
    /// Inlined into the driver's loop, its one caller (see [`events::earliest`]).
    #[inline(always)]
    pub fn step(
        &mut self,
        t_bp: f64,
        on_dense: &mut dyn FnMut(&DenseStep),
    ) -> Result<StepOutcome, SolverError> {
        debug_assert!(
            !self.stale,
            "enter_segment is called after every record point"
        );
        let sys = self.p.sys;
        // A held contact whose force is already tensile is released before stepping.
        if !self.s.held.set.is_empty() {
            let (ratio, k) = held::force_ratio(
                &self.p,
                &self.s.stories,
                &self.s.held,
                &self.s.y,
                self.seg.at(self.s.t),
            );
            if ratio < -1.0 {
                let c = self.s.held.set[k];
                self.release(c)?;
                self.restart();
                return Ok(StepOutcome::Released { contact: c });
            }
        }
        let t = self.s.t;
        let mut hs = self.h;
        let mut land = false;
        if t + 1.01 * hs >= t_bp {
            hs = t_bp - t;
            land = true;
        }
        self.total_steps += 1;
        if self.total_steps > self.cfg.max_steps {
            return Err(SolverError::StepBudget {
                time: t,
                steps: self.total_steps - 1,
                limit: self.cfg.max_steps,
                context: format!("next step {hs:.3e} s, held contacts: {:?}", self.s.held.set),
            });
        }
        self.progress.check(t, self.total_steps)?;
        let err = {
            let (stories, held, buf, seg) =
                (&self.s.stories, &self.s.held, &mut self.buf, &self.seg);
            let mut f =
                |tt: f64, yy: &[f64], o: &mut [f64]| rhs(sys, stories, seg, held, buf, tt, yy, o);
            self.dp.try_step(&mut f, t, &self.s.y, hs)
        };
        self.stats.rhs_evaluations += 6;
        let (ok, hnew) = self.dp.control(err, hs, self.rejected_before);
        if !ok {
            self.stats.rejected_steps += 1;
            self.rejected_before = true;
            self.h = hnew;
            let h = hnew;
            let hmin = 1e-14 * (1.0 + t);
            if h < hmin {
                if err.is_nan() {
                    return Err(SolverError::NonFinite {
                        time: t,
                        context: format!(
                            "the trial step of {hs:.3e} s produced a non-finite state \
                             (held contacts: {:?})",
                            self.s.held.set
                        ),
                    });
                }
                return Err(SolverError::StepSizeUnderflow {
                    time: t,
                    step: h,
                    min_step: hmin,
                    context: format!(
                        "error norm {err:.3e} after {} rejections; held contacts: {:?}",
                        self.stats.rejected_steps, self.s.held.set
                    ),
                });
            }
            return Ok(StepOutcome::Rejected);
        }
        self.rejected_before = false;
        self.dp.prepare_dense(t, &self.s.y, hs);

        let event = events::earliest(
            &self.p,
            &mut self.s,
            &self.dp,
            &self.seg,
            (t, hs),
            &mut self.scratch,
            &mut self.stats.root_iterations,
        );

        // --- the part of the step taken, shown to the driver; then the state moves on ----
        let th_end = event.as_ref().map_or(1.0, |(th, _)| th.min(1.0));
        if th_end < 1.0 {
            self.dp.dense_all(th_end, &mut self.y_end);
        } else {
            self.y_end.copy_from_slice(&self.dp.y1);
        }
        on_dense(&DenseStep {
            dp: &self.dp,
            stories: &self.s.stories,
            t,
            y0: &self.s.y,
            y1: &self.y_end,
            th_end,
        });
        let full = th_end >= 1.0;
        if full && event.is_none() && self.s.held.set.is_empty() {
            self.dp.accept_full(&mut self.s.y);
        } else {
            self.s.y.copy_from_slice(&self.y_end);
        }
        self.s.t = if full {
            if land {
                t_bp
            } else {
                t + hs
            }
        } else {
            t + th_end * hs
        };
        let taken = self.s.t - t;
        if taken > 0.0 {
            self.stats.min_step = self.stats.min_step.min(taken);
        }
        self.stats.max_step = self.stats.max_step.max(taken);
        self.stats.steps += 1;
        self.h = hnew;

        // The FSAL stage is stale unless the whole step was taken with nothing to handle.
        let restart = !(full && event.is_none() && self.s.held.set.is_empty());
        // The accepted state: commit the yielding stories there (once the peaks over the
        // step, which need the start-of-step law, are taken).
        let kink = match &event {
            Some((_, Event::Kink(k))) => Some(*k),
            _ => None,
        };
        self.commit(kink.as_ref());
        // Held contacts: relative velocity and gap back to zero after every step.
        let held = self.s.held.set.clone();
        self.project_held(&held)?;
        let ag = self.seg.at(self.s.t);
        let breakpoint = land && full;
        let outcome = match event {
            Some((_, Event::Release(c))) => {
                self.release(c)?;
                StepOutcome::ContactOpened {
                    contact: c,
                    breakpoint,
                }
            }
            Some((_, Event::Closure(set))) => {
                self.impact(&set, ag)?;
                StepOutcome::Impact {
                    contacts: set,
                    breakpoint,
                }
            }
            Some((_, Event::Kink(_))) => {
                self.stats.story_kinks += 1;
                StepOutcome::StoryKink { breakpoint }
            }
            None if breakpoint => StepOutcome::Breakpoint,
            None => StepOutcome::Accepted,
        };
        if breakpoint {
            self.stale = restart;
        } else if restart {
            self.restart();
        }
        Ok(outcome)
    }

    /// At the record point reached: enters the next record interval, whose ground piece is
    /// `next` (`None` after the last). The FSAL stage restarts once if the step that landed
    /// here changed the state or the held set, or if the excitation jumps here (only where
    /// the record ends).
    pub fn enter_segment(&mut self, next: Option<Segment>) {
        if let Some(next) = next {
            let t = self.s.t;
            let (a_new, a_old) = (next.at(t), self.seg.at(t));
            if (a_new - a_old).abs() > 1e-9 * (a_new.abs() + a_old.abs()) {
                self.stale = true;
            }
            self.seg = next;
        }
        if self.stale {
            self.restart();
        }
    }

    /// Ends the run: the contacts still held close their phases at the end of the analysis;
    /// the energy audit (refused if the final state is not finite), the impacts, the
    /// persistent phases, the statistics and the story state.
    #[allow(clippy::type_complexity)]
    pub fn finish(
        mut self,
    ) -> Result<
        (
            Vec<Impact>,
            Vec<PersistentContact>,
            EnergyAudit,
            Stats,
            Stories,
        ),
        SolverError,
    > {
        for (&c, &start) in self.s.held.set.iter().zip(&self.s.held.start) {
            self.phases.push(PersistentContact {
                contact: c,
                start,
                end: self.s.t,
                released_by: "end of analysis".into(),
            });
        }
        if self.stats.min_step == f64::INFINITY {
            self.stats.min_step = 0.0;
        }
        let sys = self.p.sys;
        let n = sys.n;
        let y = &self.s.y;
        if !y.iter().all(|x| x.is_finite()) {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: "floor state at the end of the analysis".into(),
            });
        }
        let mut stories0 = sys.stories();
        stories0.start(&sys.u0, &sys.v0);
        let initial = sys.mech_energy(&stories0, &sys.u0, &sys.v0);
        let final_ = sys.mech_energy(&self.s.stories, &y[..n], &y[n..2 * n]);
        let (input, damping) = (y[2 * n], y[2 * n + 1]);
        let contact = y[2 * n + 2] + self.contact_loss;
        let hysteretic = self.s.stories.hysteretic_energy();
        let energy = EnergyAudit::closed(initial, input, damping, contact, hysteretic, final_);
        Ok((
            self.impacts,
            self.phases,
            energy,
            self.stats,
            self.s.stories,
        ))
    }

    /// Kinetic energy ½ vᵀ M v, J.
    pub(super) fn kinetic(&self) -> f64 {
        let n = self.p.sys.n;
        0.5 * self.s.y[n..2 * n]
            .iter()
            .zip(&self.p.sys.mass)
            .map(|(v, m)| m * v * v)
            .sum::<f64>()
    }

    /// Relative velocity u̇_l − u̇_r of contact c, m/s.
    pub(super) fn rel_velocity(&self, c: usize) -> f64 {
        let n = self.p.sys.n;
        self.p.sys.contacts[c].rel(&self.s.y[n..2 * n])
    }

    /// Commits the yielding stories at the current state (`kink`: the story kink located
    /// at this state, if any). Called for every accepted state and after every change of the
    /// state by an event (impulse, projection), never for a trial.
    pub(super) fn commit(&mut self, kink: Option<&Kink>) {
        let n = self.p.sys.n;
        self.s
            .stories
            .commit(&self.s.y[..n], &self.s.y[n..2 * n], kink);
    }

    /// Mechanical energy (kinetic + recoverable strain) plus the hysteretic energy
    /// dissipated so far, J, with the committed story state.
    pub(super) fn energy_with_hysteresis(&self) -> f64 {
        let n = self.p.sys.n;
        self.p
            .sys
            .mech_energy(&self.s.stories, &self.s.y[..n], &self.s.y[n..2 * n])
            + self.s.stories.hysteretic_energy()
    }
}
