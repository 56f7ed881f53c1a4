//! `pound export opensees`: the script is valid Python, carries the model's numbers as
//! literals, the CLI prints it (exit 0) or refuses a scene it cannot express (exit 2).
//!
//! An opt-in test (`cargo test -p studies --test export -- --ignored`) runs the script with
//! OpenSeesPy (`pip install openseespy`) and compares it with `pound run --method gap` at the
//! same fixed Newmark step.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use structure::scene::ContactLaw;
use structure::testing::paper_scene_path;
use structure::{GroundMotion, RecordFormat, Scene};
use studies::export::{opensees_caveats, opensees_script, ExportError};

mod common;
use common::{opensees_python, pound, TempDir};

fn records_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/ground-motions")
}

fn paper() -> Scene {
    Scene::from_file(&paper_scene_path()).unwrap()
}

/// A small two-building scene on the Capitola record (10 s), fixed-step Newmark.
fn small_scene_text(law: &str) -> String {
    format!(
        r#"name = "small"

[[buildings]]
name = "a"
masses = [1.0e5, 1.0e5, 1.0e5]
story_stiffness = [2.0e8, 1.8e8, 1.5e8]
damping_ratio = 0.05

[[buildings]]
name = "b"
masses = [2.0e5, 2.0e5]
story_stiffness = [6.0e8, 5.0e8]
damping_ratio = [0.02, 0.04]

[[contacts]]
left = "a"
left_floor = 2
right = "b"
right_floor = 2
gap = 0.005
restitution = 0.7

[ground_motion]
file = {file:?}
pga = 0.5

[analysis]
duration = 10.0

[gap_element]
stiffness = 1.0e9
law = "{law}"
integrator = "newmark"
time_step = 0.001
"#,
        file = records_dir()
            .join("RSN752_LOMAP_CAP000.AT2")
            .display()
            .to_string(),
    )
}

fn small(law: &str, sets: &[&str]) -> Scene {
    let o: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::from_str_with_overrides(&small_scene_text(law), "small.toml", Path::new("."), &o)
        .unwrap()
}

fn python3() -> Option<&'static str> {
    let ok = Command::new("python3")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    ok.then_some("python3")
}

/// Asserts that `script` parses as Python (skips, saying so, without python3).
#[track_caller]
fn assert_valid_python(script: &str, what: &str) {
    let Some(py) = python3() else {
        eprintln!("SKIPPED: python3 is not installed, cannot check that the {what} script parses");
        return;
    };
    let d = TempDir::new("ast");
    let f = d.write("model.py", script);
    let out = Command::new(py)
        .args([
            "-c",
            "import ast,sys; ast.parse(open(sys.argv[1]).read(), sys.argv[1])",
        ])
        .arg(&f)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "the {what} script is not valid Python: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The Python list literal assigned to `name` (its text between the brackets).
fn py_list<'a>(script: &'a str, name: &str) -> &'a str {
    let start = script
        .find(&format!("\n{name} = ["))
        .unwrap_or_else(|| panic!("{name} is not in the script"));
    let rest = &script[start + name.len() + 5..];
    &rest[..rest.find(']').unwrap()]
}

fn floats(list: &str) -> Vec<f64> {
    list.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().unwrap())
        .collect()
}

fn lit(x: f64) -> String {
    format!("{x:?}")
}

// ---------------------------------------------------------------------------------------

#[test]
fn paper_script_is_valid_python() {
    assert_valid_python(&opensees_script(&paper()).unwrap(), "paper scene");
}

#[test]
fn other_scripts_are_valid_python() {
    for (what, scene) in [
        ("kelvin-voigt", small("kelvin-voigt", &[])),
        ("linear", small("linear", &[])),
        ("zero gap", small("linear", &["contacts.0.gap=0"])),
        (
            "initial conditions",
            small(
                "linear",
                &[
                    "buildings.0.initial_velocity=[0.1, 0.2, 0.3]",
                    "buildings.1.initial_displacement=[0.01, 0.02]",
                ],
            ),
        ),
    ] {
        assert_valid_python(&opensees_script(&scene).unwrap(), what);
    }
    // Free vibration, no contact, a name that needs escaping.
    let text = "name = \"it's a \\\"test\\\" \\\\ \"\n[[buildings]]\nname = \"solo\"\nmasses = [1.0]\nstory_stiffness = [4.0]\ninitial_displacement = [0.1]\n[analysis]\nduration = 1.0\n";
    let s = Scene::from_str_with_overrides(text, "free.toml", Path::new("."), &[]).unwrap();
    let script = opensees_script(&s).unwrap();
    assert!(script.contains("RECORD_NPTS = 0"));
    assert!(script.contains("CONTACTS = [\n]"));
    assert_valid_python(&script, "free-vibration");
}

