//! The stepper: the mutable [`State`] and [`Stepper::advance`], which propagates one
//! segment and reports what happened as a typed [`Step`].
//!
//! Between events every mode follows eq. 27 exactly: a full base step uses the constant
//! Nigam–Jennings propagator of the step ([`super::modal::StepCoeffs`]),
//! (q, q̇)ₖ₊₁ = A (q, q̇)ₖ + B (f(tₖ), f(tₖ₊₁)), f = −Γ a_g; a step that may hold a
//! closure, or a partial step, uses the closed form [`Arc`] (the Taylor series for a slow
//! mode, [`super::modal::SERIES_BELOW`]) with event location ([`super::events`]). Every accepted segment is observed: floor displacements
//! u = Φq (eq. 26), story shears k_j (u_j − u_{j−1}) and their continuous peaks
//! ([`super::peaks`]), the overlap audit, the history. Impacts are resolved in
//! [`super::impact`], persistent-contact phases in [`super::persistent`].

use std::collections::VecDeque;

use structure::Scene;

use super::energy::EnergyAccount;
use super::events::ModalGap;
pub use super::impact::ImpactDiagnostics;
use super::modal::{Arc, ArcLanes, TrigMemo};
use super::peaks;
pub use super::problem::{Problem, MAX_SUB, SIMULTANEOUS};
use crate::closure::Search;
use crate::overlap::OverlapTracker;
use crate::response::ResponseTracker;
use crate::rules::ImpactRateGuard;
use crate::{BuildingResponse, History, Impact, PersistentContact, SolverError, Stats};

/// Relative size of the energy-audit residual (and of a negative contact or damping
/// account) beyond which a run is stopped as untrustworthy: the method closes its audit to
/// round-off (1e-13 to 1e-11 of the energy scale on the robustness sweep and the randomized
/// tests), so 1e-6 is far from any sound run. The end audit's scale is initial + |input| +
/// final energy plus [`Problem::static_energy`], the size of the closed form's terms, whose
/// round-off (about ε of it) is all a run too short to gather energy has: a run of 1e-9 s
/// closed to 5.7e-17 J of energies of about 1e-16 J and was stopped before it was part of
/// the scale.
pub const AUDIT_TOLERANCE: f64 = 1e-6;

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
    /// Reached the end of the segment (a base-step point or the analysis end).
    Reached,
    /// These contacts close at `time` (state is at `time`, before the impulse).
    ContactClosed { contacts: Vec<usize>, time: f64 },
    /// A persistent contact was released at `time` (force would turn tensile).
    Released { contact: usize, time: f64 },
    /// The analysis end is reached.
    Finished,
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
    /// Observations over an interval ([`super::observe`]): building samples taken and
    /// skipped by the energy envelope, and overlap audits skipped (of as many samples
    /// as there were observations of each building).
    pub building_samples: u64,
    pub building_samples_skipped: u64,
    pub overlap_audits_skipped: u64,
    /// Held-gap projections beyond the round-off band (`Stepper::close_held_gaps`): held
    /// segments cut by another contact's closure.
    pub gap_projections: u64,
    /// The largest |δ| / `pen` of a contact at an impact it takes part in: the closure search
    /// resolves an impact where the gap is 0 (or `pen`, not yet re-armed), so this stays at
    /// most 1 plus round-off; a larger value is an impact resolved away from the contact
    /// surface (floors through each other, or apart).
    pub impact_gap_ratio: f64,
    /// Held segments taken (their accuracy checked: `Stepper::held_accurate_length`), and
    /// trials of them shortened for accuracy (`momentum.held_tolerance`).
    pub held_segments: u64,
    pub held_subdivisions: u64,
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
    /// Stops a run whose segments no longer advance time ([`crate::step::Progress`]).
    pub(super) progress: crate::step::Progress,
    pub diag: Diagnostics,
    /// The contact audit, when asked for ([`super::solve_audited`]).
    pub(super) audit: Option<super::audit::ContactAudit>,
    pub(super) guard: ImpactRateGuard,
    pub(super) last_impacts: Vec<VecDeque<f64>>,
    /// Per contact: just resolved (impact, release, graze) and not yet re-armed. Such a
    /// contact's closure is detected at δ = `pen` instead of 0, until its gap has opened
    /// beyond −`pen`: a contact left touching at rest is not found closing again and again
    /// at the same state by round-off.
    pub(super) grazing: Vec<bool>,
    /// The longest held segment (s) while a touching contact keeps being found closing at
    /// the start of held segments (`Stepper::persistent_segment`); `None`: no cap.
    pub(super) held_cap: Option<f64>,
    /// The length the last accepted held segment suggests for the next one
    /// (`persistent::HeldLength`).
    pub(super) held_next: Option<super::persistent::HeldLength>,
    /// Round-off band of each gap, m: [`crate::closure::band`], 1e-10 · max(gap, 1 mm).
    pub(super) pen: Vec<f64>,
    pub(super) xn: Vec<f64>,
    pub(super) vn: Vec<f64>,
    /// Running peaks, floor (story) index, building b's at `b * fs` (`fs` floors each:
    /// [`super::modal::BuildingModes::padded_floors`] of the widest building), zero-padded
    /// (as `stiffness` and the lower bounds).
    pub(super) disp_max: Vec<f64>,
    /// The stride of the per-building floor buffers: the widest building's padded floors.
    pub(super) fs: usize,
    /// The works of the accepted fast steps (input, damping) in four lane sums over the modes
    /// and steps, J, without their a·a terms; folded in by `finish`.
    pub(super) work_acc: [[f64; 4]; 2],
    /// Σ a₀², Σ a₀a₁, Σ a₁² over the accepted fast steps (the works' a·a terms,
    /// [`super::modal::StepCoeffs::aa_input`]).
    pub(super) aa_acc: [f64; 3],
    /// g·x of the first contact at the fast step's start, summed as `delta_fast` does.
    pub(super) delta0: f64,
    /// Per mode q̇² + ω² q² at the start of the fast step (the terms of 2E).
    pub(super) e_terms: Vec<f64>,
    /// Per building: its modes as chunks of `e_terms` (padded with zeros to whole chunks).
    pub(super) energy_spans: Vec<ChunkSpan>,
    /// The fast path found that base step j needs the closed form (state unchanged since).
    pub(super) fast_rejected: Option<usize>,
    /// Scratch of the fast step's interior checks: per mode the δ and δ̇ terms (before g).
    pub(super) check_d: Vec<f64>,
    pub(super) check_dd: Vec<f64>,
    pub(super) shear_max: Vec<f64>,
    pub(super) stiffness: Vec<f64>,
    pub(super) arcs: Vec<Arc>,
    /// [`Arc::trig`] of every arc at the segment end τ (shared by the end state and the
    /// damping integral).
    pub(super) trig_end: Vec<[f64; 3]>,
    /// Per arc: memo of [`Arc::trig`] (cleared when the arcs are rebuilt).
    pub(super) memo: Vec<TrigMemo>,
    /// The arcs by field, for the event location's evaluations in vectors, and its
    /// scratch (2 · [`ArcLanes::padded`]).
    pub(super) lanes: ArcLanes,
    pub(super) lane_buf: Vec<f64>,
    /// Floor displacements and velocities at the current and at the previous sample, building
    /// b's at `b * (fs + 1)`. Each building's part holds a leading zero (the ground) before
    /// its padded floors: floor i is at index i + 1, so `[..P]` is the floor below each
    /// floor of `[1..]`.
    pub(super) u: Vec<f64>,
    pub(super) ud: Vec<f64>,
    pub(super) u_prev: Vec<f64>,
    pub(super) ud_prev: Vec<f64>,
    /// The interval integrated since the previous sample (continuous peaks, [`peaks`]).
    pub(super) interval: peaks::Interval,
    /// Story-shear coefficients c_n = k_j (φ_n\[j\] − φ_n\[j−1\]) per building, story-major.
    pub(super) shear_rows: Vec<Vec<f64>>,
    /// Scratch: the coefficients of one response quantity.
    pub(super) coef: Vec<f64>,
    /// Contact forces of the segment being integrated at its planned end, N, one per scene
    /// contact: the holding forces of held contacts, 0 otherwise (history output).
    pub(super) held_force: Vec<f64>,
    /// The same at the segment's start (the forces are linear in time in between).
    pub(super) held_force_start: Vec<f64>,
    /// Scratch: the contact forces at a sample.
    pub(super) held_force_now: Vec<f64>,
    /// The held trials' buffers: ψ of the last length, the modes' transcendental parts and
    /// the held set's eliminated Delassus matrix (`persistent::HeldScratch`).
    pub(super) held_scratch: std::cell::RefCell<super::persistent::HeldScratch>,
    /// Overlap audit of facing floors without a contact ([`crate::overlap`]).
    pub overlaps: OverlapTracker,
    /// Per audited pair: coefficients of u_left − u_right on all modes (φ_left − φ_right).
    pub(super) overlap_rows: Vec<Vec<f64>>,
    /// Running lower bounds of the peaks from deferred candidates (filters only), per
    /// building (floor / story), and of the overlap maxima per pair.
    pub(super) disp_lower: Vec<f64>,
    pub(super) shear_lower: Vec<f64>,
    pub(super) overlap_lower: Vec<f64>,
    /// Candidates for the continuous peaks, refined at the end ([`peaks::Deferred`]).
    pub(super) deferred: peaks::Deferred,
    /// Scratch of the observation: the turn bits of one building (words of 64 bits stored as
    /// f64 bit patterns: floor displacements and story shears interleaved, 32 floors per
    /// word; see `observe::sample`), and the homogeneous amplitudes of every
    /// mode over the interval (for the Hermite error bounds; building b's modes valid if
    /// `amp_valid[b] == amp_epoch`) with their per-mode constants.
    pub(super) flags: Vec<f64>,
    pub(super) obs_amp: Vec<f64>,
    pub(super) amp_valid: Vec<u64>,
    /// The sample count that makes `amp_valid[b]` current (bumped per sample, instead of
    /// clearing a flag per building).
    pub(super) amp_epoch: u64,
    pub(super) amp_k: Vec<[f64; 3]>,
    /// Energy envelope of the observation ([`super::observe`]): per building (at `2 b fs`),
    /// the inverse flexibility norms 1/f_y of its floor displacements then story shears
    /// (each padded with ∞ to its padded floors P, the shears at `2 b fs + P`)
    /// (f_y = √(Σ_n c_n²/ω_n²), m/√J resp. N/√J), ‖Γ_b‖ (kg^½), the envelope threshold
    /// min_y peak_y/f_y (√J; 0 until the first observation) and whether the previous
    /// sample was observed (else u_prev, u̇_prev are rebuilt from the interval start).
    pub(super) env_inv: Vec<f64>,
    pub(super) env_gamma: Vec<f64>,
    pub(super) env_thr: Vec<f64>,
    /// Per building: a peak or lower bound grew since the threshold was computed.
    pub(super) env_stale: Vec<bool>,
    pub(super) prev_valid: Vec<bool>,
    /// The instruction set of the vectorised fast path (detected once).
    pub(super) arch: pulp::Arch,
    /// Per overlap pair: 1/f_y of u_left − u_right; per building: scratch envelope radius.
    pub(super) overlap_inv: Vec<f64>,
    pub(super) env_r: Vec<f64>,
    pub(super) skip: Vec<bool>,
    /// 2E_b per building at the start of the interval being observed: from the fast path's
    /// contact bound when it computed it (`env_e2_fresh`), else from the observation's
    /// envelope (`observe::twice_energy`); read only by the envelope.
    pub(super) env_e2: Vec<f64>,
    pub(super) env_e2_fresh: bool,
    /// The overlap pairs as runs of consecutive pairs whose floors both step by one (the
    /// paper scene's 14 pairs are one run): the first pass of the audit over slices.
    pub(super) overlap_runs: Vec<OverlapRun>,
    /// Per run: min_k max(maximum_k, lower_k)/f_y,k over its pairs (maxima of
    /// u_left − u_right; 0 if some pair has no positive one yet), recomputed when a maximum
    /// or a lower bound grew (`overlap_stale`).
    pub(super) overlap_lim: Vec<f64>,
    pub(super) overlap_stale: bool,
    /// Per overlap pair: its rate turned from + to − over the interval (1) or not (0).
    pub(super) overlap_turn: Vec<f64>,
}

