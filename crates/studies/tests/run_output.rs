//! `pound run --out` says what was run (version, overrides, record) and reports the
//! amplification factors from a run of the same model without contact.

mod common;
use common::{pound, TempDir};

fn scene() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../studies/paper/scene.toml"
    )
    .to_string()
}

#[test]
fn run_json_has_provenance_and_amplification() {
    let d = TempDir::new("runjson");
    let out = d.path("run.json");
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "momentum",
        "--set",
        "contacts.0.gap=0.05",
        "--set",
        "analysis.duration=12",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(
        v["overrides"],
        serde_json::json!(["contacts.0.gap=0.05", "analysis.duration=12"])
    );
    let file = v["record"]["file"].as_str().unwrap();
    assert!(std::path::Path::new(file).is_absolute() && file.ends_with("RSN752_LOMAP_CAP000.AT2"));
    assert_eq!(v["record"]["pga_g"], 0.4);
    // Amplification = peak story shear with contact / without; recompute the denominator.
    let free = d.path("free.json");
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "momentum",
        "--set",
        "contacts.0.gap=1000",
        "--set",
        "analysis.duration=12",
        "--no-baseline",
        "--out",
        free.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&free).unwrap()).unwrap();
    assert!(f.get("amplification").is_none(), "--no-baseline skips it");
    for b in 0..2 {
        let amp = v["amplification"][b]["story_shear"].as_array().unwrap();
        let with = v["buildings"][b]["story_shear_max"].as_array().unwrap();
        let without = f["buildings"][b]["story_shear_max"].as_array().unwrap();
        assert_eq!(amp.len(), 15);
        for ((a, w), wo) in amp.iter().zip(with).zip(without) {
            let expect = w.as_f64().unwrap() / wo.as_f64().unwrap();
            assert!(
                (a.as_f64().unwrap() - expect).abs() <= 1e-12 * expect,
                "{a} vs {expect}"
            );
        }
    }
    // The printed summary has the column too.
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "gap",
        "--set",
        "analysis.duration=12",
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("amplification"));
}

/// `--out` onto a read-only file fails (exit 1) and leaves it as it was; the history written
/// before is removed: all or nothing.
#[test]
fn read_only_out_is_not_replaced_and_nothing_is_left_behind() {
    let d = TempDir::new("readonly");
    let out = d.write("run.json", "keep me\n");
    let mut perm = std::fs::metadata(&out).unwrap().permissions();
    perm.set_readonly(true);
    std::fs::set_permissions(&out, perm).unwrap();
    let hist = d.path("history.csv");
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "momentum",
        "--set",
        "analysis.duration=2",
        "--history",
        hist.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("read-only") && err.contains("run.json"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "keep me\n");
    assert!(!hist.exists(), "history left behind");
}
