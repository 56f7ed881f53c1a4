//! Peak-response tracking and history sampling, shared by both solvers.

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
        }
    }

    /// Records the floor displacements `u` (m) of building `b` at one instant.
    #[inline]
    pub fn observe(&mut self, b: usize, u: &[f64]) {
        let k = &self.stiffness[b];
        let vmax = &mut self.shear_max[b];
        let dmax = &mut self.disp_max[b];
        let mut below = 0.0;
        for j in 0..u.len() {
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
        let off = self.offsets[b];
        self.row[off..off + u.len()].copy_from_slice(u);
    }

    /// Stores the floor displacements `u` of building `b` for the history row only, without
    /// updating the peaks (instants that are not peak-sampling instants).
    #[inline]
    pub fn history_row(&mut self, b: usize, u: &[f64]) {
        let off = self.offsets[b];
        self.row[off..off + u.len()].copy_from_slice(u);
    }

    /// After every building has been observed at time `t`, appends the sample to `history`.
    pub fn sample(&self, t: f64, history: Option<&mut History>) {
        if let Some(h) = history {
            h.time.push(t);
            h.displacement.push(self.row.clone());
        }
    }

    /// The peaks, per building.
    pub fn finish(self) -> Vec<BuildingResponse> {
        self.names
            .into_iter()
            .zip(self.shear_max)
            .zip(self.disp_max)
            .map(
                |((name, story_shear_max), floor_displacement_max)| BuildingResponse {
                    name,
                    story_shear_max,
                    floor_displacement_max,
                },
            )
            .collect()
    }
}
