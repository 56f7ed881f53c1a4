//! The contact ledger of the gap-element integrators (adaptive and Newmark): per contact its
//! [`Mode`] (closed or not, approach speed at closure δ̇⁻ in m/s for Hertz-damp) and the
//! [`Episode`] in progress (closure to opening), the finished episodes as [`Impact`]s, and
//! the impact-rate storm guard ([`ImpactRateGuard`], `analysis.max_impact_rate`, 1/s).
//!
//! An episode opens at a closure t_c with the approach speed δ̇⁻ and the contact impulse
//! accumulated so far I(t_c); its peaks (largest force, largest penetration δ) are raised
//! while it lasts; at the opening t_o it becomes one impact with duration t_o − t_c,
//! impulse I(t_o) − I(t_c), speed after δ̇⁺ and achieved restitution −δ̇⁺/δ̇⁻
//! ([`super::restitution_undefined`] says when that is reported as null). Episodes still
//! open at the end of the analysis are reported up to its end ([`ContactLedger::finish`]).
//! The integrators decide *when* a contact closes or opens (located events for the adaptive
//! one, the state of the step's iterate for Newmark); the ledger only keeps the books.

use crate::rules::ImpactRateGuard;
use crate::{Impact, SolverError};

/// Mode of one contact, frozen during a trial step.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Mode {
    pub closed: bool,
    /// Approach speed at closure (Hertz-damp), m/s.
    pub v_close: f64,
}

/// Tracks one contact episode (closure to opening).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Episode {
    /// Closure time, s.
    pub t_close: f64,
    /// Relative velocity δ̇ before the closure (approach speed, > 0 approaching), m/s.
    pub v_before: f64,
    /// Contact impulse accumulated up to the closure, N·s.
    pub impulse0: f64,
    /// Largest contact force so far, N.
    pub peak_force: f64,
    /// Largest penetration δ so far, m.
    pub max_pen: f64,
}

impl Episode {
    /// The impact of this episode, opened at `t_open` (s) with relative velocity `v_after`
    /// (m/s) and accumulated impulse `impulse1` (N·s).
    pub fn impact(&self, contact: usize, t_open: f64, v_after: f64, impulse1: f64) -> Impact {
        let r = -v_after / self.v_before;
        let undefined = super::restitution_undefined(self.v_before, r);
        Impact {
            contact,
            time: self.t_close,
            relative_velocity_before: self.v_before,
            relative_velocity_after: v_after,
            achieved_restitution: if undefined.is_some() { f64::NAN } else { r },
            restitution_undefined: undefined.map(String::from),
            impulse: impulse1 - self.impulse0,
            duration: Some(t_open - self.t_close),
            peak_force: Some(self.peak_force),
            max_penetration: Some(self.max_pen),
        }
    }
}

/// The books of every contact of one run: modes, open episodes, finished impacts and the
/// impact-rate guard.
#[derive(Debug)]
pub(crate) struct ContactLedger {
    modes: Vec<Mode>,
    episodes: Vec<Episode>,
    impacts: Vec<Impact>,
    guard: ImpactRateGuard,
}

impl ContactLedger {
    /// `nc` contacts, all open; at most `max_impact_rate` closures per second, all contacts
    /// together (`analysis.max_impact_rate`, 1/s).
    pub fn new(nc: usize, max_impact_rate: f64) -> Self {
        ContactLedger {
            modes: vec![Mode::default(); nc],
            episodes: vec![Episode::default(); nc],
            impacts: Vec::new(),
            guard: ImpactRateGuard::new(max_impact_rate),
        }
    }

    /// The modes of all contacts (what the right-hand side freezes during a trial step).
    #[inline]
    pub fn modes(&self) -> &[Mode] {
        &self.modes
    }

    /// Whether contact `ci` is closed.
    #[inline]
    pub fn closed(&self, ci: usize) -> bool {
        self.modes[ci].closed
    }

    /// Approach speed at the closure of contact `ci`'s episode (m/s).
    #[inline]
    pub fn v_close(&self, ci: usize) -> f64 {
        self.modes[ci].v_close
    }

    /// The episode of contact `ci` (its peaks are raised while it is closed).
    #[inline]
    pub fn episode_mut(&mut self, ci: usize) -> &mut Episode {
        &mut self.episodes[ci]
    }

    /// Closes contact `ci` with approach speed `v_close` (m/s, the law's δ̇⁻) and starts
    /// `episode`. Not counted by the impact-rate guard (closures present at t = 0).
    pub fn close(&mut self, ci: usize, v_close: f64, episode: Episode) {
        self.modes[ci] = Mode {
            closed: true,
            v_close,
        };
        self.episodes[ci] = episode;
    }

