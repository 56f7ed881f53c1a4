//! Contact audit (opt-in: [`super::solve_audited`]): do open contacts stay open?
//!
//! The closure search ([`crate::closure`]) decides from a contact's gap function at a few
//! points per window which windows can hold a closure; a wrong decision lets two floors pass
//! through each other unnoticed (defects 6 and 7 of docs/solvers.md did, for up to 0.5 ms).
//! The audit checks every integrated interval independently of that search: it rebuilds the
//! closed-form arcs of the interval ([`super::peaks::arcs`]: the same exact solution, a
//! separate evaluation) and samples the gap function of every contact that is not held,
//!
//! ```text
//! δ_c(s) = g_c·q(s) − gap_c      at s = τ k / K, k = 1 … K (K = AUDIT_SAMPLES),
//! ```
//!
//! τ the length integrated. Wherever the search is right, δ_c stays at most 2·`pen_c`:
//! `pen_c` = 1e-10·max(gap, 1 mm) m ([`crate::closure::band`]) is the round-off band in
//! which a contact just resolved is searched (its closure is located at δ = 0, or at
//! δ = pen until it is re-armed), and a touching contact that rises less than one more band
//! before it falls back is taken for a round-off overlap, not a closure. The audit reports the largest δ_c / pen_c over the run
//! with its contact and instant: above 2 (beyond round-off) a closure was missed, and the
//! excess times pen is how far the floors went through each other at a sample. Sampled, not continuous: an overlap shorter than τ/K can pass between
//! the samples. It costs K evaluations of every arc per interval (an audited analysis of the
//! paper scene took 55–61 times a plain one, two timings of five runs each), so it is off in
//! normal runs (one untaken branch per interval).

use super::peaks;
use super::stepper::Stepper;

/// Samples per interval.
pub const AUDIT_SAMPLES: usize = 32;

/// The audit's findings.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ContactAudit {
    /// Intervals audited.
    pub intervals: u64,
    /// Largest δ / pen of an open contact at the samples (−∞ if no contact was sampled),
    /// its contact and instant, s.
    pub worst: f64,
    pub contact: usize,
    pub time: f64,
}

impl ContactAudit {
    pub fn new() -> Self {
        ContactAudit {
            worst: f64::NEG_INFINITY,
            ..Default::default()
        }
    }
}

impl Stepper<'_> {
    /// Audits the interval just integrated (see module docs).
    #[cold]
    #[inline(never)]
    pub(super) fn audit_interval(&mut self) {
        let iv = &self.interval;
        let len = iv.tau_done;
        if len <= 0.0 {
            return;
        }
        let p = self.p;
        let arcs = peaks::arcs(&p.modal, 0..p.modal.len(), iv);
        let t0 = self.s.t - len;
        let Some(audit) = self.audit.as_mut() else {
            return;
        };
        audit.intervals += 1;
        let mut x = vec![0.0; arcs.len()];
        for k in 1..=AUDIT_SAMPLES {
            let s = len * k as f64 / AUDIT_SAMPLES as f64;
            for (x, a) in x.iter_mut().zip(&arcs) {
                *x = a.xv(s).0;
            }
            for (c, ct) in p.contacts.iter().enumerate() {
                if self.s.persistent.iter().any(|&(h, _)| h == c) {
                    continue;
                }
                let r = ct.delta(&x) / self.pen[c];
                if r > audit.worst {
                    (audit.worst, audit.contact, audit.time) = (r, c, t0 + s);
                }
            }
        }
    }
}
