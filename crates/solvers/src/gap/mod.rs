//! The gap-element (penalty) method.
//!
//! Physical coordinates: every floor of every building, displacements u and velocities v
//! relative to the ground, floors of building 0 first. Per building the lumped mass M, the
//! stiffness K applied in story form (V_j = k_j (u_j − u_{j−1})) and the classical damping
//! C = `Building::damping_matrix(&modes)` (dense, identical to the momentum method's). A
//! building with `story_law = "bilinear"` replaces k_j d_j by the story law's force
//! V_j(d_j; history) ([`stories`]); its damping matrix stays the elastic building's
//! (built from the modes of the initial stiffness, not updated when stories yield):
//!
//! ```text
//! M ü + C u̇ + f_s(u) = −M 1 a_g(t) + Σ_contacts F_c (e_right − e_left),  f_s = K u if linear
//! δ = u_left − u_right − gap   (closed while the law's event function g ≥ 0, see law.rs)
//! ```
//!
//! A wall contact (`right = "wall"`) has no e_right term and δ = u_left − gap: the wall
//! moves with the ground, so it stands still in these relative coordinates. Its
//! Kelvin–Voigt dashpot uses m_eff = m_left (the reduced mass m_l m_r/(m_l + m_r) as the
//! wall's mass m_r → ∞).
//!
//! Two integrators:
//! - `adaptive` (default, [`adaptive`]): Dormand–Prince 5(4) ([`dopri`]) with error
//!   control, dense output, located contact events and steps that never straddle a record
//!   point. Energy and per-contact impulse are extra ODE components integrated with the same
//!   stages, so the energy balance measures the integration error only.
//! - `newmark` ([`newmark`]): fixed-step average acceleration with Newton iterations on
//!   the contact force, contact state judged per step (no event location).
//!
//! Record points are the ground-motion samples t = i·dt (continued at the same spacing after
//! the record ends); without a record, every [`FREE_VIBRATION_SAMPLE`] s. Peak responses are
//! observed at every record point and every event (adaptive) or every step (Newmark).
//!
//! Energy audit (J): `input` = ∫ −u̇ᵀ M 1 a_g dt, `damping` = ∫ u̇ᵀ C u̇ dt,
//! `contact` = W_c + S₀ − S_T with W_c = ∫ Σ F δ̇ dt the work done on the contact elements
//! and S the energy stored in closed contact springs (so the dashpot work and, for the
//! clamped Kelvin–Voigt law, the spring energy released when the force vanishes with δ > 0),
//! `hysteretic` = Σ over yielding stories of the plastic work ∫ V du_p less the energy
//! ½ α²/H still stored in the hardening spring, `final` = kinetic + strain + S_T,
//! `initial` = kinetic + strain + S₀, the strain energy of a yielding story being its
//! recoverable part ½ k₀ (d − u_p)² + ½ α²/H.

pub mod adaptive;
pub mod dopri;
pub mod law;
pub(crate) mod ledger;
pub mod newmark;
pub mod stories;

use structure::scene::Integrator;
use structure::Scene;

use crate::output::EnergyAudit;
use crate::{History, RunOutput, SolverError};
use law::Law;
pub(crate) use ledger::{ContactLedger, Episode, Mode};
pub use stories::Stories;

/// Spacing of the record points of a scene without ground motion, s.
pub const FREE_VIBRATION_SAMPLE: f64 = 1e-3;

