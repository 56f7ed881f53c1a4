//! Fixed-step average-acceleration Newmark (γ = ½, β = ¼) with Newton iterations on the
//! contact force, the way general FE programs run a gap element.
//!
//! - Δt = `gap_element.time_step`, adjusted down so that a whole number of steps covers the
//!   duration.
//! - The linear effective stiffness A = K + (2/Δt) C + (4/Δt²) M (block diagonal, one block
//!   per building) is factorised once per block (Cholesky, kept as the explicit inverse of
//!   the small block). The contact tangent (∂F/∂δ + (2/Δt) ∂F/∂δ̇) w wᵀ, w = e_left − e_right, of
//!   the contacts active at the current iterate enters by the Woodbury identity with
//!   Z = A⁻¹ W precomputed, so nothing is refactorised when the contact set changes.
//! - Yielding stories ([`super::stories`]): inside the Newton iteration each story's force
//!   and consistent tangent (k₀ elastic, b k₀ in flow) come from the return mapping of the
//!   trial drift from the state committed at the step start; a yielding building's block of
//!   A is refactorised with the tangents whenever the set of yielded stories of the iterate
//!   changes (and Z with it). The stories are committed once the step has converged. The
//!   kinks are not located: a step that crosses one carries O(Δt²) error in the energy
//!   balance (the trapezoidal story work is exact only on one branch).
//! - Contact state is judged from the iterate itself ([`super::law::Law::state_force`]): no
//!   event location, a contact lasts a whole number of steps. For Hertz-damp the approach
//!   speed δ̇⁻ is δ̇ at the start of the step in which the contact first carries force.
//! - Newton converges when ‖R‖∞ ≤ 1e-10 · (force scale) or the update is below
//!   1e-13 · (1 mm + ‖u‖∞); 50 iterations at most, then [`SolverError::NewtonFailure`].
//! - Impacts: closure time = the end of the first step with force, `relative_velocity_before`
//!   = δ̇ at the start of that step, `relative_velocity_after` = δ̇ at the end of the first
//!   step without force; impulse by the trapezoidal rule.
//! - Energy: input Σ −Δuᵀ M 1 ā_g, damping Σ Δt v̄ᵀ C v̄, contact work Σ Δδ F̄, hysteretic and
//!   recoverable story energy from the committed story state (trapezoidal
//!   sums, exact for the linear part of the scheme). With Δu = Δt v̄ and Δv = Δt ā, the
//!   equilibrium M a + C v + K u + F_c = p − r at both ends of a step, averaged and dotted
//!   with Δu, gives ΔT + ΔV + Δt v̄ᵀ C v̄ + Δδ F̄ = Δuᵀ p̄ − Δuᵀ r̄: the balance error is the
//!   work Σ Δuᵀ r̄ of the residuals r that Newton leaves (`EnergyAudit::residual_work`,
//!   reported beside it) plus round-off, on linear stories; a yielding story whose step
//!   crosses a kink adds its O(Δt²) trapezoidal error.
//! - Peak responses and the overlap audit are taken at every step, as a finite-element
//!   program reports them (between steps Newmark has no interpolant of its own accuracy,
//!   so these are not continuous maxima). History: every step.
//!
//! Shape: `NewmarkStepper::step` takes one step and reports a `StepOutcome` (`crate::step`):
//! `Accepted`, `ContactsChanged` (the contacts that began or stopped carrying force in the
//! step, judged from its converged end state), or `Finished` once the duration is covered;
//! the driver `run` owns the loop, the response tracker, the history and the overlap
//! audit. The contact books (modes, episodes, impacts, impact-rate guard) are the
//! `ledger::ContactLedger` shared with the adaptive integrator.

use nalgebra::{DMatrix, DVector};
use structure::Scene;

use super::{audit, output, ContactLedger, Episode, System};
use crate::output::EnergyAudit;
use crate::response::ResponseTracker;
use crate::step::StepOutcome;
use crate::{History, Impact, RunOutput, SolverError, Stats};

const MAX_NEWTON: usize = 50;
/// Largest number of contact-state sets tried in one step (active-set iteration).
const MAX_SET_PASSES: usize = 16;

