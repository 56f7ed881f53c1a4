//! Scene files: buildings, contacts, ground motion and solver options, in TOML.
//!
//! The format is documented in docs/scenes.md. Loading happens in two stages:
//! the text is parsed into raw serde structs with `deny_unknown_fields` (so a misspelt key
//! is an error that names it, with line and column), then validated into model types
//! ([`Scene`]) with errors that name the file and the dotted key (`contacts[0].gap`).
//!
//! `--set PATH=VALUE` overrides edit the parsed TOML tree before validation: `PATH` is a
//! dotted path whose numeric segments index arrays (`contacts.0.gap`), `VALUE` is parsed as
//! a TOML value and, failing that, taken as a bare string (`gap_element.law=linear`).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::ground::{FormatRefusal, GroundMotion, RecordError, RecordFormat, Units};
use crate::model::{
    calibrate_first_frequency, calibrate_two_frequencies, Building, Damping, ModelError, StoryLaw,
};

/// Errors from reading, overriding or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene file {file}: {}", crate::ground::record::io_reason(.error))]
    Io { file: String, error: std::io::Error },
    /// The file is not UTF-8 text: `offset` (0-based) is the first invalid byte, on 1-based
    /// `line` at byte `column` (1-based).
    #[error("{file} line {line}, byte {column} (byte offset {offset}): expected UTF-8 text, found the invalid byte 0x{byte:02X}")]
    Encoding {
        file: String,
        line: usize,
        column: usize,
        offset: usize,
        byte: u8,
    },
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    #[error("{file}: key `{key}`: {message}")]
    Invalid {
        file: String,
        key: String,
        message: String,
    },
    #[error("--set {expr}: {message}")]
    Override { expr: String, message: String },
    #[error("{file}: key `ground_motion.file`: {source}")]
    Record { file: String, source: RecordError },
    #[error("{file}: {source}")]
    Model { file: String, source: ModelError },
}

/// Variant of the momentum method's impulse (`momentum.impulse`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ImpulseVariant {
    /// P = (1 + c_r) v_rel / W with W the Delassus value of the kept modes: exact
    /// restitution and momentum conservation with any number of modes.
    #[default]
    Consistent,
    /// The paper's eqs (23)–(24) with floor masses, projected on the kept modes.
    Paper,
}

/// Options of the modal momentum solver (`[momentum]`).
#[derive(Debug, Clone, PartialEq)]
pub struct MomentumOptions {
    /// Modes kept per building; `None` = all (default). Clamped to each building's floors.
    pub modes: Option<usize>,
    /// Impulse variant (default `consistent`).
    pub impulse: ImpulseVariant,
    /// Switch to a persistent-contact phase when impacts accumulate (default true).
    pub persistent_contact: bool,
    /// Approach speed, m/s, below which a contact that keeps closing is captured into a
    /// persistent-contact phase (default 1e-4 m/s).
    pub capture_velocity: f64,
    /// How far a held gap may stray inside a held segment of a persistent-contact phase,
    /// relative to max(gap, 1 mm) (default 1e-6): the holding forces are linear over a
    /// segment, and a segment is shortened until its gaps stray no further at its middle and
    /// its force's jump at the next segment's start would move them no further.
    pub held_tolerance: f64,
}

impl Default for MomentumOptions {
    fn default() -> Self {
        MomentumOptions {
            modes: None,
            impulse: ImpulseVariant::Consistent,
            persistent_contact: true,
            capture_velocity: 1e-4,
            held_tolerance: 1e-6,
        }
    }
}

/// Contact law of the gap element (`gap_element.law`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ContactLaw {
    /// Compression-only linear spring k⟨δ⟩.
    Linear,
    /// Spring and dashpot (Anagnostopoulos), ξ from c_r.
    #[default]
    KelvinVoigt,
    /// Hertz spring k_h δ^{3/2} with Muthukumar–DesRoches damping.
    HertzDamp,
}

impl ContactLaw {
    /// The law's name in a scene file (`gap_element.law`).
    pub fn key(self) -> &'static str {
        match self {
            ContactLaw::Linear => "linear",
            ContactLaw::KelvinVoigt => "kelvin-voigt",
            ContactLaw::HertzDamp => "hertz-damp",
        }
    }
}

/// Time integrator of the gap-element solver (`gap_element.integrator`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Integrator {
    /// Embedded Runge–Kutta pair with error control and event location (default).
    #[default]
    Adaptive,
    /// Fixed-step average-acceleration Newmark with Newton iterations.
    Newmark,
}

/// Options of the gap-element solver (`[gap_element]`).
#[derive(Debug, Clone, PartialEq)]
pub struct GapElementOptions {
    /// Spring stiffness k, N/m (N/m^1.5 for `hertz-damp`). Default 1e10.
    pub stiffness: f64,
    /// Contact law (default `kelvin-voigt`).
    pub law: ContactLaw,
    /// Integrator (default `adaptive`).
    pub integrator: Integrator,
    /// Adaptive: relative error tolerance per step (default 1e-8); the absolute tolerance is
    /// this times 1e-3 m (displacements) and 1e-3 m/s (velocities).
    pub tolerance: f64,
    /// Newmark: fixed time step, s (default 1e-3).
    pub time_step: f64,
    /// Kelvin–Voigt: let the dashpot pull (tensile force) until the gap reopens (true) or
    /// clamp the force at zero and end contact when it vanishes (false, default).
    pub tension: bool,
}

impl Default for GapElementOptions {
    fn default() -> Self {
        GapElementOptions {
            stiffness: 1.0e10,
            law: ContactLaw::KelvinVoigt,
            integrator: Integrator::Adaptive,
            tolerance: 1.0e-8,
            time_step: 1.0e-3,
            tension: false,
        }
    }
}

/// Guardrails shared by both solvers (`[analysis]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Most impacts per second of simulated time before the run stops as an event storm
    /// (default 2000 /s).
    pub max_impact_rate: f64,
    /// Most time steps (or events) in one run (default 50 000 000).
    pub max_steps: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_impact_rate: 2000.0,
            max_steps: 50_000_000,
        }
    }
}

/// A contact pair between two floors of two buildings.
#[derive(Debug, Clone, PartialEq)]
pub struct Contact {
    /// Index of the left building in [`Scene::buildings`].
    pub left: usize,
    /// 0-based floor index (DOF) of the left building (scene files count floors from 1).
    pub left_dof: usize,
    /// Index of the right building.
    pub right: usize,
    /// 0-based floor index of the right building.
    pub right_dof: usize,
    /// Gap at rest, m (≥ 0). In contact while u_left − u_right ≥ gap.
    pub gap: f64,
    /// Coefficient of restitution c_r in [0, 1].
    pub restitution: f64,
    /// The right side is a rigid wall that moves with the ground (scene `right = "wall"`):
    /// in the relative frame it stands still at u = gap, so δ = u_left − gap. For a wall
    /// contact `right` and `right_dof` repeat `left` and `left_dof` (valid indices, never a
    /// second body): code that reads the right side must check `wall` first.
    pub wall: bool,
    /// The scene file's `[[contacts]]` entry this contact was resolved from (0-based index
    /// in the file's `contacts` array): a `floors = "aligned"` entry expands to several
    /// contacts, all with its index. Bookkeeping only (reports group contacts by it,
    /// [`Scene::contact_entries`]); no solver reads it. A contact built in code has no file
    /// entry: give it an entry of its own, by convention its index in [`Scene::contacts`]
    /// (what `structure::testing` does); contacts that share a value are reported as one
    /// entry.
    pub entry: usize,
}

/// The name that makes a contact's right side a rigid wall (`right = "wall"`); no building
/// may take it.
pub const WALL: &str = "wall";

