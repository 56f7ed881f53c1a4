//! Continuous peaks between samples (issue 10): the momentum method knows every mode in
//! closed form between events (a slow mode by its Taylor series,
//! [`super::modal::SERIES_BELOW`]), so a peak of a response quantity y(t) = Σ_n c_n q_n(t) (a
//! floor displacement, c_n = φ_n\[i\]; a story shear, c_n = k_j (φ_n\[j\] − φ_n\[j−1\])) that falls
//! between two samples is found exactly rather than sampled.
//!
//! At each sample the solver knows y and ẏ (ẏ = Σ c_n q̇_n) at both ends of the interval just
//! integrated. A sign change of ẏ means an interior extremum (intervals are at most one
//! base step, at most a quarter of the shortest kept period since record steps longer than
//! that are split ([`super::problem::STEPS_PER_PERIOD`]): at most one extremum of the
//! quantity). Its value is estimated by the cubic Hermite interpolant H of (y, ẏ) at the
//! ends; when that estimate could raise the running peak (|H| ≥ 0.9 × peak and |H| plus the
//! bound len⁴/384 · Σ|c_n| ω_n⁴ |A_n − iB_n| on |y − H| reaches the peak), the
//! extremum is located by Newton's method on ẏ(s) = 0 with ÿ from the equations of motion
//! (q̈ = f − 2ζωq̇ − ω²q), started at the Hermite estimate, on the closed form, to a
//! relative step of 1e-13, and its exact value replaces the peak if larger.
//!
//! The overlap audit ([`crate::overlap`]) uses the same machinery for the signed maxima of
//! u_left\[i\] − u_right\[j\], whose coefficients c_n = φ_n\[i\] on the left building's modes and
//! −φ_n\[j\] on the right building's span both buildings (`first` = 0, all modes).

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
    /// Modal loads of held contacts (persistent phase), if any: per mode at the start, then
    /// per mode at `tau` (linear in time in between).
    pub fc: Option<Vec<f64>>,
    /// Length actually integrated (≤ `tau`: an event may end the interval early), s.
    pub tau_done: f64,
}

pub use crate::response::hermite_extremum;

/// A necessary condition of [`turns_twice`], cheaper, in rates (`inv_len` = 1/len): with
/// D = (ẏ0 + ẏ1)/2 − (y1 − y0)/len, H′(θ)/len = (1 − θ) ẏ0 + θ ẏ1 − 6Dθ(1 − θ), so a dip of
/// H′ to the other sign than its ends needs D of their sign and 1.5|D| > min(|ẏ0|, |ẏ1|)
/// (θ(1 − θ) ≤ 1/4). The scalar form of the test in `observe::sample`, the same operations:
/// the sample's vectors and its scalar tail decide alike, on every instruction set.
#[inline(always)]
pub fn may_turn_twice(y0: f64, yd0: f64, y1: f64, yd1: f64, inv_len: f64) -> bool {
    let dd = 0.5 * (yd0 + yd1) - (y1 - y0) * inv_len;
    0.0 < dd * yd0 && yd0.abs().min(yd1.abs()) < 1.5 * dd.abs()
}

/// Whether the cubic Hermite interpolant of (y0, ẏ0, y1, ẏ1) over `len` turns twice inside
/// the interval: its derivative m0 + 2c2θ + 3c3θ² (m = ẏ len, Δ = y1 − y0, c2 = 3Δ − 2m0 − m1,
/// c3 = m0 + m1 − 2Δ) has its vertex in (0, 1), where it has the other sign than m0 (and so
/// than m1 too, the rates then of one sign). The scalar form of the test in
/// `observe::sample`, the same operations.
#[inline(always)]
pub fn turns_twice(y0: f64, yd0: f64, y1: f64, yd1: f64, len: f64) -> bool {
    let dy = y1 - y0;
    let (m0, m1) = (yd0 * len, yd1 * len);
    let c2 = 3.0 * dy - 2.0 * m0 - m1;
    let c3 = m0 + m1 - 2.0 * dy;
    let m0c3 = m0 * c3;
    0.0 < m0c3 && m0 * c2 < 0.0 && c2.abs() < 3.0 * c3.abs() && 3.0 * m0c3 < c2 * c2
}