/// The modes of one building as chunks of four of the fast step's per-mode buffers: chunks
/// `k0 ..= k1` (modes 4k0 … 4k1 + 3), the lanes of the first and the last that belong to the
/// building as masks (all ones or zeros).
#[derive(Debug, Clone, Copy)]
pub(super) struct ChunkSpan {
    k0: usize,
    k1: usize,
    head: [u64; 4],
    tail: [u64; 4],
}

impl ChunkSpan {
    fn new(r: std::ops::Range<usize>) -> ChunkSpan {
        let (k0, k1) = (r.start / 4, (r.end.max(r.start + 1) - 1) / 4);
        let lane = |ok: bool| if ok { u64::MAX } else { 0 };
        ChunkSpan {
            k0,
            k1,
            head: std::array::from_fn(|i| lane(4 * k0 + i >= r.start)),
            tail: std::array::from_fn(|i| lane(4 * k1 + i < r.end)),
        }
    }

    /// Σ of the span's terms in `t` (padded to whole chunks): four lane sums over the chunks,
    /// then (l₀ + l₁) + (l₂ + l₃).
    #[inline(always)]
    fn sum(&self, t: &[f64]) -> f64 {
        let masked = |c: &[f64], m: [u64; 4]| -> [f64; 4] {
            std::array::from_fn(|i| f64::from_bits(c[i].to_bits() & m[i]))
        };
        let s = &t[4 * self.k0..4 * self.k1 + 4];
        let mut acc;
        if self.k0 == self.k1 {
            let m = std::array::from_fn(|i| self.head[i] & self.tail[i]);
            acc = masked(s, m);
        } else {
            acc = masked(&s[..4], self.head);
            let inner = &s[4..s.len() - 4];
            for c in inner.chunks_exact(4) {
                acc = std::array::from_fn(|i| acc[i] + c[i]);
            }
            let last = masked(&s[s.len() - 4..], self.tail);
            acc = std::array::from_fn(|i| acc[i] + last[i]);
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3])
    }
}

