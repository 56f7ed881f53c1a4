//! The sweep engine: cases with stable ids, parallel and resumable execution, shards.
//!
//! A study expands into a list of [`CaseSpec`]s (a base scene file, `--set` overrides, a
//! record, a method). Each case has a stable id, the FNV-1a hash of its canonical
//! parameters (scene path, method, record, PGA, sorted overrides, history flag, repeats),
//! so it is the same on every machine and in every run. Cases run in parallel with rayon;
//! results are collected in case order, so nothing downstream depends on the thread count.
//!
//! Every finished case is written at once to `<out>/<study>/cases/<id>.json` (atomically);
//! a rerun loads those files and skips the cases. With a shard `i/n` only the cases whose
//! index satisfies `index % n == i − 1` run. A failed case (bad scene, solver error, even a
//! panic) is a result with its reason, never a crashed sweep.
//!
//! Reports are always built from the case files as read back from disk, so a single run, a
//! resumed run and a merge of shards produce bit-identical tables and figures.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use solvers::{History, Method, SolverError};
use structure::{Scene, SceneError};

use crate::io::{write_atomic, write_json, OutputError};

/// Errors of the sweep engine and of the studies.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{file}: {message}")]
    Definition { file: String, message: String },
    #[error("cannot read {path}: {message}")]
    Read { path: String, message: String },
    #[error("study `{study}`: {missing} of {total} cases have no result (missing ids: {ids})")]
    Incomplete {
        study: String,
        missing: usize,
        total: usize,
        ids: String,
    },
    /// A case file that `studies merge` would use cannot be read or parsed (truncated,
    /// corrupt) or holds another case.
    #[error("{path}: not a usable case file ({message}), and no other copy of the case parses; rerun the shard that wrote it (a rerun recomputes the case files it cannot read), or remove the file and rerun that shard")]
    CaseFile { path: String, message: String },
    /// A study manifest that `studies merge` reads does not parse (truncated, corrupt).
    #[error("{path}: not a usable study manifest ({message}); rerun the shard that wrote it")]
    Manifest { path: String, message: String },
    /// `studies merge` found no `<study>/manifest.json` under any of the folders.
    #[error("no study manifests found under {dirs}")]
    NoManifests { dirs: String },
    #[error("{0}")]
    Other(String),
}

pub type Result<T> = std::result::Result<T, StudyError>;

/// FNV-1a, 64 bits: a hash that is the same everywhere (unlike Rust's seeded hasher).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// One analysis to run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseSpec {
    /// Stable id (16 hex digits), see [`CaseSpec::compute_id`].
    pub id: String,
    /// Base scene file, relative to the studies folder (or absolute).
    pub scene: String,
    pub method: Method,
    /// Ground-motion record replacing the scene's: relative to the studies folder, or absolute.
    pub record: Option<String>,
    /// Target PGA (g) of the record.
    pub pga: Option<f64>,
    /// `PATH=VALUE` overrides, sorted.
    pub set: Vec<String>,
    /// Keep the top-floor displacement histories of the contact floors.
    pub history: bool,
    /// Run this many times and keep the fastest wall time (cost studies). A timed case
    /// (`repeat` > 1) runs alone: after the study's other cases, one analysis at a time, so
    /// no other case shares the machine with it, and in rounds with the other timed cases
    /// (every one once, then again; see [`run_interleaved`]).
    pub repeat: u32,
    /// Labels for tables; not part of the id.
    pub params: BTreeMap<String, serde_json::Value>,
    /// The solver error this case exists to show (e.g. `Stalled`: a study of where a
    /// method fails); such a failure is a result, not a failed sweep. Not part of the id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expect_failure: Option<String>,
}

impl CaseSpec {
    /// A case of `scene` with `method`; add overrides with [`CaseSpec::with`].
    pub fn new(scene: &str, method: Method) -> Self {
        let mut c = CaseSpec {
            id: String::new(),
            scene: scene.to_string(),
            method,
            record: None,
            pga: None,
            set: Vec::new(),
            history: false,
            repeat: 1,
            params: BTreeMap::new(),
            expect_failure: None,
        };
        c.compute_id();
        c
    }

    /// Adds (or replaces) an override `path=value`.
    pub fn with(mut self, path: &str, value: impl std::fmt::Display) -> Self {
        let prefix = format!("{path}=");
        self.set.retain(|s| !s.starts_with(&prefix));
        self.set.push(format!("{path}={value}"));
        self.set.sort();
        self.compute_id();
        self
    }

    /// Removes every override whose path starts with `prefix`.
    pub fn without(mut self, prefix: &str) -> Self {
        self.set.retain(|s| !s.starts_with(prefix));
        self.compute_id();
        self
    }

    pub fn record(mut self, record: &str, pga: Option<f64>) -> Self {
        self.record = Some(record.to_string());
        self.pga = pga;
        self.compute_id();
        self
    }

    pub fn history(mut self, on: bool) -> Self {
        self.history = on;
        self.compute_id();
        self
    }

    pub fn repeat(mut self, n: u32) -> Self {
        self.repeat = n.max(1);
        self.compute_id();
        self
    }

    /// Marks the case as one that exists to show the solver error `kind`.
    pub fn expect_failure(mut self, kind: &str) -> Self {
        self.expect_failure = Some(kind.to_string());
        self
    }

    pub fn param(mut self, key: &str, value: impl Into<serde_json::Value>) -> Self {
        self.params.insert(key.to_string(), value.into());
        self
    }

