//! Yielding stories (issue 13) through the `pound` binary: the momentum method refuses a
//! building with `story_law = "bilinear"` (exit 2, naming the building and the methods that
//! apply, no output file).

mod common;
use common::{pound, TempDir};

const PAPER: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../studies/paper/scene.toml"
);

#[test]
fn momentum_refuses_a_yielding_building() {
    let dir = TempDir::new("yield-refuse");
    let out = dir.0.join("run.json");
    let o = pound(&[
        "run",
        PAPER,
        "--method",
        "momentum",
        "--set",
        "buildings.1.story_law=bilinear",
        "--set",
        "buildings.1.yield_shear=2e6",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    for part in ["building2", "yielding", "--method gap", "--method impulse"] {
        assert!(err.contains(part), "stderr {err:?} should contain {part:?}");
    }
    assert!(!out.exists(), "no output file on a refusal");
}

/// `pound run --method gap` on a yielding paper scene (aligned-floor contacts, both
/// buildings bilinear): exit 0; the JSON carries per-story peak drift, ductility and
/// residual drift, the hysteretic energy per building and in the energy audit (whose
/// balance closes), and the history CSV's story shears are the law's (bounded by the
/// hardening branch, not k·drift), for both integrators.
#[test]
fn gap_runs_a_yielding_scene_with_ductility_and_hysteretic_energy_in_the_json() {
    let aligned = PAPER.replace("scene.toml", "scene-aligned.toml");
    for integrator in ["adaptive", "newmark"] {
        let dir = TempDir::new("yield-run");
        let out = dir.0.join("run.json");
        let hist = dir.0.join("history.csv");
        let o = pound(&[
            "run",
            &aligned,
            "--method",
            "gap",
            "--set",
            &format!("gap_element.integrator={integrator}"),
            "--set",
            "buildings.0.story_law=bilinear",
            "--set",
            "buildings.0.yield_shear=3e7",
            "--set",
            "buildings.1.story_law=bilinear",
            "--set",
            "buildings.1.yield_shear=3e7",
            "--set",
            "analysis.duration=8",
            "--out",
            out.to_str().unwrap(),
            "--history",
            hist.to_str().unwrap(),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{integrator}: stderr {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let e = &v["energy"];
        let (input, hyst) = (
            e["input"].as_f64().unwrap(),
            e["hysteretic"].as_f64().unwrap(),
        );
        assert!(hyst > 0.0 && hyst < input, "{integrator}: {e}");
        // The Newton residuals' work is Newmark's alone (its key absent for the adaptive
        // integrator); with yield kinks it is not the whole balance error.
        assert_eq!(
            e.get("residual_work").is_some_and(|w| w.is_f64()),
            integrator == "newmark",
            "{integrator}: {e}"
        );
        // Adaptive: the error control, 10 × the default rtol 1e-8 (measured 3.0e-8).
        // Newmark: a discretisation error of order Δt² where a step crosses a yield kink
        // (measured 3.9e-6 at Δt = 1 ms).
        let bound = if integrator == "adaptive" { 1e-7 } else { 1e-5 };
        assert!(
            e["balance_error"].as_f64().unwrap().abs() < bound * input,
            "{integrator}: {e}"
        );
        let mut sum = 0.0;
        let mut mu_max: f64 = 0.0;
        for (bi, b) in v["buildings"].as_array().unwrap().iter().enumerate() {
            let n = b["story_shear_max"].as_array().unwrap().len();
            let drift = b["story_drift_max"].as_array().unwrap();
            let mu = b["ductility"].as_array().unwrap();
            assert_eq!((drift.len(), mu.len()), (n, n));
            assert_eq!(b["residual_drift"].as_array().unwrap().len(), n);
            // ductility = peak drift / (F_y / k₀), F_y = 3e7 N for every story.
            let k: Vec<f64> = serde_json::from_value(
                v["resolved_scene"]["buildings"][bi]["story_stiffness"].clone(),
            )
            .unwrap();
            for j in 0..n {
                let (d, m) = (drift[j].as_f64().unwrap(), mu[j].as_f64().unwrap());
                assert!(
                    (m - d / (3e7 / k[j])).abs() <= 1e-12 * m,
                    "{integrator}: {b}"
                );
                mu_max = mu_max.max(m);
            }
            sum += b["hysteretic_energy"].as_f64().unwrap();
        }
        assert!(mu_max > 1.0, "{integrator}: the stories yield ({mu_max})");
        assert!(
            (sum - hyst).abs() <= 1e-9 * hyst,
            "{integrator}: {sum} vs {hyst}"
        );
        // The history's story shears are the law's: never above F_y (1 + b (μ − 1)) (b = 0.02,
        // the default), where k·drift would reach μ F_y.
        let csv = std::fs::read_to_string(&hist).unwrap();
        let mut lines = csv.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|h| h.trim_matches('"').to_string())
            .collect();
        let cols: Vec<usize> = (0..header.len())
            .filter(|&i| header[i].contains("_V") && header[i].ends_with("_N"))
            .collect();
        assert!(!cols.is_empty(), "{header:?}");
        let bound = 3e7 * (1.0 + 0.02 * (mu_max - 1.0)) * (1.0 + 1e-9);
        let mut rows = 0;
        let mut v_max: f64 = 0.0;
        for line in lines {
            let f: Vec<&str> = line.split(',').collect();
            for &c in &cols {
                v_max = v_max.max(f[c].trim_matches('"').parse::<f64>().unwrap().abs());
            }
            rows += 1;
        }
        assert!(rows > 100, "{integrator}: {rows} rows");
        assert!(
            v_max > 3e7 * (1.0 - 1e-6) && v_max <= bound,
            "{integrator}: history shear {v_max} vs yield 3e7, bound {bound}"
        );
    }
}

/// The `pound run` summary of a yielding run: drift, ductility and residual drift columns,
/// the hysteretic energy per building and in the energy line.
#[test]
fn the_run_summary_shows_ductility_and_hysteretic_energy() {
    let o = pound(&[
        "run",
        PAPER,
        "--method",
        "gap",
        "--no-baseline",
        "--set",
        "buildings.1.story_law=bilinear",
        "--set",
        "buildings.1.yield_shear=3e7",
        "--set",
        "analysis.duration=6",
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for part in [
        "drift max (m)",
        "ductility",
        "residual drift (m)",
        "hysteretic energy (J):",
        ", hysteretic ",
        "story kinks",
    ] {
        assert!(stdout.contains(part), "summary lacks {part:?}:\n{stdout}");
    }
}

/// The history CSV of a yielding building: the absolute floor accelerations come from the
/// law's story forces (a = −(V_j − V_{j+1})/m_j without damping and ground motion), so they
/// agree with the rate of the recorded floor velocities (central differences over the 1 ms
/// samples of free vibration: O((ω Δt)²) ≈ 1e-3 relative away from the yield kinks, O(Δt)
/// at them). With k·drift in place of the law's force they would be off by up to the
/// ductility (here about 3).
#[test]
fn history_accelerations_of_a_yielding_building_follow_the_law() {
    let dir = TempDir::new("yield-history");
    let scene = dir.write(
        "osc.toml",
        r#"name = "two-story bilinear oscillator"

[[buildings]]
name = "osc"
masses = [1.0e5, 1.0e5]
story_stiffness = [4.0e7, 3.0e7]
damping_ratio = 0.0
initial_velocity = [0.25, 0.4]
story_law = "bilinear"
yield_shear = [1.0e5, 8.0e4]
hardening_ratio = 0.05

[analysis]
duration = 1.0
"#,
    );
    let (out, hist) = (dir.0.join("run.json"), dir.0.join("history.csv"));
    let o = pound(&[
        "run",
        scene.to_str().unwrap(),
        "--method",
        "gap",
        "--set",
        "gap_element.tolerance=1e-10",
        "--out",
        out.to_str().unwrap(),
        "--history",
        hist.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let mu = v["buildings"][0]["ductility"].as_array().unwrap()[1]
        .as_f64()
        .unwrap();
    assert!(mu > 2.0, "the upper story yields well: {mu}");

    let csv = std::fs::read_to_string(&hist).unwrap();
    let mut lines = csv.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|h| h.trim_matches('"').to_string())
        .collect();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (t, v2, a2) = (
        col("time_s"),
        col("osc_v2_m_per_s"),
        col("osc_a2_abs_m_per_s2"),
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|x| x.trim_matches('"').parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    // Record points only (kink instants sit between them): a 1 ms grid.
    let grid: Vec<&Vec<f64>> = rows
        .iter()
        .filter(|r| ((r[t] * 1e3).round() - r[t] * 1e3).abs() < 1e-6)
        .collect();
    let a_max = grid.iter().map(|r| r[a2].abs()).fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for w in grid.windows(3) {
        let fd = (w[2][v2] - w[0][v2]) / (w[2][t] - w[0][t]);
        worst = worst.max((fd - w[1][a2]).abs() / a_max);
    }
    eprintln!("finite difference vs CSV acceleration: worst {worst:.2e} of the peak");
    assert!(
        worst < 2e-2,
        "finite difference vs CSV acceleration: {worst:e}"
    );
}
