//! Fuzz target: the ground-motion record reader on arbitrary UTF-8 text, in all three
//! layouts (PEER AT2, two-column, one-column). Any input must give `Ok` or an error, never
//! a panic; a record that parses must have finite, well-defined peaks.
//!
//! The first byte picks the units and the time step of the one-column layout; the rest is
//! the file's text.

#![no_main]

use libfuzzer_sys::fuzz_target;
use structure::ground::record::MIN_RECORD_DT;
use structure::ground::{GroundMotion, Units};

fn exercise(g: &GroundMotion) {
    // What every reader guarantees (the property tests of tests/ground.rs assert the same).
    if let Some(v) = structure::testing::read_record_violation(g) {
        panic!("a record that reads is invalid: {v}");
    }
    let _ = g.accel_at(-1.0);
    let _ = g.accel_at(2.0 * g.duration() + 1.0);
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let units = match selector % 3 {
        0 => Units::G,
        1 => Units::MetersPerSecond2,
        _ => Units::CentimetersPerSecond2,
    };
    let dt = match selector / 3 % 4 {
        0 => 0.005,
        1 => 0.02,
        2 => 1.0e-9, // invalid: below MIN_RECORD_DT, must be refused
        _ => 0.0,    // invalid: must be refused
    };
    if let Ok(g) = GroundMotion::from_at2_str(text, "fuzz.at2") {
        exercise(&g);
    }
    if let Ok(g) = GroundMotion::from_two_column_str(text, "fuzz.txt", units) {
        exercise(&g);
    }
    match GroundMotion::from_one_column_str(text, "fuzz.dat", dt, units) {
        Ok(g) => {
            assert!(dt >= MIN_RECORD_DT, "dt = {dt} must be refused");
            exercise(&g);
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
});
