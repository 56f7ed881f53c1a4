//! # studies — sweeps, plots and the `pound` command line
//!
//! - [`io`]: atomic file writes, CSV and JSON output of runs and histories.
//! - [`report`]: human-readable tables for the CLI.
//!
//! The binary (`src/main.rs`) is the only place that uses `anyhow`.

pub mod io;
pub mod report;
