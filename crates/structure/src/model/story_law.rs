//! Story force–drift laws beyond linear elasticity (issue 13, first building block): an
//! elastic–plastic story spring with linear kinematic hardening, the bilinear law of
//! OpenSees' `Steel01` without isotropic hardening (Fy, E0, b).
//!
//! With elastic stiffness k₀ (N/m), yield shear F_y (N) and hardening ratio b (post-yield
//! tangent b·k₀), the state is the plastic drift u_p (m) and the back force α (N). For a
//! drift u the trial force is F* = k₀ (u − u_p) and the yield function
//!
//! ```text
//! f = |F* − α| − F_y,        H = b k₀ / (1 − b)   (kinematic hardening modulus, N/m)
//! f ≤ 0: elastic, F = F*, tangent k₀
//! f > 0: Δγ = f / (k₀ + H), s = sign(F* − α):
//!        F = F* − k₀ Δγ s,  u_p ← u_p + Δγ s,  α ← α + H Δγ s,  tangent k₀ H/(k₀ + H) = b k₀
//! ```
//!
//! (the closest-point return mapping, exact for a linear law: Simo & Hughes, *Computational
//! Inelasticity*, 1998, box 1.5). The plastic work of a step, ∫ F du_p, is exact by the
//! trapezoidal rule in u_p because F is linear in u_p during flow (F = s F_y + α). The
//! recoverable energy is ½ k₀ (u − u_p)² (spring) plus ½ α²/H (the hardening spring); the
//! hysteretic energy of the energy audit is the plastic work less the change of ½ α²/H.
//!
//! The state follows trial / commit / revert (as in OpenSees): [`Bilinear::trial`] computes
//! the force at a drift from the *committed* state without changing it, [`Bilinear::commit`]
//! accepts the last trial, and a rejected adaptive step simply never commits, so the history
//! is never corrupted. [`Bilinear::elastic_range`] gives the drifts between which the
//! committed state answers elastically: the yield kinks an adaptive integrator locates as
//! events.

/// How the stories of a building resist drift (scene key `story_law`).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum StoryLaw {
    /// Linear elastic stories, V_j = k_j (u_j − u_{j−1}) (`story_law = "linear"`, the default).
    #[default]
    Linear,
    /// Bilinear elastic–plastic stories with kinematic hardening ([`Bilinear`]):
    /// `story_law = "bilinear"` with `yield_shear` and `hardening_ratio`.
    Bilinear {
        /// Yield shear F_y per story, N, story 1 first (`yield_shear`: a number for every
        /// story or one per story; no default).
        yield_shear: Vec<f64>,
        /// Post-yield tangent over the elastic story stiffness, b in [0, 1)
        /// (`hardening_ratio`, dimensionless; default [`DEFAULT_HARDENING_RATIO`]).
        hardening_ratio: f64,
    },
}

/// Default of the scene key `hardening_ratio` (dimensionless).
pub const DEFAULT_HARDENING_RATIO: f64 = 0.02;

impl StoryLaw {
    /// True for a law that can yield (the linear modal method does not apply).
    pub fn is_yielding(&self) -> bool {
        !matches!(self, StoryLaw::Linear)
    }

    /// The bilinear parameters of every story, given the elastic story stiffnesses (N/m);
    /// `None` for linear stories.
    pub fn bilinear_params(&self, story_stiffness: &[f64]) -> Option<Vec<BilinearParams>> {
        match self {
            StoryLaw::Linear => None,
            StoryLaw::Bilinear {
                yield_shear,
                hardening_ratio,
            } => Some(
                story_stiffness
                    .iter()
                    .zip(yield_shear)
                    .map(|(&k, &fy)| BilinearParams {
                        stiffness: k,
                        yield_shear: fy,
                        hardening_ratio: *hardening_ratio,
                    })
                    .collect(),
            ),
        }
    }
}

/// Parameters of a bilinear story spring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BilinearParams {
    /// Elastic stiffness k₀, N/m (> 0).
    pub stiffness: f64,
    /// Yield shear F_y, N (> 0).
    pub yield_shear: f64,
    /// Post-yield tangent over k₀, b in [0, 1) (dimensionless; scene default 0.02).
    pub hardening_ratio: f64,
}

impl BilinearParams {
    /// Kinematic hardening modulus H = b k₀ / (1 − b), N/m.
    pub fn hardening_modulus(&self) -> f64 {
        self.hardening_ratio * self.stiffness / (1.0 - self.hardening_ratio)
    }

    /// Yield drift F_y / k₀, m.
    pub fn yield_drift(&self) -> f64 {
        self.yield_shear / self.stiffness
    }

