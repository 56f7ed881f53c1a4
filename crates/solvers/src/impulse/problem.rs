//! The impulse method's problem and configuration, fixed for a run: the assembled system,
//! the contact rows in mass-scaled coordinates, the re-arming bands of the gaps and the
//! chattering-capture step ([`Problem`]); the options it reads ([`Config`]).

use structure::Scene;

use super::contact;
use crate::gap::System;
use crate::momentum::impulse::ContactGeom;

/// What does not change during a run.
pub(super) struct Problem<'a> {
    pub sys: &'a System,
    /// One row per scene contact in mass-scaled coordinates ([`contact::geometry`]).
    pub geoms: Vec<ContactGeom>,
    /// Round-off band of each gap, m: [`crate::closure::band`], 1e-10 · max(gap, 1 mm) (the
    /// momentum method's re-arming band).
    pub pen: Vec<f64>,
    /// The momentum method's base step h (record step, or T_min/8 without a record): the
    /// chattering-capture rule compares impact intervals with it, s.
    pub capture_h: f64,
}

impl<'a> Problem<'a> {
    pub fn new(scene: &Scene, sys: &'a System) -> Self {
        let geoms = contact::geometry(sys, scene);
        let capture_h = match &scene.ground {
            Some(g) => g.dt,
            None => 2.0 * std::f64::consts::PI / sys.omega_max / 8.0,
        };
        Problem {
            sys,
            pen: geoms.iter().map(|c| crate::closure::band(c.gap)).collect(),
            geoms,
            capture_h,
        }
    }
}

/// The options of a scene the impulse method reads.
#[derive(Debug, Clone, Copy)]
pub(super) struct Config {
    /// `momentum.persistent_contact`: capture accumulating impacts into held contacts.
    pub persistent_contact: bool,
    /// `momentum.capture_velocity`: approach speed (m/s) at or below which a closing
    /// contact is touching, not impacting.
    pub capture_velocity: f64,
    /// `gap_element.tolerance`: the step error tolerance (rtol; atol = rtol·1e-3).
    pub tolerance: f64,
    /// `analysis.max_steps`: the budget of trial steps.
    pub max_steps: u64,
    /// `analysis.max_impact_rate`: the impact-rate guard, 1/s.
    pub max_impact_rate: f64,
}

impl Config {
    pub fn new(scene: &Scene) -> Self {
        Config {
            persistent_contact: scene.momentum.persistent_contact,
            capture_velocity: scene.momentum.capture_velocity,
            tolerance: scene.gap_element.tolerance,
            max_steps: scene.limits.max_steps,
            max_impact_rate: scene.limits.max_impact_rate,
        }
    }
}