/// The number of Newmark steps for `scene` and the step actually used (s): the duration in
/// equal steps of at most `gap_element.time_step` ([`crate::rules::grid_steps`]), for tools
/// that reproduce the run elsewhere (the OpenSees export).
pub fn steps_and_step(scene: &Scene) -> (u64, f64) {
    let nsteps = crate::rules::grid_steps(scene.duration, scene.gap_element.time_step);
    (nsteps, scene.duration / nsteps as f64)
}

/// The fixed-step Newmark integrator between two steps: the effective-stiffness block
/// inverses and Z = A⁻¹W (linear and in use), the state (u, v, a) with the committed story
/// state, the contact forces and impulses, the contact ledger, the energy sums and the
/// statistics. [`NewmarkStepper::step`] advances by Δt and reports a [`StepOutcome`]
/// (accepted, contacts changed, finished); the driver [`run`] owns the loop, the response
/// tracker, the history and the overlap audit.
struct NewmarkStepper<'a> {
    sys: &'a System,
    /// Step, s, and the Newmark constants 4/Δt² (1/s²) and 2/Δt (1/s).
    dt: f64,
    a0: f64,
    a1: f64,
    ainv: Vec<Vec<f64>>,
    ainv_lin: Vec<Vec<f64>>,
    z: Vec<DVector<f64>>,
    wz: DMatrix<f64>,
    z_lin: Vec<DVector<f64>>,
    wz_lin: DMatrix<f64>,
    stories: super::Stories,
    linear_stories: super::Stories,
    kt_used: Vec<Vec<f64>>,
    kt_new: Vec<f64>,
    tmp: Vec<f64>,
    /// Floor displacements (m), velocities (m/s), accelerations (m/s²) at the step start.
    u: Vec<f64>,
    v: Vec<f64>,
    acc: Vec<f64>,
    f: Vec<f64>,
    /// Contact forces at the step start (N) and accumulated impulses (N·s).
    force: Vec<f64>,
    impulse: Vec<f64>,
    ledger: ContactLedger,
    stats: Stats,
    /// Ground acceleration at the step start, m/s².
    ag: f64,
    /// Input, damping and contact work so far, J.
    e_in: f64,
    e_damp: f64,
    e_work: f64,
    /// Work of the equilibrium residuals left at the accepted steps, J
    /// ([`EnergyAudit::residual_work`]), and the residual at the step start (N; zero at
    /// t = 0, where the acceleration is solved from equilibrium).
    e_res: f64,
    r_prev: Vec<f64>,
    u_new: Vec<f64>,
    v_new: Vec<f64>,
    a_new: Vec<f64>,
    res: DVector<f64>,
    vbar: Vec<f64>,
    zero: Vec<f64>,
    f_new: Vec<f64>,
    alpha: Vec<f64>,
    vc_trial: Vec<f64>,
    on: Vec<bool>,
    visited: Vec<Vec<bool>>,
    force_closed: Vec<f64>,
    /// The contacts that closed and opened in the last step.
    closed_now: Vec<usize>,
    opened_now: Vec<usize>,
    /// Steps taken, and the number of steps that cover the duration.
    step: u64,
    nsteps: u64,
    /// Initial energy (mechanical + stored in closed contacts), J; stored at t = 0, J.
    initial: f64,
    stored0: f64,
}

/// u ← A⁻¹ r block by block (`ainv`: the explicit block inverses, row-major), in place;
/// `tmp` holds one block.
fn solve_blocks(sys: &System, ainv: &[Vec<f64>], r: &mut DVector<f64>, tmp: &mut [f64]) {
    for (b, inv) in sys.blocks.iter().zip(ainv) {
        let (o, m) = (b.off, b.len);
        let rb = &r.as_slice()[o..o + m];
        let tb = &mut tmp[..m];
        tb.fill(0.0);
        // A⁻¹ is symmetric: accumulate by columns.
        for (col, &rj) in inv.chunks_exact(m).zip(rb) {
            for (x, &a) in tb.iter_mut().zip(col) {
                *x += a * rj;
            }
        }
        r.as_mut_slice()[o..o + m].copy_from_slice(tb);
    }
}

