//! The event search of the impulse method on the dense output of an accepted step
//! ([`earliest`]): closures of open contacts (the case analysis shared with the momentum
//! method, [`crate::closure`], on the interpolant: [`DenseGap`]), the release of a held
//! contact (its holding force over its round-off band crossing −1) and the kinks of yielding
//! stories before either.

use super::held;
use super::problem::Problem;
use super::stepper::State;
use crate::closure::{find_root_brent, rearm_at_window_end, Conv, GapCurve, Search};
use crate::gap::adaptive::kin;
use crate::gap::dopri::Dopri5;
use crate::gap::stories::Kink;
use crate::gap::Segment;
use crate::momentum::problem::SIMULTANEOUS;

/// Samples of the dense output per step for the event search (each window holds at most one
/// extremum of a gap function: steps are far below an eighth of the shortest period).
const EVENT_SAMPLES: usize = 4;

/// The earliest event of an accepted step.
#[derive(Debug, Clone)]
pub(super) enum Event {
    /// These contacts close (within [`SIMULTANEOUS`] s of the first).
    Closure(Vec<usize>),
    /// This held contact's holding force turns tensile.
    Release(usize),
    /// A kink of a yielding story (yield or unloading) before any contact event.
    Kink(Kink),
}

/// Brent's method on [a, b] with absolute tolerance `tol`; without a bracket (round-off at
/// an end) the end where |f| is smaller.
fn brent(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, tol: f64, iters: &mut u64) -> f64 {
    let mut conv = Conv { tol, iterations: 0 };
    let r = find_root_brent(a, b, &mut f, &mut conv);
    *iters += conv.iterations as u64 + 1;
    match r {
        Ok(s) => s.clamp(a, b),
        Err(_) => {
            if f(a).abs() <= f(b).abs() {
                a
            } else {
                b
            }
        }
    }
}

/// One contact's gap function on the dense output of a step, θ ∈ [0, 1]: the [`GapCurve`]
/// of the impulse method. Its rate is the interpolated δ̇ (m/s, a positive multiple of
/// dδ/dθ up to the interpolation error); the interpolant bounds no derivative, so every
/// window whose signs ask for it is searched (no filter).
struct DenseGap<'a> {
    dp: &'a Dopri5,
    n: usize,
    l: usize,
    right: Option<usize>,
    gap: f64,
}

impl GapCurve for DenseGap<'_> {
    fn delta(&mut self, th: f64) -> f64 {
        kin(self.dp, self.n, self.l, self.right, self.gap, th).0
    }
    fn rate(&mut self, th: f64) -> f64 {
        kin(self.dp, self.n, self.l, self.right, self.gap, th).1
    }
    fn derivative_bound(&self, _k: u32) -> Option<f64> {
        None
    }
}

