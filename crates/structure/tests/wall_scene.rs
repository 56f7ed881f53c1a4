//! Scene text of a rigid wall contact (`right = "wall"`, issue 13) and its refusals.

use std::path::Path;

use structure::{Scene, SceneError};

const WALL: &str = r#"
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

[[contacts]]
left = "b"
left_floor = 2
right = "wall"
gap = 0.03
restitution = 0.5

[analysis]
duration = 1.0
"#;

fn load(text: &str, overrides: &[&str]) -> Result<Scene, SceneError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_str_with_overrides(text, "wall.toml", Path::new("."), &o)
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
fn a_wall_contact_loads_with_one_side() {
    let s = load(WALL, &[]).unwrap();
    assert_eq!(s.contacts.len(), 2);
    let w = &s.contacts[1];
    assert!(w.wall && !s.contacts[0].wall);
    assert_eq!((w.left, w.left_dof), (1, 1));
    assert_eq!((w.right, w.right_dof), (w.left, w.left_dof));
    assert_eq!((w.gap, w.restitution), (0.03, 0.5));
    // δ = u_left − gap whatever is passed for the right side.
    assert_eq!(w.penetration(0.05, 123.0), 0.05 - 0.03);
    // Walls join no pair of buildings (the overlap audit and the facings ignore them).
    assert_eq!(s.joined_pairs(), vec![(0, 1)]);
    // Restitution defaults to 1 as for any contact.
    let mut text = WALL.replace("restitution = 0.5\n", "");
    text.push('\n');
    assert_eq!(load(&text, &[]).unwrap().contacts[1].restitution, 1.0);
}

#[test]
fn wall_refusals_name_the_key() {
    err_has(
        load(WALL, &["contacts.1.right_floor=2"]),
        &["wall.toml", "contacts[1].right_floor", "wall"],
    );
    err_has(
        load(WALL, &["contacts.1.floors=aligned"]),
        &["wall.toml", "contacts[1].floors", "left_floor"],
    );
    err_has(
        load(
            &WALL.replace("left_floor = 2\nright = \"wall\"", "right = \"wall\""),
            &[],
        ),
        &["wall.toml", "contacts[1].left_floor", "missing"],
    );
    err_has(
        load(WALL, &["contacts.1.left_floor=3"]),
        &["contacts[1].left_floor", "out of range"],
    );
    err_has(
        load(WALL, &["buildings.0.name=wall"]),
        &["wall.toml", "buildings[0].name", "reserved"],
    );
    err_has(load(WALL, &["contacts.1.gap=-0.1"]), &["contacts[1].gap"]);
    // Two wall contacts at the same floor.
    let twice = format!(
        "{WALL}\n[[contacts]]\nleft = \"b\"\nleft_floor = 2\nright = \"wall\"\ngap = 0.05\n"
    );
    err_has(load(&twice, &[]), &["contacts[2]", "duplicate", "the wall"]);
    // Starting past the wall.
    err_has(
        load(WALL, &["buildings.1.initial_displacement=[0.0, 0.04]"]),
        &["contacts[1]", "the wall", "penetrated"],
    );
}
