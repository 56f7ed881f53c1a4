//! Integration tests for `structure::scene`: the paper scene, `--set` overrides, shorthand
//! forms, documented defaults, errors that name the key, and a property test that no input
//! (arbitrary text, mutations of the paper scene, arbitrary overrides) makes the loader panic,
//! load an invalid scene or give an error that names neither the file nor the `--set`.
//!
//! The command-line side of the bad-input catalogue (exit code 2, no partial output) lives in
//! `crates/studies/tests/cli_bad_input.rs`.

mod common;
use common::err_has;
use std::path::{Path, PathBuf};

use proptest::prelude::*;
use structure::ground::{RecordFormat, Units};
use structure::scene::{ContactLaw, ImpulseVariant, Integrator, MAX_STORIES};
use structure::testing::paper_scene_path;
use structure::{Damping, Purpose, Scene, SceneError, G};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scenes")
        .join(name)
}

fn fixtures_dir() -> PathBuf {
    fixture("")
}

fn paper_dir() -> PathBuf {
    paper_scene_path().parent().unwrap().to_path_buf()
}

fn paper_text() -> String {
    std::fs::read_to_string(paper_scene_path()).unwrap()
}

fn load_str(text: &str, overrides: &[&str]) -> Result<Scene, SceneError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_str_with_overrides(text, "test.toml", &fixtures_dir(), &o)
}

fn load_paper(overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_file_with_overrides(&paper_scene_path(), &o).unwrap()
}

const TINY: &str = r#"
[[buildings]]
name = "a"
masses = [1.0e5, 1.0e5]
story_stiffness = [1.0e8, 1.0e8]

[[buildings]]
name = "b"
masses = [1.2e5, 1.2e5]
story_stiffness = [1.5e8, 1.5e8]

[[contacts]]
left = "a"
left_floor = 2
right = "b"
right_floor = 2
gap = 0.01

[analysis]
duration = 1.0
"#;

// ---------------------------------------------------------------------------------------
// The paper scene
// ---------------------------------------------------------------------------------------

#[test]
fn paper_scene_loads_and_is_calibrated() {
    let s = Scene::from_file(&paper_scene_path()).unwrap();
    assert_eq!(s.name, "paper-pair");
    assert_eq!(s.file.as_deref(), Some(paper_scene_path().as_path()));
    assert_eq!(s.buildings.len(), 2);
    let targets = [("building1", [0.67, 2.23]), ("building2", [0.81, 3.06])];
    for (b, (name, f)) in s.buildings.iter().zip(targets) {
        assert_eq!(b.name, name);
        assert_eq!(b.n_floors(), 15);
        assert_eq!(b.story_stiffness.len(), 15);
        assert_eq!(b.reference_frequencies_hz, f.to_vec());
        assert_eq!(b.damping, Damping::Uniform(0.05));
        let got = b.modes().unwrap().frequencies_hz();
        for i in 0..2 {
            // Calibrated by a root search to 1e-14: 1e-12 relative (measured 4.8e-14 Hz).
            assert!(
                (got[i] - f[i]).abs() < 1e-12 * f[i],
                "{name} mode {}: {} Hz, target {} Hz",
                i + 1,
                got[i],
                f[i]
            );
        }
    }
    // Building 2 is about 20 % more massive.
    let ratio = s.buildings[1].total_mass() / s.buildings[0].total_mass();
    assert!((ratio - 1.2).abs() < 1e-12, "mass ratio {ratio}");

    assert_eq!(s.contacts.len(), 1);
    let c = &s.contacts[0];
    assert_eq!((c.left, c.left_dof, c.right, c.right_dof), (0, 14, 1, 14));
    assert_eq!(c.gap, 0.10);
    assert_eq!(c.restitution, 1.0);

    let g = s
        .ground
        .as_ref()
        .expect("the paper scene has a ground motion");
    assert!((g.pga() - 0.40 * G).abs() < 1e-9 * G, "PGA {}", g.pga() / G);
    let src = s.ground_source.as_ref().unwrap();
    assert_eq!(src.format, RecordFormat::At2);
    assert_eq!(src.pga_g, Some(0.40));
    assert!(src.file.ends_with("RSN752_LOMAP_CAP000.AT2"));
    // Without [analysis] duration the record's length is used.
    assert_eq!(s.duration, g.duration());
    assert_eq!(s.gap_element.law, ContactLaw::Linear);
    assert_eq!(s.gap_element.stiffness, 1.0e10);
}

// ---------------------------------------------------------------------------------------
// --set overrides
// ---------------------------------------------------------------------------------------

#[test]
fn set_overrides_from_the_issue() {
    let base = load_paper(&[]);
    let s = load_paper(&[
        "contacts.0.gap=0.05",
        "ground_motion.pga=0.15",
        "momentum.modes=10",
        "gap_element.law=linear",
    ]);
    assert_eq!(s.contacts[0].gap, 0.05);
    let g = s.ground.as_ref().unwrap();
    assert!((g.pga() - 0.15 * G).abs() < 1e-9 * G);
    assert_eq!(s.ground_source.as_ref().unwrap().pga_g, Some(0.15));
    assert_eq!(s.momentum.modes, Some(10));
    assert_eq!(s.gap_element.law, ContactLaw::Linear);
    // Everything else is untouched.
    assert_eq!(s.buildings, base.buildings);
    assert_eq!(s.contacts[0].restitution, base.contacts[0].restitution);
    assert_eq!(s.duration, base.duration);
}

#[test]
fn set_bare_words_and_toml_values() {
    // A bare word is a string; a quoted word too; TOML values keep their type.
    let s = load_paper(&["gap_element.law=kelvin-voigt"]);
    assert_eq!(s.gap_element.law, ContactLaw::KelvinVoigt);
    let s = load_paper(&["gap_element.law=\"hertz-damp\""]);
    assert_eq!(s.gap_element.law, ContactLaw::HertzDamp);
    let s = load_paper(&[
        "gap_element.integrator=newmark",
        "gap_element.time_step=0.002",
    ]);
    assert_eq!(s.gap_element.integrator, Integrator::Newmark);
    assert_eq!(s.gap_element.time_step, 0.002);
    let s = load_paper(&[
        "momentum.impulse=paper",
        "momentum.persistent_contact=false",
    ]);
    assert_eq!(s.momentum.impulse, ImpulseVariant::Paper);
    assert!(!s.momentum.persistent_contact);
    // New tables and keys can be created; spaces around `=` are ignored.
    let s = load_paper(&["analysis.duration = 5.0", "name=renamed"]);
    assert_eq!(s.duration, 5.0);
    assert_eq!(s.name, "renamed");
    // Arrays index by number, also inside a building.
    let s = load_str(
        TINY,
        &["buildings.1.masses.0=2.0e5", "contacts.0.restitution=0.5"],
    )
    .unwrap();
    assert_eq!(s.buildings[1].masses, vec![2.0e5, 1.2e5]);
    assert_eq!(s.contacts[0].restitution, 0.5);
    // Whole arrays as TOML values.
    let s = load_str(TINY, &["buildings.0.story_stiffness=[3e8, 2e8]"]).unwrap();
    assert_eq!(s.buildings[0].story_stiffness, vec![3e8, 2e8]);
    // Swapping pga for scale needs both edits; the later one wins.
    let s = load_paper(&["ground_motion.pga=0.2", "ground_motion.pga=0.3"]);
    assert_eq!(s.ground_source.unwrap().pga_g, Some(0.3));
}

