//! Scene keys of yielding stories (issue 13): `story_law`, `yield_shear`, `hardening_ratio`
//! on a building, their defaults, the errors that name the key, and the resolved parameters.

use structure::model::story_law::DEFAULT_HARDENING_RATIO;
use structure::model::StoryLaw;
use structure::testing::paper_scene_path;
use structure::{Scene, SceneError};

fn load_paper(overrides: &[&str]) -> Result<Scene, SceneError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_file_with_overrides(&paper_scene_path(), &o)
}

#[track_caller]
fn err_has(r: Result<Scene, SceneError>, parts: &[&str]) {
    let msg = match r {
        Ok(_) => panic!("expected an error containing {parts:?}, the scene loaded"),
        Err(e) => e.to_string(),
    };
    for p in parts {
        assert!(msg.contains(p), "error {msg:?} should contain {p:?}");
    }
}

#[test]
fn linear_is_the_default() {
    let s = load_paper(&[]).unwrap();
    for b in &s.buildings {
        assert_eq!(b.story_law, StoryLaw::Linear);
        assert!(!b.story_law.is_yielding());
        assert!(b.story_law.bilinear_params(&b.story_stiffness).is_none());
    }
}

#[test]
fn bilinear_with_one_yield_shear_and_the_default_hardening() {
    let s = load_paper(&[
        "buildings.0.story_law=bilinear",
        "buildings.0.yield_shear=2.5e6",
    ])
    .unwrap();
    let b = &s.buildings[0];
    let n = b.n_floors();
    assert_eq!(
        b.story_law,
        StoryLaw::Bilinear {
            yield_shear: vec![2.5e6; n],
            hardening_ratio: DEFAULT_HARDENING_RATIO
        }
    );
    assert!(b.story_law.is_yielding());
    let p = b.story_law.bilinear_params(&b.story_stiffness).unwrap();
    assert_eq!(p.len(), n);
    for (j, q) in p.iter().enumerate() {
        assert_eq!(q.stiffness, b.story_stiffness[j]);
        assert_eq!(q.yield_shear, 2.5e6);
        assert_eq!(q.hardening_ratio, 0.02);
    }
    // The other building stays linear.
    assert_eq!(s.buildings[1].story_law, StoryLaw::Linear);
}

#[test]
fn bilinear_per_story_and_explicit_hardening() {
    let s = load_paper(&[]).unwrap();
    let n = s.buildings[1].n_floors();
    let list: Vec<String> = (0..n).map(|j| format!("{}e6", j + 1)).collect();
    let set_list = format!("buildings.1.yield_shear=[{}]", list.join(", "));
    let s = load_paper(&[
        "buildings.1.story_law=bilinear",
        &set_list,
        "buildings.1.hardening_ratio=0.1",
    ])
    .unwrap();
    match &s.buildings[1].story_law {
        StoryLaw::Bilinear {
            yield_shear,
            hardening_ratio,
        } => {
            assert_eq!(yield_shear.len(), n);
            assert_eq!(yield_shear[n - 1], n as f64 * 1e6);
            assert_eq!(*hardening_ratio, 0.1);
        }
        other => panic!("expected bilinear, got {other:?}"),
    }
}

#[test]
fn errors_name_the_key() {
    err_has(
        load_paper(&["buildings.0.story_law=bilinear"]),
        &["buildings[0].yield_shear", "missing"],
    );
    err_has(
        load_paper(&["buildings.0.yield_shear=1e6"]),
        &["buildings[0].yield_shear", "story_law = \"bilinear\""],
    );
    err_has(
        load_paper(&["buildings.0.hardening_ratio=0.05"]),
        &["buildings[0].hardening_ratio", "story_law"],
    );
    err_has(
        load_paper(&["buildings.0.story_law=elastoplastic"]),
        &["buildings[0].story_law", "elastoplastic", "\"bilinear\""],
    );
    err_has(
        load_paper(&[
            "buildings.0.story_law=bilinear",
            "buildings.0.yield_shear=[1e6, 2e6]",
        ]),
        &["buildings[0].yield_shear", "has 2 values"],
    );
    err_has(
        load_paper(&[
            "buildings.0.story_law=bilinear",
            "buildings.0.yield_shear=-1e6",
        ]),
        &["buildings[0].yield_shear[0]", "> 0 (N)"],
    );
    for b in ["1.0", "-0.1", "nan"] {
        err_has(
            load_paper(&[
                "buildings.0.story_law=bilinear",
                "buildings.0.yield_shear=1e6",
                &format!("buildings.0.hardening_ratio={b}"),
            ]),
            &["buildings[0].hardening_ratio", "[0, 1)"],
        );
    }
}
