//! Contact laws of the gap element.
//!
//! Notation: δ = u_left − u_right − gap (m) is the penetration (closed while δ ≥ 0),
//! δ̇ = u̇_left − u̇_right (m/s, > 0 while approaching), F ≥ 0 the compressive contact force:
//! +F acts on the right floor and −F on the left floor. e = c_r is the coefficient of
//! restitution of the contact and m_eff = m_l·m_r/(m_l + m_r) of the two contact floors.
//!
//! | law | force while closed | how c_r enters | contact ends |
//! |---|---|---|---|
//! | `linear` | F = k δ | ignored: the spring is elastic, the achieved restitution is 1 (up to the structure's own motion) | δ = 0 |
//! | `kelvin-voigt`, `tension = true` | F = k δ + c δ̇ | c = 2ξ√(k m_eff), ξ = −ln e / √(π² + ln² e) (Anagnostopoulos 1988; ξ = 1 for e = 0) | δ = 0 (F may turn tensile just before: delivers e exactly for two free masses) |
//! | `kelvin-voigt`, `tension = false` (default) | F = k δ + c δ̇ | same c | F = k δ + c δ̇ = 0, the force is never tensile (achieved e = 0.674751 for a 0.65 target on two free masses, a closed form checked in `tests/gap_laws.rs`) |
//! | `hertz-damp` | F = k_h δ^{3/2} (1 + ξ̄ δ̇/δ̇⁻), clamped at 0 | ξ̄ = 8(1−e)/(5e) (Muthukumar & DesRoches 2006 with Ye et al. 2009); δ̇⁻ the approach speed at closure | δ = 0 (achieved e the root of ξ̄(1 + e) + ln((1 − ξ̄e)/(1 + ξ̄)) = 0: 0.630 for 0.65, independent of k_h, mass, speed) |
//!
//! k is `gap_element.stiffness` (N/m; N/m^{3/2} for `hertz-damp`).
//!
//! Event functions: a contact is closed while g ≥ 0 with g = δ, except for the clamped
//! Kelvin–Voigt law where g = min(δ, k δ + c δ̇): it closes when both the gap has closed and
//! the force it would carry is compressive, and it opens when the force reaches zero (which
//! happens while δ > 0; the spring energy ½kδ² left at that instant is released and counted
//! as contact dissipation).
//!
//! Guards: for `hertz-damp` the restitution is taken ≥ 0.01 (ξ̄ is infinite at e = 0) and
//! the approach speed δ̇⁻ ≥ 1e-4 m/s (grazing contacts would otherwise get an unbounded
//! dashpot); the force is clamped at zero, which only matters for e ≲ 0.3.

use structure::scene::{ContactLaw as LawKind, GapElementOptions};

/// Smallest approach speed used in the Hertz-damp dashpot, m/s.
pub const HERTZ_MIN_APPROACH_SPEED: f64 = 1e-4;
/// Smallest restitution used for ξ̄ of the Hertz-damp law.
pub const HERTZ_MIN_RESTITUTION: f64 = 0.01;

/// Anagnostopoulos damping ratio ξ = −ln e / √(π² + ln² e) (ξ = 1 at e = 0, 0 at e = 1).
pub fn kelvin_voigt_xi(e: f64) -> f64 {
    if e <= 0.0 {
        return 1.0;
    }
    if e >= 1.0 {
        return 0.0;
    }
    let l = e.ln();
    -l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
}

/// Ye et al. damping constant ξ̄ = 8(1 − e)/(5e) of the Hertz-damp law.
pub fn hertz_xi_bar(e: f64) -> f64 {
    let e = e.clamp(HERTZ_MIN_RESTITUTION, 1.0);
    8.0 * (1.0 - e) / (5.0 * e)
}

/// One contact's law with its constants resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Law {
    pub kind: LawKind,
    /// k, N/m (N/m^1.5 for Hertz).
    pub k: f64,
    /// Kelvin–Voigt dashpot c, N·s/m (0 otherwise).
    pub c: f64,
    /// Hertz-damp ξ̄ (0 otherwise).
    pub xi_bar: f64,
    /// Kelvin–Voigt: tension allowed until δ = 0.
    pub tension: bool,
    /// Effective mass of the two contact floors, kg.
    pub m_eff: f64,
    /// Target coefficient of restitution.
    pub restitution: f64,
}

impl Law {
    pub fn new(opts: &GapElementOptions, restitution: f64, m_eff: f64) -> Law {
        let k = opts.stiffness;
        let (c, xi_bar) = match opts.law {
            LawKind::Linear => (0.0, 0.0),
            LawKind::KelvinVoigt => (2.0 * kelvin_voigt_xi(restitution) * (k * m_eff).sqrt(), 0.0),
            LawKind::HertzDamp => (0.0, hertz_xi_bar(restitution)),
        };
        Law {
            kind: opts.law,
            k,
            c,
            xi_bar,
            tension: opts.tension,
            m_eff,
            restitution,
        }
    }

