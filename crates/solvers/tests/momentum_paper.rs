//! The paper scene (two 15-storey sticks, Capitola 0.40 g) with both variants.

use solvers::momentum::{solve, solve_with_diagnostics};
use structure::testing::paper_scene_path;
use structure::Scene;

fn run(overrides: &[&str]) -> solvers::RunOutput {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let scene = Scene::from_file_with_overrides(&paper_scene_path(), &o).unwrap();
    solve(&scene, None).unwrap()
}

#[test]
fn paper_scene_all_cases_run_with_small_energy_error() {
    for gap in ["0.10", "0.05"] {
        for modes in [None, Some("10")] {
            for variant in ["consistent", "paper"] {
                let mut ov = vec![
                    format!("contacts.0.gap={gap}"),
                    format!("momentum.impulse=\"{variant}\""),
                ];
                if let Some(m) = modes {
                    ov.push(format!("momentum.modes={m}"));
                }
                let ovs: Vec<&str> = ov.iter().map(|s| s.as_str()).collect();
                let out = run(&ovs);
                let e = &out.energy;
                let rel = e.balance_error.abs() / e.input.abs().max(e.initial);
                println!(
                    "gap {gap} modes {modes:?} {variant}: impacts {} steps {} events {} root_it {} rel.err {rel:.2e} contact {:.4e} J  V1max {:.4e}  r_n {:.3}/{:.3}  [{}]",
                    out.impacts.len(),
                    out.stats.steps,
                    out.stats.events,
                    out.stats.root_iterations,
                    e.contact,
                    out.buildings[0].story_shear_max[0],
                    out.r_n[0].r_n_left,
                    out.r_n[0].r_n_right,
                    out.settings
                );
                assert!(!out.impacts.is_empty(), "no impact at gap {gap}");
                assert!(rel < 1e-8, "balance error {rel:e}");
                if modes.is_none() {
                    assert!((out.r_n[0].r_n_left - 1.0).abs() < 1e-12);
                }
            }
        }
    }
}

#[test]
fn paper_scene_reference_values() {
    let scene = Scene::from_file(&paper_scene_path()).unwrap();
    let (out, d) = solve_with_diagnostics(&scene, None).unwrap();
    // c_r = 1 with all modes: no energy lost in impacts.
    assert!(out.energy.contact.abs() < 1e-9 * out.energy.input);
    for im in &d.impacts {
        assert!(
            (im.momentum_after - im.momentum_before).abs() < 1e-9 * out.impacts[0].impulse.max(1.0)
        );
    }
    println!(
        "reference: impacts {} steps {} events {} root_iterations {} first impact {:.12} s",
        out.impacts.len(),
        out.stats.steps,
        out.stats.events,
        out.stats.root_iterations,
        out.impacts[0].time
    );
}
