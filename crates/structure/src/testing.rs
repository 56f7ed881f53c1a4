//! Small scenes with closed-form answers, shared by tests and benchmarks, and the invariants
//! the loader and the record readers guarantee, shared by the property tests and the fuzz
//! targets.

use std::path::PathBuf;

use crate::ground::GroundMotion;
use crate::model::Building;
use crate::scene::{Contact, GapElementOptions, Limits, MomentumOptions, Scene};

/// A scene without ground motion built in code. The contacts are kept as given, their
/// [`Contact::entry`] too (the helpers below build one contact each, entry 0).
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
// The closed forms' own parameters, in their order.
#[allow(clippy::too_many_arguments)]
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
        wall: false,
        entry: 0,
    };
    free_scene(vec![a, b], vec![c], duration)
}

/// Path of the paper scene shipped in `studies/paper/scene.toml`.
pub fn paper_scene_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../studies/paper/scene.toml")
}

/// The paper scene (roof-only contact) with `--set`-style overrides.
pub fn paper_scene(overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_file_with_overrides(&paper_scene_path(), &o).expect("paper scene")
}

/// The paper pair with contact at every facing floor (`studies/paper/scene-aligned.toml`,
/// `floors = "aligned"`) with `--set`-style overrides.
pub fn paper_scene_aligned(overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let path = paper_scene_path().with_file_name("scene-aligned.toml");
    Scene::from_file_with_overrides(&path, &o).expect("aligned paper scene")
}

/// The same piecewise-linear record on a grid `k` times finer (linear interpolation between
/// the record's points, so an exact solver must not change its answer).
pub fn refined(g: &GroundMotion, k: usize) -> GroundMotion {
    let mut accel = Vec::with_capacity((g.accel.len() - 1) * k + 1);
    for w in g.accel.windows(2) {
        for i in 0..k {
            accel.push(w[0] + (w[1] - w[0]) * i as f64 / k as f64);
        }
    }
    accel.push(*g.accel.last().unwrap_or(&0.0));
    GroundMotion {
        name: format!("{} x{k}", g.name),
        dt: g.dt / k as f64,
        accel,
    }
}

/// Closed-form impacts (time s, approach speed m/s) up to `duration` of the undamped
/// oscillator of mass `m` (kg) and stiffness `k` (N/m) leaving u = 0 at `v0` (m/s) toward a
/// rigid wall at `gap` (m) with restitution `cr`: the first impact at t₁ = asin(gω/v₀)/ω with
/// v₁ = v₀ cos ωt₁; after impact n it leaves u = g at −c_rⁿ v₁ and returns after
/// τₙ = (2π − 2 acos(g/A))/ω, A = √(g² + (c_rⁿ v₁/ω)²), at the speed it left with.
pub fn wall_impacts(m: f64, k: f64, v0: f64, gap: f64, cr: f64, duration: f64) -> Vec<(f64, f64)> {
    let w = (k / m).sqrt();
    let mut t = (gap * w / v0).asin() / w;
    let mut v = v0 * (w * t).cos();
    let mut out = vec![];
    while t < duration {
        out.push((t, v));
        let after = cr * v;
        let a = (gap * gap + (after / w).powi(2)).sqrt();
        t += (2.0 * std::f64::consts::PI - 2.0 * (gap / a).acos()) / w;
        v = after;
    }
    out
}

/// Two near-free masses about to collide (the stereomechanical impact): m1 = 2e6 kg at
/// 0.5 m/s toward m2 = 2.4e6 kg at −0.3 m/s, 1 µm apart, restitution `cr`, stories of
/// 1e-3 N/m (free particles over the 2 µs simulated).
pub fn stereomechanics(cr: f64) -> Scene {
    let mut a = Building::new("left", vec![2.0e6], vec![1e-3], 0.0);
    a.initial_velocity = vec![0.5];
    let mut b = Building::new("right", vec![2.4e6], vec![1e-3], 0.0);
    b.initial_velocity = vec![-0.3];
    let c = Contact {
        left: 0,
        left_dof: 0,
        right: 1,
        right_dof: 0,
        gap: 1e-6,
        restitution: cr,
        wall: false,
        entry: 0,
    };
    free_scene(vec![a, b], vec![c], 2e-6)
}

/// What the scene loader guarantees of a scene it returns, whatever its input: at least one
/// building, each valid with 1 ..= [`crate::scene::MAX_STORIES`] floors; a finite positive
/// duration; contacts between two buildings (or a building and a wall, whose right side
/// repeats its left) at existing floors, with gap ≥ 0 and c_r in [0, 1]. The property tests
/// of `tests/scene.rs` and the fuzz target `fuzz/fuzz_targets/scene_loader.rs` assert it.
pub fn loaded_scene_violation(scene: &Scene) -> Option<String> {
    if scene.buildings.is_empty() {
        return Some("no building".into());
    }
    if !(scene.duration.is_finite() && scene.duration > 0.0) {
        return Some(format!("duration {}", scene.duration));
    }
    for b in &scene.buildings {
        if let Err(e) = b.validate() {
            return Some(format!("building {}: {e}", b.name));
        }
        if !(1..=crate::scene::MAX_STORIES).contains(&b.n_floors()) {
            return Some(format!("building {}: {} floors", b.name, b.n_floors()));
        }
    }
    for c in &scene.contacts {
        let floors = |i: usize| scene.buildings.get(i).map_or(0, Building::n_floors);
        let ok = (c.left != c.right || (c.wall && c.left_dof == c.right_dof))
            && c.left_dof < floors(c.left)
            && c.right_dof < floors(c.right)
            && c.gap >= 0.0
            && (0.0..=1.0).contains(&c.restitution);
        if !ok {
            return Some(format!("contact {c:?}"));
        }
    }
    None
}

/// What the record readers guarantee of a record they return, whatever the text: at least
/// two finite samples, a time step of at least [`crate::ground::record::MIN_RECORD_DT`], and
/// finite peaks, slopes and integrals ([`GroundMotion::integrals_finite`]). The property
/// tests of `tests/ground.rs` and the fuzz target `fuzz/fuzz_targets/record_reader.rs`
/// assert it.
pub fn read_record_violation(g: &GroundMotion) -> Option<String> {
    if g.npts() < 2 || !g.accel.iter().all(|a| a.is_finite()) {
        return Some(format!("{} samples, not all finite", g.npts()));
    }
    if !crate::ground::record::valid_dt(g.dt) {
        return Some(format!("dt {}", g.dt));
    }
    if !(g.pga().is_finite() && g.integrals_finite()) {
        return Some("peaks, slopes or integrals not finite".into());
    }
    if !g.accel_at(0.5 * g.duration()).is_finite() {
        return Some("interpolation not finite".into());
    }
    None
}
