//! The shear-stick building and its matrices (see the module docs of [`crate::model`]).

use nalgebra::{DMatrix, DVector};

use super::{ModelError, Modes};

/// Modal damping: one ratio for every mode, or one per mode (scene files must give one per
/// mode; past the list, code that builds a `PerMode` directly gets its last value).
#[derive(Debug, Clone, PartialEq)]
pub enum Damping {
    /// ζ for every mode (dimensionless). Scene default: 0.05.
    Uniform(f64),
    /// ζ_n per mode, lowest mode first; modes past the list use its last value.
    PerMode(Vec<f64>),
}

impl Damping {
    /// Damping ratio of mode `n` (0-based).
    pub fn ratio(&self, n: usize) -> f64 {
        match self {
            Damping::Uniform(z) => *z,
            Damping::PerMode(v) => *v.get(n).or(v.last()).unwrap_or(&0.0),
        }
    }
}

/// Rayleigh damping C = a M + b K. Being classical, it is modal damping with the ratios
/// ζ_n = a / (2 ω_n) + b ω_n / 2; through two anchor frequencies ω_i ≠ ω_j with the same
/// ratio ζ at both: a = 2 ζ ω_i ω_j / (ω_i + ω_j) (1/s), b = 2 ζ / (ω_i + ω_j) (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rayleigh {
    /// Mass-proportional coefficient a, 1/s.
    pub a: f64,
    /// Stiffness-proportional coefficient b, s.
    pub b: f64,
}

impl Rayleigh {
    /// The coefficients giving ratio `zeta` at circular frequencies `w_i` and `w_j` (rad/s,
    /// finite, > 0 and different); `None` otherwise.
    pub fn through(zeta: f64, w_i: f64, w_j: f64) -> Option<Rayleigh> {
        let ok = |w: f64| w.is_finite() && w > 0.0;
        if !(ok(w_i) && ok(w_j) && w_i != w_j && zeta.is_finite()) {
            return None;
        }
        let s = w_i + w_j;
        Some(Rayleigh {
            a: 2.0 * zeta * w_i * w_j / s,
            b: 2.0 * zeta / s,
        })
    }

    /// Damping ratio at circular frequency `w` (rad/s): a / (2ω) + b ω / 2.
    pub fn ratio(&self, w: f64) -> f64 {
        self.a / (2.0 * w) + self.b * w / 2.0
    }
}

/// A planar lumped-mass shear stick.
#[derive(Debug, Clone, PartialEq)]
pub struct Building {
    /// Name used by contacts and in outputs.
    pub name: String,
    /// Floor masses, kg, floor 1 (lowest) first.
    pub masses: Vec<f64>,
    /// Story stiffnesses, N/m, story 1 (ground to floor 1) first.
    pub story_stiffness: Vec<f64>,
    /// Modal damping ratios (dimensionless).
    pub damping: Damping,
    /// Initial floor displacements relative to the ground, m (zeros by default).
    pub initial_displacement: Vec<f64>,
    /// Initial floor velocities relative to the ground, m/s (zeros by default).
    pub initial_velocity: Vec<f64>,
    /// Published frequencies (Hz) shown beside the model's by `pound modes`; may be empty.
    pub reference_frequencies_hz: Vec<f64>,
    /// The story force–drift law (linear by default). The modes, the damping matrix and
    /// `story_stiffness` are those of the elastic building (initial stiffness).
    pub story_law: super::StoryLaw,
}

impl Building {
    /// A building at rest with the given masses (kg), story stiffnesses (N/m) and one
    /// damping ratio for every mode.
    pub fn new(name: &str, masses: Vec<f64>, story_stiffness: Vec<f64>, zeta: f64) -> Self {
        let n = masses.len();
        Building {
            name: name.to_string(),
            masses,
            story_stiffness,
            damping: Damping::Uniform(zeta),
            initial_displacement: vec![0.0; n],
            initial_velocity: vec![0.0; n],
            reference_frequencies_hz: Vec::new(),
            story_law: super::StoryLaw::Linear,
        }
    }

    /// A uniform stick: `n` floors of mass `m` (kg) and stories of stiffness `k` (N/m).
    pub fn uniform(name: &str, n: usize, m: f64, k: f64, zeta: f64) -> Self {
        Self::new(name, vec![m; n], vec![k; n], zeta)
    }