/// The equilibrium residual r = p − M a + f_int + (contact forces pushing the floors apart)
/// at ground acceleration `ag` (m/s²), accelerations `a`, internal forces `f` (N) and contact
/// forces `fc` (N) into `res`; returns the force scale of its terms (at least 1 N), against
/// which Newton's tolerance is set.
fn residual(
    sys: &System,
    ag: f64,
    a: &[f64],
    f: &[f64],
    fc: &[f64],
    res: &mut DVector<f64>,
) -> f64 {
    let mut scale: f64 = 1.0;
    for i in 0..sys.n {
        let p = -sys.mass[i] * ag;
        let ma = sys.mass[i] * a[i];
        res[i] = p - ma + f[i];
        scale = scale.max(p.abs()).max(ma.abs()).max(f[i].abs());
    }
    for (c, &fc) in sys.contacts.iter().zip(fc) {
        c.push_apart(res.as_mut_slice(), fc);
        scale = scale.max(fc.abs());
    }
    scale
}

/// The law on a frozen state: the smooth branch while `on` (F may be negative: the
/// active-set check then opens the contact), zero otherwise. (F, ∂F/∂δ, ∂F/∂δ̇).
fn frozen(c: &super::ContactDof, on: bool, d: f64, dd: f64, vc: f64) -> (f64, f64, f64) {
    if on {
        let (kd, kv) = c.law.tangent(d, dd, vc);
        (c.law.force(d, dd, vc), kd, kv)
    } else {
        (0.0, 0.0, 0.0)
    }
}