/// Runs the gap-element method with the integrator chosen in `scene.gap_element`.
pub fn solve(scene: &Scene, history: Option<&mut History>) -> Result<RunOutput, SolverError> {
    let start = std::time::Instant::now();
    let sys = System::new(scene)?;
    refuse_too_long(scene, &sys)?;
    let mut out = match scene.gap_element.integrator {
        Integrator::Adaptive => adaptive::run(scene, &sys, history)?,
        Integrator::Newmark => newmark::run(scene, &sys, history)?,
    };
    out.stats.wall_seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The adaptive integrator with a given first trial step `first_step` (s) instead of
/// Hairer's starting step: a hook for tests of the step control (a first step far too long
/// is rejected, and a rejected step must leave the contact and story state untouched).
pub fn solve_adaptive_from(scene: &Scene, first_step: f64) -> Result<RunOutput, SolverError> {
    let sys = System::new(scene)?;
    refuse_too_long(scene, &sys)?;
    adaptive::run_from(scene, &sys, None, Some(first_step))
}

/// Refuses, before anything is allocated, a run whose step count surely exceeds
/// `analysis.max_steps`: Newmark needs ⌈duration / Δt⌉ steps; the explicit adaptive pair
/// at least one step per record interval and, for stability, one per 3.3/ω_max s (the
/// stability boundary of Dormand–Prince 5(4) on the imaginary axis is near 3.3).
fn refuse_too_long(scene: &Scene, sys: &System) -> Result<(), SolverError> {
    let (steps, why) = match scene.gap_element.integrator {
        Integrator::Newmark => (
            scene.duration / scene.gap_element.time_step,
            format!(
                "steps of gap_element.time_step = {:.3e} s",
                scene.gap_element.time_step
            ),
        ),
        Integrator::Adaptive => {
            let by_record = scene.duration / sys.sample_dt;
            let by_stability = scene.duration * sys.omega_max / 3.3;
            if by_stability > by_record {
                (
                    by_stability,
                    format!(
                        "explicit steps (the stiffest building mode, ω = {:.3e} rad/s, limits the \
                         step to about {:.3e} s; use gap_element.integrator = \"newmark\")",
                        sys.omega_max,
                        3.3 / sys.omega_max
                    ),
                )
            } else {
                (
                    by_record,
                    format!("record intervals of {:.3e} s", sys.sample_dt),
                )
            }
        }
    };
    if steps.is_finite() && steps <= scene.limits.max_steps as f64 {
        return Ok(());
    }
    Err(SolverError::Refused {
        reason: format!(
            "analysis.duration = {:.6e} s needs at least {steps:.3e} {why}, more than \
             analysis.max_steps = {}",
            scene.duration, scene.limits.max_steps
        ),
    })
}

/// One building's block of the system.
#[derive(Debug, Clone)]
pub(crate) struct Block {
    pub off: usize,
    pub len: usize,
    /// Classical damping matrix, row-major len × len.
    pub c: Vec<f64>,
}

/// One contact with global DOF indices.
#[derive(Debug, Clone)]
pub(crate) struct ContactDof {
    pub l: usize,
    /// The right floor; equals `l` for a wall contact (never read then, see [`Self::rel`]).
    pub r: usize,
    pub gap: f64,
    pub law: Law,
    /// The right side is a rigid wall moving with the ground: u_r ≡ v_r ≡ 0 in the
    /// relative frame, and the contact force acts on the left floor only.
    pub wall: bool,
}

impl ContactDof {
    /// x_l − x_r of a per-floor vector (displacements or velocities); x_l for a wall.
    #[inline]
    pub fn rel(&self, x: &[f64]) -> f64 {
        x[self.l] - if self.wall { 0.0 } else { x[self.r] }
    }

    /// Adds the contact force F ≥ 0 (pushing the floors apart) to a per-floor vector:
    /// −F on the left floor, +F on the right one (the wall takes it for a wall contact).
    #[inline]
    pub fn push_apart(&self, acc: &mut [f64], f: f64) {
        acc[self.l] -= f;
        if !self.wall {
            acc[self.r] += f;
        }
    }
}

/// The assembled structure: everything the right-hand side needs.
#[derive(Debug, Clone)]
pub(crate) struct System {
    /// Total number of floors.
    pub n: usize,
    pub blocks: Vec<Block>,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    pub story_k: Vec<f64>,
    pub contacts: Vec<ContactDof>,
    /// Initial displacements and velocities.
    pub u0: Vec<f64>,
    pub v0: Vec<f64>,
    /// Record points: spacing and ground samples (m/s²), `None` without a record.
    pub sample_dt: f64,
    pub accel: Option<Vec<f64>>,
    /// The record itself (for [`structure::ground::GroundMotion::accel_at`]).
    pub ground: Option<structure::ground::GroundMotion>,
    /// Largest circular frequency of the buildings, rad/s (explicit-stability estimate).
    pub omega_max: f64,
    /// Virgin story state of the yielding buildings (empty when all are linear).
    pub stories0: Stories,
}

/// Ground acceleration inside one record interval: a(t) = a0 + slope·(t − t0).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Segment {
    pub t0: f64,
    pub a0: f64,
    pub slope: f64,
}

impl Segment {
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        self.a0 + self.slope * (t - self.t0)
    }
}

