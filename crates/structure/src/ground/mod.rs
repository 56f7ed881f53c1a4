//! Ground motions: records, the exact piecewise-linear propagator, response spectra.

pub mod nigam_jennings;
pub mod record;
pub mod spectrum;

pub use nigam_jennings::Propagator;
pub use record::{
    peak_abs, record_path_problem, GroundMotion, ParseUnitsError, RecordError, RecordFormat,
    RecordPathProblem, Units,
};
pub use spectrum::{default_periods, response_spectrum, SpectrumPoint};
