//! The result of one analysis, common to the three methods (the `pound run --out` JSON).

use serde::Serialize;

/// Peak responses of one building.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct BuildingResponse {
    pub name: String,
    /// Peak |story shear| per story, N, story 1 first (V_j = k_j (u_j − u_{j−1}) for linear
    /// stories; the story law's force for yielding ones).
    pub story_shear_max: Vec<f64>,
    /// Peak |floor displacement| relative to the ground, m, floor 1 first.
    pub floor_displacement_max: Vec<f64>,
    /// Peak |story drift| |u_j − u_{j−1}| per story, m, story 1 first.
    pub story_drift_max: Vec<f64>,
    /// Story drift u_j − u_{j−1} at the end of the analysis, m, story 1 first (signed; the
    /// permanent set of a yielded story once the motion has died out). Empty for the
    /// momentum method.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub residual_drift: Vec<f64>,
    /// Ductility demand per story, peak drift / yield drift F_y/k₀ (dimensionless; > 1 when
    /// the story yielded); only for a building with `story_law = "bilinear"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ductility: Option<Vec<f64>>,
    /// Energy dissipated by yielding in this building's stories, J (plastic work less the
    /// hardening energy still stored); only for a building with `story_law = "bilinear"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hysteretic_energy: Option<f64>,
}

impl BuildingResponse {
    /// Fills `story_drift_max` of a linear building from its peak shears: |d_j| = |V_j|/k_j
    /// at every instant, so the peaks are at the same instants (methods that track shears
    /// only, such as the momentum method).
    pub fn drifts_from_shears(&mut self, story_stiffness: &[f64]) {
        if self.story_drift_max.is_empty() {
            self.story_drift_max = self
                .story_shear_max
                .iter()
                .zip(story_stiffness)
                .map(|(v, k)| v / k)
                .collect();
        }
    }
}

/// One impact (momentum method) or one contact episode (gap element).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Impact {
    /// Index of the contact in the scene.
    pub contact: usize,
    /// Instant of impact (momentum) or of contact closure (gap element), s.
    pub time: f64,
    /// u̇_left − u̇_right just before, m/s (> 0 when approaching).
    pub relative_velocity_before: f64,
    /// u̇_left − u̇_right just after the impulse or at contact opening, m/s.
    pub relative_velocity_after: f64,
    /// −after / before: the restitution actually achieved. NaN (`null` in JSON) for a
    /// momentum-method impact whose approach speed is below `momentum.capture_velocity`
    /// (a touching contact, such as the capture that starts a persistent phase).
    pub achieved_restitution: f64,
    /// Why `achieved_restitution` is undefined (`null`), when it is: e.g. "touching"
    /// (approach speed below the capture threshold) or "separating at closure".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restitution_undefined: Option<String>,
    /// Impulse transmitted, N·s.
    pub impulse: f64,
    /// Contact duration, s (gap element only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// Peak contact force, N (gap element only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_force: Option<f64>,
    /// Largest penetration δ, m (gap element only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_penetration: Option<f64>,
}

/// A phase in which two floors move together (momentum and impulse methods, c_r < 1).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PersistentContact {
    pub contact: usize,
    /// Start and end of the phase, s (end = analysis end if still in contact).
    pub start: f64,
    pub end: f64,
    /// Why it ended: "tension" (contact force would turn tensile), "impact" (an impact at
    /// another contact pulled the floors apart) or "end of analysis".
    pub released_by: String,
}

/// Energy audit, J. balance_error = initial + input − damping − contact − hysteretic − final.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct EnergyAudit {
    /// Kinetic + strain energy at the start (relative motion).
    pub initial: f64,
    /// Work done by the ground (effective earthquake forces −M 1 a_g).
    pub input: f64,
    /// Dissipated by the classical viscous damping.
    pub damping: f64,
    /// Lost in impacts (momentum) or dissipated by the contact element (gap element).
    pub contact: f64,
    /// Dissipated by yielding stories: plastic work ∫ V du_p less the energy ½ α²/H still
    /// stored in the hardening springs (0 for linear buildings).
    pub hysteretic: f64,
    /// Kinetic + recoverable strain energy at the end (plus energy stored in contact
    /// springs); a yielding story holds ½ k₀ (d − u_p)² + ½ α²/H.
    #[serde(rename = "final")]
    pub final_: f64,
    /// initial + input − damping − contact − hysteretic − final.
    pub balance_error: f64,
    /// Newmark only (`None`, and absent from the JSON, for the other solvers): the work
    /// Σ Δuᵀ (r_n + r_{n+1})/2 of the equilibrium residuals r = p − M a − C v − K u − F_c that
    /// its Newton iterations leave at the accepted steps (each within 1e-10 of the step's
    /// force scale). Average-acceleration Newmark conserves the discrete energy exactly on
    /// linear stories, so `balance_error` less this is round-off there: the balance error
    /// is the convergence tolerance's, not the scheme's (a kinked yielding story adds its
    /// O(Δt²) trapezoidal error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_work: Option<f64>,
}

impl EnergyAudit {
    /// The audit of these terms (J) with its balance error: the one place every solver
    /// closes the balance.
    pub fn closed(
        initial: f64,
        input: f64,
        damping: f64,
        contact: f64,
        hysteretic: f64,
        final_: f64,
    ) -> EnergyAudit {
        EnergyAudit {
            initial,
            input,
            damping,
            contact,
            hysteretic,
            final_,
            balance_error: initial + input - damping - contact - hysteretic - final_,
            residual_work: None,
        }
    }
}