#[test]
fn script_carries_the_models_numbers() {
    let scene = paper();
    let script = opensees_script(&scene).unwrap();
    for b in &scene.buildings {
        assert!(script.contains(&format!("\"name\": \"{}\"", b.name)));
        for m in &b.masses {
            assert!(script.contains(&lit(*m)), "mass {m}");
        }
        for k in &b.story_stiffness {
            assert!(script.contains(&lit(*k)), "story stiffness {k}");
        }
        // Every mode's frequency, as pound computes it.
        for w in b.modes().unwrap().omega {
            assert!(script.contains(&lit(w)), "omega {w}");
        }
    }
    let c = &scene.contacts[0];
    assert!(script.contains(&format!("\"gap\": {}", lit(c.gap))));
    assert!(script.contains(&format!("\"left_floor\": {}", c.left_dof + 1)));
    assert!(script.contains(&format!(
        "\"stiffness\": {}",
        lit(scene.gap_element.stiffness)
    )));
    assert!(script.contains("'ElasticPPGap'"));
    assert!(script.contains("\"law\": \"linear\""));
    assert!(script.contains(&format!(
        "DT = DURATION / N_STEPS  # s (gap_element.time_step = {})",
        lit(scene.gap_element.time_step)
    )));
    assert!(script.contains(&format!("DURATION = {}", lit(scene.duration))));
    let nsteps = (scene.duration / scene.gap_element.time_step).ceil() as u64;
    assert!(script.contains(&format!("N_STEPS = {nsteps}  #")));

    // The record: every value, in g as read, the dt, and the factor G × scale.
    let src = scene.ground_source.as_ref().unwrap();
    let raw = GroundMotion::load(&src.file, &src.format).unwrap();
    let values = floats(py_list(&script, "RECORD_G"));
    assert_eq!(values.len(), raw.npts());
    assert!(script.contains(&format!("RECORD_NPTS = {}\n", raw.npts())));
    assert!(script.contains(&format!("RECORD_DT = {}", lit(raw.dt))));
    assert!(script.contains(&format!(
        "RECORD_FACTOR = {}",
        lit(structure::G * src.factor)
    )));
    let g = scene.ground.as_ref().unwrap();
    for (i, v) in values.iter().enumerate() {
        let a = v * structure::G * src.factor;
        assert!(
            (a - g.accel[i]).abs() <= 1e-12 * g.pga(),
            "sample {i}: {a} vs {}",
            g.accel[i]
        );
    }
    assert_eq!(src.format, RecordFormat::At2);
    assert!(script.contains("ops.timeSeries('Path', 1, '-dt', RECORD_DT, '-values', *RECORD_G, '-factor', RECORD_FACTOR)"));
    assert!(script.contains("ops.pattern('UniformExcitation', 1, 1, '-accel', 1)"));
    assert!(script.contains("ops.model('basic', '-ndm', 1, '-ndf', 1)"));
    assert!(script.contains("ops.integrator('Newmark', 0.5, 0.25)"));
    assert!(script.contains("ops.algorithm('Newton')"));
    assert!(script.contains("ops.modalDamping(*MODAL_DAMPING)"));
    assert!(script.contains("\"method\": \"opensees\""));
}

#[test]
fn modal_damping_ratios_follow_the_combined_mode_order() {
    // Building a: 5 % everywhere; building b: 2 % then 4 %. The combined list is sorted by
    // frequency and each ratio belongs to its building's mode.
    let scene = small("linear", &[]);
    let script = opensees_script(&scene).unwrap();
    let omega = floats(py_list(&script, "MODAL_OMEGA"));
    let zeta = floats(py_list(&script, "MODAL_DAMPING"));
    let owner = floats(py_list(&script, "MODAL_BUILDING"));
    assert_eq!(omega.len(), 5);
    assert_eq!(zeta.len(), 5);
    assert!(omega.windows(2).all(|w| w[0] <= w[1]));
    let mut expect = Vec::new();
    for (bi, b) in scene.buildings.iter().enumerate() {
        let m = b.modes().unwrap();
        for (w, z) in m.omega.iter().zip(&m.zeta) {
            expect.push((*w, *z, bi as f64));
        }
    }
    expect.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (i, (w, z, b)) in expect.into_iter().enumerate() {
        assert_eq!((omega[i], zeta[i], owner[i]), (w, z, b), "mode {i}");
    }
}