    /// True for the clamped Kelvin–Voigt law (event on the force, not on δ).
    #[inline]
    pub fn force_event(&self) -> bool {
        self.kind == LawKind::KelvinVoigt && !self.tension
    }

    /// Contact force F (N, compressive > 0) while the contact is closed; `v_close` is the
    /// approach speed at closure (Hertz-damp only). No clamping except Hertz (see module docs).
    #[inline]
    pub fn force(&self, delta: f64, ddot: f64, v_close: f64) -> f64 {
        match self.kind {
            LawKind::Linear => self.k * delta,
            LawKind::KelvinVoigt => self.k * delta + self.c * ddot,
            LawKind::HertzDamp => {
                let d = delta.max(0.0);
                let f = self.k
                    * d
                    * d.sqrt()
                    * (1.0 + self.xi_bar * ddot / v_close.max(HERTZ_MIN_APPROACH_SPEED));
                f.max(0.0)
            }
        }
    }

    /// (∂F/∂δ, ∂F/∂δ̇) while closed.
    #[inline]
    pub fn tangent(&self, delta: f64, ddot: f64, v_close: f64) -> (f64, f64) {
        match self.kind {
            LawKind::Linear => (self.k, 0.0),
            LawKind::KelvinVoigt => (self.k, self.c),
            LawKind::HertzDamp => {
                let d = delta.max(0.0);
                let vc = v_close.max(HERTZ_MIN_APPROACH_SPEED);
                let damp = 1.0 + self.xi_bar * ddot / vc;
                if damp <= 0.0 {
                    return (0.0, 0.0);
                }
                (
                    1.5 * self.k * d.sqrt() * damp,
                    self.k * d * d.sqrt() * self.xi_bar / vc,
                )
            }
        }
    }

    /// Event function: the contact is closed while g ≥ 0.
    #[inline]
    pub fn event(&self, delta: f64, ddot: f64) -> f64 {
        if self.force_event() {
            delta.min(self.k * delta + self.c * ddot)
        } else {
            delta
        }
    }

    /// Force the element carries at state (δ, δ̇) judged from the state alone (what a
    /// fixed-step program does): zero unless δ > 0; never tensile except Kelvin–Voigt with
    /// `tension = true`. Returns (F, ∂F/∂δ, ∂F/∂δ̇).
    #[inline]
    pub fn state_force(&self, delta: f64, ddot: f64, v_close: f64) -> (f64, f64, f64) {
        if delta <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let f = self.force(delta, ddot, v_close);
        if f <= 0.0 && !(self.kind == LawKind::KelvinVoigt && self.tension) {
            return (0.0, 0.0, 0.0);
        }
        let (kd, kv) = self.tangent(delta, ddot, v_close);
        (f, kd, kv)
    }

    /// Energy stored in the spring at penetration δ, J: ½kδ² or (2/5)k_h δ^{5/2}.
    pub fn stored_energy(&self, delta: f64) -> f64 {
        let d = delta.max(0.0);
        match self.kind {
            LawKind::HertzDamp => 0.4 * self.k * d * d * d.sqrt(),
            _ => 0.5 * self.k * d * d,
        }
    }

    /// Circular frequency of the contact oscillation, rad/s, for a contact closing at speed
    /// `v_close`: √(k/m_eff) or, for Hertz, the tangent frequency at the peak penetration of
    /// an elastic impact δ_max = (5 m_eff v² / (4 k_h))^{2/5}.
    pub fn contact_omega(&self, v_close: f64) -> f64 {
        match self.kind {
            LawKind::HertzDamp => {
                let v = v_close.abs().max(HERTZ_MIN_APPROACH_SPEED);
                let dmax = (1.25 * self.m_eff * v * v / self.k).powf(0.4);
                (1.5 * self.k * dmax.sqrt() / self.m_eff).sqrt()
            }
            _ => (self.k / self.m_eff).sqrt(),
        }
    }

    /// Name and constants in words, for `settings`.
    pub fn describe(&self) -> String {
        match self.kind {
            LawKind::Linear => format!("linear k={:.1e} N/m", self.k),
            LawKind::KelvinVoigt => format!(
                "kelvin-voigt k={:.1e} N/m ({})",
                self.k,
                if self.tension {
                    "tension allowed until δ=0"
                } else {
                    "force clamped at 0"
                }
            ),
            LawKind::HertzDamp => format!("hertz-damp k_h={:.1e} N/m^1.5", self.k),
        }
    }
}
