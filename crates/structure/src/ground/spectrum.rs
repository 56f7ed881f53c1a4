//! Elastic response spectra, exact for piecewise-linear excitation.
//!
//! For each period T (ω = 2π/T) the relative displacement of  x'' + 2ζωx' + ω²x = −a_g(t)
//! from rest is propagated exactly from sample to sample ([`Propagator`]); SD = max|x| over
//! the record's samples (the record duration only), PSV = ω·SD, PSA = ω²·SD. T = 0 gives
//! SD = 0 and PSA = PGA.

use super::{GroundMotion, Propagator};

/// One point of a spectrum: period (s), SD (m), PSV (m/s), PSA (m/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectrumPoint {
    pub period: f64,
    pub sd: f64,
    pub psv: f64,
    pub psa: f64,
}

/// Spectral displacement of one oscillator (ω in rad/s, ζ).
pub fn spectral_displacement(gm: &GroundMotion, omega: f64, zeta: f64) -> f64 {
    let p = Propagator::new(omega, zeta, gm.dt);
    let (mut x, mut v) = (0.0, 0.0);
    let mut sd: f64 = 0.0;
    for w in gm.accel.windows(2) {
        (x, v) = p.step(x, v, -w[0], -w[1]);
        sd = sd.max(x.abs());
    }
    sd
}

/// The response spectrum of `gm` at `periods` (s) for damping ratio `zeta`.
pub fn response_spectrum(gm: &GroundMotion, periods: &[f64], zeta: f64) -> Vec<SpectrumPoint> {
    periods
        .iter()
        .map(|&period| {
            if period <= 0.0 {
                return SpectrumPoint {
                    period,
                    sd: 0.0,
                    psv: 0.0,
                    psa: gm.pga(),
                };
            }
            let w = 2.0 * std::f64::consts::PI / period;
            let sd = spectral_displacement(gm, w, zeta);
            SpectrumPoint {
                period,
                sd,
                psv: w * sd,
                psa: w * w * sd,
            }
        })
        .collect()
}

/// 100 log-spaced periods from 0.02 s to 10 s.
pub fn default_periods() -> Vec<f64> {
    let (a, b) = (0.02f64.ln(), 10.0f64.ln());
    (0..100)
        .map(|i| (a + (b - a) * i as f64 / 99.0).exp())
        .collect()
}