#[test]
fn set_errors_name_the_expression() {
    let m = err_has(
        load_str(TINY, &["contacts.3.gap=0.05"]),
        &["--set contacts.3.gap=0.05"],
    );
    assert!(
        m.contains("out of range") && m.contains("has 1 entry (index 0)"),
        "{m}"
    );
    assert!(!m.contains("entries"), "{m}");
    err_has(
        load_str(TINY, &["buildings.2.name=c"]),
        &[
            "index 2 is out of range",
            "`buildings` has 2 entries (indices 0 … 1)",
        ],
    );
    err_has(
        load_str(TINY, &["contacts.0.gap"]),
        &["--set contacts.0.gap", "PATH=VALUE"],
    );
    err_has(load_str(TINY, &["=0.05"]), &["--set =0.05", "empty"]);
    err_has(
        load_str(TINY, &["contacts.first.gap=0.05"]),
        &["contacts.first.gap", "numeric index", "`first`"],
    );
    err_has(
        load_str(TINY, &["contacts.0.gap.x=1"]),
        &["contacts.0.gap.x=1", "`contacts.0.gap` is a value"],
    );
    // An override that creates an unknown key is reported like one in the file.
    err_has(
        load_str(TINY, &["gap_element.stifness=1e9"]),
        &["test.toml", "`stifness`", "gap_element", "--set"],
    );
    err_has(
        load_str(TINY, &["gap_element.law=hertz"]),
        &["test.toml", "`hertz`", "gap_element.law"],
    );
    // Overridden values are validated like any other.
    err_has(
        load_str(TINY, &["contacts.0.gap=-0.05"]),
        &["test.toml", "contacts[0].gap", ">= 0"],
    );
}

// ---------------------------------------------------------------------------------------
// Shorthand forms and defaults
// ---------------------------------------------------------------------------------------

#[test]
fn shorthand_forms() {
    let s = Scene::from_file(&fixture("shorthand.toml")).unwrap();
    assert_eq!(s.name, "shorthand");
    let l = &s.buildings[0];
    assert_eq!(l.masses, vec![5.0e5; 4]);
    assert_eq!(l.story_stiffness, vec![8.0e8; 4]);
    assert_eq!(l.damping, Damping::PerMode(vec![0.02, 0.03, 0.03, 0.04]));
    assert_eq!(l.damping.ratio(3), 0.04, "one ratio per mode");
    let r = &s.buildings[1];
    assert_eq!(r.initial_displacement, vec![0.001, 0.002, 0.003]);
    assert_eq!(r.initial_velocity, vec![0.0, 0.0, -0.01]);
    let c = &s.contacts[0];
    assert_eq!((c.left_dof, c.right_dof), (3, 2));
    assert_eq!(c.restitution, 1.0, "default restitution");

    let src = s.ground_source.as_ref().unwrap();
    assert_eq!(
        src.format,
        RecordFormat::OneColumn {
            dt: 0.01,
            units: Units::MetersPerSecond2
        }
    );
    assert_eq!(src.factor, 2.0);
    assert_eq!(src.pga_g, None);
    let g = s.ground.as_ref().unwrap();
    assert_eq!(g.npts(), 9);
    assert_eq!(g.dt, 0.01);
    assert!((g.pga() - 2.0).abs() < 1e-12, "1.0 m/s^2 scaled by 2");
    assert!(
        (s.duration - 0.08).abs() < 1e-12,
        "duration = record length"
    );

    // The shorthand is the same building as the long form.
    let long = TINY.replace(
        "masses = [1.0e5, 1.0e5]\nstory_stiffness = [1.0e8, 1.0e8]",
        "stories = 2\nmass = 1.0e5\nstory_stiffness = 1.0e8",
    );
    assert_ne!(long, TINY);
    assert_eq!(
        load_str(&long, &[]).unwrap().buildings,
        load_str(TINY, &[]).unwrap().buildings
    );
}

#[test]
fn documented_defaults() {
    let s = Scene::from_file(&fixture("minimal.toml")).unwrap();
    assert_eq!(s.name, "scene");
    let b = &s.buildings[0];
    assert_eq!(b.damping, Damping::Uniform(0.05));
    assert_eq!(b.initial_displacement, vec![0.0; 3]);
    assert_eq!(b.initial_velocity, vec![0.0; 3]);
    assert!(b.reference_frequencies_hz.is_empty());
    assert!(s.contacts.is_empty());
    assert!(s.ground.is_none() && s.ground_source.is_none());
    assert_eq!(s.ground_accel(0.5), 0.0);
    assert_eq!(s.duration, 2.0);

    assert_eq!(s.momentum.modes, None);
    assert_eq!(s.momentum.impulse, ImpulseVariant::Consistent);
    assert!(s.momentum.persistent_contact);
    assert_eq!(s.momentum.capture_velocity, 1e-4);
    assert_eq!(s.momentum.held_tolerance, 1e-6);

    assert_eq!(s.gap_element.stiffness, 1.0e10);
    assert_eq!(s.gap_element.law, ContactLaw::KelvinVoigt);
    assert_eq!(s.gap_element.integrator, Integrator::Adaptive);
    assert_eq!(s.gap_element.tolerance, 1.0e-8);
    assert_eq!(s.gap_element.time_step, 1.0e-3);
    assert!(!s.gap_element.tension);

    assert_eq!(s.limits.max_impact_rate, 2000.0);
    assert_eq!(s.limits.max_steps, 50_000_000);
}

