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