/// The estimate of an interior extremum of a quantity whose rate has one sign at both ends
/// of the interval (ẏ0 ẏ1 ≥ 0), flagged because it may turn twice inside near its peak
/// (`observe::sample`): from the cubic Hermite interpolant H of (y0, ẏ0, y1, ẏ1) over
/// `len`, whose derivative is then either of one sign on [0, 1] or has two roots there.
/// With two, the one of larger |H|, as (θ, H(θ)) (θ ∈ (0, 1), the fraction of `len`);
/// with none (H monotone, the turns if any hidden in its error), the point where |H′| is
/// least and the end value of larger |y|, a start for Newton's method that cannot raise
/// the peak by itself.
pub fn double_turn_estimate(y0: f64, yd0: f64, y1: f64, yd1: f64, len: f64) -> (f64, f64) {
    let end = if y0.abs() >= y1.abs() { y0 } else { y1 };
    double_turn_pick(y0, yd0, y1, yd1, len, |h, best| h.abs() > best.abs(), end)
}

/// As [`double_turn_estimate`] for a signed maximum (the overlap audit's u_left − u_right,
/// flagged in `observe::OverlapPass`): with two critical points inside, the one of larger
/// H, which is the cubic's local maximum (H falls from its local maximum to its local
/// minimum between them, or rises from the minimum to the maximum); with none, the point
/// where |H′| is least and the larger end value, which cannot raise the maximum by itself.
pub fn double_turn_maximum(y0: f64, yd0: f64, y1: f64, yd1: f64, len: f64) -> (f64, f64) {
    double_turn_pick(y0, yd0, y1, yd1, len, |h, best| h > best, y0.max(y1))
}

/// The critical point θ ∈ (0, 1) of the cubic Hermite interpolant H of (y0, ẏ0, y1, ẏ1) over
/// `len` whose value `better` prefers (`better(h, best)`: h replaces best), as (θ, H(θ));
/// with none, (θ where |H′| is least, `end`).
#[inline(always)]
fn double_turn_pick(
    y0: f64,
    yd0: f64,
    y1: f64,
    yd1: f64,
    len: f64,
    better: impl Fn(f64, f64) -> bool,
    end: f64,
) -> (f64, f64) {
    let [c1, c2, c3] = crate::response::hermite_cubic(y0, yd0, y1, yd1, len);
    let h = |t: f64| y0 + t * (c1 + t * (c2 + t * c3));
    // H′(θ) = a θ² + b θ + c.
    let (a, b, c) = (3.0 * c3, 2.0 * c2, c1);
    let mut best: Option<(f64, f64)> = None;
    let disc = b * b - 4.0 * a * c;
    if a != 0.0 && disc > 0.0 {
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        for t in [q / a, if q != 0.0 { c / q } else { f64::NAN }] {
            if t > 0.0 && t < 1.0 && best.is_none_or(|(_, v)| better(h(t), v)) {
                best = Some((t, h(t)));
            }
        }
    }
    best.unwrap_or_else(|| {
        let tv = if a != 0.0 {
            (-b / (2.0 * a)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (tv, end)
    })
}

/// The closed-form arcs of the modes `range` over the interval `iv`.
pub fn arcs(modal: &Modal, range: std::ops::Range<usize>, iv: &Interval) -> Vec<Arc> {
    arcs_of(
        modal,
        range,
        &iv.x0,
        &iv.v0,
        iv.fc.as_deref(),
        iv.a0,
        iv.a1,
        iv.tau,
    )
}

/// The closed-form arcs of the modes `range` from the state (`x0`, `v0`) under the ground
/// acceleration a0 → a1 over `tau` plus the held-contact loads `fc` (per mode at the start,
/// then at `tau`; see [`Interval::fc`]).
#[allow(clippy::too_many_arguments)]
pub fn arcs_of(
    modal: &Modal,
    range: std::ops::Range<usize>,
    x0: &[f64],
    v0: &[f64],
    fc: Option<&[f64]>,
    a0: f64,
    a1: f64,
    tau: f64,
) -> Vec<Arc> {
    let nm = modal.len();
    range
        .map(|n| {
            let (f0, f1) = (-modal.gamma[n] * a0, -modal.gamma[n] * a1);
            match fc {
                None => modal.arc(n, x0[n], v0[n], f0, f1, tau),
                Some(f) => modal.held_arc(n, x0[n], v0[n], f0 + f[n], f1 + f[nm + n], tau),
            }
        })
        .collect()
}

/// The response quantity a deferred candidate may raise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// |u_i| of building `building`, floor index `floor`.
    Displacement { building: usize, floor: usize },
    /// |k_j (u_j − u_{j−1})| of building `building`, story index `story`.
    Shear { building: usize, story: usize },
    /// u_left − u_right of overlap pair `pair` (signed maximum).
    Overlap { pair: usize },
}

/// An interior extremum whose exact value may exceed the running peak, kept for the end
/// of the run: the Hermite estimate h at s0 and the rigorous upper bound |h| + |y − H|max.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    pub target: Target,
    /// Index of the stored interval ([`Deferred::interval`]).
    pub interval: usize,
    /// Start point of Newton's method, s from the interval start.
    pub s0: f64,
    /// Upper bound of the extremum's value (|y| for peaks, y for overlaps).
    pub upper: f64,
}