impl Contact {
    /// Gap function δ = u_left − u_right − gap (m): closed when δ ≥ 0. For a wall contact
    /// `u_right` is ignored (the wall is at relative displacement 0).
    pub fn penetration(&self, u_left: f64, u_right: f64) -> f64 {
        u_left - if self.wall { 0.0 } else { u_right } - self.gap
    }
}

/// Where the ground motion came from (for reports and the OpenSees export).
#[derive(Debug, Clone, PartialEq)]
pub struct GroundMotionSource {
    /// Resolved path of the record file.
    pub file: PathBuf,
    pub format: RecordFormat,
    /// Factor applied to the record as read (1 if neither `pga` nor `scale` is given).
    pub factor: f64,
    /// Target PGA, g, if `pga` was given.
    pub pga_g: Option<f64>,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub name: String,
    /// The scene file, if it came from one.
    pub file: Option<PathBuf>,
    pub buildings: Vec<Building>,
    /// Story heights per building, m, story 1 first (`buildings[i].story_height`); `None`
    /// when not given (then floor i of one building faces floor i of the other). An entry
    /// missing for a building index (a scene built in code) counts as `None`.
    pub story_heights: Vec<Option<Vec<f64>>>,
    /// The resolved contacts, in the order of the scene file's entries (an aligned entry's
    /// contacts roof first); each knows its entry ([`Contact::entry`]).
    pub contacts: Vec<Contact>,
    /// Ground acceleration (m/s², already scaled); `None` = free vibration.
    pub ground: Option<GroundMotion>,
    pub ground_source: Option<GroundMotionSource>,
    /// Analysis duration, s. `analysis.duration`, else the record's duration. A scene read
    /// for its structure alone ([`Purpose::Structure`]) without either has 0 here: it
    /// cannot be analysed.
    pub duration: f64,
    pub momentum: MomentumOptions,
    pub gap_element: GapElementOptions,
    pub limits: Limits,
}

/// Two floors at the same elevation agree within this distance, m (`story_height`).
pub const ELEVATION_TOLERANCE: f64 = 1e-6;

/// A floor of one building whose elevation lies strictly between two levels (floors, or
/// the ground) of an adjacent building: it would strike the other building's column
/// mid-story (floor-to-column impact), which the shear-stick models do not represent. Only
/// arises when both buildings give `story_height`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UnmodelledFacing {
    /// Name of the building whose floor this is, and the floor (1-based).
    pub building: String,
    pub floor: usize,
    /// Its elevation above the ground, m.
    pub elevation: f64,
    /// The adjacent building, and the levels of that building just below and just above
    /// (1-based floors; 0 = the ground).
    pub other: String,
    pub between: [usize; 2],
}

/// Which floors of two buildings face each other.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Facings {
    /// (floor of a, floor of b), 0-based, floor of a ascending: the floors at the same
    /// elevation (within [`ELEVATION_TOLERANCE`]) when both buildings give story heights,
    /// otherwise floor i with floor i up to the lower roof.
    pub pairs: Vec<(usize, usize)>,
    /// Floors of either building at an elevation strictly between two levels of the other
    /// (only with story heights on both).
    pub unmodelled: Vec<UnmodelledFacing>,
}

/// Floor elevations (m above the ground, floor 1 first) from story heights.
fn elevations(heights: &[f64]) -> Vec<f64> {
    heights
        .iter()
        .scan(0.0, |z, h| {
            *z += h;
            Some(*z)
        })
        .collect()
}

/// The facing floors of buildings `a` and `b` (see [`Facings`]).
fn facings(buildings: &[Building], heights: &[Option<Vec<f64>>], a: usize, b: usize) -> Facings {
    let h = |i: usize| heights.get(i).and_then(|h| h.as_ref());
    match (h(a), h(b)) {
        (Some(ha), Some(hb)) => {
            let (za, zb) = (elevations(ha), elevations(hb));
            let mut out = Facings::default();
            for (i, &z) in za.iter().enumerate() {
                if let Some(j) = zb
                    .iter()
                    .position(|&w| (w - z).abs() <= ELEVATION_TOLERANCE)
                {
                    out.pairs.push((i, j));
                }
            }
            // Floors strictly between two levels of the other (ground = level 0), below its
            // roof by more than the tolerance.
            let mut between = |x: usize, zx: &[f64], y: usize, zy: &[f64]| {
                for (i, &z) in zx.iter().enumerate() {
                    let roof = *zy.last().unwrap_or(&0.0);
                    if z >= roof - ELEVATION_TOLERANCE
                        || zy.iter().any(|&w| (w - z).abs() <= ELEVATION_TOLERANCE)
                    {
                        continue;
                    }
                    let above = zy.iter().position(|&w| w > z).unwrap_or(zy.len() - 1);
                    out.unmodelled.push(UnmodelledFacing {
                        building: buildings[x].name.clone(),
                        floor: i + 1,
                        elevation: z,
                        other: buildings[y].name.clone(),
                        between: [above, above + 1],
                    });
                }
            };
            between(a, &za, b, &zb);
            between(b, &zb, a, &za);
            out
        }
        _ => Facings {
            pairs: (0..buildings[a].n_floors().min(buildings[b].n_floors()))
                .map(|i| (i, i))
                .collect(),
            unmodelled: vec![],
        },
    }
}

impl Scene {
    /// The contacts grouped by the scene file's entry they come from ([`Contact::entry`]):
    /// (entry, its contacts' indices in [`Scene::contacts`]), in the order of each entry's
    /// first contact.
    pub fn contact_entries(&self) -> Vec<(usize, Vec<usize>)> {
        let mut entries: Vec<(usize, Vec<usize>)> = Vec::new();
        for (i, c) in self.contacts.iter().enumerate() {
            let e = c.entry;
            match entries.iter_mut().find(|(k, _)| *k == e) {
                Some((_, v)) => v.push(i),
                None => entries.push((e, vec![i])),
            }
        }
        entries
    }

    /// The facing floors of buildings `a` and `b` (indices in [`Scene::buildings`]).
    pub fn facings(&self, a: usize, b: usize) -> Facings {
        facings(&self.buildings, &self.story_heights, a, b)
    }

    /// Pairs of buildings (a < b) joined by at least one contact, in order of first contact
    /// (wall contacts join no pair).
    pub fn joined_pairs(&self) -> Vec<(usize, usize)> {
        let mut out: Vec<(usize, usize)> = Vec::new();
        for c in self.contacts.iter().filter(|c| !c.wall) {
            let p = (c.left.min(c.right), c.left.max(c.right));
            if !out.contains(&p) {
                out.push(p);
            }
        }
        out
    }

    /// Floor-to-column facings of every pair of buildings joined by a contact: floors that
    /// would strike an adjacent building mid-story, which no contact models (see
    /// [`UnmodelledFacing`]). Empty unless the buildings give `story_height`.
    pub fn unmodelled_facings(&self) -> Vec<UnmodelledFacing> {
        self.joined_pairs()
            .into_iter()
            .flat_map(|(a, b)| self.facings(a, b).unmodelled)
            .collect()
    }
}

// ---------------------------------------------------------------------------------------
// Raw file structures

