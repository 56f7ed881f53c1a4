//! Calibration of a shear stick to two target frequencies, or to one with a given taper.
//!
//! Uniform floor mass `m` and a linearly tapered story-stiffness profile with two parameters,
//!
//! ```text
//! k_j = K · (1 − β (j − 1) / n),   j = 1 … n,   β < 1
//! ```
//!
//! The frequency ratio f₂/f₁ depends on β alone (scaling K scales every ω by √K), so β is
//! found by Brent's method on the ratio, then K = K₀ (f₁ / f₁(K₀))². β = 0 is the uniform
//! stick, whose ratio is sin(3π/(2(2n+1))) / sin(π/(2(2n+1))) ≈ 3; a softer top (β > 0)
//! lowers the ratio, a softer base (β < 0) raises it. Ratios above ≈ 3 (both paper buildings:
//! 3.33 and 3.78) therefore need stories that stiffen with height: the planar shear stick
//! stands in for a flexural-shear building, whose higher modes are further apart.
//!
//! [`calibrate_first_frequency`] fixes the taper instead, through the ratio of the top to the
//! ground story stiffness r = k_n / k_1 = 1 − β (n − 1)/n, i.e. β = (1 − r) n / (n − 1)
//! (r = 1: uniform stick; r < 1: softer top), and fits K to the first frequency alone by the
//! same exact scaling ω ∝ √K.

use super::{Building, ModelError};

/// The result of a calibration: the building and its profile parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    pub building: Building,
    /// Base story stiffness K, N/m.
    pub k_base: f64,
    /// Taper β (dimensionless): the top story has stiffness K (1 − β (n−1)/n).
    pub taper: f64,
}

impl Calibration {
    /// Ratio of the top to the ground story stiffness, k_n / k_1 (dimensionless).
    pub fn top_to_ground_ratio(&self) -> f64 {
        top_to_ground(&self.building)
    }
}

/// k_n / k_1 of a building (1 for a single story).
pub fn top_to_ground(b: &Building) -> f64 {
    match (b.story_stiffness.first(), b.story_stiffness.last()) {
        (Some(k1), Some(kn)) => kn / k1,
        _ => f64::NAN,
    }
}

fn profile(n: usize, k: f64, beta: f64) -> Vec<f64> {
    (0..n)
        .map(|j| k * (1.0 - beta * j as f64 / n as f64))
        .collect()
}

fn first_two(b: &Building) -> Result<(f64, f64), ModelError> {
    let m = b.modes()?;
    Ok((m.omega[0], m.omega[1]))
}

