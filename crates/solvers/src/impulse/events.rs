//! The event search of the impulse method on the dense output of an accepted step
//! ([`earliest`]): closures of open contacts (the momentum method's case analysis on the
//! interpolant, [`closure_in`]), the release of a held contact (its holding force over its
//! round-off band crossing −1) and the kinks of yielding stories before either.

use super::held;
use super::problem::Problem;
use super::stepper::State;
use crate::gap::adaptive::kin;
use crate::gap::dopri::Dopri5;
use crate::gap::stories::Kink;
use crate::gap::Segment;
use crate::momentum::events::Conv;
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
    let r = roots::find_root_brent(a, b, &mut f, &mut conv);
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

/// The first closure θ in the window [lo, hi] of the dense output, given (δ, δ̇) at both
/// ends: the momentum method's case analysis ([`crate::momentum::events`]) on the
/// interpolant instead of the closed form (the interior maximum is located by Brent on δ̇
/// whenever δ̇ turns from + to −, without the closed form's rigorous filter).
#[allow(clippy::too_many_arguments)]
#[inline]
fn closure_in(
    f: impl Fn(f64) -> (f64, f64),
    lo: f64,
    hi: f64,
    (d0, dd0): (f64, f64),
    (d1, dd1): (f64, f64),
    tol: f64,
    iters: &mut u64,
) -> Option<f64> {
    let d = |s: f64| f(s).0;
    let dd = |s: f64| f(s).1;
    if d0 >= 0.0 {
        if dd0 > 0.0 {
            return if d1 >= 0.0 { Some(lo) } else { None };
        }
        if dd1 <= 0.0 {
            return None;
        }
        let s_min = brent(dd, lo, hi, tol, iters);
        if d(s_min) >= 0.0 {
            return Some(s_min);
        }
        if d1 >= 0.0 {
            return Some(brent(d, s_min, hi, tol, iters));
        }
        return None;
    }
    if d1 >= 0.0 {
        if dd0 < 0.0 && dd1 > 0.0 {
            let s_min = brent(dd, lo, hi, tol, iters);
            return Some(brent(d, s_min, hi, tol, iters));
        }
        return Some(brent(d, lo, hi, tol, iters));
    }
    if dd0 > 0.0 && dd1 < 0.0 {
        let s_max = brent(dd, lo, hi, tol, iters);
        if d(s_max) >= 0.0 {
            return Some(brent(d, lo, s_max, tol, iters));
        }
    }
    None
}

/// The earliest event of the accepted step `(t, hs)` (start, length, s) on its dense
/// output `dp`, as (θ, event):
/// - closures of the open contacts, each searched in [`EVENT_SAMPLES`] windows by
///   [`closure_in`] against its gap (shifted by the re-arming band `pen` while the contact
///   is grazing; a grazing contact whose gap has opened beyond the band is re-armed here);
///   the closures within [`SIMULTANEOUS`] s of the first form one event;
/// - the release of a held contact: min λ/band over the held set crossing −1 between the
///   samples, located by Brent (it wins a tie with a closure);
/// - a story kink before either ([`crate::gap::Stories::locate_kink`]), so that no step
///   straddles a kink of the story law.
///
/// Root tolerance: 2ε·t in time (the momentum method's), in units of θ. `scratch` holds
/// one state; `iters` counts the root-finder evaluations.
///
/// Inlined (with [`closure_in`]) into [`super::stepper::ImpulseStepper::step`] and from
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
    for (ci, cd) in sys.contacts.iter().enumerate() {
        if s.held.set.contains(&ci) {
            continue;
        }
        if s.grazing[ci] && cd.rel(&s.y[..n]) - cd.gap < -p.pen[ci] {
            s.grazing[ci] = false;
        }
        let shift = if s.grazing[ci] { p.pen[ci] } else { 0.0 };
        let right = (!cd.wall).then_some(cd.r);
        let f = |th: f64| kin(dp, n, cd.l, right, cd.gap + shift, th);
        let mut prev = f(0.0);
        for j in 1..=EVENT_SAMPLES {
            let (lo, hi) = (
                (j - 1) as f64 / EVENT_SAMPLES as f64,
                j as f64 / EVENT_SAMPLES as f64,
            );
            let cur = f(hi);
            if let Some(th) = closure_in(f, lo, hi, prev, cur, th_tol, iters) {
                closures.push((th, ci));
                break;
            }
            prev = cur;
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
    if s.stories.is_empty() {
        return event;
    }
    let limit = event.as_ref().map_or(1.0, |(th, _)| *th);
    match s.stories.locate_kink(dp, 0, n, limit, iters) {
        Some(k) => Some((k.theta, Event::Kink(k))),
        None => event,
    }
}