    /// The canonical text hashed into the id.
    pub fn canonical(&self) -> String {
        let mut s = format!("scene={}\nmethod={}\n", self.scene, self.method);
        if let Some(r) = &self.record {
            s.push_str(&format!("record={r}\n"));
        }
        if let Some(p) = self.pga {
            s.push_str(&format!("pga={p:e}\n"));
        }
        let mut set = self.set.clone();
        set.sort();
        for o in set {
            s.push_str(&format!("set={o}\n"));
        }
        if self.history {
            s.push_str("history\n");
        }
        if self.repeat > 1 {
            s.push_str(&format!("repeat={}\n", self.repeat));
        }
        s
    }

    pub fn compute_id(&mut self) {
        self.id = format!("{:016x}", fnv1a64(self.canonical().as_bytes()));
    }

    /// The value of override `path`, if set.
    pub fn get(&self, path: &str) -> Option<&str> {
        let prefix = format!("{path}=");
        self.set
            .iter()
            .find_map(|s| s.strip_prefix(prefix.as_str()))
    }

    /// The same analysis without impact: contact overrides dropped (a whole `contacts=[…]`
    /// list too, so the scene's own contacts come back) and contact 0 pushed 1 km away,
    /// contact-law options dropped (they cannot matter), integrator options kept.
    pub fn baseline(&self) -> CaseSpec {
        let mut b = self.clone();
        b.set.retain(|s| {
            !(s.starts_with("contacts.")
                || s.starts_with("contacts=")
                || s.starts_with("gap_element.stiffness=")
                || s.starts_with("gap_element.law=")
                || s.starts_with("gap_element.tension=")
                || s.starts_with("momentum.impulse=")
                || s.starts_with("momentum.persistent_contact=")
                || s.starts_with("momentum.capture_velocity="))
        });
        b.params = BTreeMap::new();
        b.params.insert("baseline".into(), true.into());
        b.params
            .insert("variant".into(), "baseline without contact".into());
        if let Some(r) = self.params.get("record") {
            b.params.insert("record".into(), r.clone());
        }
        b.expect_failure = None;
        b.repeat = 1;
        b = b.with("contacts.0.gap", "1000.0").history(true);
        b
    }

    fn resolve(path: &str, studies_dir: &Path) -> PathBuf {
        let p = Path::new(path);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            studies_dir.join(p)
        }
    }

    /// Loads the scene of this case.
    pub fn load_scene(&self, studies_dir: &Path) -> std::result::Result<Scene, String> {
        self.try_scene(studies_dir).map_err(|e| e.to_string())
    }

    /// [`CaseSpec::load_scene`] with the scene's own error (its key, for the message that
    /// names the override that set it).
    pub fn try_scene(&self, studies_dir: &Path) -> std::result::Result<Scene, SceneError> {
        let mut set = self.set.clone();
        if let Some(r) = &self.record {
            let path = Self::resolve(r, studies_dir);
            let abs = std::path::absolute(&path).unwrap_or(path);
            set.push(format!("ground_motion.file={}", abs.display()));
            if let Some(p) = self.pga {
                set.push(format!("ground_motion.pga={p:?}"));
            }
        }
        Scene::from_file_with_overrides(&Self::resolve(&self.scene, studies_dir), &set)
    }
}

/// Displacement histories of the two floors of contact 0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactHistory {
    pub time: Vec<f64>,
    /// Left floor of contact 0, m.
    pub u_left: Vec<f64>,
    /// Right floor of contact 0, m.
    pub u_right: Vec<f64>,
}

/// What a finished case keeps of its run (all deterministic).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseOutputs {
    pub settings: String,
    /// Building names, as in the scene.
    #[serde(default)]
    pub buildings: Vec<String>,
    /// Per building: the floor (from 1) where contact 0 meets it, if it does. The story
    /// below that floor is the "contact story" the studies report.
    #[serde(default)]
    pub contact_floor: Vec<Option<usize>>,
    /// Peak |story shear|, N, per building, story 1 first.
    pub story_shear_max: Vec<Vec<f64>>,
    /// Peak |floor displacement|, m, per building, floor 1 first.
    pub floor_displacement_max: Vec<Vec<f64>>,
    /// Peak |story drift| u_j − u_{j−1}, m, per building, story 1 first (empty in case
    /// files written before it existed).
    #[serde(default)]
    pub story_drift_max: Vec<Vec<f64>>,
    /// Story drift at the end of the analysis, m, per building, story 1 first: the residual
    /// drift of yielding stories (empty when the solver does not report it).
    #[serde(default)]
    pub story_drift_residual: Vec<Vec<f64>>,
    /// Hysteretic energy dissipated by yielding stories, J (energy audit; 0 for linear
    /// buildings); None in case files written before it existed.
    #[serde(default)]
    pub energy_hysteretic: Option<f64>,
    /// Impacts (momentum) or contact episodes (gap element).
    pub impacts: usize,
    pub impact_times: Vec<f64>,
    /// Achieved restitution over the impacts with a finite value.
    pub restitution_mean: Option<f64>,
    pub restitution_min: Option<f64>,
    pub restitution_max: Option<f64>,
    /// Largest penetration (gap element), m.
    pub max_penetration: Option<f64>,
    /// Approach speeds u̇_left − u̇_right just before the impacts (gap element: at contact
    /// closure) that approach (> 0), m/s: median and largest; None without such an impact.
    #[serde(default)]
    pub approach_speed_median: Option<f64>,
    #[serde(default)]
    pub approach_speed_max: Option<f64>,
    pub persistent_contacts: usize,
    /// Impacts (entries with a defined restitution) whose approach speed is ≤ 0.
    #[serde(default)]
    pub impacts_nonpositive_approach: usize,
    /// Defined achieved restitutions outside [0, 1].
    #[serde(default)]
    pub restitution_outside_unit: usize,
    /// Entries whose achieved restitution is null (with a reason: touching, grazing, …).
    #[serde(default)]
    pub restitution_undefined: usize,
    pub energy_input: f64,
    pub energy_contact: f64,
    pub energy_balance_error: f64,
    pub steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
    pub events: u64,
    pub newton_iterations: u64,
    /// r_N of contact 0, left and right.
    pub r_n: Option<(f64, f64)>,
    /// Peak of u_left − u_right at contact 0 over the history (cases with a history).
    pub peak_closure: Option<f64>,
    /// Contact-floor histories (cases with `history`, except baselines).
    pub contact_history: Option<ContactHistory>,
    /// Overlap audit (facing floors without a contact of their own): the worst pair, if
    /// any pair is audited.
    #[serde(default)]
    pub worst_overlap: Option<solvers::Overlap>,
    /// How many audited pairs overlap beyond the gap.
    #[serde(default)]
    pub overlaps_beyond_gap: usize,
}

