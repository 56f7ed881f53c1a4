//! Continuous peaks between samples (issue 10): the momentum method knows every mode in
//! closed form between events, so a peak of a response quantity y(t) = Σ_n c_n q_n(t) (a
//! floor displacement, c_n = φ_n[i]; a story shear, c_n = k_j (φ_n[j] − φ_n[j−1])) that falls
//! between two samples is found exactly rather than sampled.
//!
//! At each sample the solver knows y and ẏ (ẏ = Σ c_n q̇_n) at both ends of the interval just
//! integrated. A sign change of ẏ means an interior extremum (intervals are at most one
//! record step, shorter than the shortest periods that matter: at most one extremum of the
//! quantity). Its value is estimated by the cubic Hermite interpolant of (y, ẏ) at the ends;
//! when that estimate could raise the running peak (it is within 5 % of it or above), the
//! extremum is located by Newton's method on ẏ(s) = 0 with ÿ from the equations of motion
//! (q̈ = f − 2ζωq̇ − ω²q), started at the Hermite estimate, on the closed form, to a
//! relative step of 1e-13, and its exact value replaces the peak if larger.

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

/// The exact extremum of y = Σ_m c[m] q_{n_m} over `iv` (modes `range` of one building,
/// `c` indexed from the building's first mode), by Newton on ẏ = 0 from `s0`, kept in
/// [0, `len`]. Returns y at the extremum.
pub fn refine(
    modal: &Modal,
    range: std::ops::Range<usize>,
    c: &[f64],
    iv: &Interval,
    len: f64,
    s0: f64,
) -> f64 {
    let arcs: Vec<Arc> = range
        .clone()
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
        .collect();
    let eval = |s: f64| {
        let (mut y, mut yd, mut ydd) = (0.0, 0.0, 0.0);
        for ((a, &cm), n) in arcs.iter().zip(c).zip(range.clone()) {
            if cm != 0.0 {
                let (x, v) = a.xv(s);
                y += cm * x;
                yd += cm * v;
                ydd += cm * modal.accel(n, x, v, a.load(s));
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
        s = next;
        (y, yd, ydd) = eval(s);
        if step <= 1e-13 * len {
            break;
        }
    }
    y
}
