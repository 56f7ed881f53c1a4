//! The studies: definitions (`studies/<name>.toml`), case lists, tables, figures, readings.
//!
//! Every study expands its definition into [`CaseSpec`]s; the driver adds the no-impact
//! baseline of every case ([`CaseSpec::baseline`]: contact pushed 1 km away, everything else
//! equal, so the amplification factor compares like with like), runs them with the sweep
//! engine, then (unless sharded) reads the case files back and writes
//! `<out>/<study>/{cases.csv,cases.json,*.csv,*.md,*.png,*.svg,summary.md}`.
//!
//! Outputs whose name contains `cpu` (and `cost/summary.md`, `yielding/summary.md`, and the
//! `cases*` files) hold wall-clock times; everything else is deterministic.

pub mod cost;
pub mod gap;
pub mod modelform;
pub mod modes;
pub mod paper;
pub mod record_table;
pub mod restitution;
pub mod robustness;
pub mod stability;
pub mod stats;
pub mod stiffness;
pub mod yielding;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use solvers::Method;

use crate::io::{write_atomic, write_json};
use crate::sweep::{
    case_path, collect, dedup, read_case, run_cases, write_cases_table, CaseOutputs, CaseResult,
    CaseSpec, EngineOptions, Result, Results, RunSummary, Shard, StudyError,
};
use crate::table::Table;

/// Studies run only by name (long sweeps or variants, not part of `--all` /
/// `make studies`): `yielding-strong` is the yielding study of a stronger pair
/// (`studies/yielding-strong.toml`).
pub const EXTRA: [&str; 2] = ["robustness", "yielding-strong"];

/// The studies that run on the records given with `--records` (instead of their
/// definition's); the others (`paper`, `cost`, `stability`) reproduce or measure one fixed
/// scene and refuse `--records` when named (the CLI's exit 2).
pub const TAKE_RECORDS: [&str; 8] = [
    "stiffness",
    "modes",
    "restitution",
    "gap",
    "modelform",
    "yielding",
    "yielding-strong",
    "robustness",
];

/// All studies, in the order `--all` runs them.
pub const NAMES: [&str; 9] = [
    "paper",
    "stiffness",
    "modes",
    "restitution",
    "gap",
    "cost",
    "stability",
    "modelform",
    "yielding",
];

/// Options that change the case list (kept in the manifest so a merge rebuilds the same).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StudyOptions {
    /// Small grids, one record, 12 s of analysis (for tests).
    pub quick: bool,
    /// Records replacing the definition's (studies 2–5); absolute paths.
    pub records: Vec<String>,
    /// `PATH=VALUE` scene overrides for every case on one of `records` (how to read them:
    /// `ground_motion.format`, `ground_motion.dt`); empty: each file's format follows its
    /// extension.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub record_set: Vec<String>,
}

/// What a study sees.
pub struct Ctx {
    pub name: String,
    pub def: toml::Table,
    pub def_file: String,
    pub opts: StudyOptions,
    pub studies_dir: PathBuf,
    /// `<out>/<study>`.
    pub dir: PathBuf,
}

impl Ctx {
    /// The definition as the study's own type (unknown keys are errors).
    pub fn def<T: serde::de::DeserializeOwned>(&self) -> Result<T> {
        toml::Value::Table(self.def.clone())
            .try_into()
            .map_err(|e: toml::de::Error| StudyError::Definition {
                file: self.def_file.clone(),
                message: e.to_string().trim_end().to_string(),
            })
    }

    /// The records to use: `--records` if given (and `user_records` is true for the study),
    /// else the definition's; the first one only with `--quick`.
    pub fn records(&self, def: &[String], user_records: bool) -> Vec<String> {
        let mut r: Vec<String> = if user_records && !self.opts.records.is_empty() {
            self.opts.records.clone()
        } else {
            def.to_vec()
        };
        if self.opts.quick {
            r.truncate(1);
        }
        r
    }

    /// A case of `scene` with `method` on `record` scaled to `pga` (12 s long with --quick).
    pub fn case(&self, scene: &str, method: Method, record: &str, pga: f64) -> CaseSpec {
        let mut c = CaseSpec::new(scene, method)
            .record(record, Some(pga))
            .param("record", record_label(record));
        if self.opts.records.iter().any(|r| r == record) {
            for s in &self.opts.record_set {
                if let Some((path, value)) = s.split_once('=') {
                    c = c.with(path, value);
                }
            }
        }
        if self.opts.quick {
            c = c.with("analysis.duration", "12.0");
        }
        c
    }
}

/// A definition value the study cannot use: `Err` naming the definition file and what was
/// expected (exit 2 before any case runs), unless `ok`.
pub fn require(ctx: &Ctx, ok: bool, message: impl FnOnce() -> String) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(StudyError::Definition {
            file: ctx.def_file.clone(),
            message: message(),
        })
    }
}

/// Most modes a study definition may name (`max_modes`, `fewer_modes`, `modes`,
/// `paper_impulse_modes`): as many as the floors of the largest `stories = N` building the
/// scene accepts ([`structure::scene::MAX_STORIES`]); a count above a building's floors keeps
/// all its modes.
pub const MAX_MODES: usize = structure::scene::MAX_STORIES;

/// Most points of a generated grid (`gap_count`, `stiffness_count`,
/// `adaptive_stiffness_count`): a guard against absurd case lists (a count of 10⁹ used to
/// abort on an allocation of gigabytes).
pub const MAX_GRID: usize = 1_000;

/// Most runs of a timed case (the cost study's `repeat`).
pub const MAX_REPEAT: u32 = 1_000;

