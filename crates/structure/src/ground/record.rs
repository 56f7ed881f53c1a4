//! Ground-motion records: choosing how a file is read ([`RecordFormat::infer`], the one rule
//! the scene loader and the commands use), reading (PEER AT2, two-column, one-column),
//! scaling, peaks and piecewise-linear interpolation.
//!
//! Every record is stored in SI units (m/s²) on a uniform grid: sample `i` is at `t = i·dt`.
//! Between samples the acceleration is taken as linear, which is also the assumption of
//! the exact (Nigam–Jennings) integration used for spectra and modal responses, so
//! [`GroundMotion::pgv`] and [`GroundMotion::pgd`] integrate that same piecewise-linear
//! function exactly.
//!
//! Parsing never panics: every problem comes back as a [`RecordError`] whose message names
//! the file, the 1-based line and what was expected.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// Units of the acceleration values in a record file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    /// Multiples of standard gravity ([`crate::G`]).
    #[serde(rename = "g", alias = "G")]
    G,
    /// m/s².
    #[serde(rename = "m/s^2", alias = "m/s2")]
    MetersPerSecond2,
    /// cm/s² (gal).
    #[serde(rename = "cm/s^2", alias = "cm/s2", alias = "gal")]
    CentimetersPerSecond2,
}

impl Units {
    /// Factor converting a value in these units to m/s².
    pub fn to_si(self) -> f64 {
        match self {
            Units::G => crate::G,
            Units::MetersPerSecond2 => 1.0,
            Units::CentimetersPerSecond2 => 0.01,
        }
    }

    /// The canonical spelling (`"g"`, `"m/s^2"`, `"cm/s^2"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Units::G => "g",
            Units::MetersPerSecond2 => "m/s^2",
            Units::CentimetersPerSecond2 => "cm/s^2",
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Error of [`Units::from_str`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown acceleration units `{0}`: expected \"g\", \"m/s^2\" (or \"m/s2\"), \"cm/s^2\" (or \"cm/s2\", \"gal\")")]
pub struct ParseUnitsError(pub String);

impl FromStr for Units {
    type Err = ParseUnitsError;

    /// Accepts `g`, `m/s2`, `m/s^2`, `cm/s2`, `cm/s^2`, `gal` (case-insensitive, trimmed).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "g" => Ok(Units::G),
            "m/s2" | "m/s^2" => Ok(Units::MetersPerSecond2),
            "cm/s2" | "cm/s^2" | "gal" => Ok(Units::CentimetersPerSecond2),
            _ => Err(ParseUnitsError(s.to_string())),
        }
    }
}

/// Layout of a record file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "format", rename_all = "kebab-case")]
pub enum RecordFormat {
    /// PEER NGA `.AT2`: four header lines (line 4 gives NPTS and DT), then the values in g.
    At2,
    /// `time accel` per line (whitespace or comma separated); `#` comments and blank lines
    /// allowed; times uniformly spaced, starting anywhere.
    TwoColumn { units: Units },
    /// Values only (one or several per line), with the time step given.
    OneColumn { dt: f64, units: Units },
}

/// A record file's layout without its settings: what a scene's `ground_motion.format` or a
/// command's `--format` names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FormatKind {
    /// PEER NGA `.AT2` ([`RecordFormat::At2`]).
    At2,
    /// Time and acceleration ([`RecordFormat::TwoColumn`]).
    TwoColumn,
    /// Acceleration values only, with a time step ([`RecordFormat::OneColumn`]).
    OneColumn,
}

impl FormatKind {
    /// The name scenes and commands use: `"at2"`, `"two-column"`, `"one-column"`.
    pub fn name(self) -> &'static str {
        match self {
            FormatKind::At2 => "at2",
            FormatKind::TwoColumn => "two-column",
            FormatKind::OneColumn => "one-column",
        }
    }

    /// The kind named `name` exactly ([`FormatKind::name`]), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        [
            FormatKind::At2,
            FormatKind::TwoColumn,
            FormatKind::OneColumn,
        ]
        .into_iter()
        .find(|k| k.name() == name)
    }
}

/// How a record file is to be read, as [`RecordFormat::infer`] chose it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordChoice {
    pub format: RecordFormat,
    /// One-column only because a time step came without a format: the read
    /// ([`GroundMotion::load_choice`]) then refuses a table of two or more values on every
    /// line ([`RecordError::InferredOneColumn`]). Without effect on the other formats.
    pub inferred: bool,
}

impl RecordChoice {
    /// The format given on purpose (not inferred).
    pub fn explicit(format: RecordFormat) -> Self {
        RecordChoice {
            format,
            inferred: false,
        }
    }

    /// Whether the read refuses a table ([`RecordChoice::inferred`] one-column).
    fn refuses_tables(&self) -> bool {
        self.inferred && matches!(self.format, RecordFormat::OneColumn { .. })
    }
}

/// Why [`RecordFormat::infer`] refuses a format, a time step and a file name together. The
/// messages name no setting: each caller phrases the refusal in its own keys or flags.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum FormatRefusal {
    /// A time step for a PEER AT2 record, which states its own on header line 4. `by_name`:
    /// no format was given and the file's name ends in `.at2` ([`is_at2_name`]).
    #[error(
        "a time step ({dt} s) was given for a PEER AT2 record ({}), which states its time step \
         on header line 4",
        if *.by_name { "its name ends in .at2" } else { "the format given" }
    )]
    DtWithAt2 { dt: f64, by_name: bool },
    /// A time step for a record given as two-column, which takes its step from its times.
    #[error(
        "a time step ({dt} s) was given for a two-column record, which takes its time step \
         from its time column"
    )]
    DtWithTwoColumn { dt: f64 },
    /// A record given as one-column without its time step.
    #[error("a one-column record needs its time step")]
    OneColumnWithoutDt,
    /// A time step of a one-column record that is not finite and > 0.
    #[error("expected a time step > 0 (s), finite and at least {MIN_RECORD_DT:e} s, found {}", short_number(*.dt))]
    BadDt { dt: f64 },
}

/// The shortest time step a record may have, s. Accelerographs sample at 50 … 1 000 Hz
/// (0.02 … 0.001 s) and a refined record at a small fraction of that; a step far below a
/// microsecond is a unit or typing error, and one near the bottom of the floating-point range
/// (1e-300 s) cannot be computed with (the propagators' ωh underflows and the solvers stop
/// at t = 0 with a non-finite state instead of naming the record's step).
pub const MIN_RECORD_DT: f64 = 1e-6;

