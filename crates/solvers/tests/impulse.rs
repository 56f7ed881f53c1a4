//! The impulse method (`--method impulse`, issue 13): the paper's impact law on the physical
//! floor coordinates, integrated by the adaptive Dormand–Prince stepper. On linear buildings
//! it must reproduce the momentum method with all modes (same impacts, peaks to 1e-6), the
//! closed forms (a floor against a wall, the stereomechanical two-mass impact), an energy
//! balance closing to the integration tolerance, and without contact the gap element
//! (the same integrator on the same equations).

use solvers::{gap, impulse, momentum, History, RunOutput};
use structure::testing::{free_scene, paper_scene, paper_scene_aligned, refined};
use structure::{Building, Contact, GroundMotion, Scene};

/// Largest relative difference of the peak story shears and floor displacements.
fn peak_diff(a: &RunOutput, b: &RunOutput) -> f64 {
    let mut worst: f64 = 0.0;
    for (x, y) in a.buildings.iter().zip(&b.buildings) {
        for (p, q) in x.story_shear_max.iter().zip(&y.story_shear_max).chain(
            x.floor_displacement_max
                .iter()
                .zip(&y.floor_displacement_max),
        ) {
            worst = worst.max((p - q).abs() / p.abs());
        }
    }
    worst
}

/// The same impacts: count, contacts, times within `dt` s, approach and rebound velocities
/// within `dv` relative to the approach speed, restitution where defined within 1e-12.
fn same_impacts(a: &RunOutput, b: &RunOutput, dt: f64, dv: f64) {
    assert_eq!(a.impacts.len(), b.impacts.len(), "impact counts");
    for (x, y) in a.impacts.iter().zip(&b.impacts) {
        let what = format!("{x:?}\nvs {y:?}");
        assert_eq!(x.contact, y.contact, "{what}");
        assert!((x.time - y.time).abs() <= dt, "time, {what}");
        let v = x.relative_velocity_before.abs();
        assert!(
            (x.relative_velocity_before - y.relative_velocity_before).abs() <= dv * v,
            "approach, {what}"
        );
        assert!(
            (x.relative_velocity_after - y.relative_velocity_after).abs() <= dv * v,
            "rebound, {what}"
        );
        assert_eq!(
            x.achieved_restitution.is_nan(),
            y.achieved_restitution.is_nan()
        );
        if !y.achieved_restitution.is_nan() {
            let cr = x.achieved_restitution;
            assert!((y.achieved_restitution - cr).abs() <= 1e-12, "{what}");
        }
    }
}

/// Largest |Δt| and largest relative velocity difference over matched impacts.
fn impact_diffs(a: &RunOutput, b: &RunOutput) -> (f64, f64) {
    a.impacts
        .iter()
        .zip(&b.impacts)
        .map(|(x, y)| {
            let v = x.relative_velocity_before.abs();
            (
                (x.time - y.time).abs(),
                ((x.relative_velocity_before - y.relative_velocity_before).abs() / v)
                    .max((x.relative_velocity_after - y.relative_velocity_after).abs() / v),
            )
        })
        .fold((0.0, 0.0), |m, x| (m.0.max(x.0), m.1.max(x.1)))
}

#[test]
fn paper_scenes_match_the_momentum_method_with_all_modes() {
    // Roof-only contact (c_r = 1) and contact at every facing floor (roof c_r = 0.5, the
    // others 1): no persistent contact, so the two methods integrate the same equations
    // and differ by the integration error only (default tolerance 1e-8).
    for (name, scene) in [
        ("roof", paper_scene(&[])),
        (
            "aligned",
            paper_scene_aligned(&["contacts.0.restitution=0.5"]),
        ),
    ] {
        let mom = momentum::solve(&scene, None).unwrap();
        let imp = impulse::solve(&scene, None).unwrap();
        assert!(
            mom.impacts.len() > 40,
            "{name}: {} impacts",
            mom.impacts.len()
        );
        assert!(mom.persistent_contacts.is_empty() && imp.persistent_contacts.is_empty());
        let d = peak_diff(&mom, &imp);
        let (dt, dv) = impact_diffs(&mom, &imp);
        eprintln!(
            "{name}: {} impacts, peaks {d:.2e}, times {dt:.2e} s, velocities {dv:.2e}; \
             impulse {:.3} s, momentum {:.3} s",
            imp.impacts.len(),
            imp.stats.wall_seconds,
            mom.stats.wall_seconds
        );
        assert!(d <= 1e-6, "{name}: peaks differ by {d:e}");
        same_impacts(&mom, &imp, 1e-7, 1e-6);
        assert_eq!(imp.method, "impulse");
        assert!(imp.settings.contains("tol=1e-8"), "{}", imp.settings);
        assert!(imp.stats.steps > 0 && imp.stats.rhs_evaluations > 6 * imp.stats.steps / 2);
        assert_eq!(imp.stats.impacts as usize, imp.impacts.len());
    }
}

#[test]
fn the_difference_from_the_momentum_method_follows_the_tolerance() {
    // Free flight and impacts are the same equations, so the difference is the adaptive
    // integration error: a hundred times tighter tolerance makes it much smaller.
    let mut diffs = vec![];
    for tol in [1e-8, 1e-10] {
        let scene = paper_scene(&[&format!("gap_element.tolerance={tol}")]);
        let mom = momentum::solve(&scene, None).unwrap();
        let imp = impulse::solve(&scene, None).unwrap();
        same_impacts(&mom, &imp, 1e-7, 1e-6);
        diffs.push((peak_diff(&mom, &imp), impact_diffs(&mom, &imp).0));
    }
    eprintln!("(peaks, impact times) at tol 1e-8, 1e-10: {diffs:?}");
    assert!(
        diffs[1].0 < diffs[0].0 / 10.0 && diffs[1].1 < diffs[0].1 / 10.0,
        "{diffs:?}"
    );
}
