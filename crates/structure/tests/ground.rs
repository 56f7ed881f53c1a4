//! Integration tests for `structure::ground`: record parsing, scaling, peaks, the
//! Nigam–Jennings propagator and response spectra.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use structure::ground::nigam_jennings::{acceleration, Propagator};
use structure::ground::spectrum::{default_periods, response_spectrum};
use structure::ground::{
    FormatKind, FormatRefusal, GroundMotion, RecordChoice, RecordError, RecordFormat,
    ScaleOverflow, Units,
};
use structure::G;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn record(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/ground-motions")
        .join(name)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

const HEAD: &str =
    "PEER NGA STRONG MOTION DATABASE RECORD\nSYNTHETIC\nACCELERATION TIME SERIES IN UNITS OF G\n";

fn at2(line4: &str, body: &str) -> String {
    format!("{HEAD}{line4}\n{body}")
}

// ---------------------------------------------------------------------------------------
// AT2
// ---------------------------------------------------------------------------------------

#[test]
fn at2_new_style_header() {
    let text = at2(
        "NPTS=  6, DT=   .0050 SEC",
        "  1.0E-01 -2.0E-01  3.0E-01\n  4.0E-01  5.0E-01 -6.0E-01\n",
    );
    let gm = GroundMotion::from_at2_str(&text, "X.AT2").unwrap();
    assert_eq!(gm.npts(), 6);
    assert_eq!(gm.dt, 0.005);
    assert_eq!(gm.name, "X");
    let want = [0.1, -0.2, 0.3, 0.4, 0.5, -0.6];
    for (a, w) in gm.accel.iter().zip(want) {
        assert_eq!(*a, w * G);
    }
    assert_eq!(gm.pga(), 0.6 * G);
    assert!((gm.duration() - 0.025).abs() < 1e-15);
}

#[test]
fn at2_header_variants() {
    for line4 in [
        "npts= 3, dt= 0.005 sec",
        "NPTS= 3 DT= 0.005 SEC",
        "NPTS=3, DT=0.005 SEC",
        "NPTS=  3, DT=   .0050 SEC  ",
        "NPTS= 3, DT= 0.005",
        "3   0.0050   NPTS, DT",
        "  3 .005 npts dt",
    ] {
        let text = at2(line4, "1.0 2.0 3.0\n");
        let gm =
            GroundMotion::from_at2_str(&text, "v.at2").unwrap_or_else(|e| panic!("{line4}: {e}"));
        assert_eq!(gm.npts(), 3, "{line4}");
        assert_eq!(gm.dt, 0.005, "{line4}");
    }
}

#[test]
fn at2_old_style_crlf_rows_of_1_and_8_stuck_negatives() {
    let gm = GroundMotion::load(&data("old_style_crlf.AT2"), &RecordFormat::At2).unwrap();
    assert_eq!(gm.name, "old_style_crlf");
    assert_eq!(gm.dt, 0.01);
    let want = [
        0.01, -0.02, 0.03, 0.04, -0.05, 0.06, 0.07, 0.08, -0.009, 0.1, 0.2, -0.3,
    ];
    assert_eq!(gm.npts(), want.len());
    for (i, (a, w)) in gm.accel.iter().zip(want).enumerate() {
        assert_eq!(*a, w * G, "sample {i}");
    }
}

#[test]
fn at2_stuck_negatives_inline_and_fortran_exponents() {
    let text = at2(
        "NPTS= 4, DT= 0.01 SEC",
        "1.2340E-02-5.6780E-03\n-1.0E+00-2.0D-01\n",
    );
    let gm = GroundMotion::from_at2_str(&text, "s.AT2").unwrap();
    let want = [1.2340e-02, -5.6780e-03, -1.0, -0.2];
    for (a, w) in gm.accel.iter().zip(want) {
        assert_eq!(*a, w * G);
    }
}

#[test]
fn cap000_parses() {
    let gm = GroundMotion::load(&record("RSN752_LOMAP_CAP000.AT2"), &RecordFormat::At2).unwrap();
    assert_eq!(gm.npts(), 7991);
    assert_eq!(gm.dt, 0.005);
    assert_eq!(gm.name, "RSN752_LOMAP_CAP000");
    assert_eq!(format!("{:.3}", gm.pga() / G), "0.529");
    assert!((gm.duration() - 39.95).abs() < 1e-9);
    // The first value from the file.
    assert_eq!(gm.accel[0], -2.0347400e-03 * G);
}

#[test]
fn all_shipped_records_parse() {
    for (f, n, pga) in [
        ("RSN752_LOMAP_CAP000.AT2", 7991, "0.529"),
        ("RSN752_LOMAP_CAP090.AT2", 7991, "0.443"),
        ("RSN767_LOMAP_G03000.AT2", 7989, "0.555"),
        ("RSN767_LOMAP_G03090.AT2", 7989, "0.367"),
    ] {
        let gm = GroundMotion::load(&record(f), &RecordFormat::At2).unwrap();
        assert_eq!(gm.npts(), n, "{f}");
        assert_eq!(format!("{:.3}", gm.pga() / G), pga, "{f}");
        assert!(gm.pgv() > 0.0 && gm.pgv().is_finite());
        assert!(gm.pgd() > 0.0 && gm.pgd().is_finite());
    }
}

// ---------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------

fn at2_err(text: &str) -> RecordError {
    match GroundMotion::from_at2_str(text, "RSN752.AT2") {
        Ok(gm) => panic!("expected an error, got {} points", gm.npts()),
        Err(e) => e,
    }
}

fn msg_has(e: &RecordError, parts: &[&str]) {
    let m = e.to_string();
    for p in parts {
        assert!(m.contains(p), "message {m:?} lacks {p:?}");
    }
}

#[test]
fn error_bad_line4() {
    let e = at2_err(&at2("NPTS= seven, DT= 0.005 SEC", "1 2\n"));
    assert!(matches!(e, RecordError::Header { line: 4, .. }), "{e:?}");
    msg_has(
        &e,
        &[
            "RSN752.AT2 line 4",
            "expected \"NPTS= <n>, DT= <s> SEC\" or \"<n> <dt> NPTS, DT\"",
            "NPTS= seven",
        ],
    );
    let e = at2_err(&at2("7991 0.005 POINTS", "1 2\n"));
    assert!(matches!(e, RecordError::Header { line: 4, .. }), "{e:?}");
}

#[test]
fn error_missing_header_lines() {
    let e = at2_err("TITLE\nEVENT\n");
    assert!(matches!(e, RecordError::Header { line: 3, .. }), "{e:?}");
    msg_has(&e, &["RSN752.AT2 line 3", "end of file"]);
    let e = at2_err(HEAD);
    assert!(matches!(e, RecordError::Header { line: 4, .. }), "{e:?}");
    msg_has(&e, &["RSN752.AT2 line 4", "expected"]);
}

#[test]
fn error_velocity_file_as_at2() {
    let e = at2_err("T\nE\nVELOCITY TIME SERIES IN UNITS OF CM/S\nNPTS= 2, DT= 0.01 SEC\n1 2\n");
    assert!(matches!(e, RecordError::Header { line: 3, .. }), "{e:?}");
}

#[test]
fn error_count_more_and_fewer() {
    let e = at2_err(&at2("NPTS= 4, DT= 0.01 SEC", "1 2 3\n"));
    assert!(
        matches!(
            e,
            RecordError::Count {
                declared: 4,
                found: 3,
                line: 4,
                ..
            }
        ),
        "{e:?}"
    );
    msg_has(&e, &["RSN752.AT2 line 4", "NPTS = 4", "3"]);
    let e = at2_err(&at2("NPTS= 2, DT= 0.01 SEC", "1 2 3\n4\n"));
    assert!(
        matches!(
            e,
            RecordError::Count {
                declared: 2,
                found: 4,
                ..
            }
        ),
        "{e:?}"
    );
    msg_has(&e, &["RSN752.AT2 line 4", "expected exactly 2"]);
}

#[test]
fn error_non_numeric_value() {
    let e = at2_err(&at2("NPTS= 4, DT= 0.01 SEC", "1.0 2.0\n3.0 x4.0\n"));
    match &e {
        RecordError::Value {
            line,
            column,
            found,
            ..
        } => {
            assert_eq!(*line, 6);
            assert_eq!(*column, 5);
            assert_eq!(found, "x4.0");
        }
        _ => panic!("{e:?}"),
    }
    msg_has(
        &e,
        &["RSN752.AT2 line 6", "column 5", "expected a number", "x4.0"],
    );
}

#[test]
fn error_non_finite() {
    for bad in ["NaN", "inf", "-Infinity", "1e400"] {
        let e = at2_err(&at2("NPTS= 3, DT= 0.01 SEC", &format!("1.0\n2.0 {bad}\n")));
        assert!(
            matches!(e, RecordError::NonFinite { line: 6, .. }),
            "{bad}: {e:?}"
        );
        msg_has(&e, &["RSN752.AT2 line 6", "expected a finite number"]);
    }
}

#[test]
fn error_bad_dt() {
    for dt in ["0.0", "-0.01", ".0000"] {
        let e = at2_err(&at2(&format!("NPTS= 2, DT= {dt} SEC"), "1 2\n"));
        assert!(
            matches!(e, RecordError::BadDt { line: Some(4), .. }),
            "{dt}: {e:?}"
        );
        msg_has(&e, &["RSN752.AT2 line 4", "expected a time step DT > 0"]);
    }
    let e = GroundMotion::from_one_column_str("1 2 3", "o.txt", 0.0, Units::G).unwrap_err();
    assert!(matches!(e, RecordError::BadDt { line: None, .. }), "{e:?}");
}

#[test]
fn error_empty() {
    for text in ["", "   \n\r\n  ", "\u{feff}"] {
        let e = at2_err(text);
        assert!(matches!(e, RecordError::Empty { .. }), "{e:?}");
        msg_has(&e, &["RSN752.AT2 line 1", "empty"]);
    }
    let e = GroundMotion::from_two_column_str("\n\n", "t.csv", Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Empty { .. }), "{e:?}");
    let e = GroundMotion::from_one_column_str("", "o.txt", 0.01, Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Empty { .. }), "{e:?}");
}