/// The record of one case: parameters, outputs or failure, wall time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    pub spec: CaseSpec,
    /// "ok" or "failed".
    pub status: String,
    /// Failure class (solver error variant, `Scene`, `Panic`).
    pub error_kind: Option<String>,
    pub error: Option<String>,
    pub outputs: Option<CaseOutputs>,
    /// Wall-clock seconds of the analysis (fastest of `repeat`); not deterministic.
    pub wall_seconds: f64,
    /// Wall-clock seconds of every repeat, in the order run (for the spread); not
    /// deterministic. Empty in case files written before it existed.
    #[serde(default)]
    pub wall_seconds_all: Vec<f64>,
}

impl CaseResult {
    pub fn ok(&self) -> Option<&CaseOutputs> {
        self.outputs.as_ref()
    }

    /// Whether the outcome is not the one the case was defined for: a failure of a case
    /// not marked [`CaseSpec::expect_failure`] (or failing with another error), or a case
    /// marked so that finished.
    pub fn unexpected(&self) -> bool {
        match (&self.spec.expect_failure, self.status.as_str()) {
            (None, status) => status != "ok",
            (Some(_), "ok") => true,
            (Some(kind), _) => self.error_kind.as_deref() != Some(kind.as_str()),
        }
    }
}

fn solver_error_kind(e: &SolverError) -> &'static str {
    match e {
        SolverError::StepSizeUnderflow { .. } => "StepSizeUnderflow",
        SolverError::NonFinite { .. } => "NonFinite",
        SolverError::NewtonFailure { .. } => "NewtonFailure",
        SolverError::StepBudget { .. } => "StepBudget",
        SolverError::EventStorm { .. } => "EventStorm",
        SolverError::Stalled { .. } => "Stalled",
        SolverError::SingularContact { .. } => "SingularContact",
        SolverError::Refused { .. } => "Refused",
        SolverError::Model(_) => "Model",
    }
}

fn failed(spec: &CaseSpec, kind: &str, msg: String, wall: f64) -> CaseResult {
    CaseResult {
        spec: spec.clone(),
        status: "failed".into(),
        error_kind: Some(kind.into()),
        error: Some(msg),
        outputs: None,
        wall_seconds: wall,
        wall_seconds_all: vec![wall],
    }
}

/// The scene of a case as it runs: the file with the case's overrides, and for a baseline
/// every contact moved 1 km apart. A scene that cannot be read is the case's failed result.
fn prepare(spec: &CaseSpec, studies_dir: &Path) -> std::result::Result<Scene, Box<CaseResult>> {
    let mut scene = spec
        .load_scene(studies_dir)
        .map_err(|e| Box::new(failed(spec, "Scene", e, 0.0)))?;
    if spec.params.contains_key("baseline") {
        // The same model without contact: every contact (not only entry 0 of the file, which
        // the override moved) 1 km apart, so a scene with several contact entries has no
        // active contact either; the contact floors stay known for the separation outputs.
        for c in &mut scene.contacts {
            c.gap = 1000.0;
        }
    }
    Ok(scene)
}

/// One analysis of a case and its wall time (s); a solver error or a panic is the case's
/// failed result, with that run's wall time.
fn run_once(
    spec: &CaseSpec,
    scene: &Scene,
) -> std::result::Result<(solvers::RunOutput, Option<History>, f64), Box<CaseResult>> {
    let t0 = Instant::now();
    let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut hist = spec.history.then(History::default);
        let r = solvers::run(scene, spec.method, hist.as_mut());
        (r, hist)
    }));
    let wall = t0.elapsed().as_secs_f64();
    match res {
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            Err(Box::new(failed(spec, "Panic", msg, wall)))
        }
        Ok((Err(e), _)) => Err(Box::new(failed(
            spec,
            solver_error_kind(&e),
            e.to_string(),
            wall,
        ))),
        Ok((Ok(run), hist)) => Ok((run, hist, wall)),
    }
}

/// Runs one case `repeat` times in a row (never panics: a panic inside the solver becomes a
/// failed case): [`run_interleaved`] with this case alone. [`run_cases`] runs the timed
/// cases of a sweep together, in rounds.
pub fn run_case(spec: &CaseSpec, studies_dir: &Path) -> CaseResult {
    let mut out = None;
    run_interleaved(&[spec], studies_dir, |_, r| {
        out = Some(r);
        Ok(())
    })
    .expect("the callback does not fail");
    out.expect("a case always has a result")
}