/// One chunk of 4 modes `r` of the fast step: the new state into (xn, vn); returns this
/// step's works of the four modes (input, damping).
#[inline(always)]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn propagate_chunk(
    blk: &super::modal::StepBlock<4>,
    r: std::ops::Range<usize>,
    (x, v): (&[f64], &[f64]),
    (xn, vn): (&mut [f64], &mut [f64]),
    (a0, a1): (f64, f64),
    (w2, et): (&[f64], &mut [f64]),
) -> [[f64; 4]; 2] {
    let (xc, vc, wc): ([f64; 4], [f64; 4], [f64; 4]) = (
        x[r.clone()].try_into().unwrap(),
        v[r.clone()].try_into().unwrap(),
        w2[r.clone()].try_into().unwrap(),
    );
    // The terms of 2E at the start (as `observe::twice_energy`).
    let terms: [f64; 4] = std::array::from_fn(|i| vc[i] * vc[i] + wc[i] * xc[i] * xc[i]);
    et[r.clone()].copy_from_slice(&terms);
    let out = super::modal::propagate::<4>(blk, xc, vc, a0, a1);
    xn[r.clone()].copy_from_slice(&out[0]);
    vn[r].copy_from_slice(&out[1]);
    [out[2], out[3]]
}

/// Pairs `k0 .. k0 + n` of the overlap audit: floors `i0 + t` of building `left` against
/// `j0 + t` of building `right`, t < n.
#[derive(Debug, Clone, Copy)]
pub(super) struct OverlapRun {
    pub k0: usize,
    pub n: usize,
    pub left: usize,
    pub i0: usize,
    pub right: usize,
    pub j0: usize,
}

