//! Yielding stories in OpenSees (issue 13): `pound export opensees` writes a bilinear story
//! as `Steel01(Fy, E0, b)` on its zeroLength spring, and on a yielding paper scene
//! (aligned-floor contacts, Newmark at 1 ms) OpenSeesPy and pound's Newmark agree on every
//! peak story shear to 1e-6 relative.
//!
//! - Always run: the script's numbers, and pound against the OpenSees reference committed in
//!   `tests/data/opensees-yield-aligned.json` (how it was produced is written in the file).
//! - Opt-in (`cargo test --release -p studies --test yield_opensees -- --ignored`, needs
//!   `pip install openseespy`): runs the exported script and checks it against pound and
//!   against the committed reference.

use std::path::{Path, PathBuf};

use solvers::Method;
use structure::Scene;
use studies::export::{opensees_caveats, opensees_script};

mod common;
use common::{opensees_python, pound, TempDir};

/// Relative agreement required on every peak story shear, drift and ductility: both programs
/// run the same Newmark scheme on the same model, so they differ by round-off (measured 1.6e-12
/// in shears, 3.9e-12 in drifts; the requirement when this was built was 1e-6).
const SHEAR_TOL: f64 = 1e-10;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn reference() -> serde_json::Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/opensees-yield-aligned.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn overrides(r: &serde_json::Value) -> Vec<String> {
    r["overrides"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

fn scene(r: &serde_json::Value) -> Scene {
    let path = root().join(r["scene"].as_str().unwrap());
    Scene::from_file_with_overrides(&path, &overrides(r)).unwrap()
}

/// Largest relative difference of `key` (a per-story array) over the buildings of two
/// result documents.
fn worst(a: &serde_json::Value, b: &serde_json::Value, key: &str) -> f64 {
    let mut w = 0.0f64;
    let (xa, xb) = (a.as_array().unwrap(), b.as_array().unwrap());
    assert_eq!(xa.len(), xb.len());
    for (x, y) in xa.iter().zip(xb) {
        assert_eq!(x["name"], y["name"]);
        let (p, q) = (x[key].as_array().unwrap(), y[key].as_array().unwrap());
        assert_eq!(p.len(), q.len(), "{key}");
        for (p, q) in p.iter().zip(q) {
            let (p, q) = (p.as_f64().unwrap(), q.as_f64().unwrap());
            w = w.max((p - q).abs() / q.abs());
        }
    }
    w
}

#[test]
fn a_bilinear_story_is_exported_as_steel01() {
    let r = reference();
    let s = scene(&r);
    let script = opensees_script(&s).unwrap();
    assert!(
        script.contains("ops.uniaxialMaterial('Steel01', tag, b[\"yield_shear\"][j], k, b[\"hardening_ratio\"])"),
        "the story material"
    );
    // Both buildings carry their yield shears (N) and hardening ratio as literals.
    assert_eq!(script.matches("\"yield_shear\": [").count(), 2);
    assert!(script.contains("50000000.0, 50000000.0"));
    assert_eq!(script.matches("\"hardening_ratio\": 0.02,").count(), 2);
    // A linear scene keeps the Elastic material and says so.
    let mut lin = s.clone();
    for b in &mut lin.buildings {
        b.story_law = structure::model::StoryLaw::Linear;
    }
    let script = opensees_script(&lin).unwrap();
    assert_eq!(script.matches("\"yield_shear\": None,").count(), 2);
}

#[test]
fn an_initial_drift_beyond_yield_is_a_caveat() {
    let r = reference();
    let mut s = scene(&r);
    assert!(
        opensees_caveats(&s).is_empty(),
        "{:?}",
        opensees_caveats(&s)
    );
    // Story 2 of building2: drift 0.02 m against a yield drift 5e7 N / k₂ ≈ 0.01 m or less.
    let k = s.buildings[1].story_stiffness[1];
    assert!(0.02 > 5e7 / k, "the drift is beyond yield");
    s.buildings[1].initial_displacement[0] = 0.0;
    s.buildings[1].initial_displacement[1] = 0.02;
    let w = opensees_caveats(&s);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("building2") && w[0].contains("story 2") && w[0].contains("Steel01"));
}

#[test]
fn pound_newmark_matches_the_committed_opensees_reference() {
    let r = reference();
    let out = solvers::run(&scene(&r), Method::Gap, None).unwrap();
    let doc = serde_json::to_value(&out).unwrap();
    let shear = worst(&doc["buildings"], &r["buildings"], "story_shear_max");
    let drift = worst(&doc["buildings"], &r["buildings"], "story_drift_max");
    let mu = worst(&doc["buildings"], &r["buildings"], "ductility");
    eprintln!("pound vs OpenSees: shear {shear:.2e}, drift {drift:.2e}, ductility {mu:.2e}");
    assert!(shear < SHEAR_TOL, "peak story shears differ by {shear:e}");
    assert!(drift < SHEAR_TOL && mu < SHEAR_TOL, "{drift:e} {mu:e}");
    // The scene really yields, and pounds.
    let mu_max = r["buildings"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|b| b["ductility"].as_array().unwrap().clone())
        .map(|m| m.as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(mu_max > 1.5, "{mu_max}");
    let times: Vec<f64> = out.impacts.iter().map(|i| i.time).collect();
    let ref_times: Vec<f64> = r["impact_times"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert!(!times.is_empty());
    assert_eq!(times.len(), ref_times.len());
    for (a, b) in times.iter().zip(&ref_times) {
        // Both close a contact at the end of the first step with force: same step.
        assert!((a - b).abs() < 0.5e-3, "impact at {a} s vs {b} s");
    }
}

#[test]
#[ignore = "needs OpenSeesPy (pip install openseespy); run with --ignored"]
fn opensees_agrees_with_pound_newmark_on_yielding_stories() {
    let Some(_) = opensees_python() else {
        panic!("openseespy does not import: pip install openseespy");
    };
    let r = reference();
    let d = TempDir::new("opensees-yield");
    let scene_path = root().join(r["scene"].as_str().unwrap());
    let mut sets = Vec::new();
    for o in overrides(&r) {
        sets.push("--set".to_string());
        sets.push(o);
    }
    let mut args = vec![
        "export".to_string(),
        "opensees".into(),
        scene_path.display().to_string(),
    ];
    args.extend(sets.iter().cloned());
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
        "run".to_string(),
        scene_path.display().to_string(),
        "--method".into(),
        "gap".into(),
        "--no-baseline".into(),
        "--out".into(),
        pd_json.display().to_string(),
    ];
    args.extend(sets);
    let out = pound(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (a, b) = (read(&os_json), read(&pd_json));
    assert_eq!(a["method"], "opensees");
    for key in [
        "story_shear_max",
        "story_drift_max",
        "floor_displacement_max",
        "ductility",
    ] {
        let w = worst(&a["buildings"], &b["buildings"], key);
        eprintln!("OpenSees vs pound, {key}: worst relative difference {w:.3e}");
        assert!(w < SHEAR_TOL, "{key}: {w:e}");
        // The committed reference is what this OpenSees run gives (up to the platform's
        // round-off in LAPACK).
        let c = worst(&a["buildings"], &r["buildings"], key);
        assert!(c < 1e-9, "committed reference, {key}: {c:e}");
    }
}