#[test]
fn record_format_inference_and_units() {
    // Not *.at2: two-column, in g, factor 1 without pga/scale.
    let text = format!("{TINY}\n[ground_motion]\nfile = \"pulse_two_column.txt\"\n")
        .replace("[analysis]\nduration = 1.0\n", "");
    let s = load_str(&text, &[]).unwrap();
    let src = s.ground_source.as_ref().unwrap();
    assert_eq!(src.format, RecordFormat::TwoColumn { units: Units::G });
    assert_eq!(src.factor, 1.0);
    let g = s.ground.as_ref().unwrap();
    assert!((g.dt - 0.02).abs() < 1e-12);
    assert!((g.pga() - 0.20 * G).abs() < 1e-12);
    assert!((s.duration - 0.08).abs() < 1e-12);
    // Units for two-column records.
    let s = load_str(&text, &["ground_motion.units=cm/s^2"]).unwrap();
    assert!((s.ground.unwrap().pga() - 0.002).abs() < 1e-12);
    // A negative scale flips the record; zero is allowed (no excitation).
    let s = load_str(&text, &["ground_motion.scale=-2"]).unwrap();
    assert!((s.ground.unwrap().accel[2] - 0.40 * G).abs() < 1e-12);
    // The paper's *.AT2 is read as AT2.
    assert_eq!(
        load_paper(&[]).ground_source.unwrap().format,
        RecordFormat::At2
    );
}

// ---------------------------------------------------------------------------------------
// Errors name the file and key (the full catalogue runs the binary: cli_bad_input.rs)
// ---------------------------------------------------------------------------------------

#[test]
fn unknown_keys_name_key_and_line() {
    let cases = [
        ("nme = \"x\"\n", "nme", "line 1"),
        ("[[buildings]]\nname = \"a\"\nmass = 1.0\nstories = 1\nstory_stifness = 1.0\n", "story_stifness", "line 5"),
        ("[[buildings]]\nname = \"a\"\nmasses = [1.0]\nstory_stiffness = [1.0]\n[gap_element]\nlaww = \"linear\"\n", "laww", "line 6"),
        ("[[buildings]]\nname = \"a\"\nmasses = [1.0]\nstory_stiffness = [1.0]\n[analysis]\nduration = 1.0\nsteps = 3\n", "steps", "line 7"),
    ];
    for (text, key, line) in cases {
        err_has(
            load_str(text, &[]),
            &["test.toml", &format!("`{key}`"), line],
        );
    }
}

#[test]
fn validation_errors_name_the_key() {
    let cases: &[(&str, &[&str])] = &[
        ("buildings.0.masses.1=0", &["buildings[0].masses[1]", "> 0"]),
        (
            "buildings.0.masses.1=nan",
            &["buildings[0].masses[1]", "finite"],
        ),
        (
            "buildings.1.story_stiffness.0=-1e8",
            &["buildings[1].story_stiffness[0]", "> 0"],
        ),
        (
            "buildings.1.story_stiffness.0=inf",
            &["buildings[1].story_stiffness[0]", "finite"],
        ),
        (
            "buildings.0.story_stiffness=[1e8]",
            &["buildings[0].story_stiffness", "expected 2"],
        ),
        (
            "buildings.0.initial_velocity=[1.0]",
            &["buildings[0]", "initial_velocity", "expected 2"],
        ),
        (
            "buildings.0.damping_ratio=1.5",
            &["buildings[0]", "damping_ratio", "< 1"],
        ),
        ("buildings.1.name=a", &["buildings[1].name", "twice"]),
        ("contacts.0.left=zz", &["contacts[0].left", "`zz`", "a, b"]),
        (
            "contacts.0.right=a",
            &["contacts[0].right", "different buildings"],
        ),
        (
            "contacts.0.left_floor=3",
            &["contacts[0].left_floor", "1 … 2"],
        ),
        (
            "contacts.0.right_floor=0",
            &["contacts[0].right_floor", "out of range"],
        ),
        ("contacts.0.gap=-0.01", &["contacts[0].gap", ">= 0"]),
        (
            "contacts.0.restitution=1.01",
            &["contacts[0].restitution", "[0, 1]"],
        ),
        (
            "contacts.0.restitution=-0.1",
            &["contacts[0].restitution", "[0, 1]"],
        ),
        ("analysis.duration=0", &["analysis.duration", "> 0"]),
        ("analysis.duration=-1", &["analysis.duration", "> 0"]),
        ("momentum.modes=0", &["momentum.modes", ">= 1"]),
        (
            "momentum.held_tolerance=0",
            &["momentum.held_tolerance", "> 0 and <= 1e-2"],
        ),
        (
            "momentum.held_tolerance=0.1",
            &["momentum.held_tolerance", "> 0 and <= 1e-2"],
        ),
        ("gap_element.stiffness=0", &["gap_element.stiffness", "> 0"]),
        (
            "gap_element.tolerance=0.1",
            &["gap_element.tolerance", "(0, 0.1)"],
        ),
        (
            "gap_element.tolerance=0",
            &["gap_element.tolerance", "(0, 0.1)"],
        ),
        ("gap_element.time_step=0", &["gap_element.time_step", "> 0"]),
        (
            "gap_element.time_step=-0.001",
            &["gap_element.time_step", "> 0"],
        ),
        (
            "ground_motion.file=missing.at2",
            &["ground_motion.file", "missing.at2", "does not exist"],
        ),
    ];
    for (set, parts) in cases {
        let mut all = vec!["test.toml"];
        all.extend_from_slice(parts);
        err_has(load_str(TINY, &[set]), &all);
    }
}

#[test]
fn ground_motion_errors_name_the_key() {
    let text = format!("{TINY}\n[ground_motion]\nfile = \"pulse_two_column.txt\"\n");
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["ground_motion.pga=0.3", "ground_motion.scale=2"],
            &["ground_motion.pga", "not both"],
        ),
        (&["ground_motion.pga=0"], &["ground_motion.pga", "> 0"]),
        (&["ground_motion.pga=-0.3"], &["ground_motion.pga", "> 0"]),
        (
            &["ground_motion.scale=nan"],
            &["ground_motion.scale", "finite"],
        ),
        (
            &["ground_motion.units=furlongs"],
            &["ground_motion.units", "furlongs"],
        ),
        (
            &["ground_motion.format=csv"],
            &["ground_motion.format", "`csv`"],
        ),
        // `dt` without `format` reads the file as one-column: a two-column file is refused
        // by the record reader (`a_dt_without_format_reads_one_column`).
        (
            &["ground_motion.format=two-column", "ground_motion.dt=0.01"],
            &["ground_motion.dt", "two-column", "remove `dt`"],
        ),
        (
            &["ground_motion.format=one-column"],
            &["ground_motion.dt", "missing"],
        ),
        (
            &["ground_motion.format=one-column", "ground_motion.dt=0"],
            &["ground_motion.dt", "> 0"],
        ),
        (
            &["ground_motion.format=one-column", "ground_motion.dt=-0.01"],
            &["ground_motion.dt", "> 0"],
        ),
        // The record reader's own message comes through with the scene's key.
        (
            &["ground_motion.format=at2"],
            &[
                "ground_motion.file",
                "pulse_two_column.txt",
                "line 3",
                "UNITS OF G",
            ],
        ),
    ];
    for (sets, parts) in cases {
        let mut all = vec!["test.toml"];
        all.extend_from_slice(parts);
        err_has(load_str(&text, sets), &all);
    }
}

