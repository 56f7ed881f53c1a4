//! The problem data built from a [`Scene`] (immutable during a run): kept modes,
//! contacts in modal form, the base grid and its propagators.
//!
//! - base step h = dt/m, the record step dt split in m = ⌈STEPS_PER_PERIOD·dt/T_min⌉ equal
//!   parts when the shortest kept period T_min is below STEPS_PER_PERIOD record steps (else
//!   m = 1; without a record h = T_min/8), n_steps = ⌈duration/h⌉. The split is exact (a_g is
//!   linear within a record step, and the closed form is exact for any step): it is there for
//!   the continuous peaks, whose check sees one sign change of a rate per step;
//! - event-check windows per step sub = ⌈8h/T_min⌉ when T_min < 8h (else 1): δ and δ̇ of
//!   every contact are checked at k·h/sub, so a window holds at most one extremum of δ;
//! - a_g piecewise linear on the grid, zero past the record (eq. 27's load −Γ_n a_g);
//! - per-step Nigam–Jennings propagators and energy forms ([`StepCoeffs`]).

use structure::ground::nigam_jennings::Propagator;
use structure::scene::Limits;
use structure::{MomentumOptions, Scene};

use super::impulse::ContactGeom;
use super::modal::{Modal, StepCoeffs};
use crate::SolverError;

/// Simultaneity window for closures, s.
pub const SIMULTANEOUS: f64 = 1e-12;

/// Fewest base steps per kept period: a record step longer than T_min/STEPS_PER_PERIOD is split
/// into equal base steps (see the module docs). The continuous peaks see one sign change of a
/// rate per step; a mode's rate changes sign every half period, so 2 would do for one mode;
/// 4 leaves room for sums of modes, whose sign changes can come closer together.
pub const STEPS_PER_PERIOD: f64 = 4.0;

/// Largest number of contact checks per record step: base steps per record step times
/// event-check windows per base step, about 8 dt/T_min (work: as many closed-form checks per
/// record step and contact; the split keeps the windows per base step at 2 or fewer, so the
/// propagator tables stay small).
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
    /// Base steps per record step m (≥ 1; see [`STEPS_PER_PERIOD`]).
    pub split: usize,
    /// Event-check windows per step (T_min < 8·h ⇒ ⌈8 h/T_min⌉, else 1): δ and δ̇ are
    /// checked at these interior points so that each window holds at most one extremum.
    pub sub: usize,
    /// Base step h = record_dt/split, s (propagation, energy, response sampling).
    pub h: f64,
    /// Propagators from a step start to its interior check points k·h/sub, k = 1 … sub−1
    /// (per point, per mode: a00 a01 b00 b01 a10 a11 b10 b11).
    pub checks: Vec<Vec<[f64; 8]>>,
    /// The same by chunks of 4 modes starting at `check_starts` (0, 4, …, and the last 4
    /// modes when a remainder is left; empty with fewer than 4 modes): per point, per chunk,
    /// the 8 coefficients then Γ, lane by lane.
    pub check_blocks: Vec<Vec<[[f64; 4]; 9]>>,
    pub check_starts: Vec<usize>,
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
    /// ½ Σ_n (Γ_n a_max)²/ω_n², J: the modes' static strain energy under the largest ground
    /// acceleration of the run, a_max = max |a_g| over the record samples its steps span. The
    /// closed form's particular (f/ω²) and homogeneous parts cancel over a short segment, so
    /// its energies carry round-off of about ε times this whatever the run's own energies
    /// (1–2 ε of it on a 3 + 3-floor pair over runs of 1e-12 … 1e-3 s, whose energies are far
    /// below it); it is part of the end audit's scale ([`super::stepper::AUDIT_TOLERANCE`]).
    /// 0 where it would be infinite (accelerations near 1e154 m/s²), rather than switch the
    /// audit off.
    pub static_energy: f64,
}