    /// Number of floors (= degrees of freedom).
    pub fn n_floors(&self) -> usize {
        self.masses.len()
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// Checks sizes, positivity and finiteness; the message names the offending field.
    pub fn validate(&self) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::Invalid {
            building: self.name.clone(),
            what,
        };
        let n = self.masses.len();
        if n == 0 {
            return Err(bad(
                "`masses` is empty: a building needs at least one floor".into(),
            ));
        }
        if self.story_stiffness.len() != n {
            return Err(bad(format!(
                "`story_stiffness` has {} but `masses` has {n}: one story per floor",
                crate::count(self.story_stiffness.len(), "value", "values")
            )));
        }
        for (key, v) in [
            ("masses", &self.masses),
            ("story_stiffness", &self.story_stiffness),
        ] {
            if let Some((i, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !(x.is_finite() && **x > 0.0))
            {
                return Err(bad(format!(
                    "`{key}[{i}]` = {x}: expected a finite value > 0"
                )));
            }
        }
        for (key, v) in [
            ("initial_displacement", &self.initial_displacement),
            ("initial_velocity", &self.initial_velocity),
        ] {
            if v.len() != n {
                return Err(bad(format!(
                    "`{key}` has {}, expected {n} (one per floor)",
                    crate::count(v.len(), "value", "values")
                )));
            }
            if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(bad(format!("`{key}[{i}]` = {x}: expected a finite value")));
            }
        }
        let ratios: Vec<f64> = match &self.damping {
            Damping::Uniform(z) => vec![*z],
            Damping::PerMode(v) if v.is_empty() => {
                return Err(bad("`damping_ratio` list is empty".into()));
            }
            Damping::PerMode(v) => v.clone(),
        };
        if let Some(z) = ratios
            .iter()
            .find(|z| !(z.is_finite() && **z >= 0.0 && **z < 1.0))
        {
            return Err(bad(format!(
                "`damping_ratio` = {z}: expected 0 <= ratio < 1 (underdamped modes)"
            )));
        }
        if let super::StoryLaw::Bilinear { yield_shear, .. } = &self.story_law {
            if yield_shear.len() != n {
                return Err(bad(format!(
                    "`yield_shear` has {}, expected {n} (one per story, story 1 first)",
                    crate::count(yield_shear.len(), "value", "values")
                )));
            }
        }
        if let Some(params) = self.story_law.bilinear_params(&self.story_stiffness) {
            for (i, p) in params.iter().enumerate() {
                p.check()
                    .map_err(|what| bad(format!("story {}: {what}", i + 1)))?;
            }
        }
        Ok(())
    }

    /// Replaces the damping by Rayleigh damping with ratio `zeta` at modes `i` and `j`
    /// (0-based, different, within the building's modes): each mode n then gets
    /// ζ_n = a / (2 ω_n) + b ω_n / 2 as a per-mode ratio. Returns the coefficients.
    pub fn set_rayleigh_damping(
        &mut self,
        zeta: f64,
        i: usize,
        j: usize,
    ) -> Result<Rayleigh, ModelError> {
        let n = self.n_floors();
        let bad = |what: String| ModelError::Invalid {
            building: self.name.clone(),
            what,
        };
        if i >= n || j >= n || i == j {
            return Err(bad(format!(
                "Rayleigh damping needs two different modes among 1 … {n}, got {} and {}",
                i + 1,
                j + 1
            )));
        }
        let omega = self.modes()?.omega;
        let r = Rayleigh::through(zeta, omega[i], omega[j]).ok_or_else(|| {
            bad(format!(
                "Rayleigh damping through modes {} and {}: equal frequencies ({} rad/s)",
                i + 1,
                j + 1,
                omega[i]
            ))
        })?;
        self.damping = Damping::PerMode(omega.iter().map(|w| r.ratio(*w)).collect());
        self.validate()?;
        Ok(r)
    }

    /// Lumped mass matrix M = diag(m), kg.
    pub fn mass_matrix(&self) -> DMatrix<f64> {
        DMatrix::from_diagonal(&DVector::from_column_slice(&self.masses))
    }

    /// Tridiagonal stiffness matrix K, N/m.
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        let n = self.n_floors();
        let k = &self.story_stiffness;
        let mut m = DMatrix::zeros(n, n);
        for j in 0..n {
            m[(j, j)] = k[j] + if j + 1 < n { k[j + 1] } else { 0.0 };
            if j + 1 < n {
                m[(j, j + 1)] = -k[j + 1];
                m[(j + 1, j)] = -k[j + 1];
            }
        }
        m
    }

    /// Classical damping matrix C = M Φ diag(2 ζ_n ω_n) Φᵀ M, N·s/m, built from all modes so
    /// that Φᵀ C Φ = diag(2 ζ_n ω_n) exactly: both solvers see the same damping.
    pub fn damping_matrix(&self, modes: &Modes) -> DMatrix<f64> {
        let mphi = DMatrix::from_fn(self.n_floors(), modes.n_modes(), |i, n| {
            self.masses[i] * modes.phi[(i, n)]
        });
        let d = DVector::from_fn(modes.n_modes(), |n, _| 2.0 * modes.zeta[n] * modes.omega[n]);
        &mphi * DMatrix::from_diagonal(&d) * mphi.transpose()
    }

    /// Mass-normalised modes sorted by frequency (all of them).
    pub fn modes(&self) -> Result<Modes, ModelError> {
        self.validate()?;
        Modes::compute(self)
    }

    /// Story shears V_j = k_j (u_j − u_{j−1}), N, story 1 first, from floor displacements
    /// `u` (m, relative to the ground).
    pub fn story_shears_into(&self, u: &[f64], out: &mut [f64]) {
        let mut below = 0.0;
        for j in 0..self.n_floors() {
            out[j] = self.story_stiffness[j] * (u[j] - below);
            below = u[j];
        }
    }

    /// Story shears as a new vector (see [`Building::story_shears_into`]).
    pub fn story_shears(&self, u: &[f64]) -> Vec<f64> {
        let mut v = vec![0.0; self.n_floors()];
        self.story_shears_into(u, &mut v);
        v
    }

    /// Strain energy ½ uᵀ K u, J.
    pub fn strain_energy(&self, u: &[f64]) -> f64 {
        let mut below = 0.0;
        let mut e = 0.0;
        for (&uj, &k) in u.iter().zip(&self.story_stiffness).take(self.n_floors()) {
            let d = uj - below;
            e += 0.5 * k * d * d;
            below = uj;
        }
        e
    }

    /// Kinetic energy ½ vᵀ M v, J (relative velocities).
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        self.masses
            .iter()
            .zip(v)
            .map(|(m, v)| 0.5 * m * v * v)
            .sum()
    }
}
