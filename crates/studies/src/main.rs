//! `pound`: seismic pounding of adjacent buildings, by the paper's momentum method, the gap
//! element and the impulse method.
//!
//! Exit codes: 0 success; 2 bad input (scene, record, arguments); 3 a solver could not go on;
//! 4 a study sweep finished but some of its cases failed (each study's `summary.md` names
//! them; tables and figures are written from the cases that finished); 1 anything else (for
//! example an output file that cannot be written, or stdout). Stdout closed by its reader (a
//! broken pipe, as in `pound export opensees SCENE | head`) ends the program quietly with
//! [`BROKEN_PIPE_STATUS`].

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};

use solvers::{History, Method};
use structure::ground::record::MIN_RECORD_DT;
use structure::ground::spectrum::{default_periods, response_spectrum};
use structure::ground::{FormatKind, FormatRefusal};
use structure::{GroundMotion, RecordError, RecordFormat, Scene, Units};
use studies::{io, report};

/// Every message on stderr goes through this `eprintln!`, which shadows std's: std's panics when
/// stderr cannot be written (a closed or full stderr), this one drops the message, since there
/// is nowhere left to report the failure; the exit code still tells.
macro_rules! eprintln {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

#[derive(Parser)]
#[command(
    name = "pound",
    version,
    about = "Seismic pounding of adjacent buildings: modal momentum method vs gap element"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Frequencies, periods, effective modal masses and contact flexibility fractions r_N.
    Modes {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene value: PATH=VALUE on a dotted TOML path (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Facts about a ground-motion record: npts, dt, duration, PGA, PGV, PGD.
    Record {
        #[command(flatten)]
        record: RecordArgs,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Elastic response spectrum (exact for piecewise-linear excitation).
    Spectrum {
        #[command(flatten)]
        record: RecordArgs,
        /// Damping ratio (dimensionless).
        #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
        damping: f64,
        /// Scale the record to this peak ground acceleration first (g).
        #[arg(long, allow_negative_numbers = true, value_parser = number_in_g)]
        pga: Option<f64>,
        /// Comma-separated periods (s); default: 100 log-spaced periods from 0.02 to 10 s.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        periods: Option<Vec<f64>>,
        /// Write CSV here (columns period_s,sd_m,psv_m_per_s,psa_g) instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run one analysis of a scene with one method (momentum, gap or impulse).
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Contact treatment: the paper's modal momentum method, the gap element, or the
        /// paper's impact law on the physical floors (impulse).
        #[arg(long, value_enum)]
        method: MethodArg,
        /// Override a scene value: PATH=VALUE on a dotted TOML path (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Write the full result as JSON here; the summary is still printed, except with `-`
        /// or stdout's own file (/dev/stdout, or where stdout is redirected): the JSON instead.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write floor displacements and story shears over time as CSV here.
        #[arg(long)]
        history: Option<PathBuf>,
        /// With --history: one row per this many seconds (the first sample at or after each
        /// multiple, and the last) instead of every sample.
        #[arg(
            long,
            value_name = "SECONDS",
            requires = "history",
            allow_negative_numbers = true
        )]
        history_dt: Option<f64>,
        /// Skip the run without contact that gives the amplification factors.
        #[arg(long)]
        no_baseline: bool,
    },
    /// Export a scene to another program; the script is printed on stdout.
    Export {
        #[command(subcommand)]
        target: ExportTarget,
    },
    /// Parameter studies: run sweeps (resumable, shardable) and merge shards.
    Studies {
        #[command(subcommand)]
        command: StudiesCommand,
    },
}

#[derive(Subcommand)]
enum ExportTarget {
    /// An OpenSeesPy script of the scene (zeroLength springs, modal damping, gap elements,
    /// the embedded record); run it as `python model.py out.json` to get the `pound run`
    /// JSON layout. Compare with `pound run SCENE --method gap --set
    /// gap_element.integrator=newmark`.
    Opensees {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Override a scene value: PATH=VALUE on a dotted TOML path (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Write the script here instead of stdout (nothing is written if the scene is refused).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum StudiesCommand {
    /// Run studies and write their tables and figures under `OUT/<study>/`.
    ///
    /// Finished cases are cached in `OUT/<study>/cases/<id>.json` and skipped on a rerun.
    /// With --shard i/n (default: SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT when set) only
    /// every n-th case runs and only case files are written; `pound studies merge` then
    /// checks coverage and writes the tables and figures.
    Run {
        /// Studies to run: paper, stiffness, modes, restitution, gap, cost, stability,
        /// modelform, yielding (what --all runs); robustness and yielding-strong by name only.
        names: Vec<String>,
        /// Run every study.
        #[arg(long)]
        all: bool,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Folder holding the study definitions (`<name>.toml`) and the scenes they name.
        #[arg(long, default_value = "studies")]
        studies_dir: PathBuf,
        /// Run the record-based studies (stiffness, modes, restitution, gap, modelform,
        /// yielding, yielding-strong, robustness) on these records instead of their
        /// definitions' (PEER AT2 for *.at2 files, else two-column time/acceleration; see
        /// --record-format). Naming a study with
        /// one fixed scene (paper, cost, stability) with --records is an error; with --all
        /// those run their own record.
        #[arg(long, num_args = 1..)]
        records: Vec<PathBuf>,
        /// Format of every --records file: at2, two-column (time, acceleration) or one-column
        /// (acceleration only; needs --record-dt). Default: at2 for *.at2 files, two-column
        /// otherwise; one-column with --record-dt. Units need no option: every study scales
        /// each record to its PGA levels.
        #[arg(long, value_enum, requires = "records")]
        record_format: Option<FormatArg>,
        /// Time step of one-column --records (s); without --record-format it means
        /// one-column.
        #[arg(long, requires = "records", allow_negative_numbers = true)]
        record_dt: Option<f64>,
        /// Run one part of the sweep: cases with index % n == i - 1.
        #[arg(long, value_name = "i/n")]
        shard: Option<String>,
        /// Worker threads, 1 … 1024 (default: one per core).
        #[arg(long)]
        threads: Option<usize>,
        /// Small grids, one record, 12 s of analysis (smoke tests).
        #[arg(long)]
        quick: bool,
        /// Recompute every case even if a finished case file exists (and remove case files
        /// the studies no longer name); without it a rerun resumes. `make studies` uses it.
        #[arg(long)]
        fresh: bool,
    },
    /// Merge shard outputs (output folders of `studies run --shard`), check that every case
    /// is present (listing missing ids otherwise) and write the tables and figures.
    Merge {
        /// Output folders of the shards (each holding `<study>/manifest.json` and cases/).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Where to write the merged results (default: the first folder).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Folder holding the scenes the studies name.
        #[arg(long, default_value = "studies")]
        studies_dir: PathBuf,
    },
}

#[derive(Args)]
struct RecordArgs {
    /// Record file: PEER AT2 (units from its header), two-column time/acceleration, or
    /// one-column.
    record: PathBuf,
    /// File format; default: at2 for *.at2 files, two-column otherwise.
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// Time step of a one-column record (s).
    #[arg(long, allow_negative_numbers = true)]
    dt: Option<f64>,
    /// Units of a two- or one-column record: g (default), m/s^2 or cm/s^2. An AT2 record
    /// states its own units on header line 3; --units must agree with them.
    #[arg(long)]
    units: Option<String>,
}

#[derive(Clone, Copy, ValueEnum)]
enum FormatArg {
    At2,
    TwoColumn,
    OneColumn,
}

impl FormatArg {
    fn kind(self) -> FormatKind {
        match self {
            FormatArg::At2 => FormatKind::At2,
            FormatArg::TwoColumn => FormatKind::TwoColumn,
            FormatArg::OneColumn => FormatKind::OneColumn,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    Momentum,
    Gap,
    Impulse,
}

/// A number for a message or a period column: as written for everyday magnitudes, in exponent
/// form otherwise (`1e-160` or `1e300`, not hundreds of digits).
fn short(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The value of `pound spectrum --pga`: a plain number, in g (`0.3`, not `0.3g`).
fn number_in_g(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|_| "expected a number in g, e.g. 0.3".to_string())
}

/// Smallest nonzero `pound spectrum --periods` value (s). Far below any record step the
/// oscillator is rigid: its PSA is the PGA that period 0 gives (at 1e-6 s on Capitola 000,
/// dt = 0.005 s, to 1.1e-7), so nothing is lost; and below about 5e-154 s the exact step's
/// ω² overflows f64 and the spectrum came out NaN.
const MIN_PERIOD: f64 = 1e-6;

/// Largest `--threads` accepted: beyond it, starting the threads alone takes minutes.
const MAX_THREADS: usize = 1024;

/// An error caused by the user's input (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct InputError(String);

/// Above this PGA (g) a scene's ground motion is almost surely in the wrong units (the
/// largest recorded peaks are about 3–4 g; a record in cm/s² read as g peaks at hundreds of g).
const PLAUSIBLE_PGA_G: f64 = 5.0;

/// Scene settings the gap element takes but does not use with the scene's contact law: said
/// on stderr, so a comparison of methods at c_r < 1 does not silently compare elastic
/// springs with inelastic impacts.
fn gap_law_notes(scene: &structure::Scene) -> Vec<String> {
    use structure::scene::ContactLaw;
    let g = &scene.gap_element;
    let mut notes = Vec::new();
    if g.law == ContactLaw::Linear {
        // One note per entry of the scene file's `contacts` (whose key it names), however
        // many contacts it expands to (`floors = "aligned"`).
        for (entry, group) in scene.contact_entries() {
            let Some(c) = group
                .iter()
                .map(|&i| &scene.contacts[i])
                .find(|c| c.restitution != 1.0)
            else {
                continue;
            };
            let n = group.len();
            let expands = if n > 1 {
                format!(" (for the {n} contacts this entry expands to)")
            } else {
                String::new()
            };
            notes.push(format!(
                "contacts.{entry}.restitution = {}{expands} is not used by the linear gap element \
                (an elastic spring, no dashpot: c_r = 1); set gap_element.law = \"kelvin-voigt\" \
                or \"hertz-damp\" for a damped impact",
                c.restitution
            ));
        }
    }
    if g.tension && g.law != ContactLaw::KelvinVoigt {
        notes.push(format!(
            "gap_element.tension = true applies to the kelvin-voigt law only; the {} law ignores it",
            g.law.key()
        ));
    }
    notes
}

/// A write to stdout that failed (exit code 1, or [`BROKEN_PIPE_STATUS`] quietly when the
/// reader has gone). Not a `#[source]`: the message holds the reason once.
#[derive(Debug, thiserror::Error)]
#[error("cannot write to stdout: {0}")]
struct StdoutError(std::io::Error);

/// Exit status when stdout's reader has closed the pipe (`pound … | head`): 141 = 128 + SIGPIPE
/// (13), the status a shell reports for a C tool such as `cat` or `grep` killed by SIGPIPE,
/// printed without a message. Not 0: the output was cut short, and under `set -o pipefail` a
/// reader that stopped early (or crashed) must not read as a complete output; not 1: nothing
/// is wrong with pound or its input, and scripts already treat 141 as "the reader stopped", as
/// they do for `yes | head`.
const BROKEN_PIPE_STATUS: u8 = 141;

/// The one place the program writes to stdout: the whole text to a locked stdout, flushed, so
/// a failure is an error (std's `print!` panics on one).
fn print_out(text: &str) -> Result<(), StdoutError> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(StdoutError)
}

fn input<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::Error::new(InputError(e.to_string()))
}

/// The files a scene was read from: the scene file and its record (none for free vibration).
fn scene_inputs(path: &std::path::Path, scene: &Scene) -> Vec<(&'static str, PathBuf)> {
    let mut inputs = vec![("scene file", path.to_path_buf())];
    if let Some(src) = &scene.ground_source {
        inputs.push(("scene's record", src.file.clone()));
    }
    inputs
}

/// Refuses (exit 2, before any work) an output path that is one of the run's input files:
/// writing it would replace the scene or the record with the output.
fn refuse_input_as_output(
    flag: &str,
    out: &std::path::Path,
    inputs: &[(&str, PathBuf)],
) -> Result<()> {
    match inputs.iter().find(|(_, p)| io::same_file(out, p)) {
        Some((what, p)) => Err(input(format!(
            "{flag} {}: is the {what} ({}); writing it would replace that input: give another path",
            out.display(),
            p.display()
        ))),
        None => Ok(()),
    }
}

/// The scene overrides that read `studies run --records` files as `--record-format` and
/// `--record-dt` say (after [`check_user_records`] has accepted them): first the study
/// scene's own `ground_motion.format`, `dt` and `units` removed (they describe its own
/// record), so that without the options the format follows each file's extension, as
/// [`check_user_records`] reads it; `--record-dt` alone means one-column, as
/// [`RecordFormat::infer`] has it (the cases read it as given on purpose: the table check of
/// an inferred one-column read is [`check_user_records`]'s).
fn record_overrides(format: Option<FormatArg>, dt: Option<f64>) -> Vec<String> {
    // The study scene's own `format`, `dt` and `units` (for its own record) are removed, so
    // that the cases read every file as these options say, as [`check_user_records`] does.
    let mut set = vec![
        "ground_motion.format=".to_string(),
        "ground_motion.dt=".to_string(),
        "ground_motion.units=".to_string(),
    ];
    let kind = match (format, dt) {
        (None, None) => return set,
        (Some(f), _) => f.kind(),
        (None, Some(_)) => FormatKind::OneColumn,
    };
    set.push(format!("ground_motion.format=\"{}\"", kind.name()));
    if let Some(dt) = dt {
        set.push(format!("ground_motion.dt={dt:?}"));
    }
    set
}

/// Reads every `studies run --records` file (units g: the studies scale each record to their
/// PGA levels) as [`RecordFormat::infer`] chooses from `--record-format`, `--record-dt` and
/// its name, before anything runs: first the options are checked against every file's name
/// (refusals phrased in the options), then each file is read once, so that a record that
/// cannot be read is refused up front, naming it, also with `--quick` (which runs the first
/// record only). A file with one value per line read as two columns is told to give
/// `--record-format one-column --record-dt S`.
fn check_user_records(
    records: &[PathBuf],
    format: Option<FormatArg>,
    dt: Option<f64>,
) -> Result<()> {
    let mut choices = Vec::with_capacity(records.len());
    let mut refusals = Vec::new();
    for r in records {
        match RecordFormat::infer(r, format.map(FormatArg::kind), dt, Units::G) {
            Ok(choice) => choices.push(choice),
            Err(f) => refusals.push((f, r)),
        }
    }
    // The refusal said: the first that asks to remove --record-dt (it does not apply to an
    // AT2 or two-column file, whatever its value), else the first; not one by the files' order.
    if let Some((f, r)) = refusals
        .iter()
        .find(|(f, _)| !matches!(f, FormatRefusal::BadDt { .. }))
        .or(refusals.first())
    {
        return Err(input(records_refusal(*f, format, r)));
    }
    for (r, choice) in records.iter().zip(&choices) {
        let how = match (choice.format, format) {
            (RecordFormat::At2, Some(_)) => "as AT2 (--record-format at2)".to_string(),
            (RecordFormat::At2, None) => "as AT2 (its name ends in .at2)".to_string(),
            (RecordFormat::TwoColumn { .. }, Some(_)) => {
                "as two columns (--record-format two-column)".to_string()
            }
            (RecordFormat::TwoColumn { .. }, None) => {
                "as two columns, time and acceleration (its name does not end in .at2 and no \
                --record-format is given)"
                    .to_string()
            }
            (RecordFormat::OneColumn { dt, .. }, _) => {
                format!("as one column with --record-dt {dt}")
            }
        };
        let read = |e: RecordError| input(format!("--records: {} (read {how}): {e}", r.display()));
        // One read of the file: its bytes are parsed (through the record memo) and, when
        // that fails, looked at for the hint below.
        let bytes = structure::ground::record::read_bytes(r).map_err(read)?;
        let e = match GroundMotion::load_bytes(r, bytes.clone(), choice) {
            Ok(_) => continue,
            Err(e) => e,
        };
        if let RecordError::InferredOneColumn { .. } = e {
            // One-column only because --record-dt came alone: a table is refused.
            return Err(input(format!(
                "--records: {}: {e}: give --record-format two-column without --record-dt to \
                 read time and acceleration, or --record-format one-column to read every value \
                 in order",
                r.display()
            )));
        }
        // The hint only for a file of one value on every line of numbers (not for a table
        // that fails for another reason, such as uneven times).
        let one_column = matches!(choice.format, RecordFormat::TwoColumn { .. })
            && matches!(
                structure::ground::record::values_per_line(&String::from_utf8_lossy(&bytes)),
                Some((1, _))
            );
        return Err(if one_column {
            input(format!(
                "--records: {} holds one value per line, a one-column record, but is read {how}: \
                give --record-format one-column --record-dt S (S: its time step, s)",
                r.display()
            ))
        } else {
            read(e)
        });
    }
    Ok(())
}

/// A refusal of [`RecordFormat::infer`] for the `studies run --records` file `file`, in the
/// options `--record-format` (`format`) and `--record-dt`.
fn records_refusal(refusal: FormatRefusal, format: Option<FormatArg>, file: &Path) -> String {
    match refusal {
        FormatRefusal::BadDt { dt } => format!(
            "--record-dt {}: expected a time step > 0 (s), finite and at least {MIN_RECORD_DT:e} s",
            short(dt)
        ),
        FormatRefusal::DtWithAt2 { dt, by_name: true } => format!(
            "--record-dt {dt}: {} is read as a PEER AT2 record, which states its time step on \
            line 4; remove --record-dt (or give --record-format one-column)",
            file.display()
        ),
        FormatRefusal::DtWithAt2 { dt, by_name: false } | FormatRefusal::DtWithTwoColumn { dt } => {
            format!(
                "--record-dt {dt}: only a one-column record needs a time step, not \
                --record-format {} (AT2 records state theirs on line 4, two-column records \
                take it from the time column); remove --record-dt, or give --record-format \
                one-column",
                format.map_or("", |f| f.kind().name())
            )
        }
        FormatRefusal::OneColumnWithoutDt => {
            "--record-format one-column: give the records' time step with --record-dt (s)".into()
        }
    }
}

/// What [`implausible_pga`] asks to check of a record read with `pound record` or `spectrum`.
const UNITS_FLAG: &str = "check the record's units (--units)";

/// Warns (stderr) when a record's PGA is above [`PLAUSIBLE_PGA_G`]: almost surely read in the
/// wrong units, or a scene's `pga` given in other units than g; `check` says what to check.
fn implausible_pga(g: &GroundMotion, check: &str) {
    let pga = g.pga() / structure::G;
    if pga > PLAUSIBLE_PGA_G {
        eprintln!(
            "warning: the ground motion's PGA is {} g, above {PLAUSIBLE_PGA_G} g, more than any \
            recorded earthquake: {check}",
            if pga < 1e6 {
                format!("{pga:.3}")
            } else {
                format!("{pga:.3e}")
            }
        );
    }
}

/// The record of `pound record` / `spectrum`, read as [`RecordFormat::infer`] chooses from
/// `--format`, `--dt`, `--units` and its name, refusals phrased in those flags.
fn load_record(a: &RecordArgs) -> Result<GroundMotion> {
    let units: Option<Units> = match &a.units {
        None => None,
        Some(u) => Some(
            u.parse()
                .map_err(|_| input(format!("--units `{u}`: expected g, m/s^2 or cm/s^2")))?,
        ),
    };
    let choice = RecordFormat::infer(
        &a.record,
        a.format.map(FormatArg::kind),
        a.dt,
        units.unwrap_or(Units::G),
    )
    .map_err(|refusal| match refusal {
        FormatRefusal::DtWithAt2 { .. } => input(format!(
            "--dt: {} is read as a PEER AT2 record, which states its time step on line 4; remove --dt (or give --format one-column)",
            a.record.display()
        )),
        FormatRefusal::DtWithTwoColumn { .. } => input(
            "--dt: a two-column record takes its time step from its time column; remove --dt",
        ),
        FormatRefusal::OneColumnWithoutDt => input("a one-column record needs --dt (s)"),
        FormatRefusal::BadDt { dt } => input(format!("--dt {}: expected a time step > 0 (s), finite and at least {MIN_RECORD_DT:e} s", short(dt))),
    })?;
    // One read of the file: the header's units are looked at in the bytes then parsed.
    let bytes = structure::ground::record::read_bytes(&a.record).map_err(input)?;
    if let (RecordFormat::At2, Some(u)) = (choice.format, units) {
        // Agreeing with the header is harmless; contradicting it is refused.
        if let Some(h) = String::from_utf8_lossy(&bytes)
            .lines()
            .nth(2)
            .and_then(structure::ground::record::at2_units)
        {
            if h != u {
                return Err(input(format!(
                    "--units {u}: {} states its units on line 3 as {h}; remove --units",
                    a.record.display()
                )));
            }
        }
    }
    GroundMotion::load_bytes(&a.record, bytes, &choice).map_err(|e| match e {
        // One-column only because --dt came without --format: a table is refused.
        RecordError::InferredOneColumn { .. } => input(format!(
            "{e}: give --format two-column without --dt to read time and acceleration, or \
             --format one-column to read every value in order"
        )),
        e => input(e),
    })
}

fn load_scene(path: &Path, set: &[String]) -> Result<Scene> {
    Scene::from_file_with_overrides(path, set).map_err(input)
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Modes {
            scene: path,
            set,
            json,
        } => {
            // The structure alone: a scene without a record or a duration is fine here.
            let scene =
                Scene::from_file_for(&path, &set, structure::Purpose::Structure).map_err(input)?;
            // A building the eigen-solver cannot take is named with its scene file.
            let in_scene = |e: structure::ModelError| input(format!("{}: {e}", path.display()));
            // Floors facing the other building mid-story: `pound run` warns about them too.
            let rest = if json {
                "in `unmodelled`"
            } else {
                "in `unmodelled` of `pound modes --json`"
            };
            if let Some(w) = report::unmodelled_warning(&scene.unmodelled_facings(), rest) {
                eprintln!("warning: {w}");
            }
            let text = if json {
                let doc = report::modes_json(&scene).map_err(in_scene)?;
                format!("{}\n", serde_json::to_string_pretty(&doc)?)
            } else {
                report::modes_table(&scene).map_err(in_scene)?
            };
            print_out(&text)?;
        }
        Command::Record { record, json } => {
            let gm = load_record(&record)?;
            implausible_pga(&gm, UNITS_FLAG);
            let text = if json {
                format!(
                    "{}\n",
                    serde_json::to_string_pretty(&report::record_json(&gm))?
                )
            } else {
                report::record_table(&gm)
            };
            print_out(&text)?;
        }
        Command::Spectrum {
            record,
            damping,
            pga,
            periods,
            out,
        } => {
            if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
                return Err(input(format!(
                    "--damping {damping}: expected 0 <= ratio < 1"
                )));
            }
            if let Some(p) = &out {
                refuse_input_as_output("--out", p, &[("record", record.record.clone())])?;
                io::check_writable(p).map_err(anyhow::Error::new)?;
            }
            let mut gm = load_record(&record)?;
            if pga.is_none() {
                implausible_pga(&gm, UNITS_FLAG);
            }
            if let Some(p) = pga {
                if !(p.is_finite() && p > 0.0) {
                    return Err(input(format!(
                        "--pga {p}: expected a peak ground acceleration > 0 (g)"
                    )));
                }
                if gm.pga() == 0.0 {
                    return Err(input(format!(
                        "--pga {p}: {} is all zeros: it cannot be scaled to a PGA",
                        record.record.display()
                    )));
                }
                gm = gm.scaled_to_pga(p);
            }
            let periods = periods.unwrap_or_else(default_periods);
            if let Some(t) = periods
                .iter()
                .find(|t| !(t.is_finite() && (**t == 0.0 || **t >= MIN_PERIOD)))
            {
                return Err(input(format!(
                    "--periods: {} is not a period of 0 (the rigid limit, PSA = PGA) or a finite period >= {MIN_PERIOD:e} s (below {MIN_PERIOD:e} s the oscillator is rigid: give 0)",
                    short(*t)
                )));
            }
            let spectrum = response_spectrum(&gm, &periods, damping);
            // Accelerations near the largest f64 (a huge --pga) overflow: refused, never a
            // NaN or inf in the output.
            if let Some(p) = spectrum
                .iter()
                .find(|p| !(p.sd.is_finite() && p.psv.is_finite() && p.psa.is_finite()))
            {
                return Err(input(format!(
                    "{}: the spectrum at period {} s is not finite (SD = {} m, PSA = {} m/s^2): the record's accelerations{} are too large to compute with",
                    record.record.display(),
                    short(p.period),
                    short(p.sd),
                    short(p.psa),
                    pga.map(|g| format!(" scaled to --pga {}", short(g)))
                        .unwrap_or_default()
                )));
            }
            let mut csv = String::from("period_s,sd_m,psv_m_per_s,psa_g\n");
            for p in spectrum {
                csv.push_str(&format!(
                    "{},{:.9e},{:.9e},{:.9e}\n",
                    short(p.period),
                    p.sd,
                    p.psv,
                    p.psa / structure::G
                ));
            }
            match out {
                Some(path) => io::write_atomic(&path, csv.as_bytes())?,
                None => print_out(&csv)?,
            }
        }
        Command::Run {
            scene: path,
            method,
            set,
            out,
            history,
            history_dt,
            no_baseline,
        } => {
            if let Some(dt) = history_dt {
                if !(dt.is_finite() && dt > 0.0) {
                    return Err(input(format!(
                        "--history-dt {dt}: expected a finite number of seconds > 0"
                    )));
                }
            }
            if let (Some(o), Some(h)) = (&out, &history) {
                if io::same_destination(o, h) {
                    return Err(input(format!(
                        "--out and --history are the same file ({}): give two paths",
                        o.display()
                    )));
                }
            }
            let scene = load_scene(&path, &set)?;
            let method = match method {
                MethodArg::Momentum => Method::Momentum,
                MethodArg::Gap => Method::Gap,
                MethodArg::Impulse => Method::Impulse,
            };
            if method == Method::Gap {
                for w in gap_law_notes(&scene) {
                    eprintln!("note: {w}");
                }
            }
            if let Some(g) = &scene.ground {
                // A `pga` the scene gives is the PGA as run: the likely culprit itself.
                let pga_given = scene.ground_source.as_ref().and_then(|s| s.pga_g);
                match pga_given {
                    Some(p) => implausible_pga(
                        g,
                        &format!(
                            "check ground_motion.pga = {}: it is the PGA as run, in g (0.3 means \
                            0.3 g), whatever the record's units",
                            short(p)
                        ),
                    ),
                    // An AT2 record's units are its header's (line 3; `units` is refused).
                    None => implausible_pga(
                        g,
                        match scene.ground_source.as_ref().map(|s| &s.format) {
                            Some(structure::RecordFormat::At2) => {
                                "check the record's units (its header, line 3) and \
                                 ground_motion.scale"
                            }
                            _ => {
                                "check the record's units (ground_motion.units and \
                                 ground_motion.scale)"
                            }
                        },
                    ),
                }
            }
            if let (Method::Momentum, Some(n)) = (method, scene.momentum.modes) {
                for b in scene.buildings.iter().filter(|b| b.n_floors() < n) {
                    eprintln!(
                        "note: momentum.modes = {n} exceeds the {} of {}: all {} kept",
                        studies::table::count(b.n_floors(), "mode", "modes"),
                        b.name,
                        b.n_floors()
                    );
                }
            }
            // The summary goes to stdout unless the JSON does: `--out -`, or an output that is
            // stdout's own file (`/dev/stdout`, or the file stdout is redirected to); with any
            // other file or device (`--out run.json`, `/dev/null`) it is printed too. Decided,
            // and a folder or unwritable place (for `--history` too) refused, before the
            // analysis runs.
            let inputs = scene_inputs(&path, &scene);
            for (flag, p) in [("--out", &out), ("--history", &history)] {
                if let Some(p) = p.as_deref().filter(|p| p.as_os_str() != "-") {
                    refuse_input_as_output(flag, p, &inputs)?;
                }
            }
            if let Some(h) = &history {
                io::check_writable(h).map_err(anyhow::Error::new)?;
            }
            let summary = match &out {
                None => true,
                Some(p) if p.as_os_str() == "-" => false,
                Some(p) => {
                    io::check_writable(p).map_err(anyhow::Error::new)?;
                    !io::is_stdout(p)
                }
            };
            let mut hist = history.as_ref().map(|_| History::default());
            let result = solvers::run(&scene, method, hist.as_mut())
                .with_context(|| format!("{}: {method} analysis failed", path.display()))?;
            // The same model without contact, same method and options: the denominator of
            // the amplification factor.
            let amplification = if no_baseline || scene.contacts.is_empty() {
                None
            } else {
                let mut free = scene.clone();
                free.contacts.clear();
                let base = solvers::run(&free, method, None).with_context(|| {
                    format!(
                        "{}: {method} analysis without contact failed",
                        path.display()
                    )
                })?;
                Some(report::amplification(&result, &base))
            };
            for w in report::overlap_warnings(&result) {
                eprintln!("warning: {w}");
            }
            // All or nothing: the history and the result are written together or not at all
            // (a file that was there before is left as it was).
            let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
            if let (Some(p), Some(h)) = (&history, &hist) {
                files.push((
                    p.clone(),
                    io::history_csv(&scene, h, history_dt)?.into_bytes(),
                ));
            }
            let mut stdout_json = None;
            if let Some(p) = &out {
                let doc = report::run_json(&scene, &set, &result, amplification.as_deref());
                let s = io::json_text(&doc, &p.display().to_string())?;
                if p.as_os_str() == "-" {
                    stdout_json = Some(s);
                } else {
                    files.push((p.clone(), s.into_bytes()));
                }
            }
            let refs: Vec<(&std::path::Path, &[u8])> = files
                .iter()
                .map(|(p, b)| (p.as_path(), b.as_slice()))
                .collect();
            io::write_all_atomic(&refs)?;
            if !files.is_empty() {
                let names: Vec<String> =
                    files.iter().map(|(p, _)| p.display().to_string()).collect();
                eprintln!("wrote {}", names.join(", "));
            }
            if let Some(s) = stdout_json {
                print_out(&s)?;
            } else if summary {
                print_out(&report::run_summary(
                    &scene,
                    &result,
                    amplification.as_deref(),
                ))?;
            }
        }
        Command::Export {
            target:
                ExportTarget::Opensees {
                    scene: path,
                    set,
                    out,
                },
        } => {
            let scene = load_scene(&path, &set)?;
            if let Some(p) = &out {
                refuse_input_as_output("--out", p, &scene_inputs(&path, &scene))?;
                io::check_writable(p).map_err(anyhow::Error::new)?;
            }
            let script = studies::export::opensees_script(&scene)
                .map_err(|e| input(format!("{}: {e}", path.display())))?;
            for w in studies::export::opensees_caveats(&scene) {
                eprintln!("warning: {w}");
            }
            match out {
                Some(p) => io::write_atomic(&p, script.as_bytes())?,
                None => print_out(&script)?,
            }
        }
        Command::Studies { command } => studies_command(command)?,
    }
    Ok(())
}

fn studies_command(command: StudiesCommand) -> Result<()> {
    use studies::studies as st;
    match command {
        StudiesCommand::Run {
            names,
            all,
            out,
            studies_dir,
            records,
            record_format,
            record_dt,
            shard,
            threads,
            quick,
            fresh,
        } => {
            if names.is_empty() && !all {
                return Err(input(format!(
                    "name at least one study or give --all (studies: {}){}",
                    st::NAMES.join(", "),
                    if records.is_empty() {
                        ""
                    } else {
                        "; --records takes every argument after it: name the studies before --records"
                    }
                )));
            }
            for n in &names {
                if st::study(n).is_none() {
                    return Err(input(format!(
                        "unknown study `{n}` (studies: {}; by name only: {})",
                        st::NAMES.join(", "),
                        st::EXTRA.join(", ")
                    )));
                }
            }
            // --all with names: every study of --all, then the named ones it does not hold
            // (e.g. `--all robustness`), each once.
            let names: Vec<String> = if all {
                let mut v: Vec<String> = st::NAMES.iter().map(|s| s.to_string()).collect();
                for n in names {
                    if !v.contains(&n) {
                        v.push(n);
                    }
                }
                v
            } else {
                names
            };
            if threads == Some(0) {
                return Err(input("--threads 0: expected at least 1"));
            }
            if let Some(n) = threads.filter(|&n| n > MAX_THREADS) {
                return Err(input(format!(
                    "--threads {n}: expected at most {MAX_THREADS} (this machine has {} cores; \
                     cases run one per thread, so more threads than cores only costs memory)",
                    std::thread::available_parallelism().map_or(1, |n| n.get())
                )));
            }
            let shard = match shard {
                Some(s) => Some(s.parse::<studies::sweep::Shard>().map_err(input)?),
                None => studies::sweep::Shard::from_slurm().map_err(input)?,
            };
            // Studies with one fixed scene and record: named with --records, an error; taken
            // in by --all, said on stderr.
            let fixed: Vec<&str> = names
                .iter()
                .map(String::as_str)
                .filter(|n| !st::TAKE_RECORDS.contains(n))
                .collect();
            if !records.is_empty() && !fixed.is_empty() {
                if !all {
                    return Err(input(format!(
                        "--records: {} {} one fixed scene and record, not yours; --records applies to {}",
                        fixed.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", "),
                        if fixed.len() == 1 { "runs" } else { "run" },
                        st::TAKE_RECORDS.join(", ")
                    )));
                }
                eprintln!(
                    "--records: {} run their own scene and record",
                    fixed.join(", ")
                );
            }
            let mut recs = Vec::new();
            for r in &records {
                match structure::ground::record_path_problem(r) {
                    Some(structure::ground::RecordPathProblem::Folder) => {
                        return Err(input(format!(
                            "--records: {} is a folder; give the record files (e.g. {}/*.AT2)",
                            r.display(),
                            r.display()
                        )))
                    }
                    Some(problem) => {
                        return Err(input(format!("--records: {} {problem}", r.display())))
                    }
                    None => {}
                }
                recs.push(std::path::absolute(r)?.display().to_string());
            }
            check_user_records(&records, record_format, record_dt)?;
            let record_set = record_overrides(record_format, record_dt);
            if !studies_dir.is_dir() {
                return Err(input(format!(
                    "--studies-dir {}: not a folder (expected the folder holding the study definitions, <name>.toml; the default is ./studies, so run from the repository's root or give --studies-dir DIR)",
                    studies_dir.display()
                )));
            }
            let cfg = st::RunConfig {
                out: out.clone(),
                studies_dir,
                threads,
                shard,
                opts: st::StudyOptions {
                    quick,
                    records: recs,
                    record_set,
                },
                progress: true,
                fresh,
            };
            let t0 = std::time::Instant::now();
            let mut timings = serde_json::Map::new();
            let mut unexpected = Vec::new();
            // A definition or scene the study cannot use is bad input (exit 2).
            let bad = |n: &str, e: studies::sweep::StudyError| match e {
                studies::sweep::StudyError::Definition { .. } => input(format!("study `{n}`: {e}")),
                e => anyhow::Error::new(e).context(format!("study `{n}`")),
            };
            // Every study's definition and case list first (0.3 s for all of them, one run),
            // so that a bad definition of a later study stops the command before any study
            // has written its outputs.
            let prepared = names
                .iter()
                .map(|n| st::prepare_study(n, &cfg).map_err(|e| bad(n, e)))
                .collect::<Result<Vec<_>>>()?;
            for w in prepared.iter().flat_map(|p| p.notes()) {
                eprintln!("note: {w}");
            }
            for (n, p) in names.iter().zip(prepared) {
                let r = st::run_prepared(p, &cfg).map_err(|e| bad(n, e))?;
                // Failures the study exists to show (e.g. chattering without the persistent
                // contact phase) are results; say so, so they do not read as errors.
                let failed = match (r.summary.failed, r.unexpected.len()) {
                    (f, 0) if f > 0 => format!("{f} failed, as the study expects"),
                    (f, u) if u < f => format!("{f} failed, {u} of them unexpectedly"),
                    (f, _) => format!("{f} failed"),
                };
                eprintln!(
                    "{:<12} {}: {} run ({failed}), {} cached, {} in other shards; {:.1} s{}",
                    r.name,
                    studies::table::count(r.summary.total, "case", "cases"),
                    r.summary.ran,
                    r.summary.skipped,
                    r.summary.other_shards,
                    r.wall_seconds,
                    if r.reported {
                        format!(" -> {}", out.join(n).display())
                    } else {
                        " (shard: case files only)".into()
                    }
                );
                unexpected.extend(r.unexpected.iter().map(|u| format!("{n}: {u}")));
                timings.insert(
                    n.clone(),
                    serde_json::json!({
                        "wall_seconds": r.wall_seconds,
                        "cases": r.summary.total,
                        "ran": r.summary.ran,
                        "cached": r.summary.skipped,
                        "failed": r.summary.failed,
                    }),
                );
            }
            let total = t0.elapsed().as_secs_f64();
            if shard.is_none() {
                // One entry per study, kept across runs: a run of some studies (e.g.
                // `make robustness` after `make studies`) replaces only their entries. The
                // run's own total and settings are stored with each entry.
                let path = out.join("timing.json");
                let mut all: serde_json::Map<String, serde_json::Value> =
                    std::fs::read_to_string(&path)
                        .ok()
                        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
                        .and_then(|v| v.get("studies").and_then(|s| s.as_object()).cloned())
                        .unwrap_or_default();
                let threads = threads.unwrap_or_else(rayon::current_num_threads);
                // A study whose cases were all cached ran nothing: its entry keeps the time of
                // the run that computed them.
                for (name, mut entry) in timings {
                    let ran = entry.get("ran").and_then(|r| r.as_u64()).unwrap_or(0);
                    if ran == 0 && all.contains_key(&name) {
                        continue;
                    }
                    if let Some(e) = entry.as_object_mut() {
                        e.insert("run_total_wall_seconds".into(), total.into());
                        e.insert("threads".into(), threads.into());
                        e.insert("quick".into(), quick.into());
                    }
                    all.insert(name, entry);
                }
                let doc = serde_json::json!({ "studies": all });
                io::write_json(&path, &doc)?;
            }
            eprintln!("total wall time {total:.1} s");
            failed_cases(&unexpected)?;
        }
        StudiesCommand::Merge {
            dirs,
            out,
            studies_dir,
        } => {
            for d in &dirs {
                if !d.is_dir() {
                    return Err(input(format!(
                        "{}: not a folder (expected the output folder of a `studies run --shard` run)",
                        d.display()
                    )));
                }
            }
            let out = out.unwrap_or_else(|| dirs[0].clone());
            // A shard missing, a case file that does not parse, or folders without
            // manifests, is bad input (exit 2); the checks come before anything is written.
            let merged = st::merge(&dirs, &out, &studies_dir).map_err(|e| match e {
                studies::sweep::StudyError::Incomplete { .. }
                | studies::sweep::StudyError::CaseFile { .. }
                | studies::sweep::StudyError::Manifest { .. }
                | studies::sweep::StudyError::Definition { .. }
                | studies::sweep::StudyError::NoManifests { .. } => input(e),
                e => anyhow::Error::new(e),
            })?;
            for w in &merged.notes {
                eprintln!("note: {w}");
            }
            for d in &merged.damaged {
                let what = if d.replaced {
                    "replaced by"
                } else {
                    "passed over for"
                };
                eprintln!(
                    "note: {} is not a usable case file ({}): {what} {}",
                    d.file.display(),
                    d.reason,
                    d.used.display()
                );
            }
            eprintln!(
                "merged {} into {}",
                merged.studies.join(", "),
                out.display()
            );
            failed_cases(&merged.unexpected)?;
        }
    }
    Ok(())
}

/// Cases of a sweep that did not finish as defined (exit code 4).
#[derive(Debug, thiserror::Error)]
#[error("{} failed (listed in each study's summary.md):\n  {}", studies::table::count(.0.len(), "case", "cases"), .0.join("\n  "))]
struct FailedCases(Vec<String>);

fn failed_cases(unexpected: &[String]) -> Result<()> {
    if unexpected.is_empty() {
        Ok(())
    } else {
        Err(FailedCases(unexpected.to_vec()).into())
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // `--help` and `--version` print on stdout, argument errors on stderr: a failed
            // help is a failed stdout write like any other.
            if let Err(io) = e.print() {
                if !e.use_stderr() {
                    return stdout_failed(&StdoutError(io));
                }
            }
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2));
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if let Some(s) = e.chain().find_map(|c| c.downcast_ref::<StdoutError>()) {
                return stdout_failed(s);
            }
            eprintln!("error: {e:#}");
            let refused = e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<solvers::SolverError>(),
                    Some(solvers::SolverError::Refused { .. } | solvers::SolverError::Model(_))
                )
            });
            if e.downcast_ref::<InputError>().is_some() || refused {
                ExitCode::from(2)
            } else if e.downcast_ref::<FailedCases>().is_some() {
                ExitCode::from(4)
            } else if e
                .chain()
                .any(|c| c.downcast_ref::<solvers::SolverError>().is_some())
            {
                ExitCode::from(3)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

/// The exit of a failed stdout write: quiet with [`BROKEN_PIPE_STATUS`] when the reader has
/// closed the pipe (the reader wanted no more, or is gone: nothing left to tell), else the
/// error and 1.
fn stdout_failed(e: &StdoutError) -> ExitCode {
    if e.0.kind() == std::io::ErrorKind::BrokenPipe {
        ExitCode::from(BROKEN_PIPE_STATUS)
    } else {
        eprintln!("error: {e}");
        ExitCode::from(1)
    }
}