#[test]
fn missing_fields_name_the_field() {
    err_has(
        load_str("name = \"x\"\n", &[]),
        &["test.toml", "`buildings`"],
    );
    err_has(
        load_str("buildings = []\n[analysis]\nduration = 1.0\n", &[]),
        &["buildings", "at least one"],
    );
    let no_mass =
        "[[buildings]]\nname = \"a\"\nstory_stiffness = [1.0]\n[analysis]\nduration = 1.0\n";
    err_has(load_str(no_mass, &[]), &["buildings[0].masses", "missing"]);
    let no_k = "[[buildings]]\nname = \"a\"\nmasses = [1.0]\n[analysis]\nduration = 1.0\n";
    err_has(
        load_str(no_k, &[]),
        &["buildings[0].story_stiffness", "missing"],
    );
    let no_duration = "[[buildings]]\nname = \"a\"\nmasses = [1.0]\nstory_stiffness = [1.0]\n";
    err_has(
        load_str(no_duration, &[]),
        &["analysis.duration", "missing"],
    );
    let no_name = "[[buildings]]\nmasses = [1.0]\nstory_stiffness = [1.0]\n";
    err_has(load_str(no_name, &[]), &["test.toml", "`name`"]);
    let no_gap = TINY.replace("gap = 0.01\n", "");
    err_has(load_str(&no_gap, &[]), &["test.toml", "`gap`"]);
    let no_file = format!("{TINY}\n[ground_motion]\npga = 0.3\n");
    err_has(load_str(&no_file, &[]), &["test.toml", "`file`"]);
}

#[test]
fn an_empty_override_removes_the_key() {
    // The paper scene scales its record to `pga`; switching to `scale` needs `pga` removed.
    err_has(
        Scene::from_file_with_overrides(
            &paper_scene_path(),
            &["ground_motion.scale=1.0".to_string()],
        ),
        &["pga", "scale"],
    );
    let s = load_paper(&["ground_motion.pga=", "ground_motion.scale=1.0"]);
    let src = s.ground_source.as_ref().unwrap();
    assert_eq!((src.pga_g, src.factor), (None, 1.0));
    // A key that is not there: nothing to remove; a nested key below an array entry.
    let t = load_paper(&[
        "momentum.capture_velocity=",
        "buildings.0.initial_velocity=",
    ]);
    assert_eq!(t.buildings[0].n_floors(), 15);
    // An array entry cannot be removed; a path through a value is refused.
    for (o, expect) in [
        ("contacts.0=", "cannot be removed"),
        ("name.x=", "is a value"),
        ("buildings.9.name=", "out of range"),
    ] {
        let r = Scene::from_file_with_overrides(&paper_scene_path(), &[o.to_string()]);
        err_has(r, &[expect]);
    }
}

#[test]
fn a_scene_read_for_its_structure_needs_no_duration() {
    // `pound modes` reads a scene for its structure alone: neither a record nor
    // `analysis.duration` is needed, and the scene says it cannot be analysed (duration 0).
    let text = "[[buildings]]\nname = \"a\"\nmasses = [1.0, 1.0]\nstory_stiffness = [4.0, 4.0]\n\
                [gap_element]\ntime_step = 0.5\n";
    let o: Vec<String> = Vec::new();
    let s = Scene::from_str_for(text, "test.toml", &fixtures_dir(), &o, Purpose::Structure)
        .expect("a structure needs no duration");
    assert_eq!(s.duration, 0.0);
    assert!(s.ground.is_none());
    assert_eq!(s.buildings[0].masses, vec![1.0, 1.0]);
    // For an analysis the same text is refused, naming the key.
    err_has(load_str(text, &[]), &["analysis.duration", "missing"]);
    // A duration that is given is still checked, and bounds the step.
    for (bad, expect) in [
        ("[analysis]\nduration = -1.0\n", "analysis.duration"),
        ("[analysis]\nduration = 0.25\n", "gap_element.time_step"),
    ] {
        let t = format!("{text}{bad}");
        err_has(
            Scene::from_str_for(&t, "test.toml", &fixtures_dir(), &o, Purpose::Structure),
            &[expect],
        );
    }
}

#[test]
fn shorthand_and_calibration_errors_name_the_key() {
    let b =
        |body: &str| format!("[[buildings]]\nname = \"a\"\n{body}\n[analysis]\nduration = 1.0\n");
    err_has(
        load_str(&b("stories = 0\nmass = 1.0\nstory_stiffness = 1.0"), &[]),
        &["buildings[0].stories", "1 ..= "],
    );
    let too_many = format!(
        "stories = {}\nmass = 1.0\nstory_stiffness = 1.0",
        MAX_STORIES + 1
    );
    err_has(load_str(&b(&too_many), &[]), &["buildings[0].stories"]);
    let huge = "stories = 9223372036854775807\nmass = 1.0\nstory_stiffness = 1.0";
    err_has(load_str(&b(huge), &[]), &["buildings[0].stories"]);
    err_has(
        load_str(&b("stories = 3\nstory_stiffness = 1.0"), &[]),
        &["buildings[0].masses", "missing"],
    );
    err_has(
        load_str(
            &b("masses = [1.0]\nstories = 1\nmass = 1.0\nstory_stiffness = 1.0"),
            &[],
        ),
        &["buildings[0].masses", "not both"],
    );
    err_has(
        load_str(&b("stories = 3\nmass = 1.0\nstory_stiffness = 1.0\ntarget_frequencies_hz = [1.0, 3.0]"), &[]),
        &["buildings[0].target_frequencies_hz", "not both"],
    );
    err_has(
        load_str(
            &b("stories = 3\nmass = 1.0\ntarget_frequencies_hz = [1.0]"),
            &[],
        ),
        &["buildings[0].target_frequencies_hz", "expected 2"],
    );
    err_has(
        load_str(
            &b("masses = [1.0, 2.0]\ntarget_frequencies_hz = [1.0, 3.0]"),
            &[],
        ),
        &["buildings[0].target_frequencies_hz", "uniform"],
    );
    err_has(
        load_str(
            &b("stories = 1\nmass = 1.0\ntarget_frequencies_hz = [1.0, 3.0]"),
            &[],
        ),
        &["buildings[0].target_frequencies_hz", "2 floors"],
    );
    err_has(
        load_str(
            &b("stories = 3\nmass = 1.0\ntarget_frequencies_hz = [3.0, 1.0]"),
            &[],
        ),
        &["buildings[0].target_frequencies_hz", "f1 < f2"],
    );
}