/// Deferred refinement (the cost of refining falls from every extremum that raises a
/// running peak to the few that can be the final one): during the run, a candidate that
/// passes the filters raises a running lower bound |h| − bound of its quantity's peak (used
/// by the filters only) and is stored with its upper bound |h| + bound; at the end,
/// candidates are refined in decreasing order of their upper bound, skipping those whose
/// upper bound is below the exact peak so far. The final peaks are the maxima of the same
/// exact values as refining at once would give.
#[derive(Debug, Clone, Default)]
pub struct Deferred {
    nm: usize,
    /// Per stored interval: x0 then v0, `nm` each, in blocks of [`STATE_BLOCK`] intervals
    /// (a full block is kept as it is and a new one begun: no reallocation copies them).
    state: Vec<Vec<f64>>,
    /// Held-contact loads of the stored intervals that have some, 2 `nm` each (start, end).
    fc: Vec<f64>,
    /// Per stored interval: (a0, a1, tau, integrated length, sample time at its end, offset
    /// of its held-contact loads in `fc` if held).
    meta: Vec<(f64, f64, f64, f64, f64, Option<usize>)>,
    pub candidates: Vec<Candidate>,
}

/// A stored interval, as given back by [`Deferred::interval`].
pub struct StoredInterval<'a> {
    pub x0: &'a [f64],
    pub v0: &'a [f64],
    pub fc: Option<&'a [f64]>,
    pub a0: f64,
    pub a1: f64,
    pub tau: f64,
    /// Length integrated (the interval ends at `t_end`), s.
    pub len: f64,
    pub t_end: f64,
}

/// Stored intervals per block of [`Deferred`]'s states (the paper scene stores about 650).
const STATE_BLOCK: usize = 256;

impl Deferred {
    pub fn new(nm: usize) -> Self {
        Deferred {
            nm,
            state: vec![Vec::with_capacity(2 * STATE_BLOCK * nm)],
            ..Default::default()
        }
    }

    /// Stores the interval `iv` (integrated up to the sample at `t_end`); returns its index.
    pub fn store(&mut self, iv: &Interval, t_end: f64) -> usize {
        let nm = self.nm;
        if self.meta.len() == self.state.len() * STATE_BLOCK {
            // Every block is full.
            self.state.push(Vec::with_capacity(2 * STATE_BLOCK * nm));
        }
        let block = self.state.last_mut().expect("a block");
        block.extend_from_slice(&iv.x0[..nm]);
        block.extend_from_slice(&iv.v0[..nm]);
        let held = iv.fc.as_ref().map(|f| {
            self.fc.extend_from_slice(&f[..2 * nm]);
            self.fc.len() - 2 * nm
        });
        self.meta
            .push((iv.a0, iv.a1, iv.tau, iv.tau_done, t_end, held));
        self.meta.len() - 1
    }