impl Problem {
    pub fn new(scene: &Scene) -> Result<Problem, SolverError> {
        let mut modal = Modal::new(&scene.buildings, scene.momentum.modes)?;
        let contacts: Vec<ContactGeom> = scene
            .contacts
            .iter()
            .map(|c| ContactGeom::new(&modal, c))
            .collect();
        let w_max = modal.omega.iter().cloned().fold(0.0, f64::max);
        let t_min = 2.0 * std::f64::consts::PI / w_max;
        let record_dt = scene.ground.as_ref().map_or(t_min / 8.0, |g| g.dt);
        // Refuse, before allocating, what cannot run: the work per record step (base steps
        // times interior check windows) grows as record step / shortest period, and the step
        // tables as duration / base step.
        if !((8.0 * record_dt / t_min).ceil() <= MAX_SUB as f64) {
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
        // (Without a record, record_dt = T_min/8: never split.)
        let split = if t_min < STEPS_PER_PERIOD * record_dt {
            (STEPS_PER_PERIOD * record_dt / t_min).ceil() as usize
        } else {
            1
        };
        let h = record_dt / split as f64;
        modal.set_base_step(h);
        let sub = if t_min < 8.0 * h {
            (8.0 * h / t_min).ceil() as usize
        } else {
            1
        };
        let steps_f = (scene.duration / h).ceil();
        if !(steps_f <= scene.limits.max_steps as f64) {
            return Err(SolverError::Refused {
                reason: format!(
                    "analysis.duration = {:.6e} s needs {steps_f:.3e} steps of {h:.3e} s, \
                     more than analysis.max_steps = {}",
                    scene.duration, scene.limits.max_steps
                ),
            });
        }
        let checks: Vec<Vec<[f64; 8]>> = (1..sub)
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
        let nm = modal.len();
        let mut check_starts: Vec<usize> = (0..nm / 4).map(|k| 4 * k).collect();
        if nm % 4 != 0 && nm >= 4 {
            check_starts.push(nm - 4);
        }
        let check_blocks = checks
            .iter()
            .map(|pt: &Vec<[f64; 8]>| {
                check_starts
                    .iter()
                    .map(|&n0| {
                        let mut b = [[0.0; 4]; 9];
                        for i in 0..4 {
                            for f in 0..8 {
                                b[f][i] = pt[n0 + i][f];
                            }
                            b[8][i] = modal.gamma[n0 + i];
                        }
                        b
                    })
                    .collect()
            })
            .collect();
        let n_steps = crate::rules::grid_steps(scene.duration, h) as usize;
        // (Built up to the record's end, then zeros: no zeroing of what is overwritten.)
        let mut ag_start = Vec::with_capacity(n_steps);
        let mut ag_end = Vec::with_capacity(n_steps);
        // The largest |a_g| of the run, for the energy audit's scale (`static_energy`).
        let mut a_max = 0.0f64;
        if let Some(g) = &scene.ground {
            let covered = n_steps.min(g.npts().saturating_sub(1) * split);
            // The record's samples the covered steps span (an interpolant lies between two of
            // them; the steps past the record's end have a_g = 0).
            a_max = structure::ground::peak_abs(
                &g.accel[..(covered.div_ceil(split) + 1).min(g.npts())],
            );
            if split == 1 {
                // The record's own grid (the common case): its samples as they are.
                ag_start.extend_from_slice(&g.accel[..covered]);
                ag_end.extend_from_slice(&g.accel[1..covered + 1]);
            } else {
                ag_start.resize(covered, 0.0);
                ag_end.resize(covered, 0.0);
                // The record's linear pieces, each cut in `split` equal parts (the ends of a
                // piece are its samples, exactly; the interior points as
                // `structure::testing::refined` computes them, so a split record and a record
                // resampled by hand give the same grid to the last bit).
                let at = |r: usize, i: usize| {
                    if i == 0 {
                        g.accel[r]
                    } else if i == split {
                        g.accel[r + 1]
                    } else {
                        g.accel[r] + (g.accel[r + 1] - g.accel[r]) * i as f64 / split as f64
                    }
                };
                let pieces = ag_start[..covered]
                    .chunks_mut(split)
                    .zip(ag_end[..covered].chunks_mut(split));
                for (r, (starts, ends)) in pieces.enumerate() {
                    for (i, (a0, a1)) in starts.iter_mut().zip(ends.iter_mut()).enumerate() {
                        (*a0, *a1) = (at(r, i), at(r, i + 1));
                    }
                }
            }
        }
        ag_start.resize(n_steps, 0.0);
        ag_end.resize(n_steps, 0.0);
        let full = StepCoeffs::new(&modal, h);
        let omega2: Vec<f64> = modal.omega.iter().map(|w| w * w).collect();
        let gamma_norm = modal.gamma.iter().map(|g| g * g).sum::<f64>().sqrt();
        let static_energy: f64 = (0..modal.len())
            .map(|n| 0.5 * (modal.gamma[n] * a_max).powi(2) / omega2[n])
            .sum();
        // (Infinite for accelerations near 1e154 m/s²: 0 then, not an audit switched off.)
        let static_energy = if static_energy.is_finite() {
            static_energy
        } else {
            0.0
        };
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
            split,
            sub,
            h,
            checks,
            check_blocks,
            check_starts,
            n_steps,
            ag_start,
            ag_end,
            full,
            static_energy,
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