// ---------------------------------------------------------------------------------------
// No input makes the loader panic
// ---------------------------------------------------------------------------------------

/// Values that stress validation: non-positive, non-finite, huge, tiny, wrong types.
const NASTY_VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "15",
    "16",
    "100",
    "0.5",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "\"\"",
    "\"building1\"",
    "\"building2\"",
    "\"linear\"",
    "\"x\"",
    "true",
    "[]",
    "[1.0]",
    "[0.67, 2.23]",
    "[1e300, 1e301]",
    "[1e-300, 2e-300]",
    "[0.0, 0.0]",
    "[nan, 1]",
    "{}",
    "[[1]]",
    "1979-05-27",
    "'''\n'''",
];

/// Overridable paths of the paper scene and some that do not exist.
const PATHS: &[&str] = &[
    "name",
    "buildings.0.stories",
    "buildings.1.mass",
    "buildings.0.masses",
    "buildings.0.story_stiffness",
    "buildings.1.target_frequencies_hz",
    "buildings.0.damping_ratio",
    "buildings.0.initial_velocity",
    "buildings.2.name",
    "contacts.0.gap",
    "contacts.0.left",
    "contacts.0.right_floor",
    "contacts.0.restitution",
    "contacts.1",
    "ground_motion.pga",
    "ground_motion.scale",
    "ground_motion.file",
    "ground_motion.format",
    "ground_motion.dt",
    "ground_motion.units",
    "analysis.duration",
    "analysis.max_steps",
    "analysis.max_impact_rate",
    "momentum.modes",
    "momentum.impulse",
    "momentum.capture_velocity",
    "momentum.held_tolerance",
    "gap_element.stiffness",
    "gap_element.law",
    "gap_element.tolerance",
    "gap_element.time_step",
    "gap_element.integrator",
    "buildings",
    "contacts",
    "x.y.z",
    "buildings.x",
    "contacts.0.gap.deeper",
    "",
];

#[derive(Debug, Clone)]
enum Mutation {
    /// Delete `len` characters at `at`.
    Delete { at: prop::sample::Index, len: usize },
    /// Insert text at `at`.
    Insert {
        at: prop::sample::Index,
        text: String,
    },
    /// Replace what follows `=` on a line with a nasty value.
    Value {
        line: prop::sample::Index,
        value: &'static str,
    },
    /// Duplicate a line after itself.
    Duplicate { line: prop::sample::Index },
    /// Swap two lines.
    Swap {
        a: prop::sample::Index,
        b: prop::sample::Index,
    },
    /// Replace a line with arbitrary text.
    Line {
        line: prop::sample::Index,
        text: String,
    },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let idx = any::<prop::sample::Index>;
    // Mostly value edits: they keep the text valid TOML and reach validation.
    prop_oneof![
        1 => (idx(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        1 => (idx(), "\\PC{0,16}|[\\[\\]=\"'.,{}#\n0-9a-z_-]{0,8}")
            .prop_map(|(at, text)| Mutation::Insert { at, text }),
        6 => (idx(), prop::sample::select(NASTY_VALUES))
            .prop_map(|(line, value)| Mutation::Value { line, value }),
        1 => idx().prop_map(|line| Mutation::Duplicate { line }),
        1 => (idx(), idx()).prop_map(|(a, b)| Mutation::Swap { a, b }),
        1 => (idx(), "\\PC{0,30}").prop_map(|(line, text)| Mutation::Line { line, text }),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        lines.push(String::new());
    }
    match m {
        Mutation::Delete { at, len } => {
            let i = at.index(chars.len() + 1);
            let j = (i + len).min(chars.len());
            chars[..i].iter().chain(&chars[j..]).collect()
        }
        Mutation::Insert { at, text } => {
            let i = at.index(chars.len() + 1);
            let mut s: String = chars[..i].iter().collect();
            s.push_str(text);
            s.extend(&chars[i..]);
            s
        }
        Mutation::Value { line, value } => {
            let i = line.index(lines.len());
            if let Some((k, _)) = lines[i].split_once('=') {
                lines[i] = format!("{k}= {value}");
            }
            lines.join("\n")
        }
        Mutation::Duplicate { line } => {
            let i = line.index(lines.len());
            let l = lines[i].clone();
            lines.insert(i, l);
            lines.join("\n")
        }
        Mutation::Swap { a, b } => {
            let (i, j) = (a.index(lines.len()), b.index(lines.len()));
            lines.swap(i, j);
            lines.join("\n")
        }
        Mutation::Line { line, text } => {
            let i = line.index(lines.len());
            lines[i] = text.clone();
            lines.join("\n")
        }
    }
}

fn tiny_with_record() -> String {
    with_record("file = \"pulse_two_column.txt\"\npga = 0.3")
}

/// A scene's `pga` and `scale` scale its record bit for bit as `GroundMotion::scaled_to_pga`
/// and `scaled` do (the scene computes the factor itself, to check it for overflow).
#[test]
fn the_scene_scales_its_record_as_the_record_does() {
    let rec = structure::GroundMotion::load(
        &fixtures_dir().join("pulse_two_column.txt"),
        &RecordFormat::TwoColumn { units: Units::G },
    )
    .unwrap();
    for pga in [0.3, 0.07, 1.9] {
        let s = load_str(&tiny_with_record(), &[&format!("ground_motion.pga={pga}")]).unwrap();
        assert_eq!(s.ground.unwrap(), rec.scaled_to_pga(pga), "pga {pga}");
    }
    let s = load_str(
        &with_record("file = \"pulse_two_column.txt\"\nscale = 0.37"),
        &[],
    )
    .unwrap();
    assert_eq!(s.ground.unwrap(), rec.scaled(0.37));
}

/// What every load must give, whatever the input: a scene that loads is valid
/// ([`structure::testing::loaded_scene_violation`], which the fuzz target asserts too); an
/// error names the file (`fuzz.toml`) or the `--set` expression it comes from.
fn loads_valid_or_names_its_source(r: Result<Scene, SceneError>) -> Result<(), TestCaseError> {
    match r {
        Ok(scene) => {
            let v = structure::testing::loaded_scene_violation(&scene);
            prop_assert!(v.is_none(), "{v:?}");
        }
        Err(e) => {
            let m = e.to_string();
            prop_assert!(m.contains("fuzz.toml") || m.starts_with("--set "), "{m}");
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,400}") {
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&text, "fuzz.toml", Path::new("."), &[]))?;
    }