/// A whole-number definition value outside `range`: `Err` naming the key, its value and the
/// allowed range (`what` says what is counted).
pub fn require_count<T>(
    ctx: &Ctx,
    key: &str,
    value: T,
    range: std::ops::RangeInclusive<T>,
    what: &str,
) -> Result<()>
where
    T: PartialOrd + std::fmt::Display + Copy,
{
    require(ctx, range.contains(&value), || {
        format!(
            "`{key}` = {value}: expected at least {} {what} and at most {} ({} ..= {})",
            range.start(),
            range.end(),
            range.start(),
            range.end()
        )
    })
}

/// A list of mode counts (`key`), each in 1 ..= [`MAX_MODES`]; at least one unless
/// `may_be_empty`.
pub fn require_mode_counts(ctx: &Ctx, key: &str, v: &[usize], may_be_empty: bool) -> Result<()> {
    let ok = (may_be_empty || !v.is_empty()) && v.iter().all(|n| (1..=MAX_MODES).contains(n));
    require(ctx, ok, || {
        format!(
            "`{key}` = {v:?}: expected {}, each in 1 ..= {MAX_MODES}",
            if may_be_empty {
                "mode counts"
            } else {
                "at least one mode count"
            }
        )
    })
}

/// A list of `key` values: at least one, each `ok` (`expected` says what is expected of
/// each, e.g. "a gap >= 0 (m)").
pub fn require_list(
    ctx: &Ctx,
    key: &str,
    v: &[f64],
    ok: impl Fn(f64) -> bool,
    expected: &str,
) -> Result<()> {
    require(ctx, !v.is_empty() && v.iter().all(|&x| ok(x)), || {
        format!("`{key}` = {v:?}: expected at least one value, each {expected}")
    })
}

/// A finite length >= 0 (a gap, m).
pub fn is_gap(x: f64) -> bool {
    x.is_finite() && x >= 0.0
}

/// A coefficient of restitution, in [0, 1].
pub fn is_restitution(x: f64) -> bool {
    (0.0..=1.0).contains(&x)
}

/// A finite number > 0.
pub fn is_positive(x: f64) -> bool {
    x.is_finite() && x > 0.0
}

/// The gap of contact 0 (m, key `gap`) of a study: finite and >= 0.
pub fn require_gap(ctx: &Ctx, gap: f64) -> Result<()> {
    require(ctx, is_gap(gap), || {
        format!("`gap` = {gap:?}: expected a finite gap >= 0 (m)")
    })
}

/// A list `key` of values the scene checks in every case (stiffnesses, tolerances, steps):
/// at least one.
pub fn require_nonempty(ctx: &Ctx, key: &str, v: &[f64]) -> Result<()> {
    require(ctx, !v.is_empty(), || {
        format!("`{key}` = []: expected at least one value")
    })
}

/// The analysis PGA `pga` (g, key `pga`) of a study: finite and > 0.
pub fn require_pga(ctx: &Ctx, pga: f64) -> Result<()> {
    require(ctx, is_positive(pga), || {
        format!("`pga` = {pga:?}: expected a finite peak ground acceleration > 0 (g)")
    })
}

/// Short label of a record file: its stem without the PEER `RSN…_…_` prefix.
pub fn record_label(path: &str) -> String {
    let stem = Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_string());
    match stem.rsplit_once('_') {
        Some((pre, last)) if pre.starts_with("RSN") => last.to_string(),
        _ => stem,
    }
}

/// Name of a record file in the record-based studies' tables: its stem without the PEER
/// `RSN<number>_` prefix (`LOMAP_CAP000`, `NORTHR-RRS_032`), unique across the project's
/// records (unlike [`record_label`], which keeps only the component).
pub fn record_name(path: &str) -> String {
    let stem = Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_string());
    match stem.split_once('_') {
        Some((pre, rest))
            if pre.len() > 3
                && pre.starts_with("RSN")
                && pre[3..].bytes().all(|b| b.is_ascii_digit())
                && !rest.is_empty() =>
        {
            rest.to_string()
        }
        _ => stem,
    }
}

/// A study: its cases and its report.
pub trait Study: Sync {
    fn cases(&self, ctx: &Ctx) -> Result<Vec<CaseSpec>>;
    fn report(&self, ctx: &Ctx, res: &Results) -> Result<()>;
    /// Whether the study's definition takes a `record_table` key (record pulse classes,
    /// [`record_classes`]); default no. [`definition_notes`] says when such a study will
    /// classify no record.
    fn takes_record_table(&self) -> bool {
        false
    }
}

pub fn study(name: &str) -> Option<&'static dyn Study> {
    Some(match name {
        "paper" => &paper::Paper,
        "stiffness" => &stiffness::Stiffness,
        "modes" => &modes::Modes,
        "restitution" => &restitution::Restitution,
        "gap" => &gap::Gap,
        "cost" => &cost::Cost,
        "stability" => &stability::Stability,
        "modelform" => &modelform::ModelForm,
        "robustness" => &robustness::Robustness,
        "yielding" | "yielding-strong" => &yielding::Yielding,
        _ => return None,
    })
}

/// Per-study manifest, written by every run and shard; `merge` rebuilds the case list from
/// it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    pub study: String,
    /// The study definition (TOML text) the cases were built from.
    pub definition: String,
    pub options: StudyOptions,
    pub ids: Vec<String>,
}

/// How to run studies.
#[derive(Debug, Clone)]
pub struct RunConfig {
    pub out: PathBuf,
    pub studies_dir: PathBuf,
    pub threads: Option<usize>,
    pub shard: Option<Shard>,
    pub opts: StudyOptions,
    pub progress: bool,
    /// Recompute cached cases (see [`crate::sweep::EngineOptions::fresh`]).
    pub fresh: bool,
}