/// A number for a message: as written for everyday magnitudes, in exponent form otherwise
/// (`1e-320`, not hundreds of digits).
pub fn short_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-3..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Whether `dt` is a record time step pound accepts: finite and at least [`MIN_RECORD_DT`].
pub fn valid_dt(dt: f64) -> bool {
    dt.is_finite() && dt >= MIN_RECORD_DT
}

/// Whether `path` is named like a PEER AT2 record: its extension is `at2` in any case.
pub fn is_at2_name(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("at2"))
}

impl RecordFormat {
    /// The one rule that chooses how a record file is read, from the format given (if
    /// any), the time step given (if any) and the file's name (not its content: nothing is
    /// read). Without a format: AT2 for a name ending in `.at2` (any case), else one-column
    /// when a time step is given ([`RecordChoice::inferred`]), else two-column. A time step
    /// is refused with AT2 and two-column, needed (finite, > 0) with one-column, in that
    /// order. `units` are those of a two- or one-column record; an AT2 record states its own
    /// on header line 3, and whether units given with it are refused or compared with the
    /// header is the caller's to decide.
    pub fn infer(
        path: &Path,
        format: Option<FormatKind>,
        dt: Option<f64>,
        units: Units,
    ) -> Result<RecordChoice, FormatRefusal> {
        let kind = match format {
            Some(k) => k,
            None if is_at2_name(path) => FormatKind::At2,
            None if dt.is_some() => FormatKind::OneColumn,
            None => FormatKind::TwoColumn,
        };
        let inferred = format.is_none() && kind == FormatKind::OneColumn;
        let format = match (kind, dt) {
            (FormatKind::At2, Some(dt)) => {
                return Err(FormatRefusal::DtWithAt2 {
                    dt,
                    by_name: format.is_none(),
                })
            }
            (FormatKind::At2, None) => RecordFormat::At2,
            (FormatKind::TwoColumn, Some(dt)) => return Err(FormatRefusal::DtWithTwoColumn { dt }),
            (FormatKind::TwoColumn, None) => RecordFormat::TwoColumn { units },
            (FormatKind::OneColumn, None) => return Err(FormatRefusal::OneColumnWithoutDt),
            (FormatKind::OneColumn, Some(dt)) if !valid_dt(dt) => {
                return Err(FormatRefusal::BadDt { dt })
            }
            (FormatKind::OneColumn, Some(dt)) => RecordFormat::OneColumn { dt, units },
        };
        Ok(RecordChoice { format, inferred })
    }

    /// Its kind, without its settings.
    pub fn kind(&self) -> FormatKind {
        match self {
            RecordFormat::At2 => FormatKind::At2,
            RecordFormat::TwoColumn { .. } => FormatKind::TwoColumn,
            RecordFormat::OneColumn { .. } => FormatKind::OneColumn,
        }
    }
}

/// Records parsed by [`GroundMotion::load_bytes`] in this process, by (file bytes, file name,
/// format), with the bytes they hold; forgotten all at once before they would pass
/// [`RECORDS_BYTES`] (the 60 records of the studies hold about 8 MB). An inferred one-column
/// read shares the explicit read's entry (the record is the same) but makes its table check
/// before looking the record up, so a table that an explicit read accepted is still refused.
type RecordKey = (Vec<u8>, String, String);
#[derive(Default)]
struct RecordMemo {
    records: std::collections::HashMap<RecordKey, GroundMotion>,
    bytes: usize,
}
static RECORDS: std::sync::LazyLock<std::sync::Mutex<RecordMemo>> =
    std::sync::LazyLock::new(Default::default);
const RECORDS_BYTES: usize = 64 << 20;

/// A uniformly sampled ground acceleration record.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundMotion {
    /// Record name (the file stem for records read from files).
    pub name: String,
    /// Time step, s.
    pub dt: f64,
    /// Acceleration, m/s²; sample `i` at `t = i·dt`.
    pub accel: Vec<f64>,
}

/// Why a record could not be read. Every message names the file, the 1-based line (where
/// one applies) and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The OS error is part of the message (not a chained source, which would print it
    /// twice).
    #[error("{path}: cannot read the record file: {}", io_reason(.error))]
    Io { path: String, error: std::io::Error },
    #[error("{origin} line {line}: expected {expected}, found {found:?}")]
    Header {
        origin: String,
        line: usize,
        expected: String,
        found: String,
    },
    /// `column` is the 1-based character column where the offending token starts. `header`:
    /// the line is the file's first data line (of a two- or one-column record) and starts
    /// with a word, as a header line would: the message then says how to keep it.
    #[error(
        "{origin} line {line}, column {column}: expected {expected}, found {found:?}{}",
        if *.header { HEADER_HINT } else { "" }
    )]
    Value {
        origin: String,
        line: usize,
        column: usize,
        expected: String,
        found: String,
        header: bool,
    },
    /// A file read as one-column (a time step given) whose every data line holds two
    /// numbers, the first rising by a constant `step` like times: a two-column record.
    /// `line` is its first data line.
    #[error("{origin} line {line}: {}", two_columns_as_one(*.step))]
    TwoColumnsAsOne {
        origin: String,
        line: usize,
        step: f64,
    },
    /// A file read as one-column only because a time step was given without a format
    /// ([`RecordChoice::inferred`]), whose every line of numbers holds the same count
    /// `values` ≥ 2 (a table such as time and acceleration, whatever its step): refused
    /// rather than read value after value. `line`: its first line of numbers. The message
    /// ends where the caller adds, after `: `, the settings to give in its own keys or flags.
    #[error(
        "{origin} line {line}: every line of numbers holds {values} values, as a table with a \
         time column does, but the file is read as one-column because a time step was given \
         without a format"
    )]
    InferredOneColumn {
        origin: String,
        line: usize,
        values: usize,
    },
    /// The number of values declared in the header (at `line`) differs from the number present.
    #[error(
        "{origin} line {line}: the header declares NPTS = {declared}, but the file holds {} \
         (expected exactly {declared})",
        crate::count(*.found, "value", "values")
    )]
    Count {
        origin: String,
        line: usize,
        declared: usize,
        found: usize,
    },
    #[error("{origin} line {line}: expected a finite number, found {found:?}")]
    NonFinite {
        origin: String,
        line: usize,
        found: String,
    },
    /// A value finite in the file's units that overflows in m/s².
    #[error("{origin} line {line}: {found:e} {units} is beyond the range of floating point in m/s^2 (expected an acceleration whose value in m/s^2 is finite; check the record's units)")]
    Overflow {
        origin: String,
        line: usize,
        found: f64,
        units: Units,
    },
    /// `line` is `None` when the time step was given by the caller, not read from the file.
    #[error("{origin}{}: expected a time step DT > 0 (s), finite and at least {MIN_RECORD_DT:e} s, found {}", line_suffix(*.line), short_number(*.dt))]
    BadDt {
        origin: String,
        line: Option<usize>,
        dt: f64,
    },
    /// Times in a two-column record that are not uniformly spaced: the step from the time
    /// on line `prev_line` to the one on `line` differs from `expected_dt` (`reference`: the
    /// first step, or the mean step when no step differs from the first) by more than
    /// `tolerance` (1e-6 of the mean step, which every step must be within).
    #[error("{origin} line {line}: expected uniformly spaced times: the step from line {prev_line} to line {line} is {found_dt} s, {reference} is {expected_dt} s (tolerance {tolerance:e} s, 1e-6 of the mean step)")]
    NonUniform {
        origin: String,
        line: usize,
        prev_line: usize,
        expected_dt: f64,
        found_dt: f64,
        /// What `expected_dt` is, in words (`the first step (line 1 to line 2)`).
        reference: String,
        tolerance: f64,
    },
    /// A time in a two-column record that is not after the one before it.
    #[error("{origin} line {line}: expected increasing times: time {time} s at line {line} is not after {prev_time} s at line {prev_line}")]
    TimeNotIncreasing {
        origin: String,
        line: usize,
        time: f64,
        prev_line: usize,
        prev_time: f64,
    },
    #[error("{origin} line 1: expected a ground-motion record, found an empty file")]
    Empty { origin: String },
    #[error("{origin} line {line}: expected at least 2 acceleration values, found {found}")]
    TooFewPoints {
        origin: String,
        line: usize,
        found: usize,
    },
    /// Accelerations finite but so large that the ground velocity or displacement (the
    /// record's exact integrals from rest, [`GroundMotion::integrals_finite`]) is not: a
    /// record no solver can compute with (1e307 g gave a PGV of `inf` before this check).
    #[error("{origin}: accelerations up to {pga:.3e} m/s^2 take the ground velocity or displacement (or the slope between two samples) beyond the range of floating point (expected a ground motion whose velocity and displacement are finite; check the record's units and values)")]
    Unbounded { origin: String, pga: f64 },
}