impl<'a> Stepper<'a> {
    pub fn new(
        p: &'a Problem,
        scene: &Scene,
        history: Option<&'a mut History>,
    ) -> Result<Self, SolverError> {
        let nm = p.modal.len();
        let nb = p.modal.buildings.len();
        // The per-building floor buffers' stride.
        let fs = p
            .modal
            .buildings
            .iter()
            .map(|b| b.padded_floors())
            .max()
            .unwrap_or(0);
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
            progress: crate::step::Progress::default(),
            diag: Diagnostics {
                sub_steps: p.sub,
                base_step: p.h,
                ..Diagnostics::default()
            },
            audit: None,
            guard: ImpactRateGuard::new(p.limits.max_impact_rate),
            last_impacts: vec![VecDeque::new(); p.contacts.len()],
            grazing: vec![false; p.contacts.len()],
            held_cap: None,
            held_next: None,
            pen: p
                .contacts
                .iter()
                .map(|c| crate::closure::band(c.gap))
                .collect(),
            xn: vec![0.0; nm],
            vn: vec![0.0; nm],
            work_acc: [[0.0; 4]; 2],
            aa_acc: [0.0; 3],
            delta0: 0.0,
            e_terms: vec![0.0; nm.div_ceil(4) * 4],
            energy_spans: p
                .modal
                .buildings
                .iter()
                .map(|bm| ChunkSpan::new(bm.range.clone()))
                .collect(),
            fast_rejected: None,
            check_d: vec![0.0; nm],
            check_dd: vec![0.0; nm],
            disp_max: vec![0.0; nb * fs],
            fs,
            shear_max: vec![0.0; nb * fs],
            stiffness: {
                let mut k = vec![0.0; nb * fs];
                for (b, bd) in scene.buildings.iter().enumerate() {
                    k[b * fs..b * fs + bd.story_stiffness.len()]
                        .copy_from_slice(&bd.story_stiffness);
                }
                k
            },
            u: vec![0.0; nb * (fs + 1)],
            arcs: Vec::with_capacity(nm),
            trig_end: vec![[0.0; 3]; nm],
            memo: vec![TrigMemo::EMPTY; nm],
            lanes: ArcLanes::default(),
            lane_buf: vec![0.0; 2 * ArcLanes::padded(nm)],
            ud: vec![0.0; nb * (fs + 1)],
            u_prev: vec![0.0; nb * (fs + 1)],
            ud_prev: vec![0.0; nb * (fs + 1)],
            interval: peaks::Interval {
                x0: vec![0.0; nm],
                v0: vec![0.0; nm],
                ..Default::default()
            },
            held_force: vec![0.0; p.contacts.len()],
            held_force_start: vec![0.0; p.contacts.len()],
            held_force_now: vec![0.0; p.contacts.len()],
            held_scratch: std::cell::RefCell::new(super::persistent::HeldScratch::new()),
            overlap_rows: Vec::new(),
            overlaps: OverlapTracker::new(scene),
            disp_lower: vec![0.0; nb * fs],
            shear_lower: vec![0.0; nb * fs],
            overlap_lower: Vec::new(),
            deferred: peaks::Deferred::new(nm),
            flags: Vec::new(),
            obs_amp: vec![0.0; nm],
            amp_valid: vec![0; p.modal.buildings.len()],
            amp_epoch: 1,
            amp_k: peaks::amplitude_constants(&p.modal),
            env_inv: Vec::new(),
            env_gamma: p
                .modal
                .buildings
                .iter()
                .map(|b| {
                    b.range
                        .clone()
                        .map(|n| p.modal.gamma[n].powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect(),
            env_thr: vec![0.0; p.modal.buildings.len()],
            env_stale: vec![true; p.modal.buildings.len()],
            prev_valid: vec![false; p.modal.buildings.len()],
            arch: pulp::Arch::new(),
            overlap_inv: Vec::new(),
            env_r: vec![0.0; p.modal.buildings.len()],
            skip: vec![false; p.modal.buildings.len()],
            env_e2: vec![0.0; p.modal.buildings.len()],
            env_e2_fresh: false,
            overlap_runs: Vec::new(),
            overlap_lim: Vec::new(),
            overlap_stale: true,
            overlap_turn: Vec::new(),
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
        st.overlap_lower = vec![f64::NEG_INFINITY; st.overlaps.pairs.len()];
        for (k, op) in st.overlaps.pairs.iter().enumerate() {
            match st.overlap_runs.last_mut() {
                Some(r)
                    if r.left == op.left
                        && r.right == op.right
                        && r.i0 + r.n == op.left_dof
                        && r.j0 + r.n == op.right_dof =>
                {
                    r.n += 1
                }
                _ => st.overlap_runs.push(OverlapRun {
                    k0: k,
                    n: 1,
                    left: op.left,
                    i0: op.left_dof,
                    right: op.right,
                    j0: op.right_dof,
                }),
            }
        }
        st.overlap_lim = vec![0.0; st.overlap_runs.len()];
        st.overlap_turn = vec![0.0; st.overlaps.pairs.len()];
        st.flags = vec![0.0; 2 * fs];
        let w2 = &p.omega2;
        let inv_f = |c: &[f64], first: usize| {
            let f2: f64 = c
                .iter()
                .enumerate()
                .map(|(m, c)| c * c / w2[first + m])
                .sum();
            // f64::MAX, not ∞, for a quantity without modal content: 0 · MAX = 0.
            if f2 > 0.0 {
                1.0 / f2.sqrt()
            } else {
                f64::MAX
            }
        };
        st.env_inv = vec![0.0; 2 * nb * fs];
        for (b, bm) in p.modal.buildings.iter().enumerate() {
            let (nf, nmb, first) = (bm.n_floors, bm.range.len(), bm.range.start);
            let disp = (0..nf).map(|i| {
                let row: Vec<f64> = (0..nmb).map(|m| bm.phi[m * nf + i]).collect();
                inv_f(&row, first)
            });
            let shear = (0..nf).map(|i| inv_f(&st.shear_rows[b][i * nmb..(i + 1) * nmb], first));
            // Padded floors: ∞ (their 0 · ∞ = NaN is never below the minimum).
            let pad = || std::iter::repeat_n(f64::INFINITY, bm.padded_floors() - nf);
            let inv = disp.chain(pad()).chain(shear).chain(pad());
            for (e, v) in st.env_inv[2 * b * fs..].iter_mut().zip(inv) {
                *e = v;
            }
        }
        st.overlap_inv = st.overlap_rows.iter().map(|r| inv_f(r, 0)).collect();
        st.energy.initial = p.modal.energy(&st.s.x, &st.s.v);
        if !st.energy.initial.is_finite() {
            return Err(SolverError::NonFinite {
                time: 0.0,
                context: format!(
                    "the initial energy is not finite ({:e} J): the initial state is too large \
                     to compute with",
                    st.energy.initial
                ),
            });
        }
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

    /// Records the interval about to be integrated from the current state (ground a0 → a1
    /// over `tau`, held-contact loads `fc`), for the continuous peaks of the next sample.
    pub(super) fn begin_interval(&mut self, a0: f64, a1: f64, tau: f64, fc: Option<&[f64]>) {
        let iv = &mut self.interval;
        iv.x0.clone_from(&self.s.x);
        iv.v0.clone_from(&self.s.v);
        (iv.a0, iv.a1, iv.tau) = (a0, a1, tau);
        iv.fc = fc.map(|f| f.to_vec());
        iv.tau_done = 0.0;
    }

    /// The velocities changed without a sample (an impulse): the next interval's rates at its
    /// start are the new ones.
    pub(super) fn refresh_rates(&mut self) {
        // In the widest instruction set (the reconstruction's fused multiply-adds inline).
        struct Op<'s, 'a> {
            st: &'s mut Stepper<'a>,
        }
        impl pulp::WithSimd for Op<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _: S) {
                let st = self.st;
                for (b, bm) in st.p.modal.buildings.iter().enumerate() {
                    let o = st.floors_at(b);
                    bm.to_floors(&st.s.v, &mut st.ud_prev[o + 1..o + st.fs + 1]);
                }
            }
        }
        let arch = self.arch;
        arch.dispatch(Op { st: self })
    }

    /// The displacements changed without a sample (the held gaps closed,
    /// [`Stepper::close_held_gaps`]): the next interval's values at its start are the new ones,
    /// and they are a sample of the peaks and overlap maxima too (the same formulas as the
    /// sample kernel: |u|, |k (u_i − u_{i−1})| and u_left − u_right), or a peak reached at the
    /// jump would be missed: the next interval's sample looks at its end and its interior only.
    pub(super) fn refresh_values(&mut self) {
        let t = self.s.t;
        for (b, bm) in self.p.modal.buildings.iter().enumerate() {
            let (o, f) = (self.floors_at(b), self.floor_at(b, 0));
            bm.to_floors(&self.s.x, &mut self.u_prev[o + 1..o + self.fs + 1]);
            // u_prev[o] is the ground's 0.
            for i in 0..bm.n_floors {
                let (u, below) = (self.u_prev[o + 1 + i], self.u_prev[o + i]);
                let shear = (self.stiffness[f + i] * (u - below)).abs();
                self.disp_max[f + i] = self.disp_max[f + i].max(u.abs());
                self.shear_max[f + i] = self.shear_max[f + i].max(shear);
            }
            self.env_stale[b] = true;
        }
        for k in 0..self.overlaps.pairs.len() {
            let op = &self.overlaps.pairs[k];
            let i = self.floors_at(op.left) + op.left_dof + 1;
            let j = self.floors_at(op.right) + op.right_dof + 1;
            let y = self.u_prev[i] - self.u_prev[j];
            self.overlaps.offer(k, t, y);
        }
        self.overlap_stale = true;
    }

    /// Peak story shears and floor displacements per building.
    pub fn peaks(&self, scene: &Scene) -> Vec<BuildingResponse> {
        scene
            .buildings
            .iter()
            .enumerate()
            .map(|(b, bd)| BuildingResponse {
                name: bd.name.clone(),
                story_shear_max: self.shear_max[self.floor_at(b, 0)..][..bd.n_floors()].to_vec(),
                floor_displacement_max: self.disp_max[self.floor_at(b, 0)..][..bd.n_floors()]
                    .to_vec(),
                ..Default::default()
            })
            .collect()
    }

    #[inline(always)]
    pub(super) fn count_step(&mut self, tau: f64) -> Result<(), SolverError> {
        self.stats.steps += 1;
        if tau > 0.0 {
            self.stats.min_step = self.stats.min_step.min(tau);
            self.stats.max_step = self.stats.max_step.max(tau);
        }
        // Checked every 64 segments (and at the end): a non-finite mode stays non-finite.
        if self.stats.steps > self.p.limits.max_steps || self.stats.steps.is_multiple_of(64) {
            return self.count_step_checks();
        }
        Ok(())
    }

    /// The rare part of [`Stepper::count_step`]: the step budget and the finiteness check.
    #[cold]
    #[inline(never)]
    fn count_step_checks(&mut self) -> Result<(), SolverError> {
        if self.stats.steps > self.p.limits.max_steps {
            let held: Vec<usize> = self.s.persistent.iter().map(|&(c, _)| c).collect();
            return Err(SolverError::StepBudget {
                time: self.s.t,
                steps: self.stats.steps,
                limit: self.p.limits.max_steps,
                context: format!(
                    "{} impacts so far, contacts in persistent contact: {held:?}",
                    self.stats.impacts
                ),
            });
        }
        self.progress.check(self.s.t, self.stats.steps)?;
        if self.stats.steps.is_multiple_of(64) && !self.state_is_finite() {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: "modal state after a propagation segment".into(),
            });
        }
        Ok(())
    }

