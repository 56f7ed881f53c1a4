//! Mass-normalised modes of a shear stick.
//!
//! The generalised eigenproblem K φ = ω² M φ with lumped M is solved in its symmetric form
//! M^(−½) K M^(−½) ψ = ω² ψ by faer's self-adjoint eigen-solver (eigenvalues ascending);
//! φ = M^(−½) ψ then satisfies Φᵀ M Φ = I and Φᵀ K Φ = diag(ω²). Signs are fixed so that the
//! top-floor component of every mode is positive (deterministic output).
//!
//! Derived quantities, all with mass-normalised φ_n:
//! - participation factor Γ_n = φ_nᵀ M 1; effective modal mass Γ_n² (Σ_n Γ_n² = Σ m);
//! - contact flexibility fraction r_N = m_c Σ_{n≤N} φ_n\[c\]² (r_all = 1, see numerics notes).

use nalgebra::DMatrix;

use super::{Building, ModelError};

/// Modes of one building, sorted by frequency.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes {
    /// Circular frequencies ω_n, rad/s, ascending.
    pub omega: Vec<f64>,
    /// Mode shapes, one column per mode (floors × modes), mass-normalised.
    pub phi: DMatrix<f64>,
    /// Damping ratio of each mode.
    pub zeta: Vec<f64>,
    /// Participation factors Γ_n = φ_nᵀ M 1, kg^½.
    pub participation: Vec<f64>,
    /// Total mass of the building, kg.
    pub total_mass: f64,
    /// Floor masses, kg (kept to evaluate r_N).
    pub masses: Vec<f64>,
}

impl Modes {
    /// All modes of `b` (the building must be valid).
    pub fn compute(b: &Building) -> Result<Modes, ModelError> {
        let n = b.n_floors();
        let k = b.stiffness_matrix();
        let s: Vec<f64> = b.masses.iter().map(|m| 1.0 / m.sqrt()).collect();
        let a = faer::Mat::<f64>::from_fn(n, n, |i, j| s[i] * k[(i, j)] * s[j]);
        let evd = a
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| ModelError::Eigen {
                building: b.name.clone(),
                reason: format!("{e:?}"),
            })?;
        let lam = evd.S().column_vector();
        let u = evd.U();
        let mut omega = Vec::with_capacity(n);
        let mut phi = DMatrix::zeros(n, n);
        for mode in 0..n {
            let l = lam[mode];
            if !(l.is_finite() && l > 0.0) {
                // A valid building's K is positive definite (every story stiffness > 0): a
                // non-positive eigenvalue is round-off swamping the smallest ones, i.e. an
                // ill-conditioned problem. Say what was found and the spreads behind it.
                let (k_lo, k_hi) = super::min_max(&b.story_stiffness);
                let (m_lo, m_hi) = super::min_max(&b.masses);
                let l_max = (0..n).map(|i| lam[i]).fold(f64::NAN, f64::max);
                return Err(ModelError::Eigen {
                    building: b.name.clone(),
                    reason: format!(
                        "mode {} has ω² = {l:e} rad²/s² (the largest is {l_max:e}), not a finite \
                         value > 0: with story stiffnesses from {k_lo:e} to {k_hi:e} N/m \
                         (ratio {:e}) and masses from {m_lo:e} to {m_hi:e} kg (ratio {:e}) the \
                         eigenproblem is too ill-conditioned for double precision",
                        mode + 1,
                        k_hi / k_lo,
                        m_hi / m_lo
                    ),
                });
            }
            omega.push(l.sqrt());
            let top = u[(n - 1, mode)];
            let sign = if top < 0.0 { -1.0 } else { 1.0 };
            for i in 0..n {
                phi[(i, mode)] = sign * s[i] * u[(i, mode)];
            }
        }
        let participation = (0..n)
            .map(|mode| (0..n).map(|i| b.masses[i] * phi[(i, mode)]).sum())
            .collect();
        Ok(Modes {
            zeta: (0..n).map(|i| b.damping.ratio(i)).collect(),
            omega,
            phi,
            participation,
            total_mass: b.total_mass(),
            masses: b.masses.clone(),
        })
    }

    /// Number of modes held.
    pub fn n_modes(&self) -> usize {
        self.omega.len()
    }

    /// The first `n` modes (all if `n` exceeds the count).
    pub fn truncated(&self, n: usize) -> Modes {
        let n = n.min(self.n_modes());
        Modes {
            omega: self.omega[..n].to_vec(),
            phi: self.phi.columns(0, n).into_owned(),
            zeta: self.zeta[..n].to_vec(),
            participation: self.participation[..n].to_vec(),
            total_mass: self.total_mass,
            masses: self.masses.clone(),
        }
    }

    /// Frequencies, Hz.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.omega
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect()
    }

    /// Periods, s.
    pub fn periods(&self) -> Vec<f64> {
        self.omega
            .iter()
            .map(|w| 2.0 * std::f64::consts::PI / w)
            .collect()
    }

    /// Effective modal mass ratios Γ_n² / Σm (they sum to 1 over all modes).
    pub fn effective_mass_ratios(&self) -> Vec<f64> {
        self.participation
            .iter()
            .map(|g| g * g / self.total_mass)
            .collect()
    }

    /// Contact flexibility fraction r_N = m_c Σ_{n≤N} φ_n\[c\]² for N = 1 … n_modes, at the
    /// floor with 0-based index `dof`.
    pub fn contact_flexibility(&self, dof: usize) -> Vec<f64> {
        let mc = self.masses[dof];
        let mut acc = 0.0;
        (0..self.n_modes())
            .map(|n| {
                acc += self.phi[(dof, n)] * self.phi[(dof, n)];
                mc * acc
            })
            .collect()
    }

    /// Delassus value W = Σ_n φ_n\[c\]² of the held modes at floor `dof`, 1/kg.
    pub fn delassus(&self, dof: usize) -> f64 {
        (0..self.n_modes())
            .map(|n| self.phi[(dof, n)].powi(2))
            .sum()
    }
}