    /// The stored interval `k`.
    pub fn interval(&self, k: usize) -> StoredInterval<'_> {
        let nm = self.nm;
        let (a0, a1, tau, len, t_end, held) = self.meta[k];
        let j = k % STATE_BLOCK;
        let (x0, v0) = self.state[k / STATE_BLOCK][2 * j * nm..2 * (j + 1) * nm].split_at(nm);
        StoredInterval {
            x0,
            v0,
            fc: held.map(|o| &self.fc[o..o + 2 * nm]),
            a0,
            a1,
            tau,
            len,
            t_end,
        }
    }

    /// Candidates in the order they are to be refined: decreasing upper bound (stable, so
    /// chronological among equal bounds).
    pub fn order(&self) -> Vec<usize> {
        self.order_where(|_| true)
    }

    /// [`Deferred::order`] of the candidates that `keep` accepts (the same relative order).
    pub fn order_where(&self, keep: impl Fn(&Candidate) -> bool) -> Vec<usize> {
        // Sorted by (key descending, index ascending), the key ordered as `f64::total_cmp`
        // orders the bounds: the permutation of the stable sort by decreasing bound.
        let mut o: Vec<(i64, usize)> = (self.candidates.iter().enumerate())
            .filter(|(_, c)| keep(c))
            .map(|(k, c)| {
                let bits = c.upper.to_bits() as i64;
                (!(bits ^ (((bits >> 63) as u64) >> 1) as i64), k)
            })
            .collect();
        o.sort_unstable();
        o.into_iter().map(|(_, k)| k).collect()
    }
}

/// Per-mode constants of [`amplitudes`]: 1/ω², ζω, 1/ω_d.
pub fn amplitude_constants(modal: &Modal) -> Vec<[f64; 3]> {
    (0..modal.len())
        .map(|n| {
            let (omega, zeta) = (modal.omega[n], modal.zeta[n]);
            [
                1.0 / (omega * omega),
                zeta * omega,
                1.0 / (omega * (1.0 - zeta * zeta).sqrt()),
            ]
        })
        .collect()
}

/// The homogeneous amplitudes |A_n − iB_n| of the modes `range` over the interval `iv` into
/// `out[range]` ([`Arc::amplitude`] without the arcs; `k` from [`amplitude_constants`]):
/// A = q₀ − α, B = (q̇₀ − β + ζωA)/ω_d with β = (f₁ − f₀)/(τω²), α = (f₀ − 2ζωβ)/ω². The
/// products by reciprocals round differently from the arcs' divisions: these amplitudes
/// feed error bounds only. In the widest instruction set of `arch` (exact operations
/// only, the same bits on every machine).
pub fn amplitudes(
    arch: pulp::Arch,
    modal: &Modal,
    k: &[[f64; 3]],
    range: std::ops::Range<usize>,
    iv: &Interval,
    out: &mut [f64],
) {
    struct Op<'x> {
        modal: &'x Modal,
        k: &'x [[f64; 3]],
        range: std::ops::Range<usize>,
        iv: &'x Interval,
        out: &'x mut [f64],
    }
    impl pulp::WithSimd for Op<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _: S) {
            amplitudes_in(self.modal, self.k, self.range, self.iv, self.out)
        }
    }
    arch.dispatch(Op {
        modal,
        k,
        range,
        iv,
        out,
    })
}

/// [`amplitudes`], inlined into the instruction set of its caller.
#[inline(always)]
fn amplitudes_in(
    modal: &Modal,
    k: &[[f64; 3]],
    range: std::ops::Range<usize>,
    iv: &Interval,
    out: &mut [f64],
) {
    let r = range;
    let (gamma, k, out) = (&modal.gamma[r.clone()], &k[r.clone()], &mut out[r.clone()]);
    let (x0, v0) = (&iv.x0[r.clone()], &iv.v0[r.clone()]);
    let nm = modal.len();
    match iv.fc.as_deref() {
        Some(f) => amplitudes_of(
            gamma,
            k,
            x0,
            v0,
            |n| (f[r.start + n], f[nm + r.start + n]),
            iv,
            out,
        ),
        None => amplitudes_of(gamma, k, x0, v0, |_| (0.0, 0.0), iv, out),
    }
}

/// [`amplitudes`] over slices of the same modes (`extra(n)`: the held-contact load at the
/// start and at the end).
#[inline(always)]
fn amplitudes_of(
    gamma: &[f64],
    k: &[[f64; 3]],
    x0: &[f64],
    v0: &[f64],
    extra: impl Fn(usize) -> (f64, f64),
    iv: &Interval,
    out: &mut [f64],
) {
    let inv_tau = 1.0 / iv.tau;
    let nm = out.len();
    let (gamma, k, x0, v0) = (&gamma[..nm], &k[..nm], &x0[..nm], &v0[..nm]);
    for n in 0..nm {
        let (e0, e1) = extra(n);
        let (f0, f1) = (-gamma[n] * iv.a0 + e0, -gamma[n] * iv.a1 + e1);
        let [inv_w2, c, inv_d] = k[n];
        let beta = (f1 - f0) * inv_tau * inv_w2;
        let alpha = (f0 - 2.0 * c * beta) * inv_w2;
        let a = x0[n] - alpha;
        let b = (v0[n] - beta + c * a) * inv_d;
        out[n] = (a * a + b * b).sqrt();
    }
}