    #[test]
    fn toml_shaped_text_never_panics(
        text in "(\\[\\[?(buildings|contacts|ground_motion|analysis|momentum|gap_element)\\]\\]?\n|[a-z_]{1,22} = (-?[0-9.e]{1,8}|\"[a-z0-9]{0,9}\"|\\[[-0-9., e]{0,20}\\]|true|nan|inf)\n){0,30}"
    ) {
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&text, "fuzz.toml", &fixtures_dir(), &[]))?;
    }

    #[test]
    fn mutated_tiny_scene_never_panics(ms in prop::collection::vec(mutation(), 1..5)) {
        let mut text = tiny_with_record();
        for m in &ms {
            text = apply(&text, m);
        }
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&text, "fuzz.toml", &fixtures_dir(), &[]))?;
    }

    #[test]
    fn arbitrary_overrides_never_panic(
        sets in prop::collection::vec(
            prop_oneof![
                (prop::sample::select(PATHS), prop::sample::select(NASTY_VALUES))
                    .prop_map(|(p, v)| format!("{p}={v}")),
                "\\PC{0,30}",
            ],
            1..4,
        )
    ) {
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&tiny_with_record(), "fuzz.toml", &fixtures_dir(), &sets))?;
    }
}

proptest! {
    // The paper scene calibrates two 15-storey sticks and reads an 8000-point record per
    // case: fewer cases.
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn mutated_paper_scene_never_panics(ms in prop::collection::vec(mutation(), 1..4)) {
        let mut text = paper_text();
        for m in &ms {
            text = apply(&text, m);
        }
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&text, "fuzz.toml", &paper_dir(), &[]))?;
    }

    #[test]
    fn paper_scene_with_arbitrary_overrides_never_panics(
        sets in prop::collection::vec(
            (prop::sample::select(PATHS), prop::sample::select(NASTY_VALUES))
                .prop_map(|(p, v)| format!("{p}={v}")),
            1..4,
        )
    ) {
        let o: Vec<String> = sets;
        loads_valid_or_names_its_source(Scene::from_str_with_overrides(&paper_text(), "fuzz.toml", &paper_dir(), &o))?;
    }
}

// ---------------------------------------------------------------------------------------
// `floors = "aligned"` and `story_height` (issue 11)
// ---------------------------------------------------------------------------------------

/// The paper scene with its roof contact replaced by `floors = "aligned"`.
fn paper_aligned_text() -> String {
    let t = paper_text();
    assert!(t.contains("left_floor = 15\n") && t.contains("right_floor = 15\n"));
    t.replace("left_floor = 15\n", "floors = \"aligned\"\n")
        .replace("right_floor = 15\n", "")
}

#[test]
fn aligned_floors_without_heights_join_floor_i_to_floor_i() {
    let s = Scene::from_str_with_overrides(
        &paper_aligned_text(),
        "aligned.toml",
        &paper_dir(),
        &[
            "contacts.0.gap=0.05".into(),
            "contacts.0.restitution=0.65".into(),
        ],
    )
    .unwrap();
    assert_eq!(s.contacts.len(), 15);
    // Highest pair first.
    for (k, c) in s.contacts.iter().enumerate() {
        let i = 14 - k;
        assert_eq!((c.left, c.left_dof, c.right, c.right_dof), (0, i, 1, i));
        assert_eq!((c.gap, c.restitution), (0.05, 0.65));
    }
    assert!(s.unmodelled_facings().is_empty());
    // Unequal heights in floors: up to the lower roof.
    let text = TINY
        .replace("masses = [1.2e5, 1.2e5]", "masses = [1.2e5, 1.2e5, 1.2e5]")
        .replace(
            "story_stiffness = [1.5e8, 1.5e8]",
            "story_stiffness = 1.5e8",
        )
        .replace("left_floor = 2\n", "floors = \"aligned\"\n")
        .replace("right_floor = 2\n", "");
    let s = load_str(&text, &[]).unwrap();
    let pairs: Vec<_> = s
        .contacts
        .iter()
        .map(|c| (c.left_dof, c.right_dof))
        .collect();
    assert_eq!(pairs, vec![(1, 1), (0, 0)]);
    assert_eq!(s.facings(0, 1).pairs, vec![(0, 0), (1, 1)]);
    assert_eq!(s.facings(1, 0).pairs, vec![(0, 0), (1, 1)]);
}

/// Building a: stories 4, 3, 3 m (floors at 4, 7, 10 m); building b: 3.5 m each, four
/// stories (3.5, 7, 10.5, 14 m). Only floor 2 of each is at a common elevation; floor 1 of
/// a (4 m) lies between floors 1 and 2 of b, floor 3 of a (10 m) between floors 2 and 3 of
/// b, floor 1 of b (3.5 m) between the ground and floor 1 of a; floors 3 and 4 of b are
/// above a's roof (no facing).
const HEIGHTS: &str = r#"
[[buildings]]
name = "a"
masses = [1.0e5, 1.0e5, 1.0e5]
story_stiffness = 1.0e8
story_height = [4.0, 3.0, 3.0]

[[buildings]]
name = "b"
stories = 4
mass = 1.2e5
story_stiffness = 1.5e8
story_height = 3.5

[[contacts]]
left = "a"
floors = "aligned"
right = "b"
gap = 0.01
restitution = 0.8

[analysis]
duration = 1.0
"#;