/// Error of [`GroundMotion::checked_scaled`]: `factor` takes sample `sample` (1-based), of
/// `value` m/s², beyond the range of floating point, or (`integrals`) leaves every sample
/// finite but takes the record's ground velocity or displacement beyond it (`sample` then
/// names the largest sample).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleOverflow {
    pub factor: f64,
    pub sample: usize,
    pub value: f64,
    pub integrals: bool,
}

impl ScaleOverflow {
    /// The refusal, with the scaling named `by` (the factor, or the PGA it comes from) and the
    /// record named `record`: the message of [`Display`](std::fmt::Display) and of a scene's
    /// `scale` or `pga`.
    pub fn message(&self, by: &str, record: &str) -> String {
        let (sample, value) = (self.sample, self.value);
        if self.integrals {
            format!(
                "{by} scales {record} (its largest sample {sample}, {value:e} m/s^2) so far that \
                 its ground velocity or displacement is beyond the range of floating point \
                 (expected a factor that leaves them finite)"
            )
        } else {
            format!(
                "{by} scales sample {sample} of {record} ({value:e} m/s^2) beyond the range of \
                 floating point (expected a factor that leaves every acceleration finite)"
            )
        }
    }
}

impl std::fmt::Display for ScaleOverflow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message(&format!("{:e}", self.factor), "the record"))
    }
}

impl std::error::Error for ScaleOverflow {}

/// The end of a [`RecordError::Value`] message on a header-like first data line.
const HEADER_HINT: &str = "; a header line is not read: remove it or start it with `#` (a comment)";

/// [`RecordError::TwoColumnsAsOne`] after its file and line.
fn two_columns_as_one(step: f64) -> String {
    format!(
        "expected one-column values (the record is read as one-column), found 2 values on this \
         line and on every line of numbers, the first rising by {step} like times (s): a \
         two-column record (time, acceleration); read it as two-column, without a time step \
         (it takes its step from its time column)"
    )
}

/// The count of values every line of numbers of `text` holds, and the first such line
/// (1-based), as the two- and one-column readers split lines (`#` starts a comment; blank
/// lines skipped); `None` when lines hold different counts or there is no line of numbers.
pub fn values_per_line(text: &str) -> Option<(usize, usize)> {
    let mut found: Option<(usize, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("");
        let n = tokens(l, true).len();
        if n == 0 {
            continue;
        }
        match found {
            None => found = Some((n, i + 1)),
            Some((m, _)) if m != n => return None,
            Some(_) => {}
        }
    }
    found
}

/// [`RecordError::InferredOneColumn`] for `text` about to be read as one-column only because
/// a time step was given without a format, when every line of numbers holds the same count
/// of two or more values: then it is most likely a table with a time column, and read value
/// after value its times would become accelerations (a two-column file whose steps are not
/// uniform, or of two rows, passes the one-column reader's own check).
fn refuse_inferred_table(text: &str, origin: &str) -> Result<(), RecordError> {
    match values_per_line(text) {
        Some((values, line)) if values >= 2 => Err(RecordError::InferredOneColumn {
            origin: origin.to_string(),
            line,
            values,
        }),
        _ => Ok(()),
    }
}

/// An I/O error in words: "is a directory" rather than the OS's wording for it.
pub fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::IsADirectory => "it is a directory, not a file".into(),
        std::io::ErrorKind::NotFound => "no such file".into(),
        _ => e.to_string(),
    }
}

/// Units stated on line 3 of a PEER AT2 header (`... IN UNITS OF G`, `UNITS OF CM/S/S`,
/// `CM/SEC/SEC`, `CM/S^2`, `GAL`, `M/S/S`, `M/SEC/SEC`, `M/S^2`), if recognised.
pub fn at2_units(line: &str) -> Option<Units> {
    let up = line.to_ascii_uppercase();
    let at = up.find("UNITS OF")?;
    let word: String = up[at + "UNITS OF".len()..]
        .split_whitespace()
        .next()?
        .trim_end_matches(['.', ','])
        .to_string();
    match word.as_str() {
        "G" | "(G)" => Some(Units::G),
        "CM/S/S" | "CM/SEC/SEC" | "CM/S2" | "CM/S^2" | "CM/SEC2" | "CM/SEC^2" | "GAL" => {
            Some(Units::CentimetersPerSecond2)
        }
        "M/S/S" | "M/SEC/SEC" | "M/S2" | "M/S^2" | "M/SEC2" | "M/SEC^2" => {
            Some(Units::MetersPerSecond2)
        }
        _ => None,
    }
}