/// What happened to one study.
#[derive(Debug, Clone)]
pub struct StudyRun {
    pub name: String,
    pub summary: RunSummary,
    /// Tables and figures written (false for a shard).
    pub reported: bool,
    pub wall_seconds: f64,
    /// Cases whose outcome was not the one they were defined for (failed cases, except
    /// those that exist to show a solver error), as `id: variant, record: error`.
    pub unexpected: Vec<String>,
}

fn make_ctx(
    name: &str,
    definition: &str,
    def_file: &str,
    cfg: &RunConfig,
    opts: &StudyOptions,
) -> Result<Ctx> {
    let def: toml::Table = toml::from_str(definition).map_err(|e| StudyError::Definition {
        file: def_file.to_string(),
        message: e.to_string().trim_end().to_string(),
    })?;
    Ok(Ctx {
        name: name.to_string(),
        def,
        def_file: def_file.to_string(),
        opts: opts.clone(),
        studies_dir: cfg.studies_dir.clone(),
        dir: cfg.out.join(name),
    })
}

/// The full case list of a study: its cases followed by their baselines, without repeats.
/// Every study compares two buildings through contact 0: a scene without them is refused
/// here, naming the study, before anything runs.
pub fn all_cases(st: &dyn Study, ctx: &Ctx) -> Result<Vec<CaseSpec>> {
    let cases = st.cases(ctx)?;
    if let Some(first) = cases.first() {
        // The scene file itself, before the study's overrides (which assume the pair).
        let scene = CaseSpec::new(&first.scene, first.method)
            .load_scene(&ctx.studies_dir)
            .map_err(|message| StudyError::Definition {
                file: ctx.def_file.clone(),
                message,
            })?;
        if scene.buildings.len() < 2 || scene.contacts.is_empty() {
            return Err(StudyError::Definition {
                file: ctx.def_file.clone(),
                message: format!(
                    "study `{}` needs a scene with two buildings joined by a contact; `{}` has {} and {}",
                    ctx.name,
                    first.scene,
                    crate::table::count(scene.buildings.len(), "building", "buildings"),
                    crate::table::count(scene.contacts.len(), "contact", "contacts")
                ),
            });
        }
        let c = &scene.contacts[0];
        let mut pair = [c.left, c.right];
        pair.sort();
        if c.wall {
            return Err(StudyError::Definition {
                file: ctx.def_file.clone(),
                message: format!(
                    "study `{}` reports buildings 1 and 2 at contact 0, which in `{}` is a wall contact (right = \"wall\"): the studies compare two buildings",
                    ctx.name, first.scene
                ),
            });
        }
        if pair != [0, 1] {
            return Err(StudyError::Definition {
                file: ctx.def_file.clone(),
                message: format!(
                    "study `{}` reports buildings 1 and 2 at contact 0, which in `{}` joins buildings {} and {} (counted from 1): list the pair first",
                    ctx.name,
                    first.scene,
                    c.left + 1,
                    c.right + 1
                ),
            });
        }
    }
    let baselines: Vec<CaseSpec> = cases.iter().map(|c| c.baseline()).collect();
    let all = dedup(cases.into_iter().chain(baselines).collect());
    check_every_case(ctx, &all)?;
    Ok(all)
}

/// Every case's scene, with all its overrides, read and validated before anything is
/// written (no solving): a value the scene refuses in any case (a study's `gap_stiffness =
/// 0`, a Newmark step longer than one record's step) is bad input naming the case, the key
/// and the override that set it (exit 2), not a sweep of failed cases (exit 4).
///
/// Cheaply, without reading every record once per case: the scene's checks that involve the
/// record (reading it in its format, scaling it to a PGA, the duration it gives, a Newmark
/// step against its step) read only the record, whether it is scaled to a PGA, and the
/// scene's `ground_motion`, `analysis` and `gap_element.{integrator,time_step}` values; its
/// other checks do not read the record. So each case's overrides (and PGA) are validated
/// once on one record (the first case with them), and each record once with the overrides
/// the record checks read ([`reads_record`]); when the latter is refused, every case on
/// that record is validated in full, so a refusal always names a real case. (A record
/// check added to the scene that reads other values would need them in [`reads_record`].)
fn check_every_case(ctx: &Ctx, specs: &[CaseSpec]) -> Result<()> {
    use std::collections::{BTreeMap, BTreeSet};
    let pga = |c: &CaseSpec| c.pga.map(f64::to_bits);
    let mut overrides = BTreeSet::new();
    for c in specs {
        if overrides.insert((&c.scene, &c.set, pga(c))) {
            c.try_scene(&ctx.studies_dir)
                .map_err(|e| case_refused(ctx, c, e))?;
        }
    }
    // (Whether the record is scaled to a PGA matters to the record checks, not its value.)
    let mut records: BTreeMap<_, Vec<&CaseSpec>> = BTreeMap::new();
    for c in specs {
        let set: Vec<&String> = c.set.iter().filter(|s| reads_record(s)).collect();
        records
            .entry((&c.scene, &c.record, c.pga.is_some(), set))
            .or_default()
            .push(c);
    }
    for ((_, _, _, set), cases) in records {
        let mut probe = cases[0].clone();
        probe.set = set.into_iter().cloned().collect();
        if probe.try_scene(&ctx.studies_dir).is_ok() {
            continue;
        }
        for c in cases {
            c.try_scene(&ctx.studies_dir)
                .map_err(|e| case_refused(ctx, c, e))?;
        }
    }
    Ok(())
}

/// Whether the scene override `expr` (`PATH=VALUE`) sets a value that the scene's record
/// checks read (see [`check_every_case`]).
fn reads_record(expr: &str) -> bool {
    let path = expr.split_once('=').map_or(expr, |(p, _)| p).trim();
    let under = |root: &str| path == root || path.starts_with(&format!("{root}."));
    under("ground_motion")
        || under("analysis")
        || path == "gap_element"
        || under("gap_element.integrator")
        || under("gap_element.time_step")
}

