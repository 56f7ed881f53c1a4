//! # studies — sweeps, plots and the `pound` command line
//!
//! - [`export`]: `pound export opensees`, an OpenSeesPy script of a scene.
//! - [`io`]: atomic file writes, CSV and JSON output of runs and histories.
//! - [`report`]: human-readable tables for the CLI.
//!
//! The binary (`src/main.rs`) is the only place that uses `anyhow`.

pub mod export;
pub mod io;
pub mod plot;
pub mod report;
pub mod studies;
pub mod sweep;
pub mod table;