const AT2_UNITS: &str = "the acceleration units on line 3, e.g. \"ACCELERATION TIME SERIES IN UNITS OF G\" (G, CM/S/S, CM/SEC/SEC, CM/S^2, GAL, M/S/S, M/SEC/SEC or M/S^2)";

/// A one-column read of a file whose every data line holds two numbers, the first rising by
/// a constant step (times), would take the times for accelerations: refused.
fn refuse_two_columns(text: &str, origin: &str) -> Result<(), RecordError> {
    let mut firsts = Vec::new();
    let mut first_line = 0;
    let mut first_data_line = true;
    for (i, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("");
        let toks = tokens(l, true);
        if toks.is_empty() {
            continue;
        }
        // A header line (the first data line, starting with a word) does not hide the two
        // columns below it: they are what to report first.
        if std::mem::take(&mut first_data_line) && parse_number(toks[0].text).is_none() {
            continue;
        }
        if toks.len() != 2 {
            return Ok(());
        }
        let Some(t) = parse_number(toks[0].text) else {
            return Ok(());
        };
        if first_line == 0 {
            first_line = i + 1;
        }
        firsts.push(t);
    }
    if firsts.len() < 3 {
        return Ok(());
    }
    let step = firsts[1] - firsts[0];
    let uniform = step > 0.0
        && firsts
            .windows(2)
            .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-6 * step.abs());
    if uniform {
        return Err(RecordError::TwoColumnsAsOne {
            origin: origin.to_string(),
            line: first_line,
            step,
        });
    }
    Ok(())
}

fn line_suffix(line: Option<usize>) -> String {
    match line {
        Some(l) => format!(" line {l}"),
        None => " (given time step)".to_string(),
    }
}

/// Shorten untrusted text for messages.
fn clip(s: &str) -> String {
    const MAX: usize = 80;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let mut out: String = s.chars().take(MAX).collect();
        out.push('…');
        out
    }
}

fn stem(origin: &str) -> String {
    let file = Path::new(origin)
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or(origin);
    match file.rfind('.') {
        Some(i) if i > 0 => file[..i].to_string(),
        _ => file.to_string(),
    }
}

/// A numeric token with its position.
struct Token<'a> {
    text: &'a str,
    /// The line it is on, and its byte offset there.
    line: &'a str,
    start: usize,
}

impl Token<'_> {
    /// 1-based character column (for messages only: counted when asked).
    fn column(&self) -> usize {
        self.line.get(..self.start).map_or(0, |p| p.chars().count()) + 1
    }
}

/// Split a data line into numeric tokens: separated by whitespace (and commas if
/// `commas`), and split further before a sign that is neither at the token start nor right
/// after an exponent letter (`1.2340E-02-5.6780E-03` → two values). One pass over the line
/// (an ASCII line, as record files are, by bytes: the same characters without decoding).
fn tokens(line: &str, commas: bool) -> Vec<Token<'_>> {
    let mut out = Vec::new();
    if line.is_ascii() {
        scan(
            line,
            line.bytes().map(char::from).enumerate(),
            commas,
            &mut out,
        );
    } else {
        scan(line, line.char_indices(), commas, &mut out);
    }
    out
}

fn scan<'a>(
    line: &'a str,
    chars: impl Iterator<Item = (usize, char)>,
    commas: bool,
    out: &mut Vec<Token<'a>>,
) {
    let is_sep = |c: char| c.is_whitespace() || (commas && (c == ',' || c == ';'));
    let mut push = |s: usize, e: usize| {
        if let Some(text) = line.get(s..e).filter(|t| !t.is_empty()) {
            out.push(Token {
                text,
                line,
                start: s,
            });
        }
    };
    // The open piece's start, and the character before this one in the piece.
    let mut start: Option<usize> = None;
    let mut prev: Option<char> = None;
    for (i, c) in chars {
        if is_sep(c) {
            if let Some(s) = start.take() {
                push(s, i);
            }
            continue;
        }
        match start {
            None => start = Some(i),
            Some(s) => {
                if (c == '-' || c == '+') && !matches!(prev, Some('e' | 'E' | 'd' | 'D')) {
                    push(s, i);
                    start = Some(i);
                }
            }
        }
        prev = Some(c);
    }
    if let Some(s) = start {
        push(s, line.len());
    }
}

/// Parse one number (Fortran `D` exponents accepted).
fn parse_number(text: &str) -> Option<f64> {
    if text.contains(['d', 'D']) {
        text.replace(['d', 'D'], "E").parse().ok()
    } else {
        text.parse().ok()
    }
}

/// max |v| over `values` (0 for none), in four running maxima (not `f64::max`, whose NaN
/// rule keeps it from vectorising; a NaN is skipped as `f64::max` skips it): the same value
/// as the one-by-one fold, a maximum being exact. (The momentum method scans the record
/// for every analysis: 0.1 % of the paper scene's instructions, against 0.4 % as the fold.)
pub fn peak_abs(values: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 4];
    let chunks = values.chunks_exact(4);
    for &a in chunks.remainder() {
        lanes[0] = lanes[0].max(a.abs());
    }
    for c in chunks {
        for (m, a) in lanes.iter_mut().zip(c) {
            let a = a.abs();
            *m = if a > *m { a } else { *m };
        }
    }
    lanes.into_iter().fold(0.0, f64::max)
}

/// Why a record path cannot be read as a record file ([`record_path_problem`]).
#[derive(Debug)]
pub enum RecordPathProblem {
    Folder,
    /// A device, pipe or socket.
    NotRegular,
    Missing,
    /// Anything else the system says (a folder that cannot be searched, a loop of links).
    Unreadable(std::io::Error),
}

impl fmt::Display for RecordPathProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Folder => f.write_str("is a directory, not a file"),
            Self::NotRegular => f.write_str(
                "is not a regular file (a device, pipe or socket): expected a record file",
            ),
            Self::Missing => f.write_str("does not exist"),
            Self::Unreadable(e) => write!(f, "cannot be read: {e}"),
        }
    }
}

/// What is wrong with `path` as a record file, links followed; `None` for a regular file.
/// (`is_file()` and `exists()` said "does not exist" for a device or a loop of links.)
pub fn record_path_problem(path: &Path) -> Option<RecordPathProblem> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => Some(RecordPathProblem::Folder),
        Ok(m) if !m.is_file() => Some(RecordPathProblem::NotRegular),
        Ok(_) => None,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some(RecordPathProblem::Missing),
        Err(e) => Some(RecordPathProblem::Unreadable(e)),
    }
}

