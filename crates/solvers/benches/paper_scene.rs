//! `paper_scene`: the three solvers side by side on one scene (two 15-storey sticks, all
//! modes, 40 s Capitola record at 0.40 g, 10 cm gap), for the speed ratios of issue 10:
//!
//! - `momentum` — the paper's method, consistent impulse, all modes;
//! - `gap/k=1e12/tol=1e-4` — adaptive Dormand–Prince, linear law, k = 1e12 N/m;
//! - `gap/k=1e10/tol=1e-4` — adaptive, Kelvin–Voigt, k = 1e10 N/m;
//! - `newmark/k=1e10/dt=1e-3` — fixed-step Newmark, Kelvin–Voigt, k = 1e10 N/m, Δt = 1 ms;
//! - `impulse/tol=1e-4` — the impulse method (the paper's impact law on the physical floors,
//!   adaptive Dormand–Prince), tolerance 1e-4 as the adaptive gap element.
//!
//! Before timing, each case prints its deterministic work counts (mode-steps, right-hand-side
//! evaluations, Newton iterations, steps) so that ratios of time can be read beside ratios of
//! work. Scenes are loaded outside the timed loop. `make bench-table` runs the group several
//! times and tabulates the runs (`examples/bench_table.rs`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use structure::testing::paper_scene as paper;

#[path = "common/paper_scene.rs"]
mod cases;

fn bench(c: &mut Criterion) {
    let cases = cases::cases();
    let mut g = c.benchmark_group("paper_scene");
    g.sample_size(20);
    for (name, method, overrides) in cases {
        let s = paper(&overrides);
        let out = solvers::run(&s, method, None).expect("run");
        let st = &out.stats;
        let modes: usize = out.r_n.first().map_or(0, |r| r.modes_left + r.modes_right);
        eprintln!(
            "{name}: steps {}, rejected {}, rhs evaluations {}, newton iterations {}, \
             mode-steps {}, impacts {}",
            st.steps,
            st.rejected_steps,
            st.rhs_evaluations,
            st.newton_iterations,
            modes as u64 * st.steps,
            out.impacts.len()
        );
        g.bench_function(name, |b| {
            b.iter(|| solvers::run(black_box(&s), method, None).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
