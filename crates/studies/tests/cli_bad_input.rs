//! The bad-input catalogue: malformed records, scenes and `--set` expressions run through the
//! real `pound` binary. Every case must
//!
//! - exit with code 2 (bad input),
//! - print an error on stderr that names the file (or the `--set` expression), the line or
//!   key, and what was expected,
//! - not panic,
//! - leave no output behind: the `--out` / `--history` files passed are never created, and
//!   nothing is printed on stdout.
//!
//! The loader-level tests (and the no-panic property test) are in
//! `crates/structure/tests/scene.rs`.

use std::path::Path;

mod common;
use common::{pound, TempDir};

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Runs `args` and checks the bad-input contract; `expect` are fragments of the message
/// (file, line or key, what was expected). `outputs` must not exist afterwards.
#[track_caller]
fn assert_bad(args: &[String], expect: &[&str], outputs: &[&Path]) -> String {
    let out = pound(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let what = format!(
        "pound {}\nstderr: {stderr}\nstdout: {stdout}",
        args.join(" ")
    );
    assert_eq!(out.status.code(), Some(2), "exit code, {what}");
    assert!(!stderr.contains("panicked"), "panic, {what}");
    // Notes (settings the method does not use) may come first; an error line must follow.
    assert!(
        stderr.lines().any(|l| l.starts_with("error")),
        "an error message, {what}"
    );
    for e in expect {
        assert!(stderr.contains(e), "stderr should contain {e:?}, {what}");
    }
    assert!(stdout.is_empty(), "nothing on stdout, {what}");
    for p in outputs {
        assert!(!p.exists(), "{} must not be written, {what}", p.display());
    }
    stderr
}

// ---------------------------------------------------------------------------------------
// Records
// ---------------------------------------------------------------------------------------

const AT2_HEAD: &str =
    "PEER NGA STRONG MOTION DATABASE RECORD\nSynthetic, bad-input test\nACCELERATION TIME SERIES IN UNITS OF G\n";

fn at2(line4: &str, body: &str) -> String {
    format!("{AT2_HEAD}{line4}\n{body}")
}

const VALUES5: &str = "  0.01  0.02 -0.03  0.04  0.00\n";

/// A record case: the file, extra `pound record` arguments, and the expected fragments.
/// Checked through `pound record`, `pound spectrum --out` and a scene's `[ground_motion]`.
#[track_caller]
fn record_case(name: &str, content: &str, cli: &[&str], scene_gm: &str, expect: &[&str]) {
    let d = TempDir::new("record");
    let rec = d.write(name, content);
    let mut args = vec!["record".to_string(), s(&rec)];
    args.extend(cli.iter().map(|a| a.to_string()));
    let mut parts = vec![name];
    parts.extend_from_slice(expect);
    assert_bad(&args, &parts, &[]);

    let csv = d.path("spectrum.csv");
    let mut args = vec!["spectrum".to_string(), s(&rec), "--out".into(), s(&csv)];
    args.extend(cli.iter().map(|a| a.to_string()));
    assert_bad(&args, &parts, &[&csv]);

    let scene = d.write(
        "scene.toml",
        &format!("{BUILDINGS}\n[ground_motion]\nfile = \"{name}\"\n{scene_gm}\n"),
    );
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    let args = run_args(&scene, &json, &hist, &[]);
    let mut parts = vec!["scene.toml", "ground_motion.file", name];
    parts.extend_from_slice(expect);
    assert_bad(&args, &parts, &[&json, &hist]);
}

#[test]
fn record_valid_baseline() {
    // The same helpers accept a good record, so the failures below are about the defect.
    let d = TempDir::new("good-record");
    let rec = d.write("good.AT2", &at2("NPTS=    5, DT=   0.0100 SEC", VALUES5));
    let out = pound(&["record".into(), s(&rec)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let scene = d.write(
        "scene.toml",
        &format!("{BUILDINGS}\n[ground_motion]\nfile = \"good.AT2\"\n"),
    );
    let out = pound(&["modes".into(), s(&scene)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn record_missing_header() {
    let body = "0.01 0.02\n0.03 0.04\n0.05 0.06\n0.07 0.08\n0.09 0.10\n";
    // Without a header, line 3 holds no units: the first line that cannot be a header.
    record_case("noheader.AT2", body, &[], "", &["line 3", "UNITS OF G"]);
}

#[test]
fn record_bad_header() {
    let text = at2("NPTS is seven, DT is small", VALUES5);
    record_case("badheader.AT2", &text, &[], "", &["line 4", "NPTS", "DT"]);
    let text = at2("NPTS=  5 0.0100 SEC", VALUES5);
    record_case("badheader2.AT2", &text, &[], "", &["line 4", "expected"]);
}

#[test]
fn record_truncated_header() {
    record_case(
        "short.AT2",
        "PEER NGA STRONG MOTION DATABASE RECORD\n",
        &[],
        "",
        &["line 2", "header"],
    );
}

#[test]
fn record_npts_larger_than_values() {
    let text = at2("NPTS=    7, DT=   0.0100 SEC", VALUES5);
    record_case(
        "npts_large.AT2",
        &text,
        &[],
        "",
        &["line 4", "NPTS = 7", "5"],
    );
}

#[test]
fn record_npts_smaller_than_values() {
    let text = at2("NPTS=    3, DT=   0.0100 SEC", VALUES5);
    record_case(
        "npts_small.AT2",
        &text,
        &[],
        "",
        &["line 4", "NPTS = 3", "5"],
    );
}

#[test]
fn record_non_numeric_value() {
    let text = at2(
        "NPTS=    5, DT=   0.0100 SEC",
        "  0.01  0.02\n  0.03  abc  0.00\n",
    );
    record_case(
        "word.AT2",
        &text,
        &[],
        "",
        &["line 6", "column", "abc", "number"],
    );
    let two = "0.00 0.1\n0.01 0.2\n0.02 x\n";
    record_case("word.txt", two, &[], "", &["line 3", "x", "number"]);
    let one = "0.1\n0.2\n0.3 0.4 zz\n";
    record_case(
        "word.dat",
        one,
        &["--format", "one-column", "--dt", "0.01"],
        "format = \"one-column\"\ndt = 0.01",
        &["line 3", "zz", "number"],
    );
}

#[test]
fn record_empty_file() {
    record_case("empty.AT2", "", &[], "", &["empty"]);
    record_case("empty.txt", "", &[], "", &["empty"]);
    record_case("blank.txt", "\n  \n\n", &[], "", &["empty"]);
    record_case(
        "empty.dat",
        "",
        &["--format", "one-column", "--dt", "0.01"],
        "format = \"one-column\"\ndt = 0.01",
        &["empty"],
    );
}

#[test]
fn record_nan_and_infinite_values() {
    for (i, bad) in [
        "NaN",
        "nan",
        "inf",
        "-inf",
        "Infinity",
        "1e999",
        "-1.0E+400",
    ]
    .iter()
    .enumerate()
    {
        let text = at2(
            "NPTS=    5, DT=   0.0100 SEC",
            &format!("  0.01  0.02 {bad}  0.04  0.00\n"),
        );
        record_case(
            &format!("nonfinite{i}.AT2"),
            &text,
            &[],
            "",
            &["line 5", bad],
        );
        let two = format!("0.00 0.1\n0.01 {bad}\n0.02 0.0\n");
        record_case(
            &format!("nonfinite{i}.txt"),
            &two,
            &[],
            "",
            &["line 2", bad],
        );
    }
}

/// Values finite in m/s² whose velocity or displacement is not (1e307 g): refused naming the
/// file, where `pound record` printed a PGV and PGD of `inf` and exited 0.
#[test]
fn record_whose_integrals_overflow() {
    record_case(
        "huge.txt",
        "0.00 1e307\n0.01 1.5e307\n0.02 1.7e307\n0.03 0.0\n",
        &[],
        "",
        &["accelerations up to", "ground velocity or displacement"],
    );
    // A scale that leaves every sample finite but not the velocity: refused naming the key.
    let d = TempDir::new("huge-scale");
    d.write("small.txt", "0.00 0.0\n0.01 1.0\n0.02 0.9\n0.03 0.5\n");
    let scene = d.write(
        "scene.toml",
        &format!("{BUILDINGS}\n[ground_motion]\nfile = \"small.txt\"\nscale = 1.5e307\n"),
    );
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    assert_bad(
        &run_args(&scene, &json, &hist, &[]),
        &[
            "ground_motion.scale",
            "1.5e307 scales",
            "its largest sample 2",
            "ground velocity or displacement",
        ],
        &[&json, &hist],
    );
}

#[test]
fn record_zero_and_negative_dt() {
    let zero = at2("NPTS=    5, DT=   0.0000 SEC", VALUES5);
    record_case("dt0.AT2", &zero, &[], "", &["line 4", "DT > 0", "found 0"]);
    let neg = at2("NPTS=    5, DT=  -0.0100 SEC", VALUES5);
    record_case("dtneg.AT2", &neg, &[], "", &["line 4", "DT > 0", "-0.01"]);
    // Below a microsecond (a unit or typing error; near 1e-300 s the solvers could not
    // compute with it and stopped at t = 0 naming no key), and infinite: "finite" is said.
    let tiny = at2("NPTS=    5, DT=  1e-8 SEC", VALUES5);
    record_case(
        "dttiny.AT2",
        &tiny,
        &[],
        "",
        &["line 4", "at least 1e-6 s", "found 1e-8"],
    );
    let inf = at2("NPTS=    5, DT=  1e400 SEC", VALUES5);
    record_case(
        "dtinf.AT2",
        &inf,
        &[],
        "",
        &["line 4", "finite", "found inf"],
    );
    // Two-column: a repeated or decreasing time.
    record_case(
        "t0.txt",
        "0 1\n0 2\n0 3\n",
        &[],
        "",
        &["line 2", "time 0 s at line 2 is not after 0 s at line 1"],
    );
    record_case(
        "tneg.txt",
        "0 1\n-0.01 2\n-0.02 3\n",
        &[],
        "",
        &[
            "line 2",
            "time -0.01 s at line 2 is not after 0 s at line 1",
        ],
    );
}

#[test]
fn record_one_column_dt_on_the_command_line() {
    let d = TempDir::new("one-column-dt");
    let rec = d.write("one.dat", "0.1\n0.2\n0.3\n");
    let csv = d.path("spectrum.csv");
    for (dt, expect) in [
        ("--dt=0", &["--dt", "0", "> 0"][..]),
        ("--dt=-0.01", &["--dt", "-0.01", "> 0"][..]),
        ("--dt=nan", &["--dt", "NaN", "> 0"][..]),
        ("--dt=1e-320", &["--dt 1e-320", "at least 1e-6 s"][..]),
    ] {
        let base = ["--format".to_string(), "one-column".into(), dt.into()];
        let mut args = vec!["record".to_string(), s(&rec)];
        args.extend(base.iter().cloned());
        assert_bad(&args, expect, &[]);
        let mut args = vec!["spectrum".to_string(), s(&rec), "--out".into(), s(&csv)];
        args.extend(base.iter().cloned());
        assert_bad(&args, expect, &[&csv]);
    }
    let args = vec![
        "record".to_string(),
        s(&rec),
        "--format".into(),
        "one-column".into(),
    ];
    assert_bad(&args, &["one-column", "--dt"], &[]);
    let args = vec![
        "record".to_string(),
        s(&rec),
        "--units".into(),
        "furlongs".into(),
    ];
    assert_bad(&args, &["--units", "furlongs"], &[]);
}

#[test]
fn record_one_column_dt_in_a_scene() {
    let d = TempDir::new("scene-dt");
    d.write("one.dat", "0.1\n0.2\n0.3\n");
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    for (gm, expect) in [
        ("dt = 0.0", &["ground_motion.dt", "> 0"][..]),
        ("dt = -0.01", &["ground_motion.dt", "-0.01", "> 0"][..]),
        ("dt = nan", &["ground_motion.dt", "> 0"][..]),
        (
            "dt = 1e-300",
            &["ground_motion.dt", "1e-300", "at least 1e-6 s"][..],
        ),
        ("", &["ground_motion.dt", "missing"][..]),
    ] {
        let scene = d.write(
            "scene.toml",
            &format!(
                "{BUILDINGS}\n[ground_motion]\nfile = \"one.dat\"\nformat = \"one-column\"\n{gm}\n"
            ),
        );
        let mut parts = vec!["scene.toml"];
        parts.extend_from_slice(expect);
        assert_bad(
            &run_args(&scene, &json, &hist, &[]),
            &parts,
            &[&json, &hist],
        );
    }
}

#[test]
fn record_file_that_does_not_exist() {
    let d = TempDir::new("no-record");
    let missing = d.path("missing.AT2");
    assert_bad(
        &["record".into(), s(&missing)],
        &["missing.AT2", "cannot read"],
        &[],
    );
    let csv = d.path("spectrum.csv");
    assert_bad(
        &["spectrum".into(), s(&missing), "--out".into(), s(&csv)],
        &["missing.AT2"],
        &[&csv],
    );
    // An all-zero record has no PGA to scale to (as `run` says of a scene's record).
    let zeros = d.write("zeros.txt", "0 0\n0.01 0\n0.02 0\n");
    assert_bad(
        &[
            "spectrum".into(),
            s(&zeros),
            "--pga".into(),
            "0.4".into(),
            "--out".into(),
            s(&csv),
        ],
        &["zeros.txt", "all zeros", "--pga 0.4"],
        &[&csv],
    );
}

#[test]
fn record_two_column_shape_errors() {
    // Three values on a line, and non-uniform times.
    let d = TempDir::new("two-column");
    let a = d.write("three.txt", "0.00 0.1\n0.01 0.2 0.3\n");
    assert_bad(
        &["record".into(), s(&a)],
        &["three.txt", "line 2", "2 values"],
        &[],
    );
    let b = d.write("uneven.txt", "0.00 0.1\n0.01 0.2\n0.05 0.3\n0.06 0.0\n");
    assert_bad(
        &["record".into(), s(&b)],
        &["uneven.txt", "line", "uniformly spaced"],
        &[],
    );
}

// ---------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------

/// Two valid buildings, no ground motion section and no analysis section.
const BUILDINGS: &str = r#"name = "bad-input"

[[buildings]]
name = "a"
masses = [1.0e5, 1.0e5]
story_stiffness = [1.0e8, 1.0e8]
damping_ratio = 0.05

[[buildings]]
name = "b"
masses = [1.2e5, 1.2e5]
story_stiffness = [1.5e8, 1.5e8]
"#;

const CONTACT: &str = r#"
[[contacts]]
left = "a"
left_floor = 2
right = "b"
right_floor = 2
gap = 0.01
restitution = 0.8
"#;

const GROUND: &str = r#"
[ground_motion]
file = "rec.txt"
pga = 0.3
"#;

const SOLVERS: &str = r#"
[analysis]
duration = 0.5

[momentum]
modes = 2

[gap_element]
stiffness = 1.0e9
law = "linear"
integrator = "newmark"
time_step = 0.001
tolerance = 1.0e-6
"#;

const RECORD: &str = "0.00 0.0\n0.01 0.1\n0.02 -0.2\n0.03 0.05\n0.04 0.0\n";

fn base_scene() -> String {
    format!("{BUILDINGS}{CONTACT}{GROUND}{SOLVERS}")
}

fn run_args(scene: &Path, json: &Path, hist: &Path, sets: &[&str]) -> Vec<String> {
    let mut a = vec![
        "run".to_string(),
        s(scene),
        "--method".into(),
        "gap".into(),
        "--out".into(),
        s(json),
        "--history".into(),
        s(hist),
    ];
    for x in sets {
        a.push("--set".into());
        a.push(x.to_string());
    }
    a
}

/// `text` with `from` replaced by `to` (which must occur exactly once).
#[track_caller]
fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from:?} in the base scene");
    text.replacen(from, to, 1)
}

/// Writes `text` as `scene.toml` next to a valid record and checks the contract through
/// `pound run` (with `--out` and `--history`), `pound modes` and `pound export opensees`.
#[track_caller]
fn scene_case(text: &str, sets: &[&str], expect: &[&str]) {
    let d = TempDir::new("scene");
    d.write("rec.txt", RECORD);
    let scene = d.write("scene.toml", text);
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    let mut parts = Vec::new();
    if !expect.iter().any(|e| e.starts_with("--set")) {
        parts.push("scene.toml");
    }
    parts.extend_from_slice(expect);
    assert_bad(
        &run_args(&scene, &json, &hist, sets),
        &parts,
        &[&json, &hist],
    );

    let mut modes = vec!["modes".to_string(), s(&scene), "--json".into()];
    let mut export = vec!["export".to_string(), "opensees".into(), s(&scene)];
    for x in sets {
        for v in [&mut modes, &mut export] {
            v.push("--set".into());
            v.push(x.to_string());
        }
    }
    assert_bad(&modes, &parts, &[]);
    assert_bad(&export, &parts, &[]);
}

#[test]
fn scene_valid_baseline() {
    // The base scene of the catalogue is valid: each case below breaks one thing.
    let d = TempDir::new("good-scene");
    d.write("rec.txt", RECORD);
    let scene = d.write("scene.toml", &base_scene());
    let out = pound(&["modes".into(), s(&scene)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for set in [
        "contacts.0.gap=0",
        "contacts.0.restitution=0",
        "contacts.0.restitution=1",
        "gap_element.tolerance=0.09",
    ] {
        let out = pound(&["modes".into(), s(&scene), "--set".into(), set.into()]);
        assert!(
            out.status.success(),
            "--set {set}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn scene_toml_syntax_error() {
    let text = edit(&base_scene(), "name = \"a\"", "name = \"a");
    scene_case(&text, &[], &["line 4", "TOML parse error"]);
    let text = edit(&base_scene(), "gap = 0.01", "gap = ");
    scene_case(&text, &[], &["line ", "TOML parse error"]);
}

#[test]
fn scene_unknown_keys() {
    let base = base_scene();
    let cases = [
        (
            edit(&base, "name = \"bad-input\"", "nmae = \"bad-input\""),
            "nmae",
            "line 1",
        ),
        (
            edit(&base, "damping_ratio = 0.05", "damping = 0.05"),
            "damping",
            "line 7",
        ),
        (edit(&base, "gap = 0.01", "gapp = 0.01"), "gapp", "line 19"),
        (edit(&base, "pga = 0.3", "pgaa = 0.3"), "pgaa", "line 24"),
        (
            edit(&base, "duration = 0.5", "durration = 0.5"),
            "durration",
            "line 27",
        ),
        (edit(&base, "modes = 2", "mode = 2"), "mode", "line 30"),
        (
            edit(&base, "time_step = 0.001", "timestep = 0.001"),
            "timestep",
            "line 36",
        ),
        (format!("{base}\n[solver]\nx = 1\n"), "solver", "line 39"),
    ];
    for (text, key, line) in &cases {
        scene_case(text, &[], &[&format!("`{key}`"), line, "expected one of"]);
    }
    // Through --set: the key is named with the table it landed in.
    scene_case(
        &base,
        &["gap_element.stifness=1e9"],
        &["`stifness`", "gap_element"],
    );
    scene_case(&base, &["buildings.0.mas=1"], &["`mas`", "buildings"]);
}

#[test]
fn scene_missing_fields() {
    let base = base_scene();
    let cases: Vec<(String, &[&str])> = vec![
        (
            edit(&base, "masses = [1.0e5, 1.0e5]\n", ""),
            &["buildings[0].masses", "missing"],
        ),
        (
            edit(&base, "story_stiffness = [1.5e8, 1.5e8]\n", ""),
            &["buildings[1].story_stiffness", "missing"],
        ),
        (edit(&base, "name = \"a\"\n", ""), &["missing field `name`"]),
        (edit(&base, "gap = 0.01\n", ""), &["missing field `gap`"]),
        (edit(&base, "left = \"a\"\n", ""), &["missing field `left`"]),
        (
            edit(&base, "right_floor = 2\n", ""),
            &["missing field `right_floor`"],
        ),
        (
            edit(&base, "file = \"rec.txt\"\n", ""),
            &["missing field `file`"],
        ),
        (
            "name = \"nothing\"\n".to_string(),
            &["missing field `buildings`"],
        ),
    ];
    for (text, expect) in &cases {
        scene_case(text, &[], expect);
    }
    // Neither a record nor a duration: an analysis (run, export) is refused naming the key;
    // `pound modes` reads the structure alone and answers.
    let d = TempDir::new("scene-no-duration");
    let scene = d.write("scene.toml", &format!("{BUILDINGS}{CONTACT}"));
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    let parts = ["scene.toml", "analysis.duration", "missing"];
    assert_bad(
        &run_args(&scene, &json, &hist, &[]),
        &parts,
        &[&json, &hist],
    );
    assert_bad(
        &["export".to_string(), "opensees".into(), s(&scene)],
        &parts,
        &[],
    );
    let out = pound(&["modes".into(), s(&scene)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn scene_non_positive_or_non_finite_masses_and_stiffnesses() {
    let base = base_scene();
    for (value, shown) in [
        ("0.0", "0"),
        ("-1.0e5", "-100000"),
        ("nan", "NaN"),
        ("inf", "inf"),
    ] {
        let text = edit(
            &base,
            "masses = [1.2e5, 1.2e5]",
            &format!("masses = [1.2e5, {value}]"),
        );
        scene_case(
            &text,
            &[],
            &["buildings[1].masses[1]", shown, "finite mass > 0"],
        );
        let text = edit(
            &base,
            "story_stiffness = [1.0e8, 1.0e8]",
            &format!("story_stiffness = [{value}, 1.0e8]"),
        );
        scene_case(
            &text,
            &[],
            &["buildings[0].story_stiffness[0]", shown, "> 0"],
        );
    }
    // The shorthands too.
    let short = edit(
        &base,
        "masses = [1.0e5, 1.0e5]\nstory_stiffness = [1.0e8, 1.0e8]",
        "stories = 2\nmass = -1.0\nstory_stiffness = 1.0e8",
    );
    scene_case(&short, &[], &["buildings[0].mass`", "> 0"]);
    let short = edit(
        &base,
        "masses = [1.0e5, 1.0e5]\nstory_stiffness = [1.0e8, 1.0e8]",
        "stories = 2\nmass = 1.0e5\nstory_stiffness = 0.0",
    );
    scene_case(&short, &[], &["buildings[0].story_stiffness`", "> 0"]);
    let short = edit(
        &base,
        "masses = [1.0e5, 1.0e5]\nstory_stiffness = [1.0e8, 1.0e8]",
        "stories = 0\nmass = 1.0e5\nstory_stiffness = 1.0e8",
    );
    scene_case(&short, &[], &["buildings[0].stories", "1 ..="]);
    // Through --set, and the damping ratio.
    scene_case(
        &base,
        &["buildings.0.masses.0=0"],
        &["buildings[0].masses[0]", "> 0"],
    );
    scene_case(
        &base,
        &["buildings.0.damping_ratio=1.0"],
        &["buildings[0]", "damping_ratio", "< 1"],
    );
    scene_case(
        &base,
        &["buildings.0.damping_ratio=-0.1"],
        &["buildings[0]", "damping_ratio"],
    );
}

#[test]
fn scene_array_lengths_that_disagree() {
    let base = base_scene();
    let text = edit(
        &base,
        "story_stiffness = [1.0e8, 1.0e8]",
        "story_stiffness = [1.0e8]",
    );
    scene_case(
        &text,
        &[],
        &["buildings[0].story_stiffness", "has 1 value,", "expected 2"],
    );
    let text = edit(
        &base,
        "story_stiffness = [1.5e8, 1.5e8]",
        "story_stiffness = [1.5e8, 1.5e8, 1.5e8]",
    );
    scene_case(
        &text,
        &[],
        &["buildings[1].story_stiffness", "3 values", "expected 2"],
    );
    scene_case(
        &base,
        &["buildings.0.initial_displacement=[0.0]"],
        &["buildings[0]", "initial_displacement", "expected 2"],
    );
    scene_case(
        &base,
        &["buildings.1.initial_velocity=[0.0, 0.0, 0.0]"],
        &["buildings[1]", "initial_velocity", "expected 2"],
    );
    scene_case(
        &base,
        &["buildings.0.masses=[]"],
        &["buildings[0].masses", "empty"],
    );
}

#[test]
fn scene_with_more_floors_than_a_building_may_have() {
    // An explicit list is capped as `stories = N` is (10 000 floors took minutes in the
    // eigen-solver with no message).
    let masses = vec!["1.0e5"; 1001].join(", ");
    let text = format!(
        "name = \"tall\"\n[[buildings]]\nname = \"a\"\nmasses = [{masses}]\nstory_stiffness = 1.0e8\n"
    );
    scene_case(
        &text,
        &[],
        &["buildings[0].masses", "1001 masses", "at most 1000 floors"],
    );
}

/// An output that is one of the run's inputs is refused (exit 2) before anything runs, the
/// input left as it was, through a hard or symbolic link too; an output that cannot be
/// written is refused (exit 1) before the analysis runs, not after it: with the adaptive
/// integrator and a budget of 50 steps (enough to start, not to finish) the analysis itself
/// fails (exit 3).
#[test]
fn outputs_that_are_inputs_or_cannot_be_written_are_refused_before_the_run() {
    let d = TempDir::new("out-in");
    let rec = d.write("rec.txt", RECORD);
    let text = base_scene();
    let scene = d.write("scene.toml", &text);
    let alias = d.path("alias.toml");
    std::fs::hard_link(&scene, &alias).unwrap();
    let link = d.path("link.txt");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&rec, &link).unwrap();
    #[cfg(not(unix))]
    std::fs::hard_link(&rec, &link).unwrap();
    let run = |flag: &str, out: &Path| {
        vec![
            "run".to_string(),
            s(&scene),
            "--method".into(),
            "gap".into(),
            flag.into(),
            s(out),
        ]
    };
    for (args, expect) in [
        (run("--out", &scene), &["--out", "is the scene file"][..]),
        (run("--out", &alias), &["--out", "is the scene file"][..]),
        (
            run("--history", &rec),
            &["--history", "is the scene's record"][..],
        ),
        (run("--out", &link), &["--out", "is the scene's record"][..]),
        (
            vec![
                "export".to_string(),
                "opensees".into(),
                s(&scene),
                "--out".into(),
                s(&scene),
            ],
            &["--out", "is the scene file"][..],
        ),
        (
            vec!["spectrum".to_string(), s(&rec), "--out".into(), s(&rec)],
            &["--out", "is the record"][..],
        ),
    ] {
        assert_bad(&args, expect, &[]);
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), text);
        assert_eq!(std::fs::read_to_string(&rec).unwrap(), RECORD);
    }

    // Cannot be written: below a file, or an existing read-only file (refused as such even
    // for root, who may write anything).
    let file = d.write("afile", "");
    let ro = d.write("ro.json", "kept");
    let mut perm = std::fs::metadata(&ro).unwrap().permissions();
    perm.set_readonly(true);
    std::fs::set_permissions(&ro, perm).unwrap();
    let budget = [
        "--set".to_string(),
        "gap_element.integrator=\"adaptive\"".into(),
        "--set".into(),
        "analysis.max_steps=50".into(),
    ];
    let mut fails = run("--out", &d.path("r.json"));
    fails.extend(budget.iter().cloned());
    let o = pound(&fails);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "the analysis alone fails: {err}");
    // A solver that cannot go on says when, why and in what state.
    assert!(
        err.contains("step budget exhausted at t = ")
            && err.contains("next step ")
            && err.contains("closed contacts: []"),
        "{err}"
    );
    for (flag, out, expect) in [
        (
            "--out",
            file.join("r.json"),
            "afile is a file, not a folder",
        ),
        (
            "--history",
            file.join("h.csv"),
            "afile is a file, not a folder",
        ),
        ("--out", ro.clone(), "read-only; it is not replaced"),
    ] {
        let mut args = run(flag, &out);
        args.extend(budget.iter().cloned());
        let o = pound(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(expect), "{err}");
        assert!(!err.contains("step budget"), "checked after the run: {err}");
    }
    assert_eq!(std::fs::read_to_string(&ro).unwrap(), "kept");
    let names: Vec<_> = std::fs::read_dir(&d.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names
            .iter()
            .any(|n| n.contains(".probe-") || n.contains(".tmp-")),
        "{names:?}"
    );
}

#[test]
fn scene_floors_out_of_range() {
    let base = base_scene();
    for (set, key) in [
        ("contacts.0.left_floor=3", "contacts[0].left_floor"),
        ("contacts.0.left_floor=0", "contacts[0].left_floor"),
        ("contacts.0.right_floor=-1", "contacts[0].right_floor"),
        ("contacts.0.right_floor=99", "contacts[0].right_floor"),
    ] {
        scene_case(&base, &[set], &[key, "out of range", "floors 1 … 2"]);
    }
}

#[test]
fn scene_contact_buildings() {
    let base = base_scene();
    scene_case(
        &edit(&base, "left = \"a\"", "left = \"c\""),
        &[],
        &["contacts[0].left", "no building named `c`", "a, b"],
    );
    scene_case(
        &base,
        &["contacts.0.right=nobody"],
        &["contacts[0].right", "`nobody`"],
    );
    scene_case(
        &edit(&base, "right = \"b\"", "right = \"a\""),
        &[],
        &["contacts[0].right", "two different buildings", "`a`"],
    );
    scene_case(
        &edit(&base, "name = \"b\"", "name = \"a\""),
        &[],
        &["buildings[1].name", "twice"],
    );
}

#[test]
fn scene_gap_and_restitution() {
    let base = base_scene();
    scene_case(
        &edit(&base, "gap = 0.01", "gap = -0.01"),
        &[],
        &["contacts[0].gap", "-0.01", ">= 0"],
    );
    scene_case(&base, &["contacts.0.gap=nan"], &["contacts[0].gap", ">= 0"]);
    scene_case(
        &base,
        &["contacts.0.gap=inf"],
        &["contacts[0].gap", "finite"],
    );
    for cr in ["1.5", "-0.2", "nan"] {
        scene_case(
            &base,
            &[&format!("contacts.0.restitution={cr}")],
            &["contacts[0].restitution", "[0, 1]"],
        );
    }
}

#[test]
fn scene_ground_motion_scaling() {
    let base = base_scene();
    scene_case(
        &edit(&base, "pga = 0.3", "pga = 0.3\nscale = 2.0"),
        &[],
        &["ground_motion.pga", "`pga` or `scale`, not both"],
    );
    for pga in ["0", "-0.3", "nan", "inf"] {
        scene_case(
            &edit(&base, "pga = 0.3", &format!("pga = {pga}")),
            &[],
            &["ground_motion.pga", "> 0"],
        );
    }
    scene_case(
        &edit(&base, "pga = 0.3", "scale = inf"),
        &[],
        &["ground_motion.scale", "finite"],
    );
    scene_case(
        &edit(&base, "pga = 0.3", "scale = 0.0"),
        &[],
        &["ground_motion.scale", "nonzero"],
    );
    scene_case(
        &edit(&base, "pga = 0.3", "units = \"furlongs\""),
        &[],
        &["ground_motion.units", "furlongs"],
    );
    scene_case(
        &edit(&base, "pga = 0.3", "format = \"csv\""),
        &[],
        &["ground_motion.format", "`csv`"],
    );
}

#[test]
fn scene_record_file_that_does_not_exist() {
    let base = base_scene();
    scene_case(
        &edit(&base, "file = \"rec.txt\"", "file = \"no-such-record.AT2\""),
        &[],
        &["ground_motion.file", "no-such-record.AT2", "does not exist"],
    );
    scene_case(
        &base,
        &["ground_motion.file=elsewhere/rec.txt"],
        &["ground_motion.file", "elsewhere/rec.txt", "does not exist"],
    );
}

#[test]
fn scene_duration() {
    let base = base_scene();
    for d in ["0.0", "-1.0", "nan", "inf"] {
        scene_case(
            &edit(&base, "duration = 0.5", &format!("duration = {d}")),
            &[],
            &["analysis.duration", "> 0"],
        );
    }
    scene_case(
        &base,
        &["analysis.max_steps=0"],
        &["analysis.max_steps", ">= 1"],
    );
    scene_case(
        &base,
        &["analysis.max_impact_rate=0"],
        &["analysis.max_impact_rate", "> 0"],
    );
}

/// Refused at load, exit 2, for every method: the same floor pair joined twice (either
/// orientation), and floors that start penetrated.
#[test]
fn scene_duplicate_contacts_and_initial_penetration() {
    let base = base_scene();
    scene_case(
        &format!("{base}{CONTACT}"),
        &[],
        &["contacts[1]", "duplicate contact", "contacts[0]"],
    );
    let flipped = CONTACT
        .replace("left = \"a\"", "left = \"x\"")
        .replace("right = \"b\"", "right = \"a\"")
        .replace("left = \"x\"", "left = \"b\"");
    scene_case(
        &format!("{base}{flipped}"),
        &[],
        &["contacts[1]", "duplicate contact"],
    );
    scene_case(
        &base,
        &["buildings.0.initial_displacement=[0.0, 0.02]"],
        &["contacts[0]", "penetrated by 1.000000e-2 m"],
    );
}

/// Scenes that would exhaust memory or time are refused before anything is allocated,
/// with exit 2 and the reason, and leave no output: durations whose step count exceeds
/// `analysis.max_steps` (1e9 s aborted on allocation, 1e300 s panicked), and a wall-like
/// story stiffness for the momentum method and the explicit gap integrator.
#[test]
fn hostile_scenes_are_refused_before_running() {
    let d = TempDir::new("hostile");
    d.write("rec.txt", RECORD);
    let scene = d.write("scene.toml", &base_scene());
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    for (method, sets, expect) in [
        (
            "momentum",
            vec!["analysis.duration=1e9"],
            "analysis.max_steps",
        ),
        (
            "momentum",
            vec!["analysis.duration=1e300"],
            "analysis.max_steps",
        ),
        ("gap", vec!["analysis.duration=1e300"], "analysis.max_steps"),
        (
            "gap",
            vec!["analysis.duration=1e9", "gap_element.integrator=adaptive"],
            "analysis.max_steps",
        ),
        (
            "momentum",
            vec!["buildings.1.story_stiffness=[1e22, 1e22]"],
            "momentum.modes",
        ),
        (
            "gap",
            vec![
                "buildings.1.story_stiffness=[1e22, 1e22]",
                "gap_element.integrator=adaptive",
            ],
            "newmark",
        ),
    ] {
        let mut a = run_args(&scene, &json, &hist, &sets);
        a[3] = method.into();
        assert_bad(&a, &["cannot be run", expect], &[&json, &hist]);
    }
}

#[test]
fn threads_beyond_the_limit_are_refused() {
    let d = TempDir::new("threads");
    let out = d.path("results");
    assert_bad(
        &[
            "studies".into(),
            "run".into(),
            "paper".into(),
            "--threads".into(),
            "100000".into(),
            "--out".into(),
            s(&out),
        ],
        &["--threads 100000", "at most 1024"],
        &[&out],
    );
}

/// `studies run` / `studies merge` arguments that cannot be used: exit 2 before anything is
/// written (a typo next to --all, a missing studies folder, a folder given as a record,
/// study names swallowed by --records, merge folders that are missing, hold no manifests, or
/// lack a shard's cases).
#[test]
fn studies_arguments_that_cannot_be_used_are_refused() {
    let d = TempDir::new("studyargs");
    let out = d.path("results");
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let studies = format!("{root}/studies");
    let rec = format!("{root}/data/ground-motions/RSN752_LOMAP_CAP000.AT2");
    let recdir = format!("{root}/data/ground-motions");
    let o = s(&out);
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec![
                "studies",
                "run",
                "--all",
                "papr",
                "--studies-dir",
                &studies,
                "--out",
                &o,
            ],
            vec!["unknown study `papr`"],
        ),
        (
            vec![
                "studies",
                "run",
                "paper",
                "--studies-dir",
                "/nonexistent/studies",
                "--out",
                &o,
            ],
            vec!["--studies-dir /nonexistent/studies", "not a folder"],
        ),
        (
            vec![
                "studies",
                "run",
                "gap",
                "--studies-dir",
                &studies,
                "--records",
                &recdir,
                "--out",
                &o,
            ],
            vec!["is a folder", "*.AT2"],
        ),
        (
            vec![
                "studies",
                "run",
                "--studies-dir",
                &studies,
                "--out",
                &o,
                "--records",
                &rec,
                "gap",
            ],
            vec!["name the studies before --records"],
        ),
        (
            vec!["studies", "merge", "/nonexistent/shard", "--out", &o],
            vec!["/nonexistent/shard", "not a folder"],
        ),
    ];
    for (args, expect) in cases {
        let a: Vec<String> = args.iter().map(|x| x.to_string()).collect();
        assert_bad(&a, &expect, &[&out]);
    }
    let empty = d.path("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert_bad(
        &[
            "studies".into(),
            "merge".into(),
            s(&empty),
            "--out".into(),
            o.clone(),
        ],
        &["no study manifests"],
        &[&out],
    );
    // One shard of two: the merge names the missing cases and writes nothing.
    let shard = d.path("shard1");
    let r = common::pound(&[
        "studies",
        "run",
        "paper",
        "--shard",
        "1/2",
        "--studies-dir",
        &studies,
        "--out",
        &s(&shard),
    ]);
    assert_eq!(r.status.code(), Some(0));
    assert_bad(
        &[
            "studies".into(),
            "merge".into(),
            s(&shard),
            "--studies-dir".into(),
            studies.clone(),
            "--out".into(),
            o.clone(),
        ],
        &["study `paper`", "missing ids"],
        &[&out],
    );
}

/// Every file under `dir` with its bytes (paths relative to `dir`).
fn snapshot(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut m = std::collections::BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                m.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    m
}

/// `studies merge` with a truncated case file in a shard (and no other copy of it) stops
/// before anything is written: exit 2 naming the file, no output folder, and the first shard
/// (the default output) left as it was. It used to copy the other case files and the
/// manifest first. A damaged file in the output with a good copy in a shard is replaced.
#[test]
fn merge_with_a_damaged_case_file_writes_nothing() {
    let d = TempDir::new("merge-damaged");
    let studies = concat!(env!("CARGO_MANIFEST_DIR"), "/../../studies");
    let (s1, s2) = (d.path("s1"), d.path("s2"));
    for (i, shard) in [(1, &s1), (2, &s2)] {
        let r = pound(&[
            "studies".to_string(),
            "run".into(),
            "paper".into(),
            "--quick".into(),
            "--shard".into(),
            format!("{i}/2"),
            "--studies-dir".into(),
            studies.into(),
            "--out".into(),
            s(shard),
        ]);
        assert_eq!(
            r.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&r.stderr)
        );
    }
    let merge = |out: Option<&Path>| {
        let mut a = vec![
            "studies".to_string(),
            "merge".into(),
            s(&s1),
            s(&s2),
            "--studies-dir".into(),
            studies.into(),
        ];
        if let Some(o) = out {
            a.extend(["--out".into(), s(o)]);
        }
        a
    };
    // The intact shards merge (so the refusal below is the damaged file's).
    let r = pound(&merge(Some(&d.path("whole"))));
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let mut cases: Vec<_> = std::fs::read_dir(s2.join("paper/cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    cases.sort();
    let case = &cases[0];
    let text = std::fs::read(case).unwrap();
    std::fs::write(case, &text[..text.len() / 2]).unwrap();
    let name = case.file_name().unwrap().to_str().unwrap();
    let shard1 = snapshot(&s1);
    let out = d.path("merged");
    assert_bad(
        &merge(Some(&out)),
        &[&format!("s2/paper/cases/{name}"), "not a usable case file"],
        &[&out],
    );
    // Without --out the first shard is the output: nothing in it changes.
    assert_bad(&merge(None), &[name, "not a usable case file"], &[]);
    assert!(snapshot(&s1) == shard1, "the first shard was changed");
    // A truncated manifest is bad input too (it was exit 1), naming the file.
    std::fs::write(case, &text).unwrap();
    let manifest = s1.join("paper/manifest.json");
    let m = std::fs::read(&manifest).unwrap();
    std::fs::write(&manifest, &m[..m.len() / 2]).unwrap();
    assert_bad(
        &merge(Some(&out)),
        &["s1/paper/manifest.json", "not a usable study manifest"],
        &[&out],
    );
    // A damaged case file in the output with a good copy in a shard: the merge uses the
    // copy (it replaces the damaged file), says so, and gives the output it gave before.
    std::fs::write(&manifest, &m).unwrap();
    let whole = d.path("whole");
    let before = snapshot(&whole);
    let damaged = whole.join("paper/cases").join(name);
    std::fs::write(&damaged, &text[..text.len() / 3]).unwrap();
    let r = pound(&merge(Some(&whole)));
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(0), "{err}");
    assert!(
        err.contains(&format!(
            "whole/paper/cases/{name} is not a usable case file"
        )) && err.contains(&format!(
            "replaced by {}",
            s2.join("paper/cases").join(name).display()
        )),
        "{err}"
    );
    assert!(snapshot(&whole) == before, "the repaired output differs");
}

/// `--out` and `--history` naming one file (the JSON would replace the history) are refused
/// before the analysis runs.
#[test]
fn out_and_history_on_one_file_are_refused() {
    let d = TempDir::new("samefile");
    let scene = d.write("scene.toml", &base_scene());
    let f = d.path("both.out");
    let mut a = run_args(&scene, &f, &f, &[]);
    assert_bad(&a, &["--out and --history are the same file"], &[&f]);
    // The same file by another spelling.
    let other = d.path("x/../both.out");
    std::fs::create_dir_all(d.path("x")).unwrap();
    a = run_args(&scene, &f, &other, &[]);
    assert_bad(&a, &["the same file"], &[&f]);
}

/// `--history-dt` must be a positive, finite number of seconds, and needs `--history`:
/// refused before the analysis runs, nothing written.
#[test]
fn history_dt_must_be_positive_and_needs_a_history() {
    let d = TempDir::new("historydt");
    let scene = d.write("scene.toml", &base_scene());
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    for (v, joined) in [
        ("0", true),
        ("-0.01", true),
        ("-0.01", false),
        ("nan", true),
        ("inf", true),
        ("1e400", true),
    ] {
        let mut a = run_args(&scene, &json, &hist, &[]);
        if joined {
            a.push(format!("--history-dt={v}"));
        } else {
            a.extend(["--history-dt".to_string(), v.to_string()]);
        }
        assert_bad(
            &a,
            &["--history-dt", "expected a finite number of seconds > 0"],
            &[&json, &hist],
        );
    }
    let a: Vec<String> = ["run", &s(&scene), "--method", "gap", "--history-dt", "0.1"]
        .map(String::from)
        .to_vec();
    assert_bad(&a, &["--history"], &[&json, &hist]);
}

/// `--records` with a study that runs one fixed scene and record (the paper's example, the
/// cost and stability scenes) is refused, naming the study and those that take records,
/// before anything is written; the record-based study named beside it does not run either.
#[test]
fn records_for_a_fixed_record_study_are_refused() {
    let d = TempDir::new("fixedrecords");
    let out = d.path("results");
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
    );
    for (names, expect) in [
        (&["paper"][..], "`paper` runs"),
        (&["gap", "cost", "stability"][..], "`cost`, `stability` run"),
    ] {
        let mut a: Vec<String> = vec!["studies".into(), "run".into()];
        a.extend(names.iter().map(|n| n.to_string()));
        a.extend(["--records".into(), rec.into(), "--quick".into()]);
        a.extend(["--out".into(), s(&out)]);
        assert_bad(
            &a,
            &["--records", expect, "applies to stiffness", "robustness"],
            &[&out],
        );
    }
}

#[test]
fn scene_solver_options_out_of_range() {
    let base = base_scene();
    let cases: &[(&str, &str, &[&str])] = &[
        ("modes = 2", "modes = 0", &["momentum.modes", ">= 1"]),
        ("modes = 2", "modes = -3", &["momentum.modes", ">= 1"]),
        (
            "stiffness = 1.0e9",
            "stiffness = 0.0",
            &["gap_element.stiffness", "> 0"],
        ),
        (
            "stiffness = 1.0e9",
            "stiffness = -1.0e9",
            &["gap_element.stiffness", "> 0"],
        ),
        (
            "stiffness = 1.0e9",
            "stiffness = nan",
            &["gap_element.stiffness", "> 0"],
        ),
        (
            "tolerance = 1.0e-6",
            "tolerance = 0.1",
            &["gap_element.tolerance", "(0, 0.1)"],
        ),
        (
            "tolerance = 1.0e-6",
            "tolerance = 0.5",
            &["gap_element.tolerance", "(0, 0.1)"],
        ),
        (
            "tolerance = 1.0e-6",
            "tolerance = 0.0",
            &["gap_element.tolerance", "(0, 0.1)"],
        ),
        (
            "time_step = 0.001",
            "time_step = 0.0",
            &["gap_element.time_step", "> 0"],
        ),
        (
            "time_step = 0.001",
            "time_step = -0.001",
            &["gap_element.time_step", "> 0"],
        ),
        (
            "time_step = 0.001",
            "time_step = 10.0",
            &["gap_element.time_step", "duration"],
        ),
        (
            "law = \"linear\"",
            "law = \"hertz\"",
            &[
                "`hertz`",
                "line 34",
                "law = ",
                "expected one of",
                "kelvin-voigt",
            ],
        ),
        (
            "integrator = \"newmark\"",
            "integrator = \"rk4\"",
            &[
                "`rk4`",
                "line 35",
                "integrator = ",
                "expected `adaptive` or `newmark`",
            ],
        ),
        (
            "modes = 2",
            "modes = 2\nimpulse = \"elastic\"",
            &[
                "`elastic`",
                "line 31",
                "impulse = ",
                "expected `consistent` or `paper`",
            ],
        ),
        (
            "modes = 2",
            "modes = 2\ncapture_velocity = -1.0",
            &["momentum.capture_velocity", ">= 0"],
        ),
    ];
    for (from, to, expect) in cases {
        scene_case(&edit(&base, from, to), &[], expect);
    }
    // The same through --set.
    scene_case(&base, &["momentum.modes=0"], &["momentum.modes", ">= 1"]);
    scene_case(
        &base,
        &["gap_element.stiffness=-5"],
        &["gap_element.stiffness", "> 0"],
    );
    scene_case(
        &base,
        &["gap_element.tolerance=0.1"],
        &["gap_element.tolerance"],
    );
    scene_case(
        &base,
        &["gap_element.time_step=0"],
        &["gap_element.time_step"],
    );
    // A wrong type names the key too.
    scene_case(&base, &["momentum.modes=ten"], &["momentum.modes"]);
}

#[test]
fn scene_bad_set_expressions() {
    let base = base_scene();
    let cases: &[(&str, &[&str])] = &[
        (
            "contacts.5.gap=0.05",
            &[
                "--set contacts.5.gap=0.05",
                "index 5 is out of range",
                "1 entry (index 0)",
            ],
        ),
        (
            "buildings.2.masses.0=1",
            &["--set buildings.2.masses.0=1", "out of range", "2 entries"],
        ),
        (
            "buildings.0.masses.7=1",
            &["--set buildings.0.masses.7=1", "out of range"],
        ),
        ("contacts.0.gap", &["--set contacts.0.gap", "PATH=VALUE"]),
        (
            "contacts.first.gap=1",
            &["--set contacts.first.gap=1", "numeric index"],
        ),
        ("=0.05", &["--set =0.05", "empty"]),
        (
            "contacts.0.gap.x=1",
            &["--set contacts.0.gap.x=1", "not a table or array"],
        ),
    ];
    for (set, expect) in cases {
        scene_case(&base, &[set], expect);
    }
}

#[test]
fn scene_file_that_does_not_exist() {
    let d = TempDir::new("no-scene");
    let scene = d.path("absent.toml");
    let (json, hist) = (d.path("out.json"), d.path("history.csv"));
    assert_bad(
        &run_args(&scene, &json, &hist, &[]),
        &["absent.toml", "cannot read"],
        &[&json, &hist],
    );
}

#[test]
fn usage_errors_exit_2() {
    // clap's own errors follow the same exit code.
    let d = TempDir::new("usage");
    d.write("rec.txt", RECORD);
    let scene = d.write("scene.toml", &base_scene());
    let json = d.path("out.json");
    let out = pound(&[
        "run".into(),
        s(&scene),
        "--method".into(),
        "teleport".into(),
        "--out".into(),
        s(&json),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("teleport"));
    assert!(!json.exists());
}

/// A study scene without two buildings joined by a contact is refused before anything runs
/// (it used to panic in the gap study), with exit 2 naming the study; nothing is written.
#[test]
fn study_scene_without_a_pair_is_refused() {
    let d = TempDir::new("study-scene");
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
    );
    d.write(
        "one.toml",
        &format!(
            "name = \"one\"\n[[buildings]]\nname = \"a\"\nstories = 3\nmass = 1.0e6\nstory_stiffness = 1.0e9\ndamping_ratio = 0.05\n[ground_motion]\nfile = \"{rec}\"\npga = 0.4\n"
        ),
    );
    let def = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../studies/gap.toml"
    ))
    .unwrap()
    .replace("scene = \"paper/scene.toml\"", "scene = \"one.toml\"")
    // The definition's record paths are relative to the repository's studies/ folder.
    .replace(
        "\"../data/",
        concat!("\"", env!("CARGO_MANIFEST_DIR"), "/../../data/"),
    );
    d.write("gap.toml", &def);
    let out = d.path("results");
    assert_bad(
        &[
            "studies".into(),
            "run".into(),
            "gap".into(),
            "--quick".into(),
            "--studies-dir".into(),
            s(&d.0),
            "--out".into(),
            s(&out),
        ],
        &[
            "study `gap`",
            "two buildings joined by a contact",
            "1 building and",
        ],
        &[&out],
    );
}

/// A `record_dirs` folder that does not exist is bad input: exit 2 naming the key, the
/// folder and the definition file; nothing is written.
#[test]
fn study_record_dir_missing_is_refused() {
    let d = TempDir::new("study-record-dirs");
    let def = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../studies/modes.toml"
    ))
    .unwrap()
    .replace(
        "record_dirs = [\"../data/ground-motions/near-field\"]",
        "record_dirs = [\"no-such-folder\"]",
    );
    assert!(def.contains("no-such-folder"));
    d.write("modes.toml", &def);
    let out = d.path("results");
    assert_bad(
        &[
            "studies".into(),
            "run".into(),
            "modes".into(),
            "--quick".into(),
            "--studies-dir".into(),
            s(&d.0),
            "--out".into(),
            s(&out),
        ],
        &[
            "study `modes`",
            "modes.toml",
            "record_dirs",
            "no-such-folder",
        ],
        &[&out],
    );
    // A record table that cannot be read: refused the same way, before any case runs.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../");
    let def = std::fs::read_to_string(format!("{root}studies/modes.toml"))
        .unwrap()
        .replace("\"../data/", &format!("\"{root}data/"))
        .replace(
            "paper/scene.toml",
            &format!("{root}studies/paper/scene.toml"),
        )
        .replace(
            &format!("record_table = \"{root}data/ground-motions/records.csv\""),
            "record_table = \"missing.csv\"",
        );
    assert!(def.contains("missing.csv"));
    d.write("modes.toml", &def);
    assert_bad(
        &[
            "studies".into(),
            "run".into(),
            "modes".into(),
            "--quick".into(),
            "--studies-dir".into(),
            s(&d.0),
            "--out".into(),
            s(&out),
        ],
        &["study `modes`", "record_table", "missing.csv"],
        &[&out],
    );
}