impl<'a> NewmarkStepper<'a> {
    /// The factorised effective stiffness, the initial state and acceleration (contacts
    /// carrying force at t = 0 open their episodes) and the number of steps.
    fn new(scene: &Scene, sys: &'a System) -> Result<Self, SolverError> {
        let n = sys.n;
        let nc = sys.contacts.len();
        let (nsteps, dt) = steps_and_step(scene);
        if nsteps > scene.limits.max_steps {
            return Err(SolverError::StepBudget {
                time: 0.0,
                steps: 0,
                limit: scene.limits.max_steps,
                context: format!(
                    "before the first step: {nsteps} fixed steps of {dt:.3e} s are needed"
                ),
            });
        }
        let a0 = 4.0 / (dt * dt);
        let a1 = 2.0 / dt;

        // Effective stiffness A = K + (2/Δt) C + (4/Δt²) M, block diagonal per building: each
        // block is factorised once (Cholesky) and kept as its explicit inverse, so a solve is a
        // small dense matvec per building. A yielding building's block is refactorised with the
        // stories' consistent tangents whenever the set of yielded stories of a Newton iterate
        // changes (K_t assembled from k_t,j = k₀ or b k₀, see story_law.rs).
        let mut ainv: Vec<Vec<f64>> = Vec::with_capacity(sys.blocks.len());
        for b in &sys.blocks {
            let kt = &sys.story_k[b.off..b.off + b.len];
            ainv.push(block_inverse(sys, b, kt, a0, a1, 0.0)?);
        }
        let mut tmp = vec![0.0; sys.blocks.iter().map(|b| b.len).max().unwrap_or(0)];
        let z: Vec<DVector<f64>> = sys
            .contacts
            .iter()
            .map(|c| {
                let mut w = DVector::zeros(n);
                w[c.l] = 1.0;
                if !c.wall {
                    w[c.r] = -1.0;
                }
                solve_blocks(sys, &ainv, &mut w, &mut tmp);
                w
            })
            .collect();
        let wz = DMatrix::from_fn(nc, nc, |i, j| sys.contacts[i].rel(z[j].as_slice()));
        // The linear block inverses and Z = A⁻¹W (those in use, `ainv`/`z`/`wz`, follow the
        // story tangents of the iterate).
        let (ainv_lin, z_lin, wz_lin) = (ainv.clone(), z.clone(), wz.clone());
        let mut stories = sys.stories();
        let linear_stories = super::Stories::default();
        // Story tangents of the block inverses in use (per building; the elastic stiffness
        // when nothing yields).
        let kt_used: Vec<Vec<f64>> = sys
            .blocks
            .iter()
            .map(|b| sys.story_k[b.off..b.off + b.len].to_vec())
            .collect();
        let kt_new: Vec<f64> = Vec::new();

        let u = sys.u0.clone();
        let v = sys.v0.clone();
        let mut acc = vec![0.0; n];
        let mut f = vec![0.0; n];
        let mut force = vec![0.0; nc];
        let impulse = vec![0.0; nc];
        // Contact modes: closed = carries force at the end of the last step; v_close = δ̇⁻ of
        // the episode.
        let mut ledger = ContactLedger::new(nc, scene.limits.max_impact_rate);
        let mut stats = Stats {
            min_step: dt,
            max_step: dt,
            ..Stats::default()
        };

        let kin = |u: &[f64], v: &[f64], ci: usize| {
            let c = &sys.contacts[ci];
            (c.rel(u) - c.gap, c.rel(v))
        };

        // Initial state and acceleration.
        for ci in 0..nc {
            let (d, dd) = kin(&u, &v, ci);
            let (fc, _, _) = sys.contacts[ci].law.state_force(d, dd, dd);
            force[ci] = fc;
            if d > 0.0 && fc != 0.0 {
                let episode = Episode {
                    t_close: 0.0,
                    v_before: dd,
                    impulse0: 0.0,
                    peak_force: fc,
                    max_pen: d,
                };
                ledger.close(ci, dd, episode);
                stats.impacts += 1;
            }
        }
        let stored0 = sys.stored(&u, |i| ledger.closed(i));
        stories.start(&u, &v);
        let initial = sys.mech_energy(&stories, &u, &v) + stored0;
        let ag = sys.ground_at(0.0);
        sys.internal(&stories, &u, &v, &mut f);
        for i in 0..n {
            acc[i] = f[i] - sys.mass[i] * ag;
        }
        for (ci, c) in sys.contacts.iter().enumerate() {
            c.push_apart(&mut acc, force[ci]);
        }
        for i in 0..n {
            acc[i] *= sys.inv_mass[i];
        }
        let u_new = vec![0.0; n];
        let v_new = vec![0.0; n];
        let a_new = vec![0.0; n];
        let res = DVector::<f64>::zeros(n);
        let vbar = vec![0.0; n];
        let zero = vec![0.0; n];
        let f_new = vec![0.0; nc];
        let alpha = vec![0.0; nc];
        let vc_trial = vec![0.0; nc];

        let on = vec![false; nc];
        let visited: Vec<Vec<bool>> = Vec::new();
        // Force of each contact in the last solve that held it closed (NaN if none this step).
        let force_closed = vec![f64::NAN; nc];
        let stepper = NewmarkStepper {
            sys,
            dt,
            a0,
            a1,
            ainv,
            ainv_lin,
            z,
            wz,
            z_lin,
            wz_lin,
            stories,
            linear_stories,
            kt_used,
            kt_new,
            tmp,
            u,
            v,
            acc,
            f,
            force,
            impulse,
            ledger,
            stats,
            ag,
            e_in: 0.0,
            e_damp: 0.0,
            e_work: 0.0,
            e_res: 0.0,
            r_prev: vec![0.0; n],
            u_new,
            v_new,
            a_new,
            res,
            vbar,
            zero,
            f_new,
            alpha,
            vc_trial,
            on,
            visited,
            force_closed,
            closed_now: Vec::with_capacity(nc),
            opened_now: Vec::with_capacity(nc),
            step: 0,
            nsteps,
            initial,
            stored0,
        };
        Ok(stepper)
    }