#[test]
fn error_too_few_points() {
    let e = at2_err(&at2("NPTS= 1, DT= 0.01 SEC", "1.0\n"));
    assert!(
        matches!(e, RecordError::TooFewPoints { found: 1, .. }),
        "{e:?}"
    );
    msg_has(&e, &["RSN752.AT2 line 5", "at least 2"]);
    let e = at2_err(&at2("NPTS= 0, DT= 0.01 SEC", ""));
    assert!(
        matches!(e, RecordError::TooFewPoints { found: 0, .. }),
        "{e:?}"
    );
    let e = GroundMotion::from_two_column_str("0 1\n", "t.csv", Units::G).unwrap_err();
    assert!(
        matches!(
            e,
            RecordError::TooFewPoints {
                found: 1,
                line: 1,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn error_io_names_path() {
    let p = data("does_not_exist.AT2");
    let e = GroundMotion::load(&p, &RecordFormat::At2).unwrap_err();
    assert!(matches!(e, RecordError::Io { .. }), "{e:?}");
    msg_has(&e, &["does_not_exist.AT2"]);
}

#[test]
fn error_load_names_file() {
    // Errors from load() use the file name as origin.
    let p = data("two_column.txt");
    let e = GroundMotion::load(&p, &RecordFormat::At2).unwrap_err();
    msg_has(&e, &["two_column.txt line "]);
}

/// Loaded records are remembered per process by (bytes, file name, format): the same file
/// loads the same record; a file rewritten with other values, read with another format, or
/// a copy under another name (the record's name is the file's stem) is parsed anew; a file
/// refused, then fixed, loads.
#[test]
fn remembered_records_follow_the_file_and_the_format() {
    let dir = std::env::temp_dir().join(format!("pound-record-memo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("rec.txt");
    let one = |dt: f64| RecordFormat::OneColumn {
        dt,
        units: Units::MetersPerSecond2,
    };
    std::fs::write(&f, "0.1 0.2 0.3\n").unwrap();
    let a = GroundMotion::load(&f, &one(0.01)).unwrap();
    assert_eq!(a.accel, vec![0.1, 0.2, 0.3]);
    assert_eq!(GroundMotion::load(&f, &one(0.01)).unwrap(), a);
    // Another format of the same bytes.
    assert_eq!(GroundMotion::load(&f, &one(0.02)).unwrap().dt, 0.02);
    // The same bytes under another name.
    let copy = dir.join("copy.txt");
    std::fs::write(&copy, "0.1 0.2 0.3\n").unwrap();
    let c = GroundMotion::load(&copy, &one(0.01)).unwrap();
    assert_eq!((c.name.as_str(), &c.accel), ("copy", &a.accel));
    // The file rewritten.
    std::fs::write(&f, "0.1 0.2 0.4\n").unwrap();
    assert_eq!(
        GroundMotion::load(&f, &one(0.01)).unwrap().accel,
        vec![0.1, 0.2, 0.4]
    );
    // Refused, then fixed.
    std::fs::write(&f, "0.1 x 0.4\n").unwrap();
    assert!(GroundMotion::load(&f, &one(0.01)).is_err());
    std::fs::write(&f, "0.1 0.5 0.4\n").unwrap();
    assert_eq!(
        GroundMotion::load(&f, &one(0.01)).unwrap().accel,
        vec![0.1, 0.5, 0.4]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// Two-column and one-column
// ---------------------------------------------------------------------------------------

#[test]
fn two_column_fixture() {
    let gm = GroundMotion::load(
        &data("two_column.txt"),
        &RecordFormat::TwoColumn {
            units: Units::CentimetersPerSecond2,
        },
    )
    .unwrap();
    assert_eq!(gm.npts(), 5);
    assert!(rel(gm.dt, 0.02) < 1e-12, "{}", gm.dt);
    let want = [0.0, 0.10, -0.205, 0.30, -0.40];
    for (a, w) in gm.accel.iter().zip(want) {
        assert!((a - w).abs() < 1e-15, "{a} vs {w}");
    }
}

#[test]
fn two_column_errors() {
    let e = GroundMotion::from_two_column_str("0 1\n0.01 2\n0.03 3\n0.04 4\n", "t.csv", Units::G)
        .unwrap_err();
    assert!(matches!(e, RecordError::NonUniform { .. }), "{e:?}");
    msg_has(&e, &["t.csv line ", "uniformly spaced"]);
    let e =
        GroundMotion::from_two_column_str("# c\n0 1\n0.01 2 3\n", "t.csv", Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Value { line: 3, .. }), "{e:?}");
    msg_has(&e, &["t.csv line 3", "2 values per line"]);
    let e = GroundMotion::from_two_column_str("0 1\n0.01\n", "t.csv", Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Value { line: 2, .. }), "{e:?}");
    let e = GroundMotion::from_two_column_str("0 1\n0 2\n", "t.csv", Units::G).unwrap_err();
    assert!(
        matches!(e, RecordError::TimeNotIncreasing { line: 2, .. }),
        "{e:?}"
    );
    let e = GroundMotion::from_two_column_str("1 1\n0 2\n", "t.csv", Units::G).unwrap_err();
    assert!(
        matches!(e, RecordError::TimeNotIncreasing { line: 2, .. }),
        "{e:?}"
    );
    let e = GroundMotion::from_two_column_str("0 1\n0.01 abc\n", "t.csv", Units::G).unwrap_err();
    assert!(
        matches!(
            e,
            RecordError::Value {
                line: 2,
                column: 6,
                ..
            }
        ),
        "{e:?}"
    );
    let e = GroundMotion::from_two_column_str("0 1\n0.01 nan\n", "t.csv", Units::G).unwrap_err();
    assert!(matches!(e, RecordError::NonFinite { line: 2, .. }), "{e:?}");
}

#[test]
fn two_column_tolerates_rounded_times() {
    // dt = 0.01 with 1e-9 jitter (relative 1e-7 of dt): accepted.
    let text: String = (0..100)
        .map(|i| {
            format!(
                "{:.12} {}\n",
                i as f64 * 0.01 + if i % 2 == 1 { 1e-9 } else { 0.0 },
                i
            )
        })
        .collect();
    let gm = GroundMotion::from_two_column_str(&text, "j.txt", Units::MetersPerSecond2).unwrap();
    assert_eq!(gm.npts(), 100);
    assert!(rel(gm.dt, 0.01) < 1e-6);
}

#[test]
fn one_column_fixture() {
    let gm = GroundMotion::load(
        &data("one_column.txt"),
        &RecordFormat::OneColumn {
            dt: 0.02,
            units: Units::G,
        },
    )
    .unwrap();
    assert_eq!(gm.npts(), 6);
    assert_eq!(gm.dt, 0.02);
    assert_eq!(gm.accel[5], -0.5 * G);
    let e = GroundMotion::from_one_column_str("1\n2\nfoo\n", "o.txt", 0.01, Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Value { line: 3, .. }), "{e:?}");
    msg_has(&e, &["o.txt line 3"]);
}

#[test]
fn units_parse_and_deserialize() {
    for (s, u) in [
        ("g", Units::G),
        ("m/s2", Units::MetersPerSecond2),
        ("m/s^2", Units::MetersPerSecond2),
        ("cm/s2", Units::CentimetersPerSecond2),
        ("cm/s^2", Units::CentimetersPerSecond2),
        ("gal", Units::CentimetersPerSecond2),
    ] {
        assert_eq!(s.parse::<Units>().unwrap(), u, "{s}");
    }
    assert!("ft/s^2".parse::<Units>().is_err());

    #[derive(serde::Deserialize)]
    struct W {
        u: Units,
        f: RecordFormat,
    }
    let w: W = toml::from_str(
        "u = \"m/s^2\"\nf = { format = \"one-column\", dt = 0.01, units = \"cm/s^2\" }\n",
    )
    .unwrap();
    assert_eq!(w.u, Units::MetersPerSecond2);
    assert_eq!(
        w.f,
        RecordFormat::OneColumn {
            dt: 0.01,
            units: Units::CentimetersPerSecond2
        }
    );
    let w: W = toml::from_str("u = \"g\"\nf = { format = \"at2\" }\n").unwrap();
    assert_eq!(w.f, RecordFormat::At2);
}

// ---------------------------------------------------------------------------------------
// Scaling, interpolation, peaks
// ---------------------------------------------------------------------------------------

#[test]
fn scaled_to_pga_is_exact() {
    for f in [
        "RSN752_LOMAP_CAP000.AT2",
        "RSN752_LOMAP_CAP090.AT2",
        "RSN767_LOMAP_G03000.AT2",
        "RSN767_LOMAP_G03090.AT2",
    ] {
        let gm = GroundMotion::load(&record(f), &RecordFormat::At2).unwrap();
        for target in [0.1, 0.3, 0.35, 0.4, 0.5, 0.529, 1.0, 1.7] {
            let s = gm.scaled_to_pga(target);
            let want = target * G;
            assert!(
                rel(s.pga(), want) < 4.0 * f64::EPSILON,
                "{f} {target}: {} vs {}",
                s.pga(),
                want
            );
            assert_eq!(s.dt, gm.dt);
            assert_eq!(s.npts(), gm.npts());
        }
    }
    let s = GroundMotion::new("z", 0.01, vec![1.0, -2.0])
        .unwrap()
        .scaled(3.0);
    assert_eq!(s.accel, vec![3.0, -6.0]);
}

#[test]
fn accel_at_and_times() {
    let gm = GroundMotion::new("t", 0.5, vec![0.0, 2.0, -2.0]).unwrap();
    assert_eq!(gm.accel_at(-1e-12), 0.0);
    assert_eq!(gm.accel_at(0.0), 0.0);
    assert_eq!(gm.accel_at(0.25), 1.0);
    assert_eq!(gm.accel_at(0.5), 2.0);
    assert_eq!(gm.accel_at(0.75), 0.0);
    assert_eq!(gm.accel_at(1.0), -2.0);
    assert_eq!(gm.accel_at(1.0 + 1e-12), 0.0);
    assert_eq!(gm.accel_at(f64::NAN), 0.0);
    assert_eq!(gm.times().collect::<Vec<_>>(), vec![0.0, 0.5, 1.0]);
    assert!(GroundMotion::new("t", 0.5, vec![1.0]).is_err());
    assert!(GroundMotion::new("t", -0.5, vec![1.0, 2.0]).is_err());
    assert!(GroundMotion::new("t", 0.5, vec![1.0, f64::NAN]).is_err());
}

#[test]
fn pgv_pgd_constant_acceleration() {
    // a = 2 for 1 s: v = 2, d = 1 exactly.
    let gm = GroundMotion::new("c", 0.1, vec![2.0; 11]).unwrap();
    assert!(rel(gm.pgv(), 2.0) < 1e-14);
    assert!(rel(gm.pgd(), 1.0) < 1e-14);
}

#[test]
fn pgv_pgd_catch_peaks_between_samples() {
    // One coarse interval from +1 to −1 (dt = 1): v(τ) = τ − τ²/2 peaks at τ = 1 with
    // v = 0.5; on the next interval (−1 → −1) v goes 0.5 → −0.5, so d peaks inside it.
    let gm = GroundMotion::new("p", 1.0, vec![1.0, -1.0, -1.0]).unwrap();
    // Dense reference of the exact piecewise-linear integral.
    let n = 200_000;
    let h = gm.duration() / n as f64;
    let (mut v, mut d, mut pv, mut pd) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for i in 0..n {
        let (a0, a1) = (gm.accel_at(i as f64 * h), gm.accel_at((i + 1) as f64 * h));
        d += h * v + h * h * (a0 / 3.0 + a1 / 6.0);
        v += 0.5 * h * (a0 + a1);
        pv = pv.max(v.abs());
        pd = pd.max(d.abs());
    }
    // The same exact integration of the piecewise-linear record: round-off (measured 1.9e-12).
    assert!(rel(gm.pgv(), pv) < 1e-11, "{} vs {pv}", gm.pgv());
    assert!(rel(gm.pgd(), pd) < 1e-11, "{} vs {pd}", gm.pgd());
    // A peak strictly between samples: a = 1 → −1 over one second gives v(τ) = τ − τ²,
    // zero at both samples but 1/4 at τ = 1/2.
    let g2 = GroundMotion::new("q", 1.0, vec![1.0, -1.0]).unwrap();
    assert!((g2.pgv() - 0.25).abs() < 4.0 * f64::EPSILON, "{}", g2.pgv());
}

// ---------------------------------------------------------------------------------------
// Nigam–Jennings propagator
// ---------------------------------------------------------------------------------------

/// Classical RK4 over [0, h] with `n` substeps, f linear from f0 to f1.
#[allow(clippy::too_many_arguments)]
fn rk4(omega: f64, zeta: f64, h: f64, n: usize, x0: f64, v0: f64, f0: f64, f1: f64) -> (f64, f64) {
    let f = |t: f64| f0 + (f1 - f0) * t / h;
    let s = h / n as f64;
    let (mut x, mut v) = (x0, v0);
    for i in 0..n {
        let t = i as f64 * s;
        let k1x = v;
        let k1v = acceleration(omega, zeta, x, v, f(t));
        let k2x = v + 0.5 * s * k1v;
        let k2v = acceleration(omega, zeta, x + 0.5 * s * k1x, k2x, f(t + 0.5 * s));
        let k3x = v + 0.5 * s * k2v;
        let k3v = acceleration(omega, zeta, x + 0.5 * s * k2x, k3x, f(t + 0.5 * s));
        let k4x = v + s * k3v;
        let k4v = acceleration(omega, zeta, x + s * k3x, k4x, f(t + s));
        x += s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    (x, v)
}

#[test]
fn propagator_matches_rk4_entrywise() {
    let omega = 3.0;
    for zeta in [0.0, 0.05, 0.9] {
        for h in [1e-8, 1e-4, 1e-1, 0.2, 1.0 / 6.0, 1.0] {
            let p = Propagator::new(omega, zeta, h);
            let n = ((omega * h / 1e-3).ceil() as usize).max(4);
            let cols = [
                (
                    rk4(omega, zeta, h, n, 1.0, 0.0, 0.0, 0.0),
                    p.a[0][0],
                    p.a[1][0],
                ),
                (
                    rk4(omega, zeta, h, n, 0.0, 1.0, 0.0, 0.0),
                    p.a[0][1],
                    p.a[1][1],
                ),
                (
                    rk4(omega, zeta, h, n, 0.0, 0.0, 1.0, 0.0),
                    p.b[0][0],
                    p.b[1][0],
                ),
                (
                    rk4(omega, zeta, h, n, 0.0, 0.0, 0.0, 1.0),
                    p.b[0][1],
                    p.b[1][1],
                ),
            ];
            for (j, ((rx, rv), px, pv)) in cols.into_iter().enumerate() {
                assert!(
                    rel(px, rx) < 1e-10,
                    "zeta {zeta} h {h} col {j}: x {px:e} vs {rx:e} ({:e})",
                    rel(px, rx)
                );
                assert!(
                    rel(pv, rv) < 1e-10,
                    "zeta {zeta} h {h} col {j}: v {pv:e} vs {rv:e} ({:e})",
                    rel(pv, rv)
                );
            }
        }
    }
}

#[test]
fn propagator_constant_load_analytic() {
    // x'' + 2ζωx' + ω²x = F from rest: x = F/ω² (1 − e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t)).
    let (omega, f) = (2.0 * std::f64::consts::PI / 0.7, 3.5);
    for zeta in [0.0f64, 0.05, 0.9] {
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        for h in [1e-6, 1e-3, 0.05, 0.3] {
            let p = Propagator::new(omega, zeta, h);
            let (mut x, mut v) = (0.0, 0.0);
            let steps = 200;
            for _ in 0..steps {
                (x, v) = p.step(x, v, f, f);
            }
            let t = steps as f64 * h;
            let e = (-zeta * omega * t).exp();
            let (s, c) = (wd * t).sin_cos();
            let xe = f / (omega * omega) * (1.0 - e * (c + zeta * omega / wd * s));
            let ve = f / (omega * omega) * e * (omega * omega / wd) * s;
            let scale_x = f / (omega * omega);
            let scale_v = f / omega;
            // Small h: x ≈ F t²/2 dominates the scale. The closed-form reference itself
            // carries round-off of order ε·F/ω² from 1 − e(cos + …), hence the second term.
            let sx = scale_x.min(f * t * t) + 16.0 * f64::EPSILON * scale_x / 1e-11;
            let sv = scale_v.min(f * t);
            assert!(
                (x - xe).abs() < 1e-11 * sx,
                "zeta {zeta} h {h}: x {x:e} vs {xe:e}"
            );
            assert!(
                (v - ve).abs() < 1e-11 * sv,
                "zeta {zeta} h {h}: v {v:e} vs {ve:e}"
            );
        }
    }
}

#[test]
fn propagator_small_h_limits() {
    let p = Propagator::new(5.0, 0.05, 0.0);
    assert_eq!(p.a, [[1.0, 0.0], [0.0, 1.0]]);
    assert_eq!(p.b, [[0.0, 0.0], [0.0, 0.0]]);
    for (omega, zeta) in [(5.0, 0.0), (5.0, 0.05), (200.0, 0.9)] {
        for h in [1e-12, 1e-9, 1e-7] {
            let p = Propagator::new(omega, zeta, h);
            let wh = omega * h;
            // Leading terms of the exact series with the first correction: the neglected
            // terms are O((ωh)²) relative, so that (plus round-off) is the tolerance.
            let tol = 8.0 * f64::EPSILON + 2.0 * wh * wh;
            assert!(rel(p.a[0][0], 1.0 - wh * wh / 2.0) < tol);
            assert!(rel(p.a[0][1], h * (1.0 - zeta * wh)) < tol);
            assert!(rel(p.a[1][0], -omega * wh * (1.0 - zeta * wh)) < tol);
            assert!(rel(p.a[1][1], 1.0 - 2.0 * zeta * wh) < tol);
            // Load terms: leading order (∫(h−τ)(1−τ/h)dτ = h²/3, ∫(h−τ)τ/h dτ = h²/6,
            // ∫(1−τ/h)dτ = ∫τ/h dτ = h/2); damping corrects them at relative order ζωh.
            let tol_b = 8.0 * f64::EPSILON + 2.0 * zeta * wh + wh * wh;
            assert!(rel(p.b[0][0], h * h / 3.0) < tol_b);
            assert!(rel(p.b[0][1], h * h / 6.0) < tol_b);
            assert!(rel(p.b[1][0], h / 2.0) < tol_b);
            assert!(rel(p.b[1][1], h / 2.0) < tol_b);
        }
    }
}

#[test]
fn propagator_continuous_across_series_switch() {
    // The propagator switches from the Taylor series to the closed form at ωh = 0.5: steps
    // 4ε apart on either side must agree to round-off. Each entry is measured in its natural
    // unit (a, b scaled by ω^p to the dimensionless propagator of ωh: a₀₁ω, a₁₀/ω, b₀ⱼω²,
    // b₁ⱼω), where the closed form's terms are of order one and cancel to the entry (b₀₀ω² ≈
    // (ωh)²/3 = 0.08): the two branches differ by at most 3.7 ε there (measured over these ω
    // and ζ; 62 ε relative to b₀₀ itself at ω = 10, ζ = 0.9), the step's own change of 4ε·h
    // included; 16 ε is asserted. (A 1e-9 change of h hid any jump below ~1e-8.)
    for omega in [10.0, 3.7, 250.0] {
        let h0 = 0.5 / omega;
        let (h_lo, h_hi) = (
            h0 * (1.0 - 2.0 * f64::EPSILON),
            h0 * (1.0 + 2.0 * f64::EPSILON),
        );
        assert!(omega * h_lo < 0.5 && omega * h_hi >= 0.5, "ω = {omega}");
        let unit_a = [[1.0, omega], [1.0 / omega, 1.0]];
        let unit_b = [[omega * omega, omega * omega], [omega, omega]];
        for zeta in [0.0, 0.05, 0.9] {
            let lo = Propagator::new(omega, zeta, h_lo);
            let hi = Propagator::new(omega, zeta, h_hi);
            for i in 0..2 {
                for j in 0..2 {
                    let da = (lo.a[i][j] - hi.a[i][j]).abs() * unit_a[i][j];
                    let db = (lo.b[i][j] - hi.b[i][j]).abs() * unit_b[i][j];
                    assert!(
                        da <= 16.0 * f64::EPSILON,
                        "ω {omega} ζ {zeta} a[{i}][{j}]: {} vs {} ({:.2} ε)",
                        lo.a[i][j],
                        hi.a[i][j],
                        da / f64::EPSILON
                    );
                    assert!(
                        db <= 16.0 * f64::EPSILON,
                        "ω {omega} ζ {zeta} b[{i}][{j}]: {} vs {} ({:.2} ε)",
                        lo.b[i][j],
                        hi.b[i][j],
                        db / f64::EPSILON
                    );
                }
            }
        }
    }
}

#[test]
fn undamped_free_vibration_conserves_energy_and_phase() {
    let omega = 2.0 * std::f64::consts::PI / 1.3;
    for h in [1e-3, 0.005, 0.21] {
        let p = Propagator::new(omega, 0.0, h);
        let (x0, v0) = (0.02, -0.15);
        let energy = |x: f64, v: f64| 0.5 * v * v + 0.5 * omega * omega * x * x;
        let e0 = energy(x0, v0);
        let (mut x, mut v) = (x0, v0);
        let steps = 100_000;
        for _ in 0..steps {
            (x, v) = p.step(x, v, 0.0, 0.0);
        }
        assert!(
            rel(energy(x, v), e0) < 1e-10,
            "h {h}: energy drift {:e}",
            rel(energy(x, v), e0)
        );
        let t = steps as f64 * h;
        let (s, c) = (omega * t).sin_cos();
        let xe = x0 * c + v0 / omega * s;
        let amp = (2.0 * e0).sqrt() / omega;
        // An exact propagator: round-off over the steps (measured 7.2e-12).
        assert!((x - xe).abs() < 1e-10 * amp, "h {h}: x {x} vs {xe}");
    }
}

// ---------------------------------------------------------------------------------------
// Spectra
// ---------------------------------------------------------------------------------------

/// Peak |x| at the record samples by RK4 with `sub` substeps per record interval.
fn rk4_sd(gm: &GroundMotion, omega: f64, zeta: f64, sub: usize) -> f64 {
    let (mut x, mut v, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for w in gm.accel.windows(2) {
        (x, v) = rk4(omega, zeta, gm.dt, sub, x, v, -w[0], -w[1]);
        peak = peak.max(x.abs());
    }
    peak
}

#[test]
fn spectrum_matches_fine_rk4_for_ramp_and_sine() {
    let dt = 0.02;
    // A ramp up then down (triangle pulse) followed by zeros, and a coarse sine.
    let ramp: Vec<f64> = (0..150)
        .map(|i| {
            if i <= 25 {
                i as f64 * 0.1
            } else if i <= 50 {
                (50 - i) as f64 * 0.1
            } else {
                0.0
            }
        })
        .collect();
    let sine: Vec<f64> = (0..200)
        .map(|i| 3.0 * (2.0 * std::f64::consts::PI * i as f64 * dt / 0.45).sin())
        .collect();
    let periods = [0.05, 0.1, 0.3, 0.45, 1.0, 2.5];
    for (name, acc) in [("ramp", ramp), ("sine", sine)] {
        let gm = GroundMotion::new(name, dt, acc).unwrap();
        for zeta in [0.0, 0.05] {
            let sp = response_spectrum(&gm, &periods, zeta);
            assert_eq!(sp.len(), periods.len());
            for p in &sp {
                let omega = 2.0 * std::f64::consts::PI / p.period;
                // RK4 with 200 sub-steps per record step: its own error is below 1e-8
                // here (measured 2.7e-9 in all).
                let reference = rk4_sd(&gm, omega, zeta, 200);
                assert!(
                    rel(p.sd, reference) < 1e-8,
                    "{name} zeta {zeta} T {}: {} vs {reference}",
                    p.period,
                    p.sd
                );
            }
        }
    }
}

#[test]
fn cap000_spectrum() {
    let gm = GroundMotion::load(&record("RSN752_LOMAP_CAP000.AT2"), &RecordFormat::At2).unwrap();
    let sp = response_spectrum(&gm, &[0.0, 1.0], 0.05);
    assert_eq!(sp[0].sd, 0.0);
    assert_eq!(sp[0].psa, gm.pga());
    let p = sp[1];
    assert!(p.sd.is_finite() && p.sd > 0.0);
    assert!(p.psa.is_finite() && p.psa > 0.0);
    // Physically sensible for a 0.53 g record: 0.1 g < PSA(1 s) < 3 g.
    assert!(
        p.psa > 0.1 * G && p.psa < 3.0 * G,
        "PSA(1 s) = {} g",
        p.psa / G
    );
    // Spot check against a fine RK4 on the real record.
    let omega = 2.0 * std::f64::consts::PI;
    assert!(rel(p.sd, rk4_sd(&gm, omega, 0.05, 20)) < 1e-11);
    // Very short period: PSA → PGA, with a relative error of order (f_record / f)² for the
    // record's frequencies f_record ≲ 25 Hz against f = 200 Hz, at most about 1.6 %
    // (measured below 0.1 %).
    let short = response_spectrum(&gm, &[0.005], 0.05)[0];
    assert!(
        rel(short.psa, gm.pga()) < 0.016,
        "{} vs {}",
        short.psa,
        gm.pga()
    );
}

#[test]
fn default_periods_shape() {
    let p = default_periods();
    assert_eq!(p.len(), 100);
    assert!(rel(p[0], 0.02) < 1e-12);
    assert!(rel(*p.last().unwrap(), 10.0) < 1e-12);
    let r0 = p[1] / p[0];
    for w in p.windows(2) {
        assert!(w[1] > w[0]);
        assert!(rel(w[1] / w[0], r0) < 1e-13);
    }
}

// ---------------------------------------------------------------------------------------
// Robustness
// ---------------------------------------------------------------------------------------

/// What every read must give, whatever the text: a record the solvers accept
/// ([`structure::testing::read_record_violation`], which the fuzz target asserts too), or an
/// error that names the file.
fn read_valid_or_named<E: std::fmt::Display>(
    r: Result<GroundMotion, E>,
    file: &str,
) -> Result<(), TestCaseError> {
    match r {
        Ok(gm) => {
            let v = structure::testing::read_record_violation(&gm);
            prop_assert!(v.is_none(), "{v:?}");
        }
        Err(e) => {
            let m = e.to_string();
            prop_assert!(m.contains(file), "{m}");
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn parsers_never_panic_on_arbitrary_text(s in any::<String>()) {
        read_valid_or_named(GroundMotion::from_at2_str(&s, "p.AT2"), "p.AT2")?;
        read_valid_or_named(GroundMotion::from_two_column_str(&s, "p.txt", Units::G), "p.txt")?;
        read_valid_or_named(GroundMotion::from_one_column_str(&s, "p.txt", 0.01, Units::G), "p.txt")?;
    }

    #[test]
    fn parsers_never_panic_on_record_like_text(
        line4 in prop_oneof![
            Just("NPTS= 3, DT= 0.01 SEC".to_string()),
            Just("3 0.01 NPTS, DT".to_string()),
            "[0-9 .,=A-Za-z-]{0,30}",
        ],
        body in "[0-9eE.+\\- \\t\\r\\n,#xa-z]{0,200}",
    ) {
        let text = format!("{HEAD}{line4}\n{body}");
        read_valid_or_named(GroundMotion::from_at2_str(&text, "p.AT2"), "p.AT2")?;
        read_valid_or_named(GroundMotion::from_two_column_str(&body, "p.txt", Units::G), "p.txt")?;
        read_valid_or_named(
            GroundMotion::from_one_column_str(&body, "p.txt", 0.01, Units::CentimetersPerSecond2),
            "p.txt",
        )?;
    }

    /// Valid AT2 records (the text above almost never is one): any finite values, written
    /// in any of the usual layouts, read back exactly, NPTS and DT from line 4.
    #[test]
    fn valid_at2_records_read_back_exactly(
        values in prop::collection::vec(-10.0f64..10.0, 2..60),
        per_line in 1usize..9,
        scientific in any::<bool>(),
    ) {
        let n = values.len();
        let mut text = format!("{HEAD}NPTS= {n}, DT= 0.005 SEC\n");
        for chunk in values.chunks(per_line) {
            let line: Vec<String> = chunk
                .iter()
                .map(|v| if scientific { format!("{v:e}") } else { format!("{v}") })
                .collect();
            text.push_str(&line.join("  "));
            text.push('\n');
        }
        let gm = GroundMotion::from_at2_str(&text, "p.AT2").map_err(|e| {
            TestCaseError::fail(format!("{e}: {text}"))
        })?;
        prop_assert_eq!(gm.npts(), n);
        prop_assert_eq!(gm.dt, 0.005);
        // In g, converted to m/s² once: the same product as the reader's.
        for (a, v) in gm.accel.iter().zip(&values) {
            prop_assert_eq!(*a, v * G);
        }
    }
}

/// `peak_abs` (four running maxima, used by `pga` and the momentum method's audit scale) is
/// the one-by-one fold of |v| for every length and position of the peak, NaNs skipped alike.
#[test]
fn peak_abs_is_the_fold_of_abs() {
    use structure::ground::peak_abs;
    let fold = |v: &[f64]| v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    for n in 0..13 {
        for at in 0..n.max(1) {
            let mut v: Vec<f64> = (0..n).map(|i| ((i * 7 % 5) as f64 - 2.0) * 0.1).collect();
            if n > 0 {
                v[at] = -3.5;
            }
            assert_eq!(peak_abs(&v), fold(&v), "{v:?}");
            if n > 1 {
                v[(at + 1) % n] = f64::NAN;
                assert_eq!(peak_abs(&v), fold(&v), "{v:?}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// What two- and one-column readers accept (docs/scenes.md), and header lines
// ---------------------------------------------------------------------------------------

#[test]
fn two_column_separators_comments_and_blank_lines_as_documented() {
    // A byte-order mark, `#` comment lines (also indented), a trailing comment, blank and
    // whitespace-only lines, CRLF endings; whitespace (tabs too), commas and semicolons,
    // several in a row counting as one; a sign inside a token starting the next value; a
    // Fortran `D` exponent.
    let text = "\u{feff}# time (s), accel (g)\r\n   # indented comment\r\n0.00;0.1\r\n\r\n  \t \n\
                0.01 , 0.2   # trailing comment\n0.02\t\t-0.3\n0.03,,0.4\n0.04-0.5\n0.05 1.0D-1\n";
    let gm = GroundMotion::from_two_column_str(text, "sep.csv", Units::G).unwrap();
    let want = [0.1, 0.2, -0.3, 0.4, -0.5, 0.1];
    assert_eq!(gm.npts(), want.len());
    assert!(rel(gm.dt, 0.01) < 1e-12, "{}", gm.dt);
    for (a, w) in gm.accel.iter().zip(want) {
        assert!((a - w * G).abs() < 1e-12, "{a} vs {w}");
    }
    // One-column files take the same separators and comments, any number of values a line.
    let one = "# accel (g)\n0.1, 0.2; 0.3\n\n0.4 # trailing\n-0.5-0.6\n";
    let gm = GroundMotion::from_one_column_str(one, "one.txt", 0.01, Units::G).unwrap();
    assert_eq!(gm.npts(), 6);
    assert!((gm.accel[5] + 0.6 * G).abs() < 1e-12);
}

#[test]
fn a_header_line_gets_a_hint_naming_the_file_and_line() {
    let hint = "a header line is not read: remove it or start it with `#`";
    let data = "0.00,0.1\n0.01,0.2\n0.02,0.3\n";
    // Two-column: a header of two words, of three words, and after comments and blank lines.
    for (text, line) in [
        (format!("time_s,accel_g\n{data}"), 1),
        (format!("time (s) accel (g)\n{data}"), 1),
        (format!("# recorded 2024\n\nTime Accel\n{data}"), 3),
    ] {
        let e = GroundMotion::from_two_column_str(&text, "h.csv", Units::G).unwrap_err();
        assert!(
            matches!(
                e,
                RecordError::Value {
                    header: true,
                    column: 1,
                    ..
                }
            ),
            "{e:?}"
        );
        msg_has(
            &e,
            &[
                &format!("h.csv line {line}, column 1"),
                "expected a number (time in s)",
                hint,
            ],
        );
    }
    let e =
        GroundMotion::from_two_column_str(&format!("time_s,accel_g\n{data}"), "h.csv", Units::G)
            .unwrap_err();
    msg_has(&e, &["found \"time_s\""]);
    // Commented out, the header is read as a comment.
    let gm =
        GroundMotion::from_two_column_str(&format!("# time_s,accel_g\n{data}"), "h.csv", Units::G)
            .unwrap();
    assert_eq!(gm.npts(), 3);
    // A word below the first line of numbers, or after a number on the first line, is a
    // bad value, not a header: no hint.
    for text in ["0 1\nfoo 2\n0.02 3\n", "0 accel\n0.01 2\n"] {
        let e = GroundMotion::from_two_column_str(text, "w.csv", Units::G).unwrap_err();
        assert!(
            matches!(e, RecordError::Value { header: false, .. }),
            "{e:?}"
        );
        assert!(!e.to_string().contains("header"), "{e}");
    }
    // One-column: the same hint on the first line of values only.
    let e = GroundMotion::from_one_column_str("# x\naccel_g\n0.1\n0.2\n", "o.txt", 0.01, Units::G)
        .unwrap_err();
    msg_has(
        &e,
        &[
            "o.txt line 2, column 1",
            "expected a number (acceleration in g)",
            "found \"accel_g\"",
            hint,
        ],
    );
    let e =
        GroundMotion::from_one_column_str("0.1\n0.2\nfoo\n", "o.txt", 0.01, Units::G).unwrap_err();
    msg_has(&e, &["o.txt line 3"]);
    assert!(!e.to_string().contains("header"), "{e}");
    // AT2 files have no `#` comments: their data lines get no such hint.
    let e = at2_err(&at2("NPTS= 2, DT= 0.01 SEC", "time accel\n"));
    assert!(!e.to_string().contains("header line"), "{e}");
}

#[test]
fn a_two_column_file_read_as_one_column_names_the_line_and_says_what_to_do() {
    let parts = [
        "two.txt line 2",
        "(the record is read as one-column)",
        "found 2 values on this line",
        "rising by 0.01",
        "a two-column record",
        "read it as two-column, without a time step",
    ];
    let text = "# t, a\n0.00 0.1\n0.01 0.2\n0.02 0.3\n";
    let e = GroundMotion::from_one_column_str(text, "two.txt", 0.01, Units::G).unwrap_err();
    assert!(
        matches!(e, RecordError::TwoColumnsAsOne { line: 2, .. }),
        "{e:?}"
    );
    msg_has(&e, &parts);
    // With a header line above the columns, the columns are what is reported.
    let text = "t,a\n0.00,0.1\n0.01,0.2\n0.02,0.3\n";
    let e = GroundMotion::from_one_column_str(text, "two.txt", 0.01, Units::G).unwrap_err();
    msg_has(&e, &parts);
}

#[test]
fn counts_of_one_are_singular() {
    let e = at2_err(&at2("NPTS= 3, DT= 0.01 SEC", "1.0\n"));
    msg_has(
        &e,
        &["NPTS = 3, but the file holds 1 value (expected exactly 3)"],
    );
    let e = at2_err(&at2("NPTS= 1, DT= 0.01 SEC", "1.0 2.0\n"));
    msg_has(
        &e,
        &["NPTS = 1, but the file holds 2 values (expected exactly 1)"],
    );
}

#[test]
fn values_per_line_counts_as_the_readers_split() {
    use structure::ground::record::values_per_line;
    assert_eq!(
        values_per_line("# t a\n\n0 0.1\n0.01, 0.2 # x\n"),
        Some((2, 3))
    );
    assert_eq!(values_per_line("0.1\n-0.2\n\n0.3\n"), Some((1, 1)));
    assert_eq!(values_per_line("0 0.1\n0.2\n"), None);
    assert_eq!(values_per_line("# only a comment\n\n"), None);
}

/// A file read as one-column only because a time step came without a format is refused when
/// every line of numbers holds the same count of two or more values, whatever its step: a
/// two-row table and one with uneven times pass the one-column reader's own check (which
/// needs three rows of uniform times) and would be read value after value.
#[test]
fn an_inferred_one_column_refuses_a_table_of_any_step() {
    let dir = std::env::temp_dir().join(format!("pound-inferred-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let inferred = |f: &Path| RecordFormat::infer(f, None, Some(0.01), Units::G).unwrap();
    for (name, text, values) in [
        ("two-rows.txt", "0 0.1\n0.01 0.2\n", 2),
        (
            "uneven.txt",
            "0 0.1\n0.0100 0.2\n0.0201 0.1\n0.0301 0.05\n",
            2,
        ),
        ("three.txt", "0 0.1 0.2\n0.01 0.2 0.3\n", 3),
    ] {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        let e = GroundMotion::load_choice(&f, &inferred(&f)).unwrap_err();
        assert!(
            matches!(&e, RecordError::InferredOneColumn { line: 1, values: v, .. } if *v == values),
            "{name}: {e:?}"
        );
        msg_has(
            &e,
            &[
                &format!("{name} line 1: every line of numbers holds {values} values"),
                "read as one-column because a time step was given without a format",
            ],
        );
        // Read as one-column on purpose (an explicit format), it is read value after value.
        let g = GroundMotion::load(
            &f,
            &RecordFormat::OneColumn {
                dt: 0.01,
                units: Units::G,
            },
        );
        assert_eq!(
            g.unwrap().accel.len(),
            text.split_whitespace().count(),
            "{name}"
        );
    }
    // One value per line, or lines of different counts: not a table, read as asked.
    for (name, text) in [
        ("one.txt", "0.1\n0.2\n0.3\n"),
        ("mixed.txt", "0.1 0.2\n0.3\n"),
    ] {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        let g = GroundMotion::load_choice(&f, &inferred(&f)).unwrap();
        assert_eq!(g.npts(), 3, "{name}");
    }
    // A file that cannot be read: the reader says why.
    let missing = dir.join("missing.txt");
    let e = GroundMotion::load_choice(&missing, &inferred(&missing)).unwrap_err();
    assert!(matches!(e, RecordError::Io { .. }), "{e:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// The one rule choosing a record file's format: RecordFormat::infer
// ---------------------------------------------------------------------------------------

#[test]
fn infer_without_a_format_follows_the_name_then_the_time_step() {
    let g = Units::G;
    let cm = Units::CentimetersPerSecond2;
    // `.at2` in any case: AT2 (its units are the header's, whatever `units` says).
    for name in ["r.at2", "r.AT2", "dir/r.At2", "r.aT2"] {
        assert_eq!(
            RecordFormat::infer(Path::new(name), None, None, cm),
            Ok(RecordChoice {
                format: RecordFormat::At2,
                inferred: false
            }),
            "{name}"
        );
    }
    // Only the extension counts: not a name merely containing it, nor a hidden file `.at2`.
    for name in ["r.at2.txt", "at2", "r_at2", ".at2", "r.at22"] {
        assert_eq!(
            RecordFormat::infer(Path::new(name), None, None, g)
                .unwrap()
                .format,
            RecordFormat::TwoColumn { units: g },
            "{name}"
        );
    }
    // A time step alone: one-column, inferred.
    assert_eq!(
        RecordFormat::infer(Path::new("r.txt"), None, Some(0.02), cm),
        Ok(RecordChoice {
            format: RecordFormat::OneColumn {
                dt: 0.02,
                units: cm
            },
            inferred: true
        })
    );
    // The same given on purpose: not inferred.
    assert_eq!(
        RecordFormat::infer(
            Path::new("r.txt"),
            Some(FormatKind::OneColumn),
            Some(0.02),
            cm
        ),
        Ok(RecordChoice {
            format: RecordFormat::OneColumn {
                dt: 0.02,
                units: cm
            },
            inferred: false
        })
    );
    // A format given wins over the name.
    assert_eq!(
        RecordFormat::infer(Path::new("r.AT2"), Some(FormatKind::TwoColumn), None, cm)
            .unwrap()
            .format,
        RecordFormat::TwoColumn { units: cm }
    );
    assert_eq!(
        RecordFormat::infer(Path::new("r.txt"), Some(FormatKind::At2), None, g)
            .unwrap()
            .format,
        RecordFormat::At2
    );
}

#[test]
fn infer_refuses_each_misfit_with_its_data() {
    let g = Units::G;
    let at2 = Path::new("r.AT2");
    let txt = Path::new("r.txt");
    // A time step with AT2, chosen by the name or given.
    assert_eq!(
        RecordFormat::infer(at2, None, Some(0.01), g),
        Err(FormatRefusal::DtWithAt2 {
            dt: 0.01,
            by_name: true
        })
    );
    assert_eq!(
        RecordFormat::infer(txt, Some(FormatKind::At2), Some(0.01), g),
        Err(FormatRefusal::DtWithAt2 {
            dt: 0.01,
            by_name: false
        })
    );
    // The AT2 refusal comes before the time step's own check.
    assert_eq!(
        RecordFormat::infer(at2, None, Some(-1.0), g),
        Err(FormatRefusal::DtWithAt2 {
            dt: -1.0,
            by_name: true
        })
    );
    // A time step with two-column (given: a time step alone means one-column).
    assert_eq!(
        RecordFormat::infer(txt, Some(FormatKind::TwoColumn), Some(0.01), g),
        Err(FormatRefusal::DtWithTwoColumn { dt: 0.01 })
    );
    // One-column without a time step.
    assert_eq!(
        RecordFormat::infer(at2, Some(FormatKind::OneColumn), None, g),
        Err(FormatRefusal::OneColumnWithoutDt)
    );
    // A time step that is not finite and > 0, inferred or given.
    for dt in [0.0, -0.01, f64::INFINITY] {
        for format in [None, Some(FormatKind::OneColumn)] {
            assert_eq!(
                RecordFormat::infer(txt, format, Some(dt), g),
                Err(FormatRefusal::BadDt { dt }),
                "{dt} {format:?}"
            );
        }
    }
    let nan = RecordFormat::infer(txt, None, Some(f64::NAN), g).unwrap_err();
    assert!(
        matches!(nan, FormatRefusal::BadDt { dt } if dt.is_nan()),
        "{nan:?}"
    );
    // The messages name no caller's setting, only what is wrong.
    for (e, parts) in [
        (
            FormatRefusal::DtWithAt2 {
                dt: 0.01,
                by_name: true,
            },
            &["0.01 s", "AT2", "ends in .at2", "line 4"][..],
        ),
        (
            FormatRefusal::DtWithTwoColumn { dt: 0.01 },
            &["0.01 s", "two-column", "time column"][..],
        ),
        (
            FormatRefusal::OneColumnWithoutDt,
            &["one-column", "time step"][..],
        ),
        (FormatRefusal::BadDt { dt: 0.0 }, &["> 0", "found 0"][..]),
    ] {
        let m = e.to_string();
        for p in parts {
            assert!(m.contains(p), "{m:?} lacks {p:?}");
        }
        assert!(!m.contains("--") && !m.contains('`'), "{m}");
    }
}

#[test]
fn format_kind_names_round_trip() {
    for k in [
        FormatKind::At2,
        FormatKind::TwoColumn,
        FormatKind::OneColumn,
    ] {
        assert_eq!(FormatKind::from_name(k.name()), Some(k));
    }
    assert_eq!(FormatKind::from_name("AT2"), None);
    assert_eq!(FormatKind::from_name("two_column"), None);
    assert_eq!(
        RecordFormat::OneColumn {
            dt: 0.1,
            units: Units::G
        }
        .kind(),
        FormatKind::OneColumn
    );
}

/// The table refusal of an inferred one-column read is made on the text being parsed (the
/// bytes `load_choice` read once), not on a second read of the file: `parse` refuses the
/// text itself, with no file at all.
#[test]
fn the_inferred_refusal_is_made_on_the_text_parsed() {
    let choice = RecordFormat::infer(Path::new("t.txt"), None, Some(0.01), Units::G).unwrap();
    let e = GroundMotion::parse("# t a\n0 0.1\n0.01 0.2\n", "t.txt", &choice).unwrap_err();
    assert!(
        matches!(
            e,
            RecordError::InferredOneColumn {
                line: 2,
                values: 2,
                ..
            }
        ),
        "{e:?}"
    );
    // Given on purpose, the same text is read value after value.
    let explicit = RecordChoice::explicit(choice.format);
    let g = GroundMotion::parse("# t a\n0 0.1\n0.01 0.2\n", "t.txt", &explicit).unwrap();
    assert_eq!(g.accel.len(), 4);
    // `inferred` means nothing to the other formats.
    let two = RecordChoice {
        format: RecordFormat::TwoColumn { units: Units::G },
        inferred: true,
    };
    let g = GroundMotion::parse("0 0.1\n0.01 0.2\n", "t.txt", &two).unwrap();
    assert_eq!((g.accel.len(), g.dt), (2, 0.01));
}

/// An inferred one-column read of a table is refused even when the record memo holds the
/// same file read as one-column on purpose: the explicit read of a table succeeds and is
/// remembered, and the inferred read after it is still refused (and the other way round, a
/// refusal leaves nothing for the explicit read to trip on).
#[test]
fn an_inferred_read_checks_its_table_before_the_memo() {
    let dir = std::env::temp_dir().join(format!("pound-memo-inferred-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("table.txt");
    std::fs::write(&f, "0 0.1\n0.01 0.2\n0.025 0.3\n").unwrap();
    let inferred = RecordFormat::infer(&f, None, Some(0.01), Units::G).unwrap();
    assert!(inferred.inferred);
    let explicit = RecordChoice::explicit(inferred.format);
    for _ in 0..2 {
        let g = GroundMotion::load_choice(&f, &explicit).unwrap();
        assert_eq!(g.npts(), 6);
        let e = GroundMotion::load_choice(&f, &inferred).unwrap_err();
        assert!(matches!(e, RecordError::InferredOneColumn { .. }), "{e:?}");
    }
    // `load` is the explicit read.
    assert_eq!(GroundMotion::load(&f, &inferred.format).unwrap().npts(), 6);
    // A one-value-per-line file read inferred gives the same record as the explicit read.
    let g = dir.join("values.txt");
    std::fs::write(&g, "0.1\n0.2\n0.3\n").unwrap();
    let a = GroundMotion::load_choice(&g, &inferred).unwrap();
    let b = GroundMotion::load_choice(&g, &explicit).unwrap();
    assert_eq!(a, b);
    // load_bytes reads the bytes given, not the file.
    let c = GroundMotion::load_bytes(&f, b"0.5\n0.6\n".to_vec(), &inferred).unwrap();
    assert_eq!(c.accel, vec![0.5 * G, 0.6 * G]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn checked_scaled_names_the_first_sample_that_overflows() {
    let g = GroundMotion::new("x", 0.01, vec![1.0, -2.0, 4.0]).unwrap();
    assert_eq!(g.checked_scaled(2.0).unwrap(), g.scaled(2.0));
    let e = g.checked_scaled(1e308).unwrap_err();
    assert_eq!(
        e,
        ScaleOverflow {
            factor: 1e308,
            sample: 2,
            value: -2.0,
            integrals: false,
        }
    );
    let m = e.to_string();
    assert!(
        m.contains("sample 2") && m.contains("beyond the range"),
        "{m}"
    );
}

/// Accelerations finite but near the top of the floating-point range take the ground
/// velocity or displacement (or the jerk between samples) beyond it: such a record is
/// refused on reading, naming the file, and a scale factor that does this is refused naming
/// the largest sample, where `pound record` used to print a PGV of `inf`.
#[test]
fn records_whose_integrals_overflow_are_refused() {
    // 1e307 g: finite in m/s² (9.8e307), but the jerk (a1 − a0)/dt and the displacement are not.
    let text = "0 1e307\n0.01 1.5e307\n0.02 1.7e307\n0.03 1.7e307\n";
    let e = GroundMotion::from_two_column_str(text, "big.txt", Units::G).unwrap_err();
    assert!(matches!(e, RecordError::Unbounded { .. }), "{e:?}");
    let m = e.to_string();
    assert!(
        m.starts_with("big.txt: accelerations up to 1.667e308 m/s^2")
            && m.contains("ground velocity or displacement (or the slope between two samples)")
            && m.contains("beyond the range of floating point"),
        "{m}"
    );
    assert!(matches!(
        GroundMotion::new("big", 0.01, vec![1e307, 1.7e308, 1.7e308]),
        Err(RecordError::Unbounded { .. })
    ));
    // Alternating samples whose difference overflows: the velocity computed from them is
    // finite (0, the crossing's time rounding to the sample) but wrong; refused by the slopes.
    let alternating = vec![1.7e308, -1.7e308, 1.7e308];
    assert!(matches!(
        GroundMotion::new("alt", 0.01, alternating.clone()),
        Err(RecordError::Unbounded { .. })
    ));
    // A slope that overflows only through a short step.
    assert!(GroundMotion::new("steep", 1e-6, vec![0.0, 1e300]).is_ok());
    assert!(GroundMotion::new("steep", 1e-6, vec![0.0, 1e303]).is_err());
    // The same record a little smaller reads, and its integrals are finite.
    let g =
        GroundMotion::from_two_column_str("0 1e3\n0.01 1.5e3\n0.02 -1.7e3\n", "ok.txt", Units::G)
            .unwrap();
    assert!(g.integrals_finite() && g.pgd().is_finite());
    // Scaling: every sample stays finite (1.5e308 m/s² at most), the velocity does not
    // (samples 2 and 3 sum to 2.85e308).
    let g = GroundMotion::new("x", 0.01, vec![0.0, 1.0, 0.9, 0.5]).unwrap();
    let e = g.checked_scaled(1.5e308).unwrap_err();
    assert_eq!(
        e,
        ScaleOverflow {
            factor: 1.5e308,
            sample: 2,
            value: 1.0,
            integrals: true,
        }
    );
    let m = e.to_string();
    assert!(
        m.contains("its largest sample 2") && m.contains("ground velocity or displacement"),
        "{m}"
    );
    assert!(g.checked_scaled(1e300).is_ok());
}
