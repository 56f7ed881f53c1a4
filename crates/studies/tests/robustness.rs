//! The robustness sweep (`pound studies run robustness`, `make robustness`) in its quick
//! form: it runs, is not part of `--all`, and its counts agree with the case files.

mod common;
use common::{pound, quick_study, read_csv, TempDir, STUDIES};

#[test]
fn quick_robustness_sweep_counts_agree_with_the_cases() {
    let d = TempDir::new("robustness");
    let dir = quick_study(&d, "robustness");
    for f in [
        "robustness.csv",
        "robustness.md",
        "summary.md",
        "cases.json",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(
        summary.contains("**Quick run**"),
        "quick results are marked: {summary}"
    );
    let rows = read_csv(&dir.join("robustness.csv"));
    let h = &rows[0];
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    // Quick: 3 records × 1 gap × 2 c_r × 4 methods, in 8 rows of 3 runs.
    assert_eq!(rows.len() - 1, 8);
    let runs: usize = rows[1..]
        .iter()
        .map(|r| r[col("runs")].parse::<usize>().unwrap())
        .sum();
    assert_eq!(runs, 24);
    let sum = |c: &str| -> usize {
        rows[1..]
            .iter()
            .map(|r| r[col(c)].parse::<usize>().unwrap())
            .sum()
    };

    // The same counts from the case files (baselines excluded).
    let cases: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cases.json")).unwrap()).unwrap();
    let cases: Vec<&serde_json::Value> = cases
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["spec"]["params"].get("baseline").is_none())
        .collect();
    assert_eq!(cases.len(), 24);
    let failed = cases.iter().filter(|c| c["status"] != "ok").count();
    assert_eq!(sum("failed"), failed);
    let total = |k: &str| -> usize {
        cases
            .iter()
            .filter_map(|c| c["outputs"][k].as_u64())
            .sum::<u64>() as usize
    };
    assert_eq!(sum("impacts"), total("impacts"));
    assert_eq!(sum("restitution_null"), total("restitution_undefined"));
    assert_eq!(
        sum("restitution_outside_unit"),
        total("restitution_outside_unit")
    );
    assert_eq!(
        sum("impacts_nonpositive_approach"),
        total("impacts_nonpositive_approach")
    );
    // Failures listed one per failed run.
    let listed = if dir.join("failures.csv").is_file() {
        read_csv(&dir.join("failures.csv")).len() - 1
    } else {
        0
    };
    assert_eq!(listed, failed);
    // Counts that are zero on the project's scene are exercised below (failures) or by the
    // solvers' own tests (approach speeds, restitutions); the ones that are not must count.
    assert!(sum("impacts") > 0 && sum("restitution_null") > 0);

    // Not part of --all.
    let o = pound(&["studies", "run", "nope"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("by name only: robustness"), "{err}");
}

/// The failure path of the robustness table: the paper scene without the momentum method's
/// persistent-contact phase stalls at the accumulation point of chattering at c_r = 0.3, for
/// the momentum and the impulse methods on each of the quick run's three records. The sweep
/// exits 4, counts the six failures in its table and lists each once.
#[test]
fn robustness_counts_and_lists_failures() {
    let d = TempDir::new("robustness-fail");
    let data = format!("{STUDIES}/../data/");
    let scene = std::fs::read_to_string(format!("{STUDIES}/paper/scene.toml"))
        .unwrap()
        .replace("[momentum]\n", "[momentum]\npersistent_contact = false\n")
        .replace("\"../../data/", &format!("\"{data}"));
    std::fs::create_dir_all(d.path("defs/paper")).unwrap();
    d.write("defs/paper/scene.toml", &scene);
    let def = std::fs::read_to_string(format!("{STUDIES}/robustness.toml"))
        .unwrap()
        .replace("\"../data/", &format!("\"{data}"));
    d.write("defs/robustness.toml", &def);
    let out = d.path("out");
    let o = common::quick_run(
        "robustness",
        d.path("defs").to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains("Stalled"), "{err}");
    let dir = out.join("robustness");
    let rows = read_csv(&dir.join("robustness.csv"));
    let h = &rows[0];
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let failed: Vec<(String, String, usize)> = rows[1..]
        .iter()
        .map(|r| {
            (
                r[col("method")].clone(),
                r[col("c_r")].clone(),
                r[col("failed")].parse().unwrap(),
            )
        })
        .filter(|r| r.2 > 0)
        .collect();
    assert_eq!(
        failed,
        [
            ("momentum".to_string(), "0.3".to_string(), 3),
            ("impulse".to_string(), "0.3".to_string(), 3)
        ],
        "{rows:?}"
    );
    let listed = read_csv(&dir.join("failures.csv"));
    assert_eq!(listed.len() - 1, 6, "{listed:?}");
}
