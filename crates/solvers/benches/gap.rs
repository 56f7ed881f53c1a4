//! Gap-element benchmarks on the paper scene (two 15-storey sticks, Capitola 0.40 g, gap
//! 0.10 m, linear law): adaptive Dormand–Prince at the default tolerance for three contact
//! stiffnesses, fixed-step Newmark at Δt = 1 ms, and the adaptive solver at k = 1e10 N/m
//! with the loosest tolerance found to keep story shears within 0.1 % of its converged
//! answer (see `tests/gap_convergence.rs`). Scenes are loaded outside the timed loop.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use structure::testing::paper_scene as paper;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("gap/paper_scene");
    g.sample_size(20);
    for k in ["1e9", "1e11", "1e13"] {
        let s = paper(&[&format!("gap_element.stiffness={k}")]);
        g.bench_function(format!("k={k}"), |b| {
            b.iter(|| solvers::gap::solve(black_box(&s), None).unwrap())
        });
    }
    for tol in ["1e-4", "1e-3"] {
        let s = paper(&[
            "gap_element.stiffness=1e10",
            &format!("gap_element.tolerance={tol}"),
        ]);
        g.bench_function(format!("k=1e10/tol={tol}"), |b| {
            b.iter(|| solvers::gap::solve(black_box(&s), None).unwrap())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("newmark/paper_scene");
    g.sample_size(20);
    let s = paper(&[
        "gap_element.integrator=newmark",
        "gap_element.time_step=1e-3",
    ]);
    g.bench_function("dt=1e-3", |b| {
        b.iter(|| solvers::gap::solve(black_box(&s), None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