/// The order in which [`run_interleaved`] runs the repeats of cases with these `repeat`
/// counts: rounds, each running once every case that has repeats left, in case order
/// (`[2, 3, 1]` gives cases 0, 1, 2, 0, 1, 1).
pub fn rounds(repeats: &[u32]) -> Vec<usize> {
    let most = repeats.iter().map(|&r| r.max(1)).max().unwrap_or(0);
    (0..most)
        .flat_map(|round| {
            repeats
                .iter()
                .enumerate()
                .filter(move |(_, &r)| round < r.max(1))
                .map(|(i, _)| i)
        })
        .collect()
}

/// Runs timed cases one analysis at a time in [`rounds`]: every case once, then every case
/// again, and so on, so that a slow spell of a shared machine falls on one repeat of many
/// settings, which the fastest of the repeats then leaves out, rather than on every repeat of
/// one setting (the ratios of a cost study compare settings). A case that fails is not run
/// again. `done` is called with each case's result as it completes (never panics).
pub fn run_interleaved(
    specs: &[&CaseSpec],
    studies_dir: &Path,
    mut done: impl FnMut(&CaseSpec, CaseResult) -> Result<()>,
) -> Result<()> {
    /// A timed case between rounds: its scene, the wall times so far and the last run.
    struct Running {
        scene: Scene,
        walls: Vec<f64>,
        last: Option<(solvers::RunOutput, Option<History>)>,
    }
    let mut running: Vec<Option<Running>> = Vec::with_capacity(specs.len());
    // Cases whose scene cannot be read are done before any analysis.
    for spec in specs {
        match prepare(spec, studies_dir) {
            Ok(scene) => running.push(Some(Running {
                scene,
                walls: Vec::new(),
                last: None,
            })),
            Err(f) => {
                running.push(None);
                done(spec, *f)?;
            }
        }
    }
    let repeats: Vec<u32> = specs.iter().map(|s| s.repeat.max(1)).collect();
    for i in rounds(&repeats) {
        let (spec, slot) = (specs[i], &mut running[i]);
        let Some(r) = slot else {
            continue;
        };
        match run_once(spec, &r.scene) {
            Ok((run, hist, wall)) => {
                r.walls.push(wall);
                r.last = Some((run, hist));
            }
            Err(f) => {
                *slot = None;
                done(spec, *f)?;
                continue;
            }
        }
        if r.walls.len() == repeats[i] as usize {
            let r = slot.take().expect("running");
            let (run, hist) = r.last.expect("a repeat ran");
            done(spec, result(spec, &r.scene, run, hist, r.walls))?;
        }
    }
    Ok(())
}