#[test]
fn kelvin_voigt_dashpot_and_caveat() {
    let scene = small("kelvin-voigt", &[]);
    let script = opensees_script(&scene).unwrap();
    assert!(script.contains("'ViscoelasticGap'"));
    // c = 2 ξ √(k m_eff), ξ from c_r = 0.7 (Anagnostopoulos), m_eff of 1e5 and 2e5 kg.
    let xi = solvers::gap::law::kelvin_voigt_xi(0.7);
    let c = 2.0 * xi * (1.0e9_f64 * (1.0e5 * 2.0e5 / 3.0e5)).sqrt();
    assert!(
        script.contains(&format!("\"dashpot\": {}", lit(c))),
        "c = {c}"
    );
    assert!(script.contains("\"restitution\": 0.7"));
    // Clamped (tension = false) is approximated: a caveat; tension = true is exact.
    let caveats = opensees_caveats(&scene);
    assert_eq!(caveats.len(), 1);
    assert!(caveats[0].contains("tension"));
    assert!(opensees_caveats(&small("kelvin-voigt", &["gap_element.tension=true"])).is_empty());
    assert!(opensees_caveats(&small("linear", &[])).is_empty());
}

#[test]
fn hertz_damp_is_refused() {
    let scene = small("hertz-damp", &[]);
    let e = opensees_script(&scene).unwrap_err();
    assert!(matches!(e, ExportError::Unsupported { .. }));
    let m = e.to_string();
    assert!(
        m.contains("hertz-damp") && m.contains("gap_element.law"),
        "{m}"
    );
    // Without contacts the law does not matter.
    let mut free = scene.clone();
    free.contacts.clear();
    assert_eq!(free.gap_element.law, ContactLaw::HertzDamp);
    assert!(opensees_script(&free).is_ok());
}

#[test]
fn tied_frequencies_with_different_damping_are_refused() {
    let text = r#"
[[buildings]]
name = "twin1"
masses = [1.0e5, 1.0e5]
story_stiffness = [1.0e8, 1.0e8]
damping_ratio = 0.02
[[buildings]]
name = "twin2"
masses = [1.0e5, 1.0e5]
story_stiffness = [1.0e8, 1.0e8]
damping_ratio = 0.05
[analysis]
duration = 1.0
"#;
    let s = Scene::from_str_with_overrides(text, "twins.toml", Path::new("."), &[]).unwrap();
    let m = opensees_script(&s).unwrap_err().to_string();
    assert!(
        m.contains("twin1") && m.contains("twin2") && m.contains("modalDamping"),
        "{m}"
    );
    // Same ratio: no ambiguity.
    let o = vec!["buildings.1.damping_ratio=0.02".to_string()];
    let s = Scene::from_str_with_overrides(text, "twins.toml", Path::new("."), &o).unwrap();
    assert!(opensees_script(&s).is_ok());
}

// ---------------------------------------------------------------------------------------
// Through the binary
// ---------------------------------------------------------------------------------------

#[test]
fn cli_prints_the_script() {
    let path = paper_scene_path();
    let out = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--set",
        "contacts.0.gap=0.05",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let script = String::from_utf8(out.stdout).unwrap();
    assert!(script.starts_with("#!/usr/bin/env python3\n"));
    assert!(script.contains("\"gap\": 0.05"), "the override is applied");
    assert!(script.contains("SCENE = \"paper-pair\""));
    // The paper scene's gap element is adaptive: the Newmark script says so.
    assert!(
        stderr.contains("integrates with Newmark") && stderr.contains("adaptive"),
        "{stderr}"
    );
    assert_valid_python(&script, "CLI");
    let newmark = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--set",
        "gap_element.integrator=newmark",
    ]);
    let stderr = String::from_utf8_lossy(&newmark.stderr);
    assert_eq!(newmark.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.is_empty(),
        "no warnings for the linear law with Newmark: {stderr}"
    );
}

#[test]
fn cli_warns_about_clamped_kelvin_voigt() {
    let path = paper_scene_path();
    let out = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--set",
        "gap_element.law=kelvin-voigt",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with("warning:") && stderr.contains("tension"),
        "{stderr}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("'ViscoelasticGap'"));
}

