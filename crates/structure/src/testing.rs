//! Small scenes with closed-form answers, shared by tests and benchmarks.

use std::path::PathBuf;

use crate::model::Building;
use crate::scene::{Contact, GapElementOptions, Limits, MomentumOptions, Scene};

/// A scene without ground motion built in code.
pub fn free_scene(buildings: Vec<Building>, contacts: Vec<Contact>, duration: f64) -> Scene {
    Scene {
        name: "test".into(),
        file: None,
        story_heights: vec![None; buildings.len()],
        buildings,
        contacts,
        ground: None,
        ground_source: None,
        duration,
        momentum: MomentumOptions::default(),
        gap_element: GapElementOptions::default(),
        limits: Limits::default(),
    }
}

/// Two undamped single-storey oscillators (m1, k1) and (m2, k2); the left one starts at the
/// origin with velocity `v0` (m/s) toward the right one, at rest. One contact with `gap`
/// (m) and restitution `cr`. First impact, for the left one alone moving:
/// t₁ = asin(gap·ω₁/v0)/ω₁ (needs gap·ω₁ < v0).
pub fn two_oscillators(
    m1: f64,
    k1: f64,
    m2: f64,
    k2: f64,
    v0: f64,
    gap: f64,
    cr: f64,
    duration: f64,
) -> Scene {
    let mut a = Building::new("left", vec![m1], vec![k1], 0.0);
    a.initial_velocity = vec![v0];
    let b = Building::new("right", vec![m2], vec![k2], 0.0);
    let c = Contact {
        left: 0,
        left_dof: 0,
        right: 1,
        right_dof: 0,
        gap,
        restitution: cr,
    };
    free_scene(vec![a, b], vec![c], duration)
}

/// Path of the paper scene shipped in `studies/paper/scene.toml`.
pub fn paper_scene_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../studies/paper/scene.toml")
}