    /// Checks the parameters: k₀ and F_y finite and > 0, b finite in [0, 1).
    pub fn check(&self) -> Result<(), String> {
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(format!(
                "story stiffness {} N/m: expected finite and > 0",
                self.stiffness
            ));
        }
        if !(self.yield_shear.is_finite() && self.yield_shear > 0.0) {
            return Err(format!(
                "yield shear {} N: expected finite and > 0",
                self.yield_shear
            ));
        }
        if !(self.hardening_ratio.is_finite() && (0.0..1.0).contains(&self.hardening_ratio)) {
            return Err(format!(
                "hardening ratio {}: expected a number in [0, 1)",
                self.hardening_ratio
            ));
        }
        Ok(())
    }
}

/// The internal variables of the law.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BilinearState {
    /// Plastic drift u_p, m.
    pub plastic_drift: f64,
    /// Back force α, N.
    pub back_force: f64,
}

/// The answer of a trial: force, tangent, the trial state and its plastic work.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trial {
    /// Drift of the trial, m.
    pub drift: f64,
    /// Story force, N.
    pub force: f64,
    /// Consistent tangent dF/du, N/m.
    pub tangent: f64,
    /// True when the trial yielded (plastic flow from the committed state).
    pub yielded: bool,
    /// The state the trial would commit.
    pub state: BilinearState,
    /// Plastic work ∫ F du_p from the committed state to this trial, J.
    pub plastic_work: f64,
}

/// A bilinear story spring with trial / commit / revert state.
#[derive(Debug, Clone, PartialEq)]
pub struct Bilinear {
    pub params: BilinearParams,
    committed: BilinearState,
    last: Option<Trial>,
    /// Plastic work committed so far, J.
    plastic_work: f64,
}

impl Bilinear {
    /// A virgin spring (no plastic drift, no back force).
    pub fn new(params: BilinearParams) -> Self {
        Bilinear {
            params,
            committed: BilinearState::default(),
            last: None,
            plastic_work: 0.0,
        }
    }

    /// The committed state.
    pub fn state(&self) -> BilinearState {
        self.committed
    }

    /// Plastic work committed so far, ∫ F du_p, J.
    pub fn plastic_work(&self) -> f64 {
        self.plastic_work
    }

    /// Energy stored in the hardening spring, ½ α²/H, J (0 without hardening).
    pub fn hardening_energy(&self) -> f64 {
        let h = self.params.hardening_modulus();
        if h > 0.0 {
            0.5 * self.committed.back_force.powi(2) / h
        } else {
            0.0
        }
    }

    /// Dissipated (hysteretic) energy so far: plastic work less the stored hardening
    /// energy, J.
    pub fn hysteretic_energy(&self) -> f64 {
        self.plastic_work - self.hardening_energy()
    }

    /// Force, tangent and state at `drift` (m) from the committed state; the spring itself
    /// is unchanged until [`Bilinear::commit`].
    pub fn trial(&mut self, drift: f64) -> Trial {
        let t = self.evaluate(drift);
        self.last = Some(t);
        t
    }

    /// The trial answer without recording it as the last trial.
    pub fn evaluate(&self, drift: f64) -> Trial {
        let p = &self.params;
        let (k0, h) = (p.stiffness, p.hardening_modulus());
        let c = self.committed;
        let f_trial = k0 * (drift - c.plastic_drift);
        let xi = f_trial - c.back_force;
        let f = xi.abs() - p.yield_shear;
        if f <= 0.0 {
            return Trial {
                drift,
                force: f_trial,
                tangent: k0,
                yielded: false,
                state: c,
                plastic_work: 0.0,
            };
        }
        let s = xi.signum();
        let dg = f / (k0 + h);
        let state = BilinearState {
            plastic_drift: c.plastic_drift + dg * s,
            back_force: c.back_force + h * dg * s,
        };
        let force = f_trial - k0 * dg * s;
        // Flow starts on the committed yield surface (F = s F_y + α_n) and ends at `force`;
        // F is linear in u_p in between.
        let f_start = s * p.yield_shear + c.back_force;
        Trial {
            drift,
            force,
            tangent: k0 * h / (k0 + h),
            yielded: true,
            state,
            plastic_work: 0.5 * (f_start + force) * dg * s,
        }
    }

    /// Accepts the last trial (no effect without one).
    pub fn commit(&mut self) {
        if let Some(t) = self.last.take() {
            self.committed = t.state;
            self.plastic_work += t.plastic_work;
        }
    }

    /// Forgets the last trial: the committed state stands.
    pub fn revert(&mut self) {
        self.last = None;
    }

    /// Drifts (lower, upper), m, between which the committed state answers elastically:
    /// u_p + (α ∓ F_y)/k₀. An adaptive step that crosses one of them passes a yield kink.
    pub fn elastic_range(&self) -> (f64, f64) {
        let p = &self.params;
        let c = self.committed;
        (
            c.plastic_drift + (c.back_force - p.yield_shear) / p.stiffness,
            c.plastic_drift + (c.back_force + p.yield_shear) / p.stiffness,
        )
    }
}