/// `v` (in `units`, read at `line`) in m/s², or [`RecordError::Overflow`] when that is not
/// finite (1e308 g is finite, 9.8e308 m/s² is not).
fn si(v: f64, units: Units, origin: &str, line: usize) -> Result<f64, RecordError> {
    let a = v * units.to_si();
    if a.is_finite() {
        Ok(a)
    } else {
        Err(RecordError::Overflow {
            origin: origin.to_string(),
            line,
            found: v,
            units,
        })
    }
}

/// Parse a value token: a `Value` error if not a number, `NonFinite` if NaN/inf.
fn value(tok: &Token<'_>, origin: &str, line: usize, expected: &str) -> Result<f64, RecordError> {
    match parse_number(tok.text) {
        Some(v) if v.is_finite() => Ok(v),
        Some(_) => Err(RecordError::NonFinite {
            origin: origin.to_string(),
            line,
            found: clip(tok.text),
        }),
        None => Err(not_a_number(tok, origin, line, expected, false)),
    }
}

/// The [`RecordError::Value`] of a token that is not a number; `header`: it starts the file's
/// first data line, where a word is taken for a header line.
fn not_a_number(
    tok: &Token<'_>,
    origin: &str,
    line: usize,
    expected: &str,
    header: bool,
) -> RecordError {
    RecordError::Value {
        origin: origin.to_string(),
        line,
        column: tok.column(),
        expected: expected.to_string(),
        found: clip(tok.text),
        header,
    }
}

/// A header line: the first data line of a two- or one-column record (`first`) starting
/// with a token that is not a number (a word such as `time_s`), refused with a message that
/// says how to keep it.
fn refuse_header(
    toks: &[Token<'_>],
    first: bool,
    origin: &str,
    line: usize,
    expected: &str,
) -> Result<(), RecordError> {
    match toks.first() {
        Some(t) if first && parse_number(t.text).is_none() => {
            Err(not_a_number(t, origin, line, expected, true))
        }
        _ => Ok(()),
    }
}

fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Take a leading number (`[0-9.eE+-]*`) off `s`.
fn take_number(s: &str) -> (&str, &str) {
    let end = s
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-')))
        .map_or(s.len(), |(i, _)| i);
    s.split_at(end)
}

/// Parse AT2 line 4 in either style. Returns (npts, dt) or `None`.
fn parse_at2_npts_dt(line: &str) -> Option<(usize, f64)> {
    let up = line.trim().to_ascii_uppercase();
    if let Some(rest) = up.strip_prefix("NPTS") {
        // NGA-West2 style: NPTS=  7991, DT=   .0050 SEC
        let rest = rest.trim_start().strip_prefix('=')?.trim_start();
        let (n, rest) = take_number(rest);
        let npts: usize = n.parse().ok()?;
        let rest = rest.trim_start();
        let rest = rest.strip_prefix(',').unwrap_or(rest).trim_start();
        let rest = rest
            .strip_prefix("DT")?
            .trim_start()
            .strip_prefix('=')?
            .trim_start();
        let (d, rest) = take_number(rest);
        let dt: f64 = parse_number(d)?;
        let tail = rest.trim().trim_matches(',').trim();
        if matches!(
            tail,
            "" | "SEC" | "SECS" | "S" | "SECONDS" | "SEC." | "SEC,"
        ) {
            Some((npts, dt))
        } else {
            None
        }
    } else {
        // Older style: 7991    0.0050    NPTS, DT
        let mut it = up
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty());
        let npts: usize = it.next()?.parse().ok()?;
        let dt: f64 = parse_number(it.next()?)?;
        if it.next()? != "NPTS" {
            return None;
        }
        Some((npts, dt))
    }
}

/// The bytes of the record file at `path` ([`RecordError::Io`] naming it when they cannot be
/// read).
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, RecordError> {
    std::fs::read(path).map_err(|error| RecordError::Io {
        path: path.display().to_string(),
        error,
    })
}

const AT2_LINE4: &str = "\"NPTS= <n>, DT= <s> SEC\" or \"<n> <dt> NPTS, DT\"";

impl GroundMotion {
    /// A record from values already in m/s². Checks `dt` ([`valid_dt`]), at least two samples,
    /// finite values and finite integrals ([`GroundMotion::integrals_finite`]).
    pub fn new(name: impl Into<String>, dt: f64, accel: Vec<f64>) -> Result<Self, RecordError> {
        let name = name.into();
        if !valid_dt(dt) {
            return Err(RecordError::BadDt {
                origin: name,
                line: None,
                dt,
            });
        }
        if accel.len() < 2 {
            return Err(RecordError::TooFewPoints {
                origin: name,
                line: 1,
                found: accel.len(),
            });
        }
        if let Some(i) = accel.iter().position(|a| !a.is_finite()) {
            let found = format!("{}", accel[i]);
            return Err(RecordError::NonFinite {
                origin: name,
                line: i + 1,
                found,
            });
        }
        let origin = name.clone();
        GroundMotion { name, dt, accel }.bounded(&origin)
    }

    /// Read a record file in `format` (given on purpose, not inferred). The record's name is
    /// the file stem.
    pub fn load(path: &Path, format: &RecordFormat) -> Result<Self, RecordError> {
        Self::load_choice(path, &RecordChoice::explicit(*format))
    }

    /// Read a record file as [`RecordFormat::infer`] chose: one read of the file, whose bytes
    /// are parsed ([`GroundMotion::parse`]; an inferred one-column read refuses a table on
    /// those same bytes). The record's name is the file stem.
    pub fn load_choice(path: &Path, choice: &RecordChoice) -> Result<Self, RecordError> {
        Self::load_bytes(path, read_bytes(path)?, choice)
    }

    /// [`GroundMotion::load_choice`] of `bytes` already read from `path` (which names the
    /// record and the file in messages), for a caller that looks at the bytes itself too.
    pub fn load_bytes(
        path: &Path,
        bytes: Vec<u8>,
        choice: &RecordChoice,
    ) -> Result<Self, RecordError> {
        let origin = path.file_name().map_or_else(
            || path.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        );
        // Every study case loads its scene, and with it its record: a file read before with
        // the same bytes, name and format is not parsed again (the key holds the bytes
        // themselves, so a changed file is read anew). An inferred one-column read checks its
        // text first: the memo may hold the same file read as one-column on purpose.
        let key = (bytes, origin, format!("{:?}", choice.format));
        let (bytes, origin, _) = &key;
        let text = String::from_utf8_lossy(bytes);
        if choice.refuses_tables() {
            refuse_inferred_table(&text, origin)?;
        }
        let memo = || RECORDS.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(g) = memo().records.get(&key) {
            return Ok(g.clone());
        }
        let g = Self::parse_as(&text, origin, &choice.format)?;
        let size = key.0.len() + 8 * g.accel.len();
        let mut m = memo();
        if m.bytes + size > RECORDS_BYTES {
            *m = RecordMemo::default();
        }
        if size <= RECORDS_BYTES {
            m.bytes += size;
            m.records.insert(key, g.clone());
        }
        Ok(g)
    }

