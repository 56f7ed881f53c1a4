//! Bad input that used to get a message naming no key, the wrong line or nothing at all (or
//! was accepted): each error names the file, the key or line the user wrote, and what was
//! expected. And every committed scene (and every study's overrides of it) still loads under
//! the new ranges.

mod common;
use common::err_has;
use std::path::{Path, PathBuf};

use structure::ground::{GroundMotion, RecordError, Units};
use structure::scene::{MASS_RANGE, MAX_SPREAD, STIFFNESS_RANGE};
use structure::{Building, Purpose, Scene, SceneError};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn fixtures_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/scenes")
}

fn load(text: &str, overrides: &[&str]) -> Result<Scene, SceneError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_str_with_overrides(text, "scene.toml", &fixtures_dir(), &o)
}

/// One building `a` with the given keys, a free-vibration analysis of 1 s.
fn one(body: &str) -> String {
    format!("[[buildings]]\nname = \"a\"\n{body}\n[analysis]\nduration = 1.0\n")
}

// ---------------------------------------------------------------------------------------
// (a) Extreme stiffness or mass: refused by validation, naming the key
// ---------------------------------------------------------------------------------------

#[test]
fn extreme_stiffness_or_mass_names_the_key_and_the_range() {
    let k_range = format!("[{:e}, {:e}] N/m", STIFFNESS_RANGE.0, STIFFNESS_RANGE.1);
    let m_range = format!("[{:e}, {:e}] kg", MASS_RANGE.0, MASS_RANGE.1);
    let cases: &[(&str, &str, &str)] = &[
        (
            "masses = [1e6, 1e6]\nstory_stiffness = [1e300, 1e9]",
            "key `buildings[0].story_stiffness[0]`: 1e300",
            &k_range,
        ),
        (
            "masses = [1e6, 1e6]\nstory_stiffness = [1e-300, 1e9]",
            "key `buildings[0].story_stiffness[0]`: 1e-300",
            &k_range,
        ),
        (
            "masses = [1e-300, 1e6]\nstory_stiffness = [1e9, 1e9]",
            "key `buildings[0].masses[0]`: 1e-300",
            &m_range,
        ),
        (
            "masses = [1e300, 1e6]\nstory_stiffness = [1e9, 1e9]",
            "key `buildings[0].masses[0]`: 1e300",
            &m_range,
        ),
        (
            "masses = [1e6, 1e6]\nstory_stiffness = 1e30",
            "key `buildings[0].story_stiffness`: 1e30",
            &k_range,
        ),
        (
            "stories = 2\nmass = 1e13\nstory_stiffness = 1e9",
            "key `buildings[0].mass`: 1e13",
            &m_range,
        ),
    ];
    for (body, key, range) in cases {
        err_has(
            load(&one(body), &[]),
            &["scene.toml: ", key, "expected", range],
        );
    }
}

#[test]
fn ill_conditioned_spreads_name_the_key_and_the_bound() {
    let bound = format!("at most {MAX_SPREAD:e}");
    // Stiffnesses within the absolute range whose ratio (1e14) makes the eigenproblem
    // ill-conditioned; masses likewise (ratio 1e13); and the two together (1e7 × 1e6 × 4).
    for (body, key, found) in [
        (
            "masses = [1e6, 1e6]\nstory_stiffness = [1e-2, 1e12]",
            "key `buildings[0].story_stiffness`",
            "ratio 1.000e14",
        ),
        (
            "masses = [1e-2, 1e11]\nstory_stiffness = [1e9, 1e9]",
            "key `buildings[0].masses`",
            "ratio 1.000e13",
        ),
        (
            "masses = [1.0, 1e6]\nstory_stiffness = [1e2, 1e9]",
            "key `buildings[0].story_stiffness`",
            "found 4.000e13",
        ),
    ] {
        err_has(
            load(&one(body), &[]),
            &[key, "ill-conditioned", "floors²", &bound, found],
        );
    }
    // The same spread through `--set`.
    err_has(
        load(
            &one("masses = [1e6, 1e6]\nstory_stiffness = [1e9, 1e9]"),
            &["buildings.0.story_stiffness=[1e-3, 1e9]"],
        ),
        &["key `buildings[0].story_stiffness`", &bound],
    );
}

