//! Energy audit of the kept modes.
//!
//! Per mode, between events, d/dt(½q̇² + ½ω²q²) = f q̇ − 2ζω q̇². Over each segment the
//! two integrals are evaluated independently of that identity:
//! - input ∫ −Γ a_g q̇ dt exactly from the end states ([`super::modal::load_work`]);
//! - damping 2ζω ∫ q̇² dt in closed form (precomputed quadratic forms for full steps,
//!   [`super::modal::Arc::damping_integral`] for partial segments).
//!
//! Impacts change the kinetic energy by exactly ½Σ(q̇⁺² − q̇⁻²) (for `consistent`,
//! ½(1−e²)v²/W per impact); that loss is `contact`. Persistent-contact forces are linear
//! in time over a held segment ([`super::persistent`]) and do a little work over a segment
//! whose ends have the same gaps (−λ̇∫δ dt, from [`super::modal::Arc::ramp_work`]); it is
//! added to `contact` too, as are the held-segment ends' velocity projections and the
//! potential energy that closing a held gap after a cut segment changes
//! (`Stepper::close_held_gaps`). balance_error = initial + input − damping − contact − final
//! therefore measures the integration itself; the run stops when it exceeds 1e-6 of the
//! energy scale, which includes the static energy of the largest ground load
//! ([`super::problem::Problem::static_energy`]: the closed form's round-off is about ε of it).

use crate::EnergyAudit;

/// Running sums, J.
#[derive(Debug, Clone, Default)]
pub struct EnergyAccount {
    pub initial: f64,
    pub input: f64,
    pub damping: f64,
    pub contact: f64,
}

impl EnergyAccount {
    pub fn finish(&self, final_: f64) -> EnergyAudit {
        // (x − 0.0 = x: the same balance as without the hysteretic term.)
        EnergyAudit::closed(
            self.initial,
            self.input,
            self.damping,
            self.contact,
            0.0,
            final_,
        )
    }
}