#[derive(Deserialize)]
#[serde(untagged, expecting = "a number or a list of numbers")]
enum ScalarOrList {
    Scalar(f64),
    List(Vec<f64>),
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a scene: tables buildings, contacts, ground_motion, analysis, momentum, gap_element"
)]
struct RawScene {
    name: Option<String>,
    buildings: Vec<RawBuilding>,
    #[serde(default)]
    contacts: Vec<RawContact>,
    ground_motion: Option<RawGround>,
    #[serde(default)]
    analysis: RawAnalysis,
    #[serde(default)]
    momentum: RawMomentum,
    #[serde(default)]
    gap_element: RawGap,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a building table (keys name, masses or stories and mass, story_stiffness or target_frequencies_hz, damping_ratio, story_height, story_law, yield_shear, hardening_ratio, ...)"
)]
struct RawBuilding {
    name: String,
    masses: Option<Vec<f64>>,
    stories: Option<usize>,
    mass: Option<f64>,
    story_stiffness: Option<ScalarOrList>,
    target_frequencies_hz: Option<Vec<f64>>,
    /// k_top / k_ground of the linear taper fitted to one target frequency.
    top_stiffness_ratio: Option<f64>,
    reference_frequencies_hz: Option<Vec<f64>>,
    damping_ratio: Option<ScalarOrList>,
    /// Two mode numbers (from 1) anchoring Rayleigh damping.
    rayleigh_modes: Option<Vec<i64>>,
    initial_displacement: Option<Vec<f64>>,
    initial_velocity: Option<Vec<f64>>,
    story_height: Option<ScalarOrList>,
    /// "linear" (default) or "bilinear".
    story_law: Option<String>,
    /// Yield shear, N, per story or one for all (bilinear stories).
    yield_shear: Option<ScalarOrList>,
    /// Post-yield stiffness over the elastic one (bilinear stories), default 0.02.
    hardening_ratio: Option<f64>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a contact table with keys left, left_floor, right, right_floor (or floors = \"aligned\"), gap, restitution"
)]
struct RawContact {
    left: String,
    left_floor: Option<i64>,
    right: String,
    right_floor: Option<i64>,
    floors: Option<String>,
    gap: f64,
    #[serde(default = "one")]
    restitution: f64,
}

fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a ground_motion table with keys file, pga or scale, format, units, dt"
)]
struct RawGround {
    file: String,
    format: Option<String>,
    dt: Option<f64>,
    units: Option<String>,
    pga: Option<f64>,
    scale: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(
    deny_unknown_fields,
    expecting = "an analysis table with keys duration, max_impact_rate, max_steps"
)]
struct RawAnalysis {
    duration: Option<f64>,
    max_impact_rate: Option<f64>,
    max_steps: Option<i64>,
}

#[derive(Deserialize, Default)]
#[serde(
    deny_unknown_fields,
    expecting = "a momentum table with keys modes, impulse, persistent_contact, capture_velocity, held_tolerance"
)]
struct RawMomentum {
    modes: Option<i64>,
    impulse: Option<ImpulseVariant>,
    persistent_contact: Option<bool>,
    capture_velocity: Option<f64>,
    held_tolerance: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(
    deny_unknown_fields,
    expecting = "a gap_element table with keys stiffness, law, integrator, tolerance, time_step, tension"
)]
struct RawGap {
    stiffness: Option<f64>,
    law: Option<ContactLaw>,
    integrator: Option<Integrator>,
    tolerance: Option<f64>,
    time_step: Option<f64>,
    tension: Option<bool>,
}

// ---------------------------------------------------------------------------------------
// Loading

/// What a scene is read for: what it must define.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    /// An analysis: the duration is `analysis.duration` or the record's (one is required).
    Analysis,
    /// The structure alone (modes, frequencies, contact flexibility): the duration may be
    /// missing (then [`Scene::duration`] is 0). Every other key is read and checked as for
    /// an analysis, the record included.
    Structure,
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        Self::from_file_with_overrides(path, &[])
    }

    /// Reads a scene file, applies `PATH=VALUE` overrides, then validates.
    pub fn from_file_with_overrides(
        path: &Path,
        overrides: &[String],
    ) -> Result<Scene, SceneError> {
        Self::from_file_for(path, overrides, Purpose::Analysis)
    }

    /// [`Scene::from_file_with_overrides`] for a [`Purpose`].
    pub fn from_file_for(
        path: &Path,
        overrides: &[String],
        purpose: Purpose,
    ) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|error| SceneError::Io {
            file: file.clone(),
            error,
        })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let bytes = e.as_bytes();
            let offset = e.utf8_error().valid_up_to();
            let before = &bytes[..offset];
            let line_start = before
                .iter()
                .rposition(|b| *b == b'\n')
                .map_or(0, |i| i + 1);
            SceneError::Encoding {
                file: file.clone(),
                line: before.iter().filter(|b| **b == b'\n').count() + 1,
                column: offset - line_start + 1,
                offset,
                byte: bytes[offset],
            }
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        let mut scene = Self::from_str_for(&text, &file, base, overrides, purpose)?;
        scene.file = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses scene text. `origin` names it in errors; relative record paths are resolved
    /// against `base_dir`.
    pub fn from_str_with_overrides(
        text: &str,
        origin: &str,
        base_dir: &Path,
        overrides: &[String],
    ) -> Result<Scene, SceneError> {
        Self::from_str_for(text, origin, base_dir, overrides, Purpose::Analysis)
    }

    /// [`Scene::from_str_with_overrides`] for a [`Purpose`].
    pub fn from_str_for(
        text: &str,
        origin: &str,
        base_dir: &Path,
        overrides: &[String],
        purpose: Purpose,
    ) -> Result<Scene, SceneError> {
        let parse_err = |message: String| SceneError::Parse {
            file: origin.to_string(),
            message,
        };
        let raw: RawScene = if overrides.is_empty() {
            toml::from_str(text).map_err(|e| parse_err(e.to_string().trim_end().to_string()))?
        } else {
            let mut table: toml::Table = toml::from_str(text)
                .map_err(|e| parse_err(e.to_string().trim_end().to_string()))?;
            for expr in overrides {
                apply_override(&mut table, expr)?;
            }
            // The path of the offending key, with array indices (`buildings[0].mass`).
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(
                |e: serde_path_to_error::Error<toml::de::Error>| {
                    let inner = e.inner().to_string();
                    let first = inner.lines().next().unwrap_or("").trim_end();
                    // A missing field is reported at its table (`.` for the top level): name
                    // the field itself.
                    let path = e.path().to_string();
                    let key = match first
                        .strip_prefix("missing field `")
                        .and_then(|r| r.split_once('`'))
                    {
                        Some((field, _)) if path == "." => field.to_string(),
                        Some((field, _)) => format!("{path}.{field}"),
                        None => path,
                    };
                    parse_err(format!("after --set overrides: key `{key}`: {first}"))
                },
            )?
        };
        validate(raw, origin, base_dir, purpose)
    }

    /// Index of the building called `name`.
    pub fn building_index(&self, name: &str) -> Option<usize> {
        self.buildings.iter().position(|b| b.name == name)
    }

    /// Ground acceleration at time `t`, m/s² (0 without a record or outside it).
    pub fn ground_accel(&self, t: f64) -> f64 {
        self.ground.as_ref().map_or(0.0, |g| g.accel_at(t))
    }
}