/// The bad-input error of a case whose scene is refused: the case (id, variant, record),
/// the scene's message and the case's overrides that set the refused key.
fn case_refused(ctx: &Ctx, c: &CaseSpec, e: structure::SceneError) -> StudyError {
    let mut message = format!("case {}", c.id);
    let variant = c.params.get("variant").and_then(|v| v.as_str());
    let record = c.record.as_deref().map(record_name);
    match (variant, record) {
        (Some(v), Some(r)) => message.push_str(&format!(" ({v}, record {r})")),
        (Some(v), None) => message.push_str(&format!(" ({v})")),
        (None, Some(r)) => message.push_str(&format!(" (record {r})")),
        (None, None) => {}
    }
    message.push_str(&format!(": {e}"));
    if let structure::SceneError::Invalid { key, .. } = &e {
        // `buildings[0].x` in the scene's message is `buildings.0.x` on an override path.
        let key = key.replace('[', ".").replace(']', "");
        let pga = c.pga.map(|p| format!("ground_motion.pga={p:?}"));
        let set: Vec<&str> = c
            .set
            .iter()
            .map(String::as_str)
            .chain(pga.as_deref())
            .filter(|s| {
                let path = s.split_once('=').map_or(*s, |(p, _)| p).trim();
                path == key
                    || key.starts_with(&format!("{path}."))
                    || path.starts_with(&format!("{key}."))
            })
            .collect();
        if !set.is_empty() {
            message.push_str(&format!(
                " (the study sets `{}` for this case)",
                set.join("`, `")
            ));
        }
    }
    StudyError::Definition {
        file: ctx.def_file.clone(),
        message,
    }
}

fn read_definition(cfg: &RunConfig, name: &str) -> Result<(String, String)> {
    let path = cfg.studies_dir.join(format!("{name}.toml"));
    // A definition that cannot be read (missing, not UTF-8, a folder) is bad input (exit 2),
    // as an unreadable scene is.
    let text = std::fs::read_to_string(&path).map_err(|e| StudyError::Definition {
        file: path.display().to_string(),
        message: format!(
            "cannot read the study definition ({e}); expected a UTF-8 TOML file `{name}.toml` in the studies folder"
        ),
    })?;
    Ok((text, path.display().to_string()))
}

/// A study ready to run ([`prepare_study`]): its definition read and checked and its full
/// case list built, nothing written yet.
pub struct PreparedStudy {
    name: String,
    st: &'static dyn Study,
    text: String,
    ctx: Ctx,
    specs: Vec<CaseSpec>,
    /// Time the preparation took, s (counted in the study's wall time).
    seconds: f64,
    notes: Vec<String>,
}

impl PreparedStudy {
    /// Cases of the study (with their baselines).
    pub fn cases(&self) -> usize {
        self.specs.len()
    }

    /// What to say on stderr about the definition before the study runs
    /// ([`definition_notes`]).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
}

/// Reads and checks a study's definition and builds its case list, writing nothing: all that
/// [`run_study`] does before its first write. `pound studies run` prepares every study it is
/// given before running the first, so that a bad definition of a later study stops the
/// command before any study has written its outputs.
pub fn prepare_study(name: &str, cfg: &RunConfig) -> Result<PreparedStudy> {
    let t0 = Instant::now();
    let st = study(name).ok_or_else(|| {
        StudyError::Other(format!(
            "unknown study `{name}` (studies: {}, {})",
            NAMES.join(", "),
            EXTRA.join(", ")
        ))
    })?;
    let (text, file) = read_definition(cfg, name)?;
    let ctx = make_ctx(name, &text, &file, cfg, &cfg.opts)?;
    let specs = all_cases(st, &ctx)?;
    let notes = definition_notes(&ctx);
    Ok(PreparedStudy {
        name: name.into(),
        st,
        text,
        ctx,
        specs,
        seconds: t0.elapsed().as_secs_f64(),
        notes,
    })
}

/// Runs one study (all its missing cases, or a shard of them) and, unless sharded, writes
/// its tables, figures and summary.
pub fn run_study(name: &str, cfg: &RunConfig) -> Result<StudyRun> {
    run_prepared(prepare_study(name, cfg)?, cfg)
}

/// [`run_study`] of a study prepared with the same `cfg`.
pub fn run_prepared(p: PreparedStudy, cfg: &RunConfig) -> Result<StudyRun> {
    let t0 = Instant::now();
    let PreparedStudy {
        name,
        st,
        text,
        ctx,
        specs,
        seconds,
        notes: _,
    } = p;
    write_json(
        &ctx.dir.join("manifest.json"),
        &Manifest {
            study: name.clone(),
            definition: text,
            options: cfg.opts.clone(),
            ids: specs.iter().map(|s| s.id.clone()).collect(),
        },
    )?;
    let summary = run_cases(
        &specs,
        &EngineOptions {
            study_dir: ctx.dir.clone(),
            studies_dir: cfg.studies_dir.clone(),
            threads: cfg.threads,
            shard: cfg.shard,
            progress: cfg.progress,
            fresh: cfg.fresh,
        },
    )?;
    let reported = cfg.shard.is_none();
    let unexpected = if reported {
        report(st, &ctx, &specs)?
    } else {
        Vec::new()
    };
    Ok(StudyRun {
        name,
        summary,
        reported,
        wall_seconds: seconds + t0.elapsed().as_secs_f64(),
        unexpected,
    })
}

