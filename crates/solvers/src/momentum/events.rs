//! Event location on the closed form (Brent, `roots` crate).
//!
//! Within a segment [0, τ] the gap function δ(s) = g·q(s) − gap is known in closed form
//! ([`super::modal::Arc`]; a slow mode's arc by its Taylor series,
//! [`super::modal::SERIES_BELOW`]). Sub-steps are short enough (≤ T_min/8) that δ has at most one
//! extremum per segment, so with the end values (δ₀, δ̇₀, δ₁, δ̇₁):
//! - δ₀ < 0 ≤ δ₁: one upward crossing, Brent on δ over [0, τ] (over [s_min, τ] when δ
//!   falls first, δ̇₀ < 0 < δ̇₁: a rebound followed at once by a new approach);
//! - δ₀, δ₁ < 0 with δ̇₀ > 0 > δ̇₁: an interior maximum. A rigorous filter first: the cubic
//!   Hermite interpolant's maximum plus its error bound τ⁴/384·max|δ⁗| (with
//!   |q_n⁗| ≤ ω_n⁴·|A_n − iB_n| for the homogeneous part) — if that is < 0 nothing closes;
//!   otherwise Brent on δ̇ locates the maximum s*, and if δ(s*) ≥ 0 Brent on δ over [0, s*].
//!   For a contact just resolved the same with δ̇₁ < 0 and any δ̇₀: at rest against its floors
//!   after a plastic impulse δ̇₀ is round-off, and δ may dip before it rises; separating
//!   slowly, it may turn and come back (a minimum, then a maximum). After the cubic filter a
//!   Taylor bound, δ₀ + δ̇₀s + max|δ̈|s²/2 < 0 at both ends: nothing closes; else a point
//!   where δ̇ > 0 is looked for (the window's eighths, then halvings towards its start) and
//!   the maximum is located after it;
//! - δ₀ ≥ 0 (touching just after an impact or a release): δ̇₀ > 0 with δ₁ ≥ 0 is an
//!   immediate (zero-speed) closure (with δ₁ < 0 a round-off overlap, ignored); otherwise,
//!   with δ̇₁ > 0, the direction is read from δ̇ a moment later (2⁻²⁰ of the window, δ̇₀
//!   being round-off at rest): rising, an immediate closure; falling, the minimum is located
//!   from there and the crossing after it.
//!
//! A contact just resolved is searched at δ = `shift` (its round-off band) until its gap
//! has opened beyond −`shift`; where it opens that far and closes again within one window,
//! it is re-armed at the minimum and the closure is the crossing of δ = 0 after it (not of
//! δ = `shift`, which would be late by shift/δ̇).

use roots::{Convergency, SearchError};

use super::impulse::ContactGeom;
use super::modal::{Arc, ArcLanes, Modal, TrigMemo};

/// Where a touching contact at rest reads its direction, as a fraction of the window (2⁻²⁰):
/// its δ̇₀ is round-off, while a moment later the acceleration has long outgrown it
/// ([`Locator::locate`]).
const AT_REST_PROBE: f64 = 1.0 / 1_048_576.0;

/// Brent convergence: |Δs| below `tol`, exact zero, iteration count recorded.
pub struct Conv {
    pub tol: f64,
    pub iterations: usize,
}

impl Convergency<f64> for Conv {
    fn is_root_found(&mut self, y: f64) -> bool {
        y == 0.0
    }
    fn is_converged(&mut self, x1: f64, x2: f64) -> bool {
        (x1 - x2).abs() <= self.tol
    }
    fn is_iteration_limit_reached(&mut self, iter: usize) -> bool {
        self.iterations = self.iterations.max(iter);
        iter >= 200
    }
}

/// `roots::find_root_brent` on a pure function `f`, with its repeated evaluations answered
/// from memory: each iteration of the crate's Brent evaluates f at the new point and again
/// at the bracket end it keeps, whose value it already had. The three most recently used
/// points (the new point and both ends of the bracket before it) are remembered, so each
/// iteration costs one evaluation of f instead of two; the points and the result are the
/// crate's, bit for bit (f is pure).
pub fn find_root_brent<Func>(
    a: f64,
    b: f64,
    mut f: Func,
    convergency: &mut dyn Convergency<f64>,
) -> Result<f64, SearchError>
where
    Func: FnMut(f64) -> f64,
{
    // Most recently used first; NaN keys never match.
    let mut seen = [(f64::NAN, 0.0); 3];
    let remembered = |s: f64| {
        if let Some(k) = seen.iter().position(|e| e.0.to_bits() == s.to_bits()) {
            seen[..=k].rotate_right(1);
            return seen[0].1;
        }
        let y = f(s);
        seen.rotate_right(1);
        seen[0] = (s, y);
        y
    };
    roots::find_root_brent(a, b, remembered, convergency)
}