#[test]
fn cli_refuses_hertz_damp_with_exit_2() {
    let path = paper_scene_path();
    let out = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--set",
        "gap_element.law=hertz-damp",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("hertz-damp") && stderr.contains("gap_element.law"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
    assert!(out.stdout.is_empty(), "no partial script on stdout");
}

/// `--out`: the script goes to the file; a refused scene writes nothing.
#[test]
fn cli_out_writes_the_script_or_nothing() {
    let d = common::TempDir::new("export-out");
    let path = paper_scene_path();
    let file = d.path("model.py");
    let out = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--out",
        file.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty());
    assert!(std::fs::read_to_string(&file)
        .unwrap()
        .contains("import openseespy"));
    let refused = d.path("refused.py");
    let out = pound(&[
        "export",
        "opensees",
        path.to_str().unwrap(),
        "--set",
        "gap_element.law=hertz-damp",
        "--out",
        refused.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!refused.exists(), "nothing written when refused");
}

#[test]
fn cli_help_lists_export() {
    let out = pound(&["export", "--help"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("opensees"));
}

// ---------------------------------------------------------------------------------------
// Opt-in: run the script with OpenSeesPy
// ---------------------------------------------------------------------------------------

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
#[ignore = "needs OpenSeesPy (pip install openseespy); run with --ignored"]
fn opensees_agrees_with_pound_newmark() {
    let Some(_) = opensees_python() else {
        panic!("openseespy does not import: pip install openseespy");
    };
    let d = TempDir::new("opensees");
    for (law, sets) in [
        ("linear", vec![]),
        ("kelvin-voigt", vec!["gap_element.tension=true"]),
        (
            "linear",
            vec![
                "buildings.0.initial_velocity=[0.1, 0.2, 0.3]",
                "buildings.1.initial_displacement=[-0.01, 0.02]",
            ],
        ),
    ] {
        let scene = d.write("small.toml", &small_scene_text(law));
        let mut set_args = Vec::new();
        for s in &sets {
            set_args.push("--set");
            set_args.push(s);
        }
        let mut args = vec!["export", "opensees", scene.to_str().unwrap()];
        args.extend(&set_args);
        let out = pound(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let script = d.write("model.py", &String::from_utf8(out.stdout).unwrap());
        let os_json = d.0.join("opensees.json");
        let run = opensees_python()
            .unwrap()
            .arg(&script)
            .arg(&os_json)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );

        let pd_json = d.0.join("pound.json");
        let mut args = vec![
            "run",
            scene.to_str().unwrap(),
            "--method",
            "gap",
            "--set",
            "gap_element.integrator=newmark",
            "--out",
            pd_json.to_str().unwrap(),
        ];
        args.extend(&set_args);
        let out = pound(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );

        let (a, b) = (json(&os_json), json(&pd_json));
        assert_eq!(a["method"], "opensees");
        let mut worst = 0.0_f64;
        for (x, y) in a["buildings"]
            .as_array()
            .unwrap()
            .iter()
            .zip(b["buildings"].as_array().unwrap())
        {
            assert_eq!(x["name"], y["name"]);
            for key in ["story_shear_max", "floor_displacement_max"] {
                for (p, q) in x[key]
                    .as_array()
                    .unwrap()
                    .iter()
                    .zip(y[key].as_array().unwrap())
                {
                    let (p, q) = (p.as_f64().unwrap(), q.as_f64().unwrap());
                    worst = worst.max((p - q).abs() / q.abs());
                }
            }
        }
        // The same Newmark scheme on the same model: round-off (docs/cli.md: 2.0e-12,
        // 1.8e-10 and 1.9e-12 for these three scenes), as the wall's test asks.
        eprintln!("{law} {sets:?}: worst relative difference {worst:.3e}");
        assert!(worst < 1e-8, "{law} {sets:?}: {worst}");
        let (na, nb) = (
            a["impacts"].as_array().unwrap().len(),
            b["impacts"].as_array().unwrap().len(),
        );
        assert!(na > 0 && na == nb, "impacts {na} vs {nb}");
    }
}

/// A building name is user text: in the script it is always a quoted, escaped Python string,
/// so a newline in a name cannot end a comment and start code.
#[test]
fn names_cannot_inject_code_into_the_script() {
    let evil = r#""a\n__import__('os').system('echo PWNED'),#""#;
    let o: Vec<String> = vec![
        format!("buildings.0.name={evil}"),
        format!("contacts.0.left={evil}"),
        "gap_element.law=linear".into(),
    ];
    let scene = Scene::from_file_with_overrides(&paper_scene_path(), &o).unwrap();
    assert!(scene.buildings[0].name.contains('\n'));
    let script = opensees_script(&scene).unwrap();
    for line in script.lines() {
        assert!(
            !line.trim_start().starts_with("__import__"),
            "a name became code: {line}"
        );
    }
    assert!(script.contains(r#""a\n__import__('os').system('echo PWNED'),#""#));
}