/// One line per case: `id: variant, record: outcome`.
fn describe_case(r: &CaseResult) -> String {
    let label = |k: &str| {
        r.spec
            .params
            .get(k)
            .and_then(|v| v.as_str())
            .map(String::from)
    };
    let what: Vec<String> = [label("variant"), label("record")]
        .into_iter()
        .flatten()
        .collect();
    let outcome = match (&r.error_kind, &r.error) {
        (Some(k), Some(e)) => format!("{k}: {e}"),
        _ => "finished".into(),
    };
    format!("{}: {}: {outcome}", r.spec.id, what.join(", "))
}

/// Tables, figures and the summary; then the failed cases listed at the end of the
/// summary. Returns the cases with an unexpected outcome.
fn report(st: &dyn Study, ctx: &Ctx, specs: &[CaseSpec]) -> Result<Vec<String>> {
    let res = collect(&ctx.name, specs, &ctx.dir)?;
    write_cases_table(&ctx.dir, &res)?;
    st.report(ctx, &res)?;
    if let Some(note) = contact_story_note(&res) {
        let path = ctx.dir.join("summary.md");
        let s = std::fs::read_to_string(&path).unwrap_or_default();
        // After the title line.
        let (title, rest) = s.split_once("\n\n").unwrap_or((&s, ""));
        write_atomic(&path, format!("{title}\n\n{note}\n\n{rest}").as_bytes())?;
    }
    let unexpected: Vec<String> = res
        .iter()
        .filter(|r| r.unexpected())
        .map(describe_case)
        .collect();
    let expected: Vec<String> = res
        .iter()
        .filter(|r| r.spec.expect_failure.is_some() && !r.unexpected())
        .map(describe_case)
        .collect();
    if !unexpected.is_empty() || !expected.is_empty() {
        let path = ctx.dir.join("summary.md");
        let mut s = std::fs::read_to_string(&path).unwrap_or_default();
        if !unexpected.is_empty() {
            s.push_str(&format!(
                "\n### Failed cases ({} of {})\n\nThese cases did not finish as defined; `pound studies run` exits with code 4.\n\n",
                unexpected.len(),
                res.order.len()
            ));
            for u in &unexpected {
                s.push_str(&format!("- `{u}`\n"));
            }
        }
        if !expected.is_empty() {
            s.push_str(&format!(
                "\n### Cases that end with the solver error they exist to show ({})\n\n",
                expected.len()
            ));
            for u in &expected {
                s.push_str(&format!("- `{u}`\n"));
            }
        }
        write_atomic(&path, s.as_bytes())?;
    }
    Ok(unexpected)
}

/// What [`merge`] did.
#[derive(Debug, Clone, Default)]
pub struct Merged {
    /// The studies merged.
    pub studies: Vec<String>,
    /// The cases with an unexpected outcome (`study: id: …`).
    pub unexpected: Vec<String>,
    /// Damaged case files (truncated, corrupt, another case's) passed over for a good copy
    /// of the same case: for each such case the first damaged copy (the copies after the one
    /// used are not read).
    pub damaged: Vec<Damaged>,
    /// What to say on stderr about the definitions ([`definition_notes`]).
    pub notes: Vec<String>,
}

/// A damaged case file that [`merge`] passed over.
#[derive(Debug, Clone)]
pub struct Damaged {
    /// The damaged file.
    pub file: PathBuf,
    /// Why it cannot be used (the parse or read error).
    pub reason: String,
    /// The good copy used instead.
    pub used: PathBuf,
    /// The damaged file is the output's own, and the good copy replaces it.
    pub replaced: bool,
}