    /// Time reached, s.
    fn t(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// One Newmark step: active-set iteration on the contact states around Newton solves,
    /// then the energy sums, the contact ledger (closures and openings of the step) and the
    /// committed story state. Reports [`StepOutcome::Accepted`], or
    /// [`StepOutcome::ContactsChanged`] with the contacts that closed and opened in the step,
    /// or [`StepOutcome::Finished`] (nothing done) once the duration is covered. Errors:
    /// a non-finite residual, Newton or the contact update failing, the impact-rate guard.
    fn step(&mut self) -> Result<StepOutcome, SolverError> {
        if self.step == self.nsteps {
            return Ok(StepOutcome::Finished);
        }
        let sys = self.sys;
        let n = sys.n;
        let nc = sys.contacts.len();
        let (dt, a0, a1, step) = (self.dt, self.a0, self.a1, self.step);
        let kin = |u: &[f64], v: &[f64], ci: usize| {
            let c = &sys.contacts[ci];
            (c.rel(u) - c.gap, c.rel(v))
        };
        let NewmarkStepper {
            ainv,
            ainv_lin,
            z,
            wz,
            z_lin,
            wz_lin,
            stories,
            kt_used,
            kt_new,
            tmp,
            u,
            v,
            acc,
            f,
            ledger,
            stats,
            u_new,
            v_new,
            a_new,
            res,
            f_new,
            alpha,
            vc_trial,
            on,
            visited,
            force_closed,
            ..
        } = self;
        let t1 = (step + 1) as f64 * dt;
        let ag1 = sys.ground_at(t1);
        for ci in 0..nc {
            vc_trial[ci] = if ledger.closed(ci) {
                ledger.v_close(ci)
            } else {
                kin(u, v, ci).1
            };
        }
        for i in 0..n {
            u_new[i] = u[i] + dt * v[i] + 0.5 * dt * dt * acc[i];
        }
        // Active-set iteration on the contact states: Newton solves the step with every
        // contact's state (carrying force / not) frozen, so that the residual is smooth;
        // then the states are checked against the law at the solution and the inconsistent
        // ones flipped, until none is (a frozen set never makes Newton flip-flop across the
        // kink of a clamped law). Starts from the states of the last step.
        for (o, m) in on.iter_mut().zip(ledger.modes()) {
            *o = m.closed;
        }
        visited.clear();
        force_closed.fill(f64::NAN);
        let mut settled = false;
        let mut converged;
        let mut last_res = f64::NAN;
        'sets: loop {
            converged = false;
            for it in 0..=MAX_NEWTON {
                for i in 0..n {
                    a_new[i] = a0 * (u_new[i] - u[i] - dt * v[i]) - acc[i];
                    v_new[i] = v[i] + 0.5 * dt * (acc[i] + a_new[i]);
                }
                sys.internal(stories, u_new, v_new, f);
                if !stories.is_empty() {
                    // Consistent tangents of the iterate (trial from the state committed at
                    // the step start): refactorise the blocks whose yielded set changed.
                    let mut changed = false;
                    for (bi, b) in sys.blocks.iter().enumerate() {
                        if !stories.yielding(bi) {
                            continue;
                        }
                        kt_new.clear();
                        let mut below = 0.0;
                        for j in 0..b.len {
                            let d = u_new[b.off + j] - below;
                            kt_new.push(stories.story_force(bi, j, d).1);
                            below = u_new[b.off + j];
                        }
                        if *kt_new != kt_used[bi] {
                            let elastic = *kt_new == sys.story_k[b.off..b.off + b.len];
                            ainv[bi] = if elastic {
                                ainv_lin[bi].clone()
                            } else {
                                block_inverse(sys, b, kt_new, a0, a1, t1)?
                            };
                            kt_used[bi].clone_from(kt_new);
                            changed = true;
                        }
                    }
                    if changed && nc > 0 {
                        if kt_used
                            .iter()
                            .zip(&sys.blocks)
                            .all(|(k, b)| k[..] == sys.story_k[b.off..b.off + b.len])
                        {
                            z.clone_from(z_lin);
                            wz.clone_from(wz_lin);
                        } else {
                            for (ci, c) in sys.contacts.iter().enumerate() {
                                let zc = &mut z[ci];
                                zc.fill(0.0);
                                zc[c.l] = 1.0;
                                if !c.wall {
                                    zc[c.r] = -1.0;
                                }
                                solve_blocks(sys, ainv, zc, tmp);
                            }
                            *wz = DMatrix::from_fn(nc, nc, |i, j| {
                                sys.contacts[i].rel(z[j].as_slice())
                            });
                        }
                    }
                }
                for (ci, c) in sys.contacts.iter().enumerate() {
                    let (d, dd) = kin(u_new, v_new, ci);
                    let (fc, kd, kv) = frozen(c, on[ci], d, dd, vc_trial[ci]);
                    f_new[ci] = fc;
                    alpha[ci] = kd + a1 * kv;
                }
                let scale = residual(sys, ag1, a_new, f, f_new, res);
                let rnorm = res.amax();
                last_res = rnorm;
                if !rnorm.is_finite() {
                    return Err(SolverError::NonFinite {
                        time: t1,
                        context: format!(
                            "Newmark residual is not finite at step {step} (Δt = {dt:.3e} s)"
                        ),
                    });
                }
                if rnorm <= 1e-10 * scale {
                    converged = true;
                    break;
                }
                if it == MAX_NEWTON {
                    break;
                }
                stats.newton_iterations += 1;
                // du = (A + W D Wᵀ)⁻¹ R by Woodbury.
                solve_blocks(sys, ainv, res, tmp);
                let act: Vec<usize> = (0..nc).filter(|&i| alpha[i] != 0.0).collect();
                if !act.is_empty() {
                    let m = act.len();
                    let g = DMatrix::from_fn(m, m, |i, j| {
                        (if i == j { 1.0 } else { 0.0 }) + alpha[act[i]] * wz[(act[i], act[j])]
                    });
                    let s = DVector::from_fn(m, |i, _| {
                        let c = &sys.contacts[act[i]];
                        alpha[act[i]] * c.rel(res.as_slice())
                    });
                    let x = g.lu().solve(&s).ok_or_else(|| SolverError::NewtonFailure {
                        time: t1,
                        iterations: it + 1,
                        residual: rnorm,
                        context: "singular contact update".into(),
                    })?;
                    for (k, &ci) in act.iter().enumerate() {
                        res.axpy(-x[k], &z[ci], 1.0);
                    }
                }
                let mut dmax: f64 = 0.0;
                let mut umax: f64 = 0.0;
                for i in 0..n {
                    u_new[i] += res[i];
                    dmax = dmax.max(res[i].abs());
                    umax = umax.max(u_new[i].abs());
                }
                if dmax <= 1e-13 * (1e-3 + umax) && it > 0 {
                    // Update at round-off level: accept after one more residual evaluation.
                    for i in 0..n {
                        a_new[i] = a0 * (u_new[i] - u[i] - dt * v[i]) - acc[i];
                        v_new[i] = v[i] + 0.5 * dt * (acc[i] + a_new[i]);
                    }
                    for (ci, c) in sys.contacts.iter().enumerate() {
                        let (d, dd) = kin(u_new, v_new, ci);
                        f_new[ci] = frozen(c, on[ci], d, dd, vc_trial[ci]).0;
                    }
                    // The residual of the accepted state (`res` holds the update), for the
                    // residual work of the energy audit.
                    sys.internal(stories, u_new, v_new, f);
                    residual(sys, ag1, a_new, f, f_new, res);
                    converged = true;
                    break;
                }
            }
            if !converged || settled {
                break 'sets;
            }
            for ci in 0..nc {
                if on[ci] {
                    force_closed[ci] = f_new[ci];
                }
            }
            // A contact that carries force stays closed while its force is compressive
            // (with tension allowed: also while δ > 0); an open one closes when the law,
            // judged from the state (δ > 0 and a compressive force), says so. The hysteresis
            // settles a closure inside the step: there the dashpot force c δ̇ jumps at δ = 0
            // and no end-of-step state may be consistent with both sets; the step then ends
            // closed with δ a hair below zero, the usual O(Δt) closure instant of a
            // fixed-step method.
            let mut flipped = false;
            for (ci, c) in sys.contacts.iter().enumerate() {
                let (d, dd) = kin(u_new, v_new, ci);
                let carries = if on[ci] {
                    f_new[ci] > 0.0
                        || (c.law.kind == structure::scene::ContactLaw::KelvinVoigt
                            && c.law.tension
                            && d > 0.0)
                } else {
                    c.law.state_force(d, dd, vc_trial[ci]).0 != 0.0
                };
                if carries != on[ci] {
                    on[ci] = carries;
                    flipped = true;
                }
            }
            if !flipped {
                break 'sets;
            }
            stats.active_set_iterations += 1;
            if visited.contains(on) || visited.len() >= MAX_SET_PASSES {
                // No consistent set: a contact opens and closes again inside the step (the
                // law jumps at δ = 0). Keep closed only the contacts whose force was
                // compressive when closed, solve once more, and accept: the contact changes
                // state at the next step instead (O(Δt), counted in the statistics).
                for (o, &f) in on.iter_mut().zip(force_closed.iter()) {
                    *o = f > 0.0;
                }
                settled = true;
                stats.contact_state_fallbacks += 1;
            }
            visited.push(on.clone());
        }
        if !converged {
            return Err(SolverError::NewtonFailure {
                time: t1,
                iterations: MAX_NEWTON,
                residual: last_res,
                context: format!(
                    "Newmark step {step}, Δt = {dt:.3e} s; contact forces {f_new:?} N"
                ),
            });
        }

        self.step += 1;
        self.accept(t1, ag1)
    }

