//! Event location on the closed form: the gap function of one contact over a segment,
//! δ(s) = g·q(s) − gap, evaluated from the modal arcs ([`super::modal::Arc`]; a slow mode's
//! arc by its Taylor series, [`super::modal::SERIES_BELOW`]), for the case analysis shared
//! with the impulse method ([`crate::closure`]: Brent from the `roots` crate, the cubic
//! Hermite filter, re-arming). Sub-steps are short enough (≤ T_min/8) that δ has at most one
//! extremum per segment. The closed form bounds its derivatives, which the filters use: with
//! |q_n⁽ʲ⁾| ≤ ω_n^j·|A_n − iB_n| for the homogeneous part of an arc (its particular part is
//! linear in s), |δ⁽²ᵏ⁾| ≤ Σ|g_n|·ω_n^(2k)·|A_n − iB_n| over the window for k ≥ 1.

use crate::closure::GapCurve;

use super::impulse::ContactGeom;
use super::modal::{Arc, ArcLanes, Modal, TrigMemo};

/// Closed-form evaluation of one contact over a segment: the [`GapCurve`] of the momentum
/// method (s in seconds from the segment's start).
pub struct ModalGap<'a> {
    pub contact: &'a ContactGeom,
    pub arcs: &'a [Arc],
    pub modal: &'a Modal,
    /// Per arc: memo of its transcendental values (empty where no evaluation is needed).
    pub memo: &'a mut [TrigMemo],
    /// The arcs by field (vector evaluation) and a scratch of 2 · [`ArcLanes::padded`].
    pub lanes: &'a ArcLanes,
    pub buf: &'a mut [f64],
}

impl ModalGap<'_> {
    /// g·q(s) (or g·q̇(s) with `velocity`) over the arcs: in vectors ([`ArcLanes`]) where s
    /// is in their range, else arc by arc through the memo; the terms summed in mode order
    /// either way (the same bits).
    fn g_dot(&mut self, s: f64, velocity: bool) -> f64 {
        let np = ArcLanes::padded(self.arcs.len());
        let (xb, vb) = self.buf.split_at_mut(np);
        let g = &self.contact.g;
        let mut d = 0.0;
        if self.lanes.eval(s, xb, vb, !velocity, velocity) {
            for (g, y) in g.iter().zip(if velocity { &*vb } else { &*xb }) {
                if *g != 0.0 {
                    d += g * y;
                }
            }
            return d;
        }
        for (n, (g, a)) in g.iter().zip(self.arcs).enumerate() {
            if *g != 0.0 {
                let t = TrigMemo::get(self.arcs, self.memo, n, s);
                d += g * if velocity {
                    a.v_from(s, t)
                } else {
                    a.x_from(s, t)
                };
            }
        }
        d
    }
}

impl GapCurve for ModalGap<'_> {
    fn delta(&mut self, s: f64) -> f64 {
        self.g_dot(s, false) - self.contact.gap
    }

    fn rate(&mut self, s: f64) -> f64 {
        self.g_dot(s, true)
    }

    /// Σ|g_n|·ω_n^(2k)·|A_n − iB_n| (module docs).
    fn derivative_bound(&self, k: u32) -> Option<f64> {
        let mut sum = 0.0;
        for (n, (g, a)) in self.contact.g.iter().zip(self.arcs).enumerate() {
            let w2 = self.modal.omega[n] * self.modal.omega[n];
            let mut term = g.abs();
            for _ in 0..k {
                term *= w2;
            }
            sum += term * a.amplitude();
        }
        Some(sum)
    }
}
