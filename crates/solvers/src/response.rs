//! Peak-response tracking and history sampling, shared by the three solvers.

use structure::Scene;

use crate::output::{BuildingResponse, History};

/// Tracks peak story shears and floor displacements of every building.
#[derive(Debug, Clone)]
pub struct ResponseTracker {
    stiffness: Vec<Vec<f64>>,
    shear_max: Vec<Vec<f64>>,
    disp_max: Vec<Vec<f64>>,
    names: Vec<String>,
    /// Offset of each building's first floor in a concatenated displacement vector.
    pub offsets: Vec<usize>,
    row: Vec<f64>,
    /// Floor velocities (m/s) and contact forces (N) of the next history sample.
    vrow: Vec<f64>,
    frow: Vec<f64>,
    /// Story shears (N) of the next history sample.
    srow: Vec<f64>,
    /// Peak |story drift| per story, m.
    drift_max: Vec<Vec<f64>>,
    /// Yield drift F_y/k₀ per story of a yielding building (m), `None` for a linear one.
    yield_drift: Vec<Option<Vec<f64>>>,
}

impl ResponseTracker {
    pub fn new(scene: &Scene) -> Self {
        let mut offsets = Vec::new();
        let mut off = 0;
        for b in &scene.buildings {
            offsets.push(off);
            off += b.n_floors();
        }
        ResponseTracker {
            stiffness: scene
                .buildings
                .iter()
                .map(|b| b.story_stiffness.clone())
                .collect(),
            shear_max: scene
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors()])
                .collect(),
            disp_max: scene
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors()])
                .collect(),
            names: scene.buildings.iter().map(|b| b.name.clone()).collect(),
            offsets,
            row: vec![0.0; off],
            vrow: vec![0.0; off],
            frow: vec![0.0; scene.contacts.len()],
            srow: vec![0.0; off],
            drift_max: scene
                .buildings
                .iter()
                .map(|b| vec![0.0; b.n_floors()])
                .collect(),
            yield_drift: scene
                .buildings
                .iter()
                .map(|b| {
                    b.story_law
                        .bilinear_params(&b.story_stiffness)
                        .map(|p| p.iter().map(|p| p.yield_drift()).collect())
                })
                .collect(),
        }
    }

    /// Records the floor displacements `u` (m) of building `b` at one instant, with the
    /// story shears `shear` (N) given by the story law (a yielding building).
    #[inline]
    pub fn observe_with_shear(&mut self, b: usize, u: &[f64], shear: &[f64]) {
        self.observe_peaks_with_shear(b, u, shear);
        let off = self.offsets[b];
        self.row[off..off + u.len()].copy_from_slice(u);
        self.srow[off..off + u.len()].copy_from_slice(&shear[..u.len()]);
    }

    /// [`Self::observe_peaks`] with the story shears `shear` (N) given by the story law.
    #[inline]
    pub fn observe_peaks_with_shear(&mut self, b: usize, u: &[f64], shear: &[f64]) {
        let vmax = &mut self.shear_max[b];
        let dmax = &mut self.disp_max[b];
        let drmax = &mut self.drift_max[b];
        let mut below = 0.0;
        for j in 0..u.len() {
            vmax[j] = vmax[j].max(shear[j].abs());
            dmax[j] = dmax[j].max(u[j].abs());
            drmax[j] = drmax[j].max((u[j] - below).abs());
            below = u[j];
        }
    }

    /// Current peak |story drift| (m) of story `j` of building `b`.
    #[inline]
    pub fn peak_drift(&self, b: usize, j: usize) -> f64 {
        self.drift_max[b][j]
    }

    /// Records the floor displacements `u` (m) of building `b` at one instant.
    #[inline]
    pub fn observe(&mut self, b: usize, u: &[f64]) {
        self.observe_peaks(b, u);
        let off = self.offsets[b];
        self.row[off..off + u.len()].copy_from_slice(u);
        let k = &self.stiffness[b];
        let mut below = 0.0;
        for (j, s) in self.srow[off..off + u.len()].iter_mut().enumerate() {
            *s = k[j] * (u[j] - below);
            below = u[j];
        }
    }

    /// Records the floor velocities `v` (m/s) of building `b` for the next history sample.
    #[inline]
    pub fn observe_velocity(&mut self, b: usize, v: &[f64]) {
        let off = self.offsets[b];
        self.vrow[off..off + v.len()].copy_from_slice(v);
    }

    /// Records the contact forces (N, compressive > 0, one per scene contact) for the next
    /// history sample.
    #[inline]
    pub fn observe_contact_forces(&mut self, f: &[f64]) {
        self.frow.copy_from_slice(f);
    }

    /// Updates the peaks of building `b` with the floor displacements `u` (m) at an instant
    /// that is not a history sample (an interior extremum found between samples).
    #[inline]
    pub fn observe_peaks(&mut self, b: usize, u: &[f64]) {
        let k = &self.stiffness[b];
        let vmax = &mut self.shear_max[b];
        let dmax = &mut self.disp_max[b];
        let drmax = &mut self.drift_max[b];
        let mut below = 0.0;
        for j in 0..u.len() {
            let dr = (u[j] - below).abs();
            if dr > drmax[j] {
                drmax[j] = dr;
            }
            let v = (k[j] * (u[j] - below)).abs();
            if v > vmax[j] {
                vmax[j] = v;
            }
            let d = u[j].abs();
            if d > dmax[j] {
                dmax[j] = d;
            }
            below = u[j];
        }
    }

    /// Current peak story shear (N) of story `j` and floor displacement (m) of floor `j` of
    /// building `b`.
    #[inline]
    pub fn peak(&self, b: usize, j: usize) -> (f64, f64) {
        (self.shear_max[b][j], self.disp_max[b][j])
    }

    /// After every building has been observed at time `t`, appends the sample to `history`.
    pub fn sample(&self, t: f64, history: Option<&mut History>) {
        if let Some(h) = history {
            h.time.push(t);
            h.displacement.push(self.row.clone());
            h.velocity.push(self.vrow.clone());
            h.contact_force.push(self.frow.clone());
            h.story_shear.push(self.srow.clone());
        }
    }

    /// The peaks, per building; the residual drift is the drift of the last observed
    /// instant (the end of the analysis: every solver observes it), the ductility demand
    /// the peak drift over the yield drift (yielding buildings).
    pub fn finish(self) -> Vec<BuildingResponse> {
        let row = self.row;
        self.names
            .into_iter()
            .zip(self.shear_max)
            .zip(self.disp_max)
            .zip(self.drift_max)
            .zip(self.yield_drift)
            .zip(self.offsets)
            .map(
                |(
                    ((((name, story_shear_max), floor_displacement_max), story_drift_max), yd),
                    off,
                )| {
                    let n = story_drift_max.len();
                    let u = &row[off..off + n];
                    let residual_drift = (0..n)
                        .map(|j| u[j] - if j > 0 { u[j - 1] } else { 0.0 })
                        .collect();
                    let ductility = yd.map(|yd| {
                        story_drift_max
                            .iter()
                            .zip(&yd)
                            .map(|(d, y)| d / y)
                            .collect()
                    });
                    BuildingResponse {
                        name,
                        story_shear_max,
                        floor_displacement_max,
                        story_drift_max,
                        residual_drift,
                        ductility,
                        hysteretic_energy: None,
                    }
                },
            )
            .collect()
    }
}