    /// Books a converged step ending at `t1` (s; ground acceleration `ag1`, m/s²): the
    /// energy sums (trapezoidal), the contact impulses and the ledger (closures, episode
    /// peaks, openings); then the state and the committed stories move on. Returns what the
    /// contacts did in the step.
    fn accept(&mut self, t1: f64, ag1: f64) -> Result<StepOutcome, SolverError> {
        let sys = self.sys;
        let n = sys.n;
        let nc = sys.contacts.len();
        let (dt, ag) = (self.dt, self.ag);
        let (mut e_in, mut e_damp, mut e_work) = (self.e_in, self.e_damp, self.e_work);
        let mut e_res = self.e_res;
        let kin = |u: &[f64], v: &[f64], ci: usize| {
            let c = &sys.contacts[ci];
            (c.rel(u) - c.gap, c.rel(v))
        };
        let NewmarkStepper {
            stories,
            linear_stories,
            u,
            v,
            acc,
            f,
            force,
            impulse,
            ledger,
            stats,
            u_new,
            v_new,
            a_new,
            vbar,
            zero,
            f_new,
            vc_trial,
            closed_now,
            opened_now,
            res,
            r_prev,
            ..
        } = self;
        // Energy (trapezoidal sums), and the work of the residuals left by Newton (the
        // residual `res` of the accepted state, in the same trapezoidal rule).
        let agbar = 0.5 * (ag + ag1);
        for i in 0..n {
            e_in -= sys.mass[i] * (u_new[i] - u[i]) * agbar;
            vbar[i] = 0.5 * (v[i] + v_new[i]);
            e_res += (u_new[i] - u[i]) * (0.5 * (r_prev[i] + res[i]));
            r_prev[i] = res[i];
        }
        e_damp += dt * sys.internal(linear_stories, zero, vbar, f);
        closed_now.clear();
        opened_now.clear();
        for ci in 0..nc {
            let (d0, _) = kin(u, v, ci);
            let (d1, dd1) = kin(u_new, v_new, ci);
            let fbar = 0.5 * (force[ci] + f_new[ci]);
            e_work += (d1 - d0) * fbar;
            impulse[ci] += dt * fbar;
            let now = f_new[ci] != 0.0;
            if now && !ledger.closed(ci) {
                let (_, dd0) = kin(u, v, ci);
                let episode = Episode {
                    t_close: t1,
                    v_before: dd0,
                    impulse0: impulse[ci] - dt * fbar,
                    peak_force: 0.0,
                    max_pen: 0.0,
                };
                stats.impacts += 1;
                stats.events += 1;
                ledger.close_at(ci, t1, vc_trial[ci], episode)?;
                closed_now.push(ci);
            }
            if now {
                let ep = ledger.episode_mut(ci);
                ep.peak_force = ep.peak_force.max(f_new[ci]);
                ep.max_pen = ep.max_pen.max(d1);
            }
            if !now && ledger.closed(ci) {
                ledger.open(ci, t1, dd1, impulse[ci]);
                stats.events += 1;
                opened_now.push(ci);
            }
            force[ci] = f_new[ci];
        }
        u.copy_from_slice(u_new);
        v.copy_from_slice(v_new);
        acc.copy_from_slice(a_new);
        stories.commit(u, v, None);
        self.ag = ag1;
        stats.steps += 1;
        self.e_in = e_in;
        self.e_damp = e_damp;
        self.e_work = e_work;
        self.e_res = e_res;
        Ok(if closed_now.is_empty() && opened_now.is_empty() {
            StepOutcome::Accepted
        } else {
            StepOutcome::ContactsChanged {
                closed: closed_now.clone(),
                opened: opened_now.clone(),
            }
        })
    }

