//! The paper scene (two 15-storey sticks, Capitola 0.40 g) with the gap element over the
//! whole stiffness range, both gaps, and the energy audit on it.

use solvers::gap;
use structure::testing::paper_scene as paper;

#[test]
fn paper_scene_runs_for_gaps_10_and_5_cm_and_k_1e7_to_1e13() {
    for gap in ["0.10", "0.05"] {
        for k in ["1e7", "1e9", "1e11", "1e13"] {
            let s = paper(&[
                &format!("contacts.0.gap={gap}"),
                &format!("gap_element.stiffness={k}"),
            ]);
            let t = std::time::Instant::now();
            let out = gap::solve(&s, None).unwrap_or_else(|e| panic!("gap={gap} k={k}: {e}"));
            let st = &out.stats;
            let vmax = out.buildings[0].story_shear_max[0];
            eprintln!(
                "gap={gap} k={k}: {:.1} ms, {} impacts, steps {} rej {} rhs {} hmin {:.2e} hmax {:.2e} roots {}, V1={:.4e} N, e_bal={:.2e} J of input {:.3e} J",
                t.elapsed().as_secs_f64() * 1e3,
                out.impacts.len(),
                st.steps,
                st.rejected_steps,
                st.rhs_evaluations,
                st.min_step,
                st.max_step,
                st.root_iterations,
                vmax,
                out.energy.balance_error,
                out.energy.input
            );
            assert!(vmax.is_finite() && vmax > 0.0);
            assert!(
                !out.impacts.is_empty(),
                "the paper scene pounds at gap {gap}"
            );
            for imp in &out.impacts {
                assert!(imp.duration.unwrap() > 0.0 && imp.peak_force.unwrap() > 0.0);
            }
            // Linear law: elastic, the spring returns what it stored, so the contact work
            // and the balance close to the error control (default rtol 1e-8): 10 × rtol
            // (measured balance up to 1.5e-8).
            let input = out.energy.input.abs();
            assert!(
                out.energy.contact.abs() < 1e-7 * input,
                "gap={gap} k={k}: contact work {:e} of input {input:e}",
                out.energy.contact
            );
            assert!(
                out.energy.balance_error.abs() < 1e-7 * input,
                "gap={gap} k={k}: balance {:e} of input {input:e}",
                out.energy.balance_error
            );
        }
    }
}