/// Bound on |y − H| over an interval of length `len`, H the cubic Hermite interpolant of
/// y = Σ c_m q_{first+m}: len⁴/384 · max|y⁗| with |q_m⁗| ≤ ω_m⁴ |A_m − iB_m| (the
/// homogeneous part, amplitudes `amp` of all modes from [`amplitudes`]; the particular
/// part is linear in time).
pub fn hermite_error_bound(modal: &Modal, first: usize, c: &[f64], amp: &[f64], len: f64) -> f64 {
    let n = c.len().min(amp.len() - first);
    let (c, amp, omega) = (
        &c[..n],
        &amp[first..first + n],
        &modal.omega[first..first + n],
    );
    let term = |cm: f64, a: f64, w: f64| {
        let w2 = w * w;
        cm.abs() * w2 * w2 * a
    };
    // The terms four at a time (independent: they vectorise), summed in mode order.
    let mut d4 = 0.0;
    let n4 = n / 4 * 4;
    for ((c4, a4), w4) in (c[..n4].chunks_exact(4))
        .zip(amp[..n4].chunks_exact(4))
        .zip(omega[..n4].chunks_exact(4))
    {
        let t: [f64; 4] = std::array::from_fn(|k| term(c4[k], a4[k], w4[k]));
        d4 += t[0];
        d4 += t[1];
        d4 += t[2];
        d4 += t[3];
    }
    for ((&cm, &a), &w) in c[n4..].iter().zip(&amp[n4..]).zip(&omega[n4..]) {
        d4 += term(cm, a, w);
    }
    len.powi(4) / 384.0 * d4
}