    /// Ends the run at `t_end` (s): the impacts (episodes still open reported up to the
    /// end), the energy audit, the statistics and the story state.
    fn finish(self, t_end: f64) -> (Vec<Impact>, EnergyAudit, Stats, super::Stories) {
        let sys = self.sys;
        let (u, v, impulse) = (&self.u, &self.v, &self.impulse);
        let stored_t = sys.stored(u, |i| self.ledger.closed(i));
        let kin = |ci: usize| sys.contacts[ci].rel(v);
        let impacts = self.ledger.finish(t_end, |ci| (kin(ci), impulse[ci]));
        let energy = EnergyAudit {
            residual_work: Some(self.e_res),
            ..audit(
                self.initial,
                self.e_in,
                self.e_damp,
                self.e_work,
                self.stored0,
                sys.mech_energy(&self.stories, u, v),
                stored_t,
                self.stories.hysteretic_energy(),
            )
        };
        (impacts, energy, self.stats, self.stories)
    }
}

/// The driver: owns the loop over the Newmark steps until the stepper reports
/// [`StepOutcome::Finished`], the response tracker, the history and the overlap audit.
/// Every step is observed, whatever its contacts did.
pub(crate) fn run(
    scene: &Scene,
    sys: &System,
    mut history: Option<&mut History>,
) -> Result<RunOutput, SolverError> {
    let mut st = NewmarkStepper::new(scene, sys)?;
    let mut tracker = ResponseTracker::new(scene);
    let mut overlaps = crate::overlap::OverlapTracker::new(scene);
    sys.observe_overlaps(&mut overlaps, 0.0, &st.u);
    sys.observe_sample(&st.stories, &mut tracker, &st.u, &st.v, &st.force);
    tracker.sample(0.0, history.as_deref_mut());
    loop {
        if let StepOutcome::Finished = st.step()? {
            break;
        }
        let t1 = st.t();
        // Peaks at every step, as a finite-element program reports them (not continuous
        // maxima: between steps Newmark has no interpolant of its own accuracy).
        if history.is_some() {
            sys.observe_sample(&st.stories, &mut tracker, &st.u, &st.v, &st.force);
        } else {
            sys.observe(&st.stories, &mut tracker, &st.u);
        }
        sys.observe_overlaps(&mut overlaps, t1, &st.u);
        tracker.sample(t1, history.as_deref_mut());
    }
    let (impacts, energy, stats, stories) = st.finish(scene.duration);
    Ok(output(
        sys,
        scene,
        &stories,
        tracker.finish(),
        impacts,
        energy,
        stats,
        overlaps,
    ))
}