/// Builds an `n`-floor stick of uniform floor mass `mass` (kg) whose first two frequencies
/// are `f1_hz` and `f2_hz`, with damping ratio `zeta` in every mode.
pub fn calibrate_two_frequencies(
    name: &str,
    n: usize,
    mass: f64,
    f1_hz: f64,
    f2_hz: f64,
    zeta: f64,
) -> Result<Calibration, ModelError> {
    let fail = |reason: String| ModelError::Calibration {
        building: name.to_string(),
        reason,
    };
    if n < 2 {
        return Err(fail(format!(
            "two target frequencies need at least 2 floors, got {n}"
        )));
    }
    if !(f1_hz.is_finite() && f2_hz.is_finite() && f1_hz > 0.0 && f2_hz > f1_hz) {
        return Err(fail(format!(
            "targets must satisfy 0 < f1 < f2, got {f1_hz} and {f2_hz} Hz"
        )));
    }
    // The same inputs give the same (K, β) bit for bit: remembered per process, since every
    // study case loads its scene anew (a building's calibration is ~50 eigenproblems).
    let key = (n, mass.to_bits(), f1_hz.to_bits(), f2_hz.to_bits());
    let memo = || TWO_FREQUENCIES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&(k, beta)) = memo().get(&key) {
        let building = Building::new(name, vec![mass; n], profile(n, k, beta), zeta);
        // The check a fresh calibration makes first (its eigenproblems validate the
        // building): the same error whether or not the process calibrated these targets.
        building.validate()?;
        return Ok(Calibration {
            building,
            k_base: k,
            taper: beta,
        });
    }
    let k0 = 1.0e9;
    let ratio_at = |beta: f64| -> Result<f64, ModelError> {
        let b = Building::new(name, vec![mass; n], profile(n, k0, beta), zeta);
        let (w1, w2) = first_two(&b)?;
        Ok(w2 / w1)
    };
    let target = f2_hz / f1_hz;
    // β range: from a base 50× softer than the top to a top 50× softer than the base.
    let hi_beta = (1.0 - 0.02) * n as f64 / (n as f64 - 1.0);
    let lo_beta = -49.0 * n as f64 / (n as f64 - 1.0);
    let (r_lo, r_hi) = (ratio_at(lo_beta)?, ratio_at(hi_beta)?);
    if !(r_lo.min(r_hi) <= target && target <= r_lo.max(r_hi)) {
        return Err(fail(format!(
            "the ratio f2/f1 = {target:.4} is outside what a linear taper reaches ({:.4} … {:.4})",
            r_hi.min(r_lo),
            r_hi.max(r_lo)
        )));
    }
    let g = |beta: f64| ratio_at(beta).map_or(f64::NAN, |r| r - target);
    let mut conv = roots::SimpleConvergency {
        eps: 1e-14,
        max_iter: 200,
    };
    let beta = roots::find_root_brent(lo_beta, hi_beta, g, &mut conv)
        .map_err(|e| fail(format!("root search for the taper failed: {e:?}")))?;
    let b0 = Building::new(name, vec![mass; n], profile(n, k0, beta), zeta);
    let (w1, _) = first_two(&b0)?;
    let k = k0 * (2.0 * std::f64::consts::PI * f1_hz / w1).powi(2);
    let building = Building::new(name, vec![mass; n], profile(n, k, beta), zeta);
    memo().insert(key, (k, beta));
    Ok(Calibration {
        building,
        k_base: k,
        taper: beta,
    })
}

/// (K, β) of [`calibrate_two_frequencies`] by (floors, floor mass, f₁, f₂) as bit patterns
/// (the frequencies do not depend on the name or the damping ratio).
type TwoFrequencyKey = (usize, u64, u64, u64);
static TWO_FREQUENCIES: std::sync::LazyLock<
    std::sync::Mutex<std::collections::HashMap<TwoFrequencyKey, (f64, f64)>>,
> = std::sync::LazyLock::new(Default::default);

/// Builds an `n`-floor stick of uniform floor mass `mass` (kg) with a linear stiffness taper
/// whose top story is `top_ratio` (dimensionless, > 0) times its ground story, scaled so that
/// its first frequency is `f1_hz` (Hz); damping ratio `zeta` in every mode. `top_ratio = 1`
/// gives the uniform stick.
pub fn calibrate_first_frequency(
    name: &str,
    n: usize,
    mass: f64,
    f1_hz: f64,
    top_ratio: f64,
    zeta: f64,
) -> Result<Calibration, ModelError> {
    let fail = |reason: String| ModelError::Calibration {
        building: name.to_string(),
        reason,
    };
    if n == 0 {
        return Err(fail("a building needs at least one floor".into()));
    }
    if !(f1_hz.is_finite() && f1_hz > 0.0) {
        return Err(fail(format!(
            "the target frequency must be finite and > 0, got {f1_hz} Hz"
        )));
    }
    if !(top_ratio.is_finite() && top_ratio > 0.0) {
        return Err(fail(format!(
            "the top-to-ground story stiffness ratio must be finite and > 0, got {top_ratio}"
        )));
    }
    if n == 1 && top_ratio != 1.0 {
        return Err(fail(format!(
            "a one-story building has no taper: its top-to-ground ratio is 1, got {top_ratio}"
        )));
    }
    let beta = if n == 1 {
        0.0
    } else {
        (1.0 - top_ratio) * n as f64 / (n as f64 - 1.0)
    };
    let k0 = 1.0e9;
    let b0 = Building::new(name, vec![mass; n], profile(n, k0, beta), zeta);
    let w1 = b0.modes()?.omega[0];
    let k = k0 * (2.0 * std::f64::consts::PI * f1_hz / w1).powi(2);
    let building = Building::new(name, vec![mass; n], profile(n, k, beta), zeta);
    Ok(Calibration {
        building,
        k_base: k,
        taper: beta,
    })
}