    pub(super) fn state_is_finite(&self) -> bool {
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

    pub(super) fn kinetic(&self) -> f64 {
        0.5 * self.s.v.iter().map(|v| v * v).sum::<f64>()
    }

    /// The step from the current state: `None` at the end of the analysis, else its index j,
    /// its end (the next grid point or the duration) and its length.
    #[inline(always)]
    fn pending(&self) -> Option<(usize, f64, f64)> {
        let p = self.p;
        if self.s.t >= p.duration - 1e-12 * p.h {
            return None;
        }
        let j = self.s.j;
        let t_end = if j + 1 >= p.n_steps {
            p.duration
        } else {
            p.grid(j + 1)
        };
        Some((j, t_end, t_end - self.s.t))
    }

    /// Whether a pending step of length `tau` is a degenerate sliver (state unchanged).
    #[inline(always)]
    fn is_sliver(&self, tau: f64) -> bool {
        tau <= (1e-12 * self.p.h).max(1e-15 * self.s.t)
    }

    /// Whether a pending step of length `tau` is a full base step from a grid point.
    #[inline(always)]
    fn is_full(&self, tau: f64) -> bool {
        self.s.on_grid && (tau - self.p.h).abs() <= 1e-9 * self.p.h
    }

    /// Advances one segment.
    pub fn advance(&mut self) -> Result<Step, SolverError> {
        let Some((j, t_end, tau)) = self.pending() else {
            return Ok(Step::Finished);
        };
        if self.is_sliver(tau) {
            // Degenerate sliver: jump to the grid point (state unchanged).
            self.finish_grid(j, t_end);
            return Ok(Step::Reached);
        }
        if !self.s.persistent.is_empty() {
            return self.persistent_segment(tau, t_end);
        }
        if self.is_full(tau) {
            // (A step the fast path already tried from this very state is not tried again.)
            if std::mem::take(&mut self.fast_rejected) != Some(j) {
                if let Some(step) = self.fast_step(j, t_end)? {
                    return Ok(step);
                }
            }
        }
        self.segment(tau, t_end, None, true)
    }

    /// The next step if [`Stepper::advance`] would take it on the fast path (the same tests
    /// in the same order): its index and end time.
    #[inline(always)]
    fn next_fast(&self) -> Option<(usize, f64)> {
        let (j, t_end, tau) = self.pending()?;
        if self.is_sliver(tau) || !self.s.persistent.is_empty() {
            return None;
        }
        self.is_full(tau).then_some((j, t_end))
    }

    pub(super) fn finish_grid(&mut self, j: usize, t_end: f64) {
        self.s.t = t_end;
        self.s.j = (j + 1).min(self.p.n_steps);
        self.s.on_grid = true;
    }

    /// A full base step with precomputed propagators; `None` if an event may occur (the
    /// caller then takes the closed-form path from the unchanged state).
    ///
    /// Runs with the widest vector instructions the machine has (AVX2 where available,
    /// [`pulp::Arch`]): the same operations in the same order (no fused multiply-add), so
    /// the results are bit-identical on every machine.
    fn fast_step(&mut self, j: usize, t_end: f64) -> Result<Option<Step>, SolverError> {
        struct Op<'s, 'a> {
            st: &'s mut Stepper<'a>,
            j: usize,
            t_end: f64,
        }
        impl pulp::WithSimd for Op<'_, '_> {
            type Output = Result<Option<Step>, SolverError>;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, simd: S) -> Self::Output {
                // Consecutive fast steps in one dispatch: after an accepted step, the next
                // one too if `advance` would take it on the fast path (the caller does
                // nothing between `Reached` steps). A step found to need the closed form
                // after some were accepted ends the run as `Reached` with the state at its
                // start, remembered so that `advance` goes to the closed form at once.
                let (mut j, mut t_end) = (self.j, self.t_end);
                let mut accepted = false;
                loop {
                    match self.st.fast_step_body(simd, j, t_end)? {
                        None if accepted => {
                            self.st.fast_rejected = Some(j);
                            return Ok(Some(Step::Reached));
                        }
                        None => return Ok(None),
                        Some(step) => match self.st.next_fast() {
                            Some(next) => {
                                accepted = true;
                                (j, t_end) = next;
                            }
                            None => return Ok(Some(step)),
                        },
                    }
                }
            }
        }
        let arch = self.arch;
        arch.dispatch(Op { st: self, j, t_end })
    }