/// Merges shard outputs: `dirs` are output roots (each with `<study>/manifest.json` and
/// `<study>/cases/`); coverage is checked (an error lists the missing ids) and every case
/// file to be used is parsed before anything is written: each case's file is the output's
/// own, else the first shard's, and the first of these that parses is used (a damaged one
/// in the output is replaced by a shard's good copy; an error names a damaged file when no
/// copy of that case parses); then the case files are gathered into `out` and the reports
/// are written.
pub fn merge(dirs: &[PathBuf], out: &Path, studies_dir: &Path) -> Result<Merged> {
    // First every study's case list, its completeness and its case files parsed, so that a
    // missing or damaged case of any study stops the merge before anything is written.
    let mut plans = Vec::new();
    let mut damaged_files = Vec::new();
    let mut notes = Vec::new();
    for &name in NAMES.iter().chain(&EXTRA) {
        let manifests: Vec<PathBuf> = dirs
            .iter()
            .map(|d| d.join(name).join("manifest.json"))
            .filter(|p| p.is_file())
            .collect();
        let Some(first) = manifests.first() else {
            continue;
        };
        let text = std::fs::read_to_string(first).map_err(|e| StudyError::Read {
            path: first.display().to_string(),
            message: e.to_string(),
        })?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| StudyError::Manifest {
            path: first.display().to_string(),
            message: e.to_string(),
        })?;
        let cfg = RunConfig {
            out: out.to_path_buf(),
            studies_dir: studies_dir.to_path_buf(),
            threads: None,
            shard: None,
            opts: m.options.clone(),
            progress: false,
            fresh: false,
        };
        let st = study(name).expect("known study");
        let ctx = make_ctx(
            name,
            &m.definition,
            &format!("{} (definition)", first.display()),
            &cfg,
            &m.options,
        )?;
        let specs = all_cases(st, &ctx)?;
        notes.extend(definition_notes(&ctx));
        // Every case's file: the output's own, else the first shard's that has it, the first
        // of these that parses (read and parsed now, before anything is copied or written).
        // A case with no file is missing; one whose every file is damaged stops the merge,
        // naming the first damaged file.
        let dest = out.join(name);
        let mut missing = Vec::new();
        let mut copies = Vec::new();
        for s in &specs {
            let to = case_path(&dest, &s.id);
            let files = std::iter::once(dest.clone())
                .chain(dirs.iter().map(|d| d.join(name)))
                .map(|d| case_path(&d, &s.id))
                .filter(|p| p.is_file());
            let (mut good, mut damaged) = (None, None);
            for f in files {
                match read_case(&f, &s.id) {
                    Ok(_) => {
                        good = Some(f);
                        break;
                    }
                    Err(e) => {
                        damaged.get_or_insert((f, e));
                    }
                }
            }
            match (good, damaged) {
                (None, None) => missing.push(s.id.clone()),
                (None, Some((_, e))) => return Err(e),
                (Some(from), damaged) => {
                    if let Some((bad, e)) = damaged {
                        let reason = match e {
                            StudyError::CaseFile { message, .. } => message,
                            e => e.to_string(),
                        };
                        damaged_files.push(Damaged {
                            replaced: bad == to,
                            file: bad,
                            reason,
                            used: from.clone(),
                        });
                    }
                    if from != to {
                        copies.push((from, to));
                    }
                }
            }
        }
        if !missing.is_empty() {
            return Err(StudyError::Incomplete {
                study: name.into(),
                missing: missing.len(),
                total: specs.len(),
                ids: missing.join(", "),
            });
        }
        plans.push((name, st, m, ctx, specs, copies));
    }
    if plans.is_empty() {
        return Err(StudyError::NoManifests {
            dirs: dirs
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    let mut merged = Vec::new();
    let mut unexpected = Vec::new();
    for (name, st, m, ctx, specs, copies) in plans {
        // (A case already in the output, e.g. when it is one of the shards, is not copied.)
        for (from, to) in &copies {
            let bytes = std::fs::read(from).map_err(|e| StudyError::Read {
                path: from.display().to_string(),
                message: e.to_string(),
            })?;
            write_atomic(to, &bytes)?;
        }
        write_json(
            &ctx.dir.join("manifest.json"),
            &Manifest {
                study: name.into(),
                definition: m.definition.clone(),
                options: m.options.clone(),
                ids: specs.iter().map(|s| s.id.clone()).collect(),
            },
        )?;
        unexpected.extend(
            report(st, &ctx, &specs)?
                .into_iter()
                .map(|u| format!("{name}: {u}")),
        );
        merged.push(name.to_string());
    }
    Ok(Merged {
        studies: merged,
        unexpected,
        damaged: damaged_files,
        notes,
    })
}

// ---------------------------------------------------------------------------------------
// Helpers shared by the studies

/// Amplification factors per building and story: V_max with impact / V_max without.
pub fn amplification(res: &Results, case: &CaseSpec) -> Option<Vec<Vec<f64>>> {
    let with = res.out(case)?;
    let without = res.out(&case.baseline())?;
    Some(
        with.story_shear_max
            .iter()
            .zip(&without.story_shear_max)
            .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x / y).collect())
            .collect(),
    )
}

/// Amplification at the contact story of building `b`: the story below the floor where
/// contact 0 meets the building (its top story when the contact is at the roof).
pub fn amp_contact(res: &Results, case: &CaseSpec, b: usize) -> Option<f64> {
    let story = contact_floor(res.out(case)?, b)?;
    amplification(res, case).and_then(|a| a.get(b).and_then(|v| v.get(story - 1).copied()))
}

/// The floor (from 1) where contact 0 meets building `b`, if it does.
pub fn contact_floor(o: &CaseOutputs, b: usize) -> Option<usize> {
    o.contact_floor.get(b).copied().flatten()
}

/// Peak |displacement| (m) of the floor where contact 0 meets building `b`.
pub fn contact_floor_displacement(o: &CaseOutputs, b: usize) -> Option<f64> {
    let f = contact_floor(o, b)?;
    o.floor_displacement_max
        .get(b)
        .and_then(|v| v.get(f - 1).copied())
}

/// "Contact story" in words: which story of each building the studies' contact-story
/// columns report.
fn contact_story_note(res: &Results) -> Option<String> {
    let o = res
        .iter()
        .filter_map(|r| r.ok())
        .find(|o| !o.contact_floor.is_empty())?;
    let parts: Vec<String> = o
        .contact_floor
        .iter()
        .enumerate()
        .filter_map(|(b, f)| {
            let name = o
                .buildings
                .get(b)
                .cloned()
                .unwrap_or_else(|| format!("building {}", b + 1));
            let n = o.story_shear_max.get(b).map_or(0, |v| v.len());
            f.map(|f| format!("story {f} of {n} of {name}"))
        })
        .collect();
    Some(format!(
        "*Contact story* (columns and readings that say so): the story just below the floor of contact 0, {}.",
        parts.join(" and ")
    ))
}

/// Largest relative story-shear difference |V − V_ref| / V_ref over every story of every
/// building.
pub fn shear_error(o: &CaseOutputs, reference: &CaseOutputs) -> f64 {
    let mut e: f64 = 0.0;
    for (a, r) in o.story_shear_max.iter().zip(&reference.story_shear_max) {
        for (x, y) in a.iter().zip(r) {
            e = e.max((x - y).abs() / y.abs());
        }
    }
    e
}