/// Contact flexibility fractions r_N at each contact with the modes actually kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactFlexibility {
    pub contact: usize,
    pub modes_left: usize,
    pub modes_right: usize,
    pub r_n_left: f64,
    pub r_n_right: f64,
}

/// Overlap audit of one facing floor pair without a contact of its own (see
/// [`crate::overlap`]): floors that pass through each other in the model.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Overlap {
    /// Left building and floor (1-based), as in the scene, oriented as the contact whose gap
    /// is used.
    pub left: String,
    pub left_floor: usize,
    pub right: String,
    pub right_floor: usize,
    /// Gap used, m: that of the contact nearest to this pair (in floors).
    pub gap: f64,
    /// Index of that contact in the scene.
    pub contact: usize,
    /// max over the run of u_left − u_right − gap, m: > 0 when the floors overlap beyond the
    /// gap, < 0 when the gap is never closed.
    pub max_overlap: f64,
    /// Instant of that maximum, s.
    pub time: f64,
}

/// Solver statistics of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Stats {
    /// Accepted time steps (momentum: propagation segments).
    pub steps: u64,
    /// Rejected adaptive steps.
    pub rejected_steps: u64,
    /// Right-hand-side evaluations (adaptive).
    pub rhs_evaluations: u64,
    /// Located events (closures, openings, releases).
    pub events: u64,
    /// Impacts (momentum) or contact episodes (gap element).
    pub impacts: u64,
    /// Root-finder iterations spent locating events.
    pub root_iterations: u64,
    /// Located kinks of yielding stories (yield and unloading): adaptive gap element and
    /// impulse method (0 for the momentum method and Newmark, which do not locate them).
    pub story_kinks: u64,
    /// Newton iterations (Newmark).
    pub newton_iterations: u64,
    /// Newmark: extra Newton solves because a contact's state (carrying force or not)
    /// assumed for the step was inconsistent with the law at its solution (active set).
    pub active_set_iterations: u64,
    /// Newmark: steps in which no contact-state set was consistent (a contact opens and
    /// closes again inside the step); the contacts whose closed force was compressive were
    /// kept closed and the step accepted, the state change falling to the next step.
    pub contact_state_fallbacks: u64,
    /// Smallest and largest accepted step, s.
    pub min_step: f64,
    pub max_step: f64,
    /// Wall-clock time of the analysis, s.
    pub wall_seconds: f64,
}

/// The full result of one analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunOutput {
    /// "momentum" or "gap".
    pub method: String,
    /// Solver settings in words (e.g. "consistent impulse, 10 modes" or "kelvin-voigt k=1e10 adaptive tol=1e-8").
    pub settings: String,
    pub scene: String,
    /// Simulated duration, s.
    pub duration: f64,
    pub buildings: Vec<BuildingResponse>,
    pub impacts: Vec<Impact>,
    pub persistent_contacts: Vec<PersistentContact>,
    pub energy: EnergyAudit,
    pub stats: Stats,
    pub r_n: Vec<ContactFlexibility>,
    /// Overlap audit: one entry per facing floor pair of two buildings joined by a contact
    /// that has no contact of its own (empty when every facing pair has one).
    pub overlaps: Vec<Overlap>,
    /// Floors that would strike an adjacent building mid-story (floor-to-column impact, not
    /// modelled); only with `story_height` on both buildings.
    pub unmodelled: Vec<structure::scene::UnmodelledFacing>,
}

impl RunOutput {
    /// The result of `method` on `scene` with the fields every solver fills alike (scene
    /// name, duration, the overlap audit's maxima, the unmodelled facing floors) and no
    /// impacts, persistent contacts or r_N (set them with struct update syntax).
    pub(crate) fn on_scene(
        scene: &structure::Scene,
        method: &str,
        settings: String,
        buildings: Vec<BuildingResponse>,
        energy: EnergyAudit,
        stats: Stats,
        overlaps: crate::overlap::OverlapTracker,
    ) -> RunOutput {
        RunOutput {
            method: method.into(),
            settings,
            scene: scene.name.clone(),
            duration: scene.duration,
            buildings,
            impacts: Vec::new(),
            persistent_contacts: Vec::new(),
            energy,
            stats,
            r_n: Vec::new(),
            overlaps: overlaps.finish(scene),
            unmodelled: crate::overlap::unmodelled(scene),
        }
    }
}

/// Sampled state over time: at every record point (for the momentum method, every base step:
/// a record step it splits is sampled at its parts) and at every event instant (impact,
/// contact closure or opening, release), so the grid is not uniform.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct History {
    /// s.
    pub time: Vec<f64>,
    /// Floor displacements relative to the ground, m. One row per sample: the floors of
    /// building 0 (floor 1 first), then building 1, …
    pub displacement: Vec<Vec<f64>>,
    /// Floor velocities relative to the ground, m/s, same layout. At an impact instant
    /// the sample after the velocity jump.
    pub velocity: Vec<Vec<f64>>,
    /// Contact forces, N (compressive > 0), one per scene contact. The gap element: the
    /// force of its law. The momentum method: the holding force of a persistent contact
    /// (linear in time over each held segment, from the instantaneous force at its start),
    /// 0 in free flight; the impulse method: the
    /// instantaneous holding force λ = W⁻¹ δ̈_free of a held contact. Impacts of both are
    /// impulses (finite momentum in zero time), listed in `RunOutput::impacts`, not forces.
    pub contact_force: Vec<Vec<f64>>,
    /// Story shears, N, one row per sample, stories in the layout of the floors (story j of
    /// a building below its floor j): k_j (u_j − u_{j−1}) for linear stories, the story law's
    /// force (which depends on the history, not on the drift alone) for yielding ones.
    pub story_shear: Vec<Vec<f64>>,
}