#[test]
fn aligned_floors_with_heights_match_elevations_and_list_floor_to_column_facings() {
    let s = load_str(HEIGHTS, &[]).unwrap();
    assert_eq!(s.story_heights[0].as_deref(), Some(&[4.0, 3.0, 3.0][..]));
    assert_eq!(s.story_heights[1].as_deref(), Some(&[3.5; 4][..]));
    assert_eq!(s.contacts.len(), 1);
    let c = &s.contacts[0];
    assert_eq!(
        (c.left_dof, c.right_dof, c.gap, c.restitution),
        (1, 1, 0.01, 0.8)
    );
    let u = s.unmodelled_facings();
    let got: Vec<_> = u
        .iter()
        .map(|f| (f.building.as_str(), f.floor, f.other.as_str(), f.between))
        .collect();
    assert_eq!(
        got,
        vec![
            ("a", 1, "b", [1, 2]),
            ("a", 3, "b", [2, 3]),
            ("b", 1, "a", [0, 1])
        ]
    );
    assert_eq!(u[0].elevation, 4.0);
    // Within the tolerance (1e-6 m) elevations agree; beyond it they do not.
    let s = load_str(
        HEIGHTS,
        &["buildings.1.story_height=[4.0000005, 3.0, 3.0, 3.0]"],
    )
    .unwrap();
    let pairs: Vec<_> = s
        .contacts
        .iter()
        .map(|c| (c.left_dof, c.right_dof))
        .collect();
    assert_eq!(pairs, vec![(2, 2), (1, 1), (0, 0)]);
    assert!(s.unmodelled_facings().is_empty());
    let s = load_str(
        HEIGHTS,
        &["buildings.1.story_height=[4.000002, 2.999998, 3.0, 3.0]"],
    )
    .unwrap();
    let pairs: Vec<_> = s
        .contacts
        .iter()
        .map(|c| (c.left_dof, c.right_dof))
        .collect();
    assert_eq!(pairs, vec![(2, 2), (1, 1)]);
    assert_eq!(s.unmodelled_facings().len(), 2);
    // Explicit floor contacts are unaffected by heights; the facings are still reported.
    let explicit = HEIGHTS.replace(
        "floors = \"aligned\"\n",
        "left_floor = 3\nright_floor = 3\n",
    );
    let s = load_str(&explicit, &[]).unwrap();
    assert_eq!((s.contacts[0].left_dof, s.contacts[0].right_dof), (2, 2));
    assert_eq!(s.unmodelled_facings().len(), 3);
}

#[test]
fn story_height_and_aligned_errors_name_the_key() {
    err_has(
        load_str(HEIGHTS, &["buildings.1.story_height=[3.5, 3.5]"]),
        &["buildings[1].story_height", "has 2 values, expected 4"],
    );
    err_has(
        load_str(HEIGHTS, &["buildings.0.story_height=[4.0, -3.0, 3.0]"]),
        &["buildings[0].story_height[1]", "-3", "> 0 (m)"],
    );
    err_has(
        load_str(HEIGHTS, &["buildings.1.story_height=0.0"]),
        &["buildings[1].story_height", "> 0 (m)"],
    );
    err_has(
        load_str(HEIGHTS, &["buildings.0.story_height=\"tall\""]),
        &["buildings", "a number or a list of numbers"],
    );
    // Heights on one building only.
    let one = HEIGHTS.replace("story_height = 3.5\n", "");
    err_has(
        load_str(&one, &[]),
        &[
            "buildings[1].story_height",
            "missing",
            "`a`",
            "`b`",
            "both buildings or for neither",
        ],
    );
    let one_explicit = one.replace(
        "floors = \"aligned\"\n",
        "left_floor = 1\nright_floor = 1\n",
    );
    err_has(
        load_str(&one_explicit, &[]),
        &["buildings[1].story_height", "missing"],
    );
    // `floors` with explicit floors, another word, or no floors at all.
    err_has(
        load_str(HEIGHTS, &["contacts.0.left_floor=1"]),
        &["contacts[0].left_floor", "not both"],
    );
    err_has(
        load_str(HEIGHTS, &["contacts.0.right_floor=2"]),
        &["contacts[0].right_floor", "not both"],
    );
    err_has(
        load_str(HEIGHTS, &["contacts.0.floors=all"]),
        &["contacts[0].floors", "`all`", "\"aligned\""],
    );
    let none = HEIGHTS.replace("floors = \"aligned\"\n", "");
    err_has(
        load_str(&none, &[]),
        &["contacts[0].left_floor", "missing", "floors = \"aligned\""],
    );
    err_has(load_str(TINY, &["contacts.0.right_floor=x"]), &["contacts"]);
    let half = TINY.replace("right_floor = 2\n", "");
    err_has(
        load_str(&half, &[]),
        &["contacts[0].right_floor", "missing"],
    );
    // No floor at a common elevation.
    err_has(
        load_str(HEIGHTS, &["buildings.1.story_height=3.3"]),
        &["contacts[0].floors", "no floor of `a`", "1e-6 m"],
    );
}

#[test]
fn duplicates_after_aligned_expansion_are_refused() {
    let roof = "\n[[contacts]]\nleft = \"b\"\nleft_floor = 15\nright = \"building1\"\nright_floor = 15\ngap = 0.1\n"
        .replace("\"b\"", "\"building2\"");
    let text = format!("{}{roof}", paper_aligned_text());
    err_has(
        Scene::from_str_with_overrides(&text, "dup.toml", &paper_dir(), &[]),
        &[
            "contacts[1]",
            "duplicate contact",
            "floor 15",
            "contacts[0]",
        ],
    );
    // Two aligned entries for the same pair.
    let twice = HEIGHTS.replace(
        "[analysis]",
        "[[contacts]]\nleft = \"b\"\nfloors = \"aligned\"\nright = \"a\"\ngap = 0.02\n\n[analysis]",
    );
    err_has(
        load_str(&twice, &[]),
        &[
            "contacts[1]",
            "duplicate contact",
            "floor 2 of `b`",
            "contacts[0]",
        ],
    );
}

// ---------------------------------------------------------------------------------------
// Record format inference: `dt` without `format`
// ---------------------------------------------------------------------------------------

/// TINY with a `[ground_motion]` table holding `gm`.
fn with_record(gm: &str) -> String {
    format!("{TINY}\n[ground_motion]\n{gm}\n")
}

#[test]
fn a_dt_without_format_reads_one_column() {
    // `pulse.txt` holds values only (four to a line): `dt` alone makes it one-column, as
    // `pound record pulse.txt --dt 0.01` reads it.
    let s = load_str(
        &with_record("file = \"pulse.txt\"\ndt = 0.01\nunits = \"m/s^2\""),
        &[],
    )
    .unwrap();
    let src = s.ground_source.as_ref().unwrap();
    assert_eq!(
        src.format,
        RecordFormat::OneColumn {
            dt: 0.01,
            units: Units::MetersPerSecond2
        }
    );
    let g = s.ground.as_ref().unwrap();
    assert_eq!((g.npts(), g.dt), (9, 0.01));
    assert_eq!(g.accel[2], 1.0);
    // The same with `dt` given through `--set`.
    let s = load_str(
        &with_record("file = \"pulse.txt\""),
        &["ground_motion.dt=0.02"],
    );
    assert!(matches!(
        s.unwrap().ground_source.unwrap().format,
        RecordFormat::OneColumn { dt: 0.02, .. }
    ));
    // Explicit `format = "one-column"` reads the same.
    let s = load_str(
        &with_record("file = \"pulse.txt\"\nformat = \"one-column\"\ndt = 0.01"),
        &[],
    );
    assert!(matches!(
        s.unwrap().ground_source.unwrap().format,
        RecordFormat::OneColumn { dt: 0.01, .. }
    ));
}