/// The coefficients [c1, c2, c3] of the cubic Hermite interpolant of (y0, ẏ0) and (y1, ẏ1)
/// over an interval of length `len`, H(θ) = y0 + c1 θ + c2 θ² + c3 θ³ (θ from 0 to 1).
#[inline]
pub fn hermite_cubic(y0: f64, yd0: f64, y1: f64, yd1: f64, len: f64) -> [f64; 3] {
    let (m0, m1) = (yd0 * len, yd1 * len);
    [
        m0,
        -3.0 * y0 - 2.0 * m0 + 3.0 * y1 - m1,
        2.0 * y0 + m0 - 2.0 * y1 + m1,
    ]
}

/// Position θ ∈ (0, 1) and value of the interior extremum of the cubic Hermite interpolant
/// of (y0, ẏ0) and (y1, ẏ1) over an interval of length `len`, if ẏ changes sign: the
/// detector of peaks between samples (both event-driven solvers).
pub fn hermite_extremum(y0: f64, yd0: f64, y1: f64, yd1: f64, len: f64) -> Option<(f64, f64)> {
    if !(yd0 * yd1 < 0.0) || !(len > 0.0) {
        return None;
    }
    // H'(θ) = c1 + 2 c2 θ + 3 c3 θ² changes sign on [0, 1] (H'(0) = m0, H'(1) = m1), so it
    // has exactly one root there: bisection.
    let [c1, c2, c3] = hermite_cubic(y0, yd0, y1, yd1, len);
    let theta = quadratic_root_in_unit(3.0 * c3, 2.0 * c2, c1);
    Some((theta, y0 + theta * (c1 + theta * (c2 + theta * c3))))
}

/// The root in [0, 1] of a t² + b t + c, which changes sign on [0, 1] (c and a + b + c of
/// opposite signs, so exactly one root lies there): the numerically stable quadratic
/// formula, bisection if round-off puts both roots outside.
fn quadratic_root_in_unit(a: f64, b: f64, c: f64) -> f64 {
    let inside = |t: f64| (0.0..=1.0).contains(&t);
    if a.abs() <= 1e-12 * (b.abs() + c.abs()) {
        let t = -c / b;
        if inside(t) {
            return t;
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            for t in [q / a, if q != 0.0 { c / q } else { f64::NAN }] {
                if inside(t) {
                    return t;
                }
            }
        }
    }
    bisect(|t| c + t * (b + t * a), 0.0, 1.0)
}

/// The sign change of `f` in [lo, hi] (f(lo) f(hi) ≤ 0 assumed) by 60 bisections.
pub fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let flo = f(lo);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) * flo > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_extremum_of_a_parabola_is_exact() {
        // y = 1 − (t − 0.3)² on [0, 1]: ẏ = −2(t − 0.3).
        let y = |t: f64| 1.0 - (t - 0.3) * (t - 0.3);
        let (th, h) = hermite_extremum(y(0.0), 0.6, y(1.0), -1.4, 1.0).unwrap();
        assert!(
            (th - 0.3).abs() < 1e-14 && (h - 1.0).abs() < 1e-14,
            "{th} {h}"
        );
        assert!(hermite_extremum(0.0, 1.0, 1.0, 1.0, 1.0).is_none());
    }
}