    #[inline(always)]
    fn fast_step_body<S: pulp::Simd>(
        &mut self,
        simd: S,
        j: usize,
        t_end: f64,
    ) -> Result<Option<Step>, SolverError> {
        let p = self.p;
        let (a0, a1) = (p.ag_start[j], p.ag_end[j]);
        let h = p.full.h;
        // This step's works (input, damping) in four lane sums over the modes.
        let mut work = [[0.0f64; 4]; 2];
        {
            // Modes in chunks of 4 (coefficients interleaved per chunk, the tail in a padded
            // chunk): fixed-width arithmetic without bounds checks, which vectorises.
            let c = &p.full;
            let nm = self.s.x.len();
            let n4 = nm / 4 * 4;
            let (x, v) = (&self.s.x[..nm], &self.s.v[..nm]);
            let (xn, vn) = (&mut self.xn[..nm], &mut self.vn[..nm]);
            let (w2, et) = (&p.omega2[..nm], &mut self.e_terms[..nm]);
            // δ of the first contact at the start as `ContactGeom::delta_fast` sums it (four
            // lane sums over the chunks, the remainder into lane 0), while x passes by (with
            // no contact, a dummy sum).
            let g0 = p.contacts.first().map_or(x, |ct| &ct.g[..nm]);
            let mut gacc = [0.0f64; 4];
            for (k, blk) in c.blocks.iter().enumerate() {
                let r = 4 * k..4 * k + 4;
                let (gc, xc): ([f64; 4], [f64; 4]) = (
                    g0[r.clone()].try_into().unwrap(),
                    x[r.clone()].try_into().unwrap(),
                );
                gacc = std::array::from_fn(|i| gacc[i] + gc[i] * xc[i]);
                let e = propagate_chunk(blk, r, (x, v), (xn, vn), (a0, a1), (w2, &mut *et));
                work = std::array::from_fn(|j| std::array::from_fn(|i| work[j][i] + e[j][i]));
            }
            for k in n4..nm {
                gacc[0] += g0[k] * x[k];
            }
            self.delta0 = (gacc[0] + gacc[1]) + (gacc[2] + gacc[3]);
            if let Some(last) = &c.last {
                // The remainder as the last 4 modes (the first of them again: same values).
                let r = nm - 4..nm;
                let e = propagate_chunk(last, r, (x, v), (xn, vn), (a0, a1), (w2, &mut *et));
                // Only the lanes of the modes past the whole chunks count.
                let new = |i: usize| nm - 4 + i >= n4;
                work = std::array::from_fn(|j| {
                    std::array::from_fn(|i| work[j][i] + if new(i) { e[j][i] } else { 0.0 })
                });
            } else if let Some(tail) = &c.tail {
                // Lane by lane (variable-length slice copies would be library calls).
                let t = nm - n4;
                let lane = |s: &[f64], i: usize| if i < t { s[n4 + i] } else { 0.0 };
                let xt: [f64; 4] = std::array::from_fn(|i| lane(x, i));
                let vt: [f64; 4] = std::array::from_fn(|i| lane(v, i));
                let out = super::modal::propagate::<4>(tail, xt, vt, a0, a1);
                for i in 0..4 {
                    if i < t {
                        let n = n4 + i;
                        et[n] = v[n] * v[n] + w2[n] * x[n] * x[n];
                        xn[n4 + i] = out[0][i];
                        vn[n4 + i] = out[1][i];
                        work[0][i] += out[2][i];
                        work[1][i] += out[3][i];
                    }
                }
            }
        }
        // Rigorous skip of far contacts: d√(2E)/dt ≤ |f| (modal load norm), so over the step
        // |δ̇| ≤ √W_c (√(2E₀) + h |a_g|max √ΣΓ²) and δ(s) ≤ δ₀ + s·max|δ̇| < 0 if δ₀ is
        // below −h times that bound.
        // Per building 2E_b = Σ (q̇² + ω² q²) over its modes (kept for the observation's
        // energy envelope of this interval), and their sum for the contact bound.
        let mut e2 = 0.0;
        for (span, env) in self.energy_spans.iter().zip(self.env_e2.iter_mut()) {
            // The terms of `observe::twice_energy`, summed by aligned chunks (another order:
            // the bounds that use 2E_b carry margins for its round-off).
            let e = span.sum(&self.e_terms);
            *env = e;
            e2 += e;
        }
        self.env_e2_fresh = true;
        let vbound = e2.sqrt() + h * a0.abs().max(a1.abs()) * p.gamma_norm;
        let sub = p.sub;
        let mut arcs_built = false;
        for (ci, ct) in p.contacts.iter().enumerate() {
            // δ, δ̇ at the window ends 0, h/sub, …, h. The skip test uses the vectorised
            // sum: its round-off (≲ 30 ε |g|·|q|) is far inside the bound's relative margin
            // of 1e-9 (h·√W·vbound ≥ h ω_min |g|·|q|).
            let df = if ci == 0 {
                self.delta0 - ct.gap
            } else {
                ct.delta_fast(&self.s.x)
            };
            if df < -h * p.sqrt_w[ci] * vbound * (1.0 + 1e-9) {
                continue;
            }
            let d_start = ct.delta(&self.s.x);
            let mut prev = (d_start, ct.dot(&self.s.v));
            if prev.0 >= 0.0 {
                return Ok(None);
            }
            for w in 1..=sub {
                let cur = if w == sub {
                    (ct.delta(&self.xn), ct.dot(&self.vn))
                } else if !p.check_starts.is_empty() {
                    // The per-mode terms by chunks of 4 (the same expressions), then the
                    // sums in mode order.
                    let r = w as f64 / sub as f64;
                    let fr = a0 + r * (a1 - a0);
                    let nm = self.s.x.len();
                    let (x, v) = (&self.s.x[..nm], &self.s.v[..nm]);
                    let (td, tdd) = (&mut self.check_d[..nm], &mut self.check_dd[..nm]);
                    for (k, &n0) in p.check_blocks[w - 1].iter().zip(&p.check_starts) {
                        let rr = n0..n0 + 4;
                        let x0: [f64; 4] = x[rr.clone()].try_into().unwrap();
                        let v0: [f64; 4] = v[rr.clone()].try_into().unwrap();
                        let mut a = [0.0; 4];
                        let mut b = [0.0; 4];
                        for i in 0..4 {
                            let gam = k[8][i];
                            let (f0, f1) = (-gam * a0, -gam * fr);
                            a[i] = k[0][i] * x0[i] + k[1][i] * v0[i] + k[2][i] * f0 + k[3][i] * f1;
                            b[i] = k[4][i] * x0[i] + k[5][i] * v0[i] + k[6][i] * f0 + k[7][i] * f1;
                        }
                        td[rr.clone()].copy_from_slice(&a);
                        tdd[rr].copy_from_slice(&b);
                    }
                    let (mut d, mut dd) = (-ct.gap, 0.0);
                    for ((g, t), tt) in ct.g.iter().zip(&*td).zip(&*tdd) {
                        if *g != 0.0 {
                            d += g * t;
                            dd += g * tt;
                        }
                    }
                    (d, dd)
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
                // Below zero at both ends: open unless δ has an interior maximum, where δ̇ falls
                // from > 0 to < 0, or where it turns twice with one sign at both ends (a
                // rattle's end: the cubic Hermite interpolant of the window's ends turns twice,
                // `peaks::turns_twice`; a double turn hidden within the cubic's error,
                // len⁴/384·max|δ⁗|, is not looked for). The slopes bound δ first, at no cost:
                // |δ̇| ≤ √W_c·vbound, so δ ≤ (δ₀ + δ₁ + len·max|δ̇|)/2 over the window. Then the
                // rigorous Hermite bound of `Search::surely_open`.
                let len = h / sub as f64;
                if prev.0 + cur.0 + len * p.sqrt_w[ci] * vbound * (1.0 + 1e-9) >= 0.0
                    && ((prev.1 > 0.0 && cur.1 < 0.0)
                        || super::peaks::turns_twice(prev.0, prev.1, cur.0, cur.1, len))
                {
                    if !arcs_built {
                        self.build_arcs(a0, a1, h, None);
                        arcs_built = true;
                    }
                    let curve = ModalGap {
                        contact: ct,
                        arcs: &self.arcs,
                        modal: &p.modal,
                        memo: &mut self.memo,
                        lanes: &self.lanes,
                        buf: &mut self.lane_buf,
                    };
                    let search = Search {
                        lo: h * (w - 1) as f64 / sub as f64,
                        hi: h * w as f64 / sub as f64,
                        tol: 0.0,
                        shift: 0.0,
                        band: 0.0,
                        iterations: 0,
                    };
                    if !search.surely_open(&curve, prev.0, prev.1, cur.0, cur.1) {
                        return Ok(None);
                    }
                }
                prev = cur;
            }
        }
        // Accepted: the new state becomes current and the old one the start of the interval
        // just integrated (buffers exchanged, nothing copied).
        std::mem::swap(&mut self.s.x, &mut self.xn);
        std::mem::swap(&mut self.s.v, &mut self.vn);
        std::mem::swap(&mut self.interval.x0, &mut self.xn);
        std::mem::swap(&mut self.interval.v0, &mut self.vn);
        let iv = &mut self.interval;
        (iv.a0, iv.a1, iv.tau, iv.fc) = (a0, a1, h, None);
        // Energy of the accepted step only (a step with a possible event is discarded).
        self.work_acc =
            std::array::from_fn(|j| std::array::from_fn(|i| self.work_acc[j][i] + work[j][i]));
        let aa = &mut self.aa_acc;
        (aa[0], aa[1], aa[2]) = (aa[0] + a0 * a0, aa[1] + a0 * a1, aa[2] + a1 * a1);
        self.finish_grid(j, t_end);
        self.count_step(h)?;
        self.interval.tau_done = h;
        // (In this instruction set already: no second dispatch.)
        self.observe_with(simd);
        Ok(Some(Step::Reached))
    }

    /// Arcs of every mode from the current state, ground a0 → a1 over tau, plus the
    /// held-contact loads `fc` (per mode at the start, then per mode at tau; linear in time).
    pub(super) fn build_arcs(&mut self, a0: f64, a1: f64, tau: f64, fc: Option<&[f64]>) {
        let m = &self.p.modal;
        self.arcs.clear();
        self.memo.iter_mut().for_each(TrigMemo::clear);
        // `Modal::arc` of every mode, the modal vectors cut once (no bounds checks in the
        // loop).
        let nm = m.len();
        let (gamma, omega, zeta) = (&m.gamma[..nm], &m.omega[..nm], &m.zeta[..nm]);
        let (series, x, v) = (&m.series[..nm], &self.s.x[..nm], &self.s.v[..nm]);
        match fc.map(|f| f[..2 * nm].split_at(nm)) {
            None => self.arcs.extend((0..nm).map(|n| {
                let (f0, f1) = (-gamma[n] * a0, -gamma[n] * a1);
                Arc::new(omega[n], zeta[n], x[n], v[n], f0, f1, tau).series_if(series[n])
            })),
            Some((e0, e1)) => self.arcs.extend((0..nm).map(|n| {
                let (f0, f1) = (-gamma[n] * a0 + e0[n], -gamma[n] * a1 + e1[n]);
                m.held_arc(n, x[n], v[n], f0, f1, tau)
            })),
        }
        self.lanes.set(&self.arcs);
    }

    /// The state at the end τ of the arcs' segment into `xn`, `vn` (and `trig_end`).
    fn end_state(&mut self, tau: f64) {
        for n in 0..self.arcs.len() {
            let t = TrigMemo::get(&self.arcs, &mut self.memo, n, tau);
            let (x1, v1) = self.arcs[n].xv_from(tau, t);
            self.xn[n] = x1;
            self.vn[n] = v1;
            self.trig_end[n] = t;
        }
    }

    /// General segment of length tau on the closed form, with event location. `grid_end`:
    /// the segment ends on the base grid point `t_end` (else at `t + tau`, inside the step).
    pub(super) fn segment(
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
        let (first, found, end_ready) = self.locate_closures(tau);
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
        if s_end == tau && !end_ready {
            self.end_state(tau);
        }
        let m = &p.modal;
        for n in 0..self.arcs.len() {
            let a = self.arcs[n];
            let (x1, v1, t) = if s_end == tau {
                (self.xn[n], self.vn[n], self.trig_end[n])
            } else {
                let t = TrigMemo::get(&self.arcs, &mut self.memo, n, s_end);
                let (x1, v1) = a.xv_from(s_end, t);
                (x1, v1, t)
            };
            if s_end > 0.0 {
                // The load's work, the ground's part to the input and the held contacts'
                // (linear over tau) to the contact account: split before the integration by
                // parts of `load_work`, whose cancellation the steep force ramps of very short
                // held segments would amplify.
                let ramps = fc.map(|f| {
                    let (c0, c1) = (f[n], f[m.len() + n]);
                    let (g0, g1) = (-m.gamma[n] * a0, -m.gamma[n] * a1);
                    [(g0, (g1 - g0) / tau), (c0, (c1 - c0) / tau)]
                });
                let (w, wc, damping) = a.segment_energy(s_end, x1, v1, t, ramps);
                self.energy.input += w;
                self.energy.contact -= wc;
                self.energy.damping += 2.0 * m.zeta[n] * m.omega[n] * damping;
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

    /// The first closure over [0, tau] of the contacts not held, on the arcs just built
    /// ([`Stepper::build_arcs`]) from the current state: its instant (from the segment start),
    /// every contact found closing with its instant, and whether (xn, vn) hold the state at
    /// tau. Commits nothing (but re-arms a contact whose gap has opened, as the search does).
    pub(super) fn locate_closures(&mut self, tau: f64) -> (Option<f64>, Vec<(usize, f64)>, bool) {
        let p = self.p;
        // The state at τ (xn, vn), computed when first needed: a closure located in an
        // earlier window does not need it.
        let mut end_ready = false;
        let tol = 2.0 * f64::EPSILON * (self.s.t + tau) + 1e-300;
        let mut first: Option<f64> = None;
        let mut found: Vec<(usize, f64)> = vec![];
        // Contacts re-armed at a window end without closing after it, and where.
        let mut rearmed: Vec<(usize, f64)> = vec![];
        for (ci, ct) in p.contacts.iter().enumerate() {
            if self.s.persistent.iter().any(|&(c, _)| c == ci) {
                continue;
            }
            // Windows of at most h/sub: at most one extremum of δ each.
            let m = ((tau / (p.h / p.sub as f64)) - 1e-9).ceil().max(1.0) as usize;
            let at = |s: f64, arcs: &[Arc], memo: &mut [TrigMemo]| {
                let (mut d, mut dd) = (-ct.gap, 0.0);
                for (n, (g, a)) in ct.g.iter().zip(arcs).enumerate() {
                    if *g != 0.0 {
                        let (x, v) = a.xv_from(s, TrigMemo::get(arcs, memo, n, s));
                        d += g * x;
                        dd += g * v;
                    }
                }
                (d, dd)
            };
            if self.grazing[ci] && ct.delta(&self.s.x) < -self.pen[ci] {
                self.grazing[ci] = false;
            }
            // A contact not yet re-armed is searched at δ = pen until its gap opens beyond
            // −pen: at a window end (the later windows at δ = 0), or inside a window at the
            // minimum that precedes a new approach (the locator re-arms it there).
            let mut shift = if self.grazing[ci] { self.pen[ci] } else { 0.0 };
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
                    if !end_ready {
                        self.end_state(tau);
                        end_ready = true;
                    }
                    (ct.delta(&self.xn) - shift, ct.dot(&self.vn))
                } else {
                    let (d, dd) = at(hi, &self.arcs, &mut self.memo);
                    (d - shift, dd)
                };
                let mut curve = ModalGap {
                    contact: ct,
                    arcs: &self.arcs,
                    modal: &p.modal,
                    memo: &mut self.memo,
                    lanes: &self.lanes,
                    buf: &mut self.lane_buf,
                };
                let mut search = Search {
                    lo,
                    hi,
                    tol,
                    shift,
                    band: self.pen[ci],
                    iterations: 0,
                };
                r = search.locate(&mut curve, prev.0, prev.1, cur.0, cur.1);
                self.stats.root_iterations += search.iterations;
                if r.is_some() {
                    break;
                }
                prev = cur;
                if crate::closure::rearm_at_window_end(&mut prev, &mut shift) {
                    rearmed.push((ci, hi));
                }
            }
            if let Some(s) = r {
                found.push((ci, s));
                first = Some(first.map_or(s, |f: f64| f.min(s)));
            }
        }
        // The re-arming outlives the segment if it came before its end (the first closure or
        // τ): a gap that opened beyond −pen and is back inside the band at the end is then
        // searched at δ = 0 by the next segment, not at δ = pen.
        for (ci, s) in rearmed {
            if first.is_none_or(|f| s <= f) {
                self.grazing[ci] = false;
            }
        }
        (first, found, end_ready)
    }

    /// Where building `b`'s part of `u`, `ud`, `u_prev` and `ud_prev` begins: its leading zero
    /// (the ground), floor i at `floors_at(b) + i + 1`.
    #[inline(always)]
    pub(super) fn floors_at(&self, b: usize) -> usize {
        b * (self.fs + 1)
    }

    /// Floor (story) `i` of building `b` in the per-floor buffers (`disp_max`, `shear_max`,
    /// their lower bounds, `stiffness`).
    #[inline(always)]
    pub(super) fn floor_at(&self, b: usize, i: usize) -> usize {
        b * self.fs + i
    }

    /// Closes open phases and returns the final modal energy.
    pub fn finish(&mut self) -> Result<f64, SolverError> {
        if !self.state_is_finite() {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: "modal state at the end of the analysis".into(),
            });
        }
        // The fast steps' works: per mode, plus the a·a terms of all modes at once.
        let (input, damping) = self.fast_works();
        self.energy.input += input;
        self.energy.damping += damping;
        self.aa_acc = [0.0; 3];
        self.work_acc = [[0.0; 4]; 2];
        self.resolve_deferred();
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
        let final_e = self.p.modal.energy(&self.s.x, &self.s.v);
        let e = &self.energy;
        let balance = e.initial + e.input - e.damping - e.contact - final_e;
        // A finite state whose squares overflow (a velocity of 1e200 m/s): no energy to
        // audit, and no result to return.
        if !(final_e.is_finite() && balance.is_finite()) {
            return Err(SolverError::NonFinite {
                time: self.s.t,
                context: format!(
                    "the energies are not finite (initial {:.6e} J, input {:.6e} J, final \
                     {final_e:.6e} J): the state is too large to compute with",
                    e.initial, e.input
                ),
            });
        }
        let scale = e.initial + e.input.abs() + final_e + self.p.static_energy;
        if balance.abs() > AUDIT_TOLERANCE * scale {
            return Err(SolverError::Stalled {
                time: self.s.t,
                reason: format!(
                    "the energy audit does not close at the end (initial {:.6e} J + input \
                     {:.6e} J − damping {:.6e} J − contact {:.6e} J − final {:.6e} J = \
                     {balance:.3e} J): the results are not trustworthy",
                    e.initial, e.input, e.damping, e.contact, final_e
                ),
            });
        }
        Ok(final_e)
    }