impl System {
    pub fn new(scene: &Scene) -> Result<System, SolverError> {
        let mut blocks = Vec::new();
        let (mut mass, mut story_k, mut u0, mut v0) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut off = 0;
        let mut offsets = Vec::new();
        let mut omega_max: f64 = 0.0;
        for b in &scene.buildings {
            let modes = b.modes()?;
            omega_max = modes.omega.iter().cloned().fold(omega_max, f64::max);
            let c = b.damping_matrix(&modes);
            let len = b.n_floors();
            let cm: Vec<f64> = (0..len * len).map(|ij| c[(ij / len, ij % len)]).collect();
            blocks.push(Block { off, len, c: cm });
            offsets.push(off);
            mass.extend_from_slice(&b.masses);
            story_k.extend_from_slice(&b.story_stiffness);
            u0.extend_from_slice(&b.initial_displacement);
            v0.extend_from_slice(&b.initial_velocity);
            off += len;
        }
        let contacts = scene
            .contacts
            .iter()
            .map(|c| {
                let l = offsets[c.left] + c.left_dof;
                let r = offsets[c.right] + c.right_dof;
                // Against a wall (infinite mass) the two-mass reduced mass m_l m_r/(m_l + m_r)
                // tends to the floor mass m_l: the Kelvin–Voigt constant is set for the
                // floor alone striking the wall.
                let m_eff = if c.wall {
                    mass[l]
                } else {
                    mass[l] * mass[r] / (mass[l] + mass[r])
                };
                ContactDof {
                    l,
                    r,
                    gap: c.gap,
                    law: Law::new(&scene.gap_element, c.restitution, m_eff),
                    wall: c.wall,
                }
            })
            .collect();
        let (sample_dt, accel) = match &scene.ground {
            Some(g) => (g.dt, Some(g.accel.clone())),
            None => (FREE_VIBRATION_SAMPLE, None),
        };
        Ok(System {
            n: off,
            blocks,
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            mass,
            story_k,
            contacts,
            u0,
            v0,
            sample_dt,
            accel,
            ground: scene.ground.clone(),
            omega_max,
            stories0: Stories::new(scene, &offsets),
        })
    }

    /// A fresh story state (virgin springs) for one analysis.
    pub fn stories(&self) -> Stories {
        self.stories0.clone()
    }

    /// Ground acceleration in record interval `i` ([i·dt, (i+1)·dt]); zero past the record.
    pub fn segment(&self, i: usize) -> Segment {
        let t0 = i as f64 * self.sample_dt;
        match &self.accel {
            Some(a) if i + 1 < a.len() => Segment {
                t0,
                a0: a[i],
                slope: (a[i + 1] - a[i]) / self.sample_dt,
            },
            _ => Segment {
                t0,
                a0: 0.0,
                slope: 0.0,
            },
        }
    }

    /// Ground acceleration at time t (piecewise linear, 0 outside the record).
    pub fn ground_at(&self, t: f64) -> f64 {
        self.ground.as_ref().map_or(0.0, |g| g.accel_at(t))
    }

    /// Restoring forces: `f` ← −f_s(u) − C v (N), f_s the story forces (k_j d_j for a
    /// linear building, the bilinear law from the committed state of `stories` for a
    /// yielding one: a pure trial); returns vᵀ C v (W).
    #[inline]
    pub fn internal(&self, stories: &Stories, u: &[f64], v: &[f64], f: &mut [f64]) -> f64 {
        let mut pdamp = 0.0;
        for (bi, b) in self.blocks.iter().enumerate() {
            let (o, n) = (b.off, b.len);
            let ub = &u[o..o + n];
            let vb = &v[o..o + n];
            let kb = &self.story_k[o..o + n];
            let fb = &mut f[o..o + n];
            let mut below = 0.0;
            if stories.yielding(bi) {
                for j in 0..n {
                    let s = stories.story_force(bi, j, ub[j] - below).0;
                    fb[j] = -s;
                    if j > 0 {
                        fb[j - 1] += s;
                    }
                    below = ub[j];
                }
            } else {
                for j in 0..n {
                    let s = kb[j] * (ub[j] - below);
                    fb[j] = -s;
                    if j > 0 {
                        fb[j - 1] += s;
                    }
                    below = ub[j];
                }
            }
            // C v by columns (C is symmetric): axpy loops that vectorise.
            let mut buf = [0.0f64; 64];
            let mut heap = Vec::new();
            let cv: &mut [f64] = if n <= 64 {
                &mut buf[..n]
            } else {
                heap.resize(n, 0.0);
                &mut heap[..]
            };
            for (col, &vj) in b.c.chunks_exact(n).zip(vb) {
                for (x, &cij) in cv.iter_mut().zip(col) {
                    *x += cij * vj;
                }
            }
            for ((f, &x), &vi) in fb.iter_mut().zip(cv.iter()).zip(vb) {
                *f -= x;
                pdamp += vi * x;
            }
        }
        pdamp
    }