    /// [`ContactLedger::close`] during the run: the closure at `t` (s) is counted by the
    /// impact-rate guard, which stops the run when the contact keeps closing.
    pub fn close_at(
        &mut self,
        ci: usize,
        t: f64,
        v_close: f64,
        episode: Episode,
    ) -> Result<(), SolverError> {
        self.close(ci, v_close, episode);
        self.guard
            .record(t, || format!("contact {ci} keeps closing (gap element)"))
    }

    /// Opens contact `ci` at `t_open` (s) with relative velocity `v_after` (m/s) and
    /// accumulated impulse `impulse1` (N·s): its episode becomes an impact.
    pub fn open(&mut self, ci: usize, t_open: f64, v_after: f64, impulse1: f64) {
        self.impacts
            .push(self.episodes[ci].impact(ci, t_open, v_after, impulse1));
        self.modes[ci].closed = false;
    }

    /// The impacts of the run: the episodes still open at `t_end` (s) are reported up to
    /// it, `at_end(ci)` giving the relative velocity (m/s) and the accumulated impulse
    /// (N·s) of contact `ci` there.
    pub fn finish(mut self, t_end: f64, at_end: impl Fn(usize) -> (f64, f64)) -> Vec<Impact> {
        for ci in 0..self.modes.len() {
            if self.modes[ci].closed {
                let (dd, imp) = at_end(ci);
                self.impacts
                    .push(self.episodes[ci].impact(ci, t_end, dd, imp));
            }
        }
        self.impacts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn episode(t: f64, v: f64, impulse0: f64) -> Episode {
        Episode {
            t_close: t,
            v_before: v,
            impulse0,
            peak_force: 0.0,
            max_pen: 0.0,
        }
    }

    #[test]
    fn an_episode_becomes_one_impact_with_its_duration_impulse_and_restitution() {
        let mut l = ContactLedger::new(2, f64::INFINITY);
        l.close_at(1, 1.0, 0.5, episode(1.0, 0.5, 3.0)).unwrap();
        assert!(l.closed(1) && !l.closed(0));
        assert_eq!(l.v_close(1), 0.5);
        let ep = l.episode_mut(1);
        ep.peak_force = ep.peak_force.max(7.0);
        ep.max_pen = ep.max_pen.max(1e-3);
        l.open(1, 1.25, -0.25, 5.0);
        assert!(!l.closed(1));
        let imp = l.finish(10.0, |_| unreachable!("no episode is open"));
        assert_eq!(imp.len(), 1);
        let i = &imp[0];
        assert_eq!((i.contact, i.time), (1, 1.0));
        assert_eq!(i.duration, Some(0.25));
        assert_eq!(i.impulse, 2.0);
        assert_eq!(i.achieved_restitution, 0.5);
        assert_eq!((i.peak_force, i.max_penetration), (Some(7.0), Some(1e-3)));
    }

    #[test]
    fn episodes_open_at_the_end_are_reported_up_to_the_end() {
        let mut l = ContactLedger::new(3, f64::INFINITY);
        l.close(0, 0.5, episode(0.0, 0.5, 0.0));
        l.close(2, 0.5, episode(2.0, 0.5, 1.0));
        let imp = l.finish(4.0, |ci| (-0.1 * ci as f64, 2.0 + ci as f64));
        let got: Vec<_> = imp
            .iter()
            .map(|i| (i.contact, i.duration, i.impulse))
            .collect();
        assert_eq!(got, vec![(0, Some(4.0), 2.0), (2, Some(2.0), 3.0)]);
    }

    #[test]
    fn the_storm_guard_counts_closures_during_the_run_only() {
        // 2000/s allows ceil(2000 · window) closures in one window; closures at t = 0
        // ([`ContactLedger::close`]) are not counted.
        let mut l = ContactLedger::new(1, 2000.0);
        for _ in 0..10_000 {
            l.close(0, 1.0, episode(0.0, 1.0, 0.0));
        }
        let mut tripped = None;
        for k in 0..100_000 {
            let t = 1.0 + k as f64 * 1e-6;
            if let Err(e) = l.close_at(0, t, 1.0, episode(t, 1.0, 0.0)) {
                tripped = Some((k, e));
                break;
            }
        }
        let (k, e) = tripped.expect("1e6 closures per second trip a guard of 2000/s");
        assert!(matches!(e, SolverError::EventStorm { .. }), "{e:?}");
        assert!(e.to_string().contains("contact 0 keeps closing"), "{e}");
        // The closure that trips it is the first beyond the allowance (all closures here
        // fall inside one window).
        assert_eq!(k, (2000.0 * crate::rules::STORM_WINDOW).ceil() as usize);
    }
}