    /// The input and damping works of the accepted fast steps not yet folded into the
    /// account (`work_acc`, `aa_acc`), J.
    fn fast_works(&self) -> (f64, f64) {
        let (aa, c) = (self.aa_acc, &self.p.full);
        let dot = |k: &[f64; 3]| k[0] * aa[0] + k[1] * aa[1] + k[2] * aa[2];
        let lanes = |w: [f64; 4]| (w[0] + w[1]) + (w[2] + w[3]);
        (
            lanes(self.work_acc[0]) + dot(&c.aa_input),
            lanes(self.work_acc[1]) + dot(&c.aa_damping),
        )
    }

    /// Held contacts and impacts can only remove energy: a contact account (the running
    /// total, not one phase's part) below −[`AUDIT_TOLERANCE`] of the energy scale (initial +
    /// |input| so far + present energy; not the end audit's static energy of the whole run's
    /// largest load, which would judge an early phase by a later load) means a held phase
    /// went wrong, and the run stops there, saying so, instead of returning garbage.
    pub(super) fn check_contact_account(&self) -> Result<(), SolverError> {
        let e = &self.energy;
        let input = e.input + self.fast_works().0;
        let now = self.p.modal.energy(&self.s.x, &self.s.v);
        if e.contact < -AUDIT_TOLERANCE * (e.initial + input.abs() + now) {
            return Err(SolverError::Stalled {
                time: self.s.t,
                reason: format!(
                    "the held contacts {:?} did {:.3e} J of work on the buildings (input so far \
                     {input:.3e} J, present energy {now:.3e} J): a held phase lost its \
                     constraint (docs/solvers.md, a held phase cut by another contact's \
                     closure); the results would not be trustworthy",
                    self.s
                        .persistent
                        .iter()
                        .map(|&(c, _)| c)
                        .collect::<Vec<_>>(),
                    -e.contact
                ),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A held-gap projection moves the floors without a sample: `refresh_values` offers the
    /// new values to the peaks and the overlap maxima (with the sample kernel's formulas), so
    /// a peak reached at the jump is not lost.
    #[test]
    fn values_moved_without_a_sample_are_offered_to_the_peaks() {
        let scene = structure::testing::paper_scene(&[]);
        let p = Problem::new(&scene).unwrap();
        let mut st = Stepper::new(&p, &scene, None).unwrap();
        assert!(!st.overlaps.is_empty());
        // Building 0 in its first mode, the roof 0.1 m towards building 1 (at rest), higher
        // modes mixed in: building 0's floors pass building 1's at every pair (the first
        // mode, of one sign, dominates), and every story of building 0 is sheared.
        let b0 = &p.modal.buildings[0];
        let mut u = vec![0.0; b0.padded_floors()];
        st.s.x[b0.range.start] = 1.0;
        b0.to_floors(&st.s.x, &mut u);
        let first = 0.1 / u[b0.n_floors - 1];
        for (n, x) in st.s.x[b0.range.clone()].iter_mut().enumerate() {
            *x = first * (n as f64 + 1.0).powi(-3) * if n % 3 == 2 { -1.0 } else { 1.0 };
        }
        let before = st.overlaps.max.clone();
        st.refresh_values();
        for (b, bm) in p.modal.buildings.iter().enumerate() {
            let mut u = vec![0.0; bm.padded_floors() + 1];
            bm.to_floors(&st.s.x, &mut u[1..]);
            for i in 0..bm.n_floors {
                let f = st.floor_at(b, i);
                assert_eq!(st.disp_max[f], u[i + 1].abs(), "building {b} floor {i}");
                let shear = (st.stiffness[f] * (u[i + 1] - u[i])).abs();
                assert_eq!(st.shear_max[f], shear, "building {b} story {i}");
                assert!(b == 1 || shear > 0.0, "building {b} story {i}");
            }
        }
        for (k, op) in st.overlaps.pairs.iter().enumerate() {
            let y = |b: usize, dof: usize| {
                let mut u = vec![0.0; p.modal.buildings[b].padded_floors()];
                p.modal.buildings[b].to_floors(&st.s.x, &mut u);
                u[dof]
            };
            let expect = y(op.left, op.left_dof) - y(op.right, op.right_dof);
            assert!(expect > before[k], "pair {k}: {expect} after {}", before[k]);
            assert_eq!(st.overlaps.max[k], expect, "pair {k}");
        }
    }
}
