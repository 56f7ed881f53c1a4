//! Overlap audit (issue 11): floors that face each other but have no contact of their own.
//!
//! A scene usually models contact at a few floor pairs only (the paper: the roofs). Every
//! other pair of facing floors ([`structure::Scene::facings`]: floor i with floor i, or
//! floors at the same elevation when both buildings give `story_height`) of two buildings
//! joined by at least one contact is audited: its overlap
//!
//! ```text
//! o(t) = u_left[i](t) − u_right[j](t) − gap        (m; > 0: the floors pass through each other)
//! ```
//!
//! is tracked to its maximum over the run. `left`/`right` and `gap` are those of the contact
//! *nearest* to the pair, with distance |i − i_c| + |j − j_c| in floors between the pair
//! (i, j) and the contact's floors (i_c, j_c), ties going to the smaller gap (the larger
//! overlap), then to the lower contact index. With one contact per building pair, as in
//! every shipped scene, that is simply its gap.
//!
//! The maximum is continuous where the solver can make it so: the momentum method takes
//! interior maxima between samples from the closed form (o is a linear combination of both
//! buildings' modal coordinates, [`crate::momentum::peaks`]); the adaptive gap element from
//! its dense output (to the integration tolerance); Newmark takes the maximum over its time
//! steps (sampled, no interpolation).

use structure::scene::UnmodelledFacing;
use structure::Scene;

use crate::output::Overlap;

/// A facing floor pair without a contact of its own.
#[derive(Debug, Clone, PartialEq)]
pub struct OverlapPair {
    /// Left and right building (indices in the scene) and floors (0-based), oriented as the
    /// contact whose gap is used.
    pub left: usize,
    pub left_dof: usize,
    pub right: usize,
    pub right_dof: usize,
    /// Gap of the nearest contact, m.
    pub gap: f64,
    /// Index of that contact in the scene.
    pub contact: usize,
}

/// The audited pairs of `scene`, in order of building pair, then floor of the first building.
pub fn pairs(scene: &Scene) -> Vec<OverlapPair> {
    let mut out = Vec::new();
    for (a, b) in scene.joined_pairs() {
        let joining: Vec<(usize, &structure::Contact)> = scene
            .contacts
            .iter()
            .enumerate()
            .filter(|(_, c)| (c.left.min(c.right), c.left.max(c.right)) == (a, b))
            .collect();
        // Floors of a and b of a contact (oriented a → b).
        let on_ab = |c: &structure::Contact| {
            if c.left == a {
                (c.left_dof, c.right_dof)
            } else {
                (c.right_dof, c.left_dof)
            }
        };
        for (i, j) in scene.facings(a, b).pairs {
            if joining.iter().any(|(_, c)| on_ab(c) == (i, j)) {
                continue;
            }
            let Some(&(ci, c)) = joining.iter().min_by(|(ci, c), (cj, d)| {
                let dist = |c: &structure::Contact| {
                    let (ia, jb) = on_ab(c);
                    ia.abs_diff(i) + jb.abs_diff(j)
                };
                dist(c)
                    .cmp(&dist(d))
                    .then(c.gap.total_cmp(&d.gap))
                    .then(ci.cmp(cj))
            }) else {
                continue;
            };
            let (left_dof, right_dof) = if c.left == a { (i, j) } else { (j, i) };
            out.push(OverlapPair {
                left: c.left,
                left_dof,
                right: c.right,
                right_dof,
                gap: c.gap,
                contact: ci,
            });
        }
    }
    out
}

/// Running maxima of u_left − u_right (m) of every audited pair, with their instants.
#[derive(Debug, Clone, Default)]
pub struct OverlapTracker {
    pub pairs: Vec<OverlapPair>,
    /// Largest u_left − u_right seen so far per pair, m (−∞ before the first sample).
    pub max: Vec<f64>,
    /// Its instant, s.
    pub time: Vec<f64>,
}

impl OverlapTracker {
    pub fn new(scene: &Scene) -> Self {
        let pairs = pairs(scene);
        let n = pairs.len();
        OverlapTracker {
            pairs,
            max: vec![f64::NEG_INFINITY; n],
            time: vec![0.0; n],
        }
    }

    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Offers the value `rel` = u_left − u_right (m) of pair `k` at time `t` (s).
    #[inline]
    pub fn offer(&mut self, k: usize, t: f64, rel: f64) {
        if rel > self.max[k] {
            self.max[k] = rel;
            self.time[k] = t;
        }
    }

    /// Offers every pair at time `t`, with `u(building, floor)` the floor displacement, m.
    #[inline]
    pub fn observe(&mut self, t: f64, u: impl Fn(usize, usize) -> f64) {
        for k in 0..self.pairs.len() {
            let p = &self.pairs[k];
            let rel = u(p.left, p.left_dof) - u(p.right, p.right_dof);
            self.offer(k, t, rel);
        }
    }

    /// The audit: one entry per pair, maximum overlap beyond the gap.
    pub fn finish(self, scene: &Scene) -> Vec<Overlap> {
        self.pairs
            .iter()
            .zip(self.max.iter().zip(&self.time))
            .map(|(p, (&m, &t))| Overlap {
                left: scene.buildings[p.left].name.clone(),
                left_floor: p.left_dof + 1,
                right: scene.buildings[p.right].name.clone(),
                right_floor: p.right_dof + 1,
                gap: p.gap,
                contact: p.contact,
                max_overlap: m - p.gap,
                time: t,
            })
            .collect()
    }
}

/// The worst overlap (largest `max_overlap`), if any pair is audited.
pub fn worst(overlaps: &[Overlap]) -> Option<&Overlap> {
    overlaps
        .iter()
        .max_by(|a, b| a.max_overlap.total_cmp(&b.max_overlap))
}

/// The facings the models leave out, for the run output.
pub fn unmodelled(scene: &Scene) -> Vec<UnmodelledFacing> {
    scene.unmodelled_facings()
}
