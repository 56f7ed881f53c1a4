//! The problem data built from a [`Scene`] (immutable during a run): kept modes,
//! contacts in modal form, the base grid and its propagators.
//!
//! - base step h = record step dt (without a record T_min/8), n_steps = ⌈duration/h⌉;
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

impl Problem {
    /// The momentum method's continuous peaks see one sign change of a rate per record step,
    /// so a kept mode whose period is below two record steps can hide an extremum between
    /// samples and the peaks can come out low (an audit found 16 % on a stiff roof story under
    /// a 0.02 s record). The warning, if the shortest kept period is that short.
    pub fn peak_sampling_warning(&self, scene: &Scene) -> Option<String> {
        scene.ground.as_ref()?;
        let w_max = self.modal.omega.iter().cloned().fold(0.0, f64::max);
        let t_min = 2.0 * std::f64::consts::PI / w_max;
        if t_min >= 2.0 * self.record_dt {
            return None;
        }
        let (b, n) = stiffest_mode(&self.modal, w_max);
        Some(format!(
            "{}'s mode {n} has a period of {t_min:.4} s, shorter than two record steps \
             ({:.4} s): the momentum method's peaks may be low; resample the record finer or \
             keep fewer modes (momentum.modes)",
            scene.buildings[b - 1].name,
            2.0 * self.record_dt
        ))
    }
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
            check_blocks,
            check_starts,
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