/// The exact extremum of y = Σ_m c\[m\] q_{first+m} on the `arcs` (closed form or series), by Newton on
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
    let na = arcs.len().min(c.len());
    let eval = |s: f64| {
        let (mut y, mut yd, mut ydd) = (0.0, 0.0, 0.0);
        // The transcendental values four arcs at a time (the same bits as `Arc::trig`).
        for m0 in (0..na).step_by(4) {
            let idx: [usize; 4] = std::array::from_fn(|k| (m0 + k).min(na - 1));
            let t = Arc::trig4(&idx.map(|i| arcs[i]), s);
            for (k, &tk) in t.iter().enumerate().take(na - m0) {
                let (m, a, cm) = (m0 + k, &arcs[m0 + k], c[m0 + k]);
                if cm != 0.0 {
                    let (x, v) = a.xv_from(s, tk);
                    y += cm * x;
                    yd += cm * v;
                    ydd += cm * modal.accel(first + m, x, v, a.load(s));
                }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The double-turn estimate is exact on a cubic: y = θ³ − 1.2 θ² + 0.4 θ over len 1 rises
    /// at both ends (ẏ = 0.4 and 1.0) and turns twice inside, a maximum 0.0407 at
    /// θ = (1.2 − √0.24)/3 and a minimum 0.0233 at (1.2 + √0.24)/3: the estimate is the
    /// critical point of larger |H|, the maximum, the same over len 2 with the rates halved.
    /// A monotone cubic (y = θ³ + θ) gives the end of larger |y| and θ where the slope is
    /// least (0).
    #[test]
    fn double_turn_estimates_are_the_cubics_critical_points() {
        let y = |t: f64| t * t * t - 1.2 * t * t + 0.4 * t;
        let (t1, t2) = ((1.2 - 0.24f64.sqrt()) / 3.0, (1.2 + 0.24f64.sqrt()) / 3.0);
        let want = if y(t1).abs() >= y(t2).abs() { t1 } else { t2 };
        let (th, h) = double_turn_estimate(y(0.0), 0.4, y(1.0), 1.0, 1.0);
        assert!((th - want).abs() < 1e-12, "{th} vs {want}");
        assert!((h - y(want)).abs() < 1e-14, "{h}");
        // Over len 2 the rates are per unit time: the same shape.
        let (th2, h2) = double_turn_estimate(y(0.0), 0.2, y(1.0), 0.5, 2.0);
        assert!((th2 - th).abs() < 1e-12 && (h2 - h).abs() < 1e-14);
        // Monotone: y = θ³ + θ (ẏ = 1 at 0, 4 at 1).
        let (th, h) = double_turn_estimate(0.0, 1.0, 2.0, 4.0, 1.0);
        assert_eq!((th, h), (0.0, 2.0));
    }

    /// The signed maximum is the cubic's local maximum, not the critical point of larger
    /// |H|: y = θ³ − 1.2 θ² + 0.4 θ − 0.05 has its maximum −0.0093 at θ = (1.2 − √0.24)/3 and
    /// its minimum −0.0267 at (1.2 + √0.24)/3 (larger in size, the estimate's pick); a
    /// monotone cubic gives the larger end value.
    #[test]
    fn double_turn_maximum_is_the_cubics_local_maximum() {
        let y = |t: f64| t * t * t - 1.2 * t * t + 0.4 * t - 0.05;
        let (t1, t2) = ((1.2 - 0.24f64.sqrt()) / 3.0, (1.2 + 0.24f64.sqrt()) / 3.0);
        let (th, h) = double_turn_maximum(y(0.0), 0.4, y(1.0), 1.0, 1.0);
        assert!((th - t1).abs() < 1e-12, "{th} vs {t1}");
        assert!((h - y(t1)).abs() < 1e-14 && h < 0.0, "{h}");
        assert!((double_turn_estimate(y(0.0), 0.4, y(1.0), 1.0, 1.0).0 - t2).abs() < 1e-12);
        // Falling at both ends (ẏ = −0.4 and −1.0), −y: its maximum is at y's minimum.
        let (th, h) = double_turn_maximum(-y(0.0), -0.4, -y(1.0), -1.0, 1.0);
        assert!(
            (th - t2).abs() < 1e-12 && (h + y(t2)).abs() < 1e-14,
            "{th} {h}"
        );
        // Monotone: y = θ³ + θ − 3 (ẏ = 1 at 0, 4 at 1): the larger end, −1.
        assert_eq!(double_turn_maximum(-3.0, 1.0, -1.0, 4.0, 1.0), (0.0, -1.0));
    }

    /// Stored intervals come back as stored, across the blocks of `Deferred::state` (a
    /// `Deferred::new` one and a default one, held-contact loads on some).
    #[test]
    fn stored_intervals_come_back_across_blocks() {
        let nm = 3;
        let iv = |k: usize| Interval {
            x0: (0..nm).map(|n| (k * 10 + n) as f64).collect(),
            v0: (0..nm).map(|n| -((k * 10 + n) as f64)).collect(),
            a0: k as f64,
            a1: 2.0 * k as f64,
            tau: 0.5,
            fc: k
                .is_multiple_of(3)
                .then(|| (0..2 * nm).map(|n| k as f64 + 0.25 * n as f64).collect()),
            tau_done: 0.25,
        };
        let n = 2 * STATE_BLOCK + 7;
        for mut d in [
            Deferred::new(nm),
            Deferred {
                nm,
                ..Default::default()
            },
        ] {
            for k in 0..n {
                assert_eq!(d.store(&iv(k), k as f64 + 1.0), k);
            }
            for k in 0..n {
                let (want, got) = (iv(k), d.interval(k));
                assert_eq!(got.x0, &want.x0[..]);
                assert_eq!(got.v0, &want.v0[..]);
                assert_eq!(got.fc, want.fc.as_deref());
                assert_eq!((got.a0, got.a1, got.tau), (want.a0, want.a1, want.tau));
                assert_eq!((got.len, got.t_end), (0.25, k as f64 + 1.0));
            }
        }
    }

    /// `Deferred::order` is the stable sort by decreasing upper bound under `total_cmp`.
    #[test]
    fn order_is_the_stable_sort() {
        let mut d = Deferred::new(1);
        let mut x = 12345u64;
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for k in 0..500 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let upper = match k % 4 {
                0 => special[(x % 7) as usize],
                1 => (x % 5) as f64 - 2.0,
                _ => f64::from_bits(x),
            };
            d.candidates.push(Candidate {
                target: Target::Overlap { pair: k },
                interval: 0,
                s0: 0.0,
                upper,
            });
        }
        let mut want: Vec<usize> = (0..d.candidates.len()).collect();
        want.sort_by(|&a, &b| d.candidates[b].upper.total_cmp(&d.candidates[a].upper));
        assert_eq!(d.order(), want);
    }
}