    /// Parse a record's text with the reader of `choice.format`; an inferred one-column read
    /// ([`RecordChoice::inferred`]) first refuses a table of two or more values on every
    /// line of numbers ([`RecordError::InferredOneColumn`]). `origin` names the file in
    /// messages.
    pub fn parse(text: &str, origin: &str, choice: &RecordChoice) -> Result<Self, RecordError> {
        if choice.refuses_tables() {
            refuse_inferred_table(text, origin)?;
        }
        Self::parse_as(text, origin, &choice.format)
    }

    /// Parse a record's text with the reader of `format` (no inferred-table check).
    fn parse_as(text: &str, origin: &str, format: &RecordFormat) -> Result<Self, RecordError> {
        match *format {
            RecordFormat::At2 => Self::from_at2_str(text, origin),
            RecordFormat::TwoColumn { units } => Self::from_two_column_str(text, origin, units),
            RecordFormat::OneColumn { dt, units } => {
                Self::from_one_column_str(text, origin, dt, units)
            }
        }
    }

    /// Parse a PEER AT2 record, in the units its header states on line 3 ([`at2_units`]).
    /// `origin` names the file in messages.
    pub fn from_at2_str(text: &str, origin: &str) -> Result<Self, RecordError> {
        let text = strip_bom(text);
        if text.trim().is_empty() {
            return Err(RecordError::Empty {
                origin: origin.to_string(),
            });
        }
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
        let mut units = Units::G;
        for n in 1..=3 {
            let Some((_, l)) = lines.next() else {
                return Err(RecordError::Header {
                    origin: origin.to_string(),
                    line: n,
                    expected: "4 header lines (title, event/station, units, NPTS/DT)".into(),
                    found: "end of file".into(),
                });
            };
            if n == 3 {
                let up = l.to_ascii_uppercase();
                if up.contains("VELOCITY") || up.contains("DISPLACEMENT") {
                    return Err(RecordError::Header {
                        origin: origin.to_string(),
                        line: 3,
                        expected: "an acceleration time series".into(),
                        found: clip(l.trim()),
                    });
                }
                units = at2_units(l).ok_or_else(|| RecordError::Header {
                    origin: origin.to_string(),
                    line: 3,
                    expected: AT2_UNITS.into(),
                    found: clip(l.trim()),
                })?;
            }
        }
        let Some((_, l4)) = lines.next() else {
            return Err(RecordError::Header {
                origin: origin.to_string(),
                line: 4,
                expected: AT2_LINE4.into(),
                found: "end of file".into(),
            });
        };
        let Some((npts, dt)) = parse_at2_npts_dt(l4) else {
            return Err(RecordError::Header {
                origin: origin.to_string(),
                line: 4,
                expected: AT2_LINE4.into(),
                found: clip(l4.trim()),
            });
        };
        if !valid_dt(dt) {
            return Err(RecordError::BadDt {
                origin: origin.to_string(),
                line: Some(4),
                dt,
            });
        }
        let mut accel = Vec::with_capacity(npts.min(1 << 24));
        let mut last_line = 4;
        let expected = format!("a number (acceleration in {units})");
        for (ln, l) in lines {
            for tok in tokens(l, false) {
                let v = value(&tok, origin, ln, &expected)?;
                accel.push(si(v, units, origin, ln)?);
                last_line = ln;
            }
        }
        if accel.len() != npts {
            return Err(RecordError::Count {
                origin: origin.to_string(),
                line: 4,
                declared: npts,
                found: accel.len(),
            });
        }
        if accel.len() < 2 {
            return Err(RecordError::TooFewPoints {
                origin: origin.to_string(),
                line: last_line,
                found: accel.len(),
            });
        }
        GroundMotion {
            name: stem(origin),
            dt,
            accel,
        }
        .bounded(origin)
    }

    /// Parse a two-column `time accel` record. `dt` is derived from the times, which must be
    /// uniformly spaced (relative tolerance 1e-6 of the step); the first sample is put at
    /// `t = 0` whatever its time in the file.
    pub fn from_two_column_str(
        text: &str,
        origin: &str,
        units: Units,
    ) -> Result<Self, RecordError> {
        let text = strip_bom(text);
        let mut times: Vec<(f64, usize)> = Vec::new();
        let mut accel = Vec::new();
        let mut any = false;
        let expected_accel = format!("a number (acceleration in {units})");
        for (i, raw) in text.lines().enumerate() {
            let ln = i + 1;
            let l = raw.split('#').next().unwrap_or("");
            if l.trim().is_empty() {
                any |= !raw.trim().is_empty();
                continue;
            }
            let toks = tokens(l, true);
            // `times` is empty on the first data line (every data line before it adds one).
            refuse_header(&toks, times.is_empty(), origin, ln, "a number (time in s)")?;
            any = true;
            if toks.len() != 2 {
                let (column, found) = match toks.get(2) {
                    Some(t) => (t.column(), l.trim().to_string()),
                    None => (toks.first().map_or(1, |t| t.column()), l.trim().to_string()),
                };
                return Err(RecordError::Value {
                    origin: origin.to_string(),
                    line: ln,
                    column,
                    header: false,
                    expected: if toks.len() == 1 {
                        format!(
                            "2 values per line (time in s, acceleration in {units}); one value per line is a one-column record: give its format (one-column) and its dt"
                        )
                    } else {
                        format!("2 values per line (time in s, acceleration in {units})")
                    },
                    found: clip(&found),
                });
            }
            let t = value(&toks[0], origin, ln, "a number (time in s)")?;
            let a = value(&toks[1], origin, ln, &expected_accel)?;
            times.push((t, ln));
            accel.push(si(a, units, origin, ln)?);
        }
        if !any {
            return Err(RecordError::Empty {
                origin: origin.to_string(),
            });
        }
        let last_line = times.last().map_or(1, |&(_, l)| l);
        if accel.len() < 2 {
            return Err(RecordError::TooFewPoints {
                origin: origin.to_string(),
                line: last_line,
                found: accel.len(),
            });
        }
        // Times must rise (they are finite here): the first line whose time is not after the
        // one before is named.
        if let Some(w) = times.windows(2).find(|w| w[1].0 <= w[0].0) {
            return Err(RecordError::TimeNotIncreasing {
                origin: origin.to_string(),
                line: w[1].1,
                time: w[1].0,
                prev_line: w[0].1,
                prev_time: w[0].0,
            });
        }
        let (t0, _) = times[0];
        let (tn, _) = times[times.len() - 1];
        let dt = (tn - t0) / (times.len() - 1) as f64;
        if !valid_dt(dt) {
            // Rising finite times with a span that overflows (e.g. -1e308 … 1e308).
            let (t1, l1) = times[1];
            return Err(RecordError::BadDt {
                origin: origin.to_string(),
                line: Some(l1),
                dt: t1 - t0,
            });
        }
        // Accepted: every step within 1e-6 of the mean step `dt` (the record's dt). A file
        // that fails is described by the first step that differs from the file's first step
        // by more than that tolerance (a step the file shows); failing that (steps within
        // the tolerance of the first one, but not of the mean), by the first step off the mean.
        let tol = 1e-6 * dt;
        let off =
            |reference: f64| move |w: &&[(f64, usize)]| ((w[1].0 - w[0].0) - reference).abs() > tol;
        if let Some(w_mean) = times.windows(2).find(off(dt)) {
            let first = times[1].0 - times[0].0;
            let (w, reference, expected_dt) = match times.windows(2).find(off(first)) {
                Some(w) => (
                    w,
                    format!(
                        "the first step (line {} to line {})",
                        times[0].1, times[1].1
                    ),
                    first,
                ),
                None => (w_mean, "the mean step".to_string(), dt),
            };
            return Err(RecordError::NonUniform {
                origin: origin.to_string(),
                line: w[1].1,
                prev_line: w[0].1,
                expected_dt,
                found_dt: w[1].0 - w[0].0,
                reference,
                tolerance: tol,
            });
        }
        GroundMotion {
            name: stem(origin),
            dt,
            accel,
        }
        .bounded(origin)
    }

