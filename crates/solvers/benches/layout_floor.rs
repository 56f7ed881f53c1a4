//! `layout_floor`: the cost floor of a block layout for the momentum method
//! (`common/layout_floor.rs`: the regular work of its fast path, without events, impacts or
//! the peaks' slow path) beside the momentum solver and the adaptive gap element at
//! k = 1e12 N/m, tol 1e-4, on the paper scene: how far the issue-10 target (momentum ≥ 10×
//! the gap element) is from what the regular work alone costs. Scenes and the floor's layout
//! are built outside the timed loop.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use solvers::momentum::Problem;
use structure::testing::paper_scene as paper;

#[path = "common/layout_floor.rs"]
mod floor;

fn bench(c: &mut Criterion) {
    let scene = paper(&[]);
    let p = Problem::new(&scene).expect("paper scene");
    let l = floor::layout(&p, &scene);
    let gap = paper(&[
        "gap_element.law=linear",
        "gap_element.stiffness=1e12",
        "gap_element.tolerance=1e-4",
    ]);
    let mut g = c.benchmark_group("layout_floor");
    g.sample_size(20);
    g.bench_function("floor", |b| b.iter(|| floor::run(black_box(&p), &l)));
    g.bench_function("momentum", |b| {
        b.iter(|| solvers::run(black_box(&scene), solvers::Method::Momentum, None).unwrap())
    });
    g.bench_function("gap/k=1e12/tol=1e-4", |b| {
        b.iter(|| solvers::run(black_box(&gap), solvers::Method::Gap, None).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