/// A building built in code past the bounds: the eigen-solver's message says what it found
/// (the eigenvalue, the spreads) and does not claim the stiffness is not positive definite.
#[test]
fn the_eigen_solver_message_says_what_was_found() {
    for (m, k) in [
        (vec![1e6, 1e6], vec![1e-300, 1e9]),
        (vec![1e6, 1e6], vec![1e300, 1e9]),
        (vec![1e-300, 1e6], vec![1e9, 1e9]),
    ] {
        let b = Building::new("a", m, k, 0.05);
        let e = b.modes().expect_err("an ill-conditioned building");
        let msg = e.to_string();
        for p in [
            "building `a`",
            "mode 1 has ω² =",
            "ill-conditioned",
            "ratio",
        ] {
            assert!(msg.contains(p), "{msg:?} should contain {p:?}");
        }
        assert!(!msg.contains("not positive definite"), "{msg}");
    }
}

// ---------------------------------------------------------------------------------------
// (b) A missing record next to a scene given by a bare file name
// ---------------------------------------------------------------------------------------

#[test]
fn a_missing_record_beside_a_bare_scene_name_shows_the_folder() {
    // `scene.toml` has the empty parent `""`: the folder is shown as `.`.
    let text =
        one("masses = [1e6]\nstory_stiffness = [1e9]") + "[ground_motion]\nfile = \"rec.AT2\"\n";
    let r = Scene::from_str_for(&text, "scene.toml", Path::new(""), &[], Purpose::Analysis);
    let msg = err_has(
        r,
        &[
            "key `ground_motion.file`",
            "record file rec.AT2 does not exist",
            "(`rec.AT2` is taken relative to the scene's folder, .",
        ],
    );
    assert!(!msg.contains("folder, )"), "{msg}");
}

// ---------------------------------------------------------------------------------------
// (c) Two-column record times: the line at fault
// ---------------------------------------------------------------------------------------

fn two_column(times: &[&str]) -> RecordError {
    let text: String = times.iter().map(|t| format!("{t} 0.1\n")).collect();
    GroundMotion::from_two_column_str(&text, "rec.txt", Units::G).expect_err("bad times")
}