/// The finished case: outputs of its last analysis, the wall times of every repeat.
fn result(
    spec: &CaseSpec,
    scene: &Scene,
    run: solvers::RunOutput,
    hist: Option<History>,
    walls: Vec<f64>,
) -> CaseResult {
    let best = walls.iter().copied().fold(f64::INFINITY, f64::min);
    let rs: Vec<f64> = run
        .impacts
        .iter()
        .map(|i| i.achieved_restitution)
        .filter(|r| r.is_finite())
        .collect();
    let (rmean, rmin, rmax) = if rs.is_empty() {
        (None, None, None)
    } else {
        (
            Some(rs.iter().sum::<f64>() / rs.len() as f64),
            Some(rs.iter().cloned().fold(f64::INFINITY, f64::min)),
            Some(rs.iter().cloned().fold(f64::NEG_INFINITY, f64::max)),
        )
    };
    let max_pen = run
        .impacts
        .iter()
        .filter_map(|i| i.max_penetration)
        .fold(None, |a: Option<f64>, p| Some(a.map_or(p, |a| a.max(p))));
    let (mut peak_closure, mut contact_history) = (None, None);
    if let (Some(h), Some(c)) = (&hist, scene.contacts.first()) {
        let off: Vec<usize> = scene
            .buildings
            .iter()
            .scan(0, |acc, b| {
                let o = *acc;
                *acc += b.n_floors();
                Some(o)
            })
            .collect();
        let (il, ir) = (off[c.left] + c.left_dof, off[c.right] + c.right_dof);
        let ul: Vec<f64> = h.displacement.iter().map(|r| r[il]).collect();
        // A wall stands at relative displacement 0.
        let ur: Vec<f64> = h
            .displacement
            .iter()
            .map(|r| if c.wall { 0.0 } else { r[ir] })
            .collect();
        peak_closure = ul
            .iter()
            .zip(&ur)
            .map(|(a, b)| a - b)
            .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.max(d))));
        if !spec.params.contains_key("baseline") {
            contact_history = Some(ContactHistory {
                time: h.time.clone(),
                u_left: ul,
                u_right: ur,
            });
        }
    }
    let approach: Vec<f64> = run
        .impacts
        .iter()
        .map(|i| i.relative_velocity_before)
        .filter(|v| *v > 0.0)
        .collect();
    let outputs = CaseOutputs {
        settings: run.settings.clone(),
        buildings: run.buildings.iter().map(|b| b.name.clone()).collect(),
        contact_floor: (0..scene.buildings.len())
            .map(|b| {
                scene.contacts.first().and_then(|c| {
                    if c.left == b {
                        Some(c.left_dof + 1)
                    } else if c.right == b && !c.wall {
                        Some(c.right_dof + 1)
                    } else {
                        None
                    }
                })
            })
            .collect(),
        story_shear_max: run
            .buildings
            .iter()
            .map(|b| b.story_shear_max.clone())
            .collect(),
        floor_displacement_max: run
            .buildings
            .iter()
            .map(|b| b.floor_displacement_max.clone())
            .collect(),
        // The solver's peak drifts; for linear stories without them V = k₀ × drift, so the
        // peak drift is V_max / k₀.
        story_drift_max: run
            .buildings
            .iter()
            .zip(&scene.buildings)
            .map(|(r, b)| {
                if r.story_drift_max.is_empty() {
                    r.story_shear_max
                        .iter()
                        .zip(&b.story_stiffness)
                        .map(|(v, k)| v / k)
                        .collect()
                } else {
                    r.story_drift_max.clone()
                }
            })
            .collect(),
        story_drift_residual: if run.buildings.iter().all(|b| b.residual_drift.is_empty()) {
            Vec::new()
        } else {
            run.buildings
                .iter()
                .map(|b| b.residual_drift.clone())
                .collect()
        },
        energy_hysteretic: Some(run.energy.hysteretic),
        impacts: run.impacts.len(),
        impact_times: run.impacts.iter().map(|i| i.time).collect(),
        restitution_mean: rmean,
        restitution_min: rmin,
        restitution_max: rmax,
        max_penetration: max_pen,
        approach_speed_median: crate::studies::stats::median(&approach),
        approach_speed_max: approach.iter().copied().reduce(f64::max),
        persistent_contacts: run.persistent_contacts.len(),
        impacts_nonpositive_approach: run
            .impacts
            .iter()
            .filter(|i| i.achieved_restitution.is_finite() && i.relative_velocity_before <= 0.0)
            .count(),
        restitution_outside_unit: run
            .impacts
            .iter()
            .filter(|i| {
                i.achieved_restitution.is_finite() && !(0.0..=1.0).contains(&i.achieved_restitution)
            })
            .count(),
        restitution_undefined: run
            .impacts
            .iter()
            .filter(|i| i.achieved_restitution.is_nan())
            .count(),
        energy_input: run.energy.input,
        energy_contact: run.energy.contact,
        energy_balance_error: run.energy.balance_error,
        steps: run.stats.steps,
        rejected_steps: run.stats.rejected_steps,
        rhs_evaluations: run.stats.rhs_evaluations,
        events: run.stats.events,
        newton_iterations: run.stats.newton_iterations,
        r_n: run.r_n.first().map(|r| (r.r_n_left, r.r_n_right)),
        peak_closure,
        contact_history,
        worst_overlap: solvers::overlap::worst(&run.overlaps).cloned(),
        overlaps_beyond_gap: run.overlaps.iter().filter(|o| o.max_overlap > 0.0).count(),
    };
    CaseResult {
        spec: spec.clone(),
        status: "ok".into(),
        error_kind: None,
        error: None,
        outputs: Some(outputs),
        wall_seconds: best,
        wall_seconds_all: walls,
    }
}

/// A shard `index/count` (1-based index).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let (a, b) = s
            .split_once('/')
            .ok_or_else(|| format!("--shard `{s}`: expected i/n, e.g. 2/8"))?;
        let index: usize = a
            .trim()
            .parse()
            .map_err(|_| format!("--shard `{s}`: `{a}` is not a whole number"))?;
        let count: usize = b
            .trim()
            .parse()
            .map_err(|_| format!("--shard `{s}`: `{b}` is not a whole number"))?;
        if count == 0 || index == 0 || index > count {
            return Err(format!("--shard `{s}`: expected 1 <= i <= n"));
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// The shard given by a Slurm job array (SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT,
    /// and SLURM_ARRAY_TASK_MIN when present: task ids are mapped to 1 … n). None outside a
    /// job array (no SLURM_ARRAY_TASK_ID); an error when the variables are there but do not
    /// give a shard (not numbers, an id out of range, or a sparse or stepped array such as
    /// `--array=1,3,5` or `1-16:2`, whose ids are not 1 … n after the minimum), so a task
    /// never runs the whole sweep by mistake.
    pub fn from_slurm() -> std::result::Result<Option<Shard>, String> {
        Shard::from_env(|k| std::env::var(k).ok())
    }

    /// [`Shard::from_slurm`] with the environment given as a lookup (for tests).
    pub fn from_env(
        get: impl Fn(&str) -> Option<String>,
    ) -> std::result::Result<Option<Shard>, String> {
        let Some(id) = get("SLURM_ARRAY_TASK_ID") else {
            return Ok(None);
        };
        let num = |k: &str, v: &str| {
            v.trim()
                .parse::<i64>()
                .map_err(|_| format!("{k} = `{v}`: not a whole number (or give --shard i/n)"))
        };
        let id = num("SLURM_ARRAY_TASK_ID", &id)?;
        let count = match get("SLURM_ARRAY_TASK_COUNT") {
            Some(c) => num("SLURM_ARRAY_TASK_COUNT", &c)?,
            None => return Err(
                "SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not: give --shard i/n"
                    .into(),
            ),
        };
        let min = match get("SLURM_ARRAY_TASK_MIN") {
            Some(m) => num("SLURM_ARRAY_TASK_MIN", &m)?,
            None => 1,
        };
        if let Some(step) = get("SLURM_ARRAY_TASK_STEP") {
            let step = num("SLURM_ARRAY_TASK_STEP", &step)?;
            if step != 1 {
                return Err(format!(
                    "a stepped job array (SLURM_ARRAY_TASK_STEP = {step}) does not number its tasks 1 … n: use --array=1-N, or give --shard i/n"
                ));
            }
        }
        if let Some(max) = get("SLURM_ARRAY_TASK_MAX") {
            let max = num("SLURM_ARRAY_TASK_MAX", &max)?;
            if max - min + 1 != count {
                return Err(format!(
                    "a sparse job array (ids {min} … {max}, {count} tasks) does not number its tasks 1 … n: use --array={min}-{}, or give --shard i/n",
                    min + count - 1
                ));
            }
        }
        let index = id - min + 1;
        if count < 1 || index < 1 || index > count {
            return Err(format!(
                "SLURM_ARRAY_TASK_ID = {id} is outside the array's {} from {min}: give --shard i/n",
                crate::table::count(count, "task", "tasks")
            ));
        }
        Ok(Some(Shard {
            index: index as usize,
            count: count as usize,
        }))
    }

    pub fn takes(&self, case_index: usize) -> bool {
        case_index % self.count == self.index - 1
    }
}

