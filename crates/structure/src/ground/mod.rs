//! Ground motions: records, the exact piecewise-linear propagator, response spectra.

pub mod nigam_jennings;
pub mod record;
pub mod spectrum;

pub use nigam_jennings::Propagator;
pub use record::{
    is_at2_name, peak_abs, record_path_problem, FormatKind, FormatRefusal, GroundMotion,
    ParseUnitsError, RecordChoice, RecordError, RecordFormat, RecordPathProblem, ScaleOverflow,
    Units,
};
pub use spectrum::{default_periods, response_spectrum, SpectrumPoint};
