//! The model-form study (`pound studies run modelform`) in its quick form: it runs, is part
//! of `--all`, writes its tables and figures, and its tables agree with the case files.

mod common;
use common::{pound, quick_study, read_csv, TempDir};

#[test]
fn quick_modelform_study_runs_and_its_tables_follow_the_cases() {
    let d = TempDir::new("modelform");
    let dir = quick_study(&d, "modelform");
    for f in [
        "modelform.csv",
        "modelform_conclusions.csv",
        "modelform_models.csv",
        "modelform_profiles.png",
        "modelform_profiles.svg",
        "modelform_gap_ratio.png",
        "summary.md",
        "cases.json",
        "peaks.csv",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("**Quick run**"), "{summary}");

    // The sticks: the calibrated pair stiffens toward the roof, the uniform and tapered
    // variants have the ratio they ask for, every variant keeps f1.
    let models = read_csv(&dir.join("modelform_models.csv"));
    let h = &models[0];
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let row = |variant: &str, b: &str| {
        models[1..]
            .iter()
            .find(|r| r[col("variant")] == variant && r[col("building")] == b)
            .unwrap_or_else(|| panic!("no row {variant} {b}"))
            .clone()
    };
    let num = |s: &str| s.parse::<f64>().unwrap();
    assert!(num(&row("calibrated", "building1")[col("k_top / k_ground")]) > 1.0);
    assert_eq!(
        row("uniform", "building2")[col("k_top / k_ground")],
        "1.000"
    );
    assert_eq!(
        row("taper 0.45", "building1")[col("k_top / k_ground")],
        "0.450"
    );
    assert_eq!(row("modes 1 & 3", "building1")[col("f2 (Hz)")], "1.590");
    for v in ["calibrated", "uniform", "taper 0.45", "modes 1 & 3"] {
        assert_eq!(row(v, "building1")[col("f1 (Hz)")], "0.670");
        assert_eq!(row(v, "building2")[col("f1 (Hz)")], "0.810");
    }
    // Rayleigh through modes 1 and 3: the target there, less between, more above.
    let r = row("Rayleigh", "building1");
    assert_eq!(r[col("ζ1")], "0.0500");
    assert_eq!(r[col("ζ3")], "0.0500");
    assert!(num(&r[col("ζ2")]) < 0.05 && num(&r[col("ζ4")]) > 0.05);

    // Every case finished; the every-floor cases have 15 contacts and share the roof-only
    // baseline (a run without any contact).
    let cases: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cases.json")).unwrap()).unwrap();
    let cases = cases.as_array().unwrap();
    assert!(cases.iter().all(|c| c["status"] == "ok"));
    let every: Vec<&serde_json::Value> = cases
        .iter()
        .filter(|c| c["spec"]["params"]["model"] == "every floor")
        .collect();
    assert!(!every.is_empty());
    for c in &every {
        let set = c["spec"]["set"].as_array().unwrap();
        let contacts = set
            .iter()
            .find_map(|s| s.as_str().unwrap().strip_prefix("contacts="))
            .expect("a contacts list override");
        assert_eq!(contacts.matches("left_floor").count(), 15, "{contacts}");
    }
    for c in cases
        .iter()
        .filter(|c| c["spec"]["params"].get("baseline").is_some())
    {
        assert!(
            c["spec"]["set"]
                .as_array()
                .unwrap()
                .iter()
                .all(|s| !s.as_str().unwrap().starts_with("contacts=")),
            "a baseline keeps a contact list: {c}"
        );
        assert_eq!(c["outputs"]["impacts"], 0, "a baseline with impacts: {c}");
    }

    // The amplification table's top-story momentum value is the case's peak shear over its
    // baseline's (headline record, first gap, c_r = 1, calibrated).
    let amp = read_csv(&dir.join("modelform.csv"));
    let h = &amp[0];
    let col = |name: &str| h.iter().position(|x| x == name).unwrap();
    let first = &amp[1];
    assert_eq!(first[col("variant")], "calibrated");
    let momentum = cases
        .iter()
        .find(|c| {
            c["spec"]["params"]["model"] == "calibrated"
                && c["spec"]["params"]["variant"] == "calibrated: momentum, all modes"
                && c["spec"]["params"]["gap_m"].as_f64() == Some(num(&first[col("gap (m)")]))
        })
        .unwrap();
    let base = cases
        .iter()
        .find(|c| {
            c["spec"]["params"].get("baseline").is_some()
                && c["spec"]["method"] == "momentum"
                && c["spec"]["set"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .all(|s| !s.as_str().unwrap().starts_with("buildings."))
                && c["spec"]["set"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .all(|s| !s.as_str().unwrap().starts_with("momentum.modes"))
        })
        .unwrap();
    let top = |c: &serde_json::Value| {
        c["outputs"]["story_shear_max"][0]
            .as_array()
            .unwrap()
            .last()
            .unwrap()
            .as_f64()
            .unwrap()
    };
    let want = format!("{:.2}", top(momentum) / top(base));
    assert_eq!(first[col("top b1 momentum")], want);

    // Listed among the studies `--all` runs.
    let o = pound(&["studies", "run", "nope"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("modelform"), "{err}");
}

#[test]
fn a_variant_the_scene_refuses_is_a_bad_definition() {
    let d = TempDir::new("modelform-bad");
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../studies");
    let def = std::fs::read_to_string(format!("{root}/modelform.toml"))
        .unwrap()
        .replace(
            "\"paper/scene.toml\"",
            &format!("\"{root}/paper/scene.toml\""),
        )
        .replace("\"../data/", &format!("\"{root}/../data/"))
        .replace("top_stiffness_ratio=0.45\"", "top_stiffnes_ratio=0.45\"");
    d.write("modelform.toml", &def);
    let out = d.path("results");
    let o = common::quick_run(
        "modelform",
        d.path("").to_str().unwrap(),
        out.to_str().unwrap(),
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("variant `taper 0.45`") && err.contains("top_stiffnes_ratio"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
    assert!(o.stdout.is_empty());
}