/// How to run a list of cases.
#[derive(Debug, Clone)]
pub struct EngineOptions {
    /// Folder for this study's outputs (`<out>/<study>`); case files go in `cases/`.
    pub study_dir: PathBuf,
    /// Folder that scene and record paths are relative to.
    pub studies_dir: PathBuf,
    /// Worker threads (None: rayon's default).
    pub threads: Option<usize>,
    pub shard: Option<Shard>,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
    /// Recompute every case of the shard even if its case file exists, and remove case
    /// files of ids the study no longer has.
    pub fresh: bool,
}

/// What [`run_cases`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunSummary {
    pub total: usize,
    /// Run now.
    pub ran: usize,
    /// Already finished (loaded from case files).
    pub skipped: usize,
    /// Left to other shards.
    pub other_shards: usize,
    pub failed: usize,
}

pub fn case_path(study_dir: &Path, id: &str) -> PathBuf {
    study_dir.join("cases").join(format!("{id}.json"))
}

/// Reads the case file `path` of case `id`: an error naming the file when it cannot be
/// read, does not parse (truncated, corrupt) or holds another case.
pub fn read_case(path: &Path, id: &str) -> Result<CaseResult> {
    let bad = |message: String| StudyError::CaseFile {
        path: path.display().to_string(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let r: CaseResult = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    if r.spec.id != id {
        return Err(bad(format!("holds case {}, expected {id}", r.spec.id)));
    }
    Ok(r)
}

/// Reads a finished case, if its file exists and parses.
pub fn load_case(study_dir: &Path, id: &str) -> Option<CaseResult> {
    read_case(&case_path(study_dir, id), id).ok()
}

/// Removes duplicate ids, keeping the first occurrence (order preserved).
pub fn dedup(specs: Vec<CaseSpec>) -> Vec<CaseSpec> {
    let mut seen = std::collections::HashSet::new();
    specs
        .into_iter()
        .filter(|s| seen.insert(s.id.clone()))
        .collect()
}

/// Removes case files whose id is not among `specs` (left by an older definition).
fn remove_orphans(specs: &[CaseSpec], study_dir: &Path) -> Result<()> {
    let ids: std::collections::HashSet<&str> = specs.iter().map(|s| s.id.as_str()).collect();
    let Ok(entries) = std::fs::read_dir(study_dir.join("cases")) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let p = e.path();
        let orphan = p.extension().is_some_and(|x| x == "json")
            && p.file_stem()
                .and_then(|s| s.to_str())
                .is_some_and(|id| !ids.contains(id));
        if orphan {
            std::fs::remove_file(&p).map_err(|err| {
                StudyError::Other(format!("cannot remove {}: {err}", p.display()))
            })?;
        }
    }
    Ok(())
}

/// Runs the cases that have no case file yet (and belong to the shard), in parallel,
/// writing each case file as soon as it is done; then the timed cases ([`schedule`]), one
/// analysis at a time in rounds ([`run_interleaved`]), each written after its last repeat.
pub fn run_cases(specs: &[CaseSpec], opts: &EngineOptions) -> Result<RunSummary> {
    let mut summary = RunSummary {
        total: specs.len(),
        ..Default::default()
    };
    if opts.fresh {
        remove_orphans(specs, &opts.study_dir)?;
    }
    let mut todo = Vec::new();
    for (i, s) in specs.iter().enumerate() {
        if let Some(sh) = opts.shard {
            if !sh.takes(i) {
                summary.other_shards += 1;
                continue;
            }
        }
        if !opts.fresh && load_case(&opts.study_dir, &s.id).is_some() {
            summary.skipped += 1;
        } else {
            todo.push(s);
        }
    }
    let bar = if opts.progress && std::io::stderr().is_terminal() && !todo.is_empty() {
        let b = indicatif::ProgressBar::new(todo.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{prefix} [{bar:40}] {pos}/{len} cases, {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        b.set_prefix(
            opts.study_dir
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let (parallel, alone) = schedule(&todo);
    // A finished case: its file written; whether it failed.
    let record = |s: &CaseSpec, r: CaseResult| -> Result<bool> {
        write_json(&case_path(&opts.study_dir, &s.id), &r)?;
        bar.inc(1);
        Ok(r.status != "ok")
    };
    let work = || -> Vec<Result<bool>> {
        let mut out: Vec<Result<bool>> = parallel
            .par_iter()
            .map(|s| record(s, run_case(s, &opts.studies_dir)))
            .collect();
        let timed = run_interleaved(&alone, &opts.studies_dir, |s, r| {
            out.push(Ok(record(s, r)?));
            Ok(())
        });
        if let Err(e) = timed {
            out.push(Err(e));
        }
        out
    };
    let results = match opts.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| {
                StudyError::Other(format!(
                    "cannot start {}: {e}",
                    crate::table::count(n, "thread", "threads")
                ))
            })?
            .install(work),
        None => work(),
    };
    bar.finish_and_clear();
    for r in results {
        if r? {
            summary.failed += 1;
        }
        summary.ran += 1;
    }
    Ok(summary)
}

/// The cases to run in parallel and the timed cases (`repeat` > 1), which run after them one
/// analysis at a time, in rounds ([`run_interleaved`]): a case timed while another runs
/// beside it measures the other case too (on the
/// 2-core development machine, in one measurement, the momentum method took 2.99 ms per
/// analysis in the cost
/// study run two cases at a time, 2.36 ms run alone, and the adaptive gap element 10.1 and
/// 9.99 ms). Both lists keep the order of `todo`.
pub fn schedule<'a>(todo: &[&'a CaseSpec]) -> (Vec<&'a CaseSpec>, Vec<&'a CaseSpec>) {
    todo.iter().copied().partition(|s| s.repeat <= 1)
}

/// The results of `specs` read back from their case files, in case order. Missing cases
/// are an [`StudyError::Incomplete`] error listing their ids.
pub fn collect(study: &str, specs: &[CaseSpec], study_dir: &Path) -> Result<Results> {
    let mut map = BTreeMap::new();
    let mut missing = Vec::new();
    for s in specs {
        match load_case(study_dir, &s.id) {
            Some(r) => {
                map.insert(s.id.clone(), r);
            }
            None => missing.push(s.id.clone()),
        }
    }
    if !missing.is_empty() {
        let n = missing.len();
        return Err(StudyError::Incomplete {
            study: study.into(),
            missing: n,
            total: specs.len(),
            ids: missing.join(", "),
        });
    }
    Ok(Results {
        order: specs.iter().map(|s| s.id.clone()).collect(),
        map,
    })
}

/// Finished cases of a study, by id, in case order.
#[derive(Debug, Clone)]
pub struct Results {
    pub order: Vec<String>,
    pub map: BTreeMap<String, CaseResult>,
}

impl Results {
    pub fn get(&self, spec: &CaseSpec) -> &CaseResult {
        &self.map[&spec.id]
    }
    /// Outputs of a case, None if it failed.
    pub fn out(&self, spec: &CaseSpec) -> Option<&CaseOutputs> {
        self.map.get(&spec.id).and_then(|r| r.outputs.as_ref())
    }
    pub fn iter(&self) -> impl Iterator<Item = &CaseResult> {
        self.order.iter().map(|id| &self.map[id])
    }
}

/// Columns of `cases.csv` after the parameters: (name, value of a finished case).
type Column = (&'static str, fn(&CaseOutputs) -> String);

fn opt_e(v: Option<f64>) -> String {
    v.map(|x| format!("{x:e}")).unwrap_or_default()
}

const OUTPUT_COLUMNS: [Column; 22] = [
    ("impacts", |o| o.impacts.to_string()),
    ("persistent_contacts", |o| o.persistent_contacts.to_string()),
    ("restitution_mean", |o| opt_e(o.restitution_mean)),
    ("restitution_min", |o| opt_e(o.restitution_min)),
    ("restitution_max", |o| opt_e(o.restitution_max)),
    ("restitution_undefined", |o| {
        o.restitution_undefined.to_string()
    }),
    ("max_penetration_m", |o| opt_e(o.max_penetration)),
    ("approach_speed_median_m_per_s", |o| {
        opt_e(o.approach_speed_median)
    }),
    ("approach_speed_max_m_per_s", |o| {
        opt_e(o.approach_speed_max)
    }),
    ("overlaps_beyond_gap", |o| o.overlaps_beyond_gap.to_string()),
    ("overlap_max_m", |o| {
        opt_e(o.worst_overlap.as_ref().map(|w| w.max_overlap))
    }),
    ("peak_closure_m", |o| opt_e(o.peak_closure)),
    ("energy_input_J", |o| format!("{:e}", o.energy_input)),
    ("energy_contact_J", |o| format!("{:e}", o.energy_contact)),
    ("energy_hysteretic_J", |o| opt_e(o.energy_hysteretic)),
    ("energy_balance_error_J", |o| {
        format!("{:e}", o.energy_balance_error)
    }),
    ("steps", |o| o.steps.to_string()),
    ("rejected_steps", |o| o.rejected_steps.to_string()),
    ("rhs_evaluations", |o| o.rhs_evaluations.to_string()),
    ("events", |o| o.events.to_string()),
    ("newton_iterations", |o| o.newton_iterations.to_string()),
    ("settings", |o| o.settings.clone()),
];

/// Writes the study's data tables (tidy: one column per variable, one name each, units as
/// suffixes, the same columns whether cases finish or fail):
/// - `cases.json`: every result without histories;
/// - `cases.csv`: one row per case: `case_id`, `method`, `variant`, `record` (label),
///   `record_file`, `pga_g`, the study's other parameters, `baseline`, `overrides`,
///   `expected_failure`, `status`, `error_kind`, `error`, the scalar outputs, `wall_s`;
/// - `peaks.csv`: one row per finished case, building and story: `case_id`, `building`
///   (as named in the scene), `story` (from 1; floor `story` is its top),
///   `story_shear_max_N`, `floor_displacement_max_m` (of floor `story`),
///   `amplification` (peak story shear over that of the case's run without contact,
///   when the study ran it), `story_drift_max_m` (peak |u_j − u_{j−1}|) and
///   `residual_drift_m` (the drift at the end of the analysis, empty when the method does
///   not report it).
pub fn write_cases_table(study_dir: &Path, results: &Results) -> Result<()> {
    let rows: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let mut r = r.clone();
            if let Some(o) = r.outputs.as_mut() {
                o.contact_history = None;
            }
            serde_json::to_value(&r).unwrap_or(serde_json::Value::Null)
        })
        .collect();
    write_json(&study_dir.join("cases.json"), &rows)?;

    const FIXED: [&str; 3] = ["variant", "record", "baseline"];
    let mut param_keys: Vec<String> = results
        .iter()
        .flat_map(|r| r.spec.params.keys().cloned())
        .filter(|k| !FIXED.contains(&k.as_str()))
        .collect();
    param_keys.sort();
    param_keys.dedup();
    let csv_err = |e: csv::Error| StudyError::Other(format!("cases.csv: {e}"));
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = [
        "case_id",
        "method",
        "variant",
        "record",
        "record_file",
        "pga_g",
    ]
    .map(String::from)
    .to_vec();
    header.extend(param_keys.iter().cloned());
    header.extend(
        [
            "baseline",
            "overrides",
            "expected_failure",
            "status",
            "error_kind",
            "error",
        ]
        .map(String::from),
    );
    header.extend(OUTPUT_COLUMNS.iter().map(|(n, _)| n.to_string()));
    header.push("wall_s".into());
    w.write_record(&header).map_err(csv_err)?;
    let param = |r: &CaseResult, k: &str| match r.spec.params.get(k) {
        None => String::new(),
        Some(serde_json::Value::String(v)) => v.clone(),
        Some(v) => v.to_string(),
    };
    for r in results.iter() {
        let s = &r.spec;
        let mut row = vec![
            s.id.clone(),
            s.method.to_string(),
            param(r, "variant"),
            // A unique name per record file (the case parameter `record` keeps only the
            // component for PEER files, which repeats across the near-field records).
            s.record
                .as_deref()
                .map(crate::studies::record_name)
                .unwrap_or_else(|| param(r, "record")),
            s.record.clone().unwrap_or_default(),
            s.pga.map(|p| p.to_string()).unwrap_or_default(),
        ];
        row.extend(param_keys.iter().map(|k| param(r, k)));
        row.extend([
            s.params.contains_key("baseline").to_string(),
            s.set.join(";"),
            s.expect_failure.clone().unwrap_or_default(),
            r.status.clone(),
            r.error_kind.clone().unwrap_or_default(),
            r.error.clone().unwrap_or_default(),
        ]);
        match r.ok() {
            Some(o) => row.extend(OUTPUT_COLUMNS.iter().map(|(_, f)| f(o))),
            None => row.extend(OUTPUT_COLUMNS.iter().map(|_| String::new())),
        }
        row.push(format!("{:.6e}", r.wall_seconds));
        w.write_record(&row).map_err(csv_err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| StudyError::Other(format!("cases.csv: {e}")))?;
    write_atomic(&study_dir.join("cases.csv"), &bytes)?;

    let peaks_err = |e: csv::Error| StudyError::Other(format!("peaks.csv: {e}"));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "case_id",
        "building",
        "story",
        "story_shear_max_N",
        "floor_displacement_max_m",
        "amplification",
        "story_drift_max_m",
        "residual_drift_m",
    ])
    .map_err(peaks_err)?;
    let at = |v: &[Vec<f64>], b: usize, j: usize| {
        v.get(b)
            .and_then(|x| x.get(j))
            .map(|x| format!("{x:e}"))
            .unwrap_or_default()
    };
    for r in results.iter() {
        let Some(o) = r.ok() else { continue };
        let base = (!r.spec.params.contains_key("baseline"))
            .then(|| results.map.get(&r.spec.baseline().id).and_then(|b| b.ok()))
            .flatten();
        for (b, shears) in o.story_shear_max.iter().enumerate() {
            let name = o
                .buildings
                .get(b)
                .cloned()
                .unwrap_or_else(|| format!("building{}", b + 1));
            for (j, v) in shears.iter().enumerate() {
                let amp = base
                    .and_then(|bo| bo.story_shear_max.get(b).and_then(|x| x.get(j)))
                    .map(|v0| format!("{:e}", v / v0))
                    .unwrap_or_default();
                w.write_record([
                    r.spec.id.clone(),
                    name.clone(),
                    (j + 1).to_string(),
                    format!("{v:e}"),
                    o.floor_displacement_max
                        .get(b)
                        .and_then(|x| x.get(j))
                        .map(|x| format!("{x:e}"))
                        .unwrap_or_default(),
                    amp,
                    at(&o.story_drift_max, b, j),
                    at(&o.story_drift_residual, b, j),
                ])
                .map_err(peaks_err)?;
            }
        }
    }
    let bytes = w
        .into_inner()
        .map_err(|e| StudyError::Other(format!("peaks.csv: {e}")))?;
    write_atomic(&study_dir.join("peaks.csv"), &bytes)?;
    Ok(())
}