/// The explicit inverse of one building's effective stiffness K_t + (2/Δt) C + (4/Δt²) M
/// (row-major, `b.len`²), K_t assembled in story form from the story tangents `kt` (N/m);
/// Cholesky. `time` (s) is reported if the matrix is not positive definite.
fn block_inverse(
    sys: &System,
    b: &super::Block,
    kt: &[f64],
    a0: f64,
    a1: f64,
    time: f64,
) -> Result<Vec<f64>, SolverError> {
    let (o, m) = (b.off, b.len);
    let mut amat = DMatrix::<f64>::zeros(m, m);
    for j in 0..m {
        let kj = kt[j];
        amat[(j, j)] += kj + a0 * sys.mass[o + j];
        if j > 0 {
            amat[(j - 1, j - 1)] += kj;
            amat[(j - 1, j)] -= kj;
            amat[(j, j - 1)] -= kj;
        }
        for i in 0..m {
            amat[(i, j)] += a1 * b.c[i * m + j];
        }
    }
    let chol = amat.cholesky().ok_or_else(|| SolverError::NewtonFailure {
        time,
        iterations: 0,
        residual: f64::NAN,
        context: "the effective stiffness K + 2C/Δt + 4M/Δt² is not positive definite".into(),
    })?;
    let inv = chol.inverse();
    Ok((0..m * m).map(|ij| inv[(ij / m, ij % m)]).collect())
}