    /// Parse a record of values only (one or several per line; `#` comments and blank lines
    /// allowed) with the given time step.
    pub fn from_one_column_str(
        text: &str,
        origin: &str,
        dt: f64,
        units: Units,
    ) -> Result<Self, RecordError> {
        let text = strip_bom(text);
        if !valid_dt(dt) {
            return Err(RecordError::BadDt {
                origin: origin.to_string(),
                line: None,
                dt,
            });
        }
        refuse_two_columns(text, origin)?;
        let mut accel = Vec::new();
        let mut last_line = 1;
        let mut any = false;
        let expected = format!("a number (acceleration in {units})");
        for (i, raw) in text.lines().enumerate() {
            let ln = i + 1;
            let l = raw.split('#').next().unwrap_or("");
            any |= !raw.trim().is_empty();
            let toks = tokens(l, true);
            // `accel` is empty up to the first data line.
            refuse_header(&toks, accel.is_empty(), origin, ln, &expected)?;
            for tok in toks {
                accel.push(si(value(&tok, origin, ln, &expected)?, units, origin, ln)?);
                last_line = ln;
            }
        }
        if !any {
            return Err(RecordError::Empty {
                origin: origin.to_string(),
            });
        }
        if accel.len() < 2 {
            return Err(RecordError::TooFewPoints {
                origin: origin.to_string(),
                line: last_line,
                found: accel.len(),
            });
        }
        GroundMotion {
            name: stem(origin),
            dt,
            accel,
        }
        .bounded(origin)
    }

    /// Number of samples.
    pub fn npts(&self) -> usize {
        self.accel.len()
    }

    /// `(npts − 1)·dt`, s.
    pub fn duration(&self) -> f64 {
        self.accel.len().saturating_sub(1) as f64 * self.dt
    }

    /// Peak ground acceleration max |a|, m/s².
    pub fn pga(&self) -> f64 {
        peak_abs(&self.accel)
    }

    /// Peak ground velocity, m/s: the peak of |v(t)| over the whole record (between samples
    /// too) for the exact integral of the piecewise-linear acceleration, from rest, with no
    /// baseline correction.
    pub fn pgv(&self) -> f64 {
        let dt = self.dt;
        let mut v = 0.0f64;
        let mut peak = 0.0f64;
        for w in self.accel.windows(2) {
            let (a0, a1) = (w[0], w[1]);
            // Interior extremum where a(τ) = 0.
            if (a0 > 0.0 && a1 < 0.0) || (a0 < 0.0 && a1 > 0.0) {
                let tau = a0 / (a0 - a1) * dt;
                peak = peak.max((v + 0.5 * a0 * tau).abs());
            }
            v += 0.5 * dt * (a0 + a1);
            peak = peak.max(v.abs());
        }
        peak
    }

    /// Peak ground displacement, m: the peak of |d(t)| over the whole record (between
    /// samples too) for the exact double integral of the piecewise-linear acceleration, from
    /// rest, with no baseline correction.
    pub fn pgd(&self) -> f64 {
        let dt = self.dt;
        let (mut v, mut d) = (0.0f64, 0.0f64);
        let mut peak = 0.0f64;
        for w in self.accel.windows(2) {
            let (a0, a1) = (w[0], w[1]);
            let s = (a1 - a0) / dt; // jerk
                                    // v(τ) = v + a0 τ + s τ²/2; d(τ) = d + v τ + a0 τ²/2 + s τ³/6.
            let dat = |tau: f64| d + tau * (v + tau * (0.5 * a0 + tau * s / 6.0));
            for tau in quadratic_roots(0.5 * s, a0, v) {
                if tau > 0.0 && tau < dt {
                    peak = peak.max(dat(tau).abs());
                }
            }
            d += dt * v + dt * dt * (a0 / 3.0 + a1 / 6.0);
            v += 0.5 * dt * (a0 + a1);
            peak = peak.max(d.abs());
        }
        peak
    }

