//! Rules every solver shares, defined once (issue 9, point 8).
//!
//! - [`grid_steps`]: how many steps of at most `dt` cover a duration, robust to the
//!   round-off of decimal inputs (0.14 s / 0.01 s is 14 steps, not 15).
//! - [`ImpactRateGuard`]: the impact-rate guard (`analysis.max_impact_rate`): a run stops
//!   with [`SolverError::EventStorm`] when more than `max(2, ⌈rate · W⌉)` impacts (momentum
//!   and impulse methods) or contact closures (gap element) fall inside any sliding window of
//!   `W =` [`STORM_WINDOW`] s of simulated time, counted over all contacts.

use std::collections::VecDeque;

use crate::SolverError;

/// Sliding window of the impact-rate guard, s.
pub const STORM_WINDOW: f64 = 0.05;

/// Number of equal steps of at most `dt` that cover `duration` (at least 1).
///
/// A ratio within 1e-9 (relative) of a whole number counts as that number, so a duration
/// that is a whole number of steps in decimal is not given an extra sliver step.
pub fn grid_steps(duration: f64, dt: f64) -> u64 {
    let x = duration / dt;
    let r = x.round();
    let n = if (x - r).abs() <= 1e-9 * r.max(1.0) {
        r
    } else {
        x.ceil()
    };
    (n as u64).max(1)
}

/// The impact-rate guard (see the module docs).
#[derive(Debug, Clone)]
pub struct ImpactRateGuard {
    times: VecDeque<f64>,
    /// Impacts per second allowed (`analysis.max_impact_rate`).
    rate: f64,
    /// Impacts allowed inside one window.
    allowed: usize,
}

impl ImpactRateGuard {
    /// A guard allowing `rate` impacts per second, 1/s.
    pub fn new(rate: f64) -> Self {
        let allowed = (rate * STORM_WINDOW).ceil().max(2.0);
        ImpactRateGuard {
            times: VecDeque::with_capacity(256),
            rate,
            allowed: if allowed.is_finite() && allowed < 1e15 {
                allowed as usize
            } else {
                usize::MAX
            },
        }
    }

    /// Records one impact (or closure) at time `t`, s. `context` is called only when the
    /// guard trips, to say which contact and why.
    pub fn record(&mut self, t: f64, context: impl FnOnce() -> String) -> Result<(), SolverError> {
        self.times.push_back(t);
        while let Some(&f) = self.times.front() {
            if t - f > STORM_WINDOW {
                self.times.pop_front();
            } else {
                break;
            }
        }
        if self.times.len() > self.allowed {
            return Err(SolverError::EventStorm {
                time: t,
                impacts: self.times.len(),
                window: STORM_WINDOW,
                limit: self.rate,
                context: context(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_steps_ignores_decimal_round_off() {
        assert_eq!(grid_steps(0.14, 0.01), 14);
        assert_eq!(grid_steps(40.0, 0.005), 8000);
        assert_eq!(grid_steps(0.145, 0.01), 15);
        assert_eq!(grid_steps(1e-3, 1.0), 1);
        assert_eq!(grid_steps(3.0, 1.0), 3);
    }

    #[test]
    fn guard_trips_past_the_allowed_count_inside_the_window() {
        // 2000/s over 0.05 s: 100 allowed, the 101st trips.
        let mut g = ImpactRateGuard::new(2000.0);
        for i in 0..100 {
            g.record(i as f64 * 1e-4, String::new).unwrap();
        }
        let e = g.record(0.0101, || "c0".into()).unwrap_err();
        assert!(matches!(e, SolverError::EventStorm { impacts: 101, .. }));
        // Spread out over time, the same count never trips.
        let mut g = ImpactRateGuard::new(2000.0);
        for i in 0..10_000 {
            g.record(i as f64 * 1e-3, String::new).unwrap();
        }
    }
}