    /// Kinetic + recoverable strain energy, J: ½ k d² per linear story, ½ k₀ (d − u_p)² +
    /// ½ α²/H per yielding story (committed state of `stories`).
    pub fn mech_energy(&self, stories: &Stories, u: &[f64], v: &[f64]) -> f64 {
        let mut e = 0.0;
        for (bi, b) in self.blocks.iter().enumerate() {
            if stories.yielding(bi) {
                for j in b.off..b.off + b.len {
                    e += 0.5 * self.mass[j] * v[j] * v[j];
                }
                continue;
            }
            let mut below = 0.0;
            for j in b.off..b.off + b.len {
                let d = u[j] - below;
                e += 0.5 * self.story_k[j] * d * d + 0.5 * self.mass[j] * v[j] * v[j];
                below = u[j];
            }
        }
        if stories.is_empty() {
            e
        } else {
            e + stories.recoverable_energy(u)
        }
    }

    /// Energy stored in the contact springs whose mode is closed, J.
    pub fn stored(&self, u: &[f64], closed: impl Fn(usize) -> bool) -> f64 {
        self.contacts
            .iter()
            .enumerate()
            .filter(|(i, _)| closed(*i))
            .map(|(_, c)| c.law.stored_energy(c.rel(u) - c.gap))
            .sum()
    }

    /// The record points up to `duration`: number of intervals and the time of point `i`.
    pub fn n_intervals(&self, duration: f64) -> usize {
        crate::rules::grid_steps(duration, self.sample_dt) as usize
    }

    /// End of record interval `i` of an analysis of `duration` (s): the next record point,
    /// the duration for the last interval.
    pub fn interval_end(&self, i: usize, duration: f64) -> f64 {
        if i + 1 >= self.n_intervals(duration) {
            duration
        } else {
            (i + 1) as f64 * self.sample_dt
        }
    }

    /// Observes every building's floor displacements.
    /// Offers u_left − u_right of every audited overlap pair at time `t` (s), `u` the
    /// floor displacements of all buildings (m).
    pub fn observe_overlaps(&self, ov: &mut crate::overlap::OverlapTracker, t: f64, u: &[f64]) {
        ov.observe(t, |b, i| u[self.blocks[b].off + i]);
    }

    pub fn observe(
        &self,
        stories: &Stories,
        tracker: &mut crate::response::ResponseTracker,
        u: &[f64],
    ) {
        for (bi, b) in self.blocks.iter().enumerate() {
            let ub = &u[b.off..b.off + b.len];
            if stories.yielding(bi) {
                let shear = self.law_shears(stories, bi, ub);
                tracker.observe_with_shear(bi, ub, &shear);
            } else {
                tracker.observe(bi, ub);
            }
        }
    }

    /// Updates the peaks of every building (floor displacements `u`, m, all buildings) at an
    /// instant that is not a history sample ([`System::observe_peaks`]).
    pub fn observe_all_peaks(
        &self,
        stories: &Stories,
        tracker: &mut crate::response::ResponseTracker,
        u: &[f64],
    ) {
        for (bi, b) in self.blocks.iter().enumerate() {
            self.observe_peaks(stories, tracker, bi, &u[b.off..b.off + b.len]);
        }
    }

    /// Updates the peaks of building `bi` (floor displacements `ub`, m, building-local) at an
    /// instant that is not a history sample, with the law's shears for a yielding building.
    pub fn observe_peaks(
        &self,
        stories: &Stories,
        tracker: &mut crate::response::ResponseTracker,
        bi: usize,
        ub: &[f64],
    ) {
        if stories.yielding(bi) {
            let shear = self.law_shears(stories, bi, ub);
            tracker.observe_peaks_with_shear(bi, ub, &shear);
        } else {
            tracker.observe_peaks(bi, ub);
        }
    }