/// Closed-form evaluation of one contact over a segment.
pub struct Locator<'a> {
    pub contact: &'a ContactGeom,
    pub arcs: &'a [Arc],
    pub modal: &'a Modal,
    /// Window [lo, hi] of the segment searched (s from the segment start).
    pub lo: f64,
    pub hi: f64,
    /// Root tolerance in s (absolute): ~2ε·t.
    pub tol: f64,
    /// The event is δ = `shift` (m) instead of δ = 0 (a contact not yet re-armed after it
    /// was resolved: see `Stepper`).
    pub shift: f64,
    pub iterations: u64,
    /// Per arc: memo of its transcendental values (empty where no evaluation is needed).
    pub memo: &'a mut [TrigMemo],
    /// The arcs by field (vector evaluation) and a scratch of 2 · [`ArcLanes::padded`].
    pub lanes: &'a ArcLanes,
    pub buf: &'a mut [f64],
}

impl Locator<'_> {
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

    fn delta(&mut self, s: f64) -> f64 {
        self.g_dot(s, false) - self.contact.gap - self.shift
    }

    fn ddelta(&mut self, s: f64) -> f64 {
        self.g_dot(s, true)
    }

    fn brent(&mut self, a: f64, b: f64, derivative: bool) -> f64 {
        let mut conv = Conv {
            tol: self.tol,
            iterations: 0,
        };
        let r = if derivative {
            find_root_brent(a, b, |s| self.ddelta(s), &mut conv)
        } else {
            find_root_brent(a, b, |s| self.delta(s), &mut conv)
        };
        self.iterations += conv.iterations as u64 + 1;
        match r {
            Ok(s) => s.clamp(a, b),
            // No bracket (round-off at an end): the end where the function is nearer zero.
            Err(_) => {
                let mut f = |s: f64| {
                    if derivative {
                        self.ddelta(s)
                    } else {
                        self.delta(s)
                    }
                };
                if f(a).abs() <= f(b).abs() {
                    a
                } else {
                    b
                }
            }
        }
    }

    /// Σ|g_n|·ω_n^(2k)·|A_n − iB_n|: with |q_n⁽ʲ⁾| ≤ ω_n^j·|A_n − iB_n| for the homogeneous
    /// part of an arc (its particular part is linear in s), a bound on |δ⁽²ᵏ⁾| over the
    /// window for k ≥ 1 (k = 1: the acceleration; k = 2: the fourth derivative of
    /// [`Locator::max_bound`]).
    fn derivative_bound(&self, k: u32) -> f64 {
        let mut sum = 0.0;
        for (n, (g, a)) in self.contact.g.iter().zip(self.arcs).enumerate() {
            let w2 = self.modal.omega[n] * self.modal.omega[n];
            let mut term = g.abs();
            for _ in 0..k {
                term *= w2;
            }
            sum += term * a.amplitude();
        }
        sum
    }

    /// A point of (lo, tau] where δ̇ > 0 (`rising`) or δ̇ < 0, if one is found: the window's
    /// eighths, then the window halved towards lo down to the root tolerance (a contact at
    /// rest after a plastic impulse moves from its start, where the motion may last a tiny
    /// part of the window before it turns).
    fn point_where(&mut self, lo: f64, tau: f64, rising: bool) -> Option<f64> {
        let span = tau - lo;
        let sign = if rising { 1.0 } else { -1.0 };
        for j in 1..8 {
            let s = lo + span * j as f64 / 8.0;
            if sign * self.ddelta(s) > 0.0 {
                return Some(s);
            }
        }
        let mut s = lo + span / 16.0;
        while s - lo > self.tol {
            if sign * self.ddelta(s) > 0.0 {
                return Some(s);
            }
            s = lo + 0.5 * (s - lo);
        }
        None
    }

    /// Upper bound of δ over the segment from the Hermite cubic and its error bound.
    fn max_bound(&self, d0: f64, dd0: f64, d1: f64, dd1: f64) -> f64 {
        let t = self.hi - self.lo;
        let (c0, c1) = (d0, t * dd0);
        let c2 = -3.0 * d0 - 2.0 * t * dd0 + 3.0 * d1 - t * dd1;
        let c3 = 2.0 * d0 + t * dd0 - 2.0 * d1 + t * dd1;
        let p = |u: f64| c0 + u * (c1 + u * (c2 + u * c3));
        let mut m = d0.max(d1);
        // roots of p'(u) = c1 + 2c2 u + 3c3 u²
        let (qa, qb, qc) = (3.0 * c3, 2.0 * c2, c1);
        let mut cands = vec![];
        if qa.abs() < 1e-300 {
            if qb != 0.0 {
                cands.push(-qc / qb);
            }
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                cands.push((-qb + sq) / (2.0 * qa));
                cands.push((-qb - sq) / (2.0 * qa));
            }
        }
        for u in cands {
            if (0.0..=1.0).contains(&u) {
                m = m.max(p(u));
            }
        }
        let d4 = self.derivative_bound(2);
        m + t.powi(4) / 384.0 * d4 * (1.0 + 1e-6) + 1e-15 * (d0.abs() + d1.abs())
    }

    /// The first closure instant s in [lo, hi], if any (see module docs); the arguments
    /// are δ, δ̇ at lo and hi.
    pub fn locate(&mut self, d0: f64, dd0: f64, d1: f64, dd1: f64) -> Option<f64> {
        let (lo, tau) = (self.lo, self.hi);
        if self.shift > 0.0 && dd0 < 0.0 && dd1 > 0.0 && d1 + self.shift >= 0.0 {
            // A contact not yet re-armed (searched at δ = shift) that falls and rises again
            // within the window to δ ≥ 0: if its gap opened beyond −shift at the minimum, it
            // is re-armed there and the closure is the crossing of δ = 0 after it.
            let s_min = self.brent(lo, tau, true);
            if self.delta(s_min) + self.shift < -self.shift {
                self.shift = 0.0;
                return Some(self.brent(s_min, tau, false));
            }
        }
        if d0 >= 0.0 {
            if dd0 > 0.0 {
                // Touching and approaching: a real closure only if δ is still ≥ 0 at the
                // window end; otherwise it is a round-off-sized overlap (velocity residue of
                // a plastic impulse or a release) that reopens at once.
                return if d1 >= 0.0 { Some(lo) } else { None };
            }
            if dd1 <= 0.0 {
                return None;
            }
            // Touching and at rest (δ̇₀ ≤ 0 is round-off after a plastic impulse, and its value
            // from the arcs may differ in sign from `dd0`, the state's): whether δ rises or
            // falls from here is the sign of δ̇ a moment later (2⁻²⁰ of the window, where the
            // acceleration has long outgrown the round-off). Rising: an immediate closure;
            // falling: the minimum is bracketed from there. Bracketed from the start, Brent had
            // no bracket when the arcs' δ̇₀ was +round-off and fell back to the start, a
            // zero-length closure found again and again at one state under a separating
            // acceleration (random seed 3927: δ̇₀ = ±2.8e-17 m/s, −0.53 m/s²; `Stalled`).
            let start = lo + (tau - lo) * AT_REST_PROBE;
            if self.ddelta(start) >= 0.0 {
                return Some(lo);
            }
            let s_min = self.brent(start, tau, true);
            if self.delta(s_min) >= 0.0 {
                return Some(s_min);
            }
            if d1 >= 0.0 {
                return Some(self.brent(s_min, tau, false));
            }
            return None;
        }
        if d1 >= 0.0 {
            // Falling first (just after a rebound, under a strong push): the crossing is
            // after the minimum, not at the start where δ is round-off below zero.
            if dd0 < 0.0 && dd1 > 0.0 {
                let s_min = self.brent(lo, tau, true);
                return Some(self.brent(s_min, tau, false));
            }
            return Some(self.brent(lo, tau, false));
        }
        // A contact just resolved (searched at δ = shift) may close again within the window
        // while δ̇ < 0 at both its ends: at rest against its floors after a plastic impulse,
        // its δ̇₀ is round-off of either sign and a compressive relative acceleration takes δ
        // up at once (or after a dip); separating slowly after an impact, it may fall, turn
        // and come back. Either way δ has a minimum and then a maximum inside the window (two
        // extrema). Looked for only when δ̇₀ > 0 and from the window's start, such re-closures
        // were missed (random seeds 574 and 3582: after a plastic impact with δ̇₀ = ∓4e-17 m/s
        // the floors, pressed together by 1.3e5 N, overlapped for 0.5 ms where the impulse
        // method holds them; seed 1828 lost an impact).
        let resolved = self.shift > 0.0;
        if (dd0 > 0.0 || resolved) && dd1 < 0.0 {
            if self.max_bound(d0, dd0, d1, dd1) < 0.0 {
                return None;
            }
            let start = if !resolved {
                lo
            } else {
                // Taylor: δ(lo + s) ≤ δ₀ + δ̇₀ s + A s²/2 with A ≥ |δ̈| over the window, a convex
                // bound whose maximum is at an end: below zero at both, nothing closes (a
                // contact separating after an elastic impact: the common case, no evaluation).
                let span = tau - lo;
                let a = self.derivative_bound(1) * (1.0 + 1e-6);
                if d0.max(d0 + span * (dd0 + 0.5 * a * span)) < 0.0 {
                    return None;
                }
                self.point_where(lo, tau, true)?
            };
            let s_max = self.brent(start, tau, true);
            if resolved && dd0 < 0.0 {
                // Fell first: if the gap opened beyond −shift at the minimum, the contact is
                // re-armed there and the closure is the crossing of δ = 0 after it (as in the
                // first case above).
                let s_min = self.brent(lo, start, true);
                if self.delta(s_min) + self.shift < -self.shift {
                    self.shift = 0.0;
                    return (self.delta(s_max) >= 0.0).then(|| self.brent(s_min, s_max, false));
                }
            }
            if self.delta(s_max) >= 0.0 {
                return Some(self.brent(lo, s_max, false));
            }
        }
        None
    }

    /// Whether the cheap tests alone prove that nothing closes (used by the fast path).
    pub fn surely_open(&self, d0: f64, dd0: f64, d1: f64, dd1: f64) -> bool {
        if d0 >= 0.0 || d1 >= 0.0 {
            return false;
        }
        if dd0 > 0.0 && dd1 < 0.0 {
            return self.max_bound(d0, dd0, d1, dd1) < 0.0;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The memoised Brent returns the crate's root bit for bit, with at most one evaluation per
    /// iteration (plus the two ends) instead of two.
    #[test]
    fn memoised_brent_is_the_crates_with_fewer_evaluations() {
        let fs: [fn(f64) -> f64; 3] = [
            |s| (7.3 * s).sin() - 0.3,
            |s| s * s * s - 2.0 * s - 5.0,
            |s| (-3.0 * s).exp() * (11.0 * s).cos() - 0.01,
        ];
        for (f, (a, b)) in fs.into_iter().zip([(0.0, 0.2), (2.0, 3.0), (0.0, 0.25)]) {
            let tol = 2.0 * f64::EPSILON;
            let (mut n_crate, mut n_memo) = (0, 0);
            let mut c1 = Conv { tol, iterations: 0 };
            let r1 = roots::find_root_brent(
                a,
                b,
                |s| {
                    n_crate += 1;
                    f(s)
                },
                &mut c1,
            )
            .unwrap();
            let mut c2 = Conv { tol, iterations: 0 };
            let r2 = find_root_brent(
                a,
                b,
                |s| {
                    n_memo += 1;
                    f(s)
                },
                &mut c2,
            )
            .unwrap();
            assert_eq!(r1.to_bits(), r2.to_bits());
            assert_eq!(c1.iterations, c2.iterations);
            assert!(c1.iterations >= 3, "{}", c1.iterations);
            // At most one evaluation per iteration (a new point equal to a remembered one, as
            // at convergence, costs none).
            assert!(
                n_memo <= c2.iterations + 2,
                "{n_memo} > {} + 2",
                c2.iterations
            );
            assert_eq!(n_crate, 2 * c1.iterations + 2);
        }
    }
}