/// The earliest event of the accepted step `(t, hs)` (start, length, s) on its dense
/// output `dp`, as (θ, event):
/// - closures of the open contacts, each searched in [`EVENT_SAMPLES`] windows by
///   [`Search::locate`] against its gap (shifted by the re-arming band `pen` while the
///   contact is grazing; a grazing contact whose gap has opened beyond the band at the step's
///   start or at a window's end before the first event is re-armed here, or inside a window
///   by the search);
///   the closures within [`SIMULTANEOUS`] s of the first form one event;
/// - the release of a held contact: min λ/band over the held set crossing −1 between the
///   samples, located by Brent (it wins a tie with a closure);
/// - a story kink before either ([`crate::gap::Stories::locate_kink`]), so that no step
///   straddles a kink of the story law.
///
/// Root tolerance: 2ε·t in time (the momentum method's), in units of θ. `scratch` holds
/// one state; `iters` counts the root-finder evaluations.
///
/// Inlined into [`super::stepper::ImpulseStepper::step`] and from
/// there into the driver's loop: inside that loop LLVM inlines the dense-output
/// evaluations of the samples, as it did when the loop was one function (callgrind: 0.8 %
/// more instructions on the paper scene otherwise).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn earliest(
    p: &Problem,
    s: &mut State,
    dp: &Dopri5,
    seg: &Segment,
    (t, hs): (f64, f64),
    scratch: &mut [f64],
    iters: &mut u64,
) -> Option<(f64, Event)> {
    let sys = p.sys;
    let n = sys.n;
    let th_tol = (2.0 * f64::EPSILON * (t + hs) + 1e-300) / hs;
    let mut closures: Vec<(f64, usize)> = Vec::new();
    let mut rearmed: Vec<(usize, f64)> = Vec::new();
    for (ci, cd) in sys.contacts.iter().enumerate() {
        if s.held.set.contains(&ci) {
            continue;
        }
        if s.grazing[ci] && cd.rel(&s.y[..n]) - cd.gap < -p.pen[ci] {
            s.grazing[ci] = false;
        }
        // A contact not yet re-armed is searched at δ = pen until its gap opens beyond −pen:
        // at a window end (the later windows at δ = 0), or inside a window at the minimum
        // that precedes a new approach (the search re-arms it there), as in the momentum
        // method.
        let mut shift = if s.grazing[ci] { p.pen[ci] } else { 0.0 };
        let mut curve = DenseGap {
            dp,
            n,
            l: cd.l,
            right: (!cd.wall).then_some(cd.r),
            gap: cd.gap,
        };
        let (d, dd) = kin(dp, n, cd.l, curve.right, cd.gap, 0.0);
        let mut prev = (d - shift, dd);
        for j in 1..=EVENT_SAMPLES {
            let (lo, hi) = (
                (j - 1) as f64 / EVENT_SAMPLES as f64,
                j as f64 / EVENT_SAMPLES as f64,
            );
            let (d, dd) = kin(dp, n, cd.l, curve.right, cd.gap, hi);
            let cur = (d - shift, dd);
            let mut search = Search {
                lo,
                hi,
                tol: th_tol,
                shift,
                band: p.pen[ci],
                iterations: 0,
            };
            let found = search.locate(&mut curve, prev.0, prev.1, cur.0, cur.1);
            *iters += search.iterations;
            if let Some(th) = found {
                closures.push((th, ci));
                break;
            }
            prev = cur;
            if rearm_at_window_end(&mut prev, &mut shift) {
                rearmed.push((ci, hi));
            }
        }
    }
    let mut release: Option<(f64, usize)> = None;
    if !s.held.set.is_empty() {
        let (stories, held) = (&s.stories, &s.held);
        let ratio = |th: f64, scratch: &mut [f64]| {
            dp.dense_all(th, scratch);
            held::force_ratio(p, stories, held, scratch, seg.at(t + th * hs))
        };
        let mut th_a = 0.0;
        let mut release_iters = 0;
        for j in 1..=EVENT_SAMPLES {
            let th_b = j as f64 / EVENT_SAMPLES as f64;
            let (fb, kb) = ratio(th_b, scratch);
            if fb < -1.0 {
                let th = brent(
                    |th| ratio(th, scratch).0 + 1.0,
                    th_a,
                    th_b,
                    th_tol,
                    &mut release_iters,
                );
                release = Some((th, held.set[kb]));
                break;
            }
            th_a = th_b;
        }
        *iters += release_iters;
    }
    let first_closure = closures.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
    let event = match release {
        Some((th, c)) if th <= first_closure => Some((th, Event::Release(c))),
        _ if first_closure.is_finite() => {
            let simultaneous = SIMULTANEOUS / hs;
            let set: Vec<usize> = closures
                .iter()
                .filter(|(th, _)| *th <= first_closure + simultaneous)
                .map(|&(_, c)| c)
                .collect();
            Some((first_closure, Event::Closure(set)))
        }
        _ => None,
    };
    let event = if s.stories.is_empty() {
        event
    } else {
        let limit = event.as_ref().map_or(1.0, |(th, _)| *th);
        match s.stories.locate_kink(dp, 0, n, limit, iters) {
            Some(k) => Some((k.theta, Event::Kink(k))),
            None => event,
        }
    };
    // The re-arming outlives the step if it came before the part of it taken (to the first
    // event or its end): a gap that opened beyond −pen and is back inside the band at the
    // end is then searched at δ = 0 by the next step, not at δ = pen.
    let taken = event.as_ref().map_or(1.0, |(th, _)| *th);
    for (ci, th) in rearmed {
        if th <= taken {
            s.grazing[ci] = false;
        }
    }
    event
}