    /// Story shears (N) of yielding building `bi` at floor displacements `ub` (m), from the
    /// committed state.
    fn law_shears(&self, stories: &Stories, bi: usize, ub: &[f64]) -> Vec<f64> {
        let mut shear = vec![0.0; ub.len()];
        stories.shears(bi, ub, &mut shear);
        shear
    }

    /// Observes every building's floor displacements and velocities and the contact forces
    /// (N, compressive > 0) for a history sample.
    pub fn observe_sample(
        &self,
        stories: &Stories,
        tracker: &mut crate::response::ResponseTracker,
        u: &[f64],
        v: &[f64],
        forces: &[f64],
    ) {
        self.observe(stories, tracker, u);
        for (bi, b) in self.blocks.iter().enumerate() {
            tracker.observe_velocity(bi, &v[b.off..b.off + b.len]);
        }
        tracker.observe_contact_forces(forces);
    }

    /// Settings in words.
    pub fn settings(&self, scene: &Scene) -> String {
        let g = &scene.gap_element;
        let law = match self.contacts.first() {
            Some(c) => c.law.describe(),
            None => format!("{:?} k={:.1e}", g.law, g.stiffness),
        };
        match g.integrator {
            Integrator::Adaptive => format!("{law}, adaptive dopri5 tol={:.0e}", g.tolerance),
            Integrator::Newmark => format!("{law}, newmark avg-accel dt={:.1e} s", g.time_step),
        }
    }
}

/// Energy audit from the integrated quantities (`hysteretic`: dissipated by yielding, J;
/// `mech_t` includes the recoverable story energy).
#[allow(clippy::too_many_arguments)]
pub(crate) fn audit(
    initial: f64,
    input: f64,
    damping: f64,
    work: f64,
    stored0: f64,
    mech_t: f64,
    stored_t: f64,
    hysteretic: f64,
) -> EnergyAudit {
    let contact = work + stored0 - stored_t;
    let final_ = mech_t + stored_t;
    EnergyAudit::closed(initial, input, damping, contact, hysteretic, final_)
}

/// The common result of both gap-element integrators: impacts in time order, no persistent
/// contacts or r_N (those belong to the momentum method).
#[allow(clippy::too_many_arguments)]
pub(crate) fn output(
    sys: &System,
    scene: &Scene,
    stories: &Stories,
    mut buildings: Vec<crate::output::BuildingResponse>,
    mut impacts: Vec<crate::Impact>,
    energy: EnergyAudit,
    stats: crate::Stats,
    overlaps: crate::overlap::OverlapTracker,
) -> RunOutput {
    impacts.sort_by(|a, b| a.time.total_cmp(&b.time));
    for (bi, b) in buildings.iter_mut().enumerate() {
        b.hysteretic_energy = stories.building_hysteretic_energy(bi);
    }
    RunOutput {
        impacts,
        ..RunOutput::on_scene(
            scene,
            "gap",
            sys.settings(scene),
            buildings,
            energy,
            stats,
            overlaps,
        )
    }
}

/// Smallest approach speed at closure for a contact episode to count as an impact whose
/// restitution is reported, m/s (the default of `momentum.capture_velocity`, so that both
/// methods call the same contacts "touching").
pub const IMPACT_MIN_APPROACH_SPEED: f64 = 1e-4;

/// Why an episode's achieved restitution is undefined, if it is. An episode is an impact
/// when the floors approach at closure faster than [`IMPACT_MIN_APPROACH_SPEED`]; its
/// restitution −v⁺/v⁻ is reported when it lies in [0, 1]. Outside, the rebound was not set
/// by the contact law but by the structure and the ground during the contact (long,
/// ground-driven episodes): reported as null with that reason.
pub(crate) fn restitution_undefined(v_before: f64, r: f64) -> Option<&'static str> {
    if v_before <= 0.0 {
        Some("separating or at rest at closure: not an impact")
    } else if v_before <= IMPACT_MIN_APPROACH_SPEED {
        Some("grazing: approach speed below 1e-4 m/s")
    } else if !(0.0..=1.0).contains(&r) {
        Some("ground-driven contact: the rebound is not set by the contact law")
    } else {
        None
    }
}