/// Applies one `PATH=VALUE` override to a parsed TOML table. `PATH=` (nothing after `=`)
/// removes the key, e.g. `ground_motion.pga=` before `ground_motion.scale=1.0`.
pub fn apply_override(table: &mut toml::Table, expr: &str) -> Result<(), SceneError> {
    let fail = |message: String| SceneError::Override {
        expr: expr.to_string(),
        message,
    };
    let (path, value) = expr
        .split_once('=')
        .ok_or_else(|| fail("expected PATH=VALUE, e.g. contacts.0.gap=0.05".into()))?;
    let path = path.trim();
    let value = value.trim();
    if path.is_empty() {
        return Err(fail("the path before `=` is empty".into()));
    }
    // `PATH=`: remove the key (None); else the value, parsed as TOML (a bare word is a string).
    let parsed: Option<toml::Value> = if value.is_empty() {
        None
    } else {
        Some(
            match toml::from_str::<toml::Table>(&format!("v = {value}")) {
                Ok(mut t) => t
                    .remove("v")
                    .unwrap_or(toml::Value::String(value.to_string())),
                // A number TOML cannot hold (1e400 overflows a double) is not a word.
                Err(_) if value.parse::<f64>().is_ok() => {
                    return Err(fail(format!(
                    "`{value}` is out of the range of a double-precision number (about ±1.8e308)"
                )))
                }
                Err(_) => toml::Value::String(value.to_string()),
            },
        )
    };
    // Setting creates missing tables on the way; removing stops at a missing one (nothing to
    // remove). An array entry can be replaced, not removed (the indices after it would shift).
    let segs: Vec<&str> = path.split('.').collect();
    let mut cur: &mut toml::Value = {
        let first = segs[0];
        if segs.len() == 1 {
            match parsed {
                Some(v) => table.insert(first.to_string(), v),
                None => table.remove(first),
            };
            return Ok(());
        }
        if parsed.is_none() && !table.contains_key(first) {
            return Ok(());
        }
        table
            .entry(first.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
    };
    for (i, seg) in segs.iter().enumerate().skip(1) {
        let last = i + 1 == segs.len();
        let so_far = segs[..i].join(".");
        cur = match cur {
            toml::Value::Array(arr) => {
                let idx: usize = seg.parse().map_err(|_| {
                    fail(format!(
                        "`{so_far}` is an array: expected a numeric index, found `{seg}`"
                    ))
                })?;
                let len = match arr.len() {
                    0 => "no entries".to_string(),
                    1 => "1 entry (index 0)".to_string(),
                    n => format!("{n} entries (indices 0 … {})", n - 1),
                };
                let slot = arr.get_mut(idx).ok_or_else(|| {
                    fail(format!("index {idx} is out of range: `{so_far}` has {len}"))
                })?;
                if last {
                    return match parsed {
                        Some(v) => {
                            *slot = v;
                            Ok(())
                        }
                        None => Err(fail(format!(
                            "`{so_far}` is an array: its entries cannot be removed, only replaced"
                        ))),
                    };
                }
                slot
            }
            toml::Value::Table(t) => {
                if last {
                    match parsed {
                        Some(v) => t.insert(seg.to_string(), v),
                        None => t.remove(*seg),
                    };
                    return Ok(());
                }
                if parsed.is_none() && !t.contains_key(*seg) {
                    return Ok(());
                }
                t.entry(seg.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            _ => return Err(fail(format!("`{so_far}` is a value, not a table or array"))),
        };
    }
    Ok(())
}

/// Floor masses a scene accepts, kg (1 g to a million tonnes a floor): with
/// [`STIFFNESS_RANGE`] it keeps ω² = k/m and the solvers' products far from overflow and
/// underflow.
pub const MASS_RANGE: (f64, f64) = (1e-3, 1e12);

/// Story stiffnesses a scene accepts, N/m (up to a wall-like 1e24 N/m).
pub const STIFFNESS_RANGE: (f64, f64) = (1e-3, 1e24);

/// Largest spread (k_max / k_min) · (m_max / m_min) · n² a building of n floors may have. It
/// estimates the condition number of the eigenproblem M^(-1/2) K M^(-1/2): round-off
/// perturbs its eigenvalues by about 1e-16 of the largest, so beyond about 1e16 the lowest
/// ones come out zero or negative (measured on graded sticks of 2 … 1000 floors); 1e12
/// keeps the lowest ω² accurate to about 1e-4 of itself.
pub const MAX_SPREAD: f64 = 1e12;

/// Target frequencies a calibration accepts (`target_frequencies_hz`), Hz.
pub const FREQUENCY_RANGE: (f64, f64) = (1e-3, 1e3);

/// Top-to-ground story stiffness ratios a one-frequency calibration accepts
/// (`top_stiffness_ratio`); the two-frequency calibration spans 1/50 … 50.
pub const TOP_STIFFNESS_RATIO_RANGE: (f64, f64) = (1e-2, 1e2);

/// Most floors a building may have, by `stories = N` or by an explicit `masses` list: a
/// guard against absurd allocations and eigen-solutions (their cost grows as n³: 3 000 floors
/// take about 11 s, 10 000 several minutes), far above any building a shear stick models.
pub const MAX_STORIES: usize = 1_000;

fn validate(
    raw: RawScene,
    origin: &str,
    base_dir: &Path,
    purpose: Purpose,
) -> Result<Scene, SceneError> {
    let invalid = |key: String, message: String| SceneError::Invalid {
        file: origin.to_string(),
        key,
        message,
    };
    let model_err = |source: ModelError| SceneError::Model {
        file: origin.to_string(),
        source,
    };
    if raw.buildings.is_empty() {
        return Err(invalid(
            "buildings".into(),
            "at least one [[buildings]] table is required".into(),
        ));
    }
    let mut buildings = Vec::with_capacity(raw.buildings.len());
    let mut story_heights: Vec<Option<Vec<f64>>> = Vec::with_capacity(raw.buildings.len());
    for (bi, rb) in raw.buildings.into_iter().enumerate() {
        let key = |k: &str| format!("buildings[{bi}].{k}");
        if rb.name.trim().is_empty() {
            return Err(invalid(
                key("name"),
                format!(
                    "{:?}: expected a non-empty name (it names the building in contacts and \
                     output columns)",
                    rb.name
                ),
            ));
        }
        if rb.name == WALL {
            return Err(invalid(
                key("name"),
                format!(
                    "`{WALL}` is reserved: a contact with right = \"{WALL}\" is a rigid wall; \
                     rename the building"
                ),
            ));
        }
        if buildings.iter().any(|b: &Building| b.name == rb.name) {
            return Err(invalid(
                key("name"),
                format!("building name `{}` is used twice", rb.name),
            ));
        }
        let zeta_list = match rb.damping_ratio {
            None => Damping::Uniform(0.05),
            Some(ScalarOrList::Scalar(z)) => Damping::Uniform(z),
            Some(ScalarOrList::List(v)) => Damping::PerMode(v),
        };
        let masses: Vec<f64> = match (&rb.masses, rb.stories, rb.mass) {
            (Some(m), None, None) => {
                if m.len() > MAX_STORIES {
                    return Err(invalid(
                        key("masses"),
                        format!(
                            "a list of {} masses: expected at most {MAX_STORIES} floors",
                            m.len()
                        ),
                    ));
                }
                m.clone()
            }
            (None, Some(n), Some(m)) => {
                if !(1..=MAX_STORIES).contains(&n) {
                    return Err(invalid(
                        key("stories"),
                        format!("{n}: expected a whole number of floors in 1 ..= {MAX_STORIES}"),
                    ));
                }
                vec![m; n]
            }
            (Some(_), _, _) => {
                return Err(invalid(key("masses"), "give either `masses` or `stories` with `mass`, not both".into()))
            }
            _ => {
                return Err(invalid(
                    key("masses"),
                    "missing: give `masses = [...]` (kg per floor) or `stories = N` with `mass = M` (kg)".into(),
                ))
            }
        };
        if let Damping::PerMode(v) = &zeta_list {
            if v.len() != masses.len() {
                return Err(invalid(
                    key("damping_ratio"),
                    format!(
                        "a list of {} for a building of {}: expected one ratio per mode ({}), \
                         or a single number for every mode",
                        crate::count(v.len(), "ratio", "ratios"),
                        crate::count(masses.len(), "floor", "floors"),
                        masses.len()
                    ),
                ));
            }
        }
        if masses.is_empty() {
            return Err(invalid(
                key("masses"),
                "is empty: expected one mass (kg) per floor, at least one floor".into(),
            ));
        }
        // The key as written: `masses[i]`, or `mass` for the `stories` + `mass` shorthand.
        let mass_key = |i: usize| {
            if rb.masses.is_some() {
                format!("buildings[{bi}].masses[{i}]")
            } else {
                key("mass")
            }
        };
        if let Some((i, m)) = masses
            .iter()
            .enumerate()
            .find(|(_, m)| !(m.is_finite() && **m > 0.0))
        {
            return Err(invalid(
                mass_key(i),
                format!("{m}: expected a finite mass > 0 (kg)"),
            ));
        }
        let (m_lo, m_hi) = MASS_RANGE;
        if let Some((i, m)) = masses
            .iter()
            .enumerate()
            .find(|(_, m)| !(m_lo..=m_hi).contains(*m))
        {
            return Err(invalid(
                mass_key(i),
                format!("{m:e}: expected a floor mass in [{m_lo:e}, {m_hi:e}] kg"),
            ));
        }
        let n = masses.len();
        let heights = match rb.story_height {
            None => None,
            Some(ScalarOrList::Scalar(h)) => {
                if !(h.is_finite() && h > 0.0) {
                    return Err(invalid(
                        key("story_height"),
                        format!("{h}: expected a finite story height > 0 (m)"),
                    ));
                }
                Some(vec![h; n])
            }
            Some(ScalarOrList::List(hs)) => {
                if hs.len() != n {
                    return Err(invalid(
                        key("story_height"),
                        format!(
                            "has {}, expected {n} (one height per story, story 1 first), \
                             or a single number for every story",
                            crate::count(hs.len(), "value", "values")
                        ),
                    ));
                }
                if let Some((i, h)) = hs
                    .iter()
                    .enumerate()
                    .find(|(_, h)| !(h.is_finite() && **h > 0.0))
                {
                    return Err(invalid(
                        format!("buildings[{bi}].story_height[{i}]"),
                        format!("{h}: expected a finite story height > 0 (m)"),
                    ));
                }
                Some(hs)
            }
        };
        story_heights.push(heights);
        // The key the story stiffnesses came from: a list, a scalar or a calibration.
        let stiffness_scalar = matches!(rb.story_stiffness, Some(ScalarOrList::Scalar(_)));
        if let (None, Some(f)) = (&rb.story_stiffness, &rb.target_frequencies_hz) {
            let (f_lo, f_hi) = FREQUENCY_RANGE;
            if let Some((i, f)) = f
                .iter()
                .enumerate()
                .find(|(_, f)| !(f_lo..=f_hi).contains(*f))
            {
                return Err(invalid(
                    format!("buildings[{bi}].target_frequencies_hz[{i}]"),
                    format!("{f:e}: expected a frequency in [{f_lo:e}, {f_hi:e}] Hz"),
                ));
            }
        }
        let (stiffness, calibrated) = match (rb.story_stiffness, &rb.target_frequencies_hz) {
            (Some(_), Some(_)) => {
                return Err(invalid(
                    key("target_frequencies_hz"),
                    "give `story_stiffness` or `target_frequencies_hz`, not both".into(),
                ))
            }
            (Some(_), None) if rb.top_stiffness_ratio.is_some() => {
                return Err(invalid(
                    key("top_stiffness_ratio"),
                    "applies to a calibration: give it with one `target_frequencies_hz` value, not with `story_stiffness`".into(),
                ))
            }
            (Some(ScalarOrList::Scalar(k)), None) => (vec![k; n], None),
            (Some(ScalarOrList::List(k)), None) => (k, None),
            (None, Some(f)) if f.len() == 2 && rb.top_stiffness_ratio.is_some() => {
                return Err(invalid(
                    key("top_stiffness_ratio"),
                    "two target frequencies fix the taper: give one target frequency (f1) with `top_stiffness_ratio`, or two without it".into(),
                ))
            }
            (None, Some(f)) if f.len() == 1 && rb.top_stiffness_ratio.is_some() => {
                let r = rb.top_stiffness_ratio.unwrap_or(1.0);
                if masses.iter().any(|m| *m != masses[0]) {
                    return Err(invalid(
                        key("target_frequencies_hz"),
                        "calibration needs a uniform floor mass".into(),
                    ));
                }
                let (r_lo, r_hi) = TOP_STIFFNESS_RATIO_RANGE;
                if !(r_lo..=r_hi).contains(&r) {
                    return Err(invalid(
                        key("top_stiffness_ratio"),
                        format!("{r:e}: expected a ratio > 0 of the top to the ground story stiffness, in [{r_lo:e}, {r_hi:e}]"),
                    ));
                }
                let c = calibrate_first_frequency(
                    &rb.name,
                    n,
                    masses[0],
                    f[0],
                    r,
                    zeta_list.ratio(0),
                )
                .map_err(|e| invalid(key("target_frequencies_hz"), e.to_string()))?;
                (c.building.story_stiffness.clone(), Some(c))
            }
            (None, Some(f)) => {
                if f.len() != 2 {
                    return Err(invalid(
                        key("target_frequencies_hz"),
                        format!(
                            "expected 2 values (f1, f2 in Hz), found {}; or one value (f1) with `top_stiffness_ratio`",
                            f.len()
                        ),
                    ));
                }
                if masses.iter().any(|m| *m != masses[0]) {
                    return Err(invalid(
                        key("target_frequencies_hz"),
                        "calibration needs a uniform floor mass".into(),
                    ));
                }
                let c = calibrate_two_frequencies(
                    &rb.name,
                    n,
                    masses[0],
                    f[0],
                    f[1],
                    zeta_list.ratio(0),
                )
                .map_err(|e| invalid(key("target_frequencies_hz"), e.to_string()))?;
                (c.building.story_stiffness.clone(), Some(c))
            }
            (None, None) => {
                return Err(invalid(
                    key("story_stiffness"),
                    "missing: give `story_stiffness` (N/m) or `target_frequencies_hz`".into(),
                ))
            }
        };
        if stiffness.len() != n {
            return Err(invalid(
                key("story_stiffness"),
                format!(
                    "has {}, expected {n} (one per story, as `masses`)",
                    crate::count(stiffness.len(), "value", "values")
                ),
            ));
        }
        // A story stiffness refused (`value`: k as the message shows it; `expected`), under
        // the key as written:
        // `story_stiffness[i]`, `story_stiffness` for one number for every story,
        // `target_frequencies_hz` for a calibrated building.
        let stiffness_error = |i: usize, value: String, expected: String| {
            match &calibrated {
            Some(_) => invalid(
                key("target_frequencies_hz"),
                format!(
                    "the calibration (`{}`) gives story {} a stiffness of {value} N/m: expected {expected}",
                    if rb.top_stiffness_ratio.is_some() {
                        "target_frequencies_hz` with `top_stiffness_ratio"
                    } else {
                        "target_frequencies_hz"
                    },
                    i + 1
                ),
            ),
            None => invalid(
                if stiffness_scalar {
                    key("story_stiffness")
                } else {
                    format!("buildings[{bi}].story_stiffness[{i}]")
                },
                format!("{value}: expected {expected}"),
            ),
        }
        };
        if let Some((i, &k)) = stiffness
            .iter()
            .enumerate()
            .find(|(_, k)| !(k.is_finite() && **k > 0.0))
        {
            return Err(stiffness_error(
                i,
                format!("{k}"),
                "a finite stiffness > 0 (N/m)".into(),
            ));
        }
        let (k_lo, k_hi) = STIFFNESS_RANGE;
        if let Some((i, &k)) = stiffness
            .iter()
            .enumerate()
            .find(|(_, k)| !(k_lo..=k_hi).contains(*k))
        {
            return Err(stiffness_error(
                i,
                format!("{k:e}"),
                format!(
                    "story stiffnesses in [{k_lo:e}, {k_hi:e}] N/m{}",
                    if calibrated.is_some() {
                        "; lower the frequencies or the masses"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let (k_min, k_max) = crate::model::min_max(&stiffness);
        let (m_min, m_max) = crate::model::min_max(&masses);
        let (k_ratio, m_ratio) = (k_max / k_min, m_max / m_min);
        let spread = k_ratio * m_ratio * (n * n) as f64;
        if spread > MAX_SPREAD {
            let which = if calibrated.is_some() {
                key("target_frequencies_hz")
            } else if k_ratio >= m_ratio {
                key("story_stiffness")
            } else {
                key("masses")
            };
            return Err(invalid(
                which,
                format!(
                    "story stiffnesses from {k_min:e} to {k_max:e} N/m (ratio {k_ratio:.3e}) and \
                     masses from {m_min:e} to {m_max:e} kg (ratio {m_ratio:.3e}) on {} \
                     make the modes ill-conditioned: expected (largest / smallest story \
                     stiffness) × (largest / smallest mass) × floors² at most {MAX_SPREAD:e}, \
                     found {spread:.3e}",
                    crate::count(n, "floor", "floors")
                ),
            ));
        }
        if let Some((i, f)) = rb
            .reference_frequencies_hz
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, f)| !(f.is_finite() && **f > 0.0))
        {
            return Err(invalid(
                format!("buildings[{bi}].reference_frequencies_hz[{i}]"),
                format!("{f}: expected a finite frequency > 0 (Hz)"),
            ));
        }
        let story_law =
            parse_story_law(&rb.story_law, &rb.yield_shear, rb.hardening_ratio, n, &key)
                .map_err(|(k, m)| invalid(k, m))?;
        let mut b = Building {
            story_law,
            name: rb.name.clone(),
            masses,
            story_stiffness: stiffness,
            damping: zeta_list,
            initial_displacement: rb.initial_displacement.unwrap_or_else(|| vec![0.0; n]),
            initial_velocity: rb.initial_velocity.unwrap_or_else(|| vec![0.0; n]),
            reference_frequencies_hz: rb.reference_frequencies_hz.unwrap_or_default(),
        };
        b.validate().map_err(|e| match e {
            ModelError::Invalid { what, .. } => invalid(format!("buildings[{bi}]"), what),
            other => model_err(other),
        })?;
        if let Some(modes) = &rb.rayleigh_modes {
            let zeta = match &b.damping {
                Damping::Uniform(z) => *z,
                Damping::PerMode(_) => {
                    return Err(invalid(
                        key("rayleigh_modes"),
                        "Rayleigh damping takes one `damping_ratio` (the ratio at both anchor modes), not a list".into(),
                    ))
                }
            };
            let ok = |m: i64| (1..=n as i64).contains(&m);
            if modes.len() != 2 || !modes.iter().all(|m| ok(*m)) || modes[0] == modes[1] {
                return Err(invalid(
                    key("rayleigh_modes"),
                    format!("{modes:?}: expected two different mode numbers in 1 ..= {n}"),
                ));
            }
            b.set_rayleigh_damping(zeta, (modes[0] - 1) as usize, (modes[1] - 1) as usize)
                .map_err(|e| match e {
                    ModelError::Invalid { what, .. } => invalid(key("rayleigh_modes"), what),
                    other => model_err(other),
                })?;
        }
        buildings.push(b);
    }

    let mut contacts: Vec<Contact> = Vec::with_capacity(raw.contacts.len());
    for (ci, rc) in raw.contacts.into_iter().enumerate() {
        let key = |k: &str| format!("contacts[{ci}].{k}");
        let find = |name: &str, k: &str| {
            buildings
                .iter()
                .position(|b| b.name == name)
                .ok_or_else(|| {
                    let names: Vec<&str> = buildings.iter().map(|b| b.name.as_str()).collect();
                    invalid(
                        key(k),
                        format!(
                            "no building named `{name}` (buildings: {})",
                            names.join(", ")
                        ),
                    )
                })
        };
        let left = find(&rc.left, "left")?;
        let wall = rc.right == WALL;
        let right = if wall {
            left
        } else {
            find(&rc.right, "right")?
        };
        if left == right && !wall {
            return Err(invalid(
                key("right"),
                format!(
                    "a contact joins two different buildings; both sides are `{}`",
                    rc.left
                ),
            ));
        }
        // Story heights on one side only: the floors cannot be matched by elevation.
        match (&story_heights[left], &story_heights[right]) {
            (Some(_), None) | (None, Some(_)) if !wall => {
                let (with, without, wi) = if story_heights[left].is_some() {
                    (left, right, right)
                } else {
                    (right, left, left)
                };
                return Err(invalid(
                    format!("buildings[{wi}].story_height"),
                    format!(
                        "missing: `{}` gives story heights and is joined to `{}` by contacts[{ci}]; \
                         give `story_height` (m) for both buildings or for neither",
                        buildings[with].name, buildings[without].name
                    ),
                ));
            }
            _ => {}
        }
        let floor = |f: i64, b: usize, k: &str| -> Result<usize, SceneError> {
            let n = buildings[b].n_floors() as i64;
            if f < 1 || f > n {
                return Err(invalid(
                    key(k),
                    format!(
                        "floor {f} is out of range: `{}` has {}",
                        buildings[b].name,
                        if n == 1 {
                            "only floor 1".to_string()
                        } else {
                            format!("floors 1 … {n}")
                        }
                    ),
                ));
            }
            Ok((f - 1) as usize)
        };
        let pairs: Vec<(usize, usize)> = match (&rc.floors, rc.left_floor, rc.right_floor) {
            _ if wall => {
                if rc.right_floor.is_some() {
                    return Err(invalid(
                        key("right_floor"),
                        format!(
                            "a wall (right = \"{WALL}\") has no floors: remove `right_floor` \
                             and give only `left_floor`"
                        ),
                    ));
                }
                if rc.floors.is_some() {
                    return Err(invalid(
                        key("floors"),
                        format!(
                            "`floors` pairs the floors of two buildings; a wall (right = \
                             \"{WALL}\") takes one `left_floor` per contact"
                        ),
                    ));
                }
                let lf = rc.left_floor.ok_or_else(|| {
                    invalid(
                        key("left_floor"),
                        "missing field `left_floor`: the floor of `left` (from 1) that meets \
                         the wall"
                            .into(),
                    )
                })?;
                let dof = floor(lf, left, "left_floor")?;
                vec![(dof, dof)]
            }
            (Some(mode), lf, rf) => {
                if mode != "aligned" {
                    return Err(invalid(
                        key("floors"),
                        format!(
                            "`{mode}`: expected \"aligned\" (a contact at every pair of floors \
                             at the same elevation), or give `left_floor` and `right_floor`"
                        ),
                    ));
                }
                if lf.is_some() || rf.is_some() {
                    let k = if lf.is_some() {
                        "left_floor"
                    } else {
                        "right_floor"
                    };
                    return Err(invalid(
                        key(k),
                        "give `floors = \"aligned\"` or `left_floor` and `right_floor`, not both"
                            .into(),
                    ));
                }
                let f = facings(&buildings, &story_heights, left, right);
                if f.pairs.is_empty() {
                    return Err(invalid(
                        key("floors"),
                        format!(
                            "\"aligned\": no floor of `{}` is at the elevation of a floor of `{}` \
                             (within {ELEVATION_TOLERANCE:e} m)",
                            buildings[left].name, buildings[right].name
                        ),
                    ));
                }
                // Highest pair first: contact 0 of the entry is at the roofs when they face
                // each other (the contact the studies report, as for a roof-only scene).
                f.pairs.into_iter().rev().collect()
            }
            (None, Some(lf), Some(rf)) => vec![(
                floor(lf, left, "left_floor")?,
                floor(rf, right, "right_floor")?,
            )],
            (None, lf, _) => {
                let k = if lf.is_none() {
                    "left_floor"
                } else {
                    "right_floor"
                };
                return Err(invalid(
                    key(k),
                    format!(
                        "missing field `{k}`: give `left_floor` and `right_floor` (floor numbers \
                         from 1), or `floors = \"aligned\"`"
                    ),
                ));
            }
        };
        if !(rc.gap.is_finite() && rc.gap >= 0.0) {
            return Err(invalid(
                key("gap"),
                format!("{}: expected a finite gap >= 0 (m)", rc.gap),
            ));
        }
        if !(0.0..=1.0).contains(&rc.restitution) {
            return Err(invalid(
                key("restitution"),
                format!(
                    "{}: expected a coefficient of restitution in [0, 1]",
                    rc.restitution
                ),
            ));
        }
        // The right side in messages: a floor, or the wall.
        let right_side = |dof: usize| {
            if wall {
                "the wall".to_string()
            } else {
                format!("floor {} of `{}`", dof + 1, buildings[right].name)
            }
        };
        for (left_dof, right_dof) in pairs {
            // The same floor pair twice (in either orientation) makes the contact system
            // singular: refuse it here rather than fail inside a solver.
            if let Some(other) = contacts.iter().position(|c: &Contact| {
                (c.left, c.left_dof, c.right, c.right_dof) == (left, left_dof, right, right_dof)
                    || (c.left, c.left_dof, c.right, c.right_dof)
                        == (right, right_dof, left, left_dof)
            }) {
                let by = if contacts[other].entry == ci {
                    "this entry".to_string()
                } else {
                    format!("contacts[{}]", contacts[other].entry)
                };
                return Err(invalid(
                    format!("contacts[{ci}]"),
                    format!(
                        "duplicate contact: floor {} of `{}` and {} are already joined by \
                         {by}; one contact per floor pair",
                        left_dof + 1,
                        buildings[left].name,
                        right_side(right_dof),
                    ),
                ));
            }
            // Initial penetration: δ = u_left − u_right − gap must not exceed round-off at
            // t = 0.
            let u_right = if wall {
                0.0
            } else {
                buildings[right].initial_displacement[right_dof]
            };
            let delta0 = buildings[left].initial_displacement[left_dof] - u_right - rc.gap;
            if delta0 > 1e-9 * rc.gap.max(1e-3) {
                return Err(invalid(
                    format!("contacts[{ci}]"),
                    format!(
                        "floor {} of `{}` and {} start penetrated by {delta0:.6e} m: \
                         initial displacements (buildings.initial_displacement) close the gap \
                         of {} m at t = 0",
                        left_dof + 1,
                        buildings[left].name,
                        right_side(right_dof),
                        rc.gap
                    ),
                ));
            }
            contacts.push(Contact {
                left,
                left_dof,
                right,
                right_dof,
                gap: rc.gap,
                restitution: rc.restitution,
                wall,
                entry: ci,
            });
        }
    }

    let (ground, ground_source) = match raw.ground_motion {
        None => (None, None),
        Some(g) => {
            let key = |k: &str| format!("ground_motion.{k}");
            let units = match &g.units {
                None => Units::G,
                Some(u) => u.parse::<Units>().map_err(|_| {
                    invalid(
                        key("units"),
                        format!("`{u}`: expected one of \"g\", \"m/s^2\", \"cm/s^2\""),
                    )
                })?,
            };
            let kind = match &g.format {
                None => None,
                Some(name) => {
                    Some(crate::ground::FormatKind::from_name(name).ok_or_else(|| {
                        invalid(
                            key("format"),
                            format!("`{name}`: expected \"at2\", \"two-column\" or \"one-column\""),
                        )
                    })?)
                }
            };
            // An AT2 record states its units and dt: either given is refused, both named.
            let at2_settings = || {
                let present: Vec<&str> = [("units", g.units.is_some()), ("dt", g.dt.is_some())]
                    .into_iter()
                    .filter_map(|(k, given)| given.then_some(k))
                    .collect();
                invalid(
                    key(present[0]),
                    format!(
                        "AT2 records state their units (header line 3) and dt (line 4); remove `{}`",
                        present.join("` and `")
                    ),
                )
            };
            // The one rule ([`RecordFormat::infer`]): without `format`, AT2 for a name ending
            // in .at2 (any case), else one-column when `dt` is given (as `pound record FILE
            // --dt S` reads it), else two-column.
            let refused = |refusal| match refusal {
                FormatRefusal::DtWithAt2 { .. } => at2_settings(),
                FormatRefusal::DtWithTwoColumn { .. } => invalid(
                    key("dt"),
                    "format \"two-column\": a two-column record takes its dt from the time \
                     column; remove `dt` (or, for a file of acceleration values only, give \
                     format \"one-column\" or no format)"
                        .into(),
                ),
                FormatRefusal::OneColumnWithoutDt => invalid(
                    key("dt"),
                    "missing: a one-column record needs `dt` (s)".into(),
                ),
                FormatRefusal::BadDt { dt } => invalid(
                    key("dt"),
                    format!(
                        "{}: expected a time step > 0 (s), finite and at least {:e} s",
                        crate::ground::record::short_number(dt),
                        crate::ground::record::MIN_RECORD_DT
                    ),
                ),
            };
            let choice =
                RecordFormat::infer(Path::new(&g.file), kind, g.dt, units).map_err(refused)?;
            if choice.format == RecordFormat::At2 && g.units.is_some() {
                return Err(at2_settings());
            }
            if g.pga.is_some() && g.scale.is_some() {
                return Err(invalid(
                    key("pga"),
                    "give `pga` or `scale`, not both".into(),
                ));
            }
            if let Some(p) = g.pga {
                if !(p.is_finite() && p > 0.0) {
                    return Err(invalid(
                        key("pga"),
                        format!("{p}: expected a peak ground acceleration > 0 (g)"),
                    ));
                }
            }
            if let Some(s) = g.scale {
                if !(s.is_finite() && s != 0.0) {
                    return Err(invalid(
                        key("scale"),
                        format!("{s}: expected a finite, nonzero factor (a zero factor leaves no ground motion)"),
                    ));
                }
            }
            let path = base_dir.join(&g.file);
            if let Some(problem) = crate::ground::record_path_problem(&path) {
                let relative = match problem {
                    crate::ground::RecordPathProblem::Missing
                        if Path::new(&g.file).is_relative() =>
                    {
                        format!(
                            " (`{}` is taken relative to the scene's folder, {})",
                            g.file,
                            folder_name(base_dir)
                        )
                    }
                    _ => String::new(),
                };
                return Err(invalid(
                    key("file"),
                    format!("record file {} {problem}{relative}", path.display()),
                ));
            }
            // One-column only because `dt` came without `format` (`choice.inferred`): a table
            // of two or more values per line is refused rather than read value after value,
            // named under `dt`, which is what chose the one-column format here.
            let rec = GroundMotion::load_choice(&path, &choice).map_err(|source| match source {
                RecordError::InferredOneColumn { .. } => invalid(
                    key("dt"),
                    format!(
                        "{source}: give `ground_motion.format = \"two-column\"` without `dt` to \
                         read time and acceleration, or `format = \"one-column\"` to read every \
                         value in order"
                    ),
                ),
                source => SceneError::Record {
                    file: origin.to_string(),
                    source,
                },
            })?;
            let format = choice.format;
            let factor = match (g.pga, g.scale) {
                (Some(p), _) => {
                    let pga = rec.pga();
                    if pga <= 0.0 {
                        return Err(invalid(
                            key("pga"),
                            "the record is all zeros: it cannot be scaled to a PGA".into(),
                        ));
                    }
                    let factor = p * crate::G / pga;
                    // A PGA near the largest f64 over a small record PGA: the factor itself
                    // overflows (every sample would be reported, the first even when zero).
                    if !factor.is_finite() {
                        return Err(invalid(
                            key("pga"),
                            format!(
                                "{p:e} g: the factor from the record's PGA ({:e} g) to it is \
                                 beyond the range of floating point (expected a PGA that leaves \
                                 every acceleration finite)",
                                pga / crate::G
                            ),
                        ));
                    }
                    factor
                }
                (None, Some(s)) => s,
                (None, None) => 1.0,
            };
            // A factor near the largest f64 overflows the record: refused here, not left to
            // stop a solver with a non-finite state. (With `pga`, `factor` is the one
            // `scaled_to_pga` would use.)
            let scaled = rec.checked_scaled(factor).map_err(|e| {
                let (k, v) = match g.pga {
                    Some(p) => ("pga", format!("{p:e} g")),
                    None => ("scale", format!("{factor:e}")),
                };
                invalid(key(k), e.message(&v, &path.display().to_string()))
            })?;
            (
                Some(scaled),
                Some(GroundMotionSource {
                    file: path,
                    format,
                    factor,
                    pga_g: g.pga,
                }),
            )
        }
    };

    let duration = match (raw.analysis.duration, &ground) {
        (Some(d), _) => {
            if !(d.is_finite() && d > 0.0) {
                return Err(invalid(
                    "analysis.duration".into(),
                    format!("{d}: expected a duration > 0 (s)"),
                ));
            }
            d
        }
        (None, Some(g)) => g.duration(),
        (None, None) if purpose == Purpose::Structure => 0.0,
        (None, None) => {
            return Err(invalid(
                "analysis.duration".into(),
                "missing: without a ground motion the duration (s) is required".into(),
            ))
        }
    };
    let mut limits = Limits::default();
    if let Some(r) = raw.analysis.max_impact_rate {
        if !(r.is_finite() && r > 0.0) {
            return Err(invalid(
                "analysis.max_impact_rate".into(),
                format!("{r}: expected impacts per second > 0"),
            ));
        }
        limits.max_impact_rate = r;
    }
    if let Some(s) = raw.analysis.max_steps {
        if s < 1 {
            return Err(invalid(
                "analysis.max_steps".into(),
                format!("{s}: expected a whole number >= 1"),
            ));
        }
        limits.max_steps = s as u64;
    }

    let mut momentum = MomentumOptions::default();
    if let Some(m) = raw.momentum.modes {
        if m < 1 {
            return Err(invalid(
                "momentum.modes".into(),
                format!("{m}: expected a number of modes >= 1"),
            ));
        }
        momentum.modes = Some(m as usize);
    }
    if let Some(v) = raw.momentum.impulse {
        momentum.impulse = v;
    }
    if let Some(p) = raw.momentum.persistent_contact {
        momentum.persistent_contact = p;
    }
    if let Some(v) = raw.momentum.capture_velocity {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(
                "momentum.capture_velocity".into(),
                format!("{v}: expected a speed >= 0 (m/s)"),
            ));
        }
        momentum.capture_velocity = v;
    }
    if let Some(v) = raw.momentum.held_tolerance {
        if !(v.is_finite() && v > 0.0 && v <= 1e-2) {
            return Err(invalid(
                "momentum.held_tolerance".into(),
                format!("{v}: expected a relative tolerance > 0 and <= 1e-2 (of max(gap, 1 mm))"),
            ));
        }
        momentum.held_tolerance = v;
    }

    let mut gap = GapElementOptions::default();
    let rg = raw.gap_element;
    if let Some(k) = rg.stiffness {
        if !(k.is_finite() && k > 0.0) {
            return Err(invalid(
                "gap_element.stiffness".into(),
                format!("{k}: expected a stiffness > 0 (N/m)"),
            ));
        }
        gap.stiffness = k;
    }
    if let Some(l) = rg.law {
        gap.law = l;
    }
    if let Some(i) = rg.integrator {
        gap.integrator = i;
    }
    if let Some(t) = rg.tolerance {
        if !(t.is_finite() && t > 0.0 && t < 0.1) {
            return Err(invalid(
                "gap_element.tolerance".into(),
                format!("{t}: expected a relative tolerance in (0, 0.1)"),
            ));
        }
        gap.tolerance = t;
    }
    if let Some(dt) = rg.time_step {
        // (A structure-only scene without a duration has no bound on the step.)
        if !(dt.is_finite() && dt > 0.0 && (dt <= duration || duration == 0.0)) {
            return Err(invalid(
                "gap_element.time_step".into(),
                format!("{dt}: expected a step > 0 and <= the duration (s)"),
            ));
        }
        gap.time_step = dt;
    }
    // A fixed step longer than the record's step skips record points (and impacts).
    // (A check that reads the record must read only `ground_motion.*`, `analysis.*` and
    // `gap_element.{integrator,time_step}` besides it: the studies check every case cheaply on
    // that assumption, `studies::studies::reads_record`; a new one reading other keys must be
    // added there.)
    if gap.integrator == Integrator::Newmark {
        if let Some(g) = &ground {
            if gap.time_step > g.dt * (1.0 + 1e-9) {
                return Err(invalid(
                    "gap_element.time_step".into(),
                    format!(
                        "{}: a Newmark step longer than the record's step ({} s) skips record points; expected at most {} s",
                        gap.time_step, g.dt, g.dt
                    ),
                ));
            }
        }
    }
    if let Some(t) = rg.tension {
        gap.tension = t;
    }

    Ok(Scene {
        name: raw.name.unwrap_or_else(|| "scene".into()),
        file: None,
        buildings,
        story_heights,
        contacts,
        ground,
        ground_source,
        duration,
        momentum,
        gap_element: gap,
        limits,
    })
}

/// A folder for messages: `.` for the empty parent of a bare file name (`scene.toml`),
/// followed by its absolute form when that differs and can be found.
fn folder_name(dir: &Path) -> String {
    let shown = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    match std::fs::canonicalize(shown) {
        Ok(abs) if abs != shown => format!("{} ({})", shown.display(), abs.display()),
        _ => shown.display().to_string(),
    }
}

/// The story law of a building from its keys `story_law`, `yield_shear` (N, one for every
/// story or one per story) and `hardening_ratio` (default
/// [`crate::model::story_law::DEFAULT_HARDENING_RATIO`]); `key` names a key of the building.
/// An error is (key, message).
fn parse_story_law(
    law: &Option<String>,
    yield_shear: &Option<ScalarOrList>,
    hardening_ratio: Option<f64>,
    n: usize,
    key: &dyn Fn(&str) -> String,
) -> Result<StoryLaw, (String, String)> {
    match law.as_deref() {
        None | Some("linear") => {
            for (k, given) in [
                ("yield_shear", yield_shear.is_some()),
                ("hardening_ratio", hardening_ratio.is_some()),
            ] {
                if given {
                    return Err((
                        key(k),
                        "applies to yielding stories: give it with `story_law = \"bilinear\"`"
                            .into(),
                    ));
                }
            }
            Ok(StoryLaw::Linear)
        }
        Some("bilinear") => {
            let fy = match yield_shear {
                None => {
                    return Err((
                        key("yield_shear"),
                        "missing: `story_law = \"bilinear\"` needs the yield shear of every story (N), one number for all or one per story".into(),
                    ))
                }
                Some(ScalarOrList::Scalar(f)) => vec![*f; n],
                Some(ScalarOrList::List(fs)) if fs.len() == n => fs.clone(),
                Some(ScalarOrList::List(fs)) => {
                    return Err((
                        key("yield_shear"),
                        format!(
                            "has {}, expected {n} (one per story, story 1 first), or a \
                             single number for every story",
                            crate::count(fs.len(), "value", "values")
                        ),
                    ))
                }
            };
            if let Some((i, f)) = fy
                .iter()
                .enumerate()
                .find(|(_, f)| !(f.is_finite() && **f > 0.0))
            {
                return Err((
                    format!("{}[{i}]", key("yield_shear")),
                    format!("{f}: expected a finite yield shear > 0 (N)"),
                ));
            }
            let b = hardening_ratio.unwrap_or(crate::model::story_law::DEFAULT_HARDENING_RATIO);
            if !(b.is_finite() && (0.0..1.0).contains(&b)) {
                return Err((
                    key("hardening_ratio"),
                    format!("{b}: expected a post-yield stiffness ratio in [0, 1)"),
                ));
            }
            Ok(StoryLaw::Bilinear {
                yield_shear: fy,
                hardening_ratio: b,
            })
        }
        Some(other) => Err((
            key("story_law"),
            format!("`{other}`: expected \"linear\" or \"bilinear\""),
        )),
    }
}