#[test]
fn two_column_time_errors_name_the_line_at_fault() {
    // An uneven step at line 3: the first step (0.01 s) and the step found (0.04 s).
    let e = two_column(&["0", "0.01", "0.05", "0.06"]);
    assert!(
        matches!(
            e,
            RecordError::NonUniform {
                line: 3,
                prev_line: 2,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    for p in [
        "rec.txt line 3: expected uniformly spaced times",
        "the step from line 2 to line 3 is 0.04",
        "the first step (line 1 to line 2) is 0.01 s",
        "tolerance 2e-8 s",
    ] {
        assert!(msg.contains(p), "{msg:?} should contain {p:?}");
    }
    // A repeated time at line 3.
    let e = two_column(&["0", "0.01", "0.01", "0.02"]);
    assert!(
        matches!(
            e,
            RecordError::TimeNotIncreasing {
                line: 3,
                prev_line: 2,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("rec.txt line 3: expected increasing times: time 0.01 s at line 3 is not after 0.01 s at line 2"),
        "{msg}"
    );
    // A time that decreases at line 3.
    let e = two_column(&["0", "0.02", "0.01"]);
    let msg = e.to_string();
    assert!(
        msg.contains("rec.txt line 3: expected increasing times: time 0.01 s at line 3 is not after 0.02 s at line 2"),
        "{msg}"
    );
    // Comment and blank lines count: the lines are the file's.
    let e = GroundMotion::from_two_column_str(
        "# t a\n0 0\n\n0.01 0\n0.02 0\n0.05 0\n",
        "rec.txt",
        Units::G,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            RecordError::NonUniform {
                line: 6,
                prev_line: 5,
                ..
            }
        ),
        "{e:?}"
    );
}

/// Uniform times are read as before: dt is the mean step, bit for bit, and jitter within
/// 1e-6 of it is accepted.
#[test]
fn uniform_two_column_times_load_as_before() {
    let times = [0.0, 0.01, 0.02, 0.030000001, 0.04];
    let text: String = times.iter().map(|t| format!("{t} 0.1\n")).collect();
    let g = GroundMotion::from_two_column_str(&text, "rec.txt", Units::G).unwrap();
    assert_eq!(g.dt.to_bits(), ((0.04 - 0.0) / 4.0f64).to_bits());
    let p = fixtures_dir().join("pulse_two_column.txt");
    let text = std::fs::read_to_string(&p).unwrap();
    GroundMotion::from_two_column_str(&text, "pulse_two_column.txt", Units::G).unwrap();
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/two_column.txt");
    let text = std::fs::read_to_string(&p).unwrap();
    GroundMotion::from_two_column_str(&text, "two_column.txt", Units::G).unwrap();
}

// ---------------------------------------------------------------------------------------
// (d) A scene that is not UTF-8
// ---------------------------------------------------------------------------------------

#[test]
fn a_non_utf8_scene_names_the_line_and_byte() {
    let dir = std::env::temp_dir().join(format!("pound-input-messages-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s2.toml");
    let mut bytes = b"[[buildings]]\nname = \"a\"\nmasses = [1e6] # caf".to_vec();
    bytes.push(0xE9);
    bytes.extend_from_slice(b"\nstory_stiffness = [1e9]\n");
    std::fs::write(&path, &bytes).unwrap();
    let r = Scene::from_file(&path);
    let _ = std::fs::remove_dir_all(&dir);
    let e = r.expect_err("not UTF-8");
    assert!(
        matches!(
            e,
            SceneError::Encoding {
                line: 3,
                column: 21,
                offset: 45,
                byte: 0xE9,
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("s2.toml line 3, byte 21 (byte offset 45): expected UTF-8 text, found the invalid byte 0xE9"),
        "{msg}"
    );
}

// ---------------------------------------------------------------------------------------
// (e) Calibration inputs: the key the user wrote, with its range
// ---------------------------------------------------------------------------------------

#[test]
fn calibration_errors_name_the_key_written() {
    err_has(
        load(
            &one("stories = 2\nmass = 1e6\ntarget_frequencies_hz = [1e200]\ntop_stiffness_ratio = 0.5"),
            &[],
        ),
        &[
            "key `buildings[0].target_frequencies_hz[0]`: 1e200",
            "expected a frequency in [1e-3, 1e3] Hz",
        ],
    );
    err_has(
        load(
            &one("stories = 2\nmass = 1e6\ntarget_frequencies_hz = [1.0]\ntop_stiffness_ratio = 1e300"),
            &[],
        ),
        &[
            "key `buildings[0].top_stiffness_ratio`: 1e300",
            "in [1e-2, 1e2]",
        ],
    );
    err_has(
        load(
            &one("stories = 2\nmass = 1e6\ntarget_frequencies_hz = [0.5, 1e300]"),
            &[],
        ),
        &[
            "key `buildings[0].target_frequencies_hz[1]`: 1e300",
            "[1e-3, 1e3] Hz",
        ],
    );
    // Frequencies and masses in range whose calibrated stiffness is not.
    let msg = err_has(
        load(
            &one("stories = 400\nmass = 1e12\ntarget_frequencies_hz = [1e3]\ntop_stiffness_ratio = 1.0"),
            &[],
        ),
        &[
            "key `buildings[0].target_frequencies_hz`",
            "the calibration",
            "expected story stiffnesses in [1e-3, 1e24] N/m",
        ],
    );
    assert!(!msg.contains("story_stiffness["), "{msg}");
}

// ---------------------------------------------------------------------------------------
// (f) `dt` with an AT2 record
// ---------------------------------------------------------------------------------------

#[test]
fn dt_with_an_at2_record_names_dt() {
    let base =
        one("masses = [1e6]\nstory_stiffness = [1e9]") + "[ground_motion]\nfile = \"rec.AT2\"\n";
    let msg = err_has(
        load(&(base.clone() + "dt = 0.01\n"), &[]),
        &["key `ground_motion.dt`", "remove `dt`"],
    );
    assert!(!msg.contains("ground_motion.units"), "{msg}");
    err_has(
        load(&(base.clone() + "units = \"g\"\n"), &[]),
        &["key `ground_motion.units`", "remove `units`"],
    );
    err_has(
        load(&(base + "units = \"g\"\ndt = 0.01\n"), &[]),
        &["key `ground_motion.units`", "remove `units` and `dt`"],
    );
}

// ---------------------------------------------------------------------------------------
// (g) `--set` removing a required key
// ---------------------------------------------------------------------------------------

#[test]
fn removing_a_required_key_names_it() {
    let text = one("masses = [1e6]\nstory_stiffness = [1e9]");
    let msg = err_has(
        load(&text, &["buildings="]),
        &["after --set overrides: key `buildings`: missing field `buildings`"],
    );
    assert!(!msg.contains("key `.`"), "{msg}");
    err_has(
        load(&text, &["buildings.0.name="]),
        &["key `buildings[0].name`: missing field `name`"],
    );
}

// ---------------------------------------------------------------------------------------
// (h) Accepted bad input: reference frequencies and building names
// ---------------------------------------------------------------------------------------

#[test]
fn reference_frequencies_must_be_finite_and_positive() {
    let b = |r: &str| {
        one(&format!(
            "masses = [1e6, 1e6]\nstory_stiffness = [1e9, 1e9]\nreference_frequencies_hz = {r}"
        ))
    };
    err_has(
        load(&b("[nan, -1]"), &[]),
        &[
            "key `buildings[0].reference_frequencies_hz[0]`: NaN",
            "finite frequency > 0 (Hz)",
        ],
    );
    err_has(
        load(&b("[1.0, -1]"), &[]),
        &["key `buildings[0].reference_frequencies_hz[1]`: -1", "> 0"],
    );
    err_has(
        load(&b("[1.0, 0.0]"), &[]),
        &["key `buildings[0].reference_frequencies_hz[1]`: 0"],
    );
    load(&b("[1.0, 3.0]"), &[]).expect("positive reference frequencies");
}

#[test]
fn building_names_must_be_non_empty() {
    let b = |name: &str| {
        format!(
            "[[buildings]]\nname = {name}\nmasses = [1e6]\nstory_stiffness = [1e9]\n[analysis]\nduration = 1.0\n"
        )
    };
    err_has(
        load(&b("\"\""), &[]),
        &["key `buildings[0].name`", "non-empty name"],
    );
    err_has(
        load(&b("\"  \""), &[]),
        &["key `buildings[0].name`", "non-empty"],
    );
    // Commas, quotes and newlines are allowed: the --history CSV quotes its header fields
    // and the OpenSees export escapes names (tests in crates/studies).
    for name in ["\"a,b\"", "'a\"b'", "\"a\\nb\""] {
        load(&b(name), &[]).expect("a name the outputs quote");
    }
    load(&b("\"left tower-1 (é)\""), &[]).expect("an ordinary name");
}

// ---------------------------------------------------------------------------------------
// Property: every committed scene, and every study's overrides of its scene, still loads
// ---------------------------------------------------------------------------------------

/// Scene files under `dir` (recursively) whose name starts with `scene` and ends `.toml`.
fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            scene_files(&p, out);
        } else if p
            .file_name()
            .and_then(|f| f.to_str())
            .is_some_and(|f| f.starts_with("scene") && f.ends_with(".toml"))
        {
            out.push(p);
        }
    }
}

#[test]
fn every_committed_scene_and_study_variant_loads() {
    let studies = root().join("studies");
    let mut scenes = Vec::new();
    scene_files(&studies, &mut scenes);
    for f in ["minimal.toml", "shorthand.toml"] {
        scenes.push(fixtures_dir().join(f));
    }
    assert!(scenes.len() >= 4, "{scenes:?}");
    for p in &scenes {
        Scene::from_file(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
    // Each study's scene(s) with each of its variants' overrides.
    let mut loaded = 0;
    for e in std::fs::read_dir(&studies).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("toml") {
            continue;
        }
        let t: toml::Table = toml::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
        let mut sets: Vec<Vec<String>> = vec![vec![]];
        if let Some(toml::Value::Array(vs)) = t.get("variants") {
            for v in vs {
                if let Some(toml::Value::Array(s)) = v.get("set") {
                    sets.push(
                        s.iter()
                            .filter_map(|x| x.as_str().map(String::from))
                            .collect(),
                    );
                }
            }
        }
        for key in ["scene", "roof_only_scene"] {
            let Some(s) = t.get(key).and_then(|v| v.as_str()) else {
                continue;
            };
            for o in &sets {
                Scene::from_file_with_overrides(&studies.join(s), o)
                    .unwrap_or_else(|e| panic!("{} ({key}, {o:?}): {e}", p.display()));
                loaded += 1;
            }
        }
    }
    assert!(loaded >= 13, "{loaded} study scenes loaded");
}

/// A non-positive or non-finite value given by a shorthand (`stories` + `mass`, one
/// `story_stiffness` for every story) is refused under the key as written, not under the
/// expanded `masses[i]` / `story_stiffness[i]` that are not in the file.
#[test]
fn shorthand_values_are_named_as_written() {
    let m = err_has(
        load(&one("stories = 2\nmass = nan\nstory_stiffness = 1e9"), &[]),
        &["key `buildings[0].mass`", "NaN", "> 0"],
    );
    assert!(!m.contains("masses["), "{m}");
    let m = err_has(
        load(&one("stories = 2\nmass = 1e5\nstory_stiffness = -1.0"), &[]),
        &["key `buildings[0].story_stiffness`", "-1", "> 0"],
    );
    assert!(!m.contains("story_stiffness["), "{m}");
    // The lists keep their index.
    err_has(
        load(
            &one("masses = [1e5, 0.0]\nstory_stiffness = [1e9, 1e9]"),
            &[],
        ),
        &["key `buildings[0].masses[1]`", "> 0"],
    );
}

// ---------------------------------------------------------------------------------------
// Values beyond floating point: a record value that overflows in m/s², a scale factor that
// overflows the record, a record path that is a device
// ---------------------------------------------------------------------------------------

/// 1e308 g is finite, 9.8e308 m/s² is not: each reader names the line (it loaded, and the
/// run stopped at 2.56 s with a non-finite state, or a study's cases failed as "singular
/// contact").
#[test]
fn a_record_value_that_overflows_in_si_names_the_line() {
    let at2 = "PEER\nrecord\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=   4, DT=   .0100 SEC\n0.1 0.2\n1e308 0.1\n";
    let e = GroundMotion::from_at2_str(at2, "big.AT2").expect_err("overflow");
    let msg = e.to_string();
    assert!(
        matches!(e, RecordError::Overflow { line: 6, .. })
            && msg.contains("big.AT2 line 6: 1e308 g")
            && msg.contains("m/s^2"),
        "{msg}"
    );
    let e = GroundMotion::from_one_column_str("0.1\n0.2\n-1e308\n", "big.txt", 0.01, Units::G)
        .expect_err("overflow");
    assert!(matches!(e, RecordError::Overflow { line: 3, .. }), "{e}");
    let e = GroundMotion::from_two_column_str("0 0.1\n0.01 1e308\n", "big.txt", Units::G)
        .expect_err("overflow");
    assert!(matches!(e, RecordError::Overflow { line: 2, .. }), "{e}");
    // In m/s² the same number is finite, but its slope from 0.1 over 0.01 s (1e310 m/s³) is
    // not: the record is refused as a whole (`Unbounded`), not at a line; 1e305 m/s² loads.
    let e =
        GroundMotion::from_one_column_str("0.1\n1e308\n", "ok.txt", 0.01, Units::MetersPerSecond2)
            .expect_err("slope");
    assert!(matches!(e, RecordError::Unbounded { .. }), "{e}");
    let g =
        GroundMotion::from_one_column_str("0.1\n1e305\n", "ok.txt", 0.01, Units::MetersPerSecond2)
            .unwrap();
    assert_eq!(g.accel[1], 1e305);
}

/// A `scale` or `pga` that takes the record beyond floating point is refused with its key
/// and the sample or the record's PGA (it stopped the solver with a non-finite state at
/// 0.32 s).
#[test]
fn a_scale_that_overflows_the_record_names_the_key() {
    let text = one("masses = [1e6]\nstory_stiffness = [1e9]")
        + "[ground_motion]\nfile = \"pulse.txt\"\nformat = \"one-column\"\ndt = 0.01\nunits = \"g\"\n";
    err_has(
        load(&format!("{text}scale = 1e308\n"), &[]),
        &[
            "key `ground_motion.scale`",
            "1e308 scales sample 2 of",
            "pulse.txt",
            "beyond the range of floating point",
        ],
    );
    // With `pga` the factor itself overflows (1e308 g × G): said so, with the record's PGA
    // (it named sample 1 as overflowing, whatever its value).
    err_has(
        load(&format!("{text}pga = 1e308\n"), &[]),
        &[
            "key `ground_motion.pga`",
            "1e308 g: the factor from the record's PGA (1e0 g) to it is beyond the range of \
             floating point",
        ],
    );
    assert!(load(&format!("{text}scale = 1e300\n"), &[]).is_ok());
}

/// A record path that is a device is said to be one (it was said not to exist), and one that
/// cannot be resolved says why.
#[cfg(unix)]
#[test]
fn a_record_that_is_a_device_is_named_so() {
    let text =
        one("masses = [1e6]\nstory_stiffness = [1e9]") + "[ground_motion]\nfile = \"/dev/null\"\n";
    err_has(
        load(&text, &[]),
        &[
            "key `ground_motion.file`",
            "/dev/null is not a regular file",
        ],
    );
    // A loop of links is said as the system says it (it was "does not exist").
    let dir = std::env::temp_dir().join(format!("pound-linkloop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b) = (dir.join("a.AT2"), dir.join("b.AT2"));
    let _ = (std::fs::remove_file(&a), std::fs::remove_file(&b));
    std::os::unix::fs::symlink(&b, &a).unwrap();
    std::os::unix::fs::symlink(&a, &b).unwrap();
    let text = one("masses = [1e6]\nstory_stiffness = [1e9]")
        + &format!("[ground_motion]\nfile = \"{}\"\n", a.display());
    let msg = err_has(
        load(&text, &[]),
        &["key `ground_motion.file`", "cannot be read"],
    );
    assert!(!msg.contains("does not exist"), "{msg}");
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// Counts of one in messages: "1 value", "1 floor", "1 entry"
// ---------------------------------------------------------------------------------------

#[test]
fn counts_of_one_are_singular_in_scene_messages() {
    let two = "masses = [1e6, 1e6]\nstory_stiffness = [1e9, 1e9]\n";
    for (body, key, want) in [
        (
            format!("{two}story_height = [3.0]"),
            "buildings[0].story_height",
            "has 1 value, expected 2",
        ),
        (
            "masses = [1e6, 1e6]\nstory_stiffness = [1e9]".to_string(),
            "buildings[0].story_stiffness",
            "has 1 value, expected 2",
        ),
        (
            format!("{two}story_law = \"bilinear\"\nyield_shear = [1e6]"),
            "buildings[0].yield_shear",
            "has 1 value, expected 2",
        ),
        (
            "masses = [1e6]\nstory_stiffness = [1e9]\ndamping_ratio = [0.05, 0.02]".to_string(),
            "buildings[0].damping_ratio",
            "a list of 2 ratios for a building of 1 floor:",
        ),
    ] {
        let m = err_has(load(&one(&body), &[]), &["scene.toml", key, want]);
        assert!(!m.contains(" 1 values") && !m.contains(" 1 floors"), "{m}");
    }
    // A floor out of range of a one-storey building; an index past a one-entry array.
    let text = "[[buildings]]\nname = \"a\"\nmasses = [1e6]\nstory_stiffness = [1e9]\n\
                [[buildings]]\nname = \"b\"\nmasses = [1e6]\nstory_stiffness = [1e9]\n\
                [[contacts]]\nleft = \"a\"\nleft_floor = 2\nright = \"b\"\nright_floor = 1\n\
                gap = 0.01\n[analysis]\nduration = 1.0\n";
    err_has(
        load(text, &[]),
        &[
            "contacts[0].left_floor",
            "floor 2 is out of range: `a` has only floor 1",
        ],
    );
    let m = err_has(
        load(text, &["buildings.0.masses.1=1e6"]),
        &[
            "--set buildings.0.masses.1=1e6",
            "`buildings.0.masses` has 1 entry (index 0)",
        ],
    );
    assert!(!m.contains("entries"), "{m}");
    // A building built in code: its own checks count the same way.
    let mut b = Building::new("c", vec![1e6, 1e6], vec![1e9, 1e9], 0.05);
    b.initial_velocity = vec![0.0];
    let m = b.validate().unwrap_err().to_string();
    assert!(
        m.contains("`initial_velocity` has 1 value, expected 2"),
        "{m}"
    );
    let b = Building::new("c", vec![1e6, 1e6], vec![1e9], 0.05);
    let m = b.validate().unwrap_err().to_string();
    assert!(
        m.contains("`story_stiffness` has 1 value but `masses` has 2"),
        "{m}"
    );
}