/// Least-squares slope and intercept of y on x.
pub fn fit_line(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx == 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// `count` log-spaced values from `lo` to `hi`, rounded to 4 significant digits so the
/// overrides are short and stable.
pub fn logspace(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    let (a, b) = (lo.log10(), hi.log10());
    (0..count)
        .map(|i| {
            let x = 10f64.powf(a + (b - a) * i as f64 / (count.max(2) - 1) as f64);
            format!("{x:.3e}").parse().unwrap_or(x)
        })
        .collect()
}

/// Writes `summary.md`: title, reading, tables, figure links.
pub fn write_summary(
    ctx: &Ctx,
    title: &str,
    reading: &[String],
    tables: &[&Table],
    figures: &[(&str, &str)],
) -> Result<()> {
    let mut s = format!("## {title}\n\n");
    if ctx.opts.quick {
        s.push_str(
            "**Quick run** (`--quick`: small grids, one record, 12 s of analysis): a smoke test, \
             not results.\n\n",
        );
    }
    for r in reading {
        s.push_str(r);
        s.push(' ');
    }
    s = s.trim_end().to_string();
    s.push_str("\n\n");
    for (stem, caption) in figures {
        // Relative to the summary's own folder, so the links work wherever `--out` is.
        s.push_str(&format!("![{caption}]({stem}.png)\n\n*{caption}*\n\n"));
    }
    for t in tables {
        s.push_str(&t.markdown());
        s.push('\n');
    }
    write_atomic(&ctx.dir.join("summary.md"), s.as_bytes())?;
    Ok(())
}

/// Mean of the finite values.
pub fn mean(v: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v.into_iter().filter(|x| x.is_finite()) {
        s += x;
        n += 1;
    }
    (n > 0).then(|| s / n as f64)
}

/// The deserialisation default for the analysis PGA (g).
pub fn default_pga() -> f64 {
    0.40
}

/// The default record set: the four Loma Prieta components, relative to `studies/`.
pub fn default_records() -> Vec<String> {
    [
        "RSN752_LOMAP_CAP000.AT2",
        "RSN752_LOMAP_CAP090.AT2",
        "RSN767_LOMAP_G03000.AT2",
        "RSN767_LOMAP_G03090.AT2",
    ]
    .iter()
    .map(|f| format!("../data/ground-motions/{f}"))
    .collect()
}

/// Finished/failed counts as a sentence fragment.
pub fn failures_note(res: &Results) -> Option<String> {
    let failed: Vec<_> = res.iter().filter(|r| r.status != "ok").collect();
    if failed.is_empty() {
        return None;
    }
    let mut kinds: Vec<String> = failed
        .iter()
        .map(|r| r.error_kind.clone().unwrap_or_default())
        .collect();
    kinds.sort();
    kinds.dedup();
    Some(format!(
        "{} of {} cases stopped with a solver error ({}); they are rows with their reason in cases.csv.",
        failed.len(),
        res.order.len(),
        kinds.join(", ")
    ))
}

/// The record metadata table a study reads when its definition has no `record_table` key,
/// relative to the studies folder (the repository's `data/ground-motions/records.csv` from
/// `studies/`); when it does not exist there, every record is unclassified
/// ([`record_classes`]).
pub const DEFAULT_RECORD_TABLE: &str = "../data/ground-motions/records.csv";

/// What a study prints on stderr about its definition before it runs (`note: …`): a study
/// that takes a record table ([`Study::takes_record_table`]) but has no `record_table` key
/// and whose default table ([`DEFAULT_RECORD_TABLE`]) does not exist beside the studies
/// folder classifies no record.
pub fn definition_notes(ctx: &Ctx) -> Vec<String> {
    let mut notes = Vec::new();
    if study(&ctx.name).is_some_and(|s| s.takes_record_table())
        && !ctx.def.contains_key("record_table")
        && !ctx.studies_dir.join(DEFAULT_RECORD_TABLE).exists()
    {
        notes.push(format!(
            "study `{}`: {} has no `record_table` and its default, `{DEFAULT_RECORD_TABLE}` \
            relative to the studies folder ({}), does not exist: every record is unclassified (no \
            pulse / no-pulse split); set `record_table` to a table to classify them",
            ctx.name,
            ctx.def_file,
            ctx.studies_dir.join(DEFAULT_RECORD_TABLE).display()
        ));
    }
    notes
}

/// The records of a record-based study: `--records` if given; else `records` (default: the
/// four Loma Prieta components when neither key is given) followed by every `*.AT2` in each
/// of `record_dirs` (relative to `studies/`, sorted by file name), without repeats; the
/// first one only with `--quick`.
pub fn study_records(
    ctx: &Ctx,
    records: Option<&[String]>,
    record_dirs: &[String],
) -> Result<Vec<String>> {
    if !ctx.opts.records.is_empty() {
        return Ok(ctx.records(&[], true));
    }
    let mut out: Vec<String> = match records {
        Some(r) => r.to_vec(),
        None if record_dirs.is_empty() => default_records(),
        None => Vec::new(),
    };
    for dir in record_dirs {
        let full = ctx.studies_dir.join(dir);
        // A folder the definition names that cannot be listed is bad input (exit 2).
        let rd = std::fs::read_dir(&full).map_err(|e| StudyError::Definition {
            file: ctx.def_file.clone(),
            message: format!("record_dirs: cannot list `{dir}` ({}): {e}", full.display()),
        })?;
        let mut names: Vec<String> = rd
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".AT2"))
            .collect();
        names.sort();
        out.extend(names.into_iter().map(|n| format!("{dir}/{n}")));
    }
    let mut seen = std::collections::BTreeSet::new();
    out.retain(|r| seen.insert(r.clone()));
    require(ctx, !out.is_empty(), || {
        format!(
            "`records` = {:?}, `record_dirs` = {record_dirs:?}: no record; expected at least one record (a file in `records` or a *.AT2 file in a folder of `record_dirs`)",
            records.unwrap_or_default()
        )
    })?;
    Ok(ctx.records(&out, false))
}