    /// The record multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        GroundMotion {
            name: self.name.clone(),
            dt: self.dt,
            accel: self.accel.iter().map(|a| a * factor).collect(),
        }
    }

    /// The record multiplied by `factor`, or [`ScaleOverflow`] naming the first sample the
    /// factor takes beyond the range of floating point (a factor near the largest `f64`), or,
    /// when every sample stays finite but the ground velocity or displacement does not
    /// ([`GroundMotion::integrals_finite`]), the largest sample.
    pub fn checked_scaled(&self, factor: f64) -> Result<Self, ScaleOverflow> {
        let scaled = self.scaled(factor);
        if let Some(i) = scaled.accel.iter().position(|a| !a.is_finite()) {
            return Err(ScaleOverflow {
                factor,
                sample: i + 1,
                value: self.accel[i],
                integrals: false,
            });
        }
        if !scaled.integrals_finite() {
            let i = (0..self.accel.len())
                .max_by(|&a, &b| self.accel[a].abs().total_cmp(&self.accel[b].abs()))
                .unwrap_or(0);
            return Err(ScaleOverflow {
                factor,
                sample: i + 1,
                value: self.accel[i],
                integrals: true,
            });
        }
        Ok(scaled)
    }

    /// Whether the ground velocity and displacement, the record's exact integrals from rest
    /// ([`GroundMotion::pgv`], [`GroundMotion::pgd`]), and the slopes between samples they are
    /// computed from, (a₁ − a₀)/Δt, are finite: accelerations finite but near the top of the
    /// floating-point range can take them beyond it (two samples of ±1.7e308 m/s² gave a PGV
    /// of 0, their difference overflowing), and no solver can compute with such a record.
    pub fn integrals_finite(&self) -> bool {
        let dt = self.dt;
        self.accel
            .windows(2)
            .all(|w| ((w[1] - w[0]) / dt).is_finite())
            && self.pgv().is_finite()
            && self.pgd().is_finite()
    }

    /// `self`, or [`RecordError::Unbounded`] when its integrals are not finite.
    fn bounded(self, origin: &str) -> Result<Self, RecordError> {
        if self.integrals_finite() {
            Ok(self)
        } else {
            Err(RecordError::Unbounded {
                origin: origin.to_string(),
                pga: self.pga(),
            })
        }
    }

    /// The record scaled so that its PGA is `pga_g`·G (to rounding). An all-zero record is
    /// returned unchanged (it cannot be scaled to a PGA).
    pub fn scaled_to_pga(&self, pga_g: f64) -> Self {
        let pga = self.pga();
        if pga > 0.0 {
            self.scaled(pga_g * crate::G / pga)
        } else {
            self.clone()
        }
    }

    /// Acceleration at time `t`, m/s², linear between samples; 0 for `t < 0`,
    /// `t > duration` and NaN.
    pub fn accel_at(&self, t: f64) -> f64 {
        let n = self.accel.len();
        if n == 0 || t.is_nan() || t < 0.0 || t > self.duration() {
            return 0.0;
        }
        if n == 1 {
            return self.accel[0];
        }
        let x = t / self.dt;
        let i = (x.floor() as usize).min(n - 2);
        let r = x - i as f64;
        self.accel[i] + r * (self.accel[i + 1] - self.accel[i])
    }

    /// Sample times `i·dt`, s.
    pub fn times(&self) -> impl Iterator<Item = f64> {
        let dt = self.dt;
        (0..self.accel.len()).map(move |i| i as f64 * dt)
    }
}

/// Real roots of `a x² + b x + c` (stable formulas; degenerate cases handled).
fn quadratic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a == 0.0 {
        return if b != 0.0 { vec![-c / b] } else { vec![] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return vec![];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q == 0.0 {
        return vec![0.0];
    }
    vec![q / a, c / q]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The two-pass tokenizer this one replaced (separators first, then sign splits, the
    /// column counted for every token): the reference of the property below.
    fn tokens_two_pass(line: &str, commas: bool) -> Vec<(&str, usize)> {
        let is_sep = |c: char| c.is_whitespace() || (commas && (c == ',' || c == ';'));
        let mut raw: Vec<(usize, usize)> = Vec::new();
        let mut start: Option<usize> = None;
        for (i, c) in line.char_indices() {
            if is_sep(c) {
                if let Some(s) = start.take() {
                    raw.push((s, i));
                }
            } else if start.is_none() {
                start = Some(i);
            }
        }
        if let Some(s) = start {
            raw.push((s, line.len()));
        }
        let mut cuts: Vec<(usize, usize)> = Vec::new();
        for (s, e) in raw {
            let mut piece_start = s;
            let mut prev: Option<char> = None;
            for (j, c) in line.get(s..e).unwrap_or("").char_indices() {
                if (c == '-' || c == '+') && j > 0 && !matches!(prev, Some('e' | 'E' | 'd' | 'D')) {
                    cuts.push((piece_start, s + j));
                    piece_start = s + j;
                }
                prev = Some(c);
            }
            cuts.push((piece_start, e));
        }
        cuts.into_iter()
            .filter(|(s, e)| e > s)
            .filter_map(|(s, e)| {
                let text = line.get(s..e)?;
                Some((text, line.get(..s).map_or(0, |p| p.chars().count()) + 1))
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]
        /// Tokens and columns as the two-pass tokenizer gives them, on lines of digits,
        /// signs, exponent letters, separators (ASCII, commas, a no-break and an ideographic
        /// space) and other letters.
        #[test]
        fn one_pass_tokens_are_the_two_pass_tokens(
            line in "[0-9.eEdD+\\- \t,;x\u{a0}\u{3000}é]{0,40}",
            commas in any::<bool>(),
        ) {
            let got: Vec<(&str, usize)> =
                tokens(&line, commas).iter().map(|t| (t.text, t.column())).collect();
            prop_assert_eq!(got, tokens_two_pass(&line, commas));
        }
    }

    #[test]
    fn split_stuck_negatives() {
        let t: Vec<_> = tokens("1.2340E-02-5.6780E-03 -1.0", false)
            .into_iter()
            .map(|t| (t.text, t.column()))
            .collect();
        assert_eq!(
            t,
            vec![("1.2340E-02", 1), ("-5.6780E-03", 11), ("-1.0", 23)]
        );
    }

    #[test]
    fn header_styles() {
        assert_eq!(
            parse_at2_npts_dt("NPTS=  7991, DT=   .0050 SEC"),
            Some((7991, 0.005))
        );
        assert_eq!(
            parse_at2_npts_dt("npts= 10 dt= 0.005 sec"),
            Some((10, 0.005))
        );
        assert_eq!(
            parse_at2_npts_dt("  7991    0.0050    NPTS, DT"),
            Some((7991, 0.005))
        );
        assert_eq!(parse_at2_npts_dt("NPTS= x, DT= 0.01 SEC"), None);
    }

    #[test]
    fn quadratic() {
        let mut r = quadratic_roots(1.0, -3.0, 2.0);
        r.sort_by(f64::total_cmp);
        assert_eq!(r, vec![1.0, 2.0]);
    }
}