#[test]
fn an_explicit_two_column_format_with_dt_is_refused() {
    let text = with_record("file = \"pulse_two_column.txt\"\nformat = \"two-column\"\ndt = 0.02");
    let m = err_has(
        load_str(&text, &[]),
        &[
            "test.toml",
            "key `ground_motion.dt`",
            "format \"two-column\"",
            "time column",
            "remove `dt`",
        ],
    );
    assert!(!m.contains("ground_motion.file"), "{m}");
}

#[test]
fn a_two_column_file_with_dt_and_no_format_is_refused_naming_the_line() {
    // Line 1 of the fixture is a comment: the first line of numbers is line 2.
    let text = with_record("file = \"pulse_two_column.txt\"\ndt = 0.02");
    err_has(
        load_str(&text, &[]),
        &[
            "test.toml",
            "key `ground_motion.dt`",
            "pulse_two_column.txt line 2",
            "every line of numbers holds 2 values",
            "read as one-column because a time step was given without a format",
            "give `ground_motion.format = \"two-column\"` without `dt`",
            "or `format = \"one-column\"` to read every value in order",
        ],
    );
    // Read as one-column on purpose, it is refused by the reader's own check (uniform
    // times), under the record file's key, not `dt` (which the scene gives on purpose).
    let text = with_record("file = \"pulse_two_column.txt\"\nformat = \"one-column\"\ndt = 0.02");
    let m = load_str(&text, &[]).unwrap_err().to_string();
    for part in [
        "key `ground_motion.file`",
        "pulse_two_column.txt line 2",
        "found 2 values on this line",
        "read it as two-column, without a time step",
    ] {
        assert!(m.contains(part), "{m:?} should contain {part:?}");
    }
    assert!(!m.contains("ground_motion.dt"), "{m}");
}

// ---------------------------------------------------------------------------------------
// Contact entries: the `[[contacts]]` entry of every contact (`Contact::entry`)
// ---------------------------------------------------------------------------------------

fn entries(s: &Scene) -> Vec<usize> {
    s.contacts.iter().map(|c| c.entry).collect()
}

#[test]
fn the_aligned_paper_scene_maps_every_contact_to_entry_0() {
    let s = structure::testing::paper_scene_aligned(&[]);
    assert_eq!(s.contacts.len(), 15);
    assert_eq!(entries(&s), vec![0; 15]);
    assert_eq!(s.contact_entries(), vec![(0, (0..15).collect::<Vec<_>>())]);
    // A contact added in code after them, given an entry of its own, is reported as one.
    let mut t = s.clone();
    let mut extra = t.contacts[0].clone();
    extra.left_dof = 0;
    extra.right_dof = 0;
    extra.entry = 1;
    t.contacts.push(extra);
    assert_eq!(t.contact_entries().len(), 2);
    assert_eq!(t.contact_entries()[1], (1, vec![15]));
    // Entries out of order (a scene built in code): grouped in order of first appearance.
    let mut u = t.clone();
    u.contacts.truncate(2);
    u.contacts[0].entry = 1;
    u.contacts[1].entry = 0;
    let mut third = u.contacts[0].clone();
    third.entry = 2;
    u.contacts.push(third);
    assert_eq!(entries(&u), vec![1, 0, 2]);
    assert_eq!(
        u.contact_entries(),
        vec![(1, vec![0]), (0, vec![1]), (2, vec![2])]
    );
    // Two contacts of one entry that are not next to each other are still one group.
    u.contacts[2].entry = 1;
    assert_eq!(u.contact_entries(), vec![(1, vec![0, 2]), (0, vec![1])]);
}

#[test]
fn contact_entries_follow_the_file() {
    // Entry 0: aligned (two contacts, roofs first); entry 1: floor 1 of `b` against a wall.
    let text = TINY
        .replace("left_floor = 2\n", "floors = \"aligned\"\n")
        .replace("right_floor = 2\n", "")
        .replace(
            "[analysis]",
            "[[contacts]]\nleft = \"b\"\nleft_floor = 1\nright = \"wall\"\ngap = 0.01\n\n\
             [analysis]",
        );
    let s = load_str(&text, &[]).unwrap();
    assert_eq!(s.contacts.len(), 3);
    assert_eq!(entries(&s), vec![0, 0, 1]);
    assert_eq!(s.contact_entries(), vec![(0, vec![0, 1]), (1, vec![2])]);
    assert!(s.contacts[2].wall);
    // Two plain entries: one contact each.
    let two = TINY.replace(
        "[analysis]",
        "[[contacts]]\nleft = \"a\"\nleft_floor = 1\nright = \"b\"\nright_floor = 1\n\
         gap = 0.02\n\n[analysis]",
    );
    let s = load_str(&two, &[]).unwrap();
    assert_eq!(entries(&s), vec![0, 1]);
    assert_eq!(s.contact_entries(), vec![(0, vec![0]), (1, vec![1])]);
    assert_eq!(s.contacts[1].gap, 0.02);
}

// ---------------------------------------------------------------------------------------
// Switching an aligned scene to a single roof contact with `--set` (docs/scenes.md)
// ---------------------------------------------------------------------------------------

#[test]
fn an_aligned_entry_becomes_a_roof_contact_with_set() {
    let s = structure::testing::paper_scene_aligned(&[
        "contacts.0.floors=",
        "contacts.0.left_floor=15",
        "contacts.0.right_floor=15",
    ]);
    assert_eq!(s.contacts.len(), 1);
    assert_eq!((s.contacts[0].left_dof, s.contacts[0].right_dof), (14, 14));
    assert_eq!(entries(&s), vec![0]);
    let roof = structure::testing::paper_scene(&[]);
    assert_eq!(s.contacts, roof.contacts);
    // Without removing `floors`, both ways of naming the floors are refused.
    let o = ["contacts.0.left_floor=15".to_string()];
    let path = paper_scene_path().with_file_name("scene-aligned.toml");
    err_has(
        Scene::from_file_with_overrides(&path, &o),
        &["contacts[0].left_floor", "not both"],
    );
    // `--set` cannot add an array entry.
    let o = ["contacts.1.gap=0.1".to_string()];
    err_has(
        Scene::from_file_with_overrides(&path, &o),
        &[
            "index 1 is out of range",
            "`contacts` has 1 entry (index 0)",
        ],
    );
}
