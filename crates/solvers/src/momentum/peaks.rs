//! Continuous peaks between samples (issue 10): the momentum method knows every mode in
//! closed form between events, so a peak of a response quantity y(t) = Σ_n c_n q_n(t) (a
//! floor displacement, c_n = φ_n[i]; a story shear, c_n = k_j (φ_n[j] − φ_n[j−1])) that falls
//! between two samples is found exactly rather than sampled.
//!
//! At each sample the solver knows y and ẏ (ẏ = Σ c_n q̇_n) at both ends of the interval just
//! integrated. A sign change of ẏ means an interior extremum (intervals are at most one
//! record step, shorter than the shortest periods that matter: at most one extremum of the
//! quantity). Its value is estimated by the cubic Hermite interpolant H of (y, ẏ) at the
//! ends; when that estimate could raise the running peak (|H| ≥ 0.9 × peak and |H| plus the
//! bound len⁴/384 · Σ|c_n| ω_n⁴ |A_n − iB_n| on |y − H| reaches the peak), the
//! extremum is located by Newton's method on ẏ(s) = 0 with ÿ from the equations of motion
//! (q̈ = f − 2ζωq̇ − ω²q), started at the Hermite estimate, on the closed form, to a
//! relative step of 1e-13, and its exact value replaces the peak if larger.
//!
//! The overlap audit ([`crate::overlap`]) uses the same machinery for the signed maxima of
//! u_left[i] − u_right[j], whose coefficients c_n = φ_n[i] on the left building's modes and
//! −φ_n[j] on the right building's span both buildings (`first` = 0, all modes).

use super::modal::{Arc, Modal};

/// The interval integrated since the last sample: the modal state at its start, the ground
/// acceleration at its ends and its length (the closed form of every mode over it).
#[derive(Debug, Clone, Default)]
pub struct Interval {
    pub x0: Vec<f64>,
    pub v0: Vec<f64>,
    /// Ground acceleration at the start and at `tau`, m/s².
    pub a0: f64,
    pub a1: f64,
    /// Length over which the ground acceleration goes from a0 to a1, s.
    pub tau: f64,
    /// Constant modal loads of held contacts (persistent phase), if any.
    pub fc: Option<Vec<f64>>,
    /// Length actually integrated (≤ `tau`: an event may end the interval early), s.
    pub tau_done: f64,
}

pub use crate::response::hermite_extremum;

/// The closed-form arcs of the modes `range` over the interval `iv`.
pub fn arcs(modal: &Modal, range: std::ops::Range<usize>, iv: &Interval) -> Vec<Arc> {
    range
        .map(|n| {
            let extra = iv.fc.as_ref().map_or(0.0, |f| f[n]);
            Arc::new(
                modal.omega[n],
                modal.zeta[n],
                iv.x0[n],
                iv.v0[n],
                -modal.gamma[n] * iv.a0 + extra,
                -modal.gamma[n] * iv.a1 + extra,
                iv.tau,
            )
        })
        .collect()
}

/// Bound on |y − H| over an interval of length `len`, H the cubic Hermite interpolant of
/// y = Σ c_m q_m: len⁴/384 · max|y⁗| with |q_m⁗| ≤ ω_m⁴ |A_m − iB_m| (the homogeneous part;
/// the particular part is linear in time).
pub fn hermite_error_bound(modal: &Modal, first: usize, c: &[f64], arcs: &[Arc], len: f64) -> f64 {
    let mut d4 = 0.0;
    for (m, (cm, a)) in c.iter().zip(arcs).enumerate() {
        let w2 = modal.omega[first + m] * modal.omega[first + m];
        d4 += cm.abs() * w2 * w2 * a.amplitude();
    }
    len.powi(4) / 384.0 * d4
}

/// The exact extremum of y = Σ_m c[m] q_{first+m} on the closed-form `arcs`, by Newton on
/// ẏ = 0 from `s0`, kept in [0, `len`]. Returns y at the extremum.
pub fn refine(modal: &Modal, first: usize, c: &[f64], arcs: &[Arc], len: f64, s0: f64) -> f64 {
    refine_at(modal, first, c, arcs, len, s0).1
}

/// As [`refine`], returning the position s ∈ [0, `len`] of the extremum as well: (s, y).
pub fn refine_at(
    modal: &Modal,
    first: usize,
    c: &[f64],
    arcs: &[Arc],
    len: f64,
    s0: f64,
) -> (f64, f64) {
    let eval = |s: f64| {
        let (mut y, mut yd, mut ydd) = (0.0, 0.0, 0.0);
        for (m, (a, &cm)) in arcs.iter().zip(c).enumerate() {
            if cm != 0.0 {
                let (x, v) = a.xv(s);
                y += cm * x;
                yd += cm * v;
                ydd += cm * modal.accel(first + m, x, v, a.load(s));
            }
        }
        (y, yd, ydd)
    };
    let mut s = s0.clamp(0.0, len);
    let (mut y, mut yd, mut ydd) = eval(s);
    for _ in 0..8 {
        if ydd == 0.0 {
            break;
        }
        let next = (s - yd / ydd).clamp(0.0, len);
        let step = (next - s).abs();
        if step <= 1e-13 * len {
            break;
        }
        s = next;
        (y, yd, ydd) = eval(s);
    }
    (s, y)
}