/// The pulse class of each record, from the metadata table at `table` (relative to
/// `studies/`; see [`record_table`]). The studies call it when they build their cases too,
/// so a bad table is refused before anything runs. A table the definition names must be
/// readable; without one ([`None`]) the default ([`DEFAULT_RECORD_TABLE`]) is read if it
/// exists, else every record is unclassified ([`definition_notes`] says so).
pub fn record_classes(
    ctx: &Ctx,
    table: Option<&str>,
    recs: &[String],
) -> Result<Vec<record_table::PulseClass>> {
    let table = match table {
        Some(t) => t,
        None if ctx.studies_dir.join(DEFAULT_RECORD_TABLE).exists() => DEFAULT_RECORD_TABLE,
        None => return Ok(vec![record_table::PulseClass::Unclassified; recs.len()]),
    };
    let full = ctx.studies_dir.join(table);
    let t = record_table::RecordTable::load(&full).map_err(|e| match e {
        // The definition names a table that cannot be read: bad input (exit 2).
        record_table::RecordTableError::Read { path, message } => StudyError::Definition {
            file: ctx.def_file.clone(),
            message: format!("record_table: cannot read `{table}` ({path}): {message}"),
        },
        e => e.into(),
    })?;
    Ok(recs.iter().map(|r| t.class(r)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `TAKE_RECORDS` (what the CLI accepts `--records` for) is what the studies do: a study
    /// in the list builds its cases on the given record only, one outside it never uses it.
    #[test]
    fn the_studies_that_take_records_are_those_listed() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let rec = root
            .join("data/ground-motions/RSN767_LOMAP_G03090.AT2")
            .display()
            .to_string();
        let opts = StudyOptions {
            quick: true,
            records: vec![rec.clone()],
            ..Default::default()
        };
        let cfg = RunConfig {
            out: std::env::temp_dir().join("pound-take-records"),
            studies_dir: root.join("studies"),
            threads: None,
            shard: None,
            opts: opts.clone(),
            progress: false,
            fresh: false,
        };
        for name in NAMES.iter().chain(EXTRA.iter()) {
            let (text, file) = read_definition(&cfg, name).unwrap();
            let ctx = make_ctx(name, &text, &file, &cfg, &opts).unwrap();
            let cases = study(name).unwrap().cases(&ctx).unwrap();
            assert!(!cases.is_empty(), "{name}");
            let mine = cases
                .iter()
                .filter(|c| c.record.as_deref() == Some(rec.as_str()))
                .count();
            if TAKE_RECORDS.contains(name) {
                assert_eq!(mine, cases.len(), "{name}: every case on the given record");
            } else {
                assert_eq!(mine, 0, "{name}: its own record");
            }
        }
    }

    /// `check_every_case` (each override set once, each record once with the overrides its
    /// checks read, [`reads_record`]) refuses a list of cases exactly when validating every
    /// case in full refuses one, and then names a case that is refused in full: over records
    /// of three steps (0.02, 0.01, 0.005 s) and two durations (40 s, 19.9 s), with and without
    /// a PGA, and override sets whose refusal depends on the record (a Newmark step longer than
    /// the record's step, a step longer than the record's duration) beside ones that do not.
    /// The records are ordered so that the first case of every override set passes: a
    /// refusal must come from the per-record probe. (Dropping `gap_element.time_step` or
    /// `gap_element.integrator` from [`reads_record`] fails this test.)
    #[test]
    fn the_cheap_check_refuses_what_checking_every_case_refuses() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let gm = root.join("data/ground-motions");
        let records: Vec<String> = [
            "near-field/RSN1086_NORTHR-SYL_032.AT2", // dt 0.02 s, 40 s
            "near-field/RSN1063_NORTHR-RRS_032.AT2", // dt 0.01 s, 19.9 s
            "RSN767_LOMAP_G03090.AT2",               // dt 0.005 s, 39.9 s
        ]
        .iter()
        .map(|r| gm.join(r).display().to_string())
        .collect();
        let ctx = Ctx {
            name: "check".into(),
            def: toml::Table::new(),
            def_file: "check.toml".into(),
            opts: StudyOptions::default(),
            studies_dir: root.join("studies"),
            dir: std::env::temp_dir().join("pound-cheap-check"),
        };
        let newmark = r#"gap_element.integrator="newmark""#;
        let sets: [&[&str]; 8] = [
            &[],
            &[newmark, "gap_element.time_step=0.008"],
            &[newmark, "gap_element.time_step=0.015"],
            &[
                newmark,
                "gap_element.time_step=0.008",
                "buildings.0.damping_ratio=0.03",
            ],
            &["gap_element.time_step=25"],
            &["gap_element.time_step=25", "analysis.duration=30"],
            &["buildings.1.damping_ratio=0.02", "contacts.0.gap=0.05"],
            &["gap_element.time_step=0.015"],
        ];
        let (mut refused, mut passed) = (0, 0);
        for set in sets {
            for pga in [None, Some(0.3)] {
                let specs: Vec<CaseSpec> = records
                    .iter()
                    .map(|r| {
                        set.iter()
                            .fold(
                                CaseSpec::new("paper/scene.toml", Method::Momentum),
                                |c, e| {
                                    let (k, v) = e.split_once('=').unwrap();
                                    c.with(k, v)
                                },
                            )
                            .record(r, pga)
                    })
                    .collect();
                let full: Vec<bool> = specs
                    .iter()
                    .map(|c| c.try_scene(&ctx.studies_dir).is_ok())
                    .collect();
                assert!(
                    full[0],
                    "{set:?}: the first case passes (so the probe decides)"
                );
                match check_every_case(&ctx, &specs) {
                    Ok(()) => {
                        assert!(full.iter().all(|&ok| ok), "{set:?} {pga:?}: {full:?}");
                        passed += 1;
                    }
                    Err(e) => {
                        let msg = e.to_string();
                        let named = specs.iter().zip(&full).find(|(c, _)| msg.contains(&c.id));
                        assert!(
                            matches!(named, Some((_, false))),
                            "{set:?} {pga:?}: names a case refused in full: {msg}"
                        );
                        refused += 1;
                    }
                }
            }
        }
        // Not vacuous: both verdicts occur (sets 2–5 are refused on some record).
        assert_eq!((refused, passed), (8, 8));
    }
}
